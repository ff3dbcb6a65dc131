"""TartanAir's numbers where they are undefined: a ground truth that never moves has no scale, an
estimate that never moves none either, a path under 5 m no KITTI segment. NaN, with no numpy
warning (they showed as RuntimeWarnings with lorisnb's source paths, or a ZeroDivisionError), and
``lorisnb evaluate`` says which sequences and why in a note, as the kitti preset says its own."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from lorisnb.cli import main
from lorisnb.core.metrics.tartanair import tartanair_scores

N = 60
Q = np.tile([0.0, 0.0, 0.0, 1.0], (N, 1))


def _turning(n: int = N) -> np.ndarray:
    a = np.linspace(0, 2, n)
    return np.c_[np.zeros((n, 2)), np.sin(a / 2), np.cos(a / 2)]


def _write(path, positions, quaternions, t0: float = 100.0) -> str:
    rows = (f"{t0 + 0.1 * i:.6f} {' '.join(f'{v:.9f}' for v in (*p, *q))}" for i, (p, q) in
            enumerate(zip(positions, quaternions, strict=True)))  # fmt: skip
    path.write_text("\n".join(rows) + "\n")
    return str(path)


def _quiet(*args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return tartanair_scores(*args, **kw)


@pytest.mark.parametrize("origin", [0.0, 0.1, 123.456789])
def test_a_ground_truth_at_one_point_has_no_scale_and_no_warning(origin):
    """Pure rotation about one point: no scale (it gave 'invalid value in scalar divide' and 'Mean of
    empty slice'; at 0.1 m from the origin a scale of rounding, 1.4)."""
    gt = np.full((N, 3), origin)
    est = gt + np.random.default_rng(0).normal(0, 0.01, gt.shape)
    out = _quiet(gt, _turning(), est, _turning(), scale=True)
    for k in ("tartanair_ate", "tartanair_ate_scale", "tartanair_scale", "tartanair_rpe_trans", "tartanair_kitti_t"):
        assert np.isnan(out[k]), k
    unscaled = _quiet(gt, _turning(), est, _turning(), scale=False)
    assert np.isfinite(unscaled["tartanair_ate"]) and np.isfinite(unscaled["tartanair_rpe_rot"])


def test_an_estimate_that_never_moves_has_no_scale_and_no_traceback():
    """It raised ZeroDivisionError from the scale rule (tartanair_tools: inf, then NaN scores)."""
    gt = np.c_[0.5 * np.arange(N), np.zeros((N, 2))]
    out = _quiet(gt, Q, np.zeros((N, 3)), Q, scale=True)
    assert np.isnan(out["tartanair_scale"]) and np.isnan(out["tartanair_ate"]) and np.isnan(out["tartanair_rpe_trans"])


def test_evaluate_says_which_sequence_has_no_scale_and_which_no_segment(tmp_path, capsys):
    rng = np.random.default_rng(1)
    still_g = _write(tmp_path / "still_g.tum", np.zeros((N, 3)), _turning())
    still_e = _write(tmp_path / "still_e.tum", rng.normal(0, 0.01, (N, 3)), _turning())
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        main(["evaluate", still_e, "--gt", still_g, "--conventions", "tartanair", "--tartanair-scale", "--no-progress"])
    cap = capsys.readouterr()
    assert "RuntimeWarning" not in cap.err and "tartanair.py" not in cap.err
    assert (
        "note: 1 sequence(s) have no TartanAir scale (still_e.tum, seq 1): the scale rule of --tartanair-scale"
        in cap.err
    )
    assert "no TartanAir KITTI segment" not in cap.err  # said once, by the scale
    short = np.c_[0.1 * np.arange(30), np.zeros((30, 2))]  # 2.9 m: under TartanAir's 5 m
    short_g = _write(tmp_path / "short_g.tum", short, _turning(30))
    short_e = _write(tmp_path / "short_e.tum", short + rng.normal(0, 0.01, short.shape), _turning(30))
    main(["evaluate", short_e, "--gt", short_g, "--conventions", "tartanair", "--no-progress"])
    err = capsys.readouterr().err
    assert "note: 1 sequence(s) hold no TartanAir KITTI segment (short_e.tum, seq 1): tartanair_tools' KITTI score " \
           "measures drift over 5 to 40 m" in err  # fmt: skip
    assert "no TartanAir scale" not in err
