"""Feedback back through the LMS: the zip each LMS's bulk feedback upload takes.

``course feedback OUT --lms canvas|moodle`` reads a grading output folder (``results.jsonl``
and ``feedback/<ID>.md``) and writes ``OUT/<lms>_feedback.zip``, one HTML page per graded
student (neither LMS renders Markdown; every text is escaped), named after the file the LMS
handed out, which the graded row records:

Canvas (*Assignment → Download Submissions*, then *Re-Upload Submissions*)
    ``<lastfirst>[_LATE]_<user number>_<submission number>_<uploaded name>.html``: the
    download's name with ``.html`` for its extension, so the user and submission numbers
    Canvas reads are those of the file it handed out; Canvas attaches each file as a comment
    to that submission.
Moodle (*View all submissions → Grading action: Upload multiple feedback files in a zip*)
    a folder per participant named as in the download
    (``Jane Doe_1234_assignsubmission_file_/feedback.html``); Moodle reads the participant
    number from it.

A student whose row is not a grade (quarantined, refused, not read, a grader fault) or whose
file the LMS did not name (a folder of ``<ID>.ipynb``) gets no file; :func:`write_feedback_zip`
says how many and why.
"""

from __future__ import annotations

import html
import zipfile
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath

from course.grading.batch.lmsnames import lms_name
from course.grading.batch.reports import read_results
from course.grading.batch.results import StudentResult
from course.grading.vocabulary import SubmissionStatus

__all__ = ["FeedbackZip", "feedback_html", "feedback_name", "write_feedback_zip"]

LMS_CHOICES = ("canvas", "moodle")
_NOT_GRADES = (
    SubmissionStatus.REFUSED,
    SubmissionStatus.GRADER_ERROR,
    SubmissionStatus.INVALID_NOTEBOOK,
)
_MAX_FEEDBACK_BYTES = 2_000_000  # our own feedback file; read no more than this


@dataclass
class FeedbackZip:
    """What :func:`write_feedback_zip` wrote: the zip, the names in it, the students left out
    (ID -> why)."""

    path: Path
    names: list[str] = field(default_factory=list)
    left_out: dict[str, str] = field(default_factory=dict)


def feedback_name(file_name: str, lms: str) -> str | None:
    """The name of a student's feedback in ``lms``'s upload zip, from the name of the file it
    handed out (``results.jsonl``'s ``file.name``: the path inside the download); None when
    that LMS did not name the file."""
    parts = PurePosixPath(file_name).parts
    if not parts:
        return None
    in_folder = len(parts) > 1
    name = lms_name(parts[0], "", folder=in_folder, moodle=lms == "moodle")
    if name.kind != lms:
        return None
    if lms == "canvas":
        return str(PurePosixPath(parts[0]).with_suffix(".html"))
    folder = parts[0] if in_folder else f"{name.person}_{name.number}_assignsubmission_file_"
    return f"{folder}/feedback.html"


def feedback_html(markdown: str, title: str) -> str:
    """A self-contained HTML page of a feedback file: headings, list items and paragraphs,
    every text escaped (student text inside stays text)."""
    body = []
    for line in markdown.splitlines():
        text = line.strip()
        if not text:
            continue
        level = len(text) - len(text.lstrip("#"))
        if 1 <= level <= 3 and text[level : level + 1] == " ":
            body.append(f"<h{level}>{html.escape(text[level + 1 :])}</h{level}>")
        elif text.startswith(("- ", "* ")):
            body.append(f"<ul><li>{html.escape(text[2:])}</li></ul>")
        else:
            body.append(f"<p>{html.escape(text)}</p>")
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{html.escape(title)}</title></head><body>\n"
        + "\n".join(body)
        + "\n</body></html>\n"
    )


def _place(row: StudentResult, out: Path, lms: str) -> tuple[str, Path] | str:
    """Where a student's feedback goes in the zip and the file it comes from, or why it is
    left out."""
    if row.status in _NOT_GRADES:
        return f"not graded ({row.status})"
    if not row.has_file or not row.file or not row.file.get("name"):
        return "no graded file (quarantined or nothing handed in)"
    name = feedback_name(str(row.file["name"]), lms)
    if name is None:
        return f"its file was not named by {lms.capitalize()}"
    source = out / "feedback" / f"{row.student}.md"
    if not source.is_file():
        return "no feedback file"
    return name, source


def write_feedback_zip(out: Path, lms: str) -> FeedbackZip:
    """Write ``out/<lms>_feedback.zip`` from the grading output folder ``out`` (see the module
    docstring)."""
    if lms not in LMS_CHOICES:
        raise ValueError(f"lms must be one of {', '.join(LMS_CHOICES)}, not {lms!r}")
    out = Path(out)
    rows = read_results(out / "results.jsonl")
    if not rows:
        raise ValueError(f"{out} holds no results.jsonl: grade the class first (course grade)")
    result = FeedbackZip(out / f"{lms}_feedback.zip")
    with zipfile.ZipFile(result.path, "w", zipfile.ZIP_DEFLATED) as zf:
        for sid in sorted(rows):
            place = _place(rows[sid], out, lms)
            if isinstance(place, str):
                result.left_out[sid] = place
                continue
            name, source = place
            with open(source, "rb") as f:
                text = f.read(_MAX_FEEDBACK_BYTES).decode("utf-8", errors="replace")
            zf.writestr(name, feedback_html(text, f"Feedback: {rows[sid].assignment}"))
            result.names.append(name)
    return result
