"""Does a student distribution give anything away? Needles from ``solutions/``, and a scan.

The needles of an assignment are what only the instructor may hold:

- the text of every solution region of the solution notebook (whole, and each distinctive
  line), and each distinctive line of ``checks.py`` (the references);
- each hidden case's inputs and expected value, each unpublished expected value, and each
  public expected value (``checks.json`` ships them sealed, :mod:`course.grading.authoring.seal`), in
  the forms a leak would take: the plain-data JSON of ``checks.json``, the base64 of an array,
  the ``repr`` of a distinctive float and its 6-digit display;
- with a secret: the key itself, and the source lines of the data generators (in a graded
  class students receive data, not generators: a generator's code alone can give a truth
  away).

:func:`scan` reads every file of a folder or archive (zip, wheel, tar.gz, recursively),
as text, with JSON (notebooks) also read as its strings, and reports each needle found.
``course export`` scans what it built before it hands anything over; the test suite scans
the folder, the zip, the wheel and the sdist.
"""

from __future__ import annotations

import ast
import hashlib
import io
import json
import re
import tarfile
import zipfile
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from course.grading.authoring.secret import Secret
from course.grading.codec import decode, encode
from course.grading.notebook import BEGIN_SOLUTION, END_SOLUTION

__all__ = ["Hit", "Needle", "needles_for", "scan"]

#: Shorter lines are too common to mean anything (``return x``, ``import numpy as np``).
MIN_LINE = 28
#: Paths that only the instructor's tree has: ``solutions/``, and an assignment's checks.py.
_INSTRUCTOR_PATH = re.compile(r"(^|[/!])(solutions(/|$)|\d\d_[^/!]+/checks\.py$)")


@dataclass(frozen=True)
class Needle:
    kind: str  # "solution", "reference", "hidden input", "hidden/public expected", "secret", ...
    where: str  # e.g. "01_least_squares q3 hidden case 2"
    text: str


@dataclass(frozen=True)
class Hit:
    needle: Needle
    file: str  # path inside the scanned tree, archives as "a.zip!inner/path"

    def __str__(self) -> str:
        return f"{self.file}: {self.needle.kind} of {self.needle.where}: {self.needle.text[:80]!r}"


def _norm(text: str) -> str:
    """Lines stripped of indentation, blank lines dropped: formatting cannot hide a match."""
    return "\n".join(s for s in (line.strip() for line in text.splitlines()) if s)


def _solution_regions(source: str) -> list[str]:
    regions: list[str] = []
    current: list[str] | None = None
    for line in source.split("\n"):
        stripped = line.strip()
        if stripped == BEGIN_SOLUTION:
            current = []
        elif stripped == END_SOLUTION and current is not None:
            regions.append("\n".join(current))
            current = None
        elif current is not None and not stripped.startswith("### STUB"):
            current.append(line)
    return regions


def _distinctive_lines(text: str) -> list[str]:
    out = []
    for line in _norm(text).splitlines():
        if len(line) >= MIN_LINE and not line.startswith(("#", "import ", "from ")):
            out.append(line)
    return out


def _floats(value) -> list[float]:
    """The floats inside a plain-data value (arrays flattened)."""
    if isinstance(value, (bool, int, str)) or value is None:
        return []
    if isinstance(value, float):
        return [value]
    if isinstance(value, np.ndarray):
        return [float(x) for x in value.ravel()] if value.dtype.kind == "f" else []
    if isinstance(value, np.floating):
        return [float(value)]
    if isinstance(value, dict):
        return [f for v in value.values() for f in _floats(v)]
    if isinstance(value, (list, tuple)):
        return [f for v in value for f in _floats(v)]
    return []


def _distinctive(x: float) -> bool:
    """A float with 8 or more significant digits: data-like, not a round number that any
    text could hold by chance."""
    if not np.isfinite(x):
        return False
    return len(re.sub(r"[^0-9]", "", f"{abs(x):.15g}").strip("0")) >= 8


def _arrays(encoded) -> list[dict]:
    """The ``__ndarray__`` entries of an encoded value."""
    if isinstance(encoded, dict):
        if "__ndarray__" in encoded:
            return [encoded["__ndarray__"]]
        return [a for v in encoded.values() for a in _arrays(v)]
    if isinstance(encoded, list):
        return [a for v in encoded for a in _arrays(v)]
    return []


