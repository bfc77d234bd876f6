#!/usr/bin/env python3
"""Write the photo-metadata test images of tests/data/colour/ (ICC colour profiles) and
tests/data/exif/ (EXIF), independently of brume.

The ICC profiles are packed here byte by byte from the ICC specification (ICC.1:2001-04,
version 2: header, tag table, ``XYZ``, ``curv``, ``desc``, ``text`` types), not by a colour
library, and each is checked by littleCMS (Pillow's ImageCms) against this script's own
matrix arithmetic before it is used: a profile lcms reads differently fails here. The
PNGs are written by Pillow (``icc_profile=``, an ``iCCP`` chunk).

- ``gamma22-ramp.png``: 16 x 16, pixel i (row-major) = (i, 255 - i, 7 i mod 256), with an
  "Adobe RGB (1998)" profile: Adobe's primaries and D65 white adapted to D50 (Bradford),
  each channel's curve a pure gamma of 563/256 (one ``curv`` entry, u8Fixed8 0x0233).
- ``gamma22-flat.png``: 32 x 8 of (200, 120, 40) with the same profile.
- ``p3-flat.png``: 32 x 8 of (200, 120, 40) with a "Display P3" profile: DCI-P3 primaries,
  D65 white, sRGB's curve as a table of 1024 16-bit entries (as HP's sRGB profile has it).
- ``garbage-icc.png``: 32 x 8 of (200, 120, 40) whose ``iCCP`` chunk holds 200 bytes that
  are no ICC profile.
- ``grey-icc.png``: 32 x 8 of (200, 120, 40), an RGB image carrying a GRAY profile.
- ``profiles.json``: for each profile, the colorants (D50 XYZ, as s15Fixed16 rounds them)
  and the gamma, for tests/colour_profile.rs to compare with what brume writes.

In tests/data/exif/, ExifTool (12.57, Debian's ``libimage-exiftool-perl``) writes the
EXIF of small Pillow images, and reads it back here:

- ``rot6.jpg``: 24 x 16 stored (a gradient), EXIF Orientation 6 (upright 16 x 24), Make,
  Model, DateTimeOriginal, ExifImageWidth/Height 24 x 16, GPS latitude and longitude, and
  an 8 x 6 JPEG thumbnail in IFD1; little-endian (Intel) byte order.
- ``big-endian.png``: 16 x 8, the same tags but the thumbnail and with Orientation 1, in
  a PNG ``eXIf`` chunk, big-endian (Motorola) byte order.
- ``broken.jpg``: ``rot6.jpg``'s pixels with an APP1 ``Exif`` segment whose TIFF block
  is cut inside its first IFD's entries.

Run: ``python3 tools/photo_metadata_fixtures.py tests/data``.
"""

import io
import json
import os
import struct
import subprocess
import sys
import tempfile
import zlib

import numpy as np
from PIL import Image, ImageCms, PngImagePlugin, TiffImagePlugin

D50 = np.array([0.9642, 1.0, 0.8249])
BRADFORD = np.array([[0.8951, 0.2664, -0.1614],
                     [-0.7502, 1.7135, 0.0367],
                     [0.0389, -0.0685, 1.0296]])
ADOBE = [(0.64, 0.33), (0.21, 0.71), (0.15, 0.06)]
P3 = [(0.680, 0.320), (0.265, 0.690), (0.150, 0.060)]
SRGB = [(0.64, 0.33), (0.30, 0.60), (0.15, 0.06)]
D65_XY = (0.3127, 0.3290)
# ACEScg's primaries (AP1) and white (SMPTE ST 2065-1, about D60), as an EXR's
# chromaticities attribute says them.
ACES_AP1 = [(0.713, 0.293), (0.165, 0.830), (0.128, 0.044)]
ACES_WHITE_XY = (0.32168, 0.33767)
GAMMA_U8F8 = 0x0233  # 563/256 = 2.19921875


def xy_to_xyz(x, y):
    return np.array([x / y, 1.0, (1 - x - y) / y])


