"""``course grade``: the batch driver that grades a folder of submitted notebooks.

It finds the submissions, skips students already graded with the same checks, library
version and key from the same file (``results.jsonl`` records the file's sha256 and makes a run
resumable; a resubmission is graded again), grades the others in parallel (or only the
students ``--student`` names), one
:class:`~course.grading.batch.session.StudentSession` each, and writes the reports
(:mod:`course.grading.batch.reports`) as students finish.

Outputs in ``OUT``: ``grades.csv`` (student, one column per question, total, max, status;
``late`` and ``penalty`` when a due date is known, :mod:`course.grading.batch.late`),
``report.html`` (the class report, :mod:`course.grading.batch.classreport`),
``feedback/<student>.md`` and ``results.jsonl`` (one line per student, appended as students
finish; a rerun skips students already graded with the same checks and library version from
the same file).
"""

from __future__ import annotations

import csv
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path

from course.grading.batch.classreport import write_report
from course.grading.batch.cluster import check_cluster_options, grade_on_cluster
from course.grading.batch.identity import resolve_identities
from course.grading.batch.intake import file_digest, find_submissions, unpack_archive
from course.grading.batch.late import (
    LateError,
    extensions_for,
    late_records,
    parse_due,
    parse_policy,
    read_extensions,
)
from course.grading.batch.marks import (
    SHORT_ANSWERS_FILE,
    MarksError,
    apply_marks,
    load_marks,
    parse_marks_csv,
    save_marks,
    short_questions,
    unimported_edits,
    unmarked_counts,
    unmarked_warning,
    validate_marks,
    write_short_answers,
)
from course.grading.batch.options import GradeOptions
from course.grading.batch.reports import (
    Summary,
    append_result,
    csv_text,
    feedback_markdown,
    read_results,
    write_csv,
)
from course.grading.batch.results import StudentResult
from course.grading.batch.roster import write_canvas_csv, write_moodle_csv
from course.grading.batch.session import AssignmentGrader

__all__ = ["Summary", "grade"]


def _intake(submissions: Path, out: Path) -> tuple[Path, list, list[str]]:
    """The folder to grade: ``submissions`` itself, or an LMS's download archive unpacked into
    ``OUT/unpacked`` (:mod:`course.grading.batch.intake`); the archive's entries that are no
    notebook, each against its student, and its lines about entries that belong to nobody."""
    if submissions.is_dir():
        return submissions, [], []
    folder = out / "unpacked"
    listed, escaped = unpack_archive(submissions, folder)
    return folder.resolve(), listed, escaped


def _identify(grader, submissions: Path, listed: list, solution_dir: Path, options):
    """Every file handed in, attributed to its student (:mod:`course.grading.batch.identity`);
    a warning at the start when nothing tells who uploaded the LMS's files."""
    found = find_submissions(submissions, grader.name, private_dir=solution_dir) + listed
    declared = _read_declared(grader, found, options)
    identity = resolve_identities(
        found,
        grader.name,
        options.roster.students if options.roster is not None else None,
        grader.data_key,
        read_declared=lambda path: declared.get(path, (None, {})),
    )
    if identity.warning and options.announce is not None:
        options.announce(identity.warning)
    return identity


def _read_declared(grader: AssignmentGrader, found: list, options: GradeOptions) -> dict:
    """The ID each file declares, read in sandboxed reader children (``--jobs`` at a time):
    decoding a notebook can cost gigabytes, which must never be the grader's own memory."""
    paths = [sub.path for sub in found if sub.path is not None]
    if not paths:
        return {}
    # started by this thread: the fork server dies with the thread that started it
    grader.sandbox  # noqa: B018
    with ThreadPoolExecutor(max_workers=max(1, int(options.jobs))) as pool:
        return dict(zip(paths, pool.map(grader.declared_id, paths)))


def _grade_locally(grader: AssignmentGrader, pending: list, jobs: int):
    """Rows of ``pending`` submissions as they finish, ``jobs`` students at a time."""
    if pending:
        grader.sandbox  # noqa: B018  (start the fork server now, not in the first student's time)
    with ThreadPoolExecutor(max_workers=max(1, int(jobs))) as pool:
        futures = [
            pool.submit(grader.grade_one, sub.student, sub.path, sub.note, sub.refused)
            for sub in pending
        ]
        for fut in as_completed(futures):
            yield fut.result()


