"""Sphinx configuration of the course website (built by ``course docs OUT_DIR``).

The source folder is the repository root, not ``docs/``: notebooks, assignments and pages keep
the paths they have in the repository, so a link that works in Jupyter or on a code host
(``../docs/bibliography.md`` from a notebook, ``../../notebooks/01_...ipynb`` from a page) also
works on the site. ``include_patterns`` says what of the repository becomes a page.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import course

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))

import course_site  # noqa: E402  (the course's own extension, found through the line above)

#: Where executed notebooks are cached (jupyter-cache); never inside the output folder.
CACHE = Path(os.environ.get("COURSE_DOCS_CACHE", DOCS.parent / ".cache" / "docs"))

project = "Validating models with residuals"
author = "the course's authors"
copyright = "the course's authors"
release = version = course.__version__

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",  # "[source]" beside each object of the API reference
    "numpydoc",
    "course_site",
]

root_doc = "docs/index"
# Only these become pages; everything else in the repository is not a source.
include_patterns = [
    "docs/**",
    "notebooks/*.ipynb",
    "exercises/*/*.ipynb",  # the student versions; solutions/ is never a source
]
exclude_patterns = [
    "docs/_build/**",
    "docs/_ext/**",
    "**/.ipynb_checkpoints/**",
    "solutions/**",
    # Not ".*/**": Sphinx also matches that against "./course.css" when copying static files.
    ".git/**",
    ".cache/**",
    ".venv*/**",
    "build/**",
    "dist/**",
]
# Module docstrings list their sources as citations and cite them in running text ("[F],
# eq. 4") rather than as reST citation references; that is not an error.
suppress_warnings = ["ref.citation"]
# Toctree globs of sections that may still be empty (course_site drops only these warnings).
course_site_optional_globs = ["students/*", "instructors/*", "*"]

# -- Notebooks (myst-nb) ----------------------------------------------------------------------
# Executed at build through jupyter-cache: a notebook runs again only when its code changed,
# and the build fails when one raises.
nb_execution_mode = "cache"
nb_execution_cache_path = str(CACHE / "jupyter_cache")
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_execution_timeout = 600
nb_execution_excludepatterns = ["exercises/*/*.ipynb"]  # student versions: stubs raise by design
nb_merge_streams = True
# Staging of the notebooks' figures, in the cache: myst-nb would write them beside the output
# folder (course_site.keep_outputs_in_cache), in the repository when the site is built into it.
course_site_output_folder = str(CACHE / "jupyter_execute")
# Widgets need a live kernel; their JavaScript would come from a CDN. Pages show the text form.
nb_ipywidgets_js: dict = {}
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist", "substitution"]
myst_heading_anchors = 3
# Figures of a notebook get their caption, alt text and label from the metadata of the cell that
# draws them ({"mystnb": {"figure": {"caption", "name"}, "image": {"alt"}}}); the prose links them
# in plain Markdown, [the figure above](#fig-...), which Jupyter shows as written and the site as
# "Figure 7.3", numbered per notebook (course_site).
numfig = True
numfig_format = {"figure": "Figure %s"}
course_site_notebooks = ["notebooks/*.ipynb"]
course_site_assignments = ["exercises/*/*.ipynb"]  # in the teaching map too
# The JupyterLite app (OUT/lite); COURSE_DOCS_LITE=0 skips it (course docs --no-lite).
course_site_lite = os.environ.get("COURSE_DOCS_LITE", "1") != "0"

# -- API reference (autosummary tables + numpydoc) -------------------------------------------
# One page per public namespace (course_site writes them): a module reads as a chapter, and
# the site stays small enough to check every page in a browser within CI's budget.
autosummary_generate = False
autodoc_typehints = "none"  # numpydoc's Parameters section carries the types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# -- Maths: MathJax 3 served from the site (see course_site.copy_mathjax) ----------------------
mathjax_path = "mathjax/tex-chtml.js"

# -- HTML ----------------------------------------------------------------------------------------
html_theme = "sphinx_book_theme"
html_title = project
html_static_path = [str(DOCS / "_static")]
html_css_files = ["course.css"]
html_js_files = ["course.js"]
html_favicon = str(DOCS / "_static" / "favicon.svg")  # else browsers ask for /favicon.ico
html_theme_options = {
    "use_download_button": True,
    "use_fullscreen_button": False,
    "show_toc_level": 2,
    "home_page_in_toc": True,
    "navigation_with_keys": False,
}
# Binder and Colab launch buttons on notebook pages, once the course has a public repository:
# set its URL (e.g. "https://github.com/OWNER/REPO") and branch here.
repository_url = ""
repository_branch = "main"
html_theme_options.update(course_site.launch_options(repository_url, repository_branch))
html_context = {"default_mode": "auto"}  # an empty mode makes the theme log a console error
html_last_updated_fmt = None
html_copy_source = True  # the download button offers the .ipynb and .md sources
