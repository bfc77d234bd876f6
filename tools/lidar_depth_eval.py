#!/usr/bin/env python3
"""Judge brume on a KITTI-style LiDAR depth map: sparse scan lines, nothing above the top beam.

KITTI's depth maps (``velodyne_raw``, and the accumulated ``groundtruth`` of the depth
completion benchmark) are a Velodyne HDL-64E's points projected into the left camera and
stored as a 16-bit PNG of metres × 256, 0 where no point fell: about 5-15 % of the pixels,
on curved scan lines, none above the scanner's top beam (+2°) nor in the sky, and, since
the scanner sits above and behind the camera, points of the background seen past the
edges of nearer objects where the camera sees the object itself (the projection has no
occlusion test). This makes such a map from brume's procedural scene and measures what
brume makes of it.

1. Renders brume's scene (``brume scene --fog none``) from the camera (the image, its
   z-buffer: the truth) and from the scanner, ``--lidar-offset`` metres up and back from
   the camera with its orientation, at ``--lidar-scale`` times the size (finer returns).
2. Scans: ``--beams`` beams from ``--top`` to ``--bottom`` degrees of elevation, one return
   each ``--azimuth-step`` degrees (a return dropped with probability ``--dropout``, none
   from the sky or beyond ``--max-range`` m), each return's range from the scanner's
   z-buffer with Gaussian noise of ``--noise`` m; every point is projected into the camera
   without an occlusion test (a later point overwrites an earlier one on the same pixel)
   and written as KITTI writes it: ``round(256·z)``, z the depth along the camera's axis.
3. For each ``--refine`` mode (none, guided, repair), brume renders with λ = 0 and
   airlights 0 and 1 (``--depth-format kitti --focal F``), so τ = 1 − (out(A=1) −
   out(A=0)) exactly; the table gives |τ − τ_true| (mean / 95th percentile) over all
   pixels, those within ``--edge-px`` of a truth depth edge, the sky, surfaces away from
   edges, surfaces above the top beam, and the pixels a point of the background reached
   past a nearer surface (the projected depth over 1.5 times the truth).
4. Foggy images (β, default airlight and λ) from the truth and from the scan with each
   mode, two by two (the truth and none above, guided and repair below), and the scan.

Outputs (in OUT_DIR): left.png, left_z.pfm, lidar_view_z.pfm, lidar.png (the KITTI map),
truth_kitti.png, scan.png (the known pixels, nearer brighter), err_*.png (|τ error| × 4),
fog_*.png, fog_side_by_side.png, results.json.

Usage (from the repository root, after ``cargo build --release --bin brume``):

    pip install opencv-python-headless numpy
    python3 tools/lidar_depth_eval.py OUT_DIR [--brume target/release/brume]
        [--size 1024x512] [--fov 45] [--beta 0.02] [--position 0,1.7,0] [--yaw 0]
        [--beams 64] [--top 2] [--bottom -24.8] [--azimuth-step 0.09] [--dropout 0.1]
        [--noise 0.02] [--max-range 120] [--lidar-offset 0.08,0.27] [--lidar-scale 2]
        [--seed 0]

Takes about 5 s on 2 cores (llvmpipe) at 1024 x 512.
"""

import argparse
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from stereo_refine_eval import (  # noqa: E402
    add_scene_arguments, cv2, near_edges, print_error_table, regions, run, stats,
    tau_from_two_airlights, truth_from_zbuffer)


