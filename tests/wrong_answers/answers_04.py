"""Wrong and right answers of assignment 04_ekf_residuals (data for tests/test_wrong_answers.py).

WRONG[q]: answers a class would plausibly write; each must lose points at grading.
RIGHT[q]: correct answers written differently; each must keep full marks.
Each source replaces the whole answer cell of q in the solution notebook (format: see the
docstring of tests/test_wrong_answers.py). The k-th variant of a question is graded as student
wa04-k: wa04-1 has window 10 and alpha 0.001 (the practice record's settings), wa04-2 window 8.
"""

ASSIGNMENT = "04_ekf_residuals"
STUDENT = "wa04"
DEPENDS = {"q7": ["q7_practice"], "q7_why": ["q7"]}

# The demo student's personal answer (window 8, alpha 0.001: a false alarm at t = 11), as a
# student copying a classmate's screen would hard-code it.
DEMO_ALARM = "(26.124481558376143, 11)"
DEMO_COUNTS = "(46, 0)"

_Q2_HEAD = """def normalized_innovations(y, a, q, r, m0, p0):
    y = np.asarray(y, dtype=float)
    x, P = float(m0), float(p0)
    z = np.empty(y.shape)
"""
_Q2_RIGHT_LOOP = """    for t, y_t in enumerate(y):
        S = P + r
        K = P / S
        eps = y_t - x
        z[t] = eps / np.sqrt(S)
        x = x + K * eps
        P = (1 - K) ** 2 * P + K**2 * r
        x, P = a * x, a**2 * P + q
    return z
"""


def _q2(body: str) -> str:
    return _Q2_HEAD + body


_Q1 = "def steady_state(q, r):\n    P = (q + np.sqrt(q * q + 4 * q * r)) / 2\n"

_Q3_HEAD = "def windowed_statistic(z, L):\n    z = np.asarray(z, dtype=float)\n"

_Q4 = "def window_threshold(L, alpha):\n    return float({})\n"

_Q5P_T = """def find_alarm(record):
    model = dg.beta_drift_model(Ts=record["Ts"], q_beta=record["q_beta"], q_x=record["q_x"],
                                r=record["r"], x0_mean=(1.0, 0.5))
    L, alpha = record["window"], record["alpha"]
    T_practice = nis.windowed_nis(kf.extended_kalman_filter(model, record["y"], record["u"]), L)
"""
_Q5_T = """model = dg.beta_drift_model(Ts=mine["Ts"], q_beta=mine["q_beta"], q_x=mine["q_x"],
                            r=mine["r"], x0_mean=(1.0, 0.5))
L, alpha = mine["window"], mine["alpha"]
T_mine = nis.windowed_nis(kf.extended_kalman_filter(model, mine["y"], mine["u"]), L)
"""
_FIRST = "int(np.flatnonzero(np.nan_to_num({T}) > {thr})[0])"

_Q6_HEAD = """def false_alarm_rates(a, q, r, N, L, alpha, n_runs, seed):
    rng = np.random.default_rng(seed)
    x = rng.standard_normal(n_runs)
    W = rng.standard_normal((N, n_runs))
    V = rng.standard_normal((N, n_runs))
    y = np.empty((n_runs, N))
    for t in range(N):
        y[:, t] = x + np.sqrt(r) * V[t]
        x = a * x + np.sqrt(q) * W[t]
    model = kf.LinearModel(F=[[a]], H=[[1.0]], Q=[[q]], R=[[r]], x0_mean=[0.0], x0_cov=[[1.0]])
    z = kf.kalman_filter(model, y[..., None]).normalized_innovations()[..., 0]
    c = np.concatenate([np.zeros((n_runs, 1)), np.cumsum(z**2, axis=1)], axis=1)
    T = c[:, L:] - c[:, :-L]
"""

_Q7_HEAD = """T7 = {}
for q_beta in (0.0, 1e-4):
    m7 = dg.beta_drift_model(Ts=mine7["Ts"], q_beta=q_beta, q_x=mine7["q_x"], r=mine7["r"],
                             x0_mean=(1.0, 0.5))
    T7[q_beta] = np.nan_to_num(nis.windowed_nis(kf.extended_kalman_filter(m7, mine7["y"], mine7["u"]), 10))
thr7 = nis.windowed_nis_threshold(10, 0.001)
t_fault7 = mine7["t_fault"]
"""

