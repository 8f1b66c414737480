"""Whose submission is this? Decided by the LMS's own grammar for where it put the file, never
by a name the student chose or by what the notebook says of itself.

Each file's name is read by its LMS's grammar (:mod:`course.grading.batch.lmsnames`): Canvas's
user number and submission number, Moodle's participant number, or a name that is an ID
(``98765.ipynb``, ``98765_<assignment>.ipynb``). The part of a name the student chose (the
uploaded file's own name) is never read.

**A roster that knows the uploaders** (Canvas's gradebook export with its user numbers, a
Moodle grading worksheet with participant numbers, or names the LMS writes: Canvas's
``lastfirst``, Moodle's full name, each matching exactly one roster student) decides: every
file is its uploader's. A notebook declaring another ID (its submission metadata, else
``STUDENT_ID``) is still graded for its uploader, reported with both IDs
(:attr:`Identity.attached`, ``identity_conflicts.csv``) and the student is told; it never
reaches the declared student, so an extra upload cannot displace or quarantine a classmate.

**Without one** (no roster, or a roster of bare IDs, which gets one warning at the start when
the files are named by an LMS: :attr:`Identity.warning`), a file named by an ID is that ID's;
every other file claims the ID its notebook declares, one uploader (the LMS's user or
participant number) at a time: a claim on an ID that a name gives, or that another uploader
claims while this uploader has an ID of its own, is not graded and is reported
(:attr:`Identity.conflicts`); only when several uploaders each claim nothing but the same ID
is nothing graded for it (a row says why: give a roster).

Among one student's files the gradable notebooks come first (not a link, not another
assignment's notebook, not a ``report.html``), then the ones whose declared ID agrees, then
the LMS's order (Canvas's submission number, then the name), never a time written inside the
notebook. Every file not graded is named against its student in the console summary
(:attr:`Identity.flags`), and a student with no gradable file gets a row that says why.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from course.grading.batch.lmsnames import LmsName, download_kind, lms_name
from course.grading.notebook import MAX_NOTEBOOK_BYTES
from course.grading.student.submit import saved_student_id
from course.grading.vocabulary import (
    CONTROL_CHARACTERS,
    DEMO_STUDENT_ID,
    PLACEHOLDER_ID,
    is_student_id,
    visible_text,
)

__all__ = ["Identity", "declared_in", "resolve_identities"]


@dataclass
class Identity:
    """The resolved submissions (:class:`~course.grading.batch.intake.Submission`, one per
    student, with the student ID decided here) and the console's flags."""

    entries: list = field(default_factory=list)
    flags: list = field(default_factory=list)
    mismatched_keys: list = field(default_factory=list)  # files worked on other data
    # files graded for nobody: (file, the ID its name gives or "", the ID it declares, why)
    conflicts: list = field(default_factory=list)
    # files graded for their uploader although the notebook declares another ID:
    # (file, the uploader's ID, the ID it declares, why)
    attached: list = field(default_factory=list)
    warning: str = ""  # said once at the start: nothing tells who uploaded the LMS's files


def _declared(path: Path | None) -> tuple[str | None, dict]:
    """The ID the notebook at ``path`` declares and its submission metadata, decoded here
    (for tools and tests; the batch reads each file in a sandboxed child instead,
    :meth:`~course.grading.batch.session.AssignmentGrader.declared_id`)."""
    if path is None:
        return None, {}
    try:
        with open(path, "rb") as f:
            nb = json.loads(f.read(MAX_NOTEBOOK_BYTES).decode("utf-8", errors="replace"))
    except (OSError, ValueError, RecursionError):
        return None, {}
    return declared_in(nb)


