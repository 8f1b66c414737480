"""Bad input, one argument at a time, for every public function of a module.

The course promises (package docstring, "Input checks") that bad input gets a
``ValueError`` or ``numpy.linalg.LinAlgError`` that *names the argument* and
says what to do, and that a valid input never gives NaN.  The test modules
``test_bad_input_<module>.py`` keep that promise checkable:

1. a table maps every public callable of the module (functions, classes and
   their public methods, discovered from ``__all__`` by
   :func:`public_callables`, so a new one cannot be missed) to a *valid* call,
   written as keyword arguments;
2. each argument is described by its kind (:func:`array`, :func:`covariance`,
   :func:`count`, :func:`scale`, ...), and the kind knows the bad values of
   its class: NaN, inf, empty, ``None``, wrong ndim or shape, a scalar where a
   sequence is expected, non-integer and negative counts, singular and
   indefinite covariances;
3. :func:`params` turns the table into one pytest case per (function,
   argument, bad value): the valid call with that one argument replaced,
   which must raise a refusal naming the argument (:func:`check_refused`);
   *extreme* values (a standard deviation of ``1e300`` or ``1e-300``) are
   valid, so they must give a finite answer or a clear refusal, never NaN, an
   ``OverflowError``, a ``ZeroDivisionError`` or a RuntimeWarning
   (:func:`check_extreme`).  The valid call itself must run without warnings
   and without NaN (:func:`check_valid`).
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import math
import re
import warnings
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import pytest
from numpy.linalg import LinAlgError

#: What a refusal may be.
REFUSALS = (ValueError, LinAlgError)

NAN, INF = float("nan"), float("inf")


@dataclasses.dataclass(frozen=True)
class Arg:
    """One argument of a valid call: its value and the bad values of its kind."""

    value: Any
    bad: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    extreme: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    names: tuple[str, ...] = ()  # what an error message may call it (default: its name)

    def but(self, *, drop: tuple[str, ...] = (), **more: Any) -> Arg:
        """The same argument without the bad values ``drop`` and with ``more``."""
        bad = {k: v for k, v in self.bad.items() if k not in drop}
        bad.update(more)
        return dataclasses.replace(self, bad=bad)


def fixed(value: Any) -> Arg:
    """An argument that is not mutated (a name, a label)."""
    return Arg(value)


# ---------------------------------------------------------------------------
# kinds of argument
# ---------------------------------------------------------------------------
def _with_first(a: np.ndarray, x: float) -> np.ndarray:
    b = np.array(a, dtype=float)
    b.flat[0] = x
    return b


def array(
    value: Any,
    *,
    ndims: tuple[int, ...] | str | None = None,
    min_ndim: int | None = None,
    shaped: bool = True,
    empty_ok: bool = False,
    none_ok: bool = False,
    names: tuple[str, ...] = (),
) -> Arg:
    """An array of real numbers.

    ``ndims``: the numbers of dimensions the function accepts (default: that of
    ``value``; ``"any"``: every ndim); ``min_ndim``: any ndim from this one up
    (leading batch axes); ``shaped``: its shape is tied to other arguments, so one more
    entry along the last axis is wrong; ``empty_ok``/``none_ok``: an empty
    array or ``None`` is valid.
    """
    a = np.asarray(value, dtype=float)
    bad: dict[str, Any] = {"text": "1 2 3", "complex": a + 1j}
    if not none_ok:
        bad["None"] = None
    if a.size:
        bad["NaN"] = _with_first(a, NAN)
        bad["inf"] = _with_first(a, -INF)
    if not empty_ok and a.ndim:
        bad["empty"] = np.zeros((0,) + a.shape[1:])
    if min_ndim is not None:
        if a.ndim >= 1:
            bad[f"{min_ndim - 1}-D"] = a[(0,) * (a.ndim - min_ndim + 1)]
    elif ndims != "any":
        ndims = (a.ndim,) if ndims is None else tuple(ndims)
        top = max(ndims) + 1
        bad[f"{top}-D"] = np.broadcast_to(a, (2,) * (top - a.ndim) + a.shape).copy()
        if 0 not in ndims and a.ndim >= 1:
            bad["scalar"] = float(a.flat[0]) if a.size else 1.0
        if min(ndims) >= 2 and a.ndim >= 2:
            bad["1-D"] = a.reshape(-1)
    if shaped and a.ndim >= 1:
        bad["longer"] = np.concatenate([a, a[..., -1:] if a.shape[-1] else a[..., :0]], axis=-1)
        if not a.shape[-1]:
            del bad["longer"]
    return Arg(value, bad, names=names)


def vector(value: Any, **kw: Any) -> Arg:
    """A 1-D array."""
    return array(value, ndims=(1,), **kw)


def matrix(value: Any, **kw: Any) -> Arg:
    """A 2-D array."""
    return array(value, ndims=(2,), **kw)


def _modify_first(a: np.ndarray, change: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """``a`` with the first matrix of its stack (or itself) changed."""
    b = np.array(a, dtype=float)
    lead = (0,) * (b.ndim - 2)
    b[lead] = change(b[lead].copy())
    return b


def _singular(c: np.ndarray) -> np.ndarray:
    if c.shape[0] == 1:
        return np.zeros_like(c)
    v = np.sqrt(np.diag(c))
    return np.outer(v, v)  # correlation 1 between every pair: rank 1


def _numerically_singular(c: np.ndarray) -> np.ndarray:
    values, vectors = np.linalg.eigh(c)
    values[0] = 1e-17 * values[-1]  # condition number 1e17 > 1/eps: singular in float64
    return (vectors * values) @ vectors.T


def _indefinite(c: np.ndarray) -> np.ndarray:
    if c.shape[0] == 1:
        return -c
    c[0, 1] = c[1, 0] = 2 * math.sqrt(c[0, 0] * c[1, 1])  # correlation 2
    return c


def _asymmetric(c: np.ndarray) -> np.ndarray:
    c[0, 1] += 0.5 * math.sqrt(c[0, 0] * c[1, 1])
    return c


def covariance(
    value: Any,
    *,
    psd: bool = False,
    ndims: tuple[int, ...] | None = None,
    extreme: bool = False,
    **kw: Any,
) -> Arg:
    """A covariance matrix (or a stack ``(..., m, m)``).

    Bad as arrays are, and also singular (exactly, and numerically: condition
    number 1e17) unless ``psd`` (semi-definite is valid), indefinite and
    asymmetric.  With ``extreme``, the covariance scaled by ``1e±300`` must
    give a finite answer or a clear refusal.
    """
    a = np.asarray(value, dtype=float)
    base = array(value, ndims=ndims or (a.ndim,), **kw)
    bad = dict(base.bad)
    if not psd:
        bad["singular"] = _modify_first(a, _singular)
        if a.shape[-1] > 1:
            bad["numerically singular"] = _modify_first(a, _numerically_singular)
    bad["indefinite"] = _modify_first(a, _indefinite)
    if a.shape[-1] > 1:
        bad["asymmetric"] = _modify_first(a, _asymmetric)
    extremes = {"tiny": a * 1e-300, "huge": a * 1e300} if extreme else {}
    return dataclasses.replace(base, bad=bad, extreme=extremes)


def count(value: Any, *, minimum: int = 1, none_ok: bool = False) -> Arg:
    """A count: the course's one integer rule (whole floats are counts, fractions are not)."""
    bad: dict[str, Any] = {
        "fraction": value + 0.5,
        "below minimum": minimum - 1,
        "negative": -1,
        "NaN": NAN,
        "inf": INF,
        "bool": True,
        "text": "3",
        "sequence": [value, value],
    }
    if minimum <= 0:
        del bad["below minimum"]
    if not none_ok:
        bad["None"] = None
    return Arg(value, bad)