_Q7P = """def count_false_alarms(record):
    L, alpha, t_f = record["window"], record["alpha"], record["t_fault"]
    T7 = {}
    for q_beta in (0.0, 1e-4):
        m7 = dg.beta_drift_model(Ts=record["Ts"], q_beta=q_beta, q_x=record["q_x"], r=record["r"],
                                 x0_mean=(1.0, 0.5))
        T7[q_beta] = np.nan_to_num(nis.windowed_nis(kf.extended_kalman_filter(m7, record["y"], record["u"]), L))
    thr7 = nis.windowed_nis_threshold(L, alpha)
"""

_Q8_HEAD = """def rls_update(theta, P, phi, y, r):
    theta, P, phi = (np.asarray(v, dtype=float) for v in (theta, P, phi))
    Pphi = P @ phi
    S = phi @ Pphi + r
    K = Pphi / S
"""

WRONG = {
    "q1": [
        (
            "filtered variance P(t|t) instead of the prediction variance",
            _Q1 + "    K = P / (P + r)\n    return ((1 - K) * P, K)\n",
        ),
        ("(K, P) order", _Q1 + "    return (P / (P + r), P)\n"),
        (
            "the negative root",
            _Q1.replace("(q + np.sqrt(", "(q - np.sqrt(") + "    return (P, P / (P + r))\n",
        ),
        (
            "one Riccati step from P = 1",
            "def steady_state(q, r):\n    P = 1.0 - 1.0 / (1.0 + r) + q\n    return (P, P / (P + r))\n",
        ),
        ("gain P/r without the sum", _Q1 + "    return (P, P / r)\n"),
        (
            "filtered variance, and K computed from it",
            _Q1 + "    P = P * r / (P + r)\n    return (P, P / (P + r))\n",
        ),
        (
            "right, but computed in float32",
            "def steady_state(q, r):\n"
            "    q, r = np.float32(q), np.float32(r)\n"
            "    P = (q + np.sqrt(q * q + np.float32(4) * q * r)) / np.float32(2)\n"
            "    return (P, P / (P + r))\n",
        ),
        (
            "the public case hard-wired (the golden ratio)",
            _Q1.replace("(q + np.sqrt(q * q + 4 * q * r)) / 2", "(1 + np.sqrt(5)) / 2")
            + "    return (P, P / (P + r))\n",
        ),
    ],
    "q2": [
        (
            "predicts before the first update",
            _q2(
                """    for t, y_t in enumerate(y):
        x, P = a * x, a**2 * P + q
        S = P + r
        K = P / S
        eps = y_t - x
        z[t] = eps / np.sqrt(S)
        x = x + K * eps
        P = (1 - K) * P
    return z
"""
            ),
        ),
        ("innovations not normalised", _q2(_Q2_RIGHT_LOOP.replace("eps / np.sqrt(S)", "eps"))),
        ("divided by S, not sqrt(S)", _q2(_Q2_RIGHT_LOOP.replace("eps / np.sqrt(S)", "eps / S"))),
        ("S = P without r", _q2(_Q2_RIGHT_LOOP.replace("eps / np.sqrt(S)", "eps / np.sqrt(P)"))),
        (
            "residual after the update instead of the innovation",
            _q2(
                """    for t, y_t in enumerate(y):
        S = P + r
        K = P / S
        x = x + K * (y_t - x)
        z[t] = (y_t - x) / np.sqrt(S)
        P = (1 - K) * P
        x, P = a * x, a**2 * P + q
    return z
"""
            ),
        ),
        (
            "first sample dropped (off by one)",
            _q2(_Q2_RIGHT_LOOP.replace("    return z\n", "    return z[1:]\n")),
        ),
        (
            "right, but computed in float32",
            _q2(_Q2_RIGHT_LOOP)
            .replace("dtype=float)", "dtype=np.float32)")
            .replace("float(m0), float(p0)", "np.float32(m0), np.float32(p0)")
            .replace("np.empty(y.shape)", "np.empty(y.shape, dtype=np.float32)")
            .replace(
                "    for t, y_t",
                "    a, q, r = np.float32(a), np.float32(q), np.float32(r)\n    for t, y_t",
            ),
        ),
    ],
    "q3": [
        (
            "right, but computed in float32",
            _Q3_HEAD.replace("dtype=float", "dtype=np.float32")
            + "    return np.convolve(z**2, np.ones(L, dtype=np.float32), mode='valid')\n",
        ),
        (
            "sums of z, not of z^2",
            _Q3_HEAD + "    c = np.concatenate([[0.0], np.cumsum(z)])\n    return c[L:] - c[:-L]\n",
        ),
        (
            "window means (1/L)",
            _Q3_HEAD
            + "    c = np.concatenate([[0.0], np.cumsum(z**2)])\n    return (c[L:] - c[:-L]) / L\n",
        ),
        (
            "N - L windows (last one missing)",
            _Q3_HEAD
            + "    return np.array([np.sum(z[k:k + L] ** 2) for k in range(len(z) - L)])\n",
        ),
        (
            "N values with partial windows at the start",
            _Q3_HEAD
            + "    c = np.cumsum(z**2)\n    return c - np.concatenate([np.zeros(L), c[:-L]])\n",
        ),
    ],
    "q4": [
        ("lower tail chi2.ppf(alpha)", _Q4.format("stats.chi2.ppf(alpha, L)")),
        ("two-sided alpha/2", _Q4.format("stats.chi2.isf(alpha / 2, L)")),
        ("L - 1 degrees of freedom", _Q4.format("stats.chi2.isf(alpha, L - 1)")),
        ("alpha / 100 (a percentage)", _Q4.format("stats.chi2.isf(alpha / 100, L)")),
        ("normal approximation", _Q4.format("L + stats.norm.isf(alpha) * np.sqrt(2 * L)")),
        ("divided by L (mean scale)", _Q4.format("stats.chi2.isf(alpha, L) / L")),
        ("the public case hard-wired", _Q4.format("stats.chi2.isf(0.001, 10)")),
    ],
    "q5_practice": [
        (
            "L - 1 degrees of freedom",
            _Q5P_T
            + "    thr = stats.chi2.isf(alpha, L - 1)\n"
            + f"    return thr, {_FIRST.format(T='T_practice', thr='thr')}\n",
        ),
        (
            "window-start index",
            _Q5P_T
            + "    thr = stats.chi2.isf(alpha, L)\n"
            + f"    return thr, {_FIRST.format(T='T_practice', thr='thr')} - (L - 1)\n",
        ),
        (
            "two-sided alpha/2",
            _Q5P_T
            + "    thr = stats.chi2.isf(alpha / 2, L)\n"
            + f"    return thr, {_FIRST.format(T='T_practice', thr='thr')}\n",
        ),
        (
            "1-based sample number",
            _Q5P_T
            + "    thr = stats.chi2.isf(alpha, L)\n"
            + f"    return thr, {_FIRST.format(T='T_practice', thr='thr')} + 1\n",
        ),
        (
            "the practice record's window and alpha whatever the record",
            _Q5P_T.replace('record["window"], record["alpha"]', "10, 0.001")
            + "    thr = stats.chi2.isf(alpha, L)\n"
            + f"    return thr, {_FIRST.format(T='T_practice', thr='thr')}\n",
        ),
        (
            "the fault onset instead of the alarm",
            "def find_alarm(record):\n"
            "    return stats.chi2.isf(record['alpha'], record['window']), t_fault_practice\n",
        ),
    ],
    "q5": [
        (
            "L - 1 degrees of freedom",
            _Q5_T
            + "thr = stats.chi2.isf(alpha, L - 1)\n"
            + f"alarm = (thr, {_FIRST.format(T='T_mine', thr='thr')})",
        ),
        (
            "the practice record's window and alpha instead of mine",
            _Q5_T.replace('mine["window"], mine["alpha"]', "10, 0.001")
            + "thr = stats.chi2.isf(alpha, L)\n"
            + f"alarm = (thr, {_FIRST.format(T='T_mine', thr='thr')})",
        ),
        (
            "window-start index",
            _Q5_T
            + "thr = stats.chi2.isf(alpha, L)\n"
            + f"alarm = (thr, {_FIRST.format(T='T_mine', thr='thr')} - (L - 1))",
        ),
        ("the demo student's answer hard-coded", f"alarm = {DEMO_ALARM}"),
        ("the practice answer hard-coded", "alarm = (29.58829844507442, 121)"),
        (
            "one-sided mix-up: alpha/2",
            _Q5_T
            + "thr = stats.chi2.isf(alpha / 2, L)\n"
            + f"alarm = (thr, {_FIRST.format(T='T_mine', thr='thr')})",
        ),
    ],
    "q6": [
        (
            "threshold with L - 1 degrees of freedom",
            _Q6_HEAD
            + "    alarm = T > stats.chi2.isf(alpha, L - 1)\n"
            + "    return float(np.mean(alarm[:, -1])), float(np.mean(alarm.any(axis=1)))\n",
        ),
        (
            "counts of runs, not fractions",
            _Q6_HEAD
            + "    alarm = T > stats.chi2.isf(alpha, L)\n"
            + "    return int(np.sum(alarm[:, -1])), int(np.sum(alarm.any(axis=1)))\n",
        ),
        (
            "rates swapped",
            _Q6_HEAD
            + "    alarm = T > stats.chi2.isf(alpha, L)\n"
            + "    return float(np.mean(alarm.any(axis=1))), float(np.mean(alarm[:, -1]))\n",
        ),
        (
            "any-window rate over all windows (mean, not any)",
            _Q6_HEAD
            + "    alarm = T > stats.chi2.isf(alpha, L)\n"
            + "    return float(np.mean(alarm[:, -1])), float(np.mean(alarm))\n",
        ),
        (
            "unnormalised innovations (z * sqrt(S))",
            _Q6_HEAD.replace(".normalized_innovations()[..., 0]", ".innovations[..., 0]")
            + "    alarm = T > stats.chi2.isf(alpha, L)\n"
            + "    return float(np.mean(alarm[:, -1])), float(np.mean(alarm.any(axis=1)))\n",
        ),
    ],
    "q7": [
        (
            "counts over the whole record (after the fault too)",
            _Q7_HEAD + "false_alarms = tuple(int(np.sum(T7[qb] > thr7)) for qb in (0.0, 1e-4))",
        ),
        (
            "order swapped",
            _Q7_HEAD
            + "false_alarms = tuple(int(np.sum(T7[qb][:t_fault7] > thr7)) for qb in (1e-4, 0.0))",
        ),
        (
            "threshold with L - 1 degrees of freedom",
            _Q7_HEAD.replace("nis.windowed_nis_threshold(10, 0.001)", "stats.chi2.isf(0.001, 9)")
            + "false_alarms = tuple(int(np.sum(T7[qb][:t_fault7] > thr7)) for qb in (0.0, 1e-4))",
        ),
        (
            "windows that start before the fault",
            _Q7_HEAD + "false_alarms = tuple(int(np.sum(T7[qb][:t_fault7 + 9] > thr7)) "
            "for qb in (0.0, 1e-4))",
        ),
        ("the demo student's counts hard-coded", f"false_alarms = {DEMO_COUNTS}"),
    ],
    "q7_practice": [
        (
            "counts over the whole record (after the fault too)",
            _Q7P + "    return tuple(int(np.sum(T7[qb] > thr7)) for qb in (0.0, 1e-4))\n",
        ),
        (
            "order swapped",
            _Q7P + "    return tuple(int(np.sum(T7[qb][:t_f] > thr7)) for qb in (1e-4, 0.0))\n",
        ),
        (
            "threshold with L - 1 degrees of freedom",
            _Q7P.replace("nis.windowed_nis_threshold(L, alpha)", "stats.chi2.isf(alpha, L - 1)")
            + "    return tuple(int(np.sum(T7[qb][:t_f] > thr7)) for qb in (0.0, 1e-4))\n",
        ),
        (
            "the public record whatever the argument",
            _Q7P.replace('record["y"], record["u"]', "y7, u7")
            + "    return tuple(int(np.sum(T7[qb][:t_f] > thr7)) for qb in (0.0, 1e-4))\n",
        ),
        (
            "the public answer hard-coded",
            "def count_false_alarms(record):\n    return (14, 0)\n",
        ),
    ],
    "q8": [
        (
            "covariance update with a plus sign",
            _Q8_HEAD + "    return theta + K * (y - phi @ theta), P + np.outer(K, Pphi)\n",
        ),
        (
            "gain without dividing by S",
            _Q8_HEAD.replace("K = Pphi / S", "K = Pphi")
            + "    return theta + K * (y - phi @ theta), P - np.outer(K, Pphi)\n",
        ),
        (
            "S without r",
            _Q8_HEAD.replace("S = phi @ Pphi + r", "S = phi @ Pphi")
            + "    return theta + K * (y - phi @ theta), P - np.outer(K, Pphi)\n",
        ),
        (
            "old covariance returned",
            _Q8_HEAD + "    return theta + K * (y - phi @ theta), P\n",
        ),
        (
            "innovation sign flipped",
            _Q8_HEAD + "    return theta + K * (phi @ theta - y), P - np.outer(K, Pphi)\n",
        ),
    ],
}

