"""Recursive least squares as the Kalman filter of a random-walk parameter.

Source: the LiU lecture on test quantities, slide "Linjär regression -
rekursiv lösare" (full reference in the course bibliography,
:doc:`/docs/bibliography`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.linalg import LinAlgError

from course import _unchecked
from course._unchecked import _symmetrize as symmetrize
from course.filters._steps import _kf_update as kf_update
from course.linalg import matrix_rank, qr_solve
from course.validation import as_covariance, as_float_array, as_matrix, as_variance, as_vector


@dataclass(frozen=True, repr=False, eq=False)
class RLSResult:
    """Output of :func:`recursive_least_squares`.

    Attributes
    ----------
    theta : (*batch, N, k)
        ``thetahat(t|t)``, the estimate from samples ``0..t``; NaN before
        ``first``.
    P : (N, k, k)
        Its covariance (shared by the batch); NaN before ``first``.
    eps : (*batch, N)
        Innovations ``y_t - phi_t^T thetahat(t-1|t-1)``; NaN up to and
        including ``first`` with the diffuse start (no prediction exists).
    S : (N,)
        Innovation variances (NaN where ``eps`` is); ``inf`` where the true
        variance exceeds double precision (``phi_t^T P phi_t ~ 1e308``), where
        :meth:`nis` and :meth:`normalized_innovations` are still right (they
        are computed from ``eps`` and ``S`` scaled by a power of two).
    first : int
        First sample with an estimate: 0 with a prior, ``k0 - 1`` with the
        diffuse start, where ``k0`` is the number of rows that first give
        ``Phi`` full column rank.
    """

    theta: np.ndarray
    P: np.ndarray
    eps: np.ndarray
    S: np.ndarray
    first: int
    # where S overflowed: S_t = _S_scaled[t] * 4**_S_exponent[t] (else exponent 0,
    # _S_scaled = S); None when no step overflowed
    _S_scaled: np.ndarray | None = field(default=None, repr=False)
    _S_exponent: np.ndarray | None = field(default=None, repr=False)

    def __repr__(self) -> str:
        return (
            f"RLSResult(n_steps={self.theta.shape[-2]}, n_params={self.theta.shape[-1]}, "
            f"first={self.first})"
        )

    @property
    def batch_shape(self) -> tuple:
        """Shape of the batch of records (``()`` for one record)."""
        return self.eps.shape[:-1]

    @property
    def n_outputs(self) -> int:
        """Number of outputs per sample: 1 (RLS has one output)."""
        return 1

    @property
    def innovations(self) -> np.ndarray:
        """Alias of ``eps`` (as in :class:`FilterResult`)."""
        return self.eps

    def normalized_innovations(self) -> np.ndarray:
        """``eps_t / sqrt(S_t)``, ``(*batch, N)``: independent N(0, 1) under the model.

        NaN where ``eps`` is (the diffuse start).  The scalar-output case of
        :meth:`FilterResult.normalized_innovations` (without its trailing
        output axis: RLS has one output).
        """
        eps, S = self._scaled()
        return _unchecked._normalized(eps[..., None], S[:, None, None])[..., 0]

    def nis(self) -> np.ndarray:
        """Normalised innovations squared ``eps_t^2 / S_t``, ``(*batch, N)``.

        Independent ``chi2(1)`` over time under the model, so
        :func:`windowed_nis` of an ``RLSResult`` is ``chi2(L)`` with a full
        window (threshold :func:`windowed_nis_threshold` with ``n_outputs=1``).
        """
        eps, S = self._scaled()
        return _unchecked._nis(eps[..., None], S[:, None, None])

    def _scaled(self) -> tuple[np.ndarray, np.ndarray]:
        """``eps_t / 2**k_t`` and ``S_t / 4**k_t``: representable where ``S_t`` is not."""
        if self._S_exponent is None or self._S_scaled is None:
            return self.eps, self.S
        return np.ldexp(self.eps, -self._S_exponent), self._S_scaled


def _first_full_rank(Phi: np.ndarray) -> int:
    """Smallest k0 with rank(Phi[:k0]) = k (rank only grows with rows: bisect)."""
    N, k = Phi.shape
    if k > N or matrix_rank(Phi) < k:
        raise LinAlgError(
            "Phi never reaches full column rank: the data do not excite every parameter, "
            "so least squares has no unique solution; give a proper prior P0 (and theta0) "
            "or more exciting regressors"
        )
    lo, hi = k, N
    while lo < hi:
        mid = (lo + hi) // 2
        if matrix_rank(Phi[:mid]) == k:
            hi = mid
        else:
            lo = mid + 1
    return lo


def recursive_least_squares(
    Phi: Any,
    y: Any,
    *,
    r: float = 1.0,
    q: Any = None,
    theta0: Any = None,
    P0: Any = None,
) -> RLSResult:
    r"""Recursive least squares: a Kalman filter for a random-walk parameter.

    Model: ``theta_{t+1} = theta_t + w_t``, ``w_t ~ N(0, q)``;
    ``y_t = phi_t^T theta_t + e_t``, ``e_t ~ N(0, r)``.

    Parameters
    ----------
    Phi : (N, k) array_like
        Regressors, one row ``phi_t^T`` per sample.
    y : array_like
        ``(N,)`` or ``(*batch, N)`` outputs (records leading; a batch shares
        ``Phi``).  A known part of the prediction, e.g. the fixed
        parameters' contribution under H0, is subtracted beforehand:
        ``y - offset``.
    r : float
        Measurement-noise variance (> 0).  ``r``, ``q``, ``theta0`` and
        ``P0`` are keyword-only.
    q : float or (k, k) array_like, optional
        Process-noise covariance of the parameter (``q * I`` for a scalar);
        zero by default: a constant parameter.
    theta0, P0 : array_like, optional
        Prior mean and covariance of ``theta_0``.  Without ``P0`` the start
        is *diffuse* (no prior information): the first ``k0`` samples that
        make ``Phi`` full column rank are solved by least squares (QR), and
        the recursion runs from there.  With ``q > 0`` the parameter is
        treated as constant during those first ``k0`` samples.

    Returns
    -------
    RLSResult

    See Also
    --------
    kf_update : The measurement update each step applies.
    course.nis.windowed_nis : A recursive test quantity from the result.

    Notes
    -----
    The lecture's recursive linear regression (LiU lecture, "Linjär regression
    - rekursiv lösare"): describe the parameter as a random walk and apply a
    standard Kalman filter; RLS is the special case :math:`q = 0`.  Each step
    is :func:`kf_update` with :math:`H = \varphi_t^{\mathsf T}`, then
    :math:`P \leftarrow P + q`.  With :math:`q = 0` and the diffuse start,
    :math:`\hat\theta(t|t)` equals the batch least-squares estimate from samples
    :math:`0, \dots, t` and :math:`P(t|t) = r (\Phi_t^{\mathsf T} \Phi_t)^{-1}`,
    exactly in exact arithmetic; with a prior it equals the regularised
    estimate minimising

    .. math::

        \frac{\lVert y - \Phi\theta \rVert^2}{r}
        + (\theta - \theta_0)^{\mathsf T} P_0^{-1} (\theta - \theta_0).

    The covariances do not depend on the data, so a batch shares them.
    Regressors beyond :math:`2^{\pm 256}` are scaled by a power of two
    :math:`c` near :math:`\sqrt{\max|\Phi|}` (exact: :math:`\theta c`,
    :math:`P c^2`) so that :math:`P`, which scales as :math:`1/|\varphi|^2`,
    stays within double precision.  Where an innovation variance
    :math:`S_t = \varphi_t^{\mathsf T} P \varphi_t + r` itself exceeds double
    precision, ``S`` holds ``inf`` there and the result keeps :math:`S_t / 4^k`
    beside it (:math:`k` an integer), so that the NIS
    :math:`(\varepsilon_t / 2^k)^2 / (S_t / 4^k)`, which does not depend on the
    scale, stays right.  The normalised innovations are independent
    :math:`N(0, 1)` while the model holds, which makes
    :func:`course.nis.windowed_nis` of the result a recursive test quantity
    (notebook 2, "recursive computation").

    Examples
    --------
    With a constant parameter (q = 0) and the diffuse start, the last estimate
    is the batch least-squares estimate:

    >>> import numpy as np
    >>> Phi = np.column_stack([np.ones(30), np.linspace(0.0, 1.0, 30)])
    >>> y = Phi @ [1.0, -2.0] + 0.1 * np.random.default_rng(0).standard_normal(30)
    >>> rls = recursive_least_squares(Phi, y, r=0.01)
    >>> bool(np.allclose(rls.theta[-1], np.linalg.lstsq(Phi, y, rcond=None)[0]))
    True
    """
    Phi = as_matrix(Phi, "Phi")
    N, k = Phi.shape
    y = as_float_array(y, "y")
    if y.ndim < 1 or y.shape[-1] != N:
        raise ValueError(
            f"y must have shape (N,) or (batch, N) with N = {N} (the rows of Phi), got {y.shape}"
        )
    r = as_variance(r, "r", positive=True, what="the measurement-noise variance")
    if q is None:
        Qw = np.zeros((k, k))
    elif np.ndim(q) == 0:
        Qw = as_variance(q, "q") * np.eye(k)
    else:
        Qw = as_covariance(q, "q", k, allow_singular=True)
    batch = y.shape[:-1]
    # Regressors far from 1 (|phi| ~ 1e160) put P ~ r / |phi|^2 out of range: run on
    # Phi / c with theta * c and P * c^2 (c a power of two near sqrt|Phi|, so both stay in
    # range; exact), and scale back. eps and S do not change. Ordinary scales: c = 1.
    c = _regressor_scale(Phi)
    Phi = Phi / c
    Qw = Qw * c * c
    R = np.array([[r]])
    theta = np.full(batch + (N, k), np.nan)
    P_all = np.full((N, k, k), np.nan)
    eps = np.full(batch + (N,), np.nan)
    S_all = np.full(N, np.nan)

    if P0 is None:
        if theta0 is not None:
            raise ValueError("theta0 without P0: give its covariance P0 as well (or neither)")
        k0 = _first_full_rank(Phi)
        first = k0 - 1
        # least squares on the first k0 rows, all runs at once (QR, no normal equations)
        rhs = np.moveaxis(y[..., :k0], -1, 0).reshape(k0, -1)
        start_fit = qr_solve(Phi[:k0], rhs)
        x = np.moveaxis(start_fit.x.reshape((k,) + batch), 0, -1)
        Ri = start_fit.R_inv
        P = symmetrize(r * (Ri @ Ri.T))  # r (Phi^T Phi)^{-1}
        theta[..., first, :] = x
        P_all[first] = P
        P = P + Qw
        start = k0
    else:
        x = np.zeros(k) if theta0 is None else as_vector(theta0, "theta0", k)
        P = as_covariance(P0, "P0", k, allow_singular=True) * c * c
        x = np.broadcast_to(x * c, batch + (k,))
        first = start = 0
    S_scaled: np.ndarray | None = None
    S_exponent: np.ndarray | None = None
    for t in range(start, N):
        P_prior = P
        x, P, e, S, _ = kf_update(x, P, y[..., t, None], Phi[t][None, :], R)
        theta[..., t, :], P_all[t], eps[..., t], S_all[t] = x, P, e[..., 0], S[0, 0]
        if not math.isfinite(S_all[t]):
            # theta and P are right (the update scales its output), S is not a double;
            # keep S / 4^k, whose NIS (eps / 2^k)^2 / (S / 4^k) is the true one
            if S_scaled is None or S_exponent is None:
                S_scaled, S_exponent = S_all.copy(), np.zeros(N, dtype=int)
            S_exponent[t], S_scaled[t] = _scaled_variance(Phi[t], P_prior, r)
        elif S_scaled is not None:
            S_scaled[t] = S_all[t]
        P = P + Qw
    if c != 1.0:
        theta, P_all = theta / c, P_all / c / c
    return RLSResult(
        theta=theta,
        P=P_all,
        eps=eps,
        S=S_all,
        first=first,
        _S_scaled=S_scaled,
        _S_exponent=S_exponent,
    )


def _scaled_variance(phi: np.ndarray, P: np.ndarray, r: float) -> tuple[int, float]:
    """``k`` and ``(phi^T P phi + r) / 4**k`` near 1, for an innovation variance beyond doubles.

    ``phi / 2**k`` and ``r / 4**k`` are exact (powers of two), so only the rounding of
    an ordinary-sized sum remains.
    """
    largest_phi = float(np.max(np.abs(phi)))
    largest_p = float(np.max(np.diagonal(P)))
    k = max(
        int(np.frexp(largest_phi)[1]) + int(np.frexp(math.sqrt(largest_p))[1]),
        int(np.frexp(math.sqrt(r))[1]),
    )
    phi_scaled = np.ldexp(phi, -k)
    return k, float(phi_scaled @ P @ phi_scaled) + math.ldexp(r, -2 * k)


def _regressor_scale(Phi: np.ndarray) -> float:
    """A power of two near ``sqrt(max |Phi|)`` when that is beyond ``2**±256``, else 1."""
    largest = float(np.max(np.abs(Phi)))
    exponent = int(np.frexp(largest)[1]) if largest > 0 else 0
    return float(np.ldexp(1.0, exponent // 2)) if abs(exponent) > 256 else 1.0
