"""Compare a student's value with an expected value and explain the difference compactly.

Used by the grader (in the trusted parent, against the true references). The student's
self-check compares against SEALED expected values with the same messages, see
:mod:`course.grading.authoring.seal`, or, where the student's copy holds no expected value, checks only
its type and shape (:func:`check_signature`): all three walk the structure with
:class:`StructuralWalk` (types, shapes, lengths, keys and what is said of them) and differ only
in their leaves. Never compares printed text.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from course.grading.codec import Band, _named_type
from course.grading.vocabulary import SPECIFIC_KINDS, MistakeKind

__all__ = [
    "SINGLE_PRECISION",
    "Verdict",
    "binomial_band",
    "chosen_hint",
    "compare",
    "describe",
    "fieldwise_mistake",
    "single_precision",
]


@dataclass(frozen=True)
class Verdict:
    """The outcome of one comparison.

    ``message`` is for the student: what is wrong in kind (shape, NaN, sign, a factor, order,
    off by one, a declared mistake) and the tolerance, never an expected value. ``detail`` is
    for the instructor's records only: expected and got, with enough digits to differ.
    ``kind`` is the diagnosis as data (a :class:`~course.grading.vocabulary.MistakeKind`, set
    where it is made; a failed verdict without one is :attr:`~MistakeKind.WRONG_VALUE`, any
    other value is refused), and ``mistake`` the declared mistake's message when ``kind`` is
    :attr:`~MistakeKind.NAMED`: what the reports count, never the message's words.
    """

    ok: bool
    message: str = ""
    detail: str = ""
    kind: MistakeKind | None = None
    mistake: str = ""

    def __post_init__(self):
        if self.ok:
            object.__setattr__(self, "kind", None)
        else:  # MistakeKind(...) refuses a kind that is not in the one list
            object.__setattr__(self, "kind", MistakeKind(self.kind or MistakeKind.WRONG_VALUE))


def binomial_band(n: int, p: float, miss: float = 1e-4) -> Band:
    """Band for an empirical rate ``k / n`` with ``k ~ Binomial(n, p)``.

    The interval holds the rate with probability at least ``1 - miss`` (equal tails, from
    ``scipy.stats.binom.interval``), so a correct Monte Carlo answer fails with probability at
    most ``miss`` whatever its seed, while a wrong threshold or formula lands outside.
    """
    from scipy.stats import binom

    n = int(n)
    if n <= 0 or not 0.0 <= float(p) <= 1.0 or not 0.0 < float(miss) < 1.0:
        raise ValueError("binomial_band needs n > 0, 0 <= p <= 1 and 0 < miss < 1")
    lo, hi = binom.interval(1.0 - float(miss), n, float(p))
    return Band(float(lo) / n, float(hi) / n)


def _fmt(x: float) -> str:
    x = float(x)
    if math.isnan(x) or math.isinf(x):
        return str(x)
    if x == int(x) and abs(x) < 1e15:
        return str(int(x))
    return f"{x:.6g}"


def _where(index, shape) -> str:
    if not shape:
        return ""
    return " at [" + ", ".join(str(int(i)) for i in index) + "]"


def describe(value: Any) -> str:
    """A short type/shape description of a value (never its full content)."""
    if value is None:
        return "None"
    if isinstance(value, (bool, np.bool_)):
        return "a bool"
    if isinstance(value, (int, np.integer)):
        return "an int"
    if isinstance(value, (float, np.floating)):
        return "a float"
    if isinstance(value, (complex, np.complexfloating)):
        return "a complex number"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, np.ndarray):
        return f"an array of shape {tuple(value.shape)} ({value.dtype})"
    if isinstance(value, (tuple, list)):
        return f"a {type(value).__name__} of length {len(value)}"
    if isinstance(value, dict):
        return f"a dict with keys {sorted(map(str, value))[:8]}"
    if value is Ellipsis:
        return "... (Ellipsis)"
    return f"a {type(value).__name__}"


def _is_plain_number(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_)
    )


def _is_number_vector(value) -> bool:
    """A 1-D real array: it answers a sequence of plain numbers (see :func:`sequence_items`)."""
    return isinstance(value, np.ndarray) and value.ndim == 1 and value.dtype.kind in "iuf"


def _is_one_number(expected) -> bool:
    """A plain number, or a band around one (a Monte Carlo rate): an array element answers it."""
    if isinstance(expected, Band):
        return np.ndim(expected.lo) == 0
    return _is_plain_number(expected)


def sequence_items(expected, got):
    """``got`` as the items answering the sequence ``expected``, or None when it cannot.

    A tuple or list answers as itself. A 1-D real array answers a sequence of plain numbers
    (or bands of one number, Monte Carlo rates): ``np.array([lo, hi])`` for ``(lower, upper)``
    is a right answer written differently.
    """
    if isinstance(got, (tuple, list)):
        return got
    if _is_number_vector(got) and len(expected) > 0 and all(_is_one_number(e) for e in expected):
        return list(got)
    return None


def length_mismatch(label: str, expected: int, got: int) -> Verdict:
    """A sequence of the wrong length, saying "one item too many/few" when it is one off."""
    text = f"{label}: expected length {expected}, got length {got}"
    one_off = abs(got - expected) == 1
    more = f": one item too {'many' if got > expected else 'few'}" if one_off else ""
    kind = MistakeKind.ONE_TOO_MANY_OR_FEW if one_off else MistakeKind.SHAPE
    return Verdict(False, text + more, text, kind)


def sequence_text(expected) -> str:
    """What a student should return, by field names when the result has them."""
    fields = getattr(type(expected), "_fields", None)
    if isinstance(fields, tuple) and len(fields) == len(expected):
        return f"a tuple ({', '.join(fields)})"
    return f"a {'list' if isinstance(expected, list) else 'tuple'} of length {len(expected)}"


def _numeric(value):
    """``value`` as a numeric ndarray, or None when it is not numeric data."""
    if isinstance(value, (str, bytes, dict)) or value is None:
        return None
    try:
        arr = np.asarray(value)
    except Exception:
        return None
    if arr.dtype.kind not in "biufc":
        return None
    return arr


def _is_boolish(expected) -> bool:
    if isinstance(expected, (bool, np.bool_)):
        return True
    return isinstance(expected, np.ndarray) and expected.dtype.kind == "b"


def _is_intish(expected) -> bool:
    if isinstance(expected, (bool, np.bool_)):
        return False
    if isinstance(expected, (int, np.integer)):
        return True
    return isinstance(expected, np.ndarray) and expected.dtype.kind in "iu"


def _label(path: str) -> str:
    return path or "value"


def _item_path(path: str, expected, got, k: int) -> str:
    """The name of item ``k`` of a tuple: its field name when either side has named fields."""
    for value in (expected, got):
        fields = getattr(type(value), "_fields", None)
        if isinstance(fields, tuple) and len(fields) == len(value) and isinstance(fields[k], str):
            return f"{path}.{fields[k]}" if path else fields[k]
    return f"{path}[{k}]" if path else f"item [{k}]"


def _key_path(path: str, key) -> str:
    return f"{path}[{key!r}]" if path else str(key)


def _tolerance_text(rtol: float, atol: float) -> str:
    return f"tolerance |got - expected| <= atol {_fmt(atol)} + rtol {_fmt(rtol)}·|expected|"


def _digits_apart(e, g) -> tuple[str, str]:
    """``e`` and ``g`` printed with the fewest digits (>= 6) that tell them apart."""
    if isinstance(e, complex) or isinstance(g, complex):
        return str(e), str(g)
    for d in (6, 8, 10, 12, 14, 17):
        a, b = f"{float(e):.{d}g}", f"{float(g):.{d}g}"
        if a != b:
            return a, b
    return repr(float(e)), repr(float(g))


def _close(e: np.ndarray, g: np.ndarray, rtol: float, atol: float) -> bool:
    """``g`` equals ``e`` within the tolerance (exactly for integers), shapes equal."""
    if e.shape != g.shape:
        return False
    if e.dtype.kind in "biu" and g.dtype.kind in "biu":
        return bool(np.array_equal(e, g))
    with np.errstate(invalid="ignore", over="ignore"):
        ok = (np.abs(g - e) <= atol + rtol * np.abs(e)) | (np.isnan(e) & np.isnan(g))
        ok |= np.isinf(e) & (g == e)
    return bool(np.all(ok))


def _simple_ratio(r: float) -> Fraction | None:
    """``r`` as a small fraction (denominator <= 4, numerator <= 1000) or a power of ten.

    Only the factors of common slips (2, 3/2, 4/3, ...): an exact ratio such as 16/9 would
    give the answer away (got / ratio), and the sealed self-check does not name it either."""
    if not math.isfinite(r) or r <= 0:
        return None
    frac = Fraction(r).limit_denominator(4)
    if frac.numerator <= 1000 and abs(float(frac) - r) <= 1e-6 * r:
        return frac
    exponent = round(math.log10(r))
    if exponent != 0 and abs(10.0**exponent - r) <= 1e-6 * r:
        return Fraction(10) ** exponent
    return None


def _factor_text(r: float, frac: Fraction | None, hidden: bool = False) -> str:
    """The words of a factor, "too large by a factor ≈ 1.5 (= 3/2)"; on a hidden case
    (``hidden``) without the factor, which could tell the case's input (M/(M-1) = 3/2 says
    M = 3)."""
    big = r >= 1
    if hidden:
        return f"too {'large' if big else 'small'} by a constant factor"
    x = r if big else 1.0 / r
    shown = f"{x:.3g}"
    if shown.isdigit():
        shown += ".0"
    if frac is not None:
        f = frac if big else 1 / frac
        if f.denominator != 1 and f.denominator < 1000:
            shown += f" (= {f.numerator}/{f.denominator})"
    return f"too {'large' if big else 'small'} by a factor ≈ {shown}"


#: The diagnosis of an answer computed in single precision, the same at self-check and at
#: grading: tolerances are set for float64 (about 16 significant digits); float32 keeps about
#: 7, so a right method in float32 can miss a tolerance by its round-off alone.
SINGLE_PRECISION = (
    "computed in single precision (float32), which keeps about 7 significant digits: too few "
    "for this tolerance; compute in float64 (numpy's default) and check again"
)
#: Significant bits of a half-precision number: values that need no more are left alone
#: (0.5, 1.25, small integers are exact in every precision and tell nothing).
_HALF_BITS = 11


def chosen_hint(failures, mistake_hints) -> str | None:
    """The hint the diagnosis of a failed answer chooses, or None for the question's staged
    hints (the same rule in the self-check and in the grading feedback).

    ``failures`` are the failed cases' diagnoses: objects with ``kind`` and ``mistake`` (the
    :class:`Verdict` of a comparison, or a case of the results; None and kind-less ones are
    skipped); ``mistake_hints`` maps a declared mistake's message to its own hint. The
    diagnosis chooses, never the order of the stages: a named mistake shows its own hint, or
    none when it has none -- its message says what to fix, and a stage about another step of
    the method would contradict it (a dof mistake is not helped by "weigh with Qyy"); an
    answer computed in single precision shows none either -- its method may well be right.
    """
    found = [f for f in failures if f is not None and getattr(f, "kind", None)]
    named = [f.mistake for f in found if f.kind == MistakeKind.NAMED and f.mistake]
    for mistake in named:
        if mistake_hints.get(mistake):
            return str(mistake_hints[mistake])
    if named:
        return ""
    if found and all(f.kind == MistakeKind.SINGLE_PRECISION for f in found):
        return ""
    return None


def single_precision(value: np.ndarray) -> bool:
    """Whether ``value`` was computed in float32 (or float16): its dtype says so, or every
    non-integral element is exactly a float32 number and one needs more bits than a float16.

    The codec keeps an array's dtype but turns a numpy scalar into a Python float, so a
    float32 scalar arrives as a float64 holding a float32 number; a number computed in float64
    is exactly a float32 number with probability about 2**-29.
    """
    arr = np.asarray(value)
    if arr.dtype in (np.float32, np.float16, np.complex64):
        return True
    if arr.dtype.kind != "f":
        return False
    x = arr[np.isfinite(arr)].astype(float)
    x = x[x != np.round(x)]
    if x.size == 0 or not bool(np.all(x.astype(np.float32).astype(float) == x)):
        return False
    mantissa, _ = np.frexp(x)
    return bool(np.any(np.mod(mantissa * 2.0**_HALF_BITS, 1.0) != 0))


#: A diagnosis: its kind and the words that say it (``(None, "")``: nothing recognised).
Diagnosis = tuple[MistakeKind | None, str]
_UNKNOWN: Diagnosis = (None, "")


def _diagnose(
    e: np.ndarray, g: np.ndarray, rtol: float, atol: float, hidden: bool = False
) -> Diagnosis:
    """:func:`_kind_of_wrong`, or nothing should it fail: a diagnosis must never break a
    verdict."""
    try:
        return _kind_of_wrong(e, g, rtol, atol, hidden)
    except Exception:
        return _UNKNOWN


def _kind_of_wrong(
    e: np.ndarray, g: np.ndarray, rtol: float, atol: float, hidden: bool = False
) -> Diagnosis:
    """What kind of wrong ``g`` is against ``e`` (same shape, not close), and its words
    (``hidden``: a hidden case's, which say no factor, see :func:`_factor_text`).

    Never names a value of ``e``: only relations (sign, factor, order, transpose, the number of
    matching digits), and none for integers, where any relation gives the answer away."""
    lo_rtol = max(rtol, 1e-7)  # relations hold only to round-off, whatever the tolerance
    ef = e.astype(complex if e.dtype.kind == "c" else float)
    gf = g.astype(ef.dtype)

    # an answer that nearly matches as it is (round-off, a symmetric matrix, a palindrome)
    # would "match" after a transform that leaves it as it was: no relation is named then
    near = _close(ef, gf, 4 * lo_rtol, 4 * atol)
    if (
        not near
        and e.ndim == 2
        and e.shape[0] == e.shape[1] > 1
        and _close(ef, gf.T, lo_rtol, atol)
    ):
        return MistakeKind.TRANSPOSED, "transposed: rows and columns are swapped"
    if not near and _close(ef, -gf, lo_rtol, atol):
        return MistakeKind.SIGN, "the sign is flipped"
    if not near and e.ndim == 1 and e.size > 1 and e.dtype.kind != "c":
        if _close(ef, gf[::-1], lo_rtol, atol):
            return MistakeKind.ORDER, "the right values in reverse order"
        if _close(np.sort(ef), np.sort(gf), lo_rtol, atol):
            return MistakeKind.ORDER, "the right values in another order (a permutation)"
    if e.dtype.kind in "iu":
        # no relation for integers: "one too large" or a factor would name the answer (an index
        # or a count is found in one or two guesses); the question's hint says what counts from 0
        return _UNKNOWN
    if e.dtype.kind == "c":
        return _UNKNOWN
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.abs(gf - ef) / np.abs(ef)
    # a near miss: the elements outside the tolerance agree to a few digits
    outside = np.abs(gf - ef) > atol + rtol * np.abs(ef)
    worst = float(np.max(rel[outside])) if np.any(outside) else math.inf
    if math.isfinite(worst) and 0 < worst < 1e-3:
        digits = max(1, math.floor(-math.log10(worst)))
        return MistakeKind.NEAR_MISS, (
            f"close: it agrees to about {digits} significant digits, but not within the "
            "tolerance (rounded, or a printed number typed in?)"
        )
    nonzero = np.abs(ef) > atol
    if bool(np.any(nonzero)) and bool(np.all(gf == 0)):
        return MistakeKind.ZEROS, "all zeros (a result never filled in?)"
    if bool(np.any(nonzero)) and bool(np.all(np.abs(gf[~nonzero]) <= atol)):
        with np.errstate(divide="ignore", invalid="ignore"):
            ratios = gf[nonzero] / ef[nonzero]
        r = float(np.median(ratios))
        if (
            math.isfinite(r)
            and r != 0
            and abs(abs(r) - 1) > 1e-3
            and _close(r * ef, gf, lo_rtol, atol * abs(r))
        ):
            frac = _simple_ratio(abs(r))
            if frac is not None or np.count_nonzero(nonzero) > 1:
                text = _factor_text(abs(r), frac, hidden)
                return MistakeKind.FACTOR, ("the sign is flipped and " if r < 0 else "") + text
        if (
            bool(np.all(ef >= 0))
            and _close(ef**2, gf, lo_rtol, atol)
            and not _close(ef, gf, lo_rtol, atol)
        ):
            return MistakeKind.SQUARE, SQUARED_TEXT
        if bool(np.all(gf >= 0)) and _close(ef, gf**2, lo_rtol, atol):
            return MistakeKind.SQUARE, SQUARE_ROOT_TEXT
    return _UNKNOWN


SQUARED_TEXT = (
    "looks like the square of the answer (a variance where a standard deviation is asked?)"
)
SQUARE_ROOT_TEXT = (
    "looks like the square root of the answer (a standard deviation where a variance is asked?)"
)


# -- the messages both comparisons give about wrong elements ---------------------------------
def _first_at(index, shape) -> str:
    return _where(index, shape).strip()[3:]


def decisions_kind(wrong: int, size: int, shape) -> MistakeKind:
    """The kind of :func:`decisions_wrong`: the opposite decision(s), or some of them wrong."""
    return MistakeKind.OPPOSITE if not shape or wrong == size else MistakeKind.DECISIONS


def decisions_wrong(label: str, wrong: int, size: int, first, shape) -> str:
    """Bools that differ: the opposite decision, every decision, or how many and the first."""
    if not shape:
        return f"{label}: the opposite of the right decision"
    if wrong == size:
        return f"{label}: every decision is the opposite (a comparison the wrong way round?)"
    return f"{label}: {wrong} of {size} wrong, first at {_first_at(first, shape)}"


def integers_wrong(label: str, wrong: int, size: int, first, shape, kind: str) -> str:
    """Integers that differ: how many and the first (arrays), and the kind of wrong."""
    where = "" if not shape else f" {wrong} of {size} wrong, first at {_first_at(first, shape)};"
    s = "s" if shape else ""
    return f"{label}:{where} {kind or 'not the right integer' + s} (integers must match exactly)"


def not_finite(label: str, g: np.ndarray, bad: np.ndarray) -> str:
    """'got NaN' or 'got inf' at the first such wrong element of ``g``; '' when there is none."""
    nan = np.isnan(g) & bad
    if np.any(nan):
        j = tuple(np.argwhere(nan)[0]) if g.ndim else ()
        return f"{label}: got NaN{_where(j, g.shape)} (a 0/0, or an empty mean?)"
    inf = np.isinf(g) & bad
    if np.any(inf):
        j = tuple(np.argwhere(inf)[0]) if g.ndim else ()
        return f"{label}: got inf{_where(j, g.shape)} (a division by zero?)"
    return ""


def numbers_wrong(label, wrong, size, which, index, shape, kind, rtol, atol) -> str:
    """Floats outside the tolerance: how many and ``which`` one (arrays), the kind of wrong."""
    count = (
        f"{wrong} of {size} elements wrong, the {which} at {_first_at(index, shape)}; "
        if size > 1
        else ""
    )
    kind = kind or "not within the tolerance"
    return f"{label}: {count}{kind}; {_tolerance_text(rtol, atol)}"


def outside_band(label: str, where: str) -> str:
    """A value outside an accepted band: what that says of the method, never the band."""
    return (
        f"{label}: outside the accepted band{where} (the band allows for the Monte Carlo "
        "spread of a right answer: the method or its parameters differ)"
    )


def band_shape_wrong(label: str, shape: tuple, arr: np.ndarray) -> Verdict | None:
    """A band stored per cell needs an answer of its ``shape``; a band of one number (shape
    ``()``) holds every element of an array. The refusal, or None when the shape is right."""
    if shape and arr.shape != shape:
        text = f"{label}: expected shape {shape}, got {tuple(arr.shape)}"
        return Verdict(False, text, text, MistakeKind.SHAPE)
    return None


# -- the structural walk ---------------------------------------------------------------------
class StructuralWalk:
    """``got`` against an expected value, walked in parallel: one place for the structure.

    The walk checks what the expected value's type and shape say -- None, a string, a
    sequence (its length; a 1-D real array may answer a sequence of numbers), a dict (its
    keys), numbers (a number at all, the shape, bools, integers, real or complex) -- with the
    messages about it, and recurses into items and dict values (first wrong one wins). A
    subclass supplies the leaves: how numbers, strings and bands are compared, whether a
    transposed matrix or another order of the items would match, and their messages. Used by
    :func:`compare` (the expected value in the clear) and by
    :func:`course.grading.authoring.seal.sealed_compare` (sealed: there the expected value is a node of
    the sealed tree, and :meth:`stand_in` gives a value of its type and shape), and by
    :func:`check_signature` (there it is a :func:`signature`, which holds no value).
    """

    #: the record of "the right items in another order" keeps the first wrong item's detail
    order_detail = True

    def stand_in(self, expected):
        """A value with the type, shape and field names of ``expected``."""
        return expected

    def item(self, expected, k: int):
        return expected[k]

    def value_at(self, expected, key):
        return expected[key]

    def walk(self, expected, got, path: str = "") -> Verdict:
        label = _label(path)
        like = self.stand_in(expected)  # a value of its type and shape
        if isinstance(like, Band):
            arr = _numeric(got)
            if arr is None or arr.dtype.kind == "c":
                text = f"{label}: expected a real number, got {describe(got)}"
                return Verdict(False, text, text, MistakeKind.TYPE)
            return self.band(expected, arr, label)
        if like is None:
            text = "" if got is None else f"{label}: expected None, got {describe(got)}"
            return Verdict(got is None, text, text, MistakeKind.TYPE)
        if isinstance(like, str):
            if not isinstance(got, str):
                return self.not_a_string(expected, got, label)
            return self.string(expected, got, label)
        if isinstance(like, (tuple, list)):
            return self._sequence(expected, like, got, path, label)
        if isinstance(like, dict):
            if not isinstance(got, dict):
                text = f"{label}: expected a dict with keys {sorted(like)}, got {describe(got)}"
                return Verdict(False, text, text, MistakeKind.TYPE)
            if set(got) != set(like):
                text = f"{label}: expected keys {sorted(like)}, got {sorted(map(str, got))[:10]}"
                return Verdict(False, text, text, MistakeKind.TYPE)
            for k in sorted(like):
                v = self.walk(self.value_at(expected, k), got[k], _key_path(path, k))
                if not v.ok:
                    return v
            return Verdict(True)
        exp = _numeric(like)
        if exp is None:
            raise TypeError(f"cannot compare against expected value of type {type(like).__name__}")
        arr = _numeric(got)
        if arr is None:
            text = f"{label}: expected {describe(like)}, got {describe(got)}"
            return Verdict(False, text, text, MistakeKind.TYPE)
        if arr.shape != exp.shape:
            return self._shape_mismatch(expected, exp, arr, label)
        s = "s" if exp.ndim else ""
        if _is_boolish(like):
            if arr.dtype.kind not in "biu" or (
                arr.dtype.kind in "iu" and np.any((arr != 0) & (arr != 1))
            ):
                text = f"{label}: expected bool{s}, got {describe(got)}"
                return Verdict(False, text, text, MistakeKind.TYPE)
        elif _is_intish(like):
            if arr.dtype.kind == "c" or (arr.dtype.kind == "f" and not np.all(np.isfinite(arr))):
                text = f"{label}: expected integer{s}, got {describe(got)}"
                return Verdict(False, text, text, MistakeKind.TYPE)
        elif arr.dtype.kind == "c" and exp.dtype.kind != "c":
            text = f"{label}: expected real numbers, got complex"
            return Verdict(False, text, text, MistakeKind.TYPE)
        return self.numbers(expected, exp, arr, label)

    def _sequence(self, expected, like, got, path: str, label: str) -> Verdict:
        items = sequence_items(like, got)
        if items is None:
            text = f"{label}: expected {sequence_text(like)}, got {describe(got)}"
            return Verdict(False, text, text, MistakeKind.TYPE)
        if len(items) != len(like):
            return length_mismatch(label, len(like), len(items))
        for k, g in enumerate(items):
            first = self.walk(self.item(expected, k), g, _item_path(path, like, items, k))
            if not first.ok:
                if self.in_another_order(expected, items):
                    text = f"{label}: the right items in another order"
                    detail = first.detail if self.order_detail else text
                    return Verdict(False, text, detail, MistakeKind.ORDER)
                return first
        return Verdict(True)

    def _shape_mismatch(self, expected, exp: np.ndarray, arr: np.ndarray, label: str) -> Verdict:
        hint, kind = "", MistakeKind.SHAPE
        if arr.size == exp.size and arr.size > 0:
            if exp.ndim == 2 and arr.shape == exp.shape[::-1] and self.transposed(expected, arr):
                hint, kind = ": transposed, rows and columns are swapped", MistakeKind.TRANSPOSED
            else:
                hint = " (the right number of elements: reshape, ravel or a missing [:, 0]?)"
        elif exp.ndim == arr.ndim == 1 and abs(arr.shape[0] - exp.shape[0]) == 1:
            hint = (
                f": one element too {'many' if arr.shape[0] > exp.shape[0] else 'few'}"
                " (off by one in a range or slice?)"
            )
            kind = MistakeKind.ONE_TOO_MANY_OR_FEW
        detail = f"{label}: expected shape {tuple(exp.shape)}, got shape {tuple(arr.shape)}"
        return Verdict(False, detail + hint, detail, kind)

    # -- the leaves: a subclass's ------------------------------------------------------------
    def band(self, expected, arr: np.ndarray, label: str) -> Verdict:
        """``arr`` (real numbers) against an accepted band."""
        raise NotImplementedError

    def not_a_string(self, expected, got, label: str) -> Verdict:
        text = f"{label}: expected a string, got {describe(got)}"
        return Verdict(False, text, text, MistakeKind.TYPE)

    def string(self, expected, got: str, label: str) -> Verdict:
        raise NotImplementedError

    def numbers(self, expected, exp: np.ndarray, arr: np.ndarray, label: str) -> Verdict:
        """``arr`` against numbers of its shape and of an agreeing kind; ``exp`` is the stand-in
        as an array."""
        raise NotImplementedError

    def transposed(self, expected, arr: np.ndarray) -> bool:
        """Whether ``arr.T`` matches (``arr`` has the transposed shape of a matrix)."""
        raise NotImplementedError

    def in_another_order(self, expected, items) -> bool:
        """Whether the sequence ``items`` (not a match) holds the right items in another order."""
        raise NotImplementedError


class _Clear(StructuralWalk):
    """The comparison with the expected value in the clear, with the exact tolerance
    (``hidden``: of a hidden case, whose messages name no factor)."""

    def __init__(self, rtol: float, atol: float, hidden: bool = False):
        self.rtol, self.atol, self.hidden = rtol, atol, hidden

    def band(self, expected: Band, arr: np.ndarray, label: str) -> Verdict:
        lo, hi = np.asarray(expected.lo, float), np.asarray(expected.hi, float)
        try:
            arr_b, lo_b, hi_b = np.broadcast_arrays(arr.astype(float), lo, hi)
        except ValueError:
            text = f"{label}: expected shape {lo.shape}, got {arr.shape}"
            return Verdict(False, text, text, MistakeKind.SHAPE)
        if arr.shape != np.broadcast_shapes(arr.shape, lo.shape):
            text = f"{label}: expected shape {lo.shape}, got {arr.shape}"
            return Verdict(False, text, text, MistakeKind.SHAPE)
        inside = (arr_b >= lo_b) & (arr_b <= hi_b)
        if bool(np.all(inside)):
            return Verdict(True)
        bad = np.argwhere(~inside)[0] if arr_b.ndim else ()
        at = tuple(bad)
        g = arr_b[at] if arr_b.ndim else arr_b[()]
        low = float(lo_b[at] if lo_b.ndim else lo_b[()])
        high = float(hi_b[at] if hi_b.ndim else hi_b[()])
        where = _where(at, arr_b.shape)
        if np.isnan(g):
            text = f"{label}: got NaN{where}"
            return Verdict(False, text, text, MistakeKind.NOT_FINITE)
        return Verdict(
            False,
            outside_band(label, where),
            f"{label}: got {_fmt(float(g))}{where}, outside the accepted [{_fmt(low)}, {_fmt(high)}]",
            MistakeKind.OUTSIDE_BAND,
        )

    def not_a_string(self, expected: str, got, label: str) -> Verdict:
        message = super().not_a_string(expected, got, label).message
        return Verdict(False, message, _string_detail(expected, got, label), MistakeKind.TYPE)

    def string(self, expected: str, got: str, label: str) -> Verdict:
        if got == expected:
            return Verdict(True)
        detail = _string_detail(expected, got, label)
        if got.strip().casefold() == expected.strip().casefold():
            text = f"{label}: differs only in upper/lower case or spaces"
            return Verdict(False, text, detail, MistakeKind.STRING_CASE)
        return Verdict(False, f"{label}: not the right string", detail, MistakeKind.WRONG_VALUE)

    def transposed(self, expected, arr: np.ndarray) -> bool:
        exp = _numeric(expected)
        return _close(exp.astype(float), arr.T.astype(float), max(self.rtol, 1e-7), self.atol)

    def in_another_order(self, expected, items) -> bool:
        return len(expected) > 1 and _is_permutation(self, expected, items)

    def numbers(self, expected, exp: np.ndarray, arr: np.ndarray, label: str) -> Verdict:
        rtol, atol = self.rtol, self.atol
        if _is_boolish(expected):
            diff = arr.astype(bool) != exp
            if not np.any(diff):
                return Verdict(True)
            i = tuple(np.argwhere(diff)[0]) if diff.ndim else ()
            g_bool = bool(arr[i]) if arr.ndim else bool(arr[()])
            wrong = int(np.sum(diff))
            message = decisions_wrong(label, wrong, diff.size, i, diff.shape)
            return Verdict(
                False,
                message,
                f"{label}{_where(i, diff.shape)}: expected {not g_bool}, got {g_bool}",
                decisions_kind(wrong, diff.size, diff.shape),
            )
        if _is_intish(expected):
            diff = arr != exp
            if not np.any(diff):
                return Verdict(True)
            i = tuple(np.argwhere(diff)[0]) if diff.ndim else ()
            e_i, g_i = (exp[i], arr[i]) if exp.ndim else (exp[()], arr[()])
            kind, text = _diagnose(exp, arr, 0.0, 0.0)
            message = integers_wrong(label, int(np.sum(diff)), diff.size, i, diff.shape, text)
            return Verdict(
                False,
                message,
                f"{label}{_where(i, diff.shape)}: expected {int(e_i)}, got {_fmt(float(g_i))}",
                kind,
            )
        # floats / complex
        e = exp.astype(complex if exp.dtype.kind == "c" else float)
        g = arr.astype(e.dtype)
        both_nan = np.isnan(e) & np.isnan(g)
        with np.errstate(invalid="ignore", over="ignore"):
            err = np.abs(g - e)
            tol = atol + rtol * np.abs(e)
            same_inf = np.isinf(e) & (g == e)
            good = both_nan | same_inf | (err <= tol)
        if bool(np.all(good)):
            return Verdict(True)
        bad = ~good
        score = np.where(bad, np.nan_to_num(err - tol, nan=np.inf, posinf=np.inf), -np.inf)
        i = np.unravel_index(int(np.argmax(score)), score.shape) if score.ndim else ()
        ei = e[i] if e.ndim else e[()]
        gi = g[i] if g.ndim else g[()]
        a, b = _digits_apart(
            ei if e.dtype.kind == "c" else ei.real, gi if g.dtype.kind == "c" else gi.real
        )
        detail = f"{label}{_where(i, e.shape)}: expected {a}, got {b} (largest error {_fmt(float(err[i] if err.ndim else err[()]))})"
        unfinished = not_finite(label, g, bad)
        if unfinished:
            return Verdict(False, unfinished, detail, MistakeKind.NOT_FINITE)
        if single_precision(arr):
            kind, text = MistakeKind.SINGLE_PRECISION, SINGLE_PRECISION
        else:
            kind, text = _diagnose(e, g, rtol, atol, self.hidden)
        if kind is None and bad.size > 1 and 0 < int(np.sum(bad)) < bad.size:
            kind, sub = _diagnose(e[bad], g[bad], rtol, atol, self.hidden)
            text = f"on the wrong elements {sub}" if sub else ""
        message = numbers_wrong(
            label, int(np.sum(bad)), bad.size, "worst", i, e.shape, text, rtol, atol
        )
        return Verdict(False, message, detail, kind)


def _string_detail(expected: str, got, label: str) -> str:
    return f"{label}: expected {expected!r}, got {got!r}"[:300]


def _match_mistake(mistakes, expected, got, rtol, atol) -> str | None:
    """The message of the first mistake ``got`` matches: as a whole, or else field-wise
    (:func:`fieldwise_mistake`)."""
    for message, wrong in mistakes:
        try:
            if compare(wrong, got, rtol, atol).ok:
                return str(message)
        except TypeError:
            continue
    if not isinstance(expected, (tuple, list)):
        return None
    for message, wrong in mistakes:
        if isinstance(wrong, (tuple, list)) and fieldwise_mistake(
            expected, expected, wrong, got, lambda want, item: compare(want, item, rtol, atol).ok
        ):
            return str(message)
    return None


def fieldwise_mistake(like, right, wrong, got, same) -> bool:
    """Whether the result ``got`` makes a mistake in some of its fields and is right in the
    others: every item matches its ``right`` item or its ``wrong`` one, and one matches only
    the ``wrong`` one. ``like`` is a value of the expected type (a tuple or list), ``same(want,
    item)`` compares one item with one item of ``right`` or ``wrong``.

    So a mistake in one field (the filtered variance for P, with K right) is named although
    the whole result matches neither the answer nor the mistake.
    """
    items = sequence_items(like, got)
    if items is None or not len(items) == len(right) == len(wrong) > 1:
        return False
    named = False
    for e, w, g in zip(right, wrong, items):
        try:
            if same(e, g):
                continue
            if not same(w, g):
                return False
        except TypeError:
            return False
        named = True
    return named


def compare(
    expected: Any,
    got: Any,
    rtol: float = 1e-7,
    atol: float = 1e-9,
    reveal: bool = True,
    path: str = "",
    mistakes=(),
    hidden: bool = False,
    others=(),
) -> Verdict:
    """Compare ``got`` with ``expected``.

    Floats and float arrays: equal shapes and ``|got - expected| <= atol + rtol*|expected|``
    element-wise (NaN only matches NaN). Bools and ints: exact. Strings and None: exact.
    Tuples/lists: same length (either container type), element by element; items of named
    tuples are named by their fields. Dicts: same keys. :class:`Band`: every element of
    ``got`` inside ``[lo, hi]``. The structure is walked by :class:`StructuralWalk`, which
    the sealed self-check shares.

    The verdict's ``message`` never contains an expected value: it says what is wrong in kind
    (type, shape or length, NaN, the sign, a constant factor, transposed, another order, off
    by one, a near miss) with the tolerance. ``mistakes`` is a sequence of ``(message, wrong
    value)``: when ``got`` matches a wrong value (and not ``expected``) its message is shown;
    so it is when a tuple is right in some fields and makes the mistake in the others
    (:func:`fieldwise_mistake`). ``detail`` (expected and got, with enough digits to differ) is for instructors only;
    ``reveal=False`` leaves it without expected values too. ``hidden``: ``expected`` is a
    hidden case's, whose input the student does not see: the message then names no factor's
    value (which could tell that input). ``others``: right answers of OTHER data (the
    question's other cases, the demo ID's data, the notebook's practice cases): a wrong answer
    that matches one, and that no more specific diagnosis names, was hard-coded or computed
    from the wrong data, and is told so (never for integers or decisions, which match another
    case's by chance). ``kind`` (and ``mistake``) say the diagnosis as data.

    Examples
    --------
    >>> compare(2.0, 4.0).message
    'value: too large by a factor ≈ 2.0; tolerance |got - expected| <= atol 1e-09 + rtol 1e-07·|expected|'
    """
    verdict = _Clear(rtol, atol, hidden).walk(expected, got, path)
    if verdict.ok:
        return verdict
    named = _match_mistake(mistakes, expected, got, rtol, atol) if mistakes else None
    detail = verdict.detail if reveal else verdict.message
    if named:
        return Verdict(False, f"{_label(path)}: {named}", detail, MistakeKind.NAMED, named)
    if (
        others
        and verdict.kind not in SPECIFIC_KINDS
        and _other_data(expected, got, others, rtol, atol)
    ):
        return Verdict(False, f"{_label(path)}: {OTHER_DATA}", detail, MistakeKind.OTHER_DATA)
    return Verdict(False, verdict.message, detail, verdict.kind)


#: The diagnosis of a right answer for other data than the question's.
OTHER_DATA = (
    "this is the right answer for OTHER data (another case, the demo ID's or the notebook's "
    "practice data): compute it from the data you are given (the function's arguments, or "
    "your own data), not from numbers typed in or the notebook's other variables"
)


def _other_data(expected, got, others, rtol, atol) -> bool:
    """Whether ``got`` is one of ``others`` (see :func:`compare`); integers and decisions
    never are (a count or an index equals another case's by chance)."""
    arr = _numeric(expected)
    if arr is not None and arr.dtype.kind in "biu":
        return False
    for other in others:
        try:
            if compare(other, got, rtol, atol).ok:
                return True
        except (TypeError, ValueError):
            continue
    return False


def _is_permutation(walk: _Clear, expected, got) -> bool:
    """Every item of ``got`` matches a distinct item of ``expected`` (small sequences only)."""
    if len(expected) > 50:
        return False
    left = list(range(len(expected)))
    for g in got:
        for j in left:
            try:
                if walk.walk(expected[j], g, "").ok:
                    left.remove(j)
                    break
            except TypeError:
                return False
        else:
            return False
    return True


def signature(value: Any) -> Any:
    """The type/shape skeleton of a value, as plain data (ships instead of a private value)."""
    if isinstance(value, Band):
        return {"band": list(np.shape(value.lo))}
    if value is None:
        return {"none": True}
    if isinstance(value, str):
        return {"str": True}
    if isinstance(value, (tuple, list)) and value and all(isinstance(v, str) for v in value):
        # a list of names (a diagnosis): its length is part of the answer, not of its type
        return {"names": True}
    if isinstance(value, (tuple, list)):
        out: dict[str, Any] = {"sequence": [signature(v) for v in value]}
        fields = getattr(type(value), "_fields", None)
        if isinstance(fields, tuple) and len(fields) == len(value):
            out["fields"] = list(fields)
        elif isinstance(value, list):
            out["type"] = "list"  # so that a wrong answer is told "a list", as at grading
        return out
    if isinstance(value, dict):
        return {"dict": {str(k): signature(v) for k, v in value.items()}}
    arr = _numeric(value)
    if arr is None:
        raise TypeError(f"no signature for {type(value).__name__}")
    kind = {"b": "bool", "i": "int", "u": "int", "f": "float", "c": "complex"}[arr.dtype.kind]
    return {"kind": kind, "shape": list(arr.shape)}


def _signature_stand_in(sig: dict):
    """A value of the type, shape and field names ``sig`` records (zeros), for the walk."""
    if "band" in sig:
        zeros = np.zeros(sig["band"])
        return Band(zeros, zeros)
    if "none" in sig:
        return None
    if "str" in sig:
        return ""
    if "names" in sig:
        return []  # never walked (see _Signature.walk): its length is not known
    if "sequence" in sig:
        items = [_signature_stand_in(s) for s in sig["sequence"]]
        if sig.get("fields"):
            return _named_type(tuple(sig["fields"]))(*items)
        return items if sig.get("type") == "list" else tuple(items)
    if "dict" in sig:
        return {k: _signature_stand_in(s) for k, s in sig["dict"].items()}
    if not sig["shape"]:
        return {"bool": False, "int": 0, "float": 0.0, "complex": 0j}[sig["kind"]]
    dtype = {"bool": bool, "int": np.int64, "float": float, "complex": complex}[sig["kind"]]
    return np.zeros(sig["shape"], dtype=dtype)


class _Signature(StructuralWalk):
    """The structural walk against a signature: any value of the right kind and shape is
    right, except NaN or inf (a signature holds no value, so it can tell no other mistake)."""

    def stand_in(self, expected):
        return _signature_stand_in(expected)

    def item(self, expected, k: int):
        return expected["sequence"][k]

    def value_at(self, expected, key):
        return expected["dict"][key]

    def walk(self, expected, got, path: str = "") -> Verdict:
        if "names" not in expected:
            return super().walk(expected, got, path)
        # a list of names of any length: the length of a diagnosis is part of the answer
        if not isinstance(got, (tuple, list)):
            text = f"{_label(path)}: expected a list of strings, got {describe(got)}"
            return Verdict(False, text, text, MistakeKind.TYPE)
        for k, name in enumerate(got):
            if not isinstance(name, str):
                return self.not_a_string(expected, name, _item_path(path, got, got, k))
        return Verdict(True)

    def band(self, expected, arr: np.ndarray, label: str) -> Verdict:
        wrong_shape = band_shape_wrong(label, tuple(expected["band"]), arr)
        if wrong_shape is not None:
            return wrong_shape
        g = arr.astype(float)
        bad = ~np.isfinite(g)
        if not np.any(bad):
            return Verdict(True)
        first = tuple(np.argwhere(bad)[0]) if g.ndim else ()
        where = _where(first, g.shape)
        # as at grading: NaN is told as such, inf is outside any band
        if np.isnan(g[first]):
            text, kind = f"{label}: got NaN{where}", MistakeKind.NOT_FINITE
        else:
            text, kind = outside_band(label, where), MistakeKind.OUTSIDE_BAND
        return Verdict(False, text, text, kind)

    def string(self, expected, got: str, label: str) -> Verdict:
        return Verdict(True)

    def numbers(self, expected, exp: np.ndarray, arr: np.ndarray, label: str) -> Verdict:
        if arr.dtype.kind not in "fc":
            return Verdict(True)  # bools and integers are finite (the walk checked the kind)
        if expected["kind"] == "int" and not np.all(arr == np.floor(arr)):
            got = arr.item() if arr.ndim == 0 else arr
            text = f"{label}: expected integer{'s' if arr.ndim else ''}, got {describe(got)}"
            return Verdict(False, text, text, MistakeKind.TYPE)
        text = not_finite(label, arr, ~np.isfinite(arr))
        return Verdict(not text, text, text, MistakeKind.NOT_FINITE)

    def transposed(self, expected, arr: np.ndarray) -> bool:
        return False  # no value to tell

    def in_another_order(self, expected, items) -> bool:
        return False


def check_signature(sig: Any, got: Any, path: str = "") -> Verdict:
    """Whether ``got`` has the type and shape of ``sig`` (and is finite where numeric).

    ``sig`` comes from :func:`signature`. The structure is walked by :class:`StructuralWalk`,
    so a structural mistake reads as in :func:`compare`; the leaves accept any number of the
    right kind and shape except NaN or inf, and any string.

    Examples
    --------
    >>> check_signature(signature((1.5, 2.5)), (1.5, 2.5, 3.5)).message
    'value: expected length 2, got length 3: one item too many'
    """
    return _Signature().walk(sig, got, path)
