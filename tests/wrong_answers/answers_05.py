"""Wrong and right answers of assignment 05_nis_wishart (data for tests/test_wrong_answers.py).

WRONG[q]: answers a class would plausibly write; each must lose points at grading.
RIGHT[q]: correct answers written differently; each must keep full marks.
Each source replaces the whole answer cell of q in the solution notebook (format: see the
docstring of tests/test_wrong_answers.py).
"""

ASSIGNMENT = "05_nis_wishart"
STUDENT = "wa05"
DEPENDS = {
    "q5": ["q2"],
    "q6_practice": ["q1", "q2"],
    "q6": ["q1", "q2", "q5"],
    "q6_which": ["q1", "q2", "q5", "q6"],
}
MANUAL = ["q6_why"]

# The demo student's personal answers, as a student copying a classmate's screen would
# hard-code them.
DEMO_PVALUES = "(0.9038436160901426, 0.0005367395161279529)"
PRACTICE_PVALUES = "(0.8153062197833431, 0.00028331731260571296)"

_WHITEN = """    eps = np.asarray(eps, dtype=float)
    K, m = eps.shape
    B = np.linalg.cholesky(np.broadcast_to(np.asarray(S, dtype=float), (K, m, m)))
    z = np.linalg.solve(B, eps[:, :, None])[:, :, 0]
"""
_Q1 = "def nis_per_step(eps, S):\n"
_Q2 = "def nis_matrix(eps, S):\n"
_Q5 = """def matrix_test(eps, S, alpha):
    K, m = np.shape(eps)
    values = np.linalg.eigvalsh(nis_matrix(eps, S))
    lmin, lmax = float(values[0]), float(values[-1])
"""
_Q5_RIGHT_THRESHOLDS = """    lower = float(nis.extreme_eigenvalue(m, K, "min").ppf(alpha / 2))
    upper = float(nis.extreme_eigenvalue(m, K, "max").isf(alpha / 2))
"""
_Q5_DECIDE = "    return (lmin, lmax, bool(lmin < lower or lmax > upper))\n"

_P6 = """K, m = {eps}.shape
total = float(np.sum(nis_per_step({eps}, {S})))
values = np.linalg.eigvalsh(nis_matrix({eps}, {S}))
F_min = nis.extreme_eigenvalue(m, K, "min").cdf(values[0])
sf_max = nis.extreme_eigenvalue(m, K, "max").sf(values[-1])
p_matrix = float(min(1.0, 2 * min(F_min, sf_max)))
"""
_P6_NIS = (
    "p_nis = float(min(1.0, 2 * min(stats.chi2(m * K).cdf(total), stats.chi2(m * K).sf(total))))\n"
)
_MINE = _P6.format(eps='mine["eps"]', S='mine["S"]')

_EB = "def eps_bar_interval(m, K, alpha):\n    return ({lo}, {hi})\n"
_MT = "def matrix_thresholds(m, K, alpha):\n    return (float({lo}), float({hi}))\n"
_NI = "def nees_interval(n, N, alpha):\n    return ({lo}, {hi})\n"
_PV = """def nis_pvalues(eps, S):
    eps = np.asarray(eps, dtype=float)
    K, m = eps.shape
    total = float(np.sum(nis_per_step(eps, S)))
    values = np.linalg.eigvalsh(nis_matrix(eps, S))
    F_min = nis.extreme_eigenvalue(m, K, "min").cdf(values[0])
    sf_max = nis.extreme_eigenvalue(m, K, "max").sf(values[-1])
    p_matrix = float(min(1.0, 2 * min(F_min, sf_max)))
    p_nis = float(min(1.0, 2 * min(stats.chi2(m * K).cdf(total), stats.chi2(m * K).sf(total))))
"""

_Q7 = """def false_alarm_rate(m, K, alpha, n_runs, seed):
    rng = np.random.default_rng(seed)
    z = rng.standard_normal((n_runs, K, m))
    Pi = np.einsum("rki,rkj->rij", z, z) / K
    values = np.linalg.eigvalsh(Pi)
"""

