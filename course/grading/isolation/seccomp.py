"""A small seccomp-BPF filter for grading children (Linux x86-64 and aarch64 only).

Installed in the child right before student code runs, it makes the KERNEL refuse:

- creating processes: ``fork``, ``vfork``, ``clone`` without ``CLONE_THREAD`` (threads are
  still allowed) and ``clone3`` (answered with ENOSYS so that glibc falls back to ``clone``),
- ``execve``/``execveat``, ``ptrace``, ``process_vm_readv``/``writev`` (reading another
  process's memory, e.g. the grader's),
- ``kill``/``tkill``/``tgkill`` aimed at any process other than the child itself,
- raising resource limits (``setrlimit``; ``prlimit64`` with a new limit).

This is the layer that still holds when the Python audit hook is bypassed (for instance through
``_posixsubprocess`` or ctypes) and when the grader runs as root, where ``RLIMIT_NPROC`` is not
enforced. It is a deny-list, not a full sandbox: file access and the network are left to the
audit hook and the resource limits (see :mod:`course.grading.sandbox`).
"""

from __future__ import annotations

import ctypes
import os
import platform
import struct

__all__ = ["available", "die_with_parent", "install"]

_LD_W_ABS = 0x20
_JEQ_K = 0x15
_JSET_K = 0x45
_RET_K = 0x06

_RET_ALLOW = 0x7FFF0000
_RET_EPERM = 0x00050000 | 1
_RET_ENOSYS = 0x00050000 | 38

_CLONE_THREAD = 0x00010000
_PR_SET_NO_NEW_PRIVS = 38
_PR_SET_SECCOMP = 22
_SECCOMP_MODE_FILTER = 2

# (audit arch, syscall numbers); fork/vfork do not exist on aarch64.
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
        ),
    ),
}


def available() -> bool:
    """Whether this platform has a filter here (Linux on x86-64 or aarch64)."""
    return os.name == "posix" and platform.system() == "Linux" and platform.machine() in _ARCHES


def _program(pid: int):
    arch, nr = _ARCHES[platform.machine()]
    code: list = []  # entries: (op, jt_label, jf_label, k) with labels resolved later

    def emit(op, k=0, jt=None, jf=None):
        code.append([op, jt, jf, k])

    emit(_LD_W_ABS, 4)  # seccomp_data.arch
    emit(_JEQ_K, arch, jt=None, jf="deny")
    emit(_LD_W_ABS, 0)  # seccomp_data.nr
    if platform.machine() == "x86_64":
        emit(0x35, 0x40000000, jt="deny", jf=None)  # JGE: x32 ABI syscalls
    for name in (
        "fork",
        "vfork",
        "execve",
        "execveat",
        "ptrace",
        "setrlimit",
        "process_vm_readv",
        "process_vm_writev",
    ):
        if name in nr:
            emit(_JEQ_K, nr[name], jt="deny", jf=None)
    emit(_JEQ_K, nr["clone3"], jt="enosys", jf=None)
    emit(_JEQ_K, nr["clone"], jt="clone", jf=None)
    for name in ("kill", "tkill", "tgkill"):
        emit(_JEQ_K, nr[name], jt="signal", jf=None)
    emit(_JEQ_K, nr["prlimit64"], jt="prlimit", jf=None)
    emit(_RET_K, _RET_ALLOW)
    labels = {}
    labels["clone"] = len(code)
    emit(_LD_W_ABS, 16)  # args[0] low word: clone flags
    emit(_JSET_K, _CLONE_THREAD, jt="allow", jf="deny")
    labels["signal"] = len(code)
    emit(_LD_W_ABS, 16)  # args[0]: target pid / tgid
    emit(_JEQ_K, pid, jt="allow", jf="deny")
    labels["prlimit"] = len(code)
    emit(_LD_W_ABS, 32)  # args[2] (new limit pointer), low word
    emit(_JEQ_K, 0, jt=None, jf="deny")
    emit(_LD_W_ABS, 36)  # high word
    emit(_JEQ_K, 0, jt="allow", jf="deny")
    labels["allow"] = len(code)
    emit(_RET_K, _RET_ALLOW)
    labels["deny"] = len(code)
    emit(_RET_K, _RET_EPERM)
    labels["enosys"] = len(code)
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


def install() -> bool:
    """Install the filter in the calling process (irreversible). Returns False if unavailable."""
    if not available():
        return False
    libc = ctypes.CDLL(None, use_errno=True)
    filters, count = _program(os.getpid())
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
