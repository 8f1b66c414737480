"""The student edition's wheel and sdist, written by ``course export`` itself (not a build
backend), meet the packaging specifications: METADATA by ``packaging``'s validator, WHEEL and
RECORD by the wheel specification (PEP 427/376), and pip installs the wheel offline.

Seconds and offline, so a move of the specifications shows here and not only in the
network-bound journey test (tests/test_journey.py).
"""

from __future__ import annotations

import base64
import csv
import email.parser
import hashlib
import io
import os
import subprocess
import sys
import tarfile
import venv
import zipfile
from pathlib import Path

import pytest

packaging_metadata = pytest.importorskip("packaging.metadata")
from packaging.utils import parse_sdist_filename, parse_wheel_filename  # noqa: E402

from course import __version__  # noqa: E402
from course.grading.authoring import export as ex  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def archives(tmp_path_factory):
    """The wheel and sdist of a stub edition, with the project's real metadata."""
    tmp = tmp_path_factory.mktemp("archives")
    folder = tmp / "edition"
    (folder / "course").mkdir(parents=True)
    (folder / "course" / "__init__.py").write_text(f'__version__ = "{__version__}"\n')
    (folder / "course" / "cli.py").write_text("def main():\n    return 0\n")
    (folder / "LICENSE").write_text((ROOT / "LICENSE").read_text(encoding="utf-8"))
    meta = ex._distribution_metadata(ex._project_metadata(ROOT), __version__)
    readme = ex._student_readme(ROOT, True)
    return (
        meta,
        ex._write_wheel(folder, tmp, meta, readme),
        ex._write_sdist(folder, tmp, meta, readme),
    )


def _validated(raw: bytes):
    return packaging_metadata.Metadata.from_email(raw, validate=True)


def test_the_metadata_passes_packagings_validator(archives):
    meta, wheel, sdist = archives
    with zipfile.ZipFile(wheel) as z:
        dist_info = next(n.split("/")[0] for n in z.namelist() if n.endswith(".dist-info/METADATA"))
        metadata = _validated(z.read(f"{dist_info}/METADATA"))
    assert str(metadata.name) == ex.DIST_NAME and str(metadata.version) == __version__
    assert [str(r) for r in metadata.requires_dist or []] == meta["dependencies"]
    with tarfile.open(sdist) as tar:
        pkg_info = tar.extractfile(f"{dist_info.removesuffix('.dist-info')}/PKG-INFO")
        assert pkg_info is not None
        assert _validated(pkg_info.read()).version == metadata.version


def test_the_file_names_follow_the_specifications(archives):
    _, wheel, sdist = archives
    name, version, build, tags = parse_wheel_filename(wheel.name)
    assert (name, str(version), build) == (ex.DIST_NAME, __version__, ())
    assert {str(t) for t in tags} == {"py3-none-any"}
    assert parse_sdist_filename(sdist.name) == (name, version)


def test_wheel_and_record_follow_the_wheel_specification(archives):
    _, wheel, _ = archives
    with zipfile.ZipFile(wheel) as z:
        names = z.namelist()
        dist_info = next(n.split("/")[0] for n in names if n.endswith(".dist-info/WHEEL"))
        fields = email.parser.BytesParser().parsebytes(z.read(f"{dist_info}/WHEEL"))
        assert fields["Wheel-Version"] == "1.0" and fields["Root-Is-Purelib"] == "true"
        assert fields.get_all("Tag") == ["py3-none-any"]
        rows = list(csv.reader(io.StringIO(z.read(f"{dist_info}/RECORD").decode("utf-8"))))
        recorded = {row[0]: row for row in rows}
        # every file is recorded once, RECORD itself without a hash
        assert sorted(recorded) == sorted(names) and len(rows) == len(names)
        assert recorded[f"{dist_info}/RECORD"][1:] == ["", ""]
        for name in names:
            if name == f"{dist_info}/RECORD":
                continue
            data = z.read(name)
            algorithm, _, digest = recorded[name][1].partition("=")
            expected = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=")
            assert algorithm == "sha256" and digest == expected.decode(), name
            assert int(recorded[name][2]) == len(data), name


def test_pip_installs_the_wheel_offline(archives, tmp_path):
    _, wheel, _ = archives
    env = tmp_path / "venv"
    venv.create(env, with_pip=False)  # this pip installs into it (--python): seconds, offline
    python = env / "bin" / "python"
    subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(python), "install", "--quiet"]
        + ["--no-deps", "--no-index", str(wheel)],
        check=True,
        timeout=300,
    )
    probe = (
        "import importlib.metadata as m, course; "
        f"print(m.version({ex.DIST_NAME!r}), course.__version__, course.__file__, "
        "[e.value for e in m.entry_points(group='console_scripts', name='course')])"
    )
    clean = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    out = subprocess.run(
        [python, "-c", probe],
        check=True,
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
        env=clean,
    ).stdout.split()
    assert out[:2] == [__version__, __version__]
    assert Path(out[2]).is_relative_to(env), out[2]  # the installed copy, not the clone's
    assert "course.cli:main" in out[3]
