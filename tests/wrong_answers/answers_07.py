"""Wrong and right answers of assignment 07_testing_theory (data for tests/test_wrong_answers.py).

WRONG[q]: answers a class would plausibly write; each must lose points at grading.
RIGHT[q]: correct answers written differently; each must keep full marks.
Each source replaces the whole answer cell of q in the solution notebook (format: see the
docstring of tests/test_wrong_answers.py).
"""

ASSIGNMENT = "07_testing_theory"
STUDENT = "wa07"
DEPENDS = {
    "q2": ["q1"],
    "q3": ["q1"],
    "q6_practice": ["q1"],
    "q6": ["q1"],
    "q7": ["q7_practice"],
}

_WHITEN = """    A = np.asarray(A, dtype=float)
    y = np.asarray(y, dtype=float)
    L = np.linalg.cholesky(Qyy)
    A_w = linalg.solve_triangular(L, A, lower=True)
    y_w = linalg.solve_triangular(L, y, lower=True)
    Q, _ = np.linalg.qr(A_w)
    e_w = y_w - Q @ (Q.T @ y_w)
"""
_Q1_HEAD = "def glr_statistic(A, y, Qyy, C):\n" + _WHITEN

# The textbook formula with explicit inverses: a right answer, if not good numerics.
_Q1_TEXTBOOK = """def glr_statistic(A, y, Qyy, C):
    A = np.asarray(A, dtype=float)
    y = np.asarray(y, dtype=float)
    C = np.asarray(C, dtype=float)
    W = np.linalg.inv(Qyy)
    Qxx = np.linalg.inv(A.T @ W @ A)
    e = y - A @ (Qxx @ A.T @ W @ y)
    Qee = Qyy - A @ Qxx @ A.T
    v = C.T @ W @ e
    return float(v @ np.linalg.solve(C.T @ W @ Qee @ W @ C, v))
"""

_Q4_HEAD = """def t_statistics(A, y, Qyy):
    A = np.asarray(A, dtype=float)
    y = np.asarray(y, dtype=float)
    m, n = A.shape
    W = np.linalg.inv(Qyy)
    Qxx = np.linalg.inv(A.T @ W @ A)
    e = y - A @ (Qxx @ A.T @ W @ y)
    Qee = Qyy - A @ Qxx @ A.T
    w = (W @ e) / np.sqrt(np.diag(W @ Qee @ W))
    omega = float(e @ W @ e)
"""

_Q9_HEAD = """def mdb_along(A, Qyy, C, alpha, power, direction):
    A = np.asarray(A, dtype=float)
    C = np.asarray(C, dtype=float)
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    W = np.linalg.inv(Qyy)
    Qxx = np.linalg.inv(A.T @ W @ A)
    Qee = Qyy - A @ Qxx @ A.T
"""

_DIA_BY = """def dia_estimate(d):
    fit = lsq.fit(d["A"], d["y"], d["Qyy"])
    T, reject = float(fit.squared_norm), bool(lsq.overall_model_test(fit, d["alpha"]).reject)
    if not reject:
        return T, reject, None, fit.x_hat
    suspect = int({suspect})
    keep = np.delete(np.arange(len(d["y"])), suspect)
    return T, reject, suspect, lsq.fit(d["A"][keep], d["y"][keep], {weights}).x_hat
"""
_RIGHT_DIA = _DIA_BY.format(
    suspect="lsq.w_tests(fit, d['alpha']).largest", weights='d["Qyy"][np.ix_(keep, keep)]'
)

