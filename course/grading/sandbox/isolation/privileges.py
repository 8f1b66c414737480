"""An unprivileged grader: grading processes started as root switch to an unprivileged user.

Root ignores file permissions and the process-count limit, so a child that stays root can read
whatever the other layers leave reachable. When ``course grade`` runs as root, the fork server
(inside bubblewrap) or each child (without it) switches to ``nobody`` — all of its user and
group IDs, no supplementary groups — before any student code exists; from then on the kernel
applies ordinary file permissions, and the seccomp filter (which sets ``no_new_privs``) keeps it
from ever regaining privileges. A child that must stay root (``nobody`` cannot read the Python
installation) drops every capability and sets ``no_new_privs`` (:func:`drop_capabilities`);
what the owner of root's files may still do to them without a capability (chmod, utime,
extended attributes, chattr flags) the seccomp filter refuses.
Run without root, the grader keeps its own user.
"""

from __future__ import annotations

import os
import sys

__all__ = ["Identity", "drop", "drop_capabilities", "target"]

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


_PR_CAPBSET_DROP = 24
_PR_SET_NO_NEW_PRIVS = 38
_PR_CAP_AMBIENT, _PR_CAP_AMBIENT_CLEAR_ALL = 47, 4
_CAP_VERSION_3 = 0x20080522


def drop_capabilities() -> None:
    """Drop every capability (bounding, ambient, effective, permitted, inheritable) and set
    ``no_new_privs``: for a child that stays root (``nobody`` cannot read the Python
    installation), so it cannot chown, set immutable flags, renice others, take a real-time
    policy or set the host name (changing the metadata of files it owns, root's, is left to
    the seccomp filter). Raise OSError if the kernel refuses."""
    import ctypes

    libc = ctypes.CDLL(None, use_errno=True)
    last = 40
    try:
        with open("/proc/sys/kernel/cap_last_cap") as f:
            last = int(f.read())
    except (OSError, ValueError):
        pass
    for cap in range(last + 1):
        if libc.prctl(_PR_CAPBSET_DROP, cap, 0, 0, 0) != 0 and ctypes.get_errno() != 22:
            raise OSError(
                ctypes.get_errno(), f"could not drop capability {cap} from the bounding set"
            )
    libc.prctl(_PR_CAP_AMBIENT, _PR_CAP_AMBIENT_CLEAR_ALL, 0, 0, 0)  # EINVAL on old kernels
    header = (ctypes.c_uint32 * 2)(_CAP_VERSION_3, 0)
    data = (ctypes.c_uint32 * 6)()  # two {effective, permitted, inheritable}: all zero
    if libc.capset(header, data) != 0:
        raise OSError(ctypes.get_errno(), "could not clear the capability sets")
    if libc.prctl(_PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "could not set no_new_privs")
