"""The seccomp filter of a grading child, written as libseccomp rules.

Installed in the child right before student code runs, it makes the KERNEL refuse:

- creating processes: ``fork``, ``vfork``, ``clone`` without ``CLONE_THREAD`` (threads are
  still allowed) and ``clone3`` (answered with ENOSYS so that glibc falls back to ``clone``),
- ``execve``/``execveat``, ``ptrace``, ``process_vm_readv``/``writev`` and ``pidfd_getfd``
  (reading another process's memory or stealing its descriptors, e.g. the grader's),
- ``kill``/``tkill``/``tgkill`` aimed at any process other than the child itself,
- raising resource limits (``setrlimit``; ``prlimit64`` with a new limit),
- every socket: ``socket`` and ``socketpair`` (so no descriptor is ever created that an audit
  hook would have to clean up), and ``io_uring`` (which could open sockets past this filter),
- leaving or rebuilding its confinement: ``unshare``, ``setns``, mounts, ``chroot``,
  ``pivot_root``, ``bpf``, ``userfaultfd``, ``perf_event_open``, kernel keys and modules,
  ``open_by_handle_at``,
- changing the metadata of any file: ``chmod``, ``chown`` and ``utime`` in every form (by path,
  descriptor or ``dir_fd``), extended attributes (``setxattr``/``removexattr`` and kin) and
  the inode flags of ``chattr`` (``FS_IOC_SETFLAGS``, ``FS_IOC_FSSETXATTR``): Landlock has no
  right for metadata, so without this a child could change any file its user owns that it can
  reach by name (a root child: root-owned host files; a child of an ordinary grader: that
  user's files), even where it may neither read nor write it,
- closing or replacing one pinned descriptor (``close``, ``dup2``/``dup3``, ``close_range``):
  the pipe on which forbidden library calls are reported to the grader
  (:mod:`course.grading.tripwire`),
- system calls of another architecture (i386 calls on x86-64, x32 calls),
- memory that the address-space limit would not count: ``memfd_create`` and ``memfd_secret``
  (answered ENOMEM, "out of memory") and growing a pipe's buffer (``fcntl`` F_SETPIPE_SZ).

Every refusal is the error EPERM (ENOSYS for ``clone3``, ENOMEM for anonymous files); nothing
is killed.

This is the layer that still holds when the Python audit hook is bypassed (for instance through
``_posixsubprocess`` or ctypes) and when the grader runs as root, where ``RLIMIT_NPROC`` is not
enforced. Files are Landlock's and the namespaces' business (:mod:`course.grading.sandbox.isolation`).

The rules are handed to libseccomp (Debian's ``libseccomp2``, present wherever systemd is),
which keeps the system-call numbers of every architecture and compiles the BPF program, the
architecture checks included. The binding is the handful of ctypes declarations below (five
functions of libseccomp's stable C API), not a Python package: Debian's ``python3-seccomp``
is built for Debian's own Python only, and ``pyseccomp`` (last released in 2021) would be a
dependency for instructors to install for those five functions, and looks the library up
with ``ctypes.util.find_library``, which starts ``ldconfig`` in a subprocess at import.
``libseccomp.so.2`` loads by its stable name through the loader's cache. A machine without
libseccomp grades without this layer, and
:meth:`~course.grading.sandbox.isolation.Isolation.describe` says so.

Arguments are compared as the kernel reads them: a descriptor or a process ID is a 32-bit int,
so where a refusal depends on one, its low 32 bits decide (``MASKED_EQ`` with ``0xFFFFFFFF``),
or a rule errs on the side of refusing (a 64-bit value with stray high bits).
"""

from __future__ import annotations

import ctypes
import errno
import functools
import os
import platform

__all__ = [
    "DENIED",
    "IF_KNOWN",
    "METADATA",
    "OUT_OF_MEMORY",
    "available",
    "die_with_parent",
    "export_pfc",
    "install",
    "rules",
]

