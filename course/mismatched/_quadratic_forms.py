"""The section statistics as quadratic forms in normal variables (Baram section 3) and their exact laws.

The works cited here are in the course bibliography,
:doc:`/docs/bibliography`.
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from course.linalg import symmetrize
from course.mismatched._moments import (  # residual_moments: the Examples call it
    ResidualMoments,
    SectionMoments,
    _check_moments,
    _index,
    _outputs,
    residual_moments,  # noqa: F401
)
from course.mismatched._statistics import _pair, _unit
from course.quadform import QuadraticForm, WeightedChiSquare
from course.validation import (
    as_count,
    as_flag,
)


# ---------------------------------------------------------------------------
# the statistics as quadratic forms (Baram section 3)
# ---------------------------------------------------------------------------
def _centering(M) -> np.ndarray:
    return np.eye(M) - np.full((M, M), 1.0 / M)


def _check_M(M: Any) -> int:
    return as_count(M, "M", minimum=2, what="the number of records")


def mean_matrix(M: int, p: int) -> np.ndarray:
    """Matrix ``A`` of the mean statistic as a quadratic form, ``||rbar_j||^2 = phi_j^T A phi_j``.

    Parameters
    ----------
    M : int
        Number of records, ``M >= 2``.
    p : int
        Residual dimension.

    Returns
    -------
    ndarray, shape (M p, M p)
        ``A = (1/M^2) 1 1^T kron I_p``, for ``phi_j = (r_1j, ..., r_Mj)``.

    See Also
    --------
    mean_statistic : The statistic this matrix gives as a quadratic form.
    statistic_law : Its law.

    Notes
    -----
    Baram (1980), (3.1)-(3.3).  The paper writes :math:`I_n`; the blocks act on
    :math:`p`-dimensional residuals, so they are :math:`I_p`.

    Examples
    --------
    >>> import numpy as np
    >>> phi = np.array([1.0, 3.0])                  # one time, two records, p = 1
    >>> float(phi @ mean_matrix(2, 1) @ phi)        # the squared norm of the mean, 2^2
    4.0
    """
    M = _check_M(M)
    return np.kron(np.full((M, M), 1.0 / M**2), np.eye(_outputs(p)))


def covariance_matrix(M: int, p: int, direction=None) -> np.ndarray:
    r"""Matrix ``G`` of the covariance statistic as a quadratic form, ``c_j = phi_j^T G phi_j``.

    Parameters
    ----------
    M : int
        Number of records, ``M >= 2``.
    p : int
        Residual dimension.
    direction : (p,) array_like, optional
        Unit vector ``v`` of the projected statistic.

    Returns
    -------
    ndarray, shape (M p, M p)
        ``G = (1/M) J kron I_p``, or ``D (J/M) D^T`` with ``D = I_M kron v``.

    See Also
    --------
    covariance_statistic : The statistic this matrix gives as a quadratic form.
    statistic_law : Its law.

    Notes
    -----
    Baram (1980), (3.11)-(3.15);

    .. math::

        J = I_M - \tfrac1M \mathbf 1 \mathbf 1^{\mathsf T}

    removes the sample mean (3.10), and needs :math:`\otimes I_p` for vector
    residuals.

    Examples
    --------
    >>> import numpy as np
    >>> phi = np.array([1.0, 3.0])
    >>> float(phi @ covariance_matrix(2, 1) @ phi)  # covariance_statistic of the same section
    1.0
    """
    M = _check_M(M)
    p = _outputs(p)
    J = _centering(M) / M
    if direction is None:
        return np.kron(J, np.eye(p))
    v = _unit(direction, p, "direction")[:, None]
    D = np.kron(np.eye(M), v)
    return D @ J @ D.T


def correlation_matrix(M: int, p: int, directions=None) -> np.ndarray:
    r"""Matrix ``B`` of the correlation statistic, ``c(j, k) = phi(j, k)^T B phi(j, k)``.

    Parameters
    ----------
    M : int
        Number of records, ``M >= 2``.
    p : int
        Residual dimension.
    directions : pair of (p,) array_like, optional
        Unit vectors ``(u, w)`` of the projected statistic.

    Returns
    -------
    ndarray, shape (2 M p, 2 M p)
        For ``phi(j, k) = (phi_j, phi_k)``:
        ``B = (1/2M) [[0, J kron I_p], [J kron I_p, 0]]``, or with directions
        ``D B_M D^T``, ``D = blockdiag(I_M kron u, I_M kron w)``.

    See Also
    --------
    correlation_statistic : The statistic this matrix gives as a quadratic form.
    statistic_law : Its law.

    Notes
    -----
    Baram (1980), (3.4)-(3.10), with :math:`J \otimes I_p` for vector residuals
    and, in (3.7)-(3.8), the left and right singular vectors of :math:`C(j, k)`
    in place of one set of principal directions.

    Examples
    --------
    >>> import numpy as np
    >>> phi = np.array([1.0, 3.0, 2.0, 0.0])        # (section j, section k)
    >>> float(phi @ correlation_matrix(2, 1) @ phi)
    -1.0
    """
    M = _check_M(M)
    p = _outputs(p)
    J = _centering(M)
    zero = np.zeros((M, M))
    B_M = np.block([[zero, J], [J, zero]]) / (2 * M)
    if directions is None:
        return np.kron(B_M, np.eye(p))
    u, w = _pair(directions, p)
    D = np.zeros((2 * M * p, 2 * M))
    D[: M * p, :M] = np.kron(np.eye(M), u[:, None])
    D[M * p :, M:] = np.kron(np.eye(M), w[:, None])
    return D @ B_M @ D.T


def section_moments(moments: ResidualMoments, j: int, M: int):
    """Mean and covariance of the stacked section ``phi_j = (r_1j, ..., r_Mj)``.

    Parameters
    ----------
    moments : ResidualMoments
    j : int
        Section (time index).
    M : int
        Number of records.

    Returns
    -------
    SectionMoments
        ``mean`` ``(M p,)``: ``1 kron m_j``; ``cov`` ``(M p, M p)``:
        ``I_M kron P_j`` (records are independent).

    See Also
    --------
    pair_moments : The moments of two sections together.
    residual_moments : The moments of the residual itself.

    Notes
    -----
    Baram (1980), (3.18) and (3.20).

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> mean, cov = section_moments(residual_moments(true, filt, 5), 2, M=3)
    >>> mean.shape, cov.shape
    ((3,), (3, 3))
    """
    M = _check_M(M)
    j = _index(j, _check_moments(moments).n_steps, "j")
    return SectionMoments(np.tile(moments.mean[j], M), np.kron(np.eye(M), moments.cov[j]))


def pair_moments(moments: ResidualMoments, j: int, k: int, M: int):
    r"""Mean and covariance of the stacked pair of sections ``phi(j, k) = (phi_j, phi_k)``.

    Parameters
    ----------
    moments : ResidualMoments
    j, k : int
        The two sections.
    M : int
        Number of records.

    Returns
    -------
    SectionMoments
        ``mean`` ``(2 M p,)`` and ``cov`` ``(2 M p, 2 M p)``,
        ``[[I_M kron P_j, I_M kron C(j, k)], [I_M kron C(j, k)^T, I_M kron P_k]]``.

    See Also
    --------
    section_moments : The moments of one section.

    Notes
    -----
    Baram (1980), (3.19) and (3.21)-(3.23), with
    :math:`C(j, k) = E\,(r_j - m_j)(r_k - m_k)^{\mathsf T}` ((2.4) corrected).

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> mean, cov = pair_moments(residual_moments(true, filt, 5), 1, 3, M=3)
    >>> mean.shape, cov.shape
    ((6,), (6, 6))
    """
    M = _check_M(M)
    N = _check_moments(moments).n_steps
    j, k = _index(j, N, "j"), _index(k, N, "k")
    mean = np.concatenate([np.tile(moments.mean[j], M), np.tile(moments.mean[k], M)])
    I = np.eye(M)
    Cjk = moments.C(j, k)
    cov = np.block(
        [
            [np.kron(I, moments.cov[j]), np.kron(I, Cjk)],
            [np.kron(I, Cjk.T), np.kron(I, moments.cov[k])],
        ]
    )
    return SectionMoments(mean, symmetrize(cov))


_KINDS = ("mean", "covariance", "correlation")
# Eigenvalues of a covariance below this share of the largest (times the size)
# leave it to the general reduction (the zero share of QuadraticForm).
_FULL_RANK_RTOL = 1e-12
_LAWS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def statistic_law(
    moments: ResidualMoments,
    kind: str,
    j: int,
    M: int,
    k: int | None = None,
    direction=None,
    full: bool = False,
):
    r"""Exact law of a section statistic when the residuals have ``moments``.

    Parameters
    ----------
    moments : ResidualMoments
        From :func:`residual_moments` of the pair that generates the data:
        ``(M^0, M^1)`` for critical regions, ``(M^2, M^1)`` for the power.
    kind : {"mean", "covariance", "correlation"}
    j : int
        Section (time index).
    M : int
        Number of records.
    k : int, optional
        Second section, for the correlation statistic.
    direction : array_like or (u, w), optional
        A unit vector for the projected covariance statistic, a pair of unit
        vectors for the projected correlation statistic; ``None`` for the
        trace statistics.
    full : bool
        Build the paper's ``M p`` (or ``2 M p``) dimensional quadratic form
        ``phi^T A phi`` of section 3 (slow, for checking); by default the
        equivalent reduced form below is used.

    Returns
    -------
    WeightedChiSquare or QuadraticForm
        With ``cdf``, ``sf``, ``ppf``, ``isf``, ``mean``, ``var``, ``rvs``.

    See Also
    --------
    mean_test : The mean test that uses this law.
    covariance_test : The covariance test that uses it.
    correlation_test : The correlation test that uses it.
    course.quadform.QuadraticForm : The law of a quadratic form.

    Notes
    -----
    Records are independent, so the Helmert transform turns the centred
    section into :math:`M - 1` independent copies of the centred residual:

    - mean: :math:`\bar r_j \sim N(m_j, P_j / M)`, so
      :math:`\lVert \bar r_j \rVert^2` is ``QuadraticForm(I_p, m_j, P_j/M)``;
    - covariance: :math:`c_j = \frac1M \sum_{l<M} \lVert z_l \rVert^2`,
      :math:`z_l \sim N(0, P_j)`: weights :math:`\operatorname{eig}(P_j)/M`, each
      with :math:`M - 1` degrees of freedom (hence
      :math:`E c_j = \frac{M-1}{M} \operatorname{tr} P_j`); projected:
      :math:`(v^{\mathsf T} P_j v / M)\,\chi^2(M - 1)`;
    - correlation: :math:`c(j, k) = \frac1M \sum_{l<M} z_l^{\mathsf T} y_l` with
      :math:`(z, y)` jointly normal with covariance

      .. math::

          S = \begin{bmatrix} P_j & C \\ C^{\mathsf T} & P_k \end{bmatrix}:

      weights the eigenvalues of :math:`S^{1/2} E S^{1/2} / (2M)`,
      :math:`E = \begin{bmatrix} 0 & I \\ I & 0 \end{bmatrix}`, each with
      :math:`M - 1` degrees of freedom.

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> law = statistic_law(residual_moments(true, filt, 5), "covariance", 2, M=10)
    >>> round(float(law.mean()), 4) == round(0.9 * float(residual_moments(true, filt, 5).cov[2, 0, 0]), 4)
    True
    """
    moments = _check_moments(moments)
    full = as_flag(full, "full")
    if not isinstance(kind, str) or kind not in _KINDS:
        raise ValueError(f"kind must be one of {_KINDS}, got {kind!r}")
    M = _check_M(M)
    N, p = moments.n_steps, moments.n_outputs
    j = _index(j, N, "j")
    if kind == "correlation":
        if k is None:
            raise ValueError("the correlation statistic needs a second section k")
        k = _index(k, N, "k")
    elif k is not None:
        raise ValueError(
            f"k (a second section) is only for the correlation statistic, not {kind!r}"
        )
    # A law is a function of its arguments: remember it with the moments, so
    # that testing many records against one null (a Monte Carlo study) builds
    # it, and finds its quantiles, once.
    key = (kind, j, M, k, full, None if direction is None else np.asarray(direction).tobytes())
    cache = _LAWS.setdefault(moments, {})
    if key not in cache:
        cache[key] = _statistic_law(moments, kind, j, M, k, direction, full, p)
    return cache[key]


def _mean_law(mean, cov):
    """Law of ``||x||^2``, ``x ~ N(mean, cov)``: ``sum e_r chi2(1, (v_r^T mean)^2 / e_r)``.

    With the eigenpairs ``(e_r, v_r)`` of a non-singular ``cov`` the reduction
    of :class:`~course.quadform.QuadraticForm` for ``A = I`` is this one
    eigendecomposition (a power curve builds two such laws per value: a
    fifth of its time went into the general reduction); a singular or
    badly scaled ``cov`` takes the general reduction.
    """
    e, V = np.linalg.eigh(cov)
    if e[0] > _FULL_RANK_RTOL * e[-1] * e.size:
        with np.errstate(over="ignore", under="ignore"):
            noncentrality = (V.T @ mean) ** 2 / e
        if np.isfinite(noncentrality).all():
            return WeightedChiSquare(e, np.ones(e.size), noncentrality)
    return QuadraticForm(np.eye(mean.size), mean, cov)


def _statistic_law(moments, kind, j, M, k, direction, full, p):
    if full:
        if kind == "mean":
            mean, cov = section_moments(moments, j, M)
            return QuadraticForm(mean_matrix(M, p), mean, cov)
        if kind == "covariance":
            mean, cov = section_moments(moments, j, M)
            return QuadraticForm(covariance_matrix(M, p, direction), mean, cov)
        mean, cov = pair_moments(moments, j, k, M)
        return QuadraticForm(correlation_matrix(M, p, direction), mean, cov)
    if kind == "mean":
        return _mean_law(moments.mean[j], moments.cov[j] / M)
    if kind == "covariance":
        P = moments.cov[j]
        if direction is None:
            weights = np.linalg.eigvalsh(P) / M
        else:
            v = _unit(direction, p, "direction")
            weights = np.array([v @ P @ v / M])
        return WeightedChiSquare(weights, np.full(weights.size, M - 1.0))
    S = np.block([[moments.cov[j], moments.C(j, k)], [moments.C(j, k).T, moments.cov[k]]])
    if direction is None:
        E = np.block([[np.zeros((p, p)), np.eye(p)], [np.eye(p), np.zeros((p, p))]])
        shape = QuadraticForm(E / (2 * M), cov=symmetrize(S))
    else:
        u, w = _pair(direction, p)
        T = np.zeros((2, 2 * p))
        T[0, :p], T[1, p:] = u, w
        shape = QuadraticForm(
            np.array([[0.0, 1.0], [1.0, 0.0]]) / (2 * M), cov=symmetrize(T @ S @ T.T)
        )
    return WeightedChiSquare(shape.weights, shape.dof * (M - 1.0))
