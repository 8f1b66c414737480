"""Benchmark: accuracy on demand of course.quadform against its own past and against chi2comb.

Run:  python tests/benchmarks/bench_quadform.py

Baseline: the implementation of ``course/quadform.py`` at the pinned git
revision ``BASELINE_REVISION`` (the last one before issue 15), loaded in the
same run from git history (``git show``) together with the modules it
imported, as the package ``quadform_baseline``: a fair, frozen "today".  A
peer: chi2comb (Davies' algorithm AS 155 in C, the package ``chi2comb``)
when it can be imported; it needs its C library, so the column is skipped
otherwise.

On Davies' 13 test cases (39 points, 30-digit reference values of
``tests/test_quadform.py``) it prints, side by side, per point:

- the baseline's time per scalar call and its error;
- the new ``imhof_cdf`` at ``rtol`` = 1e-6 and at the default accuracy: time
  per scalar call and error (the relative error of the smaller tail must be
  below the requested ``rtol``);
- chi2comb at its default tolerance (1e-4) and at 1e-12: time and error.

Then: many points in one vectorised call, a law of 500 weights, and the
summary with the targets of issue 15: per scalar call at least 20x faster
than the baseline at ``rtol=1e-6`` and 5x at the default accuracy (ratio of
the total times over the 39 points), and the same 5x with 500 weights.
Times are the minimum of repeated calls in process CPU time (the machine is
shared).  A scalar call on a law already seen (the usual loop: a scan over
c, a root search) reuses the validated terms (see ``course.quadform._law``);
the "cold" column clears that memo before every call and is reported too.
Exits with status 1 when a target is missed or an accuracy is not met.
"""

from __future__ import annotations

import functools
import importlib
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))
from test_quadform import DAVIES_CASES  # noqa: E402

from course import quadform  # noqa: E402

BASELINE_REVISION = "a19d68cbc02bdd35da2c604d7a7285383ef185a7"
BASELINE_MODULES = ("quadform", "linalg", "distributions", "results")
TARGET_FAST = 20.0  # at rtol = 1e-6
TARGET_DEFAULT = 5.0  # at the default rtol, also with 500 weights


def load_baseline():
    """``course.quadform`` as of BASELINE_REVISION, imported from git history."""
    folder = pathlib.Path(tempfile.mkdtemp(prefix="quadform_baseline_"))
    package = folder / "quadform_baseline"
    package.mkdir()
    (package / "__init__.py").write_text("")
    for name in BASELINE_MODULES:
        shown = subprocess.run(
            ["git", "-C", str(ROOT), "show", f"{BASELINE_REVISION}:course/{name}.py"],
            capture_output=True,
            text=True,
        )
        if shown.returncode != 0:
            sys.exit(
                f"cannot load the baseline from git history ({shown.stderr.strip()}); "
                "run the benchmark in a full clone (git fetch --unshallow)"
            )
        (package / f"{name}.py").write_text(shown.stdout)
    sys.path.insert(0, str(folder))
    return importlib.import_module("quadform_baseline.quadform")


def load_chi2comb():
    try:
        from chi2comb import ChiSquared, chi2comb_cdf
    except ImportError as exc:
        print(f"chi2comb column skipped (cannot import chi2comb: {exc})")
        return None

    def cdf(c, weights, dof, nc, atol):
        terms = [ChiSquared(w, d, h) for w, h, d in zip(weights, dof, nc)]
        p, errno, _ = chi2comb_cdf(c, terms, 0.0, lim=100_000, atol=atol)
        return p if errno == 0 else np.nan

    return cdf


def cpu_time(func, repeat=7, number=3):
    """Minimum CPU time of one call over ``repeat`` rounds of ``number`` calls."""
    best = np.inf
    for _ in range(repeat):
        start = time.process_time()
        for _ in range(number):
            func()
        best = min(best, (time.process_time() - start) / number)
    return best


def cold_call(call):
    """``call()`` on a law never seen (the memo of validated laws, where there is one, cleared)."""
    getattr(quadform, "_LAWS", {}).clear()
    return call()


def relative_error(p, ref):
    small = min(ref, 1.0 - ref)
    got = p if ref < 0.5 else 1.0 - p
    return abs(got - small) / small


