"""Grading one submission: the trusted parent's side of one student's session.

:class:`AssignmentGrader` holds what does not depend on the student (the checks, the release,
references computed once, the sandbox); :class:`StudentSession` runs one student's plan in a
sandboxed child (:mod:`course.grading.sandbox.parent`), asks the child for values and function
results and compares them with references computed here, in the parent. A timeout or crash
costs only the question it happened in: the child is killed, a fresh one re-runs the cells
(skipping the bad one) and grading continues.
"""

from __future__ import annotations

import builtins
import errno
import re
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from course.grading.authoring.checks import student_seed
from course.grading.authoring.personal import students_data_source
from course.grading.authoring.release import checks_digest, load_assignment
from course.grading.authoring.secret import public_key_id
from course.grading.batch.options import GradeOptions
from course.grading.batch.plan import build_plan
from course.grading.batch.results import CaseResult, QuestionResult, StudentResult
from course.grading.batch.similarity import fingerprint
from course.grading.codec import EncodingError, decode, encode
from course.grading.compare import compare
from course.grading.items import choice_verdict, is_unanswered_text
from course.grading.notebook import SubmissionError
from course.grading.sandbox.parent import (
    ChildDied,
    ChildHandle,
    ChildTimeout,
    Limits,
    Sandbox,
    SandboxError,
)
from course.grading.vocabulary import (
    ABNORMAL,
    DEMO_STUDENT_ID,
    PLACEHOLDER_ID,
    CellOrigin,
    CellRole,
    GradeStatus,
    MistakeKind,
    Op,
    QuestionKind,
    ReplyStatus,
    SubmissionStatus,
    answer_cell_id,
)

__all__ = ["AssignmentGrader", "StudentSession"]


def _version() -> str:
    import course

    return str(getattr(course, "__version__", "unknown"))


_HEX = re.compile(r"0x[0-9a-fA-F]{6,}")
# the keys of a returned dict, named by compare's message: student text, cut for hidden cases
_KEYS = re.compile(r" with keys \[.*")
#: The longest short answer kept (characters): the rest is cut in the marking file.
MAX_SHORT_ANSWER = 20_000
#: Cell source (characters) of notebooks read for the identity step and kept for their
#: sessions (each then needs no second reader child); at most ~40 MB of the parent's memory.
MAX_CACHED_CHARS = 10_000_000


