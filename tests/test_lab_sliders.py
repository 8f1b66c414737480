"""A course slider in a real JupyterLab and in Notebook 7, moved in a real browser, redraws its
figure.

The sliders of ``course.interactive`` put their figure into the output area as the Output
widget's state, set in the kernel (so that nbclient runners do not stall, see
``course.interactive._build``). The unit tests check the widget's state in Python; this test
checks what a student sees: JupyterLab started as ``course open`` starts it, the notebook's
slider cell run, the second slider dragged with the mouse, and the figure in the output area
replaced by a new one (one figure, never a second copy below the first). The same server also
serves the classic-looking Notebook 7 interface (``/notebooks/...``, installed with ``jupyter``),
which a student may prefer; the slider is checked there too.

Skipped, with the reason, when Chromium or Playwright is missing (see ``tests/browser.py``).
"""

from __future__ import annotations

import nbformat
import pytest
from browser import CHROMIUM_ARGS, chromium_or_skip, jupyterlab

pytestmark = pytest.mark.browser

CHROMIUM = chromium_or_skip()
sync_api = pytest.importorskip(
    "playwright.sync_api", reason='the docs extra is not installed (pip install -e ".[docs]")'
)
pytest.importorskip("ipywidgets", reason="the sliders need ipywidgets (the notebooks extra)")
pytest.importorskip("jupyterlab", reason="JupyterLab is not installed (the tests extra)")

# the interface and the URL path it opens a notebook at
UIS = {"lab": "lab/tree", "notebook7": "notebooks"}
SLIDER_CELL = "%matplotlib inline\nfrom course import interactive\ninteractive.omt_widget()"


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """JupyterLab serving a folder with one notebook (its kernel named, so Lab asks nothing)."""
    folder = tmp_path_factory.mktemp("lab")
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {
        "name": "python3",
        "display_name": "Python 3",
        "language": "python",
    }
    nb.cells = [nbformat.v4.new_code_cell(SLIDER_CELL)]
    for ui in UIS:  # a notebook per interface: each gets its own kernel session
        nbformat.write(nb, folder / f"sliders-{ui}.ipynb")
    home = tmp_path_factory.mktemp("home")  # a fresh Lab workspace: no restored layout
    with jupyterlab(folder, home) as (base, token):
        yield (
            {ui: f"{base}/{path}/sliders-{ui}.ipynb?token={token}" for ui, path in UIS.items()},
            folder,
        )


def _figure(page) -> str:
    """The ``src`` of the one image in the slider cell's output area."""
    images = page.query_selector_all(".jp-OutputArea-output img")
    assert len(images) == 1, f"expected one figure in the output area, found {len(images)}"
    return images[0].get_attribute("src") or ""


@pytest.mark.parametrize("ui", list(UIS))
def test_moving_a_slider_redraws_the_figure(lab, ui):
    urls, folder = lab
    url = urls[ui]
    with sync_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            page.goto(url)
            page.wait_for_selector(".jp-Notebook .jp-Cell", timeout=90_000)
            # Lab drops a run request made before its kernel connection is up (the cell
            # moves on and stays "[ ]"), so: run, and run again until the cell has started
            for _attempt in range(6):
                page.locator(".jp-Cell .jp-InputArea-editor").first.click()
                page.keyboard.press("Shift+Enter")
                try:
                    page.wait_for_function(
                        "/\\[(\\*|\\d+)\\]/.test(document.querySelector("
                        "'.jp-Cell .jp-InputPrompt').textContent)",
                        timeout=10_000,
                    )
                    break
                except sync_api.TimeoutError:
                    continue
            page.wait_for_selector(".widget-slider", timeout=90_000)
            page.wait_for_function(
                "document.querySelectorAll('.jp-OutputArea-output img').length > 0",
                timeout=60_000,
            )
            first = _figure(page)
            readouts = page.locator(".widget-readout")
            assert readouts.nth(1).inner_text() == "15.00"  # the outlier slider's default
            handle = page.locator(".widget-slider .noUi-handle").nth(1)
            # dragged with the mouse, as students do (in Notebook 7 the focused handle does
            # not answer the arrow keys; JupyterLab's does)
            box = handle.bounding_box()
            assert box is not None, "the outlier slider's handle is not on screen"
            x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
            page.mouse.move(x, y)
            page.mouse.down()
            page.mouse.move(x - 40, y, steps=5)
            page.mouse.up()
            page.wait_for_function(
                "([old]) => { const i = document.querySelectorAll("
                "'.jp-OutputArea-output img'); return i.length === 1 && i[0].src !== old; }",
                arg=[first],
                timeout=60_000,
            )
            assert float(readouts.nth(1).inner_text()) < 15.0
            second = _figure(page)
            assert second != first and second.startswith("data:image/png")
        except Exception:
            # what the student would have seen, and the server's side of it
            page.screenshot(path=str(folder / f"failure-{ui}.png"))
            outputs = page.locator(".jp-OutputArea").all_inner_texts()
            log = (folder / "lab.log").read_text()[-3000:]
            print(
                f"screenshot: {folder / f'failure-{ui}.png'}\noutput areas: {outputs}\nlab.log:\n{log}"
            )
            raise
        finally:
            browser.close()