def index(value: Any, size: int, *, negative: bool = False, none_ok: bool = False) -> Arg:
    """An index into a sequence of length ``size``."""
    bad: dict[str, Any] = {
        "fraction": value + 0.5,
        "out of range": size,
        "negative": -size - 1 if negative else -1,
        "NaN": NAN,
        "text": "0",
    }
    if not none_ok:
        bad["None"] = None
    return Arg(value, bad)


def indices(value: Any, size: int, *, none_ok: bool = True) -> Arg:
    """A sequence of distinct indices into a sequence of length ``size``."""
    bad: dict[str, Any] = {
        "out of range": [size],
        "repeated": [0, 0],
        "fraction": [0.5],
        "text": "0",
        "nested": [[0]],
    }
    if not none_ok:
        bad["None"] = None
    return Arg(value, bad)


def real(value: Any, *, none_ok: bool = False, names: tuple[str, ...] = ()) -> Arg:
    """A real, finite scalar."""
    bad: dict[str, Any] = {
        "NaN": NAN,
        "inf": INF,
        "text": "1",
        "sequence": [value, value],
        "complex": complex(value, 1),
    }
    if not none_ok:
        bad["None"] = None
    return Arg(value, bad, names=names)


def positive(value: Any, **kw: Any) -> Arg:
    """A positive, finite scalar."""
    base = real(value, **kw)
    return base.but(zero=0.0, negative=-abs(value))


def scale(value: Any, *, zero_ok: bool = False, **kw: Any) -> Arg:
    """A standard deviation or variance: positive, and valid at the limits of floating point."""
    base = positive(value, **kw)
    if zero_ok:
        base = base.but(drop=("zero",))
    return dataclasses.replace(base, extreme={"1e300": 1e300, "1e-300": 1e-300})


