"""The ``course`` command.

``course open``
    start Jupyter on the course notebooks (the course's main entry point).
``course release`` and ``course grade``
    the instructors' exercise commands (see :mod:`course.exercises`).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent


def _open(args) -> int:
    target = Path(args.path) if args.path else REPO_ROOT / "notebooks"
    if not target.exists():
        print(f"course open: {target} does not exist; run it from a clone of the course", file=sys.stderr)
        return 2
    jupyter = shutil.which("jupyter")
    if jupyter is None:
        print(
            "course open: Jupyter is not installed; install the course with "
            "`python -m pip install -e \".[all]\"`",
            file=sys.stderr,
        )
        return 2
    command = [jupyter, args.app, *( ["--no-browser"] if args.no_browser else [])]
    print(f"Opening the course in Jupyter {args.app} at {target} (Ctrl-C to stop)")
    return subprocess.call(command, cwd=target if target.is_dir() else target.parent)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="course", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)

    p_open = sub.add_parser("open", help="open the course notebooks in Jupyter")
    p_open.add_argument("path", nargs="?", help="folder to open (default: the course's notebooks/)")
    p_open.add_argument("--app", default="lab", choices=["lab", "notebook"], help="Jupyter front end")
    p_open.add_argument("--no-browser", action="store_true", help="do not launch a browser")
    p_open.set_defaults(func=_open)

    try:
        from course.exercises import cli as exercise_cli
    except ImportError:
        exercise_cli = None
    if exercise_cli is not None:
        exercise_cli.add_commands(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    return int(args.func(args) or 0)


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
