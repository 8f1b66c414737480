"""The words every part of the grading package shares, defined once.

Cell roles of a solution notebook, the placeholder and demo student IDs, the operations of the
parent-child protocol, the statuses of replies, questions and submissions, and
:class:`PublicSpec`, the content of the ``checks.json`` a release ships to students.

The enums are ``str`` subclasses, so a status is written to JSON and CSV as its plain value
(``"not answered"``) and a row read back from ``results.jsonl`` compares equal to the enum.
"""

from __future__ import annotations

import enum
import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = [
    "ABNORMAL",
    "CHECKS_FILE",
    "CLASS_FILE",
    "DEMO_STUDENT_ID",
    "PLACEHOLDER_ID",
    "PUBLIC_FORMAT",
    "SPECIFIC_KINDS",
    "STUDENT_ID_RULE",
    "CellOrigin",
    "CellRole",
    "GradeStatus",
    "MistakeKind",
    "Op",
    "PublicCase",
    "PublicQuestion",
    "PublicSpec",
    "QuestionKind",
    "ReplyStatus",
    "SubmissionStatus",
    "answer_cell_id",
    "check_student_id",
    "compile_id_pattern",
    "id_off_pattern",
    "id_pattern_in",
    "is_student_id",
    "visible_text",
]


class _Word(str, enum.Enum):
    """A string enum that prints as its value (also under ``format`` and f-strings)."""

    def __str__(self) -> str:
        return str(self.value)

    def __format__(self, spec: str) -> str:
        return format(str(self.value), spec)


#: The value of ``STUDENT_ID`` in a released notebook, until the student sets it.
PLACEHOLDER_ID = "replace-with-your-student-id"

#: The student ID the public self-check and ``course release`` use where one is needed.
DEMO_STUDENT_ID = "demo"

#: What a student ID may look like: it names files (``<ID>_<assignment>.ipynb``), rows of
#: ``grades.csv`` and LMS imports, so no spaces, no path separators and no leading ``=+-@``.
STUDENT_ID_RULE = "1 to 64 letters, digits and . _ - @, starting with a letter or digit"
_STUDENT_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._@-]{0,63}$")


# control characters (C0, DEL, C1), and the invisible ones that reorder or hide text
CONTROL_CHARACTERS = re.compile(
    r"[\x00-\x1f\x7f-\x9f\u200b-\u200f\u2028-\u202e\u2066-\u2069\ufeff]"
)


def visible_text(text) -> str:
    """``text`` with every control character shown as an escape (``\\x1b``, ``\\n``): student
    text (file names, exception messages) reaching the console, a CSV cell, a file name or
    the feedback can neither move the cursor, ring, recolour nor start a new line."""
    return CONTROL_CHARACTERS.sub(lambda m: repr(m.group())[1:-1], str(text))


def is_student_id(text) -> bool:
    """True when ``text`` is a well-formed student ID (not checking placeholder or demo)."""
    return isinstance(text, str) and _STUDENT_ID.fullmatch(text) is not None


#: A graded class's rules for the student's side (``course export --id-pattern``), written
#: beside each assignment's ``checks.json`` in the class's edition.
CLASS_FILE = "class.json"


def compile_id_pattern(pattern) -> re.Pattern:
    """The instructor's ID pattern (a Python regular expression that a whole ID must match),
    compiled; ValueError when it is not one."""
    if not isinstance(pattern, str) or not pattern.strip():
        raise ValueError("the student ID pattern is empty: give a regular expression")
    try:
        return re.compile(pattern)
    except re.error as exc:
        raise ValueError(
            f"the student ID pattern {pattern!r} is not a regular expression ({exc})"
        ) from None


def id_pattern_in(folder) -> str | None:
    """The class's student ID pattern from ``folder/class.json`` (None: no pattern set, or
    no readable file: the self-check then checks only the ID's form)."""
    try:
        content = json.loads((Path(folder) / CLASS_FILE).read_text("utf-8"))
        pattern = content.get("id_pattern") if isinstance(content, dict) else None
        compile_id_pattern(pattern)
    except (OSError, ValueError):
        return None
    return pattern


def id_off_pattern(student_id: str, pattern: str | None, where: str = "STUDENT_ID") -> str:
    """What is wrong with ``student_id`` against the class's ``pattern`` ('' when it matches,
    or when there is no pattern)."""
    if not pattern or compile_id_pattern(pattern).fullmatch(student_id):
        return ""
    return (
        f"{where} {student_id!r} is not a student ID of this class: your instructor's IDs "
        f"match the pattern {pattern}. Set it to your student ID exactly as registered and "
        "run that cell again"
    )


