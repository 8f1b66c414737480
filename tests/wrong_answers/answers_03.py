"""Wrong and right answers of assignment 03_estimation_and_likelihood (data for
tests/test_wrong_answers.py).

WRONG[q]: answers a class would plausibly write; each must lose points at grading.
RIGHT[q]: correct answers written differently; each must keep full marks.
MANUAL: questions an instructor marks (short answers), not graded automatically.
Each source replaces the whole answer cell of q in the solution notebook (format: see the
docstring of tests/test_wrong_answers.py).
"""

ASSIGNMENT = "03_estimation_and_likelihood"
STUDENT = "wa03"
DEPENDS = {"q3": ["q1"], "q5": ["q4"], "q9": ["q9_practice"]}
MANUAL = ["q3b"]

# The demo student's posterior, as a student copying it would hard-code it.
DEMO_POSTERIOR = (
    "np.array([0.6258459470180282, 0.29731553939438665, 0.06829418430940029, 0.00854432927818483])"
)

_Q1 = """def joint_parameter_test(U, y, sigma, alpha):
    U = np.asarray(U, dtype=float)
    y = np.asarray(y, dtype=float)
    Phi = U[:, :2]
    theta = np.linalg.lstsq(Phi, y - U[:, 2], rcond=None)[0]
    C = sigma**2 * np.linalg.inv(Phi.T @ Phi)
"""
_LIK = """def likelihood(theta, z, sigma):
    theta = np.asarray(theta, dtype=float)
    z = np.asarray(z, dtype=float)
"""
_LEAK = """def leak_theta2(U, theta1):
    U = np.asarray(U, dtype=float)
    u1_, u2_ = U[:, 0], U[:, 1]
"""
_PP = """def power_pair(U, sigma, theta2, alpha):
    U = np.asarray(U, dtype=float)
    n = U.shape[0]
    s2 = sigma * np.sqrt(np.linalg.inv(U[:, :2].T @ U[:, :2])[1, 1])
    z = stats.norm.isf(alpha / 2)
    b = theta2 - 1.0
    d = (theta2 - 1.0) * U[:, 1]
    d_perp = d - U[:, 0] * (U[:, 0] @ d) / (U[:, 0] @ U[:, 0])
    p_pe = float(stats.ncx2.sf(stats.chi2.isf(alpha, n - 1), n - 1, (d_perp @ d_perp) / sigma**2))
"""
_ML = """def maximum_likelihood(z, sigma):
    z = np.asarray(z, dtype=float)
    t = float(np.mean(z))
"""
_POST_HEAD = """def posteriors(y, U, sigma, tau, priors):
    n = len(y)
    mean = U @ np.ones(3)
    log_l = [stats.multivariate_normal(mean, sigma**2 * np.eye(n)).logpdf(y)]
    for i in range(3):
        ui = U[:, i]
        cov = sigma**2 * np.eye(n) + tau**2 * np.outer(ui, ui)
        log_l.append(stats.multivariate_normal(mean, cov).logpdf(y))
"""
_Q8 = """def boundary_false_alarm(n, alpha, n_runs, seed):
    rng = np.random.default_rng(seed)
"""
_MAXIMISED = """def maximised_posteriors(y_, U_, sigma_, priors_):
    n_ = len(y_)
    r0 = y_ - U_ @ np.ones(3)
    log_l = [-(r0 @ r0) / (2 * sigma_**2)]
    for i in range(3):
        u = U_[:, i]
        r = r0 - u * (u @ r0) / (u @ u)
        log_l.append(-(r @ r) / (2 * sigma_**2))
    log_post = np.array(log_l) - n_ / 2 * np.log(2 * np.pi * sigma_**2) + np.log(priors_)
    return np.exp(log_post - np.logaddexp.reduce(log_post))

"""
_OWN_POSTERIOR = """def own_posteriors(y_, U_, sigma_, tau_, priors_):
    y_ = np.asarray(y_, dtype=float)
    mean_ = U_ @ np.ones(3)
    covs = [sigma_**2 * np.eye(len(y_))]
    covs += [sigma_**2 * np.eye(len(y_)) + tau_**2 * np.outer(u, u) for u in U_.T]
    log_l = []
    for C in covs:
        L = np.linalg.cholesky(C)
        w = linalg.solve_triangular(L, y_ - mean_, lower=True)
        log_l.append(-0.5 * w @ w - np.sum(np.log(np.diag(L))) - len(y_) / 2 * np.log(2 * np.pi))
    p = np.exp(np.array(log_l) - max(log_l)) * priors_
    return list(p / p.sum())

"""

