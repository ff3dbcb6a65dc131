"""Trajectories from ROS 1 and ROS 2 bags (through the ``rosbags`` package, which evo uses too):
a ``geometry_msgs/PoseStamped``, ``PoseWithCovarianceStamped``, ``TransformStamped``,
``PointStamped`` (positions only: the identity orientation, as evo) or ``nav_msgs/Odometry`` topic, or a TF chain ``parent:child`` (evo's ``/tf:parent.child``) from ``/tf``
and ``/tf_static``; several of one bag at once with :func:`read_bag_topics`.

Stamps are the messages' header stamps (seconds); quaternions ``xyzw``. Messages are checked as
the text readers check lines (a message's number on its topic stands for the line): repeated or
decreasing stamps are sorted with a warning, NaN poses skipped with a warning, and a topic whose
header stamps are all zero (headers never set) is refused. A TF chain may pass
through several frames: its poses are taken at the stamps of its busiest moving link, the other
moving links interpolated there (linear positions, slerp), the static ones applied as they are.
"""

from __future__ import annotations

import os
import warnings
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

from lorisnb.core.alignment.geometry import quat_multiply, quat_rotate, slerp
from lorisnb.core.spec.validate import choice
from lorisnb.core.trajectory.poses import Trajectory
from lorisnb.errors import LorisWarning, MissingDependencyError, ParseError
from lorisnb.io.parsing.scanner import REPEATED, check_rows, finish
from lorisnb.io.readers.options import check_reading

POSE_TYPES = {
    "geometry_msgs/msg/PoseStamped": lambda m: m.pose,
    "geometry_msgs/msg/PoseWithCovarianceStamped": lambda m: m.pose.pose,
    "nav_msgs/msg/Odometry": lambda m: m.pose.pose,
    "geometry_msgs/msg/TransformStamped": lambda m: m.transform,
    "geometry_msgs/msg/PointStamped": lambda m: m.point,  # no orientation: the identity, as evo reads it
}
TF_TOPICS = ("/tf", "/tf_static")
#: The message types that carry a pose covariance (read by :func:`covariance_messages`).
COVARIANCE_TYPES = ("geometry_msgs/msg/PoseWithCovarianceStamped", "nav_msgs/msg/Odometry")


def _reader(path: Path):
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise MissingDependencyError("reading ROS bags needs rosbags: pip install 'lorisnb[bags]'") from None
    return AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))


def _stamp(msg: Any) -> float:
    st = msg.header.stamp
    return st.sec + st.nanosec * 1e-9


def _pose(p: Any) -> list[float]:
    if hasattr(p, "x"):  # a Point: no orientation (only position errors mean something)
        return [p.x, p.y, p.z, 0.0, 0.0, 0.0, 1.0]
    t = p.position if hasattr(p, "position") else p.translation  # a Pose or a Transform
    q = p.orientation if hasattr(p, "orientation") else p.rotation
    return [t.x, t.y, t.z, q.x, q.y, q.z, q.w]


def _open(path: str | os.PathLike):
    """An open rosbags reader of a ROS 1 bag, a ROS 2 bag folder, or a lone ``.db3`` / ``.mcap``
    file (read with its folder when the folder has the bag's ``metadata.yaml``)."""
    spath = str(path)
    p = Path(path)
    if p.suffix in (".db3", ".mcap") and p.is_file() and (p.parent / "metadata.yaml").is_file():
        p = p.parent  # a file of a ROS 2 bag folder: the whole bag (a misspelt file is not found)
    if not p.exists():
        raise ParseError(
            spath, None, "file not found; expected a ROS 1 bag (.bag), a ROS 2 bag folder or a .db3 / .mcap file"
        )
    try:
        reader = _reader(p)
        reader.open()
    except MissingDependencyError:
        raise
    except Exception as exc:  # noqa: BLE001 (rosbags raises its own types for non-bags)
        raise ParseError(
            spath, None, f"not a readable ROS bag ({exc}); expected a ROS 1 .bag, a ROS 2 bag folder or .db3/.mcap"
        ) from None
    return reader


def message_types(path: str | os.PathLike) -> dict[str, str]:
    """Each topic of a bag with its message type (``geometry_msgs/msg/PoseStamped``, ...)."""
    reader = _open(path)
    try:
        return {c.topic: c.msgtype for c in reader.connections}
    finally:
        reader.close()


