"""USD stages, authored here with Pixar's own library (usd-core's `pxr`), against the same scenes
written in illum's JSON: each stage renders as its JSON twin, light units follow the UsdLux
definition computed here, transforms compose as pxr composes them, and bad stages fail naming
the prim and attribute."""
import json
import math

import numpy as np
import OpenEXR
import pytest
from pxr import Gf, Sdf, Usd, UsdGeom, UsdLux, UsdRender, UsdShade

import illum

from conftest import cli

F32 = lambda x: float(np.float32(x))  # noqa: E731 (what a float attribute stores)


def new_stage(path, up="Y"):
    s = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(s, up)
    return s


def camera(s, translate, size=(48, 32), rotate=None, focal=35.0):
    cam = UsdGeom.Camera.Define(s, "/Cam")
    api = UsdGeom.XformCommonAPI(cam)
    api.SetTranslate(translate)
    if rotate:
        api.SetRotate(rotate)
    cam.CreateFocalLengthAttr(focal)
    rs = UsdRender.Settings.Define(s, "/Render/Settings")
    rs.CreateResolutionAttr(Gf.Vec2i(*size))
    rs.CreateCameraRel().SetTargets([cam.GetPath()])
    return cam


def fov_y(size, focal=35.0, h_ap=20.955, v_ap=15.2908):
    """UsdGeomCamera's vertical field of view under expandAperture (the default policy)."""
    h_ap, v_ap, focal = F32(h_ap), F32(v_ap), F32(focal)
    v = max(v_ap, h_ap / (size[0] / size[1]))
    return math.degrees(2 * math.atan(v / (2 * focal)))


def json_camera(position, look_at, size=(48, 32), up=(0, 1, 0), focal=35.0):
    return {"position": list(position), "look_at": list(look_at), "up": list(up),
            "fov_y": fov_y(size, focal), "resolution": list(size)}


def mesh(s, path, points, counts, indices):
    m = UsdGeom.Mesh.Define(s, path)
    m.CreatePointsAttr(points)
    m.CreateFaceVertexCountsAttr(counts)
    m.CreateFaceVertexIndicesAttr(indices)
    m.CreateSubdivisionSchemeAttr("none")
    return m


def preview(s, path, **inputs):
    mat = UsdShade.Material.Define(s, path)
    sh = UsdShade.Shader.Define(s, path + "/Surface")
    sh.CreateIdAttr("UsdPreviewSurface")
    for k, v in inputs.items():
        t = Sdf.ValueTypeNames.Color3f if isinstance(v, tuple) else Sdf.ValueTypeNames.Float
        sh.CreateInput(k, t).Set(v)
    mat.CreateSurfaceOutput().ConnectToSource(sh.ConnectableAPI(), "surface")
    return mat


def bind(prim, mat):
    UsdShade.MaterialBindingAPI.Apply(prim.GetPrim()).Bind(mat)


def ggx(base, roughness, metallic=0.0, ior=1.5):
    """illum's mapping of a metallic-roughness UsdPreviewSurface (docs/scene-format.md)."""
    base = [F32(c) for c in base]
    d = ((F32(ior) - 1) / (F32(ior) + 1)) ** 2
    m = F32(metallic)
    return {"diffuse": [c * (1 - m) for c in base],
            "specular": [{"model": "ggx", "roughness": F32(roughness) ** 2,
                          "fresnel": {"schlick": [d + (c - d) * m for c in base]}}]}


def render(scene, **kw):
    kw.setdefault("spp", 4)
    return scene.render(**kw).beauty


def twin(d, tmp_path):
    return illum.Scene.from_dict(d, base_dir=tmp_path)


FLOOR = [(-3, 0, -3), (-3, 0, 3), (3, 0, 3), (3, 0, -3)]


def test_a_stage_renders_bit_for_bit_as_its_json_twin(tmp_path):
    s = new_stage(tmp_path / "row.usda")
    camera(s, (0, 1, 6))
    mesh(s, "/World/Floor", FLOOR, [4], [0, 1, 2, 3])
    ball = UsdGeom.Sphere.Define(s, "/World/Ball")
    ball.CreateRadiusAttr(0.5)
    UsdGeom.XformCommonAPI(ball).SetTranslate((0, 0.5, 0))
    bind(ball, preview(s, "/Looks/Clay", diffuseColor=(0.7, 0.2, 0.1), roughness=0.4))
    bulb = UsdLux.SphereLight.Define(s, "/Lights/Bulb")
    bulb.CreateRadiusAttr(0.25)
    bulb.CreateIntensityAttr(30)
    bulb.CreateExposureAttr(1)
    bulb.CreateColorAttr((1, 0.9, 0.8))
    UsdGeom.XformCommonAPI(bulb).SetTranslate((1.5, 2, 1))
    UsdLux.DomeLight.Define(s, "/Lights/Sky").CreateIntensityAttr(0.2)
    s.Save()
    d = {
        "camera": json_camera((0, 1, 6), (0, 1, 5)),
        "materials": {"clay": ggx((0.7, 0.2, 0.1), 0.4), "grey": {"diffuse": [F32(0.18)] * 3}},
        "shapes": {
            "floor": {"mesh": {"positions": FLOOR, "indices": [0, 1, 2, 0, 2, 3]},
                      "material": "grey", "transform": {"translate": [0, 0, 0]}},
            "ball": {"sphere": {"center": [0, 0.5, 0], "radius": 0.5}, "material": "clay"},
        },
        "lights": {
            "bulb": {"sphere": {"center": [1.5, 2, 1], "radius": 0.25}, "intensity": 30,
                     "exposure": 1, "color": [1, F32(0.9), F32(0.8)]},
            "sky": {"dome": {"rotation": 180}, "intensity": F32(0.2)},
        },
    }
    usd = illum.load(tmp_path / "row.usda")
    assert usd.warnings == [] and usd.resolution == (48, 32)
    a, b = render(usd, integrator="full"), render(twin(d, tmp_path), integrator="full")
    assert a.mean() > 0.01
    assert np.array_equal(a, b)


