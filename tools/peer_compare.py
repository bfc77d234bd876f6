#!/usr/bin/env python3
"""Time brume's uniform blur against two widely used CPU Gaussian filters, in one run.

On the same machine, image size (default 1600x1120, 4-channel float32) and scales
(default sigma = 5 and 25):

* OpenCV ``cv2.GaussianBlur(img, (0, 0), sigmaX=s, sigmaY=s, borderType=BORDER_REPLICATE)``
* SciPy ``scipy.ndimage.gaussian_filter(img, sigma=(s, s, 0), mode='nearest')``
* ``brume bench speed --sigmas 5,25 --schemes matched --precisions f32 --json --size WxH
  --coarse-from 2`` (``--coarse-from off``: the paper's full-resolution pipeline)

Each peer is run once as a warm-up, then timed ``--runs`` times (default 5); the median is
reported. brume reports its own median (GL_TIME_ELAPSED where available: see its clock).
The image is tests/data/aloe/left.jpg (in this repository) resized to the size (linear
light), or random values if that file or OpenCV's decoder is missing; the content does
not change the time of either method.

Usage:  python3 tools/peer_compare.py [BRUME_BINARY] [--size 1600x1120] [--sigmas 5,25]
        python3 tools/peer_compare.py --brume-json FILE   (parse a saved brume JSON)

Requirements: tools/requirements.txt (numpy, scipy, opencv-python-headless).
"""

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

NOTE = (
    "brume's figure is its space-variant machinery (per-pixel rates and offsets, "
    "N+2 GPU passes) run with a uniform sigma; the peers are uniform-only separable "
    "filters on the CPU. The ratio is what the generality costs (or saves) on this "
    "machine, not a like-for-like filter comparison."
)
# Found from the script itself, so that the tool works from any directory and any clone.
ALOE = Path(__file__).resolve().parent.parent / "tests/data/aloe/left.jpg"


def fail(message):
    """Print one clear error line and exit with status 2."""
    print(f"peer_compare: error: {message}", file=sys.stderr)
    sys.exit(2)


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "brume",
        nargs="?",
        default="target/release/brume",
        help="path to the brume binary (default: target/release/brume)",
    )
    p.add_argument("--size", default="1600x1120", help="image size WxH (default 1600x1120)")
    p.add_argument("--sigmas", default="5,25", help="comma list of sigma in px (default 5,25)")
    p.add_argument("--runs", type=int, default=5, help="timed runs after a warm-up (default 5)")
    p.add_argument(
        "--coarse-from",
        metavar="PX|off",
        default="2",
        help="brume's coarse to fine (steps at half resolution once the blur has reached PX; "
        "a sigma of 10 px or more starts at step 0): default 2, as `brume render`; off runs "
        "the paper's full-resolution pipeline, `brume bench speed`'s default",
    )
    p.add_argument(
        "--brume-json",
        metavar="FILE",
        help="use this saved `brume bench speed --json` output instead of running brume",
    )
    args = p.parse_args(argv)
    try:
        w, h = (int(v) for v in args.size.lower().split("x"))
        sigmas = [float(s) for s in args.sigmas.split(",")]
    except ValueError:
        fail(f"bad --size {args.size!r} or --sigmas {args.sigmas!r}")
    if w < 1 or h < 1 or not sigmas or min(sigmas) <= 0 or args.runs < 1:
        fail("--size must be positive, --sigmas non-empty and > 0, --runs >= 1")
    args.width, args.height, args.sigma_list = w, h, sigmas
    return args


def import_peers():
    """numpy, scipy.ndimage and cv2, or a clear message saying how to install them."""
    try:
        import numpy as np
        import scipy.ndimage as ndi
        import cv2
    except ImportError as e:
        fail(f"{e}; install the peers with: pip install -r tools/requirements.txt")
    return np, ndi, cv2


def test_image(np, cv2, width, height):
    """(image HxWx4 float32, description): Aloe resized in linear light, or noise."""
    bgr = cv2.imread(str(ALOE), cv2.IMREAD_COLOR) if ALOE.is_file() else None
    if bgr is None:
        rng = np.random.default_rng(1)
        return rng.random((height, width, 4), dtype=np.float32), "random (Aloe not found)"
    srgb = bgr[:, :, ::-1].astype(np.float32) / 255.0
    linear = np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)
    resized = cv2.resize(linear.astype(np.float32), (width, height), interpolation=cv2.INTER_AREA)
    rgba = np.concatenate([resized, np.ones((height, width, 1), np.float32)], axis=2)
    return np.ascontiguousarray(rgba), "tests/data/aloe/left.jpg resized"


def time_median(fn, runs):
    """Median wall time (ms) of `runs` calls after one warm-up call."""
    fn()
    samples = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        samples.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(samples)


def time_peers(np, ndi, cv2, img, sigmas, runs):
    """{sigma: {"opencv": ms, "scipy": ms}}."""
    out = {}
    for s in sigmas:
        out[s] = {
            "opencv": time_median(
                lambda: cv2.GaussianBlur(
                    img, (0, 0), sigmaX=s, sigmaY=s, borderType=cv2.BORDER_REPLICATE
                ),
                runs,
            ),
            "scipy": time_median(
                lambda: ndi.gaussian_filter(img, sigma=(s, s, 0), mode="nearest"), runs
            ),
        }
    return out


