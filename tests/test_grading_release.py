"""Release: every assignment under solutions/ is released exactly as committed, its solution
scores full marks and its untouched student notebook scores 0. Parametrised over solutions/*,
so new assignments are covered automatically. Also: the marker rules of `course release`."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest
from conftest import class_submissions

from course.grading.authoring.checks import load_checks
from course.grading.authoring.notebooks import (
    answer_cell,
    check_cell,
    code,
    md,
    new_assignment_notebook,
    setup_cell,
)
from course.grading.authoring.passes import make_release
from course.grading.authoring.release import find_solutions, release_files
from course.grading.notebook import MarkerError, strip_markers

ROOT = Path(__file__).resolve().parents[1]
SOLUTIONS = ROOT / "solutions"
EXERCISES = ROOT / "exercises"
ASSIGNMENTS = find_solutions(SOLUTIONS)


def test_there_is_at_least_one_assignment():
    assert "01_least_squares" in ASSIGNMENTS


def _close(a, b, path="") -> None:
    """Structural equality with a relative tolerance on floats (BLAS may differ in the last ulp)."""
    if isinstance(a, float) or isinstance(b, float):
        assert isinstance(a, (int, float)) and isinstance(b, (int, float)), path
        assert math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12), (path, a, b)
    elif isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), path
        if set(a) == {"__ndarray__"}:
            import numpy as np

            from course.grading.codec import decode

            x, y = decode(a), decode(b)
            assert x.dtype == y.dtype and x.shape == y.shape, path
            assert np.allclose(x, y, rtol=1e-9, atol=1e-12, equal_nan=True), path
            return
        for k in a:
            _close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _close(x, y, f"{path}[{i}]")
    else:
        assert a == b, (path, a, b)


@pytest.mark.parametrize("name", ASSIGNMENTS)
def test_committed_release_is_fresh(name):
    fresh = release_files(SOLUTIONS / name)
    committed_dir = EXERCISES / name
    committed = {
        p.relative_to(committed_dir).as_posix()
        for p in committed_dir.rglob("*")
        if p.is_file() and "__pycache__" not in p.parts and ".ipynb_checkpoints" not in p.parts
    }
    assert committed == set(fresh), f"run `course release {name}`"
    for rel, content in fresh.items():
        on_disk = (committed_dir / rel).read_bytes()
        if rel == "checks.json":
            # expected values are floats computed with numpy: compare with a tolerance
            _close(json.loads(content), json.loads(on_disk))
        else:
            assert on_disk == content, f"{name}/{rel} is stale: run `course release {name}`"


@pytest.mark.parametrize("name", ASSIGNMENTS)
def test_release_leaks_no_solution(name):
    checks = load_checks(SOLUTIONS / name)
    files = release_files(SOLUTIONS / name)
    nb = nbformat.reads(files[f"{name}.ipynb"].decode(), as_version=4)
    text = files[f"{name}.ipynb"].decode()
    assert "BEGIN SOLUTION" not in text and "HIDDEN TESTS" not in text
    assert (
        'STUDENT_ID = "replace-with-your-student-id"'
        in nb.cells[[c.cell_type for c in nb.cells].index("code")].source
    )
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert cell.outputs == [] and cell.execution_count is None
            compile(
                __import__("course.grading.notebook", fromlist=["x"]).python_source(cell.source),
                "<c>",
                "exec",
            )
    spec = json.loads(files["checks.json"])
    for q in spec["questions"]:
        cq = checks.questions[q["id"]]
        assert len(q["cases"]) == (
            len(cq.public_cases) if cq.kind == "function" else int(cq.public)
        )
        if cq.kind == "short_answer":  # marked by the instructor: no case at all
            assert q["hidden_cases"] == 0
            continue
        assert q["hidden_cases"] == (
            len(cq.hidden_cases) if cq.kind == "function" else int(not cq.public)
        )
    import inspect

    # hints are public prose written for students; everything else must carry no reference code
    raw = json.dumps([{k: v for k, v in q.items() if k != "hint"} for q in spec["questions"]])

    for cq in checks.questions.values():  # no line of any reference ships
        if cq.reference is None:  # a short answer has no reference (its rubric never ships)
            continue
        body = inspect.getsource(cq.reference).splitlines()[1:]
        for line in body:
            line = line.strip()
            if len(line) > 12 and not line.startswith(("#", '"', "'")):
                assert line not in raw, (cq.id, line)
    assert "checks.py" not in files


@class_submissions("release")
def _release_submissions(name: str, subs: Path) -> None:
    """Every solution (as the demo student and as another ID) and every untouched release."""
    solution = (SOLUTIONS / name / f"{name}.ipynb").read_bytes()
    (subs / "demo.ipynb").write_bytes(solution)
    (subs / "other-student.ipynb").write_bytes(solution)
    (subs / "untouched.ipynb").write_bytes((EXERCISES / name / f"{name}.ipynb").read_bytes())


@pytest.mark.parametrize("name", ASSIGNMENTS)
def test_solution_scores_full_marks(graded_class, name):
    for sid in ("demo", "other-student"):
        row = graded_class(name).rows[sid]
        # short answers wait for the instructor's marks ("to mark"): all the rest is automatic
        to_mark = sum(r["max"] for r in row["questions"].values() if r["status"] == "to mark")
        assert row["total"] == row["max"] - to_mark > 0, (
            sid,
            {q: (r["status"], r["message"]) for q, r in row["questions"].items()},
        )
        assert row["status"] == "ok"


@pytest.mark.parametrize("name", ASSIGNMENTS)
def test_untouched_release_scores_zero(graded_class, name):
    row = graded_class(name).rows["untouched"]
    assert row["total"] == 0
    assert all(r["status"] == "not answered" for r in row["questions"].values()), row["questions"]


# ---------------------------------------------------------------------------------------
# marker rules
# ---------------------------------------------------------------------------------------
def _nb(answer_source: str, extra=()):
    return new_assignment_notebook(
        "x",
        [
            md("# t"),
            setup_cell("x"),
            code("import numpy as np"),
            answer_cell("q1", answer_source),
            check_cell("q1"),
            *extra,
        ],
    )


def _question_texts(name: str) -> dict[str, str]:
    """Each question's markdown in the released notebook: from its ``## qid`` header to the
    next question's header."""
    nb = json.loads((EXERCISES / name / f"{name}.ipynb").read_text("utf-8"))
    texts: dict[str, str] = {}
    current = None
    for cell in nb["cells"]:
        if cell["cell_type"] != "markdown":
            continue
        for line in "".join(cell["source"]).splitlines():
            if line.startswith("## q"):
                current = line[3:].split()[0]
            if current is not None:
                texts[current] = texts.get(current, "") + "\n" + line
    return texts


