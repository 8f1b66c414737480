"""The warm fork server: ``python -m course.grading.forkserver SOCK_FD PRELOAD_JSON``.

Started once per :class:`~course.grading.sandbox.Sandbox`, it imports the scientific stack and
the course library, then forks one child per request of the grader (received on a UNIX
socket together with the child's two pipe ends). It never runs student code itself; its children
run :func:`course.grading.runner.child_main` and never return.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import sys
import time

__all__: list[str] = []


def _server_main(sock_fd: int, preload_json: str) -> None:
    from course.grading import runner
    from course.grading.isolation import seccomp
    from course.grading.vocabulary import Op

    seccomp.die_with_parent()
    if os.getppid() == 1:  # the grader is already gone
        return
    sock = socket.socket(fileno=sock_fd)
    runner.preload(json.loads(preload_json))
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

    sock.send(json.dumps({"status": "ready"}).encode())
    while True:
        try:
            msg, fds, _flags, _addr = socket.recv_fds(sock, 65536, 4)
        except OSError:
            break
        if not msg:
            break
        reap()
        req = json.loads(msg)
        if req["op"] == Op.SPAWN:
            req_r, resp_w = fds
            pid = os.fork()
            if pid == 0:  # the child: never returns
                try:
                    os.setsid()
                    keep = {0, 1, 2, req_r, resp_w}
                    for fd in (
                        map(int, os.listdir("/proc/self/fd"))
                        if os.path.isdir("/proc/self/fd")
                        else []
                    ):
                        if fd not in keep:
                            with contextlib.suppress(OSError):
                                os.close(fd)
                    if not os.path.isdir("/proc/self/fd"):
                        sock.close()
                    runner.child_main(req_r, resp_w, req["tmpdir"])
                finally:
                    os._exit(5)
            for fd in fds:
                os.close(fd)
            sock.send(json.dumps({"pid": pid}).encode())
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
