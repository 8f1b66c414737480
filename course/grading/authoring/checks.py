"""The authoring vocabulary of ``solutions/<name>/checks.py``: questions, cases, references.

A ``checks.py`` creates one :class:`Checks` object (conventionally ``CHECKS``) and registers
questions on it with the :meth:`Checks.value` and :meth:`Checks.function` decorators. The
decorated function is the trusted REFERENCE: it runs in the grader (and in ``course release``
for the public cases), never in a student's process. See ``docs/instructors/authoring.md``.
"""

from __future__ import annotations

import hashlib
import importlib.util
import re
import sys
import types
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from course.grading.authoring.secret import Secret
from course.grading.codec import Band, decode, encode
from course.grading.compare import binomial_band
from course.grading.tripwire import resolve
from course.grading.vocabulary import DEMO_STUDENT_ID, QuestionKind

__all__ = [
    "DEMO_STUDENT_ID",
    "Band",
    "Case",
    "Checks",
    "Mistake",
    "Question",
    "binomial_band",
    "load_checks",
    "student_rng",
    "student_seed",
]


_QID = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,30}$")
_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_NAME = re.compile(r"^[0-9A-Za-z][0-9A-Za-z_.-]*$")


def student_rng(
    assignment: str, key: str, student_id: str, secret: Secret | None = None
) -> np.random.Generator:
    """The random generator of one student's data set ``key`` of ``assignment``.

    Without ``secret`` (self-learners): seeded with the first 128 bits of
    ``sha256(assignment NUL key NUL student_id)``, so anyone with the ID rebuilds the data.
    With the instructor's :class:`~course.grading.authoring.secret.Secret`: seeded with
    ``HMAC-SHA256(secret, ...)``, which nothing in the student distribution determines.
    Surrounding whitespace of the ID is ignored; the seed is the same on every machine and in
    every process (Python's ``hash`` is salted per process and is never used).
    """
    return np.random.default_rng(student_seed(assignment, key, student_id, secret))


def student_seed(assignment: str, key: str, student_id: str, secret: Secret | None = None) -> int:
    """The seed of :func:`student_rng`: a value derived from the key for one student's data
    set, which is all a machine that grades that student needs (a Dask worker is sent this,
    never the key itself)."""
    if secret is not None:
        return secret.seed(assignment, key, student_id)
    text = f"{assignment}\0{key}\0{str(student_id).strip()}".encode()
    return int.from_bytes(hashlib.sha256(text).digest()[:16], "little")


@dataclass(frozen=True)
class Mistake:
    """A plausible wrong answer the feedback recognises and names.

    Parameters
    ----------
    message : str
        What the student reads when the answer matches this mistake (and not the right answer),
        e.g. ``"looks one-sided: z_alpha instead of z_alpha/2"``. Say what went wrong in kind;
        never the right value.
    reference : callable
        Computes the WRONG answer, with the signature of the question's own reference: ``f()``
        or ``f(data)`` for a value question, ``f(*case_args, **case_kwargs)`` for a function
        question. Like the reference it runs in the grader and in ``course release`` (public
        cases: its value ships in ``checks.json``), never in a student's process.
    hint : str, optional
        The hint a student sees when the answer matches this mistake, in the self-check and
        in the grading feedback, instead of the question's staged hint: the hint follows the
        diagnosed mistake. Like every hint it names no value.

    Notes
    -----
    A case whose answer matches a mistake within the question's tolerance scores 0 like any
    other wrong answer; the mistake only changes the message. Automatic diagnostics (shape,
    NaN, sign, a constant factor, transposed, a permutation) need no declaration: declare the
    mistakes that are specific to the method taught. An integer answer (an index, a count) gets
    no relation to the right one, whose message would give it away.

    Examples
    --------
    >>> from scipy.stats import norm
    >>> one_sided = Mistake("looks one-sided: z_alpha instead of z_alpha/2",
    ...                     lambda alpha: norm.isf(alpha))
    >>> one_sided.message
    'looks one-sided: z_alpha instead of z_alpha/2'
    """

    message: str
    reference: Callable
    #: The hint shown when this mistake is diagnosed, instead of the question's next staged
    #: hint (which follows the order of the method, not the mistake); '' keeps the stages.
    hint: str = ""

    def __post_init__(self):
        if not isinstance(self.message, str) or not self.message.strip():
            raise ValueError("Mistake(message, reference): message must be a non-empty string")
        if not callable(self.reference):
            raise ValueError(
                "Mistake(message, reference): reference must be a function computing the wrong "
                "answer, with the signature of the question's reference"
            )
        if not isinstance(self.hint, str):
            raise ValueError("Mistake(message, reference, hint=...): hint must be a string")


