"""Wrong and right answers of assignment 02_test_quantities (data for tests/test_wrong_answers.py).

WRONG[q]: answers a class would plausibly write; each must lose points at grading.
RIGHT[q]: correct answers written differently; each must keep full marks.
Each source replaces the whole answer cell of q in the solution notebook (format: see the
docstring of tests/test_wrong_answers.py).
"""

ASSIGNMENT = "02_test_quantities"
STUDENT = "wa02"
DEPENDS = {
    "q7_practice": ["q4"],
    "q8_practice": ["q1", "q7_practice"],
    "q7": ["q7_practice"],
    "q8": ["q1", "q7", "q8a", "q8_practice"],
    "q8b": ["q8"],
}

# The demo student's T_mine, as a student copying a classmate's (or the demo's) output would
# hard-code it.
DEMO_T = "np.array([5.503664327062542, 0.44364052036632473, 5.0548576396959755])"

_T1 = """def T1_statistic(y, u1, u2, u3):
    y, u1, u2, u3 = (np.asarray(a, dtype=float) for a in (y, u1, u2, u3))
    target = y - u2 - u3
"""
_T_ALL = """def _T(U_, y_, k):
    others = [j for j in range(3) if j != k]
    target = y_ - U_[:, others].sum(axis=1)
    u = U_[:, k]
    r = target - u * (u @ target) / (u @ u)
    return float(r @ r)

"""
_HYP = """def hypotheses(sensitivity, modes, k):
    row = np.asarray(sensitivity)[k]
    return ([m for m, x in zip(modes, row) if {h0}], [m for m, x in zip(modes, row) if {h1}])
"""
_BF = """def bias_free_T(y, u):
    r = np.asarray(y, dtype=float) - np.asarray(u, dtype=float)
"""
_TP = """def threshold_and_power(U, sigma, theta2, alpha):
    U = np.asarray(U, dtype=float)
    n = U.shape[0]
    J = sigma**2 * stats.chi2.isf(alpha, n - 1)
    d = (theta2 - 1.0) * U[:, 1]
    d_perp = d - U[:, 0] * (U[:, 0] @ d) / (U[:, 0] @ U[:, 0])
    lam = (d_perp @ d_perp) / sigma**2
    return float(J), float(stats.ncx2.sf(J / sigma**2, n - 1, lam))
"""
_SFD = """def single_fault_diagnosis(U, y, sigma, alpha):
    J = sigma**2 * stats.chi2.isf({level}, {dof})
    return single_fault_diagnoses(LECTURE, MODES, three_statistics(U, y) > J)
"""
_Q9 = """def detection_rate(U, theta, sigma, alpha, n_runs, seed):
    rng = np.random.default_rng(seed)
    U = np.asarray(U, dtype=float)
    n = U.shape[0]
"""
_Q9_T = """    target = Y - U[:, 1] - U[:, 2]
    u = U[:, 0]
    R = target - np.outer(target @ u, u) / (u @ u)
    T = np.sum(R**2, axis=1)
"""

