"""Similarity hints: answers whose code is the same once names, literals' spelling and layout
are set aside, for the instructor to look at.

:func:`fingerprint` reduces an answer's source to a hash of its syntax tree: every name the
student chose (variables, arguments, functions they define, ``as`` aliases) is replaced by its
order of first appearance, a literal by its value (``1e3`` and ``1000.0``, ``'a'`` and ``"a"``
alike), comments, docstrings and whitespace vanish; attribute and keyword names (``.T``,
``axis=``) stay, they are the library's. The handed-out skeleton does not count: a top-level
statement the skeleton already holds is left out, and an answer that adds fewer than
:data:`MIN_NODES` syntax nodes to it gets no fingerprint (short answers coincide by
themselves). :func:`similar_groups` lists, per question, the students who share a fingerprint.

A shared fingerprint is a hint to look at two answers side by side, never evidence of
copying: a standard answer written by several students independently can coincide. It is
shown in the class report only, never in a student's feedback.

The grading parent computes a fingerprint from the cell sources the sandboxed reader child
handed it: at most :data:`MAX_SOURCE_CHARS` characters are parsed, the tree is walked without
recursion, and any failure (a syntax error, a tree too deep) just means no fingerprint.
"""

from __future__ import annotations

import ast
import hashlib
import warnings
from collections.abc import Callable, Iterable

__all__ = ["MAX_SOURCE_CHARS", "MIN_NODES", "fingerprint", "similar_groups"]

#: The longest answer source (characters) that is fingerprinted.
MAX_SOURCE_CHARS = 20_000
#: The fewest syntax nodes an answer must add to the skeleton to be fingerprinted.
MIN_NODES = 12
#: Identifier fields that hold a name the student chose (renamed); others are the library's.
_CHOSEN = {
    ("Name", "id"),
    ("arg", "arg"),
    ("FunctionDef", "name"),
    ("AsyncFunctionDef", "name"),
    ("ClassDef", "name"),
    ("ExceptHandler", "name"),
    ("alias", "asname"),
    ("Global", "names"),
    ("Nonlocal", "names"),
    ("MatchAs", "name"),
    ("MatchStar", "name"),
    ("MatchMapping", "rest"),
}
_SKIP_FIELDS = {"ctx", "type_comment", "kind"}


def _parse(source: str) -> ast.Module | None:
    if not isinstance(source, str) or len(source) > MAX_SOURCE_CHARS:
        return None
    try:
        with warnings.catch_warnings():  # an invalid escape in a student's string: no output
            warnings.simplefilter("ignore")
            return ast.parse(source)
    except (SyntaxError, ValueError, MemoryError, RecursionError, OverflowError):
        return None


def _is_docstring(stmt: ast.stmt) -> bool:
    return (
        isinstance(stmt, ast.Expr)
        and isinstance(stmt.value, ast.Constant)
        and isinstance(stmt.value.value, str)
    )


def _tokens(node: ast.AST, rename: Callable[[str], str] | None) -> tuple[list[str], int]:
    """The pre-order token stream of ``node`` (names through ``rename``; None: kept) and its
    number of syntax nodes; iterative, so a deep tree cannot exhaust the stack."""
    out: list[str] = []
    nodes = 0
    stack: list[object] = [node]
    while stack:
        item = stack.pop()
        if isinstance(item, tuple):  # (marker,) pushed below
            out.append(item[0])
            continue
        if isinstance(item, list):
            out.append(f"[{len(item)}")
            stack.extend(reversed(item))
            continue
        if not isinstance(item, ast.AST):
            out.append(repr(item))
            continue
        if isinstance(item, ast.expr_context):
            continue
        nodes += 1
        kind = type(item).__name__
        out.append(kind)
        if isinstance(item, ast.Constant):  # the value, not how it was written
            out.append(f"{type(item.value).__name__}:{item.value!r}")
            continue
        body = getattr(item, "body", None)
        if isinstance(body, list):  # docstrings and bare strings are comments
            body = [s for s in body if not _is_docstring(s)]
        fields = []
        for name, value in ast.iter_fields(item):
            if name in _SKIP_FIELDS:
                continue
            if name == "body" and isinstance(value, list):
                value = body
            if (kind, name) in _CHOSEN and rename is not None and value is not None:
                value = (
                    [(rename(v),) for v in value] if isinstance(value, list) else (rename(value),)
                )
            elif isinstance(value, str):
                value = (repr(value),)
            fields.append(value)
        stack.extend(reversed(fields))
    return out, nodes


def _statements(tree: ast.Module) -> list[str]:
    """Each top-level statement as text with the names as written (to match the skeleton's)."""
    return ["\x00".join(_tokens(s, None)[0]) for s in tree.body if not _is_docstring(s)]


def fingerprint(source: str, skeleton: str = "") -> str | None:
    """The hash of ``source``'s normalised syntax tree (see the module docstring), or None:
    not parseable within the bounds, or too little beyond the ``skeleton``.

    Examples
    --------
    >>> a = "def f(t, y):\\n    total = sum(y) * 2.0\\n    return total / len(t) + 1e3"
    >>> b = "def f(x, obs):  # renamed\\n    s = sum(obs)*2.\\n    return s/len(x) + 1000.0"
    >>> fingerprint(a) == fingerprint(b) != None
    True
    >>> fingerprint("def f(t, y):\\n    ...", skeleton="def f(t, y):\\n    ...") is None
    True
    """
    tree = _parse(source)
    if tree is None:
        return None
    given = _parse(skeleton) if skeleton else None
    handed_out = set(_statements(given)) if given is not None else set()
    tree.body = [
        s
        for s, text in zip([s for s in tree.body if not _is_docstring(s)], _statements(tree))
        if text not in handed_out
    ]
    names: dict[str, str] = {}

    def rename(name: str) -> str:
        return names.setdefault(name, f"n{len(names)}")

    try:
        tokens, nodes = _tokens(tree, rename)
    except (MemoryError, RecursionError):
        return None
    if nodes - 1 < MIN_NODES:  # the Module node itself is no code
        return None
    return hashlib.sha256("\x00".join(tokens).encode("utf-8", "surrogatepass")).hexdigest()[:32]


def similar_groups(
    fingerprints: Iterable[tuple[str, str, str | None]],
) -> list[tuple[str, list[str]]]:
    """``(question, students)`` for every group of two or more students sharing a fingerprint,
    from ``(question, student, fingerprint)`` triples; by question, then largest group first.

    Examples
    --------
    >>> similar_groups([("q1", "b", "x"), ("q1", "a", "x"), ("q1", "c", "y"), ("q2", "c", None)])
    [('q1', ['a', 'b'])]
    """
    by_key: dict[tuple[str, str], list[str]] = {}
    order: dict[str, int] = {}
    for qid, student, fp in fingerprints:
        order.setdefault(qid, len(order))
        if fp:
            by_key.setdefault((qid, fp), []).append(student)
    groups = [(qid, sorted(s)) for (qid, _), s in by_key.items() if len(s) > 1]
    return sorted(groups, key=lambda g: (order[g[0]], -len(g[1]), g[1]))
