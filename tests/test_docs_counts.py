"""What the docs count is what the course holds.

The student guide said "six teaching notebooks and six auto-graded assignments" when there were
seven of each (issue 37 item 7). Every "<number> teaching notebooks", "<number> appendix
notebooks" and "<number> (auto-graded) assignments" in README.md and docs/ must match
``notebooks/`` (NN_*.ipynb are the teaching notebooks, NNa_*.ipynb the appendices) and
``exercises/`` (one folder per assignment).
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WORDS = [
    "zero",
    "one",
    "two",
    "three",
    "four",
    "five",
    "six",
    "seven",
    "eight",
    "nine",
    "ten",
    "eleven",
    "twelve",
]
_COUNTED = re.compile(
    r"\b(" + "|".join(WORDS) + r"|\d+)\s+(teaching\s+notebooks|appendix\s+notebooks|"
    r"(?:auto-graded\s+)?assignments)\b",
    re.I,
)


def _counts() -> dict[str, int]:
    names = [p.name for p in (ROOT / "notebooks").glob("*.ipynb")]
    return {
        "teaching notebooks": sum(bool(re.match(r"\d\d_", n)) for n in names),
        "appendix notebooks": sum(bool(re.match(r"\d\d[a-z]_", n)) for n in names),
        "assignments": sum((p / "checks.json").is_file() for p in (ROOT / "exercises").iterdir()),
    }


def _said(text: str) -> list[tuple[str, int]]:
    out = []
    for number, what in _COUNTED.findall(text):
        n = int(number) if number.isdigit() else WORDS.index(number.lower())
        kind = " ".join(what.lower().split()).replace("auto-graded ", "")
        out.append((kind, n))
    return out


def test_the_docs_counts_match_the_notebooks_and_assignments():
    counts = _counts()
    assert counts["teaching notebooks"] >= 7 and counts["assignments"] >= 7
    wrong = []
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    for page in pages:
        for kind, n in _said(page.read_text(encoding="utf-8")):
            if n != counts[kind]:
                wrong.append(f"{page.relative_to(ROOT)}: {n} {kind}, the course has {counts[kind]}")
    assert not wrong, "\n".join(wrong)


def test_the_count_reader():
    assert _said("six teaching notebooks and six\nauto-graded assignments") == [
        ("teaching notebooks", 6),
        ("assignments", 6),
    ]
    assert _said("two appendix notebooks, 7 assignments") == [
        ("appendix notebooks", 2),
        ("assignments", 7),
    ]
