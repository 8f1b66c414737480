"""Bad input to every public callable of course.results and course.distributions.

See tests/bad_input.py for the method.  A :class:`TestResult` whose fields
contradict each other (a decision that disagrees with statistic and critical
value, a p-value outside [0, 1], ``reject="no"``) is bad input too.
"""

import numpy as np
from bad_input import (
    Arg,
    array,
    case,
    choice,
    count,
    fixed,
    function,
    generator,
    module_tests,
    obj,
    probability,
    real,
)
from scipy import stats

from course import results
from course.distributions import FrozenDistribution, TailPair
from course.results import TestResult

CHI2 = stats.chi2(2)


class Uniform2(FrozenDistribution):
    """A law on [0, 2] from its cdf alone (the base class's example)."""

    _bounds = (0.0, 2.0)

    def _cdf(self, x):
        return x / 2

    def _rvs(self, size, rng):
        return rng.uniform(0.0, 2.0, size)


LAW = Uniform2()
PAIR = TailPair(
    stats.norm(loc=-1),
    stats.norm(loc=1),
    lambda size, rng: (rng.normal(-1, 1, size), rng.normal(1, 1, size)),
)


def size(value=3):
    """A sample size: a count (0 gives no draws), a shape tuple, or None."""
    return count(value, minimum=0, none_ok=True).but(
        drop=("sequence",), shape_with_fraction=(2, 2.5), negative_shape=(2, -1)
    )


def law_point(value=0.5):
    """The argument of cdf/sf/pdf: any array of real numbers (NaN is refused, inf is not)."""
    return array(value, ndims="any", shaped=False, empty_ok=True).but(drop=("inf",))


def quantile_level(value=0.25):
    """The argument of ppf/isf: probabilities in [0, 1]."""
    return array(value, ndims="any", shaped=False, empty_ok=True).but(above_one=1.5, negative=-0.25)


TABLE = {
    # -- results ------------------------------------------------------------
    "TestResult": case(
        TestResult,
        name=fixed("z-test"),
        statistic=real(2.5).but(drop=("inf",)),  # an infinite statistic is possible (p = 0)
        alpha=probability(0.05),
        critical_value=real(1.6448536269514722),
        pvalue=Arg(
            0.006209665325776132,
            {
                "NaN": np.nan,
                "negative": -0.1,
                "above one": 1.5,
                "None": None,
                "text": "0.1",
                "contradicts the decision": 0.5,
            },
        ),
        reject=Arg(True, {"text": "no", "number": 2, "None": None, "contradicts statistic": False}),
        null=obj(stats.norm()),
        dof=Arg(None, {"NaN": np.nan, "text": "2", "negative": -1}),
        alternative=choice("greater"),
        details=Arg({}, {"list": [1.0], "text": "a"}),
    ),
    "TestResult.from_null": case(
        TestResult.from_null,
        name=fixed("z-test"),
        statistic=real(2.5).but(drop=("inf",)),
        null=obj(stats.norm()),
        alpha=probability(0.05),
        alternative=choice("two-sided"),
        dof=Arg(None, {"NaN": np.nan, "text": "2"}),
        details=Arg(None, {"list": [1.0], "text": "a"}),
    ),
    "TestResult.power": case(
        TestResult.from_null("z-test", 2.5, stats.norm(), 0.05).power,
        alternative_law=obj(stats.norm(loc=2.0)),
    ),
    "TestResult.summary": case(TestResult.from_null("z-test", 2.5, stats.norm(), 0.05).summary),
    "as_plain": case(results.as_plain, value=fixed((np.float64(6.0), np.int64(2)))),
    "critical_value": case(
        results.critical_value, null=obj(CHI2), alpha=probability(0.01), alternative=choice("less")
    ),
    "decide": case(
        results.decide,
        null=obj(CHI2),
        statistic=array([0.5, 12.0], ndims="any", shaped=False).but(drop=("inf",)),
        alpha=probability(0.01),
        alternative=choice("greater"),
    ),
    "describe_distribution": case(results.describe_distribution, dist=fixed(CHI2)),
    "format_number": case(
        results.format_number,
        value=Arg(0.0497870684, {}, extreme={"1e300": 1e300, "-1e-300": -1e-300}),
        digits=count(4),
    ),
    "rejection_probability": case(
        results.rejection_probability,
        law=obj(stats.norm(loc=3)),
        critical=Arg(
            (-1.96, 1.96),
            {
                "NaN": (np.nan, 1.96),
                "None": None,
                "scalar": 1.96,
                "three values": (1.0, 2.0, 3.0),
                "text": "ab",
            },
        ),
        alternative=choice("two-sided"),
    ),
    # -- distributions --------------------------------------------------------
    "FrozenDistribution": case(Uniform2),
    "FrozenDistribution.cdf": case(LAW.cdf, x=law_point()),
    "FrozenDistribution.sf": case(LAW.sf, x=law_point()),
    "FrozenDistribution.logcdf": case(LAW.logcdf, x=law_point()),
    "FrozenDistribution.logsf": case(LAW.logsf, x=law_point()),
    "FrozenDistribution.pdf": case(LAW.pdf, x=law_point()),
    "FrozenDistribution.ppf": case(LAW.ppf, q=quantile_level()),
    "FrozenDistribution.isf": case(LAW.isf, q=quantile_level()),
    "FrozenDistribution.support": case(LAW.support),
    "FrozenDistribution.median": case(LAW.median),
    "FrozenDistribution.interval": case(LAW.interval, confidence=quantile_level(0.9)),
    "FrozenDistribution.mean": case(LAW.mean),
    "FrozenDistribution.var": case(LAW.var),
    "FrozenDistribution.std": case(LAW.std),
    "FrozenDistribution.expect": case(
        LAW.expect,
        func=function(np.square, none_ok=True),
        lb=real(0.5, none_ok=True).but(drop=("inf",), above_ub=1.7),
        ub=real(1.5, none_ok=True).but(drop=("inf",)),
        conditional=Arg(True, {"text": "no", "number": 2}),
    ),
    "FrozenDistribution.rvs": case(LAW.rvs, size=size(), rng=generator()),
    "TailPair": case(
        TailPair,
        lower=obj(stats.norm(loc=-1)),
        upper=obj(stats.norm(loc=1)),
        joint_rvs=function(None, none_ok=True),
    ),
    "TailPair.cdf": case(PAIR.cdf, x=law_point()),
    "TailPair.sf": case(PAIR.sf, x=law_point()),
    "TailPair.ppf": case(PAIR.ppf, q=quantile_level()),
    "TailPair.isf": case(PAIR.isf, q=quantile_level()),
    "TailPair.rvs": case(PAIR.rvs, size=size(), rng=generator()),
}

EXEMPT = {
    "CriticalValues": "a named tuple the library returns",
    "Decision": "a named tuple the library returns",
    "Law": "a typing protocol, never called",
    "Law.cdf": "a typing protocol, never called",
    "Law.sf": "a typing protocol, never called",
    "Law.ppf": "a typing protocol, never called",
    "Law.isf": "a typing protocol, never called",
    "Law.rvs": "a typing protocol, never called",
}

(
    test_every_public_callable_has_cases,
    test_valid_call,
    test_bad_input_is_refused,
    test_extreme_input,
) = module_tests(("course.results", "course.distributions"), TABLE, EXEMPT)
