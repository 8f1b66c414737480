"""The course website, built by ``course docs`` and checked in a real browser.

The site is built from a copy of the repository into a temporary folder, with its own
notebook cache seeded with the outputs saved in the teaching notebooks (``stored_outputs``:
nbval, in the same suite, checks that a fresh run reproduces them, so the build need not run
each notebook a second time), served on 127.0.0.1 and visited with Debian's Chromium through
Playwright. Screenshots of the landing
page and of a notebook page are saved under the test's temporary folder (printed at the end;
set ``COURSE_WEBSITE_ARTIFACTS=DIR`` to keep them in DIR instead).

Skipped, with the reason, when Chromium or the docs extra is not installed: install them with
``apt-get install chromium`` and ``python -m pip install -e ".[docs]"``.
"""

from __future__ import annotations

import functools
import http.server
import json
import os
import re
import shutil
import threading
import time
import uuid
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urldefrag, urlparse

import pytest
from browser import CHROMIUM_ARGS, chromium_or_skip

pytestmark = pytest.mark.browser

ROOT = Path(__file__).resolve().parent.parent
CHROMIUM = chromium_or_skip()
pytest.importorskip("sphinx", reason='the docs extra is not installed (pip install -e ".[docs]")')
sync_api = pytest.importorskip(
    "playwright.sync_api", reason='the docs extra is not installed (pip install -e ".[docs]")'
)

from course.docsite import LITE_INSTALL_CELL, build_site  # noqa: E402

# Where the incremental-build test adds a cell: the quickest teaching notebook to re-run.
INCREMENTAL_NOTEBOOK = "notebooks/03_parameter_estimation_and_likelihood.ipynb"


# -- Build and serve ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("website")


@pytest.fixture(scope="module")
def source(workdir) -> Path:
    """A copy of the repository, so the incremental test can edit a notebook."""
    copy = workdir / "src"
    shutil.copytree(
        ROOT,
        copy,
        ignore=shutil.ignore_patterns(
            ".git", ".cache", ".venv*", "build", "dist", "*.egg-info", "__pycache__", "_build"
        ),
    )
    return copy


@pytest.fixture(scope="module")
def site(source, workdir):
    # COURSE_WEBSITE_CACHE=DIR keeps the cache between runs of this test (local iteration).
    cache = Path(os.environ.get("COURSE_WEBSITE_CACHE") or workdir / "cache")
    report = build_site(
        workdir / "site", root=source, cache_dir=cache, quiet=True, stored_outputs=True
    )
    print(report.summary())
    return report


def test_the_build_writes_nothing_beside_its_output_folder(site):
    """myst-nb's default puts the notebooks' images in ``<out>/../jupyter_execute``: in the
    repository when the site is built into it, as the README says (issue 39)."""
    assert not (site.out_dir.parent / "jupyter_execute").exists()


def test_no_page_embeds_widget_state_that_nothing_renders(site):
    """The site loads no widget JavaScript (conf.py), so a slider's saved state is dead weight."""
    heavy = [
        page.name
        for page in (site.out_dir / "notebooks").glob("*.html")
        if "application/vnd.jupyter.widget-state+json" in page.read_text(encoding="utf-8")
    ]
    assert not heavy, heavy


def test_the_build_shows_the_saved_outputs_without_running_notebooks(site):
    """Each teaching notebook runs once in the suite (nbval), not again for the website."""
    assert site.executed == [], f"the build ran {site.executed}: is the seeded cache missed?"


@pytest.fixture(scope="module")
def server(site):
    handler = functools.partial(_QuietHandler, directory=str(site.out_dir))
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}/"
    httpd.shutdown()
    httpd.server_close()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


@pytest.fixture(scope="module")
def browser(server):
    with sync_api.sync_playwright() as playwright:
        # Playwright gives every launch a fresh, empty profile (user data dir).
        chromium = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield chromium
        chromium.close()


@pytest.fixture(scope="module")
def artifacts(workdir) -> Path:
    folder = Path(os.environ.get("COURSE_WEBSITE_ARTIFACTS") or workdir / "screenshots")
    folder.mkdir(parents=True, exist_ok=True)
    return folder


