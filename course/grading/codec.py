"""Plain-data encoding used between the grader, its sandboxed children and ``checks.json``.

Everything that crosses a process boundary or ships to students is JSON: numbers, strings,
booleans, ``None``, lists, dicts with string keys, and three tagged forms:

``{"__ndarray__": {"dtype": "<f8", "shape": [2, 3], "data": "<base64>"}}``
    a numpy array of a numeric or boolean dtype (raw little-endian bytes, never pickle),
``{"__tuple__": [...]}``
    a tuple (so that a reference returning a tuple round-trips),
``{"__namedtuple__": {"fields": [...], "values": [...]}}``
    a named tuple (decoded as a named tuple with the same field names, so feedback can name
    ``critical_value`` instead of ``item [1]``),
``{"__float__": "nan" | "inf" | "-inf"}`` and ``{"__complex__": [re, im]}``
    the floats JSON cannot spell, and complex scalars,
``{"__band__": [lo, hi]}``
    a :class:`Band` (an accepted interval), only in expected values written by the grader;
    decoding a student's value uses ``allow_band=False``.

Decoding never executes anything: an unknown tag or an object dtype is an error.
"""

from __future__ import annotations

import base64
import collections
import functools
import json
import keyword
import math
from typing import Any

import numpy as np

__all__ = ["MAX_ELEMENTS", "Band", "EncodingError", "decode", "dumps", "encode", "loads"]

#: Largest array (in elements) accepted on either side: a runaway answer cannot flood the pipe.
MAX_ELEMENTS = 5_000_000

_ALLOWED_KINDS = "biufc"


class EncodingError(TypeError):
    """A value cannot be represented as plain data."""


class Band:
    """An accepted interval ``[lo, hi]`` for an expected value (e.g. a Monte Carlo rate).

    A reference returns ``Band(lo, hi)`` where any answer inside the interval is right; ``lo``
    and ``hi`` may be arrays (element-wise bands).
    """

    __slots__ = ("hi", "lo")

    def __init__(self, lo, hi):
        lo_arr, hi_arr = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        if lo_arr.shape != hi_arr.shape:
            raise ValueError(
                f"Band: lo and hi must have the same shape, got {lo_arr.shape} and {hi_arr.shape}"
            )
        if np.any(np.isnan(lo_arr)) or np.any(np.isnan(hi_arr)) or np.any(lo_arr > hi_arr):
            raise ValueError("Band: need lo <= hi (no NaN)")
        self.lo = float(lo_arr) if lo_arr.ndim == 0 else lo_arr
        self.hi = float(hi_arr) if hi_arr.ndim == 0 else hi_arr

    def __repr__(self):
        return f"Band({self.lo!r}, {self.hi!r})"

    def __eq__(self, other):
        return (
            isinstance(other, Band)
            and np.array_equal(self.lo, other.lo)
            and np.array_equal(self.hi, other.hi)
        )

    __hash__ = None  # type: ignore[assignment]  # bands compare by value, unhashable


def _encode_float(value: float):
    if math.isfinite(value):
        return value
    return {"__float__": "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")}


def encode(value: Any, _depth: int = 0) -> Any:
    """Turn ``value`` into JSON-compatible plain data (see the module docstring)."""
    if _depth > 50:
        raise EncodingError("value is nested too deeply")
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        return _encode_float(value)
    if isinstance(value, complex):
        return {"__complex__": [_encode_float(value.real), _encode_float(value.imag)]}
    if isinstance(value, np.generic):
        if isinstance(value, np.bool_):
            return bool(value)
        if isinstance(value, np.integer):
            return int(value)
        if isinstance(value, np.floating):
            return _encode_float(float(value))
        if isinstance(value, np.complexfloating):
            return encode(complex(value), _depth + 1)
        raise EncodingError(f"unsupported numpy scalar type {type(value).__name__}")
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "US":
            raise EncodingError(
                "a numpy array of strings: return a plain list of strings (arr.tolist())"
            )
        if value.dtype.kind not in _ALLOWED_KINDS:
            raise EncodingError(f"unsupported array dtype {value.dtype} (use numbers or booleans)")
        if value.size > MAX_ELEMENTS:
            raise EncodingError(f"array too large ({value.size} elements)")
        arr = np.ascontiguousarray(value, dtype=value.dtype.newbyteorder("<"))
        return {
            "__ndarray__": {
                "dtype": arr.dtype.str,
                "shape": list(arr.shape),
                "data": base64.b64encode(arr.tobytes()).decode("ascii"),
            }
        }
    if isinstance(value, Band):
        return {"__band__": [encode(value.lo, _depth + 1), encode(value.hi, _depth + 1)]}
    if isinstance(value, tuple):
        fields = getattr(type(value), "_fields", None)
        if isinstance(fields, tuple) and _valid_fields(fields) and len(fields) == len(value):
            return {
                "__namedtuple__": {
                    "fields": list(fields),
                    "values": [encode(v, _depth + 1) for v in value],
                }
            }
        return {"__tuple__": [encode(v, _depth + 1) for v in value]}
    if isinstance(value, list):
        return [encode(v, _depth + 1) for v in value]
    if isinstance(value, dict):
        out = {}
        for key, item in value.items():
            if not isinstance(key, str) or key.startswith("__"):
                raise EncodingError(f"dict keys must be plain strings, got {key!r}"[:200])
            out[key] = encode(item, _depth + 1)
        return out
    raise EncodingError(f"unsupported type {type(value).__name__}")


