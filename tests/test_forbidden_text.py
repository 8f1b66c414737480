"""What a question's text forbids is what its checks enforce, in every released assignment.

A student reads what is forbidden in the notebook; the grader enforces ``forbid`` of
``checks.json``. The two were written in two places and drifted apart: 07's introduction
forbade ``lsq.mdb`` in q1–q4 and ``lsq.fit`` ... in q5, which only q9 and none enforced (issue
37 item 4). This test reads each question's text in the released notebook (the markdown cells
after the previous answer cell, up to its own), takes the functions named in its sentences that
say "not allowed" (and those of the question a "Same rules as qN" or "as in qN" points to), and
checks that they are exactly the functions ``checks.json`` forbids for that question; a
function a sentence calls allowed must not be forbidden.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ASSIGNMENTS = sorted(
    p.name for p in (ROOT / "exercises").iterdir() if (p / "checks.json").is_file()
)

#: module names and the notebooks' aliases of them: a name is what follows the last of them
#: (``course.diagnosis.prediction_error`` and ``prediction_error`` are one function)
MODULES = {
    "course", "lsq", "kf", "filters", "nis", "diagnosis", "dg", "mismatched", "results",
    "linalg", "chi2", "quadform",
}  # fmt: skip
_NOT_ALLOWED = re.compile(r"\bnot\s+allowed\b", re.I)
_ALLOWED = re.compile(r"\ballowed\b", re.I)
_SAME_AS = re.compile(r"\b(?:[Ss]ame\s+rules\s+as|[Aa]s\s+in)\s+(q\w+)")


def _name(dotted: str) -> str:
    """``course.nis.nis`` -> ``nis``, ``kf.LinearModel`` -> ``LinearModel``; a module alone
    (``course.diagnosis``) -> ``""``."""
    parts = dotted.split(".")
    if all(p in MODULES for p in parts) and len(parts) <= 2:
        return ""
    while len(parts) > 1 and parts[0] in MODULES:
        parts.pop(0)
    return ".".join(parts)


def _named(sentence: str) -> set[str]:
    """The functions a sentence names in backticks (a call's arguments dropped, modules too)."""
    names = (re.sub(r"\(.*", "", n) for n in re.findall(r"`([^`]+)`", sentence))
    return {n for n in map(_name, names) if n and re.fullmatch(r"[A-Za-z_][\w.]*", n)}


def _sentences(text: str) -> list[str]:
    return [s for s in re.split(r"(?<=[.;]\))\s+|(?<=[.;])\s+|\n\n", text) if s.strip()]


def _texts(name: str) -> dict[str, str]:
    """Each question's text: the markdown cells after the previous answer cell up to its own."""
    nb = json.loads((ROOT / "exercises" / name / f"{name}.ipynb").read_text(encoding="utf-8"))
    texts, pending = {}, []
    for cell in nb["cells"]:
        course = cell.get("metadata", {}).get("course", {})
        if cell["cell_type"] == "markdown" and course.get("role") != "answer":
            pending.append("".join(cell["source"]))
        elif course.get("role") == "answer":
            texts[course["question"]] = "\n\n".join(pending)
            pending = []
    return texts


def _said(name: str) -> dict[str, tuple[set[str], set[str]]]:
    """Per question: the functions its text forbids, and those it calls allowed."""
    said: dict[str, tuple[set[str], set[str]]] = {}
    for qid, text in _texts(name).items():
        forbidden, allowed = set(), set()
        for sentence in _sentences(text):
            if _NOT_ALLOWED.search(sentence):
                forbidden |= _named(sentence)
            elif _ALLOWED.search(sentence):
                allowed |= _named(sentence)
        for other in _SAME_AS.findall(text):
            if other in said:
                forbidden |= said[other][0]
        said[qid] = (forbidden, allowed)
    return said


def _enforced(name: str) -> dict[str, set[str]]:
    spec = json.loads((ROOT / "exercises" / name / "checks.json").read_text(encoding="utf-8"))
    return {q["id"]: {_name(f) for f in q.get("forbid") or ()} for q in spec["questions"]}


@pytest.mark.parametrize("name", ASSIGNMENTS)
def test_what_the_text_forbids_is_what_the_checks_enforce(name):
    said, enforced = _said(name), _enforced(name)
    wrong = []
    for qid, forbid in enforced.items():
        text_forbids, text_allows = said.get(qid, (set(), set()))
        if text_forbids != forbid:
            wrong.append(
                f"{qid}: the text forbids {sorted(text_forbids - forbid)} that the checks do not, "
                f"the checks forbid {sorted(forbid - text_forbids)} that the text does not name"
            )
        if text_allows & forbid:
            wrong.append(f"{qid}: the text allows {sorted(text_allows & forbid)}, forbidden")
    assert not wrong, "\n".join(wrong)


def test_the_reader_finds_forbidden_names_in_the_notebooks_phrasings():
    """The parser itself, on the phrasings the notebooks use."""
    assert _named("`course.diagnosis`'s `prediction_error` and `glr_test` are not allowed") == {
        "prediction_error",
        "glr_test",
    }
    assert _named("the laws `nis.extreme_eigenvalue(m, K, which)`") == {"extreme_eigenvalue"}
    assert _named("`course.nis.nis`, `nis.nees` and `course.results`") == {"nis", "nees"}
    assert _named("`results.TestResult.from_null` and `kf.LinearModel`") == {
        "TestResult.from_null",
        "LinearModel",
    }
    said = _said("07_testing_theory")
    assert "mdb" in said["q9"][0] and "mdb" not in said["q2"][0]
    assert said["q5"][0] == {"b_method"} and "noncentrality" in said["q5"][1]
