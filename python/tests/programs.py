"""The `brume` program the tests compare the package with (shared by the test modules)."""

import os
import shutil
import subprocess
from pathlib import Path

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
