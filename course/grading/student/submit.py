"""Handing in: ``check.submit()`` in the notebook and ``course submit NOTEBOOK`` in a terminal.

Both write ``<ID>_<assignment>.ipynb``, a copy of the SAVED notebook whose metadata
(``metadata.course.submission``) records the student ID, the assignment, the course version,
the key id of the personal data it was worked on and the time it was written, and print the
file's sha256 (a receipt: ``results.jsonl`` records the digest of every graded file). A
missing, placeholder, demo or malformed ID, or an ID the class's personal data do not know,
is refused with one message and nothing is written.

The grader takes the ID from this metadata when a learning-management system renamed the
file (``Doe_John_98765_02_test_quantities.ipynb``); see :mod:`course.grading.batch.identity`.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from datetime import datetime, timezone
from pathlib import Path

from course.grading.authoring.personal import PersonalData
from course.grading.authoring.secret import public_key_id
from course.grading.items import is_unanswered_text
from course.grading.notebook import SubmissionError, read_submission, student_id_in
from course.grading.vocabulary import CellRole, check_student_id

__all__ = [
    "Refused",
    "make_submission",
    "submission_name",
    "submit_from_kernel",
    "unanswered_questions",
]


class Refused(ValueError):
    """Nothing was written: the message says why and what to do."""


def submission_name(student_id: str, assignment: str) -> str:
    return f"{student_id}_{assignment}.ipynb"


def _cells(nb: dict) -> list[dict]:
    return [c for c in nb.get("cells", []) if isinstance(c, dict)]


def _source(cell: dict) -> str:
    src = cell.get("source", "")
    return "".join(src) if isinstance(src, list) else str(src)


def _role(cell: dict) -> dict:
    meta = cell.get("metadata")
    course = meta.get("course") if isinstance(meta, dict) else None
    return course if isinstance(course, dict) else {}


def saved_student_id(nb: dict) -> str | None:
    """``STUDENT_ID`` as written in the saved notebook's setup cell (None if absent)."""
    for cell in _cells(nb):
        if cell.get("cell_type") != "code":
            continue
        if _role(cell).get("role") == CellRole.SETUP or cell.get("id") == "setup":
            return student_id_in(_source(cell))
    for cell in _cells(nb):  # a notebook whose metadata was lost: the first code cell
        if cell.get("cell_type") == "code":
            return student_id_in(_source(cell))
    return None


def unanswered_questions(nb: dict) -> list[str]:
    """Questions whose answer cell still holds the release's stub (or ``...``)."""
    out = []
    for cell in _cells(nb):
        meta = _role(cell)
        if meta.get("role") != CellRole.ANSWER or not meta.get("question"):
            continue
        src = _source(cell)
        stub = "raise NotImplementedError(" in src and "not answered yet" in src
        if cell.get("cell_type") == "markdown":  # a short answer: still its placeholder?
            stub = is_unanswered_text(src)
        if stub or src.strip().endswith("= ..."):
            out.append(str(meta["question"]))
    return out


