#!/usr/bin/env python3
"""Converts an illum scene (docs/scene-format.md) into a Mitsuba 3 scene dict, for measurement only
(docs/performance-sampling.md, "Against Mitsuba 3 at equal time"); Mitsuba is not a dependency of illum.

The conventions are the ones docs/scene-format.md shares with Mitsuba 3: radiance in W m^-2 sr^-1,
one-sided area emitters, +Y up, vertical fov, alpha roughness. What has no exact Mitsuba 3
counterpart is refused with a message naming the field: the course's D-BRDF (no shadowing term),
Schlick Fresnel, illum's own dome mapping, finite suns, textures on surfaces, meshes and glTF.
`--comparable OUT.json` writes the nearest scene that converts (dbrdf -> beckmann, Schlick f0 ->
the exact dielectric Fresnel of eta = (1 + sqrt f0) / (1 - sqrt f0), the dome's map read with
Mitsuba's convention): render that one with both renderers.

A material (Lambert diffuse + one specular lobe, summed) becomes Mitsuba's blendbsdf at weight 1/2
of the doubled components, which is their sum; Mitsuba's diffuse and roughconductor do not clamp
reflectances above 1. Integrator: `direct` with 1 emitter and 1 BSDF sample per camera sample
for an illum `direct` scene, `path` (max_depth as the scene's, -1 unless given) for a `path` or
`full` one; `independent` sampler, box reconstruction filter (illum integrates a box pixel).

    to-mitsuba.py SCENE.json --spp N -o out.exr      # render (needs the mitsuba package)
    to-mitsuba.py SCENE.json --comparable OUT.json   # the convertible variant (no mitsuba needed)

Mitsuba's llvm variants need LLVM >= 16 (Debian 12's libLLVM 15 fails on `fminimum`): set
DRJIT_LIBLLVM_PATH, e.g. to /usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 (apt-get install libllvm19).
"""
import argparse
import copy
import json
import math
import os
import sys


class Unsupported(Exception):
    pass


def _norm(v):
    n = math.sqrt(sum(c * c for c in v))
    if n == 0:
        raise Unsupported("zero-length vector %r" % (v,))
    return [c / n for c in v]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def _frame(normal, up=None):
    """illum's rect frame (docs/scene-format.md, rect): u_dir, v_dir, n with u x v = n."""
    n = _norm(normal)
    if up is None:
        up = [0, 0, -1] if abs(n[1]) > 0.999 else [0, 1, 0]
    d = _dot(up, n)
    v = _norm([up[i] - d * n[i] for i in range(3)])
    u = _cross(v, n)
    return u, v, n


def _matrix(u, v, n, c):
    """Row-major 4x4 with columns u, v, n and translation c (Mitsuba's local x, y, z)."""
    return [[u[0], v[0], n[0], c[0]], [u[1], v[1], n[1], c[1]],
            [u[2], v[2], n[2], c[2]], [0, 0, 0, 1]]


def _radiance(light, where):
    s = light.get("intensity", 1.0) * 2.0 ** light.get("exposure", 0.0)
    return [c * s for c in light.get("color", [1, 1, 1])]


def _check_fields(obj, allowed, where):
    for k in obj:
        if k not in allowed:
            raise Unsupported("%s: field %r has no Mitsuba 3 counterpart in this converter"
                              % (where, k))


def _unbounded(rgb):
    """An RGB value that may exceed 1 (the plain "rgb" form rejects reflectances above 1)."""
    return {"type": "srgb", "color": rgb, "unbounded": True}


