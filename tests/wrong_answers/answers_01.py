"""Wrong and right answers of assignment 01_least_squares (data for tests/test_wrong_answers.py).

WRONG[q]: answers a class would plausibly write; each must lose points at grading.
RIGHT[q]: correct answers written differently; each must keep full marks.
Each source replaces the whole answer cell of q in the solution notebook (format: see the
docstring of tests/test_wrong_answers.py).
"""

ASSIGNMENT = "01_least_squares"
STUDENT = "wa01"
DEPENDS = {"q6": ["q3"], "q6_practice": ["q3"], "q6b": ["q6"]}

# The demo student's personal answers, as a student copying them from a classmate's screen
# (or from the solution run as "demo") would hard-code them.
DEMO_T = "22.57078379203652"
DEMO_SUSPECT = "6"

_Q3_HEAD = """def overall_model_test_stat(A, y, Qyy, alpha):
    A = np.asarray(A, dtype=float)
    y = np.asarray(y, dtype=float)
    m, n = A.shape
"""
_Q3_WEIGHTED = """    L = np.linalg.cholesky(Qyy)
    A_w = linalg.solve_triangular(L, A, lower=True)
    y_w = linalg.solve_triangular(L, y, lower=True)
    x = np.linalg.lstsq(A_w, y_w, rcond=None)[0]
    T = float(np.sum((y_w - A_w @ x) ** 2))
"""
_Q4_HEAD = """def w_statistics(A, y, Qyy):
    A = np.asarray(A, dtype=float)
    y = np.asarray(y, dtype=float)
    Qyy = np.asarray(Qyy, dtype=float)
    W = np.linalg.inv(Qyy)
    Qxx = np.linalg.inv(A.T @ W @ A)
    e = y - A @ (Qxx @ A.T @ W @ y)
    Qee = Qyy - A @ Qxx @ A.T
"""
_Q5_HEAD = """def band_95(A, Qyy, a):
    A = np.asarray(A, dtype=float)
    W = np.linalg.inv(Qyy)
    s = float(np.sqrt(a @ np.linalg.inv(A.T @ W @ A) @ a))
"""
_Q8_HEAD = """def rejection_rate(A, Qyy, alpha, n_runs, seed, bias):
    rng = np.random.default_rng(seed)
    A = np.asarray(A, dtype=float)
    m, n = A.shape
    L = np.linalg.cholesky(Qyy)
"""
_Q8_SIM = """    Y = np.asarray(bias, dtype=float)[:, None] + L @ rng.standard_normal((n_runs, m)).T
    A_w = linalg.solve_triangular(L, A, lower=True)
    Y_w = linalg.solve_triangular(L, Y, lower=True)
    X = np.linalg.lstsq(A_w, Y_w, rcond=None)[0]
    T = np.sum((Y_w - A_w @ X) ** 2, axis=0)
"""

