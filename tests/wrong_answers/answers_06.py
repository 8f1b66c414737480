"""Wrong and right answers of assignment 06_mismatched_filters (data for tests/test_wrong_answers.py).

WRONG[q]: answers a class would plausibly write; each must lose points at grading.
RIGHT[q]: correct answers written differently; each must keep full marks.
Each source replaces the whole answer cell of q in the solution notebook (format: see the
docstring of tests/test_wrong_answers.py).
"""

ASSIGNMENT = "06_mismatched_filters"
STUDENT = "wa06"
DEPENDS = {"q2": ["q1"], "q7": ["q5"], "q6_which": ["q6"]}
MANUAL = ["q6_why"]

# The demo student's personal answers and the practice answer, hard-coded.
DEMO_PVALUES = "(0.00017178774037778847, 0.3205080201016515)"
PRACTICE_PVALUES = "(0.7518761254761387, 0.2778886525507667)"

_Q1 = """def augmented_matrices(F0, H0, F1, H1, K):
    F0, H0, F1, H1, K = (np.asarray(a, dtype=float) for a in (F0, H0, F1, H1, K))
    n0, n1 = F0.shape[0], F1.shape[0]
    F_tilde = np.zeros((n0 + n1, n0 + n1))
    F_tilde[:n0, :n0] = F0
"""
_Q1_LL = "    F_tilde[n0:, :n0] = F1 @ K @ H0\n"
_Q1_LR = "    F_tilde[n0:, n0:] = F1 @ (np.eye(n1) - K @ H1)\n"
_Q1_END = "    return F_tilde, np.hstack([H0, -H1])\n"

_Q2 = """def residual_covariances(F0, G0, Q0, H0, R0, Psi0, F1, H1, K):
    F0, G0, Q0, H0, R0, Psi0, F1, H1, K = (np.asarray(a, dtype=float)
                                           for a in (F0, G0, Q0, H0, R0, Psi0, F1, H1, K))
    n0, n1 = F0.shape[0], F1.shape[0]
    N, p = K.shape[0], H0.shape[0]
    Psi = np.zeros((n0 + n1, n0 + n1))
    Psi[:n0, :n0] = Psi0
    P = np.empty((N, p, p))
    for t in range(N):
        F_tilde, H_tilde = augmented_matrices(F0, H0, F1, H1, K[t])
"""
_Q2_RECORD = "        P[t] = H_tilde @ Psi @ H_tilde.T + R0\n"
_Q2_NOISE = """        FK = F1 @ K[t]
        noise = np.zeros_like(Psi)
        noise[:n0, :n0] = G0 @ Q0 @ G0.T
        noise[n0:, n0:] = FK @ R0 @ FK.T
"""
_Q2_STEP = "        Psi = F_tilde @ Psi @ F_tilde.T + noise\n"
_Q2_END = "    return P\n"

_Q4 = """def section_statistics(residuals, j, k):
    r = np.asarray(residuals, dtype=float)
    rbar_j = r[:, j].mean(axis=0)
    dj = r[:, j] - rbar_j
    dk = r[:, k] - r[:, k].mean(axis=0)
"""
_Q4_RIGHT = (
    "    return (float(rbar_j @ rbar_j), float(np.mean(np.sum(dj * dj, axis=1))),\n"
    "            float(np.mean(np.sum(dj * dk, axis=1))))\n"
)

_Q5 = "def covariance_critical_values(P, M, alpha):\n    P = np.asarray(P, dtype=float)\n"

# q6: the notebook's practice solution as a template (names replaced per variant).
_PV = """def two_sided_pvalues(r, mean, cov, cross_cov, j, k):
    M = r.shape[0]
    rbar = r[:, j].mean(axis=0)
    law_mean = QuadraticForm(np.eye(len(rbar)), mean[j], cov[j] / M)
    stat_mean = float(rbar @ rbar)
    p_mean = min(1.0, 2 * min(float(law_mean.cdf(stat_mean)), float(law_mean.sf(stat_mean))))
    S = np.block([[cov[j], cross_cov[j, k]], [cross_cov[j, k].T, cov[k]]])
    p = cov[j].shape[0]
    A = np.block([[np.zeros((p, p)), np.eye(p)], [np.eye(p), np.zeros((p, p))]]) / (2 * M)
    shape = QuadraticForm(A, cov=S)
    law_corr = WeightedChiSquare(shape.weights, dof=shape.dof * (M - 1))
    dj = r[:, j] - r[:, j].mean(axis=0)
    dk = r[:, k] - r[:, k].mean(axis=0)
    stat_corr = float(np.mean(np.sum(dj * dk, axis=1)))
    p_corr = min(1.0, 2 * min(float(law_corr.cdf(stat_corr)), float(law_corr.sf(stat_corr))))
    return (p_mean, p_corr)


"""
_CALL_PRACTICE = (
    "two_sided_pvalues(residuals_practice, np.array(null_practice.mean), "
    "np.array(null_practice.cov), np.array(null_practice.cross_cov), 4, 5)"
)
_CALL_MINE = 'two_sided_pvalues(exp["residuals"], exp["mean"], exp["cov"], exp["cross_cov"], exp["j"], exp["k"])'


