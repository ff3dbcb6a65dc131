"""``diff`` exits 1 when an input of either result folder was not scored, as ``evaluate``,
``sweep`` and ``compare`` do on the same inputs: a pair with no time overlap, a manifest session
without an estimate (the numbers of both sides agree; only the inputs tell that nothing was scored)."""

from __future__ import annotations

import pytest
from helpers import write

import lorisnb as ln
from lorisnb.tools.decisions.diff import diff_tables, exit_status, unevaluated


def _shifted(src, seconds: float) -> str:
    """A TUM file with every stamp moved by ``seconds`` (outside the ground truth's time span)."""
    out = []
    for line in src.read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            stamp, rest = line.split(maxsplit=1)
            line = f"{float(stamp) + seconds:.6f} {rest}"
        out.append(line)
    return "\n".join(out) + "\n"


def test_diff_of_inputs_not_scored_exits_1(tmp_path, data):
    tum = data.root / "tum-rgbd"
    gt = tum / "fr2_desk_groundtruth.txt"
    # a pair with no time overlap: read, not scored (evaluate exits 1 on it)
    folder = tmp_path / "shifted"
    write(folder, "a/x.txt", _shifted(tum / "fr2_desk_ORB.txt", 100_000.0))
    ev = ln.evaluate_pairs(folder, gt)
    assert ev.exit_status() == 1 and ev.sequences()["matched"].tolist() == [0]
    failed = unevaluated(ev, folder)
    assert list(failed) == ["a/x.txt"] and "no estimate stamp falls inside" in failed["a/x.txt"]
    table = ev.sequences()
    d = diff_tables(table, table, cand_failures=failed)
    assert d.verdict["verdict"] == "ok"  # the numbers agree: only the inputs tell that nothing was scored
    assert exit_status(d, failed, failed) == 1 and exit_status(d, {}, failed) == 1
    assert exit_status(d, {}, {}) == 0
    # a manifest session without an estimate: the others are scored, the file is not wholly
    est = tmp_path / "est"
    write(est, "algo/fr2_desk.txt", (tum / "fr2_desk_ORB.txt").read_bytes())
    manifest = write(tmp_path, "m.toml", f'name = "two"\nscene = "tumscene"\nroot = "{tum}"\nlifelong = false\n'
                     'groundtruth_format = "tum"\nestimate_format = "tum"\n[conventions]\npreset = "tum"\n'
                     '[[session]]\nname = "fr2_desk"\ngroundtruth = "fr2_desk_groundtruth.txt"\n'
                     '[[session]]\nname = "fr2_missing"\ngroundtruth = "fr2_desk_groundtruth.txt"\n')  # fmt: skip
    ev = ln.evaluate_manifest(manifest, est)
    table = ev.sequences()
    assert ev.exit_status() == 1 and table["matched"].tolist()[1] == 0 and table["matched"].tolist()[0] > 2000
    failed = unevaluated(ev, est)
    assert failed == {"algo": f"{est / 'algo'}: no estimate for session(s) [2]"}
    assert exit_status(diff_tables(table, table), failed, failed) == 1


@pytest.mark.thorough
def test_the_command_line_diff_exits_1_on_inputs_not_scored(tmp_path, data, capsys):
    from lorisnb.cli import main

    tum = data.root / "tum-rgbd"
    gt = tum / "fr2_desk_groundtruth.txt"
    folder = tmp_path / "shifted"
    write(folder, "a/x.txt", _shifted(tum / "fr2_desk_ORB.txt", 100_000.0))
    assert main(["diff", str(folder), str(folder), "--gt", str(gt), "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert "could not be evaluated or were not scored" in err
    scored = tmp_path / "scored"
    write(scored, "a/x.txt", (tum / "fr2_desk_ORB.txt").read_bytes())
    assert main(["diff", str(scored), str(scored), "--gt", str(gt), "--no-progress"]) == 0
    # CAND's unscored input also counts when BASE was scored
    write(tmp_path / "mixed", "a/x.txt", _shifted(tum / "fr2_desk_ORB.txt", 100_000.0))
    assert main(["diff", str(scored), str(tmp_path / "mixed"), "--gt", str(gt), "--no-progress"]) == 1
