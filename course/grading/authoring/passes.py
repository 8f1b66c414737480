"""The student release of a solution notebook, as a pipeline of passes (nbgrader's manner).

:func:`make_release` runs :data:`PASSES` in order over one :class:`Draft`; each pass does one
job and raises :class:`~course.grading.notebook.MarkerError` naming the cell when the solution
notebook breaks its rule:

1. :func:`read_cells`: every cell has a valid, unique id and a known type.
2. :func:`assign_roles`: each cell's role (``metadata.course.role``, else inferred: the first
   code cell with ``STUDENT_ID`` is the setup cell, ``check("q1")`` a check cell, any other
   code a context cell; markdown is text, or a short answer's answer cell).
3. :func:`strip_solutions`: the student's source of each cell (solution regions replaced by
   their stubs, hidden tests removed; a short answer becomes its placeholder), the setup cell's
   ``STUDENT_ID`` replaced by the placeholder, both versions valid Python.
4. :func:`one_answer_cell_each`: a question has at most one answer cell.
5. :func:`write_header_points`: each question's markdown header states its points (checks.py's).
6. :func:`match_checks`: the questions of checks.py and the answer cells agree (kind, the
   variable or function defined, a header each).
7. :func:`add_points_cell`: the cell after the title that states the total.

The passes that need checks.py (5-7) do nothing without ``questions``. :func:`make_release`
then writes the notebook: answer cells get the id ``<question>-answer``, cells get their locks.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import nbformat

from course.grading.items import SHORT_ANSWER_STUB
from course.grading.notebook import (
    _MARKER_WORDS,
    _STUDENT_ID_LINE,
    BEGIN_SOLUTION,
    MarkerError,
    Release,
    ReleaseCell,
    _compiles,
    _course_meta,
    _defined_names,
    _source,
    strip_markers,
)
from course.grading.vocabulary import PLACEHOLDER_ID, CellRole, QuestionKind, answer_cell_id

__all__ = ["PASSES", "POINTS_CELL_ID", "Draft", "make_release", "points_cell_text"]

_VALID_ID = re.compile(r"^[a-zA-Z0-9-_]{1,64}$")
_CHECK_SOURCE = re.compile(r"""^\s*check\(\s*["']([A-Za-z][A-Za-z0-9_]*)["']\s*\)\s*$""")
_ROLES = (CellRole.SETUP, CellRole.ANSWER, CellRole.CHECK, CellRole.CONTEXT)
PLACEHOLDER_LINE = f'STUDENT_ID = "{PLACEHOLDER_ID}"   # <- your student ID, exactly as registered'

#: The id of the release-generated cell that states the total and how points are earned.
POINTS_CELL_ID = "points-total"

# Cell locks of a release (the JupyterLab / nbgrader convention, nbformat cell metadata):
# instructions, context and check cells can be neither edited nor deleted; answer cells and
# the setup cell (its STUDENT_ID line) can be edited but not deleted.
LOCKED = {"editable": False, "deletable": False}
UNDELETABLE = {"editable": True, "deletable": False}


@dataclass
class DraftCell:
    """One cell on its way to the release: the solution's cell, then what the passes decide."""

    index: int
    id: str
    cell_type: str
    solution: str  # the solution's source
    meta: dict  # the solution cell's metadata.course
    where: str  # names the cell in messages
    attachments: Any = None
    role: CellRole | None = None
    question: str | None = None
    released: str = ""  # the student's source


@dataclass
class Draft:
    """The release being built: the notebook's name, checks.py's questions (or None) and the
    cells; :func:`add_points_cell` adds the points cell at ``points_at``."""

    name: str
    solution_nb: Any
    questions: dict | None
    cells: list[DraftCell] = field(default_factory=list)
    all_ids: set = field(default_factory=set)
    answers: dict[str, DraftCell] = field(default_factory=dict)  # question -> its answer cell
    headers: dict[str, str] = field(default_factory=dict)  # question -> where its header is
    points_cell: str | None = None

    @property
    def where(self) -> str:
        return f"{self.name}.ipynb"


def read_cells(draft: Draft) -> None:
    """Every cell has a valid, unique id (``cell-<index>`` when it has none) and a known type."""
    draft.all_ids = {c.get("id") for c in draft.solution_nb.cells}
    seen: set[str] = set()
    for index, cell in enumerate(draft.solution_nb.cells):
        cid = cell.get("id") or f"cell-{index}"
        if not _VALID_ID.match(cid):
            raise MarkerError(f"{draft.where}, cell {index}: id {cid!r} is not a valid cell id")
        if cid in seen:
            raise MarkerError(f"{draft.where}, cell {index}: duplicate cell id {cid!r}")
        seen.add(cid)
        ctype = cell.get("cell_type")
        where = f"{draft.where}, cell {index} (id {cid!r})"
        if ctype not in ("markdown", "raw", "code"):
            raise MarkerError(f"{where}: unknown cell type {ctype!r}")
        draft.cells.append(
            DraftCell(
                index,
                cid,
                ctype,
                _source(cell),
                _course_meta(cell),
                where,
                cell.get("attachments"),
            )
        )


def assign_roles(draft: Draft) -> None:
    """Each cell's role and question; the first code cell is the setup cell."""
    first_code = True
    for c in draft.cells:
        if c.cell_type != "code":
            if c.cell_type == "markdown" and c.meta.get("role") == CellRole.ANSWER:
                if not c.meta.get("question"):
                    raise MarkerError(f"{c.where}: an answer cell needs metadata course.question")
                c.role, c.question = CellRole.ANSWER, c.meta["question"]
            else:
                c.role = CellRole.TEXT
            continue
        role, question = c.meta.get("role"), c.meta.get("question")
        if role is None:
            m = _CHECK_SOURCE.match(c.solution)
            if first_code and _STUDENT_ID_LINE.search(c.solution):
                role = CellRole.SETUP
            elif m:
                role, question = CellRole.CHECK, m.group(1)
            else:
                role = CellRole.CONTEXT
        if role not in _ROLES:
            raise MarkerError(f"{c.where}: unknown role {role!r} (use one of {', '.join(_ROLES)})")
        role = CellRole(role)
        if role == CellRole.SETUP and not first_code:
            raise MarkerError(f"{c.where}: the setup cell must be the first code cell")
        if first_code and role != CellRole.SETUP:
            raise MarkerError(
                f"{c.where}: the first code cell must be the setup cell with STUDENT_ID "
                "(course.grading.authoring.notebooks.setup_cell)"
            )
        first_code = False
        if role in (CellRole.ANSWER, CellRole.CHECK) and not question:
            raise MarkerError(f"{c.where}: an {role} cell needs metadata course.question")
        c.role, c.question = role, question
    if first_code:
        raise MarkerError(
            f"{draft.where}: no code cells (the first code cell must be the setup cell)"
        )


def strip_solutions(draft: Draft) -> None:
    """The student's source of every cell."""
    for c in draft.cells:
        if c.cell_type != "code":
            if c.role == CellRole.ANSWER:
                c.released = SHORT_ANSWER_STUB
                continue
            if _MARKER_WORDS.search(c.solution):
                raise MarkerError(f"{c.where}: markers are only supported in code cells")
            c.released = c.solution
            continue
        released, regions = strip_markers(
            c.solution, c.where, c.question, allow_solution=(c.role == CellRole.ANSWER)
        )
        if c.role == CellRole.ANSWER and regions == 0:
            raise MarkerError(
                f"{c.where}: answer cell for {c.question} has no '{BEGIN_SOLUTION}' region"
            )
        if c.role == CellRole.SETUP:
            if not _STUDENT_ID_LINE.search(released):
                raise MarkerError(
                    f"{c.where}: the setup cell must assign STUDENT_ID on a line of its own"
                )
            # the solution may carry a real ID (e.g. "demo"); students always get the placeholder
            released = _STUDENT_ID_LINE.sub(lambda _m: PLACEHOLDER_LINE, released, count=1)
        for text, what in ((c.solution, "solution"), (released, "released")):
            problem = _compiles(text)
            if problem:
                raise MarkerError(f"{c.where}: the {what} cell is not valid Python ({problem})")
        c.released = released


def one_answer_cell_each(draft: Draft) -> None:
    """A question has at most one answer cell."""
    for c in draft.cells:
        if c.role != CellRole.ANSWER:
            continue
        first = draft.answers.get(str(c.question))
        if first is not None:
            raise MarkerError(
                f"{c.where}: second answer cell for {c.question} (first: cell {first.index})"
            )
        draft.answers[str(c.question)] = c


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


def write_header_points(draft: Draft) -> None:
    """Each question's header (in a markdown text cell) states the points of checks.py."""
    if draft.questions is None:
        return
    for c in draft.cells:
        if c.cell_type == "markdown" and c.role == CellRole.TEXT:
            c.released = write_points(c.released, draft.questions, c.where, draft.headers)


def match_checks(draft: Draft) -> None:
    """checks.py's questions and the answer cells agree: one answer cell per question, of the
    question's kind, defining its variable or function; no answer cell without a question; a
    header per question."""
    if draft.questions is None:
        return
    for qid, q in draft.questions.items():
        cell = draft.answers.get(qid)
        if cell is None:
            raise MarkerError(f"{draft.where}: question {qid} (checks.py) has no answer cell")
        if (q.kind == QuestionKind.SHORT_ANSWER) != (cell.cell_type == "markdown"):
            raise MarkerError(
                f"{draft.where}: the answer cell of {qid} must be a "
                + (
                    "markdown cell (a short answer; course.grading.authoring.notebooks.short_answer_cell)"
                    if q.kind == QuestionKind.SHORT_ANSWER
                    else "code cell"
                )
            )
        if q.kind == QuestionKind.SHORT_ANSWER:
            continue
        if q.target not in _defined_names(cell.solution):
            what = "define function" if q.kind == "function" else "assign variable"
            raise MarkerError(f"{draft.where}: the answer cell of {qid} must {what} {q.target!r}")
    for qid in draft.answers:
        if qid not in draft.questions:
            raise MarkerError(
                f"{draft.where}: answer cell for {qid!r}, which checks.py does not define"
            )
    for qid in draft.questions:
        if qid not in draft.headers:
            raise MarkerError(
                f"{draft.where}: question {qid} has no header: start its markdown cell with a "
                f"heading such as '## {qid}: what it asks' (the release writes its points)"
            )


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
        "- An answer that runs too long or crashes earns 0 for its question; the other "
        "questions are graded as usual."
    )
    if any(getattr(q, "forbid", ()) for q in qs):
        lines.append(
            "- Calling a library function that a question does not allow (under any name, or "
            "through its private implementation) earns that question 0: in its answer cell, while "
            "your function runs, and, for a value question, in any cell you add. Importing it "
            "costs nothing. Another question's answer cell may call what that question allows; "
            "copying this question's answer from such a call is against the honour code, though "
            "the grader cannot see it."
        )
    lines += [
        "",
        '`check("qN")` runs the public checks of one question; hidden cases, values from your '
        "personal data and choices are checked only when your instructor grades. "
        "`check.all()` ends with the points the public checks give.",
    ]
    return "\n".join(lines)


def add_points_cell(draft: Draft) -> None:
    """The text of the cell that states the total (placed after the title by the writer)."""
    if draft.questions is None:
        return
    if POINTS_CELL_ID in draft.all_ids:
        raise MarkerError(f"{draft.where}: the cell id {POINTS_CELL_ID!r} is the release's own")
    draft.points_cell = points_cell_text(draft.questions)


#: The passes of :func:`make_release`, in order.
PASSES: tuple[Callable[[Draft], None], ...] = (
    read_cells,
    assign_roles,
    strip_solutions,
    one_answer_cell_each,
    write_header_points,
    match_checks,
    add_points_cell,
)


def _release_id(draft: Draft, c: DraftCell) -> str:
    """A cell's released id: ``<question>-answer`` for an answer cell whatever the solution
    uses, so every release of the assignment names it alike and the grader finds it when
    moved."""
    if c.role != CellRole.ANSWER:
        return c.id
    stable = answer_cell_id(str(c.question))
    if stable != c.id and stable in draft.all_ids:
        raise MarkerError(
            f"{c.where}: the id {stable!r} belongs to the answer cell of {c.question}; rename "
            "the other cell"
        )
    return stable


def _write(draft: Draft) -> Release:
    """The release notebook of a draft the passes accepted."""
    cells_out = []
    release_cells = []
    for c in draft.cells:
        role = c.role
        assert role is not None
        if c.cell_type == "code":
            new = nbformat.v4.new_code_cell(c.released)
        elif c.cell_type == "markdown":
            new = nbformat.v4.new_markdown_cell(c.released)
        else:
            new = nbformat.v4.new_raw_cell(c.released)
        new["id"] = _release_id(draft, c)
        course_meta: dict[str, Any] = {"role": str(role)}
        if c.question and role != CellRole.TEXT:
            course_meta["question"] = c.question
        new["metadata"] = {
            "course": course_meta,
            **(UNDELETABLE if role in (CellRole.ANSWER, CellRole.SETUP) else LOCKED),
        }
        if role == CellRole.TEXT and c.attachments:
            new["attachments"] = c.attachments
        cells_out.append(new)
        release_cells.append(
            ReleaseCell(
                c.index,
                new["id"],
                c.cell_type,
                role,
                c.question if role != CellRole.TEXT else None,
                c.released,
                c.solution if role != CellRole.TEXT else c.released,
            )
        )
    if draft.points_cell is not None:
        totals = nbformat.v4.new_markdown_cell(draft.points_cell)
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
        "course": {"assignment": draft.name},
    }
    nb["nbformat"], nb["nbformat_minor"] = 4, 5
    nbformat.validate(nb)
    return Release(draft.name, nb, release_cells)


def make_release(solution_nb, name: str, questions: dict | None = None) -> Release:
    """Build the student release of a solution notebook: run :data:`PASSES`, then write it.

    ``questions`` maps question id -> :class:`~course.grading.authoring.checks.Question`; when
    given, every question must have exactly one answer cell (and vice versa) and its variable
    or function must be defined there.
    """
    draft = Draft(name, solution_nb, questions)
    for run in PASSES:
        run(draft)
    return _write(draft)
