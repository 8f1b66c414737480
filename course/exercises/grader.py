"""``course grade``: grade a folder of submitted notebooks, safely and in parallel.

The trusted parent (this module) reads each notebook as plain JSON, matches it against the
release (:func:`course.exercises.notebook.build_plan`), runs the student's cells in a sandboxed
child (:mod:`course.exercises.sandbox`), then asks the child for values and function results
and compares them with references it computes itself. A timeout or crash costs only the
question it happened in: the child is killed, a fresh one re-runs the cells (skipping the bad
one) and grading continues.

Outputs in ``OUT``: ``grades.csv`` (student, one column per question, total, max, status),
``feedback/<student>.md`` and ``results.jsonl`` (one line per student, appended as students
finish; a rerun skips students already graded with the same checks and library version).
"""

from __future__ import annotations

import csv
import io
import json
import os
import re
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

from course.exercises.codec import EncodingError, decode, encode
from course.exercises.compare import compare
from course.exercises.notebook import (
    SubmissionError,
    build_plan,
    forbidden_mentions,
    read_submission,
)
from course.exercises.release import checks_digest, load_assignment
from course.exercises.sandbox import ChildDied, ChildTimeout, Limits, Sandbox
from course.exercises.selfcheck import PLACEHOLDER_ID

__all__ = ["GradeOptions", "Grader", "Summary", "find_submissions", "grade"]

ABNORMAL = ("timeout", "crash", "memory", "forbidden", "grader error", "skipped")


def _version() -> str:
    import course

    return str(getattr(course, "__version__", "unknown"))


@dataclass
class GradeOptions:
    jobs: int = field(default_factory=lambda: os.cpu_count() or 1)
    timeout: float | None = None  # overrides every question's time limit
    memory_mb: int = 1024
    mode: str = "auto"
    regrade: bool = False
    progress: bool = True
    ready_timeout: float = 60.0
    student_budget: float | None = None  # wall-clock seconds for one student, all attempts


def find_submissions(folder: Path, assignment: str) -> list[tuple[str, Path | None, str | None]]:
    """``(student_id, notebook_path, problem)`` for every submission in ``folder``: a file
    ``<id>.ipynb`` or a folder ``<id>/`` holding ``<assignment>.ipynb`` (or a single notebook)."""
    found: dict[str, tuple[str, Path | None, str | None]] = {}
    for entry in sorted(Path(folder).iterdir()):
        if entry.name.startswith((".", "_")):
            continue
        if entry.is_file() and entry.suffix == ".ipynb":
            sid = entry.stem
            found[sid] = (sid, entry, None)
        elif entry.is_dir():
            sid = entry.name
            if sid in found:
                continue
            preferred = entry / f"{assignment}.ipynb"
            notebooks = sorted(
                p for p in entry.rglob("*.ipynb") if ".ipynb_checkpoints" not in p.parts
            )
            if preferred.is_file():
                found[sid] = (sid, preferred, None)
            elif len(notebooks) >= 1:
                note = (
                    None
                    if len(notebooks) == 1
                    else f"several notebooks in the folder; graded {notebooks[0].name}"
                )
                found[sid] = (sid, notebooks[0], note)
            else:
                found[sid] = (sid, None, "no notebook (.ipynb) in the submission folder")
    return [found[k] for k in sorted(found)]


_HEX = re.compile(r"0x[0-9a-fA-F]{6,}")