# -- Crawl every page once --------------------------------------------------------------------------


class _Links(HTMLParser):
    def __init__(self):
        super().__init__()
        self.hrefs: list[str] = []
        self.ids: set[str] = set()

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        for key in ("id", "name"):
            if attrs.get(key):
                self.ids.add(attrs[key])
        if tag == "a" and attrs.get("href"):
            self.hrefs.append(attrs["href"])
        if tag in ("link", "script", "img") and (attrs.get("href") or attrs.get("src")):
            self.hrefs.append(attrs.get("href") or attrs.get("src"))


def _parsed(cache: dict[Path, _Links], path: Path) -> _Links:
    """Each page parsed once (a module page is large and linked to many times)."""
    if path not in cache:
        cache[path] = _parse(path)
    return cache[path]


def _parse(path: Path) -> _Links:
    parser = _Links()
    parser.feed(path.read_text(encoding="utf-8", errors="replace"))
    return parser


@dataclass
class PageVisit:
    """What the browser saw on one page."""

    console_errors: list[str] = field(default_factory=list)
    failed_requests: list[str] = field(default_factory=list)
    maths: int = 0  # elements Sphinx marked as maths
    typeset: int = 0  # of those, how many MathJax turned into mjx-container
    math_errors: int = 0  # TeX MathJax could not parse
    images: list = field(default_factory=list)  # [src, loaded] of every notebook output image


def _html_pages(site_dir: Path) -> list[str]:
    """Every page of the Sphinx site (the JupyterLite app under lite/ is checked apart)."""
    return sorted(
        p.relative_to(site_dir).as_posix()
        for p in site_dir.rglob("*.html")
        if not p.relative_to(site_dir).as_posix().startswith(("lite/", "_static/"))
    )


MATH_CHECK = """async () => {
  const maths = document.querySelectorAll('.math');
  if (maths.length === 0) return [0, 0, 0];
  for (let i = 0; i < 100 && !(window.MathJax && MathJax.startup && MathJax.startup.promise); i++)
    await new Promise(r => setTimeout(r, 100));
  if (window.MathJax && MathJax.startup) await MathJax.startup.promise;
  let typeset = 0;
  for (const m of maths) if (m.querySelector('mjx-container') || m.tagName === 'MJX-CONTAINER') typeset++;
  return [maths.length, typeset, document.querySelectorAll('mjx-merror').length];
}"""

#: Displayed width over drawn width of every loaded figure of a notebook page.
FIGURE_SCALES = """() => Array.from(document.querySelectorAll('.cell_output img'))
  .filter(img => img.naturalWidth > 0)
  .map(img => img.getBoundingClientRect().width / img.naturalWidth)"""

IMAGE_CHECK = """() => Array.from(document.querySelectorAll('.cell_output img')).map(
  img => [img.getAttribute('src'), img.complete && img.naturalWidth > 0])"""


@pytest.fixture(scope="module")
def visits(site, server, browser) -> dict[str, PageVisit]:
    """Every page of the site, loaded once in Chromium."""
    context = browser.new_context()
    result = {}
    for rel in _html_pages(site.out_dir):
        if rel == "index.html":
            continue  # forwards to docs/index.html (checked in the screenshot test)
        visit = PageVisit()
        page = context.new_page()
        page.on(
            "console",
            lambda m, v=visit: v.console_errors.append(m.text) if m.type == "error" else None,
        )
        page.on("pageerror", lambda e, v=visit: v.console_errors.append(str(e)))
        page.on("requestfailed", lambda r, v=visit: v.failed_requests.append(r.url))
        page.on(
            "response",
            lambda r, v=visit: (
                v.failed_requests.append(f"{r.status} {r.url}") if r.status >= 400 else None
            ),
        )
        page.goto(server + rel, wait_until="load")
        visit.maths, visit.typeset, visit.math_errors = page.evaluate(MATH_CHECK)
        visit.images = page.evaluate(IMAGE_CHECK)
        page.close()
        result[rel] = visit
    context.close()
    return result


# -- The checks -----------------------------------------------------------------------------------


