#!/usr/bin/env python3
"""Judge brume's refinement of phone depth: coarse, noisy, with holes, under a street photo with sky.

What it does, in one run:

1. Renders brume's procedural 3D scene (``brume scene --fog none``) at ``--size`` with its
   z-buffer, and from it the TRUE eye depth z and range R (as ``tools/stereo_refine_eval.py``:
   ``z = n·f / (f − d·(f − n))``, ``R = z·|ray|``, focal ``F = (H/2) / tan(fov/2)`` px; one
   scene unit is one metre).
2. Makes a PHONE depth map from it, ``--factor`` times smaller on each side, as an Android
   app saves it (``--format``): ARCore's Depth API (``acquireDepthImage16Bits``: 16-bit PNG,
   millimetres of z-depth, 0 unknown, 65.535 m at most; the default) or Camera2's
   ``DEPTH16`` from a time-of-flight sensor (13 bits of millimetres of range, 8.191 m at most,
   the 3 confidence bits 0: full confidence), or a portrait photo's GDepth (``gdepth``: the
   photo as a JPEG whose XMP holds the z-depth as an 8-bit RangeInverse PNG from 1 m to
   ``--gdepth-far``, which has no "unknown": the model's unknown cells below (the sky, all
   beyond Far, and what the noise takes past it) are at Far; "surfaces without phone
   depth" are the cells at Far), or an iPhone's portrait (``apple-depth``: the photo as a
   JPEG followed by its disparity 1/z as an 8-bit grey JPEG (quality 95) in a Multi-Picture
   Format image, codes 0..255 over 1/``--gdepth-far``..the largest disparity, Apple's
   ``apdi`` and ``depthData`` XMP with ``Accuracy`` relative and the ``IntrinsicMatrix`` of
   ``--fov``, so no ``--fov`` is passed; the unknown cells at code 0, as GDepth's at Far).
   The model (its parameters are options; they are
   assumptions, not measurements of one phone):
   - each cell is the mean depth (z, or range for DEPTH16) of the full-resolution pixels it
     covers (a coarse sensor or a depth-from-motion estimate mixes both sides of an edge:
     "flying pixels");
   - a cell more than half sky, or beyond the format's reach, is unknown (0);
   - the known cells are smoothed by a normalised box of ``--bleed`` cells' radius (dense
     phone depth bleeds across edges; 0 turns it off);
   - multiplicative log-normal noise, σ = ``--noise-base`` + ``--noise-per-m``·z (depth from
     motion or stereo loses precision with distance), seeded by ``--seed``;
   - quantised to millimetres.
3. Measures brume's transmittance per pixel for each ``--refine`` (none = joint bilateral
   upsampling only, the default for both formats; guided; unreliable; repair): ``brume
   render --image left.png --depth phone.png --depth-format arcore --fov FOV --beta B
   --lambda 0`` (``--depth-format android-depth16``, read as range, for DEPTH16),
   run with ``--airlight 0,0,0`` and ``1,1,1``: with λ = 0 nothing is blurred, so
   ``τ = 1 − (out(A=1) − out(A=0))`` exactly. τ_true = exp(−β·R_true), 0 in the sky.
4. Prints |τ − τ_true| (mean and 95th percentile, green channel) over: all pixels; pixels
   within ``--edge-px`` of a truth depth edge (log z jumps by more than 0.05 between
   neighbours, or sky next to a surface); the sky; surfaces away from edges; surfaces whose
   phone depth is unknown (beyond its reach, or mixed with the sky).
5. Renders the foggy image (default airlight and blur) from the true range and from the phone
   depth with each refinement, as PNGs, and the truth beside ``none`` and ``guided``.

Outputs (in OUT_DIR): left.png, left_z.pfm, truth_range.pfm, phone.png (the phone's map),
err_*.png (|τ error| × 4, grey), fog_truth.png, fog_phone_{mode}.png, fog_side_by_side.png,
results.json.

Usage (from the repository root, after ``cargo build --release --bin brume``):

    pip install opencv-python-headless numpy
    python3 tools/phone_depth_eval.py OUT_DIR [--brume target/release/brume]
        [--format arcore|android-depth16|gdepth|apple-depth] [--gdepth-far 10]
        [--gdepth-mime png|jpeg] [--size 1024x512]
        [--factor 8] [--fov 45] [--camera-from flag|exif|none]
        [--beta 0.02] [--position 0,1.7,0]
        [--yaw 0] [--pitch 0] [--roll 0] [--bleed 1] [--noise-base 0.01] [--noise-per-m 0.0015] [--seed 0]
        [--margin PX]  (passed to brume render)
        [--docs DIR]   (also copy fog_truth and fog_phone_none there as refine-phone-*.png)

``--camera-from exif`` needs ExifTool too (Debian: ``libimage-exiftool-perl``). Needs
numpy, OpenCV and the brume binary (headless EGL; llvmpipe is fine). About 10 s at
1024x512 on 2 cores.
"""

