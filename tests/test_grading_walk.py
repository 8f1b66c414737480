"""One structural walk for the three checks (course.grading.compare.StructuralWalk).

Grading compares with the expected value in the clear (:func:`compare`), the student's
self-check with a sealed one (:func:`sealed_compare`) or, where the student's copy holds no
expected value, with its type and shape only (:func:`check_signature`). All three walk the
structure the same way: here the same structural mismatch must give the same message through
each -- a fixed list of cases, and a hypothesis property that breaks the structure of a random
nested value at a random place -- so that they cannot drift apart. The messages that differ on
purpose (the seal has no near miss and cannot tell the worst element; a signature holds no
value, so it sees no mistake of value and no transposed matrix, and not the length of a list
of names) are pinned as different.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from course.grading.authoring.seal import make_salt, seal, sealed_compare
from course.grading.codec import Band
from course.grading.compare import check_signature, compare, signature

RTOL, ATOL = 1e-8, 1e-10
SALT = make_salt("tests", "walk")
Result = namedtuple("Result", ["statistic", "critical_value", "reject"])


def both(expected, got, path="r", mistakes=()):
    """The verdicts of grading and of the self-check (cheap hashes: the walk is under test)."""
    clear = compare(expected, got, RTOL, ATOL, path=path, mistakes=mistakes)
    sealed = sealed_compare(
        seal(expected, RTOL, ATOL, SALT, iterations=10),
        got,
        path=path,
        mistakes=[(m, seal(w, RTOL, ATOL, SALT + m, iterations=10)) for m, w in mistakes],
    )
    return clear, sealed


def by_signature(expected, got, path="r"):
    """The verdict of the self-check of a question whose expected value is not shipped."""
    return check_signature(signature(expected), got, path)


#: mistakes of value: a signature (type and shape, no value) cannot see them
VALUE_MISTAKES = {
    "differs only in upper/lower case or spaces",
    "the right items in another order",
    "transposed, rows and columns are swapped",
    "every decision",
    "1 of 3 wrong, first at",
    "3 of 3 wrong",
    "the opposite of the right decision",
    "1 of 3 wrong, first at [2]; not the right",
    "the sign is flipped",
    "r[1]: outside the accepted band",
}


MATRIX = np.array([[1.5, 2.0, 3.5], [3.0, 4.5, 6.25]])


@pytest.mark.parametrize(
    "expected, got, words",
    [
        (None, 0.0, "expected None, got a float"),
        ("Reject", 1.0, "expected a string, got a float"),
        ("Reject", np.zeros(3), "expected a string, got an array of shape (3,)"),
        ("Reject", "reject ", "differs only in upper/lower case or spaces"),
        ((1.5, 2.75), {"a": 1.5}, "expected a tuple of length 2, got a dict"),
        ([1.5, 2.75], (1.5, 2.75, 4.0), "expected length 2, got length 3: one item too many"),
        ((1.5, 2.75, 4.0, 5.0), [1.5], "expected length 4, got length 1"),
        ((1.5, "F1"), np.array([1.5, 2.0]), "expected a tuple of length 2, got an array"),
        (Result(6.1, 9.2, False), (6.1, 9.2, 0.5), "r.reject: expected bool, got a float"),
        (Result(6.1, 9.2, False), (6.1, 9.2), "expected length 3, got length 2: one item too few"),
        (Result(6.1, 9.2, False), "6.1", "expected a tuple (statistic, critical_value, reject)"),
        ((1.5, 2.75), (2.75, 1.5), "the right items in another order"),
        ({"a": 1.25, "b": [1, 2]}, [1.25], "expected a dict with keys ['a', 'b'], got a list"),
        ({"a": 1.25, "b": [1, 2]}, {"a": 1.25}, "expected keys ['a', 'b'], got ['a']"),
        ({"a": 1.25, "b": [1, 2]}, {"a": 1.25, "b": [1]}, "r['b']: expected length 2"),
        ({"a": (1.0, Result(1.0, 2.0, True))}, {"a": (1.0, (1.0, 2.0, 1j))}, "r['a'][1].reject"),
        (1.5, "1.5", "expected a float, got a string"),
        (MATRIX, MATRIX.ravel(), "expected shape (2, 3), got shape (6,) (the right number"),
        (MATRIX, MATRIX.T, "transposed, rows and columns are swapped"),
        (MATRIX[0], MATRIX[0, :2], "one element too few (off by one in a range or slice?)"),
        (np.array([True, False]), np.array([0.0, 1.0]), "expected bools, got an array"),
        (np.array([True, False, True]), np.array([False, True, False]), "every decision"),
        (np.array([True, False, True]), np.array([True, True, True]), "1 of 3 wrong, first at"),
        (True, False, "the opposite of the right decision"),
        (3, 2.5 + 1j, "expected integer, got a complex number"),
        (np.array([3, 7]), np.array([3.0, np.nan]), "expected integers, got an array"),
        (np.array([3, 7, 9]), np.array([4, 8, 10]), "3 of 3 wrong"),
        (np.array([3, 7, 9]), np.array([3, 7, 1]), "1 of 3 wrong, first at [2]; not the right"),
        (1.5, 1.5 + 1j, "expected real numbers, got complex"),
        (np.array([1.5, 2.25]), np.array([1.5, np.nan]), "got NaN at [1] (a 0/0"),
        (np.array([1.5, 2.25]), np.array([np.inf, 2.25]), "got inf at [0] (a division by zero?)"),
        (-2.25, 2.25, "the sign is flipped"),
        (Band(0.04, 0.06), "0.05", "expected a real number, got a string"),
        (Band(0.04, 0.06), 0.05j, "expected a real number, got a complex number"),
        (Band(0.04, 0.06), float("nan"), "r: got NaN"),
        ((Band(0.04, 0.06), Band(0.3, 0.35)), (0.05, 0.5), "r[1]: outside the accepted band"),
    ],
)
def test_a_mismatch_reads_the_same_in_grading_and_in_the_self_check(expected, got, words):
    clear, sealed = both(expected, got)
    assert not clear.ok and not sealed.ok
    assert words in clear.message, clear.message
    assert sealed.message == clear.message
    if words not in VALUE_MISTAKES:
        assert by_signature(expected, got).message == clear.message


@pytest.mark.parametrize(
    "expected, got",
    [
        (["F1", "F3"], ["F1", 3]),
        ({"d": ["F1"], "x": 1.0}, {"d": [None], "x": 1.0}),
        ([1.5, 2.75], 1.5),
        ([[1.5, 2.0], 3], [[1.5], 3]),
        ((np.arange(2), 1), (np.arange(2.0), "1")),
        ((np.arange(2), 1), (np.arange(2.0), 1j)),
    ],
)
def test_a_signature_reads_a_mismatch_as_grading_does(expected, got):
    """More structures through all three: lists of names, plain lists, integers."""
    clear, sealed = both(expected, got)
    sig = by_signature(expected, got)
    assert not clear.ok and not sig.ok
    assert sig.message == sealed.message == clear.message


def test_a_signature_accepts_what_grading_accepts_of_its_kind():
    """check_signature refused 0/1 integers for a decision, an array for a tuple of Monte
    Carlo rates and an array of rates for one rate, which grading's walk accepts."""
    for expected, right in [
        (True, 1),
        (np.array([True, False]), np.array([1, 0])),
        ((Band(0.04, 0.06), Band(0.30, 0.35)), np.array([0.05, 0.32])),
        (Band(0.04, 0.06), np.array([0.05, 0.05])),
    ]:
        assert all(v.ok for v in both(expected, right))
        assert by_signature(expected, right).ok