def rgb_to_xyz_d50(primaries, white_xy=D65_XY):
    """The RGB-to-XYZ matrix of ``primaries`` with a white (D65 unless given), adapted to
    D50 (Bradford), as an ICC profile's colorants hold it (columns: red, green, blue)."""
    white = xy_to_xyz(*white_xy)
    p = np.stack([xy_to_xyz(x, y) for x, y in primaries], axis=1)
    m = p * np.linalg.solve(p, white)
    cone_src, cone_dst = BRADFORD @ white, BRADFORD @ D50
    adapt = np.linalg.inv(BRADFORD) @ np.diag(cone_dst / cone_src) @ BRADFORD
    return adapt @ m


def s15f16(v):
    return struct.pack(">i", int(round(v * 65536)))


def xyz_tag(xyz):
    return b"XYZ \0\0\0\0" + b"".join(s15f16(v) for v in xyz)


def curv_tag(entries):
    return b"curv\0\0\0\0" + struct.pack(">I", len(entries)) + b"".join(
        struct.pack(">H", e) for e in entries)


def desc_tag(text):
    ascii_ = text.encode("ascii") + b"\0"
    return (b"desc\0\0\0\0" + struct.pack(">I", len(ascii_)) + ascii_
            + struct.pack(">II", 0, 0) + struct.pack(">HB", 0, 0) + b"\0" * 67)


def text_tag(text):
    return b"text\0\0\0\0" + text.encode("ascii") + b"\0"


def profile(colour_space, description, tags):
    """An ICC v2 display profile: ``tags`` a list of (signature, data)."""
    tags = [(b"desc", desc_tag(description)), (b"cprt", text_tag("No copyright, test data"))] + tags
    table_size = 4 + 12 * len(tags)
    offset = 128 + table_size
    table, data = struct.pack(">I", len(tags)), b""
    for sig, body in tags:
        body += b"\0" * (-len(body) % 4)
        table += sig + struct.pack(">II", offset + len(data), len(body))
        data += body
    size = 128 + table_size + len(data)
    header = struct.pack(">I", size) + b"\0" * 4 + struct.pack(">I", 0x02100000)
    header += b"mntr" + colour_space + b"XYZ " + struct.pack(">6H", 2026, 12, 5, 0, 0, 0)
    header += b"acsp" + b"\0" * 24 + struct.pack(">I", 0)
    header += b"".join(s15f16(v) for v in D50) + b"\0" * 4 + b"\0" * 16
    header += b"\0" * (128 - len(header))
    return header + table + data


def srgb_curve_table(n=1024):
    x = np.linspace(0, 1, n)
    lin = np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)
    return [int(round(v * 65535)) for v in lin]


def rgb_profile(description, primaries, curve):
    m = rgb_to_xyz_d50(primaries)
    tags = [(b"wtpt", xyz_tag(D50))]
    tags += [(sig, xyz_tag(m[:, k])) for k, sig in enumerate([b"rXYZ", b"gXYZ", b"bXYZ"])]
    tags += [(sig, curv_tag(curve)) for sig in [b"rTRC", b"gTRC", b"bTRC"]]
    return profile(b"RGB ", description, tags), m


def srgb_encode(v):
    v = np.clip(v, 0, 1)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)


def check_with_lcms(icc, m, decode, name):
    """lcms's sRGB rendition of a few colours through ``icc`` against this script's: decode
    by the curve, to XYZ D50 by ``m``, to sRGB by sRGB's own adapted matrix."""
    colours = np.array([[200, 120, 40], [30, 180, 90], [128, 128, 128], [250, 20, 220]],
                       np.uint8)
    src = ImageCms.ImageCmsProfile(io.BytesIO(icc))
    to_srgb = ImageCms.buildTransform(src, ImageCms.createProfile("sRGB"), "RGB", "RGB",
                                      renderingIntent=ImageCms.Intent.RELATIVE_COLORIMETRIC)
    got = np.asarray(ImageCms.applyTransform(Image.fromarray(colours[None]), to_srgb))[0]
    xyz = decode(colours / 255.0) @ m.T
    srgb = np.clip(xyz @ np.linalg.inv(rgb_to_xyz_d50(SRGB)).T, 0, 1)
    want = np.round(srgb_encode(srgb) * 255)
    error = np.abs(got.astype(int) - want).max()
    assert error <= 2, f"{name}: lcms differs by {error} codes:\n{got}\n{want}"


