"""Whose submission is this? The student ID of each file, decided from the outside in.

The name the learning-management system (or the instructor) gave the file or folder decides
whose submission it is; the ID written inside the notebook only has to agree with it:

* a name that is an ID (``98765.ipynb``, a folder ``98765/``, or ``98765_<assignment>.ipynb``
  as ``check.submit()`` writes it), on the roster when there is one;
* with a roster, the one roster student the name points at: a roster student ID, Canvas user
  number or login as a token of the name (Canvas's ``doejohn_LATE_12345_67890_<file>``), or the
  full name of a Moodle folder (``John Doe_1234_assignsubmission_file_``), or the ``lastfirst``
  part of a Canvas name (so a roster without Canvas's user numbers still ties
  ``doejane_1234_5678_<file>`` to Jane Doe). An ID token wins over a name.

A notebook whose declared ID (its submission metadata, else ``STUDENT_ID``) is another roster
student's, or (without a roster) differs from the ID its name gives, is **quarantined**: graded
for nobody, reported with both IDs, and it never replaces another student's work. A declared ID
that is on no roster (a typo, ``s0O3`` for ``s003``) takes nobody's work: the file is graded
for the roster student its name gives, and reported (:attr:`Identity.attached`). A file whose
name gives no ID is graded under its declared ID, unless a named file claims that ID (then it
is quarantined) or files from different uploaders claim it (then all of them are). Among
several files of one student the LMS's order decides (Canvas's file number, then the name),
never a time written inside the notebook.

Every conflict (:attr:`Identity.conflicts`, with both names), every attached file and every
guess about the file that is graded becomes a line of the console summary
(:attr:`Identity.flags`); the driver also writes the conflicts and attached files to
``identity_conflicts.csv``. A file whose declared ID is on the roster and whose LMS name
points at nobody is flagged only when the roster could have named its uploader (Canvas user
numbers or names to compare): a roster of bare IDs gives nothing to check.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from course.grading.notebook import MAX_NOTEBOOK_BYTES
from course.grading.student.submit import saved_student_id
from course.grading.vocabulary import (
    CONTROL_CHARACTERS,
    DEMO_STUDENT_ID,
    PLACEHOLDER_ID,
    is_student_id,
    visible_text,
)

__all__ = ["Identity", "resolve_identities"]


@dataclass
class Identity:
    """The resolved submissions (:class:`~course.grading.batch.driver.Submission`, each with the
    student ID decided here) and the console's flags."""

    entries: list = field(default_factory=list)
    flags: list = field(default_factory=list)
    mismatched_keys: list = field(default_factory=list)  # files worked on other data
    # quarantined files: (file, the ID its name gives or "", the ID it declares, why)
    conflicts: list = field(default_factory=list)
    # files graded for the student their name gives although the notebook declares an ID on
    # no roster: (file, the ID its name gives, the ID it declares, why)
    attached: list = field(default_factory=list)


def _declared(path: Path | None) -> tuple[str | None, dict]:
    """The ID the notebook declares and its submission metadata (cheap, lenient)."""
    if path is None:
        return None, {}
    try:
        with open(path, "rb") as f:
            nb = json.loads(f.read(MAX_NOTEBOOK_BYTES).decode("utf-8", errors="replace"))
    except (OSError, ValueError, RecursionError):
        return None, {}
    if not isinstance(nb, dict):
        return None, {}
    meta: dict = nb["metadata"] if isinstance(nb.get("metadata"), dict) else {}
    course_meta: dict = meta["course"] if isinstance(meta.get("course"), dict) else {}
    sub: dict = course_meta["submission"] if isinstance(course_meta.get("submission"), dict) else {}
    sid = sub.get("student_id")
    if not (isinstance(sid, str) and is_student_id(sid)):
        try:
            sid = saved_student_id(nb)
        except Exception:  # a malformed notebook: the session reports it
            sid = None
    if not isinstance(sid, str):
        return None, sub
    sid = sid.strip()
    if sid in (PLACEHOLDER_ID, DEMO_STUDENT_ID) or not is_student_id(sid):
        return None, sub
    return sid, sub


