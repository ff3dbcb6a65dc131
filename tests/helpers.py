"""Test helpers: synthetic trajectories and a small OpenLORIS-format fixture (no ../shared/data
needed), and the few lines that read a real result file with its ground truth."""

from __future__ import annotations

import contextlib
import os
import socket
import stat
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from lorisnb.core import FileErrors, ResultFile, Trajectory, compute_errors
from lorisnb.io import load_groundtruth, read_openloris, scene_durations


def write(tmp_path: Path, name: str, text: str | bytes) -> Path:
    """Write ``text`` to ``tmp_path/name`` (folders created) and return the path."""
    p = tmp_path / name
    p.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(text, bytes):
        p.write_bytes(text)
    else:
        p.write_text(text)
    return p


def errors_of(
    path: str | os.PathLike[str] | ResultFile,
    groundtruth: ResultFile | None = None,
    *,
    data_root=None,
    remove_repeated: bool = True,
    repair_stamps: bool = False,
    **kw,
) -> FileErrors:
    """Read a result file and compute its errors against its scene's ground truth (raises on bad
    input, unlike lorisnb.evaluate, which collects failures)."""
    if isinstance(path, ResultFile):
        result = path
    else:
        result = read_openloris(path, remove_repeated=remove_repeated, warn=False, repair_stamps=repair_stamps)
    gt = groundtruth if groundtruth is not None else load_groundtruth(result.scene, data_root, remove_repeated)
    kw.setdefault("algorithm", result.path.parent.name)
    return compute_errors(result, gt, **kw)


def durations_of(*files: FileErrors):
    """Ground-truth durations of the scenes of ``files`` (from the shared data)."""
    return scene_durations(sorted({f.scene for f in files}))


def circle(n: int = 200, rate_hz: float = 10.0, radius_m: float = 5.0, t0: float = 1000.0) -> Trajectory:
    """A synthetic ground truth: a robot driving a circle at constant speed, heading along the path."""
    t = t0 + np.arange(n) / rate_hz
    ang = np.linspace(0, 2 * np.pi, n, endpoint=False)
    pos = np.column_stack([radius_m * np.cos(ang), radius_m * np.sin(ang), np.zeros(n)])
    rot = Rotation.from_euler("z", (ang + np.pi / 2)[:, None])
    return Trajectory.from_rotations(t, pos, rot)


def perturbed(gt: Trajectory, position_m: float = 0.0, yaw_deg: float = 0.0, seed: int = 0) -> Trajectory:
    """``gt`` with white position noise (std per axis, metres) and a constant yaw error."""
    rng = np.random.default_rng(seed)
    pos = gt.positions + rng.normal(0, position_m, gt.positions.shape) if position_m else gt.positions.copy()
    rot = Rotation.from_euler("z", yaw_deg, degrees=True) * gt.rotations() if yaw_deg else gt.rotations()
    return Trajectory.from_rotations(gt.stamps.copy(), pos, rot)


def openloris_text(sequences: dict[int, Trajectory], scene: str = "cafe", frame: str = "base_link") -> str:
    """A small file in OpenLORIS format (``scene:``, ``frame:``, ``seq: N`` blocks)."""
    lines = [f"scene: {scene}", f"frame: {frame}"]
    for s, t in sorted(sequences.items()):
        lines.append(f"seq: {s}")
        lines += [" ".join(f"{v:.9f}" for v in row) for row in np.column_stack([t.stamps, t.positions, t.quaternions])]
    return "\n".join(lines) + "\n"


def openloris_fixture(tmp_path: Path) -> tuple[Path, Path]:
    """A ground truth (two sequences of a circle) and an estimate file in OpenLORIS format, written
    to ``tmp_path``: (ground-truth path, estimate path). The estimate of seq 1 has 0.05 m noise,
    seq 2 a 40-degree yaw error from its 100th pose on."""
    gt1, gt2 = circle(), circle(t0=2000.0)
    est2 = perturbed(gt2)
    rot = est2.rotations()
    wrong = Rotation.from_euler("z", 40, degrees=True)
    q = np.vstack([rot[:100].as_quat(), (wrong * rot[100:]).as_quat()])
    est2 = Trajectory(est2.stamps, est2.positions, q)
    gt = write(tmp_path, "gt_cafe_1.txt", openloris_text({1: gt1, 2: gt2}))
    est = write(tmp_path, "synthetic/cafe.txt", openloris_text({1: perturbed(gt1, 0.05), 2: est2}))
    return gt, est


