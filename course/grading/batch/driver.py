"""``course grade``: the batch driver that grades a folder of submitted notebooks.

It finds the submissions, skips students already graded with the same checks, library
version and key from the same file (the term's record, :mod:`course.grading.batch.record`,
keeps the file's sha256 and makes a run resumable; a resubmission is graded again), grades the
others in parallel (or only the students ``--student`` names), one
:class:`~course.grading.batch.session.StudentSession` each, and stores each row in the record
as the student finishes. A submission the grader fails on (a fault of the grader, never of the
student) is graded again up to :data:`FAULT_RETRIES` times, then stored as *not graded*: blank
in every LMS file, named in the summary, and graded again by the next run.

Outputs in ``OUT``, all exports of the record, rewritten by every run: ``grades.csv`` (student,
one column per question, total, max, status; ``late`` and ``penalty`` when a due date is known,
:mod:`course.grading.batch.late`), ``report.html`` (the class report,
:mod:`course.grading.batch.classreport`), ``feedback/<student>.md``, ``results.jsonl`` (one
line per student), ``short_answers.csv`` (:mod:`course.grading.batch.marks`) and, with a
roster, ``canvas.csv`` and ``moodle.csv``.
"""

from __future__ import annotations

import csv
import json
import shlex
import sys
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
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
    MARKS_FILE,
    SHORT_ANSWERS_FILE,
    MarksError,
    answer_entries,
    apply_marks,
    export_short_answers,
    parse_marks_csv,
    refused_text,
    short_questions,
    unmarked_counts,
    unmarked_warning,
    validate_marks,
)
from course.grading.batch.options import GradeOptions
from course.grading.batch.record import Record
from course.grading.batch.reports import (
    Summary,
    csv_text,
    feedback_markdown,
    write_csv,
)
from course.grading.batch.results import StudentResult
from course.grading.batch.roster import write_canvas_csv, write_moodle_csv
from course.grading.batch.session import AssignmentGrader
from course.grading.vocabulary import SubmissionStatus

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


#: How many more times a submission the grader failed on (its run folder gone, its worker
#: lost, the grader's own exception) is graded before it is stored as *not graded*.
FAULT_RETRIES = 2


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
    with (
        Record(out) as record,
        AssignmentGrader(solution_dir, options, deny_read=[archive, submissions, out]) as grader,
    ):
        marks_in, marks_refused = (
            None,
            list[str](),
        )  # a filled marking file: read before anyone is graded
        if options.short_answers is not None:
            if not short_questions(grader.checks):
                raise MarksError(f"{grader.name} has no short-answer questions to mark")
            marks_in, marks_refused = parse_marks_csv(Path(options.short_answers), grader.checks)
        imported = record.import_old(out / "results.jsonl", out / MARKS_FILE)
        if options.regrade and options.students is None:
            record.forget_results()
        # -- who handed in what (the identity step) ---------------------------------------
        identity = _identify(grader, submissions, listed, solution_dir, options)
        identity.flags[:0] = unpacked
        todo = identity.entries
        # -- the end of the identity step ---------------------------------------------------
        _write_conflicts(identity.conflicts, identity.attached, out / "identity_conflicts.csv")
        record.set_quarantines(identity.conflicts)
        late, late_notes = _late_work(grader.checks, todo, submissions, options)
        if options.students is not None:
            _check_selection(options.students, todo)
        files = {sub.student: _file_record(sub.path, submissions) for sub in todo}
        record.set_submissions(_submission_rows(todo, files))
        record.set_late(late)
        previous = record.results()
        failed_before = set(record.not_graded())
        qids = [q.id for q in grader.questions]
        rows: dict[str, StudentResult] = {}
        pending = []
        regraded: dict[str, int] = {}  # why students graded before were graded again
        stale: list[str] = []  # out of date, left alone because --student chose others
        skipped = 0  # never graded and not chosen by --student
        for sub in todo:
            old = previous.get(sub.student)
            chosen = options.students is None or sub.student in options.students
            why = _regrade_reason(old, grader, files[sub.student])
            if old is None and sub.student in failed_before:
                why = "not graded last time (a fault of the grader)"
            if chosen and options.regrade and old is not None:
                why = "--regrade"
            if old is not None and (why is None or not chosen):
                old.order_questions(qids)
                rows[sub.student] = old
                if why is not None:
                    stale.append(sub.student)
                elif old.set_late(late.get(sub.student)):  # a new due date, policy or time
                    record.put_result(old)
            elif chosen:
                pending.append(sub)
                if why is not None:
                    regraded[why] = regraded.get(why, 0) + 1
            else:
                skipped += 1
        resumed = len(rows)
        not_graded: dict[str, StudentResult] = {}

        def finish(row: StudentResult) -> None:
            row.order_questions(qids)
            row.record_file(files.get(row.student))
            row.set_late(late.get(row.student))
            if row.status == SubmissionStatus.GRADER_ERROR:
                row.status = SubmissionStatus.NOT_GRADED
                record.put_result(row, graded=False)
                not_graded[row.student] = row
            else:
                record.put_result(row)
                rows[row.student] = row

        if options.announce is not None and not options.cluster:
            # before the progress bar, whose line has no end until it closes
            iso = grader.sandbox.isolation if pending else grader.isolation
            options.announce(iso.describe())
        _grade_with_retries(grader, pending, options, finish)
        grader.close()  # now: what its cleanup could not remove goes into the summary
        final = [rows[sub.student] for sub in todo if sub.student in rows]
        marking = _merge_marks(grader.checks, final, out, options, marks_in, record)
        if marks_refused or marking.refused:
            marking.text = "\n".join(
                t for t in (marking.text, refused_text(marks_refused + marking.refused)) if t
            )
        # -- the exports: written from the record, never read back ---------------------------
        exported = [*final, *not_graded.values()]
        _export_rows(record, exported, grader.checks, qids, out)
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
        summary.marking = marking.text
        summary.late_notes = late_notes
        summary.cleanup_failed = list(grader.cleanup_failures)
        summary.not_graded = sorted(not_graded)
        summary.regrade_command = _regrade_command(grader.name, submissions, out)
        summary.imported = imported
        if options.roster is not None:
            _class_files(summary, exported, grader, options, out)
        return summary


