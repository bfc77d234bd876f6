#!/usr/bin/env python3
"""Judge brume's pre-processing of a real LiDAR depth map against held-out ground truth.

``tools/lidar_depth_eval.py`` measures it on brume's rendered scene; this runs on one real
KITTI depth-completion frame, which brume cannot ship (KITTI's data is CC BY-NC-SA 3.0).
Such a frame is, e.g., ``2011_09_26_drive_0001_sync`` frame 5 in the tests of
``andreaconti/torch_kitti`` (MIT; ``tests/test_data/depth_completion/``: ``test_image.png``,
``velodyne_raw_image_02.png``, ``groundtruth_image_02.png``; focal length 721.5377 px from
``raw/calib_cam_to_cam.txt``'s ``P_rect_02``), or any frame of KITTI's own download.

1. ``brume prep --depth-format kitti --focal F`` reads the velodyne_raw map (16-bit PNG, z in
   metres times 256, 0 unknown) with the colour image, once per ``--refine`` mode, and writes
   the prepared range (PFM).
2. The ground truth (KITTI's accumulated, denser map in the same format) is turned into range
   with the same pinhole model brume uses for a given focal length (the principal point at the
   image's centre), R = z·|ray|, independently of brume.
3. It prints |ln(R / R_true)| (mean, the share more than 5 % and 20 % off) and |τ − τ_true| at
   ``--beta`` (mean / 95th percentile) over the held-out pixels: those the truth knows and the
   LiDAR map does not, which pre-processing filled; also by bands of rows.

Usage (from the repository root, after ``cargo build --release --bin brume``):

    pip install numpy pillow opencv-python-headless
    python3 tools/lidar_real_eval.py --image rgb.png --depth velodyne_raw.png \\
        --truth groundtruth.png --focal 721.5377 [--brume target/release/brume] [--beta 0.03]
        [--refine none,guided,repair] [--out DIR]

Takes about a second per mode at 1242 x 375 on 2 cores.
"""

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from stereo_refine_eval import read_pfm  # noqa: E402


def kitti_depth(path):
    """A KITTI depth PNG in metres (z), NaN where unknown."""
    raw = np.asarray(Image.open(path)).astype(np.float64)
    return np.where(raw > 0, raw / 256.0, np.nan)


def ray_lengths(w, h, focal):
    """|ray| of each pixel centre, the principal point at the image's centre."""
    x, y = np.meshgrid(np.arange(w) + 0.5 - w / 2, np.arange(h) + 0.5 - h / 2)
    return np.sqrt((x / focal) ** 2 + (y / focal) ** 2 + 1.0)


def scores(r, r_true, beta):
    """|ln R/R_true| mean, share > 5 % and > 20 %; |τ − τ_true| mean and 95th percentile."""
    e = np.abs(np.log(r / r_true))
    t = np.abs(np.exp(-beta * r) - np.exp(-beta * r_true))
    return e.mean(), (e > 0.05).mean(), (e > 0.2).mean(), t.mean(), np.percentile(t, 95)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--image", required=True)
    ap.add_argument("--depth", required=True, help="the LiDAR map (velodyne_raw)")
    ap.add_argument("--truth", required=True, help="the ground truth map (groundtruth)")
    ap.add_argument("--focal", type=float, required=True, help="px")
    ap.add_argument("--brume", default="target/release/brume")
    ap.add_argument("--beta", type=float, default=0.03)
    ap.add_argument("--refine", default="none,guided,repair")
    ap.add_argument("--out", default=None, help="keep the prepared ranges here")
    a = ap.parse_args()

    sparse, truth = kitti_depth(a.depth), kitti_depth(a.truth)
    h, w = truth.shape
    r_true = truth * ray_lengths(w, h, a.focal)
    held = np.isfinite(truth) & ~np.isfinite(sparse)
    out = a.out or tempfile.mkdtemp(prefix="brume-lidar-real-")
    os.makedirs(out, exist_ok=True)
    print(f"{w}x{h}, focal {a.focal} px, LiDAR {100 * np.isfinite(sparse).mean():.1f} % "
          f"known, truth {100 * np.isfinite(truth).mean():.1f} %, {held.sum()} px held out; "
          f"beta {a.beta}/m")
    print(f"{'refine':8} {'rows':>9} {'px':>6}  |ln R/R_true| mean  >5 %   >20 %   "
          f"|tau err| mean / p95")
    bands = [(0, h)] + [(y, min(y + 64, h)) for y in range(0, h, 64)]
    for mode in a.refine.split(","):
        path = os.path.join(out, f"range_{mode}.pfm")
        subprocess.run([a.brume, "prep", "--image", a.image, "--depth", a.depth,
                        "--depth-format", "kitti", "--focal", str(a.focal), "--refine", mode,
                        "--out", path], check=True, capture_output=True)
        r = read_pfm(path)
        for y0, y1 in bands:
            m = held.copy()
            m[:y0], m[y1:] = False, False
            if m.sum() == 0:
                continue
            mean, over5, over20, tau, tau95 = scores(r[m], r_true[m], a.beta)
            print(f"{mode:8} {y0:>4}-{y1:<4} {m.sum():>6}  {mean:17.4f} {100 * over5:5.1f} "
                  f"{100 * over20:6.1f}   {tau:.4f} / {tau95:.4f}")


if __name__ == "__main__":
    main()
