"""The sandboxed child that runs ONE student's notebook for the grader.

It is forked from the warm fork server (:mod:`course.grading.sandbox.forkserver`):

1. :func:`prepare` (once per fork server) imports the library, instruments forbidden
   functions and opens the Landlock allow-list;
2. the child moves into its fresh temporary directory, scrubs its environment, sends its own
   stdout and stderr to a capped file there, and reads the ``init`` request from the grader;
3. it switches to ``nobody`` if that is its job, sets resource limits, turns on the silent
   grading stand-in for ``check``, then confines itself with Landlock, installs the seccomp
   filter and the audit hook (all irreversible) — only then does student code run;
4. it answers requests, one JSON line each, on its dedicated response pipe: ``run`` a cell
   (IPython semantics, magics work), ``value`` of a variable, ``call`` a function with
   arguments. Values travel as plain data (:mod:`course.grading.codec`), never pickle.

Nothing here decides a score: the trusted parent compares values with references it computes
itself, so a child that lies can only misreport its own answers.
"""

from __future__ import annotations

import base64  # noqa: F401  (imported before student code, used by the codec)
import contextlib
import importlib.abc
import importlib.util
import json
import os
import signal
import sys
import typing
from builtins import (  # bound now, so a student patching builtins cannot break the protocol
    BaseException,
    Exception,
    NotImplementedError,
    callable,
    dict,
    getattr,
    int,
    len,
    list,
    str,
    type,
)
from dataclasses import dataclass, field

from course.grading import codec
from course.grading.notebook import MAX_NOTEBOOK_BYTES, SubmissionError, reduce_notebook
from course.grading.sandbox.isolation.audit import close_leaked, make_audit_hook, open_fds
from course.grading.sandbox.isolation.limits import set_limits
from course.grading.tripwire import course_modules, label_callers
from course.grading.vocabulary import Op, ReplyStatus

_dumps = json.dumps
_loads = json.loads
_write = os.write
_encode = codec.encode
_decode = codec.decode

# plain strings (not enum members) in replies: nothing student code patches can change them
_OK, _ERROR, _READY = ReplyStatus.OK.value, ReplyStatus.ERROR.value, ReplyStatus.READY.value
_UNDEFINED, _STUB = ReplyStatus.UNDEFINED.value, ReplyStatus.STUB.value
_NOT_CALLABLE, _UNENCODABLE = ReplyStatus.NOT_CALLABLE.value, ReplyStatus.UNENCODABLE.value

OUTPUT_FILE = "output.txt"
READ_FILE = "submission.ipynb"  # the notebook a reader child decodes (copied in by the parent)
MAX_RESPONSE_BYTES = 64_000_000


_PROTECTED_MODULES = (
    "builtins",
    "json",
    "json.decoder",
    "json.encoder",
    "json.scanner",
    "base64",
    "binascii",
    "math",
    "numpy",
    "course.grading.codec",
)


class _Trusted:
    """Snapshot of the modules the protocol relies on, taken before student code runs.

    While the runner encodes or decodes, it puts the snapshot's objects back (and afterwards
    restores whatever the student had patched), so patching ``json.dumps``, ``numpy.asarray``
    or ``builtins.len`` breaks only the student's own code, not the channel.
    """

    def __init__(self):
        self.snapshots = [
            (vars(sys.modules[name]), dict(vars(sys.modules[name])))
            for name in _PROTECTED_MODULES
            if name in sys.modules
        ]
        self._changes = []

    def __enter__(self):
        changes = []
        for live, snap in self.snapshots:
            for key, value in snap.items():
                current = live.get(key, _MISSING)
                if current is not value:
                    changes.append((live, key, current))
                    live[key] = value
        self._changes.append(changes)
        return self

    def __exit__(self, *exc):
        for live, key, value in reversed(self._changes.pop()):
            if value is _MISSING:
                live.pop(key, None)
            else:
                live[key] = value
        return False


_MISSING = object()
_TRUSTED: typing.Any = (
    contextlib.nullcontext()
)  # replaced by a _Trusted snapshot before student code runs


