"""`course grade --cluster`: the same submissions graded on a real Dask distributed cluster (a
LocalCluster with two worker processes, each with its own warm sandbox) give the same outputs
as a local run, row for row."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from course.grading.batch.driver import grade
from course.grading.batch.options import GradeOptions

distributed = pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[1]
NAME = "01_least_squares"
SOLUTION_DIR = ROOT / "solutions" / NAME


def _rows(out: Path) -> dict:
    rows = {}
    for line in (out / "results.jsonl").read_text().splitlines():
        row = json.loads(line)
        assert row.pop("wall_seconds") >= 0  # the one field that differs between runs
        rows[row["student"]] = row
    return rows


@pytest.mark.slow  # a fresh install or a whole grading run
def test_cluster_grades_like_a_local_run(tmp_path):
    solution = json.loads((SOLUTION_DIR / f"{NAME}.ipynb").read_text())
    release = json.loads((ROOT / "exercises" / NAME / f"{NAME}.ipynb").read_text())
    subs = tmp_path / "subs"
    subs.mkdir()
    wrong = copy.deepcopy(solution)
    for cell in wrong["cells"]:
        if cell.get("id") == "q1-answer":
            cell["source"] = "x_hat_day1 = np.zeros(2)"
    for sid, nb in {"alice": solution, "bob": wrong, "carol": release, "dave": solution}.items():
        (subs / f"{sid}.ipynb").write_text(json.dumps(nb))
    (subs / "eve.ipynb").write_text("{ not json")
    options = dict(jobs=2, timeout=5.0, progress=False)
    grade(SOLUTION_DIR, subs, tmp_path / "local", GradeOptions(**options))

    announced: list[str] = []
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        summary = grade(
            SOLUTION_DIR,
            subs,
            tmp_path / "cluster",
            GradeOptions(**options, cluster=cluster, announce=announced.append),
        )
    assert summary.graded == 5
    assert any("worker(s) at" in line and "Sandbox: " in line for line in announced), announced
    local, remote = _rows(tmp_path / "local"), _rows(tmp_path / "cluster")
    assert remote == local
    full = local["alice"]["max"]  # the assignment's total, from checks.py
    assert local["alice"]["total"] == full and 0 < local["bob"]["total"] < full
    for name in ("grades.csv",):
        assert (tmp_path / "cluster" / name).read_text() == (tmp_path / "local" / name).read_text()
    for fb in sorted((tmp_path / "local" / "feedback").iterdir()):
        assert (tmp_path / "cluster" / "feedback" / fb.name).read_text() == fb.read_text()
