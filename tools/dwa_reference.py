"""Writes tests/data/exr/aloe-{dwaa,dwab}.exr with OpenEXR's own C++ library (the
`OpenEXR` Python bindings), and beside each the pixels OpenEXR decodes from it
(`.rgb.f32`, raw little-endian float32, rows top first, R G B interleaved), and the
depth written (`aloe.z.f32`, the same layout, one value a pixel), which
tests/io_exr_blocks.rs compares brume's decoder against.

    pip install OpenEXR numpy pillow && python3 tools/dwa_reference.py

The picture is tests/data/aloe (Middlebury 2006 "Aloe"), cropped and downsampled to
70x45 (neither side a multiple of 8, the side of DWA's DCT blocks; 45 rows are two
DWAA blocks, of 32 and 13 lines, and part of one DWAB block of 256): R, G, B as half floats
(linear, lossy in DWA), A = 1 (run-length coded) and Z as float32 (zlib coded, lossless):
depth in metres from the disparity, Z = 3740 px * 0.16 m / (d + 240 px), NaN where
the disparity is unknown (0).
"""
import pathlib

import numpy as np
import OpenEXR
from PIL import Image

ROOT = pathlib.Path(__file__).resolve().parent.parent
ALOE = ROOT / "tests" / "data" / "aloe"
OUT = ROOT / "tests" / "data" / "exr"
SIZE = (70, 45)
BOX = (100, 200, 1100, 843)  # a 1000x643 crop: leaves, pot and cloth


def srgb_to_linear(v):
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def pictures():
    colour = Image.open(ALOE / "left.jpg").convert("RGB").crop(BOX)
    colour = np.asarray(colour.resize(SIZE, Image.BOX), dtype=np.float64) / 255.0
    rgb = srgb_to_linear(colour).astype(np.float16)
    disparity = Image.open(ALOE / "disparity.png").crop(BOX)
    d = np.asarray(disparity.resize(SIZE, Image.NEAREST), dtype=np.float64)
    z = np.where(d > 0, 3740.0 * 0.16 / (d + 240.0), np.nan).astype(np.float32)
    return rgb, z


def main():
    rgb, z = pictures()
    z.astype("<f4").tofile(OUT / "aloe.z.f32")
    channels = {
        "R": rgb[:, :, 0].copy(),
        "G": rgb[:, :, 1].copy(),
        "B": rgb[:, :, 2].copy(),
        "A": np.ones(rgb.shape[:2], dtype=np.float16),
        "Z": z,
    }
    for name, compression in [
        ("dwaa", OpenEXR.DWAA_COMPRESSION),
        ("dwab", OpenEXR.DWAB_COMPRESSION),
    ]:
        header = {"compression": compression, "type": OpenEXR.scanlineimage}
        path = OUT / f"aloe-{name}.exr"
        with OpenEXR.File(header, channels) as f:
            f.write(str(path))
        with OpenEXR.File(str(path), separate_channels=True) as f:
            read = f.channels()
            decoded = np.stack([read[c].pixels for c in "RGB"], axis=-1)
            assert np.array_equal(read["Z"].pixels, z, equal_nan=True), "Z is lossless"
        decoded.astype("<f4").tofile(OUT / f"aloe-{name}.rgb.f32")
        error = np.abs(decoded.astype(np.float64) - rgb.astype(np.float64)).max()
        print(f"{path.name}: {path.stat().st_size} bytes, OpenEXR {OpenEXR.__version__}, "
              f"largest RGB change by the lossy coding {error:.4g}")


if __name__ == "__main__":
    main()
