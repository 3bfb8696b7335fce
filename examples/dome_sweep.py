#!/usr/bin/env python3
"""A lighting sweep from Python: turn the textured sky of scenes/bench/dome.json through a full
circle in 8 frames, render each, and print (or plot, with matplotlib) the image's mean luminance
against the dome's rotation. Needs the `illum` module (scripts/setup-debian.sh, then
scripts/test.sh builds it into .venv-py; or `maturin develop` in python/).

    .venv-py/bin/python examples/dome_sweep.py [--spp 16] [--width 160] [--plot sweep.png]
"""
import argparse
import json
import pathlib

import numpy as np

import illum

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "bench" / "dome.json"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--plot", metavar="PNG", help="also plot the sweep (needs matplotlib)")
    a = ap.parse_args()
    d = json.loads(SCENE.read_text())
    angles, means = [], []
    for i in range(a.frames):
        angle = 360.0 * i / a.frames
        d["lights"]["sky"]["dome"]["rotation"] = angle
        scene = illum.Scene.from_dict(d, base_dir=SCENE.parent)
        r = scene.render(spp=a.spp, width=a.width, seed=i)
        y = r.beauty @ np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)
        angles.append(angle)
        means.append(float(y.mean()))
        print(f"rotation {angle:6.1f} deg: mean luminance {means[-1]:.5f} "
              f"({r.spp} spp, {float(r.metadata['illum.renderSeconds']):.2f} s)")
    if a.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        plt.plot(angles, means, marker="o")
        plt.xlabel("dome rotation (degrees)")
        plt.ylabel("mean luminance")
        plt.savefig(a.plot, dpi=100)
        print(f"wrote {a.plot}")


if __name__ == "__main__":
    main()