def _value_texts(value, per_value: int = 6) -> list[str]:
    """The forms a leaked value takes in a file: the base64 of each array holding data-like
    numbers (as in ``checks.json``), and the ``repr`` and 6-digit display of the first
    ``per_value`` data-like numbers."""
    try:
        encoded = encode(value)
    except TypeError:
        return []
    texts = []
    for array in _arrays(encoded):
        if any(_distinctive(x) for x in _floats(decode({"__ndarray__": array}))):
            texts.append(array["data"])
    for x in [x for x in _floats(value) if _distinctive(x)][:per_value]:
        texts.append(repr(x))
        short = f"{x:.6g}"
        if len(re.sub(r"[^0-9]", "", short.split("e")[0]).strip("0")) >= 6:
            texts.append(short)
    return texts


def public_corpus(root: Path, releases: dict[str, dict[str, bytes]]) -> str:
    """The course material that is public by design, normalised: the library's source, the
    teaching notebooks, and of each release (``{name: release_files(...)}``) the cells that
    are not answers, and checks.json (whose expected values are sealed). A needle found here gives nothing away (the library implements what
    some exercises ask for; the textbook examples are worked in the notebooks)."""
    root = Path(root)
    parts = []
    for path in sorted((root / "course").rglob("*.py")):
        parts.append(path.read_text("utf-8", errors="replace"))
    for path in sorted((root / "notebooks").glob("*.ipynb")):
        parts.extend(text for _, text in _texts(path.name, path.read_bytes()))
    for name, files in releases.items():
        nb = json.loads(files[f"{name}.ipynb"])
        for cell in nb["cells"]:
            if cell.get("metadata", {}).get("course", {}).get("role") != "answer":
                parts.append("".join(cell["source"]))
        # checks.json itself (inputs, hints): its expected values are sealed, never public
        parts.append(files["checks.json"].decode("utf-8"))
    return _norm("\n".join(parts))


def needles_for(solution_dir: Path, secret: Secret | None = None, public: str = "") -> list[Needle]:
    """Everything of one assignment that a student distribution must not contain; needles
    found in ``public`` (:func:`public_corpus`) are left out, except the secret and whole
    multi-line solutions."""
    from course.grading.authoring.release import load_assignment

    solution_dir = Path(solution_dir)
    name = solution_dir.name
    checks, release = load_assignment(solution_dir)
    out: list[Needle] = []
    for cell in release.cells:
        if cell.question and cell.cell_type == "markdown":  # a short answer's model answer
            if len(_norm(cell.solution_source)) > 12:
                out.append(
                    Needle("solution", f"{name} {cell.question}", _norm(cell.solution_source))
                )
        elif cell.question:
            for region in _solution_regions(cell.solution_source):
                if _norm(region):
                    out.append(Needle("solution", f"{name} {cell.question}", _norm(region)))
                for line in _distinctive_lines(region):
                    out.append(Needle("solution", f"{name} {cell.question}", line))
    tree = ast.parse((solution_dir / "checks.py").read_text("utf-8"))
    lines = (solution_dir / "checks.py").read_text("utf-8").splitlines()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):  # a reference: its body, not its signature
            body = "\n".join(lines[node.body[0].lineno - 1 : node.end_lineno])
            for line in _distinctive_lines(body):
                if not line.startswith(('"""', "'''")):
                    out.append(Needle("reference", f"{name} {node.name}", line))
    for q in checks.questions.values():
        if q.kind == "function":
            for i, case in enumerate(q.hidden_cases, 1):
                where = f"{name} {q.id} hidden case {i}"
                for text in _value_texts(list(case.args)):
                    out.append(Needle("hidden input", where, text))
                for text in _value_texts(q.expected(case)):
                    out.append(Needle("hidden expected", where, text))
            for i, case in enumerate(q.public_cases, 1):  # shipped sealed, never in the clear
                for text in _value_texts(q.expected(case)):
                    out.append(Needle("public expected", f"{name} {q.id} public case {i}", text))
        elif q.kind == "value" and not q.public and q.data is None:
            for text in _value_texts(q.expected()):
                out.append(Needle("hidden expected", f"{name} {q.id}", text))
        elif q.kind == "value" and q.data is None:  # shipped sealed, never in the clear
            for text in _value_texts(q.expected()):
                out.append(Needle("public expected", f"{name} {q.id}", text))
    if secret is not None:
        out.append(Needle("secret", "the instructor's key", secret.key.hex()))
        data_py = solution_dir / "data.py"
        if data_py.is_file() and checks.data_keys():
            source = data_py.read_text("utf-8")
            src_lines = source.splitlines()
            for node in ast.parse(source).body:
                if isinstance(node, ast.FunctionDef) and node.name in checks.data_keys():
                    body = "\n".join(src_lines[node.body[0].lineno - 1 : node.end_lineno])
                    for line in _distinctive_lines(body):
                        out.append(Needle("generator", f"{name} data.{node.name}", line))
    unique = {(n.kind, n.where, n.text): n for n in out}
    # a whole multi-line solution is never public: in a teaching notebook it is a leak
    return [
        n
        for n in unique.values()
        if n.kind == "secret" or (n.kind == "solution" and "\n" in n.text) or n.text not in public
    ]