def _valid_fields(fields) -> bool:
    return (
        isinstance(fields, tuple)
        and 0 < len(fields) <= 64
        and len(set(fields)) == len(fields)
        and all(
            isinstance(f, str)
            and f.isidentifier()
            and not f.startswith("_")
            and not keyword.iskeyword(f)
            for f in fields
        )
    )


@functools.lru_cache(maxsize=256)
def _named_type(fields: tuple) -> type:
    """The named-tuple type of a decoded value (built from field names, nothing executed)."""
    return collections.namedtuple("Result", fields)


def _decode_float(value):
    if isinstance(value, dict) and "__float__" in value:
        return float(value["__float__"])
    return float(value)


def decode(data: Any, allow_band: bool = True, _depth: int = 0) -> Any:
    """Inverse of :func:`encode`; returns fresh objects (arrays are writable copies).

    Nesting deeper than :func:`encode` writes is refused (:class:`EncodingError`), so a
    hostile reply cannot exhaust the parent's stack here or in the comparison."""
    if data is None or isinstance(data, (bool, int, float, str)):
        return data
    if _depth > 60:
        raise EncodingError("the value is nested too deeply")
    _depth += 1
    if isinstance(data, list):
        return [decode(v, allow_band, _depth) for v in data]
    if isinstance(data, dict):
        if len(data) == 1:
            ((tag, body),) = data.items()
            if tag == "__ndarray__":
                dtype = np.dtype(body["dtype"])
                if dtype.kind not in _ALLOWED_KINDS:
                    raise EncodingError(f"refusing array dtype {dtype}")
                shape = tuple(int(n) for n in body["shape"])
                if math.prod(shape) > MAX_ELEMENTS:
                    raise EncodingError("array too large")
                raw = base64.b64decode(body["data"].encode("ascii"), validate=True)
                return np.frombuffer(raw, dtype=dtype).reshape(shape).copy()
            if tag == "__tuple__":
                return tuple(decode(v, allow_band, _depth) for v in body)
            if tag == "__namedtuple__":
                fields = tuple(body["fields"])
                if not _valid_fields(fields) or len(fields) != len(body["values"]):
                    raise EncodingError("malformed named tuple")
                return _named_type(fields)(*(decode(v, allow_band, _depth) for v in body["values"]))
            if tag == "__band__" and allow_band:
                return Band(decode(body[0], False, _depth), decode(body[1], False, _depth))
            if tag == "__float__":
                return _decode_float(data)
            if tag == "__complex__":
                return complex(_decode_float(body[0]), _decode_float(body[1]))
        if any(k.startswith("__") for k in data):
            raise EncodingError(f"unknown tagged value {sorted(data)[:3]}")
        return {k: decode(v, allow_band, _depth) for k, v in data.items()}
    raise EncodingError(f"cannot decode {type(data).__name__}")


def dumps(value: Any, **kwargs) -> str:
    """``json.dumps(encode(value))`` with NaN refused (it is encoded as a tag instead)."""
    return json.dumps(encode(value), allow_nan=False, **kwargs)


def loads(text: str | bytes, allow_band: bool = True) -> Any:
    """``decode(json.loads(text))``."""
    return decode(json.loads(text), allow_band)
