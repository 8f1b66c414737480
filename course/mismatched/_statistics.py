"""The statistics of a cross-record section: mean, covariance and correlation.

The works cited here are in the course bibliography,
:doc:`/docs/bibliography`.
"""

from __future__ import annotations

import numpy as np

from course.mismatched._moments import (  # residual_moments: the Examples call it
    EigenDirections,
    ResidualMoments,
    SingularDirections,
    _as_records,
    _check_moments,
    _index,
    _scaled_sections,
    _times_square,
    residual_moments,  # noqa: F401
)
from course.validation import (
    as_float_array,
)

# ---------------------------------------------------------------------------
# statistics of a cross-record section
# ---------------------------------------------------------------------------


def _unit(v, p, name) -> np.ndarray:
    v = as_float_array(v, name)
    if v.shape != (p,):
        raise ValueError(f"{name} must be a vector of length p = {p}, got shape {v.shape}")
    norm = np.linalg.norm(v)
    if not np.isclose(norm, 1.0, rtol=1e-8):
        raise ValueError(f"{name} must be a unit vector (norm 1), got norm {norm:.6g}")
    return v


def principal_directions(moments: ResidualMoments, j: int, k: int | None = None):
    r"""Principal directions of ``P_j`` or of ``C(j, k)`` under the null pair.

    Parameters
    ----------
    moments : ResidualMoments
        Moments under the null pair ``(M^0, M^1)``.
    j : int
        Section (time index).
    k : int, optional
        Second section: directions of ``C(j, k)`` instead of ``P_j``.

    Returns
    -------
    EigenDirections or SingularDirections
        For ``k is None``: :class:`EigenDirections` ``(values, vectors)``,
        the eigenvalues of ``P_j`` in decreasing order and the eigenvectors
        as the *columns* of ``vectors``.  Otherwise
        :class:`SingularDirections` ``(values, left, right)``, the singular
        value decomposition ``C(j, k) = U diag(s) W^T``: ``left[:, g]``
        projects ``r_j`` and ``right[:, g]`` projects ``r_k``.  Both are
        named tuples: ``lam, V = ...`` and ``s, U, W = ...``.

    See Also
    --------
    covariance_statistic : The statistic projected on these directions.
    correlation_statistic : The cross-time statistic projected on them.

    Notes
    -----
    Baram (1980), (2.7) and (2.13)-(2.15), corrected: a residual is projected
    on a principal direction by :math:`v_g^{\mathsf T} r = (V^{\mathsf T} r)_g`
    (the paper prints :math:`a^{(g)} V_j r`, a row of :math:`V_j`); and
    :math:`C(j, k)` is not symmetric, so its left and right principal
    directions differ and come from an SVD, with
    :math:`E\,c^{(g)}(j, k) = \frac{M-1}{M} s_g`.

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> values, vectors = principal_directions(residual_moments(true, filt, 5), 2)
    >>> vectors.shape
    (1, 1)
    """
    N = _check_moments(moments).n_steps
    j = _index(j, N, "j")
    if k is None:
        lam, V = np.linalg.eigh(moments.cov[j])
        return EigenDirections(lam[::-1], V[:, ::-1])
    k = _index(k, N, "k")
    U, s, Wt = np.linalg.svd(moments.C(j, k))
    return SingularDirections(s, U, Wt.T)


def mean_statistic(residuals, j: int) -> float:
    r"""Mean statistic of section ``j``: the squared norm of the cross-record mean.

    Parameters
    ----------
    residuals : (M, N, p) or (M, N) array_like
        Residuals of ``M >= 2`` records.
    j : int
        Section (time index).

    Returns
    -------
    float
        ``||rbar_j||^2 = rbar_j^T rbar_j`` with ``rbar_j = (1/M) sum_i r_ij``.

    See Also
    --------
    mean_test : The test of this statistic.
    mean_matrix : The statistic as a quadratic form.

    Notes
    -----
    Baram (1980), (2.5)-(2.6): the paper writes
    :math:`\lVert \bar r_j \rVert = \bar r_j^{\mathsf T} \bar r_j`; the
    statistic is the *squared* norm,

    .. math::

        \lVert \bar r_j \rVert^2 = \bar r_j^{\mathsf T} \bar r_j
        = \varphi_j^{\mathsf T} A \varphi_j

    of (3.2)-(3.3) (see :func:`mean_matrix`).

    Examples
    --------
    >>> mean_statistic([[1.0, 2.0], [3.0, 0.0]], 0)   # two records, mean 2 at time 0
    4.0
    """
    r = _as_records(residuals)
    j = _index(j, r.shape[1], "j")
    (rj,), c = _scaled_sections(r, j)
    rbar = rj.mean(axis=0)
    return _times_square(rbar @ rbar, c)


