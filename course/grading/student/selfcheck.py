"""The student's self-check: ``check = Assignment.load(name, student_id=STUDENT_ID)``.

``check("q1")`` finds the answer (variable or function) in the notebook, runs the PUBLIC cases
shipped in ``checks.json`` (their expected values sealed: :mod:`course.grading.authoring.seal`) and prints, per case, pass or fail: on failure a hint (staged: a nudge
first, more after repeated failures, counted in this kernel) and what is wrong IN KIND (shape,
NaN, sign, a constant factor, transposed, off by one, another order, a declared mistake) with the
tolerance. It never prints an expected value, never shows test code, and says how many hidden
cases run at grading. A forbidden library call is a FAIL, as it scores 0 at grading: from the
setup cell on, the forbidden functions report every call from the notebook, whatever the path
(the grader's tripwires, :func:`course.grading.tripwire.watch`); an import alone costs nothing.
A function question counts the calls of its public cases and of its answer cell; a value
question those of its answer cell and of cells the student added (not another question's
answer cell, nor a protected cell of the released notebook), as the grader does. ``check("q1", value)`` checks an explicit value; ``check.data("key")`` returns the student's personal data set. Everything works offline.

In the grader's sandbox the same setup cell returns a silent stand-in (no checks run in the
student's process); see :mod:`course.grading.sandbox.runner`.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import sys
import weakref
from pathlib import Path
from typing import Any

from course.grading.authoring.personal import PersonalData
from course.grading.authoring.seal import sealed_compare
from course.grading.codec import decode, encode
from course.grading.compare import check_signature, chosen_hint, describe
from course.grading.items import ITEM_KINDS, AnswerCells, self_check_item
from course.grading.tripwire import course_modules, label_callers, watch
from course.grading.vocabulary import (
    CHECKS_FILE,
    PLACEHOLDER_ID,
    CellRole,
    PublicQuestion,
    PublicSpec,
    QuestionKind,
    answer_cell_id,
    id_off_pattern,
    id_pattern_in,
)

__all__ = ["PLACEHOLDER_ID", "Assignment"]


#: Set by the grading runner (sandboxed child) before any student code runs.
_GRADING: dict | None = None


class _GradingStandIn:
    """What ``Assignment.load`` returns inside the grader: silent ``check``, grader's data."""

    def __init__(self, context):
        self._context = context

    def __call__(self, *args, **kwargs):
        return None

    def data(self, key: str):
        if key not in self._context["data"]:
            raise KeyError(f"no data set {key!r} in this assignment")
        return decode(self._context["data"][key])

    def all(self):
        return None

    def submit(self, *args, **kwargs):
        return None

    def __repr__(self):
        return "<self-check disabled while grading>"


def _locate(name: str, path) -> tuple[str, Path]:
    candidates = []
    if path:
        candidates += [Path(path), Path(path) / name]
    env = os.environ.get("COURSE_EXERCISES")
    if env:
        candidates += [Path(env) / name, Path(env)]
    cwd = Path.cwd()
    for folder in [cwd, *cwd.parents]:
        candidates += [folder, folder / name, folder / "exercises" / name]
    if os.environ.get("COURSE_DIR"):  # never the package's own location (site-packages)
        candidates.append(Path(os.environ["COURSE_DIR"]) / "exercises" / name)
    from course.workspace import packaged_materials

    packaged = packaged_materials()
    if packaged is not None:  # an installed student edition: its own copy of the release
        candidates.append(packaged / "exercises" / name)
    for folder in candidates:
        spec_file = folder / CHECKS_FILE
        if spec_file.is_file():
            try:
                if json.loads(spec_file.read_text("utf-8")).get("assignment") == name:
                    return "json", folder
            except (OSError, ValueError):
                continue
        if folder.name == name and (folder / "checks.py").is_file():
            return "solution", folder
    raise FileNotFoundError(
        f"Cannot find the checks of assignment {name!r}. Open the notebook from its folder "
        f"(exercises/{name}/, which holds checks.json) or pass path=... to Assignment.load."
    )