def _pv(var: str, call: str, old: str = "", new: str = "", result: str = "") -> str:
    body = _PV.replace(old, new) if old else _PV
    return body + f"{var} = {result or call}\n"


_ONE_SIDED = (
    "p_mean = min(1.0, 2 * min(float(law_mean.cdf(stat_mean)), float(law_mean.sf(stat_mean))))",
    "p_mean = float(law_mean.sf(stat_mean))",
)
_NOT_OVER_M = ("cov[j] / M)", "cov[j])")
_DOF_M = ("dof=shape.dof * (M - 1)", "dof=shape.dof * M")
_CENTRAL = (
    "QuadraticForm(np.eye(len(rbar)), mean[j], cov[j] / M)",
    "QuadraticForm(np.eye(len(rbar)), cov=cov[j] / M)",
)

_Q3 = "def expected_c(P, M):\n    P = np.asarray(P, dtype=float)\n    return float({})\n"
_Q7 = """def power_cov(P0, P2, M, alpha):
    P0, P2 = np.asarray(P0, dtype=float), np.asarray(P2, dtype=float)
    law2 = WeightedChiSquare(np.linalg.eigvalsh(P2) / M, dof=M - 1.0)
"""

WRONG = {
    "q1": [
        (
            "the paper's H~ = [H0, H1]",
            _Q1 + _Q1_LL + _Q1_LR + "    return F_tilde, np.hstack([H0, H1])\n",
        ),
        (
            "filtered, not predicted: K H0 without F1",
            _Q1 + "    F_tilde[n0:, :n0] = K @ H0\n" + _Q1_LR + _Q1_END,
        ),
        (
            "lower-right block (I - K H1) F1",
            _Q1 + _Q1_LL + "    F_tilde[n0:, n0:] = (np.eye(n1) - K @ H1) @ F1\n" + _Q1_END,
        ),
        (
            "lower-right block F1 without (I - K H1)",
            _Q1 + _Q1_LL + "    F_tilde[n0:, n0:] = F1\n" + _Q1_END,
        ),
        (
            "sign of the lower-left block",
            _Q1 + "    F_tilde[n0:, :n0] = -F1 @ K @ H0\n" + _Q1_LR + _Q1_END,
        ),
    ],
    "q2": [
        (
            "no measurement noise through the gain",
            _Q2 + _Q2_RECORD + _Q2_NOISE.replace("FK @ R0 @ FK.T", "0.0") + _Q2_STEP + _Q2_END,
        ),
        (
            "recorded after propagating (off by one)",
            _Q2 + _Q2_NOISE + _Q2_STEP + _Q2_RECORD + _Q2_END,
        ),
        (
            "without + R0",
            _Q2 + _Q2_RECORD.replace(" + R0", "") + _Q2_NOISE + _Q2_STEP + _Q2_END,
        ),
        (
            "the first gain for every step",
            _Q2.replace("K[t])", "K[0])")
            + _Q2_RECORD
            + _Q2_NOISE.replace("K[t]", "K[0]")
            + _Q2_STEP
            + _Q2_END,
        ),
    ],
    "q3": [
        ("tr(P), no factor", _Q3.format("float(np.trace(P))")),
        ("M/(M - 1) instead of (M - 1)/M", _Q3.format("M / (M - 1) * np.trace(P)")),
        ("(M - 1)/M^2", _Q3.format("(M - 1) / M**2 * np.trace(P)")),
        ("one output only (P[0, 0])", _Q3.format("(M - 1) / M * P[0, 0]")),
        ("the public case hard-wired", _Q3.format("3 / 4 * 3.0")),
    ],
    "q4": [
        (
            "norm, not squared",
            _Q4
            + "    return (float(np.linalg.norm(rbar_j)), float(np.mean(np.sum(dj * dj, axis=1))),\n"
            + "            float(np.mean(np.sum(dj * dk, axis=1))))\n",
        ),
        (
            "divided by M - 1",
            _Q4
            + "    M = r.shape[0]\n"
            + "    return (float(rbar_j @ rbar_j), float(np.sum(dj * dj) / (M - 1)),\n"
            + "            float(np.sum(dj * dk) / (M - 1)))\n",
        ),
        (
            "sample means not subtracted",
            _Q4
            + "    return (float(rbar_j @ rbar_j), float(np.mean(np.sum(r[:, j] ** 2, axis=1))),\n"
            + "            float(np.mean(np.sum(r[:, j] * r[:, k], axis=1))))\n",
        ),
        (
            "averages over times (axis 1), not records",
            """def section_statistics(residuals, j, k):
    r = np.asarray(residuals, dtype=float)
    rbar_j = r[j].mean(axis=0)
    dj = r[j] - rbar_j
    dk = r[k] - r[k].mean(axis=0)
    return (float(rbar_j @ rbar_j), float(np.mean(np.sum(dj * dj, axis=1))),
            float(np.mean(np.sum(dj * dk, axis=1))))
""",
        ),
    ],
    "q5": [
        (
            "M degrees of freedom",
            _Q5
            + "    law = WeightedChiSquare(np.linalg.eigvalsh(P) / M, dof=M)\n"
            + "    return (float(law.ppf(alpha / 2)), float(law.isf(alpha / 2)))\n",
        ),
        (
            "weights eig(P), not divided by M",
            _Q5
            + "    law = WeightedChiSquare(np.linalg.eigvalsh(P), dof=M - 1.0)\n"
            + "    return (float(law.ppf(alpha / 2)), float(law.isf(alpha / 2)))\n",
        ),
        (
            "alpha not split",
            _Q5
            + "    law = WeightedChiSquare(np.linalg.eigvalsh(P) / M, dof=M - 1.0)\n"
            + "    return (float(law.ppf(alpha)), float(law.isf(alpha)))\n",
        ),
        (
            "weights diag(P), not eigenvalues",
            _Q5
            + "    law = WeightedChiSquare(np.diag(P) / M, dof=M - 1.0)\n"
            + "    return (float(law.ppf(alpha / 2)), float(law.isf(alpha / 2)))\n",
        ),
        (
            "scaled chi2 with the trace (ignores the weights)",
            _Q5
            + "    from scipy import stats\n"
            + "    law = stats.chi2(len(P) * (M - 1), scale=np.trace(P) / (len(P) * M))\n"
            + "    return (float(law.ppf(alpha / 2)), float(law.isf(alpha / 2)))\n",
        ),
    ],
    "q6_practice": [
        ("one-sided mean p-value", _PV.replace(*_ONE_SIDED)),
        ("covariance P_j, not P_j / M", _PV.replace(*_NOT_OVER_M)),
        ("M degrees of freedom", _PV.replace(*_DOF_M)),
        ("central law (mean m_j ignored)", _PV.replace(*_CENTRAL)),
        (
            "(p_corr, p_mean) order",
            _PV.replace("return (p_mean, p_corr)", "return (p_corr, p_mean)"),
        ),
        (
            "the practice sections 4 and 5 whatever j and k",
            _PV.replace(
                "(r, mean, cov, cross_cov, j, k):",
                "(r, mean, cov, cross_cov, j_, k_):\n    j, k = 4, 5",
            ),
        ),
    ],
    "q6": [
        ("the demo student's answer hard-coded", f"pvalues = {DEMO_PVALUES}"),
        ("the practice answer hard-coded", f"pvalues = {PRACTICE_PVALUES}"),
        ("one-sided mean p-value", _pv("pvalues", _CALL_MINE, *_ONE_SIDED)),
        ("covariance P_j, not P_j / M", _pv("pvalues", _CALL_MINE, *_NOT_OVER_M)),
        ("M degrees of freedom", _pv("pvalues", _CALL_MINE, *_DOF_M)),
        ("central law (mean m_j ignored)", _pv("pvalues", _CALL_MINE, *_CENTRAL)),
    ],
    "q6_which": [
        (
            "decision inverted (rejects when p > alpha)",
            "p_mean, p_corr = pvalues\n"
            'which_rejects = ["neither", "only the mean test", "only the correlation test", "both"][\n'
            '    int(p_mean > exp["alpha"]) + 2 * int(p_corr > exp["alpha"])]',
        ),
        ("the demo student's verdict hard-coded", 'which_rejects = "only the mean test"'),
    ],
    "q7": [
        (
            "one-sided: upper critical value at alpha only",
            _Q7
            + "    law0 = WeightedChiSquare(np.linalg.eigvalsh(P0) / M, dof=M - 1.0)\n"
            + "    return float(law2.sf(law0.isf(alpha)))\n",
        ),
        (
            "critical values from the alternative's law",
            _Q7
            + "    lower, upper = covariance_critical_values(P2, M, alpha)\n"
            + "    return float(law2.cdf(lower) + law2.sf(upper))\n",
        ),
        (
            "1 - power (the miss probability)",
            _Q7
            + "    lower, upper = covariance_critical_values(P0, M, alpha)\n"
            + "    return float(law2.cdf(upper) - law2.cdf(lower))\n",
        ),
        (
            "the alternative's law with M degrees of freedom",
            _Q7.replace("dof=M - 1.0", "dof=float(M)")
            + "    lower, upper = covariance_critical_values(P0, M, alpha)\n"
            + "    return float(law2.cdf(lower) + law2.sf(upper))\n",
        ),
        (
            "upper tail only",
            _Q7
            + "    lower, upper = covariance_critical_values(P0, M, alpha)\n"
            + "    return float(law2.sf(upper))\n",
        ),
        (
            "the public case's M = 20 hard-wired",
            _Q7.replace("/ M, dof=M - 1.0", "/ 20, dof=19.0")
            + "    lower, upper = covariance_critical_values(P0, 20, alpha)\n"
            + "    return float(law2.cdf(lower) + law2.sf(upper))\n",
        ),
    ],
}

