"""What a fresh process imports: ``import lorisnb`` and ``lorisnb --help`` import neither pandas nor
scipy; a small pair evaluated to the terminal imports no pandas (its files read by pyarrow's CSV
reader where pyarrow is installed); a command that writes a table imports pandas; ``--parquet``
still writes Parquet. Each case runs in a fresh interpreter (this one has imported everything)."""

from __future__ import annotations

import importlib.util
import subprocess
import sys

import pytest

HEAVY = ("pandas", "pyarrow", "scipy", "matplotlib", "tqdm")


def _imported(code: str) -> list[str]:
    """The heavy modules a fresh interpreter holds after running ``code``."""
    probe = f"{code}\nimport sys\nprint(sorted(m for m in {HEAVY!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    return eval(out.strip().splitlines()[-1])  # noqa: S307 (our own list literal)


@pytest.mark.thorough
def test_import_and_public_names_are_lazy():
    assert _imported("import lorisnb") == []
    assert _imported("import lorisnb as ln; ln.Trajectory; ln.read_tum") == []
    assert _imported("import lorisnb as ln; ln.score") == []  # pandas only when a table is built
    assert "pandas" in _imported("import lorisnb as ln; ln.sweep")


def test_help_imports_no_pandas():
    code = "from lorisnb.cli import main\ntry:\n    main(['evaluate', '--help'])\nexcept SystemExit:\n    pass"
    assert _imported(code) == []


@pytest.mark.thorough
def test_names_and_submodules_keep_their_meaning():
    """A name that is also a submodule's stays the name (``lorisnb.core.lifelong.sweep`` the function)."""
    code = (
        "import lorisnb.core.lifelong.sweep, lorisnb.tools.evaluation.runner, lorisnb as ln\n"
        "assert callable(ln.core.sweep) and callable(ln.tools.evaluate) and callable(ln.core.simulate)\n"
        "assert ln.io.read_tum is ln.read_tum and 'read_tum' in dir(ln)"
    )
    _imported(code)


@pytest.mark.skipif(importlib.util.find_spec("pyarrow") is None, reason="pyarrow is not installed")
@pytest.mark.thorough
def test_a_pair_evaluates_to_the_terminal_without_pandas(data, tmp_path):
    tum = data.tum
    args = [str(tum / "fr2_desk_ORB.txt"), "--gt", str(tum / "fr2_desk_groundtruth.txt"), "--no-progress"]
    code = f"from lorisnb.cli import main\nassert main(['evaluate', *{args!r}]) == 0"
    # printed to the terminal: read by pyarrow's CSV reader (the public parser, where installed),
    # scored and tabulated without pandas
    assert _imported(code) == ["pyarrow"]
    csv = tmp_path / "t.csv"
    code = f"from lorisnb.cli import main\nassert main(['evaluate', *{args!r}, '--csv', {str(csv)!r}]) == 0"
    assert _imported(code) == ["pandas", "pyarrow"]  # a table written: pandas too
    out = tmp_path / "table"
    code = f"from lorisnb.cli import main\nassert main(['evaluate', *{args!r}, '--parquet', {str(out)!r}]) == 0"
    assert "pyarrow" in _imported(code)
    assert list(out.rglob("*.parquet"))


@pytest.mark.skipif(importlib.util.find_spec("rfc3987_syntax") is None, reason="rfc3987_syntax is not installed")
@pytest.mark.thorough
def test_report_processes_import_papermill_without_the_iri_grammars():
    """jsonschema (imported by nbformat, papermill, nbconvert) imports rfc3987_syntax, about 2 s of
    grammar compilation, only to check 'iri' strings; lorisnb's command and a report's workers
    import it without, notebooks still validate, and the module stays importable."""
    probe = (
        "import sys\n{setup}\nimport papermill, nbformat\n"
        "nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell('1')])\nnbformat.validate(nb)\n"
        "print('rfc3987_syntax' in sys.modules)\nimport rfc3987_syntax\nprint(callable(rfc3987_syntax.is_valid_syntax))"
    )

    def run(setup: str) -> list[str]:
        code = probe.format(setup=setup)
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
        return out.split()[-2:]

    assert run("") == ["True", "True"]  # what a plain process pays
    assert run("from lorisnb.tools.report.build import _worker_start\n_worker_start(None)") == ["False", "True"]
    cli = "from lorisnb.cli import main\nassert main(['report', '--notebooks', 'no_such_notebook']) == 2"  # refused, after the set-up
    assert run(cli) == ["False", "True"]


def test_workers_are_forked_with_their_modules_where_the_process_runs_one_thread():
    """A pool's workers are forked (no interpreter to start, the modules they need already imported)
    while this process runs a single thread, else started from a fork server (evaluation) or
    spawned (a report's workers), as in a Jupyter kernel, which runs threads."""
    code = (
        "import sys, threading\nfrom lorisnb.tools.evaluation.pool import start_context\n"
        "ctx = start_context(('xml.dom.minidom', 'not_installed_anywhere'), fallback='spawn')  # the task says what is missing\n"
        "print(ctx.get_start_method(), 'xml.dom.minidom' in sys.modules)\n"
        "threading.Thread(target=threading.Event().wait, daemon=True).start()\n"
        "print(start_context(('wave',), fallback='spawn').get_start_method(), 'wave' in sys.modules)\n"
        "print(start_context(('wave',)).get_start_method(), 'wave' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["fork", "True", "spawn", "False", "forkserver", "False"]
