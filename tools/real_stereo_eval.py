#!/usr/bin/env python3
"""Judge brume's depth refinement and left-right check on a real stereo pair's matcher output.

``tools/stereo_refine_eval.py`` measures them on brume's rendered scene, whose truth is exact
but whose pictures are clean. This runs the same measurement on a real photograph pair with
measured ground truth: Middlebury 2006 "Aloe" (``tests/data/aloe``: the left and right views as
JPEGs, the left view's structured-light disparity, 0 where unknown).

1. OpenCV's StereoSGBM matches the pair (left view's disparity, 1/16 px). Its disparity and
   the truth are written as float PFMs (+inf where unknown) and read by brume as
   ``--depth-kind disparity`` with the 2006 sets' geometry given in full (``--focal 3740
   --baseline 160 --disparity-offset 270``), so the range is in metres: Z = f·B/(d + offset),
   R = Z·|ray| (principal point at the centre).
2. The true transmittance, written here independently of brume, is τ = exp(−β·R(d_true)) on
   the pixels the truth knows (occlusions and the border are left out of every statistic).
3. For the truth and SGBM, each ``--refine`` mode (none, guided, repair) and with or without
   the left-right check (``--right``), brume renders with λ = 0 and airlights 0 and 1, so
   τ = 1 − (out(A=1) − out(A=0)) exactly; the table gives |τ − τ_true| (mean / 95th
   percentile) over all known pixels, those within 5 px of a truth edge (disparity step > 1 px),
   the rest, the band along the left border that SGBM cannot match (x < numDisparities), and
   the pixels where SGBM is good (valid, ≤ 3 px off) and bad.
4. Foggy images (β, default airlight and λ) from the truth, SGBM unrefined, SGBM repaired,
   and SGBM repaired after the left-right check, side by side.

Outputs (in OUT_DIR): sgbm_disparity.pfm, truth_disparity.pfm, tau_*.npy, err_*.png
(|τ error| × 4), fog_*.png, fog_side_by_side.png, results.json.

Usage (from the repository root, after ``cargo build --release --bin brume``):

    pip install opencv-python-headless numpy
    python3 tools/real_stereo_eval.py OUT_DIR [--brume target/release/brume] [--beta 0.5]
        [--pair tests/data/aloe] [--block-size 5] [--edge-px 5]

Takes about 12 s on 2 cores (llvmpipe) at Aloe's 1282 x 1110.
"""

import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from stereo_refine_eval import (  # noqa: E402
    cv2, near_edges, print_error_table, run, stats, tau_from_two_airlights)

# The Middlebury 2006 sets' geometry (src/io/depth/middlebury.rs's defaults), given in full.
FOCAL_PX, BASELINE_MM, OFFSET_PX = 3740.0, 160.0, 270.0


def write_pfm(path, a):
    """A float32 PFM (one channel), rows stored bottom to top, little-endian."""
    a = np.asarray(a, np.float32)
    with open(path, "wb") as f:
        f.write(b"Pf\n%d %d\n-1.0\n" % (a.shape[1], a.shape[0]))
        f.write(np.ascontiguousarray(a[::-1]).astype("<f4").tobytes())


