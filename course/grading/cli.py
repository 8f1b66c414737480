"""The ``course release`` and ``course grade`` subcommands (hooked into :mod:`course.cli`)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]


def _release(args) -> int:
    from course.grading.notebook import MarkerError
    from course.grading.release import find_solutions, release

    solutions = Path(args.solutions)
    exercises = Path(args.exercises)
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
    from course.grading.driver import GradeOptions, grade

    solutions = Path(args.solutions)
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
        jobs=args.jobs or os.cpu_count() or 1,
        timeout=args.timeout,
        memory_mb=args.memory,
        mode=args.mode,
        regrade=args.regrade,
        progress=not args.no_progress,
    )
    summary = grade(solution_dir, submissions, Path(args.out), options)
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
    p_rel.add_argument(
        "--solutions",
        default=str(REPO_ROOT / "solutions"),
        help="authoring folder (default: %(default)s)",
    )
    p_rel.add_argument(
        "--exercises",
        default=str(REPO_ROOT / "exercises"),
        help="output folder (default: %(default)s)",
    )
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
        help="students graded in parallel (default: number of cores)",
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
        "--solutions",
        default=str(REPO_ROOT / "solutions"),
        help="authoring folder (default: %(default)s)",
    )
    p_gr.set_defaults(func=_grade)
