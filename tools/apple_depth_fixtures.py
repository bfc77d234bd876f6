#!/usr/bin/env python3
"""Write the Apple portrait test JPEGs of tests/data/apple/.

An iPhone's portrait photo, saved as JPEG, keeps its depth as a second JPEG after the
photo: the photo's APP2 segment holds a Multi-Picture Format index (CIPA DC-007: a TIFF
whose MP Index IFD lists each image's attribute, size and offset from that TIFF header,
the first image's offset 0), and each auxiliary image carries XMP in Apple's namespaces:
``apdi`` (http://ns.apple.com/pixeldatainfo/1.0/) says what its 8-bit codes hold
(``NativeFormat``, a Core Video pixel format as the number its four characters make:
``hdis``/``fdis`` disparity in 1/m, ``hdep``/``fdep`` depth in m; codes ``IntMinValue``
to ``IntMaxValue`` spread evenly over ``FloatMinValue`` to ``FloatMaxValue``), and
``depthData`` (http://ns.apple.com/depthData/1.0/) its ``Accuracy`` and the camera's
``IntrinsicMatrix`` (column-major: fx 0 0, 0 fy 0, cx cy 1, in pixels of an image
``IntrinsicMatrixReferenceWidth`` x ``Height``). The portrait mattes sit beside it, grey
(``NativeFormat`` 1278226488, ``L008``), no depth.

This script writes that layout from the specification, independently of brume: OpenCV
encodes the images, ExifTool 12.57 writes each auxiliary image's XMP packet (``-xmp<=``)
and the photo's EXIF Orientation, this script assembles the MPF index, and ExifTool then
reads the index back: every ``MPImage`` it extracts must be the bytes written.

- ``portrait.jpg``: 64 x 48 photo; a 32 x 24 portrait matte first, then the 32 x 24
  disparity (``hdis``, codes 0..255 over 0.2..1.0 1/m, ``Accuracy`` relative): the top 8
  rows at code 0 (the background, as far as the map goes), below them the plane
  Z = 1 + 0.05 x + 0.1 (y − 8) m; ``IntrinsicMatrix`` fx = fy = 60, cx 30, cy 26 of a
  64 x 48 reference.
- ``portrait-rot6.jpg``: the same with EXIF Orientation 6 on the photo (a phone held
  upright), the depth as stored.
- ``depth-abs.jpg``: a depth map (``fdep``, codes 0..255 over 0.5..8.5 m, ``Accuracy``
  absolute, its XMP as attributes, no intrinsics): Z = 0.5 + 0.25 x m, the right 8
  columns at code 255 (where the map stops).
- ``matte-only.jpg``: the photo and its matte, no depth.
- ``gain-map.jpg``: the photo and an MPF image of another kind (an HDR gain map with
  Google's ``hdrgm`` XMP), no depth.

The JPEG codec is lossy: OpenCV at quality 100 leaves the flat blocks exact and the
plane within one code, which this script checks.

With ``--real IMAGE``, it also writes ``iphone-x.jpg`` from a real iPhone portrait:
``image-with-depth.jpg`` of Shuichi Tsutsumi's iOS-Depth-Sampler (MIT licence;
https://github.com/shu223/iOS-Depth-Sampler, ``iOS-Depth-Sampler/Resources/``, commit
a2e10669061a6a9d9de25e3aeb36a4b80ffd4599; an iPhone X on iOS 12, 3024 x 4032): its photo
at a quarter of its size (OpenCV, quality 85) with the original's EXIF and ICC profile
(Display P3; ExifTool), and its disparity image, the MPF image 2 that ExifTool extracts,
byte for byte, in a new index.

Usage (Debian: ``apt install libimage-exiftool-perl``; ``pip install numpy opencv-python-headless``):

    python3 tools/apple_depth_fixtures.py tests/data/apple [--real image-with-depth.jpg]
"""

import os
import shutil
import struct
import subprocess
import sys
import tempfile

import cv2
import numpy as np

from gdepth_fixtures import photo, segment