RIGHT = {
    "q1": [
        (
            "iterate the recursion (list)",
            "def steady_state(q, r):\n    P = 1.0\n    for _ in range(500):\n"
            "        P = P - P**2 / (P + r) + q\n    return [P, P / (P + r)]\n",
        ),
        (
            "np.roots, numpy scalars, extra print",
            "def steady_state(q, r):\n    P = max(np.roots([1.0, -q, -q * r]))\n"
            "    print(P)\n    return (P, P / (P + r))\n",
        ),
    ],
    "q2": [
        (
            "short covariance update (1 - K) P, list output",
            _q2(
                _Q2_RIGHT_LOOP.replace("P = (1 - K) ** 2 * P + K**2 * r", "P = (1 - K) * P")
            ).replace("    return z\n", "    return list(z)\n"),
        ),
        (
            "information form P r / (P + r), **0.5",
            _q2(
                _Q2_RIGHT_LOOP.replace("P = (1 - K) ** 2 * P + K**2 * r", "P = P * r / (P + r)")
            ).replace("np.sqrt(S)", "S**0.5"),
        ),
    ],
    "q3": [
        (
            "Python loop",
            _Q3_HEAD
            + "    return np.array([sum(v * v for v in z[k:k + L]) for k in range(len(z) - L + 1)])\n",
        ),
        ("np.convolve", _Q3_HEAD + "    return np.convolve(z**2, np.ones(L), mode='valid')\n"),
        (
            "sliding_window_view",
            _Q3_HEAD + "    return np.lib.stride_tricks.sliding_window_view(z**2, L).sum(axis=1)\n",
        ),
    ],
    "q4": [
        ("ppf(1 - alpha)", _Q4.format("stats.chi2.ppf(1 - alpha, L)")),
        (
            "numpy scalar with a print",
            "def window_threshold(L, alpha):\n"
            "    c = np.float64(stats.chi2.isf(alpha, L))\n    print(round(c, 2))\n    return c\n",
        ),
    ],
    "q5_practice": [
        (
            "nis.windowed_nis_threshold and np.argmax, list",
            _Q5P_T
            + "    thr = nis.windowed_nis_threshold(L, alpha)\n"
            + "    return [thr, int(np.argmax(np.nan_to_num(T_practice) > thr))]\n",
        ),
        (
            "loop, numpy int",
            _Q5P_T
            + "    thr = stats.chi2.isf(alpha, L)\n"
            + "    first = next(t for t in range(len(T_practice)) if T_practice[t] > thr)\n"
            + "    return (thr, np.int64(first))\n",
        ),
    ],
    "q5": [
        (
            "nis.windowed_nis_threshold and np.argmax",
            _Q5_T
            + "thr = nis.windowed_nis_threshold(L, alpha)\n"
            + "alarm = (thr, int(np.argmax(np.nan_to_num(T_mine) > thr)))",
        ),
        (
            "loop with a print, numpy int",
            _Q5_T
            + "thr = stats.chi2.ppf(1 - alpha, L)\n"
            + "first = next(t for t in range(len(T_mine)) if T_mine[t] > thr)\n"
            + "print('first alarm at', first)\n"
            + "alarm = [thr, np.int64(first)]",
        ),
    ],
    "q6": [
        (
            "own vectorised filter, noise drawn up front",
            """def false_alarm_rates(a, q, r, N, L, alpha, n_runs, seed):
    rng = np.random.default_rng(seed)
    x0, w, v = rng.standard_normal(n_runs), rng.standard_normal((N, n_runs)), rng.standard_normal((N, n_runs))
    xs, xh, P = x0, np.zeros(n_runs), 1.0
    z2 = np.empty((N, n_runs))
    for t in range(N):
        y = xs + np.sqrt(r) * v[t]
        S = P + r
        z2[t] = (y - xh) ** 2 / S
        K = P / S
        xh = a * (xh + K * (y - xh))
        P = a**2 * (1 - K) * P + q
        xs = a * xs + np.sqrt(q) * w[t]
    T = np.lib.stride_tricks.sliding_window_view(z2, L, axis=0).sum(axis=-1)
    alarm = T > stats.chi2.isf(alpha, L)
    return float(alarm[-1].mean()), float(alarm.any(axis=0).mean())
""",
        ),
    ],
    "q7": [
        (
            "np.count_nonzero with errstate, list",
            """counts = []
for q_beta in (0.0, 1e-4):
    m7 = dg.beta_drift_model(Ts=0.1, q_beta=q_beta, q_x=1e-4, r=2.5e-3, x0_mean=(1.0, 0.5))
    T7 = nis.windowed_nis(kf.extended_kalman_filter(m7, mine7["y"], mine7["u"]), 10)
    with np.errstate(invalid="ignore"):
        counts.append(np.count_nonzero(T7[: mine7["t_fault"]] > stats.chi2.isf(0.001, 10)))
false_alarms = counts""",
        ),
    ],
    "q7_practice": [
        (
            "np.count_nonzero with errstate, a list",
            """def count_false_alarms(record):
    out = []
    for q_beta in (0.0, 1e-4):
        m = dg.beta_drift_model(Ts=record["Ts"], q_beta=q_beta, q_x=record["q_x"], r=record["r"],
                                x0_mean=(1.0, 0.5))
        T = nis.windowed_nis(kf.extended_kalman_filter(m, record["y"], record["u"]), record["window"])
        with np.errstate(invalid="ignore"):
            out.append(np.count_nonzero(T[: record["t_fault"]] > stats.chi2.isf(record["alpha"], record["window"])))
    return out
""",
        ),
    ],
    "q8": [
        (
            "short covariance form, lists",
            _Q8_HEAD
            + "    return list(theta + K * (y - phi @ theta)), (P - np.outer(K, Pphi)).tolist()\n",
        ),
        (
            "np.linalg.solve for the 1x1 S",
            """def rls_update(theta, P, phi, y, r):
    theta, P = np.asarray(theta, float), np.asarray(P, float)
    H = np.asarray(phi, float)[None, :]
    S = H @ P @ H.T + r
    K = np.linalg.solve(S, H @ P).T
    theta_new = theta + (K @ (np.atleast_1d(y) - H @ theta))
    P_new = P - K @ H @ P
    return theta_new, (P_new + P_new.T) / 2
""",
        ),
    ],
}

