#!/usr/bin/env python3
"""Writes the equal-time benchmark suite's own scenes (scenes/bench/suite/, docs/performance-sampling.md,
"The benchmark suite"): direct-lighting scenes of kinds the four bench scenes do not cover, each
convertible to Mitsuba 3 by scripts/to-mitsuba.py (analytic shapes, Lambert + one Beckmann/GGX
lobe with conductor or constant Fresnel, area lights, constant or Mitsuba-convention map domes,
delta suns). Deterministic (a fixed seed). Re-run after editing:
    python3 scripts/make-suite-scenes.py
"""
import json
import math
import os
import random

OUT = os.path.join(os.path.dirname(__file__), "..", "scenes", "bench", "suite")
DIELECTRIC = {"conductor": {"eta": [1.5, 1.5, 1.5], "k": [0, 0, 0]}}
GOLD = {"conductor": {"eta": [0.18, 0.42, 1.37], "k": [3.42, 2.35, 1.77]}}


def cam(pos, at, fov=40, res=(256, 192)):
    return {"position": list(pos), "look_at": list(at), "fov_y": fov, "resolution": list(res)}


def glossy(diffuse, alpha, fresnel=DIELECTRIC, model="beckmann"):
    return {"diffuse": list(diffuse),
            "specular": [{"model": model, "roughness": alpha, "fresnel": fresnel}]}


def rect(c, n, size, material=None, up=None):
    r = {"center": list(c), "normal": list(n), "size": list(size)}
    if up:
        r["up"] = list(up)
    return {"rect": r, "material": material} if material else {"rect": r}


def sphere(c, r, material):
    return {"sphere": {"center": list(c), "radius": r}, "material": material}


def room(materials, shapes, w=4.0, h=2.6, d=4.0, window=None):
    """A closed box room (walls facing in); `window`: (x0, x1, y0, y1) cut from the back wall."""
    materials.update({"wall": {"diffuse": [0.7, 0.7, 0.7]}, "red": {"diffuse": [0.65, 0.15, 0.12]},
                      "green": {"diffuse": [0.15, 0.5, 0.15]}})
    shapes["floor"] = rect((0, 0, 0), (0, 1, 0), (w, d), "wall")
    shapes["ceiling"] = rect((0, h, 0), (0, -1, 0), (w, d), "wall")
    shapes["left"] = rect((-w / 2, h / 2, 0), (1, 0, 0), (d, h), "red", up=(0, 1, 0))
    shapes["right"] = rect((w / 2, h / 2, 0), (-1, 0, 0), (d, h), "green", up=(0, 1, 0))
    shapes["front"] = rect((0, h / 2, d / 2), (0, 0, -1), (w, h), "wall", up=(0, 1, 0))
    if window is None:
        shapes["back"] = rect((0, h / 2, -d / 2), (0, 0, 1), (w, h), "wall", up=(0, 1, 0))
        return
    x0, x1, y0, y1 = window
    z = -d / 2
    for name, (a, b, c, e) in {"back_l": (-w / 2, x0, 0, h), "back_r": (x1, w / 2, 0, h),
                               "back_b": (x0, x1, 0, y0), "back_t": (x0, x1, y1, h)}.items():
        shapes[name] = rect(((a + b) / 2, (c + e) / 2, z), (0, 0, 1), (b - a, e - c), "wall",
                            up=(0, 1, 0))


def spheres_row(materials, shapes, y=0.5, r=0.5):
    materials.update({"matte": {"diffuse": [0.6, 0.5, 0.4]},
                      "plastic": glossy((0.1, 0.2, 0.5), 0.15),
                      "gold": glossy((0, 0, 0), 0.1, GOLD, "ggx")})
    for i, m in enumerate(["matte", "plastic", "gold"]):
        shapes["ball_" + m] = sphere(((i - 1) * 1.2, y, -0.4), r, m)


