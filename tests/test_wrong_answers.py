"""The wrong-answer suite: plausible wrong answers lose points, right answers keep full marks.

Each assignment has one plain-data module ``tests/wrong_answers/answers_NN.py`` (NN = the
assignment's number, ``answers_01.py`` for ``01_least_squares``)::

    ASSIGNMENT = "01_least_squares"  # its folder under solutions/
    STUDENT = "wa01"                 # submissions are graded as STUDENT-1, STUDENT-2, ... (never
                                     # the demo ID, so answers copied from the demo student differ)
    DEPENDS = {"q6": ["q3"]}         # optional: q6's solution cell uses q3's answer (its function)
    WRONG = {                        # per question id: answers a class would plausibly write;
        "q1": [                      # each must score LESS than the question's points
            ("(slope, intercept)", "def line_estimate(t, y): return np.polyfit(t, y, 1)"),
        ],
    }
    RIGHT = {                        # per question id: correct answers written differently;
        "q1": [("reversed", "def line_estimate(t, y): return np.polyfit(t, y, 1)[::-1]")],
    }                                # each must keep FULL marks
    MANUAL = ["q6_why"]              # optional: questions graded by hand (short answers)
    COINCIDES = {                    # optional: (qid, label) of a WRONG method on personal data
        ("q6b", "alpha / 2"): f,     # that gives some students the right answer by chance:
    }                                # f(checks, student_id) is True for those, where the
                                     # variant then counts as right (it must keep full marks)

A ``source`` is the complete replacement text of that question's answer cell in the solution
notebook; what follows a line ``# %% added cell`` (``ADDED_CELL``) becomes a cell the student added
right below the answer cell, after ``# %% added cell at the end`` (``ADDED_AT_END``) one added at
the end of the notebook (scratch cells, e.g. a forbidden call whose numbers the answer pastes): no ``### BEGIN SOLUTION`` markers, the same context cells above it. It may use what
the protected cells define and, for a question listed in ``DEPENDS``, the answers of the
questions it depends on (the suite only places such a variant in a notebook where those are
right). Wrong answers of a question that other questions depend on are placed where no
dependent question is graded.

To stay cheap, the suite packs the variants of different questions into few notebooks
(questions are graded independently; a notebook holds at most one variant per question, every
other answer cell keeps the solution, and no variant there rebinds a name another question's answer
binds: the grader reads the notebook's final variables, and a later redefinition of a function
is reported in the feedback, so such a pair would not be graded as each variant alone) and grades them with the real grader,
``course.grading.batch.driver.grade``, in the assignment's graded class that the whole-class tests
share (``graded_class`` in ``tests/conftest.py``).

``python tests/test_wrong_answers.py [NN ...]`` prints the table of every variant's score.
"""

from __future__ import annotations

import ast
import contextlib
import functools
import importlib.util
import io
import json
import os
import re
import sys
import types
from dataclasses import dataclass, field
from pathlib import Path

import nbformat
import pytest
from conftest import class_submissions

from course.grading.authoring.checks import load_checks
from course.grading.batch.driver import grade
from course.grading.batch.options import GradeOptions
from course.grading.notebook import _STUDENT_ID_LINE
from course.grading.vocabulary import answer_cell_id

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
    coincides: dict = field(default_factory=dict)

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
        coincides=dict(getattr(mod, "COINCIDES", {})),
    )


def _defined(source: str) -> set[str]:
    """The names an answer cell defines at top level (functions and assigned variables)."""
    try:
        tree = ast.parse(source)
    except SyntaxError:
        return set()
    names: set[str] = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names |= {n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)}
    return names


def _bound(source: str) -> set[str]:
    """Every name an answer cell binds at top level: what it defines and what it imports."""
    names = _defined(source)
    try:
        tree = ast.parse(source)
    except SyntaxError:
        return names
    for node in tree.body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            names |= {(a.asname or a.name).split(".")[0] for a in node.names}
    return names