def test_the_messages_that_differ_on_purpose():
    """The seal cannot tell a near miss (it would let checks.json be searched at a coarse
    precision first) nor which wrong element is worst (it names the first)."""
    clear, sealed = both(3.0, 3.0000001)
    assert "close: it agrees to about 7 significant digits" in clear.message
    assert "close" not in sealed.message and "not within the tolerance" in sealed.message
    clear, sealed = both(np.array([1.0, 2.0, 3.0]), np.array([1.0, 2.5, 3.9]))
    assert "2 of 3 elements wrong, the worst at [2]" in clear.message
    assert "2 of 3 elements wrong, the first at [1]" in sealed.message
    # a signature holds no value: a transposed matrix is a reshape to it
    clear, sealed = both(MATRIX, MATRIX.T)
    assert "transposed" in clear.message and sealed.message == clear.message
    assert by_signature(MATRIX, MATRIX.T).message == (
        "r: expected shape (2, 3), got shape (3, 2) (the right number of elements: reshape, "
        "ravel or a missing [:, 0]?)"
    )
    # nor the length of a list of names (the length of a diagnosis is part of the answer)
    assert by_signature(["F1", "F3"], ["F2"]).ok
    assert by_signature(["F1", "F3"], "F1").message == "r: expected a list of strings, got a string"
    assert "expected a list of length 2, got a string" in compare(["F1", "F3"], "F1").message
    # a fraction where an integer is asked is not an integer at all, whatever the value
    assert by_signature(3, 2.5).message == "r: expected integer, got a float"
    assert by_signature(np.arange(3), [0, 1.5, 2]).message.startswith("r: expected integers")


