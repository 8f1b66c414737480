"""Notebook handling: solution markers, the student release, and the grading plan.

The solution notebook's code cells have roles (``metadata.course.role``):

``setup``    the first code cell: ``STUDENT_ID = "..."`` and ``check = Assignment.load(...)``
``answer``   a student's answer to ``metadata.course.question``; holds SOLUTION regions
``check``    ``check("q1")``: the self-check (skipped at grading)
``context``  any other code cell (protected: the release version runs at grading)

:func:`make_release` turns it into the student notebook; :func:`build_plan` matches a
submitted notebook against the release and lists what the grader runs, in which order.
"""

from __future__ import annotations

import ast
import errno
import json
import os
import re
import stat
from dataclasses import dataclass, field
from typing import Any

import nbformat

from course.grading.items import SHORT_ANSWER_STUB
from course.grading.vocabulary import (
    PLACEHOLDER_ID,
    CellOrigin,
    CellRole,
    QuestionKind,
    answer_cell_id,
)

__all__ = [
    "MarkerError",
    "Plan",
    "PlanCell",
    "Release",
    "ReleaseCell",
    "SubmissionError",
    "build_plan",
    "forbidden_mentions",
    "make_release",
    "read_notebook_bytes",
    "read_submission",
    "student_id_in",
]

BEGIN_SOLUTION = "### BEGIN SOLUTION"
END_SOLUTION = "### END SOLUTION"
BEGIN_HIDDEN = "### BEGIN HIDDEN TESTS"
END_HIDDEN = "### END HIDDEN TESTS"
STUB_PREFIX = "### STUB"
_MARKER_WORDS = re.compile(r"(BEGIN|END)\s+(SOLUTION|HIDDEN\s+TESTS)", re.IGNORECASE)
_CHECK_SOURCE = re.compile(r"""^\s*check\(\s*["']([A-Za-z][A-Za-z0-9_]*)["']\s*\)\s*$""")
_STUDENT_ID_LINE = re.compile(r"^STUDENT_ID\s*=.*$", re.MULTILINE)
_ROLES = (CellRole.SETUP, CellRole.ANSWER, CellRole.CHECK, CellRole.CONTEXT)
PLACEHOLDER_LINE = f'STUDENT_ID = "{PLACEHOLDER_ID}"   # <- your student ID, exactly as registered'
MAX_NOTEBOOK_BYTES = 50_000_000


class MarkerError(ValueError):
    """The solution notebook has a malformed or misplaced marker (release refuses it)."""


class SubmissionError(ValueError):
    """A submitted notebook cannot be read at all."""


def _source(cell) -> str:
    src = cell.get("source", "")
    if isinstance(src, list):
        src = "".join(s for s in src if isinstance(s, str))
    return src if isinstance(src, str) else ""


def _course_meta(cell) -> dict:
    meta = cell.get("metadata")
    course = meta.get("course") if isinstance(meta, dict) else None
    return course if isinstance(course, dict) else {}


def python_source(source: str) -> str:
    """Cell source with IPython syntax (magics, ``!cmd``) turned into plain Python."""
    from IPython.core.inputtransformer2 import TransformerManager

    return TransformerManager().transform_cell(source)


def _compiles(source: str) -> str | None:
    try:
        compile(python_source(source), "<cell>", "exec")
    except SyntaxError as exc:
        return f"line {exc.lineno}: {exc.msg}"
    return None


