"""Build the course website: ``course docs OUT_DIR``.

The site is a Sphinx project (``docs/conf.py``) whose sources are the repository itself: the
pages under ``docs/``, the teaching notebooks in ``notebooks/`` (executed at build through
jupyter-cache, so only a notebook whose code changed runs again) and the student versions of
the assignments. ``OUT_DIR/index.html`` is the entry page; ``OUT_DIR/lite/`` holds a JupyterLite
app with the course's own wheel, so the notebooks run in a browser without installing.

Sphinx warnings are errors, and a notebook that raises fails the build.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["BuildReport", "build_lite", "build_site", "cache_stored_outputs", "find_root"]

REPO_ROOT = Path(__file__).resolve().parent.parent

#: The first cell of every notebook in JupyterLite: install the course from the site's own wheel.
LITE_INSTALL_CELL = "%pip install -q residual-validation-course"

#: Jupyter extensions of tools that are not part of the course (the grading benchmark's
#: peers): never bundled into the JupyterLite app, even from an environment that has them.
LITE_EXCLUDED_EXTENSIONS = ("nbgrader",)


@dataclass
class BuildReport:
    """What a build did: where the site is, which notebooks ran and how long it took."""

    out_dir: Path
    cache_dir: Path
    seconds: float
    executed: list[str] = field(default_factory=list)

    def summary(self) -> str:
        ran = ", ".join(self.executed) if self.executed else "none (all from the cache)"
        return (
            f"site built in {self.seconds:.0f} s: {self.out_dir / 'index.html'}\n"
            f"notebooks executed: {ran}\n"
            "To run the notebooks in the browser (JupyterLite), serve the folder over http "
            "(browsers do not start it from a file:// page):\n"
            f"  python -m http.server --directory {self.out_dir} 8000   "
            "then open http://localhost:8000/"
        )


def find_root(start: Path | None = None) -> Path:
    """The course clone: the nearest folder (from ``start`` up) with ``docs/conf.py`` and
    ``course/``; else the clone this package was installed from with ``pip install -e``."""
    start = Path.cwd() if start is None else Path(start)
    for folder in (start, *start.parents):
        if (folder / "docs" / "conf.py").is_file() and (folder / "course").is_dir():
            return folder
    if (REPO_ROOT / "docs" / "conf.py").is_file():
        return REPO_ROOT
    raise FileNotFoundError(
        "course docs: no docs/conf.py found; run it from a clone of the course repository"
    )


def default_cache(root: Path) -> Path:
    return root / ".cache" / "docs"


def _cached_records(cache_dir: Path) -> dict[int, str]:
    """Primary key -> notebook path of every executed notebook in the jupyter-cache."""
    path = cache_dir / "jupyter_cache"
    if not path.exists():
        return {}
    from jupyter_cache import get_cache

    return {record.pk: record.uri for record in get_cache(str(path)).list_cache_records()}


def cache_stored_outputs(root: Path, cache_dir: Path) -> list[str]:
    """Put the teaching notebooks, with the outputs saved in them, into the execution cache.

    The test suite checks with nbval that a fresh run of every committed teaching notebook
    reproduces its saved outputs, so those outputs are what the build would compute: the build
    (and CI, which runs nbval anyway) need not run each notebook a second time. A notebook
    with a code cell that was never run (no execution count; the widget cells that nbval skips
    aside) is left out and runs as usual, and the cache is keyed by the code, so a notebook
    edited later runs too. Widget cells show no output this way (a run shows their text form).
    Returns the notebooks added.
    """
    import nbformat
    from jupyter_cache import get_cache

    cache = get_cache(str(Path(cache_dir) / "jupyter_cache"))
    added = []
    for path in sorted(Path(root).glob("notebooks/*.ipynb")):
        notebook = nbformat.read(path, as_version=4)
        if not _saved_after_a_run(notebook):
            continue
        with contextlib.suppress(KeyError):  # KeyError: no cached run of this code yet
            cache.match_cache_notebook(notebook)
            continue
        # no check_validity: the skipped widget cells keep no execution count
        cache.cache_notebook_file(str(path), check_validity=False)
        added.append(path.relative_to(root).as_posix())
    return added


def _saved_after_a_run(notebook) -> bool:
    """Whether every code cell but nbval's skipped ones holds the count of a run."""
    return all(
        cell.get("execution_count") is not None
        or "nbval-skip" in cell.get("metadata", {}).get("tags", [])
        for cell in notebook.cells
        if cell.cell_type == "code"
    )


