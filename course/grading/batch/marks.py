"""Short answers: the marking file ``course grade`` writes, and the marks it merges back.

``OUT/short_answers.csv`` has one row per answered short-answer question and student:

``student, question, answer, points_possible, points, rubric, comment, answer_id``

It is an export of the term's record (:mod:`course.grading.batch.record`), where the marks
live: the marking view (``course mark OUT``, :mod:`course.grading.batch.marking`) writes each
mark into the record and the file at once. A marker who prefers a spreadsheet fills ``points``
(blank: not marked yet) and optionally ``comment`` (shown to the student), saves the file as
comma-separated CSV and runs ``course grade NAME SUBMISSIONS --out OUT --short-answers FILE``.

The file is read with one fixed dialect, RFC 4180's (comma, ``"`` quoting, a ``"`` inside a
cell doubled), never guessed from its content: its cells are the students' text. Each row is
matched to its answer by the answer's ID (``answer_id``, a digest of the answer's text) and by
the answer's text itself; a row that does not match (an unknown student or question, points
that are not a number between 0 and ``points_possible``, a row given twice, an answer changed
since the file was written, a row that is not one) is refused with its line number, and every
other row is imported. Text cells are written spreadsheet-safe
(:func:`course.grading.batch.reports.csv_text`). Answers not marked yet count as 0 until they
are, and :func:`unmarked_warning` says so in the console summary and ``report.html``.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
from pathlib import Path

from course.grading.batch.reports import csv_text
from course.grading.batch.results import StudentResult
from course.grading.vocabulary import GradeStatus, QuestionKind, visible_text

__all__ = [
    "MARKS_FILE",
    "SHORT_ANSWERS_FILE",
    "MarksError",
    "answer_entries",
    "answer_id",
    "apply_marks",
    "export_short_answers",
    "parse_marks_csv",
    "parse_points",
    "read_marking_file",
    "refused_text",
    "short_questions",
    "unimported_edits",
    "unmarked_counts",
    "unmarked_warning",
    "validate_marks",
    "write_short_answers",
]

SHORT_ANSWERS_FILE = "short_answers.csv"
MARKS_FILE = "short_answer_marks.json"  # an older version's marks, imported once
COLUMNS = [
    "student",
    "question",
    "answer",
    "points_possible",
    "points",
    "rubric",
    "comment",
    "answer_id",
]
#: the columns a marking file must have (the others are the marker's reading)
_REQUIRED = ("student", "question", "points", "answer_id")
_MAX_ERRORS = 20


class MarksError(ValueError):
    """A marking file that cannot be imported (the message lists every bad line)."""


def answer_id(text: str) -> str:
    """A short digest of an answer's text: a mark applies only to the answer it was given for."""
    return hashlib.sha256(text.strip().encode("utf-8")).hexdigest()[:12]


def short_questions(checks) -> dict:
    """The short-answer questions of ``checks``, by id."""
    return {q.id: q for q in checks.questions.values() if q.kind == QuestionKind.SHORT_ANSWER}


def _fmt(x: float) -> str:
    return f"{round(float(x), 4):g}"


def answer_entries(rows: list[StudentResult], checks) -> list[dict]:
    """The short answers of ``rows`` to mark, in the marking file's order (by student, then
    question): dicts of student, question, answer_id, text, points_possible, rubric."""
    shorts = short_questions(checks)
    out = []
    for row in sorted(rows, key=lambda r: r.student):
        for qid, q in shorts.items():
            result = row.questions.get(qid)
            if result is None or result.answer is None:
                continue  # not answered: nothing to mark
            out.append(
                {
                    "student": row.student,
                    "question": qid,
                    "answer_id": answer_id(result.answer),
                    "text": result.answer,
                    "points_possible": float(q.points),
                    "rubric": q.rubric or "",
                }
            )
    return out


