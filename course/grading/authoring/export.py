"""``course export DEST``: build what students receive, and nothing of what they must not.

``DEST`` (new, or an empty folder) receives:

``residual-validation-course-<version>/``
    the student edition as a folder: the library (``course/``), and inside the package
    ``course/materials/`` the teaching notebooks, the released exercises and the student
    README; its own ``pyproject.toml``, so ``pip install ./<folder>`` works;
``residual-validation-course-<version>.zip``
    the same folder, zipped;
``residual_validation_course-<version>-py3-none-any.whl`` and ``….tar.gz``
    an installable wheel and sdist: ``pip install <file>`` then ``course open`` copies the
    notebooks and exercises into a working folder of the student's choosing;
``EXPORT.md``
    for the instructor: what is where, which file to hand out, and what students can see.

Never included: ``solutions/``, any ``checks.py``, hidden cases, reference code, the tests,
the instructor's secret. With ``secret`` and ``roster`` (a graded class), each assignment with
personal data ships ``personal_data.json`` (the roster's data, drawn with the secret) and only
the public part of ``data.py`` (see :mod:`course.grading.authoring.personal`). Before anything is handed
over, every file (archives included) is scanned for the needles of :mod:`course.grading.authoring.leaks`;
a hit aborts the export. A failed export leaves ``DEST`` as it was.
"""

from __future__ import annotations

import base64
import gzip
import hashlib
import io
import json
import os
import shutil
import tarfile
import tempfile
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

from course.grading.authoring.checks import load_checks
from course.grading.authoring.leaks import Hit, needles_for, public_corpus, scan
from course.grading.authoring.personal import PERSONAL_FILE, build_personal_data, public_data_source
from course.grading.authoring.release import find_solutions, release_files
from course.grading.authoring.secret import Secret, public_key_id
from course.grading.batch.roster import Roster
from course.grading.vocabulary import CLASS_FILE, compile_id_pattern

__all__ = ["DIST_NAME", "ExportError", "ExportResult", "export"]

REPO_ROOT = Path(__file__).resolve().parents[3]
DIST_NAME = "residual-validation-course"
_WHEEL_NAME = DIST_NAME.replace("-", "_")
STUDENT_PAGE = Path("docs/students/install-and-submit.md")
#: What students run beyond the library: `course open` starts JupyterLab, and the teaching
#: notebooks' sliders need ipywidgets (the wheel has no extras and is on no index, so
#: everything a shipped notebook imports must be a plain dependency).
_STUDENT_EXTRA_DEPENDENCIES = ["jupyterlab>=4", "ipykernel>=6.25", "ipywidgets>=8.0"]
# a fixed timestamp makes every archive byte-for-byte reproducible (zip cannot go below 1980)
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)


class ExportError(ValueError):
    """The export cannot be made (nothing was written)."""


@dataclass
class ExportResult:
    dest: Path
    folder: Path
    zip: Path
    wheel: Path
    sdist: Path
    data_key: str  # the secret's key id, or "public"
    students: int  # roster size (0 without a roster)
    hits: list[Hit] = field(default_factory=list)

    @property
    def artefacts(self) -> list[Path]:
        return [self.folder, self.zip, self.wheel, self.sdist]


def _project_metadata(root: Path) -> dict:
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        try:
            import tomli as tomllib
        except ModuleNotFoundError:
            raise ExportError("course export needs Python 3.11 or the tomli package") from None
    return tomllib.loads((root / "pyproject.toml").read_text("utf-8"))["project"]


def _distribution_metadata(project: dict, version: str) -> dict:
    """The student edition's core metadata, from the project's ``[project]`` table."""
    return {
        "name": DIST_NAME,
        "version": version,
        "summary": project.get("description", ""),
        "requires_python": project.get("requires-python", ">=3.10"),
        "dependencies": list(project.get("dependencies", [])) + _STUDENT_EXTRA_DEPENDENCIES,
        "license": _license(project.get("license")),
    }


def _check_destination(dest: Path) -> None:
    if dest.exists():
        if not dest.is_dir():
            raise ExportError(f"{dest} exists and is a file; name a new folder")
        if any(dest.iterdir()):
            raise ExportError(
                f"{dest} exists and is not empty; name a new folder (or empty this one): "
                "an export never mixes with older files"
            )
    elif not dest.parent.is_dir():
        raise ExportError(f"cannot create {dest}: the folder {dest.parent} does not exist")


