"""How the course changes its API: a DeprecationWarning for one release, then removal.

Every deprecated call keeps working in the release that deprecates it and
warns with a message saying what to write instead; the next release removes
it.  CHANGELOG.md lists each deprecation.
"""

from __future__ import annotations

import functools
import inspect
import warnings
from collections.abc import Callable
from typing import Any, TypeVar

#: The release that deprecates, and the one that removes.
SINCE = "0.2"
REMOVED_IN = "0.3"

F = TypeVar("F", bound=Callable[..., Any])


def warn(message: str, stacklevel: int = 3) -> None:
    """Issue a DeprecationWarning pointing at the caller's line."""
    warnings.warn(
        f"{message} (deprecated in {SINCE}, removed in {REMOVED_IN})",
        DeprecationWarning,
        stacklevel=stacklevel,
    )


def keyword_only(*names: str) -> Callable[[F], F]:
    """Accept, with a warning, the old positional use of now keyword-only ``names``.

    The decorated function declares ``names`` after ``*``; a call that still
    passes them positionally (after all positional parameters) gets them
    mapped in order, and a DeprecationWarning.
    """

    def decorate(func: F) -> F:
        signature = inspect.signature(func)
        n_positional = sum(
            p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)
            for p in signature.parameters.values()
        )

        @functools.wraps(func)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            if len(args) > n_positional:
                extra = args[n_positional:]
                if len(extra) > len(names):
                    raise TypeError(
                        f"{func.__name__}() takes at most {n_positional + len(names)} "
                        f"positional arguments ({len(args)} given)"
                    )
                moved = names[: len(extra)]
                for name, value in zip(moved, extra):
                    if name in kwargs:
                        raise TypeError(f"{func.__name__}() got multiple values for {name!r}")
                    kwargs[name] = value
                shown = ", ".join(f"{n}=..." for n in moved)
                warn(f"passing {', '.join(moved)} to {func.__name__}() by position; write {shown}")
                args = args[:n_positional]
            return func(*args, **kwargs)

        return wrapper  # type: ignore[return-value]

    return decorate


def _is_level(value: Any) -> bool:
    """A level of significance: a non-integer number strictly inside (0, 1)."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        return False
    return not isinstance(value, bool) and 0.0 < number < 1.0


def alpha_first(new_call: str, keyword: str | None = None) -> Callable[[F], F]:
    """Accept, with a warning, the old order ``f(alpha, first[, third])``.

    The decorated function takes ``f(first, alpha=..., *, keyword=...)``.  A
    call whose first positional argument is a level in (0, 1) and that has a
    second positional argument is an old-order call (the first parameter of
    the new order is a count, never a fraction): the two are swapped, a third
    positional argument moves to ``keyword``, and a DeprecationWarning says
    ``new_call``.
    """

    def decorate(func: F) -> F:
        @functools.wraps(func)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            if len(args) >= 2 and _is_level(args[0]) and not _is_level(args[1]):
                alpha, first, *rest = args
                if rest:
                    if keyword is None or len(rest) > 1 or keyword in kwargs:
                        raise TypeError(f"{func.__name__}() got too many positional arguments")
                    kwargs[keyword] = rest[0]
                warn(f"{func.__name__}(alpha, ...) is now {new_call}")
                args = (first, alpha)
            return func(*args, **kwargs)

        return wrapper  # type: ignore[return-value]

    return decorate
