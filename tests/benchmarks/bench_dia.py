"""Benchmark: DIA at network sizes against statsmodels' ``outlier_test`` (issue 38).

A quadratic trend (n = 3) observed m times with uncorrelated, unequal variances and one
outlier; both tools go from the data to the identified observation:

* ours: ``lsq.fit(A, y, variances)`` then ``lsq.dia(fit)`` (detection by the overall model
  test, identification by the largest w-test, adaptation);
* statsmodels: ``OLS(y / sigma, A / sigma).fit().outlier_test()`` on the whitened model
  (its ``outlier_test`` takes OLS results only; the whitening is in its time): externally
  studentised residuals with Bonferroni's correction, the largest ``|student_resid|``.

statsmodels' ``outlier_test`` grows faster than m (0.9 s of CPU at m = 10³ on the
development machine), so by default it runs at m = 10³ only (``--statsmodels-max``).
The identified index must be the planted outlier for both, or the benchmark stops.
Targets (CPU time of this process, ``time.process_time``, BLAS threads included; each
size repeated ``--repeats`` times, ours and statsmodels alternating, the best of each):

* m = 10³: ours at most 0.5x statsmodels' time;
* the time exponent of ours over m = 10³ … 10⁵ (log-log slope of the best times) at most 1.2;
* m = 10⁵: ``lsq.dia`` alone (on a given fit) under 1 s of CPU, and the peak memory of
  fit + dia under 200 MB (the peak resident set, VmHWM, of a fresh subprocess that
  imports only the course, data and interpreter included);
* a full Qyy at m = 2,000: ``lsq.dia`` on a given fit at most 1.5x ``lsq.fit``'s own time.

Exits 1 when a target is missed.

Usage::

    OPENBLAS_NUM_THREADS=1 python tests/benchmarks/bench_dia.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import subprocess
import sys
import time

import numpy as np

from course import lsq

SIZES = (1_000, 10_000, 100_000)
TARGET_RATIO = 0.5  # ours / statsmodels at m = 1e3, at most
TARGET_EXPONENT = 1.2
TARGET_SECONDS = 1.0  # dia alone at m = 1e5
TARGET_MB = 200.0  # peak resident memory of fit + dia at m = 1e5
TARGET_DENSE = 1.5  # dia / fit at m = 2000, full Qyy


def problem(m, seed=0):
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, m)
    A = np.column_stack([np.ones(m), t, t**2])
    variances = (0.01 * rng.uniform(0.5, 2.0, m)) ** 2
    y = A @ [1.0, -2.0, 0.5] + np.sqrt(variances) * rng.standard_normal(m)
    outlier = m // 3
    y[outlier] += 60.0 * math.sqrt(variances[outlier])
    return A, y, variances, outlier


def dense_problem(m, seed=1):
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, m)
    A = np.column_stack([np.ones(m), t, t**2])
    lag = np.arange(m)
    Q = 1e-4 * (0.5 * np.exp(-np.abs(lag[:, None] - lag[None, :]) / 20.0) + np.eye(m))
    y = A @ [1.0, -2.0, 0.5] + np.linalg.cholesky(Q) @ rng.standard_normal(m)
    y[m // 3] += 0.2
    return A, y, Q, m // 3


def ours(A, y, variances):
    result = lsq.dia(lsq.fit(A, y, variances))
    return int(result.candidate_names[result.identified].split()[-1])


def statsmodels_outlier_test(A, y, variances):
    import statsmodels.api as sm

    # outlier_test needs OLS results (WLS has no influence measures): the whitened model
    sigma = np.sqrt(variances)
    table = sm.OLS(y / sigma, A / sigma[:, None]).fit().outlier_test()
    return int(np.argmax(np.abs(np.asarray(table)[:, 0])))


def cpu(call, *args):
    t0 = time.process_time()
    value = call(*args)
    return time.process_time() - t0, value


def peak_resident_mb() -> float:
    """This process's peak resident memory: VmHWM (of its own address space, new at exec),
    not ru_maxrss, which Linux keeps across execve and so shows the parent's size at fork."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def child(m: int) -> None:
    """Fit + dia at m in this fresh process; print the CPU time and peak resident memory."""
    A, y, variances, outlier = problem(m)
    seconds, index = cpu(ours, A, y, variances)
    f = lsq.fit(A, y, variances)
    dia_seconds, _ = cpu(lsq.dia, f)
    peak_mb = peak_resident_mb()
    print(
        json.dumps(
            {"seconds": seconds, "dia": dia_seconds, "peak_mb": peak_mb, "ok": index == outlier}
        )
    )


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument(
        "--statsmodels-max",
        type=int,
        default=SIZES[0],
        help="largest m at which statsmodels runs (its outlier_test costs ~0.9 s at 1e3 here)",
    )
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        child(args.child)
        return 0
    try:  # (imported here, outside the timed calls)
        import statsmodels.api  # noqa: F401
    except ImportError:
        statsmodels_here = False
        print("statsmodels is not installed (pip install '.[bench]'): no baseline ratio")
    else:
        statsmodels_here = True
    failures = []
    best = {}
    print(f"{'m':>8} {'ours fit+dia':>13} {'statsmodels':>12} {'ratio':>7}  identified")
    for m in SIZES:
        A, y, variances, outlier = problem(m)
        mine, theirs = [], []
        for _ in range(args.repeats):
            seconds, index = cpu(ours, A, y, variances)
            if index != outlier:
                print(f"m = {m}: ours identified {index}, the outlier is {outlier}")
                return 1
            mine.append(seconds)
            if statsmodels_here and m <= args.statsmodels_max:
                seconds, index = cpu(statsmodels_outlier_test, A, y, variances)
                if index != outlier:
                    print(f"m = {m}: statsmodels identified {index}, the outlier is {outlier}")
                    return 1
                theirs.append(seconds)
        best[m] = min(mine)
        ratio = best[m] / min(theirs) if theirs else float("nan")
        shown = f"{min(theirs):12.4f}" if theirs else f"{'-':>12}"
        who = "(both)" if theirs else "(ours)"
        print(f"{m:>8} {best[m]:13.4f} {shown} {ratio:7.3f}  {outlier} {who}")
        if m == SIZES[0] and theirs and not ratio <= TARGET_RATIO:
            failures.append(f"m = {m}: {ratio:.3f}x statsmodels > {TARGET_RATIO}x")
    # exponent: CPU time resolution is ~1 ms, so the slope comes from the end points
    exponent = math.log(best[SIZES[-1]] / best[SIZES[0]]) / math.log(SIZES[-1] / SIZES[0])
    print(f"time exponent over m = {SIZES[0]} ... {SIZES[-1]}: {exponent:.3f}")
    if not exponent <= TARGET_EXPONENT:
        failures.append(f"time exponent {exponent:.3f} > {TARGET_EXPONENT}")
    out = subprocess.run(
        [sys.executable, __file__, "--child", str(SIZES[-1])],
        capture_output=True,
        text=True,
        check=True,
    )
    measured = json.loads(out.stdout.strip().splitlines()[-1])
    print(
        f"m = {SIZES[-1]} in a fresh process: fit + dia {measured['seconds']:.3f} s CPU, "
        f"dia alone {measured['dia']:.3f} s CPU, peak resident {measured['peak_mb']:.0f} MB"
    )
    if not measured["ok"]:
        failures.append("the fresh process identified the wrong observation")
    if not measured["dia"] < TARGET_SECONDS:
        failures.append(f"dia at m = {SIZES[-1]}: {measured['dia']:.3f} s >= {TARGET_SECONDS} s")
    if not measured["peak_mb"] < TARGET_MB:
        failures.append(f"peak memory {measured['peak_mb']:.0f} MB >= {TARGET_MB} MB")
    # a full Qyy: dia on a given fit against the fit's own time
    A, y, Q, outlier = dense_problem(2_000)
    fit_times, dia_times = [], []
    for _ in range(args.repeats):
        seconds, f = cpu(lsq.fit, A, y, Q)
        fit_times.append(seconds)
        seconds, result = cpu(lsq.dia, f)  # (a fresh fit: nothing cached)
        dia_times.append(seconds)
        if result.candidate_names[result.identified] != f"observation {outlier}":
            print(f"full Qyy: dia identified {result.decision}, the outlier is {outlier}")
            return 1
    ratio = min(dia_times) / min(fit_times)
    print(
        f"full Qyy, m = 2000: fit {min(fit_times):.4f} s, dia {min(dia_times):.4f} s CPU: "
        f"{ratio:.3f}x the fit"
    )
    if not ratio <= TARGET_DENSE:
        failures.append(f"full Qyy: dia {ratio:.3f}x fit > {TARGET_DENSE}x")
    for failure in failures:
        print("MISSED:", failure)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
