"""Benchmark: exact Wishart extreme-eigenvalue laws against Monte Carlo at equal accuracy.

Task: the null laws of the NIS-matrix test for m = 6, K = 1000, i.e. the
CDFs of lambda_min and lambda_max of W/K (W ~ W_m(K, I)) on a grid of 200
points, and the two critical values at alpha = 0.05.

* ours: ``course.nis.extreme_eigenvalue(...).cdf`` / ``ppf`` / ``isf``
  (Chiani's Pfaffian in a standardised basis; error < 1e-13);
* baseline: Monte Carlo with the fastest sampler we know (Bartlett's
  decomposition, m(m+1)/2 random numbers per draw, batched ``eigvalsh``; one
  set of draws serves both extremes and every grid point), with as many
  draws as the DKW inequality needs for a sup-error of ``eps`` at 95 %
  confidence: N = ln(2/0.05) / (2 eps^2).

"Equal accuracy" is generous to Monte Carlo: the exact values are ~10
orders of magnitude more accurate than eps.  Target: >= 100x.  Exits with
status 1 when the target is missed, or when the exact and Monte Carlo CDFs
differ by more than 2 eps (by the DKW inequality a chance of about 1e-6).

Run: ``python tests/benchmarks/bench_nis.py [--eps 1e-3]``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

from course import nis


def best_time(func, repeat=5):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        value = func()
        times.append(time.perf_counter() - start)
    return min(times), value


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--m", type=int, default=6)
    parser.add_argument("--K", type=int, default=1000)
    parser.add_argument("--eps", type=float, default=1e-3, help="sup-error of the CDF (DKW, 95 %%)")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    m, K, eps, alpha = args.m, args.K, args.eps, 0.05
    n_draws = math.ceil(math.log(2 / 0.05) / (2 * eps**2))

    laws = {w: nis.extreme_eigenvalue(m, K, w) for w in ("min", "max")}
    lo, hi = float(laws["min"].ppf(1e-6)), float(laws["max"].isf(1e-6))
    grid = np.linspace(lo, hi, 200)

    def exact():
        cdf_min, cdf_max = laws["min"].cdf(grid), laws["max"].cdf(grid)
        crit = (float(laws["min"].ppf(alpha / 2)), float(laws["max"].isf(alpha / 2)))
        return cdf_min, cdf_max, crit

    def monte_carlo():
        rng = np.random.default_rng(args.seed)
        lmin, lmax = nis.simulate_extreme_eigenvalues(m, K, n_draws, rng=rng)
        lmin.sort()
        lmax.sort()
        cdf_min = np.searchsorted(lmin, grid, side="right") / n_draws
        cdf_max = np.searchsorted(lmax, grid, side="right") / n_draws
        crit = (float(np.quantile(lmin, alpha / 2)), float(np.quantile(lmax, 1 - alpha / 2)))
        return cdf_min, cdf_max, crit

    t_exact, (e_min, e_max, e_crit) = best_time(exact)
    t_mc, (s_min, s_max, s_crit) = best_time(monte_carlo, repeat=1)
    gap = max(np.max(np.abs(e_min - s_min)), np.max(np.abs(e_max - s_max)))
    ratio = t_mc / t_exact

    print(
        f"task: CDFs of lambda_min and lambda_max of W/K on 200 points + critical values, m={m}, K={K}"
    )
    print(f"accuracy: sup-error {eps:g} at 95% (Monte Carlo needs N = {n_draws} draws by DKW)")
    print(f"exact (course.nis, Chiani Pfaffian):   {t_exact * 1e3:10.1f} ms")
    print(f"Monte Carlo (Bartlett + eigvalsh):     {t_mc * 1e3:10.1f} ms")
    print(
        f"ratio Monte Carlo / exact:             {ratio:10.0f}x  (target >= 100x: "
        f"{'met' if ratio >= 100 else 'NOT met'})"
    )
    print(
        f"check: sup |exact - MC| = {gap:.2e} (<= {eps:g} expected); critical values "
        f"exact ({e_crit[0]:.5f}, {e_crit[1]:.5f}) vs MC ({s_crit[0]:.5f}, {s_crit[1]:.5f})"
    )
    return 0 if ratio >= 100 and gap <= 2 * eps else 1


if __name__ == "__main__":
    sys.exit(main())
