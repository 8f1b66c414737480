"""The term's rules: how ``course gradebook`` turns assignment scores into a final grade.

One small JSON file per term (JSON because Python reads it without any package on every
version the course supports; a comment-free format is a small price for that), e.g.
``term.json``::

    {
      "categories": [
        {"name": "homework", "weight": 40, "assignments": ["A1", "A2", "A3"],
         "drop_lowest": 1},
        {"name": "exam", "weight": 60, "assignments": ["A4"]}
      ],
      "letters": {"A": 90, "B": 80, "C": 70, "D": 60, "F": 0},
      "pass": 50,
      "exemptions": [{"id": "s003", "assignment": "A2"}],
      "extensions": "extensions.csv"
    }

``categories``
    each with a ``weight`` (any positive numbers: they are normalised), the ``assignments``
    it holds (an assignment's folder name, ``01_least_squares``, or its gradebook column) and
    optionally ``drop_lowest`` N. A weight per assignment is a category per assignment. Every
    assignment of the gradebook must be in exactly one category.
``letters`` and ``pass`` (either or both)
    the lowest final percentage of each letter (one of them 0), and the pass mark in %.
``exemptions``
    students excused from an assignment: it is left out of their category (its blank never
    counts as 0), as if it had not been set for them.
``extensions``
    the extensions CSV (``id,assignment,due``; a path relative to this file), the same file
    ``course grade --extensions`` reads (see :mod:`course.grading.batch.late`).

The arithmetic, per student:

* an assignment's share is its total (after any late deduction) over its points possible; a
  missing submission scores 0, an exempted one is left out;
* ``drop_lowest`` N drops the N lowest shares of the category's counted assignments (the
  first in the file's order on a tie), never all of them;
* a category's percentage is ``100 * sum(points) / sum(points possible)`` of what is left
  (points, as Canvas and Moodle total a category), and the final percentage is the
  weighted mean of the categories that count anything, ``sum(w_c p_c) / sum(w_c)`` (a
  category a student is wholly exempt from gives its weight to the others);
* the letter is the first whose threshold the final percentage, rounded to 2 decimals, reaches.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path

from course.grading.batch.late import LateError, read_extensions

__all__ = ["Category", "TermError", "TermGrade", "TermRules", "read_term", "term_grades"]

_KEYS = {"categories", "letters", "pass", "exemptions", "extensions"}
_CATEGORY_KEYS = {"name", "weight", "assignments", "drop_lowest"}


class TermError(ValueError):
    """The term's rules cannot be used (the message names the file, the entry and the fix)."""


@dataclass(frozen=True)
class Category:
    name: str
    weight: float
    assignments: tuple[str, ...]
    drop_lowest: int = 0


@dataclass(frozen=True)
class TermRules:
    """The rules of :func:`read_term`; ``extensions`` by (student ID, assignment)."""

    categories: tuple[Category, ...]
    letters: tuple[tuple[str, float], ...] = ()  # (letter, lowest %), highest first
    pass_mark: float | None = None
    exemptions: frozenset[tuple[str, str]] = frozenset()
    extensions: dict[tuple[str, str], datetime] = field(default_factory=dict)
    path: Path | None = None

    def letter(self, percent: float) -> str:
        """The letter of a final percentage (rounded to 2 decimals first)."""
        shown = round(percent, 2)
        return next((name for name, low in self.letters if shown >= low), "")


def _number(value, where: str, low: float = 0.0) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise TermError(f"{where}: give a number, not {value!r}")
    if value < low:
        raise TermError(f"{where}: give a number of at least {low:g}, not {value!r}")
    return float(value)


def _pairs(value, where: str) -> list[tuple[str, str]]:
    """``[{"id": ..., "assignment": ...}, ...]`` as (id, assignment) pairs."""
    if not isinstance(value, list):
        raise TermError(f'{where}: give a list of {{"id": ..., "assignment": ...}}')
    out = []
    for i, item in enumerate(value):
        ok = isinstance(item, dict) and set(item) == {"id", "assignment"}
        if not ok or not all(isinstance(v, str) and v.strip() for v in item.values()):
            raise TermError(f'{where}[{i}]: write {{"id": "s001", "assignment": "A1"}}')
        out.append((item["id"].strip(), item["assignment"].strip()))
    return out


def _category(item, i: int, where: str) -> Category:
    if not isinstance(item, dict):
        raise TermError(
            f"{where}: categories[{i}] must be an object with name, weight, assignments"
        )
    unknown = set(item) - _CATEGORY_KEYS
    if unknown:
        raise TermError(
            f"{where}: categories[{i}] has unknown key(s) {sorted(unknown)}; use "
            + ", ".join(sorted(_CATEGORY_KEYS))
        )
    name = item.get("name")
    if not isinstance(name, str) or not name.strip():
        raise TermError(f"{where}: categories[{i}] needs a name")
    here = f"{where}: category {name!r}"
    assignments = item.get("assignments")
    if (
        not isinstance(assignments, list)
        or not assignments
        or not all(isinstance(a, str) and a.strip() for a in assignments)
    ):
        raise TermError(f'{here}: "assignments" must be a list of assignment names')
    drop = item.get("drop_lowest", 0)
    if isinstance(drop, bool) or not isinstance(drop, int) or drop < 0:
        raise TermError(f'{here}: "drop_lowest" must be a whole number >= 0, not {drop!r}')
    if drop >= len(assignments):
        raise TermError(f"{here}: drops {drop} of its {len(assignments)} assignment(s)")
    weight = _number(item.get("weight"), f'{here}: "weight"')
    if weight <= 0:
        raise TermError(f'{here}: "weight" must be positive')
    return Category(name.strip(), weight, tuple(a.strip() for a in assignments), drop)