def test_light_units_are_usdlux_s(tmp_path):
    """Each light's radiance as UsdLux defines it, computed here: color × intensity ×
    2^exposure × blackbody (pxr's), over the world area when normalized; a distant light's
    radiance L over its cone gives the irradiance L·π·sin²(angle/2) illum's sun takes."""
    s = new_stage(tmp_path / "lights.usda")
    camera(s, (0, 1, 6))
    mesh(s, "/World/Wall", [(-4, -1, -1), (4, -1, -1), (4, 4, -1), (-4, 4, -1)], [4], [0, 1, 2, 3])
    mesh(s, "/World/Floor", FLOOR, [4], [0, 1, 2, 3])
    rect = UsdLux.RectLight.Define(s, "/Lights/Panel")
    rect.CreateWidthAttr(2)
    rect.CreateHeightAttr(0.5)
    rect.CreateIntensityAttr(40)
    rect.CreateExposureAttr(-0.5)
    rect.CreateNormalizeAttr(True)
    api = UsdGeom.XformCommonAPI(rect)
    api.SetTranslate((-1, 2, 3))
    api.SetScale((1.5, 1.5, 1.5))
    disk = UsdLux.DiskLight.Define(s, "/Lights/Disk")
    disk.CreateRadiusAttr(0.3)
    disk.CreateIntensityAttr(25)
    disk.CreateEnableColorTemperatureAttr(True)
    disk.CreateColorTemperatureAttr(3200)
    UsdGeom.XformCommonAPI(disk).SetTranslate((1.5, 1.5, 2))
    sun = UsdLux.DistantLight.Define(s, "/Lights/Sun")
    sun.CreateAngleAttr(2.0)
    sun.CreateIntensityAttr(800)
    s.Save()
    bb = UsdLux.BlackbodyTemperatureAsRgb(3200)
    rect_l = 40 * 2 ** -0.5 / (2 * 1.5 * 0.5 * 1.5)
    sun_e = 800 * math.pi * math.sin(math.radians(2.0) / 2) ** 2
    grey = {"diffuse": [F32(0.18)] * 3}
    d = {
        "camera": json_camera((0, 1, 6), (0, 1, 5)),
        "materials": {"grey": grey},
        "shapes": {
            "wall": {"mesh": {"positions": [[-4, -1, -1], [4, -1, -1], [4, 4, -1], [-4, 4, -1]],
                              "indices": [0, 1, 2, 0, 2, 3]}, "material": "grey"},
            "floor": {"mesh": {"positions": FLOOR, "indices": [0, 1, 2, 0, 2, 3]},
                      "material": "grey"},
        },
        "lights": {
            "panel": {"rect": {"center": [-1, 2, 3], "normal": [0, 0, -1], "size": [3, 0.75],
                               "up": [0, 1, 0]}, "intensity": rect_l},
            "disk": {"disk": {"center": [1.5, 1.5, 2], "normal": [0, 0, -1], "radius": F32(0.3)},
                     "intensity": 25, "color": [float(c) for c in bb]},
            "sun": {"sun": {"direction": [0, 0, 1], "angular_diameter": 2.0}, "intensity": sun_e},
        },
    }
    a = render(illum.load(tmp_path / "lights.usda"), spp=8)
    b = render(twin(d, tmp_path), spp=8)
    assert a.mean() > 0.01
    # The blackbody colour is float32 in pxr, float64 here: the same to ~1e-7.
    np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-7)


def test_the_blackbody_colour_is_pxr_s(tmp_path):
    for kelvin in [1000, 2000, 3333, 4500, 6500, 8200, 10000, 12000]:
        s = new_stage(tmp_path / f"bb{kelvin}.usda")
        camera(s, (0, 0, 0), size=(4, 4))
        dome = UsdLux.DomeLight.Define(s, "/Sky")
        dome.CreateEnableColorTemperatureAttr(True)
        dome.CreateColorTemperatureAttr(kelvin)
        s.Save()
        # The camera sees the constant dome: every sample is its radiance.
        px = render(illum.load(tmp_path / f"bb{kelvin}.usda"), spp=1)
        want = np.array(UsdLux.BlackbodyTemperatureAsRgb(kelvin), dtype=np.float32)
        np.testing.assert_allclose(px.reshape(-1, 3), np.tile(want, (16, 1)), rtol=2e-6)


def test_transforms_compose_as_pxr_composes_them(tmp_path):
    s = new_stage(tmp_path / "xf.usda")
    camera(s, (0, 1.5, 7))
    top = UsdGeom.Xform.Define(s, "/World")
    top.AddTranslateOp().Set((0.3, 0.1, -0.2))
    top.AddRotateXYZOp().Set((5, 20, -10))
    top.AddScaleOp().Set((1.2, 1.2, 1.2))
    mid = UsdGeom.Xform.Define(s, "/World/Group")
    mid.AddOrientOp().Set(Gf.Quatf(0.9238795, 0, 0.3826834, 0))
    mid.AddTranslateOp(opSuffix="pivot").Set((0.5, 0, 0))
    mid.AddRotateZOp().Set(15)
    mid.AddTranslateOp(opSuffix="pivot", isInverseOp=True)
    ball = UsdGeom.Sphere.Define(s, "/World/Group/Ball")
    ball.CreateRadiusAttr(0.4)
    ball.AddTransformOp().Set(Gf.Matrix4d().SetTranslate(Gf.Vec3d(0.2, 0.6, 0.1)))
    box = UsdGeom.Cube.Define(s, "/World/Group/Box")
    box.AddTranslateOp().Set((-1, 0.5, 0))
    box.AddRotateYXZOp().Set((30, 10, 45))
    box.AddScaleOp().Set((0.5, 1.0, 0.3))
    free = UsdGeom.Sphere.Define(s, "/World/Group/Free")
    free.CreateRadiusAttr(0.3)
    UsdGeom.Xformable(free).SetResetXformStack(True)
    free.AddTranslateOp().Set((1.5, 0.3, 0.5))
    UsdLux.DomeLight.Define(s, "/Sky")
    s.Save()

    def world(prim):
        m = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
        return np.array(m, dtype=np.float64).T  # row vectors -> column vectors

    def sphere(prim, r):
        m = world(prim)
        return {"center": list(m[:3, 3]), "radius": r * float(np.linalg.norm(m[:3, 0]))}

    d = {
        "camera": json_camera((0, 1.5, 7), (0, 1.5, 6)),
        "materials": {"grey": {"diffuse": [F32(0.18)] * 3}},
        "shapes": {
            "ball": {"sphere": sphere(ball.GetPrim(), 0.4), "material": "grey"},
            "box": {"mesh": cube_mesh(2.0), "material": "grey",
                    "transform": {"matrix": list(world(box.GetPrim()).reshape(-1))}},
            "free": {"sphere": sphere(free.GetPrim(), 0.3), "material": "grey"},
        },
        "lights": {"sky": {"dome": {"rotation": 180}}},
    }
    a = render(illum.load(tmp_path / "xf.usda"), spp=4)
    b = render(twin(d, tmp_path), spp=4)
    assert a.mean() > 0.01
    np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-6)