WRONG = {
    "q1": [
        (
            "quadratic form with S, not its inverse",
            _Q1
            + "    eps = np.asarray(eps, float)\n"
            + "    S = np.broadcast_to(np.asarray(S, float), (len(eps),) + np.shape(S)[-2:])\n"
            + "    return np.einsum('ki,kij,kj->k', eps, S, eps)\n",
        ),
        (
            "upper factor: solve(B^T, eps)",
            _Q1
            + _WHITEN.replace("np.linalg.solve(B, ", "np.linalg.solve(np.swapaxes(B, -1, -2), ")
            + "    return np.sum(z * z, axis=1)\n",
        ),
        ("the sum over steps", _Q1 + _WHITEN + "    return float(np.sum(z * z))\n"),
        (
            "one S only (the first of a stack)",
            _Q1
            + "    eps = np.asarray(eps, float)\n"
            + "    S = np.asarray(S, float)\n"
            + "    B = np.linalg.cholesky(S if S.ndim == 2 else S[0])\n"
            + "    z = np.linalg.solve(B, eps.T).T\n"
            + "    return np.sum(z * z, axis=1)\n",
        ),
        (
            "one S only (a single Cholesky factor of the stack's mean)",
            _Q1
            + "    eps = np.asarray(eps, float)\n"
            + "    S = np.asarray(S, float).reshape(-1, eps.shape[1], eps.shape[1]).mean(axis=0)\n"
            + "    z = np.linalg.solve(np.linalg.cholesky(S), eps.T).T\n"
            + "    return np.sum(z * z, axis=1)\n",
        ),
        ("divided by m", _Q1 + _WHITEN + "    return np.sum(z * z, axis=1) / m\n"),
        (
            "diagonal of S only",
            _Q1
            + "    eps = np.asarray(eps, float)\n"
            + "    d = np.diagonal(np.broadcast_to(np.asarray(S, float), (len(eps),) + np.shape(S)[-2:]), axis1=1, axis2=2)\n"
            + "    return np.sum(eps**2 / d, axis=1)\n",
        ),
    ],
    "q2": [
        ("sum, not mean (factor K)", _Q2 + _WHITEN + "    return z.T @ z\n"),
        ("divided by K - 1", _Q2 + _WHITEN + "    return z.T @ z / (K - 1)\n"),
        ("not whitened", _Q2 + _WHITEN + "    return eps.T @ eps / K\n"),
        (
            "the symmetric square root of S (scipy.linalg.sqrtm)",
            _Q2
            + "    import scipy.linalg\n"
            + "    eps = np.asarray(eps, dtype=float)\n"
            + "    K, m = eps.shape\n"
            + "    S = np.broadcast_to(np.asarray(S, dtype=float), (K, m, m))\n"
            + "    z = np.stack([np.linalg.solve(scipy.linalg.sqrtm(S[k]).real, eps[k]) for k in range(K)])\n"
            + "    return z.T @ z / K\n",
        ),
        (
            "sum over steps, whitened (factor K)",
            _Q2 + _WHITEN + "    return np.einsum('ki,kj->ij', z, z)\n",
        ),
        (
            "one S only (the first of a stack)",
            _Q2
            + "    eps = np.asarray(eps, float)\n"
            + "    S = np.asarray(S, float)\n"
            + "    B = np.linalg.cholesky(S if S.ndim == 2 else S[0])\n"
            + "    z = np.linalg.solve(B, eps.T).T\n"
            + "    return z.T @ z / len(eps)\n",
        ),
        (
            "upper factor: B^-T eps",
            _Q2
            + _WHITEN.replace("np.linalg.solve(B, ", "np.linalg.solve(np.swapaxes(B, -1, -2), ")
            + "    return z.T @ z / K\n",
        ),
        ("outer products in the wrong order (K x K)", _Q2 + _WHITEN + "    return z @ z.T / K\n"),
    ],
    "q3": [
        (
            "the poster's law: chi2(mK) for eps_bar itself",
            _EB.format(
                lo="stats.chi2(m * K).ppf(alpha / 2)", hi="stats.chi2(m * K).isf(alpha / 2)"
            ),
        ),
        (
            "alpha not split (alpha in each tail)",
            _EB.format(
                lo="stats.chi2(m * K).ppf(alpha) / K", hi="stats.chi2(m * K).isf(alpha) / K"
            ),
        ),
        (
            "divided by m K",
            _EB.format(
                lo="stats.chi2(m * K).ppf(alpha / 2) / (m * K)",
                hi="stats.chi2(m * K).isf(alpha / 2) / (m * K)",
            ),
        ),
        (
            "dof m K - 1",
            _EB.format(
                lo="stats.chi2(m * K - 1).ppf(alpha / 2) / K",
                hi="stats.chi2(m * K - 1).isf(alpha / 2) / K",
            ),
        ),
        (
            "chi2(m) per step, divided by K",
            _EB.format(
                lo="stats.chi2(m).ppf(alpha / 2) / K", hi="stats.chi2(m).isf(alpha / 2) / K"
            ),
        ),
        (
            "the public case hard-wired (95 %, m K = 60)",
            _EB.format(lo="stats.chi2(60).ppf(0.025) / K", hi="stats.chi2(60).isf(0.025) / K"),
        ),
    ],
    "q4": [
        (
            "alpha not split",
            _MT.format(
                lo='nis.extreme_eigenvalue(m, K, "min").ppf(alpha)',
                hi='nis.extreme_eigenvalue(m, K, "max").isf(alpha)',
            ),
        ),
        (
            "both from the law of lambda_max",
            _MT.format(
                lo='nis.extreme_eigenvalue(m, K, "max").ppf(alpha / 2)',
                hi='nis.extreme_eigenvalue(m, K, "max").isf(alpha / 2)',
            ),
        ),
        (
            "laws swapped (lambda_max's for the lower, lambda_min's for the upper)",
            _MT.format(
                lo='nis.extreme_eigenvalue(m, K, "max").ppf(alpha / 2)',
                hi='nis.extreme_eigenvalue(m, K, "min").isf(alpha / 2)',
            ),
        ),
        (
            "chi2(m K)/K thresholds of the NIS test",
            _MT.format(
                lo="stats.chi2(m * K).ppf(alpha / 2) / K", hi="stats.chi2(m * K).isf(alpha / 2) / K"
            ),
        ),
        (
            "upper tail for the lower threshold",
            _MT.format(
                lo='nis.extreme_eigenvalue(m, K, "min").isf(alpha / 2)',
                hi='nis.extreme_eigenvalue(m, K, "max").isf(alpha / 2)',
            ),
        ),
        (
            "the public case hard-wired (m = 2, K = 30)",
            _MT.format(
                lo='nis.extreme_eigenvalue(2, 30, "min").ppf(alpha / 2)',
                hi='nis.extreme_eigenvalue(2, 30, "max").isf(alpha / 2)',
            ),
        ),
    ],
    "q5": [
        (
            "one-sided thresholds at alpha instead of alpha/2",
            _Q5 + _Q5_RIGHT_THRESHOLDS.replace("alpha / 2", "alpha") + _Q5_DECIDE,
        ),
        (
            "eigenvalues of K * Pi",
            _Q5.replace("nis_matrix(eps, S))", "K * nis_matrix(eps, S))")
            + _Q5_RIGHT_THRESHOLDS
            + _Q5_DECIDE,
        ),
        (
            "only the upper tail, at alpha",
            _Q5
            + '    upper = float(nis.extreme_eigenvalue(m, K, "max").isf(alpha))\n'
            + "    return (lmin, lmax, bool(lmax > upper))\n",
        ),
        (
            "m and K swapped",
            _Q5.replace("K, m = np.shape(eps)", "m, K = np.shape(eps)")
            + _Q5_RIGHT_THRESHOLDS
            + _Q5_DECIDE,
        ),
        (
            "(lmax, lmin) order",
            _Q5
            + _Q5_RIGHT_THRESHOLDS
            + "    return (lmax, lmin, bool(lmin < lower or lmax > upper))\n",
        ),
        ("never rejects", _Q5 + "    return (lmin, lmax, False)\n"),
        (
            "and instead of or",
            _Q5
            + _Q5_RIGHT_THRESHOLDS
            + "    return (lmin, lmax, bool(lmin < lower and lmax > upper))\n",
        ),
        ("always rejects", _Q5 + "    return (lmin, lmax, True)\n"),
        (
            "comparisons the wrong way round",
            _Q5
            + _Q5_RIGHT_THRESHOLDS
            + "    return (lmin, lmax, bool(lmin > lower or lmax < upper))\n",
        ),
        (
            "only the upper threshold, at alpha/2",
            _Q5 + _Q5_RIGHT_THRESHOLDS + "    return (lmin, lmax, bool(lmax > upper))\n",
        ),
        (
            "only the lower threshold, at alpha/2",
            _Q5 + _Q5_RIGHT_THRESHOLDS + "    return (lmin, lmax, bool(lmin < lower))\n",
        ),
        (
            "reject as the string 'reject'",
            _Q5
            + _Q5_RIGHT_THRESHOLDS
            + "    return (lmin, lmax, 'reject' if lmin < lower or lmax > upper else 'accept')\n",
        ),
    ],
    "q6_practice": [
        (
            "one-sided NIS p-value (sf)",
            _PV + "    return (float(stats.chi2(m * K).sf(total)), p_matrix)\n",
        ),
        (
            "chi2(mK) at the average, not the sum",
            _PV.replace("total = float(np.sum(", "total = float(np.mean(")
            + "    return (p_nis, p_matrix)\n",
        ),
        (
            "no factor 2 in p_matrix",
            _PV.replace("2 * min(F_min, sf_max)", "min(F_min, sf_max)")
            + "    return (p_nis, p_matrix)\n",
        ),
        ("(p_matrix, p_nis) order", _PV + "    return (p_matrix, p_nis)\n"),
        (
            "the practice answer hard-coded",
            f"def nis_pvalues(eps, S):\n    return {PRACTICE_PVALUES}\n",
        ),
    ],
    "q6": [
        ("the demo student's answer hard-coded", f"pvalues = {DEMO_PVALUES}"),
        ("the practice answer hard-coded", f"pvalues = {PRACTICE_PVALUES}"),
        (
            "one-sided NIS p-value (sf)",
            _MINE + "pvalues = (float(stats.chi2(m * K).sf(total)), p_matrix)",
        ),
        (
            "chi2(mK) at the average, not the sum",
            _MINE.replace("total = float(np.sum(", "total = float(np.mean(")
            + _P6_NIS
            + "pvalues = (p_nis, p_matrix)",
        ),
        ("(p_matrix, p_nis) order", _MINE + _P6_NIS + "pvalues = (p_matrix, p_nis)"),
    ],
    "q6_which": [
        (
            "decision inverted (rejects when p > alpha)",
            "p_nis, p_matrix = pvalues\n"
            'which_rejects = ["neither", "only the NIS test", "only the matrix test", "both"][\n'
            '    int(p_nis > mine["alpha"]) + 2 * int(p_matrix > mine["alpha"])]',
        ),
        # The demo student's verdict hard-coded is not listed: with four options it is the
        # right verdict for a share of the class, and a copied choice that happens to be
        # right cannot be told from a right one (q6 grades the p-values behind it).
    ],
    "q7": [
        ("the nominal alpha (no simulation)", _Q7 + "    return alpha\n"),
        (
            "one-sided thresholds at alpha",
            _Q7
            + "    lower, upper = nis.nis_matrix_critical_values(m, K, 2 * alpha)\n"
            + "    return float(np.mean((values[:, 0] < lower) | (values[:, -1] > upper)))\n",
        ),
        (
            "sum, not mean (factor K)",
            _Q7.replace(") / K\n", ")\n")
            + "    lower, upper = nis.nis_matrix_critical_values(m, K, alpha)\n"
            + "    return float(np.mean((values[:, 0] < lower) | (values[:, -1] > upper)))\n",
        ),
        (
            "only lambda_max tested",
            _Q7
            + "    lower, upper = nis.nis_matrix_critical_values(m, K, alpha)\n"
            + "    return float(np.mean(values[:, -1] > upper))\n",
        ),
        (
            "count of rejections, not the fraction",
            _Q7
            + "    lower, upper = nis.nis_matrix_critical_values(m, K, alpha)\n"
            + "    return int(np.sum((values[:, 0] < lower) | (values[:, -1] > upper)))\n",
        ),
    ],
    "q8": [
        (
            "chi2(n N) not divided by N",
            _NI.format(
                lo="stats.chi2(n * N).ppf(alpha / 2)", hi="stats.chi2(n * N).isf(alpha / 2)"
            ),
        ),
        (
            "normal approximation n +- 1.96 sqrt(2n/N)",
            _NI.format(lo="n - 1.96 * np.sqrt(2 * n / N)", hi="n + 1.96 * np.sqrt(2 * n / N)"),
        ),
        (
            "normal approximation with the exact z",
            _NI.format(
                lo="n - stats.norm.isf(alpha / 2) * np.sqrt(2 * n / N)",
                hi="n + stats.norm.isf(alpha / 2) * np.sqrt(2 * n / N)",
            ),
        ),
        (
            "chi2(n) of one run",
            _NI.format(lo="stats.chi2(n).ppf(alpha / 2)", hi="stats.chi2(n).isf(alpha / 2)"),
        ),
        (
            "divided by n N",
            _NI.format(
                lo="stats.chi2(n * N).ppf(alpha / 2) / (n * N)",
                hi="stats.chi2(n * N).isf(alpha / 2) / (n * N)",
            ),
        ),
        (
            "alpha not split",
            _NI.format(
                lo="stats.chi2(n * N).ppf(alpha) / N", hi="stats.chi2(n * N).isf(alpha) / N"
            ),
        ),
        (
            "dof n N - 1",
            _NI.format(
                lo="stats.chi2(n * N - 1).ppf(alpha / 2) / N",
                hi="stats.chi2(n * N - 1).isf(alpha / 2) / N",
            ),
        ),
    ],
}

