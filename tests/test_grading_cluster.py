"""`course grade --cluster`: the same submissions graded on a real Dask distributed cluster (a
LocalCluster with two worker processes, each with its own warm sandbox) give the same outputs
as a local run, row for row, with a class key that never leaves the driver; the workers delete
every file they were given; a remote scheduler is reached over TLS only (plain tcp:// beyond
this machine is refused); and a worker's event loop never runs the grader's build."""

from __future__ import annotations

import asyncio
import base64
import copy
import json
import os
import secrets
import shutil
import subprocess
import sys
import threading
from pathlib import Path

import dask
import pytest

from course.grading.authoring.secret import Secret
from course.grading.batch import session as session_module
from course.grading.batch.cluster import ClusterError, ConnectionFiles, cluster_target
from course.grading.batch.driver import grade
from course.grading.batch.options import GradeOptions
from course.grading.codec import encode
from course.grading.sandbox.isolation import detect

distributed = pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[1]
NAME = "01_least_squares"
SOLUTION_DIR = ROOT / "solutions" / NAME
#: What the workers are given and must delete: the assignment's authoring files.
GIVEN = {"checks.py", "data.py", f"{NAME}.ipynb"}


def _rows(out: Path) -> dict:
    rows = {}
    for line in (out / "results.jsonl").read_text().splitlines():
        row = json.loads(line)
        assert row.pop("wall_seconds") >= 0  # the one field that differs between runs
        rows[row["student"]] = row
    return rows


def _submissions(folder: Path, students=("alice", "bob", "carol", "dave", "eve")) -> Path:
    solution = json.loads((SOLUTION_DIR / f"{NAME}.ipynb").read_text())
    release = json.loads((ROOT / "exercises" / NAME / f"{NAME}.ipynb").read_text())
    wrong = copy.deepcopy(solution)
    for cell in wrong["cells"]:
        if cell.get("id") == "q1-answer":
            cell["source"] = "def line_estimate(t, y): return np.zeros(2)"
    folder.mkdir()
    notebooks = {"alice": solution, "bob": wrong, "carol": release, "dave": solution}
    for sid in students:
        if sid in notebooks:
            (folder / f"{sid}.ipynb").write_text(json.dumps(notebooks[sid]))
        else:
            (folder / f"{sid}.ipynb").write_text("{ not json")
    return folder


def _given_files(folder: Path) -> list[str]:
    """The assignment's files (or a worker's folder of them) still under ``folder``."""
    return sorted(
        str(p)
        for p in folder.rglob("*")
        if p.name in GIVEN or p.name.startswith("course-grade-assignment-")
    )


@pytest.fixture(scope="module")
def class_run(tmp_path_factory):
    """One class graded locally and on a two-process LocalCluster with the same key, with
    every message the driver and the scheduler send recorded as it goes on the wire, and the
    workers' temporary folder listed at the end of the run and after the cluster's shutdown."""
    tmp = tmp_path_factory.mktemp("cluster")
    subs = _submissions(tmp / "subs")
    secret = Secret(secrets.token_bytes(32), "test")
    options = dict(jobs=2, timeout=5.0, progress=False, secret=secret)
    grade(SOLUTION_DIR, subs, tmp / "local", GradeOptions(**options))

    wire: list[bytes] = []
    original = distributed.protocol.dumps

    def recording_dumps(*args, **kwargs):
        frames = original(*args, **kwargs)
        wire.append(b"".join(bytes(f) for f in frames))
        return frames

    workers_tmp = tmp / "workers-tmp"
    workers_tmp.mkdir()
    announced: list[str] = []
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(distributed.protocol, "dumps", recording_dumps)  # every comm's to_frames
        mp.setenv("TMPDIR", str(workers_tmp))  # the worker processes' tempfile folder
        with (
            dask.config.set({"distributed.comm.compression": None}),
            distributed.LocalCluster(
                n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
            ) as cluster,
        ):
            summary = grade(
                SOLUTION_DIR,
                subs,
                tmp / "cluster",
                GradeOptions(**options, cluster=cluster, announce=announced.append),
            )
            after_run = _given_files(workers_tmp)
    return {
        "tmp": tmp,
        "secret": secret,
        "summary": summary,
        "announced": announced,
        "wire": b"".join(wire),
        "after_run": after_run,
        "after_shutdown": _given_files(workers_tmp),
    }


