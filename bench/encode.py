"""Bytes and seconds of writing the image, per format and compression: the teapot at
4096x3072, theta 16, aa 1, one thread (the encode then runs on the rendering thread, so
seconds_output of --stats-json is the encode and write alone), each setting rendered
--repeat times interleaved, the fastest kept. The scan and shading are the same work in
every run: seconds_render less seconds_output is the baseline the encode is set against.
Writes encode.csv and encode.md to --out."""
import argparse
import json
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(__file__))
from common import publish, run  # noqa: E402

# (extension, compression or "" for the format's default): each format's default first.
SETTINGS = [
    ("png", ""), ("png", "zip:6"), ("png", "zip:1"), ("png", "zip:3"), ("png", "zip:5"), ("png", "zip:9"), ("png", "none"),
    ("tif", ""), ("tif", "zip:1"), ("tif", "lzw"), ("tif", "none"),
    ("exr", ""), ("exr", "zips"), ("exr", "piz"), ("exr", "rle"), ("exr", "dwaa"), ("exr", "none"),
    ("jpg", ""), ("jpg", "jpeg:90"),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--binary", default="build/patchscan")
    ap.add_argument("--out", default="docs")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--size", default="4096x3072")
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args()
    best = {}
    with tempfile.TemporaryDirectory() as work:
        js = os.path.join(work, "stats.json")
        for _ in range(args.repeat):
            for ext, compression in SETTINGS:
                out = os.path.join(work, "out." + ext)
                cmd = [args.binary, "render", "surfaces/teapot.bpt", "-o", out, "--size", args.size, "--mode", "theta",
                       "--aa", "1", "--threads", str(args.threads), "--quiet", "--stats-json", js]
                if compression:
                    cmd += ["--compression", compression]
                code, _, err = run(cmd)
                if code != 0:
                    sys.exit(f"encode: {ext} {compression} failed:\n{err}")
                with open(js) as f:
                    stats = json.load(f)
                key = (ext, compression)
                entry = (stats["seconds_output"], stats["seconds_render"] - stats["seconds_output"], os.path.getsize(out))
                if key not in best or entry[0] < best[key][0]:
                    best[key] = entry
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "encode.csv"), "w") as f:
        f.write("format,compression,bytes,seconds_output,seconds_rest\n")
        for (ext, compression), (out_s, rest_s, size) in best.items():
            f.write(f"{ext},{compression or 'default'},{size},{out_s:.4f},{rest_s:.4f}\n")
    lines = [f"Writing the teapot at {args.size}, theta 16, aa 1, --threads {args.threads}: fastest of {args.repeat} "
             "(`python3 bench/encode.py`). 'rest' is the render without the output (the same work every run).", "",
             "| format | compression | bytes | seconds writing | seconds rest | writing / rest |", "|---|---|---|---|---|---|"]
    for (ext, compression), (out_s, rest_s, size) in best.items():
        lines.append(f"| .{ext} | {compression or 'default'} | {size:,} | {out_s:.3f} | {rest_s:.3f} | {out_s / rest_s:.2f} |")
    publish(args.out, "encode.md", lines, "Image formats and compressions", args.binary)


if __name__ == "__main__":
    main()
