"""A Python environment in a temporary folder (a venv in /tmp/x/venv-teach): the grading sandbox
kept all of /tmp visible (the folder held the interpreter's prefix, so it was not emptied, without a
word), and a submission's `best_algorithm = str(os.listdir('/tmp'))` listed the real /tmp in its
feedback (the adversarial teaching pass). The temporary folder is now emptied, the environment bound
back in it read-only; a folder that cannot be emptied (it is itself a needed path) is named on stderr."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import textwrap
import uuid
from pathlib import Path

import pytest

from lorisnb.tools.teaching import sandbox
from lorisnb.tools.teaching.sandbox import can_isolate, kept_paths, private_folders

pytestmark = pytest.mark.xdist_group("grading")


def test_a_needed_path_in_a_private_folder_is_kept_not_the_folder_left_open(tmp_path):
    tmp = tmp_path / "tmp"
    venv = tmp / "x" / "venv-teach"
    (venv / "bin").mkdir(parents=True)
    (tmp / "x" / "other").mkdir()
    work = tmp / "grade" / "work"
    work.mkdir(parents=True)
    needed = [venv, venv / "bin", tmp_path / "elsewhere"]
    private = private_folders(work, [tmp], needed, tmp=False)
    assert private == [tmp.resolve()]  # emptied, not left open because it holds the environment
    assert kept_paths(private, needed) == [venv.resolve()]  # bound back: the outermost needed path only


def test_a_folder_that_is_a_needed_path_is_left_open_with_a_warning(tmp_path, capsys):
    tmp = tmp_path / "tmp"
    (tmp / "lib").mkdir(parents=True)
    sandbox._WARNED.discard(tmp.resolve())
    assert private_folders(tmp_path / "work", [tmp], [tmp], tmp=False) == []
    assert private_folders(tmp_path / "work", [tmp / "lib"], [tmp], tmp=False) == []
    err = capsys.readouterr().err
    assert f"cannot hide {tmp.resolve()}" in err and f"cannot hide {(tmp / 'lib').resolve()}" in err
    assert "Install the environment elsewhere" in err


CHILD = """
import json, os, shutil, sys, tempfile
from pathlib import Path
from lorisnb.tools.teaching.sandbox import Sandbox, Limits

venv, marker = Path(sys.argv[1]), sys.argv[2]
work = Path(tempfile.mkdtemp(prefix="lorisnb-sandbox-test-"))
try:
    with Sandbox(work, limits=Limits(cell_timeout_s=60)) as box:
        r = box.run(
            "import json, os, numpy, lorisnb, sys\\n"
            "tmp = json.dumps(sorted(os.listdir('/tmp')))\\n"
            f"beside = json.dumps(sorted(os.listdir({str(venv.parent)!r})))\\n"
            "prefix = sys.prefix\\n"
            "try:\\n"
            f"    open({str(venv / 'written')!r}, 'w')\\n"
            "    wrote = True\\n"
            "except OSError:\\n"
            "    wrote = False\\n",
            ["tmp", "beside", "prefix", "wrote"],
        )
finally:
    shutil.rmtree(work)
values = {k: v.get("value") for k, v in r.get("values", {}).items()}
values["tmp"], values["beside"] = json.loads(values["tmp"]), json.loads(values["beside"])
values["work"] = work.name
print(json.dumps({"ok": r["ok"], "error": r.get("error"), "values": values}))
"""


@pytest.mark.skipif(not can_isolate(), reason="needs root on Linux with unshare and setpriv (as CI runs)")
@pytest.mark.thorough
def test_a_venv_in_tmp_runs_the_sandbox_and_shows_nothing_else_of_tmp(tmp_path):
    root = Path(tempfile.mkdtemp(prefix="lorisnb-venv-test-", dir="/tmp"))
    marker = Path("/tmp") / f"lorisnb-marker-{uuid.uuid4().hex}"
    try:
        root.chmod(0o755)  # the sandbox's user must reach the environment
        venv = root / "venv-teach"
        base = Path(sys.base_prefix) / "bin" / f"python{sys.version_info.major}.{sys.version_info.minor}"
        subprocess.run([str(base), "-m", "venv", "--without-pip", str(venv)], check=True)
        (root / "secret.txt").write_text("not for students")  # beside the environment, in the same folder
        marker.write_text("another grader's file")
        purelib = subprocess.run(
            [str(venv / "bin" / "python"), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
            capture_output=True, text=True, check=True,
        ).stdout.strip()  # fmt: skip
        # layered on this environment, as the Makefile's .venv-teach is on .venv
        Path(purelib, "lorisnb-venv.pth").write_text(
            f"import site; site.addsitedir({sysconfig.get_paths()['purelib']!r})\n"
        )
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
        proc = subprocess.run(
            [str(venv / "bin" / "python"), "-c", textwrap.dedent(CHILD), str(venv), marker.name],
            capture_output=True, text=True, env=env, timeout=300,
        )  # fmt: skip
        assert proc.returncode == 0, proc.stderr
        got = json.loads(proc.stdout.strip().splitlines()[-1])
        assert got["ok"], got
        values = got["values"]
        assert values["prefix"] == str(venv)  # the child ran in the environment in /tmp
        assert marker.name not in values["tmp"], values["tmp"]
        assert set(values["tmp"]) == {root.name, values["work"]}, values["tmp"]  # the environment's and its own
        assert values["beside"] == ["venv-teach"]  # secret.txt beside it is not shown
        assert values["wrote"] is False  # the environment is read-only
        assert "cannot hide" not in proc.stderr
    finally:
        marker.unlink(missing_ok=True)
        shutil.rmtree(root, ignore_errors=True)
