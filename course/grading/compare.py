"""Compare a student's value with an expected value and explain the difference compactly.

Used by both the self-check (in the student's kernel, against public expected values) and the
grader (in the trusted parent). Never compares printed text.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from course.grading.codec import Band

__all__ = ["Verdict", "binomial_band", "compare", "describe"]


@dataclass(frozen=True)
class Verdict:
    """The outcome of one comparison: ``ok`` and a one-line explanation when not ok."""

    ok: bool
    message: str = ""


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


def compare(
    expected: Any,
    got: Any,
    rtol: float = 1e-7,
    atol: float = 1e-9,
    reveal: bool = True,
    path: str = "",
) -> Verdict:
    """Compare ``got`` with ``expected``.

    Floats and float arrays: equal shapes and ``|got - expected| <= atol + rtol*|expected|``
    element-wise (NaN only matches NaN). Bools and ints: exact. Strings and None: exact.
    Tuples/lists: same length (either container type), element by element. Dicts: same keys.
    :class:`Band`: every element of ``got`` inside ``[lo, hi]``.

    ``reveal=False`` (hidden cases) omits expected numbers from the message.
    """
    label = path or "value"
    if isinstance(expected, Band):
        arr = _numeric(got)
        if arr is None or arr.dtype.kind == "c":
            return Verdict(False, f"{label}: expected a real number, got {describe(got)}")
        lo, hi = np.asarray(expected.lo, float), np.asarray(expected.hi, float)
        try:
            arr_b, lo_b, hi_b = np.broadcast_arrays(arr.astype(float), lo, hi)
        except ValueError:
            return Verdict(False, f"{label}: expected shape {lo.shape}, got {arr.shape}")
        if arr.shape != np.broadcast_shapes(arr.shape, lo.shape):
            return Verdict(False, f"{label}: expected shape {lo.shape}, got {arr.shape}")
        inside = (arr_b >= lo_b) & (arr_b <= hi_b)
        if bool(np.all(inside)):
            return Verdict(True)
        bad = np.argwhere(~inside)[0] if arr_b.ndim else ()
        at = tuple(bad)
        g = arr_b[at] if arr_b.ndim else arr_b[()]
        low = float(lo_b[at] if lo_b.ndim else lo_b[()])
        high = float(hi_b[at] if hi_b.ndim else hi_b[()])
        band = f" [{_fmt(low)}, {_fmt(high)}]" if reveal else " band"
        return Verdict(
            False,
            f"{label}: got {_fmt(float(g))}{_where(at, arr_b.shape)}, outside the accepted{band}",
        )
    if expected is None:
        return Verdict(
            got is None, "" if got is None else f"{label}: expected None, got {describe(got)}"
        )
    if isinstance(expected, str):
        if got == expected:
            return Verdict(True)
        shown = f"{expected!r}" if reveal else "another string"
        return Verdict(
            False,
            f"{label}: expected {shown}, got {describe(got) if not isinstance(got, str) else repr(got[:60])}",
        )
    if isinstance(expected, (tuple, list)):
        if not isinstance(got, (tuple, list)):
            return Verdict(
                False,
                f"{label}: expected a {type(expected).__name__} of length {len(expected)}, got {describe(got)}",
            )
        if len(got) != len(expected):
            return Verdict(
                False, f"{label}: expected length {len(expected)}, got length {len(got)}"
            )
        for k, (e, g) in enumerate(zip(expected, got)):
            v = compare(e, g, rtol, atol, reveal, f"{path}[{k}]" if path else f"item [{k}]")
            if not v.ok:
                return v
        return Verdict(True)
    if isinstance(expected, dict):
        if not isinstance(got, dict):
            return Verdict(
                False, f"{label}: expected a dict with keys {sorted(expected)}, got {describe(got)}"
            )
        if set(got) != set(expected):
            return Verdict(
                False,
                f"{label}: expected keys {sorted(expected)}, got {sorted(map(str, got))[:10]}",
            )
        for k in sorted(expected):
            v = compare(
                expected[k], got[k], rtol, atol, reveal, f"{path}[{k!r}]" if path else f"[{k!r}]"
            )
            if not v.ok:
                return v
        return Verdict(True)

    exp = _numeric(expected)
    if exp is None:
        raise TypeError(f"cannot compare against expected value of type {type(expected).__name__}")
    arr = _numeric(got)
    if arr is None:
        return Verdict(False, f"{label}: expected {describe(expected)}, got {describe(got)}")
    if arr.shape != exp.shape:
        return Verdict(
            False, f"{label}: expected shape {tuple(exp.shape)}, got shape {tuple(arr.shape)}"
        )

    if _is_boolish(expected):
        if arr.dtype.kind not in "biu":
            return Verdict(
                False, f"{label}: expected bool{'s' if exp.ndim else ''}, got {describe(got)}"
            )
        diff = arr.astype(bool) != exp
        if arr.dtype.kind in "iu" and np.any((arr != 0) & (arr != 1)):
            return Verdict(
                False, f"{label}: expected bool{'s' if exp.ndim else ''}, got {describe(got)}"
            )
        if not np.any(diff):
            return Verdict(True)
        i = tuple(np.argwhere(diff)[0]) if diff.ndim else ()
        g = bool(arr[i]) if arr.ndim else bool(arr[()])
        extra = f": expected {not g}, got {g}" if reveal else f": got {g}"
        return Verdict(
            False,
            f"{label}: {int(np.sum(diff))} of {diff.size} wrong, first{_where(i, diff.shape)}{extra}",
        )

    if _is_intish(expected):
        if arr.dtype.kind == "c" or (arr.dtype.kind == "f" and not np.all(np.isfinite(arr))):
            return Verdict(
                False, f"{label}: expected integer{'s' if exp.ndim else ''}, got {describe(got)}"
            )
        diff = arr != exp
        if not np.any(diff):
            return Verdict(True)
        i = tuple(np.argwhere(diff)[0]) if diff.ndim else ()
        g = arr[i] if arr.ndim else arr[()]
        e = exp[i] if exp.ndim else exp[()]
        extra = f": expected {_fmt(e)}, got {_fmt(g)}" if reveal else f": got {_fmt(g)}"
        return Verdict(
            False,
            f"{label}: {int(np.sum(diff))} of {diff.size} wrong, first{_where(i, diff.shape)}{extra}",
        )

    # floats / complex
    if arr.dtype.kind == "c" and exp.dtype.kind != "c":
        return Verdict(False, f"{label}: expected real numbers, got complex")
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
    if np.any(np.isnan(g) & bad):
        i = tuple(np.argwhere(np.isnan(g) & bad)[0]) if g.ndim else ()
        return Verdict(False, f"{label}: got NaN{_where(i, g.shape)}")
    score = np.where(bad, np.nan_to_num(err - tol, nan=np.inf, posinf=np.inf), -np.inf)
    i = np.unravel_index(int(np.argmax(score)), score.shape) if score.ndim else ()
    ei = e[i] if e.ndim else e[()]
    gi = g[i] if g.ndim else g[()]
    erri = err[i] if err.ndim else err[()]
    toli = tol[i] if tol.ndim else tol[()]
    count = f"{int(np.sum(bad))} of {bad.size} elements wrong; " if bad.size > 1 else ""
    if reveal:
        what = f"expected {_fmt(ei.real) if e.dtype.kind != 'c' else ei}, got {_fmt(gi.real) if g.dtype.kind != 'c' else gi}; "
    else:
        what = f"got {_fmt(gi.real) if g.dtype.kind != 'c' else gi}; "
    tolerance = f"tolerance {_fmt(toli)} = " if reveal else "tolerance "
    return Verdict(
        False,
        f"{label}: {count}largest error {_fmt(erri)}{_where(i, e.shape)} ({what}"
        f"{tolerance}atol {_fmt(atol)} + rtol {_fmt(rtol)}·|expected|)",
    )


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
        return {"sequence": [signature(v) for v in value]}
    if isinstance(value, dict):
        return {"dict": {str(k): signature(v) for k, v in value.items()}}
    arr = _numeric(value)
    if arr is None:
        raise TypeError(f"no signature for {type(value).__name__}")
    kind = {"b": "bool", "i": "int", "u": "int", "f": "float", "c": "complex"}[arr.dtype.kind]
    return {"kind": kind, "shape": list(arr.shape)}


def check_signature(sig: Any, got: Any, path: str = "") -> Verdict:
    """Whether ``got`` has the type and shape of ``sig`` (and is finite where numeric)."""
    label = path or "value"
    if "band" in sig:
        sig = {"kind": "float", "shape": sig["band"]}
    if "none" in sig:
        return Verdict(
            got is None, "" if got is None else f"{label}: expected None, got {describe(got)}"
        )
    if "str" in sig:
        return Verdict(
            isinstance(got, str),
            "" if isinstance(got, str) else f"{label}: expected a string, got {describe(got)}",
        )
    if "names" in sig:
        ok = isinstance(got, (tuple, list)) and all(isinstance(v, str) for v in got)
        return Verdict(
            ok, "" if ok else f"{label}: expected a list of strings, got {describe(got)}"
        )
    if "sequence" in sig:
        items = sig["sequence"]
        if not isinstance(got, (tuple, list)) or len(got) != len(items):
            return Verdict(
                False, f"{label}: expected a sequence of length {len(items)}, got {describe(got)}"
            )
        for i, (s, g) in enumerate(zip(items, got)):
            v = check_signature(s, g, f"{path}[{i}]" if path else f"item [{i}]")
            if not v.ok:
                return v
        return Verdict(True)
    if "dict" in sig:
        keys = sig["dict"]
        if not isinstance(got, dict) or set(got) != set(keys):
            return Verdict(
                False, f"{label}: expected a dict with keys {sorted(keys)}, got {describe(got)}"
            )
        for k in sorted(keys):
            v = check_signature(keys[k], got[k], f"{path}[{k!r}]" if path else f"[{k!r}]")
            if not v.ok:
                return v
        return Verdict(True)
    arr = _numeric(got)
    shape = tuple(sig["shape"])
    kind = sig["kind"]
    noun = "a number" if not shape else f"an array of shape {shape}"
    if arr is None:
        return Verdict(False, f"{label}: expected {noun}, got {describe(got)}")
    if arr.shape != shape:
        return Verdict(False, f"{label}: expected shape {shape}, got shape {tuple(arr.shape)}")
    if kind == "bool" and arr.dtype.kind != "b":
        return Verdict(False, f"{label}: expected bool{'s' if shape else ''}, got {describe(got)}")
    if kind in ("float", "int") and arr.dtype.kind == "c":
        return Verdict(False, f"{label}: expected real numbers, got complex")
    if kind == "int" and arr.dtype.kind == "f" and not np.all(np.mod(arr, 1) == 0):
        return Verdict(
            False, f"{label}: expected integer{'s' if shape else ''}, got {describe(got)}"
        )
    if arr.dtype.kind in "fc" and not np.all(np.isfinite(arr)):
        return Verdict(False, f"{label}: contains NaN or inf")
    return Verdict(True)
