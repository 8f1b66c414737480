"""What a grading child may read: the Python installation, system libraries, the course's data.

Shared by the two file-system layers: bubblewrap mounts :func:`mount_paths` read-only into an
otherwise empty root, and Landlock allows reading beneath :func:`landlock_paths` only. Neither
list contains the course's sources (they are imported before student code runs, so a child
cannot re-import a library module to get around :mod:`course.grading.tripwire`), the course
folders (solutions, submissions, output), the home folder or the working directory.
"""

from __future__ import annotations

import contextlib
import os
import site
import sys
import sysconfig
from pathlib import Path

__all__ = ["course_package_dir", "landlock_paths", "mount_paths", "python_paths"]

#: System folders that hold shared libraries and the loader's cache (read-only).
SYSTEM_PATHS = (
    "/usr/lib",
    "/usr/lib64",
    "/usr/lib32",
    "/usr/local/lib",
    "/lib",
    "/lib64",
    "/lib32",
    "/etc/ld.so.cache",
    "/etc/localtime",
    "/usr/share/zoneinfo",
)
#: Devices a child may open (read and write).
DEVICES = ("/dev/null", "/dev/zero", "/dev/urandom", "/dev/random")


def course_package_dir() -> Path:
    """The folder of the installed ``course`` package (inside a clone for ``pip install -e``)."""
    import course

    return Path(course.__file__).resolve().parent


def python_paths() -> list[str]:
    """The Python installation: interpreter prefixes, standard library and site-packages."""
    paths = {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix}
    for key in ("stdlib", "platstdlib", "purelib", "platlib"):
        value = sysconfig.get_paths().get(key)
        if value:
            paths.add(value)
    with contextlib.suppress(AttributeError):  # old virtualenv
        paths.update(site.getsitepackages())
    for entry in sys.path:
        # site-packages-like entries only: never the working directory or a PYTHONPATH folder
        if entry and Path(entry).name in ("site-packages", "dist-packages", "lib-dynload"):
            paths.add(entry)
    out = []
    for p in sorted(paths):
        real = os.path.realpath(p)
        if os.path.exists(real) and real not in out:
            out.append(real)
    return _outermost(out)


def _outermost(paths: list[str]) -> list[str]:
    """Drop paths that lie beneath another path of the list."""
    paths = sorted(set(paths))
    out: list[str] = []
    for p in paths:
        if not any(p == q or p.startswith(q.rstrip("/") + "/") for q in out):
            out.append(p)
    return out


def _beneath(path: str, folder: str) -> bool:
    return path == folder or path.startswith(folder.rstrip("/") + "/")


def _without(roots: list[str], excluded: list[str]) -> list[str]:
    """``roots`` with every ``excluded`` folder cut out: a root that contains an excluded folder
    is replaced by its other entries, recursively along the way down."""
    out: list[str] = []
    for root in roots:
        if root in excluded:
            continue
        inside = [x for x in excluded if _beneath(x, root)]
        if not inside:
            out.append(root)
            continue
        try:
            entries = sorted(os.listdir(root))
        except OSError:
            continue
        out.extend(_without([os.path.join(root, e) for e in entries], inside))
    return out


def mount_paths(protected: list[str]) -> list[str]:
    """Read-only bind mounts of the bubblewrap root: Python, the course package, system libs.

    The course package stays whole (the fork server imports it inside the mount namespace);
    anything under ``protected`` (course folders, submissions, output, home) is cut out, should
    a Python folder contain one.
    """
    protected = [os.path.realpath(p) for p in protected]
    roots = _outermost([*python_paths(), str(course_package_dir()), "/usr", "/lib", "/lib64"])
    roots += [p for p in ("/etc/ld.so.cache", "/etc/localtime") if os.path.exists(p)]
    return _without([r for r in roots if os.path.exists(r)], protected)


def landlock_paths(protected: list[str]) -> list[str]:
    """Folders and files a child may read under Landlock: Python and system libraries, the
    course's data folder; not the course's sources, nor anything ``protected``."""
    package = str(course_package_dir())
    excluded = [os.path.realpath(p) for p in protected] + [package]
    roots = _outermost([*python_paths(), *(p for p in SYSTEM_PATHS if os.path.exists(p))])
    allowed = _without(roots, excluded)
    data = os.path.join(package, "data")
    if os.path.isdir(data):
        allowed.append(data)
    return allowed
