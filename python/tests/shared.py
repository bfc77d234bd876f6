"""What the test modules share: the `brume` program they compare the package with, the
check that calls on several threads give the serial results, and a monocular model's map
of a sky over the ground."""

import os
import shutil
import subprocess
import threading
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]


def brume_bin():
    """$BRUME_BIN, else the newer of the repository's builds, else a release build."""
    given = os.environ.get("BRUME_BIN")
    if given:
        return Path(given)
    # The newer of the two builds: an older one may predate the library this package
    # was built from.
    built = [p for p in (REPO / "target/release/brume", REPO / "target/debug/brume") if p.exists()]
    if built:
        return max(built, key=lambda p: p.stat().st_mtime)
    if shutil.which("cargo") is None:
        pytest.skip("no brume binary (set BRUME_BIN) and no cargo to build it")
    subprocess.run(
        ["nice", "cargo", "build", "--release", "--bin", "brume"], cwd=REPO, check=True
    )
    return REPO / "target/release/brume"


def assert_threads_match_serial(calls):
    """Each zero-argument call run on a thread of its own, all at once, returns what it
    returns when the calls run one after the other."""
    serial = [call() for call in calls]
    results = [None] * len(calls)

    def work(i):
        results[i] = calls[i]()

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(calls))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for a, b in zip(serial, results):
        np.testing.assert_array_equal(a, b)
    return serial


def sky_over_ground(eye, sky_disparity):
    """A photo of a blue sky over striped grass, its top 12 rows the sky, and its relative
    inverse depth as a monocular model writes it: 3 / eye below, `sky_disparity` (an array
    of the width, small and positive, not 0) in the sky."""
    h, w = eye.shape
    image = np.zeros((h, w, 3), np.uint8)
    image[:12] = (150, 180, 240)
    image[12:] = (60, 110, 50)
    image[12:, ::3] = (70, 120, 55)
    disparity = 3.0 / eye
    disparity[:12] = sky_disparity
    return image, disparity