def save(path, pixels, icc):
    Image.fromarray(pixels).save(path, icc_profile=icc)


EXIF_TAGS = ["-Make=brume test", "-Model=fixture", "-DateTimeOriginal=2026:07:14 06:30:00",
             "-GPSLatitude=48.8566", "-GPSLatitudeRef=N", "-GPSLongitude=2.3522",
             "-GPSLongitudeRef=E"]


def exiftool(path, *args):
    subprocess.run(["exiftool", "-q", "-overwrite_original", *args, path], check=True)


def read_back(path):
    out = subprocess.run(["exiftool", "-j", "-n", "-a", "-G1", path], check=True,
                         capture_output=True).stdout
    return json.loads(out)[0]


def exif_fixtures(out_dir):
    os.makedirs(out_dir, exist_ok=True)
    y, x = np.mgrid[0:16, 0:24]
    stored = np.stack([x * 10, y * 15, np.full_like(x, 128)], axis=2).astype(np.uint8)
    rot6 = os.path.join(out_dir, "rot6.jpg")
    Image.fromarray(stored).save(rot6, quality=95)
    with tempfile.TemporaryDirectory() as tmp:
        thumb = os.path.join(tmp, "thumb.jpg")
        Image.fromarray(stored[::2, ::3]).save(thumb, quality=80)
        exiftool(rot6, "-ExifByteOrder=Little-endian", "-IFD0:Orientation#=6",
                 "-ExifImageWidth=24", "-ExifImageHeight=16", f"-ThumbnailImage<={thumb}",
                 *EXIF_TAGS)
    tags = read_back(rot6)
    assert tags["IFD0:Orientation"] == 6 and tags["ExifIFD:ExifImageWidth"] == 24, tags
    assert "IFD1:ThumbnailImage" in tags and tags["GPS:GPSLatitude"] > 48.8, tags

    png = os.path.join(out_dir, "big-endian.png")
    Image.fromarray(stored[:8, :16]).save(png)
    exiftool(png, "-ExifByteOrder=Big-endian", "-IFD0:Orientation#=1",
             "-ExifImageWidth=16", "-ExifImageHeight=8", *EXIF_TAGS)
    tags = read_back(png)
    assert tags["ExifIFD:DateTimeOriginal"] == "2026:07:14 06:30:00", tags

    # The TIFF block cut inside IFD0's entries, its APP1 segment shortened to match.
    data = open(rot6, "rb").read()
    at = data.index(b"Exif\0\0")
    length = struct.unpack(">H", data[at - 2:at])[0]
    tiff_at = at + 6
    ifd0 = struct.unpack("<I", data[tiff_at + 4:tiff_at + 8])[0]
    cut = ifd0 + 2 + 5
    broken = (data[:at - 2] + struct.pack(">H", 2 + 6 + cut) + data[at:tiff_at + cut]
              + data[at - 2 + length:])
    open(os.path.join(out_dir, "broken.jpg"), "wb").write(broken)


def fixed(v):
    """A PNG chunk's unsigned number of 1/100000 (gAMA, cHRM)."""
    return struct.pack(">I", round(v * 100000))


