"""Benchmark: the sealed self-check's comparisons against the clear comparison they replace.

For every assignment, every public case (the sealed ``checks.json`` of a fresh release) is
compared with the right answer (the reference from ``solutions/``) and with a wrong one (the
reference doubled, which runs the diagnoses), once through
:func:`course.grading.authoring.seal.sealed_compare` (what a student's ``check.all()`` pays) and once
through :func:`course.grading.compare.compare` on the value in the clear (the baseline, what
format 1 did). The seal is deliberately slow (a PBKDF2 hash per number), so the ratio is large
by design; the targets are absolute:

* the right answers of a whole assignment: under 0.5 s of comparisons (``check.all()``);
* any one wrong answer: under 1 s (the diagnoses try about twenty transforms of the answer,
  a couple of hashes each, and every element is checked to say how many are wrong).

Usage::

    python tests/benchmarks/bench_seal.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from course.grading.authoring.checks import load_checks
from course.grading.authoring.release import find_solutions, public_spec
from course.grading.authoring.seal import _digest, sealed_compare
from course.grading.codec import Band
from course.grading.compare import compare
from course.grading.vocabulary import DEMO_STUDENT_ID

ROOT = Path(__file__).resolve().parents[2]
TARGET_ALL = 0.5
TARGET_ONE = 1.0


def _doubled(value):
    if isinstance(value, Band):
        return 2.0 * np.asarray(value.hi) + 1.0
    if isinstance(value, (bool, np.bool_, str)) or value is None:
        return value
    if isinstance(value, (tuple, list)):
        return [_doubled(v) for v in value]
    if isinstance(value, dict):
        return {k: _doubled(v) for k, v in value.items()}
    return np.asarray(value) * 2 + 1


def _right(value):
    if isinstance(value, Band):
        return (np.asarray(value.lo) + np.asarray(value.hi)) / 2.0
    if isinstance(value, tuple):
        return tuple(_right(v) for v in value)
    return value


def cases(name: str):
    """(sealed case, question, reference) for every public case of ``name``."""
    checks = load_checks(ROOT / "solutions" / name)
    spec = public_spec(checks)
    for entry in spec.questions:
        q = checks.questions[entry.id]
        if q.kind == "function":
            refs = [q.expected(c) for c in q.public_cases]
        elif entry.cases:
            refs = [q.expected(data=checks.data_for(q.data, DEMO_STUDENT_ID) if q.data else None)]
        else:
            continue
        for case, ref in zip(entry.cases, refs):
            yield case, q, ref


def main() -> int:
    ok = True
    print(f"{'assignment':<32} {'right: sealed':>14} {'clear':>9} {'ratio':>7} {'worst wrong':>12}")
    for name in find_solutions(ROOT / "solutions"):
        items = list(cases(name))
        _digest.cache_clear()  # a fresh kernel: nothing hashed yet
        t0 = time.perf_counter()
        for case, _, ref in items:
            assert sealed_compare(case.expected, _right(ref), mistakes=case.mistakes).ok
        sealed_all = time.perf_counter() - t0
        t0 = time.perf_counter()
        for _, q, ref in items:
            compare(ref, _right(ref), q.rtol, q.atol)
        clear_all = time.perf_counter() - t0
        worst = 0.0
        for case, _, ref in items:
            t0 = time.perf_counter()
            sealed_compare(case.expected, _doubled(ref), mistakes=case.mistakes)
            worst = max(worst, time.perf_counter() - t0)
        ratio = sealed_all / max(clear_all, 1e-9)
        print(f"{name:<32} {sealed_all:>13.3f}s {clear_all:>8.4f}s {ratio:>6.0f}x {worst:>11.3f}s")
        ok &= sealed_all < TARGET_ALL and worst < TARGET_ONE
    print(
        f"targets: right answers of an assignment < {TARGET_ALL} s, one wrong answer < {TARGET_ONE} s"
    )
    print("PASS" if ok else "MISSED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
