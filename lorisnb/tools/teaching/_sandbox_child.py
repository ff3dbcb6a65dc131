"""The process that runs a student's code inside the grading sandbox (started by
:mod:`lorisnb.tools.teaching.sandbox`; never imported by lorisnb, and it imports nothing of lorisnb).

It reads one JSON request a line from stdin and writes one JSON reply a line to the stdout it was
started with; the student's own prints go to ``student-output.txt`` in the working folder.

- ``{"op": "exec", "source": ..., "capture": [names]}``: run one cell in the notebook's namespace,
  then reply with each captured name's value as a plain value (number, bool, string, an array of
  numbers, a list or tuple of numbers as their array; anything else is reported by its type only,
  never converted, so an object cannot wait to see the reference);
- ``{"op": "call", "name": ..., "args": {...}}``: call a function the cells defined and reply with
  its result as plain values (numbers or booleans, scalars or arrays);
- ``{"op": "sync"}``: reply at once, running nothing (the grader asks it after each reply: any
  line the pipe holds before this reply was written by the student's code);
- ``{"op": "set", "values": {...}}``: bind values in the notebook's namespace, running nothing (the
  lab's numbers a prediction run alone is given, described by :func:`given`: numbers, strings,
  arrays of numbers, tuples and lists of numbers).

With ``--no-lorisnb`` (formula answers and predictions, graded with numpy alone) lorisnb cannot be
used: :func:`install_guard` refuses it from any copy on the machine before the student's code runs,
and reports each refusal, and what :func:`install_guard`'s scan finds after each request, to the
grader as a line ``{"lorisnb": what}``. Whatever the student's code does to this process can only
change the replies about its own answers: the references it is compared with are computed by the
grader, in another process.
"""

from __future__ import annotations

import ast
import json
import os
import sys
import traceback
from typing import Any


def _plain(value: Any) -> Any:
    """A JSON-able description of an answer value (exact types only: no subclass, no proxy)."""
    import numpy as np

    def number(v: Any) -> bool:  # a number of Python's or numpy's own (exact types)
        return type(v) in (bool, int, float) or (
            isinstance(v, np.generic) and type(v).__module__ == "numpy" and v.dtype.kind in "biuf"
        )

    t = type(value)
    if value is Ellipsis:
        return {"missing": True}
    if t in (bool, int, float, str) or value is None:
        return {"value": value}
    if isinstance(value, np.generic) and t.__module__ == "numpy" and value.dtype.kind in "biufU":  # numpy's str_ too
        return {"value": value.item()}
    if t in (list, tuple) and all(number(v) for v in value):  # one boolean per pose, as a list: the numbers' array
        value, t = np.array(value), np.ndarray
    pd = sys.modules.get("pandas")
    if pd is not None and t in (pd.Series, pd.DataFrame, pd.Index):  # pandas' own types (no subclass): their numbers
        value, t = value.to_numpy(), np.ndarray
    if t is np.ndarray and value.dtype.kind in "biuf":
        return {"array": value.tolist(), "dtype": value.dtype.str}
    return {"not_plain": f"{t.__module__}.{t.__qualname__}"}


def given(value: Any) -> Any:
    """A value a prediction may use, described as :func:`_plain` does (numbers, strings, None, numpy
    arrays of numbers) or as a tuple or list of numbers and strings (``{"items": [...], "tuple": ...}``);
    anything else (a function, a module, a table) as ``{"not_plain": type}``."""
    t = type(value)
    if t in (tuple, list) and len(value) <= 100_000:
        items = [_plain(v) for v in value]
        if all(set(i) == {"value"} for i in items):
            return {"items": [i["value"] for i in items], "tuple": t is tuple}
    if t in (bool, int, float, str) or value is None or t.__module__ == "numpy":
        return _plain(value)
    return {"not_plain": f"{t.__module__}.{t.__qualname__}"}


def _decode(arg: Any) -> Any:
    import numpy as np

    if isinstance(arg, dict) and "array" in arg:
        return np.array(arg["array"], dtype=arg["dtype"])
    if isinstance(arg, dict) and "scalar" in arg:
        return np.dtype(arg["dtype"]).type(arg["scalar"])
    return arg


