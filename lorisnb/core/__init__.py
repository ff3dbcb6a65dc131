"""The core: pure functions on arrays and dataclasses (trajectories, geometry, frames,
association, the paper's metrics, the pipeline, scoring, sweeps, the simulator). Nothing here
reads files, looks up data, draws or prints; :mod:`lorisnb.io` and :mod:`lorisnb.tools` do."""

from typing import TYPE_CHECKING

from lorisnb._lazy import attach

if TYPE_CHECKING:
    from lorisnb.core.alignment.association import MAX_GAP, Association, associate, groundtruth_in_frame
    from lorisnb.core.alignment.geometry import Sim3, umeyama
    from lorisnb.core.conventions.choices import Conventions, associate_nearest, fit_alignment
    from lorisnb.core.lifelong.aggregate import aggregate_scenes, durations_table
    from lorisnb.core.lifelong.scoring import pose_table, score, sequence_grid
    from lorisnb.core.lifelong.surfaces import Surfaces, cr_surfaces
    from lorisnb.core.lifelong.sweep import eps_at_cr, rank_stability, rank_swaps, sweep, sweep_scenes
    from lorisnb.core.metrics.relative import relative_table, rpg_relative_errors
    from lorisnb.core.pipeline.model import (
        EXTRA_COLUMNS,
        SCENE_COLUMNS,
        SEQUENCE_COLUMNS,
        FileErrors,
        OpenLorisFile,
        ResultFile,
        SequenceErrors,
        is_monocular,
        scene_eps,
    )
    from lorisnb.core.pipeline.sessions import compute_errors, evaluate_sessions, sequence_errors, session_errors
    from lorisnb.core.simulate import Faults, simulate, simulated_errors, simulated_result
    from lorisnb.core.spec.evalspec import PRESETS, EvalSpec, make_spec
    from lorisnb.core.trajectory.frames import FRAMES, PAPER_EPS, PAPER_PHI, SCENES
    from lorisnb.core.trajectory.poses import Trajectory, extent, path_length

__getattr__, __dir__ = attach(__name__)

__all__ = [
    "EXTRA_COLUMNS", "FRAMES", "MAX_GAP", "PAPER_EPS", "PAPER_PHI", "SCENES", "SCENE_COLUMNS", "SEQUENCE_COLUMNS",
    "Association", "Faults", "Surfaces", "FileErrors", "OpenLorisFile", "ResultFile", "SequenceErrors", "Sim3", "Trajectory",
    "aggregate_scenes", "associate", "compute_errors", "cr_surfaces", "durations_table", "eps_at_cr", "extent",
    "groundtruth_in_frame", "is_monocular", "path_length", "pose_table", "rank_stability", "rank_swaps",
    "scene_eps", "score", "sequence_errors", "sequence_grid", "simulate", "simulated_errors", "simulated_result",
    "sweep", "sweep_scenes", "umeyama", "Conventions", "associate_nearest", "fit_alignment", "session_errors",
    "relative_table", "rpg_relative_errors", "EvalSpec", "PRESETS", "evaluate_sessions", "make_spec",
]  # fmt: skip
