#!/usr/bin/env python3
"""Judge brume's image-guided depth refinement on real stereo-matcher artefacts (issue 19).

What it does, in one run:

1. Renders a stereo pair of brume's procedural 3D scene with the release binary
   (``brume scene --fog none``): the left view at ``--position``/``--yaw`` and the right view
   with the eye moved by ``--baseline`` scene units along the camera's right vector
   (``(cos yaw, 0, sin yaw)``, src/camera.rs). Both views share their orientation, so the pair
   is rectified (horizontal shift only). The left view's z-buffer (``--depth-out``, OpenGL
   window depth in [0, 1], 1 = sky) gives the TRUE range: eye depth ``z = n·f / (f − d·(f − n))``
   and range ``R = z·|ray|``, ``|ray| = sqrt(1 + ((x − cx)/F)² + ((y − cy)/F)²)``, principal
   point at ((W − 1)/2, (H − 1)/2), ``F = (H/2) / tan(fov/2)`` px. One scene unit is one metre.
2. Runs OpenCV's StereoSGBM (semi-global matching, as Cityscapes' SGM) on the pair and writes
   its disparity as a Cityscapes disparity PNG (uint16, ``p = 256·d + 1``, 0 = invalid) with a
   ``{name}_camera.json`` (baseline in metres, fx = fy = F, u0 = cx, v0 = cy; the mount: z the
   eye's height over the level ground y = 0, pitch down positive, roll 0). The TRUE
   disparity ``F·B/z`` (0 for the sky) is written the same way, for reference.
3. Measures brume's transmittance per pixel for each depth (truth disparity, SGBM disparity)
   and each ``--refine`` (none, guided, unreliable, repair = the default for Cityscapes disparity):
   ``brume render --image left.png --depth … --depth-format cityscapes --beta B --lambda 0``
   is run twice, with ``--airlight 0,0,0`` and ``--airlight 1,1,1``, written as linear PFM.
   With λ = 0 nothing is blurred, so ``out = τ·J + (1 − τ)·A`` and
   ``τ = 1 − (out(A=1) − out(A=0))``, exactly, whatever the colour J. The real left image is
   kept as the colour input because the guided filter uses it as its guide (a white image
   would turn the guided filter into a plain box filter and measure something else).
   τ_true = exp(−β·R_true), 0 in the sky (R = ∞).
4. Prints a table of the absolute τ error |τ − τ_true| (mean and 95th percentile, over the
   green channel, all channels being equal with a grey tint) over: all pixels; pixels within
   5 px (Chebyshev) of a truth depth discontinuity (neighbouring truth disparities differing by
   more than 1 px, or sky next to a surface); the truth sky; the rest (surfaces away from
   edges); the left band where SGBM has no disparity (x < numDisparities); surface pixels where
   SGBM is good (valid and within 3 px of the truth) and where it is bad (invalid or > 3 px
   off), to see what the refinement repairs and what it damages. The SGBM disparity
   itself is summarised too (invalid fraction, bad pixels > 1 px and > 3 px among valid ones).
5. Renders the real-looking foggy image (left view, β, default airlight and λ) from the truth
   disparity (refine none), from SGBM with ``--refine none`` and from SGBM with the default
   guided refinement, as PNGs, plus the three side by side.

Outputs (in OUT_DIR): left.png, right.png, left_z.pfm, truth_disparity.png,
sgbm_disparity.png (+ *_camera.json), tau_*.npy maps (float32), err_*.png (|τ error| × 4, grey),
fog_truth.png, fog_sgbm_none.png, fog_sgbm_guided.png, fog_sgbm_repair.png, fog_side_by_side.png,
results.json.

Usage (from the repository root, after ``cargo build --release --bin brume``):

    pip install opencv-python-headless numpy
    python3 tools/stereo_refine_eval.py OUT_DIR [--brume target/release/brume]
        [--size 1024x512] [--fov 45] [--baseline 0.5] [--beta 0.02]
        [--position 0,1.7,0] [--yaw 0] [--pitch 0] [--num-disparities 144 per 1024 px of width]
        [--refine-radius PX] [--refine-eps EPS] [--seed N]   (passed to brume render)
        [--view left|right] [--read-as left|right]   (the right view's disparity, the
            mirrored pair's SGBM mirrored back, and which view brume is told it is)
        [--docs DIR]   (also copy the four foggy PNGs there as refine-sgbm-{truth,none,guided,repair}.png)

Needs: numpy, opencv-python-headless (``pip install opencv-python-headless numpy``), and the
brume binary (headless EGL; llvmpipe is fine). Takes about 10 s at 1024x512 and 35 s at 2048x1024 on 2 cores (llvmpipe).
"""

