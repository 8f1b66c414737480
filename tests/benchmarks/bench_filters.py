"""Benchmark: vectorised EKF Monte Carlo against a per-run filterpy loop.

The lecture's example (state (beta, x), beta a random walk, y = x + e) is
simulated for many independent runs; every run is filtered by

* ours: :func:`course.filters.extended_kalman_filter` on the whole batch at
  once (one call; each step acts on all runs), and
* the baseline: ``filterpy.kalman.ExtendedKalmanFilter``, one filter object
  per run, stepped in a Python loop (update, then predict with the
  Jacobian), the usual way of running a Monte Carlo study with it.

Both compute the same innovations (checked to 1e-9 on the common runs).
The baseline is timed on ``--baseline-runs`` runs and scaled linearly to
``--runs`` (its cost is exactly proportional to the number of runs), so the
benchmark finishes in well under a minute.  Both are timed in CPU time of this
process (``time.process_time``, BLAS threads included), so that other work on a
shared machine does not move the ratio.  Target: at least 20x.

Usage::

    python tests/benchmarks/bench_filters.py [--runs 10000] [--steps 200] [--baseline-runs 300]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from course import diagnosis as dg
from course import filters as kf

TARGET = 20.0
TS, Q_BETA, Q_X, R = 0.1, 1e-4, 1e-4, 2.5e-3


def make_data(runs, steps, seed=0):
    model = dg.beta_drift_model(Ts=TS, q_beta=Q_BETA, q_x=Q_X, r=R, x0_mean=(1.0, 0.5))
    u = np.where((np.arange(steps) // 40) % 2 == 0, 0.5, 1.5)
    _, y = model.simulate(steps, np.random.default_rng(seed), batch=runs, u=u)
    return model, u, y


def ours(model, u, y):
    res = kf.extended_kalman_filter(model, y, u, store_covariances=False)
    return res.eps[..., 0]


def filterpy_loop(model, u, y):
    from filterpy.kalman import ExtendedKalmanFilter

    class BetaEKF(ExtendedKalmanFilter):
        def predict_x(self, u=0):
            beta, x = self.x[0, 0], self.x[1, 0]
            self.x = np.array([[beta], [x - TS * beta * x + TS * u]])

    def HJacobian(x):
        return np.array([[0.0, 1.0]])

    def Hx(x):
        return x[1:2]

    runs, steps = y.shape[0], y.shape[1]
    eps = np.empty((runs, steps))
    for r in range(runs):
        ekf = BetaEKF(dim_x=2, dim_z=1)
        ekf.x = model.x0_mean.reshape(2, 1).copy()
        ekf.P = model.x0_cov.copy()
        ekf.Q = model.GQG.copy()
        ekf.R = model.R.copy()
        for t in range(steps):
            ekf.update(y[r, t], HJacobian, Hx)
            eps[r, t] = ekf.y[0, 0]
            beta, x = ekf.x[0, 0], ekf.x[1, 0]
            ekf.F = np.array([[1.0, 0.0], [-TS * x, 1.0 - TS * beta]])
            ekf.predict(u[t])
    return eps


def best_of(fun, repeats, *args):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.process_time()
        out = fun(*args)
        times.append(time.process_time() - t0)
    return min(times), out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=10_000)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--baseline-runs", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)

    model, u, y = make_data(args.runs, args.steps)
    t_ours, eps = best_of(ours, args.repeats, model, u, y)
    nb = min(args.baseline_runs, args.runs)
    t_base, eps_base = best_of(filterpy_loop, 1, model, u, y[:nb])
    err = float(np.max(np.abs(eps[:nb] - eps_base)))
    if err > 1e-9:
        raise SystemExit(f"the two filters disagree: max |eps difference| = {err:.3g}")
    t_base_full = t_base * args.runs / nb
    ratio = t_base_full / t_ours
    print(f"EKF Monte Carlo, lecture example: {args.runs} runs x {args.steps} steps")
    print(f"  course.filters (vectorised, best of {args.repeats}): {t_ours:8.3f} s CPU")
    print(
        f"  filterpy ExtendedKalmanFilter, per-run loop: {t_base:8.3f} s for {nb} runs"
        f" -> {t_base_full:8.1f} s for {args.runs} runs"
    )
    print(f"  innovations agree to {err:.1e}")
    print(
        f"  speed-up: {ratio:.1f}x (target >= {TARGET:g}x): {'met' if ratio >= TARGET else 'NOT met'}"
    )
    return 0 if ratio >= TARGET else 1


if __name__ == "__main__":
    raise SystemExit(main())