def check_student_id(student_id, where: str = "STUDENT_ID", pattern: str | None = None) -> str:
    """The stripped ``student_id``, or ValueError saying what is wrong and what to do.

    Refuses a missing ID, the release's placeholder, the demo ID, malformed text and, when
    the class has one (``pattern``, see :func:`id_pattern_in`), an ID off its pattern.
    """
    sid = "" if student_id is None else str(student_id).strip()
    if not sid:
        raise ValueError(f"{where} is empty: set it to your student ID, exactly as registered")
    if sid == PLACEHOLDER_ID:
        raise ValueError(
            f"{where} is still the placeholder {PLACEHOLDER_ID!r}: set it to your student ID "
            "in the first cell and run that cell again"
        )
    if sid == DEMO_STUDENT_ID:
        raise ValueError(
            f"{where} is the demo ID {DEMO_STUDENT_ID!r}: set it to your own student ID"
        )
    if not is_student_id(sid):
        raise ValueError(f"{where} {sid!r} is not a valid student ID ({STUDENT_ID_RULE})")
    off = id_off_pattern(sid, pattern, where)
    if off:
        raise ValueError(off)
    return sid


#: The public file of a release, and the version of its format (2: expected values sealed,
#: see :mod:`course.grading.authoring.seal`; 1 shipped them in the clear and is refused).
CHECKS_FILE = "checks.json"
PUBLIC_FORMAT = 2


class CellRole(_Word):
    """The role of a cell of a solution notebook (``metadata.course.role``)."""

    SETUP = "setup"  # the first code cell: STUDENT_ID and the self-check
    ANSWER = "answer"  # a student's answer to metadata.course.question
    CHECK = "check"  # check("q1"): skipped at grading
    CONTEXT = "context"  # any other code cell: runs as released
    TEXT = "text"  # markdown and raw cells


class QuestionKind(_Word):
    """What a question asks for (``Question.kind``, ``checks.json``)."""

    VALUE = "value"  # a variable, compared with the reference value
    FUNCTION = "function"  # a function, called on public and hidden cases
    CHOICE = "choice"  # one of a list of options (multiple choice), graded at grading only
    SHORT_ANSWER = "short_answer"  # text in a markdown cell, marked by the instructor


#: The id of the answer cell of question ``qid`` in every release (the grader finds it by it).
def answer_cell_id(qid: str) -> str:
    return f"{qid}-answer"


class CellOrigin(_Word):
    """Where a cell the grader runs comes from."""

    SETUP = "setup"
    CONTEXT = "context"
    ANSWER = "answer"
    EXTRA = "extra"  # a cell the student added


class Op(_Word):
    """Operations of the protocol between the grader and its processes."""

    INIT = "init"  # parent -> child: student ID, data, limits; reply: ready
    RUN = "run"  # run one cell
    VALUE = "value"  # the value of a variable
    CALL = "call"  # call a function with plain-data arguments
    READ = "read"  # decode the submitted notebook in the child's folder (no student code ran)
    EXIT = "exit"  # stop politely
    SPAWN = "spawn"  # parent -> fork server: fork a child
    STATUS = "status"  # parent -> fork server: exit status of a child


class ReplyStatus(_Word):
    """The status a child puts in its reply to one request."""

    OK = "ok"
    ERROR = "error"
    READY = "ready"
    UNDEFINED = "undefined"  # no such variable or function
    STUB = "stub"  # still ``...`` or raising NotImplementedError
    NOT_CALLABLE = "notcallable"
    UNENCODABLE = "unencodable"  # not plain data


class GradeStatus(_Word):
    """The status of one graded question."""

    PASS = "pass"
    FAIL = "fail"
    PARTIAL = "partial"
    ERROR = "error"
    NOT_ANSWERED = "not answered"
    TIMEOUT = "timeout"
    CRASH = "crash"
    MEMORY = "memory"
    FORBIDDEN = "forbidden"
    GRADER_ERROR = "grader error"
    SKIPPED = "skipped"
    TO_MARK = "to mark"  # a short answer the instructor has not marked yet
    MARKED = "marked"  # a short answer marked by the instructor (course grade --short-answers)


