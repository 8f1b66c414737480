r"""Quadratic forms in normal variables and their exact distribution (Imhof's method).

A quadratic form :math:`Q = x^T A x` in a normal vector :math:`x \sim N(\mu, \Sigma)`
is, after an eigen-decomposition, a weighted sum of independent (noncentral)
chi-square variables,

.. math::

    Q = \sum_r \lambda_r \chi^2(h_r, \delta_r^2) \;[+\; \sigma Z + q_0],

where the :math:`\lambda_r` are the eigenvalues of :math:`\Sigma^{1/2} A \Sigma^{1/2}`
(either sign), :math:`h_r` their multiplicities and :math:`\delta_r^2` the squared
means along the eigenvectors (Imhof 1961, section 2; Baram 1980, (3.16)-(3.17)).
The normal term :math:`\sigma Z` and the constant :math:`q_0` appear only when
:math:`\Sigma` is singular and the mean has a component outside its range that
:math:`A` couples to the random part.  Full references to Imhof (1961), Davies (1980), Liu, Tang
and Zhang (2009) and Baram (1980) are in the course bibliography, :doc:`/docs/bibliography`.

Public API
----------
imhof_cdf, imhof_sf
    :math:`P(Q \le c)` and :math:`P(Q > c)` of a weighted sum of noncentral chi-square
    variables, vectorised over ``c``, with a controlled error.
imhof_cdf_batch, imhof_sf_batch
    The same for many laws (one row of weights each) and points in one vectorised call.
liu_tang_zhang_cdf, liu_tang_zhang_sf
    The fast four-cumulant approximation of Liu, Tang and Zhang (2009).
inversion_integrands
    Imhof's real-axis integrand and the contour integrand, for figures.
WeightedChiSquare
    Frozen distribution of :math:`\sum_r w_r \chi^2(h_r, \delta_r^2) + \sigma Z + q_0`.
QuadraticForm
    Frozen distribution of :math:`x^T A x` with :math:`x \sim N(\mu, \Sigma)`
    (singular :math:`\Sigma` allowed), built on :class:`WeightedChiSquare`.

Numerics
--------
Imhof's formula inverts the characteristic function along the imaginary
axis of the Laplace variable :math:`s`; there its integrand decays only like
:math:`|s|^{-1-k}` with :math:`k = \frac12 \sum_r h_r`, so a single chi-square with one degree
of freedom needs an astronomically long integration range for 1e-8
accuracy.  The same integral is evaluated here along a *deformed* contour:
a hyperbola through the saddle point of the integrand that opens into the
half-plane where :math:`e^{-sc}` decays.  Cauchy's theorem makes the two
integrals equal; on the hyperbola the integrand decays exponentially (often
double-exponentially) in the path parameter and is analytic in a strip, so
the trapezoidal rule converges geometrically.

Accuracy on demand.  The law is first scaled to :math:`\max(|w_r|, \sigma) = 1`
(the laws are scale-invariant), so weights, ``sigma`` or covariances of
1e-300 or 1e300 integrate like unit ones, and the integrand is computed as
:math:`e^{E - E_0}` with :math:`E_0` its exponent at the vertex, so tails down to
1e-300 keep their relative accuracy (below the smallest double the answer is
0).  The error is controlled by (i) a rigorous truncation bound in the style
of Imhof's :math:`T_U` and (ii) the trapezoidal rule at two steps from one
evaluation, the coarse step chosen from ``rtol`` (:math:`3.5 / \log(1/\text{rtol})`), the
step halved while the two levels differ by more than the tolerance.  (The
square of that difference, the asymptotic error model, would halve the
nodes but erred by up to 1e3 rtol on random laws: the convergence is often
not yet in its asymptotic regime.)  A loose ``rtol`` therefore costs fewer
nodes.  There is one path: every call, of one point or many, sets up all
its points together in numpy (saddle points, paths, truncation, steps) and
sums them without a Python loop over the points, so one point costs a fixed
few hundred microseconds and each further point of the same call a few.
Far below the weights of a positive form the first term of the expansion at
0 is exact to double precision and is used instead (``imhof_cdf(1e-300,
[5.0])``).

Any degrees of freedom.  :math:`\log(1 - 2 w s)` summed :math:`h` times loses about
:math:`\varepsilon h` of the exponent, which at dof 1e8 is an error of 1e-8.  Beyond 1e4
degrees of freedom (or noncentrality) in a term, points near the mean take
the exponent centred at the mean, :math:`K(s) - s \operatorname{E} Q`, from
:math:`\log(1 + u) - u` with :math:`u = -2 w s` summed without cancellation, and
:math:`x - \operatorname{E} Q` from exact
products; far from the mean (where centring would cancel instead) they keep
the plain form.  Beyond 1e200 degrees of freedom the law is normal to double
precision (skewness below 1e-100) and the normal limit is used, on cumulants
scaled by a power of two so that no sum overflows.

Quantiles (``ppf``, ``isf``, critical values) are found for every level, and
both tails, by Newton's method on contours set up once at the Liu-Tang-Zhang
guesses: moving the point along a fixed contour multiplies the integrand by
:math:`e^{-s \delta}`, so the tail probability and its derivative at any
nearby point come from the same nodes, and each root is checked as a fresh
integral would be (``_search``); the levels it does not settle take a
bracketing search.  A two-sided critical region is one integral set-up, and
its rejection probability under another law one evaluation of both tails.
Many laws at their points are one vectorised integral too
(:func:`imhof_cdf_batch`).

Modules: ``_terms`` (validation of the terms, shared constants), ``_contour``
(the vectorised integral), ``_batch`` (the same for many laws at once),
``_search`` (quantiles by Newton's method on a fixed contour), ``_imhof`` (the
public integrals), ``_ltz`` (the Liu-Tang-Zhang approximation), ``_laws`` (the
frozen laws).
"""

from ._imhof import imhof_cdf, imhof_cdf_batch, imhof_sf, imhof_sf_batch, inversion_integrands
from ._laws import QuadraticForm, WeightedChiSquare
from ._ltz import liu_tang_zhang_cdf, liu_tang_zhang_sf
from ._terms import ATOL as ATOL
from ._terms import RTOL as RTOL

__all__ = [
    "QuadraticForm",
    "WeightedChiSquare",
    "imhof_cdf",
    "imhof_cdf_batch",
    "imhof_sf",
    "imhof_sf_batch",
    "inversion_integrands",
    "liu_tang_zhang_cdf",
    "liu_tang_zhang_sf",
]
