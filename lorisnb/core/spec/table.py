"""The evaluation spec documented: what each option means, its unit and the inputs it applies to,
and the manual's table of it (:func:`spec_table`, every preset's default; a test keeps docs/guide/evaluation-spec.md
equal to it)."""

from __future__ import annotations

from lorisnb.core.spec import evo
from lorisnb.core.spec.evalspec import PRESETS, text

#: What each option of the spec means, its unit, and which inputs it applies to: the manual's
#: spec table is :func:`spec_table` (a test keeps them equal).
OPTIONS: dict[str, tuple[str, str, str]] = {
    "association": (
        "how poses are matched in time: interpolate / nearest / index / evo-nearest / evo-interpolate",
        "",
        "all",
    ),
    "max_gap": ("interpolation bracket: both neighbours within it", "s", "interpolate"),
    "max_diff": ("nearest association: largest stamp difference", "s", "nearest, evo-*"),
    "t_offset": ("added to every estimate stamp (a known clock offset)", "s", "all"),
    "repeated": ("poses repeating the previous one or its stamp: drop (official) / keep (evo)", "", "all"),
    "align": ("se3 / sim3 / posyaw / none / auto (sim3 for dso, svo) / scale (only) / origin (first pose)", "", "all"),
    "align_frames": ("fit the alignment on the first N matched poses", "poses", "align != none"),
    "mode": ("auto / per-seq / lifelong (one alignment, first sequence with matches)", "", "all"),
    "official_interpolation": (
        "the official tool's orientation slips (AOE, and the RPE of the same poses)",
        "",
        "interpolate",
    ),
    "official_lifelong": (
        "the official tool's lifelong alignment: none at all when the first sequence matches nothing",
        "",
        "OpenLORIS files, lifelong",
    ),
    "repair_stamps": ("read nanosecond stamps written without zero padding", "", "OpenLORIS files"),
    "eps": ("ATE threshold: metres / paper (1/3/5 m) / relative:F", "m", "all"),
    "phi": ("AOE threshold", "deg", "all"),
    "delta": ("validity window of a pose (Eq. 2, 3)", "s", "all"),
    "tau": ("re-localization time factor (Eq. 4)", "s", "all"),
    "rpe_delta": ("RPE step", "rpe_unit", "all"),
    "rpe_unit": ("unit of the RPE step: s / m / f or frames / deg / rad", "", "all"),
    **evo.EVO_OPTIONS,
    "kitti_precision": ("the KITTI metric's arithmetic: single (the devkit's floats) / double", "", "kitti preset"),
    "tartanair_scale": (
        "TartanAir's scale (its monocular track): its ATE scale and its rule for RPE, KITTI",
        "",
        "tartanair preset",
    ),
    "tartanair_seed": ("seed of TartanAir's random RPE pairs (Python's random)", "", "tartanair preset"),
    "transform": ("T_est_gt: the ground-truth body's pose in the estimate's body frame", "4x4", "pairs, manifests"),
}


def spec_table() -> str:
    """The manual's table of the spec: option, meaning, unit, default per preset, inputs."""
    names = list(PRESETS)
    head = "| option | meaning | unit | " + " | ".join(f"`{n}`" for n in names) + " | applies to |"
    rows = [head, "|" + "---|" * (len(names) + 4)]
    for key, (meaning, unit, applies) in OPTIONS.items():
        defaults = " | ".join(text(getattr(PRESETS[n], key)) for n in names)
        rows.append(f"| `{key}` | {meaning} | {unit} | {defaults} | {applies} |")
    return "\n".join(rows)
