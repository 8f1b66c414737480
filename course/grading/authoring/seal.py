"""Sealed public checks: what ``checks.json`` ships instead of an expected value.

A release used to ship each public case's expected value (base64 in ``__ndarray__``), so a
student who decoded ``checks.json`` had the answer of every public value question. A sealed
value keeps what a comparison needs in the clear -- the type, shape, dtype, field names and
dict keys -- and replaces every number by a salted, deliberately slow hash
(``hashlib.pbkdf2_hmac``, :data:`ITERATIONS` rounds of SHA-256, about a millisecond each) of
a quantisation of that number on a grid tied to the question's tolerance. The self-check
quantises the student's value the same way and compares hashes. Grading (``course grade``)
is unchanged: it compares with the true references, in the clear, with the exact tolerance.

The grid of a float element
---------------------------
Let ``tol(e) = atol + rtol*|e|`` be the question's tolerance. The magnitude of ``e`` is
rounded up to a quarter binade, ``q = ceil(4*log2|e|)`` (clipped below at the magnitude where
``atol`` dominates), and the grid step is ``h(q) = 2*(atol + rtol*2**(q/4))``, so that
``tol(e) <= h/2`` (``rtol`` taken at least ``2**-39``, about 1.8e-12: finer tolerances are
not resolved, and ``e/h`` stays below ``2**38`` so that it is computed far more precisely than
the cells need). The element is sealed as ``hash(q, floor(e/h))``. Neither ``q`` nor ``h``
is stored: the self-check derives the candidate ``q`` from the student's own number ``s``
(the one or two quarter binades that a right answer's ``e`` can lie in), and for each ``q``
tries the cell of ``s/h`` and its two neighbours at distance ``h/2``. Hence:

* **guaranteed band** -- every ``s`` with ``|s - e| <= tol(e)`` passes: ``e/h`` lies within
  1/2 of ``s/h``, so its cell is among the cells tried, whatever side of a grid line it is;
* **stated band** -- a pass needs the same ``q`` and a cell at most one away, so
  ``|s - e| < 1.5*h(q)``, which is at most ``6*tol(e)`` (``3.6*tol(e)`` unless ``atol``
  dominates; with ``rtol`` below ``2**-39`` read ``2**-39`` for it); :func:`stated_band`
  gives the exact bound. Between the two bands the self-check
  may say PASS where grading, with the exact tolerance, says FAIL.

Each element is hashed on its own (the salt names the element), so one failing element does
not hide the others, and no combination of ambiguous cells has to be enumerated: a right
answer of n elements costs n to 3n hashes, never an exponential number.

Exact values
------------
Integers, booleans, strings and ``None`` are hashed exactly (integers match a float that is
integral, as :func:`course.grading.compare.compare` does); NaN and +-inf are their own
payloads. A float question with ``rtol = atol = 0`` is exact too.

Bands
-----
A :class:`~course.grading.codec.Band` (an accepted interval, e.g. a binomial band of a Monte
Carlo rate) is sealed too: its limits are built from a reference rate that the question asks
the student to simulate, so its midpoint would be an answer. The interval is cut into
:data:`BAND_CELLS` cells of width ``h = (hi - lo)/16`` (``h`` in the clear, which tells the
band's width, a function of the public number of runs) and the hash of every cell that meets
``[lo, hi]`` is stored, sorted. Every value in ``[lo, hi]`` passes; every value farther than
``h`` outside fails.

Property checks of private (personal) values ship no value at all, only a type/shape
signature and the name of a public property function: nothing to seal. Choice options are
public text by construction and ship in the clear; the right option never ships.

What a sealed check leaks
-------------------------
Nothing beyond what the self-check reveals as an oracle. The check answers "does ``s``
pass?", element by element (its messages already say how many elements are wrong and where);
a sealed element answers exactly that question and nothing else: its hash is a function of
the cell, and every value of the cell passes or fails alike. Without the stored ``q`` or ``h``
the file does not even say the order of magnitude. Recovering an answer from the file is
therefore a search with the oracle, made slower by the hash: a float with ``rtol = 1e-8``
has about ``0.25/rtol = 2.5e7`` cells per quarter binade, i.e. hours per element at a
millisecond per try. A loose tolerance (``rtol = 1e-4``) or a small integer (an index, a
count) is found in seconds -- exactly as with the self-check itself, which is a public
oracle by design; such a question must not rely on its public case being secret (the
graded answer lives in hidden or personal cases). The salt (unique per assignment, question,
case and element, derived from the assignment's ``checks.py``) stops precomputed tables and
makes equal numbers in two places hash differently. It is derived, not random, so that a
release stays byte-for-byte reproducible.

Diagnostics
-----------
The structure -- types, shapes, lengths, field names, dict keys, and every message about
them -- is walked by :class:`course.grading.compare.StructuralWalk`, the same walk as
grading's; only the leaves here compare hashes instead of numbers and strings.

The automatic kind-of-wrong messages need no expected value: the self-check tries transforms
of the STUDENT's value against the seal -- ``-s``, ``s.T``, ``s[::-1]``, a permutation
(small arrays), ``s -+ 1`` for integers, ``s/f`` for a fixed list of factors
(:data:`FACTORS`), ``sqrt(s)`` and ``s**2`` -- each stopping at the first element that does
not match. The "close: agrees to about N digits" diagnosis is not offered: a coarse seal
would let the file be searched at the coarse precision first.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import math
from fractions import Fraction
from typing import Any

import numpy as np

from course.grading.codec import Band, _named_type
from course.grading.compare import (
    SINGLE_PRECISION,
    SQUARE_ROOT_TEXT,
    SQUARED_TEXT,
    Diagnosis,
    StructuralWalk,
    Verdict,
    _factor_text,
    _key_path,
    _label,
    _numeric,
    _where,
    band_shape_wrong,
    decisions_kind,
    decisions_wrong,
    fieldwise_mistake,
    integers_wrong,
    not_finite,
    numbers_wrong,
    outside_band,
    single_precision,
)
from course.grading.vocabulary import MistakeKind

__all__ = [
    "BAND_CELLS",
    "FACTORS",
    "ITERATIONS",
    "SEAL_TAG",
    "is_sealed",
    "make_salt",
    "matches",
    "seal",
    "sealed_compare",
    "stated_band",
]

#: The tag of a sealed value in ``checks.json``.
SEAL_TAG = "__sealed__"
#: PBKDF2-SHA256 rounds per hash: about a millisecond, so a right answer of n elements costs
#: n to 3n ms to check, and a search of the file costs a millisecond per try.
ITERATIONS = 2000
_DIGEST_BYTES = 12
#: Quarter binades: the grid of magnitude |e| is at most 2**(1/4) too coarse.
_STEPS_PER_BINADE = 4
#: Cells of a sealed band.
BAND_CELLS = 16
#: The constant factors the self-check tries (``too large by a factor ≈ 2.0``).
FACTORS = tuple(
    Fraction(f)
    for f in ("2", "3", "4", "10", "100", "1/2", "1/3", "1/4", "1/10", "1/100", "3/2", "2/3")
) + (Fraction(4, 3), Fraction(3, 4))
#: Largest 1-D array for which another order (a permutation) is tried.
_MAX_PERMUTATION = 6
# a guard on the cells tried around s/h: the rounding of s/h (|s/h| < 2**38, so an error
# below 2**-14) cannot drop the right cell
_EPS = 1e-3
#: The finest relative grid: tolerances below it are not resolved (float64 round-off is
#: 1.1e-16; the public checks use rtol >= 1e-10).
_MIN_RTOL = 2.0**-39


def make_salt(*parts: Any) -> str:
    """A salt unique to ``parts`` (assignment digest, question, case): 16 bytes, hex."""
    h = hashlib.sha256(b"course-seal-v1")
    for part in parts:
        h.update(b"\0" + str(part).encode("utf-8"))
    return h.hexdigest()[:32]


@functools.lru_cache(maxsize=65536)
def _digest(salt: str, iterations: int, where: str, payload: str) -> str:
    return hashlib.pbkdf2_hmac(
        "sha256",
        payload.encode("utf-8"),
        f"{salt}|{where}".encode(),
        iterations,
        _DIGEST_BYTES,
    ).hex()


class _Ctx:
    """The salt, cost and tolerance of one sealed value."""

    def __init__(self, salt: str, iterations: int, rtol: float, atol: float, explain=True):
        self.salt, self.iterations = salt, int(iterations)
        self.rtol, self.atol = float(rtol), float(atol)
        # False: only whether it matches (no diagnosis, first mismatch ends it): the price of
        # a comparison is its hashes, and a declared mistake or a permutation needs no words
        self.explain = explain

    def quiet(self) -> _Ctx:
        return _Ctx(self.salt, self.iterations, self.rtol, self.atol, explain=False)

    def hash(self, where: str, payload: str) -> str:
        return _digest(self.salt, self.iterations, where, payload)


# -- the grid --------------------------------------------------------------------------------
def _exact(rtol: float, atol: float) -> bool:
    return rtol <= 0.0 and atol <= 0.0


def _grid_rtol(rtol: float) -> float:
    """``rtol`` as the grid uses it: at least :data:`_MIN_RTOL`, so that ``|e/h| < 2**38``
    and ``e/h`` is computed to far better than the margin of the cells tried."""
    return max(rtol, _MIN_RTOL)


def _q_floor(rtol: float, atol: float) -> int | None:
    """The smallest quarter binade: below it ``atol`` dominates the grid (None: no floor)."""
    if atol <= 0.0:
        return None
    return math.floor(_STEPS_PER_BINADE * math.log2(atol / _grid_rtol(rtol))) - _STEPS_PER_BINADE


def _q_of(x: float, rtol: float, atol: float) -> int | None:
    """The quarter binade of magnitude ``x >= 0`` (None: beyond the float range)."""
    floor = _q_floor(rtol, atol)
    if not math.isfinite(x):
        return None
    if x <= 0.0:
        return floor
    q = math.ceil(_STEPS_PER_BINADE * math.log2(x))
    return q if floor is None else max(q, floor)


def _step(q: int | None, rtol: float, atol: float) -> float:
    """Grid step ``h(q) = 2*(atol + rtol*2**(q/4))`` (inf or 0 when out of range)."""
    if q is None:
        return math.inf
    try:
        scale = math.ldexp(2.0 ** ((q % _STEPS_PER_BINADE) / _STEPS_PER_BINADE), q // 4)
    except OverflowError:
        return math.inf
    return 2.0 * (atol + _grid_rtol(rtol) * scale)


def _usable(h: float, x: float) -> bool:
    return 0.0 < h < math.inf and math.isfinite(x / h) and abs(x / h) < 2.0**62


def _special(x: float) -> str | None:
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "+inf" if x > 0 else "-inf"
    return None


def _float_payload(e: float, rtol: float, atol: float) -> str:
    """The payload sealed for expected element ``e``."""
    e = float(e) + 0.0  # -0.0 is 0.0
    special = _special(e)
    if special:
        return special
    if _exact(rtol, atol):
        return f"x|{e!r}"
    if atol <= 0.0 and e == 0.0:
        return "zero"
    q = _q_of(abs(e), rtol, atol)
    h = _step(q, rtol, atol)
    if not _usable(h, e):
        return f"x|{e!r}"
    return f"g|{q}|{math.floor(e / h)}"


def _float_candidates(s: float, rtol: float, atol: float) -> list[str]:
    """The payloads a right answer ``s`` can match (its cell first)."""
    s = float(s) + 0.0
    special = _special(s)
    if special:
        return [special]
    if _exact(rtol, atol):
        return [f"x|{s!r}"]
    if atol <= 0.0 and s == 0.0:
        return ["zero"]
    out: list[str] = []
    # |e| of a right answer lies within t of |s|: its quarter binade is in this range
    t = 1.01 * (atol + rtol * (abs(s) + atol) / (1.0 - min(rtol, 0.5))) + 1e-300
    low = max(abs(s) - t, abs(s) / 2.0 if atol <= 0.0 else 0.0)
    q_lo, q_hi = _q_of(low, rtol, atol), _q_of(abs(s) + t, rtol, atol)
    if q_lo is None or q_hi is None:  # s beyond the float range
        return [f"x|{s!r}"]
    qs = list(range(q_lo, min(q_hi, q_lo + 8) + 1))
    for q in qs:
        h = _step(q, rtol, atol)
        if not _usable(h, s):
            out.append(f"x|{s!r}")
            continue
        x = s / h
        for k in (math.floor(x), math.floor(x - 0.5 - _EPS), math.floor(x + 0.5 + _EPS)):
            payload = f"g|{q}|{k}"
            if payload not in out:
                out.append(payload)
    return out


def stated_band(e: float, rtol: float, atol: float) -> float:
    """The largest ``|s - e|`` that a sealed check of ``e`` may accept (see the module
    docstring); every ``|s - e| <= atol + rtol*|e|`` is accepted."""
    e = float(e)
    if _exact(rtol, atol) or not math.isfinite(e) or (atol <= 0.0 and e == 0.0):
        return 0.0
    q = _q_of(abs(e), rtol, atol)
    h = _step(q, rtol, atol)
    if not _usable(h, e):
        return 0.0
    return (1.5 + 2 * _EPS) * h


# -- sealing ---------------------------------------------------------------------------------
def _py_type(value) -> str:
    if isinstance(value, np.ndarray):
        return "array"
    if isinstance(value, (bool, np.bool_)):
        return "bool"
    if isinstance(value, (int, np.integer)):
        return "int"
    if isinstance(value, (complex, np.complexfloating)):
        return "complex"
    return "float"


def _kind_of(arr: np.ndarray) -> str:
    return {"b": "b", "i": "i", "u": "i", "f": "f", "c": "c"}[arr.dtype.kind]


def _complex_payload(e: complex, rtol: float, atol: float) -> str:
    # both parts on the grid of |e|: tol(e) bounds each part's error
    mag = abs(e) if math.isfinite(abs(e)) else 0.0
    re = _float_payload_at(e.real, mag, rtol, atol)
    im = _float_payload_at(e.imag, mag, rtol, atol)
    return f"c|{re}|{im}"


def _float_payload_at(x: float, mag: float, rtol: float, atol: float) -> str:
    """``x`` on the grid of magnitude ``mag`` (a part of a complex number)."""
    special = _special(x)
    if special or _exact(rtol, atol) or (atol <= 0.0 and mag == 0.0):
        return special or _float_payload(x, rtol, atol)
    q = _q_of(mag, rtol, atol)
    h = _step(q, rtol, atol)
    return f"g|{q}|{math.floor(x / h)}" if _usable(h, x) else f"x|{float(x)!r}"


def _complex_candidates(s: complex, rtol: float, atol: float) -> list[str]:
    mag = abs(s)
    if not math.isfinite(mag) or _exact(rtol, atol) or (atol <= 0.0 and mag == 0.0):
        return [_complex_payload(s, rtol, atol)]
    t = 1.01 * (atol + rtol * (mag + atol) / (1.0 - min(rtol, 0.5))) + 1e-300
    q_lo = _q_of(max(mag - t, mag / 2.0 if atol <= 0.0 else 0.0), rtol, atol)
    q_hi = _q_of(mag + t, rtol, atol)
    out: list[str] = []
    if q_lo is None or q_hi is None:
        return [_complex_payload(s, rtol, atol)]
    for q in range(q_lo, min(q_hi, q_lo + 8) + 1):
        h = _step(q, rtol, atol)
        cells = []
        for part in (s.real, s.imag):
            if not _usable(h, part):
                cells.append([f"x|{float(part)!r}"])
                continue
            x = part / h
            ks = dict.fromkeys(
                (math.floor(x), math.floor(x - 0.5 - _EPS), math.floor(x + 0.5 + _EPS))
            )
            cells.append([f"g|{q}|{k}" for k in ks])
        out += [f"c|{a}|{b}" for a in cells[0] for b in cells[1]]
    return list(dict.fromkeys(out))


def _element_payload(kind: str, e, ctx: _Ctx) -> str:
    if kind == "b":
        return f"b|{int(bool(e))}"
    if kind == "i":
        return f"i|{int(e)}"
    if kind == "c":
        return _complex_payload(complex(e), ctx.rtol, ctx.atol)
    return _float_payload(float(e), ctx.rtol, ctx.atol)


def _seal_node(value, ctx: _Ctx, where: str) -> dict:
    if isinstance(value, Band):
        return _seal_band(value, ctx, where)
    if value is None:
        return {"none": True}
    if isinstance(value, str):
        return {"str": ctx.hash(where, f"s|{value}")}
    if isinstance(value, (tuple, list)):
        node: dict = {
            "seq": [_seal_node(v, ctx, f"{where}.{i}") for i, v in enumerate(value)],
            "type": type(value).__name__ if isinstance(value, list) else "tuple",
        }
        fields = getattr(type(value), "_fields", None)
        if isinstance(fields, tuple) and len(fields) == len(value):
            node["fields"] = list(fields)
        return node
    if isinstance(value, dict):
        return {"dict": {str(k): _seal_node(v, ctx, _key_path(where, k)) for k, v in value.items()}}
    arr = _numeric(value)
    if arr is None:
        raise TypeError(f"cannot seal a value of type {type(value).__name__}")
    kind = _kind_of(arr)
    return {
        "num": kind,
        "py": _py_type(value),
        "shape": list(arr.shape),
        "h": [
            ctx.hash(f"{where}#{i}", _element_payload(kind, e, ctx))
            for i, e in enumerate(arr.ravel().tolist())
        ],
    }


def _seal_band(band: Band, ctx: _Ctx, where: str) -> dict:
    lo, hi = np.asarray(band.lo, float), np.asarray(band.hi, float)
    steps, cells = [], []
    for i, (a, b) in enumerate(zip(lo.ravel().tolist(), hi.ravel().tolist())):
        h = max((b - a) / BAND_CELLS, abs(a) * 1e-12, abs(b) * 1e-12, 1e-300)
        steps.append(h)
        ks = range(math.floor(a / h), math.floor(b / h) + 1)
        cells.append(sorted(ctx.hash(f"{where}#{i}", f"k|{k}") for k in ks))
    return {"band": list(lo.shape), "step": steps, "cells": cells}


def seal(value: Any, rtol: float, atol: float, salt: str, iterations: int = ITERATIONS) -> dict:
    """``value`` sealed for ``checks.json`` (see the module docstring): plain JSON data.

    Examples
    --------
    >>> sealed = seal(0.5477225575, 1e-8, 1e-8, make_salt("demo", "q1"))
    >>> "0.547" in str(sealed)
    False
    >>> sealed_compare(sealed, 0.5477225575051661).ok, sealed_compare(sealed, 0.55).ok
    (True, False)
    """
    ctx = _Ctx(salt, iterations, rtol, atol)
    return {
        SEAL_TAG: {
            "salt": salt,
            "iterations": int(iterations),
            "rtol": float(rtol),
            "atol": float(atol),
            "value": _seal_node(value, ctx, ""),
        }
    }


def is_sealed(data: Any) -> bool:
    return isinstance(data, dict) and set(data) == {SEAL_TAG}


def _open(sealed: dict) -> tuple[dict, _Ctx]:
    if not is_sealed(sealed):
        raise ValueError("not a sealed value")
    body = sealed[SEAL_TAG]
    return body["value"], _Ctx(body["salt"], body["iterations"], body["rtol"], body["atol"])


# -- comparing -------------------------------------------------------------------------------
def _skeleton(node: dict):
    """A stand-in of the expected value's type and shape (zeros), for :func:`describe`."""
    if "none" in node:
        return None
    if "str" in node:
        return ""
    if "band" in node:
        return Band(np.zeros(node["band"]), np.zeros(node["band"]))
    if "seq" in node:
        items = [_skeleton(n) for n in node["seq"]]
        if node.get("fields"):
            return _named_type(tuple(node["fields"]))(*items)
        return items if node.get("type") == "list" else tuple(items)
    if "dict" in node:
        return {k: _skeleton(n) for k, n in node["dict"].items()}
    dtype = {"b": bool, "i": np.int64, "f": float, "c": complex}[node["num"]]
    if node["py"] == "array":
        return np.zeros(node["shape"], dtype=dtype)
    return {"bool": False, "int": 0, "float": 0.0, "complex": 0j}[node["py"]]


