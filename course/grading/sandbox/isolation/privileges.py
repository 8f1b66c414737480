"""An unprivileged grader: grading processes started as root switch to an unprivileged user.

Root ignores file permissions and the process-count limit, so a child that stays root can read
whatever the other layers leave reachable. When ``course grade`` runs as root, the fork server
(inside bubblewrap) or each child (without it) switches to ``nobody`` — all of its user and
group IDs, no supplementary groups — before any student code exists; from then on the kernel
applies ordinary file permissions, and the seccomp filter (which sets ``no_new_privs``) keeps it
from ever regaining privileges. Run without root, the grader keeps its own user.
"""

from __future__ import annotations

import os
import sys

__all__ = ["Identity", "drop", "target"]

Identity = tuple[int, int]  # (uid, gid)


def target() -> Identity | None:
    """The (uid, gid) to switch to: ``nobody`` when this process is root, otherwise None."""
    if sys.platform == "win32" or os.geteuid() != 0:
        return None
    try:
        import pwd

        entry = pwd.getpwnam("nobody")
        return entry.pw_uid, entry.pw_gid
    except (ImportError, KeyError):
        return 65534, 65534


def drop(identity: Identity) -> None:
    """Switch every user and group ID to ``identity`` (irreversible); raise OSError if refused."""
    uid, gid = identity
    os.setgroups([])
    os.setresgid(gid, gid, gid)
    os.setresuid(uid, uid, uid)
    if os.getresuid() != (uid, uid, uid) or os.getresgid() != (gid, gid, gid):
        raise OSError("could not switch to an unprivileged user")


def readable_by(identity: Identity, paths: list[str]) -> bool:
    """Whether ``identity`` can read every path (checked in a forked probe that drops first)."""
    pid = os.fork()
    if pid == 0:  # pragma: no cover - child
        code = 1
        try:
            drop(identity)
            ok = all(os.access(p, os.R_OK | (os.X_OK if os.path.isdir(p) else 0)) for p in paths)
            code = 0 if ok else 1
        finally:
            os._exit(code)
    _, status = os.waitpid(pid, 0)
    return os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0
