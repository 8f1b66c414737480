"""The course's figures: one style, every function checked, bad input refused at once.

Every public plotting function is called with good data (the style
contract: it returns its axes, puts its legend outside the data, labels its
axes, never shows the figure) and with bad data (NaN, infinities, empty or
wrongly shaped arrays: a ValueError naming the argument).
"""

from __future__ import annotations

import functools
import importlib
import pkgutil

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg", force=True)
import matplotlib.pyplot as plt  # noqa: E402

from course import diagnosis as dg  # noqa: E402
from course import filters as kf  # noqa: E402
from course import lsq, mismatched  # noqa: E402
from course.plotting import diagnosis as pd  # noqa: E402
from course.plotting import filters as pf  # noqa: E402
from course.plotting import lsq as pl  # noqa: E402
from course.plotting import mismatched as pm  # noqa: E402
from course.plotting import nis as pn  # noqa: E402
from course.plotting import style  # noqa: E402

T4 = np.arange(1.0, 5.0)
A_LINE = np.column_stack([np.ones(4), T4])
DAY1 = np.array([14.0, 20.0, 20.0, 24.0])
STRUCTURE = dg.DecisionStructure.from_text("NF F1 F2 F3\nT1 0 0 X X\nT2 0 X 0 X\nT3 0 X X 0")


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


