#!/usr/bin/env python3
"""Write the GDepth test JPEGs of tests/data/gdepth/ with ExifTool, a writer independent of brume.

Each file is a small synthetic colour JPEG whose XMP carries Google's depth map metadata
(https://developers.google.com/depthmap-metadata), written by ExifTool's XMP-GDepth tags
(``-XMP-GDepth:DepthImage<=depth.png`` base64-encodes the PNG into ``GDepth:Data``; a packet
over 64 KB goes into extended XMP segments, as Adobe's XMP specification part 3 says).
The depth encoded is a plane, so that tests/io_gdepth.rs can check brume's reading
against the specification's formulas without a second file:

- ``inv8.jpg``: 64 x 48 photo, 32 x 24 8-bit PNG, RangeInverse, Near 1.5 Far 20.75, no
  Units (metres), no MeasureType (optical axis); depth d = 1.5 + 0.25 x + 0.5 y m.
- ``lin16.jpg``: the same photo and plane, 16-bit PNG, RangeLinear, Near 1500 Far 20750,
  Units mm, MeasureType OpticRay (range).
- ``conf8.jpg``: ``inv8.jpg`` with a confidence map (``GDepth:Confidence``, a PNG of the
  same size: 255 (1.0) in the left half, 64 (0.251) in the right).
- ``conf-low.jpg``: ``inv8.jpg`` with a confidence map of 64 (0.251) everywhere, which a
  ``--min-confidence`` above it leaves no sample of.
- ``inv8-jpeg.jpg``: ``inv8.jpg``'s map as a grey JPEG of quality 100 (``Mime``
  image/jpeg): lossy, each code within one of the PNG's (checked here); its plane reaches
  Far, no clamp.
- ``far8-jpeg.jpg``: a map clamped at Far as a portrait mode writes it, as a grey JPEG of
  quality 100: the top 6 rows at Far (the sky), below them d = 1.5 + 0.2 x + 0.4 (y − 6) m
  (codes up to 247); the JPEG moves some of the Far samples off it by one (checked here).
- ``ext8.jpg``: ``inv8.jpg`` with its ``GDepth:Data`` moved by this script (not ExifTool)
  into an extended packet of two segments written in reverse order, the GUID in an
  element whose start tag declares its namespace: what a reader must accept beyond
  ExifTool's layout.
- ``dd8.jpg``: the small photo in Android's Dynamic Depth layout: ExifTool writes the
  XMP (``XMP-Device``: a ``Container:Directory`` of the primary image, length 0, a
  confidence PNG and the depth PNG, with their lengths and ``DataURI``; a camera's
  ``DepthMap`` with ``inv8.jpg``'s Format, Near and Far, ``Units`` Meters and its
  ``DepthURI``, and its ``ImagingModel``: focal lengths 60 and 62 px of the 64 x 48
  photo, principal point 0.45, 0.55), then this script appends the two PNGs after the
  JPEG in that order.
- ``rot6.jpg`` and ``dd8-rot6.jpg``: ``inv8.jpg`` and ``dd8.jpg`` with an EXIF
  Orientation of 6 (turned 90° clockwise to show: a phone held upright) that ExifTool
  adds, the depth left as stored, as phones write it (ExifTool keeps the Dynamic Depth
  items appended after the JPEG).
- ``f26.jpg``: ``rot6.jpg`` with ``FocalLengthIn35mmFormat`` 26 (EXIF 0xA405) that ExifTool
  adds: the focal length that turns its depth into range.
- ``f26-crop.jpg``: ``f26.jpg`` whose EXIF also says the camera wrote 4032 x 2268 (16:9),
  another aspect ratio than its 64 x 48: a crop, whose focal length is not used.
- ``ext16.jpg``: 320 x 240 photo, 320 x 240 16-bit PNG, RangeInverse, Near 2 Far 42, the
  plane d = 2 + 0.05 x + 0.1 y m plus up to 1 cm of seeded noise (which keeps the PNG
  from compressing, so that the XMP needs extended segments).

d_n = Far (d − Near) / (d (Far − Near)) for RangeInverse, (d − Near) / (Far − Near) for
RangeLinear; the sample is round(d_n (2^bits − 1)).

Usage (Debian: ``apt install libimage-exiftool-perl``; ``pip install numpy opencv-python-headless``):

    python3 tools/gdepth_fixtures.py tests/data/gdepth
"""

import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile

import cv2
import numpy as np