RIGHT = {
    "q1": [
        (
            "np.block, lists in",
            """def augmented_matrices(F0, H0, F1, H1, K):
    F0, H0, F1, H1, K = (np.atleast_2d(np.array(a, dtype=float)) for a in (F0, H0, F1, H1, K))
    n1 = F1.shape[0]
    F_tilde = np.block([[F0, np.zeros((F0.shape[0], n1))],
                        [F1 @ K @ H0, F1 - F1 @ K @ H1]])
    return F_tilde, np.concatenate([H0, -H1], axis=1)
""",
        ),
    ],
    "q2": [
        (
            "scipy block_diag and G~ written out",
            """def residual_covariances(F0, G0, Q0, H0, R0, Psi0, F1, H1, K):
    from scipy.linalg import block_diag
    F0, G0, Q0, H0, R0, Psi0, F1, H1, K = (np.asarray(a, dtype=float)
                                           for a in (F0, G0, Q0, H0, R0, Psi0, F1, H1, K))
    n1 = F1.shape[0]
    Psi = block_diag(Psi0, np.zeros((n1, n1)))
    out = []
    for Kt in K:
        F_tilde, H_tilde = augmented_matrices(F0, H0, F1, H1, Kt)
        out.append(H_tilde @ Psi @ H_tilde.T + R0)
        G = block_diag(G0, F1 @ Kt)
        Psi = F_tilde @ Psi @ F_tilde.T + G @ block_diag(Q0, R0) @ G.T
    return np.array(out)
""",
        ),
    ],
    "q3": [
        (
            "sum of eigenvalues",
            "def expected_c(P, M):\n    return (M - 1) / M * float(np.sum(np.linalg.eigvalsh(P)))\n",
        ),
        (
            "plain float with a print",
            "def expected_c(P, M):\n    v = (M - 1) / M * sum(np.diag(P))\n    print(v)\n    return v\n",
        ),
    ],
    "q4": [
        (
            "einsum and a list",
            _Q4
            + "    M = r.shape[0]\n"
            + "    return [float(np.dot(rbar_j, rbar_j)), float(np.einsum('ip,ip->', dj, dj) / M),\n"
            + "            float(np.einsum('ip,ip->', dj, dk) / M)]\n",
        ),
        (
            "np.cov with bias=True",
            """def section_statistics(residuals, j, k):
    r = np.asarray(residuals, dtype=float)
    p = r.shape[2]
    C = np.atleast_2d(np.cov(np.hstack([r[:, j], r[:, k]]).T, bias=True))
    rbar_j = r[:, j].mean(axis=0)
    return (float(rbar_j @ rbar_j), float(np.trace(C[:p, :p])), float(np.trace(C[:p, p:])))
""",
        ),
    ],
    "q5": [
        (
            "ppf(1 - alpha/2), numpy floats",
            _Q5
            + "    law = WeightedChiSquare(np.linalg.eigvals(P).real / M, dof=M - 1)\n"
            + "    return (law.ppf(alpha / 2), law.ppf(1 - alpha / 2))\n",
        ),
    ],
    "q6_practice": [
        (
            "list with a print",
            _PV.replace(
                "return (p_mean, p_corr)", "print(p_mean, p_corr)\n    return [p_mean, p_corr]"
            ),
        ),
        (
            "cdf as 1 - sf",
            _PV.replace("float(law_corr.cdf(stat_corr))", "1.0 - float(law_corr.sf(stat_corr))"),
        ),
    ],
    "q6": [
        (
            "list with a print",
            _pv("pvalues", _CALL_MINE, result=f"list({_CALL_MINE})") + "print(pvalues)\n",
        ),
        (
            "cdf as 1 - sf",
            _pv(
                "pvalues",
                _CALL_MINE,
                "float(law_mean.cdf(stat_mean))",
                "1.0 - float(law_mean.sf(stat_mean))",
            ),
        ),
    ],
    "q6_which": [
        (
            "if/else",
            "p_mean, p_corr = pvalues\n"
            'a = exp["alpha"]\n'
            "if p_mean < a and p_corr < a:\n"
            '    which_rejects = "both"\n'
            "elif p_mean < a:\n"
            '    which_rejects = "Only the mean test"\n'
            "elif p_corr < a:\n"
            '    which_rejects = "only the correlation test"\n'
            "else:\n"
            '    which_rejects = "neither"',
        ),
    ],
    "q7": [
        (
            "1 - probability inside",
            _Q7.replace("dof=M - 1.0", "dof=M - 1")
            + "    lower, upper = covariance_critical_values(P0, M, alpha)\n"
            + "    return 1 - (law2.cdf(upper) - law2.cdf(lower))\n",
        ),
    ],
}

