"""Process isolation for grading, without Docker: the parent's side.

Each submission runs in its OWN process (never the grader's), forked from a warm *fork server*
(:mod:`course.grading.sandbox.forkserver`) that imports numpy, scipy, matplotlib, IPython and
the whole course library once; a child starts in milliseconds. The server never runs student
code.

There is one start mode. A second one, a fresh ``python -m ...runner`` per child ("spawn"),
was removed: it took 5-12 s per student against 0.1-0.6 s forked (the same five submissions
of 01_least_squares, one job, a loaded 2-core machine), doubled the start path, and served
only systems other than Linux, where the sandbox has no walls (no bubblewrap, Landlock or
seccomp) and grading is refused anyway. The grader needs Linux.

With bubblewrap, the fork server lives in namespaces of its own: a root
that holds only the Python installation, the course package and the children's temporary
folders, no network, its own PID space. Each child then, before any student code, confines
itself with Landlock (it may read Python and the course's data, write only its own temporary
folder), switches to ``nobody`` when the grader is root, sets resource limits and installs a
seccomp filter; see :mod:`course.grading.sandbox.isolation` for what each layer enforces and the
order in which :func:`~course.grading.sandbox.isolation.detect` falls back.

The parent enforces a wall-clock limit on every request and, on expiry, kills the child with
SIGKILL through a pidfd (valid across PID namespaces). Fork server and children also ask the
kernel to kill them when their parent dies, so an interrupted grader leaves nothing running.
Requests and replies are JSON lines on two dedicated pipes (not stdout/stderr), each reply
echoing a random nonce; numpy arrays travel as dtype/shape/base64, never pickle. A third pipe
carries reports of forbidden library calls (:mod:`course.grading.tripwire`), read by the parent
as they happen. Hidden inputs are sent only after the student's cells ran, and references are
computed and compared only in the parent.

What a submission can still do is listed in ``docs/instructors/sandbox.md``.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import secrets
import select
import shutil
import signal
import socket
import stat
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from course.grading.notebook import MAX_NOTEBOOK_BYTES, SubmissionError
from course.grading.sandbox.forkserver import TAMPERED
from course.grading.sandbox.isolation import Isolation, detect
from course.grading.tripwire import Call, parse_events
from course.grading.vocabulary import Op, ReplyStatus

__all__ = [
    "ChildDied",
    "ChildHandle",
    "ChildTimeout",
    "Limits",
    "Sandbox",
    "SandboxError",
    "describe_exit",
]

_PACKAGE_PARENT = str(Path(__file__).resolve().parents[3])
#: The longest reply line the parent takes from a child, and the most JSON values (counted as
#: ``[``, ``{`` and ``,``) in it: decoding costs the parent up to ~4 bytes per byte of a
#: string and ~70 bytes per value, so a reply costs it at most ~40 MB (numpy arrays travel as
#: base64 strings, so 8 MB is an array of a million numbers). A longer reply stops the child
#: and fails its question ("the reply was too large").
MAX_REPLY_BYTES = 8_000_000
MAX_REPLY_ITEMS = 200_000
#: A reader child's reply: the reduced notebook (at most 1,000,000 characters of source,
#: 12 bytes each at worst as JSON escapes), from a child that ran no student code.
MAX_READ_REPLY_BYTES = 16_000_000
_READ_FILE = "submission.ipynb"  # runner.READ_FILE (the runner is not imported by the parent)
#: How often (seconds) the parent measures a working child's files, and the most entries of
#: its folder it counts (more count as over the limit).
FILES_POLL = 0.25
MAX_FOLDER_ENTRIES = 10_000


def _host_pid(pidfd: int | None) -> int | None:
    """The pid, in the grader's PID namespace, of the process ``pidfd`` refers to."""
    if pidfd is None:
        return None
    try:
        with open(f"/proc/self/fdinfo/{pidfd}") as f:
            for line in f:
                if line.startswith("Pid:"):
                    pid = int(line.split()[1])
                    return pid if pid > 0 else None
    except (OSError, ValueError):
        pass
    return None