def build_site(
    out_dir: str | os.PathLike,
    *,
    root: str | os.PathLike | None = None,
    cache_dir: str | os.PathLike | None = None,
    jobs: int = 1,
    lite: bool = True,
    quiet: bool = False,
    stored_outputs: bool = False,
) -> BuildReport:
    """Build the website into ``out_dir``; raise ``RuntimeError`` when Sphinx fails.

    ``cache_dir`` keeps the executed notebooks and Sphinx's parsed pages between builds
    (default ``<clone>/.cache/docs``); it is never inside ``out_dir``, so a new output folder
    still reuses every notebook whose code did not change.

    ``stored_outputs``: show the outputs saved in the teaching notebooks instead of running
    them (see :func:`cache_stored_outputs`); a notebook with a cell never run still runs.
    """
    root = find_root() if root is None else Path(root).resolve()
    out = Path(out_dir).resolve()
    cache = default_cache(root) if cache_dir is None else Path(cache_dir).resolve()
    if cache == out or out in cache.parents:
        raise ValueError(f"cache_dir {cache} must not be inside out_dir {out}")
    cache.mkdir(parents=True, exist_ok=True)
    if stored_outputs:
        cache_stored_outputs(root, cache)
    before = _cached_records(cache)
    env = dict(os.environ)
    env["COURSE_DOCS_CACHE"] = str(cache)
    env["COURSE_DOCS_LITE"] = "1" if lite else "0"
    # The notebook kernels inherit this: small matrices, 2 shared cores.
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        env.setdefault(var, "1")
    env.setdefault("MPLBACKEND", "Agg")
    command = [
        sys.executable,
        "-m",
        "sphinx",
        "-b",
        "html",
        "-W",
        "--keep-going",
        # Write every page: reading stays incremental (only changed sources are parsed and
        # only changed notebooks run), but a page that links to an object that moved would
        # otherwise keep its old link.
        "-a",
        "-j",
        str(jobs),
        "-c",
        str(root / "docs"),
        "-d",
        str(cache / "doctrees"),
        str(root),
        str(out),
    ]
    if quiet:
        command.insert(3, "-q")
    start = time.perf_counter()
    completed = subprocess.run(command, cwd=root, env=env, check=False)
    seconds = time.perf_counter() - start
    if completed.returncode != 0:
        raise RuntimeError(
            f"the site build failed (sphinx-build exit code {completed.returncode}); "
            "its warnings and errors are printed above"
        )
    after = _cached_records(cache)
    executed = sorted(
        Path(uri).relative_to(root).as_posix() if Path(uri).is_relative_to(root) else uri
        for pk, uri in after.items()
        if pk not in before
    )
    return BuildReport(out_dir=out, cache_dir=cache, seconds=seconds, executed=executed)


def _joined(value):
    """A multi-line field of a notebook as one string (a list of lines joined), else as is."""
    if isinstance(value, list) and all(isinstance(line, str) for line in value):
        return "".join(value)
    return value


def _join_multiline_strings(notebook: dict) -> None:
    """Write every multi-line string of ``notebook`` as one string, in place.

    nbformat allows a cell's source, a stream's text and a text or image output as a list of
    lines; Jupyter joins them, but JupyterLite's contents shows such a list as its items
    separated by commas (a leading comma on every stored output line, jupyterlite#1105).
    """
    for cell in notebook.get("cells", []):
        cell["source"] = _joined(cell.get("source", ""))
        for output in cell.get("outputs", []):
            if "text" in output:
                output["text"] = _joined(output["text"])
            data = output.get("data", {})
            for mime, value in data.items():
                # JSON outputs are objects, not lines: only strings and lists of strings join.
                if not mime.endswith("json"):
                    data[mime] = _joined(value)


