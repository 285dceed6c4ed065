#!/usr/bin/env python3
"""Writes sky.png: the environment of a z-up world as a 512x256 lat-long image in OpenEXR's
layout (the image's rows run from +y to -y, its centre column is +z), 8-bit linear (a
texture's values are light as they are: no sRGB decoding).

Above the horizon (world z > 0) a sky from pale at the horizon to deep blue overhead with a
sun towards -x +y; below, a floor of large checks fading into the horizon's haze. Run it from
this folder."""
import math
import struct
import zlib

WIDTH, HEIGHT = 512, 256
SUN = (-0.5, 0.6, 0.62)  # world direction towards the sun


def linear8(v):
    return bytes([round(255 * min(max(v, 0.0), 1.0))])


def colour(d):
    x, y, z = d
    if z >= 0:
        t = z ** 0.5
        sky = [(1 - t) * a + t * b for a, b in zip((0.75, 0.82, 0.95), (0.12, 0.25, 0.65))]
        n = math.sqrt(sum(c * c for c in SUN))
        c = sum(a * b / n for a, b in zip(d, SUN))
        glow = max(c, 0.0) ** 400 * 6 + max(c, 0.0) ** 8 * 0.3
        return [s + glow * k for s, k in zip(sky, (1.0, 0.9, 0.7))]
    # The floor: checks on the plane z = -1 seen from the origin, hazier towards the horizon.
    u, v = x / -z, y / -z
    check = (math.floor(u) + math.floor(v)) % 2
    floor = (0.55, 0.45, 0.35) if check else (0.25, 0.2, 0.16)
    haze = math.exp(6 * z)
    return [(1 - haze) * f + haze * h for f, h in zip(floor, (0.75, 0.82, 0.95))]


def chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


rows = bytearray()
for j in range(HEIGHT):
    rows.append(0)
    lat = math.pi / 2 - math.pi * (j + 0.5) / HEIGHT
    for i in range(WIDTH):
        lon = math.pi - 2 * math.pi * (i + 0.5) / WIDTH
        # A lookup takes the world direction as the map's: the texel at map direction d shows
        # what a z-up world has in direction d.
        d = (math.cos(lat) * math.sin(lon), math.sin(lat), math.cos(lat) * math.cos(lon))
        rows += b"".join(linear8(c) for c in colour(d))
with open("sky.png", "wb") as f:
    f.write(b"\x89PNG\r\n\x1a\n")
    f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", WIDTH, HEIGHT, 8, 2, 0, 0, 0)))
    f.write(chunk(b"IDAT", zlib.compress(bytes(rows), 9)))
    f.write(chunk(b"IEND", b""))
