"""Reference values as data: ``tests/reference/<name>.json``, each with its provenance.

A reference file holds the values a test compares with and says where they came from: the
script that computed them (in ``tests/``), the command that writes the file, the tools and
their versions, and the date. Tests read values with :func:`load`; a generator script writes
them with :func:`write` (``python tests/<script>.py --write``), so a value never lives as an
unexplained literal. ``test_every_reference_file_records_its_provenance`` checks the record.
"""

from __future__ import annotations

import datetime
import json
import platform
from importlib import metadata
from pathlib import Path

FOLDER = Path(__file__).resolve().parent / "reference"
ROOT = FOLDER.parents[1]


def load(name: str) -> dict:
    """The data of ``tests/reference/<name>.json`` (its ``values`` and ``columns``)."""
    return json.loads((FOLDER / f"{name}.json").read_text(encoding="utf-8"))


def write(name: str, *, script: str, about: str, columns: list[str], values, tools: list[str]):
    """Write ``tests/reference/<name>.json``, recording ``script`` (a path in the repository)
    and the installed versions of ``tools`` (distribution names) beside the values."""
    record = {
        "about": about,
        "provenance": {
            "script": script,
            "command": f"python {script} --write",
            "tools": {"python": platform.python_version()}
            | {tool: metadata.version(tool) for tool in tools},
            "written": datetime.date.today().isoformat(),
        },
        "columns": columns,
        "values": values,
    }
    # one row a line: a reviewer reads the table, and a regenerated file diffs by row
    head = json.dumps({k: v for k, v in record.items() if k != "values"}, indent=1)[:-2]
    rows = ",\n".join(f"  {json.dumps(row)}" for row in values)
    text = f'{head},\n "values": [\n{rows}\n ]\n}}\n'
    (FOLDER / f"{name}.json").write_text(text, encoding="utf-8")
