"""An output never replaces what is not a file (s70): ``--csv NAME --force`` where NAME was a
character device replaced the device node with a regular file; as root, a run writing to
``/dev/null`` so replaced the system's ``/dev/null`` and every later ``> /dev/null`` of every
program wrote into a file. A device, a named pipe or a socket is refused, ``--force`` or not, by the
command line before any work and by every writer (:func:`lorisnb.io.writers.write_atomically`)."""

from __future__ import annotations

import os
import socket
import stat

import pandas as pd
import pytest

from lorisnb.cli import main
from lorisnb.errors import OutputError
from lorisnb.io.writers import write_csv, write_text


def _specials(folder) -> dict[str, str]:
    """name -> what it is: a named pipe and a socket everywhere, a character device as root."""
    made = {}
    os.mkfifo(folder / "pipe.csv")
    made["pipe.csv"] = "a named pipe"
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(folder / "sock.csv"))
    sock.close()
    made["sock.csv"] = "a socket"
    if os.geteuid() == 0:
        os.mknod(folder / "null.csv", 0o666 | stat.S_IFCHR, os.makedev(1, 3))
        made["null.csv"] = "a character device"
    return made


def _unchanged(path, kind: str) -> bool:
    mode = os.lstat(path).st_mode
    return {"a named pipe": stat.S_ISFIFO, "a socket": stat.S_ISSOCK, "a character device": stat.S_ISCHR}[kind](mode)


def test_writers_refuse_what_is_not_a_file_force_or_not(tmp_path):
    for name, kind in _specials(tmp_path).items():
        for force in (False, True):
            with pytest.raises(OutputError, match=f"{name} is {kind}, not a file: .*never replaces"):
                write_csv(pd.DataFrame({"a": [1.0], "b": [2.0]}), tmp_path / name, force=force)
            with pytest.raises(OutputError, match=f"is {kind}"):
                write_text("x\n", tmp_path / name, force=force)
        assert _unchanged(tmp_path / name, kind)
    link = tmp_path / "link.csv"  # a link is replaced itself, never what it points to
    link.symlink_to(tmp_path / "pipe.csv")
    write_csv(pd.DataFrame({"a": [1.0], "b": [2.0]}), link, force=True)
    assert link.is_file() and not link.is_symlink() and _unchanged(tmp_path / "pipe.csv", "a named pipe")


def test_the_command_line_refuses_them_before_any_work(tmp_path, tum_folder, capsys):
    for name, kind in _specials(tmp_path).items():
        rc = main(["evaluate", str(tum_folder / "fr2_desk_ORB.txt"), "--gt", str(tum_folder / "fr2_desk_groundtruth.txt"),
                   "--csv", str(tmp_path / name), "--force", "--no-progress"])  # fmt: skip
        err = capsys.readouterr().err
        assert rc == 2 and f"is {kind}, not a file" in err, err
        assert "evaluated" not in err  # refused before the evaluation
        assert _unchanged(tmp_path / name, kind)
