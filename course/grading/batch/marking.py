"""``course mark``: marking the short answers in Jupyter, one answer at a time.

:class:`MarkingView` is an ipywidgets view of the short answers of a grading output folder, as
the term's record holds them (``OUT/record.sqlite``, :mod:`course.grading.batch.record`; written
by ``course grade``). It shows one answer of one short-answer question at a time, with the
question's rubric and points, a points box (a number between 0 and the question's points;
``1.5`` or ``1,5``) and a comment box for the student. Every mark is written into the record at
once, with the marker and the time, and the marking file ``OUT/short_answers.csv`` (its export,
:mod:`course.grading.batch.marks`) is rewritten from it; the next ``course grade`` run merges
the marks into the grades, feedback and LMS files. Two views of one folder (two markers at
once) lose no mark: each writes only its own mark, in a transaction, and each shows the other's
marks as it moves on. Where the instructor stopped is kept in ``OUT/marking_progress.json``.

The view is anonymous by default: it shows *answer 3 of 12*, not the student's ID (a check box
shows the IDs). Answers come grouped: identical answers (the same text up to case, whitespace
and punctuation) and near-identical ones form a group (:mod:`course.grading.batch.answergroups`),
the largest group first; within a group, in the order of a digest of the text, not of the
roster, so the position does not give the student away either. The view says how large the
answer's group is, lists its other texts, and *mark the group* gives the answer's mark to the
group's members (:meth:`MarkingView.mark_group`: members marked on their own keep their mark).
Answers are shown as plain text (a student's HTML is never run in the instructor's browser).

``course mark OUT`` writes ``OUT/marking.ipynb``, a notebook whose one cell shows the view, and
opens it in JupyterLab (:func:`write_marking_notebook`). The view needs ipywidgets (the
``notebooks`` extra); the record and :class:`MarkingFile` do not.
"""

from __future__ import annotations

import html
import json
from dataclasses import dataclass, replace
from pathlib import Path

from course.grading.batch.answergroups import group
from course.grading.batch.marks import (
    COLUMNS,
    SHORT_ANSWERS_FILE,
    MarksError,
    export_short_answers,
    parse_points,
    read_marking_file,
)
from course.grading.batch.record import RECORD_FILE, Record
from course.grading.vocabulary import visible_text

__all__ = [
    "NOTEBOOK_FILE",
    "PROGRESS_FILE",
    "Answer",
    "MarkingFile",
    "MarkingView",
    "write_marking_notebook",
]

PROGRESS_FILE = "marking_progress.json"
NOTEBOOK_FILE = "marking.ipynb"


def _unquote(text: str | None) -> str:
    """A cell as the marker reads it (without the spreadsheet guard of ``csv_text``)."""
    text = (text or "").strip()
    return text[1:] if text.startswith("'") and text[1:2] in ("=", "+", "-", "@") else text


def _fmt(x: float) -> str:
    return f"{round(float(x), 4):g}"


@dataclass(frozen=True)
class Answer:
    """One row of the marking file: a student's answer to a question and its mark so far
    (``points`` None: not marked yet)."""

    student: str
    question: str
    text: str
    points_possible: float
    rubric: str
    answer_id: str
    points: float | None
    comment: str

    @property
    def marked(self) -> bool:
        return self.points is not None

    @property
    def key(self) -> tuple[str, str]:
        return (self.student, self.question)