def covariance_messages(path: str | os.PathLike, topic: str | None = None) -> tuple[str, np.ndarray, np.ndarray]:
    """The messages of a bag's ``topic`` of :data:`COVARIANCE_TYPES` (None: its only such topic), as
    read: where they are (the bag and the topic, for messages), their header stamps (N,) and rows
    (N, 43): position, quaternion ``xyzw`` and the 36 numbers of ``pose.covariance``. ParseError names
    the bag's topics with covariances when the choice is missing or wrong, and refuses header stamps
    never set. :func:`lorisnb.io.readers.covariance.read_covariance_bag` checks and sorts them."""
    spath = str(path)
    reader = _open(path)
    try:
        have = {c.topic: c.msgtype for c in reader.connections if c.msgtype in COVARIANCE_TYPES}
        listing = ", ".join(f"{t} ({m.split('/')[-1]})" for t, m in sorted(have.items())) or "none"
        if topic is None:
            if len(have) != 1:
                raise ParseError(spath, None, f"choose a topic with covariances (--topic); such topics in this bag: "
                                              f"{listing}")  # fmt: skip
            topic = next(iter(have))
        if topic not in have:
            kinds = sorted({c.msgtype for c in reader.connections if c.topic == topic})
            held = f"holds {', '.join(kinds)} messages" if kinds else "is not in this bag"
            raise ParseError(spath, None, f"topic {topic!r} {held}; expected PoseWithCovarianceStamped or Odometry "
                                          f"(a pose with its covariance); such topics in this bag: {listing}")  # fmt: skip
        conns = [c for c in reader.connections if c.topic == topic]
        stamps, rows = [], []
        for conn, _, raw in reader.messages(connections=conns):  # rosbags deserializes one message at a time
            msg = reader.deserialize(raw, conn.msgtype)
            rows.append([*_pose(msg.pose.pose), *np.asarray(msg.pose.covariance, float)])
            stamps.append(_stamp(msg))
    finally:
        reader.close()
    if not stamps:
        raise ParseError(spath, None, f"topic {topic!r} holds no message")
    t = np.array(stamps, float)
    _unset_stamps(spath, topic, t)
    return f"{spath} {topic}", t, np.array(rows, float).reshape(-1, 43)


def tf_chain(text: str) -> str | None:
    """lorisnb's ``parent:child`` spelling of evo's TF trajectory id ``/tf:parent.child`` (with an
    optional ``:/tf_static`` suffix); None if ``text`` is not one."""
    topic, sep, rest = text.partition(":")
    if not sep or topic not in TF_TOPICS[:1] or "." not in rest:
        return None
    frames = rest.rpartition(":")[0] if ":" in rest else rest
    parent, _, child = frames.partition(".")
    return f"{parent}:{child}" if parent and child else None


def read_bag(
    path: str | os.PathLike, topic: str | None = None, tf: str | None = None, repeated: str = "drop"
) -> Trajectory:
    """Read a trajectory from a ROS 1 bag (``.bag``) or a ROS 2 bag (its folder, or a lone ``.db3``
    or ``.mcap`` file): the poses of ``topic``, or the transform chain ``tf="parent:child"`` (evo's
    ``/tf:parent.child`` is accepted as ``topic`` or ``tf``). Without either, the bag's only pose
    topic. ParseError names what the bag holds when the choice is missing or wrong. ``repeated``:
    poses of a repeated stamp, as :func:`lorisnb.io.readers.plain.read_tum`. ``topic`` and ``tf`` together
    are refused (ValidationError)."""
    check_reading({"topic": topic, "tf": tf})
    reader = _open(path)
    try:
        return _read_one(reader, str(path), topic, tf, repeated)
    finally:
        reader.close()


def read_bag_topics(
    path: str | os.PathLike, topics: list[str] | None = None, repeated: str = "drop"
) -> dict[str, Trajectory]:
    """Several trajectories of one bag in one pass over its index: ``{topic: Trajectory}`` for each
    of ``topics`` (pose topics, or TF chains as evo's ``/tf:parent.child``; None: every pose topic
    of the bag). Each trajectory's ``meta`` says its topic or chain."""
    reader = _open(path)
    try:
        names = sorted(_pose_topics(reader)) if topics is None else list(topics)
        if not names:
            raise ParseError(str(path), None, "no pose topic in this bag; name TF chains as /tf:parent.child")
        return {name: _read_one(reader, str(path), name, None, repeated) for name in names}  # a few topics
    finally:
        reader.close()


