"""Plain pairs and sessions under the field's conventions, against the tools that define them.

REFERENCE holds values computed by the tools themselves on the bundled TUM RGB-D pairs
(../shared/data/tum-rgbd), on 2026-11-22:

- ``tum_ate``: TUM RGB-D benchmark tools, ``evaluate_ate.py`` and ``associate.py`` from
  github.com/jbriales/rgbd_benchmark_tools (commit 80723c9c9530481ec7dc92d3c3f77575f6a25bec, TUM's
  scripts as distributed), converted to Python 3 with lib2to3 and ``numpy.linalg.linalg.svd`` read
  as ``numpy.linalg.svd`` (numpy 2); their ``associate(first, second, offset, max_difference)``
  and ``align`` called directly, RMSE at full precision. Key: offset and max_difference.
- ``rpg_abs`` and ``rpg_rel``: rpg_trajectory_evaluation (github.com/uzh-rpg/rpg_trajectory_evaluation,
  commit 8c8ceec55c5c5094a6494208cfc5f54afe0bbc4d), ``load_estimate_and_associate`` (max_diff
  0.02), ``alignTrajectory(method, n_aligned)``, the aligned poses as ``Trajectory.align_trajectory``
  builds them, ``compute_absolute_error`` (RMSE of e_trans and e_rot) and ``compute_relative_error``
  at rpg's default lengths (10..50 % of the length, truncated to cm; max_dist_diff 0.2 L; the
  Sim(3) scale), mean of the % translation and deg/m rotation errors.

- ``whole_rpg_rel``: rpg_trajectory_evaluation's ``Trajectory`` class itself (same commit;
  ``align_type="sim3"``, the two files as ``stamped_groundtruth.txt`` and
  ``stamped_traj_estimate.txt``; ``np.linalg.linalg.svd`` read as ``np.linalg.svd``), run on
  2026-11-23: ``traj_length`` is the path length of the whole ground-truth file (every row, a
  repeated stamp's too), the lengths its ``preset_boxplot_distances``, then
  ``compute_relative_errors()``.

Values: tum_ate (pairs, ATE RMSE m); rpg_abs (pairs, ATE RMSE m, rotation RMSE deg, scale);
rpg_rel and whole_rpg_rel (length m, samples, mean translation %, mean deg/m); whole_rpg_length (the
whole ground truth's path length, m).
"""

from __future__ import annotations

REFERENCE = {
    "fr1_xyz": {
        "rpg_abs none n=-1": (786, 0.02007766718141919, 0.7019677399448414, 1.0),
        "rpg_abs posyaw n=-1": (786, 0.014046763444015328, 1.4141202881673103, 1.0),
        "rpg_abs posyaw n=1": (786, 0.01933460864421716, 0.6970370604196963, 1.0),
        "rpg_abs se3 n=-1": (786, 0.013473467769906787, 2.0518937319212167, 1.0),
        "rpg_abs se3 n=1": (786, 0.01936677140803008, 0.6912815365415773, 1.0),
        "rpg_abs se3 n=100": (786, 0.020640032146350656, 4.763578875227224, 1.0),
        "rpg_abs sim3 n=-1": (786, 0.013394054874269222, 2.0518937319212167, 1.0079236662147342),
        "rpg_abs sim3 n=100": (786, 0.021121776376579235, 4.763578875227224, 0.9769434637174141),
        "rpg_rel 10% sim3": (0.8, 671, 2.5401785725027786, 1.0733093989993157),
        "rpg_rel 20% sim3": (1.6, 604, 1.232736542180146, 0.5675891473031258),
        "rpg_rel 30% sim3": (2.4, 539, 0.7402029001748855, 0.3564773138607906),
        "rpg_rel 40% sim3": (3.2, 472, 0.5873326325000785, 0.27767246779993515),
        "rpg_rel 50% sim3": (4.0, 410, 0.44444501234038075, 0.21157804766060312),
        "whole_rpg_length": 9.159267877342058,
        "whole_rpg_rel 10%": (0.91, 665, 1.8999473017794999, 0.8542995986876568),
        "whole_rpg_rel 20%": (1.83, 589, 1.0653479389730693, 0.4760282478993496),
        "whole_rpg_rel 30%": (2.74, 509, 0.6698936933615771, 0.3107743248950327),
        "whole_rpg_rel 40%": (3.66, 433, 0.4929916648962269, 0.24178267010328952),
        "whole_rpg_rel 50%": (4.57, 382, 0.3990204295885851, 0.19041827045798232),
        "tum_ate offset=0.0 max_diff=0.02": (786, 0.013473467769906785),
        "tum_ate offset=0.0 max_diff=0.05": (787, 0.013492843176733781),
        "tum_ate offset=0.01 max_diff=0.02": (786, 0.013465998875679806),
    },
    "fr2_desk": {
        "rpg_abs none n=-1": (2223, 3.1668600928240167, 132.481129341028, 1.0),
        "rpg_abs posyaw n=-1": (2223, 1.9741365970255929, 122.7821736978506, 1.0),
        "rpg_abs posyaw n=1": (2223, 3.189060938593912, 117.89169128023764, 1.0),
        "rpg_abs se3 n=-1": (2223, 0.008143967169519399, 0.9931225011890431, 1.0),
        "rpg_abs se3 n=1": (2223, 0.042336538513015165, 1.2872536351562431, 1.0),
        "rpg_abs se3 n=100": (2223, 0.04484357458880605, 1.8932009035865183, 1.0),
        "rpg_abs sim3 n=-1": (2223, 0.006185672900328248, 0.9931225011890431, 0.9970022884061697),
        "rpg_abs sim3 n=100": (2223, 0.04411367525962381, 1.8932009035865183, 0.9950330072543387),
        "rpg_rel 10% sim3": (1.88, 1912, 0.7431170183395043, 0.4095750075967164),
        "rpg_rel 20% sim3": (3.77, 1766, 0.6240121237108037, 0.29605301528742356),
        "rpg_rel 30% sim3": (5.65, 1568, 0.6900408965232799, 0.26031267925489127),
        "rpg_rel 40% sim3": (7.54, 1360, 0.6823758639064132, 0.2251528171720297),
        "rpg_rel 50% sim3": (9.42, 1151, 0.6224454167314558, 0.18682892562189554),
        "whole_rpg_length": 20.339009122208303,
        "whole_rpg_rel 10%": (2.03, 1893, 0.7159162994472416, 0.39193266564730034),
        "whole_rpg_rel 20%": (4.06, 1734, 0.6277212802594234, 0.2872860155492568),
        "whole_rpg_rel 30%": (6.1, 1513, 0.7030492713843857, 0.2534629009823356),
        "whole_rpg_rel 40%": (8.13, 1284, 0.6902313310059869, 0.2181714686255691),
        "whole_rpg_rel 50%": (10.16, 1043, 0.5840875728664031, 0.17310136444682875),
        "tum_ate offset=0.0 max_diff=0.02": (2223, 0.008143967169519095),
        "tum_ate offset=0.0 max_diff=0.05": (2275, 0.008309766381214778),
        "tum_ate offset=0.01 max_diff=0.02": (2225, 0.008440773977154247),
    },
}
