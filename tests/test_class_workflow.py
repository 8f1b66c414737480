"""A graded class end to end: submitting, whose file is whose, the roster, and the grade files
an LMS imports. Grading runs once (module fixture) with a secret and a roster, on files named
as students and learning-management systems name them."""

from __future__ import annotations

import csv
import hashlib
import json
import shutil
from pathlib import Path

import nbformat
import numpy as np
import pytest

from course.cli import main as course_main
from course.grading import Assignment
from course.grading.authoring.checks import load_checks, load_data_module, student_rng
from course.grading.authoring.personal import PERSONAL_FILE, PersonalData, build_personal_data
from course.grading.authoring.secret import Secret
from course.grading.batch.driver import grade
from course.grading.batch.identity import resolve_identities
from course.grading.batch.intake import Submission
from course.grading.batch.options import GradeOptions
from course.grading.batch.roster import RosterError, read_roster
from course.grading.student.submit import make_submission

ROOT = Path(__file__).resolve().parents[1]
NAME = "01_least_squares"
SOLUTION = ROOT / "solutions" / NAME
EXERCISE = ROOT / "exercises" / NAME
SECRET = Secret(bytes(range(32)), "test key")
ROSTER_IDS = [f"s00{i}" for i in range(1, 9)]


def _notebook(tmp: Path, student_id: str, answers: dict | None = None) -> Path:
    """The solution notebook as a student would save it, with STUDENT_ID set."""
    nb = nbformat.read(SOLUTION / f"{NAME}.ipynb", as_version=4)
    for cell in nb.cells:
        if cell.get("id") == "setup":
            cell.source = cell.source.replace('STUDENT_ID = "demo"', f'STUDENT_ID = "{student_id}"')
        qid = cell.get("metadata", {}).get("course", {}).get("question")
        if answers and qid in answers and cell["metadata"]["course"]["role"] == "answer":
            cell.source = answers[qid]
    folder = tmp / student_id
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{NAME}.ipynb"
    nbformat.write(nb, path)
    return path


def _issued(tmp: Path) -> PersonalData:
    folder = tmp / "issued"
    folder.mkdir()
    text = build_personal_data(load_checks(SOLUTION), ROSTER_IDS + ["s006"], SECRET)
    (folder / PERSONAL_FILE).write_text(text)
    return PersonalData.read(folder)


# ---------------------------------------------------------------------------------------
# submitting
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "student_id, message",
    [
        ("replace-with-your-student-id", "still the placeholder"),
        ("", "is empty"),
        ("demo", "the demo ID"),
        ("Jane Doe", "not a valid student ID"),
        ("=1+1", "not a valid student ID"),
    ],
)
def test_submit_refuses_a_bad_id_and_writes_nothing(tmp_path, capsys, student_id, message):
    saved = _notebook(tmp_path, "s001")
    out = tmp_path / "out"
    out.mkdir()
    check = Assignment.load(NAME, student_id=student_id, path=EXERCISE)
    capsys.readouterr()  # the load's note on a placeholder ID
    assert check.submit(saved, out) is None
    printed = capsys.readouterr().out
    assert printed.startswith("Not submitted:") and message in printed
    assert list(out.iterdir()) == []
    code = course_main(["submit", str(saved), "--id", student_id, "--out", str(out)])
    assert code == 2 and message in capsys.readouterr().err
    assert list(out.iterdir()) == []


def test_submit_writes_the_file_to_upload(tmp_path, capsys):
    saved = _notebook(tmp_path, "s002")
    check = Assignment.load(NAME, student_id="s002", path=EXERCISE)

    def line_estimate(t, y):  # q1, answered
        return np.polyfit(t, y, 1)[::-1]

    kernel = {"check": check, "saved": saved, "line_estimate": line_estimate}
    exec("written = check.submit(saved)", kernel)  # as in the notebook's last cell
    written = kernel["written"]
    printed = capsys.readouterr().out
    assert written == saved.parent / f"s002_{NAME}.ipynb"
    assert "q1 (1 point)" in printed and "PASS" in printed  # every self-check ran first
    digest = hashlib.sha256(written.read_bytes()).hexdigest()
    assert f"sha256 {digest[:16]}" in printed and str(written) in printed
    meta = json.loads(written.read_text())["metadata"]["course"]
    assert meta["assignment"] == NAME and meta["submission"]["student_id"] == "s002"
    assert meta["submission"]["data_key"] == "public"
    # the kernel runs as another ID than the saved notebook: save first
    other = Assignment.load(NAME, student_id="s003", path=EXERCISE)
    assert other.submit(saved) is None
    assert "Save the notebook" in capsys.readouterr().out


