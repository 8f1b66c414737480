"""The warm fork server: ``python -m course.grading.sandbox.forkserver SOCK_FD CONFIG_JSON``.

Started once per :class:`~course.grading.sandbox.parent.Sandbox` (inside bubblewrap when available),
it prepares everything that does not depend on the student, once:

1. switches to ``nobody`` when the grader is root and the namespaces make that possible;
2. imports the scientific stack and every course module;
3. instruments the forbidden library functions (:mod:`course.grading.tripwire`) to report to a
   descriptor number reserved now;
4. opens the Landlock allow-list (descriptors of the folders children may read).

Then it forks one child per request of the grader (first putting its own CPU affinity, nice
value and scheduling policy back as they were when it started, which every child inherits), received on a UNIX socket together with the
child's three pipe ends, and answers with the child's pid and a pidfd (which the grader can
signal across PID namespaces). It never runs student code itself; its children run
:func:`course.grading.sandbox.runner.child_main` and never return.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import sys
import time

__all__ = ["TAMPERED"]

#: The server's answer to a spawn request when a child changed its scheduling state and it
#: could not put it back: the grader replaces it with a fresh server.
TAMPERED = "scheduling changed"


def _scheduling() -> tuple:
    """This process's scheduling state: CPU affinity, nice value, policy and its priority."""
    return (
        frozenset(os.sched_getaffinity(0)),
        os.getpriority(os.PRIO_PROCESS, 0),
        os.sched_getscheduler(0),
        os.sched_getparam(0).sched_priority,
    )


def _restore_scheduling(initial: tuple) -> bool:
    """Put the server's scheduling state back as it started, before each fork: children
    inherit it, and a child may have pinned or reniced the server where seccomp does not
    refuse that (seccomp off, or a kernel without it). False when it cannot (an unprivileged
    server cannot lower its nice value again): the server must then be replaced."""
    if _scheduling() == initial:
        return True
    affinity, nice, policy, priority = initial
    with contextlib.suppress(OSError):
        os.sched_setscheduler(0, policy, os.sched_param(priority))
    with contextlib.suppress(OSError):
        os.sched_setaffinity(0, affinity)
    with contextlib.suppress(OSError):
        os.setpriority(os.PRIO_PROCESS, 0, nice)
    return _scheduling() == initial


def _allow_nice_back(nice: int) -> None:
    """Let the server lower its nice value back to ``nice`` once it is ``nobody`` (an
    unprivileged process may not, unless its RLIMIT_NICE allows it: 20 - nice). Children
    inherit the limit: it lets them go no lower than the server started."""
    import resource

    with contextlib.suppress(OSError, ValueError):
        resource.setrlimit(resource.RLIMIT_NICE, (20 - nice, 20 - nice))


def _server_main(sock_fd: int, config_json: str) -> None:
    from course.grading.sandbox import runner
    from course.grading.sandbox.isolation import seccomp
    from course.grading.vocabulary import Op, ReplyStatus

    seccomp.die_with_parent()
    initial = _scheduling()
    config = json.loads(config_json)
    if config.get("nice_back", True):  # off: as where the hard limit cannot be raised
        _allow_nice_back(initial[1])
    if os.getppid() == 1 and not config.get("namespaced"):  # the grader is already gone
        return
    sock = socket.socket(fileno=sock_fd)
    setup = runner.prepare(config)
    statuses: dict[int, int] = {}

    def reap():
        while True:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                return
            if pid == 0:
                return
            statuses[pid] = status
            if len(statuses) > 10000:
                statuses.pop(next(iter(statuses)))

    sock.send(
        json.dumps(
            {
                "status": ReplyStatus.READY.value,
                "unprivileged": setup.unprivileged,
                "tripwires": setup.tripwires,
            }
        ).encode()
    )
    keep_base = {0, 1, 2, setup.event_fd, *setup.policy_fds()}
    while True:
        try:
            msg, fds, _flags, _addr = socket.recv_fds(sock, 65536, 4)
        except OSError:
            break
        if not msg:
            break
        reap()
        req = json.loads(msg)
        if req["op"] == Op.SPAWN and len(fds) == 3 and not _restore_scheduling(initial):
            for fd in fds:
                os.close(fd)
            # the grader forks later children from a fresh server; this one forks no more but
            # lives on (its children die with it) until the grader closes its socket
            sock.send(json.dumps({"error": TAMPERED}).encode())
            continue
        if req["op"] == Op.SPAWN and len(fds) == 3:
            req_r, resp_w, event_w = fds
            pid = os.fork()
            if pid == 0:  # the child: never returns
                try:
                    os.setsid()
                    keep = keep_base | {req_r, resp_w, event_w}
                    for fd in map(int, os.listdir("/proc/self/fd")):
                        if fd not in keep:
                            with contextlib.suppress(OSError):
                                os.close(fd)
                    os.dup2(event_w, setup.event_fd)  # the number the tripwires write to
                    os.close(event_w)
                    runner.child_main(req_r, resp_w, req["tmpdir"], setup)
                finally:
                    os._exit(5)
            for fd in fds:
                os.close(fd)
            pidfd = None
            with contextlib.suppress(OSError, AttributeError):
                pidfd = os.pidfd_open(pid)
            reply = json.dumps({"pid": pid}).encode()
            if pidfd is not None:
                socket.send_fds(sock, [reply], [pidfd])
                os.close(pidfd)
            else:
                sock.send(reply)
        elif req["op"] == Op.STATUS:
            pid = int(req["pid"])
            deadline = time.monotonic() + 5
            while pid not in statuses and time.monotonic() < deadline:
                try:
                    got, status = os.waitpid(pid, os.WNOHANG)
                except ChildProcessError:
                    break
                if got == pid:
                    statuses[pid] = status
                    break
                time.sleep(0.01)
            sock.send(json.dumps({"status": statuses.pop(pid, None)}).encode())
        else:
            for fd in fds:
                os.close(fd)
            sock.send(b'{"error": "unknown op"}')


if __name__ == "__main__":
    _server_main(int(sys.argv[1]), sys.argv[2])
