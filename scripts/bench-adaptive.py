#!/usr/bin/env python3
"""Adaptive sampling (--noise-threshold, --adaptive) against uniform sampling at equal time
(docs/adaptive-sampling.md). For measurement only: needs numpy and OpenEXR (pip) and a release
build of illum.

For each scene: a reference (uniform, --ref-spp samples, another seed; cached in --out), then
for each threshold T an adaptive render (and for each mean N of --means an --adaptive render of
N samples a pixel on average), and a uniform render given the adaptive one's render time
(--time). Per pixel, the squared relative error against the reference (epsilon 0.01, as
src/metrics.rs) less the reference's own (its Variance plane over the same denominator). The
table gives the image relMSE and the share of pixels whose error exceeds T² (what a noise
threshold promises to bound), the adaptive render's mean count and the uniform one's spp.

    python3 scripts/bench-adaptive.py scenes/bench/dome.json scenes/veach.json --width 160
"""
import argparse
import os
import re
import subprocess

import numpy as np
import OpenEXR

HERE = os.path.dirname(os.path.abspath(__file__))
ILLUM = os.path.join(HERE, "..", "target", "release", "illum")


def render(scene, out, args):
    cmd = [ILLUM, "render", scene, "-o", out, "--quiet"] + args
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: {p.stderr}")
    f = OpenEXR.File(out)
    ch = f.channels()
    seconds = float(np.ravel(f.header()["illum.renderSeconds"])[0])
    counts = ch["SampleCount"].pixels if "SampleCount" in ch else None
    return ch["RGB"].pixels.astype(np.float64), ch["Variance"].pixels.astype(np.float64), counts, seconds


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--thresholds", default="0.05,0.02")
    ap.add_argument("--means", default="", help="mean counts for --adaptive, e.g. 64,256")
    ap.add_argument("--ref-spp", type=int, default=16384)
    ap.add_argument("--out", default="bench-adaptive")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    print("| scene | T | adaptive: s, mean spp, relMSE, share > T² | uniform at equal time: spp, relMSE, share > T² |")
    print("|---|---|---|---|")
    for scene in a.scenes:
        name = re.sub(r"[^A-Za-z0-9]+", "-", os.path.relpath(scene, os.path.join(HERE, "..")))
        base = ["--width", str(a.width)]
        ref_path = os.path.join(a.out, f"{name}-ref-{a.width}-{a.ref_spp}.exr")
        if not os.path.exists(ref_path):
            render(scene, ref_path, base + ["--spp", str(a.ref_spp), "--seed", "1000"])
        f = OpenEXR.File(ref_path)
        ref = f.channels()["RGB"].pixels.astype(np.float64)
        ref_var = f.channels()["Variance"].pixels.astype(np.float64)
        den = ref * ref + 0.01

        def errors(img):
            e = (((img - ref) ** 2 - ref_var) / den).mean(axis=-1)
            return e

        runs = [(f"T {t}", ["--noise-threshold", t], float(t)) for t in a.thresholds.split(",") if t]
        runs += [(f"mean {n}", ["--adaptive", "--spp", n], None) for n in a.means.split(",") if n]
        for label, flags, t in runs:
            img, _, counts, secs = render(scene, os.path.join(a.out, "adaptive.exr"),
                                          base + flags + ["--seed", "3"])
            t = t if t is not None else 0.02
            e = errors(img)
            uimg, _, _, _ = render(scene, os.path.join(a.out, "uniform.exr"),
                                   base + ["--time", f"{secs:.4f}", "--seed", "3"])
            uf = OpenEXR.File(os.path.join(a.out, "uniform.exr"))
            uspp = uf.header()["illum.spp"]
            ue = errors(uimg)
            mean = counts.mean() if counts is not None else float("nan")
            print(f"| {scene} | {label} | {secs:.2f} s, {mean:.1f}, {e.mean():.2e}, {np.mean(e > t * t):.1%} "
                  f"| {uspp}, {ue.mean():.2e}, {np.mean(ue > t * t):.1%} |")


if __name__ == "__main__":
    main()