def test_a_string_answered_by_an_array_is_a_message_not_a_crash():
    """compare raised 'The truth value of an array ... is ambiguous' (it tried got == expected
    before asking whether got is a string); the self-check said 'expected a string'."""
    clear, sealed = both("F2", np.array(["F2", "F3"]))
    assert (
        clear.message == sealed.message == "r: expected a string, got an array of shape (2,) (<U2)"
    )


def test_an_array_answers_a_tuple_of_rates_in_grading_as_in_the_self_check():
    """A 1-D real array answers a tuple of numbers, and a Monte Carlo rate (a band) is one
    number: the self-check accepted np.array([rate, rate]) where grading refused it, and named
    a declared mistake holding a band that grading never named."""
    expected = (Band(0.04, 0.06), Band(0.30, 0.35))
    assert all(v.ok for v in both(expected, np.array([0.05, 0.32])))
    mistakes = [("rate_last is alpha itself", (0.05, Band(0.0, 1.0)))]
    clear, sealed = both((0.052, 0.4), np.array([0.05, 0.5]), mistakes=mistakes)
    assert clear.message == sealed.message == "r: rate_last is alpha itself"


# -- the property: break the structure anywhere, read the same message --------------------
_leaves = st.one_of(
    st.floats(0.1, 100.0).map(lambda x: round(x, 3)),
    st.integers(-50, 50),
    st.booleans(),
    st.sampled_from(["F1", "NF", "Reject"]),
    st.none(),
    st.sampled_from([(2,), (3,), (2, 2), (2, 3)]).map(
        lambda shape: np.arange(1.0, 1.0 + np.prod(shape)).reshape(shape) * 1.25
    ),
    st.just(Band(0.04, 0.06)),
)
_values = st.recursive(
    _leaves,
    lambda inner: st.one_of(
        st.lists(inner, min_size=1, max_size=3),
        st.lists(inner, min_size=1, max_size=3).map(tuple),
        st.dictionaries(st.sampled_from(["a", "b", "c"]), inner, min_size=1, max_size=3),
    ),
    max_leaves=6,
)


def _places(value, at=()):
    """The path of every node of ``value`` (the value itself first)."""
    out = [at]
    if isinstance(value, (tuple, list)):
        for k, v in enumerate(value):
            out += _places(v, (*at, k))
    elif isinstance(value, dict):
        for k, v in value.items():
            out += _places(v, (*at, k))
    return out


