"""The student's working folder: where an installed course keeps the notebooks they edit.

The student edition of the course (``course export``) carries its teaching notebooks and
exercises inside the package (``course/materials/``). Installed files are not the place for
a student's work (a reinstall replaces them), so ``course open`` copies them, on first use,
into a working folder the student chooses (default ``~/residual-validation-course``) and
remembers it. Later opens add what a newer course version brings and refresh the course's
own files (``checks.json``, ``data.py``, ``personal_data.json``), but never overwrite a
notebook the student may have edited.
"""

from __future__ import annotations

import filecmp
import os
import shutil
from pathlib import Path

__all__ = [
    "MATERIALS",
    "default_workdir",
    "packaged_materials",
    "prepare_workdir",
    "remember_workdir",
    "remembered_workdir",
]

#: Where the student edition keeps its notebooks and exercises inside the package.
MATERIALS = Path(__file__).resolve().parent / "materials"
_APP = "residual-validation-course"


def packaged_materials() -> Path | None:
    """The packaged notebooks and exercises, or None (a clone of the repository has none)."""
    return MATERIALS if (MATERIALS / "exercises").is_dir() else None


def default_workdir() -> Path:
    return Path.home() / _APP


def _config_file(env=None) -> Path:
    env = os.environ if env is None else env
    base = env.get("XDG_CONFIG_HOME") or env.get("APPDATA") or str(Path.home() / ".config")
    return Path(base) / _APP / "workdir"


def remembered_workdir(env=None) -> Path | None:
    """The working folder chosen at the first ``course open`` (None if never chosen)."""
    try:
        text = _config_file(env).read_text("utf-8").strip()
    except OSError:
        return None
    return Path(text) if text else None


def remember_workdir(folder: Path, env=None) -> None:
    path = _config_file(env)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(str(Path(folder).resolve()) + "\n", encoding="utf-8")
    except OSError:
        pass  # remembering is a convenience: `course open --workdir` still works


def prepare_workdir(folder: Path, materials: Path) -> tuple[list[Path], list[Path]]:
    """Copy the course into ``folder``: ``(added, refreshed)`` relative paths.

    Missing files are added; notebooks that exist are left alone (they hold the student's
    work); other course files that differ are refreshed.
    """
    folder = Path(folder)
    added: list[Path] = []
    refreshed: list[Path] = []
    for source in sorted(p for p in materials.rglob("*") if p.is_file()):
        rel = source.relative_to(materials)
        if "__pycache__" in rel.parts or ".ipynb_checkpoints" in rel.parts:
            continue
        target = folder / rel
        if not target.exists():
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(source, target)
            added.append(rel)
        elif source.suffix != ".ipynb" and not filecmp.cmp(source, target, shallow=False):
            shutil.copyfile(source, target)
            refreshed.append(rel)
    return added, refreshed