def scan(a, z_lidar, F_lidar, rng):
    """The scanner's points in its own eye frame (x right, y up, z back: the camera looks
    down −z), from its view's eye depth ``z_lidar`` (inf in the sky)."""
    Hl, Wl = z_lidar.shape
    cxl, cyl = (Wl - 1) / 2.0, (Hl - 1) / 2.0
    half_h = math.degrees(math.atan(cxl / F_lidar))
    az = np.radians(np.arange(-half_h, half_h, a.azimuth_step))
    points = []
    for e in np.radians(np.linspace(a.top, a.bottom, a.beams)):
        d = np.stack([np.sin(az) * math.cos(e), np.full_like(az, math.sin(e)),
                      -np.cos(az) * math.cos(e)], axis=1)
        u, v = d[:, 0] / -d[:, 2], -d[:, 1] / -d[:, 2]
        px, py = np.round(cxl + F_lidar * u).astype(int), np.round(cyl + F_lidar * v).astype(int)
        inside = (px >= 0) & (px < Wl) & (py >= 0) & (py < Hl)
        d, px, py = d[inside], px[inside], py[inside]
        depth = z_lidar[py, px]
        rng_m = depth / -d[:, 2]
        rng_m = rng_m + rng.normal(0.0, a.noise, rng_m.shape)
        keep = np.isfinite(rng_m) & (rng_m < a.max_range) & (rng.random(rng_m.shape) >= a.dropout)
        points.append(d[keep] * rng_m[keep, None])
    return np.concatenate(points)


