"""Writes flat-5800x5800-f64.tif: a tiled, deflate-compressed TIFF of 64-bit floats, 10.0
everywhere, whose TileOffsets all point at one compressed tile, so that a map of 269 MB
decoded is 5 kB on disk. Run: python3 make_tiled_tiff.py (standard library only)."""
import struct
import zlib

W = H = 5800
TILE = 256
VALUE = 10.0
SHORT, LONG = 3, 4

tiles = -(-W // TILE) * -(-H // TILE)
tile = zlib.compress(struct.pack("<d", VALUE) * (TILE * TILE), 9)
tile_at = 8
offsets_at = tile_at + len(tile)
counts_at = offsets_at + 4 * tiles
ifd_at = counts_at + 4 * tiles
entries = [  # tag, type, count, value (or offset of the values)
    (256, LONG, 1, W),  # ImageWidth
    (257, LONG, 1, H),  # ImageLength
    (258, SHORT, 1, 64),  # BitsPerSample
    (259, SHORT, 1, 8),  # Compression: deflate
    (262, SHORT, 1, 1),  # PhotometricInterpretation: black is zero
    (277, SHORT, 1, 1),  # SamplesPerPixel
    (322, SHORT, 1, TILE),  # TileWidth
    (323, SHORT, 1, TILE),  # TileLength
    (324, LONG, tiles, offsets_at),  # TileOffsets
    (325, LONG, tiles, counts_at),  # TileByteCounts
    (339, SHORT, 1, 3),  # SampleFormat: IEEE float
]
ifd = struct.pack("<H", len(entries))
for tag, kind, count, value in entries:
    if kind == SHORT and count == 1:
        ifd += struct.pack("<HHIHH", tag, kind, count, value, 0)
    else:
        ifd += struct.pack("<HHII", tag, kind, count, value)
ifd += struct.pack("<I", 0)
with open("flat-5800x5800-f64.tif", "wb") as out:
    out.write(b"II*\x00" + struct.pack("<I", ifd_at) + tile)
    out.write(struct.pack(f"<{tiles}I", *[tile_at] * tiles))
    out.write(struct.pack(f"<{tiles}I", *[len(tile)] * tiles))
    out.write(ifd)