WRONG = {
    "q1": [
        (
            "(slope, intercept) order",
            "def line_estimate(t, y):\n    return np.polyfit(t, y, 1)",
        ),
        (
            "no intercept column",
            "def line_estimate(t, y):\n"
            "    return np.linalg.lstsq(np.asarray(t)[:, None], y, rcond=None)[0]",
        ),
        (
            "mean and zero slope",
            "def line_estimate(t, y):\n    return np.array([np.mean(y), 0.0])",
        ),
        (
            "the global A (length 4 only)",
            "def line_estimate(t, y):\n    return np.linalg.lstsq(A, y, rcond=None)[0]",
        ),
        (
            "hard-coded day-1 values",
            "def line_estimate(t, y):\n    return np.array([12.0, 3.0])",
        ),
    ],
    "q2": [
        (
            "sign: A x_hat - y",
            "def line_residuals(t, y):\n"
            "    A = np.column_stack([np.ones(len(t)), t])\n"
            "    return A @ np.linalg.lstsq(A, y, rcond=None)[0] - y",
        ),
        (
            "squared residuals",
            "def line_residuals(t, y):\n"
            "    A = np.column_stack([np.ones(len(t)), t])\n"
            "    return (y - A @ np.linalg.lstsq(A, y, rcond=None)[0]) ** 2",
        ),
        (
            "sorted residuals",
            "def line_residuals(t, y):\n"
            "    A = np.column_stack([np.ones(len(t)), t])\n"
            "    return np.sort(y - A @ np.linalg.lstsq(A, y, rcond=None)[0])",
        ),
        (
            "day 1's estimate on any data",
            "def line_residuals(t, y):\n"
            "    A = np.column_stack([np.ones(len(t)), t])\n"
            "    return y - A @ np.linalg.lstsq(A, y_day1, rcond=None)[0]",
        ),
        (
            "hard-coded day-2 residuals",
            "def line_residuals(t, y):\n"
            "    return y_day2 - A @ np.linalg.lstsq(A, y_day2, rcond=None)[0]",
        ),
    ],
    "q3": [
        (
            "Qyy ignored (unweighted T)",
            _Q3_HEAD
            + """    x = np.linalg.lstsq(A, y, rcond=None)[0]
    T = float(np.sum((y - A @ x) ** 2))
    c = float(stats.chi2.isf(alpha, m - n))
    return T, c, T > c
""",
        ),
        (
            "dof m instead of m - n",
            _Q3_HEAD
            + _Q3_WEIGHTED
            + "    c = float(stats.chi2.isf(alpha, m))\n    return T, c, T > c\n",
        ),
        (
            "two-sided: alpha / 2",
            _Q3_HEAD
            + _Q3_WEIGHTED
            + "    c = float(stats.chi2.isf(alpha / 2, m - n))\n    return T, c, T > c\n",
        ),
        (
            "T / (m - n) (the variance factor)",
            _Q3_HEAD
            + _Q3_WEIGHTED
            + "    T = T / (m - n)\n    c = float(stats.chi2.isf(alpha, m - n))\n    return T, c, T > c\n",
        ),
        (
            "public answers hard-coded",
            """def overall_model_test_stat(A, y, Qyy, alpha):
    if np.asarray(y)[0] == 14.0:
        return 6.0, 9.21034, False
    return 216.0, 9.21034, True
""",
        ),
    ],
    "q4": [
        ("sigma of y instead of sigma of e", _Q4_HEAD + "    return e / np.sqrt(np.diag(Qyy))\n"),
        ("sign flipped", _Q4_HEAD + "    return -(W @ e) / np.sqrt(np.diag(W @ Qee @ W))\n"),
        (
            "e_i / sigma_ei also for a correlated Qyy",
            _Q4_HEAD + "    return e / np.sqrt(np.diag(Qee))\n",
        ),
    ],
    "q5": [
        (
            "one-sided 95 %: norm.isf(0.05)",
            _Q5_HEAD + "    return s, float(stats.norm.isf(0.05)) * s\n",
        ),
        (
            "variance instead of sigma",
            _Q5_HEAD + "    v = s**2\n    return v, float(stats.norm.isf(0.025)) * v\n",
        ),
        (
            "Qyy ignored: Qxx = (A^T A)^-1",
            """def band_95(A, Qyy, a):
    A = np.asarray(A, dtype=float)
    s = float(np.sqrt(a @ np.linalg.inv(A.T @ A) @ a))
    return s, float(stats.norm.isf(0.025)) * s
""",
        ),
        (
            "sigma of the observation (1)",
            "def band_95(A, Qyy, a):\n    return 1.0, float(stats.norm.isf(0.025))\n",
        ),
        (
            "unknowns swapped (a reversed)",
            _Q5_HEAD.replace("a @ np", "a[::-1] @ np").replace("@ a))", "@ a[::-1]))")
            + "    return s, float(stats.norm.isf(0.025)) * s\n",
        ),
        (
            "Student t with m - n dof instead of the normal",
            _Q5_HEAD + "    return s, float(stats.t.isf(0.025, A.shape[0] - A.shape[1])) * s\n",
        ),
        (
            "the day-1 answer hard-coded",
            "def band_95(A, Qyy, a):\n    return 0.5477226, 1.0735165\n",
        ),
    ],
    "q6": [
        (
            "unweighted T (Qyy ignored)",
            """x_mine = np.linalg.lstsq(mine["A"], mine["y"], rcond=None)[0]
T_mine = float(np.sum((mine["y"] - mine["A"] @ x_mine) ** 2))
""",
        ),
        (
            "divided by sigma instead of sigma^2",
            """fit_mine = lsq.fit(mine["A"], mine["y"], mine["Qyy"])
T_mine = float(np.sum(fit_mine.e_hat**2 / np.sqrt(np.diag(mine["Qyy"]))))
""",
        ),
        (
            "T / (m - n)",
            """T_mine, critical_mine, reject_mine = overall_model_test_stat(mine["A"], mine["y"], mine["Qyy"], mine["alpha"])
T_mine = T_mine / 10
""",
        ),
        ("the demo student's T hard-coded", "T_mine = " + DEMO_T),
    ],
    "q7": [
        (
            "1-based index",
            """snooping = lsq.data_snooping(lsq.fit(mine["A"], mine["y"], mine["Qyy"]), alpha=mine["alpha"])
suspect_mine = int(snooping.removed[0]) + 1
""",
        ),
        (
            "largest |e| instead of the largest |w|",
            """fit_mine = lsq.fit(mine["A"], mine["y"], mine["Qyy"])
suspect_mine = int(np.argmax(np.abs(fit_mine.e_hat)))
""",
        ),
        (
            "snooping without the weights",
            """snooping = lsq.data_snooping(lsq.fit(mine["A"], mine["y"], np.eye(len(mine["y"]))), alpha=mine["alpha"])
suspect_mine = int(snooping.removed[0])
""",
        ),
        (
            "largest |e_i / sigma_i| of the unweighted fit (not a w-test)",
            """x_u = np.linalg.lstsq(mine["A"], mine["y"], rcond=None)[0]
e_u = mine["y"] - mine["A"] @ x_u
suspect_mine = int(np.argmax(np.abs(e_u) / np.sqrt(np.diag(mine["Qyy"]))))
""",
        ),
        ("the demo student's index hard-coded", "suspect_mine = " + DEMO_SUSPECT),
    ],
    "q8": [
        (
            "returns alpha (the promise, not a simulation)",
            "def rejection_rate(A, Qyy, alpha, n_runs, seed, bias):\n    return float(alpha)\n",
        ),
        (
            "dof m instead of m - n",
            _Q8_HEAD + _Q8_SIM + "    return float(np.mean(T > stats.chi2.isf(alpha, m)))\n",
        ),
        (
            "bias forgotten",
            _Q8_HEAD
            + _Q8_SIM.replace("np.asarray(bias, dtype=float)[:, None] + ", "")
            + "    return float(np.mean(T > stats.chi2.isf(alpha, m - n)))\n",
        ),
        (
            "Qyy ignored in the test",
            _Q8_HEAD
            + """    Y = np.asarray(bias, dtype=float)[:, None] + L @ rng.standard_normal((n_runs, m)).T
    X = np.linalg.lstsq(A, Y, rcond=None)[0]
    T = np.sum((Y - A @ X) ** 2, axis=0)
    return float(np.mean(T > stats.chi2.isf(alpha, m - n)))
""",
        ),
        (
            "the exact probability (ncx2), not a simulation",
            """def rejection_rate(A, Qyy, alpha, n_runs, seed, bias):
    A = np.asarray(A, dtype=float)
    m, n = A.shape
    lam = lsq.fit(A, np.asarray(bias, dtype=float), Qyy).squared_norm
    c = stats.chi2.isf(alpha, m - n)
    return float(stats.ncx2.sf(c, m - n, lam)) if lam > 0 else float(alpha)
""",
        ),
        (
            "noise drawn as (m, n_runs): another random sample",
            _Q8_HEAD
            + _Q8_SIM.replace(
                "rng.standard_normal((n_runs, m)).T", "rng.standard_normal((m, n_runs))"
            )
            + "    return float(np.mean(T > stats.chi2.isf(alpha, m - n)))\n",
        ),
    ],
}

