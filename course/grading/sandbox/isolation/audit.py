"""The Python audit hook of a grading child: friendly error messages, not a security boundary.

Code in the same interpreter can switch an audit hook off (for instance by rewriting its
closure variables found through :mod:`gc`), so nothing here is relied upon for safety: the
kernel layers (:mod:`course.grading.sandbox.isolation`) are. The hook stays because it turns what the
kernel would refuse anyway into a clear ``PermissionError: not allowed while grading: ...``.
"""

from __future__ import annotations

import os
import stat

__all__ = ["close_leaked", "make_audit_hook", "open_fds"]


def open_fds() -> set[int]:
    """The descriptors open in this process now."""
    try:
        return {int(fd) for fd in os.listdir("/proc/self/fd")}
    except OSError:
        return set()


def close_leaked(before: set[int], keep=()) -> list[int]:
    """Close the sockets opened since ``before`` (call after an event was refused).

    ``socket.socketpair()`` creates both sockets before Python raises its audit events; when
    the hook refuses them, the descriptors would stay open in the child. (The seccomp filter
    refuses sockets outright; this is the clean-up for a child without it.)
    """
    closed = []
    for fd in sorted(open_fds() - set(before) - set(keep)):
        try:
            if stat.S_ISSOCK(os.fstat(fd).st_mode):
                os.close(fd)
                closed.append(fd)
        except OSError:
            continue
    return closed


_BLOCKED_EVENTS = frozenset(
    {
        "os.system",
        "os.exec",
        "os.posix_spawn",
        "os.spawn",
        "os.fork",
        "os.forkpty",
        "os.vfork",
        "subprocess.Popen",
        "pty.spawn",
        "os.startfile",
        "webbrowser.open",
        "ctypes.dlopen",
        "ctypes.dlsym",
        "ctypes.call_function",
        "ctypes.cdata",
        "socket.__new__",
        "socket.connect",
        "socket.bind",
        "socket.sendto",
        "socket.sendmsg",
        "resource.setrlimit",
        "resource.prlimit",
        "signal.pthread_kill",
        "sys.remote_exec",
    }
)
_PATH_EVENTS = {
    "os.remove": (0,),
    "os.rename": (0, 1),
    "os.rmdir": (0,),
    "os.mkdir": (0,),
    "os.chmod": (0,),
    "os.chown": (0,),
    "os.link": (0, 1),
    "os.symlink": (1,),
    "os.truncate": (0,),
    "os.utime": (0,),
    "shutil.rmtree": (0,),
    "os.mkfifo": (0,),
    "os.mknod": (0,),
    "os.setxattr": (0,),
    "os.removexattr": (0,),
    "os.chflags": (0,),
    "os.lchmod": (0,),
    "os.lchflags": (0,),
    "shutil.copyfile": (1,),
    "shutil.copytree": (1,),
    "shutil.move": (1,),
    "shutil.chown": (0,),
}


def make_audit_hook(tmpdir: str, deny_read=(), on_refuse=None):
    """The audit hook: refuse process creation, native code loading, sockets, signals to other
    processes, raising limits, any write outside ``tmpdir`` and reads under ``deny_read``."""
    realpath, fspath, sep = os.path.realpath, os.fspath, os.sep
    root = realpath(tmpdir)
    allowed_write = (root + sep,)
    denied = tuple(realpath(p) for p in deny_read)
    write_flags = os.O_WRONLY | os.O_RDWR | os.O_APPEND | os.O_CREAT | os.O_TRUNC
    me = os.getpid()
    blocked, path_events = _BLOCKED_EVENTS, _PATH_EVENTS

    def resolve(path):
        if isinstance(path, int):
            return None
        path = fspath(path)
        if isinstance(path, bytes):
            path = path.decode("utf-8", "surrogateescape")
        return realpath(path)

    def writable(full):
        return full is None or full == root or full.startswith(allowed_write) or full == "/dev/null"

    proc_self = (f"/proc/{me}", "/proc/self", "/proc/thread-self")

    def readable(full):
        if full is None:
            return True
        if full.startswith("/proc/"):
            # other processes' memory, environment and files (e.g. the grader's) are off limits
            part = full[6:].split(sep, 1)[0]
            if part.isdigit() and not full.startswith(proc_self):
                return False
        return not any(full == d or full.startswith(d + sep) for d in denied)

    refused = on_refuse if on_refuse is not None else (lambda: None)

    def refuse(message: str):
        refused()
        raise PermissionError(message)

    def hook(event, args):
        if event in blocked:
            refuse(f"not allowed while grading: {event}")
        if event == "open":
            full = resolve(args[0]) if args[0] is not None else None
            flags = args[2] if len(args) > 2 and isinstance(args[2], int) else 0
            mode = args[1] if isinstance(args[1], str) else ""
            if (flags & write_flags or any(c in mode for c in "wax+")) and not writable(full):
                refuse(
                    f"not allowed while grading: writing {args[0]!r} (outside the temporary folder)"
                )
            if not readable(full):
                refuse(f"not allowed while grading: reading {args[0]!r}")
        elif event in path_events:
            for i in path_events[event]:
                if (
                    i < len(args)
                    and not isinstance(args[i], int)
                    and not writable(resolve(args[i]))
                ):
                    refuse(f"not allowed while grading: {event} {args[i]!r}")
        elif event in ("os.kill", "os.killpg"):
            if not (event == "os.kill" and args and args[0] == me):
                refuse(f"not allowed while grading: {event}")
        elif (
            event in ("os.listdir", "os.scandir")
            and args
            and args[0] is not None
            and not readable(resolve(args[0]))
        ):
            refuse("not allowed while grading: listing a protected folder")

    return hook
