#!/usr/bin/env python3
"""Figures for `illum view` (docs/view.md): time to the first frame on a cold and a warm shader
cache, for `illum render` and `illum view`, and the time from saving an edit of the scene file
to the first frame that shows it, for a light, a material and a camera edit.

    scripts/bench-view.py [--scene scenes/default.json] [--width 256] [--integrator full]

Runs under the current DISPLAY, else starts Xvfb. Cold: Mesa's shader cache pointed at an empty
folder (MESA_SHADER_CACHE_DIR); warm: the same folder again.
"""
import argparse, json, os, re, shutil, subprocess, sys, tempfile, time

here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
illum = os.path.join(here, "target", "release", "illum")


def xvfb():
    if os.environ.get("DISPLAY"):
        return None
    for n in range(150, 250):
        if not os.path.exists(f"/tmp/.X{n}-lock"):
            p = subprocess.Popen(["Xvfb", f":{n}", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            for _ in range(200):
                if os.path.exists(f"/tmp/.X11-unix/X{n}"):
                    os.environ["DISPLAY"] = f":{n}"
                    return p
                time.sleep(0.05)
    sys.exit("no Xvfb display could be started")


def timed(cmd, env):
    t = time.monotonic()
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"{cmd}: {r.stderr}")
    return time.monotonic() - t, r.stderr


def background_compiles():
    """Processes compiling optimised kernels after a fast start (src/cli/fast_start/)."""
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/environ", "rb") as f:
                if b"ILLUM_FAST_START_COMPILE=1" in f.read():
                    found.append(pid)
        except OSError:
            pass
    return found


def settle():
    """Waits for background compiles to end: they write into the cache the next run measures."""
    t = time.monotonic()
    while background_compiles() and time.monotonic() - t < 300:
        time.sleep(0.1)


def save(path, doc):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(doc, f, indent=1)
    os.replace(tmp, path)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default=os.path.join(here, "scenes", "default.json"))
    ap.add_argument("--width", default="256")
    ap.add_argument("--integrator", default=None)
    a = ap.parse_args()
    server = xvfb()
    work = tempfile.mkdtemp(prefix="illum-bench-view-")
    scene = os.path.join(work, "scene.json")
    with open(a.scene) as f:
        doc = json.load(f)
    save(scene, doc)
    extra = ["--width", a.width] + (["--integrator", a.integrator] if a.integrator else [])
    env = dict(os.environ, MESA_SHADER_CACHE_DIR=os.path.join(work, "cache"))
    print(f"scene {a.scene}, width {a.width}")
    for label in ["cold", "warm"]:
        t, err = timed([illum, "render", scene, "--spp", "1", "-o", os.path.join(work, "r.exr")] + extra, env)
        whose = " (the fast start's second process's image)" if "fast start: this image" in err else ""
        print(f"  render --spp 1, {label} cache: {t:.2f} s process{whose}")
        settle()
    shutil.rmtree(os.path.join(work, "cache"))
    for label in ["cold", "warm"]:
        t, err = timed([illum, "view", scene, "--frames", "1", "-o", os.path.join(work, "v.exr")] + extra, env)
        m = re.search(r"first frame ([0-9.]+) s after start", err)
        print(f"  view, first frame, {label} cache: {m.group(1) if m else '?'} s after start ({t:.2f} s process)")
    # Edits while the view runs.
    v = subprocess.Popen([illum, "view", scene, "-o", os.path.join(work, "v.exr"), "--spp", "64"] + extra,
                         env=env, stderr=subprocess.PIPE, text=True)

    def wait(what):
        for line in v.stderr:
            if what in line:
                return line.strip()
        sys.exit(f"the view ended before saying {what!r}")

    wait("first frame")
    time.sleep(1.0)
    light = next(iter(doc["lights"]))
    material = next(iter(doc.get("materials", {})), None)
    edits = [("light", lambda d: d["lights"][light].__setitem__("intensity", d["lights"][light].get("intensity", 1) * 0.5))]
    if material:
        edits.append(("material", lambda d: d["materials"][material].__setitem__("diffuse", [0.2, 0.5, 0.8])))
    edits.append(("camera", lambda d: d["camera"]["position"].__setitem__(0, d["camera"]["position"][0] + 0.3)))
    for name, edit in edits:
        edit(doc)
        save(scene, doc)
        line = wait("applied the edit")
        m = re.search(r": (.*); first updated frame ([0-9.]+) s after applying it, ([0-9.]+) s after the save", line)
        print(f"  {name} edit: {m.group(3)} s from save to the first updated frame ({m.group(1)})")
        time.sleep(1.0)
    v.terminate()
    v.wait()
    if server:
        server.terminate()
    shutil.rmtree(work)


main()