def _hint_stages(qid: str, hint) -> tuple[str, ...]:
    """``hint=`` as a tuple of stages: a str is one stage, a sequence of str is staged."""
    if hint is None or hint == "":
        return ()
    if isinstance(hint, str):
        return (hint,)
    try:
        stages = tuple(hint)
    except TypeError:
        raise ValueError(f"{qid}: hint must be a string or a sequence of strings") from None
    if not stages or not all(isinstance(s, str) and s.strip() for s in stages):
        raise ValueError(f"{qid}: hint stages must be non-empty strings")
    return stages


@dataclass
class Case:
    """Arguments of one call of a student's function, public or hidden."""

    args: tuple
    kwargs: dict
    label: str
    hidden: bool


@dataclass
class Question:
    """One graded question (built by :meth:`Checks.value`, :meth:`Checks.function`,
    :meth:`Checks.choice` or :meth:`Checks.short_answer`)."""

    id: str
    kind: str  # a QuestionKind: "value", "function", "choice" or "short_answer"
    target: str  # the variable or function name the student defines ("" for a short answer)
    points: float
    hint: str | tuple  # one stage (str) or staged hints; see ``hints``
    reference: Callable | None
    rtol: float = 1e-7
    atol: float = 1e-9
    data: str | None = None
    public: bool = True
    properties: str | None = None
    forbid: tuple = ()
    timeout: float | None = None
    partial: bool = True
    cases: list = field(default_factory=list)
    mistakes: tuple = ()  # Mistake objects: plausible wrong answers with their messages
    options: tuple = ()  # a choice question's options
    rubric: str = ""  # a short-answer question's marking guide (instructors only)

    @property
    def mistake_hints(self) -> dict[str, str]:
        """The declared mistakes' own hints, by the mistake's message."""
        return {m.message: m.hint for m in self.mistakes if m.hint}

    @property
    def hints(self) -> tuple[str, ...]:
        """The hint stages: after the k-th failed self-check the student sees stage
        ``min(k, len(hints)) - 1`` (a nudge first, the formula only at the last stage)."""
        return _hint_stages(self.id, self.hint)

    def __call__(self, reference: Callable) -> Question:
        """``@CHECKS.short_answer(...)`` on a stub: keeps the stub (e.g. returning a model
        answer for the markers) and returns the question."""
        if self.kind != QuestionKind.SHORT_ANSWER:
            raise TypeError(f"{self.id}: only a short-answer question decorates a function")
        self.reference = reference
        return self

    def case(
        self, *args, label: str | None = None, hidden: bool = False, kwargs: dict | None = None
    ) -> Case:
        """Add a call of the student's function with these arguments (function questions only)."""
        if self.kind != "function":
            raise ValueError(
                f"{self.id}: cases belong to function questions; a value question has one value"
            )
        kwargs = dict(kwargs or {})
        try:
            encode(args), encode(kwargs)
        except TypeError as exc:
            raise ValueError(f"{self.id}: case arguments must be plain data ({exc})") from None
        n_kind = sum(1 for c in self.cases if c.hidden == hidden) + 1
        label = label or f"{'hidden' if hidden else 'public'} case {n_kind}"
        case = Case(tuple(args), kwargs, str(label), bool(hidden))
        self.cases.append(case)
        return case

    @property
    def public_cases(self) -> list:
        return [c for c in self.cases if not c.hidden]

    @property
    def hidden_cases(self) -> list:
        return [c for c in self.cases if c.hidden]

    def expected(self, case: Case | None = None, data: Any = None) -> Any:
        """The reference value (normalised through the plain-data codec)."""
        if self.reference is None:
            raise ValueError(f"{self.id}: a {self.kind} question has no reference value")
        if self.kind == "function":
            assert case is not None, "a function question needs a case"
            value = self.reference(*decode(encode(case.args)), **decode(encode(case.kwargs)))
        elif self.data is not None:
            value = self.reference(data)
        else:
            value = self.reference()
        return decode(encode(value))

    def mistaken(self, case: Case | None = None, data: Any = None) -> list[tuple[str, Any]]:
        """``(message, wrong value)`` of each declared :class:`Mistake` for this case or data
        (normalised through the plain-data codec like :meth:`expected`)."""
        out = []
        for mistake in self.mistakes:
            if self.kind == "function":
                assert case is not None, "a function question needs a case"
                args, kwargs = decode(encode(case.args)), decode(encode(case.kwargs))
                value = mistake.reference(*args, **kwargs)
            elif self.data is not None:
                value = mistake.reference(data)
            else:
                value = mistake.reference()
            out.append((mistake.message, decode(encode(value))))
        return out


