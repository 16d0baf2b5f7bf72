//! A dispersive glass in a scene against Snell's law: the shipped
//! `scenes/prism.toml` (an SF11 prism and a lit slit seen through it),
//! rendered at the F and C lines, shows the slit in the columns where a ray
//! traced through the prism's faces by Snell's law, with the glass's
//! catalogue index at that wavelength, reaches the slit's centre.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use glam::{DVec3, Vec2};
use lenspath::camera::{Camera, CameraSample, PerspectiveCamera};
use lenspath::film::{Filter, PixelRect};
use lenspath::glass::{C_LINE_NM, F_LINE_NM};
use lenspath::integrator::Integrator;
use lenspath::io::load_scene;
use lenspath::materials::Material;
use lenspath::render::{render, FilmResponse, RenderSettings};
use lenspath::scene::Scene;

/// Schott's datasheet indices of SF11 at the F and C lines: independent
/// of the refractiveindex.info Sellmeier fit lenspath ships.
const SF11_N_F: f64 = 1.80645;
const SF11_N_C: f64 = 1.77599;

const WIDTH: u32 = 640;
const HEIGHT: u32 = 400;
/// The rows checked, in the middle of the spectrum (lower rows see the
/// table before the slit).
const ROWS: std::ops::Range<u32> = 118..122;

/// The prism's triangles and the slit's centre line, in f64.
struct Geometry {
    /// Every triangle of the dielectric mesh.
    prism: Vec<[DVec3; 3]>,
    /// A point of the slit's centre line, the line's direction, and the
    /// unit vector across the slit (in its plane).
    slit_centre: DVec3,
    slit_along: DVec3,
    slit_across: DVec3,
}

impl Geometry {
    fn of(scene: &Scene) -> Geometry {
        let to_d = |v: glam::Vec3| v.as_dvec3();
        let prism = scene
            .meshes
            .iter()
            .filter(|m| matches!(scene.materials[m.material as usize], Material::Dielectric { .. }))
            .flat_map(|m| m.indices.iter().map(|t| t.map(|i| to_d(m.positions[i as usize]))))
            .collect::<Vec<_>>();
        let slit = scene
            .meshes
            .iter()
            .find(|m| m.emission.is_some())
            .expect("the scene has a slit");
        let corners: Vec<DVec3> = slit.positions.iter().map(|&p| to_d(p)).collect();
        let centre = corners.iter().sum::<DVec3>() / corners.len() as f64;
        // The slit is a tall quad: its long side is vertical.
        let slit_along = DVec3::Y;
        let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]).normalize();
        Geometry {
            prism,
            slit_centre: centre,
            slit_along,
            slit_across: slit_along.cross(normal).normalize(),
        }
    }

    /// The nearest prism triangle `origin + t·direction` meets (t > 1e-9),
    /// with its unit normal.
    fn hit(&self, origin: DVec3, direction: DVec3) -> Option<(DVec3, DVec3)> {
        let mut best: Option<(f64, DVec3)> = None;
        for [a, b, c] in &self.prism {
            // Möller–Trumbore.
            let (e1, e2) = (*b - *a, *c - *a);
            let p = direction.cross(e2);
            let det = e1.dot(p);
            if det.abs() < 1e-15 {
                continue;
            }
            let s = origin - *a;
            let u = s.dot(p) / det;
            let q = s.cross(e1);
            let v = direction.dot(q) / det;
            let t = e2.dot(q) / det;
            if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 1e-9 && best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, e1.cross(e2).normalize()));
            }
        }
        best.map(|(t, n)| (origin + t * direction, n))
    }

    /// Where a camera ray ends up across the slit's plane: its signed
    /// distance from the slit's centre line after refracting into and out of
    /// the prism with index `n` (None: it misses the prism or is totally
    /// reflected inside).
    fn offset_at_slit(&self, origin: DVec3, direction: DVec3, n: f64) -> Option<f64> {
        let (p, normal) = self.hit(origin, direction)?;
        let inside = refract(direction, normal, 1.0 / n)?;
        let (q, normal) = self.hit(p, inside)?;
        let out = refract(inside, normal, n)?;
        let slit_normal = self.slit_across.cross(self.slit_along);
        let t = (self.slit_centre - q).dot(slit_normal) / out.dot(slit_normal);
        (t > 0.0).then(|| (q + t * out - self.slit_centre).dot(self.slit_across))
    }
}

/// Snell's law in vector form: `direction` refracted at a surface of unit
/// normal `normal` (either side) with relative index `eta` = n_from / n_to.
fn refract(direction: DVec3, normal: DVec3, eta: f64) -> Option<DVec3> {
    let normal = if direction.dot(normal) > 0.0 { -normal } else { normal };
    let cos_i = -direction.dot(normal);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    (k >= 0.0).then(|| eta * direction + (eta * cos_i - k.sqrt()) * normal)
}

