"""Issue 27 item 5: an instructor marks two short answers in the marking view, in a real
JupyterLab (and Notebook 7, ``course mark --app notebook``) and Chromium, and ``course grade
--short-answers`` merges them into the grades. Issue 35 item 2: a group of alike answers is
marked at once with the keyboard only, one member is overridden, and every member's mark
reaches the exports.

The class of ``tests/test_grading_marking.py`` (four answers to the 2-point short question q3)
is graded with a roster; ``course mark OUT --no-open`` writes the marking notebook; JupyterLab
serves OUT as ``course mark`` would start it; the browser runs the notebook's cell, types the
points and a comment of one answer, goes to the next unmarked answer, types its points, and
shows the IDs to learn whose answer that was. Then the marks are merged and ``grades.csv``,
``canvas.csv``, ``moodle.csv`` and the feedback are checked.

Skipped, with the reason, when Chromium or Playwright is missing (see ``tests/browser.py``).
"""

from __future__ import annotations

import csv
import json

import pytest
from browser import CHROMIUM_ARGS, chromium_or_skip, jupyterlab, run_cell
from test_grading_marking import _grade, _moodle
from test_grading_marking import course as course  # the fixture

pytestmark = [pytest.mark.browser, pytest.mark.slow]

CHROMIUM = chromium_or_skip()
sync_api = pytest.importorskip(
    "playwright.sync_api", reason='the docs extra is not installed (pip install -e ".[docs]")'
)
pytest.importorskip("ipywidgets", reason="the marking view needs ipywidgets (notebooks extra)")
pytest.importorskip("jupyterlab", reason="JupyterLab is not installed (the tests extra)")

STUDENTS = ("s1", "s2", "s3", "s4", "s5")


def _heading(page) -> str:
    return page.locator(".course-marking-heading").inner_text()


def _wait_status(page, text: str) -> None:
    page.wait_for_function(
        "([t]) => document.querySelector('.course-marking-status').textContent.includes(t)",
        arg=[text],
        timeout=30_000,
    )


def _wait_heading(page, text: str) -> None:
    page.wait_for_function(
        "([t]) => document.querySelector('.course-marking-heading').textContent.includes(t)",
        arg=[text],
        timeout=30_000,
    )


# the front ends of `course mark --app lab|notebook` and the URL path each opens a notebook at
UIS = {"lab": "lab/tree", "notebook7": "notebooks"}


@pytest.mark.parametrize("ui", list(UIS))
def test_marking_two_answers_in_jupyter_reaches_the_grades(course, tmp_path, ui):
    from course.cli import main

    out = tmp_path / "out"
    _grade(course, out)
    assert main(["mark", str(out), "--no-open"]) == 0
    with (
        jupyterlab(out, tmp_path / "home") as (base, token),
        sync_api.sync_playwright() as playwright,
    ):
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": 1400, "height": 1000})
        try:
            page.goto(f"{base}/{UIS[ui]}/marking.ipynb?token={token}")
            page.wait_for_selector(".jp-Notebook .jp-CodeCell", timeout=90_000)
            run_cell(page, sync_api)
            page.wait_for_selector(".course-marking-points input", timeout=90_000)
            first = _heading(page)
            assert "answer 1 of 4" in first
            assert not any(sid in first for sid in STUDENTS)  # anonymous by default
            # the first answer: points with a decimal comma and a comment, then next unmarked
            page.fill(".course-marking-points input", "1,5")
            page.fill(".course-marking-comment textarea", "Name the degrees of freedom.")
            page.click(".course-marking-next-unmarked button, button.course-marking-next-unmarked")
            page.wait_for_function(
                "document.querySelector('.course-marking-heading').textContent"
                ".includes('answer 2 of 4')",
                timeout=30_000,
            )
            # the second: out of range first (refused on screen), then right
            page.fill(".course-marking-points input", "3")
            page.keyboard.press("Enter")
            _wait_status(page, "Not saved: 3 points: give between 0 and 2")
            page.fill(".course-marking-points input", "2")
            page.keyboard.press("Enter")  # saves and goes to the next unmarked answer
            _wait_heading(page, "answer 3 of 4")
            page.click(".course-marking-show-ids input")
            _wait_heading(page, "student ")
        except Exception:
            page.screenshot(path=str(tmp_path / "failure.png"))
            print(
                f"screenshot: {tmp_path / 'failure.png'}\n"
                f"lab.log:\n{(out / 'lab.log').read_text()[-3000:]}"
            )
            raise
        finally:
            browser.close()

    rows = list(csv.DictReader((out / "short_answers.csv").open(encoding="utf-8")))
    marked = {r["student"]: (r["points"], r["comment"]) for r in rows if r["points"]}
    assert sorted(marked.values()) == [("1.5", "Name the degrees of freedom."), ("2", "")]
    first_sid = next(sid for sid, m in marked.items() if m[0] == "1.5")
    second = next(sid for sid, m in marked.items() if m[0] == "2")

    summary = _grade(course, out)  # the view's marks are in the record: a plain run merges
    assert "short answers: 2 to mark" in summary.text()
    grades = {r["student"]: r for r in csv.DictReader((out / "grades.csv").open())}
    assert (grades[first_sid]["q3"], grades[first_sid]["total"]) == ("1.5", "4.5")
    assert (grades[second]["q3"], grades[second]["total"]) == ("2", "5")
    canvas = {r[2]: r for r in csv.reader((out / "canvas.csv").open(encoding="utf-8"))}
    assert (canvas[first_sid][5], canvas[second][5]) == ("4.5", "5")
    assert "q3 1.5/2" in _moodle(out)[first_sid][-1]
    feedback = (out / "feedback" / f"{first_sid}.md").read_text()
    assert "Name the degrees of freedom." in feedback


