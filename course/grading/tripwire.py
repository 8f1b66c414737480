"""Tripwires on forbidden library functions.

A question may forbid functions (``"course.lsq.w_tests"``, ...) that would answer it outright.

At grading, :func:`instrument` rewrites each forbidden function IN PLACE, in the warm fork
server before any student code exists: the function object keeps its identity (so every
reference to it, ``from course.lsq import w_tests`` included, is covered) but its code now
starts with a report, written straight to a pipe whose other end only the trusted parent
holds. The report is one ``os.write`` of at most a few dozen bytes (atomic on a pipe); it is
made before the function does anything, and if it cannot be made the call fails. The parent
counts it against the question whose request is running at that moment, so nothing a
submission does afterwards in its own process (clearing records, patching modules) changes
it. The seccomp filter keeps the pipe's descriptor from being closed or replaced, and
Landlock keeps the library's sources unreadable, so a module cannot be re-imported from
source to get a function without the report.

Calls made by the library itself (``data_snooping`` calling ``w_tests``) are not reported.
Whether a caller is library code does not depend on anything a submission can set: the caller
frame must run a code object that belonged to the library before student code ran (compared by
identity; every such object is kept alive, so its identity cannot be reused) or one of the
instrumented code objects, and its globals must be a library module's own namespace (also by
identity). ``__name__``, a module's globals, the frame's file name: none of them counts. The
decision data sit in the instrumented code objects' constants (immutable), not in variables.

What remains possible (see ``docs/instructors/authoring.md``): rewriting compiled library code
(``types.CodeType``, ``code.replace``) or copying the library's source into the notebook
gives a function without the report; that is plagiarism of the library, not a sandbox escape.
A library function that takes a callback calls it as library code.

:func:`wrap_forbidden` is the student self-check's version: a friendly warning in the student's
own Jupyter, with no security claim.
"""

from __future__ import annotations

import ast
import importlib
import linecache
import os
import re
import sys
import types
import warnings
from builtins import getattr, setattr, str  # bound before student code runs (see runner)

__all__ = ["EVENT", "instrument", "parse_events", "wrap_forbidden"]

#: The record written for one forbidden call (the name is a dotted Python name).
EVENT = b"\x1ecourse-forbidden-call:%s\x1f"
_EVENT_RE = re.compile(rb"\x1ecourse-forbidden-call:([A-Za-z0-9_.]{1,200})\x1f")
_LIBRARY_PREFIX = "course."
_NOT_LIBRARY = ("course.grading", "course.cli", "course.__main__")

# placeholders in the prologue's source, replaced by objects in the compiled code's constants
_P_FRAME, _P_ID, _P_WRITE = "__tw_getframe__", "__tw_id__", "__tw_write__"
_P_GLOBALS, _P_CODES, _P_MARK = "__tw_globals__", "__tw_codes__", "__tw_mark__"
_PROLOGUE = (
    f"if not ({_P_ID!r}({_P_FRAME!r}(1).f_globals) in {_P_GLOBALS!r} and "
    f"({_P_ID!r}({_P_FRAME!r}(1).f_code) in {_P_CODES!r} or "
    f"{_P_MARK!r} in {_P_FRAME!r}(1).f_code.co_consts)): "
    f"{_P_WRITE!r}(__TW_FD__, __TW_EVENT__)"
)


def parse_events(buffer: bytes) -> tuple[list[str], bytes]:
    """Forbidden calls reported in ``buffer``, and the tail to keep for the next read.

    Records are found anywhere in the stream, so bytes a submission writes in between can add
    reports (against itself) but never hide one.
    """
    names = [m.group(1).decode("ascii") for m in _EVENT_RE.finditer(buffer)]
    cut = buffer.rfind(b"\x1e")
    tail = buffer[cut:] if cut >= 0 and not _EVENT_RE.search(buffer, cut) else b""
    return names, tail[-300:]


def _is_library(module_name: str) -> bool:
    return (module_name == "course" or module_name.startswith(_LIBRARY_PREFIX)) and not any(
        module_name == p or module_name.startswith(p + ".") for p in _NOT_LIBRARY
    )