def declared_in(nb) -> tuple[str | None, dict]:
    """The ID a decoded notebook declares (its submission metadata, else ``STUDENT_ID``) and
    its submission metadata with the ``assignment`` the notebook names (cheap, lenient)."""
    if not isinstance(nb, dict):
        return None, {}
    meta: dict = nb["metadata"] if isinstance(nb.get("metadata"), dict) else {}
    course_meta: dict = meta["course"] if isinstance(meta.get("course"), dict) else {}
    sub: dict = course_meta["submission"] if isinstance(course_meta.get("submission"), dict) else {}
    info = dict(sub)
    if isinstance(course_meta.get("assignment"), str):
        info["assignment"] = course_meta["assignment"]
    sid = sub.get("student_id")
    if not (isinstance(sid, str) and is_student_id(sid)):
        try:
            sid = saved_student_id(nb)
        except Exception:  # a malformed notebook: the session reports it
            sid = None
    if not isinstance(sid, str):
        return None, info
    sid = sid.strip()
    if sid in (PLACEHOLDER_ID, DEMO_STUDENT_ID) or not is_student_id(sid):
        return None, info
    return sid, info


def _contains(name: str, sid: str) -> bool:
    """``sid`` is a whole token of ``name`` (``s123`` is not in ``s1234``)."""
    return re.search(rf"(?<![A-Za-z0-9]){re.escape(sid)}(?![A-Za-z0-9])", name) is not None


def _safe_name(name: str) -> str:
    """A file name as a row's name: control and invisible characters and path signs become
    ``_``, so it is safe as a file name, a CSV cell and a console line."""
    return re.sub(r"[/\\]", "_", CONTROL_CHARACTERS.sub("_", name)).lstrip(".") or "_"


def _looks_bare(name_id: str) -> bool:
    """A single token (``98765``, ``s123``, ``jane.doe``): no sign of a name with extra text."""
    return re.fullmatch(r"[A-Za-z0-9.@-]+", name_id) is not None


def _full_name(text: str) -> str:
    return " ".join(text.casefold().split())


def _letters(text: str) -> str:
    return re.sub(r"[\W_]", "", text.casefold())


def _full_names(student) -> set[str]:
    """The full names Moodle could have written of a roster student."""
    out = {_full_name(f"{student.first} {student.last}"), _full_name(student.name)}
    if "," in student.name:
        last, first = student.name.split(",", 1)
        out.add(_full_name(f"{first} {last}"))
    out.discard("")
    return out


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


def _unique(pairs) -> dict[str, str]:
    """``{key: id}`` of the keys that name exactly one student."""
    seen: dict[str, set[str]] = {}
    for key, sid in pairs:
        if key:
            seen.setdefault(key, set()).add(sid)
    return {key: next(iter(ids)) for key, ids in seen.items() if len(ids) == 1}


class _Directory:
    """Who each LMS name belongs to, as far as the roster can tell."""

    def __init__(self, roster_ids) -> None:
        students = [r for r in (roster_ids or ()) if not isinstance(r, str)]
        self.given = roster_ids is not None
        self.ids = {r if isinstance(r, str) else r.id for r in (roster_ids or ())}
        self.canvas = _unique((s.canvas_id, s.id) for s in students)
        self.participants = _unique((s.participant, s.id) for s in students)
        self.full = _unique((n, s.id) for s in students for n in _full_names(s))
        self.lastfirst = _unique((n, s.id) for s in students for n in _last_first(s))

    @property
    def knows_uploaders(self) -> bool:
        return bool(self.canvas or self.participants or self.full or self.lastfirst)

    def owner(self, name: LmsName) -> str | None:
        """The roster student who uploaded the file so named (an ID name: that ID)."""
        if name.kind == "canvas":
            return self.canvas.get(name.number) or self.lastfirst.get(_letters(name.person))
        if name.kind == "moodle":
            return self.participants.get(name.number) or self.full.get(_full_name(name.person))
        if name.kind == "id" and (not self.given or name.number in self.ids):
            return name.number
        return None


@dataclass
class _Candidate:
    """One file and what is known of it: its LMS name, the ID it declares, its owner (the
    student its LMS name gives) and the ID it is finally attributed to."""

    sub: Any
    name: LmsName
    shown: str
    declared: str | None
    meta: dict
    why_not: str = ""  # not gradable although it is a notebook (another assignment's)
    owner: str | None = None
    sid: str | None = None
    doubt: str = ""  # a line for the console when this file is the one graded

    @property
    def gradable(self) -> bool:
        return self.sub.path is not None and not self.why_not

    def key(self) -> tuple:
        preferred = self.sub.path is not None and self.sub.path.stem == self.sub.student
        agrees = self.declared is None or self.declared == self.sid
        return (self.gradable, agrees, self.name.order, preferred, self.shown)


