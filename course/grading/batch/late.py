"""Late work: the due date, when each submission was handed in, and the late penalty.

The due date is ``course grade --due`` (an ISO 8601 date-time with its time zone,
``2026-10-20T23:59+02:00``), else ``Checks(..., due=...)`` in the assignment's ``checks.py``.
When a submission was handed in comes from what the learning-management system (LMS) gives:

* a **timestamps file** (``--submitted-at FILE``): a CSV with a student column (``id``, or the
  ``Identifier``/``ID number``/``Email address`` of a Moodle grading worksheet, or a Canvas
  ``SIS User ID``) and a time column (``submitted_at``, or Moodle's ``Last modified
  (submission)``); an optional ``due`` column holds a student's own due date (an extension).
  A row names a submission by its student ID, its Moodle participant number
  (``Participant 12345``, the number in the folder ``Full Name_12345_assignsubmission_file_``),
  its Canvas user number, or the roster's e-mail address;
* ``--submitted-at file-times``: the files' modification times, meaningful only when the
  download kept them (an archive unpacked with times restored);
* Canvas's ``_LATE_`` marker in a file name (``doejane_LATE_1234_5678_<file>``): late, by a time
  Canvas does not say.

Extensions (``--extensions FILE``, also named by the term's rules, see
:mod:`course.grading.batch.termrules`) are a CSV with the header ``id,assignment,due``: the
student ID, the assignment (its folder name, ``01_least_squares``, or its title) and the
student's own due date (ISO 8601 with its zone). It is read with one fixed dialect (comma,
double quotes, UTF-8), never guessed; its due date wins over a timestamps file's ``due``.

The late policy (``--late-policy``, or ``Checks(..., late_policy=...)``) is a comma-separated
list, e.g. ``percent-per-day:10,cap:50`` or ``percent-per-day:10,zero-after:2026-10-27T23:59Z``:

``percent-per-day:P``
    P % of the points possible per started day late (a minute late is one day), as Canvas's
    own late policy deducts;
``cap:C``
    the deduction never exceeds C % of the points possible;
``zero-after:DATE``
    a submission handed in after DATE scores 0;
``none``
    mark late work, deduct nothing (the default).

The total never drops below 0. A file Canvas marked ``_LATE_`` with no time known is charged
as **one day late** (the least a late file can be), the zero-after rule is not applied to it,
and the console lists it so the instructor can give its time with ``--submitted-at``.
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone
from pathlib import Path

from course.grading.batch.lmsnames import LmsName, lms_name

__all__ = [
    "FILE_TIMES",
    "LateError",
    "LatePolicy",
    "Lateness",
    "late_records",
    "parse_due",
    "parse_policy",
    "read_extensions",
    "read_timestamps",
]

FILE_TIMES = "file-times"
_DAY = timedelta(days=1)


class LateError(ValueError):
    """A due date, late policy or timestamps file that cannot be used (the message says what
    to write instead)."""


def _iso(text: str) -> datetime:
    """``datetime.fromisoformat`` that reads a trailing ``Z`` (UTC) on Python 3.10 too."""
    text = text.strip()
    return datetime.fromisoformat(text[:-1] + "+00:00" if text[-1:] in "Zz" and text else text)


def parse_due(text: str, what: str = "--due") -> datetime:
    """An ISO 8601 date-time with its time zone (``2026-10-20T23:59+02:00`` or ``...Z``)."""
    try:
        when = _iso(str(text))
    except ValueError:
        raise LateError(
            f"{what} {text!r} is not an ISO 8601 date-time: write e.g. 2026-10-20T23:59+02:00"
        ) from None
    if when.tzinfo is None:
        raise LateError(
            f"{what} {text!r} has no time zone: write e.g. 2026-10-20T23:59+02:00 (or Z for UTC)"
        )
    return when


@dataclass(frozen=True)
class LatePolicy:
    """How much a late submission loses (see the module docstring for the syntax)."""

    percent_per_day: float = 0.0
    cap: float = 100.0
    zero_after: datetime | None = None

    def describe(self) -> str:
        """The policy in words, for the feedback and the report."""
        parts = []
        if self.percent_per_day:
            parts.append(f"{self.percent_per_day:g} % of the points possible per started day late")
            if self.cap < 100:
                parts.append(f"at most {self.cap:g} %")
        if self.zero_after is not None:
            parts.append(f"0 points after {_show(self.zero_after)}")
        return ", ".join(parts) or "no deduction"

    def percent(self, days: int | None, submitted: datetime | None) -> float:
        """The deduction in % of the points possible (``days`` None: late by an unknown time,
        charged as one day)."""
        if self.zero_after is not None and submitted is not None and submitted > self.zero_after:
            return 100.0
        if days is None:
            days = 1
        return min(self.cap, self.percent_per_day * days, 100.0)


def parse_policy(text: str | None) -> LatePolicy:
    """``percent-per-day:10,cap:50``, ``zero-after:2026-10-27T23:59+02:00``, ``none``."""
    if text is None or not str(text).strip():
        return LatePolicy()
    values: dict[str, object] = {}
    for item in str(text).split(","):
        key, _, value = item.strip().partition(":")
        key = key.strip().lower()
        if key == "none" and not value:
            continue
        if key in ("percent-per-day", "cap"):
            try:
                number = float(value)
            except ValueError:
                number = math.nan
            if not 0 <= number <= 100:
                raise LateError(
                    f"--late-policy {key}:{value!r}: give a percentage between 0 and 100"
                )
            values[key] = number
        elif key == "zero-after":
            values[key] = parse_due(value.strip(), "--late-policy zero-after:")
        else:
            raise LateError(
                f"--late-policy: unknown rule {item.strip()!r}; use percent-per-day:P, cap:C, "
                "zero-after:DATE or none (e.g. percent-per-day:10,cap:50)"
            )
    return LatePolicy(
        percent_per_day=float(values.get("percent-per-day", 0.0)),  # type: ignore[arg-type]
        cap=float(values.get("cap", 100.0)),  # type: ignore[arg-type]
        zero_after=values.get("zero-after"),  # type: ignore[arg-type]
    )


def _show(when: datetime) -> str:
    return when.isoformat(timespec="minutes")


# -- when each submission was handed in -----------------------------------------------------
_ID_COLUMNS = ("id", "student", "studentid", "sisuserid", "idnumber", "identifier", "emailaddress",
               "email")  # fmt: skip
_TIME_COLUMNS = ("submittedat", "submitted", "submissiontime", "lastmodifiedsubmission",
                 "timesubmitted")  # fmt: skip
# Moodle writes its worksheet's times in the site's language and zone, without the zone
_MOODLE_TIMES = ("%A, %d %B %Y, %I:%M %p", "%d %B %Y, %I:%M %p", "%A, %d %B %Y, %H:%M",
                 "%d %B %Y, %H:%M", "%Y-%m-%d %H:%M:%S", "%Y-%m-%d %H:%M")  # fmt: skip


def _key(header: str) -> str:
    return re.sub(r"[^a-z0-9]", "", header.lower())


def _time(text: str, zone, where: str) -> datetime | None:
    """A time cell (None: no submission, Moodle's ``-``); naive times are in ``zone``."""
    text = text.strip()
    if text in ("", "-"):
        return None
    try:
        when = _iso(text)
    except ValueError:
        when = None
        for fmt in _MOODLE_TIMES:
            try:
                when = datetime.strptime(text, fmt)
                break
            except ValueError:
                continue
    if when is None:
        raise LateError(
            f"{where}: {text!r} is not a time: write ISO 8601 (2026-10-20T23:59+02:00) or "
            "Moodle's 'Tuesday, 20 October 2026, 11:59 PM'"
        )
    if when.tzinfo is None:
        if zone is None:
            raise LateError(
                f"{where}: {text!r} has no time zone and there is no due date to take it from"
            )
        when = when.replace(tzinfo=zone)
    return when


def read_timestamps(path: Path, zone) -> dict[str, tuple[datetime | None, datetime | None]]:
    """``{key: (handed in, own due date or None)}`` of a timestamps CSV (see the module
    docstring); a key is the cell as written, lower-cased, and a Moodle ``Participant N``
    also as ``N``."""
    try:
        text = Path(path).read_text("utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise LateError(f"cannot read the timestamps file {path}: {exc}") from None
    lines = text.splitlines()
    if not lines:
        raise LateError(f"the timestamps file {path} is empty: it needs a header id,submitted_at")
    try:
        delimiter = csv.Sniffer().sniff(lines[0], delimiters=",;\t").delimiter
    except csv.Error:
        delimiter = ","
    reader = csv.reader(io.StringIO(text), delimiter=delimiter)
    header = [_key(h) for h in next(reader)]
    id_col = next((header.index(c) for c in _ID_COLUMNS if c in header), None)
    time_col = next((header.index(c) for c in _TIME_COLUMNS if c in header), None)
    due_col = header.index("due") if "due" in header else None
    if id_col is None or time_col is None:
        raise LateError(
            f"the timestamps file {path} needs a student column (id) and a time column "
            "(submitted_at); found " + ", ".join(repr(h) for h in header if h)
        )
    out: dict[str, tuple[datetime | None, datetime | None]] = {}
    for line_no, row in enumerate(reader, start=2):
        if len(row) <= max(id_col, time_col) or not row[id_col].strip():
            continue
        where = f"{path}, line {line_no}"
        when = _time(row[time_col], zone, where)
        own_due = None
        if due_col is not None and due_col < len(row) and row[due_col].strip():
            own_due = _time(row[due_col], zone, where)
        key = row[id_col].strip().lower()
        out[key] = (when, own_due)
        participant = re.fullmatch(r"participant\s+(\d+)", key)
        if participant:
            out[participant.group(1)] = (when, own_due)
    return out


_EXTENSION_COLUMNS = {"id": ("id", "student", "studentid", "sisuserid", "idnumber"),
                      "assignment": ("assignment",), "due": ("due", "newdue", "duedate")}  # fmt: skip


def read_extensions(path: Path) -> dict[tuple[str, str], datetime]:
    r"""``{(student ID, assignment): own due date}`` of an extensions CSV (header
    ``id,assignment,due``; see the module docstring). One fixed dialect (RFC 4180: comma,
    double quotes), never sniffed: a student's ID is data, not a hint about the format.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "extensions.csv"
    >>> _ = f.write_text("id,assignment,due\ns001,01_least_squares,2026-10-23T23:59+02:00\n")
    >>> read_extensions(f)[("s001", "01_least_squares")].isoformat()
    '2026-10-23T23:59:00+02:00'
    """
    try:
        text = Path(path).read_text("utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise LateError(f"cannot read the extensions file {path}: {exc}") from None
    reader = csv.reader(io.StringIO(text))
    header = [_key(h) for h in next(reader, [])]
    found = {
        name: next((header.index(c) for c in choices if c in header), None)
        for name, choices in _EXTENSION_COLUMNS.items()
    }
    cols = {name: i for name, i in found.items() if i is not None}
    if len(cols) != len(found):
        raise LateError(
            f"the extensions file {path} needs the header id,assignment,due (a comma-separated "
            "CSV); found " + (", ".join(repr(h) for h in header if h) or "nothing")
        )
    out: dict[tuple[str, str], datetime] = {}
    for line_no, row in enumerate(reader, start=2):
        if not any(cell.strip() for cell in row):
            continue
        if len(row) <= max(cols.values()):
            raise LateError(f"{path}, line {line_no}: give id, assignment and due")
        sid, assignment, due = (row[cols[c]].strip() for c in ("id", "assignment", "due"))
        if not sid or not assignment:
            raise LateError(f"{path}, line {line_no}: the id and the assignment must be given")
        key = (sid, assignment)
        if key in out:
            raise LateError(f"{path}, line {line_no}: a second extension of {sid} for {assignment}")
        out[key] = parse_due(due, f"{path}, line {line_no}: due")
    return out


def extensions_for(table: dict[tuple[str, str], datetime], *names: str) -> dict[str, datetime]:
    """The extensions of one assignment, by student ID (``names``: its folder name, title)."""
    wanted = {n for n in names if n}
    return {sid: due for (sid, assignment), due in table.items() if assignment in wanted}


@dataclass(frozen=True)
class Lateness:
    """What is known about one submission's time, as its row's ``late`` record."""

    submitted_at: datetime | None
    due: datetime | None
    source: str  # where the time came from
    marked_late: bool  # the LMS's name says late (Canvas's _LATE_)

    def record(self, policy: LatePolicy) -> dict:
        """The row's ``late`` record: ``days`` late (None: late by an unknown time), the
        deduction in ``percent`` of the points possible, and the texts the reports show."""
        days: int | None
        if self.submitted_at is not None and self.due is not None:
            over = self.submitted_at - self.due
            days = max(0, math.ceil(over / _DAY)) if over > timedelta(0) else 0
        elif self.marked_late:
            days = None
        else:
            days = 0
        percent = policy.percent(days, self.submitted_at) if days != 0 else 0.0
        return {
            "submitted_at": None if self.submitted_at is None else _show(self.submitted_at),
            "due": None if self.due is None else _show(self.due),
            "source": self.source,
            "days": days,
            "percent": round(percent, 4),
            "policy": policy.describe(),
        }


def _lms_name(sub, submissions: Path) -> LmsName:
    """What the LMS's name of the submission says (the file's, or its student's folder's),
    read by that LMS's grammar (:mod:`course.grading.batch.lmsnames`): the uploader's number
    comes from where the LMS wrote it, never from a part the student chose."""
    path = sub.path
    try:
        parts = path.relative_to(submissions).parts
    except ValueError:
        parts = (path.name,)
    top = getattr(sub, "lms", "") or parts[0]
    in_folder = getattr(sub, "in_folder", False) if getattr(sub, "lms", "") else len(parts) > 1
    return lms_name(top, "", folder=in_folder)


def late_records(
    entries: list,
    submissions: Path,
    due: datetime | None,
    policy: LatePolicy,
    submitted_at: str | Path | None = None,
    roster=None,
    extensions: dict[str, datetime] | None = None,
) -> tuple[dict[str, dict], list[str]]:
    """The ``late`` record of every resolved submission that has one, and the console's notes.

    A submission gets a record when there is a due date (the class's, or the student's own in
    ``extensions``, by student ID), or when the LMS marked it late. The time comes from the
    timestamps file (or the file times), else Canvas's ``_LATE_``.
    """
    extensions = extensions or {}
    submissions = Path(submissions).resolve()
    zone = due.tzinfo if due is not None else None
    table = None
    if submitted_at is not None and str(submitted_at) != FILE_TIMES:
        table = read_timestamps(Path(submitted_at), zone)
    emails = {s.id: s.email.lower() for s in (roster.students if roster else ()) if s.email}
    # an LMS number that is also a student ID names that student, never another's upload
    student_ids = {sub.student.lower() for sub in entries}
    records: dict[str, dict] = {}
    unknown, disagree, untimed = [], [], []
    for sub in entries:
        if sub.path is None:
            continue
        name = _lms_name(sub, submissions)
        marked = name.kind == "canvas" and name.late
        when, own_due, source = None, None, ""
        if table is not None:
            keys = [sub.student.lower(), emails.get(sub.student, "")]
            if name.kind in ("canvas", "moodle") and name.number not in student_ids:
                keys.append(name.number)
            hit = next((table[k] for k in keys if k and k in table), None)
            if hit is not None:
                when, own_due = hit
                source = "timestamps file"
            else:
                untimed.append(sub.student)
        elif submitted_at is not None:
            when = datetime.fromtimestamp(os.stat(sub.path).st_mtime, tz=timezone.utc)
            source = "file time"
        if when is None and marked:
            source = "Canvas's _LATE_ in the file name"
        own_due = extensions.get(sub.student, own_due)
        if due is None and own_due is None and not marked:
            continue
        lateness = Lateness(when, own_due or due, source or "no time known", marked)
        record = lateness.record(policy)
        records[sub.student] = record
        if record["days"] is None:
            unknown.append(sub.student)
        elif marked and record["days"] == 0:
            disagree.append(sub.student)
    notes = []
    if unknown:
        charged = any(records[sid]["percent"] for sid in unknown)
        notes.append(
            f"{len(unknown)} file(s) Canvas marked _LATE_ without a known time: "
            + ", ".join(unknown)
            + (
                "; charged as 1 day late"
                if charged
                else "; no deduction (" + ("no due date" if due is None else "the policy") + ")"
            )
            + " (give their times with --submitted-at FILE)"
        )
    if disagree:
        notes.append(
            f"{len(disagree)} file(s) Canvas marked _LATE_ were handed in before the due date "
            "(an extension, or another due date in Canvas?): " + ", ".join(disagree)
        )
    # a file that lists only the late students is the usual case: the others are on time,
    # and are counted, never listed as if something were wrong with them (the files the LMS
    # marked late without a time are named above)
    on_time = [sid for sid in untimed if sid not in unknown]
    if on_time:
        notes.append(
            f"{len(on_time)} submission(s) not in {submitted_at}: taken as handed in on time"
        )
    return records, notes
