"""Benchmark: `course grade` against nbgrader-style autograding, on the same notebooks.

Run:  python tests/benchmarks/bench_grading.py [--n 40] [--jobs N]

Ours: ``course.grading.driver.grade`` on N submissions of 01_least_squares (each student's
cells run in a sandboxed child forked from a warm server; students in parallel, default one per
core). Baseline, the way ``nbgrader autograde`` executes notebooks: one fresh Jupyter kernel per
notebook (nbclient, like nbconvert's ExecutePreprocessor), cells run top to bottom including the
test cells (here the notebooks' ``check("qN")`` cells), serially, notebook after notebook. The
baseline does less than we do (no hidden cases, no sandbox, no per-question restarts), so the
ratio is conservative. Target: >= 5x on a 2-core machine.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
NAME = "01_least_squares"
TARGET = 5.0


def make_submissions(folder: Path, n: int) -> None:
    """N notebooks: mostly full solutions, some with a wrong or missing answer (seeded)."""
    rnd = random.Random(1234)
    solution = json.loads((ROOT / "solutions" / NAME / f"{NAME}.ipynb").read_text())
    release = json.loads((ROOT / "exercises" / NAME / f"{NAME}.ipynb").read_text())
    by_id = {c["id"]: c for c in release["cells"]}
    for i in range(n):
        nb = json.loads(json.dumps(solution))
        for cell in nb["cells"]:
            if cell.get("id") == "setup":
                cell["source"] = "".join(cell["source"]).replace('"demo"', f'"student{i:03d}"')
            if cell.get("id", "").endswith("-answer") and rnd.random() < 0.1:
                cell["source"] = by_id[cell["id"]]["source"]  # left unanswered
        (folder / f"student{i:03d}.ipynb").write_text(json.dumps(nb))


def run_ours(subs: Path, out: Path, jobs: int) -> float:
    from course.grading.driver import GradeOptions, grade

    start = time.perf_counter()
    summary = grade(ROOT / "solutions" / NAME, subs, out, GradeOptions(jobs=jobs, progress=False))
    elapsed = time.perf_counter() - start
    assert summary.graded == len(list(subs.glob("*.ipynb")))
    return elapsed


def run_nbgrader_style(subs: Path) -> float:
    import nbformat
    from nbclient import NotebookClient

    start = time.perf_counter()
    for path in sorted(subs.glob("*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        client = NotebookClient(
            nb,
            kernel_name="python3",
            timeout=120,
            allow_errors=True,
            resources={"metadata": {"path": str(ROOT / "exercises" / NAME)}},
        )
        client.execute()  # starts a new kernel, runs every cell, shuts the kernel down
    return time.perf_counter() - start


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=40, help="number of submissions (default 40)")
    parser.add_argument(
        "--jobs", type=int, default=os.cpu_count() or 1, help="parallel students for ours"
    )
    args = parser.parse_args(argv)
    os.environ.setdefault("MPLBACKEND", "Agg")
    tmp = Path(tempfile.mkdtemp(prefix="bench-grading-"))
    try:
        subs = tmp / "subs"
        subs.mkdir()
        make_submissions(subs, args.n)
        print(
            f"{args.n} submissions of {NAME}; {os.cpu_count()} cores; ours with --jobs {args.jobs}"
        )
        ours = run_ours(subs, tmp / "out", args.jobs)
        print(
            f"course grade (sandboxed, parallel, incl. fork-server start): {ours:8.1f} s"
            f"  ({ours / args.n:.2f} s per notebook)"
        )
        base = run_nbgrader_style(subs)
        print(
            f"nbgrader-style (one Jupyter kernel per notebook, serial):  {base:8.1f} s"
            f"  ({base / args.n:.2f} s per notebook)"
        )
        ratio = base / ours
        print(
            f"speed-up: {ratio:.1f}x (target >= {TARGET:g}x): {'met' if ratio >= TARGET else 'NOT met'}"
        )
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
