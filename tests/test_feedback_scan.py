"""No self-check output shows a public expected value of a graded question (issue 13 item 2).

For every released assignment (``exercises/<name>/``, the student edition), every question is
self-checked, as a student would with ``check("qN", answer)``, with the right answer (which
must pass), a right answer written differently, and plausible wrong answers: a factor 2, 1/2
or 4/3, the sign, plus one, rounded to 4 digits, a near miss within display precision, another
order or transposed, NaN, a string, one item of a tuple wrong, every declared mistake. Each
wrong answer is checked several times so that every hint stage is printed too. The output is
then scanned for every public expected value of that assignment (each number of every public
case, band limits included) in the forms a student would see: 6 and 8 significant digits and
``repr``, and quoted strings; and for any ``expected <value>`` phrase at all (``expected 3,
got 3``). Any hit fails, naming the question, the answer and the text.

Round numbers (fewer than 3 significant digits: ``12.0``, ``0.5``, ``-4``, ``2.5``) are left to
the ``expected <value>`` rule: as bare tokens they match counts, shapes, question numbers and
the parameters a question states (``alpha = 0.05``).
"""

from __future__ import annotations

import contextlib
import functools
import io
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from conftest import class_submissions
from value_leaves import leaves

from course.grading.authoring.release import find_solutions
from course.grading.codec import Band, decode, encode
from course.grading.student.selfcheck import Assignment

ROOT = Path(__file__).resolve().parents[1]
EXERCISES = ROOT / "exercises"
ASSIGNMENTS = find_solutions(ROOT / "solutions")

# The scan builds its answers itself: a numpy warning here is a defect of the scan (it once cast
# NaN to an int field), not noise to filter.
pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")

#: ``expected`` followed by a value (a number, a quoted string, a bool or a container)
_EXPECTED_VALUE = re.compile(r"\bexpected:?\s+(?:[-+]?\d|\.\d|'|\"|True\b|False\b|\[|\()")


# -- the values a student must never see ----------------------------------------------------
def _patterns(leaf) -> list[str]:
    """The printed forms of one expected leaf that must not appear in the output."""
    if isinstance(leaf, bool) or leaf is None:
        return []  # only as `expected True` (the _EXPECTED_VALUE rule)
    if isinstance(leaf, str):
        return [repr(leaf), json.dumps(leaf)] if len(leaf) >= 2 else []
    if isinstance(leaf, complex):
        return [repr(leaf)]
    x = float(leaf)
    if not math.isfinite(x):
        return []
    if len(re.sub(r"[^0-9]", "", f"{abs(x):.6e}".split("e")[0]).rstrip("0")) < 3:
        return []  # a round number (12.0, 0.5, 2.5): only as `expected 12` (see the docstring)
    return sorted({f"{x:.6g}", f"{x:.8g}", repr(x)})


def _number_regex(text: str) -> re.Pattern:
    # a whole number token: not inside a longer number or a name (0.5 must not match 10.55,
    # 123 not the student ID s123)
    return re.compile(rf"(?<![\w.]){re.escape(text)}(?![\d])")


@functools.cache
def references(name: str) -> dict[str, list[tuple]]:
    """Question id -> ``(expected, [(message, wrong value), ...])`` per public case, computed
    from ``solutions/<name>/checks.py`` in the order of ``checks.json`` (which ships them
    sealed: the student's file holds no value to read them from)."""
    from course.grading.authoring.checks import load_checks
    from course.grading.vocabulary import DEMO_STUDENT_ID

    checks = load_checks(ROOT / "solutions" / name)
    out: dict[str, list[tuple]] = {}
    for q in checks.questions.values():
        if q.kind == "function":
            out[q.id] = [(q.expected(c), list(q.mistaken(c))) for c in q.public_cases]
        elif q.kind == "value" and q.public:
            data = checks.data_for(q.data, DEMO_STUDENT_ID) if q.data else None
            out[q.id] = [(q.expected(data=data), list(q.mistaken(data=data)))]
    return out


def public_values(name: str) -> dict[str, list]:
    """Question id -> the leaves of every public expected value of that question."""
    out: dict[str, list] = {}
    for qid, cases in references(name).items():
        for expected, _ in cases:
            leaves(expected, out.setdefault(qid, []), limit=500)
    return out