def main():
    old = load_baseline()
    chi2comb = load_chi2comb()
    rtols = {"1e-6": 1e-6, "default": quadform.RTOL}
    header = (
        f"{'case':<22}{'c':>5}{'P(Q<=c)':>10} | {'today ms':>8}{'err':>8} |"
        + "".join(f"{'rtol ' + k + ' ms':>17}{'rel.err':>8}{'cold':>7} |" for k in rtols)
        + (f"{'chi2comb 1e-4 ms':>17}{'err':>8}{'1e-12 err':>10}" if chi2comb else "")
    )
    print(f"baseline: course/quadform.py at {BASELINE_REVISION[:10]} (from git history)")
    print(header)
    print("-" * len(header))
    totals = {"today": 0.0, **dict.fromkeys(rtols, 0.0), **{k + " cold": 0.0 for k in rtols}}
    ok = True
    chi_errors = []
    for (weights, dof, nc), values in DAVIES_CASES.items():
        name = f"w={weights}"[:21]
        for c, ref in values:
            today = functools.partial(old.imhof_cdf, c, weights, dof, nc)
            t_old = cpu_time(today, repeat=3, number=2)
            e_old = abs(today() - ref)
            totals["today"] += t_old
            row = f"{name:<22}{c:>5g}{ref:>10.6f} | {1e3 * t_old:>8.3f}{e_old:>8.0e} |"
            for key, rtol in rtols.items():
                call = functools.partial(quadform.imhof_cdf, c, weights, dof, nc, rtol=rtol)
                t_new, t_cold = cpu_time(call), cpu_time(functools.partial(cold_call, call))
                err = relative_error(call(), ref)
                ok &= err <= rtol
                totals[key] += t_new
                totals[key + " cold"] += t_cold
                row += f"{1e3 * t_new:>17.3f}{err:>8.0e}{1e3 * t_cold:>7.3f} |"
            if chi2comb:
                peer = functools.partial(chi2comb, c, weights, dof, nc)
                t_chi = cpu_time(functools.partial(peer, 1e-4))
                e_chi, e_chi12 = abs(peer(1e-4) - ref), abs(peer(1e-12) - ref)
                chi_errors.append((e_chi, e_chi12))
                row += f"{1e3 * t_chi:>17.3f}{e_chi:>8.0e}{e_chi12:>10.0e}"
            print(row)
            name = ""
    print("-" * len(header))

    # many points in one call: no Python loop over the points
    weights, dof, nc = (7, 3, -7, -3), (6, 2, 1, 1), (6, 2, 6, 2)
    grid = np.linspace(-80.0, 250.0, 2000)
    t_vec_old = cpu_time(lambda: old.imhof_cdf(grid, weights, dof, nc), repeat=1, number=1)
    t_vec = {
        k: cpu_time(lambda r=r: quadform.imhof_cdf(grid, weights, dof, nc, rtol=r), 3, 1)
        for k, r in rtols.items()
    }
    ref_grid = quadform.imhof_cdf(grid, weights, dof, nc, rtol=1e-13)
    print(
        f"2000 points in one call: today {1e3 * t_vec_old:.0f} ms; "
        + "; ".join(
            f"rtol {k} {1e3 * t:.0f} ms ({1e6 * t / grid.size:.1f} us/point, "
            f"max error {np.max(np.abs(quadform.imhof_cdf(grid, weights, dof, nc, rtol=rtols[k]) - ref_grid)):.0e})"
            for k, t in t_vec.items()
        )
    )

    # a law of 500 weights
    rng = np.random.default_rng(1)
    many = rng.uniform(0.1, 1.0, 500)
    point = float(np.sum(many)) * 1.3
    t_many_old = cpu_time(lambda: old.imhof_cdf(point, many), repeat=3, number=1)
    t_many = cpu_time(lambda: quadform.imhof_cdf(point, many), repeat=3, number=2)
    t_many_cold = cpu_time(
        functools.partial(cold_call, lambda: quadform.imhof_cdf(point, many)), 3, 2
    )
    gap = abs(quadform.imhof_cdf(point, many) - old.imhof_cdf(point, many, rtol=1e-13))
    ratio_many = t_many_old / t_many
    print(
        f"500 weights, one point: today {1e3 * t_many_old:.2f} ms, default {1e3 * t_many:.2f} ms "
        f"(cold {1e3 * t_many_cold:.2f} ms), {ratio_many:.1f}x; |new - today at 1e-13| = {gap:.0e}"
    )
    ok &= gap < 1e-10

    print()
    print("summary (per scalar call, total over Davies' 39 points; min CPU time of repeated calls)")
    results = []
    for key, target in (("1e-6", TARGET_FAST), ("default", TARGET_DEFAULT)):
        ratio = totals["today"] / totals[key]
        cold_ratio = totals["today"] / totals[key + " cold"]
        met = ratio >= target
        results.append(met)
        print(
            f"  rtol {key:<8}: {1e6 * totals[key] / 39:7.0f} us/call vs today "
            f"{1e6 * totals['today'] / 39:.0f} us: {ratio:5.1f}x (target >= {target:g}x: "
            f"{'met' if met else 'NOT met'}); cold (memo cleared) {cold_ratio:.1f}x"
        )
    results.append(ratio_many >= TARGET_DEFAULT)
    print(
        f"  500 weights   : {ratio_many:.1f}x at the default accuracy (target >= "
        f"{TARGET_DEFAULT:g}x: {'met' if results[-1] else 'NOT met'})"
    )
    print(f"  requested accuracy met at every point and rtol: {'yes' if ok else 'NO'}")
    if chi_errors:
        errors = np.array(chi_errors)
        print(
            f"  chi2comb: worst error {np.nanmax(errors[:, 0]):.1e} at its default 1e-4, "
            f"{np.nanmax(errors[:, 1]):.1e} at 1e-12 ({int(np.isnan(errors[:, 1]).sum())} "
            "points where it reports a failure)"
        )
    return 0 if ok and all(results) else 1


if __name__ == "__main__":
    sys.exit(main())