def _element_candidates(kind: str, s, ctx: _Ctx) -> list[str]:
    if kind == "b":
        return [f"b|{int(bool(s))}"] if s in (0, 1, True, False) else []
    if kind == "i":
        x = complex(s)
        if x.imag != 0 or not math.isfinite(x.real) or x.real != math.floor(x.real):
            return []
        return [f"i|{int(x.real)}"]
    if kind == "c":
        return _complex_candidates(complex(s), ctx.rtol, ctx.atol)
    if isinstance(s, complex):
        return []
    return _float_candidates(float(s), ctx.rtol, ctx.atol)


def _element_ok(node: dict, i: int, s, ctx: _Ctx, where: str) -> bool:
    target = node["h"][i]
    return any(
        ctx.hash(f"{where}#{i}", p) == target for p in _element_candidates(node["num"], s, ctx)
    )


def _all_match(node: dict, arr: np.ndarray, ctx: _Ctx, where: str) -> bool:
    """Every element of ``arr`` (same shape) matches; stops at the first that does not."""
    if tuple(arr.shape) != tuple(node["shape"]):
        return False
    flat = arr.ravel().tolist()
    return all(_element_ok(node, i, s, ctx, where) for i, s in enumerate(flat))


def _is_permuted(node: dict, g: np.ndarray, ctx: _Ctx, where: str) -> bool:
    flat = g.ravel().tolist()
    left = list(range(len(flat)))
    for i in range(len(flat)):
        j = next((j for j in left if _element_ok(node, i, flat[j], ctx, where)), None)
        if j is None:
            return False
        left.remove(j)
    return True


