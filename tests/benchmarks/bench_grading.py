"""Benchmark: `course grade` against real `nbgrader autograde`, on the same submissions.

Run:  python tests/benchmarks/bench_grading.py [--n 40] [--jobs N] [--skip-nbgrader]

Ours: ``course.grading.batch.driver.grade`` on N submissions of 01_least_squares (mostly full
solutions, some answers left unanswered; seeded), every isolation layer on, default --jobs (the
CPUs this process may use). Also printed: the per-student overhead of the kernel isolation
(the same run with Landlock and namespaces off), and the scaling with --jobs.

Baseline: nbgrader, in a course folder the benchmark builds itself: the
solution notebook converted to nbgrader's format (answer cells as solution cells, one
autograder test cell per question that checks the same public and hidden cases with the same
tolerances through ``course.grading.compare``), ``nbgrader generate_assignment``, then every
submission converted and ``nbgrader autograde``, which runs each notebook in a fresh Jupyter
kernel. Target: ours at least 8x faster. Exits non-zero when a target is missed.

Both tools run as command lines (``python -m course grade ...``, ``python -m nbgrader
autograde ...``) and are timed in CPU time: the user + system time of the command and of every
descendant it reaps (the grader's fork server and sandbox children, nbgrader's kernels), read
from this process's children's rusage, so that other work on a shared machine does not move
the ratio. A descendant that is never reaped by its parent would not be counted. The wall time
of a loaded machine says nothing about either tool. The runs without isolation use
``--unsafe-no-isolation`` (every kernel layer off).

nbgrader is not part of the course (``.[all]`` leaves it out: its Jupyter extensions would
show in ``course open``). Where it is not importable here, the benchmark installs it with the
course into a virtual environment of its own (``--peers DIR`` keeps that environment between
runs; the first run downloads nbgrader) and runs it from there, with that environment's
``bin/`` first on ``PATH`` (nbgrader calls ``alembic`` for its database). ``python -m pip
install -e ".[bench]"`` into a separate environment runs it in place instead.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import random
import resource
import shutil
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
NAME = "01_least_squares"
SOLUTION_DIR = ROOT / "solutions" / NAME
TARGET = 8.0


def make_submissions(folder: Path, n: int) -> None:
    """N notebooks: mostly full solutions, some with an answer left unanswered (seeded)."""
    rnd = random.Random(1234)
    solution = json.loads((SOLUTION_DIR / f"{NAME}.ipynb").read_text())
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


def children_cpu() -> float:
    """User + system seconds of this process's reaped descendants so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run_ours(subs: Path, out: Path, jobs: int, isolation: bool = True) -> float:
    """CPU seconds of ``course grade`` as a command line, its sandbox children included."""
    shutil.rmtree(out, ignore_errors=True)
    command = [sys.executable, "-m", "course", "grade", str(SOLUTION_DIR), str(subs)]
    command += ["--out", str(out), "--jobs", str(jobs), "--no-progress"]
    if not isolation:
        command.append("--unsafe-no-isolation")
    start = children_cpu()
    subprocess.run(
        command, check=True, capture_output=True, env=dict(os.environ, COURSE_DIR=str(ROOT))
    )
    elapsed = children_cpu() - start
    with open(out / "grades.csv", newline="") as rows:
        graded = sum(1 for _ in csv.DictReader(rows))
    assert graded == len(list(subs.glob("*.ipynb"))), graded
    return elapsed


# -- nbgrader ------------------------------------------------------------------------------------
def _test_source(q) -> str:
    """An nbgrader autograder cell checking question ``q`` as course grade does."""
    head = (
        "from course.grading.authoring.checks import load_checks\n"
        "from course.grading.codec import decode, encode\n"
        "from course.grading.compare import compare\n"
        f"_q = load_checks({str(SOLUTION_DIR)!r}).questions[{q.id!r}]\n"
    )
    if q.kind == "function":
        return head + (
            "for _case in _q.cases:\n"
            f"    _got = decode(encode({q.target}(*_case.args, **_case.kwargs)))\n"
            "    assert compare(_q.expected(_case), _got, _q.rtol, _q.atol).ok, _case.label\n"
        )
    data = (
        f"_q.expected(data=load_checks({str(SOLUTION_DIR)!r}).data_for({q.data!r}, STUDENT_ID))"
        if q.data
        else "_q.expected()"
    )
    return head + f"assert compare({data}, decode(encode({q.target})), _q.rtol, _q.atol).ok\n"


def nbgrader_source(checks) -> dict:
    """The solution notebook in nbgrader's format (our markers are nbgrader's)."""
    nb = json.loads((SOLUTION_DIR / f"{NAME}.ipynb").read_text())
    cells = []
    for cell in nb["cells"]:
        meta = cell.get("metadata", {}).get("course", {})
        if meta.get("role") == "check":
            continue  # nbgrader's test cells replace the self-check
        cell = dict(cell, outputs=[], execution_count=None) if cell["cell_type"] == "code" else cell
        if meta.get("role") == "answer":
            cell["metadata"] = {
                "nbgrader": {
                    "grade": False,
                    "grade_id": cell["id"],
                    "locked": False,
                    "schema_version": 3,
                    "solution": True,
                    "task": False,
                }
            }
            cells.append(cell)
            q = checks.questions[meta["question"]]
            cells.append(
                {
                    "cell_type": "code",
                    "id": f"{q.id}-test",
                    "execution_count": None,
                    "outputs": [],
                    "source": _test_source(q),
                    "metadata": {
                        "nbgrader": {
                            "grade": True,
                            "grade_id": f"{q.id}-test",
                            "locked": True,
                            "points": q.points,
                            "schema_version": 3,
                            "solution": False,
                            "task": False,
                        }
                    },
                }
            )
        else:
            cells.append(cell)
    nb["cells"] = cells
    return nb


