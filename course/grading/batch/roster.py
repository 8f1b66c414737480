"""The class roster, and the grade files a learning-management system imports.

A roster is a CSV file with a header row and one row per student: the student ID (the one
students type as ``STUDENT_ID``), and optionally the name and e-mail. The gradebook exports
of Canvas and Moodle work as rosters as they are (their column names are recognised), and a
hand-made file needs only ``id,name,email``. See ``docs/instructors/term.md``.

``course grade ... --roster FILE`` then reports missing and unknown submissions and writes,
beside ``grades.csv``:

``canvas.csv``
    Canvas's gradebook import: ``Student, ID, SIS User ID, SIS Login ID, Section`` and one
    column named after the assignment, with a ``Points Possible`` row first;
``moodle.csv``
    Moodle's CSV grade import: ``ID number, Email address, First name, Last name``, the
    assignment's column and a ``Feedback`` column.
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass
from pathlib import Path

from course.grading.batch.reports import csv_text, late_sentence
from course.grading.batch.results import StudentResult
from course.grading.vocabulary import STUDENT_ID_RULE, GradeStatus, is_student_id

__all__ = [
    "Roster",
    "RosterError",
    "Student",
    "canvas_table",
    "moodle_table",
    "read_roster",
    "write_canvas_csv",
    "write_moodle_csv",
    "write_table",
]


class RosterError(ValueError):
    """The roster cannot be used (the message names the file, the line and what to do)."""


@dataclass(frozen=True)
class Student:
    id: str
    name: str = ""
    first: str = ""
    last: str = ""
    email: str = ""
    canvas_id: str = ""  # Canvas's own user number (column "ID" of its gradebook export)
    login: str = ""  # Canvas's "SIS Login ID"
    section: str = ""
    participant: str = ""  # Moodle's participant number ("Participant 12" of its worksheet)

    @property
    def sortable_name(self) -> str:
        """ "Last, First", as Canvas writes names."""
        if self.last or self.first:
            return ", ".join(p for p in (self.last, self.first) if p)
        return self.name

    def split_name(self) -> tuple[str, str]:
        """(first, last), as Moodle wants them."""
        if self.first or self.last:
            return self.first, self.last
        if "," in self.name:
            last, first = (p.strip() for p in self.name.split(",", 1))
            return first, last
        first, _, last = self.name.rpartition(" ")
        return (first, last) if first else (self.name, "")


@dataclass
class Roster:
    students: list[Student]
    path: Path

    @property
    def ids(self) -> list[str]:
        return [s.id for s in self.students]

    def get(self, student_id: str) -> Student | None:
        return next((s for s in self.students if s.id == student_id), None)


def _key(header: str) -> str:
    return re.sub(r"[^a-z0-9]", "", header.lower())


# normalised header -> field; the first header present wins for each field
_ALIASES = {
    "id": ["sisuserid", "studentid", "idnumber", "studentnumber", "matriculationnumber", "id"],
    "canvas_id": ["id"],
    "name": ["name", "student", "fullname", "studentname"],
    "first": ["firstname", "givenname"],
    "last": ["lastname", "surname", "familyname"],
    "email": ["email", "emailaddress", "mail"],
    "login": ["sisloginid", "loginid", "username"],
    "section": ["section", "group"],
    "participant": ["identifier", "participant", "participantnumber"],
}
_SKIPPED_NAMES = {"", "points possible", "test student", "student, test"}


def read_roster(path: str | Path) -> Roster:
    """Read a roster CSV (UTF-8, with or without a byte-order mark; ``,`` ``;`` or tab)."""
    path = Path(path)
    try:
        text = path.read_text("utf-8-sig")
    except FileNotFoundError:
        raise RosterError(f"the roster {path} does not exist") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise RosterError(f"cannot read the roster {path}: {exc}") from None
    lines = text.splitlines()
    if not lines or not lines[0].strip():
        raise RosterError(
            f"the roster {path} is empty: it needs a header row such as id,name,email"
        )
    try:
        dialect = csv.Sniffer().sniff(lines[0], delimiters=",;\t")
        delimiter = dialect.delimiter
    except csv.Error:
        delimiter = ","
    reader = csv.reader(io.StringIO(text), delimiter=delimiter)
    header = [_key(h) for h in next(reader)]
    column: dict[str, int] = {}
    for field_name, aliases in _ALIASES.items():
        for alias in aliases:
            if alias in header:
                column[field_name] = header.index(alias)
                break
    if "sisuserid" not in header:
        column.pop("canvas_id", None)  # then "id" is the student ID itself
    if "id" not in column:
        raise RosterError(
            f"the roster {path} has no ID column: name one 'id' (or 'student id', 'ID number', "
            "'SIS User ID'); found columns " + ", ".join(repr(h) for h in header if h)
        )
    students: list[Student] = []
    seen: dict[str, int] = {}
    duplicates: list[str] = []
    for line_no, row in enumerate(reader, start=2):
        if not any(cell.strip() for cell in row):
            continue

        def cell(name: str, row=row) -> str:
            i = column.get(name)
            return row[i].strip() if i is not None and i < len(row) else ""

        sid = cell("id")
        if not sid:
            if cell("name").lower().strip() in _SKIPPED_NAMES:
                continue  # Canvas's "Points Possible" row and its test student
            raise RosterError(f"{path}, line {line_no}: no student ID")
        if not is_student_id(sid):
            raise RosterError(
                f"{path}, line {line_no}: {sid!r} is not a valid student ID ({STUDENT_ID_RULE})"
            )
        if sid in seen:
            duplicates.append(f"{sid!r} (lines {seen[sid]} and {line_no})")
            continue
        seen[sid] = line_no
        students.append(
            Student(
                id=sid,
                name=cell("name"),
                first=cell("first"),
                last=cell("last"),
                email=cell("email"),
                canvas_id=cell("canvas_id"),
                login=cell("login"),
                section=cell("section"),
                participant="".join(re.findall(r"\d+", cell("participant"))),
            )
        )
    if duplicates:
        raise RosterError(
            f"the roster {path} lists the same student ID twice: {', '.join(duplicates)}; "
            "each student needs one row with a unique ID"
        )
    if not students:
        raise RosterError(f"the roster {path} lists no students")
    return Roster(students, path)


# --------------------------------------------------------------------------------------
# LMS grade files
# --------------------------------------------------------------------------------------
def _points(x) -> str:
    return f"{round(float(x), 2):g}"


def _write(rows: list[list[str]], path: Path) -> None:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\r\n")
    for row in rows:
        writer.writerow([csv_text(c) for c in row])
    path.write_text(buf.getvalue(), encoding="utf-8")


def _score(row: StudentResult | None, missing_as_zero: bool) -> str:
    if row is None:
        return "0" if missing_as_zero else ""
    if not row.counts:  # not graded, refused or quarantined: no grade, never a 0
        return ""
    return _points(row.total)


def canvas_table(roster: Roster, columns: list[tuple[str, float, dict[str, str]]]) -> list:
    """Canvas's gradebook import as rows: ``Student, ID, SIS User ID, SIS Login ID, Section``,
    then one column per ``(name, points possible, score by student ID)``; a ``Points Possible``
    row first, as Canvas exports it, and one row per roster student (a missing score: blank,
    which leaves Canvas's grade unchanged)."""
    table = [
        ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", *(c[0] for c in columns)],
        ["    Points Possible", "", "", "", "", *(_points(c[1]) for c in columns)],
    ]
    for s in roster.students:
        table.append(
            [
                s.sortable_name,
                s.canvas_id,
                s.id,
                s.login,
                s.section,
                *(c[2].get(s.id, "") for c in columns),
            ]
        )
    return table


def moodle_table(roster: Roster, columns: list[tuple[str, dict[str, str]]]) -> list:
    """Moodle's CSV grade import as rows: ``ID number, Email address, First name, Last name``
    and one column per ``(name, text by student ID)``, one row per roster student."""
    table = [["ID number", "Email address", "First name", "Last name", *(c[0] for c in columns)]]
    for s in roster.students:
        first, last = s.split_name()
        table.append([s.id, s.email, first, last, *(c[1].get(s.id, "") for c in columns)])
    return table


def write_table(table: list, path: Path) -> None:
    """Write an LMS file: CRLF rows, no cell a spreadsheet would run as a formula."""
    _write(table, path)


def _scores(rows: dict[str, StudentResult], roster: Roster, missing_as_zero: bool) -> dict:
    return {s.id: _score(rows.get(s.id), missing_as_zero) for s in roster.students}


def write_canvas_csv(
    rows: dict[str, StudentResult],
    roster: Roster,
    column: str,
    max_points: float,
    path: Path,
    missing_as_zero: bool = False,
) -> None:
    """Canvas gradebook import: one row per roster student, matched by Canvas on ``ID`` or
    ``SIS User ID`` (our student ID); a blank score leaves Canvas's grade unchanged."""
    columns = [(column, max_points, _scores(rows, roster, missing_as_zero))]
    _write(canvas_table(roster, columns), path)


def _feedback(row: StudentResult | None) -> str:
    if row is None:
        return "No submission received."
    if not row.counts:  # the score is blank: say why, and no points
        return f"Not graded: {'; '.join(row.notes) or row.status}"
    parts = [  # an answer not marked yet says so: its 0 is no grade
        f"{qid} {_points(r.points)}/{_points(r.max)}"
        + (" not marked yet" if r.status == GradeStatus.TO_MARK else "")
        for qid, r in row.questions.items()
    ]
    text = f"{_points(row.total)} of {_points(row.max)} points ({'; '.join(parts)})."
    if row.status != "ok":
        text += f" Status: {row.status}."
    late = late_sentence(row)
    return f"{text} {late}" if late else text


def write_moodle_csv(
    rows: dict[str, StudentResult],
    roster: Roster,
    column: str,
    path: Path,
    missing_as_zero: bool = False,
) -> None:
    """Moodle CSV grade import: map ``ID number`` to useridnumber (or ``Email address`` to
    useremail), the assignment's column to its grade item and ``Feedback`` to its feedback."""
    feedback = {s.id: _feedback(rows.get(s.id)) for s in roster.students}
    columns = [(column, _scores(rows, roster, missing_as_zero)), ("Feedback", feedback)]
    _write(moodle_table(roster, columns), path)