def png_colour_chunk_fixtures(out_dir, ramp, flat, adobe):
    """PNGs stating their colour space by chunks other than iCCP; Pillow writes each chunk
    (with its CRC) before the image data, as given."""
    def save_with(name, pixels, chunks, icc=None):
        info = PngImagePlugin.PngInfo()
        for kind, data in chunks:
            info.add(kind, data)
        path = os.path.join(out_dir, name)
        Image.fromarray(pixels).save(path, pnginfo=info, icc_profile=icc)
        held = Image.open(path)
        held.load()
        if any(kind == b"gAMA" for kind, _ in chunks):
            assert abs(held.info["gamma"] - struct.unpack(">I", dict(chunks)[b"gAMA"])[0]
                       / 100000) < 1e-9, name
    srgb_chrm = b"".join(fixed(v) for v in (0.3127, 0.329, 0.64, 0.33, 0.3, 0.6, 0.15, 0.06))
    p3_chrm = b"".join(fixed(v) for v in (0.3127, 0.329, 0.68, 0.32, 0.265, 0.69, 0.15, 0.06))
    save_with("gama-linear-ramp.png", ramp, [(b"gAMA", fixed(1.0))])
    save_with("gama-srgb-flat.png", flat, [(b"gAMA", fixed(1 / 2.2)), (b"cHRM", srgb_chrm)])
    save_with("chrm-p3-flat.png", flat, [(b"gAMA", fixed(1 / 2.2)), (b"cHRM", p3_chrm)])
    save_with("cicp-p3-flat.png", flat, [(b"cICP", bytes([12, 13, 0, 1]))])
    save_with("cicp-linear-ramp.png", ramp, [(b"cICP", bytes([1, 8, 0, 1])),
                                             (b"gAMA", fixed(1 / 2.2))], adobe)
    save_with("cicp-pq-flat.png", flat, [(b"cICP", bytes([9, 16, 0, 1]))])
    linear16_fixture(out_dir)
    webp_fixtures(out_dir, ramp, adobe)
    tiff_fixtures(out_dir, ramp, adobe)


def webp_fixtures(out_dir, ramp, adobe):
    """The gamma-2.2 ramp as a lossless WebP with its profile, and turned by EXIF
    Orientation 6: Pillow (libwebp) writes both, and reads the pixels back exactly."""
    exif = Image.Exif()
    exif[0x0112] = 6
    path = os.path.join(out_dir, "gamma22-ramp.webp")
    Image.fromarray(ramp).save(path, lossless=True, icc_profile=adobe, exif=exif.tobytes())
    held = Image.open(path)
    assert np.array_equal(np.asarray(held.convert("RGB")), ramp), "lossless"
    assert held.info["icc_profile"] == adobe and held.getexif()[0x0112] == 6


def tiff_fixtures(out_dir, ramp, adobe):
    """The gamma-2.2 ramp as an LZW TIFF with its profile and Orientation 6 (Pillow, as raw
    converters write photos); the 16-bit ramp as a 16-bit RGB TIFF, and four times it over
    65535 as a float32 RGB TIFF (linear light above 1, as HDR merges write), both by OpenCV,
    whose TIFF writer (libtiff) is not the crate brume reads with."""
    import cv2

    ifd = TiffImagePlugin.ImageFileDirectory_v2()
    ifd[0x0112] = 6
    path = os.path.join(out_dir, "gamma22-ramp.tif")
    Image.fromarray(ramp).save(path, compression="tiff_lzw", icc_profile=adobe, tiffinfo=ifd)
    held = Image.open(path)
    assert held.info["icc_profile"] == adobe and held.tag_v2[0x0112] == 6
    # Pillow turns a TIFF upright as it loads it: 90° clockwise for Orientation 6.
    assert np.array_equal(np.asarray(held.convert("RGB")), np.rot90(ramp, -1)), "lossless"
    pixels = ramp16()
    for name, data in (("ramp16.tif", pixels),
                       ("ramp-float.tif", (pixels / 65535.0 * 4.0).astype(np.float32))):
        path = os.path.join(out_dir, name)
        assert cv2.imwrite(path, data[:, :, ::-1])
        back = cv2.imread(path, cv2.IMREAD_UNCHANGED)[:, :, ::-1]
        assert back.dtype == data.dtype and np.array_equal(back, data), name


def png_chunk(kind, data):
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def ramp16():
    """The 16 x 16 ramp at 16 bits: pixel i = (257 i - i mod 7, 65535 - 257 i, 4099 i mod
    65536), codes that no 8-bit value gives."""
    i = np.arange(256, dtype=np.int64)
    rgb = np.stack([257 * i - i % 7, 65535 - 257 * i, (4099 * i) % 65536], axis=1)
    assert rgb.min() >= 0 and rgb.max() <= 65535
    return rgb.astype(np.uint16).reshape(16, 16, 3)