def run_brume(binary, args):
    """The JSON object printed by `brume bench speed ... --json`."""
    if shutil.which(binary) is None and not os.access(binary, os.X_OK):
        fail(
            f"brume binary {binary!r} not found or not executable; build it with "
            "`cargo build --release` or pass its path as the first argument"
        )
    cmd = [
        binary,
        "bench",
        "speed",
        "--sigmas",
        ",".join(f"{s:g}" for s in args.sigma_list),
        "--schemes",
        "matched",
        "--precisions",
        "f32",
        "--json",
        "--size",
        f"{args.width}x{args.height}",
        "--runs",
        str(args.runs),
    ]
    if args.coarse_from != "off":
        cmd += ["--coarse-from", str(args.coarse_from)]
    print("running: " + " ".join(cmd), file=sys.stderr)
    done = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if done.returncode != 0:
        fail(f"{' '.join(cmd)} exited with {done.returncode}:\n{done.stderr.strip()}")
    return parse_brume_json(done.stdout, " ".join(cmd))


def parse_brume_json(text, source):
    """Checks the fields this script relies on and returns the parsed report."""
    try:
        report = json.loads(text)
    except json.JSONDecodeError as e:
        fail(f"{source}: not one JSON object ({e})")
    if report.get("benchmark") != "speed" or not isinstance(report.get("rows"), list):
        fail(f"{source}: not a `brume bench speed --json` report")
    for key in ("renderer", "clock", "width", "height"):
        if key not in report:
            fail(f"{source}: missing field {key!r}")
    return report


def brume_medians(report):
    """{sigma: (median ms, clock)} of the matched/f32 rows that ran."""
    out = {}
    for row in report["rows"]:
        if row.get("scheme") == "matched" and row.get("precision") == "f32":
            if not row.get("skipped") and row.get("median_ms") is not None:
                out[float(row["sigma_ref"])] = (row["median_ms"], row.get("clock"))
    return out


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def pipeline_label(args, report):
    """Which of brume's pipelines the report timed: read from its pass names (a coarse
    stage has `down` passes), so that a saved report (--brume-json) is not labelled with
    this run's --coarse-from; the scale itself is known only when brume ran here."""
    coarse = any(
        name.startswith("down")
        for row in report["rows"]
        for name in row.get("pass_names") or []
    )
    if not coarse:
        return " (full resolution)"
    if args.brume_json:
        return " (coarse to fine)"
    return f" --coarse-from {args.coarse_from}"


def markdown(args, img_desc, peers, report, versions):
    brume = brume_medians(report)
    coarse = pipeline_label(args, report)
    lines = [
        f"Machine: {cpu_model()}, nproc = {os.cpu_count()}; "
        f"brume renderer: {report['renderer']}, clock: {report['clock']}",
        f"Image: {args.width}x{args.height}, 4-channel float32 ({img_desc}); "
        f"median of {args.runs} runs after a warm-up; {versions}",
        "",
        f"| σ (px) | brume matched f32{coarse} (ms) | OpenCV GaussianBlur (ms) "
        "| SciPy gaussian_filter (ms)"
        " | OpenCV / brume | SciPy / brume |",
        "| ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for s in args.sigma_list:
        b = brume.get(s)
        cv, sp = peers[s]["opencv"], peers[s]["scipy"]
        if b is None:
            lines.append(f"| {s:g} | (not run) | {cv:.1f} | {sp:.1f} | - | - |")
        else:
            ms = b[0]
            lines.append(
                f"| {s:g} | {ms:.1f} | {cv:.1f} | {sp:.1f} | {cv / ms:.2f}x | {sp / ms:.2f}x |"
            )
    lines += [
        "",
        "Ratios are peer time / brume time: above 1, brume is faster.",
        f"Note: {NOTE}",
    ]
    return "\n".join(lines)


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    # Cheap checks first (imports, binary), so that nothing long runs before a failure.
    np, ndi, cv2 = import_peers()
    import scipy

    if args.brume_json:
        with open(args.brume_json) as f:
            report = parse_brume_json(f.read(), args.brume_json)
    else:
        report = run_brume(args.brume, args)
    if (report["width"], report["height"]) != (args.width, args.height):
        fail(
            f"brume's report is {report['width']}x{report['height']} but --size is "
            f"{args.width}x{args.height}: compare at one size"
        )

    img, desc = test_image(np, cv2, args.width, args.height)
    peers = time_peers(np, ndi, cv2, img, args.sigma_list, args.runs)
    versions = (
        f"OpenCV {cv2.__version__} ({cv2.getNumThreads()} threads), "
        f"SciPy {scipy.__version__} (1 thread), NumPy {np.__version__}"
    )
    print(markdown(args, desc, peers, report, versions))


if __name__ == "__main__":
    main()