class Grader:
    """Grades submissions of one assignment (thread-safe: one :meth:`grade_one` per thread)."""

    def __init__(self, solution_dir: Path, options: GradeOptions | None = None, deny_read=()):
        self.options = options or GradeOptions()
        self.solution_dir = Path(solution_dir).resolve()
        self.checks, self.release = load_assignment(self.solution_dir)
        self.name = self.checks.name
        self.digest = checks_digest(self.solution_dir, self.checks.files)
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
        solutions_root = (
            self.solution_dir.parent
            if self.solution_dir.parent.name == "solutions"
            else self.solution_dir
        )
        self.sandbox = Sandbox(
            mode=self.options.mode,
            limits=Limits(memory_mb=self.options.memory_mb, cpu_seconds=int(self.budget()) + 5),
            preload=self.checks.preload,
            deny_read=[solutions_root, *deny_read],
        )

    def close(self) -> None:
        self.sandbox.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- limits ---------------------------------------------------------------------------
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
    def _row(self, sid: str) -> dict:
        return {
            "student": sid,
            "assignment": self.name,
            "checks_sha256": self.digest,
            "version": self.version,
            "questions": {},
            "notes": [],
            "total": 0.0,
            "max": self.checks.max_points,
            "status": "ok",
        }

    def _question_result(self, q, status, message="", points=0.0, cases=None) -> dict:
        return {
            "points": round(float(points), 4),
            "max": q.points,
            "status": status,
            "message": message,
            "cases": cases or [],
        }

    def grade_one(self, sid: str, path: Path | None, problem: str | None = None) -> dict:
        """Grade one submission; never raises (a grader failure is recorded in the row)."""
        row = self._row(sid)
        try:
            self._grade(row, sid, path, problem)
        except Exception as exc:  # a bug or sandbox failure must not abort the batch
            for q in self.questions:
                row["questions"].setdefault(
                    q.id, self._question_result(q, "grader error", "not graded")
                )
            row["notes"].append(
                f"The grader failed on this submission ({type(exc).__name__}: {exc}); please tell your instructor."
            )
            row["status"] = "grader error"
        row["total"] = round(sum(r["points"] for r in row["questions"].values()), 4)
        abnormal = [
            f"{qid}: {r['status']}"
            for qid, r in row["questions"].items()
            if r["status"] in ABNORMAL
        ]
        if row["status"] == "ok" and abnormal:
            row["status"] = "; ".join(abnormal)
        return row

    def _grade(self, row: dict, sid: str, path: Path | None, problem: str | None) -> None:
        if problem and path is None:
            row["status"] = "invalid notebook"
            row["notes"].append(problem[0].upper() + problem[1:] + ".")
            for q in self.questions:
                row["questions"][q.id] = self._question_result(q, "not answered", problem)
            return
        if problem:
            row["notes"].append(problem[0].upper() + problem[1:] + ".")
        try:
            nb = read_submission(path)
        except SubmissionError as exc:
            row["status"] = "invalid notebook"
            row["notes"].append(f"The submission could not be read: {exc}.")
            for q in self.questions:
                row["questions"][q.id] = self._question_result(
                    q, "not answered", "not graded: the notebook could not be read"
                )
            return
        plan = build_plan(self.release, nb, sid)
        row["notes"].extend(plan.notes)
        nb_id = plan.notebook_student_id
        if nb_id is not None and nb_id.strip() == PLACEHOLDER_ID:
            row["notes"].append(
                f"STUDENT_ID was not set in the notebook; graded as {sid!r} (the submission's name)."
            )
        elif nb_id is not None and nb_id.strip() != sid:
            row["notes"].append(
                f"STUDENT_ID in the notebook is {nb_id!r}, but the submission is named {sid!r}: "
                f"graded as {sid!r}, with the data of {sid!r}."
            )
        if not plan.answered and not any(c.origin == "extra" for c in plan.cells):
            for q in self.questions:
                row["questions"][q.id] = self._question_result(
                    q, "not answered", "no answer cell found"
                )
            if not nb.get("cells"):
                row["notes"].append("The notebook is empty.")
            return
        _Session(self, row, sid, plan).run()


