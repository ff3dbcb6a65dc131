"""Grade one returned lab notebook so that the grade holds (``teaching/README.md``, "Grading").

The student's notebook is never run as it was returned. The grader takes the instructor's
notebook (``source/<lab>/<lab>.ipynb``) and keeps only the student's **answer cells** (nbgrader
``solution`` cells, matched by ``grade_id``); every other cell (data, parameters, reference values,
explanations, checks) is the instructor's, whatever the student did to it. Then:

1. **In the sandbox** (:mod:`.sandbox`), in a folder holding only the release files: the lab's cells
   run with the student's answers (every cell of an answer's id, in the order the notebook ran them,
   and the code cells the student added, each after the lab's cell above it), the parameters set for this student (``student_id``: their data
   variant). Right after each answer cell, the names its check reads are read back as plain values
   (numbers, strings, arrays), before any reference value after it exists.
2. **Formula answers** (answer cells defining a function) run again alone, in a sandbox without
   lorisnb (numpy only): a function that calls lorisnb, or copies its formula at run time, fails;
   one that takes lorisnb's code from another copy on the machine is refused by the sandbox's guard
   (:func:`._sandbox_child.install_guard`), and its points with it, with a note.
3. **In the grader's own process**, the instructor's notebook runs with the same parameters; each
   test cell (with its hidden tests) runs there, with the student's values and sandboxed
   functions put in place of the answers' names, and the checks imported by the grader. Hidden
   tests draw their cases from ``hidden_seed``, a seed the student never saw. **Predictions**
   (answer cells tagged ``prediction``) are graded from a run of their own, alone, in a sandbox
   without lorisnb, given only the numbers the lab's own cells had set before them (as this process
   has them: no answer cell can change them): a prediction computed with the lab's functions
   (``simulate_and_score``) or lorisnb is not a prediction, and scores 0, saying so.

A test cell that raises scores 0, else its points (nbgrader's rule).
"""

from __future__ import annotations

import ast
import builtins
import contextlib
import errno
import hashlib
import io
import json
import os
import re
import shutil
import stat
import symtable
import tempfile
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, NoReturn

import nbformat

from lorisnb.errors import AnswerError, ValidationError
from lorisnb.tools.teaching._grading import SandboxedAnswer
from lorisnb.tools.teaching._prose import lab_variant, same_id
from lorisnb.tools.teaching.sandbox import Limits, NotPlain, Sandbox, SandboxError, SandboxTimeout, decode, error_of

GRADER_VERSION = "19"  # part of every result's digest: a new grader regrades everything (3: D1-G1 vary per student;
# 4: the guard keeps lorisnb out of formula answers, predictions are graded alone from the lab's numbers;
# 5: lists and tuples of numbers, and numpy's strings, read back as values; E1 reads a one-value Series;
# 6: IPython's magics and shell escapes run as in Jupyter; the lab's names a def reads when defined (eps=eps)
# given to answers run alone; predictions get the functions of the earlier answer cells; 7: those names' values are
# the grader's run of the lab's, not the student's; a cell under %%time/%%capture is read as its body; each sandbox
# sees its own folder alone in the temporary folders; 8: %%capture NAME binds NAME, as IPython does; 9: every cell of
# an answer's id runs (a split cell's halves, copies), in the notebook's execution order; cells the student added run
# in their place; a prediction's set-up (earlier cells' functions and imports, its own imports) is not timed as the
# prediction, and a failing line after its value (display) is left out; display and _ as in Jupyter; a failing answer
# cell's error is its message; prints past the file size limit are cut, not fatal; the copy check's exemption of the
# instructor's answer reads it without its placeholders; 10: a prediction failing alone after its value is graded
# on what it computed up to the failing line (+=, if, for kept); an id's cells that fail in execution-count order
# run top to bottom; the lab's def-time values are given to added cells' defs too; 11: a formula run alone gets the
# functions of the cells added below it up to its check; values set in cells added right below an answer are read
# there, and a name left unset without a placeholder is no "no answer yet"; no file of a submission is read through
# a link or quoted; the instructor's markers noted; an unused top-level import of lorisnb left out of a formula or
# prediction run alone (one used is refused, as before); a NameError alone says what the formula has; float32 named;
# 12: an answer whose cell is missing (deleted, metadata removed) is unanswered, never graded from the lab's run;
# 13: the earlier cells' functions given to an answer run alone run cell by cell, and a refusal names the cell that
# used lorisnb; 14: a formula whose cell fails alone after binding its functions (a try-out line's TypeError) is
# graded on its definitions, as a NameError's was; an unanswered prediction is "no answer yet"; only the values the
# cells added below an answer changed are read and named there; a sandbox that ended is no time-out; every reply
# value is checked, whatever wrote it; 15: a seed set in the parameters cell is noted, as a student_id of another
# student is: the variant graded is the folder's; 16: only the names the grader asked for are read from a reply and a
# check's references are never rebound by an answer's values; an answer whose code wrote into the grader's reply channel
# (a line beside its reply, a second reply, names not asked for) scores 0 with a note; ids alike in Unicode (NFKC) are one;
# 17: a reply to a request found after its first was read (the code forged it and answered the grader's sync itself)
# scores 0 for the request's answer, wherever it is found; C1's hidden cases are drawn from the grader's seed;
# 18: the cells run in a module registered as __main__, as in Jupyter: a cell's function pickles by name (a fork pool);
# 19: a wrong number is told too high or too low, never lorisnb's number (nor a hidden case's value): feedback written
# by 18 gave it; a temporary folder holding the Python environment is emptied, the environment bound back read-only)


@dataclass(frozen=True)
class Question:
    """A test cell: its ``grade_id``, points, the answer cells it checks and the names it reads."""

    grade_id: str
    points: float
    answers: tuple[str, ...]
    names: tuple[str, ...]


@dataclass(frozen=True)
class LabSpec:
    """What the grader needs of an instructor notebook."""

    name: str
    notebook: nbformat.NotebookNode
    questions: tuple[Question, ...]
    functions: Mapping[str, tuple[str, ...]]  # answer grade_id -> the functions it defines
    values: Mapping[str, tuple[str, ...]]  # answer grade_id -> the names read back after it
    # prediction answer grade_id -> the names the lab's own cells bound before it (what it may use)
    predictions: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    # every answer grade_id -> the names the lab's own cells bound before it
    lab_before: Mapping[str, tuple[str, ...]] = field(default_factory=dict)

    @property
    def max_points(self) -> float:
        return float(sum(q.points for q in self.questions))


PREDICTION = "prediction"  # the tag of an answer cell that predicts: graded alone, from the lab's numbers


def _nbgrader(cell: nbformat.NotebookNode) -> dict[str, Any]:
    return dict(cell.get("metadata", {}).get("nbgrader", {}))


def _assigned(source: str) -> set[str]:
    """Names a cell binds at its top level (assignments, defs, imports)."""
    tree = ast.parse(source)
    names: set[str] = set()
    for node in tree.body:
        targets: list[ast.expr] = []
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, (ast.AnnAssign, ast.AugAssign)):
            targets = [node.target]
        elif isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        for t in targets:
            names |= {n.id for n in ast.walk(t) if isinstance(n, ast.Name)}
    return names


def _imported(source: str) -> set[str]:
    """Names a cell's top-level imports bind."""
    names: set[str] = set()
    for node in ast.parse(source).body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            names |= {(a.asname or a.name).split(".")[0] for a in node.names if a.name != "*"}
    return names


def _loaded(source: str) -> set[str]:
    return {n.id for n in ast.walk(ast.parse(source)) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}


def lab_spec(source_nb: Path) -> LabSpec:
    """The questions of an instructor notebook: each test cell checks the answer cells since the
    previous test cell; the names it reads that they bind are what is graded."""
    nb = nbformat.read(source_nb, as_version=4)
    questions, pending = [], []
    functions: dict[str, tuple[str, ...]] = {}
    values: dict[str, tuple[str, ...]] = {}
    predictions: dict[str, tuple[str, ...]] = {}
    lab_before: dict[str, tuple[str, ...]] = {}
    lab_names: set[str] = set()  # bound by the lab's own cells so far
    for cell in nb.cells:
        meta = _nbgrader(cell)
        if cell.cell_type != "code":
            continue
        if meta.get("solution"):
            pending.append((meta["grade_id"], cell.source))
            lab_before[str(meta["grade_id"])] = tuple(sorted(lab_names))
            if PREDICTION in cell.get("metadata", {}).get("tags", []):
                predictions[str(meta["grade_id"])] = tuple(sorted(lab_names))
        elif meta.get("grade"):
            read = _loaded(cell.source)
            names: list[str] = []
            for gid, src in pending:
                tree = ast.parse(src)
                defs = tuple(n.name for n in tree.body if isinstance(n, ast.FunctionDef) and n.name in read)
                functions[gid] = defs
                values[gid] = tuple(sorted((_assigned(src) & read) - set(defs)))
                names += [*defs, *values[gid]]
            questions.append(
                Question(meta["grade_id"], float(meta.get("points", 0)), tuple(g for g, _ in pending), tuple(names))
            )
            pending = []
        else:
            lab_names |= _assigned(cell.source) | _imported(cell.source)
    if not questions:
        raise ValueError(f"{source_nb}: no test cell (nbgrader 'grade' cell with points): nothing to grade")
    return LabSpec(source_nb.stem, nb, tuple(questions), functions, values, predictions, lab_before)


@dataclass
class Score:
    """One question's result: points out of ``max_points`` and what the checks said."""

    question: str
    points: float
    max_points: float
    message: str


@dataclass
class SubmissionResult:
    """A graded submission (``result.json`` in its output folder)."""

    student: str
    lab: str
    scores: list[Score]
    isolation: str
    seconds: float
    notes: list[str] = field(default_factory=list)
    digest: str = ""
    error: str = ""  # not graded (the notebook could not be read...): every question 0, and why
    # the cells holding nbgrader's instructor markers (:data:`SOURCE_MARKERS`): the lab's solutions leaked
    instructor_markers: list[str] = field(default_factory=list)

    @property
    def points(self) -> float:
        return float(sum(s.points for s in self.scores))

    @property
    def max_points(self) -> float:
        return float(sum(s.max_points for s in self.scores))

    def to_json(self) -> str:
        return json.dumps(asdict(self), indent=1)

    @classmethod
    def from_json(cls, text: str) -> SubmissionResult:
        d = json.loads(text)
        d["scores"] = [Score(**s) for s in d["scores"]]
        return cls(**d)


def answer_cells(nb: nbformat.NotebookNode, counted: bool = True) -> dict[str, list[str]]:
    """grade_id -> the sources of a returned notebook's answer cells of that id, in the order the
    notebook ran them: several when JupyterLab's "split cell" gave both halves the id, or a cell was
    copied (a copy keeps it). Their ``execution_count`` order where each has one, else the
    notebook's order (cells never run, split ones: run top to bottom); ``counted=False``: the
    notebook's order always (a count is only a cell's *last* run: a split cell whose top half was
    run again last counts bottom first, and the grader falls back on this order when that fails)."""
    found: dict[str, list[tuple[int, Any, str]]] = {}
    for k, cell in enumerate(nb.cells):
        meta = _nbgrader(cell)
        if cell.cell_type == "code" and meta.get("solution") and meta.get("grade_id") is not None:
            found.setdefault(str(meta["grade_id"]), []).append((k, cell.get("execution_count"), cell.source))
    out: dict[str, list[str]] = {}
    for gid, cells in found.items():
        by_count = counted and all(isinstance(c, int) and not isinstance(c, bool) for _, c, _ in cells)
        cells.sort(key=lambda t: (t[1], t[0]) if by_count else (t[0],))
        out[gid] = [src for _, _, src in cells]
    return out


def student_answers(nb: nbformat.NotebookNode) -> dict[str, str]:
    """grade_id -> the source of a returned notebook's answer cell: of several cells of one id
    (:func:`answer_cells`), their sources one after the other, in the order the notebook ran them
    (:func:`repeated_answers` names them for a note)."""
    return {gid: "\n".join(srcs) for gid, srcs in answer_cells(nb).items()}


def repeated_answers(nb: nbformat.NotebookNode) -> dict[str, int]:
    """grade_id -> how many answer cells of a returned notebook carry it, where more than one."""
    return {g: len(srcs) for g, srcs in answer_cells(nb).items() if len(srcs) > 1}


