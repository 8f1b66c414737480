"""Sealed public checks (course.grading.authoring.seal): ``checks.json`` holds no answer.

- a scan of every released ``exercises/*/checks.json``: every tagged value decoded, no
  reference value of any graded question (public, hidden or the demo student's, and no
  declared mistake's value) appears in it within that question's tolerance;
- the seal's bands: everything within the tolerance passes, everything beyond
  :func:`stated_band` fails (boundary cases and a hypothesis property);
- the kind-of-wrong diagnoses and declared mistakes still fire without the expected value;
- an older ``checks.json`` (format 1, values in the clear) is refused with a clear message.
"""

from __future__ import annotations

import functools
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from value_leaves import leaves

from course.grading.authoring.release import find_solutions
from course.grading.authoring.seal import (
    is_sealed,
    make_salt,
    matches,
    seal,
    sealed_compare,
    stated_band,
)
from course.grading.codec import Band, decode
from course.grading.compare import compare

ROOT = Path(__file__).resolve().parents[1]
ASSIGNMENTS = find_solutions(ROOT / "solutions")
_CODEC_TAGS = ("__ndarray__", "__float__", "__complex__")


# -- the scan ---------------------------------------------------------------------------------
def file_leaves(data) -> list:
    """Every number and string of a checks.json, codec-tagged arrays and floats decoded."""
    out: list = []
    if isinstance(data, dict):
        if len(data) == 1 and next(iter(data)) in _CODEC_TAGS:
            return leaves(decode(data), out)
        for key, v in data.items():
            if key == "step" and "band" in data:
                continue  # a sealed band's cell width: (hi - lo)/16, public by design
            out.append(key)
            out += file_leaves(v)
    elif isinstance(data, list):
        for v in data:
            out += file_leaves(v)
    else:
        out.append(data)
    return out


def _distinctive(x: float, tol: float) -> bool:
    """A number that cannot turn up by chance as a shape, a count or a stated parameter: no
    round number (two significant digits, zero included) lies within its tolerance."""
    if not math.isfinite(x) or abs(x) <= tol:
        return False
    scale = 10.0 ** (math.floor(math.log10(abs(x))) - 1)
    return abs(x - round(x / scale) * scale) > tol


@functools.cache
def graded_references(name: str) -> list[tuple[str, object, float, float]]:
    """(where, value, rtol, atol) for every reference a grade depends on: each case of every
    function question, every value question (with the demo student's data where personal),
    and every declared mistake's value."""
    from course.grading.authoring.checks import load_checks
    from course.grading.vocabulary import DEMO_STUDENT_ID

    checks = load_checks(ROOT / "solutions" / name)
    out = []
    for q in checks.questions.values():
        if q.kind == "function":
            for i, case in enumerate(q.public_cases + q.hidden_cases):
                out.append((f"{q.id} case {i}", q.expected(case), q.rtol, q.atol))
                for m, v in q.mistaken(case):
                    out.append((f"{q.id} case {i} mistake {m[:30]!r}", v, q.rtol, q.atol))
        elif q.kind == "value":
            data = checks.data_for(q.data, DEMO_STUDENT_ID) if q.data else None
            out.append((q.id, q.expected(data=data), q.rtol, q.atol))
            for m, v in q.mistaken(data=data):
                out.append((f"{q.id} mistake {m[:30]!r}", v, q.rtol, q.atol))
    return out


