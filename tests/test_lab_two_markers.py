"""Issue 34 (done when): two markers mark short answers at once, each in a browser view of
their own (Chromium, a real JupyterLab), on the same OUT folder, and every mark lands.

The class of ``tests/test_grading_marking.py`` (four answers to the 2-point question q3) is
graded; ``course mark OUT --no-open`` writes the marking notebook, and each marker gets a copy
naming them (``MarkingView(".", marker=...)``), so the two pages run two kernels, two views and
two connections to the record. The markers interleave: Ann marks answer 1, Ben answer 2, Ann
answer 3, then Ben gives answer 1 another mark. Every mark is in the record with its marker, the
change of answer 1 is in ``course history`` (Ann's mark, then Ben's: the last write wins and the
first is kept), and a plain ``course grade`` run puts all three into grades.csv and canvas.csv.

Skipped, with the reason, when Chromium or Playwright is missing (see ``tests/browser.py``).
"""

from __future__ import annotations

import csv
import json

import pytest
from browser import CHROMIUM_ARGS, chromium_or_skip, jupyterlab, run_cell
from test_grading_marking import _grade
from test_grading_marking import course as course  # the fixture

pytestmark = [pytest.mark.browser, pytest.mark.slow]

CHROMIUM = chromium_or_skip()
sync_api = pytest.importorskip(
    "playwright.sync_api", reason='the docs extra is not installed (pip install -e ".[docs]")'
)
pytest.importorskip("ipywidgets", reason="the marking view needs ipywidgets (notebooks extra)")
pytest.importorskip("jupyterlab", reason="JupyterLab is not installed (the tests extra)")

MARKERS = ("ann", "ben")


def _notebook_for(out, marker: str) -> str:
    """A copy of the marking notebook whose view names ``marker`` and shows the IDs."""
    nb = json.loads((out / "marking.ipynb").read_text())
    (cell,) = [c for c in nb["cells"] if c["cell_type"] == "code"]
    source = "".join(cell["source"])
    assert 'MarkingView(".")' in source
    cell["source"] = source.replace(
        'MarkingView(".")', f'MarkingView(".", anonymous=False, marker="{marker}")'
    )
    name = f"marking-{marker}.ipynb"
    (out / name).write_text(json.dumps(nb))
    return name


def _heading(page) -> str:
    return page.locator(".course-marking-heading").inner_text()


def _go(page, number: int) -> str:
    """Move the view to answer ``number`` (of 4); returns that answer's student."""
    for _ in range(8):
        heading = _heading(page)
        at = int(heading.split("answer ")[1].split()[0])
        if at == number:
            return heading.split("student ")[1].split()[0]
        button = "next" if at < number else "previous"
        page.click(f".course-marking-{button} button, button.course-marking-{button}")
        page.wait_for_function(
            "([n]) => document.querySelector('.course-marking-heading').textContent"
            ".includes('answer ' + n + ' of 4')",
            arg=[at + (1 if at < number else -1)],
            timeout=30_000,
        )
    raise AssertionError(f"the view never reached answer {number}: {_heading(page)}")


def _mark(page, points: str, saved: str) -> None:
    page.fill(".course-marking-points input", points)
    page.keyboard.press("Tab")  # leaving the box saves and stays (Enter saves and moves on)
    page.wait_for_function(
        "([t]) => document.querySelector('.course-marking-status').textContent.includes(t)",
        arg=[f"Saved: {saved} of 2 points"],
        timeout=30_000,
    )


def test_two_markers_at_once_lose_no_mark(course, tmp_path, capsys):
    from course.cli import main
    from course.grading.batch.record import Record

    out = tmp_path / "out"
    _grade(course, out)
    assert main(["mark", str(out), "--no-open"]) == 0
    notebooks = {m: _notebook_for(out, m) for m in MARKERS}
    with (
        jupyterlab(out, tmp_path / "home") as (base, token),
        sync_api.sync_playwright() as playwright,
    ):
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        pages = {}
        try:
            for marker in MARKERS:  # two browser contexts: two markers, two kernels
                page = browser.new_context(viewport={"width": 1400, "height": 1000}).new_page()
                # a workspace each: Lab keeps a workspace's open tabs on the server, and a
                # shared one would open Ann's notebook, hidden, in Ben's page too
                page.goto(
                    f"{base}/lab/workspaces/{marker}/tree/{notebooks[marker]}?reset&token={token}"
                )
                page.wait_for_selector(".jp-Notebook .jp-CodeCell", timeout=90_000)
                run_cell(page, sync_api)
                page.wait_for_selector(".course-marking-points input", timeout=90_000)
                pages[marker] = page
            ann, ben = pages["ann"], pages["ben"]
            first = _go(ann, 1)
            _mark(ann, "1", "1")
            second = _go(ben, 2)
            _mark(ben, "2", "2")
            third = _go(ann, 3)
            _mark(ann, "0", "0")
            assert _go(ben, 1) == first
            _mark(ben, "0,5", "0.5")  # Ben changes Ann's mark: the last write wins
        except Exception:
            for marker, page in pages.items():
                page.screenshot(path=str(tmp_path / f"failure-{marker}.png"))
            print(f"screenshots in {tmp_path}\nlab.log:\n{(out / 'lab.log').read_text()[-3000:]}")
            raise
        finally:
            browser.close()

    assert len({first, second, third}) == 3
    with Record(out) as record:
        marks = {a["student"]: a["points"] for a in record.answers() if a["points"] is not None}
    assert marks == {first: 0.5, second: 2.0, third: 0.0}
    capsys.readouterr()
    assert main(["history", str(out), first]) == 0
    history = [line for line in capsys.readouterr().out.splitlines() if " mark " in line]
    # Ann's mark, then Ben's, each with its marker: the first is kept in the history
    assert [line.split()[1] for line in history] == ["ann", "ben"], history

    summary = _grade(course, out)  # a plain run: the marks are in the record
    assert summary is not None
    grades = {r["student"]: r for r in csv.DictReader((out / "grades.csv").open())}
    canvas = {r[2]: r for r in csv.reader((out / "canvas.csv").open(encoding="utf-8"))}
    for sid, q3 in ((first, "0.5"), (second, "2"), (third, "0")):
        total = grades[sid]["total"]
        assert grades[sid]["q3"] == q3 and float(total) == 3 + float(q3), grades[sid]
        assert canvas[sid][5] == total
    rows = {r["student"]: r for r in csv.DictReader((out / "short_answers.csv").open())}
    assert {sid: rows[sid]["points"] for sid in (first, second, third)} == {
        first: "0.5",
        second: "2",
        third: "0",
    }
