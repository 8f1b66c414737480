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
            f"notebooks executed: {ran}"
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


def _lite_notebook(source: Path, target: Path) -> None:
    """A copy of a teaching notebook whose first cell installs the course in the browser."""
    notebook = json.loads(source.read_text(encoding="utf-8"))
    install = {
        "cell_type": "code",
        "execution_count": None,
        "id": "install-course",
        "metadata": {"tags": ["jupyterlite-install"]},
        "outputs": [],
        "source": [
            "# In the browser (JupyterLite) the course is installed from this site's own wheel.\n",
            LITE_INSTALL_CELL,
        ],
    }
    notebook["cells"].insert(0, install)
    target.write_text(json.dumps(notebook, indent=1, ensure_ascii=False), encoding="utf-8")


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