def write_bag(path: Path, traj, ros: int, msgtype: str = "geometry_msgs/msg/PoseStamped", topic: str = "/pose",
              tf: tuple[str, str, str] | None = None, covariances=None) -> Path:  # fmt: skip
    """Write ``traj`` to a ROS 1 bag (``ros=1``, a .bag file) or a ROS 2 bag (``ros=2``, a folder) as
    ``msgtype`` messages on ``topic``; with ``tf=(parent, middle, child)`` also as TF: a static
    ``parent -> middle`` offset (1 m along x) and ``middle -> child`` moving so that the chain
    ``parent -> child`` equals the trajectory. ``covariances``: (N, 36) pose covariances of a
    ``PoseWithCovarianceStamped`` or ``Odometry`` topic (default zeros)."""
    import numpy as np
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC if ros == 1 else Stores.ROS2_HUMBLE)
    T = ts.types
    Time, Header = T["builtin_interfaces/msg/Time"], T["std_msgs/msg/Header"]
    Point, Quat, Pose = T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Quaternion"], T["geometry_msgs/msg/Pose"]
    Vec, Tr = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Transform"]

    def header(t, frame="world"):
        sec = int(np.floor(t))
        return Header(seq=0, stamp=Time(sec=sec, nanosec=int(round((t - sec) * 1e9))), frame_id=frame) if ros == 1 else \
            Header(stamp=Time(sec=sec, nanosec=int(round((t - sec) * 1e9))), frame_id=frame)  # fmt: skip

    def pose(p, q):
        return Pose(position=Point(x=p[0], y=p[1], z=p[2]), orientation=Quat(x=q[0], y=q[1], z=q[2], w=q[3]))

    def msg(t, p, q, i):
        if msgtype.endswith("PoseStamped") and "Covariance" not in msgtype:
            return T[msgtype](header=header(t), pose=pose(p, q))
        c = np.zeros(36) if covariances is None else np.asarray(covariances[i], float)
        cov = T["geometry_msgs/msg/PoseWithCovariance"](pose=pose(p, q), covariance=c)
        if msgtype.endswith("PoseWithCovarianceStamped"):
            return T[msgtype](header=header(t), pose=cov)
        twist = T["geometry_msgs/msg/TwistWithCovariance"](
            twist=T["geometry_msgs/msg/Twist"](linear=Vec(x=0.0, y=0.0, z=0.0), angular=Vec(x=0.0, y=0.0, z=0.0)),
            covariance=np.zeros(36),
        )
        return T[msgtype](header=header(t), child_frame_id="base", pose=cov, twist=twist)

    def ser(m, kind):
        return ts.serialize_ros1(m, kind) if ros == 1 else ts.serialize_cdr(m, kind)

    if ros == 1:
        from rosbags.rosbag1 import Writer

        writer = Writer(path)
    else:
        from rosbags.rosbag2 import Writer

        writer = Writer(path, version=8)
    with writer:
        conn = writer.add_connection(topic, msgtype, typestore=ts)
        tf_conn = static_conn = None
        if tf is not None:
            kind = "tf2_msgs/msg/TFMessage"
            if kind not in T:
                from rosbags.typesys import get_types_from_msg

                ts.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"))
                T = ts.types
            tf_conn = writer.add_connection("/tf", kind, typestore=ts)
            static_conn = writer.add_connection("/tf_static", kind, typestore=ts)
            TS = T["geometry_msgs/msg/TransformStamped"]
            parent, middle, child = tf
            t0 = float(traj.stamps[0])
            static = TS(header=header(t0, parent), child_frame_id=middle,
                        transform=Tr(translation=Vec(x=1.0, y=0.0, z=0.0), rotation=Quat(x=0.0, y=0.0, z=0.0, w=1.0)))  # fmt: skip
            writer.write(static_conn, int(t0 * 1e9), ser(T[kind](transforms=[static]), kind))
        for i, (t, p, q) in enumerate(zip(traj.stamps, traj.positions, traj.quaternions, strict=True)):
            ns = int(round(t * 1e9))
            writer.write(conn, ns, ser(msg(float(t), p, q, i), msgtype))
            if tf is not None:
                moved = Tr(translation=Vec(x=p[0] - 1.0, y=p[1], z=p[2]), rotation=Quat(x=q[0], y=q[1], z=q[2], w=q[3]))
                m = TS(header=header(float(t), tf[1]), child_frame_id=tf[2], transform=moved)
                writer.write(tf_conn, ns, ser(T[kind](transforms=[m]), kind))
    return path


def widget_controls(box) -> dict:
    """The controls (sliders, dropdowns) below an ipywidgets box, by description."""
    found, stack = [], [box]
    while stack:
        w = stack.pop()
        if hasattr(w, "children"):
            stack.extend(w.children)
        elif hasattr(w, "value") and hasattr(w, "description"):
            found.append(w)
    return {w.description: w for w in found}


