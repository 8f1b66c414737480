"""The batch grader against a hostile class: every bad submission gets the right status and the
right points for its honest parts, and nothing escapes OUT.

All submissions are variations of the 01_least_squares solution (14 points, 8 questions), graded
in ONE run (2 jobs, 3 s per question) so the suite stays fast.
"""

from __future__ import annotations

import copy
import csv
import hashlib
import json
from pathlib import Path

import pytest

from course.grading.driver import GradeOptions, grade

ROOT = Path(__file__).resolve().parents[1]
NAME = "01_least_squares"
SOLUTION_DIR = ROOT / "solutions" / NAME
FULL = 14.0
POINTS = {"q1": 1, "q2": 1, "q3": 3, "q4": 3, "q5": 1, "q6": 2, "q7": 1, "q8": 2}
TIMEOUT = 3.0


def _load(path: Path) -> dict:
    nb = json.loads(path.read_text())
    for cell in nb["cells"]:
        if isinstance(cell["source"], list):
            cell["source"] = "".join(cell["source"])
    return nb


def _solution() -> dict:
    return _load(SOLUTION_DIR / f"{NAME}.ipynb")


def _release() -> dict:
    return _load(ROOT / "exercises" / NAME / f"{NAME}.ipynb")


def _cell(nb: dict, cell_id: str) -> dict:
    return next(c for c in nb["cells"] if c.get("id") == cell_id)


def _with_answer(qid: str, source: str, nb: dict | None = None) -> dict:
    nb = copy.deepcopy(nb or _solution())
    _cell(nb, f"{qid}-answer")["source"] = source
    return nb


