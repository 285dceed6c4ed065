"""Speed-up of `render --threads N` against `--threads 1`, each measured in the same run,
interleaved, the fastest of --repeat runs: the render's wall time with the image written
(seconds_render of --stats-json) and the whole process's. With POV-Ray installed, its
bicubic_patch render of the teapot on as many threads (+WT N) beside patchscan's, in the same
run. Writes threads.csv and threads.md."""
import argparse
import json
import os
import shutil
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(__file__))
from common import camera_args, framed_camera, provenance, run  # noqa: E402
import povray  # noqa: E402

CASES = [
    ("teapot 1024x768 theta16 aa 4", "surfaces/teapot.bpt", ["--size", "1024x768", "--mode", "theta", "--aa", "4"]),
    ("teapot 1024x768 exact aa 3", "surfaces/teapot.bpt", ["--size", "1024x768", "--mode", "exact", "--aa", "3"]),
    ("teapot 4096x3072 theta16 aa 1", "surfaces/teapot.bpt", ["--size", "4096x3072", "--mode", "theta", "--aa", "1"]),
    ("teapot 4096x3072 theta16 aa 3", "surfaces/teapot.bpt", ["--size", "4096x3072", "--mode", "theta", "--aa", "3"]),
    ("quadrics.rib 1024x768 theta16 aa 3", "surfaces/quadrics.rib", ["--size", "1024x768", "--mode", "theta", "--aa", "3"]),
    ("sphere.bpt 1024x768 exact aa 3", "surfaces/sphere.bpt", ["--size", "1024x768", "--mode", "exact", "--aa", "3"]),
    ("teapot 1024x768 tess rate 16 aa 4", "surfaces/teapot.bpt", ["--size", "1024x768", "--mode", "tess", "--tess-rate", "16", "--aa", "4"]),
    # The multi-surface production scene, its picture frame (its shadow map made first, below).
    ("still_life.rib frame 2 960x540 exact aa 3", "surfaces/still_life.rib", ["--frame", "2", "--mode", "exact"]),
    ("still_life.rib frame 2 960x540 theta16 aa 3", "surfaces/still_life.rib", ["--frame", "2", "--mode", "theta"]),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--binary", default="build/patchscan")
    ap.add_argument("--out", default="docs")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--povray-steps", type=int, default=4,
                    help="POV-Ray's bicubic_patch subdivision (2^steps pieces a side; 0: no POV-Ray)")
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as work:
        png, js = os.path.join(work, "out.png"), os.path.join(work, "stats.json")
        # still_life.rib's frames write and read their shadow map in the working directory.
        binary = os.path.abspath(args.binary)
        here = os.getcwd()
        os.chdir(work)
        code, _, err = run([binary, "render", os.path.join(here, "surfaces/still_life.rib"), "--quiet"])
        if code != 0:
            sys.exit(f"threads: still_life.rib's frames failed:\n{err}")
        for name, scene, extra in CASES:
            best = {}
            for _ in range(args.repeat):
                for n in args.threads:
                    t0 = time.perf_counter()
                    code, _, err = run([binary, "render", os.path.join(here, scene), "-o", png, "--threads", str(n),
                                        "--stats-json", js] + extra)
                    wall = time.perf_counter() - t0
                    if code != 0:
                        sys.exit(f"threads: {name} --threads {n} failed:\n{err}")
                    with open(js) as f:
                        render = json.load(f)["seconds_render"]
                    old = best.get(n, (1e9, 1e9))
                    best[n] = (min(old[0], render), min(old[1], wall))
            for n in args.threads:
                rows.append({"case": name, "threads": n, "seconds_render": best[n][0], "seconds_wall": best[n][1],
                             "speedup_render": best[args.threads[0]][0] / best[n][0],
                             "speedup_wall": best[args.threads[0]][1] / best[n][1]})
                print(f"{name}, --threads {n}: render {best[n][0]:.3f} s, wall {best[n][1]:.3f} s, "
                      f"speed-up {rows[-1]['speedup_render']:.2f}x", flush=True)
        # POV-Ray beside patchscan: the teapot at 4096x3072 aa 1, the same camera, as many threads.
        pov_rows = []
        if args.povray_steps > 0 and shutil.which("povray"):
            size, extra = "4096x3072", ["--mode", "theta", "--aa", "1"]
            scene = os.path.join(here, "surfaces/teapot.bpt")
            cam = framed_camera(binary, scene, [], size)
            w, h = 4096, 3072
            pov_scene, pov_png = os.path.join(work, "teapot.pov"), os.path.join(work, "pov.png")
            povray.write_scene(scene, pov_scene, cam["eye"], cam["look-at"], cam["up"], cam["fov"], w, h,
                               args.povray_steps)
            best = {}
            for _ in range(args.repeat):
                for n in args.threads:
                    t0 = time.perf_counter()
                    code, _, err = run([binary, "render", scene, "-o", png, "--threads", str(n), "--size", size] + extra + camera_args(cam))
                    ours = time.perf_counter() - t0
                    if code != 0:
                        sys.exit(f"threads: teapot --threads {n} failed:\n{err}")
                    theirs = povray.render(pov_scene, pov_png, w, h, 1, n)
                    old = best.get(n, (1e9, 1e9))
                    best[n] = (min(old[0], ours), min(old[1], theirs))
            for n in args.threads:
                pov_rows.append({"threads": n, "patchscan": best[n][0], "povray": best[n][1]})
                print(f"teapot 4096x3072 aa 1, {n} threads: patchscan theta16 {best[n][0]:.3f} s, POV-Ray "
                      f"{best[n][1]:.3f} s, ratio {best[n][0] / best[n][1]:.3f}", flush=True)
    os.chdir(here)
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "threads.csv"), "w") as f:
        f.write("case,threads,seconds_render,seconds_wall,speedup_render,speedup_wall\n")
        for r in rows:
            f.write(f"{r['case']},{r['threads']},{r['seconds_render']:.4f},{r['seconds_wall']:.4f},"
                    f"{r['speedup_render']:.3f},{r['speedup_wall']:.3f}\n")
    with open(os.path.join(args.out, "threads.md"), "w") as f:
        f.write(f"# render --threads N against --threads 1\n\n{provenance(args.binary)}\n\n`bench/threads --repeat {args.repeat}` on "
                f"{os.cpu_count()} cores: the fastest of the repeats, interleaved; render = seconds_render of "
                "--stats-json (scanning, shading and writing the PNG).\n\n")
        f.write("| case | threads | render s | process s | speed-up (render) | speed-up (process) |\n|---|---|---|---|---|---|\n")
        for r in rows:
            f.write(f"| {r['case']} | {r['threads']} | {r['seconds_render']:.3f} | {r['seconds_wall']:.3f} | "
                    f"{r['speedup_render']:.2f} | {r['speedup_wall']:.2f} |\n")
        if pov_rows:
            f.write(f"\n## POV-Ray beside patchscan\n\nThe teapot at 4096x3072 aa 1, the same camera, whole "
                    f"processes (load, render, PNG written): patchscan theta16 and POV-Ray 3.7's bicubic_patch "
                    f"({2 ** args.povray_steps}x{2 ** args.povray_steps} pieces a patch) on the same number of "
                    "threads (+WT N), interleaved, the fastest of the repeats.\n\n"
                    "| threads | patchscan s | POV-Ray s | patchscan / POV-Ray |\n|---|---|---|---|\n")
            for r in pov_rows:
                f.write(f"| {r['threads']} | {r['patchscan']:.3f} | {r['povray']:.3f} | "
                        f"{r['patchscan'] / r['povray']:.3f} |\n")


if __name__ == "__main__":
    main()