RIGHT = {
    "q1": [
        (
            "np.linalg.solve with S, list",
            _Q1
            + "    eps = np.asarray(eps, float)\n"
            + "    S = np.broadcast_to(np.asarray(S, float), (len(eps),) + np.shape(S)[-2:])\n"
            + "    return [float(e @ np.linalg.solve(s, e)) for e, s in zip(eps, S)]\n",
        ),
        (
            "scipy cho_factor per step",
            _Q1
            + "    from scipy import linalg\n"
            + "    eps = np.asarray(eps, float)\n"
            + "    S = np.broadcast_to(np.asarray(S, float), (len(eps),) + np.shape(S)[-2:])\n"
            + "    out = np.empty(len(eps))\n"
            + "    for k in range(len(eps)):\n"
            + "        out[k] = eps[k] @ linalg.cho_solve(linalg.cho_factor(S[k]), eps[k])\n"
            + "    return out\n",
        ),
    ],
    "q2": [
        (
            "einsum of outer products",
            _Q2 + _WHITEN + "    return np.einsum('ki,kj->ij', z, z) / K\n",
        ),
        (
            "loop with solve_triangular",
            _Q2
            + "    from scipy import linalg\n"
            + "    eps = np.asarray(eps, float)\n"
            + "    K, m = eps.shape\n"
            + "    S = np.broadcast_to(np.asarray(S, float), (K, m, m))\n"
            + "    Pi = np.zeros((m, m))\n"
            + "    for k in range(K):\n"
            + "        z = linalg.solve_triangular(np.linalg.cholesky(S[k]), eps[k], lower=True)\n"
            + "        Pi += np.outer(z, z)\n"
            + "    return Pi / K\n",
        ),
    ],
    "q3": [
        (
            "chi2.interval",
            "def eps_bar_interval(m, K, alpha):\n"
            "    return tuple(np.array(stats.chi2(m * K).interval(1 - alpha)) / K)\n",
        ),
        (
            "the gamma law of eps_bar, list",
            "def eps_bar_interval(m, K, alpha):\n"
            "    law = stats.gamma(a=m * K / 2, scale=2 / K)\n"
            "    return [law.ppf(alpha / 2), law.ppf(1 - alpha / 2)]\n",
        ),
    ],
    "q4": [
        (
            "ppf(1 - alpha/2) for the upper one, list",
            "def matrix_thresholds(m, K, alpha):\n"
            '    return [nis.extreme_eigenvalue(m, K, "min").ppf(alpha / 2),\n'
            '            nis.extreme_eigenvalue(m, K, "max").ppf(1 - alpha / 2)]\n',
        ),
    ],
    "q5": [
        (
            "nis_matrix_critical_values and numpy types",
            "def matrix_test(eps, S, alpha):\n"
            + "    K, m = np.shape(eps)\n"
            + "    values = np.linalg.eigvalsh(nis_matrix(eps, S))\n"
            + "    lower, upper = nis.nis_matrix_critical_values(m, K, alpha)\n"
            + "    return (values[0], values[-1], np.bool_(values[0] < lower or values[-1] > upper))\n",
        ),
        (
            "sorted np.linalg.eigvals, list",
            _Q5.replace(
                "np.linalg.eigvalsh(nis_matrix(eps, S))",
                "np.sort(np.linalg.eigvals(nis_matrix(eps, S)).real)",
            )
            + _Q5_RIGHT_THRESHOLDS
            + "    return [lmin, lmax, lmin < lower or lmax > upper]\n",
        ),
    ],
    "q6_practice": [
        (
            "list with a print",
            _PV + "    print(p_nis, p_matrix)\n    return [p_nis, p_matrix]\n",
        ),
    ],
    "q6": [
        ("list with a print", _MINE + _P6_NIS + "pvalues = [p_nis, p_matrix]\nprint(pvalues)"),
    ],
    "q6_which": [
        (
            "if/else, other spacing and case",
            "p_nis, p_matrix = pvalues\n"
            'a = mine["alpha"]\n'
            "if p_nis < a and p_matrix < a:\n"
            '    which_rejects = "Both"\n'
            "elif p_nis < a:\n"
            '    which_rejects = " only the NIS test"\n'
            "elif p_matrix < a:\n"
            '    which_rejects = "only the matrix test "\n'
            "else:\n"
            '    which_rejects = "neither"',
        ),
    ],
    "q7": [
        (
            "draws of shape (K, n_runs, m), eigh",
            """def false_alarm_rate(m, K, alpha, n_runs, seed):
    rng = np.random.default_rng(seed)
    z = rng.standard_normal((K, n_runs, m))
    Pi = np.einsum("kri,krj->rij", z, z) / K
    values = np.linalg.eigh(Pi)[0]
    lower, upper = nis.nis_matrix_critical_values(m, K, alpha)
    inside = (values[:, 0] >= lower) & (values[:, -1] <= upper)
    return 1.0 - inside.mean()
""",
        ),
    ],
    "q8": [
        (
            "chi2.interval, list",
            "def nees_interval(n, N, alpha):\n"
            "    return list(np.array(stats.chi2(n * N).interval(1 - alpha)) / N)\n",
        ),
    ],
}

