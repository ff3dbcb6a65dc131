"""A finished ``lorisnb`` command ends before the interpreter tears its objects down: pyarrow's
C++ thread pools aborted the process there now and then ("terminate called without an active
exception", exit status 134 after every table was written; 1 of 40 runs of an evaluation on a
loaded machine), which a nightly job read as a failure. The status is the command's, whatever
the teardown would do. Real data: a bundled icra20 result file."""

from __future__ import annotations

import subprocess
import sys

SCRIPT = """
import os, sys

class Teardown:  # destroyed when the interpreter tears its modules down, after the exit functions
    def __del__(self):
        os.write(2, b"teardown ran\\n")
        os._exit(99)

import atexit
import logging
logging.getLogger("x").addHandler(logging.StreamHandler())  # its exit function (logging.shutdown) still runs
from lorisnb.cli import run

def late():  # an exit function of the command's (registered after lorisnb.cli), which runs as ever
    import types

    held = types.ModuleType("held")  # made after the command froze its objects (gc.freeze): a module
    held.keep = Teardown()  # the teardown clears, if it runs
    sys.modules["held"] = held
    os.write(1, b"exit function ran\\n")

atexit.register(late)

sys.argv = ["lorisnb", "evaluate", sys.argv[1], "--data", sys.argv[2], "--no-progress"]
run()
"""


def test_a_finished_command_exits_with_its_status_before_teardown(tmp_path, icra20, data):
    est = next((icra20 / "per-seq" / "odom").glob("cafe*1*1*.txt"))
    for given, status in ((est, 0), (tmp_path / "missing.txt", 1)):
        out = subprocess.run([sys.executable, "-c", SCRIPT, str(given), str(data.root)], capture_output=True,
                             text=True, timeout=300, cwd=tmp_path)  # fmt: skip
        assert out.returncode == status, out.stderr
        assert "teardown ran" not in out.stderr and "exit function ran" in out.stdout
        assert "cafe" in out.stdout if status == 0 else "file not found" in out.stderr
