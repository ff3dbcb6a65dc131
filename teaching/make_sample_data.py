"""Write lorisnb's small teaching data (``lorisnb/sample_data/``) from a full data root.

The primer and the labs run on it when no data root is found (a student who installed the wheel
and has no ``../shared/data``). It is a subset of the real data, copied unchanged: the cafe
scene's ground truth (both sequences), the icra20 results of cafe of a few algorithms (per
sequence and lifelong), a TUM RGB-D pair (the indoor reference of the difficulty exercise) and
the published tables. Every file stays under 512 KiB.

    python teaching/make_sample_data.py [DATA_ROOT]      # default: the data root lorisnb finds
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "lorisnb" / "sample_data"
MAX_BYTES = 512 * 1024

FILES = [
    "openloris-scene/LICENSE.txt",
    "openloris-scene/groundtruth/gt_cafe_1.txt",
    "openloris-scene/icra20_results/per-seq/orbslam2_rgbd/cafe_1_1_orbslam2-original.txt",
    "openloris-scene/icra20_results/per-seq/orbslam2_rgbd/cafe_1_2_orbslam2-original.txt",
    "openloris-scene/icra20_results/per-seq/vins_mono_color_imu_with_loop/cafe-1-1.txt",
    "openloris-scene/icra20_results/per-seq/vins_mono_color_imu_with_loop/cafe-1-2.txt",
    "openloris-scene/icra20_results/per-seq/ds-slam/cafe-1-1.txt",
    "openloris-scene/icra20_results/per-seq/ds-slam/cafe-1-2.txt",
    "openloris-scene/icra20_results/per-seq/dso/cafe-1-1-all.txt",
    "openloris-scene/icra20_results/per-seq/infinitam_aligned_depth/cafe-1-1_infinitam-cuda.txt",
    "openloris-scene/icra20_results/per-seq/infinitam_aligned_depth/cafe-1-2_infinitam-cuda.txt",
    # exercise E1: an orientation that drifts, so that a scan ignoring phi finds another eps
    "openloris-scene/icra20_results/per-seq/orbslam2_t265/cafe_1_1_orbslam2-original.txt",
    "openloris-scene/icra20_results/per-seq/orbslam2_t265/cafe_1_2_orbslam2-original.txt",
    "openloris-scene/icra20_results/lifelong/vins_mono_color_imu_with_loop/cafe-1.txt",
    "openloris-scene/icra20_results/lifelong/ds-slam/cafe-1.txt",
    "openloris-scene/icra20_results/lifelong/orbslam2_t265/cafe_1_orbslam2-original.txt",
    "openloris-scene/icra20_results/lifelong/infinitam_aligned_depth/cafe-1_infinitam-cuda.txt",
    "tum-rgbd/freiburg1_xyz-groundtruth.txt",
    "tum-rgbd/freiburg1_xyz-rgbdslam.txt",
    "published/README.md",
    "published/ordslam_table3_ate_rmse_cm.csv",
    "published/ordslam_table4_tum_ate_rmse_cm.csv",
    "published/openloris_table3_reloc_scores.csv",
]

README = """# lorisnb's sample data (teaching)

A small subset of the real data, copied unchanged by `teaching/make_sample_data.py` (do not edit
by hand): the OpenLORIS-Scene cafe ground truth and a few icra20 results of cafe (MIT licence, see
`openloris-scene/LICENSE.txt`), the TUM RGB-D freiburg1_xyz pair, and tables transcribed from the
papers. The primer and the labs use it when no data root is found; pass `data_root=` or set
`LORISNB_DATA` for the full data.
"""


def main(src: Path) -> None:
    missing = [f for f in FILES if not (src / f).is_file()]
    if missing:
        sys.exit(f"not a full data root: {src} lacks {', '.join(missing)}")
    if OUT.exists():
        shutil.rmtree(OUT)
    for f in FILES:
        size = (src / f).stat().st_size
        if size > MAX_BYTES:
            sys.exit(f"{f} is {size} bytes; every tracked file must stay under {MAX_BYTES}")
        (OUT / f).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src / f, OUT / f)
    (OUT / "README.md").write_text(README)
    total = sum(p.stat().st_size for p in OUT.rglob("*") if p.is_file())
    print(f"{len(FILES) + 1} files, {total / 1e6:.2f} MB in {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    from lorisnb import find_data

    main(find_data(sys.argv[1] if len(sys.argv) > 1 else None).root)
