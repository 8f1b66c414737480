"""Issue 27 item 5: an instructor marks two short answers in the marking view, in a real
JupyterLab (and Notebook 7, ``course mark --app notebook``) and Chromium, and ``course grade
--short-answers`` merges them into the grades.

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
            page.keyboard.press("Enter")
            _wait_status(page, "Saved: 2 of 2 points")
            page.click(".course-marking-show-ids input")
            page.wait_for_function(
                "document.querySelector('.course-marking-heading').textContent"
                ".includes('student ')",
                timeout=30_000,
            )
            second = _heading(page).split("student ")[1].split()[0]
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
    assert len(marked) == 2 and marked[second] == ("2", "")
    (first_sid,) = set(marked) - {second}
    assert marked[first_sid] == ("1.5", "Name the degrees of freedom.")

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