def photo(w, h, path):
    ys, xs = np.mgrid[0:h, 0:w]
    rgb = np.stack([40 + 160 * xs // w, 60 + 120 * ys // h, 200 - 160 * xs // w], -1)
    cv2.imwrite(path, rgb.astype(np.uint8)[:, :, ::-1], [cv2.IMWRITE_JPEG_QUALITY, 85])


def samples(d, near, far, inverse, bits):
    d_n = far * (d - near) / (d * (far - near)) if inverse else (d - near) / (far - near)
    assert d_n.min() >= 0 and d_n.max() <= 1, "the plane is within Near..Far"
    top = 2**bits - 1
    return np.round(d_n * top).astype(np.uint8 if bits == 8 else np.uint16)


def embed(src, out, depth_png, tags, mime="image/png"):
    shutil.copy(src, out)
    args = ["exiftool", "-q", "-overwrite_original"] + [f"-XMP-GDepth:{t}" for t in tags]
    args += [f"-XMP-GDepth:Mime={mime}", f"-XMP-GDepth:DepthImage<={depth_png}", out]
    subprocess.run(args, check=True)


XMP = b"http://ns.adobe.com/xap/1.0/\x00"
EXTENDED = b"http://ns.adobe.com/xmp/extension/\x00"
GUID = b"0123456789ABCDEF0123456789ABCDEF"


def segment(marker, payload):
    return bytes([0xFF, marker]) + struct.pack(">H", len(payload) + 2) + payload


def split_data(src, out):
    """Rewrites ``src`` with its GDepth:Data in two extended segments, the second first."""
    jpeg = open(src, "rb").read()
    i, parts = 2, [b"\xff\xd8"]
    while jpeg[i + 1] != 0xDA:
        marker = jpeg[i + 1]
        length = struct.unpack(">H", jpeg[i + 2:i + 4])[0]
        payload = jpeg[i + 4:i + 2 + length]
        i += 2 + length
        if marker != 0xE1 or not payload.startswith(XMP):
            parts.append(segment(marker, payload))
            continue
        xmp = payload[len(XMP):].decode()
        data = re.search(r"<GDepth:Data>(.*?)</GDepth:Data>", xmp, re.S).group(1)
        xmp = re.sub(r"\s*<GDepth:Data>.*?</GDepth:Data>", "", xmp, flags=re.S)
        note = ('<xmpNote:HasExtendedXMP xmlns:xmpNote="http://ns.adobe.com/xmp/note/">'
                f"{GUID.decode()}</xmpNote:HasExtendedXMP>\n  <GDepth:Far>")
        xmp = xmp.replace("<GDepth:Far>", note, 1)
        parts.append(segment(0xE1, XMP + xmp.encode()))
        packet = ('<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF xmlns:rdf='
                  '"http://www.w3.org/1999/02/22-rdf-syntax-ns#"><rdf:Description '
                  'rdf:about="" xmlns:GDepth="http://ns.google.com/photos/1.0/depthmap/">'
                  f"<GDepth:Data>{data}</GDepth:Data></rdf:Description></rdf:RDF>"
                  "</x:xmpmeta>").encode()
        half = len(packet) // 2
        for offset, chunk in ((half, packet[half:]), (0, packet[:half])):
            head = EXTENDED + GUID + struct.pack(">II", len(packet), offset)
            parts.append(segment(0xE1, head + chunk))
    open(out, "wb").write(b"".join(parts) + jpeg[i:])


def dynamic_depth(src, out, depth_png, tmp):
    """``src`` with Dynamic Depth XMP by ExifTool and the confidence and depth PNGs appended."""
    confidence = os.path.join(tmp, "confidence.png")
    cv2.imwrite(confidence, np.full((24, 32), 255, np.uint8))
    lengths = [os.path.getsize(confidence), os.path.getsize(depth_png)]
    shutil.copy(src, out)
    directory = ("{Directory=[{Item={Mime=image/jpeg,Length=0}},"
                 f"{{Item={{Mime=image/png,Length={lengths[0]},DataURI=android/confidencemap}}}},"
                 f"{{Item={{Mime=image/png,Length={lengths[1]},DataURI=android/depthmap}}}}]}}")
    cameras = ("[{Camera={DepthMap={Format=RangeInverse,Near=1.5,Far=20.75,Units=Meters,"
               "MeasureType=OpticalAxis,DepthURI=android/depthmap,"
               "ConfidenceURI=android/confidencemap,ItemSemantic=Depth},"
               "ImagingModel={FocalLengthX=60,FocalLengthY=62,ImageWidth=64,ImageHeight=48,"
               "PrincipalPointX=0.45,PrincipalPointY=0.55}}}]")
    subprocess.run(["exiftool", "-q", "-overwrite_original", f"-XMP-Device:Container={directory}",
                    f"-XMP-Device:Cameras={cameras}", out], check=True)
    with open(out, "ab") as f:
        for png in (confidence, depth_png):
            f.write(open(png, "rb").read())


def oriented(src, out, value, *more):
    """``src`` with the EXIF Orientation ``value`` (and ``more`` tags) written by ExifTool."""
    subprocess.run(["exiftool", "-q", "-o", out, f"-IFD0:Orientation#={value}", *more, src],
                   check=True)


def main(out_dir):
    os.makedirs(out_dir, exist_ok=True)
    tmp = tempfile.mkdtemp()
    small = os.path.join(tmp, "small.jpg")
    photo(64, 48, small)
    y, x = np.mgrid[0:24, 0:32]
    plane = 1.5 + 0.25 * x + 0.5 * y
    inv8 = os.path.join(tmp, "inv8.png")
    cv2.imwrite(inv8, samples(plane, 1.5, 20.75, True, 8))
    embed(small, os.path.join(out_dir, "inv8.jpg"), inv8,
          ["Format=RangeInverse", "Near=1.5", "Far=20.75"])
    split_data(os.path.join(out_dir, "inv8.jpg"), os.path.join(out_dir, "ext8.jpg"))
    inv8_jpeg = os.path.join(tmp, "inv8.jpeg")
    codes = samples(plane, 1.5, 20.75, True, 8)
    cv2.imwrite(inv8_jpeg, codes, [cv2.IMWRITE_JPEG_QUALITY, 100])
    moved = np.abs(cv2.imread(inv8_jpeg, cv2.IMREAD_UNCHANGED).astype(int) - codes).max()
    assert moved <= 1, f"the JPEG moved a code by {moved}"
    embed(small, os.path.join(out_dir, "inv8-jpeg.jpg"), inv8_jpeg,
          ["Format=RangeInverse", "Near=1.5", "Far=20.75"], "image/jpeg")
    far8_jpeg = os.path.join(tmp, "far8.jpeg")
    codes = samples(1.5 + 0.2 * x + 0.4 * np.maximum(y - 6, 0), 1.5, 20.75, True, 8)
    codes[:6] = 255
    cv2.imwrite(far8_jpeg, codes, [cv2.IMWRITE_JPEG_QUALITY, 100])
    decoded = cv2.imread(far8_jpeg, cv2.IMREAD_UNCHANGED).astype(int)
    assert np.abs(decoded - codes).max() <= 1 and (decoded[:6] < 255).any()
    embed(small, os.path.join(out_dir, "far8-jpeg.jpg"), far8_jpeg,
          ["Format=RangeInverse", "Near=1.5", "Far=20.75"], "image/jpeg")
    conf = os.path.join(tmp, "conf8.png")
    cv2.imwrite(conf, np.where(x < 16, 255, 64).astype(np.uint8))
    embed(small, os.path.join(out_dir, "conf8.jpg"), inv8,
          ["Format=RangeInverse", "Near=1.5", "Far=20.75", "ConfidenceMime=image/png",
           f"Confidence<={conf}"])
    low = os.path.join(tmp, "low.png")
    cv2.imwrite(low, np.full((24, 32), 64, np.uint8))
    embed(small, os.path.join(out_dir, "conf-low.jpg"), inv8,
          ["Format=RangeInverse", "Near=1.5", "Far=20.75", "ConfidenceMime=image/png",
           f"Confidence<={low}"])
    lin16 = os.path.join(tmp, "lin16.png")
    cv2.imwrite(lin16, samples(plane * 1000, 1500, 20750, False, 16))
    embed(small, os.path.join(out_dir, "lin16.jpg"), lin16,
          ["Format=RangeLinear", "Near=1500", "Far=20750", "Units=mm",
           "MeasureType#=OpticRay"])
    big = os.path.join(tmp, "big.jpg")
    photo(320, 240, big)
    y, x = np.mgrid[0:240, 0:320]
    noisy = 2 + 0.05 * x + 0.1 * y + 0.01 * np.random.default_rng(1).random(x.shape)
    ext16 = os.path.join(tmp, "ext16.png")
    cv2.imwrite(ext16, samples(noisy, 2.0, 42.0, True, 16))
    embed(big, os.path.join(out_dir, "ext16.jpg"), ext16,
          ["Format=RangeInverse", "Near=2", "Far=42"])
    dynamic_depth(small, os.path.join(out_dir, "dd8.jpg"), inv8, tmp)
    shutil.copy(small, os.path.join(out_dir, "no-depth.jpg"))
    for name in ("inv8", "dd8"):
        rotated = "rot6.jpg" if name == "inv8" else f"{name}-rot6.jpg"
        oriented(os.path.join(out_dir, f"{name}.jpg"), os.path.join(out_dir, rotated), 6)
    oriented(os.path.join(out_dir, "inv8.jpg"), os.path.join(out_dir, "f26.jpg"), 6,
             "-ExifIFD:FocalLengthIn35mmFormat=26")
    oriented(os.path.join(out_dir, "inv8.jpg"), os.path.join(out_dir, "f26-crop.jpg"), 6,
             "-ExifIFD:FocalLengthIn35mmFormat=26", "-ExifIFD:ExifImageWidth=4032",
             "-ExifIFD:ExifImageHeight=2268")
    shutil.rmtree(tmp)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "tests/data/gdepth")
