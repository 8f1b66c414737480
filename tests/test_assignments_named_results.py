"""Results with several parts are named tuples in every assignment (issue 13).

A reference that returns ``(T, critical_value, reject)`` as a plain tuple makes the feedback say
``item [1]``; as a named tuple it says ``critical_value``, the name the question text uses. A
student's plain tuple or list in the same order stays right: the grader compares item by item.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from course.grading.authoring.checks import load_checks
from course.grading.authoring.seal import make_salt, seal, sealed_compare
from course.grading.compare import check_signature, compare, signature

ROOT = Path(__file__).resolve().parents[1]
NAMES = sorted(p.name for p in (ROOT / "solutions").iterdir() if (p / "checks.py").is_file())


@pytest.fixture(scope="module", params=NAMES)
def checks(request):
    return load_checks(ROOT / "solutions" / request.param)


def _expected(checks, q):
    """The reference's answer: the first public case, or the demo student's data."""
    if q.kind == "function":
        return q.expected(q.public_cases[0])
    if q.data is not None:
        return q.expected(data=checks.data_for(q.data, "demo"))
    return q.expected()


def _is_names(value) -> bool:
    """A list of mode names (a diagnosis): its length is part of the answer, it has no fields."""
    return all(isinstance(v, str) for v in value)


def test_no_multi_part_result_is_a_plain_tuple(checks):
    plain, named = [], 0
    for q in checks.questions.values():
        if q.kind not in ("value", "function"):
            continue
        value = _expected(checks, q)
        if not isinstance(value, (tuple, list)) or len(value) < 2 or _is_names(value):
            continue
        if getattr(type(value), "_fields", None):
            named += 1
        else:
            plain.append(f"{q.id} returns a plain {type(value).__name__} of {len(value)}")
    assert not plain, "name the parts (collections.namedtuple):\n" + "\n".join(plain)
    assert named > 0, "every assignment has a question with a multi-part result"


# One question per assignment whose wrong part the feedback must name.
FIELD_CASES = [
    ("01_least_squares", "q3", "critical_value"),
    ("02_test_quantities", "q4", "dof"),
    ("03_estimation_and_likelihood", "q1", "s"),
    ("04_ekf_residuals", "q5_practice", "first_alarm"),
    ("05_nis_wishart", "q5", "lmax"),
    ("06_mismatched_filters", "q4", "c_jk"),
]


def _spoil(value):
    if isinstance(value, (bool, np.bool_)):
        return not value
    if isinstance(value, (int, np.integer)):
        return int(value) + 1
    return 2.0 * np.asarray(value) + 1.0


@pytest.mark.parametrize(("name", "qid", "field"), FIELD_CASES)
def test_feedback_names_the_wrong_field(name, qid, field):
    checks = load_checks(ROOT / "solutions" / name)
    q = checks.questions[qid]
    expected = _expected(checks, q)
    k = type(expected)._fields.index(field)
    answer = list(expected)
    answer[k] = _spoil(answer[k])
    verdict = compare(expected, tuple(answer), q.rtol, q.atol, reveal=False)
    assert not verdict.ok
    assert verdict.message.startswith(f"{field}:"), verdict.message
    assert "item [" not in verdict.message


@pytest.mark.parametrize("name", NAMES)
def test_a_plain_tuple_or_list_in_order_is_right(name):
    checks = load_checks(ROOT / "solutions" / name)
    n = 0
    for q in checks.questions.values():
        if q.kind not in ("value", "function"):
            continue
        expected = _expected(checks, q)
        if not getattr(type(expected), "_fields", None):
            continue
        for answer in (tuple(expected), list(expected)):
            assert compare(expected, answer, q.rtol, q.atol).ok, (q.id, type(answer))
        n += 1
    assert n > 0


def test_a_numpy_array_in_order_is_right_for_a_pair_of_floats():
    # np.array([lo, hi]) for (lower, upper) is a right answer written differently: at grading
    # (true reference) and in the sealed self-check a student runs
    checks = load_checks(ROOT / "solutions" / "05_nis_wishart")
    q = checks.questions["q3"]
    expected = q.expected(q.public_cases[0])
    answer = np.array(expected)
    assert compare(expected, answer, q.rtol, q.atol).ok
    sealed = seal(expected, q.rtol, q.atol, make_salt("test", "q3"))
    assert sealed_compare(sealed, answer).ok
    assert check_signature(signature(expected), answer).ok
    wrong = answer * np.array([1.0, 2.0])
    assert not compare(expected, wrong, q.rtol, q.atol).ok
    verdict = sealed_compare(sealed, wrong)
    assert not verdict.ok and verdict.message.startswith(f"{expected._fields[1]}:")


def test_an_answer_of_the_wrong_type_is_told_the_fields_not_a_class_name():
    checks = load_checks(ROOT / "solutions" / "05_nis_wishart")
    q = checks.questions["q3"]
    expected = q.expected(q.public_cases[0])
    wanted = f"expected a tuple ({', '.join(expected._fields)})"
    sealed = seal(expected, q.rtol, q.atol, make_salt("test", "q3"))
    for verdict in (
        compare(expected, 1.0, q.rtol, q.atol),
        sealed_compare(sealed, 1.0),
        check_signature(signature(expected), 1.0),
    ):
        assert not verdict.ok and wanted in verdict.message, verdict.message
    # an array cannot stand for results of mixed kinds (a decision is not a number)
    q5 = checks.questions["q5"]
    mixed = q5.expected(q5.public_cases[0])  # (lmin, lmax, reject)
    assert not compare(mixed, np.array(mixed, dtype=float), q5.rtol, q5.atol).ok
