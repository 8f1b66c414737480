"""Choice and short-answer questions: what the self-check, the grader and the release share.

A *choice* question (``CHECKS.choice``) asks the student to set a variable to one of a few
options (``"accept"``/``"reject"``, ``"A"``–``"D"``, or numbers). The self-check only says
whether the answer IS one of the options, never whether it is right; the grader compares it
with the reference's option(s).

A *short-answer* question (``CHECKS.short_answer``) is a markdown answer cell that the
instructor marks: ``course grade`` exports every answer with the rubric into a CSV
(:mod:`course.grading.batch.marks`) and merges the filled CSV back into the grades.
"""

from __future__ import annotations

import contextlib
import math
from typing import Any

from course.grading.compare import Verdict
from course.grading.vocabulary import MistakeKind, QuestionKind, answer_cell_id

__all__ = [
    "ITEM_KINDS",
    "SHORT_ANSWER_STUB",
    "AnswerCells",
    "check_options",
    "choice_verdict",
    "is_unanswered_text",
    "match_option",
    "option_text",
    "right_options",
    "self_check_item",
]

#: Question kinds that are not computed answers (checked by :func:`self_check_item`).
ITEM_KINDS = (QuestionKind.CHOICE, QuestionKind.SHORT_ANSWER)

#: The released text of a short-answer cell, until the student replaces it.
SHORT_ANSWER_STUB = "*Your answer here: replace this line with a few sentences.*"


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _key(x: Any):
    """The comparison key of an option or answer: strings ignore case and surrounding
    spaces, numbers compare by value (``2 == 2.0``), bools stay bools."""
    if isinstance(x, str):
        return ("s", " ".join(x.split()).casefold())
    if isinstance(x, bool):
        return ("b", x)
    if _is_number(x):
        return ("n", float(x))
    return None


def check_options(qid: str, options) -> tuple:
    """The options of a choice question as a tuple; ValueError when they are not 2 or more
    distinct strings or numbers."""
    if isinstance(options, (str, bytes)) or not hasattr(options, "__iter__"):
        raise ValueError(f"{qid}: options must be a list of strings or numbers, got {options!r}")
    out = []
    for opt in options:
        if hasattr(opt, "item") and callable(opt.item):  # numpy scalars
            opt = opt.item()
        if _key(opt) is None or (_is_number(opt) and not math.isfinite(opt)):
            raise ValueError(f"{qid}: option {opt!r} is not a string or a finite number")
        if isinstance(opt, str) and not opt.strip():
            raise ValueError(f"{qid}: an option is empty")
        out.append(opt)
    if len(out) < 2:
        raise ValueError(f"{qid}: a choice question needs at least 2 options, got {len(out)}")
    keys = [_key(o) for o in out]
    if len(set(keys)) != len(keys):
        raise ValueError(f"{qid}: options must differ (case and spaces ignored): {out!r}")
    return tuple(out)


def match_option(options, answer) -> int | None:
    """The index of the option ``answer`` names (case and spaces ignored), or None."""
    if hasattr(answer, "item") and callable(answer.item) and getattr(answer, "ndim", 1) == 0:
        answer = answer.item()
    key = _key(answer)
    if key is None:
        return None
    for i, opt in enumerate(options):
        if _key(opt) == key:
            return i
    return None


def right_options(qid: str, options, reference_value) -> set[int]:
    """The indices of the right options: the reference returns one option, or a list (or
    tuple, set) of options each of which is accepted."""
    values = (
        list(reference_value)
        if isinstance(reference_value, (list, tuple, set, frozenset))
        else [reference_value]
    )
    out = set()
    for v in values:
        i = match_option(options, v)
        if i is None:
            raise ValueError(f"{qid}: the reference returns {v!r}, which is not an option")
        out.add(i)
    if not out:
        raise ValueError(f"{qid}: the reference returns no option")
    return out


def option_text(options) -> str:
    return ", ".join(repr(o) for o in options)


def choice_verdict(qid: str, options, reference_value, answer) -> Verdict:
    """The verdict on a student's ``answer`` (its kind: not an option, or another option); the
    message never names the right option."""
    i = match_option(options, answer)
    if i is None:
        text = f"{answer!r} is not one of the options ({option_text(options)})"
        return Verdict(False, text, text, MistakeKind.NOT_AN_OPTION)
    if i in right_options(qid, options, reference_value):
        return Verdict(True)
    text = f"{options[i]!r} is not the right option"
    return Verdict(False, text, text, MistakeKind.WRONG_OPTION)


def is_unanswered_text(text: str | None) -> bool:
    """True when a short-answer cell is empty or still holds the release's stub."""
    if text is None:
        return True
    stripped = text.strip()
    return not stripped or stripped == SHORT_ANSWER_STUB


