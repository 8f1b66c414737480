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


# ---------------------------------------------------------------------------
# prose that quotes a number reads it from the output above it
# ---------------------------------------------------------------------------
NUMBER = r"(\d+(?:\.\d+)?)"
# (notebook, a sentence of the prose with its numbers as groups, the printed line with the same
# numbers as groups, the factor from printed to quoted (100 for a rate quoted in per cent)).
# The numbers are compared as sorted lists, each within the rounding of both sides.
QUOTED_NUMBERS = [
    (
        "01_least_squares_validation",
        rf"the MDBs are {NUMBER}σ to {NUMBER}σ at the same",
        rf"MDB \[m\] \(alpha=5%,\s+power=80%\) = \[{NUMBER}, {NUMBER},",
        1,
    ),
    (
        "01_least_squares_validation",
        rf"and {NUMBER}σ to {NUMBER}σ at Baarda's 0\.1",
        rf"MDB \[m\] \(alpha=0\.1%, power=80%\) = \[{NUMBER}, {NUMBER},",
        1,
    ),
    (
        "03_parameter_estimation_and_likelihood",
        rf"put NF first only {NUMBER} % of the time",
        rf"0\.003 \|\s+{NUMBER} \|",
        100,
    ),
    (
        "03_parameter_estimation_and_likelihood",
        rf"ranked first in only {NUMBER} % of the records",
        rf"\n\s+30 \|\s+\S+ \|\s+{NUMBER}",
        100,
    ),
    (
        "03_parameter_estimation_and_likelihood",
        rf"the median\s+largest posterior is {NUMBER}",
        rf"\n0\.003 \|\s+\S+ \|\s+\S+ \| {NUMBER}",
        1,
    ),
    (
        "04_ekf_residual_generators",
        rf"band at {NUMBER} of the {NUMBER} samples",
        rf"band at {NUMBER} of {NUMBER} samples",
        1,
    ),
    (
        "04_ekf_residual_generators",
        rf"the fault adds {NUMBER} standard deviations\s+to the normalised innovation, then {NUMBER} "
        rf"and {NUMBER}",
        rf"t = 150, 151, 152: \[{NUMBER} {NUMBER} {NUMBER}\]",
        1,
    ),
    (
        "04_ekf_residual_generators",
        rf"\({NUMBER} alarms where",
        rf"alarms at the last sample: {NUMBER} of",
        1,
    ),
    (
        "05_nis_matrix_and_wishart",
        rf"at or above the NIS at {NUMBER} of the {NUMBER} window lengths",
        rf"at or above the NIS at {NUMBER} of {NUMBER} window lengths",
        1,
    ),
    (
        "05_nis_matrix_and_wishart",
        rf"rises from {NUMBER} % at\s+\$K=2\$",
        rf"NIS rate at K = 2: {NUMBER},",
        100,
    ),
    (
        "05_nis_matrix_and_wishart",
        rf"NIS matrix are {NUMBER} and {NUMBER}\.",
        rf"NIS-matrix eigenvalue test: statistic = \({NUMBER}, {NUMBER}\)",
        1,
    ),
    (
        "05_nis_matrix_and_wishart",
        rf"below the lower\s+threshold {NUMBER}",
        rf"NIS-matrix eigenvalue test: .* outside \[{NUMBER},",
        1,
    ),
    (
        "06_mismatched_filters",
        rf"power climbs to {NUMBER} and\s+stays there",
        rf"large-M limit of the mean test's power {NUMBER}",
        1,
    ),
    (
        "06_mismatched_filters",
        rf"has power {NUMBER} at \$j = 5\$ and {NUMBER} at \$j = 29\$",
        rf"against M2a at other times: j=5: {NUMBER} .* j=29: {NUMBER}",
        1,
    ),
    (
        "06_mismatched_filters",
        rf"\(power\s+{NUMBER} at \$j = 3\$, {NUMBER} at \$j = 29\$\)",
        rf"against M2b at other times: j=3: {NUMBER} .* j=29: {NUMBER}",
        1,
    ),
    (
        "05_nis_matrix_and_wishart",
        rf"almost invisible to the time-averaged NIS \({NUMBER} % of the time averages",
        rf"correlated: share of runs whose time average is outside = {NUMBER}",
        100,
    ),
    # notebook 07, corrected and backed in issue 39
    (
        "07_testing_theory",
        rf"its p-value \({NUMBER}\) is the smallest of twenty",
        rf"obs\. 18: p-value {NUMBER}",
        1,
    ),
    (
        "07_testing_theory",
        rf"at most \$20 \\times {NUMBER} = {NUMBER}\$",
        rf"at most 20 x {NUMBER} = {NUMBER} \(Bonferroni\)",
        1,
    ),
    (
        "07_testing_theory",
        rf"rejects the true line in about half the runs \({NUMBER}\)",
        rf"chi2 test {NUMBER}, F test",
        1,
    ),
    (
        "07_testing_theory",
        rf"for the same power \({NUMBER} against\s+\$\\lambda_0 = {NUMBER}\$\)",
        rf"lambda_0 = {NUMBER}, critical[\s\S]*at alpha = 0\.001: semi-axes .*\s+non-centrality {NUMBER}",
        1,
    ),
    (
        "07_testing_theory",
        rf"At the B-method's \$\\alpha_2 = {NUMBER}\$",
        rf"at the B-method's alpha_2 = {NUMBER}",
        1,
    ),
    (
        "07_testing_theory",
        rf"MDB of observation 4 exactly \({NUMBER} and {NUMBER}\)",
        rf"reach along obs\. 4 {NUMBER} \(w-test MDB of obs\. 4: {NUMBER}\)",
        1,
    ),
    (
        "07_testing_theory",
        rf"Detection succeeds in about {NUMBER} % of the runs",
        rf"detection {NUMBER}, correct",
        100,
    ),
    (
        "07_testing_theory",
        rf"non-centrality for both \(\$\\lambda_0 = {NUMBER}\$\), but spread over 18 degrees of freedom "
        rf"it is found\s+with probability {NUMBER} only",
        rf"one MDB in obs\. 0: non-centrality {NUMBER}; overall model test \(q = 18, alpha = 0\.05\) "
        rf"detects it with probability {NUMBER}",
        1,
    ),
    (
        "07_testing_theory",
        rf"has the plain fit's \({NUMBER} against {NUMBER},",
        rf"plain fit:\s+mean \S+, std {NUMBER}\nnothing detected:\s+mean slope error \S+, std {NUMBER}",
        1,
    ),
    (
        "07_testing_theory",
        rf"without observation 0 \({NUMBER} against {NUMBER}\)",
        rf"obs\. 0 identified: mean slope error \S+, std {NUMBER}\nslope std of the fit without "
        rf"obs\. 0: {NUMBER}",
        1,
    ),
    (
        "07_testing_theory",
        rf"its mean is −{NUMBER} and its spread {NUMBER}",
        rf"slope error of the DIA estimator: mean -{NUMBER}, std {NUMBER}",
        1,
    ),
]