def probability(value: Any, *, none_ok: bool = False) -> Arg:
    """A probability in (0, 1): a level of significance, a power."""
    bad: dict[str, Any] = {
        "zero": 0.0,
        "one": 1.0,
        "above one": 1.5,
        "NaN": NAN,
        "text": "0.05",
        "sequence": [value, value],
    }
    if not none_ok:
        bad["None"] = None
    return Arg(value, bad)


def function(value: Any, *, none_ok: bool = False) -> Arg:
    """A callable."""
    bad: dict[str, Any] = {"not callable": 3.0}
    if not none_ok:
        bad["None"] = None
    return Arg(value, bad)


def choice(value: Any, *, none_ok: bool = False) -> Arg:
    """One of a fixed set of strings."""
    bad: dict[str, Any] = {"unknown": "nonsense", "number": 3}
    if not none_ok:
        bad["None"] = None
    return Arg(value, bad)


def flag(value: Any) -> Arg:
    """A bool: ``"no"`` must not be read as True."""
    return Arg(value, {"text": "no", "number": 2})


def obj(value: Any, *, none_ok: bool = False, names: tuple[str, ...] = ()) -> Arg:
    """An object of a course type (a model, a structure, a result)."""
    bad: dict[str, Any] = {"number": 3.0, "text": "model"}
    if not none_ok:
        bad["None"] = None
    return Arg(value, bad, names=names)


def mapping(value: Any) -> Arg:
    """A dict."""
    return Arg(value, {"None": None, "list": [1.0], "text": "a"})


def generator(value: Any = 0) -> Arg:
    """A numpy Generator or a seed."""
    return Arg(value, {"text": "seed", "fraction": 2.5, "legacy": np.random.RandomState(0)})


# ---------------------------------------------------------------------------
# a table of valid calls
# ---------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class Case:
    """A valid call of a public callable, described argument by argument."""

    call: Callable[..., Any]
    args: Mapping[str, Arg]
    nan_ok: bool = False  # the answer legitimately holds NaN (e.g. windows not yet filled)

    def kwargs(self, **replace: Any) -> dict[str, Any]:
        out = {name: arg.value for name, arg in self.args.items()}
        out.update(replace)
        return out


def case(call: Callable[..., Any], *, nan_ok: bool = False, **args: Any) -> Case:
    """``case(f, x=vector([1.0]), name="t")``: plain values are :func:`fixed`."""
    args = {k: v if isinstance(v, Arg) else fixed(v) for k, v in args.items()}
    return Case(call, args, nan_ok)


def params(table: Mapping[str, Case], xfail: Mapping[str, str] | None = None) -> dict:
    """pytest parameters: ``valid``, ``refused`` and ``extreme`` cases of a table.

    ``xfail`` maps a test id (``function:argument=label``) or a function name to
    the reason it is still expected to fail (a function name marks its bad and
    extreme values, not its valid call, which must always pass).
    """
    xfail = dict(xfail or {})
    out: dict[str, list] = {"valid": [], "refused": [], "extreme": []}

    def mark(test_id: str, name: str) -> list:
        reason = xfail.get(test_id) or (None if test_id.endswith(":valid") else xfail.get(name))
        return [pytest.mark.xfail(reason=reason, strict=False)] if reason else []

    for name, entry in table.items():
        out["valid"].append(pytest.param(entry, id=name, marks=mark(f"{name}:valid", name)))
        for arg_name, arg in entry.args.items():
            for kind, store in (("bad", "refused"), ("extreme", "extreme")):
                for label, value in getattr(arg, kind).items():
                    test_id = f"{name}:{arg_name}={label}"
                    out[store].append(
                        pytest.param(entry, arg_name, value, id=test_id, marks=mark(test_id, name))
                    )
    return out


# ---------------------------------------------------------------------------
# the checks
# ---------------------------------------------------------------------------
def _names_argument(message: str, names: tuple[str, ...]) -> bool:
    return any(re.search(rf"(?<![\w.]){re.escape(n)}(?!\w)", message) for n in names)


def _assert_names(exc: BaseException, entry: Case, arg_name: str) -> None:
    names = entry.args[arg_name].names or (arg_name,)
    message = str(exc)
    assert _names_argument(message, names), (
        f"the {type(exc).__name__} does not name the argument {arg_name!r}: {message!r}"
    )


