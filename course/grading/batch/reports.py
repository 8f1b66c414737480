"""What ``course grade`` writes and prints: feedback, the grades table, the results log and the
console summary.

``OUT/feedback/<student>.md``
    points, status, message and hint per question (no hidden inputs, no test code);
``OUT/grades.csv``
    student, one column per question, total, max, status;
``OUT/results.jsonl``
    one JSON row per student, appended as students finish (:func:`read_results` reads it back,
    so a rerun resumes).
"""

from __future__ import annotations

import csv
import io
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

from course.grading.batch.results import StudentResult
from course.grading.compare import chosen_hint
from course.grading.vocabulary import visible_text

__all__ = [
    "Summary",
    "append_result",
    "csv_text",
    "feedback_markdown",
    "late_cells",
    "late_sentence",
    "read_results",
    "slowest",
    "write_csv",
]


def _fmt_points(x: float) -> str:
    return f"{round(float(x), 2):g}"


_MARKDOWN = re.compile(r"([\\`*_{}\[\]<>#!|~])")


def md_text(text) -> str:
    """Student text (messages the child produced, file names) as inert markdown on one line:
    control characters shown as escapes, every markdown or HTML sign backslash-escaped, so it
    can forge no heading, no ``**Total:`` line, no link and no ``<!--`` comment."""
    return _MARKDOWN.sub(r"\\\1", visible_text(text))


def late_sentence(row: StudentResult) -> str:
    """One sentence on the row's late work ("" when on time or nothing is known)."""
    late = row.late
    if not late or late.get("days") == 0:
        return ""
    days = late.get("days")
    percent = float(late.get("percent") or 0)
    if days is None:
        when = "The learning-management system marked this submission late, without its time" + (
            " (charged as 1 day late)" if percent else ""
        )
    else:
        when = (
            f"Handed in {late.get('submitted_at')}, {_days(days)} after the due date "
            f"{late.get('due')}"
        )
    if not percent:
        return f"{when}; no late deduction."
    return (
        f"{when}; late deduction {_fmt_points(percent)} % of the points possible "
        f"({late.get('policy')}): -{_fmt_points(row.penalty)} points, "
        f"{_fmt_points(row.total)} instead of {_fmt_points(row.points)}."
    )


def _days(days: int | None) -> str:
    return "late by an unknown time" if days is None else f"{days} day{'s' if days != 1 else ''}"


def late_cells(row: StudentResult) -> list[str]:
    """grades.csv's ``late`` (days late, 0 on time, ``unknown``: marked late without a time;
    empty: nothing known) and ``penalty`` (the points deducted)."""
    if row.late is None:
        return ["", ""]
    days = row.late.get("days")
    return ["unknown" if days is None else str(days), _fmt_points(row.penalty)]


def feedback_markdown(row: StudentResult, checks) -> str:
    """The student's feedback: per question points, status, message and hint.

    It never shows an expected value (a case's ``detail`` stays in results.jsonl, for the
    instructor) and only the first stage of staged hints."""
    lines = [f"# {checks.title}: feedback for {md_text(row.student)}", ""]
    if row.status == "not graded":
        lines += [
            "**Not graded yet:** the grader failed on this submission (not your fault); your "
            "instructor grades it again.",
            "",
        ]
    lines.append(
        f"**Total: {_fmt_points(row.total)} / {_fmt_points(row.max)}**"
        + ("" if row.status == "ok" else f"  (status: {row.status})")
    )
    late = late_sentence(row)
    if late:
        lines += ["", f"**Late:** {md_text(late)}"]
    order = [q for q in checks.questions if q in row.questions]
    questions = {q: row.questions[q] for q in order}
    questions.update(row.questions)  # questions no longer in the checks: after, as they came
    lines += ["", "| question | points | status |", "|---|---|---|"]
    for qid, r in questions.items():
        lines.append(f"| {qid} | {_fmt_points(r.points)} / {_fmt_points(r.max)} | {r.status} |")
    for qid, r in questions.items():
        q = checks.questions.get(qid)
        lines += ["", f"## {qid}: {_fmt_points(r.points)} / {_fmt_points(r.max)} ({r.status})"]
        if r.message:
            lines.append("")
            lines.append(md_text(r.message))
        if len(r.cases) > 1 and r.status != "not answered":
            lines.append("")
            for case in r.cases:
                lines.append(
                    f"- {'PASS' if case.ok else 'FAIL'} {case.label}"
                    + (f": {md_text(case.message)}" if case.message and not case.ok else "")
                )
        if q is not None and not r.full_marks and r.status != "to mark":
            hint = _feedback_hint(q, r)
            if hint:
                lines += ["", f"Hint: {hint}"]
    if row.notes:
        lines += ["", "## Notes", ""] + [f"- {md_text(n)}" for n in row.notes]
    lines.append("")
    lines.append(
        f"<sub>{row.assignment} · checks {row.checks_sha256[:12]} · course {row.version}</sub>"
    )
    return "\n".join(lines) + "\n"


