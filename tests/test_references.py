"""Every reference file under tests/reference/ says where its values came from."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from references import FOLDER, ROOT

FILES = sorted(FOLDER.glob("*.json"))


def test_the_reference_files_are_found():
    assert len(FILES) >= 3


def _versions(provenance: dict) -> dict:
    """The tools and their versions a record names: ``tools`` or top-level entries."""
    tools = dict(provenance.get("tools", {}))
    tools |= {k: v for k, v in provenance.items() if k in ("python", "numpy", "scipy", "mpmath")}
    return tools


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_every_reference_file_records_its_provenance(path: Path):
    """Values are either written by a generator script of the repository (``script``, its
    ``--write`` command, the date) or recorded from an earlier version of the code to pin a
    rewrite (``commit``, what was recorded); either way with the tools' versions."""
    record = json.loads(path.read_text(encoding="utf-8"))
    provenance = record.get("provenance", {})
    if "commit" in provenance:
        assert re.fullmatch(r"[0-9a-f]{40}", provenance["commit"]), path.name
        assert provenance.get("what"), f"{path.name}: say what was recorded from that commit"
    else:
        script = provenance.get("script", "")
        assert (ROOT / script).is_file(), f"{path.name}: provenance names no script"
        assert "--write" in provenance.get("command", "") and script in provenance["command"]
        assert "--write" in (ROOT / script).read_text(encoding="utf-8"), f"{script} writes nothing"
        assert re.fullmatch(r"\d{4}-\d{2}-\d{2}", provenance.get("written", "")), path.name
        assert record.get("about"), f"{path.name}: say what the values are"
        columns, values = record.get("columns", []), record.get("values", [])
        assert values and all(len(row) == len(columns) for row in values), path.name
    tools = _versions(provenance)
    assert len(tools) >= 2, f"{path.name}: which tools (and versions) made the values?"
    assert all(re.fullmatch(r"\d+(\.\w+)+", v) for v in tools.values()), tools