def files_bytes(folder: str, pid: int | None = None) -> int:
    """The bytes a child's files take: every file beneath ``folder`` (allocated blocks, links
    not followed) and, for the process ``pid``, the regular files it keeps open that no folder
    names any more (deleted, or made with ``O_TMPFILE``). A folder of more than
    :data:`MAX_FOLDER_ENTRIES` entries counts as without bound."""
    total, seen = 0, 0
    todo = [folder]
    while todo:
        try:
            entries = list(os.scandir(todo.pop()))
        except OSError:
            continue
        for entry in entries:
            seen += 1
            if seen > MAX_FOLDER_ENTRIES:
                return sys.maxsize
            try:
                st = entry.stat(follow_symlinks=False)
            except OSError:
                continue
            if stat.S_ISDIR(st.st_mode):
                todo.append(entry.path)
            else:
                total += st.st_blocks * 512
    if pid is not None:
        try:
            fds = os.listdir(f"/proc/{pid}/fd")
        except OSError:
            fds = []
        for fd in fds[:MAX_FOLDER_ENTRIES]:
            try:
                st = os.stat(f"/proc/{pid}/fd/{fd}")
            except OSError:
                continue
            if stat.S_ISREG(st.st_mode) and st.st_nlink == 0:
                total += st.st_blocks * 512
    return total


@dataclass
class Limits:
    """Resource limits of one child."""

    memory_mb: int = 1024
    cpu_seconds: int = 600
    file_mb: int = 64
    output_chars: int = 1_000_000
    seccomp: bool = True
    #: every file the child holds (its folder, and files it deleted but keeps open), in total:
    #: on a tmpfs they are memory, which the address-space limit does not count
    files_mb: int = 256
    open_files: int = 256

    def as_dict(self) -> dict:
        return dict(
            memory_mb=self.memory_mb,
            cpu_seconds=self.cpu_seconds,
            file_mb=self.file_mb,
            output_chars=self.output_chars,
            seccomp=self.seccomp,
            open_files=self.open_files,
        )


class SandboxError(RuntimeError):
    """The sandbox itself failed (not the student's code)."""


class ChildTimeout(Exception):
    """The child did not answer within the time limit (it has been killed)."""


class ChildDied(Exception):
    """The child exited or was killed while working on a request."""

    def __init__(self, cause: str):
        super().__init__(cause)
        self.cause = cause


def describe_exit(returncode: int | None) -> str:
    """Human description of a child's end from a subprocess-style returncode (-signal or code)."""
    if returncode is None:
        return "the process ended"
    if returncode >= 0:
        return f"the process exited (exit code {returncode})"
    sig = -returncode
    if sig == signal.SIGXCPU:
        return "the CPU time limit was exceeded"
    if sig == signal.SIGKILL:
        return "the process was killed (memory or CPU limit)"
    if sig == signal.SIGSEGV:
        return "the process crashed (segmentation fault)"
    if sig == signal.SIGABRT:
        return "the process aborted"
    if sig == signal.SIGSYS:
        return "a forbidden system call was made"
    try:
        name = signal.Signals(sig).name
    except ValueError:
        name = str(sig)
    return f"the process was killed by signal {name}"


def _server_env(rundir: str) -> dict:
    """The environment of the fork server (children replace theirs): nothing of the grader's.

    A child can read its process's initial environment in ``/proc/self/environ``, so the
    grader's variables (tokens, paths) must not be there in the first place.
    """
    env = {
        "PATH": "/usr/bin:/bin",
        "HOME": rundir,
        "LANG": "C.UTF-8",
        "LC_ALL": "C.UTF-8",
        "MPLBACKEND": "Agg",
        "MPLCONFIGDIR": os.path.join(rundir, "matplotlib"),
        "OPENBLAS_NUM_THREADS": "1",
        "OMP_NUM_THREADS": "1",
        "MKL_NUM_THREADS": "1",
        "PYTHONDONTWRITEBYTECODE": "1",
        "PYTHONPATH": _PACKAGE_PARENT,
    }
    return env


