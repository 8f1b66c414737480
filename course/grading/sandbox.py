"""Process isolation for grading, without Docker.

Each submission runs in its OWN process (never the grader's), started in one of two ways:

``fork`` (default on Linux)
    A warm *fork server* (``python -m course.grading.forkserver``) imports numpy, scipy,
    matplotlib, IPython and the course library once; each child is ``os.fork()``-ed from it and
    starts in milliseconds. The server never runs student code.
``spawn``
    ``python -m course.grading.runner`` per submission: slower (every child imports the
    scientific stack), works wherever ``subprocess`` works.

Either way the child (see :mod:`course.grading.runner`) lives in its own session/process
group, in a fresh ``tempfile.mkdtemp`` directory, with a scrubbed environment (PATH, HOME=its
temp dir, LANG, MPLBACKEND=Agg, thread counts; no PYTHON* variables but PYTHONPATH when needed),
stdin from /dev/null and stdout/stderr in a capped file in its temp dir. Before student code it
sets limits (``RLIMIT_AS`` = mapped memory + budget, ``RLIMIT_CPU``, ``RLIMIT_FSIZE``, no core
files; ``RLIMIT_NPROC`` = 0 when seccomp is unavailable), then installs

- a Python audit hook (``sys.addaudithook``; cannot be removed) refusing process creation
  (fork, exec, system, spawn, subprocess), ctypes, sockets, signals to other processes,
  raising limits, writes outside its temp dir, and reads of the grader's own folders
  (solutions, submissions, output);
- a seccomp-BPF filter (:mod:`course.grading.isolation.seccomp`, Linux x86-64/aarch64) in which the
  kernel refuses fork/clone of processes, exec, ptrace, kill of other processes and raising
  limits — this still holds when the audit hook is bypassed and when grading as root, where
  ``RLIMIT_NPROC`` is not enforced.

The parent enforces a wall-clock limit on every request and, on expiry, kills the child's whole
process group with SIGKILL (a loop ignoring SIGINT cannot survive it). Fork server and children
also ask the kernel to kill them when their parent dies, so an interrupted grader leaves nothing
running. Requests and replies are
JSON lines on two dedicated pipes (not stdout/stderr), each reply echoing a random nonce;
numpy arrays travel as dtype/shape/base64, never pickle. Hidden inputs are sent only after the
student's cells ran, and references are computed and compared only in the parent.

What this sandbox does NOT stop (it is defence in depth, not a security boundary):

- Audit hooks are not a security boundary: code in the same interpreter can reach around them
  (e.g. through objects created before the hook, or C extensions already loaded). The seccomp
  filter is the kernel-enforced layer, and it covers only process creation, exec, ptrace,
  signals and limits.
- READING files: a submission can read any file the grading user can read (except the folders
  the grader denies to the audit hook), e.g. other files in your home directory. Run the
  grader as an unprivileged user that can read little else. Without network and without
  writes outside its temp dir it has few ways to get data out, but its own feedback text
  (exception messages) is one.
- Network: blocked only by the audit hook (sockets) — there is no network namespace.
- Memory is limited per process as address space (RLIMIT_AS), not as resident memory; the
  temp dir is limited per file (RLIMIT_FSIZE), not in total; CPU is limited per process.
- A submission can lie about its own answers (for instance by writing on the reply pipe):
  it can never see hidden inputs before its code ran, and the parent does the comparing, so
  a lie cannot turn a wrong answer into points, only break its own grading.
- Timing side channels, /proc information about other processes, and the shared CPU
  (a submission can slow down others running in parallel within its CPU limit).
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import select
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

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

_PACKAGE_PARENT = str(Path(__file__).resolve().parents[2])
MAX_REPLY_BYTES = 64_000_000


@dataclass
class Limits:
    """Resource limits of one child."""

    memory_mb: int = 1024
    cpu_seconds: int = 600
    file_mb: int = 64
    output_chars: int = 1_000_000
    seccomp: bool = True

    def as_dict(self) -> dict:
        return dict(
            memory_mb=self.memory_mb,
            cpu_seconds=self.cpu_seconds,
            file_mb=self.file_mb,
            output_chars=self.output_chars,
            seccomp=self.seccomp,
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


def _scrubbed_env(extra: dict | None = None) -> dict:
    env = {
        k: v
        for k, v in os.environ.items()
        if not k.startswith(("PYTHON", "JUPYTER", "IPYTHON", "MPL"))
    }
    env.update(
        {
            "MPLBACKEND": "Agg",
            "OPENBLAS_NUM_THREADS": "1",
            "OMP_NUM_THREADS": "1",
            "MKL_NUM_THREADS": "1",
            "PYTHONDONTWRITEBYTECODE": "1",
            "PYTHONPATH": _PACKAGE_PARENT,
        }
    )
    env.update(extra or {})
    return env


class ChildHandle:
    """The grader's (parent's) handle on one sandboxed child: requests, kill, exit status."""

    def __init__(
        self, sandbox: Sandbox, pid: int, tmpdir: str, req_w: int, resp_r: int, popen=None
    ):
        self.sandbox = sandbox
        self.pid = pid
        self.tmpdir = tmpdir
        self.req_w = req_w
        self.resp_r = resp_r
        self.popen = popen
        self.alive = True
        self.killed_by_us = False
        self._buffer = b""
        self._next_id = 0
        self.info: dict = {}

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

    def _readline(self, deadline: float) -> bytes:
        while b"\n" not in self._buffer:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise ChildTimeout()
            ready, _, _ = select.select([self.resp_r], [], [], remaining)
            if not ready:
                continue
            chunk = os.read(self.resp_r, 1 << 20)
            if not chunk:
                raise ChildDied(self._death_cause())
            self._buffer += chunk
            if len(self._buffer) > MAX_REPLY_BYTES:
                self.kill()
                raise ChildDied("the reply was too large")
        line, self._buffer = self._buffer.split(b"\n", 1)
        return line

    def request(self, op: str, timeout: float, **fields) -> dict:
        """Send one request and wait for its reply; on timeout the child is killed.

        Raises :class:`ChildTimeout` or :class:`ChildDied`; lines that are not the reply to this
        request (wrong nonce, not JSON) are ignored, so printing cannot forge a reply.
        """
        if not self.alive:
            raise ChildDied("the process had already ended")
        self._next_id += 1
        nonce = secrets.token_hex(8)
        deadline = time.monotonic() + timeout
        try:
            self._send({"op": op, "id": self._next_id, "nonce": nonce, **fields}, deadline)
            while True:
                line = self._readline(deadline)
                try:
                    reply = json.loads(line)
                except ValueError:
                    continue
                if (
                    isinstance(reply, dict)
                    and reply.get("nonce") == nonce
                    and reply.get("id") == self._next_id
                ):
                    return reply
        except ChildTimeout:
            self.kill()
            raise
        except ChildDied:
            self.kill()
            raise

    # -- lifecycle -------------------------------------------------------------------------
    def kill(self) -> None:
        """SIGKILL the child's whole process group (idempotent)."""
        if self.alive:
            self.killed_by_us = True
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(self.pid, signal.SIGKILL)
            self.alive = False

    def _death_cause(self) -> str:
        was_alive = self.alive
        if was_alive:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(self.pid, signal.SIGKILL)  # make sure nothing of it keeps running
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
        if self.popen is not None:
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.popen.wait(timeout=5)
        for fd in (self.req_w, self.resp_r):
            with contextlib.suppress(OSError):
                os.close(fd)
        self.req_w = self.resp_r = -1
        shutil.rmtree(self.tmpdir, ignore_errors=True)


