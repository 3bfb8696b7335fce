//! The camera section: the look-at form, or a camera of a glTF shape.

use super::check::Ctx;
use super::error::{SceneError, fmt_num, fmt_vec, quoted};
use super::format::{CameraDef, SceneFile};
use super::gltf::GltfCamera;
use super::load::{Builder, known};
use super::types::Camera;
use glam::DVec3;

type Result<T> = std::result::Result<T, SceneError>;

impl Builder<'_> {
    pub(crate) fn camera(&self, c: &CameraDef, file: &SceneFile) -> Result<Camera> {
        let ctx = self.ctx;
        let [width, height] = c.resolution;
        if width == 0 || height == 0 {
            let value = format!("[{width}, {height}]");
            return Err(ctx.err("camera.resolution", value, "width and height must be > 0"));
        }
        if let Some(shape) = &c.gltf {
            return self.gltf_camera(c, shape, file, width, height);
        }
        if c.index.is_some() {
            return Err(SceneError::unsupported(
                ctx.file,
                "camera.index",
                "only allowed together with camera.gltf",
            ));
        }
        let required =
            |key: &str, v: Option<[f64; 3]>| v.ok_or_else(|| missing_camera_field(ctx, key));
        let position = ctx.point("camera.position", required("position", c.position)?)?;
        let look_at_v = required("look_at", c.look_at)?;
        let look_at = ctx.point("camera.look_at", look_at_v)?;
        let fov_y = c.fov_y.ok_or_else(|| missing_camera_field(ctx, "fov_y"))?;
        if !(fov_y > 0.0 && fov_y < 180.0) {
            return Err(ctx.err(
                "camera.fov_y",
                fmt_num(fov_y),
                "must be in (0, 180) degrees",
            ));
        }
        let forward = look_at - position;
        if !forward.is_finite() || forward.length() == 0.0 {
            return Err(ctx.err(
                "camera.look_at",
                fmt_vec(&look_at_v),
                &format!(
                    "must differ from camera.position {}",
                    fmt_vec(&position.to_array())
                ),
            ));
        }
        let up = match c.up {
            Some(up) => ctx.direction("camera.up", up)?,
            None => DVec3::Y,
        };
        if forward.normalize().cross(up).length() < 1e-6 {
            return Err(ctx.err(
                "camera.up",
                fmt_vec(&up.to_array()),
                "must not be parallel to the view direction (set camera.up)",
            ));
        }
        Ok(Camera {
            position,
            look_at,
            up,
            fov_y_deg: fov_y,
            width,
            height,
        })
    }

    fn gltf_camera(
        &self,
        c: &CameraDef,
        shape: &str,
        file: &SceneFile,
        width: u32,
        height: u32,
    ) -> Result<Camera> {
        let ctx = self.ctx;
        for (key, given) in [
            ("position", c.position.is_some()),
            ("look_at", c.look_at.is_some()),
            ("up", c.up.is_some()),
            ("fov_y", c.fov_y.is_some()),
        ] {
            if given {
                return Err(SceneError::unsupported(
                    ctx.file,
                    format!("camera.{key}"),
                    "not allowed with camera.gltf (the glTF camera defines it)",
                ));
            }
        }
        let Some(cameras) = self.gltf_cameras.get(shape) else {
            let reason = if file.shapes.0.contains_key(shape) {
                "must name a shape with a gltf geometry".to_owned()
            } else {
                let gltf_shapes = file.shapes.0.iter().filter(|s| s.1.gltf.is_some());
                format!("no such gltf shape ({})", known(gltf_shapes.map(|s| s.0)))
            };
            return Err(ctx.err("camera.gltf", quoted(shape), &reason));
        };
        let index = c.index.unwrap_or(0);
        let Some(cam) = cameras.get(index as usize) else {
            return Err(ctx.err(
                "camera.index",
                index,
                &format!(
                    "out of range (shape \"{shape}\" has {} cameras)",
                    cameras.len()
                ),
            ));
        };
        match cam {
            GltfCamera::Perspective {
                position,
                forward,
                up,
                yfov_deg,
            } => Ok(Camera {
                position: *position,
                look_at: *position + *forward,
                up: *up,
                fov_y_deg: *yfov_deg,
                width,
                height,
            }),
            GltfCamera::Orthographic => Err(SceneError::unsupported(
                ctx.file,
                "camera.index",
                format!(
                    "glTF camera {index} of \"{shape}\" is orthographic; only perspective cameras are supported"
                ),
            )),
            GltfCamera::Unplaced => Err(SceneError::unsupported(
                ctx.file,
                "camera.index",
                format!(
                    "glTF camera {index} of \"{shape}\" is not used by any node of the loaded glTF scene"
                ),
            )),
        }
    }
}

fn missing_camera_field(ctx: Ctx, key: &str) -> SceneError {
    SceneError::unsupported(
        ctx.file,
        format!("camera.{key}"),
        "missing (required unless camera.gltf is given)",
    )
}
