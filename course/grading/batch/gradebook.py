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

With the term's rules (``--rules term.json``, :mod:`course.grading.batch.termrules`),
``gradebook.csv`` has, after the assignments' columns, one ``<category> %`` column per category,
``dropped`` (the assignments drop-lowest left out), ``percent`` (the final percentage) and
``letter`` and/or ``pass``; an exempted student's cell is ``EX`` (left out, never a 0).
``canvas.csv`` then writes ``EX`` for an exemption (Canvas's "excused"; set the weights and
drop rules in Canvas's assignment groups, as Canvas computes its own total), and ``moodle.csv``
leaves the exempted cell blank and adds ``Final %`` and ``Letter`` (or ``Pass``).
An extension of the rules that moves a student's due date past the time they handed in
waives that assignment's late deduction; a later hand-in needs the assignment graded again
with ``course grade --extensions FILE`` (the gradebook says so).
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

from course.grading.batch.reports import csv_text, read_results
from course.grading.batch.results import StudentResult
from course.grading.batch.roster import Roster, canvas_table, moodle_table, write_table
from course.grading.batch.termrules import TermGrade, TermRules, term_grades
from course.grading.vocabulary import GradeStatus

__all__ = ["Gradebook", "GradebookError", "apply_rules", "read_gradebook", "write_gradebook"]


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


def _column_of(book: Gradebook, name: str, rules: TermRules) -> Column:
    """The column an assignment name of the rules means (its folder name or column name)."""
    hit = next((c for c in book.columns if name in (c.assignment, c.name)), None)
    if hit is None:
        raise GradebookError(
            f"{rules.path}: {name!r} is no assignment of this gradebook ("
            + ", ".join(c.assignment for c in book.columns)
            + "): name each by its folder name or column, or grade it first"
        )
    return hit


def _when(text) -> datetime | None:
    try:
        return datetime.fromisoformat(str(text)) if text else None
    except ValueError:
        return None


def _extended_total(row: StudentResult, due: datetime, what: str) -> float:
    """The row's total under the student's own due date ``due``: as graded when it was
    graded with that due date (or no late record), without the deduction when the file came
    by ``due``; otherwise the row must be graded again with the extension."""
    late = row.late
    if not late or not late.get("percent") or _when(late.get("due")) == due:
        return row.total
    submitted = _when(late.get("submitted_at"))
    if submitted is not None and submitted <= due:
        return row.points
    raise GradebookError(
        f"{what}: the extension to {due.isoformat(timespec='minutes')} still leaves the "
        f"submission late ({late.get('submitted_at') or 'time unknown'}); grade the "
        "assignment again with `course grade ... --extensions FILE` so the deduction is "
        "computed from the new due date, then build the gradebook again"
    )


def apply_rules(
    book: Gradebook, rules: TermRules, students: list[str]
) -> tuple[dict[str, dict[str, float | None]], dict[str, TermGrade]]:
    """Per student, each column's points under the rules (None: exempt; absent: no
    submission) and the :class:`~course.grading.batch.termrules.TermGrade`."""
    named = {a: _column_of(book, a, rules) for c in rules.categories for a in c.assignments}
    placed = {col.name for col in named.values()}
    left = [c.name for c in book.columns if c.name not in placed]
    if left:
        raise GradebookError(
            f"{rules.path}: {', '.join(left)} in no category: add each to a category "
            "(a weight of its own is a category of one)"
        )
    for what, pairs in (("exemption", rules.exemptions), ("extension", rules.extensions)):
        for _, assignment in sorted(pairs):
            if not any(assignment in (c.assignment, c.name) for c in book.columns):
                raise GradebookError(
                    f"{rules.path}: the {what} names {assignment!r}, no assignment of this "
                    "gradebook"
                )
    points: dict[str, dict[str, float | None]] = {}
    for sid in students:
        mine: dict[str, float | None] = {}
        for c in book.columns:
            if (sid, c.assignment) in rules.exemptions or (sid, c.name) in rules.exemptions:
                mine[c.name] = None
                continue
            row = c.rows.get(sid)
            if row is None:
                continue
            due = rules.extensions.get((sid, c.assignment)) or rules.extensions.get((sid, c.name))
            mine[c.name] = (
                row.total if due is None else _extended_total(row, due, f"{sid}, {c.name}")
            )
        points[sid] = mine
    by_rule = {
        sid: {a: mine[col.name] for a, col in named.items() if col.name in mine}
        for sid, mine in points.items()
    }
    maxima = {a: col.max_points for a, col in named.items()}
    return points, term_grades(rules, by_rule, maxima)


def _percent(x: float | None) -> str:
    return "" if x is None else f"{round(x, 2):g}"


def _pass_text(grade: TermGrade) -> str:
    return "" if grade.passed is None else "pass" if grade.passed else "fail"


def _write_with_rules(
    book: Gradebook,
    dest: Path,
    rules: TermRules,
    roster: Roster | None,
    missing_as_zero: bool,
) -> list[Path]:
    students = roster.ids if roster is not None else book.students()
    points, grades = apply_rules(book, rules, students)

    def cell(sid: str, c: Column, exempt: str) -> str:
        mine = points[sid]
        if c.name not in mine:
            return "0" if missing_as_zero else ""
        value = mine[c.name]
        return exempt if value is None else _points(value)

    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    categories = [cat.name for cat in rules.categories]
    tail = (["letter"] if rules.letters else []) + (["pass"] if rules.pass_mark is not None else [])
    writer.writerow(
        ["student", *(csv_text(c.name) for c in book.columns)]
        + [csv_text(f"{name} %") for name in categories]
        + ["dropped", "percent", *tail]
    )
    for sid in students:
        g = grades[sid]
        verdict = ([g.letter] if rules.letters else []) + (
            [_pass_text(g)] if rules.pass_mark is not None else []
        )
        writer.writerow(
            [csv_text(sid), *(cell(sid, c, "EX") for c in book.columns)]
            + [_percent(g.categories[name]) for name in categories]
            + [csv_text("; ".join(g.dropped)), _percent(g.percent), *map(csv_text, verdict)]
        )
    written = [dest / "gradebook.csv"]
    written[0].write_text(buf.getvalue(), encoding="utf-8")
    if roster is None:
        return written
    canvas = [
        (c.name, c.max_points, {sid: cell(sid, c, "EX") for sid in students}) for c in book.columns
    ]
    write_table(canvas_table(roster, canvas), dest / "canvas.csv")
    moodle = [(c.name, {sid: cell(sid, c, "") for sid in students}) for c in book.columns]
    moodle.append(("Final %", {sid: _percent(grades[sid].percent) for sid in students}))
    if rules.letters:
        moodle.append(("Letter", {sid: grades[sid].letter for sid in students}))
    elif rules.pass_mark is not None:
        moodle.append(("Pass", {sid: _pass_text(grades[sid]) for sid in students}))
    write_table(moodle_table(roster, moodle), dest / "moodle.csv")
    return [*written, dest / "canvas.csv", dest / "moodle.csv"]


def write_gradebook(
    book: Gradebook,
    dest: Path,
    roster: Roster | None = None,
    missing_as_zero: bool = False,
    rules: TermRules | None = None,
) -> list[Path]:
    """Write ``gradebook.csv`` (and with a roster ``canvas.csv`` and ``moodle.csv``) into
    ``dest``, under the term's ``rules`` when given; returns the files written."""
    dest = Path(dest)
    dest.mkdir(parents=True, exist_ok=True)
    if rules is not None:
        return _write_with_rules(book, dest, rules, roster, missing_as_zero)
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
