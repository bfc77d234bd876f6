#!/usr/bin/env python3
"""Foggy Cityscapes' depth completion against brume's `--refine repair`, on a stereo frame.

Foggy Cityscapes (Sakaridis et al., IJCV 2018) completes SGM's disparity by fitting a
plane with RANSAC to the valid pixels of each SLIC superpixel of the image and taking
the plane's depth in the superpixel. This tool reimplements that shape (not its exact
parameters, which the paper gives only in part) on an output folder of
``tools/stereo_refine_eval.py`` and measures it against brume's own pre-processed range:

1. ``brume prep`` of the SGBM disparity (``--refine repair``, Cityscapes' default) and of
   the true disparity, with the image as guide (the range maps, the sky).
2. SLIC superpixels of the left image (scikit-image, ``--segments`` of them, compactness
   10). In each superpixel outside brume's sky with at least 20 valid SGBM pixels (and 30 %
   of its pixels), RANSAC (100 draws, inliers within ``--threshold`` px) fits
   ``d = a + b·x + c·y`` (a plane of the scene is affine in disparity), refitted by least
   squares on its inliers; a fit with fewer than half the valid pixels as inliers is
   dropped. The plane's range ``f·B/d·|ray|`` replaces brume's either in the whole
   superpixel (``everywhere``, as Foggy Cityscapes) or only where SGBM has no value or
   one off the plane (``outliers``); elsewhere brume's range is kept.
3. ``τ = exp(−β·R)`` (0 in brume's sky) against the truth's, mean |τ − τ_true| over the
   frame and over the true surfaces.

Usage (after ``tools/stereo_refine_eval.py OUT``)::

    pip install scikit-image opencv-python-headless numpy
    python3 tools/superpixel_planes.py OUT [--brume target/release/brume]
        [--segments 256,1024,4096] [--threshold 1.0] [--beta 0.02] [--seed 0]
"""

import argparse
import importlib.util
import json
import os
import sys

import numpy as np

try:
    import cv2
    from skimage.segmentation import slic
except ImportError:  # pragma: no cover
    sys.exit("superpixel_planes: pip install scikit-image opencv-python-headless numpy")

HERE = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.util.spec_from_file_location(
    "stereo_refine_eval", os.path.join(HERE, "stereo_refine_eval.py"))
sre = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(sre)


def plane_ranges(image, disp, base, sky, cam, segments, threshold, everywhere, rng):
    """brume's range ``base`` with each fitted superpixel's plane put in (see the docs)."""
    H, W = disp.shape
    f, B = cam["intrinsic"]["fx"], cam["extrinsic"]["baseline"]
    cx, cy = cam["intrinsic"]["u0"], cam["intrinsic"]["v0"]
    ys, xs = np.mgrid[0:H, 0:W]
    ray = np.sqrt(1 + ((xs - cx) / f) ** 2 + ((ys - cy) / f) ** 2)
    labels = slic(image, n_segments=segments, compactness=10, start_label=0)
    out, fitted = base.copy(), 0
    far = base[~sky].max()
    for s in range(labels.max() + 1):
        m = (labels == s) & ~sky
        valid = m & np.isfinite(disp) & (disp > 0)
        if valid.sum() < max(20, 0.3 * m.sum()):
            continue
        vy, vx = np.nonzero(valid)
        A = np.stack([np.ones(len(vx)), vx, vy], 1)
        d = disp[valid]
        best, best_n = None, 0
        for _ in range(100):
            pick = rng.choice(len(d), 3, replace=False)
            try:
                c = np.linalg.solve(A[pick], d[pick])
            except np.linalg.LinAlgError:
                continue
            n = int((np.abs(A @ c - d) < threshold).sum())
            if n > best_n:
                best, best_n = c, n
        if best is None or best_n < 0.5 * len(d):
            continue
        inl = np.abs(A @ best - d) < threshold
        best = np.linalg.lstsq(A[inl], d[inl], rcond=None)[0]
        my, mx = np.nonzero(m)
        dp = best[0] + best[1] * mx + best[2] * my
        R = np.where(dp > 0.05, f * B / np.maximum(dp, 0.05) * ray[my, mx], base[my, mx])
        R = np.minimum(R, far)
        if not everywhere:
            dm = disp[my, mx]
            off = ~(np.isfinite(dm) & (np.abs(dm - dp) < threshold))
            my, mx, R = my[off], mx[off], R[off]
        out[my, mx] = R
        fitted += 1
    return out, fitted


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out_dir", help="an output folder of tools/stereo_refine_eval.py")
    ap.add_argument("--brume", default="target/release/brume")
    ap.add_argument("--segments", default="256,1024,4096")
    ap.add_argument("--threshold", type=float, default=1.0, help="RANSAC inlier, px")
    ap.add_argument("--beta", type=float, default=0.02)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    o = lambda name: os.path.join(a.out_dir, name)  # noqa: E731
    setup = json.load(open(o("results.json")))["setup"]
    _, true_sky, _, R_true = sre.truth_from_zbuffer(
        o("left_z.pfm"), setup["fov_deg"], setup["near"], setup["far"])
    prepared = {}
    for name in ("sgbm", "truth"):
        sre.run([a.brume, "prep", "--depth", o(f"{name}_disparity.png"), "--image",
                 o("left.png"), "--out", o(f"prep_{name}.pfm")])
        prepared[name] = sre.read_pfm(o(f"prep_{name}.pfm"))
    base = prepared["sgbm"]
    sky = base >= 0.999 * base.max()
    image = cv2.imread(o("left.png"))[..., ::-1]
    p = cv2.imread(o("sgbm_disparity.png"), cv2.IMREAD_UNCHANGED).astype(np.float64)
    disp = np.where(p > 0, (p - 1) / 256, np.nan)
    cam = json.load(open(o("sgbm_camera.json")))
    tau_true = np.where(true_sky, 0.0, np.exp(-a.beta * np.where(true_sky, 0.0, R_true)))

    def report(name, R):
        err = np.abs(np.where(sky, 0.0, np.exp(-a.beta * R)) - tau_true)
        print(f"{name:<34} all {err.mean():.4f}  surfaces {err[~true_sky].mean():.4f}")

    report("brume, --refine repair", base)
    for segments in (int(s) for s in a.segments.split(",")):
        for everywhere in (True, False):
            rng = np.random.default_rng(a.seed)
            R, fitted = plane_ranges(image, disp, base, sky, cam, segments, a.threshold,
                                     everywhere, rng)
            where = "everywhere" if everywhere else "outliers"
            report(f"planes, {segments} SLIC, {where} ({fitted})", R)


if __name__ == "__main__":
    main()
