"""Benchmark: grouping a class's short answers (issue 35 item 2) against all-pairs difflib.

A class of ``--students`` answers to one question: a quarter give the same sentence (with
changes of case and punctuation), a tenth a variant with a typo or a changed word, the rest
distinct sentences drawn from the course's words. Timed:

* ours: :func:`course.grading.batch.answergroups.group` (leader clustering on 3-gram sets);
* the baseline: the obvious approach, ``difflib.SequenceMatcher(...).ratio()`` of every pair
  of distinct normalised texts (the similarity most Python code reaches for), timed on
  ``--baseline-texts`` texts and scaled by the number of pairs (its cost is per pair).

Target: at least 10x faster than the baseline, so the view regroups without a pause.

Usage::

    python tests/benchmarks/bench_answergroups.py [--students 400] [--baseline-texts 120]
"""

from __future__ import annotations

import argparse
import difflib
import sys
import time

import numpy as np

from course.grading.batch.answergroups import group, normalise

TARGET = 10.0
WORDS = [
    "the",
    "residual",
    "test",
    "statistic",
    "exceeds",
    "critical",
    "value",
    "because",
    "filter",
    "innovations",
    "are",
    "correlated",
    "white",
    "noise",
    "covariance",
    "trace",
    "matrix",
    "eigenvalues",
    "degrees",
    "of",
    "freedom",
    "power",
    "alternative",
    "mean",
    "shift",
    "samples",
    "too",
    "few",
    "threshold",
    "rejects",
    "accepts",
    "model",
    "wrong",
]
SENTENCE = "Because the statistic exceeds the critical value of the chi-square law."


def make_answers(students: int, rng: np.random.Generator) -> list[str]:
    same = [SENTENCE, SENTENCE.upper(), SENTENCE.lower().rstrip("."), f"  {SENTENCE}!"]
    variants = [SENTENCE.replace("critical", "critcal"), SENTENCE.replace("the chi", "a chi")]
    answers = []
    for i in range(students):
        if i % 4 == 0:
            answers.append(same[int(rng.integers(len(same)))])
        elif i % 10 == 1:
            answers.append(variants[int(rng.integers(len(variants)))])
        else:
            n = int(rng.integers(8, 25))
            answers.append(" ".join(rng.choice(WORDS, size=n)).capitalize() + ".")
    return answers


def baseline(texts: list[str]) -> int:
    distinct = list(dict.fromkeys(normalise(t) for t in texts))
    near = 0
    for i, a in enumerate(distinct):
        for b in distinct[i + 1 :]:
            near += difflib.SequenceMatcher(None, a, b, autojunk=False).ratio() >= 0.8
    return near


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=400)
    parser.add_argument("--baseline-texts", type=int, default=120)
    args = parser.parse_args()
    answers = make_answers(args.students, np.random.default_rng(35))

    start = time.perf_counter()
    groups = group(answers)
    ours = time.perf_counter() - start
    assert sorted(i for g in groups for i in g) == list(range(len(answers)))
    assert len(groups[0]) >= args.students // 4  # the common sentence and its variants

    sample = answers[: args.baseline_texts]
    start = time.perf_counter()
    baseline(sample)
    measured = time.perf_counter() - start
    n_all = len({normalise(t) for t in answers})
    n_sample = len({normalise(t) for t in sample})
    scaled = measured * (n_all * (n_all - 1)) / max(n_sample * (n_sample - 1), 1)

    ratio = scaled / ours
    print(
        f"{args.students} answers ({n_all} distinct texts, {len(groups)} groups): "
        f"ours {ours * 1e3:.1f} ms, all-pairs difflib {scaled * 1e3:.0f} ms (scaled from "
        f"{n_sample} texts) -> {ratio:.1f}x (target {TARGET:g}x)"
    )
    return 0 if ratio >= TARGET else 1


if __name__ == "__main__":
    sys.exit(main())