WRONG = {
    "q1": [
        (
            "one-sided: z_alpha instead of z_alpha/2",
            _Q1
            + "    s = float(np.sqrt(C[1, 1]))\n"
            + "    return float(theta[1]), s, bool(abs(theta[1] - 1) > s * stats.norm.isf(alpha))\n",
        ),
        (
            "variance instead of standard deviation",
            _Q1
            + "    s = float(C[1, 1])\n"
            + "    return float(theta[1]), s, bool(abs(theta[1] - 1) > s * stats.norm.isf(alpha / 2))\n",
        ),
        (
            "theta2 estimated alone (theta1 fixed at 1)",
            """def joint_parameter_test(U, y, sigma, alpha):
    U = np.asarray(U, dtype=float)
    y = np.asarray(y, dtype=float)
    u = U[:, 1]
    target = y - U[:, 0] - U[:, 2]
    th = (u @ target) / (u @ u)
    s = float(sigma / np.sqrt(u @ u))
    return float(th), s, bool(abs(th - 1) > s * stats.norm.isf(alpha / 2))
""",
        ),
        (
            "the (1, 1) element: the std of theta1",
            _Q1
            + "    s = float(np.sqrt(C[0, 0]))\n"
            + "    return float(theta[1]), s, bool(abs(theta[1] - 1) > s * stats.norm.isf(alpha / 2))\n",
        ),
        (
            "all three gains estimated",
            """def joint_parameter_test(U, y, sigma, alpha):
    U = np.asarray(U, dtype=float)
    theta = np.linalg.lstsq(U, np.asarray(y, dtype=float), rcond=None)[0]
    s = float(np.sqrt(sigma**2 * np.linalg.inv(U.T @ U)[1, 1]))
    return float(theta[1]), s, bool(abs(theta[1] - 1) > s * stats.norm.isf(alpha / 2))
""",
        ),
    ],
    "q2": [
        ("the joint estimate (decoupled: 1)", "def leak_theta2(U, theta1):\n    return 1.0\n"),
        (
            "the leak alone, without the 1",
            _LEAK + "    return float((theta1 - 1) * (u2_ @ u1_) / (u2_ @ u2_))\n",
        ),
        (
            "divided by u1'u1",
            _LEAK + "    return float(1 + (theta1 - 1) * (u2_ @ u1_) / (u1_ @ u1_))\n",
        ),
        (
            "u1 not subtracted (theta1 u1 + u2 regressed on u2)",
            _LEAK + "    return float(u2_ @ (theta1 * u1_ + u2_) / (u2_ @ u2_))\n",
        ),
        (
            "the context's signals u1, u2 instead of U's",
            "def leak_theta2(U, theta1):\n    return float(1 + (theta1 - 1) * (u2 @ u1) / (u2 @ u2))\n",
        ),
        (
            "the public answer hard-coded",
            "def leak_theta2(U, theta1):\n    return 1.2215142211441814\n",
        ),
    ],
    "q3": [
        (
            "one tail of the parameter test only",
            _PP + "    return float(stats.norm.sf(z - b / s2)), p_pe\n",
        ),
        (
            "one-sided z_alpha in the parameter test",
            _PP.replace("z = stats.norm.isf(alpha / 2)", "z = stats.norm.isf(alpha)")
            + "    return float(stats.norm.sf(z - b / s2) + stats.norm.cdf(-z - b / s2)), p_pe\n",
        ),
        (
            "lambda without projecting out u1",
            _PP.replace("d_perp = d - U[:, 0] * (U[:, 0] @ d) / (U[:, 0] @ U[:, 0])", "d_perp = d")
            + "    return float(stats.norm.sf(z - b / s2) + stats.norm.cdf(-z - b / s2)), p_pe\n",
        ),
        (
            "dof N in the prediction-error test",
            _PP.replace("n - 1", "n")
            + "    return float(stats.norm.sf(z - b / s2) + stats.norm.cdf(-z - b / s2)), p_pe\n",
        ),
        (
            "the public fault 0.1 and alpha 0.05 hard-wired",
            _PP.replace("theta2 - 1.0", "0.1").replace("alpha", "0.05")
            + "    return float(stats.norm.sf(z - b / s2) + stats.norm.cdf(-z - b / s2)), p_pe\n",
        ),
    ],
    "q4": [
        (
            "right, but computed in float32",
            _LIK.replace("float)", "np.float32)")
            + "    pdf = stats.norm.pdf(z[None, :], theta.reshape(-1, 1), np.float32(sigma))\n"
            + "    return np.prod(pdf.astype(np.float32), axis=1).reshape(theta.shape)\n",
        ),
        (
            "the log-likelihood",
            _LIK
            + "    return np.sum(stats.norm.logpdf(z[None, :], theta.reshape(-1, 1), sigma), axis=1).reshape(theta.shape)\n",
        ),
        (
            "sigma^2 passed as the scale",
            _LIK
            + "    return np.prod(stats.norm.pdf(z[None, :], theta.reshape(-1, 1), sigma**2), axis=1).reshape(theta.shape)\n",
        ),
        (
            "sum of densities instead of the product",
            _LIK
            + "    return np.sum(stats.norm.pdf(z[None, :], theta.reshape(-1, 1), sigma), axis=1).reshape(theta.shape)\n",
        ),
        (
            "first observation only",
            _LIK + "    return stats.norm.pdf(z[0], theta, sigma)\n",
        ),
    ],
    "q5": [
        (
            "the log of the maximum",
            _ML + "    return t, float(np.sum(stats.norm.logpdf(z, t, sigma)))\n",
        ),
        ("one density factor", _ML + "    return t, float(stats.norm.pdf(z[0], t, sigma))\n"),
        (
            "theta at the first observation",
            _ML + "    return float(z[0]), float(np.prod(stats.norm.pdf(z, z[0], sigma)))\n",
        ),
        (
            "sigma^2 passed as the scale",
            _ML + "    return t, float(np.prod(stats.norm.pdf(z, t, sigma**2)))\n",
        ),
        (
            "the lecture's answer hard-coded",
            "def maximum_likelihood(z, sigma):\n    return 4.0, float(np.exp(-1.0) / (2 * np.pi))\n",
        ),
    ],
    "q6": [
        (
            "not divided by sigma^2",
            """def glr_nf_vs_f2(U, y, sigma):
    U = np.asarray(U, dtype=float)
    r0 = np.asarray(y, dtype=float) - U.sum(axis=1)
    u = U[:, 1]
    r1 = r0 - u * (u @ r0) / (u @ u)
    stat = float(r0 @ r0 - r1 @ r1)
    return stat, float(stats.chi2.sf(stat, 1))
""",
        ),
        (
            "p-value from the cdf",
            """def glr_nf_vs_f2(U, y, sigma):
    U = np.asarray(U, dtype=float)
    r0 = np.asarray(y, dtype=float) - U.sum(axis=1)
    u = U[:, 1]
    r1 = r0 - u * (u @ r0) / (u @ u)
    stat = float((r0 @ r0 - r1 @ r1) / sigma**2)
    return stat, float(stats.chi2.cdf(stat, 1))
""",
        ),
        (
            "chi2(N - 1) for the p-value",
            """def glr_nf_vs_f2(U, y, sigma):
    U = np.asarray(U, dtype=float)
    r0 = np.asarray(y, dtype=float) - U.sum(axis=1)
    u = U[:, 1]
    r1 = r0 - u * (u @ r0) / (u @ u)
    stat = float((r0 @ r0 - r1 @ r1) / sigma**2)
    return stat, float(stats.chi2.sf(stat, len(r0) - 1))
""",
        ),
        (
            "theta1 freed instead of theta2",
            """def glr_nf_vs_f2(U, y, sigma):
    U = np.asarray(U, dtype=float)
    r0 = np.asarray(y, dtype=float) - U.sum(axis=1)
    u = U[:, 0]
    r1 = r0 - u * (u @ r0) / (u @ u)
    stat = float((r0 @ r0 - r1 @ r1) / sigma**2)
    return stat, float(stats.chi2.sf(stat, 1))
""",
        ),
    ],
    "q7": [
        (
            "two-sided z_alpha/2",
            """def np_power(n, theta0, theta1, sigma, alpha):
    d = np.sqrt(n) * abs(theta1 - theta0) / sigma
    return float(stats.norm.sf(stats.norm.isf(alpha / 2) - d))
""",
        ),
        (
            "sqrt(n) forgotten",
            """def np_power(n, theta0, theta1, sigma, alpha):
    d = abs(theta1 - theta0) / sigma
    return float(stats.norm.sf(stats.norm.isf(alpha) - d))
""",
        ),
        (
            "the false-alarm side (cdf instead of sf)",
            """def np_power(n, theta0, theta1, sigma, alpha):
    d = np.sqrt(n) * abs(theta1 - theta0) / sigma
    return float(stats.norm.cdf(stats.norm.isf(alpha) - d))
""",
        ),
        (
            "sigma^2 instead of sigma",
            """def np_power(n, theta0, theta1, sigma, alpha):
    d = np.sqrt(n) * abs(theta1 - theta0) / sigma**2
    return float(stats.norm.sf(stats.norm.isf(alpha) - d))
""",
        ),
        (
            "sigma left out",
            """def np_power(n, theta0, theta1, sigma, alpha):
    d = np.sqrt(n) * abs(theta1 - theta0)
    return float(stats.norm.sf(stats.norm.isf(alpha) - d))
""",
        ),
        (
            "n / sigma instead of sqrt(n) / sigma",
            """def np_power(n, theta0, theta1, sigma, alpha):
    d = n * abs(theta1 - theta0) / sigma
    return float(stats.norm.sf(stats.norm.isf(alpha) - d))
""",
        ),
    ],
    "q8": [
        (
            "the theoretical rate alpha / 2",
            "def boundary_false_alarm(n, alpha, n_runs, seed):\n    return alpha / 2\n",
        ),
        (
            "Wilks' promise alpha",
            "def boundary_false_alarm(n, alpha, n_runs, seed):\n    return alpha\n",
        ),
        (
            "samples in columns: another random sample",
            _Q8
            + "    zbar = rng.standard_normal((n, n_runs)).mean(axis=0)\n"
            + "    return float(np.mean(n * np.maximum(zbar, 0.0) ** 2 > stats.chi2.isf(alpha, 1)))\n",
        ),
        (
            "no boundary: n zbar^2 (two-sided)",
            _Q8
            + "    zbar = rng.standard_normal((n_runs, n)).mean(axis=1)\n"
            + "    return float(np.mean(n * zbar**2 > stats.chi2.isf(alpha, 1)))\n",
        ),
        (
            "one sample per run only (n ignored)",
            _Q8
            + "    z = rng.standard_normal(n_runs)\n"
            + "    return float(np.mean(np.maximum(z, 0.0) ** 2 > stats.chi2.isf(alpha, 1)))\n",
        ),
    ],
    "q9_practice": [
        (
            "maximised instead of marginal likelihood",
            _MAXIMISED
            + "def posteriors(y, U, sigma, tau, priors):\n"
            + "    return maximised_posteriors(y, U, sigma, priors)\n",
        ),
        (
            "priors forgotten",
            _POST_HEAD
            + """    log_l = np.array(log_l)
    return np.exp(log_l - np.logaddexp.reduce(log_l))
""",
        ),
        (
            "tau instead of tau^2",
            _POST_HEAD.replace("tau**2", "tau")
            + """    log_post = np.array(log_l) + np.log(priors)
    return np.exp(log_post - np.logaddexp.reduce(log_post))
""",
        ),
        (
            "the practice record's posterior whatever the record",
            _POST_HEAD.replace(
                "def posteriors(y, U, sigma, tau, priors):", "def _post(y, U, sigma, tau, priors):"
            )
            + """    log_post = np.array(log_l) + np.log(priors)
    return np.exp(log_post - np.logaddexp.reduce(log_post))

def posteriors(y, U_, sigma_, tau_, priors_):
    return _post(y_modes, U, sigma, tau, priors)
""",
        ),
    ],
    "q9": [
        (
            "maximised instead of marginal likelihood",
            _MAXIMISED
            + 'posterior_mine = maximised_posteriors(mine["y"], mine["U"], mine["sigma"], mine["priors"])\n',
        ),
        (
            "the practice record instead of mine",
            "posterior_mine = posteriors(y_modes, U, sigma, tau, priors)",
        ),
        (
            "unnormalised posteriors",
            """lp = []
for i in range(4):
    cov = mine["sigma"] ** 2 * np.eye(len(mine["y"]))
    if i:
        cov = cov + mine["tau"] ** 2 * np.outer(mine["U"][:, i - 1], mine["U"][:, i - 1])
    lp.append(stats.multivariate_normal(mine["U"] @ np.ones(3), cov).logpdf(mine["y"]))
posterior_mine = np.exp(np.array(lp) - max(lp)) * mine["priors"]
""",
        ),
        ("the demo student's posterior hard-coded", "posterior_mine = " + DEMO_POSTERIOR),
    ],
}