def _decimals(text):
    return len(text.split(".")[1]) if "." in text else 0


def _agree(quoted, printed, factor):
    """Quoted and printed numbers (strings) agree as sorted lists, within both roundings."""
    if len(quoted) != len(printed):
        return False
    pairs = zip(sorted(quoted, key=float), sorted(printed, key=float))
    return all(
        abs(float(q) - factor * float(p))
        <= 0.5 * 10.0 ** -_decimals(q) + factor * 0.5 * 10.0 ** -_decimals(p) + 1e-12
        for q, p in pairs
    )


def _quoted_and_printed(nb, prose, printed):
    """The numbers of the one markdown cell matching ``prose`` and of the output above it."""
    hits = [
        (i, m)
        for i, c in enumerate(nb.cells)
        if c.cell_type == "markdown"
        for m in [re.search(prose, c.source, re.S)]
        if m
    ]
    assert len(hits) == 1, f"the sentence {prose!r} must occur once, found {len(hits)}"
    index, match = hits[0]
    outputs = "\n".join(
        text for c in nb.cells[:index] if c.cell_type == "code" for _, text in _outputs_text(c)
    )
    found = re.findall(printed, outputs)
    assert found, f"no printed line {printed!r} above the sentence {prose!r}"
    last = found[-1] if isinstance(found[-1], tuple) else (found[-1],)
    return list(match.groups()), list(last)


@pytest.mark.parametrize(
    ("name", "prose", "printed", "factor"),
    QUOTED_NUMBERS,
    ids=[f"{name[:3]}{k}" for k, (name, *_) in enumerate(QUOTED_NUMBERS)],
)
def test_a_quoted_number_is_the_printed_number(name, prose, printed, factor):
    nb = _read(ROOT / "notebooks" / f"{name}.ipynb")
    quoted, shown = _quoted_and_printed(nb, prose, printed)
    assert _agree(quoted, shown, factor), (
        f"{name}: the prose says {quoted} where the output above prints {shown}"
    )


def test_the_quoted_number_check_can_fail():
    assert _agree(["3.3", "5.1"], ["5.11", "3.35"], 1)
    assert _agree(["30"], ["0.300"], 100)
    assert not _agree(["4.9", "7.5"], ["5.11", "3.35"], 1)
    assert not _agree(["0.128"], ["0.131"], 1)
    assert not _agree(["1", "2"], ["1"], 1)


