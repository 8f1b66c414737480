"""The tests on least-squares residuals: the overall model test, Baarda's w-tests and data snooping.

The works cited here are in the course bibliography,
:doc:`/docs/bibliography`.
"""

from __future__ import annotations

import html
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from scipy import linalg as sla
from scipy import stats

from course.chi2 import residual_norm_law
from course.lsq._fit import (
    _TIE_RTOL,
    _UNTESTABLE_RTOL,
    LeastSquaresFit,
    _check_fit,
    _readonly,
    _require_redundancy,
    _require_residuals_for_sigma,
    _standard_normal,
    fit,
)
from course.results import TestResult, decide, format_number
from course.validation import (
    as_count,
    as_index,
    as_probability,
)

_refit = fit  # data_snooping's argument is named fit, like every test's; it refits by this name


# ---------------------------------------------------------------------------
# overall model test
# ---------------------------------------------------------------------------
def overall_model_test(fit: LeastSquaresFit, alpha: float = 0.05) -> TestResult:
    r"""Overall model test: is the weighted squared norm of ``ê`` too large?

    Parameters
    ----------
    fit : LeastSquaresFit
        Result of :func:`fit`.
    alpha : float
        Level of significance (false-alarm probability), in (0, 1).

    Returns
    -------
    TestResult
        ``statistic`` T, ``dof`` m - n, ``critical_value`` ``chi2.isf(alpha, m - n)``,
        ``pvalue`` ``chi2.sf(T, m - n)``, ``null`` ``chi2(m - n)``; ``details``
        holds the variance factor ``T / (m - n)``.

    Raises
    ------
    ValueError
        If ``m - n = 0``: without redundancy the test is void.

    See Also
    --------
    w_tests : Tests of the single observations.
    data_snooping : Detection, identification and adaptation in a loop.
    course.chi2.residual_norm_law : The chi-square law of a residual norm.

    Notes
    -----
    Eq. (10.2): under H0 (:math:`y \sim N(Ax, Q_{yy})`)

    .. math:: T = \\hat e^T Q_{yy}^{-1} \\hat e \\sim \\chi^2(m - n, 0),

    rejected (right-sided) when :math:`T > \chi^2_\alpha(m - n)`. For diagonal
    :math:`Q_{yy}`, :math:`T = \sum_i (\hat e_i / \sigma_i)^2` (10.3); for
    :math:`m` repeated measurements of one quantity
    :math:`T / (m - 1) = \hat\sigma^2 / \sigma^2` (Section 10.1.4), which is
    why :math:`T / (m - n)` is reported as the (a-posteriori) variance
    factor. :math:`T` is evaluated as :math:`\lVert \tilde e \rVert^2` with
    :math:`\tilde e = L^{-1} \hat e` the whitened residuals, the same number
    without :math:`Q_{yy}^{-1}`.

    A 1-D Qyy filled with standard deviations :math:`s_i` instead of variances
    is a likely slip that no check of Qyy alone can see (both are positive
    numbers). It shows here, and only here: the variance factor is then
    about the typical :math:`s_i` instead of 1. A :class:`UserWarning` says so
    when Qyy was given as a 1-D array :math:`v`, T falls outside the central
    range :math:`[\chi^2_{1-\alpha}(m - n),\ \chi^2_\alpha(m - n)]`, the same data with the
    values read as standard deviations (:math:`Q_{yy} = \operatorname{diag}(v^2)`, squared norm
    :math:`T_2`) give a plausible :math:`\chi^2(m - n)` value (inside its central
    99.8 %), and the data favour that reading by a
    likelihood ratio :math:`\Lambda` of at least 1000. :math:`\Lambda` is the ratio of the
    restricted likelihoods (the density of the residual contrasts, free of
    x, as in REML) of the two fully specified covariances,

    .. math:: \\log\\Lambda = \\tfrac12\\Big(T - T_2 - \\sum_i \\log v_i
              + \\log\\frac{\\det A^T \\operatorname{diag}(v)^{-1} A}
                         {\\det A^T \\operatorname{diag}(v^2)^{-1} A}\\Big),

    so it weighs both the overall scale and the residuals' pattern. Under
    H0 :math:`E\Lambda = 1` (a density ratio), hence (Markov's inequality) :math:`\Lambda`
    reaches 1000 in at most 0.1 % of correct fits, whatever :math:`v` and A;
    values near 1, where the two readings barely differ, stay silent. With equal values the slip
    looks exactly like a wrong variance factor, so the warning names both.

    Examples
    --------
    The chapter's second day of line fitting: the line is rejected.

    >>> import numpy as np
    >>> A = np.column_stack([np.ones(4), np.arange(1, 5)])
    >>> result = overall_model_test(fit(A, [28, 20, 16, 36]), alpha=0.01)
    >>> round(result.statistic, 6), round(result.critical_value, 4), result.reject
    (216.0, 9.2103, True)
    """
    fit = _check_fit(fit)
    alpha = as_probability(alpha)
    _require_redundancy(fit, "overall model test")
    dof = fit.redundancy
    T = fit.squared_norm
    null = residual_norm_law(dof)
    result = TestResult.from_null(
        "overall model test",
        T,
        null,
        alpha,
        dof=dof,
        details={"variance factor T/(m-n)": T / dof},
    )
    hint = _standard_deviation_hint(fit, result)
    if hint:
        warnings.warn(hint, UserWarning, stacklevel=2)
    return result


