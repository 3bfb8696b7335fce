#!/usr/bin/env python3
"""Writes a binary glTF (.glb) of a displaced grid with about N triangles, for benchmarks.

usage: scripts/make-mesh.py TRIANGLES OUT.glb
The grid spans [-1, 1]^2 in x/z with a smooth height field, positions and normals as float32,
indices as uint32. Standard library only.
"""
import json
import math
import struct
import sys


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    tris = int(sys.argv[1])
    out = sys.argv[2]
    n = max(1, int(math.sqrt(tris / 2)))  # n x n quads, 2 triangles each
    pos = bytearray()
    nrm = bytearray()
    lo = [1e30] * 3
    hi = [-1e30] * 3
    for j in range(n + 1):
        for i in range(n + 1):
            x = -1 + 2 * i / n
            z = -1 + 2 * j / n
            y = 0.1 * math.sin(6 * x) * math.cos(5 * z)
            dx = 0.6 * math.cos(6 * x) * math.cos(5 * z)
            dz = -0.5 * math.sin(6 * x) * math.sin(5 * z)
            ln = math.sqrt(dx * dx + 1 + dz * dz)
            pos += struct.pack("<3f", x, y, z)
            nrm += struct.pack("<3f", -dx / ln, 1 / ln, -dz / ln)
            for k, v in enumerate((x, y, z)):
                lo[k] = min(lo[k], v)
                hi[k] = max(hi[k], v)
    idx = bytearray()
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            b, c, d = a + 1, a + n + 1, a + n + 2
            idx += struct.pack("<6I", a, c, b, b, c, d)
    nv = (n + 1) * (n + 1)
    blob = bytes(pos) + bytes(nrm) + bytes(idx)
    doc = {
        "asset": {"version": "2.0", "generator": "illum scripts/make-mesh.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}],
        "buffers": [{"byteLength": len(blob)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(pos), "target": 34962},
            {"buffer": 0, "byteOffset": len(pos), "byteLength": len(nrm), "target": 34962},
            {"buffer": 0, "byteOffset": len(pos) + len(nrm), "byteLength": len(idx), "target": 34963},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": nv, "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5126, "count": nv, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5125, "count": 6 * n * n, "type": "SCALAR"},
        ],
    }
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    blob += b"\0" * (-len(blob) % 4)
    total = 12 + 8 + len(js) + 8 + len(blob)
    with open(out, "wb") as f:
        f.write(struct.pack("<III", 0x46546C67, 2, total))
        f.write(struct.pack("<II", len(js), 0x4E4F534A) + js)
        f.write(struct.pack("<II", len(blob), 0x004E4942) + blob)
    print(f"{out}: {2 * n * n} triangles, {nv} vertices")


if __name__ == "__main__":
    main()