#: The routes of a plain file (:func:`use_parser`).
PARSERS = ["numpy", "pandas", "blocks", "pieces", "read_csv", "chunks"]


def use_parser(monkeypatch, parser: str) -> list:
    """Read plain files by ``parser``: numpy's reader (a small file while pandas is not imported),
    the piece parser in one piece (``pandas``; ``blocks``: that piece parsed by pyarrow in blocks of
    about 4 KB on its threads, as a process not started by ``multiprocessing`` does, in blocks of
    its size over the cores), pyarrow's CSV reader on pieces of about 4 KB on 3 threads
    (``pieces``), the same pieces each read by pandas' ``read_csv`` (``read_csv``: a machine
    without pyarrow), or the chunked reader (``chunks``). Returns the list of what the piece reads
    returned (None: not plain after all; ``blocks``: the count of blocks of each threaded parse)."""
    from lorisnb.io.parsing import pieces, whole

    read = []
    monkeypatch.setattr(pieces, "arrow_threads", lambda: parser == "blocks")
    if parser == "blocks":  # ``read``: how many blocks each threaded parse gave
        monkeypatch.setattr(pieces, "arrow_block_bytes", lambda size: 4096)
        batches = pieces.piece_batches

        def spy(*a, **k):
            got = batches(*a, **k)
            if k.get("threads") and got is not None:
                read.append(len(got))
            return got

        monkeypatch.setattr(pieces, "piece_batches", spy)
        monkeypatch.setattr("lorisnb.io.parsing.chunks.piece_batches", spy)
    monkeypatch.setattr(whole, "pandas_loaded", lambda: parser != "numpy")
    if parser == "numpy":  # numpy's reader is for a machine without pyarrow
        monkeypatch.setattr(whole, "pyarrow_installed", lambda: False)
    if parser in ("pieces", "read_csv"):
        monkeypatch.setattr(pieces, "PIECE_BYTES", 4096)
        monkeypatch.setattr(pieces, "PARSE_THREADS", 3)
        real = pieces.piece_rows
        monkeypatch.setattr(whole, "piece_rows", lambda *a: read.append(real(*a)) or read[-1])
    else:
        monkeypatch.setattr(pieces, "PIECE_BYTES", whole.WHOLE_MAX_BYTES + 1)
        monkeypatch.setattr(pieces, "SPLIT_MIN_BYTES", whole.WHOLE_MAX_BYTES + 1)
    if parser == "read_csv":
        monkeypatch.setattr(pieces, "pyarrow_installed", lambda: False)
    if parser == "chunks":
        monkeypatch.setattr(whole, "WHOLE_MAX_BYTES", 0)
    return read


def as_trials(table_csv, out_csv=None, spread: float = 0.005) -> None:
    """A per-sequence table as three trials a sequence whose mean is the table's own value (CR-like
    columns -spread, 0, +spread within [0, 1]; errors x (1 - spread), 1, (1 + spread)): the same
    numbers with a rerun spread, so that diff judges them by its test, not by its single-run band."""
    import pandas as pd

    t = pd.read_csv(table_csv)
    parts = []
    for k, step in enumerate((-1.0, 0.0, 1.0), start=1):
        x = t.assign(trial=k)
        for c in ("cr", "cr_t", "cs_r"):
            if c in x.columns:
                x[c] = (x[c] + step * spread).clip(0, 1)
        for c in ("ate_rmse", "aoe_rmse", "c_ate_rmse", "c_aoe_rmse", "rpe_trans_rmse", "rpe_rot_rmse"):
            if c in x.columns:
                x[c] = x[c] * (1 + step * spread)
        parts.append(x)
    pd.concat(parts, ignore_index=True).to_csv(out_csv or table_csv, index=False)


def synthetic_covariances(stamps) -> tuple:
    """Pose covariances for a real trajectory that has none (plain numpy, deterministic): orientation
    (N, 3, 3) rad^2 about 0.8 deg and position (N, 3, 3) m^2 about 1 cm per axis, correlated between
    axes, each growing by 5 % a second and turning with time."""
    import numpy as np

    t = np.asarray(stamps, float) - float(stamps[0])

    def cov(scale: float, rate: float):
        a = np.stack([np.sin(rate * t + j) for j in range(9)], 1).reshape(-1, 3, 3) * 0.5 + np.eye(3)
        return scale**2 * (1 + 0.05 * t)[:, None, None] * (a @ a.transpose(0, 2, 1))

    return cov(np.radians(0.8), 0.7), cov(0.01, 1.3)