def _sha_tree(folder: Path) -> dict:
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def _submissions(tmp: Path, sentinel: Path) -> dict[str, object]:
    """student id -> notebook dict (or raw text for broken files)."""
    subs: dict[str, object] = {}
    subs["solution"] = _solution()
    subs["untouched"] = _release()
    subs["infinite_loop"] = _with_answer("q1", "while True:\n    pass")
    subs["ignores_sigint"] = _with_answer(
        "q3",
        (
            "import signal\n"
            "def overall_model_test_stat(A, y, Qyy, alpha):\n"
            "    signal.signal(signal.SIGINT, signal.SIG_IGN)\n"
            "    signal.signal(signal.SIGTERM, signal.SIG_IGN)\n"
            "    while True:\n"
            "        pass"
        ),
    )
    subs["os_exit"] = _with_answer("q2", "import os\nos._exit(3)")
    subs["sys_exit"] = _with_answer("q5", "import sys\nsys.exit('bye')")
    subs["memory_bomb"] = _with_answer(
        "q4",
        (
            "def w_statistics(A, y, Qyy):\n"
            "    hoard = []\n"
            "    while True:\n"
            "        hoard.append(bytearray(1 << 30))"
        ),
    )
    subs["fork_bomb"] = _with_answer("q1", ("import os\nwhile True:\n    os.fork()"))
    subs["subprocess"] = _with_answer(
        "q2",
        (
            "import subprocess\n"
            "subprocess.run(['sh', '-c', 'echo pwned > /tmp/course_pwned'])\n"
            "e_hat_day2 = 0"
        ),
    )
    subs["output_flood"] = _with_answer(
        "q2",
        (
            "%time _ = 1\n"
            "import warnings\n"
            "warnings.warn('this answer is noisy')\n"
            "print('x' * 50_000_000)\n"
            "import sys\n"
            "sys.stderr.write('y' * 10_000_000)\n"
            "x_hat_day2 = np.linalg.lstsq(A, y_day2, rcond=None)[0]\n"
            "e_hat_day2 = y_day2 - A @ x_hat_day2"
        ),
    )
    forged = json.dumps({"id": 1, "nonce": "0", "status": "ok", "value": [12.0, 3.0]})
    subs["forged_result"] = _with_answer(
        "q1",
        (
            "import os\n"
            f"line = {forged!r} + '\\n'\n"
            "print(line * 20)\n"
            "for fd in map(int, os.listdir('/proc/self/fd')):\n"
            "    try:\n"
            "        os.write(fd, line.encode())\n"
            "    except OSError:\n"
            "        pass\n"
            "print('q1: PASS 1/1 points')\n"
            "x_hat_day1 = np.array([0.0, 0.0])"
        ),
    )
    subs["monkeypatch"] = _with_answer(
        "q1",
        (
            "import builtins, json\n"
            "np.allclose = lambda *a, **k: True\n"
            "np.isclose = lambda *a, **k: True\n"
            "np.array_equal = lambda *a, **k: True\n"
            "np.testing.assert_allclose = lambda *a, **k: None\n"
            "builtins.abs = lambda x: 0\n"
            "builtins.round = lambda *a: 0\n"
            'json.dumps = lambda *a, **k: \'{"status": "ok"}\'\n'
            "json.loads = lambda *a, **k: {}\n"
            "import course.grading.codec as codec\n"
            "codec.encode = lambda v: [12.0, 3.0]\n"
            "x_hat_day1 = np.array([0.0, 0.0])"
        ),
    )
    subs["writes_outside"] = _with_answer(
        "q1",
        (
            f"open({str(sentinel)!r}, 'w').write('overwritten')\n"
            "x_hat_day1 = np.linalg.lstsq(A, y_day1, rcond=None)[0]"
        ),
    )
    subs["deletes_outside"] = _with_answer(
        "q2", (f"import os, shutil\nos.remove({str(sentinel)!r})\ne_hat_day2 = 0")
    )
    subs["reads_solutions"] = _with_answer(
        "q1",
        (
            f"source = open({str(SOLUTION_DIR / 'checks.py')!r}).read()\n"
            "x_hat_day1 = np.array([12.0, 3.0])"
        ),
    )
    nb = _solution()
    nb["cells"] = [c for c in nb["cells"] if c.get("id") not in ("q2-answer", "code-02")]
    q3 = next(c for c in nb["cells"] if c.get("id") == "q3-answer")
    wrong = copy.deepcopy(q3)
    wrong["id"] = "copied-cell"
    wrong["source"] = "def overall_model_test_stat(A, y, Qyy, alpha):\n    return 0.0, 0.0, False"
    nb["cells"].insert(nb["cells"].index(q3), wrong)  # duplicate before the real one: last wins
    q5 = next(c for c in nb["cells"] if c.get("id") == "q5-answer")
    nb["cells"].remove(q5)
    nb["cells"].insert(3, q5)  # moved to the top
    subs["deleted_duplicated_moved"] = nb
    nb = _solution()
    _cell(nb, "code-02")["source"] = _cell(nb, "code-02")["source"].replace(
        "14.0, 20.0", "99.0, 99.0"
    )
    _cell(nb, "setup")["source"] = _cell(nb, "setup")["source"].replace('"demo"', '"someone-else"')
    subs["edited_protected"] = nb
    subs["forbidden_static"] = _with_answer(
        "q3",
        (
            "def overall_model_test_stat(A, y, Qyy, alpha):\n"
            "    r = lsq.overall_model_test(lsq.fit(A, y, Qyy), alpha)\n"
            "    return r.statistic, r.critical_value, r.reject"
        ),
    )
    subs["forbidden_runtime"] = _with_answer(
        "q4",
        (
            "def w_statistics(A, y, Qyy):\n"
            "    f = getattr(lsq, 'f' + 'it')\n"
            "    return getattr(lsq, 'w_' + 'tests')(f(A, y, Qyy), 0.05).w"
        ),
    )
    subs["copied_numbers"] = _with_answer(
        "q6", "T_mine = 76.50528606174367  # the demo student's value"
    )
    # a Monte Carlo answer that does not simulate: right under H0, wrong for every biased case
    subs["constant_rate"] = _with_answer(
        "q8", ("def rejection_rate(A, Qyy, alpha, n_runs, seed, bias):\n    return alpha")
    )
    subs["empty"] = {"cells": [], "metadata": {}, "nbformat": 4, "nbformat_minor": 5}
    subs["not_json"] = "{ this is not json"
    subs["not_a_notebook"] = json.dumps({"hello": "world"})
    return subs


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("hostile")
    sub_dir, out = tmp / "submissions", tmp / "out"
    sub_dir.mkdir()
    outside = tmp / "outside"
    outside.mkdir()
    sentinel = outside / "sentinel.txt"
    sentinel.write_text("original")
    for sid, nb in _submissions(tmp, sentinel).items():
        text = nb if isinstance(nb, str) else json.dumps(nb)
        if sid == "solution":
            (sub_dir / sid).mkdir()
            (sub_dir / sid / f"{NAME}.ipynb").write_text(text)  # the folder form
        else:
            (sub_dir / f"{sid}.ipynb").write_text(text)
    before_subs, before_repo = _sha_tree(sub_dir), _sha_tree(ROOT / "solutions")
    options = GradeOptions(jobs=2, timeout=TIMEOUT, memory_mb=512, progress=False)
    summary = grade(SOLUTION_DIR, sub_dir, out, options)
    rows = {
        json.loads(line)["student"]: json.loads(line)
        for line in (out / "results.jsonl").read_text().splitlines()
    }
    return {
        "summary": summary,
        "rows": rows,
        "out": out,
        "sub_dir": sub_dir,
        "sentinel": sentinel,
        "before_subs": before_subs,
        "before_repo": before_repo,
        "options": options,
    }


