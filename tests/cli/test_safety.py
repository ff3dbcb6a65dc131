"""Nothing lost, nothing silently wrong (issue 11): each test reproduces a realistic user mistake
and checks the outcome: the data still there, the error text, the exit status."""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from helpers import write

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.core.alignment.geometry import quat_to_matrix
from lorisnb.tools.report import build as report
from lorisnb.tools.report.provenance import sha256

ORB = "per-seq/orbslam2_rgbd/cafe_1_1_orbslam2-original.txt"
DSO = "per-seq/dso/corridor-1-1-all.txt"


# --- data loss ------------------------------------------------------------------------------


def _user_folder(tmp_path: Path) -> Path:
    d = tmp_path / "results"
    write(d, "paper.tex", "my own work")
    write(d, "run-old/index.html", "an earlier run without a marker")
    return d


@pytest.mark.parametrize("target", ["results", "cwd", "parent", "data"])
def test_report_force_never_replaces_a_folder_it_did_not_create(tmp_path, monkeypatch, capsys, target, data):
    d = _user_folder(tmp_path)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    out = {"results": d, "cwd": work, "parent": tmp_path, "data": data.root}[target]
    before = sorted(p.name for p in out.iterdir())
    rc = main(["report", "--out", str(out), "--force", "--notebooks", "metrics_primer", "--no-progress"])
    assert rc == 2
    err = capsys.readouterr().err
    assert "--force will not replace" in err
    assert sorted(p.name for p in out.iterdir()) == before
    assert (d / "paper.tex").read_text() == "my own work"


def _fake_run(tmp_calls: list, effect=None):
    def run(name, out_dir, parameters, timeout=1800, notebooks_dir=None):
        tmp_calls.append(out_dir)
        if effect:
            effect()
        (out_dir / name).mkdir(parents=True, exist_ok=True)
        return report.NotebookRun(name)

    return run


def test_report_force_replaces_its_own_run_folder(tmp_path, monkeypatch):
    calls: list = []
    monkeypatch.setattr(report, "run_notebook", _fake_run(calls))
    out = tmp_path / "run"
    first, _ = report.run_report(out, {}, ["metrics_primer"], progress=False)
    assert (first / report.RUN_MARKER).is_file()
    (out / "metrics_primer" / "stale.csv").write_text("written by the first run")
    marker = json.loads((out / report.RUN_MARKER).read_text())
    assert "metrics_primer/stale.csv" not in marker["files"] and "index.html" in marker["files"]
    # what the first run wrote (its marker lists it) is replaced as a whole ...
    (out / "metrics_primer" / "stale.csv").unlink()
    second, _ = report.run_report(out, {}, ["metrics_primer"], force=True, progress=False)
    assert second == out and (out / "index.html").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


@pytest.mark.parametrize("added", ["NOTES.txt", "metrics_primer/mine.csv", "empty/", "index.html"])
def test_report_force_keeps_a_run_folder_holding_what_its_run_did_not_write(tmp_path, monkeypatch, capsys, added):
    """A file added to an old run folder (or one of its files changed since) is the user's: --force
    refuses (exit 2, naming it) and removes nothing; the run's own files are left too."""
    monkeypatch.setattr(report, "run_notebook", _fake_run([]))
    out = tmp_path / "run"
    report.run_report(out, {}, ["metrics_primer"], progress=False)
    if added.endswith("/"):
        (out / added).mkdir()
    else:
        (out / added).write_text("my notes")
    before = sorted(p.relative_to(out).as_posix() for p in out.rglob("*"))
    rc = main(["report", "--out", str(out), "--force", "--notebooks", "metrics_primer", "--no-progress"])
    assert rc == 2
    err = capsys.readouterr().err
    assert "--force will not replace" in err and added.rstrip("/") in err and "did not write" in err
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*")) == before
    if not added.endswith("/"):
        assert (out / added).read_text() == "my notes"
    assert [p.name for p in tmp_path.iterdir()] == ["run"]


