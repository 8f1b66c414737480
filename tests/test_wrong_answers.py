"""The wrong-answer suite: plausible wrong answers lose points, right answers keep full marks.

Each assignment has one plain-data module ``tests/wrong_answers/answers_NN.py`` (NN = the
assignment's number, ``answers_01.py`` for ``01_least_squares``)::

    ASSIGNMENT = "01_least_squares"  # its folder under solutions/
    STUDENT = "wa01"                 # submissions are graded as STUDENT-1, STUDENT-2, ... (never
                                     # the demo ID, so answers copied from the demo student differ)
    DEPENDS = {"q6": ["q3"]}         # optional: q6's solution cell uses q3's answer (its function)
    WRONG = {                        # per question id: answers a class would plausibly write;
        "q1": [                      # each must score LESS than the question's points
            ("unweighted fit", "x_hat_day1 = np.linalg.lstsq(A, y_day2, rcond=None)[0]"),
        ],
    }
    RIGHT = {                        # per question id: correct answers written differently
        "q1": [("lsq.fit", "x_hat_day1 = lsq.fit(A, y_day1).x_hat")],  # must keep FULL marks
    }
    MANUAL = ["q6_why"]              # optional: questions graded by hand (short answers)

A ``source`` is the complete replacement text of that question's answer cell in the solution
notebook: no ``### BEGIN SOLUTION`` markers, the same context cells above it. It may use what
the protected cells define and, for a question listed in ``DEPENDS``, the answers of the
questions it depends on (the suite only places such a variant in a notebook where those are
right). Wrong answers of a question that other questions depend on are placed where no
dependent question is graded.

To stay cheap, the suite packs the variants of different questions into few notebooks
(questions are graded independently; a notebook holds at most one variant per question, every
other answer cell keeps the solution) and grades each assignment's notebooks in one batch with
the real grader, ``course.grading.driver.grade``.

``python tests/test_wrong_answers.py [NN ...]`` prints the table of every variant's score.
"""

from __future__ import annotations

import importlib.util
import json
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import nbformat
import pytest

from course.grading.checks import load_checks
from course.grading.driver import GradeOptions, grade
from course.grading.notebook import _STUDENT_ID_LINE

ROOT = Path(__file__).resolve().parents[1]
SOLUTIONS = ROOT / "solutions"
ANSWERS = Path(__file__).resolve().parent / "wrong_answers"
ANSWER_FILES = sorted(ANSWERS.glob("answers_*.py"))


@dataclass(frozen=True)
class Variant:
    qid: str
    right: bool
    label: str
    source: str


@dataclass
class Spec:
    assignment: str
    student: str
    depends: dict
    wrong: dict
    right: dict
    manual: list

    @property
    def variants(self) -> list[Variant]:
        out = []
        for right, table in ((False, self.wrong), (True, self.right)):
            for qid, entries in table.items():
                out += [Variant(qid, right, label, src) for label, src in entries]
        return out