def _given_value(plain: dict[str, Any]) -> Any:
    """The value :func:`given` described."""
    import numpy as np

    if "items" in plain:
        return tuple(plain["items"]) if plain["tuple"] else list(plain["items"])
    if "array" in plain:
        return np.array(plain["array"], dtype=plain["dtype"])
    return plain["value"]


# --- the guard of an answer graded with numpy only (--no-lorisnb) --------------------------------

# What an answer graded with numpy only may not do, and why, in the words of the error it gets
NO_LORISNB = (
    "this answer is graded with numpy only (a formula, or a prediction): lorisnb's code may not be used, "
    "from any copy of it on this machine ({what}); work it out yourself, with numpy"
)
NO_ESCAPE = (
    "this answer (graded with numpy only) may not use {what}: the grader refuses it, as it could reach past "
    "the guard that keeps lorisnb out; work it out with numpy"
)
# audit events refused to such an answer: other processes (they would run without the guard), C
# calls and memory (ctypes could remove the guard), the garbage collector's view of every object (the
# guard's own) and the network (lorisnb's source is downloadable)
_REFUSED_EVENTS = (
    "os.fork", "os.forkpty", "os.exec", "os.posix_spawn", "os.spawn", "os.system", "subprocess.Popen",
    "ctypes.", "gc.get_objects", "gc.get_referrers", "gc.get_referents", "socket.",
    "cpython.PyInterpreterState_New",
)  # fmt: skip
# extension modules whose functions start processes or interpreters without an audit event of their own
_REFUSED_MODULES = ("_posixsubprocess", "_xxsubinterpreters", "_xxinterpchannels")
_ARCHIVES = (".whl", ".zip", ".egg", ".tar", ".tar.gz", ".tgz", ".tar.bz2", ".tar.xz", ".dist-info")


