"""``course grade ... --cluster ADDRESS``: one task per student on a Dask distributed scheduler.

For a class of thousands, the batch driver (:mod:`course.grading.batch.driver`) stays where it is:
it finds the submissions, reads each notebook (refusing links), and writes ``grades.csv``,
``feedback/`` and the resumable ``results.jsonl`` as rows stream back. The grading itself runs
on the cluster's workers (:mod:`course.grading.batch.clusterworker`): each worker process keeps
its own warm :class:`~course.grading.batch.session.AssignmentGrader` (checks loaded once,
references computed once, one fork server with every isolation layer) for all the students it
is given.

What travels to a worker: the assignment's authoring files (once per worker, in a worker
plugin that deletes them when the run ends), the grading options, the class key's public id,
and per task one student's notebook bytes and that student's data seeds, derived from the key
here. The class key itself never leaves this process.

How it travels: to a remote scheduler over TLS (``tls://``, with the CA, certificate and key
files of :class:`ConnectionFiles`, as :class:`distributed.security.Security`); a plain
``tcp://`` address is accepted only on this machine (loopback) unless the instructor passes
``insecure`` (``course grade --insecure-cluster``).

Requires the ``distributed`` package (``pip install "residual-validation-course[cluster]"``);
every worker needs the course package at the same version (the rows record it). The
instructors' guide is ``docs/instructors/cluster.md``.
"""

from __future__ import annotations

import hashlib
import ipaddress
import warnings
from dataclasses import dataclass
from itertools import islice
from pathlib import Path
from urllib.parse import urlsplit

from course.grading.authoring.secret import KEY_FILE_PREFIX
from course.grading.notebook import SubmissionError, read_notebook_bytes

__all__ = ["ClusterError", "ConnectionFiles", "cluster_target", "grade_on_cluster"]

#: Options a worker needs (not the driver's callbacks, jobs, key or the cluster address).
_WORKER_OPTIONS = (
    "timeout",
    "memory_mb",
    "ready_timeout",
    "student_budget",
    "unsafe_no_isolation",
    "namespaces",
    "landlock",
)

_ENCRYPTED = frozenset({"tls", "wss"})
_NO_DISTRIBUTED = (
    '--cluster needs the distributed package: pip install "residual-validation-course[cluster]"'
)


class ClusterError(ValueError):
    """The cluster address or its TLS files cannot be used as given (the message says why)."""


@dataclass(frozen=True)
class ConnectionFiles:
    """The TLS files of the connection to the scheduler: the certificate authority that signed
    the scheduler's certificate, and this client's certificate and key (``key`` None: the key
    is in the certificate file). Dask's TLS is mutual: the scheduler checks the client too."""

    ca_file: Path | None = None
    cert: Path | None = None
    key: Path | None = None

    @property
    def given(self) -> bool:
        return any(f is not None for f in (self.ca_file, self.cert, self.key))

    def security(self):
        """A :class:`distributed.security.Security` requiring encryption with these files."""
        try:
            from distributed.security import Security
        except ImportError:  # pragma: no cover - depends on the installation
            raise RuntimeError(_NO_DISTRIBUTED) from None
        missing = [
            flag
            for flag, value in (("--tls-ca-file", self.ca_file), ("--tls-cert", self.cert))
            if value is None
        ]
        if missing:
            raise ClusterError(
                f"a TLS connection needs {' and '.join(missing)} (the CA that signed the "
                "scheduler's certificate, and this client's certificate; --tls-key if its key "
                "is in a file of its own)"
            )
        for flag, value in (
            ("--tls-ca-file", self.ca_file),
            ("--tls-cert", self.cert),
            ("--tls-key", self.key),
        ):
            if value is not None and not Path(value).is_file():
                raise ClusterError(f"{flag} {value}: no such file")
        return Security(
            tls_ca_file=str(self.ca_file),
            tls_client_cert=str(self.cert),
            tls_client_key=str(self.key) if self.key is not None else None,
            require_encryption=True,
        )


def _is_loopback(host: str) -> bool:
    host = host.strip("[]")
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False  # a host name: it may resolve anywhere


def cluster_target(address, files: ConnectionFiles | None = None, insecure: bool = False):
    """``(address, security)`` to connect to, after the transport rules: TLS to a remote
    scheduler, plain ``tcp://`` only on loopback or with ``insecure``.

    ``address`` is a scheduler address (``tls://host:8786``, ``tcp://127.0.0.1:8786``, or
    ``host:8786``, which means TLS when TLS files are given) or a Dask cluster object (its own
    security is used). Raises :class:`ClusterError` with what to do otherwise.
    """
    files = files or ConnectionFiles()
    is_cluster = hasattr(address, "scheduler_address")  # LocalCluster, SSHCluster, ...
    if is_cluster:
        if files.given:
            raise ClusterError("a cluster object brings its own security: give no TLS files")
        text = str(address.scheduler_address)
    else:
        text = str(address).strip()
        if "://" not in text:
            text = ("tls://" if files.given else "tcp://") + text
    parts = urlsplit(text)
    scheme, host = parts.scheme.lower(), parts.hostname or ""
    if scheme in _ENCRYPTED:
        return (address, None) if is_cluster else (text, files.security())
    if files.given:
        raise ClusterError(
            f"--cluster {text}: TLS files are given but the address is {scheme}://, which is "
            f"not encrypted; use tls://{parts.netloc}"
        )
    if scheme == "inproc" or _is_loopback(host) or insecure:
        return (address if is_cluster else text), None
    raise ClusterError(
        f"refusing to send the class's submissions and assignment files to {text} unencrypted: "
        f"{scheme}:// is only accepted on this machine (localhost). Start the scheduler with "
        "TLS and pass tls://HOST:PORT with --tls-ca-file, --tls-cert and --tls-key, or pass "
        "--insecure-cluster if the network itself is private and trusted "
        "(docs/instructors/cluster.md)"
    )