RIGHT = {
    "q1": [
        (
            "explicit inverse, a list and numpy types",
            _Q1
            + "    s = np.sqrt(C[1, 1])\n"
            + "    return [theta[1], s, np.abs(theta[1] - 1) > s * stats.norm.ppf(1 - alpha / 2)]\n",
        ),
    ],
    "q2": [
        (
            "by least squares on the noise-free record",
            """def leak_theta2(U, theta1):
    tgt = U @ np.array([theta1, 1.0, 1.0]) - U[:, 0] - U[:, 2]
    return np.linalg.lstsq(U[:, 1:2], tgt, rcond=None)[0][0]
""",
        ),
    ],
    "q3": [
        (
            "by hand with an explicit inverse, a list",
            """def power_pair(U, sigma, theta2, alpha):
    U = np.asarray(U, dtype=float)
    n = len(U)
    s2 = sigma * np.sqrt(np.linalg.inv(U[:, :2].T @ U[:, :2])[1, 1])
    z = stats.norm.ppf(1 - alpha / 2)
    b = abs(theta2 - 1.0) / s2
    P1 = np.outer(U[:, 0], U[:, 0]) / (U[:, 0] @ U[:, 0])
    d_perp = (np.eye(n) - P1) @ ((theta2 - 1.0) * U[:, 1])
    lam = d_perp @ d_perp / sigma**2
    return [stats.norm.cdf(b - z) + stats.norm.cdf(-b - z),
            stats.ncx2.sf(stats.chi2.ppf(1 - alpha, n - 1), n - 1, lam)]
""",
        ),
    ],
    "q4": [
        (
            "product of pdfs by broadcasting",
            _LIK + "    return np.prod(stats.norm.pdf(z, theta[..., None], sigma), axis=-1)\n",
        ),
    ],
    "q5": [
        (
            "the closed form of the maximum",
            """def maximum_likelihood(z, sigma):
    z = np.asarray(z, dtype=float)
    t = z.mean()
    n = z.size
    L = (2 * np.pi * sigma**2) ** (-n / 2) * np.exp(-np.sum((z - t) ** 2) / (2 * sigma**2))
    return [t, L]
""",
        ),
    ],
    "q6": [
        (
            "lstsq for T1, a list",
            """def glr_nf_vs_f2(U, y, sigma):
    U = np.asarray(U, dtype=float)
    r0 = np.asarray(y, dtype=float) - U.sum(axis=1)
    th = np.linalg.lstsq(U[:, [1]], r0, rcond=None)[0]
    r1 = r0 - U[:, 1] * th[0]
    stat = (r0 @ r0 - r1 @ r1) / sigma**2
    return [stat, 1 - stats.chi2.cdf(stat, 1)]
""",
        ),
    ],
    "q7": [
        (
            "cdf form",
            """def np_power(n, theta0, theta1, sigma, alpha):
    d = abs(theta1 - theta0) * n**0.5 / sigma
    return stats.norm.cdf(d - stats.norm.ppf(1 - alpha))
""",
        ),
    ],
    "q8": [
        (
            "sum instead of mean, numpy result",
            _Q8
            + "    Z = rng.standard_normal((n_runs, n))\n"
            + "    s = Z.sum(axis=1)\n"
            + "    glr = np.where(s > 0, s**2 / n, 0.0)\n"
            + "    return np.count_nonzero(glr > stats.chi2.ppf(1 - alpha, 1)) / n_runs\n",
        ),
    ],
    "q9_practice": [
        (
            "Cholesky log-densities by hand, a list",
            _OWN_POSTERIOR + "posteriors = own_posteriors\n",
        ),
    ],
    "q9": [
        (
            "self-contained, Cholesky by hand",
            _OWN_POSTERIOR
            + 'posterior_mine = own_posteriors(mine["y"], mine["U"], mine["sigma"], mine["tau"], mine["priors"])\n',
        ),
    ],
}