def _codes_of(code: types.CodeType):
    yield code
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            yield from _codes_of(const)


def _library_functions():
    """Every Python function of the library's modules (methods and wrapped functions too)."""
    seen: set[int] = set()
    for name, module in list(sys.modules.items()):
        if module is None or not _is_library(name):
            continue
        stack = list(vars(module).values())
        while stack:
            obj = stack.pop()
            if id(obj) in seen:
                continue
            seen.add(id(obj))
            if isinstance(obj, (staticmethod, classmethod)):
                stack.append(obj.__func__)
            elif isinstance(obj, property):
                stack.extend(f for f in (obj.fget, obj.fset, obj.fdel) if f is not None)
            elif isinstance(obj, types.FunctionType):
                if _is_library(str(getattr(obj, "__module__", "") or "")):
                    yield obj
                wrapped = getattr(obj, "__wrapped__", None)
                if wrapped is not None:
                    stack.append(wrapped)
            elif isinstance(obj, type) and _is_library(str(getattr(obj, "__module__", ""))):
                stack.extend(vars(obj).values())


def _recompile(func: types.FunctionType, prologue: str | None) -> types.CodeType | None:
    """``func``'s code compiled again from its module's source (the whole module, so that the
    compiler sees the same context), optionally with ``prologue`` as its first statement."""
    code = func.__code__
    source = "".join(linecache.getlines(code.co_filename))
    if not source:
        return None
    try:
        tree = ast.parse(source)
    except SyntaxError:
        return None
    fdef = next(
        (
            n
            for n in tree.body
            if isinstance(n, ast.FunctionDef)
            and n.name == code.co_name
            and min([n.lineno, *(d.lineno for d in n.decorator_list)]) == code.co_firstlineno
        ),
        None,
    )
    if fdef is None:
        return None
    if prologue is not None:
        body = fdef.body
        has_doc = bool(
            body
            and isinstance(body[0], ast.Expr)
            and isinstance(body[0].value, ast.Constant)
            and isinstance(body[0].value.value, str)
        )
        at = 1 if has_doc else 0  # after the docstring, which stays the docstring
        anchor = body[at].lineno if len(body) > at else fdef.lineno
        stmt = ast.parse(prologue).body[0]
        ast.increment_lineno(stmt, anchor - 1)
        body.insert(at, stmt)
    tree.body = [n for n in tree.body if n is fdef or not isinstance(n, ast.FunctionDef)]
    flags = code.co_flags & _FUTURE_FLAGS
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SyntaxWarning)  # the prologue calls string placeholders
        module_code = compile(tree, code.co_filename, "exec", flags, dont_inherit=True)
    found = [
        c
        for c in module_code.co_consts
        if isinstance(c, types.CodeType)
        and c.co_name == code.co_name
        and c.co_firstlineno == code.co_firstlineno
    ]
    return found[0] if len(found) == 1 else None


def _future_flags() -> int:
    import __future__

    return sum(getattr(__future__, f).compiler_flag for f in __future__.all_feature_names)


_FUTURE_FLAGS = _future_flags()


def _replace_consts(code: types.CodeType, mapping: dict, mark) -> types.CodeType:
    consts = []
    for c in code.co_consts:
        if isinstance(c, types.CodeType):
            consts.append(_replace_consts(c, mapping, mark))
        elif isinstance(c, str) and c in mapping:
            consts.append(mapping[c])
        else:
            consts.append(c)
    return code.replace(co_consts=(*consts, mark))  # every nested code object carries the mark


def _same_code(a: types.CodeType, b: types.CodeType) -> bool:
    return a.co_code == b.co_code and a.co_names == b.co_names and a.co_varnames == b.co_varnames


#: Library code objects trusted as callers; kept alive so that their ids stay theirs.
_KEEP: list = []


