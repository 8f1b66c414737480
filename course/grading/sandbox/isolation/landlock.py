"""Landlock: the kernel's allow-list of what one process may open, bind and signal (Linux ≥ 5.13).

A grading child calls :func:`confine` right before student code runs. From then on the kernel
lets it read only beneath the paths it was given (the Python installation, the course's data)
and write only beneath its own temporary folder, whatever path, ``dir_fd``, symlink, hard link
or ``/proc/<pid>/cwd`` it goes through: Landlock checks where the opened file really is. With
ABI 4 or newer it may neither bind nor connect TCP sockets, with ABI 6 or newer it may not
connect to abstract UNIX sockets or signal processes outside its own domain (other students,
the grader). The restriction cannot be lifted and is inherited by any thread.

Why the ctypes calls are written here rather than taken from a library: the ``landlock`` package
on PyPI (1.0.0.dev5) covers file-system rights only, and ``py-landlock`` (0.1.1, alpha) resolves
every path again in each process; we need network rules, scopes and rules built from
descriptors opened once in the warm fork server. The three system calls are small and stable
(``landlock(7)``); this module holds all of them.

What Landlock does not govern: ``stat`` and ``readlink`` (a child can learn that a path exists,
not read or list it), files opened before :func:`confine`, connecting to named UNIX sockets, and
UDP. The seccomp filter refuses sockets altogether, and the namespaces of bubblewrap, when
available, hide the rest of the file system (:mod:`course.grading.sandbox.isolation`).
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import platform
import stat

__all__ = ["Policy", "abi_version", "confine"]

_SYS_CREATE_RULESET, _SYS_ADD_RULE, _SYS_RESTRICT_SELF = 444, 445, 446  # all architectures
_CREATE_RULESET_VERSION = 1 << 0
_RULE_PATH_BENEATH = 1
_PR_SET_NO_NEW_PRIVS = 38

# file-system rights (landlock.h), with the ABI that introduced them
EXECUTE = 1 << 0
WRITE_FILE = 1 << 1
READ_FILE = 1 << 2
READ_DIR = 1 << 3
REMOVE_DIR = 1 << 4
REMOVE_FILE = 1 << 5
MAKE_CHAR = 1 << 6
MAKE_DIR = 1 << 7
MAKE_REG = 1 << 8
MAKE_SOCK = 1 << 9
MAKE_FIFO = 1 << 10
MAKE_BLOCK = 1 << 11
MAKE_SYM = 1 << 12
REFER = 1 << 13  # ABI 2
TRUNCATE = 1 << 14  # ABI 3
IOCTL_DEV = 1 << 15  # ABI 5
# network rights (ABI 4) and scopes (ABI 6)
NET_BIND_TCP = 1 << 0
NET_CONNECT_TCP = 1 << 1
SCOPE_ABSTRACT_UNIX_SOCKET = 1 << 0
SCOPE_SIGNAL = 1 << 1

_FILE_RIGHTS = EXECUTE | WRITE_FILE | READ_FILE | TRUNCATE | IOCTL_DEV


class _RulesetAttr(ctypes.Structure):
    _fields_ = [
        ("handled_access_fs", ctypes.c_uint64),
        ("handled_access_net", ctypes.c_uint64),
        ("scoped", ctypes.c_uint64),
    ]


class _PathBeneathAttr(ctypes.Structure):
    _pack_ = 1  # packed in the kernel's header
    _fields_ = [("allowed_access", ctypes.c_uint64), ("parent_fd", ctypes.c_int32)]


_libc = None


def _syscall():
    global _libc
    if _libc is None:
        _libc = ctypes.CDLL(None, use_errno=True)
        _libc.syscall.restype = ctypes.c_long
    return _libc


def abi_version() -> int:
    """The Landlock ABI version the running kernel offers (0: none, or not Linux)."""
    if platform.system() != "Linux":
        return 0
    try:
        libc = _syscall()
    except OSError:
        return 0
    version = libc.syscall(_SYS_CREATE_RULESET, None, ctypes.c_size_t(0), _CREATE_RULESET_VERSION)
    return max(0, int(version))


def handled_fs(abi: int) -> int:
    """Every file-system right the given ABI knows: what a ruleset of that ABI restricts."""
    rights = (1 << 13) - 1  # EXECUTE .. MAKE_SYM (ABI 1)
    if abi >= 2:
        rights |= REFER
    if abi >= 3:
        rights |= TRUNCATE
    if abi >= 5:
        rights |= IOCTL_DEV
    return rights


#: Rights beneath a folder the child may only read.
READ_ONLY = READ_FILE | READ_DIR
#: Rights beneath the child's own temporary folder: everything but executing.
READ_WRITE = (
    WRITE_FILE
    | READ_FILE
    | READ_DIR
    | REMOVE_DIR
    | REMOVE_FILE
    | MAKE_DIR
    | MAKE_REG
    | MAKE_SOCK
    | MAKE_FIFO
    | MAKE_SYM
    | REFER
    | TRUNCATE
)
#: Rights on a device file such as /dev/null.
DEVICE = READ_FILE | WRITE_FILE | TRUNCATE | IOCTL_DEV


class Policy:
    """What one child may touch: descriptors (``O_PATH``) of allowed paths and their rights.

    Build it in the warm parent with :meth:`allow` (paths are opened once there, so every child
    reuses the descriptors), then call :func:`confine` in each child.
    """

    def __init__(self) -> None:
        self.rules: list[tuple[int, int, bool]] = []  # (fd, rights, is_dir)

    def allow(self, path: str, rights: int) -> bool:
        """Allow ``rights`` beneath ``path``; False (and nothing allowed) when it does not exist."""
        try:
            fd = os.open(path, os.O_PATH | os.O_CLOEXEC)
        except OSError:
            return False
        is_dir = stat.S_ISDIR(os.fstat(fd).st_mode)
        self.rules.append((fd, rights, is_dir))
        return True

    def fds(self) -> list[int]:
        return [fd for fd, _, _ in self.rules]

    def close(self) -> None:
        for fd, _, _ in self.rules:
            with contextlib.suppress(OSError):
                os.close(fd)
        self.rules = []


def _check(result: int, what: str) -> int:
    if result < 0:
        err = ctypes.get_errno()
        raise OSError(err, f"landlock {what}: {os.strerror(err)}")
    return result


def confine(policy: Policy, abi: int | None = None) -> int:
    """Restrict the calling process (irreversibly) to ``policy``; return the ABI used (0: none).

    Sets ``no_new_privs`` (required without CAP_SYS_ADMIN). Raises OSError when the kernel
    offers Landlock but refuses the ruleset (a bug, never silently ignored).
    """
    abi = abi_version() if abi is None else abi
    if abi < 1:
        return 0
    libc = _syscall()
    fs = handled_fs(abi)
    attr = _RulesetAttr(
        fs, NET_BIND_TCP | NET_CONNECT_TCP, SCOPE_ABSTRACT_UNIX_SOCKET | SCOPE_SIGNAL
    )
    size = 8 if abi < 4 else (16 if abi < 6 else 24)  # older kernels reject the newer fields
    ruleset = _check(
        libc.syscall(_SYS_CREATE_RULESET, ctypes.byref(attr), ctypes.c_size_t(size), 0),
        "create_ruleset",
    )
    try:
        for fd, rights, is_dir in policy.rules:
            allowed = (rights if is_dir else rights & _FILE_RIGHTS) & fs
            if not allowed:
                continue
            rule = _PathBeneathAttr(allowed, fd)
            _check(
                libc.syscall(_SYS_ADD_RULE, ruleset, _RULE_PATH_BENEATH, ctypes.byref(rule), 0),
                "add_rule",
            )
        _check(libc.prctl(_PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0), "no_new_privs")
        _check(libc.syscall(_SYS_RESTRICT_SELF, ruleset, 0), "restrict_self")
    finally:
        os.close(ruleset)
    return abi
