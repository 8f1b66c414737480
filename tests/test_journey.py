"""The student's journey, on the artifacts students receive: the test of record for "students
can use this".

An instructor exports a graded class's edition (``course export`` with a secret and a roster);
a student installs the wheel, alone, into a fresh virtual environment (pip takes its
dependencies from the package index, as on a student's machine), gets the working folder that
``course open`` makes, and runs every teaching notebook and every assignment top to bottom in
that environment's own Jupyter kernel. The assignments carry the solution's answers pasted
into the student's copy, with a registered ``STUDENT_ID``, and end, as released, with
``check.submit()`` (which runs ``check.all()``). Asserted: no error, no warning, no failed
self-check, full public marks, the submission written. The developers' environment (``.[all]``)
never enters: what a shipped notebook imports and the student wheel does not declare fails
here.

One edition and one environment per test run (module fixtures); the notebooks run two at a
time. Cost: 6 to 7 minutes measured on 2 cores shared with other work (see ``executed``).

Below them, the smaller things met on the same walk, each with the test that failed before.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import nbformat
import numpy as np
import pytest

from course.cli import main as course_main
from course.grading.authoring.checks import load_checks
from course.grading.authoring.personal import PersonalData, build_personal_data
from course.grading.authoring.release import find_solutions
from course.grading.authoring.secret import Secret

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: pytest's own TOML reader
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
SOLUTIONS = ROOT / "solutions"
ASSIGNMENTS = find_solutions(SOLUTIONS)
TEACHING = sorted(p.name for p in (ROOT / "notebooks").glob("*.ipynb"))
ROSTER_IDS = ["s001", "s002", "98765"]
STUDENT = "s001"

#: Executes one notebook in the student's environment (nbclient comes with its JupyterLab).
RUNNER = """
import sys
from pathlib import Path

import nbformat
from nbclient import NotebookClient

source, target = Path(sys.argv[1]), Path(sys.argv[2])
nb = nbformat.read(source, as_version=4)
client = NotebookClient(
    nb, timeout=600, kernel_name="python3", allow_errors=True,
    resources={"metadata": {"path": str(source.parent)}},
)
client.execute()
nbformat.write(nb, target)
"""


# ---------------------------------------------------------------------------------------
# the edition, the environment, the working folder
# ---------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def journey(tmp_path_factory):
    """The class's edition exported through the command line (into a path written with
    ``..``), installed alone into a fresh venv, and the working folder ``course open`` makes."""
    tmp = tmp_path_factory.mktemp("journey")
    key = tmp / "class.key"
    roster = tmp / "roster.csv"
    roster.write_text(
        "id,name,email\n"
        + "".join(f"{sid},Student {sid},{sid}@example.org\n" for sid in ROSTER_IDS)
    )
    (tmp / "elsewhere").mkdir()
    with contextlib.redirect_stdout(io.StringIO()):
        assert course_main(["secret", "new", str(key)]) == 0
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = course_main(
            ["export", f"{tmp}/elsewhere/../handout", "--secret", str(key), "--roster", str(roster)]
        )
    assert code == 0, printed.getvalue()
    handout = tmp / "handout"
    wheel = next(handout.glob("*.whl"))
    venv = tmp / "student-env"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    pip = [sys.executable, "-m", "pip", "--python", str(python), "install", "--quiet"]
    # without PYTHONPATH: pip must not see a source tree's course (or its egg-info) as
    # "already installed"
    outer = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    subprocess.run([*pip, "--disable-pip-version-check", str(wheel)], check=True, env=outer)
    home = tmp / "home"
    home.mkdir()
    env = {
        "HOME": str(home),
        "PATH": f"{venv / 'bin'}:/usr/bin:/bin",
        "LANG": "C.UTF-8",
        "OPENBLAS_NUM_THREADS": "1",
        "OMP_NUM_THREADS": "1",
    }
    work = home / "my-course"
    copied = subprocess.run(
        [
            str(python),
            "-c",
            "import sys; from course import workspace; "
            "assert 'site-packages' in workspace.__file__; "
            "workspace.prepare_workdir(sys.argv[1], workspace.packaged_materials())",
            str(work),
        ],
        cwd=home,  # not the repository, whose course/ would shadow the installed one
        env=env,
        capture_output=True,
        text=True,
    )
    assert copied.returncode == 0, copied.stderr
    return {
        "printed": printed.getvalue(),
        "handout": handout,
        "venv": venv,
        "env": env,
        "work": work,
    }


def _answers(name: str) -> dict[str, str]:
    """The solution's answer to each question, as a student would type it (markers removed)."""
    nb = nbformat.read(SOLUTIONS / name / f"{name}.ipynb", as_version=4)
    answers = {}
    for cell in nb.cells:
        meta = cell.get("metadata", {}).get("course", {})
        if meta.get("role") == "answer" and meta.get("question"):
            lines = cell.source.splitlines()
            kept = [line for line in lines if not line.strip().startswith(MARKERS)]
            answers[meta["question"]] = "\n".join(kept)
    return answers


