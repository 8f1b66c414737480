"""Issue 27 item 5: marking short answers in Jupyter, and no unmarked answer exported as 0
without a warning.

The marking view (:mod:`course.grading.batch.marking`) is tested here without a browser, through
its widgets' values and buttons as the front end sets them; ``tests/test_lab_marking.py`` drives
it in a real JupyterLab.
"""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import pytest
from test_grading_items import NAME, RIGHT, _course, _student

from course.grading.batch.driver import grade
from course.grading.batch.options import GradeOptions
from course.grading.batch.roster import read_roster


def _moodle(out: Path) -> dict[str, list[str]]:
    return {r[0]: r for r in csv.reader((out / "moodle.csv").open(encoding="utf-8"))}


@pytest.fixture(scope="module")
def course(tmp_path_factory):
    """Four students answered the short question q3 (2 points), one did not."""
    root = tmp_path_factory.mktemp("marking")
    _course(root)
    subs = root / "subs"
    subs.mkdir()
    answers = {
        "s1": "Because T exceeds the critical value.",
        "s2": "<img src=x onerror=alert(1)> the p-value is small",
        "s3": "Because T exceeds the critical value.",  # the same text as s1
        "s4": "I do not know.",
    }
    for sid, text in answers.items():
        (subs / f"{sid}.ipynb").write_text(json.dumps(_student(root, {**RIGHT, "q3": text})))
    (subs / "s5.ipynb").write_text(json.dumps(_student(root, {**RIGHT, "q3": ""})))
    roster = root / "roster.csv"
    roster.write_text(
        "id,name,email\n" + "".join(f"s{i},Student {i},s{i}@example.org\n" for i in range(1, 6))
    )
    return root


def _grade(course: Path, out: Path, **options):
    opts = GradeOptions(jobs=1, progress=False, roster=read_roster(course / "roster.csv"))
    for key, value in options.items():
        setattr(opts, key, value)
    return grade(course / "solutions" / NAME, course / "subs", out, opts)


@pytest.fixture(scope="module")
def graded(course, tmp_path_factory):
    out = tmp_path_factory.mktemp("out")
    return _grade(course, out), out


# -- unmarked answers are never exported as 0 without a warning ----------------------------
def test_unmarked_answers_are_counted_per_question_in_the_console(graded):
    """Old code: "4 to mark in …" and nothing said that grades and LMS files count them 0."""
    summary, out = graded
    text = summary.text()
    assert (
        "WARNING: 4 short answer(s) NOT marked yet count as 0 (q3: 4 of 4 answers) in "
        "grades.csv, report.html and the LMS files"
    ) in text
    assert f"course mark {out}" in text


def test_unmarked_answers_are_a_warning_in_the_report(graded):
    _, out = graded
    page = (out / "report.html").read_text()
    warning = page.split('<div class="warning">')[1].split("</div>")[0]
    assert "4 short answer(s) NOT marked yet count as 0" in warning
    assert "<td>q3</td><td>4</td><td>4</td>" in warning
    # first: every number below it counts the unmarked answers as 0
    assert page.index('<div class="warning">') < page.index("student(s); total out of")


def test_lms_files_carry_the_unmarked_zero_visibly(graded):
    """The choice (docs/instructors/term.md): the LMS files carry the points so far, the
    unmarked answer as 0, and say so wherever the file has room for words."""
    _, out = graded
    canvas = {r[2]: r for r in csv.reader((out / "canvas.csv").open(encoding="utf-8"))}
    assert canvas["s1"][5] == "3"  # q1 1 + q2 2 + q3 (not marked) 0
    moodle = _moodle(out)
    assert moodle["s1"][4] == "3"
    assert "q3 0/2 not marked yet" in moodle["s1"][-1]
    assert "not marked" not in moodle["s5"][-1]  # no answer given: a real 0


def _copy(graded, tmp_path: Path) -> Path:
    """A copy of the graded class's output (a rerun resumes every student: no grading)."""
    out = tmp_path / "out"
    shutil.copytree(graded[1], out)
    return out