# --------------------------------------------------------------------------------------
# scanning
# --------------------------------------------------------------------------------------
def _texts(name: str, data: bytes) -> Iterable[tuple[str, str]]:
    """(label, text) pairs of one file: nested archives opened, JSON read as its strings."""
    lower = name.lower()
    if lower.endswith((".zip", ".whl")):
        with zipfile.ZipFile(io.BytesIO(data)) as z:
            for info in z.infolist():
                if not info.is_dir():
                    yield from _texts(f"{name}!{info.filename}", z.read(info))
        return
    if lower.endswith((".tar.gz", ".tgz")):
        with tarfile.open(fileobj=io.BytesIO(data), mode="r:gz") as t:
            for member in t.getmembers():
                if member.isfile():
                    f = t.extractfile(member)
                    if f is not None:
                        yield from _texts(f"{name}!{member.name}", f.read())
        return
    if b"\0" in data[:4096]:
        return  # binary (an image, a compiled file)
    text = data.decode("utf-8", errors="replace")
    if lower.endswith((".ipynb", ".json")):
        try:
            content = json.loads(text)
        except ValueError:
            yield name, text
            return
        strings: list[str] = []

        def walk(x):
            if isinstance(x, str):
                strings.append(x)
            elif isinstance(x, list):
                if x and all(isinstance(s, str) for s in x):
                    strings.append("".join(x))  # a notebook's source as a list of lines
                else:
                    for v in x:
                        walk(v)
            elif isinstance(x, dict):
                for k, v in x.items():
                    strings.append(str(k))
                    walk(v)

        walk(content)
        text = "\n".join(strings)
    yield name, text


def _files(root: Path) -> Iterable[tuple[str, bytes]]:
    if root.is_file():
        yield root.name, root.read_bytes()
        return
    for path in sorted(root.rglob("*")):
        if path.is_file():
            yield path.relative_to(root).as_posix(), path.read_bytes()


def scan(roots: Iterable[Path], needles: list[Needle]) -> list[Hit]:
    """Every needle found in the files under ``roots`` (folders or archives), and every file
    named like the instructor's (``solutions/``, ``checks.py``)."""
    hits: list[Hit] = []
    found_in: dict[bytes, list[Needle]] = {}  # the same bytes (a file and its archived copy) once
    for root in roots:
        root = Path(root)
        prefix = "" if root.is_file() else f"{root.name}/"
        for name, data in _files(root):
            for label, text in _texts(name, data):
                found = _INSTRUCTOR_PATH.search(label)
                if found:
                    needle = Needle("file name", "the instructor's files", found.group(2))
                    hits.append(Hit(needle, prefix + label))
                key = hashlib.sha256(text.encode("utf-8", errors="replace")).digest()
                if key not in found_in:
                    flat = _norm(text)
                    found_in[key] = [n for n in needles if n.text in flat]
                hits.extend(Hit(n, prefix + label) for n in found_in[key])
    return hits
