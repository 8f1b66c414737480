"""Whose file is whose, and what a file may be (issue 34 items 2 and 3): each LMS's grammar read
by its own parser, uploaders decided by the LMS never by the student's names, and every file
looked at with ``lstat`` before anything opens it, in folders and in the LMS's download zips."""

from __future__ import annotations

import json
import os
import signal
import stat
import zipfile
from pathlib import Path

import pytest

from course.grading.batch.identity import _contains, resolve_identities
from course.grading.batch.intake import Submission, file_digest, find_submissions, unpack_archive
from course.grading.batch.lmsnames import LmsName, canvas_name, download_kind, lms_name, moodle_name
from course.grading.batch.roster import read_roster

NAME = "01_least_squares"


# -- the parsers: real names and hostile ones --------------------------------------------------
@pytest.mark.parametrize(
    ("name", "expected"),
    [
        (f"doejane_101_5001_{NAME}.ipynb", ("101", "doejane", 5001, False)),
        (f"doejane_LATE_101_5001_{NAME}-1.ipynb", ("101", "doejane", 5001, True)),
        ("doejane_late_101_5001_x.ipynb", ("101", "doejane", 5001, True)),
        ("doejane_101_5001_report.html", ("101", "doejane", 5001, False)),
        # the uploaded part never identifies: another user's numbers in it are text
        ("lorymal_102_950_timvic_LATE_101_9999_x.ipynb", ("102", "lorymal", 950, False)),
        ("lorymal_102_950_victim1.ipynb", ("102", "lorymal", 950, False)),
        ("lorymal_102_950_", None),  # nothing uploaded
        ("doe_jane_101_5001_x.ipynb", None),  # Canvas's lastfirst has no "_"
        ("98765.ipynb", None),
        ("Jane Doe_11_assignsubmission_file_", None),
    ],
)
def test_canvas_names(name, expected):
    parsed = canvas_name(name)
    if expected is None:
        assert parsed is None
    else:
        assert (parsed.number, parsed.person, parsed.order, parsed.late) == expected
        assert parsed.kind == "canvas" and parsed.uploader == f"canvas:{expected[0]}"


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("Jane Doe_11_assignsubmission_file_", ("11", "Jane Doe")),
        ("Jane Doe_11_assignsubmission_onlinetext_", ("11", "Jane Doe")),
        ("Zoë O'Neil-Ng_4711_assignsubmission_file_", ("4711", "Zoë O'Neil-Ng")),
        # a display name holding another participant's marker: the number is read from the end
        ("Zed_111_assignsubmission_file__112_assignsubmission_file_", ("112", "Zed_111_assignsubmission_file_")),
        ("Mal_111_assignsubmission_file_ x_12_assignsubmission_file_", ("12", "Mal_111_assignsubmission_file_ x")),
        # a flat file: only with one marker (both sides are anyone's text)
        ("Jane Doe_11_assignsubmission_file_notebook.ipynb", ("11", "Jane Doe")),
        ("A_1_assignsubmission_file_B_2_assignsubmission_file_c.ipynb", None),
        ("_11_assignsubmission_file_x.ipynb", None),
        ("Jane Doe_assignsubmission_file_", None),
        ("doejane_101_5001_x.ipynb", None),
    ],
)  # fmt: skip
def test_moodle_names(name, expected):
    parsed = moodle_name(name)
    assert (None if parsed is None else (parsed.number, parsed.person)) == expected


@pytest.mark.parametrize(
    ("name", "folder", "expected"),
    [
        ("98765.ipynb", False, LmsName("id", "98765")),
        (f"98765_{NAME}.ipynb", False, LmsName("id", "98765")),
        ("98765", True, LmsName("id", "98765")),
        (f"{NAME}.ipynb", False, LmsName("other", person=f"{NAME}.ipynb")),
        ("s001.html", False, LmsName("id", "s001")),  # an ID's file that is not a notebook
        ("evil\x1bname.ipynb", False, LmsName("other", person="evil\x1bname.ipynb")),
        ("Jane Doe_11_assignsubmission_file_", True, LmsName("moodle", "11", "Jane Doe")),
        # a folder is never read as Canvas's, a file never as a Moodle folder
        ("doejane_101_5001_x", True, LmsName("id", "doejane_101_5001_x")),
    ],
)
def test_lms_name_picks_the_grammar(name, folder, expected):
    assert lms_name(name, NAME, folder=folder) == expected


