"""The course's one figure style.

Every figure of the course is drawn by :mod:`course.plotting`, and every
plotting function draws in this style:

- **paired colours, safe for colour-blind readers**: each fault mode, filter
  or test owns a pair from the Okabe–Ito palette (a dark shade for lines,
  theory and estimates; a light shade for bands and shaded regions), so the
  same thing has the same colour in every notebook (``pair("F1")``,
  ``pair(0)``); each pair also owns a marker and a line style
  (``pair(k).marker``, ``pair(k).ls``), so curves told apart by colour are
  told apart without it too;
- **one look per kind of plot**: a simulated sample is a grey histogram
  (:data:`SAMPLE`, :func:`sample_histogram`) and the law it is compared
  with a dark line (:data:`LAW`), in every notebook;
- **shaded α tails**: the critical region of a test is filled in the
  "reject" colour (:func:`shade_tail`), its threshold drawn dashed black;
- **legends outside the data** (:func:`legend_outside`), so the curves the
  text talks about are never covered;
- **units and mathtext labels**: axis labels say what and in which unit
  (``"t [s]"``, ``r"$\\chi^2(18)$"``), never a bare ``"y"``;
- **theory on a fine grid** (:func:`theory_grid`, at least
  :data:`THEORY_POINTS` points) with Monte Carlo results as dots on the
  coarse grid where they were simulated (:func:`monte_carlo_dots`).

Nothing happens on import: :func:`use` switches the style on for a notebook
(call it once in the first cell), and every plotting function also draws
inside :func:`context`, so library figures keep the style without it.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

__all__ = [
    "LAW",
    "MAX_WIDTH",
    "RC_PARAMS",
    "REJECT",
    "SAMPLE",
    "THEORY_POINTS",
    "THRESHOLD",
    "Pair",
    "context",
    "legend_outside",
    "mark_time",
    "monte_carlo_dots",
    "pair",
    "plain_log_axis",
    "sample_histogram",
    "shade_tail",
    "styled",
    "theory_grid",
    "threshold_line",
    "use",
]

#: Smallest number of points on which a theoretical curve is drawn.
THEORY_POINTS = 241


class Pair(NamedTuple):
    """A colour pair: ``dark`` for lines and markers, ``light`` for fills.

    ``marker`` and ``ls`` (line style) go with the colour, so that two curves
    differ in shape as well as in hue.
    """

    dark: str
    light: str
    marker: str = "o"
    ls: str | tuple = "-"


# The Okabe–Ito palette (Okabe & Ito 2008), distinguishable under the common
# colour-vision deficiencies; each dark shade is paired with a light tint of
# itself (35 % colour on white) for bands and fills. Vermillion is kept for
# rejections and grey for the fault-free mode and reference material.
_PAIRS = (
    Pair("#0072b2", "#a6cbe0", "o", "-"),  # blue
    Pair("#e69f00", "#f7dca6", "s", "--"),  # orange
    Pair("#009e73", "#a6dccd", "^", "-."),  # bluish green
    Pair("#cc79a7", "#edd1e1", "D", ":"),  # reddish purple
    Pair("#56b4e9", "#cce7f7", "v", (0, (5, 1.5, 1, 1.5, 1, 1.5))),  # sky blue
    Pair("#000000", "#a6a6a6", "P", (0, (8, 2))),  # black
)
_GREY = Pair("#4d4d4d", "#c7c7c7", "o", "-")

#: The colour of rejections: critical regions, alarms, rejected observations (vermillion).
REJECT = Pair("#d55e00", "#f2c4a6", "x", "-")
#: Thresholds and critical values are dashed black lines.
THRESHOLD = "#000000"
#: Histograms of simulated samples, in every notebook: light grey bars.
SAMPLE = _GREY
#: A theoretical law (a density drawn over a sample): the blue pair's dark shade.
LAW = "#0072b2"
#: The widest figure of the course, in inches: it fits the website's text column.
MAX_WIDTH = 8.5

_NAMED = {"NF": _GREY, "none": _GREY, "reference": _GREY, "data": _GREY}


def pair(key) -> Pair:
    """The colour pair of a fault mode, filter or curve.

    Parameters
    ----------
    key : int or str
        ``"NF"`` (and ``"none"``, ``"reference"``, ``"data"``) are grey;
        ``"F1"``, ``"F2"``, ... take pair 0, 1, ...; an integer ``i`` takes
        pair ``i`` (cycling).

    Returns
    -------
    Pair
        ``(dark, light)`` hex colours.

    Examples
    --------
    >>> from course.plotting.style import pair
    >>> pair("F1") == pair(0)
    True
    >>> pair("NF").dark
    '#4d4d4d'
    """
    if isinstance(key, (bool, np.bool_)):
        raise ValueError(f"colour key must be an int or a name such as 'F1', got {key!r}")
    if isinstance(key, (int, np.integer)):
        return _PAIRS[int(key) % len(_PAIRS)]
    if isinstance(key, str):
        if key in _NAMED:
            return _NAMED[key]
        if key[:1] == "F" and key[1:].isdigit() and int(key[1:]) >= 1:
            return _PAIRS[(int(key[1:]) - 1) % len(_PAIRS)]
    raise ValueError(f"no colour pair for {key!r}: use an int, 'NF' or a fault name such as 'F2'")


#: rcParams of the style (the colour cycle, the dark shades of the pairs, is added on use).
RC_PARAMS = {
    "figure.figsize": (6.4, 3.6),
    "figure.dpi": 100,
    "figure.constrained_layout.use": True,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.grid": True,
    "axes.titlesize": "medium",
    "axes.labelsize": "medium",
    "grid.alpha": 0.35,
    "grid.linewidth": 0.5,
    "legend.frameon": False,
    "legend.fontsize": "small",
    "lines.linewidth": 1.5,
    "lines.markersize": 4.5,
    "font.size": 11,
    "image.cmap": "viridis",
    "mathtext.fontset": "dejavusans",
    "savefig.bbox": "tight",
}


def _rc() -> dict:
    from cycler import cycler

    return {**RC_PARAMS, "axes.prop_cycle": cycler(color=[p.dark for p in _PAIRS])}


def use() -> None:
    """Switch the course style on for the rest of the session (call once per notebook)."""
    import matplotlib as mpl

    mpl.rcParams.update(_rc())


def context():
    """A context manager drawing in the course style, restoring the settings afterwards."""
    import matplotlib as mpl

    return mpl.rc_context(_rc())


def styled(function: Callable) -> Callable:
    """Decorator: run a plotting function inside :func:`context`."""

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        with context():
            return function(*args, **kwargs)

    return wrapper


def legend_outside(ax, where: str = "right", **kwargs):
    """Place the legend of ``ax`` outside its data area.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    where : {"right", "below", "above"}
        Beside the axes (default), under the x-label, or above the title.
    **kwargs
        Passed to ``ax.legend`` (``ncol``, ``title``, ...).

    Returns
    -------
    matplotlib.legend.Legend or None
        None when nothing on the axes has a label.
    """
    handles, labels = ax.get_legend_handles_labels()
    if not handles:
        return None
    placement = {
        "right": dict(loc="upper left", bbox_to_anchor=(1.02, 1.0)),
        "below": dict(loc="upper center", bbox_to_anchor=(0.5, -0.2)),
        "above": dict(loc="lower center", bbox_to_anchor=(0.5, 1.08)),
    }
    if where not in placement:
        raise ValueError(f"where must be 'right', 'below' or 'above', got {where!r}")
    options = {**placement[where], "borderaxespad": 0.0}
    if where != "right":
        options["ncol"] = min(len(handles), 3)
    options.update(kwargs)
    return ax.legend(handles, labels, **options)


def theory_grid(lo: float, hi: float, num: int = THEORY_POINTS) -> np.ndarray:
    """An evenly spaced grid for drawing a theoretical curve (at least THEORY_POINTS points)."""
    if not (np.isfinite(lo) and np.isfinite(hi)) or not lo < hi:
        raise ValueError(f"theory_grid needs finite lo < hi, got lo={lo!r}, hi={hi!r}")
    return np.linspace(lo, hi, max(int(num), THEORY_POINTS))


def shade_tail(ax, x, density, lower=None, upper=None, label: str | None = "critical region"):
    """Fill the density over the critical region ``x < lower`` and/or ``x > upper``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    x, density : array_like
        The density curve, on a fine grid.
    lower, upper : float, optional
        Critical values; either or both.
    label : str or None
        Legend text of the shaded region (given once).
    """
    x = np.asarray(x, dtype=float)
    density = np.asarray(density, dtype=float)
    for k, (bound, side) in enumerate(((lower, "lower"), (upper, "upper"))):
        if bound is None:
            continue
        mask = x <= bound if side == "lower" else x >= bound
        if not np.any(mask):
            continue
        # close the region exactly at the critical value
        xs = np.append(x[mask], bound) if side == "lower" else np.insert(x[mask], 0, bound)
        ys = np.interp(xs, x, density)
        first = label if (k == 0 or lower is None) else None
        ax.fill_between(xs, ys, color=REJECT.light, lw=0, label=first, zorder=1)
    return ax


def sample_histogram(ax, sample, bins=40, label: str | None = "simulated", **kwargs):
    """A simulated sample as a density histogram in the course's one sample colour.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    sample : array_like
        The simulated values.
    bins : int or sequence
        Passed to ``ax.hist``.
    label : str or None
        Legend text.
    **kwargs
        Passed to ``ax.hist`` (``range``, ...).

    Returns
    -------
    tuple
        What ``ax.hist`` returns (heights, bin edges, patches).
    """
    options = dict(density=True, color=SAMPLE.light, edgecolor="white", linewidth=0.3)
    options.update(kwargs)
    return ax.hist(np.asarray(sample, dtype=float), bins=bins, label=label, **options)


def plain_log_axis(ax, axis: str = "y"):
    """A logarithmic axis labelled with plain numbers, one kind of label only.

    Matplotlib's default labels a short log axis with a mix of ``10^k`` and
    ``2 x 10^k`` in two sizes; this keeps plain ``%g`` labels (``0.001``,
    ``0.01`` ...) and no minor labels: at 1, 2 and 5 times each power of ten
    when the data span at most two and a half decades, at the powers of ten
    otherwise. Call it after the data are drawn.
    """
    from matplotlib import ticker

    if axis not in ("x", "y"):
        raise ValueError(f"axis must be 'x' or 'y', got {axis!r}")
    target = ax.yaxis if axis == "y" else ax.xaxis
    (ax.set_yscale if axis == "y" else ax.set_xscale)("log")
    lo, hi = ax.get_ylim() if axis == "y" else ax.get_xlim()
    few = lo > 0 and np.log10(hi / lo) <= 2.5
    target.set_major_locator(ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0) if few else (1.0,)))
    target.set_major_formatter(ticker.FuncFormatter(lambda value, _: f"{value:g}"))
    target.set_minor_formatter(ticker.NullFormatter())
    return ax


def threshold_line(ax, value, label: str | None = None, orientation: str = "vertical"):
    """A dashed black line at a critical value (vertical) or a level (horizontal)."""
    draw = ax.axvline if orientation == "vertical" else ax.axhline
    return draw(value, color=THRESHOLD, ls="--", lw=1.0, label=label, zorder=3)


def mark_time(ax, t, label: str | None = "fault appears"):
    """A dotted vertical line at an event time (a fault onset)."""
    return ax.axvline(t, color=REJECT.dark, ls=":", lw=1.2, label=label, zorder=3)


def monte_carlo_dots(ax, x, y, color_pair: Pair, label: str | None = None, yerr=None):
    """Monte Carlo results as dots (with optional error bars) on their coarse grid.

    The marker is the colour pair's own (``color_pair.marker``), so two series
    differ in shape as well as in colour.
    """
    if yerr is None:
        return ax.plot(
            x,
            y,
            color_pair.marker,
            ms=4.5,
            mfc=color_pair.light,
            mec=color_pair.dark,
            mew=1.0,
            ls="none",
            label=label,
            zorder=4,
        )
    return ax.errorbar(
        x,
        y,
        yerr=yerr,
        fmt=color_pair.marker,
        ms=4.5,
        mfc=color_pair.light,
        mec=color_pair.dark,
        ecolor=color_pair.dark,
        elinewidth=1.0,
        capsize=2,
        label=label,
        zorder=4,
    )