def _right(value):
    """A right answer: the value itself, a band's midpoint for a band."""
    if isinstance(value, Band):
        return (value.lo + value.hi) / 2
    if isinstance(value, (tuple, list)):
        return type(value)(_right(v) for v in value)
    if isinstance(value, dict):
        return {k: _right(v) for k, v in value.items()}
    return value


def _broken(value, how: int):
    """``value`` with its structure or kind broken (never only its numbers)."""
    if isinstance(value, (tuple, list)):
        return [
            type(value)(_right(value)[:-1]),
            type(value)([*_right(value), 1.0]),
            {"a": 1.0},
            "F1",
        ][how % 4]
    if isinstance(value, dict):
        first = sorted(value)[0]
        return [
            {k: _right(v) for k, v in value.items() if k != first},
            {**_right(value), "z": 1.0},
            [1.0],
            None,
        ][how % 4]
    if isinstance(value, np.ndarray):
        return [value.ravel() if value.ndim > 1 else value[:-1], value[None], value + 1j, "x"][
            how % 4
        ]
    if isinstance(value, Band):
        return ["0.05", 0.05j, None, np.array([0.05, 0.5])][how % 4]
    if value is None:
        return [0.0, "None", (), np.zeros(1)][how % 4]
    if isinstance(value, str):
        return [1.0, None, np.zeros(2), [value]][how % 4]
    if isinstance(value, bool):
        return [0.5, "True", None, np.array([value, value])][how % 4]
    return [str(value), None, complex(value, 1.0), np.array([value, value])][how % 4]


def _names(node) -> bool:
    """A list of names: its signature holds no length (see compare.signature)."""
    return isinstance(node, (tuple, list)) and bool(node) and all(isinstance(v, str) for v in node)


def _replace(value, at, new):
    if not at:
        return new
    k, rest = at[0], at[1:]
    if isinstance(value, dict):
        return {key: _replace(v, rest, new) if key == k else _right(v) for key, v in value.items()}
    items = [_replace(v, rest, new) if i == k else _right(v) for i, v in enumerate(value)]
    return type(value)(*items) if hasattr(value, "_fields") else type(value)(items)


@settings(max_examples=200, deadline=None, derandomize=True, database=None)
@given(value=_values, data=st.data())
def test_a_broken_structure_reads_the_same_in_grading_and_in_the_self_check(value, data):
    assert all(v.ok for v in both(value, _right(value)))
    places = _places(value)
    at = places[data.draw(st.integers(0, len(places) - 1), label="place")]
    node = value
    for k in at:
        node = node[k]
    broken = _broken(node, data.draw(st.integers(0, 3), label="how"))
    got = _replace(value, at, broken)
    clear, sealed = both(value, got)
    assert not clear.ok and not sealed.ok, (clear, sealed)
    assert sealed.message == clear.message
    assert by_signature(value, _right(value)).ok
    sig = by_signature(value, got)
    if _names(node):  # its signature holds no length: any list of strings is of its type
        names = isinstance(broken, (tuple, list)) and all(isinstance(v, str) for v in broken)
        assert sig.ok == names, sig
        return
    if isinstance(node, Band) and isinstance(broken, np.ndarray):
        assert sig.ok  # an array of rates for one rate: outside the band, not a wrong kind
        return
    assert sig.message == clear.message


# -- the tolerance rule at its boundary (issue 26, item 6) --------------------------------
# |got - expected| <= atol + rtol*|expected|: just inside passes, just outside fails, so that a
# rule loosened (a doubled tolerance) or tightened (a halved one, < instead of <=) fails here.
_TOLERANCES = [
    pytest.param(1e-7, 0.0, id="rtol only"),
    pytest.param(0.0, 1e-9, id="atol only"),
    pytest.param(1e-6, 1e-9, id="both"),
    pytest.param(1e-4, 1e-12, id="loose rtol"),
]


