"""The moments of mismatched-filter residuals (Baram's appendix, corrected) and their Monte Carlo check.

The works cited here are in the course bibliography,
:doc:`/docs/bibliography`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from course.filters import LinearModel, kalman_filter, riccati_gains
from course.linalg import readonly, symmetrize
from course.validation import (
    InputTypeError,
    as_count,
    as_float_array,
    as_index,
)

_readonly = readonly


#: The misprints of Baram's appendix that :func:`residual_moments_as_printed`
#: can put back: name -> (equation, as printed, as corrected). (A15), printed
#: "[H_j^0 - H_j^1]", is not among them: in the paper's block notation (blocks
#: separated by spaces, as in (A14)) it reads [H^0, -H^1], which is right; nor is
#: (A26), which prints the zero block of the known initial estimate and is wrong
#: only by a tilde, a slip no computation can show.
APPENDIX_MISPRINTS = {
    "gain_of_tested_model": (
        "(A17)-(A18)",
        "K^0 from a Riccati recursion of M^0 (mixing H^0 and H^1)",
        "K^1 from the Riccati recursion of the filter's own model M^1",
    ),
    "Q1_block": (
        "(A14), (A20)",
        "a random w^1 with covariance Q^1 drives the estimate",
        "the estimate is driven by the mean of w^1 only: no Q^1 block",
    ),
    "mean_without_noise_mean": (
        "(A23)",
        "m_j = H~ E[x~_j] (no measurement-noise mean)",
        "m_j = H~ E[x~_j] + m_v^0 - m_v^1",
    ),
    "cross_covariance_without_v": (
        "(A27)",
        "C(k, j) = H~ Theta(k, j) Psi~_j H~^T for j < k",
        "plus H~ Theta(k, j+1) [0; F^1 K_j R^0]: v_j enters xhat through the gain",
    ),
    "C_is_P_k": (
        "(2.4)",
        "C(j, k) = E{(r_k - m_k)(r_k - m_k)^T} (= P_k)",
        "C(j, k) = E{(r_j - m_j)(r_k - m_k)^T}",
    ),
}


# ---------------------------------------------------------------------------
# moments of the residuals
# ---------------------------------------------------------------------------
@dataclass(frozen=True, repr=False, eq=False)
class ResidualMoments:
    """First and second moments of mismatched-filter residuals.

    Attributes
    ----------
    mean : (N, p) ndarray
        ``m_t = E r_t``.
    cov : (N, p, p) ndarray
        ``P_t = E (r_t - m_t)(r_t - m_t)^T``.
    cross_cov : (N, N, p, p) ndarray
        ``cross_cov[j, k] = C(j, k) = E (r_j - m_j)(r_k - m_k)^T``;
        ``cross_cov[j, j] = P_j`` and ``cross_cov[k, j] = C(j, k)^T``.

    Raises
    ------
    ValueError
        Shapes that do not agree, NaN or inf (when built by hand).

    See Also
    --------
    residual_moments : The function that builds it.
    simulate_records : Records to compare the moments with.

    Notes
    -----
    Normally built by :func:`residual_moments` (Baram 1980, appendix,
    corrected); the arrays are read-only copies.
    """

    mean: np.ndarray
    cov: np.ndarray
    cross_cov: np.ndarray

    def __post_init__(self):
        # Built by hand too (e.g. from stored moments): check the shapes agree;
        # as_float_array copies, so the read-only arrays never alias the caller's.
        mean = as_float_array(self.mean, "mean")
        if mean.ndim != 2:
            raise ValueError(f"mean must have shape (N, p), got {mean.shape}")
        N, p = mean.shape
        cov = as_float_array(self.cov, "cov")
        if cov.shape != (N, p, p):
            raise ValueError(
                f"cov must have shape (N, p, p) = {(N, p, p)} to match mean, got {cov.shape}"
            )
        cross = as_float_array(self.cross_cov, "cross_cov")
        if cross.shape != (N, N, p, p):
            raise ValueError(
                f"cross_cov must have shape (N, N, p, p) = {(N, N, p, p)} to match mean, got {cross.shape}"
            )
        for name, value in (("mean", mean), ("cov", cov), ("cross_cov", cross)):
            object.__setattr__(self, name, _readonly(value))

    @property
    def n_steps(self) -> int:
        return self.mean.shape[0]

    @property
    def n_outputs(self) -> int:
        return self.mean.shape[1]

    def C(self, j: int, k: int) -> np.ndarray:
        """``C(j, k) = E (r_j - m_j)(r_k - m_k)^T``."""
        return self.cross_cov[_index(j, self.n_steps, "j"), _index(k, self.n_steps, "k")]

    def stacked_cov(self) -> np.ndarray:
        """Covariance of ``(r_0, ..., r_{N-1})`` stacked, ``(N p, N p)``."""
        N, p = self.mean.shape
        return self.cross_cov.transpose(0, 2, 1, 3).reshape(N * p, N * p)

    def __repr__(self) -> str:
        return f"ResidualMoments(n_steps={self.n_steps}, n_outputs={self.n_outputs})"


def _check_models(true_model, filter_model):
    for name, model in (("true_model", true_model), ("filter_model", filter_model)):
        if not isinstance(model, LinearModel):
            raise InputTypeError(
                f"{name} must be a course.filters.LinearModel, got {type(model).__name__}"
            )
        if model.n_inputs:
            raise ValueError(
                f"{name} has an input (B); the mismatched-filter analysis here has none: "
                "fold a known constant input into w_mean"
            )
    if true_model.n_outputs != filter_model.n_outputs:
        raise ValueError(
            f"true_model and filter_model must have the same number of outputs: the true "
            f"model has {true_model.n_outputs}, the filter's {filter_model.n_outputs}"
        )


def _check_moments(moments: Any, name: str = "moments") -> ResidualMoments:
    if not isinstance(moments, ResidualMoments):
        raise InputTypeError(
            f"{name} must be the ResidualMoments of a pair of models (from residual_moments), "
            f"got {type(moments).__name__}"
        )
    return moments


def _outputs(p: Any) -> int:
    return as_count(p, "p", what="the number of outputs")


def _check_steps(N: Any) -> int:
    return as_count(N, "N", what="the number of samples per record")


def residual_moments(true_model, filter_model, N) -> ResidualMoments:
    r"""Moments of the residuals of ``filter_model``'s Kalman filter on data of ``true_model``.

    Parameters
    ----------
    true_model : course.filters.LinearModel
        ``M^0`` (or ``M^2``), the model that generates the data.
    filter_model : course.filters.LinearModel
        ``M^1``, the model inside the filter (it may have fewer states).
    N : int
        Number of samples per record.

    Returns
    -------
    ResidualMoments
        ``mean (N, p)``, ``cov (N, p, p)``, ``cross_cov (N, N, p, p)``.

    See Also
    --------
    residual_moments_as_printed : The same moments with the paper's misprints.
    simulate_records : Monte Carlo records of the same residual.
    moment_zscores : Standardised differences between the two.
    course.filters.riccati : The filter's own gains.

    Notes
    -----
    The residual :math:`r_t = y_t - H^1 \hat x(t|t-1) - \bar v^1` of the filter
    of :func:`course.filters.kalman_filter` is the output of the augmented
    system (Baram 1980, appendix, (A9)-(A15), corrected), with centred noises
    :math:`\tilde w_t = w_t - \bar w^0`, :math:`\tilde v_t = v_t - \bar v^0`:

    .. math::

        \tilde x_t &= \begin{bmatrix} x_t \\ \hat x(t|t-1) \end{bmatrix}, \qquad
        \tilde x_{t+1} = \tilde F_t \tilde x_t
            + \tilde G_t \begin{bmatrix} \tilde w_t \\ \tilde v_t \end{bmatrix} + \tilde u_t, \\
        \tilde F_t &= \begin{bmatrix} F^0 & 0 \\ F^1 K_t H^0 & F^1 (I - K_t H^1) \end{bmatrix}
            \quad \text{(A13)}, \qquad
        \tilde G_t = \begin{bmatrix} G^0 & 0 \\ 0 & F^1 K_t \end{bmatrix}
            \quad \text{(A14), no } G^1 w^1 \text{ block}, \\
        \tilde u_t &= \begin{bmatrix} G^0 \bar w^0 \\
            F^1 K_t (\bar v^0 - \bar v^1) + G^1 \bar w^1 \end{bmatrix}, \qquad
        r_t = \tilde H \tilde x_t + \tilde v_t + \bar v^0 - \bar v^1, \quad
        \tilde H = [H^0,\ -H^1] \quad \text{(A15)},

    with :math:`K_t` the filter's own gains (Riccati recursion of :math:`M^1`,
    (A17)-(A18) corrected), :math:`E\tilde x_0 = [m^0_0;\ m^1_0]` (A21) and
    :math:`\tilde\Psi_0 = \operatorname{blockdiag}(\Psi^0_0, 0)` (A26).  Then

    - :math:`E\tilde x_{t+1} = \tilde F_t E\tilde x_t + \tilde u_t`;
      :math:`m_t = \tilde H E\tilde x_t + \bar v^0 - \bar v^1` (A23);
    - :math:`\tilde\Psi_{t+1} = \tilde F_t \tilde\Psi_t \tilde F_t^{\mathsf T}
      + \tilde G_t \tilde Q \tilde G_t^{\mathsf T}`,
      :math:`\tilde Q = \operatorname{blockdiag}(Q^0, R^0)` (A20), (A25);
    - :math:`P_t = \tilde H \tilde\Psi_t \tilde H^{\mathsf T} + R^0` (A28);
    - for :math:`j < k`: :math:`C(k, j) = \tilde H Z_{k,j}` with
      :math:`Z_{j+1,j} = \tilde F_j \tilde\Psi_j \tilde H^{\mathsf T}
      + [0;\ F^1 K_j R^0]` and :math:`Z_{t+1,j} = \tilde F_t Z_{t,j}` (A27
      corrected: the transition from :math:`j` to :math:`k`, and :math:`v_j`
      enters the estimate through the gain).

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> moments = residual_moments(true, filt, 5)
    >>> moments.mean.shape, moments.cov.shape, moments.cross_cov.shape
    ((5, 1), (5, 1, 1), (5, 5, 1, 1))
    """
    return _moments(true_model, filter_model, N, misprint=None)


def residual_moments_as_printed(true_model, filter_model, N, misprint) -> ResidualMoments:
    """:func:`residual_moments` with one misprint of Baram's appendix put back.

    For teaching: comparing these moments with Monte Carlo shows that the
    printed formula is wrong and the corrected one right.

    Parameters
    ----------
    misprint : str
        A key of :data:`APPENDIX_MISPRINTS`.

    Returns
    -------
    ResidualMoments
        The moments the printed formula would give.

    Raises
    ------
    ValueError
        Unknown misprint, or ``"gain_of_tested_model"`` with models of
        different state dimensions (the printed gain is then not even
        conformable with ``F^1``).

    See Also
    --------
    residual_moments : The corrected moments.

    Notes
    -----
    :data:`APPENDIX_MISPRINTS` lists each printed formula (Baram 1980,
    appendix and (2.4)) next to its correction.

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> printed = residual_moments_as_printed(true, filt, 5, "Q1_block")
    >>> bool(printed.cov[-1, 0, 0] != residual_moments(true, filt, 5).cov[-1, 0, 0])
    True
    """
    if misprint not in APPENDIX_MISPRINTS:
        raise ValueError(f"misprint must be one of {sorted(APPENDIX_MISPRINTS)}, got {misprint!r}")
    return _moments(true_model, filter_model, N, misprint=misprint)


def _moments(m0, m1, N, misprint):
    _check_models(m0, m1)
    N = _check_steps(N)
    n0, n1, p = m0.n_states, m1.n_states, m0.n_outputs
    if misprint == "gain_of_tested_model":
        if n0 != n1:
            raise ValueError(
                "the printed gain K^0 (from M^0) is n0 x p and cannot multiply F^1 (n1 x n1) "
                f"when the filter has fewer states ({n1} vs {n0}): the printed formula has no meaning here"
            )
        K = riccati_gains(m0, N)
    else:
        K = riccati_gains(m1, N)
    na = n0 + n1
    Ht = np.hstack([m0.H, -m1.H])
    x_mean = np.concatenate([m0.x0_mean, m1.x0_mean])
    Psi = np.zeros((na, na))
    Psi[:n0, :n0] = m0.x0_cov
    dv = m0.v_mean - m1.v_mean
    R0 = m0.R
    mean = np.empty((N, p))
    cov = np.empty((N, p, p))
    cross = np.empty((N, N, p, p))
    F_all = np.empty((N, na, na))
    Z_first = np.empty((N, na, p))  # Cov(x~_{j+1}, r_j)
    for t in range(N):
        mean[t] = Ht @ x_mean + (dv if misprint != "mean_without_noise_mean" else 0.0)
        cov[t] = symmetrize(Ht @ Psi @ Ht.T + R0)
        FK = m1.F @ K[t]
        Ft = np.zeros((na, na))
        Ft[:n0, :n0] = m0.F
        Ft[n0:, :n0] = FK @ m0.H
        Ft[n0:, n0:] = m1.F - FK @ m1.H
        F_all[t] = Ft
        Z = Ft @ Psi @ Ht.T
        if misprint != "cross_covariance_without_v":
            Z[n0:] += FK @ R0
        Z_first[t] = Z
        # noise: [w^0; v^0] through G~ = [[G^0, 0], [0, F^1 K]]
        noise = np.zeros((na, na))
        noise[:n0, :n0] = m0.GQG
        noise[n0:, n0:] = FK @ R0 @ FK.T
        if misprint == "Q1_block":
            noise[n0:, n0:] += m1.GQG
        x_mean = Ft @ x_mean + np.concatenate([m0.G @ m0.w_mean, FK @ dv + m1.G @ m1.w_mean])
        Psi = symmetrize(Ft @ Psi @ Ft.T + noise)
    for j in range(N):
        cross[j, j] = cov[j]
        Z = Z_first[j]
        for k in range(j + 1, N):
            Ckj = Ht @ Z  # C(k, j) = E (r_k - m_k)(r_j - m_j)^T
            cross[k, j] = Ckj
            cross[j, k] = Ckj.T
            Z = F_all[k] @ Z
    if misprint == "C_is_P_k":
        for j in range(N):
            for k in range(N):
                cross[j, k] = cov[k]
    return ResidualMoments(_readonly(mean), _readonly(cov), _readonly(cross))


def simulate_records(true_model, filter_model, M, N, rng) -> np.ndarray:
    """Residuals of ``filter_model``'s Kalman filter on M records of ``true_model``.

    Parameters
    ----------
    true_model, filter_model : course.filters.LinearModel
    M : int
        Number of independent records (experiments).
    N : int
        Samples per record.
    rng : numpy.random.Generator

    Returns
    -------
    ndarray, shape (M, N, p)
        ``residuals[i, t]`` is ``r_{i,t}`` of the paper (record i, time t).

    See Also
    --------
    residual_moments : The predicted moments of these records.
    moment_zscores : How far the records are from the prediction.

    Notes
    -----
    The records are independent runs of ``true_model`` (Baram 1980,
    section 1: independent noise sequences across experiments), filtered
    by :func:`course.filters.kalman_filter` with ``filter_model``; the
    residual is that filter's innovation, (2.1).

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> import numpy as np
    >>> simulate_records(true, filt, 200, 5, np.random.default_rng(0)).shape
    (200, 5, 1)
    """
    _check_models(true_model, filter_model)
    N = _check_steps(N)
    M = as_count(M, "M", what="the number of records")
    _, y = true_model.simulate(N, rng, batch=M)
    return np.array(kalman_filter(filter_model, y).eps)


class MomentZScores(NamedTuple):
    """Result of :func:`moment_zscores` (unpacks as ``z_mean, z_cov``)."""

    z_mean: np.ndarray
    """``(N, p)`` standardised errors of the sample means."""
    z_cov: np.ndarray
    """``(N, N, p, p)`` standardised errors of the sample cross-covariances."""


class EigenDirections(NamedTuple):
    """Principal directions of ``P_j`` (unpacks as ``values, vectors``)."""

    values: np.ndarray
    """Eigenvalues in decreasing order."""
    vectors: np.ndarray
    """Eigenvectors as the *columns*, in the same order."""


class SingularDirections(NamedTuple):
    """Principal directions of ``C(j, k) = U diag(s) W^T`` (unpacks as ``s, U, W``)."""

    values: np.ndarray
    """Singular values in decreasing order."""
    left: np.ndarray
    """``U``: its columns project ``r_j``."""
    right: np.ndarray
    """``W``: its columns project ``r_k``."""


class SectionMoments(NamedTuple):
    """Mean and covariance of a stacked section (unpacks as ``mean, cov``)."""

    mean: np.ndarray
    cov: np.ndarray


def moment_zscores(residuals: Any, moments: ResidualMoments) -> MomentZScores:
    r"""Standardised differences between sample moments and ``moments``.

    Parameters
    ----------
    residuals : (M, N, p) array_like
        Residuals of many independent records.
    moments : ResidualMoments
        Predicted moments.

    Returns
    -------
    MomentZScores
        ``z_mean`` ``(N, p)``: ``(rbar_t - m_t) / sqrt(P_t,aa / M)``;
        ``z_cov`` ``(N, N, p, p)``:
        ``(S(j, k)_ab - C(j, k)_ab) / se`` with the unbiased sample
        cross-covariance ``S`` (divisor ``M - 1``) and the normal-theory
        standard error ``se^2 = (P_j,aa P_k,bb + C(j, k)_ab^2) / M``.

    See Also
    --------
    residual_moments : The predicted moments.
    simulate_records : The records.

    Notes
    -----
    Each entry is a sample moment minus its prediction, divided by its
    standard error, :math:`z = (\hat\mu - \mu)/\widehat{\operatorname{se}}`.
    If the moments are right, every entry is approximately :math:`N(0, 1)`; a
    wrong formula shows up as entries of tens or hundreds.

    Examples
    --------
    >>> from course.filters import LinearModel
    >>> true = LinearModel(F=[[0.9, 1.0], [0.0, 0.95]], H=[[1.0, 0.0]], Q=[[0.5, 0], [0, 0.02]], R=[[1.0]])
    >>> filt = LinearModel(F=[[0.95]], H=[[1.0]], Q=[[1.0]], R=[[1.2]])
    >>> import numpy as np
    >>> r = simulate_records(true, filt, 4000, 5, np.random.default_rng(0))
    >>> z = moment_zscores(r, residual_moments(true, filt, 5))
    >>> bool(np.abs(z.z_mean).max() < 5 and np.abs(z.z_cov).max() < 5)
    True
    """
    moments = _check_moments(moments)
    r = _as_records(residuals)
    M = r.shape[0]
    if r.shape[1:] != moments.mean.shape:
        raise ValueError(
            f"residuals have (N, p) = {r.shape[1:]} but the moments are for {moments.mean.shape}"
        )
    rbar = r.mean(axis=0)
    variances = np.diagonal(moments.cov, axis1=1, axis2=2)
    z_mean = (rbar - moments.mean) / np.sqrt(variances / M)
    dev = r - rbar
    sample = np.einsum("ija,ikb->jkab", dev, dev) / (M - 1)
    se = np.sqrt(
        (variances[:, None, :, None] * variances[None, :, None, :] + moments.cross_cov**2) / M
    )
    return MomentZScores(z_mean, (sample - moments.cross_cov) / se)


def _as_records(residuals) -> np.ndarray:
    r = as_float_array(residuals, "residuals", empty=False)
    if r.ndim == 2:
        r = r[..., None]
    if r.ndim != 3:
        raise ValueError(
            f"residuals must have shape (M, N, p) (records, times, outputs) or (M, N), got {r.shape}"
        )
    if r.shape[0] < 2:
        raise ValueError(
            f"residuals holds {r.shape[0]} record(s): cross-record statistics need at least "
            "two records"
        )
    return r


def _scaled_sections(r: np.ndarray, *sections: int) -> tuple[tuple[np.ndarray, ...], float]:
    """The sections ``r[:, j]`` divided by a power of two ``c`` near their largest value.

    The statistics are quadratic: residuals near 1e154 overflow in sums of products (and
    then give NaN) where the statistic itself does not. Scaling by a power of two is exact,
    so at ordinary scales the statistic is the unscaled one to the last bit.
    """
    largest = max(float(np.max(np.abs(r[:, j]))) for j in sections)
    c = float(np.ldexp(1.0, np.frexp(largest)[1]))
    return tuple(r[:, j] / c for j in sections), c


def _times_square(value: Any, c: float) -> float:
    """``value * c**2``: inf (never NaN) where the statistic exceeds double precision."""
    with np.errstate(over="ignore"):
        return float(value * c * c)


def _index(j: Any, N: int, name: str) -> int:
    return as_index(j, name, N, what="a time index")