# --------------------------------------------------------------------------------------
# release
# --------------------------------------------------------------------------------------
def strip_markers(
    source: str, where: str, question: str | None, allow_solution: bool
) -> tuple[str, int]:
    """Return the released source (stubs for SOLUTION regions, HIDDEN TESTS regions removed)
    and the number of solution regions; raise :class:`MarkerError` on malformed markers."""
    out: list[str] = []
    state: Any = None  # None | ("solution", indent, line, stubs) | ("hidden", line)
    regions = 0
    lines = source.split("\n")
    for n, line in enumerate(lines, 1):
        stripped = line.strip()
        if stripped in (BEGIN_SOLUTION, END_SOLUTION, BEGIN_HIDDEN, END_HIDDEN):
            if stripped == BEGIN_SOLUTION:
                if state is not None:
                    raise MarkerError(
                        f"{where}, line {n}: '{BEGIN_SOLUTION}' inside an open region (line {state[2] if state[0] == 'solution' else state[1]}); close it first"
                    )
                if not allow_solution:
                    raise MarkerError(
                        f"{where}, line {n}: a SOLUTION region outside an answer cell; "
                        "tag the cell as an answer (course.grading.authoring.notebooks.answer_cell)"
                    )
                indent = line[: len(line) - len(line.lstrip())]
                state = ("solution", indent, n, [])
            elif stripped == END_SOLUTION:
                if state is None or state[0] != "solution":
                    raise MarkerError(
                        f"{where}, line {n}: '{END_SOLUTION}' without a matching '{BEGIN_SOLUTION}'"
                    )
                _, indent, _, stubs = state
                if stubs:
                    out.extend(stubs)
                else:
                    out.append(f"{indent}# YOUR CODE HERE")
                    out.append(f'{indent}raise NotImplementedError("{question}: not answered yet")')
                regions += 1
                state = None
            elif stripped == BEGIN_HIDDEN:
                if state is not None:
                    raise MarkerError(
                        f"{where}, line {n}: '{BEGIN_HIDDEN}' inside an open region; close it first"
                    )
                state = ("hidden", n)
            else:
                if state is None or state[0] != "hidden":
                    raise MarkerError(
                        f"{where}, line {n}: '{END_HIDDEN}' without a matching '{BEGIN_HIDDEN}'"
                    )
                state = None
            continue
        if _MARKER_WORDS.search(line) and stripped.startswith("#"):
            raise MarkerError(
                f"{where}, line {n}: malformed marker {stripped!r}; write exactly "
                f"'{BEGIN_SOLUTION}', '{END_SOLUTION}', '{BEGIN_HIDDEN}' or '{END_HIDDEN}'"
            )
        if state is None:
            if stripped.startswith(STUB_PREFIX):
                raise MarkerError(
                    f"{where}, line {n}: '{STUB_PREFIX}' lines belong inside a SOLUTION region"
                )
            out.append(line)
        elif state[0] == "solution" and stripped.startswith(STUB_PREFIX):
            indent = line[: len(line) - len(line.lstrip())]
            state[3].append(indent + stripped[len(STUB_PREFIX) :].lstrip())
        # hidden regions are dropped
    if state is not None:
        kind = BEGIN_SOLUTION if state[0] == "solution" else BEGIN_HIDDEN
        line_no = state[2] if state[0] == "solution" else state[1]
        raise MarkerError(f"{where}, line {line_no}: '{kind}' is never closed")
    return "\n".join(out), regions


@dataclass
class ReleaseCell:
    """One cell of a release: its role, question, and the released (student) source."""

    index: int
    id: str
    cell_type: str
    role: CellRole
    question: str | None
    source: str
    solution_source: str


@dataclass
class Release:
    name: str
    notebook: Any  # nbformat.NotebookNode
    cells: list

    def by_id(self) -> dict:
        return {c.id: c for c in self.cells}

    @property
    def setup(self) -> ReleaseCell:
        return next(c for c in self.cells if c.role == CellRole.SETUP)

    def answer(self, qid: str) -> ReleaseCell:
        return next(c for c in self.cells if c.role == CellRole.ANSWER and c.question == qid)

    def text(self) -> str:
        return nbformat.writes(self.notebook) + "\n"


_VALID_ID = re.compile(r"^[a-zA-Z0-9-_]{1,64}$")

#: The id of the release-generated cell that states the total and how points are earned.
POINTS_CELL_ID = "points-total"