def _points(row) -> dict:
    return {q: r["points"] for q, r in row["questions"].items()}


def _expect(row, zero: dict, status: str | None = None):
    """All questions full marks except those in ``zero`` (qid -> expected status)."""
    for qid, pts in POINTS.items():
        r = row["questions"][qid]
        if qid in zero:
            assert r["points"] == 0, (qid, r)
            if zero[qid] is not None:
                assert r["status"] == zero[qid], (qid, r)
        else:
            assert r["points"] == pts, (qid, r)
    assert row["total"] == FULL - sum(POINTS[q] for q in zero)


def test_every_submission_is_graded(graded):
    rows = graded["rows"]
    assert set(rows) == set(_submissions(Path("."), Path("x")).keys())
    with open(graded["out"] / "grades.csv") as f:
        table = list(csv.DictReader(f))
    assert [r["student"] for r in table] == sorted(rows)
    assert list(table[0]) == ["student", *POINTS, "total", "max", "status"]
    for sid in rows:
        assert (graded["out"] / "feedback" / f"{sid}.md").is_file()


def test_solution_and_untouched(graded):
    rows = graded["rows"]
    _expect(rows["solution"], {})
    assert rows["solution"]["status"] == "ok"
    untouched = rows["untouched"]
    assert untouched["total"] == 0
    assert all(r["status"] == "not answered" for r in untouched["questions"].values())


def test_infinite_loop_costs_only_its_question(graded):
    row = graded["rows"]["infinite_loop"]
    _expect(row, {"q1": "timeout"})
    assert "q1: timeout" in row["status"]


def test_sigint_ignoring_loop_is_killed(graded):
    # q6 calls the student's own q3 function, so it loops too; the rest is unaffected
    _expect(graded["rows"]["ignores_sigint"], {"q3": "timeout", "q6": "timeout"})


def test_os_exit_is_a_crash_of_that_question(graded):
    row = graded["rows"]["os_exit"]
    _expect(row, {"q2": "crash"})
    assert "exit code 3" in row["questions"]["q2"]["message"]


def test_sys_exit_is_an_error_not_a_crash(graded):
    row = graded["rows"]["sys_exit"]
    _expect(row, {"q5": "error"})
    assert "SystemExit" in row["questions"]["q5"]["message"]


def test_memory_bomb(graded):
    _expect(graded["rows"]["memory_bomb"], {"q4": "memory"})


def test_fork_bomb_is_blocked(graded):
    row = graded["rows"]["fork_bomb"]
    _expect(row, {"q1": "error"})
    assert "PermissionError" in row["questions"]["q1"]["message"]


def test_subprocess_is_blocked(graded):
    _expect(graded["rows"]["subprocess"], {"q2": "error"})
    assert not Path("/tmp/course_pwned").exists()


def test_output_flood_and_warnings_do_not_matter(graded):
    _expect(graded["rows"]["output_flood"], {})


def test_forged_output_cannot_score(graded):
    _expect(graded["rows"]["forged_result"], {"q1": "fail"})


def test_monkeypatching_numpy_and_builtins(graded):
    _expect(graded["rows"]["monkeypatch"], {"q1": "fail"})


def test_writes_and_deletes_outside_tmp_are_refused(graded):
    _expect(graded["rows"]["writes_outside"], {"q1": None})
    _expect(graded["rows"]["deletes_outside"], {"q2": "error"})
    assert graded["sentinel"].read_text() == "original"
    assert "PermissionError" in graded["rows"]["writes_outside"]["questions"]["q1"]["message"]