@pytest.mark.parametrize(("rtol", "atol"), _TOLERANCES)
@pytest.mark.parametrize("expected", [3.7, -0.0123, 2.5e5, 0.0])
@pytest.mark.parametrize("side", [1.0, -1.0])
def test_the_tolerance_rule_holds_at_its_boundary(rtol, atol, expected, side):
    tol = atol + rtol * abs(expected)
    if tol == 0.0:
        pytest.skip("no tolerance: exact equality, tested elsewhere")
    inside, outside = expected + side * 0.98 * tol, expected + side * 1.02 * tol
    assert compare(expected, inside, rtol, atol).ok
    assert not compare(expected, outside, rtol, atol).ok
    # element-wise in arrays: one element just outside fails the whole answer
    e = np.array([expected, 1.0, -2.0])
    t = atol + rtol * np.abs(e)
    assert compare(e, e + side * 0.98 * t, rtol, atol).ok
    just_out = e + side * 0.98 * t
    just_out[0] = outside
    assert not compare(e, just_out, rtol, atol).ok


def test_the_tolerance_boundary_itself_passes():
    """``<=``: a difference of exactly the tolerance (representable: atol only) passes."""
    assert compare(1.0, 1.5, 0.0, 0.5).ok
    assert compare(1.0, 0.5, 0.0, 0.5).ok
    assert not compare(1.0, np.nextafter(1.5, 2.0), 0.0, 0.5).ok


@pytest.mark.parametrize(
    "band",
    [Band(0.25, 0.75), Band(np.array([0.1, 0.2]), np.array([0.3, 0.4]))],
    ids=["a number", "per element"],
)
def test_a_band_holds_its_ends_and_nothing_beyond(band):
    lo, hi = np.asarray(band.lo, float), np.asarray(band.hi, float)
    assert compare(band, lo if lo.ndim else float(lo)).ok
    assert compare(band, hi if hi.ndim else float(hi)).ok
    assert compare(band, (lo + hi) / 2 if lo.ndim else float((lo + hi) / 2)).ok
    below = np.nextafter(lo, -np.inf)
    above = np.nextafter(hi, np.inf)
    for wrong in (below, above):
        assert not compare(band, wrong if wrong.ndim else float(wrong)).ok
    # a band does not take the question's tolerance: just outside fails whatever rtol/atol say
    assert not compare(band, above if above.ndim else float(above), 1e-3, 1e-3).ok


# -- feedback never gives the answer away as a ratio (issue 26, items 4/5) ----------------
@pytest.mark.parametrize(
    ("expected", "got"),
    [
        (14, 16),  # 04 q7: "too large by a factor ≈ 1.14 (= 8/7)" gave 14 away
        ((14, 0), (16, 0)),
        (np.array([37, 38]), np.array([40, 40])),  # 02 q4: dof from the columns
        (38, 40),
    ],
)
def test_integer_feedback_names_no_factor(expected, got):
    message = compare(expected, got, RTOL, ATOL).message
    assert message and "factor" not in message and "/" not in message.split(";")[0], message


def test_float_feedback_names_no_revealing_ratio():
    """06 q3: (M - 1)/M against M/(M - 1) was told "(= 16/9)"; only the ratios of common
    slips (as the seal names them) are spelled out."""
    e = 0.75 * 2.345
    assert "16/9" not in compare(e, 2.345 * 4 / 3, RTOL, ATOL).message
    assert "(= 4/3)" in compare(e, e * 4 / 3, RTOL, ATOL).message
    assert "(= 3/2)" in compare(e, e * 1.5, RTOL, ATOL).message


def test_an_array_of_strings_is_told_to_be_a_list():
    """02 q1 answered with np.array(['F1', 'F2']) was told "(use numbers or booleans)"."""
    from course.grading.codec import EncodingError, encode

    with pytest.raises(EncodingError, match="list of strings"):
        encode(np.array(["F1", "F2"]))
    assert encode(["F1", "F2"]) == ["F1", "F2"]