def _clobbers(batch: dict, solutions: dict) -> bool:
    """Whether a cell of ``batch`` rebinds a name another question's answer binds (its graded
    function or variable, or a global that function reads): the grader calls a function and
    reads a variable as they stand when the notebook ends, so a later question's cell that
    redefines ``two_sided_pvalues`` would be graded in place of q6_practice's variant."""
    bound = {q: _bound(v.source) for q, v in batch.items()}
    return any(
        bound[q] & (bound[p] | _bound(solutions.get(p, ""))) for q in batch for p in batch if p != q
    )


def _mentions(source: str, names: set[str]) -> bool:
    try:
        used = {n.id for n in ast.walk(ast.parse(source)) if isinstance(n, ast.Name)}
    except SyntaxError:
        return True
    return bool(used & names)


class _Needs:
    """Which answers a cell's source relies on, given the batch it runs in.

    ``DEPENDS`` says which questions' answers a question may use; a source relies on one only
    when it uses a name that question's solution cell defines (so a self-contained variant can
    share a notebook with a wrong prerequisite). An answer left at the solution relies on what
    the solution's cell uses, transitively. Without the solution sources every listed
    dependency counts.
    """

    def __init__(self, depends: dict, solutions: dict):
        self.depends = depends
        self.solutions = solutions
        self.defined = {
            p: _defined(solutions[p]) if p in solutions else None
            for deps in depends.values()
            for p in deps
        }

    def __call__(self, qid: str, source: str, batch: dict, seen: frozenset = frozenset()) -> set:
        out: set = set()
        for p in self.depends.get(qid, []):
            names = self.defined.get(p)
            if p in seen or (names is not None and not _mentions(source, names)):
                continue
            out.add(p)
            if p in batch and not batch[p].right:
                continue
            src = batch[p].source if p in batch else self.solutions.get(p, "")
            out |= self(p, src, batch, seen | {qid})
        return out


def pack(spec: Spec, solutions: dict | None = None) -> list[dict[str, Variant]]:
    """First-fit packing of the variants into notebooks (one variant per question per notebook).

    A variant joins a notebook only when no answer graded there relies (directly, or through a
    solution cell) on a wrong variant, and no two answers there bind the same name (see
    :func:`_clobbers`). ``solutions``: question -> the solution's answer source.
    """
    needs = _Needs(spec.depends, solutions or {})
    batches: list[dict[str, Variant]] = []
    for v in spec.variants:
        for batch in batches:
            if v.qid in batch:
                continue
            trial = {**batch, v.qid: v}
            if any(
                p in trial and not trial[p].right
                for r in trial
                for p in needs(r, trial[r].source, trial)
            ) or _clobbers(trial, solutions or {}):
                continue
            batch[v.qid] = v
            break
        else:
            batches.append({v.qid: v})
    return batches


def _solution_sources(solution_nb) -> dict[str, str]:
    return {
        c.metadata["course"]["question"]: c.source
        for c in solution_nb.cells
        if c.get("metadata", {}).get("course", {}).get("role") == "answer"
    }


#: In a variant's source, the line after which the text is a cell the student added below the
#: answer cell (``ADDED_CELL``) or at the end of the notebook (``ADDED_AT_END``).
ADDED_CELL = "# %% added cell"
ADDED_AT_END = "# %% added cell at the end"


def build_notebook(solution_nb, batch: dict[str, Variant], student_id: str):
    """A copy of the solution notebook with the answer cells of ``batch`` replaced (and the
    cells their sources add after ``ADDED_CELL`` appended at the end)."""
    nb = nbformat.from_dict(json.loads(json.dumps(solution_nb)))
    seen = set()
    cells, at_end = [], []
    for cell in nb.cells:
        cells.append(cell)
        meta = cell.get("metadata", {}).get("course", {})
        if meta.get("role") == "setup":
            cell.source = _STUDENT_ID_LINE.sub(f'STUDENT_ID = "{student_id}"', cell.source, 1)
        if meta.get("role") == "answer" and meta.get("question") in batch:
            source, _, end = batch[meta["question"]].source.partition(f"\n{ADDED_AT_END}\n")
            answer, _, below = source.partition(f"\n{ADDED_CELL}\n")
            cell.source = answer
            cells += [nbformat.v4.new_code_cell(below)] if below else []
            at_end += [nbformat.v4.new_code_cell(end)] if end else []
            seen.add(meta["question"])
    nb.cells = cells + at_end
    missing = set(batch) - seen
    assert not missing, f"no answer cell for {sorted(missing)} in the solution notebook"
    return nb