class _Session:
    """Runs one student's plan, with restarts after timeouts and crashes."""

    def __init__(self, grader: Grader, row: dict, sid: str, plan):
        self.g = grader
        self.row = row
        self.sid = sid
        self.plan = plan
        self.skipped: set[int] = set()
        self.hard: dict[str, tuple[str, str]] = {}  # question -> (status, message) from its cells
        self.cell_errors: dict[int, dict] = {}
        self.hits: dict[str, set] = {}
        self.child = None
        self.deadline = time.monotonic() + grader.budget()
        self.data = {key: grader.checks.data_for(key, sid) for key in grader.checks.data_keys()}

    # -- messages -------------------------------------------------------------------------
    def clean(self, text: str) -> str:
        if self.child is not None:
            text = text.replace(self.child.tmpdir, "<tmp>")
        return _HEX.sub("0x…", str(text))[:400]

    def _err_text(self, err: dict) -> str:
        return self.clean(f"{err.get('type', 'Error')}: {err.get('message', '')}".rstrip(": "))

    # -- child lifecycle ------------------------------------------------------------------
    def _failure_status(self, cause: str) -> str:
        return "memory" if ("memory" in cause or "MemoryError" in cause) else "crash"

    def _run_cells(self) -> bool:
        for i, cell in enumerate(self.plan.cells):
            if i in self.skipped:
                continue
            limit = self.g.timeout_for(cell.question)
            try:
                reply = self.child.request(
                    "run",
                    min(limit, max(0.1, self.deadline - time.monotonic())),
                    source=cell.source,
                    question=cell.question,
                )
            except ChildTimeout:
                self._cell_failed(
                    i, "timeout", f"{cell.label} did not finish within {limit:g} s and was stopped"
                )
                return False
            except ChildDied as exc:
                self._cell_failed(
                    i,
                    self._failure_status(exc.cause),
                    f"{cell.label} stopped the process: {exc.cause}",
                )
                return False
            if cell.question:
                self.hits.setdefault(cell.question, set()).update(reply.get("tripwire") or [])
            if reply.get("status") == "error":
                err = reply.get("error") or {}
                self.cell_errors[i] = err
                if cell.question and err.get("type") == "MemoryError":
                    self.hard.setdefault(
                        cell.question, ("memory", f"{cell.label} ran out of memory (MemoryError)")
                    )
        return True

    def _cell_failed(self, i: int, status: str, message: str) -> None:
        self.skipped.add(i)
        cell = self.plan.cells[i]
        if cell.question:
            self.hard.setdefault(cell.question, (status, message))
        else:
            self.row["notes"].append(
                f"{message[0].upper() + message[1:]}; it was skipped ({status})."
            )
        self._drop_child()

    def _drop_child(self) -> None:
        if self.child is not None:
            self.child.close()
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
                "forbid": {q.id: list(q.forbid) for q in self.g.questions if q.forbid},
            }
            self.child = self.g.sandbox.start(init, self.g.options.ready_timeout)
            if not self._run_cells():
                self._drop_child()
        return True

    # -- grading ----------------------------------------------------------------------------
    def run(self) -> None:
        try:
            for q in self.g.questions:
                self.row["questions"][q.id] = self._grade_question(q)
        finally:
            self._drop_child()

    def _answer_cell_error(self, qid: str):
        errors = [
            self.cell_errors[i]
            for i, c in enumerate(self.plan.cells)
            if c.question == qid and c.origin == "answer" and i in self.cell_errors
        ]
        return errors[-1] if errors else None

    def _grade_question(self, q) -> dict:
        g = self.g
        if q.id not in self.plan.answered:
            return g._question_result(q, "not answered", "no answer cell found (deleted?)")
        static = forbidden_mentions(self.plan.answer_sources.get(q.id, ""), q.forbid)
        if static:
            return g._question_result(
                q, "forbidden", f"the answer uses {', '.join(static)}, which this question forbids"
            )
        if not self.ensure_child():
            return g._question_result(
                q, "skipped", "not graded: the time budget for this submission ran out"
            )
        if q.id in self.hard:
            status, message = self.hard[q.id]
            return g._question_result(q, status, message)
        if self.hits.get(q.id):
            return g._question_result(
                q,
                "forbidden",
                f"the answer calls {', '.join(sorted(self.hits[q.id]))}, which this question forbids",
            )
        if q.kind == "value":
            return self._grade_value(q)
        return self._grade_function(q)

    def _missing(self, q, what: str) -> dict:
        err = self._answer_cell_error(q.id)
        if err is None or err.get("type") == "NotImplementedError":
            return self.g._question_result(q, "not answered", what)
        return self.g._question_result(q, "error", f"your answer cell raised {self._err_text(err)}")

    def _grade_value(self, q) -> dict:
        g = self.g
        try:
            reply = self.child.request("value", 30, name=q.target)
        except (ChildTimeout, ChildDied) as exc:
            self._drop_child()
            return g._question_result(
                q, "crash", f"reading {q.target} failed ({getattr(exc, 'cause', 'timeout')})"
            )
        status = reply.get("status")
        if status == "undefined":
            return self._missing(q, f"no variable {q.target}")
        if status == "stub":
            return g._question_result(q, "not answered", f"{q.target} is still ...")
        if status != "ok":
            return g._question_result(
                q,
                "error",
                f"{q.target} must be plain data (numbers, arrays, bools, strings): "
                f"{self._err_text(reply.get('error') or {})}",
            )
        try:
            got = decode(reply.get("value"), allow_band=False)
        except (EncodingError, TypeError, ValueError, KeyError):
            return g._question_result(q, "error", f"{q.target} could not be read")
        if q.data is not None:
            expected = q.expected(data=self.data[q.data])
        else:
            expected = g.value_expected[q.id]
        verdict = compare(expected, got, q.rtol, q.atol, reveal=q.public)
        case = {"label": q.target, "ok": verdict.ok, "message": verdict.message}
        if verdict.ok:
            return g._question_result(q, "pass", "", q.points, [case])
        message = verdict.message
        err = self._answer_cell_error(q.id)
        if err is not None:
            message += f" (your answer cell also raised {self._err_text(err)})"
        return g._question_result(q, "fail", message, 0.0, [case])

    def _grade_function(self, q) -> dict:
        g = self.g
        cases = q.public_cases + q.hidden_cases
        expected = g.case_expected[q.id]
        results = []
        status = None
        first_message = ""
        n_hidden = 0
        for case, exp in zip(cases, expected):
            if case.hidden:
                n_hidden += 1
                label = f"hidden case {n_hidden}"
            else:
                label = case.label
            if status in ("timeout", "crash", "memory", "not answered", "skipped"):
                results.append({"label": label, "ok": False, "message": "not run"})
                continue
            if self.child is None and not self.ensure_child():
                status = "skipped"
                first_message = first_message or "the time budget for this submission ran out"
                results.append({"label": label, "ok": False, "message": "not run"})
                continue
            limit = g.timeout_for(q.id)
            try:
                reply = self.child.request(
                    "call",
                    limit,
                    name=q.target,
                    question=q.id,
                    args=encode(case.args),
                    kwargs=encode(case.kwargs),
                )
            except ChildTimeout:
                status = "timeout"
                first_message = (
                    f"{q.target} did not return within {limit:g} s on {label} and was stopped"
                )
                results.append({"label": label, "ok": False, "message": "timeout"})
                self._drop_child()
                continue
            except ChildDied as exc:
                status = self._failure_status(exc.cause)
                first_message = f"calling {q.target} on {label} stopped the process: {exc.cause}"
                results.append({"label": label, "ok": False, "message": exc.cause})
                self._drop_child()
                continue
            if reply.get("tripwire"):
                self.hits.setdefault(q.id, set()).update(reply["tripwire"])
            rstatus = reply.get("status")
            if rstatus == "undefined":
                return self._missing(q, f"no function {q.target}")
            if rstatus == "stub":
                status = "not answered"
                first_message = f"{q.target} raises NotImplementedError"
                results.append({"label": label, "ok": False, "message": "not answered"})
                continue
            if rstatus == "notcallable":
                return g._question_result(q, "error", f"{q.target} is not a function")
            if rstatus == "error":
                err = reply.get("error") or {}
                text = f"raised {self._err_text(err)}"
                if err.get("type") == "MemoryError":
                    status = "memory"
                results.append({"label": label, "ok": False, "message": text})
                first_message = first_message or f"{label}: {text}"
                continue
            if rstatus != "ok":
                text = f"returned something that is not plain data ({self._err_text(reply.get('error') or {})})"
                results.append({"label": label, "ok": False, "message": text})
                first_message = first_message or f"{label}: {text}"
                continue
            try:
                got = decode(reply.get("value"), allow_band=False)
            except (EncodingError, TypeError, ValueError, KeyError):
                results.append({"label": label, "ok": False, "message": "unreadable result"})
                continue
            verdict = compare(exp, got, q.rtol, q.atol, reveal=not case.hidden)
            results.append({"label": label, "ok": verdict.ok, "message": verdict.message})
            if not verdict.ok:
                first_message = first_message or f"{label}: {verdict.message}"
        if self.hits.get(q.id):
            return g._question_result(
                q,
                "forbidden",
                f"the answer calls {', '.join(sorted(self.hits[q.id]))}, "
                "which this question forbids",
                0.0,
                results,
            )
        passed = sum(1 for r in results if r["ok"])
        if status == "not answered" and passed == 0:
            return g._question_result(q, "not answered", first_message, 0.0, results)
        fraction = passed / len(results) if q.partial else float(passed == len(results))
        points = q.points * fraction
        if status is None:
            if passed == len(results):
                status = "pass"
            elif (
                all(r["message"].startswith("raised ") for r in results if not r["ok"])
                and passed == 0
            ):
                status = "error"
            else:
                status = "partial" if points > 0 else "fail"
        return g._question_result(
            q, status, "" if passed == len(results) else first_message, points, results
        )


