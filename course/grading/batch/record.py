"""The term's record: the grading state of one assignment's class in one SQLite database.

``OUT/record.sqlite`` (Python's :mod:`sqlite3`, WAL mode, every change in a transaction) holds

* ``submissions``: each file graded or refused, its sha256, where it came from and whom it was
  attributed to, and why;
* ``results``: each student's current row (:class:`~course.grading.batch.results.StudentResult`
  as JSON), and whether it is a grade at all (``graded`` 0: the grader failed on it, so it is
  *not graded*: blank in every LMS file and graded again by the next run);
* ``answers`` and ``marks``: the short answers to mark and each mark with its marker and time;
* ``late`` and ``quarantines``: each student's late record and each file held back;
* ``history``: every change of a grade, a mark, a late record or a quarantine, with who made
  it and when (``course history OUT STUDENT`` prints a student's).

``grades.csv``, ``results.jsonl``, ``short_answers.csv``, ``canvas.csv``, ``moodle.csv``, the
feedback and ``report.html`` are exports, written from the record and never read back as
truth. Two marking views (two markers, two browser tabs) write their marks row by row in
transactions, so neither loses the other's. nbgrader keeps its gradebook in SQLite for the same
reasons.

An output folder of an older version (``results.jsonl`` and ``short_answer_marks.json``, no
record) is imported once, the first time the record is opened there (:meth:`Record.import_old`).
"""

from __future__ import annotations

import getpass
import json
import os
import sqlite3
import threading
from contextlib import contextmanager
from datetime import datetime, timezone
from pathlib import Path

from course.grading.batch.reports import read_results
from course.grading.batch.results import StudentResult

__all__ = ["RECORD_FILE", "Record", "whoami"]

RECORD_FILE = "record.sqlite"

_SCHEMA = """
CREATE TABLE IF NOT EXISTS submissions (
    student TEXT NOT NULL, name TEXT NOT NULL, sha256 TEXT, origin TEXT NOT NULL,
    reason TEXT NOT NULL, PRIMARY KEY (student, name));
CREATE TABLE IF NOT EXISTS results (
    student TEXT PRIMARY KEY, graded INTEGER NOT NULL, row TEXT NOT NULL,
    at TEXT NOT NULL, who TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS answers (
    student TEXT NOT NULL, question TEXT NOT NULL, answer_id TEXT NOT NULL, text TEXT NOT NULL,
    points_possible REAL NOT NULL, rubric TEXT NOT NULL, position INTEGER NOT NULL,
    PRIMARY KEY (student, question));
CREATE TABLE IF NOT EXISTS marks (
    student TEXT NOT NULL, question TEXT NOT NULL, answer_id TEXT NOT NULL, points REAL,
    comment TEXT NOT NULL, who TEXT NOT NULL, at TEXT NOT NULL,
    PRIMARY KEY (student, question));
CREATE TABLE IF NOT EXISTS late (student TEXT PRIMARY KEY, record TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS quarantines (
    file TEXT PRIMARY KEY, named_as TEXT NOT NULL, declares TEXT NOT NULL, why TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS history (
    id INTEGER PRIMARY KEY AUTOINCREMENT, at TEXT NOT NULL, who TEXT NOT NULL,
    student TEXT NOT NULL, kind TEXT NOT NULL, question TEXT NOT NULL, change TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
"""


def whoami() -> str:
    """Who makes a change: ``COURSE_MARKER`` if set (a shared account), else the login name."""
    name = os.environ.get("COURSE_MARKER", "").strip()
    if name:
        return name
    try:
        return getpass.getuser()
    except (KeyError, OSError):  # no name for this uid (a container)
        return f"uid {os.getuid()}"


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z")


def _fmt(x) -> str:
    return f"{round(float(x), 4):g}"


def _grade_text(row: StudentResult, graded: bool) -> str:
    """A grade as the history shows it: ``14/17 ok (q1 1/1, q2 0/2) file ab12cd34ef56``."""
    if not graded:
        return f"NOT GRADED ({row.status})"
    parts = ", ".join(f"{qid} {_fmt(r.points)}/{_fmt(r.max)}" for qid, r in row.questions.items())
    sha = (row.file or {}).get("sha256") or ""
    late = f", late -{_fmt(row.penalty)}" if row.penalty else ""
    return f"{_fmt(row.total)}/{_fmt(row.max)} {row.status} ({parts}{late})" + (
        f" file {sha[:12]}" if sha else ""
    )


