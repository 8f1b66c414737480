"""The course's one figure style.

Every figure of the course is drawn by :mod:`course.plotting`, and every
plotting function draws in this style:

- **paired colours**: each fault mode, filter or test owns a pair (a dark
  shade for lines, theory and estimates; a light shade for bands, histograms
  and shaded regions), so the same thing has the same colour in every
  notebook (``pair("F1")``, ``pair(0)``);
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
    "RC_PARAMS",
    "REJECT",
    "THEORY_POINTS",
    "THRESHOLD",
    "Pair",
    "context",
    "legend_outside",
    "mark_time",
    "monte_carlo_dots",
    "pair",
    "shade_tail",
    "styled",
    "theory_grid",
    "threshold_line",
    "use",
]

#: Smallest number of points on which a theoretical curve is drawn.
THEORY_POINTS = 241


class Pair(NamedTuple):
    """A colour pair: ``dark`` for lines and markers, ``light`` for fills."""

    dark: str
    light: str


# ColorBrewer "Paired" (light, dark) reordered so that the first four pairs
# are the ones a reader tells apart most easily; grey is reserved for the
# fault-free mode and for reference material.
_PAIRS = (
    Pair("#1f78b4", "#a6cee3"),  # blue
    Pair("#ff7f00", "#fdbf6f"),  # orange
    Pair("#33a02c", "#b2df8a"),  # green
    Pair("#6a3d9a", "#cab2d6"),  # purple
    Pair("#b15928", "#f3c9a5"),  # brown
    Pair("#e7298a", "#f4b6d6"),  # magenta
)
_GREY = Pair("#4d4d4d", "#c7c7c7")

#: The colour of rejections: critical regions, alarms, rejected observations.
REJECT = Pair("#d7191c", "#f7b5b5")
#: Thresholds and critical values are dashed black lines.
THRESHOLD = "#000000"

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
    "font.size": 10,
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


def threshold_line(ax, value, label: str | None = None, orientation: str = "vertical"):
    """A dashed black line at a critical value (vertical) or a level (horizontal)."""
    draw = ax.axvline if orientation == "vertical" else ax.axhline
    return draw(value, color=THRESHOLD, ls="--", lw=1.0, label=label, zorder=3)


def mark_time(ax, t, label: str | None = "fault appears"):
    """A dotted vertical line at an event time (a fault onset)."""
    return ax.axvline(t, color=REJECT.dark, ls=":", lw=1.2, label=label, zorder=3)


def monte_carlo_dots(ax, x, y, color_pair: Pair, label: str | None = None, yerr=None):
    """Monte Carlo results as dots (with optional error bars) on their coarse grid."""
    if yerr is None:
        return ax.plot(
            x,
            y,
            "o",
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
        fmt="o",
        ms=4.5,
        mfc=color_pair.light,
        mec=color_pair.dark,
        ecolor=color_pair.dark,
        elinewidth=1.0,
        capsize=2,
        label=label,
        zorder=4,
    )
