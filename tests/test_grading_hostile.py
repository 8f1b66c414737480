"""The batch grader against a hostile class: every bad submission gets the right status and the
right points for its honest parts, and nothing escapes OUT.

All submissions are variations of the 01_least_squares solution (17 points, 11 questions), graded
in ONE run (2 jobs, 3 s per question) so the suite stays fast. The assignment is graded from a
copy of the course in a temporary folder that also holds secrets (a file beside checks.py, a
file in a fake $HOME, another student's notebook): the attacks of issue 11 try to read them
(dir_fd, /proc, listings, a switched-off audit hook), to write outside the child's folder, to
reach a TCP listener, to forge points for forbidden calls, and to slip the solution in as a
link. Secrets must never reach OUT, files outside the temporary folders keep their hashes,
forged points are 0 and the honest students of the same batch keep full marks.
"""

from __future__ import annotations

import copy
import csv
import hashlib
import json
import os
import platform
import secrets
import shutil
import socket
import types
from pathlib import Path

import pytest

from course.grading.authoring.checks import load_checks
from course.grading.batch.driver import grade
from course.grading.batch.options import GradeOptions

ROOT = Path(__file__).resolve().parents[1]
NAME = "01_least_squares"
SOLUTION_DIR = ROOT / "solutions" / NAME
FULL = 17.0
POINTS = {
    "q1": 1,
    "q2": 1,
    "q3": 3,
    "q4": 3,
    "q5": 1,
    "q6_practice": 1,
    "q7_practice": 1,
    "q6": 2,
    "q6b": 1,
    "q7": 1,
    "q8": 2,
}
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


# 01 q1 is a function question: an answer whose reply is huge returns the huge value
_Q1_RETURNS = "def line_estimate(t, y):\n    return "


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