class CappedWriter:
    """A text stream that keeps the first ``limit`` characters and silently drops the rest."""

    def __init__(self, fd: int, limit: int):
        self._fd = fd
        self._left = limit
        self.dropped = 0
        self.encoding = "utf-8"
        self.errors = "replace"

    def write(self, text) -> int:
        text = str(text)
        if self._left > 0:
            chunk = text[: self._left]
            self._left -= len(chunk)
            try:
                _write(self._fd, chunk.encode("utf-8", "replace"))
            except OSError:
                self._left = 0
        self.dropped += max(0, len(text) - max(self._left, 0))
        return len(text)

    def writelines(self, lines) -> None:
        for line in lines:
            self.write(line)

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return False

    def fileno(self) -> int:
        return self._fd

    @property
    def closed(self) -> bool:
        return False

    def writable(self) -> bool:
        return True

    def readable(self) -> bool:
        return False


# --------------------------------------------------------------------------------------
# process setup (trusted: runs before any student code)
# --------------------------------------------------------------------------------------
def child_environment(tmpdir: str) -> dict:
    """The scrubbed environment of a grading child."""
    env = {
        "PATH": "/usr/bin:/bin",
        "HOME": tmpdir,
        "TMPDIR": tmpdir,
        "LANG": "C.UTF-8",
        "LC_ALL": "C.UTF-8",
        "MPLBACKEND": "Agg",
        "MPLCONFIGDIR": os.path.join(tmpdir, ".matplotlib"),
        "IPYTHONDIR": os.path.join(tmpdir, ".ipython"),
        "OPENBLAS_NUM_THREADS": "1",
        "OMP_NUM_THREADS": "1",
        "MKL_NUM_THREADS": "1",
        "PYTHONDONTWRITEBYTECODE": "1",
        "PYTHONHASHSEED": "0",
    }
    return env