def make_submission(
    notebook: Path,
    student_id: str | None,
    assignment: str | None = None,
    out: Path | None = None,
    personal: PersonalData | None = None,
    id_pattern: str | None = None,
) -> tuple[Path, str, dict]:
    """Write the submission file of a saved notebook: ``(path, sha256, notebook)``.

    ``student_id`` None takes it from the notebook's setup cell. Raises :class:`Refused`
    (nothing written) on a bad ID, an ID off the class's ``id_pattern`` (``class.json``), a
    notebook that is not the assignment's, or an ID that the issued personal data do not know.
    """
    notebook = Path(notebook)
    try:
        nb = read_submission(notebook)
    except SubmissionError as exc:
        raise Refused(f"{notebook} cannot be read: {exc}") from None
    meta: dict = nb["metadata"] if isinstance(nb.get("metadata"), dict) else {}
    course_meta: dict = meta["course"] if isinstance(meta.get("course"), dict) else {}
    name = assignment or course_meta.get("assignment")
    if not name:
        raise Refused(
            f"{notebook.name} is not an assignment notebook of the course (no assignment in its "
            "metadata); submit the notebook from your exercises/ folder"
        )
    if assignment and course_meta.get("assignment") not in (None, assignment):
        raise Refused(
            f"{notebook.name} is the notebook of {course_meta['assignment']}, not of {assignment}"
        )
    saved = saved_student_id(nb)
    where = "STUDENT_ID" if student_id is None else "the student ID"
    try:
        sid = check_student_id(saved if student_id is None else student_id, where, id_pattern)
    except ValueError as exc:
        raise Refused(str(exc)) from None
    if student_id is not None and saved is not None and saved.strip() != sid:
        raise Refused(
            f"the saved notebook has STUDENT_ID = {saved!r}, but you are submitting as {sid!r}: "
            "save the notebook (Ctrl-S) after setting STUDENT_ID, then submit again"
        )
    if personal is not None and not personal.has(sid):
        raise Refused(_unknown_id(sid, personal))
    import course

    submission = {
        "student_id": sid,
        "assignment": name,
        "course_version": str(getattr(course, "__version__", "unknown")),
        "data_key": personal.key_id if personal is not None else public_key_id,
        "written": datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "source": notebook.name,
    }
    nb["metadata"] = dict(meta, course=dict(course_meta, assignment=name, submission=submission))
    folder = Path(out) if out is not None else notebook.parent
    if not folder.is_dir():
        raise Refused(f"cannot write the submission: {folder} is not a folder")
    target = folder / submission_name(sid, name)
    data = (json.dumps(nb, indent=1, ensure_ascii=False) + "\n").encode("utf-8")
    tmp = target.with_name(f".{target.name}.partial")
    tmp.write_bytes(data)
    os.replace(tmp, target)
    return target, hashlib.sha256(data).hexdigest(), nb


def _unknown_id(sid: str, personal: PersonalData) -> str:
    known = personal.registered_case(sid)
    if known is not None:
        return (
            f"your student ID {sid!r} is not registered, but {known!r} is: IDs are "
            f"case-sensitive. Set STUDENT_ID = {known!r} in the first cell, run that cell, "
            "save, and submit again"
        )
    return (
        f"your student ID {sid!r} is not in this course's personal data, so it cannot be "
        "graded on your data: check STUDENT_ID in the first cell (exactly as registered, the "
        "same upper and lower case), run that cell, save, and submit again; if it is right, "
        "ask your instructor"
    )


# --------------------------------------------------------------------------------------
# in the notebook
# --------------------------------------------------------------------------------------
def _notebook_path(namespace: dict, assignment: str) -> Path | None:
    """The notebook this kernel belongs to, as the front end tells it, else the
    assignment's notebook in the working folder."""
    hints = [
        namespace.get("__session__"),  # JupyterLab / Notebook 7 (ipykernel >= 6.22)
        namespace.get("__vsc_ipynb_file__"),  # VS Code
        os.environ.get("JPY_SESSION_NAME"),
    ]
    for hint in hints:
        if isinstance(hint, str) and hint.endswith(".ipynb"):
            path = Path(hint)
            if not path.is_absolute():
                path = Path.cwd() / path.name if not path.exists() else path.resolve()
            if path.is_file():
                return path
    path = Path.cwd() / f"{assignment}.ipynb"
    return path if path.is_file() else None


def saved_short_answer(namespace: dict, assignment: str, qid: str) -> str | None:
    """The text of ``qid``'s short-answer cell in the saved notebook of this kernel (None when
    the notebook or the cell is not found): the self-check says whether it is answered."""
    path = _notebook_path(namespace, assignment)
    if path is None:
        return None
    try:
        nb = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    for cell in _cells(nb):
        meta = _role(cell)
        if meta.get("role") == CellRole.ANSWER and meta.get("question") == qid:
            return _source(cell)
    return None


