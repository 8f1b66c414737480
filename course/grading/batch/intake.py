"""What was handed in: the files of a submissions folder or an LMS's download archive, each
looked at without trusting it.

:func:`find_submissions` lists every file of a submissions folder as a
:class:`Submission` (a notebook to grade, or a file refused or not a notebook, with the reason
told to its student); :func:`unpack_archive` reads a Canvas or Moodle download (a ``.zip``) as
it comes. Whose file is whose is decided afterwards, by :mod:`course.grading.batch.identity`.

The rules hold for folders and archives alike. Nothing is opened before ``lstat`` says what it
is: a symbolic link, a FIFO, a device or a socket is refused by name (a FIFO opened for reading
would stall the batch), a hard link to a file outside the submissions (its link count is
higher than the links inside) or to the course's own files is refused, and a notebook larger
than :data:`~course.grading.notebook.MAX_NOTEBOOK_BYTES` is refused for its size without
reading it (a sparse file of 20 GB costs nothing). Files are opened with ``O_NOFOLLOW`` and
``O_NONBLOCK`` and checked again with ``fstat``, so a file swapped after the listing gains
nothing. An archive entry whose path would leave the folder it is unpacked into (``../``, an
absolute path: zip-slip), a link, or anything beyond the archive's budgets (entries, bytes) is
refused; only notebooks are written out, every other entry is listed by name.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import stat
import zipfile
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from course.grading.notebook import MAX_NOTEBOOK_BYTES

__all__ = [
    "MAX_ARCHIVE_BYTES",
    "MAX_ARCHIVE_ENTRIES",
    "IntakeError",
    "Submission",
    "file_digest",
    "find_submissions",
    "open_regular",
    "unpack_archive",
]

MAX_ARCHIVE_ENTRIES = 50_000  # a class of 1,000 with a few dozen files each
MAX_ARCHIVE_BYTES = 8_000_000_000  # the notebooks unpacked, all together
_MAX_WALK = 200_000  # files looked at in a submissions folder
_MAX_DEPTH = 24
_MB = MAX_NOTEBOOK_BYTES // 1_000_000


class IntakeError(ValueError):
    """A submissions archive that cannot be read as a whole (the message says why)."""


@dataclass(frozen=True)
class Submission:
    """One file handed in (``path`` None: nothing to grade, ``note`` says why).

    ``student`` is the file's stem or its student's folder name until the identity step
    replaces it with a student ID; ``lms`` is the name the LMS gave the file or the folder it
    lies in, ``in_folder`` says which."""

    student: str
    path: Path | None
    note: str | None = None  # told to the student and the instructor
    refused: bool = False  # a link, a FIFO, too large, from outside the submissions
    lms: str = ""
    in_folder: bool = False


def open_regular(path, limit: int = MAX_NOTEBOOK_BYTES) -> int:
    """A read-only descriptor of the regular file at ``path`` of at most ``limit`` bytes,
    opened without following a link or waiting on a FIFO; OSError (with the reason) else."""
    fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise OSError(f"{path} is not a regular file")
        if st.st_size > limit:
            raise OSError(f"{path} is larger than {limit} bytes")
    except OSError:
        os.close(fd)
        raise
    return fd


def file_digest(path: Path | None) -> str | None:
    """The sha256 of a submitted file, read in chunks (1 MB of memory); None for anything
    that could not be graded (a link, a FIFO, a file over the notebook size limit)."""
    if path is None:
        return None
    sha = hashlib.sha256()
    try:
        with os.fdopen(open_regular(path), "rb") as f:
            while chunk := f.read(1 << 20):
                sha.update(chunk)
    except OSError:
        return None
    return sha.hexdigest()


def _kind(mode: int) -> str:
    for test, what in (
        (stat.S_ISLNK, "a symbolic link; submit the notebook file itself"),
        (stat.S_ISFIFO, "a FIFO (named pipe), not a file"),
        (stat.S_ISSOCK, "a socket, not a file"),
        (stat.S_ISCHR, "a device, not a file"),
        (stat.S_ISBLK, "a device, not a file"),
    ):
        if test(mode):
            return what
    return "not a regular file"


def _walk(root: Path) -> list[tuple[Path, os.stat_result]]:
    """Every file under ``root`` with its ``lstat``, links never followed; folders of
    checkpoints and hidden files (``.DS_Store``) left out."""
    out: list[tuple[Path, os.stat_result]] = []
    stack = [(root, 0)]
    while stack:
        folder, depth = stack.pop()
        with os.scandir(folder) as it:
            entries = sorted(it, key=lambda e: e.name)
        for entry in entries:
            if entry.name.startswith(".") or entry.name == "__MACOSX":
                continue
            st = entry.stat(follow_symlinks=False)
            if stat.S_ISDIR(st.st_mode) and depth < _MAX_DEPTH:
                stack.append((Path(entry.path), depth + 1))
            elif not stat.S_ISDIR(st.st_mode):
                out.append((Path(entry.path), st))
            if len(out) > _MAX_WALK:
                raise IntakeError(f"{root} holds more than {_MAX_WALK} files")
    return out


def _inodes(folder: Path | None) -> set[tuple[int, int]]:
    if folder is None or not Path(folder).is_dir():
        return set()
    return {(st.st_dev, st.st_ino) for _, st in _walk(Path(folder))}


@dataclass
class _Rules:
    """What a file of the submissions folder must not be (see the module docstring)."""

    private: set  # (device, inode) of the course's own files
    links: Counter  # (device, inode) -> links to it inside the submissions

    def refusal(self, path: Path, st: os.stat_result) -> str | None:
        if not stat.S_ISREG(st.st_mode):
            return _kind(st.st_mode)
        key = (st.st_dev, st.st_ino)
        if key in self.private:
            return "a hard link to one of the course's own files"
        if st.st_nlink > self.links[key]:
            return "a hard link to a file outside the submissions folder"
        if path.suffix == ".ipynb" and st.st_size > MAX_NOTEBOOK_BYTES:
            return f"larger than {_MB} MB (not read)"
        return None


def _entry(path: Path, st, root: Path, rules: _Rules) -> Submission:
    """The :class:`Submission` of one file of the folder."""
    rel = path.relative_to(root)
    top = rel.parts[0]
    in_folder = len(rel.parts) > 1
    student = top if in_folder else path.stem
    shown = "/".join(rel.parts[1:]) if in_folder else top
    why = rules.refusal(path, st)
    if why is not None:
        note = f"the submission was refused: {shown} is {why}"
        return Submission(student, None, note, True, top, in_folder)
    if path.suffix != ".ipynb":
        note = f"handed in {shown}, not a notebook (.ipynb)"
        return Submission(student, None, note, False, top, in_folder)
    return Submission(student, path, None, False, top, in_folder)


def find_submissions(folder: Path, assignment: str, private_dir: Path | None = None) -> list:
    """A :class:`Submission` for every file in ``folder`` (a notebook ``<id>.ipynb``, an LMS's
    file or a student's folder with its files), and one for each student folder without any
    file; names starting with ``.`` or ``_`` at the top are the instructor's own, skipped.

    ``private_dir`` is the assignment's solution folder: a hard link to one of its files is
    refused (a "submission" linked to the solution must not be graded as the student's).
    """
    root = Path(folder).resolve()
    files = [
        (p, st)
        for p, st in _walk(root)
        if not p.relative_to(root).parts[0].startswith((".", "_"))
        and ".ipynb_checkpoints" not in p.parts
    ]
    links = Counter((st.st_dev, st.st_ino) for _, st in files if stat.S_ISREG(st.st_mode))
    rules = _Rules(_inodes(private_dir), links)
    found = [_entry(p, st, root, rules) for p, st in files]
    tops = {s.lms for s in found}
    for entry in sorted(root.iterdir()):
        skipped = entry.name.startswith((".", "_")) or entry.name in tops
        if entry.is_dir() and not entry.is_symlink() and not skipped:
            note = "no notebook (.ipynb) in the submission folder"
            found.append(Submission(entry.name, None, note, False, entry.name, True))
    return sorted(found, key=lambda s: (s.lms, str(s.path or "")))


# -- an LMS's download archive ----------------------------------------------------------------
_DRIVE = re.compile(r"[A-Za-z]:")


def _parts(name: str) -> list[str] | None:
    """The path parts of an archive entry, or None when the path would leave the folder."""
    if name.startswith(("/", "\\")) or "\x00" in name:
        return None
    parts = [p for p in re.split(r"[/\\]", name) if p not in ("", ".")]
    if not parts or ".." in parts or _DRIVE.fullmatch(parts[0]):
        return None
    return parts


def _archive_refusal(info: zipfile.ZipInfo) -> str | None:
    mode = info.external_attr >> 16
    if info.create_system == 3 and stat.S_IFMT(mode) not in (0, stat.S_IFREG):
        return _kind(mode)
    if info.flag_bits & 0x1:
        return "encrypted"
    if info.filename.endswith(".ipynb") and info.file_size > MAX_NOTEBOOK_BYTES:
        return f"larger than {_MB} MB (not unpacked)"
    return None


def _listed(parts: list[str], note: str, refused: bool) -> Submission:
    """An archive entry not unpacked, said against its student (the entry's top name)."""
    top = parts[0]
    in_folder = len(parts) > 1
    student = top if in_folder else Path(top).stem
    shown = "/".join(parts[1:]) if in_folder else top
    text = f"the submission was refused: {shown} is {note}" if refused else note % shown
    return Submission(student, None, text, refused, top, in_folder)


def _copy_entry(archive: zipfile.ZipFile, info: zipfile.ZipInfo, target: Path, budget: list):
    """Write one notebook entry to ``target`` (never over an existing file or through a
    link), within the notebook size and the archive's byte budget; the reason when refused."""
    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        fd = os.open(target, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    except FileExistsError:
        return "in the archive twice"
    written = 0
    with os.fdopen(fd, "wb") as out, archive.open(info) as src:
        while chunk := src.read(1 << 20):
            written += len(chunk)
            budget[0] -= len(chunk)
            if budget[0] < 0:
                raise IntakeError(f"the archive unpacks to more than {MAX_ARCHIVE_BYTES} bytes")
            if written > MAX_NOTEBOOK_BYTES:
                break
            out.write(chunk)
    if written > MAX_NOTEBOOK_BYTES:
        target.unlink()
        return f"larger than {_MB} MB (not unpacked)"
    return None


def unpack_archive(archive: Path, dest: Path) -> tuple[list[Submission], list[str]]:
    """Unpack the notebooks of an LMS's download (Canvas's flat files, Moodle's folders, any
    depth) into ``dest`` (emptied first). Returns a :class:`Submission` for every other entry
    (refused: a link, too large; or not a notebook), and the console's lines about entries
    that belong to no student (a path leaving ``dest``)."""
    try:
        zf = zipfile.ZipFile(archive)
    except (OSError, zipfile.BadZipFile) as exc:
        raise IntakeError(f"cannot read the archive {archive}: {exc}") from None
    with zf:
        infos = zf.infolist()
        if len(infos) > MAX_ARCHIVE_ENTRIES:
            raise IntakeError(
                f"the archive {archive} holds {len(infos)} entries, more than "
                f"{MAX_ARCHIVE_ENTRIES}: not a class's download"
            )
        if dest.exists():
            shutil.rmtree(dest)
        dest.mkdir(parents=True)
        return _unpack(zf, infos, dest)


def _unpack(zf: zipfile.ZipFile, infos: list, dest: Path) -> tuple[list[Submission], list]:
    listed: list[Submission] = []
    escaped: list[str] = []
    budget = [MAX_ARCHIVE_BYTES]
    for info in infos:
        parts = _parts(info.filename)
        if parts is None:
            shown = ascii(info.filename)[1:-1][:200]
            escaped.append(f"the archive's entry {shown} was refused: its path leaves the folder")
            continue
        if info.is_dir() or parts[0] == "__MACOSX" or parts[-1].startswith("."):
            continue
        why = _archive_refusal(info)
        if why is None and not parts[-1].endswith(".ipynb"):
            listed.append(_listed(parts, "handed in %s, not a notebook (.ipynb)", False))
            continue
        if why is None:
            try:
                why = _copy_entry(zf, info, dest.joinpath(*parts), budget)
            except (OSError, zipfile.BadZipFile, ValueError) as exc:
                if isinstance(exc, IntakeError):
                    raise
                why = f"unreadable in the archive ({type(exc).__name__})"
        if why is not None:
            listed.append(_listed(parts, why, True))
    return listed, escaped