class AssignmentGrader:
    """Grades submissions of one assignment (thread-safe: one :meth:`grade_one` per thread)."""

    def __init__(
        self,
        solution_dir: Path,
        options: GradeOptions | None = None,
        deny_read=(),
        data_key: str | None = None,
    ):
        """``data_key``: the key id of a class whose key this grader does not hold (a cluster
        worker); each student's data then come from the seeds :meth:`grade_one` is given."""
        self.options = options if options is not None else GradeOptions()
        self.solution_dir = Path(solution_dir).resolve()
        self.checks, self.release = load_assignment(self.solution_dir)
        self.name = self.checks.name
        self.digest = checks_digest(self.solution_dir, self.checks.files)
        # personal data are drawn with the instructor's secret when the class has one
        self.secret = getattr(self.options, "secret", None)
        if data_key is not None and self.secret is not None and data_key != self.secret.key_id:
            raise ValueError(f"data_key {data_key!r} is not the key id of options.secret")
        self.data_key = data_key or (
            self.secret.key_id if self.secret is not None else public_key_id
        )
        # the data.py beside the student's notebook: `from data import ...` works at grading too
        # (a keyed class, graded here or on a worker that holds only the key's id, gets the
        # public part only, as its edition does)
        self.data_source = students_data_source(self.checks, self.data_key != public_key_id)
        self.version = _version()
        self.questions = list(self.checks.questions.values())
        # references that do not depend on the student: computed once, here, in the parent
        self.case_expected = {
            q.id: [q.expected(case) for case in q.public_cases + q.hidden_cases]
            for q in self.questions
            if q.kind == "function"
        }
        self.value_expected = {
            q.id: q.expected() for q in self.questions if q.kind == "value" and q.data is None
        }
        # declared mistakes (message, wrong value) of the same cases: named in the feedback
        self.case_mistakes = {
            q.id: [q.mistaken(case) for case in q.public_cases + q.hidden_cases]
            for q in self.questions
            if q.kind == "function"
        }
        self.value_mistakes = {
            q.id: q.mistaken() for q in self.questions if q.kind == "value" and q.data is None
        }
        # right answers of other data, which a wrong answer may be (hard-coded, or computed
        # from the notebook's practice data): a personal value against the demo ID's answer and
        # the public cases', a case against the question's other cases (compare's ``others``)
        public = [
            e
            for q in self.questions
            if q.kind == "function"
            for e in self.case_expected[q.id][: len(q.public_cases)]
        ]
        self.other_answers = {
            q.id: [*self._demo_answers(q), *public]
            for q in self.questions
            if q.kind == "value" and q.data is not None
        }
        solutions_root = (
            self.solution_dir.parent
            if self.solution_dir.parent.name == "solutions"
            else self.solution_dir
        )
        #: question -> the forbidden functions it names (reports of others are ignored)
        self.forbid = {q.id: frozenset(q.forbid) for q in self.questions}
        #: the questions graded on a value the student could paste from a scratch cell
        self.forbid_by_value = [
            q.id for q in self.questions if q.forbid and q.kind != QuestionKind.FUNCTION
        ]
        #: question -> the answer cell as handed out (left out of the similarity fingerprint)
        self.skeletons = {
            c.question: c.source
            for c in self.release.cells
            if c.role == CellRole.ANSWER and c.cell_type == "code" and c.question
        }
        self._deny_read = [solutions_root, *deny_read]
        self.isolation = self.options.isolation()  # refuses early where nothing walls files off
        self._sandbox: Sandbox | None = None
        self._sandbox_lock = threading.Lock()
        self._unreadable: dict[str, str] = {}  # path -> why its reader child failed
        self._read_cache: dict[str, tuple[dict, int]] = {}  # path -> (reduced notebook, chars)
        self._cached_chars = 0
        self._read_lock = threading.Lock()
        self.cleanup_failures: list[str] = []  # of sandboxes closed: "<path> (<reason>)"

    @property
    def sandbox(self) -> Sandbox:
        """The sandbox (its warm fork server starts on first use)."""
        with self._sandbox_lock:
            if self._sandbox is None:
                self._sandbox = Sandbox(
                    limits=Limits(
                        memory_mb=self.options.memory_mb, cpu_seconds=int(self.budget()) + 5
                    ),
                    preload=self.checks.preload,
                    deny_read=self._deny_read,
                    forbid=[name for names in self.forbid.values() for name in names],
                    isolation=self.isolation,
                    labels=[q.id for q in self.questions],
                )
            return self._sandbox

    def declared_id(self, path: Path | None) -> tuple[str | None, dict]:
        """The ID a submission declares and its submission metadata, read by a sandboxed
        reader child (:meth:`~course.grading.sandbox.parent.Sandbox.read_notebook`);
        ``(None, {})`` when it cannot be read (its session reports why)."""
        from course.grading.batch.identity import declared_in

        if path is None:
            return None, {}
        try:
            nb = self.sandbox.read_notebook(path, self.options.ready_timeout)
        except SubmissionError as exc:  # kept (a line), so its session does not read it again
            self._unreadable[str(path)] = str(exc)
            return None, {}
        except (SandboxError, OSError):  # the sandbox failed, not the file: its session retries
            return None, {}
        size = sum(len(cell["source"]) for cell in nb["cells"])
        with self._read_lock:  # kept for its session while the cache stays within its bound
            if self._cached_chars + size <= MAX_CACHED_CHARS:
                self._read_cache[str(path)] = (nb, size)
                self._cached_chars += size
        return declared_in(nb)

    def _read(self, path: Path | None, raw: bytes | None) -> dict:
        """The submission's reduced notebook: as the identity step read it, else read now."""
        if raw is None:
            with self._read_lock:
                nb, size = self._read_cache.pop(str(path), (None, 0))
                self._cached_chars -= size
            if nb is not None:
                return nb
            if str(path) in self._unreadable:
                raise SubmissionError(self._unreadable[str(path)])
        return self.sandbox.read_notebook(
            raw if raw is not None else path, self.options.ready_timeout
        )

    def close(self) -> None:
        """Stop the sandbox; what no cleanup could remove is in :attr:`cleanup_failures`."""
        with self._sandbox_lock:
            if self._sandbox is not None:
                self._sandbox.close()
                self.cleanup_failures.extend(self._sandbox.cleanup_failures)
                self._sandbox = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- limits ---------------------------------------------------------------------------
    def _demo_answers(self, q) -> list:
        """The answers of ``q`` for the demo ID's data, with and without the class key."""
        out = []
        for secret in dict.fromkeys([None, self.secret]):
            try:
                out.append(q.expected(data=self.checks.data_for(q.data, DEMO_STUDENT_ID, secret)))
            except Exception:  # a diagnosis never stops grading
                continue
        return out

    def timeout_for(self, qid: str | None) -> float:
        if self.options.timeout is not None:
            return float(self.options.timeout)
        q = self.checks.questions.get(qid) if qid else None
        if q is not None and q.timeout is not None:
            return float(q.timeout)
        return self.checks.timeout

    def budget(self) -> float:
        if self.options.student_budget is not None:
            return float(self.options.student_budget)
        per_q = sum(self.timeout_for(q.id) * (1 + len(q.cases)) for q in self.questions)
        return max(60.0, 2.0 * per_q + 30.0)

    # -- one student ----------------------------------------------------------------------
    def student_seeds(self, sid: str) -> dict[str, int]:
        """The seed of each of ``sid``'s personal data sets, derived from the key here: what a
        machine that grades ``sid`` without the key needs (see :meth:`grade_one`)."""
        if self.secret is None and self.data_key != public_key_id:
            raise ValueError("this grader holds no key: it cannot derive a student's seeds")
        return {
            key: student_seed(self.name, key, sid, self.secret) for key in self.checks.data_keys()
        }

    def _row(self, sid: str) -> StudentResult:
        return StudentResult(
            student=sid,
            assignment=self.name,
            checks_sha256=self.digest,
            version=self.version,
            data_key=self.data_key,
            max=self.checks.max_points,
            status=SubmissionStatus.OK,
        )

    def grade_one(
        self,
        sid: str,
        path: Path | None,
        problem: str | None = None,
        refused: bool = False,
        raw: bytes | None = None,
        seeds: dict[str, int] | None = None,
    ) -> StudentResult:
        """Grade one submission (its notebook at ``path``, or its bytes ``raw``); never raises
        (a grader failure is recorded in the row). ``wall_seconds`` says how long it took.
        ``seeds``: the student's :meth:`student_seeds`, computed where the key is (a grader
        without the key needs them; one with the key derives them itself)."""
        start = time.monotonic()
        row = self._row(sid)
        try:
            self._grade(row, sid, path, problem, refused, raw, seeds)
        except Exception as exc:  # a bug or sandbox failure must not abort the batch
            self._fault(row, exc)
        row.add_total()
        abnormal = [
            f"{qid}: {r.status}" for qid, r in row.questions.items() if r.status in ABNORMAL
        ]
        if row.status == SubmissionStatus.OK and abnormal:
            row.status = "; ".join(abnormal)
        row.wall_seconds = round(time.monotonic() - start, 3)
        return row

    def _fault(self, row: StudentResult, exc: BaseException) -> None:
        for q in self.questions:
            row.questions.setdefault(
                q.id, _question_result(q, GradeStatus.GRADER_ERROR, "not graded")
            )
        row.notes.append(
            f"The grader failed on this submission ({type(exc).__name__}: {exc}); "
            "please tell your instructor."
        )
        row.status = SubmissionStatus.GRADER_ERROR

    def fault_row(self, sid: str, exc: BaseException) -> StudentResult:
        """The row of a submission the grader could not grade (its grader or its worker
        failed): a fault, never a grade (the driver retries it, then stores it as not
        graded)."""
        row = self._row(sid)
        self._fault(row, exc)
        row.add_total()
        return row

    def _grade(
        self,
        row: StudentResult,
        sid: str,
        path: Path | None,
        problem: str | None,
        refused: bool = False,
        raw: bytes | None = None,
        seeds: dict[str, int] | None = None,
    ) -> None:
        if problem and path is None and raw is None:
            row.status = SubmissionStatus.REFUSED if refused else SubmissionStatus.INVALID_NOTEBOOK
            row.notes.append(problem[0].upper() + problem[1:] + ".")
            for q in self.questions:
                row.questions[q.id] = _question_result(q, GradeStatus.NOT_ANSWERED, problem)
            return
        if problem:
            row.notes.append(problem[0].upper() + problem[1:] + ".")
        try:  # decoded in a sandboxed child: only a bounded part of it reaches this process
            nb = self._read(path, raw)
        except SubmissionError as exc:
            row.status = SubmissionStatus.INVALID_NOTEBOOK
            row.notes.append(f"The submission could not be read: {exc}.")
            for q in self.questions:
                row.questions[q.id] = _question_result(
                    q, GradeStatus.NOT_ANSWERED, "not graded: the notebook could not be read"
                )
            return
        plan = build_plan(self.release, nb, sid, {q.id: q.target for q in self.questions})
        row.notes.extend(plan.notes)
        if plan.deleted:
            row.deleted_answers = dict(plan.deleted)
        nb_id = plan.notebook_student_id
        if nb_id is not None and nb_id.strip() == PLACEHOLDER_ID:
            row.notes.append(
                f"STUDENT_ID was not set in the notebook; graded as {sid!r} (the submission's name)."
            )
        elif nb_id is not None and nb_id.strip() != sid:
            row.notes.append(
                f"STUDENT_ID in the notebook is {nb_id!r}, but the submission is named {sid!r}: "
                f"graded as {sid!r}, with the data of {sid!r}."
            )
        if not plan.answered and not any(c.origin == CellOrigin.EXTRA for c in plan.cells):
            for q in self.questions:
                row.questions[q.id] = _question_result(
                    q, GradeStatus.NOT_ANSWERED, "no answer cell found"
                )
            if not nb.get("cells"):
                row.notes.append("The notebook is empty.")
            return
        StudentSession(self, row, sid, plan, seeds).run()
        self._fingerprint(row, plan)

    def _fingerprint(self, row: StudentResult, plan) -> None:
        """Each answer's code fingerprint, for the report's similarity hints (bounded: see
        :mod:`course.grading.batch.similarity`; computed here, from the sources the reader
        child handed over, never by running anything)."""
        for qid, source in plan.answer_sources.items():
            res = row.questions.get(qid)
            if res is None or res.status == GradeStatus.NOT_ANSWERED:
                continue
            try:
                res.fingerprint = fingerprint(source, self.skeletons.get(qid, ""))
            except Exception:  # a hint that fails is no hint; it must never cost the grade
                res.fingerprint = None


