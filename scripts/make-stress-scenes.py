#!/usr/bin/env python3
"""Writes the stress suite, scenes/stress/*.json and the dome map dome-hot-pixel.exr.

Each scene is one numerically hard case; its "description" says what is extreme. The cases and
their references are listed in src/stress/mod.rs (CASES). Re-run after editing:
    python3 scripts/make-stress-scenes.py
"""
import json
import math
import os
import re
import struct

OUT = os.path.join(os.path.dirname(__file__), "..", "scenes", "stress")
SIZE = [64, 64]


def floor(material, size=40.0, center=(0.0, 0.0, 0.0)):
    return {"rect": {"center": list(center), "normal": [0, 1, 0], "size": [size, size]},
            "material": material}


def lambert(a):
    return {"diffuse": [a, a, a]}


def lobe(model, alpha, f=0.9, diffuse=0.05, tangent=None):
    m = {"diffuse": [diffuse] * 3,
         "specular": [{"model": model, "roughness": alpha, "fresnel": {"constant": [f, f, f]}}]}
    if tangent:
        m["tangent"] = tangent
    return m


def camera(pos, at, fov, up=None):
    c = {"position": pos, "look_at": at, "fov_y": fov, "resolution": SIZE}
    if up:
        c["up"] = up
    return c


def two_lobes(alpha, description, lights, cam=None, f=0.9, diffuse=0.05, tangent=None):
    """A floor of two halves: the D-BRDF on the left, GGX on the right."""
    return {
        "description": description,
        "camera": cam or camera([0, 3, 4], [0, 0, 0], 40),
        "materials": {"dbrdf": lobe("dbrdf", alpha, f, diffuse, tangent),
                      "ggx": lobe("ggx", alpha, f, diffuse, tangent)},
        "shapes": {
            "left": {"rect": {"center": [-10, 0, 0], "normal": [0, 1, 0], "size": [20, 40]},
                     "material": "dbrdf"},
            "right": {"rect": {"center": [10, 0, 0], "normal": [0, 1, 0], "size": [20, 40]},
                      "material": "ggx"},
        },
        "lights": lights,
    }


DOME = {"sky": {"dome": {}, "intensity": 1.0}}


