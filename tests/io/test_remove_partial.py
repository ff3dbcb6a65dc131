"""An unfinished output folder is removed even while a process being stopped still writes in it
(a SIGTERM'd `lorisnb report` once left its `.partial` folder behind: its kernels were still
writing when the folder was removed once)."""

from __future__ import annotations

import shutil
import threading
import time

from lorisnb.io.writers import remove_partial


def test_a_partial_folder_goes_while_a_late_writer_still_writes(tmp_path):
    folder = tmp_path / ".run.partial-x"
    (folder / "figures").mkdir(parents=True)
    stop = time.monotonic() + 0.6

    def late_writer() -> None:  # a kernel that has not died yet: files keep appearing for a while
        i = 0
        while time.monotonic() < stop:
            try:
                (folder / "figures").mkdir(parents=True, exist_ok=True)
                (folder / "figures" / f"f{i}.png").write_bytes(b"x" * 100)
            except OSError:
                pass
            i += 1

    writer = threading.Thread(target=late_writer)
    writer.start()
    time.sleep(0.05)
    once = tmp_path / "once"
    shutil.copytree(folder, once)
    remove_partial(folder)
    writer.join()
    assert not folder.exists() and list(tmp_path.iterdir()) == [once]


def test_a_writer_that_pauses_and_writes_again_does_not_leave_the_folder(tmp_path):
    """A writer being stopped that is off the CPU for a moment (a loaded machine) and then writes
    again (making its folder again): the folder is removed once it has stayed gone (CI failed once:
    the folder was gone, removal stopped, and the writer made it again)."""
    folder = tmp_path / ".run.partial-y"
    (folder / "figures").mkdir(parents=True)
    paused = threading.Event()

    def pausing_writer() -> None:
        paused.set()
        time.sleep(0.2)  # off the CPU while the folder is removed
        (folder / "figures").mkdir(parents=True, exist_ok=True)
        (folder / "figures" / "late.png").write_bytes(b"x" * 100)

    writer = threading.Thread(target=pausing_writer)
    writer.start()
    paused.wait()
    remove_partial(folder)
    writer.join()
    assert not folder.exists() and list(tmp_path.iterdir()) == []