def added_cells(lab: nbformat.NotebookNode, nb: nbformat.NotebookNode) -> dict[int, list[str]]:
    """The code cells a student added to a returned notebook (no nbgrader metadata, not the
    parameters cell, not a cell of the lab's own without metadata): index of the instructor's cell
    they follow (the nearest cell above them the lab has: by ``grade_id``, the parameters cell by its
    tag; -1 at the top) -> their sources, in the notebook's order. nbgrader keeps them, and the
    notebook ran them (an import, a helper a later answer calls): the grader runs them in their place."""
    by_id: dict[str, int] = {}
    plain: dict[str, int] = {}
    params = -1
    for i, cell in enumerate(lab.cells):
        gid = _nbgrader(cell).get("grade_id")
        if gid is not None:
            by_id.setdefault(str(gid), i)
        elif "parameters" in cell.get("metadata", {}).get("tags", []):
            params = i
        elif cell.cell_type == "code":
            plain.setdefault(cell.source.strip(), i)
    out: dict[int, list[str]] = {}
    anchor = -1
    for cell in nb.cells:
        gid = _nbgrader(cell).get("grade_id")
        if gid is not None:
            anchor = by_id.get(str(gid), anchor)
        elif "parameters" in cell.get("metadata", {}).get("tags", []):
            anchor = params if params >= 0 else anchor
        elif cell.cell_type == "code" and cell.source.strip() in plain:
            anchor = plain[cell.source.strip()]
        elif cell.cell_type == "code" and cell.source.strip():
            out.setdefault(anchor, []).append(cell.source)
    return out


def as_python(source: str) -> str:
    """An answer cell as IPython runs it: its magics (``%%time``, ``%matplotlib inline``) and shell
    escapes (``!ls``, ``x = !ls``) made the calls IPython makes of them
    (``get_ipython().run_cell_magic('time', '', ...)``, IPython's own
    ``TransformerManager().transform_cell``), which the sandbox's stand-in for IPython's shell runs
    (:class:`._sandbox_child.Shell`); plain Python is unchanged. A shell escape runs as
    ``os.system`` would, in the same sandbox, so it can do nothing plain Python cannot (and in an
    answer graded with numpy only it is refused, as another process is)."""
    runs = re.match(r"\s*%%(time|timeit|capture|prun)\b([^\n]*)\n(.*)", source, re.S)
    if runs:  # IPython transforms the body of these before it runs it (%%time over a cell with %matplotlib)
        name, line, body = runs.groups()
        return f"get_ipython().run_cell_magic({name!r}, {line.strip()!r}, {as_python(body)!r})\n"
    try:
        from IPython.core.inputtransformer2 import TransformerManager
    except ImportError:  # pragma: no cover (the notebooks extra installs IPython)
        return source
    try:
        return str(TransformerManager().transform_cell(source))
    except Exception:  # noqa: BLE001 (what IPython cannot transform runs as it is, and fails as Python)
        return source


#: Cell magics that run their body in the notebook's namespace, as IPython does (its definitions stay
#: there); ``%%timeit``'s names stay its own.
RUN_BODY = ("time", "capture", "prun")


def cell_body(source: str) -> str:
    """An answer cell as :func:`as_python` made it, as read for its definitions: a cell under
    ``%%time``, ``%%capture`` or ``%%prun`` (one ``get_ipython().run_cell_magic(...)`` call, which
    runs the body in the notebook's namespace) is its body's Python, after a blank line for the
    magic's (so its lines stay the cell's); any other cell as it is."""
    try:
        tree = ast.parse(source)
    except SyntaxError:
        return source
    if len(tree.body) != 1 or not isinstance(tree.body[0], ast.Expr):
        return source
    call = tree.body[0].value
    if not (
        isinstance(call, ast.Call)
        and isinstance(call.func, ast.Attribute)
        and call.func.attr == "run_cell_magic"
        and isinstance(call.func.value, ast.Call)
        and isinstance(call.func.value.func, ast.Name)
        and call.func.value.func.id == "get_ipython"
        and len(call.args) == 3
        and all(isinstance(a, ast.Constant) and isinstance(a.value, str) for a in call.args)
    ):
        return source
    name, body = call.args[0].value, call.args[2].value  # type: ignore[attr-defined]
    return "\n" + cell_body(str(body)) if name in RUN_BODY else source


def defined_with(source: str) -> set[str]:
    """The names a cell's top-level functions and classes read when they are *defined* (their
    default values, decorators, annotations unless ``from __future__ import annotations``, and a
    class's bases and keywords): ``def correctness(ate_m, aoe_deg, eps=eps, phi=phi)`` needs the
    lab's ``eps`` and ``phi`` before it is even called (under ``%%time``: :func:`cell_body`). Empty
    when it does not parse."""
    try:
        tree = ast.parse(cell_body(source))
    except SyntaxError:
        return set()
    lazy = any(
        isinstance(n, ast.ImportFrom) and n.module == "__future__" and any(a.name == "annotations" for a in n.names)
        for n in tree.body
    )
    exprs: list[ast.AST] = []
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            a = node.args
            exprs += [*node.decorator_list, *a.defaults, *(d for d in a.kw_defaults if d is not None)]
            if not lazy:
                exprs += [x.annotation for x in (*a.posonlyargs, *a.args, *a.kwonlyargs, a.vararg, a.kwarg)
                          if x is not None and x.annotation is not None]  # fmt: skip
                exprs += [node.returns] if node.returns is not None else []
        elif isinstance(node, ast.ClassDef):
            exprs += [*node.decorator_list, *node.bases, *(k.value for k in node.keywords)]
    return {n.id for e in exprs for n in ast.walk(e) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}


def plain_values(values: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    """The values read back (``_plain``'s form) that are numbers, strings or arrays of numbers, as
    :meth:`.sandbox.Sandbox.bind` takes them."""
    return {n: dict(v) for n, v in values.items() if set(v) == {"value"} or "array" in v}


#: Top-level statements a formula answer keeps when it is graded on its definitions only.
_DEFINITIONS = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Import, ast.ImportFrom)


def _rebuild(source: str, pick: Callable[[ast.stmt], ast.stmt | str | None]) -> str | None:
    """``source`` rebuilt from its top-level statements, each one's line kept (an error names the
    cell's line): ``pick(statement)`` gives it back to keep it as written, a text to put in its place
    (one line), None to leave it out. Statements, not lines: ``import lorisnb as ln; STRICT = False``
    is two. None when it does not parse."""
    text = source.replace("\r\n", "\n").replace("\r", "\n")
    try:
        tree = ast.parse(text)
    except SyntaxError:
        return None
    lines = text.split("\n")
    raw = [line.encode() for line in lines]  # the AST's columns count UTF-8 bytes
    out = [""] * len(lines)
    for node in tree.body:
        got = pick(node)
        if got is None:
            continue
        decorators = getattr(node, "decorator_list", [])
        first = min([node.lineno, *(d.lineno for d in decorators)])
        if isinstance(got, str):
            piece = got
        else:  # as written, from its first decorator (a decorated def starts its line) to its end
            col = 0 if decorators else node.col_offset
            last, end = node.end_lineno or node.lineno, node.end_col_offset or 0
            if last == first:
                piece = raw[first - 1][col:end].decode()
            else:
                piece = b"\n".join([raw[first - 1][col:], *raw[first : last - 1], raw[last - 1][:end]]).decode()
        for k, part in enumerate(piece.split("\n")):
            at = first - 1 + k
            out[at] = f"{out[at]}; {part}" if k == 0 and out[at].strip() else part
    return "\n".join(out)


def _lorisnb_alias(node: ast.Import | ast.ImportFrom, alias: ast.alias) -> bool:
    module = alias.name if isinstance(node, ast.Import) else ("" if node.level else node.module or "")
    return module.split(".")[0] == "lorisnb"


def _without_aliases(node: ast.Import | ast.ImportFrom, drop: Callable[[ast.alias], bool]) -> ast.stmt | str | None:
    """The import ``node`` without the names ``drop`` picks (:func:`_rebuild`'s ``pick``): as it is,
    rewritten with its other names (``import lorisnb as ln, pandas as pd`` -> ``import pandas as pd``),
    or None."""
    rest = [a for a in node.names if not drop(a)]
    if len(rest) == len(node.names):
        return node
    if not rest:
        return None
    one = ast.Import(names=rest) if isinstance(node, ast.Import) else ast.ImportFrom(node.module, rest, node.level)
    return ast.unparse(one)


def _global_reads(source: str) -> set[str]:
    """The module's names ``source`` reads: at its top level, or in its functions, lambdas, classes
    and comprehensions where the name is the module's (a function's own local ``ln`` is not)."""
    top = symtable.symtable(source, "<cell>", "exec")
    read = {s.get_name() for s in top.get_symbols() if s.is_referenced()}
    tables = list(top.get_children())
    while tables:
        t = tables.pop()
        tables += t.get_children()
        read |= {s.get_name() for s in t.get_symbols() if s.is_referenced() and s.is_global()}
    return read


#: What a kept assignment's value may be made of (:func:`safe_value`) besides constants and names.
_SAFE_NODES = (ast.Constant, ast.Tuple, ast.List, ast.Set, ast.Dict, ast.UnaryOp, ast.BinOp, ast.BoolOp,
               ast.Compare, ast.unaryop, ast.operator, ast.boolop, ast.cmpop, ast.Load, ast.keyword)  # fmt: skip


def safe_value(expr: ast.expr, known: set[str]) -> bool:
    """Whether a helper's top-level value can be given to an answer run alone: constants and their
    arithmetic, tuples and lists of them, names of what the cells define or import (``known``: a
    function, an import, a constant kept before), an attribute of those (``np.inf``), a lambda whose
    defaults are such values. Never a call, nor a name of the lab's (its variables may hold what the
    answer is checked against)."""
    if isinstance(expr, ast.Lambda):
        a = expr.args
        return all(safe_value(d, known) for d in [*a.defaults, *(d for d in a.kw_defaults if d is not None)])
    if isinstance(expr, ast.Name):
        return expr.id in known
    if isinstance(expr, ast.Attribute):
        return safe_value(expr.value, known)
    if isinstance(expr, ast.Starred):
        return safe_value(expr.value, known)
    if not isinstance(expr, _SAFE_NODES):
        return False
    return all(safe_value(c, known) if isinstance(c, ast.expr) else isinstance(c, _SAFE_NODES)
               for c in ast.iter_child_nodes(expr))  # fmt: skip


def _targets(node: ast.stmt) -> list[str] | None:
    """The names an assignment binds when its targets are plain names (``A = 1``, ``A, B = 1, 2``), else None."""
    targets = node.targets if isinstance(node, ast.Assign) else [node.target]  # type: ignore[attr-defined]
    names: list[str] = []
    for t in targets:
        elts = t.elts if isinstance(t, (ast.Tuple, ast.List)) else [t]
        plain = [e for e in elts if isinstance(e, ast.Name)]
        if len(plain) != len(elts):
            return None
        names += [e.id for e in plain]
    return names


def definitions_only(
    source: str,
    assignments: bool = False,
    lorisnb: bool = True,
    keep: tuple[type[ast.stmt], ...] | None = None,
    known: set[str] | None = None,
) -> str | None:
    """``source`` with every top-level statement other than a ``def``, a ``class`` or an import
    (``assignments``: and an assignment; ``lorisnb=False``: and no import of lorisnb, the import's
    other names kept) left out, each statement on its line (an error names the line of the cell);
    None when it does not parse. A formula answer's try-out lines (``print(correctness(ate, aoe,
    eps, phi))``, reading the lab's numbers) are not its formula. A cell under ``%%time`` is read as
    its body (:func:`cell_body`). ``keep``: the kinds of statement kept, instead. ``known`` (names
    defined before, updated with this cell's): assignments of a value :func:`safe_value` accepts are
    kept too (a helper cell's ``GAP_FLOOR = 0.0``, ``_held = lambda ...``, ``_decay = _decay_impl``)."""
    if keep is None:
        keep = _DEFINITIONS + ((ast.Assign, ast.AnnAssign) if assignments else ())

    def pick(node: ast.stmt) -> ast.stmt | str | None:
        if isinstance(node, (ast.Import, ast.ImportFrom)) and isinstance(node, keep):
            got = node if lorisnb else _without_aliases(node, lambda a: _lorisnb_alias(node, a))
            if got is not None and known is not None:
                known.update((a.asname or a.name).split(".")[0] for a in node.names if not _lorisnb_alias(node, a))
            return got
        if isinstance(node, keep):
            if known is not None and isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                known.add(node.name)
            return node
        if known is not None and isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None:
            names = _targets(node)
            if names is not None and safe_value(node.value, known):
                known.update(names)
                return node
        return None

    return _rebuild(cell_body(source), pick)


def _copy_private(src: Path, dst: Path, ignore: Callable[[str, list[str]], Any]) -> None:
    """Copy the folder ``src`` into the (private) folder ``dst``, every folder made 0700 and every file
    0600 as it is created (never readable by another user, even for a moment)."""
    names = os.listdir(src)
    skip = set(ignore(str(src), names))
    for name in names:
        if name in skip:
            continue
        s, d = src / name, dst / name
        if s.is_dir():
            d.mkdir(mode=0o700)
            _copy_private(s, d, ignore)
        else:
            _copy_private_file(s, d)