@pytest.mark.parametrize("name", ASSIGNMENTS)
def test_every_forbidden_function_is_named_in_its_question(name):
    """Forbidden means promised: each function a question forbids is named in its text, and
    the release states how calls count (issue 26)."""
    checks = load_checks(SOLUTIONS / name)
    texts = _question_texts(name)
    for qid, text in list(texts.items()):  # "Same rules as q1", "as in q5": that list applies
        for ref in re.findall(r"\bas (?:in )?(q\w+)", text):
            texts[qid] = text + texts.get(ref, "")
    unnamed = [
        f"{q.id}: {dotted}"
        for q in checks.questions.values()
        for dotted in q.forbid
        if f"`{dotted.rsplit('.', 1)[1]}`" not in texts.get(q.id, "")
        and f".{dotted.rsplit('.', 1)[1]}`" not in texts.get(q.id, "")
    ]
    assert not unnamed, f"forbidden but not named in the question: {unnamed}"
    notebook = (EXERCISES / name / f"{name}.ipynb").read_text("utf-8")
    if any(q.forbid for q in checks.questions.values()):
        assert "Importing it costs nothing" in notebook and "honour code" in notebook


def test_stub_replaces_solution_at_its_indentation():
    src = "def f(x):\n    ### BEGIN SOLUTION\n    return 2 * x\n    ### END SOLUTION\n"
    out, n = strip_markers(src, "cell", "q1", allow_solution=True)
    assert n == 1
    assert (
        out
        == 'def f(x):\n    # YOUR CODE HERE\n    raise NotImplementedError("q1: not answered yet")\n'
    )
    out, _ = strip_markers(
        "### BEGIN SOLUTION\nx = 1\n### STUB x = ...\n### END SOLUTION", "c", "q1", True
    )
    assert out == "x = ..."
    out, _ = strip_markers(
        "a = 1\n### BEGIN HIDDEN TESTS\nassert a == 1\n### END HIDDEN TESTS\nb = 2",
        "c",
        None,
        False,
    )
    assert out == "a = 1\nb = 2"