def _bsdf(name, m):
    where = "materials.%s" % name
    _check_fields(m, {"diffuse", "specular", "emission", "two_sided"}, where)
    kd = m.get("diffuse", [0.5, 0.5, 0.5])
    lobes = m.get("specular", [])
    if len(lobes) > 1:
        raise Unsupported("%s.specular: %d lobes; only one converts" % (where, len(lobes)))
    parts = []
    if any(c > 0 for c in kd):
        parts.append(("diffuse", {"type": "diffuse",
                                  "reflectance": {"type": "rgb", "value": list(kd)}}))
    for i, lobe in enumerate(lobes):
        lw = "%s.specular[%d]" % (where, i)
        _check_fields(lobe, {"model", "roughness", "fresnel"}, lw)
        model = lobe["model"]
        if model not in ("beckmann", "ggx"):
            raise Unsupported("%s.model: %r has no Mitsuba 3 counterpart (the D-BRDF has no "
                              "shadowing term); use beckmann (roughconductor) or --comparable"
                              % (lw, model))
        r = lobe["roughness"]
        ax, ay = (r, r) if isinstance(r, (int, float)) else r
        if ax == 0 and ay == 0:
            raise Unsupported("%s.roughness: 0 (a delta mirror) is not converted" % lw)
        b = {"type": "roughconductor", "distribution": model,
             "alpha_u": max(ax, 1e-4), "alpha_v": max(ay, 1e-4)}
        fr = lobe.get("fresnel", {"schlick": [0.04, 0.04, 0.04]})
        if "constant" in fr:  # Mitsuba's conductor "none" reflects everything: F = 1
            b["material"] = "none"
            b["specular_reflectance"] = {"type": "rgb", "value": list(fr["constant"])}
        elif "conductor" in fr:
            b["eta"] = {"type": "rgb", "value": list(fr["conductor"]["eta"])}
            b["k"] = {"type": "rgb", "value": list(fr["conductor"]["k"])}
        else:
            raise Unsupported("%s.fresnel: %s has no Mitsuba 3 counterpart; use conductor or "
                              "--comparable" % (lw, list(fr)[0]))
        parts.append(("specular", b))
    if not parts:
        parts.append(("diffuse", {"type": "diffuse", "reflectance": {"type": "rgb",
                                                                     "value": [0, 0, 0]}}))
    if len(parts) == 1:
        bsdf = parts[0][1]
    else:  # the sum of two lobes: a half-half blend of each doubled
        a, b = copy.deepcopy(parts[0][1]), copy.deepcopy(parts[1][1])
        a["reflectance"] = _unbounded([2 * c for c in a["reflectance"]["value"]])
        ks = b.get("specular_reflectance", {"value": [1, 1, 1]})["value"]
        b["specular_reflectance"] = _unbounded([2 * c for c in ks])
        bsdf = {"type": "blendbsdf", "weight": 0.5, "a": a, "b": b}
    return {"type": "twosided", "bsdf": bsdf}


def _geometry(obj, where, light):
    """Mitsuba shape dict of an illum rect, disk or sphere (world space, no transform)."""
    keys = [k for k in ("rect", "disk", "sphere", "mesh", "gltf", "dome", "sun") if k in obj]
    if len(keys) != 1:
        raise Unsupported("%s: expected exactly one geometry key, found %r" % (where, keys))
    k = keys[0]
    g = obj[k]
    if k == "sphere":
        return {"type": "sphere", "center": g["center"], "radius": g["radius"]}
    if k == "rect":
        u, v, n = _frame(g["normal"], g.get("up"))
        w, h = g["size"]
        u = [c * w / 2 for c in u]
        v = [c * h / 2 for c in v]
        return {"type": "rectangle", "to_world": _matrix(u, v, n, g["center"])}
    if k == "disk":
        u, v, n = _frame(g["normal"])
        r = g["radius"]
        return {"type": "disk",
                "to_world": _matrix([c * r for c in u], [c * r for c in v], n, g["center"])}
    raise Unsupported("%s.%s: not converted (only rect, disk and sphere%s)"
                      % (where, k, ", dome and sun" if light else ""))


def _key(prefix, name):
    """A Mitsuba object key: '.' is its path delimiter."""
    return prefix + "".join(c if c.isalnum() else "_" for c in name)