def cube_mesh(size):
    """A cube of edge `size` about the origin, one quad (2 triangles) per face, outward."""
    h = size / 2
    positions, normals, indices = [], [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = np.eye(3)[axis] * sign
            u = np.eye(3)[(axis + 1) % 3] * sign
            v = np.cross(n, u)
            base = len(positions)
            for a, b in [(-1, -1), (1, -1), (1, 1), (-1, 1)]:
                positions.append(list((n + u * a + v * b) * h))
                normals.append(list(n))
            indices += [base + i for i in (0, 1, 2, 0, 2, 3)]
    return {"positions": positions, "normals": normals, "indices": indices}


def test_z_up_stages_render_as_authored(tmp_path):
    def build(up):
        # Z-up coordinates of a Y-up point (x, y, z) are (x, -z, y).
        p = (lambda x, y, z: (x, y, z)) if up == "Y" else (lambda x, y, z: (x, -z, y))
        s = new_stage(tmp_path / f"up{up}.usda", up)
        camera(s, p(0, 1, 6), rotate=(0, 0, 0) if up == "Y" else (90, 0, 0))
        mesh(s, "/World/Floor", [p(*q) for q in FLOOR], [4], [0, 1, 2, 3])
        ball = UsdGeom.Sphere.Define(s, "/World/Ball")
        ball.CreateRadiusAttr(0.6)
        UsdGeom.XformCommonAPI(ball).SetTranslate(p(0.4, 0.6, 0))
        key = UsdLux.SphereLight.Define(s, "/Lights/Key")
        key.CreateIntensityAttr(40)
        key.CreateRadiusAttr(0.3)
        UsdGeom.XformCommonAPI(key).SetTranslate(p(-1.5, 2.5, 1.5))
        sun = UsdLux.DistantLight.Define(s, "/Lights/Sun")
        sun.CreateIntensityAttr(2000)
        # The sun turned in Y-up coordinates, then carried into Z-up ones (row vectors).
        turn = Gf.Matrix4d().SetRotate(Gf.Rotation(Gf.Vec3d(1, 0, 0), -60)) * \
            Gf.Matrix4d().SetRotate(Gf.Rotation(Gf.Vec3d(0, 1, 0), 30))
        to_z = Gf.Matrix4d().SetRotate(Gf.Rotation(Gf.Vec3d(1, 0, 0), 90))
        sun.AddTransformOp().Set(turn if up == "Y" else turn * to_z)
        s.Save()
        return illum.load(tmp_path / f"up{up}.usda")

    y, z = build("Y"), build("Z")
    assert z.warnings == []
    a, b = render(y, spp=8), render(z, spp=8)
    assert a.mean() > 0.01
    np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-6)