class StudentSession:
    """Runs one student's plan, with restarts after timeouts and crashes."""

    def __init__(
        self,
        grader: AssignmentGrader,
        row: StudentResult,
        sid: str,
        plan,
        seeds: dict[str, int] | None = None,
    ):
        self.g = grader
        self.row = row
        self.sid = sid
        self.plan = plan
        self.skipped: set[int] = set()
        self.hard: dict[
            str, tuple[GradeStatus, str]
        ] = {}  # question -> (status, message) from its cells
        self.cell_errors: dict[int, dict] = {}
        # question -> {where: {what was called: None}}: the forbidden calls charged on it
        self.hits: dict[str, dict[str, dict[str, None]]] = {}
        # question -> notes on calls its function made through another question's function,
        # charged there
        self.via: dict[str, dict[str, None]] = {}
        self.redefined: set[str] = set()  # questions whose function a later cell redefined
        self.child: ChildHandle | None = None
        self.deadline = time.monotonic() + grader.budget()
        if seeds is None:
            seeds = grader.student_seeds(sid)
        self.data = {
            key: grader.checks.data_from_seed(key, seeds[key]) for key in grader.checks.data_keys()
        }

    # -- messages -------------------------------------------------------------------------
    def clean(self, text: str) -> str:
        if self.child is not None:
            text = text.replace(self.child.tmpdir, "<tmp>")
        return _HEX.sub("0x…", str(text))[:400]

    def _hidden_error(self, q, err: dict) -> str:
        """What a hidden case's exception may show: its type if Python's own (a class the
        student made could be named after the inputs) and the line of the student's answer cell
        it names, never its message (the student's code holds the hidden inputs there)."""
        kind = err.get("type")
        builtin = getattr(builtins, kind, None) if isinstance(kind, str) else None
        python_s = isinstance(builtin, type) and issubclass(builtin, BaseException)
        text = str(kind) if python_s else "an exception"
        line = err.get("line")
        source = self.plan.answer_sources.get(q.id, "").splitlines()
        if isinstance(line, int) and not isinstance(line, bool) and 1 <= line <= len(source):
            text += f" at line {line} of your answer: {source[line - 1].strip()[:200]}"
        return text + " (a hidden case: its message is not shown)"

    def _err_text(self, err: dict) -> str:
        return self.clean(f"{err.get('type', 'Error')}: {err.get('message', '')}".rstrip(": "))

    # -- child lifecycle ------------------------------------------------------------------
    def _failure_status(self, cause: str) -> GradeStatus:
        if "memory" in cause or "MemoryError" in cause:
            return GradeStatus.MEMORY
        return GradeStatus.CRASH

    def _run_cells(self) -> bool:
        for i, cell in enumerate(self.plan.cells):
            if i in self.skipped:
                continue
            limit = self.g.timeout_for(cell.question)
            try:
                reply = self._request(
                    cell.question,
                    Op.RUN,
                    min(limit, max(0.1, self.deadline - time.monotonic())),
                    added=cell.origin == CellOrigin.EXTRA
                    and self.plan.deleted.get(cell.question or "") != "adopted",
                    where=cell.label if cell.origin == CellOrigin.EXTRA else "your answer cell",
                    source=cell.source,
                    capture=self._captured_by(cell),
                )
            except ChildTimeout:
                self._cell_failed(
                    i,
                    GradeStatus.TIMEOUT,
                    f"{cell.label} did not finish within {limit:g} s and was stopped",
                )
                return False
            except ChildDied as exc:
                self._cell_failed(
                    i,
                    self._failure_status(exc.cause),
                    f"{cell.label} stopped the process: {exc.cause}",
                )
                return False
            if reply.get("status") == ReplyStatus.ERROR:
                err = reply.get("error") or {}
                self.cell_errors[i] = err
                if cell.question and _out_of_memory(err):
                    self.hard.setdefault(
                        cell.question,
                        (GradeStatus.MEMORY, f"{cell.label} ran out of memory (MemoryError)"),
                    )
        return True

    def _captured_by(self, cell) -> list[list[str]]:
        """``[[name, question]]`` of the answer function a cell of a function question
        defines: the child keeps it as that cell left it, grading calls that one (issue 37
        item 5: the answer graded is the one its answer cell defined, as the self-check right
        after it sees it), and its forbidden calls are its question's (item 3)."""
        q = self.g.checks.questions.get(cell.question) if cell.question else None
        if q is None or q.kind != QuestionKind.FUNCTION or not q.target:
            return []
        return [[q.target, q.id]]

    def _cell_failed(self, i: int, status: GradeStatus, message: str) -> None:
        self.skipped.add(i)
        cell = self.plan.cells[i]
        if cell.question:
            self.hard.setdefault(cell.question, (status, message))
        else:
            self.row.notes.append(f"{message[0].upper() + message[1:]}; it was skipped ({status}).")
        self._drop_child()

    def _request(
        self,
        question: str | None,
        op: Op,
        timeout: float,
        *,
        added: bool = False,
        where: str = "your answer",
        **fields,
    ) -> dict:
        """One request to the child; forbidden calls it reported meanwhile are charged (they
        reached the parent as they happened, see course.grading.tripwire) once each, on the
        question whose code made them (issue 37 item 3):

        - a call made by an answer function of another question that forbids it (the child
          labels each answer function with its question right after its answer cell) is
          charged there, and ``question`` gets a note instead;
        - any other call counts against ``question``, named as coming from ``where``;
        - a cell the student ``added`` (not one adopted as a deleted answer cell) is a
          scratch cell, wherever it stands: its call counts against every value question that
          forbids the function, since its numbers could be pasted into the answer, and against
          no function question (graded on hidden inputs, so trying the library in a scratch
          cell costs it nothing).

        A label names only what the child says of itself: at worst it moves a charge to
        another question that forbids the same function, as calling that question's function
        would."""
        child = self.child
        assert child is not None, "ensure_child() first"
        try:
            return child.request(op, timeout, **fields)
        finally:
            for call in child.take_events():
                self._charge(question, call, added, where)

    def _charge(self, question: str | None, call, added: bool, where: str) -> None:
        if added:
            for qid in self.g.forbid_by_value:
                self._hit(qid, call, where)
            return
        if question is None:
            return
        owner = call.where
        if (
            owner
            and owner != question
            and self.g.forbid.get(owner, frozenset()) & set(call.implements)
        ):
            self._hit(owner, call, "your answer")
            if self.g.forbid.get(question, frozenset()) & set(call.implements):
                q, o = self.g.checks.questions[question], self.g.checks.questions[owner]
                note = (
                    f"your {q.target} calls {o.target} (your answer to {owner}), which calls "
                    f"{call.describe(self.g.forbid[owner])}: charged on {owner}"
                )
                self.via.setdefault(question, {})[note] = None
            return
        self._hit(question, call, where)

    def _hit(self, question: str, call, where: str) -> None:
        forbidden = self.g.forbid.get(question, frozenset())
        if forbidden & set(call.implements):
            text = call.describe(forbidden)
            self.hits.setdefault(question, {}).setdefault(where, {})[text] = None

    def _forbidden_message(self, qid: str) -> str:
        """ "your answer calls course.lsq.fit; your added cell at position 9 calls ...,
        which this question forbids"."""
        parts = [
            f"{where} calls {', '.join(sorted(what))}" for where, what in self.hits[qid].items()
        ]
        return "; ".join(parts) + ", which this question forbids"

    def _drop_child(self) -> None:
        if self.child is not None:
            self.child.close()
            if self.child.cleanup_failed:  # the instructor's record (never the feedback)
                self.row.cleanup_failed = (self.row.cleanup_failed or []) + [
                    f for f in self.child.cleanup_failed if f not in (self.row.cleanup_failed or [])
                ]
            self.child = None

    def ensure_child(self) -> bool:
        """A live child that has run every (non-skipped) cell; False when out of time."""
        while self.child is None:
            if time.monotonic() > self.deadline:
                return False
            init = {
                "student_id": self.sid,
                "assignment": self.g.name,
                "data": {k: encode(v) for k, v in self.data.items()},
                "data_module": self.g.data_source,
            }
            self.child = self.g.sandbox.start(init, self.g.options.ready_timeout)
            if not self._run_cells():
                self._drop_child()
        return True

    # -- grading ----------------------------------------------------------------------------
    def run(self) -> None:
        try:
            for q in self.g.questions:
                result = self._grade_question(q)
                if self.plan.deleted.get(q.id) == "adopted":
                    result.message = (
                        f"graded from your added cell (the answer cell of {q.id} was deleted)"
                        + (f"; {result.message}" if result.message else "")
                    )
                for note in self.via.get(q.id, ()):
                    result.message = note + (f"; {result.message}" if result.message else "")
                if q.id in self.redefined:
                    result.message = (
                        f"{q.target} is defined again after its answer cell: the answer "
                        "cell's version was graded, as the self-check sees it"
                        + (f"; {result.message}" if result.message else "")
                    )
                self.row.questions[q.id] = result
            self._late_charges()
        finally:
            self._drop_child()

    def _late_charges(self) -> None:
        """A question charged after it was graded (its function made a forbidden call while a
        later question ran it, on inputs its own cases never gave): it scores 0 now."""
        for qid in self.hits:
            result = self.row.questions.get(qid)
            if result is not None and result.status not in (
                GradeStatus.FORBIDDEN,
                GradeStatus.NOT_ANSWERED,
            ):
                q = self.g.checks.questions[qid]
                self.row.questions[qid] = _question_result(
                    q, GradeStatus.FORBIDDEN, self._forbidden_message(qid), 0.0, result.cases
                )

    def _answer_cell_error(self, qid: str):
        errors = [
            self.cell_errors[i]
            for i, c in enumerate(self.plan.cells)
            if c.question == qid and c.origin == CellOrigin.ANSWER and i in self.cell_errors
        ]
        return errors[-1] if errors else None

    def _grade_question(self, q) -> QuestionResult:
        if q.id not in self.plan.answered:
            return _question_result(
                q,
                GradeStatus.NOT_ANSWERED,
                f"the answer cell of {q.id} (id {answer_cell_id(q.id)!r}) is missing from the "
                "notebook (deleted?)"
                + (f" and no added cell defines {q.target}" if q.target else ""),
            )
        if q.kind == QuestionKind.SHORT_ANSWER:
            return self._grade_short_answer(q)
        if not self.ensure_child():
            return _question_result(
                q, GradeStatus.SKIPPED, "not graded: the time budget for this submission ran out"
            )
        if q.id in self.hard:
            status, message = self.hard[q.id]
            return _question_result(q, status, message)
        if self.hits.get(q.id):
            return _question_result(q, GradeStatus.FORBIDDEN, self._forbidden_message(q.id))
        if q.kind == QuestionKind.CHOICE:
            return self._grade_choice(q)
        if q.kind == "value":
            return self._grade_value(q)
        return self._grade_function(q)

    def _grade_short_answer(self, q) -> QuestionResult:
        """A short answer waits for the instructor's mark (course grade --short-answers)."""
        text = self.plan.texts.get(q.id, "")
        if is_unanswered_text(text):
            return _question_result(
                q, GradeStatus.NOT_ANSWERED, "the answer cell still holds its placeholder"
            )
        result = _question_result(q, GradeStatus.TO_MARK, "your instructor marks this answer")
        result.answer = text[:MAX_SHORT_ANSWER]
        return result

    def _read_variable(self, q) -> tuple[dict, QuestionResult | None]:
        """Ask the child for the answer variable of ``q``: ``(reply, None)``, or a finished
        question result when the child failed or the variable is missing or still a stub."""
        try:
            reply = self._request(q.id, Op.VALUE, 30, name=q.target)
        except (ChildTimeout, ChildDied) as exc:
            self._drop_child()
            return {}, _question_result(
                q,
                GradeStatus.CRASH,
                f"reading {q.target} failed ({getattr(exc, 'cause', 'timeout')})",
            )
        status = reply.get("status")
        if status == ReplyStatus.UNDEFINED:
            return reply, self._missing(q, f"no variable {q.target}")
        if status == ReplyStatus.STUB:
            return reply, _question_result(q, GradeStatus.NOT_ANSWERED, f"{q.target} is still ...")
        return reply, None

    def _grade_choice(self, q) -> QuestionResult:
        reply, early = self._read_variable(q)
        if early is not None:
            return early
        status = reply.get("status")
        try:
            got = decode(reply.get("value"), allow_band=False) if status == ReplyStatus.OK else None
        except (EncodingError, TypeError, ValueError, KeyError):
            got = None
        expected = q.expected(data=self.data[q.data] if q.data is not None else None)
        verdict = choice_verdict(q.id, q.options, expected, got)
        case = CaseResult.of(q.target, verdict)
        if verdict.ok:
            return _question_result(q, GradeStatus.PASS, "", q.points, [case])
        return _question_result(q, GradeStatus.FAIL, verdict.message, 0.0, [case])

    def _missing(self, q, what: str) -> QuestionResult:
        err = self._answer_cell_error(q.id)
        if err is None or err.get("type") == "NotImplementedError":
            return _question_result(q, GradeStatus.NOT_ANSWERED, what)
        return _question_result(
            q, GradeStatus.ERROR, f"your answer cell raised {self._err_text(err)}"
        )

    def _grade_value(self, q) -> QuestionResult:
        g = self.g
        reply, early = self._read_variable(q)
        if early is not None:
            return early
        status = reply.get("status")
        if status != ReplyStatus.OK:
            return _question_result(
                q,
                GradeStatus.ERROR,
                f"{q.target} must be plain data (numbers, arrays, bools, strings): "
                f"{self._err_text(reply.get('error') or {})}",
            )
        try:
            got = decode(reply.get("value"), allow_band=False)
        except (EncodingError, TypeError, ValueError, KeyError):
            return _question_result(q, GradeStatus.ERROR, f"{q.target} could not be read")
        if q.data is not None:
            expected = q.expected(data=self.data[q.data])
            mistakes = q.mistaken(data=self.data[q.data]) if q.mistakes else []
        else:
            expected = g.value_expected[q.id]
            mistakes = g.value_mistakes[q.id]
        # message: for the student, never an expected value; detail: the instructor's records
        others = g.other_answers.get(q.id, ())
        verdict = compare(
            expected, got, q.rtol, q.atol, path=q.target, mistakes=mistakes, others=others
        )
        case = CaseResult.of(q.target, verdict)
        if not verdict.ok:
            case.detail = verdict.detail  # instructor only (results.jsonl)
        if verdict.ok:
            return _question_result(q, GradeStatus.PASS, "", q.points, [case])
        message = verdict.message
        err = self._answer_cell_error(q.id)
        if err is not None:
            message += f" (your answer cell also raised {self._err_text(err)})"
        return _question_result(q, GradeStatus.FAIL, message, 0.0, [case])

    def _grade_function(self, q) -> QuestionResult:
        """Call the student's function on every case, in order; a timeout, crash, stub or the
        end of the time budget stops the run (later cases are "not run")."""
        g = self.g
        cases = q.public_cases + q.hidden_cases
        run = _CaseRun()
        answers = g.case_expected[q.id]
        for k, (case, label, expected, mistakes) in enumerate(
            zip(cases, _case_labels(cases), answers, g.case_mistakes[q.id])
        ):
            others = answers[:k] + answers[k + 1 :]  # a result hard-coded from another case
            if run.stopped:
                run.results.append(CaseResult(label, False, "not run"))
            elif self.child is None and not self.ensure_child():
                run.stop(GradeStatus.SKIPPED, "the time budget for this submission ran out", True)
                run.results.append(CaseResult(label, False, "not run"))
            else:
                early = self._call_case(q, run, case, label, expected, mistakes, others)
                if early is not None:
                    return early
        if self.hits.get(q.id):
            return _question_result(
                q, GradeStatus.FORBIDDEN, self._forbidden_message(q.id), 0.0, run.results
            )
        return run.result(q)

    def _call_case(
        self, q, run: _CaseRun, case, label: str, expected, mistakes, others=()
    ) -> QuestionResult | None:
        """Run one case into ``run``; a finished question result when the function is missing
        or not a function."""
        limit = self.g.timeout_for(q.id)
        try:
            reply = self._request(
                q.id,
                Op.CALL,
                limit,
                name=q.target,
                args=encode(case.args),
                kwargs=encode(case.kwargs),
            )
        except ChildTimeout:
            self._drop_child()
            run.stop(
                GradeStatus.TIMEOUT,
                f"{q.target} did not return within {limit:g} s on {label} and was stopped",
            )
            run.results.append(CaseResult(label, False, "timeout"))
            return None
        except ChildDied as exc:
            self._drop_child()
            run.stop(
                self._failure_status(exc.cause),
                f"calling {q.target} on {label} stopped the process: {exc.cause}",
            )
            run.results.append(CaseResult(label, False, exc.cause))
            return None
        status = reply.get("status")
        if reply.get("redefined") is True:
            self.redefined.add(q.id)
        if status == ReplyStatus.UNDEFINED:
            return self._missing(q, f"no function {q.target}")
        if status == ReplyStatus.NOT_CALLABLE:
            return _question_result(q, GradeStatus.ERROR, f"{q.target} is not a function")
        if status == ReplyStatus.STUB:
            run.stop(GradeStatus.NOT_ANSWERED, f"{q.target} raises NotImplementedError")
            run.results.append(CaseResult(label, False, "not answered"))
        elif status == ReplyStatus.ERROR:
            err = reply.get("error") or {}
            if _out_of_memory(err):
                run.status = GradeStatus.MEMORY  # stops the run; the message stays the first
            text = self._hidden_error(q, err) if case.hidden else self._err_text(err)
            run.fail(
                CaseResult(label, False, f"raised {text}", raised=True, kind=MistakeKind.RAISED)
            )
        elif status != ReplyStatus.OK:
            why = "" if case.hidden else f" ({self._err_text(reply.get('error') or {})})"
            message = f"returned something that is not plain data{why}"
            run.fail(CaseResult(label, False, message, kind=MistakeKind.NOT_PLAIN_DATA))
        else:
            try:
                got = decode(reply.get("value"), allow_band=False)
            except (EncodingError, TypeError, ValueError, KeyError):
                run.results.append(CaseResult(label, False, "unreadable result"))
                return None
            verdict = compare(
                expected,
                got,
                q.rtol,
                q.atol,
                mistakes=mistakes,
                hidden=case.hidden,
                others=others,
            )
            message = _KEYS.sub("", verdict.message) if case.hidden else verdict.message
            result = CaseResult.of(label, verdict, message)
            if verdict.ok:
                run.results.append(result)
            else:  # detail: the instructor's records only (results.jsonl)
                result.detail = verdict.detail
                run.fail(result)
        return None