class Sandbox:
    """Factory of sandboxed children (one per submission attempt), thread-safe."""

    def __init__(self, mode: str = "auto", limits: Limits | None = None, preload=(), deny_read=()):
        if mode == "auto":
            mode = (
                "fork"
                if (sys.platform.startswith("linux") and hasattr(socket, "send_fds"))
                else "spawn"
            )
        if mode not in ("fork", "spawn"):
            raise ValueError(f"unknown sandbox mode {mode!r}")
        self.mode = mode
        self.limits = limits or Limits()
        from course.grading.runner import PRELOAD

        self.preload = tuple(dict.fromkeys(PRELOAD + tuple(preload)))
        self.deny_read = [str(Path(p).resolve()) for p in deny_read]
        self._lock = threading.Lock()
        self._server = None
        self._sock = None
        self._rundir = tempfile.mkdtemp(prefix="course-grade-run-")
        if mode == "fork":
            self._start_server()

    # -- fork server ----------------------------------------------------------------------
    def _start_server(self) -> None:
        parent_sock, child_sock = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        log = open(os.path.join(self._rundir, "forkserver.log"), "wb")
        self._server = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "course.grading.forkserver",
                str(child_sock.fileno()),
                json.dumps(self.preload),
            ],
            pass_fds=(child_sock.fileno(),),
            cwd=self._rundir,
            env=_scrubbed_env(),
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
        log.close()
        child_sock.close()
        self._sock = parent_sock
        self._sock.settimeout(120)
        try:
            reply = json.loads(self._sock.recv(65536) or b"null")
        except (OSError, ValueError):
            reply = None
        if not reply or reply.get("status") != ReplyStatus.READY:
            self.close()
            raise SandboxError(
                "the fork server did not start; see " + os.path.join(self._rundir, "forkserver.log")
            )

    def _server_call(self, message: dict, fds=()) -> dict:
        data = json.dumps(message).encode()
        if fds:
            socket.send_fds(self._sock, [data], list(fds))
        else:
            self._sock.send(data)
        reply = self._sock.recv(65536)
        if not reply:
            raise SandboxError("the fork server died")
        return json.loads(reply)

    # -- children -------------------------------------------------------------------------
    def start(self, init: dict, ready_timeout: float = 60.0) -> ChildHandle:
        """Start a child, send it ``init`` and wait until it is ready for student code."""
        tmpdir = tempfile.mkdtemp(prefix="course-grade-")
        req_r, req_w = os.pipe()
        resp_r, resp_w = os.pipe()
        for fd in (req_w, resp_r):
            os.set_inheritable(fd, False)
        popen = None
        try:
            if self.mode == "fork":
                with self._lock:
                    if self._server is None or self._server.poll() is not None:
                        self._start_server()
                    reply = self._server_call(
                        {"op": Op.SPAWN, "tmpdir": tmpdir}, fds=(req_r, resp_w)
                    )
                pid = int(reply["pid"])
            else:
                log = open(os.path.join(tmpdir, "startup.txt"), "wb")
                popen = subprocess.Popen(
                    [sys.executable, "-m", "course.grading.runner", str(req_r), str(resp_w)],
                    pass_fds=(req_r, resp_w),
                    cwd=tmpdir,
                    env=_scrubbed_env({"MPLCONFIGDIR": os.path.join(self._rundir, "matplotlib")}),
                    stdin=subprocess.DEVNULL,
                    stdout=log,
                    stderr=subprocess.STDOUT,
                    start_new_session=True,
                )
                log.close()
                pid = popen.pid
        finally:
            os.close(req_r)
            os.close(resp_w)
        child = ChildHandle(self, pid, tmpdir, req_w, resp_r, popen)
        init = dict(init, limits=self.limits.as_dict(), deny_read=self.deny_read)
        try:
            reply = child.request(Op.INIT, ready_timeout, **init)
        except (ChildTimeout, ChildDied) as exc:
            out = child.output()
            child.close()
            raise SandboxError(f"a grading process did not start ({exc!r}); {out[-500:]}") from None
        child.info = {"seccomp": bool(reply.get("seccomp"))}
        return child

    def _exit_status(self, child: ChildHandle):
        if child.popen is not None:
            try:
                return child.popen.wait(timeout=5)
            except subprocess.TimeoutExpired:
                return None
        with self._lock:
            try:
                reply = self._server_call({"op": Op.STATUS, "pid": child.pid})
            except (OSError, SandboxError, ValueError):
                return None
        status = reply.get("status")
        if status is None:
            return None
        return -os.WTERMSIG(status) if os.WIFSIGNALED(status) else os.WEXITSTATUS(status)

    def close(self) -> None:
        """Stop the fork server and remove the run directory."""
        if self._sock is not None:
            with contextlib.suppress(OSError):
                self._sock.close()
            self._sock = None
        if self._server is not None:
            try:
                self._server.wait(timeout=5)
            except subprocess.TimeoutExpired:
                os.killpg(self._server.pid, signal.SIGKILL)
                self._server.wait()
            self._server = None
        shutil.rmtree(self._rundir, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