def _submissions(env) -> dict[str, object]:
    """student id -> notebook dict (or raw text for broken files)."""
    sentinel = env.sentinel
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
            "def line_residuals(t, y):\n"
            "    return 0"
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
            "def line_residuals(t, y):\n"
            "    A = np.column_stack([np.ones(len(t)), t])\n"
            "    return y - A @ np.linalg.lstsq(A, y, rcond=None)[0]"
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
            "def line_estimate(t, y):\n"
            "    return np.array([0.0, 0.0])"
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
            "def line_estimate(t, y):\n"
            "    return np.array([0.0, 0.0])"
        ),
    )
    subs["writes_outside"] = _with_answer(
        "q1",
        (
            f"open({str(sentinel)!r}, 'w').write('overwritten')\n"
            "def line_estimate(t, y):\n"
            "    return np.polyfit(t, y, 1)[::-1]"
        ),
    )
    subs["deletes_outside"] = _with_answer(
        "q2",
        (
            f"import os, shutil\nos.remove({str(sentinel)!r})\n"
            "def line_residuals(t, y):\n    return 0"
        ),
    )
    subs["reads_solutions"] = _with_answer(
        "q1",
        (
            f"source = open({str(env.solution_dir / 'checks.py')!r}).read()\n"
            "def line_estimate(t, y):\n"
            "    return np.array([12.0, 3.0])"
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
    # its own ID (a notebook declaring another's is quarantined: see the identity tests below)
    _cell(nb, "setup")["source"] = _cell(nb, "setup")["source"].replace(
        '"demo"', '"edited_protected"'
    )
    subs["edited_protected"] = nb
    subs["forbidden_static"] = _with_answer(
        "q3",
        (
            "def overall_model_test_stat(A, y, Qyy, alpha):\n"
            "    r = lsq.overall_model_test(lsq.fit(A, y, Qyy), alpha)\n"
            "    return r.statistic, r.critical_value, r.reject"
        ),
    )
    solution_q3 = _cell(_solution(), "q3-answer")["source"]
    solution_q3 = "".join(solution_q3) if isinstance(solution_q3, list) else solution_q3
    subs["forbidden_unused_import"] = _with_answer(
        "q3",
        "from course.lsq import overall_model_test, fit as f\nimport course.lsq as cl\n"
        + solution_q3,
    )
    subs["forbidden_runtime"] = _with_answer(
        "q4",
        (
            "def w_statistics(A, y, Qyy):\n"
            "    f = getattr(lsq, 'f' + 'it')\n"
            "    return getattr(lsq, 'w_' + 'tests')(f(A, y, Qyy), 0.05).statistic"
        ),
    )
    # right values through the private implementation of the forbidden w_tests, imported
    # before the function runs (issue 26): a function question's call reports it as w_tests
    subs["forbidden_private_twin"] = _with_answer(
        "q4",
        _cell(_solution(), "q4-answer")["source"]
        .replace(
            "def w_statistics", "from course.lsq._tests import _w_test_result\n\n\ndef w_statistics"
        )
        .replace(
            "    return numerator / denominator",
            "    w = numerator / denominator\n"
            "    return _w_test_result(w, np.ones_like(w), np.ones_like(w), 0.05).statistic",
        ),
    )
    # the demo student's right T, computed (a hard-coded number went stale when the data changed)
    checks = load_checks(SOLUTION_DIR)
    demo_t = checks.questions["q6"].expected(data=checks.data_for("survey", "demo"))
    subs["copied_numbers"] = _with_answer("q6", f"T_mine = {float(demo_t)!r}  # the demo student's")
    # a Monte Carlo answer that does not simulate: what the test promises, not what it does
    subs["constant_rate"] = _with_answer(
        "q8", ("def rejection_rate(A, Qyy, alpha, n_runs, seed, bias):\n    return alpha")
    )
    subs.update(_issue_11_attacks(env))
    subs["empty"] = {"cells": [], "metadata": {}, "nbformat": 4, "nbformat_minor": 5}
    subs["not_json"] = "{ this is not json"
    subs["not_a_notebook"] = json.dumps({"hello": "world"})
    return subs


W_TESTS = "getattr(lsq, 'w_' + 'tests')(getattr(lsq, 'f' + 'it')(A, y, Qyy), 0.05).statistic"


def _q3_honest() -> str:
    source = _cell(_solution(), "q3-answer")["source"]
    return source.replace("def overall_model_test_stat(", "def _honest_q3(")


def _attack_in_q3(attack: str) -> dict:
    """A notebook whose q3 function first runs ``attack`` (which appends what it got hold of to
    ``leaked``) and then answers honestly. Anything leaked is raised, so it would reach the
    student's feedback (every case of q3 reports the error)."""
    body = "".join("    " + line + "\n" for line in attack.strip("\n").split("\n"))
    return _with_answer(
        "q3",
        _q3_honest()
        + "\n\n\ndef overall_model_test_stat(A, y, Qyy, alpha):\n"
        + "    import os, socket, stat\n    leaked = []\n"
        + body
        + "    if leaked:\n"
        + "        raise RuntimeError('LEAKED ' + ' | '.join(map(str, leaked)))\n"
        + "    return _honest_q3(A, y, Qyy, alpha)\n",
    )


def _issue_11_attacks(env) -> dict[str, object]:
    secret_paths = [
        str(env.solution_dir / "checks.py"),
        str(env.solution_secret),
        str(env.home_secret),
        str(env.victim),
    ]
    subs: dict[str, object] = {}
    # reading secrets with os.open(folder) + a relative path and dir_fd, and through /proc
    subs["reads_with_dir_fd"] = _attack_in_q3(
        (
            f"for p in {secret_paths!r}:\n"
            "    for base, rel in (('/', p.lstrip('/')), ('/proc/self/root', p.lstrip('/')),\n"
            "                      (os.path.dirname(p), os.path.basename(p))):\n"
            "        try:\n"
            "            d = os.open(base, os.O_RDONLY)\n"
            "            fd = os.open(rel, os.O_RDONLY, dir_fd=d)\n"
            "            leaked.append(os.read(fd, 100).decode(errors='replace'))\n"
            "            break\n"
            "        except OSError:\n"
            "            pass\n"
        ),
    )
    # listings tell where the submissions and the output are
    subs["lists_folders"] = _attack_in_q3(
        (
            f"for d in ('/', '/tmp', {str(env.root)!r}, {str(env.root.parent)!r}):\n"
            "    try:\n"
            "        leaked.extend(os.listdir(d))\n"
            "    except OSError:\n"
            "        pass\n"
        ),
    )
    # writing outside the temporary folder with dir_fd, and renaming with src_dir_fd
    marker = env.marker
    subs["writes_with_dir_fd"] = _with_answer(
        "q2",
        (
            "import os\n"
            f"for d in ({str(env.course)!r}, {str(env.home)!r}, '/tmp'):\n"
            "    try:\n"
            "        dfd = os.open(d, os.O_RDONLY)\n"
            f"        fd = os.open('{marker}', os.O_WRONLY | os.O_CREAT, 0o644, dir_fd=dfd)\n"
            "        os.write(fd, b'pwned')\n"
            "    except OSError:\n"
            "        pass\n"
            "try:\n"
            f"    cfd = os.open({str(env.course)!r}, os.O_RDONLY)\n"
            f"    os.rename('README.md', '{marker}.md', src_dir_fd=cfd, dst_dir_fd=cfd)\n"
            "except OSError:\n"
            "    pass\n"
            "def line_residuals(t, y):\n"
            "    A = np.column_stack([np.ones(len(t)), t])\n"
            "    return y - A @ np.linalg.lstsq(A, y, rcond=None)[0]"
        ),
    )
    # switching the audit hook off through gc, then reading, writing and connecting freely
    subs["hook_switched_off"] = _attack_in_q3(
        (
            "import gc\n"
            "for f in gc.get_objects():\n"
            "    if type(f).__name__ == 'function' and f.__name__ == 'hook' and f.__closure__:\n"
            "        for name, cell in zip(f.__code__.co_freevars, f.__closure__):\n"
            "            if name == 'blocked':\n"
            "                cell.cell_contents = frozenset()\n"
            "            elif name == 'path_events':\n"
            "                cell.cell_contents = {}\n"
            "            elif name in ('readable', 'writable'):\n"
            "                cell.cell_contents = lambda full: True\n"
            f"for p in {secret_paths!r}:\n"
            "    try:\n"
            "        leaked.append(open(p).read(100))\n"
            "    except OSError:\n"
            "        pass\n"
            "try:\n"
            f"    open('/tmp/{marker}-hook', 'w').write('pwned')\n"
            "except OSError:\n"
            "    pass\n"
            "try:\n"
            f"    socket.create_connection(('127.0.0.1', {env.port}), timeout=2).sendall(b'pwned')\n"
            "    leaked.append('connected')\n"
            "except OSError:\n"
            "    pass\n"
        ),
    )
    # a refused socketpair() must not leave sockets open in the child
    subs["socketpair_leak"] = _attack_in_q3(
        (
            "try:\n"
            "    socket.socketpair()\n"
            "except OSError:\n"
            "    pass\n"
            "for fd in map(int, os.listdir('/proc/self/fd')):\n"
            "    try:\n"
            "        if stat.S_ISSOCK(os.fstat(fd).st_mode):\n"
            "            leaked.append(f'open socket {fd}')\n"
            "    except OSError:\n"
            "        pass\n"
        ),
    )
    # forbidden calls from code whose globals claim to be the library
    forged = f"def w_statistics(A, y, Qyy):\n    return {W_TESTS}\n"
    subs["forged_library_name"] = _with_answer(
        "q4",
        (
            "_g = {'__name__': 'course.lsq', 'lsq': lsq}\n"
            f"exec({forged!r}, _g)\n"
            "w_statistics = _g['w_statistics']\n"
        ),
    )
    # a forbidden call, then clearing the child's own record of it
    subs["cleared_record"] = _with_answer(
        "q4",
        (
            "import sys\n"
            "def w_statistics(A, y, Qyy):\n"
            f"    out = {W_TESTS}\n"
            "    for m in list(sys.modules.values()):\n"
            "        state = getattr(m, '_STATE', None)\n"
            "        if state is not None and hasattr(state, 'hits'):\n"
            "            state.hits.clear()\n"
            "    return out\n"
        ),
    )
    # the original function fished out of the tripwire, or a fresh module from source
    subs["unwrapped_original"] = _with_answer(
        "q4",
        (
            "def w_statistics(A, y, Qyy):\n"
            "    w, f = getattr(lsq, 'w_' + 'tests'), getattr(lsq, 'f' + 'it')\n"
            "    w = (getattr(w, '__kwdefaults__', None) or {}).get('__original', w)\n"
            "    f = (getattr(f, '__kwdefaults__', None) or {}).get('__original', f)\n"
            "    return w(f(A, y, Qyy), 0.05).statistic\n"
        ),
    )
    subs["reloaded_module"] = _with_answer(
        "q4",
        (
            "import importlib\n"
            "def w_statistics(A, y, Qyy):\n"
            "    fresh = importlib.reload(lsq)\n"
            "    return getattr(fresh, 'w_' + 'tests')(getattr(fresh, 'f' + 'it')(A, y, Qyy), 0.05).statistic\n"
        ),
    )
    subs["=1+1"] = _solution()  # an honest student whose ID is a spreadsheet formula
    return subs


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("hostile")
    token = secrets.token_hex(8)
    env = types.SimpleNamespace(root=tmp, marker=f"pwned-{token}", token=token)
    # a copy of the course, with a secret beside checks.py and a file of the "repository"
    env.course = tmp / "course"
    env.solution_dir = env.course / "solutions" / NAME
    shutil.copytree(SOLUTION_DIR, env.solution_dir)
    (env.course / "README.md").write_text("the course repository\n")
    env.solution_secret = env.solution_dir / "secret-answers.txt"
    env.solution_secret.write_text(f"SOLSECRET-{token}\n")
    env.home = tmp / "home"
    env.home.mkdir()
    env.home_secret = env.home / "token.txt"
    env.home_secret.write_text(f"HOMESECRET-{token}\n")
    sub_dir, out = tmp / f"subs-{token}", tmp / f"out-{token}"
    sub_dir.mkdir()
    env.victim = sub_dir / "victim.ipynb"
    outside = tmp / "outside"
    outside.mkdir()
    env.sentinel = outside / "sentinel.txt"
    env.sentinel.write_text("original")
    listener = socket.create_server(("127.0.0.1", 0))
    listener.setblocking(False)
    env.port = listener.getsockname()[1]
    victim = _solution()
    victim["cells"].append(
        {"cell_type": "markdown", "id": "victim-note", "metadata": {}, "source": f"VICTIM-{token}"}
    )
    subs = _submissions(env)
    subs["victim"] = victim
    for sid, nb in subs.items():
        text = nb if isinstance(nb, str) else json.dumps(nb)
        if sid == "solution":
            (sub_dir / sid).mkdir()
            (sub_dir / sid / f"{NAME}.ipynb").write_text(text)  # the folder form
        else:
            (sub_dir / f"{sid}.ipynb").write_text(text)
    solution_nb = env.solution_dir / f"{NAME}.ipynb"
    (sub_dir / "symlinked_file.ipynb").symlink_to(solution_nb)  # the solution, as a link
    (sub_dir / "symlinked_folder").mkdir()
    (sub_dir / "symlinked_folder" / f"{NAME}.ipynb").symlink_to(solution_nb)
    os.link(solution_nb, sub_dir / "hardlinked.ipynb")
    watched = {"course": env.course, "home": env.home, "submissions": sub_dir}
    before = {name: _sha_tree(folder) for name, folder in watched.items()}
    before_repo = _sha_tree(ROOT / "solutions")
    tmp_before = set(os.listdir("/tmp"))
    options = GradeOptions(jobs=2, timeout=TIMEOUT, memory_mb=512, progress=False)
    old_home = os.environ.get("HOME")
    os.environ["HOME"] = str(env.home)
    try:
        summary = grade(env.solution_dir, sub_dir, out, options)
    finally:
        if old_home is None:
            os.environ.pop("HOME", None)
        else:
            os.environ["HOME"] = old_home
    try:
        connection = listener.accept()[0]
        connection.close()
        connected = True
    except BlockingIOError:
        connected = False
    listener.close()
    rows = {
        json.loads(line)["student"]: json.loads(line)
        for line in (out / "results.jsonl").read_text().splitlines()
    }
    return {
        "summary": summary,
        "rows": rows,
        "out": out,
        "env": env,
        "sub_dir": sub_dir,
        "sentinel": env.sentinel,
        "watched": watched,
        "before": before,
        "before_repo": before_repo,
        "tmp_new": set(os.listdir("/tmp")) - tmp_before,
        "connected": connected,
        "expected_ids": set(subs) | {"symlinked_file", "symlinked_folder", "hardlinked"},
        "options": options,
        "solution_dir": env.solution_dir,
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
    assert set(rows) == graded["expected_ids"]
    with open(graded["out"] / "grades.csv") as f:
        table = list(csv.DictReader(f))
    assert [r["student"].removeprefix("'") for r in table] == sorted(rows)
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
    # q6 and q6_practice call the student's own q3 function, so they loop too, and q6b reads
    # q6's decision; the rest is unaffected
    _expect(
        graded["rows"]["ignores_sigint"],
        {"q3": "timeout", "q6": "timeout", "q6_practice": "timeout", "q6b": None},
    )


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
    for name, folder in graded["watched"].items():
        assert _sha_tree(folder) == graded["before"][name], name
    assert _sha_tree(ROOT / "solutions") == graded["before_repo"]
    from course.grading.batch.classreport import TABLES

    names = {p.name for p in graded["out"].iterdir()}
    tables = {f"report-{name}.csv" for name in TABLES}  # the report's tables, beside it
    assert names - tables == {
        "grades.csv",
        "results.jsonl",
        "feedback",
        "report.html",
        "record.sqlite",
    }


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


def test_forbidden_calls(graded):
    _expect(graded["rows"]["forbidden_static"], {"q3": "forbidden"})
    # an import is not a call: a right answer that imports a forbidden function keeps its points
    _expect(graded["rows"]["forbidden_unused_import"], {})
    row = graded["rows"]["forbidden_runtime"]
    _expect(row, {"q4": "forbidden"})
    assert "course.lsq.w_tests" in row["questions"]["q4"]["message"]
    row = graded["rows"]["forbidden_private_twin"]
    _expect(row, {"q4": "forbidden"})
    assert "course.lsq.w_tests" in row["questions"]["q4"]["message"]


def test_copied_numbers_fail_per_student_question(graded):
    # q6b reads the decision of q6's cell, which the copied number replaced
    _expect(graded["rows"]["copied_numbers"], {"q6": "fail", "q6b": None})


def test_monte_carlo_is_not_fooled_by_returning_alpha(graded):
    """q8 repeats the student's seeded simulation (issue 13): alpha is not a simulated rate,
    not even under H0, where it used to pass three cases of six."""
    row = graded["rows"]["constant_rate"]
    assert all(row["questions"][q]["points"] == pts for q, pts in POINTS.items() if q != "q8")
    q8 = row["questions"]["q8"]
    assert len(q8["cases"]) == 6 and not any(c["ok"] for c in q8["cases"])
    assert q8["status"] == "fail" and q8["points"] == 0


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
        if "hidden case" in fb:
            line = fb.split("hidden case", 1)[1].split("\n", 1)[0]
            # the tolerance rule "|got - expected| <= atol + rtol |expected|" names no value
            assert "expected" not in line.split("tolerance ", 1)[0], line


def test_rerun_resumes_and_regrade_is_identical(graded, tmp_path):
    out = graded["out"]
    before = (out / "results.jsonl").read_text()
    summary = grade(graded["solution_dir"], graded["sub_dir"], out, graded["options"])
    assert summary.graded == 0 and summary.resumed == len(graded["rows"])
    assert (out / "results.jsonl").read_text() == before
    # regrading from scratch gives identical rows (no timestamps, no temp paths)
    small = tmp_path / "subs"
    small.mkdir()
    for sid in ("untouched", "infinite_loop", "os_exit", "forged_result", "not_json"):
        src = graded["sub_dir"] / f"{sid}.ipynb"
        (small / src.name).write_bytes(src.read_bytes())
    out2 = tmp_path / "out2"
    grade(graded["solution_dir"], small, out2, graded["options"])
    again = {
        json.loads(l)["student"]: json.loads(l)
        for l in (out2 / "results.jsonl").read_text().splitlines()
    }
    for sid, row in again.items():  # identical but for the time it took
        assert row.pop("wall_seconds") >= 0 and graded["rows"][sid]["wall_seconds"] >= 0
        assert row == {k: v for k, v in graded["rows"][sid].items() if k != "wall_seconds"}, sid
    assert all(r["checks_sha256"] and r["version"] for r in again.values())


def test_summary_text(graded):
    text = graded["summary"].text()
    assert "q1" in text and "full marks" in text and "status:" in text


# -- issue 11: the kernel's walls ------------------------------------------------------------
def _out_text(graded) -> str:
    out = graded["out"]
    return "\n".join(p.read_text(errors="replace") for p in sorted(out.rglob("*")) if p.is_file())


def test_secrets_never_reach_the_output(graded):
    text, token = _out_text(graded), graded["env"].token
    for secret in ("SOLSECRET", "HOMESECRET", "VICTIM"):
        assert f"{secret}-{token}" not in text, secret
    assert "binomial_band" not in text and "CHECKS = Checks" not in text  # checks.py unread


def test_dir_fd_and_proc_cannot_read_secrets(graded):
    _expect(graded["rows"]["reads_with_dir_fd"], {})  # nothing leaked, so the answer stands


def test_listings_do_not_reveal_the_grader_s_folders(graded):
    token = graded["env"].token
    assert f"subs-{token}" not in _out_text(graded) and f"out-{token}" not in _out_text(graded)
    _expect(graded["rows"]["lists_folders"], {})


def test_dir_fd_cannot_write_or_rename_outside(graded):
    _expect(graded["rows"]["writes_with_dir_fd"], {})
    marker = graded["env"].marker
    assert not any(name.startswith(marker) for name in graded["tmp_new"])
    assert (graded["env"].course / "README.md").is_file()


def test_switching_the_audit_hook_off_gains_nothing(graded):
    _expect(graded["rows"]["hook_switched_off"], {})
    assert not graded["connected"], "a submission reached a TCP listener of the grading machine"
    assert not any(name.startswith(graded["env"].marker) for name in graded["tmp_new"])


def test_refused_socketpair_leaves_no_socket_open(graded):
    _expect(graded["rows"]["socketpair_leak"], {})


@pytest.mark.parametrize(
    "sid", ["forged_library_name", "cleared_record", "unwrapped_original", "reloaded_module"]
)
def test_forbidden_calls_cannot_be_forged(graded, sid):
    row = graded["rows"][sid]
    _expect(row, {"q4": None})  # zero points for q4, everything else untouched
    assert row["questions"]["q4"]["status"] in ("forbidden", "error"), row["questions"]["q4"]


def test_links_to_the_solution_are_refused(graded):
    for sid in ("symlinked_file", "symlinked_folder", "hardlinked"):
        row = graded["rows"][sid]
        assert row["total"] == 0 and row["status"] == "refused", row
        assert "refused" in " ".join(row["notes"]), row["notes"]


def test_honest_students_of_the_batch_keep_full_marks(graded):
    for sid in ("solution", "victim", "=1+1"):
        _expect(graded["rows"][sid], {})


def test_csv_cells_cannot_be_spreadsheet_formulas(graded):
    with open(graded["out"] / "grades.csv", newline="") as f:
        cells = [cell for row in csv.reader(f) for cell in row]
    assert "'=1+1" in cells
    assert not [c for c in cells if c[:1] in ("=", "+", "@") or (c[:1] == "-" and c[1:2].isalpha())]


def test_summary_names_the_slowest_students(graded):
    text = graded["summary"].text()
    slow = [line for line in text.splitlines() if line.startswith("slowest: ")]
    times = sorted((r["wall_seconds"], sid) for sid, r in graded["rows"].items())
    assert all(t >= 0 for t, _ in times)
    assert slow and all(sid in slow[0] for _, sid in times[-3:]), (slow, times[-3:])
    # a submission that times out on a question is slower than the honest solution
    assert graded["rows"]["infinite_loop"]["wall_seconds"] > TIMEOUT


# ---------------------------------------------------------------------------------------
# issue 25: whose submission is whose is decided by the LMS's names, never by the notebook
# ---------------------------------------------------------------------------------------
def _id_notebook(path: Path, sid: str, written: str | None = None) -> Path:
    """A notebook declaring ``sid`` (setup cell and submission metadata, with a forged time)."""
    nb = {
        "nbformat": 4,
        "nbformat_minor": 5,
        "metadata": {"course": {"submission": {"student_id": sid, "written": written or ""}}},
        "cells": [
            {
                "cell_type": "code",
                "id": "setup",
                "metadata": {"course": {"role": "setup"}},
                "source": f'STUDENT_ID = "{sid}"',
                "outputs": [],
                "execution_count": None,
            }
        ],
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(nb))
    return path


def _roster_file(tmp_path: Path):
    from course.grading.batch.roster import read_roster

    path = tmp_path / "roster.csv"
    path.write_text(
        "Student,ID,SIS User ID,SIS Login ID\n"
        '"Tim, Vic",101,v1,vic\n"Lory, Mal",102,m2,mal\n"Other, Ann",103,a3,ann\n'
    )
    return read_roster(path)


def _resolve(folder: Path, roster=None):
    from course.grading.batch.identity import resolve_identities
    from course.grading.batch.intake import find_submissions

    return resolve_identities(
        find_submissions(folder, NAME), NAME, roster.students if roster else None
    )


def _graded_file(identity, sid: str) -> str | None:
    entry = next(e for e in identity.entries if e.student == sid)
    return None if entry.path is None else entry.path.relative_to(entry.path.parents[1]).as_posix()


def test_a_moodle_upload_cannot_take_another_students_grade(tmp_path):
    """Issue 25.1: an extra upload in the attacker's Moodle folder declares the victim's ID and a
    future time; the victim keeps their own file. Issue 34: the upload is its uploader's (graded
    for m2, reported with both IDs), never the victim's."""
    subs = tmp_path / "subs"
    _id_notebook(subs / "Vic Tim_11_assignsubmission_file_" / f"{NAME}.ipynb", "v1", "2020")
    _id_notebook(subs / "Mal Lory_12_assignsubmission_file_" / "x.ipynb", "v1", "2999-01-01")
    identity = _resolve(subs, _roster_file(tmp_path))
    assert _graded_file(identity, "v1") == f"Vic Tim_11_assignsubmission_file_/{NAME}.ipynb"
    assert [a[:3] for a in identity.attached] == [
        ("Mal Lory_12_assignsubmission_file_/x.ipynb", "m2", "v1")
    ]
    m2 = next(e for e in identity.entries if e.student == "m2")
    assert not m2.refused and m2.path.name == "x.ipynb" and "graded as 'm2'" in m2.note
    assert not identity.conflicts
    assert any("Mal Lory" in f and "'v1'" in f for f in identity.flags)


def test_without_a_roster_a_claim_from_another_uploader_is_never_graded(tmp_path):
    """Issue 34: two uploaders claiming one ID quarantined both, so an extra upload took a
    classmate out of the batch; now the uploader with an ID of its own keeps only that."""
    subs = tmp_path / "subs"
    _id_notebook(subs / "Vic Tim_11_assignsubmission_file_" / f"{NAME}.ipynb", "v1")
    _id_notebook(subs / "Mal Lory_12_assignsubmission_file_" / f"{NAME}.ipynb", "m2")
    _id_notebook(subs / "Mal Lory_12_assignsubmission_file_" / "victim1.ipynb", "v1")
    identity = _resolve(subs)
    assert _graded_file(identity, "v1") == f"Vic Tim_11_assignsubmission_file_/{NAME}.ipynb"
    assert _graded_file(identity, "m2") == f"Mal Lory_12_assignsubmission_file_/{NAME}.ipynb"
    assert [c[0] for c in identity.conflicts] == [
        "Mal Lory_12_assignsubmission_file_/victim1.ipynb"
    ]
    assert identity.flags[0].startswith("WARNING: 3 file(s) are named by an LMS")
    # two uploaders with nothing but the same ID: nothing tells whose it is, both are held
    (subs / "Mal Lory_12_assignsubmission_file_" / f"{NAME}.ipynb").unlink()
    identity = _resolve(subs)
    assert _graded_file(identity, "v1") is None and len(identity.conflicts) == 2
    assert "give the LMS's roster export as --roster" in identity.conflicts[0][3]


def test_canvas_order_decides_between_one_students_files_not_the_written_time(tmp_path):
    subs = tmp_path / "subs"
    _id_notebook(subs / f"timvic_101_700_{NAME}.ipynb", "v1", "2999-01-01")  # forged time
    _id_notebook(subs / f"timvic_LATE_101_900_{NAME}-1.ipynb", "v1", "2000-01-01")
    # another Canvas user's upload declaring v1, with an even later file number: its uploader's
    _id_notebook(subs / f"lorymal_102_950_{NAME}.ipynb", "v1", "2999-12-31")
    identity = _resolve(subs, _roster_file(tmp_path))
    entry = next(e for e in identity.entries if e.student == "v1")
    assert entry.path.name == f"timvic_LATE_101_900_{NAME}-1.ipynb"
    assert [c[:3] for c in identity.attached] == [(f"lorymal_102_950_{NAME}.ipynb", "m2", "v1")]
    assert any("the last in the LMS's order" in f for f in identity.flags)


# ---------------------------------------------------------------------------------------
# issue 25.2 and 25.9: nothing a submission holds can stall or bloat the parent
# ---------------------------------------------------------------------------------------
class _Alarm:
    """Fail (instead of hanging the suite) when the parent's work on student text takes more
    than ``seconds``: the old code took tens of seconds on each of these inputs."""

    def __init__(self, seconds: int):
        self.seconds = seconds

    def __enter__(self):
        import signal

        def stop(signum, frame):
            raise TimeoutError(f"the parent spent more than {self.seconds} s on student text")

        self.old = signal.signal(signal.SIGALRM, stop)
        signal.alarm(self.seconds)

    def __exit__(self, *exc):
        import signal

        signal.alarm(0)
        signal.signal(signal.SIGALRM, self.old)


@pytest.mark.parametrize(
    "cell",
    [
        "\n".join(f"!echo {i}" for i in range(600)),  # the issue's 5 KB setup cell
        "\n".join(f"%time x{i} = {i}" for i in range(1_500)),
        "\n".join(f"y{i} = !ls" for i in range(1_000)),
    ],
)
def test_ipython_syntax_in_a_cell_cannot_stall_the_parent(cell):
    from course.grading.notebook import student_id_in

    with _Alarm(10):
        assert student_id_in('STUDENT_ID = "s1"\n' + cell) in (None, "s1")


def test_ipython_syntax_of_an_honest_cell_is_still_understood():
    from course.grading.notebook import student_id_in

    assert student_id_in('%matplotlib inline\n!pip list\nSTUDENT_ID = "s1"') == "s1"


def test_a_huge_cell_is_not_parsed_by_the_parent():
    from course.grading.notebook import MAX_PARSED_CHARS, python_source

    with pytest.raises(SyntaxError, match="larger than"):
        python_source("x = 1\n" * (MAX_PARSED_CHARS // 6 + 1))


def _handle(forbid=("numpy.linalg.inv",)):
    from course.grading.sandbox.parent import ChildHandle

    sandbox = types.SimpleNamespace(
        forbid=tuple(forbid),
        forbid_set=frozenset(forbid),
        instrumented=frozenset(forbid),
        labels=frozenset({"q1"}),
        limits=types.SimpleNamespace(files_mb=0),
    )
    req_r, req_w = os.pipe()
    resp_r, resp_w = os.pipe()
    ev_r, ev_w = os.pipe()
    for fd in (resp_r, ev_r, req_w):
        os.set_blocking(fd, False)
    child = ChildHandle(sandbox, os.getpid(), "/nonexistent", req_w, resp_r, ev_r)
    return child, resp_w, ev_w, (req_r, req_w, resp_r, resp_w, ev_r, ev_w)


def test_forbidden_call_reports_keep_one_entry_per_name():
    from course.grading.tripwire import EVENT

    child, _, ev_w, fds = _handle()
    try:
        os.set_blocking(ev_w, False)
        inv = b"numpy.linalg.inv"
        record = EVENT % (inv, inv, b"q1")
        for i in range(2_000):
            fakes = [
                EVENT % (b"made.up.name", inv, b""),  # not instrumented
                EVENT % (inv, b"made.up.name", b""),  # implements nothing forbidden
                EVENT % (inv, inv, b"label%d" % i),  # an unknown label: none
            ]
            os.write(ev_w, b"".join(fakes) * 7 + record)
            child._read_events()
        assert len(child._events) == 2 and child.events_reported == 2_000 * 22
        assert child.take_events() == [
            (inv.decode(), (inv.decode(),), ""),
            (inv.decode(), (inv.decode(),), "q1"),
        ]
        assert child.take_events() == []
    finally:
        for fd in fds:
            os.close(fd)


@pytest.mark.parametrize(
    "junk",
    [b"[" * 100_000, b"{" * 50_000, b'{"a":' * 30_000, b"\xff\xfe" * 1000, b"null"],
)
def test_a_malformed_reply_line_is_ignored_not_a_grader_error(junk):
    """Issue 25.9: only ValueError was caught; a line of 100,000 '[' raised RecursionError."""
    child, resp_w, _, fds = _handle()
    real = None
    try:
        import course.grading.sandbox.parent as parent_module

        nonce = "abcd"
        orig = parent_module.secrets.token_hex
        parent_module.secrets.token_hex = lambda n: nonce
        try:
            real = json.dumps({"id": 1, "nonce": nonce, "status": "ok"}).encode()
            import threading

            data = junk + b"\n" + real + b"\n"  # more than a pipe holds: written alongside
            writer = threading.Thread(target=lambda: os.write(resp_w, data), daemon=True)
            writer.start()
            reply = child.request("value", 5.0, name="x")
            writer.join(5)
        finally:
            parent_module.secrets.token_hex = orig
        assert reply["status"] == "ok"
    finally:
        for fd in fds:
            os.close(fd)


def test_a_deeply_nested_value_is_refused_by_the_decoder():
    from course.grading.codec import EncodingError, decode

    deep: list = []
    for _ in range(5_000):
        deep = [deep]
    with pytest.raises(EncodingError, match="nested too deeply"):
        decode(deep)
    assert decode([[[1.5]]]) == [[[1.5]]]


# ---------------------------------------------------------------------------------------
# issue 25.5: feedback that cannot leak or lie; control characters reach nothing
# ---------------------------------------------------------------------------------------
_FORGERIES = [
    "\n\n**Total: 17 / 17**\n",
    "<!-- the rest is hidden -->",
    "\x1b[2J\x1b[1;1H**Total: 17 / 17**\x07",
    "\r# q1: 1 / 1 (pass)",
    "`code` [link](http://x) | a | b |",
    "\u202e71 / 71 :latoT\u202c",
]


def _row_with_message(text: str):
    from course.grading.batch.results import CaseResult, QuestionResult, StudentResult

    row = StudentResult("s1", NAME, "0" * 64, "1", "none", 2.0)
    row.questions["q1"] = QuestionResult(
        0.0, 1.0, "error", f"your answer cell raised ValueError: {text}"
    )
    row.questions["q3"] = QuestionResult(
        0.0,
        1.0,
        "fail",
        "",
        [CaseResult("a", False, f"raised KeyError: {text}"), CaseResult("b", True)],
    )
    row.notes.append(f"Cell said {text}")
    return row


@pytest.mark.parametrize("text", _FORGERIES)
def test_student_text_cannot_forge_feedback(text):
    from course.grading.batch.reports import feedback_markdown

    fb = feedback_markdown(_row_with_message(text), load_checks(SOLUTION_DIR))
    assert sum(line.startswith("**Total:") for line in fb.splitlines()) == 1
    assert "<!--" not in fb and "](" not in fb.replace("\\](", "")
    assert not any(c in fb for c in "\x1b\x07\r\u202e\u202c")
    assert [line for line in fb.splitlines() if line.startswith("#")] == [
        line for line in fb.splitlines() if line.startswith(("# ", "## "))
    ] and not any(line.startswith("# q1") for line in fb.splitlines())


def test_control_characters_never_reach_csv_cells_file_names_or_the_console(tmp_path):
    from course.grading.batch.reports import write_csv
    from course.grading.vocabulary import is_student_id

    row = _row_with_message("\x1b]0;owned\x07 =1+1")
    write_csv([row], ["q1", "q3"], tmp_path / "grades.csv")
    raw = (tmp_path / "grades.csv").read_text()
    assert "\x1b" not in raw and "\x07" not in raw
    assert not is_student_id("s123\n") and not is_student_id("s123\x1b")
    subs = tmp_path / "subs"
    _id_notebook(subs / "evil\x1b[31m\x07name.ipynb", "placeholder-not-an-id")
    identity = _resolve(subs)
    (student,) = [e.student for e in identity.entries]
    assert student.isprintable() and "/" not in student and "\x1b" not in student
    assert all(flag.isprintable() for flag in identity.flags)


def test_a_hidden_case_s_exception_shows_its_type_and_the_student_s_line_only():
    """Issue 25.7: a function raising with its arguments put every hidden input into the
    feedback; the parent now shows Python's exception type and the student's own line."""
    from course.grading.batch.session import StudentSession

    me = types.SimpleNamespace(
        plan=types.SimpleNamespace(
            answer_sources={"q3": "def f(A, y):\n    raise ValueError(repr((A, y)))\n"}
        )
    )
    q = types.SimpleNamespace(id="q3")
    secret = "[[0.3141592, 2.71828]]"
    err = {"type": "ValueError", "message": secret, "line": 2}
    text = StudentSession._hidden_error(me, q, err)
    assert secret not in text and "0.314" not in text
    assert text.startswith("ValueError at line 2 of your answer: raise ValueError(repr((A, y)))")
    # an exception class named after the inputs, a forged line number: nothing of them shows
    forged = {"type": "Err_0_3141592", "message": secret, "line": 99}
    text = StudentSession._hidden_error(me, q, forged)
    assert "3141592" not in text and text.startswith("an exception (")


# ---------------------------------------------------------------------------------------
# issue 25.3 (5, 6): a child cannot change the fork server's scheduling or use System V IPC
# ---------------------------------------------------------------------------------------
def test_seccomp_keeps_scheduling_and_sysv_ipc_to_the_child_itself():
    import subprocess
    import sys
    import textwrap

    from course.grading.sandbox.isolation import seccomp

    if not seccomp.available():
        pytest.skip("no libseccomp on this machine")
    code = textwrap.dedent(
        """
        import ctypes, os, sys
        from course.grading.sandbox.isolation import seccomp
        libc = ctypes.CDLL(None, use_errno=True)
        server = int(sys.argv[1])  # a process standing for the fork server (own group)
        def attempt(f, *args):
            try:
                f(*args)
                return "yes"
            except OSError:
                return "no"
        mine = os.sched_getaffinity(0)
        assert seccomp.install()
        print(attempt(os.sched_setaffinity, server, {min(mine)}),
              attempt(os.setpriority, os.PRIO_PROCESS, server, 19),
              attempt(os.setpriority, os.PRIO_USER, 54321, 19),  # a user with no processes
              attempt(os.setpriority, os.PRIO_PGRP, server, 19),
              attempt(os.sched_setscheduler, server, os.SCHED_IDLE, os.sched_param(0)),
              attempt(os.sched_setparam, server, os.sched_param(0)),
              attempt(os.sched_setscheduler, 0, os.SCHED_FIFO, os.sched_param(1)),
              attempt(os.setpriority, os.PRIO_PROCESS, 0, -5))
        shm = libc.shmget(0, 1 << 20, 0o1600)  # IPC_PRIVATE | IPC_CREAT
        msg = libc.msgget(0, 0o1600)
        sem = libc.semget(0, 1, 0o1600)
        print("no" if shm == -1 else "yes", "no" if msg == -1 else "yes",
              "no" if sem == -1 else "yes")
        for ident, ctl in ((shm, libc.shmctl), (msg, libc.msgctl)):
            if ident != -1:
                ctl(ident, 0, None)  # IPC_RMID: leave nothing behind on the old code
        if sem != -1:
            libc.semctl(sem, 0, 0)
        print(attempt(os.sched_setaffinity, 0, mine),
              attempt(os.setpriority, os.PRIO_PROCESS, 0, os.getpriority(os.PRIO_PROCESS, 0)),
              attempt(os.sched_setscheduler, 0, os.SCHED_OTHER, os.sched_param(0)))
        """
    )
    # the target is a sleeper in its own session: on the old code the child changed only it
    server = subprocess.Popen(["sleep", "60"], start_new_session=True)
    try:
        before = (os.sched_getaffinity(server.pid), os.getpriority(os.PRIO_PROCESS, server.pid))
        out = subprocess.run(
            [sys.executable, "-c", code, str(server.pid)],
            capture_output=True,
            text=True,
            timeout=60,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
        )
        after = (os.sched_getaffinity(server.pid), os.getpriority(os.PRIO_PROCESS, server.pid))
    finally:
        server.kill()
        server.wait()
    assert out.returncode == 0, out.stderr
    lines = out.stdout.split("\n")
    assert lines[0].split() == ["no"] * 8  # nothing aimed at another process, no real time
    assert lines[1].split() == ["no"] * 3  # no System V shared memory, queues, semaphores
    assert lines[2].split() == ["yes"] * 3  # the child's own thread keeps its calls
    assert after == before


# ---------------------------------------------------------------------------------------
# issue 25.4: a child that stays root keeps root's user ID but none of its powers
# ---------------------------------------------------------------------------------------
@pytest.mark.skipif(os.geteuid() != 0, reason="needs root (a root child)")
def test_a_root_child_drops_every_capability(tmp_path):
    import subprocess
    import sys
    import textwrap

    host = tmp_path / "host.txt"  # a host file of another user, as a root child could reach
    host.write_text("x")
    os.chown(host, 65534, 65534)
    os.chmod(host, 0o640)
    code = textwrap.dedent(
        f"""
        import os, socket
        from course.grading.sandbox.isolation import privileges
        def attempt(f, *args):
            try:
                f(*args)
                return "yes"
            except OSError:
                return "no"
        privileges.drop_capabilities()
        path = {str(host)!r}
        print(os.geteuid(),
              attempt(os.chmod, path, 0o666), attempt(os.chown, path, 0, 0),
              attempt(os.utime, path, (0, 0)), attempt(socket.sethostname, socket.gethostname()),
              attempt(os.setpriority, os.PRIO_PROCESS, 0, -1),
              attempt(os.sched_setscheduler, 0, os.SCHED_FIFO, os.sched_param(1)),
              attempt(os.setpriority, os.PRIO_PROCESS, 1, 0),
              attempt(open, "/proc/self/status"))
        print([l for l in open("/proc/self/status") if l.startswith(("CapEff", "CapBnd", "NoNewPrivs"))])
        """
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=60,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert out.returncode == 0, out.stderr
    first, status = out.stdout.split("\n")[:2]
    assert first.split() == ["0"] + ["no"] * 7 + ["yes"], out.stdout
    assert "CapEff:\\t0000000000000000" in status and "NoNewPrivs:\\t1" in status
    assert host.stat().st_mode & 0o777 == 0o640 and host.stat().st_uid == 65534


# ioctl requests are laid out differently there (_IOC_WRITE is 4, shifted by 29)
_OTHER_IOC_LAYOUT = platform.machine().startswith(("ppc", "powerpc", "mips", "sparc", "alpha"))


def test_seccomp_refuses_every_change_of_file_metadata(tmp_path):
    """Issue 25.4 for every child, root or not: a child of an ordinary grader owns that user's
    files as a root child owns root's. chmod, chown, utime, extended attributes and chattr's
    inode flags are refused with EPERM (not merely unsupported here), by path, descriptor and
    ``dir_fd``; reading metadata and writing the file stay allowed."""
    import subprocess
    import sys
    import textwrap

    from course.grading.sandbox.isolation import seccomp

    if not seccomp.available():
        pytest.skip("no libseccomp on this machine")
    target = tmp_path / "mine.txt"
    target.write_text("x")
    target.chmod(0o640)
    os.utime(target, (1_000_000_000, 1_000_000_000))
    before = target.stat()
    code = textwrap.dedent(
        f"""
        import errno, fcntl, os, struct
        from course.grading.sandbox.isolation import seccomp
        path = {str(target)!r}
        def answer(f, *args, **kwargs):
            try:
                f(*args, **kwargs)
                return "yes"
            except OSError as exc:
                return "EPERM" if exc.errno == errno.EPERM else "other"
        fd = os.open(path, os.O_RDWR)
        handle = os.open(os.path.dirname(path), os.O_PATH | os.O_DIRECTORY)
        name = os.path.basename(path)
        no_flags = struct.pack("l", 0)  # chattr's flags, all off (a fresh file has none)
        write = 4 << 29 if {_OTHER_IOC_LAYOUT!r} else 1 << 30  # _IOW of this architecture
        set_flags = write | (struct.calcsize("l") << 16) | (ord("f") << 8) | 2
        set_fsxattr = write | (28 << 16) | (ord("X") << 8) | 32
        assert seccomp.install()
        st = os.stat(path)
        print(answer(os.chmod, path, 0o666), answer(os.chmod, fd, 0o666),
              answer(os.chmod, name, 0o666, dir_fd=handle),
              answer(os.chown, path, st.st_uid, st.st_gid), answer(os.chown, fd, -1, -1),
              answer(os.chown, name, -1, -1, dir_fd=handle), answer(os.lchown, path, -1, -1),
              answer(os.utime, path, (0, 0)), answer(os.utime, fd, (0, 0)),
              answer(os.utime, name, (0, 0), dir_fd=handle), answer(os.utime, path, None),
              answer(os.setxattr, path, "user.mark", b"x"), answer(os.setxattr, fd, "user.mark", b"x"),
              answer(os.removexattr, path, "user.mark"),
              answer(fcntl.ioctl, fd, set_flags, no_flags),
              answer(fcntl.ioctl, fd, set_fsxattr, bytes(28)))
        print(answer(os.stat, path), answer(os.write, fd, b"y"))
        """
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=60,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert out.returncode == 0, out.stderr
    refused, allowed = out.stdout.split("\n")[:2]
    assert refused.split() == ["EPERM"] * 16, out.stdout
    assert allowed.split() == ["yes", "yes"]
    after = target.stat()
    assert (after.st_mode, after.st_uid, after.st_gid) == (
        before.st_mode,
        before.st_uid,
        before.st_gid,
    )


_METADATA_ATTACK = """
import ctypes, gc, os
for f in gc.get_objects():  # the audit hook off first: only the kernel's answer counts
    if type(f).__name__ == 'function' and f.__name__ == 'hook' and f.__closure__:
        for name, cell in zip(f.__code__.co_freevars, f.__closure__):
            if name == 'blocked':
                cell.cell_contents = frozenset()
            elif name == 'path_events':
                cell.cell_contents = {}
def attempt(f, *args, **kwargs):
    try:
        f(*args, **kwargs)
        return 'yes'
    except OSError:
        return 'no'
folder = os.path.dirname(HOST)
handle = os.open(folder, os.O_PATH | os.O_DIRECTORY)  # Landlock lets any path be walked
# a file it may read, root's where Python is installed by root: the same mode, owner and
# times back (harmless should the call pass), by descriptor
fd = os.open(os.__file__, os.O_RDONLY)
st = os.fstat(fd)
name = os.path.basename(HOST)
host = [
    attempt(os.chmod, HOST, 0o666),
    attempt(os.chmod, name, 0o666, dir_fd=handle),
    attempt(os.chmod, fd, st.st_mode & 0o7777),
    attempt(os.chmod, folder, 0o777),
    attempt(os.utime, HOST, (0, 0)),
    attempt(os.utime, name, (0, 0), dir_fd=handle),
    attempt(os.utime, fd, ns=(st.st_atime_ns, st.st_mtime_ns)),
    attempt(os.chown, HOST, 0, 0),
    attempt(os.chown, name, 0, 0, dir_fd=handle),
    attempt(os.chown, fd, st.st_uid, st.st_gid),
    attempt(os.setxattr, HOST, 'user.mark', b'x'),
    attempt(os.removexattr, HOST, 'user.kept'),
]
with open('mine.txt', 'w') as f:  # its own folder stays writable
    own_write = 'yes' if f.write('x') == 1 else 'no'
own = [
    attempt(os.chmod, 'mine.txt', 0o600),
    attempt(os.utime, 'mine.txt', (0, 0)),
    attempt(os.chown, 'mine.txt', 0, 0),
]
"""


@pytest.mark.skipif(os.geteuid() != 0, reason="needs root (a child that stays root)")
def test_a_root_child_cannot_change_the_metadata_of_host_files(tmp_path):
    """Issue 25.10: with Landlock alone and children that stay root, a child turned a host
    file from 640 to 666 with mtime 0 and made the grader's folders 0777 through O_PATH
    handles: Landlock has no right for metadata, and as the owner (uid 0) of root's files it
    needs no capability. Seccomp refuses chmod, chown, utime and extended attributes outright,
    by path, descriptor or ``dir_fd``, for every child (also on its own files)."""
    from course.grading.codec import decode
    from course.grading.sandbox.isolation import IsolationError, detect
    from course.grading.sandbox.parent import Limits, Sandbox

    try:
        isolation = detect(namespaces=False)
    except IsolationError:
        pytest.skip("no file-system isolation here")
    if isolation.landlock == 0 or not isolation.seccomp:
        pytest.skip("needs Landlock and libseccomp")
    folder = tmp_path / "grader-output"  # root's, as the grader's folders are
    folder.mkdir(mode=0o755)
    host = folder / "grades.csv"
    host.write_text("s1,17\n")
    host.chmod(0o640)
    try:
        os.setxattr(host, "user.kept", b"1")
        xattrs = True
    except OSError:  # a file system without user attributes (tmpfs before Linux 6.6)
        xattrs = False
    os.utime(host, (1_000_000_000, 1_000_000_000))
    before = [(p.stat().st_mode, p.stat().st_uid, p.stat().st_mtime_ns) for p in (folder, host)]
    # the child stays root: no user to switch to, as where nobody cannot read the Python
    # installation
    isolation = isolation.with_(drop_to=None)
    source = _METADATA_ATTACK.replace("HOST", repr(str(host)))
    with Sandbox(limits=Limits(memory_mb=512), isolation=isolation) as sandbox:
        child = sandbox.start({"student_id": "s1", "assignment": NAME, "data": {}})
        try:
            info = child.info
            reply = child.request("run", 20, source=source)
            assert reply["status"] == "ok", reply
            answers = {
                name: decode(child.request("value", 20, name=name)["value"])
                for name in ("host", "own", "own_write")
            }
        finally:
            child.close()
    assert info["uid"] == 0 and info["landlock"] and info["seccomp"], info
    after = [(p.stat().st_mode, p.stat().st_uid, p.stat().st_mtime_ns) for p in (folder, host)]
    assert after == before
    if xattrs:
        assert os.listxattr(host) == ["user.kept"]
    assert answers["host"] == ["no"] * 12, answers
    assert answers["own"] == ["no"] * 3, answers  # one policy: metadata is never a child's
    assert answers["own_write"] == "yes"


# ---------------------------------------------------------------------------------------
# issue 25.2: the parent's memory stays within a fixed bound whatever the submissions hold
# ---------------------------------------------------------------------------------------
_MEMORY_SCRIPT = """
import json, sys
from pathlib import Path
from course.grading.batch.driver import grade
from course.grading.batch.options import GradeOptions

def status(field):  # bytes; ru_maxrss would count the pages of the process that forked us
    line = next(l for l in open("/proc/self/status") if l.startswith(field + ":"))
    return int(line.split()[1]) * 1024

solution_dir, warm, subs, out = map(Path, sys.argv[1:5])
options = dict(jobs=2, timeout=float(sys.argv[5]), memory_mb=512, progress=False,
               namespaces=sys.argv[6] == "namespaces")
grade(solution_dir, warm, out / "warm", GradeOptions(**options))  # every import, one honest run
with open("/proc/self/clear_refs", "w") as f:
    f.write("5")  # the high-water mark starts again from the resident size now
idle = status("VmRSS")
summary = grade(solution_dir, subs, out / "hostile", GradeOptions(**options))
print(json.dumps({"idle": idle, "peak": status("VmHWM"), "seconds": summary.seconds}))
"""


def _huge_setup(source: str) -> dict:
    nb = _solution()
    _cell(nb, "setup")["source"] = source
    return nb


def _bloating_submissions(folder: Path) -> dict[str, str]:
    """What each file would cost a parent that decodes it whole: gigabytes."""
    folder.mkdir()
    honest = json.dumps(_solution())
    setup = _cell(_solution(), "setup")["source"]
    files = {
        "honest_a": honest,
        "honest_b": honest,
        # ~48 MB of empty lists: ~1.1 GB as Python objects
        "fifty_mb": '{"cells": [], "metadata": {}, "x": [' + "[]," * 16_000_000 + "[]]}",
        "deep": "[" * 5_000_000,
        "many_cells": json.dumps(
            {"cells": [{"cell_type": "code", "source": "x=1"}] * 200_000, "metadata": {}}
        ),
        "tiny_strings": json.dumps(
            {"cells": [{"cell_type": "code", "source": ["a"] * 4_000_000}], "metadata": {}}
        ),
        "wide_string": json.dumps(  # one non-ASCII character makes a str 4 bytes a character
            {"cells": [{"cell_type": "code", "source": "\U0001f600" + "a" * 40_000_000}]}
        ),
        "huge_setup": json.dumps(_huge_setup(setup + "x=1\n" * 200_000)),
        "huge_answer": json.dumps(
            _with_answer(
                "q1",
                "def line_estimate(t, y):\n    return 0\n"
                + "(" * 40
                + "1"
                + ")" * 40
                + "\n" * 900_000,
            )
        ),
        "reply_items": json.dumps(_with_answer("q1", _Q1_RETURNS + "[[]] * 2_000_000")),
        "reply_bytes": json.dumps(_with_answer("q1", _Q1_RETURNS + "'\\u00e9' * 2_000_000")),
        "reply_string": json.dumps(
            _with_answer("q1", _Q1_RETURNS + "'\U0001f600' + 'a' * 7_000_000")
        ),
    }
    for sid, text in files.items():
        (folder / f"{sid}.ipynb").write_text(text)
    return files


#: The memory test bounds memory, not time: none of its submissions loops, so a per-call
#: timeout only has to be long enough that a busy machine never turns an honest call into a
#: "timeout" (3 s did, at load 13-26 in a full .ci/run).
_MEMORY_TEST_TIMEOUT = 120.0


@pytest.mark.parametrize("namespaces", [True, False], ids=["all-layers", "landlock-alone"])
def test_the_parent_s_memory_is_bounded_whatever_the_submissions_hold(tmp_path, namespaces):
    """Issue 25.2: a 1.2 MB setup cell added 687 MB to the grader, and a 50 MB notebook of
    empty lists costs over a gigabyte to decode. Submissions are decoded in sandboxed reader
    children now, and a reply is bounded in bytes and values before the parent decodes it:
    the grader's peak memory stays within 300 MB of its idle size."""
    import subprocess
    import sys

    from course.grading.sandbox.isolation import IsolationError, detect

    try:
        detect(namespaces=namespaces)
    except IsolationError:
        pytest.skip("no file-system isolation here")
    warm, subs, out = tmp_path / "warm", tmp_path / "subs", tmp_path / "out"
    warm.mkdir()
    (warm / "warm.ipynb").write_text(json.dumps(_solution()))
    _bloating_submissions(subs)
    run = subprocess.run(
        [sys.executable, "-c", _MEMORY_SCRIPT, SOLUTION_DIR, warm, subs, out]
        + [str(_MEMORY_TEST_TIMEOUT)]
        + ["namespaces" if namespaces else "landlock"],
        capture_output=True,
        text=True,
        timeout=900,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert run.returncode == 0, run.stderr[-3000:]
    measured = json.loads(run.stdout.strip().splitlines()[-1])
    grown = (measured["peak"] - measured["idle"]) / 1e6
    rows = {
        json.loads(line)["student"]: json.loads(line)
        for line in (out / "hostile" / "results.jsonl").read_text().splitlines()
    }
    assert grown < 300, (grown, {sid: row["status"] for sid, row in rows.items()})
    print(f"the parent grew by {grown:.0f} MB over its idle size")
    for sid in ("honest_a", "honest_b"):
        _expect(rows[sid], {})
    for sid in ("fifty_mb", "deep", "many_cells", "tiny_strings", "wide_string"):
        assert rows[sid]["status"] == "invalid notebook", (sid, rows[sid])
        assert rows[sid]["total"] == 0
    notes = {sid: " ".join(rows[sid]["notes"]) for sid in rows}
    assert "2,000" in notes["many_cells"] and "1,000,000 characters" in notes["tiny_strings"]
    assert "nested" in notes["deep"] or "too large" in notes["deep"]
    for sid in ("reply_items", "reply_bytes"):
        _expect(rows[sid], {"q1": None})
        assert "too large" in rows[sid]["questions"]["q1"]["message"], rows[sid]["questions"]
    _expect(rows["reply_string"], {"q1": None})
    _expect(rows["huge_answer"], {"q1": None})
    _expect(rows["huge_setup"], {})


# ---------------------------------------------------------------------------------------
# issue 25.3: no scheduling state crosses from one child to the next
# ---------------------------------------------------------------------------------------
_SCHEDULING = (
    "import os\n"
    "state = [sorted(os.sched_getaffinity(0)), os.getpriority(os.PRIO_PROCESS, 0),\n"
    "         os.sched_getscheduler(0)]\n"
)
_PIN_AND_RENICE = """
import os
done = []
server = os.getppid()  # the fork server
for name, call in [
    ("affinity", lambda: os.sched_setaffinity(server, {max(os.sched_getaffinity(0))})),
    ("nice", lambda: os.setpriority(os.PRIO_PROCESS, server, 19)),
    ("policy", lambda: os.sched_setscheduler(server, os.SCHED_IDLE, os.sched_param(0))),
]:
    try:
        call()
        done.append(name)
    except OSError:
        pass
"""


@pytest.mark.parametrize("namespaces", [True, False], ids=["all-layers", "landlock-alone"])
def test_a_child_cannot_leave_the_fork_server_pinned_or_niced(namespaces):
    """Issue 25.5: a child pinned the fork server to one CPU and niced it to 19, and every
    later student ran so. Seccomp refuses that, so it is off here: the server itself puts its
    affinity, nice value and policy back before each fork."""
    from course.grading.codec import decode
    from course.grading.sandbox.isolation import IsolationError, detect
    from course.grading.sandbox.parent import Limits, Sandbox

    try:
        isolation = detect(namespaces=namespaces)
    except IsolationError:
        pytest.skip("no file-system isolation here")
    if not namespaces and isolation.landlock == 0:
        pytest.skip("no Landlock on this kernel")
    init = {"student_id": "s1", "assignment": NAME, "data": {}}
    with Sandbox(limits=Limits(memory_mb=512, seccomp=False), isolation=isolation) as sandbox:
        states, attacked = [], []
        for attack in (_PIN_AND_RENICE, ""):
            child = sandbox.start(init)
            try:
                assert child.request("run", 20, source=_SCHEDULING)["status"] == "ok"
                states.append(decode(child.request("value", 20, name="state")["value"]))
                if attack:
                    assert child.request("run", 20, source=attack)["status"] == "ok"
                    attacked = decode(child.request("value", 20, name="done")["value"])
            finally:
                child.close()
    if not attacked:
        pytest.skip(
            "the kernel refuses the calls here (e.g. a child without capabilities cannot change a server that has them)"
        )
    assert states[1] == states[0], (attacked, states)


# ---------------------------------------------------------------------------------------
# issue 25.12: nothing a child made survives its run, and a failed cleanup is reported
# ---------------------------------------------------------------------------------------
def _make_undeletable(path: Path) -> bool:
    """Make ``path`` impossible to remove for its cleanup, as an immutable file left by a
    child would be: ``chattr +i`` as root (where the file system has the flag), else a
    read-only folder around it (a cleanup that is not root cannot empty it)."""
    import subprocess

    if os.geteuid() == 0:
        done = subprocess.run(["chattr", "+i", str(path)], capture_output=True)
        return done.returncode == 0
    os.chmod(path.parent, 0o500)
    return True


def _make_deletable(path: Path) -> None:
    import subprocess

    if os.geteuid() == 0:
        subprocess.run(["chattr", "-i", str(path)], capture_output=True)
    else:
        os.chmod(path.parent, 0o700)
    shutil.rmtree(path.parent, ignore_errors=True)


@pytest.mark.parametrize("namespaces", [True, False], ids=["all-layers", "landlock-alone"])
def test_a_failed_cleanup_is_reported_in_the_row_and_on_the_console(
    tmp_path, monkeypatch, namespaces
):
    """Issue 25.12: an immutable file kept the run folder in /tmp after grading and the
    cleanup failed silently. Whatever a cleanup cannot remove is now named in the student's
    row (``cleanup_failed``) and in the console summary; everything else is removed."""
    from course.grading.sandbox.isolation import IsolationError, detect
    from course.grading.sandbox.parent import ChildHandle

    try:
        detect(namespaces=namespaces)
    except IsolationError:
        pytest.skip("no file-system isolation here")
    subs, out = tmp_path / "subs", tmp_path / "out"
    subs.mkdir()
    (subs / "honest.ipynb").write_text(json.dumps(_solution()))
    leaver = _with_answer(
        "q1",
        _cell(_solution(), "q1-answer")["source"]
        + "\nimport os\nos.mkdir('kept')\nopen('kept/left.txt', 'w').write('x')\n",
    )
    (subs / "leaver.ipynb").write_text(json.dumps(leaver))
    locked: list[Path] = []
    original = ChildHandle.close

    def close(self):  # the file becomes undeletable just before the cleanup, as chattr would
        left = Path(self.tmpdir) / "kept" / "left.txt"
        if left.exists() and left not in locked:
            if not _make_undeletable(left):
                pytest.skip("this file system has no immutable flag")
            locked.append(left)
        return original(self)

    monkeypatch.setattr(ChildHandle, "close", close)
    import tempfile

    private_tmp = tmp_path / "tmp"  # the run folders of this grading only
    private_tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(private_tmp))
    try:
        options = GradeOptions(
            jobs=2, timeout=TIMEOUT, memory_mb=512, progress=False, namespaces=namespaces
        )
        summary = grade(SOLUTION_DIR, subs, out, options)
        rows = {
            json.loads(line)["student"]: json.loads(line)
            for line in (out / "results.jsonl").read_text().splitlines()
        }
        left_files = sorted(p for p in private_tmp.rglob("*") if not p.is_dir())
    finally:
        for path in locked:
            _make_deletable(path)
    assert locked, (
        "the leaver's cell did not run",
        rows["leaver"]["questions"]["q1"],
        rows["leaver"]["notes"],
    )
    assert left_files == locked  # the undeletable file, and nothing else, survived
    assert "cleanup_failed" not in rows["honest"]
    failed = rows["leaver"]["cleanup_failed"]
    assert any(str(locked[0]) in f for f in failed), failed
    text = summary.text()
    assert "WARNING cleanup_failed" in text and str(locked[0]) in text
    assert str(locked[0]) not in (out / "feedback" / "leaver.md").read_text()
    _expect(rows["leaver"], {})
    _expect(rows["honest"], {})


# ---------------------------------------------------------------------------------------
# issue 25, done when: honest students graded after a hostile batch get what a clean batch gives
# ---------------------------------------------------------------------------------------
_STATE_ATTACKS = {
    "scheduler": (  # the fork server and the child itself: pinned, niced, idle
        "import os\n"
        "for call in (lambda: os.sched_setaffinity(os.getppid(), {0}),\n"
        "             lambda: os.setpriority(os.PRIO_PROCESS, os.getppid(), 19),\n"
        "             lambda: os.sched_setscheduler(os.getppid(), os.SCHED_IDLE, os.sched_param(0)),\n"
        "             lambda: os.sched_setaffinity(0, {0}),\n"
        "             lambda: os.setpriority(os.PRIO_PROCESS, 0, 19)):\n"
        "    try:\n        call()\n    except OSError:\n        pass\n"
    ),
    "leaves_files": (  # files in its folder, /tmp and /dev/shm, a process-wide umask
        "import os\nos.umask(0)\n"
        "for where in ('.', '/tmp', '/dev/shm'):\n"
        "    try:\n"
        "        open(os.path.join(where, 'left-behind.txt'), 'w').write('x' * 100000)\n"
        "    except OSError:\n        pass\n"
    ),
    "sysv": (
        "import ctypes\nlibc = ctypes.CDLL(None)\n"
        "shm = libc.shmget(0x5EED, 1 << 20, 0o1666)\nmsg = libc.msgget(0x5EED, 0o1666)\n"
    ),
    "forbidden_flood": "from course import lsq\nfor _ in range(20000):\n    lsq.fit\n",
}


def _honest_after_hostile_batch(folder: Path, env) -> None:
    folder.mkdir()
    subs = _submissions(env)
    chosen = {k: subs[k] for k in ("infinite_loop", "memory_bomb", "fork_bomb", "output_flood")}
    chosen |= {k: subs[k] for k in ("monkeypatch", "forbidden_runtime", "os_exit", "not_json")}
    q1 = _cell(_solution(), "q1-answer")["source"]
    for name, attack in _STATE_ATTACKS.items():
        chosen[name] = _with_answer("q1", attack + "\n" + q1)
    chosen["reply_items"] = _with_answer("q1", _Q1_RETURNS + "[[]] * 2_000_000")
    for sid, nb in chosen.items():
        text = nb if isinstance(nb, str) else json.dumps(nb)
        (folder / f"a_{sid}.ipynb").write_text(text)  # graded before the honest ones
    (folder / "a_deep.ipynb").write_text("[" * 200_000)


def _comparable(row: dict, out: Path) -> dict:
    """What a student gets: points, statuses and messages of every question, notes, feedback."""
    kept = {k: v for k, v in row.items() if k not in ("wall_seconds", "file")}
    kept["feedback"] = (out / "feedback" / f"{row['student']}.md").read_text()
    return kept


@pytest.mark.parametrize("namespaces", [True, False], ids=["all-layers", "landlock-alone"])
def test_honest_students_after_a_hostile_batch_get_what_a_clean_batch_gives(tmp_path, namespaces):
    from course.grading.sandbox.isolation import IsolationError, detect

    try:
        detect(namespaces=namespaces)
    except IsolationError:
        pytest.skip("no file-system isolation here")
    env = types.SimpleNamespace(
        root=tmp_path,
        sentinel=tmp_path / "outside" / "sentinel.txt",
        solution_dir=SOLUTION_DIR,
        course=ROOT,
        home=tmp_path,
        solution_secret=SOLUTION_DIR / "checks.py",
        home_secret=tmp_path / "home-token.txt",
        victim=tmp_path / "victim.ipynb",
        port=1,
        marker="pwned",
        token="0",
    )
    env.sentinel.parent.mkdir()
    env.sentinel.write_text("original")
    clean, hostile = tmp_path / "clean", tmp_path / "hostile"
    clean.mkdir()
    _honest_after_hostile_batch(hostile, env)
    for folder in (clean, hostile):
        for sid in ("zz_honest_1", "zz_honest_2"):
            (folder / f"{sid}.ipynb").write_text(json.dumps(_solution()))
    results = {}
    for folder in (clean, hostile):
        out = tmp_path / f"out-{folder.name}"
        options = GradeOptions(
            jobs=2, timeout=TIMEOUT, memory_mb=512, progress=False, namespaces=namespaces
        )
        summary = grade(SOLUTION_DIR, folder, out, options)
        rows = {r.student: r.to_json() for r in summary.rows}
        results[folder.name] = {
            sid: _comparable(rows[sid], out) for sid in ("zz_honest_1", "zz_honest_2")
        }
        assert len(rows) == len(list(folder.glob("*.ipynb")))
    assert results["hostile"] == results["clean"]
    for row in results["clean"].values():
        assert row["total"] == FULL and row["status"] == "ok"
    assert env.sentinel.read_text() == "original"


def test_a_sandbox_failure_while_reading_identities_does_not_abort_the_batch(tmp_path, monkeypatch):
    """The identity step reads every file in a reader child; a sandbox failure there (not the
    file's fault) must leave that file to its session, which reads it again."""
    from course.grading.sandbox.parent import Sandbox, SandboxError

    subs = tmp_path / "subs"
    subs.mkdir()
    for sid in ("s1", "s2"):
        (subs / f"{sid}.ipynb").write_text(json.dumps(_solution()))
    original, calls = Sandbox.read_notebook, []

    def flaky(self, source, timeout=60.0):
        calls.append(source)
        if len(calls) == 1:
            raise SandboxError("the fork server died")
        return original(self, source, timeout)

    monkeypatch.setattr(Sandbox, "read_notebook", flaky)
    options = GradeOptions(jobs=1, timeout=TIMEOUT, memory_mb=512, progress=False)
    summary = grade(SOLUTION_DIR, subs, tmp_path / "out", options)
    assert sorted(r.student for r in summary.rows) == ["s1", "s2"]
    assert all(r.total == FULL and r.status == "ok" for r in summary.rows)
    assert len(calls) == 3  # the failed file was read again by its session


def _fork_server_pid(top: int) -> int:
    """The host pid of the fork server below ``top`` (bubblewrap's process): the topmost
    descendant running the fork server's module (its children run the same command line)."""
    parents = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
                parents[int(entry)] = int(stat.rsplit(")", 1)[1].split()[1])
            except (OSError, ValueError, IndexError):
                continue

    def is_server(pid: int) -> bool:
        try:
            argv = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
        except OSError:
            return False
        return argv[1:3] == [b"-m", b"course.grading.sandbox.forkserver"]  # not bwrap's own

    level = [top]
    while level:
        found = [pid for pid in level if pid != top and is_server(pid)]
        if found:
            return found[0]
        level = [pid for pid, ppid in parents.items() if ppid in level]
    raise LookupError("no fork server below the sandbox's process")


def test_a_server_that_cannot_reset_itself_is_replaced_and_its_children_live_on(monkeypatch):
    """Should the fork server fail to put its scheduling back (here: an unprivileged server
    without the RLIMIT_NICE to lower its nice value again, as where a grader that is not root
    cannot raise that limit, niced to 19), later children come from a fresh server, and the
    children the old one forked keep running."""
    from course.grading.codec import decode
    from course.grading.sandbox.parent import Limits, Sandbox

    original = Sandbox._config
    monkeypatch.setattr(Sandbox, "_config", lambda self: original(self) | {"nice_back": False})
    init = {"student_id": "s1", "assignment": NAME, "data": {}}
    with Sandbox(limits=Limits(memory_mb=512)) as sandbox:
        if not (sandbox.isolation.bwrap and sandbox.isolation.unprivileged) or os.geteuid():
            pytest.skip("needs an unprivileged fork server in bubblewrap, started by root")
        first = sandbox.start(init)
        assert first.request("run", 20, source="x = 41")["status"] == "ok"
        os.setpriority(os.PRIO_PROCESS, _fork_server_pid(sandbox._server.pid), 19)
        second = sandbox.start(init)
        try:
            assert sandbox.server_restarts == 1
            assert second.request("run", 20, source=_SCHEDULING)["status"] == "ok"
            nice = decode(second.request("value", 20, name="state")["value"])[1]
            assert nice == os.getpriority(os.PRIO_PROCESS, 0)  # the grader's, not 19
            assert first.request("run", 20, source="x += 1")["status"] == "ok"
            assert decode(first.request("value", 20, name="x")["value"]) == 42
        finally:
            first.close()
            second.close()


# ---------------------------------------------------------------------------------------
# issue 36: forbidden calls that cannot be hidden, memory that cannot leave its limit
# ---------------------------------------------------------------------------------------
# q3 forbids course.lsq.fit and course.lsq.overall_model_test: both attacks compute q3 with
# exactly those calls. The first jumps over the report with a trace function's f_lineno.
_TRACE_JUMP = """
import sys
def overall_model_test_stat(A, y, Qyy, alpha):
    def tracer(frame, event, arg):
        if event == "call" and frame.f_code.co_name in ("fit", "overall_model_test"):
            first = [True]
            def local(frame, event, arg):
                if event == "line" and first[0]:
                    first[0] = False
                    try:
                        frame.f_lineno = frame.f_lineno + 1
                    except ValueError:
                        pass
                return local
            return local
        return None
    sys.settrace(tracer)
    try:
        r = lsq.overall_model_test(lsq.fit(A, y, Qyy), alpha)
    finally:
        sys.settrace(None)
    return r.statistic, r.critical_value, r.reject
"""
# The second copies the constant that marked library code into its own two-line function,
# built with the library module's namespace as globals.
_COPIED_MARKER = """
import types
import course.lsq as _L
_marks = [c for c in _L.fit.__code__.co_consts if type(c) is object]
def _mine(A, y, Qyy, alpha):
    r = overall_model_test(fit(A, y, Qyy), alpha)
    return r.statistic, r.critical_value, r.reject
overall_model_test_stat = types.FunctionType(
    _mine.__code__.replace(co_consts=_mine.__code__.co_consts + tuple(_marks)), vars(_L)
)
"""
# memory the address-space limit does not count: memfd pages written with write(), and files
# of the child's folder deleted but kept open (on a tmpfs they are memory too); 640 MB and
# 384 MB against a 512 MB limit (files: 256 MB), and then the right answer
_Q4_RIGHT = "    return _honest(A, y, Qyy)\n"


def _q4_after(fill: str) -> str:
    honest = _cell(_solution(), "q4-answer")["source"].replace("def w_statistics(", "def _honest(")
    body = "".join("    " + line + "\n" for line in fill.strip("\n").split("\n"))
    return (
        honest
        + "\n\ndef w_statistics(A, y, Qyy):\n    import os\n    held = []\n"
        + body
        + _Q4_RIGHT
    )


_MEMFD_FILL = """
for i in range(10):
    fd = os.memfd_create(f"hoard{i}")
    for _ in range(64):
        os.write(fd, b"x" * (1 << 20))
    held.append(fd)
"""
_DELETED_FILES_FILL = """
for i in range(8):
    fd = os.open(f"hoard{i}", os.O_RDWR | os.O_CREAT, 0o600)
    try:
        os.posix_fallocate(fd, 0, 48 << 20)
    except OSError:
        for _ in range(48):
            os.write(fd, b"x" * (1 << 20))
    os.unlink(f"hoard{i}")
    held.append(fd)
"""


@pytest.mark.parametrize("namespaces", [True, False], ids=["all-layers", "landlock-alone"])
def test_forbidden_calls_cannot_be_hidden_and_memory_cannot_leave_its_limit(tmp_path, namespaces):
    """Issue 36: a trace function's line jump over the report and a copied library marker
    scored q3 3/3; 640 MB of memfds and 384 MB of deleted files passed a 512 MB limit. They
    score 0 ``forbidden`` and 0 ``memory``, and an honest student of the batch keeps 17/17."""
    from course.grading.sandbox.isolation import IsolationError, detect

    try:
        isolation = detect(namespaces=namespaces)
    except IsolationError:
        pytest.skip("no file-system isolation here")
    if not namespaces and isolation.landlock == 0:
        pytest.skip("no Landlock on this kernel")
    subs = tmp_path / "subs"
    subs.mkdir()
    files = {
        "trace_jump": _with_answer("q3", _TRACE_JUMP),
        "copied_marker": _with_answer("q3", _COPIED_MARKER),
        "memfd_fill": _with_answer("q4", _q4_after(_MEMFD_FILL)),
        "deleted_files_fill": _with_answer("q4", _q4_after(_DELETED_FILES_FILL)),
        "honest": _solution(),
    }
    for sid, nb in files.items():
        (subs / f"{sid}.ipynb").write_text(json.dumps(nb))
    options = GradeOptions(jobs=2, timeout=20, memory_mb=512, progress=False, namespaces=namespaces)
    summary = grade(SOLUTION_DIR, subs, tmp_path / "out", options)
    rows = {r.student: r.to_json() for r in summary.rows}
    expected = {
        "honest": {},
        "trace_jump": {"q3": "forbidden"},
        "copied_marker": {"q3": "forbidden"},
        "memfd_fill": {"q4": "memory"},
        "deleted_files_fill": {"q4": "memory"},
    }
    failed = []  # every attack checked, so that a failure names each one that got through
    for sid, zero in expected.items():
        try:
            _expect(rows[sid], zero)
        except AssertionError as exc:
            failed.append(f"{sid}: {exc}")
    assert not failed, "\n".join(failed)
    for sid in ("trace_jump", "copied_marker"):
        assert "course.lsq.fit" in rows[sid]["questions"]["q3"]["message"], rows[sid]