# The likelihood ratio "standard deviations" : "variances" from which the slip is named.
_LOG_EVIDENCE_FOR_STANDARD_DEVIATIONS = float(np.log(1000.0))
_PLAUSIBLE_TAIL = 0.001  # each tail of chi2(m - n) outside which T with squared values is odd


def _standard_deviation_hint(fit: LeastSquaresFit, result: TestResult) -> str:
    """A message when a 1-D Qyy of variances looks like standard deviations, else ``""``."""
    cov = fit._covariance
    # T inside the central range [chi2_{1-alpha}, chi2_alpha]: nothing to explain. Read off
    # the decision (p = sf(T)), so that the usual case costs no quantile computations.
    if cov.given_as != "variances" or not (result.reject or 1.0 - result.pvalue < result.alpha):
        return ""
    T, alpha, null = result.statistic, result.alpha, result.null
    low, high = float(null.ppf(alpha)), float(null.isf(alpha))
    sigma = cov.diagonal()  # the given variances, read as standard deviations
    # The refit costs one more O(m n²) QR, paid only when the test is already surprising.
    A_w = np.asfortranarray(fit.A / sigma[:, None])
    y_w = fit.y / sigma
    Q1, R_alt = sla.qr(A_w, mode="economic", overwrite_a=True, check_finite=False)
    e_w = y_w - Q1 @ (Q1.T @ y_w)
    T_alt = float(e_w @ e_w)
    # Squaring must explain the scale: T_alt a plausible chi2(m - n) value (within its
    # central 99.8 %, not the test's range, which would miss one slip in 10 at alpha = 0.05).
    if not null.ppf(_PLAUSIBLE_TAIL) <= T_alt <= null.isf(_PLAUSIBLE_TAIL):
        return ""
    # Restricted log-likelihood of the residual contrasts under Qyy = diag(sigma²) minus that
    # under Qyy = diag(sigma): its exponential has mean 1 under H0, so by Markov's inequality
    # a ratio of 1000 or more happens in at most 0.1 % of correct fits. Both the scale and
    # the pattern of the residuals count; values near 1 (readings alike) never reach it.
    log_det_ratio = 2.0 * float(
        np.sum(np.log(np.abs(np.diag(fit._R)))) - np.sum(np.log(np.abs(np.diag(R_alt))))
    )
    log_ratio = 0.5 * (T - T_alt - float(np.sum(np.log(sigma))) + log_det_ratio)
    if log_ratio < _LOG_EVIDENCE_FOR_STANDARD_DEVIATIONS:
        return ""
    dof = fit.redundancy
    return (
        f"Qyy was given as a 1-D array of variances and the overall model test finds "
        f"T = {T:.4g}, a variance factor T/(m-n) = {T / dof:.3g}, outside the central range "
        f"[{low:.4g}, {high:.4g}] of chi2({dof}) at alpha = {alpha:g}. Read as standard "
        f"deviations (variances Qyy**2), the same data give T = {T_alt:.4g}, a plausible "
        f"value of chi2({dof}), and are about 10^{log_ratio / np.log(10.0):.0f} times more "
        "likely (ratio of the restricted likelihoods of the two readings). Qyy must hold "
        "VARIANCES: if you passed standard deviations sigma, pass "
        "sigma**2 (if Qyy does hold variances, the model or the stated precision is wrong)."
    )


