#!/usr/bin/env python3
"""How time and memory grow with image size and with scene size, in θ and tessellated modes,
and the size targets: the 4096×3072 teapot in θ mode (16 steps) and the 16384×16384 teapot's
peak memory above the program's baseline.

Memory is the peak resident set reported by `render --stats-json`; the baseline is the same
figure for a 1×1 render of the teapot (the mapped libraries and the scene). Seconds are set-up
plus render without encoding and writing the PNG, the fastest of the repeats.
Writes scaling.csv and scaling.md.
"""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys

import povray
from common import camera_args, framed_camera, provenance

MODES = [("theta 16", ["--mode", "theta", "--theta-steps", "16"]),
         ("tess rate 8", ["--mode", "tess", "--tess-rate", "8"])]


def render(binary, scene, size, args, work, repeat, extra=()):
    best = None
    for _ in range(repeat):
        out, js = os.path.join(work, "out.png"), os.path.join(work, "stats.json")
        cmd = [binary, "render", scene, "-o", out, "--size", size, "--aa", "1", "--stats-json", js, "--threads", "1",
               *extra, *args]
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if r.returncode != 0:
            sys.exit(f"scaling: {' '.join(cmd)} failed ({r.returncode}):\n{r.stderr}")
        with open(js) as f:
            st = json.load(f)
        secs = st["seconds_tessellate"] + st["seconds_render"] - st["seconds_output"]
        if best is None or secs < best[0]:
            best = (secs, st["peak_rss_kib"] / 1024.0, secs + st["seconds_output"] + st["seconds_load"])
    return best


def teapots(src, n, path):
    """Writes n copies of the teapot on a square grid, 8 units apart, as one .bpt file."""
    patches = povray.read_bpt(src)
    side = 1
    while side * side < n:
        side += 1
    with open(path, "w") as f:
        f.write(f"{n * len(patches)}\n")
        for t in range(n):
            dx, dy = 8.0 * (t % side), 8.0 * (t // side)
            for p in patches:
                f.write("3 3\n")
                for (x, y, z) in p:
                    f.write(f"{x + dx:.9g} {y + dy:.9g} {z:.9g}\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", default="build/patchscan")
    ap.add_argument("--out", default="build/scaling")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--max-size", type=int, default=8192, help="largest square image of the size sweep")
    ap.add_argument("--max-teapots", type=int, default=1000)
    ap.add_argument("--no-targets", action="store_true", help="skip the 4096x3072 and 16384² renders")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    work = os.path.join(args.out, "work")
    os.makedirs(work, exist_ok=True)
    teapot = "surfaces/teapot.bpt"
    rows = []

    _, baseline, _ = render(args.binary, teapot, "1x1", MODES[1][1], work, 1)
    print(f"baseline (1x1 render): {baseline:.1f} MiB", file=sys.stderr)

    size = 512
    while size <= args.max_size:
        for name, margs in MODES:
            secs, mib, _ = render(args.binary, teapot, f"{size}x{size}", margs, work, args.repeat)
            rows.append({"sweep": "image", "n": size, "mode": name, "seconds": secs, "peak_mib": mib,
                         "above_baseline_mib": mib - baseline})
            print(f"image {size}² {name}: {secs:.3f} s, {mib:.1f} MiB", file=sys.stderr)
        size *= 2

    n = 1
    while n <= args.max_teapots:
        scene = os.path.join(work, f"teapots{n}.bpt")
        teapots(teapot, n, scene)
        for name, margs in MODES:
            secs, mib, _ = render(args.binary, scene, "1024x768", margs, work, args.repeat)
            rows.append({"sweep": "teapots", "n": n, "mode": name, "seconds": secs, "peak_mib": mib,
                         "above_baseline_mib": mib - baseline})
            print(f"{n} teapots {name}: {secs:.3f} s, {mib:.1f} MiB", file=sys.stderr)
        n *= 10

    targets = []
    if not args.no_targets:
        # The 4096×3072 teapot against POV-Ray's bicubic_patch, same camera, one thread each.
        cam = framed_camera(args.binary, teapot, [], "4096x3072")
        secs, mib, total = render(args.binary, teapot, "4096x3072", MODES[0][1], work, args.repeat,
                                  camera_args(cam))
        line = (f"- 4096×3072 teapot, θ 16 steps, aa 1, one thread: {secs:.2f} s to render, {total:.2f} s with "
                f"loading and writing the PNG ({mib:.1f} MiB peak)")
        pov_scene, pov_png = os.path.join(work, "teapot.pov"), os.path.join(work, "pov.png")
        povray.write_scene(teapot, pov_scene, cam["eye"], cam["look-at"], cam["up"], cam["fov"], 4096, 3072, 4)
        pov = povray.render(pov_scene, pov_png, 4096, 3072, 1)
        if pov is None:
            line += "; POV-Ray not installed (apt-get install povray): no comparison."
        else:
            ratio = total / pov
            line += (f"; POV-Ray 3.7 bicubic_patch (16² pieces per patch, +WT1, no AA) {pov:.2f} s wall: "
                     f"patchscan, writing its PNG too, takes {ratio:.3f} of its time (target ≤ 0.05: "
                     f"{'met' if ratio <= 0.05 else f'missed by {ratio / 0.05:.1f}×'}).")
        targets.append(line)
        secs, mib, _ = render(args.binary, teapot, "16384x16384", MODES[0][1], work, 1)
        targets.append(f"- 16384×16384 teapot, θ 16 steps, aa 1: {secs:.1f} s, peak {mib:.1f} MiB, "
                       f"{mib - baseline:.1f} MiB above the baseline ({'within' if mib - baseline <= 64 else 'over'} "
                       f"the 64 MiB target).")
        print("\n".join(targets), file=sys.stderr)

    with open(os.path.join(args.out, "scaling.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["sweep", "n", "mode", "seconds", "peak_mib", "above_baseline_mib"])
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in r.items()})
    lines = ["# Growth with image and scene size", "", provenance(args.binary), "",
             f"Baseline (a 1×1 render of the teapot): {baseline:.1f} MiB peak resident.", "",
             "| sweep | image side or teapots | mode | seconds | peak MiB | above baseline MiB |", "|---|---|---|---|---|---|"]
    for r in rows:
        label = f"{r['n']}²" if r["sweep"] == "image" else str(r["n"])
        lines.append(f"| {r['sweep']} | {label} | {r['mode']} | {r['seconds']:.3g} | {r['peak_mib']:.1f} | "
                     f"{r['above_baseline_mib']:.1f} |")
    if targets:
        lines += ["", "Targets:", ""] + targets
    with open(os.path.join(args.out, "scaling.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    shutil.rmtree(work)
    print(f"scaling: wrote scaling.csv and scaling.md in {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
