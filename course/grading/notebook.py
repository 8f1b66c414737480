"""Notebooks: solution markers, the release's cells, and reading a submission.

The solution notebook's code cells have roles (``metadata.course.role``):

``setup``    the first code cell: ``STUDENT_ID = "..."`` and ``check = Assignment.load(...)``
``answer``   a student's answer to ``metadata.course.question``; holds SOLUTION regions
``check``    ``check("q1")``: the self-check (skipped at grading)
``context``  any other code cell (protected: the release version runs at grading)

:func:`~course.grading.authoring.passes.make_release` turns it into the student notebook
(a :class:`Release`); :func:`~course.grading.batch.plan.build_plan` matches a submitted
notebook against the release and lists what the grader runs, in which order.
"""

from __future__ import annotations

import ast
import errno
import json
import os
import re
import stat
from dataclasses import dataclass
from typing import Any

from course.grading.vocabulary import (
    CellRole,
)

__all__ = [
    "MarkerError",
    "Release",
    "ReleaseCell",
    "SubmissionError",
    "read_notebook_bytes",
    "read_submission",
    "reduce_notebook",
    "student_id_in",
]

BEGIN_SOLUTION = "### BEGIN SOLUTION"
END_SOLUTION = "### END SOLUTION"
BEGIN_HIDDEN = "### BEGIN HIDDEN TESTS"
END_HIDDEN = "### END HIDDEN TESTS"
STUB_PREFIX = "### STUB"
_MARKER_WORDS = re.compile(r"(BEGIN|END)\s+(SOLUTION|HIDDEN\s+TESTS)", re.IGNORECASE)
_STUDENT_ID_LINE = re.compile(r"^STUDENT_ID\s*=.*$", re.MULTILINE)
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


#: Cells the trusted parent hands to IPython's input transformer at most: it re-tokenizes the
#: whole cell once per magic or ``!`` line (up to 500 passes), so its time grows with the
#: square of a cell full of them (600 ``!`` lines took 52 s). Larger ones are not transformed.
MAX_TRANSFORMED_CHARS = 20_000
MAX_TRANSFORMED_LINES = 40  # lines that look like IPython syntax
#: Cells the parent parses at all (the syntax tree costs ~630 bytes of memory per source
#: byte, so 50,000 characters cost ~32 MB); a larger cell is :class:`SyntaxError` to every
#: reader here (its forbidden-call scan falls back to the linear text scan).
MAX_PARSED_CHARS = 50_000


def _ipython_lines(source: str) -> int:
    """How many lines may need IPython's transformer (magics, ``!cmd``, ``x?``, prompts)."""
    return sum(
        1
        for line in source.splitlines()
        if line.lstrip()[:1] in ("%", "!", "?", ">")
        or line.rstrip().endswith("?")
        or "= !" in line
        or "= %" in line
    )


def python_source(source: str) -> str:
    """Cell source with IPython syntax (magics, ``!cmd``) turned into plain Python.

    Plain Python is returned as it is (IPython would not change it). IPython's transformer
    runs only on a cell within :data:`MAX_TRANSFORMED_CHARS` and
    :data:`MAX_TRANSFORMED_LINES`; a larger one comes back unchanged, so its callers see
    a cell that does not parse (its student's problem, never the batch's). A cell beyond
    :data:`MAX_PARSED_CHARS` raises :class:`SyntaxError`.
    """
    if len(source) > MAX_PARSED_CHARS:
        raise SyntaxError(f"the cell is larger than {MAX_PARSED_CHARS:,} characters")
    try:
        ast.parse(source)
        return source
    except (SyntaxError, ValueError):
        pass
    except (RecursionError, MemoryError):
        raise SyntaxError("the cell is nested too deeply to read") from None
    if len(source) > MAX_TRANSFORMED_CHARS or _ipython_lines(source) > MAX_TRANSFORMED_LINES:
        return source
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
        import nbformat  # only the release writes notebooks (the fork server never does)

        return nbformat.writes(self.notebook) + "\n"


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
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)  # a FIFO never waits
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


#: What the grader keeps of a submission (:func:`reduce_notebook`): at most this many cells,
#: this many characters of cell source in all, and this many characters in an id, a role, a
#: question or a submission field. Outputs and other metadata are dropped unread.
MAX_CELLS = 2_000
MAX_SOURCE_CHARS = 1_000_000
MAX_FIELD_CHARS = 200
_SUBMISSION_FIELDS = 32


def _short(value) -> str | None:
    return value if isinstance(value, str) and len(value) <= MAX_FIELD_CHARS else None


def reduce_notebook(nb) -> dict:
    """The part of a decoded submission the grader reads, with bounded size.

    Kept: each cell's type, id, source and ``metadata.course`` role and question, and the
    notebook's ``metadata.course`` assignment and submission fields (scalars, short strings);
    outputs and every
    other field are dropped. The sandboxed child that decodes a submission sends only this to
    the parent (:meth:`course.grading.sandbox.parent.Sandbox.read_notebook`), so what a notebook
    costs the parent is bounded by :data:`MAX_CELLS`, :data:`MAX_SOURCE_CHARS` and
    :data:`MAX_FIELD_CHARS`, whatever the file holds. :class:`SubmissionError` (that student's
    problem) when the notebook exceeds them or is not a notebook.
    """
    if not isinstance(nb, dict) or not isinstance(nb.get("cells", None), list):
        raise SubmissionError(
            "the file is JSON but not a Jupyter notebook (no 'cells' list; nbformat 4 expected)"
        )
    if len(nb["cells"]) > MAX_CELLS:
        raise SubmissionError(
            f"the notebook has {len(nb['cells']):,} cells; the grader reads at most {MAX_CELLS:,}"
        )
    cells, chars = [], 0
    for cell in nb["cells"]:
        if not isinstance(cell, dict):
            continue
        source = _source(cell)
        chars += len(source)
        if chars > MAX_SOURCE_CHARS:
            raise SubmissionError(
                f"the notebook's cells hold more than {MAX_SOURCE_CHARS:,} characters of "
                "source; the grader reads at most that (outputs do not count)"
            )
        meta = _course_meta(cell)
        kept = {k: meta[k] for k in ("role", "question") if _short(meta.get(k)) is not None}
        cells.append(
            {
                "cell_type": _short(cell.get("cell_type")),
                "id": _short(cell.get("id")),
                "source": source,
                "metadata": {"course": kept} if kept else {},
            }
        )
    top = nb.get("metadata")
    course = top.get("course") if isinstance(top, dict) else None
    submission = course.get("submission") if isinstance(course, dict) else None
    fields: dict = {}
    if isinstance(submission, dict):
        for key, value in list(submission.items())[:_SUBMISSION_FIELDS]:
            if _short(key) is not None and (
                _short(value) is not None
                or (isinstance(value, (int, float, bool)) or value is None)
            ):
                fields[key] = value
    kept_course: dict = {"submission": fields} if fields else {}
    assignment = course.get("assignment") if isinstance(course, dict) else None
    if _short(assignment) is not None:  # which assignment's notebook it is
        kept_course["assignment"] = assignment
    return {"metadata": {"course": kept_course} if kept_course else {}, "cells": cells}


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
