"""The worked example of docs/instructors/authoring.md scores its own solution full marks.

The page builds an assignment ``01_example`` from three code blocks (the notebook generator,
``checks.py`` and ``data.py``). Its q4 used to hard-code ``verdict = 'reject'`` for personal
data, so the example's own solution scored 4 of 7 for most IDs (issue 37 item 7). This test
writes the blocks to a folder, builds the notebook, runs its solution cells as a student of
each of 40 IDs would (``check.data`` gives that ID's data) and compares every automatically
graded answer with the reference the grader uses.
"""

from __future__ import annotations

import json
import re
import runpy
from pathlib import Path

import numpy as np

from course.grading.authoring.checks import load_checks
from course.grading.compare import compare
from course.grading.items import match_option

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "instructors" / "authoring.md"


def _blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", PAGE.read_text(encoding="utf-8"), re.S)


def _block(marker: str) -> str:
    (block,) = [b for b in _blocks() if marker in b]
    return block


class _Check:
    """The notebook's ``check`` for one student: only ``check.data`` is used by answers."""

    def __init__(self, checks, student_id):
        self._checks, self._id = checks, student_id

    def data(self, key):
        return self._checks.data_for(key, self._id, None)

    def __call__(self, *args, **kwargs):
        return None


def test_the_worked_example_scores_its_own_solution_full_marks(tmp_path, monkeypatch):
    folder = tmp_path / "solutions" / "01_example"
    folder.mkdir(parents=True)
    (folder / "__init__.py").write_text("")
    (folder / "checks.py").write_text(_block('CHECKS = Checks("01_example"'), encoding="utf-8")
    (folder / "data.py").write_text(_block("def line(rng)"), encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    runpy.run_path(_write(tmp_path / "make.py", _block("new_assignment_notebook(")))
    checks = load_checks(folder)
    nb = json.loads((folder / "01_example.ipynb").read_text(encoding="utf-8"))
    graded = {qid: q for qid, q in checks.questions.items() if q.kind != "short_answer"}
    assert graded, "the example has automatically graded questions"
    for k in range(40):
        student = f"s{k:03d}"
        ns = {"check": _Check(checks, student)}
        for cell in nb["cells"]:
            role = cell.get("metadata", {}).get("course", {}).get("role")
            if cell["cell_type"] == "code" and role != "setup" and role != "check":
                source = "".join(cell["source"])
                exec(compile(source, cell.get("id", "cell"), "exec"), ns)
        for qid, q in graded.items():
            assert q.reference is not None
            d = checks.data_for(q.data, student, None) if q.data else None
            if q.kind == "function":
                for case in q.cases:
                    got = ns[q.target](*case.args, **(case.kwargs or {}))
                    want = q.reference(*case.args, **(case.kwargs or {}))
                    assert compare(want, got, q.rtol, q.atol).ok, (student, qid)
                continue
            want = q.reference(d) if q.data else q.reference()
            got = ns[q.target]
            if q.kind == "choice":
                assert match_option(list(q.options), got) == match_option(list(q.options), want), (
                    student,
                    qid,
                    got,
                    want,
                )
            else:
                assert compare(
                    want, np.asarray(got) if isinstance(got, list) else got, q.rtol, q.atol
                ).ok


def _write(path: Path, text: str) -> str:
    path.write_text(text, encoding="utf-8")
    return str(path)
