"""Benchmark: every teaching notebook executed as a new user would, against 30 s.

Each notebook runs in a fresh kernel through ``jupyter nbconvert --to notebook
--execute`` (kernel start-up, imports and every cell included), timed as CPU
time: the user + system time of nbconvert and the kernel it starts (the
children's rusage, which counts every descendant once it is reaped), so that a
loaded shared machine does not move the measure; the wall time is printed
beside it.  The baseline, measured in the same run, is a fresh kernel that only
runs ``import course`` (the fixed cost every notebook pays); the ratio printed
is notebook CPU time over that baseline.  ``--load N`` starts N busy-loop
processes for the duration of the run (the loaded 2-core machine of issue 16)
and ends them afterwards.  ``--cells K`` prints the K slowest cells of each
notebook (from the execution timestamps nbclient records).

The runner is watched too: the kernel stamps when each cell starts and ends, so a
runner sitting idle between the kernel's reply and the next cell (or the end of
the run) shows as a gap, reported as STALL.  Such a stall lasts exactly the cell
timeout (nbclient's wait for the reply misses its wake-up when the runner sends on
the same socket meanwhile, https://github.com/jupyter/nbclient/issues/312; the
course's sliders once triggered it) and passes silently in nbconvert, so the
timeout here is short enough to measure it, and a stall is a miss.

Target: every notebook under 30 s of CPU, without a stall.  Exits non-zero when one
misses it.

Usage::

    python tests/benchmarks/bench_notebooks.py [--load 2] [--cells 3] [notebooks ...]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time
from datetime import datetime
from pathlib import Path

TARGET_S = 30.0
# per cell; a missed wake-up of nbclient's reply wait costs exactly this (see above)
CELL_TIMEOUT_S = 60
# the runner idle this long between the kernel's idle of one cell and the next cell (or the
# end of the run: kernel shutdown and writing the notebook included) is a stall
STALL_GAP_S, STALL_TAIL_S = 10.0, 20.0
# a notebook still running after this long is reported as hung (a miss) instead of stalling
# the benchmark
HANG_S = 300.0
ROOT = Path(__file__).resolve().parents[2]
BUSY_LOOP = "while True: pass"


def children_cpu() -> float:
    """User + system seconds of this process's reaped descendants so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def execute(path: Path, out_dir: Path) -> tuple[float, float, Path, float]:
    """CPU and wall seconds of executing ``path`` in a fresh kernel, the executed copy, and
    the end (epoch seconds)."""
    out = out_dir / path.name
    cpu = children_cpu()
    start = time.perf_counter()
    subprocess.run(
        [
            sys.executable,
            "-m",
            "jupyter",
            "nbconvert",
            "--to",
            "notebook",
            "--execute",
            f"--ExecutePreprocessor.timeout={CELL_TIMEOUT_S}",
            "--output-dir",
            str(out_dir),
            str(path),
        ],
        check=True,
        cwd=path.parent,
        capture_output=True,
        timeout=HANG_S,
    )
    wall = time.perf_counter() - start
    return children_cpu() - cpu, wall, out, time.time()


def _stamp(timing: dict, key: str) -> float | None:
    """Epoch seconds of one of nbclient's execution timestamps (kernel clock), if recorded."""
    if key not in timing:
        return None
    return datetime.fromisoformat(timing[key].replace("Z", "+00:00")).timestamp()


def stalls(nb: dict, end: float) -> list[tuple[float, int]]:
    """(seconds, cell index) of each time the runner sat idle after a cell had finished."""
    found, previous = [], None
    for i, cell in enumerate(nb["cells"]):
        timing = cell.get("metadata", {}).get("execution", {})
        busy = _stamp(timing, "iopub.status.busy")
        if busy is None:
            continue
        if previous is not None and busy - previous[0] >= STALL_GAP_S:
            found.append((busy - previous[0], previous[1]))
        ends = [_stamp(timing, k) for k in ("iopub.status.idle", "shell.execute_reply")]
        previous = (max((t for t in ends if t is not None), default=busy), i)
    if previous is not None and end - previous[0] >= STALL_TAIL_S:
        found.append((end - previous[0], previous[1]))
    return found