def project_kitti(points_cam, F, W, H):
    """KITTI's 16-bit map of points in the camera's eye frame: round(256·z), z the depth
    along the axis, 0 where none fell; a later point overwrites an earlier one."""
    z = -points_cam[:, 2]
    front = z > 0.1
    p, z = points_cam[front], z[front]
    cx, cy = (W - 1) / 2.0, (H - 1) / 2.0
    x = np.round(cx + F * p[:, 0] / z).astype(int)
    y = np.round(cy - F * p[:, 1] / z).astype(int)
    inside = (x >= 0) & (x < W) & (y >= 0) & (y < H)
    m = np.zeros((H, W), np.uint16)
    m[y[inside], x[inside]] = np.clip(np.round(256.0 * z[inside]), 1, 65535).astype(np.uint16)
    return m


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add_scene_arguments(ap)
    ap.add_argument("--beams", type=int, default=64)
    ap.add_argument("--top", type=float, default=2.0, help="top beam's elevation, degrees")
    ap.add_argument("--bottom", type=float, default=-24.8, help="bottom beam's, degrees")
    ap.add_argument("--azimuth-step", type=float, default=0.09, help="degrees")
    ap.add_argument("--dropout", type=float, default=0.1)
    ap.add_argument("--noise", type=float, default=0.02, help="range noise, m (σ)")
    ap.add_argument("--max-range", type=float, default=120.0)
    ap.add_argument("--lidar-offset", default="0.08,0.27",
                    help="the scanner's place from the camera: UP,BACK in metres")
    ap.add_argument("--lidar-scale", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--edge-px", type=int, default=5)
    a = ap.parse_args()

    os.makedirs(a.out_dir, exist_ok=True)
    o = lambda n: os.path.join(a.out_dir, n)  # noqa: E731
    W, H = (int(v) for v in a.size.lower().split("x"))
    B = a.brume
    rng = np.random.default_rng(a.seed)

    # 1. The camera's view and the scanner's.
    pos = [float(v) for v in a.position.split(",")]
    up, back = (float(v) for v in a.lidar_offset.split(","))
    yaw = math.radians(a.yaw)
    # brume scene: yaw 0 looks down −z with +x to the right; back is +z turned by the yaw.
    back_vec = (-math.sin(yaw), 0.0, math.cos(yaw))
    pos_l = [pos[0] + back * back_vec[0], pos[1] + up, pos[2] + back * back_vec[2]]
    common = ["scene", "--fog", "none", "--yaw", str(a.yaw), "--fov", str(a.fov),
              "--near", str(a.near), "--far", str(a.far)]
    run([B] + common + ["--size", f"{W}x{H}", "--position", ",".join(map(str, pos)),
                        "--out", o("left.png"), "--depth-out", o("left_z.pfm")])
    s = a.lidar_scale
    run([B] + common + ["--size", f"{s * W}x{s * H}", "--position", ",".join(map(str, pos_l)),
                        "--out", o("lidar_view.png"), "--depth-out", o("lidar_view_z.pfm")])
    F, sky, z, R_true = truth_from_zbuffer(o("left_z.pfm"), a.fov, a.near, a.far)
    F_l, _, z_l, _ = truth_from_zbuffer(o("lidar_view_z.pfm"), a.fov, a.near, a.far)
    tau_true = np.where(sky, 0.0, np.exp(-a.beta * R_true))

    # 2. The scan, in the camera's frame (same orientation: the offset alone).
    pts = scan(a, z_l, F_l, rng)
    pts_cam = pts + np.array([0.0, up, back])
    lidar = project_kitti(pts_cam, F, W, H)
    cv2.imwrite(o("lidar.png"), lidar)
    known = lidar > 0
    z_scan = lidar / 256.0
    past_edge = known & ~sky & (z_scan > 1.5 * z)
    cx, cy = (W - 1) / 2.0, (H - 1) / 2.0
    ys = np.meshgrid(np.arange(W), np.arange(H))[1]
    # Above the top beam as seen from the camera (level camera: a row's elevation).
    above_top = np.degrees(np.arctan((cy - ys) / F)) > a.top + 0.5
    surf = ~sky
    near_edge = near_edges(np.log(np.where(sky, 1e9, z)), 0.05, sky, a.edge_px)
    masks = regions(near_edge, sky, a.edge_px, {
        "surfaces above the top beam": surf & above_top,
        "background points past an edge": past_edge,
    })

    # 3. τ per refinement.
    def tau_of(refine):
        def render(airlight, out):
            run([B, "render", "--image", o("left.png"), "--depth", o("lidar.png"),
                 "--depth-format", "kitti", "--focal", str(F), "--beta", str(a.beta),
                 "--lambda", "0", "--airlight", airlight, "--refine", refine, "--out", out])
        return tau_from_two_airlights(render, lambda A: o(f"tau_{refine}_A{A}.pfm"))

    modes = ["none", "guided", "repair"]
    errors = {}
    results = {"setup": vars(a) | {"focal_px": F, "scanner_focal_px": F_l,
                                   "known_fraction": float(known.mean()),
                                   "background_points_past_edges": int(past_edge.sum()),
                                   "mask_pixels": {m: int(v.sum()) for m, v in masks.items()}},
               "tau_abs_error": {}}
    for refine in modes:
        t = tau_of(refine)
        err = np.abs(t - tau_true)
        np.save(o(f"tau_{refine}.npy"), t.astype(np.float32))
        cv2.imwrite(o(f"err_{refine}.png"), np.clip(err * 4 * 255, 0, 255).astype(np.uint8))
        errors[f"lidar/{refine}"] = {m: stats(err, v) for m, v in masks.items()}
    results["tau_abs_error"] = errors

    # 4. Foggy images.
    # The truth as a KITTI map (depths past 256 m stored as 256 m, the format's largest).
    truth_z = np.where(sky, 0, np.clip(np.round(256.0 * z), 1, 65535)).astype(np.uint16)
    cv2.imwrite(o("truth_kitti.png"), truth_z)
    sheet = []
    for out, depth, refine in [("fog_truth.png", "truth_kitti.png", "none")] + [
            (f"fog_lidar_{m}.png", "lidar.png", m) for m in modes]:
        run([B, "render", "--image", o("left.png"), "--depth", o(depth), "--depth-format",
             "kitti", "--focal", str(F), "--beta", str(a.beta), "--refine", refine,
             "--out", o(out)])
        sheet.append(cv2.imread(o(out)))
    scan_img = np.zeros((H, W, 3), np.uint8)
    scan_img[known] = 255 - np.clip(np.log(z_scan[known]) / math.log(a.max_range) * 255, 0,
                                    255).astype(np.uint8)[:, None]
    cv2.imwrite(o("fog_side_by_side.png"), np.vstack([np.hstack(sheet[:2]),
                                                      np.hstack(sheet[2:])]))
    cv2.imwrite(o("scan.png"), scan_img)
    with open(o("results.json"), "w") as fh:
        json.dump(results, fh, indent=1)

    print(f"scene {W}x{H}, fov {a.fov}°, F = {F:.1f} px, beta {a.beta}/m; scan: {a.beams} "
          f"beams {a.top}°..{a.bottom}°, {known.mean():.1%} of pixels known, "
          f"{int(past_edge.sum())} px of background seen past a nearer edge")
    print_error_table(42, list(errors), errors, masks)


if __name__ == "__main__":
    main()
