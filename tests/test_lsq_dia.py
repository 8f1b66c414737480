"""DIA at the scale of real networks (issue 38): the O(m n) default candidates, the chunked
Monte Carlo against the recorded output of the former implementation, the candidates' layout."""

from __future__ import annotations

import json
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from course import lsq

REFERENCE = Path(__file__).parent / "reference" / "dia_monte_carlo_before_rewrite.json"


def _model(kind):
    t = np.arange(12.0)
    A = np.column_stack([np.ones(12), t, np.sin(t)])
    if kind == "diagonal":
        Q = 0.01 * (1.0 + 0.1 * t)
    else:
        B = np.random.default_rng(5).standard_normal((12, 12))
        Q = 0.01 * (np.eye(12) + 0.05 * B @ B.T)
    return lsq.fit(A, np.zeros(12), Q)


def _candidates(name):
    if name == "default":
        return None
    return [np.eye(12)[:, [i, i + 1]] for i in range(0, 11, 2)] + [np.eye(12)[:, 3]]


def test_the_reference_records_its_provenance():
    provenance = json.loads(REFERENCE.read_text())["provenance"]
    assert {"commit", "numpy", "scipy", "what"} <= set(provenance)


@pytest.mark.parametrize("case", json.loads(REFERENCE.read_text())["cases"], ids=str)
def test_dia_monte_carlo_equals_the_former_implementation_for_the_same_seed(case):
    """The chunked O(m n) simulation draws the same numbers and decides alike: every
    identified index equal, the errors equal to round-off (recorded before the rewrite)."""
    bias = np.zeros(12)
    bias[4] = 0.4
    f = _model(case["model"])
    mc = lsq.dia_monte_carlo(
        f,
        _candidates(case["candidates"]),
        alpha=0.05,
        bias=bias,
        size=case["size"],
        rng=np.random.default_rng(case["seed"]),
    )
    expected = np.array(case["identified"].split(), dtype=int)
    np.testing.assert_array_equal(mc.identified, expected)
    np.testing.assert_allclose(mc.errors.sum(axis=0), case["errors_column_sums"], rtol=1e-11)
    np.testing.assert_allclose((mc.errors**2).sum(axis=0), case["errors_squared_sums"], rtol=1e-11)
    np.testing.assert_allclose(
        mc.errors[case["adapted_rows"]], case["errors_at_adapted_rows"], rtol=1e-11, atol=1e-15
    )
    np.testing.assert_allclose(
        mc.errors_null.sum(axis=0), case["errors_null_column_sums"], rtol=1e-11, atol=1e-13
    )


def test_chunks_do_not_change_the_simulation(monkeypatch):
    from course.lsq import _dia

    f = _model("full")
    one = lsq.dia_monte_carlo(f, alpha=0.2, size=300, rng=np.random.default_rng(4))
    monkeypatch.setattr(_dia, "_CHUNK_BYTES", 8 * 4 * 12 * 7)  # chunks of 7 runs
    chunked = lsq.dia_monte_carlo(f, alpha=0.2, size=300, rng=np.random.default_rng(4))
    np.testing.assert_array_equal(one.identified, chunked.identified)
    np.testing.assert_array_equal(one.errors, chunked.errors)


def _network(m, seed=0):
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, m)
    A = np.column_stack([np.ones(m), t, t**2])
    sigma = 0.01 * (1.0 + rng.random(m))
    y = A @ [1.0, -2.0, 0.5] + sigma * rng.standard_normal(m)
    y[m // 3] += 0.5
    return A, y, sigma**2


def test_dia_default_candidates_need_no_m_by_m_matrix():
    """At m = 20,000 one m x m matrix is 3.2 GB: the default candidates fit in O(m n) memory
    (the former code kept an m x m identity alive per candidate)."""
    A, y, variances = _network(20_000)
    f = lsq.fit(A, y, variances)
    tracemalloc.start()
    try:
        result = lsq.dia(f)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert result.identified is not None
    assert result.candidate_names[result.identified] == f"observation {20_000 // 3}"
    assert peak < 50 * 20_000 * 8  # a few vectors of length m
    mc = lsq.dia_monte_carlo(f, size=3, rng=np.random.default_rng(1))
    assert mc.errors.shape == (3, 3)


def test_default_candidates_equal_the_explicit_unit_vectors():
    """The O(m n) path gives dia's statistics, bias and x̂ of the general path (unit vectors)."""
    A, y, variances = _network(40, seed=3)
    B = np.random.default_rng(2).standard_normal((40, 40))
    for Q in (variances, 1e-4 * (np.eye(40) + 0.02 * B @ B.T)):
        f = lsq.fit(A, y, Q)
        fast = lsq.dia(f, alpha=0.05)
        slow = lsq.dia(f, [np.eye(40)[:, i] for i in range(40)], alpha=0.05)
        assert fast.identified == slow.identified is not None
        np.testing.assert_allclose(fast.statistics, slow.statistics, rtol=1e-10)
        np.testing.assert_allclose(fast.x_hat, slow.x_hat, rtol=1e-10)
        np.testing.assert_allclose(fast.bias, slow.bias, rtol=1e-10)


@pytest.mark.parametrize("layout", ["matrix", "square", "vector"])
def test_dia_refuses_candidates_given_as_one_array(layout):
    """A matrix is not a list of candidates: read as a list it gave its rows (issue 38)."""
    f = _model("diagonal")
    value = {
        "matrix": np.eye(12)[:, [2, 5]],
        "square": np.eye(12),
        "vector": np.eye(12)[:, 3],
    }[layout]
    with pytest.raises(ValueError, match=r"list\(C\.T\)"):
        lsq.dia(f, value)
    with pytest.raises(ValueError, match=r"list\(C\.T\)"):
        lsq.dia_monte_carlo(f, value, size=5, rng=np.random.default_rng(0))
