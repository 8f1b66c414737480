"""``course gradebook``: several assignments' grading outputs combined into one gradebook.

Each ``OUT`` folder is what ``course grade`` wrote for one assignment; its ``results.jsonl``
holds every graded student's total (short-answer marks merged). The gradebook has one column per
assignment, named as that assignment's LMS files name it (the column of ``OUT/canvas.csv``,
i.e. ``--lms-column`` or the assignment's title; the assignment's folder name without one), and
the total:

``gradebook.csv``
    ``student``, one column per assignment, ``total``, ``max`` (every student graded in any of
    the assignments, or the roster's students with ``--roster``);
``canvas.csv`` (with a roster)
    Canvas's gradebook import with one column per assignment; no total column, because Canvas
    computes its own and would import a column it does not know as a new assignment, counting
    every point twice;
``moodle.csv`` (with a roster)
    Moodle's grade import with one column per assignment and ``Total`` (map it to a grade item,
    or leave it unmapped).

A student without a submission gets an empty cell, or 0 with ``missing_as_zero``; the total
counts an empty cell as 0. A short answer not marked yet counts as 0 (:meth:`Gradebook.unmarked`
counts them, and ``course gradebook`` warns).
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

from course.grading.batch.reports import csv_text, read_results
from course.grading.batch.results import StudentResult
from course.grading.batch.roster import Roster, canvas_table, moodle_table, write_table
from course.grading.vocabulary import GradeStatus

__all__ = ["Gradebook", "GradebookError", "read_gradebook", "write_gradebook"]


class GradebookError(ValueError):
    """An output folder cannot go into the gradebook (the message names it and what to do)."""


@dataclass(frozen=True)
class Column:
    """One assignment of the gradebook: its column name, points possible and rows."""

    name: str
    assignment: str
    max_points: float
    rows: dict[str, StudentResult]


@dataclass(frozen=True)
class Gradebook:
    columns: list[Column]

    @property
    def max_points(self) -> float:
        return sum(c.max_points for c in self.columns)

    def students(self) -> list[str]:
        return sorted({sid for c in self.columns for sid in c.rows})

    def unmarked(self) -> dict[str, int]:
        """Per column that has them: how many short answers are not marked yet (they count as
        0 in the gradebook until they are marked and merged)."""
        counts = {
            c.name: sum(
                res.status == GradeStatus.TO_MARK
                for row in c.rows.values()
                for res in row.questions.values()
            )
            for c in self.columns
        }
        return {name: n for name, n in counts.items() if n}


def _points(x: float) -> str:
    return f"{round(float(x), 2):g}"


def _column_name(out: Path, assignment: str) -> str:
    """The assignment's column in its own LMS files (``--lms-column`` or its title)."""
    canvas = out / "canvas.csv"
    if canvas.is_file():
        header = next(csv.reader(io.StringIO(canvas.read_text("utf-8-sig"))), [])
        if len(header) > 5 and header[5]:
            return header[5].removeprefix("'")
    return assignment


def read_gradebook(outs: list[Path]) -> Gradebook:
    """The gradebook of the grading outputs ``outs`` (one per assignment, in this order)."""
    if not outs:
        raise GradebookError("name at least one grading output folder (the --out of course grade)")
    columns: list[Column] = []
    for out in map(Path, outs):
        results = out / "results.jsonl"
        if not results.is_file():
            raise GradebookError(
                f"{out} holds no results.jsonl: give the --out folder of a `course grade` run"
            )
        rows = read_results(results)
        if not rows:
            raise GradebookError(f"{results} holds no graded student")
        assignments = {r.assignment for r in rows.values()}
        maxima = {r.max for r in rows.values()}
        if len(assignments) != 1 or len(maxima) != 1:
            raise GradebookError(
                f"{results} mixes assignments or maxima ({', '.join(sorted(assignments))}): "
                "grade each assignment into its own folder"
            )
        assignment = assignments.pop()
        twice = next((c for c in columns if c.assignment == assignment), None)
        if twice is not None:
            raise GradebookError(
                f"{out} and another folder both hold {assignment}: give one output per assignment"
            )
        columns.append(Column(_column_name(out, assignment), assignment, maxima.pop(), rows))
    names = [c.name for c in columns]
    if len(set(names)) != len(names):
        raise GradebookError(f"two assignments share a column name: {names}; rename one")
    return Gradebook(columns)


def _cells(book: Gradebook, students: list[str], missing_as_zero: bool) -> dict:
    """Per student: the score text of each column and the total."""
    out = {}
    for sid in students:
        texts, total = [], 0.0
        for c in book.columns:
            row = c.rows.get(sid)
            if row is None:
                texts.append("0" if missing_as_zero else "")
            else:
                texts.append(_points(row.total))
                total += row.total
        out[sid] = (texts, _points(total))
    return out


def write_gradebook(
    book: Gradebook, dest: Path, roster: Roster | None = None, missing_as_zero: bool = False
) -> list[Path]:
    """Write ``gradebook.csv`` (and with a roster ``canvas.csv`` and ``moodle.csv``) into
    ``dest``; returns the files written."""
    dest = Path(dest)
    dest.mkdir(parents=True, exist_ok=True)
    students = roster.ids if roster is not None else book.students()
    cells = _cells(book, students, missing_as_zero)
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["student", *(csv_text(c.name) for c in book.columns), "total", "max"])
    for sid in students:
        texts, total = cells[sid]
        writer.writerow([csv_text(sid), *texts, total, _points(book.max_points)])
    written = [dest / "gradebook.csv"]
    written[0].write_text(buf.getvalue(), encoding="utf-8")
    if roster is None:
        return written
    by_column = [{sid: cells[sid][0][i] for sid in students} for i in range(len(book.columns))]
    canvas = [(c.name, c.max_points, by_column[i]) for i, c in enumerate(book.columns)]
    write_table(canvas_table(roster, canvas), dest / "canvas.csv")
    moodle = [(c.name, by_column[i]) for i, c in enumerate(book.columns)]
    moodle.append(("Total", {sid: cells[sid][1] for sid in students}))
    write_table(moodle_table(roster, moodle), dest / "moodle.csv")
    return [*written, dest / "canvas.csv", dest / "moodle.csv"]