def remove_tree(path: str) -> list[str]:
    """Remove the folder ``path`` and everything in it; what could not be removed, each as
    ``"<path> (<reason>)"`` (at most 20; empty when all is gone). A file a child made
    immutable (``chattr +i``) is one; the caller reports it, never silently."""
    failed: list[str] = []
    seen: set[str] = set()

    def note(_func, where, exc_info) -> None:
        exc = exc_info[1]
        if isinstance(exc, FileNotFoundError) or where in seen:
            return
        if isinstance(exc, OSError) and exc.errno == errno.ENOTEMPTY:
            return  # a folder that still holds what failed: that is reported itself
        seen.add(where)
        if len(failed) < 20:
            failed.append(f"{where} ({getattr(exc, 'strerror', None) or exc})")

    shutil.rmtree(path, onerror=note)
    if not failed and os.path.lexists(path):
        failed.append(f"{path} (still there)")
    return failed


def _copy_notebook(source, target: str) -> None:
    """Write a submission (its bytes, or the file at ``source``) to ``target``, refusing a
    symbolic link, anything but a regular file and more than ``MAX_NOTEBOOK_BYTES``; the
    copy goes in chunks, so a file of any size costs the parent 1 MB of memory."""
    if isinstance(source, bytes):
        if len(source) > MAX_NOTEBOOK_BYTES:
            raise SubmissionError(
                f"the notebook is larger than {MAX_NOTEBOOK_BYTES // 1_000_000} MB"
            )
        with open(target, "wb") as out:
            out.write(source)
        return
    try:
        fd = os.open(source, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)  # a FIFO never waits
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise SubmissionError("the notebook is a symbolic link") from None
        raise SubmissionError(f"cannot read the notebook ({exc.strerror})") from None
    with os.fdopen(fd, "rb") as f, open(target, "wb") as out:
        if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
            raise SubmissionError("the notebook is not a regular file")
        copied = 0
        while chunk := f.read(1 << 20):
            copied += len(chunk)
            if copied > MAX_NOTEBOOK_BYTES:
                raise SubmissionError(
                    f"the notebook is larger than {MAX_NOTEBOOK_BYTES // 1_000_000} MB"
                )
            out.write(chunk)