# q6b: the survey puts T within 1.35 of its critical value, so a wrong threshold flips the
# verdict of every rejected survey (the suite's students; ignoring Qyy flips the accepted ones,
# see tests/test_assignments_01_03.py) and a hard-coded verdict is right for half of the class.
_VERDICT = 'verdict_mine = "rejected" if T_mine > stats.chi2.isf({level}, {dof}) else "accepted"'
WRONG["q6b"] = [
    ("the decision read backwards", 'verdict_mine = "accepted" if reject_mine else "rejected"'),
    ("chi2 with m degrees of freedom", _VERDICT.format(level='mine["alpha"]', dof=12)),
    ("chi2 with m - 1 degrees of freedom", _VERDICT.format(level='mine["alpha"]', dof=11)),
    ("two-sided: alpha / 2", _VERDICT.format(level='mine["alpha"] / 2', dof=10)),
]
WRONG["q6_practice"] = [
    (
        "unweighted T (Qyy ignored)",
        """def survey_T(survey):
    x = np.linalg.lstsq(survey["A"], survey["y"], rcond=None)[0]
    return float(np.sum((survey["y"] - survey["A"] @ x) ** 2))
""",
    ),
    (
        "divided by sigma instead of sigma^2",
        """def survey_T(survey):
    f = lsq.fit(survey["A"], survey["y"], survey["Qyy"])
    return float(np.sum(f.e_hat**2 / np.sqrt(np.diag(survey["Qyy"]))))
""",
    ),
    (
        "diag(sigma) passed as Qyy",
        """def survey_T(survey):
    sigma = np.sqrt(np.diag(survey["Qyy"]))
    return float(lsq.fit(survey["A"], survey["y"], np.diag(sigma)).squared_norm)
""",
    ),
    (
        "the public survey's Qyy instead of the argument's",
        """def survey_T(survey):
    T, _, _ = overall_model_test_stat(survey["A"], survey["y"], Q_practice, survey["alpha"])
    return T
""",
    ),
    (
        "the practice answer hard-coded",
        """def survey_T(survey):
    T, _, _ = overall_model_test_stat(A_practice, y_practice, Q_practice, alpha_practice)
    return T
""",
    ),
]
WRONG["q7_practice"] = [
    (
        "1-based index",
        """def first_suspect(survey):
    s = lsq.data_snooping(lsq.fit(survey["A"], survey["y"], survey["Qyy"]), alpha=survey["alpha"])
    return int(s.removed[0]) + 1
""",
    ),
    (
        "largest |e| instead of the largest |w|",
        """def first_suspect(survey):
    return int(np.argmax(np.abs(lsq.fit(survey["A"], survey["y"], survey["Qyy"]).e_hat)))
""",
    ),
    (
        "snooping without the weights",
        """def first_suspect(survey):
    s = lsq.data_snooping(lsq.fit(survey["A"], survey["y"], np.eye(len(survey["y"]))), alpha=survey["alpha"])
    return int(s.removed[0])
""",
    ),
    (
        "largest |e_i / sigma_i| of the unweighted fit (not a w-test)",
        """def first_suspect(survey):
    x = np.linalg.lstsq(survey["A"], survey["y"], rcond=None)[0]
    e = survey["y"] - survey["A"] @ x
    return int(np.argmax(np.abs(e) / np.sqrt(np.diag(survey["Qyy"]))))
""",
    ),
]