WRONG = {
    "q1": [
        (
            "C not projected (C^T Qyy^-1 C in the middle)",
            _Q1_HEAD
            + """    C_w = linalg.solve_triangular(L, np.asarray(C, dtype=float), lower=True)
    v = C_w.T @ e_w
    return float(v @ np.linalg.solve(C_w.T @ C_w, v))
""",
        ),
        (
            "unweighted",
            """def glr_statistic(A, y, Qyy, C):
    A = np.asarray(A, dtype=float)
    y = np.asarray(y, dtype=float)
    C = np.asarray(C, dtype=float)
    Q, _ = np.linalg.qr(A)
    e = y - Q @ (Q.T @ y)
    C_bar = C - Q @ (Q.T @ C)
    Qc, _ = np.linalg.qr(C_bar)
    return float(np.sum((Qc.T @ e) ** 2))
""",
        ),
        ("the overall model test's T", _Q1_HEAD + "    return float(e_w @ e_w)\n"),
        (
            "notebook 3's linear_glr_test on the whitened extended model",
            """from course import diagnosis
def glr_statistic(A, y, Qyy, C):
    L = np.linalg.cholesky(Qyy)
    U = linalg.solve_triangular(L, np.column_stack([A, C]), lower=True)
    y_w = linalg.solve_triangular(L, np.asarray(y, dtype=float), lower=True)
    n = np.shape(A)[1]
    return diagnosis.linear_glr_test(y_w, U, np.zeros(U.shape[1]), range(n), sigma=1.0).statistic
""",
        ),
        (
            "the library's private modules",
            """from course.lsq import _alternatives, _fit
def glr_statistic(A, y, Qyy, C):
    f = _fit.fit(np.asarray(A, dtype=float), np.asarray(y, dtype=float), Qyy)
    return float(_alternatives.glr_test(f, C).statistic)
""",
        ),
        (
            "computed in float32",
            """def glr_statistic(A, y, Qyy, C):
    A = np.asarray(A, dtype=np.float32)
    y = np.asarray(y, dtype=np.float32)
    C = np.asarray(C, dtype=np.float32)
    L = np.linalg.cholesky(np.asarray(Qyy, dtype=np.float32))
    A_w = linalg.solve_triangular(L, A, lower=True)
    y_w = linalg.solve_triangular(L, y, lower=True)
    C_w = linalg.solve_triangular(L, C, lower=True)
    Q, _ = np.linalg.qr(A_w)
    Qc, _ = np.linalg.qr(C_w - Q @ (Q.T @ C_w))
    v = Qc.T @ (y_w - Q @ (Q.T @ y_w))
    return v @ v
""",
        ),
        (
            "whitened with the standard deviations only (diagonal of Qyy)",
            """def glr_statistic(A, y, Qyy, C):
    s = np.sqrt(np.diag(Qyy))
    A_w = np.asarray(A, dtype=float) / s[:, None]
    y_w = np.asarray(y, dtype=float) / s
    C_w = np.asarray(C, dtype=float) / s[:, None]
    Q, _ = np.linalg.qr(A_w)
    Qc, _ = np.linalg.qr(C_w - Q @ (Q.T @ C_w))
    return float(np.sum((Qc.T @ (y_w - Q @ (Q.T @ y_w))) ** 2))
""",
        ),
        (
            "w of the first column, not squared",
            _Q1_HEAD
            + """    C_w = linalg.solve_triangular(L, np.asarray(C, dtype=float), lower=True)
    c = C_w[:, 0] - Q @ (Q.T @ C_w[:, 0])
    return float(c @ e_w / np.linalg.norm(c))
""",
        ),
        (
            "residuals not whitened before projecting",
            _Q1_HEAD
            + """    C_w = linalg.solve_triangular(L, np.asarray(C, dtype=float), lower=True)
    C_bar = C_w - Q @ (Q.T @ C_w)
    Qc, _ = np.linalg.qr(C_bar)
    e = y - A @ np.linalg.lstsq(A_w, y_w, rcond=None)[0]
    return float(np.sum((Qc.T @ e) ** 2))
""",
        ),
    ],
    "q2": [
        (
            "chi2 with m - n degrees of freedom",
            """def glr_decision(A, y, Qyy, C, alpha):
    T = glr_statistic(A, y, Qyy, C)
    m, n = np.shape(A)
    critical_value = float(stats.chi2.isf(alpha, m - n))
    return T, critical_value, T > critical_value
""",
        ),
        (
            "one degree of freedom always",
            """def glr_decision(A, y, Qyy, C, alpha):
    T = glr_statistic(A, y, Qyy, C)
    critical_value = float(stats.chi2.isf(alpha, 1))
    return T, critical_value, T > critical_value
""",
        ),
        (
            "two-sided",
            """def glr_decision(A, y, Qyy, C, alpha):
    T = glr_statistic(A, y, Qyy, C)
    critical_value = float(stats.chi2.isf(alpha / 2, np.shape(C)[1]))
    return T, critical_value, T > critical_value
""",
        ),
        (
            "a list, and T compared with the level instead of the critical value",
            """def glr_decision(A, y, Qyy, C, alpha):
    T = glr_statistic(A, y, Qyy, C)
    critical_value = float(stats.chi2.isf(alpha, np.shape(C)[1]))
    return [T, critical_value, bool(stats.chi2.sf(T, np.shape(C)[1]) > alpha)]
""",
        ),
        (
            "ppf instead of isf",
            """def glr_decision(A, y, Qyy, C, alpha):
    T = glr_statistic(A, y, Qyy, C)
    critical_value = float(stats.chi2.ppf(alpha, np.shape(C)[1]))
    return T, critical_value, T > critical_value
""",
        ),
    ],
    "q3": [
        (
            "sigma² from the null model",
            """def f_test(A, y, Qyy, C, alpha):
    A = np.asarray(A, dtype=float)
    m, n = A.shape
    q = np.shape(C)[1]
    T = glr_statistic(A, y, Qyy, C)
    L = np.linalg.cholesky(Qyy)
    A_w = linalg.solve_triangular(L, A, lower=True)
    y_w = linalg.solve_triangular(L, np.asarray(y, dtype=float), lower=True)
    r = y_w - A_w @ np.linalg.lstsq(A_w, y_w, rcond=None)[0]
    F = (T / q) / (float(r @ r) / (m - n))
    critical_value = float(stats.f.isf(alpha, q, m - n - q))
    return F, critical_value, F > critical_value
""",
        ),
        (
            "F's denominator dof m - n",
            """def f_test(A, y, Qyy, C, alpha):
    A = np.asarray(A, dtype=float)
    m, n = A.shape
    q = np.shape(C)[1]
    T = glr_statistic(A, y, Qyy, C)
    L = np.linalg.cholesky(Qyy)
    A_w = linalg.solve_triangular(L, A, lower=True)
    y_w = linalg.solve_triangular(L, np.asarray(y, dtype=float), lower=True)
    r = y_w - A_w @ np.linalg.lstsq(A_w, y_w, rcond=None)[0]
    F = (T / q) / ((float(r @ r) - T) / (m - n - q))
    critical_value = float(stats.f.isf(alpha, q, m - n))
    return F, critical_value, F > critical_value
""",
        ),
        (
            "chi-square critical value",
            """def f_test(A, y, Qyy, C, alpha):
    A = np.asarray(A, dtype=float)
    m, n = A.shape
    q = np.shape(C)[1]
    T = glr_statistic(A, y, Qyy, C)
    L = np.linalg.cholesky(Qyy)
    A_w = linalg.solve_triangular(L, A, lower=True)
    y_w = linalg.solve_triangular(L, np.asarray(y, dtype=float), lower=True)
    r = y_w - A_w @ np.linalg.lstsq(A_w, y_w, rcond=None)[0]
    F = (T / q) / ((float(r @ r) - T) / (m - n - q))
    critical_value = float(stats.chi2.isf(alpha, q) / q)
    return F, critical_value, F > critical_value
""",
        ),
        (
            "Omega, not Omega - T_q, over m - n - q",
            """def f_test(A, y, Qyy, C, alpha):
    A = np.asarray(A, dtype=float)
    m, n = A.shape
    q = np.shape(C)[1]
    T = glr_statistic(A, y, Qyy, C)
    L = np.linalg.cholesky(Qyy)
    A_w = linalg.solve_triangular(L, A, lower=True)
    y_w = linalg.solve_triangular(L, np.asarray(y, dtype=float), lower=True)
    r = y_w - A_w @ np.linalg.lstsq(A_w, y_w, rcond=None)[0]
    F = (T / q) / (float(r @ r) / (m - n - q))
    critical_value = float(stats.f.isf(alpha, q, m - n - q))
    return F, critical_value, F > critical_value
""",
        ),
        (
            "T_q / q with the F threshold (sigma² as stated in Qyy)",
            """def f_test(A, y, Qyy, C, alpha):
    m, n = np.shape(A)
    q = np.shape(C)[1]
    F = glr_statistic(A, y, Qyy, C) / q
    critical_value = float(stats.f.isf(alpha, q, m - n - q))
    return F, critical_value, F > critical_value
""",
        ),
        (
            "T_q itself with the F threshold",
            """def f_test(A, y, Qyy, C, alpha):
    m, n = np.shape(A)
    q = np.shape(C)[1]
    T = glr_statistic(A, y, Qyy, C)
    critical_value = float(stats.f.isf(alpha, q, m - n - q))
    return T, critical_value, T > critical_value
""",
        ),
    ],
    "q4": [
        ("Pope's tau", _Q4_HEAD + "    return w / np.sqrt(omega / (m - n))\n"),
        ("w itself (sigma known)", _Q4_HEAD + "    return w\n"),
        (
            "absolute values",
            _Q4_HEAD + "    return np.abs(w) / np.sqrt((omega - w**2) / (m - n - 1))\n",
        ),
        (
            "normalised residuals e_i / sigma_e_i in place of w_i",
            _Q4_HEAD
            + """    v = e / np.sqrt(np.diag(Qee))
    return v / np.sqrt((omega - v**2) / (m - n - 1))
""",
        ),
        (
            "dof m - n in the estimate",
            _Q4_HEAD + "    return w / np.sqrt((omega - w**2) / (m - n))\n",
        ),
        ("variance, not its root", _Q4_HEAD + "    return w / ((omega - w**2) / (m - n - 1))\n"),
    ],
    "q5": [
        (
            "the power of the q-dimensional test at alpha_1, not a level",
            """def b_method_level(alpha_1, power, q):
    lambda_0 = chi2.noncentrality(alpha_1, power, 1)
    return float(stats.ncx2.sf(stats.chi2.isf(alpha_1, q), q, lambda_0))
""",
        ),
        ("alpha_1 returned", "def b_method_level(alpha_1, power, q):\n    return alpha_1\n"),
        (
            "alpha_1 / 2 for lambda_0 (two-sided w)",
            """def b_method_level(alpha_1, power, q):
    lambda_0 = chi2.noncentrality(alpha_1 / 2, power, 1)
    critical = stats.ncx2.ppf(1.0 - power, q, lambda_0)
    return float(stats.chi2.sf(critical, q))
""",
        ),
        (
            "lambda_0 with q degrees of freedom",
            """def b_method_level(alpha_1, power, q):
    lambda_0 = chi2.noncentrality(alpha_1, power, q)
    critical = stats.ncx2.ppf(1.0 - power, q, lambda_0)
    return float(stats.chi2.sf(critical, q))
""",
        ),
        (
            "the power-quantile",
            """def b_method_level(alpha_1, power, q):
    lambda_0 = chi2.noncentrality(alpha_1, power, 1)
    critical = stats.ncx2.ppf(power, q, lambda_0)
    return float(stats.chi2.sf(critical, q))
""",
        ),
        (
            "1 - the level",
            """def b_method_level(alpha_1, power, q):
    lambda_0 = chi2.noncentrality(alpha_1, power, 1)
    critical = stats.ncx2.ppf(1.0 - power, q, lambda_0)
    return float(stats.chi2.cdf(critical, q))
""",
        ),
    ],
    "q6_practice": [
        (
            "w² of the first of the pair",
            "def pair_statistic(line):\n"
            "    return glr_statistic(line['A'], line['y'], line['Qyy'], "
            "np.eye(len(line['y']))[:, line['pair'][:1]])\n",
        ),
        (
            "unweighted",
            "def pair_statistic(line):\n"
            "    n = len(line['y'])\n"
            "    return glr_statistic(line['A'], line['y'], np.eye(n), np.eye(n)[:, line['pair']])\n",
        ),
        (
            "the overall model test's T",
            "def pair_statistic(line):\n"
            "    return lsq.fit(line['A'], line['y'], line['Qyy']).squared_norm\n",
        ),
        (
            "the practice pair whatever the line",
            "def pair_statistic(line):\n"
            "    return glr_statistic(line['A'], line['y'], line['Qyy'], "
            "np.eye(len(line['y']))[:, [7, 8]])\n",
        ),
    ],
    "q6": [
        (
            "w² of the first of the pair",
            "T_pair_mine = glr_statistic(mine['A'], mine['y'], mine['Qyy'], "
            "np.eye(14)[:, mine['pair'][:1]])",
        ),
        (
            "the practice line's T_2",
            "T_pair_mine = glr_statistic(practice['A'], practice['y'], practice['Qyy'], "
            "np.eye(14)[:, practice['pair']])",
        ),
        (
            "the neighbour pair on the other side",
            "T_pair_mine = glr_statistic(mine['A'], mine['y'], mine['Qyy'], "
            "np.eye(14)[:, [mine['pair'][0] - 1, mine['pair'][0]]])",
        ),
        (
            "unweighted",
            "T_pair_mine = glr_statistic(mine['A'], mine['y'], np.eye(14), "
            "np.eye(14)[:, mine['pair']])",
        ),
    ],
    "q7_practice": [
        (
            "no adaptation (x_hat of H0)",
            _RIGHT_DIA.replace(
                'lsq.fit(d["A"][keep], d["y"][keep], d["Qyy"][np.ix_(keep, keep)]).x_hat',
                "fit.x_hat",
            ),
        ),
        (
            "x_hat alone, as the question used to ask",
            "def dia_estimate(d):\n"
            "    fit = lsq.fit(d['A'], d['y'], d['Qyy'])\n"
            "    keep = np.delete(np.arange(14), lsq.w_tests(fit, d['alpha']).largest)\n"
            "    return lsq.fit(d['A'][keep], d['y'][keep], d['Qyy'][np.ix_(keep, keep)]).x_hat\n",
        ),
        (
            "the pair's first observation removed, no detection or identification",
            _DIA_BY.format(suspect="d['pair'][0]", weights='d["Qyy"][np.ix_(keep, keep)]'),
        ),
        (
            "largest |e| removed",
            _DIA_BY.format(
                suspect="int(np.argmax(np.abs(fit.e_hat)))",
                weights='d["Qyy"][np.ix_(keep, keep)]',
            ),
        ),
        (
            "adapted fit unweighted",
            _DIA_BY.format(suspect="lsq.w_tests(fit, d['alpha']).largest", weights="None"),
        ),
        (
            "data snooping (several removals)",
            _RIGHT_DIA.replace(
                'lsq.fit(d["A"][keep], d["y"][keep], d["Qyy"][np.ix_(keep, keep)]).x_hat',
                'lsq.data_snooping(fit, alpha=d["alpha"]).fit.x_hat',
            ),
        ),
        (
            "(slope, height) order",
            _RIGHT_DIA.replace("[np.ix_(keep, keep)]).x_hat", "[np.ix_(keep, keep)]).x_hat[::-1]"),
        ),
    ],
    "q7": [
        ("the practice answer", "dia_mine = dia_estimate(practice)"),
        (
            "largest |e| removed",
            "fit = lsq.fit(mine['A'], mine['y'], mine['Qyy'])\n"
            "suspect = int(np.argmax(np.abs(fit.e_hat)))\n"
            "keep = np.delete(np.arange(14), suspect)\n"
            "dia_mine = (fit.squared_norm, True, suspect, lsq.fit(mine['A'][keep], "
            "mine['y'][keep], mine['Qyy'][np.ix_(keep, keep)]).x_hat)",
        ),
        (
            "no adaptation (x_hat of H0)",
            "fit = lsq.fit(mine['A'], mine['y'], mine['Qyy'])\n"
            "dia_mine = (fit.squared_norm, True, lsq.w_tests(fit).largest, fit.x_hat)",
        ),
        (
            "the pair's second observation removed, no detection or identification",
            "fit = lsq.fit(mine['A'], mine['y'], mine['Qyy'])\n"
            "keep = np.delete(np.arange(14), mine['pair'][1])\n"
            "dia_mine = (fit.squared_norm, True, mine['pair'][1], lsq.fit(mine['A'][keep], "
            "mine['y'][keep], mine['Qyy'][np.ix_(keep, keep)]).x_hat)",
        ),
        (
            "x_hat alone, as the question used to ask",
            "dia_mine = dia_estimate(mine)[3]",
        ),
    ],
    "q8": [
        ("normal, null model", 'dia_law = "normal, with the covariance of the null model"'),
        ("normal, adapted model", 'dia_law = "normal, with the covariance of the adapted model"'),
        ("not an option", 'dia_law = "normal"'),
    ],
    "q9": [
        (
            "lambda_0 with one degree of freedom",
            _Q9_HEAD
            + """    M = C.T @ W @ Qee @ W @ C
    lambda_0 = chi2.noncentrality(alpha, power, 1)
    return np.sqrt(lambda_0 / (d @ M @ d)) * d
""",
        ),
        (
            "C not projected",
            _Q9_HEAD
            + """    M = C.T @ W @ C
    lambda_0 = chi2.noncentrality(alpha, power, C.shape[1])
    return np.sqrt(lambda_0 / (d @ M @ d)) * d
""",
        ),
        (
            "the size only",
            _Q9_HEAD
            + """    M = C.T @ W @ Qee @ W @ C
    lambda_0 = chi2.noncentrality(alpha, power, C.shape[1])
    return np.sqrt(lambda_0 / (d @ M @ d))
""",
        ),
        (
            "direction not normalised",
            """def mdb_along(A, Qyy, C, alpha, power, direction):
    A = np.asarray(A, dtype=float)
    C = np.asarray(C, dtype=float)
    d = np.asarray(direction, dtype=float)
    W = np.linalg.inv(Qyy)
    Qxx = np.linalg.inv(A.T @ W @ A)
    Qee = Qyy - A @ Qxx @ A.T
    M = C.T @ W @ Qee @ W @ C
    lambda_0 = chi2.noncentrality(alpha, power, C.shape[1])
    return np.sqrt(lambda_0 / (d @ M @ d)) * d * np.linalg.norm(d)
""",
        ),
    ],
}