class MistakeKind(_Word):
    """The kind of wrong answer a failed case shows, set where the diagnosis is made
    (:mod:`course.grading.compare`, :mod:`course.grading.authoring.seal`, the grader's session)
    and written with the case to ``results.jsonl`` (``"kind"``): the class report counts by it,
    never by reading a message, so rewording a message moves no count.

    The one list: :class:`~course.grading.compare.Verdict` refuses any other kind."""

    NAMED = "named mistake"  # a declared Mistake of checks.py (its message: ``mistake``)
    RAISED = "raised an exception"
    NOT_PLAIN_DATA = "not plain data"
    SINGLE_PRECISION = "computed in float32"
    TRANSPOSED = "transposed"
    SIGN = "the sign"
    FACTOR = "a constant factor"
    SQUARE = "squared or square root"
    ORDER = "another order"
    ONE_TOO_MANY_OR_FEW = "one too many or few"
    SHAPE = "the shape or length"
    NOT_FINITE = "NaN or inf"
    NEAR_MISS = "a near miss"
    ZEROS = "all zeros"
    OPPOSITE = "the opposite decision"
    DECISIONS = "some decisions wrong"
    OUTSIDE_BAND = "outside the band"
    TYPE = "the type"
    STRING_CASE = "upper/lower case or spaces"
    NOT_AN_OPTION = "not an option"
    WRONG_OPTION = "another option"
    OTHER_DATA = "the answer of other data"  # hard-coded, or a global in place of an argument
    WRONG_VALUE = "another wrong value"  # nothing more specific recognised


#: Kinds that name what went wrong; the others (a bare factor, a value outside the tolerance
#: or the band, another option or string) say only that it is wrong.
SPECIFIC_KINDS = frozenset(MistakeKind) - {
    MistakeKind.FACTOR,
    MistakeKind.DECISIONS,
    MistakeKind.OUTSIDE_BAND,
    MistakeKind.WRONG_OPTION,
    MistakeKind.WRONG_VALUE,
}


#: Question statuses that the submission's status lists (``"q1: timeout; q3: forbidden"``).
ABNORMAL = frozenset(
    {
        GradeStatus.TIMEOUT,
        GradeStatus.CRASH,
        GradeStatus.MEMORY,
        GradeStatus.FORBIDDEN,
        GradeStatus.GRADER_ERROR,
        GradeStatus.SKIPPED,
    }
)


class SubmissionStatus(_Word):
    """The fixed statuses of a whole submission (otherwise it lists its abnormal questions)."""

    OK = "ok"
    INVALID_NOTEBOOK = "invalid notebook"
    REFUSED = "refused"  # e.g. a symbolic link among the submissions
    GRADER_ERROR = "grader error"  # a fault of the grader, retried
    NOT_GRADED = "not graded"  # still a fault after the retries: no grade, blank in LMS files


# --------------------------------------------------------------------------------------
# checks.json
# --------------------------------------------------------------------------------------
@dataclass
class PublicCase:
    """One public case: the encoded arguments (function questions), the sealed expected value
    and the declared mistakes as ``[message, sealed wrong value]`` pairs (sealed values:
    :func:`course.grading.authoring.seal.seal`)."""

    label: str
    expected: Any
    args: Any = None
    kwargs: Any = None
    mistakes: list = field(default_factory=list)

    def to_dict(self) -> dict:
        out: dict = {"label": self.label}
        if self.args is not None:
            out["args"] = self.args
            out["kwargs"] = self.kwargs
        out["expected"] = self.expected
        if self.mistakes:
            out["mistakes"] = [[str(m), v] for m, v in self.mistakes]
        return out

    @classmethod
    def from_dict(cls, d: dict) -> PublicCase:
        mistakes = [(str(m), v) for m, v in d.get("mistakes", [])]
        return cls(d["label"], d["expected"], d.get("args"), d.get("kwargs"), mistakes)


