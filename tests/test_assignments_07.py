"""Assignment 07_testing_theory: every student's levelling line tells the declared mistakes apart.

The personal questions q6 (T_2 of a pair) and q7 (the DIA result) are graded at rtol 1e-6;
a mistake that happened to give the right value on some student's line would score full marks
there. The generator redraws until the blunder is detected and identified by the w-test while
the largest |e| sits elsewhere; these tests check that promise over many IDs and under several
class keys, and that every mistake is far outside the tolerance for every student. The keys are
fixed (one written out, a few drawn from a seeded generator), so that a failure reproduces.

The blunder is drawn anywhere on the line, apart from q6's pair, and q7 grades the detection
and identification steps too (issue 37 item 1): refitting without a fixed observation of the
pair, with no detection or identification, must not score for anyone.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

from course import lsq
from course.grading.authoring.checks import load_checks
from course.grading.authoring.secret import Secret
from course.grading.compare import compare

ROOT = Path(__file__).resolve().parents[1]
NAME = "07_testing_theory"
_KEY_RNG = np.random.default_rng(20261208)
KEYS = {
    "public": None,
    "fixed class key": Secret(bytes(range(32)), "test"),
    **{f"seeded class key {i}": Secret(_KEY_RNG.bytes(32), "test") for i in range(3)},
}
N_IDS = 300


@functools.cache
def _checks():
    return load_checks(ROOT / "solutions" / NAME)


def _far(a, b, rtol=1e-6, atol=1e-8) -> bool:
    """``a`` fails the question's tolerance against ``b`` by a wide margin (x100); a result
    with parts (q7's DIA result) is far when one of its parts is: another decision or
    identified observation, or a number far off."""
    if isinstance(b, tuple):
        return len(a) != len(b) or any(_far(x, y, rtol, atol) for x, y in zip(a, b))
    if a is None or b is None or isinstance(b, (bool, int, np.bool_, np.integer)):
        return a is None or b is None or a != b
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape:
        return True
    return bool(np.any(np.abs(a - b) > 100 * (atol + rtol * np.abs(b))))


@pytest.mark.parametrize("key", list(KEYS))
def test_every_line_is_detected_identified_and_misleads_by_the_largest_residual(key):
    checks = _checks()
    for k in range(N_IDS):
        d = checks.data_for("levelling", f"s{k:05d}", KEYS[key])
        fit = lsq.fit(d["A"], d["y"], d["Qyy"])
        assert lsq.overall_model_test(fit, d["alpha"]).reject, k
        w = lsq.w_tests(fit, d["alpha"])
        assert w.reject[w.largest], k
        assert w.largest not in d["pair"], k  # the pair says nothing of the blunder
        assert int(np.argmax(np.abs(fit.e_hat))) != w.largest, k
        assert lsq.dia(fit, alpha=d["alpha"]).identified == w.largest, k


@pytest.mark.parametrize("key", list(KEYS))
def test_the_blunder_is_anywhere_and_not_where_the_pair_points(key):
    """Over the IDs of a class the identified observation takes every position, and no fixed
    offset from the pair finds it for more than a fifth of the class (the old generator put it
    at pair[0] on every line, so refitting without pair[0] scored full marks)."""
    checks = _checks()
    where, offsets = [], []
    for k in range(N_IDS):
        d = checks.data_for("levelling", f"s{k:05d}", KEYS[key])
        identified = checks.questions["q7"].reference(d).identified
        where.append(identified)
        offsets.append(identified - d["pair"][0])
    assert set(where) == set(range(14)), sorted(set(where))
    assert max(np.unique(offsets, return_counts=True)[1]) < N_IDS / 5


@pytest.mark.parametrize("qid", ["q7", "q7_practice"])
def test_skipping_detection_and_identification_cannot_score(qid):
    """The answer holds T, the decision and the identified index besides x_hat: a refit
    without either observation of the pair, or x_hat alone, fails for every line; and no
    message of the question names an index of the data (the old "not pair[1]" pointed the
    way to pair[0])."""
    checks = _checks()
    q = checks.questions[qid]
    for mistake in q.mistakes:
        assert "pair" not in mistake.message, mistake.message
    lines = [checks.data_for("levelling", f"s{k:05d}", KEYS["fixed class key"]) for k in range(60)]
    for d in lines:
        right = q.reference(d)
        fit = lsq.fit(d["A"], d["y"], d["Qyy"])
        for suspect in d["pair"]:
            keep = np.delete(np.arange(14), suspect)
            x_hat = lsq.fit(d["A"][keep], d["y"][keep], d["Qyy"][np.ix_(keep, keep)]).x_hat
            shortcut = (fit.squared_norm, True, suspect, x_hat)
            assert not compare(right, shortcut, q.rtol, q.atol).ok
            assert not compare(right, x_hat, q.rtol, q.atol).ok
        assert compare(right, tuple(right), q.rtol, q.atol).ok


@pytest.mark.parametrize("qid", ["q6", "q7"])
@pytest.mark.parametrize("key", list(KEYS))
def test_every_declared_mistake_is_far_from_every_students_answer(qid, key):
    checks = _checks()
    q = checks.questions[qid]
    assert q.mistakes, qid
    for k in range(N_IDS):
        d = checks.data_for("levelling", f"s{k:05d}", KEYS[key])
        right = q.reference(d)
        for mistake in q.mistakes:
            assert _far(mistake.reference(d), right), (qid, k, mistake.message)


def test_the_practice_line_is_the_generators_line_for_seed_7():
    """The notebook prints the practice line as literal arrays: they must be the generator's."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "levelling_data", ROOT / "solutions" / NAME / "data.py"
    )
    data = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(data)
    d = data.levelling(np.random.default_rng(7))
    source = (ROOT / "solutions" / NAME / f"{NAME}.ipynb").read_text(encoding="utf-8")
    for value in d["y"]:
        assert f"{value:.3f}" in source
    for value in np.sqrt(np.diag(d["Qyy"])):
        assert f"{value:.3f}" in source
    assert f'\\"pair\\": {d["pair"]}' in source and d["alpha"] == 0.05  # JSON-escaped