WRONG = {
    "q1": [
        (
            "an alarm keeps the modes with a 0 (inverted)",
            """def single_fault_diagnoses(sensitivity, modes, alarms):
    S = np.asarray(sensitivity, dtype=bool)
    a = np.asarray(alarms, dtype=bool)
    return [m for m, ok in zip(modes, np.all(~S[a], axis=0)) if ok]
""",
        ),
        (
            "a silent test also rules out its X modes",
            """def single_fault_diagnoses(sensitivity, modes, alarms):
    S = np.asarray(sensitivity, dtype=bool)
    a = np.asarray(alarms, dtype=bool)
    ok = np.all(S[a], axis=0) & ~np.any(S[~a], axis=0)
    return [m for m, keep in zip(modes, ok) if keep]
""",
        ),
        (
            "any alarmed row instead of every alarmed row",
            """def single_fault_diagnoses(sensitivity, modes, alarms):
    S = np.asarray(sensitivity, dtype=bool)
    a = np.asarray(alarms, dtype=bool)
    ok = np.any(S[a], axis=0) if a.any() else np.ones(len(modes), bool)
    return [m for m, keep in zip(modes, ok) if keep]
""",
        ),
        (
            "a boolean mask instead of the names",
            """def single_fault_diagnoses(sensitivity, modes, alarms):
    S = np.asarray(sensitivity, dtype=bool)
    return np.all(S[np.asarray(alarms, dtype=bool)], axis=0)
""",
        ),
    ],
    "q2": [
        ("H0 and H1 swapped", _HYP.format(h0="x != 0", h1="x == 0")),
        ("NF forgotten in H0", _HYP.format(h0="x == 0 and m != 'NF'", h1="x != 0")),
        (
            "the next row read (T_k for row k)",
            _HYP.replace("[k]", "[k + 1 if k + 1 < len(sensitivity) else 0]").format(
                h0="x == 0", h1="x != 0"
            ),
        ),
        (
            "the public answer hard-coded",
            'def hypotheses(sensitivity, modes, k):\n    return (["NF", "F1", "F4"], ["F2", "F3"])\n',
        ),
    ],
    "q3": [
        (
            "u1 = 0 divides by zero (nan)",
            _T1
            + "    th = (target @ u1) / (u1 @ u1)\n    r = target - th * u1\n    return float(r @ r)\n",
        ),
        (
            "theta1 fixed at 1 (not minimised)",
            _T1 + "    r = target - u1\n    return float(r @ r)\n",
        ),
        (
            "divided by sigma^2",
            _T1
            + "    e = u1 @ u1\n    th = (target @ u1) / e if e > 0 else 0.0\n"
            + "    r = target - th * u1\n    return float(r @ r) / sigma**2\n",
        ),
        (
            "no u1 = 0 guard, nan turned into 0 afterwards",
            _T1
            + "    with np.errstate(invalid='ignore', divide='ignore'):\n"
            + "        th = (target @ u1) / (u1 @ u1)\n"
            + "    r = target - th * u1\n    return float(np.nan_to_num(r @ r))\n",
        ),
        (
            "u1 = 0 returns 0 (nothing to fit, nothing left)",
            _T1
            + "    if not np.any(u1):\n        return 0.0\n"
            + "    th = (target @ u1) / (u1 @ u1)\n    r = target - th * u1\n    return float(r @ r)\n",
        ),
        (
            "mean instead of sum",
            _T1
            + "    e = u1 @ u1\n    th = (target @ u1) / e if e > 0 else 0.0\n"
            + "    return float(np.mean((target - th * u1) ** 2))\n",
        ),
        (
            "ratio upside down",
            _T1
            + "    e = target @ u1\n    th = (u1 @ u1) / e if e != 0 else 0.0\n"
            + "    r = target - th * u1\n    return float(r @ r)\n",
        ),
    ],
    "q4": [
        (
            "dof = N - number of columns (rank ignored)",
            """def regression_residual(Phi, Y):
    Phi = np.asarray(Phi, dtype=float)
    Y = np.asarray(Y, dtype=float)
    theta = np.linalg.lstsq(Phi, Y, rcond=None)[0]
    r = Y - Phi @ theta
    return float(r @ r), Phi.shape[0] - Phi.shape[1]
""",
        ),
        (
            "normal equations with pinv, dof N - rank - 1",
            """def regression_residual(Phi, Y):
    Phi = np.asarray(Phi, dtype=float)
    Y = np.asarray(Y, dtype=float)
    r = Y - Phi @ (np.linalg.pinv(Phi) @ Y)
    return float(r @ r), Phi.shape[0] - np.linalg.matrix_rank(Phi) - 1
""",
        ),
        (
            "returns the estimate's residual norm, not its square",
            """def regression_residual(Phi, Y):
    Phi = np.asarray(Phi, dtype=float)
    Y = np.asarray(Y, dtype=float)
    r = Y - Phi @ (np.linalg.pinv(Phi) @ Y)
    return float(np.linalg.norm(r)), Phi.shape[0] - np.linalg.matrix_rank(Phi)
""",
        ),
    ],
    "q5": [
        (
            "sum instead of mean (1/N forgotten)",
            _BF + "    return float(np.sum((r - np.mean(r)) ** 2))\n",
        ),
        ("bias not removed", _BF + "    return float(np.mean(r**2))\n"),
        ("sample variance with 1/(N - 1)", _BF + "    return float(np.var(r, ddof=1))\n"),
        (
            "the notebook's record whatever the arguments",
            "def bias_free_T(y, u):\n    return float(np.var(y_gb - u_gb))\n",
        ),
    ],
    "q5b": [("no", 'bias_decoupled = "no"')],
    "q6": [
        ("dof N instead of N - 1", _TP.replace("n - 1", "n")),
        (
            "threshold not scaled by sigma^2",
            _TP.replace("J = sigma**2 * stats", "J = stats").replace("J / sigma**2", "J"),
        ),
        (
            "lambda without projecting out u1",
            _TP.replace("d - U[:, 0] * (U[:, 0] @ d) / (U[:, 0] @ U[:, 0])", "d"),
        ),
        ("alpha / 2", _TP.replace("isf(alpha,", "isf(alpha / 2,")),
        (
            "the context's u1, u2 and N instead of U's",
            _TP.replace("U[:, 0]", "u1")
            .replace("U[:, 1]", "u2")
            .replace("n = U.shape[0]", "n = N"),
        ),
    ],
    "q7_practice": [
        (
            "divided by sigma^2",
            _T_ALL
            + "def three_statistics(U, y):\n"
            + "    return np.array([_T(U, y, k) for k in range(3)]) / sigma**2\n",
        ),
        (
            "mean of squares, not the sum",
            _T_ALL
            + "def three_statistics(U, y):\n"
            + "    return np.array([_T(U, y, k) for k in range(3)]) / len(y)\n",
        ),
        (
            "all three gains fixed (no gain estimated)",
            "def three_statistics(U, y):\n    return np.array([float(np.sum((y - U.sum(axis=1)) ** 2))] * 3)\n",
        ),
        (
            "T_k estimates all three gains",
            """def three_statistics(U, y):
    r = y - U @ np.linalg.lstsq(U, y, rcond=None)[0]
    return np.array([r @ r] * 3)
""",
        ),
    ],
    "q8_practice": [
        ("chi2(N) instead of chi2(N - 1)", _SFD.format(level="alpha", dof="len(y)")),
        ("alpha / 2", _SFD.format(level="alpha / 2", dof="len(y) - 1")),
        (
            "the practice sigma 0.2 whatever the record",
            _SFD.format(level="alpha", dof="len(y) - 1").replace("sigma**2", "0.2**2"),
        ),
    ],
    "q7": [
        (
            "the practice record instead of mine",
            "T_mine = three_statistics(U, y_near)",
        ),
        (
            "tests in the wrong order (T3, T2, T1)",
            'T_mine = three_statistics(mine["U"], mine["y"])[::-1]',
        ),
        (
            "divided by sigma^2",
            'T_mine = three_statistics(mine["U"], mine["y"]) / mine["sigma"] ** 2',
        ),
        ("the demo student's T hard-coded", "T_mine = " + DEMO_T),
    ],
    "q8a": [
        (
            "chi2(N) instead of chi2(N - 1)",
            'J_mine = mine["sigma"] ** 2 * stats.chi2.isf(mine["alpha"], len(mine["y"]))',
        ),
        (
            "alpha / 2",
            'J_mine = mine["sigma"] ** 2 * stats.chi2.isf(mine["alpha"] / 2, len(mine["y"]) - 1)',
        ),
        ("not scaled by sigma^2", 'J_mine = stats.chi2.isf(mine["alpha"], len(mine["y"]) - 1)'),
        (
            "sigma instead of sigma^2",
            'J_mine = mine["sigma"] * stats.chi2.isf(mine["alpha"], len(mine["y"]) - 1)',
        ),
        (
            "the practice threshold (sigma = 0.2, alpha = 0.01)",
            "J_mine = 0.2**2 * stats.chi2.isf(0.01, N - 1)",
        ),
    ],
    "q8": [
        (
            "the modes whose tests alarm (rows read as columns)",
            "diagnosis_mine = [MODES[k + 1] for k in range(3) if T_mine[k] > J_mine]",
        ),
        (
            "the practice record's diagnosis",
            "diagnosis_mine = single_fault_diagnosis(U, y_near, 0.2, 0.01)",
        ),
    ],
    "q8b": [
        ("NF always", 'mode_mine = "NF"'),
        ("F1 (first fault, a guess)", 'mode_mine = "F1"'),
        ("no single fault fits, always", 'mode_mine = "no single fault fits"'),
        ("several faults fit, always", 'mode_mine = "several faults fit"'),
    ],
    "q9": [
        (
            "the exact power (formula, not a simulation)",
            """def detection_rate(U, theta, sigma, alpha, n_runs, seed):
    U = np.asarray(U, dtype=float)
    n = U.shape[0]
    d = U @ (np.asarray(theta, dtype=float) - 1.0)
    u = U[:, 0]
    d_perp = d - u * (u @ d) / (u @ u)
    lam = (d_perp @ d_perp) / sigma**2
    return float(stats.ncx2.sf(stats.chi2.isf(alpha, n - 1), n - 1, lam))
""",
        ),
        (
            "records in columns: another random sample",
            _Q9
            + "    Y = (U @ np.asarray(theta, dtype=float))[:, None] + sigma * rng.standard_normal((n, n_runs))\n"
            + "    Y = Y.T\n"
            + _Q9_T
            + "    return float(np.mean(T > sigma**2 * stats.chi2.isf(alpha, n - 1)))\n",
        ),
        (
            "dof N instead of N - 1",
            _Q9
            + "    Y = U @ np.asarray(theta, dtype=float) + sigma * rng.standard_normal((n_runs, n))\n"
            + _Q9_T
            + "    return float(np.mean(T > sigma**2 * stats.chi2.isf(alpha, n)))\n",
        ),
        (
            "threshold not scaled by sigma^2",
            _Q9
            + "    Y = U @ np.asarray(theta, dtype=float) + sigma * rng.standard_normal((n_runs, n))\n"
            + _Q9_T
            + "    return float(np.mean(T > stats.chi2.isf(alpha, n - 1)))\n",
        ),
        (
            "returns alpha",
            "def detection_rate(U, theta, sigma, alpha, n_runs, seed):\n    return alpha\n",
        ),
        (
            "the notebook's global N instead of U.shape[0]",
            _Q9.replace("    n = U.shape[0]\n", "    n = N\n")
            + "    Y = U @ np.asarray(theta, dtype=float) + sigma * rng.standard_normal((n_runs, n))\n"
            + _Q9_T
            + "    return float(np.mean(T > sigma**2 * stats.chi2.isf(alpha, n - 1)))\n",
        ),
        (
            "the global N in the threshold only",
            _Q9
            + "    Y = U @ np.asarray(theta, dtype=float) + sigma * rng.standard_normal((n_runs, n))\n"
            + _Q9_T
            + "    return float(np.mean(T > sigma**2 * stats.chi2.isf(alpha, N - 1)))\n",
        ),
    ],
}


