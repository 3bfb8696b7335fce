#!/usr/bin/env python3
"""Option sets of illum against each other at equal render time (docs/allocation.md). For
measurement only: needs numpy and OpenEXR (the Python test venv has both) and a release build.

For each scene, --rounds rounds, interleaved: `illum render SCENE --time T --seed r` with each
option set. The efficiency of a set is the variance part of relMSE from pairs of its rounds,
mean((a - b)^2 / 2 / (ref^2 + 0.01)) with ref the mean of every round of every set, times the
seconds rendered / T (relMSE of an unbiased estimator falls as 1/time), averaged over the pairs:
free of bias and of a reference's own noise. Printed as ratios to the first set.

    .venv-py/bin/python scripts/equal-time.py --time 4 --set "fixed=--allocation fixed" \\
        --set "auto=" scenes/bench/suite/*.json scenes/bench/mitsuba-*.json

A set whose options start with @PATH runs the binary at PATH (two builds against each other:
`--set "before=@OTHER_BUILD/illum" --set "after="`, OTHER_BUILD a copy of another build).
"""
import argparse
import itertools
import os
import re
import shlex
import subprocess
import tempfile

import numpy as np
import OpenEXR


def rgb(path):
    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            return np.asarray(ch["RGB"].pixels, dtype=np.float64)
        return np.stack([np.asarray(ch[c].pixels, dtype=np.float64) for c in "RGB"], axis=-1)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--illum", default="target/release/illum")
    ap.add_argument("--time", type=float, default=4.0)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--set", action="append", required=True,
                    help="NAME=OPTIONS (repeatable); OPTIONS starting with @PATH run the binary at PATH")
    a = ap.parse_args()
    sets = [(s.split("=", 1)[0], shlex.split(s.split("=", 1)[1])) for s in a.set]
    sets = [(n, o[0][1:], o[1:]) if o and o[0].startswith("@") else (n, a.illum, o) for n, o in sets]
    out = os.path.join(tempfile.mkdtemp(), "r.exr")
    for scene in a.scenes:
        res = {n: [] for n, _, _ in sets}
        for r in range(a.rounds):
            for name, illum, opts in sets:
                cmd = [illum, "render", scene, "--time", str(a.time), "--spp", "1000000",
                       "--seed", str(r + 1), "-o", out] + opts
                p = subprocess.run(cmd, capture_output=True, text=True, check=True)
                m = re.search(r"at (\d+) spp.*render ([0-9.]+) s .*?([0-9.]+) rays per sample", p.stderr)
                res[name].append((rgb(out), float(m.group(2)), int(m.group(1)), float(m.group(3))))
        ref = np.mean([x[0] for xs in res.values() for x in xs], axis=0)
        rows = []
        for name, xs in res.items():
            es = [np.mean((x[0] - y[0]) ** 2 / 2 / (ref ** 2 + 0.01)) * (x[1] + y[1]) / 2 / a.time
                  for x, y in itertools.combinations(xs, 2)]
            rows.append((name, float(np.mean(es)), np.mean([x[2] for x in xs]), np.mean([x[3] for x in xs])))
        base = rows[0][1]
        print(os.path.basename(scene) + ": " + "; ".join(
            f"{n} {e:.3e} ({e / base:.2f}x, {spp:.0f} spp, {rays:.2f} rays a sample)"
            for n, e, spp, rays in rows), flush=True)


if __name__ == "__main__":
    main()