def _read_one(reader, spath: str, topic: str | None, tf: str | None, repeated: str) -> Trajectory:
    if tf is not None:
        return _read_tf(reader, spath, tf_chain(tf) or tf, repeated)
    if topic is not None and tf_chain(topic) is not None:
        return _read_tf(reader, spath, str(tf_chain(topic)), repeated)
    return _read_topic(reader, spath, topic, repeated)


def _pose_topics(reader) -> dict[str, str]:
    return {c.topic: c.msgtype for c in reader.connections if c.msgtype in POSE_TYPES}


#: How to choose, on either side of a pair (the ground truth's options are --gt-topic, --gt-tf).
CHOOSE = "--topic or --tf parent:child; --gt-topic or --gt-tf for the ground truth"
#: How the messages name the TF option where a bag's choice is wrong (:func:`manifest_terms` renames it).
TF_OPTION = "--tf parent:child"


def manifest_terms(reason: str, topic_key: str, tf_key: str, manifest: str) -> str:
    """A bag reader's message (``reason``) said on a manifest's route: the command-line options it
    names (:data:`CHOOSE`, ``--tf``), which a manifest's sessions do not take, replaced by the
    manifest's keys (``estimate_topic`` and ``estimate_tf``, or ``groundtruth_topic`` and
    ``groundtruth_tf``) in ``manifest``, the file to write them in."""
    tf = f"{tf_key} = 'parent:child' in {manifest}"
    return (
        reason.replace(CHOOSE, f"{topic_key} = '/topic' or {tf}")
        .replace(TF_OPTION, tf)
        .replace("(TF: use --tf)", f"(TF: use {tf})")
        .replace("--tf '", f"{tf_key} = '")
    )


def _listing(reader, topics: dict[str, str]) -> str:
    """The bag's pose topics; when it has none, every topic with its type (and the TF hint)."""
    if topics:
        return "pose topics in this bag: " + ", ".join(f"{t} ({m.split('/')[-1]})" for t, m in sorted(topics.items()))
    every = sorted({(c.topic, c.msgtype) for c in reader.connections})
    tf = f" (read a TF chain with {TF_OPTION})" if any(t in TF_TOPICS for t, _ in every) else ""
    return "no pose topic in this bag; its topics: " + (", ".join(f"{t} ({m})" for t, m in every) or "none") + tf


def _read_topic(reader, spath: str, topic: str | None, repeated: str = "drop") -> Trajectory:
    topics = _pose_topics(reader)
    listing = _listing(reader, topics)
    if topic is None:
        if len(topics) != 1:
            raise ParseError(spath, None, f"choose a pose topic or a TF chain ({CHOOSE}); {listing}")
        topic = next(iter(topics))
    if topic not in topics:
        kinds = sorted({c.msgtype for c in reader.connections if c.topic == topic})
        if not kinds:
            raise ParseError(spath, None, f"no pose topic {topic!r}; {listing}")
        expected = ", ".join(m.split("/")[-1] for m in POSE_TYPES)
        what = f"; expected {expected}" if topic not in TF_TOPICS else "" if "--tf" in listing else " (TF: use --tf)"
        raise ParseError(spath, None, f"topic {topic!r} holds {', '.join(kinds)} messages, not poses{what}; {listing}")
    conns = [c for c in reader.connections if c.topic == topic]
    get = POSE_TYPES[topics[topic]]
    stamps, poses = [], []
    for conn, _, raw in reader.messages(connections=conns):  # rosbags deserializes one message at a time
        msg = reader.deserialize(raw, conn.msgtype)
        stamps.append(_stamp(msg))
        poses.append(_pose(get(msg)))
    if not stamps:
        raise ParseError(spath, None, f"topic {topic!r} holds no message")
    notes: list[str] = []
    where = f"{spath} {topic}"
    t = np.array(stamps, float)
    _unset_stamps(spath, topic, t)
    line_no = np.arange(1, len(stamps) + 1)  # message number on the topic
    pose = np.array(poses, float).reshape(-1, 7)
    try:  # a message's number stands for the line of a text file
        keep = check_rows(where, t, pose[:, :3], pose[:, 3:], line_no, notes)
    except ParseError as exc:
        raise ParseError(where if exc.line is None else f"{where}, message {exc.line}", None, exc.reason) from None
    if not keep.all():
        t, pose, line_no = t[keep], pose[keep], line_no[keep]
    traj = finish(where, t, pose[:, :3], pose[:, 3:], line_no, "", notes, repeated)
    if topics[topic] == "geometry_msgs/msg/PointStamped":  # positions only: AOE would look like a measurement
        notes.append(f"{topic} holds PointStamped messages (positions, no orientation): read with the identity "
                     "orientation, as evo reads them; AOE and anything with phi measure nothing (use --phi inf and "
                     "ATE only)")  # fmt: skip
        traj.meta["positions_only"] = True
    traj.meta.update(source=spath, topic=topic, notes=notes)
    for note in notes:
        warnings.warn(note.replace(" at line ", " at message "), LorisWarning, stacklevel=4)
    return traj