# ---------------------------------------------------------------------------
# w-tests
# ---------------------------------------------------------------------------
@dataclass(frozen=True, repr=False, eq=False)
class WTestResult:
    """Baarda's w-test applied to every observation of a fit.

    Unpacks like scipy's results and :class:`~course.results.TestResult`:
    ``w, pvalue = w_tests(fit)``.

    Attributes
    ----------
    statistic : ndarray, shape (m,)
        Baarda's ``w_i``, one per observation (NaN where an observation cannot
        be tested); the textbook writes ``w``. With an estimated variance, the
        Student statistics ``t_i``.
    critical_value : float
        ``null.isf(alpha / 2)``: reject observation i when ``|w_i|`` exceeds it
        (``norm.isf(alpha / 2)``, or ``t(m - n - 1).isf(alpha / 2)`` with an
        estimated variance).
    reject : ndarray of bool, shape (m,)
        Decision per observation.
    pvalue : ndarray, shape (m,)
        Two-sided p-values ``2 null.sf(|w_i|)`` (NaN where untestable).
    largest : int
        Index (0-based) of the largest ``|w_i|``: the most suspicious observation.
    testable : ndarray of bool, shape (m,)
        False for observations with no redundancy (generalised redundancy
        number below 1e-10): an outlier there leaves no trace in ê.
    alpha : float
        Level of significance of each single test.
    null : scipy.stats frozen distribution
        ``norm()``, the law of each ``w_i`` under H0; ``t(m - n - 1)`` for the
        tests with an estimated variance.
    variance : {"known", "estimated"}
        Whether ``Qyy`` was taken as known (Baarda's w) or its factor σ² was
        estimated (the Student statistic ``t_i``).
    dof : int or None
        Degrees of freedom of the t law (``m - n - 1``); None for known variance.
    """

    statistic: np.ndarray
    critical_value: float
    reject: np.ndarray
    pvalue: np.ndarray
    largest: int
    testable: np.ndarray
    alpha: float
    null: Any
    variance: str = "known"
    dof: int | None = None

    def __iter__(self) -> Iterator[np.ndarray]:
        """``statistic, pvalue = result``, as scipy's test results unpack."""
        return iter((self.statistic, self.pvalue))

    @property
    def any_reject(self) -> bool:
        """True when at least one observation is rejected."""
        return bool(np.any(self.reject))

    @property
    def rejected(self) -> list[int]:
        """Indices (0-based) of the rejected observations."""
        return [int(i) for i in np.flatnonzero(self.reject)]

    def test(self, i: int) -> TestResult:
        """The w-test of observation ``i`` as a :class:`~course.results.TestResult`."""
        i = as_index(i, "i", self.statistic.shape[0], negative=True, what="observation index")
        if not self.testable[i]:
            raise ValueError(
                f"observation {i} cannot be tested: it has no redundancy (its residual is "
                "always zero), so an outlier in it is invisible"
            )
        return TestResult.from_null(
            f"w-test, observation {i}", float(self.statistic[i]), self.null, self.alpha, "two-sided"
        )

    def tests(self) -> list[TestResult]:
        """One :class:`~course.results.TestResult` per testable observation."""
        return [self.test(int(i)) for i in np.flatnonzero(self.testable)]

    def summary(self) -> str:
        """One line: largest ``|w|``, threshold and the rejected observations."""
        i = self.largest
        return (
            f"w-tests (alpha = {format_number(self.alpha)}): critical |w| = "
            f"{format_number(self.critical_value, 5)}, largest |w| = "
            f"{format_number(abs(float(self.statistic[i])), 5)} at observation {i}, "
            f"rejected: {self.rejected if self.rejected else 'none'}"
        )

    def __repr__(self) -> str:
        i = self.largest
        variance = "" if self.variance == "known" else f", variance='estimated', dof={self.dof}"
        return (
            f"WTestResult(m={self.statistic.shape[0]}{variance}, alpha={format_number(self.alpha)}, "
            f"critical_value={format_number(self.critical_value, 5)}, largest={i}, "
            f"w_largest={format_number(float(self.statistic[i]), 5)}, rejected={self.rejected})"
        )

    def _repr_html_(self) -> str:
        rows = []
        for i, (w, p, r, ok) in enumerate(
            zip(self.statistic, self.pvalue, self.reject, self.testable)
        ):
            style = " style='font-weight:bold'" if r else ""
            w_text = format_number(float(w), 4) if ok else "untestable"
            p_text = format_number(float(p), 3) if ok else ""
            rows.append(
                f"<tr{style}><td>{i}</td><td>{html.escape(w_text)}</td>"
                f"<td>{p_text}</td><td>{bool(r)}</td></tr>"
            )
        caption = (
            f"w-tests, alpha = {format_number(self.alpha)}, critical |w| = "
            f"{format_number(self.critical_value, 5)}"
        )
        return (
            f"<table><caption>{caption}</caption>"
            "<tr><th>i</th><th>w</th><th>p-value</th><th>reject</th></tr>"
            + "".join(rows)
            + "</table>"
        )