class MarkingFile:
    """The answers to mark of the grading output folder ``out_dir`` and their marks, in the
    term's record (:mod:`course.grading.batch.record`); :meth:`mark` writes one mark into the
    record (and the marking file, its export) at once.

    ``answers`` are ordered by question (as in the file), then by a digest of the answer's text
    (``answer_id``), then by student. Two marking views of one folder (two markers) each write
    only the mark given, in a transaction: neither loses the other's. ``marker`` names who
    marks (default: ``COURSE_MARKER``, else the login name), kept with every mark.

    A folder with a marking file and no record (written by an older version, or by hand) is
    imported into the record once; a row that cannot be imported is listed in
    :attr:`refused` with its line number, and every other row is.
    """

    def __init__(self, out_dir: str | Path, marker: str | None = None):
        self.out = Path(out_dir).resolve()  # the messages name it: "." would say nothing
        self.path = self.out / SHORT_ANSWERS_FILE
        if not (self.out / RECORD_FILE).is_file() and not self.path.is_file():
            raise MarksError(
                f"{self.path} does not exist: `course grade NAME SUBMISSIONS --out {self.out}` "
                "writes it for an assignment with short-answer questions"
            )
        self.record = Record(self.out, who=marker)
        #: rows of a marking file imported without a record that could not be ("line 3: ...")
        self.refused: list[str] = []
        if not self.record.has_answers() and self.path.is_file():
            self.refused = _import_marking_file(self.record, self.path)
        self.answers: list[Answer] = []
        self.reload()

    def reload(self) -> None:
        """Read the record again (marks given in another view, a rerun of ``course grade``)."""
        answers = [
            Answer(
                student=a["student"],
                question=a["question"],
                text=a["text"],
                points_possible=float(a["points_possible"]),
                rubric=a["rubric"],
                answer_id=a["answer_id"],
                points=None if a["points"] is None else float(a["points"]),
                comment=a["comment"],
            )
            for a in self.record.answers()
        ]
        order = {q: i for i, q in enumerate(dict.fromkeys(a.question for a in answers))}
        self.answers = sorted(answers, key=lambda a: (order[a.question], a.answer_id, a.student))

    @property
    def questions(self) -> list[str]:
        """The questions with answers to mark, in the file's order."""
        return list(dict.fromkeys(a.question for a in self.answers))

    def of(self, question: str) -> list[Answer]:
        """The answers to ``question``, in marking order."""
        return [a for a in self.answers if a.question == question]

    def find(self, key: tuple[str, str]) -> Answer | None:
        return next((a for a in self.answers if a.key == key), None)

    def mark(self, answer: Answer, points: str, comment: str = "") -> Answer:
        """Give ``answer`` the ``points`` typed (blank: not marked) and ``comment``, and write
        them into the record (then the marking file); returns the answer as marked.

        :class:`MarksError` (and nothing written) for points that are not a number between 0
        and the question's points, a comment without points (the import would refuse it), or
        an answer that is no longer the one to mark (``course grade`` graded a changed
        answer since).
        """
        value = parse_points(points, answer.points_possible)
        comment = comment.strip()
        if value is None and comment:
            raise MarksError("a comment needs points (0 is fine): give the points to save it")
        try:
            self.record.set_mark(answer.student, answer.question, answer.answer_id, value, comment)
        except ValueError:
            raise MarksError(
                f"this answer is no longer in {self.record.path} (the student's answer changed "
                "and `course grade` graded it again): reload the view"
            ) from None
        self._export()
        self.reload()
        return self.find(answer.key) or replace(answer, points=value, comment=comment)

    def _export(self) -> None:
        """The marking file, rewritten from the record unless it holds a spreadsheet's marks
        never imported (``course grade --short-answers`` imports them; the record has the
        view's marks either way)."""
        export_short_answers(self.record, self.path)


def _import_marking_file(record: Record, path: Path) -> list[str]:
    """Put the answers and marks of a marking file into a record that has none; returns the
    rows refused ("line N: why"), every other row imported."""
    header, rows = read_marking_file(path)
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise MarksError(
            f"{path}: no column {', '.join(missing)}; rerun `course grade` for a fresh marking file"
        )
    answers, marks, refused = [], [], []
    for line, r in rows:
        if "__error__" in r:
            refused.append(f"line {line}: not a row of the marking file ({r['__error__']})")
            continue
        try:
            top = float(r["points_possible"])
        except ValueError:
            refused.append(f"line {line}: points_possible {r['points_possible']!r} is no number")
            continue
        answer: dict = {
            "student": _unquote(r["student"]),
            "question": _unquote(r["question"]),
            "answer_id": (r["answer_id"] or "").strip(),
            "text": _unquote(r["answer"]),
            "points_possible": top,
            "rubric": _unquote(r["rubric"]),
        }
        answers.append(answer)
        try:
            points = parse_points(r.get("points") or "", top)
        except MarksError as exc:
            refused.append(f"line {line}: {exc}")
            continue
        if points is not None:
            marks.append((answer, points, _unquote(r.get("comment"))))
    record.set_answers(answers)
    who = f"{record.who} (imported {path.name})"
    for a, points, comment in marks:
        record.set_mark(a["student"], a["question"], a["answer_id"], points, comment, who)
    return refused


