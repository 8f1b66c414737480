"""Sphinx extension that turns the course's repository into its website.

What it adds to a plain Sphinx + myst-nb + numpydoc build:

* **API pages from the public names.** One page per public namespace (every name in
  ``course.__all__``, plus the submodules of ``course.plotting``) documenting that namespace's
  ``__all__``. Only public names are used, so moving a
  function between private submodules (a module becoming a package) changes no page.
* **Teaching map.** Every code cell of every notebook on the site is parsed (``ast``) for the
  ``course`` names it uses; each public object's docstring then gets a "See also" entry naming
  the notebooks that use it, and each notebook page a list of the API it uses. Nothing is
  maintained by hand: a new notebook or a new import shows up at the next build.
* **Run in the browser.** A link on every notebook page to the same notebook in the site's
  JupyterLite (see ``course.docsite``), built at the end of the Sphinx build.
* **Offline maths.** MathJax 3 is served from the site itself (the ``django-static-mathjax``
  wheel ships it), so formulas are typeset without reaching a CDN.
* **Entry page.** ``OUT/index.html`` forwards to the landing page ``docs/index.html``.
* **Several numbered figures from one cell.** myst-nb gives every output of a cell the same
  figure options, so a cell that draws two figures cannot name both. Its metadata may list
  them instead, ``{"course": {"figures": [{"name", "caption", "alt"}, ...]}}``, one entry per
  image output in order; each becomes a numbered, captioned figure with its own alt text.
* **Hideable answers.** An admonition with the class ``dropdown`` becomes an HTML ``<details>``
  box, closed until the reader opens it, without JavaScript and without sphinx-togglebutton or
  sphinx-design.
* **Markup every front end renders.** The notebooks are read in JupyterLab, Notebook 7 and
  JupyterLite, which render plain Markdown only, so they hold no MyST roles or fences: a figure is
  cited by a link to its name (``[the figure above](#fig-07-power)``) and a call-out is a block
  quote that opens with a bold word (``> **Note.** ...``, ``> **Warning.** ...``,
  ``> **Exercise: ...**``, ``> **Answer to 1.** ...``). The site turns them into what MyST would
  have made: "Figure 7.3" for the link, a note, warning, tip or closed answer box for the quote.
* **Figure numbers per notebook.** A notebook's figures are numbered from its own number
  ("Figure 7.3" is notebook 7's third), not across the site.
"""

from __future__ import annotations

import ast
import html
import importlib
import inspect
import json
import logging as std_logging
import pkgutil
import re
import shutil
from pathlib import Path

from docutils import nodes
from sphinx.transforms import SphinxTransform
from sphinx.util import logging

logger = logging.getLogger(__name__)

#: Packages whose *submodules* are the public namespaces (course.plotting.lsq, ...).
SUBMODULE_NAMESPACES = ("course.plotting",)

API_DIR = "docs/api"


# --------------------------------------------------------------------------------------------
# Public namespaces and API pages
# --------------------------------------------------------------------------------------------


def public_namespaces() -> list[str]:
    """The dotted names of the course's public modules, in the order the API lists them."""
    course = importlib.import_module("course")
    names = [f"course.{name}" for name in course.__all__ if not name.startswith("_")]
    names = [n for n in names if _is_module(n)]
    for package in SUBMODULE_NAMESPACES:
        if package not in names:
            continue
        module = importlib.import_module(package)
        for info in pkgutil.iter_modules(module.__path__):
            if not info.name.startswith("_"):
                names.append(f"{package}.{info.name}")
    return names


def _is_module(dotted: str) -> bool:
    try:
        importlib.import_module(dotted)
    except ImportError:
        return False
    return True


def public_members(module_name: str) -> list[str]:
    """The names of ``__all__`` to document on the module's page.

    A submodule listed in ``__all__`` (``course.plotting.style``) has its own page; documenting
    it here too would describe the same object twice.
    """
    module = importlib.import_module(module_name)
    names = getattr(module, "__all__", [])
    return sorted(n for n in names if not inspect.ismodule(getattr(module, n, None)))


