#!/usr/bin/env python3
"""The speed/accuracy sweep: every mode of patchscan against its exact render, measured in
one run on one machine.

For each scene and supersampling level, the exact render is the reference; each θ-step
count and tessellation setting is rendered with the same camera, timed, and measured
against it with `patchscan compare`. Writes accuracy.csv, report.md (tables, the fastest
setting per accuracy, the targets) and, when gnuplot is installed, accuracy.png.

Run through bench/accuracy, which installs what is missing and builds first.
"""
import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import time

import make_cage
import povray
from common import camera_args, framed_camera, provenance, run

SCENES = [  # name, file, extra camera options
    ("teapot", "surfaces/teapot.bpt", []),
    ("teacup", "surfaces/teacup.bpt", ["--up", "0,1,0"]),
    ("teaspoon", "surfaces/teaspoon.bpt", ["--up", "0,1,0"]),
    ("sphere", "surfaces/sphere.bpt", []),
    ("cage", None, []),  # bench/make_cage.py's torus cage of 2,176 faces, written into --out
]
THETA_STEPS = [4, 6, 8, 12, 16, 32, 64]
# θ with slabs between lines of chains (--y-step h pixels) instead of the default chains
# on every sample row, as (steps, h): only differs with supersampling (at aa 1 every row is
# a line). Two- and four-pixel slabs trade silhouette error (h/4 + h²/(8R)) for fewer lines.
THETA_SLABS = [(4, 1), (8, 1), (16, 1), (32, 1), (64, 1), (4, 2), (16, 2), (4, 4)]
TESS_RATES = [2, 4, 8, 12, 16, 24, 32]
TESS_PIXELS = [16, 8, 4, 2, 1]
AAS = [1, 4]
# The accuracy levels the report asks about: maximum coverage-edge distance, pixels.
LEVELS = [0.5, 0.25, 0.1]
MODES = ["theta", "tess", "tess-pixels", "povray"]
RMSE_LEVELS = [0.01, 0.005, 0.002]

FIELDS = ["scene", "aa", "mode", "setting", "seconds", "seconds_wall", "peak_rss_mib", "triangles",
          "silhouette_max_px", "silhouette_p99_px", "pixels_coverage_differs", "depth_rel_p99",
          "depth_rel_max", "normal_deg_p99", "normal_deg_max", "rmse", "psnr_db"]


def settings(aa, only=None):
    """(mode, setting, options) of every setting at supersampling aa, or of those `only`
    names (a set of short names: exact, theta16, theta16s, tess8, px4, ...)."""
    every = [("exact", "", [], "exact")]
    for n in THETA_STEPS:
        every.append(("theta", f"steps {n}", ["--mode", "theta", "--theta-steps", str(n)], f"theta{n}"))
    if aa > 1:
        for n, h in THETA_SLABS:
            every.append(("theta", f"steps {n}, {h}-px slabs",
                          ["--mode", "theta", "--theta-steps", str(n), "--y-step", str(h)],
                          f"theta{n}s" if h == 1 else f"theta{n}s{h}"))
    for r in TESS_RATES:
        every.append(("tess", f"rate {r}", ["--mode", "tess", "--tess-rate", str(r)], f"tess{r}"))
    for p in TESS_PIXELS:
        every.append(("tess-pixels", f"{p} px", ["--mode", "tess", "--tess-pixels", str(p)], f"px{p}"))
    for mode, setting, options, short in every:
        if only is None or short in only:
            yield mode, setting, options


def render(binary, scene, extra, aa, mode_args, size, out_exr, stats_json):
    """Renders once; returns the (setup + render) seconds, the process's wall time, and its
    stats."""
    cmd = [binary, "render", scene, "-o", out_exr, "--aov", "--aa", str(aa), "--size", size,
           "--stats-json", stats_json, "--threads", "1"] + extra + mode_args
    t0 = time.perf_counter()
    code, _, err = run(cmd)
    wall = time.perf_counter() - t0
    if code != 0:
        sys.exit(f"accuracy: {' '.join(cmd)} failed ({code}):\n{err}")
    with open(stats_json) as f:
        stats = json.load(f)
    return stats["seconds_tessellate"] + stats["seconds_render"] - stats["seconds_output"], wall, stats


def compare(binary, a, b, js):
    code, out, err = run([binary, "compare", a, b, "--json", js])
    if code > 2:
        sys.exit(f"accuracy: compare {a} {b} failed ({code}):\n{err}")
    with open(js) as f:
        return json.load(f)