def _kind_of_wrong(node: dict, g: np.ndarray, ctx: _Ctx, where: str) -> Diagnosis:
    """What kind of wrong ``g`` is (same shape, not a match) and its words, as
    :func:`course.grading.compare._kind_of_wrong` says them; ``(None, "")`` when unknown.
    Tries transforms of ``g`` against the seal, never an expected value."""
    shape, kind = tuple(node["shape"]), node["num"]
    gf = g.astype(complex if kind == "c" or g.dtype.kind == "c" else float)
    integral = kind == "i"

    def same(x):
        if integral and not (np.all(np.isfinite(x)) and np.all(np.mod(x.real, 1) == 0)):
            return False
        # a transform that leaves g as it was (a symmetric matrix, a palindrome, zeros) tells
        # nothing: g would match after it only by the luck of its round-off
        if not integral and np.allclose(x, gf, rtol=1e-6, atol=ctx.atol):
            return False
        return _all_match(node, np.asarray(x), ctx, where)

    if len(shape) == 2 and shape[0] == shape[1] > 1 and same(gf.T):
        return MistakeKind.TRANSPOSED, "transposed: rows and columns are swapped"
    if same(-gf):
        return MistakeKind.SIGN, "the sign is flipped"
    if len(shape) == 1 and gf.size > 1 and kind != "c":
        if same(gf[::-1]):
            return MistakeKind.ORDER, "the right values in reverse order"
        if gf.size <= _MAX_PERMUTATION and _is_permuted(node, gf, ctx, where):
            return MistakeKind.ORDER, "the right values in another order (a permutation)"
    if integral:  # as in compare: a relation to an integer answer would name it
        return None, ""
    if kind == "c":
        return None, ""
    if bool(np.all(gf == 0)):
        return MistakeKind.ZEROS, "all zeros (a result never filled in?)"
    for f in FACTORS:
        for sign in (1, -1):
            if sign < 0 and f not in (2, Fraction(1, 2)):
                continue
            if same(gf / (sign * float(f))):
                text = _factor_text(float(f), f)
                return MistakeKind.FACTOR, ("the sign is flipped and " if sign < 0 else "") + text
    if bool(np.all(gf >= 0)):
        if same(np.sqrt(gf)):
            return MistakeKind.SQUARE, SQUARED_TEXT
        if same(gf**2):
            return MistakeKind.SQUARE, SQUARE_ROOT_TEXT
    return None, ""


