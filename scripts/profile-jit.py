#!/usr/bin/env python3
"""Where lavapipe's JIT code spends a render's time, by kind of instruction (docs/performance-kernels.md,
"The traversal stack's top in vectors"). For measurement only: needs perf and gdb.

Runs `illum render ARGS... --quiet` in the background, samples it with perf for --seconds once
--warmup seconds have passed (kernels compiled, the render under way), reads the hot JIT code
back from the running process with gdb, and classifies each sample by its instruction and the
one before it (perf's address is often the instruction after the one that stalled):

    private array   a load or store at rsp + offset + per-lane index: an array in the kernel's
                    private memory indexed per lane (lavapipe does these lane by lane)
    gather          a hardware gather (a load from a per-lane address)
    spill/fill      a fixed stack slot (register spills)
    other memory, alu/branch

    scripts/profile-jit.py render scenes/interior.json --integrator path --spp 100000
"""
import argparse
import collections
import os
import re
import signal
import subprocess
import sys
import tempfile
import time


def kind(s):
    if re.search(r"\(%rsp,%r\w+,[48]\)", s):
        return "private array"
    if "gather" in s:
        return "gather"
    if re.search(r"\(%rsp\)", s):
        return "spill/fill"
    if re.search(r"\(%r\w+(,%r\w+,[1248])?\)", s):
        return "other memory"
    return "alu/branch"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--illum", default="target/release/illum")
    ap.add_argument("--warmup", type=float, default=4.0)
    ap.add_argument("--seconds", type=float, default=6.0)
    ap.add_argument("--dump", metavar="FILE", help="write the hot code, each instruction with its samples")
    ap.add_argument("args", nargs=argparse.REMAINDER, help="illum arguments (render SCENE ...)")
    a = ap.parse_args()
    tmp = tempfile.mkdtemp()
    proc = subprocess.Popen([a.illum, *a.args, "--quiet"], stderr=subprocess.DEVNULL)
    try:
        time.sleep(a.warmup)
        data = os.path.join(tmp, "perf.data")
        subprocess.run(["perf", "record", "-F", "1999", "-p", str(proc.pid), "-o", data, "--",
                        "sleep", str(a.seconds)], check=True, capture_output=True)
        rows = subprocess.run(["perf", "script", "-i", data, "-F", "ip,dso"], check=True,
                              capture_output=True, text=True).stdout.splitlines()
        # JIT code belongs to no file: perf names it [unknown], //anon or its perf-PID.map.
        jit = (r.split(None, 1) for r in rows if re.search(r"\[unknown\]|//anon|perf-\d+\.map", r))
        hot = collections.Counter(int(f[0], 16) for f in jit)
        if not hot:
            sys.exit("profile-jit: no samples in JIT code: the render finished, or was still compiling its\n"
                     "kernels (a new build compiles them cold: run once before, or raise --warmup)")
        # Clusters of hot addresses, each read back as one range (the JIT heap has holes).
        addrs = sorted(hot)
        ranges, lo, hi = [], addrs[0], addrs[0]
        for x in addrs[1:]:
            if x - hi > 65536:
                ranges.append((lo, hi))
                lo = x
            hi = x
        ranges.append((lo, hi))
        # One gdb call a range, from no lower than its first page (the mapping may start
        # there): gdb gives up on the commands after one that cannot read.
        dis = ""
        for lo, hi in ranges:
            gdb = subprocess.run(["gdb", "-p", str(proc.pid), "-batch", "-ex",
                                  "disassemble 0x%x,0x%x" % (max(lo - 64, lo & ~0xfff), hi + 16)],
                                 capture_output=True, text=True)
            dis += gdb.stdout
            if "Cannot access memory" in gdb.stderr:
                print("profile-jit: gdb could not read 0x%x-0x%x:" % (lo, hi),
                      gdb.stderr.strip().splitlines()[-1], file=sys.stderr)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    code = {}
    for line in dis.splitlines():
        m = re.match(r"\s*(?:=> )?(0x[0-9a-f]+)(?: <[^>]*>)?:\s+(.*)", line)
        if m:
            code[int(m.group(1), 16)] = m.group(2)
    order = sorted(code)
    index = {x: i for i, x in enumerate(order)}
    total = sum(hot.values())
    kinds, arrays = collections.Counter(), collections.Counter()
    for x, n in hot.items():
        if x not in index:
            kinds["not read back"] += n
            continue
        i = index[x]
        before = code[order[i - 1]] if i > 0 else ""
        k = kind(before)
        k = kind(code[x]) if k == "alu/branch" else k
        kinds[k] += n
        for s in (before, code[x]):
            m = re.search(r"(0x[0-9a-f]+)\(%rsp,%r\w+,[48]\)", s)
            if m:
                arrays[m.group(1)] += n
                break
    if a.dump:
        with open(a.dump, "w") as f:
            for x in order:
                f.write("%6d %x: %s\n" % (hot.get(x, 0), x, code[x]))
    print("%d samples in JIT code" % total)
    for k, n in kinds.most_common():
        print("  %-16s %5.1f%%" % (k, 100.0 * n / total))
    print("private arrays by rsp offset:", ", ".join("%s %.1f%%" % (k, 100.0 * n / total)
                                                      for k, n in arrays.most_common(6)))


if __name__ == "__main__":
    main()