def _w_quantities(fit: LeastSquaresFit):
    """Numerators, squared denominators and testability of Baarda's w_i."""
    numerator, denom2, weight = fit._w_parts
    return numerator, denom2, denom2 > _UNTESTABLE_RTOL * weight


def _w_test_result(
    numerator, denom2, weight, alpha: float, squared_norm: float | None = None, dof: int = 0
) -> WTestResult:
    """Baarda's w_i = numerator_i / sqrt(denom2_i) and their two-sided tests.

    With ``squared_norm`` (the residuals' ê^T Qyy^{-1} ê) and ``dof`` (m - n - 1) the
    variance factor is estimated: each w_i becomes Student's t_i (see :func:`w_tests`).
    """
    testable = denom2 > _UNTESTABLE_RTOL * weight
    m = numerator.shape[0]
    w = np.full(m, np.nan)
    w[testable] = numerator[testable] / np.sqrt(denom2[testable])
    null = _standard_normal()
    if squared_norm is not None:
        # sigma² estimated under the alternative of test i: (Ω - w_i²)/(m - n - 1); w_i² <= Ω
        # always (the alternative's residuals are a projection), so only round-off makes it < 0.
        rest = np.maximum(squared_norm - w[testable] ** 2, 0.0)
        with np.errstate(divide="ignore"):
            w[testable] = w[testable] / np.sqrt(rest / dof)
        null = _student(dof)
    decision = decide(null, w[testable], alpha, "two-sided")
    critical = decision.critical_value.upper
    pvalue = np.full(m, np.nan)
    pvalue[testable] = decision.pvalue
    reject = np.zeros(m, dtype=bool)
    reject[testable] = decision.reject
    largest = 0
    if np.any(testable):
        # The first of the largest: |w| equal up to rounding count as a tie (with redundancy
        # 1 all testable |w_i| are equal), so the choice does not depend on round-off.
        abs_w = np.abs(w)
        largest = int(np.flatnonzero(abs_w >= (1 - _TIE_RTOL) * np.nanmax(abs_w))[0])
    return WTestResult(
        statistic=_readonly(w),
        critical_value=critical,
        reject=_readonly(reject),
        pvalue=_readonly(pvalue),
        largest=largest,
        testable=_readonly(testable),
        alpha=alpha,
        null=null,
        variance="known" if squared_norm is None else "estimated",
        dof=None if squared_norm is None else dof,
    )


