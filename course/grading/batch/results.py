"""The graded results: one :class:`StudentResult` per submission, one :class:`QuestionResult`
per question, one :class:`CaseResult` per case run.

They are what the session produces and what the reports, the marking of short answers, the LMS
files and the cluster's workers read. On disk they are one JSON object per line of
``results.jsonl`` (:meth:`StudentResult.to_json`, read back with
:meth:`StudentResult.from_json`): an optional field is written only when it is set, and a key
this version does not know is kept as it was read, so a resumed run rewrites a row unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

__all__ = ["CaseResult", "QuestionResult", "StudentResult"]


@dataclass
class CaseResult:
    """One case of a question: its label, whether it passed and the student's message.

    ``detail`` (expected and got) is for the instructor's records only (``results.jsonl``),
    never the feedback; ``None``: not written. ``raised``: the student's code raised on this
    case (not written; the question's status is :attr:`~GradeStatus.ERROR` when every failed
    case raised and none passed).

    ``kind``: the diagnosis of a failed case as data, a
    :class:`~course.grading.vocabulary.MistakeKind` value set where the diagnosis was made
    (written as its string; ``None``: nothing diagnosed -- a timeout, a case not run -- and not
    written); ``mistake``: the declared mistake's message when ``kind`` is ``"named mistake"``
    (``None``: not written). The reports count these, never the message's words."""

    label: str
    ok: bool
    message: str = ""
    detail: str | None = None
    raised: bool = False
    kind: str | None = None
    mistake: str | None = None

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"label": self.label, "ok": self.ok, "message": self.message}
        if self.detail is not None:
            out["detail"] = self.detail
        if self.kind is not None:
            out["kind"] = str(self.kind)
        if self.mistake is not None:
            out["mistake"] = self.mistake
        return out

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> CaseResult:
        return cls(
            d["label"],
            d["ok"],
            d["message"],
            d.get("detail"),
            kind=d.get("kind"),
            mistake=d.get("mistake"),
        )

    @classmethod
    def of(cls, label: str, verdict, message: str | None = None) -> CaseResult:
        """The case ``label`` as the comparison's ``verdict`` judged it (its message, or
        ``message`` in its place), with the diagnosis's kind and named mistake."""
        return cls(
            label,
            verdict.ok,
            verdict.message if message is None else message,
            kind=None if verdict.ok or verdict.kind is None else str(verdict.kind),
            mistake=verdict.mistake or None,
        )


@dataclass
class QuestionResult:
    """One question's grade: points of ``max``, a status (a
    :class:`~course.grading.vocabulary.GradeStatus`), the student's message and the cases.

    ``answer``: a short answer's text, kept for the instructor's marking (``None``: not
    written). ``fingerprint``: the answer code's normalised fingerprint
    (:func:`course.grading.batch.similarity.fingerprint`), for the report's similarity hints
    only (``None``: none, not written)."""

    points: float
    max: float
    status: str
    message: str = ""
    cases: list[CaseResult] = field(default_factory=list)
    answer: str | None = None
    fingerprint: str | None = None

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "points": self.points,
            "max": self.max,
            "status": self.status,
            "message": self.message,
            "cases": [c.to_json() for c in self.cases],
        }
        if self.answer is not None:
            out["answer"] = self.answer
        if self.fingerprint is not None:
            out["fingerprint"] = self.fingerprint
        return out

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> QuestionResult:
        return cls(
            points=d["points"],
            max=d["max"],
            status=d["status"],
            message=d["message"],
            cases=[CaseResult.from_json(c) for c in d["cases"]],
            answer=d.get("answer"),
            fingerprint=d.get("fingerprint"),
        )

    @property
    def full_marks(self) -> bool:
        return self.points >= self.max


#: StudentResult's fields that are written only when set (None: absent from the JSON row)
_OPTIONAL = ("deleted_answers", "wall_seconds", "file", "late", "cleanup_failed")