class Assignment:
    """The self-check of one assignment (see the module docstring)."""

    def __init__(self, spec: PublicSpec, folder: Path, student_id: str | None, data_module=None):
        self.spec = spec
        self.name = spec.assignment
        self.folder = folder
        self.student_id = None if student_id is None else str(student_id).strip()
        self._questions: dict[str, PublicQuestion] = {q.id: q for q in spec.questions}
        self._data_module = data_module
        self._data_cache: dict[str, Any] = {}
        self._failures: dict[str, int] = {}  # failed self-checks per question: hint stage
        # a graded class's data, issued by the instructor (None: drawn here from data.py)
        self.personal = PersonalData.read(folder) if data_module is None else None
        # which cell set each answer (notes an answer set outside its answer cell)
        self._cells = AnswerCells.install({q.target: q.id for q in spec.questions if q.target})
        # the class's student ID pattern (``course export --id-pattern``), None without one
        self.id_pattern = id_pattern_in(folder)
        # the notebook's protected cells (setup and context): a forbidden call there counts
        # against no question, as at grading
        self._protected = _protected_cells(folder, spec.assignment, data_module is not None)
        # forbidden calls from the notebook: (cell, call) pairs, and the calls made while a
        # question's public cases run
        self.calls: set[tuple] = set()
        self._running: set | None = None
        # the tripwires' labels of calling code: each function answer, by its question
        self._callers: dict = {}
        _watch_forbidden(self)

    @classmethod
    def load(cls, name: str, student_id: str | None = None, path=None):
        """The self-check of assignment ``name`` (searches ``checks.json`` from the current folder
        upwards, then the course's ``exercises/``; in ``solutions/<name>/`` it reads checks.py)."""
        if _GRADING is not None:
            return _GradingStandIn(_GRADING)
        kind, folder = _locate(name, path)
        if kind == "json":
            check = cls(PublicSpec.read(folder), folder, student_id)
        else:
            from course.grading.authoring.checks import load_checks
            from course.grading.authoring.release import public_spec

            checks = load_checks(folder)
            spec = PublicSpec.loads(public_spec(checks).text())  # exactly what a release ships
            check = cls(spec, folder, student_id, data_module=checks.data_module)
        note = check.id_note()
        if note:
            print(note)
        return check

    def id_note(self) -> str:
        """What is wrong with ``STUDENT_ID`` ('' when nothing is, or none was given): still
        the placeholder, or off the pattern of the class's IDs. Said when the self-check is
        loaded and by ``check.all()``; ``check.submit()`` refuses such an ID."""
        sid = self.student_id
        if sid is None:
            return ""
        if sid == PLACEHOLDER_ID:
            return (
                f"Note: STUDENT_ID is still the placeholder {PLACEHOLDER_ID!r}: set it to your "
                "student ID, exactly as registered, and run this cell again (your personal "
                "data and check.submit() need it)."
            )
        off = id_off_pattern(sid, self.id_pattern)
        return f"Note: {off} (check.submit() refuses it)." if off else ""

    # -- data ---------------------------------------------------------------------------
    def _data_mod(self):
        if self._data_module is None:
            if not self.spec.data_file:
                raise KeyError(f"assignment {self.name} has no per-student data")
            from course.grading.authoring.checks import load_data_module

            self._data_module = load_data_module(self.folder / self.spec.data_file, self.name)
        return self._data_module

    def data(self, key: str):
        """Your personal data set ``key`` (generated from your STUDENT_ID)."""
        if key not in self.spec.data_keys:
            raise KeyError(
                f"assignment {self.name} has no data set {key!r}; known: {self.spec.data_keys}"
            )
        self._require_id()
        if self.personal is not None:
            return self.personal.data(str(self.student_id), key)
        if key not in self._data_cache:
            from course.grading.authoring.checks import student_rng

            func = getattr(self._data_mod(), key)
            self._data_cache[key] = encode(func(student_rng(self.name, key, str(self.student_id))))
        return decode(self._data_cache[key])

    def _require_id(self):
        if not self.student_id or self.student_id == PLACEHOLDER_ID:
            raise ValueError(
                "Set STUDENT_ID in the first cell to your student ID, then re-run that cell."
            )
        off = id_off_pattern(self.student_id, self.id_pattern)
        if off:
            raise ValueError(off + ".")

    # -- submitting ---------------------------------------------------------------------
    def submit(self, notebook=None, out=None):
        """Run every self-check, then write ``<ID>_<assignment>.ipynb`` ready to upload.

        Refuses (with one message, writing nothing) a missing, placeholder, demo or malformed
        ``STUDENT_ID`` and an ID the class's personal data do not know. ``notebook`` is the
        saved notebook (found automatically in Jupyter and VS Code); ``out`` the folder to
        write to (default: beside the notebook). Returns the path written, or None.
        """
        from course.grading.student.submit import submit_from_kernel

        return submit_from_kernel(self, sys._getframe(1).f_globals, notebook, out)

    # -- checking -----------------------------------------------------------------------
    def __repr__(self):
        return f"<self-check of {self.name}: {len(self._questions)} questions; call check('q1')>"

    def all(self, namespace: dict | None = None) -> None:
        """Self-check every question in turn, then sum up (:func:`public_summary`)."""
        ns = namespace if namespace is not None else sys._getframe(1).f_globals
        earned = {}
        for qid in self._questions:
            earned[qid] = self._check(qid, ns, None, False)
            print()
        print(public_summary(self.spec, earned))
        note = self.id_note()
        if note:
            print(note)

    def __call__(self, qid: str, *value) -> None:
        """Self-check question ``qid``; pass ``value`` to check it instead of the notebook's."""
        if len(value) > 1:
            raise TypeError("check(question) or check(question, value)")
        self._check(qid, sys._getframe(1).f_globals, value[0] if value else None, bool(value))

    def _check(self, qid, ns, value, explicit) -> float:
        """Print the self-check of ``qid``; return the points its public checks give."""
        earned = self._check_one(qid, ns, value, explicit)
        q = self._questions.get(qid)
        note = self._cells.note(qid, q.target) if q is not None and not explicit else None
        if note:
            print(note)
        return earned

    def _check_one(self, qid, ns, value, explicit) -> float:
        if qid not in self._questions:
            print(
                f"{qid}: no such question in {self.name} (questions: {', '.join(self._questions)})"
            )
            return 0.0
        q = self._questions[qid]
        if q.kind in ITEM_KINDS:  # choice, short answer: never right/wrong here
            saved = None
            if q.kind == QuestionKind.SHORT_ANSWER:
                from course.grading.student.submit import saved_short_answer

                saved = saved_short_answer(ns, self.name, qid)
            got = value if explicit else ns.get(q.target, _MISSING)
            self_check_item(q, got, _MISSING, saved)
            return 0.0
        points = f"{q.points:g} point{'s' if q.points != 1 else ''}"
        print(f"{qid} ({points}): {'function' if q.kind == 'function' else 'variable'} {q.target}")
        if q.kind == "function":
            fraction = self._check_function(
                q, value if explicit else ns.get(q.target, _MISSING), ns
            )
        else:
            fraction = self._check_value(q, value if explicit else ns.get(q.target, _MISSING))
        return q.points * float(fraction or 0.0)

    # -- hints --------------------------------------------------------------------------
    def _failed(self, q, verdicts=()) -> str:
        """Count one failed self-check of ``q`` and return the hint line it earns ('' if none).

        The diagnosis chooses first (:func:`~course.grading.compare.chosen_hint`): a declared
        mistake one of the failed ``verdicts`` names shows its own hint (or none), an answer
        computed in float32 none.
        Otherwise, after the k-th failure the student sees stage ``min(k, n) - 1`` of the n
        stages: a nudge first, the formula only after repeated failures. The count lives in
        this object, i.e. in the kernel's memory, and starts again with a fresh kernel.
        """
        chosen = chosen_hint(verdicts, q.mistake_hints)
        if chosen is not None:
            return f"Hint (for this mistake): {chosen}" if chosen else ""
        self._failures[q.id] = self._failures.get(q.id, 0) + 1
        stages = q.hints
        if not stages:
            return ""
        k = min(self._failures[q.id], len(stages))
        if len(stages) == 1:
            return f"Hint: {stages[0]}"
        more = " (another failed check shows the next one)" if k < len(stages) else ""
        return f"Hint {k} of {len(stages)}{more}: {stages[k - 1]}"

    def _not_answered(self, q, why: str) -> None:
        print(f"  not answered yet: {why}")

    def _forbidden_fail(self, q, names) -> None:
        """``names``: what the notebook called, as :meth:`tripwire.Call.describe` says it."""
        where = (
            "your answer"
            if q.kind == "function"
            else "your answer cell or a cell you added (they run at grading too)"
        )
        print(
            f"  FAIL: {where} calls {', '.join(sorted(names))} (or its private implementation), "
            "which this question forbids: it scores 0 at grading whatever it returns. Compute it "
            "with numpy instead; if you deleted the call, restart the kernel and run all cells."
        )

    # -- forbidden calls ----------------------------------------------------------------
    def _record(self, call) -> None:
        """A forbidden function was called from the notebook (a :class:`tripwire.Call`)."""
        if self._running is not None:
            self._running.add(call)  # while the self-check runs the student's function
            return
        self.calls.add((self._cell_now(), call))

    def _forget_cell(self, info=None) -> None:
        """A cell is run again: the calls its previous run made no longer stand (IPython's
        ``pre_run_cell``; a deleted cell's calls stay until the kernel restarts)."""
        cell = getattr(info, "cell_id", None)
        if cell:
            self.calls = {(c, call) for c, call in self.calls if c != cell}

    def _cell_now(self):
        """The running cell: its id when the front end says it, else its input number."""
        cell = getattr(self._cells, "_cell", None)
        if cell:
            return str(cell)
        shell = getattr(self._cells, "_shell", None)
        history = getattr(shell, "user_ns", {}).get("In") if shell is not None else None
        return ("In", len(history) - 1) if isinstance(history, list) else None

    def _cell_question(self, cell) -> str | None:
        """Whose cell ``cell`` is: a question's id for its answer cell, "" for another cell
        (added), None for a protected or check cell or when unknown (outside a notebook)."""
        if isinstance(cell, str):
            for qid in self._questions:
                if cell == answer_cell_id(qid):
                    return qid
            return None if cell.endswith("-check") or cell in self._protected else ""
        if isinstance(cell, tuple):
            shell = getattr(self._cells, "_shell", None)
            history = getattr(shell, "user_ns", {}).get("In", [])
            source = history[cell[1]] if 0 <= cell[1] < len(history) else ""
            for q in self._questions.values():
                if q.target and _defines(source, q.target):
                    return q.id
            return ""
        return None

    def _forbidden_calls(self, q) -> set[str]:
        """What the notebook called, of the forbidden functions of ``q`` (their private
        helpers named as such), where grading counts it (:meth:`_record`): its answer cell,
        and for a value question also the added cells."""
        if not q.forbid:
            return set()
        mine = {q.id, ""} if q.kind != "function" else {q.id}
        return {
            call.describe(q.forbid)
            for cell, call in self.calls
            if set(call.implements) & set(q.forbid) and self._cell_question(cell) in mine
        }

    def _label_answers(self, ns: dict) -> None:
        """Label every function answer in ``ns`` with its question, so that a forbidden call
        its code makes is charged there, as the grader does (:func:`tripwire.label_callers`)."""
        self._callers.clear()
        for other in self._questions.values():
            func = ns.get(other.target) if other.kind == "function" and other.target else None
            if callable(func):
                label_callers(self._callers, func, other.id)

    def _charged_here(self, q, calls: set) -> set[str]:
        """Of the forbidden calls made while ``q``'s function ran, those charged on ``q``:
        one made by another question's function, which forbids it too, is charged there (the
        student is told), as the grader does."""
        charged = set()
        for call in calls:
            if not set(call.implements) & set(q.forbid):
                continue
            owner = self._questions.get(call.where) if call.where != q.id else None
            if owner is not None and set(call.implements) & set(owner.forbid):
                print(
                    f"  note: your {q.target} calls {owner.target} (your answer to {owner.id}), "
                    f"which calls {call.describe(owner.forbid)}: charged on {owner.id}, not here"
                )
                continue
            charged.add(call.describe(q.forbid))
        return charged

    @contextlib.contextmanager
    def _running_cases(self, into: set):
        """Count the forbidden calls made while the student's function runs into ``into``."""
        self._running = into
        try:
            yield
        finally:
            self._running = None

    def _check_value(self, q, got):  # -> 1.0 or 0.0 when public, else None
        if got is _MISSING:
            return self._not_answered(q, f"no variable {q.target} (run your answer cell first)")
        if got is Ellipsis:
            return self._not_answered(q, f"{q.target} is still ...")
        try:
            got = decode(encode(got))
        except TypeError as exc:
            hint = self._failed(q)
            print(f"  FAIL: {q.target} must be plain numbers/arrays/bools/strings ({exc})")
            if hint:
                print(f"      {hint}")
            return
        forbidden = self._forbidden_calls(q)
        if forbidden:
            self._forbidden_fail(q, forbidden)
            hint = self._failed(q)
            if hint:
                print(f"      {hint}")
            return
        if q.cases:
            case = q.cases[0]
            verdict = _compare_case(case, got, q, path=q.target)
            if verdict.ok:
                print("  PASS")
                return 1.0
            print("  FAIL")
            hint = self._failed(q, [verdict])
            if hint:
                print(f"      {hint}")
            print(f"      {verdict.message}")
            return 0.0
        # private value (per-student or not public): type/shape, then public properties
        results = []
        verdict = check_signature(q.signature, got, path=q.target)
        results.append((f"type and shape ({_sig_text(q.signature)})", verdict.ok, verdict.message))
        if verdict.ok and q.properties:
            try:
                data = self.data(q.data) if q.data else None
                for text, ok in getattr(self._data_mod(), q.properties)(data, got):
                    results.append((str(text), bool(ok), ""))
            except Exception as exc:  # a property function must not break the self-check
                results.append(
                    ("properties", False, f"could not evaluate: {type(exc).__name__}: {exc}")
                )
        failed = [r for r in results if not r[1]]
        hint = self._failed(q) if failed else ""
        if hint:
            print(f"  {hint}")
        for text, ok, message in results:
            print(
                f"  {'PASS' if ok else 'FAIL'}: {text}" + (f"\n      {message}" if message else "")
            )
        who = f" for your ID {self.student_id!r}" if q.data else ""
        print(
            f"  The value itself{who} is not shipped with the notebook: it is checked at grading."
        )

    def _check_function(self, q, func, ns=None):  # -> the fraction of public cases that count
        if func is _MISSING:
            return self._not_answered(q, f"no function {q.target} (run your answer cell first)")
        if not callable(func):
            hint = self._failed(q)
            print(f"  FAIL: {q.target} is {describe(func)}, not a function")
            if hint:
                print(f"      {hint}")
            return
        forbidden: set[str] = self._forbidden_calls(q)
        self._label_answers(ns if ns is not None else {})
        running: set = set()
        passed = 0
        lines: list[str] = []
        failures: list = []  # the failed cases' verdicts: their diagnosis may choose the hint
        for case in q.cases:
            args, kwargs = decode(case.args), decode(case.kwargs)
            try:
                with self._running_cases(running):
                    got = func(*args, **kwargs)
            except NotImplementedError:
                return self._not_answered(q, f"{q.target} raises NotImplementedError")
            except Exception as exc:
                message = f"your function raised {type(exc).__name__}: {str(exc)[:200]}"
                verdict = None
            else:
                if got is Ellipsis:
                    return self._not_answered(q, f"{q.target} returns ...")
                try:
                    verdict = _compare_case(case, decode(encode(got)), q)
                    message = verdict.message
                except TypeError as exc:
                    verdict, message = (
                        None,
                        f"returned {describe(got)}, which is not plain data ({exc})",
                    )
            if verdict is not None and verdict.ok:
                passed += 1
                lines.append(f"  PASS: {case.label}")
            else:
                lines.append(f"  FAIL: {case.label}\n      {message}")
                failures.append(verdict)
        forbidden |= self._charged_here(q, running)
        n = len(q.cases)
        hidden = q.hidden_cases
        more = (
            f"; {hidden} hidden case{'s' if hidden != 1 else ''} run{'s' if hidden == 1 else ''} at grading"
            if hidden
            else ""
        )
        if forbidden:
            self._forbidden_fail(q, forbidden)
            hint = self._failed(q)
            if hint:
                print(f"      {hint}")
            print(
                f"  0 of {n} public case{'s count' if n != 1 else ' counts'} while the forbidden "
                f"call stays ({passed} of {n} give the right values){more}."
            )
            return 0.0
        if passed < n:
            hint = self._failed(q, failures)
            if hint:
                print(f"  {hint}")
        for line in lines:
            print(line)
        print(f"  {passed} of {n} public case{'s pass' if n != 1 else ' passes'}{more}.")
        return passed / n if q.partial or passed == n else 0.0


