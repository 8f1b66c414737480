"""``report.html``: the picture of a graded class, written beside ``grades.csv`` by each run.

One self-contained page (figures embedded as base64 PNG in the course's figure style, no
script, no style sheet or font from outside), readable without the console:

- the pass rate per question: full marks, and the public and hidden cases apart;
- the distribution of the totals;
- per question, how often each named mistake (a :class:`~course.grading.authoring.checks.Mistake`
  of ``checks.py``) and each kind of wrong answer the comparison diagnosed (a constant factor,
  the sign, the shape, off by one, ...) occurred;
- the timeouts, forbidden calls and other abnormal ends, with the students;
- the slowest students.

Counts are of students: a student whose three hidden cases show the same factor counts once.
"""

from __future__ import annotations

import base64
import html
import io
import threading
from collections import Counter
from pathlib import Path

from course.grading.batch.results import StudentResult
from course.grading.vocabulary import GradeStatus

__all__ = ["diagnosis", "report_html", "warm_up", "write_report"]

REPORT_FILE = "report.html"

#: (text in a failed case's message, the kind of wrong answer it shows), first match wins.
_KINDS = (
    ("raised ", "raised an exception"),
    ("transposed", "transposed"),
    ("sign is flipped", "the sign"),
    ("factor", "a constant factor"),
    ("off by one", "off by one"),
    ("another order", "another order"),
    ("one element too", "one element too many or few"),
    ("one item too", "one item too many or few"),
    ("expected shape", "the shape or length"),
    ("expected length", "the shape or length"),
    ("got NaN", "NaN or inf"),
    ("got inf", "NaN or inf"),
    ("close: it agrees", "a near miss"),
    ("opposite", "the opposite decision"),
    ("outside the accepted band", "outside the band"),
    ("expected a", "the type"),
    ("expected real", "the type"),
    ("expected integer", "the type"),
    ("expected bool", "the type"),
    ("expected None", "the type"),
    ("expected keys", "the type"),
)
#: Case messages that are not a diagnosis of a wrong answer (the question's status says it).
_NOT_A_DIAGNOSIS = ("timeout", "not run", "not answered", "unreadable result")
_ABNORMAL = (
    GradeStatus.TIMEOUT,
    GradeStatus.FORBIDDEN,
    GradeStatus.CRASH,
    GradeStatus.MEMORY,
    GradeStatus.ERROR,
    GradeStatus.GRADER_ERROR,
)


def diagnosis(message: str, named: list[str] | tuple[str, ...] = ()) -> tuple[str, str] | None:
    """``("named", mistake)`` or ``("kind", kind of wrong)`` for a failed case's message, or
    None when the message diagnoses nothing (a timeout, a case not run).

    Examples
    --------
    >>> diagnosis("T: too large by a factor ≈ 2.0; tolerance ...")
    ('kind', 'a constant factor')
    >>> diagnosis("z: looks one-sided", named=["looks one-sided"])
    ('named', 'looks one-sided')
    """
    text = str(message)
    if not text or text in _NOT_A_DIAGNOSIS:
        return None
    for mistake in named:
        if text.endswith(f": {mistake}") or text == mistake:
            return ("named", mistake)
    for needle, kind in _KINDS:
        if needle in text:
            return ("kind", kind)
    return ("kind", "another wrong value")


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
            q = checks.questions.get(qid)
            names = [m.message for m in getattr(q, "mistakes", ())] if q is not None else []
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
                    if not case.ok:
                        found = diagnosis(case.message, names)
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


def _import_figures() -> None:
    import matplotlib.backends.backend_agg
    import matplotlib.figure  # noqa: F401

    import course.plotting.style  # noqa: F401