def write_submissions(spec: Spec, subs: Path) -> list[tuple[str, dict[str, Variant]]]:
    """Write the packed notebooks of ``spec`` into ``subs``; return (student ID, batch) pairs."""
    solution_nb = nbformat.read(
        SOLUTIONS / spec.assignment / f"{spec.assignment}.ipynb", as_version=4
    )
    batches = pack(spec, _solution_sources(solution_nb))
    ids = [f"{spec.student}-{k + 1}" for k in range(len(batches))]
    for sid, batch in zip(ids, batches):
        nbformat.write(build_notebook(solution_nb, batch, sid), subs / f"{sid}.ipynb")
    return list(zip(ids, batches))


def variant_rows(made, rows: dict) -> list[tuple[Variant, dict]]:
    """(variant, that question's result row) pairs of the notebooks ``write_submissions`` made."""
    return [
        (v, rows[sid]["questions"][v.qid] | {"student": sid})
        for sid, batch in made
        for v in batch.values()
    ]


def grade_spec(spec: Spec, tmp: Path) -> list[tuple[Variant, dict]]:
    """Grade every variant of ``spec`` on its own; return (variant, result row) pairs."""
    subs = tmp / "subs"
    subs.mkdir(parents=True)
    made = write_submissions(spec, subs)
    grade(SOLUTIONS / spec.assignment, subs, tmp / "out", GradeOptions(jobs=2, progress=False))
    lines = (tmp / "out" / "results.jsonl").read_text().splitlines()
    return variant_rows(made, {row["student"]: row for row in map(json.loads, lines)})


SPECS = {p.stem.removeprefix("answers_"): p for p in ANSWER_FILES}


@class_submissions("wrong answers")
def _class_submissions(name: str, subs: Path):
    """The suite's notebooks of assignment ``name``, in the shared graded class."""
    specs = [spec for spec in map(load_spec, ANSWER_FILES) if spec.assignment == name]
    return [made for spec in specs for made in write_submissions(spec, subs)]


@pytest.fixture(scope="module")
def graded(graded_class):
    def get(key: str):
        spec = load_spec(SPECS[key])
        graded = graded_class(spec.assignment)
        made = graded.made["wrong answers"]
        return variant_rows([m for m in made if m[0].startswith(f"{spec.student}-")], graded.rows)

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


def _right_by_chance(spec: Spec, v: Variant, student: str) -> bool:
    """A wrong method whose answer is, for this student's data, the right one (COINCIDES):
    where the suite packs a variant depends on the other variants, so whose data it meets
    does too; it counts as wrong only where it differs from the student's true answer."""
    same = spec.coincides.get((v.qid, v.label))
    return same is not None and bool(same(_checks(spec.assignment), student.removeprefix("'")))


@functools.cache
def _checks(assignment: str):
    return load_checks(SOLUTIONS / assignment)


@pytest.mark.parametrize("key", sorted(SPECS))
def test_wrong_answers_lose_points(graded, key):
    spec = load_spec(SPECS[key])
    rows = [(v, r) for v, r in graded(key) if not v.right]
    kept = [
        _describe(v, r)
        for v, r in rows
        if r["points"] >= r["max"] and not _right_by_chance(spec, v, r["student"])
    ]
    assert not kept, "wrong answers with full marks:\n" + "\n".join(kept)
    lost = [
        _describe(v, r)
        for v, r in rows
        if r["points"] < r["max"] and _right_by_chance(spec, v, r["student"])
    ]
    assert not lost, "answers right for this student that lost points:\n" + "\n".join(lost)


@pytest.mark.parametrize("key", sorted(SPECS))
def test_coinciding_wrong_answers_are_declared_by_their_label(key):
    spec = load_spec(SPECS[key])
    labels = {(qid, label) for qid, entries in spec.wrong.items() for label, _ in entries}
    assert set(spec.coincides) <= labels, sorted(set(spec.coincides) - labels)