def test_every_page_loads_without_console_errors(visits):
    assert len(visits) > 25, f"only {len(visits)} pages: is the API reference missing?"
    bad = {
        rel: v.console_errors + v.failed_requests
        for rel, v in visits.items()
        if v.console_errors or v.failed_requests
    }
    assert not bad, f"pages with console errors or failed requests: {bad}"


def test_every_internal_link_resolves(site):
    """Every href/src of every page points at a file of the site, and every #anchor exists."""
    out = site.out_dir
    parsed: dict[Path, _Links] = {}
    broken = []
    for rel in _html_pages(out):
        page = out / rel
        links = _parsed(parsed, page)
        for href in links.hrefs:
            url, fragment = urldefrag(href)
            if urlparse(href).scheme or href.startswith(("//", "mailto:", "javascript:")):
                continue  # external: none may be needed to read the site (next test)
            target = (page.parent / unquote(urlparse(url).path)).resolve() if url else page
            if target.is_dir():
                target = target / "index.html"
            if not target.is_file():
                broken.append(f"{rel}: {href}")
                continue
            if fragment and target.suffix == ".html":
                ids = _parsed(parsed, target).ids
                if fragment not in ids:
                    broken.append(f"{rel}: {href} (no #{fragment})")
    assert not broken, f"{len(broken)} broken internal links: {broken[:30]}"


def test_no_resource_comes_from_outside_the_site(site):
    """Scripts, styles, fonts and images are served by the site itself (it works offline)."""
    outside = set()
    for rel in _html_pages(site.out_dir):
        page = site.out_dir / rel
        text = page.read_text(encoding="utf-8")
        for match in re.finditer(
            r'<(?:script|link|img)[^>]+(?:src|href)="(https?:)?//([^"/]+)', text
        ):
            outside.add(f"{rel}: {match.group(2)}")
    assert not outside, sorted(outside)[:20]


def test_formulas_are_typeset(visits):
    with_math = {rel: v for rel, v in visits.items() if v.maths}
    assert any(rel.startswith("notebooks/") for rel in with_math), "no notebook page has maths"
    assert any(rel.startswith("docs/api/") for rel in with_math), "no API page has maths"
    untypeset = {
        rel: f"{v.typeset}/{v.maths} typeset, {v.math_errors} TeX errors"
        for rel, v in with_math.items()
        if v.typeset < v.maths or v.math_errors
    }
    assert not untypeset, untypeset


def test_every_notebook_page_shows_its_figures(site, visits):
    notebooks = sorted((site.out_dir / "notebooks").glob("*.html"))
    assert len(notebooks) >= 6
    for page in notebooks:
        rel = page.relative_to(site.out_dir).as_posix()
        source = json.loads((ROOT / "notebooks" / f"{page.stem}.ipynb").read_text())
        expected = sum(
            "image/png" in output.get("data", {})
            for cell in source["cells"]
            for output in cell.get("outputs", [])
        )
        images = visits[rel].images
        assert len(images) >= max(expected, 1), f"{rel}: {len(images)} figures, expected {expected}"
        assert all(loaded for _, loaded in images), f"{rel}: figures that did not load {images}"


_IMG = re.compile(r"<img\b[^>]*>")
_ATTR = re.compile(r'(\w+)="([^"]*)"')
_HASH_NAME = re.compile(r"^[0-9a-f]{16,}(\.\w+)?$")


