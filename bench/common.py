"""Helpers shared by the bench scripts."""
import datetime
import os
import platform
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


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


def machine():
    """The machine a run measures: its processor, cores and memory, and the system."""
    model = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            model = next((l.split(":", 1)[1].strip() for l in f if l.startswith("model name")), model)
    except OSError:
        pass
    mem = ""
    try:
        with open("/proc/meminfo") as f:
            kib = next(int(l.split()[1]) for l in f if l.startswith("MemTotal:"))
        mem = f", {kib / 2 ** 20:.0f} GiB"
    except (OSError, StopIteration):
        pass
    return f"{model}, {os.cpu_count()} cores{mem}, {platform.system()} {platform.release()}"


def provenance(binary="build/patchscan"):
    """One line for the top of a page: when it was measured, on what commit and machine."""
    root = os.path.dirname(HERE)
    code, commit, _ = run(["git", "-C", root, "rev-parse", "--short=7", "HEAD"])
    commit = commit.strip() if code == 0 else "unknown"
    # Changes to what the program is built from (the pages this run writes are not).
    code, changes, _ = run(["git", "-C", root, "status", "--porcelain", "--untracked-files=no", "--",
                            "src", "cmake", "CMakeLists.txt"])
    if code == 0 and changes.strip():
        commit += " with changes to the source not yet committed"
    code, version, _ = run([binary, "--version"])
    version = version.strip() if code == 0 else "patchscan"
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return f"Measured {date} by `{version}`, commit {commit}, on {machine()}."


def publish(out_dir, name, lines, title, binary="build/patchscan"):
    """Writes a report's lines as out_dir/name (a Markdown page under `title`, with the run's
    date, commit and machine) and prints them."""
    text = "\n".join([f"# {title}", "", provenance(binary), ""] + lines) + "\n"
    with open(os.path.join(out_dir, name), "w") as f:
        f.write(text)
    print(text, end="")