# Cell locks of a release (the JupyterLab / nbgrader convention, nbformat cell metadata):
# instructions, context and check cells can be neither edited nor deleted; answer cells and
# the setup cell (its STUDENT_ID line) can be edited but not deleted.
LOCKED = {"editable": False, "deletable": False}
UNDELETABLE = {"editable": True, "deletable": False}


def _points_text(points: float) -> str:
    return f"{points:g} point{'' if points == 1 else 's'}"


def _header_pattern(qid: str):
    """A markdown heading naming question ``qid`` (``## q3: ...``, ``### **q3** ...``), with
    the points it may state (``## q3 (2 points): ...``)."""
    return re.compile(
        rf"^(?P<lead>#{{1,6}}[ \t]+(?:\*\*)?{re.escape(qid)}(?![A-Za-z0-9_])(?:\*\*)?)"
        r"(?P<pts>[ \t]*\([ \t]*(?P<n>[0-9]+(?:\.[0-9]*)?)[ \t]*points?[ \t]*\))?",
        re.MULTILINE,
    )


def write_points(text: str, questions: dict, where: str, found: dict) -> str:
    """``text`` (a markdown cell) with each question header stating the points of checks.py;
    :class:`MarkerError` when a header states other points. Records headers in ``found``."""
    for qid, q in questions.items():
        pattern = _header_pattern(qid)
        matches = list(pattern.finditer(text))
        if not matches:
            continue
        if len(matches) > 1 or qid in found:
            raise MarkerError(
                f"{where}: a second header names {qid} (first: {found.get(qid, where)}); "
                f"keep one '## {qid}: ...' heading per question"
            )
        found[qid] = where
        m = matches[0]
        if m.group("n") is not None and float(m.group("n")) != float(q.points):
            raise MarkerError(
                f"{where}: the header of {qid} states {m.group('n')} point(s), checks.py gives "
                f"{q.points:g}: make them agree (or drop the points from the header: the "
                "release writes them)"
            )
        text = text[: m.start()] + f"{m.group('lead')} ({_points_text(q.points)})" + text[m.end() :]
    return text


def points_cell_text(questions: dict) -> str:
    """The release-generated cell after the title: the total, and how points are earned."""
    qs = list(questions.values())
    total = sum(q.points for q in qs)
    kinds = {str(q.kind) for q in qs}
    lines = [
        f"**Points.** {len(qs)} question{'s' if len(qs) != 1 else ''}, "
        f"{_points_text(total)} in total: "
        + " · ".join(
            f"{q.id} {q.points:g}"
            + (" (all or nothing)" if q.kind == QuestionKind.FUNCTION and not q.partial else "")
            for q in qs
        )
        + ".",
        "",
        "*How points are earned.*",
    ]
    if str(QuestionKind.FUNCTION) in kinds:
        lines.append(
            "- A function you write is called on several cases, public and hidden; it earns its "
            "points in proportion to the cases it passes (3 of 4 cases: three quarters of the "
            "points), unless the list above says *all or nothing*."
        )
    if kinds & {str(QuestionKind.VALUE), str(QuestionKind.CHOICE)}:
        lines.append(
            "- A value (within its stated tolerance) or a choice is either right, for all its "
            "points, or not, for none."
        )
    if str(QuestionKind.SHORT_ANSWER) in kinds:
        lines.append(
            "- A short answer (a markdown cell) is marked by your instructor against a rubric; "
            "any part of its points may be given."
        )
    lines.append(
        "- An answer that runs too long, crashes or uses a forbidden function earns 0 for its "
        "question; the other questions are graded as usual."
    )
    lines += [
        "",
        '`check("qN")` runs the public checks of one question; hidden cases, values from your '
        "personal data and choices are checked only when your instructor grades. "
        "`check.all()` ends with the points the public checks give.",
    ]
    return "\n".join(lines)