import argparse
import json
import math
import os
import shutil
import subprocess
import sys

import numpy as np

try:
    import cv2
except ImportError:  # pragma: no cover
    sys.exit("stereo_refine_eval: needs OpenCV: pip install opencv-python-headless numpy")


def read_pfm(path):
    """A PFM as a float32 array, row 0 at the top (PFM stores rows bottom to top)."""
    with open(path, "rb") as f:
        kind = f.readline().strip()
        w, h = (int(v) for v in f.readline().split())
        scale = float(f.readline())
        data = np.fromfile(f, "<f4" if scale < 0 else ">f4")
    ch = 3 if kind == b"PF" else 1
    img = data.reshape(h, w, ch) if ch == 3 else data.reshape(h, w)
    return np.flipud(img).astype(np.float64)


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        sys.exit(f"stereo_refine_eval: failed ({r.returncode}): {' '.join(cmd)}\n{r.stderr}")
    return r.stdout + r.stderr


def write_cityscapes(path, disp):
    """Cityscapes disparity PNG: p = 256·d + 1 for d > 0, 0 where invalid."""
    p = np.zeros(disp.shape, np.uint16)
    ok = np.isfinite(disp) & (disp > 0)
    p[ok] = np.clip(np.round(256.0 * disp[ok] + 1.0), 1, 65535).astype(np.uint16)
    cv2.imwrite(path, p)


def truth_from_zbuffer(path, fov, near, far):
    """The true eye depth z and range R (inf in the sky) of brume's z-buffer at ``path``
    (OpenGL window depth in [0, 1], 1 = sky), the sky mask and the focal length F in px:
    ``z = n·f / (f − d·(f − n))``, ``R = z·|ray|``, principal point at the image's centre."""
    zbuf = read_pfm(path)
    H, W = zbuf.shape
    F = (H / 2.0) / math.tan(math.radians(fov) / 2.0)
    cx, cy = (W - 1) / 2.0, (H - 1) / 2.0
    sky = zbuf >= 1.0
    z = np.where(sky, np.inf, near * far / (far - zbuf * (far - near)))
    xs, ys = np.meshgrid(np.arange(W), np.arange(H))
    R = z * np.sqrt(1.0 + ((xs - cx) / F) ** 2 + ((ys - cy) / F) ** 2)
    return F, sky, z, R


def near_edges(field, jump, sky, edge_px):
    """Pixels within ``edge_px`` (Chebyshev) of a truth depth edge: 4-neighbours whose
    ``field`` differs by more than ``jump``, or sky beside a surface."""
    e = np.zeros(field.shape, bool)
    jx = (np.abs(np.diff(field, axis=1)) > jump) | (sky[:, 1:] != sky[:, :-1])
    jy = (np.abs(np.diff(field, axis=0)) > jump) | (sky[1:, :] != sky[:-1, :])
    e[:, 1:] |= jx
    e[:, :-1] |= jx
    e[1:, :] |= jy
    e[:-1, :] |= jy
    k = 2 * edge_px + 1
    return cv2.dilate(e.astype(np.uint8), np.ones((k, k), np.uint8)) > 0


def regions(near_edge, sky, edge_px, extra):
    """The regions every evaluation on brume's scene reports (all pixels, those within
    ``edge_px`` of a truth edge, the sky, the surfaces away from edges), then ``extra``."""
    return {
        "all": np.ones(sky.shape, bool),
        f"near edges ({edge_px} px)": near_edge,
        "sky": sky,
        "surfaces, not near edges": ~sky & ~near_edge,
        **extra,
    }


def tau_from_two_airlights(render, path_for):
    """τ (green channel) from two renders without blur, ``render(airlight, out_path)`` with
    airlight 0 and 1: out = τ·J + (1 − τ)·A, so τ = 1 − (out(A=1) − out(A=0)) whatever J."""
    outs = []
    for A in ("0,0,0", "1,1,1"):
        p = path_for(A[0])
        render(A, p)
        outs.append(read_pfm(p)[..., 1])
        os.remove(p)
    return 1.0 - (outs[1] - outs[0])