def test_the_dome_is_oriented_as_openexr_lays_out_lat_long_maps(tmp_path):
    """OpenEXR's lat-long map (UsdLux's): its left half (longitude π to 0) covers +X, its right
    half -X. A camera looking along +X sees the left half's colour, and a dome turned 90° about
    +Y carries it to -Z."""
    w, h = 64, 32
    px = np.zeros((h, w, 3), dtype=np.float32)
    px[:, : w // 2] = (1, 0, 0)
    px[:, w // 2:] = (0, 1, 0)
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                      {"RGB": px}) as f:
        f.write(str(tmp_path / "halves.exr"))

    def look(rotate_cam, rotate_dome):
        s = new_stage(tmp_path / "dome.usda")
        camera(s, (0, 0, 0), size=(4, 4), rotate=rotate_cam, focal=100)
        dome = UsdLux.DomeLight.Define(s, "/Sky")
        dome.CreateTextureFileAttr("halves.exr")
        if rotate_dome:
            UsdGeom.XformCommonAPI(dome).SetRotate((0, rotate_dome, 0))
        s.Save()
        return render(illum.load(tmp_path / "dome.usda"), spp=1).mean(axis=(0, 1))

    plus_x, minus_x = (0, -90, 0), (0, 90, 0)
    assert look(plus_x, 0)[0] > 0.99 and look(plus_x, 0)[1] < 0.01
    assert look(minus_x, 0)[1] > 0.99 and look(minus_x, 0)[0] < 0.01
    # Turned 90° about +Y, +X goes to -Z: the camera's default view (-Z) sees red.
    assert look((0, 0, 0), 90)[0] > 0.99
    assert look((0, 180, 0), 90)[1] > 0.99


def test_references_variants_and_instances_compose(tmp_path):
    asset = new_stage(tmp_path / "ball.usda")
    root = UsdGeom.Xform.Define(asset, "/Ball")
    asset.SetDefaultPrim(root.GetPrim())
    ball = UsdGeom.Sphere.Define(asset, "/Ball/Geom")
    ball.CreateRadiusAttr(0.5)
    vset = root.GetPrim().GetVariantSets().AddVariantSet("paint")
    for name, rgb in [("red", (0.8, 0.1, 0.1)), ("blue", (0.1, 0.2, 0.8))]:
        vset.AddVariant(name)
        vset.SetVariantSelection(name)
        with vset.GetVariantEditContext():
            ball.CreateDisplayColorAttr([rgb])
    vset.SetVariantSelection("red")
    asset.Save()

    s = new_stage(tmp_path / "shot.usda")
    camera(s, (0, 0.5, 6))
    placed = []
    for i, (x, paint, instanced) in enumerate([(-1.2, None, False), (0, "blue", False),
                                               (1.2, "blue", True)]):
        p = UsdGeom.Xform.Define(s, f"/World/Ball{i}")
        p.GetPrim().GetReferences().AddReference("ball.usda")
        if paint:
            p.GetPrim().GetVariantSets().GetVariantSet("paint").SetVariantSelection(paint)
        p.GetPrim().SetInstanceable(instanced)
        UsdGeom.XformCommonAPI(p).SetTranslate((x, 0.5, 0))
        placed.append((x, paint or "red"))
    UsdLux.DomeLight.Define(s, "/Sky")
    s.Save()
    rgb = {"red": [F32(c) for c in (0.8, 0.1, 0.1)], "blue": [F32(c) for c in (0.1, 0.2, 0.8)]}
    d = {
        "camera": json_camera((0, 0.5, 6), (0, 0.5, 5)),
        "materials": {k: {"diffuse": v} for k, v in rgb.items()},
        "shapes": {f"b{i}": {"sphere": {"center": [x, 0.5, 0], "radius": 0.5}, "material": paint}
                   for i, (x, paint) in enumerate(placed)},
        "lights": {"sky": {"dome": {"rotation": 180}}},
    }
    a = render(illum.load(tmp_path / "shot.usda"))
    b = render(twin(d, tmp_path))
    assert np.array_equal(a, b)


def bad_stage(tmp_path, build):
    path = tmp_path / f"{build.__name__}.usda"
    s = new_stage(path)
    camera(s, (0, 1, 6))
    UsdLux.DomeLight.Define(s, "/Sky")
    build(s)
    s.Save()
    with pytest.raises(illum.IllumError) as e:
        illum.load(path)
    p = cli("render", path, "-o", tmp_path / "x.exr", "--quiet")
    assert p.returncode != 0
    assert p.stderr.strip().splitlines()[-1] == f"illum: error: {e.value}"
    return str(e.value)


def test_bad_stages_get_errors_naming_the_prim(tmp_path):
    def bad_indices(s):
        mesh(s, "/World/Bad", FLOOR, [4], [0, 1, 2, 7])
    e = bad_stage(tmp_path, bad_indices)
    assert "/World/Bad.faceVertexIndices" in e and "got 7" in e, e

    def bad_counts(s):
        mesh(s, "/World/Bad", FLOOR, [4, 3], [0, 1, 2, 3])
    e = bad_stage(tmp_path, bad_counts)
    assert "/World/Bad.faceVertexIndices" in e and "adds up to 7" in e, e

    def non_finite(s):
        b = UsdGeom.Sphere.Define(s, "/World/Ball")
        b.AddTranslateOp().Set((0, float("inf"), 0))
    e = bad_stage(tmp_path, non_finite)
    assert "/World/Ball.xformOp:translate" in e and "finite" in e, e

    def missing_reference(s):
        s.DefinePrim("/World/Prop").GetReferences().AddReference("nowhere.usda")
    e = bad_stage(tmp_path, missing_reference)
    assert "nowhere.usda" in e and "/World/Prop" in e, e

    (tmp_path / "loop.usda").write_text('#usda 1.0\n(defaultPrim = "A")\n'
                                        'def "A" (references = @./cycle.usda@</World/Loop>) {}\n')

    def cycle(s):
        s.DefinePrim("/World/Loop").GetReferences().AddReference("loop.usda")
    e = bad_stage(tmp_path, cycle)
    assert "cycle" in e, e

    def opacity(s):
        b = UsdGeom.Sphere.Define(s, "/World/Glass")
        bind(b, preview(s, "/Looks/Glass", opacity=0.5))
    e = bad_stage(tmp_path, opacity)
    assert "/Looks/Glass/Surface.inputs:opacity" in e, e


def test_what_is_not_rendered_is_listed_and_strict_refuses_it(tmp_path):
    s = new_stage(tmp_path / "warn.usda")
    camera(s, (0, 1, 6))
    UsdGeom.BasisCurves.Define(s, "/World/Hair")
    key = UsdLux.SphereLight.Define(s, "/Lights/Spot")
    UsdLux.ShapingAPI.Apply(key.GetPrim()).CreateShapingConeAngleAttr(30)
    s.Save()
    path = tmp_path / "warn.usda"
    w = illum.load(path).warnings
    assert any(x.startswith("/World/Hair: BasisCurves is not rendered") for x in w), w
    assert any(x.startswith("/Lights/Spot.inputs:shaping:cone:angle:") for x in w), w
    p = cli("render", path, "-o", tmp_path / "x.exr", "--spp", 1, "--quiet")
    assert p.returncode == 0 and "/World/Hair: BasisCurves is not rendered" in p.stderr, p.stderr
    p = cli("render", path, "-o", tmp_path / "y.exr", "--spp", 1, "--strict")
    assert p.returncode != 0 and "--strict: 2 warning(s)" in p.stderr, p.stderr
    assert not (tmp_path / "y.exr").exists()


@pytest.mark.parametrize("kind, depth", [("Cylinder", 5.0), ("Cone", 5.5), ("Capsule", 5.5),
                                         ("Cylinder_1", 5.25)])
def test_cylinders_cones_and_capsules_render_where_they_are(kind, depth, tmp_path):
    """Each quadric about Y at the origin, seen from (0, 0, 6): the centre pixel's depth is the
    distance to its surface there (radius 1: 5; the cone's, apex up at y = 1: 5.5; the capsule's,
    radius 0.5: 5.5; a frustum of radii 1 and 0.5: 5.25), within the depth's spread over the
    pixel (a few thousandths) and the tessellation (7.5e-5)."""
    s = new_stage(tmp_path / "q.usda")
    camera(s, (0, 0, 6), size=(33, 33))
    p = s.DefinePrim("/World/Q", kind)
    p.CreateAttribute("axis", Sdf.ValueTypeNames.Token).Set("Y")
    if kind == "Cylinder_1":
        p.CreateAttribute("radiusBottom", Sdf.ValueTypeNames.Double).Set(1.0)
        p.CreateAttribute("radiusTop", Sdf.ValueTypeNames.Double).Set(0.5)
    UsdLux.DomeLight.Define(s, "/Lights/Sky")
    s.Save()
    scene = illum.load(tmp_path / "q.usda")
    assert scene.warnings == [], scene.warnings
    z = scene.render(spp=16).depth
    assert abs(z[16, 16] - depth) < 0.01, (kind, z[16, 16])
    assert np.isfinite(z[16]).sum() > 2


def test_usdc_and_usdz_read_as_usda(tmp_path):
    s = new_stage(tmp_path / "row.usda")
    camera(s, (0, 1, 6))
    mesh(s, "/World/Floor", FLOOR, [4], [0, 1, 2, 3])
    UsdLux.DomeLight.Define(s, "/Sky")
    s.Save()
    s.Export(str(tmp_path / "row.usdc"))
    from pxr import UsdUtils
    assert UsdUtils.CreateNewUsdzPackage(str(tmp_path / "row.usdc"), str(tmp_path / "row.usdz"))
    a = render(illum.load(tmp_path / "row.usda"))
    for ext in ["usdc", "usdz"]:
        assert np.array_equal(render(illum.load(tmp_path / f"row.{ext}")), a), ext


def test_the_lookdev_stage_loads_without_warnings():
    root = __import__("pathlib").Path(__file__).resolve().parents[2]
    s = illum.load(root / "scenes" / "lookdev.usda")
    assert s.warnings == [] and s.resolution == (768, 384)
    stage = Usd.Stage.Open(str(root / "scenes" / "lookdev.usda"))
    cam = UsdGeom.Camera(stage.GetPrimAtPath("/World/Camera")).GetCamera()
    # pxr's field of view of the camera equals the JSON row's (scenes/default.json: 27°).
    assert cam.GetFieldOfView(Gf.Camera.FOVVertical) == pytest.approx(27, abs=1e-4)
    r = s.render(spp=2, width=64)
    assert r.beauty.mean() > 0.05


def write_exr(path, px):
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                      {"RGB": np.asarray(px, dtype=np.float32)}) as f:
        f.write(str(path))