PORTRAIT_XMP = """<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF
 xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#"><rdf:Description rdf:about=""
 xmlns:apdi="http://ns.apple.com/pixeldatainfo/1.0/"
 xmlns:depthData="http://ns.apple.com/depthData/1.0/">
 <apdi:IntMaxValue>255</apdi:IntMaxValue>
 <apdi:StoredFormat>1278226488</apdi:StoredFormat>
 <apdi:NativeFormat>1751411059</apdi:NativeFormat>
 <apdi:IntMinValue>0</apdi:IntMinValue>
 <apdi:FloatMaxValue>1.000000</apdi:FloatMaxValue>
 <apdi:FloatMinValue>0.200000</apdi:FloatMinValue>
 <apdi:AuxiliaryImageType>disparity</apdi:AuxiliaryImageType>
 <depthData:IntrinsicMatrixReferenceWidth>64</depthData:IntrinsicMatrixReferenceWidth>
 <depthData:Quality>high</depthData:Quality>
 <depthData:IntrinsicMatrix><rdf:Seq><rdf:li>60</rdf:li><rdf:li>0</rdf:li><rdf:li>0</rdf:li>
 <rdf:li>0</rdf:li><rdf:li>60</rdf:li><rdf:li>0</rdf:li><rdf:li>30</rdf:li><rdf:li>26</rdf:li>
 <rdf:li>1</rdf:li></rdf:Seq></depthData:IntrinsicMatrix>
 <depthData:IntrinsicMatrixReferenceHeight>48</depthData:IntrinsicMatrixReferenceHeight>
 <depthData:Accuracy>relative</depthData:Accuracy>
 <depthData:Filtered>True</depthData:Filtered>
</rdf:Description></rdf:RDF></x:xmpmeta>"""

DEPTH_XMP = """<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF
 xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#"><rdf:Description rdf:about=""
 xmlns:apdi="http://ns.apple.com/pixeldatainfo/1.0/"
 xmlns:depthData="http://ns.apple.com/depthData/1.0/"
 apdi:NativeFormat="fdep" apdi:StoredFormat="1278226488" apdi:IntMinValue="0"
 apdi:IntMaxValue="255" apdi:FloatMinValue="0.5" apdi:FloatMaxValue="8.5"
 apdi:AuxiliaryImageType="depth" depthData:Accuracy="absolute"/></rdf:RDF></x:xmpmeta>"""

MATTE_XMP = """<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF
 xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#"><rdf:Description rdf:about=""
 xmlns:apdi="http://ns.apple.com/pixeldatainfo/1.0/">
 <apdi:AuxiliaryImageSubType>portraiteffectsmatte</apdi:AuxiliaryImageSubType>
 <apdi:NativeFormat>1278226488</apdi:NativeFormat>
 <apdi:AuxiliaryImageType>depth</apdi:AuxiliaryImageType>
 <apdi:StoredFormat>1278226488</apdi:StoredFormat>
</rdf:Description></rdf:RDF></x:xmpmeta>"""

GAIN_MAP_XMP = """<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF
 xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#"><rdf:Description rdf:about=""
 xmlns:hdrgm="http://ns.adobe.com/hdr-gain-map/1.0/" hdrgm:Version="1.0"
 hdrgm:GainMapMax="2.0" hdrgm:HDRCapacityMax="2.0"/></rdf:RDF></x:xmpmeta>"""


def grey_jpeg(codes, xmp, path, tmp):
    """``codes`` as a grey JPEG (quality 100) whose XMP packet ExifTool writes."""
    cv2.imwrite(path, codes, [cv2.IMWRITE_JPEG_QUALITY, 100])
    packet = os.path.join(tmp, "packet.xmp")
    with open(packet, "w") as f:
        f.write(xmp)
    subprocess.run(["exiftool", "-q", "-overwrite_original", f"-xmp<={packet}", path],
                   check=True)
    decoded = cv2.imread(path, cv2.IMREAD_UNCHANGED).astype(int)
    error = np.abs(decoded - codes.astype(int)).max()
    assert error <= 1, f"{path}: JPEG moved a code by {error}"
    return open(path, "rb").read()


def mpf_segment(sizes, offsets):
    """The APP2 segment of an MPF index (little-endian TIFF): version, count, entries."""
    count = len(sizes)
    entries_at = 8 + 2 + 3 * 12 + 4
    tiff = b"II*\x00" + struct.pack("<I", 8) + struct.pack("<H", 3)
    tiff += struct.pack("<HHI4s", 0xB000, 7, 4, b"0100")
    tiff += struct.pack("<HHII", 0xB001, 4, 1, count)
    tiff += struct.pack("<HHII", 0xB002, 7, 16 * count, entries_at)
    tiff += struct.pack("<I", 0)
    for k, (size, offset) in enumerate(zip(sizes, offsets)):
        # The first image: representative (bit 29), Baseline MP Primary Image (0x030000).
        attribute = 0x20030000 if k == 0 else 0
        tiff += struct.pack("<IIIHH", attribute, size, offset, 0, 0)
    return segment(0xE2, b"MPF\x00" + tiff)