def _unset_stamps(spath: str, topic: str, stamps: np.ndarray) -> None:
    """ParseError if every one of several messages has header stamp 0: headers never set, so the
    poses have no time to be matched at."""
    if stamps.size > 1 and not stamps.any():
        raise ParseError(
            spath,
            None,
            f"all {stamps.size} messages of {topic} have header stamp 0 (the header was never set); lorisnb "
            "pairs poses by their header stamps: record with header.stamp set, or rewrite the stamps (for "
            "example from the bag's receive times, with rosbags) before evaluating",
        )


def _read_tf(reader, spath: str, chain: str, repeated: str = "drop") -> Trajectory:
    """The poses of ``child`` in ``parent`` along a TF chain: one a transform of its moving link
    with the most transforms (the base link), the other links interpolated at its stamps. Of a
    stamp the base link repeats, as a pose topic's (:func:`lorisnb.io.parsing.scanner.finish`):
    the last transform received (``repeated="drop"``) or every one, in the order received
    (``"keep"``, evo's)."""
    keep_all = choice("repeated", repeated, REPEATED) == "keep"
    parent, sep, child = chain.partition(":")
    if not sep or not parent or not child:
        raise ParseError(spath, None, f"--tf {chain!r}: expected 'parent:child' frame names")
    edges: dict[tuple[str, str], list[tuple[float, list[float]]]] = defaultdict(list)
    static: set[tuple[str, str]] = set()
    conns = [c for c in reader.connections if c.topic in TF_TOPICS]
    for conn, _, raw in reader.messages(connections=conns) if conns else ():  # (no connections: all topics)
        msg = reader.deserialize(raw, conn.msgtype)
        for t in msg.transforms:
            key = (t.header.frame_id.strip("/"), t.child_frame_id.strip("/"))
            edges[key].append((_stamp(t), _pose(t.transform)))
            if conn.topic == "/tf_static":
                static.add(key)
    path = _chain(edges, parent.strip("/"), child.strip("/"))
    if path is None:
        frames = sorted({f for e in edges for f in e})
        raise ParseError(
            spath,
            None,
            f"no TF chain from {parent!r} to {child!r}; frames in /tf and /tf_static: {', '.join(frames) or 'none'}",
        )
    moving = [e for e, _ in path if e not in static]
    if not moving:
        raise ParseError(spath, None, f"the TF chain {parent}->{child} is static; expected a moving frame")
    base = max(moving, key=lambda e: len(edges[e]))
    raw_stamps = np.array([s for s, _ in edges[base]])
    _unset_stamps(spath, f"the TF link {base[0]}->{base[1]}", raw_stamps)
    order = np.argsort(raw_stamps, kind="stable")
    if not keep_all:
        order = order[np.append(raw_stamps[order][1:] != raw_stamps[order][:-1], True)]  # each stamp's last
    stamps = raw_stamps[order]
    repeats = raw_stamps.size - np.unique(raw_stamps).size
    if repeats:
        rule = (
            "kept every transform of a repeated stamp in the order received (repeated='keep'), as a pose topic's"
            if keep_all
            else "kept the last pose of each stamp, as a pose topic's"
        )
        warnings.warn(
            f"{spath} TF link {base[0]}->{base[1]}: {repeats} of {raw_stamps.size} transforms repeat a stamp; {rule}",
            LorisWarning,
            stacklevel=4,
        )
    back = int((np.diff(raw_stamps) < 0).sum())
    if back:  # sorted, as a pose topic's stamps are, and said as they are
        warnings.warn(
            f"{spath} TF link {base[0]}->{base[1]}: stamps are not increasing ({back} times); sorted them",
            LorisWarning,
            stacklevel=4,
        )
    pos = np.zeros((stamps.size, 3))
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (stamps.size, 1))
    keep = np.ones(stamps.size, bool)
    outside: list[str] = []  # the links that left some of the base link's stamps without a transform
    for edge, forward in path:  # a few links
        if edge == base:  # the base link's own transforms, each at its stamp (none interpolated)
            v = np.array([edges[base][k][1] for k in order], float).reshape(-1, 7)
            p, q = v[:, :3], v[:, 3:] / np.linalg.norm(v[:, 3:], axis=1, keepdims=True)
        else:
            _, p, q, inside = _link_at(edges[edge], stamps, edge in static)
            if not inside.all():
                span = [s for s, _ in edges[edge]]
                outside.append(f"{edge[0]}->{edge[1]} ({int((~inside).sum()):,} poses; its transforms span "
                               f"{min(span):.3f}..{max(span):.3f} s)")  # fmt: skip
            keep &= inside
        if not forward:  # the inverse transform
            q = q * np.array([-1.0, -1.0, -1.0, 1.0])
            p = -quat_rotate(q, p)
        pos = pos + quat_rotate(quat, p)
        quat = quat_multiply(quat, q)
    where = f"{spath} TF {parent}:{child}"
    notes: list[str] = []
    if outside:  # not extrapolated (tf2 and evo refuse to): said, as a reader says the poses it skips
        said = (
            f"{where}: {int((~keep).sum()):,} of {stamps.size:,} poses of the chain dropped: no transform of "
            f"{'the link' if len(outside) == 1 else 'the links'} {' and '.join(outside)} brackets their time (the "
            f"chain's stamps are its link {base[0]}->{base[1]}'s, {stamps[0]:.3f}..{stamps[-1]:.3f} s); a link is "
            "interpolated between its transforms, never extrapolated, as tf2 and evo read it: record that link over "
            "the whole run to keep them"
        )
        if not keep.any():
            raise ParseError(spath, None, said.replace(f"{where}: ", f"TF {parent}:{child}: ", 1))
        notes.append(said)
    stamps, pos, quat = stamps[keep], pos[keep], quat[keep]
    line_no = np.arange(1, stamps.size + 1)  # the pose's number in the chain stands for the line
    fine = check_rows(where, stamps, pos, quat, line_no, notes)  # sorted above, repeats kept or not as asked
    traj = finish(where, stamps[fine], pos[fine], quat[fine], line_no[fine], "", notes, repeated)
    traj.meta.update(source=spath, tf=f"{parent}:{child}")
    for note in notes:
        warnings.warn(note.replace(" at line ", " at pose "), LorisWarning, stacklevel=4)
    return traj


