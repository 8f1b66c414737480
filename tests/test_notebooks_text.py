"""The teaching notebooks as documents: sources named, links that work, outputs worth comparing.

nbval (the notebook tests) checks that every cell still prints what it printed; these tests
check what nbval cannot: that no notebook names a file the student does not have, that every
notebook links the bibliography and its appendix, that the style is switched on, that the
sliders never run under the tests, and that no stored output compares round-off.
"""

from __future__ import annotations

import re
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
ALL_NOTEBOOKS = sorted(
    p
    for p in ROOT.rglob("*.ipynb")
    if ".ipynb_checkpoints" not in p.parts and ".git" not in p.parts
)
APPENDICES = {
    "05_nis_matrix_and_wishart": "05a_wishart_numerics_under_the_hood",
    "06_mismatched_filters": "06a_imhof_and_the_errata",
}
# The source documents of the course live outside the repository: a path to them, or their
# file names, mean nothing to a student. Cite the published work instead (docs/bibliography.md).
SOURCE_PATH = re.compile(
    r"(?<![\w-])(seeds|shared)/|lsq_validation_chapter10|test_quantities_lecture_sv"
    r"|nis_matrix_wishart_forsling|mismatched_filters_baram"
)


def _read(path):
    return nbformat.read(path, as_version=4)


def _outputs_text(cell):
    for out in cell.get("outputs", []):
        if out.get("output_type") == "stream":
            yield out.get("name", ""), out.get("text", "")
        elif "data" in out and "text/plain" in out["data"]:
            yield "data", out["data"]["text/plain"]
        elif out.get("output_type") == "error":
            yield "error", "\n".join(out.get("traceback", []))


def test_the_teaching_notebooks_and_their_appendices_exist():
    names = {p.stem for p in NOTEBOOKS}
    assert len(NOTEBOOKS) >= 8
    assert set(APPENDICES) | set(APPENDICES.values()) <= names