# q6 is graded by a seeded-sample identity (the prescribed draws give everyone the same runs):
# the value the test promises, a formula for dependent windows, or the same simulation with the
# draws in another order (another sample) must all lose the points.
_Q6_RATES = "    return float(np.mean(alarm[:, -1])), float(np.mean(alarm.any(axis=1)))\n"
WRONG["q6"] += [
    (
        "return alpha (the theoretical value of the last window)",
        _Q6_HEAD + "    alarm = T > stats.chi2.isf(alpha, L)\n"
        "    return alpha, float(np.mean(alarm.any(axis=1)))\n",
    ),
    (
        "theoretical values: alpha and 1 - (1 - alpha)^(windows)",
        """def false_alarm_rates(a, q, r, N, L, alpha, n_runs, seed):
    return alpha, 1 - (1 - alpha) ** (N - L + 1)
""",
    ),
    (
        "draws interleaved sample by sample (another sample than prescribed)",
        _Q6_HEAD.replace(
            """    W = rng.standard_normal((N, n_runs))
    V = rng.standard_normal((N, n_runs))
""",
            "",
        )
        .replace("np.sqrt(r) * V[t]", "np.sqrt(r) * rng.standard_normal(n_runs)")
        .replace("np.sqrt(q) * W[t]", "np.sqrt(q) * rng.standard_normal(n_runs)")
        + "    alarm = T > stats.chi2.isf(alpha, L)\n"
        + _Q6_RATES,
    ),
]
RIGHT["q6"] += [
    (
        "nis.windowed_nis on the library filter, a list",
        """def false_alarm_rates(a, q, r, N, L, alpha, n_runs, seed):
    rng = np.random.default_rng(seed)
    x0 = rng.standard_normal(n_runs)
    W = rng.standard_normal((N, n_runs))
    V = rng.standard_normal((N, n_runs))
    x = np.empty((N, n_runs))
    x[0] = x0
    for t in range(N - 1):
        x[t + 1] = a * x[t] + np.sqrt(q) * W[t]
    y = (x + np.sqrt(r) * V).T[..., None]
    model = kf.LinearModel(F=[[a]], H=[[1.0]], Q=[[q]], R=[[r]], x0_mean=[0.0], x0_cov=[[1.0]])
    T = nis.windowed_nis(kf.kalman_filter(model, y), L)[:, L - 1:]
    alarm = T > stats.chi2.isf(alpha, L)
    return [alarm[:, -1].mean(), alarm.any(axis=1).mean()]
""",
    ),
]