@pytest.fixture(autouse=True)
def _no_show(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("library plotting code must not call plt.show()")

    monkeypatch.setattr(plt, "show", refuse)


@functools.cache
def _fit1():
    return lsq.fit(A_LINE, DAY1)


@functools.cache
def _kalman():
    model = kf.LinearModel(F=[[0.9]], H=[[1.0]], Q=[[0.5]], R=[[1.0]], x0_cov=[[4.0]])
    _, y = model.simulate(10, np.random.default_rng(3))
    return kf.kalman_filter(model, y), y


@functools.cache
def _moments():
    m0 = kf.LinearModel(F=[[0.9]], H=[[1.0]], Q=[[0.5]], R=[[1.0]], x0_cov=[[1.0]])
    m1 = kf.LinearModel(F=[[0.8]], H=[[1.0]], Q=[[1.0]], R=[[1.0]], x0_cov=[[1.0]])
    moments = mismatched.residual_moments(m0, m1, 8)
    records = mismatched.simulate_records(m0, m1, 40, 8, np.random.default_rng(4))
    return moments, records


RNG = np.random.default_rng(0)
CHI2 = RNG.chisquare(3, 400)
STAT = np.abs(RNG.standard_normal((20, 30))) * 10
STAT[:, :4] = np.nan


@functools.cache
def _iso():
    membership = np.array([[1, 1, 1, 1], [0, 1, 0, 0], [0.1, 0.2, 0.9, 0.1], [0, 0.1, 0, 1.0]])
    return dg.IsolationResult(
        STRUCTURE, STRUCTURE.modes, np.zeros((4, 3)), membership, np.ones(4), 10
    )


@functools.cache
def _extreme():
    from course import nis

    return nis.extreme_eigenvalue(2, 20, "min"), nis.extreme_eigenvalue(2, 20, "max")


# name -> (function, positional args, keyword args): one good call per public function
GOOD = {
    "lsq.plot_line_fit": (pl.plot_line_fit, lambda: (T4, DAY1, _fit1()), {}),
    "lsq.plot_residual_segments": (pl.plot_residual_segments, lambda: (T4, DAY1, _fit1()), {}),
    "lsq.plot_projection_geometry": (
        pl.plot_projection_geometry,
        lambda: (np.array([[1.0, -1.0], [1.0, 0.0], [1.0, 1.0]]), np.array([1.0, 3.0, 2.0])),
        {},
    ),
    "lsq.plot_error_bars": (pl.plot_error_bars, lambda: (T4, DAY1, 1.0), {}),
    "lsq.plot_confidence_band": (pl.plot_confidence_band, lambda: (T4, _fit1()), {}),
    "lsq.plot_sum_of_squares": (
        pl.plot_sum_of_squares,
        lambda: (A_LINE, DAY1, np.linspace(6, 18, 13), np.linspace(0, 6, 7)),
        {"log10": True, "minimum": (12.0, 3.0)},
    ),
    "lsq.plot_chi2_histogram": (pl.plot_chi2_histogram, lambda: (CHI2, 3), {"alpha": 0.05}),
    "lsq.plot_w_tests": (
        pl.plot_w_tests,
        lambda: (lsq.w_tests(lsq.fit(A_LINE, [28.0, 20.0, 16.0, 36.0]), 0.01),),
        {},
    ),
    "lsq.plot_data_snooping_loop": (
        pl.plot_data_snooping_loop,
        lambda: (lsq.data_snooping(lsq.fit(A_LINE, [28.0, 20.0, 16.0, 36.0]), alpha=0.01),),
        {},
    ),
    "diagnosis.plot_residual_geometry": (
        pd.plot_residual_geometry,
        lambda: (np.sin(np.arange(10.0)), np.cos(np.arange(10.0)), -0.6),
        {},
    ),
    "diagnosis.plot_decision_structure": (
        pd.plot_decision_structure,
        lambda: (STRUCTURE,),
        {"alarms": [False, True, True]},
    ),
    "diagnosis.plot_density": (pd.plot_density, lambda: (0.0, 1.0, 2.0), {}),
    "diagnosis.plot_likelihood": (pd.plot_likelihood, lambda: ([3.0, 5.0],), {}),
    "diagnosis.plot_criterion": (
        pd.plot_criterion,
        lambda: (np.linspace(0, 2, 50), np.linspace(0, 2, 50) ** 2),
        {"minimiser": 0.0},
    ),
    "diagnosis.plot_null_histogram": (
        pd.plot_null_histogram,
        lambda: (CHI2, __import__("scipy.stats").stats.chi2(3), 7.81),
        {},
    ),
    "diagnosis.plot_power_curves": (
        pd.plot_power_curves,
        lambda: (
            np.linspace(0, 1, 5),
            {"T1": np.linspace(0.05, 1, 241)},
            {"T1": np.linspace(0.05, 1, 5)},
        ),
        {"theory_sizes": np.linspace(0, 1, 241), "alpha": 0.05, "n_records": 100},
    ),
    "diagnosis.plot_isolation": (pd.plot_isolation, lambda: (_iso(),), {}),
    "diagnosis.plot_recursive_estimates": (
        pd.plot_recursive_estimates,
        lambda: (np.arange(30), np.linspace(1, 2, 30)),
        {"band": np.full(30, 0.1)},
    ),
    "diagnosis.plot_windowed_statistic": (
        pd.plot_windowed_statistic,
        lambda: (np.arange(30), STAT[0], 12.0),
        {},
    ),
    "filters.plot_signals": (
        pf.plot_signals,
        lambda: (np.arange(30), np.sin(np.arange(30.0)), np.ones(30)),
        {"fault_time": 20},
    ),
    "filters.plot_estimate": (
        pf.plot_estimate,
        lambda: (np.arange(30), np.ones(30), np.full(30, 0.1)),
        {"truth": np.ones(30), "fault_time": 20},
    ),
    "filters.plot_residual": (
        pf.plot_residual,
        lambda: (np.arange(30), np.sin(np.arange(30.0))),
        {"std": np.ones(30)},
    ),
    "filters.plot_test_statistic": (
        pf.plot_test_statistic,
        lambda: (np.arange(30), STAT[0], 12.0),
        {"log": True},
    ),
    "filters.plot_alarm_rate": (
        pf.plot_alarm_rate,
        lambda: (np.arange(30), STAT, 12.0),
        {"alpha": 0.01, "fault_time": 20},
    ),
    "filters.plot_delay_histogram": (
        pf.plot_delay_histogram,
        lambda: (np.array([0.0, 2.0, np.nan, 5.0]),),
        {},
    ),
    "filters.plot_normalized_histogram": (
        pf.plot_normalized_histogram,
        lambda: (RNG.standard_normal(500),),
        {},
    ),
    "filters.plot_kalman_timeline": (
        pf.plot_kalman_timeline,
        lambda: _kalman(),
        {"steps": slice(0, 6)},
    ),
    "nis.plot_sample_against_law": (
        pn.plot_sample_against_law,
        lambda: (CHI2, __import__("scipy.stats").stats.chi2(3)),
        {"label": "draws", "law_label": "chi2(3)"},
    ),
    "nis.plot_extreme_laws": (
        pn.plot_extreme_laws,
        lambda: _extreme(),
        {"thresholds": (0.3, 2.0)},
    ),
    "nis.plot_cdf_errors": (
        pn.plot_cdf_errors,
        lambda: (np.linspace(0, 1, 20), {"a": np.linspace(-0.01, 0.01, 20)}),
        {},
    ),
    "nis.plot_detection": (
        pn.plot_detection,
        lambda: ([2, 4, 8], {"NIS": [0.05, 0.1, 0.2], "matrix": [0.05, 0.2, 0.5]}),
        {"alpha": 0.05, "n_runs": 400},
    ),
    "nis.plot_consistency": (
        pn.plot_consistency,
        lambda: (np.arange(20), 2 + RNG.standard_normal(20) * 0.3, (1.5, 2.6)),
        {},
    ),
    "nis.plot_whitened_scatter": (
        pn.plot_whitened_scatter,
        lambda: (RNG.standard_normal((40, 2)),),
        {"thresholds": (0.5, 1.6), "truth": np.eye(2)},
    ),
    "mismatched.plot_residual_band": (pm.plot_residual_band, lambda: _moments(), {}),
    "mismatched.plot_records_matrix": (pm.plot_records_matrix, lambda: (_moments()[1],), {"j": 3}),
    "mismatched.plot_cross_record_section": (
        pm.plot_cross_record_section,
        lambda: (_moments()[1], 3),
        {"moments": _moments()[0]},
    ),
    "mismatched.plot_cross_covariance": (pm.plot_cross_covariance, lambda: (_moments()[0],), {}),
    "mismatched.plot_law_against_sample": (
        pm.plot_law_against_sample,
        lambda: (CHI2, __import__("scipy.stats").stats.chi2(3)),
        {"critical": (0.2, 9.3)},
    ),
    "mismatched.plot_imhof_integrands": (
        pm.plot_imhof_integrands,
        lambda: (
            np.linspace(0, 5, 50),
            np.sin(np.linspace(0, 5, 50)),
            np.exp(-np.linspace(0, 5, 50)),
        ),
        {},
    ),
    "mismatched.plot_power_curves": (
        pm.plot_power_curves,
        lambda: ([3, 10, 30], {"mean test": [0.1, 0.3, 0.7]}),
        {"alpha": 0.05, "simulated": {"mean test": [(10, 0.32)]}, "n_experiments": 500},
    ),
}


def _plotting_modules():
    """Every public module of course.plotting but the style, found (not listed): a new
    plotting module's functions need a good call below or the test fails."""
    package = importlib.import_module("course.plotting")
    for info in pkgutil.iter_modules(package.__path__):
        if not info.name.startswith("_") and info.name != "style":
            yield importlib.import_module(f"course.plotting.{info.name}")


PUBLIC = sorted(
    f"{module.__name__.rsplit('.', 1)[1]}.{name}"
    for module in _plotting_modules()
    for name in module.__all__
    if name.startswith("plot_")
)


def test_every_public_plotting_function_has_a_good_call():
    assert sorted(GOOD) == PUBLIC


def _overlaps(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


@pytest.mark.parametrize("name", sorted(GOOD))
def test_style_contract(name):
    function, args, kwargs = GOOD[name]
    ax = function(*args(), **kwargs)
    assert ax is not None and hasattr(ax, "figure"), f"{name} must return its axes"
    fig = ax.figure
    fig.set_dpi(40)  # the geometry is the same at any resolution, and drawing is faster
    fig.canvas.draw()
    legend = ax.get_legend()
    if legend is not None:
        # the legend sits outside the data area: it never covers what the text talks about
        assert not _overlaps(legend.get_window_extent(), ax.get_window_extent()), name
    if ax.axison and not name.endswith(("decision_structure", "isolation")):
        assert ax.get_xlabel() and ax.get_ylabel(), f"{name} must label both axes"
        assert ax.get_ylabel() != "y" and ax.get_xlabel() != "x", name
    # a library figure made from scratch is constrained-laid-out (the style is on)
    if name not in ("lsq.plot_projection_geometry",):
        assert fig.get_layout_engine() is not None


def test_theory_curves_are_drawn_on_fine_grids():
    ax = pl.plot_chi2_histogram(CHI2, 3, alpha=0.05)
    densities = [line for line in ax.get_lines() if "density" in str(line.get_label())]
    assert densities and all(line.get_xdata().size >= style.THEORY_POINTS for line in densities)
    ax = pd.plot_null_histogram(CHI2, __import__("scipy.stats").stats.chi2(3), 7.8)
    assert max(np.size(line.get_xdata()) for line in ax.get_lines()) >= style.THEORY_POINTS


def test_alpha_tail_is_shaded_exactly_beyond_the_critical_value():
    from scipy import stats

    ax = pl.plot_chi2_histogram(CHI2, 3, alpha=0.05)
    region = [c for c in ax.collections if c.get_label().startswith("critical region")]
    assert len(region) == 1
    x = region[0].get_paths()[0].vertices[:, 0]
    assert x.min() == pytest.approx(stats.chi2.isf(0.05, 3))


def test_style_is_opt_in_and_pairs_are_stable():
    import matplotlib as mpl

    before = mpl.rcParams["axes.spines.top"]
    import importlib

    importlib.reload(style)
    assert mpl.rcParams["axes.spines.top"] == before  # importing changes nothing
    with style.context():
        assert mpl.rcParams["axes.spines.top"] is False
    assert style.pair("F2") == style.pair(1) and style.pair("NF") != style.pair(0)
    with pytest.raises(ValueError, match="no colour pair"):
        style.pair("G7")


def test_decision_structure_figure_shows_the_diagnoses():
    ax = pd.plot_decision_structure(STRUCTURE, alarms=["T2", "T3"])
    texts = [t.get_text() for t in ax.texts]
    assert texts.count("✓") == 1 and texts.count("alarm") == 2  # only F1 explains T2 and T3
    assert [tick.get_text() for tick in ax.get_yticklabels()][-1] == "diagnoses"
    # the surviving mode keeps its own colour (F1's pair), not another fault's
    f1_cell = [p for p in ax.patches if tuple(np.round(p.get_xy(), 2)) == (1.0, 3.1)]
    assert len(f1_cell) == 1
    assert matplotlib.colors.to_hex(f1_cell[0].get_facecolor()) == style.pair("F1").light


def test_whitened_scatter_reports_nis_as_the_trace():
    z = np.random.default_rng(5).standard_normal((30, 2))
    ax = pn.plot_whitened_scatter(z)
    expected = f"{np.trace(z.T @ z / 30):.2f}"
    assert any(expected in str(line.get_label()) for line in ax.get_lines())


def test_isolation_figure_colours_distance_from_the_ideal():
    ax = pd.plot_isolation(_iso())
    image = ax.get_images()[0].get_array()
    assert float(image[0].max()) == 0.0  # NF row all ones: ideal, white
    assert float(image[2, 1]) == pytest.approx(0.2)


# ---------------------------------------------------------------------------
# bad input: a clear ValueError naming the argument, before anything is drawn
# ---------------------------------------------------------------------------
BAD_VALUES = {
    "nan": lambda good: np.where(
        np.arange(np.size(good)).reshape(np.shape(good)) == 0, np.nan, good
    ),
    "inf": lambda good: np.where(
        np.arange(np.size(good)).reshape(np.shape(good)) == 0, np.inf, good
    ),
    "empty": lambda good: np.array([]),
    "ndim": lambda good: np.stack([np.asarray(good, float)] * 2, axis=-1),
}

# (name in GOOD, index of the positional argument or keyword, argument name, kinds)
CASES = [
    ("lsq.plot_line_fit", 0, "t", "nan inf empty ndim"),
    ("lsq.plot_line_fit", 1, "y", "nan inf empty ndim"),
    ("lsq.plot_residual_segments", 1, "y", "nan inf empty ndim"),
    ("lsq.plot_error_bars", 1, "y", "nan inf empty ndim"),
    ("lsq.plot_confidence_band", 0, "t", "nan inf empty ndim"),
    ("lsq.plot_sum_of_squares", 1, "y", "nan inf empty ndim"),
    ("lsq.plot_chi2_histogram", 0, "T", "nan inf empty ndim"),
    ("lsq.plot_projection_geometry", 1, "y", "nan inf empty ndim"),
    ("diagnosis.plot_residual_geometry", 0, "U1", "nan inf empty ndim"),
    ("diagnosis.plot_criterion", 1, "values", "nan inf empty ndim"),
    ("diagnosis.plot_null_histogram", 0, "samples", "nan inf empty ndim"),
    ("diagnosis.plot_likelihood", 0, "z", "nan inf empty ndim"),
    ("diagnosis.plot_recursive_estimates", 1, "theta", "nan inf empty"),
    ("diagnosis.plot_windowed_statistic", 1, "statistic", "inf empty ndim"),
    ("filters.plot_signals", 1, "y", "nan inf empty"),
    ("filters.plot_estimate", 1, "estimate", "inf empty"),
    ("filters.plot_residual", 1, "residual", "nan inf empty"),
    ("filters.plot_test_statistic", 1, "statistic", "inf empty ndim"),
    ("filters.plot_alarm_rate", 1, "statistic", "inf empty"),
    ("filters.plot_delay_histogram", 0, "delays", "inf empty ndim"),
    ("filters.plot_normalized_histogram", 0, "z", "inf empty"),
    ("nis.plot_sample_against_law", 0, "sample", "nan inf empty ndim"),
    ("nis.plot_whitened_scatter", 0, "z", "nan inf empty"),
    ("nis.plot_consistency", 1, "averages", "nan inf empty ndim"),
    ("mismatched.plot_law_against_sample", 0, "sample", "nan inf empty ndim"),
    ("mismatched.plot_imhof_integrands", 1, "real_axis", "nan inf empty ndim"),
]
PARAMS = [
    pytest.param(name, index, arg, kind, id=f"{name}-{arg}-{kind}")
    for name, index, arg, kinds in CASES
    for kind in kinds.split()
]


@pytest.mark.parametrize(("name", "index", "arg", "kind"), PARAMS)
def test_bad_input_is_refused_naming_the_argument(name, index, arg, kind):
    function, args, kwargs = GOOD[name]
    args = list(args())
    args[index] = BAD_VALUES[kind](np.asarray(args[index], dtype=float))
    with pytest.raises(ValueError, match=rf"\b{arg}\b"):
        function(*args, **kwargs)


def test_two_dimensional_T_is_refused_at_once():
    # it used to draw one histogram per column: more than 10 s for 20 000 x 20
    with pytest.raises(ValueError, match=r"T must be 1-D.*shape \(20000, 20\)"):
        pl.plot_chi2_histogram(np.ones((20000, 20)), 18)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: pl.plot_chi2_histogram(CHI2, 0), "dof"),
        (lambda: pl.plot_chi2_histogram(CHI2, 2.5), "dof"),
        (lambda: pl.plot_chi2_histogram(CHI2, 3, alpha=1.5), "alpha"),
        (lambda: pl.plot_chi2_histogram(CHI2, 3, alpha="0.05"), "alpha"),  # text, as validation
        (lambda: pl.plot_chi2_histogram(CHI2, "3"), "dof"),
        (lambda: pl.plot_chi2_histogram(CHI2, 3, bins=None), "bins"),
        (lambda: pl.plot_error_bars(T4, DAY1, -1.0), "sigma"),
        (lambda: pl.plot_error_bars(T4, DAY1, [1.0, 2.0]), "sigma"),
        (lambda: pl.plot_line_fit(T4[:3], DAY1, _fit1()), "same length"),
        (lambda: pl.plot_line_fit(T4, DAY1, _fit1(), show_data="no"), "show_data"),
        (lambda: pd.plot_decision_structure(STRUCTURE, alarms=[True]), "alarms"),
        (lambda: pd.plot_decision_structure(STRUCTURE, alarms=["T9"]), "alarms"),
        (lambda: pd.plot_power_curves([0, 1], {"a": [0.1] * 5}), "theory"),
        (lambda: pf.plot_alarm_rate(np.arange(30), STAT[0], 12.0), "statistic"),
        (lambda: pf.plot_kalman_timeline(_kalman()[0], steps=[99]), "steps"),
        (lambda: pn.plot_whitened_scatter(np.ones((10, 3))), "two columns"),
        (lambda: pm.plot_records_matrix(_moments()[1], j=99), "j"),
        (lambda: pl.plot_w_tests(lsq.w_tests(_fit1(), 0.05), ax="left"), "ax"),
    ],
)
def test_other_bad_arguments(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_sum_of_squares_axis_names_its_unit():
    t = np.arange(6.0)
    A, y = np.column_stack([np.ones_like(t), t]), 1.0 + 0.5 * t + 0.1 * np.sin(t)
    grid = np.linspace(0.0, 2.0, 5)
    ax = pl.plot_sum_of_squares(A, y, grid, grid, surface=True)
    assert "m$^2$" in ax.get_zlabel()
    fig, ax = plt.subplots()
    pl.plot_sum_of_squares(A, y, grid, grid, log10=True, ax=ax)
    assert "m$^2$" in fig.axes[-1].get_ylabel()  # the colour bar
    plt.close("all")


def test_consistency_marks_points_outside_with_one_legend_entry():
    _, ax = plt.subplots()
    times = np.arange(5)
    pn.plot_consistency(times, [1.0, 3.0, 1.0, 1.0, 1.0], (0.5, 2.0), ax=ax, label="a")
    pn.plot_consistency(times, [1.0, 1.0, 0.1, 1.0, 1.0], (0.5, 2.0), ax=ax, label="b", color=1)
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert labels.count("outside the interval") == 1
    _, ax = plt.subplots()
    pn.plot_consistency(times, np.ones(5), (0.5, 2.0), ax=ax, label="inside")
    assert "outside the interval" not in [t.get_text() for t in ax.get_legend().get_texts()]
    plt.close("all")


# ---------------------------------------------------------------------------
# figures that read at the page (issue 29)
# ---------------------------------------------------------------------------
def test_the_palette_is_okabe_ito_with_a_marker_and_line_style_per_pair():
    okabe_ito = {"#0072b2", "#e69f00", "#009e73", "#cc79a7", "#56b4e9", "#000000", "#d55e00"}
    pairs = [style.pair(k) for k in range(6)]
    assert {p.dark for p in pairs} | {style.REJECT.dark} <= okabe_ito
    assert len({p.marker for p in pairs}) == 6 and len({str(p.ls) for p in pairs}) == 6


def test_every_simulated_sample_histogram_has_the_one_sample_colour():
    from scipy import stats

    rng = np.random.default_rng(2)
    draws = rng.chisquare(3, 400)
    axes = [
        pl.plot_chi2_histogram(draws, 3, alpha=0.05),
        pd.plot_null_histogram(draws, stats.chi2(3), 7.8),
        pf.plot_normalized_histogram(rng.standard_normal(400)),
        pn.plot_sample_against_law(draws, stats.chi2(3)),
        pm.plot_law_against_sample(draws, stats.chi2(3)),
    ]
    for ax in axes:
        bars = [p for p in ax.patches if type(p).__name__ == "Rectangle" and p.get_height() > 0]
        assert bars
        assert {matplotlib.colors.to_hex(p.get_facecolor()) for p in bars} == {style.SAMPLE.light}
    plt.close("all")


def test_isolation_colour_scale_ends_at_the_largest_distance_and_shows_exact():
    ax = pd.plot_isolation(_iso())
    image = ax.get_images()[0]
    assert image.get_clim()[1] == pytest.approx(0.2)  # the largest |P - ideal| is 0.2, not 1
    assert [t.get_text() for t in ax.get_xticklabels()][-1] == "exact"
    assert sum(t.get_text() == "1.00" for t in ax.texts) >= 3  # the exact column is written out
    plt.close("all")


def test_whitened_scatter_frame_is_set_by_the_ring_not_by_an_outlier():
    z = np.random.default_rng(4).standard_normal((50, 2))
    z[0] = (8.0, 0.0)
    ax = pn.plot_whitened_scatter(z, thresholds=(0.55, 1.6))
    assert ax.get_xlim()[1] < 5.0
    labels = [str(line.get_label()) for line in ax.get_lines()]
    assert any("1 outside the frame" in label for label in labels)
    radius = np.sqrt(np.trace(z.T @ z / 50) / 2)
    assert any(f"= {radius:.2f}" in label for label in labels)  # the dotted circle's own radius
    plt.close("all")


def test_imhof_integrands_on_log_axes_show_absolute_values():
    u = np.geomspace(0.01, 10.0, 50)
    ax = pm.plot_imhof_integrands(u, np.sin(u) / u, np.exp(-u), log=True)
    assert ax.get_yscale() == "log" and ax.get_xscale() == "log"
    assert all(np.all(line.get_ydata() > 0) for line in ax.get_lines())
    plt.close("all")


def test_plain_log_axis_has_one_kind_of_label():
    _, ax = plt.subplots()
    ax.plot([1, 2, 3], [0.002, 0.02, 0.05])
    style.plain_log_axis(ax)
    plt.gcf().canvas.draw()
    labels = [t.get_text() for t in ax.get_yticklabels() if t.get_text()]
    assert labels and all("times" not in s and "^" not in s for s in labels)
    assert not [t.get_text() for t in ax.yaxis.get_minorticklabels() if t.get_text()]
    plt.close("all")


def test_cross_covariance_diagonal_is_not_white():
    moments = mismatched.residual_moments(
        kf.LinearModel(F=[[0.9]], H=[[1.0]], Q=[[0.5]], R=[[1.0]]),
        kf.LinearModel(F=[[0.8]], H=[[1.0]], Q=[[1.0]], R=[[1.0]]),
        6,
    )
    ax = pm.plot_cross_covariance(moments)
    bad = ax.get_images()[0].get_cmap().get_bad()
    assert matplotlib.colors.to_hex(bad) != "#ffffff"
    plt.close("all")


def test_power_curves_differ_in_marker_and_line_style():
    ax = pm.plot_power_curves(
        [3, 10, 30], {"mean test": [0.1, 0.2, 0.3], "covariance test": [0.1, 0.2, 0.3]}
    )
    lines = [line for line in ax.get_lines() if "(exact)" in str(line.get_label())]
    assert len({line.get_marker() for line in lines}) == 2
    assert len({str(line.get_linestyle()) for line in lines}) == 2
    plt.close("all")