def _compare_case(case, got, q, path: str = ""):
    """The student's ``got`` against a public case's SEALED expected value (and its declared
    mistakes): the file holds no value to compare with, see :mod:`course.grading.authoring.seal`."""
    return sealed_compare(case.expected, got, path=path, mistakes=case.mistakes)


def public_summary(spec: PublicSpec, earned: dict) -> str:
    """The last line of ``check.all()``: "N of M points from public checks; K hidden cases at
    grading", and what else only grading decides. ``earned``: question -> points."""
    covered = sum(q.points for q in spec.questions if q.kind == "function" or q.cases)
    hidden = sum(q.hidden_cases for q in spec.questions if q.kind != "short_answer")
    later = [q for q in spec.questions if q.kind != "function" and not q.cases]
    line = (
        f"{sum(earned.values()):g} of {covered:g} points from public checks; "
        f"{hidden} hidden case{'s' if hidden != 1 else ''} at grading"
    )
    if later:
        kinds = sorted(
            {
                {"choice": "choices", "short_answer": "short answers"}.get(
                    q.kind, "personal or private values"
                )
                for q in later
            }
        )
        line += (
            f"; {sum(q.points for q in later):g} more points ({', '.join(kinds)}) are decided "
            "only at grading"
        )
    return f"{line} ({spec.max_points:g} points in total)."


