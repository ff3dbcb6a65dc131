"""The grader's hardening after an adversarial pass (grading): the root grader never writes, reads or
changes the owner of anything by its name in the folder a student's code owns; answers written as
in Jupyter (magics, defaults from the lab's names, a prediction with an earlier answer's function)
are graded as the notebook ran; the reply pipe's buffer is bounded."""

from __future__ import annotations

import stat
import tempfile
from pathlib import Path

import pytest

from lorisnb.tools.teaching.sandbox import Limits, Sandbox, SandboxError, can_isolate

pytestmark = pytest.mark.xdist_group("grading")
isolated = pytest.mark.skipif(not can_isolate(), reason="needs root on Linux with unshare and setpriv (as CI runs)")


def _reachable_dir() -> Path:
    d = Path(tempfile.mkdtemp(prefix="lorisnb-hardening-", dir="/tmp"))
    d.chmod(0o711)
    return d


@isolated
def test_a_link_planted_in_the_sandbox_folder_never_makes_the_root_grader_write_or_chown_elsewhere():
    base = _reachable_dir()
    victim = base / "victim.txt"
    victim.write_text("root's file\n")
    victim.chmod(0o600)
    victim_dir = base / "victim-dir"
    victim_dir.mkdir(mode=0o700)
    (victim_dir / "inside.txt").write_text("root's too\n")
    work = base / "work"
    work.mkdir()
    (work / "release.txt").write_text("handed out\n")
    before = (victim.read_bytes(), victim.stat(), (victim_dir / "inside.txt").stat(), victim_dir.stat())
    try:
        with Sandbox(work, limits=Limits(cell_timeout_s=3), uid=62300) as box:
            assert (work / "release.txt").stat().st_uid == 62300  # the folder as made was given to its user
            # the tester's attack: the child script's name made a link to a root file, then a time-out
            # (the grader restarts the sandbox), and links of every name a restart could touch
            planted = (
                "import os, shutil\n"
                f"for name in ('_sandbox_child.py', 'student-output.txt', 'release.txt', '.matplotlib'):\n"
                "    try:\n"
                "        os.remove(name)\n"
                "    except OSError:\n"
                "        shutil.rmtree(name, ignore_errors=True)\n"
                f"    os.symlink({str(victim)!r}, name)\n"
                f"os.symlink({str(victim_dir)!r}, 'a-folder')\n"
            )
            r = box.run(planted)
            assert r["ok"], r
            with pytest.raises(SandboxError, match="time limit"):
                box.run("while True:\n    pass")
            box.restart()
            r = box.run("x = 1 + 1", ["x"])
            assert r["ok"] and r["values"]["x"]["value"] == 2
            box.restart()
    finally:
        after = (victim.read_bytes(), victim.stat(), (victim_dir / "inside.txt").stat(), victim_dir.stat())
        for b, a in zip(before[1:], after[1:], strict=True):
            assert (a.st_uid, a.st_gid, stat.S_IMODE(a.st_mode)) == (b.st_uid, b.st_gid, stat.S_IMODE(b.st_mode))
        assert after[0] == before[0] == b"root's file\n"
        import shutil

        shutil.rmtree(base)


def test_the_child_script_is_never_a_file_of_the_sandbox_folder():
    import shutil

    base = _reachable_dir()
    tmp_path = base / "work"
    tmp_path.mkdir()
    with Sandbox(tmp_path, limits=Limits(cell_timeout_s=5), uid=62300) as box:
        r = box.run("import os\nx = len([n for n in os.listdir('.') if n.endswith('.py')])", ["x"])
        assert r["ok"] and r["values"]["x"]["value"] == 0
        box.restart()
        assert not any(p.suffix == ".py" for p in tmp_path.iterdir())
    shutil.rmtree(base)


def test_a_flood_of_the_reply_pipe_without_a_line_end_is_bounded_and_fails_the_cell(monkeypatch):
    import resource
    import shutil

    from lorisnb.tools.teaching import sandbox as sb

    monkeypatch.setattr(sb, "REPLY_BYTES", 4 * 1024**2)
    base = _reachable_dir()
    work = base / "work"
    work.mkdir()
    flood = (
        "import os\n"
        "chunk = b'x' * (1 << 20)\n"
        "for fd in range(3, 12):\n"
        "    try:\n"
        "        os.fstat(fd)\n"
        "    except OSError:\n"
        "        continue\n"
        "    try:\n"
        "        for _ in range(400):\n"
        "            os.write(fd, chunk)\n"
        "    except OSError:\n"
        "        pass\n"
    )
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    try:
        with Sandbox(work, limits=Limits(cell_timeout_s=20), uid=62300) as box:
            with pytest.raises(SandboxError, match="MiB into the grader's reply pipe without a line end"):
                box.run(flood)
            box.restart()
            r = box.run("x = 3", ["x"])
            assert r["ok"] and r["values"]["x"]["value"] == 3
    finally:
        shutil.rmtree(base)
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss0 < 200 * 1024  # KiB: far below the 400 MB sent