@pytest.mark.parametrize("key", sorted(SPECS))
def test_right_answers_keep_full_marks(graded, key):
    lost = [_describe(v, r) for v, r in graded(key) if v.right and r["points"] < r["max"]]
    assert not lost, "right answers that lost points:\n" + "\n".join(lost)


#: The share of the tables' wrong answers whose feedback names the mistake (issue 37 item 6)
#: at least: the named ones' share is printed by the test below.
NAMED_SHARE = 0.80
#: Wrong answers that must get their declared mistake (issue 37 item 6 lists them).
MUST_BE_NAMED = [
    ("01", "q5", "unknowns swapped (a reversed)"),
    ("01", "q6_practice", "diag(sigma) passed as Qyy"),
    ("01", "q3", "dof m instead of m - n"),
    ("04", "q4", "alpha / 100 (a percentage)"),
    ("05", "q4", "laws swapped (lambda_max's for the lower, lambda_min's for the upper)"),
    ("06", "q3", "M/(M - 1) instead of (M - 1)/M"),
    ("07", "q3", "sigma² from the null model"),
    ("07", "q3", "F's denominator dof m - n"),
    ("07", "q5", "alpha_1 / 2 for lambda_0 (two-sided w)"),
]


def names_its_mistake(row: dict) -> bool:
    """Whether a wrong answer's graded question names its mistake: a forbidden call named, or
    the first failed case (the one its message quotes) diagnosed with a kind that says what
    went wrong (:data:`~course.grading.vocabulary.SPECIFIC_KINDS`: not "not within the
    tolerance", a bare factor, outside the band, another option)."""
    from course.grading.vocabulary import SPECIFIC_KINDS, GradeStatus

    if row["status"] == GradeStatus.FORBIDDEN:
        return True
    failed = [c for c in row["cases"] if not c["ok"]]
    return bool(failed) and failed[0].get("kind") in SPECIFIC_KINDS


def test_wrong_answers_name_their_mistake(graded):
    """Issue 37 item 6: the tables' wrong answers get a message that names the mistake, at
    least :data:`NAMED_SHARE` of them (printed, per assignment), and every one the issue lists
    its declared mistake."""
    named = total = 0
    lines = []
    rows_by = {}
    for key in sorted(SPECS):
        spec = load_spec(SPECS[key])
        rows = [
            (v, r)
            for v, r in graded(key)
            if not v.right
            and r["points"] < r["max"]
            and not _right_by_chance(spec, v, r["student"])
        ]
        k = sum(names_its_mistake(r) for _, r in rows)
        named, total = named + k, total + len(rows)
        lines.append(f"{key}: {k} of {len(rows)} wrong answers named ({k / len(rows):.0%})")
        rows_by.update({(key, v.qid, v.label): r for v, r in rows})
    share = named / total
    print("\n".join([*lines, f"all: {named} of {total} named ({share:.1%})"]))
    unnamed = [
        f"{key} {qid} {label!r}: {rows_by[key, qid, label]['cases']}"
        for key, qid, label in MUST_BE_NAMED
        if not any(c.get("kind") == "named mistake" for c in rows_by[key, qid, label]["cases"])
    ]
    assert not unnamed, "listed wrong answers without their named mistake:\n" + "\n".join(unnamed)
    assert share >= NAMED_SHARE, f"{share:.1%} of the wrong answers named"


def _running_cell(ns: dict, cell_id: str | None) -> None:
    """Tell the self-check which cell runs, as JupyterLab does (its forbidden-call records
    are per cell)."""
    check = ns.get("check")
    cells = getattr(check, "_cells", None)
    if cells is not None:
        check._forget_cell(types.SimpleNamespace(cell_id=cell_id))  # IPython's pre_run_cell
        cells._cell = cell_id


#: The self-check whose tripwires are set in this process (one per kernel, as in Jupyter).
_ARMED: list = [None]