@lru_cache(maxsize=64)
def _student(dof: int):
    # Freezing a scipy distribution costs ~1 ms; Monte Carlo loops reuse it.
    return stats.t(dof)


def w_tests(fit: LeastSquaresFit, alpha: float = 0.05, variance: str = "known") -> WTestResult:
    r"""Baarda's w-test of every observation for a single outlier.

    Parameters
    ----------
    fit : LeastSquaresFit
        Result of :func:`fit`.
    alpha : float
        Level of significance of each (two-sided) test.
    variance : {"known", "estimated"}
        ``"known"`` (default): ``Qyy`` is the covariance, ``w_i ~ N(0, 1)``.
        ``"estimated"``: ``Qyy`` is known up to a factor σ², estimated from
        the residuals; each test uses Student's ``t_i ~ t(m - n - 1)`` (needs
        ``m - n >= 2``).

    Returns
    -------
    WTestResult
        ``statistic`` (the ``w_i``; the ``t_i`` with an estimated variance),
        ``critical_value`` (``null.isf(alpha/2)``), ``reject``, ``pvalue``,
        ``largest`` (index of max ``|w|``), ``testable``, ``alpha`` and ``null``:
        the normal law ``norm()`` for a known variance, Student's
        ``t(m - n - 1)`` for an estimated one; ``.tests()`` gives one
        :class:`~course.results.TestResult` per observation.

    Raises
    ------
    ValueError
        If ``m - n = 0`` (nothing can be tested), or ``m - n = 1`` with
        ``variance="estimated"``, or ``variance="estimated"`` with data that
        the model fits exactly (residuals at round-off level: σ̂² = 0).

    See Also
    --------
    overall_model_test : The test of the whole model.
    data_snooping : The w-tests repeated after each removal.
    mdb : The smallest outlier each w-test finds with a given power.
    glr_test : The same test for a bias of any dimension (``w_i² = T_1``).

    Notes
    -----
    The alternative hypothesis of test i is :math:`E(y) = Ax + c_i\nabla` with
    :math:`c_i` the i-th unit vector (an outlier :math:`\nabla` in observation i). Baarda's
    statistic

    .. math:: w_i = \\frac{c_i^T Q_{yy}^{-1} \\hat e}
                         {\\sqrt{c_i^T Q_{yy}^{-1} Q_{\\hat e\\hat e} Q_{yy}^{-1} c_i}}
              \\sim N(0, 1) \\text{ under H0}

    reduces for diagonal :math:`Q_{yy}` to the chapter's eq. (10.4),
    :math:`w_i = \hat e_i / \sigma_{\hat e_i}`, and also holds for correlated
    observations. The critical value is two-sided, :math:`N_{\alpha/2}(0, 1)`
    (Section 10.3). With :math:`Q_{yy} = LL^{\mathsf T}`, the thin QR
    :math:`L^{-1}A = Q_1 R` and the whitened residuals :math:`\tilde e`:
    :math:`Q_{yy}^{-1}\hat e = L^{-\mathsf T}\tilde e` and

    .. math::

        c_i^{\mathsf T} Q_{yy}^{-1} Q_{\hat e\hat e} Q_{yy}^{-1} c_i
        = \lVert L^{-1} c_i \rVert^2 - \lVert Q_1^{\mathsf T} L^{-1} c_i \rVert^2,

    where :math:`\lVert L^{-1} c_i \rVert^2 = (Q_{yy}^{-1})_{ii}`; so the numerators and the
    denominators come from one whitening solve with n + 1 right-hand sides
    and the diagonal of :math:`Q_{yy}^{-1}` (O(m n) for diagonal Qyy).
    Reference: W. Baarda (1968), *A testing procedure for use in geodetic
    networks*, Netherlands Geodetic Commission.

    With the variance factor unknown (:math:`Q_{yy} = \sigma^2 G`, G known),
    σ² is estimated under the alternative of test i, where observation i has
    a bias parameter of its own: :math:`\hat\sigma_i^2 = (\Omega - w_i^2)/(m - n - 1)`
    with :math:`\Omega = \hat e^{\mathsf T} G^{-1} \hat e` (the residual norm
    drops by exactly :math:`w_i^2` when the bias is estimated). Then

    .. math:: t_i = \frac{w_i}{\hat\sigma_i} \sim t(m - n - 1) \text{ under H0},

    numerator and denominator being independent. Pope (1976) divides by the
    estimate under H0 instead, :math:`\tau_i = w_i / \sqrt{\Omega/(m - n)}`, whose
    law is his τ distribution. The two are one test:
    :math:`t_i^2 = (m - n - 1)\,\tau_i^2 / (m - n - \tau_i^2)` is increasing in
    :math:`|\tau_i|`, so both reject the same observations at the same level and
    give the same p-values (checked in the course's tests).

    Examples
    --------
    A line observed with sigma = 0.1 and an outlier of 0.6 at observation 6:

    >>> import numpy as np
    >>> A = np.column_stack([np.ones(10), np.arange(10.0)])
    >>> y = [2.03, 2.58, 3.03, 3.37, 4.09, 4.54, 5.55, 5.56, 6.04, 6.53]
    >>> wt = w_tests(fit(A, y, 0.01 * np.eye(10)), alpha=0.01)
    >>> wt.largest, wt.rejected, round(float(wt.statistic[6]), 2)
    (6, [6], 4.83)
    """
    fit = _check_fit(fit)
    alpha = as_probability(alpha)
    if not isinstance(variance, str) or variance not in ("known", "estimated"):
        raise ValueError(
            f"variance must be 'known' (w ~ N(0, 1)) or 'estimated' (sigma² estimated from "
            f"the residuals, t ~ t(m - n - 1)), got {variance!r}"
        )
    _require_redundancy(fit, "w-test")
    if variance == "known":
        return _w_test_result(*fit._w_parts, alpha)
    if fit.redundancy < 2:
        raise ValueError(
            "w-tests with an estimated variance need m - n >= 2: with m - n = 1 the "
            "alternative of each test explains every residual and leaves nothing to "
            "estimate sigma² from; use variance='known'"
        )
    _require_residuals_for_sigma(fit, "the w-test")
    return _w_test_result(*fit._w_parts, alpha, fit.squared_norm, fit.redundancy - 1)