def test_submit_refuses_an_id_without_issued_data(tmp_path, capsys):
    issued = _issued(tmp_path)
    saved = _notebook(tmp_path, "s099")
    check = Assignment.load(NAME, student_id="s099", path=EXERCISE)
    check.personal = issued
    assert check.submit(saved) is None
    assert "not in this course's personal data" in capsys.readouterr().out
    assert sorted(p.name for p in saved.parent.iterdir()) == [f"{NAME}.ipynb"]


def test_course_submit_takes_the_id_from_the_notebook(tmp_path, capsys):
    saved = _notebook(tmp_path, "s004")
    assert course_main(["submit", str(saved)]) == 0
    assert (saved.parent / f"s004_{NAME}.ipynb").is_file()
    untouched = tmp_path / "untouched.ipynb"
    shutil.copyfile(EXERCISE / f"{NAME}.ipynb", untouched)
    assert course_main(["submit", str(untouched)]) == 2
    assert "placeholder" in capsys.readouterr().err
    assert not list(tmp_path.glob("*_01_least_squares.ipynb"))


# ---------------------------------------------------------------------------------------
# a graded class
# ---------------------------------------------------------------------------------------
def _reconstructed_T(student_id: str) -> float:
    """q6 from the public generator run with one's own ID (the attack the secret defeats)."""
    from course import lsq

    data = load_data_module(EXERCISE / "data.py", NAME).survey(
        student_rng(NAME, "survey", student_id)
    )
    return float(lsq.overall_model_test(lsq.fit(data["A"], data["y"], data["Qyy"]), 0.01).statistic)


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("class")
    issued = _issued(tmp)
    subs = tmp / "submissions"
    subs.mkdir()
    # renamed by an LMS after check.submit(): the ID comes from the metadata
    path, _, _ = make_submission(_notebook(tmp, "s002"), None, NAME, None, issued)
    shutil.copyfile(path, subs / f"doejane_102_5551_{path.name}")
    # a bare <ID>.ipynb whose notebook says another ID: the name decides, and it is reported
    shutil.copyfile(_notebook(tmp, "s004"), subs / "s003.ipynb")
    # a name no LMS wrote, holding a roster ID as a word: it identifies nobody; graded under
    # the notebook's ID, flagged
    shutil.copyfile(_notebook(tmp, "s006"), subs / "Smith_Bob_s005_attempt2.ipynb")
    # someone not on the roster
    shutil.copyfile(_notebook(tmp, "zz9"), subs / "zz9.ipynb")
    # the public-generator attack on the personal question, submitted without secret data
    attack = _notebook(tmp, "s007", {"q6": f"T_mine = {_reconstructed_T('s007')!r}"})
    path, _, _ = make_submission(attack, None, NAME, None, None)
    shutil.copyfile(path, subs / path.name)
    roster = tmp / "roster.csv"
    roster.write_text(
        "\ufeffStudent,ID,SIS User ID,SIS Login ID,Section\n"
        "    Points Possible,,,,\n"
        + "".join(f'"Last{i}, First{i}",{100 + i},s00{i},login{i},A\n' for i in range(1, 9))
        + '"Student, Test",999,,,A\n'
    )
    options = GradeOptions(jobs=2, progress=False, secret=SECRET, roster=read_roster(roster))
    summary = grade(SOLUTION, subs, tmp / "out", options)
    return summary, tmp / "out"