def _solution_namespace(assignment: str, student: str) -> dict:
    """The namespace of the solution notebook run in this process as ``student`` (its check
    cells skipped): what a student's kernel holds when every answer is right. Built once; its
    self-check's tripwires are set again when another assignment's load replaced them (a
    kernel holds one self-check's: without this, a test of 01 after one of 07 saw no call)."""
    from course.grading.student.selfcheck import _watch_forbidden

    ns = _built_namespace(assignment, student)
    if _ARMED[0] is not ns["check"]:
        _watch_forbidden(ns["check"])
        _ARMED[0] = ns["check"]
    return ns


@functools.cache
def _built_namespace(assignment: str, student: str) -> dict:
    import matplotlib

    matplotlib.use("Agg")
    nb = nbformat.read(SOLUTIONS / assignment / f"{assignment}.ipynb", as_version=4)
    ns: dict = {"__name__": "__main__"}
    here = Path.cwd()
    try:
        os.chdir(ROOT / "exercises" / assignment)  # the self-check finds checks.json from here
        with contextlib.redirect_stdout(io.StringIO()):
            for cell in nb.cells:
                role = cell.get("metadata", {}).get("course", {}).get("role")
                if cell.cell_type != "code" or role == "check":
                    continue
                source = cell.source
                if role == "setup":
                    source = _STUDENT_ID_LINE.sub(f'STUDENT_ID = "{student}"', source, 1)
                _running_cell(ns, cell.get("id"))
                exec(compile(source, f"<{assignment}>", "exec"), ns)
    finally:
        os.chdir(here)
    return ns


@pytest.mark.parametrize("key", sorted(SPECS))
def test_right_answers_pass_the_public_self_check(key):
    """Every right variant of the suite, self-checked in a kernel where the other answers are
    the solution's, against the released (sealed) checks.json: no FAIL, and PASS where the
    question has public cases. A right answer never fails a public check."""
    spec = load_spec(SPECS[key])
    ns = _solution_namespace(spec.assignment, f"{spec.student}-self")
    check = ns["check"]
    failed = []
    for v in spec.variants:
        q = check.spec.question(v.qid)
        if not v.right or q.kind in ("choice", "short_answer"):
            continue
        mine = dict(ns)
        buf = io.StringIO()
        source, _, end = v.source.partition(f"\n{ADDED_AT_END}\n")
        answer, _, below = source.partition(f"\n{ADDED_CELL}\n")
        with contextlib.redirect_stdout(buf):
            for cell_id, text in (
                (answer_cell_id(v.qid), answer),
                ("added-1", below),
                ("added-2", end),
            ):
                _running_cell(ns, cell_id)
                exec(compile(text, f"<{v.qid} {v.label}>", "exec"), mine)
            check(v.qid, mine[q.target])
        out = buf.getvalue()
        if "FAIL" in out or (q.cases and "PASS" not in out):
            failed.append(f"{v.qid} {v.label!r}:\n{out}")
    assert not failed, "right answers failing the self-check:\n" + "\n".join(failed)


@pytest.mark.parametrize("key", sorted(SPECS))
def test_the_solution_makes_no_forbidden_call_that_counts(key):
    """Run cell by cell as JupyterLab runs it, the solution calls no function where the
    self-check (and the grader) counts it against a question that forbids it: the protected
    cells and the other questions' answers may use what those allow."""
    spec = load_spec(SPECS[key])
    check = _solution_namespace(spec.assignment, f"{spec.student}-solution")["check"]
    counted = {q.id: check._forbidden_calls(q) for q in check.spec.questions}
    assert not any(counted.values()), counted


def test_every_assignment_has_answers():
    """Every assignment has a wrong-answer file: a new assignment without one fails here."""
    names = {load_spec(p).assignment for p in ANSWER_FILES}
    missing = [n for n in sorted(p.name for p in SOLUTIONS.iterdir()) if n not in names]
    missing = [n for n in missing if (SOLUTIONS / n / "checks.py").is_file()]
    assert not missing, f"no tests/wrong_answers/answers_NN.py for {missing}"


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
    # with the solutions known, a variant that does not use q3's function may join a wrong q3
    spec.wrong["q6"] = [("w6a", "T = 1.0"), ("w6b", "T = f(2)")]
    solutions = {"q3": "def f(x):\n    return x", "q6": "T = f(1)", "q7": "u = T"}
    batches = pack(spec, solutions)
    assert any("q3" in b and not b["q3"].right and b.get("q6", None) for b in batches)
    for batch in batches:
        if "q6" in batch and "q3" in batch and "f(" in batch["q6"].source:
            assert batch["q3"].right
        if "q7" in batch and "q3" in batch and "q6" not in batch:  # q7 -> solution q6 -> q3
            assert batch["q3"].right


