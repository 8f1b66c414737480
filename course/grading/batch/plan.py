"""The grading plan: which cells of a submitted notebook the grader runs, in which order.

:func:`build_plan` matches a submission against the release
(:class:`~course.grading.notebook.Release`, built by
:func:`~course.grading.authoring.passes.make_release`): protected cells run as released, answer
cells are found by id wherever they moved, cells the student added run where they were added,
and an answer retyped in an added cell is adopted when its answer cell was deleted.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

from course.grading.notebook import (
    _STUDENT_ID_LINE,
    Release,
    ReleaseCell,
    _course_meta,
    _defined_names,
    _source,
    student_id_in,
)
from course.grading.vocabulary import CellOrigin, CellRole, answer_cell_id

__all__ = ["Plan", "PlanCell", "build_plan"]


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
    matcher = _Matcher(release)
    for pos, cell in enumerate(nb.get("cells", [])):
        if isinstance(cell, dict) and cell.get("cell_type") == "markdown":
            matcher.short_answer(plan, cell)
        elif isinstance(cell, dict) and cell.get("cell_type") == "code":
            matcher.code(plan, pos, cell)
    for qid in sorted(matcher.text_answers - plan.answered):
        plan.deleted[qid] = "missing"
        plan.notes.append(
            f"The answer cell of {qid} (id {answer_cell_id(qid)!r}) is missing from the "
            f"notebook (deleted?): {qid} counts as not answered."
        )
    _adopt_added_answers(plan, matcher.slots, matcher.answer_slot, targets or {})
    _lay_out(plan, release, matcher, student_id)
    return plan


class _Matcher:
    """Where each cell of a submission goes: the release cell it matches (its *slot*), or the
    slot of the matched cell before it (an added cell)."""

    def __init__(self, release: Release):
        self.by_id = release.by_id()
        self.text_answers = {
            c.question
            for c in release.cells
            if c.role == CellRole.ANSWER and c.cell_type == "markdown"
        }
        self.code_cells = [c for c in release.cells if c.cell_type == "code"]
        self.slots: dict[Any, list[PlanCell]] = {c.index: [] for c in self.code_cells}
        self.answer_slot = {
            c.question: c.index for c in self.code_cells if c.role == CellRole.ANSWER
        }
        self.used_ids: set[str] = set()
        self.anchor = release.setup.index  # the slot an added cell joins

    def short_answer(self, plan: Plan, cell: dict) -> None:
        """A markdown cell: the text of a short answer (matched by id, then metadata)."""
        cid = cell.get("id") if isinstance(cell.get("id"), str) else None
        meta = _course_meta(cell)
        if cid in self.by_id and self.by_id[cid].question in self.text_answers:
            qid = self.by_id[cid].question
        elif meta.get("role") == CellRole.ANSWER and meta.get("question") in self.text_answers:
            qid = meta["question"]
        else:
            return
        plan.texts[qid] = (plan.texts.get(qid, "") + "\n\n" + _source(cell)).strip()
        plan.answered.add(qid)

    def _match(self, cell: dict) -> ReleaseCell | str | None:
        """The release cell a code cell matches: by id (once), then an answer by metadata;
        ``"copy"`` for a copy of a protected cell; None for a cell the student added."""
        cid = cell.get("id")
        meta = _course_meta(cell)
        if (
            isinstance(cid, str)
            and cid in self.by_id
            and cid not in self.used_ids
            and self.by_id[cid].cell_type == "code"
        ):
            self.used_ids.add(cid)
            return self.by_id[cid]
        if meta.get("role") == CellRole.ANSWER and meta.get("question") in self.answer_slot:
            slot = self.answer_slot[meta["question"]]
            return next(c for c in self.code_cells if c.index == slot)
        if meta.get("role") in (CellRole.SETUP, CellRole.CONTEXT, CellRole.CHECK):
            return "copy"
        return None

    def code(self, plan: Plan, pos: int, cell: dict) -> None:
        src = _source(cell)
        match = self._match(cell)
        if match == "copy":
            plan.notes.append(
                f"Ignored a copy of a protected cell (notebook cell {pos + 1}); protected cells run as released."
            )
            return
        if not isinstance(match, ReleaseCell):
            self.slots[self.anchor].append(
                PlanCell(src, None, CellOrigin.EXTRA, f"your added cell at position {pos + 1}")
            )
            return
        if match.role == CellRole.ANSWER:
            self.slots[match.index].append(
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
        self.anchor = match.index


def _lay_out(plan: Plan, release: Release, matcher: _Matcher, student_id: str) -> None:
    """The cells to run in release order: a protected cell's released version, then its slot
    (answers and added cells); an answer's slot is the question's answer source."""
    for cell in matcher.code_cells:
        slot = matcher.slots[cell.index]
        if cell.role == CellRole.SETUP:
            plan.cells.append(
                PlanCell(setup_source(release, student_id), None, CellOrigin.SETUP, "setup cell")
            )
        elif cell.role == CellRole.CONTEXT:
            plan.cells.append(
                PlanCell(cell.source, None, CellOrigin.CONTEXT, f"protected cell {cell.id!r}")
            )
        if cell.role != CellRole.ANSWER:
            plan.cells.extend(slot)
            continue
        q = cell.question
        for item in slot:
            plan.cells.append(PlanCell(item.source, item.question or q, item.origin, item.label))
        if q not in plan.deleted:
            own = [item for item in slot if item.question in (None, q)]
            plan.answer_sources[q] = "\n\n".join(item.source for item in own)


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