def grade(
    solution_dir: Path, submissions: Path, out: Path, options: GradeOptions | None = None
) -> Summary:
    """Grade every submission in ``submissions`` into ``out`` (see the module docstring)."""
    options = options or GradeOptions()
    check_cluster_options(options)  # an unusable or unencrypted address: before anything
    start = time.monotonic()
    solution_dir, submissions, out = (
        Path(solution_dir).resolve(),
        Path(submissions).resolve(),
        Path(out).resolve(),
    )
    out.mkdir(parents=True, exist_ok=True)
    (out / "feedback").mkdir(exist_ok=True)
    archive = submissions  # the folder, or the LMS's download: the sandbox reads neither
    submissions, listed, unpacked = _intake(submissions, out)
    results_path = out / "results.jsonl"
    if options.regrade and options.students is None and results_path.exists():
        results_path.unlink()
    lock = threading.Lock()
    with AssignmentGrader(solution_dir, options, deny_read=[archive, submissions, out]) as grader:
        marks_in = None  # a filled marking file: checked before anyone is graded
        if options.short_answers is not None:
            if not short_questions(grader.checks):
                raise MarksError(f"{grader.name} has no short-answer questions to mark")
            marks_in = parse_marks_csv(Path(options.short_answers), grader.checks)
        identity = _identify(grader, submissions, listed, solution_dir, options)
        identity.flags[:0] = unpacked
        todo = identity.entries
        _write_conflicts(identity.conflicts, identity.attached, out / "identity_conflicts.csv")
        late, late_notes = _late_work(grader.checks, todo, submissions, options)
        if options.students is not None:
            _check_selection(options.students, todo)
        previous = read_results(results_path)
        files = {sub.student: _file_record(sub.path, submissions) for sub in todo}
        rows: dict[str, StudentResult] = {}
        pending = []
        regraded: dict[str, int] = {}  # why students graded before were graded again
        stale: list[str] = []  # out of date, left alone because --student chose others
        skipped = 0  # never graded and not chosen by --student
        for sub in todo:
            old = previous.get(sub.student)
            chosen = options.students is None or sub.student in options.students
            why = _regrade_reason(old, grader, files[sub.student])
            if chosen and options.regrade and old is not None:
                why = "--regrade"
            if old is not None and (why is None or not chosen):
                rows[sub.student] = old
                if why is not None:
                    stale.append(sub.student)
                elif old.set_late(late.get(sub.student)):  # a new due date, policy or time
                    append_result(old, results_path)
                    (out / "feedback" / f"{old.student}.md").write_text(
                        feedback_markdown(old, grader.checks), encoding="utf-8"
                    )
            elif chosen:
                pending.append(sub)
                if why is not None:
                    regraded[why] = regraded.get(why, 0) + 1
            else:
                skipped += 1
        resumed = len(rows)

        def finish(row: StudentResult) -> None:
            with lock:
                row.record_file(files.get(row.student))
                row.set_late(late.get(row.student))
                append_result(row, results_path)
                (out / "feedback" / f"{row.student}.md").write_text(
                    feedback_markdown(row, grader.checks), encoding="utf-8"
                )
                rows[row.student] = row

        if options.announce is not None and not options.cluster:
            # before the progress bar, whose line has no end until it closes
            iso = grader.sandbox.isolation if pending else grader.isolation
            options.announce(iso.describe())
        try:
            from tqdm import tqdm
        except ImportError:  # pragma: no cover
            tqdm = None
        bar = (
            tqdm(
                total=len(pending),
                desc=f"grading {grader.name}",
                unit="student",
                file=sys.stderr,
                disable=not options.progress or tqdm is None,
            )
            if tqdm
            else None
        )
        if options.cluster:
            results = grade_on_cluster(options.cluster, grader, pending, options)
        else:
            results = _grade_locally(grader, pending, options.jobs)
        for row in results:
            finish(row)
            if bar is not None:
                bar.update(1)
        if bar is not None:
            bar.close()
        grader.close()  # now: what its cleanup could not remove goes into the summary
        for row in rows.values():  # feedback of resumed students too (cheap, keeps OUT complete)
            fb = out / "feedback" / f"{row.student}.md"
            if not fb.exists():
                fb.write_text(feedback_markdown(row, grader.checks), encoding="utf-8")
        qids = [q.id for q in grader.questions]
        final = [rows[sub.student] for sub in todo if sub.student in rows]
        marking = _merge_marks(grader.checks, final, out, options, marks_in, results_path)
        write_csv(final, qids, out / "grades.csv")
        write_report(final, grader.checks, qids, out)
        summary = Summary(
            final,
            qids,
            {q.id: q.points for q in grader.questions},
            len(pending),
            resumed,
            time.monotonic() - start,
            out,
        )
        summary.flags = identity.flags
        summary.regraded = regraded
        summary.stale = stale
        summary.unselected = skipped
        summary.marking = marking
        summary.late_notes = late_notes
        summary.cleanup_failed = list(grader.cleanup_failures)
        if options.roster is not None:
            _class_files(summary, grader, options, out)
        return summary


class SelectionError(ValueError):
    """``--student`` names an ID that has no submission in the folder."""


def _check_selection(students, todo: list) -> None:
    found = {sub.student for sub in todo}
    unknown = sorted(set(students) - found)
    if unknown:
        raise SelectionError(
            f"--student {', '.join(unknown)}: no submission with this ID in the folder "
            f"({len(found)} submission(s) found; the ID is the one grades.csv lists)"
        )