import argparse
import base64
import json
import math
import os
import shutil
import struct
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from stereo_refine_eval import (  # noqa: E402
    add_scene_arguments, cv2, near_edges, print_error_table, read_pfm, regions, run, stats,
    tau_from_two_airlights, truth_from_zbuffer)

MODES = ("none", "guided", "unreliable", "repair")
# The most each format holds, in metres: 16 and 13 bits of millimetres (GDepth: --gdepth-far).
REACH_M = {"arcore": 65.535, "android-depth16": 8.191, "gdepth": None, "apple-depth": None}
# The formats whose map has no "unknown": it ends at --gdepth-far.
PORTRAIT = ("gdepth", "apple-depth")
# GDepth's nearest depth (its Near), metres: nearer than anything in the scene.
GDEPTH_NEAR_M = 1.0


def write_pfm(path, a):
    """A float32 grey PFM, little-endian, rows stored bottom to top."""
    h, w = a.shape
    with open(path, "wb") as f:
        f.write(f"Pf\n{w} {h}\n-1.0\n".encode())
        np.flipud(a).astype("<f4").tofile(f)


def cell_mean(z, factor):
    """The mean of the finite values over each factor x factor cell, and the known fraction."""
    h, w = z.shape
    cells = z.reshape(h // factor, factor, w // factor, factor)
    known = np.isfinite(cells)
    total = np.where(known, cells, 0.0).sum(axis=(1, 3))
    count = known.sum(axis=(1, 3))
    mean = np.where(count > 0, total / np.maximum(count, 1), np.nan)
    return mean, count / float(factor * factor)


def box_known(v, radius):
    """The mean over a (2r + 1)² box of the known (finite) values; unknown stays unknown."""
    if radius <= 0:
        return v
    known = np.isfinite(v)
    k = (2 * radius + 1, 2 * radius + 1)
    s = cv2.boxFilter(np.where(known, v, 0.0), -1, k, normalize=False,
                      borderType=cv2.BORDER_CONSTANT)
    n = cv2.boxFilter(known.astype(np.float64), -1, k, normalize=False,
                      borderType=cv2.BORDER_CONSTANT)
    return np.where(known, s / np.maximum(n, 1e-9), np.nan)


def phone_depth(z, a):
    """The phone's depth in metres at 1/factor (NaN unknown), as the docstring models it.
    GDepth has no unknown: what is unknown here is at its Far."""
    reach = a.gdepth_far if a.format in PORTRAIT else REACH_M[a.format]
    mean, known_fraction = cell_mean(z, a.factor)
    mean[(known_fraction <= 0.5) | ~(mean <= reach)] = np.nan
    log_z = box_known(np.log(mean), a.bleed)
    rng = np.random.default_rng(a.seed)
    sigma = a.noise_base + a.noise_per_m * np.exp(log_z)
    noisy = np.exp(log_z + sigma * rng.standard_normal(log_z.shape))
    known = np.isfinite(noisy) & (noisy <= reach)
    if a.format in PORTRAIT:
        return np.where(known, np.maximum(noisy, GDEPTH_NEAR_M), reach)
    return np.where(known, noisy, np.nan)


def write_phone(path, depth_m, fmt):
    """16 bits of millimetres, 0 unknown: all 16 for ARCore, the low 13 for DEPTH16 (its
    confidence bits 0, full confidence)."""
    top = 65535 if fmt == "arcore" else 8191
    mm = np.where(np.isfinite(depth_m), np.clip(np.round(depth_m * 1000.0), 1, top), 0)
    cv2.imwrite(path, mm.astype(np.uint16))


def write_gdepth(path, photo_path, depth_m, far, mime):
    """The photo as a JPEG (quality 95) whose XMP carries the depth as GDepth: 8-bit
    RangeInverse from GDEPTH_NEAR_M to ``far``, along the optical axis, in metres, as a
    PNG or (``mime`` jpeg) a grey JPEG of quality 95
    (https://developers.google.com/depthmap-metadata)."""
    near = GDEPTH_NEAR_M
    d_n = far * (depth_m - near) / (depth_m * (far - near))
    codes = np.round(np.clip(d_n, 0, 1) * 255).astype(np.uint8)
    if mime == "jpeg":
        ok, image = cv2.imencode(".jpg", codes, [cv2.IMWRITE_JPEG_QUALITY, 95])
    else:
        ok, image = cv2.imencode(".png", codes)
    xmp = ('<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF '
           'xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#"><rdf:Description '
           'rdf:about="" xmlns:GDepth="http://ns.google.com/photos/1.0/depthmap/" '
           f'GDepth:Format="RangeInverse" GDepth:Near="{near}" GDepth:Far="{far}" '
           'GDepth:Units="m" GDepth:MeasureType="OpticalAxis" '
           f'GDepth:Mime="image/{mime}" '
           f'GDepth:Data="{base64.b64encode(image.tobytes()).decode()}"/></rdf:RDF></x:xmpmeta>')
    ok, jpeg = cv2.imencode(".jpg", cv2.imread(photo_path), [cv2.IMWRITE_JPEG_QUALITY, 95])
    with open(path, "wb") as f:
        f.write(with_xmp(jpeg.tobytes(), xmp, "GDepth"))


def with_xmp(jpeg, xmp, what):
    """``jpeg`` (bytes) with the XMP packet ``xmp`` in an APP1 segment after its
    start-of-image marker; ``what`` names the packet if it needs extended XMP."""
    payload = b"http://ns.adobe.com/xap/1.0/\x00" + xmp.encode()
    if len(payload) > 65533:
        sys.exit(f"phone_depth_eval: the {what} packet needs extended XMP: use a larger --factor")
    return jpeg[:2] + b"\xff\xe1" + struct.pack(">H", len(payload) + 2) + payload + jpeg[2:]


def write_apple(path, photo_path, depth_m, far, fov, turned):
    """The photo as a JPEG (quality 95; with ``turned``, EXIF Orientation 6 by ExifTool)
    followed by its disparity 1/z as an iPhone stores it: an 8-bit grey JPEG (quality 95),
    codes 0..255 over 1/``far``..the largest disparity, with Apple's XMP (``NativeFormat``
    hdis, ``Accuracy`` relative, the ``IntrinsicMatrix`` of ``fov`` on the stored frame),
    listed by a Multi-Picture Format index (``tools/apple_depth_fixtures.py``)."""
    from apple_depth_fixtures import with_mpf
    disparity = 1.0 / depth_m
    low, high = 1.0 / far, float(disparity.max())
    codes = np.round(np.clip((disparity - low) / (high - low), 0, 1) * 255).astype(np.uint8)
    ok, aux = cv2.imencode(".jpg", codes, [cv2.IMWRITE_JPEG_QUALITY, 95])
    photo = cv2.imread(photo_path)
    h, w = photo.shape[:2]
    # --fov is the upright frame's vertical angle: its height is the stored width if turned.
    f = ((w if turned else h) / 2) / math.tan(math.radians(fov) / 2)
    matrix = "".join(f"<rdf:li>{v}</rdf:li>"
                     for v in (f, 0, 0, 0, f, 0, (w - 1) / 2, (h - 1) / 2, 1))
    xmp = ('<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF '
           'xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#"><rdf:Description '
           'rdf:about="" xmlns:apdi="http://ns.apple.com/pixeldatainfo/1.0/" '
           'xmlns:depthData="http://ns.apple.com/depthData/1.0/">'
           '<apdi:NativeFormat>1751411059</apdi:NativeFormat>'
           '<apdi:IntMinValue>0</apdi:IntMinValue><apdi:IntMaxValue>255</apdi:IntMaxValue>'
           f'<apdi:FloatMinValue>{low:.6f}</apdi:FloatMinValue>'
           f'<apdi:FloatMaxValue>{high:.6f}</apdi:FloatMaxValue>'
           '<depthData:Accuracy>relative</depthData:Accuracy>'
           f'<depthData:IntrinsicMatrixReferenceWidth>{w}</depthData:IntrinsicMatrixReferenceWidth>'
           f'<depthData:IntrinsicMatrixReferenceHeight>{h}</depthData:IntrinsicMatrixReferenceHeight>'
           f'<depthData:IntrinsicMatrix><rdf:Seq>{matrix}</rdf:Seq></depthData:IntrinsicMatrix>'
           '</rdf:Description></rdf:RDF></x:xmpmeta>')
    aux = with_xmp(aux.tobytes(), xmp, "Apple depth")
    ok, primary = cv2.imencode(".jpg", photo, [cv2.IMWRITE_JPEG_QUALITY, 95])
    primary = primary.tobytes()
    if turned:
        plain = path + ".primary.jpg"
        with open(plain, "wb") as fh:
            fh.write(primary)
        run(["exiftool", "-q", "-overwrite_original", "-IFD0:Orientation#=6", plain])
        primary = open(plain, "rb").read()
        os.remove(plain)
    with_mpf(primary, [aux], path, verify=False)


def render_scene(a, W, H, colour_path, zbuffer_path):
    """``brume scene`` at W x H, its colour and z-buffer. With ``--roll``, rendered larger
    at the same focal length and turned about the image's centre (a roll about the optical
    axis of a pinhole camera turns its image and leaves each pixel's eye depth), nearest
    pixel for both so that colour and depth stay one."""
    if a.roll == 0.0:
        W2, H2, fov = W, H, a.fov
    else:
        t = math.radians(abs(a.roll))
        W2 = int(math.ceil(W * math.cos(t) + H * math.sin(t))) + 2
        H2 = int(math.ceil(W * math.sin(t) + H * math.cos(t))) + 2
        focal = (H / 2.0) / math.tan(math.radians(a.fov) / 2.0)
        fov = math.degrees(2.0 * math.atan((H2 / 2.0) / focal))
    big_colour, big_z = colour_path + ".big.png", zbuffer_path + ".big.pfm"
    run([a.brume, "scene", "--fog", "none", "--size", f"{W2}x{H2}", "--yaw", str(a.yaw),
         "--pitch", str(a.pitch), "--fov", str(fov), "--near", str(a.near), "--far",
         str(a.far), "--position", a.position, "--out", big_colour, "--depth-out", big_z])
    # Output pixel (x, y) samples the rendered one at the centre + rot(−roll)·(offset).
    c = math.cos(math.radians(a.roll))
    s = math.sin(math.radians(a.roll))
    cx2, cy2, cx, cy = (W2 - 1) / 2.0, (H2 - 1) / 2.0, (W - 1) / 2.0, (H - 1) / 2.0
    # Image rows grow downward, so a counter-clockwise turn of the camera turns the
    # picture clockwise on the screen.
    m = np.array([[c, -s, cx2 - c * cx + s * cy], [s, c, cy2 - s * cx - c * cy]])
    flags = cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP
    colour = cv2.warpAffine(cv2.imread(big_colour), m, (W, H), flags=flags)
    zbuf = cv2.warpAffine(read_pfm(big_z).astype(np.float32), m, (W, H), flags=flags)
    cv2.imwrite(colour_path, colour)
    write_pfm(zbuffer_path, zbuf)
    os.remove(big_colour)
    os.remove(big_z)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add_scene_arguments(ap)
    ap.add_argument("--format", choices=sorted(REACH_M), default="arcore")
    ap.add_argument("--factor", type=int, default=8, help="the phone depth is this much smaller")
    ap.add_argument("--gdepth-far", type=float, default=10.0,
                    help="--format gdepth or apple-depth: the map's farthest depth (m; GDepth's "
                         "Far); the sky and what lies beyond are at it")
    ap.add_argument("--gdepth-mime", choices=["png", "jpeg"], default="png",
                    help="--format gdepth: the depth image's codec (jpeg: quality 95, lossy)")
    ap.add_argument("--camera-from", choices=["flag", "exif", "none"], default="flag",
                    help="how brume learns the field of view that turns depth into range: "
                         "flag (--fov), exif (as a phone writes the photo: its "
                         "FocalLengthIn35mmFilm, from --fov by the diagonal and rounded to "
                         "the mm, and Orientation 6 with the photo and its depth stored "
                         "turned; written by ExifTool), none (depth used as range). "
                         "apple-depth carries its IntrinsicMatrix: no --fov in any case")
    ap.add_argument("--pitch", type=float, default=0.0)
    ap.add_argument("--roll", type=float, default=0.0,
                    help="the camera turned about its axis (degrees, positive counter-clockwise)")
    ap.add_argument("--bleed", type=int, default=1, help="smoothing radius in cells (0: none)")
    ap.add_argument("--noise-base", type=float, default=0.01, help="relative noise at 0 m")
    ap.add_argument("--noise-per-m", type=float, default=0.0015,
                    help="relative noise added per metre of z")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--edge-px", type=int, default=None, help="[the factor]")
    ap.add_argument("--margin", default=None, help="passed to brume render [its default]")
    ap.add_argument("--docs", default=None)
    a = ap.parse_args()

    os.makedirs(a.out_dir, exist_ok=True)
    o = lambda n: os.path.join(a.out_dir, n)  # noqa: E731
    W, H = (int(v) for v in a.size.lower().split("x"))
    if W % a.factor or H % a.factor:
        sys.exit(f"phone_depth_eval: --size {a.size} is not a multiple of --factor {a.factor}")
    edge_px = a.edge_px if a.edge_px is not None else a.factor
    B = a.brume

    # 1. The photo and the truth.
    render_scene(a, W, H, o("left.png"), o("left_z.pfm"))
    _, sky, z, R_true = truth_from_zbuffer(o("left_z.pfm"), a.fov, a.near, a.far)
    tau_true = np.where(sky, 0.0, np.exp(-a.beta * R_true))
    write_pfm(o("truth_range.pfm"), np.where(sky, np.inf, R_true))

    # 2. The phone's depth, and the photo as the phone stores it: upright, or (--camera-from
    # exif) turned anticlockwise, with the tags that say so and give the focal length.
    measured = R_true if a.format == "android-depth16" else z
    z_phone = phone_depth(np.where(sky, np.nan, measured), a)
    exif = a.camera_from == "exif"
    stored = (lambda img: np.rot90(img, 1).copy()) if exif else (lambda img: img)
    photo_png = o("left.png")
    if exif:
        photo_png = o("left_stored.png")
        cv2.imwrite(photo_png, stored(cv2.imread(o("left.png"))))
    if a.format == "apple-depth":
        write_apple(o("phone.jpg"), photo_png, stored(z_phone), a.gdepth_far, a.fov, exif)
        unknown_full = np.kron(z_phone >= a.gdepth_far, np.ones((a.factor, a.factor), bool))
    elif a.format == "gdepth":
        write_gdepth(o("phone.jpg"), photo_png, stored(z_phone), a.gdepth_far, a.gdepth_mime)
        unknown_full = np.kron(z_phone >= a.gdepth_far, np.ones((a.factor, a.factor), bool))
    else:
        write_phone(o("phone.png"), stored(z_phone), a.format)
        unknown_full = np.kron(~np.isfinite(z_phone), np.ones((a.factor, a.factor), bool))
    if exif and a.format != "apple-depth":
        focal_px = (H / 2) / np.tan(np.radians(a.fov) / 2)
        f35 = int(round(focal_px * np.hypot(36, 24) / np.hypot(W, H)))
        tagged = o("phone.jpg") if a.format == "gdepth" else photo_png
        run(["exiftool", "-q", "-overwrite_original", "-IFD0:Orientation#=6",
             f"-ExifIFD:FocalLengthIn35mmFormat={f35}", tagged])

    surf = ~sky
    # Truth edges: log z jumps by more than 0.05, or sky beside a surface.
    near_edge = near_edges(np.log(np.where(sky, 1.0, z)), 0.05, sky, edge_px)
    masks = regions(near_edge, sky, edge_px, {
        "surfaces without phone depth": surf & unknown_full,
    })

    # 3. τ per refinement.
    prep_opts = [] if a.margin is None else ["--margin", a.margin]

    depth_opts = ["--depth-format", a.format]
    if a.format in ("arcore", "gdepth") and a.camera_from == "flag":
        depth_opts += ["--fov", str(a.fov)]
    # A portrait photo is its own depth file.
    photo, depth = ((o("phone.jpg"), o("phone.jpg")) if a.format in PORTRAIT
                    else (photo_png, o("phone.png")))

    def render(refine, out, extra):
        run([B, "render", "--image", photo, "--depth", depth] + depth_opts
            + ["--beta", str(a.beta), "--refine", refine, "--out", out] + extra + prep_opts)

    results = {"setup": {"format": a.format, "size": [W, H], "factor": a.factor,
                         "fov_deg": a.fov, "camera_from": a.camera_from,
                         "beta": a.beta, "position": a.position, "yaw": a.yaw,
                         "pitch": a.pitch, "roll": a.roll, "bleed": a.bleed,
                         "noise_base": a.noise_base,
                         "noise_per_m": a.noise_per_m, "seed": a.seed,
                         "phone_unknown_fraction": float((~np.isfinite(z_phone)).mean()),
                         "sky_fraction": float(sky.mean()),
                         "mask_pixels": {m: int(v.sum()) for m, v in masks.items()}},
               "tau_abs_error": {}}
    for mode in MODES:
        tau = tau_from_two_airlights(
            lambda A, out: render(mode, out, ["--lambda", "0", "--airlight", A]),
            lambda A: o(f"tau_{mode}_A{A}.pfm"))
        err = np.abs(tau - tau_true)
        cv2.imwrite(o(f"err_{mode}.png"), np.clip(err * 4 * 255, 0, 255).astype(np.uint8))
        results["tau_abs_error"][mode] = {m: stats(err, v) for m, v in masks.items()}

    # 5. Foggy pictures.
    run([B, "render", "--image", o("left.png"), "--depth", o("truth_range.pfm"),
         "--depth-format", "float", "--depth-kind", "range", "--depth-scale", "1", "--beta", str(a.beta),
         "--out", o("fog_truth.png")])
    for mode in MODES:
        render(mode, o(f"fog_phone_{mode}.png"), [])
    sheet = [cv2.imread(o(p)) for p in ("fog_truth.png", "fog_phone_none.png",
                                         "fog_phone_guided.png")]
    cv2.imwrite(o("fog_side_by_side.png"), np.hstack(sheet))
    if a.docs:
        os.makedirs(a.docs, exist_ok=True)
        for mode in ("truth", "phone_none"):
            dst = "refine-phone-" + mode.replace("phone_", "") + ".png"
            shutil.copyfile(o(f"fog_{mode}.png"), os.path.join(a.docs, dst))

    with open(o("results.json"), "w") as fh:
        json.dump(results, fh, indent=1)

    # 4. The table.
    s = results["setup"]
    print(f"scene {W}x{H}, fov {a.fov}°, beta {a.beta}/m; {a.format} depth {W // a.factor}x"
          f"{H // a.factor} (1/{a.factor}), {100 * s['phone_unknown_fraction']:.1f} % unknown, "
          f"bleed {a.bleed}, noise {a.noise_base} + {a.noise_per_m}/m; sky "
          f"{100 * s['sky_fraction']:.1f} %")
    print_error_table(40, MODES, results["tau_abs_error"], masks)


if __name__ == "__main__":
    main()
