"""``report.html``: the picture of a graded class, written beside ``grades.csv`` by each run.

One self-contained page (figures as inline SVG in the course's figure style, no script, no
style sheet or font from outside), readable without the console:

- the pass rate per question: full marks, and the public and hidden cases apart;
- the distribution of the totals;
- per question, how often each named mistake (a :class:`~course.grading.authoring.checks.Mistake`
  of ``checks.py``) and each kind of wrong answer the comparison diagnosed (a constant factor,
  the sign, the shape, off by one, ...) occurred;
- the timeouts, forbidden calls and other abnormal ends, with the students;
- the late submissions and their deductions (when a due date is known or the LMS marked a
  file late);
- the slowest students;
- the item analysis per question (difficulty, discrimination, the share of each diagnosed
  kind; questions that do not discriminate flagged, :mod:`course.grading.batch.itemanalysis`);
- similarity hints: students whose answer code is the same after normalising names, literals
  and layout (:mod:`course.grading.batch.similarity`), for the instructor to look at.

Counts are of students: a student whose three hidden cases show the same factor counts once.

Each table is also written beside ``report.html`` as ``report-<table>.csv`` (:data:`TABLES`):
RFC 4180 CSV (comma, double quotes, CRLF rows, UTF-8), the cells as the page shows them and
student text kept as it is (data, to read into a spreadsheet, not to open as a formula sheet).
"""

from __future__ import annotations

import csv
import html
import io
from collections import Counter
from pathlib import Path

from course.grading.batch.itemanalysis import FLAG_BELOW, MIN_STUDENTS, item_analysis
from course.grading.batch.marks import unmarked_counts, unmarked_warning
from course.grading.batch.results import StudentResult
from course.grading.batch.similarity import similar_groups
from course.grading.vocabulary import GradeStatus, MistakeKind, visible_text

__all__ = ["TABLES", "diagnosis", "report_html", "report_tables", "write_report"]

REPORT_FILE = "report.html"
#: The report's tables, each also written as ``report-<name>.csv`` when the page has it.
TABLES = ("no_grade", "unmarked", "questions", "items", "kinds", "wrong", "abnormal", "late", "slowest",
          "similar")  # fmt: skip

_ABNORMAL = (
    GradeStatus.TIMEOUT,
    GradeStatus.FORBIDDEN,
    GradeStatus.CRASH,
    GradeStatus.MEMORY,
    GradeStatus.ERROR,
    GradeStatus.GRADER_ERROR,
)


def diagnosis(case) -> tuple[str, str] | None:
    """``("named", mistake)`` or ``("kind", kind of wrong)`` for a failed case, from the
    diagnosis the comparison recorded with it (``case.kind``, ``case.mistake``), or None when
    it diagnosed nothing (a timeout, a case not run, a row of a version that recorded none).
    Never from the message's words: rewording a message moves no count, and a student's text
    in a message ("factor") is not a diagnosis.

    Examples
    --------
    >>> from course.grading.batch.results import CaseResult
    >>> diagnosis(CaseResult("c", False, "T: too large by a factor ≈ 2.0", kind="a constant factor"))
    ('kind', 'a constant factor')
    >>> diagnosis(CaseResult("c", False, "z: looks one-sided", kind="named mistake",
    ...                      mistake="looks one-sided"))
    ('named', 'looks one-sided')
    """
    if case.ok or not case.kind:
        return None
    if case.kind == MistakeKind.NAMED and case.mistake:
        return ("named", str(case.mistake))
    return ("kind", str(case.kind))


def _rate(passed: int, run: int) -> float | None:
    return passed / run if run else None


