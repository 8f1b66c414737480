"""``course grade``: the batch driver that grades a folder of submitted notebooks.

It finds the submissions, skips students already graded with the same checks and library
version (``results.jsonl`` makes a run resumable), grades the others in parallel, one
:class:`~course.grading.session.StudentSession` each, and writes the reports
(:mod:`course.grading.reports`) as students finish.

Outputs in ``OUT``: ``grades.csv`` (student, one column per question, total, max, status),
``feedback/<student>.md`` and ``results.jsonl`` (one line per student, appended as students
finish; a rerun skips students already graded with the same checks and library version).
"""

from __future__ import annotations

import os
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

from course.grading.reports import (
    Summary,
    append_result,
    feedback_markdown,
    read_results,
    write_csv,
)
from course.grading.session import AssignmentGrader

__all__ = ["GradeOptions", "Summary", "find_submissions", "grade"]


@dataclass
class GradeOptions:
    jobs: int = field(default_factory=lambda: os.cpu_count() or 1)
    timeout: float | None = None  # overrides every question's time limit
    memory_mb: int = 1024
    mode: str = "auto"
    regrade: bool = False
    progress: bool = True
    ready_timeout: float = 60.0
    student_budget: float | None = None  # wall-clock seconds for one student, all attempts


def find_submissions(folder: Path, assignment: str) -> list[tuple[str, Path | None, str | None]]:
    """``(student_id, notebook_path, problem)`` for every submission in ``folder``: a file
    ``<id>.ipynb`` or a folder ``<id>/`` holding ``<assignment>.ipynb`` (or a single notebook)."""
    found: dict[str, tuple[str, Path | None, str | None]] = {}
    for entry in sorted(Path(folder).iterdir()):
        if entry.name.startswith((".", "_")):
            continue
        if entry.is_file() and entry.suffix == ".ipynb":
            sid = entry.stem
            found[sid] = (sid, entry, None)
        elif entry.is_dir():
            sid = entry.name
            if sid in found:
                continue
            preferred = entry / f"{assignment}.ipynb"
            notebooks = sorted(
                p for p in entry.rglob("*.ipynb") if ".ipynb_checkpoints" not in p.parts
            )
            if preferred.is_file():
                found[sid] = (sid, preferred, None)
            elif len(notebooks) >= 1:
                note = (
                    None
                    if len(notebooks) == 1
                    else f"several notebooks in the folder; graded {notebooks[0].name}"
                )
                found[sid] = (sid, notebooks[0], note)
            else:
                found[sid] = (sid, None, "no notebook (.ipynb) in the submission folder")
    return [found[k] for k in sorted(found)]


def grade(
    solution_dir: Path, submissions: Path, out: Path, options: GradeOptions | None = None
) -> Summary:
    """Grade every submission in ``submissions`` into ``out`` (see the module docstring)."""
    options = options or GradeOptions()
    start = time.monotonic()
    solution_dir, submissions, out = (
        Path(solution_dir).resolve(),
        Path(submissions).resolve(),
        Path(out).resolve(),
    )
    out.mkdir(parents=True, exist_ok=True)
    (out / "feedback").mkdir(exist_ok=True)
    results_path = out / "results.jsonl"
    if options.regrade and results_path.exists():
        results_path.unlink()
    lock = threading.Lock()
    with AssignmentGrader(solution_dir, options, deny_read=[submissions, out]) as grader:
        todo = find_submissions(submissions, grader.name)
        previous = read_results(results_path)
        rows: dict[str, dict] = {}
        pending = []
        for sid, path, problem in todo:
            old = previous.get(sid)
            if (
                old
                and old.get("checks_sha256") == grader.digest
                and old.get("version") == grader.version
            ):
                rows[sid] = old
            else:
                pending.append((sid, path, problem))
        resumed = len(rows)

        def finish(row: dict) -> None:
            with lock:
                append_result(row, results_path)
                (out / "feedback" / f"{row['student']}.md").write_text(
                    feedback_markdown(row, grader.checks), encoding="utf-8"
                )
                rows[row["student"]] = row

        try:
            from tqdm import tqdm
        except ImportError:  # pragma: no cover
            tqdm = None
        bar = (
            tqdm(
                total=len(pending),
                desc=f"grading {grader.name}",
                unit="student",
                file=sys.stderr,
                disable=not options.progress or tqdm is None,
            )
            if tqdm
            else None
        )
        jobs = max(1, int(options.jobs))
        with ThreadPoolExecutor(max_workers=jobs) as pool:
            futures = [
                pool.submit(grader.grade_one, sid, path, problem) for sid, path, problem in pending
            ]
            for fut in as_completed(futures):
                finish(fut.result())
                if bar is not None:
                    bar.update(1)
        if bar is not None:
            bar.close()
        for row in rows.values():  # feedback of resumed students too (cheap, keeps OUT complete)
            fb = out / "feedback" / f"{row['student']}.md"
            if not fb.exists():
                fb.write_text(feedback_markdown(row, grader.checks), encoding="utf-8")
        qids = [q.id for q in grader.questions]
        final = [rows[sid] for sid, _, _ in todo]
        write_csv(final, qids, out / "grades.csv")
        return Summary(
            final,
            qids,
            {q.id: q.points for q in grader.questions},
            len(pending),
            resumed,
            time.monotonic() - start,
            out,
        )