def make_release(solution_nb, name: str, questions: dict | None = None) -> Release:
    """Build the student release of a solution notebook (see the module docstring).

    ``questions`` maps question id -> :class:`~course.grading.authoring.checks.Question`; when given, every
    question must have exactly one answer cell (and vice versa) and its variable or function
    must be defined there.
    """
    where_nb = f"{name}.ipynb"
    cells_out = []
    release_cells = []
    seen_ids = set()
    seen_answers: dict[str, int] = {}
    headers: dict[str, str] = {}  # question -> where its header is
    all_ids = {c.get("id") for c in solution_nb.cells}
    first_code = True
    for index, cell in enumerate(solution_nb.cells):
        ctype = cell.get("cell_type")
        cid = cell.get("id") or f"cell-{index}"
        if not _VALID_ID.match(cid):
            raise MarkerError(f"{where_nb}, cell {index}: id {cid!r} is not a valid cell id")
        if cid in seen_ids:
            raise MarkerError(f"{where_nb}, cell {index}: duplicate cell id {cid!r}")
        seen_ids.add(cid)
        src = _source(cell)
        meta = _course_meta(cell)
        where = f"{where_nb}, cell {index} (id {cid!r})"
        if ctype == "markdown" and meta.get("role") == CellRole.ANSWER:
            question = meta.get("question")
            if not question:
                raise MarkerError(f"{where}: an answer cell needs metadata course.question")
            if question in seen_answers:
                raise MarkerError(
                    f"{where}: second answer cell for {question} (first: cell {seen_answers[question]})"
                )
            seen_answers[str(question)] = index
            new = nbformat.v4.new_markdown_cell(SHORT_ANSWER_STUB)
            new["id"] = _answer_id(question, cid, all_ids, where)
            new["metadata"] = {
                "course": {"role": str(CellRole.ANSWER), "question": question},
                **UNDELETABLE,
            }
            cells_out.append(new)
            release_cells.append(
                ReleaseCell(
                    index, new["id"], ctype, CellRole.ANSWER, question, SHORT_ANSWER_STUB, src
                )
            )
            continue
        if ctype == "markdown" or ctype == "raw":
            if _MARKER_WORDS.search(src):
                raise MarkerError(f"{where}: markers are only supported in code cells")
            if questions is not None and ctype == "markdown":
                src = write_points(src, questions, where, headers)
            new = (
                nbformat.v4.new_markdown_cell(src)
                if ctype == "markdown"
                else nbformat.v4.new_raw_cell(src)
            )
            new["id"] = cid
            new["metadata"] = {"course": {"role": str(CellRole.TEXT)}, **LOCKED}
            if cell.get("attachments"):
                new["attachments"] = cell["attachments"]
            cells_out.append(new)
            release_cells.append(ReleaseCell(index, cid, ctype, CellRole.TEXT, None, src, src))
            continue
        if ctype != "code":
            raise MarkerError(f"{where}: unknown cell type {ctype!r}")
        role = meta.get("role")
        question = meta.get("question")
        if role is None:
            m = _CHECK_SOURCE.match(src)
            if first_code and _STUDENT_ID_LINE.search(src):
                role = CellRole.SETUP
            elif m:
                role, question = CellRole.CHECK, m.group(1)
            else:
                role = CellRole.CONTEXT
        if role not in _ROLES:
            raise MarkerError(f"{where}: unknown role {role!r} (use one of {', '.join(_ROLES)})")
        role = CellRole(role)
        if role == CellRole.SETUP and not first_code:
            raise MarkerError(f"{where}: the setup cell must be the first code cell")
        if first_code and role != CellRole.SETUP:
            raise MarkerError(
                f"{where}: the first code cell must be the setup cell with STUDENT_ID "
                "(course.grading.authoring.notebooks.setup_cell)"
            )
        first_code = False
        if role in (CellRole.ANSWER, CellRole.CHECK) and not question:
            raise MarkerError(f"{where}: an {role} cell needs metadata course.question")
        released, regions = strip_markers(
            src, where, question, allow_solution=(role == CellRole.ANSWER)
        )
        if role == CellRole.ANSWER:
            if regions == 0:
                raise MarkerError(
                    f"{where}: answer cell for {question} has no '{BEGIN_SOLUTION}' region"
                )
            if question in seen_answers:
                raise MarkerError(
                    f"{where}: second answer cell for {question} (first: cell {seen_answers[question]})"
                )
            seen_answers[str(question)] = index
        if role == CellRole.SETUP:
            if not _STUDENT_ID_LINE.search(released):
                raise MarkerError(
                    f"{where}: the setup cell must assign STUDENT_ID on a line of its own"
                )
            # the solution may carry a real ID (e.g. "demo"); students always get the placeholder
            released = _STUDENT_ID_LINE.sub(lambda _m: PLACEHOLDER_LINE, released, count=1)
        for text, what in ((src, "solution"), (released, "released")):
            problem = _compiles(text)
            if problem:
                raise MarkerError(f"{where}: the {what} cell is not valid Python ({problem})")
        new = nbformat.v4.new_code_cell(released)
        new["id"] = _answer_id(question, cid, all_ids, where) if role == CellRole.ANSWER else cid
        new["metadata"] = {
            "course": {"role": str(role), **({"question": question} if question else {})},
            **(UNDELETABLE if role in (CellRole.ANSWER, CellRole.SETUP) else LOCKED),
        }
        cells_out.append(new)
        release_cells.append(ReleaseCell(index, new["id"], "code", role, question, released, src))
    if first_code:
        raise MarkerError(f"{where_nb}: no code cells (the first code cell must be the setup cell)")

    if questions is not None:
        for qid, q in questions.items():
            if qid not in seen_answers:
                raise MarkerError(f"{where_nb}: question {qid} (checks.py) has no answer cell")
            cell = next(c for c in release_cells if c.role == CellRole.ANSWER and c.question == qid)
            if (q.kind == QuestionKind.SHORT_ANSWER) != (cell.cell_type == "markdown"):
                raise MarkerError(
                    f"{where_nb}: the answer cell of {qid} must be a "
                    + (
                        "markdown cell (a short answer; course.grading.authoring.notebooks.short_answer_cell)"
                        if q.kind == QuestionKind.SHORT_ANSWER
                        else "code cell"
                    )
                )
            if q.kind == QuestionKind.SHORT_ANSWER:
                continue
            defined = _defined_names(cell.solution_source)
            if q.target not in defined:
                what = "define function" if q.kind == "function" else "assign variable"
                raise MarkerError(f"{where_nb}: the answer cell of {qid} must {what} {q.target!r}")
        for qid in seen_answers:
            if qid not in questions:
                raise MarkerError(
                    f"{where_nb}: answer cell for {qid!r}, which checks.py does not define"
                )
        for qid in questions:
            if qid not in headers:
                raise MarkerError(
                    f"{where_nb}: question {qid} has no header: start its markdown cell with a "
                    f"heading such as '## {qid}: what it asks' (the release writes its points)"
                )
        if POINTS_CELL_ID in all_ids:
            raise MarkerError(f"{where_nb}: the cell id {POINTS_CELL_ID!r} is the release's own")
        totals = nbformat.v4.new_markdown_cell(points_cell_text(questions))
        totals["id"] = POINTS_CELL_ID
        totals["metadata"] = {"course": {"role": str(CellRole.TEXT)}, **LOCKED}
        at = 1 if cells_out and cells_out[0]["cell_type"] == "markdown" else 0
        cells_out.insert(at, totals)
        release_cells.append(
            ReleaseCell(-1, POINTS_CELL_ID, "markdown", CellRole.TEXT, None, totals.source, "")
        )

    nb = nbformat.v4.new_notebook()
    nb["cells"] = cells_out
    nb["metadata"] = {
        "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
        "language_info": {"name": "python"},
        "course": {"assignment": name},
    }
    nb["nbformat"], nb["nbformat_minor"] = 4, 5
    nbformat.validate(nb)
    return Release(name, nb, release_cells)