def stat(c, key, field):
    return c[key][field] if c.get(key) else float("nan")


def fmt(x, digits=3):
    if isinstance(x, float):
        if math.isnan(x):
            return "–"
        return f"{x:.{digits}g}"
    return str(x)


def joint_table(sub):
    """θ against tessellation (uniform or screen-adaptive) where both bounds hold at once: for
    each silhouette level (max px, 1 px down) and colour level (RMSE), the fastest setting of
    each reaching both, and which is faster."""
    def fastest(modes, level, rmse):
        ok = [r for r in sub if r["mode"] in modes and r["silhouette_max_px"] <= level and r["rmse"] <= rmse]
        return min(ok, key=lambda r: r["seconds"]) if ok else None
    if not any(r["mode"] == "theta" for r in sub) or not any(r["mode"].startswith("tess") for r in sub):
        return []
    lines = ["", "θ against the fastest tessellation (uniform or screen-adaptive) reaching both bounds at "
             "once (max silhouette error and colour RMSE):", "",
             "| max silhouette error | " + " | ".join(f"RMSE ≤ {x}" for x in RMSE_LEVELS) + " |",
             "|---" * (len(RMSE_LEVELS) + 1) + "|"]
    for level in [1.0] + LEVELS:
        cells = []
        for rmse in RMSE_LEVELS:
            t, m = fastest(["theta"], level, rmse), fastest(["tess", "tess-pixels"], level, rmse)
            if t is None and m is None:
                cells.append("neither")
            elif m is None:
                cells.append(f"θ {t['setting']} {fmt(t['seconds'])} s; no tessellation")
            elif t is None:
                cells.append(f"no θ; {m['mode']} {m['setting']} {fmt(m['seconds'])} s")
            else:
                win = "θ" if t["seconds"] <= m["seconds"] else "tess"
                cells.append(f"θ {t['setting']} {fmt(t['seconds'])} s, {m['mode']} {m['setting']} "
                             f"{fmt(m['seconds'])} s: **{win}**")
        lines.append(f"| ≤ {level:g} px | " + " | ".join(cells) + " |")
    return lines


