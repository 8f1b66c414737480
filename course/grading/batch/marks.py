"""Short answers: the marking file ``course grade`` writes, and the marks it merges back.

``OUT/short_answers.csv`` has one row per answered short-answer question and student:

``student, question, answer, points_possible, points, rubric, comment, answer_id``

The instructor fills ``points`` (blank: not marked yet) and optionally ``comment`` (shown to
the student) in the marking view (``course mark OUT``, :mod:`course.grading.batch.marking`) or
any spreadsheet, then runs ``course grade NAME SUBMISSIONS --out
OUT --short-answers FILE``. The file is checked as a whole first: an unknown student or
question, points that are not a number between 0 and ``points_possible``, a row given twice or
an answer changed since the file was written refuses the import, line by line, and changes
nothing. Accepted marks are kept in ``OUT/short_answer_marks.json`` (so a regrade keeps them,
as long as the answer is the same: ``answer_id`` is a digest of its text) and merged into
``grades.csv``, ``results.jsonl`` and the feedback. Text cells are written spreadsheet-safe
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
from course.grading.vocabulary import GradeStatus, QuestionKind

__all__ = [
    "MARKS_FILE",
    "SHORT_ANSWERS_FILE",
    "MarksError",
    "answer_id",
    "apply_marks",
    "load_marks",
    "parse_marks_csv",
    "parse_points",
    "read_marking_file",
    "save_marks",
    "short_questions",
    "unimported_edits",
    "unmarked_counts",
    "unmarked_warning",
    "validate_marks",
    "write_marking_file",
    "write_short_answers",
]

SHORT_ANSWERS_FILE = "short_answers.csv"
MARKS_FILE = "short_answer_marks.json"
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


def write_short_answers(rows: list[StudentResult], checks, path: Path, marks: dict) -> int:
    """Write the marking file of ``rows``; returns how many answers are still to mark."""
    shorts = short_questions(checks)
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(COLUMNS)
    to_mark = 0
    for row in sorted(rows, key=lambda r: r.student):
        for qid, q in shorts.items():
            result = row.questions.get(qid)
            if result is None or result.answer is None:
                continue  # not answered: nothing to mark
            aid = answer_id(result.answer)
            mark = marks.get(row.student, {}).get(qid)
            if mark is None or mark.get("answer_id") != aid:
                mark, to_mark = {}, to_mark + 1
            writer.writerow(
                [
                    csv_text(row.student),
                    csv_text(qid),
                    csv_text(result.answer),
                    _fmt(q.points),
                    _fmt(mark["points"]) if "points" in mark else "",
                    csv_text(q.rubric),
                    csv_text(mark.get("comment", "")),
                    aid,
                ]
            )
    path.write_text(buf.getvalue(), encoding="utf-8")
    return to_mark


def _unquote(text: str) -> str:
    """Undo :func:`csv_text`'s guard (a ``'`` before ``= + - @``) on a cell read back."""
    text = (text or "").strip()
    return text[1:] if text.startswith("'") and text[1:2] in ("=", "+", "-", "@") else text


def _read_rows(path: Path) -> list[tuple[int, dict]]:
    return _read_table(path)[1]


def _read_table(path: Path) -> tuple[list[str], list[tuple[int, dict]]]:
    try:
        raw = Path(path).read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise MarksError(f"cannot read {path}: {exc}") from None
    try:  # spreadsheets save with ',' ';' or a tab, depending on the locale
        dialect: type[csv.Dialect] | csv.Dialect = csv.Sniffer().sniff(
            raw.split("\n", 1)[0], delimiters=",;\t"
        )
    except csv.Error:
        dialect = csv.excel
    reader = csv.DictReader(io.StringIO(raw), dialect=dialect)
    header = [(h or "").strip() for h in reader.fieldnames or []]
    missing = [c for c in ("student", "question", "points") if c not in header]
    if missing:
        raise MarksError(
            f"{path}: no column {', '.join(missing)}; use the file `course grade` wrote "
            f"({SHORT_ANSWERS_FILE}: {', '.join(COLUMNS)})"
        )
    reader.fieldnames = header
    return header, [(n, r) for n, r in enumerate(reader, start=2)]


def read_marking_file(path: Path) -> tuple[list[str], list[dict]]:
    """The header and the rows of a marking file, each cell as written (a tool that fills the
    file in place, :mod:`course.grading.batch.marking`, writes them back unchanged)."""
    header, rows = _read_table(path)
    return header, [r for _, r in rows]


def write_marking_file(path: Path, header: list[str], rows: list[dict]) -> None:
    """Write ``rows`` (cells as :func:`read_marking_file` gave them) under ``header``; the file
    is replaced in one step, so a reader never sees half of it."""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=header, lineterminator="\n", extrasaction="ignore")
    writer.writeheader()
    writer.writerows(rows)
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(buf.getvalue(), encoding="utf-8")
    tmp.replace(path)


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


def parse_marks_csv(path: Path, checks) -> dict:
    """The marks of a filled marking file: {(student, question): {points, comment, answer_id,
    line}}. Rows with blank points are not marked yet and skipped. :class:`MarksError` lists
    unknown questions, bad or out-of-range points and repeated rows."""
    shorts = short_questions(checks)
    errors: list[str] = []
    out: dict[tuple[str, str], dict] = {}
    for line, r in _read_rows(path):
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
            "line": line,
        }
    _raise(path, errors)
    return out


def validate_marks(path: Path, entries: dict, rows: dict[str, StudentResult]) -> dict:
    """Check ``entries`` against the graded ``rows`` (student -> row): unknown students, answers
    not given or changed since the file was written. Returns the marks to keep."""
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
        if entry["answer_id"] and entry["answer_id"] != current:
            errors.append(
                f"line {line}: the answer of {sid} to {qid} changed since this file was written; "
                "mark the new answer (rerun `course grade` for a fresh file)"
            )
            continue
        marks.setdefault(sid, {})[qid] = {
            "points": entry["points"],
            "comment": entry["comment"],
            "answer_id": current,
        }
    _raise(path, errors)
    return marks


def _raise(path: Path, errors: list) -> None:
    if errors:
        more = f"\n  … and {len(errors) - _MAX_ERRORS} more" if len(errors) > _MAX_ERRORS else ""
        raise MarksError(
            f"{path}: {len(errors)} row(s) refused, nothing imported:\n  "
            + "\n  ".join(errors[:_MAX_ERRORS])
            + more
        )


def load_marks(out: Path) -> dict:
    path = Path(out) / MARKS_FILE
    if not path.is_file():
        return {}
    try:
        data = json.loads(path.read_text("utf-8"))
    except ValueError as exc:
        raise MarksError(f"{path} is damaged ({exc}); restore it from a backup") from None
    return data if isinstance(data, dict) else {}


def save_marks(out: Path, marks: dict) -> None:
    path = Path(out) / MARKS_FILE
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(marks, sort_keys=True, indent=1, ensure_ascii=False), "utf-8")
    tmp.replace(path)


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