def load_spec(path: Path) -> Spec:
    """Read one ``answers_NN.py`` data module."""
    spec = importlib.util.spec_from_file_location(f"_wrong_answers_{path.stem}", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return Spec(
        assignment=mod.ASSIGNMENT,
        student=mod.STUDENT,
        depends={k: list(v) for k, v in getattr(mod, "DEPENDS", {}).items()},
        wrong=dict(mod.WRONG),
        right=dict(mod.RIGHT),
        manual=list(getattr(mod, "MANUAL", [])),
    )


def _closure(depends: dict) -> dict[str, set]:
    """Every question each question depends on, directly or through another answer."""
    out: dict[str, set] = {}

    def visit(q: str, seen: set) -> set:
        if q not in out:
            deps: set = set()
            for p in depends.get(q, []):
                if p not in seen:
                    deps |= {p} | visit(p, seen | {p})
            out[q] = deps
        return out[q]

    for q in depends:
        visit(q, {q})
    return out


def pack(spec: Spec) -> list[dict[str, Variant]]:
    """First-fit packing of the variants into notebooks (one variant per question per notebook).

    A variant of q joins a notebook only when every question q depends on (directly or not) is
    absent or right there, and a wrong variant only when no question depending on it is graded
    there.
    """
    needs = _closure(spec.depends)
    batches: list[dict[str, Variant]] = []
    for v in spec.variants:
        for batch in batches:
            if v.qid in batch:
                continue
            if any(p in batch and not batch[p].right for p in needs.get(v.qid, ())):
                continue
            if not v.right and any(v.qid in needs.get(r, ()) for r in batch):
                continue
            batch[v.qid] = v
            break
        else:
            batches.append({v.qid: v})
    return batches


def build_notebook(solution_nb, batch: dict[str, Variant], student_id: str):
    """A copy of the solution notebook with the answer cells of ``batch`` replaced."""
    nb = nbformat.from_dict(json.loads(json.dumps(solution_nb)))
    seen = set()
    for cell in nb.cells:
        meta = cell.get("metadata", {}).get("course", {})
        if meta.get("role") == "setup":
            cell.source = _STUDENT_ID_LINE.sub(f'STUDENT_ID = "{student_id}"', cell.source, 1)
        if meta.get("role") == "answer" and meta.get("question") in batch:
            cell.source = batch[meta["question"]].source
            seen.add(meta["question"])
    missing = set(batch) - seen
    assert not missing, f"no answer cell for {sorted(missing)} in the solution notebook"
    return nb


def grade_spec(spec: Spec, tmp: Path) -> list[tuple[Variant, dict]]:
    """Grade every variant of ``spec``; return (variant, that question's result row) pairs."""
    solution_dir = SOLUTIONS / spec.assignment
    solution_nb = nbformat.read(solution_dir / f"{spec.assignment}.ipynb", as_version=4)
    subs = tmp / "subs"
    subs.mkdir(parents=True)
    batches = pack(spec)
    ids = [f"{spec.student}-{k + 1}" for k in range(len(batches))]
    for sid, batch in zip(ids, batches):
        nbformat.write(build_notebook(solution_nb, batch, sid), subs / f"{sid}.ipynb")
    grade(solution_dir, subs, tmp / "out", GradeOptions(jobs=2, progress=False))
    rows = {}
    for line in (tmp / "out" / "results.jsonl").read_text().splitlines():
        row = json.loads(line)
        rows[row["student"]] = row
    out = []
    for sid, batch in zip(ids, batches):
        for v in batch.values():
            out.append((v, rows[sid]["questions"][v.qid] | {"student": sid}))
    return out


SPECS = {p.stem.removeprefix("answers_"): p for p in ANSWER_FILES}


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    cache: dict[str, list] = {}

    def get(key: str):
        if key not in cache:
            cache[key] = grade_spec(load_spec(SPECS[key]), tmp_path_factory.mktemp(f"wa{key}"))
        return cache[key]

    return get


def _describe(v: Variant, r: dict) -> str:
    return f"{v.qid} {v.label!r} ({r['student']}): {r['points']:g}/{r['max']:g} {r['status']} {r['message'][:160]}"


@pytest.mark.parametrize("key", sorted(SPECS))
def test_answers_cover_every_question(key):
    spec = load_spec(SPECS[key])
    checks = load_checks(SOLUTIONS / spec.assignment)
    assert spec.student != "demo"
    known = set(checks.questions)
    named = set(spec.wrong) | set(spec.right) | set(spec.depends) | set(spec.manual)
    assert named <= known, f"unknown questions {sorted(named - known)}"
    auto = known - set(spec.manual)
    assert not auto - set(spec.wrong), (
        f"questions without wrong answers: {sorted(auto - set(spec.wrong))}"
    )
    assert not auto - set(spec.right), (
        f"questions without right answers: {sorted(auto - set(spec.right))}"
    )


@pytest.mark.parametrize("key", sorted(SPECS))
def test_wrong_answers_lose_points(graded, key):
    kept = [_describe(v, r) for v, r in graded(key) if not v.right and r["points"] >= r["max"]]
    assert not kept, "wrong answers with full marks:\n" + "\n".join(kept)


@pytest.mark.parametrize("key", sorted(SPECS))
def test_right_answers_keep_full_marks(graded, key):
    lost = [_describe(v, r) for v, r in graded(key) if v.right and r["points"] < r["max"]]
    assert not lost, "right answers that lost points:\n" + "\n".join(lost)


def test_every_assignment_has_answers():
    """Every assignment gets a wrong-answer file (04-06 are added in their own branch)."""
    names = {load_spec(p).assignment for p in ANSWER_FILES}
    missing = [n for n in sorted(p.name for p in SOLUTIONS.iterdir()) if n not in names]
    missing = [n for n in missing if (SOLUTIONS / n / "checks.py").is_file()]
    if missing:
        pytest.skip(f"no wrong-answer file yet for {missing}")


def test_packing_respects_dependencies():
    spec = Spec(
        "x",
        "s",
        {"q6": ["q3"], "q7": ["q6"]},
        {"q3": [("w3", "")], "q6": [("w6a", ""), ("w6b", "")], "q7": [("w7", "")]},
        {"q3": [("r3", "")], "q6": [("r6", "")], "q7": [("r7", "")]},
        [],
    )
    batches = pack(spec)
    for batch in batches:
        for q, p in (("q6", "q3"), ("q7", "q6"), ("q7", "q3")):  # q7 needs q3 through q6
            if q in batch and p in batch:
                assert batch[p].right, batch
    assert sum(len(b) for b in batches) == 7


def _natural(qid: str) -> list:
    return [int(p) if p.isdigit() else p for p in re.split(r"(\d+)", qid)]


def main(keys) -> None:
    """Print the score of every variant (markdown table)."""
    import tempfile

    for key in keys or sorted(SPECS):
        with tempfile.TemporaryDirectory() as tmp:
            rows = grade_spec(load_spec(SPECS[key]), Path(tmp))
        print(f"\n### {key}\n\n| q | kind | answer | points |\n|---|---|---|---|")
        for v, r in sorted(rows, key=lambda x: (_natural(x[0].qid), x[0].right)):
            kind = "right" if v.right else "wrong"
            print(f"| {v.qid} | {kind} | {v.label} | {r['points']:g}/{r['max']:g} |")


if __name__ == "__main__":
    main(sys.argv[1:])