def _write_if_changed(path: Path, text: str) -> None:
    # Unchanged sources keep their mtime, so Sphinx does not reread them.
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")


def _directive(module_name: str, name: str) -> str:
    obj = getattr(importlib.import_module(module_name), name)
    if isinstance(obj, type):
        return f".. autoclass:: {name}\n   :members:\n   :show-inheritance:\n"
    if callable(obj):
        return f".. autofunction:: {name}\n"
    return f".. autodata:: {name}\n   :no-value:\n"


def home_namespaces(api: dict[str, list[str]]) -> dict[int, str]:
    """id(object) -> the one namespace that documents it.

    A name several namespaces export (``course.filters.AlarmStatistics`` is
    ``course.nis.AlarmStatistics``) is documented once, where it is defined (the namespace its
    ``__module__`` lies in), else in the first namespace that exports it; the others point
    there.
    """
    homes: dict[int, str] = {}
    for module_name, members in api.items():
        module = importlib.import_module(module_name)
        for name in members:
            obj = getattr(module, name)
            if not _is_documentable(obj):
                continue
            defined_in = getattr(obj, "__module__", "") or ""
            current = homes.get(id(obj))
            if current is None or (
                not _within(defined_in, current) and _within(defined_in, module_name)
            ):
                homes[id(obj)] = module_name
    return homes


def _within(module: str, namespace: str) -> bool:
    return module == namespace or module.startswith(namespace + ".")


def _is_documentable(obj) -> bool:
    # Constants (numbers, strings, tables) are documented wherever they are exported.
    return isinstance(obj, type) or callable(obj)


def write_api_pages(srcdir: Path) -> dict[str, list[str]]:
    """Write ``docs/api/modules/<module>.rst`` for every public namespace; drop stale pages.

    A page shows the module's docstring, a summary table of its ``__all__`` and then every
    public object, documented under its public name (``course.diagnosis.glr_test``), wherever
    it is defined. Names re-exported from another namespace link to that namespace's entry.
    """
    modules_dir = srcdir / API_DIR / "modules"
    api = {module_name: public_members(module_name) for module_name in public_namespaces()}
    homes = home_namespaces(api)
    for module_name, members in api.items():
        module = importlib.import_module(module_name)
        own, reexported = [], []
        for name in members:
            home = homes.get(id(getattr(module, name)), module_name)
            if home == module_name:
                own.append(name)
            else:
                reexported.append((name, home))
        title = f"``{module_name}``"
        lines = [
            title,
            "=" * len(title),
            "",
            f".. automodule:: {module_name}",
            "   :no-members:",
            "",
            f".. currentmodule:: {module_name}",
            "",
        ]
        if own:
            lines += [".. rubric:: Contents", "", ".. autosummary::", "   :nosignatures:", ""]
            lines += [f"   {name}" for name in own]
            lines.append("")
        if reexported:
            lines += [".. rubric:: Also exported here", ""]
            lines += [
                f"* ``{module_name}.{name}`` is :py:obj:`{home}.{name}`"
                for name, home in reexported
            ]
            lines.append("")
        lines += [_directive(module_name, name) for name in own]
        _write_if_changed(modules_dir / f"{module_name}.rst", "\n".join(lines))
    wanted = {f"{m}.rst" for m in api}
    if modules_dir.is_dir():
        for page in modules_dir.glob("*.rst"):
            if page.name not in wanted:
                page.unlink()  # a namespace that left the API must not leave a broken page
    return api


# --------------------------------------------------------------------------------------------
# Teaching map: which notebook uses which public object
# --------------------------------------------------------------------------------------------


def _code_cells(notebook: Path) -> list[str]:
    data = json.loads(notebook.read_text(encoding="utf-8"))
    cells = []
    for cell in data.get("cells", []):
        if cell.get("cell_type") != "code":
            continue
        source = cell.get("source", "")
        cells.append("".join(source) if isinstance(source, list) else source)
    return cells


