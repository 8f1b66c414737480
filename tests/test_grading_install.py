"""A real non-editable install (``pip install .``, not ``-e``): the package then lives in
site-packages, far from any course folder, and `course release` / `course grade` must still work
from a course folder (found through the working directory, ``--course-dir`` or ``COURSE_DIR``,
never through the package's own location).

The fresh venv gets the course package only (``--no-deps``); numpy & co. come from the test
run's own environment through a path entry (not a site dir, so its editable-install hooks do
not load and cannot shadow the installed package).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NAME = "01_least_squares"


def _venv(tmp: Path) -> tuple[Path, str]:
    venv = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    purelib = subprocess.run(
        [
            str(venv / "bin" / "python"),
            "-c",
            "import sysconfig; print(sysconfig.get_paths()['purelib'])",
        ],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    (Path(purelib) / "_test_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    return venv, purelib


@pytest.mark.slow  # a fresh install or a whole grading run
def test_non_editable_install_grades_from_a_course_folder(tmp_path):
    venv, purelib = _venv(tmp_path)
    python = venv / "bin" / "python"
    source = tmp_path / "src"
    shutil.copytree(
        ROOT,
        source,
        ignore=shutil.ignore_patterns(".git", "*.egg-info", "build", "__pycache__", "notebooks"),
    )
    install = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps"]
        # --target, not --prefix: pip must not touch the running environment's own install
        + ["--target", purelib, str(source)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert install.returncode == 0, install.stderr[-3000:]
    where = subprocess.run(
        [str(python), "-c", "import course, os; print(os.path.dirname(course.__file__))"],
        capture_output=True,
        text=True,
        check=True,
        cwd=tmp_path,
    ).stdout.strip()
    assert "site-packages" in where and not where.startswith(str(ROOT)), where
    assert (Path(where) / "data" / "sea_level_mude" / "Dataset_0.txt").is_file()  # package data

    # a course folder elsewhere, and a submission
    course_dir = tmp_path / "my-course"
    shutil.copytree(ROOT / "solutions" / NAME, course_dir / "solutions" / NAME)
    subs = course_dir / "submissions"
    subs.mkdir()
    shutil.copy(ROOT / "solutions" / NAME / f"{NAME}.ipynb", subs / "alice.ipynb")
    env = {k: v for k, v in os.environ.items() if k not in ("COURSE_DIR", "PYTHONPATH")}
    course = [str(python), "-m", "course"]

    released = subprocess.run(
        [*course, "release", NAME],
        cwd=course_dir / "submissions",
        env=env,
        capture_output=True,
        text=True,
    )
    assert released.returncode == 0, released.stderr  # found from a sub-folder of the course
    assert (course_dir / "exercises" / NAME / "checks.json").is_file()

    graded = subprocess.run(
        [*course, "grade", NAME, str(subs), "--out", str(tmp_path / "out"), "--no-progress"],
        cwd=tmp_path,  # not inside the course folder: COURSE_DIR tells where it is
        env=dict(env, COURSE_DIR=str(course_dir)),
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert graded.returncode == 0, graded.stderr[-3000:]
    row = json.loads((tmp_path / "out" / "results.jsonl").read_text())
    assert row["student"] == "alice" and row["total"] == row["max"] > 0, row

    missing = subprocess.run(
        [*course, "grade", NAME, str(subs), "--out", str(tmp_path / "out2")],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
    )
    assert missing.returncode == 2 and "no assignment" in missing.stderr  # not from site-packages
