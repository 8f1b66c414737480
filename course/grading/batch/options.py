"""The options of ``course grade`` (:class:`GradeOptions`), read by the driver, each student's
session and the cluster workers alike: a module of their own, so none of those imports another
to learn its options."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any

from course.grading.authoring.secret import Secret
from course.grading.batch.late import LatePolicy
from course.grading.batch.roster import Roster
from course.grading.sandbox.isolation import Isolation, detect

__all__ = ["GradeOptions", "available_cpus"]


def available_cpus() -> int:
    """The CPUs this process may actually run on: its affinity mask, capped by a cgroup CPU
    quota (containers), at least 1. ``os.cpu_count()`` counts the machine's cores instead."""
    try:
        cpus = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cpus = os.cpu_count() or 1
    try:
        quota, period = Path("/sys/fs/cgroup/cpu.max").read_text().split()[:2]
        if quota != "max":
            cpus = min(cpus, max(1, int(-(-int(quota) // int(period)))))
    except (OSError, ValueError):
        pass
    return max(1, cpus)


@dataclass
class GradeOptions:
    jobs: int = field(default_factory=available_cpus)
    timeout: float | None = None  # overrides every question's time limit
    memory_mb: int = 1024
    regrade: bool = False
    progress: bool = True
    ready_timeout: float = 60.0
    student_budget: float | None = None  # wall-clock seconds for one student, all attempts
    unsafe_no_isolation: bool = False  # grade even where the kernel offers no file-system walls
    namespaces: bool = True  # use bubblewrap when installed
    landlock: bool = True  # use Landlock when the kernel has it
    announce: Callable[[str], None] | None = None  # told once which sandbox layers are active
    cluster: Any = None  # a Dask scheduler address (or Cluster object): one task per student
    cluster_files: Any = None  # TLS files of the scheduler connection (cluster.ConnectionFiles)
    insecure_cluster: bool = False  # accept a plain tcp:// scheduler beyond this machine
    secret: Secret | None = None  # the instructor's key of personal data (None: public data)
    roster: Roster | None = None  # the class: missing/unknown submissions, LMS grade files
    missing_as_zero: bool = False  # LMS files: 0 (not blank) for students without submission
    lms_column: str | None = None  # LMS files: the assignment's column (default: its title)
    students: frozenset[str] | None = None  # grade only these IDs (None: everyone)
    short_answers: Path | None = None  # a filled marking file to merge (course.grading.batch.marks)
    due: datetime | None = None  # the due date (None: checks.py's due=, else no due date)
    late_policy: LatePolicy | None = None  # None: checks.py's late_policy=, else no deduction
    submitted_at: Path | str | None = None  # a timestamps CSV, or "file-times" (late.FILE_TIMES)
    extensions: Path | None = None  # a CSV id,assignment,due of students' own due dates

    def isolation(self) -> Isolation:
        """The sandbox layers (raises IsolationError where none walls off the file system)."""
        return detect(
            namespaces=self.namespaces, landlock=self.landlock, unsafe=self.unsafe_no_isolation
        )