#: Refused outright with EPERM (a name that does not exist on an architecture, e.g. ``fork``
#: on aarch64, is known to libseccomp and simply matches nothing there).
DENIED = (
    "fork",
    "vfork",
    "execve",
    "execveat",
    "ptrace",
    "setrlimit",
    "process_vm_readv",
    "process_vm_writev",
    "pidfd_getfd",
    "socket",
    "socketpair",
    "io_uring_setup",
    "io_uring_enter",
    "io_uring_register",
    "unshare",
    "setns",
    "mount",
    "umount2",
    "pivot_root",
    "chroot",
    "move_mount",
    "open_tree",
    "fsopen",
    "fsconfig",
    "fsmount",
    "fspick",
    "mount_setattr",
    "bpf",
    "userfaultfd",
    "perf_event_open",
    "keyctl",
    "add_key",
    "request_key",
    "open_by_handle_at",
    "name_to_handle_at",
    "kexec_load",
    "kexec_file_load",
    "init_module",
    "finit_module",
    "delete_module",
    # System V IPC: its objects live outside the child's memory limit and outlive it (without
    # bubblewrap's IPC namespace, even the run); POSIX shared memory is a file in its folder
    "shmget",
    "shmat",
    "shmctl",
    "msgget",
    "msgsnd",
    "msgrcv",
    "msgctl",
    "semget",
    "semop",
    "semtimedop",
    "semctl",
    # real-time and deadline scheduling (sched_setattr), and the host's names
    "sched_setattr",
    "sethostname",
    "setdomainname",
)
#: Answered "out of memory" (ENOMEM): an anonymous file's pages are written, not mapped, so the
#: address-space limit does not count them (issue 36: 1,280 MB held in 20 memfds under a
#: 1,024 MB limit). Nothing numpy, scipy, matplotlib or IPython does in a child uses them.
OUT_OF_MEMORY = ("memfd_create",)
#: As :data:`OUT_OF_MEMORY` where this libseccomp knows the name.
OUT_OF_MEMORY_IF_KNOWN = ("memfd_secret",)
#: ``fcntl``'s F_SETPIPE_SZ: a pipe keeps its default buffer (16 pages), so the pipes a child
#: can open (its descriptor limit) hold a few megabytes at most, outside its address space.
_F_SETPIPE_SZ = 1031
#: File metadata, refused outright with EPERM for every child (also in its own folder): Landlock
#: has no right for it, and the owner of a file (root for root's files, when a child has to stay
#: root) may change it without any capability.
METADATA = (
    "chmod",
    "fchmod",
    "fchmodat",
    "chown",
    "fchown",
    "lchown",
    "fchownat",
    "chown32",  # the 16-bit-uid architectures' (32-bit ARM, i386) names
    "fchown32",
    "lchown32",
    "utime",
    "utimes",
    "futimesat",
    "utimensat",
    "utimensat_time64",
    "setxattr",
    "lsetxattr",
    "fsetxattr",
    "removexattr",
    "lremovexattr",
    "fremovexattr",
)
#: Refused like :data:`METADATA` where this libseccomp knows the name (calls newer than its
#: release; one it does not know stays open: libseccomp 2.5.4 knows ``fchmodat2`` but not
#: the ``*xattrat`` calls of Linux 6.13 nor ``file_setattr`` of 6.17).
IF_KNOWN = (
    "fchmodat2",
    "setxattrat",
    "removexattrat",
    "file_setattr",
    *OUT_OF_MEMORY_IF_KNOWN,
)
#: Refused depending on their arguments (see :func:`rules`).
_CONDITIONAL = (
    "clone",
    "clone3",
    "kill",
    "tkill",
    "tgkill",
    "prlimit64",
    "close",
    "dup2",
    "dup3",
    "close_range",
    "sched_setaffinity",
    "sched_setscheduler",
    "sched_setparam",
    "setpriority",
    "ioprio_set",
    "ioctl",
    "fcntl",
)

# libseccomp's ABI (seccomp.h of libseccomp 2.x)
_ACT_ALLOW = 0x7FFF0000
_ACT_ERRNO = 0x00050000
_ATTR_ACT_BADARCH = 2
_NE, _LE, _GE, _GT, _MASKED_EQ = 1, 3, 5, 6, 7
_SIGN = 0x80000000  # the sign bit of an int argument
_NR_SCMP_ERROR = -1  # a name libseccomp does not know

_CLONE_THREAD = 0x00010000
_LOW_WORD = 0xFFFFFFFF  # the kernel reads an int: the low 32 bits of the register
# clone's flags are its first argument, except on s390 (where they come second)
_CLONE_FLAGS = 1 if platform.machine().startswith("s390") else 0


def _iow(kind: str, number: int, size: int) -> int:
    """The Linux ioctl request ``_IOW(kind, number, size)`` of this machine's architecture."""
    if platform.machine().startswith(("ppc", "powerpc", "mips", "sparc", "alpha")):
        return (4 << 29) | (size << 16) | (ord(kind) << 8) | number  # _IOC_WRITE is 4 there
    return (1 << 30) | (size << 16) | (ord(kind) << 8) | number