def enter_sandbox_dir(tmpdir: str) -> None:
    """chdir into the temp dir, replace the environment, point fds 0/1/2 at /dev/null and the
    capped output file."""
    os.chdir(tmpdir)
    os.umask(0o077)
    os.environ.clear()
    os.environ.update(child_environment(tmpdir))
    devnull = os.open(os.devnull, os.O_RDONLY)
    os.dup2(devnull, 0)
    os.close(devnull)
    out = os.open(os.path.join(tmpdir, OUTPUT_FILE), os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    os.dup2(out, 1)
    os.dup2(out, 2)
    os.close(out)
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    signal.signal(signal.SIGCHLD, signal.SIG_DFL)
    signal.signal(
        signal.SIGXFSZ, signal.SIG_IGN
    )  # over-long files fail with EFBIG instead of killing us


def make_shell():
    """A plain IPython shell (no history database, no colours): IPython semantics for cells."""
    from IPython.core.interactiveshell import InteractiveShell
    from traitlets.config import Config

    config = Config()
    config.HistoryManager.enabled = False
    config.InteractiveShell.colors = "NoColor"
    config.InteractiveShell.autocall = 0
    config.InteractiveShell.xmode = "Plain"
    shell = InteractiveShell.instance(config=config)

    def _noop_magic(line="", cell=None):
        return None

    for magic in ("matplotlib", "pylab"):
        shell.register_magic_function(_noop_magic, "line", magic)  # type: ignore[arg-type]
    return shell


PRELOAD = (
    "numpy",
    "scipy",
    "scipy.linalg",
    "scipy.stats",
    "scipy.optimize",
    "matplotlib",
    "matplotlib.pyplot",
    "IPython.core.interactiveshell",
    "course",
    "course.results",
    "course.linalg",
    "course.lsq",
    "course.grading.student.selfcheck",
)


def preload(modules=PRELOAD) -> list:
    """Import modules now (trusted, before limits and the hook); returns those that failed."""
    import importlib

    os.environ.setdefault("MPLBACKEND", "Agg")
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    failed = []
    for name in modules:
        try:
            importlib.import_module(name)
        except Exception:
            failed.append(name)
    return failed


class ReleasedData(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """The import of ``data``: the ``data.py`` released beside the student's notebook, so that
    ``from data import ...`` works at grading as at self-check (the child's folder holds no
    file of it, and nothing of it can be changed there: the module is made from the text the
    grader sent, when the notebook first imports it)."""

    NAME = "data"

    def __init__(self, source: str):
        self.source = source

    def find_spec(self, fullname, path=None, target=None):
        if fullname != self.NAME:
            return None
        return importlib.util.spec_from_loader(fullname, self, origin="data.py")

    def create_module(self, spec):
        return None  # the default module object

    def exec_module(self, module) -> None:
        module.__file__ = "data.py"
        exec(compile(self.source, "data.py", "exec"), module.__dict__)


def offer_released_data(source) -> None:
    """Make ``import data`` find the released ``data.py`` (``source``; None: there is none).
    First on the import path, as the notebook's own folder is in the student's kernel."""
    if isinstance(source, str) and source:
        sys.meta_path.insert(0, ReleasedData(source))


# --------------------------------------------------------------------------------------
# the request loop
# --------------------------------------------------------------------------------------
def _value_reply(value) -> dict:
    """The reply carrying an answer (a variable's value or a function's result): ``...`` is a
    stub left unanswered; anything the codec cannot carry is reported, not raised."""
    if value is Ellipsis:
        return {"status": _STUB}
    try:
        with _TRUSTED:
            return {"status": _OK, "value": _encode(value)}
    except BaseException as exc:
        return {"status": _UNENCODABLE, "error": _error_info(exc)}


def _error_info(exc) -> dict:
    message = str(exc)
    info: dict = {"type": type(exc).__name__, "message": message[:500]}
    # the line number in the student's own cell code where it was raised (the parent shows
    # that line from the source it holds; the last frame of a cell's code, "<...>" files)
    tb, line = exc.__traceback__, None
    while tb is not None:
        if tb.tb_frame.f_code.co_filename.startswith("<"):
            line = tb.tb_lineno
        tb = tb.tb_next
    if line is not None:
        info["line"] = line
    return info


class RequestLoop:
    """The child's side of the protocol: answers the grader's requests, one JSON line each."""

    def __init__(self, req_fd: int, resp_fd: int):
        self.requests = os.fdopen(req_fd, "rb", buffering=1 << 16)
        self.resp_fd = resp_fd
        self.shell: typing.Any = None  # the IPython shell, made before student code
        self.refused = False  # set by the audit hook when it refuses an event
        # answer functions as their answer cells left them (the graded ones), by name
        self.captured: dict = {}
        self.callers: dict = {}  # the tripwires' labels of calling code (its question)

    def note_refusal(self) -> None:
        self.refused = True

    def send(self, obj: dict) -> None:
        with _TRUSTED:
            data = (_dumps(obj, allow_nan=False, separators=(",", ":")) + "\n").encode("utf-8")
        view = memoryview(data)
        while view:
            n = _write(self.resp_fd, view)
            view = view[n:]

    def receive(self):
        line = self.requests.readline(MAX_RESPONSE_BYTES)
        if not line:
            return None
        with _TRUSTED:
            return _loads(line)

    # -- operations ---------------------------------------------------------------------
    def op_run(self, req):
        try:
            result = self.shell.run_cell(req["source"], store_history=False, silent=False)
            error = result.error_before_exec or result.error_in_exec
        except BaseException as exc:  # run_cell normally catches everything itself
            error = exc
        sys.stdout.flush()
        ns = self.shell.user_ns
        for name, question in req.get("capture") or ():  # what an answer cell defined
            if isinstance(name, str) and callable(ns.get(name)):
                self.captured[name] = ns[name]  # graded, and its calls are its question's
                label_callers(self.callers, ns[name], str(question))
        reply: dict = {"status": _OK if error is None else _ERROR}
        if error is not None:
            reply["error"] = _error_info(error)
        return reply

    def op_read(self, req):
        """Decode the submission the parent copied into this folder and send back the part the
        grader reads (:func:`~course.grading.notebook.reduce_notebook`): a notebook that costs
        gigabytes to decode costs them here, under this child's limits, never in the parent.
        Only a reader child (no student code ever runs in it) gets this request."""
        try:
            fd = os.open(READ_FILE, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
            with os.fdopen(fd, "rb") as f:
                raw = f.read(MAX_NOTEBOOK_BYTES + 1)
            os.unlink(READ_FILE)
            if len(raw) > MAX_NOTEBOOK_BYTES:
                raise SubmissionError(
                    f"the notebook is larger than {MAX_NOTEBOOK_BYTES // 1_000_000} MB"
                )
            if not raw.strip():
                raise SubmissionError("the notebook file is empty")
            text = raw.decode("utf-8", errors="replace")
            del raw
            try:
                nb = _loads(text)
            except ValueError as exc:
                where = f" at line {exc.lineno}" if hasattr(exc, "lineno") else ""
                raise SubmissionError(
                    f"the notebook is not valid JSON ({getattr(exc, 'msg', exc)}{where})"
                ) from None
            except RecursionError:
                raise SubmissionError(
                    "the notebook is not valid JSON (too deeply nested)"
                ) from None
            del text
            return {"status": _OK, "notebook": reduce_notebook(nb)}
        except SubmissionError as exc:
            return {"status": _ERROR, "error": {"type": "SubmissionError", "message": str(exc)}}
        except MemoryError:
            return {
                "status": _ERROR,
                "error": {
                    "type": "SubmissionError",
                    "message": "the notebook is too large to read within the grader's memory "
                    "limit (clear its outputs and submit again)",
                },
            }

    def op_value(self, req):
        ns = self.shell.user_ns
        name = req["name"]
        if name not in ns:
            return {"status": _UNDEFINED}
        return _value_reply(ns[name])

    def op_call(self, req):
        """Call the answer function ``name``: the one its answer cell defined when the parent
        asked to capture it there (a later redefinition is reported, ``redefined``, not
        called), else the notebook's current one."""
        ns = self.shell.user_ns
        name = req["name"]
        if name in self.captured:
            func = self.captured[name]
            redefined = ns.get(name, _MISSING) is not func
            reply = self._call(func, req)
            if redefined:
                reply["redefined"] = True
            return reply
        func = ns.get(name)
        if func is None and name not in ns:
            return {"status": _UNDEFINED}
        return self._call(func, req)

    def _call(self, func, req) -> dict:
        if not callable(func):
            return {"status": _NOT_CALLABLE, "error": {"type": type(func).__name__, "message": ""}}
        try:
            with _TRUSTED:
                args = _decode(req["args"], False)
                kwargs = _decode(req["kwargs"], False)
        except BaseException as exc:
            return {"status": _ERROR, "error": _error_info(exc)}
        try:
            out = func(*args, **kwargs)
        except NotImplementedError:
            return {"status": _STUB}
        except BaseException as exc:  # includes SystemExit and KeyboardInterrupt from student code
            return {"status": _ERROR, "error": _error_info(exc)}
        return _value_reply(out)

    def serve(self) -> None:
        while True:
            try:
                req = self.receive()
            except BaseException:
                return
            if req is None or req.get("op") == Op.EXIT.value:
                return
            op = getattr(self, "op_" + str(req.get("op")), None)
            before = open_fds()
            self.refused = False
            try:
                reply = (
                    op(req)
                    if op is not None
                    else {"status": _ERROR, "error": {"type": "Protocol", "message": "unknown op"}}
                )
            except BaseException as exc:
                reply = {"status": _ERROR, "error": _error_info(exc)}
            if self.refused:  # e.g. socket.socketpair(): refused after the sockets existed
                close_leaked(before, keep=(self.resp_fd,))
            reply["id"] = req.get("id")
            reply["nonce"] = req.get("nonce")
            try:
                self.send(reply)
            except BaseException:
                try:
                    self.send(
                        {
                            "id": req.get("id"),
                            "nonce": req.get("nonce"),
                            "status": _ERROR,
                            "error": {"type": "Protocol", "message": "reply could not be encoded"},
                        }
                    )
                except BaseException:
                    return


@dataclass
class Setup:
    """What :func:`prepare` made ready for every child of one fork server."""

    event_fd: int
    landlock_abi: int = 0
    policy: typing.Any = None  # a landlock.Policy, or None
    seccomp: bool = True
    drop_child: tuple[int, int] | None = None  # each child switches to this (uid, gid)
    unprivileged: bool = False
    tripwires: dict = field(default_factory=dict)
    callers: dict = field(default_factory=dict)  # read by the tripwires (label_callers)

    def policy_fds(self) -> list[int]:
        return self.policy.fds() if self.policy is not None else []


def prepare(config: dict) -> Setup:
    """Everything before any child exists (trusted; once per fork server)."""
    from course.grading import tripwire
    from course.grading.sandbox.isolation import landlock, privileges, seccomp
    from course.grading.sandbox.isolation.paths import python_paths

    if config.get("seccomp", True):
        seccomp.available()  # loads libseccomp once, for every child, while files are readable

    drop_to = tuple(config["drop_to"]) if config.get("drop_to") else None
    unprivileged = os.geteuid() != 0
    if drop_to and config.get("drop_in_server"):
        privileges.drop(drop_to)  # inside bubblewrap: every path it needs is traversable
        unprivileged = True
    event_fd = os.open(os.devnull, os.O_WRONLY)  # reserves the number; a child dup2s onto it
    preload(tuple(config.get("preload", PRELOAD)) + tuple(course_modules()))
    callers: dict = {}
    tripwires = tripwire.instrument(config.get("forbid", ()), event_fd, callers)
    policy = None
    if config.get("landlock"):
        policy = landlock.Policy()
        for path in config.get("read", ()):
            policy.allow(path, landlock.READ_ONLY)
        for path in config.get("devices", ()):
            policy.allow(path, landlock.DEVICE)
    drop_child = None
    if (
        drop_to
        and not config.get("drop_in_server")
        and privileges.readable_by(drop_to, config.get("read") or python_paths())
    ):
        drop_child, unprivileged = drop_to, True
    return Setup(
        event_fd=event_fd,
        landlock_abi=int(config.get("landlock") or 0),
        policy=policy,
        seccomp=bool(config.get("seccomp", True)),
        drop_child=drop_child,
        unprivileged=unprivileged,
        tripwires=tripwires,
        callers=callers,
    )


def child_main(req_fd: int, resp_fd: int, tmpdir: str, setup: Setup, shell=None) -> None:
    """Everything the child does after it exists (both modes); never returns normally."""
    code = 0
    try:
        enter_sandbox_dir(tmpdir)
        child = RequestLoop(req_fd, resp_fd)
        child.callers = setup.callers
        init = child.receive()
        if not init or init.get("op") != Op.INIT.value:
            os._exit(3)
        limits = init.get("limits", {})
        from course.grading.sandbox.isolation import landlock, privileges, seccomp
        from course.grading.student import selfcheck

        if setup.drop_child is not None:
            privileges.drop(setup.drop_child)
        elif os.geteuid() == 0:  # a root child: root's user ID, none of its powers
            privileges.drop_capabilities()
        use_seccomp = bool(limits.get("seccomp", True)) and setup.seccomp and seccomp.available()
        if not use_seccomp:
            limits = dict(limits, nproc=0)  # only a backstop for non-root users
        set_limits(limits)
        sys.dont_write_bytecode = True
        if not init.get("reader"):  # a reader child decodes a notebook and runs no cell
            child.shell = shell or make_shell()
        selfcheck._GRADING = {"student_id": init["student_id"], "data": init.get("data", {})}
        offer_released_data(init.get("data_module"))
        cap = int(limits.get("output_chars", 1_000_000))
        sys.stdout = CappedWriter(1, cap)
        sys.stderr = CappedWriter(2, cap // 4)
        import warnings

        warnings.simplefilter("default")
        global _TRUSTED
        _TRUSTED = _Trusted()
        seccomp.die_with_parent()
        abi = 0
        if setup.policy is not None:  # ctypes, like seccomp: before the audit hook
            setup.policy.allow(tmpdir, landlock.READ_WRITE)
            setup.policy.allow(f"/proc/{os.getpid()}", landlock.READ_ONLY)
            abi = landlock.confine(setup.policy, setup.landlock_abi)
            setup.policy.close()
        secure = seccomp.install(pinned_fd=setup.event_fd) if use_seccomp else False
        sys.addaudithook(
            make_audit_hook(tmpdir, init.get("deny_read", ()), on_refuse=child.note_refusal)
        )
        child.send(
            {
                "id": init.get("id"),
                "nonce": init.get("nonce"),
                "status": _READY,
                "seccomp": bool(secure),
                "landlock": abi,
                "uid": os.getuid(),
                "pid": os.getpid(),
            }
        )
        child.serve()
    except BaseException:
        code = 4
        try:
            import traceback

            os.write(2, traceback.format_exc().encode("utf-8", "replace"))
        except BaseException:
            pass
    finally:
        os._exit(code)
