"""``course release``: generate ``exercises/<name>/`` from ``solutions/<name>/``.

The release holds the student notebook (stubs, no outputs, no hidden tests), ``checks.json``
(public cases with SEALED expected values, see :mod:`course.grading.authoring.seal`: type, shape and
field names in the clear, every number a salted slow hash of its tolerance cell; never a value,
never reference code), and the public ``data.py`` plus any extra files the assignment lists. The output is byte-for-byte
deterministic for a given solution, library version and platform.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import nbformat

from course.grading.authoring.checks import Checks, load_checks
from course.grading.authoring.passes import make_release
from course.grading.authoring.seal import make_salt, seal
from course.grading.codec import encode
from course.grading.compare import signature
from course.grading.items import right_options
from course.grading.notebook import Release
from course.grading.vocabulary import (
    CHECKS_FILE,
    DEMO_STUDENT_ID,
    PUBLIC_FORMAT,
    PublicCase,
    PublicQuestion,
    PublicSpec,
    QuestionKind,
)

__all__ = [
    "FORMAT",
    "checks_digest",
    "find_solutions",
    "load_assignment",
    "public_spec",
    "release",
    "release_files",
]

FORMAT = PUBLIC_FORMAT


def find_solutions(solutions_dir: Path) -> list[str]:
    """Names of the assignments under ``solutions_dir`` (folders with a checks.py)."""
    solutions_dir = Path(solutions_dir)
    if not solutions_dir.is_dir():
        return []
    return sorted(p.name for p in solutions_dir.iterdir() if (p / "checks.py").is_file())


def load_assignment(solution_dir: Path) -> tuple[Checks, Release]:
    """Load ``checks.py`` and build the release of the solution notebook (validates both)."""
    solution_dir = Path(solution_dir).resolve()
    name = solution_dir.name
    checks = load_checks(solution_dir)
    nb_path = solution_dir / f"{name}.ipynb"
    if not nb_path.is_file():
        raise FileNotFoundError(
            f"{nb_path} does not exist: the solution notebook is named after its folder"
        )
    solution_nb = nbformat.read(nb_path, as_version=4)
    rel = make_release(solution_nb, name, checks.questions)
    return checks, rel


def _sealer(checks: Checks):
    """``sealer(q, case_index, what, value)``: the sealed value, salted per assignment (its
    checks.py), question, case and what it is (the expected value or mistake k)."""
    digest = checks.name
    if checks.solution_dir is not None and (checks.solution_dir / "checks.py").is_file():
        digest = hashlib.sha256((checks.solution_dir / "checks.py").read_bytes()).hexdigest()

    def sealer(q, index: int, what: str, value):
        salt = make_salt(digest, checks.name, q.id, index, what)
        return seal(value, q.rtol, q.atol, salt)

    return sealer


def public_spec(checks: Checks) -> PublicSpec:
    """The public part of the checks: what the self-check needs, expected values sealed."""
    sealed = _sealer(checks)
    questions = []
    for q in checks.questions.values():
        entry = PublicQuestion(
            id=q.id,
            kind=q.kind,
            target=q.target,
            points=q.points,
            hint=q.hint if isinstance(q.hint, str) else list(q.hint),
            rtol=q.rtol,
            atol=q.atol,
            partial=q.partial,
            forbid=list(q.forbid),
            data=q.data,
            properties=q.properties,
            public=q.public,
            mistake_hints=q.mistake_hints,
        )
        if q.kind == QuestionKind.SHORT_ANSWER:
            pass  # marked by the instructor: nothing to check in the notebook
        elif q.kind == QuestionKind.CHOICE:
            data = checks.data_for(q.data, DEMO_STUDENT_ID) if q.data else None
            right_options(q.id, q.options, q.expected(data=data))  # an option, or release fails
            entry.options = encode(list(q.options))
            entry.hidden_cases = 1
        elif q.kind == "function":
            for i, case in enumerate(q.public_cases):
                entry.cases.append(
                    PublicCase(
                        label=case.label,
                        args=encode(case.args),
                        kwargs=encode(case.kwargs),
                        expected=sealed(q, i, "expected", q.expected(case)),
                        mistakes=[
                            (m, sealed(q, i, f"mistake {k}", v))
                            for k, (m, v) in enumerate(q.mistaken(case))
                        ],
                    )
                )
            entry.hidden_cases = len(q.hidden_cases)
        else:
            data = checks.data_for(q.data, DEMO_STUDENT_ID) if q.data else None
            value = q.expected(data=data)
            if q.public:
                entry.cases.append(
                    PublicCase(
                        label=q.target,
                        expected=sealed(q, 0, "expected", value),
                        mistakes=[
                            (m, sealed(q, 0, f"mistake {k}", v))
                            for k, (m, v) in enumerate(q.mistaken(data=data))
                        ],
                    )
                )
            else:
                entry.signature = signature(value)
                entry.hidden_cases = 1
        questions.append(entry)
    return PublicSpec(
        assignment=checks.name,
        title=checks.title,
        max_points=checks.max_points,
        data_file="data.py" if checks.data_module is not None else None,
        data_keys=checks.data_keys(),
        questions=questions,
    )


def release_files(solution_dir: Path) -> dict[str, bytes]:
    """Everything ``course release`` writes for one assignment: relative path -> content."""
    solution_dir = Path(solution_dir).resolve()
    name = solution_dir.name
    checks, rel = load_assignment(solution_dir)
    files = {
        f"{name}.ipynb": rel.text().encode("utf-8"),
        CHECKS_FILE: public_spec(checks).text().encode("utf-8"),
    }
    if checks.data_module is not None:
        data_file = solution_dir / "data.py"
        if not data_file.is_file():
            raise FileNotFoundError(
                f"{data_file}: Checks(data=...) needs the public data.py next to checks.py"
            )
        files["data.py"] = data_file.read_bytes()
    for extra in checks.files:
        path = (solution_dir / extra).resolve()
        if solution_dir not in path.parents or not path.is_file():
            raise FileNotFoundError(
                f"{name}: listed file {extra!r} is not a file inside {solution_dir}"
            )
        if path.name in ("checks.py",) or path.suffix == ".ipynb":
            raise ValueError(
                f"{name}: refusing to release {extra!r} (checks and solutions stay private)"
            )
        files[Path(extra).as_posix()] = path.read_bytes()
    return files


def release(name: str, solutions_dir: Path, exercises_dir: Path) -> list[Path]:
    """Write the release of ``solutions_dir/name`` into ``exercises_dir/name``; return the paths."""
    files = release_files(Path(solutions_dir) / name)
    out_dir = Path(exercises_dir) / name
    written = []
    for rel_path, content in sorted(files.items()):
        target = out_dir / rel_path
        target.parent.mkdir(parents=True, exist_ok=True)
        if not target.exists() or target.read_bytes() != content:
            target.write_bytes(content)
        written.append(target)
    return written


def checks_digest(solution_dir: Path, files=()) -> str:
    """sha256 over the assignment's authoring files (checks.py, data.py, the solution notebook
    and listed ``files``): recorded with every grade so a changed assignment is detectable."""
    solution_dir = Path(solution_dir).resolve()
    h = hashlib.sha256()
    names = ["checks.py", "data.py", f"{solution_dir.name}.ipynb", *sorted(files)]
    for rel_path in names:
        path = solution_dir / rel_path
        if path.is_file():
            h.update(rel_path.encode() + b"\0" + hashlib.sha256(path.read_bytes()).digest())
    return h.hexdigest()
