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

_Q7_HEAD = """P0 = np.array([[1.5, 0.4], [0.4, 1.0]])
P2 = np.array([[2.2, 0.4], [0.4, 1.1]])
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
        ("tr(P), no factor", "expected_c = np.trace(np.array([[2.0, 0.5], [0.5, 1.0]]))"),
        ("M/(M - 1) instead of (M - 1)/M", "expected_c = 4 / 3 * 3.0"),
        ("(M - 1)/M^2", "expected_c = 3 / 16 * 3.0"),
        ("one output only (P[0, 0])", "expected_c = 3 / 4 * 2.0"),
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
        ("one-sided mean p-value", _pv("pvalues_practice", _CALL_PRACTICE, *_ONE_SIDED)),
        ("covariance P_j, not P_j / M", _pv("pvalues_practice", _CALL_PRACTICE, *_NOT_OVER_M)),
        ("M degrees of freedom", _pv("pvalues_practice", _CALL_PRACTICE, *_DOF_M)),
        ("central law (mean m_j ignored)", _pv("pvalues_practice", _CALL_PRACTICE, *_CENTRAL)),
        (
            "(p_corr, p_mean) order",
            _pv("pvalues_practice", _CALL_PRACTICE, result=f"{_CALL_PRACTICE}[::-1]"),
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
            _Q7_HEAD
            + "law0 = WeightedChiSquare(np.linalg.eigvalsh(P0) / 20, dof=19.0)\n"
            + "law2 = WeightedChiSquare(np.linalg.eigvalsh(P2) / 20, dof=19.0)\n"
            + "power_cov = float(law2.sf(law0.isf(0.05)))",
        ),
        (
            "critical values from the alternative's law",
            _Q7_HEAD
            + "lower, upper = covariance_critical_values(P2, 20, 0.05)\n"
            + "law2 = WeightedChiSquare(np.linalg.eigvalsh(P2) / 20, dof=19.0)\n"
            + "power_cov = float(law2.cdf(lower) + law2.sf(upper))",
        ),
        (
            "1 - power (the miss probability)",
            _Q7_HEAD
            + "lower, upper = covariance_critical_values(P0, 20, 0.05)\n"
            + "law2 = WeightedChiSquare(np.linalg.eigvalsh(P2) / 20, dof=19.0)\n"
            + "power_cov = float(law2.cdf(upper) - law2.cdf(lower))",
        ),
        (
            "the alternative's law with M degrees of freedom",
            _Q7_HEAD
            + "lower, upper = covariance_critical_values(P0, 20, 0.05)\n"
            + "law2 = WeightedChiSquare(np.linalg.eigvalsh(P2) / 20, dof=20.0)\n"
            + "power_cov = float(law2.cdf(lower) + law2.sf(upper))",
        ),
        (
            "upper tail only",
            _Q7_HEAD
            + "lower, upper = covariance_critical_values(P0, 20, 0.05)\n"
            + "law2 = WeightedChiSquare(np.linalg.eigvalsh(P2) / 20, dof=19.0)\n"
            + "power_cov = float(law2.sf(upper))",
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
            "expected_c = 0.75 * float(np.sum(np.linalg.eigvalsh([[2.0, 0.5], [0.5, 1.0]])))",
        ),
        ("plain float with a print", "expected_c = (4 - 1) / 4 * (2.0 + 1.0)\nprint(expected_c)"),
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
            _pv("pvalues_practice", _CALL_PRACTICE, result=f"list({_CALL_PRACTICE})")
            + "print(pvalues_practice)\n",
        ),
        (
            "cdf as 1 - sf",
            _pv(
                "pvalues_practice",
                _CALL_PRACTICE,
                "float(law_corr.cdf(stat_corr))",
                "1.0 - float(law_corr.sf(stat_corr))",
            ),
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
            _Q7_HEAD
            + "lower, upper = covariance_critical_values(P0, 20, 0.05)\n"
            + "law2 = WeightedChiSquare(np.linalg.eigvalsh(P2) / 20, dof=19)\n"
            + "power_cov = 1 - (law2.cdf(upper) - law2.cdf(lower))",
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
WRONG["q6_practice"] += [
    (
        "the private twin mismatched._statistic_law (1/1 before)",
        """from course.mismatched._quadratic_forms import _statistic_law

r = residuals_practice
M = r.shape[0]
law_mean = _statistic_law(null_practice, "mean", 4, M, None, None, False, 1)
law_corr = _statistic_law(null_practice, "correlation", 4, M, 5, None, False, 1)
rbar = r[:, 4].mean(axis=0)
stat_mean = float(rbar @ rbar)
dj, dk = r[:, 4] - r[:, 4].mean(axis=0), r[:, 5] - r[:, 5].mean(axis=0)
stat_corr = float(np.mean(np.sum(dj * dk, axis=1)))
pvalues_practice = tuple(
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

P0 = np.array([[1.5, 0.4], [0.4, 1.0]])
P2 = np.array([[2.2, 0.4], [0.4, 1.1]])
law0 = WeightedChiSquare(np.linalg.eigvalsh(P0) / 20, dof=19.0)
law2 = WeightedChiSquare(np.linalg.eigvalsh(P2) / 20, dof=19.0)
power_cov = results.rejection_probability(
    law2, results.critical_value(law0, 0.05, "two-sided"), "two-sided"
)
""",
    ),
]