class _Missing:
    def __repr__(self):
        return "<missing>"


_MISSING = _Missing()


def _protected_cells(folder: Path, name: str, solution: bool) -> frozenset[str]:
    """The ids of the protected cells (setup and context) of notebook ``name`` in ``folder``,
    as the release marks them (``metadata.course.role``); in a ``solution`` notebook, which
    marks only what is not protected, every code cell without a role. A copy of a protected
    cell keeps its role and grading ignores it: here it counts nowhere either. Empty when the
    notebook cannot be read (every other cell then counts as added, the stricter reading)."""
    try:
        cells = json.loads((folder / f"{name}.ipynb").read_text("utf-8")).get("cells", [])
    except (OSError, ValueError, AttributeError):
        return frozenset()
    ids = set()
    for cell in cells if isinstance(cells, list) else ():
        if not isinstance(cell, dict) or cell.get("cell_type") != "code":
            continue
        meta = cell.get("metadata", {}).get("course", {})
        role = meta.get("role") if isinstance(meta, dict) else None
        if isinstance(cell.get("id"), str) and (
            role in (CellRole.SETUP, CellRole.CONTEXT) or (solution and role is None)
        ):
            ids.add(cell["id"])
    return frozenset(ids)


def _defines(source: str, target: str) -> bool:
    """Whether a cell's ``source`` assigns or defines ``target`` at the start of a line."""
    return bool(
        re.search(
            rf"^\s*(?:def\s+{re.escape(target)}\s*\(|{re.escape(target)}\s*(?::[^=]*)?=(?!=))",
            source,
            re.MULTILINE,
        )
    )