def _verdict_coincides(level_factor: float, dof_minus: int):
    """A wrong threshold (alpha scaled, m - dof_minus degrees of freedom) gives the right verdict
    for the students whose T is on the same side of both thresholds (about half of them)."""

    def same(checks, student):
        from scipy import stats

        d = checks.data_for("survey", student)
        statistic = checks.questions["q6"].expected(data=d)
        wrong = statistic > stats.chi2.isf(d["alpha"] * level_factor, len(d["y"]) - dof_minus)
        return ("rejected" if wrong else "accepted") == checks.questions["q6b"].expected(data=d)

    return same


COINCIDES = {
    ("q6b", "chi2 with m degrees of freedom"): _verdict_coincides(1.0, 0),
    ("q6b", "chi2 with m - 1 degrees of freedom"): _verdict_coincides(1.0, 1),
    ("q6b", "two-sided: alpha / 2"): _verdict_coincides(0.5, 2),
}

RIGHT = {
    "q1": [
        (
            "lsq.fit, with a print",
            "def line_estimate(t, y):\n"
            "    x = lsq.fit(np.column_stack([np.ones(len(t)), t]), y).x_hat\n"
            "    print(x)\n"
            "    return x",
        ),
        (
            "normal equations, as a list",
            "def line_estimate(t, y):\n"
            "    A = np.column_stack([np.ones(len(t)), t])\n"
            "    return list(np.linalg.solve(A.T @ A, A.T @ np.asarray(y)))",
        ),
        ("polyfit reversed", "def line_estimate(t, y):\n    return np.polyfit(t, y, 1)[::-1]"),
    ],
    "q2": [
        (
            "lsq.fit",
            "def line_residuals(t, y):\n"
            "    return lsq.fit(np.column_stack([np.ones(len(t)), t]), y).e_hat",
        ),
        (
            "projector, as a list",
            "def line_residuals(t, y):\n"
            "    A = np.column_stack([np.ones(len(t)), t])\n"
            "    return list((np.eye(len(t)) - A @ np.linalg.pinv(A)) @ np.asarray(y))",
        ),
    ],
    "q3": [
        (
            "explicit inverse, list and numpy bool",
            _Q3_HEAD
            + """    W = np.linalg.inv(Qyy)
    x = np.linalg.solve(A.T @ W @ A, A.T @ W @ y)
    e = y - A @ x
    T = e @ W @ e
    c = stats.chi2.isf(alpha, m - n)
    return [T, c, np.bool_(T > c)]
""",
        ),
        (
            "cho_factor / cho_solve",
            _Q3_HEAD
            + """    cf = linalg.cho_factor(Qyy)
    N = A.T @ linalg.cho_solve(cf, A)
    x = np.linalg.solve(N, A.T @ linalg.cho_solve(cf, y))
    e = y - A @ x
    T = float(e @ linalg.cho_solve(cf, e))
    c = float(stats.chi2.ppf(1 - alpha, m - n))
    print("T =", round(T, 3))
    return T, c, bool(T > c)
""",
        ),
    ],
    "q4": [
        ("explicit inverses", _Q4_HEAD + "    return (W @ e) / np.sqrt(np.diag(W @ Qee @ W))\n"),
        (
            "as a list, via the redundancy matrix",
            _Q4_HEAD
            + "    R = W @ Qee @ W\n    return [float(v) for v in (W @ e) / np.sqrt(np.diag(R))]\n",
        ),
    ],
    "q5": [
        (
            "lsq.confidence_band",
            """def band_95(A, Qyy, a):
    f = lsq.fit(A, np.zeros(len(A)), Qyy)
    _, half = lsq.confidence_band(f, np.array([a]), level=0.95)
    return [float(np.sqrt(a @ f.Qxx @ a)), float(half[0])]
""",
        ),
        (
            "explicit inverses and norm.ppf(0.975)",
            """def band_95(A, Qyy, a):
    W = np.linalg.inv(Qyy)
    s = np.sqrt(a @ np.linalg.inv(A.T @ W @ A) @ a)
    return (s, stats.norm.ppf(0.975) * s)
""",
        ),
    ],
    "q6": [
        (
            "lsq",
            """T_mine = lsq.overall_model_test(lsq.fit(mine["A"], mine["y"], mine["Qyy"]), mine["alpha"]).statistic""",
        ),
        (
            "weights 1/sigma^2 by hand, numpy scalar",
            """w = 1 / np.diag(mine["Qyy"])
sw = np.sqrt(w)
x_mine = np.linalg.lstsq(mine["A"] * sw[:, None], mine["y"] * sw, rcond=None)[0]
T_mine = np.sum(w * (mine["y"] - mine["A"] @ x_mine) ** 2)
print(T_mine)
""",
        ),
    ],
    "q7": [
        (
            "largest |w| by hand (numpy int)",
            """Q = mine["Qyy"]
W = np.linalg.inv(Q)
Ai = mine["A"]
Qxx = np.linalg.inv(Ai.T @ W @ Ai)
e = mine["y"] - Ai @ (Qxx @ Ai.T @ W @ mine["y"])
w = (W @ e) / np.sqrt(np.diag(W @ (Q - Ai @ Qxx @ Ai.T) @ W))
suspect_mine = np.argmax(np.abs(w))
""",
        ),
        (
            "lsq.w_tests",
            """res = lsq.w_tests(lsq.fit(mine["A"], mine["y"], mine["Qyy"]), mine["alpha"])
suspect_mine = int(np.argmax(np.abs(res.statistic)))
""",
        ),
    ],
    "q8": [
        (
            "runs as rows, explicit projector",
            _Q8_HEAD
            + """    A_w = linalg.solve_triangular(L, A, lower=True)
    P = np.eye(m) - A_w @ np.linalg.pinv(A_w)
    Z = rng.standard_normal((n_runs, m))
    Y_w = linalg.solve_triangular(L, np.asarray(bias, dtype=float), lower=True) + Z
    R = Y_w @ P
    T = np.einsum("ij,ij->i", R, R)
    return np.mean(T > stats.chi2.isf(alpha, m - n))
""",
        ),
    ],
}
RIGHT["q6b"] = [
    (
        "own comparison, capitalised",
        'verdict_mine = "Rejected" if T_mine > stats.chi2.isf(mine["alpha"], 10) else "Accepted"',
    ),
]
RIGHT["q6_practice"] = [
    (
        "lsq",
        """def survey_T(survey):
    f = lsq.fit(survey["A"], survey["y"], survey["Qyy"])
    return lsq.overall_model_test(f, survey["alpha"]).statistic
""",
    ),
]
RIGHT["q7_practice"] = [
    (
        "largest |w| (numpy int)",
        """def first_suspect(survey):
    f = lsq.fit(survey["A"], survey["y"], survey["Qyy"])
    return np.argmax(np.abs(lsq.w_tests(f, survey["alpha"]).statistic))
""",
    ),
]