def answers_in_file(name: str, folder: Path) -> list[str]:
    """Every reference value of ``name`` found among the leaves of ``folder/checks.json``."""
    data = json.loads((folder / "checks.json").read_text("utf-8"))
    shipped = file_leaves(data)
    numbers = np.array(
        [float(x) for x in shipped if isinstance(x, (int, float)) and not isinstance(x, bool)]
        + [c.real for c in shipped if isinstance(c, complex)]
    )
    strings = {x for x in shipped if isinstance(x, str)}
    options = {
        str(o) for q in data["questions"] for o in leaves(decode(q.get("options") or []), [])
    }
    # a function case's inputs are public by construction: an expected number equal to one of
    # its own question's inputs (a variance that is an input squared back) gives nothing away
    inputs = {
        q["id"]: np.array(
            [
                float(x)
                for c in q["cases"]
                for x in file_leaves([c.get("args"), c.get("kwargs")])
                if isinstance(x, (int, float)) and not isinstance(x, bool)
            ]
        )
        for q in data["questions"]
    }
    input_strings = {  # likewise a name among the inputs (a mode of a structure)
        q["id"]: {
            x
            for c in q["cases"]
            for x in file_leaves([c.get("args"), c.get("kwargs")])
            if isinstance(x, str)
        }
        for q in data["questions"]
    }
    found = []
    for where, value, rtol, atol in graded_references(name):
        own = inputs.get(where.split()[0], np.array([]))
        own_strings = input_strings.get(where.split()[0], set())
        for leaf in leaves(value, []):
            if isinstance(leaf, str):
                if len(leaf) >= 2 and leaf in strings and leaf not in options | own_strings:
                    found.append(f"{where}: the string {leaf!r}")
            elif isinstance(leaf, (int, float, complex)) and not isinstance(leaf, bool):
                x = leaf.real if isinstance(leaf, complex) else float(leaf)
                tol = max(atol + rtol * abs(x), 1e-12 * abs(x))
                if not _distinctive(x, tol) or not numbers.size:
                    continue
                if own.size and np.any(np.abs(own - x) <= tol):
                    continue
                hits = numbers[np.abs(numbers - x) <= tol]
                if hits.size:
                    found.append(f"{where}: {x!r} appears as {hits[0]!r}")
    return found


@pytest.mark.parametrize("name", ASSIGNMENTS)
def test_released_checks_hold_no_graded_answer(name):
    found = answers_in_file(name, ROOT / "exercises" / name)
    assert not found, f"{len(found)} answers in exercises/{name}/checks.json:\n" + "\n".join(
        found[:30]
    )


@pytest.mark.parametrize("name", ASSIGNMENTS)
def test_the_scan_finds_answers_shipped_in_the_clear(name, tmp_path):
    """The scan is not blind: with the public values encoded by the codec, as format 1 shipped
    them, it finds every public value, and the first public case of every function question,
    that has a distinctive number or string."""
    from course.grading.authoring.checks import load_checks
    from course.grading.codec import encode
    from course.grading.vocabulary import DEMO_STUDENT_ID

    checks = load_checks(ROOT / "solutions" / name)
    data = json.loads((ROOT / "exercises" / name / "checks.json").read_text("utf-8"))
    options = {
        str(o) for q in data["questions"] for o in leaves(decode(q.get("options") or []), [])
    }  # public text (mode names): the scan leaves them out
    wanted = set()
    for entry in data["questions"]:
        q = checks.questions[entry["id"]]
        if q.kind in ("value", "function") and entry["cases"]:
            if q.kind == "function":  # its first public case (issue 26: most questions are)
                value = q.expected(q.public_cases[0])
            else:
                personal = checks.data_for(q.data, DEMO_STUDENT_ID) if q.data else None
                value = q.expected(data=personal)
            entry["cases"][0]["expected"] = encode(value)
            # an item equal to one of the question's own (public) inputs is no answer
            own = file_leaves([[c.get("args"), c.get("kwargs")] for c in entry["cases"]])
            own_numbers = [float(x) for x in own if isinstance(x, (int, float))]
            if any(
                (len(x) >= 2 and x not in options and x not in own)
                if isinstance(x, str)
                else _distinctive(float(x), q.atol + q.rtol * abs(x) + 1e-12 * abs(x))
                and float(x) not in own_numbers
                for x in leaves(value, [])
                if not isinstance(x, (bool, complex)) and x is not None
            ):
                wanted.add(q.id)
    (tmp_path / "checks.json").write_text(json.dumps(data))
    found = {f.split(":")[0].split(" ")[0] for f in answers_in_file(name, tmp_path)}
    assert wanted and wanted <= found, sorted(wanted - found)


def test_every_public_case_is_sealed():
    for name in ASSIGNMENTS:
        data = json.loads((ROOT / "exercises" / name / "checks.json").read_text("utf-8"))
        assert data["format"] == 2
        for q in data["questions"]:
            for case in q["cases"]:
                assert is_sealed(case["expected"]), (name, q["id"])
                assert all(is_sealed(v) for _, v in case.get("mistakes", [])), (name, q["id"])