#: The authoring markers (course.grading.notebook): the solution's region and its stub lines.
MARKERS = ("### BEGIN SOLUTION", "### END SOLUTION", "### STUB")


def _student_copy(path: Path, name: str) -> None:
    """Fill in the student's copy in place: STUDENT_ID and every answer, then save."""
    nb = nbformat.read(path, as_version=4)
    answers = _answers(name)
    filled = set()
    for cell in nb.cells:
        meta = cell.get("metadata", {}).get("course", {})
        if meta.get("role") == "setup":
            cell.source, n = re.subn(
                r'^STUDENT_ID = "[^"]*"', f'STUDENT_ID = "{STUDENT}"', cell.source, flags=re.M
            )
            assert n == 1, cell.source
        elif meta.get("role") == "answer" and meta.get("question") in answers:
            cell.source = answers[meta["question"]]
            filled.add(meta["question"])
    assert filled == set(answers), f"{name}: no answer cell for {set(answers) - filled}"
    nbformat.write(nb, path)


@pytest.fixture(scope="module")
def executed(journey):
    """Every teaching and assignment notebook of the working folder, executed in the student's
    environment: ``{notebook name: (executed notebook, seconds)}``.

    Measured on 2 cores shared with other jobs: 6 to 7 min for the whole file, of which the
    export and the environment (pip, its cache warm from installing ``.[all]``) take 2 to 3
    min and the 14 notebooks, two at a time, 3 to 4 min.
    """
    work, python = journey["work"], journey["venv"] / "bin" / "python"
    runner = work.parent / "run_notebook.py"
    runner.write_text(RUNNER)
    jobs = [work / "notebooks" / name for name in TEACHING]
    for name in ASSIGNMENTS:
        path = work / "exercises" / name / f"{name}.ipynb"
        _student_copy(path, name)
        jobs.append(path)

    def run(path: Path):
        out = path.with_name(f"{path.stem}.executed.ipynb")
        start = time.perf_counter()
        done = subprocess.run(
            [str(python), str(runner), str(path), str(out)],
            cwd=path.parent,
            env=journey["env"],
            capture_output=True,
            text=True,
            timeout=900,
        )
        seconds = time.perf_counter() - start
        assert done.returncode == 0, f"{path.name} did not run:\n{done.stderr[-3000:]}"
        return path.name, (nbformat.read(out, as_version=4), seconds)

    with ThreadPoolExecutor(max_workers=2) as pool:  # CI has two cores
        return dict(pool.map(run, jobs))


def _outputs(nb) -> list[tuple[int, dict]]:
    return [(i, out) for i, cell in enumerate(nb.cells) for out in cell.get("outputs", [])]


def _text(out: dict) -> str:
    if out.get("output_type") == "stream":
        return out.get("text", "")
    if out.get("output_type") == "error":
        return "\n".join(out.get("traceback", []))
    return str(out.get("data", {}).get("text/plain", ""))


def _problems(nb) -> list[str]:
    """Errors, anything written to stderr (warnings included) and failed self-checks."""
    found = []
    for i, out in _outputs(nb):
        text = _text(out)
        if out.get("output_type") == "error":
            found.append(f"cell {i}: {out.get('ename')}: {out.get('evalue')}")
        elif out.get("output_type") == "stream" and out.get("name") == "stderr":
            found.append(f"cell {i} wrote to stderr: {text[:500]}")
        elif re.search(r"\bFAIL\b|Warning|Traceback", text):
            found.append(f"cell {i}: {text[:800]}")
    return found