def read_term(path: str | Path) -> TermRules:
    """The term's rules in the JSON file ``path`` (see the module docstring).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "term.json"
    >>> _ = f.write_text('{"categories": [{"name": "hw", "weight": 1, "assignments": ["A1"]}],'
    ...                  ' "letters": {"pass": 50, "fail": 0}}')
    >>> rules = read_term(f)
    >>> rules.categories[0].assignments, rules.letter(49.996)
    (('A1',), 'pass')
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text("utf-8-sig"))
    except (OSError, UnicodeDecodeError) as exc:
        raise TermError(f"cannot read the term's rules {path}: {exc}") from None
    except json.JSONDecodeError as exc:
        raise TermError(
            f"{path} is not JSON: {exc.msg} at line {exc.lineno}, column {exc.colno} "
            "(a trailing comma? keys in double quotes?)"
        ) from None
    if not isinstance(data, dict):
        raise TermError(f"{path}: the rules are one JSON object {{...}}")
    unknown = set(data) - _KEYS
    if unknown:
        raise TermError(f"{path}: unknown key(s) {sorted(unknown)}; use {', '.join(sorted(_KEYS))}")
    raw = data.get("categories")
    if not isinstance(raw, list) or not raw:
        raise TermError(f'{path}: "categories" must list at least one category')
    categories = tuple(_category(item, i, str(path)) for i, item in enumerate(raw))
    seen: dict[str, str] = {}
    for c in categories:
        for a in c.assignments:
            if a in seen:
                raise TermError(f"{path}: {a} is in two categories ({seen[a]}, {c.name})")
            seen[a] = c.name
    letters_in = data.get("letters", {})
    if not isinstance(letters_in, dict):
        raise TermError(f'{path}: "letters" must map each letter to its lowest %, e.g. {{"A": 90}}')
    letters = sorted(
        ((str(k), _number(v, f"{path}: letter {k!r}")) for k, v in letters_in.items()),
        key=lambda kv: -kv[1],
    )
    if letters and letters[-1][1] != 0:
        raise TermError(f'{path}: "letters" needs a lowest letter at 0 (e.g. "F": 0)')
    pass_mark = data.get("pass")
    if pass_mark is not None:
        pass_mark = _number(pass_mark, f'{path}: "pass"')
    exemptions = frozenset(_pairs(data.get("exemptions", []), f'{path}: "exemptions"'))
    extensions: dict[tuple[str, str], datetime] = {}
    if data.get("extensions") is not None:
        if not isinstance(data["extensions"], str):
            raise TermError(f'{path}: "extensions" is the path of the extensions CSV')
        try:
            extensions = read_extensions(path.parent / data["extensions"])
        except LateError as exc:
            raise TermError(f"{path}: {exc}") from None
    return TermRules(categories, tuple(letters), pass_mark, exemptions, extensions, path)


def _share(item: tuple[str, float, float]) -> float:
    _, points, possible = item
    return points / possible if possible > 0 else 1.0


@dataclass(frozen=True)
class TermGrade:
    """One student's final grade: percentage per category (None: nothing of it counts), the
    final percentage (None: nothing counts at all), letter, pass, and the assignments dropped."""

    categories: dict[str, float | None]
    percent: float | None
    letter: str
    passed: bool | None
    dropped: tuple[str, ...]


def term_grades(
    rules: TermRules,
    scores: dict[str, dict[str, float | None]],
    maxima: dict[str, float],
) -> dict[str, TermGrade]:
    """Per student, the :class:`TermGrade` of ``scores`` (student -> assignment -> points, None
    for exempt; an assignment absent: no submission, 0) with the points possible ``maxima``.

    The assignments are named as in ``rules``; see the module docstring for the arithmetic.

    Examples
    --------
    >>> rules = TermRules((Category("hw", 1.0, ("A1", "A2"), drop_lowest=1),),
    ...                   letters=(("pass", 50.0), ("fail", 0.0)))
    >>> g = term_grades(rules, {"s1": {"A1": 2.0, "A2": 8.0}}, {"A1": 10.0, "A2": 10.0})["s1"]
    >>> g.percent, g.letter, g.dropped
    (80.0, 'pass', ('A1',))
    """
    out = {}
    for sid, mine in scores.items():
        per_category: dict[str, float | None] = {}
        dropped: list[str] = []
        for c in rules.categories:
            counted = [
                (a, float(mine.get(a) or 0.0), maxima[a])
                for a in c.assignments
                if not (a in mine and mine[a] is None)  # exempt: left out, never a 0
            ]
            n_drop = min(c.drop_lowest, len(counted) - 1)
            if n_drop > 0:
                order = sorted(range(len(counted)), key=lambda i: (_share(counted[i]), i))
                gone = set(order[:n_drop])
                dropped += [counted[i][0] for i in sorted(gone)]
                counted = [x for i, x in enumerate(counted) if i not in gone]
            possible = sum(m for _, _, m in counted)
            per_category[c.name] = (
                100.0 * sum(p for _, p, _ in counted) / possible if possible > 0 else None
            )
        weights = [(c.weight, per_category[c.name]) for c in rules.categories]
        total_weight = sum(w for w, p in weights if p is not None)
        percent = (
            sum(w * p for w, p in weights if p is not None) / total_weight
            if total_weight > 0
            else None
        )
        out[sid] = TermGrade(
            per_category,
            percent,
            "" if percent is None else rules.letter(percent),
            None
            if percent is None or rules.pass_mark is None
            else round(percent, 2) >= rules.pass_mark,
            tuple(dropped),
        )
    return out