def test_older_format_is_refused_with_a_clear_message(tmp_path):
    from course.grading.student.selfcheck import Assignment

    data = json.loads((ROOT / "exercises" / "01_least_squares" / "checks.json").read_text())
    data["format"] = 1
    (tmp_path / "checks.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match=r"format 1 .*older release.*course release --all"):
        Assignment.load("01_least_squares", student_id="s1", path=tmp_path)


# -- the bands of the seal --------------------------------------------------------------------
SALT = make_salt("tests", "seal")


def _ok(expected, got, rtol=1e-8, atol=1e-10) -> bool:
    return sealed_compare(seal(expected, rtol, atol, SALT), got).ok


@pytest.mark.parametrize(
    "e, rtol, atol",
    [
        (0.5477225575051661, 1e-8, 1e-8),
        (-3.75, 1e-6, 1e-9),
        (0.0, 1e-7, 1e-9),
        (1e300, 1e-8, 0.0),
        (-1e-300, 1e-8, 0.0),
        (2.0**10, 1e-8, 1e-10),  # exactly on a binade and a grid line
        (12.0, 0.0, 5e-6),  # atol only
        (6.103515625e-05, 1e-4, 1e-8),
    ],
)
def test_tolerance_edge_passes_and_stated_band_fails(e, rtol, atol):
    sealed = seal(e, rtol, atol, SALT)
    tol = atol + rtol * abs(e)
    for s in (e, e + tol, e - tol, np.nextafter(e + tol, e), e + 0.999 * tol, e - 0.5 * tol):
        assert sealed_compare(sealed, float(s)).ok, (e, s)
    band = stated_band(e, rtol, atol)
    assert band >= tol
    for s in (e + band * 1.001 + 1e-300, e - band * 1.001 - 1e-300, e + 10 * band + 1e-300):
        if s != e:
            assert not sealed_compare(sealed, float(s)).ok, (e, s)


def test_values_at_grid_lines():
    """Right answers whose cell differs from the expected value's (a grid line between them)
    pass whichever side they fall: the neighbours are tried."""
    rtol, atol = 1e-6, 1e-9
    rng = np.random.default_rng(1)
    for e in rng.uniform(-100, 100, 200):
        sealed = seal(float(e), rtol, atol, SALT)
        tol = atol + rtol * abs(e)
        for s in np.linspace(e - tol, e + tol, 9):
            assert sealed_compare(sealed, float(s)).ok


def test_exact_kinds():
    assert _ok(3, 3) and _ok(3, 3.0) and _ok(3, np.int64(3)) and not _ok(3, 4)
    assert not _ok(3, 3.5)
    assert _ok(True, True) and not _ok(True, False) and _ok(False, np.False_)
    assert _ok("F2", "F2") and not _ok("F2", "F3")
    assert _ok(None, None) and not _ok(None, 0.0)
    assert _ok(np.array([1, 2, 3]), [1, 2, 3]) and not _ok(np.array([1, 2, 3]), [1, 2, 4])
    assert _ok(0.25, 0.25, 0.0, 0.0) and not _ok(0.25, 0.25 + 1e-16, 0.0, 0.0)
    assert _ok(1 + 2j, 1 + 2j + 1e-12) and not _ok(1 + 2j, 1 - 2j)


def test_nan_inf_and_zero():
    assert _ok(float("nan"), float("nan")) and not _ok(float("nan"), 0.0)
    assert _ok(np.array([1.0, np.nan]), [1.0, np.nan])
    assert not _ok(1.0, float("nan")) and not _ok(1.0, float("inf"))
    assert _ok(float("inf"), float("inf")) and not _ok(float("inf"), -float("inf"))
    assert _ok(0.0, 0.0) and _ok(0.0, -0.0) and _ok(0.0, 5e-11) and not _ok(0.0, 1e-6)
    assert _ok(0.0, 0.0, 1e-8, 0.0) and not _ok(0.0, 1e-300, 1e-8, 0.0)


def test_structure_in_the_clear_values_sealed():
    from collections import namedtuple

    Result = namedtuple("Result", ["statistic", "critical_value", "reject"])
    value = Result(6.123456, 9.210340, False)
    sealed = seal(value, 1e-7, 1e-9, SALT)
    text = json.dumps(sealed)
    assert "critical_value" in text and "6.12" not in text and "9.21" not in text
    assert sealed_compare(sealed, Result(6.123456, 9.210340, False)).ok
    assert sealed_compare(sealed, (6.123456, 9.210340, False)).ok
    v = sealed_compare(sealed, (6.123456, 9.5, False), path="r")
    assert not v.ok and "r.critical_value" in v.message and "9.21" not in v.message
    assert (
        "the right items in another order"
        in sealed_compare(seal((1.5, 2.75), 1e-7, 1e-9, SALT), (2.75, 1.5)).message
    )
    d = seal({"a": 1.25, "b": [1, 2]}, 1e-7, 1e-9, SALT)
    assert sealed_compare(d, {"a": 1.25, "b": [1, 2]}).ok
    assert "expected keys" in sealed_compare(d, {"a": 1.25}).message


@pytest.mark.parametrize(
    "e, got, words",
    [
        (np.array([[1.0, 2.0], [3.0, 4.5]]), lambda e: e.T, "transposed"),
        (np.array([[1.0, 2.0, 3.5], [3.0, 4.5, 6.25]]), lambda e: e.T, "transposed"),
        (np.array([1.5, -2.25, 3.0]), lambda e: -e, "the sign is flipped"),
        (np.array([1.5, -2.25, 3.0]), lambda e: 2 * e, "too large by a factor ≈ 2.0"),
        (0.7320508, lambda e: e / 2, "too small by a factor ≈ 2.0"),
        (0.7320508, lambda e: e * 4 / 3, "too large by a factor ≈ 1.33 (= 4/3)"),
        (np.array([1.5, -2.25, 3.0]), lambda e: e[::-1], "reverse order"),
        (np.array([1.5, -2.25, 3.0, 7.0]), lambda e: e[[1, 0, 3, 2]], "a permutation"),
        (np.array([1.5, 2.25]), lambda e: e**2, "the square of the answer"),
        (np.array([1.5, 2.25]), lambda e: np.sqrt(e), "square root"),
        (np.array([1.5, 2.25]), lambda e: np.zeros(2), "all zeros"),
        (np.array([1.5, 2.25]), lambda e: np.array([1.5, np.nan]), "got NaN at [1]"),
        (np.array([1.5, 2.25, 4.0]), lambda e: e[:2], "one element too few"),
        (np.array([True, False]), lambda e: ~e, "every decision is the opposite"),
        ("Reject", lambda e: "reject ", "differs only in upper/lower case or spaces"),
    ],
)
def test_kind_of_wrong_without_the_expected_value(e, got, words):
    v = sealed_compare(
        seal(e, 1e-8, 1e-10, SALT), got(np.asarray(e) if not isinstance(e, str) else e)
    )
    assert not v.ok and words in v.message, v.message


@pytest.mark.parametrize(
    "e, got",
    [(4, 5), (4, 3), (np.array([3, 7, 9]), np.array([4, 8, 10])), (np.array([0, 3]), [-1, 2])],
)
def test_an_integer_answer_is_not_named_by_its_neighbour(e, got):
    """Issue 26: "off by one: one too large" told a student the index (got - 1); an integer
    answer gets no relation to the right one, in the self-check as at grading."""
    for v in (sealed_compare(seal(e, 0, 0, SALT), got), compare(e, got, 0, 0)):
        assert not v.ok
        assert "one too" not in v.message and "off by one" not in v.message, v.message


def test_declared_mistake_fires_on_a_match():
    e, one_sided = 1.959963984540054, 1.6448536269514722
    sealed = seal(e, 1e-7, 1e-10, SALT)
    mistakes = [
        ("looks one-sided: z_alpha instead of z_alpha/2", seal(one_sided, 1e-7, 1e-10, "m"))
    ]
    v = sealed_compare(sealed, 1.6448536269514722, path="z", mistakes=mistakes)
    assert not v.ok and v.message == "z: looks one-sided: z_alpha instead of z_alpha/2"
    assert sealed_compare(sealed, e, mistakes=mistakes).ok
    assert "one-sided" not in sealed_compare(sealed, 1.7, mistakes=mistakes).message
    assert matches(mistakes[0][1], one_sided)


def test_band_sealed():
    band = Band(0.0414, 0.0591)
    sealed = seal(band, 0.0, 5e-6, SALT)
    assert "0.04" not in json.dumps(sealed) and "0.059" not in json.dumps(sealed)
    width = 0.0591 - 0.0414
    for x in np.linspace(0.0414, 0.0591, 50):
        assert sealed_compare(sealed, float(x)).ok
    for x in (0.0414 - width / 16 * 1.01, 0.0591 + width / 16 * 1.01, 0.05 * 2, float("nan")):
        assert not sealed_compare(sealed, x).ok
    pair = seal((Band(0.04, 0.06), Band(0.30, 0.35)), 0.0, 5e-6, SALT)
    assert sealed_compare(pair, (0.05, 0.32)).ok
    assert "outside the accepted band" in sealed_compare(pair, (0.05, 0.4)).message


def test_shape_mismatch_names_shapes_only():
    sealed = seal(np.arange(6.0).reshape(2, 3) + 0.5, 1e-8, 1e-10, SALT)
    v = sealed_compare(sealed, np.zeros(6), path="P")
    assert "expected shape (2, 3), got shape (6,)" in v.message and "reshape" in v.message


def test_a_right_answer_costs_about_one_hash_per_number(monkeypatch):
    """The price of a check is its hashes (about a millisecond each; the timing itself is
    tests/benchmarks/bench_seal.py): a right answer of n numbers needs n to 3n of them, a
    wrong one a bounded number more for the diagnoses."""
    from course.grading.authoring import seal as sealing

    calls = []
    real = sealing._digest.__wrapped__

    def counted(*args):
        calls.append(args)
        return real(*args)

    monkeypatch.setattr(sealing, "_digest", counted)
    e = np.linspace(0.1, 3.0, 30)
    sealed = seal(e, 1e-7, 1e-9, SALT)
    calls.clear()
    assert sealed_compare(sealed, e * (1 + 3e-8)).ok
    assert 30 <= len(calls) <= 90
    calls.clear()
    assert not sealed_compare(sealed, e * 1.7).ok
    assert len(calls) <= 2 * 30 + 80


# -- the property ---------------------------------------------------------------------------
_finite = st.floats(allow_nan=False, allow_infinity=False, min_value=-1e12, max_value=1e12)


@settings(max_examples=150, deadline=None, derandomize=True, database=None)
@given(
    e=_finite,
    u=st.floats(min_value=-1.0, max_value=1.0),
    far=st.floats(min_value=1.0001, max_value=100.0),
    rtol=st.sampled_from([1e-4, 1e-6, 1e-8, 1e-10, 0.0]),
    atol=st.sampled_from([0.0, 1e-12, 1e-9, 5e-6]),
    sign=st.sampled_from([-1.0, 1.0]),
)
def test_guaranteed_band_passes_stated_band_fails(e, u, far, rtol, atol, sign):
    assume(rtol > 0 or atol > 0)
    sealed = seal(e, rtol, atol, make_salt("property", e))
    tol = atol + rtol * abs(e)
    inside = e + u * tol
    assume(abs(inside - e) <= tol)  # rounding of e + u*tol
    assert sealed_compare(sealed, inside).ok
    outside = e + sign * far * stated_band(e, rtol, atol)
    assume(abs(outside - e) > stated_band(e, rtol, atol))
    assert not sealed_compare(sealed, outside).ok


@pytest.mark.parametrize("rtol, atol", [(1e-8, 1e-10), (1e-6, 0.0), (0.0, 5e-6), (1e-4, 1e-8)])
@pytest.mark.parametrize("magnitude", [3.0e-7, 0.75, 1.0, 12.0, 4096.0, 6.02e23])
def test_expected_exactly_on_a_grid_line(rtol, atol, magnitude):
    """e = k*h exactly (the edge of its cell): s one ulp below and above, and s at the
    tolerance's edge on either side, all pass; values beyond the stated band fail."""
    from course.grading.authoring import seal as sealing

    for sign in (1.0, -1.0):
        q = sealing._q_of(magnitude, rtol, atol)
        h = sealing._step(q, rtol, atol)
        e = sign * math.floor(magnitude / h) * h
        if e == 0.0 or sealing._q_of(abs(e), rtol, atol) != q:
            continue
        sealed = seal(e, rtol, atol, SALT)
        tol = atol + rtol * abs(e)
        for s in (np.nextafter(e, -np.inf), np.nextafter(e, np.inf), e - tol, e + tol):
            assert sealed_compare(sealed, float(s)).ok, (e, s, h)
        far = stated_band(e, rtol, atol) * 1.01
        assert not sealed_compare(sealed, e + far).ok and not sealed_compare(sealed, e - far).ok