# ---------------------------------------------------------------------------------------
# the journey
# ---------------------------------------------------------------------------------------
def test_the_export_prints_a_normalised_path(journey):
    assert "/../" not in journey["printed"] and "/elsewhere/" not in journey["printed"]
    assert str(journey["handout"]) in journey["printed"]


@pytest.mark.parametrize("name", TEACHING)
def test_every_teaching_notebook_runs_in_the_student_edition(executed, name):
    nb, _ = executed[name]
    assert _problems(nb) == []
    assert all(
        c.get("execution_count") for c in nb.cells if c.cell_type == "code" and c.source.strip()
    ), f"{name} stopped early"


@pytest.mark.parametrize("name", ASSIGNMENTS)
def test_every_assignment_earns_full_public_marks_and_is_submitted(executed, journey, name):
    nb, _ = executed[f"{name}.ipynb"]
    assert _problems(nb) == []
    submit = next(c for c in nb.cells if c.cell_type == "code" and "check.submit(" in c.source)
    printed = "".join(_text(out) for out in submit.outputs)
    marks = re.search(r"([\d.]+) of ([\d.]+) points from public checks", printed)
    assert marks and float(marks[1]) == float(marks[2]) > 0, printed
    assert "not answered" not in printed and "sha256" in printed, printed
    # the receipt is the last thing shown: no stray PosixPath('...') of the returned path
    assert submit.outputs[-1]["output_type"] == "stream", submit.outputs[-1]
    assert "PosixPath" not in printed
    written = journey["work"] / "exercises" / name / f"{STUDENT}_{name}.ipynb"
    meta = json.loads(written.read_text())["metadata"]["course"]["submission"]
    assert meta["student_id"] == STUDENT and meta["data_key"] != "public"


def test_short_answers_are_submitted_without_a_false_warning(executed):
    """03 q3b, 05 q6_why and 06 q6_why are markdown: the kernel never ran them."""
    short = [
        name
        for name in ASSIGNMENTS
        if any(q.kind == "short_answer" for q in load_checks(SOLUTIONS / name).questions.values())
    ]
    assert len(short) >= 3, short
    for name in short:
        nb, _ = executed[f"{name}.ipynb"]
        assert "are not what this kernel ran" not in "".join(_text(o) for _, o in _outputs(nb))


