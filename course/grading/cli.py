"""The instructors' subcommands ``course release``, ``grade``, ``gradebook``, ``feedback``,
``mark``, ``export`` and ``secret``, and the students' ``course submit`` (hooked into :mod:`course.cli`)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from course.grading.vocabulary import visible_text

#: Where `course release` and `course grade` look for solutions/ and exercises/.
COURSE_DIR_HELP = (
    "the course folder holding solutions/ and exercises/ (default: $COURSE_DIR, else the "
    "working folder or the nearest parent that has one of them)"
)


def find_course_dir(explicit: str | None = None) -> Path:
    """The course folder: ``--course-dir``, then ``$COURSE_DIR``, then the working folder and
    its parents (the first holding ``solutions/`` or ``exercises/``), else the working folder.

    Never the package's own location: installed without ``-e`` the package lives in
    site-packages, far from any course folder.
    """
    if explicit:
        return Path(explicit).expanduser().resolve()
    if os.environ.get("COURSE_DIR"):
        return Path(os.environ["COURSE_DIR"]).expanduser().resolve()
    here = Path.cwd().resolve()
    for folder in (here, *here.parents):
        if (folder / "solutions").is_dir() or (folder / "exercises").is_dir():
            return folder
    return here


def _folder(args, name: str) -> Path:
    explicit = getattr(args, name, None)
    return Path(explicit) if explicit else find_course_dir(args.course_dir) / name


def _release(args) -> int:
    from course.grading.authoring.release import find_solutions, release
    from course.grading.notebook import MarkerError

    solutions = _folder(args, "solutions")
    exercises = _folder(args, "exercises")
    names = find_solutions(solutions) if args.all else list(args.names)
    if not names:
        print(
            "course release: name an assignment (e.g. `course release 01_least_squares`) or use --all; "
            f"assignments in {solutions}: {', '.join(find_solutions(solutions)) or 'none'}",
            file=sys.stderr,
        )
        return 2
    status = 0
    for name in names:
        name = Path(name).name  # accept solutions/<name>/ too
        if not (solutions / name / "checks.py").is_file():
            print(
                f"course release: no assignment {name!r} in {solutions} (expected {solutions / name}/checks.py)",
                file=sys.stderr,
            )
            status = 2
            continue
        try:
            written = release(name, solutions, exercises)
        except (MarkerError, ValueError, FileNotFoundError, SyntaxError, ImportError) as exc:
            print(f"course release: {name}: {exc}", file=sys.stderr)
            status = 1
            continue
        print(
            f"released {name}: "
            + ", ".join(
                str(p.relative_to(exercises)) if p.is_relative_to(exercises) else str(p)
                for p in written
            )
        )
    return status


def _grade(args) -> int:
    _limit_blas_threads()
    from course.grading.batch.cluster import ClusterError, ConnectionFiles
    from course.grading.batch.driver import SelectionError, grade
    from course.grading.batch.intake import IntakeError
    from course.grading.batch.late import LateError, parse_due, parse_policy
    from course.grading.batch.marks import MarksError
    from course.grading.batch.options import GradeOptions, available_cpus
    from course.grading.sandbox.isolation import IsolationError

    solutions = _folder(args, "solutions")
    name = Path(args.assignment).name
    solution_dir = (
        Path(args.assignment)
        if (Path(args.assignment) / "checks.py").is_file()
        else solutions / name
    )
    if not (solution_dir / "checks.py").is_file():
        print(
            f"course grade: no assignment {name!r} (looked for {solution_dir}/checks.py)",
            file=sys.stderr,
        )
        return 2
    submissions = Path(args.submissions)
    if not (submissions.is_dir() or submissions.suffix.lower() == ".zip"):
        print(
            f"course grade: {submissions} is neither a folder of submissions nor an LMS's "
            "download (.zip)",
            file=sys.stderr,
        )
        return 2
    try:
        late_options = {
            "due": parse_due(args.due) if args.due else None,
            "late_policy": parse_policy(args.late_policy) if args.late_policy else None,
            "submitted_at": args.submitted_at,
            "extensions": Path(args.extensions) if args.extensions else None,
        }
    except LateError as exc:
        print(f"course grade: {exc}", file=sys.stderr)
        return 2
    class_options = _class_options(args)
    if class_options is None:
        return 2
    options = GradeOptions(
        **late_options,
        **class_options,
        jobs=args.jobs or available_cpus(),
        timeout=args.timeout,
        memory_mb=args.memory,
        regrade=args.regrade,
        progress=not args.no_progress,
        unsafe_no_isolation=args.unsafe_no_isolation,
        cluster=args.cluster,
        cluster_files=ConnectionFiles(
            *(Path(f) if f else None for f in (args.tls_ca_file, args.tls_cert, args.tls_key))
        ),
        insecure_cluster=args.insecure_cluster,
        announce=lambda text: print(text, file=sys.stderr),
        short_answers=Path(args.short_answers) if args.short_answers else None,
        students=frozenset(args.student) if args.student else None,
    )
    try:
        summary = grade(solution_dir, submissions, Path(args.out), options)
    except IsolationError as exc:
        print(f"course grade: refusing to run: {exc}", file=sys.stderr)
        return 2
    except (MarksError, SelectionError, LateError, ClusterError, IntakeError) as exc:
        print(f"course grade: {exc}", file=sys.stderr)
        return 2
    except RuntimeError as exc:
        if args.cluster and "distributed" in str(exc):
            print(f"course grade: {exc}", file=sys.stderr)
            return 2
        raise
    print(summary.text())
    return 1 if summary.not_graded else 0  # a fault of the grader is no finished run


def _limit_blas_threads() -> None:
    """One BLAS thread for the grading parent, set before numpy is first imported: its own
    linear algebra is the references' and named mistakes' tiny calls, around which an
    OpenBLAS worker pool only spins (a quarter of a class's CPU). The sandbox's children get
    their own environment (one thread too)."""
    if "numpy" in sys.modules:
        return
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[name] = "1"


def _history(args) -> int:
    from course.grading.batch.record import RECORD_FILE, Record

    out = Path(args.out_dir)
    if not (out / RECORD_FILE).is_file():
        print(
            f"course history: {out} holds no {RECORD_FILE} (the --out folder of `course grade`)",
            file=sys.stderr,
        )
        return 2
    with Record(out) as record:
        events = record.history(args.student)
        files = record.submissions(args.student)
    if not events and not files:
        print(f"course history: nothing recorded for {args.student!r} in {out}", file=sys.stderr)
        return 2
    print(f"History of {visible_text(args.student)} in {out}:")
    for _sid, name, sha, _origin, reason in files:
        print(f"  file {visible_text(name)} sha256 {(sha or '?')[:12]}: {visible_text(reason)}")
    for at, who, kind, question, change in events:
        what = f"{kind} {question}".strip()
        print(f"  {at}  {visible_text(who):<20} {what:<10} {visible_text(change)}")
    return 0


def _class_options(args) -> dict | None:
    """The secret and the roster of ``course grade`` (None after printing why not)."""
    from course.grading.authoring.secret import SECRET_ENV, SecretError, load_secret
    from course.grading.batch.roster import RosterError, read_roster

    try:
        secret = None if args.no_secret else load_secret(args.secret)
        roster = read_roster(args.roster) if args.roster else None
    except (SecretError, RosterError) as exc:
        print(f"course grade: {exc}", file=sys.stderr)
        return None
    if roster is not None and secret is None and not args.no_secret:
        print(
            "course grade: --roster without the class's secret: the students of an edition "
            "exported with --secret worked on personal data drawn with that key, and without it "
            "their personal questions would be graded against public data instead. Pass "
            f"--secret FILE (or set {SECRET_ENV}), or --no-secret for a class whose edition was "
            "exported with --no-secret.",
            file=sys.stderr,
        )
        return None
    print(
        "personal data: "
        + (
            f"drawn with the secret {secret.key_id} ({secret.source})"
            if secret is not None
            else "public generators (no secret)"
        ),
        file=sys.stderr,
    )
    return {
        "secret": secret,
        "roster": roster,
        "missing_as_zero": args.missing_as_zero,
        "lms_column": args.lms_column,
    }


def _gradebook(args) -> int:
    from course.grading.batch.gradebook import GradebookError, read_gradebook, write_gradebook
    from course.grading.batch.roster import RosterError, read_roster
    from course.grading.batch.termrules import TermError, read_term

    try:
        roster = read_roster(args.roster) if args.roster else None
        rules = read_term(args.rules) if args.rules else None
        book = read_gradebook([Path(p) for p in args.outs])
        written = write_gradebook(book, Path(args.out), roster, args.missing_as_zero, rules)
    except (GradebookError, RosterError, TermError) as exc:
        print(f"course gradebook: {exc}", file=sys.stderr)
        return 2
    columns = ", ".join(f"{c.name} ({c.max_points:g})" for c in book.columns)
    print(f"Gradebook of {len(book.columns)} assignment(s): {columns}")
    print("Wrote " + ", ".join(str(p) for p in written))
    unmarked = book.unmarked()
    if unmarked:
        print(
            f"WARNING: {sum(unmarked.values())} short answer(s) NOT marked yet count as 0 ("
            + ", ".join(f"{name}: {n}" for name, n in unmarked.items())
            + "); mark them (course mark OUT_DIR), merge them (course grade … --short-answers), "
            "then build the gradebook again"
        )
    return 0


def _feedback(args) -> int:
    from course.grading.batch.lmsfeedback import write_feedback_zip

    try:
        written = write_feedback_zip(Path(args.out_dir), args.lms)
    except (ValueError, OSError) as exc:
        print(f"course feedback: {exc}", file=sys.stderr)
        return 2
    print(f"Wrote {written.path}: feedback for {len(written.names)} student(s)")
    if written.left_out:
        print(
            f"Not in it ({len(written.left_out)}): "
            + "; ".join(f"{sid}: {why}" for sid, why in sorted(written.left_out.items()))
        )
    return 0


def _mark(args) -> int:
    import subprocess
    from importlib.util import find_spec

    from course.grading.batch.marking import write_marking_notebook
    from course.grading.batch.marks import MarksError

    try:
        notebook = write_marking_notebook(Path(args.out_dir))
    except MarksError as exc:
        print(f"course mark: {exc}", file=sys.stderr)
        return 2
    if args.no_open:
        print(f"Marking notebook: {notebook} (open it in Jupyter and run its cell)")
        return 0
    module = "jupyterlab" if args.app == "lab" else "notebook"
    if find_spec(module) is None or find_spec("ipywidgets") is None:
        print(
            f"course mark: the marking view needs {module} and ipywidgets for {sys.executable} "
            '(pip install -e ".[notebooks]"); the notebook is ready at ' + str(notebook),
            file=sys.stderr,
        )
        return 2
    command = [sys.executable, "-m", module, notebook.name]
    command += ["--no-browser"] if args.no_browser else []
    command += list(getattr(args, "jupyter_args", []))
    print(f"Opening {notebook} in Jupyter {args.app} (Ctrl-C to stop)")
    return subprocess.call(command, cwd=notebook.parent)


def _add_mark_command(subparsers) -> None:
    p_mark = subparsers.add_parser(
        "mark",
        help="mark the short answers of a graded assignment in Jupyter",
        description="Write OUT_DIR/marking.ipynb (unless it exists) and open it in JupyterLab: "
        "a view of the short answers in OUT_DIR's record that shows one answer at a time, "
        "anonymous by default, with the rubric, a points box and a comment box; alike answers come in groups that can be marked at once. Every mark is "
        "saved into the record (OUT_DIR/record.sqlite, with the marker and the time) and "
        "OUT_DIR/short_answers.csv at once; the next `course grade NAME SUBMISSIONS --out "
        "OUT_DIR` merges them into the grades. Options that course does not know (e.g. --port 8890, "
        "--ip 0.0.0.0, --allow-root) are passed on to Jupyter.",
    )
    p_mark.add_argument("out_dir", metavar="OUT_DIR", help="the --out folder of `course grade`")
    p_mark.add_argument(
        "--app", default="lab", choices=["lab", "notebook"], help="Jupyter front end"
    )
    p_mark.add_argument(
        "--no-browser", action="store_true", help="start Jupyter without opening a browser"
    )
    p_mark.add_argument(
        "--no-open", action="store_true", help="only write the notebook (do not start Jupyter)"
    )
    p_mark.set_defaults(func=_instructor_only(_mark))


def _export(args) -> int:
    from course.grading.authoring.export import ExportError, export
    from course.grading.authoring.secret import SecretError, load_secret
    from course.grading.batch.roster import RosterError, read_roster

    try:
        secret = None if args.no_secret else load_secret(args.secret)
        roster = read_roster(args.roster) if args.roster else None
        result = export(
            args.dest,
            root=find_course_dir(args.course_dir),
            secret=secret,
            roster=roster,
            id_pattern=args.id_pattern,
        )
    except (ExportError, SecretError, RosterError, OSError) as exc:
        print(f"course export: {exc}", file=sys.stderr)
        return 2
    if secret is None:
        print(
            "course export: no instructor secret: personal data come from the public data.py, "
            "so students can rebuild the truth behind personal questions (fine for "
            "self-learners; for a graded class pass --secret and --roster)",
            file=sys.stderr,
        )
    print(f"exported the student edition into {result.dest}:")
    for path in result.artefacts:
        print(f"  {path.name}{'/' if path.is_dir() else ''}")
    print(
        f"personal data: {result.data_key}"
        + (f", {result.students} students" if result.students else "")
        + "; nothing of solutions/ found in any file (see EXPORT.md)"
    )
    return 0


def _submit(args) -> int:
    from course.grading.authoring.personal import PersonalData
    from course.grading.student.submit import Refused, make_submission, unanswered_questions
    from course.grading.vocabulary import id_pattern_in

    notebook = Path(args.notebook)
    if not notebook.is_file():
        print(f"course submit: {notebook} is not a file", file=sys.stderr)
        return 2
    try:
        personal = PersonalData.read(notebook.parent)
        path, digest, nb = make_submission(
            notebook,
            args.id,
            None,
            Path(args.out) if args.out else None,
            personal,
            id_pattern_in(notebook.parent),
        )
    except (Refused, ValueError) as exc:
        print(f"course submit: not submitted: {exc}", file=sys.stderr)
        return 2
    missing = unanswered_questions(nb)
    if missing:
        print(f"not answered: {', '.join(missing)}")
    print(
        f"wrote {path} (sha256 {digest[:16]}…). The self-checks run in the notebook "
        "(check.submit()); upload this file to your course's assignment page."
    )
    return 0


def _secret(args) -> int:
    from course.grading.authoring.secret import SecretError, load_secret, new_secret

    try:
        secret = new_secret(args.file) if args.action == "new" else load_secret(args.file)
    except SecretError as exc:
        print(f"course secret: {exc}", file=sys.stderr)
        return 2
    if secret is None:
        print(
            "course secret: no key file given and $COURSE_SECRET_FILE is not set", file=sys.stderr
        )
        return 2
    verb = "created" if args.action == "new" else "read"
    print(f"{verb} {secret.source}: key id {secret.key_id} (keep the file private; back it up)")
    return 0


def _add_class_commands(subparsers) -> None:
    """``course export``, ``course submit`` and ``course secret`` (the student distribution)."""
    p_ex = subparsers.add_parser(
        "export",
        help="build the student distribution (folder, zip, wheel, sdist) without solutions",
        description="Write into DEST (new or empty) what students receive: the library, the "
        "teaching notebooks, the released exercises and a student README, as a folder, a zip, "
        "a wheel and an sdist. Nothing of solutions/; every file is scanned before it is "
        "handed over. For a graded class give --secret and --roster: students then get their "
        "personal data, not the generators.",
    )
    p_ex.add_argument("dest", metavar="DEST", help="output folder (must not exist, or be empty)")
    p_ex.add_argument(
        "--secret",
        default=None,
        help="the class's key file (default: $COURSE_SECRET_FILE; make one with `course secret new`)",
    )
    p_ex.add_argument(
        "--no-secret",
        action="store_true",
        help="ignore $COURSE_SECRET_FILE: a self-learner edition",
    )
    p_ex.add_argument("--roster", default=None, help="CSV of the class (id, name, email)")
    p_ex.add_argument(
        "--id-pattern",
        default=None,
        metavar="REGEX",
        help="the form of this class's student IDs, a regular expression a whole ID matches "
        "(e.g. 's[0-9]{6}'): the self-check says when STUDENT_ID does not match it and "
        "check.submit() refuses it; every roster ID must match",
    )
    p_ex.add_argument("--course-dir", help=COURSE_DIR_HELP)
    p_ex.set_defaults(func=_instructor_only(_export))

    p_sub = subparsers.add_parser(
        "submit",
        help="write <ID>_<assignment>.ipynb from a saved assignment notebook, ready to upload",
        description="Check the student ID of a saved assignment notebook and write "
        "<ID>_<assignment>.ipynb beside it (with the ID in its metadata). In the notebook, "
        "check.submit() does the same after running every self-check.",
    )
    p_sub.add_argument("notebook", metavar="NOTEBOOK", help="the saved assignment notebook")
    p_sub.add_argument(
        "--id", default=None, help="student ID (default: STUDENT_ID in the notebook)"
    )
    p_sub.add_argument("--out", default=None, help="folder to write to (default: beside NOTEBOOK)")
    p_sub.set_defaults(func=_submit)

    p_sec = subparsers.add_parser(
        "secret",
        help="make (or check) the instructor's key file of a graded class",
        description="`course secret new FILE` writes a new random key (mode 0600; never "
        "overwrites). `course secret show [FILE]` prints its public key id. Keep the file "
        "outside the course folder; grade and export with --secret FILE or "
        "COURSE_SECRET_FILE=FILE.",
    )
    p_sec.add_argument("action", choices=["new", "show"])
    p_sec.add_argument("file", metavar="FILE", nargs="?", default=None)
    p_sec.set_defaults(func=_secret)


def _instructor_only(command):
    """``command``, or a clear refusal where the grader's rooms are not installed (the student
    edition ships without ``course.grading.batch`` and ``course.grading.sandbox``)."""

    def run(args) -> int:
        try:
            return command(args)
        except ModuleNotFoundError as exc:
            rooms = ("course.grading.batch", "course.grading.sandbox")
            if not (exc.name or "").startswith(rooms):
                raise
            print(
                f"course {args.command}: this is the student edition, which has no grader; "
                "grading and exports are done from the instructor's clone of the course",
                file=sys.stderr,
            )
            return 2

    return run


def add_commands(subparsers) -> None:
    """Add ``release`` and ``grade`` to the ``course`` command's subparsers."""
    p_rel = subparsers.add_parser(
        "release",
        help="generate student notebooks in exercises/ from solutions/",
        description="Write exercises/<name>/ (student notebook with stubs, public checks.json, data.py) "
        "from solutions/<name>/. Fails on malformed markers.",
    )
    p_rel.add_argument(
        "names", nargs="*", metavar="NAME", help="assignment(s) to release, e.g. 01_least_squares"
    )
    p_rel.add_argument(
        "--all", action="store_true", help="release every assignment under solutions/"
    )
    p_rel.add_argument("--course-dir", help=COURSE_DIR_HELP)
    p_rel.add_argument("--solutions", help="authoring folder (default: COURSE_DIR/solutions)")
    p_rel.add_argument("--exercises", help="output folder (default: COURSE_DIR/exercises)")
    p_rel.set_defaults(func=_release)

    p_gr = subparsers.add_parser(
        "grade",
        help="grade a folder of submitted notebooks in a sandbox",
        description="Grade SUBMISSIONS (one <id>.ipynb or <id>/ folder per student) against solutions/NAME. "
        "Writes OUT/grades.csv, OUT/feedback/<id>.md and OUT/results.jsonl (a rerun resumes).",
    )
    p_gr.add_argument(
        "assignment", metavar="NAME", help="assignment name (or path to its solutions folder)"
    )
    p_gr.add_argument(
        "submissions",
        metavar="SUBMISSIONS",
        help="folder of submissions, or the LMS's download (Canvas's or Moodle's .zip)",
    )
    p_gr.add_argument("--out", required=True, help="output folder")
    p_gr.add_argument(
        "--jobs",
        type=int,
        default=None,
        help="students graded in parallel (default: the CPUs this process may use)",
    )
    p_gr.add_argument(
        "--timeout",
        type=float,
        default=None,
        help="time limit in seconds per answer cell and per call (default: from checks.py)",
    )
    p_gr.add_argument(
        "--memory",
        type=int,
        default=1024,
        help="memory budget per student in MB (default: %(default)s)",
    )
    p_gr.add_argument(
        "--regrade",
        action="store_true",
        help="ignore previous results in OUT and grade everyone again (with --student: "
        "only those students)",
    )
    p_gr.add_argument(
        "--student",
        action="append",
        metavar="ID",
        default=None,
        help="grade only this student (repeatable); the others keep their previous results",
    )
    p_gr.add_argument("--no-progress", action="store_true", help="no progress bar")
    p_gr.add_argument(
        "--secret",
        default=None,
        help="the class's key file, as given to `course export` (default: $COURSE_SECRET_FILE)",
    )
    p_gr.add_argument(
        "--no-secret",
        action="store_true",
        help="grade on public data although a secret is set (a class whose edition was "
        "exported with --no-secret); --roster needs --secret or this",
    )
    p_gr.add_argument(
        "--roster",
        default=None,
        help="CSV of the class (id, name, email): report missing and unknown submissions and "
        "write canvas.csv and moodle.csv beside grades.csv",
    )
    p_gr.add_argument(
        "--missing-as-zero",
        action="store_true",
        help="LMS files: 0 for roster students without a submission (default: blank)",
    )
    p_gr.add_argument(
        "--lms-column",
        default=None,
        help="LMS files: the assignment's column name (default: the assignment's title)",
    )
    p_gr.add_argument(
        "--short-answers",
        metavar="FILE",
        default=None,
        help="merge the marks of a filled short-answer file (OUT/short_answers.csv, filled by "
        "`course mark OUT` or in a spreadsheet) into the grades and the feedback; a bad row "
        "refuses the import",
    )
    p_gr.add_argument(
        "--due",
        metavar="DATE",
        default=None,
        help="the due date, ISO 8601 with its time zone (2026-10-20T23:59+02:00); default: "
        "due= in checks.py. Adds the late and penalty columns to grades.csv",
    )
    p_gr.add_argument(
        "--late-policy",
        metavar="RULES",
        default=None,
        help="late deduction, e.g. percent-per-day:10,cap:50 (percent of the points possible "
        "per started day, at most cap) or zero-after:DATE; default: late_policy= in checks.py, "
        "else none (late work is marked, nothing deducted)",
    )
    p_gr.add_argument(
        "--submitted-at",
        metavar="FILE",
        default=None,
        help="when each submission was handed in: a CSV with columns id,submitted_at (or a "
        "Moodle grading worksheet), or 'file-times' for the files' modification times; "
        "without it only Canvas's _LATE_ in file names marks late work",
    )
    p_gr.add_argument(
        "--extensions",
        metavar="FILE",
        default=None,
        help="students' own due dates: a CSV with the header id,assignment,due (one row per "
        "student and assignment, due in ISO 8601 with its zone); the same file the term's "
        "rules name (docs/instructors/term.md)",
    )
    p_gr.add_argument(
        "--cluster",
        metavar="ADDRESS",
        help="grade on the Dask distributed scheduler at ADDRESS, one task per student: "
        "tls://host:8786 with the --tls-* files, or tcp://127.0.0.1:8786 on this machine; "
        "needs the [cluster] extra (docs/instructors/cluster.md)",
    )
    p_gr.add_argument(
        "--tls-ca-file",
        metavar="FILE",
        default=None,
        help="--cluster: the certificate authority that signed the scheduler's certificate",
    )
    p_gr.add_argument(
        "--tls-cert", metavar="FILE", default=None, help="--cluster: this client's certificate"
    )
    p_gr.add_argument(
        "--tls-key",
        metavar="FILE",
        default=None,
        help="--cluster: this client's private key (if not in the --tls-cert file)",
    )
    p_gr.add_argument(
        "--insecure-cluster",
        action="store_true",
        help="--cluster: accept a plain tcp:// scheduler on another machine (submissions and "
        "assignment files then cross the network unencrypted; only on a private network)",
    )
    p_gr.add_argument(
        "--unsafe-no-isolation",
        action="store_true",
        help="grade even on a machine whose kernel offers neither Landlock nor user namespaces "
        "(student code could then read and change the grader's files)",
    )
    p_gr.add_argument("--course-dir", help=COURSE_DIR_HELP)
    p_gr.add_argument("--solutions", help="authoring folder (default: COURSE_DIR/solutions)")
    p_gr.set_defaults(func=_instructor_only(_grade))

    p_gb = subparsers.add_parser(
        "gradebook",
        help="combine several assignments' grading outputs into one gradebook",
        description="Read the results.jsonl of each OUT_DIR (the --out of a `course grade` run, "
        "one per assignment) and write DEST/gradebook.csv (a column per assignment and the "
        "total); with --roster also DEST/canvas.csv and DEST/moodle.csv.",
    )
    p_gb.add_argument("outs", nargs="+", metavar="OUT_DIR", help="grading output folders")
    p_gb.add_argument("--out", required=True, metavar="DEST", help="folder to write to")
    p_gb.add_argument(
        "--roster", default=None, help="CSV of the class: write canvas.csv and moodle.csv too"
    )
    p_gb.add_argument(
        "--missing-as-zero",
        action="store_true",
        help="0 for an assignment a student did not submit (default: blank)",
    )
    p_gb.add_argument(
        "--rules",
        metavar="TERM_JSON",
        default=None,
        help="the term's rules (weights, drop-lowest, letters or pass mark, exemptions, "
        "extensions): a JSON file, see docs/instructors/term.md; adds the category, final "
        "percent and letter columns",
    )
    p_gb.set_defaults(func=_instructor_only(_gradebook))

    p_fb = subparsers.add_parser(
        "feedback",
        help="the zip of feedback files an LMS's bulk feedback upload takes",
        description="Write OUT_DIR/<lms>_feedback.zip from a `course grade` output folder: one "
        "HTML page per graded student, named after the file the LMS handed out (Canvas: "
        "Re-Upload Submissions; Moodle: Upload multiple feedback files in a zip).",
    )
    p_fb.add_argument("out_dir", metavar="OUT_DIR", help="the --out of a course grade run")
    p_fb.add_argument("--lms", required=True, choices=["canvas", "moodle"])
    p_fb.set_defaults(func=_instructor_only(_feedback))
    _add_mark_command(subparsers)
    p_hist = subparsers.add_parser(
        "history",
        help="every change of a student's grade and marks, with who and when",
        description="Print what the term's record of OUT_DIR (record.sqlite) holds about "
        "STUDENT: the files graded, then every grade, mark, late record and quarantine, oldest "
        "first, with who made the change and when (to answer a regrade request).",
    )
    p_hist.add_argument("out_dir", metavar="OUT_DIR", help="the --out folder of `course grade`")
    p_hist.add_argument("student", metavar="STUDENT", help="the student's ID (as grades.csv)")
    p_hist.set_defaults(func=_instructor_only(_history))
    _add_class_commands(subparsers)