def test_one_upload_named_like_the_other_lms_does_not_change_the_class():
    """In a Canvas class, a file uploaded as ``x_12_assignsubmission_file_y`` stays Canvas's."""
    names = [f"doe{i}_10{i}_50{i}_{NAME}.ipynb" for i in range(5)]
    names.append("mal_109_509_Zed_12_assignsubmission_file_y.ipynb")
    assert download_kind(names, []) == "canvas"
    assert lms_name(names[-1], NAME).number == "109"
    folders = [f"Ann {i}_{i}_assignsubmission_file_" for i in range(3)]
    assert download_kind(["Bob_7_8_x.ipynb"], folders) == "moodle"
    assert lms_name("Bob_1_2_assignsubmission_file_x.ipynb", NAME, moodle=True).number == "2"


def test_an_id_inside_a_longer_token_never_matches(tmp_path):
    """Issue 40 item 5: ``s123`` is not in ``s1234`` (a mutation of the token rule survived)."""
    assert not _contains("s1234", "s123") and not _contains("xs123", "s123")
    assert not _contains("s123a", "s123") and _contains("late_s123", "s123")
    assert _contains("s123-2", "s123")
    subs = tmp_path / "subs"
    _notebook(subs / "hw_s1234.ipynb", "s123")
    _notebook(subs / "s1234.ipynb", "s1234")
    identity = _resolve(subs, _roster(tmp_path, "id\ns123\ns1234\n"))
    graded = {e.student: e.path.name for e in identity.entries}
    assert graded == {"s123": "hw_s1234.ipynb", "s1234": "s1234.ipynb"}
    # graded as s123 only because the notebook says so, and flagged: the name did not agree
    assert any(
        f.startswith("hw_s1234.ipynb: the file name is not an LMS's name or an ID")
        for f in identity.flags
    ), identity.flags


# -- the six identity cases of issue 34 -----------------------------------------------------------
def _notebook(path: Path, sid: str | None, assignment: str = NAME) -> Path:
    """A notebook declaring ``sid`` (submission metadata and setup cell) for ``assignment``."""
    declared = sid or "replace-with-your-student-id"
    nb = {
        "nbformat": 4,
        "nbformat_minor": 5,
        "metadata": {"course": {"assignment": assignment, "submission": {"student_id": declared}}},
        "cells": [
            {
                "cell_type": "code",
                "id": "setup",
                "metadata": {"course": {"role": "setup"}},
                "source": f'STUDENT_ID = "{declared}"',
                "outputs": [],
                "execution_count": None,
            }
        ],
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(nb))
    return path


def _roster(tmp_path: Path, text: str):
    path = tmp_path / "roster.csv"
    path.write_text(text, encoding="utf-8")
    return read_roster(path)


def _resolve(folder: Path, roster=None):
    return resolve_identities(
        find_submissions(folder, NAME), NAME, roster.students if roster else None
    )


def _graded(identity, sid: str) -> str | None:
    entry = next((e for e in identity.entries if e.student == sid), None)
    return None if entry is None or entry.path is None else entry.path.name


NAMES_ROSTER = "id,name\nvictim1,Vic Tim\nmallory,Mal Lory\n"
CANVAS_ROSTER = 'Student,ID,SIS User ID\n"Tim, Vic",101,victim1\n"Lory, Mal",102,mallory\n'


@pytest.mark.parametrize("roster_text", [NAMES_ROSTER, CANVAS_ROSTER])
def test_mallory_uploads_victim1_ipynb(tmp_path, roster_text):
    """Cases 1 and 2: Mallory's upload named ``victim1.ipynb`` declaring victim1 had the
    highest submission number and took victim1's grade (victim1's own file dropped)."""
    subs = tmp_path / "subs"
    _notebook(subs / f"timvic_101_500_{NAME}.ipynb", "victim1")
    _notebook(subs / "lorymal_102_950_victim1.ipynb", "victim1")
    identity = _resolve(subs, _roster(tmp_path, roster_text))
    assert _graded(identity, "victim1") == f"timvic_101_500_{NAME}.ipynb"
    assert _graded(identity, "mallory") == "lorymal_102_950_victim1.ipynb"
    assert [a[:3] for a in identity.attached] == [
        ("lorymal_102_950_victim1.ipynb", "mallory", "victim1")
    ]
    assert not identity.conflicts and not identity.warning


