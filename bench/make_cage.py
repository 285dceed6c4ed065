#!/usr/bin/env python3
"""A subdivision cage for the benchmarks: a bumpy torus of 64 x 32 quadrilaterals, every
16th cut into two triangles (so 256 vertices of valence 5 and 5-sided neighbourhoods), 2,176
faces, written as a Wavefront .obj that patchscan reads as a Catmull-Clark cage.

    python3 bench/make_cage.py OUT.obj
"""
import math
import sys

NU, NV = 64, 32        # around the ring, around the tube
MAJOR, MINOR = 1.0, 0.35
SPLIT_EVERY = 16       # every 16th quadrilateral becomes two triangles


def write(path):
    with open(path, "w") as f:
        f.write(f"# bumpy torus cage, {NU} x {NV} quadrilaterals, every {SPLIT_EVERY}th split\n")
        for i in range(NU):
            a = 2 * math.pi * i / NU
            for j in range(NV):
                b = 2 * math.pi * j / NV
                r = MINOR * (1 + 0.18 * math.sin(5 * a) * math.cos(3 * b))
                x = (MAJOR + r * math.cos(b)) * math.cos(a)
                y = (MAJOR + r * math.cos(b)) * math.sin(a)
                z = r * math.sin(b)
                f.write(f"v {x:.9f} {y:.9f} {z:.9f}\n")
        k = 0
        for i in range(NU):
            for j in range(NV):
                v = lambda ii, jj: (ii % NU) * NV + (jj % NV) + 1
                q = [v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)]
                if k % SPLIT_EVERY == 0:
                    f.write(f"f {q[0]} {q[1]} {q[2]}\nf {q[0]} {q[2]} {q[3]}\n")
                else:
                    f.write(f"f {q[0]} {q[1]} {q[2]} {q[3]}\n")
                k += 1
    return path


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    write(sys.argv[1])