class Record:
    """The record of the grading output folder ``out`` (created on first use).

    One connection per object, used under a lock (a view's widget callbacks and the driver's
    threads may share it); every change is one ``BEGIN IMMEDIATE`` transaction, so two
    processes writing at once wait for each other (up to ``timeout`` seconds) instead of
    overwriting each other.
    """

    def __init__(self, out: str | Path, who: str | None = None, timeout: float = 30.0):
        self.out = Path(out)
        self.path = self.out / RECORD_FILE
        self.who = who or whoami()
        self.created = not self.path.exists()
        self._lock = threading.Lock()
        self._con = sqlite3.connect(
            self.path, timeout=timeout, isolation_level=None, check_same_thread=False
        )
        self._con.execute("PRAGMA journal_mode=WAL")
        self._con.execute("PRAGMA synchronous=NORMAL")
        with self._tx() as con:
            for statement in _SCHEMA.split(";"):
                if statement.strip():
                    con.execute(statement)

    def close(self) -> None:
        with self._lock:
            self._con.close()

    def __enter__(self) -> Record:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    @contextmanager
    def _tx(self):
        with self._lock:
            self._con.execute("BEGIN IMMEDIATE")
            try:
                yield self._con
            except BaseException:
                self._con.execute("ROLLBACK")
                raise
            self._con.execute("COMMIT")

    def _read(self, sql: str, args=()) -> list:
        with self._lock:
            return self._con.execute(sql, args).fetchall()

    def _log(self, con, student: str, kind: str, change: str, question: str = "", who=None):
        con.execute(
            "INSERT INTO history (at, who, student, kind, question, change) VALUES (?,?,?,?,?,?)",
            (_now(), who or self.who, student, kind, question, change),
        )

    # -- results --------------------------------------------------------------------------
    def results(self, graded: bool | None = True) -> dict[str, StudentResult]:
        """The current rows by student: graded ones (``graded`` True), those the grader failed
        on (False), or all (None)."""
        rows = self._read("SELECT student, graded, row FROM results ORDER BY student")
        return {
            sid: StudentResult.from_json(json.loads(text))
            for sid, ok, text in rows
            if graded is None or bool(ok) == graded
        }

    def not_graded(self) -> list[str]:
        """The students whose last attempt was not graded (a fault of the grader)."""
        return [sid for (sid,) in self._read("SELECT student FROM results WHERE graded = 0")]

    def put_result(self, row: StudentResult, graded: bool = True, who: str | None = None) -> None:
        """Store ``row`` as the student's current row; the history keeps the change of grade."""
        text = json.dumps(row.to_json(), ensure_ascii=False)
        change = _grade_text(row, graded)
        with self._tx() as con:
            old = con.execute(
                "SELECT graded, row FROM results WHERE student = ?", (row.student,)
            ).fetchone()
            con.execute(
                "INSERT OR REPLACE INTO results (student, graded, row, at, who) VALUES (?,?,?,?,?)",
                (row.student, int(graded), text, _now(), who or self.who),
            )
            before = (
                _grade_text(StudentResult.from_json(json.loads(old[1])), bool(old[0]))
                if old
                else None
            )
            if before != change:
                self._log(con, row.student, "grade", change, who=who)

    def forget_results(self) -> None:
        """Drop every current row (``--regrade`` of the whole class); the history stays."""
        with self._tx() as con:
            con.execute("DELETE FROM results")

    # -- what was handed in ---------------------------------------------------------------
    def set_submissions(self, files: list[tuple[str, str, str | None, str, str]]) -> None:
        """This run's files: (student, name, sha256, origin, reason), replacing the last run's."""
        with self._tx() as con:
            con.execute("DELETE FROM submissions")
            con.executemany("INSERT OR REPLACE INTO submissions VALUES (?,?,?,?,?)", files)

    def submissions(self, student: str | None = None) -> list[tuple]:
        if student is None:
            return self._read("SELECT * FROM submissions ORDER BY student, name")
        return self._read("SELECT * FROM submissions WHERE student = ? ORDER BY name", (student,))

    def set_quarantines(self, rows: list[tuple[str, str, str, str]]) -> None:
        """This run's quarantined files (file, the ID its name gives, the ID it declares, why);
        a file no longer held back is cleared, in the history of both IDs."""
        new = {r[0]: tuple(str(x or "") for x in r) for r in rows}
        with self._tx() as con:
            old = {r[0]: r for r in con.execute("SELECT * FROM quarantines").fetchall()}
            for file, (_, named, declares, why) in new.items():
                if file not in old:
                    for sid in {named, declares} - {""}:
                        self._log(con, sid, "quarantine", f"{file} held back: {why}")
            for file, (_, named, declares, _why) in old.items():
                if file not in new:
                    for sid in {named, declares} - {""}:
                        self._log(con, sid, "quarantine", f"{file} cleared")
            con.execute("DELETE FROM quarantines")
            con.executemany("INSERT INTO quarantines VALUES (?,?,?,?)", list(new.values()))

    def quarantines(self) -> list[tuple]:
        return self._read("SELECT * FROM quarantines ORDER BY file")

    def set_late(self, records: dict[str, dict]) -> None:
        """This run's late records by student; a changed one goes into the history."""
        with self._tx() as con:
            old = dict(con.execute("SELECT student, record FROM late").fetchall())
            for sid, record in records.items():
                text = json.dumps(record, sort_keys=True)
                if old.get(sid) != text:
                    days = record.get("days")
                    self._log(
                        con,
                        sid,
                        "late",
                        f"{'unknown' if days is None else days} day(s) late, "
                        f"{_fmt(record.get('percent') or 0)} % deducted ({record.get('source')})",
                    )
            con.execute("DELETE FROM late")
            con.executemany(
                "INSERT INTO late VALUES (?,?)",
                [(sid, json.dumps(r, sort_keys=True)) for sid, r in records.items()],
            )

    # -- short answers and marks ----------------------------------------------------------
    def set_answers(self, answers: list[dict]) -> None:
        """The short answers to mark (dicts of student, question, answer_id, text,
        points_possible, rubric), in marking-file order, replacing the last run's."""
        with self._tx() as con:
            con.execute("DELETE FROM answers")
            con.executemany(
                "INSERT INTO answers VALUES (?,?,?,?,?,?,?)",
                [
                    (
                        a["student"],
                        a["question"],
                        a["answer_id"],
                        a["text"],
                        float(a["points_possible"]),
                        a["rubric"],
                        i,
                    )
                    for i, a in enumerate(answers)
                ],
            )

    def answers(self) -> list[dict]:
        """The short answers to mark, each with its mark (``points`` None: not marked; a mark
        given to another text of the answer does not count)."""
        rows = self._read(
            "SELECT a.student, a.question, a.answer_id, a.text, a.points_possible, a.rubric, "
            "m.points, m.comment, m.answer_id FROM answers a LEFT JOIN marks m "
            "ON a.student = m.student AND a.question = m.question ORDER BY a.position"
        )
        out = []
        for sid, qid, aid, text, top, rubric, points, comment, marked_id in rows:
            same = marked_id == aid
            out.append(
                {
                    "student": sid,
                    "question": qid,
                    "answer_id": aid,
                    "text": text,
                    "points_possible": top,
                    "rubric": rubric,
                    "points": points if same else None,
                    "comment": (comment or "") if same else "",
                }
            )
        return out

    def has_answers(self) -> bool:
        return bool(self._read("SELECT 1 FROM answers LIMIT 1"))

    def marks(self) -> dict[str, dict[str, dict]]:
        """Every mark given: student -> question -> {points, comment, answer_id, who, at}
        (a mark cleared in the view has ``points`` None and is left out)."""
        out: dict[str, dict[str, dict]] = {}
        for sid, qid, aid, points, comment, who, at in self._read(
            "SELECT student, question, answer_id, points, comment, who, at FROM marks"
        ):
            if points is not None:
                out.setdefault(sid, {})[qid] = {
                    "points": points,
                    "comment": comment,
                    "answer_id": aid,
                    "who": who,
                    "at": at,
                }
        return out

    def set_mark(
        self,
        student: str,
        question: str,
        answer_id: str,
        points: float | None,
        comment: str = "",
        who: str | None = None,
        current: bool = True,
    ) -> bool:
        """Give the answer ``answer_id`` of ``student`` to ``question`` its mark (``points``
        None: clear it); True when it changed. ``current``: refuse (ValueError) unless the
        record's answer to mark still has this ``answer_id`` (checked in the same transaction,
        so a regrade in between cannot slip a mark onto a new answer)."""
        with self._tx() as con:
            if current:
                row = con.execute(
                    "SELECT answer_id FROM answers WHERE student = ? AND question = ?",
                    (student, question),
                ).fetchone()
                if row is None or row[0] != answer_id:
                    raise ValueError("this answer is no longer the one to mark")
            old = con.execute(
                "SELECT answer_id, points, comment FROM marks WHERE student = ? AND question = ?",
                (student, question),
            ).fetchone()
            if old == (answer_id, points, comment):
                return False
            con.execute(
                "INSERT OR REPLACE INTO marks VALUES (?,?,?,?,?,?,?)",
                (student, question, answer_id, points, comment, who or self.who, _now()),
            )
            shown = "not marked" if points is None else f"{_fmt(points)} points"
            self._log(
                con,
                student,
                "mark",
                shown + (f", comment {comment!r}" if comment else "") + f" (answer {answer_id})",
                question,
                who,
            )
            return True

    # -- history --------------------------------------------------------------------------
    def history(self, student: str) -> list[tuple[str, str, str, str, str]]:
        """Every change of ``student``'s grade, marks, late record and quarantines, oldest
        first: (when, who, kind, question, change)."""
        return self._read(
            "SELECT at, who, kind, question, change FROM history WHERE student = ? ORDER BY id",
            (student,),
        )

    def students(self) -> list[str]:
        return [s for (s,) in self._read("SELECT DISTINCT student FROM history ORDER BY student")]

    def meta(self, key: str) -> str | None:
        rows = self._read("SELECT value FROM meta WHERE key = ?", (key,))
        return rows[0][0] if rows else None

    def set_meta(self, key: str, value: str) -> None:
        with self._tx() as con:
            con.execute("INSERT OR REPLACE INTO meta VALUES (?, ?)", (key, value))

    # -- an older folder ------------------------------------------------------------------
    def import_old(self, results_jsonl: Path, marks_json: Path | None = None) -> str:
        """Import an output folder of an older version once (a fresh record only): the rows of
        ``results.jsonl`` (the last row of a student wins; a line that is not a row is skipped)
        and the marks of ``short_answer_marks.json``. Returns the message to show ("" when
        nothing was imported)."""
        if not self.created or self._read("SELECT 1 FROM meta WHERE key = 'imported'"):
            return ""
        rows = read_results(results_jsonl)
        marks: dict = {}
        if marks_json is not None and marks_json.is_file():
            try:
                data = json.loads(marks_json.read_text("utf-8"))
                marks = data if isinstance(data, dict) else {}
            except ValueError:
                marks = {}
        who = f"{self.who} (imported)"
        for row in rows.values():
            self.put_result(row, graded=row.status != "grader error", who=who)
        n_marks = 0
        for sid, by_q in marks.items():
            for qid, mark in (by_q or {}).items():
                try:
                    points = float(mark["points"])
                    self.set_mark(
                        str(sid),
                        str(qid),
                        str(mark.get("answer_id", "")),
                        points,
                        str(mark.get("comment", "")),
                        who=who,
                        current=False,
                    )
                    n_marks += 1
                except (KeyError, TypeError, ValueError):
                    continue
        with self._tx() as con:
            con.execute("INSERT OR REPLACE INTO meta VALUES ('imported', ?)", (_now(),))
        if not rows and not n_marks:
            return ""
        return (
            f"Imported {len(rows)} row(s) of {results_jsonl.name}"
            + (f" and {n_marks} mark(s) of {marks_json.name}" if n_marks and marks_json else "")
            + f" into {self.path} (once: the record is the truth from now on, "
            f"{results_jsonl.name} an export of it)"
        )