def self_check_item(q, got, missing, saved_text: str | None = None) -> None:
    """The self-check of a choice or short-answer question (prints; never says right/wrong).

    ``q`` is a :class:`~course.grading.vocabulary.PublicQuestion`, ``got`` the student's value
    of ``q.target`` or ``missing`` when the notebook has none. ``saved_text`` is a short
    answer's cell as the saved notebook holds it (None when the notebook was not found): the
    message says whether it is still the placeholder, not "replace it" to a student who did.
    """
    from course.grading.codec import decode

    points = f"{q.points:g} point{'s' if q.points != 1 else ''}"
    if q.kind == QuestionKind.SHORT_ANSWER:
        cell = f"the markdown cell below the question (cell id {answer_cell_id(q.id)!r})"
        print(f"{q.id} ({points}): short answer")
        if saved_text is None:
            where = f"  Your answer goes in {cell}."
        elif is_unanswered_text(saved_text):
            where = (
                f"  not answered yet: {cell} still holds its placeholder line in the saved "
                "notebook; write your answer there (and save)."
            )
        else:
            where = f"  Answered: {cell} holds your text in the saved notebook."
        print(f"{where} Your instructor marks it after grading; there is nothing to check here.")
        return
    options = decode(q.options or [])
    print(f"{q.id} ({points}): choice {q.target}, one of {option_text(options)}")
    if got is missing:
        print(f"  not answered yet: no variable {q.target} (run your answer cell first)")
        return
    if got is Ellipsis:
        print(f"  not answered yet: {q.target} is still ...")
        return
    if match_option(options, got) is None:
        print(f"  FAIL: {got!r} is not one of the options ({option_text(options)})")
        if q.hints:  # the first stage: a choice is never right or wrong here
            print(f"      Hint: {q.hints[0]}")
        return
    print(
        f"  OK: {got!r} is one of the options. Whether it is the right one is checked only at "
        "grading (the self-check never tells)."
    )


class AnswerCells:
    """Which notebook cell last set each answer, as the kernel saw it run.

    JupyterLab (and VS Code) tell the kernel the id of every cell they run; a question's answer
    belongs in the cell ``<qid>-answer``. The grader finds answers by that id, so a self-check
    notes when an answer was set in another cell (typically: the answer cell was deleted and
    the answer retyped in a new one). Only object identities of the answers' names are
    compared before and after each cell: nothing is copied.
    """

    _active: AnswerCells | None = None  # one per kernel: re-running the setup cell replaces it

    def __init__(self, targets: dict[str, str]):
        self.targets = dict(targets)  # name -> question
        self.set_in: dict[str, str] = {}
        self._before: dict[str, int] = {}
        self._cell: str | None = None
        self._shell: Any = None

    @classmethod
    def install(cls, targets: dict[str, str]) -> AnswerCells:
        watcher = cls(targets)
        try:
            from IPython import get_ipython
        except ImportError:  # pragma: no cover - IPython is a dependency
            return watcher
        shell = get_ipython()
        if shell is None:
            return watcher
        old = cls._active
        if old is not None and old._shell is not None:
            for event, callback in (("pre_run_cell", old._pre), ("post_run_cell", old._post)):
                with contextlib.suppress(ValueError):
                    old._shell.events.unregister(event, callback)
        watcher._shell = shell
        shell.events.register("pre_run_cell", watcher._pre)
        shell.events.register("post_run_cell", watcher._post)
        cls._active = watcher
        return watcher

    def _pre(self, info=None) -> None:
        ns = self._shell.user_ns
        self._cell = getattr(info, "cell_id", None)
        self._before = {name: id(ns.get(name, _UNSET)) for name in self.targets}

    def _post(self, result=None) -> None:
        if not self._cell:
            return  # this front end does not say which cell ran
        ns = self._shell.user_ns
        for name in self.targets:
            if name in ns and id(ns[name]) != self._before.get(name):
                self.set_in[name] = self._cell

    def note(self, qid: str, name: str) -> str | None:
        """A note when ``name`` (the answer of ``qid``) was last set outside its answer cell."""
        cell = self.set_in.get(name)
        if not name or cell is None or cell == answer_cell_id(qid):
            return None
        return (
            f"  Note: {name} was last set in a cell that is not the answer cell of {qid} "
            f"(id {answer_cell_id(qid)!r}). If you deleted that cell, undo it (Edit → Undo "
            "Cell Operation, or z), or keep the answer where it is: the grader then grades the "
            "cell that sets it, and tells your instructor that the answer cell is missing."
        )


_UNSET = object()