@dataclass
class StudentResult:
    """One submission's grade: the row of ``results.jsonl``.

    ``status`` is a :class:`~course.grading.vocabulary.SubmissionStatus`, or the abnormal
    questions (``"q1: timeout; q3: forbidden"``); ``notes`` are for the student;
    ``deleted_answers`` maps a question whose answer cell was deleted to ``"adopted"`` (graded
    from an added cell) or ``"missing"``; ``file`` is the graded file and its sha256; ``late``
    is when it was handed in and the late deduction (:mod:`course.grading.batch.late`), and
    ``total`` is then the points after the deduction; ``cleanup_failed`` lists what its
    processes left that could not be removed (instructor only: ``"<path> (<reason>)"``)."""

    student: str
    assignment: str
    checks_sha256: str
    version: str
    data_key: str
    max: float
    questions: dict[str, QuestionResult] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    total: float = 0.0
    status: str = "ok"
    deleted_answers: dict[str, str] | None = None
    wall_seconds: float | None = None
    file: dict[str, Any] | None = None
    late: dict[str, Any] | None = None
    has_file: bool = False  # ``file`` is written (null included) once the driver recorded it
    cleanup_failed: list[str] | None = None
    extra: dict[str, Any] = field(default_factory=dict)  # keys of other versions, kept as read

    @property
    def points(self) -> float:
        """The sum of the questions' points, before any late deduction."""
        return round(sum(r.points for r in self.questions.values()), 4)

    @property
    def penalty(self) -> float:
        """The points the late deduction takes (never more than the points earned)."""
        percent = float((self.late or {}).get("percent") or 0.0)
        return round(min(self.points, percent / 100 * self.max), 4)

    def add_total(self) -> None:
        """``total``: the sum of the questions' points less the late deduction (rounded as
        written, never below 0)."""
        self.total = round(self.points - self.penalty, 4)

    def set_late(self, record: dict[str, Any] | None) -> bool:
        """Attach the late record (None: nothing known) and recompute the total; True when
        the row changed."""
        before = (self.late, self.total)
        self.late = record
        if record is not None or before[0] is not None:
            self.add_total()
        return (self.late, self.total) != before

    def order_questions(self, order: list[str]) -> None:
        """Put the questions in ``order`` (the notebook's), any others after them: a row read
        back from JSON, or graded on another machine, then writes the same feedback."""
        ordered = {q: self.questions[q] for q in order if q in self.questions}
        ordered.update((q, r) for q, r in self.questions.items() if q not in ordered)
        self.questions = ordered

    @property
    def counts(self) -> bool:
        """Whether the row is a grade (not one the grader failed on, nor a refused or
        quarantined file): only then does it reach an LMS file."""
        return self.status not in ("not graded", "grader error", "refused")

    def record_file(self, file: dict[str, Any] | None) -> None:
        self.file = file
        self.has_file = True

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = dict(self.extra)
        out.update(
            student=self.student,
            assignment=self.assignment,
            checks_sha256=self.checks_sha256,
            version=self.version,
            data_key=self.data_key,
            questions={qid: r.to_json() for qid, r in self.questions.items()},
            notes=list(self.notes),
            total=self.total,
            max=self.max,
            status=self.status,
        )
        if self.deleted_answers is not None:
            out["deleted_answers"] = dict(self.deleted_answers)
        if self.wall_seconds is not None:
            out["wall_seconds"] = self.wall_seconds
        if self.has_file:
            out["file"] = self.file
        if self.late is not None:
            out["late"] = dict(self.late)
        if self.cleanup_failed:
            out["cleanup_failed"] = list(self.cleanup_failed)
        return out

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> StudentResult:
        """The row ``d`` of ``results.jsonl`` (KeyError or TypeError: not a row of this
        format)."""
        known = {
            "student",
            "assignment",
            "checks_sha256",
            "version",
            "data_key",
            "questions",
            "notes",
            "total",
            "max",
            "status",
            *_OPTIONAL,
        }
        return cls(
            student=d["student"],
            assignment=d["assignment"],
            checks_sha256=d["checks_sha256"],
            version=d["version"],
            data_key=d["data_key"],
            max=d["max"],
            questions={qid: QuestionResult.from_json(r) for qid, r in d["questions"].items()},
            notes=list(d["notes"]),
            total=d["total"],
            status=d["status"],
            deleted_answers=d.get("deleted_answers"),
            wall_seconds=d.get("wall_seconds"),
            file=d.get("file"),
            late=d.get("late"),
            has_file="file" in d,
            cleanup_failed=d.get("cleanup_failed"),
            extra={k: v for k, v in d.items() if k not in known},
        )
