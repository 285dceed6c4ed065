"""Single-core time by phase, against POV-Ray in the same run: the teapot, theta 16, aa 1,
--threads 1, the PNG written, at 1024x768 and 4096x3072; POV-Ray 3.7's bicubic_patch
(2^steps pieces a side, +WT1) with the same camera, interleaved, the fastest of --repeat
runs. Phases from --stats-json: load, set-up, render without the output (scan and shade),
output (encode and write), and start-up plus exit = the whole process less those. Newton
iterations per tracker-row and per sample from one exact aa 3 and one theta aa 4 render at
1024x768. With --baseline BINARY (another build) its figures are measured beside, in the
same run. Writes phases.csv and phases.md to --out."""
import argparse
import json
import os
import shutil
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(__file__))
from common import camera_args, framed_camera, publish, run  # noqa: E402
import povray  # noqa: E402

SCENE = "surfaces/teapot.bpt"
SIZES = [(1024, 768), (4096, 3072)]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--binary", default="build/patchscan")
    ap.add_argument("--baseline", default="", help="another patchscan build, measured beside")
    ap.add_argument("--baseline-label", default="baseline", help="its name in the tables (e.g. its commit)")
    ap.add_argument("--out", default="docs")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--povray-steps", type=int, default=4)
    args = ap.parse_args()
    builds = [("patchscan", args.binary)] + ([(args.baseline_label, args.baseline)] if args.baseline else [])
    have_pov = args.povray_steps > 0 and shutil.which("povray")
    results = {}
    with tempfile.TemporaryDirectory() as work:
        png, js = os.path.join(work, "out.png"), os.path.join(work, "stats.json")
        for w, h in SIZES:
            size = f"{w}x{h}"
            cam = framed_camera(args.binary, SCENE, [], size)
            pov_scene = os.path.join(work, "teapot.pov")
            if have_pov:
                povray.write_scene(SCENE, pov_scene, cam["eye"], cam["look-at"], cam["up"], cam["fov"], w, h,
                                   args.povray_steps)
            for _ in range(args.repeat):
                for name, binary in builds:
                    t0 = time.perf_counter()
                    code, _, err = run([binary, "render", SCENE, "-o", png, "--size", size, "--mode", "theta", "--aa", "1",
                                        "--threads", "1", "--quiet", "--stats-json", js] + camera_args(cam))
                    wall = time.perf_counter() - t0
                    if code != 0:
                        sys.exit(f"phases: {name} {size} failed:\n{err}")
                    with open(js) as f:
                        s = json.load(f)
                    inner = s["seconds_load"] + s["seconds_tessellate"] + s["seconds_render"]
                    row = {"wall": wall, "load": s["seconds_load"], "setup": s["seconds_tessellate"],
                           "scan_shade": s["seconds_render"] - s["seconds_output"], "output": s["seconds_output"],
                           "startup_exit": wall - inner, "rss_kib": s["peak_rss_kib"]}
                    key = (name, size)
                    if key not in results or wall < results[key]["wall"]:
                        results[key] = row
                if have_pov:
                    secs = povray.render(pov_scene, os.path.join(work, "pov.png"), w, h, 1, 1)
                    key = ("POV-Ray", size)
                    if key not in results or secs < results[key]["wall"]:
                        results[key] = {"wall": secs}
        newton = {}
        for name, binary in builds:
            for mode, aa in (("exact", "3"), ("theta", "4")):
                code, _, err = run([binary, "render", SCENE, "-o", png, "--size", "1024x768", "--mode", mode, "--aa", aa,
                                    "--threads", "1", "--quiet", "--stats-json", js])
                if code != 0:
                    sys.exit(f"phases: {name} {mode} failed:\n{err}")
                with open(js) as f:
                    s = json.load(f)
                newton[(name, mode)] = (s["newton_iterations_per_tracker_row"], s["xscan_newton_iterations_per_call"])
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "phases.csv"), "w") as f:
        f.write("build,size,wall,load,setup,scan_shade,output,startup_exit,rss_kib\n")
        for (name, size), r in results.items():
            f.write(f"{name},{size}," + ",".join(f"{r.get(k, float('nan')):.4f}" for k in
                                                ("wall", "load", "setup", "scan_shade", "output", "startup_exit", "rss_kib")) + "\n")
    lines = [f"Teapot, theta 16, aa 1, one thread, PNG written; fastest of {args.repeat} interleaved runs "
             f"(`python3 bench/phases.py`); POV-Ray 3.7 bicubic_patch {2 ** args.povray_steps}x{2 ** args.povray_steps} "
             "pieces a patch, +WT1, same camera.", "",
             "| build | size | process s | start-up + exit | load | set-up | scan + shade | encode + write | peak MB | / POV-Ray |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for w, h in SIZES:
        size = f"{w}x{h}"
        pov = results.get(("POV-Ray", size), {}).get("wall")
        for name, _ in builds:
            r = results[(name, size)]
            ratio = f"{r['wall'] / pov:.3f}" if pov else "-"
            lines.append(f"| {name} | {size} | {r['wall']:.3f} | {r['startup_exit']:.3f} | {r['load']:.3f} | "
                         f"{r['setup']:.3f} | {r['scan_shade']:.3f} | {r['output']:.3f} | {r['rss_kib'] / 1024:.1f} | {ratio} |")
        if pov:
            lines.append(f"| POV-Ray | {size} | {pov:.3f} | | | | | | | 1 |")
    lines += ["", "Newton iterations (teapot 1024x768, one thread):", "",
              "| build | per tracker-row, exact aa 3 | per sample, exact aa 3 | per tracker-row, theta aa 4 |",
              "|---|---|---|---|"]
    for name, _ in builds:
        e, t = newton[(name, "exact")], newton[(name, "theta")]
        lines.append(f"| {name} | {e[0]:.3f} | {e[1]:.3f} | {t[0]:.3f} |")
    publish(args.out, "phases.md", lines, "Where the time of a render goes", args.binary)


if __name__ == "__main__":
    main()