def _practice_diagnosis_coincides(checks, student):
    """The practice record's diagnosis is right for the students whose own diagnosis is the
    same (tests/test_assignments_personal.py measures how many)."""
    d = checks.data_for("record", student)
    q = checks.questions["q8_practice"]
    practice = q.expected(q.public_cases[0])
    return checks.questions["q8"].expected(data=d) == practice


COINCIDES = {("q8", "the practice record's diagnosis"): _practice_diagnosis_coincides}

RIGHT = {
    "q1": [
        (
            "loops, as a tuple",
            """def single_fault_diagnoses(sensitivity, modes, alarms):
    out = []
    for j, m in enumerate(modes):
        if all(sensitivity[k][j] for k in range(len(alarms)) if alarms[k]):
            out.append(m)
    return tuple(out)
""",
        ),
    ],
    "q2": [
        (
            "tuples and a print",
            """def hypotheses(sensitivity, modes, k):
    h = (tuple(m for m, x in zip(modes, sensitivity[k]) if not x),
         tuple(m for m, x in zip(modes, sensitivity[k]) if x))
    print(h)
    return [list(h[0]), list(h[1])]
""",
        )
    ],
    "q3": [
        (
            "np.linalg.lstsq on one column",
            _T1
            + "    if not np.any(u1):\n        return float(target @ target)\n"
            + "    th = np.linalg.lstsq(u1[:, None], target, rcond=None)[0]\n"
            + "    return float(np.sum((target - u1 * th) ** 2))\n",
        ),
    ],
    "q4": [
        (
            "np.linalg.lstsq reports the rank",
            """def regression_residual(Phi, Y):
    Phi = np.asarray(Phi, dtype=float)
    Y = np.asarray(Y, dtype=float)
    theta, _, rank, _ = np.linalg.lstsq(Phi, Y, rcond=None)
    r = Y - Phi @ theta
    return [r @ r, np.int64(Phi.shape[0] - rank)]
""",
        ),
    ],
    "q5": [
        ("np.var (1/N)", "def bias_free_T(y, u):\n    return np.var(np.subtract(y, u))\n"),
    ],
    "q5b": [("Yes, with spaces and capitals", 'bias_decoupled = " Yes "')],
    "q6": [
        (
            "chi2.residual_threshold and a projector",
            """from course.chi2 import residual_threshold


def threshold_and_power(U, sigma, theta2, alpha):
    n = len(U)
    J = residual_threshold(n - 1, alpha, sigma=sigma)
    P = np.eye(n) - np.outer(U[:, 0], U[:, 0]) / (U[:, 0] @ U[:, 0])
    lam = np.sum((P @ ((theta2 - 1) * U[:, 1])) ** 2) / sigma**2
    return [J, stats.ncx2.sf(J / sigma**2, n - 1, lam)]
""",
        ),
    ],
    "q7_practice": [
        (
            "by hand, as a list",
            _T_ALL + "def three_statistics(U, y):\n    return [_T(U, y, k) for k in range(3)]\n",
        ),
    ],
    "q8_practice": [
        (
            "alarms by hand, as a tuple",
            """def single_fault_diagnosis(U, y, sigma, alpha):
    J_p = sigma**2 * stats.chi2.ppf(1 - alpha, len(y) - 1)
    alarms_p = [bool(T > J_p) for T in three_statistics(U, y)]
    return tuple(single_fault_diagnoses(LECTURE, MODES, alarms_p))
""",
        ),
    ],
    "q7": [
        (
            "by hand, as a list",
            _T_ALL + 'T_mine = [_T(mine["U"], mine["y"], k) for k in range(3)]\n',
        ),
    ],
    "q8a": [
        (
            "chi2.residual_threshold",
            "from course.chi2 import residual_threshold\n\n"
            'J_mine = residual_threshold(len(mine["y"]) - 1, mine["alpha"], sigma=mine["sigma"])',
        ),
    ],
    "q8": [
        (
            "self-contained, with a print",
            _T_ALL
            + """T_own = np.array([_T(mine["U"], mine["y"], k) for k in range(3)])
J_own = mine["sigma"] ** 2 * stats.chi2.isf(mine["alpha"], len(mine["y"]) - 1)
alarmed = LECTURE[T_own > J_own].astype(bool)
diagnosis_mine = [m for j, m in enumerate(MODES) if alarmed[:, j].all()]
print(diagnosis_mine)
""",
        ),
    ],
    "q8b": [
        (
            "from a dictionary",
            """conclusion = {0: "no single fault fits", 4: "no fault detected"}
if len(diagnosis_mine) == 1:
    conclusion[1] = diagnosis_mine[0]
mode_mine = conclusion.get(len(diagnosis_mine), "several faults fit")
""",
        ),
    ],
    "q9": [
        (
            "projector matrix, one matrix product",
            _Q9
            + """    from course.chi2 import residual_threshold

    E = rng.standard_normal((n_runs, n))
    u = U[:, 0]
    P = np.eye(n) - np.outer(u, u) / (u @ u)
    base = U @ np.asarray(theta, dtype=float) - U[:, 1] - U[:, 2]
    R = (base + sigma * E) @ P
    T = np.einsum("ij,ij->i", R, R)
    return np.mean(T > residual_threshold(n - 1, alpha, sigma=sigma))
""",
        ),
    ],
}