def _late_work(checks, entries: list, submissions: Path, options: GradeOptions):
    """The late record of each submission and the console's notes about them
    (:mod:`course.grading.batch.late`); the command line's due date and policy win over
    ``checks.py``'s."""
    due = options.due
    if due is None and getattr(checks, "due", None):
        due = parse_due(checks.due, "due= in checks.py")
    policy = options.late_policy or parse_policy(getattr(checks, "late_policy", None))
    if options.submitted_at is not None and due is None:
        raise LateError(
            "--submitted-at needs a due date: pass --due 2026-10-20T23:59+02:00 (or set due= "
            "in the assignment's checks.py)"
        )
    extensions = None
    if options.extensions is not None:  # this assignment's rows, by its folder name or title
        extensions = extensions_for(
            read_extensions(Path(options.extensions)), checks.name, getattr(checks, "title", "")
        )
    return late_records(
        entries, submissions, due, policy, options.submitted_at, options.roster, extensions
    )


def _regrade_reason(old: StudentResult | None, grader, file: dict | None) -> str | None:
    """Why the student's previous row cannot be kept (None: it can; a student never graded
    has no reason). A row is kept only when it was graded with the same checks, library
    version and key, from the same file (its sha256): a resubmission is graded again."""
    if old is None:
        return None
    if old.checks_sha256 != grader.digest:
        return "checks changed"
    if old.version != grader.version:
        return "course version changed"
    if old.data_key != grader.data_key:
        return "key changed"
    before = (old.file or {}).get("sha256") if old.has_file else None
    now = (file or {}).get("sha256")
    if old.has_file and before != now:
        return "file changed"
    return None


def _merge_marks(checks, final: list, out: Path, options, entries, results_path: Path) -> str:
    """Merge the instructor's short-answer marks into the rows (and their results and
    feedback) and write the marking file; returns the console summary's line about it."""
    if not short_questions(checks):
        return ""
    marks = load_marks(out)
    imported = 0
    if entries is not None:
        new = validate_marks(Path(options.short_answers), entries, {r.student: r for r in final})
        for sid, by_q in new.items():
            marks.setdefault(sid, {}).update(by_q)
            imported += len(by_q)
        save_marks(out, marks)
    for row in final:
        if apply_marks(row, checks, marks):
            append_result(row, results_path)
        (out / "feedback" / f"{row.student}.md").write_text(
            feedback_markdown(row, checks), encoding="utf-8"
        )
    path = out / SHORT_ANSWERS_FILE
    just_read = (
        options.short_answers is not None
        and path.exists()
        and Path(options.short_answers).resolve() == path.resolve()
    )
    head = f"short answers: {imported} mark(s) imported; " if entries is not None else ""
    # never a 0 for an unmarked answer in grades.csv or the LMS files without saying so
    warning = unmarked_warning(unmarked_counts(final, checks))
    if warning:
        warning = (
            f"\nWARNING: {warning} in grades.csv, report.html and the LMS files; mark them "
            f"with `course mark {out}` (or fill `points` in {path}), then rerun with "
            f"--short-answers {path}"
        )
    edits = 0 if just_read or not path.exists() else unimported_edits(path, marks)
    if edits:
        return (
            f"{head}{path} was NOT rewritten: {edits} row(s) hold marks never imported "
            f"(import them with --short-answers {path}){warning}"
        )
    to_mark = write_short_answers(final, checks, path, marks)
    return (
        f"{head or 'short answers: '}{to_mark} to mark in {path}{warning}"
        if to_mark
        else f"{head or 'short answers: '}all marked ({path})"
    )


def _write_conflicts(conflicts: list, attached: list, path: Path) -> None:
    """Every quarantined file with both IDs (the name's and the notebook's), and every file
    graded for its name's student although its notebook declares an ID on no roster."""
    if not conflicts and not attached:
        path.unlink(missing_ok=True)
        return
    rows = [(*row, "quarantined") for row in conflicts]
    rows += [(*row, f"graded as {row[1]}") for row in attached]
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(["file", "named_as", "declares", "why", "decision"])
        writer.writerows([csv_text(cell) for cell in row] for row in rows)


def _file_record(path: Path | None, submissions: Path) -> dict | None:
    """The graded file and its sha256: the receipt ``check.submit()`` printed matches it."""
    if path is None:
        return None
    digest = file_digest(path)  # never a link, a FIFO or a file too large to grade
    name = (
        path.relative_to(submissions).as_posix() if path.is_relative_to(submissions) else path.name
    )
    return {"name": name, "sha256": digest}


def _class_files(summary: Summary, grader, options: GradeOptions, out: Path) -> None:
    """Missing and unknown submissions against the roster, and the LMS grade files."""
    roster = options.roster
    assert roster is not None
    by_id = {row.student: row for row in summary.rows}
    summary.missing = [s.id for s in roster.students if s.id not in by_id]
    known = set(roster.ids)
    summary.unknown = sorted(sid for sid in by_id if sid not in known)
    column = options.lms_column or grader.checks.title
    write_canvas_csv(
        by_id, roster, column, grader.checks.max_points, out / "canvas.csv", options.missing_as_zero
    )
    write_moodle_csv(by_id, roster, column, out / "moodle.csv", options.missing_as_zero)