def _out_of_memory(err: dict) -> bool:
    """Whether a child's error is its memory running out: a MemoryError, or an OSError with
    ENOMEM (the sandbox answers so where memory would escape its limit, e.g. memfd_create)."""
    kind, message = err.get("type"), str(err.get("message", ""))
    return kind == "MemoryError" or (
        kind in ("OSError", "MemoryError") and message.startswith(f"[Errno {errno.ENOMEM}]")
    )


def _question_result(q, status, message="", points=0.0, cases=None) -> QuestionResult:
    return QuestionResult(round(float(points), 4), q.points, status, message, cases or [])


def _case_labels(cases) -> list[str]:
    """A public case's own label; hidden cases are numbered ("hidden case 2")."""
    labels, n_hidden = [], 0
    for case in cases:
        n_hidden += bool(case.hidden)
        labels.append(f"hidden case {n_hidden}" if case.hidden else case.label)
    return labels


#: After one of these, the remaining cases of a function question are not run.
_STOPPING = frozenset(
    {
        GradeStatus.TIMEOUT,
        GradeStatus.CRASH,
        GradeStatus.MEMORY,
        GradeStatus.NOT_ANSWERED,
        GradeStatus.SKIPPED,
    }
)


@dataclass
class _CaseRun:
    """The cases of one function question so far: their results, the status that stopped the
    run (``None``: none did) and the message the student sees."""

    results: list[CaseResult] = field(default_factory=list)
    status: GradeStatus | None = None
    message: str = ""

    @property
    def stopped(self) -> bool:
        return self.status in _STOPPING

    def stop(self, status: GradeStatus, message: str, keep_first: bool = False) -> None:
        """The run stops with ``status``; its message replaces the first failure's unless
        ``keep_first``."""
        self.status = status
        self.message = (self.message or message) if keep_first else message

    def fail(self, case: CaseResult) -> None:
        """A failed case; the first failure's message is the one the student sees."""
        self.results.append(case)
        self.message = self.message or f"{case.label}: {case.message}"

    def result(self, q) -> QuestionResult:
        """Points by the fraction of cases passed (all or nothing unless ``q.partial``); the
        status: the one that stopped the run, else pass, error (every failed case raised and
        none passed), partial or fail."""
        passed = sum(1 for r in self.results if r.ok)
        if self.status == GradeStatus.NOT_ANSWERED and passed == 0:
            return _question_result(q, self.status, self.message, 0.0, self.results)
        everything = passed == len(self.results)
        points = q.points * (passed / len(self.results) if q.partial else float(everything))
        status = self.status
        if status is None:
            if everything:
                status = GradeStatus.PASS
            elif passed == 0 and all(r.raised for r in self.results if not r.ok):
                status = GradeStatus.ERROR
            else:
                status = GradeStatus.PARTIAL if points > 0 else GradeStatus.FAIL
        return _question_result(q, status, "" if everything else self.message, points, self.results)