def _name_id(name: str, assignment: str) -> str | None:
    """The ID a name is (``98765``, or ``98765_01_least_squares`` as submit() writes it)."""
    suffix = f"_{assignment}"
    if name.endswith(suffix):
        name = name[: -len(suffix)]
    return name if is_student_id(name) and assignment not in name else None


def _contains(name: str, sid: str) -> bool:
    return re.search(rf"(?<![A-Za-z0-9]){re.escape(sid)}(?![A-Za-z0-9])", name) is not None


def _safe_name(name: str) -> str:
    """A file name as a row's name: control and invisible characters and path signs become
    ``_``, so it is safe as a file name, a CSV cell and a console line."""
    return re.sub(r"[/\\]", "_", CONTROL_CHARACTERS.sub("_", name)).lstrip(".") or "_"


def _looks_bare(name_id: str) -> bool:
    """A single token (``98765``, ``s123``, ``jane.doe``): no sign of a name with extra text."""
    return re.fullmatch(r"[A-Za-z0-9.@-]+", name_id) is not None


# Canvas: "<lastfirst>[_LATE]_<user number>_<file number>_<uploaded name>"
_CANVAS = re.compile(r"^[^_]+(?:_[^_]+)*?_(?:LATE_)?(\d+)_(\d+)_", re.IGNORECASE)
# Moodle: "<Full Name>_<participant number>_assignsubmission_<plugin>_"
_MOODLE = re.compile(r"^(.+?)_(\d+)_assignsubmission_", re.IGNORECASE)


def _uploader(name: str) -> str:
    """Who uploaded the file, as the LMS names them (Canvas user, Moodle participant)."""
    for pattern, lms in ((_MOODLE, "moodle"), (_CANVAS, "canvas")):
        m = pattern.match(name)
        if m:
            return f"{lms}:{m.group(2) if lms == 'moodle' else m.group(1)}"
    return f"name:{name}"


def _lms_order(name: str) -> tuple[int, str]:
    """The LMS's order of one student's files: Canvas's file number (later uploads have larger
    numbers), then the name."""
    m = _CANVAS.match(name)
    return (int(m.group(2)) if m else 0, name)


def _full_name(text: str) -> str:
    return " ".join(text.casefold().split())


# Canvas's "lastfirst": the sortable name, lower case, letters and digits only
_CANVAS_NAME = re.compile(r"^([^_]+)_(?:LATE_)?\d+_\d+_")


def _letters(text: str) -> str:
    return re.sub(r"[\W_]", "", text.casefold())


def _last_first(student) -> set[str]:
    """The ``lastfirst`` forms Canvas could have made of a roster student's name."""
    out = {_letters(student.last + student.first)}
    if "," in student.name:
        last, first = student.name.split(",", 1)
        out.add(_letters(last + first))
    elif student.name:
        first, _, last = student.name.strip().rpartition(" ")
        out.add(_letters(last + first))
    out.discard("")
    return out


def _roster_named(names: list[str], roster: list) -> list[str]:
    """The roster IDs a file or folder name points at: an ID, Canvas user number or login as a
    token; else a Moodle folder's full name or a Canvas name's ``lastfirst``."""
    by_token = {
        s.id
        for s in roster
        if any(_contains(n, t) for n in names for t in (s.id, s.canvas_id, s.login) if t)
    }
    if by_token:
        return sorted(by_token)
    hits = set()
    for student in roster:
        full = {_full_name(f"{student.first} {student.last}"), _full_name(student.name)}
        if student.name and "," in student.name:
            last, first = student.name.split(",", 1)
            full.add(_full_name(f"{first} {last}"))
        full.discard("")
        for n in names:
            m = _MOODLE.match(n)
            if m and _full_name(m.group(1)) in full:
                hits.add(student.id)
            c = _CANVAS_NAME.match(n)
            if c and _letters(c.group(1)) in _last_first(student):
                hits.add(student.id)
    return sorted(hits)


