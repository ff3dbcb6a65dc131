"""Scenes, robots and sensor frames of OpenLORIS-Scene, with the extrinsics shipped in the package.

The numbers are facts from the OpenLORIS-Scene benchmark tools (``benchmark/openloris_tf_data.py``,
MIT licence, Intel Corporation), the same as ``openloris-scene/extrinsics.json`` of the shared data.
Each entry is ``T_base_link_<sensor>``: the pose of the sensor frame expressed in ``base_link``
(translation in metres, unit quaternion ``qx qy qz qw``). Ground truth is given for
``base_link``; an estimate reported in sensor frame ``S`` is compared with ground truth composed
on the right with ``T_base_link_S`` (``world_T_S = world_T_base_link @ T_base_link_S``).
"""

from __future__ import annotations

import functools

import numpy as np

from lorisnb.core.alignment.geometry import quat_conjugate, quat_multiply, quat_normalize, quat_rotate
from lorisnb.errors import FrameError

#: Scenes in the order the official tool matches them (by substring of the ``scene:`` header).
SCENES: tuple[str, ...] = ("office", "corridor", "home", "cafe", "market")


#: The paper's lifelong ATE thresholds (Fig. 3 caption), metres: 1 m office, 3 m home and cafe,
#: 5 m corridor and market. The AOE threshold there is 30 degrees for every scene.
PAPER_EPS: dict[str, float] = {"office": 1.0, "corridor": 5.0, "home": 3.0, "cafe": 3.0, "market": 5.0}
PAPER_PHI: float = 30.0

#: Which robot recorded which scene.
ROBOT_OF_SCENE: dict[str, str] = {
    "office": "segway_deliverybot_s1",
    "corridor": "segway_deliverybot_s1",
    "home": "segway_deliverybot_s1",
    "cafe": "segway_deliverybot_s1",
    "market": "gaussian_scrubber_75",
}

# T_base_link_<frame>: (xyz metres, quaternion xyzw)
_EXTRINSICS: dict[str, dict[str, tuple[tuple[float, float, float], tuple[float, float, float, float]]]] = {
    "segway_deliverybot_s1": {
        "d400_color": (
            (0.2264836849091656, -0.05114194035652147, 0.916),
            (-0.49676229968284136, 0.4998795887129771, -0.49510681269354095, 0.5081504289345848),
        ),
        "d400_depth": (
            (0.22722047136786871, -0.06601512576001335, 0.9157872415132173),
            (-0.49538006860636935, 0.49954735142309487, -0.49840674562280746, 0.5065982108450463),
        ),
        "d400_imu": (
            (0.21545245195759705, -0.07164430142403165, 0.9206998887739904),
            (-0.49538006860636935, 0.49954735142309487, -0.49840674562280746, 0.5065982108450463),
        ),
        "t265_fisheye1": (
            (0.23757012582874237, -0.038724749600647444, 0.8950755692783204),
            (-0.49597362846259985, 0.49833071591566835, -0.4958921122758979, 0.5096740825539088),
        ),
        "t265_fisheye2": (
            (0.2379100555955274, -0.10269086731607438, 0.8938944689217037),
            (-0.4925125657739745, 0.4999316027612397, -0.4977612079783229, 0.5096406037074316),
        ),
        "t265_imu": (
            (0.23769333650938815, -0.04942265635384921, 0.894903580913328),
            (0.5030437335657985, 0.49268060367606764, 0.5074439466966938, 0.4967025929491916),
        ),
    },
    "gaussian_scrubber_75": {
        "d400_color": (
            (0.398363566676407, 0.029117046016620643, 1.198511534258444),
            (0.5508509426177262, -0.5167305893488635, 0.44976770953124534, -0.47671977566632984),
        ),
        "d400_depth": (
            (0.399546294466062, 0.014453458565135675, 1.1984746547500458),
            (0.5499697614834611, -0.5171593202226934, 0.4537274051736184, -0.47350917705472384),
        ),
        "d400_imu": (
            (0.38894162200484866, 0.00842158791024528, 1.2052174620767606),
            (0.5504510403790713, -0.5176133892954977, 0.4532057328200385, -0.47295305803713444),
        ),
        "t265_fisheye1": (
            (0.873, 0.026, 0.68),
            (-0.3949830160954541, 0.40598254312596027, -0.5999742016639807, 0.5649757065669153),
        ),
        "t265_fisheye2": (
            (0.8696611328664977, -0.03799129213961659, 0.6804951110039751),
            (-0.3919558964011141, 0.40672335425280526, -0.6018891254946375, 0.5645140999063238),
        ),
        "t265_imu": (
            (0.8724694754706082, 0.015314402373202411, 0.6801628399570413),
            (0.4108974443723151, 0.39141685497790646, 0.5636503288904802, 0.600211998038325),
        ),
    },
}

#: Every frame an estimate may be reported in.
FRAMES: tuple[str, ...] = ("base_link",) + tuple(_EXTRINSICS["segway_deliverybot_s1"])


def match_scene(value: str) -> str | None:
    """Return the scene named in a ``scene:`` header value, matched by substring as the official
    tool does (``office``, ``corridor``, ``home``, ``cafe``, ``market`` in that order; case is
    ignored), or None if none matches."""
    low = value.lower()
    for scene in SCENES:
        if scene in low:
            return scene
    return None


def extrinsic(scene: str, frame: str) -> tuple[np.ndarray, np.ndarray]:
    """``T_base_link_<frame>`` for the robot of ``scene``: (translation (3,) in metres,
    unit quaternion (4,) ``xyzw``). ``base_link`` gives the identity.

    Raises FrameError for an unknown scene or frame.
    """
    if scene not in ROBOT_OF_SCENE:
        raise FrameError(f"unknown scene {scene!r}: expected one of {', '.join(SCENES)}")
    if frame == "base_link":
        return np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0])
    table = _EXTRINSICS[ROBOT_OF_SCENE[scene]]
    if frame not in table:
        raise FrameError(f"unknown frame {frame!r} for scene {scene!r}: expected one of {', '.join(FRAMES)}")
    xyz, q = table[frame]
    return np.array(xyz, dtype=float), np.array(q, dtype=float)


@functools.lru_cache(maxsize=256)
def relative_extrinsic(scene: str, from_frame: str, to_frame: str) -> tuple[np.ndarray, np.ndarray]:
    """``T_from_to`` = ``T_base_from^-1 @ T_base_to`` for the robot of ``scene``: (translation (3,)
    in metres, unit quaternion (4,) ``xyzw``). Ground truth reported in ``from_frame`` is moved to
    ``to_frame`` by composing it on the right with this transform."""
    t_a, q_a = extrinsic(scene, from_frame)
    t_b, q_b = extrinsic(scene, to_frame)
    inv = quat_conjugate(quat_normalize(q_a))
    t, q = quat_rotate(inv, t_b - t_a), quat_multiply(inv, quat_normalize(q_b))
    t.flags.writeable = False  # cached: shared by every caller
    q.flags.writeable = False
    return t, q