def _diagnose(node, g, ctx, where) -> Diagnosis:
    try:
        with np.errstate(all="ignore"):
            return _kind_of_wrong(node, g, ctx, where)
    except Exception:  # a diagnosis must never break a verdict
        return None, ""


class _Sealed(StructuralWalk):
    """The structural walk against a sealed value; the leaves compare hashes.

    ``expected`` is a pair ``(node, where)``: a node of the sealed tree and its place, which
    the salt of its hashes names."""

    order_detail = False  # the self-check's record is its message: no expected value to show

    def __init__(self, ctx: _Ctx):
        self.ctx = ctx

    def stand_in(self, expected):
        return _skeleton(expected[0])

    def item(self, expected, k: int):
        node, where = expected
        return node["seq"][k], f"{where}.{k}"

    def value_at(self, expected, key):
        node, where = expected
        return node["dict"][key], _key_path(where, key)

    def band(self, expected, arr: np.ndarray, label: str) -> Verdict:
        node, where = expected
        shape = tuple(node["band"])
        wrong_shape = band_shape_wrong(label, shape, arr)
        if wrong_shape is not None:
            return wrong_shape
        for i, x in enumerate(arr.astype(float).ravel().tolist()):
            j = i if shape else 0
            at = _where(np.unravel_index(i, arr.shape) if arr.ndim else (), arr.shape)
            if math.isnan(x):
                text = f"{label}: got NaN{at}"
                return Verdict(False, text, text, MistakeKind.NOT_FINITE)
            h = node["step"][j]
            inside = math.isfinite(x) and abs(x / h) < 2.0**62
            if not inside or self.ctx.hash(f"{where}#{j}", f"k|{math.floor(x / h)}") not in set(
                node["cells"][j]
            ):
                text = outside_band(label, at)
                return Verdict(False, text, text, MistakeKind.OUTSIDE_BAND)
        return Verdict(True)

    def string(self, expected, got: str, label: str) -> Verdict:
        node, where = expected
        if self.ctx.hash(where, f"s|{got}") == node["str"]:
            return Verdict(True)
        if not self.ctx.explain:
            return Verdict(False)
        variants = dict.fromkeys(
            v(got.strip()) for v in (str, str.lower, str.upper, str.title, str.capitalize)
        )
        if any(self.ctx.hash(where, f"s|{v}") == node["str"] for v in variants if v != got):
            text = f"{label}: differs only in upper/lower case or spaces"
            return Verdict(False, text, text, MistakeKind.STRING_CASE)
        text = f"{label}: not the right string"
        return Verdict(False, text, text, MistakeKind.WRONG_VALUE)

    def transposed(self, expected, arr: np.ndarray) -> bool:
        node, where = expected
        return arr.dtype.kind != "c" and _all_match(node, arr.T.astype(float), self.ctx, where)

    def in_another_order(self, expected, items) -> bool:
        node, where = expected
        return (
            self.ctx.explain
            and 1 < len(node["seq"]) <= 4
            and _is_item_permutation(node["seq"], items, self.ctx, where)
        )

    def numbers(self, expected, exp: np.ndarray, arr: np.ndarray, label: str) -> Verdict:
        node, where = expected
        ctx = self.ctx
        if not ctx.explain:
            return Verdict(_all_match(node, arr, ctx, where))
        shape, kind = tuple(node["shape"]), node["num"]
        flat = arr.ravel().tolist()
        if kind == "b":
            flat = [bool(x) for x in flat]
        bad = [i for i, x in enumerate(flat) if not _element_ok(node, i, x, ctx, where)]
        if not bad:
            return Verdict(True)
        first = np.unravel_index(bad[0], shape) if shape else ()
        if kind == "b":
            message = decisions_wrong(label, len(bad), len(flat), first, shape)
            return Verdict(False, message, message, decisions_kind(len(bad), len(flat), shape))
        if kind == "i":
            found, text = _diagnose(node, arr, ctx, where)
            message = integers_wrong(label, len(bad), len(flat), first, shape, text)
            return Verdict(False, message, message, found)
        g = arr.astype(complex if kind == "c" else float)
        wrong = np.zeros(g.size, dtype=bool)
        wrong[bad] = True
        message = not_finite(label, g, wrong.reshape(g.shape))
        if message:
            return Verdict(False, message, message, MistakeKind.NOT_FINITE)
        if single_precision(arr):
            found, text = MistakeKind.SINGLE_PRECISION, SINGLE_PRECISION
        else:
            found, text = _diagnose(node, g, ctx, where)
        message = numbers_wrong(
            label,
            len(bad),
            len(flat),
            "worst" if len(bad) == 1 else "first",  # the seal cannot tell the worst
            first,
            shape,
            text,
            ctx.rtol,
            ctx.atol,
        )
        return Verdict(False, message, message, found)