def dotted_names_used(cells: list[str]) -> set[str]:
    """Dotted ``course...`` names the code cells of a notebook refer to.

    Import aliases carry over from cell to cell (``from course import lsq`` in the first cell,
    ``lsq.w_tests(...)`` in a later one), as in a kernel; a cell that does not parse is skipped.
    """
    aliases: dict[str, str] = {}
    used: set[str] = set()
    for source in cells:
        # IPython magics and shell escapes are not Python.
        lines = [ln for ln in source.splitlines() if not ln.lstrip().startswith(("%", "!"))]
        try:
            tree = ast.parse("\n".join(lines))
        except SyntaxError:
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name == "course" or alias.name.startswith("course."):
                        # "import course.lsq" binds "course"; "import course.lsq as l" binds "l"
                        if alias.asname:
                            aliases[alias.asname] = alias.name
                        else:
                            aliases["course"] = "course"
            elif (
                isinstance(node, ast.ImportFrom)
                and node.level == 0
                and node.module
                and (node.module == "course" or node.module.startswith("course."))
            ):
                for alias in node.names:
                    full = f"{node.module}.{alias.name}"
                    aliases[alias.asname or alias.name] = full
                    used.add(full)
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute):
                chain = []
                current: ast.AST = node
                while isinstance(current, ast.Attribute):
                    chain.append(current.attr)
                    current = current.value
                if isinstance(current, ast.Name) and current.id in aliases:
                    parts = list(reversed(chain))
                    for i in range(1, len(parts) + 1):
                        used.add(".".join([aliases[current.id], *parts[:i]]))
    return used