def _copy_private_file(src: Path, dst: Path) -> None:
    fd = os.open(dst, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    with open(src, "rb") as f, os.fdopen(fd, "wb") as out:
        shutil.copyfileobj(f, out)


def _write_private(dst: Path, data: bytes) -> None:
    """Write ``data`` to the new file ``dst``, 0600 as it is created (a link there is not followed)."""
    fd = os.open(dst, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    with os.fdopen(fd, "wb") as out:
        out.write(data)


def read_submitted(path: Path, below: Path | None = None, limit: int | None = None) -> bytes:
    """The bytes of a file a student submitted, read without following a symbolic link: the file
    and, with ``below`` (a folder above it: the course's ``submitted/``), every folder between
    ``below`` and it are opened with ``O_NOFOLLOW``, so a link anywhere there is refused (the grader,
    often root, would read what it points to: the instructor's notebook, the course's secret,
    ``/etc/shadow``); only a regular file is read (a FIFO would block the grader). ``limit``: at most
    so many bytes (a larger file is refused). Raises :class:`~lorisnb.errors.ValidationError` naming
    the file and why, never quoting what it holds; OSError (FileNotFoundError...) as ``open`` does."""
    path = Path(path)
    base = Path(below) if below is not None else path.parent
    parts = path.relative_to(base).parts if below is not None else (path.name,)

    def refused(why: str) -> NoReturn:
        raise ValidationError(f"{path}: {why}: refused (the grader reads no file of a submission through a link, and "
                              "only regular files; submit the file itself)")  # fmt: skip

    fd = os.open(base, os.O_RDONLY | os.O_DIRECTORY)
    try:
        for k, part in enumerate(parts):
            last = k == len(parts) - 1
            flags = os.O_RDONLY | os.O_NOFOLLOW | (os.O_NONBLOCK | os.O_NOCTTY if last else os.O_DIRECTORY)
            try:
                nfd = os.open(part, flags, dir_fd=fd)
            except OSError as exc:
                where = "it" if last else f"the folder {base.joinpath(*parts[: k + 1])}"
                if exc.errno == errno.ELOOP or (
                    exc.errno == errno.ENOTDIR and os.path.islink(base.joinpath(*parts[: k + 1]))
                ):
                    refused(f"{where} is a symbolic link")
                if exc.errno == errno.ENOTDIR:
                    refused(f"{where} is not a folder")
                raise
            os.close(fd)
            fd = nfd
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            refused("not a regular file")
        with os.fdopen(os.dup(fd), "rb") as f:
            data = f.read() if limit is None else f.read(limit + 1)
    finally:
        os.close(fd)
    if limit is not None and len(data) > limit:
        refused(f"larger than {limit} bytes")
    return data


#: nbgrader's markers of an instructor's notebook, which ``nbgrader generate_assignment`` removes from the
#: notebook handed out (with the solutions and hidden tests between them)
SOURCE_MARKERS = ("### BEGIN SOLUTION", "### END SOLUTION", "### BEGIN HIDDEN TESTS", "### END HIDDEN TESTS")


def instructor_markers(nb: nbformat.NotebookNode) -> list[str]:
    """The cells of a returned notebook that hold one of nbgrader's instructor markers
    (:data:`SOURCE_MARKERS`, alone on a line): ``<grade_id or cell N>: <marker>``, once per cell."""
    found = []
    for k, cell in enumerate(nb.cells):
        lines = {line.strip() for line in str(cell.get("source", "")).splitlines()}
        hit = next((m for m in SOURCE_MARKERS if m in lines), None)
        if hit:
            found.append(f"{_nbgrader(cell).get('grade_id') or f'cell {k + 1}'}: {hit}")
    return found


def _lab_names_before(spec: LabSpec, at: int) -> set[str]:
    """The names the lab's own cells (not answers, not checks) above its cell ``at`` bind."""
    names: set[str] = set()
    for cell in spec.notebook.cells[: max(at, 0)]:
        meta = _nbgrader(cell)
        if cell.cell_type == "code" and not meta.get("solution") and not meta.get("grade"):
            try:
                names |= _assigned(cell.source) | _imported(cell.source)
            except SyntaxError:
                continue
    return names


def _lab_values(
    spec: LabSpec, code: Mapping[str, str], params: Mapping[str, Any], root: Path, at: Mapping[str, int]
) -> dict[str, dict[str, Any]]:
    """Key (an answer's grade_id, an added cell's :func:`_added_key`) -> the lab's names the functions
    of its cell (``code``) read when defined (:func:`defined_with`, as plain values), as the grader's
    own run of the instructor's notebook has them just before the lab's cell ``at[key]`` (the
    student's run could have rebound them); answer cells and added cells alike. Runs the lab only
    when some cell reads such names, up to the last one; empty when the lab's own cells fail (the
    checks' run then says why)."""
    wanted = {g: defined_with(a) & _lab_names_before(spec, at[g]) for g, a in code.items() if g in at}
    wanted = {g: w for g, w in wanted.items() if w}
    if not wanted:
        return {}
    import matplotlib

    from lorisnb.tools.teaching._sandbox_child import given

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out: dict[str, dict[str, Any]] = {}
    ns: dict[str, Any] = {"__name__": "__main__"}
    cwd = os.getcwd()
    os.chdir(root)
    try:
        for i, cell in enumerate([*spec.notebook.cells, None]):
            for key in (g for g, w in wanted.items() if at[g] == i):
                values = {n: given(ns[n]) for n in sorted(wanted[key]) if n in ns}
                out[key] = {n: v for n, v in values.items() if "not_plain" not in v and "missing" not in v}
            if len(out) == len(wanted) or cell is None:
                break
            meta = _nbgrader(cell)
            if cell.cell_type != "code" or meta.get("grade"):
                continue
            source = cell.source
            if "parameters" in cell.get("metadata", {}).get("tags", []):
                source = _parameters(source, {**params, "output_dir": str(root / "reference-out")})
            with contextlib.redirect_stdout(io.StringIO()):
                exec(compile(source, f"<instructor {meta.get('grade_id', 'cell')}>", "exec"), ns)  # noqa: S102
    except Exception:  # noqa: BLE001 (the lab's own cells failed: the checks' run of them says so)
        pass
    finally:
        os.chdir(cwd)
        plt.close("all")
    return out


def parameter_notes(nb: nbformat.NotebookNode, student: str) -> list[str]:
    """What a returned notebook's parameters cell sets that draws another data variant than the one
    graded (its ``student_id`` other than its folder's, its ``seed`` set), each with what to do: the
    grader draws the variant from the submission's folder, so numbers the notebook showed (a curve
    read by eye, a value typed in) may differ from those graded."""
    found: list[str] = []
    typed = declared_id(nb)
    if typed is not None and typed != student:
        if same_id(typed) == same_id(student):
            found.append(f"the notebook's student_id is {typed!r}, its folder {student!r}: the same id (case and "
                         "spaces are ignored), so the same data variant; graded as that student")  # fmt: skip
        else:
            found.append(f"the notebook's student_id is {typed!r}, but it was submitted as {student!r}: it is graded "
                         f"with the data variant of {student!r} (the submission's folder), so the numbers the notebook "
                         f"showed for {typed!r} may differ from those graded; set student_id to {student!r} (or leave "
                         "it None on JupyterHub)")  # fmt: skip
    seed = declared(nb, "seed")
    if seed is not None and seed != lab_variant(student).seed:
        found.append(f"the notebook's parameters cell sets seed = {seed!r}, which draws another data variant than "
                     f"the one graded: the grader draws {student!r}'s from the submission's folder, so numbers the "
                     "notebook showed (a curve or timeline read by eye) may differ from those graded; leave seed None "
                     "(it is the instructor's, to try other variants)")  # fmt: skip
    return found


def declared(nb: nbformat.NotebookNode, name: str) -> object:
    """The constant a returned notebook's parameters cell assigns to ``name`` (the last such
    assignment; a negative number too), else None."""
    found = None
    for cell in nb.cells:
        if cell.cell_type != "code" or "parameters" not in cell.get("metadata", {}).get("tags", []):
            continue
        try:
            tree = ast.parse(cell.source)
        except SyntaxError:
            continue
        for node in tree.body:
            if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == name for t in node.targets):
                try:
                    found = ast.literal_eval(node.value)
                except ValueError:  # not a constant: the lab computes it
                    continue
    return found


def declared_id(nb: nbformat.NotebookNode) -> str | None:
    """The ``student_id`` a returned notebook's parameters cell sets to a string (the last such
    assignment), else None."""
    typed = declared(nb, "student_id")
    return typed if isinstance(typed, str) else None


def earlier_cells(answers: Mapping[str, str], before: Sequence[str]) -> list[tuple[str, str]]:
    """The functions (and imports, lorisnb's left out, and assignments of constants, lambdas and
    names of those: :func:`safe_value`) of each of the cells ``before`` (answer grade_ids, added
    cells' keys, in the notebook's order) that has any, as (key, code): what an answer run alone
    may call, as it did in the notebook (:func:`run_cells` runs them)."""
    known = {"np", "math"}  # numpy and math are there (PRELUDE); then what each cell defines, in order
    parts = [(g, definitions_only(answers[g], lorisnb=False, known=known)) for g in before if g in answers]
    return [(g, d) for g, d in parts if d]


def earlier_functions(answers: Mapping[str, str], before: Sequence[str]) -> str:
    """:func:`earlier_cells`' code, joined."""
    return "\n".join(d for _, d in earlier_cells(answers, before))


def cell_name(key: str) -> str:
    """How a message names a cell: ``your answer cell A1``, or an added cell by its key's words."""
    return key.strip("<>") if key.startswith("<") else f"your answer cell {key}"


def run_cells(
    box: Sandbox, cells: Sequence[tuple[str, str]], timeout: Callable[[], float]
) -> tuple[str | None, list[tuple[str, str]]]:
    """Each of :func:`earlier_cells`' ``cells`` run in ``box``, one after another as the notebook ran
    them: the first cell during whose run the guard refused or found lorisnb (None if none did),
    so that a refusal names the cell whose code used it (a def-time default ``m=__import__('lorisnb')``
    in a helper's cell, not the answer given that helper), and the cells that failed (key, error)."""
    culprit, failed = None, []
    for key, code in cells:
        seen = len(box.findings)
        reply = box.run(code, name=f"<the functions of {cell_name(key)}>", timeout_s=timeout())
        if culprit is None and len(box.findings) > seen:
            culprit = key
        if not reply.get("ok"):
            failed.append((key, str(reply.get("error"))))
    return culprit, failed


def unkept_values(code: Mapping[str, str], order: Sequence[str]) -> dict[str, str]:
    """Name -> the cell (its grade_id, or an added cell's key) that assigns it at its top level, where
    that assignment is not given to the answers run alone (:func:`earlier_functions`: not a
    :func:`safe_value`): what a NameError of such a name is told."""
    known = {"np", "math"}
    out: dict[str, str] = {}
    for key in order:
        source = code.get(key, "")
        kept = definitions_only(source, lorisnb=False, known=known)
        try:
            lost = _assigned(cell_body(source)) - _assigned(kept or "") - known
        except SyntaxError:
            continue
        out.update({n: cell_name(key) for n in lost})
    return out


def _parameters(cell_source: str, params: Mapping[str, Any]) -> str:
    """The instructor's parameters cell followed by this run's values (as papermill injects them)."""
    return cell_source + "\n# injected by the grader\n" + "".join(f"{k} = {v!r}\n" for k, v in params.items())


class Budget:
    """The wall-clock budget of one submission (``Limits.submission_s``): the seconds its code may
    take in all, from its first answer cell on (the cells, the lab's own after them, the replays
    after a time-out, its functions' sandboxes, the checks' calls; a ``reserve`` is kept for the
    calls). The lab's cells before the first answer are not charged: no student code ran yet."""

    def __init__(self, seconds: float, reserve: float = 0.0) -> None:
        self.seconds, self.used = float(seconds), 0.0
        self.reserve = min(float(reserve), self.seconds / 3)  # kept for the checks' calls
        self.spent_at = ""  # where it ran out
        self._since: float | None = None  # the start of the charge running now

    def left(self, run: bool = False) -> float:
        """Seconds left: for the checks' calls, or (``run``) for running cells, the reserve kept."""
        running = time.monotonic() - self._since if self._since is not None else 0.0
        return self.seconds - self.used - running - (self.reserve if run else 0.0)

    @contextlib.contextmanager
    def charge(self) -> Any:
        if self._since is not None:  # already charging (a replay's cells)
            yield
            return
        self._since = time.monotonic()
        try:
            yield
        finally:
            self.used += time.monotonic() - self._since
            self._since = None

    def out(self, where: str, run: bool = True) -> bool:
        """Whether it is spent (for running cells, ``run``: its reserve for the checks' calls
        kept), and then, the first time, remember where."""
        if self.left(run) > 0:
            return False
        self.spent_at = self.spent_at or where
        return True

    def note(self) -> str:
        return (
            f"time budget: grading runs a submission's code for at most {self.seconds:g} s in all (--budget), "
            f"and this one's ran out at {self.spent_at}: what it had earned by then counts, and each question "
            "whose answer or check did not run in time scores 0 (slow or endless cells and calls cost their time "
            "limit, and again in the replay after each time-out)"
        )


def lorisnb_used(name: str, findings: Sequence[str], by: str | None = None) -> str:
    """The message of an answer refused because its code used lorisnb (``findings``: what the
    sandbox's guard refused or found), or, with ``by``, the code of the earlier cell ``by`` whose
    functions and values it is given (:func:`run_cells`)."""
    what = "; ".join(dict.fromkeys(findings))
    who = (
        "its code tried to use lorisnb"
        if by is None
        else f"{cell_name(by)}, whose functions and values it is given (the notebook ran that cell before it), "
        "tried to use lorisnb when run (a default value or constant computed with lorisnb?)"
    )
    return (
        f"{name}: refused (0 points): {who} ({what}). An answer graded with numpy "
        "only (a formula, or a prediction) may not use lorisnb's code, from any copy of it on the machine "
        "(another environment, a checkout, a wheel); write it yourself, with numpy"
        + ("" if by is None else f", in {cell_name(by)}")
    )


class RemoteFunction(SandboxedAnswer):
    """A student's function, called in its sandbox (no lorisnb there); results come back as values.
    Its calls by the checks share one per-cell time limit (``call_budget_s``) and the submission's
    budget. ``refused``: the function is not graded (its code used lorisnb): every call raises
    :class:`~lorisnb.errors.AnswerError` with this message (so does a call during which the guard
    refuses or finds lorisnb)."""

    def __init__(
        self,
        sandbox: Sandbox | None,
        name: str,
        error: str | None = None,
        budget: Budget | None = None,
        call_budget_s: float | None = None,
        refused: str | None = None,
        hint: Callable[[str], str] | None = None,
    ) -> None:
        self.sandbox, self.name, self.error = sandbox, name, error
        self.budget = budget
        self.calls_left = call_budget_s
        self.refused = refused
        self.hint = hint  # what a call's error is told with (:func:`_with_hint`: what a formula has alone)
        self.__name__ = name

    def __call__(self, **kwargs: Any) -> Any:
        if self.refused:
            raise AnswerError(f"✗ {self.refused}")
        if self.sandbox is None:
            _raise(self.error or f"NameError: {self.name} is not defined")
        left = [t for t in (self.calls_left, self.budget.left() if self.budget else None) if t is not None]
        timeout = min(left) if left else None
        if timeout is not None and timeout <= 0:
            self._stop(f"the check's calls of {self.name}")
        t0 = time.monotonic()
        box, seen, told, late = (
            self.sandbox,
            len(self.sandbox.findings),
            len(self.sandbox.tampered),
            len(self.sandbox.late),
        )
        try:
            with self.budget.charge() if self.budget else contextlib.nullcontext():
                reply = self.sandbox.call(self.name, kwargs, timeout_s=timeout)
        except SandboxError as exc:
            if self.budget is not None and self.budget.out(f"a check's call of {self.name}", run=False):
                self._stop(f"a check's call of {self.name}")
            if self.calls_left is not None and self.calls_left - (time.monotonic() - t0) <= 0:
                self._stop(f"the check's calls of {self.name}")
            self.sandbox, self.error = None, error_of(exc)
            _raise(self.error)
        finally:
            if self.calls_left is not None:
                self.calls_left -= time.monotonic() - t0
            if len(box.findings) > seen:  # lorisnb used during the call (refused or found after)
                self.refused, self.sandbox = (
                    lorisnb_used(f"{self.name}, called by the check", box.findings[seen:]),
                    None,
                )
            elif len(box.tampered) > told or len(box.late) > late:  # its code wrote into the grader's pipe
                how = [*box.tampered[told:], *(h for _, h in box.late[late:])]
                self.refused, self.sandbox = tampered(f"{self.name}, called by the check", how), None
        if self.refused:
            raise AnswerError(f"✗ {self.refused}")
        if not reply.get("ok"):
            error = str(reply.get("error", "RuntimeError: failed"))
            _raise(self.hint(error) if self.hint is not None else error)
        return decode(reply["result"])

    def _stop(self, where: str) -> NoReturn:
        if self.budget is not None and self.budget.out(where, run=False):
            self.error = f"TimeoutError: the submission's time budget ({self.budget.seconds:g} s) ran out ({where})"
        else:
            limit = self.sandbox.limits.cell_timeout_s if self.sandbox else 0
            self.error = (
                f"TimeoutError: the checks' calls of {self.name} took more than {limit:g} s in all "
                "(the time limit of a cell, shared by a function's calls)"
            )
        self.sandbox = None
        _raise(self.error)

    def __repr__(self) -> str:
        return f"<your function {self.name}, run in the grading sandbox>"


def settled(functions: Iterable[Any]) -> str | None:
    """After a check: what the sandboxes of ``functions`` (the answer's, as the check called them)
    wrote since the reply to their last call, read (:meth:`.sandbox.Sandbox.settle`). A reply to a
    call whose reply was read already (the code forged that reply and answered the grader's check
    of the channel itself: the child's own reply came after them, past the check's last call)
    refuses every function of that sandbox, as a reply found during a call does; returns the
    refusal (the check then scores 0), or None."""
    boxes: dict[int, tuple[Sandbox, list[RemoteFunction]]] = {}
    for f in functions:
        if isinstance(f, RemoteFunction) and f.sandbox is not None and not f.refused:
            boxes.setdefault(id(f.sandbox), (f.sandbox, []))[1].append(f)
    refused = None
    for box, owned in boxes.values():
        late = len(box.late)
        with contextlib.suppress(SandboxError):
            box.settle()
        if len(box.late) > late:
            how = [h for _, h in box.late[late:]]
            for f in owned:
                f.refused, f.sandbox = tampered(f"{f.name}, called by the check", how), None
            refused = refused or owned[0].refused
    return refused


def tampered(what: str, told: Sequence[str]) -> str:
    """The error of an answer during whose run the student's code wrote a reply of its own into the
    grader's reply channel (``Sandbox.tampered``: a second reply to a request, names the
    grader did not ask for): not trusted, whatever its values, so 0 points and a note."""
    return (
        f"RuntimeError: {what}: the notebook's code wrote into the grader's reply channel from the sandbox "
        f"({'; '.join(told[:3])}): the values read back cannot be trusted and the answer scores 0 (the instructor "
        "is told); an answer's code must not touch the grader's requests or replies"
    )


def _raise(error: str) -> NoReturn:
    """Raise the student's error again, as its built-in type when it has one."""
    name, _, text = error.partition(": ")
    exc_type = getattr(builtins, name, None)
    if isinstance(exc_type, type) and issubclass(exc_type, Exception) and exc_type is not SystemExit:
        raise exc_type(text)
    raise RuntimeError(error)


def hidden_seed(secret: str, student: str, lab: str) -> int:
    """The seed of the hidden tests' data: from a secret of the course, so no student can know it."""
    return int(hashlib.sha256(f"{secret}\0{student}\0{lab}".encode()).hexdigest()[:8], 16) % 2**31


def _package_paths() -> tuple[Path, list[Path]]:
    """The folder to put on the sandbox's PYTHONPATH (holding lorisnb), and the folders to hide from
    it: in each checkout lorisnb or the Python environment lives in (a folder with pyproject.toml),
    every sub-folder except the package and the environment (sources, tests, the lab sources, the
    git database). Only the package and the environment's folders count as needed: its prefixes and
    every folder holding installed distributions (site-packages, also one a ``.pth`` file adds, as
    the teaching environment adds lorisnb's). Other ``sys.path`` entries do not, or a grader started
    as ``python teaching/grade.py`` (its folder first on ``sys.path``) would open the labs' solutions."""
    import importlib.metadata
    import sys

    import lorisnb

    pkg = Path(lorisnb.__file__).resolve().parent
    needed = [pkg, Path(sys.prefix).resolve(), Path(sys.base_prefix).resolve(), Path(sys.executable).resolve()]
    sites = {Path(str(d.locate_file(""))).resolve() for d in importlib.metadata.distributions()}
    needed += sorted(p for p in sites if p.is_dir())
    hide: list[Path] = []
    for root in {pkg.parent, *(p.parent for p in needed[1:3])}:
        if not (root / "pyproject.toml").is_file():
            continue
        for entry in root.iterdir():
            if entry.is_dir() and not entry.is_symlink() and not any(n.is_relative_to(entry.resolve()) for n in needed):
                hide.append(entry.resolve())
        if (root / ".git").is_file():  # a worktree: its git database is elsewhere
            hide += git_databases([root])
    return pkg.parent, list(dict.fromkeys(hide))


def git_databases(paths: Sequence[Path]) -> list[Path]:
    """The git database of each repository holding one of ``paths`` (its ``.git`` folder; a
    worktree's, whose ``.git`` file names it, the main repository's): its history holds every file
    ever committed there, the labs' solutions too, so the sandbox hides it with the course and the
    sources (a course kept in a repository of its own, not the checkout lorisnb runs from, left it
    readable)."""
    found: list[Path] = []
    for path in paths:
        for root in (Path(path).resolve(), *Path(path).resolve().parents):
            git = root / ".git"
            if git.is_dir():
                found.append(git)
                break
            if git.is_file():
                m = re.match(r"gitdir:\s*(.+)", git.read_text())
                d = (root / m.group(1).strip()).resolve() if m else root
                while d.name != ".git" and d != d.parent:
                    d = d.parent
                if d.name == ".git":
                    found.append(d)
                break
    return list(dict.fromkeys(found))


@dataclass(frozen=True)
class GradeSettings:
    """How to grade: the sandbox's limits, folders to hide besides the course and the checkouts,
    the course's secret (hidden tests' seed), the sandbox user id, and the folder of the
    submissions (``submitted``: no folder between it and a notebook may be a link,
    :func:`read_submitted`)."""

    limits: Limits = Limits()
    hidden: tuple[Path, ...] = ()
    secret: str = ""
    uid: int = 62000
    submitted: Path | None = None


def grade_submission(
    spec: LabSpec,
    release_dir: Path,
    notebook: Path,
    student: str,
    settings: GradeSettings = GradeSettings(),
) -> SubmissionResult:
    """Grade ``notebook`` (``student``'s copy of ``spec``'s lab); ``release_dir``: the files handed
    out with it (copied into the sandbox, the notebook excepted)."""
    t0 = time.monotonic()
    try:
        data = read_submitted(notebook, settings.submitted)  # a link refused: never what it points to
        nb, read_notes = read_notebook(data)
        markers = instructor_markers(nb)
        # magics as IPython runs them; every cell of an answer's id, in the order the notebook ran them
        parts = {g: [as_python(a) for a in srcs] for g, srcs in answer_cells(nb).items()}
        answers = {g: "\n".join(srcs) for g, srcs in parts.items()}
        # the notebook's order, where it differs from the counts' (run when the counts' order fails)
        top_down = {g: [as_python(a) for a in srcs] for g, srcs in answer_cells(nb, counted=False).items()}
        top_down = {g: srcs for g, srcs in top_down.items() if srcs != parts.get(g)}
        repeated = repeated_answers(nb)
        added = {i: [as_python(a) for a in srcs] for i, srcs in added_cells(spec.notebook, nb).items()}
    except Exception as exc:  # noqa: BLE001 (any way a returned file fails to be a notebook: this student's 0)
        return unreadable(spec, student, notebook, exc, time.monotonic() - t0, why=not_a_notebook(exc))
    py_path, checkout_dirs = _package_paths()
    hidden = [*settings.hidden, *checkout_dirs]
    _check_reachable(py_path, settings)
    notes: list[str] = [*read_notes] + [
        f"{gid}: {n} cells carry this answer's id (a split or copied cell keeps it): all of them run, in the order "
        "the notebook last ran them (their execution counts; top to bottom where a cell has none, or where that "
        "order fails), so what the one run last set is graded; "
        + ("they are copies of one cell: delete the extra ones" if len(set(parts[gid])) == 1 else
           "if one is an attempt you abandoned, delete it (Merge Cells joins the halves of a split cell)")
        for gid, n in repeated.items()
    ]  # fmt: skip
    expected = [str(_nbgrader(c)["grade_id"]) for c in spec.notebook.cells if _nbgrader(c).get("solution")]
    if not any(g in answers for g in expected):
        added = {}  # none of its cells is the lab's (its metadata removed): nothing is in its place, nothing runs
    if added:
        n_added = sum(len(v) for v in added.values())
        notes.append(f"{n_added} code cell(s) you added (no nbgrader metadata) ran in their place in the notebook, as "
                     "Jupyter ran them, with your answer cells' rules (and their functions and imports, lorisnb's "
                     "left out, before the answers graded alone)")  # fmt: skip
    # the answer cells and the added cells (by a key of their own) in the order they run: what an answer run
    # alone is given of the cells before it (their functions and imports)
    order, code, at = _in_order(spec, answers, added)

    def reorder(gid: str, srcs: Sequence[str]) -> None:
        """``gid``'s cells ran (and are graded) in the order ``srcs``: its runs alone use it too."""
        parts[gid] = list(srcs)
        answers[gid] = code[gid] = "\n".join(srcs)

    missing = [g for g in expected if g not in answers]
    if missing and len(missing) == len(expected):
        notes.append(
            f"{notebook.name} holds none of the lab's answer cells (the cells' nbgrader metadata was removed, or it "
            "is another notebook): every question is graded as unanswered. Submit the notebook you were handed "
            "out, answered in its own cells (copy your answers into a fresh copy if its cells were recreated)"
        )
    elif missing:
        notes.append(f"{notebook.name} lacks the answer cells {', '.join(missing)} (their nbgrader metadata was "
                     "removed, or the cells deleted): graded as unanswered")  # fmt: skip
    notes += parameter_notes(nb, student)
    params = {"student_id": student}
    n_functions = sum(1 for defs in spec.functions.values() if defs)
    budget = Budget(settings.limits.submission_s, reserve=n_functions * settings.limits.cell_timeout_s)
    boxes: list[Sandbox] = []
    with tempfile.TemporaryDirectory(prefix="lorisnb-grade-", dir=_reachable_tmp()) as tmp:
        root = Path(tmp)  # made 0700; opened to be passed (0711) only once what it holds is private
        work = root / "work"
        work.mkdir(mode=0o700)  # private before anything is copied in: a student's answers are read by no other
        (root / "reference-out").mkdir(mode=0o700)  # the grader's own run's outputs (the reference values)
        _copy_private(release_dir, work, ignore=shutil.ignore_patterns("*.ipynb", ".*"))
        _write_private(work / notebook.name, data)  # the bytes graded, read once
        root.chmod(0o711)
        # the answers run alone (numpy only) do not see the lab's folder: the lab's code, which may use the
        # lab's functions, could open it to others (chmod) and leave there what a prediction would read; nor
        # (each sandbox sees its own folder alone in the temporary folders) each other's
        apart = [*hidden, work]
        # the lab's values each answer's functions read when defined (eps=eps), as the grader's own run of the
        # lab has them, never as the student's run left them (an answer cell could rebind them there)
        # (one path for the answer cells and the cells the student added: a helper's def eps=eps alike)
        # a formula's check calls its functions once the notebook has run the cells below it up to the check: the
        # functions of those the student added (a helper defined below, as `_held` under B2) are given to its run
        # alone, after its own cells, their defs given the lab's values as the lab had them at the answer (no value
        # the lab's cells between the answer and its check set: none of them is given)
        below = {g: _up_to_check(spec, order, at, g) for g in order if spec.functions.get(g)}
        below_code = {_below_key(k, g): code[k] for g, ks in below.items() for k in ks}
        below_at = {_below_key(k, g): at[g] for g, ks in below.items() for k in ks}
        clean = _lab_values(spec, {**code, **below_code},
                            params | {"hidden_seed": hidden_seed(settings.secret, student, spec.name)},
                            root, {**at, **below_at})  # fmt: skip
        functions: dict[str, RemoteFunction] = {}
        unkept = unkept_values(code, order)  # a NameError of one of these says why it is not there

        def alone(gid: str, failed: str | None) -> None:
            """Step 2 for one formula answer, right after its cell ran in step 1 (its time is
            charged then, so the points earned before a budget runs out are kept)."""
            defs = spec.functions.get(gid, ())
            if not defs:
                return
            if gid not in answers:  # its cell deleted or its metadata removed: unanswered, whatever defines it
                functions.update({d: RemoteFunction(None, d, absent(gid)) for d in defs})
                return
            if failed:
                functions.update({d: RemoteFunction(None, d, failed) for d in defs})
                return
            if budget.out(f"<answer {gid}>, run alone"):
                error = f"TimeoutError: {_BUDGET_ERROR.format(budget.seconds)}"
                functions.update({d: RemoteFunction(None, d, error) for d in defs})
                return
            fwork = root / f"fn-{gid}"
            fwork.mkdir(mode=0o700)
            box = Sandbox(fwork, limits=settings.limits, hidden=apart, uid=settings.uid + 1, no_lorisnb=True,
                          private=[root])  # fmt: skip
            boxes.append(box)
            source = answers.get(gid, "")
            after = below.get(gid, [])
            try:
                with budget.charge():
                    box.run(PRELUDE, name="<numpy and math>", timeout_s=budget.left(True))
                    before = order[: order.index(gid)] if gid in order else []
                    # the lab's numbers its functions (and the earlier cells') read when defined (eps=eps)
                    lab = {n: v for g in [*before, gid] for n, v in clean.get(g, {}).items()}
                    lab |= {n: v for k in after for n, v in clean.get(_below_key(k, gid), {}).items()}
                    if lab:
                        box.bind(lab, timeout_s=budget.left(True))
                    # the functions the student's earlier answer cells define, which this one may call (as the
                    # notebook did), before its own: its own definitions win
                    culprit, _ = run_cells(box, earlier_cells(code, before), lambda: budget.left(True))
                    # what its functions' names held before its cells ran (an earlier cell's function, or nothing):
                    # a cell that fails after rebinding every one of them had defined them, as in Jupyter
                    box.run(f"{_BEFORE} = {{n: globals().get(n) for n in {list(defs)!r}}}",
                            name=f"<before answer {gid}>", timeout_s=budget.left(True))  # fmt: skip
                    # each of its cells (a split cell's halves, copies) as the notebook ran them, an unused top-level
                    # import of lorisnb left out (as in the other cells: it costs nothing; one it uses meets the guard)
                    dropped = False
                    for part in parts.get(gid) or [source]:
                        run = without_lorisnb(part)
                        dropped = dropped or run != part
                        reply = box.run(run, name=f"<answer {gid}>", timeout_s=budget.left(True))
                    if dropped:
                        notes.append(f"{gid}: its unused import of lorisnb is left out when the formula runs alone "
                                     "(graded with numpy only, as the imports of your other cells are): it costs "
                                     "nothing; a formula that uses lorisnb is refused")  # fmt: skip
                    error = "" if reply.get("ok") else str(reply.get("error", ""))
                    # a try-out line: reading the lab's numbers (eps, tau: a NameError alone), or failing after the
                    # cell had defined its functions (a call missing an argument), as in Jupyter, where the check
                    # then calls the functions the cell defined: the formula is the cell's definitions
                    tryout = error and not error.startswith("NameError") and _defined_before_failing(box, gid, defs)
                    if error.startswith("NameError") or tryout:
                        for assignments in (True, False):
                            defs_only = definitions_only(source, assignments, lorisnb=False)
                            if defs_only is None or defs_only == source:
                                continue
                            again = box.run(defs_only, name=f"<answer {gid}>", timeout_s=budget.left(True))
                            if again.get("ok"):
                                notes.append(_tryout_note(gid, defs, error, run, reply.get("line"), bool(tryout)))
                                reply = again
                                break
                    # the functions of the cells the student added below it, up to its check (the notebook ran them
                    # before the check called its functions)
                    seen = len(box.findings)
                    below_culprit, below_failed = run_cells(box, earlier_cells(code, after), lambda: budget.left(True))
                    culprit = culprit or (below_culprit if len(box.findings) > seen else None)
                    if below_failed:
                        notes.append(f"{gid}: the functions of the cells you added below it (up to its check), "
                                     f"given to it run alone, failed: {_with_hint(spec, below_failed[0][1], unkept)}")  # fmt: skip
            except SandboxError as exc:
                spent = budget.out(f"<answer {gid}>, run alone")
                why = f"TimeoutError: {_BUDGET_ERROR.format(budget.seconds)}" if spent else error_of(exc)
                functions.update({d: RemoteFunction(None, d, why) for d in defs})
                return
            if box.findings:  # the guard refused lorisnb to it (or found it loaded): no points, whatever it returns
                refused = lorisnb_used(f"the answer cell {gid}", box.findings, by=culprit)
                functions.update({d: RemoteFunction(None, d, refused=refused) for d in defs})
                return
            if box.tampered or box.late:  # its code wrote into the grader's pipe: not graded, whatever it returns
                told = [*box.tampered, *(how for _, how in box.late)]
                functions.update({d: RemoteFunction(None, d, refused=tampered(f"the answer cell {gid}", told))
                                  for d in defs})  # fmt: skip
                return
            err = None if reply.get("ok") else str(reply.get("error"))
            if err:  # the cell failed on its own, with numpy only: say so, then its error
                err = ("RuntimeError: the answer cell, run alone with numpy only (no lorisnb, as graded), failed: "
                       + _with_hint(spec, err, unkept))  # fmt: skip
            functions.update({d: RemoteFunction(None if err else box, d, err, budget, settings.limits.cell_timeout_s,
                                                hint=lambda e: _with_hint(spec, e, unkept)) for d in defs})  # fmt: skip

        try:
            took: dict[str, float] = {}  # seconds each answer cell took in the lab
            values = _run_student(spec, parts, params | {"output_dir": str(work / "out")}, work, py_path,
                                  hidden, settings, notes, budget, boxes, alone, took, private=[root],
                                  added=added, fallback=top_down, reorder=reorder)  # fmt: skip
            for gid in missing:  # never what the lab's run read where its cell was (an added cell set it)
                values[gid] = {n: {"error": absent(gid)} for n in spec.values.get(gid, ())}
            isolation = "full" if settings.uid and _isolated() else "limits"
            for defs in spec.functions.values():  # not reached: the budget ran out before
                functions.update({d: RemoteFunction(None, d, f"TimeoutError: {_BUDGET_ERROR.format(budget.seconds)}")
                                  for d in defs if d not in functions})  # fmt: skip

            def predicted(gid: str, given: Mapping[str, Any]) -> dict[str, Any]:
                """A prediction run alone (numpy, math and ``given``, the lab's numbers), its values;
                one that did not run in the lab (a time limit, the budget) keeps that error."""
                if gid not in answers:  # no answer cell: unanswered (never the lab's run's value there)
                    return {n: {"error": absent(gid)} for n in spec.values.get(gid, ())}
                if gid not in took or any("error" in v for v in values.get(gid, {}).values()):
                    return dict(values.get(gid, {}))
                before = order[: order.index(gid)] if gid in order else []
                lab = {n: v for g in before for n, v in clean.get(g, {}).items()}
                # with the cells the student added right below it (before the lab's next cell, which computes
                # what it is checked against): the notebook's check saw the value they left
                srcs = [answers[gid], *(added.get(at[gid], ()) if gid in at else ())]
                got = _predict(spec, gid, "\n".join(srcs), {**lab, **given}, root, apart, settings, budget, notes,
                               took[gid], boxes, earlier_cells(code, before))  # fmt: skip
                return unset(got, srcs)

            scores = _run_checks(
                spec,
                values,
                functions,
                params | {"hidden_seed": hidden_seed(settings.secret, student, spec.name)},
                root,
                predicted,
            )
        finally:
            for box in boxes:
                box.close()
    notes += list(dict.fromkeys(f.refused for f in functions.values() if f.refused))
    if budget.spent_at:
        notes.append(budget.note())
    stray = sum(box.stray for box in boxes)
    told = [t for box in boxes for t in (*box.tampered, *(how for _, how in box.late))]
    if told:
        notes.append(
            f"the submission's code wrote replies of its own into the grader's reply channel from the sandbox "
            f"({'; '.join(told[:3])}{'; ...' if len(told) > 3 else ''}): each answer during whose run it did so "
            "scores 0 (its own note says so)"
        )
    if stray:
        notes.append(
            f"the grader's reply pipe from the sandbox held {stray} line(s) it did not ask for, no reply to any of its "
            "requests: the submission's code wrote them (they were not read as replies)"
        )
    if markers:
        notes.append(leaked_note(markers))
    notes = [shorten(n) for n in notes]
    return SubmissionResult(student, spec.name, scores, isolation, round(time.monotonic() - t0, 2), notes,
                            instructor_markers=markers)  # fmt: skip


def absent(gid: str) -> str:
    """The error of an answer whose cell the returned notebook lacks (deleted, or its nbgrader
    metadata removed): unanswered, whatever the other cells compute or define."""
    return (
        f"RuntimeError: the notebook has no answer cell {gid} (the cell was deleted, or its nbgrader metadata "
        "removed): unanswered, whatever other cells compute or define; answer in the lab's own answer cell"
    )


def leaked_note(markers: Sequence[str]) -> str:
    """The note of a submission holding nbgrader's instructor markers (:func:`instructor_markers`)."""
    shown = "; ".join(markers[:6]) + (f"; and {len(markers) - 6} more" if len(markers) > 6 else "")
    return (
        f"instructor's markers in this notebook ({shown}): nbgrader removes them, with the solutions and hidden "
        "tests between them, from the notebook handed out, so this is the instructor's source notebook or cells "
        "copied from it: the lab's solutions leaked. Graded as any submission (no points changed): an instructor "
        "decides (teaching/README.md, 'Grading')"
    )


class ByteOrderMark(ValueError):
    """A returned file that is JSON after a UTF-8 byte-order mark (which Jupyter does not open)."""


def read_notebook(data: bytes) -> tuple[nbformat.NotebookNode, list[str]]:
    """A returned notebook's bytes read as nbformat reads them (version 4), and the notes of what
    nbformat mended: cells sharing an id (it gives them new ones; its warnings are not printed, one
    per cell, to the grader's terminal). Raises (:func:`not_a_notebook` says why in words): not
    UTF-8, :class:`ByteOrderMark` (JSON after a byte-order mark), not JSON, or JSON that is no
    notebook, a cell whose source or metadata is not as Jupyter writes them included (a number as a
    cell's source)."""
    import warnings

    text = data.decode("utf-8")
    if text.startswith("\ufeff"):
        try:
            json.loads(text[1:])
        except ValueError:
            pass  # not JSON either: said so
        else:
            raise ByteOrderMark("JSON after a UTF-8 byte-order mark")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        nb = nbformat.reads(text, as_version=4)
    for cell in nb.get("cells", []):
        if not isinstance(cell, dict) or not isinstance(cell.get("source"), str):
            raise TypeError("a cell's source is not text")
        if not isinstance(cell.get("metadata", {}), dict) or not isinstance(cell.get("cell_type"), str):
            raise TypeError("a cell's metadata or type is not as Jupyter writes them")
    notes = []
    duplicated = sum(1 for w in caught if type(w.message).__name__ == "DuplicateCellId")
    if duplicated:
        notes.append(f"{duplicated} cell(s) of the notebook repeated another cell's id (cells copied outside Jupyter, "
                     "or an edited file): nbformat gave them new ids, as Jupyter does when it opens the notebook; "
                     "nothing else changed, and the cells are graded by their nbgrader metadata")  # fmt: skip
    return nb, notes


def not_a_notebook(exc: BaseException) -> str:
    """Why a returned file is no notebook, in words that quote nothing of it (an error of nbformat or
    json quotes the file's first bytes: a file the grader should never have read would be shown in
    the feedback): the link or FIFO refused (:func:`read_submitted`), not UTF-8, not JSON, JSON but
    not a notebook."""
    if isinstance(exc, ValidationError):
        return str(exc)
    name = type(exc).__name__
    if isinstance(exc, UnicodeDecodeError):
        what = "not UTF-8 text, so not a notebook"
    elif isinstance(exc, ByteOrderMark):
        what = ("JSON with a byte-order mark (the bytes EF BB BF before it), which Jupyter does not open either: "
                "save it without one (an editor's 'UTF-8', not 'UTF-8 with BOM'), or as Jupyter saves it")  # fmt: skip
    elif name == "NotJSONError" or isinstance(exc, json.JSONDecodeError):
        what = "not JSON, so not a notebook as Jupyter saves it"
    elif isinstance(exc, OSError):
        what = f"it cannot be read ({os.strerror(exc.errno) if exc.errno else 'an error of the system'})"
    else:
        what = "JSON, but not a notebook nbformat reads (its cells or metadata are not as Jupyter writes them)"
    return f"{name}: {what}; the grader quotes no part of a submission's file (open it to see what it holds)"


def _added_key(index: int, k: int) -> str:
    return f"<your added cell {k + 1} after cell {index}>"


def _in_order(
    spec: LabSpec, answers: Mapping[str, str], added: Mapping[int, Sequence[str]]
) -> tuple[list[str], dict[str, str], dict[str, int]]:
    """The answer cells' grade_ids and the added cells' keys (:func:`_added_key`) in the order the
    grader runs them, key -> source for both, and key -> the lab's cell before which it runs (an
    answer: its own; an added cell: the one after the cell it follows)."""
    order: list[str] = []
    code = dict(answers)
    at: dict[str, int] = {}
    for i in range(-1, len(spec.notebook.cells)):
        if i >= 0 and _nbgrader(spec.notebook.cells[i]).get("solution"):
            order.append(str(_nbgrader(spec.notebook.cells[i])["grade_id"]))
            at[order[-1]] = i
        for k, src in enumerate(added.get(i, ())):
            order.append(_added_key(i, k))
            code[_added_key(i, k)] = src
            at[order[-1]] = i + 1
    return order, code, at


def _up_to_check(spec: LabSpec, order: Sequence[str], at: Mapping[str, int], gid: str) -> list[str]:
    """The keys (:func:`_in_order`: answer grade_ids, added cells) that run after ``gid``'s cell and
    before the test cell that checks it: what the notebook had run when the check called its functions."""
    checks = {q.grade_id: q for q in spec.questions}
    check = next((i for i, cell in enumerate(spec.notebook.cells) if _nbgrader(cell).get("grade")
                  and gid in getattr(checks.get(str(_nbgrader(cell).get("grade_id"))), "answers", ())), None)  # fmt: skip
    if check is None or gid not in order:
        return []
    return [k for k in order[order.index(gid) + 1 :] if at[k] <= check]


def _below_key(key: str, gid: str) -> str:
    """The key of ``key``'s cell as given to ``gid``'s run alone (its defs' lab values taken at ``gid``)."""
    return f"{key}, below {gid}"


def without_lorisnb(source: str) -> str:
    """``source`` with its *unused* top-level imports of lorisnb left out (each name of an import
    alone: ``import lorisnb as ln, math`` keeps ``import math``; ``import lorisnb as ln; STRICT =
    False`` keeps ``STRICT = False``): what an answer graded with numpy only runs. An ``import lorisnb
    as ln`` whose name the cell never reads as the module's costs nothing (the other cells' imports of
    lorisnb are left out too, :func:`earlier_functions`; a function's own local ``ln`` is not a read
    of it); one the cell reads (``ln.score``, even in a function) stays, and the guard refuses it, and
    the points with it, as any other way to lorisnb. ``source`` itself when it has none (or does not parse)."""
    body = cell_body(source)
    try:
        read = _global_reads(body.replace("\r\n", "\n").replace("\r", "\n"))
    except SyntaxError:
        return source
    found = False

    def pick(node: ast.stmt) -> ast.stmt | str | None:
        nonlocal found
        if not isinstance(node, (ast.Import, ast.ImportFrom)):
            return node
        got = _without_aliases(node, lambda a: _lorisnb_alias(node, a) and a.name != "*"
                               and (a.asname or a.name).split(".")[0] not in read)  # fmt: skip
        found = found or got is not node
        return got

    rebuilt = _rebuild(body, pick)
    return rebuilt + "\n" if found and rebuilt is not None else source


def _lab_imports(spec: LabSpec) -> dict[str, str]:
    """name -> the import statement of the lab's own cells that binds it (``pd`` -> ``import pandas as pd``)."""
    out: dict[str, str] = {}
    for cell in spec.notebook.cells:
        meta = _nbgrader(cell)
        if cell.cell_type != "code" or meta.get("solution") or meta.get("grade"):
            continue
        try:
            tree = ast.parse(cell.source)
        except SyntaxError:
            continue
        for node in tree.body:
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                for a in node.names:
                    one = (ast.Import(names=[a]) if isinstance(node, ast.Import)
                           else ast.ImportFrom(module=node.module, names=[a], level=node.level))  # fmt: skip
                    out.setdefault((a.asname or a.name).split(".")[0], ast.unparse(one))
    return out


#: what an answer graded alone (a formula) has, in the words of its errors
ALONE = (
    "a formula is graded alone, in a sandbox with numpy (np) and math only besides your answer cell: with the "
    "functions and imports of your other cells (up to its check) and the lab's values its defs read when defined "
    "(eps=eps), never the lab's imports and variables"
)


_BEFORE = "_lorisnb_grader_defs_before"  # what a formula's names held before its cells ran (in its sandbox)


def _defined_before_failing(box: Sandbox, gid: str, defs: Sequence[str]) -> bool:
    """Whether the answer cell that just failed in ``box`` had bound every one of its functions
    ``defs`` (each name holds another object than before its cells ran): the error came after the
    definitions, as a try-out line's does, and in Jupyter the check would call them."""
    probe = (f"{_BEFORE}_ok = isinstance(globals().get({_BEFORE!r}), dict) and all("
             f"n in globals() and globals()[n] is not {_BEFORE}.get(n) for n in {list(defs)!r})")  # fmt: skip
    try:
        reply = box.run(probe, (f"{_BEFORE}_ok",), name=f"<after answer {gid}>")
        box.run(f"globals().pop({_BEFORE!r}, None); globals().pop({_BEFORE + '_ok'!r}, None)", name="<cleanup>")
    except SandboxError:
        return False
    return bool(reply.get("ok")) and reply.get("values", {}).get(f"{_BEFORE}_ok") == {"value": True}


def _tryout_note(gid: str, defs: Sequence[str], error: str, source: str, line: Any, after: bool) -> str:
    """The note of a formula graded on its definitions because a line outside them failed alone
    (``error``; ``line``: the cell's line that raised it, when the sandbox could tell)."""
    if not after:
        return (f"{gid}: a line outside its functions needs the lab's numbers ({error}); run alone, as formulas are "
                "graded, the cell is graded on its functions (and imports) only")  # fmt: skip
    lines = source.split("\n")
    where = "a line after its functions"
    magic = cell_body(source) != source  # a %%time cell: its lines are the magic's call's, not the cell's
    if isinstance(line, int) and 0 < line <= len(lines) and lines[line - 1].strip() and not magic:
        where = f"line {line} of the cell (`{shorten(lines[line - 1].strip(), 80)}`)"
    return (f"{gid}: {where} raised {error}, after the cell had defined {', '.join(f'`{d}`' for d in defs)}: "
            "graded on its functions (and imports), which is what the check calls (in Jupyter they were defined "
            "before that line failed); tidy that try-out line (fix the call, or remove it) so the cell runs "
            "without an error")  # fmt: skip


def _with_hint(spec: LabSpec, error: str, unkept: Mapping[str, str] | None = None) -> str:
    """``error`` of a formula run alone; a NameError (``name 'pd' is not defined``) says what the
    formula has there, and what to do (:func:`_name_tip`)."""
    tip = _name_tip(spec, error, unkept=unkept)
    return error if tip is None else f"{error} ({ALONE}; {tip})"


def _name_tip(
    spec: LabSpec, error: str, imports_only: bool = False, unkept: Mapping[str, str] | None = None
) -> str | None:
    """What to do about a NameError of an answer run alone: the lab's import to put in the cell, the
    lab's variable to take as an argument (not with ``imports_only``: a prediction's message says
    which numbers it is given); None for another error."""
    m = re.search(r"NameError: name '([^']+)' is not defined", error)
    if m is None:
        return None
    name = m.group(1)
    imports = _lab_imports(spec)
    if name in imports and "lorisnb" in imports[name]:
        tip = f"the lab's `{imports[name]}` is not there: lorisnb may not be used by a formula, write it with numpy"
    elif name in imports:
        tip = f"the lab's `{imports[name]}` is not run there: put `{imports[name]}` in your answer cell"
    elif unkept and name in unkept:  # the student did define it: say why it is not there
        tip = (f"`{name}` is assigned in {unkept[name]}, but that value is not given to a formula run alone: only "
               "functions, imports, and values made of constants, lambdas and your functions' names are (never a "
               "call's result or a value read from the lab's variables, which may hold what the answer is checked "
               f"against); define `{name}` with `def`, or as such a value")  # fmt: skip
    elif imports_only:
        return None
    elif name in _lab_names_before(spec, len(spec.notebook.cells)):
        tip = (f"the lab's `{name}` is not there: take it as an argument (or a default read when defined, {name}={name}, "
               "where it holds a plain value: a number, a string, a tuple of them; a table or a trajectory is not given)")  # fmt: skip
    else:
        tip = f"define or import `{name}` in your answer cell"
    return tip


_BUDGET_ERROR = "the submission's time budget ({:g} s) ran out before this answer was graded"
PRELUDE = "import math\nimport numpy as np\n"  # what an answer run alone has besides its own code


def _predict(
    spec: LabSpec,
    gid: str,
    source: str,
    given: Mapping[str, Any],
    root: Path,
    hidden: Sequence[Path],
    settings: GradeSettings,
    budget: Budget,
    notes: list[str],
    took: float,
    boxes: list[Sandbox],
    helpers: Sequence[tuple[str, str]] = (),
) -> dict[str, Any]:
    """A prediction (``gid``'s answer cell, ``source``) run alone in a sandbox without lorisnb, with
    numpy, math and the lab's numbers ``given`` (name -> :func:`._sandbox_child.given`'s form, as the
    grader's own run of the lab has them at that cell); the values read back (each ``{"error": ...}``
    when it fails, the reason in the note it adds). First, under ``--timeout`` of their own, numpy and
    math, the functions and imports of the earlier answer cells (``helpers``) and the cell's own
    imports (a fresh process imports scipy, pandas or matplotlib in seconds, which the lab's process
    had done before the cell ran); then the cell gets twice the ``took`` seconds it took in the lab,
    plus 2 s (at most ``--timeout``). Both are charged to the budget but run even when that is spent:
    the cell ran in time in the lab, and a question answered by then keeps its points. A cell that
    fails (a ``display(Markdown(...))`` or ``print`` line reading the lab's objects) after its value
    is bound is graded on the value it had computed up to the failing line (its statements run in
    order, stopped at the first that fails, none left out); one whose value is not bound by then
    scores 0 with that error."""
    capture = spec.values.get(gid, ())

    def failed(error: str, note: str | None = None) -> dict[str, Any]:
        notes.append(note or f"{gid}: {error}")
        return {n: {"error": error} for n in capture}

    usable = {n: v for n, v in given.items() if "not_plain" not in v and "missing" not in v}
    work = root / f"prediction-{gid}"
    work.mkdir(mode=0o700)
    limit = min(2 * took + 2.0, settings.limits.cell_timeout_s)
    setup = settings.limits.cell_timeout_s
    box = Sandbox(work, limits=settings.limits, hidden=hidden, uid=settings.uid + 1, no_lorisnb=True, private=[root])
    boxes.append(box)  # its stray lines are counted with the others'
    own_imports = definitions_only(source, keep=(ast.Import, ast.ImportFrom), lorisnb=False) or ""
    stage = "setup"
    culprit = None
    try:
        with budget.charge():
            box.bind(usable)  # the sandbox's start (no code of the answer runs yet)
            # what the lab's process had imported and defined before the cell ran: not the cell's time (numpy and
            # math, each earlier cell's functions as the notebook ran them, then the cell's own imports)
            deadline = time.monotonic() + setup
            box.run(PRELUDE, name="<numpy and math>", timeout_s=setup)
            culprit, _ = run_cells(box, helpers, lambda: max(deadline - time.monotonic(), 0.1))
            box.run(own_imports, name=f"<the imports of your answer cell {gid}>",
                    timeout_s=max(deadline - time.monotonic(), 0.1))  # fmt: skip
            stage = "cell"
            # an unused top-level import of lorisnb left out, as a formula's (it costs nothing)
            reply = box.run(PRELUDE + without_lorisnb(source), capture, name=f"<answer {gid}>", timeout_s=limit)
            # a line after the value failing alone (display(Markdown(...)), a print of the lab's objects): the
            # value is what the cell had computed when it failed, every statement before the failing one having
            # run in order (+=, if, for, with: none left out), as the notebook computed it; never a re-run of a
            # part of the cell (leaving a statement out changes the value)
            got = reply.get("values", {})
            partial = (not reply.get("ok") and not box.findings and bool(got)
                       and not any(v.get("missing") for v in got.values()))  # fmt: skip
    except SandboxError as exc:
        if stage == "setup":
            return failed(
                "numpy, math, the functions and imports of your earlier answer cells and this cell's imports, run "
                "before the prediction (alone), did not finish"
                + (f" within {setup:g} s (--timeout): {exc}" if isinstance(exc, SandboxTimeout) else f": {exc}")
            )
        if not isinstance(exc, SandboxTimeout):
            return failed(f"the prediction, run alone, did not finish: {exc}")
        return failed(
            f"the prediction, run alone, did not finish within {limit:.3g} s (twice the time it took in the lab, "
            f"plus 2 s, its imports and your earlier cells' functions run before it and not counted): {exc}"
        )
    finally:
        box.close()
    if box.findings:
        message = lorisnb_used(f"the prediction {gid}", box.findings, by=culprit)
        return failed(message, message)
    if box.tampered or box.late:  # the prediction's code wrote into the grader's pipe: not trusted, whatever it holds
        message = tampered(f"the prediction {gid}", [*box.tampered, *(how for _, how in box.late)])
        return failed(message, f"{gid}: {message}")
    if partial:
        notes.append(f"{gid}: a line failed when the prediction ran alone ({reply.get('error')}), after its value was "
                     "set: graded on the value the cell had computed up to that line (every line before it ran, in "
                     "order, as in the notebook)")  # fmt: skip
        return {n: v for n, v in got.items() if n in capture}
    if unanswered(reply, capture):  # left as handed out (`pred = ...`, nbgrader's stub): "no answer yet"
        return {n: {"missing": True} for n in capture}
    if not reply.get("ok"):
        try:
            read = _loaded(cell_body(source))
        except SyntaxError:
            read = set()
        numbers = ", ".join(sorted(n for n in usable if n in read)) or "none of them"
        withheld = ", ".join(sorted(n for n in given if n in read and n not in usable))
        if withheld:
            numbers += f"; not the lab's functions and objects it reads: {withheld}"
        own = ", ".join(sorted(_defined_functions("\n".join(d for _, d in helpers)) & read)) or "none"
        return failed(
            "a prediction is worked out from the lab's numbers, with numpy, math and the functions of your earlier "
            "answer cells, not computed with the lab's functions or lorisnb; run so (alone: given the numbers the "
            f"lab's cells had set, of which it reads {numbers}; and your earlier answer cells' functions, of which it "
            f"calls {own}), the answer cell failed: {reply.get('error')}"
            + (f" ({tip})" if (tip := _name_tip(spec, str(reply.get("error")), imports_only=True)) else "")
        )
    return {n: v for n, v in reply.get("values", {}).items() if n in capture}  # the names asked for, no other


def unanswered(reply: Mapping[str, Any], capture: Sequence[str]) -> bool:
    """Whether a cell's run (``reply``) is that of an answer cell left as handed out: it failed on
    nbgrader's stub (``raise NotImplementedError()``) with every name it is graded on unset or
    still ``...``; "no answer yet", as a value question says, never an error of the answer."""
    values = reply.get("values", {})
    return (
        not reply.get("ok")
        and str(reply.get("error", "")).startswith("NotImplementedError")
        and all(values.get(n, {"missing": True}).get("missing") for n in capture)
    )


def _defined_functions(source: str) -> set[str]:
    try:
        return {
            n.name for n in ast.parse(cell_body(source)).body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
        }
    except SyntaxError:
        return set()


MESSAGE_CHARS = 2000  # a check's message or a note, at most (a long answer echoed back is shortened)


def shorten(text: str, limit: int = MESSAGE_CHARS) -> str:
    """``text`` as is when short, else its beginning and end around the number of characters left out."""
    if len(text) <= limit:
        return text
    keep = limit // 2
    return f"{text[:keep]} [... {len(text) - 2 * keep} characters left out ...] {text[-keep:]}"


def unreadable(
    spec: LabSpec, student: str, notebook: Path, exc: BaseException, seconds: float, why: str | None = None
) -> SubmissionResult:
    """The result of a submission that could not be graded: every question 0, the file and why
    (``why``, else the exception's type and message)."""
    what = shorten(why or f"{type(exc).__name__}: {exc}", 500)
    error = f"{notebook.parent.parent.name}/{notebook.parent.name}/{notebook.name} could not be graded: {what}"
    scores = [Score(q.grade_id, 0.0, q.points, f"not graded: {what}") for q in spec.questions]
    note = error + " (return the notebook as saved by Jupyter: File > Save, then submit it again)"
    return SubmissionResult(student, spec.name, scores, "none", round(seconds, 2), [note], error=error)


def _check_reachable(py_path: Path, settings: GradeSettings) -> None:
    """Refuse to grade when the sandbox's user (an unprivileged uid) could not read lorisnb or the
    Python environment (a checkout in a folder closed to others): every answer would fail and score
    0 without a word about why."""
    import sys

    from lorisnb.errors import ValidationError
    from lorisnb.tools.teaching.sandbox import closed_to_others

    if not (settings.uid and _isolated()):
        return
    # lorisnb and the environment's packages (the interpreter itself may lie in a closed home: a
    # child that cannot follow its link runs the system's Python of the same version, as CI's does)
    need = [py_path / "lorisnb", Path(sys.prefix)]
    closed = closed_to_others(need)
    if closed:
        raise ValidationError(
            f"the grading sandbox runs each answer as an unprivileged user, which cannot read {closed[0]} "
            "(closed to other users): lorisnb and its Python environment must be readable by others "
            "(chmod o+rx on that folder, or install them elsewhere) before grading"
        )


def _reachable_tmp() -> str:
    """A temporary folder the sandbox's user can enter: ``$TMPDIR`` unless it (or a folder above it)
    is closed to other users (then /tmp, /var/tmp)."""
    for d in (tempfile.gettempdir(), "/tmp", "/var/tmp"):
        p = Path(d).resolve()
        if p.is_dir() and all(q.stat().st_mode & 0o001 for q in (p, *p.parents)):
            return str(p)
    return tempfile.gettempdir()


def _isolated() -> bool:
    from lorisnb.tools.teaching.sandbox import can_isolate

    return can_isolate()


def _run_student(
    spec: LabSpec,
    answers: Mapping[str, Sequence[str]],
    params: Mapping[str, Any],
    work: Path,
    py_path: Path,
    hidden: Sequence[Path],
    settings: GradeSettings,
    notes: list[str],
    budget: Budget,
    boxes: list[Sandbox],
    alone: Callable[[str, str | None], None],
    answered: dict[str, float] | None = None,
    private: Sequence[Path] = (),
    added: Mapping[int, Sequence[str]] = {},  # noqa: B006 (read only)
    fallback: Mapping[str, Sequence[str]] = {},  # noqa: B006 (read only)
    reorder: Callable[[str, Sequence[str]], None] | None = None,
) -> dict[str, dict[str, Any]]:
    """Step 1: the lab's cells with the student's answers, in the sandbox. Returns the values read
    back after each answer cell; ``alone(grade_id, error)`` runs after each answer cell (step 2 of a
    formula answer; ``error``: the cell hit a limit); ``answered`` gets the seconds each answer cell
    that ran took; ``private``: folders the sandbox sees empty (but for its own). ``answers``: grade_id
    -> its cells, run one after the other (the values read back after the last); ``added``: the cells
    the student added (:func:`added_cells`), run after the lab's cell they follow, as answer cells
    are (unlocked, charged); ``fallback``: grade_id -> its cells in the notebook's order, where that
    differs from ``answers``' (execution counts): when a cell of the id fails in the counts' order,
    they run again in this order (a count is only a cell's last run: the top half of a split cell run
    again last counts bottom first), and the values are read after them when none of them fails
    (``reorder(grade_id, cells)`` is then told; else the counts' order is graded). Every cell from the
    first answer cell on (the lab's own after it too: the student's code could slow them), and every replay after a time-out, is charged to ``budget``;
    once it is spent no more cells run. A replay gives each cell twice the time it took (plus two
    seconds)."""
    # (source, answer grade_id, name, the student's code, the answer's last cell, in the fallback order)
    cells: list[tuple[str, str | None, str, bool, bool, bool]] = []
    # the cells the student added right below an answer cell (before the lab's next cell) -> its grade_id: the
    # notebook's check saw the answer's values after them (an answer computed in a cell inserted below)
    follows: dict[int, str] = {}
    cells += [(src, None, _added_key(-1, j), True, False, False) for j, src in enumerate(added.get(-1, ()))]
    for i, cell in enumerate(spec.notebook.cells):
        meta = _nbgrader(cell)
        if cell.cell_type != "code" or meta.get("grade"):
            pass  # the checks run in the grader's process
        elif "parameters" in cell.get("metadata", {}).get("tags", []):
            cells.append((_parameters(cell.source, params), None, "parameters", False, False, False))
        elif meta.get("solution"):
            answer_id = str(meta["grade_id"])
            name = f"<answer {answer_id}>"
            srcs = list(answers.get(answer_id, ())) or [""]
            alt = list(fallback.get(answer_id, ()))
            cells += [(src, answer_id, name, True, j == len(srcs) - 1, False) for j, src in enumerate(srcs)]
            cells += [(src, answer_id, name, True, j == len(alt) - 1, True) for j, src in enumerate(alt)]
        else:
            cells.append((cell.source, None, f"<cell {i}>", False, False, False))
        if meta.get("solution") and cell.cell_type == "code":
            follows.update({len(cells) + j: str(meta["grade_id"]) for j in range(len(added.get(i, ())))})
        cells += [(src, None, _added_key(i, j), True, False, False) for j, src in enumerate(added.get(i, ()))]
    values: dict[str, dict[str, Any]] = {}
    errors: dict[str, str] = {}  # answer grade_id -> the first error of its cells
    stopped: set[str] = set()  # answers whose cell hit a limit: their other cells do not run
    retrying: dict[str, str] = {}  # answers run again in the notebook's order -> the counts' order's first error
    pending: dict[str, list[str]] = {}  # the notes of an answer's failing cells, until its order is settled
    skipped: set[int] = set()
    took: dict[int, float] = {}  # seconds each cell took on its first run
    set_below: dict[str, list[str]] = {}  # answer grade_id -> the names the cells added below it set
    told: dict[str, list[str]] = {}  # answer grade_id -> how its cells (or those added below it) wrote into the pipe
    box = Sandbox(work, limits=settings.limits, hidden=hidden, uid=settings.uid, python_path=[py_path], private=private)
    boxes.append(box)

    def unrun(k: int) -> None:  # the answer cells from k on get no value: the budget is spent
        for _, gid, _, _, _, _ in cells[k:]:
            if gid and gid not in values:
                values[gid] = {n: {"error": _BUDGET_ERROR.format(budget.seconds)} for n in spec.values.get(gid, ())}

    try:
        k, charged = 0, False
        while k < len(cells):
            source, gid, cell_name, student, final, in_fallback = cells[k]
            if gid in stopped or (in_fallback and gid not in retrying):
                skipped.add(k)
                k += 1
                continue
            capture: Sequence[str] = spec.values.get(gid, ()) if gid and final else ()
            below = follows.get(k) if k + 1 not in follows or follows[k + 1] != follows.get(k) else None
            if below is not None:  # the last cell added below an answer: its values read again after it
                capture = spec.values.get(below, ())
            charged = charged or student
            if charged and budget.out(cell_name):
                unrun(k)
                break
            t0 = time.monotonic()
            seen = len(box.tampered)
            try:
                with budget.charge() if charged else contextlib.nullcontext():
                    reply = box.run(source, capture, cell_name, locked=not student,
                                    timeout_s=budget.left(True) if charged else None)  # fmt: skip
            except SandboxError as exc:
                where = gid or cell_name
                spent = charged and budget.out(cell_name)
                notes.extend(pending.pop(gid or "", []))
                notes.append(f"{where}: {_BUDGET_ERROR.format(budget.seconds) if spent else exc}")
                if gid:
                    error = _BUDGET_ERROR.format(budget.seconds) if spent else str(exc)
                    values[gid] = {n: {"error": error} for n in spec.values.get(gid, ())}
                    stopped.add(gid)
                    alone(gid, f"TimeoutError: {error}" if spent else error_of(exc))
                if spent:
                    unrun(k)
                    break
                skipped.add(k)
                with budget.charge():  # replay what ran before, without the cell that hit the limit
                    box.restart()
                    for j in range(k):
                        if j in skipped:
                            continue
                        if budget.out(f"the replay after {where}"):
                            break
                        replayed = len(box.tampered)
                        try:
                            box.run(cells[j][0], (), cells[j][2], locked=not cells[j][3],
                                    timeout_s=min(2 * took.get(j, 0.0) + 2.0, budget.left(True)))  # fmt: skip
                        except SandboxError:
                            skipped.add(j)
                        owner = cells[j][1] or follows.get(j)
                        if owner and cells[j][3] and len(box.tampered) > replayed:
                            told.setdefault(owner, []).extend(box.tampered[replayed:])
                if budget.out(f"the replay after {where}"):
                    unrun(k + 1)
                    break
                k += 1
                continue
            took[k] = time.monotonic() - t0
            owner = gid or follows.get(k)
            if owner and student and len(box.tampered) > seen:  # the answer's code wrote into the grader's pipe
                told.setdefault(owner, []).extend(box.tampered[seen:])
            if reply.get("output_truncated_mib"):
                notes.append(f"{gid or cell_name}: what the cells printed was cut at {reply['output_truncated_mib']:g} "
                             "MiB (the sandbox's file size limit): the rest is left out; the cells ran on")  # fmt: skip
            if gid and answered is not None:
                answered[gid] = answered.get(gid, 0.0) + took[k]
            if k in follows and answered is not None and follows[k] in answered:  # a prediction's time includes them
                answered[follows[k]] += took[k]
            if below is not None and below in values:  # set (or changed) below the answer: what the check saw
                before = values[below]
                later = {n: v for n, v in reply.get("values", {}).items()
                         if n in capture and not v.get("missing") and not _same(v, before.get(n))}  # fmt: skip
                if later:
                    values[below] = {**values[below], **later}
                    set_below[below] = sorted(later)
            if not reply.get("ok"):
                if gid and gid in fallback:  # said once its order is settled
                    pending.setdefault(gid, []).append(f"{gid}: {reply.get('error')}")
                else:
                    notes.append(f"{gid or cell_name}: {reply.get('error')}")
                if gid:
                    errors.setdefault(gid, str(reply.get("error")))
            if gid and final and not in_fallback and gid in errors and gid in fallback:
                # failed in the counts' order: run its cells again top to bottom, before anything reads them
                retrying[gid] = errors.pop(gid)
                values[gid] = {n: v for n, v in reply.get("values", {}).items() if n in capture}
                if answered is not None:
                    answered[gid] = 0.0  # the time of the order graded
                k += 1
                continue
            if gid and final and in_fallback:
                if gid not in errors:  # top to bottom it ran: graded so
                    pending.pop(gid, None)
                    notes.append(f"{gid}: its cells failed in the order of their execution counts "
                                 f"({retrying[gid]}), which record only each cell's last run; top to bottom, as the "
                                 "notebook could have run them, they succeed: graded in that order")  # fmt: skip
                    if reorder is not None:
                        reorder(gid, fallback[gid])
                else:  # both orders fail: the counts' order is graded, with its error
                    errors[gid] = retrying[gid]
                    reply = {"values": values.get(gid, {})}
            if gid and final:
                notes.extend(pending.pop(gid, []))
                got = dict(reply.get("values", {}))
                values[gid] = {n: v for n, v in got.items() if n in capture}
                failed = errors.get(gid, "")
                if failed and not failed.startswith("NotImplementedError") and gid not in spec.predictions:
                    # no value because the cell failed: say so, not "no answer yet" (a prediction's own run says why)
                    values[gid] = {n: {"error": f"your answer cell failed: {failed}"} if v.get("missing") else v
                                   for n, v in values[gid].items()}  # fmt: skip
                alone(gid, tampered(f"your answer cell {gid}", told[gid]) if gid in told else None)
            k += 1
    finally:
        box.close()
    # a reply found after the grader had read one to its request (the code forged it and answered the grader's
    # check itself): the answer whose cell the request ran, whenever it was found
    owners = {name: cells[k][1] or follows.get(k) for k, (_, _, name, student, _, _) in enumerate(cells) if student}
    for name, found in box.late:
        owner = owners.get(name)
        if owner:
            told.setdefault(owner, []).append(found)
        else:
            notes.append(f"{found}: the request ran the lab's own code or a cell of no answer; no answer is marked, "
                         "but its code wrote into the grader's reply channel")  # fmt: skip
    for gid, names in set_below.items():
        if gid not in spec.predictions and gid in answers:
            notes.append(f"{gid}: {', '.join(names)} set in the cell(s) you added right below the answer cell, before "
                         "the lab's next cell: read there, as the notebook's check saw it")  # fmt: skip
    for gid, own in answers.items():  # a name left unset with no placeholder there: not "no answer yet"
        if gid in values and gid not in spec.predictions:
            values[gid] = unset(
                values[gid], [*own, *(src for k, (src, *_) in enumerate(cells) if follows.get(k) == gid)]
            )
    for gid, how in told.items():  # its code wrote into the grader's pipe: not trusted, whatever it holds
        error = tampered(f"your answer cell {gid}", how)
        values[gid] = {n: {"error": error} for n in spec.values.get(gid, ())}
        notes.append(f"{gid}: {error}")
    return values


def _same(a: Any, b: Any) -> bool:
    """Whether two values read back (``_plain``'s form) are the same (NaN as NaN): a cell added below
    an answer that left a value as the answer cell set it did not set it."""
    return json.dumps(a, sort_keys=True, default=str) == json.dumps(b, sort_keys=True, default=str)


def unset(values: Mapping[str, Mapping[str, Any]], sources: Sequence[str]) -> dict[str, dict[str, Any]]:
    """An answer's values read back, each name its cells (``sources``: the answer's and those added
    right below it) left unset *without* nbgrader's placeholder there (``name = ...`` or ``raise
    NotImplementedError``) told so, instead of "no answer yet": the cell defines a helper and the
    value is computed further down, past the lab's next cell, where the grader reads nothing."""
    text = "\n".join(sources)
    stub = "NotImplementedError" in text
    out: dict[str, dict[str, Any]] = {}
    for n, v in values.items():
        placeholder = stub or re.search(rf"(?m)^\s*{re.escape(n)}\s*=\s*\.\.\.\s*(#.*)?$", text) is not None
        if v.get("missing") and not placeholder:
            v = {"error": f"`{n}` is not set by your answer cell, nor by a cell you added right below it (it ran "
                          f"without error): the check reads `{n}`; set it in the answer cell (a cell further down, "
                          "past the lab's next cell, is not read: the lab's cells after an answer compute what it is "
                          "checked against)"}  # fmt: skip
        out[n] = dict(v)
    return out


def _student_value(plain: Mapping[str, Any]) -> Any:
    if "error" in plain:
        return NotPlain("no value", error=str(plain["error"]))
    return decode(dict(plain))


def _run_checks(
    spec: LabSpec,
    values: Mapping[str, Mapping[str, Mapping[str, Any]]],
    functions: Mapping[str, RemoteFunction],
    params: Mapping[str, Any],
    root: Path,
    predicted: Callable[[str, Mapping[str, Any]], dict[str, Any]] | None = None,
) -> list[Score]:
    """Step 3: the instructor's notebook in this process; each test cell with the student's answers.
    At a prediction's answer cell, ``predicted(grade_id, the lab's numbers then)`` gives the values
    its check reads (instead of those of the student's run of the lab)."""
    import matplotlib

    from lorisnb.tools.teaching._sandbox_child import given

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = root / "reference-out"
    ns: dict[str, Any] = {"__name__": "__main__"}
    by_id = {q.grade_id: q for q in spec.questions}
    scores: list[Score] = []
    values = dict(values)
    cwd = os.getcwd()
    os.chdir(root)
    try:
        for cell in spec.notebook.cells:
            meta = _nbgrader(cell)
            if cell.cell_type != "code":
                continue
            gid = str(meta.get("grade_id"))
            if meta.get("solution") and gid in spec.predictions and predicted is not None:
                lab = {n: given(ns[n]) for n in spec.predictions[gid] if n in ns}
                values[gid] = predicted(gid, lab)
            source = cell.source
            if "parameters" in cell.get("metadata", {}).get("tags", []):
                source = _parameters(source, {**params, "output_dir": str(out)})
            q = by_id.get(str(meta.get("grade_id"))) if meta.get("grade") else None
            if q is None:
                with contextlib.redirect_stdout(io.StringIO()):
                    exec(compile(source, f"<instructor {meta.get('grade_id', 'cell')}>", "exec"), ns)  # noqa: S102
                continue
            student: dict[str, Any] = {}
            for gid in q.answers:
                student.update({n: f for n, f in functions.items() if n in spec.functions.get(gid, ())})
                # the answer's own names and no other: a reply can never rebind the check's reference
                own = spec.values.get(gid, ())
                student.update({n: _student_value(v) for n, v in values.get(gid, {}).items() if n in own})
                student.update({n: Ellipsis for n in spec.values.get(gid, ()) if n not in student})
            saved = {n: ns.get(n) for n in student}
            ns.update(student)
            buf = io.StringIO()
            try:
                with contextlib.redirect_stdout(buf):
                    exec(compile(source, f"<test {q.grade_id}>", "exec"), ns)  # noqa: S102
                if refused := settled(student.values()):  # a call's reply forged, found after the check's last call
                    raise AnswerError(f"✗ {refused}")
                scores.append(Score(q.grade_id, q.points, q.points, shorten(buf.getvalue().strip())))
            except Exception as exc:  # a failed check (AnswerError) or the answer's own error
                text = str(exc) if isinstance(exc, AssertionError) else f"{type(exc).__name__}: {exc}"
                scores.append(Score(q.grade_id, 0.0, q.points, shorten((buf.getvalue() + text).strip())))
            finally:
                ns.update(saved)
            plt.close("all")
    finally:
        os.chdir(cwd)
        plt.close("all")
    return scores


def digest(*parts: bytes | str) -> str:
    """A digest of what a grade depends on (submission, lab source, release, settings, grader)."""
    h = hashlib.sha256(GRADER_VERSION.encode())
    for p in parts:
        h.update(b"\0" + (p.encode() if isinstance(p, str) else p))
    return h.hexdigest()