def _lite_notebook(source: Path, target: Path) -> None:
    """A copy of a teaching notebook whose first cell installs the course in the browser.

    Multi-line strings are joined, since JupyterLite would show their lines comma-separated.
    """
    notebook = json.loads(source.read_text(encoding="utf-8"))
    _join_multiline_strings(notebook)
    install: dict[str, Any] = {
        "cell_type": "code",
        "execution_count": None,
        "id": "install-course",
        "metadata": {"tags": ["jupyterlite-install"]},
        "outputs": [],
        "source": "# In the browser (JupyterLite) the course is installed from this site's own "
        f"wheel.\n{LITE_INSTALL_CELL}",
    }
    notebook["cells"].insert(0, install)
    target.write_text(json.dumps(notebook, indent=1, ensure_ascii=False), encoding="utf-8")


#: Served beside the JupyterLite app and loaded by each of its pages: without it a reader who
#: is offline, or who opened the site from ``file://``, sees a kernel error icon and no reason.
LITE_CHECK_SCRIPT = """\
// The course: tell the reader why Python cannot start in the browser, when it cannot.
(function () {
  var PYODIDE = "%(pyodide)s";
  function banner(html) {
    var show = function () {
      var box = document.createElement("div");
      box.id = "course-lite-problem";
      box.setAttribute("role", "alert");
      box.style.cssText = "position:fixed;top:0;left:0;right:0;z-index:10000;padding:0.8em 1em;" +
        "background:#fff3cd;color:#3d2e00;border-bottom:2px solid #b58900;font:15px/1.4 sans-serif";
      box.innerHTML = html;
      document.body.appendChild(box);
    };
    if (document.body) { show(); } else { document.addEventListener("DOMContentLoaded", show); }
  }
  if (location.protocol === "file:") {
    banner("<b>The notebooks cannot run from a file on disk.</b> Browsers do not let JupyterLite " +
      "start Python from a <code>file://</code> page. Serve the site folder over http: " +
      "<code>python -m http.server --directory SITE_FOLDER 8000</code>, then open " +
      "<code>http://localhost:8000/</code>.");
    return;
  }
  var failed = function () {
    banner("<b>Python could not be loaded into the browser.</b> The in-browser kernel " +
      "downloads Python (Pyodide, about 30 MB) from " + PYODIDE.split("/")[2] + " the first " +
      "time, and that failed: are you offline? The notebook pages of the course site show " +
      "every output without running anything; to run the notebooks offline, install the course " +
      "and use <code>course open</code>.");
  };
  if (navigator.onLine === false) { failed(); return; }
  var timer = new Promise(function (_, reject) { setTimeout(reject, 15000); });
  Promise.race([fetch(PYODIDE + "/pyodide.mjs", {method: "HEAD", mode: "no-cors"}), timer])
    .catch(failed);
})();
"""


def _pyodide_url() -> str:
    """Where the JupyterLite kernel loads Pyodide from (the kernel package's default CDN)."""
    try:
        from jupyterlite_pyodide_kernel.constants import PYODIDE_CDN_URL
    except ImportError:  # an older kernel package: the check still explains file:// pages
        return "https://cdn.jsdelivr.net/pyodide"
    return str(PYODIDE_CDN_URL)


def add_lite_check(lite_dir: Path) -> list[Path]:
    """Add the reader-facing check of :data:`LITE_CHECK_SCRIPT` to every page of the app."""
    script = lite_dir / "course-lite-check.js"
    script.write_text(LITE_CHECK_SCRIPT % {"pyodide": _pyodide_url()}, encoding="utf-8")
    pages = []
    for page in sorted(lite_dir.glob("*/index.html")):
        html = page.read_text(encoding="utf-8")
        tag = '<script src="../course-lite-check.js"></script>'
        if tag not in html and "</head>" in html:
            page.write_text(html.replace("</head>", f"{tag}\n</head>", 1), encoding="utf-8")
            pages.append(page)
    return pages


