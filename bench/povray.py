"""POV-Ray's rendering of the same Bézier patches (bicubic_patch), for the benches: the
scene file, the command, and its time. POV-Ray is left-handed with y up: world (x, y, z)
maps to (x, z, y), a reflection that keeps the image the same way round."""
import math
import shutil
import subprocess
import time


def read_bpt(path):
    with open(path) as f:
        words = [w for line in f for w in line.split("#")[0].split()]
    count, k, patches = int(words[0]), 1, []
    for _ in range(count):
        k += 2
        patches.append([tuple(float(x) for x in words[k + 3 * i:k + 3 * i + 3]) for i in range(16)])
        k += 48
    return patches


def pov(p):
    return f"<{p[0]:.9g},{p[2]:.9g},{p[1]:.9g}>"


def write_scene(bpt, path, eye, look_at, up, fov_deg, width, height, steps):
    """`steps`: POV-Ray subdivides each patch into 2^steps × 2^steps pieces."""
    hfov = 2 * math.degrees(math.atan(math.tan(math.radians(fov_deg) / 2) * width / height))
    with open(path, "w") as f:
        f.write("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\n")
        f.write(f"camera {{ perspective location {pov(eye)} sky {pov(up)} up y right x*{width}/{height} "
                f"angle {hfov:.9g} look_at {pov(look_at)} }}\n")
        f.write(f"light_source {{ {pov(eye)} color rgb 1 }}\n")
        for p in read_bpt(bpt):
            f.write(f"bicubic_patch {{ type 1 flatness 0 u_steps {steps} v_steps {steps}\n")
            f.write(",".join(pov(q) for q in p))
            f.write("\n pigment { color rgb 0.8 } }\n")


def render(scene, out_png, width, height, aa, threads=1):
    """Renders on `threads` threads (+WT); returns wall seconds, or None when povray is missing."""
    if not shutil.which("povray"):
        return None
    cmd = ["povray", f"+I{scene}", f"+O{out_png}", f"+W{width}", f"+H{height}", "+FN", "+UA",
           "-D", f"+WT{threads}", "-GA"]
    # Antialiasing: method 1 with threshold 0 supersamples every pixel, depth aa.
    cmd += [f"+A0.0", "+AM1", f"+R{aa}"] if aa > 1 else ["-A"]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    secs = time.perf_counter() - t0
    if r.returncode != 0:
        raise RuntimeError(f"povray failed ({r.returncode}): {r.stderr[-2000:]}")
    return secs