def write_short_answers(path: Path, answers: list[dict]) -> int:
    """Write the marking file (an export of the record: ``answers`` as
    :meth:`~course.grading.batch.record.Record.answers` gives them, each with its mark so
    far), replaced in one step; returns how many answers are still to mark."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")  # RFC 4180: comma, '"' doubled
    writer.writerow(COLUMNS)
    to_mark = 0
    for a in answers:
        marked = a.get("points") is not None
        to_mark += not marked
        writer.writerow(
            [
                csv_text(a["student"]),
                csv_text(a["question"]),
                csv_text(a["text"]),
                _fmt(a["points_possible"]),
                _fmt(a["points"]) if marked else "",
                csv_text(a["rubric"]),
                csv_text(a.get("comment") or "") if marked else "",
                a["answer_id"],
            ]
        )
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(buf.getvalue(), encoding="utf-8")
    tmp.replace(path)
    return to_mark


def export_short_answers(record, path: Path, just_read: bool = False) -> tuple[int | None, int]:
    """Rewrite the marking file from ``record`` (a
    :class:`~course.grading.batch.record.Record`): ``(answers still to mark, 0)``; or, when
    the file was changed since the record last wrote it and holds marks never imported (a
    spreadsheet's), leave it as it is: ``(None, rows with such marks)``. ``just_read``: the
    file was just imported, so nothing in it can be lost."""
    path = Path(path)
    if path.exists() and not just_read:
        sha = hashlib.sha256(path.read_bytes()).hexdigest()
        if sha != record.meta("short_answers_sha256"):
            edits = unimported_edits(path, record.marks())
            if edits:
                return None, edits
    to_mark = write_short_answers(path, record.answers())
    record.set_meta("short_answers_sha256", hashlib.sha256(path.read_bytes()).hexdigest())
    return to_mark, 0


def _unquote(text: str) -> str:
    """Undo :func:`csv_text`'s guard (a ``'`` before ``= + - @``) on a cell read back."""
    text = (text or "").strip()
    return text[1:] if text.startswith("'") and text[1:2] in ("=", "+", "-", "@") else text


def _read_rows(path: Path) -> list[tuple[int, dict]]:
    return _read_table(path)[1]


def _read_table(path: Path) -> tuple[list[str], list[tuple[int, dict]]]:
    """The header and the rows (with their line numbers) of a marking file, read with one
    fixed dialect, RFC 4180's (comma, ``"`` quoting, a ``"`` in a cell doubled): never guessed
    from the file, whose cells are the students' text."""
    try:
        raw = Path(path).read_bytes().decode("utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise MarksError(f"cannot read {path}: {exc}") from None
    reader = csv.reader(io.StringIO(raw, newline=""), dialect=csv.excel, strict=False)
    try:
        header = [(h or "").strip() for h in next(reader, [])]
    except csv.Error as exc:
        raise MarksError(f"{path}: line 1 is not CSV ({exc})") from None
    missing = [c for c in _REQUIRED if c not in header]
    if missing:
        raise MarksError(
            f"{path}: no column {', '.join(missing)}; use the file `course grade` wrote "
            f"({SHORT_ANSWERS_FILE}: {', '.join(COLUMNS)}), saved as comma-separated CSV "
            "(a spreadsheet's 'CSV UTF-8 (comma delimited)')"
        )
    rows: list[tuple[int, dict]] = []
    line = reader.line_num + 1
    while True:
        try:
            cells = next(reader)
        except StopIteration:
            break
        except csv.Error as exc:
            rows.append((line, {"__error__": str(exc)}))
            line = reader.line_num + 1
            continue
        cells += [""] * (len(header) - len(cells))
        row = dict(zip(header, cells))
        if len(cells) > len(header):
            row["__error__"] = f"{len(cells)} cells where the header has {len(header)}"
        rows.append((line, row))
        line = reader.line_num + 1
    return header, rows


def read_marking_file(path: Path) -> tuple[list[str], list[tuple[int, dict]]]:
    """The header and the rows of a marking file with their line numbers, each cell as written
    (a row that is not one holds ``__error__``)."""
    return _read_table(path)


def parse_points(text: str, top: float) -> float | None:
    """The points typed for an answer worth ``top`` points (``1.5`` or ``1,5``; blank: None, not
    marked); :class:`MarksError` for anything that is not a number between 0 and ``top``."""
    try:
        points = _points(text)
    except ValueError:
        raise MarksError(f"{text.strip()!r} is not a number of points") from None
    if points is not None and not (math.isfinite(points) and 0 <= points <= top):
        raise MarksError(f"{points:g} points: give between 0 and {top:g}")
    return points


def unmarked_counts(rows: list[StudentResult], checks) -> dict[str, tuple[int, int]]:
    """Per short-answer question: (answers not marked yet, answers given). An answer not
    given is no answer to mark (it scores 0 as *not answered*)."""
    counts = {}
    for qid in short_questions(checks):
        given = [
            r.questions[qid]
            for r in rows
            if qid in r.questions and r.questions[qid].answer is not None
        ]
        counts[qid] = (sum(res.status == GradeStatus.TO_MARK for res in given), len(given))
    return counts


def unmarked_warning(counts: dict[str, tuple[int, int]]) -> str:
    """The warning about answers not marked yet ('' when every answer is marked), e.g.
    ``3 short answer(s) NOT marked yet count as 0 (q3: 2 of 6, q7: 1 of 6)``.

    Examples
    --------
    >>> unmarked_warning({"q3": (2, 6), "q7": (0, 6)})
    '2 short answer(s) NOT marked yet count as 0 (q3: 2 of 6 answers)'
    >>> unmarked_warning({"q3": (0, 6)})
    ''
    """
    todo = {qid: c for qid, c in counts.items() if c[0]}
    if not todo:
        return ""
    per = ", ".join(f"{qid}: {n} of {given}" for qid, (n, given) in todo.items())
    return (
        f"{sum(n for n, _ in todo.values())} short answer(s) NOT marked yet count as 0 "
        f"({per} answers)"
    )


def _points(text: str) -> float | None:
    text = (text or "").strip()
    if not text:
        return None
    if "," in text and "." not in text:  # a decimal comma (0,5)
        text = text.replace(",", ".")
    return float(text)


def parse_marks_csv(path: Path, checks) -> tuple[dict, list[str]]:
    """The marks of a filled marking file and the rows refused:
    ``({(student, question): {points, comment, answer_id, answer, line}}, ["line 7: ..."])``.

    Rows with blank points are not marked yet and skipped. A row is refused (its line
    number and why) for an unknown question, points that are not a number between 0 and the
    question's points, a comment without points, a row given twice, or a row that is not one
    (more cells than the header); every other row is kept. :class:`MarksError` only for a
    file that cannot be read as a marking file at all."""
    shorts = short_questions(checks)
    errors: list[str] = []
    out: dict[tuple[str, str], dict] = {}
    for line, r in _read_rows(path):
        if "__error__" in r:
            errors.append(f"line {line}: not a row of the marking file ({r['__error__']})")
            continue
        sid, qid = _unquote(r.get("student", "")), _unquote(r.get("question", ""))
        if not sid and not qid and not any((v or "").strip() for v in r.values() if v):
            continue  # an empty line
        if qid not in shorts:
            what = (
                "is not a short-answer question" if qid in checks.questions else "is not a question"
            )
            errors.append(f"line {line}: {qid!r} {what} of {checks.name}")
            continue
        try:
            points = _points(r.get("points", ""))
        except ValueError:
            errors.append(f"line {line}: points {r.get('points')!r} is not a number")
            continue
        if points is None:
            if _unquote(r.get("comment") or ""):
                errors.append(
                    f"line {line}: a comment but no points for {sid} {qid}: give the points "
                    "(0 is fine) or clear the comment"
                )
            continue
        top = shorts[qid].points
        if not (math.isfinite(points) and 0 <= points <= top):
            errors.append(
                f"line {line}: {points:g} points for {sid} {qid}: give between 0 and {top:g}"
            )
            continue
        if (sid, qid) in out:
            errors.append(
                f"line {line}: {sid} {qid} is marked twice (also line {out[(sid, qid)]['line']})"
            )
            continue
        out[(sid, qid)] = {
            "points": points,
            "comment": _unquote(r.get("comment") or ""),
            "answer_id": (r.get("answer_id") or "").strip(),
            "answer": r.get("answer"),
            "line": line,
        }
    return out, errors


def _same_text(cell: str, answer: str) -> bool:
    """Whether a marking file's answer cell is the export of ``answer`` (compared by digest,
    line ends as a spreadsheet may have changed them)."""

    def digest(text: str) -> str:
        return answer_id(text.replace("\r\n", "\n").replace("\r", "\n"))

    return digest(cell or "") == digest(csv_text(answer))


def validate_marks(entries: dict, rows: dict[str, StudentResult]) -> tuple[dict, list[str]]:
    """The marks of ``entries`` that belong to an answer of the graded ``rows`` (student ->
    row), and the rows refused. A mark is matched to its answer by the answer's ID *and* the
    answer's text: the row's ``answer_id`` must be the digest of the student's answer as
    graded, and its ``answer`` cell (when the file has the column) that answer's text, so a
    row cannot carry a mark to another student's or another version's answer."""
    errors: list[str] = []
    marks: dict[str, dict] = {}
    for (sid, qid), entry in sorted(entries.items(), key=lambda kv: kv[1]["line"]):
        line = entry["line"]
        row = rows.get(sid)
        if row is None:
            errors.append(f"line {line}: unknown student {sid!r} (no graded submission)")
            continue
        result = row.questions.get(qid)
        answer = result.answer if result is not None else None
        if answer is None:
            errors.append(f"line {line}: {sid} gave no answer to {qid}: nothing to mark")
            continue
        current = answer_id(answer)
        if not entry["answer_id"]:
            errors.append(
                f"line {line}: no answer_id for {sid} {qid}: mark the rows of the file "
                "`course grade` wrote (their answer_id ties each mark to its answer)"
            )
            continue
        if entry["answer_id"] != current:
            errors.append(
                f"line {line}: the answer of {sid} to {qid} changed since this file was written; "
                "mark the new answer (rerun `course grade` for a fresh file)"
            )
            continue
        if entry.get("answer") is not None and not _same_text(entry["answer"], answer):
            errors.append(
                f"line {line}: the answer text of {sid} {qid} is not the answer its answer_id "
                "names; mark the rows of the file `course grade` wrote"
            )
            continue
        marks.setdefault(sid, {})[qid] = {
            "points": entry["points"],
            "comment": entry["comment"],
            "answer_id": current,
        }
    return marks, errors


def refused_text(errors: list[str]) -> str:
    """The console's lines about rows of a marking file that were refused ('' for none)."""
    if not errors:
        return ""
    more = f"\n  … and {len(errors) - _MAX_ERRORS} more" if len(errors) > _MAX_ERRORS else ""
    return (
        f"{len(errors)} row(s) of the marking file refused (every other row was imported):\n  "
        + "\n  ".join(visible_text(e) for e in errors[:_MAX_ERRORS])
        + more
    )


def apply_marks(row: StudentResult, checks, marks: dict) -> bool:
    """Put the instructor's marks into ``row`` (in place); True when the row changed."""
    before = json.dumps(row.to_json(), sort_keys=True, default=str)
    mine = marks.get(row.student, {})
    for qid in short_questions(checks):
        result = row.questions.get(qid)
        if result is None or result.answer is None:
            continue
        mark = mine.get(qid)
        if mark is not None and mark.get("answer_id") == answer_id(result.answer):
            result.points = round(float(mark["points"]), 4)
            result.status = GradeStatus.MARKED
            result.message = mark.get("comment") or "marked by your instructor"
        else:
            result.points = 0.0
            result.status = GradeStatus.TO_MARK
            result.message = "your instructor marks this answer" + (
                " again: it changed since it was marked" if mark is not None else ""
            )
    row.add_total()
    return json.dumps(row.to_json(), sort_keys=True, default=str) != before


def unimported_edits(path: Path, marks: dict) -> int:
    """How many rows of an existing marking file hold points or comments that were never
    imported (a rewrite would lose them)."""
    try:
        rows = _read_rows(path)
    except MarksError:
        return 0
    n = 0
    for _, r in rows:
        if "__error__" in r:
            continue  # not a row: nothing a rewrite could lose
        sid, qid = _unquote(r.get("student", "")), _unquote(r.get("question", ""))
        points, comment = (r.get("points") or "").strip(), _unquote(r.get("comment") or "")
        if not points and not comment:
            continue
        mark = marks.get(sid, {}).get(qid)
        try:
            same = mark is not None and _points(points) == mark["points"]
        except ValueError:
            same = False
        if not same or comment != mark.get("comment", ""):
            n += 1
    return n