def build_lite(root: Path, site_dir: Path, cache: Path, notebooks: list[Path]) -> Path:
    """Build the JupyterLite app into ``site_dir/lite`` with the course's wheel and notebooks.

    The Pyodide kernel itself (Python compiled to WebAssembly, with numpy, scipy and
    matplotlib) is not part of the site: the browser loads it from Pyodide's CDN the first
    time a notebook runs.
    """
    work = cache / "lite"
    # The wheel is built again only when what goes into it changed (not for a notebook edit).
    wheels = work / "wheels" / _wheel_inputs_digest(root)
    contents = work / "contents"
    extensions = work / "labextensions"
    for folder in (contents, extensions):
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
    # the environment's extensions, those of non-course tools left out (jupyter lite would
    # take every one under sys.prefix: see ignore_sys_prefix below)
    installed = Path(sys.prefix) / "share" / "jupyter" / "labextensions"
    for extension in lite_extensions():
        shutil.copytree(extension, extensions / extension.relative_to(installed))
    if not any(wheels.glob("*.whl")):
        shutil.rmtree(wheels.parent, ignore_errors=True)
        wheels.mkdir(parents=True)
        # pip builds in a temporary copy so that the clone gets no build/ or egg-info folders.
        with tempfile.TemporaryDirectory() as tmp:
            copy = Path(tmp) / "src"
            shutil.copytree(
                root,
                copy,
                ignore=shutil.ignore_patterns(
                    ".git", ".cache", ".venv*", "build", "dist", "*.egg-info", "__pycache__"
                ),
                symlinks=True,
            )
            command = [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w"]
            _run([*command, str(wheels), str(copy)])
    wheel = next(wheels.glob("*.whl"))
    for notebook in notebooks:
        _lite_notebook(notebook, contents / notebook.name)
    config = {
        "LiteBuildConfig": {
            "apps": ["lab", "notebooks"],
            "no_sourcemaps": True,
            "contents": [str(contents)],
            "output_dir": str(site_dir / "lite"),
            "ignore_sys_prefix": ["federated_extensions"],
        },
        "FederatedExtensionAddon": {"extra_labextensions_path": [str(extensions)]},
        "PipliteAddon": {"piplite_urls": [str(wheel)]},
    }
    (work / "jupyter_lite_config.json").write_text(json.dumps(config, indent=1))
    _run([sys.executable, "-m", "jupyter", "lite", "build", "--lite-dir", str(work)], cwd=work)
    add_lite_check(site_dir / "lite")
    return site_dir / "lite"


def lite_extensions(prefix: Path | None = None) -> list[Path]:
    """The prebuilt JupyterLab extensions of the environment ``prefix`` (default: this one)
    that the JupyterLite app bundles: their folders, without :data:`LITE_EXCLUDED_EXTENSIONS`."""
    root = Path(sys.prefix if prefix is None else prefix) / "share" / "jupyter" / "labextensions"
    found = sorted([*root.glob("*/package.json"), *root.glob("@*/*/package.json")])
    return [
        p.parent
        for p in found
        if not any(
            word in p.parent.relative_to(root).as_posix() for word in LITE_EXCLUDED_EXTENSIONS
        )
    ]


def _wheel_inputs_digest(root: Path) -> str:
    """A digest of everything the course's wheel is built from: the package and the files
    ``pyproject.toml`` names (its readme and licence)."""
    digest = hashlib.sha256()
    files = [root / name for name in ("pyproject.toml", "README.md", "LICENSE")]
    files += sorted(p for p in (root / "course").rglob("*") if "__pycache__" not in p.parts)
    for path in files:
        if path.is_file():
            digest.update(path.relative_to(root).as_posix().encode() + b"\0")
            digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def _run(command: list[str], cwd: Path | None = None) -> None:
    completed = subprocess.run(command, cwd=cwd, capture_output=True, text=True, check=False)
    if completed.returncode != 0:
        raise RuntimeError(
            f"{' '.join(command[:4])} ... failed:\n{completed.stdout[-3000:]}\n"
            f"{completed.stderr[-3000:]}"
        )