def linear16_fixture(out_dir):
    """A 16-bit RGB PNG of linear light (gAMA 1.0), packed here (Pillow writes no 16-bit
    RGB) and read back by OpenCV, whose decoder is not the one brume uses."""
    pixels = ramp16()
    h, w, _ = pixels.shape
    rows = b"".join(b"\0" + pixels[y].astype(">u2").tobytes() for y in range(h))
    png = (b"\x89PNG\r\n\x1a\n"
           + png_chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 2, 0, 0, 0))
           + png_chunk(b"gAMA", fixed(1.0))
           + png_chunk(b"IDAT", zlib.compress(rows, 9))
           + png_chunk(b"IEND", b""))
    path = os.path.join(out_dir, "gama-linear-ramp16.png")
    with open(path, "wb") as f:
        f.write(png)
    import cv2
    back = cv2.imread(path, cv2.IMREAD_UNCHANGED)[..., ::-1]
    assert back.dtype == np.uint16 and np.array_equal(back, pixels), "OpenCV reads it back"


def main(data_dir):
    exif_fixtures(os.path.join(data_dir, "exif"))
    out_dir = os.path.join(data_dir, "colour")
    os.makedirs(out_dir, exist_ok=True)
    gamma = GAMMA_U8F8 / 256
    adobe, m_adobe = rgb_profile("Adobe RGB (1998) test", ADOBE, [GAMMA_U8F8])
    check_with_lcms(adobe, m_adobe, lambda c: c ** gamma, "gamma 2.2")
    p3, m_p3 = rgb_profile("Display P3 test", P3, srgb_curve_table())
    check_with_lcms(p3, m_p3, lambda c: np.where(c <= 0.04045, c / 12.92,
                                                 ((c + 0.055) / 1.055) ** 2.4), "P3")
    grey = profile(b"GRAY", "Grey gamma 2.2 test", [(b"wtpt", xyz_tag(D50)),
                                                    (b"kTRC", curv_tag([GAMMA_U8F8]))])
    ImageCms.ImageCmsProfile(io.BytesIO(grey))  # lcms reads it

    i = np.arange(256)
    ramp = np.stack([i, 255 - i, (7 * i) % 256], axis=1).astype(np.uint8).reshape(16, 16, 3)
    flat = np.zeros((8, 32, 3), np.uint8)
    flat[:] = (200, 120, 40)
    save(os.path.join(out_dir, "gamma22-ramp.png"), ramp, adobe)
    save(os.path.join(out_dir, "gamma22-flat.png"), flat, adobe)
    save(os.path.join(out_dir, "p3-flat.png"), flat, p3)
    garbage = np.random.default_rng(5).integers(0, 256, 200, dtype=np.uint8).tobytes()
    save(os.path.join(out_dir, "garbage-icc.png"), flat, garbage)
    save(os.path.join(out_dir, "grey-icc.png"), flat, grey)
    # Pillow gives back each profile as written.
    for name, icc in [("gamma22-flat.png", adobe), ("p3-flat.png", p3),
                      ("garbage-icc.png", garbage), ("grey-icc.png", grey)]:
        assert Image.open(os.path.join(out_dir, name)).info["icc_profile"] == icc, name
    png_colour_chunk_fixtures(out_dir, ramp, flat, adobe)
    quantised = lambda m: [[round(v * 65536) / 65536 for v in m[:, k]] for k in range(3)]
    with open(os.path.join(out_dir, "profiles.json"), "w") as f:
        json.dump({
            "gamma22": {"gamma": gamma, "colorants": quantised(m_adobe)},
            "p3": {"colorants": quantised(m_p3)},
            "srgb": {"colorants": quantised(rgb_to_xyz_d50(SRGB))},
            "acescg": {"colorants": quantised(rgb_to_xyz_d50(ACES_AP1, ACES_WHITE_XY))},
        }, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "tests/data")