# Forbidden functions (issue 26): a call by any path loses the points (an alias, getattr,
# __import__, functools.partial, a private twin, a call in an added cell for a value);
# an import alone, a call another question allows, and an inverse (advice) cost nothing.
WRONG["q2"] += [
    (
        "DecisionStructure(...).hypotheses (not allowed)",
        """def hypotheses(sensitivity, modes, k):
    h = dg.DecisionStructure(np.asarray(sensitivity), modes=list(modes)).hypotheses(f"T{k + 1}")
    return (list(h.null), list(h.alternative))
""",
    ),
]
WRONG["q3"] += [
    (
        "linear_test_statistics in one line",
        """def T1_statistic(y, u1, u2, u3):
    U_ = np.column_stack([u1, u2, u3])
    return float(dg.linear_test_statistics(np.asarray(y, float)[None], U_, [1.0, 1.0, 1.0], [[0]])[0, 0])
""",
    ),
    (
        "least_squares_residual through an alias",
        """from course.diagnosis import least_squares_residual as lsr


def T1_statistic(y, u1, u2, u3):
    y, u1, u2, u3 = (np.asarray(a, dtype=float) for a in (y, u1, u2, u3))
    return float(lsr(u1[:, None], y - u2 - u3).statistic)
""",
    ),
]
WRONG["q7_practice"] += [
    (
        "prediction_error per test (not allowed)",
        """def three_statistics(U, y):
    return np.array(
        [float(dg.prediction_error(y, U, [1.0, 1.0, 1.0], [k]).statistic) for k in range(3)]
    )
""",
    ),
]
RIGHT["q3"] += [
    (
        "the solution, with the forbidden functions imported and never called",
        """from course.diagnosis import least_squares_residual, prediction_error  # noqa: F401


def T1_statistic(y, u1, u2, u3):
    y, u1, u2, u3 = (np.asarray(a, dtype=float) for a in (y, u1, u2, u3))
    target = y - u2 - u3
    energy = u1 @ u1
    theta1 = (target @ u1) / energy if energy > 0 else 0.0
    r = target - theta1 * u1
    return float(r @ r)
""",
    ),
]
WRONG["q5"] += [
    (
        "prediction_error with a constant regressor (not allowed)",
        """def bias_free_T(y, u):
    n = len(y)
    return float(
        dg.prediction_error(y, np.column_stack([u, np.ones(n)]), [1.0, 0.0], [1]).statistic
    ) / n
""",
    ),
]