class _Class:
    """The figures' and tables' numbers, from the rows."""

    def __init__(self, rows: list[StudentResult], checks, question_ids: list[str]):
        self.rows = sorted(rows, key=lambda r: r.student)
        self.qids = question_ids
        self.checks = checks
        self.full: dict[str, float | None] = {}
        self.public: dict[str, float | None] = {}
        self.hidden: dict[str, float | None] = {}
        self.named: dict[str, Counter] = {}
        self.kinds: dict[str, Counter] = {}
        self.abnormal: dict[str, dict[str, list[str]]] = {}
        for qid in question_ids:
            answered = [r for r in self.rows if qid in r.questions]
            full = sum(r.questions[qid].full_marks for r in answered)
            self.full[qid] = _rate(full, len(answered))
            counts = {"public": [0, 0], "hidden": [0, 0]}
            named: Counter[str] = Counter()
            kinds: Counter[str] = Counter()
            abnormal: dict[str, list[str]] = {}
            for r in answered:
                res = r.questions[qid]
                if res.status in _ABNORMAL:
                    abnormal.setdefault(res.status, []).append(r.student)
                seen = set()
                for case in res.cases:
                    side = "hidden" if case.label.startswith("hidden case") else "public"
                    if res.status not in (GradeStatus.NOT_ANSWERED, GradeStatus.TO_MARK):
                        counts[side][0] += bool(case.ok)
                        counts[side][1] += 1
                    found = diagnosis(case)
                    if found is not None:
                        seen.add(found)
                for how, what in seen:
                    (named if how == "named" else kinds)[what] += 1
            self.public[qid] = _rate(*counts["public"])
            self.hidden[qid] = _rate(*counts["hidden"])
            self.named[qid], self.kinds[qid], self.abnormal[qid] = named, kinds, abnormal

    @property
    def totals(self) -> list[float]:
        return [float(r.total) for r in self.rows]

    @property
    def max_points(self) -> float:
        return max((float(r.max) for r in self.rows), default=0.0)


# -- figures: inline SVG in the course's figure style ------------------------------------------
# Drawn by hand rather than by matplotlib: importing and drawing with matplotlib costs about a
# second of CPU per run, more than the grading-speed budget allows; the figures keep the
# style's colours (:func:`course.plotting.style.pair`, ``SAMPLE``, ``THRESHOLD``), its legend
# outside the data, its dashed black threshold line and axis labels with units.
_W, _H = 720, 320
_LEFT, _RIGHT, _TOP, _BOTTOM = 64, 150, 14, 90
_FONT = 'font-family="system-ui, sans-serif" font-size="12"'


def _num(x: float) -> str:
    return f"{x:.1f}".rstrip("0").rstrip(".")


def _svg(alt: str, body: list[str]) -> str:
    return (
        f'<svg role="img" viewBox="0 0 {_W} {_H}" '
        f'width="{_W}" height="{_H}" {_FONT}><title>{html.escape(alt)}</title>'
        + "".join(body)
        + "</svg>"
    )


def _axes(ticks: list[tuple[float, str]], y_of, xlabel: str, ylabel: str) -> list[str]:
    """Frame, horizontal grid lines with their labels, and the axis labels."""
    x0, x1, y0 = _LEFT, _W - _RIGHT, _H - _BOTTOM
    out = []
    for value, label in ticks:
        y = y_of(value)
        out.append(f'<line x1="{x0}" x2="{x1}" y1="{_num(y)}" y2="{_num(y)}" stroke="#e5e5e5"/>')
        out.append(
            f'<text x="{x0 - 6}" y="{_num(y + 4)}" text-anchor="end">{html.escape(label)}</text>'
        )
    out.append(f'<line x1="{x0}" x2="{x0}" y1="{_TOP}" y2="{y0}" stroke="#000"/>')
    out.append(f'<line x1="{x0}" x2="{x1}" y1="{y0}" y2="{y0}" stroke="#000"/>')
    out.append(
        f'<text x="{(x0 + x1) / 2}" y="{_H - 6}" text-anchor="middle">{html.escape(xlabel)}</text>'
    )
    mid = (_TOP + y0) / 2
    out.append(
        f'<text x="14" y="{mid}" text-anchor="middle" transform="rotate(-90 14 {mid})">'
        f"{html.escape(ylabel)}</text>"
    )
    return out