def _row(summary, sid):
    return next(r.to_json() for r in summary.rows if r.student == sid)


def test_grader_uses_the_secret_data_and_the_metadata_id(graded):
    summary, _ = graded
    assert sorted(r.student for r in summary.rows) == ["s002", "s003", "s006", "s007", "zz9"]
    # s003.ipynb declares s004: graded as s003's (its name), with s003's data, and s003 is told
    assert "graded as 's003''s" in " ".join(_row(summary, "s003")["notes"])
    assert _row(summary, "s003")["total"] == _row(summary, "s003")["max"]
    row = _row(summary, "s002")
    assert row["total"] == row["max"], {q: r["message"] for q, r in row["questions"].items()}
    assert row["data_key"] == SECRET.key_id and row["file"]["name"].startswith("doejane_102_")
    attack = _row(summary, "s007")
    assert attack["questions"]["q6"]["points"] == 0  # rebuilt from the public generator
    assert attack["questions"]["q7"]["points"] > 0  # its other answers are right


def test_console_flags_every_name_mismatch(graded):
    summary, out = graded
    text = summary.text()
    assert "s003.ipynb: the notebook declares STUDENT_ID 's004', but its name makes it" in text
    assert (
        "Smith_Bob_s005_attempt2.ipynb: the file name is not an LMS's name or an ID; graded as "
        "'s006', the notebook's STUDENT_ID" in text
    )
    conflicts = list(csv.reader((out / "identity_conflicts.csv").open(encoding="utf-8")))
    assert [r[:3] + r[-1:] for r in conflicts[1:]] == [
        ["s003.ipynb", "s003", "s004", "graded as s003"]
    ]
    assert "worked on personal data issued with another key" in text and "s007_01" in text
    assert "doejane" not in text  # a renamed file whose name holds the right ID is fine
    assert "Roster: 4 missing (s001, s004, s005, s008), 1 not on the roster (zz9)" in text


def test_lms_grade_files(graded):
    summary, out = graded
    canvas = list(csv.reader((out / "canvas.csv").open(encoding="utf-8")))
    title = load_checks(SOLUTION).title
    assert canvas[0] == ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", title]
    assert (
        canvas[1][0].strip() == "Points Possible"
        and float(canvas[1][5]) == _row(summary, "s002")["max"]
    )
    by_sis = {r[2]: r for r in canvas[2:]}
    assert by_sis["s002"][:5] == ["Last2, First2", "102", "s002", "login2", "A"]
    assert float(by_sis["s002"][5]) == _row(summary, "s002")["total"]
    assert by_sis["s001"][5] == ""  # missing: blank leaves Canvas's grade alone
    assert "zz9" not in by_sis and len(canvas) == 2 + 8
    moodle = list(csv.reader((out / "moodle.csv").open(encoding="utf-8")))
    assert moodle[0] == ["ID number", "Email address", "First name", "Last name", title, "Feedback"]
    s2 = next(r for r in moodle if r[0] == "s002")
    assert s2[2:4] == ["First2", "Last2"] and "q1 1/1" in s2[5]
    assert next(r for r in moodle if r[0] == "s001")[4:] == ["", "No submission received."]
    assert (out / "grades.csv").is_file()


def test_a_roster_with_duplicates_stops_grading(tmp_path, capsys):
    roster = tmp_path / "roster.csv"
    roster.write_text("id;name;email\ns1;A;a@x\ns1;B;b@x\n")
    subs = tmp_path / "subs"
    subs.mkdir()
    out = tmp_path / "out"
    code = course_main(["grade", NAME, str(subs), "--out", str(out), "--roster", str(roster)])
    assert code == 2 and "'s1' (lines 2 and 3)" in capsys.readouterr().err
    assert not out.exists()