def test_notebook_figures_have_alt_text_numbered_captions_and_references(site):
    """No figure is announced to a screen reader by a file hash; figures are numbered and cited."""
    pages = sorted((site.out_dir / "notebooks").glob("*.html"))
    assert len(pages) >= 6
    hashed, unnumbered, uncited = {}, [], []
    for page in pages:
        text = page.read_text(encoding="utf-8")
        article = text[text.index('<article class="bd-article"') :]
        alts = [dict(_ATTR.findall(tag)).get("alt", "") for tag in _IMG.findall(article)]
        bad = [alt for alt in alts if not alt.strip() or _HASH_NAME.match(alt.strip())]
        if bad:
            hashed[page.name] = bad
        numbers = re.findall(r'<span class="caption-number">Figure (\d+[a-z]?\.\d+)', article)
        if len(numbers) < len(alts):  # every figure of the page numbered and captioned
            unnumbered.append(f"{page.name}: {len(numbers)} numbered of {len(alts)}")
        # numbered per notebook, from its own number: 07_... has Figure 7.1, 7.2, ... (issue 39)
        prefix = re.match(r"0*(\d+[a-z]?)_", page.name).group(1)  # type: ignore[union-attr]
        if numbers != [f"{prefix}.{k}" for k in range(1, len(numbers) + 1)]:
            unnumbered.append(f"{page.name}: numbered {numbers}, not from {prefix}.1 on")
        cited = re.findall(
            r'<a class="reference internal" href="#fig-[^"]+"><span class="std std-numref">Figure',
            article,
        )
        if not cited:
            uncited.append(page.name)
    assert not hashed, f"images whose alt text is empty or a file hash: {hashed}"
    assert not unnumbered, f"figures without a numbered caption: {unnumbered}"
    assert not uncited, f"notebook pages whose prose cites no figure by number: {uncited}"


def test_answers_are_hidden_until_opened(site):
    """An exercise's answers (admonitions of class dropdown) are closed <details> boxes."""
    text = (site.out_dir / "notebooks/06_mismatched_filters.html").read_text(encoding="utf-8")
    boxes = re.findall(r"<details class=\"admonition dropdown[^\"]*\"( open)?>", text)
    assert len(boxes) >= 2 and not any(boxes), boxes
    assert '<summary class="admonition-title">Answer to 1</summary>' in text


@pytest.mark.parametrize(
    "module",
    [
        "course.nis",
        "course.chi2",
        "course.lsq",
        "course.filters",
        "course.mismatched",
        "course.diagnosis",
    ],
)
def test_api_pages_typeset_their_formulas(visits, module):
    """The Notes of the API reference are maths, not ASCII formulas in code literals."""
    visit = visits[f"docs/api/modules/{module}.html"]
    assert visit.maths >= 3 and visit.typeset == visit.maths, (visit.maths, visit.typeset)


def test_search_finds_the_w_test(server, browser):
    page = browser.new_page()
    page.goto(server + "search.html?q=w-test", wait_until="load")
    page.wait_for_selector("#search-results li", timeout=30_000)
    hits = page.eval_on_selector_all("#search-results li a", "els => els.map(a => a.href)")
    page.close()
    assert any("course.lsq" in hit or "01_least_squares" in hit for hit in hits), hits


def test_screenshots_of_landing_and_notebook_page(server, browser, artifacts):
    page = browser.new_page(viewport={"width": 1280, "height": 900})
    page.goto(server, wait_until="networkidle")  # index.html forwards to the landing page
    assert page.url.endswith("docs/index.html")
    assert "Learning path" in page.inner_text("body")
    page.screenshot(path=str(artifacts / "landing.png"))
    page.goto(server + "notebooks/01_least_squares_validation.html", wait_until="networkidle")
    page.wait_for_selector("mjx-container", state="attached")  # typeset (some sit in folded toc)
    page.screenshot(path=str(artifacts / "notebook-01.png"))
    page.close()
    for name in ("landing.png", "notebook-01.png"):
        assert (artifacts / name).stat().st_size > 10_000
    print(f"screenshots in {artifacts}")


def test_assignments_appear_only_as_student_versions(site):
    assert not (site.out_dir / "solutions").exists()
    pages = list((site.out_dir / "exercises").rglob("*.html"))
    assert len(pages) >= 6
    for folder in ("exercises", "notebooks"):  # the authoring guide may explain the markers
        for page in (site.out_dir / folder).rglob("*.html"):
            assert "BEGIN SOLUTION" not in page.read_text(encoding="utf-8"), page


def test_api_pages_name_the_notebooks_that_use_them(site):
    page = (site.out_dir / "docs/api/modules/course.lsq.html").read_text()
    w_tests = page[page.index('id="course.lsq.w_tests"') :]
    end = w_tests.find('<dl class="py', 1)  # up to the next documented object, if any
    w_tests = w_tests if end < 0 else w_tests[:end]
    assert "seealso" in w_tests and "01_least_squares_validation.html" in w_tests
    notebook = (site.out_dir / "notebooks/01_least_squares_validation.html").read_text()
    assert "course.lsq.html#course.lsq.w_tests" in notebook