def test_report_force_keeps_an_earlier_run_folder_whose_marker_lists_nothing(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(report, "run_notebook", _fake_run([]))
    out = tmp_path / "run"
    write(out, report.RUN_MARKER, json.dumps({"lorisnb": "0.3.0", "pid": 1}))
    write(out, "index.html", "an earlier run")
    write(out, "NOTES.txt", "my notes")
    assert main(["report", "--out", str(out), "--force", "--notebooks", "metrics_primer", "--no-progress"]) == 2
    assert "does not list the files" in capsys.readouterr().err
    assert (out / "NOTES.txt").read_text() == "my notes" and (out / "index.html").read_text() == "an earlier run"


def test_report_force_keeps_a_file_added_while_it_runs(tmp_path, monkeypatch, capsys):
    """A file added to the old run folder while the new run is built: the old folder stays as it is
    and the new run lands beside it, saying so."""
    out = tmp_path / "run"
    monkeypatch.setattr(report, "run_notebook", _fake_run([]))
    report.run_report(out, {}, ["metrics_primer"], progress=False)
    monkeypatch.setattr(report, "run_notebook", _fake_run([], lambda: write(out, "NOTES.txt", "my notes")))
    assert main(["report", "--out", str(out), "--force", "--notebooks", "metrics_primer", "--no-progress"]) == 0
    assert (out / "NOTES.txt").read_text() == "my notes" and (out / "index.html").exists()
    assert (tmp_path / "run-2" / "index.html").exists()
    assert "appeared while this report ran" in capsys.readouterr().err


def test_two_reports_into_one_folder_keep_both(tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"

    def other_run_lands():  # the other report finishes first, while this one runs
        write(out, "index.html", "the other run")

    monkeypatch.setattr(report, "run_notebook", _fake_run([], other_run_lands))
    rc = main(["report", "--out", str(out), "--notebooks", "metrics_primer", "--no-progress"])
    assert rc == 0
    assert (out / "index.html").read_text() == "the other run"
    assert (tmp_path / "run-2" / "index.html").exists()
    assert "appeared while this report ran" in capsys.readouterr().err
    for page in ("index.html", "report.html"):  # the pages name the folder they are in
        text = (tmp_path / "run-2" / page).read_text()
        assert "Run folder <code>run-2</code>" in text and "Run folder <code>run</code>" not in text
    marker = json.loads((tmp_path / "run-2" / report.RUN_MARKER).read_text())
    assert marker["files"]["index.html"] == sha256(tmp_path / "run-2" / "index.html")  # --force may replace it


def test_interrupted_report_cleans_up(tmp_path, monkeypatch, capsys):
    def interrupt():
        raise KeyboardInterrupt

    monkeypatch.setattr(report, "run_notebook", _fake_run([], interrupt))
    rc = main(["report", "--out", str(tmp_path / "run"), "--notebooks", "metrics_primer", "--no-progress"])
    assert rc == 130 and "interrupted" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_csv_never_replaces_an_input(tmp_path, icra20, capsys):
    src = write(tmp_path, "orb/cafe.txt", (icra20 / ORB).read_bytes())
    before = src.read_bytes()
    assert main(["evaluate", str(src), "--csv", str(src), "--force", "--no-progress"]) == 2
    assert "is an input of this command" in capsys.readouterr().err
    assert main(["evaluate", str(tmp_path), "--csv", str(tmp_path / "orb" / "new.txt"), "--no-progress"]) == 2
    assert "lies in the input folder" in capsys.readouterr().err
    assert src.read_bytes() == before and sorted(p.name for p in (tmp_path / "orb").iterdir()) == ["cafe.txt"]
    # any output among the inputs, whatever its suffix: diff --json CAND/run.json made CAND a "run folder"
    # whose run.json lacked every key, and the next diff of it failed
    for option, name in (("--json", "run.json"), ("--markdown", "notes.md")):
        rc = main(["diff", str(tmp_path), str(tmp_path), option, str(tmp_path / "orb" / name), "--no-progress"])
        assert rc == 2 and "lies in the input folder" in capsys.readouterr().err
    assert sorted(p.name for p in (tmp_path / "orb").iterdir()) == ["cafe.txt"]


@pytest.mark.parametrize("target", ["gt", "gt_times", "est_times", "manifest_gt"])
def test_force_never_replaces_any_input(tmp_path, data, capsys, target):
    """Every file a command reads is an input, not only the estimates: the ground truth, KITTI
    times files, a manifest's ground-truth files (each given as --csv with --force: refused before
    anything is read, the input byte for byte as it was)."""
    est = write(tmp_path, "est.txt", (data.root / "tum-rgbd" / "freiburg1_xyz-rgbdslam.txt").read_bytes())
    gt = write(tmp_path, "gt.txt", (data.root / "tum-rgbd" / "freiburg1_xyz-groundtruth.txt").read_bytes())
    if target == "gt":
        args, victim = ["evaluate", str(est), "--gt", str(gt)], gt
    elif target == "manifest_gt":
        gt_csv = write(tmp_path, "gt.csv", gt.read_bytes())
        manifest = write(
            tmp_path, "m.toml", f'name = "m"\n[[session]]\nname = "s"\nscene = "x"\ngroundtruth = "{gt_csv}"\n'
        )
        args, victim = ["evaluate", str(tmp_path / "algos"), "--manifest", str(manifest)], gt_csv
        write(tmp_path, "algos/a/s.txt", est.read_bytes())
    else:  # the same pair as KITTI poses with their times files
        paths = {}
        for side, src in (("est", est), ("gt", gt)):
            rows = np.loadtxt(src)
            mats = np.concatenate([quat_to_matrix(rows[:, 4:8]), rows[:, 1:4, None]], axis=2).reshape(-1, 12)
            np.savetxt(tmp_path / f"{side}.kitti", mats, fmt="%.9f")
            paths[side] = write(tmp_path, f"{side}.times.csv", "\n".join(f"{t:.6f}" for t in rows[:, 0]) + "\n")
        args = ["evaluate", str(tmp_path / "est.kitti"), "--gt", str(tmp_path / "gt.kitti"), "--format", "kitti",
                "--est-times", str(paths["est"]), "--gt-times", str(paths["gt"])]  # fmt: skip
        victim = paths["est" if target == "est_times" else "gt"]
    before = victim.read_bytes()
    assert main([*args, "--csv", str(victim), "--force", "--no-progress"]) == 2
    assert "is an input of this command" in capsys.readouterr().err
    assert victim.read_bytes() == before


def test_parquet_force_is_refused_before_the_evaluation(tmp_path, icra20, capsys):
    """--force may replace a Parquet dataset lorisnb wrote, nothing else, and says so before
    anything is read or written (no --csv left behind by a refused run)."""
    user = write(tmp_path, "user/thesis.tex", "precious\n").parent
    out = tmp_path / "table.csv"
    assert (
        main(["evaluate", str(icra20 / ORB), "--csv", str(out), "--parquet", str(user), "--force", "--no-progress"])
        == 2
    )
    err = capsys.readouterr().err
    assert "--force will not replace" in err and "thesis.tex" in err and "conventions:" not in err
    assert not out.exists() and [p.name for p in user.iterdir()] == ["thesis.tex"]


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes anywhere; the directory case below still runs")
def test_csv_into_read_only_folder(tmp_path, icra20, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(stat.S_IRUSR | stat.S_IXUSR)
    assert main(["evaluate", str(icra20 / ORB), "--csv", str(ro / "x.csv"), "--no-progress"]) == 2
    assert "not writable" in capsys.readouterr().err


def test_csv_onto_a_folder_or_empty_name(tmp_path, icra20, capsys):
    assert main(["evaluate", str(icra20 / ORB), "--csv", str(tmp_path), "--no-progress"]) == 2
    assert "is a folder; expected a file name" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:  # an empty value: a usage error, as for every option
        main(["evaluate", str(icra20 / ORB), "--csv", "", "--no-progress"])
    assert exc.value.code == 2 and "--csv: an empty value" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


# --- wrong results without a word -------------------------------------------------------------


def test_scale_words_mean_what_they_say(icra20):
    for off in ("off", "no", "false", "se3", "OFF", False, 0):
        assert ln.evaluate(icra20 / DSO, scale=off).sequences()["scale"].iloc[0] == 1.0
    for on in ("on", "sim3", True):
        assert ln.evaluate(icra20 / DSO, scale=on).sequences()["scale"].iloc[0] == pytest.approx(4.045, abs=1e-3)
    for bad in ("maybe", "", 2, None):
        with pytest.raises(ln.ValidationError, match="scale="):
            ln.evaluate(icra20 / DSO, scale=bad)


@pytest.mark.parametrize(
    "args, message",
    [
        (["-p", "esp", "0.1"], "esp not declared by the selected notebooks; they declare: "),
        (["-p", "eps", "abc"], "eps=abc is not a number"),
        (["-p", "eps", "-1"], "eps=-1: expected 'paper', 'relative:F', a number of metres >= 0"),
        (["-p", "delta", "0"], "delta=0: expected a number of seconds > 0"),
        (["-p", "scale", "maybe"], "scale=maybe: expected True, False, 'auto'"),
    ],
)
def test_report_parameters_are_checked_before_anything_runs(tmp_path, capsys, args, message):
    out = tmp_path / "run"
    assert main(["report", "--out", str(out), "--notebooks", "lifelong_benchmark", *args, "--no-progress"]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_thresholds_are_validated_everywhere(icra20):
    ev = ln.evaluate(icra20 / ORB)
    bad = [dict(delta=-1.0), dict(delta=0), dict(eps=float("nan")), dict(tau=0), dict(phi=-5), dict(eps="big")]
    for kw in bad:
        with pytest.raises(ln.ValidationError):
            ev.sequences(**kw)
        with pytest.raises(ln.ValidationError):
            ln.sweep(ev.errors, **{k: [v] for k, v in kw.items()})
    from lorisnb.tools.notebook.widgets import ThresholdExplorer

    with pytest.raises(ln.ValidationError, match="tau=0"):
        ThresholdExplorer(ev.errors, ev.durations(), tau=0)
    # the command line's words, in any case
    assert ev.sequences(eps="Paper", phi="INF")["eps"].iloc[0] == ln.PAPER_EPS["cafe"]


def test_crosscheck_refuses_unequal_kitti_files_without_stamps(tmp_path, capsys):
    rows = [f"1 0 0 {k} 0 1 0 {k * k % 3} 0 0 1 {k % 2}" for k in range(5)]
    gt = write(tmp_path, "gt.txt", "\n".join(rows) + "\n")
    est = write(tmp_path, "est.txt", "\n".join(rows[:3]) + "\n")
    assert main(["crosscheck", str(gt), str(est), "--format", "kitti"]) == 1  # inputs that cannot be paired
    assert "the ground truth has 5 poses and the estimate 3" in capsys.readouterr().err
    gt_t = write(tmp_path, "gt_times.txt", "\n".join(str(0.1 * k) for k in range(5)) + "\n")
    est_t = write(tmp_path, "est_times.txt", "0.1\n0.2\n0.3\n")
    assert main(["crosscheck", str(gt), str(est), "--format", "kitti", "--gt-times", str(gt_t)]) == 2
    assert (
        "the estimate is a KITTI file, which has no stamps: give its times file (--est-times" in capsys.readouterr().err
    )
    rc = main(
        ["crosscheck", str(gt), str(est), "--format", "kitti", "--gt-times", str(gt_t), "--est-times", str(est_t)]
    )
    assert rc == 0


@pytest.mark.thorough
def test_crosscheck_euroc_follows_evo(tmp_path, data, capsys):
    """--format euroc: ground truth as EuRoC CSV, estimate as TUM text (evo's convention); the
    numbers equal those of the same poses read as TUM."""
    gt = ln.read_tum(data.tum / "freiburg1_xyz-groundtruth.txt")
    rows = np.column_stack([np.round(gt.stamps * 1e9).astype(np.int64), gt.positions, gt.quaternions[:, [3, 0, 1, 2]]])
    csv = tmp_path / "data.csv"
    with open(csv, "w") as fh:
        fh.write("#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []\n")
        for r in rows:
            fh.write(f"{int(r[0])}," + ",".join(f"{v:.9f}" for v in r[1:]) + "\n")
    est = data.tum / "freiburg1_xyz-rgbdslam.txt"
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    assert main(["crosscheck", str(csv), str(est), "--format", "euroc", "--csv", str(a)]) == 0
    assert main(["crosscheck", str(data.tum / "freiburg1_xyz-groundtruth.txt"), str(est), "--csv", str(b)]) == 0
    ta, tb = pd.read_csv(a), pd.read_csv(b)
    ident = ta["note"].str.startswith("identical pairs")
    assert ta.loc[ident, "agrees"].all()
    # equal up to the stamps' trip through integer nanoseconds (interpolation at stamps ~1e-7 s apart)
    np.testing.assert_allclose(ta.loc[ident, "lorisnb"], tb.loc[ident, "lorisnb"], rtol=1e-5)


def test_empty_path_is_an_error(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exc:  # a usage error on the command line, as for every argument
        main(["evaluate", "", "--no-progress"])
    assert exc.value.code == 2 and "FILE_OR_DIR: an empty value" in capsys.readouterr().err
    with pytest.raises(ln.ValidationError, match="an empty path"):
        ln.evaluate("")


# --- tracebacks and unclear messages ------------------------------------------------------------


@pytest.mark.parametrize(
    "args, message",
    [
        (["sweep", "X", "--eps", ","], "eps: an empty list"),
        (["sweep", "X", "--tau", "0"], "tau=0: expected a number of seconds > 0"),
        (["crosscheck", "A", "B", "--rpe-frames", "0"], "--rpe-frames=0: expected a positive whole number"),
        (["crosscheck", "A", "B", "--rpe-metres", "-1"], "--rpe-metres=-1: expected a positive number"),
        (["evaluate", "X", "--delta", "-1"], "delta=-1"),
    ],
)
def test_bad_options_are_usage_errors(capsys, args, message):
    with pytest.raises(SystemExit) as exc:
        main(args)
    assert exc.value.code == 2 and message in capsys.readouterr().err


def test_huge_sweep_is_refused_up_front(icra20):
    ev = ln.evaluate(icra20 / ORB)
    with pytest.raises(ln.ValidationError, match=r"would need about .* GiB"):
        ln.sweep(
            ev.errors, np.linspace(0.1, 10, 2000), np.linspace(1, 180, 1000), [1, 2, 3, 4, 5], [10, 30, 60, 90, 120]
        )


def test_hidden_and_editor_files_are_skipped(tmp_path, icra20):
    write(tmp_path, "orb/cafe.txt", (icra20 / ORB).read_bytes())
    write(tmp_path, "orb/.cafe.txt", "garbage")
    write(tmp_path, "orb/.#cafe.txt", "lock")
    write(tmp_path, ".trash/orb/x.txt", "garbage")
    ev = ln.evaluate(tmp_path)
    assert len(ev.errors) == 1 and not ev.failures


def test_crosscheck_of_an_openloris_file_suggests_the_format(icra20, data, capsys):
    assert (
        main(["crosscheck", str(data.groundtruth("cafe")), str(icra20 / ORB)]) == 1
    )  # an input that cannot be read: 1, as for every command
    assert "--format openloris" in capsys.readouterr().err


@pytest.mark.parametrize("value", [42, pd.DataFrame({"a": [1]}), [Path("x"), 3], b"bytes", None])
def test_wrong_types_get_lorisnb_errors(value):
    with pytest.raises(ln.ValidationError, match="expected"):
        ln.evaluate(value)


def test_score_of_a_path_says_what_to_do():
    with pytest.raises(ln.ValidationError, match=r"evaluate it first: lorisnb.evaluate\(path\)"):
        ln.score("file.txt")


def test_report_skips_a_notebook_whose_extra_is_missing(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(report.NOTEBOOK_NEEDS, "metrics_primer", ("no_such_package_for_lorisnb",))
    out = tmp_path / "run"
    assert main(["report", "--out", str(out), "--notebooks", "metrics_primer", "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "metrics_primer" in text and "skipped" in text and "needs no_such_package_for_lorisnb" in text
    assert "skipped" in (out / "index.html").read_text()


@pytest.mark.parametrize(
    "call, error",
    [
        (lambda p: ln.evaluate(p, data_root=42), ln.DataNotFoundError),
        (lambda p: ln.evaluate(p, algorithms=5), ln.ValidationError),
        (lambda p: ln.evaluate(p, scenes=[1, 2]), ln.ValidationError),
        (lambda p: ln.evaluate(p, mode=None), ln.ValidationError),
        (lambda p: ln.read_openloris(None), ln.ParseError),
        (lambda p: ln.read_tum(42), ln.ParseError),
        (lambda p: ln.read_openloris(""), ln.ParseError),
        (lambda p: ln.load_groundtruth("kitchen"), ln.DataNotFoundError),
        (lambda p: ln.score(ln.evaluate(p).errors, eps=[1, 2]), ln.ValidationError),
        (lambda p: ln.sweep(ln.evaluate(p).errors, eps=[]), ln.ValidationError),
        (lambda p: ln.sweep(ln.evaluate(p).errors, relative_to="size"), ln.ValidationError),
        (lambda p: ln.evaluate(p).sequences(rpe_delta=0), ln.ValidationError),
        (lambda p: ln.evaluate(p).sequences(rpe_unit="km"), ln.ValidationError),
    ],
)
def test_wrong_values_in_python_get_lorisnb_errors(icra20, call, error):
    with pytest.raises(error):
        call(icra20 / ORB)
