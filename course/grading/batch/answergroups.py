"""Groups of alike short answers, so that a marker marks 60 copies of one sentence once.

Two answers are **identical** when their normalised texts are equal (:func:`normalise`: Unicode
compatibility form, case folded, punctuation dropped unless it is part of a number, whitespace
collapsed). Two answers are **near-identical** when the Jaccard similarity of the sets of
character 3-grams of their normalised texts (:func:`similarity`) is at least
:data:`NEAR` (0.8): a changed word, a typo or a reordered clause in a sentence of some
length, never a different sentence. It is a likeness of letters, not of meaning ("correlated"
and "uncorrelated" are near): the view lists a group's texts, and a member marked on its own
keeps its mark. The q-gram similarity follows Ukkonen (1992); full reference in the course
bibliography, :doc:`/docs/bibliography`.

:func:`group` puts each distinct normalised text into a group in one deterministic pass: the
texts in order of how many answers share them (most first, ties in the order given), each
joining the group whose first text (its *leader*) it is most similar to, if that similarity
reaches the threshold, else starting a group. Every member is thus near its group's leader
(no chains of small steps from one answer to a quite different one), and the cost is bounded
by (distinct texts) x (groups) set comparisons, a few tens of thousands for a class of 200.

The module is pure (texts in, positions out): the marking view
(:mod:`course.grading.batch.marking`) decides what a group mark does, and where marks are
stored is no concern of this module.
"""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Sequence

__all__ = ["NEAR", "group", "normalise", "similarity"]

#: the least 3-gram Jaccard similarity of two near-identical answers
NEAR = 0.8

_NUMBER_MARK = re.compile(r"[.,+-](?=\d)")


def normalise(text: str) -> str:
    """The text of an answer as compared: NFKC, case folded, punctuation replaced by a space
    (except ``. , + -`` before a digit: a decimal point or a sign stays, ``-1`` is not
    ``1``), whitespace collapsed. Symbols such as ``< > =`` are kept (``T > c`` is not
    ``T < c``).

    Examples
    --------
    >>> normalise("  Because T EXCEEDS\\nthe critical-value!! ")
    'because t exceeds the critical value'
    >>> normalise("p = 0.05, not -1.") == normalise("P = 0.05 not -1")
    True
    >>> normalise("T > c") == normalise("T < c")
    False
    """
    text = unicodedata.normalize("NFKC", str(text)).casefold()
    keep = {m.start() for m in _NUMBER_MARK.finditer(text)}
    chars = [
        " " if unicodedata.category(ch).startswith("P") and i not in keep else ch
        for i, ch in enumerate(text)
    ]
    return " ".join("".join(chars).split())


def _grams(norm: str) -> frozenset[str]:
    padded = f" {norm} "
    return frozenset(padded[i : i + 3] for i in range(len(padded) - 2))


def similarity(a: str, b: str) -> float:
    """The Jaccard similarity ``|A ∩ B| / |A ∪ B|`` of the sets of character 3-grams of the
    normalised texts ``a`` and ``b`` (each padded with one space at both ends); 1.0 for
    identical normalised texts, 0.0 when they share no 3-gram.

    Notes
    -----
    Sets of character *q*-grams make a similarity that a typo or a changed word moves a
    little and a different sentence moves a lot, at the cost of one set intersection
    (Ukkonen 1992, "Approximate string-matching with q-grams and maximal matches",
    Theoretical Computer Science 92, 191-211).

    Examples
    --------
    >>> similarity("Because T exceeds the critical value.", "because T exceeds the critcal value")
    0.8684
    >>> similarity("The p-value is small.", "I do not know.") < 0.2
    True
    """
    ga, gb = _grams(normalise(a)), _grams(normalise(b))
    if ga == gb:
        return 1.0
    return round(len(ga & gb) / len(ga | gb), 4)


def group(texts: Sequence[str], threshold: float = NEAR) -> list[list[int]]:
    """Group the answers ``texts`` into identical and near-identical ones.

    Parameters
    ----------
    texts : sequence of str
        The answers to one question.
    threshold : float, default :data:`NEAR`
        The least :func:`similarity` of a near-identical answer to its group's leader; 1.0
        groups identical answers only.

    Returns
    -------
    list of list of int
        Every position of ``texts`` in exactly one group. Groups by size (largest first,
        ties by their first position); within a group the leader's answers first, then the
        other texts in the order they joined, each text's answers in the order given.

    Notes
    -----
    Distinct normalised texts are visited most common first; each joins the group whose
    leader it is most similar to (the earliest such group on a tie) when that similarity is
    at least ``threshold``, else it leads a new group. Deterministic for given ``texts`` and
    O(distinct texts x groups) set comparisons.

    Examples
    --------
    >>> group(["T exceeds c.", "no idea", "t exceeds c", "T exceeds  c!", "No idea."])
    [[0, 2, 3], [1, 4]]
    >>> group(["The test rejects the null.", "The test rejects the nul", "Too few samples."])
    [[0, 1], [2]]
    """
    if not 0.0 < threshold <= 1.0:
        raise ValueError(f"threshold={threshold!r}: give a similarity in (0, 1]")
    by_text: dict[str, list[int]] = {}
    for i, text in enumerate(texts):
        by_text.setdefault(normalise(text), []).append(i)
    order = sorted(by_text, key=lambda t: (-len(by_text[t]), by_text[t][0]))
    leaders: list[frozenset[str]] = []
    groups: list[list[str]] = []
    for norm in order:
        grams = _grams(norm)
        best, best_sim = -1, threshold
        for g, lead in enumerate(leaders):
            small, large = sorted((len(grams), len(lead)))
            if small < best_sim * large:
                continue  # |A ∩ B| / |A ∪ B| <= small / large: cannot reach the bar
            common = len(grams & lead)
            union = len(grams) + len(lead) - common
            sim = common / union if union else 1.0
            if sim >= best_sim and (best < 0 or sim > best_sim):
                best, best_sim = g, sim
        if best < 0:
            leaders.append(grams)
            groups.append([norm])
        else:
            groups[best].append(norm)
    out = [[i for norm in members for i in by_text[norm]] for members in groups]
    return sorted(out, key=lambda g: (-len(g), g[0]))