def _grade_with_retries(grader: AssignmentGrader, pending: list, options, finish) -> None:
    """Grade ``pending`` and hand each row to ``finish``; a submission the grader failed on
    is graded again, up to :data:`FAULT_RETRIES` more times, before its fault is final."""
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
            disable=not options.progress,
        )
        if tqdm
        else None
    )
    batch, attempt = list(pending), 0
    by_id = {sub.student: sub for sub in pending}
    while batch:
        retry = []
        if options.cluster:
            results = grade_on_cluster(options.cluster, grader, batch, options)
        else:
            results = _grade_locally(grader, batch, options.jobs)
        for row in results:
            if row.status == SubmissionStatus.GRADER_ERROR and attempt < FAULT_RETRIES:
                retry.append(by_id[row.student])
                continue
            finish(row)
            if bar is not None:
                bar.update(1)
        batch, attempt = retry, attempt + 1
    if bar is not None:
        bar.close()


def _regrade_command(name: str, submissions: Path, out: Path) -> str:
    return f"course grade {shlex.quote(name)} {shlex.quote(str(submissions))} --out {shlex.quote(str(out))}"


def _export_rows(record: Record, rows: list[StudentResult], checks, qids: list, out: Path) -> None:
    """grades.csv, report.html, the feedback and results.jsonl, from the rows of the record."""
    write_csv(rows, qids, out / "grades.csv")
    write_report(rows, checks, qids, out)  # rows that are no grade: listed, not counted
    for row in rows:
        _write_if_changed(out / "feedback" / f"{row.student}.md", feedback_markdown(row, checks))
    current = record.results(graded=None)
    text = "".join(
        json.dumps(current[sid].to_json(), sort_keys=True, ensure_ascii=False) + "\n"
        for sid in sorted(current)
    )
    _write_if_changed(out / "results.jsonl", text)


def _write_if_changed(path: Path, text: str) -> None:
    try:
        if path.read_text(encoding="utf-8") == text:
            return
    except OSError:
        pass
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)


def _submission_rows(entries: list, files: dict) -> list[tuple]:
    """The record's rows of this run's files: (student, name, sha256, origin, reason); the
    origin is the entry of the submissions folder the file came from (the name the LMS gave
    it), never an absolute path of the instructor's machine."""
    out = []
    for sub in entries:
        file = files.get(sub.student) or {}
        name = file.get("name") or ""
        origin = name.split("/", 1)[0] if name else ""
        reason = sub.note or ("refused" if sub.refused else f"the file's name gives {sub.student}")
        out.append((sub.student, name, file.get("sha256"), origin, reason))
    return out


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


@dataclass
class _Marking:
    text: str = ""  # the console summary's line about the short answers
    refused: list = field(default_factory=list)  # rows of the marking file refused


def _merge_marks(checks, final: list, out: Path, options, entries, record: Record) -> _Marking:
    """Merge the imported marks into the record, the record's marks into the rows, and write
    the marking file (an export of the record)."""
    if not short_questions(checks):
        return _Marking()
    imported, refused = 0, list[str]()
    if entries is not None:
        new, refused = validate_marks(entries, {r.student: r for r in final})
        who = f"{record.who} (--short-answers {Path(options.short_answers).name})"
        for sid, by_q in new.items():
            for qid, mark in by_q.items():
                imported += record.set_mark(
                    sid, qid, mark["answer_id"], mark["points"], mark["comment"], who, False
                )
    record.set_answers(answer_entries(final, checks))
    marks = record.marks()
    for row in final:
        if apply_marks(row, checks, marks):
            record.put_result(row)
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
            f"with `course mark {out}` and run `course grade` again (or fill `points` in "
            f"{path} and rerun with --short-answers {path})"
        )
    to_mark, edits = export_short_answers(record, path, just_read)
    if to_mark is None:
        return _Marking(
            f"{head}{path} was NOT rewritten: {edits} row(s) hold marks never imported "
            f"(import them with --short-answers {path}){warning}",
            refused,
        )
    return _Marking(
        f"{head or 'short answers: '}{to_mark} to mark in {path}{warning}"
        if to_mark
        else f"{head or 'short answers: '}all marked ({path})",
        refused,
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


def _class_files(summary: Summary, rows: list, grader, options: GradeOptions, out: Path) -> None:
    """Missing and unknown submissions against the roster, and the LMS grade files (a
    student not graded, refused or quarantined: blank, with the reason in the feedback)."""
    roster = options.roster
    assert roster is not None
    by_id = {row.student: row for row in rows}
    summary.missing = [s.id for s in roster.students if s.id not in by_id]
    known = set(roster.ids)
    summary.unknown = sorted(sid for sid in by_id if sid not in known)
    column = options.lms_column or grader.checks.title
    write_canvas_csv(
        by_id, roster, column, grader.checks.max_points, out / "canvas.csv", options.missing_as_zero
    )
    write_moodle_csv(by_id, roster, column, out / "moodle.csv", options.missing_as_zero)