def test_packing_keeps_apart_answers_that_rebind_each_others_names():
    """The grader calls q6_practice's ``two_sided_pvalues`` as it stands when the notebook
    ends: a q6 variant that redefines it (a right one) hid the private-twin variant of
    q6_practice (scored 1/1 in the suite, forbidden on its own), and wrong q6 copies made wrong
    q6_practice variants lose points for q6's mistake. Imports rebind names too."""
    twin = "from m import _law\n\n\ndef pv(r):\n    return _law(r)"
    spec = Spec(
        "x",
        "s",
        {},
        {"q6_practice": [("twin", twin)], "q2": [("alias f", "from m import kf as f")]},
        {
            "q6": [("copies pv", "def pv(r):\n    return 1.0\n\n\npvalues = pv(3)")],
            "q8": [("alias f", "from m import upd as f\nstep = f(1)")],
        },
        [],
    )
    solutions = {"q6_practice": "def pv(r):\n    return r", "q6": "pvalues = pv(2)", "q2": "y = 1"}
    for batch in pack(spec, solutions):
        assert not {"q6", "q6_practice"} <= set(batch), batch  # q6 rebinds pv
        assert not {"q2", "q8"} <= set(batch), batch  # both bind f
    # answers that bind different names still share a notebook
    spec.right["q6"] = [("own name", "pvalues = 2.0")]
    spec.right["q8"] = [("own name", "step = 1")]
    assert len(pack(spec, solutions)) == 1


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


@pytest.mark.parametrize("key", sorted(SPECS))
def test_forbidden_calls_are_found_alike_at_the_self_check_and_at_grading(graded, key):
    """Issue 36: the self-check and the grader find the same forbidden calls. Every variant of
    the suite, wrong or right, self-checked as in ``test_right_answers_pass_the_public_self_check``
    (answer cell, added cells, then ``check(q)`` on the notebook's names): the self-check
    fails it for a forbidden call exactly when grading scores it ``forbidden``. The class is
    graded in this process with the self-check's tripwires set, so the grader's own calls of
    the references land on the last cell run, the protected ``check.submit()``: they count
    against no question, as at grading (they did against every value question before)."""
    spec = load_spec(SPECS[key])
    ns = _solution_namespace(spec.assignment, f"{spec.student}-self")
    check = ns["check"]
    differ = []
    for v, row in graded(key):
        q = check.spec.question(v.qid)
        if q.kind in ("choice", "short_answer"):
            continue
        mine = dict(ns)
        buf = io.StringIO()
        source, _, end = v.source.partition(f"\n{ADDED_AT_END}\n")
        answer, _, below = source.partition(f"\n{ADDED_CELL}\n")
        with contextlib.redirect_stdout(buf):
            for cell_id, text in (
                (answer_cell_id(v.qid), answer),
                ("added-1", below),
                ("added-2", end),
            ):
                _running_cell(ns, cell_id)
                with contextlib.suppress(Exception):  # grading sees a raise too
                    exec(compile(text, f"<{v.qid} {v.label}>", "exec"), mine)
            _running_cell(ns, f"{v.qid}-check")  # as in the notebook: its check cell
            check._check(v.qid, mine, None, False)
        at_self_check = "which this question forbids" in buf.getvalue()
        at_grading = row["status"] == "forbidden"
        if at_self_check != at_grading:
            differ.append(f"{_describe(v, row)}\n  self-check: {buf.getvalue()[:600]}")
    assert not differ, "forbidden calls found differently:\n" + "\n".join(differ)