def write_ov_eval_file(path: Path, traj, orientation, position) -> Path:
    """``traj`` with its covariances in ov_eval's text layout (``stamp tx ty tz qx qy qz qw``, then the
    upper triangles of the orientation and position blocks), every number as repr (round-trips)."""
    iu = ([0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2])
    lines = ["# timestamp(s) tx ty tz qx qy qz qw Pr11 Pr12 Pr13 Pr22 Pr23 Pr33 Pt11 Pt12 Pt13 Pt22 Pt23 Pt33"]
    for i in range(len(traj.stamps)):
        vals = [traj.stamps[i], *traj.positions[i], *traj.quaternions[i], *orientation[i][iu], *position[i][iu]]
        lines.append(" ".join(repr(float(v)) for v in vals))
    path.write_text("\n".join(lines) + "\n")
    return path


def temp_litter_patterns() -> tuple[str, ...]:
    """What running notebooks can leave in the temporary folder: a kernel's ipc sockets made outside a
    report's kernel folder (``lorisnb.tools.report.notebooks.kernel_files``) and a notebook's output
    folder, made where it runs outside a checkout with no ``output_dir`` (``default_output_dir``)."""
    from lorisnb.tools.report.build import DEFAULT_NOTEBOOKS

    return ("lorisnb-kernel-*", *(f"lorisnb-{name}-*" for name in DEFAULT_NOTEBOOKS))


def _listened_on(path: Path) -> bool:
    """A socket that some process still listens on: a kernel running now (a test's beside this one,
    under pytest-xdist), not one left behind (a connection to that is refused)."""
    try:
        if not stat.S_ISSOCK(path.lstat().st_mode):
            return False
    except OSError:
        return False
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.settimeout(2)
        try:
            s.connect(str(path))
        except OSError:
            return False
    return True


@contextlib.contextmanager
def temp_dir_left_as_found(settle_s: float = 5.0) -> Iterator[None]:
    """Fails when what runs inside leaves in the temporary folder (``tempfile.gettempdir()``) an entry
    of :func:`temp_litter_patterns` that was not there before. Beside other test processes
    (pytest-xdist) an entry is left only if it is still there ``settle_s`` later and no process
    listens on it: another test's running kernel's sockets, or those its manager is removing, are not."""
    tmp = Path(tempfile.gettempdir())
    patterns = temp_litter_patterns()

    def left(before: set[Path]) -> set[Path]:
        return {p for pattern in patterns for p in tmp.glob(pattern)} - before

    before = left(set())
    yield
    stale = {p for p in left(before) if not _listened_on(p)}
    if stale:
        time.sleep(settle_s)
        stale = {p for p in stale & left(before) if not _listened_on(p)}
    assert not stale, f"left in {tmp}: " + ", ".join(sorted(p.name for p in stale))


def rerun_trials(table, trials, seed: int):
    """Trials of the run ``table`` (a sequences table) with the spread of real reruns (CR +-0.017,
    ATE +-19 %), seeded: one copy of the table per trial number of ``trials``."""
    import pandas as pd

    rng = np.random.default_rng(seed)
    parts = []
    for k in trials:
        t = table.assign(trial=k)
        t["cr"] = np.clip(t["cr"] + rng.normal(0, 0.017, len(t)), 0, 1)
        t["ate_rmse"] = t["ate_rmse"] * np.exp(rng.normal(0, 0.19, len(t)))
        parts.append(t)
    return pd.concat(parts, ignore_index=True)


def longest_tracked(table, algorithm: str) -> tuple[str, int]:
    """(scene, seq) of ``algorithm``'s longest sequence in ``table`` tracked correctly most of the
    time (CR above 0.6)."""
    g = table[(table["algorithm"] == algorithm) & (table["cr"] > 0.6)].sort_values("gt_duration", ascending=False)
    return str(g["scene"].iloc[0]), int(g["seq"].iloc[0])


def run_cli(capsys, *args, joined: bool = False) -> tuple[int, str, str]:
    """``lorisnb ARGS`` in this process (:func:`lorisnb.cli.main`, each argument ``str()``-ed): its
    exit status, stdout and stderr; ``joined``: stderr with its lines and runs of spaces joined (a
    message the terminal's width wrapped reads as one line)."""
    from lorisnb.cli import main

    rc = main([*map(str, args)])
    out = capsys.readouterr()
    return rc, out.out, " ".join(out.err.split()) if joined else out.err


def table_nights(folder: Path, *tables) -> list[Path]:
    """Tables ``1.csv``, ``2.csv``... in ``folder`` (lorisnb's CSV writer), each made 1000 s after the
    one before: a history's nights."""
    from lorisnb.io.writers import write_csv

    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for k, t in enumerate(tables, 1):
        f = folder / f"{k}.csv"
        write_csv(t, f)
        os.utime(f, (1.7e9 + 1000 * k, 1.7e9 + 1000 * k))
        paths.append(f)
    return paths
