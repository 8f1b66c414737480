"""Sliders for the notebooks: move a parameter, watch the test react.

Seven explorers, one per place where a student would rather move a parameter
than read a table:

=====================  =========================================  ==========
explorer               sliders                                    notebook
=====================  =========================================  ==========
:func:`omt_widget`     α, outlier size                            01
:func:`power_widget`   fault size, α, σ                           02
:func:`ekf_widget`     q_β, fault size                            04
:func:`nis_widget`     correlation, anisotropy, K                 05
:func:`records_widget` number of records M                        06
:func:`glr_widget`     bias size, α                               07
:func:`b_method_widget` α₁, γ₀                                    07
=====================  =========================================  ==========

Each explorer is split in two. Its **update function** (``omt_view``,
``power_view``, ...) is a plain function: it takes the slider values and the
axes to draw on, draws, and returns the numbers it shows as a dict, so it is
unit-tested like any other function and can be called in a notebook without
widgets. Its **widget builder** (``omt_widget``, ...) wires ipywidgets
sliders (``continuous_update=False``: the figure is redrawn when the slider
is released) to the update function. ipywidgets is imported only by the
builders; it comes with the ``notebooks`` extra and is not needed by the
library or the tests. The sources of the examples are listed in the course
bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

import numpy as np

from .plotting.style import (
    REJECT,
    legend_outside,
    pair,
    shade_tail,
    styled,
    theory_grid,
    threshold_line,
)
from .results import critical_value, rejection_probability
from .validation import as_count, as_finite, as_positive, as_probability

__all__ = [
    "b_method_view",
    "b_method_widget",
    "ekf_view",
    "ekf_widget",
    "glr_view",
    "glr_widget",
    "nis_view",
    "nis_widget",
    "omt_view",
    "omt_widget",
    "power_view",
    "power_widget",
    "records_view",
    "records_widget",
]


def _axes(axes, n, **kwargs):
    """``n`` axes: the given ones, or a new figure of ``n`` panels one above the other.

    Stacked, not side by side, so that the figure fits the website's text column
    (at most ``style.MAX_WIDTH`` inches wide) and stays legible on a phone.
    """
    if axes is not None:
        axes = list(np.atleast_1d(axes))
        if len(axes) != n:
            raise ValueError(f"axes must hold {n} matplotlib axes, got {len(axes)}")
        return axes
    import matplotlib.pyplot as plt

    from .plotting.style import context

    with context():
        _, new = plt.subplots(n, 1, figsize=(7.0, 3.4 * n), **kwargs)
    return list(np.atleast_1d(new))


def _ipywidgets():
    try:
        import ipywidgets
    except ImportError:  # pragma: no cover - depends on the installation
        raise ImportError(
            "the sliders need ipywidgets: install it into this environment with "
            "`python -m pip install ipywidgets` (the student edition brings it)"
        ) from None
    return ipywidgets


def _slider(kind, description, value, lo, hi, step, **kwargs):
    widgets = _ipywidgets()
    cls = {"float": widgets.FloatSlider, "int": widgets.IntSlider, "log": widgets.FloatLogSlider}[
        kind
    ]
    options = dict(
        value=value,
        description=description,
        continuous_update=False,
        style={"description_width": "initial"},
        layout=widgets.Layout(width="420px"),
    )
    if kind == "log":
        options.update(base=10, min=lo, max=hi, step=step)
    else:
        options.update(min=lo, max=hi, step=step)
    options.update(kwargs)
    return cls(**options)


def _display_data(obj) -> dict:
    """``obj`` as a display_data output, formatted as the running IPython shows it."""
    from IPython import get_ipython

    shell = get_ipython()
    if shell is None:  # plain Python (a script, the tests): no front end to show an image
        data, metadata = {"text/plain": repr(obj)}, {}
    else:
        data, metadata = shell.display_formatter.format(obj)
    return {"output_type": "display_data", "data": data, "metadata": metadata}


def _build(update, sliders: dict):
    """Sliders above an output area that ``update(**values)`` redraws on release.

    The figure goes into the output area as the Output widget's state, set in the kernel, not
    by ``with output: display(figure)``. Output routed through ``with output:`` makes a
    notebook runner without a browser (nbconvert, ``jupyter execute``, the website build: all
    nbclient) send each output back to the kernel on the shell socket while it waits for the
    cell's reply on that socket; that send can swallow the reply's wake-up (jupyter_client
    sends through a blocking shadow of the asyncio socket), and the run then sits idle for the
    whole cell timeout (https://github.com/jupyter/nbclient/issues/312).
    """
    widgets = _ipywidgets()
    import matplotlib.pyplot as plt

    output = widgets.Output()

    def draw():
        open_before = set(plt.get_fignums())
        try:
            update(**{name: slider.value for name, slider in sliders.items()})
            return _display_data(plt.gcf())
        finally:  # the figure lives on in the output area only
            for number in set(plt.get_fignums()) - open_before:
                plt.close(number)

    def redraw(change):
        try:
            shown = draw()
        except Exception as error:  # shown where the figure would be, as `with output:` did
            shown = {
                "output_type": "stream",
                "name": "stderr",
                "text": f"{type(error).__name__}: {error}\n",
            }
        output.outputs = (shown,)

    output.outputs = (draw(),)  # the first figure; a bad fixed argument raises here
    for slider in sliders.values():
        slider.observe(redraw, names="value")
    rows = list(sliders.values())
    return widgets.VBox([widgets.HBox(rows[:2]), widgets.HBox(rows[2:]), output])


# ---------------------------------------------------------------------------
# 01: the overall model test and the w-tests against an outlier
# ---------------------------------------------------------------------------
@styled
def omt_view(alpha=0.05, outlier=15.0, *, record=0, index=4, sigma=2.0, axes=None):
    r"""Overall model test and w-tests of a MUDE sea-level record with an added outlier.

    Parameters
    ----------
    alpha : float
        Level of both tests.
    outlier : float
        Size of the error added to observation ``index`` (in the units of
        the record).
    record : int
        Which MUDE sea-level record (0..3) to start from.
    index : int
        Which observation gets the outlier.
    sigma : float
        Stated standard deviation of the observations.
    axes : pair of matplotlib axes, optional

    Returns
    -------
    dict
        ``T``, ``critical`` (of the overall model test), ``omt_reject``,
        ``w_reject`` (indices), ``w`` (the w-statistic of the observation
        with the outlier), ``omt_power`` and ``w_power`` (the
        probabilities that each test detects an outlier of this size).

    See Also
    --------
    course.lsq.overall_model_test : The overall model test.
    course.lsq.w_tests : The w-tests.
    course.lsq.mdb : Minimal detectable biases.

    Notes
    -----
    An outlier :math:`\nabla` in observation :math:`i` makes :math:`T`
    non-central :math:`\chi^2(m - n, \lambda)` and :math:`w_i` normal with mean
    :math:`\sqrt\lambda`, with

    .. math::

        \lambda = \nabla^2 \bigl(Q_{yy}^{-1} Q_{\hat e\hat e} Q_{yy}^{-1}\bigr)_{ii}

    (Teunissen 2000).
    """
    from scipy import stats

    from . import lsq

    alpha = as_probability(alpha, "alpha")
    outlier = as_finite(outlier, "outlier")
    sigma = as_positive(sigma, "sigma")
    t, y = lsq.load_sea_level(record)
    if not isinstance(index, (int, np.integer)) or not 0 <= index < t.size:
        raise ValueError(f"index must be an observation index 0..{t.size - 1}, got {index!r}")
    y = np.array(y, dtype=float)
    y[index] += outlier
    A = np.column_stack([np.ones_like(t), t])
    Qyy = sigma**2 * np.eye(t.size)
    fit = lsq.fit(A, y, Qyy)
    omt = lsq.overall_model_test(fit, alpha)
    wt = lsq.w_tests(fit, alpha)
    # non-centrality of an outlier of this size in observation `index`
    r_i = fit.redundancy_numbers[index]
    lam = outlier**2 * r_i / sigma**2
    dof = fit.redundancy
    omt_power = (
        rejection_probability(stats.ncx2(dof, lam), omt.critical_value) if lam > 0 else alpha
    )
    k = wt.critical_value
    # the outlier's w-statistic is N(sqrt(lam), 1); the w-test rejects |w| > k
    w_power = rejection_probability(stats.norm(loc=np.sqrt(lam)), (-k, k), "two-sided")

    ax_T, ax_w = _axes(axes, 2)
    upper = max(stats.chi2.isf(1e-3, dof), 1.15 * omt.statistic, stats.ncx2.isf(0.01, dof, lam))
    grid = theory_grid(0.0, upper, 401)[1:]
    null = stats.chi2.pdf(grid, dof)
    shade_tail(
        ax_T, grid, null, upper=omt.critical_value, label=rf"critical region, $\alpha$ = {alpha:g}"
    )
    ax_T.plot(grid, null, color=pair(0).dark, label=rf"$\chi^2({dof})$: no outlier")
    if lam > 0:
        ax_T.plot(
            grid,
            stats.ncx2.pdf(grid, dof, lam),
            color=pair(1).dark,
            label=rf"$\chi^2({dof}, \lambda$ = {lam:.1f}): power {omt_power:.2f}",
        )
    threshold_line(ax_T, omt.critical_value)
    ax_T.axvline(
        omt.statistic,
        color=REJECT.dark if omt.reject else pair(2).dark,
        lw=2,
        label=f"this record: T = {omt.statistic:.1f} → {'reject' if omt.reject else 'accept'}",
    )
    ax_T.set_xlabel("overall model test statistic $T$")
    ax_T.set_ylabel("density")
    ax_T.set_title(
        rf"overall model test: $T$ = {omt.statistic:.1f} against $\chi^2({dof})$"
        f" → {'reject' if omt.reject else 'accept'}"
    )
    legend_outside(ax_T)
    from .plotting.lsq import plot_w_tests

    plot_w_tests(wt, ax=ax_w)
    ax_w.set_title(f"w-tests: outlier {outlier:g} in observation {index}; power {w_power:.2f}")
    return {
        "T": float(omt.statistic),
        "critical": float(omt.critical_value),
        "omt_reject": bool(omt.reject),
        "w_reject": tuple(int(i) for i in wt.rejected),
        "w": float(wt.statistic[index]),
        "omt_power": omt_power,
        "w_power": w_power,
    }


def omt_widget(**fixed):
    """Sliders for α and the outlier size over :func:`omt_view` (notebook 01)."""
    sliders = {
        "alpha": _slider("float", "α", 0.05, 0.001, 0.2, 0.001, readout_format=".3f"),
        "outlier": _slider("float", "outlier [record units]", 15.0, 0.0, 25.0, 0.5),
    }
    return _build(lambda **v: omt_view(**v, **fixed), sliders)


# ---------------------------------------------------------------------------
# 02: power of prediction-error tests against fault size, alpha and noise
# ---------------------------------------------------------------------------
@styled
def power_view(size=0.2, alpha=0.05, sigma=0.2, *, U, nominal, free, ax=None, max_size=0.6):
    """Power of a prediction-error test against a fault in each parameter.

    Parameters
    ----------
    size : float
        The fault size marked on the curves (``|θ_i − θ_i⁰|``).
    alpha : float
        False-alarm rate of the test.
    sigma : float
        Noise standard deviation.
    U, nominal, free
        The test, as in :func:`course.diagnosis.prediction_error_power`.
    ax : matplotlib axes, optional
    max_size : float
        Right end of the fault-size axis.

    Returns
    -------
    dict
        Power against a fault of ``size`` in each parameter, ``{"F1": ..., ...}``.
    """
    from . import diagnosis as dg
    from .plotting.diagnosis import plot_power_curves

    size = as_finite(size, "size")
    alpha = as_probability(alpha, "alpha")
    sigma = as_positive(sigma, "sigma")
    max_size = as_positive(max(max_size, 1.2 * abs(size)), "max_size")
    nominal = np.asarray(nominal, dtype=float)
    grid = theory_grid(0.0, max_size)
    curves, at_size = {}, {}
    for i in range(nominal.size):
        mode = f"F{i + 1}"
        thetas = np.repeat(nominal[None, :], grid.size, axis=0)  # one parameter vector per row
        thetas[:, i] += grid
        curves[mode] = dg.prediction_error_power(U, nominal, free, thetas, sigma=sigma, alpha=alpha)
        theta = nominal.copy()
        theta[i] += size
        at_size[mode] = float(
            dg.prediction_error_power(U, nominal, free, theta, sigma=sigma, alpha=alpha)
        )
    (ax,) = _axes(ax, 1)
    plot_power_curves(
        grid,
        curves,
        alpha=alpha,
        ax=ax,
        colors={m: m for m in curves},
        xlabel=r"fault size $|\theta_i - 1|$",
    )
    ax.axvline(size, color="0.3", lw=1)
    for mode, p in at_size.items():
        ax.plot([size], [p], "o", color=pair(mode).dark, ms=7)
    ax.set_title(
        f"σ = {sigma:g}, α = {alpha:g}: power at size {size:g}: "
        + ", ".join(f"{m} {p:.2f}" for m, p in at_size.items())
    )
    return at_size


def power_widget(**fixed):
    """Sliders for fault size, α and σ over :func:`power_view` (notebook 02)."""
    sliders = {
        "size": _slider("float", "fault size", 0.2, 0.0, 0.6, 0.01),
        "alpha": _slider("float", "α", 0.05, 0.001, 0.2, 0.001, readout_format=".3f"),
        "sigma": _slider("float", "σ", 0.2, 0.05, 0.5, 0.01),
    }
    return _build(lambda **v: power_view(**v, **fixed), sliders)


# ---------------------------------------------------------------------------
# 04: the EKF residual generator: q_beta against fault size
# ---------------------------------------------------------------------------
@styled
def ekf_view(
    q_beta=1e-4,
    fault_size=0.2,
    *,
    runs=300,
    seed=20240504,
    window=10,
    alpha=0.001,
    t_fault=150,
    axes=None,
):
    """The lecture's EKF residual generator with a chosen random-walk variance and fault.

    Parameters
    ----------
    q_beta : float
        Variance of the random walk the filter assumes for β (0: constant).
    fault_size : float
        Sensor offset appearing at ``t_fault``.
    runs : int
        Monte Carlo runs for the alarm rate.
    seed : int
        Seed of the simulation (the same records for every slider position).
    window, alpha : int, float
        The windowed NIS test.
    t_fault : int
        Fault onset (sample).
    axes : three matplotlib axes, optional

    Returns
    -------
    dict
        ``false_alarm_rate`` (per sample, before the fault), ``detection``
        (share of runs with an alarm within ``window`` samples of the onset)
        and ``in_alarm_after`` (share of the samples after the fault in alarm).
    """
    from . import diagnosis as dg
    from . import filters as kf
    from . import nis
    from .plotting.filters import plot_alarm_rate, plot_estimate, plot_residual

    q_beta = as_finite(q_beta, "q_beta")
    if q_beta < 0:
        raise ValueError(f"q_beta must be >= 0 (a variance), got {q_beta:g}")
    fault_size = as_finite(fault_size, "fault_size")
    runs = as_count(runs, "runs")
    Ts, q_x, r, N = 0.1, 1e-4, 2.5e-3, 200
    t = np.arange(N)
    u = np.where((t // 40) % 2 == 0, 0.5, 1.5)
    beta = 0.8 + 0.6 * t / N
    fault = np.where(t >= t_fault, fault_size, 0.0)
    rng = np.random.default_rng(seed)
    _, y = dg.simulate_beta_system(
        beta, u, rng, Ts=Ts, q_x=q_x, r=r, x0=0.5, fault=fault, batch=runs
    )
    model = dg.beta_drift_model(Ts=Ts, q_beta=q_beta, q_x=q_x, r=r, x0_mean=(1.0, 0.5))
    result = kf.extended_kalman_filter(model, y, u)  # stores the covariances it draws
    P_filt = np.asarray(result.P_filt)
    statistic = nis.windowed_nis(result, window)
    threshold = nis.windowed_nis_threshold(window, alpha)
    with np.errstate(invalid="ignore"):
        alarm = statistic > threshold
    before = alarm[:, window - 1 : t_fault]
    after = alarm[:, t_fault:]
    numbers = {
        "false_alarm_rate": float(before.mean()),
        "detection": float(after[:, :window].any(axis=1).mean()),
        "in_alarm_after": float(after.mean()),
    }
    ax_r, ax_b, ax_a = _axes(axes, 3)
    plot_residual(
        t,
        result.eps[0],
        std=np.sqrt(result.S[0, :, 0, 0]),
        ax=ax_r,
        fault_time=t_fault,
        label="innovation (run 1)",
    )
    ax_r.set_title(rf"$q_\beta$ = {q_beta:g}, fault {fault_size:g}")
    plot_estimate(
        t,
        result.x_filt[0, :, 0],
        np.sqrt(P_filt[0, :, 0, 0]),
        truth=beta,
        ax=ax_b,
        label=r"$\hat\beta$ (run 1)",
        truth_label=r"true $\beta$",
        fault_time=t_fault,
        ylabel=r"$\beta$ [1/s]",
    )
    plot_alarm_rate(
        t,
        statistic,
        threshold,
        ax=ax_a,
        alpha=alpha,
        fault_time=t_fault,
        label=f"{runs} runs in alarm",
    )
    ax_a.set_yscale("log")
    ax_a.set_ylim(1 / (2 * runs), 1.5)
    ax_a.set_title(f"detected within {window} samples: {numbers['detection']:.2f}")
    return numbers


def ekf_widget(**fixed):
    """Sliders for q_β and the fault size over :func:`ekf_view` (notebook 04)."""
    sliders = {
        "q_beta": _slider("log", "q_β", 1e-4, -6, -2, 0.25),
        "fault_size": _slider("float", "fault size", 0.2, 0.0, 0.4, 0.01),
    }
    return _build(lambda **v: ekf_view(**v, **fixed), sliders)


# ---------------------------------------------------------------------------
# 05: the NIS and the NIS matrix against a covariance error
# ---------------------------------------------------------------------------
@styled
def nis_view(correlation=0.6, anisotropy=1.0, K=50, *, alpha=0.05, runs=4000, seed=2025, axes=None):
    """Whitened innovations of a filter whose covariance is wrong, and both tests' power.

    Parameters
    ----------
    correlation : float
        Correlation between the two whitened outputs (the filter assumes 0).
    anisotropy : float
        Variance ratio of the two outputs; the true covariance is
        ``[[a, ρ], [ρ, 1/a]]`` scaled to keep each direction's ``ρ``
        (``a = sqrt(anisotropy)``), whose determinant is ``1 − ρ²``.
    K : int
        Steps in the window.
    alpha : float
        Level of both tests.
    runs : int
        Monte Carlo windows for the power.
    seed : int
    axes : two matplotlib axes, optional

    Returns
    -------
    dict
        ``nis_power`` and ``matrix_power`` (Monte Carlo), ``eigenvalues`` of
        the true covariance, and the thresholds.
    """
    from . import nis
    from .plotting.nis import plot_whitened_scatter

    rho = as_finite(correlation, "correlation")
    if not -1 < rho < 1:
        raise ValueError(f"correlation must lie strictly between -1 and 1, got {rho:g}")
    ratio = as_positive(anisotropy, "anisotropy")
    K = as_count(K, "K")
    if K < 2:
        raise ValueError("K must be at least 2 (the window of a 2-output NIS matrix)")
    a = np.sqrt(ratio)
    sd = np.array([np.sqrt(a), 1 / np.sqrt(a)])
    truth = np.array([[1.0, rho], [rho, 1.0]]) * np.outer(sd, sd)
    L = np.linalg.cholesky(truth)
    rng = np.random.default_rng(seed)
    z = rng.standard_normal((runs, K, 2)) @ L.T
    Pi = np.einsum("rki,rkj->rij", z, z) / K
    lmin_lmax = np.linalg.eigvalsh(Pi)
    nis_lo, nis_hi = nis.nis_critical_values(2, K, alpha)
    lower, upper = nis.nis_matrix_critical_values(2, K, alpha)
    total = K * np.trace(Pi, axis1=1, axis2=2)
    nis_power = float(np.mean((total < nis_lo) | (total > nis_hi)))
    matrix_power = float(np.mean((lmin_lmax[:, 0] < lower) | (lmin_lmax[:, -1] > upper)))
    ax_z, ax_p = _axes(axes, 2)
    plot_whitened_scatter(z[0], ax=ax_z, thresholds=(lower, upper), truth=truth)
    ax_z.set_title(f"one window of K = {K} steps")
    se = lambda p: 1.96 * np.sqrt(p * (1 - p) / runs)  # noqa: E731
    names = ["NIS (χ² of the trace)", "NIS matrix (eigenvalues)"]
    values = [nis_power, matrix_power]
    ax_p.bar(
        names,
        values,
        color=[pair(0).light, pair(1).light],
        edgecolor=[pair(0).dark, pair(1).dark],
        yerr=[se(v) for v in values],
        capsize=4,
    )
    ax_p.axhline(alpha, color="0.4", ls=":", label=rf"$\alpha$ = {alpha:g}")
    ax_p.set_ylim(0, 1)
    ax_p.set_ylabel(f"probability of detection ({runs} windows)")
    ax_p.set_title(f"ρ = {rho:g}, variance ratio {ratio:g}")
    legend_outside(ax_p)
    eig = np.linalg.eigvalsh(truth)
    return {
        "nis_power": nis_power,
        "matrix_power": matrix_power,
        "eigenvalues": (float(eig[0]), float(eig[1])),
        "nis_thresholds": (float(nis_lo), float(nis_hi)),
        "matrix_thresholds": (float(lower), float(upper)),
    }


def nis_widget(**fixed):
    """Sliders for correlation, anisotropy and K over :func:`nis_view` (notebook 05)."""
    sliders = {
        "correlation": _slider("float", "correlation ρ", 0.6, -0.95, 0.95, 0.05),
        "anisotropy": _slider("log", "variance ratio", 1.0, -1, 1, 0.05),
        "K": _slider("int", "K (steps)", 50, 2, 200, 1),
    }
    return _build(lambda **v: nis_view(**v, **fixed), sliders)


# ---------------------------------------------------------------------------
# 06: laws and power of the section statistics against the number of records
# ---------------------------------------------------------------------------
@styled
def records_view(
    M=20,
    *,
    null,
    alternative,
    j,
    k=None,
    alpha=0.05,
    axes=None,
    kinds=("covariance", "correlation"),
):
    """Null and alternative laws of cross-record statistics for ``M`` records.

    Parameters
    ----------
    M : int
        Number of records.
    null, alternative : ResidualMoments
        Moments under ``(M⁰, M¹)`` and under ``(M², M¹)``.
    j, k : int
        Section (and second section for the correlation statistic).
    alpha : float
        Level of the two-sided tests.
    axes : matplotlib axes, one per kind, optional
    kinds : sequence of {"mean", "covariance", "correlation"}

    Returns
    -------
    dict
        The power of each test against the alternative.
    """
    from . import mismatched as mm

    M = as_count(M, "M")
    if M < 2:
        raise ValueError("M must be at least 2 records (a sample covariance needs two)")
    alpha = as_probability(alpha, "alpha")
    axs = _axes(axes, len(kinds))
    powers = {}
    for ax, kind in zip(axs, kinds):
        second = k if kind == "correlation" else None
        law0 = mm.statistic_law(null, kind, j, M, k=second)
        law2 = mm.statistic_law(alternative, kind, j, M, k=second)
        lo, hi = critical_value(law0, alpha, "two-sided")
        power = rejection_probability(law2, (lo, hi), "two-sided")
        powers[kind] = power
        left = min(float(law0.ppf(1e-3)), float(law2.ppf(1e-3)))
        right = max(float(law0.isf(1e-3)), float(law2.isf(1e-3)))
        grid = theory_grid(left, right)
        d0, d2 = law0.pdf(grid), law2.pdf(grid)
        index = {"mean": 0, "covariance": 1, "correlation": 2}[kind]
        ax.fill_between(
            grid,
            d2,
            where=(grid <= lo) | (grid >= hi),
            color=pair(index).light,
            lw=0,
            label=f"power {power:.2f}",
        )
        shade_tail(
            ax, grid, d0, lower=lo, upper=hi, label=rf"critical region, $\alpha$ = {alpha:g}"
        )
        ax.plot(grid, d0, color=pair("NF").dark, label="null law $(M^0, M^1)$")
        ax.plot(grid, d2, color=pair(index).dark, label="alternative $(M^2, M^1)$")
        threshold_line(ax, lo)
        threshold_line(ax, hi)
        ax.set_xlabel(f"{kind} statistic")
        ax.set_ylabel("density")
        ax.set_title(f"{kind} test, M = {M} records")
        legend_outside(ax, where="below")
    return powers


def records_widget(**fixed):
    """A slider for the number of records over :func:`records_view` (notebook 06)."""
    sliders = {"M": _slider("int", "records M", 20, 2, 200, 1)}
    return _build(lambda **v: records_view(**v, **fixed), sliders)


# ---------------------------------------------------------------------------
# 07: the power of tests of different dimension, and Baarda's B-method
# ---------------------------------------------------------------------------
@styled
def glr_view(size=6.0, alpha=0.05, *, sigma=2.0, ax=None, max_size=16.0):
    r"""Power of three tests against one outlier in observation 4 of a 20-epoch line fit.

    Parameters
    ----------
    size : float
        The outlier marked on the curves (in the units of the record).
    alpha : float
        Level of every test.
    sigma : float
        Standard deviation of the observations.
    ax : matplotlib axes, optional
    max_size : float
        Right end of the bias axis.

    Returns
    -------
    dict
        Power against an outlier of ``size`` in observation 4 of the w-test of
        observation 4 (``"q = 1"``), the test of observations 4 and 5 together
        (``"q = 2"``) and the overall model test (``"q = 18"``).

    See Also
    --------
    course.lsq.glr_test : The tests.
    course.lsq.alternative_law : Their laws under the outlier.

    Notes
    -----
    Each of the three alternatives contains the outlier :math:`\nabla c_4`
    (with the line, the overall model test's alternative spans everything), so
    each statistic is :math:`\chi^2(q, \lambda)` with the same
    :math:`\lambda = \nabla^2 r_4 / \sigma^2` (:math:`r_4` the redundancy number);
    the tests differ only in how many degrees of freedom share it. The test
    whose alternative is exactly the bias (q = 1) is the most powerful, the
    overall model test (q = m - n) the least (Teunissen 2000).
    """
    from . import chi2, lsq

    size = as_finite(size, "size")
    alpha = as_probability(alpha, "alpha")
    sigma = as_positive(sigma, "sigma")
    max_size = as_positive(max(max_size, 1.2 * abs(size)), "max_size")
    t = np.arange(1.0, 21.0)
    fit = lsq.fit(np.column_stack([np.ones_like(t), t]), np.zeros(t.size), sigma**2 * np.ones(20))
    lam_per_unit = float(fit.redundancy_numbers[4]) / sigma**2
    grid = theory_grid(0.0, max_size)
    (ax,) = _axes(ax, 1)
    at_size = {}
    labels = {
        1: "w-test of obs. 4",
        2: "obs. 4 and 5 together",
        fit.redundancy: "overall model test",
    }
    for k, (q, label) in enumerate(labels.items()):
        curve = chi2.chi2_power(q, lam_per_unit * grid**2, alpha)
        at_size[f"q = {q}"] = float(chi2.chi2_power(q, lam_per_unit * size**2, alpha))
        ax.plot(grid, curve, color=pair(k).dark, ls=pair(k).ls, label=f"{label} (q = {q})")
        ax.plot([size], [at_size[f"q = {q}"]], "o", color=pair(k).dark, ms=7)
    ax.axhline(alpha, color="0.5", lw=0.8, ls=":", label=rf"$\alpha$ = {alpha:g}")
    ax.axvline(size, color="0.3", lw=1)
    ax.set_xlabel(r"outlier $\nabla$ in observation 4")
    ax.set_ylabel("probability of rejection")
    ax.set_ylim(0.0, 1.02)
    ax.set_title(f"σ = {sigma:g}, α = {alpha:g}: outlier {size:g}")
    legend_outside(ax, where="below", ncol=2)
    return at_size


def glr_widget(**fixed):
    """Sliders for the outlier size and α over :func:`glr_view` (notebook 07)."""
    sliders = {
        "size": _slider("float", "outlier", 6.0, 0.0, 16.0, 0.5),
        "alpha": _slider("float", "α", 0.05, 0.001, 0.2, 0.001, readout_format=".3f"),
    }
    return _build(lambda **v: glr_view(**v, **fixed), sliders)


@styled
def b_method_view(alpha_1=0.001, power=0.80, *, max_q=30, ax=None):
    r"""Baarda's B-method: the level ``alpha_q`` of a q-dimensional test, for q = 1..max_q.

    Parameters
    ----------
    alpha_1 : float
        Level of the one-dimensional tests (w-tests).
    power : float
        Reference power γ0.
    max_q : int
        Largest dimension drawn.
    ax : matplotlib axes, optional

    Returns
    -------
    dict
        ``lambda0`` and ``alpha_q`` at q = 2, 5, 18 (18 = m - n of the sea-level line
        fits) and ``max_q``.

    See Also
    --------
    course.lsq.b_method : The computation.
    """
    from . import lsq

    alpha_1 = as_probability(alpha_1, "alpha_1")
    power = as_probability(power, "power")
    max_q = as_count(max_q, "max_q", minimum=2)
    q = np.arange(1, max_q + 1)
    b = lsq.b_method(alpha_1, power, q)
    (ax,) = _axes(ax, 1)
    ax.plot(q, b.alpha_q, "o-", color=pair(0).dark, ms=4, label=r"level $\alpha_q$")
    ax.axhline(alpha_1, color="0.5", lw=0.8, ls=":", label=rf"$\alpha_1$ = {alpha_1:g}")
    ax.set_yscale("log")
    ax.set_xlabel("dimension q of the test")
    ax.set_ylabel(r"level $\alpha_q$")
    ax.set_title(
        rf"$\lambda_0$ = {b.lambda0:.2f}: every test detects it with probability {power:g}"
    )
    legend_outside(ax, where="below", ncol=2)
    shown = {"lambda0": float(b.lambda0)}
    for k in sorted({2, 5, 18, max_q}):
        if k <= max_q:
            shown[f"alpha_{k}"] = float(b.alpha_q[k - 1])
    return shown


def b_method_widget(**fixed):
    """Sliders for α₁ and γ₀ over :func:`b_method_view` (notebook 07)."""
    sliders = {
        "alpha_1": _slider("log", "α₁", 0.001, -4, -1, 0.1, readout_format=".4f"),
        "power": _slider("float", "power γ₀", 0.80, 0.5, 0.99, 0.01),
    }
    return _build(lambda **v: b_method_view(**v, **fixed), sliders)
