"""Issue 35 item 2: groups of identical and near-identical short answers
(:mod:`course.grading.batch.answergroups`), the pure part of marking a class at once."""

from __future__ import annotations

import itertools

import pytest
from hypothesis import given
from hypothesis import strategies as st

from course.grading.batch.answergroups import NEAR, group, normalise, similarity

SENTENCE = "Because the statistic exceeds the critical value of the chi-square law."


def test_identical_after_normalising_case_whitespace_and_punctuation():
    variants = [
        SENTENCE,
        "because the statistic exceeds the critical value of the chi square law",
        "  BECAUSE the statistic\nexceeds the critical value, of the chi-square law!! ",
        "Because the statistic exceeds the critical value of the “chi-square” law…",
    ]
    assert len({normalise(v) for v in variants}) == 1
    assert group([*variants, "No idea."], threshold=1.0) == [[0, 1, 2, 3], [4]]


def test_numbers_signs_and_relations_are_not_punctuation():
    assert normalise("alpha = 0.05") != normalise("alpha = 005")
    assert normalise("the bias is -1") != normalise("the bias is 1")
    assert normalise("1,5 points") != normalise("15 points")
    assert normalise("T > c") != normalise("T < c")
    assert group(["T > c", "T < c"]) == [[0], [1]]


def test_near_identical_answers_join_the_group():
    typo = "Because the statistic exceeds the critcal value of the chi-square law"
    word = "Because the statistic exceeds the critical value of a chi-square law."
    assert similarity(SENTENCE, typo) >= NEAR and similarity(SENTENCE, word) >= NEAR
    # the most common text leads: two copies of SENTENCE, then its variants
    assert group([typo, SENTENCE, "I do not know.", SENTENCE, word]) == [[1, 3, 0, 4], [2]]
    # identical only: each variant is its own group
    assert group([typo, SENTENCE, SENTENCE, word], threshold=1.0) == [[1, 2], [0], [3]]


def test_different_answers_are_not_grouped():
    answers = [
        SENTENCE,
        "The p-value is smaller than alpha, so the test rejects.",
        "Too few samples.",
        "The residuals are correlated, so the filter is mismatched.",
        "",
    ]
    assert group(answers) == [[i] for i in range(len(answers))]
    assert similarity(answers[0], answers[1]) < 0.3


def test_members_are_near_their_leader_not_chained():
    """A chain of small steps (each text near the previous one) does not pull a quite
    different text into the group (single linkage would make one group of all nine):
    every member is near its group's leader."""
    words = "the residual test of the filter rejects the model because the innovations are "
    other = "a residue tests for one filtr reject that models since these innovation were "
    w, o = (words + "correlated in time").split(), (other + "correlatd over times").split()
    chain = [" ".join(o[:k] + w[k:]) for k in range(0, len(w) + 1, 2)]
    assert all(similarity(a, b) >= NEAR for a, b in itertools.pairwise(chain))
    groups = group(chain)
    assert len(groups) > 1 and not any(0 in g and 8 in g for g in groups)
    for g in groups:
        assert all(similarity(chain[g[0]], chain[i]) >= NEAR for i in g)


def test_bad_threshold_is_refused():
    with pytest.raises(ValueError, match="threshold=0: give a similarity in"):
        group(["a"], threshold=0)


@given(st.lists(st.sampled_from(["T exceeds c.", "t exceeds c", "No idea", "no idea!", "T < c"])))
def test_groups_partition_the_answers_and_keep_identical_ones_together(texts):
    groups = group(texts)
    assert sorted(i for g in groups for i in g) == list(range(len(texts)))
    where = {i: n for n, g in enumerate(groups) for i in g}
    for i, a in enumerate(texts):
        for j, b in enumerate(texts):
            if normalise(a) == normalise(b):
                assert where[i] == where[j]
    assert [len(g) for g in groups] == sorted((len(g) for g in groups), reverse=True)
    assert group(texts) == groups  # deterministic