def write_report(rows, path, size, povray_line, binary="build/patchscan"):
    lines = [f"# Speed and accuracy at {size}", "", provenance(binary), "",
             "Every error is measured against the exact render of the same scene, camera and "
             "supersampling (`patchscan compare`). Silhouette: distance between the alpha = 1/2 "
             "coverage contours (max and 99th percentile, pixels); depth: relative, and normal "
             "angle: degrees, both on pixels fully covered by the same surface in both renders "
             "(99th percentile); colour RMSE over all pixels. Seconds: set-up (tessellation) "
             "plus render, without encoding and writing the image (`seconds_output` of "
             "--stats-json), the fastest of the repeats (taken in turn across each scene's "
             "settings); the CSV also has the process's wall time (which includes writing an EXR "
             "with AOVs). Memory: peak resident set of the process.",
             ""]
    for scene in dict.fromkeys(r["scene"] for r in rows):
        for aa in AAS:
            sub = [r for r in rows if r["scene"] == scene and r["aa"] == aa]
            if not sub:
                continue
            lines += [f"## {scene}, aa {aa}", "",
                      "| mode | setting | seconds | MiB | triangles | silhouette max / p99 px | "
                      "depth p99 | normal p99° | RMSE |", "|---|---|---|---|---|---|---|---|---|"]
            for r in sub:
                lines.append(f"| {r['mode']} | {r['setting']} | {fmt(r['seconds'])} | "
                             f"{fmt(r['peak_rss_mib'], 4)} | {r['triangles']} | "
                             f"{fmt(r['silhouette_max_px'])} / {fmt(r['silhouette_p99_px'])} | "
                             f"{fmt(r['depth_rel_p99'])} | {fmt(r['normal_deg_p99'])} | {fmt(r['rmse'])} |")
            lines += ["", "Fastest setting per mode reaching each silhouette accuracy "
                      "(max coverage-edge distance):", "",
                      "| max silhouette error | " + " | ".join(MODES) + " | fastest |",
                      "|---" * (len(MODES) + 2) + "|"]
            for level in LEVELS:
                cells, winner = [], None
                for mode in MODES:
                    ok = [r for r in sub if r["mode"] == mode and r["silhouette_max_px"] <= level]
                    if ok:
                        b = min(ok, key=lambda r: r["seconds"])
                        cells.append(f"{b['setting']}: {fmt(b['seconds'])} s")
                        if winner is None or b["seconds"] < winner[1]:
                            winner = (mode, b["seconds"])
                    elif any(r["mode"] == mode for r in sub):
                        cells.append("not reached")
                    else:
                        cells.append("–")
                lines.append(f"| ≤ {level} px | " + " | ".join(cells) + f" | {winner[0] if winner else '–'} |")
            lines += ["", "Fastest setting per mode reaching each colour accuracy (RMSE against exact; "
                      "θ mode's coverage is exact on the scan lines its chains are made on and within "
                      "h/4 + h²/(8R) px between them for --y-step h, so its error is mostly in "
                      "depth, normal and colour):", "",
                      "| colour RMSE | " + " | ".join(MODES[:3]) + " | fastest |", "|---" * 5 + "|"]
            for level in RMSE_LEVELS:
                cells, winner = [], None
                for mode in MODES[:3]:
                    ok = [r for r in sub if r["mode"] == mode and r["rmse"] <= level]
                    if ok:
                        b = min(ok, key=lambda r: r["seconds"])
                        cells.append(f"{b['setting']}: {fmt(b['seconds'])} s")
                        if winner is None or b["seconds"] < winner[1]:
                            winner = (mode, b["seconds"])
                    else:
                        cells.append("not reached")
                lines.append(f"| ≤ {level} | " + " | ".join(cells) + f" | {winner[0] if winner else '–'} |")
            lines += joint_table(sub)
            # Target of the measure-the-trade issue: θ (16 steps) at least twice as fast as the
            # best tessellated setting whose silhouette error is at most 0.25 px.
            theta16 = [r for r in sub if r["mode"] == "theta" and r["setting"] == "steps 16"]
            tess = [r for r in sub if r["mode"].startswith("tess") and r["silhouette_max_px"] <= 0.25]
            if theta16 and tess:
                b = min(tess, key=lambda r: r["seconds"])
                ratio = b["seconds"] / theta16[0]["seconds"]
                lines += ["", f"θ 16 steps against the fastest tessellation with silhouette ≤ 0.25 px "
                          f"({b['mode']} {b['setting']}): {fmt(ratio)}× "
                          f"({'meets' if ratio >= 2 else 'misses'} the 2× target)."]
            elif theta16 and aa > 1:
                tess_all = [r for r in sub if r["mode"].startswith("tess")]
                b = min(tess_all, key=lambda r: r["silhouette_max_px"])
                lines += ["", f"No tessellated setting reaches a silhouette error of 0.25 px; the closest, "
                          f"{b['mode']} {b['setting']} ({fmt(b['silhouette_max_px'])} px), takes "
                          f"{fmt(b['seconds'] / theta16[0]['seconds'])}× the time of θ 16 steps."]
            lines.append("")
    if povray_line:
        lines += ["## POV-Ray", "", povray_line, ""]
    with open(path, "w") as f:
        f.write("\n".join(lines))


def Series(r):
    """The plot's series of a row: its mode, θ's slabs of each height apart from its rows."""
    if r["mode"] == "theta" and "slabs" in r["setting"]:
        return "theta " + r["setting"].split(", ")[1]  # "theta 1-px slabs"
    return r["mode"]


