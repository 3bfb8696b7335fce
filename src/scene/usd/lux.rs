//! UsdLux lights as illum's: the same five, with UsdLux's radiance (color × intensity ×
//! 2^exposure × the blackbody colour, over the world area when `normalize` is on) and each
//! light's frame taken from its world transform (lights emit along their local -Z).

use super::{Reader, Result, value};
use crate::scene::format::{
    DiskDef, DomeConventionDef, DomeDef, LightDef, RectDef, SphereDef, SunDef, WrapDef,
};
use glam::{DMat4, DVec3};
use openusd::sdf::{self, Value};
use std::f64::consts::PI;

/// The blackbody table of `UsdLuxBlackbodyTemperatureAsRgb` (after John Walker's "Colour
/// Rendering of Spectra"): linear Rec.709 RGB at 1000 K to 10000 K in 500 K steps, the ends
/// repeated for the Catmull-Rom spline.
const BLACKBODY: [[f64; 3]; 22] = [
    [1.0, 0.027490, 0.0],
    [1.0, 0.027490, 0.0],
    [1.0, 0.149664, 0.0],
    [1.0, 0.256644, 0.008095],
    [1.0, 0.372033, 0.067450],
    [1.0, 0.476725, 0.153601],
    [1.0, 0.570376, 0.259196],
    [1.0, 0.653480, 0.377155],
    [1.0, 0.726878, 0.501606],
    [1.0, 0.791543, 0.628050],
    [1.0, 0.848462, 0.753228],
    [1.0, 0.898581, 0.874905],
    [1.0, 0.942771, 0.991642],
    [0.906947, 0.890456, 1.0],
    [0.828247, 0.841838, 1.0],
    [0.765791, 0.801896, 1.0],
    [0.715255, 0.768579, 1.0],
    [0.673683, 0.740423, 1.0],
    [0.638992, 0.716359, 1.0],
    [0.609681, 0.695588, 1.0],
    [0.609681, 0.695588, 1.0],
    [0.609681, 0.695588, 1.0],
];

/// The colour of a blackbody at `kelvin` (clamped to 1000–10000 K) with Rec.709 luminance 1,
/// as UsdLux defines `colorTemperature`.
pub(crate) fn blackbody(kelvin: f64) -> [f64; 3] {
    let x = ((kelvin - 1000.0) / 9000.0).clamp(0.0, 1.0) * (BLACKBODY.len() - 4) as f64;
    let seg = (x.floor() as usize).min(BLACKBODY.len() - 4);
    let t = x - seg as f64;
    let rgb: [f64; 3] = std::array::from_fn(|c| {
        let [a, b, d, e] = [0, 1, 2, 3].map(|i| BLACKBODY[seg + i][c]);
        0.5 * (2.0 * b
            + (d - a) * t
            + (2.0 * a - 5.0 * b + 4.0 * d - e) * t * t
            + (3.0 * b - a - 3.0 * d + e) * t * t * t)
    });
    let luma = 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
    rgb.map(|c| c / luma)
}

/// The light's frame in world space: centre, its local X and Y axes (scaled), and the
/// direction it emits toward (its local -Z, normalised).
struct Frame {
    center: DVec3,
    x: DVec3,
    y: DVec3,
    emit: DVec3,
}

fn frame(world: DMat4) -> Frame {
    Frame {
        center: world.transform_point3(DVec3::ZERO),
        x: world.transform_vector3(DVec3::X),
        y: world.transform_vector3(DVec3::Y),
        emit: world.transform_vector3(DVec3::NEG_Z).normalize_or_zero(),
    }
}