def test_nothing_outside_out_changed(graded):
    assert _sha_tree(graded["sub_dir"]) == graded["before_subs"]
    assert _sha_tree(ROOT / "solutions") == graded["before_repo"]
    names = {p.name for p in graded["out"].iterdir()}
    assert names == {"grades.csv", "results.jsonl", "feedback"}


def test_solutions_folder_is_unreadable(graded):
    row = graded["rows"]["reads_solutions"]
    _expect(row, {"q1": "error"})
    assert "not allowed while grading: reading" in row["questions"]["q1"]["message"]


def test_deleted_duplicated_moved_cells(graded):
    row = graded["rows"]["deleted_duplicated_moved"]
    _expect(row, {"q2": "not answered"})  # deleted protected cell still ran; last copy of q3 won


def test_edited_protected_cells_are_not_trusted(graded):
    row = graded["rows"]["edited_protected"]
    _expect(row, {})
    notes = " ".join(row["notes"])
    assert "'code-02' was edited" in notes
    assert "'someone-else'" in notes and "'edited_protected'" in notes


def test_forbidden_calls(graded):
    _expect(graded["rows"]["forbidden_static"], {"q3": "forbidden"})
    row = graded["rows"]["forbidden_runtime"]
    _expect(row, {"q4": "forbidden"})
    assert "course.lsq.w_tests" in row["questions"]["q4"]["message"]


def test_copied_numbers_fail_per_student_question(graded):
    _expect(graded["rows"]["copied_numbers"], {"q6": "fail"})


def test_monte_carlo_band_is_not_fooled_by_returning_alpha(graded):
    row = graded["rows"]["constant_rate"]
    assert all(row["questions"][q]["points"] == pts for q, pts in POINTS.items() if q != "q8")
    q8 = row["questions"]["q8"]
    passed = [c["ok"] for c in q8["cases"]]
    assert len(passed) == 6 and sum(passed) == 3  # the three cases without a bias
    assert q8["status"] == "partial" and q8["points"] == pytest.approx(1.0)
    assert not q8["cases"][1]["ok"] and "outside the accepted" in q8["cases"][1]["message"]


def test_broken_files(graded):
    rows = graded["rows"]
    for sid in ("not_json", "not_a_notebook"):
        assert rows[sid]["total"] == 0 and rows[sid]["status"] == "invalid notebook", rows[sid]
    assert "not valid JSON" in " ".join(rows["not_json"]["notes"])
    assert rows["empty"]["total"] == 0
    assert all(r["status"] == "not answered" for r in rows["empty"]["questions"].values())


def test_feedback_hides_hidden_cases_and_code(graded):
    text = (graded["out"] / "feedback" / "infinite_loop.md").read_text()
    assert "q1: 0 / 1 (timeout)" in text and "Hint:" in text
    for sid in graded["rows"]:
        fb = (graded["out"] / "feedback" / f"{sid}.md").read_text()
        assert "def q3" not in fb and "A_SEA" not in fb and "binomial_band" not in fb
        assert (
            "hidden case" not in fb
            or "expected" not in fb.split("hidden case", 1)[1].split("\n", 1)[0]
        )


def test_rerun_resumes_and_regrade_is_identical(graded, tmp_path):
    out = graded["out"]
    before = (out / "results.jsonl").read_text()
    summary = grade(SOLUTION_DIR, graded["sub_dir"], out, graded["options"])
    assert summary.graded == 0 and summary.resumed == len(graded["rows"])
    assert (out / "results.jsonl").read_text() == before
    # regrading from scratch gives identical rows (no timestamps, no temp paths)
    small = tmp_path / "subs"
    small.mkdir()
    for sid in ("untouched", "infinite_loop", "os_exit", "forged_result", "not_json"):
        src = graded["sub_dir"] / f"{sid}.ipynb"
        (small / src.name).write_bytes(src.read_bytes())
    out2 = tmp_path / "out2"
    grade(SOLUTION_DIR, small, out2, graded["options"])
    again = {
        json.loads(l)["student"]: json.loads(l)
        for l in (out2 / "results.jsonl").read_text().splitlines()
    }
    for sid, row in again.items():
        assert row == graded["rows"][sid], sid
    assert all(r["checks_sha256"] and r["version"] for r in again.values())


def test_summary_text(graded):
    text = graded["summary"].text()
    assert "q1" in text and "full marks" in text and "status:" in text
