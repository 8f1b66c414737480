"""The seccomp-BPF filter of a grading child (Linux x86-64 and aarch64).

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
- closing or replacing one pinned descriptor (``close``, ``dup2``/``dup3``, ``close_range``):
  the pipe on which forbidden library calls are reported to the grader
  (:mod:`course.grading.tripwire`).

This is the layer that still holds when the Python audit hook is bypassed (for instance through
``_posixsubprocess`` or ctypes) and when the grader runs as root, where ``RLIMIT_NPROC`` is not
enforced. Files are Landlock's and the namespaces' business (:mod:`course.grading.sandbox.isolation`).
"""

from __future__ import annotations

import ctypes
import os
import platform
import struct

__all__ = ["available", "die_with_parent", "install"]

_LD_W_ABS = 0x20
_JEQ_K = 0x15
_JGT_K = 0x25
_JGE_K = 0x35
_JSET_K = 0x45
_RET_K = 0x06

_RET_ALLOW = 0x7FFF0000
_RET_EPERM = 0x00050000 | 1
_RET_ENOSYS = 0x00050000 | 38

_CLONE_THREAD = 0x00010000
_PR_SET_NO_NEW_PRIVS = 38
_PR_SET_SECCOMP = 22
_SECCOMP_MODE_FILTER = 2

# offsets in struct seccomp_data: nr, arch, then 64-bit args from 16 (low words first)
_NR, _ARCH, _ARG0, _ARG1, _ARG2 = 0, 4, 16, 24, 32

#: Refused outright with EPERM (names missing on an architecture are skipped).
_DENIED = (
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
)

# (audit arch, syscall numbers); fork/vfork/dup2 do not exist on aarch64.
# fmt: off
_ARCHES = {
    "x86_64": (
        0xC000003E,
        dict(
            fork=57,
            vfork=58,
            execve=59,
            execveat=322,
            clone=56,
            clone3=435,
            kill=62,
            tkill=200,
            tgkill=234,
            ptrace=101,
            setrlimit=160,
            prlimit64=302,
            process_vm_readv=310,
            process_vm_writev=311,
            pidfd_getfd=438,
            socket=41,
            socketpair=53,
            io_uring_setup=425,
            io_uring_enter=426,
            io_uring_register=427,
            unshare=272,
            setns=308,
            mount=165,
            umount2=166,
            pivot_root=155,
            chroot=161,
            move_mount=429,
            open_tree=428,
            fsopen=430,
            fsconfig=431,
            fsmount=432,
            fspick=433,
            mount_setattr=442,
            bpf=321,
            userfaultfd=323,
            perf_event_open=298,
            keyctl=250,
            add_key=248,
            request_key=249,
            open_by_handle_at=304,
            name_to_handle_at=303,
            kexec_load=246,
            kexec_file_load=320,
            init_module=175,
            finit_module=313,
            delete_module=176,
            close=3,
            dup2=33,
            dup3=292,
            close_range=436,
        ),
    ),
    "aarch64": (
        0xC00000B7,
        dict(
            execve=221,
            execveat=281,
            clone=220,
            clone3=435,
            kill=129,
            tkill=130,
            tgkill=131,
            ptrace=117,
            setrlimit=164,
            prlimit64=261,
            process_vm_readv=270,
            process_vm_writev=271,
            pidfd_getfd=438,
            socket=198,
            socketpair=199,
            io_uring_setup=425,
            io_uring_enter=426,
            io_uring_register=427,
            unshare=97,
            setns=268,
            mount=40,
            umount2=39,
            pivot_root=41,
            chroot=51,
            move_mount=429,
            open_tree=428,
            fsopen=430,
            fsconfig=431,
            fsmount=432,
            fspick=433,
            mount_setattr=442,
            bpf=280,
            userfaultfd=282,
            perf_event_open=241,
            keyctl=219,
            add_key=217,
            request_key=218,
            open_by_handle_at=265,
            name_to_handle_at=264,
            kexec_load=104,
            kexec_file_load=294,
            init_module=105,
            finit_module=273,
            delete_module=106,
            close=57,
            dup3=24,
            close_range=436,
        ),
    ),
}
# fmt: on


def available() -> bool:
    """Whether this platform has a filter here (Linux on x86-64 or aarch64)."""
    return os.name == "posix" and platform.system() == "Linux" and platform.machine() in _ARCHES