def range_m(d):
    """Range in metres of disparity ``d`` (px, NaN unknown) at the 2006 geometry, principal
    point at the image's centre as brume assumes it ((W − 1)/2, (H − 1)/2)."""
    H, W = d.shape
    z = FOCAL_PX * BASELINE_MM / (d + OFFSET_PX) / 1000.0
    xs, ys = np.meshgrid(np.arange(W), np.arange(H))
    cx, cy = (W - 1) / 2.0, (H - 1) / 2.0
    return z * np.sqrt(1.0 + ((xs - cx) / FOCAL_PX) ** 2 + ((ys - cy) / FOCAL_PX) ** 2)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out_dir")
    ap.add_argument("--brume", default="target/release/brume")
    ap.add_argument("--pair", default="tests/data/aloe",
                    help="a folder with left.jpg, right.jpg and disparity.png (Middlebury 2006)")
    ap.add_argument("--beta", type=float, default=0.5,
                    help="per metre: Aloe lies 1.2 to 1.9 m away [0.5]")
    ap.add_argument("--block-size", type=int, default=5)
    ap.add_argument("--edge-px", type=int, default=5)
    a = ap.parse_args()

    os.makedirs(a.out_dir, exist_ok=True)
    o = lambda n: os.path.join(a.out_dir, n)  # noqa: E731
    left, right = os.path.join(a.pair, "left.jpg"), os.path.join(a.pair, "right.jpg")
    L, R = cv2.imread(left, cv2.IMREAD_COLOR), cv2.imread(right, cv2.IMREAD_COLOR)
    truth = cv2.imread(os.path.join(a.pair, "disparity.png"), cv2.IMREAD_UNCHANGED)
    d_true = np.where(truth > 0, truth.astype(np.float64), np.nan)
    known = np.isfinite(d_true)
    H, W = d_true.shape

    # 1. StereoSGBM, searching past the largest true disparity.
    num = int(np.ceil((np.nanmax(d_true) + 16) / 16.0)) * 16
    bs = a.block_size
    sgbm = cv2.StereoSGBM_create(
        minDisparity=0, numDisparities=num, blockSize=bs,
        P1=8 * 3 * bs * bs, P2=32 * 3 * bs * bs, disp12MaxDiff=1, uniquenessRatio=10,
        speckleWindowSize=100, speckleRange=2, mode=cv2.STEREO_SGBM_MODE_SGBM_3WAY)
    d_sgbm = sgbm.compute(L, R).astype(np.float64) / 16.0
    d_sgbm[d_sgbm <= 0] = np.nan
    write_pfm(o("sgbm_disparity.pfm"), np.where(np.isfinite(d_sgbm), d_sgbm, np.inf))
    write_pfm(o("truth_disparity.pfm"), np.where(known, d_true, np.inf))
    valid = np.isfinite(d_sgbm)
    dd = np.abs(d_sgbm - d_true)

    # 2. The truth.
    tau_true = np.exp(-a.beta * range_m(d_true))
    near_edge = near_edges(np.nan_to_num(d_true), 1.0, ~known, a.edge_px) & known
    masks = {
        "all known": known,
        f"near edges ({a.edge_px} px)": near_edge,
        "not near edges": known & ~near_edge,
        f"left band x<{num}": known & (np.arange(W)[None, :] < num),
        "SGBM good (valid, <=3 px off)": known & valid & (dd <= 3),
        "SGBM bad (invalid or >3 px off)": known & ~(valid & (dd <= 3)),
    }

    geometry = ["--depth-kind", "disparity", "--focal", str(FOCAL_PX),
                "--baseline", str(BASELINE_MM), "--disparity-offset", str(OFFSET_PX)]

    def render_args(depth, refine, check):
        return (["render", "--image", left, "--depth", o(depth), "--refine", refine]
                + geometry + (["--right", right] if check else []))

    # 3. τ per condition.
    conds = [("truth", "truth_disparity.pfm", "none", False),
             ("truth +LR", "truth_disparity.pfm", "none", True),
             ("SGBM/none", "sgbm_disparity.pfm", "none", False),
             ("SGBM/none +LR", "sgbm_disparity.pfm", "none", True),
             ("SGBM/guided", "sgbm_disparity.pfm", "guided", False),
             ("SGBM/repair", "sgbm_disparity.pfm", "repair", False),
             ("SGBM/repair +LR", "sgbm_disparity.pfm", "repair", True)]
    errors, results = {}, {"tau_abs_error": {}}
    for label, depth, refine, check in conds:
        tag = label.replace("/", "_").replace(" +", "_").lower()

        def render(airlight, out, depth=depth, refine=refine, check=check):
            run([a.brume] + render_args(depth, refine, check)
                + ["--beta", str(a.beta), "--lambda", "0", "--airlight", airlight, "--out", out])

        t = tau_from_two_airlights(render, lambda A, tag=tag: o(f"tau_{tag}_A{A}.pfm"))
        err = np.where(known, np.abs(t - tau_true), 0.0)
        np.save(o(f"tau_{tag}.npy"), t.astype(np.float32))
        cv2.imwrite(o(f"err_{tag}.png"), np.clip(err * 4 * 255, 0, 255).astype(np.uint8))
        errors[label] = {m: stats(err, v) for m, v in masks.items()}
    results["tau_abs_error"] = errors

    # 4. Foggy images.
    fogs = [("fog_truth.png", "truth_disparity.pfm", "none", False),
            ("fog_sgbm_none.png", "sgbm_disparity.pfm", "none", False),
            ("fog_sgbm_repair.png", "sgbm_disparity.pfm", "repair", False),
            ("fog_sgbm_repair_lr.png", "sgbm_disparity.pfm", "repair", True)]
    for out, depth, refine, check in fogs:
        run([a.brume] + render_args(depth, refine, check)
            + ["--beta", str(a.beta), "--out", o(out)])
    sheet = np.hstack([cv2.imread(o(f[0])) for f in fogs])
    cv2.imwrite(o("fog_side_by_side.png"), sheet)

    results["setup"] = {
        "pair": a.pair, "size": [W, H], "beta": a.beta,
        "geometry": {"focal_px": FOCAL_PX, "baseline_mm": BASELINE_MM, "offset_px": OFFSET_PX},
        "sgbm": {"numDisparities": num, "blockSize": bs, "mode": "SGBM_3WAY"},
        "mask_pixels": {m: int(v.sum()) for m, v in masks.items()},
    }
    results["sgbm_disparity"] = {
        "invalid_fraction_of_known": float((known & ~valid).sum() / known.sum()),
        "bad1_fraction_of_valid": float(((dd > 1) & valid & known).sum() / (valid & known).sum()),
        "bad3_fraction_of_valid": float(((dd > 3) & valid & known).sum() / (valid & known).sum()),
    }
    with open(o("results.json"), "w") as fh:
        json.dump(results, fh, indent=1)

    s = results["sgbm_disparity"]
    print(f"{a.pair}: {W}x{H}, beta {a.beta}/m, truth known at {known.mean():.1%} of pixels")
    print("SGBM: invalid at {:.1%} of known px; bad>1px {:.1%}, bad>3px {:.1%} of valid".format(
        s["invalid_fraction_of_known"], s["bad1_fraction_of_valid"], s["bad3_fraction_of_valid"]))
    print_error_table(42, list(errors), errors, masks)


if __name__ == "__main__":
    main()