def export(
    dest: str | Path,
    root: str | Path = REPO_ROOT,
    secret: Secret | None = None,
    roster: Roster | None = None,
    check_leaks: bool = True,
    releases: dict[str, dict[str, bytes]] | None = None,
    id_pattern: str | None = None,
) -> ExportResult:
    """Build the student distribution into ``dest`` (see the module docstring).

    ``id_pattern`` (a regular expression a whole student ID matches) goes into each
    assignment's ``class.json``: the self-check then says when ``STUDENT_ID`` is off it and
    ``check.submit()`` refuses it. Every roster ID must match it.

    ``releases`` are the assignments' release files when already at hand (``{name:
    release_files(...)}``, e.g. for several editions in a row); by default they are made here.
    """
    # normalised (no "..") without resolving links: the path printed is the one to hand out
    dest, root = Path(os.path.abspath(dest)), Path(root).resolve()
    _check_destination(dest)
    if (secret is None) != (roster is None):
        raise ExportError(
            "a graded class needs both --secret and --roster (students get the roster's data "
            "drawn with the secret); for a self-learners' edition give neither"
        )
    if id_pattern is not None:
        _check_id_pattern(id_pattern, roster)
    for needed in ("course", "notebooks", "solutions", STUDENT_PAGE):
        if not (root / needed).exists():
            raise ExportError(f"{root} is not the course's repository (no {needed})")
    names = find_solutions(root / "solutions")
    if releases is None or sorted(releases) != names:
        releases = {name: release_files(root / "solutions" / name) for name in names}
    staging = Path(tempfile.mkdtemp(prefix=f".{dest.name}.partial-", dir=dest.parent))
    try:
        result = _build(staging, dest, root, names, releases, secret, roster, id_pattern)
        if check_leaks:
            public = public_corpus(root, releases)
            needles = [
                n for name in names for n in needles_for(root / "solutions" / name, secret, public)
            ]
            hits = scan(
                [staging / result.folder.name, result.zip, result.wheel, result.sdist], needles
            )
            if hits:
                shown = "\n  ".join(str(h) for h in hits[:12])
                raise ExportError(
                    f"refusing to export: {len(hits)} leak(s) of instructor material found:\n  "
                    + shown
                )
        if dest.exists():
            dest.rmdir()
        os.replace(staging, dest)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    for name in ("folder", "zip", "wheel", "sdist"):
        setattr(result, name, dest / getattr(result, name).name)
    result.dest = dest
    return result


#: The grader's rooms that only the instructor runs (``course grade`` and its sandbox): the
#: student edition leaves them out, and ``course grade`` there says it is the instructor's.
INSTRUCTOR_ONLY_ROOMS = ("batch", "sandbox")


def _not_for_students(package: Path):
    """``copytree``'s ignore function for the student edition's copy of ``course/``."""
    everywhere = shutil.ignore_patterns("__pycache__", "*.pyc", "materials", ".*")
    grading = (package / "grading").resolve()

    def ignore(folder: str, names: list[str]) -> set[str]:
        skipped = set(everywhere(folder, names))
        if Path(folder).resolve() == grading:
            skipped |= set(INSTRUCTOR_ONLY_ROOMS) & set(names)
        return skipped

    return ignore


def _check_id_pattern(pattern: str, roster: Roster | None) -> None:
    try:
        compiled = compile_id_pattern(pattern)
    except ValueError as exc:
        raise ExportError(str(exc)) from None
    if roster is not None:
        off = [sid for sid in roster.ids if not compiled.fullmatch(sid)]
        if off:
            shown = ", ".join(repr(sid) for sid in off[:5]) + (" ..." if len(off) > 5 else "")
            raise ExportError(
                f"{len(off)} roster ID(s) do not match --id-pattern {pattern!r}: {shown}; "
                "fix the pattern or the roster (those students could not submit)"
            )