@pytest.mark.slow  # a whole grading run, twice
def test_cluster_grades_like_a_local_run(class_run):
    tmp = class_run["tmp"]
    assert class_run["summary"].graded == 5
    announced = class_run["announced"]
    assert any("worker(s) at" in line and "Sandbox: " in line for line in announced), announced
    local, remote = _rows(tmp / "local"), _rows(tmp / "cluster")
    assert remote == local
    assert local["alice"]["data_key"] == class_run["secret"].key_id
    full = local["alice"]["max"]  # the assignment's total, from checks.py
    # full marks with personal data: the workers' seeds draw the data the key draws
    assert local["alice"]["total"] == full and 0 < local["bob"]["total"] < full
    for name in ("grades.csv",):
        assert (tmp / "cluster" / name).read_text() == (tmp / "local" / name).read_text()
    for fb in sorted((tmp / "local" / "feedback").iterdir()):
        assert (tmp / "cluster" / "feedback" / fb.name).read_text() == fb.read_text()


@pytest.mark.slow
def test_the_class_key_never_travels_to_the_workers(class_run):
    wire = class_run["wire"]
    # the recording sees what the workers are given: the checks and a submission
    assert (SOLUTION_DIR / "checks.py").read_bytes()[:2000] in wire
    assert b"def line_estimate(t, y): return np.zeros(2)" in wire
    key = class_run["secret"].key
    for form in (
        key,
        key.hex().encode(),
        key.hex().upper().encode(),
        base64.b64encode(key),
        base64.urlsafe_b64encode(key),
    ):
        assert form not in wire, "the class key was sent to the cluster"


@pytest.mark.slow
def test_workers_delete_the_files_they_were_given(class_run):
    assert class_run["after_run"] == [], "left on the workers at the end of the run"
    assert class_run["after_shutdown"] == [], "left on the workers after their shutdown"


@pytest.mark.slow  # a cluster and a grading run
def test_a_failed_cleanup_is_reported(tmp_path, monkeypatch):
    from course.grading.batch import clusterworker

    kept: list[Path] = []
    real_delete = clusterworker._delete

    def failing_delete(folder: Path) -> None:
        kept.append(folder)
        real_delete(folder / NAME / "checks.py")  # not a folder: shutil leaves it all

    monkeypatch.setattr(clusterworker, "_delete", failing_delete)
    subs = _submissions(tmp_path / "subs", students=("eve",))
    announced: list[str] = []
    try:
        with distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cluster:
            summary = grade(
                SOLUTION_DIR,
                subs,
                tmp_path / "out",
                GradeOptions(jobs=1, progress=False, cluster=cluster, announce=announced.append),
            )
    finally:
        for path in kept:
            shutil.rmtree(path, ignore_errors=True)
    assert summary.graded == 1 and len(kept) == 1
    assert any(
        "could not delete the assignment's files" in line and str(kept[0]) in line
        for line in announced
    ), announced


def test_the_driver_holds_a_bounded_window_of_notebooks(tmp_path, monkeypatch):
    """Each submission sent to the cluster holds its bytes (up to 50 MB) in the driver until
    its task is done: the driver reads them as the window moves (two per worker thread), not
    the whole class before the first result (issue 25 item 2: the parent's memory must not
    grow with the class)."""
    from course.grading.batch import cluster as cluster_module
    from course.grading.batch import driver

    reads: list[str] = []
    real_read = cluster_module.read_notebook_bytes

    def counting_read(path):
        reads.append(Path(path).name)
        return real_read(path)

    read_at_each_result: list[int] = []
    real_grade_on_cluster = cluster_module.grade_on_cluster

    def watched(*args, **kwargs):
        for row in real_grade_on_cluster(*args, **kwargs):
            read_at_each_result.append(len(reads))
            yield row

    monkeypatch.setattr(cluster_module, "read_notebook_bytes", counting_read)
    monkeypatch.setattr(driver, "grade_on_cluster", watched)
    subs = _submissions(tmp_path / "subs")  # five students
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        summary = grade(
            SOLUTION_DIR,
            subs,
            tmp_path / "out",
            GradeOptions(jobs=1, progress=False, cluster=cluster),
        )
    assert summary.graded == 5 and len(reads) == 5
    # one thread: two notebooks in flight, one more read after each result
    assert read_at_each_result == [2, 3, 4, 5, 5], read_at_each_result