# ---------------------------------------------------------------------------------------
# rosters and names, without grading
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "text, ids, first",
    [
        ("id,name,email\n98765,Jane Doe,jd@x\n", ["98765"], ("Jane", "Doe")),
        (
            "First name,Last name,ID number,Institution,Department,Email address\n"
            "Jane,Doe,98765,U,D,jd@x\n",
            ["98765"],
            ("Jane", "Doe"),
        ),
        ("Name\tStudent ID\nDoe, Jane\t98765\n", ["98765"], ("Jane", "Doe")),
    ],
)
def test_rosters_from_lms_exports(tmp_path, text, ids, first):
    path = tmp_path / "r.csv"
    path.write_text(text)
    roster = read_roster(path)
    assert roster.ids == ids and roster.students[0].split_name() == first


@pytest.mark.parametrize(
    "text, message",
    [
        ("", "is empty"),
        ("name,email\nA,a@x\n", "no ID column"),
        ("id,name\n,A\n", "line 2: no student ID"),
        ("id,name\n=cmd|x,A\n", "line 2: '=cmd|x' is not a valid student ID"),
        ("id,name\n", "lists no students"),
    ],
)
def test_bad_rosters(tmp_path, text, message):
    path = tmp_path / "r.csv"
    path.write_text(text)
    with pytest.raises(RosterError, match=message):
        read_roster(path)
    with pytest.raises(RosterError, match="does not exist"):
        read_roster(tmp_path / "missing.csv")


def test_names_resolved_without_a_roster(tmp_path):
    def saved(name, sid):
        nb = nbformat.v4.new_notebook()
        cell = nbformat.v4.new_code_cell(f'STUDENT_ID = "{sid}"')
        cell["id"], cell["metadata"] = "setup", {"course": {"role": "setup"}}
        nb.cells = [cell]
        nbformat.write(nb, tmp_path / name)
        return Submission(Path(name).stem, tmp_path / name)

    entries = [
        saved("98765.ipynb", "98765"),
        saved(f"11111_{NAME}.ipynb", "11111"),
        saved("Doe_John_22222_01_least_squares.ipynb", "22222"),
        saved("Roe_Ann_33333_01_least_squares.ipynb", "replace-with-your-student-id"),
        saved("44444.ipynb", "44445"),
        saved("late_44444.ipynb", "44444"),
    ]
    identity = resolve_identities(entries, NAME)
    assert [e.student for e in identity.entries] == [
        "11111",
        "22222",
        "44444",
        "98765",
        "Roe_Ann_33333",
    ]
    flags = "\n".join(identity.flags)
    # the name makes 44444.ipynb 44444's, the notebook says 44445: 44444 is graded from the
    # file whose name and notebook agree, and the other is named; 44445 gets nothing
    assert "2 submissions claim the ID '44444': 44444.ipynb, late_44444.ipynb" in flags
    assert next(e for e in identity.entries if e.student == "44444").path.name == "late_44444.ipynb"
    assert not identity.conflicts
    assert (
        "Roe_Ann_33333_01_least_squares.ipynb: no student ID in the notebook; graded under" in flags
    )
    assert "22222" not in flags and "11111" not in flags


@pytest.mark.slow  # a fresh install or a whole grading run
def test_submitting_section_in_a_real_kernel(tmp_path):
    """The released notebook, run top to bottom in a Jupyter kernel as a student would (with
    unanswered questions), ends by writing the file to upload."""
    from nbclient import NotebookClient

    folder = tmp_path / NAME
    shutil.copytree(EXERCISE, folder)
    path = folder / f"{NAME}.ipynb"
    nb = nbformat.read(path, as_version=4)
    setup = next(c for c in nb.cells if c.get("id") == "setup")
    setup.source = setup.source.replace("replace-with-your-student-id", "s123")
    nbformat.write(nb, path)  # saved, as submit() asks
    NotebookClient(
        nb, timeout=120, allow_errors=True, resources={"metadata": {"path": str(folder)}}
    ).execute()
    last = "".join(o.get("text", "") for o in nb.cells[-1].outputs)
    written = folder / f"s123_{NAME}.ipynb"
    assert f"wrote {written}" in last and "not answered in the saved notebook: q1" in last, last
    meta = json.loads(written.read_text())["metadata"]["course"]["submission"]
    assert meta["student_id"] == "s123" and meta["source"] == path.name
