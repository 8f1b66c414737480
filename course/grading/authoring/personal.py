"""Personal data of a graded class: issued as data, drawn with the instructor's secret.

``course export --secret KEY --roster ROSTER`` writes, per assignment with personal data,
``personal_data.json`` (every student's data sets, generated here from the secret) and
replaces ``data.py`` by its public part (:func:`public_data_source`: the self-check's property
functions, never the generators, whose code alone can give a truth away, e.g. that every
record is faulty). The student's ``check.data("key")`` reads the file; the grader draws the
same data again from the secret.

The file maps ``sha256(salt, assignment, ID)`` to each student's data, so it does not list
the class's IDs in clear (IDs are short: someone who guesses an ID can still look it up and
see that student's data, which is no more than that student could show them).
"""

from __future__ import annotations

import ast
import hashlib
import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from course.grading.authoring.secret import Secret
from course.grading.codec import decode, encode

__all__ = [
    "PERSONAL_FILE",
    "PersonalData",
    "build_personal_data",
    "public_data_source",
    "students_data_source",
]

PERSONAL_FILE = "personal_data.json"
_FORMAT = 1


def _lookup(salt: str, assignment: str, student_id: str) -> str:
    text = f"{salt}\0{assignment}\0{str(student_id).strip()}".encode()
    return hashlib.sha256(text).hexdigest()[:32]


def build_personal_data(checks, student_ids: Iterable[str], secret: Secret) -> str:
    """The text of ``personal_data.json`` of one assignment for these students."""
    keys = checks.data_keys()
    salt = secret.derive(f"salt\0{checks.name}")[:16].hex()
    students = {}
    for sid in student_ids:
        students[_lookup(salt, checks.name, sid)] = {
            key: encode(checks.data_for(key, sid, secret)) for key in keys
        }
    content = {
        "format": _FORMAT,
        "assignment": checks.name,
        "key_id": secret.key_id,
        "salt": salt,
        "keys": keys,
        "students": dict(sorted(students.items())),
    }
    return json.dumps(content, sort_keys=True, separators=(",", ":"), allow_nan=False) + "\n"


class PersonalData:
    """The issued personal data of one assignment (read by the student's self-check)."""

    def __init__(self, content: dict, path: Path):
        self.path = path
        self.assignment = content["assignment"]
        self.key_id = content.get("key_id", "")
        self.keys = list(content.get("keys", []))
        self._salt = content["salt"]
        self._students = content["students"]

    @classmethod
    def read(cls, folder: Path) -> PersonalData | None:
        """The file in ``folder``, or None when the assignment's data are public."""
        path = Path(folder) / PERSONAL_FILE
        if not path.is_file():
            return None
        try:
            content = json.loads(path.read_text("utf-8"))
            if content.get("format", _FORMAT) > _FORMAT:
                raise ValueError("written by a newer course package: upgrade the course")
            return cls(content, path)
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise ValueError(
                f"{path} cannot be read ({exc}); download the course again or ask your instructor"
            ) from None

    def has(self, student_id: str) -> bool:
        return _lookup(self._salt, self.assignment, student_id) in self._students

    def registered_case(self, student_id: str) -> str | None:
        """The registered ID that differs from ``student_id`` only in upper/lower case, if
        any: IDs are case-sensitive, and ``s001`` typed as ``S001`` is the likeliest slip."""
        sid = str(student_id).strip()
        variants = {sid.lower(), sid.upper(), sid.capitalize(), sid.swapcase()} - {sid}
        return next((v for v in sorted(variants) if self.has(v)), None)

    def data(self, student_id: str, key: str) -> Any:
        entry = self._students.get(_lookup(self._salt, self.assignment, student_id))
        if entry is None:
            sid = str(student_id).strip()
            known = self.registered_case(sid)
            if known is not None:
                raise KeyError(
                    f"Your student ID {sid!r} is not registered, but {known!r} is: IDs are "
                    f"case-sensitive. Set STUDENT_ID = {known!r} in the first cell and run it."
                )
            raise KeyError(
                f"Your student ID {sid!r} is not in this course's personal data. Check "
                "STUDENT_ID in the first cell (exactly as registered: the same upper and "
                "lower case, no spaces, no missing digits). If it is right, ask your "
                "instructor: the data may have been issued before you enrolled."
            )
        return decode(entry[key])


# --------------------------------------------------------------------------------------
# the public part of data.py
# --------------------------------------------------------------------------------------
def _names_used(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}


def _bound_names(node: ast.stmt) -> set[str]:
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        return {node.name}
    if isinstance(node, (ast.Import, ast.ImportFrom)):
        return {(a.asname or a.name).split(".")[0] for a in node.names}
    if isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
        targets = node.targets if isinstance(node, ast.Assign) else [node.target]
        return {n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)}
    return set()


def public_data_source(source: str, keep: Iterable[str], private: Iterable[str], name: str) -> str:
    """The public part of an assignment's ``data.py``: the functions in ``keep`` (the
    self-check's property functions) and the module-level names they use, nothing else.

    ``private`` are the generators; a kept function that needs one is an authoring error
    (it would ship the generator), reported as ValueError.
    """
    tree = ast.parse(source)
    keep, private = set(keep), set(private)
    top: dict[str, ast.stmt] = {}
    for node in tree.body:
        for bound in _bound_names(node):
            top[bound] = node
    missing = keep - set(top)
    if missing:
        raise ValueError(f"{name}/data.py has no function {', '.join(sorted(missing))}")
    wanted: set[str] = set()
    todo = sorted(keep)
    while todo:
        current = todo.pop()
        if current in wanted:
            continue
        if current in private:
            raise ValueError(
                f"{name}/data.py: a property function uses the generator {current!r}, which "
                "must stay with the instructor; compute what it needs from its arguments"
            )
        wanted.add(current)
        todo.extend(sorted(n for n in _names_used(top[current]) if n in top and n not in wanted))
    nodes = sorted({id(top[n]): top[n] for n in wanted}.values(), key=lambda n: n.lineno)
    lines = source.splitlines()
    parts = [
        f'"""Public part of the personal-data module of assignment {name}.\n\n'
        "Your data set comes from your instructor (personal_data.json beside this file), drawn\n"
        "with a key only your instructor has; this module holds only the self-check's sanity\n"
        'checks, which do not reveal the answers."""'
    ]
    for node in nodes:
        first = min([node.lineno, *(d.lineno for d in getattr(node, "decorator_list", []))])
        parts.append("\n".join(lines[first - 1 : node.end_lineno]))
    return "\n\n\n".join(parts) + "\n"


def students_data_source(checks, keyed: bool) -> str | None:
    """The ``data.py`` a student has beside the notebook, as text (None: the assignment has
    none): the released file, or its public part (:func:`public_data_source`) in a graded
    class's edition (``keyed``: its personal data drawn with a secret). The grader offers the
    same module to the notebook (``from data import ...``), so what runs at self-check runs
    at grading."""
    if checks.data_module is None or checks.solution_dir is None:
        return None
    path = Path(checks.solution_dir) / "data.py"
    if not path.is_file():
        return None
    source = path.read_text("utf-8")
    if keyed and checks.data_keys():
        keep = {q.properties for q in checks.questions.values() if q.properties}
        source = public_data_source(source, keep, checks.data_keys(), checks.name)
    return source
