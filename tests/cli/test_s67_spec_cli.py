"""Values of the command line checked as on every surface: ``-p`` numbers, ``--badge``'s suffix,
``eps='paper'`` on a pair refused before any work (CLI, Python), ``sweep --relative-to`` refused
before any file is read, and messages in the surface's own words (``--scale on, then off``,
``--rpe-delta 90 with --rpe-unit rad``, ``--max-gap inf``, ``consistency --topic``, a session's
``groundtruth_format``)."""

from __future__ import annotations

import pytest

import lorisnb as ln
from lorisnb.cli import main
from lorisnb.cli.options import param_value
from lorisnb.errors import ValidationError


@pytest.fixture
def tum(data):
    t = data.root / "tum-rgbd"
    if not (t / "freiburg1_xyz-groundtruth.txt").is_file():
        pytest.skip("no tum-rgbd data")
    return t / "freiburg1_xyz-rgbdslam.txt", t / "freiburg1_xyz-groundtruth.txt"


def _err(capsys) -> str:
    return capsys.readouterr().err.strip().splitlines()[-1]


def test_p_values_take_the_number_check_of_every_surface():
    for text in ("1e400", "[1, 1e400]", "-1e400", "1" + "0" * 400):
        with pytest.raises(ValidationError, match=r"-p eps=.*too large to be a number"):
            param_value(text, "-p eps")
    assert param_value("NaN") == "NaN" and param_value("[1, Infinity]") == [1, "Infinity"]  # checked where used
    assert (param_value("1"), param_value("2.5"), param_value("true"), param_value("inf")) == (
        1,
        2.5,
        True,
        float("inf"),
    )


def test_report_refuses_p_1e400(tmp_path, capsys):
    assert main(["report", "--notebooks", "metrics_primer", "-p", "eps", "1e400", "--out", str(tmp_path / "r")]) == 2
    assert "too large to be a number" in _err(capsys)
    assert not (tmp_path / "r").exists()


def test_badge_needs_an_svg_name(tmp_path, capsys):
    out = tmp_path / "out" / "b.png"
    out.parent.mkdir()
    runs = tmp_path / "runs"
    runs.mkdir()
    assert main(["diff", str(runs), str(runs), "--badge", str(out), "--no-progress"]) == 2
    assert "--badge" in (err := _err(capsys)) and "expected a .svg file name" in err
    assert not out.exists()


def test_eps_paper_on_a_pair_is_refused_before_any_work(tum, tmp_path, capsys):
    est, gt = tum
    with pytest.raises(ValidationError, match="eps='paper': the paper's 1/3/5 m are for the OpenLORIS scenes; scene "
                       "'freiburg1_xyz' is not one"):  # fmt: skip
        ln.evaluate_pairs(est, gt, "tum", eps="paper")
    assert main(["evaluate", str(est), "--gt", str(gt), "--eps", "paper", "--no-progress"]) == 2
    assert _err(capsys).startswith("error: --eps paper: the paper's 1/3/5 m")
    assert ln.evaluate_pairs(est, gt, "tum", eps="paper", scene="cafe").exit_status() == 0  # an OpenLORIS scene


def test_report_refuses_eps_paper_on_a_pair_before_the_run_folder(tum, tmp_path, capsys):
    est, gt = tum
    out = tmp_path / "r"
    code = main(["report", "--notebooks", "evaluate_my_results.ipynb", "-p", "groundtruth", str(gt), "-p", "path",
                 str(est), "-p", "eps", "paper", "--out", str(out), "--no-progress"])  # fmt: skip
    assert code == 2 and not out.exists()
    assert "scene 'freiburg1_xyz' is not one" in _err(capsys)


def test_report_takes_a_notebook_name_with_its_suffix(tmp_path, capsys):
    from lorisnb.tools.report.notebooks import notebook_path, select_notebooks

    assert select_notebooks(["metrics_primer.ipynb"], None, None)[0] == ["metrics_primer"]
    assert notebook_path("metrics_primer.ipynb").name == "metrics_primer.ipynb"


@pytest.mark.parametrize("argv", [["--eps", "paper", "--relative-to", "extent"], ["--relative-to", "extent"]])
def test_sweep_relative_to_refused_before_reading(tum, argv, capsys, monkeypatch):
    import lorisnb.cli.commands as commands

    est, gt = tum
    monkeypatch.setattr(commands, "_run_evaluation", lambda *a, **k: pytest.fail("evaluated before refusing"))
    assert main(["sweep", str(est), "--gt", str(gt), *argv, "--no-progress"]) == 2
    err = _err(capsys)
    assert "--relative-to extent" in err and "relative_to" not in err.replace("--relative-to", "")


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--scale", "on", "--scale", "off"], "--scale given twice ('on', then 'off')"),
        (
            ["--rpe-unit", "rad", "--rpe-delta", "90"],
            "--rpe-delta 90 with --rpe-unit rad: expected an angle in [0, pi] rad",
        ),
        (["--max-gap", "inf"], "--max-gap=inf: expected a positive number of seconds, not infinity"),
    ],
)
def test_messages_say_the_values_as_given(tum, argv, says, capsys):
    est, gt = tum
    try:
        code = main(["evaluate", str(est), "--gt", str(gt), *argv, "--no-progress"])
    except SystemExit as exc:  # argparse's own refusal
        code = exc.code
    assert code == 2
    assert says in _err(capsys)