def _legend(entries: list[tuple[str, str]]) -> list[str]:
    """The legend outside the data, right of the axes: (label, SVG of its 14 px key)."""
    out = []
    for k, (label, key) in enumerate(entries):
        x, y = _W - _RIGHT + 14, _TOP + 8 + 20 * k
        out.append(f'<g transform="translate({x} {y})">{key}</g>')
        out.append(f'<text x="{x + 22}" y="{y + 11}">{html.escape(label)}</text>')
    return out


def _pass_rate_svg(data: _Class) -> str:
    from course.plotting.style import pair

    x0, x1, y0 = _LEFT, _W - _RIGHT, _H - _BOTTOM
    n_q = max(len(data.qids), 1)
    slot = (x1 - x0) / n_q
    width = slot * 0.26

    def y_of(percent: float) -> float:
        return y0 - (y0 - _TOP) * percent / 100

    body = _axes(
        [(v, str(v)) for v in range(0, 101, 20)],
        y_of,
        "question",
        "students or cases passed [%]",
    )
    series = (
        ("full marks", data.full, pair(0).dark),
        ("public cases", data.public, pair(2).dark),
        ("hidden cases", data.hidden, pair(1).dark),
    )
    rotate = len(data.qids) > 6 or max((len(q) for q in data.qids), default=0) > 4
    for i, qid in enumerate(data.qids):
        centre = x0 + slot * (i + 0.5)
        for k, (label, rates, colour) in enumerate(series):
            rate = rates[qid]
            if rate is None:  # no case of this kind: no bar (the table shows —), not a zero
                continue
            top = y_of(100 * rate)
            body.append(
                f'<rect x="{_num(centre + (k - 1.5) * width)}" y="{_num(top)}" '
                f'width="{_num(width)}" height="{_num(y0 - top)}" fill="{colour}">'
                f"<title>{html.escape(qid)}, {label}: {100 * rate:.0f} %</title></rect>"
            )
        label = html.escape(qid)
        if rotate:
            body.append(
                f'<text x="{_num(centre)}" y="{y0 + 14}" text-anchor="end" '
                f'transform="rotate(-35 {_num(centre)} {y0 + 14})">{label}</text>'
            )
        else:
            body.append(
                f'<text x="{_num(centre)}" y="{y0 + 16}" text-anchor="middle">{label}</text>'
            )
    legend = [(label, f'<rect width="14" height="14" fill="{c}"/>') for label, _, c in series]
    return _svg(
        "pass rate per question: full marks, public and hidden cases", body + _legend(legend)
    )


def _nice_step(rough: float) -> float:
    """The smallest of 1, 2, 5 times a power of ten at least ``rough`` (axis tick spacing)."""
    import math

    power = 10.0 ** math.floor(math.log10(rough)) if rough > 0 else 1.0
    return next(m * power for m in (1, 2, 5, 10) if m * power >= rough)