impl Reader {
    pub(super) fn light(&mut self, prim: &sdf::Path, kind: &str, world: DMat4) -> Result<()> {
        let distant = kind == "DistantLight";
        let mut intensity = self.number(
            prim,
            "inputs:intensity",
            if distant { 50000.0 } else { 1.0 },
        )?;
        let exposure = self.number(prim, "inputs:exposure", 0.0)?;
        let mut color = self.color(prim, "inputs:color", [1.0; 3])?;
        let normalize = self.boolean(prim, "inputs:normalize", false)?;
        if self.boolean(prim, "inputs:enableColorTemperature", false)? {
            let t = self.number(prim, "inputs:colorTemperature", 6500.0)?;
            let bb = blackbody(t);
            color = std::array::from_fn(|c| color[c] * bb[c]);
        }
        for attr in ["inputs:diffuse", "inputs:specular"] {
            let m = self.number(prim, attr, 1.0)?;
            if m != 1.0 {
                return Err(self.invalid(
                    prim,
                    attr,
                    m,
                    "illum's lights light every lobe alike (only 1 can be rendered exactly)",
                ));
            }
        }
        if !self.boolean(prim, "inputs:shadow:enable", true)? {
            return Err(self.invalid(
                prim,
                "inputs:shadow:enable",
                false,
                "illum traces every light's shadows",
            ));
        }
        self.light_extras(prim)?;
        let f = frame(world);
        let mut def = LightDef {
            rect: None,
            disk: None,
            sphere: None,
            dome: None,
            sun: None,
            color,
            intensity: 0.0,
            exposure,
            two_sided: false,
            texture: None,
            visible: true,
            shadows: None,
        };
        let texture = self.texture_file(prim)?;
        if texture.is_some() && !matches!(kind, "DomeLight" | "DomeLight_1" | "RectLight") {
            return Err(self.unsupported(
                prim,
                "inputs:texture:file",
                format!(
                    "textures on a {kind} are not read yet (a DomeLight's and RectLight's are)"
                ),
            ));
        }
        match kind {
            "RectLight" => {
                let w = self.number(prim, "inputs:width", 1.0)?;
                let h = self.number(prim, "inputs:height", 1.0)?;
                if f.x.dot(f.y).abs() > 1e-9 * f.x.length() * f.y.length() {
                    return Err(self.unsupported(
                        prim,
                        "xformOpOrder",
                        "the world transform shears the rectangle (illum's are rectangles)",
                    ));
                }
                let size = [w * f.x.length(), h * f.y.length()];
                if normalize && size[0] * size[1] > 0.0 {
                    intensity /= size[0] * size[1];
                }
                let normal = self.plane_normal(&f);
                let mut up = f.y;
                if let Some(name) = &texture {
                    // UsdLux puts the image's first texel at local (+X, +Y) and its last at
                    // (-X, -Y). illum's rect uvs start at -u/2 - v/2 with rows along v: so v
                    // runs along -Y, and where u then runs along +X the image is mirrored.
                    up = -f.y;
                    let u = up.cross(normal);
                    let mirror = u.dot(-f.x) < 0.0;
                    if let Some(t) = self.out.textures.0.get_mut(name) {
                        t.mirror_u = mirror;
                    }
                    def.texture = texture.clone();
                }
                def.rect = Some(RectDef {
                    center: f.center.to_array(),
                    normal: normal.to_array(),
                    size,
                    up: Some(up.to_array()),
                });
            }
            "DiskLight" => {
                let r = self.number(prim, "inputs:radius", 0.5)?;
                let (lx, ly) = (f.x.length(), f.y.length());
                if (lx - ly).abs() > 1e-9 * lx.max(ly) || f.x.dot(f.y).abs() > 1e-9 * lx * ly {
                    return Err(self.unsupported(
                        prim,
                        "xformOpOrder",
                        "the world transform makes the disk an ellipse (illum's are circles)",
                    ));
                }
                let radius = r * lx;
                if normalize && radius > 0.0 {
                    intensity /= PI * radius * radius;
                }
                def.disk = Some(DiskDef {
                    center: f.center.to_array(),
                    normal: self.plane_normal(&f).to_array(),
                    radius,
                });
            }
            "SphereLight" => {
                if self.boolean(prim, "treatAsPoint", false)? {
                    return Err(self.invalid(
                        prim,
                        "treatAsPoint",
                        true,
                        "illum has no point lights (give the sphere a radius)",
                    ));
                }
                let r = self.number(prim, "inputs:radius", 0.5)?;
                let s = self.uniform_scale(prim, world, "illum's sphere lights are spheres")?;
                let radius = r * s;
                if normalize && radius > 0.0 {
                    intensity /= 4.0 * PI * radius * radius;
                }
                def.sphere = Some(SphereDef {
                    center: f.center.to_array(),
                    radius,
                });
            }
            "DistantLight" => {
                let angle = self.number(prim, "inputs:angle", 0.53)?;
                // Unnormalized, intensity is the radiance of the sun's disk; illum's sun takes
                // the irradiance it gives, L·π·sin²(angle/2). Normalized (or a delta light), it
                // is that irradiance already.
                if !normalize && angle > 0.0 {
                    intensity *= PI * (angle.to_radians() / 2.0).sin().powi(2);
                }
                def.sun = Some(SunDef {
                    direction: (-f.emit).to_array(),
                    angular_diameter: angle,
                });
            }
            _ => {
                def.dome = Some(self.dome(prim, kind, world)?);
                def.texture = texture;
            }
        }
        def.intensity = intensity;
        self.out.lights.0.insert(prim.as_str().to_string(), def);
        Ok(())
    }