def covariance_statistic(residuals, j: int, direction=None) -> float:
    r"""Sample covariance statistic of section ``j``.

    Parameters
    ----------
    residuals : (M, N, p) or (M, N) array_like
        Residuals of ``M >= 2`` records.
    j : int
        Section (time index).
    direction : (p,) array_like, optional
        A unit vector ``v`` (normally a principal direction of the null
        ``P_j``, see :func:`principal_directions`).

    Returns
    -------
    float
        ``c_j = tr Pbar_j = (1/M) sum_i |r_ij - rbar_j|^2``, or with a
        direction ``c_j^(g) = (1/M) sum_i (v^T (r_ij - rbar_j))^2``.

    See Also
    --------
    covariance_test : The test of this statistic.
    covariance_matrix : The statistic as a quadratic form.
    principal_directions : The directions of the projected statistic.

    Notes
    -----
    Baram (1980), (2.16)-(2.17) and (2.13)-(2.14) corrected: the projected
    statistic averages the *squared* projections (averaging the projections
    themselves gives zero identically) and projects with :math:`V_j^{\mathsf T}`.
    With the divisor :math:`M` and the sample mean removed,

    .. math::

        E\,c_j = \frac{M-1}{M} \operatorname{tr} P_j, \qquad
        E\,c_j^{(g)} = \frac{M-1}{M} v^{\mathsf T} P_j v.

    Examples
    --------
    >>> covariance_statistic([[1.0, 2.0], [3.0, 0.0]], 0)   # ((1-2)^2 + (3-2)^2) / 2
    1.0
    """
    r = _as_records(residuals)
    j = _index(j, r.shape[1], "j")
    (rj,), c = _scaled_sections(r, j)
    dev = rj - rj.mean(axis=0)
    if direction is None:
        return _times_square(np.mean(np.sum(dev * dev, axis=1)), c)
    v = _unit(direction, r.shape[2], "direction")
    return _times_square(np.mean((dev @ v) ** 2), c)


def correlation_statistic(residuals, j: int, k: int, directions=None) -> float:
    r"""Sample correlation statistic of sections ``j`` and ``k``.

    Parameters
    ----------
    residuals : (M, N, p) or (M, N) array_like
        Residuals of ``M >= 2`` records.
    j, k : int
        The two sections (time indices).
    directions : pair of (p,) array_like, optional
        Unit vectors ``(u, w)``, normally the left and right singular
        vectors of the null ``C(j, k)`` (:func:`principal_directions`).

    Returns
    -------
    float
        ``c(j, k) = tr Cbar(j, k) = (1/M) sum_i (r_ij - rbar_j)^T (r_ik -
        rbar_k)``, or with directions ``c^(g)(j, k) = (1/M) sum_i (u^T (r_ij
        - rbar_j)) (w^T (r_ik - rbar_k))``.

    See Also
    --------
    correlation_test : The test of this statistic.
    correlation_matrix : The statistic as a quadratic form.
    principal_directions : The singular directions it projects on.

    Notes
    -----
    Baram (1980), (2.12), and (2.7)-(2.9) with an SVD in place of the principal
    directions of the non-symmetric :math:`C(j, k)`;

    .. math::

        E\,c^{(g)}(j, k) = \frac{M-1}{M} u^{\mathsf T} C(j, k) w.

    With an SVD the projected statistics no longer add up to the trace as
    (2.11)-(2.12) state (that needs one orthonormal basis on both sides).

    Examples
    --------
    >>> correlation_statistic([[1.0, 2.0], [3.0, 0.0]], 0, 1)   # ((-1)(1) + (1)(-1)) / 2
    -1.0
    """
    r = _as_records(residuals)
    N, p = r.shape[1], r.shape[2]
    j, k = _index(j, N, "j"), _index(k, N, "k")
    (rj, rk), c = _scaled_sections(r, j, k)
    dj = rj - rj.mean(axis=0)
    dk = rk - rk.mean(axis=0)
    if directions is None:
        return _times_square(np.mean(np.sum(dj * dk, axis=1)), c)
    u, w = _pair(directions, p)
    return _times_square(np.mean((dj @ u) * (dk @ w)), c)


def _pair(directions, p, name="directions"):
    if isinstance(directions, (str, bytes)):
        raise ValueError(f"{name} must be a pair (u, w) of unit vectors, got {directions!r}")
    try:
        u, w = directions
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair (u, w) of unit vectors") from None
    return _unit(u, p, f"{name}[0] (u)"), _unit(w, p, f"{name}[1] (w)")