def _program(pid: int, pinned_fd: int | None = None) -> tuple[bytes, int]:
    arch, nr = _ARCHES[platform.machine()]
    code: list = []  # entries: [op, jt_label, jf_label, k] with labels resolved below
    labels: dict[str, int] = {}

    def emit(op, k=0, jt=None, jf=None):
        code.append([op, jt, jf, k])

    def label(name):
        labels[name] = len(code)

    emit(_LD_W_ABS, _ARCH)
    emit(_JEQ_K, arch, jt=None, jf="deny")
    emit(_LD_W_ABS, _NR)
    if platform.machine() == "x86_64":
        emit(_JGE_K, 0x40000000, jt="deny", jf=None)  # x32 ABI syscalls
    for name in _DENIED:
        if name in nr:
            emit(_JEQ_K, nr[name], jt="deny", jf=None)
    emit(_JEQ_K, nr["clone3"], jt="enosys", jf=None)
    emit(_JEQ_K, nr["clone"], jt="clone", jf=None)
    for name in ("kill", "tkill", "tgkill"):
        emit(_JEQ_K, nr[name], jt="signal", jf=None)
    emit(_JEQ_K, nr["prlimit64"], jt="prlimit", jf=None)
    if pinned_fd is not None:
        emit(_JEQ_K, nr["close"], jt="close", jf=None)
        if "dup2" in nr:
            emit(_JEQ_K, nr["dup2"], jt="dup", jf=None)
        emit(_JEQ_K, nr["dup3"], jt="dup", jf=None)
        emit(_JEQ_K, nr["close_range"], jt="close_range", jf=None)
    emit(_RET_K, _RET_ALLOW)
    label("clone")
    emit(_LD_W_ABS, _ARG0)  # clone flags
    emit(_JSET_K, _CLONE_THREAD, jt="allow", jf="deny")
    label("signal")
    emit(_LD_W_ABS, _ARG0)  # target pid / tgid
    emit(_JEQ_K, pid, jt="allow", jf="deny")
    label("prlimit")
    emit(_LD_W_ABS, _ARG2)  # new-limit pointer, low word
    emit(_JEQ_K, 0, jt=None, jf="deny")
    emit(_LD_W_ABS, _ARG2 + 4)  # high word
    emit(_JEQ_K, 0, jt="allow", jf="deny")
    if pinned_fd is not None:
        label("close")
        emit(_LD_W_ABS, _ARG0)  # the kernel reads an int: the low word
        emit(_JEQ_K, pinned_fd, jt="deny", jf="allow")
        label("dup")
        emit(_LD_W_ABS, _ARG1)  # newfd
        emit(_JEQ_K, pinned_fd, jt="deny", jf="allow")
        label("close_range")
        emit(_LD_W_ABS, _ARG0)  # first
        emit(_JGT_K, pinned_fd, jt="allow", jf=None)
        emit(_LD_W_ABS, _ARG1)  # last
        emit(_JGE_K, pinned_fd, jt="deny", jf="allow")
    label("allow")
    emit(_RET_K, _RET_ALLOW)
    label("deny")
    emit(_RET_K, _RET_EPERM)
    label("enosys")
    emit(_RET_K, _RET_ENOSYS)

    packed = b""
    for i, (op, jt, jf, k) in enumerate(code):
        offsets = []
        for target in (jt, jf):
            off = 0 if target is None else labels[target] - (i + 1)
            if not 0 <= off < 256:
                raise RuntimeError("seccomp program jump out of range")
            offsets.append(off)
        packed += struct.pack("=HBBI", op, offsets[0], offsets[1], k & 0xFFFFFFFF)
    return packed, len(code)


def install(pinned_fd: int | None = None) -> bool:
    """Install the filter in the calling process (irreversible). Returns False if unavailable.

    ``pinned_fd``: a descriptor the process may then neither close nor replace.
    """
    if not available():
        return False
    libc = ctypes.CDLL(None, use_errno=True)
    filters, count = _program(os.getpid(), pinned_fd)
    buf = ctypes.create_string_buffer(filters, len(filters))

    class _SockFprog(ctypes.Structure):
        _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]

    prog = _SockFprog(count, ctypes.cast(buf, ctypes.c_void_p))
    if libc.prctl(_PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
        return False
    return libc.prctl(_PR_SET_SECCOMP, _SECCOMP_MODE_FILTER, ctypes.byref(prog), 0, 0) == 0


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
