"""The names learning-management systems give the files they hand out, each read by its own
grammar.

Who uploaded a file is written by the LMS in the name it gives the download, next to a part the
student chose. Each parser below reads only the LMS's part, from the side the student cannot
reach, so no file name a student picks can make the file another student's:

Canvas (``Download Submissions``)
    ``<lastfirst>[_LATE]_<user number>_<submission number>_<the name the student uploaded>``,
    read from the front: ``lastfirst`` is Canvas's sortable name without punctuation (no
    ``_``), then the two numbers; the uploaded name is never read.
Moodle (``Download all submissions``, in folders)
    a folder ``<Full Name>_<participant number>_assignsubmission_<plugin>_`` read from the end
    (the full name may hold anything, ``_12_assignsubmission_file_`` included); a flat file
    ``<Full Name>_<participant>_assignsubmission_file_<uploaded name>`` only when the marker
    occurs once, since both sides around it may be anyone's text.
An ID
    ``98765.ipynb``, a folder ``98765/`` or ``98765_<assignment>.ipynb`` (as ``check.submit()``
    writes it): names an instructor or ``check.submit()`` gave.

Every other name is ``"other"``: it identifies nobody (see :mod:`course.grading.batch.identity`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from course.grading.vocabulary import is_student_id

__all__ = ["LmsName", "canvas_name", "download_kind", "lms_name", "moodle_name", "plain_id"]


@dataclass(frozen=True)
class LmsName:
    """What an LMS's name of a file or folder says: its grammar (``kind``: ``"canvas"``,
    ``"moodle"``, ``"id"`` or ``"other"``), the uploader as that LMS knows them (``number``:
    Canvas's user number, Moodle's participant number, the ID of an ID name), the person's name
    as the LMS wrote it, Canvas's submission number (its order of one student's uploads) and
    Canvas's ``_LATE_`` marker."""

    kind: str
    number: str = ""
    person: str = ""
    order: int = 0
    late: bool = False

    @property
    def uploader(self) -> str:
        """A key of the uploader, unique across grammars (``canvas:123``)."""
        return f"{self.kind}:{self.number or self.person}"


_CANVAS = re.compile(r"([^_]+)(_LATE|_late)?_(\d+)_(\d+)_(.+)", re.DOTALL)
_MOODLE_FOLDER = re.compile(r"(.*)_(\d+)_assignsubmission_[^_]+_", re.DOTALL)
_MOODLE_MARK = re.compile(r"_(\d+)_assignsubmission_file_")


def canvas_name(name: str) -> LmsName | None:
    """A Canvas download name, or None (``doejane_LATE_101_5001_x.ipynb``: user 101, 5001)."""
    m = _CANVAS.fullmatch(name)
    if m is None:
        return None
    return LmsName("canvas", m.group(3), m.group(1), int(m.group(4)), m.group(2) is not None)


def moodle_name(name: str) -> LmsName | None:
    """A Moodle folder name (participant number read from the end), or a flat Moodle file name
    whose marker ``_<n>_assignsubmission_file_`` occurs exactly once; else None."""
    m = _MOODLE_FOLDER.fullmatch(name)
    if m is not None:
        return LmsName("moodle", m.group(2), m.group(1))
    marks = list(_MOODLE_MARK.finditer(name))
    if len(marks) == 1 and marks[0].start() > 0:
        return LmsName("moodle", marks[0].group(1), name[: marks[0].start()])
    return None


def plain_id(stem: str, assignment: str) -> str | None:
    """The ID a name is: ``98765``, or ``98765_<assignment>`` as ``check.submit()`` writes it."""
    suffix = f"_{assignment}"
    if stem.endswith(suffix) and len(stem) > len(suffix):
        stem = stem[: -len(suffix)]
    return stem if is_student_id(stem) and assignment not in stem else None


def lms_name(name: str, assignment: str, folder: bool = False, moodle: bool = False) -> LmsName:
    """The grammar a file's or folder's name (as the LMS wrote it, extension included) follows:
    a folder is Moodle's or an ID; a file Canvas's or Moodle's (``moodle``: the download is
    Moodle's, so its grammar is tried first, see :func:`download_kind`), else an ID;
    ``"other"`` when none."""
    if folder:
        found = moodle_name(name) if _MOODLE_FOLDER.fullmatch(name) else None
    elif moodle:
        found = moodle_name(name) or canvas_name(name)
    else:
        found = canvas_name(name) or moodle_name(name)
    if found is not None:
        return found
    stem = name if folder or "." not in name[1:] else name.rsplit(".", 1)[0]
    sid = plain_id(stem, assignment)
    return LmsName("id", sid) if sid is not None else LmsName("other", person=name)


def download_kind(names: list[str], folders: list[str]) -> str:
    """Whose download a folder holds: ``"moodle"`` when more of its names follow Moodle's
    grammar than Canvas's (so one student's upload named like the other LMS cannot change how
    a classmate's name is read), else ``"canvas"``."""
    moodle = sum(_MOODLE_FOLDER.fullmatch(n) is not None for n in folders)
    moodle += sum(moodle_name(n) is not None for n in names)
    canvas = sum(canvas_name(n) is not None for n in names)
    return "moodle" if moodle > canvas else "canvas"