#: issue 35 item 2: q3 answers of a class where four are alike (three identical after
#: normalising case and punctuation, one with a typo) and one is different
GROUP_ANSWERS = {
    "s1": "Because T exceeds the critical value.",
    "s2": "because T exceeds the critical value",
    "s3": "<img src=x onerror=alert(1)> the p-value is small",
    "s4": "BECAUSE T EXCEEDS THE CRITICAL VALUE!",
    "s5": "Because T exceeds the critcal value.",
}
GROUP = {"s1", "s2", "s4", "s5"}


@pytest.fixture(scope="module")
def group_course(tmp_path_factory):
    from test_grading_items import RIGHT, _course, _student

    root = tmp_path_factory.mktemp("group")
    _course(root)
    subs = root / "subs"
    subs.mkdir()
    for sid, text in GROUP_ANSWERS.items():
        (subs / f"{sid}.ipynb").write_text(json.dumps(_student(root, {**RIGHT, "q3": text})))
    (root / "roster.csv").write_text(
        "id,name,email\n" + "".join(f"{sid},Student {sid},{sid}@example.org\n" for sid in STUDENTS)
    )
    return root


@pytest.mark.parametrize("ui", list(UIS))
def test_a_group_marked_at_once_with_the_keyboard_reaches_every_members_grade(
    group_course, tmp_path, ui
):
    from course.cli import main

    out = tmp_path / "out"
    _grade(group_course, out)
    assert main(["mark", str(out), "--no-open"]) == 0
    comment = "Name the degrees of freedom."
    with (
        jupyterlab(out, tmp_path / "home") as (base, token),
        sync_api.sync_playwright() as playwright,
    ):
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": 1400, "height": 1000})
        try:
            page.goto(f"{base}/{UIS[ui]}/marking.ipynb?token={token}")
            page.wait_for_selector(".jp-Notebook .jp-CodeCell", timeout=90_000)
            run_cell(page, sync_api)
            page.wait_for_selector(".course-marking-points input", timeout=90_000)
            assert "answer 1 of 5" in _heading(page)
            info = page.locator(".course-marking-group-info").inner_text()
            assert "Group of 4 answers" in info and "critcal" in info
            assert not any(sid in info + _heading(page) for sid in STUDENTS)  # anonymous
            # keyboard only: points, Tab, the comment, Tab to "mark the group", Enter
            page.focus(".course-marking-points input")
            page.keyboard.type("1,5")
            page.keyboard.press("Tab")
            page.keyboard.type(comment)
            page.keyboard.press("Tab")
            page.keyboard.press("Enter")
            _wait_status(page, "Marked 3 more answer(s) of this group")
            _wait_heading(page, "answer 5 of 5")  # the next unmarked: the one different answer
            # override one member: back to it, 2 points, Enter (saves, goes to the next unmarked)
            page.click(".course-marking-previous button, button.course-marking-previous")
            _wait_heading(page, "answer 4 of 5")
            page.click(".course-marking-show-ids input")
            _wait_heading(page, "student ")
            overridden = _heading(page).split("student ")[1].split()[0]
            page.fill(".course-marking-points input", "2")
            page.keyboard.press("Enter")
            _wait_heading(page, "answer 5 of 5")
        except Exception:
            page.screenshot(path=str(tmp_path / "failure.png"))
            print(
                f"screenshot: {tmp_path / 'failure.png'}\n"
                f"lab.log:\n{(out / 'lab.log').read_text()[-3000:]}"
            )
            raise
        finally:
            browser.close()

    assert overridden in GROUP
    rows = list(csv.DictReader((out / "short_answers.csv").open(encoding="utf-8")))
    marks = {r["student"]: (r["points"], r["comment"]) for r in rows}
    for sid in GROUP - {overridden}:
        assert marks[sid] == ("1.5", comment)
    assert marks[overridden] == ("2", comment) and marks["s3"] == ("", "")

    summary = _grade(group_course, out)  # the view's marks are in the record: a plain run merges
    assert "short answers: 1 to mark" in summary.text()
    grades = {r["student"]: r for r in csv.DictReader((out / "grades.csv").open())}
    canvas = {r[2]: r for r in csv.reader((out / "canvas.csv").open(encoding="utf-8"))}
    moodle = _moodle(out)
    for sid in GROUP:
        points, total = ("2", "5") if sid == overridden else ("1.5", "4.5")
        assert (grades[sid]["q3"], grades[sid]["total"]) == (points, total)
        assert canvas[sid][5] == total and moodle[sid][4] == total
        assert f"q3 {points}/2" in moodle[sid][-1]
        assert comment in (out / "feedback" / f"{sid}.md").read_text()
    assert (grades["s3"]["q3"], grades["s3"]["total"]) == ("0", "3")
    assert "q3 0/2 not marked yet" in moodle["s3"][-1]
