//! The viewpoint: the camera a `UsdRenderSettings` prim names (with its resolution and aspect
//! ratio conform policy), else the first `UsdGeomCamera` of the stage. Cameras look down their
//! local -Z with +Y up; the vertical field of view follows from the focal length and the
//! aperture the conform policy leaves.

use super::{Reader, Result, value};
use crate::scene::format::CameraDef;
use glam::DVec3;
use openusd::sdf;

/// The image height when nothing sets a resolution; the width follows the aperture's aspect.
const DEFAULT_HEIGHT: f64 = 480.0;

impl Reader {
    pub(super) fn camera(&mut self) -> Result<CameraDef> {
        let root = sdf::Path::abs_root();
        let settings = self.settings_prim()?;
        let mut camera = None;
        let mut resolution = None;
        let mut policy = "expandAperture".to_string();
        if let Some(s) = &settings {
            camera = self.targets(s, "camera")?.first().cloned();
            if let Some(v) = self.attr(s, "resolution")? {
                let r = value::vec2(&v).ok_or_else(|| {
                    self.invalid(s, "resolution", value::show(&v), "expected int2")
                })?;
                resolution = Some(r);
            }
            let aspect = self.number(s, "pixelAspectRatio", 1.0)?;
            if aspect != 1.0 {
                return Err(self.invalid(
                    s,
                    "pixelAspectRatio",
                    aspect,
                    "illum renders square pixels only",
                ));
            }
            policy = self.token(s, "aspectRatioConformPolicy", "expandAperture")?;
        }
        let camera = match camera {
            Some(c) => {
                if !self.cameras.contains(&c) {
                    return Err(self.invalid(
                        settings.as_ref().unwrap_or(&root),
                        "camera",
                        c.as_str(),
                        "names no rendered Camera prim",
                    ));
                }
                c
            }
            None => self.cameras.first().cloned().ok_or_else(|| {
                self.unsupported(&root, "", "the stage has no Camera prim to render from")
            })?,
        };
        if self.token(&camera, "projection", "perspective")? != "perspective" {
            return Err(self.invalid(
                &camera,
                "projection",
                "orthographic",
                "illum renders perspective cameras only",
            ));
        }
        let focal = self.number(&camera, "focalLength", 50.0)?;
        let h_ap = self.number(&camera, "horizontalAperture", 20.955)?;
        let v_ap = self.number(&camera, "verticalAperture", 15.2908)?;
        if !(focal > 0.0 && h_ap > 0.0 && v_ap > 0.0) {
            return Err(self.invalid(
                &camera,
                "focalLength",
                format!("{focal} (apertures {h_ap} x {v_ap})"),
                "the focal length and apertures must be positive",
            ));
        }
        for attr in ["horizontalApertureOffset", "verticalApertureOffset"] {
            let o = self.number(&camera, attr, 0.0)?;
            if o != 0.0 {
                return Err(self.invalid(&camera, attr, o, "illum's cameras have no lens shift"));
            }
        }
        if self.number(&camera, "fStop", 0.0)? > 0.0 {
            self.warn(
                &camera,
                "fStop",
                "depth of field is not rendered (all in focus)",
            );
        }
        if self.authored(&camera, "clippingRange")? {
            self.warn(
                &camera,
                "clippingRange",
                "not applied (illum does not clip)",
            );
        }
        let [w, h] = match resolution {
            Some([w, h]) => [w, h],
            None => [(DEFAULT_HEIGHT * h_ap / v_ap).round(), DEFAULT_HEIGHT],
        };
        if !(w >= 1.0 && h >= 1.0 && w <= 16384.0 && h <= 16384.0) {
            let s = settings.as_ref().unwrap_or(&root);
            return Err(self.invalid(s, "resolution", format!("{w} x {h}"), "must be 1 to 16384"));
        }
        let image = w / h;
        // The vertical aperture the conform policy gives at this image aspect.
        let v_eff = match policy.as_str() {
            "expandAperture" => v_ap.max(h_ap / image),
            "cropAperture" => v_ap.min(h_ap / image),
            "adjustApertureWidth" => v_ap,
            "adjustApertureHeight" => h_ap / image,
            other => {
                let s = settings.as_ref().unwrap_or(&root);
                return Err(self.invalid(
                    s,
                    "aspectRatioConformPolicy",
                    other,
                    "illum keeps pixels square (expandAperture, cropAperture, \
                     adjustApertureWidth or adjustApertureHeight)",
                ));
            }
        };
        let world = self.world.get(&camera).copied().unwrap_or(self.to_y_up);
        let position = world.transform_point3(DVec3::ZERO);
        let forward = world.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
        let up = world.transform_vector3(DVec3::Y);
        Ok(CameraDef {
            position: Some(position.to_array()),
            look_at: Some((position + forward).to_array()),
            up: Some(up.to_array()),
            fov_y: Some((2.0 * (v_eff / (2.0 * focal)).atan()).to_degrees()),
            gltf: None,
            index: None,
            resolution: [w as u32, h as u32],
        })
    }

    /// The stage's `renderSettingsPrimPath`, else its first RenderSettings prim.
    fn settings_prim(&mut self) -> Result<Option<sdf::Path>> {
        let root = sdf::Path::abs_root();
        let named = self
            .stage
            .stage_metadata("renderSettingsPrimPath")
            .map_err(|e| self.read_error(&root, "renderSettingsPrimPath", e))?;
        if let Some(p) = named
            .as_ref()
            .and_then(value::token)
            .filter(|p| !p.is_empty())
        {
            let path =
                sdf::path(p).map_err(|e| self.read_error(&root, "renderSettingsPrimPath", e))?;
            if !self.render_settings.contains(&path) {
                return Err(self.invalid(
                    &root,
                    "renderSettingsPrimPath",
                    p,
                    "names no RenderSettings prim",
                ));
            }
            return Ok(Some(path));
        }
        Ok(self.render_settings.first().cloned())
    }
}