class ChildHandle:
    """The grader's (parent's) handle on one sandboxed child: requests, kill, exit status."""

    def __init__(
        self,
        sandbox: Sandbox,
        pid: int,
        tmpdir: str,
        req_w: int,
        resp_r: int,
        event_r: int,
        pidfd: int | None = None,
    ):
        self.sandbox = sandbox
        self.pid = pid
        self.pidfd = pidfd
        self.tmpdir = tmpdir
        self.req_w = req_w
        self.resp_r = resp_r
        self.event_r = event_r
        self.alive = True
        self.killed_by_us = False
        self._buffer = b""
        self._events_tail = b""
        # forbidden calls reported: only instrumented functions and known labels, each
        # (function, label) once (in order) with the names it implements and a count, so a
        # flood of reports costs the parent no memory
        self._events: dict[tuple[str, str], tuple[dict[str, None], int]] = {}
        self.events_reported = 0
        self._next_id = 0
        self._max_bytes = MAX_REPLY_BYTES
        self.cleanup_failed: list[str] = []  # what close() could not remove
        self.info: dict = {}
        self.host_pid = _host_pid(pidfd)
        self._files_limit = sandbox.limits.files_mb * 1024 * 1024
        self._files_checked = time.monotonic()

    # -- protocol -------------------------------------------------------------------------
    def _send(self, obj: dict, deadline: float) -> None:
        data = (json.dumps(obj, allow_nan=False, separators=(",", ":")) + "\n").encode("utf-8")
        view = memoryview(data)
        while view:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise ChildTimeout()
            _, writable, _ = select.select([], [self.req_w], [], remaining)
            if not writable:
                continue
            try:
                n = os.write(self.req_w, view[: 1 << 16])
            except (BrokenPipeError, OSError):
                raise ChildDied(self._death_cause()) from None
            view = view[n:]

    def _read_events(self) -> None:
        """Take what is in the event pipe now (never blocks)."""
        while self.event_r >= 0:
            try:
                chunk = os.read(self.event_r, 1 << 16)
            except BlockingIOError:
                return
            except OSError:
                return
            if not chunk:
                return
            calls, self._events_tail = parse_events(self._events_tail + chunk)
            self.events_reported += len(calls)
            for call in calls:
                if call.called not in self.sandbox.instrumented:
                    continue
                where = call.where if call.where in self.sandbox.labels else ""
                implements, count = self._events.get((call.called, where), ({}, 0))
                for name in call.implements:
                    if name in self.sandbox.forbid_set:
                        implements[name] = None
                if implements:
                    self._events[(call.called, where)] = (implements, count + 1)

    def _check_files(self) -> None:
        """Stop the child when its files exceed their limit (``Limits.files_mb``)."""
        self._files_checked = time.monotonic()
        if self._files_limit > 0 and files_bytes(self.tmpdir, self.host_pid) > self._files_limit:
            self.kill()
            raise ChildDied(f"its files took more than {self._files_limit >> 20} MB (memory limit)")

    def _readline(self, deadline: float) -> bytes:
        while b"\n" not in self._buffer:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise ChildTimeout()
            watched = [self.resp_r] + ([self.event_r] if self.event_r >= 0 else [])
            ready, _, _ = select.select(watched, [], [], min(remaining, FILES_POLL))
            if self.event_r in ready:
                self._read_events()
            if time.monotonic() >= self._files_checked + FILES_POLL:  # whatever else arrives
                self._check_files()
            if self.resp_r not in ready:
                continue
            chunk = os.read(self.resp_r, 1 << 20)
            if not chunk:
                raise ChildDied(self._death_cause())
            self._buffer += chunk
            if len(self._buffer) > self._max_bytes:
                self.kill()
                raise ChildDied("the reply was too large")
        line, self._buffer = self._buffer.split(b"\n", 1)
        return line

    def take_events(self) -> list[Call]:
        """Forbidden library calls reported since the last call (in the order they happened),
        each function called once per label of the calling code."""
        self._read_events()
        events, self._events = self._events, {}
        return [Call(called, tuple(names), where) for (called, where), (names, _) in events.items()]

    def request(
        self,
        op: str,
        timeout: float,
        *,
        max_bytes: int = MAX_REPLY_BYTES,
        max_items: int | None = MAX_REPLY_ITEMS,
        **fields,
    ) -> dict:
        """Send one request and wait for its reply; on timeout the child is killed.

        Raises :class:`ChildTimeout` or :class:`ChildDied`; lines that are not the reply to this
        request (wrong nonce, not JSON) are ignored, so printing cannot forge a reply. A line
        longer than ``max_bytes`` or with more than ``max_items`` JSON values stops the child
        (:class:`ChildDied`, "the reply was too large") before the parent decodes it. Reports
        of forbidden calls made meanwhile are collected (:meth:`take_events`).
        """
        if not self.alive:
            raise ChildDied("the process had already ended")
        self._next_id += 1
        self._max_bytes = max_bytes
        nonce = secrets.token_hex(8)
        deadline = time.monotonic() + timeout
        try:
            self._send({"op": op, "id": self._next_id, "nonce": nonce, **fields}, deadline)
            while True:
                line = self._readline(deadline)
                if (
                    max_items is not None
                    and line.count(b",") + line.count(b"[") + line.count(b"{") > max_items
                ):
                    self.kill()
                    raise ChildDied("the reply was too large")
                try:
                    reply = json.loads(line)
                except (ValueError, RecursionError):  # deep nesting ("[[[[...") too
                    continue
                if (
                    isinstance(reply, dict)
                    and reply.get("nonce") == nonce
                    and reply.get("id") == self._next_id
                ):
                    self._read_events()  # written before the reply, so already in the pipe
                    self._check_files()
                    return reply
        except (ChildTimeout, ChildDied):
            self._read_events()
            self.kill()
            raise

    # -- lifecycle -------------------------------------------------------------------------
    def _signal_kill(self) -> None:
        if self.pidfd is not None:
            with contextlib.suppress(ProcessLookupError, OSError):
                signal.pidfd_send_signal(self.pidfd, signal.SIGKILL)
        else:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(self.pid, signal.SIGKILL)

    def kill(self) -> None:
        """SIGKILL the child (idempotent)."""
        if self.alive:
            self.killed_by_us = True
            self._signal_kill()
            self.alive = False

    def _death_cause(self) -> str:
        if self.alive:
            self._signal_kill()  # make sure nothing of it keeps running
            self.alive = False
        status = self.sandbox._exit_status(self)
        return describe_exit(status)

    def output(self, limit: int = 4000) -> str:
        """The first ``limit`` characters the child printed (for debugging)."""
        try:
            with open(os.path.join(self.tmpdir, "output.txt"), "rb") as f:
                return f.read(limit).decode("utf-8", "replace")
        except OSError:
            return ""

    def close(self) -> None:
        """Stop the child (politely, then SIGKILL) and delete its temp dir."""
        if self.alive:
            with contextlib.suppress(ChildTimeout, ChildDied):
                self._send({"op": Op.EXIT}, time.monotonic() + 0.5)
            self.kill()
        for fd in (self.req_w, self.resp_r, self.event_r, self.pidfd):
            if fd is not None and fd >= 0:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self.req_w = self.resp_r = self.event_r = -1
        self.pidfd = None
        if os.path.lexists(self.tmpdir):
            self.cleanup_failed = remove_tree(self.tmpdir)
            self.sandbox.note_cleanup_failed(self.cleanup_failed)