# q3's reference is a named tuple (lower, upper): a named tuple of the student's own with other
# field names is as right as a plain tuple or a list.
RIGHT["q3"] += [
    (
        "a named tuple of the student's own",
        """from collections import namedtuple
Iv = namedtuple("Iv", "lo hi")


def eps_bar_interval(m, K, alpha):
    return Iv(*(v / K for v in stats.chi2(m * K).interval(1 - alpha)))
""",
    ),
]

WRONG["q6_practice"] += [  # a one-line library answer is on the list now (issue 26)
    (
        "nis.nis_test and nis.nis_matrix_test (not allowed)",
        "def nis_pvalues(eps, S):\n"
        "    return (nis.nis_test(eps, S, 0.05).pvalue, nis.nis_matrix_test(eps, S, 0.05).pvalue)\n",
    ),
]

WRONG["q6"] += [  # a one-line library answer is on the list now (issue 26)
    (
        "nis.nis_test and nis.nis_matrix_test (not allowed)",
        'pvalues = (nis.nis_test(mine["eps"], mine["S"], mine["alpha"]).pvalue,\n'
        '           nis.nis_matrix_test(mine["eps"], mine["S"], mine["alpha"]).pvalue)',
    ),
]

# Forbidden functions (issue 26): a call by any path loses the points (an alias, getattr,
# __import__, functools.partial, a private twin, a call in an added cell for a value);
# an import alone, a call another question allows, and an inverse (advice) cost nothing.
WRONG["q1"] += [
    (
        "linalg.whitened_squared_norms (not allowed)",
        """from course import linalg as cl


def nis_per_step(eps, S):
    eps = np.asarray(eps, dtype=float)
    K, m = eps.shape
    B = np.linalg.cholesky(np.broadcast_to(np.asarray(S, dtype=float), (K, m, m)))
    return cl.whitened_squared_norms(B, eps)
""",
    ),
]
WRONG["q4"] += [
    (
        "nis_matrix_critical_values in a cell added at the end, numbers pasted (1/1 before)",
        """def matrix_thresholds(m, K, alpha):
    return (0.44949981369389597, 1.7796915167114988)  # pasted from the last cell
# %% added cell at the end
print(nis.nis_matrix_critical_values(2, 30, 0.05))
""",
    ),
    (
        "nis_matrix_test's critical values on any record",
        """def matrix_thresholds(m, K, alpha):
    r = nis.nis_matrix_test(np.ones((K, m)), np.eye(m), alpha)
    return (float(r.critical_value[0]), float(r.critical_value[1]))
""",
    ),
]
WRONG["q8"] += [
    (
        "nis_critical_values / N (not allowed)",
        """def nees_interval(n, N, alpha):
    lo, hi = nis.nis_critical_values(n, N, alpha)
    return (lo / N, hi / N)
""",
    ),
]
RIGHT["q4"] += [
    (
        "the solution, and nis.nis in an added cell (forbidden only in the function question q1)",
        """def matrix_thresholds(m, K, alpha):
    return (float(nis.extreme_eigenvalue(m, K, "min").ppf(alpha / 2)),
            float(nis.extreme_eigenvalue(m, K, "max").isf(alpha / 2)))
# %% added cell
print(nis.nis(np.ones((3, 2)), np.eye(2)))
""",
    ),
]