def _resolve(dotted: str):
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        try:
            for attr in parts[i:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return None
        return obj
    return None


def teaching_map(notebooks: dict[str, Path], api: dict[str, list[str]]) -> dict[str, list[str]]:
    """Public object name -> docnames of the notebooks that use it (learning-path order).

    Objects are matched by identity, so a notebook that imports a name from a private
    submodule, or from another namespace that re-exports it, counts for the one public name
    the API documents it under.
    """
    homes = home_namespaces(api)
    by_id: dict[int, list[str]] = {}
    for module_name, members in api.items():
        module = importlib.import_module(module_name)
        for name in members:
            obj = getattr(module, name, None)
            # Only the name the API documents the object under (a re-export points there).
            if _is_documentable(obj) and homes.get(id(obj)) == module_name:
                by_id.setdefault(id(obj), []).append(f"{module_name}.{name}")
    taught: dict[str, list[str]] = {}
    for docname in sorted(notebooks):
        used = dotted_names_used(_code_cells(notebooks[docname]))
        for dotted in sorted(used):
            obj = _resolve(dotted)
            for public in by_id.get(id(obj), []) if obj is not None else []:
                if docname not in taught.setdefault(public, []):
                    taught[public].append(docname)
    return taught


# --------------------------------------------------------------------------------------------
# Docstring rendering
# --------------------------------------------------------------------------------------------


def escape_shape_stars(app, what, name, obj, options, lines) -> None:
    """Before numpydoc: the shape ``(*batch, N, n)`` in a type is text, not reST emphasis.

    Only outside inline literals, where a backslash would show.
    """
    for i, line in enumerate(lines):
        if "(*" not in line:
            continue
        parts = line.split("``")
        parts[::2] = [part.replace("(*", "(\\*") for part in parts[::2]]
        lines[i] = "``".join(parts)


class _OptionalGlobFilter(std_logging.Filter):
    """Drop "toctree glob pattern didn't match" for globs of sections other work fills in.

    Sphinx gives this warning no type, so ``suppress_warnings`` cannot name it.
    """

    def __init__(self, app) -> None:
        super().__init__()
        self.app = app

    def filter(self, record: std_logging.LogRecord) -> bool:
        if "toctree glob pattern" not in str(record.msg) or not record.args:
            return True
        return record.args[0] not in self.app.config.course_site_optional_globs


# --------------------------------------------------------------------------------------------
# Sphinx event handlers
# --------------------------------------------------------------------------------------------


def _notebook_docs(app, setting: str = "course_site_notebooks") -> dict[str, Path]:
    """Docname -> path of the teaching notebooks (or of the assignments)."""
    srcdir = Path(app.srcdir)
    found = {}
    for pattern in getattr(app.config, setting):
        for path in sorted(srcdir.glob(pattern)):
            found[str(path.relative_to(srcdir).with_suffix("").as_posix())] = path
    return found


def on_config_inited(app, config) -> None:
    api = write_api_pages(Path(app.srcdir))
    app.course_api = api
    pages = {**_notebook_docs(app), **_notebook_docs(app, "course_site_assignments")}
    app.course_taught = teaching_map(pages, api)
    logger.info(
        "[course-site] teaching map: %d public objects are used by a notebook",
        len(app.course_taught),
    )


def outdated_by_teaching_map(app, env, added, changed, removed) -> list[str]:
    """Pages whose rendering depends on the teaching map, when the map has changed.

    An API page shows the notebooks that use its object and a notebook page the API it uses;
    neither source file changes when another file does, so Sphinx must be told.
    """
    new = getattr(app, "course_taught", {})
    old = getattr(env, "course_taught", {})
    env.course_taught = new
    stale = set()
    for name in set(old) | set(new):
        if old.get(name) != new.get(name):
            stale.add(f"{API_DIR}/modules/{name.rsplit('.', 1)[0]}")
            stale.update(old.get(name, []))
            stale.update(new.get(name, []))
    return sorted(stale & set(env.found_docs))


def add_notebook_see_also(app, what, name, obj, options, lines) -> None:
    """After numpydoc: name the notebooks that use this object in its "See also" box."""
    docnames = getattr(app, "course_taught", {}).get(name)
    if not docnames:
        return
    assignments = set(_notebook_docs(app, "course_site_assignments"))
    entries = []
    for docname in docnames:
        role = "Assignment that uses it." if docname in assignments else "Notebook that uses it."
        entries += [f"    :doc:`/{docname}`", f"        {role}", ""]
    if ".. seealso::" in lines:
        at = lines.index(".. seealso::") + 2  # after the directive and its blank line
        lines[at:at] = entries
    else:
        lines += ["", ".. seealso::", "", *entries]


def add_notebook_links(app, doctree) -> None:
    """On a notebook page: a link to run it in JupyterLite, and the API it uses.

    Assignment pages get the list of the API only: students run them where they hand them in.
    """
    docname = app.env.docname
    teaching = docname in _notebook_docs(app)
    if not teaching and docname not in _notebook_docs(app, "course_site_assignments"):
        return
    sections = list(doctree.findall(nodes.section))
    if not sections:
        return
    first = sections[0]
    if teaching and app.config.course_site_lite:
        depth = docname.count("/")
        lite = "../" * depth + f"lite/lab/index.html?path={Path(docname).name}.ipynb"
        para = nodes.paragraph(classes=["course-launch"])
        para += nodes.reference(
            "", "▶ Run this notebook in your browser (JupyterLite)", refuri=lite, internal=False
        )
        para += nodes.Text(
            " — nothing to install; the first run loads Python into the browser (needs internet)."
        )
        title_index = first.first_child_matching_class(nodes.title)
        first.insert(0 if title_index is None else title_index + 1, para)

    taught = getattr(app, "course_taught", {})
    used = sorted(name for name, docs in taught.items() if docname in docs)
    if not used:
        return
    section = nodes.section(ids=["api-used-in-this-notebook"])
    section += nodes.title(text="Library functions used in this notebook")
    bullet = nodes.bullet_list()
    for name in used:
        item = nodes.list_item()
        ref = nodes.paragraph()
        ref += _api_reference(app, docname, name)
        item += ref
        bullet += item
    section += bullet
    first += section


def _api_reference(app, fromdoc: str, fullname: str):
    from sphinx.addnodes import pending_xref

    xref = pending_xref(
        "",
        refdomain="py",
        reftype="obj",
        reftarget=fullname,
        refexplicit=False,
        refdoc=fromdoc,
        refwarn=True,
    )
    xref += nodes.literal(text=fullname)
    return xref


def launch_options(repository_url: str, branch: str = "main") -> dict:
    """The book theme's options for Binder and Colab launch buttons on notebook pages.

    Empty when no repository is configured: a launch button needs the notebooks at a public
    URL (Binder and Colab open them from there), and a dead button is worse than none.
    """
    url = repository_url.strip().rstrip("/")
    if not url:
        return {}
    if not url.startswith("https://"):
        raise ValueError(f"repository_url must be an https:// URL of a public repository: {url!r}")
    return {
        "repository_url": url,
        "repository_branch": branch,
        "path_to_docs": "",  # the Sphinx source is the repository root (see conf.py)
        "use_repository_button": True,
        "launch_buttons": {
            "binderhub_url": "https://mybinder.org",
            "colab_url": "https://colab.research.google.com",
            "notebook_interface": "jupyterlab",
        },
    }


def copy_mathjax(app, exception) -> None:
    """Serve MathJax from the site: tex-chtml plus its fonts and on-demand extensions."""
    if exception is not None or app.builder.format != "html":
        return
    from importlib.util import find_spec

    spec = find_spec("mathjax")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError(
            'MathJax is not installed: install the docs extra (python -m pip install -e ".[docs]")'
        )
    es5 = Path(next(iter(spec.submodule_search_locations))) / "static" / "mathjax" / "es5"
    target = Path(app.outdir) / "_static" / "mathjax"
    target.mkdir(parents=True, exist_ok=True)
    shutil.copy2(es5 / "tex-chtml.js", target / "tex-chtml.js")
    for sub in ("input/tex/extensions", "output/chtml/fonts/woff-v2", "ui", "a11y"):
        shutil.copytree(es5 / sub, target / sub, dirs_exist_ok=True)


def build_lite(app, exception) -> None:
    if exception is not None or app.builder.format != "html" or not app.config.course_site_lite:
        return
    from course.docsite import build_lite as build

    logger.info("[course-site] building JupyterLite into %s/lite", app.outdir)
    cache = Path(app.config.nb_execution_cache_path).parent
    build(Path(app.srcdir), Path(app.outdir), cache, list(_notebook_docs(app).values()))


def write_entry_page(app, exception) -> None:
    if exception is not None or app.builder.format != "html":
        return
    root = app.config.root_doc
    if root == "index":
        return
    target = f"{root}.html"
    (Path(app.outdir) / "index.html").write_text(
        "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>\n"
        f"<title>{app.config.project}</title>\n"
        f"<meta http-equiv='refresh' content='0; url={target}'>\n"
        f"<link rel='canonical' href='{target}'>\n</head>\n"
        f"<body><p><a href='{target}'>{app.config.project}</a></p></body></html>\n",
        encoding="utf-8",
    )


class CellFigures(SphinxTransform):
    """Wrap each image output of a cell in the figure its ``course.figures`` metadata names.

    Runs before ``SphinxDomains`` (850) records the labels, so ``{numref}`` finds them.
    """

    default_priority = 840

    def apply(self, **kwargs) -> None:
        for cell in list(self.document.findall(nodes.container)):
            if cell.get("nb_element") != "cell_code":
                continue
            metadata = cell.get("cell_metadata") or {}
            figures = (metadata.get("course") or {}).get("figures")
            if not figures:
                continue
            bundles = [
                node
                for node in cell.findall(nodes.container)
                if node.get("nb_element") == "mime_bundle"
                and any(
                    str(child.get("mime_type", "")).startswith("image/") for child in node.children
                )
            ]
            if len(bundles) != len(figures):
                logger.warning(
                    f"{len(figures)} figures named in the cell's metadata, {len(bundles)} drawn",
                    location=cell,
                )
                continue
            for bundle, spec in zip(bundles, figures):
                figure = nodes.figure()
                figure["names"].append(nodes.fully_normalize_name(spec["name"]))
                bundle.replace_self(figure)
                figure += bundle
                self.document.note_explicit_target(figure, figure)
                for image in bundle.findall(nodes.image):
                    image["alt"] = spec["alt"]
                figure += nodes.caption(spec["caption"], spec["caption"])


def dropdown_admonitions(app, doctree, docname) -> None:
    """Turn each admonition of class ``dropdown`` into a closed ``<details>`` box (HTML only).

    In Jupyter the same markdown shows the answer in plain text under its title line; on the
    site it stays hidden until the reader clicks the title.
    """
    if app.builder.format != "html":
        return
    for node in list(doctree.findall(nodes.admonition)):
        if "dropdown" not in node["classes"] or not node.children:
            continue
        title = node.children[0]
        label = title.astext() if isinstance(title, nodes.title) else "Answer"
        body = node.children[1:] if isinstance(title, nodes.title) else node.children
        classes = " ".join(["admonition", *node["classes"]])
        opening = nodes.raw(
            "",
            f'<details class="{html.escape(classes)}">'
            f'<summary class="admonition-title">{html.escape(label)}</summary>',
            format="html",
        )
        closing = nodes.raw("", "</details>", format="html")
        node.replace_self([opening, *body, closing])


# --------------------------------------------------------------------------------------------
# Markup every front end renders: block-quote call-outs, figure links, numbers per notebook
# --------------------------------------------------------------------------------------------

CALLOUT_NODES = {
    "note": nodes.note,
    "warning": nodes.warning,
    "tip": nodes.tip,
    "important": nodes.important,
}


def blockquote_callouts(app, doctree) -> None:
    """``> **Note.** text`` becomes a note (warning, tip, important alike); ``> **Exercise: X.**``
    a tip titled "Exercise: X"; ``> **Answer to 1.**`` a closed answer box (class dropdown).

    A block quote that does not open with one of these bold words stays a quotation.
    """
    for quote in list(doctree.findall(nodes.block_quote)):
        if not quote.children or not isinstance(quote[0], nodes.paragraph):
            continue
        para = quote[0]
        for child in list(para.children):  # MyST may open a paragraph with an empty text
            if isinstance(child, nodes.Text) and not child.astext().strip():
                para.remove(child)
            else:
                break
        if not para.children or not isinstance(para[0], nodes.strong):
            continue
        heading = para[0].astext().strip()
        label = heading.rstrip(".:").strip()
        key = label.lower()
        if not heading.endswith((".", ":")) or not label:
            continue
        box: nodes.Element
        if key in CALLOUT_NODES:
            box = CALLOUT_NODES[key]()
        elif key.startswith(("answer", "exercise")):
            box = nodes.admonition(classes=["dropdown" if key.startswith("answer") else "tip"])
            box += nodes.title(label, label)
        else:
            continue
        para.remove(para[0])
        if para.children and isinstance(para[0], nodes.Text):
            para[0] = nodes.Text(para[0].astext().lstrip())
        empty = not para.astext().strip() and not list(para.findall(nodes.math))
        children = [child for child in quote.children if child is not para or not empty]
        quote.children = []
        for child in children:
            box += child
        quote.replace_self(box)


def notebook_number(docname: str) -> str:
    """The number a notebook's file name starts with: ``notebooks/07_x`` -> "7", ``05a_y`` -> "5a"."""
    match = re.match(r"0*(\d+[a-z]?)_", Path(docname).name)
    return match.group(1) if match else ""


def number_figures_per_notebook(app, env) -> list[str]:
    """After Sphinx numbers the figures across the site: number each notebook's from its own."""
    for docname in _notebook_docs(app):
        prefix = notebook_number(docname)
        figures = env.toc_fignumbers.get(docname, {}).get("figure", {})
        order = sorted(figures, key=lambda figure_id: figures[figure_id])
        for k, figure_id in enumerate(order, start=1):
            figures[figure_id] = (prefix, k) if prefix else (k,)
    return []


# The words a notebook links a figure with; the site shows its number instead.
FIGURE_LINK_TEXT = re.compile(
    r"(?i)^the (?:(?:first|second) )?figure(?: above| below)?$|^the second$"
)


def figure_link_numbers(app, doctree, docname) -> None:
    """``[the figure above](#fig-x)`` reads "Figure 7.3" on the site, as a numref would."""
    figures = app.env.toc_fignumbers.get(docname, {}).get("figure", {})
    for ref in list(doctree.findall(nodes.reference)):
        uri = ref.get("refuri", "")
        target = ref.get("refid") or (uri.split("#", 1)[1] if "#" in uri else "")
        if target not in figures or not FIGURE_LINK_TEXT.match(ref.astext().strip()):
            continue
        number = ".".join(map(str, figures[target]))
        ref.children = []
        ref += nodes.inline("", f"Figure {number}", classes=["std", "std-numref"])


def keep_outputs_in_cache(app) -> None:
    """myst-nb writes a notebook's images to ``<output folder>/../jupyter_execute`` whatever
    the configuration says (its ``output_folder`` is not a Sphinx setting): next to the site, in
    the repository when the site is built into it (issue 39). Point it at
    ``course_site_output_folder`` (in the build cache) instead."""
    config = getattr(app.env, "mystnb_config", None)
    folder = app.config.course_site_output_folder
    if config is not None and folder:
        app.env.mystnb_config = config.copy(output_folder=str(Path(folder).resolve()))


def drop_unrendered_widget_state(app, doctree) -> None:
    """myst-nb embeds a notebook's saved widget state (tens of KiB per slider page) even when no
    widget JavaScript is loaded to render it (``nb_ipywidgets_js = {}``): drop it then."""
    if getattr(app.config, "nb_ipywidgets_js", None):
        return
    metadata = getattr(app.env, "nb_metadata", {}).get(app.env.docname, {})
    metadata.get("js_files", {}).pop("ipywidgets_state", None)


def setup(app):
    app.add_config_value("course_site_notebooks", ["notebooks/*.ipynb"], "env")
    app.add_config_value("course_site_assignments", ["exercises/*/*.ipynb"], "env")
    app.add_config_value("course_site_lite", True, "env")
    app.add_config_value("course_site_optional_globs", [], "env")
    app.add_config_value("course_site_output_folder", "", "env")
    std_logging.getLogger("sphinx.sphinx.directives.other").addFilter(_OptionalGlobFilter(app))
    app.connect("autodoc-process-docstring", escape_shape_stars, priority=400)
    # Before autosummary (priority 500) reads the pages this writes.
    app.connect("config-inited", on_config_inited, priority=400)
    app.connect("env-get-outdated", outdated_by_teaching_map)
    app.connect("autodoc-process-docstring", add_notebook_see_also, priority=600)
    app.connect("doctree-read", add_notebook_links)
    app.connect("doctree-read", blockquote_callouts)
    app.connect("doctree-read", drop_unrendered_widget_state)
    app.connect("builder-inited", keep_outputs_in_cache, priority=900)  # after myst-nb's
    # after Sphinx's own figure numbering (the toctree collector, priority 500)
    app.connect("env-get-updated", number_figures_per_notebook, priority=900)
    app.connect("doctree-resolved", figure_link_numbers, priority=400)
    app.connect("doctree-resolved", dropdown_admonitions)
    app.add_transform(CellFigures)
    app.connect("build-finished", copy_mathjax)
    app.connect("build-finished", write_entry_page)
    app.connect("build-finished", build_lite)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