def install_guard(reply_fd: int) -> tuple[Any, Any]:
    """Keep lorisnb out of an answer graded with numpy only (a formula, a prediction): an audit hook
    (``sys.addaudithook``: Python code cannot remove it) refuses importing a module named ``lorisnb``
    from anywhere, and opening, compiling or running a file in a folder named ``lorisnb`` (links
    followed: any copy of the package, a checkout, another environment's, an unpacked wheel), and
    what could reach past it (other processes, ctypes, the garbage collector's list of objects, the
    network). Each refusal of lorisnb is written to the grader's pipe at once (``{"lorisnb": what}``),
    before the answer's code can do anything about it. Returns ``report`` (writes a finding) and
    ``scan`` (the after-the-fact check of the modules loaded and of the answer's functions; each
    finding reported once).

    The hook uses only functions captured here, never one the answer's code could replace (a
    patched ``os.path`` or ``json`` would run inside it). What it cannot see: a copy of lorisnb's
    code in a folder by another name, the text of its formulas typed in or read from such a copy,
    and a deliberate corruption of the interpreter's memory (numpy can point an array anywhere)."""
    import _posixsubprocess
    import posix
    import subprocess
    import types

    def no_process(*_args: Any, **_kwargs: Any) -> Any:
        raise PermissionError(NO_ESCAPE.format(what="another process"))

    # pandas and scipy import subprocess: it stays importable, but its unaudited way to start a
    # process is gone (a new copy of _posixsubprocess is refused below)
    subprocess._fork_exec = no_process  # type: ignore[attr-defined]
    _posixsubprocess.fork_exec = no_process

    _type, _issub, _str, _bytes, _int, _ord, _len = type, issubclass, str, bytes, int, ord, len
    _str_add, _bytes_add, _decode, _split = str.__add__, bytes.__add__, bytes.decode, str.split
    _starts, _join, _item = str.startswith, str.join, tuple.__getitem__
    _write, _lstat, _readlink, _getcwd = posix.write, posix.lstat, posix.readlink, posix.getcwd
    _code, _module, _function = types.CodeType, types.ModuleType, types.FunctionType
    _list, _get, _modules = list, dict.get, sys.modules
    _ImportError, _PermissionError, _RuntimeError = ImportError, PermissionError, RuntimeError
    no_lorisnb, no_escape, events, modules, archives = (
        NO_LORISNB,
        NO_ESCAPE,
        _REFUSED_EVENTS,
        _REFUSED_MODULES,
        _ARCHIVES,
    )
    seen: set[str] = set()

    def part(component: str) -> bool:  # a component naming lorisnb's code: its package folder (any case), an
        # lorisnb.egg-info, or a distribution's archive (lorisnb-0.3.0-py3-none-any.whl)
        c = component.lower()
        if c == "lorisnb" or c.startswith("lorisnb."):
            return True
        return c.startswith("lorisnb-") and c[8:9].isdigit() and c.endswith(archives)

    def report(what: str) -> None:
        out = []
        for ch in what[:600]:
            o = _ord(ch)
            out.append(ch if 32 <= o < 127 and ch != '"' and ch != "\\" else "\\u%04x" % (o if o < 0x10000 else 0xFFFD))
        try:
            _write(reply_fd, _str.encode('\n{"lorisnb": "' + _join("", out) + '"}\n'))
        except OSError:
            pass

    def text(x: Any) -> str | None:  # a path as an exact str (a str or bytes subclass copied), else None
        t = _type(x)
        if t is _str:
            return x
        if _issub(t, _str):
            return _str_add("", x)
        if t is _bytes or _issub(t, _bytes):
            return _decode(_bytes_add(b"", x), "utf-8", "surrogateescape")
        return None

    def resolved(path: str) -> list[str]:  # the path's components with every link followed
        if not _starts(path, "/"):
            try:
                path = _str_add(_str_add(_getcwd(), "/"), path)
            except OSError:
                pass
        todo = _split(path, "/")
        todo.reverse()
        done: list[str] = []
        hops = 0
        while todo:
            c = todo.pop()
            if c == "" or c == ".":
                continue
            if c == "..":
                if done:
                    done.pop()
                continue
            here = _str_add("/", _join("/", [*done, c]))
            try:
                mode = _int(_item(_lstat(here), 0))
            except (OSError, ValueError):
                done.append(c)
                continue
            if mode & 0o170000 == 0o120000 and hops < 40:
                hops += 1
                try:
                    target = _readlink(here)
                except (OSError, ValueError):
                    done.append(c)
                    continue
                if _starts(target, "/"):
                    done = []
                more = _split(target, "/")
                more.reverse()
                todo.extend(more)
            else:
                done.append(c)
        return done

    def in_lorisnb(x: Any) -> str | None:  # the path, when it lies in lorisnb's code (links followed)
        path = text(x)
        if path is None or path == "" or _starts(path, "<"):
            return None
        for c in _split(path, "/"):
            if part(c):
                return path
        for c in resolved(path):
            if part(c):
                return path
        return None

    def code_in_lorisnb(code: Any) -> str | None:
        todo, n = [code], 0
        while todo and n < 10000:
            c = todo.pop()
            n += 1
            if _type(c) is not _code:
                continue
            found = in_lorisnb(c.co_filename)
            if found is not None:
                return found
            todo.extend(k for k in c.co_consts if _type(k) is _code)
        return None

    def refuse(exc: type[BaseException], what: str) -> None:
        report(what)
        raise exc(no_lorisnb.format(what=what))

    def hook(event: str, args: tuple[Any, ...]) -> None:
        if event == "import":
            name = text(args[0]) or ""
            parts = _split(name, ".")
            if parts[0] == "lorisnb":
                refuse(_ImportError, f"import {name}")
            if parts[-1] in modules:
                raise _ImportError(no_escape.format(what=f"the module {name}"))
            found = in_lorisnb(args[1]) if _len(args) > 1 else None
            if found is not None:
                refuse(_ImportError, f"import {name} from {found}")
        elif event == "open":
            if _type(args[0]) is _int:
                return
            if text(args[0]) is None:
                raise _PermissionError(no_escape.format(what="a path that is neither a str nor bytes"))
            found = in_lorisnb(args[0])
            if found is not None:
                refuse(_PermissionError, f"open {found}")
        elif event in ("os.chdir", "os.link", "os.symlink", "os.rename", "shutil.copyfile", "shutil.copytree"):
            found = in_lorisnb(args[0]) if _len(args) else None
            if found is not None:
                refuse(_PermissionError, f"{event} {found}")
        elif event == "compile":
            found = in_lorisnb(args[1]) if _len(args) > 1 else None
            if found is not None:
                refuse(_RuntimeError, f"compile {found}")
        elif event == "code.__new__":
            found = in_lorisnb(args[1]) if _len(args) > 1 else None
            if found is not None:
                refuse(_RuntimeError, f"code of {found}")
        elif event == "exec":
            found = code_in_lorisnb(args[0]) if _len(args) else None
            if found is not None:
                refuse(_RuntimeError, f"run code of {found}")
        elif _starts(event, events):
            raise _PermissionError(no_escape.format(what=event))

    def scan(namespace: dict[str, Any]) -> None:
        """After a cell or a call: every module loaded whose name or file is lorisnb's, and every
        function the answer defined whose code (or the code of the functions and modules it names)
        comes from lorisnb's files. Best effort: the answer's code can delete what it loaded."""
        found: list[str] = []
        for name, mod in _list(_modules.items()):
            if mod is None or _type(mod) is not _module:
                continue
            name = text(name) or ""
            where = in_lorisnb(_get(mod.__dict__, "__file__"))
            if _split(name, ".")[0] == "lorisnb" or where is not None:
                found.append(f"the module {name} was loaded{f' from {where}' if where else ''}")
        for name, value in _list(namespace.items()):
            if _type(value) is not _function:
                continue
            named = [value] + [_get(value.__globals__, n) for n in value.__code__.co_names]
            for f in named:
                where = None
                if _type(f) is _function:
                    where = code_in_lorisnb(f.__code__)
                elif _type(f) is _module:
                    where = in_lorisnb(_get(f.__dict__, "__file__"))
                if where is not None:
                    found.append(f"{text(name)} runs code of {where}")
                    break
        for what in found:
            if what not in seen:
                seen.add(what)
                report(what)

    sys.addaudithook(hook)
    return report, scan


