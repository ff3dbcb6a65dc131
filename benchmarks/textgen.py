"""Fast writers of large benchmark inputs (OpenLORIS text, millions of poses) and the lifelong
trajectories to fill them: fixed-point numbers formatted with numpy, not one Python call per value.

Only for benchmarks: the files are generated on the fly and never committed. lorisnb's own writer
(:func:`lorisnb.io.write_openloris`) writes exact ``%.17g`` numbers and is the one for users.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from lorisnb.core.simulate import Faults, simulate
from lorisnb.core.trajectory.poses import Trajectory


def fixed(values: np.ndarray, decimals: int, width: int) -> np.ndarray:
    """(n,) floats as (n, width) ASCII bytes, right-aligned, ``decimals`` digits after the point."""
    scaled = np.rint(np.abs(values) * 10**decimals).astype(np.int64)
    out = np.full((len(values), width), ord(" "), np.uint8)
    col = width - 1
    for _ in range(decimals):
        out[:, col] = (scaled % 10).astype(np.uint8) + ord("0")
        scaled //= 10
        col -= 1
    out[:, col] = ord(".")
    col -= 1
    first = True
    while col >= 1:  # integer digits; column 0 is kept for the sign
        digit = (scaled % 10).astype(np.uint8) + ord("0")
        out[:, col] = digit if first else np.where(scaled == 0, ord(" "), digit)
        scaled //= 10
        col -= 1
        first = False
    if (scaled != 0).any():
        raise ValueError(f"values do not fit in {width} characters")
    neg = values < 0
    if neg.any():  # the minus sign goes just before the first digit
        first = np.argmax(out != ord(" "), axis=1)
        rows = np.flatnonzero(neg)
        out[rows, first[rows] - 1] = ord("-")
    return out


def pose_lines(t: Trajectory) -> bytes:
    """OpenLORIS/TUM pose lines ``stamp x y z qx qy qz qw`` (stamps with 9 decimals, nanoseconds)."""
    space = np.full((len(t), 1), ord(" "), np.uint8)
    cols = [fixed(t.stamps, 9, 21)]
    cols += [c for k in range(3) for c in (space, fixed(t.positions[:, k], 4, 9))]
    cols += [c for k in range(4) for c in (space, fixed(t.quaternions[:, k], 7, 10))]
    table = np.concatenate(cols + [np.full((len(t), 1), ord("\n"), np.uint8)], axis=1)
    return table.tobytes()


def write_lines(
    path: Path, scene: str, sequences: dict[int, Trajectory], simulated: bool, single: bool = False
) -> None:
    """An OpenLORIS file of the given sequences (``simulated: true`` in its header if asked), its
    numbers in fixed-width columns, or with ``single`` one space apart."""
    with open(path, "wb") as fh:
        fh.write(f"scene: {scene}\nframe: base_link\n".encode())
        if simulated:
            fh.write(b"simulated: true\n")
        for seq, t in sequences.items():
            fh.write(f"seq: {seq}\n".encode())
            for lo in range(0, len(t), 1_000_000):
                part = Trajectory(t.stamps[lo : lo + 1_000_000], t.positions[lo : lo + 1_000_000],
                                  t.quaternions[lo : lo + 1_000_000])  # fmt: skip
                text = pose_lines(part)
                fh.write(squeeze(np.frombuffer(text, np.uint8).reshape(len(part), -1)) if single else text)


def lifelong_groundtruth(n_poses: int, n_sessions: int, rate_hz: float = 16.0, seed: int = 0) -> dict[int, Trajectory]:
    """A robot driving smooth loops through one building, ``n_sessions`` sessions a few hours
    apart, ``n_poses`` poses in all at ``rate_hz`` (16 Hz for a week: 10 million poses)."""
    rng = np.random.default_rng(seed)
    per = n_poses // n_sessions
    out = {}
    start = 1_560_000_000.0
    for s in range(1, n_sessions + 1):
        t = start + np.arange(per) / rate_hz
        u = np.arange(per) / rate_hz * 0.05 + rng.uniform(0, 6.28)
        pos = np.column_stack([20 * np.sin(u) + 3 * np.sin(7.1 * u), 12 * np.sin(2 * u + 0.3), 0.05 * np.sin(13 * u)])
        yaw = np.unwrap(np.arctan2(np.gradient(pos[:, 1]), np.gradient(pos[:, 0])))
        q = np.column_stack([np.zeros(per), np.zeros(per), np.sin(yaw / 2), np.cos(yaw / 2)])
        out[s] = Trajectory(t, pos, q)
        start = t[-1] + 4 * 3600.0
    return out


def lifelong_files(folder: Path, n_poses: int = 10_000_000, n_sessions: int = 5) -> tuple[Path, Path]:
    """Ground truth and a simulated estimate (drift, noise, a wrong re-localization late in each
    session, a lost stretch) of ``n_poses`` poses, written to ``folder``."""
    gt = lifelong_groundtruth(n_poses, n_sessions)
    est = {}
    for s, g in gt.items():
        span = g.stamps[-1] - g.stamps[0]
        faults = Faults(
            position_noise_m=0.02,
            orientation_noise_deg=0.5,
            drift_per_m=0.002,
            wrong_reloc_at_s=0.8 * span,
            lost=((0.3 * span, 0.32 * span),),
            seed=s,
        )
        est[s] = simulate(g, faults)
    gt_path, est_path = folder / "lifelong_groundtruth.txt", folder / "simulated_lifelong.txt"
    write_lines(gt_path, "market", gt, simulated=True)  # a known scene name; base_link frame on both sides
    write_lines(est_path, "market", est, simulated=True)
    return gt_path, est_path


def squeeze(table: np.ndarray) -> bytes:
    """(n, width) ASCII rows of right-aligned fixed-width fields as bytes with single spaces: the
    padding is dropped (a space after a space or at a line's start), so each line reads as
    ``pd.read_csv(sep=" ")`` reads it."""
    flat = table.reshape(-1)
    space = flat == ord(" ")
    before = np.concatenate(([ord("\n")], flat[:-1]))
    return flat[~(space & ((before == ord(" ")) | (before == ord("\n"))))].tobytes()


def _columns(values: list[tuple[np.ndarray, int, int]], sep: int, n: int) -> np.ndarray:
    """(n, width) ASCII rows of the fixed-width ``(values, decimals, width)`` fields, ``sep`` between."""
    cut = np.full((n, 1), sep, np.uint8)
    cols = []
    for k, (v, decimals, width) in enumerate(values):
        cols += ([cut] if k else []) + [fixed(v, decimals, width)]
    return np.concatenate(cols + [np.full((n, 1), ord("\n"), np.uint8)], axis=1)


def write_plain(path: Path, t: Trajectory, fmt: str) -> None:
    """``t`` as a single-spaced TUM file (``stamp x y z qx qy qz qw``), a KITTI pose file (12
    numbers of ``[R | t]`` per line, no stamps) or a EuRoC CSV (``#timestamp,...`` header, stamps in
    nanoseconds, ``qw`` first)."""
    from lorisnb.core.alignment.geometry import quat_to_matrix

    with open(path, "wb") as fh:
        if fmt == "euroc":
            fh.write(
                b"#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []\n"
            )
        for lo in range(0, len(t), 1_000_000):
            s, p, q = (a[lo : lo + 1_000_000] for a in (t.stamps, t.positions, t.quaternions))
            n = len(s)
            if fmt == "tum":
                values = [(s, 9, 22)] + [(p[:, k], 4, 10) for k in range(3)] + [(q[:, k], 7, 11) for k in range(4)]
                fh.write(squeeze(_columns(values, ord(" "), n)))
            elif fmt == "kitti":
                m = quat_to_matrix(q)
                values = [(m[:, i, j] if j < 3 else p[:, i], 6, 13) for i in range(3) for j in range(4)]
                fh.write(squeeze(_columns(values, ord(" "), n)))
            else:
                ns = np.rint((s - s[0]) * 1e9) + 1.4e18  # nanoseconds, 19 digits
                values = [(ns, 0, 21)] + [(p[:, k], 4, 10) for k in range(3)] + [(q[:, k], 7, 11) for k in (3, 0, 1, 2)]
                fh.write(squeeze(_columns(values, ord(" "), n)).replace(b". ", b" ").replace(b" ", b","))
