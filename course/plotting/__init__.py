"""Plotting for the course notebooks.

Library code never plots; every figure of the course is drawn by a function
in this package, in the one course style (:mod:`course.plotting.style`:
paired colours, shaded α tails, legends outside the data, units and mathtext
labels, theory on fine grids).  Each function takes ``ax=None`` (a new
figure is made when it is None), returns the axes it drew on and never calls
``plt.show()``; bad input (NaN, infinities, empty or wrongly shaped arrays)
raises a ``ValueError`` naming the argument.  One submodule per topic:

- :mod:`course.plotting.lsq` – line fits, residuals and their geometry, error
  bars, confidence bands, sum-of-squares surfaces, chi-square histograms,
  w-tests and the data-snooping loop.
- :mod:`course.plotting.diagnosis` – decision structures, residual geometry,
  likelihoods, isolation tables and detection probabilities.
- :mod:`course.plotting.filters` – signals, innovations with their bands,
  parameter tracks, the Kalman filter's predict/update timeline,
  false-alarm and detection-delay studies.
- :mod:`course.plotting.nis` – whitened innovations, eigenvalue laws against
  Monte Carlo, detection probability against the number of samples.
- :mod:`course.plotting.mismatched` – records over time, residual moments
  over many records, quadratic-form laws, critical regions and power.

Matplotlib is imported lazily inside the functions, so importing
:mod:`course` never loads it. The figures follow the course's sources, which
are listed in full in the course bibliography, :doc:`/docs/bibliography`.
"""

from __future__ import annotations

import numpy as np

from . import style

__all__ = ["axes_or_new", "style"]


def axes_or_new(ax=None, **subplot_kw):
    """Return ``ax``, or a fresh axes on a new figure (in the course style) when ``ax`` is None."""
    if ax is not None:
        if not hasattr(ax, "figure") or not hasattr(ax, "plot"):
            raise ValueError(f"ax must be a matplotlib Axes or None, got {type(ax).__name__}")
        return ax
    import matplotlib.pyplot as plt

    with style.context():
        _, ax = plt.subplots(subplot_kw=subplot_kw or None)
    return ax


def _mark_alarms(ax, t, statistic, threshold, marker="o", **kwargs):
    """Mark the samples of ``statistic`` (an ndarray) above ``threshold``; NaN never alarms."""
    with np.errstate(invalid="ignore"):
        alarm = statistic > threshold
    if np.any(alarm):
        options = dict(color=style.REJECT.dark, ms=3.5, ls="none", label="alarm", zorder=5)
        options.update(kwargs)
        ax.plot(np.asarray(t)[alarm], statistic[alarm], marker, **options)