# q7_why: the cause of the false alarms of the student's own q7 record ("model" when only the
# constant-beta filter alarms, "noise" when both do); a fixed option is right for some of the
# class only (COINCIDES), a rule that ignores which filters alarm for none.
_CAUSE = {
    "threshold": 'false_alarm_cause = "threshold"',
    "fault": 'false_alarm_cause = "fault"',
    "model, always (the lecture's answer)": 'false_alarm_cause = "model"',
    "noise, always": 'false_alarm_cause = "noise"',
    "the cause read backwards": 'false_alarm_cause = "model" if false_alarms[1] >= 5 else "noise"',
}
WRONG["q7_why"] = list(_CAUSE.items())
RIGHT["q7_why"] = [
    (
        "capitals and spaces, by comparing the counts",
        'false_alarm_cause = " Noise " if false_alarms[1] > false_alarms[0] / 4 else " Model "',
    )
]


def _cause_coincides(option):
    def same(checks, student):
        d = checks.data_for("drift", student)
        return checks.questions["q7_why"].reference(d) == option

    return same


COINCIDES = {
    ("q7_why", "model, always (the lecture's answer)"): _cause_coincides("model"),
    ("q7_why", "noise, always"): _cause_coincides("noise"),
}
WRONG["q1"] += [  # a one-line library answer is on the list now (issue 26)
    (
        "kf.steady_state (not allowed)",
        "def steady_state(q, r):\n"
        "    ss = kf.steady_state(kf.LinearModel(F=[[1.0]], H=[[1.0]], Q=[[q]], R=[[r]]))\n"
        "    return (float(ss.P_pred[0, 0]), float(ss.K[0, 0]))\n",
    ),
]