def _feedback_hint(q, r) -> str:
    """The hint of a question's feedback: the one a diagnosed mistake chooses (its own, or
    none for an answer computed in float32), else the first stage only -- the later ones
    (the formula) stay in the self-check."""
    chosen = chosen_hint([c for c in r.cases if not c.ok], getattr(q, "mistake_hints", {}))
    if chosen is not None:
        return chosen
    return q.hints[0] if q.hints else ""


_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


def csv_text(value) -> str:
    """A text cell that a spreadsheet will not run as a formula: a leading ``= + - @`` (or tab,
    carriage return) gets a ``'`` in front (OWASP's advice against CSV injection). A student
    ID is a file name, chosen by the student."""
    text = visible_text(value)
    return "'" + text if text.startswith(_FORMULA_START) else text


def write_csv(rows: list[StudentResult], question_ids: list[str], path: Path) -> None:
    """``grades.csv``; the ``late`` and ``penalty`` columns (:func:`late_cells`) appear when a
    row has a late record (a due date was given, or the LMS marked a file late)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    with_late = any(r.late is not None for r in rows)
    writer.writerow(
        ["student", *(csv_text(q) for q in question_ids), "total", "max", "status"]
        + (["late", "penalty"] if with_late else [])
    )
    for row in sorted(rows, key=lambda r: r.student):
        graded = row.status != "not graded"  # a fault of the grader: no points at all
        writer.writerow(
            [
                csv_text(row.student),
                *(
                    _fmt_points(row.questions[q].points if q in row.questions else 0)
                    if graded
                    else ""
                    for q in question_ids
                ),
                _fmt_points(row.total) if graded else "",
                _fmt_points(row.max),
                csv_text(row.status),
            ]
            + (late_cells(row) if with_late else [])
        )
    path.write_text(buf.getvalue(), encoding="utf-8")


@dataclass
class Summary:
    rows: list[StudentResult]
    question_ids: list
    max_points: dict
    graded: int
    resumed: int
    seconds: float
    out: Path
    flags: list = field(default_factory=list)  # doubts about who submitted what (identity)
    missing: list | None = None  # roster IDs without a submission (None: no roster)
    unknown: list = field(default_factory=list)  # submissions whose ID is not on the roster
    marking: str = ""  # what happened to the short answers (course.grading.batch.marks)
    regraded: dict = field(default_factory=dict)  # why graded again -> how many ("file changed")
    stale: list = field(default_factory=list)  # out of date, not regraded: --student chose others
    unselected: int = 0  # submissions never graded and not chosen by --student
    late_notes: list = field(default_factory=list)  # late files without a time, disagreements
    cleanup_failed: list = field(default_factory=list)  # left behind: "<path> (<reason>)"
    not_graded: list = field(default_factory=list)  # the grader failed on them, after retries
    regrade_command: str = ""  # the command that grades them again
    imported: str = ""  # an older folder imported into the record (once)

    def class_text(self) -> str:
        """The students not graded, the identity flags, deleted answer cells, the roster's
        missing and unknown submissions and the short answers to mark."""
        lines = [self.imported] if self.imported else []
        if self.not_graded:
            lines.append(
                f"NOT GRADED: {len(self.not_graded)} submission(s) the grader failed on, "
                f"after retries (a fault of the grader, not of the student; blank in every LMS "
                f"file): {', '.join(visible_text(s) for s in self.not_graded[:20])}"
                f"{' …' if len(self.not_graded) > 20 else ''}; grade them again with "
                f"`{self.regrade_command}` (a plain run grades them again)"
            )
        deleted = [
            f"{r.student} ("
            + ", ".join(
                f"{qid}: {'graded from an added cell' if how == 'adopted' else 'not answered'}"
                for qid, how in sorted(r.deleted_answers.items())
            )
            + ")"
            for r in self.rows
            if r.deleted_answers
        ]
        if deleted:
            lines.append(f"Answer cells deleted in {len(deleted)} submission(s):")
            lines += [f"  - {text}" for text in deleted]
        if self.flags:
            lines.append(f"Check these {len(self.flags)} submission name(s):")
            lines += [f"  - {flag}" for flag in self.flags]
        if self.missing is not None:
            lines.append(
                f"Roster: {len(self.missing)} missing"
                + (
                    f" ({', '.join(self.missing[:20])}{' …' if len(self.missing) > 20 else ''})"
                    if self.missing
                    else ""
                )
                + f", {len(self.unknown)} not on the roster"
                + (f" ({', '.join(self.unknown)})" if self.unknown else "")
                + "; LMS files: canvas.csv, moodle.csv"
            )
        records = [r.late for r in self.rows if r.late]
        late = [r for r in self.rows if r.late and r.late.get("days") != 0]
        if records or self.late_notes:
            dues = sorted({str(x["due"]) for x in records if x.get("due")})
            rule = (
                f"due {', '.join(dues) or 'not given'}; {records[0].get('policy')}"
                if records
                else ""
            )
            lines.append(
                f"Late: {len(late)} submission(s)"
                + (": " if late else "")
                + ", ".join(
                    f"{r.student} ({_days((r.late or {}).get('days'))}, "
                    + (f"-{_fmt_points(r.penalty)} points)" if r.penalty else "no deduction)")
                    for r in sorted(late, key=lambda r: r.student)
                )
                + (f"; {rule}" if rule else "")
            )
            lines += [f"  - {note}" for note in self.late_notes]
        if self.marking:
            lines.append(self.marking)
        if self.cleanup_failed:
            lines.append(
                f"WARNING cleanup_failed: {len(self.cleanup_failed)} path(s) the grading "
                "processes left could not be removed (check them, `chattr -i` if immutable, "
                "then delete them):"
            )
            lines += [f"  - {visible_text(path)}" for path in self.cleanup_failed[:20]]
        return "\n".join(lines)

    def headline(self) -> str:
        """How many were graded, why those graded before were graded again, how many were
        kept, e.g. ``Graded 3 submission(s) (3 regraded: file changed), 29 already graded
        (resumed)``."""
        why = ", ".join(
            f"{n} regraded: {reason}"
            for reason, n in sorted(self.regraded.items(), key=lambda kv: (-kv[1], kv[0]))
        )
        text = (
            f"Graded {self.graded} submission(s)"
            + (f" ({why})" if why else "")
            + f", {self.resumed} already graded (resumed)"
        )
        if self.stale:
            text += (
                f"; {len(self.stale)} out of date but not chosen by --student "
                f"({', '.join(self.stale[:20])}{' …' if len(self.stale) > 20 else ''})"
            )
        if self.unselected:
            text += f"; {self.unselected} never graded and not chosen by --student"
        return (
            text + f", in {self.seconds:.1f} s; results in {self.out} (the class report: "
            f"{self.out / 'report.html'})"
        )

    def text(self) -> str:
        n = len(self.rows)
        lines = [self.headline()]
        if not n:
            return "\n".join([lines[0], self.class_text()]).rstrip()
        lines.append(f"{'question':<10}{'max':>6}{'mean':>8}{'full marks':>12}")
        for qid in self.question_ids:
            pts = [r.questions[qid].points for r in self.rows if qid in r.questions]
            full = sum(1 for r in self.rows if qid in r.questions and r.questions[qid].full_marks)
            mean = sum(pts) / len(pts) if pts else 0.0
            lines.append(
                f"{qid:<10}{_fmt_points(self.max_points[qid]):>6}{mean:>8.2f}{100 * full / n:>11.0f}%"
            )
        total = sum(r.total for r in self.rows) / n
        lines.append(f"{'total':<10}{_fmt_points(sum(self.max_points.values())):>6}{total:>8.2f}")
        statuses: dict[str, int] = {}
        for r in self.rows:
            statuses[r.status] = statuses.get(r.status, 0) + 1
        lines.append(
            "status: "
            + ", ".join(
                f"{k} ({v})" for k, v in sorted(statuses.items(), key=lambda kv: (-kv[1], kv[0]))
            )
        )
        slow = slowest(self.rows)
        if slow:
            times = sorted(r.wall_seconds for r in self.rows if r.wall_seconds is not None)
            median = times[len(times) // 2]
            lines.append(
                "slowest: "
                + ", ".join(f"{r.student} ({float(r.wall_seconds or 0):.1f} s)" for r in slow)
                + f"; median {median:.2f} s per student"
            )
        extra = self.class_text()
        return "\n".join(lines + ([extra] if extra else []))


def slowest(rows: list[StudentResult], n: int = 3) -> list[StudentResult]:
    """The ``n`` rows with the longest ``wall_seconds`` (the students worth a look)."""
    timed = [r for r in rows if isinstance(r.wall_seconds, (int, float))]
    return sorted(timed, key=lambda r: (-float(r.wall_seconds or 0), r.student))[:n]


def read_results(path: Path) -> dict[str, StudentResult]:
    """The rows of ``results.jsonl`` by student (the last row of a student wins; a row that
    is not one, e.g. a line cut short by an interrupted run, is skipped: that student is
    graded again)."""
    rows: dict[str, StudentResult] = {}
    if not path.is_file():
        return rows
    with open(path, encoding="utf-8") as f:
        for line in f:
            try:
                row = StudentResult.from_json(json.loads(line))
            except (ValueError, KeyError, TypeError, AttributeError):
                continue
            rows[row.student] = row
    return rows


def append_result(row: StudentResult, path: Path) -> None:
    """Append one row to ``results.jsonl`` (and flush, so an interrupted run keeps it)."""
    with open(path, "a", encoding="utf-8") as f:
        f.write(json.dumps(row.to_json(), sort_keys=True, ensure_ascii=False) + "\n")
        f.flush()
