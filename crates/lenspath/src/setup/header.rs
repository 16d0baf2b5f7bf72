//! What an image records of the render that made it: the EXR header of a
//! [`RenderSetup`] (OpenEXR's standard attributes and lenspath's own).

use std::collections::BTreeMap;

use glam::{Mat4, Vec4};

use super::{CameraSettings, RenderSetup};
use crate::camera::LensFocus;
use crate::error::Result;
use crate::io::exr::HeaderValue;
use crate::io::image::ImageHeader;
use crate::lens::LensSystem;
use crate::names::Named;
use crate::sensor::Exposure;

impl RenderSetup {
    /// The EXR header of this setup's render of `scene_name` (taken with
    /// `exposure` through a sensor): a crop's place in the full frame, the
    /// OpenEXR standard attributes that apply (`worldToCamera`; `worldToNDC`
    /// for the projective cameras, which a real lens's distortion is not;
    /// `focus` in metres and `aperture` as an f-number for a real lens;
    /// `expTime` and `isoSpeed` through a sensor; `software`, `comments`),
    /// and the settings under `lenspath/`. No `owner`: lenspath does not
    /// know who owns the image.
    pub fn image_header(&self, scene_name: &str, exposure: Option<&Exposure>) -> Result<ImageHeader> {
        use HeaderValue::{Float, Int, Matrix, Text};
        let s = &self.settings;
        let (width, height) = (s.width, s.height);
        let mut a = BTreeMap::new();
        let mut put = |name: &str, value: HeaderValue| a.insert(name.to_string(), value);
        let camera_from_render = Mat4::from(self.pose.render_from_camera.inverse());
        put("worldToCamera", Matrix(camera_from_render.to_cols_array()));
        put("software", Text(format!("lenspath {}", env!("CARGO_PKG_VERSION"))));
        put("lenspath/scene", Text(scene_name.to_string()));
        let camera_kind = self.camera.kind().name();
        put("lenspath/camera", Text(camera_kind.to_string()));
        let mut comments = format!("{scene_name} through a {camera_kind} camera");
        match &self.camera {
            CameraSettings::Pinhole { fov_y_deg } | CameraSettings::ThinLens { fov_y_deg, .. } => {
                put(
                    "worldToNDC",
                    Matrix((ndc_from_camera(*fov_y_deg, width, height) * camera_from_render).to_cols_array()),
                );
                put("lenspath/fovYDeg", Float(*fov_y_deg));
                if let CameraSettings::ThinLens {
                    aperture_radius,
                    focus_distance,
                    ..
                } = &self.camera
                {
                    put("lenspath/apertureRadius", Float(*aperture_radius));
                    put("lenspath/focusDistance", Float(*focus_distance));
                }
            }
            CameraSettings::Realistic(r) => {
                let system = LensSystem::new(&r.lens);
                let f_number = match r.f_number {
                    Some(n) => n,
                    None => system.paraxial()?.f_number,
                };
                put("aperture", Float(f_number as f32));
                put("lenspath/lens", Text(r.lens.name().to_string()));
                put("lenspath/sceneUnitM", Float(r.scene_unit_m as f32));
                match r.focus {
                    LensFocus::Distance(d) => {
                        put("focus", Float((d * r.scene_unit_m) as f32));
                        put("lenspath/focusDistance", Float(d as f32));
                    }
                    LensFocus::SensorDepthMm(mm) => {
                        put("lenspath/sensorDepthMm", Float(mm as f32));
                    }
                }
                comments += &format!(" ({} at f/{f_number:.2})", r.lens.name());
            }
        }
        if let Some(exposure) = exposure {
            put("expTime", Float(exposure.exposure_time_s as f32));
            put("isoSpeed", Float(exposure.iso as f32));
            put("lenspath/sensor", Text(exposure.sensor_name.clone()));
        }
        let path = s.integrator.path_settings();
        put("lenspath/integrator", Text(s.integrator.kind().name().to_string()));
        put("lenspath/maxDepth", Int(path.max_depth.min(i32::MAX as u32) as i32));
        put(
            "lenspath/lightSamples",
            Int(path.light_samples.min(i32::MAX as u32) as i32),
        );
        put("lenspath/sampler", Text(s.sampler.name().to_string()));
        // An int when it fits (every seed a front end defaults to), else a double (exact for a u32).
        put(
            "lenspath/seed",
            i32::try_from(s.seed).map_or(HeaderValue::Double(f64::from(s.seed)), Int),
        );
        if let Some(nm) = s.film.wavelength_nm() {
            put("lenspath/wavelengthNm", Float(nm));
        }
        comments += &format!(", {} spp of the {} integrator", s.spp, s.integrator.kind().name());
        put("comments", Text(comments));
        Ok(ImageHeader {
            frame: s.crop.map(|c| ((width, height), (c.x0 as i32, c.y0 as i32))),
            attributes: a,
        })
    }
}

/// The perspective cameras' projection from camera space to OpenEXR's NDC
/// (0, 0) at the display window's top-left corner, (1, 1) at its bottom
/// right; w is the depth along the view): `x/(2 tan(fov_x/2) z) + 1/2` and
/// `−y/(2 tan(fov_y/2) z) + 1/2`, the inverse of
/// `PerspectiveCamera::direction_through`.
fn ndc_from_camera(fov_y_deg: f32, width: u32, height: u32) -> Mat4 {
    let tan_y = (0.5 * fov_y_deg.to_radians()).tan();
    let tan_x = tan_y * width as f32 / height as f32;
    Mat4::from_cols(
        Vec4::new(0.5 / tan_x, 0.0, 0.0, 0.0),
        Vec4::new(0.0, -0.5 / tan_y, 0.0, 0.0),
        Vec4::new(0.5, 0.5, 0.0, 1.0),
        Vec4::new(0.0, 0.0, 1.0, 0.0),
    )
}
