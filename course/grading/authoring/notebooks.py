"""Helpers to write solution notebooks with the cell metadata and stable ids the grader needs.

Use them in a generator script (see ``docs/instructors/authoring.md``)::

    nb = new_assignment_notebook("01_example", [
        md("# Example"), setup_cell("01_example"), code("import numpy as np"),
        md("**q1** ..."), answer_cell("q1", "### BEGIN SOLUTION\\nx = 1\\n### END SOLUTION"),
        check_cell("q1"),
    ])
    nbformat.write(nb, "solutions/01_example/01_example.ipynb")
"""

from __future__ import annotations

import re

import nbformat

__all__ = [
    "SETUP_TEMPLATE",
    "answer_cell",
    "check_cell",
    "code",
    "md",
    "new_assignment_notebook",
    "setup_cell",
    "short_answer_cell",
]

SETUP_TEMPLATE = """\
STUDENT_ID = "{student_id}"   # <- your student ID, exactly as registered
from course.grading import Assignment
check = Assignment.load("{name}", student_id=STUDENT_ID)"""


def _code(source: str, cell_id: str | None, course: dict | None):
    cell = nbformat.v4.new_code_cell(source)
    cell["metadata"] = {"course": course} if course else {}
    cell["id"] = cell_id
    return cell


def setup_cell(name: str, student_id: str = "demo"):
    """The first code cell: the student's ID and the self-check object ``check``.

    The solution notebook runs as ``student_id`` (default ``"demo"``); the release always
    replaces that line with a placeholder the student overwrites.
    """
    return _code(
        SETUP_TEMPLATE.format(name=name, student_id=student_id), "setup", {"role": "setup"}
    )


def answer_cell(question: str, source: str, cell_id: str | None = None):
    """An answer cell of ``question``; ``source`` holds ``### BEGIN/END SOLUTION`` regions."""
    return _code(source, cell_id or f"{question}-answer", {"role": "answer", "question": question})


def short_answer_cell(question: str, model_answer: str = "", cell_id: str | None = None):
    """The markdown answer cell of a short-answer question (``CHECKS.short_answer``).

    ``model_answer`` is the solution's text (instructors only): the release replaces the whole
    cell by a placeholder line the student overwrites.
    """
    cell = nbformat.v4.new_markdown_cell(model_answer or "*(model answer)*")
    cell["metadata"] = {"course": {"role": "answer", "question": question}}
    cell["id"] = cell_id or f"{question}-answer"
    return cell


def check_cell(question: str, cell_id: str | None = None):
    """``check("q1")``: the student's self-check of ``question``."""
    return _code(
        f'check("{question}")',
        cell_id or f"{question}-check",
        {"role": "check", "question": question},
    )


def md(text: str, cell_id: str | None = None):
    """A markdown cell (protected)."""
    cell = nbformat.v4.new_markdown_cell(text)
    cell["id"] = cell_id
    return cell


def code(source: str, cell_id: str | None = None):
    """A protected code cell: at grading its released version runs, whatever the student did."""
    return _code(source, cell_id, None)


def new_assignment_notebook(name: str, cells):
    """A notebook from these cells; cells without an id get ``<kind>-<NN>`` by position."""
    nb = nbformat.v4.new_notebook()
    used = {c["id"] for c in cells if c.get("id")}
    for i, cell in enumerate(cells):
        if not cell.get("id"):
            base = f"{'text' if cell['cell_type'] == 'markdown' else 'code'}-{i:02d}"
            cid, k = base, 1
            while cid in used:
                k += 1
                cid = f"{base}-{k}"
            cell["id"] = cid
            used.add(cid)
        if not re.match(r"^[a-zA-Z0-9-_]{1,64}$", cell["id"]):
            raise ValueError(f"invalid cell id {cell['id']!r}")
    if len(used) != len(cells):
        raise ValueError("duplicate cell ids")
    nb["cells"] = list(cells)
    nb["metadata"] = {
        "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
        "language_info": {"name": "python"},
        "course": {"assignment": name},
    }
    nbformat.validate(nb)
    return nb