# --------------------------------------------------------------------------------------
# outputs
# --------------------------------------------------------------------------------------
def _fmt_points(x: float) -> str:
    return f"{round(float(x), 2):g}"


def feedback_markdown(row: dict, checks) -> str:
    """The student's feedback: per question points, status, message and hint."""
    lines = [f"# {checks.title}: feedback for {row['student']}", ""]
    lines.append(
        f"**Total: {_fmt_points(row['total'])} / {_fmt_points(row['max'])}**"
        + ("" if row["status"] == "ok" else f"  (status: {row['status']})")
    )
    lines += ["", "| question | points | status |", "|---|---|---|"]
    for qid, r in row["questions"].items():
        lines.append(
            f"| {qid} | {_fmt_points(r['points'])} / {_fmt_points(r['max'])} | {r['status']} |"
        )
    for qid, r in row["questions"].items():
        q = checks.questions.get(qid)
        lines += [
            "",
            f"## {qid}: {_fmt_points(r['points'])} / {_fmt_points(r['max'])} ({r['status']})",
        ]
        if r["message"]:
            lines.append("")
            lines.append(r["message"])
        if r["cases"] and len(r["cases"]) > 1 and r["status"] != "not answered":
            lines.append("")
            for case in r["cases"]:
                lines.append(
                    f"- {'PASS' if case['ok'] else 'FAIL'} {case['label']}"
                    + (f": {case['message']}" if case["message"] and not case["ok"] else "")
                )
        if q is not None and q.hint and r["points"] < r["max"]:
            lines += ["", f"Hint: {q.hint}"]
    if row["notes"]:
        lines += ["", "## Notes", ""] + [f"- {n}" for n in row["notes"]]
    lines.append("")
    lines.append(
        f"<sub>{row['assignment']} · checks {row['checks_sha256'][:12]} · course {row['version']}</sub>"
    )
    return "\n".join(lines) + "\n"