def _another_assignment(meta: dict, assignment: str) -> str:
    other = meta.get("assignment")
    if not isinstance(other, str) or other == assignment:
        return ""
    other = visible_text(other[:80])
    number = other.split("_", 1)[0]
    return (
        f"this is assignment {number}'s notebook ({other}), not {assignment}'s; hand in the "
        f"notebook of {assignment}"
    )


def _candidate(sub, assignment: str, moodle: bool, read, directory: _Directory) -> _Candidate:
    in_folder = sub.in_folder if sub.lms else sub.path is not None and sub.path.stem != sub.student
    lms = sub.lms or (sub.path.name if sub.path is not None and not in_folder else sub.student)
    name = lms_name(lms, assignment, folder=in_folder, moodle=moodle)
    shown = lms
    if in_folder and sub.path is not None:
        shown = f"{lms}/{sub.path.name}"
    declared, meta = read(sub.path) if sub.path is not None else (None, {})
    c = _Candidate(sub, name, shown, declared, meta, _another_assignment(meta, assignment))
    c.owner = directory.owner(name)
    stem = Path(lms).stem if not in_folder else lms
    if name.kind in ("id", "other") and declared is not None and _contains(stem, declared):
        c.owner = declared  # a name the notebook agrees with (``late_44444.ipynb``)
    return c


class _Resolver:
    """The rules of the module docstring, applied to every candidate file."""

    def __init__(self, cands: list[_Candidate], directory: _Directory, out: Identity):
        self.cands, self.directory, self.out = cands, directory, out

    def quarantine(self, c: _Candidate, named: str, why: str) -> None:
        c.sid = None
        self.out.conflicts.append((c.shown, named, c.declared or "", why))
        self.out.flags.append(f"QUARANTINED {c.shown}: {why}")

    def bind(self) -> None:
        """The owner of each named file; for the others, the ID their notebook declares,
        uploader by uploader (see the module docstring)."""
        for c in self.cands:
            c.sid = c.owner
        taken = {c.owner: c for c in self.cands if c.owner is not None}
        claims: dict[str, set[str]] = {}
        for c in self._unowned():
            if c.declared in taken:
                self.quarantine(
                    c,
                    "",
                    f"the notebook declares STUDENT_ID {c.declared!r}, but {c.declared!r} has "
                    f"its own submission ({taken[c.declared].shown}); graded for nobody",
                )
            elif c.declared is not None:
                claims.setdefault(c.declared, set()).add(c.name.uploader)
        own: dict[str, set[str]] = {}
        for sid, uploaders in claims.items():
            if len(uploaders) == 1:
                own.setdefault(next(iter(uploaders)), set()).add(sid)
        for sid, uploaders in sorted(claims.items()):
            self._settle(sid, uploaders, own)
        self._attach_the_rest(own)

    def _unowned(self) -> list[_Candidate]:
        return [c for c in self.cands if c.owner is None and c.gradable]

    def _settle(self, sid: str, uploaders: set[str], own: dict) -> None:
        """Who of the uploaders declaring ``sid`` gets it: the one without an ID of its own."""
        mine = [c for c in self._unowned() if c.declared == sid]
        keep = {u for u in uploaders if len(uploaders) == 1 or not own.get(u)}
        for c in mine:
            if c.name.uploader not in keep:
                theirs = ", ".join(sorted(own[c.name.uploader]))
                self.quarantine(
                    c,
                    "",
                    f"the notebook declares STUDENT_ID {sid!r}, which files of another uploader "
                    f"declare too, while its uploader's own files declare {theirs!r}; graded "
                    "for nobody",
                )
            elif len(keep) > 1:
                self.quarantine(
                    c,
                    "",
                    f"{len(keep)} uploaders declare STUDENT_ID {sid!r} and none of them another "
                    "ID: nothing tells whose it is (give the LMS's roster export as --roster "
                    "so that the uploader decides)",
                )
            else:
                c.sid = sid
                own.setdefault(c.name.uploader, set()).add(sid)
        if len(keep) > 1:
            note = "the submission was quarantined: files from several uploaders claim this ID"
            self.out.entries.append(replace(mine[0].sub, student=sid, path=None, note=note))
            self.out.entries[-1] = replace(self.out.entries[-1], refused=True)

    def _attach_the_rest(self, own: dict) -> None:
        """Files without a usable declared ID (a report.html, a link, an unset STUDENT_ID):
        their uploader's ID, when the uploader has exactly one; else their name."""
        no_roster = not self.directory.given
        for c in self.cands:
            if c.sid is not None or c.owner is not None:
                continue
            if c.gradable and c.declared is not None:
                continue  # quarantined above
            ids = own.get(c.name.uploader, set())
            if len(ids) == 1:
                c.sid = next(iter(ids))
                continue
            c.sid = _safe_name(c.sub.student)
            if c.gradable:
                c.doubt = (
                    f"{c.shown}: no student ID in the notebook, and the file name is not "
                    f"{'an ID' if no_roster else 'a roster ID'}; graded as {c.sid!r} "
                    "(rename it to <ID>.ipynb and grade again)"
                )


