"""The website's machinery without building it: the teaching map, API pages, the CLI.

The full build and its checks in a browser are in ``test_website.py``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import nbformat
import pytest

pytest.importorskip("sphinx", reason='the docs extra is not installed (pip install -e ".[docs]")')

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "docs" / "_ext"))

import course_site  # noqa: E402

from course import cli  # noqa: E402
from course.docsite import (  # noqa: E402
    LITE_INSTALL_CELL,
    _lite_notebook,
    _wheel_inputs_digest,
    build_site,
    cache_stored_outputs,
    find_root,
)


def test_names_used_follow_aliases_across_cells():
    cells = [
        "%matplotlib inline\nfrom course import lsq\nimport course.nis as N\nfrom course.plotting import lsq as plots",
        "fit = lsq.fit(A, y)\nN.nis_test(e, S)",
        "plots.plot_w_tests(result)\n!ls",
        "this is not python (",
        "import course\ncourse.quadform.imhof_cdf(1.0, [1.0])",
    ]
    used = course_site.dotted_names_used(cells)
    for name in (
        "course.lsq.fit",
        "course.nis.nis_test",
        "course.plotting.lsq.plot_w_tests",
        "course.quadform.imhof_cdf",
    ):
        assert name in used
    assert not any("numpy" in name for name in used)


def test_teaching_map_matches_objects_through_private_modules(tmp_path):
    notebook = tmp_path / "nb.ipynb"
    # windowed_nis is defined in a private module of course.nis (course.nis._windowed).
    notebook.write_text(
        json.dumps(
            {
                "cells": [
                    {"cell_type": "code", "source": "from course.nis import windowed_nis"},
                    {"cell_type": "code", "source": ["from course import lsq\n", "lsq.w_tests"]},
                ]
            }
        )
    )
    api = {m: course_site.public_members(m) for m in course_site.public_namespaces()}
    taught = course_site.teaching_map({"notebooks/nb": notebook}, api)
    assert taught["course.lsq.w_tests"] == ["notebooks/nb"]
    assert taught["course.nis.windowed_nis"] == ["notebooks/nb"]
    assert "course.nis._windowed.windowed_nis" not in taught  # documented under its public home


def test_every_public_object_is_documented_exactly_once():
    api = {m: course_site.public_members(m) for m in course_site.public_namespaces()}
    homes = course_site.home_namespaces(api)
    for module_name, members in api.items():
        module = __import__(module_name, fromlist=["_"])
        for name in members:
            obj = getattr(module, name)
            if course_site._is_documentable(obj):
                assert homes[id(obj)] in api
    assert "course.grading" in api and "course.plotting.lsq" in api


def test_api_pages_follow_the_public_names_and_drop_stale_pages(tmp_path):
    stale = tmp_path / "docs/api/modules/course.gone.rst"
    stale.parent.mkdir(parents=True)
    stale.write_text("old")
    api = course_site.write_api_pages(tmp_path)
    pages = {p.stem for p in (tmp_path / "docs/api/modules").glob("*.rst")}
    assert pages == set(api)
    lsq = (tmp_path / "docs/api/modules/course.lsq.rst").read_text()
    assert ".. autofunction:: w_tests" in lsq
    filters = (tmp_path / "docs/api/modules/course.filters.rst").read_text()
    assert ".. autofunction:: kalman_filter\n" in filters
    assert "Also exported here" not in filters  # one public name per object


def test_shapes_in_types_are_escaped_but_not_inside_literals():
    lines = ["x : (*batch, N) ndarray", "    Shape ``(*batch, N)`` as given.", "(*batch,) ndarray"]
    course_site.escape_shape_stars(None, "function", "f", None, {}, lines)
    assert lines == [
        "x : (\\*batch, N) ndarray",
        "    Shape ``(*batch, N)`` as given.",
        "(\\*batch,) ndarray",
    ]


def test_see_also_names_the_notebook_after_numpydoc():
    from types import SimpleNamespace

    app = SimpleNamespace(
        srcdir=str(ROOT),
        config=SimpleNamespace(course_site_assignments=["exercises/*/*.ipynb"]),
        course_taught={
            "course.lsq.fit": [
                "notebooks/01_least_squares_validation",
                "exercises/01_least_squares/01_least_squares",
            ]
        },
    )
    with_box = ["Text.", "", ".. seealso::", "", "    :obj:`w_tests`", "        W-tests.", ""]
    course_site.add_notebook_see_also(app, "function", "course.lsq.fit", None, {}, with_box)
    assert with_box[4:10] == [
        "    :doc:`/notebooks/01_least_squares_validation`",
        "        Notebook that uses it.",
        "",
        "    :doc:`/exercises/01_least_squares/01_least_squares`",
        "        Assignment that uses it.",
        "",
    ]
    without = ["Text."]
    course_site.add_notebook_see_also(app, "function", "course.lsq.fit", None, {}, without)
    assert ".. seealso::" in without
    untouched = ["Text."]
    course_site.add_notebook_see_also(app, "function", "course.lsq.mdb", None, {}, untouched)
    assert untouched == ["Text."]


def test_lite_copy_installs_the_course_first(tmp_path):
    source = ROOT / "notebooks" / "01_least_squares_validation.ipynb"
    _lite_notebook(source, tmp_path / source.name)
    copy = json.loads((tmp_path / source.name).read_text())
    original = json.loads(source.read_text())
    assert "".join(copy["cells"][0]["source"]).endswith(LITE_INSTALL_CELL)
    # The same cells, every multi-line field as one string (nbformat's reader joins them too).
    assert copy["cells"][1:] == nbformat.reads(source.read_text(), as_version=4)["cells"]
    assert len(copy["cells"]) == len(original["cells"]) + 1


def test_lite_copy_has_no_line_lists_that_jupyterlite_would_show_with_commas(tmp_path):
    # jupyterlite#1105: a stored output kept as a list of lines shows as "line1\n,line2\n".
    source = tmp_path / "src.ipynb"
    notebook = {
        "cells": [
            {
                "cell_type": "code",
                "execution_count": 1,
                "id": "a",
                "metadata": {},
                "source": ["x = 1\n", "print(x)"],
                "outputs": [
                    {"name": "stdout", "output_type": "stream", "text": ["1\n", "2\n"]},
                    {
                        "output_type": "execute_result",
                        "execution_count": 1,
                        "metadata": {},
                        "data": {
                            "text/plain": ["array([1,\n", "       2])"],
                            "application/json": {"lines": ["kept", "as is"]},
                        },
                    },
                ],
            }
        ],
        "metadata": {},
        "nbformat": 4,
        "nbformat_minor": 5,
    }
    source.write_text(json.dumps(notebook))
    _lite_notebook(source, tmp_path / "copy.ipynb")
    cell = json.loads((tmp_path / "copy.ipynb").read_text())["cells"][1]
    assert cell["source"] == "x = 1\nprint(x)"
    assert cell["outputs"][0]["text"] == "1\n2\n"
    assert cell["outputs"][1]["data"]["text/plain"] == "array([1,\n       2])"
    assert cell["outputs"][1]["data"]["application/json"] == {"lines": ["kept", "as is"]}


def test_docs_command_is_wired(capsys):
    args = cli.build_parser().parse_args(["docs", "out", "--no-lite", "--jobs", "2"])
    assert args.func is cli._docs and args.no_lite and args.jobs == 2
    assert find_root(ROOT / "notebooks") == ROOT


def test_cache_inside_the_output_folder_is_refused(tmp_path):
    with pytest.raises(ValueError, match="cache_dir"):
        build_site(tmp_path / "site", root=ROOT, cache_dir=tmp_path / "site" / "cache")


def test_stored_outputs_fill_the_cache_until_the_code_changes(tmp_path):
    """``course docs --stored-outputs``: each teaching notebook enters the execution cache once,
    with its saved outputs; a cell added and never run keeps its notebook out (it will run)."""
    pytest.importorskip("jupyter_cache")
    root = tmp_path / "clone"
    (root / "notebooks").mkdir(parents=True)
    names = [
        "03_parameter_estimation_and_likelihood.ipynb",
        "05a_wishart_numerics_under_the_hood.ipynb",
    ]
    for name in names:
        (root / "notebooks" / name).write_bytes((ROOT / "notebooks" / name).read_bytes())
    cache = tmp_path / "cache"
    assert cache_stored_outputs(root, cache) == [f"notebooks/{n}" for n in names]
    assert cache_stored_outputs(root, cache) == []
    edited = root / "notebooks" / names[0]
    notebook = json.loads(edited.read_text())
    notebook["cells"].append(
        {"cell_type": "code", "execution_count": None, "metadata": {}, "outputs": []}
        | {"id": "never-run", "source": "x_new = 1"}
    )
    edited.write_text(json.dumps(notebook, indent=1))
    assert cache_stored_outputs(root, cache) == []
    notebook["cells"][-1]["execution_count"] = 99  # saved after a run: its outputs count
    edited.write_text(json.dumps(notebook, indent=1))
    assert cache_stored_outputs(root, cache) == [f"notebooks/{names[0]}"]


def test_the_lite_wheel_is_rebuilt_only_when_its_inputs_change(tmp_path):
    """The JupyterLite app reuses the course's wheel across builds unless the package (or the
    files pyproject.toml names) changed: editing a notebook does not rebuild it."""
    root = tmp_path / "clone"
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_bytes((ROOT / name).read_bytes())
    (root / "course").mkdir()
    (root / "course" / "__init__.py").write_text("__version__ = '0'\n")
    (root / "notebooks").mkdir()
    (root / "notebooks" / "a.ipynb").write_text("{}")
    first = _wheel_inputs_digest(root)
    (root / "notebooks" / "a.ipynb").write_text('{"cells": []}')
    (root / "course" / "__pycache__").mkdir()
    (root / "course" / "__pycache__" / "x.pyc").write_bytes(b"compiled")
    assert _wheel_inputs_digest(root) == first
    (root / "course" / "lsq.py").write_text("x = 1\n")
    assert _wheel_inputs_digest(root) != first


def test_launch_buttons_appear_only_with_a_repository():
    assert course_site.launch_options("") == {}
    options = course_site.launch_options("https://github.com/owner/course/", "trunk")
    assert options["repository_url"] == "https://github.com/owner/course"
    assert options["repository_branch"] == "trunk"
    assert options["launch_buttons"]["binderhub_url"] == "https://mybinder.org"
    assert options["launch_buttons"]["colab_url"] == "https://colab.research.google.com"
    with pytest.raises(ValueError, match="repository_url"):
        course_site.launch_options("git@github.com:owner/course.git")


def test_lite_pages_explain_why_python_cannot_start(tmp_path):
    lite = tmp_path / "lite"
    for app in ("lab", "notebooks"):
        (lite / app).mkdir(parents=True)
        (lite / app / "index.html").write_text("<html><head><title>x</title></head><body></body>")
    from course.docsite import add_lite_check

    assert len(add_lite_check(lite)) == 2
    assert add_lite_check(lite) == []  # idempotent: a rebuild adds no second tag
    script = (lite / "course-lite-check.js").read_text()
    assert "file:" in script and "offline" in script and "https://" in script
    assert "course-lite-check.js" in (lite / "lab" / "index.html").read_text()


def _quote(*children):
    from docutils import nodes

    para = nodes.paragraph()
    for child in children:
        para += child
    quote = nodes.block_quote()
    quote += para
    return quote


def test_blockquote_callouts_become_boxes_and_quotations_stay():
    """Notebooks write call-outs as block quotes every Jupyter renders; the site boxes them."""
    from docutils import nodes

    doc = nodes.section()
    doc += _quote(nodes.Text(""), nodes.strong(text="Note."), nodes.Text(" Read this."))
    doc += _quote(nodes.strong(text="Answer to 1."), nodes.Text(" It is 2."))
    doc += _quote(nodes.strong(text="Exercise: two formulas."))
    doc += _quote(nodes.Text("A quotation, "), nodes.strong(text="not."), nodes.Text(" a box"))
    course_site.blockquote_callouts(None, doc)
    kinds = [type(child).__name__ for child in doc.children]
    assert kinds == ["note", "admonition", "admonition", "block_quote"]
    assert doc[0].astext() == "Read this."
    assert doc[1]["classes"] == ["dropdown"] and doc[1][0].astext() == "Answer to 1"
    assert doc[2]["classes"] == ["tip"] and doc[2].astext() == "Exercise: two formulas"


def test_figures_are_numbered_from_their_notebook(monkeypatch):
    from types import SimpleNamespace

    assert course_site.notebook_number("notebooks/07_testing_theory") == "7"
    assert course_site.notebook_number("notebooks/05a_wishart") == "5a"
    env = SimpleNamespace(
        toc_fignumbers={"notebooks/07_x": {"figure": {"fig-b": (49,), "fig-a": (48,)}}}
    )
    monkeypatch.setattr(course_site, "_notebook_docs", lambda app: {"notebooks/07_x": None})
    course_site.number_figures_per_notebook(None, env)
    assert env.toc_fignumbers["notebooks/07_x"]["figure"] == {
        "fig-a": ("7", 1),
        "fig-b": ("7", 2),
    }
