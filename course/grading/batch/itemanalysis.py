"""Item analysis of a graded class: which questions work, for the class report.

Per question, over the students graded on it (a question not answered scores 0; a short
answer not marked yet is left out of its question, having no score yet):

difficulty
    the mean share of the points, ``p = mean(points / max)`` (1: everyone full marks);
discrimination
    the corrected item-total correlation: Pearson's correlation between the question's
    score and the *rest* of the test (the student's points on the other questions, before any
    late deduction). For a question scored right or wrong it is the point-biserial
    correlation; leaving the question out of the total keeps it from correlating with itself.
    None when either has no spread (everyone scored the same);
kinds
    the share of the students with at least one failed case of each diagnosed kind (a case's
    ``kind``; a failed case without one counts as ``unknown``).

A question is flagged when its discrimination is below :data:`FLAG_BELOW` (near zero or
negative: the strong students do no better on it than the weak, or worse, which is what a wrong
expected value or an ambiguous question does), once at least :data:`MIN_STUDENTS` students are
graded on it.

Notes
-----
``r = sum((x - x̄)(y - ȳ)) / sqrt(sum((x - x̄)^2) sum((y - ȳ)^2))`` with ``x`` the question's
score and ``y`` the rest score; item difficulty and discrimination as in classical test
theory, Crocker and Algina (1986) (sources: :doc:`/docs/bibliography`). The usual
reading takes a discrimination below 0.2 as weak, and one near zero or below as a question to
revise.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field

from course.grading.batch.results import StudentResult
from course.grading.vocabulary import GradeStatus

__all__ = ["FLAG_BELOW", "MIN_STUDENTS", "ItemStats", "item_analysis"]

#: Discrimination below this flags a question (near zero or negative).
FLAG_BELOW = 0.1
#: Fewer students than this: no flag (a correlation of a handful of students is noise).
MIN_STUDENTS = 5
#: A failed case's kind when the results do not carry one.
UNKNOWN_KIND = "unknown"


@dataclass(frozen=True)
class ItemStats:
    """One question's item analysis (see the module docstring)."""

    question: str
    students: int
    difficulty: float | None
    discrimination: float | None
    kinds: dict[str, float] = field(default_factory=dict)  # kind -> share of the students
    flagged: bool = False


def _kind(case) -> str:
    """A failed case's kind as text (an enum's value, a string; absent: unknown)."""
    kind = getattr(case, "kind", None)
    if kind is None or kind == "":
        return UNKNOWN_KIND
    return str(getattr(kind, "value", kind))


def _correlation(x: list[float], y: list[float]) -> float | None:
    """Pearson's r of ``x`` and ``y`` (None: one of them has no spread)."""
    n = len(x)
    if n < 2:
        return None
    mx, my = math.fsum(x) / n, math.fsum(y) / n
    dx = [a - mx for a in x]
    dy = [b - my for b in y]
    sxx = math.fsum(a * a for a in dx)
    syy = math.fsum(b * b for b in dy)
    # relative cut: a spread of rounding noise (1e-16 of the values) is no spread
    scale_x = max((abs(a) for a in x), default=0.0) or 1.0
    scale_y = max((abs(b) for b in y), default=0.0) or 1.0
    if sxx <= (1e-12 * scale_x) ** 2 * n or syy <= (1e-12 * scale_y) ** 2 * n:
        return None
    r = math.fsum(a * b for a, b in zip(dx, dy)) / math.sqrt(sxx * syy)
    return max(-1.0, min(1.0, r))


def item_analysis(rows: list[StudentResult], question_ids: list[str]) -> list[ItemStats]:
    """The :class:`ItemStats` of each question of ``question_ids`` over ``rows``.

    Examples
    --------
    >>> from course.grading.batch.results import QuestionResult, StudentResult
    >>> def row(sid, a, b):
    ...     r = StudentResult(sid, "A1", "c", "v", "k", 2.0)
    ...     r.questions = {"q1": QuestionResult(a, 1.0, "x"), "q2": QuestionResult(b, 1.0, "x")}
    ...     return r
    >>> stats = item_analysis([row("a", 1, 1), row("b", 1, 0), row("c", 0, 0)], ["q1", "q2"])
    >>> round(stats[0].difficulty, 3), round(stats[0].discrimination, 3)
    (0.667, 0.5)
    """
    out = []
    for qid in question_ids:
        graded = [
            r for r in rows if qid in r.questions and r.questions[qid].status != GradeStatus.TO_MARK
        ]
        scores, rest = [], []
        kinds: Counter[str] = Counter()
        for r in graded:
            res = r.questions[qid]
            scores.append(float(res.points) / float(res.max) if res.max else 0.0)
            rest.append(math.fsum(float(o.points) for q, o in r.questions.items() if q != qid))
            kinds.update({_kind(c) for c in res.cases if not c.ok})
        n = len(graded)
        difficulty = math.fsum(scores) / n if n else None
        discrimination = _correlation(scores, rest)
        flagged = n >= MIN_STUDENTS and discrimination is not None and discrimination < FLAG_BELOW
        shares = {k: c / n for k, c in sorted(kinds.items(), key=lambda kv: (-kv[1], kv[0]))}
        out.append(ItemStats(qid, n, difficulty, discrimination, shares, flagged))
    return out