def _names_uploaders(roster: list) -> bool:
    """Whether the roster can tell who uploaded an LMS file (Canvas user numbers or names)."""
    return any(s.canvas_id or s.name or s.first or s.last for s in roster)


def _duplicate_rule(claims: list) -> str:
    """The rule that picked one student's file among several, in words."""
    numbered = [c.order[0] > 0 for c in claims]
    if all(numbered):
        return (
            "the last in the LMS's order: the highest Canvas submission number, its latest upload"
        )
    if not any(numbered):
        return "the last in the LMS's order: by file name"
    return "the last in the LMS's order: Canvas's submission number, then the file name"


@dataclass
class _Claim:
    shown: str  # the file (or folder) name as the report shows it
    sub: Any
    named: bool  # the LMS name gave this ID (else only the notebook declares it)
    uploader: str
    order: tuple[int, str]
    flag: str = ""  # a doubt about this file, told when it is the file graded


def resolve_identities(
    entries: list, assignment: str, roster_ids=None, data_key: str | None = None
) -> Identity:
    """Decide the student ID of every submission (``.student`` is its name in the folder).

    ``roster_ids`` are the roster's IDs, or its :class:`~course.grading.batch.roster.Student`
    rows (then Canvas user numbers, logins and Moodle full names name students too). See the
    module docstring for the rules; every quarantine and guess is flagged.
    """
    students = [r for r in (roster_ids or ()) if not isinstance(r, str)]
    roster = {r if isinstance(r, str) else r.id for r in (roster_ids or ())}
    out = Identity()
    claimed: dict[str, list[_Claim]] = {}
    held: dict[str, Any] = {}  # a quarantined file of each ID its name gave

    def quarantine(shown: str, named: str | None, declared: str, why: str) -> None:
        out.conflicts.append((shown, named or "", declared, why))
        out.flags.append(f"QUARANTINED {shown}: {why}")

    for sub in entries:
        name, path = sub.student, sub.path
        if path is None:  # refused or empty: nothing to read, the name stays
            key = name if is_student_id(name) else _safe_name(name)
            claimed.setdefault(key, []).append(_Claim(key, sub, True, f"name:{name}", (0, name)))
            continue
        shown = path.name if path.stem == name else name
        # the file's own name inside an LMS's folder is the uploader's choice, not the LMS's
        inner = path.stem != name and _MOODLE.match(name) is None
        names = [name] + ([path.stem] if inner else [])
        name_id = next((c for c in (_name_id(n, assignment) for n in names) if c), None)
        if name_id is not None and roster and name_id not in roster:
            name_id = None
        if name_id is None and roster:
            in_name = _roster_named(names, students) if students else []
            if not students:
                in_name = sorted({r for r in roster if any(_contains(n, r) for n in names)})
            name_id = in_name[0] if len(in_name) == 1 else None
        declared, meta = _declared(path)
        named, flag = True, ""
        if declared is not None and (
            declared == name_id or any(_contains(n, declared) for n in names)
        ):
            sid = declared
        elif declared is not None and name_id is not None and roster and declared not in roster:
            # an ID on no roster takes nobody's work: the LMS's name decides, and it is told
            sid = name_id
            why = (
                f"the notebook declares STUDENT_ID {declared!r}, which is not on the roster; "
                f"graded as {name_id!r}, the roster student its name points at (check the "
                "notebook's ID)"
            )
            out.attached.append((shown, name_id, declared, why))
            flag = f"{shown}: {why}"
            note = (
                f"Your notebook's STUDENT_ID {declared!r} is not on the class list; this file "
                f"was graded as {name_id!r}, the student its file name gives. Set the right "
                "STUDENT_ID next time."
            )
            sub = replace(sub, note=f"{sub.note} {note}" if sub.note else note)
        elif declared is not None and name_id is not None:
            quarantine(
                shown,
                name_id,
                declared,
                f"its name makes it {name_id!r}'s submission but the notebook declares "
                f"STUDENT_ID {declared!r}; graded for nobody (fix the notebook's ID, or rename "
                "the file to the right ID, and grade again)",
            )
            claimed.setdefault(name_id, [])
            held.setdefault(name_id, sub)
            continue
        elif declared is not None:
            sid, named = declared, False
            lms_named = _CANVAS.match(name) is not None or _MOODLE.match(name) is not None
            if not (roster and declared in roster and lms_named and not _names_uploaders(students)):
                flag = (
                    f"{shown}: the file name "
                    + (
                        "points at no roster student"
                        if roster and lms_named
                        else "does not contain the notebook's STUDENT_ID"
                    )
                    + f"; graded as {declared!r}, the notebook's STUDENT_ID"
                )
        elif name_id is not None:
            sid = name_id
            if name_id not in roster and not _looks_bare(name_id):
                flag = (
                    f"{shown}: no student ID in the notebook; graded under its file name "
                    f"{name_id!r} (rename it to <ID>.ipynb and grade again if that is wrong)"
                )
            elif name_id in roster and name_id not in names and name_id != name:
                flag = (
                    f"{shown}: the notebook has no student ID; graded as {name_id!r}, the "
                    "roster student its name points at"
                )
        else:
            sid = name_id or _safe_name(name)
            flag = (
                f"{shown}: no student ID in the notebook, and the file name is not "
                f"{'a roster ID' if roster else 'an ID'}; graded as {sid!r} "
                "(rename it to <ID>.ipynb and grade again)"
            )
        if data_key is not None and meta.get("data_key") not in (None, data_key):
            out.mismatched_keys.append(shown)
        claimed.setdefault(sid, []).append(
            _Claim(shown, sub, named, _uploader(name), _lms_order(name), flag)
        )
    for sid in sorted(claimed):
        claims = claimed[sid]
        if not claims:  # every file its name gave was quarantined: the row says so
            why = "; ".join(c[0] for c in out.conflicts if c[1] == sid)
            note = f"the submission was quarantined: it declares another student's ID ({why})"
            out.entries.append(_refused(held[sid], sid, note))
            continue
        by_name = [c for c in claims if c.named]
        if by_name:
            for c in claims:
                if not c.named:
                    quarantine(
                        c.shown,
                        "",
                        sid,
                        f"the notebook declares STUDENT_ID {sid!r}, but {sid!r} has its own "
                        f"submission ({by_name[0].shown}); graded for nobody",
                    )
            claims = by_name
        elif len({c.uploader for c in claims}) > 1:
            for c in claims:
                quarantine(
                    c.shown,
                    "",
                    sid,
                    f"{len(claims)} files from different uploaders declare STUDENT_ID {sid!r} "
                    f"({', '.join(x.shown for x in claims)}); none is graded (give a --roster "
                    "so that the LMS names decide)",
                )
            out.entries.append(
                _refused(
                    claims[0].sub,
                    sid,
                    "the submission was quarantined: files from several uploaders claim this ID",
                )
            )
            continue
        claims.sort(key=lambda c: c.order)
        if claims[-1].flag:  # doubts about files not graded would be noise
            out.flags.append(claims[-1].flag)
        if len(claims) > 1:
            out.flags.append(
                f"{len(claims)} submissions claim the ID {sid!r}: "
                + ", ".join(c.shown for c in claims)
                + f"; graded {claims[-1].shown} ({_duplicate_rule(claims)})"
            )
        out.entries.append(replace(claims[-1].sub, student=sid))
    out.flags = [visible_text(f) for f in out.flags]  # file names reach the console
    if out.mismatched_keys:
        out.flags.append(
            f"{len(out.mismatched_keys)} submission(s) were worked on personal data issued with "
            f"another key than this run's ({data_key}): "
            + ", ".join(visible_text(k) for k in out.mismatched_keys[:5])
            + (" …" if len(out.mismatched_keys) > 5 else "")
            + "; grade with the class's --secret, or their personal questions score 0"
        )
    return out


def _refused(sub, sid: str, note: str):
    """A row for ``sid`` that grades nothing and says why (``sub`` is a Submission)."""
    return replace(sub, student=sid, path=None, note=note, refused=True)
