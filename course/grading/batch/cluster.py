"""``course grade ... --cluster ADDRESS``: one task per student on a Dask distributed scheduler.

For a class of thousands, the batch driver (:mod:`course.grading.batch.driver`) stays where it is:
it finds the submissions, reads each notebook (refusing links), and writes ``grades.csv``,
``feedback/`` and the resumable ``results.jsonl`` as rows stream back. The grading itself runs
on the cluster's workers: each task carries one student's notebook bytes, and each worker
process keeps its own warm :class:`~course.grading.batch.session.AssignmentGrader` (checks loaded
once, references computed once, one fork server with every isolation layer) for all the
students it is given. The assignment's authoring files travel once per worker, as bytes, and
are written to a private temporary folder there (no shared file system needed).

Requires the ``distributed`` package (``pip install "residual-validation-course[cluster]"``);
every worker needs the course package at the same version (the rows record it).
"""

from __future__ import annotations

import atexit
import hashlib
import tempfile
import threading
from pathlib import Path

from course.grading.batch.options import GradeOptions
from course.grading.batch.session import AssignmentGrader
from course.grading.notebook import SubmissionError, read_notebook_bytes

__all__ = ["grade_on_cluster"]

#: Options a worker needs (not the driver's callbacks, jobs or the cluster address).
_WORKER_OPTIONS = (
    "timeout",
    "memory_mb",
    "ready_timeout",
    "student_budget",
    "unsafe_no_isolation",
    "namespaces",
    "landlock",
    "secret",  # a graded class's key: workers draw the same personal data
)

# -- worker side ---------------------------------------------------------------------------------
_GRADERS: dict = {}
_LOCK = threading.Lock()


def _worker_grader(bundle: dict, name: str, options: dict):
    """This worker process's grader for the assignment (created on its first student)."""
    key = (name, hashlib.sha256(repr(sorted(bundle.items())).encode()).hexdigest(), repr(options))
    with _LOCK:
        grader = _GRADERS.get(key)
        if grader is None:
            folder = Path(tempfile.mkdtemp(prefix="course-grade-assignment-")) / name
            for rel, content in bundle.items():
                target = folder / rel
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_bytes(content)
            grader = AssignmentGrader(folder, GradeOptions(**options), deny_read=[folder.parent])
            _GRADERS[key] = grader
            atexit.register(grader.close)
        return grader


def _grade_task(bundle, name, options, student, raw, note, refused):
    """One student, on a worker: the same row as a local run."""
    grader = _worker_grader(bundle, name, options)
    return grader.grade_one(student, None, note, refused, raw)


def _describe(bundle, name, options) -> str:
    grader = _worker_grader(bundle, name, options)
    return grader.sandbox.isolation.describe()


# -- driver side ----------------------------------------------------------------------------------
def _bundle(solution_dir: Path) -> dict[str, bytes]:
    """The assignment's authoring files, relative path -> bytes."""
    return {
        p.relative_to(solution_dir).as_posix(): p.read_bytes()
        for p in sorted(solution_dir.rglob("*"))
        if p.is_file() and "__pycache__" not in p.parts
    }


def _client(address):
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - depends on the installation
        raise RuntimeError(
            "--cluster needs the distributed package: "
            'pip install "residual-validation-course[cluster]"'
        ) from None
    if hasattr(address, "scheduler_address"):  # a Cluster object (e.g. a LocalCluster in tests)
        return Client(address)
    return Client(str(address))


def grade_on_cluster(address, grader, pending: list, options):
    """Rows of ``pending`` submissions, graded on the Dask cluster at ``address``, as they
    finish. ``grader`` is the driver's own (local) grader: only its checks and folder are used."""
    from distributed import as_completed

    worker_options = {k: getattr(options, k) for k in _WORKER_OPTIONS}
    client = _client(address)
    try:
        bundle = client.scatter(_bundle(grader.solution_dir), broadcast=True, hash=False)
        if options.announce is not None:
            described = client.run(
                _describe, _bundle(grader.solution_dir), grader.name, worker_options
            )
            for text in sorted(set(described.values())):
                workers = sum(1 for t in described.values() if t == text)
                options.announce(f"{workers} worker(s) at {client.scheduler.address}: {text}")
        futures = []
        for sub in pending:
            raw, note, refused = None, sub.note, sub.refused
            if sub.path is not None:
                try:
                    raw = read_notebook_bytes(sub.path)  # read here: links were refused here
                except SubmissionError as exc:
                    note = str(exc)
            futures.append(
                client.submit(
                    _grade_task,
                    bundle,
                    grader.name,
                    worker_options,
                    sub.student,
                    raw,
                    note,
                    refused,
                    key=f"grade-{grader.name}-{sub.student}-{hashlib.sha1(raw or b'').hexdigest()[:10]}",
                    pure=False,
                    retries=1,
                )
            )
        for future in as_completed(futures):
            yield future.result()
    finally:
        client.close()