def peer_python(peers: Path, log) -> Path:
    """The interpreter that runs nbgrader: this one when nbgrader is installed here, else
    ``peers/bin/python``, made (once) with nbgrader and the course, whose autograder cells
    import ``course.grading``."""
    from importlib.util import find_spec

    if find_spec("nbgrader") is not None:
        return Path(sys.executable)
    python = peers / "bin" / "python"
    if not python.is_file():
        print(f"installing nbgrader into {peers} (once) ...", flush=True)
        subprocess.run([sys.executable, "-m", "venv", str(peers)], check=True)
        subprocess.run(
            [str(python), "-m", "pip", "install", "--quiet", "nbgrader>=0.9", "-e", str(ROOT)],
            stdout=log,
            stderr=log,
            check=True,
        )
    return python


def run_nbgrader(subs: Path, work: Path, log, python: Path) -> float:
    from course.grading.authoring.checks import load_checks

    checks = load_checks(SOLUTION_DIR)
    course = work / "nbgrader-course"
    (course / "source" / NAME).mkdir(parents=True)
    (course / "nbgrader_config.py").write_text(
        "c = get_config()\n"
        f"c.CourseDirectory.root = {str(course)!r}\n"
        "c.CourseDirectory.course_id = 'bench'\n"
        "c.ExecutePreprocessor.timeout = 120\n"
    )
    (course / "source" / NAME / f"{NAME}.ipynb").write_text(json.dumps(nbgrader_source(checks)))
    nbgrader = [str(python), "-m", "nbgrader"]
    # the notebooks' self-check finds exercises/; the peers' bin/ first, for nbgrader's alembic
    path = os.pathsep.join([str(python.parent), os.environ.get("PATH", "")])
    env = dict(os.environ, COURSE_DIR=str(ROOT), PATH=path)
    subprocess.run(
        [*nbgrader, "generate_assignment", NAME, "--force", "--create"],
        cwd=course,
        env=env,
        stdout=log,
        stderr=log,
        check=True,
    )
    released = json.loads((course / "release" / NAME / f"{NAME}.ipynb").read_text())
    for path in sorted(subs.glob("*.ipynb")):
        mine = {c.get("id"): c for c in json.loads(path.read_text())["cells"]}
        nb = json.loads(json.dumps(released))
        for cell in nb["cells"]:
            grade_id = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")
            source_id = grade_id if grade_id in mine else cell.get("id")
            locked = cell.get("metadata", {}).get("nbgrader", {}).get("locked")
            if source_id in mine and (grade_id or source_id == "setup") and not locked:
                cell["source"] = mine[source_id]["source"]
        target = course / "submitted" / path.stem / NAME
        target.mkdir(parents=True)
        (target / f"{NAME}.ipynb").write_text(json.dumps(nb))
    start = children_cpu()  # (its kernels are its children, reaped by it: counted)
    subprocess.run(
        [*nbgrader, "autograde", NAME, "--create", "--force"],
        cwd=course,
        env=env,
        stdout=log,
        stderr=log,
        check=True,
    )
    return children_cpu() - start


def main(argv=None) -> int:
    from course.grading.batch.options import available_cpus

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=40, help="number of submissions (default 40)")
    parser.add_argument("--jobs", type=int, default=None, help="default: the CPUs we may use")
    parser.add_argument("--skip-nbgrader", action="store_true", help="ours only")
    parser.add_argument(
        "--peers",
        type=Path,
        default=None,
        help="virtual environment for nbgrader, kept between runs (default: a temporary one, "
        "unless nbgrader is installed here)",
    )
    args = parser.parse_args(argv)
    os.environ.setdefault("MPLBACKEND", "Agg")
    warnings.simplefilter("ignore")  # results below, not buried under warnings
    cpus = available_cpus()
    jobs = args.jobs or cpus
    tmp = Path(tempfile.mkdtemp(prefix="bench-grading-"))
    failed = False
    try:
        subs = tmp / "subs"
        subs.mkdir()
        make_submissions(subs, args.n)
        n = args.n
        from course.grading.sandbox.isolation import detect

        print(f"{n} submissions of {NAME}; {cpus} CPU(s) available; --jobs {jobs}")
        print(detect().describe())
        ours = run_ours(subs, tmp / "out", jobs=jobs)
        plain = run_ours(subs, tmp / "out-plain", jobs=jobs, isolation=False)
        print(
            f"course grade, every layer:        {ours:7.1f} s CPU  ({ours / n:.2f} s per student)"
        )
        print(
            f"course grade, --unsafe-no-isolation: {plain:7.1f} s CPU  ({plain / n:.2f} s per student)"
        )
        print(f"isolation overhead: {(ours - plain) / n:+.3f} s per student")
        print(
            "scaling with --jobs (every layer; CPU time stays flat where the jobs add no overhead):"
        )
        for j in sorted({1, *range(2, cpus + 1)}):
            t = ours if j == jobs else run_ours(subs, tmp / f"out-{j}", jobs=j)
            print(f"  --jobs {j}: {t:7.1f} s CPU  ({t / n:.2f} s per student)")
        if not args.skip_nbgrader:
            with open(tmp / "nbgrader.log", "wb") as log:
                python = peer_python(args.peers or tmp / "peers", log)
                base = run_nbgrader(subs, tmp, log, python)
            print(
                f"nbgrader autograde (kernel per notebook): {base:7.1f} s CPU  ({base / n:.2f} s per student)"
            )
            ratio = base / ours
            met = ratio >= TARGET
            failed = failed or not met
            print(
                f"speed-up vs nbgrader: {ratio:.1f}x (target >= {TARGET:g}x): {'met' if met else 'NOT met'}"
            )
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
