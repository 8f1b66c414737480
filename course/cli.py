"""The ``course`` command: open the course notebooks, release and grade assignments.

``course open``
    start Jupyter on the course notebooks (the course's main entry point).
``course docs OUT_DIR``
    build the course website (notebooks, API reference, guides) into OUT_DIR.
``course release``, ``course grade``, ``course export``, ``course secret``
    the instructors' exercise commands (see :mod:`course.grading`);
``course submit``
    write a student's notebook as the file to upload.

``python -m course`` is the same command.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent


def _default_notebooks() -> Path | None:
    # A clone's notebooks/ next to the working directory wins, so `course open` also works
    # from a clone when the package was installed without -e (then REPO_ROOT is site-packages).
    for folder in (Path.cwd(), *Path.cwd().parents):
        if (folder / "notebooks").is_dir() and (folder / "course").is_dir():
            return folder / "notebooks"
    if (REPO_ROOT / "notebooks").is_dir():
        return REPO_ROOT / "notebooks"
    return None


def _student_workdir(args) -> Path | None:
    """The student edition: copy the packaged course into the working folder (chosen on first
    open, then remembered) and return it; None when this install carries no materials."""
    from course import workspace

    materials = workspace.packaged_materials()
    if materials is None:
        return None
    chosen = args.workdir or workspace.remembered_workdir()
    if chosen is None:
        suggestion = workspace.default_workdir()
        chosen = suggestion
        if sys.stdin.isatty():
            answer = input(
                f"Where should the course keep your notebooks and your work? [{suggestion}] "
            ).strip()
            chosen = Path(answer).expanduser() if answer else suggestion
    folder = Path(chosen).expanduser().resolve()
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"{folder} is a file, not a folder; choose another with --workdir")
    first = not folder.exists()
    added, refreshed = workspace.prepare_workdir(folder, materials)
    workspace.remember_workdir(folder)
    if first:
        print(f"Copied the course into {folder}: your work is saved there.")
    elif added or refreshed:
        print(
            f"Updated {folder}: {len(added)} new file(s), {len(refreshed)} course file(s) "
            "refreshed; your notebooks were not touched."
        )
    return folder


def _jupyter_command(app: str):
    """The Jupyter front end of THIS interpreter (not whatever ``jupyter`` is first on PATH)."""
    from importlib.util import find_spec

    module = "jupyterlab" if app == "lab" else "notebook"
    if find_spec(module) is None:
        return None
    return [sys.executable, "-m", module]


def _open(args) -> int:
    target: Path | None
    if args.path:
        target = Path(args.path).resolve()
    else:
        target = _default_notebooks() if args.workdir is None else None
        if target is None:
            try:
                target = _student_workdir(args)
            except (OSError, ValueError) as exc:
                print(f"course open: {exc}", file=sys.stderr)
                return 2
        if target is None:
            print(
                "course open: no course notebooks here; run it from a clone of the course, "
                "install the student edition (`pip install <course wheel>`), or pass a folder",
                file=sys.stderr,
            )
            return 2
    if not target.exists():
        print(
            f"course open: {target} does not exist; run it from a clone of the course "
            "(or pass the folder of the notebooks)",
            file=sys.stderr,
        )
        return 2
    command = _jupyter_command(args.app)
    if command is None:
        front_end, package = (
            ("Lab", "jupyterlab") if args.app == "lab" else ("Notebook", "notebook")
        )
        print(
            f"course open: Jupyter {front_end} is not installed for {sys.executable}; install it "
            f"with `{Path(sys.executable).name} -m pip install {package}`",
            file=sys.stderr,
        )
        return 2
    folder = target if target.is_dir() else target.parent
    command += ["--no-browser"] if args.no_browser else []
    command += list(getattr(args, "jupyter_args", []))
    if target.is_file():
        command.append(target.name)  # open that notebook, rooted at its folder
    print(f"Opening the course in Jupyter {args.app} at {target} (Ctrl-C to stop)")
    return subprocess.call(command, cwd=folder)


def _docs(args) -> int:
    from course.docsite import build_site

    try:
        report = build_site(
            args.out_dir,
            cache_dir=args.cache,
            jobs=args.jobs,
            lite=not args.no_lite,
            stored_outputs=args.stored_outputs,
        )
    except (RuntimeError, FileNotFoundError, ValueError) as error:
        print(f"course docs: {error}", file=sys.stderr)
        return 1
    print(report.summary())
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="course",
        description=__doc__.split("\n\n")[0].replace("``", ""),
        epilog="examples: course open | course release 01_least_squares | "
        "course grade 01_least_squares submissions/ --out grading-output/",
    )
    from course import __version__

    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    p_open = sub.add_parser(
        "open",
        help="open the course notebooks in Jupyter",
        description="Start JupyterLab (or the classic Notebook) on the course's notebooks/ folder; "
        "begin with 01_least_squares_validation.ipynb. Stop it with Ctrl-C. Options that "
        "course does not know are passed on to Jupyter in either form (--port 8890 or "
        "--port=8890, --ip 0.0.0.0, --allow-root).",
    )
    p_open.add_argument(
        "path",
        nargs="?",
        help="folder or notebook to open (default: notebooks/ of the course clone, or your "
        "working folder in the student edition)",
    )
    p_open.add_argument(
        "--app", default="lab", choices=["lab", "notebook"], help="Jupyter front end"
    )
    p_open.add_argument("--no-browser", action="store_true", help="do not launch a browser")
    p_open.add_argument(
        "--workdir",
        type=Path,
        default=None,
        help="student edition: the folder for your notebooks and work (asked on first open, "
        "then remembered; default ~/residual-validation-course)",
    )
    p_open.set_defaults(func=_open)

    p_docs = sub.add_parser(
        "docs",
        help="build the course website into a folder",
        description="Build the course website (executed notebooks, API reference, guides, "
        "an in-browser JupyterLite) into OUT_DIR; open OUT_DIR/index.html, or serve the folder "
        "over http (python -m http.server --directory OUT_DIR) for the in-browser notebooks, "
        "which browsers do not start from a file:// page. Needs the docs "
        'extra (python -m pip install -e ".[docs]"). Executed notebooks are cached, so a '
        "rebuild runs only the notebooks whose code changed. Sphinx warnings are errors.",
    )
    p_docs.add_argument("out_dir", help="folder to write the site into")
    p_docs.add_argument(
        "--cache", help="folder for executed notebooks between builds (default .cache/docs)"
    )
    p_docs.add_argument("--jobs", type=int, default=1, help="parallel Sphinx processes")
    p_docs.add_argument("--no-lite", action="store_true", help="skip the JupyterLite app")
    p_docs.add_argument(
        "--stored-outputs",
        action="store_true",
        help="show the outputs saved in the teaching notebooks instead of running them "
        "(the test suite checks that a fresh run reproduces them)",
    )
    p_docs.set_defaults(func=_docs)

    try:
        from course.grading import cli as grading_cli
    except ImportError:  # the library without its grader: `course open` only
        pass
    else:
        grading_cli.add_commands(sub)
    return parser


# Jupyter's own switches that take no value (``jupyter lab --help-all``, jupyter_server, jupyterlab
# and notebook 7); any other option Jupyter gets in the space form (``--port 8899``) takes the
# next word as its value, as traitlets parses it.
JUPYTER_FLAGS = frozenset(
    {
        "allow-root", "autoreload", "collaborative", "core-mode", "custom-css", "debug",
        "dev-mode", "expose-app-in-browser", "extensions-in-dev-mode", "generate-config",
        "no-browser", "no-mathjax", "no-script", "script", "show-config", "show-config-json",
        "skip-dev-build", "splice-source", "watch", "y",
    }
)  # fmt: skip

# The subcommands that start Jupyter and pass the options they do not know on to it.
PASSES_ON_TO_JUPYTER = ("open", "mark")


def split_jupyter_args(
    command: argparse.ArgumentParser, words: list[str]
) -> tuple[list[str], list[str]]:
    """Split a subcommand's words into its own and Jupyter's, each option with its value.

    An option ``command`` does not define goes to Jupyter with the word after it when it is
    written ``--port 8899`` (a value that does not look like an option) and is not one of
    Jupyter's value-less switches, so the value is never taken for the subcommand's folder.
    """
    own_options = command._option_string_actions
    ours: list[str] = []
    theirs: list[str] = []
    i = 0
    while i < len(words):
        word = words[i]
        following = words[i + 1] if i + 1 < len(words) else None
        takes_next = following is not None and not following.startswith("-") and "=" not in word
        if word == "--":  # everything after belongs to the subcommand
            ours += words[i:]
            break
        if not word.startswith("-") or word == "-":
            ours.append(word)
        elif word.split("=", 1)[0] in own_options:
            action = own_options[word.split("=", 1)[0]]
            ours.append(word)
            if action.nargs != 0 and takes_next:
                ours.append(following)  # type: ignore[arg-type]
                i += 1
        else:
            theirs.append(word)
            if takes_next and word.lstrip("-") not in JUPYTER_FLAGS:
                theirs.append(following)  # type: ignore[arg-type]
                i += 1
        i += 1
    return ours, theirs


def main(argv=None) -> int:
    parser = build_parser()
    words = list(sys.argv[1:] if argv is None else argv)
    subcommands = next(
        action for action in parser._actions if isinstance(action, argparse._SubParsersAction)
    )
    jupyter_args: list[str] = []
    for at, word in enumerate(words):
        if not word.startswith("-"):  # the subcommand: the first word that is not an option
            if word in PASSES_ON_TO_JUPYTER and word in subcommands.choices:
                own, jupyter_args = split_jupyter_args(subcommands.choices[word], words[at + 1 :])
                words = [*words[: at + 1], *own]
            break
    args = parser.parse_args(words)
    args.jupyter_args = jupyter_args
    return int(args.func(args) or 0)


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