@pytest.mark.parametrize("path", ALL_NOTEBOOKS, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_notebook_names_a_source_file(path):
    nb = _read(path)
    for index, cell in enumerate(nb.cells):
        texts = [cell.source] + [text for _, text in _outputs_text(cell)]
        for text in texts:
            found = SOURCE_PATH.search(text)
            assert found is None, (
                f"{path.name}, cell {index}: {found.group(0)!r} names a source file the student "
                "does not have; cite the published source (docs/bibliography.md)"
            )


def test_the_pattern_catches_paths_and_file_names():
    assert SOURCE_PATH.search("see shared/seeds/test_quantities_lecture_sv.txt")
    assert SOURCE_PATH.search("(source document `mismatched_filters_baram.txt`)")
    assert SOURCE_PATH.search("seeds/README.md")
    assert not SOURCE_PATH.search("the seeds of doubt; a shared interest; random seeds")


def test_no_library_source_names_a_source_file():
    offenders = []
    for path in sorted((ROOT / "course").rglob("*.py")):
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
            if SOURCE_PATH.search(line):
                offenders.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert not offenders, "cite author and year instead of a file:\n" + "\n".join(offenders)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_one_title_and_a_link_to_the_bibliography(path):
    nb = _read(path)
    titles = [
        line
        for cell in nb.cells
        if cell.cell_type == "markdown"
        for line in cell.source.splitlines()
        if line.startswith("# ")
    ]
    assert len(titles) == 1, f"{path.name} needs exactly one top-level title, has {titles}"
    assert nb.cells[0].cell_type == "markdown" and nb.cells[0].source.startswith("# ")
    markdown = "\n".join(c.source for c in nb.cells if c.cell_type == "markdown")
    assert "](../docs/bibliography.md" in markdown


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_relative_links_resolve(path):
    nb = _read(path)
    for cell in nb.cells:
        if cell.cell_type != "markdown":
            continue
        for target in re.findall(r"\]\(([^)\s]+)\)", cell.source):
            if "://" in target or target.startswith(("#", "mailto:")):
                continue
            file = (path.parent / target.split("#")[0]).resolve()
            assert file.exists(), f"{path.name} links to {target}, which does not exist"


@pytest.mark.parametrize(("main", "appendix"), APPENDICES.items())
def test_appendices_are_linked_both_ways(main, appendix):
    def links(name):
        nb = _read(ROOT / "notebooks" / f"{name}.ipynb")
        return "\n".join(c.source for c in nb.cells if c.cell_type == "markdown")

    assert f"]({appendix}.ipynb)" in links(main)
    assert f"]({main}.ipynb)" in links(appendix)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_the_course_style_is_switched_on_before_the_first_figure(path):
    code = [c for c in _read(path).cells if c.cell_type == "code"]
    assert "style.use()" in code[0].source, f"{path.name}: call style.use() in the first code cell"
    for cell in code:
        assert "tight_layout" not in cell.source, "the style lays figures out (constrained layout)"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_figure_cells_end_with_plt_show(path):
    for index, cell in enumerate(_read(path).cells):
        if cell.cell_type != "code" or "_widget(" in cell.source:
            continue
        draws = re.search(
            r"plt\.(subplots|figure)\(|\bplot_\w+\(|interactive\.\w+_view\(", cell.source
        )
        if draws:
            assert cell.source.rstrip().endswith("plt.show()"), f"{path.name}, cell {index}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_sliders_never_run_under_the_tests(path):
    for index, cell in enumerate(_read(path).cells):
        if cell.cell_type == "code" and "_widget(" in cell.source:
            tags = cell.metadata.get("tags", [])
            assert "nbval-skip" in tags, (
                f"{path.name}, cell {index}: tag the widget cell nbval-skip"
            )
            assert not cell.outputs, f"{path.name}, cell {index}: store widget cells without output"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_sliders_come_only_from_course_interactive(path):
    """ipywidgets' own interact()/Output capture make a runner without a browser (nbconvert, the
    website build) send outputs back to the kernel mid-cell, which can stall the run for the
    whole cell timeout (nbclient#312); course.interactive's builders do not."""
    for index, cell in enumerate(_read(path).cells):
        if cell.cell_type == "code":
            assert not re.search(r"ipywidgets|\binteract(ive)?\(|Output\(", cell.source), (
                f"{path.name}, cell {index}: build sliders with course.interactive"
            )


# a number printed in scientific notation whose exponent says "round-off of an O(1) quantity"
ROUND_OFF = re.compile(r"\b\d(?:\.\d+)?e-1[3-7]\b")
# a rounded zero that kept the sign of its round-off ("-0.0000"): the sign flips between machines
NEGATIVE_ZERO = re.compile(r"(?<![\w.])-0(?:\.0+)?(?![\d.]|e[+-]?\d)")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_stored_outputs_compare_teaching_not_round_off(path):
    for index, cell in enumerate(_read(path).cells):
        if cell.cell_type != "code":
            continue
        for kind, text in _outputs_text(cell):
            assert kind not in ("stderr", "error"), f"{path.name}, cell {index}: {text[:200]}"
            found = ROUND_OFF.search(text)
            assert found is None, (
                f"{path.name}, cell {index} prints {found.group(0)}: round-off differs between "
                "machines; print a decision such as '< 1e-12' instead"
            )
            found = NEGATIVE_ZERO.search(text)
            assert found is None, (
                f"{path.name}, cell {index} prints {found.group(0)}: a rounded zero with the sign "
                "of its round-off; add 0.0 after rounding"
            )


def test_the_round_off_pattern():
    assert ROUND_OFF.search("largest |e_hat| = 2.8e-14")
    assert ROUND_OFF.search("difference 4e-16")
    assert not ROUND_OFF.search("p = 1.248e-47") and not ROUND_OFF.search("posterior 2.076e-09")


def test_the_negative_zero_pattern():
    assert NEGATIVE_ZERO.search("0.5924    -0.0000")
    assert NEGATIVE_ZERO.search("x_hat = [-0.0, 1.0]") and NEGATIVE_ZERO.search("shift -0 samples")
    for fine in ("-0.0542", "-0.003", "e_hat = -0.5", "t - 0.05", "10-0.0", "1e-05", "-0.07"):
        assert not NEGATIVE_ZERO.search(fine), fine