# -- the transport ------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "address",
    ["tcp://10.1.2.3:8786", "scheduler.example.org:8786", "tcp://[2001:db8::1]:8786"],
)
def test_plain_tcp_beyond_this_machine_is_refused(address):
    with pytest.raises(ClusterError, match=r"unencrypted.*--insecure-cluster"):
        cluster_target(address)
    target, security = cluster_target(address, insecure=True)
    assert target.startswith("tcp://") and security is None


@pytest.mark.parametrize(
    "address", ["tcp://127.0.0.1:8786", "tcp://localhost:8786", "tcp://[::1]:8786", "127.0.0.2:1"]
)
def test_plain_tcp_on_this_machine_is_accepted(address):
    target, security = cluster_target(address)
    assert target.startswith("tcp://") and security is None


def test_tls_needs_its_files(tmp_path):
    with pytest.raises(ClusterError, match="--tls-ca-file and --tls-cert"):
        cluster_target("tls://scheduler.example.org:8786")
    with pytest.raises(ClusterError, match="no such file"):
        cluster_target("tls://h:1", ConnectionFiles(tmp_path / "ca.pem", tmp_path / "me.pem", None))
    cert = tmp_path / "me.pem"
    cert.write_text("x")
    with pytest.raises(ClusterError, match=r"not encrypted; use tls://h:1"):
        cluster_target("tcp://h:1", ConnectionFiles(cert, cert, None))
    target, security = cluster_target("h:1", ConnectionFiles(cert, cert, None))
    assert target == "tls://h:1" and security.require_encryption


def test_the_command_refuses_plain_tcp_before_grading(tmp_path, capsys):
    from course.cli import main

    subs = _submissions(tmp_path / "subs", students=("alice",))
    out = tmp_path / "out"
    args = ["grade", NAME, str(subs), "--out", str(out), "--course-dir", str(ROOT)]
    assert main([*args, "--no-secret", "--cluster", "tcp://192.0.2.7:8786"]) == 2
    err = capsys.readouterr().err
    assert "refusing to send" in err and "--insecure-cluster" in err
    assert not out.exists()  # refused before anything was written (or connected)
    tls = ["--cluster", "tls://127.0.0.1:1", "--tls-ca-file", str(tmp_path / "ca.pem")]
    assert main([*args, "--no-secret", *tls, "--tls-cert", str(subs / "alice.ipynb")]) == 2
    assert f"--tls-ca-file {tmp_path / 'ca.pem'}: no such file" in capsys.readouterr().err
    assert not out.exists()


def _certificates(folder: Path) -> tuple[Path, Path, Path]:
    """A throw-away CA and one certificate (with its key) it signed for 127.0.0.1."""
    openssl = shutil.which("openssl")
    if openssl is None:
        pytest.skip("the openssl command makes the test's certificates")
    ec = ["-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes"]

    def run(*args):
        subprocess.run([openssl, *args], cwd=folder, check=True, capture_output=True)

    run("req", "-x509", *ec, "-keyout", "ca.key", "-out", "ca.pem", "-days", "2", "-subj", "/CN=ca")
    run("req", *ec, "-keyout", "node.key", "-out", "node.csr", "-subj", "/CN=localhost")
    (folder / "san.ext").write_text("subjectAltName=DNS:localhost,IP:127.0.0.1\n")
    run(
        "x509", "-req", "-in", "node.csr", "-CA", "ca.pem", "-CAkey", "ca.key",
        "-CAcreateserial", "-out", "node.pem", "-days", "2", "-extfile", "san.ext",
    )  # fmt: skip
    return folder / "ca.pem", folder / "node.pem", folder / "node.key"