def test_the_students_jupyter_has_no_grading_tool(journey):
    """`course open` starts the JupyterLab of the student's environment: only the course's
    extensions, never nbgrader's Formgrader or Assignment List."""
    bin_dir = journey["venv"] / "bin"
    for what in (["labextension", "list"], ["server", "extension", "list"]):
        listed = subprocess.run(
            [str(bin_dir / "jupyter"), *what],
            env=journey["env"],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert listed.returncode == 0, listed.stderr
        assert "nbgrader" not in (listed.stdout + listed.stderr).lower()


def test_the_edition_ships_no_grader_and_says_so(journey):
    """Students run the self-check and submit; the batch grader and its sandbox stay with the
    instructor, and `course grade` in the student edition says whose tool it is."""
    import zipfile

    wheel = next(journey["handout"].glob("*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    assert "course/grading/student/selfcheck.py" in names
    assert "course/grading/authoring/seal.py" in names
    shipped = [
        n for n in names if n.startswith(("course/grading/batch/", "course/grading/sandbox/"))
    ]
    assert not shipped, shipped
    course_cli = journey["venv"] / "bin" / "course"
    for command in (["grade", "01_least_squares", "subs", "--out", "graded"], ["export", "out"]):
        done = subprocess.run(
            [str(course_cli), *command],
            env=journey["env"],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert done.returncode == 2, done.stderr
        assert "student edition" in done.stderr and "Traceback" not in done.stderr


def test_course_open_in_this_environment_shows_no_grading_tool():
    """The developers' `course open` (this interpreter's JupyterLab, `.[all]` installed) lists
    no nbgrader extension either; an environment installed from an older `.[all]`, or with
    `.[bench]`, fails here until `python -m pip uninstall nbgrader`."""
    for what in (["labextension", "list"], ["server", "extension", "list"]):
        listed = subprocess.run(
            [sys.executable, "-m", "jupyter", *what], capture_output=True, text=True, timeout=120
        )
        assert listed.returncode == 0, listed.stderr
        assert "nbgrader" not in (listed.stdout + listed.stderr).lower(), what


def test_journey_cost(executed):
    """Not a speed target: a notebook that hangs stops the journey here, with the times."""
    times = {name: seconds for name, (_, seconds) in executed.items()}
    assert max(times.values()) < 600, times


# ---------------------------------------------------------------------------------------
# what the course declares
# ---------------------------------------------------------------------------------------
def _extras(name: str, project: dict) -> set[str]:
    """The requirement names an extra brings in, its own extras expanded."""
    names = set()
    for requirement in project["optional-dependencies"][name]:
        base = re.match(r"[A-Za-z0-9_.\-]+", requirement)[0]
        if base == project["name"]:
            inner = re.search(r"\[(.*)\]", requirement)[1]
            for extra in inner.split(","):
                names |= _extras(extra.strip(), project)
        else:
            names.add(base.lower())
    return names


def test_all_holds_no_nbgrader():
    """`.[all]`, the README's install, is the course, its tests, docs and lint: the grading
    benchmark's peers (nbgrader) stay in the `bench` extra."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert "nbgrader" in _extras("bench", project)
    assert "nbgrader" not in _extras("all", project)


def test_the_jupyterlite_app_leaves_grading_tools_out(tmp_path):
    from course.docsite import lite_extensions

    labextensions = tmp_path / "share" / "jupyter" / "labextensions"
    for name in ("@jupyter/nbgrader", "@jupyter-widgets/jupyterlab-manager", "plain_ext"):
        (labextensions / name).mkdir(parents=True)
        (labextensions / name / "package.json").write_text("{}")
    kept = [p.relative_to(labextensions).as_posix() for p in lite_extensions(tmp_path)]
    assert kept == ["@jupyter-widgets/jupyterlab-manager", "plain_ext"]
    assert not any("nbgrader" in p.as_posix() for p in lite_extensions())


def test_the_student_wheel_declares_what_the_notebooks_import(journey):
    """Every module a shipped notebook imports is the library, the standard library or a
    dependency of the wheel (checked statically too, so the failure names the module)."""
    import zipfile

    wheel = zipfile.ZipFile(next(journey["handout"].glob("*.whl")))
    metadata = wheel.read(next(n for n in wheel.namelist() if n.endswith("METADATA"))).decode()
    declared = {
        re.match(r"[A-Za-z0-9_.\-]+", d)[0].lower().replace("-", "_")
        for d in re.findall(r"^Requires-Dist: (.+)$", metadata, re.MULTILINE)
    }
    imported = set()
    for name in wheel.namelist():
        if name.startswith("course/materials/") and name.endswith(".ipynb"):
            nb = json.loads(wheel.read(name))
            for cell in nb["cells"]:
                if cell["cell_type"] == "code":
                    source = "".join(cell["source"])
                    imported |= set(re.findall(r"^\s*(?:from|import)\s+(\w+)", source, re.M))
    third_party = imported - set(sys.stdlib_module_names) - {"course"}
    assert third_party <= declared, third_party - declared


# ---------------------------------------------------------------------------------------
# the smaller things met on the same walk
# ---------------------------------------------------------------------------------------
def test_markdown_answers_are_not_compared_with_the_kernels_history():
    from course.grading.student.submit import _stale_answers

    answer = {"role": "answer", "question": "q6_why"}
    nb = {
        "cells": [
            {"cell_type": "code", "metadata": {"course": {"role": "answer", "question": "q1"}},
             "source": "x = 1"},
            {"cell_type": "markdown", "metadata": {"course": answer},
             "source": "Because the law is exact."},
        ]
    }  # fmt: skip
    assert _stale_answers(nb, {"In": ["", "x = 1"]}) == []
    assert _stale_answers(nb, {"In": ["", "x = 2"]}) == ["q1"]  # a code answer still is


def test_the_submit_cell_does_not_show_the_returned_path():
    from IPython.core.interactiveshell import InteractiveShell

    from course.grading.student.submit import WrittenPath

    written = WrittenPath("/tmp/s001_01_least_squares.ipynb")
    assert written == Path("/tmp/s001_01_least_squares.ipynb")
    assert InteractiveShell.instance().display_formatter.format(written) == ({}, {})


def test_open_names_the_missing_front_end(tmp_path, monkeypatch, capsys):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "notebook" else real(name, *a)
    )
    assert course_main(["open", str(tmp_path), "--app", "notebook", "--no-browser"]) == 2
    err = capsys.readouterr().err
    assert "Jupyter Notebook is not installed" in err and "pip install notebook`" in err


def test_the_sliders_advice_works_in_the_student_edition(monkeypatch):
    from course import interactive

    monkeypatch.setitem(sys.modules, "ipywidgets", None)
    with pytest.raises(ImportError, match=r"pip install ipywidgets") as error:
        interactive._ipywidgets()
    assert "[notebooks]" not in str(error.value)


def test_the_student_guide_says_the_expected_values_are_sealed():
    guide = (ROOT / "docs" / "students" / "install-and-submit.md").read_text()
    assert "with their expected values" not in guide and "sealed" in guide


def test_an_id_that_differs_only_in_case_is_told_so(tmp_path):
    from course.grading.student.submit import _unknown_id

    name = "01_least_squares"
    secret = Secret(bytes(range(32)), "test key")
    (tmp_path / "personal_data.json").write_text(
        build_personal_data(load_checks(SOLUTIONS / name), ["s001", "AB12"], secret)
    )
    issued = PersonalData.read(tmp_path)
    for typed, registered in (("S001", "s001"), ("ab12", "AB12")):
        assert registered in _unknown_id(typed, issued) and "case" in _unknown_id(typed, issued)
        with pytest.raises(KeyError, match=f"'{registered}' is: IDs are case-sensitive"):
            issued.data(typed, "survey")
    assert "the same upper and lower case" in _unknown_id("zz9", issued)


# ---------------------------------------------------------------------------------------
# the declared floors
# ---------------------------------------------------------------------------------------
def test_lsq_fit_works_where_scipy_has_no_dtrcon(monkeypatch):
    """scipy < 1.15 (and Pyodide's 1.14) has no lapack.dtrcon: the fit must not need it."""
    from scipy.linalg import lapack

    from course import lsq
    from course.lsq import _fit

    rng = np.random.default_rng(7)
    A = rng.standard_normal((30, 4))
    y = A @ np.arange(1.0, 5.0) + 0.1 * rng.standard_normal(30)
    reference = lsq.fit(A, y)
    R = np.linalg.qr(A, mode="r")
    estimate = _fit._rcond_upper(R)
    monkeypatch.delattr(lapack, "dtrcon", raising=False)
    assert not hasattr(lapack, "dtrcon")
    fitted = lsq.fit(A, y)
    np.testing.assert_allclose(fitted.x_hat, reference.x_hat, rtol=1e-12)
    exact = _fit._rcond_upper(R)  # 1 / (||R||_1 ||R^-1||_1); LAPACK estimates it within 3x
    assert exact == pytest.approx(1 / (np.linalg.norm(R, 1) * np.linalg.norm(np.linalg.inv(R), 1)))
    assert exact / 3 <= estimate <= 3 * exact
    dependent = np.column_stack([A[:, :3], A[:, 0] + A[:, 1]])
    with pytest.raises(np.linalg.LinAlgError, match="full column rank"):
        lsq.fit(dependent, y)
    singular = np.triu(np.ones((3, 3)))
    singular[1, 1] = 0.0
    assert _fit._rcond_upper(singular) == 0.0


def test_the_readme_states_the_supported_range():
    """The README's floors are pyproject's, and the CI step installs exactly those."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    pattern = re.compile(r"(numpy|scipy|matplotlib)>=([\d.]+)$")
    floors = dict(pattern.match(d).groups() for d in project["dependencies"] if pattern.match(d))
    assert set(floors) == {"numpy", "scipy", "matplotlib"}
    readme = (ROOT / "README.md").read_text()
    for name, version in floors.items():
        assert f"{name} {version}" in readme, name
    sys.path.insert(0, str(ROOT / ".ci"))
    try:
        from min_constraints import constraints
    finally:
        sys.path.remove(str(ROOT / ".ci"))
    assert constraints(ROOT / "pyproject.toml") == [
        f"{name}=={version}.*" for name, version in sorted(floors.items())
    ]
    assert "min_constraints.py" in (ROOT / ".ci" / "run").read_text()
    assert os.access(ROOT / ".ci" / "run", os.X_OK)