/// The column (raster x) whose camera ray on row `y` reaches the slit's
/// centre line through the prism of index `n`: bisection between the pixel
/// centres where the offset changes sign.
fn predicted_column(camera: &PerspectiveCamera, geometry: &Geometry, y: f32, n: f64) -> f64 {
    let offset = |x: f64| {
        let ray = camera
            .generate_ray(CameraSample::new(Vec2::new(x as f32, y), Vec2::splat(0.5)))?
            .ray;
        geometry.offset_at_slit(ray.origin.as_dvec3(), ray.direction.as_dvec3().normalize(), n)
    };
    let columns: Vec<(f64, f64)> = (0..WIDTH)
        .filter_map(|x| {
            let x = f64::from(x) + 0.5;
            offset(x).map(|o| (x, o))
        })
        .collect();
    let (mut lo, mut hi) = columns
        .windows(2)
        .find(|w| w[0].1.signum() != w[1].1.signum() && w[1].0 - w[0].0 == 1.0)
        .map(|w| (w[0], w[1]))
        .expect("some column sees the slit through the prism");
    for _ in 0..40 {
        let mid = 0.5 * (lo.0 + hi.0);
        let o = offset(mid).expect("between two columns that see the slit");
        if o.signum() == lo.1.signum() {
            lo = (mid, o);
        } else {
            hi = (mid, o);
        }
    }
    0.5 * (lo.0 + hi.0)
}

/// The slit's image on each row: the light-weighted mean column of the
/// pixels within 12 columns of `around` (the slit is about 4 wide).
fn measured_columns(image: &lenspath::film::Image, around: &[f64]) -> Vec<f64> {
    (0..image.height)
        .map(|y| {
            let centre = around[y as usize].round() as i64;
            let (mut sum, mut first) = (0.0, 0.0);
            for x in (centre - 12).max(0)..(centre + 12).min(i64::from(image.width)) {
                let v = f64::from(image.pixel(x as u32, y)[0]);
                sum += v;
                first += v * (x as f64 + 0.5);
            }
            first / sum
        })
        .collect()
}

#[test]
fn a_prism_spreads_the_slit_where_snells_law_puts_each_wavelength() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/prism.toml");
    let loaded = load_scene(&path).unwrap();
    let view = loaded.scene.view.expect("the scene file gives its camera");
    let geometry = Geometry::of(&loaded.scene);
    let camera = PerspectiveCamera::pinhole(view.pose, view.fov_y_deg, WIDTH, HEIGHT);
    let scene = loaded.scene.compile(&Default::default()).unwrap();
    let crop = PixelRect {
        x0: 0,
        y0: ROWS.start,
        width: WIDTH,
        height: ROWS.len() as u32,
    };
    let mut centres = Vec::new();
    for (nm, n) in [(F_LINE_NM, SF11_N_F), (C_LINE_NM, SF11_N_C)] {
        let settings = RenderSettings {
            width: WIDTH,
            height: HEIGHT,
            spp: 64,
            integrator: Integrator::path(4, 1),
            seed: 5,
            filter: Filter::Box,
            crop: Some(crop),
            depth: false,
            film: FilmResponse::radiance(Some(nm as f32)),
            ..Default::default()
        };
        let image = render(&scene, &camera, &settings, &|_, _| {}, &AtomicBool::new(false))
            .unwrap()
            .image;
        let predicted: Vec<f64> = ROWS
            .map(|y| predicted_column(&camera, &geometry, y as f32 + 0.5, n))
            .collect();
        let measured = measured_columns(&image, &predicted);
        for (row, (m, p)) in ROWS.zip(measured.iter().zip(&predicted)) {
            eprintln!("{nm} nm, row {row}: slit at column {m:.3}, Snell's law {p:.3}");
            assert!(
                (m - p).abs() < 0.25,
                "{nm} nm, row {row}: slit at column {m:.3}, Snell's law {p:.3}"
            );
        }
        centres.push((measured.iter().sum::<f64>(), predicted.iter().sum::<f64>()));
    }
    // Blue is bent more than red, by the predicted number of columns.
    let [(blue, blue_predicted), (red, red_predicted)] = centres[..] else {
        unreachable!()
    };
    let (spread, predicted) = (red - blue, red_predicted - blue_predicted);
    eprintln!("F to C: {spread:.3} columns, Snell's law {predicted:.3} (summed over the rows)");
    assert!(
        predicted > 20.0 * ROWS.len() as f64,
        "the prism disperses: {predicted:.3} columns over the rows"
    );
    assert!(
        (spread / predicted - 1.0).abs() < 0.01,
        "F to C {spread:.3} columns, Snell's law {predicted:.3}"
    );
}