    /// The normal of a rect or disk light: perpendicular to its X and Y, on the side it emits.
    fn plane_normal(&self, f: &Frame) -> DVec3 {
        let n = f.x.cross(f.y);
        if n.dot(f.emit) < 0.0 { -n } else { n }
    }

    /// UsdLux features illum does not render, as warnings (the light itself is right).
    fn light_extras(&mut self, prim: &sdf::Path) -> Result<()> {
        for attr in [
            "inputs:shaping:cone:angle",
            "inputs:shaping:focus",
            "inputs:shaping:ies:file",
        ] {
            if self.authored(prim, attr)? {
                self.warn(
                    prim,
                    attr,
                    "light shaping is not rendered (the light emits unshaped)",
                );
            }
        }
        if !self.targets(prim, "light:filters")?.is_empty() {
            self.warn(prim, "light:filters", "light filters are not rendered");
        }
        Ok(())
    }

    /// `inputs:texture:file` as a texture of the scene, by the path it resolves to.
    fn texture_file(&mut self, prim: &sdf::Path) -> Result<Option<String>> {
        let attr = "inputs:texture:file";
        let Some(v) = self.attr(prim, attr)? else {
            return Ok(None);
        };
        let Value::AssetPath(a) = &v else {
            return Err(self.invalid(prim, attr, value::show(&v), "expected an asset path"));
        };
        if a.as_str().is_empty() {
            return Ok(None);
        }
        let (file, bytes) = self.asset_file(prim, attr, a);
        let name = format!("{}.{attr}", prim.as_str());
        self.add_texture(&name, file, bytes, None, WrapDef::Repeat);
        Ok(Some(name))
    }

    /// A DomeLight's orientation: its pole must be illum's +Y (after the stage's up axis), so
    /// that only a turn about it is left, which illum's `rotation` takes.
    fn dome(&mut self, prim: &sdf::Path, kind: &str, world: DMat4) -> Result<DomeDef> {
        match self
            .token(prim, "inputs:texture:format", "automatic")?
            .as_str()
        {
            "automatic" | "latlong" => {}
            other => {
                return Err(self.invalid(
                    prim,
                    "inputs:texture:format",
                    other,
                    "illum samples lat-long dome maps only",
                ));
            }
        }
        // DomeLight's pole is world +Y; DomeLight_1's is its poleAxis ("scene": the up axis).
        let pole_z = kind == "DomeLight_1"
            && match self.token(prim, "poleAxis", "scene")?.as_str() {
                "scene" => self.z_up,
                "Y" => false,
                "Z" => true,
                other => {
                    return Err(self.invalid(prim, "poleAxis", other, "expected scene, Y or Z"));
                }
            };
        let frame = if pole_z {
            world * DMat4::from_rotation_x(std::f64::consts::FRAC_PI_2)
        } else {
            world
        };
        let x = frame.transform_vector3(DVec3::X).normalize_or_zero();
        let y = frame.transform_vector3(DVec3::Y).normalize_or_zero();
        if (y - DVec3::Y).length() > 1e-6 || x.y.abs() > 1e-6 {
            return Err(self.unsupported(
                prim,
                "xformOpOrder",
                format!(
                    "the dome's pole points along {:?}, not the stage's up axis: illum turns a \
                     dome about its pole only",
                    y.to_array()
                ),
            ));
        }
        // OpenEXR's lat-long layout (UsdLux's) is illum's turned half a turn about +Y, then
        // the dome's own turn about +Y.
        let turn = (-x.z).atan2(x.x).to_degrees();
        Ok(DomeDef {
            rotation: 180.0 + turn,
            convention: DomeConventionDef::Illum,
        })
    }
}