# ---------------------------------------------------------------------------
# data snooping
# ---------------------------------------------------------------------------
@dataclass(frozen=True, repr=False, eq=False)
class SnoopingResult:
    """Outcome of :func:`data_snooping`.

    Attributes
    ----------
    removed : tuple of int
        Removed observations, in the order of removal, as 0-based indices of
        the ORIGINAL observation vector.
    kept : tuple of int
        Original indices of the observations in the final fit.
    rounds : tuple of WTestResult
        The w-tests of each round (round k tests the observations ``kept``
        before the k-th removal; its indices are positions in that round).
    round_indices : tuple of tuple of int
        For each round, the original index of each observation it tested.
    fit : LeastSquaresFit
        The final fit, on the kept observations.
    stop_reason : str
        Why the procedure stopped: ``"no observation rejected"``,
        ``"no redundancy left"`` or ``"max_removals reached"``.
    alpha : float
        Level of significance of the w-tests.
    """

    removed: tuple
    kept: tuple
    rounds: tuple
    round_indices: tuple
    fit: LeastSquaresFit
    stop_reason: str
    alpha: float

    def __repr__(self) -> str:
        return (
            f"SnoopingResult(removed={list(self.removed)}, rounds={len(self.rounds)}, "
            f"final m={self.fit.m}, n={self.fit.n}, stop_reason={self.stop_reason!r})"
        )

    def summary(self) -> str:
        """One line: what was removed and why the procedure stopped."""
        removed = list(self.removed) if self.removed else "nothing"
        return (
            f"data snooping (alpha = {format_number(self.alpha)}): removed {removed} "
            f"in {len(self.rounds)} round(s); stopped: {self.stop_reason}"
        )

    def _repr_html_(self) -> str:
        rows = []
        for k, (wt, idx) in enumerate(zip(self.rounds, self.round_indices)):
            j = wt.largest
            action = f"remove {idx[j]}" if wt.reject[j] else "stop"
            rows.append(
                f"<tr><td>{k + 1}</td><td>{len(idx)}</td><td>{idx[j]}</td>"
                f"<td>{format_number(float(wt.statistic[j]), 4)}</td>"
                f"<td>{format_number(wt.critical_value, 4)}</td><td>{action}</td></tr>"
            )
        caption = html.escape(self.summary())
        return (
            f"<table><caption>{caption}</caption><tr><th>round</th><th>m</th>"
            "<th>largest |w| at (original index)</th><th>w</th><th>critical</th><th>action</th></tr>"
            + "".join(rows)
            + "</table>"
        )


