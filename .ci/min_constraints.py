"""Print pip constraints that pin numpy, scipy and matplotlib to the oldest releases that
pyproject.toml accepts (``numpy>=1.24`` becomes ``numpy==1.24.*``): CI installs the course
with them and runs a fast subset of the tests, so the declared floors are tested floors.

Usage: ``python .ci/min_constraints.py [pyproject.toml] > constraints.txt``
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

#: The numerical core whose oldest versions are installed and tested.
PINNED = ("matplotlib", "numpy", "scipy")


def constraints(pyproject: Path) -> list[str]:
    """``name==X.Y.*`` for every package of :data:`PINNED`, from its ``>=X.Y`` floor."""
    project = tomllib.loads(Path(pyproject).read_text(encoding="utf-8"))["project"]
    floors = {}
    for requirement in project["dependencies"]:
        found = re.fullmatch(r"([A-Za-z0-9_.\-]+)\s*>=\s*([\d.]+)", requirement.strip())
        if found and found[1].lower() in PINNED:
            floors[found[1].lower()] = found[2]
    missing = sorted(set(PINNED) - set(floors))
    if missing:
        raise SystemExit(f"pyproject.toml declares no '>=' floor for {', '.join(missing)}")
    return [f"{name}=={floors[name]}.*" for name in sorted(floors)]


if __name__ == "__main__":
    root = Path(__file__).resolve().parents[1]
    print(
        "\n".join(constraints(Path(sys.argv[1]) if len(sys.argv) > 1 else root / "pyproject.toml"))
    )