def warm_up() -> threading.Thread:
    """Import matplotlib in a background thread (about a second): the driver starts it while
    the children grade, when the parent mostly waits, so the report adds only its drawing to
    the run's time."""
    thread = threading.Thread(target=_import_figures, name="report-warm-up", daemon=True)
    thread.start()
    return thread


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _figures(data: _Class) -> list[tuple[str, str]]:
    """(alt text, base64 PNG) of the pass-rate bars and the histogram of totals."""
    from matplotlib.figure import Figure  # no pyplot: no global figure state, no backend
    from matplotlib.ticker import MaxNLocator

    from course.plotting.style import SAMPLE, THRESHOLD, context, legend_outside, pair

    out = []
    with context():
        n_q = len(data.qids)
        fig = Figure(figsize=(min(8.5, 3.5 + 0.6 * n_q), 3.6))
        ax = fig.subplots()
        width = 0.27
        series = (
            ("full marks", data.full, pair(0)),
            ("public cases", data.public, pair(2)),
            ("hidden cases", data.hidden, pair(1)),
        )
        for k, (label, rates, colours) in enumerate(series):
            # no bar where a question has no case of the kind (the table shows —), not a zero
            shown = [(i, rates[q]) for i, q in enumerate(data.qids) if rates[q] is not None]
            xs = [i + (k - 1) * width for i, _ in shown]
            ys = [100 * (rate or 0.0) for _, rate in shown]
            ax.bar(xs, ys, width, label=label, color=colours.dark)
        ax.set_xticks(range(n_q), data.qids)
        if n_q > 6 or max((len(q) for q in data.qids), default=0) > 4:
            ax.tick_params(axis="x", labelrotation=35)
            for tick in ax.get_xticklabels():
                tick.set_horizontalalignment("right")
        ax.set_ylim(0, 100)
        ax.set_ylabel("students or cases passed [%]")
        ax.set_xlabel("question")
        legend_outside(ax)
        out.append(("pass rate per question: full marks, public and hidden cases", _png(fig)))

        fig = Figure(figsize=(6.4, 3.2))
        ax = fig.subplots()
        top = data.max_points or 1.0
        bins = max(5, min(20, int(top) + 1))
        ax.hist(
            data.totals,
            bins=bins,
            range=(0, top),
            color=SAMPLE.light,
            edgecolor=SAMPLE.dark,
            linewidth=0.5,
            label="students",
        )
        ax.axvline(top, color=THRESHOLD, ls="--", lw=1, label="maximum")
        ax.set_xlabel("total [points]")
        ax.set_ylabel("students")
        ax.yaxis.set_major_locator(MaxNLocator(integer=True))
        legend_outside(ax)
        out.append(("distribution of the totals", _png(fig)))
    return out


def _pct(rate: float | None) -> str:
    return "—" if rate is None else f"{100 * rate:.0f} %"


def _table(head: list[str], rows: list[list]) -> str:
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
img { max-width: 100%; height: auto; display: block; margin: 0.5rem 0 1rem; }
.note { color: #555; }
"""


def report_html(rows: list[StudentResult], checks, question_ids: list[str]) -> str:
    """The class report of ``rows`` as one self-contained HTML page."""
    data = _Class(rows, checks, question_ids)
    title = f"{checks.title}: class report"
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
    ]
    n = len(data.rows)
    if not n:
        parts.append("<p>No submission was graded.</p></body></html>")
        return "\n".join(parts) + "\n"
    totals = sorted(data.totals)
    median = totals[n // 2] if n % 2 else (totals[n // 2 - 1] + totals[n // 2]) / 2
    parts.append(
        f"<p>{n} student(s); total out of {data.max_points:g}: mean {sum(totals) / n:.2f}, "
        f"median {median:g}, lowest {totals[0]:g}, highest {totals[-1]:g}.</p>"
    )
    figures = _figures(data)
    parts.append("<h2>Pass rate per question</h2>")
    alt, png = figures[0]
    parts.append(f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{png}">')
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
        _table(["question", "points", "mean", "full marks", "public cases", "hidden cases"], rows_q)
    )
    parts.append(
        '<p class="note">Full marks: share of students. Public and hidden cases: share of the '
        "cases run that passed (a question not answered runs none; — : no such case).</p>"
    )
    parts.append("<h2>Distribution of the totals</h2>")
    alt, png = figures[1]
    parts.append(f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{png}">')

    parts.append("<h2>What went wrong, per question</h2>")
    wrong = []
    for qid in data.qids:
        for what, count in data.named[qid].most_common():
            wrong.append([qid, "named mistake", what, count])
        for what, count in data.kinds[qid].most_common():
            wrong.append([qid, "kind of wrong", what, count])
    parts.append(
        _table(["question", "diagnosis", "what", "students"], wrong)
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
        _table(["question", "status", "students", "who"], abnormal) if abnormal else "<p>None.</p>"
    )

    parts.append("<h2>Slowest students</h2>")
    timed = sorted(
        (r for r in data.rows if isinstance(r.wall_seconds, (int, float))),
        key=lambda r: (-float(r.wall_seconds or 0), r.student),
    )
    parts.append(
        _table(
            ["student", "seconds", "status"],
            [[r.student, f"{float(r.wall_seconds or 0):.2f}", r.status] for r in timed[:5]],
        )
        if timed
        else "<p>No times recorded.</p>"
    )
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def write_report(rows: list[StudentResult], checks, question_ids: list[str], out: Path) -> Path:
    """Write ``out/report.html``; returns its path."""
    path = Path(out) / REPORT_FILE
    path.write_text(report_html(rows, checks, question_ids), encoding="utf-8")
    return path