def write_exr(path, w, h, pixel):
    """Uncompressed scanline OpenEXR, FLOAT B, G, R; pixel(x, y) -> (r, g, b)."""
    def attr(name, kind, data):
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(data)) + data
    chans = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in "BGR") + b"\0"
    box = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    header = (struct.pack("<ii", 20000630, 2)
              + attr("channels", "chlist", chans)
              + attr("compression", "compression", b"\0")
              + attr("dataWindow", "box2i", box)
              + attr("displayWindow", "box2i", box)
              + attr("lineOrder", "lineOrder", b"\0")
              + attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
              + attr("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
              + attr("screenWindowWidth", "float", struct.pack("<f", 1.0))
              + b"\0")
    line_bytes = 3 * 4 * w
    first = len(header) + 8 * h
    offsets = b"".join(struct.pack("<Q", first + y * (8 + line_bytes)) for y in range(h))
    body = b""
    for y in range(h):
        px = [pixel(x, y) for x in range(w)]
        data = b"".join(struct.pack("<%df" % w, *[p[c] for p in px]) for c in (2, 1, 0))
        body += struct.pack("<ii", y, len(data)) + data
    with open(path, "wb") as f:
        f.write(header + offsets + body)


def ccw_up(positions, a, b, c, up):
    """The triangle (a, b, c) wound so that its normal points along `up` (+1: +Y, -1: -Y)."""
    pa, pb, pc = positions[a], positions[b], positions[c]
    ny = (pb[2] - pa[2]) * (pc[0] - pa[0]) - (pb[0] - pa[0]) * (pc[2] - pa[2])
    return [a, b, c] if ny * up > 0 else [a, c, b]


def sliver_floor(h=10.0, n=24):
    """The square [-h, h]² of the plane y = 0 as a fan from its corner (-h, h) whose triangles
    narrow geometrically to 2h·1e-9 wide (aspect ratio 1e9; in float32 the last ones have zero
    area), with zero-area triangles (repeated and collinear vertices) among them."""
    apex = [-h, 0.0, h]
    rim = [[h - 2 * h * 10 ** (-9 * j / n), 0.0, -h] for j in range(n + 1)]   # far edge
    rim += [[h, 0.0, -h]]
    rim += [[h, 0.0, -h + 2 * h * 10 ** (-9 * (n - k) / n)] for k in range(n + 1)]  # right edge
    positions = [apex] + rim
    idx = []
    for k in range(1, len(rim)):
        a, b = k, k + 1
        idx += ccw_up(positions, 0, a, b, 1)
        if k % 6 == 0:
            idx += [0, a, a, a, a, b]   # repeated vertices: zero area
    # Collinear: the apex, the midpoint of its edge to the first rim point, and that point.
    positions.append([(apex[0] + rim[0][0]) / 2, 0.0, (apex[2] + rim[0][2]) / 2])
    idx += [0, len(positions) - 1, 1]
    return positions, idx


def sliver_emitter(y, half, n=16):
    """A square emitter facing down (-Y) at height y, cut into strips that narrow to 1e-7 of its
    width, each strip two slivers, plus a zero-area triangle per strip."""
    positions, idx = [], []
    xs = [-half] + [half - 2 * half * 10 ** (-7 * j / n) for j in range(1, n + 1)] + [half]
    for k in range(len(xs) - 1):
        x0, x1 = xs[k], xs[k + 1]
        base = len(positions)
        positions += [[x0, y, -half], [x1, y, -half], [x1, y, half], [x0, y, half]]
        idx += ccw_up(positions, base, base + 1, base + 2, -1)
        idx += ccw_up(positions, base, base + 2, base + 3, -1)
        idx += [base, base, base + 2]
    return positions, idx


def scenes():
    s = {}
    s["microfacet-alpha-1e-4"] = two_lobes(
        1e-4, "D-BRDF (left) and GGX (right) at alpha 1e-4, Mitsuba's floor: the sharpest lobes sampled (peak D 3e7), under a constant dome", DOME)
    s["microfacet-alpha-1e-3"] = two_lobes(
        1e-3, "D-BRDF and GGX at alpha 1e-3 (peak D 3e5), under a constant dome", DOME)
    s["microfacet-alpha-1"] = two_lobes(
        1.0, "D-BRDF and GGX at alpha 1: half the D-BRDF's samples go below the horizon",
        {"key": {"rect": {"center": [0, 2, 0], "normal": [0, -1, 0], "size": [1, 1]},
                 "intensity": 10, "visible": False},
         "sky": {"dome": {}, "intensity": 0.2}}, diffuse=0.1)
    s["anisotropic-100"] = two_lobes(
        [0.3, 0.003], "anisotropic D-BRDF and GGX, alpha 0.3 x 0.003 (100:1)",
        {"strip": {"rect": {"center": [0, 2, -1], "normal": [0, -1, 0.3], "size": [3, 0.2]},
                   "intensity": 20, "visible": False},
         "bulb": {"sphere": {"center": [1, 1, 1], "radius": 0.05}, "intensity": 500,
                  "visible": False}},
        tangent=[1, 0, 0], diffuse=0.1)
    beta = math.radians(0.06)  # view direction below the horizon
    s["grazing-diffuse"] = {
        "description": "view and light at grazing angles: n.v from 1.7e-4, sun at n.l = 1e-4",
        "camera": camera([0, 1, 0], [0, 1 - 1000 * math.tan(beta), -1000], 0.1),
        "materials": {"floor": lambert(0.5)},
        "shapes": {"floor": floor("floor", 2e4)},
        "lights": {"sky": {"dome": {}, "intensity": 0.5},
                   "sun": {"sun": {"direction": [1, 1e-4, 0], "angular_diameter": 0},
                           "intensity": 1e4}},
    }
    beta = math.radians(1.0)
    s["grazing-glossy"] = two_lobes(
        0.05, "glossy D-BRDF and GGX (alpha 0.05) seen and lit at grazing angles: n.v from 4e-3, "
        "a 0.53 degree sun cut by the horizon, a sphere light at n.l = 0.01",
        {"sun": {"sun": {"direction": [0, math.tan(math.radians(0.2)), -1]}, "intensity": 50},
         "bulb": {"sphere": {"center": [0, 1, -100], "radius": 1}, "intensity": 100,
                  "visible": False}},
        cam=camera([0, 0.05, 5], [0, 0.05 - 1000 * math.tan(beta), 5 - 1000], 1.5), diffuse=0.1)
    s["sphere-light-tiny"] = {
        "description": "sphere light of radius 1e-4 and radiance 1e8 at distance 1",
        "camera": camera([0, 2, 2], [0, 0, 0], 60),
        "materials": {"floor": lambert(0.8)},
        "shapes": {"floor": floor("floor")},
        "lights": {"bulb": {"sphere": {"center": [0, 1, 0], "radius": 1e-4}, "intensity": 1e8,
                            "visible": False}},
    }
    s["sphere-light-touching"] = {
        "description": "sphere light of radius 0.5 a hair (1e-5) above the floor it lights",
        "camera": camera([0, 3, 3], [0, 0, 0], 50),
        "materials": {"floor": lambert(0.8)},
        "shapes": {"floor": floor("floor")},
        "lights": {"ball": {"sphere": {"center": [0, 0.50001, 0], "radius": 0.5},
                            "intensity": 1, "visible": False}},
    }
    s["rect-light-huge-far"] = {
        "description": "rect light 1e4 wide, 1e5 away",
        "camera": camera([0, 2, 2], [0, 0, 0], 60),
        "materials": {"floor": lambert(0.8)},
        "shapes": {"floor": floor("floor")},
        "lights": {"sky_panel": {"rect": {"center": [0, 1e5, 0], "normal": [0, -1, 0],
                                          "size": [1e4, 1e4]},
                                 "intensity": 100, "visible": False}},
    }
    o = 1e5
    s["far-from-origin"] = {
        "description": "the whole scene (mesh floor, sphere light, sun) translated 1e5 from the origin",
        "camera": camera([o, o + 2, o + 2], [o, o, o], 60),
        "materials": {"floor": lambert(0.8)},
        "shapes": {"floor": {"mesh": {"positions": [[-20, 0, -20], [-20, 0, 20], [20, 0, 20],
                                                    [20, 0, -20]],
                                      "indices": [0, 1, 2, 0, 2, 3]},
                             "material": "floor", "transform": {"translate": [o, o, o]}}},
        "lights": {"bulb": {"sphere": {"center": [o + 0.3, o + 1, o], "radius": 0.2},
                            "intensity": 10, "visible": False},
                   "sun": {"sun": {"direction": [1, 2, 0.5], "angular_diameter": 0},
                           "intensity": 1}},
    }
    s["dome-hot-pixel"] = {
        "description": "dome map black except one texel of 1e6 (64x32 map)",
        "camera": camera([0, 2, 2], [0, 0, 0], 60),
        "textures": {"hot": {"file": "dome-hot-pixel.exr"}},
        "materials": {"floor": lambert(0.8)},
        "shapes": {"floor": floor("floor")},
        "lights": {"sky": {"dome": {}, "texture": "hot", "visible": False}},
    }
    fp, fi = sliver_floor()
    ep, ei = sliver_emitter(3.0, 1.0)
    s["triangles-degenerate"] = {
        "description": "floor and emitter made of sliver triangles (aspect ratio up to 1e9) and "
                       "zero-area ones (repeated and collinear vertices)",
        "camera": camera([0, 3, 3], [0, 0, 0], 50),
        "materials": {"floor": lambert(0.8), "glow": {"diffuse": [0, 0, 0], "emission": [2, 2, 2]}},
        "shapes": {"floor": {"mesh": {"positions": fp, "indices": fi}, "material": "floor"},
                   "panel": {"mesh": {"positions": ep, "indices": ei}, "material": "glow"}},
    }
    s["lights-zero"] = {
        "description": "zero-size lights (rect of width 0, sphere and disk of radius 0) and "
                       "zero-intensity ones beside one sphere light",
        "camera": camera([0, 2, 2], [0, 0, 0], 60),
        "materials": {"floor": lambert(0.8)},
        "shapes": {"floor": floor("floor")},
        "lights": {
            "flat": {"rect": {"center": [0, 1, 0], "normal": [0, -1, 0], "size": [0, 1]},
                     "intensity": 5},
            "point": {"sphere": {"center": [0.5, 1, 0], "radius": 0}, "intensity": 5},
            "dot": {"disk": {"center": [-0.5, 1, 0], "normal": [0, -1, 0], "radius": 0},
                    "intensity": 5},
            "off": {"rect": {"center": [0, 1.5, 0], "normal": [0, -1, 0], "size": [1, 1]},
                    "intensity": 0},
            "dark_sun": {"sun": {"direction": [0, 1, 0]}, "intensity": 0},
            "bulb": {"sphere": {"center": [0, 1.5, 0.5], "radius": 0.3}, "intensity": 5,
                     "visible": False},
        },
    }
    s["sun-delta"] = {
        "description": "sun of angular diameter 0 (a delta light)",
        "camera": camera([0, 2, 2], [0, 0, 0], 60),
        "materials": {"floor": lambert(0.5)},
        "shapes": {"floor": floor("floor")},
        "lights": {"sun": {"sun": {"direction": [1, math.sqrt(3), 0], "angular_diameter": 0},
                           "intensity": 3}},
    }
    el = math.radians(10)
    s["sun-30deg"] = {
        "description": "sun of angular diameter 30 degrees, 10 degrees above the horizon (cut by it)",
        "camera": camera([0, 2, 2], [0, 0, 0], 60),
        "materials": {"floor": lambert(0.5)},
        "shapes": {"floor": floor("floor")},
        "lights": {"sun": {"sun": {"direction": [math.cos(el), math.sin(el), 0],
                                   "angular_diameter": 30},
                           "intensity": 2}},
    }
    return s


def main():
    os.makedirs(OUT, exist_ok=True)
    for name, scene in scenes().items():
        # Each case tests a numeric extreme, not lights shadowing each other: where a scene has
        # several lights, its area lights cast no shadows, so the closed forms stay exact.
        lights = scene.get("lights", {})
        if len(lights) > 1:
            for light in lights.values():
                if any(k in light for k in ("rect", "disk", "sphere")):
                    light["shadows"] = False
        with open(os.path.join(OUT, name + ".json"), "w") as f:
            text = json.dumps({"$schema": "../../docs/scene.schema.json", **scene}, indent=2)
            # Arrays of numbers on one line.
            text = re.sub(r"\[\s+([-0-9.e+,\s]+?)\s+\]",
                          lambda m: "[" + ", ".join(m.group(1).split()).replace(",,", ",") + "]",
                          text)
            f.write(text + "\n")
    write_exr(os.path.join(OUT, "dome-hot-pixel.exr"), 64, 32,
              lambda x, y: (1e6, 1e6, 1e6) if (x, y) == (40, 10) else (0.0, 0.0, 0.0))


if __name__ == "__main__":
    main()