def test_mallory_uploads_victim1_ipynb_without_a_roster(tmp_path):
    """Case 3: without a roster the uploader (Canvas's user number) still holds: Mallory's
    own file declares her ID, so her claim on victim1 is hers alone and is not graded."""
    subs = tmp_path / "subs"
    _notebook(subs / f"timvic_101_500_{NAME}.ipynb", "victim1")
    _notebook(subs / f"lorymal_102_900_{NAME}.ipynb", "mallory")
    _notebook(subs / "lorymal_102_950_victim1.ipynb", "victim1")
    identity = _resolve(subs)
    assert _graded(identity, "victim1") == f"timvic_101_500_{NAME}.ipynb"
    assert _graded(identity, "mallory") == f"lorymal_102_900_{NAME}.ipynb"
    assert [c[0] for c in identity.conflicts] == ["lorymal_102_950_victim1.ipynb"]
    # told once, at the start: nothing tells who uploaded the LMS's files
    assert identity.warning.startswith("WARNING: 3 file(s) are named by an LMS")
    assert "there is no --roster" in identity.warning
    assert identity.flags[0] == identity.warning
    assert sum(f.startswith("WARNING") for f in identity.flags) == 1


def test_a_moodle_display_name_cannot_borrow_a_participant_number(tmp_path):
    """Case 4: the lazy ``^(.+?)_(\\d+)_assignsubmission_`` read Mallory's folder (display name
    ``Zed_111_assignsubmission_file_``) as participant 111's, victim1's: same uploader, and
    her file won by name order."""
    subs = tmp_path / "subs"
    _notebook(subs / "Vic Tim_111_assignsubmission_file_" / f"{NAME}.ipynb", "victim1")
    mallory = "Zed_111_assignsubmission_file__112_assignsubmission_file_"
    _notebook(subs / mallory / f"{NAME}.ipynb", "victim1")
    identity = _resolve(subs)
    assert _graded(identity, "victim1") is None or (
        next(e for e in identity.entries if e.student == "victim1").path.parent.name != mallory
    )
    assert any(c[0].startswith(mallory) for c in identity.conflicts)
    # with the grading worksheet as roster: participant numbers decide, nobody is held
    roster = _roster(
        tmp_path,
        "Identifier,Full name,ID number\nParticipant 111,Vic Tim,victim1\n"
        "Participant 112,Zed_111_assignsubmission_file_,mallory\n",
    )
    identity = _resolve(subs, roster)
    assert next(e for e in identity.entries if e.student == "victim1").path.parent.name == (
        "Vic Tim_111_assignsubmission_file_"
    )
    assert next(e for e in identity.entries if e.student == "mallory").path.parent.name == mallory
    assert not identity.conflicts and not identity.warning


def test_a_moodle_display_name_cannot_borrow_a_participants_time(tmp_path):
    """Case 5: late.py's lazy pattern charged Mallory participant 111's time (on time)
    instead of her own (3.5 days late)."""
    from course.grading.batch.late import late_records, parse_due, parse_policy

    subs = tmp_path / "subs"
    _notebook(subs / "Vic Tim_111_assignsubmission_file_" / f"{NAME}.ipynb", "victim1")
    mallory = "Zed_111_assignsubmission_file__112_assignsubmission_file_"
    path = _notebook(subs / mallory / f"{NAME}.ipynb", "mallory")
    sheet = tmp_path / "worksheet.csv"
    sheet.write_text(
        "Identifier,Full name,Last modified (submission)\n"
        'Participant 111,Vic Tim,"Tuesday, 20 October 2026, 11:00 PM"\n'
        'Participant 112,Zed,"Saturday, 24 October 2026, 11:00 AM"\n'
    )
    due = parse_due("2026-10-20T23:59+02:00")
    entries = [Submission("mallory", path, lms=mallory, in_folder=True)]
    records, _ = late_records(entries, subs, due, parse_policy("percent-per-day:10"), sheet)
    assert records["mallory"]["submitted_at"] == "2026-10-24T11:00+02:00"
    assert records["mallory"]["days"] == 4 and records["mallory"]["percent"] == 40
    # the same from the folder alone (no lms field): the name is read the same way
    records, _ = late_records([Submission("mallory", path)], subs, due, parse_policy(None), sheet)
    assert records["mallory"]["days"] == 4