def data_snooping(
    fit: LeastSquaresFit, alpha: float = 0.01, max_removals: int | None = None
) -> SnoopingResult:
    r"""Iterated w-tests: remove the worst rejected observation and refit.

    Parameters
    ----------
    fit : LeastSquaresFit
        The fit of the full model, from :func:`fit` (its A, y and Qyy are the
        model; like every other test, data snooping starts from a fit).
    alpha : float
        Level of significance of every w-test.
    max_removals : int, optional
        Stop after this many removals (default: no limit).

    Returns
    -------
    SnoopingResult
        Removed indices (original numbering), the w-tests of every round, the
        final fit and the reason for stopping.

    See Also
    --------
    w_tests : One round of tests.
    overall_model_test : The detection step.

    Notes
    -----
    Section 10.3: the observation with the largest :math:`|w_i|` is the most
    likely faulty one; if its test rejects, it is removed (its row of A, its
    entry of y and its row and column of Qyy) and the estimation and
    validation are repeated, until no w-test rejects or the redundancy
    :math:`m - n` is used up. Observations without redundancy are never tested,
    and removing a testable one keeps A of full column rank. With
    redundancy 1 all testable :math:`|w_i|` are equal, so a rejection there
    cannot tell which observation is wrong: the removal is then arbitrary
    (the first largest), which is why practitioners want redundancy to spare.

    Each removal is a rank-one downdate, not a fresh fit: removing
    observation i gives the same estimate, T and w-tests of the others as
    keeping it with an outlier parameter of its own, :math:`E(y) = Ax + c_i\nabla_i`
    (the alternative hypothesis of its w-test). In the whitened problem that
    adds the column :math:`L^{-1} c_i` to the design, i.e. one orthonormal
    vector :math:`q` to :math:`Q_1`; the whitened residuals lose their component
    along :math:`q` (T drops by exactly :math:`w_i^2`), and the numerators and squared
    denominators of the remaining :math:`w_j` change by :math:`L^{-\mathsf T} q` terms. Qyy
    is factored once; a round costs O(m (n + k)) for diagonal Qyy and O(m²)
    for a dense one, against O(m n²) and O(m³) for a fresh fit. The final
    ``fit`` is computed once, on the kept observations. (Only the cut-off
    for untestable observations, a generalised redundancy below 1e-10, is
    measured in the full model's weights :math:`(Q_{yy}^{-1})_{jj}`.)

    Examples
    --------
    >>> import numpy as np
    >>> A = np.column_stack([np.ones(10), np.arange(10.0)])
    >>> y = [2.03, 2.58, 3.03, 3.37, 4.09, 4.54, 5.55, 5.56, 6.04, 6.53]
    >>> result = data_snooping(fit(A, y, 0.01 * np.eye(10)), alpha=0.01)
    >>> result.removed, result.stop_reason
    ((6,), 'no observation rejected')
    """
    alpha = as_probability(alpha)
    if max_removals is not None:
        max_removals = as_count(max_removals, "max_removals", minimum=0)
    first = _check_fit(fit)
    model = _OutlierModel(first)
    kept = np.arange(first.m)
    removed: list[int] = []
    rounds: list[WTestResult] = []
    round_indices: list[tuple] = []
    while True:
        if first.redundancy - len(removed) == 0:
            reason = "no redundancy left"
            break
        # Round 1 tests the fit itself; later rounds read the downdated model.
        wt = model.w_tests(kept, alpha) if removed else w_tests(first, alpha)
        rounds.append(wt)
        round_indices.append(tuple(kept.tolist()))
        if not wt.any_reject:
            reason = "no observation rejected"
            break
        if max_removals is not None and len(removed) >= max_removals:
            reason = "max_removals reached"
            break
        worst = int(kept[wt.largest])
        kept = np.delete(kept, wt.largest)
        removed.append(worst)
        model.remove(worst)
    current = first
    if removed:
        current = _refit(first.A[kept], first.y[kept], first._covariance.take(kept))
    return SnoopingResult(
        removed=tuple(removed),
        kept=tuple(kept.tolist()),
        rounds=tuple(rounds),
        round_indices=tuple(round_indices),
        fit=current,
        stop_reason=reason,
        alpha=alpha,
    )