def convert(path, spp=16, light_samples=1, bsdf_samples=1):
    """Mitsuba 3 scene dict for the illum scene at `path` (transform matrices as nested lists;
    `load` turns them into Mitsuba transforms)."""
    with open(path) as f:
        s = json.load(f)
    base = os.path.dirname(os.path.abspath(path))
    _check_fields(s, {"$schema", "description", "camera", "integrator", "textures",
                      "materials", "shapes", "lights"}, path)
    integ = s.get("integrator", {})
    kind = integ.get("type", "direct")
    if kind not in ("direct", "path", "full"):
        raise Unsupported("integrator.type: %r (direct, path and full convert)" % kind)
    cam = s["camera"]
    _check_fields(cam, {"position", "look_at", "up", "fov_y", "resolution"}, "camera")
    if "fov_y" not in cam:
        raise Unsupported("camera: only the look-at form converts")
    w, h = cam.get("resolution", [512, 512])
    d = {"type": "scene",
         "integrator": ({"type": "direct", "emitter_samples": light_samples,
                         "bsdf_samples": bsdf_samples} if kind == "direct" else
                        # illum's path and full both render all light paths: Mitsuba's path,
                        # max_depth counted alike (-1: unbounded).
                        {"type": "path", "max_depth": int(integ.get("max_depth", -1))}),
         "sensor": {"type": "perspective", "fov_axis": "y", "fov": cam["fov_y"],
                    "to_world": ("look_at", cam["position"], cam["look_at"],
                                 cam.get("up", [0, 1, 0])),
                    "sampler": {"type": "independent", "sample_count": spp},
                    "film": {"type": "hdrfilm", "width": w, "height": h,
                             "pixel_format": "rgb", "rfilter": {"type": "box"}}}}
    mats = s.get("materials", {})
    for name, sh in s.get("shapes", {}).items():
        where = "shapes.%s" % name
        _check_fields(sh, {"rect", "disk", "sphere", "mesh", "gltf", "material", "pole",
                           "transform"}, where)
        if "transform" in sh:
            raise Unsupported("%s.transform: not converted" % where)
        shape = _geometry(sh, where, False)
        m = mats[sh["material"]]
        shape["bsdf"] = _bsdf(sh["material"], m)
        em = m.get("emission", [0, 0, 0])
        if any(c > 0 for c in em):
            if m.get("two_sided"):
                raise Unsupported("materials.%s.two_sided: Mitsuba's area emitter is one-sided"
                                  % sh["material"])
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": em}}
        d[_key("shape_", name)] = shape
    textures = s.get("textures", {})
    for name, li in s.get("lights", {}).items():
        where = "lights.%s" % name
        _check_fields(li, {"rect", "disk", "sphere", "dome", "sun", "color", "intensity",
                           "exposure", "two_sided", "texture", "visible", "shadows"}, where)
        if li.get("visible", True) is False or li.get("shadows", True) is False:
            raise Unsupported("%s: visible/shadows false have no Mitsuba 3 counterpart" % where)
        if li.get("two_sided"):
            raise Unsupported("%s.two_sided: Mitsuba's area emitter is one-sided" % where)
        rad = _radiance(li, where)
        if "dome" in li:
            dome = li["dome"]
            _check_fields(dome, {"rotation", "convention"}, where + ".dome")
            rot = dome.get("rotation", 0.0)
            if "texture" not in li:
                d[_key("emitter_", name)] = {"type": "constant",
                                        "radiance": {"type": "rgb", "value": rad}}
                continue
            if dome.get("convention", "illum") != "mitsuba":
                raise Unsupported("%s.dome.convention: %r; only \"mitsuba\" maps identically "
                                  "(use --comparable)" % (where, dome.get("convention", "illum")))
            if not (rad[0] == rad[1] == rad[2]):
                raise Unsupported("%s.color: a coloured scale of a dome map does not convert"
                                  % where)
            t = textures[li["texture"]]
            _check_fields(t, {"file", "srgb", "filter", "wrap"}, "textures." + li["texture"])
            d[_key("emitter_", name)] = {"type": "envmap", "filename": os.path.join(base, t["file"]),
                                    "scale": rad[0], "to_world": ("rotate_y", rot)}
            continue
        if "sun" in li:
            sun = li["sun"]
            if sun.get("angular_diameter", 0.53) != 0:
                raise Unsupported("%s.sun.angular_diameter: Mitsuba 3 has only the delta "
                                  "`directional` emitter; set 0" % where)
            d[_key("emitter_", name)] = {"type": "directional", "direction":
                                    [-c for c in _norm(sun["direction"])],
                                    "irradiance": {"type": "rgb", "value": rad}}
            continue
        if "texture" in li:
            raise Unsupported("%s.texture: textured area lights are not converted" % where)
        shape = _geometry(li, where, True)
        shape["bsdf"] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0, 0, 0]}}
        shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": rad}}
        d[_key("light_", name)] = shape
    return d