def check_valid(entry: Case) -> Any:
    """The valid call runs without a warning and answers without NaN."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = entry.call(**entry.kwargs())
    if not entry.nan_ok:
        assert_no_nan(out)
    return out


def check_refused(entry: Case, arg_name: str, bad: Any) -> None:
    """One bad argument: a ValueError/LinAlgError that names it."""
    with pytest.raises(REFUSALS) as info:
        entry.call(**entry.kwargs(**{arg_name: bad}))
    _assert_names(info.value, entry, arg_name)


def check_extreme(entry: Case, arg_name: str, value: Any) -> None:
    """A valid extreme value: a finite answer or a clear refusal; never NaN or overflow."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        try:
            out = entry.call(**entry.kwargs(**{arg_name: value}))
        except REFUSALS as exc:
            _assert_names(exc, entry, arg_name)
            return
    if not entry.nan_ok:
        assert_no_nan(out)


def assert_no_nan(out: Any, where: str = "the answer") -> None:
    """No NaN anywhere in a result (numbers, arrays, tuples, dicts, dataclasses)."""
    if isinstance(out, (bool, np.bool_, str, bytes)) or out is None:
        return
    if isinstance(out, (float, np.floating)):
        assert not math.isnan(out), f"{where} is NaN"
        return
    if isinstance(out, np.ndarray):
        if out.dtype.kind in "fc":
            assert not np.isnan(out).any(), f"{where} holds NaN"
        elif out.dtype == object:
            for i, item in enumerate(out.flat):
                assert_no_nan(item, f"{where}[{i}]")
        return
    if isinstance(out, Mapping):
        for key, item in out.items():
            assert_no_nan(item, f"{where}[{key!r}]")
        return
    if isinstance(out, (tuple, list)):
        for i, item in enumerate(out):
            assert_no_nan(item, f"{where}[{i}]")
        return
    if dataclasses.is_dataclass(out) and not isinstance(out, type):
        for f in dataclasses.fields(out):
            if f.name != "null":  # a law, checked by its own cases
                assert_no_nan(getattr(out, f.name), f"{where}.{f.name}")


# ---------------------------------------------------------------------------
# discovery
# ---------------------------------------------------------------------------
def _home(obj: Any) -> str:
    """``course.nis`` for an object defined in ``course.nis._windowed``."""
    return ".".join(str(getattr(obj, "__module__", "")).split(".")[:2])


def public_callables(module_name: str) -> set[str]:
    """Public functions, classes and public methods defined in ``module_name``.

    Found from the module's ``__all__``; a name re-exported from another
    module is that module's (``course.filters.windowed_nis`` is tested with
    ``course.nis``).  Methods are ``"Class.method"``.
    """
    module = importlib.import_module(module_name)
    found: set[str] = set()
    for name in module.__all__:
        obj = getattr(module, name)
        if not callable(obj) or _home(obj) != module_name:
            continue
        found.add(name)
        if isinstance(obj, type):  # its own public methods (inherited ones are the base's)
            for attr, member in vars(obj).items():
                if attr.startswith("_"):
                    continue
                if isinstance(member, (classmethod, staticmethod)) or inspect.isfunction(member):
                    found.add(f"{name}.{attr}")
    return found


def assert_all_covered(
    modules: tuple[str, ...], table: Mapping[str, Any], exempt: Mapping[str, str]
) -> None:
    """Every public callable has a case or an exemption with its reason; no stale entries."""
    public = set().union(*(public_callables(name) for name in modules))
    missing = sorted(public - set(table) - set(exempt))
    assert not missing, f"public callables of {modules} without a bad-input case: {missing}"
    stale = sorted((set(table) | set(exempt)) - public)
    assert not stale, f"cases for names that are not public in {modules}: {stale}"


def module_tests(
    modules: str | tuple[str, ...],
    table: Mapping[str, Case],
    exempt: Mapping[str, str],
    xfail: Mapping[str, str] | None = None,
) -> tuple[Callable[..., None], ...]:
    """The four tests of a module's table, to assign to ``test_*`` names in a test module."""
    cases = params(table, xfail)
    modules = (modules,) if isinstance(modules, str) else tuple(modules)

    def test_every_public_callable_has_cases():
        assert_all_covered(modules, table, exempt)

    @pytest.mark.parametrize("entry", cases["valid"])
    def test_valid_call(entry):
        check_valid(entry)

    @pytest.mark.parametrize("entry, arg, bad", cases["refused"])
    def test_bad_input_is_refused(entry, arg, bad):
        check_refused(entry, arg, bad)

    # every table has extreme cases: an always-skipped placeholder would hide a table without
    assert cases["extreme"], f"{modules}: no argument of the table has extreme values"

    @pytest.mark.parametrize("entry, arg, value", cases["extreme"])
    def test_extreme_input(entry, arg, value):
        check_extreme(entry, arg, value)

    return (
        test_every_public_callable_has_cases,
        test_valid_call,
        test_bad_input_is_refused,
        test_extreme_input,
    )
