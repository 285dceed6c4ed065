"""Helpers shared by the bench scripts."""
import os
import subprocess
import sys


def framed_camera(binary, scene, extra, size):
    """The camera automatic framing picks, as explicit options, so that every render of the
    scene (and POV-Ray's) uses exactly the same one."""
    code, out, err = run([binary, "info", scene, "--size", size] + extra)
    if code != 0:
        sys.exit(f"bench: info {scene} failed:\n{err}")
    line = next(l for l in out.splitlines() if l.startswith("camera: "))
    fields = dict(part.strip().split(" ", 1) for part in line[len("camera: "):].split(", ")[1:5])
    vec = lambda t: tuple(float(x) for x in t.split(","))
    return {"eye": vec(fields["eye"]), "look-at": vec(fields["look-at"]), "up": vec(fields["up"]),
            "fov": float(fields["fov"])}


def camera_args(cam):
    return ["--eye", ",".join(map(repr, cam["eye"])), "--look-at", ",".join(map(repr, cam["look-at"])),
            "--up", ",".join(map(repr, cam["up"])), "--fov", repr(cam["fov"])]


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    return r.returncode, r.stdout, r.stderr


def publish(out_dir, name, lines):
    """Writes a report's lines as out_dir/name (a Markdown file) and prints them."""
    text = "\n".join(lines) + "\n"
    with open(os.path.join(out_dir, name), "w") as f:
        f.write(text)
    print(text, end="")