def write_csv(rows: list[dict], question_ids: list[str], path: Path) -> None:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["student", *question_ids, "total", "max", "status"])
    for row in sorted(rows, key=lambda r: r["student"]):
        writer.writerow(
            [
                row["student"],
                *(_fmt_points(row["questions"].get(q, {}).get("points", 0)) for q in question_ids),
                _fmt_points(row["total"]),
                _fmt_points(row["max"]),
                row["status"],
            ]
        )
    path.write_text(buf.getvalue(), encoding="utf-8")


@dataclass
class Summary:
    rows: list
    question_ids: list
    max_points: dict
    graded: int
    resumed: int
    seconds: float
    out: Path

    def text(self) -> str:
        n = len(self.rows)
        lines = [
            f"Graded {self.graded} submission(s), {self.resumed} already graded (resumed), "
            f"in {self.seconds:.1f} s; results in {self.out}"
        ]
        if not n:
            return lines[0]
        lines.append(f"{'question':<10}{'max':>6}{'mean':>8}{'full marks':>12}")
        for qid in self.question_ids:
            pts = [r["questions"][qid]["points"] for r in self.rows if qid in r["questions"]]
            full = sum(
                1
                for r in self.rows
                if qid in r["questions"]
                and r["questions"][qid]["points"] >= r["questions"][qid]["max"]
            )
            mean = sum(pts) / len(pts) if pts else 0.0
            lines.append(
                f"{qid:<10}{_fmt_points(self.max_points[qid]):>6}{mean:>8.2f}{100 * full / n:>11.0f}%"
            )
        total = sum(r["total"] for r in self.rows) / n
        lines.append(f"{'total':<10}{_fmt_points(sum(self.max_points.values())):>6}{total:>8.2f}")
        statuses: dict[str, int] = {}
        for r in self.rows:
            statuses[r["status"]] = statuses.get(r["status"], 0) + 1
        lines.append(
            "status: "
            + ", ".join(
                f"{k} ({v})" for k, v in sorted(statuses.items(), key=lambda kv: (-kv[1], kv[0]))
            )
        )
        return "\n".join(lines)