#: what the view tells the marker about the keyboard (Jupyter's own shortcuts do not reach the
#: boxes: a widget's input keeps its keys)
KEYS = (
    "Keyboard: type the points, <kbd>Enter</kbd> saves and goes to the next unmarked answer; "
    "<kbd>Tab</kbd> goes on to the comment box and the buttons (<kbd>Shift</kbd>+<kbd>Tab</kbd> "
    "back), <kbd>Enter</kbd> presses the button in focus: points, "
    "<kbd>Tab</kbd>, <kbd>Tab</kbd>, <kbd>Enter</kbd> marks the whole group."
)
#: how many of a group's other texts the view lists
_LISTED = 8


def _box(text: str, css: str) -> str:
    """Student text as inert HTML: escaped, its lines kept, every other control character
    (an escape sequence, a bell, a bidirectional override) shown as an escape."""
    style = "white-space: pre-wrap; border-left: 3px solid #999; padding: 0.2em 0.7em"
    shown = "\n".join(visible_text(line) for line in text.split("\n"))
    return f'<div class="{css}" style="{style}">{html.escape(shown, quote=False)}</div>'


class MarkingView:
    """The marking view of the grading output folder ``out_dir``, shown by a notebook cell.

    Parameters
    ----------
    out_dir : str or Path
        The ``--out`` folder of ``course grade`` (it holds ``record.sqlite``).
    question : str, optional
        The question to start with; default: where marking stopped last time, else the first
        answer not marked yet.
    anonymous : bool, default True
        Hide the students' IDs (the *show IDs* check box shows them).
    marker : str, optional
        Who marks, kept with every mark (default: ``COURSE_MARKER``, else the login name).

    Notes
    -----
    A mark is saved when the points or the comment box is left (Enter, Tab or a click
    elsewhere): into the record (and ``short_answers.csv``) at once. Enter after typing points
    saves and goes to the next unmarked answer. Leaving an answer whose boxes hold something
    that cannot be saved (points out of range, a comment without points) is refused with the
    reason, so nothing typed is lost or silently changed. *Next unmarked* goes to the next
    answer without points, in this question first, then in the others.

    *Mark the group* (:meth:`mark_group`) gives the answer's points and comment to the other
    members of its group (:func:`course.grading.batch.answergroups.group`) that are not marked
    yet or still hold the mark this answer had when you came to it (they followed it), then
    goes to the next unmarked answer. A member marked otherwise was marked on its own (an
    override): it keeps its mark, and the status says how many did. So marking a group again
    with a changed mark moves the members that had its old mark and never an override.

    Examples
    --------
    In a notebook, ``MarkingView("grades/03")`` as the cell's last line shows the view
    (``course mark grades/03`` writes such a notebook). Here, a marking file of one answer:

    >>> import csv, tempfile
    >>> from course.grading.batch.marks import COLUMNS, answer_id
    >>> tmp = tempfile.TemporaryDirectory()
    >>> out = Path(tmp.name)
    >>> text = "Because T exceeds its critical value."
    >>> row = ["s1", "q3", text, "2", "", "names the critical value", "", answer_id(text)]
    >>> with open(out / "short_answers.csv", "w", newline="") as f:
    ...     csv.writer(f, lineterminator="\\n").writerows([COLUMNS, row])
    >>> view = MarkingView(out)
    >>> view.current.student, view.current.marked, "s1" in view.heading.value
    ('s1', False, False)
    >>> view.points.value = "1,5"  # what the points box sends when the marker leaves it
    >>> view.current.points, (out / "short_answers.csv").read_text().splitlines()[1]
    (1.5, 's1,q3,Because T exceeds its critical value.,2,1.5,names the critical value,,...')
    >>> view.points.value = "3"  # more than the question's points: refused, nothing written
    >>> view.current.points, "give between 0 and 2" in view.status.value
    (1.5, True)
    >>> tmp.cleanup()
    """

    def __init__(
        self,
        out_dir: str | Path,
        question: str | None = None,
        anonymous: bool = True,
        marker: str | None = None,
    ) -> None:
        import ipywidgets as widgets

        self.file = MarkingFile(out_dir, marker)
        self.progress_path = self.file.out / PROGRESS_FILE
        if question is not None and question not in self.file.questions:
            raise ValueError(
                f"question={question!r}: no answers to mark for it in {self.file.path} "
                f"(questions with answers: {', '.join(self.file.questions) or 'none'})"
            )
        self._loading = False
        layout = widgets.Layout(width="100%")
        self.question = widgets.Dropdown(options=self.file.questions, description="question")
        self.show_ids = widgets.Checkbox(value=not anonymous, description="show IDs", indent=False)
        self.heading = widgets.HTML()
        self.answer = widgets.HTML(layout=layout)
        self.rubric = widgets.HTML(layout=layout)
        self.points = widgets.Text(description="points", continuous_update=False)
        self.comment = widgets.Textarea(
            description="comment",
            placeholder="shown to the student in the feedback (optional)",
            continuous_update=False,
            layout=widgets.Layout(width="100%", height="5em"),
        )
        self.group_info = widgets.HTML(layout=layout)
        self.status = widgets.HTML()
        self.counts = widgets.HTML()
        self.keys = widgets.HTML(KEYS)
        self.group_button = widgets.Button(description="mark the group")
        self.previous_button = widgets.Button(description="◀ previous")
        self.next_button = widgets.Button(description="next ▶")
        self.unmarked_button = widgets.Button(description="next unmarked", button_style="primary")
        for name in (
            "question",
            "show_ids",
            "heading",
            "answer",
            "rubric",
            "group_info",
            "points",
            "comment",
            "status",
            "counts",
            "keys",
        ):
            getattr(self, name).add_class(f"course-marking-{name.replace('_', '-')}")
        for name, button in (
            ("mark-group", self.group_button),
            ("previous", self.previous_button),
            ("next", self.next_button),
            ("next-unmarked", self.unmarked_button),
        ):
            button.add_class(f"course-marking-{name}")
        self.widget = widgets.VBox(
            [
                widgets.HBox([self.question, self.show_ids]),
                self.heading,
                self.answer,
                self.group_info,
                self.rubric,
                self.points,
                self.comment,
                widgets.HBox(
                    [
                        self.group_button,
                        self.previous_button,
                        self.next_button,
                        self.unmarked_button,
                    ]
                ),
                self.status,
                self.counts,
                self.keys,
            ],
            layout=layout,
        )
        self.widget.add_class("course-marking")
        self.previous_button.on_click(lambda _: self.previous())
        self.next_button.on_click(lambda _: self.next())
        self.unmarked_button.on_click(lambda _: self.next_unmarked())
        self.group_button.on_click(lambda _: self.mark_group())
        self.points.on_msg(self._points_message)
        self.points.observe(self._points_edited, names="value")
        self.comment.observe(self._edited, names="value")
        self.show_ids.observe(lambda _: self._show(), names="value")
        self.question.observe(self._question_chosen, names="value")
        self.current: Answer | None = None
        self._arrived: tuple[float, str] | None = None  # the mark of the answer shown, on arrival
        self._enter: tuple[str, str] | None = None  # Enter pressed in the points box of this answer
        self._groups: dict[str, tuple[tuple, list[list[tuple[str, str]]]]] = {}
        self._start(question)

    # -- what the notebook shows -----------------------------------------------------------
    def _repr_mimebundle_(self, **kwargs):
        return self.widget._repr_mimebundle_(**kwargs)

    # -- navigation ------------------------------------------------------------------------
    @property
    def answers(self) -> list[Answer]:
        """The answers of the question shown, in marking order (group by group)."""
        return self._ordered(self.question.value) if self.question.value else []

    def groups(self, question: str) -> list[list[Answer]]:
        """The groups of identical and near-identical answers to ``question``, largest first
        (:func:`course.grading.batch.answergroups.group` of its answers in digest order)."""
        answers = self.file.of(question)
        stamp = tuple((a.key, a.answer_id) for a in answers)
        cached = self._groups.get(question)
        if cached is None or cached[0] != stamp:  # grouped once per set of answers
            keys = [[answers[i].key for i in g] for g in group([a.text for a in answers])]
            cached = self._groups[question] = (stamp, keys)
        by_key = {a.key: a for a in answers}
        return [[by_key[k] for k in g] for g in cached[1]]

    def group_of(self, answer: Answer) -> list[Answer]:
        """The group of ``answer`` (itself included)."""
        return next(g for g in self.groups(answer.question) if answer.key in {b.key for b in g})

    def _ordered(self, question: str) -> list[Answer]:
        return [a for g in self.groups(question) for a in g]

    @property
    def index(self) -> int:
        """The position of the answer shown among its question's answers (0-based)."""
        keys = [a.key for a in self.answers]
        return keys.index(self.current.key) if self.current is not None else 0

    def previous(self) -> bool:
        """Show the previous answer of this question; False when there is none or the answer
        shown holds edits that cannot be saved."""
        i = self.index
        return i > 0 and self.go(self.answers[i - 1])

    def next(self) -> bool:
        """Show the next answer of this question (False as :meth:`previous`)."""
        i = self.index
        return i + 1 < len(self.answers) and self.go(self.answers[i + 1])

    def next_unmarked(self) -> bool:
        """Show the next answer without points: in this question after the one shown, then
        from its start, then in the other questions; False when every answer is marked."""
        if self.current is None:
            return False
        i, here = self.index, self.answers
        order = here[i + 1 :] + here[:i]
        for q in self.file.questions:
            if q != self.current.question:
                order += self._ordered(q)
        target = next((a for a in order if not a.marked), None)
        if target is None:
            if self._leave():
                self._say(
                    "Every answer is marked. Merge the marks: `course grade NAME SUBMISSIONS "
                    f"--out {self.file.out} --short-answers {self.file.path}`."
                )
            return False
        return self.go(target)

    def go(self, answer: Answer) -> bool:
        """Show ``answer`` (after saving the one shown); False when the boxes of the answer
        shown cannot be saved (the status says why)."""
        if not self._leave():
            return False
        self.file.reload()  # the marks another view (another marker) gave meanwhile
        self.current = self.file.find(answer.key) or answer
        a = self.current
        self._arrived = (a.points, a.comment) if a.points is not None else None
        self._enter = None
        self._loading = True
        try:
            self.question.value = self.current.question
            self.points.value = "" if self.current.points is None else _fmt(self.current.points)
            self.comment.value = self.current.comment
        finally:
            self._loading = False
        self._save_progress()
        self._show()
        self._say("")
        return True

    def _start(self, question: str | None) -> None:
        if not self.file.answers:
            self._say(f"No answers to mark in {self.file.path}.")
            for button in (
                self.previous_button,
                self.next_button,
                self.unmarked_button,
                self.group_button,
            ):
                button.disabled = True
            self.points.disabled = self.comment.disabled = True
            return
        saved = self._load_progress()
        start = saved if saved is not None and question in (None, saved.question) else None
        if start is None:
            pool = self._ordered(question) if question else self._ordered(self.file.questions[0])
            if question is None:
                pool += [a for q in self.file.questions[1:] for a in self._ordered(q)]
            start = next((a for a in pool if not a.marked), pool[0])
        self.go(start)
        if self.file.refused:
            self._say(
                f"{len(self.file.refused)} row(s) of {self.file.path} not imported: "
                + "; ".join(self.file.refused[:5]),
                error=True,
            )

    def _question_chosen(self, change) -> None:
        if self._loading or self.current is None or change["new"] == self.current.question:
            return
        pool = self._ordered(change["new"])
        if not self.go(next((a for a in pool if not a.marked), pool[0])):
            self._loading = True
            try:
                self.question.value = self.current.question  # stay: the status says why
            finally:
                self._loading = False

    # -- marking ---------------------------------------------------------------------------
    def _edited(self, _change) -> None:
        if not self._loading:
            self._save()

    def _unsaved(self) -> bool:
        a = self.current
        if a is None:
            return False
        shown = "" if a.points is None else _fmt(a.points)
        return (self.points.value.strip(), self.comment.value.strip()) != (shown, a.comment)

    def _save(self) -> bool:
        """Write the boxes' mark into the file; False (with the reason) when it cannot be."""
        a = self.current
        if a is None or not self._unsaved():
            return True
        try:
            self.current = self.file.mark(a, self.points.value, self.comment.value)
        except MarksError as exc:
            self._say(f"Not saved: {exc}.", error=True)
            return False
        saved = self.current
        self._say(
            f"Saved: {_fmt(saved.points)} of {_fmt(saved.points_possible)} points."
            if saved.points is not None
            else "Saved: not marked."
        )
        self._save_progress()
        self._show_counts()
        return True

    def _leave(self) -> bool:
        return self._save()

    def _points_message(self, _widget, content, _buffers) -> None:
        # Enter in the points box: the front end sends "submit" BEFORE the value it commits
        # (and may hold a value back while the kernel is busy), so moving on now would give
        # that value to the next answer; the value's arrival moves on (_points_edited)
        if content.get("event") == "submit" and self.current is not None:
            self._enter = self.current.key

    def _points_edited(self, _change) -> None:
        if self._loading:
            return
        enter = self.current is not None and self._enter == self.current.key
        self._enter = None
        if self._save() and enter:
            self.next_unmarked()

    def mark_group(self) -> bool:
        """Give the answer shown's mark (points and comment) to the members of its group that
        are not marked yet or still hold the mark it had when it was shown, one by one through
        :meth:`MarkingFile.mark`; then go to the next unmarked answer. Members marked otherwise
        keep their mark (an override sticks). False, with the reason, when the boxes cannot be
        saved or the answer has no points yet."""
        if not self._save():
            return False
        a = self.current
        if a is None or a.points is None:
            self._say("Not marked: give this answer its points first, then mark the group.", True)
            return False
        mark, arrived = (a.points, a.comment), self._arrived
        done, kept, errors = 0, 0, []
        for member in self.group_of(a):
            member = self.file.find(member.key) or member
            if member.key == a.key or (member.points, member.comment) == mark:
                continue
            if member.marked and (member.points, member.comment) != arrived:
                kept += 1  # marked on its own: an override
                continue
            try:
                self.file.mark(member, _fmt(a.points), a.comment)
            except MarksError as exc:
                errors.append(str(exc))
                continue
            done += 1
        self._arrived = mark  # a second press now moves what followed this mark
        what = f"{_fmt(a.points)} of {_fmt(a.points_possible)} points"
        text = f"Marked {done} more answer(s) of this group: {what}."
        if kept:
            text += f" {kept} marked on their own kept their mark."
        if errors:
            text += f" Not saved for {len(errors)}: {errors[0]}."
        if not self.next_unmarked():
            text += (
                " Every answer is marked: merge the marks with `course grade … --short-answers`."
            )
        self._say(text, error=bool(errors))
        self._show_counts()
        return not errors

    # -- display ---------------------------------------------------------------------------
    def _say(self, text: str, error: bool = False) -> None:
        color = "#b3261e" if error else "#1a1a1a"
        self.status.value = f'<span style="color: {color}">{html.escape(text, quote=False)}</span>'

    def _show(self) -> None:
        a = self.current
        if a is None:
            return
        answers = self.answers
        who = f" · student {html.escape(a.student)}" if self.show_ids.value else ""
        same = sum(b.answer_id == a.answer_id for b in answers) - 1
        twin = f" · the same text as {same} other answer(s)" if same else ""
        self.heading.value = (
            f"<b>{html.escape(a.question)}</b> ({_fmt(a.points_possible)} points) · answer "
            f"{self.index + 1} of {len(answers)}{who}{twin}"
        )
        self.answer.value = _box(a.text, "course-marking-text")
        self._show_group(a)
        self.rubric.value = "<b>Rubric:</b> " + (
            _box(a.rubric, "course-marking-rubric-text") if a.rubric else "<i>none given</i>"
        )
        self.points.placeholder = f"0 to {_fmt(a.points_possible)}"
        self.previous_button.disabled = self.index == 0
        self.next_button.disabled = self.index + 1 >= len(answers)
        self._show_counts()

    def _show_group(self, a: Answer) -> None:
        members = self.group_of(a)
        self.group_button.disabled = len(members) < 2
        self.group_button.description = f"mark the group ({len(members)})"
        if len(members) < 2:
            self.group_info.value = "<i>No other answer like this one.</i>"
            return
        texts: dict[str, int] = {}
        for b in members:
            if b.answer_id != a.answer_id:
                texts[b.text] = texts.get(b.text, 0) + 1
        todo = sum(not b.marked for b in members)
        near = sum(texts.values())
        lines = [
            f'<span class="course-marking-group-size">Group of {len(members)} answers</span>: '
            f"{len(members) - near} with this text, {near} with a text alike (below); "
            f"{todo} not marked yet."
        ]
        for text, n in list(texts.items())[:_LISTED]:
            lines.append(_box(f"×{n}: {text}", "course-marking-group-text"))
        if len(texts) > _LISTED:
            lines.append(f"<i>and {len(texts) - _LISTED} more texts</i>")
        self.group_info.value = "".join(lines)

    def _show_counts(self) -> None:
        per = [
            f"{html.escape(q)}: {sum(a.marked for a in self.file.of(q))} of "
            f"{len(self.file.of(q))} marked"
            for q in self.file.questions
        ]
        self.counts.value = (
            "; ".join(per) + f'. <span class="course-marking-file">Marks are saved in '
            f"{html.escape(str(self.file.record.path))} (exported to "
            f"{html.escape(str(self.file.path))}); the next <code>course grade</code> run "
            "merges them into the grades.</span>"
        )

    # -- where marking stopped -------------------------------------------------------------
    def _save_progress(self) -> None:
        if self.current is None:
            return
        tmp = self.progress_path.with_name(self.progress_path.name + ".tmp")
        a = self.current
        tmp.write_text(json.dumps({"question": a.question, "student": a.student}), "utf-8")
        tmp.replace(self.progress_path)

    def _load_progress(self) -> Answer | None:
        try:
            data = json.loads(self.progress_path.read_text("utf-8"))
            return self.file.find((str(data["student"]), str(data["question"])))
        except (OSError, ValueError, KeyError, TypeError):
            return None  # no progress yet, or a damaged file: start at the first unmarked