def _mismatch(c: _Candidate, directory: _Directory, out: Identity) -> Any:
    """Tell (console, conflicts file, student) that the graded file declares another ID."""
    sid, declared = c.sid, c.declared
    if directory.given and declared not in directory.ids:
        why = (
            f"the notebook declares STUDENT_ID {declared!r}, which is not on the roster; "
            f"graded as {sid!r}, the roster student its name points at (check the notebook's ID)"
        )
        note = (
            f"Your notebook's STUDENT_ID {declared!r} is not on the class list; this file was "
            f"graded as {sid!r}, the student its file name gives. Set the right STUDENT_ID "
            "next time."
        )
    else:
        why = (
            f"the notebook declares STUDENT_ID {declared!r}, but its name makes it {sid!r}'s "
            f"submission; graded as {sid!r}, never as the ID a notebook declares"
        )
        note = (
            f"Your notebook's STUDENT_ID is {declared!r}, but this file was handed in as "
            f"{sid!r}'s: it was graded as {sid!r}'s. Set your own STUDENT_ID next time."
        )
    out.attached.append((c.shown, sid, declared, why))
    c.doubt = f"{c.shown}: {why}"
    return replace(c.sub, note=f"{c.sub.note} {note}" if c.sub.note else note)


def _unnamed_doubt(c: _Candidate, directory: _Directory) -> str:
    """A line about a file graded under the ID its notebook declares (no name gave one)."""
    if c.name.kind in ("canvas", "moodle"):
        if not directory.knows_uploaders:
            return ""  # the warning at the start says it once for all
        where = "points at no roster student"
    else:
        where = "is not an LMS's name or an ID"
    return f"{c.shown}: the file name {where}; graded as {c.sid!r}, the notebook's STUDENT_ID"


def _duplicate_rule(claims: list[_Candidate]) -> str:
    """The rule that picked one student's file among several, in words."""
    numbered = [c.name.order > 0 for c in claims]
    if all(numbered):
        return (
            "the last in the LMS's order: the highest Canvas submission number, its latest upload"
        )
    if not any(numbered):
        return "the last in the LMS's order: by file name"
    return "the last in the LMS's order: Canvas's submission number, then the file name"


def _doubt(best: _Candidate, sid: str, directory: _Directory, out: Identity):
    """The graded file's submission, with a note when its notebook declares another ID; the
    console's line about any doubt on it."""
    sub = best.sub
    if best.declared not in (None, sid):
        sub = _mismatch(best, directory, out)
    elif best.owner is None and not best.doubt:
        best.doubt = _unnamed_doubt(best, directory)
    elif best.name.kind == "id" and not _looks_bare(sid) and not best.declared:
        best.doubt = (
            f"{best.shown}: no student ID in the notebook; graded under its file name {sid!r} "
            "(rename it to <ID>.ipynb and grade again if that is wrong)"
        )
    if best.doubt:
        out.flags.append(best.doubt)
    return sub