def plot(rows, csv_path, png_path):
    if not shutil.which("gnuplot"):
        print("accuracy: gnuplot not installed: no plot (apt-get install gnuplot-nox)", file=sys.stderr)
        return
    # One data block per scene, mode and aa, for gnuplot's index.
    data = png_path + ".dat"
    blocks = []
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    with open(data, "w") as f:
        for scene in scenes:
            for mode in ["theta", "theta 1-px slabs", "theta 2-px slabs", "theta 4-px slabs", "tess", "tess-pixels", "povray"]:
                for aa in AAS:
                    sub = [r for r in rows if r["scene"] == scene and Series(r) == mode and r["aa"] == aa]
                    if not sub:
                        continue
                    for r in sub:
                        # Zero silhouette error (θ mode's edges are exact) is drawn at 0.01 px.
                        f.write(f"{r['seconds']} {max(r['silhouette_max_px'], 0.01)} {max(r['rmse'], 1e-5) if not math.isnan(r['rmse']) else 'NaN'}\n")
                    f.write("\n\n")
                    blocks.append((scene, mode, aa))
    has_cairo = run(["gnuplot", "-e", "set terminal pngcairo"])[0] == 0
    script = [
        f"set terminal {'pngcairo' if has_cairo else 'png'} size {400 * len(scenes)},800",
        f"set output '{png_path}'", "set logscale xy", "set grid", "set key top right font ',8'",
        f"set multiplot layout 2,{len(scenes)} title 'error against time, per mode (aa 1 open, aa 4 filled)'"]
    colours = {"theta": "#d62728", "theta 1-px slabs": "#ff9896", "theta 2-px slabs": "#8c564b", "theta 4-px slabs": "#e377c2",
               "tess": "#1f77b4", "tess-pixels": "#2ca02c",
               "povray": "#9467bd"}
    for col, label in [(2, "max silhouette error, px (0 drawn at 0.01)"), (3, "colour RMSE")]:
        for scene in scenes:
            plots = []
            for k, (s, mode, aa) in enumerate(blocks):
                if s != scene:
                    continue
                pt = 6 if aa == 1 else 7
                plots.append(f"'{data}' index {k} using 1:{col} with linespoints pt {pt} "
                             f"lc rgb '{colours[mode]}' title '{mode} aa {aa}'")
            script += [f"set title '{scene}'", "set xlabel 'seconds'", f"set ylabel '{label}'",
                       "plot " + ", ".join(plots)]
    script.append("unset multiplot")
    code, _, err = run(["gnuplot", "-e", "; ".join(script)])
    if code != 0:
        print(f"accuracy: gnuplot failed: {err}", file=sys.stderr)
    os.remove(data)