def _build(staging, dest, root, names, releases, secret, roster, id_pattern=None) -> ExportResult:
    import course

    version = str(course.__version__)
    project = _project_metadata(root)
    folder = staging / f"{DIST_NAME}-{version}"
    package = folder / "course"
    shutil.copytree(root / "course", package, ignore=_not_for_students(root / "course"))
    materials = package / "materials"
    (materials / "notebooks").mkdir(parents=True)
    for nb in sorted((root / "notebooks").glob("*.ipynb")):
        shutil.copyfile(nb, materials / "notebooks" / nb.name)
    for name in names:
        files = dict(releases[name])
        checks = load_checks(root / "solutions" / name)
        if secret is not None and checks.data_keys():
            files[PERSONAL_FILE] = build_personal_data(checks, roster.ids, secret).encode()
            keep = {q.properties for q in checks.questions.values() if q.properties}
            files["data.py"] = public_data_source(
                files["data.py"].decode("utf-8"), keep, checks.data_keys(), name
            ).encode()
        if id_pattern is not None:
            files[CLASS_FILE] = (
                json.dumps({"format": 1, "id_pattern": id_pattern}) + "\n"
            ).encode()
        for rel, content in sorted(files.items()):
            target = materials / "exercises" / name / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(content)
    readme = _student_readme(root, secret is not None)
    (folder / "README.md").write_text(readme, encoding="utf-8")
    (materials / "README.md").write_text(readme, encoding="utf-8")
    meta = _distribution_metadata(project, version)
    if (root / "LICENSE").is_file():
        shutil.copyfile(root / "LICENSE", folder / "LICENSE")
    (folder / "pyproject.toml").write_text(_pyproject(meta), encoding="utf-8")
    zip_path = staging / f"{folder.name}.zip"
    _write_zip(folder, zip_path)
    wheel = _write_wheel(folder, staging, meta, readme)
    sdist = _write_sdist(folder, staging, meta, readme)
    result = ExportResult(
        dest=dest,
        folder=folder,
        zip=zip_path,
        wheel=wheel,
        sdist=sdist,
        data_key=secret.key_id if secret is not None else public_key_id,
        students=len(roster.students) if roster is not None else 0,
    )
    (staging / "EXPORT.md").write_text(_instructor_notes(result, names), encoding="utf-8")
    return result


# --------------------------------------------------------------------------------------
# texts
# --------------------------------------------------------------------------------------
def _student_readme(root: Path, keyed: bool) -> str:
    text = (root / STUDENT_PAGE).read_text("utf-8")
    if keyed:
        note = (
            "\n## Your personal data\n\n"
            "Some questions use data generated for your student ID. In this edition they come "
            "from your instructor (`personal_data.json` in each exercise folder), drawn with a "
            "key only your instructor holds: set `STUDENT_ID` exactly as registered, or "
            "`check.data(...)` will not find your data.\n"
        )
    else:
        note = (
            "\n## Your personal data\n\n"
            "Some questions use data generated for your student ID by `data.py` in each exercise "
            "folder. In this self-learner edition anyone can regenerate them, including the "
            "truth behind them (which fault, which blunder): reading the generator spoils the "
            "exercise, so work from the data first.\n"
        )
    return text.rstrip() + "\n" + note


def _instructor_notes(result: ExportResult, names: list[str]) -> str:
    keyed = result.data_key != public_key_id
    mode = (
        f"graded class: personal data of {result.students} students drawn with the secret "
        f"(key id {result.data_key}); grade with the same secret"
        if keyed
        else "self-learners: personal data are generated from the public data.py "
        "(students can rebuild the truth behind personal questions)"
    )
    return f"""# Student distribution

Built by `course export`. Edition: {mode}.
Assignments: {", ".join(names)}.

| file | what it is | hand it out? |
|---|---|---|
| `{result.wheel.name}` | the installable course: `pip install {result.wheel.name}`, then `course open` | yes (simplest) |
| `{result.zip.name}` | the same as a folder, zipped: unzip, `pip install ./{result.folder.name}`, `course open` | yes |
| `{result.sdist.name}` | source distribution (`pip install` builds it) | if you prefer |
| `{result.folder.name}/` | the unzipped folder | it is the zip's content |
| `EXPORT.md` | this note | no |

Students can see: the library's source, the teaching notebooks, the assignment notebooks,
`checks.json` (the public cases with their expected values sealed, i.e. checkable but not
readable, the hints, how many hidden cases there are), `data.py` (the self-check's property checks{"" if keyed else " and the data generators"})
{"and `personal_data.json` (every listed student's data, indexed by a hash of the ID)" if keyed else ""}.
They cannot see: solution notebooks, `checks.py` (references, hidden cases, tolerances of
hidden cases), {"the data generators, the secret, " if keyed else ""}the tests.
Every file here, archives included, was scanned for those before the export finished.
"""


def _license(value) -> str:
    """The SPDX expression of ``[project].license`` (a string, or the older ``{text = ...}``)."""
    if isinstance(value, dict):
        return str(value.get("text", ""))
    return str(value or "")


def _toml_list(items) -> str:
    return "[" + ", ".join(json.dumps(i) for i in items) + "]"


def _pyproject(meta: dict) -> str:
    return f"""[build-system]
requires = ["setuptools>=77"]
build-backend = "setuptools.build_meta"

[project]
name = {json.dumps(meta["name"])}
version = {json.dumps(meta["version"])}
description = {json.dumps(meta["summary"])}
readme = "README.md"
requires-python = {json.dumps(meta["requires_python"])}
license = {json.dumps(meta["license"])}
license-files = ["LICENSE"]
dependencies = {_toml_list(meta["dependencies"])}

[project.scripts]
course = "course.cli:main"

[tool.setuptools.packages.find]
include = ["course*"]

[tool.setuptools.package-data]
course = ["data/**/*", "materials/**/*"]
"""