def scenes():
    rng = random.Random(2026)
    out = {}

    # A room lit through a window by a constant sky: the light arrives through a small opening.
    m, s = {}, {}
    room(m, s, window=(-0.6, 0.6, 1.0, 2.0))
    spheres_row(m, s)
    out["window-room"] = {"camera": cam((0, 1.3, 1.9), (0, 0.9, -1)), "materials": m, "shapes": s,
                          "lights": {"sky": {"dome": {}, "color": [0.9, 0.95, 1.0], "intensity": 3}}}

    # 300 sphere lights of log-uniform power (1e-2 .. 1e2) over spheres and a floor.
    m, s = {"floor": {"diffuse": [0.5, 0.5, 0.5]}}, {}
    s["floor"] = rect((0, 0, 0), (0, 1, 0), (20, 20), "floor")
    spheres_row(m, s)
    lights = {}
    for i in range(300):
        p = (rng.uniform(-5, 5), rng.uniform(1.5, 4), rng.uniform(-6, 2))
        lights["l%03d" % i] = {"sphere": {"center": list(p), "radius": 0.05},
                               "color": [rng.uniform(0.3, 1) for _ in range(3)],
                               "intensity": 10 ** rng.uniform(-1, 3) / 30}
    out["lights300-unequal"] = {"camera": cam((0, 1.6, 4.5), (0, 0.6, -0.5)), "materials": m,
                                "shapes": s, "lights": lights}

    # Tiny bright lights seen in glossy surfaces: highlights carry the image.
    m, s = {"floor": glossy((0.05, 0.05, 0.05), 0.02)}, {}
    s["floor"] = rect((0, 0, 0), (0, 1, 0), (20, 20), "floor")
    m["mirrorish"] = glossy((0, 0, 0), 0.01, GOLD, "ggx")
    m["rough"] = glossy((0.3, 0.3, 0.3), 0.05)
    s["b1"] = sphere((-0.7, 0.5, 0), 0.5, "mirrorish")
    s["b2"] = sphere((0.7, 0.5, 0), 0.5, "rough")
    lights = {"t%d" % i: {"sphere": {"center": [-2 + i, 2.5, -1.5 + 0.4 * i], "radius": 0.01},
                          "intensity": 4000.0} for i in range(5)}
    lights["fill"] = {"dome": {}, "color": [0.05, 0.05, 0.06]}
    out["tiny-lights-glossy"] = {"camera": cam((0, 1.2, 4), (0, 0.4, 0)), "materials": m,
                                 "shapes": s, "lights": lights}

    # Grazing delta sun and a constant sky over spheres on a plane.
    m, s = {"floor": {"diffuse": [0.45, 0.42, 0.4]}}, {}
    s["floor"] = rect((0, 0, 0), (0, 1, 0), (30, 30), "floor")
    spheres_row(m, s)
    out["sun-grazing"] = {"camera": cam((0, 1.5, 4.5), (0, 0.5, 0)), "materials": m, "shapes": s,
                          "lights": {"sun": {"sun": {"direction": [-1, -0.12, -0.3],
                                                     "angular_diameter": 0}, "intensity": 3},
                                     "sky": {"dome": {}, "color": [0.2, 0.3, 0.5]}}}

    # A light large and close: a 6x6 panel 0.6 above a floor with spheres under it.
    m, s = {"floor": {"diffuse": [0.6, 0.6, 0.6]}}, {}
    s["floor"] = rect((0, 0, 0), (0, 1, 0), (20, 20), "floor")
    spheres_row(m, s, y=0.25, r=0.25)
    out["panel-close"] = {"camera": cam((0, 0.55, 3.5), (0, 0.2, 0)), "materials": m, "shapes": s,
                          "lights": {"panel": {"rect": {"center": [0, 0.7, 0], "normal": [0, -1, 0],
                                                        "size": [6, 6]}, "intensity": 1}}}

    # Soft shadows: a disk light half hidden by a blocker above spheres.
    m, s = {"floor": {"diffuse": [0.6, 0.6, 0.6]}, "black": {"diffuse": [0.05, 0.05, 0.05]}}, {}
    s["floor"] = rect((0, 0, 0), (0, 1, 0), (20, 20), "floor")
    spheres_row(m, s)
    s["blocker"] = rect((0.4, 2.2, 0), (0, -1, 0), (1.2, 3), "black")
    out["penumbra-disk"] = {"camera": cam((0, 2.0, 4.5), (0, 0.5, 0)), "materials": m, "shapes": s,
                            "lights": {"disk": {"disk": {"center": [0, 3, 0], "normal": [0, -1, 0],
                                                         "radius": 1.0}, "intensity": 6}}}

    # A grid of 16 small rect lights over a glossy floor: reflections of every light.
    m, s = {"floor": glossy((0.2, 0.2, 0.22), 0.08)}, {}
    s["floor"] = rect((0, 0, 0), (0, 1, 0), (20, 20), "floor")
    spheres_row(m, s)
    lights = {"g%d%d" % (i, j): {"rect": {"center": [-1.5 + i, 2.5, -2.5 + j],
                                          "normal": [0, -1, 0], "size": [0.25, 0.25]},
                                 "intensity": 20} for i in range(4) for j in range(4)}
    out["grid16-glossy"] = {"camera": cam((0, 1.5, 4), (0, 0.4, -0.5)), "materials": m,
                            "shapes": s, "lights": lights}

    # A closed room with one small ceiling light, a matte and a gold sphere (issue 25's kind).
    m, s = {}, {}
    room(m, s)
    spheres_row(m, s)
    out["room-one-rect"] = {"camera": cam((0, 1.3, 1.9), (0, 0.9, -1)), "materials": m,
                            "shapes": s,
                            "lights": {"key": {"rect": {"center": [0, 2.59, -0.3],
                                                        "normal": [0, -1, 0], "size": [0.5, 0.5]},
                                               "intensity": 20}}}
    return out


def main():
    os.makedirs(OUT, exist_ok=True)
    for name, scene in scenes().items():
        scene = {"description": "benchmark suite: " + name + " (scripts/make-suite-scenes.py)",
                 "integrator": {"type": "direct"}, **scene}
        with open(os.path.join(OUT, name + ".json"), "w") as f:
            json.dump(scene, f, indent=1)
            f.write("\n")


if __name__ == "__main__":
    main()