class _OutlierModel:
    """A fit whose removed observations each carry an outlier parameter of their own.

    Holds the whitened residuals and the w-test numerators and squared
    denominators of every observation, and downdates them by one rank per
    removal (see :func:`data_snooping`).
    """

    def __init__(self, first: LeastSquaresFit):
        self._covariance = first._covariance
        # Orthonormal columns spanning the whitened design and the outlier columns added so
        # far, in a column-major buffer that grows by doubling (columns contiguous for BLAS).
        self._n = first.n
        self._basis = np.empty((first.m, 2 * first.n + 8), order="F")
        self._basis[:, : first.n] = first._Q1
        numerator, denom2, weight = first._w_parts
        self._e_w = first._e_w.copy()
        self._numerator = numerator.copy()
        self._denom2 = denom2.copy()
        self._weight = weight

    def remove(self, i: int) -> None:
        v = self._covariance.whiten_unit(i)  # the outlier column L^{-1} c_i
        basis = self._basis[:, : self._n]
        for _ in range(2):  # classical Gram-Schmidt, twice: orthogonal to working precision
            v -= basis @ (basis.T @ v)
        q = v / np.linalg.norm(v)
        coefficient = float(q @ self._e_w)  # = w_i of the round that removed i
        self._e_w -= coefficient * q
        Lt_q = self._covariance.whiten_transpose(q)
        self._numerator -= coefficient * Lt_q
        self._denom2 -= Lt_q * Lt_q
        if self._n == self._basis.shape[1]:
            grown = np.empty((self._basis.shape[0], 2 * self._n), order="F")
            grown[:, : self._n] = self._basis
            self._basis = grown
        self._basis[:, self._n] = q
        self._n += 1

    def w_tests(self, index: np.ndarray, alpha: float) -> WTestResult:
        return _w_test_result(
            self._numerator[index], self._denom2[index], self._weight[index], alpha
        )