def _core_metadata(meta: dict, readme: str) -> str:
    lines = [
        "Metadata-Version: 2.4",
        f"Name: {meta['name']}",
        f"Version: {meta['version']}",
        f"Summary: {meta['summary']}",
        f"License-Expression: {meta['license']}",
        "License-File: LICENSE",
        f"Requires-Python: {meta['requires_python']}",
        *(f"Requires-Dist: {d}" for d in meta["dependencies"]),
        "Description-Content-Type: text/markdown",
    ]
    return "\n".join(lines) + "\n\n" + readme


# --------------------------------------------------------------------------------------
# archives, written here rather than by the project's build backend (setuptools.build_meta):
# - in-process, the backend is whatever setuptools the instructor's environment holds, and
#   `license = "MIT"` (PEP 639) needs setuptools >= 77, which `.[all]` does not bring (pip's
#   isolated builds fetch it); through pip or `build` it needs the index, or a warm cache;
# - no build step: a backend build copies the tree again into build/ and egg-info folders;
# - byte-reproducible as it is: setuptools' sdist records the files' mtimes and the build's
#   time in its gzip header (SOURCE_DATE_EPOCH reaches the wheel only), so two exports of
#   the same tree would differ.
# The wheel is pure Python and its metadata few (_core_metadata); tests/test_journey.py
# installs it with pip into a fresh environment, and pip validates RECORD and METADATA.
# --------------------------------------------------------------------------------------
def _tree_files(folder: Path) -> list[tuple[str, bytes]]:
    return [
        (p.relative_to(folder).as_posix(), p.read_bytes())
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    ]


def _zip_entry(z: zipfile.ZipFile, name: str, data: bytes) -> None:
    info = zipfile.ZipInfo(name, date_time=_ZIP_TIME)
    info.compress_type = zipfile.ZIP_DEFLATED
    info.external_attr = 0o644 << 16
    z.writestr(info, data)


def _write_zip(folder: Path, path: Path) -> None:
    with zipfile.ZipFile(path, "w") as z:
        for rel, data in _tree_files(folder):
            _zip_entry(z, f"{folder.name}/{rel}", data)


def _write_wheel(folder: Path, out: Path, meta: dict, readme: str) -> Path:
    """A pure-Python wheel (PEP 427) of ``folder/course``."""
    tag = "py3-none-any"
    dist_info = f"{_WHEEL_NAME}-{meta['version']}.dist-info"
    files = [(rel, data) for rel, data in _tree_files(folder) if rel.startswith("course/")]
    files += [
        (f"{dist_info}/METADATA", _core_metadata(meta, readme).encode("utf-8")),
        (
            f"{dist_info}/WHEEL",
            f"Wheel-Version: 1.0\nGenerator: course-export\nRoot-Is-Purelib: true\nTag: {tag}\n".encode(),
        ),
        (f"{dist_info}/entry_points.txt", b"[console_scripts]\ncourse = course.cli:main\n"),
    ]
    if (folder / "LICENSE").is_file():  # PEP 639: license files under dist-info/licenses/
        files.append((f"{dist_info}/licenses/LICENSE", (folder / "LICENSE").read_bytes()))
    record = io.StringIO()
    for rel, data in files:
        digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
        record.write(f"{rel},sha256={digest},{len(data)}\n")
    record.write(f"{dist_info}/RECORD,,\n")
    files.append((f"{dist_info}/RECORD", record.getvalue().encode()))
    path = out / f"{_WHEEL_NAME}-{meta['version']}-{tag}.whl"
    with zipfile.ZipFile(path, "w") as z:
        for rel, data in files:
            _zip_entry(z, rel, data)
    return path


def _write_sdist(folder: Path, out: Path, meta: dict, readme: str) -> Path:
    """A source distribution (PEP 517/625): the folder, plus PKG-INFO."""
    base = f"{_WHEEL_NAME}-{meta['version']}"
    path = out / f"{base}.tar.gz"
    files = _tree_files(folder) + [("PKG-INFO", _core_metadata(meta, readme).encode("utf-8"))]
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w", format=tarfile.PAX_FORMAT) as tar:
        for rel, data in sorted(files):
            info = tarfile.TarInfo(f"{base}/{rel}")
            info.size, info.mode, info.mtime = len(data), 0o644, 0
            tar.addfile(info, io.BytesIO(data))
    with open(path, "wb") as f, gzip.GzipFile(fileobj=f, mode="wb", mtime=0, filename="") as gz:
        gz.write(buf.getvalue())
    return path
