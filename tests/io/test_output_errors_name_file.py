"""A write that fails where the system names no file (a full disk: ENOSPC is raised by write()
without a file name) names the output it was writing, through Python and the command line;
never the temporary name it was written under."""

from __future__ import annotations

import errno
import shutil

import pandas as pd
import pytest

from lorisnb.cli import main
from lorisnb.io.writers import write_csv, write_parquet, write_text


def full_disk(*a, **k):
    raise OSError(errno.ENOSPC, "No space left on device")


def csv_disk_full(monkeypatch) -> None:
    """The CSV writer fails as on a full disk (pandas writes every CSV's header line)."""
    monkeypatch.setattr(pd.DataFrame, "to_csv", full_disk)


@pytest.mark.parametrize("writer", ["csv", "text", "parquet"])
def test_a_full_disk_names_the_output_in_python(tmp_path, monkeypatch, writer):
    out = tmp_path / f"table.{writer}"
    if writer == "csv":
        csv_disk_full(monkeypatch)
        call = lambda: write_csv(pd.DataFrame({"a": [1]}), out)  # noqa: E731
    elif writer == "text":
        monkeypatch.setattr("pathlib.Path.write_text", full_disk)
        call = lambda: write_text("x", out)  # noqa: E731
    else:
        pytest.importorskip("pyarrow")
        import pyarrow.parquet as pq

        monkeypatch.setattr(pq, "write_table", full_disk)
        call = lambda: write_parquet(pd.DataFrame({"algorithm": ["a"], "x": [1.0]}), out)  # noqa: E731
    with pytest.raises(OSError) as exc:
        call()
    assert exc.value.errno == errno.ENOSPC and exc.value.filename == str(out)
    assert list(tmp_path.iterdir()) == []  # nothing half-written left


def test_a_full_disk_names_the_output_on_the_command_line(tmp_path, data, icra20, monkeypatch, capsys):
    res = tmp_path / "res" / "orb"
    res.mkdir(parents=True)
    shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt", res)
    csv_disk_full(monkeypatch)
    out = tmp_path / "seq.csv"
    rc = main(["evaluate", str(res.parent), "--data", str(data.root), "--csv", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and f"error: {out}: No space left on device" in err and ".tmp-" not in err


def test_a_figure_on_a_full_disk_names_its_file_in_python_and_on_the_command_line(tmp_path, data, icra20,
                                                                                 monkeypatch, capsys):  # fmt: skip
    """Figures are written as every output is (history --out, save_figure): the file named, nothing
    half-written left."""
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    import lorisnb as ln
    from lorisnb.tools.figures.plotting import save_figure

    res = tmp_path / "res" / "orb"
    res.mkdir(parents=True)
    shutil.copy(icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt", res)
    table = ln.evaluate(res.parent, data_root=data, progress=False).sequences()
    table.to_csv(tmp_path / "a.csv", index=False)
    table.to_csv(tmp_path / "b.csv", index=False)
    real = Figure.savefig

    def full_after_a_byte(self, fname, *a, **k):
        with open(fname, "wb") as f:
            f.write(b"x")
        full_disk()

    monkeypatch.setattr(Figure, "savefig", full_after_a_byte)
    with pytest.raises(OSError) as exc:
        save_figure(plt.figure(), tmp_path / "figs", "f", formats=("png",))
    assert exc.value.errno == errno.ENOSPC and exc.value.filename == str(tmp_path / "figs" / "f.png")
    assert not (tmp_path / "figs").exists()  # nothing half-written, not even the folder made for it
    rc = main(["history", str(tmp_path / "a.csv"), str(tmp_path / "b.csv"), "--out", str(tmp_path / "hist")])
    err = capsys.readouterr().err
    assert rc == 2 and f"error: {tmp_path / 'hist' / 'history_cr.png'}: No space left on device" in err
    assert not (tmp_path / "hist").exists() and ".tmp-" not in err
    monkeypatch.setattr(Figure, "savefig", real)
    assert main(["history", str(tmp_path / "a.csv"), str(tmp_path / "b.csv"), "--out", str(tmp_path / "hist")]) == 0
    assert len(list((tmp_path / "hist").glob("history_*.png"))) == 4
