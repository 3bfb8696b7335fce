#!/usr/bin/env python3
"""Camera samples per CPU-second of illum binaries, measured in interleaved runs.

On a shared machine wall-clock throughput scatters by up to 2x with other people's load; the CPU
time the render process is charged scatters far less (about +-5% at load average 6 on 2 cores).
Each measurement renders a scene twice, at --spp 1 and at --spp N, and takes

    M camera samples per CPU-second = W * H * (N - 1) / (cpu(N) - cpu(1)) / 1e6,

so process start-up, scene upload and kernel creation (the same in both runs) cancel. cpu() is
user + system time of the child (wait4). Binaries are run interleaved (A, B, A, B, ...) for each
configuration, and the median over the rounds is printed with each binary's ratio to the first.

What it does not see: time a process waits without using a CPU (idle driver threads, an unequal
split of a dispatch between threads). Compare wall-clock figures for those.

    scripts/cpu-throughput.py --rounds 3 --spp 128 --bin target/release/illum --bin /tmp/other \\
        --config "dome=scenes/bench/dome.json" \\
        --config "dome 1/1=scenes/bench/dome.json --light-samples 1 --brdf-samples 1 --diffuse-mis"
"""

import argparse
import os
import re
import shlex
import statistics
import subprocess
import sys
import tempfile


def run(binary, args, spp, out):
    """CPU seconds, pixel count and estimated relMSE of one render."""
    cmd = [binary, "render", *args, "--spp", str(spp), "-o", out]
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    err = p.stderr.read()
    _, status, usage = os.wait4(p.pid, 0)
    size = re.search(r"(\d+)x(\d+) at", err)
    if status != 0 or not size:
        sys.exit(f"cpu-throughput: {' '.join(cmd)} failed (status {status}):\n{err[-2000:]}")
    rel = re.search(r"estimated relMSE ([0-9.eE+-]+)", err)
    pixels = int(size.group(1)) * int(size.group(2))
    return usage.ru_utime + usage.ru_stime, pixels, rel.group(1) if rel else "?"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", action="append", required=True, help="an illum binary (repeat; the first is the base)")
    ap.add_argument("--config", action="append", required=True,
                    help='"NAME=SCENE [render options]" (repeat)')
    ap.add_argument("--rounds", type=int, default=3, help="interleaved rounds (default 3)")
    ap.add_argument("--spp", type=int, default=128, help="samples per pixel of the long run (default 128)")
    ap.add_argument("--warm", action="store_true",
                    help="render each configuration once at 1 spp first (fills the driver's kernel cache)")
    a = ap.parse_args()
    if a.spp < 2 or a.rounds < 1:
        ap.error("--spp must be at least 2 and --rounds at least 1")
    configs = []
    for c in a.config:
        name, sep, rest = c.partition("=")
        if not sep or not rest.strip():
            ap.error(f'--config "{c}": expected NAME=SCENE [options]')
        configs.append((name, shlex.split(rest)))
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.exr")
        if a.warm:
            for _, args in configs:
                for b in a.bin:
                    run(b, args, 1, out)
        rates, rel = {}, {}
        for _ in range(a.rounds):
            for name, args in configs:
                for b in a.bin:
                    c1, _, _ = run(b, args, 1, out)
                    cn, pixels, r = run(b, args, a.spp, out)
                    rates.setdefault((name, b), []).append(pixels * (a.spp - 1) / max(cn - c1, 1e-9) / 1e6)
                    rel[(name, b)] = r
    for name, _ in configs:
        print(name)
        base = statistics.median(rates[(name, a.bin[0])])
        for b in a.bin:
            v = rates[(name, b)]
            m = statistics.median(v)
            runs = " ".join(f"{x:.2f}" for x in v)
            print(f"  {b:40s} {m:7.3f} M/CPU-s (x{m / base:.2f})  [{runs}]  relMSE {rel[(name, b)]}")
    with open("/proc/loadavg") as f:
        print("load average:", " ".join(f.read().split()[:3]))


if __name__ == "__main__":
    main()