def test_consistency_topic_named_as_the_option(tum, capsys):
    est, gt = tum
    assert main(["consistency", str(est), str(gt), "--topic", "/x"]) == 2
    err = _err(capsys)
    assert err.startswith("error: --topic /x:") and "topic=" not in err


def test_a_sessions_format_advice_names_groundtruth_format(tum, tmp_path, capsys):
    est, gt = tum
    (tmp_path / "res" / "alg").mkdir(parents=True)
    (tmp_path / "res" / "alg" / "a.txt").write_bytes(est.read_bytes())
    m = tmp_path / "m.toml"
    m.write_text(
        f'root = "{gt.parent}"\n[[session]]\nname = "a"\ngroundtruth = "{gt.name}"\ngroundtruth_format = "kitti"\n'
    )
    assert main(["evaluate", str(tmp_path / "res"), "--manifest", str(m), "--manifest-outside", "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert "read it with groundtruth_format = 'tum' in the manifest" in err and "estimate_format = 'tum'" not in err


@pytest.mark.parametrize("command", [["consistency", "a.txt", "b.txt"], ["crosscheck", "a.txt", "b.txt"]])
def test_seq_is_checked_by_the_one_rule_of_every_surface(command, capsys):
    """--seq took its own check ('expected a positive whole number') beside the manifest's and
    Python's seq rule (validate.seq_number): one rule, one message."""
    with pytest.raises(SystemExit) as exit_:
        main([*command, "--seq", "0"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert "--seq=0: expected a positive whole number (sequences are numbered from 1)" in err, err


def test_crosscheck_takes_times_files_by_evaluates_rule(tum, tmp_path, capsys):
    """A KITTI estimate against a TUM ground truth: its times file alone pairs them (it was refused
    with 'give stamps for both files', impossible for a TUM ground truth), and --gt-times on the TUM
    ground truth is refused (it was dropped: exit 0 with a times file of 788 lines beside 3,000 poses)."""
    est, gt = tum
    rows = [ln_.split() for ln_ in est.read_text().splitlines() if ln_[:1].isdigit()]
    kitti, stamps = tmp_path / "est.kitti", tmp_path / "times.txt"
    import numpy as np

    from lorisnb.core.alignment.geometry import quat_to_matrix

    q = np.array([[float(v) for v in r[4:8]] for r in rows])
    m = quat_to_matrix(q)
    p = np.array([[float(v) for v in r[1:4]] for r in rows])
    kitti.write_text("".join(" ".join(repr(float(x)) for x in np.hstack([m[k], p[k][:, None]]).ravel()) + "\n"
                             for k in range(len(rows))))  # fmt: skip
    stamps.write_text("".join(r[0] + "\n" for r in rows))
    base = ["crosscheck", str(gt), str(kitti), "--est-format", "kitti"]
    assert main([*base, "--est-times", str(stamps)]) == 0
    capsys.readouterr()
    assert main([*base, "--est-times", str(stamps), "--gt-times", str(stamps)]) == 2
    assert "--gt-times: only for kitti files; the ground truth is read as tum" in capsys.readouterr().err
    assert main(base) == 2
    assert "the estimate is a KITTI file, which has no stamps: give its times file (--est-times" in (
        capsys.readouterr().err
    )


def test_lifelong_on_files_of_one_sequence_is_noted_as_on_a_pair(icra20, capsys):
    """--lifelong (or --per-seq) on OpenLORIS files that each hold one sequence changes nothing, as
    on a pair, which is told so; such files were told nothing. A file of several sequences among them:
    no note (the mode applies to it)."""
    one = icra20 / "per-seq" / "orbslam2_rgbd" / "cafe_1_1_orbslam2-original.txt"
    several = icra20 / "lifelong" / "ds-slam" / "cafe-1.txt"
    said = "every input has one sequence, so per-seq and lifelong agree"
    for mode in ("--lifelong", "--per-seq"):
        assert main(["evaluate", str(one), mode, "--no-progress"]) == 0
        assert said in capsys.readouterr().err
    assert main(["evaluate", str(one), str(several), "--lifelong", "--no-progress"]) == 0
    assert said not in capsys.readouterr().err
    with pytest.warns(ln.LorisWarning, match=said):
        ev = ln.evaluate(one, lifelong=True)
    assert any(said in n for n in ev.notes)