@pytest.mark.slow  # a cluster and a grading run
def test_grading_over_tls(tmp_path):
    from distributed.security import Security

    ca, cert, key = _certificates(tmp_path)
    nodes = {
        f"tls_{role}_{part}": str(path)
        for role in ("scheduler", "worker", "client")
        for part, path in (("cert", cert), ("key", key))
    }
    security = Security(tls_ca_file=str(ca), require_encryption=True, **nodes)
    subs = _submissions(tmp_path / "subs", students=("alice", "eve"))
    with distributed.LocalCluster(
        n_workers=1,
        threads_per_worker=1,
        processes=False,
        protocol="tls://",
        security=security,
        dashboard_address=None,
    ) as cluster:
        address = cluster.scheduler_address
        assert address.startswith("tls://127.0.0.1:")
        summary = grade(
            SOLUTION_DIR,
            subs,
            tmp_path / "out",
            GradeOptions(
                jobs=1,
                timeout=5.0,
                progress=False,
                cluster=address,
                cluster_files=ConnectionFiles(ca, cert, key),
            ),
        )
    rows = _rows(tmp_path / "out")
    assert summary.graded == 2
    assert rows["alice"]["total"] == rows["alice"]["max"] > 0
    assert rows["eve"]["status"] == "invalid notebook"


# -- the worker's event loop ----------------------------------------------------------------------
@pytest.mark.slow  # a cluster and a grading run
def test_the_grader_is_not_built_on_a_workers_event_loop(tmp_path, monkeypatch):
    """Every grader a worker builds is built off its event loop, and the loop runs a callback
    while a build is under way (it would wait forever if the build held the loop)."""
    detect()  # this machine can grade at all
    builds: list[dict] = []
    original = session_module.AssignmentGrader.__init__
    driver = threading.get_ident()
    loops: list = []  # the worker's event loop, once the cluster runs

    def watched_init(self, *args, **kwargs):
        if threading.get_ident() != driver:  # a worker's grader
            try:
                asyncio.get_running_loop()
                on_loop = True
            except RuntimeError:
                on_loop = False
            loop_ran = threading.Event()
            loops[0].add_callback(loop_ran.set)
            # a generous bound that only stops a deadlock: the loop runs the callback at once
            # unless this very build is holding it
            builds.append({"on_loop": on_loop, "loop_ran": loop_ran.wait(30)})
        original(self, *args, **kwargs)

    monkeypatch.setattr(session_module.AssignmentGrader, "__init__", watched_init)
    subs = _submissions(tmp_path / "subs", students=("eve",))
    announced: list[str] = []
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        (worker,) = cluster.workers.values()
        loops.append(worker.loop)
        grade(
            SOLUTION_DIR,
            subs,
            tmp_path / "out",
            GradeOptions(jobs=1, progress=False, cluster=cluster, announce=announced.append),
        )
    assert builds, "the worker built no grader"
    assert builds == [{"on_loop": False, "loop_ran": True}] * len(builds)


async def _watch_the_loop(dask_worker, tick: float = 0.02) -> None:
    """Runs on a worker's event loop (``Client.run``): records the loop's largest stall, the
    time a ``tick`` sleep overran by, in ``dask_worker.loop_stall``."""
    import time

    stall = dask_worker.loop_stall = {"largest": 0.0, "modules": sorted(sys.modules)}

    async def watch():
        last = time.monotonic()
        while True:
            await asyncio.sleep(tick)
            now = time.monotonic()
            stall["largest"] = max(stall["largest"], now - last - tick)
            last = now

    dask_worker.loop_watch = asyncio.ensure_future(watch())


