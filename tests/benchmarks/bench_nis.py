"""Benchmark: exact Wishart extreme-eigenvalue laws: speed against Monte Carlo, and accuracy.

Three parts, each with a target; the script exits with status 1 when any is missed.

1. **Speed at equal accuracy** (``m = 6``, ``K = 1000`` by default): the CDFs of
   lambda_min and lambda_max of W/K (W ~ W_m(K, I)) on a grid of 200 points and
   the two critical values at alpha = 0.05,

   * ours: ``course.nis.extreme_eigenvalue(...).cdf`` / ``ppf`` / ``isf``, timed
     **cold**: the laws are built inside the timed call and the module's one
     cache (the quadrature panel) is cleared first, so nothing computed by an
     earlier repeat is reused;
   * baseline: Monte Carlo with the fastest sampler we know (Bartlett's
     decomposition, m(m+1)/2 random numbers per draw, batched ``eigvalsh``; one
     set of draws serves both extremes and every grid point), with as many draws
     as the DKW inequality needs for a sup-error of ``eps`` at 95 % confidence:
     N = ln(2/0.05) / (2 eps^2).

   Both are timed in CPU time (``time.process_time``), not wall clock: the
   machine is shared and wall time measures the neighbours.  Target: >= 100x;
   and the exact and Monte Carlo CDFs must differ by at most 2 eps (by DKW a
   chance of about 1e-6).

2. **Accuracy over the validated region** (``--grid``): for every m <= 30 and K
   from m to 2m (``full``; ``standard`` takes K = m, m+1, m+2, 3m/2, 2m), both
   laws at the levels 0.001, 0.025, 0.5, 0.975, 0.999: the CDF at the computed
   quantile against Chiani's formula in his own basis evaluated with mpmath at
   a precision raised until 30 digits settle (``tests/nis_reference.py``).
   Target: CDF error <= 1e-8 and quantile level error <= 1e-8; and a cold law
   plus one CDF point within 100 ms of CPU time at every size.

3. **Monte Carlo** (``--mc-draws``, default 200,000 Bartlett draws per size, on
   the sizes of ``--mc-grid``): at the exact 2.5 %, 50 % and 97.5 % points the
   share of draws below must lie in the binomial band of miss probability 1e-6
   (Bonferroni over all checks stays below 1e-3).  The largest deviation is
   printed beside the Monte Carlo standard error: the band shrinks as
   1/sqrt(draws), about 4e-3 at the median with the default, 1e-3 at 4e6 draws.

Run: ``python tests/benchmarks/bench_nis.py [--grid standard|full|none] [--mc-draws N]``
(``--grid none --mc-draws 0`` runs the speed part alone, in a few seconds; the
standard grid takes about 10 minutes of a busy 2-core machine, the full one about 20).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy import stats

from course import nis
from course.nis import _pfaffians

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/ for nis_reference

LEVELS = (1e-3, 0.025, 0.5, 0.975, 0.999)
TOLERANCE = 1e-8
POINT_BUDGET = 0.100  # seconds of CPU per cold law and CDF point


def cold() -> None:
    """Forget everything an earlier call computed (the panel matrix is the only cache)."""
    _pfaffians._panel_rule.cache_clear()


def cpu_time(func, repeat=3):
    """Minimum CPU time of ``func()`` over ``repeat`` cold calls, and its last value."""
    best, value = math.inf, None
    for _ in range(repeat):
        cold()
        start = time.process_time()
        value = func()
        best = min(best, time.process_time() - start)
    return best, value


def speed(m, K, eps, seed):
    alpha = 0.05
    n_draws = math.ceil(math.log(2 / 0.05) / (2 * eps**2))
    laws = {w: nis.extreme_eigenvalue(m, K, w) for w in ("min", "max")}
    grid = np.linspace(float(laws["min"].ppf(1e-6)), float(laws["max"].isf(1e-6)), 200)

    def exact():
        law_min, law_max = nis.extreme_eigenvalue(m, K, "min"), nis.extreme_eigenvalue(m, K, "max")
        cdf_min, cdf_max = law_min.cdf(grid), law_max.cdf(grid)
        return cdf_min, cdf_max, (float(law_min.ppf(alpha / 2)), float(law_max.isf(alpha / 2)))

    def monte_carlo():
        lmin, lmax = nis.simulate_extreme_eigenvalues(
            m, K, n_draws, rng=np.random.default_rng(seed)
        )
        lmin.sort()
        lmax.sort()
        cdf_min = np.searchsorted(lmin, grid, side="right") / n_draws
        cdf_max = np.searchsorted(lmax, grid, side="right") / n_draws
        crit = (float(np.quantile(lmin, alpha / 2)), float(np.quantile(lmax, 1 - alpha / 2)))
        return cdf_min, cdf_max, crit

    t_exact, (e_min, e_max, e_crit) = cpu_time(exact)
    t_mc, (s_min, s_max, s_crit) = cpu_time(monte_carlo, repeat=1)
    gap = max(np.max(np.abs(e_min - s_min)), np.max(np.abs(e_max - s_max)))
    ratio = t_mc / t_exact
    met = ratio >= 100 and gap <= 2 * eps
    print(
        f"1. speed: CDFs of lambda_min and lambda_max on 200 points + critical values, m={m}, K={K}"
    )
    print(f"   accuracy: sup-error {eps:g} at 95% (Monte Carlo needs N = {n_draws} draws by DKW)")
    print("   CPU time (process_time); exact laws built cold inside the timed call, best of 3")
    print(f"   exact (course.nis, Chiani Pfaffian):   {t_exact * 1e3:10.1f} ms")
    print(f"   Monte Carlo (Bartlett + eigvalsh):     {t_mc * 1e3:10.1f} ms")
    print(
        f"   ratio Monte Carlo / exact:             {ratio:10.0f}x  (target >= 100x: "
        f"{'met' if ratio >= 100 else 'NOT met'})"
    )
    print(
        f"   check: sup |exact - MC| = {gap:.2e} (<= {2 * eps:g} required); critical values "
        f"exact ({e_crit[0]:.5f}, {e_crit[1]:.5f}) vs MC ({s_crit[0]:.5f}, {s_crit[1]:.5f})"
    )
    return met


def sizes(kind):
    largest = nis.EXACT_LAW_LIMITS["m"]
    for m in range(1, largest + 1):
        if kind == "full":
            Ks = range(m, 2 * m + 1)
        else:
            Ks = sorted({m, m + 1, m + 2, (3 * m) // 2, 2 * m})
        for K in Ks:
            yield m, K


def accuracy(kind):
    import nis_reference  # needs mpmath

    print(f"2. accuracy against the mpmath reference, grid '{kind}' (m <= 30, K = m..2m)")
    worst_cdf = worst_level = worst_point = 0.0
    where = {}
    for m, K in sizes(kind):
        intervals, computed = [], []
        for which in ("max", "min"):
            cold()
            start = time.process_time()
            law = nis.extreme_eigenvalue(m, K, which)
            law.cdf(1.0)
            point = time.process_time() - start
            if point > worst_point:
                worst_point, where["point"] = point, (m, K, which)
            xs = np.array([float(law.ppf(q)) for q in LEVELS])
            computed.append(law.cdf(xs))
            intervals += [(0.0, x) if which == "max" else (x, math.inf) for x in xs]
        inside = np.array(nis_reference.checked_probabilities(m, K, intervals))
        truth = np.concatenate([inside[: len(LEVELS)], 1.0 - inside[len(LEVELS) :]])
        cdf_error = float(np.max(np.abs(np.concatenate(computed) - truth)))
        level_error = float(np.max(np.abs(truth - np.tile(LEVELS, 2))))
        if cdf_error > worst_cdf:
            worst_cdf, where["cdf"] = cdf_error, (m, K)
        if level_error > worst_level:
            worst_level, where["level"] = level_error, (m, K)
        if cdf_error > TOLERANCE or level_error > TOLERANCE:
            print(
                f"   MISSED at m={m}, K={K}: CDF error {cdf_error:.1e}, level error {level_error:.1e}"
            )
        if K - 2 * m == 0:  # the last K of this m: one progress line per dimension
            print(f"   m={m:2d} done; largest CDF error so far {worst_cdf:.1e}", flush=True)
    print(f"   largest CDF error {worst_cdf:.1e} at (m, K) = {where.get('cdf')} (target <= 1e-8)")
    print(
        f"   largest quantile level error {worst_level:.1e} at {where.get('level')} (target <= 1e-8)"
    )
    print(
        f"   slowest cold law + one CDF point: {worst_point * 1e3:.1f} ms CPU at {where.get('point')} "
        f"(target <= {POINT_BUDGET * 1e3:.0f} ms)"
    )
    return worst_cdf <= TOLERANCE and worst_level <= TOLERANCE and worst_point <= POINT_BUDGET


MC_SIZES = [
    (m, K) for m in (1, 2, 3, 5, 8, 12, 16, 20, 24, 30) for K in (m, m + 1, (3 * m) // 2, 2 * m)
]


def monte_carlo_check(draws, seed):
    levels = (0.025, 0.5, 0.975)
    print(
        f"3. Monte Carlo: {draws} Bartlett draws per size, {len(MC_SIZES)} sizes, m <= 30, K = m..2m"
    )
    ok, worst, worst_at = True, 0.0, None
    rng = np.random.default_rng(seed)
    for m, K in dict.fromkeys(MC_SIZES):
        lmin, lmax = nis.simulate_extreme_eigenvalues(m, K, draws, rng=rng)
        for which, sample in (("min", lmin), ("max", lmax)):
            law = nis.extreme_eigenvalue(m, K, which)
            for q in levels:
                share = float(np.mean(sample <= float(law.ppf(q))))
                lo, hi = stats.binom.interval(1 - 1e-6, draws, q)
                if not lo / draws <= share <= hi / draws:
                    ok = False
                    print(
                        f"   MISSED at m={m}, K={K}, {which}, level {q}: Monte Carlo share {share:.5f}"
                    )
                if abs(share - q) > worst:
                    worst, worst_at = abs(share - q), (m, K, which, q)
    se = math.sqrt(0.25 / draws)
    print(
        f"   largest |share below the exact quantile - level| = {worst:.1e} at {worst_at} "
        f"(Monte Carlo standard error at the median {se:.1e}); all in their binomial bands: {ok}"
    )
    return ok


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--m", type=int, default=6)
    parser.add_argument("--K", type=int, default=1000)
    parser.add_argument("--eps", type=float, default=1e-3, help="sup-error of the CDF (DKW, 95 %%)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--grid", choices=("standard", "full", "none"), default="standard")
    parser.add_argument("--mc-draws", type=int, default=200_000)
    args = parser.parse_args(argv)
    met = speed(args.m, args.K, args.eps, args.seed)
    if args.grid != "none":
        met &= accuracy(args.grid)
    if args.mc_draws > 0:
        met &= monte_carlo_check(args.mc_draws, args.seed)
    print("all targets met" if met else "a target was MISSED")
    return 0 if met else 1


if __name__ == "__main__":
    sys.exit(main())