def test_two_uploaders_claiming_one_id_never_quarantine_the_classmate(tmp_path):
    """Case 6: with a roster of bare IDs, two Canvas uploaders declaring victim1 quarantined
    both; Mallory's own file declares her ID, so only her extra upload is held."""
    subs = tmp_path / "subs"
    _notebook(subs / f"timvic_101_500_{NAME}.ipynb", "victim1")
    _notebook(subs / f"lorymal_102_900_{NAME}.ipynb", "mallory")
    _notebook(subs / "lorymal_102_950_anything.ipynb", "victim1")
    identity = _resolve(subs, _roster(tmp_path, "id\nvictim1\nmallory\n"))
    assert _graded(identity, "victim1") == f"timvic_101_500_{NAME}.ipynb"
    assert _graded(identity, "mallory") == f"lorymal_102_900_{NAME}.ipynb"
    assert not any(e.refused for e in identity.entries)
    assert [c[0] for c in identity.conflicts] == ["lorymal_102_950_anything.ipynb"]
    assert "the roster lists bare IDs" in identity.warning


def test_files_that_are_not_notebooks_are_said_against_their_student(tmp_path):
    subs = tmp_path / "subs"
    roster = _roster(tmp_path, CANVAS_ROSTER)
    (subs).mkdir()
    (subs / "timvic_101_500_report.html").write_text("<p>my answers</p>")
    _notebook(subs / "lorymal_102_900_hw.ipynb", "mallory")
    (subs / "lorymal_102_901_notes.txt").write_text("x")
    _notebook(subs / f"lorymal_102_950_{NAME}.ipynb", "mallory", "03_estimation_and_likelihood")
    identity = _resolve(subs, roster)
    victim = next(e for e in identity.entries if e.student == "victim1")
    assert victim.path is None and "handed in timvic_101_500_report.html, not a notebook" in (
        victim.note
    )
    mallory = next(e for e in identity.entries if e.student == "mallory")
    assert mallory.path.name == "lorymal_102_900_hw.ipynb"  # the other assignment's is refused
    assert "this is assignment 03's notebook" in mallory.note and "notes.txt" in mallory.note
    flags = "\n".join(identity.flags)
    assert "timvic_101_500_report.html (victim1): handed in" in flags
    assert f"lorymal_102_950_{NAME}.ipynb (mallory): this is assignment 03's notebook" in flags
    # only the other assignment's notebook: a refused row that says so
    (subs / "lorymal_102_900_hw.ipynb").unlink()
    mallory = next(e for e in _resolve(subs, roster).entries if e.student == "mallory")
    assert mallory.refused and mallory.path is None and "assignment 03's" in mallory.note


# -- file safety in a plain folder ---------------------------------------------------------------
class _Alarm:
    """Fail instead of hanging when an open blocks (the old code waited on a FIFO forever)."""

    def __enter__(self):
        def stop(signum, frame):
            raise TimeoutError("blocked on a file of the submissions")

        self.old = signal.signal(signal.SIGALRM, stop)
        signal.alarm(20)

    def __exit__(self, *exc):
        signal.alarm(0)
        signal.signal(signal.SIGALRM, self.old)


def _entry(found: list, student: str) -> Submission:
    return next(s for s in found if s.student == student)


def test_a_fifo_is_refused_without_being_opened(tmp_path):
    from course.grading.notebook import SubmissionError, read_notebook_bytes

    subs = tmp_path / "subs"
    (subs / "s2").mkdir(parents=True)
    os.mkfifo(subs / "s1.ipynb")
    os.mkfifo(subs / "s2" / f"{NAME}.ipynb")
    with _Alarm():
        found = find_submissions(subs, NAME)
        for sid in ("s1", "s2"):
            entry = _entry(found, sid)
            assert entry.refused and entry.path is None and "a FIFO" in entry.note, entry
        assert file_digest(subs / "s1.ipynb") is None
        with pytest.raises(SubmissionError, match="not a regular file"):
            read_notebook_bytes(subs / "s1.ipynb")