@pytest.mark.parametrize(
    "source, message",
    [
        ("### BEGIN SOLUTION\nx = 1\n", "never closed"),
        ("x = 1\n### END SOLUTION\n", "without a matching"),
        (
            "### BEGIN SOLUTION\n### BEGIN SOLUTION\nx = 1\n### END SOLUTION\n",
            "inside an open region",
        ),
        (
            "### BEGIN HIDDEN TESTS\n### BEGIN SOLUTION\nx=1\n### END SOLUTION\n### END HIDDEN TESTS",
            "inside an open region",
        ),
        ("### BEGIN SOLUTION\nx = 1\n### END HIDDEN TESTS\n", "without a matching"),
        ("## BEGIN SOLUTION\nx = 1\n### END SOLUTION\n", "malformed marker"),
        ("x = 1\n", "has no '### BEGIN SOLUTION' region"),
        ("### BEGIN SOLUTION\nx = (1\n### END SOLUTION\n", "not valid Python"),
    ],
)
def test_release_refuses_bad_markers(source, message):
    with pytest.raises(MarkerError, match=message):
        make_release(_nb(source), "x")


def test_release_refuses_solution_outside_answer_and_mismatched_questions():
    bad = _nb(
        "### BEGIN SOLUTION\nx = 1\n### END SOLUTION",
        extra=[code("### BEGIN SOLUTION\ny = 2\n### END SOLUTION")],
    )
    with pytest.raises(MarkerError, match="outside an answer cell"):
        make_release(bad, "x")

    class Q:
        kind, target = "value", "x"

    with pytest.raises(MarkerError, match=r"q2 .*has no answer cell"):
        make_release(
            _nb("### BEGIN SOLUTION\nx = 1\n### END SOLUTION"), "x", {"q1": Q(), "q2": Q()}
        )
    Q.target = "not_defined"
    with pytest.raises(MarkerError, match="must assign variable 'not_defined'"):
        make_release(_nb("### BEGIN SOLUTION\nx = 1\n### END SOLUTION"), "x", {"q1": Q()})


def test_cli_release_fails_clearly_on_unclosed_marker(tmp_path):
    sol = tmp_path / "solutions" / "00_bad"
    sol.mkdir(parents=True)
    nbformat.write(
        new_assignment_notebook(
            "00_bad",
            [
                setup_cell("00_bad"),
                answer_cell("q1", "### BEGIN SOLUTION\nx = 1\n"),
                check_cell("q1"),
            ],
        ),
        sol / "00_bad.ipynb",
    )
    (sol / "checks.py").write_text(
        "from course.grading.authoring.checks import Checks\nCHECKS = Checks('00_bad')\n"
        "@CHECKS.value('q1', var='x', points=1)\ndef q1():\n    return 1\n"
    )
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "course",
            "release",
            "00_bad",
            "--solutions",
            str(tmp_path / "solutions"),
            "--exercises",
            str(tmp_path / "exercises"),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert proc.returncode == 1
    assert "00_bad" in proc.stderr and "never closed" in proc.stderr and "q1-answer" in proc.stderr
    assert not (tmp_path / "exercises" / "00_bad").exists()


def test_release_is_deterministic():
    name = ASSIGNMENTS[0]
    assert release_files(SOLUTIONS / name) == release_files(SOLUTIONS / name)
