"""Every notebook reads in JupyterLab and Notebook 7 as written: no raw MyST markup.

Students read the notebooks in JupyterLab, Notebook 7 or JupyterLite, whose Markdown knows no
MyST: a ``{numref}`` role or a ``:::{note}`` fence shows there as raw text (issue 39). The
notebooks therefore use plain Markdown only (links to figure names, block-quote call-outs) and
the website adds numbers and boxes at build time (``docs/_ext/course_site.py``). This test opens
every teaching notebook and every exercise in a real JupyterLab and Notebook 7 (Chromium), lets
each render all its Markdown cells, and looks for a role or a fence in the rendered text.

Skipped, with the reason, when Chromium or Playwright is missing (see ``tests/browser.py``).
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import nbformat
import pytest
from browser import CHROMIUM_ARGS, chromium_or_skip, jupyterlab

pytestmark = pytest.mark.browser

CHROMIUM = chromium_or_skip()
sync_api = pytest.importorskip(
    "playwright.sync_api", reason='the docs extra is not installed (pip install -e ".[docs]")'
)
pytest.importorskip("jupyterlab", reason="JupyterLab is not installed (the tests extra)")

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb")) + sorted(
    (ROOT / "exercises").glob("*/*.ipynb")
)
UIS = {"lab": "lab/tree", "notebook7": "notebooks"}
# A MyST role ({numref}`x`, {ref}`x`, {doc}`x`, ...) or directive fence (:::{note}, ```{figure})
# as the rendered page shows it: Jupyter's Markdown turns `x` into code, leaving "{numref}x".
RAW_MYST = re.compile(
    r"\{(?:numref|ref|doc|eq|term|math|cite|download|abbr)\}|:::|\{(?:note|warning|tip|admonition|figure|dropdown)\}"
)


def raw_markup(text: str) -> list[str]:
    return [m.group(0) for m in RAW_MYST.finditer(text)]


def test_the_pattern_finds_what_jupyter_shows_of_myst():
    assert raw_markup("See {numref}fig-07-power.") == ["{numref}"]
    assert raw_markup(":::{note}\nIn Jupyter ...\n:::") == [":::", "{note}", ":::"]
    assert not raw_markup("See the figure above. Note. a: b {x} `code`")


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """JupyterLab (and Notebook 7 on the same server) serving copies of every notebook."""
    folder = tmp_path_factory.mktemp("markup")
    names = []
    for path in NOTEBOOKS:
        name = f"{path.parent.name}--{path.name}"
        shutil.copy(path, folder / name)
        names.append(name)
    home = tmp_path_factory.mktemp("home")
    with jupyterlab(folder, home) as (base, token):
        yield base, token, names, folder


@pytest.mark.parametrize("ui", list(UIS))
def test_no_raw_myst_in_jupyterlab_or_notebook7(lab, ui):
    base, token, names, folder = lab
    found: dict[str, list[str]] = {}
    with sync_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            for name in names:
                expected = sum(
                    cell.cell_type == "markdown"
                    for cell in nbformat.read(folder / name, as_version=4).cells
                )
                # ?reset: JupyterLab opens this notebook alone, not every one opened before
                reset = "reset&" if ui == "lab" else ""
                page.goto(f"{base}/{UIS[ui]}/{name}?{reset}token={token}")
                panel = ".jp-NotebookPanel:not(.lm-mod-hidden) .jp-Notebook"
                page.wait_for_selector(f"{panel} .jp-Cell", state="attached", timeout=120_000)
                # every Markdown cell rendered (an unrendered one would show its source)
                page.wait_for_function(
                    "([sel, n]) => document.querySelectorAll(sel).length >= n",
                    arg=[f"{panel} .jp-MarkdownCell .jp-MarkdownOutput", expected],
                    timeout=120_000,
                )
                text = page.evaluate(
                    "([sel]) => Array.from(document.querySelectorAll(sel))"
                    ".map(e => e.textContent).join('\\n')",
                    [f"{panel} .jp-MarkdownCell .jp-MarkdownOutput"],
                )
                if raw_markup(text):
                    found[name] = sorted(set(raw_markup(text)))
                # the call-outs are block quotes and the figure citations links, as written
                if name == "notebooks--06_mismatched_filters.ipynb":
                    assert page.locator(".jp-MarkdownOutput blockquote strong").count() >= 3
                    assert page.locator('.jp-MarkdownOutput a[href^="#fig-"]').count() >= 1
        except Exception:
            page.screenshot(path=str(folder / f"failure-{ui}.png"))
            print(f"screenshot: {folder / f'failure-{ui}.png'}")
            raise
        finally:
            browser.close()
    assert not found, f"raw MyST markup shown in {ui}: {found}"