QUAD = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
QUAD_ST = [(0, 0), (1, 0), (1, 1), (0, 1)]
QUAD_UV = [[u, 1 - v] for u, v in QUAD_ST]  # illum's uvs of QUAD_ST (origin top left)


def textured_card(s, primvar="st"):
    """/World/Card: the 2 × 2 quad facing +Z with face-varying texture coordinates QUAD_ST in
    `primvar`, bound to /Looks/Card (a UsdPreviewSurface) with a UsdPrimvarReader_float2 of that
    primvar: (the surface shader, the reader)."""
    m = mesh(s, "/World/Card", QUAD, [4], [0, 1, 2, 3])
    UsdGeom.PrimvarsAPI(m).CreatePrimvar(primvar, Sdf.ValueTypeNames.TexCoord2fArray,
                                         UsdGeom.Tokens.faceVarying).Set(QUAD_ST)
    mat = UsdShade.Material.Define(s, "/Looks/Card")
    ps = UsdShade.Shader.Define(s, "/Looks/Card/Surface")
    ps.CreateIdAttr("UsdPreviewSurface")
    reader = UsdShade.Shader.Define(s, "/Looks/Card/St")
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    reader.CreateInput("varname", Sdf.ValueTypeNames.Token).Set(primvar)
    mat.CreateSurfaceOutput().ConnectToSource(ps.ConnectableAPI(), "surface")
    bind(m, mat)
    return ps, reader


def uv_texture(s, name, file, st, surface=None, input=None, output="rgb"):
    """/Looks/Card/<name>: a UsdUVTexture of `file` reading its coordinates from the node `st`
    (its `result`), connected through `output` to `surface`'s `input` when given."""
    tex = UsdShade.Shader.Define(s, f"/Looks/Card/{name}")
    tex.CreateIdAttr("UsdUVTexture")
    tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(file)
    tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(st.ConnectableAPI(), "result")
    if surface is not None:
        kind = Sdf.ValueTypeNames.Color3f if output == "rgb" else Sdf.ValueTypeNames.Float
        surface.CreateInput(input, kind).ConnectToSource(tex.ConnectableAPI(), output)
    return tex


def card_twin(material, uvs, textures, lights=None):
    """The JSON twin of a textured_card stage seen from (0, 0, 4) at 32 × 32 under a white dome:
    the quad with illum's uvs `uvs` (one per QUAD corner)."""
    return {
        "camera": json_camera((0, 0, 4), (0, 0, 3), size=(32, 32)),
        "textures": textures,
        "materials": {"card": material},
        "shapes": {"card": {"mesh": {"positions": [list(p) for p in QUAD],
                                     "indices": [0, 1, 2, 0, 2, 3], "uvs": uvs},
                            "material": "card"}},
        "lights": {"sky": {"dome": {"rotation": 180}}, **(lights or {})},
    }


@pytest.mark.parametrize("uv", ["st", "UVMap"])
def test_a_textured_preview_surface_maps_st_as_usd_does(tmp_path, uv):
    """USD's st has (0, 0) at the image's bottom left: a quad whose st spans [0, 1]² shows the
    image upright. Its JSON twin has illum's top-left uvs. The primvar is the one the
    material's primvar reader names."""
    px = np.zeros((8, 8, 3), dtype=np.float32)
    px[:4] = (0.9, 0.05, 0.05)  # top half red
    px[4:] = (0.05, 0.9, 0.05)  # bottom half green
    write_exr(tmp_path / "halves.exr", px)
    s = new_stage(tmp_path / "tex.usda")
    camera(s, (0, 0, 4), size=(32, 32))
    ps, reader = textured_card(s, uv)
    tex = uv_texture(s, "Image", "halves.exr", reader, ps, "diffuseColor")
    tex.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set("clamp")
    tex.CreateInput("wrapT", Sdf.ValueTypeNames.Token).Set("clamp")
    UsdLux.DomeLight.Define(s, "/Sky")
    s.Save()
    d = card_twin({**ggx((1, 1, 1), 0.5), "diffuse_texture": "halves"},
                  QUAD_UV,
                  {"halves": {"file": "halves.exr", "wrap": "clamp"}})
    a = render(illum.load(tmp_path / "tex.usda"))
    b = render(twin(d, tmp_path))
    assert np.array_equal(a, b)
    top, bottom = a[12, 16], a[20, 16]
    assert top[0] > 3 * top[1] and bottom[1] > 3 * bottom[0], (top, bottom)
    # Packaged as USDZ in a folder of its own: the image is read from inside the package.
    from pxr import UsdUtils
    (tmp_path / "pkg").mkdir()
    assert UsdUtils.CreateNewUsdzPackage(str(tmp_path / "tex.usda"), str(tmp_path / "pkg" / "tex.usdz"))
    assert not (tmp_path / "pkg" / "halves.exr").exists()
    assert np.array_equal(render(illum.load(tmp_path / "pkg" / "tex.usdz")), a)