def busy_seconds(nb: dict) -> float:
    """Seconds the kernel spent running the notebook's cells (busy to idle, summed)."""
    total = 0.0
    for cell in nb["cells"]:
        timing = cell.get("metadata", {}).get("execution", {})
        busy, idle = _stamp(timing, "iopub.status.busy"), _stamp(timing, "iopub.status.idle")
        if busy is not None and idle is not None:
            total += idle - busy
    return total


def slowest_cells(nb: dict, k: int) -> list[tuple[float, int, str]]:
    """The ``k`` slowest code cells as (seconds, index, first line)."""
    cells = []
    for i, cell in enumerate(nb["cells"]):
        timing = cell.get("metadata", {}).get("execution", {})
        t0, t1 = _stamp(timing, "iopub.execute_input"), _stamp(timing, "shell.execute_reply")
        if t0 is not None and t1 is not None:
            first = "".join(cell["source"]).strip().splitlines()[0][:60]
            cells.append((t1 - t0, i, first))
    return sorted(cells, reverse=True)[:k]


def baseline(out_dir: Path) -> float:
    """Wall seconds of a fresh kernel that only imports the course."""
    import nbformat

    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell("import course")]
    nb.metadata["kernelspec"] = {
        "name": "python3",
        "display_name": "Python 3",
        "language": "python",
    }
    path = out_dir / "baseline_import_course.ipynb"
    nbformat.write(nb, path)
    cpu, _, _, _ = execute(path, out_dir / "done")
    return cpu


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("notebooks", nargs="*", type=Path)
    parser.add_argument("--load", type=int, default=0, help="busy-loop processes to run")
    parser.add_argument("--cells", type=int, default=0, help="slowest cells to print")
    args = parser.parse_args()
    notebooks = args.notebooks or sorted((ROOT / "notebooks").glob("*.ipynb"))
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

    # SIGTERM ends the run through the finally below, so no busy loop outlives it
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(1))
    busy = [subprocess.Popen([sys.executable, "-c", BUSY_LOOP]) for _ in range(args.load)]
    missed = []
    try:
        with tempfile.TemporaryDirectory() as tmp:
            out_dir = Path(tmp)
            (out_dir / "done").mkdir()
            base = baseline(out_dir)
            print(f"load: {args.load} busy loops; loadavg {os.getloadavg()[0]:.1f}")
            print(f"baseline (fresh kernel, import course): {base:5.1f} s CPU")
            for path in notebooks:
                try:
                    cpu, wall, executed, end = execute(path.resolve(), out_dir / "done")
                except subprocess.TimeoutExpired:
                    print(f"HUNG {path.name:45s} no result after {HANG_S:.0f} s")
                    missed.append(path.name)
                    continue
                except subprocess.CalledProcessError as error:
                    tail = error.stderr.decode(errors="replace").strip().splitlines()[-1:]
                    print(f"FAIL {path.name:45s} {' '.join(tail)}")
                    missed.append(path.name)
                    continue
                nb = json.loads(executed.read_text())
                stalled = stalls(nb, end)
                mark = "ok " if cpu < TARGET_S and not stalled else "MISS"
                print(
                    f"{mark} {path.name:45s} {cpu:5.1f} s CPU  ({cpu / base:4.1f}x baseline; "
                    f"wall {wall:5.1f} s; cells {busy_seconds(nb):5.1f} s wall)"
                )
                for sec, i in stalled:
                    print(f"        STALL after cell {i:3d}: runner idle {sec:5.1f} s")
                for sec, i, first in slowest_cells(nb, args.cells):
                    print(f"        cell {i:3d} {sec:5.1f} s  {first}")
                if cpu >= TARGET_S or stalled:
                    missed.append(path.name)
    finally:
        for proc in busy:
            proc.kill()
            proc.wait()
    if missed:
        print(f"target {TARGET_S:.0f} s CPU missed by: {', '.join(missed)}")
        return 1
    print(f"all notebooks under {TARGET_S:.0f} s of CPU")
    return 0


if __name__ == "__main__":
    sys.exit(main())
