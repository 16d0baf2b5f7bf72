//! The range finder: probe rays through the patch find its dominant depth,
//! and the lens model turns that depth into a sensor position, without
//! rendering ([`Focuser::range_focus`]); the `rangefinder` and `depth`
//! strategies start from it.

use glam::{DVec3, Vec2, Vec3};

use super::search::{Focuser, BEST_FOCUS_CYCLES_PER_PIXEL, DEPTH_BUDGET_OF_SWEEP};
use crate::camera::{Camera, CameraSample, RealisticCamera};
use crate::error::Result;

/// Where the range finder puts a patch's focus, mm behind the stop.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RangeFocus {
    /// The real-ray conjugate of the dominant depth (a focus scale's reading).
    pub conjugate_z_mm: f64,
    /// The best-contrast position for the surface there, aberrations and field curvature included.
    pub best_focus_z_mm: f64,
    /// The fraction of the probes that hit something and fall in the dominant one-DoF window.
    pub dominant_fraction: f64,
    /// The conjugates of the farthest and the nearest probe's depth, mm
    /// behind the stop: the patch's depths, whatever carries its contrast.
    pub probe_span_z_mm: (f64, f64),
}

impl Focuser<'_> {
    /// Camera rays through `k` × `k` points of the patch: what each hits, in
    /// camera space (scene units; the sensor centre is the origin and +z the
    /// view axis, so `z` is the depth along the axis).
    pub(super) fn probe_points(&mut self, k: u32) -> Result<Vec<Vec3>> {
        let s = &self.settings;
        let camera = RealisticCamera::for_region(
            self.pose,
            s.width,
            s.height,
            &self.camera_settings(self.range_mm.0),
            s.patch,
        )?;
        let camera_from_render = self.pose.render_from_camera.inverse();
        let p = s.patch;
        let mut points = Vec::new();
        for j in 0..k {
            for i in 0..k {
                let film = Vec2::new(
                    p.x0 as f32 + (i as f32 + 0.5) / k as f32 * p.width as f32,
                    p.y0 as f32 + (j as f32 + 0.5) / k as f32 * p.height as f32,
                );
                // The first of a few lens positions the optics let through.
                let ray = [Vec2::splat(0.5), Vec2::new(0.25, 0.5), Vec2::new(0.75, 0.5)]
                    .into_iter()
                    .find_map(|lens| camera.generate_ray(CameraSample::new(film, lens)));
                if let Some(cr) = ray {
                    self.camera_rays += 1;
                    if let Some(hit) = self.scene.intersect(&cr.ray) {
                        points.push(camera_from_render.transform_point3(hit.p));
                    }
                }
            }
        }
        Ok(points)
    }

    /// Where the patch's dominant surface focuses, from 8×8 probe rays: each
    /// probe's depth conjugate; the densest one-DoF window of them (the depth
    /// most of the patch sees, robust to a background peeking past an edge)
    /// and its median; and the best-contrast sensor position of up to nine
    /// probes spread through that window, from the lens's through-focus
    /// modulation at their actual positions (`Focuser::point_best_focus_z`),
    /// and their median. `None` when no probe hits anything.
    pub fn range_focus(&mut self) -> Result<Option<RangeFocus>> {
        let mut probes: Vec<(f64, Vec3)> = self
            .probe_points(8)?
            .into_iter()
            .filter_map(|p| self.sensor_depth_mm_for_distance(f64::from(p.z)).ok().map(|z| (z, p)))
            .collect();
        if probes.is_empty() {
            return Ok(None);
        }
        probes.sort_by(|a, b| a.0.total_cmp(&b.0));
        let window = self.depth_of_focus_mm(probes[probes.len() / 2].0);
        let (mut best_start, mut best_count, mut end) = (0, 0, 0);
        for start in 0..probes.len() {
            while end < probes.len() && probes[end].0 - probes[start].0 <= window {
                end += 1;
            }
            if end - start > best_count {
                (best_start, best_count) = (start, end - start);
            }
        }
        let dominant = &probes[best_start..best_start + best_count];
        let picks = dominant.len().min(9);
        let mut best_focus: Vec<f64> = (0..picks)
            .map(|k| {
                let (z, p) = dominant[k * (dominant.len() - 1) / (picks - 1).max(1)];
                self.point_best_focus_z(p, z)
            })
            .collect();
        best_focus.sort_by(f64::total_cmp);
        Ok(Some(RangeFocus {
            conjugate_z_mm: dominant[dominant.len() / 2].0,
            best_focus_z_mm: best_focus[best_focus.len() / 2],
            dominant_fraction: best_count as f64 / probes.len() as f64,
            probe_span_z_mm: (probes[0].0, probes[probes.len() - 1].0),
        }))
    }

    /// The camera-space point `p` (scene units from the sensor centre) in lens
    /// coordinates (mm, from the stop) with the sensor `z` mm behind the stop.
    pub(super) fn lens_point(&self, p: Vec3, z: f64) -> DVec3 {
        let mm = self.mm_per_scene;
        DVec3::new(f64::from(p.x) * mm, f64::from(p.y) * mm, z - f64::from(p.z) * mm)
    }

    /// The sensor position where the image of the camera-space point `p` has
    /// the most contrast at the frequencies the focus measures see
    /// ([`BEST_FOCUS_CYCLES_PER_PIXEL`]), searched within 5 DoF of its
    /// conjugate `conjugate_z` (which it falls back to). The point's place in
    /// lens coordinates depends on the sensor position (the lens moves to
    /// focus), so the search is repeated once from its own answer.
    pub(super) fn point_best_focus_z(&self, p: Vec3, conjugate_z: f64) -> f64 {
        let frequency_per_mm = BEST_FOCUS_CYCLES_PER_PIXEL / self.pitch_mm;
        let mut z = conjugate_z;
        for _ in 0..2 {
            let half_range = 5.0 * self.depth_of_focus_mm(z);
            let bundle = self.system.spot_bundle(self.lens_point(p, z), 32);
            match bundle.best_focus_z(z - half_range, z + half_range, 100, frequency_per_mm) {
                Some(best) => z = best,
                None => return conjugate_z,
            }
        }
        z
    }

    /// Range-finder focusing ([`Focuser::range_focus`]); with nothing in the
    /// patch to range on (only sky), the contrast search instead (not `fast`,
    /// which would probe again).
    pub(super) fn rangefinder(&mut self) -> Result<f64> {
        match self.range_focus()? {
            Some(range) => Ok(range.best_focus_z_mm),
            None => self.contrast_search(),
        }
    }

    /// The range finder ([`Focuser::range_focus`]), then a short contrast
    /// refinement from a light field with the rest of
    /// [`DEPTH_BUDGET_OF_SWEEP`] ([`Focuser::refocused_peak`]); with nothing
    /// in the patch to range on, the contrast search instead.
    pub(super) fn depth(&mut self) -> Result<f64> {
        match self.range_focus()? {
            Some(range) => self.refocused_peak(range.best_focus_z_mm, range.probe_span_z_mm, DEPTH_BUDGET_OF_SWEEP),
            None => self.contrast_search(),
        }
    }
}