def test_textured_metallic_and_roughness_read_as_the_metallic_roughness_model(tmp_path):
    """roughness and metallic connected to channels of two UsdUVTextures (G of one, R of the
    other, with a scale) over a textured diffuseColor: the JSON twin's metallic_roughness
    material with the same maps and channels, bit for bit; another channel gives another
    image."""
    write_exr(tmp_path / "albedo.exr", [[(0.9, 0.2, 0.1), (0.2, 0.8, 0.3)],
                                        [(0.3, 0.3, 0.9), (0.8, 0.8, 0.8)]])
    write_exr(tmp_path / "masks.exr", [[(0, 0.9, 1), (0, 0.2, 1)], [(0, 0.5, 0), (0, 0.05, 0)]])
    write_exr(tmp_path / "metal.exr", [[(0, 1, 1), (1, 0, 0)], [(1, 1, 0), (0, 0, 1)]])
    s = new_stage(tmp_path / "mr.usda")
    camera(s, (0, 0, 4), size=(32, 32))
    ps, reader = textured_card(s)
    uv_texture(s, "Albedo", "albedo.exr", reader, ps, "diffuseColor")
    metal = uv_texture(s, "Metal", "metal.exr", reader, ps, "metallic", "r")
    metal.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set((0.8,) * 4)
    uv_texture(s, "Masks", "masks.exr", reader, ps, "roughness", "g")
    UsdLux.DomeLight.Define(s, "/Sky")
    key = UsdLux.SphereLight.Define(s, "/Key")
    key.CreateRadiusAttr(0.2)
    key.CreateIntensityAttr(30)
    UsdGeom.XformCommonAPI(key).SetTranslate((1, 1, 2))
    s.Save()

    def twin_with(metal_channel):
        return twin(card_twin(
            {"diffuse": [1, 1, 1], "diffuse_texture": "albedo",
             "metallic_roughness": {
                 "metallic": F32(0.8),
                 "metallic_texture": {"texture": "metal", "channel": metal_channel},
                 "roughness": 1,
                 "roughness_texture": {"texture": "masks", "channel": "g"}}},
            QUAD_UV,
            {"albedo": {"file": "albedo.exr"}, "metal": {"file": "metal.exr"},
             "masks": {"file": "masks.exr"}},
            {"key": {"sphere": {"center": [1, 1, 2], "radius": F32(0.2)}, "intensity": 30}}),
            tmp_path)

    stage = illum.load(tmp_path / "mr.usda")
    assert stage.warnings == []
    a = render(stage, spp=8)
    assert np.array_equal(a, render(twin_with("r"), spp=8))
    assert not np.array_equal(a, render(twin_with("b"), spp=8))


@pytest.mark.parametrize("mirrored", [False, True])
def test_a_rect_light_s_texture_lies_as_usdlux_lays_it(tmp_path, mirrored):
    """UsdLux puts a RectLight texture's first texel at local (+X, +Y) and its last at (-X, -Y)
    (the schema's own words): seen from the side it lights, the image reads upright; a
    transform that mirrors the light mirrors the image."""
    quadrants = {(0, 0): (1, 0, 0), (0, 1): (0, 1, 0), (1, 0): (0, 0, 1), (1, 1): (1, 1, 1)}
    px = np.zeros((64, 64, 3), dtype=np.float32)
    for (r, c), colour in quadrants.items():
        px[32 * r:32 * r + 32, 32 * c:32 * c + 32] = colour
    write_exr(tmp_path / "quads.exr", px)
    s = new_stage(tmp_path / "rect.usda")
    # The light emits along -Z: the camera at -Z looks back along +Z.
    camera(s, (0, 0, -12), size=(16, 16), rotate=(0, 180, 0), focal=50)
    light = UsdLux.RectLight.Define(s, "/Panel")
    light.CreateTextureFileAttr("quads.exr")
    light.CreateWidthAttr(4)
    light.CreateHeightAttr(4)
    if mirrored:
        UsdGeom.XformCommonAPI(light).SetScale((-1, 1, 1))
    s.Save()
    stage = illum.load(tmp_path / "rect.usda")
    assert stage.warnings == []
    img = render(stage, spp=1)
    for (r, c), colour in quadrants.items():
        cc = 1 - c if mirrored else c
        seen = img[8 * r + 3:8 * r + 6, 8 * cc + 3:8 * cc + 6].mean(axis=(0, 1))
        assert np.allclose(seen, colour, atol=1e-6), ((r, c), seen, colour)


def test_a_transform2d_moves_texture_coordinates_as_the_preview_surface_spec_says(tmp_path):
    """UsdTransform2d between the primvar reader and the texture: st' = R(rotation) (scale st)
    + translation (UsdPreviewSurface's order), computed here, then flipped to illum's uvs: the
    stage renders as the JSON twin whose uvs hold st' (to float rounding of the rotation)."""
    write_exr(tmp_path / "albedo.exr", [[(0.9, 0.2, 0.1), (0.2, 0.8, 0.3), (0.1, 0.1, 0.9)],
                                        [(0.3, 0.3, 0.9), (0.8, 0.8, 0.8), (0.9, 0.9, 0.1)]])
    rotation, scale, translation = 30.0, (2.0, 1.5), (0.25, -0.5)
    s = new_stage(tmp_path / "xf2d.usda")
    camera(s, (0, 0, 4), size=(32, 32))
    ps, reader = textured_card(s)
    xf = UsdShade.Shader.Define(s, "/Looks/Card/Place")
    xf.CreateIdAttr("UsdTransform2d")
    xf.CreateInput("in", Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(),
                                                                    "result")
    xf.CreateInput("rotation", Sdf.ValueTypeNames.Float).Set(rotation)
    xf.CreateInput("scale", Sdf.ValueTypeNames.Float2).Set(scale)
    xf.CreateInput("translation", Sdf.ValueTypeNames.Float2).Set(translation)
    uv_texture(s, "Image", "albedo.exr", xf, ps, "diffuseColor")
    UsdLux.DomeLight.Define(s, "/Sky")
    s.Save()

    def placed(p):
        a = math.radians(rotation)
        x, y = p[0] * scale[0], p[1] * scale[1]
        u = math.cos(a) * x - math.sin(a) * y + translation[0]
        v = math.sin(a) * x + math.cos(a) * y + translation[1]
        return [u, 1 - v]

    material = {**ggx((1, 1, 1), 0.5), "diffuse_texture": "albedo"}
    textures = {"albedo": {"file": "albedo.exr"}}
    stage = illum.load(tmp_path / "xf2d.usda")
    assert stage.warnings == []
    a = render(stage)
    b = render(twin(card_twin(material, [placed(p) for p in QUAD_ST], textures), tmp_path))
    assert np.abs(a - b).max() <= 1e-5 * np.abs(b).max(), np.abs(a - b).max()
    plain = render(twin(card_twin(material, QUAD_UV, textures), tmp_path))
    assert np.abs(a - plain).max() > 0.05