def _read_results(path: Path) -> dict[str, dict]:
    rows = {}
    if not path.is_file():
        return rows
    with open(path, encoding="utf-8") as f:
        for line in f:
            try:
                row = json.loads(line)
            except ValueError:
                continue  # e.g. a line cut short by an interrupted run
            if isinstance(row, dict) and "student" in row:
                rows[row["student"]] = row
    return rows


def grade(
    solution_dir: Path, submissions: Path, out: Path, options: GradeOptions | None = None
) -> Summary:
    """Grade every submission in ``submissions`` into ``out`` (see the module docstring)."""
    options = options or GradeOptions()
    start = time.monotonic()
    solution_dir, submissions, out = (
        Path(solution_dir).resolve(),
        Path(submissions).resolve(),
        Path(out).resolve(),
    )
    out.mkdir(parents=True, exist_ok=True)
    (out / "feedback").mkdir(exist_ok=True)
    results_path = out / "results.jsonl"
    if options.regrade and results_path.exists():
        results_path.unlink()
    lock = threading.Lock()
    with Grader(solution_dir, options, deny_read=[submissions, out]) as grader:
        todo = find_submissions(submissions, grader.name)
        previous = _read_results(results_path)
        rows: dict[str, dict] = {}
        pending = []
        for sid, path, problem in todo:
            old = previous.get(sid)
            if (
                old
                and old.get("checks_sha256") == grader.digest
                and old.get("version") == grader.version
            ):
                rows[sid] = old
            else:
                pending.append((sid, path, problem))
        resumed = len(rows)

        def finish(row: dict) -> None:
            with lock:
                with open(results_path, "a", encoding="utf-8") as f:
                    f.write(json.dumps(row, sort_keys=True, ensure_ascii=False) + "\n")
                    f.flush()
                (out / "feedback" / f"{row['student']}.md").write_text(
                    feedback_markdown(row, grader.checks), encoding="utf-8"
                )
                rows[row["student"]] = row

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
        jobs = max(1, int(options.jobs))
        with ThreadPoolExecutor(max_workers=jobs) as pool:
            futures = [
                pool.submit(grader.grade_one, sid, path, problem) for sid, path, problem in pending
            ]
            for fut in as_completed(futures):
                finish(fut.result())
                if bar is not None:
                    bar.update(1)
        if bar is not None:
            bar.close()
        for row in rows.values():  # feedback of resumed students too (cheap, keeps OUT complete)
            fb = out / "feedback" / f"{row['student']}.md"
            if not fb.exists():
                fb.write_text(feedback_markdown(row, grader.checks), encoding="utf-8")
        qids = [q.id for q in grader.questions]
        final = [rows[sid] for sid, _, _ in todo]
        write_csv(final, qids, out / "grades.csv")
        return Summary(
            final,
            qids,
            {q.id: q.points for q in grader.questions},
            len(pending),
            resumed,
            time.monotonic() - start,
            out,
        )