def test_a_hard_link_to_a_file_outside_the_folder_is_refused(tmp_path):
    secret = _notebook(tmp_path / "private" / "answers.ipynb", "s1")
    subs = tmp_path / "subs"
    subs.mkdir()
    os.link(secret, subs / "s1.ipynb")
    _notebook(subs / "s2.ipynb", "s2")
    os.link(subs / "s2.ipynb", subs / "s3.ipynb")  # two links, both inside: fine
    found = find_submissions(subs, NAME)
    s1 = _entry(found, "s1")
    assert s1.refused and s1.path is None
    assert "a hard link to a file outside the submissions folder" in s1.note
    assert _entry(found, "s2").path is not None and _entry(found, "s3").path is not None


def test_a_huge_sparse_file_is_refused_for_its_size_without_reading_it(tmp_path):
    subs = tmp_path / "subs"
    subs.mkdir()
    with open(subs / "s1.ipynb", "wb") as f:
        f.truncate(20 * 1024**3)  # 20 GB, no block written
    found = find_submissions(subs, NAME)
    s1 = _entry(found, "s1")
    assert s1.refused and s1.path is None and "larger than 50 MB (not read)" in s1.note
    with _Alarm():  # the digest looks at the size first: nothing is read
        assert file_digest(subs / "s1.ipynb") is None


def test_links_devices_and_empty_folders_in_a_folder(tmp_path):
    subs = tmp_path / "subs"
    (subs / "s1").mkdir(parents=True)
    (subs / "s2").mkdir()
    (subs / "_instructor").mkdir()
    target = _notebook(tmp_path / "elsewhere.ipynb", "s1")
    (subs / "s1" / f"{NAME}.ipynb").symlink_to(target)
    (subs / "s1" / "data").symlink_to(tmp_path, target_is_directory=True)
    found = find_submissions(subs, NAME)
    s1 = [s for s in found if s.student == "s1"]
    assert len(s1) == 2 and all(s.refused and "symbolic link" in s.note for s in s1)
    assert _entry(found, "s2").note == "no notebook (.ipynb) in the submission folder"
    assert not [s for s in found if s.student == "_instructor"]
    assert stat.S_ISLNK(os.lstat(subs / "s1" / "data").st_mode)  # listed, never followed


# -- the LMS's download archive ------------------------------------------------------------------
def _zip(path: Path, entries: dict, links: dict | None = None) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in entries.items():
            zf.writestr(name, data)
        for name, target in (links or {}).items():
            info = zipfile.ZipInfo(name)
            info.create_system = 3
            info.external_attr = (stat.S_IFLNK | 0o777) << 16
            zf.writestr(info, target)
    return path


def test_an_archive_is_unpacked_safely(tmp_path):
    nb = (_notebook(tmp_path / "nb.ipynb", "s1")).read_bytes()
    archive = _zip(
        tmp_path / "submissions.zip",
        {
            f"doejane_101_5001_{NAME}.ipynb": nb,
            "doejane_101_5002_report.html": b"<p>hi</p>",
            "../../escaped.ipynb": nb,
            "/etc/absolute.ipynb": nb,
            "a\\..\\..\\back.ipynb": nb,
            "Ann Roe_12_assignsubmission_file_/deep/er/work.ipynb": nb,
            "Ann Roe_12_assignsubmission_file_/data.csv": b"1,2",
            "__MACOSX/._x.ipynb": b"junk",
            "big_1_2_huge.ipynb": b"{" + b" " * (50_000_001),
        },
        links={"roeann_102_5003_link.ipynb": "/etc/passwd"},
    )
    dest = tmp_path / "out" / "unpacked"
    listed, escaped = unpack_archive(archive, dest)
    written = sorted(p.relative_to(dest).as_posix() for p in dest.rglob("*") if p.is_file())
    assert written == [
        "Ann Roe_12_assignsubmission_file_/deep/er/work.ipynb",
        f"doejane_101_5001_{NAME}.ipynb",
    ]
    assert not (tmp_path / "escaped.ipynb").exists() and len(escaped) == 3
    assert all("leaves the folder" in line for line in escaped)
    notes = {(s.lms, s.note) for s in listed}
    assert ("doejane_101_5002_report.html", "handed in doejane_101_5002_report.html, not a "
            "notebook (.ipynb)") in notes  # fmt: skip
    assert ("Ann Roe_12_assignsubmission_file_", "handed in data.csv, not a notebook (.ipynb)") in (
        notes
    )
    refused = {s.lms: s.note for s in listed if s.refused}
    assert "a symbolic link" in refused["roeann_102_5003_link.ipynb"]
    assert "larger than 50 MB" in refused["big_1_2_huge.ipynb"]
    # unpacked again from scratch: a rerun sees the same files
    assert unpack_archive(archive, dest)[0] == listed


