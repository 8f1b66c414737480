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

A forbidden function's private implementation is forbidden with it: :func:`implementation`
follows the calls in its source to the private functions of its own package (and of the shared
``course._*`` modules), transitively, and each of those reports itself with the public names it
implements (the nearest first), so ``course.filters._steps._kf_update`` counts as
``course.filters.kf_update`` and is named as what the student called. What is forbidden is the
code that computes, not the name.

A report also carries the label of the calling code when it has one (:func:`label_callers`):
the grader labels each answer function with its question, so that a call is charged on the
question whose function made it, however another question reached that function.

Calls made by the library itself (``data_snooping`` calling ``w_tests``) are not reported.
Whether a caller is library code does not depend on anything a submission can set: the caller
frame must run a code object that belonged to the library before student code ran (compared by
identity; every such object is kept alive, so its identity cannot be reused) or one of the
instrumented code objects, and its globals must be a library module's own namespace (also by
identity). ``__name__``, a module's globals, the frame's file name, a constant a submission
can copy into its own code object: none of them counts. The decision data sit in the
instrumented code objects' constants (immutable frozensets of ids), not in variables; a
submission may read those ids, but no object it makes can have one of them, since every object
named there is kept alive (``_KEEP``).

The report cannot be skipped by a trace function: the body of an instrumented function runs
inside a one-pass loop whose header makes the report, and the interpreter's ``frame.f_lineno``
setter refuses a jump into a loop's body ("can't jump into the body of a for loop"); a profile
function or ``sys.monitoring`` cannot jump at all. So tracing stays allowed (debuggers work
in the student's Jupyter) and changes nothing.

What remains possible (see ``docs/instructors/authoring.md``): rewriting compiled library code
(``types.CodeType``, ``code.replace``) or copying the library's source into the notebook
gives a function without the report; that is plagiarism of the library, not a sandbox escape.
A library function that takes a callback calls it as library code.

:func:`watch` is the student self-check's version: the same rewriting, the same functions and
the same rule for who counts as the library, reporting to a Python callable instead of a pipe,
and undone by the function it returns (no security claim: it runs in the student's own Jupyter).
"""

from __future__ import annotations

import ast
import importlib
import inspect
import linecache
import os
import re
import sys
import textwrap
import types
import typing
import warnings
from builtins import getattr, setattr, str  # bound before student code runs (see runner)
from typing import Any

__all__ = [
    "EVENT",
    "Call",
    "course_modules",
    "implementation",
    "instrument",
    "label_callers",
    "parse_events",
    "resolve",
    "watch",
]

#: The record written for one forbidden call: the function called (dotted), the public
#: functions it implements (itself for a public one; the nearest first), and where the call
#: came from (``callers``' label of the calling code, empty when it has none).
EVENT = b"\x1ecourse-forbidden-call:%s=%s@%s\x1f"
_EVENT_RE = re.compile(
    rb"\x1ecourse-forbidden-call:([A-Za-z0-9_.]{1,200})=([A-Za-z0-9_.,]{1,4000})"
    rb"@([A-Za-z0-9_]{0,40})\x1f"
)
_LIBRARY_PREFIX = "course."
_NOT_LIBRARY = ("course.grading", "course.cli", "course.__main__")

# placeholders in the prologue's source, replaced by objects in the compiled code's constants
_P_FRAME, _P_ID, _P_WRITE = "__tw_getframe__", "__tw_id__", "__tw_write__"
_P_GLOBALS, _P_CODES, _P_CALLERS = "__tw_globals__", "__tw_codes__", "__tw_callers__"
# The report sits in the header of a one-pass ``for`` loop that holds the whole body: a trace
# function may set ``frame.f_lineno`` only to a line outside any loop it is not already in
# ("can't jump into the body of a for loop"), so no line jump reaches the body without the
# header having run. The loop unpacks ``()`` into no name, so the function gets no new local.
# The caller is trusted by identity only: its code object is one of the library's or of the
# tripwires' own (ids, of objects kept alive), or it is this very code (recursion), and its
# globals are a library module's namespace.
_PROLOGUE = (
    f"for [] in (((),) if ({_P_ID!r}({_P_FRAME!r}(1).f_globals) in {_P_GLOBALS!r} and "
    f"({_P_ID!r}({_P_FRAME!r}(1).f_code) in {_P_CODES!r} or "
    f"{_P_FRAME!r}(1).f_code is {_P_FRAME!r}(0).f_code)) "
    f"else ({_P_WRITE!r}(__TW_FD__, __TW_EVENT__ + "
    f"{_P_CALLERS!r}.get({_P_ID!r}({_P_FRAME!r}(1).f_code), b'') + b'\\x1f'), ())[1:]):"
    "\n    pass\n"
)


class Call(typing.NamedTuple):
    """One forbidden call reported: ``called`` as the submission called it (a public function,
    or a private helper), the public functions it implements (``implements``, the nearest
    first) and the label of the calling code (``where``; '' when unlabelled)."""

    called: str
    implements: tuple[str, ...]
    where: str

    def describe(self, forbidden=None) -> str:
        """``course.lsq.fit``, or ``course.filters._steps._update_core (a private helper of
        course.filters.kf_update)``: the nearest public function it implements among
        ``forbidden`` (default: all)."""
        if self.implements == (self.called,):
            return self.called
        nearest = [n for n in self.implements if forbidden is None or n in forbidden]
        return f"{self.called} (a private helper of {(nearest or self.implements)[0]})"


def parse_events(buffer: bytes) -> tuple[list[Call], bytes]:
    """Forbidden calls reported in ``buffer``, and the tail to keep for the next read.

    Records are found anywhere in the stream, so bytes a submission writes in between can add
    reports (against itself) but never hide one.
    """
    calls = [
        Call(
            m.group(1).decode("ascii"),
            tuple(n for n in m.group(2).decode("ascii").split(",") if n),
            m.group(3).decode("ascii"),
        )
        for m in _EVENT_RE.finditer(buffer)
    ]
    cut = buffer.rfind(b"\x1e")
    tail = buffer[cut:] if cut >= 0 and not _EVENT_RE.search(buffer, cut) else b""
    return calls, tail[-4300:]


#: Code objects labelled in a ``callers`` mapping, kept alive so that their ids stay theirs.
_LABELLED: list = []


def label_callers(callers: dict, func, label: str) -> None:
    """Label ``func``'s code (and every code object nested in it) as ``label`` in ``callers``
    (``id(code) -> label``), the mapping a tripwire reads to say where a call came from: the
    grader labels each answer function with its question, right after its answer cell."""
    code = getattr(func, "__code__", None)
    if not isinstance(code, types.CodeType) or not re.fullmatch(r"[A-Za-z0-9_]{1,40}", label):
        return
    for c in _codes_of(code):
        callers[id(c)] = label.encode("ascii")
        _LABELLED.append(c)


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

    def here(n) -> bool:
        return (
            isinstance(n, ast.FunctionDef)
            and n.name == code.co_name
            and min([n.lineno, *(d.lineno for d in n.decorator_list)]) == code.co_firstlineno
        )

    fdef = next((n for n in tree.body if isinstance(n, ast.FunctionDef) and here(n)), None)
    owner = None  # a method: the class statement that holds it (its other methods dropped)
    if fdef is None:
        for cdef in tree.body:
            if isinstance(cdef, ast.ClassDef):
                fdef = next(
                    (n for n in cdef.body if isinstance(n, ast.FunctionDef) and here(n)), None
                )
                if fdef is not None:
                    owner = cdef
                    break
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
        assert isinstance(stmt, ast.For)
        if len(body) > at:  # the body runs inside the loop (its lines unchanged)
            stmt.body = body[at:]
            stmt.end_lineno = body[-1].end_lineno
            stmt.end_col_offset = body[-1].end_col_offset
        fdef.body = [*body[:at], stmt]
    if owner is not None:
        owner.body = [n for n in owner.body if n is fdef or not isinstance(n, ast.FunctionDef)]
        owner.decorator_list = []
    keep = owner if owner is not None else fdef
    tree.body = [
        n for n in tree.body if n is keep or not isinstance(n, (ast.FunctionDef, ast.ClassDef))
    ]
    flags = code.co_flags & _FUTURE_FLAGS
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SyntaxWarning)  # the prologue calls string placeholders
        module_code = compile(tree, code.co_filename, "exec", flags, dont_inherit=True)
    found = [
        c
        for c in _codes_of(module_code)
        if c.co_name == code.co_name
        and c.co_firstlineno == code.co_firstlineno
        and getattr(c, "co_qualname", None) == getattr(code, "co_qualname", None)
    ]
    return found[0] if len(found) == 1 else None


def _future_flags() -> int:
    import __future__

    return sum(getattr(__future__, f).compiler_flag for f in __future__.all_feature_names)


_FUTURE_FLAGS = _future_flags()


def _replace_consts(code: types.CodeType, mapping: dict) -> types.CodeType:
    consts = []
    for c in code.co_consts:
        if isinstance(c, types.CodeType):
            consts.append(_replace_consts(c, mapping))
        elif isinstance(c, str) and c in mapping:
            consts.append(mapping[c])
        else:
            consts.append(c)
    return code.replace(co_consts=tuple(consts))


def _same_code(a: types.CodeType, b: types.CodeType) -> bool:
    return a.co_code == b.co_code and a.co_names == b.co_names and a.co_varnames == b.co_varnames


#: Library code objects trusted as callers (and the instrumented ones, and the library's
#: namespaces); kept alive so that their ids stay theirs.
_KEEP: list = []


def course_modules() -> list[str]:
    """Every module of the course library (not the grader's own, which pull in nbformat).

    The grader imports them all before student code (a child may not read the library's
    sources), and so does the self-check before :func:`watch`, so that every library module's
    namespace is known as the library's when a forbidden function asks who called it."""
    import pkgutil

    import course

    names = ["course"]
    skip = ("course.__main__", "course.cli", "course.grading")
    for info in pkgutil.walk_packages(course.__path__, "course."):
        if not any(info.name == s or info.name.startswith(s + ".") for s in skip):
            names.append(info.name)
    return names


def _resolve(expr: ast.expr, namespace: dict):
    """The object a call's function expression names (``f``, ``module.f``), or None."""
    if isinstance(expr, ast.Name):
        return namespace.get(expr.id)
    if isinstance(expr, ast.Attribute):
        base = _resolve(expr.value, namespace)
        if isinstance(base, (types.ModuleType, type)):
            return getattr(base, expr.attr, None)
    return None


def _callees(func: types.FunctionType) -> list[types.FunctionType]:
    """The library functions ``func``'s source calls by a name it can resolve (its module's
    globals): calls, not mere mentions, so that a helper handed to scipy as a callback is not
    taken for the implementation."""
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
    except (OSError, TypeError, SyntaxError):
        return []
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            target = _resolve(node.func, func.__globals__)
            if isinstance(target, types.FunctionType) and target not in out:
                out.append(target)
    return out


def _topic(module_name: str) -> str:
    """``course.filters`` for ``course.filters._steps``: the package a function belongs to."""
    return ".".join(module_name.split(".")[:2])


def _public_ids() -> set[int]:
    """Ids of the functions that some public name of the library reaches (``course.x.f``)."""
    ids: set[int] = set()
    for name, module in list(sys.modules.items()):
        if module is None or not _is_library(name):
            continue
        if any(part.startswith("_") for part in name.split(".")):
            continue
        public = getattr(module, "__all__", None)
        names = public if public is not None else [n for n in vars(module) if n[:1] != "_"]
        for attr in names:
            obj = vars(module).get(attr)
            if isinstance(obj, types.FunctionType):
                ids.add(id(obj))
    return ids


def implementation(func, public_ids: set[int] | None = None) -> list[types.FunctionType]:
    """The private functions that compute ``func``: those its source calls, transitively,
    that are library functions of its own package (``course.filters._steps._kf_update`` for
    ``course.filters.kf_update``) or of a shared internal module (``course._unchecked``) and
    that no public name reaches. ``func`` itself is not in the list."""
    if not isinstance(func, types.FunctionType):
        return []
    public = _public_ids() if public_ids is None else public_ids
    topic = _topic(str(func.__module__ or ""))

    return list(_implementation_depths(func, _private_of(topic, public)))


def _private_of(topic: str, public: set[int]):
    """Whether a function is private library code of ``topic`` or of a shared module."""

    def private_here(f: types.FunctionType) -> bool:
        module_name = str(getattr(f, "__module__", "") or "")
        if not _is_library(module_name) or id(f) in public:
            return False
        return _topic(module_name) == topic or module_name.split(".")[1][:1] == "_"

    return private_here


def _implementation_depths(func, private_here) -> dict:
    """:func:`implementation` breadth first: each private function with the number of calls
    between ``func`` and it (1: ``func`` calls it)."""
    found: dict = {}
    todo = [(func, 0)]
    while todo:
        caller, depth = todo.pop(0)
        for callee in _callees(caller):
            if callee is not func and callee not in found and private_here(callee):
                found[callee] = depth + 1
                todo.append((callee, depth + 1))
    return found


def _targets(names) -> tuple[dict[str, object], dict[types.FunctionType, list[str]]]:
    """The forbidden objects by dotted name (None when missing), and every private function
    that implements one of them with the public names it implements, the nearest first
    (fewest calls away, then of its own module, then first in the source), so that a report
    names ``_update_core`` a helper of ``kf_update``, not of the seven other filters it
    also serves."""
    named: dict[str, object] = {}
    for dotted in sorted(set(names)):
        named[dotted] = resolve(dotted)
    for dotted, obj in named.items():
        init = vars(obj).get("__init__") if isinstance(obj, type) else None
        if isinstance(init, types.FunctionType) and _is_library(str(init.__module__)):
            named[dotted] = init  # a class: its constructor reports
    public = _public_ids()
    forbidden_ids = {id(f) for f in named.values()}
    ranked: dict[types.FunctionType, list[tuple]] = {}
    for dotted, func in named.items():
        if not isinstance(func, types.FunctionType):
            continue
        private_here = _private_of(_topic(str(func.__module__ or "")), public)
        for f, depth in _implementation_depths(func, private_here).items():
            if id(f) not in forbidden_ids:
                where = (depth, f.__module__ != func.__module__, func.__code__.co_firstlineno)
                ranked.setdefault(f, []).append((*where, dotted))
    private = {f: [rank[-1] for rank in sorted(ranks)] for f, ranks in ranked.items()}
    return named, private


def resolve(dotted: str):
    """The object a forbid entry names: ``module.function``, ``module.Class`` or
    ``module.Class.method`` (a class or static method: its function); None when missing."""
    parts = dotted.split(".")
    for cut in range(len(parts) - 1, 0, -1):
        obj: Any
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        owner = None
        for attr in parts[cut:]:
            owner, obj = obj, (vars(obj).get(attr) if isinstance(obj, type) else None)
            if obj is None:
                obj = getattr(owner, attr, None)
            if obj is None:
                return None
        if isinstance(obj, (staticmethod, classmethod)):
            obj = obj.__func__
        return obj
    return None


def _event_head(called: str, implements) -> bytes:
    """A record up to the caller's label (the prologue adds the label and the end byte)."""
    return (EVENT % (called.encode("ascii"), ",".join(implements).encode("ascii"), b""))[:-1]


def _callers_first(jobs: list) -> list:
    """``jobs`` ordered so that a function comes after every other job function whose source
    calls it (a cycle, beyond a function calling itself, keeps its members' given order)."""
    funcs = [job[1] for job in jobs]
    index = {id(f): i for i, f in enumerate(funcs) if f is not None}
    calls = {
        i: {index[id(c)] for c in _callees(f) if id(c) in index and index[id(c)] != i}
        if isinstance(f, types.FunctionType)
        else set()
        for i, f in enumerate(funcs)
    }
    waiting = {i: sum(i in callees for callees in calls.values()) for i in range(len(jobs))}
    order: list[int] = []
    ready = [i for i in range(len(jobs)) if waiting[i] == 0]
    while ready:
        i = ready.pop(0)
        order.append(i)
        for j in sorted(calls[i]):
            waiting[j] -= 1
            if waiting[j] == 0:
                ready.append(j)
    order += [i for i in range(len(jobs)) if i not in order]
    return [jobs[i] for i in order]


def _rewrite(names, event_fd: int, write, callers: dict):
    """Rewrite the forbidden functions ``names`` and their private implementation to call
    ``write(event_fd, record)`` when called from outside the library (the record ends with
    ``callers``' label of the calling code, see :func:`label_callers`). Returns the report
    ``{name: how}`` and what undoes it: ``(function, original code)`` pairs and
    ``(module, attr, original)`` triples of wrapped attributes.

    A caller counts as the library when its code object is, by identity, one the library had
    before (kept alive in ``_KEEP``, so no other object can take its id) or one rewritten here
    earlier. The rewritten functions are made callers first (a function after those that call
    it), so each one's set of trusted ids, fixed in its constants, holds its rewritten callers."""
    named, private = _targets(names)
    functions = list(_library_functions())
    rewritten_ids = {id(f) for f in named.values() if isinstance(f, types.FunctionType)}
    rewritten_ids |= {id(f) for f in private}
    trusted = [c for f in functions if id(f) not in rewritten_ids for c in _codes_of(f.__code__)]
    _KEEP.extend(trusted)
    module_dicts = [
        vars(m) for n, m in list(sys.modules.items()) if m is not None and _is_library(n)
    ]
    _KEEP.extend(module_dicts)
    trusted_ids = {id(c) for c in trusted}
    mapping = {
        _P_FRAME: sys._getframe,
        _P_ID: id,
        _P_WRITE: write,
        _P_GLOBALS: frozenset(id(d) for d in module_dicts),
        _P_CALLERS: callers,
    }
    report: dict[str, str] = {}
    codes: list[tuple[types.FunctionType, types.CodeType]] = []
    wrapped: list[tuple] = []
    jobs = [(dotted, func, [dotted]) for dotted, func in named.items()]
    jobs += [
        (f"{f.__module__}.{f.__qualname__}", f, implements) for f, implements in private.items()
    ]
    for dotted, func, implements in _callers_first(jobs):
        if func is None:
            report[dotted] = "missing"
            continue
        event = _event_head(dotted, implements)
        prologue = _PROLOGUE.replace("__TW_FD__", str(int(event_fd))).replace(
            "__TW_EVENT__", repr(event)
        )
        plain = isinstance(func, types.FunctionType) and not func.__code__.co_freevars
        original = _recompile(func, None) if plain else None
        new = _recompile(func, prologue) if original is not None else None
        if (
            isinstance(func, types.FunctionType)
            and new is not None
            and original is not None
            and _same_code(original, func.__code__)
        ):
            codes.append((func, func.__code__))
            func.__code__ = _replace_consts(new, {**mapping, _P_CODES: frozenset(trusted_ids)})
            made = list(_codes_of(func.__code__))
            _KEEP.extend(made)  # alive, whatever happens to the function, so its id stays its
            trusted_ids.update(id(c) for c in made)
            report[dotted] = "instrumented"
        elif dotted in named and isinstance(
            sys.modules.get(dotted.rpartition(".")[0]), types.ModuleType
        ):
            wrapped.append(_wrap_reporting(dotted, func, event_fd, event + b"\x1f", write))
            report[dotted] = "wrapped"
        elif dotted in named:
            report[dotted] = "missing"  # a method that cannot be rewritten: nothing to wrap
        # a private helper that cannot be rewritten stays as it is: no public name to wrap
    return report, codes, wrapped


def instrument(names, event_fd: int, callers: dict | None = None) -> dict[str, str]:
    """Instrument the forbidden functions ``names`` (dotted), and their private implementation
    (:func:`implementation`), to report to ``event_fd``.

    Call once, in the warm process, after every library module is imported and before student
    code exists. Returns ``{name: how}`` with ``how`` one of ``"instrumented"``, ``"wrapped"``
    (not a plain function with source: a reporting wrapper replaces the module attribute, a
    weaker guard) or ``"missing"``; the private functions rewritten are listed too, by their
    own dotted names. ``callers``: the mapping :func:`label_callers` fills (the label of
    the calling code is part of each report).
    """
    report, _, _ = _rewrite(names, event_fd, os.write, {} if callers is None else callers)
    linecache.clearcache()  # no library source left in memory for a child to read
    return report


def watch(names, record, callers: dict | None = None):
    """The self-check's tripwires: :func:`instrument`'s rewriting, reporting to ``record``.

    Every call of a forbidden function in ``names`` (or of its private implementation) from
    outside the library, by any path (an alias, ``getattr``, ``functools.partial``, a private
    twin), calls ``record(call)`` with the :class:`Call`, before the function runs. Import the
    library first (:func:`course_modules`): the modules imported later do not count as the
    library.

    Returns
    -------
    callable
        Puts every function back as it was.
    """

    def write(_fd, event: bytes) -> None:
        for call in parse_events(event)[0]:
            record(call)

    _, codes, wrapped = _rewrite(names, 0, write, {} if callers is None else callers)

    def restore() -> None:
        for func, code in reversed(codes):
            func.__code__ = code
        for module, attr, original in reversed(wrapped):
            setattr(module, attr, original)

    return restore


def _wrap_reporting(dotted: str, func, event_fd: int, event: bytes, write=os.write):
    module_name, _, attr = dotted.rpartition(".")
    module = importlib.import_module(module_name)

    def reporting(*args, **kwargs):
        write(event_fd, event)
        return func(*args, **kwargs)

    reporting.__name__ = getattr(func, "__name__", attr)
    reporting.__doc__ = getattr(func, "__doc__", None)
    setattr(module, attr, reporting)
    return module, attr, func