class MagicNotRun(Exception):
    """An IPython magic the grader does not run (not NotImplementedError: that is the answer stub's,
    and a cell raising it reads as "not written yet")."""


def _captured(out: Any, err: Any) -> Any:
    """What IPython's ``%%capture NAME`` binds: its ``CapturedIO`` of the texts kept (a stand-in with
    the same ``stdout``, ``stderr``, ``outputs`` and ``show()`` where IPython is not installed)."""
    try:
        from IPython.utils.capture import CapturedIO
    except ImportError:

        class CapturedIO:  # type: ignore[no-redef]
            def __init__(self, stdout: Any, stderr: Any, outputs: Any = None) -> None:
                self._stdout, self._stderr, self.outputs = stdout, stderr, outputs or []

            stdout = property(lambda self: self._stdout.getvalue() if self._stdout else "")
            stderr = property(lambda self: self._stderr.getvalue() if self._stderr else "")

            def __str__(self) -> str:
                return self.stdout

            def show(self) -> None:
                sys.stdout.write(self.stdout)
                sys.stderr.write(self.stderr)

            __call__ = show

    return CapturedIO(out, err, [])


class Shell:
    """What ``get_ipython()`` returns to an answer cell here: the calls IPython's input transformer
    makes of magics and shell escapes (the grader transforms each answer cell as IPython would,
    :func:`lorisnb.tools.teaching.autograde.as_python`), run as Jupyter runs them where they change
    what the cell computes: ``%time``/``%%time``, ``%timeit``/``%%timeit``, ``%%capture`` run their
    code (``%%timeit``'s names stay its own, as in IPython); display settings (``%matplotlib``,
    ``%config``, ``%precision``, ``%load_ext``, ``%autoreload``...) do nothing; ``!cmd``, ``%%bash`` and
    ``x = !cmd`` run the command as ``os.system`` and ``subprocess`` would, in this sandbox (refused
    where another process is, in an answer graded with numpy only), after putting in the Python
    values it names (``!echo {x} $y``) as IPython does (:meth:`var_expand`). Another magic fails,
    naming it."""

    QUIET = frozenset({
        "matplotlib", "config", "precision", "load_ext", "reload_ext", "unload_ext", "autoreload", "aimport",
        "pylab", "xmode", "colors", "pdb", "automagic", "autocall", "pprint", "doctest_mode", "who", "whos",
        "who_ls", "lsmagic", "magic", "history", "notebook", "qtconsole", "env", "pinfo", "pinfo2",
    })  # fmt: skip
    RUN = frozenset({"time", "timeit", "capture", "prun"})
    SHELL = frozenset({"bash", "sh", "script", "system", "sx"})

    def __init__(self, namespace: dict[str, Any]) -> None:
        self.user_ns = namespace

    def _run(self, code: str, name: str, own: bool = False) -> Any:
        ns = dict(self.user_ns) if own else self.user_ns
        try:
            return eval(compile(code, name, "eval"), ns)  # noqa: S307 (the student's own expression)
        except SyntaxError:
            exec(compile(code, name, "exec"), ns)  # noqa: S102 (the student's own cell)
            return None

    def _unknown(self, what: str) -> Any:
        raise MagicNotRun(
            f"the IPython magic {what} is not run by the grader (it runs %time, %timeit, %%capture, display "
            "settings such as %matplotlib, and shell escapes): remove it, or write it in Python"
        )

    def run_line_magic(self, name: str, line: str, _stack_depth: int = 1) -> Any:
        if name in self.RUN:
            options = ("-n", "-r", "-o", "-q", "-p")
            words = line.split()
            while words and words[0].startswith(options):  # %timeit -n 10 -r 3 f(x)
                words = words[2:] if words[0] in ("-n", "-r") else words[1:]
            return self._run(" ".join(words), "<magic>", own=name == "timeit")
        if name in self.QUIET:
            return None
        if name in self.SHELL:
            return self._system(self.var_expand(line, _stack_depth))
        if name == "pwd":
            return os.getcwd()
        if name == "cd":
            os.chdir(line.strip() or ".")
            return None
        return self._unknown(f"%{name}")

    def run_cell_magic(self, name: str, line: str, cell: str) -> Any:
        if name == "capture":
            return self._capture(line, cell)
        if name in self.RUN:
            self._run(cell, "<cell magic>", own=name == "timeit")
            return None
        if name in self.SHELL:
            return self._system(cell)
        if name == "writefile":
            with open(line.split()[-1], "a" if "-a" in line.split() else "w", encoding="utf-8") as f:
                f.write(cell)
            return None
        return self._unknown(f"%%{name}")

    def _capture(self, line: str, cell: str) -> None:
        """``%%capture [--no-stdout] [--no-stderr] [--no-display] [NAME]``: the cell run with what it
        prints kept, not shown, and bound to NAME as IPython binds it (its ``CapturedIO``: ``.stdout``,
        ``.stderr``, ``.show()``), even when the cell fails, as IPython does."""
        import contextlib
        import io

        words = line.split()
        out = None if "--no-stdout" in words else io.StringIO()
        err = None if "--no-stderr" in words else io.StringIO()
        names = [w for w in words if not w.startswith("-")]
        try:
            with contextlib.ExitStack() as stack:
                if out is not None:
                    stack.enter_context(contextlib.redirect_stdout(out))
                if err is not None:
                    stack.enter_context(contextlib.redirect_stderr(err))
                self._run(cell, "<cell magic>")
        finally:
            if names:
                self.user_ns[names[0]] = _captured(out, err)

    def var_expand(self, cmd: str, depth: int = 0) -> str:
        """``cmd`` with the Python names and expressions it names (``{x}``, ``{x + 1}``, ``$x``; ``$$``
        for a ``$``) put in, from the notebook's namespace and the caller's ``depth`` frames up, as
        IPython's ``InteractiveShell.var_expand`` does (with IPython's own formatter); as it is when
        it cannot be expanded (as IPython leaves it)."""
        ns = dict(self.user_ns)
        try:
            ns.update(sys._getframe(depth + 1).f_locals)
        except ValueError:
            pass
        try:
            from IPython.utils.text import DollarFormatter

            return str(DollarFormatter().vformat(cmd, args=[], kwargs=ns))
        except Exception:  # noqa: BLE001 (IPython leaves what it cannot expand as it is)
            return cmd

    def system(self, cmd: str) -> None:
        self._system(self.var_expand(cmd, depth=1))

    def _system(self, cmd: str) -> None:
        import subprocess

        subprocess.run(cmd, shell=True, check=False)  # noqa: S602 (the student's own command, in the sandbox)

    def getoutput(self, cmd: str, split: bool = True, _depth: int = 0) -> Any:
        import subprocess

        cmd = self.var_expand(cmd, depth=_depth + 1)
        out = subprocess.run(cmd, shell=True, check=False, capture_output=True, text=True).stdout  # noqa: S602
        return out.splitlines() if split else out

    def magic(self, line: str) -> Any:
        name, _, rest = line.lstrip("%").partition(" ")
        return self.run_line_magic(name, rest)