def instrument(names, event_fd: int) -> dict[str, str]:
    """Instrument the forbidden functions ``names`` (dotted) to report to ``event_fd``.

    Call once, in the warm process, after every library module is imported and before student
    code exists. Returns ``{name: how}`` with ``how`` one of ``"instrumented"``, ``"wrapped"``
    (not a plain function with source: a reporting wrapper replaces the module attribute, a
    weaker guard) or ``"missing"``.
    """
    functions = list(_library_functions())
    targets: dict[str, types.FunctionType | None] = {}
    for dotted in sorted(set(names)):
        module_name, _, attr = dotted.rpartition(".")
        try:
            obj = getattr(importlib.import_module(module_name), attr)
        except (ImportError, AttributeError):
            targets[dotted] = None
            continue
        targets[dotted] = obj
    instrumented_ids = {id(f) for f in targets.values() if isinstance(f, types.FunctionType)}
    trusted = [c for f in functions if id(f) not in instrumented_ids for c in _codes_of(f.__code__)]
    _KEEP.extend(trusted)
    module_dicts = [
        vars(m) for n, m in list(sys.modules.items()) if m is not None and _is_library(n)
    ]
    _KEEP.extend(module_dicts)
    mark = object()  # only the instrumented code objects hold it (identity, no equality)
    mapping = {
        _P_FRAME: sys._getframe,
        _P_ID: id,
        _P_WRITE: os.write,
        _P_GLOBALS: frozenset(id(d) for d in module_dicts),
        _P_CODES: frozenset(id(c) for c in trusted),
        _P_MARK: mark,
    }
    report: dict[str, str] = {}
    for dotted, func in targets.items():
        if func is None:
            report[dotted] = "missing"
            continue
        event = EVENT % dotted.encode("ascii")
        prologue = _PROLOGUE.replace("__TW_FD__", str(int(event_fd))).replace(
            "__TW_EVENT__", repr(event)
        )
        plain = isinstance(func, types.FunctionType) and not func.__code__.co_freevars
        original = _recompile(func, None) if plain else None
        new = _recompile(func, prologue) if original is not None else None
        if new is not None and original is not None and _same_code(original, func.__code__):
            func.__code__ = _replace_consts(new, mapping, mark)
            report[dotted] = "instrumented"
        else:
            _wrap_reporting(dotted, func, event_fd, event)
            report[dotted] = "wrapped"
    linecache.clearcache()  # no library source left in memory for a child to read
    return report


def _wrap_reporting(dotted: str, func, event_fd: int, event: bytes) -> None:
    module_name, _, attr = dotted.rpartition(".")
    module = importlib.import_module(module_name)

    def reporting(*args, **kwargs):
        os.write(event_fd, event)
        return func(*args, **kwargs)

    reporting.__name__ = getattr(func, "__name__", attr)
    reporting.__doc__ = getattr(func, "__doc__", None)
    setattr(module, attr, reporting)


def wrap_forbidden(dotted: str, record, user_ns: dict | None = None):
    """Replace the function ``dotted`` (``"package.module.name"``) by a reporting wrapper.

    For the student's self-check only (a warning before grading, no security claim).

    Parameters
    ----------
    dotted : str
        Full dotted name of the function.
    record : callable
        ``record(dotted)``, called before the original on each call from notebook code.
    user_ns : dict, optional
        The notebook's namespace, which counts as notebook code even if it is named like a
        library module.

    Returns
    -------
    tuple or None
        ``(module, attr, original)`` to put the original back, or None when there is no such
        function (nothing is wrapped).
    """
    module_name, _, attr = dotted.rpartition(".")
    try:
        module = importlib.import_module(module_name)
        original = getattr(module, attr)
    except (ImportError, AttributeError):
        return None

    def wrapper(*args, __original=original, __name=dotted, **kwargs):
        caller = sys._getframe(1).f_globals
        # calls from inside the library (e.g. data_snooping -> w_tests) are allowed
        if caller is user_ns or not str(caller.get("__name__", "")).startswith("course."):
            record(__name)
        return __original(*args, **kwargs)

    wrapper.__name__ = getattr(original, "__name__", attr)
    wrapper.__doc__ = getattr(original, "__doc__", None)
    setattr(module, attr, wrapper)
    return module, attr, original