def _stale_answers(nb: dict, namespace: dict) -> list[str]:
    """Questions whose SAVED code answer was never run in this kernel (edited and not saved,
    or not run since the kernel started).

    Only code cells reach the kernel's input history ``In``. A short answer (a markdown
    cell) is graded as the saved file holds it, and the submission is that file, so there is
    nothing to compare it with.
    """
    history = namespace.get("In")
    if not isinstance(history, list) or len(history) < 2:
        return []
    ran = {"\n".join(line.rstrip() for line in str(h).strip().splitlines()) for h in history}
    stale = []
    for cell in _cells(nb):
        meta = _role(cell)
        if cell.get("cell_type") != "code":
            continue
        if meta.get("role") == CellRole.ANSWER and meta.get("question"):
            saved = "\n".join(line.rstrip() for line in _source(cell).strip().splitlines())
            if saved and saved not in ran:
                stale.append(str(meta["question"]))
    return stale


class WrittenPath(type(Path())):  # type: ignore[misc]
    """The submission's path, returned by ``check.submit()``: a :class:`~pathlib.Path` that
    Jupyter does not display, since the receipt printed above already names the file (the
    submit cell ends with the call, so its value would show as ``PosixPath('…')``)."""

    def _ipython_display_(self) -> None:
        return None


def submit_from_kernel(check, namespace: dict, notebook=None, out=None) -> Path | None:
    """``check.submit()``: refuse or write, and print what happened (never a traceback)."""
    name = check.name
    try:
        sid = check_student_id(check.student_id, pattern=check.id_pattern)
    except ValueError as exc:
        print(f"Not submitted: {exc}.")
        return None
    if check.personal is not None and not check.personal.has(sid):
        print(f"Not submitted: {_unknown_id(sid, check.personal)}.")
        return None
    path = Path(notebook) if notebook is not None else _notebook_path(namespace, name)
    if path is None or not path.is_file():
        print(
            "Not submitted: cannot find your saved notebook. Save it (Ctrl-S), then run "
            f"check.submit('{name}.ipynb') with the path of your notebook file."
        )
        return None
    try:
        saved_nb = read_submission(path)
    except SubmissionError as exc:
        print(f"Not submitted: {path} cannot be read: {exc}.")
        return None
    saved = saved_student_id(saved_nb)
    if saved is None or saved.strip() != sid:
        print(
            f"Not submitted: the saved notebook has STUDENT_ID = {saved!r}, but this kernel "
            f"runs with {sid!r}. Save the notebook (Ctrl-S), then run this cell again."
        )
        return None
    print(f"Self-checks of {name} (student {sid}):\n")
    check.all(namespace)
    try:
        target, digest, nb = make_submission(path, sid, name, out, check.personal, check.id_pattern)
    except Refused as exc:
        print(f"Not submitted: {exc}.")
        return None
    age = max(0.0, time.time() - path.stat().st_mtime)
    when = f"{age:.0f} s" if age < 120 else f"{age / 60:.0f} min"
    print(f"Submission of {name} for student {sid}:")
    missing = unanswered_questions(nb)
    if missing:
        print(f"  not answered in the saved notebook: {', '.join(missing)}")
    stale = _stale_answers(nb, namespace)
    if stale:
        print(
            f"  Warning: the saved answers to {', '.join(stale)} are not what this kernel ran: "
            "save (Ctrl-S), restart and run all cells, then submit again."
        )
    size = target.stat().st_size
    print(
        f"  wrote {target} ({size / 1024:.0f} KB, from the notebook saved {when} ago)\n"
        f"  sha256 {digest[:16]}… (your receipt)\n"
        "  Upload this file to your course's assignment page. Changed something? Save, run "
        "this cell again and upload the new file."
    )
    return WrittenPath(target)