class Output:
    """The student's prints (``sys.stdout`` and ``sys.stderr``): written to ``student-output.txt``
    (the file descriptor ``fd``) up to ``cap`` bytes in all, the rest left out after one line saying
    so, so that a cell printing more than the sandbox's file size limit neither ends the process
    (``SIGXFSZ``) nor fails the cells after it (the instructor's too). ``truncated``: set once the
    cap was reached."""

    encoding = "utf-8"
    errors = "backslashreplace"

    def __init__(self, fd: int, cap: int) -> None:
        self.fd, self.cap = fd, cap
        try:
            self.left = cap - os.fstat(fd).st_size  # a restarted sandbox appends to what the first wrote
        except OSError:
            self.left = cap
        self.truncated = self.left <= 0
        self.reported = self.truncated  # the grader is told once

    def write(self, text: Any) -> int:
        if not isinstance(text, str):
            raise TypeError(f"write() argument must be str, not {type(text).__name__}")
        self.write_bytes(text.encode("utf-8", "backslashreplace"))
        return len(text)

    def write_bytes(self, data: bytes) -> None:
        if self.truncated:
            return
        keep = data[: max(self.left, 0)]
        self._put(keep)
        self.left -= len(keep)
        if len(keep) < len(data):
            self.truncated = True
            mib = (self.cap + NOTE_BYTES) / 1024**2
            self._put(f"\n[output truncated at {mib:g} MiB: the rest of what the cells printed is not kept]\n".encode())

    def _put(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            try:
                n = os.write(self.fd, view)
            except OSError:  # the file size limit (SIGXFSZ ignored), a full disk: the rest is lost
                return
            view = view[n:]

    def flush(self) -> None:
        pass

    def fileno(self) -> int:
        return self.fd

    def isatty(self) -> bool:
        return False

    def writable(self) -> bool:
        return True

    def readable(self) -> bool:
        return False

    @property
    def closed(self) -> bool:
        return False

    @property
    def buffer(self) -> Any:  # what writes bytes to ``sys.stdout.buffer``
        return _Bytes(self)


class _Bytes:
    def __init__(self, out: Output) -> None:
        self.out = out

    def write(self, data: Any) -> int:
        data = bytes(data)
        self.out.write_bytes(data)
        return len(data)

    def flush(self) -> None:
        pass


NOTE_BYTES = 4096  # kept under the file size limit for the line saying the output was truncated


def display(*objs: Any, **_kwargs: Any) -> None:
    """Jupyter's ``display`` (IPython puts it in every notebook's builtins): here, as IPython's own
    does outside a notebook, the objects printed."""
    print(*objs)


class Unders:
    """IPython's ``_``, ``__``, ``___``: the values of the last three cells that ended with an
    expression (not None, not silenced by a trailing ``;``); never over a ``_`` the cells set."""

    def __init__(self) -> None:
        self.last: list[Any] = []

    def run(self, source: str, name: str, namespace: dict[str, Any]) -> None:
        """Run one cell as IPython runs it: its last statement, an expression, evaluated for ``_``."""
        tree = ast.parse(source, name)
        last = tree.body[-1] if tree.body else None
        if not isinstance(last, ast.Expr) or source.rstrip().endswith(";"):
            exec(compile(tree, name, "exec"), namespace)  # noqa: S102 (the cell's own code)
            return
        exec(compile(ast.Module(body=tree.body[:-1], type_ignores=[]), name, "exec"), namespace)  # noqa: S102
        value = eval(compile(ast.Expression(body=last.value), name, "eval"), namespace)  # noqa: S307
        if value is None:
            return
        if "_" in namespace and (not self.last or namespace["_"] is not self.last[0]):
            return  # the cells' own _ (a loop variable): IPython leaves it
        self.last = [value, *self.last[:2]]
        namespace.update(zip(("_", "__", "___"), self.last, strict=False))


def notebook_module() -> Any:
    """The module the cells run in, registered as ``sys.modules["__main__"]`` as IPython registers
    its user namespace: a function or class a cell defines is found by name in ``__main__``, so it
    pickles as in Jupyter (``multiprocessing.Pool().map(f, data)``, ``ProcessPoolExecutor``, with the
    fork start method; a spawned or forkserver worker cannot see the notebook's cells, in Jupyter
    either). The child's own code stays in the module it was started as (``-c``), out of the cells'
    ``__main__``; nothing of the grader's is in either (its references are in another process)."""
    import types

    module = types.ModuleType("__main__")
    sys.modules["__main__"] = module
    return module


def main() -> None:
    no_lorisnb = "--no-lorisnb" in sys.argv
    cap = next((int(a.split("=", 1)[1]) for a in sys.argv if a.startswith("--output-bytes=")), 64 * 1024**2)
    import signal

    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # past the file size limit a write fails, never the process
    reply = os.fdopen(os.dup(1), "w", encoding="utf-8")
    requests = os.fdopen(os.dup(0), "r", encoding="utf-8")
    try:  # the student's prints; a name the student's code made a link (or anything but a file) is not followed
        log = os.open("student-output.txt", os.O_WRONLY | os.O_CREAT | os.O_APPEND | os.O_NOFOLLOW, 0o600)
    except OSError:
        log = os.open(os.devnull, os.O_WRONLY)
    devnull = os.open(os.devnull, os.O_RDONLY)
    os.dup2(devnull, 0)
    os.dup2(log, 1)
    os.dup2(log, 2)
    sys.stdin = open(0, encoding="utf-8", closefd=False)  # noqa: SIM115 (the process's own stdin)
    output = Output(1, max(cap - NOTE_BYTES, 0))
    sys.stdout = sys.stderr = output
    scan = None
    if no_lorisnb:
        for name in [m for m in sys.modules if m == "lorisnb" or m.startswith("lorisnb.")]:
            del sys.modules[name]
        sys.modules["lorisnb"] = None  # type: ignore[assignment]  # import lorisnb -> ImportError
        import numpy  # noqa: F401  # imported before the guard (it loads ctypes, which the answer may not)

        _report, scan = install_guard(reply.fileno())
    else:
        import matplotlib

        matplotlib.use("Agg")  # figures are drawn, never shown
    namespace = notebook_module().__dict__
    shell = Shell(namespace)
    namespace["get_ipython"] = lambda: shell  # what IPython's transformed magics and shell escapes call
    namespace["display"] = display  # as Jupyter gives it
    unders = Unders()
    for line in requests:
        req = json.loads(line)
        request_id = req.pop("id", None)
        if req.get("op") == "sync":  # the grader's own, after each reply: nothing runs (anything between is not ours)
            reply.write(json.dumps({"ok": True, "id": request_id}) + "\n")
            reply.flush()
            continue
        out: dict[str, Any] = {"ok": True}
        try:
            if req["op"] == "exec":
                unders.run(req["source"], req.get("name", "<cell>"), namespace)
            elif req["op"] == "set":
                namespace.update({n: _given_value(v) for n, v in req["values"].items()})
            else:
                fn = namespace.get(req["name"])
                if not callable(fn):
                    raise NameError(f"{req['name']} is not defined (or not a function)")
                out["result"] = _plain(fn(**{k: _decode(v) for k, v in req["args"].items()}))
        except BaseException as exc:  # the student's code failed (or called exit()): its error is the reply
            out = {"ok": False, "error": f"{type(exc).__name__}: {exc}"[:2000]}
            if req["op"] == "exec":  # the cell's line that raised (its outermost frame in the cell's own code)
                frames = traceback.walk_tb(exc.__traceback__)
                at = next((n for f, n in frames if f.f_code.co_filename == req.get("name", "<cell>")), None)
                if at is not None:
                    out["line"] = at
            traceback.print_exc()
        if req["op"] == "exec":
            out["values"] = {n: (_plain(namespace[n]) if n in namespace else {"missing": True}) for n in req["capture"]}
        if scan is not None:
            try:
                scan(namespace)
            except Exception:  # noqa: BLE001 (the answer's objects can break a scan: it is best effort)
                traceback.print_exc()
        sys.stdout.flush()
        if output.truncated and not output.reported:
            output.reported = True
            out["output_truncated_mib"] = round(cap / 1024**2, 1)
        out["id"] = request_id
        reply.write(json.dumps(out, default=str) + "\n")
        reply.flush()


if __name__ == "__main__":
    main()
