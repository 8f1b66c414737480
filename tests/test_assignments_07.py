"""Assignment 07_testing_theory: every student's levelling line tells the declared mistakes apart.

The personal questions q6 (T_2 of a pair) and q7 (the DIA estimate) are graded at rtol 1e-6;
a mistake that happened to give the right value on some student's line would score full marks
there. The generator redraws until the blunder is detected and identified by the w-test while
the largest |e| sits elsewhere; these tests check that promise over many IDs and under several
class keys, and that every mistake is far outside the tolerance for every student. The keys are
fixed (one written out, a few drawn from a seeded generator), so that a failure reproduces.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

from course import lsq
from course.grading.authoring.checks import load_checks
from course.grading.authoring.secret import Secret

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
    """``a`` fails the question's tolerance against ``b`` by a wide margin (x100)."""
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
        assert w.largest == d["pair"][0], k
        assert int(np.argmax(np.abs(fit.e_hat))) != d["pair"][0], k
        assert lsq.dia(fit, alpha=d["alpha"]).identified == d["pair"][0], k


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
    assert d["pair"] == [7, 8] and d["alpha"] == 0.05