def _totals_svg(data: _Class) -> str:
    from course.plotting.style import SAMPLE, THRESHOLD

    x0, x1, y0 = _LEFT, _W - _RIGHT, _H - _BOTTOM
    top = data.max_points or 1.0
    n_bins = max(5, min(20, int(top) + 1))
    counts = [0] * n_bins
    for total in data.totals:
        counts[min(n_bins - 1, max(0, int(n_bins * total / top)))] += 1
    peak = max(max(counts), 1)
    step = max(1, -(-peak // 5))  # at most about five integer ticks
    y_max = step * -(-peak // step)

    def y_of(count: float) -> float:
        return y0 - (y0 - _TOP) * count / y_max

    def x_of(points: float) -> float:
        return x0 + (x1 - x0 - 10) * points / top

    body = _axes(
        [(v, str(v)) for v in range(0, y_max + 1, step)], y_of, "total [points]", "students"
    )
    for b, count in enumerate(counts):
        lo, hi = top * b / n_bins, top * (b + 1) / n_bins
        if count:
            body.append(
                f'<rect x="{_num(x_of(lo))}" y="{_num(y_of(count))}" '
                f'width="{_num(x_of(hi) - x_of(lo))}" height="{_num(y0 - y_of(count))}" '
                f'fill="{SAMPLE.light}" stroke="{SAMPLE.dark}" stroke-width="0.5">'
                f"<title>{_num(lo)} to {_num(hi)} points: {count} student(s)</title></rect>"
            )
    tick = _nice_step(top / 4)
    steps = [tick * k for k in range(int(top // tick) + 1) if top - tick * k > 0.3 * tick]
    for value in [*steps, top]:  # the maximum labelled, no tick crowding it
        x = _num(x_of(value))
        body.append(f'<line x1="{x}" x2="{x}" y1="{y0}" y2="{y0 + 4}" stroke="#000"/>')
        body.append(f'<text x="{x}" y="{y0 + 17}" text-anchor="middle">{value:g}</text>')
    xm = _num(x_of(top))
    dash = 'stroke-dasharray="5 3"'
    body.append(f'<line x1="{xm}" x2="{xm}" y1="{_TOP}" y2="{y0}" stroke="{THRESHOLD}" {dash}/>')
    legend = [
        (
            "students",
            f'<rect width="14" height="14" fill="{SAMPLE.light}" stroke="{SAMPLE.dark}"/>',
        ),
        ("maximum", f'<line x1="0" x2="14" y1="7" y2="7" stroke="{THRESHOLD}" {dash}/>'),
    ]
    return _svg("distribution of the totals", body + _legend(legend))


def _pct(rate: float | None) -> str:
    return "—" if rate is None else f"{100 * rate:.0f} %"


def _table(head: list[str], rows: list[list], name: str = "", into: dict | None = None) -> str:
    """An HTML table (every cell escaped); with ``into``, also kept there as ``name``'s CSV."""
    if into is not None:
        into[name] = (list(head), [[str(c) for c in row] for row in rows])
    cells = "".join(f"<th>{html.escape(h)}</th>" for h in head)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>" for row in rows
    )
    return f"<table><thead><tr>{cells}</tr></thead><tbody>{body}</tbody></table>"


_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 60rem; margin: 1.5rem auto;
       padding: 0 1rem; color: #1a1a1a; line-height: 1.45; }
table { border-collapse: collapse; margin: 0.5rem 0 1.2rem; }
th, td { border-bottom: 1px solid #ccc; padding: 0.2rem 0.7rem; text-align: left; }
figure { margin: 0.5rem 0 1rem; }
svg { max-width: 100%; height: auto; display: block; }
.note { color: #555; }
.warning { border-left: 4px solid #b3261e; background: #fdf0ee; padding: 0.3rem 0.9rem;
           margin: 0.8rem 0; }
"""


def report_html(rows: list[StudentResult], checks, question_ids: list[str]) -> str:
    """The class report of ``rows`` as one self-contained HTML page. Rows that are no grade
    (not graded, refused, quarantined: blank in the LMS files) are listed with their reason
    and left out of the numbers."""
    return _report(rows, checks, question_ids)[0]


def report_tables(
    rows: list[StudentResult], checks, question_ids: list[str]
) -> dict[str, tuple[list[str], list[list[str]]]]:
    """The report's tables by name (:data:`TABLES`): ``(header, rows)``, cells as shown."""
    return _report(rows, checks, question_ids)[1]


def _report(rows: list[StudentResult], checks, question_ids: list[str]) -> tuple[str, dict]:
    blank = [r for r in rows if not r.counts]  # no grade: listed with the reason, not counted
    rows = [r for r in rows if r.counts]
    data = _Class(rows, checks, question_ids)
    tables: dict[str, tuple[list[str], list[list[str]]]] = {}
    title = f"{checks.title}: class report"
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
    ]
    if blank:
        parts.append(
            f"<h2>No grade: {len(blank)} student(s), blank in the LMS files</h2>"
            + _table(
                ["student", "status", "why"],
                [[r.student, r.status, visible_text("; ".join(r.notes))] for r in blank],
                "no_grade",
                tables,
            )
        )
    n = len(data.rows)
    if not n:
        parts.append("<p>No submission was graded.</p></body></html>")
        return "\n".join(parts) + "\n", tables
    unmarked = unmarked_counts(data.rows, checks)
    warning = unmarked_warning(unmarked)
    if warning:  # every number below counts them as 0: say so first
        parts.append(
            f'<div class="warning"><p><strong>{html.escape(warning)}</strong> in this report, '
            "grades.csv and the LMS files. Mark them (<code>course mark OUT_DIR</code>) and "
            "rerun <code>course grade</code> with <code>--short-answers</code>.</p>"
            + _table(
                ["question", "not marked yet", "answers"],
                [[qid, todo, given] for qid, (todo, given) in unmarked.items() if todo],
                "unmarked",
                tables,
            )
            + "</div>"
        )
    totals = sorted(data.totals)
    median = totals[n // 2] if n % 2 else (totals[n // 2 - 1] + totals[n // 2]) / 2
    parts.append(
        f"<p>{n} student(s); total out of {data.max_points:g}: mean {sum(totals) / n:.2f}, "
        f"median {median:g}, lowest {totals[0]:g}, highest {totals[-1]:g}.</p>"
    )
    parts.append("<h2>Pass rate per question</h2>")
    parts.append(f"<figure>{_pass_rate_svg(data)}</figure>")
    rows_q = []
    for qid in data.qids:
        pts = [r.questions[qid].points for r in data.rows if qid in r.questions]
        q = checks.questions.get(qid)
        maximum = getattr(q, "points", None)
        rows_q.append(
            [
                qid,
                "" if maximum is None else f"{maximum:g}",
                f"{sum(pts) / len(pts):.2f}" if pts else "—",
                _pct(data.full[qid]),
                _pct(data.public[qid]),
                _pct(data.hidden[qid]),
            ]
        )
    parts.append(
        _table(
            ["question", "points", "mean", "full marks", "public cases", "hidden cases"],
            rows_q,
            "questions",
            tables,
        )
    )
    parts.append(
        '<p class="note">Full marks: share of students. Public and hidden cases: share of the '
        "cases run that passed (a question not answered runs none; — : no such case).</p>"
    )
    parts.append("<h2>Distribution of the totals</h2>")
    parts.append(f"<figure>{_totals_svg(data)}</figure>")

    parts.append("<h2>What went wrong, per question</h2>")
    wrong = []
    for qid in data.qids:
        for what, count in data.named[qid].most_common():
            wrong.append([qid, "named mistake", what, count])
        for what, count in data.kinds[qid].most_common():
            wrong.append([qid, "kind of wrong", what, count])
    parts.append(
        _table(["question", "diagnosis", "what", "students"], wrong, "wrong", tables)
        if wrong
        else "<p>No wrong answer was diagnosed.</p>"
    )
    parts.append(
        '<p class="note">Named mistakes are those of checks.py; the kinds of wrong are what '
        "the comparison recognised in a failed case. A student counts once per question.</p>"
    )

    parts.append("<h2>Timeouts, forbidden calls and other abnormal ends</h2>")
    abnormal = [
        [qid, status, len(students), ", ".join(students)]
        for qid in data.qids
        for status, students in sorted(data.abnormal[qid].items())
    ]
    parts.append(
        _table(["question", "status", "students", "who"], abnormal, "abnormal", tables)
        if abnormal
        else "<p>None.</p>"
    )

    if any(r.late is not None for r in data.rows):
        parts.append("<h2>Late submissions</h2>")
        parts.append(_late_table(data.rows, tables))

    parts.append("<h2>Slowest students</h2>")
    timed = sorted(
        (r for r in data.rows if isinstance(r.wall_seconds, (int, float))),
        key=lambda r: (-float(r.wall_seconds or 0), r.student),
    )
    parts.append(
        _table(
            ["student", "seconds", "status"],
            [[r.student, f"{float(r.wall_seconds or 0):.2f}", r.status] for r in timed[:5]],
            "slowest",
            tables,
        )
        if timed
        else "<p>No times recorded.</p>"
    )
    parts += _item_sections(data, tables)
    parts.append("</body></html>")
    return "\n".join(parts) + "\n", tables


def _rounded(x: float | None) -> str:
    return "—" if x is None else f"{x:.2f}"


def _item_sections(data: _Class, tables: dict) -> list[str]:
    """The item analysis, the kinds per question and the similarity hints."""
    stats = item_analysis(data.rows, data.qids)
    parts = ["<h2>Item analysis</h2>"]
    parts.append(
        _table(
            ["question", "students", "difficulty", "discrimination", "check"],
            [
                [
                    s.question,
                    s.students,
                    _rounded(s.difficulty),
                    _rounded(s.discrimination),
                    "flagged: discrimination near zero or negative (a wrong expected value? "
                    "ambiguous?)"
                    if s.flagged
                    else "",
                ]
                for s in stats
            ],
            "items",
            tables,
        )
    )
    parts.append(
        '<p class="note">Difficulty: the mean share of the points (1: everyone full marks). '
        "Discrimination: the point-biserial (item-rest) correlation of the question's score "
        "with the student's points on the other questions; — when either has no spread. "
        f"Flagged below {FLAG_BELOW:g} (from {MIN_STUDENTS} students): strong students do no "
        "better on the question than weak ones, or worse.</p>"
    )
    kinds = [[s.question, kind, f"{share:.2f}"] for s in stats for kind, share in s.kinds.items()]
    parts.append("<h3>Diagnosed kinds per question</h3>")
    parts.append(
        _table(["question", "kind", "share of students"], kinds, "kinds", tables)
        if kinds
        else "<p>No failed case.</p>"
    )
    groups = similar_groups(
        (qid, r.student, r.questions[qid].fingerprint)
        for qid in data.qids
        for r in data.rows
        if qid in r.questions
    )
    parts.append("<h2>Similar answers (hints)</h2>")
    parts.append(
        _table(
            ["question", "students", "who"],
            [[qid, len(who), ", ".join(who)] for qid, who in groups],
            "similar",
            tables,
        )
        if groups
        else "<p>No two answers alike.</p>"
    )
    parts.append(
        '<p class="note">Answers whose code is the same once names, the spelling of literals, '
        "comments and layout are set aside (the handed-out skeleton left out, very short "
        "answers not compared). A hint to put the answers side by side, not evidence of "
        "copying: students can arrive at the same code independently. Never shown to "
        "students.</p>"
    )
    return parts


def _late_table(rows: list[StudentResult], tables: dict | None = None) -> str:
    """The late submissions: when, how late, the deduction and the total after it (the
    totals above are after the deductions too)."""
    late = sorted((r for r in rows if r.late and r.late.get("days") != 0), key=lambda r: r.student)
    due = sorted({str(r.late.get("due")) for r in rows if r.late and r.late.get("due")})
    head = f"<p>Due {html.escape(', '.join(due)) if due else 'date unknown'}; {len(late)} late.</p>"
    if not late:
        return head
    body = [
        [
            r.student,
            r.late.get("submitted_at") or "unknown",
            "unknown (charged 1)" if r.late.get("days") is None else r.late["days"],
            f"{r.penalty:g}",
            f"{r.points:g}",
            f"{r.total:g}",
        ]
        for r in late
        if r.late is not None
    ]
    table = _table(
        ["student", "handed in", "days late", "deduction", "points", "total"], body, "late", tables
    )
    policy = html.escape(str(late[0].late.get("policy") if late[0].late else ""))
    return (
        head
        + table
        + f'<p class="note">Late policy: {policy}. Totals above are after the deduction.</p>'
    )


def write_report(rows: list[StudentResult], checks, question_ids: list[str], out: Path) -> Path:
    """Write ``out/report.html`` and its tables' CSV files beside it (a table the page no
    longer has loses its CSV); returns the page's path."""
    page, tables = _report(rows, checks, question_ids)
    path = Path(out) / REPORT_FILE
    path.write_text(page, encoding="utf-8")
    for name in TABLES:
        target = Path(out) / f"report-{name}.csv"
        if name not in tables:
            target.unlink(missing_ok=True)
            continue
        head, body = tables[name]
        buf = io.StringIO()
        writer = csv.writer(buf, dialect="excel", lineterminator="\r\n")
        writer.writerow(head)
        writer.writerows(body)
        target.write_text(buf.getvalue(), encoding="utf-8", newline="")
    return path