class Checks:
    """The questions of one assignment.

    Parameters
    ----------
    name : str
        The assignment name; must match the folder ``solutions/<name>/``.
    title : str, optional
        Shown in feedback.
    data : module, optional
        The assignment's public ``data.py`` module (``from . import data``), whose functions
        ``key(rng)`` make per-student data sets.
    timeout : float
        Default time limit in seconds for each answer cell and each call of a student's function.
    preload : list of str
        Modules imported once before any student code runs (speed only).
    files : list of str
        Extra files of ``solutions/<name>/`` copied verbatim into the release (public!).
    due : str, optional
        The due date, an ISO 8601 date-time with its time zone (``"2026-10-20T23:59+02:00"``);
        ``course grade --due`` overrides it. Changing it changes the checks' digest, so set it
        before the first grading run (or pass ``--due``).
    late_policy : str, optional
        The late policy, e.g. ``"percent-per-day:10,cap:50"`` (see
        :mod:`course.grading.batch.late`); ``course grade --late-policy`` overrides it.
    """

    def __init__(
        self,
        name: str,
        title: str = "",
        data: types.ModuleType | None = None,
        timeout: float = 10.0,
        preload=(),
        files=(),
        due: str | None = None,
        late_policy: str | None = None,
    ):
        if not _NAME.match(str(name)):
            raise ValueError(f"assignment name {name!r}: use letters, digits, '_', '-', '.'")
        self.name = str(name)
        self.title = title or self.name
        self.data_module = data
        self.timeout = float(timeout)
        self.preload = tuple(preload)
        self.files = tuple(files)
        self.due = due
        self.late_policy = late_policy
        self.questions: dict[str, Question] = {}
        self.solution_dir: Path | None = None  # set by load_checks

    # -- decorators --------------------------------------------------------------------
    def _register(self, question: Question) -> Question:
        if not _QID.match(question.id):
            raise ValueError(
                f"question id {question.id!r}: start with a letter; letters, digits, '_'"
            )
        if question.id in self.questions:
            raise ValueError(f"question {question.id!r} is defined twice")
        if question.kind != QuestionKind.SHORT_ANSWER and not _IDENT.match(question.target):
            raise ValueError(f"{question.id}: {question.target!r} is not a Python name")
        if not question.points > 0:
            raise ValueError(f"{question.id}: points must be positive")
        if question.rtol < 0 or question.atol < 0:
            raise ValueError(f"{question.id}: tolerances must be non-negative")
        question.hints  # noqa: B018  (validates hint=)
        if not all(isinstance(m, Mistake) for m in question.mistakes):
            raise ValueError(
                f"{question.id}: mistakes=[Mistake('message', reference), ...] (from "
                "course.grading.authoring.checks import Mistake)"
            )
        for name in question.forbid:
            if "." not in name:
                raise ValueError(
                    f"{question.id}: forbid entries are dotted names such as 'course.lsq.w_tests', got {name!r}"
                )
            target = resolve(name)
            if target is None:
                raise ValueError(f"{question.id}: forbid names {name!r}, which does not exist")
            if not callable(target) or not hasattr(target, "__name__"):
                raise ValueError(
                    f"{question.id}: forbid lists functions and classes (a call is what counts), "
                    f"but {name!r} is {type(target).__name__}"
                )
        if question.data is not None and (
            self.data_module is None or not callable(getattr(self.data_module, question.data, None))
        ):
            raise ValueError(
                f"{question.id}: data={question.data!r} needs a function {question.data}(rng) in data.py "
                "and Checks(..., data=data)"
            )
        if question.properties is not None and (
            self.data_module is None
            or not callable(getattr(self.data_module, question.properties, None))
        ):
            raise ValueError(
                f"{question.id}: properties={question.properties!r} is not a function in data.py"
            )
        self.questions[question.id] = question
        return question

    def value(
        self,
        qid: str,
        *,
        var: str,
        points: float,
        hint: str | Sequence[str] = "",
        rtol: float = 1e-7,
        atol: float = 1e-9,
        data: str | None = None,
        public: bool = True,
        properties: str | None = None,
        forbid=(),
        timeout: float | None = None,
        partial: bool = True,
        mistakes: Sequence[Mistake] = (),
    ):
        """Register a question whose answer is the variable ``var``; decorate its reference.

        ``hint`` is one string, or a sequence of strings shown in stages (a nudge after the
        first failed self-check, the next stage after the next failure, ..., the formula last).
        ``mistakes`` lists :class:`Mistake` objects: plausible wrong answers, computed like the
        reference (``f()``, or ``f(data)`` with ``data=``), whose message the feedback shows
        when the answer matches one of them.
        """

        def decorator(reference):
            return self._register(
                Question(
                    id=qid,
                    kind="value",
                    target=var,
                    points=float(points),
                    hint=hint if isinstance(hint, str) else tuple(hint),
                    reference=reference,
                    rtol=float(rtol),
                    atol=float(atol),
                    data=data,
                    public=bool(public) and data is None,
                    properties=properties,
                    forbid=tuple(forbid),
                    timeout=timeout,
                    partial=partial,
                    mistakes=tuple(mistakes),
                )
            )

        return decorator

    def function(
        self,
        qid: str,
        *,
        func: str,
        points: float,
        hint: str | Sequence[str] = "",
        rtol: float = 1e-7,
        atol: float = 1e-9,
        forbid=(),
        timeout: float | None = None,
        partial: bool = True,
        mistakes: Sequence[Mistake] = (),
    ):
        """Register a question whose answer is the function ``func``; decorate its reference.

        ``hint`` and ``mistakes`` as in :meth:`value`; a mistake's reference takes the case's
        arguments, like the question's reference.
        """

        def decorator(reference):
            return self._register(
                Question(
                    id=qid,
                    kind="function",
                    target=func,
                    points=float(points),
                    hint=hint if isinstance(hint, str) else tuple(hint),
                    reference=reference,
                    rtol=float(rtol),
                    atol=float(atol),
                    forbid=tuple(forbid),
                    timeout=timeout,
                    partial=partial,
                    mistakes=tuple(mistakes),
                )
            )

        return decorator

    def choice(
        self,
        qid: str,
        *,
        var: str,
        options,
        points: float,
        hint: str = "",
        data: str | None = None,
        timeout: float | None = None,
    ):
        """Register a multiple-choice question; decorate the reference returning the right option.

        The student sets ``var`` to one of ``options`` (strings or numbers; strings match
        ignoring case and surrounding spaces, numbers by value). The public self-check says only
        whether the answer is one of the options, never whether it is right; ``course grade``
        gives full ``points`` when it is a right option and 0 otherwise.

        Parameters
        ----------
        qid : str
            The question id (``"q6b"``); its header and answer cell name it.
        var : str
            The variable the answer cell assigns (``verdict = "reject"``).
        options : sequence of str or numbers
            At least two distinct options, shown in the self-check (public).
        points : float
            Points for a right option.
        hint : str, optional
            Shown when the answer is not one of the options.
        data : str, optional
            A per-student data set: the reference is then ``f(d)`` for the student's data.
        timeout : float, optional
            Time limit of the answer cell in seconds.

        Notes
        -----
        The reference returns the right option, or a list of options that are all accepted
        (two wordings of one idea). A reference returning something that is not an option
        fails ``course release``. For a numeric item whose value stays private, use
        :meth:`value` with ``public=False``.

        Examples
        --------
        >>> checks = Checks("00_demo")
        >>> @checks.choice("q1", var="verdict", options=["accept", "reject"], points=1)
        ... def q1():
        ...     return "reject"
        >>> checks.questions["q1"].options
        ('accept', 'reject')
        """
        from course.grading.items import check_options

        opts = check_options(qid, options)

        def decorator(reference):
            return self._register(
                Question(
                    id=qid,
                    kind=QuestionKind.CHOICE,
                    target=var,
                    points=float(points),
                    hint=hint,
                    reference=reference,
                    data=data,
                    public=False,
                    timeout=timeout,
                    partial=False,
                    options=opts,
                )
            )

        return decorator

    def short_answer(self, qid: str, *, points: float, rubric: str = "", hint: str = ""):
        """Register a short-answer question, marked by the instructor; returns the question.

        The student writes a few sentences in the question's markdown answer cell (in the
        solution notebook: a markdown cell with ``metadata.course = {"role": "answer",
        "question": qid}``, see :func:`course.grading.authoring.notebooks.short_answer_cell`; its text
        is the model answer and never ships). ``course grade`` scores it "to mark" (0 points)
        and writes every answer, with ``rubric`` and blank points/comment columns, into
        ``OUT/short_answers.csv``; ``course grade ... --short-answers FILE`` merges the filled
        file into the grades and the feedback.

        Parameters
        ----------
        qid : str
            The question id.
        points : float
            The most points a marker may give.
        rubric : str, optional
            What a full answer says (instructors and markers only; never released).
        hint : str, optional
            Shown to the student in the feedback when the answer did not get full points.

        Notes
        -----
        Works as a plain call or as a decorator on a stub (its return value is ignored by the
        grader; it may return the model answer for your own reference).

        Examples
        --------
        >>> checks = Checks("00_demo")
        >>> q = checks.short_answer("q2", points=1, rubric="names the dof; says why")
        >>> str(q.kind), q.points
        ('short_answer', 1.0)
        """
        return self._register(
            Question(
                id=qid,
                kind=QuestionKind.SHORT_ANSWER,
                target="",
                points=float(points),
                hint=hint,
                reference=None,
                public=False,
                partial=True,
                rubric=str(rubric),
            )
        )

    # -- helpers -----------------------------------------------------------------------
    @property
    def max_points(self) -> float:
        return float(sum(q.points for q in self.questions.values()))

    def data_keys(self) -> list[str]:
        return sorted({q.data for q in self.questions.values() if q.data is not None})

    def data_for(self, key: str, student_id: str, secret: Secret | None = None) -> Any:
        """The per-student data set ``key`` for ``student_id`` (plain data), drawn with the
        instructor's ``secret`` when one is given (see :func:`student_rng`)."""
        return self.data_from_seed(key, student_seed(self.name, key, student_id, secret))

    def data_from_seed(self, key: str, seed: int) -> Any:
        """The data set ``key`` drawn from ``seed`` (a :func:`student_seed`), as plain data."""
        func = getattr(self.data_module, key)
        return decode(encode(func(np.random.default_rng(seed))))

    def validate(self) -> None:
        """Check the question set for authoring mistakes (raises ValueError)."""
        if not self.questions:
            raise ValueError(f"{self.name}: checks.py defines no questions")
        for q in self.questions.values():
            if q.kind == "function" and not q.public_cases:
                raise ValueError(
                    f"{q.id}: a function question needs at least one public case (q.case(...))"
                )


