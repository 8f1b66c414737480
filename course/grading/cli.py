"""The ``course release`` and ``course grade`` subcommands (hooked into :mod:`course.cli`)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

#: Where `course release` and `course grade` look for solutions/ and exercises/.
COURSE_DIR_HELP = (
    "the course folder holding solutions/ and exercises/ (default: $COURSE_DIR, else the "
    "working folder or the nearest parent that has one of them)"
)


def find_course_dir(explicit: str | None = None) -> Path:
    """The course folder: ``--course-dir``, then ``$COURSE_DIR``, then the working folder and
    its parents (the first holding ``solutions/`` or ``exercises/``), else the working folder.

    Never the package's own location: installed without ``-e`` the package lives in
    site-packages, far from any course folder.
    """
    if explicit:
        return Path(explicit).expanduser().resolve()
    if os.environ.get("COURSE_DIR"):
        return Path(os.environ["COURSE_DIR"]).expanduser().resolve()
    here = Path.cwd().resolve()
    for folder in (here, *here.parents):
        if (folder / "solutions").is_dir() or (folder / "exercises").is_dir():
            return folder
    return here


def _folder(args, name: str) -> Path:
    explicit = getattr(args, name, None)
    return Path(explicit) if explicit else find_course_dir(args.course_dir) / name


def _release(args) -> int:
    from course.grading.notebook import MarkerError
    from course.grading.release import find_solutions, release

    solutions = _folder(args, "solutions")
    exercises = _folder(args, "exercises")
    names = find_solutions(solutions) if args.all else list(args.names)
    if not names:
        print(
            "course release: name an assignment (e.g. `course release 01_least_squares`) or use --all; "
            f"assignments in {solutions}: {', '.join(find_solutions(solutions)) or 'none'}",
            file=sys.stderr,
        )
        return 2
    status = 0
    for name in names:
        name = Path(name).name  # accept solutions/<name>/ too
        if not (solutions / name / "checks.py").is_file():
            print(
                f"course release: no assignment {name!r} in {solutions} (expected {solutions / name}/checks.py)",
                file=sys.stderr,
            )
            status = 2
            continue
        try:
            written = release(name, solutions, exercises)
        except (MarkerError, ValueError, FileNotFoundError, SyntaxError, ImportError) as exc:
            print(f"course release: {name}: {exc}", file=sys.stderr)
            status = 1
            continue
        print(
            f"released {name}: "
            + ", ".join(
                str(p.relative_to(exercises)) if p.is_relative_to(exercises) else str(p)
                for p in written
            )
        )
    return status


def _grade(args) -> int:
    from course.grading.driver import GradeOptions, available_cpus, grade
    from course.grading.isolation import IsolationError

    solutions = _folder(args, "solutions")
    name = Path(args.assignment).name
    solution_dir = (
        Path(args.assignment)
        if (Path(args.assignment) / "checks.py").is_file()
        else solutions / name
    )
    if not (solution_dir / "checks.py").is_file():
        print(
            f"course grade: no assignment {name!r} (looked for {solution_dir}/checks.py)",
            file=sys.stderr,
        )
        return 2
    submissions = Path(args.submissions)
    if not submissions.is_dir():
        print(f"course grade: {submissions} is not a folder of submissions", file=sys.stderr)
        return 2
    options = GradeOptions(
        jobs=args.jobs or available_cpus(),
        timeout=args.timeout,
        memory_mb=args.memory,
        mode=args.mode,
        regrade=args.regrade,
        progress=not args.no_progress,
        unsafe_no_isolation=args.unsafe_no_isolation,
        cluster=args.cluster,
        announce=lambda text: print(text, file=sys.stderr),
    )
    try:
        summary = grade(solution_dir, submissions, Path(args.out), options)
    except IsolationError as exc:
        print(f"course grade: refusing to run: {exc}", file=sys.stderr)
        return 2
    except RuntimeError as exc:
        if args.cluster and "distributed" in str(exc):
            print(f"course grade: {exc}", file=sys.stderr)
            return 2
        raise
    print(summary.text())
    return 0


def add_commands(subparsers) -> None:
    """Add ``release`` and ``grade`` to the ``course`` command's subparsers."""
    p_rel = subparsers.add_parser(
        "release",
        help="generate student notebooks in exercises/ from solutions/",
        description="Write exercises/<name>/ (student notebook with stubs, public checks.json, data.py) "
        "from solutions/<name>/. Fails on malformed markers.",
    )
    p_rel.add_argument(
        "names", nargs="*", metavar="NAME", help="assignment(s) to release, e.g. 01_least_squares"
    )
    p_rel.add_argument(
        "--all", action="store_true", help="release every assignment under solutions/"
    )
    p_rel.add_argument("--course-dir", help=COURSE_DIR_HELP)
    p_rel.add_argument("--solutions", help="authoring folder (default: COURSE_DIR/solutions)")
    p_rel.add_argument("--exercises", help="output folder (default: COURSE_DIR/exercises)")
    p_rel.set_defaults(func=_release)

    p_gr = subparsers.add_parser(
        "grade",
        help="grade a folder of submitted notebooks in a sandbox",
        description="Grade SUBMISSIONS (one <id>.ipynb or <id>/ folder per student) against solutions/NAME. "
        "Writes OUT/grades.csv, OUT/feedback/<id>.md and OUT/results.jsonl (a rerun resumes).",
    )
    p_gr.add_argument(
        "assignment", metavar="NAME", help="assignment name (or path to its solutions folder)"
    )
    p_gr.add_argument("submissions", metavar="SUBMISSIONS", help="folder of submissions")
    p_gr.add_argument("--out", required=True, help="output folder")
    p_gr.add_argument(
        "--jobs",
        type=int,
        default=None,
        help="students graded in parallel (default: the CPUs this process may use)",
    )
    p_gr.add_argument(
        "--timeout",
        type=float,
        default=None,
        help="time limit in seconds per answer cell and per call (default: from checks.py)",
    )
    p_gr.add_argument(
        "--memory",
        type=int,
        default=1024,
        help="memory budget per student in MB (default: %(default)s)",
    )
    p_gr.add_argument(
        "--mode",
        choices=["auto", "fork", "spawn"],
        default="auto",
        help="fork: children forked from a warm server (fast, Linux); spawn: a fresh interpreter per student",
    )
    p_gr.add_argument(
        "--regrade",
        action="store_true",
        help="ignore previous results in OUT and grade everyone again",
    )
    p_gr.add_argument("--no-progress", action="store_true", help="no progress bar")
    p_gr.add_argument(
        "--cluster",
        metavar="ADDRESS",
        help="grade on the Dask distributed scheduler at ADDRESS (e.g. tcp://host:8786), one "
        "task per student; needs the [cluster] extra",
    )
    p_gr.add_argument(
        "--unsafe-no-isolation",
        action="store_true",
        help="grade even on a machine whose kernel offers neither Landlock nor user namespaces "
        "(student code could then read and change the grader's files)",
    )
    p_gr.add_argument("--course-dir", help=COURSE_DIR_HELP)
    p_gr.add_argument("--solutions", help="authoring folder (default: COURSE_DIR/solutions)")
    p_gr.set_defaults(func=_grade)