BOX_POINTS = [(-0.5, 0, -0.5), (0.5, 0, -0.5), (0.5, 0, 0.5), (-0.5, 0, 0.5),
              (-0.5, 1, -0.5), (0.5, 1, -0.5), (0.5, 1, 0.5), (-0.5, 1, 0.5)]
BOX_FACES = [0, 1, 2, 3, 4, 7, 6, 5, 0, 4, 5, 1, 1, 5, 6, 2, 2, 6, 7, 3, 3, 7, 4, 0]


def test_instances_share_their_prototype_s_mesh(tmp_path):
    asset = new_stage(tmp_path / "box.usda")
    root = UsdGeom.Xform.Define(asset, "/Box")
    asset.SetDefaultPrim(root.GetPrim())
    mesh(asset, "/Box/Geom", BOX_POINTS, [4] * 6, BOX_FACES)
    asset.Save()
    s = new_stage(tmp_path / "boxes.usda")
    camera(s, (0, 1, 6))
    xs = [-1.5, 0.0, 1.5]
    for i, x in enumerate(xs):
        p = UsdGeom.Xform.Define(s, f"/World/Box{i}")
        p.GetPrim().GetReferences().AddReference("box.usda")
        p.GetPrim().SetInstanceable(True)
        UsdGeom.XformCommonAPI(p).SetTranslate((x, 0, 0))
    UsdLux.DomeLight.Define(s, "/Sky")
    s.Save()
    # The quads as fans (v0, v1, v2), (v0, v2, v3).
    tris = [q[k] for q in (BOX_FACES[i:i + 4] for i in range(0, 24, 4))
            for k in (0, 1, 2, 0, 2, 3)]
    shapes = {"b0": {"mesh": {"positions": [list(p) for p in BOX_POINTS], "indices": tris},
                     "material": "grey", "transform": {"translate": [xs[0], 0, 0]}}}
    for i, x in enumerate(xs[1:], 1):
        shapes[f"b{i}"] = {"instance": "b0", "transform": {"translate": [x, 0, 0]}}
    d = {
        "camera": json_camera((0, 1, 6), (0, 1, 5)),
        "materials": {"grey": {"diffuse": [F32(0.18)] * 3}},
        "shapes": shapes,
        "lights": {"sky": {"dome": {"rotation": 180}}},
    }
    a = render(illum.load(tmp_path / "boxes.usda"))
    assert a.mean() > 0.01
    assert np.array_equal(a, render(twin(d, tmp_path)))
    # One mesh of 12 triangles, placed three times: the trace structure says so.
    p = cli("render", tmp_path / "boxes.usda", "-o", tmp_path / "b.exr", "--spp", 1)
    assert p.returncode == 0 and "(12 triangles;" in p.stderr, p.stderr


def test_surfaces_behind_node_graphs_and_interface_inputs(tmp_path):
    """A Material whose surface comes out of a NodeGraph, with the diffuse colour fed from the
    material's interface input, reads as the same UsdPreviewSurface authored directly."""
    def build(name, wrapped):
        s = new_stage(tmp_path / f"{name}.usda")
        camera(s, (0, 0.5, 4))
        ball = UsdGeom.Sphere.Define(s, "/World/Ball")
        ball.CreateRadiusAttr(0.5)
        UsdGeom.XformCommonAPI(ball).SetTranslate((0, 0.5, 0))
        mat = UsdShade.Material.Define(s, "/Looks/Paint")
        if wrapped:
            graph = UsdShade.NodeGraph.Define(s, "/Looks/Paint/Graph")
            ps = UsdShade.Shader.Define(s, "/Looks/Paint/Graph/Surface")
            ps.CreateIdAttr("UsdPreviewSurface")
            color = mat.CreateInput("paint", Sdf.ValueTypeNames.Color3f)
            color.Set((0.2, 0.5, 0.8))
            ps.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(color)
            ps.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(0.3)
            out = graph.CreateOutput("surface", Sdf.ValueTypeNames.Token)
            out.ConnectToSource(ps.ConnectableAPI(), "surface")
            mat.CreateSurfaceOutput().ConnectToSource(out)
        else:
            ps = UsdShade.Shader.Define(s, "/Looks/Paint/Surface")
            ps.CreateIdAttr("UsdPreviewSurface")
            ps.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set((0.2, 0.5, 0.8))
            ps.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(0.3)
            mat.CreateSurfaceOutput().ConnectToSource(ps.ConnectableAPI(), "surface")
        bind(ball, mat)
        UsdLux.DomeLight.Define(s, "/Sky")
        s.Save()
        return illum.load(tmp_path / f"{name}.usda")

    wrapped, direct = build("wrapped", True), build("direct", False)
    assert wrapped.warnings == []
    assert np.array_equal(render(wrapped), render(direct))


