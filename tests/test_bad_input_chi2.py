"""Bad input to every public function of course.chi2 (see tests/bad_input.py)."""

from bad_input import array, case, count, module_tests, probability, scale

from course import chi2

TABLE = {
    "chi2_power": case(
        chi2.chi2_power,
        dof=count(3),
        noncentrality=array([0.0, 4.0], ndims="any", shaped=False, empty_ok=True).but(
            negative=[-1.0]
        ),
        alpha=probability(0.05),
    ),
    "noncentrality": case(
        chi2.noncentrality, alpha=probability(0.05), power=probability(0.8), dof=count(2)
    ),
    "residual_norm_law": case(chi2.residual_norm_law, dof=count(4), sigma=scale(0.5)),
    "residual_threshold": case(
        chi2.residual_threshold, dof=count(4), alpha=probability(0.05), sigma=scale(0.5)
    ),
}

(
    test_every_public_callable_has_cases,
    test_valid_call,
    test_bad_input_is_refused,
    test_extreme_input,
) = module_tests("course.chi2", TABLE, exempt={})