RIGHT = {
    "q1": [
        ("the textbook formula with inverses", _Q1_TEXTBOOK),
        (
            "the drop of the residual norm between two nested whitened fits, C as a list",
            """def glr_statistic(A, y, Qyy, C):
    L = np.linalg.cholesky(np.asarray(Qyy, dtype=float))
    white = lambda X: linalg.solve_triangular(L, np.asarray(X, dtype=float), lower=True)
    y_w = white(y)
    def norm2(X_w):
        r = y_w - X_w @ np.linalg.lstsq(X_w, y_w, rcond=None)[0]
        return r @ r
    return norm2(white(A)) - norm2(white(np.column_stack([A, np.asarray(C).tolist()])))
""",
        ),
    ],
    "q2": [
        (
            "a list and a named tuple of its own, numpy bool",
            """from collections import namedtuple
Decision = namedtuple("Decision", "statistic threshold rejected")
def glr_decision(A, y, Qyy, C, alpha):
    T = np.float64(glr_statistic(A, y, Qyy, C))
    c = stats.chi2.isf(alpha, len(np.asarray(C)[0]))
    return Decision(T, c, np.greater(T, c))
""",
        ),
        (
            "a result namedtuple-like tuple with p-value logic",
            """def glr_decision(A, y, Qyy, C, alpha):
    T = glr_statistic(A, y, Qyy, C)
    q = np.asarray(C).shape[1]
    return T, float(stats.chi2.ppf(1 - alpha, q)), bool(stats.chi2.sf(T, q) < alpha)
""",
        ),
    ],
    "q3": [
        (
            "F from two nested weighted fits",
            """def f_test(A, y, Qyy, C, alpha):
    A = np.asarray(A, dtype=float)
    C = np.asarray(C, dtype=float)
    m, n = A.shape
    q = C.shape[1]
    s = np.linalg.cholesky(Qyy)
    def norm2(X):
        X_w = linalg.solve_triangular(s, X, lower=True)
        y_w = linalg.solve_triangular(s, np.asarray(y, dtype=float), lower=True)
        r = y_w - X_w @ np.linalg.lstsq(X_w, y_w, rcond=None)[0]
        return float(r @ r)
    omega0, omega_a = norm2(A), norm2(np.column_stack([A, C]))
    F = ((omega0 - omega_a) / q) / (omega_a / (m - n - q))
    critical_value = float(stats.f.ppf(1 - alpha, q, m - n - q))
    return F, critical_value, F > critical_value
""",
        )
    ],
    "q6_practice": [
        (
            "the nested fits' drop of the residual norm",
            """def pair_statistic(line):
    s = np.sqrt(np.diag(line["Qyy"]))

    def norm2(X):
        Xw = X / s[:, None]
        r = line["y"] / s - Xw @ np.linalg.lstsq(Xw, line["y"] / s, rcond=None)[0]
        return float(r @ r)

    C = np.eye(len(line["y"]))[:, line["pair"]]
    return norm2(line["A"]) - norm2(np.column_stack([line["A"], C]))
""",
        )
    ],
    "q6": [
        (
            "lsq.glr_test (allowed here)",
            "T_pair_mine = float(lsq.glr_test(lsq.fit(mine['A'], mine['y'], mine['Qyy']), "
            "np.eye(14)[:, mine['pair']]).statistic)",
        )
    ],
    "q7": [
        (
            "a list from the practice function",
            "dia_mine = list(dia_estimate(mine))",
        ),
        (
            "lsq.dia (allowed here)",
            "fit = lsq.fit(mine['A'], mine['y'], mine['Qyy'])\n"
            "result = lsq.dia(fit, alpha=mine['alpha'])\n"
            "dia_mine = (fit.squared_norm, lsq.overall_model_test(fit, mine['alpha']).reject, "
            "result.identified, result.x_hat)",
        ),
    ],
    "q4": [
        (
            "a list from one nested fit per observation",
            """def t_statistics(A, y, Qyy):
    A = np.asarray(A, dtype=float)
    m, n = A.shape
    L = np.linalg.cholesky(Qyy)
    A_w = linalg.solve_triangular(L, A, lower=True)
    y_w = linalg.solve_triangular(L, np.asarray(y, dtype=float), lower=True)
    def fit_w(X_w):
        x = np.linalg.lstsq(X_w, y_w, rcond=None)[0]
        return x, y_w - X_w @ x
    omega = float(np.sum(fit_w(A_w)[1] ** 2))
    out = []
    for i in range(m):
        c_w = linalg.solve_triangular(L, np.eye(m)[:, i], lower=True)
        x, r = fit_w(np.column_stack([A_w, c_w]))
        nabla = x[-1]
        sigma2 = float(r @ r) / (m - n - 1)
        w = np.sign(nabla) * np.sqrt(max(omega - float(r @ r), 0.0))
        out.append(float(w / np.sqrt(sigma2)))
    return out
""",
        ),
        (
            "via Pope's tau",
            _Q4_HEAD
            + """    tau = w / np.sqrt(omega / (m - n))
    r = m - n
    return np.sign(tau) * np.sqrt((r - 1) * tau**2 / (r - tau**2))
""",
        ),
    ],
    "q5": [
        (
            "a 0-d array from an array computation",
            """def b_method_level(alpha_1, power, q):
    lam = chi2.noncentrality(alpha_1, power, 1)
    return np.asarray(stats.chi2.sf(stats.ncx2.isf(power, np.asarray([q]), lam), q))[0]
""",
        ),
        (
            "a root search for alpha_q",
            """def b_method_level(alpha_1, power, q):
    from scipy import optimize
    lambda_0 = chi2.noncentrality(alpha_1, power, 1)
    gap = lambda a: stats.ncx2.sf(stats.chi2.isf(a, q), q, lambda_0) - power
    return float(optimize.brentq(gap, 1e-12, 0.999, xtol=1e-15, rtol=1e-14))
""",
        ),
    ],
    "q7_practice": [
        (
            "the refit as least squares by hand",
            """def dia_estimate(d):
    fit = lsq.fit(d["A"], d["y"], d["Qyy"])
    if not lsq.overall_model_test(fit, d["alpha"]).reject:
        return fit.squared_norm, False, None, fit.x_hat
    suspect = int(np.argmax(np.abs(lsq.w_tests(fit).statistic)))
    keep = np.delete(np.arange(len(d["y"])), suspect)
    s = np.sqrt(np.diag(d["Qyy"]))[keep]
    x = np.linalg.lstsq(d["A"][keep] / s[:, None], d["y"][keep] / s, rcond=None)[0]
    return [fit.squared_norm, True, suspect, x]
""",
        )
    ],
    "q8": [("other case and spaces", 'dia_law = "  A mixture, not normal "')],
    "q9": [
        (
            "a list, whitened and projected with QR",
            """def mdb_along(A, Qyy, C, alpha, power, direction):
    L = np.linalg.cholesky(Qyy)
    A_w = linalg.solve_triangular(L, np.asarray(A, dtype=float), lower=True)
    C_w = linalg.solve_triangular(L, np.asarray(C, dtype=float), lower=True)
    Q, _ = np.linalg.qr(A_w)
    _, R_c = np.linalg.qr(C_w - Q @ (Q.T @ C_w))
    d = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    s = np.sqrt(chi2.noncentrality(alpha, power, C_w.shape[1])) / np.linalg.norm(R_c @ d)
    return list(s * d)
""",
        ),
        (
            "the textbook formula",
            _Q9_HEAD
            + """    M = C.T @ W @ Qee @ W @ C
    lambda_0 = chi2.noncentrality(alpha, power, C.shape[1])
    return np.sqrt(lambda_0 / (d @ M @ d)) * d
""",
        ),
    ],
}