# -- answers a class would produce ----------------------------------------------------------
def _map(value, f):
    """Apply ``f`` to every numeric leaf (floats, ints, float/int arrays); keep the rest."""
    if isinstance(value, Band):
        return f(np.asarray((np.asarray(value.lo) + np.asarray(value.hi)) / 2.0))
    if isinstance(value, dict):
        return {k: _map(v, f) for k, v in value.items()}
    if isinstance(value, tuple):
        return (
            type(value)(*(_map(v, f) for v in value))
            if hasattr(value, "_fields")
            else tuple(_map(v, f) for v in value)
        )
    if isinstance(value, list):
        return [_map(v, f) for v in value]
    if isinstance(value, (bool, np.bool_, str)) or value is None:
        return value
    if isinstance(value, (int, np.integer)):
        x = float(f(np.float64(value)))
        return round(x) if math.isfinite(x) else x
    if isinstance(value, np.ndarray) and value.dtype.kind in "iu":
        x = f(value.astype(float))
        return np.round(x).astype(value.dtype) if np.all(np.isfinite(x)) else x
    if isinstance(value, np.ndarray) and value.dtype.kind == "b":
        return value
    return f(value)


def _round_sig(x, digits):
    x = np.asarray(x, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(x == 0, 1.0, 10.0 ** (digits - 1 - np.floor(np.log10(np.abs(x)))))
    out = np.round(x * scale) / scale
    return float(out) if out.ndim == 0 else out


def _reorder(value):
    if isinstance(value, np.ndarray) and value.ndim == 2:
        return value.T
    if isinstance(value, np.ndarray) and value.ndim == 1 and value.size > 1:
        return value[::-1].copy()
    if isinstance(value, (tuple, list)) and len(value) > 1:
        return (
            type(value)(reversed(value))
            if not hasattr(value, "_fields")
            else tuple(reversed(value))
        )
    return value


def _first_item_wrong(value):
    if isinstance(value, (tuple, list)) and value:
        items = list(value)
        items[0] = _map(items[0], lambda x: x * 2.0 + 1.0)
        return tuple(items)
    return _map(value, lambda x: x * 2.0 + 1.0)


def _flip_bools(value):
    if isinstance(value, (bool, np.bool_)):
        return not value
    if isinstance(value, np.ndarray) and value.dtype.kind == "b":
        return ~value
    if isinstance(value, (tuple, list)):
        return tuple(_flip_bools(v) for v in value)
    if isinstance(value, dict):
        return {k: _flip_bools(v) for k, v in value.items()}
    return value


def _plain(value):
    """A right answer written differently: lists for arrays and tuples, numpy scalars."""
    if isinstance(value, Band):
        return float(np.mean([np.mean(value.lo), np.mean(value.hi)]))
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    if isinstance(value, float):
        return np.float64(value)
    return value


TRANSFORMS = {
    "right": lambda v: v if not isinstance(v, Band) else _map(v, lambda x: x),
    "right, written differently": _plain,
    "times 2": lambda v: _map(v, lambda x: x * 2.0),
    "halved": lambda v: _map(v, lambda x: x * 0.5),
    "times 4/3": lambda v: _map(v, lambda x: x * (4.0 / 3.0)),
    "sign flipped": lambda v: _map(v, lambda x: -x),
    "plus one": lambda v: _map(v, lambda x: x + 1.0),
    "rounded to 4 digits": lambda v: _map(v, lambda x: _round_sig(x, 4)),
    "near miss (display precision)": lambda v: _map(v, lambda x: x * (1 + 3e-8) + 1e-12),
    "near miss (1e-4)": lambda v: _map(v, lambda x: x * (1 + 1e-4)),
    "another order": _reorder,
    "NaN": lambda v: _map(v, lambda x: x * np.nan),
    "first item wrong": _first_item_wrong,
    "decisions flipped": _flip_bools,
    "a string": lambda v: "0.5",
}


def _key(args, kwargs) -> str:
    return json.dumps(encode([list(args), kwargs]), sort_keys=True)


def _answers(q, refs):
    """(label, answer) pairs for a public question: values, or functions over its cases.
    ``refs``: the question's ``(expected, mistakes)`` per public case (:func:`references`)."""
    for label, transform in TRANSFORMS.items():
        if q.kind == "value":
            yield label, transform(refs[0][0])
        else:
            table = {
                _key(decode(c.args), decode(c.kwargs)): transform(ref[0])
                for c, ref in zip(q.cases, refs)
            }

            def answer(*args, _table=table, **kwargs):
                return _table[_key(args, kwargs)]

            yield label, answer
    # the declared mistakes of the public cases
    declared = refs[0][1] if refs else []
    for k, (message, _) in enumerate(declared):
        if q.kind == "value":
            yield f"mistake {message!r}", refs[0][1][k][1]
        else:
            table = {
                _key(decode(c.args), decode(c.kwargs)): ref[1][k][1]
                for c, ref in zip(q.cases, refs)
            }

            def mistaken(*args, _table=table, **kwargs):
                return _table[_key(args, kwargs)]

            yield f"mistake {message!r}", mistaken


def _from_signature(sig, fill):
    if "band" in sig:
        sig = {"kind": "float", "shape": sig["band"]}
    if "none" in sig:
        return None
    if "str" in sig:
        return "F1"
    if "names" in sig:  # a list of names of any length (a diagnosis)
        return ["F1"]
    if "sequence" in sig:
        return tuple(_from_signature(s, fill) for s in sig["sequence"])
    if "dict" in sig:
        return {k: _from_signature(s, fill) for k, s in sig["dict"].items()}
    dtype = {"bool": bool, "int": int, "float": float, "complex": complex}[sig["kind"]]
    if dtype in (bool, int) and np.isnan(fill):
        fill = 0  # no int or bool is NaN: the NaN answer puts NaN in its float items only
    value = np.full(tuple(sig["shape"]), fill).astype(dtype)
    return value if value.ndim else value.item()


def _private_answers(q):
    yield "zeros of the right shape", _from_signature(q.signature, 0)
    yield "negative", _from_signature(q.signature, -1)
    yield (
        "NaN",
        _from_signature(q.signature, np.nan) if "float" in json.dumps(q.signature) else None,
    )
    yield "a string", "0.5"


@functools.cache
def run_self_checks(name: str, exercises: Path = EXERCISES) -> list[tuple[str, str, str]]:
    """Self-check every question of ``name`` with every answer; (question, answer, output)."""
    check = Assignment.load(name, student_id="s123", path=exercises / name)
    outputs = []
    for q in check.spec.questions:
        if q.kind in ("choice", "short_answer"):  # never right/wrong in the self-check
            continue
        answers = (
            list(_answers(q, references(name)[q.id])) if q.cases else list(_private_answers(q))
        )
        repeats = max(3, len(q.hints) if hasattr(q, "hints") else 1)
        for label, answer in answers:
            buf = io.StringIO()
            with contextlib.redirect_stdout(buf):
                for _ in range(1 if label.startswith("right") else repeats):
                    check(q.id, answer)
            outputs.append((q.id, label, buf.getvalue()))
    for q in check.spec.questions:  # choices: every option, and one that is none of them
        if q.kind == "choice":
            for option in [*decode(q.options or []), "none of these"]:
                buf = io.StringIO()
                with contextlib.redirect_stdout(buf):
                    check(q.id, option)
                outputs.append((q.id, f"option {option!r}", buf.getvalue()))
    return outputs


def leaks(name: str, exercises: Path = EXERCISES) -> list[str]:
    """Every place where a self-check output shows a public expected value of ``name``."""
    from course.grading.vocabulary import PublicSpec

    spec = PublicSpec.read(exercises / name)
    values = public_values(name)
    # a choice's options are public text (mode names such as 'F2'), not an answer shown
    options = {str(o) for q in spec.questions for o in (getattr(q, "options", None) or ())}
    patterns = sorted(
        {
            (qid, p)
            for qid, leaves in values.items()
            for leaf in leaves
            if not (isinstance(leaf, str) and leaf in options)
            for p in _patterns(leaf)
        }
    )
    compiled = [(qid, p, _number_regex(p)) for qid, p in patterns]
    # a choice lists its options and echoes the student's: public by construction
    options = {
        q.id: {p for o in decode(q.options or []) for p in _patterns(o)}
        for q in spec.questions
        if q.kind == "choice"
    }
    found = []
    for qid, label, out in run_self_checks(name, exercises):
        for line in out.splitlines():
            if _EXPECTED_VALUE.search(line):
                found.append(f"{qid} / {label}: {line.strip()[:160]}")
                continue
            for owner, text, regex in compiled:
                if text in options.get(qid, ()):
                    continue
                if regex.search(line):
                    found.append(
                        f"{qid} / {label}: shows {text} (expected value of {owner}): "
                        f"{line.strip()[:160]}"
                    )
    return found


@pytest.mark.parametrize("name", ASSIGNMENTS)
def test_self_check_output_shows_no_public_expected_value(name):
    found = leaks(name)
    assert not found, f"{len(found)} leak(s) in {name}:\n" + "\n".join(found[:40])


@pytest.mark.parametrize("name", ASSIGNMENTS)
def test_right_answers_pass_every_public_check(name):
    for qid, label, out in run_self_checks(name):
        if label.startswith("right") and "PASS" in out:
            assert "FAIL" not in out, f"{name} {qid} ({label}):\n{out}"


# -- the grading feedback a student receives -----------------------------------------------
_WRONG_HELPER = """\
import numpy as _np


def _wrong(v):  # a plausible wrong answer of the same type: floats doubled, ints + 1, ...
    if isinstance(v, (bool, _np.bool_)):
        return not v
    if isinstance(v, (int, _np.integer)):
        return int(v) + 1
    if isinstance(v, (float, _np.floating)):
        return float(v) * 2.0
    if isinstance(v, _np.ndarray):
        return {"b": lambda: ~v, "i": lambda: v + 1, "u": lambda: v + 1}.get(
            v.dtype.kind, lambda: v * 2.0
        )()
    if isinstance(v, tuple):
        return tuple(_wrong(x) for x in v)
    if isinstance(v, list):
        return [_wrong(x) for x in v]
    if isinstance(v, dict):
        return {k: _wrong(x) for k, x in v.items()}
    if isinstance(v, str):
        return v.lower() + "x"
    return v
"""


def _wrong_submission(name: str):
    """The solution notebook with every answer made wrong by a cell the student added."""
    import nbformat

    from course.grading.authoring.checks import load_checks

    checks = load_checks(ROOT / "solutions" / name)
    nb = nbformat.read(ROOT / "solutions" / name / f"{name}.ipynb", as_version=4)
    cells = []
    for cell in nb.cells:
        cells.append(cell)
        meta = cell.get("metadata", {}).get("course", {})
        if meta.get("role") == "setup":
            cells.append(nbformat.v4.new_code_cell(_WRONG_HELPER))
        qid = meta.get("question") if meta.get("role") == "answer" else None
        if qid in checks.questions and checks.questions[qid].kind != "short_answer":
            q = checks.questions[qid]
            t = q.target
            if q.kind == "value":
                source = f"{t} = _wrong({t})"
            else:
                source = (
                    f"_right_{t} = {t}\n\n\ndef {t}(*args, **kwargs):\n"
                    f"    return _wrong(_right_{t}(*args, **kwargs))"
                )
            cells.append(nbformat.v4.new_code_cell(source))
    nb.cells = cells
    return nb, checks


def _graded_values(checks, sid: str) -> list:
    """The expected values of every case the grader checks for ``sid`` (hidden and personal)."""
    out: list = []
    for q in checks.questions.values():
        if q.kind == "short_answer":
            continue  # marked by the instructor: no expected value
        if q.kind == "function":
            for case in q.cases:
                leaves(q.expected(case), out, limit=500)
        elif q.data is not None:
            leaves(q.expected(data=checks.data_for(q.data, sid)), out, limit=500)
        else:
            leaves(q.expected(), out, limit=500)
    return out


@class_submissions("feedback scan")
def _class_submission(name: str, subs: Path) -> None:
    """One student, ``s-wrong``, answers every question of ``name`` wrong."""
    import nbformat

    nbformat.write(_wrong_submission(name)[0], subs / "s-wrong.ipynb")


def test_grading_feedback_shows_no_expected_value(graded_class):
    """Wrong answers to every question of every assignment, graded: the student's feedback
    file names what is wrong without any expected value (public, hidden or personal); the
    instructor's results.jsonl keeps expected and got."""
    from course.grading.authoring.checks import load_checks

    found, details = [], 0
    for name in ASSIGNMENTS:
        graded = graded_class(name)
        checks = load_checks(ROOT / "solutions" / name)
        text, row = graded.feedback("s-wrong"), graded.rows["s-wrong"]
        assert row["total"] < row["max"], (name, row["total"])
        details += sum(
            "expected" in case.get("detail", "")
            for r in row["questions"].values()
            for case in r["cases"]
        )
        patterns = {p for leaf in _graded_values(checks, "s-wrong") for p in _patterns(leaf)}
        # a choice's options are printed in the question itself: public by construction
        patterns -= {
            p
            for q in checks.questions.values()
            if q.kind == "choice"
            for o in getattr(q, "options", ())
            for p in _patterns(o)
        }
        regexes = [(p, _number_regex(p)) for p in sorted(patterns)]
        for line in text.splitlines():
            if _EXPECTED_VALUE.search(line):
                found.append(f"{name}: {line.strip()[:160]}")
            found += [
                f"{name}: shows {p}: {line.strip()[:160]}" for p, r in regexes if r.search(line)
            ]
    assert not found, f"{len(found)} leak(s):\n" + "\n".join(found[:40])
    assert details > 0  # the instructor's records do say what was expected
