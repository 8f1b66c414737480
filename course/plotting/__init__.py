"""Plotting for the course notebooks.

Library code never plots; every figure of the course is drawn by a function
in this package.  Each function takes ``ax=None`` (a new figure is made when
it is None) and returns the axes it drew on, so notebooks can compose and
restyle figures.  One submodule per topic:

- :mod:`course.plotting.lsq` – line fits, error bars, confidence bands,
  sum-of-squares surfaces, chi-square histograms, w-tests.
- :mod:`course.plotting.diagnosis` – decision structures, residual geometry,
  likelihoods, confusion matrices and detection probabilities.
- :mod:`course.plotting.filters` – signals, innovations with their bands,
  parameter tracks, false-alarm and detection-delay studies.
- :mod:`course.plotting.nis` – eigenvalue laws against Monte Carlo, detection
  probability against the number of samples.
- :mod:`course.plotting.mismatched` – residual moments over many records,
  quadratic-form laws, critical regions and power.

Matplotlib is imported lazily inside the functions, so importing
:mod:`course` never loads it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["axes_or_new"]


def axes_or_new(ax=None, **subplot_kw):
    """Return ``ax``, or a fresh axes on a new figure when ``ax`` is None."""
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    _, ax = plt.subplots(subplot_kw=subplot_kw or None)
    return ax


def _mark_alarms(ax, t, statistic, threshold, marker, **style):
    """Mark the samples of ``statistic`` (an ndarray) above ``threshold``; NaN never alarms."""
    with np.errstate(invalid="ignore"):
        alarm = statistic > threshold
    if np.any(alarm):
        ax.plot(np.asarray(t)[alarm], statistic[alarm], marker, label="alarm", **style)