def with_mpf(primary, aux, out, verify=True):
    """``primary`` with an MPF index after its first APP segments, ``aux`` appended; with
    ``verify``, ExifTool must extract each of ``aux`` as written."""
    i = 2
    while primary[i + 1] in (0xE0, 0xE1):
        i += 2 + struct.unpack(">H", primary[i + 2:i + 4])[0]
    head, tail = primary[:i], primary[i:]
    blank = mpf_segment([0] * (1 + len(aux)), [0] * (1 + len(aux)))
    primary_size = len(head) + len(blank) + len(tail)
    tiff_start = len(head) + 4 + 4  # the marker and length, then "MPF\0"
    sizes, offsets, at = [primary_size], [0], primary_size
    for image in aux:
        sizes.append(len(image))
        offsets.append(at - tiff_start)
        at += len(image)
    index = mpf_segment(sizes, offsets)
    assert len(index) == len(blank)
    with open(out, "wb") as f:
        f.write(head + index + tail + b"".join(aux))
    for k, image in enumerate(aux if verify else [], start=2):
        read = subprocess.run(["exiftool", "-b", f"-MPImage{k}", out], check=True,
                              capture_output=True).stdout
        assert read == image, f"{out}: ExifTool's MPImage{k} is not the image written"


def real_portrait(src, out, tmp):
    """``src`` (a real iPhone portrait JPEG) with its photo a quarter of its size, its EXIF
    and ICC profile (Display P3) kept, and its MPF image 2 (the disparity) as it is."""
    aux = subprocess.run(["exiftool", "-b", "-MPImage2", src], check=True,
                         capture_output=True).stdout
    assert b"http://ns.apple.com/pixeldatainfo/1.0/" in aux, "MPF image 2 is no Apple depth"
    photo_path = os.path.join(tmp, "quarter.jpg")
    image = cv2.imread(src)
    h, w = image.shape[:2]
    quarter = cv2.resize(image, (w // 4, h // 4), interpolation=cv2.INTER_AREA)
    cv2.imwrite(photo_path, quarter, [cv2.IMWRITE_JPEG_QUALITY, 85])
    subprocess.run(["exiftool", "-q", "-overwrite_original", "-tagsFromFile", src, "-exif:all",
                    "-icc_profile", photo_path], check=True)
    with_mpf(open(photo_path, "rb").read(), [aux], out)


def main(out_dir, real=None):
    os.makedirs(out_dir, exist_ok=True)
    tmp = tempfile.mkdtemp()
    small = os.path.join(tmp, "small.jpg")
    photo(64, 48, small)
    turned = os.path.join(tmp, "turned.jpg")
    subprocess.run(["exiftool", "-q", "-o", turned, "-IFD0:Orientation#=6", small], check=True)
    y, x = np.mgrid[0:24, 0:32]
    disparity = 1.0 / (1.0 + 0.05 * x + 0.1 * (y - 8))
    codes = np.round((disparity - 0.2) / 0.8 * 255).astype(np.uint8)
    codes[:8] = 0
    portrait = grey_jpeg(codes, PORTRAIT_XMP, os.path.join(tmp, "disparity.jpg"), tmp)
    matte_codes = np.where((x >= 8) & (x < 24) & (y >= 8), 255, 0).astype(np.uint8)
    matte = grey_jpeg(matte_codes, MATTE_XMP, os.path.join(tmp, "matte.jpg"), tmp)
    depth_codes = np.round(0.25 * x / 8.0 * 255).astype(np.uint8)
    depth_codes[:, 24:] = 255
    depth = grey_jpeg(depth_codes, DEPTH_XMP, os.path.join(tmp, "depth.jpg"), tmp)
    gain = grey_jpeg(np.full((24, 32), 128, np.uint8), GAIN_MAP_XMP,
                     os.path.join(tmp, "gain.jpg"), tmp)
    small_bytes, turned_bytes = open(small, "rb").read(), open(turned, "rb").read()
    with_mpf(small_bytes, [matte, portrait], os.path.join(out_dir, "portrait.jpg"))
    with_mpf(turned_bytes, [matte, portrait], os.path.join(out_dir, "portrait-rot6.jpg"))
    with_mpf(small_bytes, [depth], os.path.join(out_dir, "depth-abs.jpg"))
    with_mpf(small_bytes, [matte], os.path.join(out_dir, "matte-only.jpg"))
    with_mpf(small_bytes, [gain], os.path.join(out_dir, "gain-map.jpg"))
    if real:
        real_portrait(real, os.path.join(out_dir, "iphone-x.jpg"), tmp)
    shutil.rmtree(tmp)


if __name__ == "__main__":
    args = sys.argv[1:]
    real = None
    if "--real" in args:
        at = args.index("--real")
        real = args[at + 1]
        del args[at:at + 2]
    main(args[0] if args else "tests/data/apple", real)
