#!/usr/bin/env python3
"""Writes dimples.png: a bump map of round dimples in staggered rows, 512x512, 16-bit grey.

Height 1 between the dimples, falling smoothly (the square of 1 - (d/r)^2, so the slope is
continuous) to 0 at each dimple's centre; eight rows of eight, every other row shifted by
half a dimple, so the texture tiles in s and t. Run it from this folder."""
import math
import struct
import zlib

SIZE, CELLS, RADIUS = 512, 8, 0.42  # RADIUS: of a dimple, as a fraction of its cell


def height(s, t):
    row = math.floor(t * CELLS)
    shift = 0.5 if row % 2 else 0.0
    cu = s * CELLS + shift
    du, dv = cu - math.floor(cu) - 0.5, t * CELLS - row - 0.5
    d = math.hypot(du, dv) / RADIUS
    return 1.0 - (1.0 - d * d) ** 2 if d < 1.0 else 1.0


def chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


rows = bytearray()
for j in range(SIZE):
    rows.append(0)  # filter: none
    for i in range(SIZE):
        rows += struct.pack(">H", round(65535 * height((i + 0.5) / SIZE, (j + 0.5) / SIZE)))
with open("dimples.png", "wb") as f:
    f.write(b"\x89PNG\r\n\x1a\n")
    f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", SIZE, SIZE, 16, 0, 0, 0, 0)))
    f.write(chunk(b"IDAT", zlib.compress(bytes(rows), 9)))
    f.write(chunk(b"IEND", b""))
