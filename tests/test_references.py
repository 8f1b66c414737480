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


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_every_reference_file_records_its_provenance(path: Path):
    record = json.loads(path.read_text(encoding="utf-8"))
    provenance = record.get("provenance", {})
    script = provenance.get("script", "")
    assert (ROOT / script).is_file(), f"{path.name}: provenance names no script of the repository"
    assert "--write" in provenance.get("command", "") and script in provenance["command"]
    assert "--write" in (ROOT / script).read_text(encoding="utf-8"), f"{script} writes no file"
    tools = provenance.get("tools", {})
    assert "python" in tools and len(tools) >= 2, f"{path.name}: which tools made the values?"
    assert all(re.fullmatch(r"\d+(\.\w+)+", v) for v in tools.values()), tools
    assert re.fullmatch(r"\d{4}-\d{2}-\d{2}", provenance.get("written", "")), path.name
    assert record.get("about"), f"{path.name}: say what the values are"
    columns, values = record.get("columns", []), record.get("values", [])
    assert values and all(len(row) == len(columns) for row in values), path.name