class Sandbox:
    """Factory of sandboxed children (one per submission attempt), thread-safe.

    Parameters
    ----------
    limits : Limits
    preload : sequence of str
        Modules to import before student code (every course module is imported anyway).
    deny_read : sequence of path
        Folders no child may see (course folders, submissions, output); the home folder and the
        working directory are added. With bubblewrap or Landlock they are unreachable anyway
        (allow-lists); the audit hook names them in its error messages.
    forbid : sequence of str
        Dotted names of forbidden library functions to instrument (:mod:`~course.grading.tripwire`).
    isolation : Isolation, optional
        The layers to use (default: :func:`~course.grading.sandbox.isolation.detect`).
    labels : sequence of str
        The labels a child may give the code that made a forbidden call (the question ids:
        a child labels each answer function with its question).
    """

    def __init__(
        self,
        limits: Limits | None = None,
        preload=(),
        deny_read=(),
        forbid=(),
        isolation: Isolation | None = None,
        labels=(),
    ):
        if not sys.platform.startswith("linux"):
            raise SandboxError(
                f"grading needs Linux (its sandbox is Linux's: namespaces, Landlock, seccomp); "
                f"this is {sys.platform}"
            )
        self.limits = limits or Limits()
        self.isolation = isolation if isolation is not None else detect()
        from course.grading.sandbox.runner import PRELOAD

        self.preload = tuple(dict.fromkeys(PRELOAD + tuple(preload)))
        self.forbid = tuple(sorted(set(forbid)))
        self.forbid_set = frozenset(self.forbid)
        #: the labels a report may give its calling code (the questions), see runner.op_run
        self.labels = frozenset(labels)
        self.deny_read = [str(Path(p).resolve()) for p in deny_read]  # named by the audit hook
        # never mounted nor allowed, should a Python folder contain one of them
        self.protected = [*self.deny_read, os.path.expanduser("~"), os.getcwd()]
        self._lock = threading.Lock()
        self._failures_lock = threading.Lock()
        #: what a child left that no cleanup could remove ("<path> (<reason>)")
        self.cleanup_failures: list[str] = []
        self._server: subprocess.Popen | None = None
        self._sock: socket.socket | None = None
        self._privates: list[str] = []  # every private directory of this run (close removes)
        self.rundir_lost = 0  # run folders that disappeared (another process cleaned them)
        self._make_rundir()
        self.server_info: dict = {}
        self.instrumented: frozenset[str] = frozenset()
        self.server_restarts = 0  # fork servers replaced because a child changed scheduling
        self._retired: list[tuple[subprocess.Popen | None, socket.socket | None]] = []
        self._start_server()

    # -- launching ------------------------------------------------------------------------
    def _make_rundir(self) -> None:
        """A fresh run folder inside a private directory of this run (``mkdtemp``: a new name
        no other process chose, mode 0700, or 0711 when children run as another user and must
        pass through it)."""
        private = os.path.realpath(tempfile.mkdtemp(prefix="course-grade-"))
        self._privates.append(private)
        if self.isolation.drop_to is not None:
            os.chmod(private, 0o711)
        self._rundir = os.path.join(private, "run")
        self._children = os.path.join(self._rundir, "children")
        for folder in self._run_folders():
            os.mkdir(folder, 0o700)
            if self.isolation.drop_to is not None:
                os.chown(folder, *self.isolation.drop_to)

    def _run_folders(self) -> tuple[str, str, str]:
        return (self._rundir, self._children, os.path.join(self._rundir, "matplotlib"))

    def _check_rundir(self) -> None:
        """Recreate the run folder (and its fork server, whose mounts and working folder were
        in it) when another process removed it: a cleaner of the temporary directory must cost
        a retry, never a grade. Called under ``_lock``."""
        if os.path.isdir(self._children):
            return
        self.rundir_lost += 1
        if self._server is not None:  # its children (other students') keep running until close
            self._retired.append((self._server, self._sock))
            self._server = self._sock = None
        self._make_rundir()

    def _config(self) -> dict:
        """What the fork server needs before any student code."""
        from course.grading.sandbox.isolation.paths import DEVICES, landlock_paths

        iso = self.isolation
        return {
            "preload": list(self.preload),
            "forbid": list(self.forbid),
            "landlock": iso.landlock,
            "read": landlock_paths(self.protected) if iso.landlock else [],
            "devices": list(DEVICES),
            "seccomp": bool(iso.seccomp and self.limits.seccomp),
            "drop_to": list(iso.drop_to) if iso.drop_to else None,
            # inside bubblewrap the server switches at once; without, each child does (if it can)
            "drop_in_server": bool(iso.bwrap and iso.drop_to),
            "namespaced": bool(iso.bwrap),  # bubblewrap's init is the parent (pid 1)
        }

    def _wrap(self, argv: list[str]) -> list[str]:
        if not self.isolation.bwrap:
            return argv
        from course.grading.sandbox.isolation.namespaces import bwrap_command
        from course.grading.sandbox.isolation.paths import mount_paths

        read_only = mount_paths(self.protected)
        return bwrap_command(self.isolation.bwrap, read_only, [self._rundir], "/") + argv

    def _start_server(self) -> None:
        parent_sock, child_sock = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        log = open(os.path.join(self._rundir, "forkserver.log"), "wb")
        argv = [
            sys.executable,
            "-m",
            "course.grading.sandbox.forkserver",
            str(child_sock.fileno()),
            json.dumps(self._config()),
        ]
        self._server = subprocess.Popen(
            self._wrap(argv),
            pass_fds=(child_sock.fileno(),),
            cwd=self._rundir,
            env=_server_env(self._rundir),
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
        log.close()
        child_sock.close()
        self._sock = parent_sock
        parent_sock.settimeout(120)
        try:
            reply = json.loads(parent_sock.recv(65536) or b"null")
        except (OSError, ValueError):
            reply = None
        if not reply or reply.get("status") != ReplyStatus.READY:
            log_text = self._server_log()
            self.close()
            raise SandboxError(f"the fork server did not start: {log_text[-1500:]}")
        self.server_info = reply
        #: the functions instrumented (public and private): the only ones a report may name
        self.instrumented = frozenset(reply.get("tripwires") or ())
        self.isolation = self.isolation.with_(unprivileged=bool(reply.get("unprivileged")))
        if self.isolation.drop_to is not None and not self.isolation.unprivileged:
            # children stay root without capabilities: a folder of nobody's on the way to
            # theirs would keep them out of it (and out of their Landlock rule)
            for folder in self._run_folders():
                os.chown(folder, os.getuid(), os.getgid())

    def _server_log(self) -> str:
        try:
            with open(os.path.join(self._rundir, "forkserver.log"), "rb") as f:
                return f.read().decode("utf-8", "replace")
        except OSError:
            return ""

    def _server_call(self, message: dict, fds=()) -> tuple[dict, list[int]]:
        if self._sock is None:
            raise SandboxError("the fork server is not running")
        data = json.dumps(message).encode()
        if fds:
            socket.send_fds(self._sock, [data], list(fds))
        else:
            self._sock.send(data)
        reply, got_fds, _flags, _addr = socket.recv_fds(self._sock, 65536, 1)
        if not reply:
            for fd in got_fds:
                os.close(fd)
            raise SandboxError("the fork server died")
        return json.loads(reply), got_fds

    # -- children -------------------------------------------------------------------------
    def start(self, init: dict, ready_timeout: float = 60.0) -> ChildHandle:
        """Start a child, send it ``init`` and wait until it is ready for student code."""
        with self._lock:
            self._check_rundir()
            if self._server is None or self._server.poll() is not None:
                self._start_server()
            tmpdir = tempfile.mkdtemp(prefix="child-", dir=self._children)
        if self._children_drop():
            os.chown(tmpdir, *self.isolation.drop_to)  # type: ignore[misc]
        req_r, req_w = os.pipe()
        resp_r, resp_w = os.pipe()
        event_r, event_w = os.pipe()
        for fd in (req_w, resp_r, event_r):
            os.set_inheritable(fd, False)
        os.set_blocking(event_r, False)
        try:
            with self._lock:
                if self._server is None or self._server.poll() is not None:
                    self._start_server()
                reply, got = self._server_call(
                    {"op": Op.SPAWN, "tmpdir": tmpdir}, fds=(req_r, resp_w, event_w)
                )
                if reply.get("error") == TAMPERED:  # a child changed the server's scheduling
                    # a fresh server for later children; the old one stays until close(), so
                    # the children it forked (other students') keep running
                    self.server_restarts += 1
                    self._retired.append((self._server, self._sock))
                    self._server = self._sock = None
                    self._start_server()
                    reply, got = self._server_call(
                        {"op": Op.SPAWN, "tmpdir": tmpdir}, fds=(req_r, resp_w, event_w)
                    )
            pid = int(reply["pid"])
            pidfd = got[0] if got else None
        finally:
            for fd in (req_r, resp_w, event_w):
                os.close(fd)
        child = ChildHandle(self, pid, tmpdir, req_w, resp_r, event_r, pidfd)
        init = dict(init, limits=self.limits.as_dict(), deny_read=self.deny_read)
        try:
            reply = child.request(Op.INIT, ready_timeout, **init)
        except (ChildTimeout, ChildDied) as exc:
            out = child.output()
            child.close()
            raise SandboxError(f"a grading process did not start ({exc!r}); {out[-500:]}") from None
        child.info = {k: reply.get(k) for k in ("seccomp", "landlock", "uid")}
        child.take_events()  # nothing before student code counts
        return child

    def _children_drop(self) -> bool:
        """Whether children run as ``drop_to`` (their folders are then theirs). A child that
        stays root has no capabilities, so it could not write a folder owned by nobody."""
        return self.isolation.drop_to is not None and bool(self.isolation.unprivileged)

    def read_notebook(self, source, timeout: float = 60.0) -> dict:
        """Decode a submitted notebook (a path, or its bytes) in a sandboxed reader child.

        The parent copies the file (at most :data:`~course.grading.notebook.MAX_NOTEBOOK_BYTES`,
        refusing links and anything but a regular file) into a fresh child's folder; the
        child, under its memory limit and before any student code, decodes it and sends back
        only what the grader reads (:func:`~course.grading.notebook.reduce_notebook`). So
        whatever a notebook holds (deep nesting, millions of tiny values, huge strings), it
        costs the parent at most a few times
        :data:`~course.grading.notebook.MAX_SOURCE_CHARS` and the reader at most ``timeout``.
        Raises :class:`~course.grading.notebook.SubmissionError` (that student's problem).
        """
        child = self.start(
            {"student_id": "", "assignment": "", "data": {}, "reader": True}, timeout
        )
        try:
            target = os.path.join(child.tmpdir, _READ_FILE)
            _copy_notebook(source, target)
            if self._children_drop():
                os.chown(target, *self.isolation.drop_to)  # type: ignore[misc]
            reply = child.request(Op.READ, timeout, max_bytes=MAX_READ_REPLY_BYTES, max_items=None)
        except ChildTimeout:
            raise SubmissionError(f"reading the notebook took longer than {timeout:g} s") from None
        except ChildDied as exc:
            raise SubmissionError(f"the notebook could not be read ({exc.cause})") from None
        finally:
            child.close()
        nb = reply.get("notebook")
        if reply.get("status") != ReplyStatus.OK or not isinstance(nb, dict):
            error = reply.get("error")
            message = error.get("message") if isinstance(error, dict) else None
            raise SubmissionError(str(message or "the notebook could not be read")[:500])
        cells = nb.get("cells")
        if not isinstance(cells, list) or not all(
            isinstance(cell, dict) and isinstance(cell.get("source"), str) for cell in cells
        ):
            raise SubmissionError("the notebook could not be read")
        return nb

    def _exit_status(self, child: ChildHandle):
        with self._lock:
            try:
                reply, got = self._server_call({"op": Op.STATUS, "pid": child.pid})
            except (OSError, SandboxError, ValueError):
                return None
        for fd in got:
            os.close(fd)
        status = reply.get("status")
        if status is None:
            return None
        return -os.WTERMSIG(status) if os.WIFSIGNALED(status) else os.WEXITSTATUS(status)

    @staticmethod
    def _stop(server: subprocess.Popen | None, sock: socket.socket | None) -> None:
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.close()
        if server is not None:
            try:
                server.wait(timeout=5)
            except subprocess.TimeoutExpired:
                os.killpg(server.pid, signal.SIGKILL)
                server.wait()

    def note_cleanup_failed(self, failed: list[str]) -> None:
        """Record paths a cleanup could not remove (:attr:`cleanup_failures`)."""
        with self._failures_lock:
            self.cleanup_failures.extend(f for f in failed if f not in self.cleanup_failures)

    def close(self) -> None:
        """Stop the fork server and remove the run directory (what cannot be removed is
        recorded in :attr:`cleanup_failures`)."""
        self._stop(self._server, self._sock)
        self._server = self._sock = None
        while self._retired:
            self._stop(*self._retired.pop())
        for private in self._privates:
            if os.path.lexists(private):
                self.note_cleanup_failed(remove_tree(private))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