def _sig_text(sig) -> str:
    if "kind" in sig:
        return f"{sig['kind']}" + (f", shape {tuple(sig['shape'])}" if sig["shape"] else " scalar")
    if "names" in sig:
        return "a list of strings"
    if "sequence" in sig:
        return f"sequence of {len(sig['sequence'])}"
    if "dict" in sig:
        return f"dict with keys {sorted(sig['dict'])}"
    return next(iter(sig))


#: Undoes the tripwires of the self-check loaded last (one per kernel: loading again replaces them).
_RESTORE: list = []


def _watch_forbidden(assignment: Assignment) -> None:
    """Set the grader's tripwires on the forbidden functions of ``assignment`` in this kernel
    (:func:`course.grading.tripwire.watch`), reporting to it while it lives."""
    while _RESTORE:
        _RESTORE.pop()()
    names = sorted({name for q in assignment.spec.questions for name in q.forbid})
    if not names:
        return
    import importlib

    for module in course_modules():  # every library module counts as the library
        with contextlib.suppress(Exception):
            importlib.import_module(module)
    ref = weakref.ref(assignment)

    def record(name: str) -> None:
        target = ref()
        if target is not None:
            target._record(name)

    def forget(info=None) -> None:
        target = ref()
        if target is not None:
            target._forget_cell(info)

    untrip = watch(names, record, assignment._callers)
    shell = getattr(assignment._cells, "_shell", None)
    if shell is not None:
        shell.events.register("pre_run_cell", forget)

    def restore() -> None:
        untrip()
        if shell is not None:
            with contextlib.suppress(ValueError):
                shell.events.unregister("pre_run_cell", forget)

    _RESTORE.append(restore)
    weakref.finalize(assignment, _restore_if_current, restore)


def _restore_if_current(restore) -> None:
    if restore in _RESTORE:
        _RESTORE.remove(restore)
        restore()
