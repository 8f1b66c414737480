"""Namespaces through bubblewrap (``bwrap``): the fork server in a root of its own, offline.

The grader starts its fork server (or, in spawn mode, each child) under ``bwrap``. Inside:

- a mount namespace whose root holds only read-only binds of the Python installation, the
  course package and the system libraries, plus the run folder (the children's temporary
  folders) read-write; ``/proc`` of its own and a minimal ``/dev``. The course folders, the
  submissions, the output folder, the home folder and the rest of the file system do not
  exist there: no path, descriptor or ``/proc`` trick can name them;
- a network namespace with nothing but a loopback interface, and new PID, IPC and UTS
  namespaces (the grader's processes are invisible, System V IPC is private);
- run as root, no user namespace: all capabilities dropped except switching to ``nobody``,
  which the fork server does at once (:mod:`course.grading.sandbox.isolation.privileges`); run as an
  ordinary user, a user namespace that maps that user.

bubblewrap is the well-kept tool that Flatpak builds on (Debian package ``bubblewrap``).
"""

from __future__ import annotations

import functools
import os
import shutil
import subprocess

__all__ = ["bwrap_command", "find_bwrap"]


def _namespace_flags(as_root: bool) -> list[str]:
    flags = [
        "--unshare-net",
        "--unshare-pid",
        "--unshare-ipc",
        "--unshare-uts",
        "--unshare-cgroup-try",
        "--die-with-parent",
        "--new-session",
    ]
    if as_root:
        # no user namespace: keep only what switching to nobody needs, then nothing
        flags += ["--cap-drop", "ALL", "--cap-add", "CAP_SETUID", "--cap-add", "CAP_SETGID"]
    else:
        flags += ["--unshare-user"]
    return flags


def _ancestors(paths: list[str]) -> list[str]:
    out: list[str] = []
    for p in paths:
        parts = p.strip("/").split("/")[:-1]
        for i in range(1, len(parts) + 1):
            a = "/" + "/".join(parts[:i])
            if a not in out:
                out.append(a)
    return out


def bwrap_command(
    bwrap: str,
    read_only: list[str],
    writable: list[str],
    chdir: str,
    as_root: bool | None = None,
) -> list[str]:
    """The ``bwrap`` arguments (before the command) for a root with exactly these binds."""
    as_root = (os.geteuid() == 0) if as_root is None else as_root
    cmd = [bwrap, *_namespace_flags(as_root)]
    targets = [*read_only, *writable]
    for folder in _ancestors(targets):
        if folder not in targets:
            cmd += ["--perms", "0755", "--dir", folder]  # traversable by nobody
    for p in read_only:
        cmd += ["--ro-bind", p, p]
    for p in writable:
        cmd += ["--bind", p, p]
    cmd += ["--proc", "/proc", "--dev", "/dev", "--chdir", chdir, "--"]
    return cmd


@functools.lru_cache(maxsize=1)
def find_bwrap() -> str | None:
    """The path of a ``bwrap`` that works here (it runs ``true`` in the namespaces), or None."""
    path = shutil.which("bwrap")
    if path is None:
        return None
    true = shutil.which("true") or "/bin/true"
    roots = [p for p in ("/usr", "/lib", "/lib64", "/bin") if os.path.exists(p)]
    try:
        result = subprocess.run(
            bwrap_command(path, roots, [], "/") + [true],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            timeout=20,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return path if result.returncode == 0 else None
