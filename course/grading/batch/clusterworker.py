"""The worker side of ``course grade --cluster`` (:mod:`course.grading.batch.cluster` is the
driver's side): imported only on a Dask worker and by the driver once it has a cluster, since it
needs the ``distributed`` package.

What a worker holds for one run is an :class:`AssignmentFiles` plugin: the released assignment's
authoring files (bytes), the worker's grading options and the class's public key id, never the
key. Each task brings one student's notebook bytes and that student's data seeds, derived from
the key by the driver. The plugin writes the files to a private temporary folder and builds its
:class:`~course.grading.batch.session.AssignmentGrader` (checks loaded, references computed, the
fork server started) on the first task, in the task's thread: a worker's event loop, which
answers the scheduler's heartbeats, never waits for that build. Nor for its imports: the worker
unpickles the plugin on its event loop, which imports this module, so this module imports only
what is light at its top and the grader's modules (nbformat's schema validator alone compiles
grammars for seconds) in the task's thread. When the run ends (the driver
unregisters the plugin) or the worker closes, :meth:`AssignmentFiles.teardown` stops the fork
server and deletes the folder with every file it was given.
"""

from __future__ import annotations

import asyncio
import atexit
import shutil
import tempfile
import threading
from pathlib import Path
from typing import TYPE_CHECKING

from distributed import WorkerPlugin, get_worker

if TYPE_CHECKING:  # imported in the task's thread, never on the worker's event loop
    from course.grading.batch.results import StudentResult
    from course.grading.batch.session import AssignmentGrader

__all__ = ["AssignmentFiles", "describe_task", "grade_task"]

#: The prefix of a worker's private folder of assignment files.
FOLDER_PREFIX = "course-grade-assignment-"


def build_grader(folder: Path, options: dict, data_key: str) -> AssignmentGrader:
    """The worker's grader of the assignment in ``folder`` (its own function so that a test can
    watch where and when the build happens); imports the grader's modules, in the caller's
    thread."""
    from course.grading.batch.options import GradeOptions
    from course.grading.batch.session import AssignmentGrader

    return AssignmentGrader(
        folder, GradeOptions(**options), deny_read=[folder.parent], data_key=data_key
    )


class AssignmentFiles(WorkerPlugin):
    """One assignment's files and grader on a worker, for one grading run.

    ``files`` maps paths relative to the assignment's folder to their bytes; ``options`` are
    the :class:`~course.grading.batch.options.GradeOptions` fields a worker needs (no key
    among them); ``data_key`` is the class key's public id, recorded in every row.
    """

    idempotent = False  # a plugin of the same name is replaced (its teardown runs first)

    def __init__(self, name: str, assignment: str, files: dict, options: dict, data_key: str):
        self.name = name
        self.assignment = assignment
        self.files = files
        self.options = options
        self.data_key = data_key

    def setup(self, worker) -> None:
        # Runs on the worker's event loop: nothing heavy here (see grader()).
        self._lock = threading.Lock()
        self._grader: AssignmentGrader | None = None
        self._folder: Path | None = None

    def grader(self) -> AssignmentGrader:
        """The grader, built on first use in the calling task's thread."""
        with self._lock:
            if self._grader is None:
                self._folder = Path(tempfile.mkdtemp(prefix=FOLDER_PREFIX))
                folder = self._folder / self.assignment
                for rel, content in self.files.items():
                    target = folder / rel
                    target.parent.mkdir(parents=True, exist_ok=True)
                    target.write_bytes(content)
                self._grader = build_grader(folder, self.options, self.data_key)
                atexit.register(self.close)  # a worker that ends without its teardown
            return self._grader

    def close(self) -> None:
        """Stop the grader's fork server and delete every file this plugin wrote (idempotent);
        raises OSError naming what could not be removed."""
        with self._lock:
            grader, folder = self._grader, self._folder
            self._grader = self._folder = None
        atexit.unregister(self.close)  # nor keep this run's files alive in a long-lived worker
        if grader is not None:
            grader.close()
        if folder is not None:
            _delete(folder)

    async def teardown(self, worker) -> None:
        # closing waits for a build in progress: off the event loop, like the build itself
        await asyncio.to_thread(self.close)


def _delete(folder: Path) -> None:
    """Remove ``folder`` and everything in it; OSError naming what is left otherwise."""
    shutil.rmtree(folder, ignore_errors=True)
    if folder.exists():
        left = sorted(str(p) for p in folder.rglob("*"))[:5]
        raise OSError(f"could not remove the assignment files in {folder}: {left}")


def _plugin(name: str) -> AssignmentFiles:
    plugin = get_worker().plugins.get(name)
    if not isinstance(plugin, AssignmentFiles):
        raise RuntimeError(f"this worker has no assignment plugin {name!r} (joined mid-run?)")
    return plugin


def grade_task(
    name: str,
    student: str,
    raw: bytes | None,
    note: str | None,
    refused: bool,
    seeds: dict[str, int],
) -> StudentResult:
    """One student, on a worker: the same row as a local run (``seeds``: the student's data
    seeds, derived from the key by the driver)."""
    return _plugin(name).grader().grade_one(student, None, note, refused, raw, seeds)


def describe_task(name: str) -> str:
    """The sandbox layers of this worker (starts its grader: the first task of a run)."""
    return _plugin(name).grader().sandbox.isolation.describe()