@pytest.mark.slow  # a cluster of one fresh worker process and a grading run
def test_a_workers_event_loop_is_never_blocked_for_a_second(tmp_path):
    """Issue 34 item 6: a worker's event loop, which answers the scheduler's heartbeats, runs
    within a second all through a run, the grader's build included. The worker is a fresh
    process that has not imported the course (as a ``dask worker`` started by hand): it
    unpickles the assignment's plugin on its loop, and importing the grader's modules there
    (nbformat's schema validator compiles grammars) held it for seconds."""
    import cloudpickle

    subs = _submissions(tmp_path / "subs", students=("alice", "eve"))
    module = sys.modules[__name__]
    cloudpickle.register_pickle_by_value(module)  # the watcher travels as code, not by name
    try:
        with (
            distributed.LocalCluster(
                n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None
            ) as cluster,
            distributed.Client(cluster) as client,
        ):
            client.run(_watch_the_loop)
            summary = grade(
                SOLUTION_DIR,
                subs,
                tmp_path / "out",
                GradeOptions(jobs=1, progress=False, cluster=cluster),
            )
            (stall,) = client.run(lambda dask_worker: dask_worker.loop_stall).values()
    finally:
        cloudpickle.unregister_pickle_by_value(module)
    assert summary.graded == 2
    assert not [m for m in stall["modules"] if m.split(".")[0] == "course"], "not a fresh worker"
    # a property, not a speed: the stall is the longest the loop waited, under this machine's
    # load (named in the message if it fails)
    assert stall["largest"] < 1.0, (
        f"the worker's event loop was blocked {stall['largest']:.2f} s "
        f"(load average {os.getloadavg()})"
    )


@pytest.mark.slow  # a cluster
def test_a_worker_without_walls_refuses_before_any_student(tmp_path, monkeypatch):
    from course.grading.sandbox.isolation import IsolationError

    driver, real = threading.get_ident(), GradeOptions.isolation

    def isolation(self):
        if threading.get_ident() != driver:
            raise IsolationError("no Landlock and no user namespaces on this worker")
        return real(self)

    submitted: list[str] = []
    real_submit = distributed.Client.submit

    def submit(self, *args, **kwargs):
        submitted.append(str(kwargs.get("key")))
        return real_submit(self, *args, **kwargs)

    monkeypatch.setattr(GradeOptions, "isolation", isolation)
    monkeypatch.setattr(distributed.Client, "submit", submit)
    subs = _submissions(tmp_path / "subs", students=("alice",))
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cluster,
        pytest.raises(IsolationError, match="on this worker"),
    ):
        grade(SOLUTION_DIR, subs, tmp_path / "out", GradeOptions(progress=False, cluster=cluster))
    assert submitted and not [key for key in submitted if key.startswith("grade-")]
    assert not (tmp_path / "out" / "results.jsonl").exists()  # nobody was graded


# -- what the driver sends ------------------------------------------------------------------------
def test_a_key_file_in_the_assignment_folder_is_not_sent(tmp_path):
    from course.grading.batch.cluster import _bundle

    folder = tmp_path / NAME
    shutil.copytree(SOLUTION_DIR, folder)
    assert set(_bundle(folder)) >= GIVEN
    secret = Secret(secrets.token_bytes(32), "test")
    (folder / "notes.txt").write_text(f"key for the term: {secret.key.hex()}\n")
    with pytest.raises(ClusterError, match=r"notes.txt holds a class key"):
        _bundle(folder, secret)
    (folder / "notes.txt").write_text("# a key file\ncourse-secret-v1:" + "ab" * 32 + "\n")
    with pytest.raises(ClusterError, match="keep key files outside"):
        _bundle(folder)


def test_a_grader_without_the_key_needs_each_students_seeds():
    secret = Secret(secrets.token_bytes(32), "test")
    keyed = session_module.AssignmentGrader(SOLUTION_DIR, GradeOptions(secret=secret))
    seeds = keyed.student_seeds("alice")
    assert seeds == {key: secret.seed(NAME, key, "alice") for key in keyed.checks.data_keys()}
    worker = session_module.AssignmentGrader(SOLUTION_DIR, GradeOptions(), data_key=secret.key_id)
    assert worker.data_key == keyed.data_key and worker.secret is None
    with pytest.raises(ValueError, match="holds no key"):
        worker.student_seeds("alice")  # never public data in place of the class's
    for key, seed in seeds.items():
        drawn = worker.checks.data_from_seed(key, seed)
        assert json.dumps(encode(drawn)) == json.dumps(
            encode(keyed.checks.data_for(key, "alice", secret))
        )
    with pytest.raises(ValueError, match="not the key id"):
        session_module.AssignmentGrader(
            SOLUTION_DIR, GradeOptions(secret=secret), data_key="0123456789ab"
        )