def _answer_id(question, cid: str, all_ids: set, where: str) -> str:
    """The released id of an answer cell: ``<question>-answer`` whatever the solution uses, so
    every release of the assignment names it alike and the grader finds it when moved."""
    stable = answer_cell_id(str(question))
    if stable != cid and stable in all_ids:
        raise MarkerError(
            f"{where}: the id {stable!r} belongs to the answer cell of {question}; rename the "
            "other cell"
        )
    return stable


def _defined_names(source: str) -> set:
    try:
        tree = ast.parse(python_source(source))
    except SyntaxError:
        return set()
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        elif isinstance(node, ast.alias):
            names.add((node.asname or node.name).split(".")[0])
    return names


# --------------------------------------------------------------------------------------
# submissions
# --------------------------------------------------------------------------------------
def read_notebook_bytes(path) -> bytes:
    """The bytes of a submitted notebook, refusing a symbolic link (even one swapped in after
    the submissions were listed) and anything larger than :data:`MAX_NOTEBOOK_BYTES` + 1."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise SubmissionError("the notebook is a symbolic link") from None
        raise SubmissionError(f"cannot read the notebook ({exc.strerror})") from None
    with os.fdopen(fd, "rb") as f:
        if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
            raise SubmissionError("the notebook is not a regular file")
        return f.read(MAX_NOTEBOOK_BYTES + 1)


def read_submission(source) -> dict:
    """Read a submitted notebook (a path, or its bytes) leniently (no schema validation);
    :class:`SubmissionError` when it is not a JSON notebook at all."""
    raw = source if isinstance(source, bytes) else read_notebook_bytes(source)
    if len(raw) > MAX_NOTEBOOK_BYTES:
        raise SubmissionError(f"the notebook is larger than {MAX_NOTEBOOK_BYTES // 1_000_000} MB")
    if not raw.strip():
        raise SubmissionError("the notebook file is empty")
    try:
        nb = json.loads(raw.decode("utf-8", errors="replace"))
    except (json.JSONDecodeError, RecursionError) as exc:
        raise SubmissionError(
            f"the notebook is not valid JSON ({getattr(exc, 'msg', 'too deeply nested')}"
            f"{f' at line {exc.lineno}' if hasattr(exc, 'lineno') else ''})"
        ) from None
    if not isinstance(nb, dict) or not isinstance(nb.get("cells", None), list):
        raise SubmissionError(
            "the file is JSON but not a Jupyter notebook (no 'cells' list; nbformat 4 expected)"
        )
    return nb


@dataclass
class PlanCell:
    """One cell the grader runs: its source, the question it belongs to, a label for messages."""

    source: str
    question: str | None
    origin: CellOrigin
    label: str


@dataclass
class Plan:
    cells: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    answered: set = field(default_factory=set)  # questions with at least one answer cell
    answer_sources: dict = field(default_factory=dict)  # question -> source of its slot
    notebook_student_id: str | None = None
    texts: dict = field(default_factory=dict)  # short-answer question -> its markdown text
    #: question -> "adopted" (answer cell deleted, an added cell defines the answer and is
    #: graded instead) or "missing" (answer cell deleted, nothing found)
    deleted: dict = field(default_factory=dict)


def student_id_in(source: str) -> str | None:
    """The literal string assigned to STUDENT_ID in ``source`` (None if absent or not literal)."""
    try:
        tree = ast.parse(python_source(source))
    except (SyntaxError, ValueError):
        return None
    for node in tree.body:
        if (
            isinstance(node, ast.Assign)
            and any(isinstance(t, ast.Name) and t.id == "STUDENT_ID" for t in node.targets)
            and isinstance(node.value, ast.Constant)
            and isinstance(node.value.value, str)
        ):
            return node.value.value
    return None


def _normalise(source: str) -> str:
    return "\n".join(line.rstrip() for line in source.strip().split("\n"))


def setup_source(release: Release, student_id: str) -> str:
    return _STUDENT_ID_LINE.sub(
        lambda _m: f"STUDENT_ID = {json.dumps(student_id)}", release.setup.source, count=1
    )


def build_plan(release: Release, nb: dict, student_id: str, targets: dict | None = None) -> Plan:
    """Match a submitted notebook against the release and list the cells to run, in order.

    Protected cells (setup, context) always run in their RELEASE version, at their release
    position, even when the student deleted or edited them (edits are noted). Answer cells are
    matched by cell id (``<question>-answer``), then by ``metadata.course``, wherever the student
    moved them; every copy runs, in the student's order, at the question's position. Cells the
    student added run right after the matched cell that precedes them in the student's notebook
    (answers they follow count as part of that answer). Check cells and copies of protected
    cells are not run. Short answers (markdown answer cells) are collected in ``plan.texts``.

    When a question's answer cell is missing (deleted, or retyped in a new cell), the added
    cells that define its variable or function (``targets``: question -> name) are graded as
    its answer, and ``plan.deleted`` and a note say so; otherwise it counts as not answered.
    """
    plan = Plan()
    by_id = release.by_id()
    text_answers = {
        c.question for c in release.cells if c.role == CellRole.ANSWER and c.cell_type == "markdown"
    }
    code_cells = [c for c in release.cells if c.cell_type == "code"]
    slots: dict[Any, list] = {c.index: [] for c in code_cells}
    answer_slot = {c.question: c.index for c in code_cells if c.role == CellRole.ANSWER}
    used_ids = set()
    anchor = release.setup.index
    n_extra = 0
    for pos, cell in enumerate(nb.get("cells", [])):
        if isinstance(cell, dict) and cell.get("cell_type") == "markdown":
            cid = cell.get("id") if isinstance(cell.get("id"), str) else None
            meta = _course_meta(cell)
            if cid in by_id and by_id[cid].question in text_answers:
                qid = by_id[cid].question
            elif meta.get("role") == CellRole.ANSWER and meta.get("question") in text_answers:
                qid = meta["question"]
            else:
                continue
            plan.texts[qid] = (plan.texts.get(qid, "") + "\n\n" + _source(cell)).strip()
            plan.answered.add(qid)
            continue
        if not isinstance(cell, dict) or cell.get("cell_type") != "code":
            continue
        src = _source(cell)
        cid = cell.get("id") if isinstance(cell.get("id"), str) else None
        meta = _course_meta(cell)
        match = None
        if cid in by_id and cid not in used_ids and by_id[cid].cell_type == "code":
            match = by_id[cid]
            used_ids.add(cid)
        elif meta.get("role") == CellRole.ANSWER and meta.get("question") in answer_slot:
            match = next(c for c in code_cells if c.index == answer_slot[meta["question"]])
        elif meta.get("role") in (CellRole.SETUP, CellRole.CONTEXT, CellRole.CHECK):
            plan.notes.append(
                f"Ignored a copy of a protected cell (notebook cell {pos + 1}); protected cells run as released."
            )
            continue
        if match is None:
            n_extra += 1
            slots[anchor].append(
                PlanCell(src, None, CellOrigin.EXTRA, f"your added cell at position {pos + 1}")
            )
            continue
        if match.role == CellRole.ANSWER:
            slots[match.index].append(
                PlanCell(src, match.question, CellOrigin.ANSWER, f"answer cell of {match.question}")
            )
            plan.answered.add(match.question)
        elif match.role == CellRole.SETUP:
            plan.notebook_student_id = student_id_in(src)
            if _normalise(_STUDENT_ID_LINE.sub("", src)) != _normalise(
                _STUDENT_ID_LINE.sub("", match.source)
            ):
                plan.notes.append("The setup cell was edited; the released version was used.")
        elif match.role == CellRole.CONTEXT and _normalise(src) != _normalise(match.source):
            plan.notes.append(
                f"Protected cell {match.id!r} was edited; the released version was used."
            )
        anchor = match.index

    for qid in sorted(text_answers - plan.answered):
        plan.deleted[qid] = "missing"
        plan.notes.append(
            f"The answer cell of {qid} (id {answer_cell_id(qid)!r}) is missing from the "
            f"notebook (deleted?): {qid} counts as not answered."
        )
    _adopt_added_answers(plan, slots, answer_slot, targets or {})

    for cell in code_cells:
        if cell.role == CellRole.SETUP:
            plan.cells.append(
                PlanCell(setup_source(release, student_id), None, CellOrigin.SETUP, "setup cell")
            )
            plan.cells.extend(slots[cell.index])
        elif cell.role == CellRole.CONTEXT:
            plan.cells.append(
                PlanCell(cell.source, None, CellOrigin.CONTEXT, f"protected cell {cell.id!r}")
            )
            plan.cells.extend(slots[cell.index])
        elif cell.role == CellRole.CHECK:
            plan.cells.extend(slots[cell.index])
        else:
            q = cell.question
            own = [item for item in slots[cell.index] if item.question in (None, q)]
            for item in slots[cell.index]:
                plan.cells.append(
                    PlanCell(item.source, item.question or q, item.origin, item.label)
                )
            if q not in plan.deleted:
                plan.answer_sources[q] = "\n\n".join(item.source for item in own)
    return plan


def _adopt_added_answers(plan: Plan, slots: dict, answer_slot: dict, targets: dict) -> None:
    """For each question whose answer cell is missing: grade the added cells that define its
    variable or function as its answer (and say so), or note that it is not answered."""
    added = [
        item
        for cells in slots.values()
        for item in cells
        if item.origin == CellOrigin.EXTRA and item.question is None
    ]
    for qid in answer_slot:
        if qid in plan.answered:
            continue
        where = (
            f"The answer cell of {qid} (id {answer_cell_id(qid)!r}) is missing from the notebook"
        )
        target = targets.get(qid)
        mine = [item for item in added if target and target in _defined_names(item.source)]
        if not mine:
            plan.deleted[qid] = "missing"
            plan.notes.append(f"{where} (deleted?): {qid} counts as not answered.")
            continue
        for item in mine:
            item.question = qid
            added.remove(item)
        plan.deleted[qid] = "adopted"
        plan.answered.add(qid)
        plan.answer_sources[qid] = "\n\n".join(item.source for item in mine)
        plan.notes.append(
            f"{where} (deleted?); {', '.join(item.label for item in mine)} "
            f"defines {target} and was graded as the answer of {qid}. Keep answers in their "
            "answer cells: JupyterLab does not let you delete them."
        )


def forbidden_mentions(source: str, forbid) -> list[str]:
    """Dotted names in ``forbid`` whose last component the source uses as an attribute, imports,
    or names in a string (``getattr(m, "name")``). Unparsable source falls back to a regex."""
    hits = []
    try:
        tree = ast.parse(python_source(source))
    except (SyntaxError, ValueError):
        tree = None
    for dotted in forbid:
        last = dotted.rsplit(".", 1)[-1]
        found = False
        if tree is None:
            found = (
                re.search(rf"(\.|import\s+|import\s.*,\s*)\b{re.escape(last)}\b", source)
                is not None
            )
        else:
            for node in ast.walk(tree):
                if (
                    (isinstance(node, ast.Attribute) and node.attr == last)
                    or (
                        isinstance(node, ast.ImportFrom) and any(a.name == last for a in node.names)
                    )
                    or (
                        isinstance(node, ast.Import)
                        and any(a.name == dotted or a.name.endswith("." + last) for a in node.names)
                    )
                    or (isinstance(node, ast.Constant) and node.value == last)
                ):
                    found = True
                if found:
                    break
        if found:
            hits.append(dotted)
    return hits