# q5's reference is a named tuple (theta_ml, L_max): a tuple in the same order is right too.
RIGHT["q5"] += [
    (
        "via the likelihood of q4, a tuple",
        """def maximum_likelihood(z, sigma):
    t = sum(z) / len(z)
    return (t, float(likelihood(np.array([t]), z, sigma)[0]))
""",
    ),
]

WRONG["q3"] += [  # a one-line library answer is on the list now (issue 26)
    (
        "the library's power functions (not allowed)",
        """def power_pair(U, sigma, theta2, alpha):
    theta_f = [1.0, theta2, 1.0]
    return [
        dg.parameter_estimate_power(U, nominal, [0, 1], 1, theta_f, sigma=sigma, alpha=alpha),
        dg.prediction_error_power(U, nominal, [0], theta_f, sigma=sigma, alpha=alpha),
    ]
""",
    ),
]

# Forbidden functions (issue 26): a call by any path loses the points (an alias, getattr,
# __import__, functools.partial, a private twin, a call in an added cell for a value);
# an import alone, a call another question allows, and an inverse (advice) cost nothing.
WRONG["q4"] += [
    (
        "exp of normal_log_likelihood (not allowed)",
        """def likelihood(theta, z, sigma):
    return np.exp(dg.normal_log_likelihood(theta, z, sigma=sigma))
""",
    ),
]
WRONG["q7"] += [
    (
        "neyman_pearson_test's power (not allowed)",
        """def np_power(n, theta0, theta1, sigma, alpha):
    r = dg.neyman_pearson_test(np.zeros(n), theta0, theta1, sigma=sigma, alpha=alpha)
    return float(r.details["power"])
""",
    ),
]
RIGHT["q1"] += [
    (
        "np.linalg.inv for the covariance (advice, not a rule), unused forbidden import",
        """from course.diagnosis import estimate_parameters, regression_parameter_test  # noqa: F401


def joint_parameter_test(U, y, sigma, alpha):
    U = np.asarray(U, dtype=float)
    Phi = U[:, :2]
    C = np.linalg.inv(Phi.T @ Phi)
    theta = C @ Phi.T @ (np.asarray(y, dtype=float) - U[:, 2])
    s = float(sigma * np.sqrt(C[1, 1]))
    theta2 = float(theta[1])
    return theta2, s, bool(abs(theta2 - 1.0) > s * stats.norm.isf(alpha / 2))
""",
    ),
]
RIGHT["q3"] += [
    (
        "the solution, with the power functions imported and never called",
        """from course.diagnosis import parameter_estimate_power, prediction_error_power  # noqa: F401


def power_pair(U, sigma, theta2, alpha):
    U = np.asarray(U, dtype=float)
    n_obs = U.shape[0]
    _, s2, _ = joint_parameter_test(U, U @ nominal, sigma, alpha)
    z = stats.norm.isf(alpha / 2)
    b = (theta2 - 1.0) / s2
    p_param = stats.norm.sf(z - b) + stats.norm.cdf(-z - b)
    d = (theta2 - 1.0) * U[:, 1]
    d_perp = d - U[:, 0] * (U[:, 0] @ d) / (U[:, 0] @ U[:, 0])
    lam = (d_perp @ d_perp) / sigma**2
    return float(p_param), float(stats.ncx2.sf(stats.chi2.isf(alpha, n_obs - 1), n_obs - 1, lam))
""",
    ),
]
RIGHT["q6"] += [
    (
        "the solution, with glr_test imported and never called (scored 0/2 before)",
        """from course.diagnosis import glr_test  # noqa: F401


def glr_nf_vs_f2(U, y, sigma):
    U = np.asarray(U, dtype=float)
    r0 = np.asarray(y, dtype=float) - U.sum(axis=1)
    u = U[:, 1]
    r1 = r0 - u * (u @ r0) / (u @ u)
    stat = float((r0 @ r0 - r1 @ r1) / sigma**2)
    return stat, float(stats.chi2.sf(stat, 1))
""",
    ),
]
WRONG["q2"] += [
    (
        "estimate_parameters (not allowed)",
        """def leak_theta2(U, theta1):
    data = U @ np.array([theta1, 1.0, 1.0])
    return float(dg.estimate_parameters(data, U, [1.0, 1.0, 1.0], [1], sigma=1.0).estimate[0])
""",
    ),
]