# q5's reference is a named tuple (sigma, half_width); a student's list, or a named tuple of
# their own with other field names, is as right as a plain tuple.
RIGHT["q5"] += [
    (
        "a list of numpy floats, by Cholesky",
        """def band_95(A, Qyy, a):
    L = np.linalg.cholesky(Qyy)
    Aw = linalg.solve_triangular(L, A, lower=True)
    s = np.sqrt(a @ np.linalg.solve(Aw.T @ Aw, a))
    return [s, stats.norm.isf(0.025) * s]
""",
    ),
    (
        "a named tuple of the student's own",
        """from collections import namedtuple
Band = namedtuple("Band", "sd hw")
def band_95(A, Qyy, a):
    f = lsq.fit(A, np.zeros(len(A)), Qyy)
    s = float(np.sqrt(a @ f.Qxx @ a))
    return Band(s, float(stats.norm.isf(0.025)) * s)
""",
    ),
]

# Forbidden functions (issue 26): a call by any path loses the points (an alias, getattr,
# __import__, functools.partial, a private twin, a call in an added cell for a value);
# an import alone, a call another question allows, and an inverse (advice) cost nothing.
WRONG["q3"] += [  # one variant only: more wrong q3 would move the q6b variants to other IDs
    (
        "diagnosis.least_squares_residual on the whitened problem",
        """from course import diagnosis


def overall_model_test_stat(A, y, Qyy, alpha):
    L = np.linalg.cholesky(Qyy)
    fit_w = diagnosis.least_squares_residual(
        linalg.solve_triangular(L, A, lower=True), linalg.solve_triangular(L, y, lower=True)
    )
    T = float(fit_w.statistic)
    critical_value = float(stats.chi2.isf(alpha, fit_w.dof))
    return T, critical_value, T > critical_value
""",
    ),
]
WRONG["q4"] += [
    (
        "aliased import of the forbidden functions",
        """from course.lsq import fit as f, w_tests as wt


def w_statistics(A, y, Qyy):
    return wt(f(A, y, Qyy), 0.05).statistic
""",
    ),
    (
        "getattr and __import__",
        """def w_statistics(A, y, Qyy):
    m = __import__("course.lsq", fromlist=["fit"])
    return getattr(m, "w_" + "tests")(m.fit(A, y, Qyy), 0.05).statistic
""",
    ),
    (
        "functools.partial of w_tests",
        """import functools

import course.lsq as cl


def w_statistics(A, y, Qyy):
    return functools.partial(cl.w_tests, alpha=0.05)(cl.fit(A, y, Qyy)).statistic
""",
    ),
]
RIGHT["q3"] += [
    (
        "the solution, with forbidden functions imported and never called",
        """from course.lsq import data_snooping, fit, overall_model_test  # noqa: F401 (never called)
import course.lsq as cl  # noqa: F401


def overall_model_test_stat(A, y, Qyy, alpha):
    A = np.asarray(A, dtype=float)
    y = np.asarray(y, dtype=float)
    L = np.linalg.cholesky(Qyy)
    A_w = linalg.solve_triangular(L, A, lower=True)
    y_w = linalg.solve_triangular(L, y, lower=True)
    x_hat = np.linalg.lstsq(A_w, y_w, rcond=None)[0]
    r = y_w - A_w @ x_hat
    T = float(r @ r)
    critical_value = float(stats.chi2.isf(alpha, A.shape[0] - A.shape[1]))
    return T, critical_value, T > critical_value
""",
    ),
    (
        "np.linalg.inv(Qyy) (advice, not a rule)",
        """def overall_model_test_stat(A, y, Qyy, alpha):
    A, y, W = np.asarray(A, float), np.asarray(y, float), np.linalg.inv(Qyy)
    x_hat = np.linalg.solve(A.T @ W @ A, A.T @ W @ y)
    e = y - A @ x_hat
    T = float(e @ W @ e)
    critical_value = float(stats.chi2.isf(alpha, A.shape[0] - A.shape[1]))
    return T, critical_value, T > critical_value
""",
    ),
]
