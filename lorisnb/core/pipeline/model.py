"""The data model of an evaluation: a parsed result file, per-pose errors, and table schemas.

Plain dataclasses; readers (:mod:`lorisnb.io`) build :class:`ResultFile`, the pipeline
(:mod:`lorisnb.core.pipeline.sessions`) builds :class:`SequenceErrors` and :class:`FileErrors`, scoring
(:mod:`lorisnb.core.lifelong.scoring`) turns them into tables with the columns defined here.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from lorisnb.core.alignment.geometry import Sim3, rotation_lever, rotations_of
from lorisnb.core.metrics import openloris as metrics
from lorisnb.core.metrics.pairs import rpe_indices
from lorisnb.core.metrics.written import written_rpe
from lorisnb.core.spec.validate import label
from lorisnb.core.trajectory.frames import FRAMES, PAPER_EPS, SCENES, match_scene
from lorisnb.core.trajectory.poses import Trajectory, size
from lorisnb.errors import EvaluationError, ParseError, ValidationError

if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation

#: Columns of the per-sequence table (``lorisnb evaluate --csv``); scripts rely on these names.
SEQUENCE_COLUMNS = [
    "algorithm", "file", "scene", "seq", "frame", "poses", "matched", "ate_rmse", "aoe_rmse",
    "c_ate_rmse", "c_aoe_rmse", "correct_time", "cr", "cr_t", "reloc_time", "cs_r",
    "eps", "phi", "delta", "tau",
]  # fmt: skip
#: Further columns of the per-sequence table, after :data:`SEQUENCE_COLUMNS`.
EXTRA_COLUMNS = [
    "suite", "mode", "aligned_on", "scale", "c_matched", "gt_start", "gt_end", "gt_duration",
    "t0", "track_time", "first_correct", "rpe_trans_rmse", "rpe_rot_rmse", "c_rpe_trans_rmse",
    "c_rpe_rot_rmse", "rpe_pairs", "c_rpe_pairs", "official_interpolation", "trial", "rotation_lever",
]  # fmt: skip
#: Error statistics of the per-sequence table (:func:`lorisnb.core.lifelong.scoring.score`), after
#: :data:`EXTRA_COLUMNS`: evo's statistics (``rmse`` is in the columns above) of ATE (m), AOE (deg)
#: and RPE translation (m) and rotation (deg), and of the same over correct poses (pairs) only.
STAT_COLUMNS = [
    f"{c}{m}_{s}" for c in ("", "c_") for m in ("ate", "aoe", "rpe_trans", "rpe_rot")
    for s in ("mean", "median", "std", "min", "max", "sse")
]  # fmt: skip
#: Columns of the per-scene table (:func:`lorisnb.core.lifelong.aggregate.aggregate_scenes`).
SCENE_COLUMNS = [
    "suite", "algorithm", "scene", "eps", "phi", "delta", "tau", "sequences", "sequences_with_output", "scene_sequences", "matched",
    "c_matched", "correct_time", "track_time", "scene_duration", "cr", "cr_t", "c_ate_rmse",
    "c_ate_rmse_pooled", "ate_rmse", "cs_r", "cs_r_with_output",
]  # fmt: skip
#: Columns of the per-pose table (:func:`lorisnb.core.lifelong.scoring.pose_table`).
POSE_COLUMNS = ["algorithm", "file", "suite", "scene", "seq", "stamp", "t_rel", "ate", "aoe", "correct"]

#: Evaluation modes: per-seq aligns each sequence on itself, lifelong on the first sequence.
MODES = ("auto", "per-seq", "lifelong")

Eps = float | str | Mapping[str, float]


@dataclass(kw_only=True)
class ResultFile:
    """One OpenLORIS result or ground-truth file, parsed (built by :func:`lorisnb.io.read_openloris`).

    Attributes:
        path: the file.
        header: ``key: value`` lines, first occurrence of each key (as the official tool).
        header_lines: 1-based line number of each header key.
        sequences: sequence number -> Trajectory, in increasing sequence order; a sequence with
            no pose maps to an empty Trajectory.
        seq_info: sequence number -> the ``key: value`` lines inside that block (``aided_reloc``,
            ``reloc``, ...).
        seq_lines: sequence number -> line of its ``seq:`` line.
        removed_repeats: sequence number -> poses dropped as repeats of the previous pose.
        warnings: what was noticed while reading (also issued as LorisWarning).
    """

    path: Path
    header: dict[str, str]
    header_lines: dict[str, int]
    sequences: dict[int, Trajectory]
    seq_info: dict[int, dict[str, str]] = field(default_factory=dict)
    seq_lines: dict[int, int] = field(default_factory=dict)
    removed_repeats: dict[int, int] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)

    @property
    def scene(self) -> str:
        """The scene matched from the ``scene:`` header (ParseError if missing or unknown)."""
        if "scene" not in self.header:
            raise ParseError(
                self.path,
                1,
                "no 'scene: NAME' header line; expected one of "
                + ", ".join(SCENES)
                + " (add e.g. 'scene: cafe' at the top)",
            )
        scene = match_scene(self.header["scene"])
        if scene is None:
            raise ParseError(
                self.path,
                self.header_lines["scene"],
                f"unknown scene {self.header['scene']!r}; expected a name containing one of " + ", ".join(SCENES),
            )
        return scene

    @property
    def frame(self) -> str:
        """The ``frame:`` header (ParseError if missing or not a known sensor frame)."""
        if "frame" not in self.header:
            raise ParseError(self.path, 1, "no 'frame: NAME' header line; expected one of " + ", ".join(FRAMES))
        frame = self.header["frame"]
        if frame not in FRAMES:
            raise ParseError(
                self.path, self.header_lines["frame"], f"unknown frame {frame!r}; expected one of " + ", ".join(FRAMES)
            )
        return frame

    @property
    def n_poses(self) -> int:
        return sum(len(t) for t in self.sequences.values())

    def __repr__(self) -> str:
        head = ", ".join(f"{k} {self.header[k]}" for k in ("scene", "frame") if k in self.header)
        n = len(self.sequences)
        return (
            f"<ResultFile {self.path.name}: {head + ', ' if head else ''}{n} sequence{'' if n == 1 else 's'}, "
            f"{self.n_poses} poses{f', {len(self.warnings)} warning(s)' if self.warnings else ''}>"
        )


#: The name the first release used for :class:`ResultFile`.
OpenLorisFile = ResultFile


@dataclass(kw_only=True)
class SequenceErrors:
    """Threshold-free per-pose errors of one sequence.

    Attributes:
        seq: sequence number.
        poses: estimate poses after reading (NaN and repeated poses dropped).
        stamps: (M,) matched estimate stamps, seconds.
        ate: (M,) metres. aoe: (M,) degrees.
        est_positions, gt_positions: (M, 3) aligned estimate and interpolated ground truth, metres.
        est_quaternions, gt_quaternions: (M, 4) the matching orientations, unit quaternions ``xyzw``
            (None if M = 0); ``est_rotations`` and ``gt_rotations`` give them as scipy ``Rotation``.
        gt_start, gt_end: ground-truth time span of the sequence, seconds.
        scale: the scale of the alignment applied to this sequence (1 for SE(3)).
        est_blocks, gt_blocks: (M, 3, 3) the matched poses' rotation blocks as their files wrote
            them (the estimate's turned by the alignment's rotation), where the spec composes the
            matrices as written (``EvalSpec.as_written``) and both files are KITTI files; else None
            (the orientations are then the quaternions').
        read_poses: (M, 14) the matched poses as read: ground-truth position and quaternion, then the
            estimate's, quaternions not normalized and the estimate not aligned, where the spec computes
            its numbers from them (``EvalSpec.poses_as_read``: tartanair_tools'); else None.
    """

    seq: int
    poses: int
    stamps: np.ndarray
    ate: np.ndarray
    aoe: np.ndarray
    est_positions: np.ndarray
    gt_positions: np.ndarray
    est_quaternions: np.ndarray | None
    gt_quaternions: np.ndarray | None
    gt_start: float
    gt_end: float
    scale: float = 1.0
    est_blocks: np.ndarray | None = field(default=None, repr=False)
    gt_blocks: np.ndarray | None = field(default=None, repr=False)
    read_poses: np.ndarray | None = field(default=None, repr=False)
    # What is computed from the errors once and kept (not init fields: ``dataclasses.replace``
    # gives a new sequence of errors empty ones, never the old errors' RPE, lever or scores).
    _rpe_cache: dict[tuple[float, str, str, bool | None, float], tuple[np.ndarray, ...]] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )
    _lever: float | None = field(default=None, init=False, repr=False, compare=False)
    _scores: dict[tuple[Any, ...], dict[str, Any]] = field(default_factory=dict, init=False, repr=False, compare=False)
    _sizes: dict[str, float] = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # read-only: what is computed from them is kept (scores per setting, RPE, lever), so an array
        # edited in place gave old scores at a setting asked before and new ones at any other (give
        # new errors with ``dataclasses.replace``, which starts with nothing kept)
        for name in ("stamps", "ate", "aoe", "est_positions", "gt_positions", "est_quaternions", "gt_quaternions",
                     "est_blocks", "gt_blocks", "read_poses"):  # fmt: skip
            a = getattr(self, name)
            if isinstance(a, np.ndarray):
                a.flags.writeable = False

    @classmethod
    def unmatched(cls, seq: int, poses: int, gt_start: float, gt_end: float) -> SequenceErrors:
        """A sequence none of whose poses matched the ground truth in time."""
        z = np.zeros(0)
        return cls(
            seq=seq, poses=poses, stamps=z, ate=z, aoe=z, est_positions=np.zeros((0, 3)),
            gt_positions=np.zeros((0, 3)), est_quaternions=None, gt_quaternions=None, gt_start=gt_start, gt_end=gt_end,
        )  # fmt: skip

    @property
    def matched(self) -> int:
        return len(self.stamps)

    @property
    def rotation_lever(self) -> float:
        """How firmly the matched ground-truth positions hold an alignment's rotation, metres
        (:func:`lorisnb.core.alignment.geometry.rotation_lever`; NaN with nothing matched): 5 mm of
        position noise turns a fit on them by about 0.005 / lever radians. Computed once."""
        if self._lever is None:
            self._lever = rotation_lever(self.gt_positions)
        return self._lever

    def __repr__(self) -> str:
        errors = ""
        if self.matched:
            ate = float(np.sqrt(np.mean(np.square(self.ate))))
            aoe = float(np.sqrt(np.mean(np.square(self.aoe))))
            errors = f", ATE RMSE {ate:.4g} m, AOE RMSE {aoe:.4g} deg"
        scale = f", scale {self.scale:.4g}" if self.scale != 1.0 else ""
        return f"<SequenceErrors seq {self.seq}: {self.poses} poses, {self.matched} matched{errors}{scale}>"

    @property
    def est_rotations(self) -> Rotation | None:
        """:attr:`est_quaternions` as a scipy ``Rotation`` (built on request)."""
        return rotations_of(self.est_quaternions)

    @property
    def gt_rotations(self) -> Rotation | None:
        """:attr:`gt_quaternions` as a scipy ``Rotation`` (built on request)."""
        return rotations_of(self.gt_quaternions)

    def rpe(
        self,
        delta: float = 1.0,
        unit: str = "s",
        pairs: str = "reference",
        all_pairs: bool | None = None,
        tolerance: float = 0.1,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Relative pose error pairs (i, j) and errors (metres, degrees) over ``delta`` in ``unit``,
        pairs taken along the ``reference`` or the ``estimate``, by lorisnb's rule
        (``all_pairs=None``) or evo's (see :func:`lorisnb.core.metrics.pairs.rpe_indices`); computed once per
        setting and kept."""
        key = (float(delta), unit, pairs, all_pairs, float(tolerance))
        if key not in self._rpe_cache:
            if self.matched < 2 or self.gt_quaternions is None or self.est_quaternions is None:
                z = np.zeros(0, int)
                self._rpe_cache[key] = (z, z, np.zeros(0), np.zeros(0))
            else:
                i, j = rpe_indices(
                    self.stamps, self.gt_positions, self.gt_quaternions, self.est_positions, self.est_quaternions,
                    delta, unit, pairs, all_pairs, tolerance,
                )  # fmt: skip
                if (
                    self.gt_blocks is not None and self.est_blocks is not None
                ):  # evo's products of the blocks as written
                    tr, rr = written_rpe(self.gt_positions, self.gt_blocks, self.est_positions, self.est_blocks, i, j)
                else:
                    tr, rr = metrics.rpe(
                        self.gt_positions, self.gt_quaternions, self.est_positions, self.est_quaternions, i, j,
                        assume_unit=True,
                    )  # fmt: skip
                if self.matched < 2**31:  # kept: indices in 4 bytes
                    i, j = i.astype(np.int32), j.astype(np.int32)
                self._rpe_cache[key] = (i, j, tr, rr)
        i, j, tr, rr = self._rpe_cache[key]
        return i, j, tr, rr


#: The per-pose fields of :class:`SequenceErrors` that :class:`ScoresOnly` lets go.
POSE_FIELDS = ("stamps", "ate", "aoe", "est_positions", "gt_positions", "est_quaternions", "gt_quaternions",
               "est_blocks", "gt_blocks", "read_poses")  # fmt: skip


def _let_go(name: str) -> property:
    def get(self: ScoresOnly) -> Any:
        raise EvaluationError(
            f"seq {self.seq}: its per-pose errors ({name}) were let go once the evaluation's own threshold "
            "setting was scored (evaluate(..., keep_poses=False)); its table at that setting can be read, "
            "nothing else: evaluate again with keep_poses=True (the default) to score other settings, sweep, "
            "plot or list poses"
        )

    return property(get)


class ScoresOnly(SequenceErrors):
    """A sequence's errors once its scores at the evaluation's spec setting are kept and its per-pose
    arrays let go (:func:`scores_only`): what a worker sends back when only that setting's table is
    wanted (``lorisnb evaluate`` printing or writing it), about 1 % of the bytes (a 1,716-pose
    sequence: 2 KB instead of 270 KB pickled). Its matched count, lever and sizes are kept; reading
    a per-pose field is an :class:`~lorisnb.errors.EvaluationError` saying how to keep them."""

    stamps = _let_go("stamps")
    ate = _let_go("ate")
    aoe = _let_go("aoe")
    est_positions = _let_go("est_positions")
    gt_positions = _let_go("gt_positions")
    est_quaternions = _let_go("est_quaternions")
    gt_quaternions = _let_go("gt_quaternions")
    est_blocks = _let_go("est_blocks")
    gt_blocks = _let_go("gt_blocks")
    read_poses = _let_go("read_poses")

    @property
    def matched(self) -> int:
        return int(self.__dict__["_matched"])

    def __repr__(self) -> str:
        return f"<SequenceErrors seq {self.seq}: {self.poses} poses, {self.matched} matched, per-pose errors let go>"

    __eq__ = object.__eq__
    __hash__ = object.__hash__


def scores_only(e: SequenceErrors) -> SequenceErrors:
    """``e`` without its per-pose arrays (:class:`ScoresOnly`), once the scores a table reads are kept
    on it (:func:`lorisnb.core.lifelong.scoring.sequence_scores`): its lever and sizes are computed
    first, its RPE pairs dropped. A sequence already let go is returned as it is."""
    if isinstance(e, ScoresOnly):
        return e
    _ = e.rotation_lever
    for how in ("extent", "length"):
        sequence_size(e, how)
    kept = {k: v for k, v in vars(e).items() if k not in POSE_FIELDS and k != "_rpe_cache"}
    out = object.__new__(ScoresOnly)
    vars(out).update(kept, _matched=e.matched, _rpe_cache={})
    return out


@dataclass(kw_only=True)
class FileErrors:
    """Threshold-free errors of one result file."""

    path: Path
    algorithm: str
    file: str
    suite: str
    scene: str
    frame: str
    mode: str
    alignment: Sim3
    aligned_on: int | None
    official_interpolation: bool
    sequences: list[SequenceErrors]
    warnings: list[str] = field(default_factory=list)
    trial: int = 0  # the trial number (:mod:`lorisnb.core.stats.trials`); 0 for the only trial
    #: first and last stamp (seconds) of every sequence of the scene's ground truth, all of them and
    #: not only those of this file: what the scene's CR is taken over (empty when not known)
    groundtruth_spans: dict[int, tuple[float, float]] = field(default_factory=dict)
    #: path length (metres) of every sequence's whole ground truth as read, before association:
    #: what rpg's relative error takes its sub-trajectory lengths from (empty when not known)
    groundtruth_lengths: dict[int, float] = field(default_factory=dict)
    #: the RPE settings of the spec the errors were computed under (``EvalSpec.rpe_options()``):
    #: what :func:`lorisnb.core.lifelong.scoring.score` and :func:`lorisnb.core.lifelong.sweep.sweep` use unless
    #: given (empty when not known: lorisnb's own rule over 1 s)
    rpe: dict[str, Any] = field(default_factory=dict)
    #: the thresholds (``eps``, ``phi``, ``delta``, ``tau``) of the spec the errors were evaluated
    #: under, as the evaluation that holds them records them: what ``score`` and ``sweep`` use
    #: unless given (:func:`lorisnb.core.lifelong.scoring.thresholds_of`; empty when not known)
    thresholds: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:  # the one place a row's labels are made: compared and grouped as NFC
        self.algorithm, self.file, self.suite, self.scene = map(label, (self.algorithm, self.file, self.suite,
                                                                     self.scene))  # fmt: skip

    def __repr__(self) -> str:
        n = len(self.sequences)
        matched = sum(e.matched for e in self.sequences)
        poses = sum(e.poses for e in self.sequences)
        trial = f", trial {self.trial}" if self.trial else ""
        notes = f", {len(self.warnings)} warning(s)" if self.warnings else ""
        return (
            f"<FileErrors {self.algorithm} {self.file} (scene {self.scene}, {self.mode}{trial}): "
            f"{n} sequence{'' if n == 1 else 's'}, {matched} of {poses} poses matched{notes}>"
        )


#: The algorithms ``scale="auto"`` aligns with Sim(3): the official tool's ``evaluate_all.py`` does so
#: for these names exactly (``alg == 'dso' or alg == 'svo'``).
MONOCULAR = ("dso", "svo")


def is_monocular(algorithm: str) -> bool:
    """Whether ``scale="auto"`` treats an algorithm as monocular (Sim(3) alignment): named ``dso``
    or ``svo`` exactly, as the official tool decides. A name holding them as a word (``dso_v2``,
    ``stereo_dso``, ``vi-dso``, ``svo_stereo``) is not: stereo and visual-inertial variants have a
    metric scale, and a free one would improve their ATE and CR over the official tool's (the
    evaluation says where a scale far from 1 fits better, :func:`lorisnb.core.pipeline.checks.scale_note`).
    A row of one of several topics of a bag, ``<algorithm>:<topic>`` (``dso:/pose``), is its algorithm's.
    """
    return algorithm.partition(":/")[0] in MONOCULAR


def scene_eps(eps: Eps, scene: str) -> float:
    """The ATE threshold for a scene, metres: a number, ``"paper"`` (1 / 3 / 5 m by scene size,
    Fig. 3 of the paper), or a mapping scene -> metres. Validate user values first with
    :func:`lorisnb.core.spec.validate.eps_value`."""
    if isinstance(eps, str):
        if eps.strip().lower() == "paper":
            if scene not in PAPER_EPS:
                raise ValidationError(
                    f"eps='paper' is the paper's 1/3/5 m for the OpenLORIS scenes; scene {scene!r} is not one: "
                    "give eps in metres or as 'relative:F' (a fraction of the ground truth's extent)"
                )
            return PAPER_EPS[scene]
        try:
            return float(eps)
        except ValueError:  # relative:F is a fraction of each sequence's extent (sequence_eps)
            raise ValidationError(f"eps={eps!r}: expected metres or 'paper' for a scene's threshold") from None
    if isinstance(eps, Mapping):
        if scene not in eps:
            raise ValidationError(f"eps={dict(eps)!r} gives no threshold for scene {scene!r}, which the inputs "
                                  f"hold: add {scene!r} to the mapping, or give one eps for every scene")  # fmt: skip
        return float(eps[scene])
    return float(eps)


def sequence_size(e: SequenceErrors, relative_to: str = "extent") -> float:
    """The size a relative eps is a fraction of, metres: :func:`~lorisnb.core.trajectory.poses.size` of the
    sequence's matched ground truth (``extent`` or ``length``; 0 with fewer than two matched poses)."""
    if relative_to not in e._sizes:  # computed once: kept by a sequence whose poses are let go (ScoresOnly)
        e._sizes[relative_to] = size(e.gt_positions, relative_to)
    return e._sizes[relative_to]


def sequence_eps(eps: Eps, scene: str, e: SequenceErrors) -> float:
    """The ATE threshold of one sequence, metres: :func:`~lorisnb.core.pipeline.model.scene_eps`, or for
    ``"relative:F"`` F times :func:`sequence_size` (the extent of the matched ground truth)."""
    if isinstance(eps, str) and eps.startswith("relative:"):
        return float(eps.split(":", 1)[1]) * sequence_size(e, "extent")
    return scene_eps(eps, scene)


def check_label(path: str | Path, file: str | None) -> str:
    """How the checks' notes name an input: its ``file`` label where it holds the folders below the
    results folder (the table's ``file`` column, ``algA/cafe1.txt``), else the path as given (a file
    given alone). Two algorithms' ``cafe1.txt`` are two inputs: a note naming only ``cafe1.txt``
    left the user to guess which (and the same text from both was said once)."""
    return file if file is not None and "/" in file else str(path)
