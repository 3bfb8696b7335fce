#!/usr/bin/env python3
"""Load time of a 1M-triangle mesh as a USD stage (.usdc and .usda) against the same mesh as glTF,
through `illum.load` (parse, compose, convert and validate; no device work). Run with the venv
that scripts/setup-debian.sh makes (usd-core writes the stages):

    .venv-py/bin/python scripts/bench-usd-load.py [N]      # N×N grid, 2(N-1)² triangles

Prints the median of 5 loads of each; docs/performance.md keeps the figures."""
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from pxr import Usd, UsdGeom, UsdLux, Vt

import illum

n = int(sys.argv[1]) if len(sys.argv) > 1 else 708
xs = np.linspace(-1, 1, n, dtype=np.float32)
gx, gz = np.meshgrid(xs, xs)
points = np.stack([gx, 0.1 * np.sin(8 * gx) * np.cos(8 * gz), gz], axis=-1).reshape(-1, 3)
i = np.arange(n * n, dtype=np.uint32).reshape(n, n)[:-1, :-1].reshape(-1)
tris = np.stack([i, i + n, i + 1, i + 1, i + n, i + n + 1], axis=-1).reshape(-1).astype(np.uint32)
print(f"{len(tris) // 3} triangles, {len(points)} points")

d = Path(tempfile.mkdtemp())
# glTF: one mesh, positions and indices in a .bin buffer.
(d / "grid.bin").write_bytes(points.tobytes() + tris.tobytes())
lo, hi = points.min(axis=0).tolist(), points.max(axis=0).tolist()
gltf = {
    "asset": {"version": "2.0"},
    "buffers": [{"uri": "grid.bin", "byteLength": points.nbytes + tris.nbytes}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": points.nbytes},
                    {"buffer": 0, "byteOffset": points.nbytes, "byteLength": tris.nbytes}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(points), "type": "VEC3",
                   "min": lo, "max": hi},
                  {"bufferView": 1, "componentType": 5125, "count": len(tris), "type": "SCALAR"}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0,
}
(d / "grid.gltf").write_text(json.dumps(gltf))
(d / "grid.json").write_text(json.dumps({
    "camera": {"position": [0, 2, 3], "look_at": [0, 0, 0], "fov_y": 40, "resolution": [64, 48]},
    "shapes": {"grid": {"gltf": {"file": "grid.gltf"}}},
    "lights": {"sky": {"dome": {}}},
}))
# USD: the same triangles as one Mesh, in binary and text crates.
stage = Usd.Stage.CreateNew(str(d / "grid.usdc"))
UsdGeom.Camera.Define(stage, "/Cam").AddTranslateOp().Set((0, 2, 3))
m = UsdGeom.Mesh.Define(stage, "/Grid")
m.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points))
m.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(tris) // 3, 3, dtype=np.int32)))
m.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(tris.astype(np.int32)))
m.CreateSubdivisionSchemeAttr("none")
UsdLux.DomeLight.Define(stage, "/Sky")
stage.Save()
stage.Export(str(d / "grid.usda"))

def median_load(path, runs=5):
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        illum.load(path)
        times.append(time.perf_counter() - t)
    return statistics.median(times)

g = median_load(d / "grid.json")
for name in ["grid.usdc", "grid.usda"]:
    u = median_load(d / name)
    print(f"{name}: {u:.3f} s; glTF: {g:.3f} s; USD / glTF = {u / g:.2f}"
          f" ({(d / name).stat().st_size / 1e6:.1f} MB against {(d / 'grid.bin').stat().st_size / 1e6:.1f} MB)")