WRONG["q4"] += [  # a one-line library answer is on the list now (issue 26)
    (
        "nis.windowed_nis_threshold (not allowed)",
        _Q4.format("nis.windowed_nis_threshold(L, alpha)"),
    ),
]

# Forbidden functions (issue 26): a call by any path loses the points (an alias, getattr,
# __import__, functools.partial, a private twin, a call in an added cell for a value);
# an import alone, a call another question allows, and an inverse (advice) cost nothing.
WRONG["q2"] += [
    (
        "kalman_filter imported under another name",
        """from course.filters import kalman_filter as f


def normalized_innovations(y, a, q, r, m0, p0):
    model = kf.LinearModel(F=[[a]], H=[[1.0]], Q=[[q]], R=[[r]], x0_mean=[m0], x0_cov=[[p0]])
    out = f(model, np.asarray(y, dtype=float)[:, None])
    return np.asarray(out.eps)[:, 0] / np.sqrt(np.asarray(out.S)[:, 0, 0])
""",
    ),
    (
        "the module under another name (import course.filters as cf)",
        """import course.filters as cf


def normalized_innovations(y, a, q, r, m0, p0):
    model = cf.LinearModel(F=[[a]], H=[[1.0]], Q=[[q]], R=[[r]], x0_mean=[m0], x0_cov=[[p0]])
    out = cf.kalman_filter(model, np.asarray(y, dtype=float)[:, None])
    return np.asarray(out.eps)[:, 0] / np.sqrt(np.asarray(out.S)[:, 0, 0])
""",
    ),
]
WRONG["q3"] += [
    (
        "windowed_sum imported under another name",
        """from course.nis import windowed_sum as ws


def windowed_statistic(z, L):
    return ws(np.asarray(z, dtype=float) ** 2, L)[L - 1 :]
""",
    ),
]
WRONG["q8"] += [
    (
        "kf_update imported under another name",
        """from course.filters import kf_update as f


def rls_update(theta, P, phi, y, r):
    out = f(np.asarray(theta, float), np.asarray(P, float), np.atleast_1d(y),
            np.asarray(phi, float)[None, :], np.array([[r]]))
    return out[0], out[1]
""",
    ),
    (
        "the private twin course.filters._steps._kf_update (2/2 before)",
        """from course.filters._steps import _kf_update


def rls_update(theta, P, phi, y, r):
    out = _kf_update(np.asarray(theta, float), np.asarray(P, float), np.atleast_1d(y),
                     np.asarray(phi, float)[None, :], np.array([[r]]))
    return out[0], out[1]
""",
    ),
    (
        "getattr(kf, 'kf_update')",
        """def rls_update(theta, P, phi, y, r):
    step = getattr(kf, "kf_" + "update")
    out = step(np.asarray(theta, float), np.asarray(P, float), np.atleast_1d(y),
               np.asarray(phi, float)[None, :], np.array([[r]]))
    return out[0], out[1]
""",
    ),
]
RIGHT["q2"] += [
    (
        "the right loop, compared with kalman_filter in a cell added below (scratch)",
        """def normalized_innovations(y, a, q, r, m0, p0):
    y = np.asarray(y, dtype=float)
    x, P = float(m0), float(p0)
    z = np.empty(y.shape)
    for t, y_t in enumerate(y):
        S = P + r
        K = P / S
        eps = y_t - x
        z[t] = eps / np.sqrt(S)
        x = x + K * eps
        P = (1 - K) ** 2 * P + K**2 * r
        x, P = a * x, a**2 * P + q
    return z
# %% added cell
_model = kf.LinearModel(F=[[0.9]], H=[[1.0]], Q=[[0.5]], R=[[1.0]], x0_mean=[0.0], x0_cov=[[1.0]])
_y = np.linspace(-1.0, 1.0, 7)
_out = kf.kalman_filter(_model, _y[:, None])
print(np.allclose(normalized_innovations(_y, 0.9, 0.5, 1.0, 0.0, 1.0),
                  np.asarray(_out.eps)[:, 0] / np.sqrt(np.asarray(_out.S)[:, 0, 0])))
""",
    ),
    (
        "the right loop, with kalman_filter imported and never called",
        """from course.filters import kalman_filter  # noqa: F401


def normalized_innovations(y, a, q, r, m0, p0):
    y = np.asarray(y, dtype=float)
    x, P = float(m0), float(p0)
    z = np.empty(y.shape)
    for t, y_t in enumerate(y):
        S = P + r
        K = P / S
        eps = y_t - x
        z[t] = eps / np.sqrt(S)
        x = x + K * eps
        P = (1 - K) ** 2 * P + K**2 * r
        x, P = a * x, a**2 * P + q
    return z
""",
    ),
]
RIGHT["q8"] += [
    (
        "np.linalg.inv(S) (advice, not a rule)",
        """def rls_update(theta, P, phi, y, r):
    theta, P = np.asarray(theta, float), np.asarray(P, float)
    H = np.asarray(phi, float)[None, :]
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + r)
    P_new = P - K @ H @ P
    return theta + K @ (np.atleast_1d(y) - H @ theta), (P_new + P_new.T) / 2
""",
    ),
]