@dataclass
class PublicQuestion:
    """What a student's self-check knows of one question (no reference code, no hidden case)."""

    id: str
    kind: str  # "value" or "function"
    target: str
    points: float
    hint: str | list = ""  # one stage, or the list of staged hints
    rtol: float = 1e-7
    atol: float = 1e-9
    partial: bool = True
    forbid: list = field(default_factory=list)
    data: str | None = None
    properties: str | None = None
    public: bool = True
    cases: list[PublicCase] = field(default_factory=list)
    hidden_cases: int = 0
    signature: dict | None = None  # type and shape of a value that is not shipped
    options: list | None = None  # a choice question's options (encoded plain data)
    mistake_hints: dict = field(default_factory=dict)  # a declared mistake's message -> its hint

    @property
    def hints(self) -> list[str]:
        """The hint stages (one stage when ``hint`` is a string; none when it is empty)."""
        if isinstance(self.hint, str):
            return [self.hint] if self.hint else []
        return [str(h) for h in self.hint]

    def to_dict(self) -> dict:
        out = {
            "id": self.id,
            "kind": self.kind,
            "target": self.target,
            "points": self.points,
            "hint": self.hint if isinstance(self.hint, str) else list(self.hint),
            "rtol": self.rtol,
            "atol": self.atol,
            "partial": self.partial,
            "forbid": list(self.forbid),
            "data": self.data,
            "properties": self.properties,
            "public": self.public,
            "cases": [c.to_dict() for c in self.cases],
            "hidden_cases": self.hidden_cases,
        }
        if self.signature is not None:
            out["signature"] = self.signature
        if self.options is not None:
            out["options"] = self.options
        if self.mistake_hints:
            out["mistake_hints"] = dict(self.mistake_hints)
        return out

    @classmethod
    def from_dict(cls, d: dict) -> PublicQuestion:
        return cls(
            id=d["id"],
            kind=d["kind"],
            target=d["target"],
            points=d["points"],
            hint=d.get("hint", ""),
            rtol=d.get("rtol", 1e-7),
            atol=d.get("atol", 1e-9),
            partial=d.get("partial", True),
            forbid=list(d.get("forbid", [])),
            data=d.get("data"),
            properties=d.get("properties"),
            public=d.get("public", True),
            cases=[PublicCase.from_dict(c) for c in d.get("cases", [])],
            hidden_cases=int(d.get("hidden_cases", 0)),
            signature=d.get("signature"),
            options=d.get("options"),
            mistake_hints={str(k): str(v) for k, v in d.get("mistake_hints", {}).items()},
        )


@dataclass
class PublicSpec:
    """The content of ``exercises/<name>/checks.json``: public cases with sealed expected values
    (:mod:`course.grading.authoring.seal`) and plain-data inputs (:mod:`course.grading.codec`), never
    code, never an expected value in the clear.

    Built by :func:`course.grading.authoring.release.public_spec`, read by the student's self-check.
    """

    assignment: str
    title: str
    max_points: float
    questions: list[PublicQuestion]
    data_file: str | None = None
    data_keys: list = field(default_factory=list)
    format: int = PUBLIC_FORMAT

    def to_dict(self) -> dict:
        return {
            "format": self.format,
            "assignment": self.assignment,
            "title": self.title,
            "max_points": self.max_points,
            "data_file": self.data_file,
            "data_keys": list(self.data_keys),
            "questions": [q.to_dict() for q in self.questions],
        }

    @classmethod
    def from_dict(cls, d: dict) -> PublicSpec:
        if not isinstance(d, dict) or "assignment" not in d:
            raise ValueError("not a checks.json of a released assignment")
        if d.get("format", PUBLIC_FORMAT) > PUBLIC_FORMAT:
            raise ValueError(
                f"checks.json format {d['format']} is newer than this course package "
                f"understands ({PUBLIC_FORMAT}); upgrade the course package"
            )
        if d.get("format", 1) < PUBLIC_FORMAT:
            raise ValueError(
                f"checks.json format {d.get('format', 1)} is from an older release, which "
                "shipped the expected values themselves; this course package self-checks only "
                f"sealed checks (format {PUBLIC_FORMAT}). Ask your instructor for the current "
                "release of the exercises (instructors: run `course release --all`)."
            )
        return cls(
            assignment=d["assignment"],
            title=d.get("title", d["assignment"]),
            max_points=d.get("max_points", 0.0),
            questions=[PublicQuestion.from_dict(q) for q in d.get("questions", [])],
            data_file=d.get("data_file"),
            data_keys=list(d.get("data_keys", [])),
            format=d.get("format", PUBLIC_FORMAT),
        )

    def text(self) -> str:
        """The file's exact text (sorted keys, so a release is byte-for-byte deterministic)."""
        return (
            json.dumps(
                self.to_dict(), sort_keys=True, indent=1, ensure_ascii=False, allow_nan=False
            )
            + "\n"
        )

    @classmethod
    def loads(cls, text: str) -> PublicSpec:
        return cls.from_dict(json.loads(text))

    def write(self, folder: Path) -> Path:
        path = Path(folder) / CHECKS_FILE
        path.write_text(self.text(), encoding="utf-8")
        return path

    @classmethod
    def read(cls, folder: Path) -> PublicSpec:
        """Read ``folder/checks.json`` (ValueError when it is not a release's checks.json)."""
        return cls.loads((Path(folder) / CHECKS_FILE).read_text("utf-8"))

    def question(self, qid: str) -> PublicQuestion:
        return next(q for q in self.questions if q.id == qid)