# ---------------------------------------------------------------------------
# figures that fit the website's text column
# ---------------------------------------------------------------------------
def _png_width(data):
    import base64
    import struct

    raw = base64.b64decode(data)
    assert raw[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    return struct.unpack(">I", raw[16:20])[0]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_figures_are_at_most_the_course_width(path):
    """A stored figure wider than style.MAX_WIDTH inches (at the style's dpi) is shrunk on the
    website's 688-px column until its 11-pt labels are unreadable: stack or split the panels."""
    from course.plotting.style import MAX_WIDTH, RC_PARAMS

    limit = MAX_WIDTH * RC_PARAMS["figure.dpi"] + 2  # the tight bounding box may add a pixel
    for index, cell in enumerate(_read(path).cells):
        for out in cell.get("outputs", []):
            data = out.get("data", {}).get("image/png")
            if data:
                width = _png_width(data)
                assert width <= limit, (
                    f"{path.name}, cell {index}: figure {width} px wide > {limit}"
                )


# ---------------------------------------------------------------------------
# prose that names panels matches the figure's layout
# ---------------------------------------------------------------------------
# "Left: ...", "Top: ...", "the right panel", "upper panel": the position words of a sentence
# that walks the reader through a figure's panels. Figures get re-laid (side by side -> stacked
# for the website's column); the prose must follow (issue 39: nb02 and nb03 said Left/Right of
# stacked panels).
PANEL_WORD = re.compile(
    r"\b(Left|Right|Top|Bottom|Middle|Upper|Lower)(?=:)"  # "Left: ...", not "... left: ..."
    r"|\b((?i:left|right|top|bottom|middle|upper|lower))(?= panel)"
)
_CANONICAL = {"upper": "top", "lower": "bottom"}
SUBPLOTS = re.compile(r"subplots\(\s*(?:nrows\s*=\s*)?(\d+)\s*,\s*(?:ncols\s*=\s*)?(\d+)")
FIGURE_NAME = re.compile(r"fig-[\w-]+")


def _panel_words(text):
    words = (a or b for a, b in PANEL_WORD.findall(text))
    return {_CANONICAL.get(w.lower(), w.lower()) for w in words}


def _words_of_grid(rows, cols):
    words = set()
    if rows > 1:
        words |= {"top", "bottom"} | ({"middle"} if rows > 2 else set())
    if cols > 1:
        words |= {"left", "right"} | ({"middle"} if cols > 2 else set())
    return words


def _figures(cell):
    """[(name, caption, allowed panel words)] of the images a code cell draws.

    The layout comes from the cell's ``subplots(rows, cols)`` when it draws one figure, else
    from each image's alt text (the position words it uses), else from the stored figure's
    axes count (one axes: no panels at all).
    """
    images = [
        out
        for out in cell.get("outputs", [])
        if any(k.startswith("image/") for k in out.get("data", {}))
    ]
    meta = cell.metadata
    specs = (meta.get("course") or {}).get("figures") or []
    if not specs and "mystnb" in meta:
        mystnb = meta["mystnb"]
        specs = [
            {
                "name": (mystnb.get("figure") or {}).get("name", ""),
                "caption": (mystnb.get("figure") or {}).get("caption", ""),
                "alt": (mystnb.get("image") or {}).get("alt", ""),
            }
        ]
    grids = SUBPLOTS.findall(cell.source)
    found = []
    for k, image in enumerate(images):
        spec = specs[k] if k < len(specs) else {"name": "", "caption": "", "alt": ""}
        if len(images) == 1 and len(grids) == 1:
            allowed = _words_of_grid(int(grids[0][0]), int(grids[0][1]))
        elif "with 1 Axes" in image["data"].get("text/plain", ""):
            allowed = set()
        else:
            allowed = _panel_words(spec.get("alt", "")) or {
                "left", "right", "top", "bottom", "middle"
            }  # fmt: skip
        found.append((spec.get("name", ""), spec.get("caption", ""), allowed))
    return found


def panel_mismatches(nb):
    """(cell index, words, allowed) for each text naming panels its figure does not have.

    A markdown cell describes the figures it names (``fig-...``); otherwise, when it ends by
    introducing what follows (a colon) and the next cell draws, that figure; otherwise the
    figure drawn by the cell just above it. A figure's caption describes its own figure.
    """
    drawn = {i: _figures(c) for i, c in enumerate(nb.cells) if c.cell_type == "code"}
    by_name = {name: allowed for figs in drawn.values() for name, _, allowed in figs if name}
    problems = []
    for i, figs in drawn.items():
        for _, caption, allowed in figs:
            words = _panel_words(caption)
            if words - allowed:
                problems.append((i, words, allowed))
    for i, cell in enumerate(nb.cells):
        if cell.cell_type != "markdown":
            continue
        words = _panel_words(cell.source)
        if not words:
            continue
        named = [by_name[n] for n in FIGURE_NAME.findall(cell.source) if n in by_name]
        if not named:
            following = drawn.get(i + 1, [])
            preceding = drawn.get(i - 1, [])
            introduces = cell.source.rstrip().endswith(":") and following
            named = [a for _, _, a in (following if introduces else preceding or following)]
        allowed = set().union(*named) if named else set()
        if words - allowed:
            problems.append((i, words, allowed))
    return problems


@pytest.mark.parametrize("path", ALL_NOTEBOOKS, ids=lambda p: str(p.relative_to(ROOT)))
def test_prose_names_only_the_panels_its_figure_has(path):
    problems = panel_mismatches(_read(path))
    assert not problems, "; ".join(
        f"{path.name}, cell {i}: names {sorted(words)} panels, the figure has "
        f"{sorted(allowed) or 'one panel'}"
        for i, words, allowed in problems
    )


def test_the_panel_check_can_fail():
    stacked = nbformat.v4.new_code_cell("fig, axes = plt.subplots(3, 1)\nplt.show()")
    stacked.outputs = [
        nbformat.v4.new_output(
            "display_data", data={"image/png": "", "text/plain": "<Figure with 3 Axes>"}
        )
    ]
    stacked.metadata["mystnb"] = {"figure": {"name": "fig-x", "caption": "Left: a."}}
    nb = nbformat.v4.new_notebook(
        cells=[
            stacked,
            nbformat.v4.new_markdown_cell("Left: this. Middle: that. Right: the rest."),
            nbformat.v4.new_markdown_cell("In the Upper panel of fig-x, this; nothing left: no."),
        ]
    )
    found = panel_mismatches(nb)
    assert [(i, sorted(w)) for i, w, _ in found] == [
        (0, ["left"]),
        (1, ["left", "middle", "right"]),
    ]
    side_by_side = stacked.source.replace("(3, 1)", "(1, 2)")
    nb.cells[0].source = side_by_side
    assert [(i, sorted(w)) for i, w, _ in panel_mismatches(nb)] == [
        (1, ["left", "middle", "right"]),
        (2, ["top"]),
    ]


# ---------------------------------------------------------------------------
# markup every front end renders (issue 39): JupyterLab, Notebook 7 and JupyterLite know no MyST
# ---------------------------------------------------------------------------
MYST_SOURCE = re.compile(r"\{[a-z:-]+\}`|^\s*(?::::+|```+)\s*\{", re.M)


@pytest.mark.parametrize("path", ALL_NOTEBOOKS, ids=lambda p: str(p.relative_to(ROOT)))
def test_markdown_cells_use_no_myst_roles_or_fences(path):
    """Cite a figure with a link to its name, ``[the figure above](#fig-...)``, and write a
    call-out as a block quote, ``> **Note.** ...``; the site numbers and boxes them
    (docs/_ext/course_site.py). tests/test_lab_markup.py checks the rendered pages."""
    for index, cell in enumerate(_read(path).cells):
        if cell.cell_type == "markdown":
            found = MYST_SOURCE.search(cell.source)
            assert found is None, f"{path.name}, cell {index}: MyST markup {found.group(0)!r}"


def test_the_myst_pattern():
    for raw in ("See {numref}`fig-1`.", ":::{note}\nx\n:::", "```{figure} a.png", "{py:func}`f`"):
        assert MYST_SOURCE.search(raw), raw
    for fine in ("[the figure above](#fig-1)", "> **Note.** x", "```python\nx = 1\n```", "{x}"):
        assert not MYST_SOURCE.search(fine), fine


#: What a notebook may cost in a fresh kernel (the course's promise to students).
NOTEBOOK_BUDGET_SECONDS = 30.0


@pytest.mark.after_notebooks
def test_every_notebook_runs_within_its_budget():
    """nbval's own run of each notebook in this session, kernel start included, stays within
    the budget. Skipped when the session ran no notebook (a subset of the tests)."""
    from conftest import NOTEBOOK_SECONDS

    if not NOTEBOOK_SECONDS:
        pytest.skip("no notebook ran in this session (the whole suite runs them with nbval)")
    slow = {
        path: round(seconds, 1)
        for path, seconds in sorted(NOTEBOOK_SECONDS.items())
        if seconds > NOTEBOOK_BUDGET_SECONDS
    }
    assert not slow, f"notebooks over {NOTEBOOK_BUDGET_SECONDS:g} s in nbval's run: {slow}"