def test_jupyterlite_has_the_course_wheel_and_the_notebooks(site, server, browser):
    lite = site.out_dir / "lite"
    wheels = json.loads((lite / "pypi" / "all.json").read_text())
    assert "residual-validation-course" in wheels or "residual_validation_course" in wheels
    contents = json.loads((lite / "api" / "contents" / "all.json").read_text())
    names = {item["name"] for item in contents["content"]}
    assert "01_least_squares_validation.ipynb" in names
    first = json.loads((lite / "files" / "01_least_squares_validation.ipynb").read_text())
    assert LITE_INSTALL_CELL in "".join(first["cells"][0]["source"])
    # the course's extensions only: no nbgrader menus beside the course (issue 23)
    config = json.loads((lite / "jupyter-lite.json").read_text())["jupyter-config-data"]
    bundled = [e["name"] for e in config.get("federated_extensions", [])]
    assert "@jupyterlite/pyodide-kernel-extension" in bundled
    assert not [name for name in bundled if "nbgrader" in name], bundled
    # The app itself loads; running code needs Pyodide from its CDN, which this test cannot reach.
    page = browser.new_page()
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(server + "lite/lab/index.html", wait_until="load")
    page.wait_for_selector("#jp-main-dock-panel", timeout=60_000)
    page.close()
    assert not errors, errors


#: Pages read on a phone: the landing page, a notebook, an API chapter and a guide with tables.
NARROW_PAGES = [
    "docs/index.html",
    "notebooks/01_least_squares_validation.html",
    "docs/api/modules/course.lsq.html",
    "docs/instructors/term.html",
]


def test_pages_do_not_scroll_sideways_at_400_px(server, browser):
    page = browser.new_page(viewport={"width": 400, "height": 800})
    wide = {}
    for rel in NARROW_PAGES:
        page.goto(server + rel, wait_until="load")
        width = page.evaluate("() => document.documentElement.scrollWidth")
        if width > 401:
            wide[rel] = width
    # On a phone a figure is scaled to the column (none half hidden in a box without a cue to
    # scroll, issue 39) and a tap opens it at full size.
    page.goto(server + "notebooks/01_least_squares_validation.html", wait_until="load")
    figures = page.evaluate(
        "() => Array.from(document.querySelectorAll('.bd-article .cell_output img')).map(i => ({"
        "fits: i.getBoundingClientRect().right <= document.documentElement.clientWidth + 1,"
        "link: (i.closest('a[href]') || {}).href || ''}))"
    )
    page.close()
    assert not wide, f"pages wider than a 400 px screen (scrollWidth): {wide}"
    assert figures and all(f["fits"] for f in figures), f"figures cut at 400 px: {figures}"
    assert all(f["link"].endswith((".png", ".svg", ".jpg")) for f in figures), figures


#: npm's axe-core, the test's own copy: .ci/run installs it (npm install axe-core) and names its
#: axe.min.js in COURSE_AXE_CORE; locally ``npm install --prefix .cache/axe axe-core@4``.
AXE = Path(
    os.environ.get("COURSE_AXE_CORE")
    or ROOT / ".cache" / "axe" / "node_modules" / "axe-core" / "axe.min.js"
)
#: One page of each type: home, a notebook, an API chapter, the instructors' guide.
AXE_PAGES = [
    "docs/index.html",
    "notebooks/07_testing_theory.html",
    "docs/api/modules/course.lsq.html",
    "docs/instructors/term.html",
]
AXE_RUN = """async () => (await axe.run(document, {resultTypes: ['violations']})).violations
    .map(v => ({id: v.id, impact: v.impact, nodes: v.nodes.slice(0, 3).map(n => n.html)}))"""