#: ``chattr``'s requests: FS_IOC_SETFLAGS (a long), FS_IOC32_SETFLAGS (an int) and
#: FS_IOC_FSSETXATTR (a 28-byte struct fsxattr); immutable and append-only need a capability,
#: the other flags (no atime, synchronous, no dump, ...) only the file's owner.
_SET_INODE_FLAGS = (
    _iow("f", 2, ctypes.sizeof(ctypes.c_long)),
    _iow("f", 2, 4),
    _iow("X", 32, 28),
)


class _ArgCmp(ctypes.Structure):
    """``struct scmp_arg_cmp``: argument ``arg`` compared by ``op`` with ``datum_a``/``b``."""

    _fields_ = [
        ("arg", ctypes.c_uint),
        ("op", ctypes.c_int),
        ("datum_a", ctypes.c_uint64),
        ("datum_b", ctypes.c_uint64),
    ]


#: One rule: (action, system call name, argument comparisons (arg, op, datum_a, datum_b)).
Rule = tuple[int, str, tuple[tuple[int, int, int, int], ...]]


@functools.cache
def _library() -> ctypes.CDLL | None:
    """libseccomp, with the signatures used here declared; None where it is missing."""
    if os.name != "posix" or platform.system() != "Linux":
        return None
    try:
        lib = ctypes.CDLL("libseccomp.so.2", use_errno=True)
    except OSError:
        return None
    lib.seccomp_init.argtypes = [ctypes.c_uint32]
    lib.seccomp_init.restype = ctypes.c_void_p
    lib.seccomp_release.argtypes = [ctypes.c_void_p]
    lib.seccomp_release.restype = None
    lib.seccomp_attr_set.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_uint32]
    lib.seccomp_syscall_resolve_name.argtypes = [ctypes.c_char_p]
    lib.seccomp_rule_add_array.argtypes = [
        ctypes.c_void_p,
        ctypes.c_uint32,
        ctypes.c_int,
        ctypes.c_uint,
        ctypes.POINTER(_ArgCmp),
    ]
    lib.seccomp_load.argtypes = [ctypes.c_void_p]
    lib.seccomp_export_pfc.argtypes = [ctypes.c_void_p, ctypes.c_int]
    return lib


def _errno(code: int) -> int:
    return _ACT_ERRNO | (code & 0xFFFF)


def rules(pid: int, pinned_fd: int | None = None) -> list[Rule]:
    """The filter's rules for the process ``pid`` (every call not named is allowed; a name
    of :data:`IF_KNOWN` this libseccomp does not know is left out when the filter is built)."""
    deny = _errno(errno.EPERM)
    out: list[Rule] = [(deny, name, ()) for name in DENIED]
    out += [
        (_errno(errno.ENOSYS), "clone3", ()),  # glibc then falls back to clone
        (deny, "clone", ((_CLONE_FLAGS, _MASKED_EQ, _CLONE_THREAD, 0),)),  # not a thread
        # another process: 64 bits compared, so stray high bits are refused too
        *((deny, name, ((0, _NE, pid, 0),)) for name in ("kill", "tkill", "tgkill")),
        (deny, "prlimit64", ((2, _NE, 0, 0),)),  # a new limit (the pointer is not NULL)
        # scheduling: only the calling thread itself (pid 0), so a child can neither pin nor
        # renice the fork server (every later student would inherit it) nor anyone else, and
        # no real-time policy (a policy other than SCHED_OTHER, 0)
        *((deny, name, ((0, _NE, 0, 0),)) for name in ("sched_setaffinity", "sched_setparam")),
        (deny, "sched_setscheduler", ((0, _NE, 0, 0),)),
        (deny, "sched_setscheduler", ((1, _NE, 0, 0),)),
        (deny, "setpriority", ((0, _NE, 0, 0),)),  # PRIO_PGRP, PRIO_USER: others too
        (deny, "setpriority", ((1, _NE, 0, 0),)),
        (deny, "setpriority", ((2, _MASKED_EQ, _SIGN, _SIGN),)),  # no negative nice (root)
        (deny, "ioprio_set", ((1, _NE, 0, 0),)),
        *(
            (deny, name, ())
            for name in (*METADATA, *IF_KNOWN)
            if name not in OUT_OF_MEMORY_IF_KNOWN
        ),
        *((_errno(errno.ENOMEM), name, ()) for name in (*OUT_OF_MEMORY, *OUT_OF_MEMORY_IF_KNOWN)),
        *(
            (deny, name, ((1, _MASKED_EQ, _LOW_WORD, _F_SETPIPE_SZ),))
            for name in ("fcntl", "fcntl64")
        ),
        # the kernel reads the request as an unsigned int: its low 32 bits decide
        *((deny, "ioctl", ((1, _MASKED_EQ, _LOW_WORD, request),)) for request in _SET_INODE_FLAGS),
    ]
    if pinned_fd is not None:
        pinned = (_MASKED_EQ, _LOW_WORD, pinned_fd)
        out += [
            (deny, "close", ((0, *pinned),)),
            (deny, "dup2", ((1, *pinned),)),  # newfd
            (deny, "dup3", ((1, *pinned),)),
            # close_range(first, last) with first <= pinned <= last; a first with high bits
            # set is read as its low word by the kernel, so it counts as low
            (deny, "close_range", ((0, _LE, pinned_fd, 0), (1, _GE, pinned_fd, 0))),
            (deny, "close_range", ((0, _GT, _LOW_WORD, 0), (1, _GE, pinned_fd, 0))),
        ]
    return out