def print_error_table(width, columns, errors, masks):
    """The |τ − τ_true| table: a row per region of ``masks``, the mean / 95th percentile of
    each entry of ``errors`` (in its order, headed by ``columns``) in turn."""
    print("|tau - tau_true|, mean / 95th percentile, per region (pixels):")
    print(f"{'region':{width}s}" + "".join(f"{c:>18s}" for c in columns))
    for m in masks:
        cells = "".join("{:>9.4f} /{:>7.4f}".format(*e[m][:2]) for e in errors.values())
        print(f"{m + ' (' + str(int(masks[m].sum())) + ')':{width}s}" + cells)


def stats(err, mask):
    e = err[mask]
    if e.size == 0:
        return (float("nan"), float("nan"), 0)
    return (float(e.mean()), float(np.percentile(e, 95)), int(e.size))


def add_scene_arguments(ap):
    """The options every evaluation on brume's rendered scene takes: where it writes, the
    brume binary, the frame, its z-buffer's planes, the fog's β and the camera's place."""
    ap.add_argument("out_dir")
    ap.add_argument("--brume", default="target/release/brume")
    ap.add_argument("--size", default="1024x512")
    ap.add_argument("--fov", type=float, default=45.0)
    ap.add_argument("--near", type=float, default=2.0,
                    help="near plane (m): large enough for a fine z-buffer far away")
    ap.add_argument("--far", type=float, default=1000.0)
    ap.add_argument("--beta", type=float, default=0.02)
    ap.add_argument("--position", default="0,1.7,0")
    ap.add_argument("--yaw", type=float, default=0.0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add_scene_arguments(ap)
    ap.add_argument("--baseline", type=float, default=0.5, help="metres (= scene units)")
    ap.add_argument("--pitch", type=float, default=0.0)
    ap.add_argument("--num-disparities", type=int, default=None,
                    help="SGBM search range, px, a multiple of 16 [144 per 1024 px of width]")
    ap.add_argument("--refine-radius", default=None, help="passed to brume render [its default]")
    ap.add_argument("--refine-eps", default=None, help="passed to brume render [its default]")
    ap.add_argument("--seed", default=None,
                    help="passed to brume render: the hole fill's RANSAC draws [its default]")
    ap.add_argument("--block-size", type=int, default=5)
    ap.add_argument("--right", action="store_true",
                    help="give brume the pair's other view (--right): its left-right check")
    ap.add_argument("--view", choices=("left", "right"), default="left",
                    help="whose disparity brume is given: the right view's is SGBM's on the "
                         "mirrored pair, mirrored back (its occlusions lie right of nearer "
                         "surfaces, its unmatched band at the right border)")
    ap.add_argument("--read-as", choices=("left", "right"), default=None,
                    help="the view brume is told the disparity is of (--stereo-view) "
                         "[--view's]: --view right --read-as left measures a right view "
                         "read as a left one")
    ap.add_argument("--edge-px", type=int, default=5)
    ap.add_argument("--docs", default=None)
    a = ap.parse_args()

    os.makedirs(a.out_dir, exist_ok=True)
    o = lambda n: os.path.join(a.out_dir, n)  # noqa: E731
    W, H = (int(v) for v in a.size.lower().split("x"))
    if a.num_disparities is None:
        a.num_disparities = max(16, int(round(144 * W / 1024 / 16)) * 16)
    refine_opts = []
    if a.refine_radius is not None:
        refine_opts += ["--refine-radius", str(a.refine_radius)]
    if a.refine_eps is not None:
        refine_opts += ["--refine-eps", str(a.refine_eps)]
    if a.seed is not None:
        refine_opts += ["--seed", str(a.seed)]
    B = a.brume

    # 1. The stereo pair and the truth.
    pos = [float(v) for v in a.position.split(",")]
    yaw = math.radians(a.yaw)
    right_vec = (math.cos(yaw), 0.0, math.sin(yaw))
    pos_r = [p + a.baseline * r for p, r in zip(pos, right_vec)]
    common = ["scene", "--fog", "none", "--size", f"{W}x{H}", "--yaw", str(a.yaw),
              "--pitch", str(a.pitch), "--fov", str(a.fov), "--near", str(a.near),
              "--far", str(a.far)]
    run([B] + common + ["--position", ",".join(map(str, pos)), "--out", o("left.png"),
                        "--depth-out", o("left_z.pfm")])
    run([B] + common + ["--position", ",".join(map(str, pos_r)), "--out", o("right.png"),
                        "--depth-out", o("right_z.pfm")])
    view = o(f"{a.view}.png")

    F, sky, z, R_true = truth_from_zbuffer(o(f"{a.view}_z.pfm"), a.fov, a.near, a.far)
    cx, cy = (W - 1) / 2.0, (H - 1) / 2.0
    xs = np.meshgrid(np.arange(W), np.arange(H))[0]
    d_true = np.where(sky, 0.0, F * a.baseline / z)
    tau_true = np.where(sky, 0.0, np.exp(-a.beta * R_true))

    # The mount over the scene's level ground (y = 0) as a car's camera file gives it:
    # height, pitch down positive (brume scene's --pitch is up positive, in degrees).
    cam = {"extrinsic": {"baseline": a.baseline, "z": pos[1],
                         "pitch": -math.radians(a.pitch), "roll": 0.0},
           "intrinsic": {"fx": F, "fy": F, "u0": cx, "v0": cy}}
    for name in ("truth", "sgbm"):
        with open(o(f"{name}_camera.json"), "w") as fh:
            json.dump(cam, fh)
    write_cityscapes(o("truth_disparity.png"), d_true)

    # 2. StereoSGBM.
    L = cv2.imread(o("left.png"), cv2.IMREAD_COLOR)
    Rimg = cv2.imread(o("right.png"), cv2.IMREAD_COLOR)
    bs = a.block_size
    sgbm = cv2.StereoSGBM_create(
        minDisparity=0, numDisparities=a.num_disparities, blockSize=bs,
        P1=8 * 3 * bs * bs, P2=32 * 3 * bs * bs, disp12MaxDiff=1, uniquenessRatio=10,
        speckleWindowSize=100, speckleRange=2, mode=cv2.STEREO_SGBM_MODE_SGBM_3WAY)
    if a.view == "left":
        d_sgbm = sgbm.compute(L, Rimg).astype(np.float64) / 16.0
    else:
        mirrored = sgbm.compute(np.ascontiguousarray(Rimg[:, ::-1]),
                                np.ascontiguousarray(L[:, ::-1]))
        d_sgbm = mirrored[:, ::-1].astype(np.float64) / 16.0
    d_sgbm[d_sgbm <= 0] = 0.0
    write_cityscapes(o("sgbm_disparity.png"), d_sgbm)
    valid = d_sgbm > 0
    surf = ~sky
    dd = np.abs(d_sgbm - d_true)
    disp_stats = {
        "max_true_disparity_px": float(d_true.max()),
        "invalid_fraction_all": float((~valid).mean()),
        "invalid_fraction_surfaces": float((~valid & surf).sum() / surf.sum()),
        "valid_in_sky_fraction_of_sky": float((valid & sky).sum() / max(sky.sum(), 1)),
        "bad1_fraction_valid_surfaces": float(((dd > 1) & valid & surf).sum() / (valid & surf).sum()),
        "bad3_fraction_valid_surfaces": float(((dd > 3) & valid & surf).sum() / (valid & surf).sum()),
    }

    # Masks: truth edges (disparity jump > 1 px or sky/surface), dilated by edge_px.
    near_edge = near_edges(d_true, 1.0, sky, a.edge_px)
    band = xs < a.num_disparities if a.view == "left" else xs >= W - a.num_disparities
    band_name = (f"left band x<{a.num_disparities}" if a.view == "left"
                 else f"right band x>={W - a.num_disparities}")
    masks = regions(near_edge, sky, a.edge_px, {
        band_name: band,
        "SGBM good (valid, <=3 px off)": surf & valid & (dd <= 3),
        "SGBM bad (invalid or >3 px off)": surf & ~(valid & (dd <= 3)),
    })

    # 3. τ per condition.
    def tau_of(depth, refine, tag):
        def render(airlight, out):
            run([B, "render", "--image", view, "--depth", o(depth),
                 "--depth-format", "cityscapes", "--camera",
                 o(depth.replace("_disparity.png", "_camera.json")),
                 "--beta", str(a.beta), "--lambda", "0", "--airlight", airlight,
                 "--refine", refine, "--out", out] + refine_opts + right_opts)
        return tau_from_two_airlights(render, lambda A: o(f"tau_{tag}_A{A}.pfm"))

    other = "right.png" if a.view == "left" else "left.png"
    right_opts = ["--right", o(other)] if a.right else []
    if (a.read_as or a.view) == "right":
        right_opts += ["--stereo-view", "right"]
    conds = [("truth disparity, refine none", "truth_disparity.png", "none", "truth_none"),
             ("truth disparity, refine guided", "truth_disparity.png", "guided", "truth_guided"),
             ("SGBM, refine none", "sgbm_disparity.png", "none", "sgbm_none"),
             ("SGBM, refine guided", "sgbm_disparity.png", "guided", "sgbm_guided"),
             ("SGBM, refine unreliable", "sgbm_disparity.png", "unreliable", "sgbm_unreliable"),
             ("truth disparity, refine repair", "truth_disparity.png", "repair", "truth_repair"),
             ("SGBM, refine repair", "sgbm_disparity.png", "repair", "sgbm_repair")]
    results = {"setup": {"size": [W, H], "fov_deg": a.fov, "focal_px": F,
                         "baseline_m": a.baseline, "beta": a.beta, "position": pos,
                         "yaw": a.yaw, "pitch": a.pitch, "near": a.near, "far": a.far,
                         "view": a.view, "read_as": a.read_as or a.view,
                         "refine_options": refine_opts,
                         "sgbm": {"numDisparities": a.num_disparities, "blockSize": bs,
                                  "mode": "SGBM_3WAY", "uniquenessRatio": 10,
                                  "speckleWindowSize": 100, "speckleRange": 2,
                                  "disp12MaxDiff": 1},
                         "truth_range_m_percentiles_1_50_99": [
                             float(v) for v in np.percentile(R_true[surf], [1, 50, 99])],
                         "sky_fraction": float(sky.mean()),
                         "mask_pixels": {m: int(v.sum()) for m, v in masks.items()}},
               "sgbm_disparity": disp_stats, "tau_abs_error": {}}
    for label, depth, refine, tag in conds:
        t = tau_of(depth, refine, tag)
        err = np.abs(t - tau_true)
        np.save(o(f"tau_{tag}.npy"), t.astype(np.float32))
        cv2.imwrite(o(f"err_{tag}.png"), np.clip(err * 4 * 255, 0, 255).astype(np.uint8))
        results["tau_abs_error"][label] = {m: stats(err, v) for m, v in masks.items()}

    # 5. Real-looking foggy images.
    fogs = [("fog_truth.png", "truth_disparity.png", "none"),
            ("fog_sgbm_none.png", "sgbm_disparity.png", "none"),
            ("fog_sgbm_guided.png", "sgbm_disparity.png", "guided"),
            ("fog_sgbm_repair.png", "sgbm_disparity.png", "repair")]
    for out, depth, refine in fogs:
        run([B, "render", "--image", view, "--depth", o(depth),
             "--depth-format", "cityscapes", "--camera",
             o(depth.replace("_disparity.png", "_camera.json")), "--beta", str(a.beta),
             "--refine", refine, "--out", o(out)] + refine_opts + right_opts)
    sheet = [cv2.imread(o(f)) for f, _, _ in fogs]
    cv2.imwrite(o("fog_side_by_side.png"), np.hstack(sheet))
    if a.docs:
        os.makedirs(a.docs, exist_ok=True)
        for src, dst in (("fog_truth.png", "refine-sgbm-truth.png"),
                         ("fog_sgbm_none.png", "refine-sgbm-none.png"),
                         ("fog_sgbm_guided.png", "refine-sgbm-guided.png"),
                         ("fog_sgbm_repair.png", "refine-sgbm-repair.png")):
            shutil.copyfile(o(src), os.path.join(a.docs, dst))

    with open(o("results.json"), "w") as fh:
        json.dump(results, fh, indent=1)

    # 4. The table.
    print(f"scene {W}x{H}, fov {a.fov}°, F = {F:.1f} px, baseline {a.baseline} m, "
          f"beta {a.beta}/m; truth range p1/p50/p99 = "
          + "/".join(f"{v:.1f}" for v in results["setup"]["truth_range_m_percentiles_1_50_99"])
          + f" m, sky {100 * sky.mean():.1f} %")
    print("SGBM: invalid {:.1%} of all px ({:.1%} of surfaces), valid in {:.1%} of the sky; "
          "bad>1px {:.1%}, bad>3px {:.1%} of valid surface px".format(
              disp_stats["invalid_fraction_all"], disp_stats["invalid_fraction_surfaces"],
              disp_stats["valid_in_sky_fraction_of_sky"],
              disp_stats["bad1_fraction_valid_surfaces"],
              disp_stats["bad3_fraction_valid_surfaces"]))
    short = ["truth/none", "truth/guided", "SGBM/none", "SGBM/guided", "SGBM/unreliable",
             "truth/repair", "SGBM/repair"]
    print_error_table(42, short, results["tau_abs_error"], masks)

if __name__ == "__main__":
    main()