def _is_item_permutation(items, got, ctx, where) -> bool:
    for order in itertools.permutations(range(len(items))):
        if list(order) == sorted(order):
            continue
        try:
            if all(
                _quiet(items[k], got[j], ctx, f"{where}.{k}")
                for k, j in zip(range(len(items)), order)
            ):
                return True
        except TypeError:
            return False
    return False


def _quiet(node, got, ctx, where) -> bool:
    try:
        return _Sealed(ctx.quiet()).walk((node, where), got).ok
    except Exception:
        return False


def matches(sealed: dict, got: Any) -> bool:
    """Whether ``got`` passes the sealed check (no message)."""
    node, ctx = _open(sealed)
    return _quiet(node, got, ctx, "")


def sealed_compare(sealed: dict, got: Any, path: str = "", mistakes=()) -> Verdict:
    """:func:`course.grading.compare.compare` against a sealed expected value.

    Same messages (what is wrong in kind, with the tolerance); the "worst" element becomes the
    first wrong one. ``mistakes``: ``(message, sealed wrong value)`` pairs. ``detail`` carries
    no expected value: the self-check has none.
    """
    node, ctx = _open(sealed)
    verdict = _Sealed(ctx).walk((node, ""), got, path)
    if verdict.ok:
        return verdict
    named = next((m for m, wrong in mistakes if matches(wrong, got)), None)
    if named is None:
        named = next((m for m, wrong in mistakes if _fieldwise(sealed, wrong, got)), None)
    if named is not None:
        text = f"{_label(path)}: {named}"
        return Verdict(False, text, text, MistakeKind.NAMED, named)
    return verdict


def _fieldwise(sealed: dict, wrong: dict, got: Any) -> bool:
    """:func:`~course.grading.compare.fieldwise_mistake` against sealed values: each item is
    compared with its own seal (the answer's or the mistake's)."""
    node, ctx = _open(sealed)
    wrong_node, wrong_ctx = _open(wrong)
    if "seq" not in node or "seq" not in wrong_node:
        return False
    right = [(n, ctx, f".{k}") for k, n in enumerate(node["seq"])]
    mistaken = [(n, wrong_ctx, f".{k}") for k, n in enumerate(wrong_node["seq"])]

    def same(want, item) -> bool:
        item_node, item_ctx, where = want
        return _quiet(item_node, item, item_ctx, where)

    return fieldwise_mistake(_skeleton(node), right, mistaken, got, same)