def check_cluster_options(options) -> None:
    """Refuse early (:class:`ClusterError`) an address or TLS files that cannot be used."""
    if options.cluster:
        cluster_target(options.cluster, options.cluster_files, options.insecure_cluster)


# -- driver side ----------------------------------------------------------------------------------
def _bundle(solution_dir: Path, secret=None) -> dict[str, bytes]:
    """The assignment's authoring files, relative path -> bytes; refuses (:class:`ClusterError`)
    a folder that holds a key file or the class's key, which would travel with it."""
    bundle = {
        p.relative_to(solution_dir).as_posix(): p.read_bytes()
        for p in sorted(solution_dir.rglob("*"))
        if p.is_file() and "__pycache__" not in p.parts
    }
    needles = [KEY_FILE_PREFIX.encode()]
    if secret is not None:
        needles += [secret.key, secret.key.hex().encode()]
    for rel, content in bundle.items():
        if any(needle in content for needle in needles):
            raise ClusterError(
                f"{solution_dir / rel} holds a class key, and the assignment's folder travels to "
                "every worker: keep key files outside the course folder"
            )
    return bundle


def _client(address, files: ConnectionFiles | None, insecure: bool):
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - depends on the installation
        raise RuntimeError(_NO_DISTRIBUTED) from None
    target, security = cluster_target(address, files, insecure)
    return Client(target, security=security) if security is not None else Client(target)


def _plugin_name(grader, bundle: dict, worker_options: dict) -> str:
    digest = hashlib.sha256(repr((sorted(bundle.items()), sorted(worker_options.items()))).encode())
    return f"course-grade-{grader.name}-{digest.hexdigest()[:12]}"


def grade_on_cluster(address, grader, pending: list, options):
    """Rows of ``pending`` submissions, graded on the Dask cluster at ``address``, as they
    finish. ``grader`` is the driver's own grader: its files, its key id and, per student, the
    data seeds it derives from the key are what the workers get (never the key)."""
    from distributed import as_completed

    from course.grading.batch.clusterworker import AssignmentFiles, describe_task, grade_task

    worker_options = {k: getattr(options, k) for k in _WORKER_OPTIONS}
    client = _client(address, options.cluster_files, options.insecure_cluster)
    plugin = None
    try:
        bundle = _bundle(grader.solution_dir, grader.secret)
        plugin = AssignmentFiles(
            _plugin_name(grader, bundle, worker_options),
            grader.name,
            bundle,
            worker_options,
            grader.data_key,
        )
        client.register_plugin(plugin)
        # every worker present builds its grader first: a worker whose kernel has no walls
        # refuses (IsolationError) before any student is sent
        worker_info = client.scheduler_info()["workers"]
        workers = list(worker_info)
        described = client.gather(
            [
                client.submit(
                    describe_task,
                    plugin.name,
                    workers=[w],
                    allow_other_workers=False,
                    pure=False,
                    key=f"describe-{plugin.name}-{i}",
                )
                for i, w in enumerate(workers)
            ]
        )
        if options.announce is not None:
            for text in sorted(set(described)):
                count = sum(1 for t in described if t == text)
                options.announce(f"{count} worker(s) at {client.scheduler.address}: {text}")

        students: dict = {}  # future -> its student

        def submit(sub):
            future = _submit(sub)
            students[future] = sub.student
            return future

        def _submit(sub):
            raw, note, refused = None, sub.note, sub.refused
            if sub.path is not None:
                try:
                    raw = read_notebook_bytes(sub.path)  # read here: links were refused here
                except SubmissionError as exc:
                    note = str(exc)
            return client.submit(
                grade_task,
                plugin.name,
                sub.student,
                raw,
                note,
                refused,
                grader.student_seeds(sub.student),
                key=f"grade-{grader.name}-{sub.student}-{hashlib.sha1(raw or b'').hexdigest()[:10]}",
                pure=False,
                retries=1,
            )

        # A bounded window of submissions in flight: each holds up to a 50 MB notebook in this
        # process until its task is done, so reading the whole class first would grow the
        # driver with the class's size; two tasks per worker thread keep every worker busy.
        threads = sum(w.get("nthreads", 1) for w in worker_info.values())
        waiting = iter(pending)
        running = as_completed([submit(sub) for sub in islice(waiting, 2 * max(threads, 1))])
        for future in running:
            try:
                yield future.result()
            except Exception as exc:  # a lost worker, a failed task: a fault, never a grade
                yield grader.fault_row(students[future], exc)
            students.pop(future, None)
            following = next(waiting, None)
            if following is not None:
                running.add(submit(following))
    finally:
        try:
            if plugin is not None:  # every worker deletes the files it was given
                client.unregister_worker_plugin(plugin.name)
        except Exception as exc:  # the grades stand; the instructor must hear of the files
            message = (
                f"a worker could not delete the assignment's files it was given "
                f"({type(exc).__name__}: {exc}); remove them by hand"
            )
            if options.announce is not None:
                options.announce(message)
            else:
                warnings.warn(message, RuntimeWarning, stacklevel=2)
        finally:
            client.close()