@functools.cache
def _unknown_names() -> tuple[str, ...]:
    """Names of the policy this libseccomp does not know (an older release than the policy)."""
    lib = _library()
    if lib is None:
        return ()
    return tuple(
        name
        for name in (*DENIED, *METADATA, *OUT_OF_MEMORY, *_CONDITIONAL)
        if lib.seccomp_syscall_resolve_name(name.encode()) == _NR_SCMP_ERROR
    )


def available() -> bool:
    """Whether this machine can install the filter: Linux with a libseccomp that knows every
    system call the policy names."""
    return _library() is not None and not _unknown_names()


def _build(pid: int, pinned_fd: int | None) -> int:
    """A libseccomp filter context holding :func:`rules` (release it with seccomp_release)."""
    lib = _library()
    if lib is None or not available():
        raise OSError("libseccomp is not available")
    ctx = lib.seccomp_init(_ACT_ALLOW)
    if not ctx:
        raise OSError("seccomp_init failed")
    try:
        if lib.seccomp_attr_set(ctx, _ATTR_ACT_BADARCH, _errno(errno.EPERM)) != 0:
            raise OSError("seccomp_attr_set failed")
        for action, name, comparisons in rules(pid, pinned_fd):
            args = (_ArgCmp * max(1, len(comparisons)))(*(_ArgCmp(*c) for c in comparisons))
            number = lib.seccomp_syscall_resolve_name(name.encode())
            if number == _NR_SCMP_ERROR and name in IF_KNOWN:
                continue  # newer than this libseccomp
            code = lib.seccomp_rule_add_array(ctx, action, number, len(comparisons), args)
            if code != 0:
                raise OSError(-code, f"seccomp rule for {name}: {os.strerror(-code)}")
    except BaseException:
        lib.seccomp_release(ctx)
        raise
    return ctx


def export_pfc(pid: int, pinned_fd: int | None = None) -> str:
    """The filter in libseccomp's readable pseudo-filter code (for tests and reviews)."""
    import tempfile

    lib = _library()
    ctx = _build(pid, pinned_fd)
    try:
        with tempfile.TemporaryFile("w+") as f:
            if lib is None or lib.seccomp_export_pfc(ctx, f.fileno()) != 0:
                raise OSError("seccomp_export_pfc failed")
            f.seek(0)
            return f.read()
    finally:
        if lib is not None:
            lib.seccomp_release(ctx)


def install(pinned_fd: int | None = None) -> bool:
    """Install the filter in the calling process (irreversible). Returns False if unavailable.

    ``pinned_fd``: a descriptor the process may then neither close nor replace. libseccomp
    sets ``no_new_privs`` first, as the kernel requires of an unprivileged process.
    """
    if not available():
        return False
    lib = _library()
    assert lib is not None
    ctx = _build(os.getpid(), pinned_fd)
    try:
        return lib.seccomp_load(ctx) == 0
    finally:
        lib.seccomp_release(ctx)


def die_with_parent() -> bool:
    """Ask the kernel to SIGKILL this process when its parent dies (``PR_SET_PDEATHSIG``), so an
    interrupted grader leaves no fork server or student process behind. Linux only."""
    if os.name != "posix" or platform.system() != "Linux":
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(1, 9, 0, 0, 0) == 0  # PR_SET_PDEATHSIG, SIGKILL
    except OSError:
        return False
