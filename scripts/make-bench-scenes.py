#!/usr/bin/env python3
"""Writes the dome benchmark scenes (docs/performance-sampling.md, "The dome path"):
scenes/bench/dome.json (a procedural HDR sky with a small bright sun over diffuse and glossy spheres),
scenes/bench/rect.json (the same spheres under one rect light, the no-regression check),
scenes/bench/lights64.json (the same spheres under 32 sphere and 32 rect lights, the
many-light case) and the map scenes/bench/sky.exr (256x128 lat-long, illum's convention). Re-run after editing:
    python3 scripts/make-bench-scenes.py
"""
import importlib.util
import json
import math
import os

HERE = os.path.dirname(__file__)
OUT = os.path.join(HERE, "..", "scenes", "bench")
spec = importlib.util.spec_from_file_location("stress", os.path.join(HERE, "make-stress-scenes.py"))
stress = importlib.util.module_from_spec(spec)
spec.loader.exec_module(stress)

W, H = 256, 128
SUN = (0.45, 0.6)   # map uv of the sun


def sky(x, y):
    u, v = (x + 0.5) / W, (y + 0.5) / H
    theta = math.pi * v
    if v > 0.5:  # ground: dim, slightly warm, with a checker
        c = 0.08 if (x // 16 + y // 16) % 2 == 0 else 0.15
        return (c * 1.1, c, c * 0.9)
    up = math.cos(theta)
    base = (0.25 + 0.6 * up, 0.4 + 0.7 * up, 0.9 + 0.8 * up)
    # Clouds: a smooth bump pattern.
    cl = 0.5 + 0.5 * math.sin(11.0 * u * 2 * math.pi) * math.sin(5.0 * v * 2 * math.pi)
    base = tuple(b * (0.6 + 0.8 * cl) for b in base)
    du = min(abs(u - SUN[0]), 1 - abs(u - SUN[0])) * 2.0
    dv = v - (1 - SUN[1]) + 0.0
    d2 = (du * W) ** 2 + ((v - 0.3) * H) ** 2
    sun = 2000.0 * math.exp(-d2 / 2.0)
    return (base[0] + sun, base[1] + sun * 0.95, base[2] + sun * 0.85)


def glossy(alpha, diffuse):
    return {"diffuse": diffuse,
            "specular": [{"model": "dbrdf", "roughness": alpha,
                          "fresnel": {"schlick": [0.04, 0.04, 0.04]}}]}


def scene(lights, description):
    shapes = {"ground": {"rect": {"center": [0, 0, 0], "normal": [0, 1, 0], "size": [40, 40]},
                         "material": "ground"}}
    mats = {"ground": {"diffuse": [0.4, 0.4, 0.4]},
            "matte": {"diffuse": [0.7, 0.5, 0.3]},
            "glossy_0.3": glossy(0.3, [0.3, 0.06, 0.05]),
            "glossy_0.1": glossy(0.1, [0.05, 0.2, 0.3]),
            "metal": {"diffuse": [0, 0, 0],
                      "specular": [{"model": "dbrdf", "roughness": 0.2,
                                    "fresnel": {"constant": [0.9, 0.9, 0.9]}}]}}
    for k, m in enumerate(["matte", "glossy_0.3", "glossy_0.1", "metal"]):
        shapes["sphere_" + m] = {"sphere": {"center": [-2.4 + 1.6 * k, 0.7, 0], "radius": 0.7},
                                 "material": m}
    return {"$schema": "../../docs/scene.schema.json", "description": description,
            "camera": {"position": [0, 2.0, 7.0], "look_at": [0, 0.5, 0], "fov_y": 35,
                       "resolution": [320, 240]},
            "integrator": {"type": "direct"},
            "textures": {"sky": {"file": "sky.exr"}} if "sky" in lights else {},
            "materials": mats, "shapes": shapes, "lights": lights}


def many_lights():
    """32 small sphere lights and 32 rect lights facing the spheres, on two rings above them."""
    lights = {}
    for k in range(64):
        a = 2 * math.pi * (k + 0.5 * (k // 32)) / 32
        r, y = (4.0, 4.0) if k % 2 == 0 else (6.5, 5.5)
        c = [round(x, 4) for x in (r * math.cos(a), y, r * math.sin(a) + 1.0)]
        col = [round(0.6 + 0.4 * math.cos(a + p), 4) for p in (0, 2.1, 4.2)]
        power = 0.5 + 1.5 * ((k * 37) % 64) / 63  # assorted, deterministic
        if k < 32:
            lights["sphere%02d" % k] = {"sphere": {"center": c, "radius": 0.1},
                                        "color": col, "intensity": round(30 * power, 4)}
        else:
            n = [-x for x in c]
            n[1] = -c[1]
            lights["rect%02d" % (k - 32)] = {"rect": {"center": c, "normal": n,
                                                      "size": [0.4, 0.4]},
                                             "color": col, "intensity": round(6 * power, 4)}
    return lights


def main():
    os.makedirs(OUT, exist_ok=True)
    stress.write_exr(os.path.join(OUT, "sky.exr"), W, H, sky)
    dome = scene({"sky": {"dome": {}, "texture": "sky", "intensity": 1.0}},
                 "issue 15 dome benchmark: textured HDR sky (256x128, a bright sun) over diffuse "
                 "and glossy spheres")
    rect = scene({"key": {"rect": {"center": [-2, 5, 3], "normal": [2, -5, -3], "size": [2, 2]},
                          "color": [1, 0.97, 0.92], "intensity": 20}},
                 "issue 15 rect benchmark: the dome benchmark's spheres under one rect light")
    lights64 = scene(many_lights(), "issue 15 many-light benchmark: the dome benchmark's spheres "
                     "under 32 sphere and 32 rect lights of assorted colours and powers")
    for name, s in (("dome", dome), ("rect", rect), ("lights64", lights64)):
        with open(os.path.join(OUT, name + ".json"), "w") as f:
            json.dump(s, f, indent=2)
            f.write("\n")


if __name__ == "__main__":
    main()
