"""Whose submission is this? The student ID of each file, and every doubt about it.

A submission's name is the student ID when the instructor collected ``<ID>.ipynb`` files or
``<ID>/`` folders (the convention before submissions had metadata) or when it is the name
``check.submit()`` writes, ``<ID>_<assignment>.ipynb``. A learning-management system renames
uploads (``Doe_John_98765_02_test_quantities.ipynb``, or a Moodle folder
``John Doe_1234_assignsubmission_file_``): then the ID comes from the notebook itself (the
submission metadata ``check.submit()`` writes, else ``STUDENT_ID`` in its setup cell).

Every case where the name and the notebook disagree, where no ID can be found, where two
files claim one ID, or where the notebook was worked on personal data issued with another key
than the one grading uses, becomes a line of the console summary (:class:`Identity.flags`).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from course.grading.notebook import MAX_NOTEBOOK_BYTES
from course.grading.student.submit import saved_student_id
from course.grading.vocabulary import DEMO_STUDENT_ID, PLACEHOLDER_ID, is_student_id

__all__ = ["Identity", "resolve_identities"]


@dataclass
class Identity:
    """The resolved submissions (:class:`~course.grading.batch.driver.Submission`, each with the
    student ID decided here) and the console's flags."""

    entries: list = field(default_factory=list)
    flags: list = field(default_factory=list)
    mismatched_keys: list = field(default_factory=list)  # files worked on other data


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


def _trusted_name(name_id: str, roster: set) -> bool:
    """Whether a name is taken as the ID against the notebook's: a roster ID when there is a
    roster, else any well-formed ID (the instructor's renaming is deliberate)."""
    return name_id in roster if roster else True


def _looks_bare(name_id: str) -> bool:
    """A single token (``98765``, ``s123``, ``jane.doe``): no sign of a name with extra text."""
    return re.fullmatch(r"[A-Za-z0-9.@-]+", name_id) is not None


def resolve_identities(
    entries: list, assignment: str, roster_ids=None, data_key: str | None = None
) -> Identity:
    """Decide the student ID of every submission (``.student`` is its name in the folder).

    The notebook's declared ID wins when the name contains it; a name that is an ID (on the
    roster, when there is one) wins over a different declared ID (the instructor's renaming);
    otherwise the declared ID wins over a name with extra text. Without a declared ID the name is used, or the one roster
    ID it contains. Every disagreement and guess is flagged.
    """
    roster = set(roster_ids or ())
    out = Identity()
    claimed: dict[str, list[tuple[str, Any, dict]]] = {}
    for sub in entries:
        name, path = sub.student, sub.path
        if path is None:  # refused or empty: nothing to read, the name stays
            claimed.setdefault(name, []).append((name, sub, {}))
            continue
        shown = path.name if path is not None and path.stem == name else name
        names = [name] + ([path.stem] if path is not None and path.stem != name else [])
        name_id = next((c for c in (_name_id(n, assignment) for n in names) if c), None)
        declared, meta = _declared(path)
        if declared is not None and any(_contains(n, declared) for n in names):
            sid = declared
        elif declared is not None and name_id is not None and _trusted_name(name_id, roster):
            sid = name_id
            out.flags.append(
                f"{shown}: the notebook says STUDENT_ID {declared!r}; graded as {name_id!r} "
                "(the file name), with the data of that ID"
            )
        elif declared is not None:
            sid = declared
            out.flags.append(
                f"{shown}: the file name does not contain the notebook's STUDENT_ID "
                f"{declared!r}; graded as {declared!r}"
            )
        elif name_id is not None and (not roster or name_id in roster):
            sid = name_id
            if name_id not in roster and not _looks_bare(name_id):
                out.flags.append(
                    f"{shown}: no student ID in the notebook; graded under its file name "
                    f"{name_id!r} (rename it to <ID>.ipynb and grade again if that is wrong)"
                )
        else:
            in_name = sorted({r for r in roster if any(_contains(n, r) for n in names)})
            if len(in_name) == 1:
                sid = in_name[0]
                out.flags.append(
                    f"{shown}: the notebook has no student ID; graded as {sid!r}, the roster ID "
                    "in its file name"
                )
            else:
                sid = name_id or name
                out.flags.append(
                    f"{shown}: no student ID in the notebook, and the file name is not "
                    f"{'a roster ID' if roster else 'an ID'}; graded as {sid!r} "
                    "(rename it to <ID>.ipynb and grade again)"
                )
        if data_key is not None and meta.get("data_key") not in (None, data_key):
            out.mismatched_keys.append(shown)
        claimed.setdefault(sid, []).append((shown, sub, meta))
    for sid in sorted(claimed):
        files = claimed[sid]
        if len(files) > 1:
            # the most recently written submission counts; the others are reported
            files.sort(key=lambda f: (str(f[2].get("written", "")), f[0]))
            out.flags.append(
                f"{len(files)} submissions claim the ID {sid!r}: "
                + ", ".join(f[0] for f in files)
                + f"; graded {files[-1][0]} (the latest written)"
            )
        out.entries.append(replace(files[-1][1], student=sid))
    if out.mismatched_keys:
        out.flags.append(
            f"{len(out.mismatched_keys)} submission(s) were worked on personal data issued with "
            f"another key than this run's ({data_key}): "
            + ", ".join(out.mismatched_keys[:5])
            + (" …" if len(out.mismatched_keys) > 5 else "")
            + "; grade with the class's --secret, or their personal questions score 0"
        )
    return out