def _choose(sid: str, group: list[_Candidate], directory: _Directory, out: Identity):
    """The one submission of ``sid`` among its files, and the console's lines about the
    others (files not graded, several notebooks)."""
    group.sort(key=_Candidate.key)
    best = group[-1]
    notebooks = [c for c in group if c.gradable]
    if len(notebooks) > 1:
        out.flags.append(
            f"{len(notebooks)} submissions claim the ID {sid!r}: "
            + ", ".join(c.shown for c in notebooks)
            + f"; graded {best.shown} ({_duplicate_rule(notebooks)})"
        )
    unfit = [(c, _unfit_note(c)) for c in group if not c.gradable]
    out.flags.extend(f"{c.shown} ({sid}): {note}" for c, note in unfit)
    notes = "; ".join(note for _, note in unfit)
    if not best.gradable:
        refused = best.sub.refused or bool(best.why_not)
        return replace(best.sub, student=sid, path=None, note=notes, refused=refused)
    sub = _doubt(best, sid, directory, out)
    if unfit:
        also = f"also {notes} (not graded)"
        sub = replace(sub, note=f"{sub.note} {also}" if sub.note else also)
    return replace(sub, student=sid)


def _unfit_note(c: _Candidate) -> str:
    return c.why_not or c.sub.note or "nothing to grade"


def _warning(cands: list[_Candidate], directory: _Directory) -> str:
    lms = [c for c in cands if c.name.kind in ("canvas", "moodle")]
    if not lms or directory.knows_uploaders:
        return ""
    who = "the roster lists bare IDs" if directory.given else "there is no --roster"
    return (
        f"WARNING: {len(lms)} file(s) are named by an LMS, but {who}: nothing tells which "
        "student uploaded which file, so each is graded under the STUDENT_ID its notebook "
        "declares. Pass the LMS's own export as --roster (Canvas: the gradebook export with its "
        "ID column; Moodle: the grading worksheet, or a roster with the students' names) so "
        "that the uploader decides."
    )


def _finish_flags(out: Identity, data_key: str | None) -> None:
    """The console's lines made safe to print, the warning first, the key mismatches last."""
    out.flags = [visible_text(f) for f in out.flags]  # file names reach the console
    if out.warning:
        out.flags.insert(0, out.warning)
    if out.mismatched_keys:
        out.flags.append(
            f"{len(out.mismatched_keys)} submission(s) were worked on personal data issued with "
            f"another key than this run's ({data_key}): "
            + ", ".join(visible_text(k) for k in out.mismatched_keys[:5])
            + (" …" if len(out.mismatched_keys) > 5 else "")
            + "; grade with the class's --secret, or their personal questions score 0"
        )


def resolve_identities(
    entries: list,
    assignment: str,
    roster_ids=None,
    data_key: str | None = None,
    read_declared: Callable[[Path], tuple[str | None, dict]] | None = None,
) -> Identity:
    """Decide the student ID of every submission, one row per student (see the module
    docstring for the rules; every file not graded and every doubt is flagged).

    ``roster_ids`` are the roster's IDs, or its :class:`~course.grading.batch.roster.Student`
    rows (then Canvas user numbers, Moodle participant numbers and the names the LMS writes
    name the uploaders). ``read_declared`` reads the ID a file declares and its submission
    metadata (default: decoded in this process; the batch passes a sandboxed reader).
    """
    read = read_declared or _declared
    directory = _Directory(roster_ids)
    tops = [(s.lms or s.student, s.in_folder) for s in entries]
    moodle = download_kind([n for n, f in tops if not f], [n for n, f in tops if f]) == "moodle"
    cands = [_candidate(sub, assignment, moodle, read, directory) for sub in entries]
    out = Identity(warning=_warning(cands, directory))
    _Resolver(cands, directory, out).bind()
    groups: dict[str, list[_Candidate]] = {}
    for c in cands:
        if c.sid is not None:
            groups.setdefault(c.sid, []).append(c)
    contested = {e.student for e in out.entries}
    for sid in sorted(set(groups) - contested):
        out.entries.append(_choose(sid, groups[sid], directory, out))
        chosen = groups[sid][-1]
        if data_key is not None and chosen.meta.get("data_key") not in (None, data_key):
            out.mismatched_keys.append(chosen.shown)
    out.entries.sort(key=lambda e: e.student)
    _finish_flags(out, data_key)
    return out