def load(d):
    """Turns convert()'s transform placeholders into Mitsuba objects and loads the scene."""
    import mitsuba as mi

    def fix(x):
        if isinstance(x, dict):
            return {k: fix(v) for k, v in x.items()}
        if isinstance(x, tuple) and x[0] == "look_at":
            return mi.ScalarTransform4f().look_at(origin=x[1], target=x[2], up=x[3])
        if isinstance(x, tuple) and x[0] == "rotate_y":
            return mi.ScalarTransform4f().rotate([0, 1, 0], x[1])
        if isinstance(x, list) and x and isinstance(x[0], list):
            return mi.ScalarTransform4f(x)
        return x
    return mi.load_dict(fix(d))


def comparable(path, out):
    """Writes the nearest convertible illum scene (see the module doc) and says what changed."""
    with open(path) as f:
        s = json.load(f)
    changes = []
    for name, m in s.get("materials", {}).items():
        for i, lobe in enumerate(m.get("specular", [])):
            if lobe["model"] == "dbrdf":
                lobe["model"] = "beckmann"
                changes.append("materials.%s.specular[%d]: dbrdf -> beckmann" % (name, i))
            fr = lobe.get("fresnel", {"schlick": [0.04, 0.04, 0.04]})
            if "schlick" in fr:
                eta = [(1 + math.sqrt(f)) / (1 - math.sqrt(f)) for f in fr["schlick"]]
                lobe["fresnel"] = {"conductor": {"eta": eta, "k": [0, 0, 0]}}
                changes.append("materials.%s.specular[%d]: schlick %s -> dielectric eta %s"
                               % (name, i, fr["schlick"], [round(e, 4) for e in eta]))
    for name, li in s.get("lights", {}).items():
        if "dome" in li and "texture" in li and li["dome"].get("convention", "illum") != "mitsuba":
            li["dome"]["convention"] = "mitsuba"
            changes.append("lights.%s.dome.convention -> mitsuba" % name)
    src = os.path.dirname(os.path.abspath(path))
    dst = os.path.dirname(os.path.abspath(out))
    for t in s.get("textures", {}).values():
        t["file"] = os.path.relpath(os.path.join(src, t["file"]), dst)
    s["description"] = ("%s (nearest Mitsuba-3-convertible variant: scripts/to-mitsuba.py "
                        "--comparable)" % s.get("description", os.path.basename(path)))
    s.pop("$schema", None)
    with open(out, "w") as f:
        json.dump(s, f, indent=2)
        f.write("\n")
    return changes


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("-o", "--output")
    ap.add_argument("--comparable", metavar="OUT.json")
    a = ap.parse_args()
    try:
        if a.comparable:
            for c in comparable(a.scene, a.comparable):
                print(c)
            return
        d = convert(a.scene, spp=a.spp)
    except Unsupported as e:
        sys.exit("%s: %s" % (a.scene, e))
    except (KeyError, TypeError, ValueError) as e:
        sys.exit("%s: malformed scene (%s: %s)" % (a.scene, type(e).__name__, e))
    import mitsuba as mi
    mi.set_variant(a.variant)
    img = mi.render(load(d), spp=a.spp, seed=a.seed)
    mi.Bitmap(img).write(a.output or "mitsuba.exr")


if __name__ == "__main__":
    main()