def test_an_archive_beyond_its_budget_is_refused(tmp_path, monkeypatch):
    from course.grading.batch import intake

    archive = _zip(tmp_path / "many.zip", {f"s{i}.ipynb": b"{}" for i in range(20)})
    monkeypatch.setattr(intake, "MAX_ARCHIVE_ENTRIES", 10)
    with pytest.raises(intake.IntakeError, match="20 entries, more than 10"):
        unpack_archive(archive, tmp_path / "dest")
    monkeypatch.setattr(intake, "MAX_ARCHIVE_ENTRIES", 100)
    monkeypatch.setattr(intake, "MAX_ARCHIVE_BYTES", 30)
    with pytest.raises(intake.IntakeError, match="unpacks to more than 30 bytes"):
        unpack_archive(archive, tmp_path / "dest")
    (tmp_path / "not.zip").write_bytes(b"PK\x03\x04 not really")
    with pytest.raises(intake.IntakeError, match="cannot read the archive"):
        unpack_archive(tmp_path / "not.zip", tmp_path / "dest")


# -- feedback back through the LMS (issue 35 item 1) --------------------------------------------
def test_feedback_zips_are_named_as_each_lms_handed_the_files_out(tmp_path, capsys):
    from course.cli import main as course_main
    from course.grading.batch.lmsfeedback import feedback_html, feedback_name
    from course.grading.batch.reports import append_result
    from course.grading.batch.results import StudentResult

    out = tmp_path / "out"
    (out / "feedback").mkdir(parents=True)
    files = {
        "s001": f"doejane_101_5001_{NAME}.ipynb",
        "s002": f"roeann_LATE_102_5010_{NAME}-1.ipynb",
        "s003": f"Ed Poe_13_assignsubmission_file_/work/{NAME}.ipynb",
        "s004": None,  # quarantined: no graded file
        "s005": f"s005_{NAME}.ipynb",  # named by ID, not by an LMS
    }
    for sid, name in files.items():
        row = StudentResult(sid, NAME, "c" * 64, "1", "public", 14.0, total=7.0)
        row.record_file(None if name is None else {"name": name, "sha256": "0" * 64})
        append_result(row, out / "results.jsonl")
        (out / "feedback" / f"{sid}.md").write_text(
            f"# Feedback: {sid}\n\n- q1: <script>alert(1)</script> & more\n\n**Total: 7 / 14**\n"
        )
    assert course_main(["feedback", str(out), "--lms", "canvas"]) == 0
    printed = capsys.readouterr().out
    assert "feedback for 2 student(s)" in printed
    assert "s004: no graded file" in printed and "s005: its file was not named by Canvas" in printed
    with zipfile.ZipFile(out / "canvas_feedback.zip") as zf:
        assert sorted(zf.namelist()) == [
            f"doejane_101_5001_{NAME}.html",
            f"roeann_LATE_102_5010_{NAME}-1.html",
        ]
        page = zf.read(f"doejane_101_5001_{NAME}.html").decode()
    assert "<script>" not in page and "&lt;script&gt;alert(1)&lt;/script&gt; &amp; more" in page
    assert "<h1>Feedback: s001</h1>" in page
    assert course_main(["feedback", str(out), "--lms", "moodle"]) == 0
    with zipfile.ZipFile(out / "moodle_feedback.zip") as zf:
        assert zf.namelist() == ["Ed Poe_13_assignsubmission_file_/feedback.html"]
    # every name keeps the numbers the LMS reads from the name it handed out
    for sid in ("s001", "s002"):
        mine, theirs = canvas_name(feedback_name(files[sid], "canvas")), canvas_name(files[sid])
        assert (mine.number, mine.order, mine.late) == (theirs.number, theirs.order, theirs.late)
    flat = feedback_name("Ed Poe_13_assignsubmission_file_notebook.ipynb", "moodle")
    assert flat == "Ed Poe_13_assignsubmission_file_/feedback.html"
    assert feedback_name(f"doejane_101_5001_{NAME}.ipynb", "moodle") is None
    assert "<li>" in feedback_html("- a", "t") and "<p>x &lt; y</p>" in feedback_html("x < y", "t")