def _chain(edges: dict, parent: str, child: str) -> list[tuple[tuple[str, str], bool]] | None:
    """The links from ``parent`` to ``child`` (breadth first), each with its direction."""
    nbr: dict[str, list[tuple[str, tuple[str, str], bool]]] = defaultdict(list)
    for a, b in edges:
        nbr[a].append((b, (a, b), True))
        nbr[b].append((a, (a, b), False))
    seen: dict[str, list[tuple[tuple[str, str], bool]]] = {parent: []}
    todo = [parent]
    while todo:  # frames, not poses
        f = todo.pop(0)
        if f == child:
            return seen[f]
        for g, edge, fwd in nbr[f]:
            if g not in seen:
                seen[g] = seen[f] + [(edge, fwd)]
                todo.append(g)
    return None


def _link_at(samples: list, stamps: np.ndarray, is_static: bool):
    """A link's transform at ``stamps``: the last one if static, else interpolated inside its span
    (of transforms of one stamp, the last received: the same pose at every stamp, the span's last
    too)."""
    t = np.array([s for s, _ in samples])
    v = np.array([p for _, p in samples], float)
    order = np.argsort(t, kind="stable")
    t, v = t[order], v[order]
    last = np.append(t[1:] != t[:-1], True)  # of a repeated stamp the last transform (in the order received)
    t, v = t[last], v[last]
    v[:, 3:] /= np.linalg.norm(v[:, 3:], axis=1, keepdims=True)
    if is_static or len(t) == 1:
        return (
            stamps,
            np.broadcast_to(v[-1, :3], (stamps.size, 3)),
            np.broadcast_to(v[-1, 3:], (stamps.size, 4)),
            np.ones(stamps.size, bool),
        )
    inside = (stamps >= t[0]) & (stamps <= t[-1])
    i = np.clip(np.searchsorted(t, stamps, side="right") - 1, 0, len(t) - 2)
    w = np.clip((stamps - t[i]) / np.where(t[i + 1] > t[i], t[i + 1] - t[i], 1.0), 0.0, 1.0)
    p = v[i, :3] * (1 - w)[:, None] + v[i + 1, :3] * w[:, None]
    q = slerp(v[i, 3:], v[i + 1, 3:], w)
    return stamps, p, q, inside