def test_no_warning_once_everything_is_marked(course, graded, tmp_path):
    out = _copy(graded, tmp_path)
    rows = list(csv.DictReader((out / "short_answers.csv").open(encoding="utf-8")))
    for r in rows:
        r["points"] = "1"
    with open(tmp_path / "all.csv", "w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    summary = _grade(course, out, short_answers=tmp_path / "all.csv")
    assert "NOT marked" not in summary.text() and "all marked" in summary.text()
    assert '<div class="warning">' not in (out / "report.html").read_text()
    assert "not marked" not in _moodle(out)["s1"][-1]


# -- the marking view, without a browser ---------------------------------------------------
widgets = pytest.importorskip("ipywidgets", reason="the marking view needs ipywidgets")

from course.grading.batch.marking import (  # noqa: E402
    PROGRESS_FILE,
    MarkingView,
    write_marking_notebook,
)
from course.grading.batch.marks import COLUMNS, MarksError, answer_id  # noqa: E402

#: (student, question, answer, points possible): q1 is worth 2 points, q2 1 point
ANSWERS = [
    ("s1", "q1", "The statistic exceeds the critical value.", 2),
    ("s2", "q1", "=SUM(A1) <b>bold</b>", 2),
    ("s3", "q1", "It is chi-square with 3 dof.", 2),
    ("s4", "q1", "The statistic exceeds the critical value.", 2),
    ("s1", "q2", "Because the residuals are correlated.", 1),
    ("s2", "q2", "No idea.", 1),
]


def _marking_file(folder: Path, marked: dict | None = None) -> Path:
    """A marking file as ``course grade`` writes it (``marked``: (student, q) -> points)."""
    marked = marked or {}
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / "short_answers.csv", "w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(COLUMNS)
        for sid, qid, text, top in ANSWERS:
            cell = "'" + text if text.startswith("=") else text
            points = marked.get((sid, qid), "")
            rubric = "names the critical value" if qid == "q1" else ""
            writer.writerow([sid, qid, cell, top, points, rubric, "", answer_id(text)])
    return folder


def _rows(folder: Path) -> dict:
    rows = csv.DictReader((folder / "short_answers.csv").open(encoding="utf-8"))
    return {(r["student"], r["question"]): r for r in rows}


def _at(file, key: tuple[str, str]):
    """The answer of ``key`` (it must be there)."""
    answer = file.find(key)
    assert answer is not None, key
    return answer


def _blur(box, value: str) -> None:
    """What the front end does when the marker types into a box and leaves it."""
    box.value = value


def test_answers_come_one_question_at_a_time_group_by_group_in_digest_order(tmp_path):
    view = MarkingView(_marking_file(tmp_path))
    q1 = [a for a in ANSWERS if a[1] == "q1"]
    # the group of two identical answers (s1, s4) first, then the others by digest
    expected = sorted(q1, key=lambda a: (a[0] not in ("s1", "s4"), answer_id(a[2]), a[0]))
    assert [a.student for a in view.answers] == [a[0] for a in expected]
    assert view.question.options == ("q1", "q2") and view.current == view.answers[0]
    assert view.previous() is False and view.previous_button.disabled
    seen = [view.current.student]
    while view.next():
        seen.append(view.current.student)
    assert seen == [a[0] for a in expected] and view.next_button.disabled
    assert "answer 4 of 4" in view.heading.value
    # the same text twice: neighbours, and the view says so
    twins = [i for i, a in enumerate(view.answers) if a.student in ("s1", "s4")]
    assert twins[1] == twins[0] + 1
    view.go(view.answers[twins[0]])
    assert "the same text as 1 other answer(s)" in view.heading.value
    view.question.value = "q2"  # choosing a question shows its first unmarked answer
    assert view.current.question == "q2" and "(1 points)" in view.heading.value


def test_next_unmarked_skips_marked_answers_and_moves_on_to_the_next_question(tmp_path):
    folder = _marking_file(tmp_path, {("s1", "q1"): 2, ("s3", "q1"): 0, ("s4", "q1"): 1})
    view = MarkingView(folder)
    assert view.current.key == ("s2", "q1")  # the first unmarked answer
    _blur(view.points, "1")
    assert view.next_unmarked() and view.current.question == "q2"
    assert not view.current.marked
    _blur(view.points, "1")
    assert view.next_unmarked() and view.current.key in {("s1", "q2"), ("s2", "q2")}
    _blur(view.points, "0")
    assert view.next_unmarked() is False and "Every answer is marked" in view.status.value
    assert all(r["points"] != "" for r in _rows(folder).values())


def test_a_mark_is_written_into_the_file_at_once(tmp_path):
    folder = _marking_file(tmp_path)
    view = MarkingView(folder)
    view.go(next(a for a in view.answers if a.student == "s2"))
    _blur(view.points, "1,5")  # a decimal comma
    _blur(view.comment, "=good; name the dof")
    row = _rows(folder)[("s2", "q1")]
    assert (row["points"], row["comment"]) == ("1.5", "'=good; name the dof")
    assert row["answer"] == "'=SUM(A1) <b>bold</b>"  # the other cells as they were
    assert "Saved: 1.5 of 2 points" in view.status.value
    assert "q1: 1 of 4 marked" in view.counts.value
    _blur(view.comment, "")
    _blur(view.points, "")  # cleared: not marked again
    assert (_rows(folder)[("s2", "q1")]["points"], view.current.marked) == ("", False)


@pytest.mark.parametrize(
    "points, comment, reason",
    [
        ("3", "", "3 points: give between 0 and 2"),
        ("-0.5", "", "give between 0 and 2"),
        ("two", "", "'two' is not a number of points"),
        ("nan", "", "give between 0 and 2"),
        ("", "see me", "a comment needs points"),
    ],
)
def test_points_outside_the_bounds_are_refused_and_kept_on_screen(
    tmp_path, points, comment, reason
):
    folder = _marking_file(tmp_path)
    before = (folder / "short_answers.csv").read_bytes()
    view = MarkingView(folder)
    first = view.current
    _blur(view.comment, comment)
    _blur(view.points, points)
    assert reason in view.status.value and "Not saved" in view.status.value
    assert (folder / "short_answers.csv").read_bytes() == before
    # leaving the answer is refused too: what was typed is neither lost nor changed
    assert view.next() is False and view.next_unmarked() is False
    view.question.value = "q2"  # another question: refused too, the menu goes back
    assert view.question.value == "q1"
    assert view.current == first and (view.points.value, view.comment.value) == (points, comment)


def test_a_restarted_view_resumes_where_marking_stopped(tmp_path):
    folder = _marking_file(tmp_path)
    view = MarkingView(folder)
    _blur(view.points, "2")
    view.next()
    view.next()
    stopped = view.current.key
    _blur(view.comment, "almost")
    _blur(view.points, "1")
    assert json.loads((folder / PROGRESS_FILE).read_text()) == dict(
        zip(("student", "question"), stopped)
    )
    again = MarkingView(folder)  # a new kernel: everything from the files
    assert again.current.key == stopped
    assert (again.points.value, again.comment.value) == ("1", "almost")
    assert "q1: 2 of 4 marked" in again.counts.value
    # a question named on the command line wins over the saved position
    assert MarkingView(folder, question="q2").current.question == "q2"
    (folder / PROGRESS_FILE).write_text("{not json")  # damaged: start at the first unmarked
    assert not MarkingView(folder).current.marked


def test_the_view_is_anonymous_by_default(tmp_path):
    view = MarkingView(_marking_file(tmp_path))
    ids = [sid for sid, *_ in ANSWERS]
    assert not view.show_ids.value
    _blur(view.points, "1")  # the status line after a mark names no one either
    for _ in range(3):
        shown = [view.heading.value, view.answer.value, view.rubric.value, view.status.value]
        assert not any(sid in text for sid in ids for text in shown)
        view.next()
    view.show_ids.value = True
    assert f"student {view.current.student}" in view.heading.value
    named = MarkingView(_marking_file(tmp_path / "b"), anonymous=False)
    assert f"student {named.current.student}" in named.heading.value


def test_answers_are_shown_as_text_never_as_html(tmp_path):
    view = MarkingView(_marking_file(tmp_path))
    view.go(next(a for a in view.answers if a.student == "s2"))
    assert "&lt;b&gt;bold&lt;/b&gt;" in view.answer.value and "<b>bold" not in view.answer.value
    assert "=SUM(A1)" in view.answer.value and "'=SUM" not in view.answer.value  # no guard


def test_an_answer_changed_by_a_regrade_is_not_marked_blindly(tmp_path):
    from course.grading.batch.record import Record

    folder = _marking_file(tmp_path)
    view = MarkingView(folder)
    current = view.current
    with Record(folder) as record:  # `course grade` graded a changed answer meanwhile
        answers = record.answers()
        for a in answers:
            if (a["student"], a["question"]) == current.key:
                a.update(answer_id="0123456789ab", text="a new answer")
        record.set_answers(answers)
    _blur(view.points, "1")
    assert "no longer in" in view.status.value and "reload the view" in view.status.value
    with Record(folder) as record:
        assert current.student not in record.marks()


def test_bad_folders_and_questions_are_refused(tmp_path):
    with pytest.raises(MarksError, match="does not exist: `course grade"):
        MarkingView(tmp_path)
    folder = _marking_file(tmp_path / "out")
    with pytest.raises(ValueError, match=r"question='q9': no answers to mark"):
        MarkingView(folder, question="q9")


def test_one_bad_row_of_a_marking_file_never_stops_the_view(tmp_path):
    """Old code: MarksError for the whole file, so nobody could mark (a row that is not one,
    e.g. a hand-edited mark out of range, blocked the class)."""
    folder = _marking_file(tmp_path / "out", {("s3", "q1"): 1})
    path = folder / "short_answers.csv"
    path.write_text(path.read_text().replace(",2,,names", ",2,9,names", 1))
    view = MarkingView(folder)
    assert "line 2: 9 points: give between 0 and 2" in view.status.value
    assert len(view.file.answers) == len(ANSWERS)  # every answer can be marked
    assert _at(view.file, ("s3", "q1")).points == 1  # the other rows' marks were imported


def test_two_markers_at_once_lose_no_mark(tmp_path):
    """Two views of one folder (two markers, two kernels) marking in turns: every mark lands,
    with its marker. Old code: each view rewrote the whole file from what it had read, so the
    later save dropped the other's marks."""
    from course.grading.batch.record import Record

    folder = _marking_file(tmp_path)
    ann, bob = MarkingView(folder, marker="ann"), MarkingView(folder, marker="bob")
    given = {}
    for i, answer in enumerate(ann.answers):
        view = (ann, bob)[i % 2]
        view.go(_at(view.file, answer.key))
        _blur(view.points, "1")
        given[answer.key] = ("ann", "bob")[i % 2]
    with Record(folder) as record:
        marks = record.marks()
    assert {(s, q): m["who"] for s, by_q in marks.items() for q, m in by_q.items()} == given
    assert all(r["points"] == "1" for k, r in _rows(folder).items() if k in given)
    bob.go(bob.answers[0])  # each view shows the other's marks as it moves on
    assert all(a.marked for a in bob.answers)


def test_marks_from_the_view_reach_the_grades_on_the_next_run(course, graded, tmp_path, capsys):
    """The view's marks are in the record: the next plain run merges them into the grades,
    feedback and LMS files, and `course history` answers a regrade request."""
    from course.cli import main

    out = _copy(graded, tmp_path)
    view = MarkingView(out, marker="ann")
    marked = {}
    for points, comment in (("1.5", "name the dof"), ("2", "")):
        _blur(view.points, points)
        _blur(view.comment, comment)
        marked[view.current.student] = (points, comment)
        view.next_unmarked()
    summary = _grade(course, out)
    assert "short answers: 2 to mark" in summary.text()
    assert "(q3: 2 of 4 answers)" in summary.text()
    grades = {r["student"]: r for r in csv.DictReader((out / "grades.csv").open())}
    moodle = _moodle(out)
    for sid, (points, comment) in marked.items():
        assert grades[sid]["q3"] == points and float(grades[sid]["total"]) == 3 + float(points)
        assert f"q3 {points}/2;" in moodle[sid][-1] or moodle[sid][-1].endswith(f"q3 {points}/2).")
        if comment:
            assert comment in (out / "feedback" / f"{sid}.md").read_text()
    # importing the view's own export changes nothing
    again = _grade(course, out, short_answers=out / "short_answers.csv")
    assert "0 mark(s) imported; 2 to mark" in again.text()
    sid, (points, _) = next(iter(marked.items()))
    capsys.readouterr()
    assert main(["history", str(out), sid]) == 0
    history = capsys.readouterr().out
    assert "ann" in history and f"{float(points):g} points" in history
    assert f"{3 + float(points):g}/5 " in history  # the grade before and after the mark
    assert history.index("mark q3") < history.rindex("grade")


def test_course_mark_writes_the_marking_notebook(tmp_path, capsys):
    from course.cli import main

    out = tmp_path / "out"
    assert main(["mark", str(out), "--no-open"]) == 2
    assert "short_answers.csv does not exist" in capsys.readouterr().err
    _marking_file(out)
    assert main(["mark", str(out), "--no-open"]) == 0
    notebook = out / "marking.ipynb"
    assert str(notebook) in capsys.readouterr().out
    source = json.loads(notebook.read_text())["cells"][-1]["source"]
    assert 'MarkingView(".")' in "".join(source)
    notebook.write_text(notebook.read_text().replace("# Marking the short answers", "# Mine"))
    assert write_marking_notebook(out) == notebook  # an existing notebook is kept as it is
    assert "# Mine" in notebook.read_text()


def test_the_gradebook_warns_about_unmarked_answers(graded, tmp_path, capsys):
    """Old code: the gradebook counted them as 0 and said nothing."""
    from course.cli import main

    _, out = graded
    assert main(["gradebook", str(out), "--out", str(tmp_path / "book")]) == 0
    text = capsys.readouterr().out
    assert "WARNING: 4 short answer(s) NOT marked yet count as 0 (Items: 4)" in text


def test_course_mark_opens_the_notebook_in_jupyter(tmp_path, monkeypatch, capsys):
    import subprocess
    import sys

    from course.cli import main

    out = _marking_file(tmp_path / "out")
    calls = []
    monkeypatch.setattr(subprocess, "call", lambda command, cwd: calls.append((command, cwd)))
    assert main(["mark", str(out), "--no-browser"]) == 0
    assert calls == [([sys.executable, "-m", "jupyterlab", "marking.ipynb", "--no-browser"], out)]
    assert main(["mark", str(out), "--app", "notebook"]) == 0
    assert calls[-1][0] == [sys.executable, "-m", "notebook", "marking.ipynb"]
    assert "Opening" in capsys.readouterr().out


# -- short answers are data: quotes, commas, formulas, HTML, control characters --------------
HOSTILE = {
    "h1": 'I do not know. "q",1,1,"ok',  # a forgery: the old import gave it 1/1 `marked`
    "h2": 'The "parameter" test is stronger, because it has one degree of freedom.',
    "h3": '=HYPERLINK("http://x","click") the statistic is large',  # refused `course mark`
    "h4": "a, b\nnew line <script>alert(1)</script> \x07bell \x1b[31mred",
}


@pytest.fixture(scope="module")
def hostile(tmp_path_factory):
    root = tmp_path_factory.mktemp("hostile_answers")
    _course(root)
    subs = root / "subs"
    subs.mkdir()
    for sid, text in HOSTILE.items():
        (subs / f"{sid}.ipynb").write_text(json.dumps(_student(root, {**RIGHT, "q3": text})))
    roster = root / "roster.csv"
    roster.write_text("id,name,email\n" + "".join(f"{s},N {s},{s}@x.org\n" for s in HOSTILE))
    out = root / "out"
    summary = _grade(root, out)
    return root, out, summary


def test_importing_the_untouched_marking_file_forges_no_mark(hostile):
    """Old code sniffed the dialect from the header (no quotes there, so no doubled quotes):
    the forgery's `"q",1,1,"ok` became cells and '2 mark(s) imported' gave two students 1/1."""
    root, out, _ = hostile
    summary = _grade(root, out, short_answers=out / "short_answers.csv")
    assert "0 mark(s) imported; 4 to mark" in summary.text()
    assert {r.student: r.questions["q3"].status for r in summary.rows} == dict.fromkeys(
        HOSTILE, "to mark"
    )


def test_hostile_answers_are_marked_and_exported_intact(hostile, tmp_path):
    """Old code: `=HYPERLINK(...)` made `course mark` refuse to open for everyone."""
    root, out, _ = hostile
    out = Path(shutil.copytree(out, tmp_path / "out"))
    view = MarkingView(out, anonymous=False)
    assert {a.student: a.text for a in view.answers} == HOSTILE  # the record: intact
    for _ in HOSTILE:
        _blur(view.points, "1")
        view.next_unmarked()
    for sid in HOSTILE:
        view.go(_at(view.file, (sid, "q3")))
        assert "<script>" not in view.answer.value and "\x1b" not in view.answer.value
    rows = list(csv.reader((out / "short_answers.csv").open(encoding="utf-8", newline="")))
    assert all(len(r) == len(rows[0]) for r in rows)  # one row per answer, every cell in place
    cells = {r[0]: r[2] for r in rows[1:]}
    assert cells["h3"].startswith("'=HYPERLINK") and "\\n" in cells["h4"]
    assert not any(c in cell for cell in cells.values() for c in "\n\x07\x1b")
    summary = _grade(root, out, short_answers=out / "short_answers.csv")
    text = summary.text()
    assert "all marked" in text and "\x1b" not in text and "\x07" not in text
    grades = {r["student"]: r for r in csv.DictReader((out / "grades.csv").open())}
    assert all(grades[sid]["q3"] == "1" for sid in HOSTILE)
    canvas = list(csv.reader((out / "canvas.csv").open(encoding="utf-8", newline="")))
    assert all(len(r) == len(canvas[0]) for r in canvas)
    page = (out / "report.html").read_text()
    assert "<script>alert" not in page


@pytest.mark.parametrize(
    "words",
    [
        ["--port", "8899", "--ip", "0.0.0.0", "--allow-root"],  # issue 34/39: was refused
        ["--port=8899", "--ip=0.0.0.0", "--allow-root"],
    ],
)
def test_course_mark_passes_jupyters_options_on_in_both_forms(tmp_path, monkeypatch, words):
    import subprocess
    import sys

    from course.cli import main

    out = _marking_file(tmp_path / "out")
    calls = []
    monkeypatch.setattr(subprocess, "call", lambda command, cwd: calls.append((command, cwd)))
    assert main(["mark", *words[:2], str(out), *words[2:], "--no-browser"]) == 0
    assert calls == [
        ([sys.executable, "-m", "jupyterlab", "marking.ipynb", "--no-browser", *words], out)
    ]


# -- issue 35 item 2: marking at the speed of a class ---------------------------------------
#: q1 (2 points): a group of five alike answers (three texts identical up to case and
#: punctuation, one with a typo, one marked already), two others; q2 one answer
CLASS = [
    ("s1", "q1", "The statistic exceeds the critical value."),
    ("s2", "q1", "the statistic exceeds the critical value"),
    ("s3", "q1", "No idea <b>at all</b>."),
    ("s4", "q1", "THE STATISTIC EXCEEDS THE CRITICAL VALUE!"),
    ("s5", "q1", "The statistic exceeds the critcal value."),
    ("s6", "q1", "It is chi-square with 3 dof."),
    ("s7", "q1", "The statistic exceeds the critical value."),
    ("s1", "q2", "Because the residuals are correlated."),
]
GROUP = {"s1", "s2", "s4", "s5", "s7"}


def _class_file(folder: Path, marked: dict | None = None) -> Path:
    marked = marked or {}
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / "short_answers.csv", "w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(COLUMNS)
        for sid, qid, text in CLASS:
            points, comment = marked.get((sid, qid), ("", ""))
            writer.writerow([sid, qid, text, 2, points, "", comment, answer_id(text)])
    return folder


def _marks(folder: Path, question: str = "q1") -> dict:
    return {
        sid: (r["points"], r["comment"]) for (sid, q), r in _rows(folder).items() if q == question
    }


def test_alike_answers_are_one_group_shown_with_its_size_and_texts(tmp_path):
    view = MarkingView(_class_file(tmp_path))
    first = view.answers[:5]
    assert {a.student for a in first} == GROUP  # the largest group first, its members together
    assert [len(g) for g in view.groups("q1")] == [5, 1, 1]
    assert view.current.student in GROUP
    info = view.group_info.value
    assert "Group of 5 answers" in info and "not marked yet" in info
    assert "critcal" in info  # the near-identical text is listed for the marker to see
    assert view.group_button.description == "mark the group (5)"
    assert not any(f"s{i}" in info + view.heading.value for i in range(1, 8))  # anonymous
    view.go(next(a for a in view.answers if a.student == "s3"))
    assert view.group_button.disabled and "No other answer like this one" in view.group_info.value
    assert "&lt;b&gt;at all&lt;/b&gt;" in view.answer.value  # plain text


def test_a_group_is_marked_at_once_and_an_override_sticks(tmp_path):
    """The rule (docs/instructors/term.md): marking the group gives the mark to members not
    marked yet and to those that still hold the mark the answer shown had; a member marked
    otherwise keeps its own mark, then and when the group is marked again."""
    folder = _class_file(tmp_path, {("s7", "q1"): ("0", "marked before")})
    view = MarkingView(folder)
    leader = view.current
    assert leader.student in GROUP - {"s7"}
    _blur(view.points, "1,5")
    _blur(view.comment, "name the dof")
    assert view.mark_group()
    marks = _marks(folder)
    for sid in GROUP - {"s7"}:
        assert marks[sid] == ("1.5", "name the dof")
    assert marks["s7"] == ("0", "marked before")  # marked before: an override, kept
    assert marks["s3"] == marks["s6"] == ("", "")  # not in the group: untouched
    assert "Marked 3 more answer(s) of this group" in view.status.value
    assert "1 marked on their own kept their mark" in view.status.value
    assert not view.current.marked and view.current.student not in GROUP  # next unmarked

    # one member overridden afterwards
    view.go(next(a for a in view.answers if a.student == "s5"))
    _blur(view.comment, "")
    _blur(view.points, "2")
    # the group marked again from its leader with a changed mark: the override stays
    view.go(view.file.find(leader.key))
    _blur(view.points, "1")
    assert view.mark_group()
    marks = _marks(folder)
    assert marks["s5"] == ("2", "") and marks["s7"] == ("0", "marked before")
    for sid in GROUP - {"s5", "s7"}:
        assert marks[sid] == ("1", "name the dof")
    assert "2 marked on their own kept their mark" in view.status.value


def test_marking_a_group_needs_points_first(tmp_path):
    folder = _class_file(tmp_path)
    before = (folder / "short_answers.csv").read_bytes()
    view = MarkingView(folder)
    assert view.mark_group() is False and "give this answer its points first" in view.status.value
    _blur(view.points, "7")
    assert view.mark_group() is False and "Not saved" in view.status.value
    assert (folder / "short_answers.csv").read_bytes() == before


def _enter(view, value: str) -> None:
    """What the front end sends when the marker types ``value`` into the points box and
    presses Enter: "submit" first, then the value (which it may also hold back a while)."""
    view.points._handle_custom_msg({"event": "submit"}, [])
    view.points.value = value


def test_enter_in_the_points_box_saves_and_goes_to_the_next_unmarked(tmp_path):
    folder = _class_file(tmp_path)
    view = MarkingView(folder)
    first = view.current
    _enter(view, "3")
    assert view.current == first and "Not saved" in view.status.value
    _enter(view, "2")  # the value after the Enter is saved for the answer it was typed for
    assert _marks(folder)[first.student] == ("2", "")
    assert view.current.key != first.key and not view.current.marked
    assert view.points.value == ""  # the next answer's box, empty
    # a value that reached the kernel, then more typed and Enter: the last value arrives
    # after the "submit" and belongs to this answer, never to the next one
    second = view.current
    view.points.value = "1"
    _enter(view, "1.5")
    assert _marks(folder)[second.student] == ("1.5", "")
    assert view.current.key not in (first.key, second.key) and not view.current.marked
    # the keyboard path is written in the view
    assert "<kbd>Enter</kbd> saves and goes to the next unmarked answer" in view.keys.value