def _safe_module_name(path: Path) -> str:
    digest = hashlib.sha256(str(path.resolve()).encode()).hexdigest()[:12]
    return f"_course_assignment_{re.sub(r'[^0-9A-Za-z_]', '_', path.name)}_{digest}"


def load_checks(solution_dir: str | Path) -> Checks:
    """Import ``solution_dir/checks.py`` (as part of a private package, so ``from . import data``
    works) and return its :class:`Checks` object."""
    solution_dir = Path(solution_dir).resolve()
    checks_file = solution_dir / "checks.py"
    if not checks_file.is_file():
        raise FileNotFoundError(f"{checks_file} does not exist: every assignment needs a checks.py")
    pkg_name = _safe_module_name(solution_dir)
    # a snapshot: another thread (a grader, a test) may import meanwhile
    for mod in [m for m in list(sys.modules) if m == pkg_name or m.startswith(pkg_name + ".")]:
        del sys.modules[mod]
    package = types.ModuleType(pkg_name)
    package.__path__ = [str(solution_dir)]
    package.__package__ = pkg_name
    sys.modules[pkg_name] = package
    spec = importlib.util.spec_from_file_location(f"{pkg_name}.checks", checks_file)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    _exec_without_bytecode(spec, module)
    found = [v for v in vars(module).values() if isinstance(v, Checks)]
    chosen = getattr(module, "CHECKS", None)
    if not isinstance(chosen, Checks):
        if len(found) != 1:
            raise ValueError(
                f"{checks_file}: define exactly one Checks object (conventionally CHECKS)"
            )
        chosen = found[0]
    if chosen.name != solution_dir.name:
        raise ValueError(
            f"{checks_file}: Checks name {chosen.name!r} differs from the folder name {solution_dir.name!r}"
        )
    chosen.validate()
    chosen.solution_dir = solution_dir
    return chosen


def load_data_module(path: str | Path, assignment: str) -> types.ModuleType:
    """Import a public ``data.py`` file under a private name (used by the self-check)."""
    path = Path(path).resolve()
    name = f"_course_data_{re.sub(r'[^0-9A-Za-z_]', '_', assignment)}"
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None
    module = importlib.util.module_from_spec(spec)
    _exec_without_bytecode(spec, module)
    return module


def _exec_without_bytecode(spec, module) -> None:
    """Execute a module without leaving __pycache__ folders in solutions/ or exercises/."""
    previous = sys.dont_write_bytecode
    sys.dont_write_bytecode = True
    try:
        spec.loader.exec_module(module)
    finally:
        sys.dont_write_bytecode = previous