def test_point_instancers_place_their_prototypes_as_pxr_does(tmp_path):
    s = new_stage(tmp_path / "pi.usda")
    camera(s, (0, 1.5, 8))
    inst = UsdGeom.PointInstancer.Define(s, "/World/Scatter")
    inst.AddTranslateOp().Set((0.2, 0, -0.5))
    box_root = UsdGeom.Xform.Define(s, "/World/Scatter/Protos/Box")
    box_root.AddTranslateOp().Set((0, 0.1, 0))
    mesh(s, "/World/Scatter/Protos/Box/Geom", BOX_POINTS, [4] * 6, BOX_FACES)
    ball = UsdGeom.Sphere.Define(s, "/World/Scatter/Protos/Ball")
    ball.CreateRadiusAttr(0.3)
    inst.CreatePrototypesRel().SetTargets([box_root.GetPath(), ball.GetPath()])
    inst.CreateProtoIndicesAttr([0, 1, 0, 1, 0])
    inst.CreatePositionsAttr([(-2, 0, 0), (-1, 0.3, 0), (0, 0, 0), (1, 0.3, 0), (2, 0, 0)])
    # Unit quaternions exact in half precision (pxr does not renormalize them; illum does).
    inst.CreateOrientationsAttr([Gf.Quath(1, 0, 0, 0), Gf.Quath(1, 0, 0, 0),
                                 Gf.Quath(0.5, 0.5, 0.5, 0.5), Gf.Quath(1, 0, 0, 0),
                                 Gf.Quath(0, 0, 1, 0)])
    inst.CreateScalesAttr([(1, 1, 1), (1.5, 1.5, 1.5), (0.8, 1.2, 0.8), (1, 1, 1), (1, 1, 1)])
    inst.CreateIdsAttr([10, 11, 12, 13, 14])
    inst.CreateInvisibleIdsAttr([13])
    UsdLux.DomeLight.Define(s, "/Sky")
    s.Save()
    # pxr's instance transforms (each with its prototype's own; visible instances only),
    # under the instancer's.
    xforms = iter(inst.ComputeInstanceTransformsAtTime(Usd.TimeCode.Default(),
                                                       Usd.TimeCode.Default()))
    top = UsdGeom.Xformable(inst).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
    tris = [q[k] for q in (BOX_FACES[i:i + 4] for i in range(0, 24, 4))
            for k in (0, 1, 2, 0, 2, 3)]
    shapes, first = {}, None
    for i, proto in enumerate([0, 1, 0, 1, 0]):
        if i == 3:
            continue  # invisible
        m = np.array(next(xforms) * top, dtype=np.float64).T
        if proto == 0:
            t = {"matrix": list(m.reshape(-1))}
            if first is None:
                first = f"i{i}"
                shapes[first] = {"mesh": {"positions": [list(p) for p in BOX_POINTS],
                                          "indices": tris}, "material": "grey", "transform": t}
            else:
                shapes[f"i{i}"] = {"instance": first, "transform": t}
        else:
            shapes[f"i{i}"] = {"sphere": {"center": list(m[:3, 3]),
                                          "radius": 0.3 * float(np.linalg.norm(m[:3, 0]))},
                               "material": "grey"}
    d = {
        "camera": json_camera((0, 1.5, 8), (0, 1.5, 7)),
        "materials": {"grey": {"diffuse": [F32(0.18)] * 3}},
        "shapes": shapes,
        "lights": {"sky": {"dome": {"rotation": 180}}},
    }
    usd = illum.load(tmp_path / "pi.usda")
    assert usd.warnings == []
    a, b = render(usd), render(twin(d, tmp_path))
    assert a.mean() > 0.01
    np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-6)
    p = cli("render", tmp_path / "pi.usda", "-o", tmp_path / "pi.exr", "--spp", 1)
    assert p.returncode == 0 and "(12 triangles;" in p.stderr, p.stderr
    # inactiveIds (prim metadata, a list op) leaves an instance out as invisibleIds does. The
    # USD library illum reads with parses list-op metadata it does not know from .usdc only.
    now = Usd.TimeCode.Default()
    inst.DeactivateId(12)
    assert len(inst.ComputeInstanceTransformsAtTime(now, now)) == 3
    s.Export(str(tmp_path / "inactive.usdc"))
    inactive = render(illum.load(tmp_path / "inactive.usdc"))
    assert not np.array_equal(inactive, a)
    inst.ActivateId(12)
    inst.GetInvisibleIdsAttr().Set([13, 12])
    s.Export(str(tmp_path / "invisible.usdc"))
    assert np.array_equal(inactive, render(illum.load(tmp_path / "invisible.usdc")))


def rect_irradiance(radiance, w, h, d):
    """Irradiance at the point a distance d below the centre of a w × h rectangle of uniform
    radiance, facing it: four corner rectangles of the classic form factor."""
    x, y = (w / 2) / d, (h / 2) / d
    corner = 0.5 * (x / math.sqrt(1 + x * x) * math.atan(y / math.sqrt(1 + x * x))
                    + y / math.sqrt(1 + y * y) * math.atan(x / math.sqrt(1 + y * y)))
    return 4 * radiance * corner


@pytest.mark.parametrize("normalize", [False, True])
def test_a_rect_light_lights_a_diffuse_plane_as_usdlux_defines(tmp_path, normalize):
    """A RectLight of intensity I and exposure E (normalized: over its area) d above a Lambert
    plane of albedo ρ: the plane's radiance below its centre is ρ/π × the closed-form irradiance
    of radiance I·2^E(/area). The 64 pixels see that same radiance (their footprints differ by
    < 1e-4 of it), each an independent estimate: the tolerance is 4σ of their mean, σ from
    their spread, plus that 1e-4."""
    w, h, d, intensity, exposure, albedo = 2.0, 1.0, 1.5, 5.0, 1.5, 0.5
    s = new_stage(tmp_path / "rect.usda")
    camera(s, (0, d / 2, 0), size=(8, 8), rotate=(-90, 0, 0), focal=500)
    floor = mesh(s, "/World/Floor", [(-50, 0, -50), (-50, 0, 50), (50, 0, 50), (50, 0, -50)],
                 [4], [0, 1, 2, 3])
    floor.CreateDisplayColorAttr([(albedo, albedo, albedo)])
    light = UsdLux.RectLight.Define(s, "/Lights/Panel")
    light.CreateWidthAttr(w)
    light.CreateHeightAttr(h)
    light.CreateIntensityAttr(intensity)
    light.CreateExposureAttr(exposure)
    light.CreateNormalizeAttr(normalize)
    api = UsdGeom.XformCommonAPI(light)
    api.SetTranslate((0, d, 0))
    api.SetRotate((-90, 0, 0))  # emits along -Y, onto the plane
    s.Save()
    radiance = intensity * 2 ** exposure / (w * h if normalize else 1)
    want = albedo / math.pi * rect_irradiance(radiance, w, h, d)
    r = illum.load(tmp_path / "rect.usda").render(spp=256, integrator="direct", light_samples=4)
    pixels = r.beauty[..., 0].astype(np.float64).reshape(-1)
    got = float(pixels.mean())
    sigma = float(pixels.std(ddof=1)) / math.sqrt(pixels.size)
    assert abs(got - want) <= 4 * sigma + 1e-4 * want, (got, want, sigma)
