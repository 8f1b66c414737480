"""The Python audit hook of a grading child: friendly error messages, not a security boundary.

Code in the same interpreter can switch an audit hook off (for instance by rewriting its
closure variables found through :mod:`gc`), so nothing here is relied upon for safety: the
kernel layers (:mod:`course.grading.isolation`) are. The hook stays because it turns what the
kernel would refuse anyway into a clear ``PermissionError: not allowed while grading: ...``.
"""

from __future__ import annotations

import os

__all__ = ["make_audit_hook"]


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


def make_audit_hook(tmpdir: str, deny_read=()):
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

    def hook(event, args):
        if event in blocked:
            raise PermissionError(f"not allowed while grading: {event}")
        if event == "open":
            full = resolve(args[0]) if args[0] is not None else None
            flags = args[2] if len(args) > 2 and isinstance(args[2], int) else 0
            mode = args[1] if isinstance(args[1], str) else ""
            if (flags & write_flags or any(c in mode for c in "wax+")) and not writable(full):
                raise PermissionError(
                    f"not allowed while grading: writing {args[0]!r} (outside the temporary folder)"
                )
            if not readable(full):
                raise PermissionError(f"not allowed while grading: reading {args[0]!r}")
        elif event in path_events:
            for i in path_events[event]:
                if (
                    i < len(args)
                    and not isinstance(args[i], int)
                    and not writable(resolve(args[i]))
                ):
                    raise PermissionError(f"not allowed while grading: {event} {args[i]!r}")
        elif event in ("os.kill", "os.killpg"):
            if not (event == "os.kill" and args and args[0] == me):
                raise PermissionError(f"not allowed while grading: {event}")
        elif (
            event in ("os.listdir", "os.scandir")
            and args
            and args[0] is not None
            and not readable(resolve(args[0]))
        ):
            raise PermissionError("not allowed while grading: listing a protected folder")

    return hook
