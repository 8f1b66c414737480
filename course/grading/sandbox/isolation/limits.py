"""Resource limits of a grading child (``setrlimit``), set before student code runs.

Memory is limited as address space (``RLIMIT_AS``, a budget on top of what the warm process has
already mapped), CPU time per process, the size of any one file, the number of open
descriptors (so the pipes a child makes hold at most a few megabytes: seccomp keeps each at its
default size), and no core files. The total of a child's files is watched by the parent
(:class:`~course.grading.sandbox.parent.ChildHandle`). The seccomp
filter (:mod:`course.grading.sandbox.isolation.seccomp`) keeps the child from raising them again.
"""

from __future__ import annotations

import contextlib
import os
import resource

__all__ = ["set_limits"]


def _vm_size() -> int:
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError):
        return 0


def set_limits(limits: dict) -> None:
    """Apply resource limits; the memory limit is a budget on top of what is already mapped."""

    def lim(res, value):
        value = int(value)
        with contextlib.suppress(ValueError, OSError):
            resource.setrlimit(res, (value, value))

    if limits.get("memory_mb"):
        lim(resource.RLIMIT_AS, _vm_size() + int(limits["memory_mb"]) * 1024 * 1024)
    if limits.get("cpu_seconds"):
        lim(resource.RLIMIT_CPU, max(1, int(limits["cpu_seconds"])))
    if limits.get("file_mb"):
        lim(resource.RLIMIT_FSIZE, int(limits["file_mb"]) * 1024 * 1024)
    if limits.get("open_files"):  # bounds what pipes can hold (seccomp keeps their size)
        lim(resource.RLIMIT_NOFILE, int(limits["open_files"]))
    lim(resource.RLIMIT_CORE, 0)
    if limits.get("nproc") is not None:
        lim(resource.RLIMIT_NPROC, limits["nproc"])