# Forbidden functions (issue 26): a call by any path loses the points (an alias, getattr,
# __import__, functools.partial, a private twin, a call in an added cell for a value);
# an import alone, a call another question allows, and an inverse (advice) cost nothing.
WRONG["q4"] += [
    (
        "covariance_statistic imported under another name",
        """from course.mismatched import correlation_statistic as cs
from course.mismatched import covariance_statistic as vs
from course.mismatched import mean_statistic as ms


def section_statistics(residuals, j, k):
    r = np.asarray(residuals, dtype=float)
    return float(ms(r, j)), float(vs(r, j)), float(cs(r, j, k))
""",
    ),
]
WRONG["q5"] += [
    (
        "course.results.critical_value (2/2 before)",
        """from course.results import critical_value


def covariance_critical_values(P, M, alpha):
    law = WeightedChiSquare(np.linalg.eigvalsh(np.asarray(P, dtype=float)) / M, dof=M - 1.0)
    lower, upper = critical_value(law, alpha, "two-sided")
    return float(lower), float(upper)
""",
    ),
]
# The private twin mismatched._statistic_law called INSIDE q6_practice's function: forbidden at
# self-check and at grading. It once showed 1/1 here because the suite packed it beside a q6
# variant that redefines two_sided_pvalues, and the grader calls the function as the notebook
# leaves it; the packing now keeps answers that rebind each other's names apart.
WRONG["q6_practice"] += [
    (
        "the private twin mismatched._statistic_law (1/1 before)",
        """from course.mismatched import ResidualMoments
from course.mismatched._quadratic_forms import _statistic_law


def two_sided_pvalues(r, mean, cov, cross_cov, j, k):
    null = ResidualMoments(mean, cov, cross_cov)
    M = r.shape[0]
    law_mean = _statistic_law(null, "mean", j, M, None, None, False, 1)
    law_corr = _statistic_law(null, "correlation", j, M, k, None, False, 1)
    rbar = r[:, j].mean(axis=0)
    stat_mean = float(rbar @ rbar)
    dj, dk = r[:, j] - r[:, j].mean(axis=0), r[:, k] - r[:, k].mean(axis=0)
    stat_corr = float(np.mean(np.sum(dj * dk, axis=1)))
    return tuple(
        min(1.0, 2 * min(float(law.cdf(s)), float(law.sf(s))))
        for law, s in ((law_mean, stat_mean), (law_corr, stat_corr))
    )
""",
    ),
]
WRONG["q7"] += [
    (
        "course.results.rejection_probability and critical_value (1/1 before)",
        """from course import results


def power_cov(P0, P2, M, alpha):
    law0 = WeightedChiSquare(np.linalg.eigvalsh(P0) / M, dof=M - 1.0)
    law2 = WeightedChiSquare(np.linalg.eigvalsh(P2) / M, dof=M - 1.0)
    return results.rejection_probability(
        law2, results.critical_value(law0, alpha, "two-sided"), "two-sided"
    )
""",
    ),
]