def write_marking_notebook(out_dir: str | Path) -> Path:
    """Write ``out_dir/marking.ipynb`` (a notebook whose cell shows :class:`MarkingView` of
    its own folder) unless it exists; returns its path. :class:`MarksError` when the folder
    has no marking file."""
    import nbformat

    out = Path(out_dir)
    if not (out / SHORT_ANSWERS_FILE).is_file():
        MarkingFile(out)  # raises with the reason
    path = out / NOTEBOOK_FILE
    if path.exists():
        return path
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {
        "name": "python3",
        "display_name": "Python 3",
        "language": "python",
    }
    nb.cells = [
        nbformat.v4.new_markdown_cell(
            "# Marking the short answers\n\n"
            "Run the cell below. Each mark is saved into this folder's record (`record.sqlite`, "
            "with your name and the time) and `short_answers.csv` as soon as you leave the "
            "points or comment box; alike answers come in groups that *mark the group* marks "
            "at once (the keys are listed under the view). Close the notebook at any time and "
            "the view starts where you stopped. `anonymous=False` shows the students' IDs, "
            '`question="q3"` starts at that question.\n\n'
            "Then merge the marks into the grades, the feedback and the LMS files:\n\n"
            "```bash\ncourse grade NAME SUBMISSIONS --out THIS_FOLDER\n```"
        ),
        nbformat.v4.new_code_cell(
            'from course.grading.batch.marking import MarkingView\n\nMarkingView(".")'
        ),
    ]
    nbformat.write(nb, path)
    return path