@pytest.mark.parametrize("rel", AXE_PAGES)
def test_no_serious_or_critical_accessibility_violations(server, browser, rel):
    """axe-core in Chromium finds no serious or critical violation (issue 39)."""
    if not AXE.is_file():
        reason = f"axe-core is not installed at {AXE} (see AXE in this file)"
        if os.environ.get("COURSE_REQUIRE_BROWSER"):  # .ci/run installs it
            pytest.fail(reason, pytrace=False)
        pytest.skip(reason)
    page = browser.new_page(viewport={"width": 1280, "height": 900})
    page.goto(server + rel, wait_until="load")
    page.add_script_tag(path=str(AXE))
    violations = page.evaluate(AXE_RUN)
    page.close()
    serious = [v for v in violations if v["impact"] in ("serious", "critical")]
    assert not serious, f"{rel}: {json.dumps(serious, indent=1)}"


def test_figures_show_near_their_drawn_size(server, browser):
    """A figure drawn wider than the content column shrinks, and its labels with it."""
    page = browser.new_page(viewport={"width": 1280, "height": 900})
    small = {}
    for html in sorted((ROOT / "notebooks").glob("*.ipynb")):
        rel = f"notebooks/{html.stem}.html"
        page.goto(server + rel, wait_until="load")
        scales = page.evaluate(FIGURE_SCALES)
        shrunk = [round(scale, 2) for scale in scales if scale < 0.75]
        if shrunk:
            small[rel] = shrunk
    page.close()
    assert not small, f"figures shown below 75 % of their size at desktop width: {small}"


def test_jupyterlite_shows_stored_outputs_without_list_commas(site):
    """jupyterlite#1105: outputs stored as lists of lines showed as 'line1\\n,line2'."""
    copy = json.loads(
        (site.out_dir / "lite" / "files" / "01_least_squares_validation.ipynb").read_text()
    )
    fields = [cell["source"] for cell in copy["cells"]]
    for cell in copy["cells"]:
        for output in cell.get("outputs", []):
            fields += [output.get("text", "")]
            fields += [v for k, v in output.get("data", {}).items() if not k.endswith("json")]
    assert fields and all(isinstance(value, str) for value in fields)


def test_jupyterlite_says_why_python_cannot_start(server, browser, site):
    """Offline, and from a file:// page, the reader gets a reason instead of an error icon."""
    page = browser.new_page()
    # Python comes from Pyodide's CDN: refuse it, as a machine without internet would.
    page.route("https://cdn.jsdelivr.net/**", lambda route: route.abort())
    page.goto(server + "lite/lab/index.html", wait_until="load")
    banner = page.wait_for_selector("#course-lite-problem", timeout=30_000)
    assert "Python could not be loaded" in banner.inner_text()
    assert "course open" in banner.inner_text()
    page.goto((site.out_dir / "lite" / "lab" / "index.html").as_uri(), wait_until="load")
    banner = page.wait_for_selector("#course-lite-problem", timeout=10_000)
    assert "file" in banner.inner_text() and "http.server" in banner.inner_text()
    page.goto((site.out_dir / "notebooks" / "01_least_squares_validation.html").as_uri())
    launch = page.inner_text("p.course-launch")
    page.close()
    assert "http.server" in launch and "Run this notebook" not in launch


def test_incremental_build_reexecutes_only_the_changed_notebook(site, source):
    marker = f"incremental build check {uuid.uuid4().hex[:8]}"  # new code: never in a cache
    notebook_path = source / INCREMENTAL_NOTEBOOK
    notebook = json.loads(notebook_path.read_text())
    notebook["cells"].append(
        {
            "cell_type": "code",
            "execution_count": None,
            "id": "incremental-build-check",
            "metadata": {},
            "outputs": [],
            "source": [f"print({marker!r})"],
        }
    )
    notebook_path.write_text(json.dumps(notebook, indent=1))
    start = time.perf_counter()
    report = build_site(site.out_dir, root=source, cache_dir=site.cache_dir, quiet=True)
    print(f"incremental rebuild: {time.perf_counter() - start:.0f} s; {report.summary()}")
    assert report.executed == [INCREMENTAL_NOTEBOOK]
    page = site.out_dir / "notebooks" / (Path(INCREMENTAL_NOTEBOOK).stem + ".html")
    assert marker in page.read_text()
