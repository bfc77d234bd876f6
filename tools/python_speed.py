#!/usr/bin/env python3
"""Per-output time of the Python package against `brume batch` on the same frames.

Issue 20's target: `brume.Renderer().fog` on a 2048x1024 frame within 10 % of
`brume batch`'s per-output time. Both do the same work per output here: one β per frame,
the frame's decode, pre-processing, refinement (`repair`, Cityscapes' default), the fog
with its diffusion blur, and the PNG encode. Batch overlaps decode, pre-processing and
encode with the GPU on its own threads; the plain Python loop does them one after
another, and the threaded one runs two frames at once on one `Renderer`.

With several β (`--beta 0.005,0.01,0.02`, Foggy Cityscapes' three) batch pre-processes and
refines each frame once for all of them; so does the Python loop, which passes the list
(`beta=[...]`). `python_separate_*` is the same loop with one `fog` call per β.

    cargo run --release --example scene_to_cityscapes -- /tmp/frames 3 2048 1024
    python3 tools/python_speed.py /tmp/frames --brume target/release/brume --runs 3

Needs the package installed (`pip install ./python`, a release build) and Pillow.
"""

import argparse
import json
import pathlib
import re
import shutil
import statistics
import subprocess
import tempfile
import time

import numpy as np
from PIL import Image

import brume


def frames(root):
    """(image, disparity, camera) of every Cityscapes frame under root."""
    out = []
    for image in sorted(root.glob("leftImg8bit/*/*/*_leftImg8bit.png")):
        stem = image.name[: -len("_leftImg8bit.png")]
        rel = image.parent.relative_to(root / "leftImg8bit")
        disparity = root / "disparity" / rel / f"{stem}_disparity.png"
        camera = root / "camera" / rel / f"{stem}_camera.json"
        out.append((image, disparity, camera))
    return out


def batch_per_output(brume_bin, root, betas):
    """Wall seconds per output of one `brume batch` run (its own summary line)."""
    with tempfile.TemporaryDirectory() as out:
        run = subprocess.run(
            [brume_bin, "batch", str(root), "--out", out, "--beta", ",".join(map(str, betas))],
            capture_output=True, text=True, check=True)
    m = re.search(r"([0-9.]+) s per output \(wall\)", run.stdout)
    if not m:
        raise SystemExit(f"no per-output time in batch's summary: {run.stdout}")
    return float(m.group(1))


def fog_all(renderer, rgb, range_m, betas, separate=False):
    """The frame's outputs, one per β: one `fog` call with the list, or one call each."""
    if separate:
        return [renderer.fog(rgb, range_m, beta=b, refine="repair") for b in betas]
    return renderer.fog(rgb, range_m, beta=list(betas), refine="repair")


def python_per_output(renderer, items, betas, separate=False):
    """Wall seconds per output of a plain Python loop (decode, fog, encode) and of its
    `Renderer.fog` calls alone."""
    fog_s = 0.0
    with tempfile.TemporaryDirectory() as out:
        started = time.perf_counter()
        for k, (image, disparity, camera) in enumerate(items):
            rgb = np.asarray(Image.open(image).convert("RGB"))
            range_m, _ = brume.load_depth(str(disparity), camera=str(camera))
            t = time.perf_counter()
            outputs = fog_all(renderer, rgb, range_m, betas, separate)
            fog_s += time.perf_counter() - t
            for j, foggy in enumerate(outputs):
                Image.fromarray(foggy).save(pathlib.Path(out) / f"{k}_{j}.png")
        loop_s = time.perf_counter() - started
    n = len(items) * len(betas)
    return loop_s / n, fog_s / n


def python_threaded_per_output(renderer, items, betas, threads):
    """Wall seconds per output of the same loop on `threads` Python threads sharing one
    renderer: one frame's decode, pre-processing and encode overlap another's GPU work."""
    from concurrent.futures import ThreadPoolExecutor

    with tempfile.TemporaryDirectory() as out:
        def one(k):
            image, disparity, camera = items[k]
            rgb = np.asarray(Image.open(image).convert("RGB"))
            range_m, _ = brume.load_depth(str(disparity), camera=str(camera))
            for j, foggy in enumerate(fog_all(renderer, rgb, range_m, betas)):
                Image.fromarray(foggy).save(pathlib.Path(out) / f"{k}_{j}.png")

        started = time.perf_counter()
        with ThreadPoolExecutor(threads) as pool:
            list(pool.map(one, range(len(items))))
        return (time.perf_counter() - started) / (len(items) * len(betas))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("root", type=pathlib.Path, help="Cityscapes-layout frames")
    p.add_argument("--brume", default=shutil.which("brume") or "target/release/brume")
    p.add_argument("--beta", default="0.01", help="one β or a comma list, e.g. 0.005,0.01,0.02")
    p.add_argument("--runs", type=int, default=3)
    args = p.parse_args()
    items = frames(args.root)
    if not items:
        raise SystemExit(f"no *_leftImg8bit.png under {args.root}")
    betas = [float(b) for b in args.beta.split(",")]
    renderer = brume.Renderer()
    python_per_output(renderer, items[:1], betas)  # warm-up: shaders, first context
    batch, python, fog, threaded, separate, separate_fog = [], [], [], [], [], []
    for _ in range(args.runs):
        batch.append(batch_per_output(args.brume, args.root, betas))
        loop_s, fog_s = python_per_output(renderer, items, betas)
        python.append(loop_s)
        fog.append(fog_s)
        threaded.append(python_threaded_per_output(renderer, items, betas, 2))
        if len(betas) > 1:
            loop_s, fog_s = python_per_output(renderer, items, betas, separate=True)
            separate.append(loop_s)
            separate_fog.append(fog_s)
    report = {
        "frames": len(items),
        "betas": betas,
        "size": list(Image.open(items[0][0]).size),
        "renderer": renderer.gl_renderer,
        "batch_s_per_output": batch,
        "python_s_per_output": python,
        "batch_median": statistics.median(batch),
        "python_fog_s_per_output": fog,
        "python_median": statistics.median(python),
        "python_fog_median": statistics.median(fog),
        "python_2_threads_s_per_output": threaded,
        "python_2_threads_median": statistics.median(threaded),
        "ratio": statistics.median(python) / statistics.median(batch),
        "threaded_ratio": statistics.median(threaded) / statistics.median(batch),
        "fog_ratio": statistics.median(fog) / statistics.median(batch),
    }
    if separate:
        report.update(
            python_separate_s_per_output=separate,
            python_separate_fog_s_per_output=separate_fog,
            python_separate_fog_median=statistics.median(separate_fog),
            separate_fog_ratio=statistics.median(separate_fog) / statistics.median(batch),
        )
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