def read_csv(path):
    rows = []
    with open(path) as f:
        for r in csv.DictReader(f):
            for k in FIELDS[4:]:
                r[k] = float(r[k])
            r["aa"] = int(r["aa"])
            r["triangles"] = int(r["triangles"])
            rows.append(r)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", default="build/patchscan")
    ap.add_argument("--out", default="build/accuracy", help="directory for the CSV, report and plot")
    ap.add_argument("--size", default="1024x768")
    ap.add_argument("--repeat", type=int, default=1,
                    help="renders per setting, taken in turn across a scene's settings; the fastest counts")
    ap.add_argument("--scenes", default=",".join(s[0] for s in SCENES))
    ap.add_argument("--settings", default="",
                    help="only these settings, by short name: exact (always), theta16, theta16s (1-px slabs), theta4s2 (2-px), tess8, "
                         "px4, ... "
                         "(default: all)")
    ap.add_argument("--aa", default=",".join(map(str, AAS)), help="supersampling levels, e.g. 1,4")
    ap.add_argument("--povray-steps", type=int, default=4,
                    help="POV-Ray's u_steps/v_steps (2^n pieces per patch side); 0: no POV-Ray")
    ap.add_argument("--report-only", action="store_true",
                    help="rewrite report.md and the plot from the CSV in --out, rendering nothing")
    args = ap.parse_args()
    if args.report_only:
        rows = read_csv(os.path.join(args.out, "accuracy.csv"))
        write_report(rows, os.path.join(args.out, "report.md"), args.size, None, args.binary)
        plot(rows, None, os.path.join(args.out, "accuracy.png"))
        return
    os.makedirs(args.out, exist_ok=True)
    work = os.path.join(args.out, "work")
    os.makedirs(work, exist_ok=True)

    rows = []
    povray_missing = False
    wanted = args.scenes.split(",")
    for name, path, extra in SCENES:
        if name not in wanted:
            continue
        if path is None:
            path = make_cage.write(os.path.join(work, "torus_cage.obj"))
        cam = framed_camera(args.binary, path, extra, args.size)
        extra = camera_args(cam)
        only = set(args.settings.split(",")) | {"exact"} if args.settings else None
        for aa in (int(a) for a in args.aa.split(",")):
            ref = os.path.join(work, f"{name}_aa{aa}_exact.exr")
            # The first pass renders each setting once and measures its error; the other
            # repeats take the settings in turn again, timing only, so that a slow spell of the
            # machine's other load falls on every setting of the scene alike rather than on
            # whichever was being repeated then. Each setting keeps its fastest time.
            group = list(settings(aa, only))
            group_rows = []
            for mode, setting, margs in group:
                exr = ref if mode == "exact" else os.path.join(work, "candidate.exr")
                secs, wall, st = render(args.binary, path, extra, aa, margs, args.size, exr,
                                        os.path.join(work, "stats.json"))
                c = compare(args.binary, exr, ref, os.path.join(work, "compare.json"))
                row = {"scene": name, "aa": aa, "mode": mode, "setting": setting, "seconds": secs,
                       "seconds_wall": wall, "peak_rss_mib": st["peak_rss_kib"] / 1024.0,
                       "triangles": st["triangles"] if mode.startswith("tess") else 0,
                       "silhouette_max_px": stat(c, "silhouette_px", "max"),
                       "silhouette_p99_px": stat(c, "silhouette_px", "p99"),
                       "pixels_coverage_differs": c["pixels_coverage_differs"],
                       "depth_rel_p99": stat(c, "depth_relative", "p99"),
                       "depth_rel_max": stat(c, "depth_relative", "max"),
                       "normal_deg_p99": stat(c, "normal_degrees", "p99"),
                       "normal_deg_max": stat(c, "normal_degrees", "max"),
                       "rmse": c["rmse"], "psnr_db": c["psnr"] if c["psnr"] is not None else float("inf")}
                group_rows.append(row)
            for _ in range(args.repeat - 1):
                for row, (mode, setting, margs) in zip(group_rows, group):
                    exr = ref if mode == "exact" else os.path.join(work, "candidate.exr")
                    secs, wall, _ = render(args.binary, path, extra, aa, margs, args.size, exr,
                                           os.path.join(work, "stats.json"))
                    row["seconds"], row["seconds_wall"] = min(row["seconds"], secs), min(row["seconds_wall"], wall)
            for row in group_rows:
                print(f"{name} aa {aa} {row['mode']} {row['setting']}: {row['seconds']:.3f} s, silhouette "
                      f"{fmt(row['silhouette_max_px'])} px, RMSE {fmt(row['rmse'])}", file=sys.stderr)
            rows += group_rows
            # POV-Ray's bicubic_patch on the same patches, camera, size and supersampling.
            if args.povray_steps > 0 and shutil.which("povray") and path.endswith(".bpt"):
                w, h = (int(x) for x in args.size.split("x"))
                pov_scene, pov_png = os.path.join(work, "scene.pov"), os.path.join(work, "pov.png")
                povray.write_scene(path, pov_scene, cam["eye"], cam["look-at"], cam["up"], cam["fov"], w, h,
                                   args.povray_steps)
                secs = min(povray.render(pov_scene, pov_png, w, h, aa) for _ in range(args.repeat))
                c = compare(args.binary, pov_png, ref, os.path.join(work, "compare.json"))
                rows.append({"scene": name, "aa": aa, "mode": "povray",
                             "setting": f"bicubic_patch, {2 ** args.povray_steps}² pieces", "seconds": secs,
                             "seconds_wall": secs, "peak_rss_mib": float("nan"), "triangles": 0,
                             "silhouette_max_px": stat(c, "silhouette_px", "max"),
                             "silhouette_p99_px": stat(c, "silhouette_px", "p99"),
                             "pixels_coverage_differs": c["pixels_coverage_differs"],
                             "depth_rel_p99": float("nan"), "depth_rel_max": float("nan"),
                             "normal_deg_p99": float("nan"), "normal_deg_max": float("nan"),
                             "rmse": float("nan"), "psnr_db": float("nan")})
                print(f"{name} aa {aa} povray: {secs:.3f} s, silhouette {fmt(rows[-1]['silhouette_max_px'])} px",
                      file=sys.stderr)
            elif args.povray_steps > 0 and not shutil.which("povray"):
                povray_missing = True

    csv_path = os.path.join(args.out, "accuracy.csv")
    with open(csv_path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    pov_note = ("POV-Ray was not found (apt-get install povray): its comparison was skipped."
                if povray_missing else
                "POV-Ray 3.7 renders the same Bézier patches as `bicubic_patch` (type 1, flatness 0) with "
                "one thread (+WT1), the same camera, size and supersampling (aa 1: none; aa L: +AM1 +R L, "
                "threshold 0); its time is the process's wall time, parsing included. Its colour is not "
                "comparable (its own lights and material): only its coverage edges are measured."
                if args.povray_steps > 0 else None)
    write_report(rows, os.path.join(args.out, "report.md"), args.size, pov_note, args.binary)
    plot(rows, csv_path, os.path.join(args.out, "accuracy.png"))
    shutil.rmtree(work)
    print(f"accuracy: wrote {csv_path}, report.md and accuracy.png in {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
