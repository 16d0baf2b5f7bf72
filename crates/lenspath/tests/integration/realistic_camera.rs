//! The realistic camera against first-order optics: exposure of a uniform
//! scene, the image of a point in and out of focus, stopping down, and how
//! many generated rays get through.

use std::sync::atomic::AtomicBool;

use glam::{Vec2, Vec3};
use lenspath::accel::BvhSettings;
use lenspath::camera::{
    Aperture, ApertureMask, ApertureShape, CameraPose, LensFocus, PerspectiveCamera, Radiometry, RealisticCamera,
    RealisticCameraSettings,
};
use lenspath::film::{Filter, Image};
use lenspath::integrator::Integrator;
use lenspath::lens::{library, LensPrescription, LensSystem, BUILTIN_LENSES};
use lenspath::lights::Light;
use lenspath::materials::Material;
use lenspath::math::Rgb;
use lenspath::render::{render, FilmResponse, RenderSettings};
use lenspath::scene::Scene;
use lenspath::shapes::Sphere;

struct Shot<'a> {
    lens: &'a str,
    sensor_mm: (f64, f64),
    pixels: (u32, u32),
    focus: LensFocus,
    f_number: Option<f64>,
    radiometry: Radiometry,
    spp: u32,
    aperture: ApertureShape,
    /// Render at this one wavelength (`None`: colour).
    wavelength_nm: Option<f32>,
}

fn camera(shot: &Shot) -> RealisticCamera {
    RealisticCamera::new(
        CameraPose::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y),
        shot.pixels.0,
        shot.pixels.1,
        &RealisticCameraSettings {
            f_number: shot.f_number,
            radiometry: shot.radiometry,
            aperture: shot.aperture.clone(),
            ..RealisticCameraSettings::new(LensPrescription::load(shot.lens).unwrap(), shot.sensor_mm, shot.focus)
        },
    )
    .unwrap()
}

fn shoot(scene: Scene, shot: &Shot) -> Image {
    let settings = RenderSettings {
        width: shot.pixels.0,
        height: shot.pixels.1,
        spp: shot.spp,
        integrator: Integrator::path(1, 1),
        seed: 7,
        filter: Filter::Box,
        threads: None,
        tile_size: 16,
        crop: None,
        depth: true,
        film: FilmResponse::radiance(shot.wavelength_nm),
        ..Default::default()
    };
    let compiled = scene.compile(&BvhSettings::default()).unwrap();
    let out = render(&compiled, &camera(shot), &settings, &|_, _| {}, &AtomicBool::new(false)).unwrap();
    assert_eq!(
        out.stats.invalid_samples, 0,
        "NaN or infinite samples through {}",
        shot.lens
    );
    out.image
}

/// The sensor `lens` is listed with.
fn listed_sensor_mm(lens: &str) -> (f64, f64) {
    library::shipped()
        .iter()
        .find(|l| l.name == lens)
        .expect("a shipped lens")
        .sensor_mm
}

fn uniform_environment() -> Scene {
    Scene {
        lights: vec![Light::Environment {
            radiance: Rgb::ONE.into(),
        }],
        ..Default::default()
    }
}

/// Mean green value over a block of pixels.
fn block_mean(image: &Image, xs: std::ops::Range<u32>, ys: std::ops::Range<u32>) -> f64 {
    let n = (xs.len() * ys.len()) as f64;
    ys.flat_map(|y| xs.clone().map(move |x| (x, y)))
        .map(|(x, y)| f64::from(image.pixel(x, y)[1]))
        .sum::<f64>()
        / n
}

/// Every shipped lens renders, focused at infinity and wide open, a uniform
/// scene onto the sensor it is listed with, and its image circle reaches that
/// sensor's corners: the corner pixels get at least 1% of the centre's light
/// (the listing's claim), or, for a lens listed as a circular fisheye, none
/// while the centre is lit.
#[test]
fn every_shipped_lens_covers_the_sensor_it_is_listed_with() {
    for lens in library::shipped() {
        let system = LensSystem::new(&LensPrescription::load(&lens.name).unwrap());
        let infinity = system.real_focus_at_infinity(0.1).unwrap().0;
        let (w, h) = (36, 24);
        let image = shoot(
            uniform_environment(),
            &Shot {
                lens: &lens.name,
                sensor_mm: lens.sensor_mm,
                pixels: (w, h),
                focus: LensFocus::SensorDepthMm(infinity),
                f_number: None,
                radiometry: Radiometry::Normalized,
                spp: 64,
                aperture: ApertureShape::Circle,
                wavelength_nm: None,
            },
        );
        let centre = block_mean(&image, w / 2 - 1..w / 2 + 1, h / 2 - 1..h / 2 + 1);
        let corners = [(0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)].map(|(x, y)| f64::from(image.pixel(x, y)[1]));
        let darkest = corners.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(centre > 0.5, "{}: centre {centre}", lens.name);
        if lens.image_circle_inside_sensor {
            assert!(corners.iter().all(|&c| c == 0.0), "{}: corners {corners:?}", lens.name);
        } else {
            assert!(
                darkest > 0.01 * centre,
                "{}: corners {corners:?}, centre {centre}",
                lens.name
            );
        }
    }
}

#[test]
fn a_uniform_scene_reads_its_radiance_at_the_centre_and_vignettes_symmetrically() {
    for (lens, _) in BUILTIN_LENSES {
        let shot = Shot {
            lens,
            sensor_mm: listed_sensor_mm(lens),
            pixels: (48, 32),
            focus: LensFocus::Distance(5.0),
            f_number: None,
            radiometry: Radiometry::Normalized,
            spp: 256,
            aperture: ApertureShape::Circle,
            wavelength_nm: None,
        };
        let image = shoot(uniform_environment(), &shot);
        assert!(image.rgb.iter().all(|v| v.is_finite() && *v >= 0.0), "{lens}");
        // The very centre: a 0.36 × 0.24 mm crop of the sensor.
        let crop = Shot {
            sensor_mm: (0.36, 0.24),
            pixels: (6, 4),
            spp: 1024,
            ..shot
        };
        let very_centre = shoot(uniform_environment(), &crop).mean()[1];
        assert!((very_centre - 1.0).abs() < 0.01, "{lens}: centre reads {very_centre}");
        let centre = block_mean(&image, 22..26, 14..18);
        let corner = block_mean(&image, 0..4, 0..4);
        let edge = block_mean(&image, 0..4, 14..18);
        // Falling toward the corners (the fisheye's image circle ends before the edges: both 0).
        assert!(
            corner <= edge && edge < centre && corner < 0.99 * centre,
            "{lens}: corner {corner}, edge {edge}, centre {centre}"
        );
        // Symmetric about the centre: each half against its mirror image.
        let (left, right) = (block_mean(&image, 0..24, 0..32), block_mean(&image, 24..48, 0..32));
        let (top, bottom) = (block_mean(&image, 0..48, 0..16), block_mean(&image, 0..48, 16..32));
        assert!(
            (left - right).abs() < 0.01 * centre,
            "{lens}: left {left}, right {right}"
        );
        assert!(
            (top - bottom).abs() < 0.01 * centre,
            "{lens}: top {top}, bottom {bottom}"
        );
    }
}

/// A camera moved or resized without being built again traces the rays a
/// camera built there, or at that size, does; a region's camera is not resized.
#[test]
fn moved_and_resized_cameras_are_the_built_ones() {
    use lenspath::camera::{Camera, CameraSample};
    use lenspath::render::PixelRect;
    let mut settings = RealisticCameraSettings::new(
        LensPrescription::load("dgauss50").unwrap(),
        (36.0, 24.0),
        LensFocus::Distance(2.0),
    );
    settings.f_number = Some(4.0);
    settings.aperture = ApertureShape::parse("blades:6").unwrap();
    let here = CameraPose::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y);
    let there = CameraPose::look_at(Vec3::new(0.3, 1.0, -2.0), Vec3::new(0.0, 0.5, 1.0), Vec3::Y);
    let built = RealisticCamera::new(here, 96, 64, &settings).unwrap();
    let moved = built.with_pose(there);
    let resized = built.with_image_size(48, 32).unwrap();
    let built_there = RealisticCamera::new(there, 96, 64, &settings).unwrap();
    let built_small = RealisticCamera::new(here, 48, 32, &settings).unwrap();
    let mut rays = 0;
    for k in 0..2000u32 {
        // A low-discrepancy spread of film and lens positions (additive recurrences).
        let u = |a: f64| (f64::from(k) * a).fract() as f32;
        let (film, lens) = (
            Vec2::new(u(0.618_034) * 96.0, u(0.754_878) * 64.0),
            Vec2::new(u(0.569_840), u(0.381_966)),
        );
        let ray = |c: &RealisticCamera, film: Vec2| {
            c.generate_ray(CameraSample::new(film, lens))
                .map(|r| (r.ray.origin, r.ray.direction, r.weight))
        };
        assert_eq!(ray(&moved, film), ray(&built_there, film));
        assert_eq!(ray(&resized, film * 0.5), ray(&built_small, film * 0.5));
        rays += usize::from(ray(&built, film).is_some());
    }
    assert!(rays > 1000, "most samples get through: {rays}");
    let patch = PixelRect {
        x0: 10,
        y0: 10,
        width: 8,
        height: 8,
    };
    let region = RealisticCamera::for_region(here, 96, 64, &settings, patch).unwrap();
    assert!(region.with_image_size(48, 32).is_err());
}

#[test]
fn physical_exposure_darkens_with_the_square_of_the_f_number() {
    let shot = |f_number| Shot {
        lens: "dgauss50",
        sensor_mm: (3.6, 2.4),
        pixels: (12, 8),
        focus: LensFocus::Distance(5.0),
        f_number,
        radiometry: Radiometry::Physical,
        spp: 256,
        aperture: ApertureShape::Circle,
        wavelength_nm: None,
    };
    let open = shoot(uniform_environment(), &shot(None)).mean()[1];
    let f8 = shoot(uniform_environment(), &shot(Some(8.0))).mean()[1];
    let wide_open = LensSystem::new(&LensPrescription::load("dgauss50").unwrap())
        .paraxial()
        .unwrap()
        .f_number;
    let expected = (wide_open / 8.0).powi(2);
    assert!(
        (f8 / open / expected - 1.0).abs() < 0.03,
        "f/8 over wide open {}, expected {expected}",
        f8 / open
    );
}

/// An emitting sphere of `radius_m` on the axis at `distance_m` in the dark.
fn point_source(distance_m: f32, radius_m: f32) -> Scene {
    Scene {
        spheres: vec![Sphere {
            center: Vec3::new(0.0, 0.0, distance_m),
            radius: radius_m,
            material: 0,
            emission: Some(Rgb::ONE.into()),
        }],
        materials: vec![Material::Diffuse { reflectance: Rgb::ZERO }],
        ..Default::default()
    }
}

/// Diameter of the image of a point from the second moment of the
/// brightness about its centroid: a uniform disc of diameter c has ⟨r²⟩ = c²/8.
fn spot_diameter_mm(image: &Image, pitch_mm: f64) -> f64 {
    let mut sum = 0.0;
    let mut first = [0.0; 2];
    let mut second = 0.0;
    for y in 0..image.height {
        for x in 0..image.width {
            let v = f64::from(image.pixel(x, y)[1]);
            let (px, py) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
            sum += v;
            first[0] += v * px;
            first[1] += v * py;
            second += v * (px * px + py * py);
        }
    }
    let (cx, cy) = (first[0] / sum, first[1] / sum);
    let r2 = second / sum - cx * cx - cy * cy;
    (8.0 * r2).sqrt() * pitch_mm
}

/// First-order optics of a point at `distance_mm` from the sensor: the
/// blur disc diameter (the image by the Gaussian lens equation about the
/// principal planes, the cone to it through the exit pupil, cut by the
/// sensor) and the lateral magnification.
fn first_order(system: &LensSystem, sensor_depth_mm: f64, distance_mm: f64) -> (f64, f64) {
    first_order_in(&system.paraxial().unwrap(), sensor_depth_mm, distance_mm)
}

/// [`first_order`] from one meridian's paraxial data.
fn first_order_in(p: &lenspath::lens::ParaxialData, sensor_depth_mm: f64, distance_mm: f64) -> (f64, f64) {
    let f = p.effective_focal_length_mm;
    let object = (sensor_depth_mm - distance_mm - p.front_principal_plane_z_mm).abs();
    let image = 1.0 / (1.0 / f - 1.0 / object);
    let image_z = p.rear_principal_plane_z_mm + image;
    let blur = p.exit_pupil_diameter_mm * (sensor_depth_mm - image_z).abs() / (image_z - p.exit_pupil_z_mm);
    (blur, image / object)
}

/// The source's own image is a uniform disc of diameter 2·r·m; second
/// moments of independent discs add, so the defocus disc is what remains.
fn defocus_diameter_mm(image: &Image, source_radius_mm: f64, magnification: f64) -> f64 {
    let measured = spot_diameter_mm(image, PITCH_MM);
    let source = 2.0 * source_radius_mm * magnification;
    (measured * measured - source * source).sqrt()
}

/// Sensor pixel pitch of the point shots.
const PITCH_MM: f64 = 0.03;

/// A source whose image is 2 pixels across wherever it is: large enough
/// that a fair share of the camera rays in its blur disc hit it.
fn source_radius_m(distance_m: f32) -> f32 {
    // m ≈ f / distance for f = 50 mm: radius = pitch · distance / f.
    (PITCH_MM / 50.0) as f32 * distance_m
}

/// Point shots render at the d line alone: first-order optics is for one
/// wavelength, and dgauss50's colour would add its own blur.
fn point_shot(f_number: Option<f64>) -> Shot<'static> {
    Shot {
        lens: "dgauss50",
        // A 2.88 mm crop of the sensor with 30 µm pixels.
        sensor_mm: (2.88, 2.88),
        pixels: (96, 96),
        focus: LensFocus::Distance(2.0),
        f_number,
        radiometry: Radiometry::Normalized,
        spp: 128,
        aperture: ApertureShape::Circle,
        wavelength_nm: Some(lenspath::spectrum::D_LINE_NM),
    }
}

/// A point at the focus distance (2 m) through `aperture` at f/4 puts over
/// 80% of its light within the 2×2 pixels around the image centre (60 µm square).
fn assert_in_focus_point_is_a_point(aperture: ApertureShape) {
    let shot = Shot {
        aperture,
        ..point_shot(Some(4.0))
    };
    let image = shoot(point_source(2.0, 0.0004), &shot);
    let total = block_mean(&image, 0..96, 0..96) * 96.0 * 96.0;
    let core = block_mean(&image, 47..49, 47..49) * 4.0;
    assert!(
        core > 0.8 * total,
        "{:?}: only {:.0}% of the light in the central 2x2 pixels",
        shot.aperture,
        100.0 * core / total
    );
}

#[test]
fn a_point_in_focus_images_into_about_a_pixel() {
    assert_in_focus_point_is_a_point(ApertureShape::Circle);
}

/// The blur of a point before and behind the focus against first-order
/// optics, within 12%: behind it (4 m) dgauss50 at f/4 blurs 9.5–11.2% more
/// than first order says (the spherical aberration first-order optics leaves
/// out), in front (1.2 m) 4–5% less (six seeds at 1024 spp; at 128 spp the
/// second moment's noise spread the first from 6% to 13%).
#[test]
fn defocus_blur_matches_first_order_optics() {
    let shot = Shot {
        spp: 1024,
        ..point_shot(Some(4.0))
    };
    let cam = camera(&shot);
    for distance_m in [1.2f32, 4.0] {
        let (predicted, magnification) = first_order(cam.system(), cam.sensor_depth_mm(), f64::from(distance_m) * 1e3);
        let radius = source_radius_m(distance_m);
        let image = shoot(point_source(distance_m, radius), &shot);
        let measured = defocus_diameter_mm(&image, f64::from(radius) * 1e3, magnification);
        assert!(
            (measured / predicted - 1.0).abs() < 0.12,
            "point at {distance_m} m: blur {measured:.4} mm, first-order optics {predicted:.4} mm"
        );
    }
}

#[test]
fn stopping_down_from_f2_to_f8_shrinks_the_blur_fourfold() {
    let (distance_m, radius) = (1.2, source_radius_m(1.2));
    let blur = |f_number| {
        let shot = point_shot(f_number);
        let cam = camera(&shot);
        let (_, magnification) = first_order(cam.system(), cam.sensor_depth_mm(), f64::from(distance_m) * 1e3);
        defocus_diameter_mm(
            &shoot(point_source(distance_m, radius), &shot),
            f64::from(radius) * 1e3,
            magnification,
        )
    };
    let (open, f8) = (blur(None), blur(Some(8.0)));
    assert!(
        (open / f8 / 4.0 - 1.0).abs() < 0.1,
        "blur wide open {open:.4} mm, at f/8 {f8:.4} mm"
    );
}

#[test]
fn most_generated_rays_get_through_at_the_centre() {
    for (lens, _) in BUILTIN_LENSES {
        for f_number in [None, Some(8.0)] {
            let system = LensSystem::new(&LensPrescription::load(lens).unwrap());
            let infinity = system.real_focus_at_infinity(0.1).unwrap().0;
            let cam = camera(&Shot {
                lens,
                sensor_mm: listed_sensor_mm(lens),
                pixels: (360, 240),
                focus: LensFocus::SensorDepthMm(infinity),
                f_number,
                radiometry: Radiometry::Normalized,
                spp: 1,
                aperture: ApertureShape::Circle,
                wavelength_nm: None,
            });
            let centre = cam.passing_fraction(Vec2::new(180.0, 120.0), 20_000);
            // 0.897 for werfel100 at f/8, the lowest.
            assert!(
                centre >= 0.88,
                "{lens} at {f_number:?}: {:.1}% pass at the centre",
                100.0 * centre
            );
        }
    }
}

/// Irradiance (unnormalised) at the film point (`x_mm`, `y_mm`) by brute
/// force: ∫ cos⁴θ dA over every point of a fine grid over 1.5× the rear
/// element that a traced ray gets through.
fn brute_force_irradiance(system: &LensSystem, sensor_depth_mm: f64, x_mm: f64, y_mm: f64) -> f64 {
    use glam::DVec3;
    use lenspath::lens::{Direction, LensRay};
    let film = DVec3::new(x_mm, y_mm, sensor_depth_mm);
    let reach = 1.5 * system.rear_aperture_radius_mm();
    let n = 500;
    let cell = 2.0 * reach / n as f64;
    let mut sum = 0.0;
    for i in 0..n {
        for j in 0..n {
            let q = DVec3::new(
                -reach + (j as f64 + 0.5) * cell,
                -reach + (i as f64 + 0.5) * cell,
                system.rear_z_mm(),
            );
            let ray = LensRay::between(film, q);
            if system.trace(&ray, Direction::ToScene).is_some() {
                sum += (-ray.direction.z).powi(4);
            }
        }
    }
    sum * cell * cell
}

/// The camera's estimate of the irradiance at raster point (`px`, `py`) at
/// `nm`: the mean weight of 200,000 generated rays.
fn sampled_irradiance(cam: &RealisticCamera, px: f32, py: f32, nm: f32) -> f64 {
    use lenspath::camera::{Camera, CameraSample};
    use lenspath::sampling::Rng;
    use lenspath::spectrum::SampledWavelengths;
    let mut rng = Rng::new(11);
    let n = 200_000;
    let sum: f64 = (0..n)
        .filter_map(|_| {
            cam.generate_ray(CameraSample {
                wavelengths: SampledWavelengths::single(nm),
                ..CameraSample::new(Vec2::new(px, py), Vec2::new(rng.uniform(), rng.uniform()))
            })
        })
        .map(|r| f64::from(r.weight))
        .sum();
    sum / f64::from(n)
}

/// The film point (lens coordinates, mm) of raster point (`px`, `py`) on a
/// `sensor_mm` sensor of `pixels`: image right and up are sensor −x and −y.
fn film_mm(px: f32, py: f32, pixels: (u32, u32), sensor_mm: (f64, f64)) -> (f64, f64) {
    (
        -(f64::from(px) / f64::from(pixels.0) - 0.5) * sensor_mm.0,
        -(0.5 - f64::from(py) / f64::from(pixels.1)) * sensor_mm.1,
    )
}

/// Irradiance across the field by brute force against the camera's
/// pupil-grid estimate: the grids must not lose light anywhere, or
/// vignetting would be wrong. Ratios to the centre, so the normalisation
/// cancels. dgauss50's glasses disperse, so it is checked at the ends of the
/// visible too: its grids bound the pupil at every wavelength, not only at
/// the d line.
#[test]
fn pupil_sampling_loses_no_light_across_the_field() {
    use lenspath::spectrum::D_LINE_NM;
    for (lens, wavelengths_nm) in [
        ("dgauss50", &[D_LINE_NM, 380.0, 800.0][..]),
        ("wide22", &[D_LINE_NM][..]),
    ] {
        let (w, h) = (360u32, 240u32);
        let cam = camera(&Shot {
            lens,
            sensor_mm: (36.0, 24.0),
            pixels: (w, h),
            focus: LensFocus::Distance(3.0),
            f_number: None,
            radiometry: Radiometry::Normalized,
            spp: 1,
            aperture: ApertureShape::Circle,
            wavelength_nm: None,
        });
        assert_eq!(cam.system().is_dispersive(), wavelengths_nm.len() > 1, "{lens}");
        for &nm in wavelengths_nm {
            let system = cam.system().at_wavelength(f64::from(nm));
            let sensor_depth_mm = cam.sensor_depth_mm();
            let centre_brute = brute_force_irradiance(&system, sensor_depth_mm, 0.0, 0.0);
            let centre_estimate = sampled_irradiance(&cam, 180.0, 120.0, nm);
            // Raster points from the centre toward the corner.
            for t in [0.23f32, 0.5, 0.71, 0.93] {
                let (px, py) = (180.0 * (1.0 + t), 120.0 * (1.0 - t));
                let (x_mm, y_mm) = film_mm(px, py, (w, h), (36.0, 24.0));
                let exact = brute_force_irradiance(&system, sensor_depth_mm, x_mm, y_mm) / centre_brute;
                let sampled = sampled_irradiance(&cam, px, py, nm) / centre_estimate;
                assert!(
                    (sampled / exact - 1.0).abs() < 0.01,
                    "{lens} at {nm} nm, {t} of the half diagonal: relative irradiance {sampled:.4}, brute force {exact:.4}"
                );
            }
        }
    }
}

/// The same for an anamorphic lens (lentil 2004 on the 22 × 18.6 mm frame
/// of 35 mm anamorphic film), whose pupil grids are kept for tiles of one
/// quadrant and mirrored into the others: points in every quadrant, on both
/// axes and near the corners, at the d line (its glasses are Abbe-number
/// models, and dispersion is covered above).
#[test]
fn pupil_sampling_loses_no_light_through_an_anamorphic_lens() {
    use lenspath::spectrum::D_LINE_NM;
    let (pixels, sensor_mm) = ((220u32, 186u32), (22.0, 18.6));
    let cam = camera(&Shot {
        pixels,
        ..anamorphic_shot(sensor_mm, LensFocus::Distance(3.0))
    });
    let system = cam.system().clone();
    let sensor_depth_mm = cam.sensor_depth_mm();
    let centre_brute = brute_force_irradiance(&system, sensor_depth_mm, 0.0, 0.0);
    let centre_estimate = sampled_irradiance(&cam, 110.0, 93.0, D_LINE_NM);
    for (px, py) in [
        (200.0f32, 93.0f32),
        (30.0, 93.0),
        (110.0, 10.0),
        (110.0, 170.0),
        (150.0, 60.0),
        (45.0, 40.0),
        (70.0, 150.0),
        (205.0, 178.0),
        (8.0, 5.0),
    ] {
        let (x_mm, y_mm) = film_mm(px, py, pixels, sensor_mm);
        let exact = brute_force_irradiance(&system, sensor_depth_mm, x_mm, y_mm) / centre_brute;
        let sampled = sampled_irradiance(&cam, px, py, D_LINE_NM) / centre_estimate;
        assert!(
            (sampled / exact - 1.0).abs() < 0.01,
            "lentil:2004 at ({x_mm:.2}, {y_mm:.2}) mm: relative irradiance {sampled:.4}, brute force {exact:.4}"
        );
    }
}

/// The same seed gives the same image bytes on one thread and on two,
/// through the lens too (rays are traced in pairs of pixels).
#[test]
fn the_image_through_a_lens_is_identical_for_any_thread_count() {
    let scene = || lenspath::builtin::builtin_scene("cornell-spheres", 0).unwrap();
    let view = scene().view.unwrap();
    let cam = RealisticCamera::new(
        view.pose,
        33,
        25,
        &RealisticCameraSettings::new(
            LensPrescription::load("dgauss50").unwrap(),
            (36.0, 36.0 * 25.0 / 33.0),
            LensFocus::Distance(f64::from(view.focus_distance)),
        ),
    )
    .unwrap();
    let compiled = scene().compile(&BvhSettings::default()).unwrap();
    let images: Vec<Image> = [1, 2]
        .map(|threads| {
            let settings = RenderSettings {
                width: 33,
                height: 25,
                spp: 6,
                threads: Some(threads),
                ..Default::default()
            };
            render(&compiled, &cam, &settings, &|_, _| {}, &AtomicBool::new(false))
                .unwrap()
                .image
        })
        .into();
    assert!(images[0].rgb.iter().any(|&v| v > 0.0));
    assert_eq!(images[0].rgb, images[1].rgb);
    assert_eq!(images[0].depth, images[1].depth);
}

/// A crop window renders exactly the pixels of the full image it covers,
/// through the lens (odd sizes and offsets, so pixel pairs straddle differently).
#[test]
fn a_crop_is_the_same_pixels_as_the_full_render() {
    use lenspath::render::PixelRect;
    let scene = lenspath::builtin::builtin_scene("cornell-spheres", 0).unwrap();
    let view = scene.view.unwrap();
    let (w, h) = (37u32, 29u32);
    let lens = RealisticCameraSettings::new(
        LensPrescription::load("dgauss50").unwrap(),
        (36.0, 36.0 * f64::from(h) / f64::from(w)),
        LensFocus::Distance(f64::from(view.focus_distance)),
    );
    let cam = RealisticCamera::new(view.pose, w, h, &lens).unwrap();
    let compiled = scene.compile(&BvhSettings::default()).unwrap();
    let run = |camera: &RealisticCamera, crop| {
        let settings = RenderSettings {
            width: w,
            height: h,
            spp: 5,
            crop,
            ..Default::default()
        };
        render(&compiled, camera, &settings, &|_, _| {}, &AtomicBool::new(false))
            .unwrap()
            .image
    };
    let full = run(&cam, None);
    let rect = PixelRect {
        x0: 7,
        y0: 11,
        width: 13,
        height: 9,
    };
    let part = run(&cam, Some(rect));
    assert_eq!((part.width, part.height), (13, 9));
    for y in 0..rect.height {
        for x in 0..rect.width {
            assert_eq!(
                part.pixel(x, y),
                full.pixel(rect.x0 + x, rect.y0 + y),
                "pixel ({x}, {y}) of the crop"
            );
        }
    }
    // A camera bounding only the region's pupil bands gives the same pixels.
    let patch_camera = RealisticCamera::for_region(view.pose, w, h, &lens, rect).unwrap();
    assert_eq!(run(&patch_camera, Some(rect)).rgb, part.rgb);
    let outside = RenderSettings {
        width: w,
        height: h,
        crop: Some(PixelRect { x0: 30, ..rect }),
        ..Default::default()
    };
    let err = outside.validate().unwrap_err().to_string();
    assert!(
        err.contains("crop 13x9 at (30, 11) is empty or leaves the 37x29 image"),
        "{err}"
    );
}

/// The pixels of `image` above half its bright level (the 90th percentile).
fn bright_pixels(image: &Image) -> Vec<(u32, u32)> {
    let mut values: Vec<f32> = image.rgb.chunks_exact(3).map(|p| p[1]).filter(|&v| v > 0.0).collect();
    values.sort_by(f32::total_cmp);
    let level = 0.5 * values[values.len() * 9 / 10];
    (0..image.height)
        .flat_map(|y| (0..image.width).map(move |x| (x, y)))
        .filter(|&(x, y)| image.pixel(x, y)[1] > level)
        .collect()
}

/// Intersection over union of the bright pixels with `aperture` scaled to
/// the same area, centroid on centroid, turned by 180° when `turned`.
fn iou_with_shape(bright: &[(u32, u32)], aperture: &Aperture, turned: bool) -> f64 {
    let n = bright.len() as f64;
    let centre = bright.iter().fold(glam::DVec2::ZERO, |c, &(x, y)| {
        c + glam::DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5) / n
    });
    // The shape's own centroid (unit-disk coordinates, y up), from a fine raster.
    let grid = 200;
    let raster = aperture.rasterize(grid, grid, 1.0);
    let (mut mass, mut shape_centre) = (0.0, glam::DVec2::ZERO);
    for (k, &v) in raster.iter().enumerate() {
        let p = glam::DVec2::new(
            -1.0 + 2.0 * ((k % grid) as f64 + 0.5) / grid as f64,
            1.0 - 2.0 * ((k / grid) as f64 + 0.5) / grid as f64,
        );
        mass += f64::from(v);
        shape_centre += p * f64::from(v);
    }
    shape_centre /= mass;
    let scale = (n / (std::f64::consts::PI * aperture.open_fraction())).sqrt();
    let sign = if turned { -1.0 } else { 1.0 };
    // Image rows run down, the shape's y up.
    let inside = |x: u32, y: u32| {
        let q = glam::DVec2::new(f64::from(x) + 0.5 - centre.x, centre.y - f64::from(y) - 0.5) / scale;
        aperture.transmission(q * sign + shape_centre) > 0.5
    };
    let size = 96;
    let mut union = 0;
    let mut intersection = 0;
    for y in 0..size {
        for x in 0..size {
            let (a, b) = (bright.contains(&(x, y)), inside(x, y));
            union += u32::from(a || b);
            intersection += u32::from(a && b);
        }
    }
    f64::from(intersection) / f64::from(union)
}

/// An L-shaped mask image: a bar down the left and a foot along the bottom.
fn l_mask() -> ApertureShape {
    let n = 64;
    let values = (0..n * n)
        .map(|k| {
            let (x, y) = ((k % n) as f64 / n as f64, (k / n) as f64 / n as f64);
            if (0.25..0.5).contains(&x) && (0.15..0.85).contains(&y)
                || (0.25..0.8).contains(&x) && (0.6..0.85).contains(&y)
            {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    ApertureShape::Mask(std::sync::Arc::new(ApertureMask::new(n, n, values).unwrap()))
}

/// An out-of-focus point images as the aperture's shape: beyond the focus
/// plane as the shape lies in the stop, nearer than it turned by 180°.
#[test]
fn an_out_of_focus_point_images_as_the_aperture_shape() {
    for (text, shape) in [
        ("blades:3", ApertureShape::parse("blades:3").unwrap()),
        ("star:5:0.45:0", ApertureShape::parse("star:5:0.45:0").unwrap()),
        ("an L-shaped mask", l_mask()),
    ] {
        let aperture = Aperture::new(&shape).unwrap();
        for (distance_m, turned) in [(1.0f32, true), (20.0, false)] {
            let shot = Shot {
                pixels: (96, 96),
                sensor_mm: (1.92, 1.92),
                f_number: None,
                spp: 1024,
                aperture: shape.clone(),
                ..point_shot(None)
            };
            let image = shoot(point_source(distance_m, source_radius_m(distance_m)), &shot);
            let bright = bright_pixels(&image);
            assert!(
                bright.len() > 100,
                "{text} at {distance_m} m: a spot of {} pixels",
                bright.len()
            );
            let (right, wrong) = (
                iou_with_shape(&bright, &aperture, turned),
                iou_with_shape(&bright, &aperture, !turned),
            );
            assert!(
                right >= 0.9 && wrong < 0.8,
                "{text} at {distance_m} m: IoU {right:.3} with the shape as expected, {wrong:.3} turned the other way"
            );
        }
    }
}

#[test]
fn an_in_focus_point_stays_a_point_through_a_shaped_aperture() {
    assert_in_focus_point_is_a_point(ApertureShape::parse("blades:5:0:0.3").unwrap());
}

/// A mask whose left half is open.
fn half_open_mask() -> ApertureShape {
    let values = (0..128 * 128).map(|k| if k % 128 < 64 { 1.0 } else { 0.0 }).collect();
    ApertureShape::Mask(std::sync::Arc::new(ApertureMask::new(128, 128, values).unwrap()))
}

/// Light follows the open area, through the real lens and the thin lens:
/// half a mask gives half the light, a hexagon 3√3/(2π) of the circle's.
#[test]
fn light_through_a_shaped_aperture_follows_its_open_area() {
    for (shape, expected) in [
        (half_open_mask(), 0.5),
        (
            ApertureShape::parse("blades:6").unwrap(),
            3.0 * 3f64.sqrt() / (2.0 * std::f64::consts::PI),
        ),
    ] {
        let shot = Shot {
            lens: "dgauss50",
            sensor_mm: (0.36, 0.24),
            pixels: (6, 4),
            focus: LensFocus::Distance(5.0),
            f_number: Some(4.0),
            radiometry: Radiometry::Normalized,
            spp: 1024,
            aperture: shape.clone(),
            wavelength_nm: None,
        };
        let through_lens = shoot(uniform_environment(), &shot).mean()[1];
        let thin =
            PerspectiveCamera::thin_lens(CameraPose::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y), 30.0, 6, 4, 0.1, 3.0)
                .with_aperture(std::sync::Arc::new(Aperture::new(&shape).unwrap()));
        let settings = RenderSettings {
            width: 6,
            height: 4,
            spp: 1024,
            integrator: Integrator::path(1, 1),
            seed: 3,
            ..RenderSettings::default()
        };
        let compiled = uniform_environment().compile(&BvhSettings::default()).unwrap();
        let thin_lens = render(&compiled, &thin, &settings, &|_, _| {}, &AtomicBool::new(false))
            .unwrap()
            .image
            .mean()[1];
        for (camera, reading) in [("realistic", through_lens), ("thin lens", thin_lens)] {
            assert!(
                (reading / expected - 1.0).abs() < 0.02,
                "{shape:?} through the {camera} camera: {reading:.4}, open area {expected:.4}"
            );
        }
    }
}

/// Shaped apertures are sampled at the stop, not by rejection: with a
/// mask open over 4% of the stop, as many rays get through as wide open
/// but for the pupil-grid share.
#[test]
fn a_small_opening_costs_no_rejected_rays() {
    let n = 128;
    let values = (0..n * n)
        .map(|k| {
            let (x, y) = ((k % n) as f64 / n as f64 - 0.5, (k / n) as f64 / n as f64 - 0.5);
            if x.hypot(y) < 0.1 {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    let mask = ApertureShape::Mask(std::sync::Arc::new(ApertureMask::new(n, n, values).unwrap()));
    let cam = camera(&Shot {
        pixels: (360, 240),
        sensor_mm: (36.0, 24.0),
        aperture: mask,
        ..point_shot(None)
    });
    let passing = cam.passing_fraction(Vec2::new(180.0, 120.0), 20_000);
    assert!(passing >= 0.85, "{:.1}% of the rays pass", 100.0 * passing);
}

/// Second moments ⟨x²⟩, ⟨y²⟩ of an image's brightness about its centroid,
/// for pixels `pitch` wide and high.
fn second_moments(image: &Image, pitch: (f64, f64)) -> (f64, f64) {
    let (mut sum, mut first, mut second) = (0.0, [0.0; 2], [0.0; 2]);
    for y in 0..image.height {
        for x in 0..image.width {
            let v = f64::from(image.pixel(x, y)[1]);
            let p = [(f64::from(x) + 0.5) * pitch.0, (f64::from(y) + 0.5) * pitch.1];
            sum += v;
            for k in 0..2 {
                first[k] += v * p[k];
                second[k] += v * p[k] * p[k];
            }
        }
    }
    let moment = |k: usize| second[k] / sum - (first[k] / sum).powi(2);
    (moment(0), moment(1))
}

/// An anamorphic lens (lentil 2004, US 6,310,731: 31.5 mm across the
/// sensor's width, 60.6 mm across its height) on a 3 mm square of its
/// sensor, 100 × 100 pixels, at the d line.
fn anamorphic_shot(sensor_mm: (f64, f64), focus: LensFocus) -> Shot<'static> {
    Shot {
        lens: "lentil:2004",
        sensor_mm,
        pixels: (100, 100),
        focus,
        f_number: None,
        radiometry: Radiometry::Normalized,
        spp: 64,
        aperture: ApertureShape::Circle,
        wavelength_nm: Some(lenspath::spectrum::D_LINE_NM),
    }
}

/// What an anamorphic lens does to an image, against first-order optics in
/// each meridian. A disc in focus (f/5.6) images as an ellipse whose height
/// over width is the squeeze (f_v / f_h), within 2% (measured 0.4%), and
/// round once desqueezed (the same pixels over a sensor the squeeze times
/// taller). An out-of-focus point (f/4, focused at infinity) blurs into an
/// ellipse whose axes are each meridian's first-order blur disc (about
/// f · D_ep · |1/d − 1/d_focus|): on the sensor 3.6 times as tall as wide,
/// desqueezed 1.9 times, the anamorphic's oval bokeh; within 5% (measured
/// 2.2% and 0.4%; wide open, aberrations shrink the blur by 8–14%).
#[test]
fn an_anamorphic_lens_squeezes_the_image_and_its_bokeh_is_oval() {
    use lenspath::lens::Meridian;
    let system = LensSystem::new(&LensPrescription::load("lentil:2004").unwrap());
    let squeeze = system.squeeze().unwrap();
    assert!((squeeze - 1.923).abs() < 1e-3, "{squeeze}");
    // Height over width of a uniform ellipse in the image (pixels), from
    // second moments, with a source's own image (an ellipse of these
    // semi-axes on the sensor, mm) taken out.
    let aspect = |image: &Image, sensor_mm: (f64, f64), source_mm: (f64, f64)| {
        let (xx, yy) = second_moments(image, (1.0, 1.0));
        let source_px = (source_mm.0 / (sensor_mm.0 / 100.0), source_mm.1 / (sensor_mm.1 / 100.0));
        ((yy - source_px.1 * source_px.1 / 4.0) / (xx - source_px.0 * source_px.0 / 4.0)).sqrt()
    };
    // A disc 0.5 m across, 20 m away, in focus at f/5.6 (wide open, the
    // aberrations' blur would round it by a few per cent).
    let (distance_m, radius_m) = (20.0f32, 0.25f32);
    for (sensor_mm, expected) in [((3.0, 3.0), squeeze), ((3.0, 3.0 * squeeze), 1.0)] {
        let shot = Shot {
            f_number: Some(5.6),
            ..anamorphic_shot(sensor_mm, LensFocus::Distance(f64::from(distance_m)))
        };
        let measured = aspect(&shoot(point_source(distance_m, radius_m), &shot), sensor_mm, (0.0, 0.0));
        assert!(
            (measured / expected - 1.0).abs() < 0.02,
            "disc in focus on a {sensor_mm:?} mm sensor: height over width {measured:.4}, expected {expected:.4}"
        );
    }
    // A small source 1.5 m away with the lens focused at infinity.
    let (distance_m, radius_m) = (1.5f32, 0.004f32);
    let infinity = system.infinity_focus_z_mm(0.1).unwrap();
    let [h, v] = Meridian::BOTH.map(|m| system.with_f_number(4.0).unwrap().paraxial_in(m).unwrap());
    let distance_mm = f64::from(distance_m) * 1e3;
    let ((blur_h, magnification_h), (blur_v, magnification_v)) = (
        first_order_in(&h, infinity, distance_mm),
        first_order_in(&v, infinity, distance_mm),
    );
    let source_mm = (
        f64::from(radius_m) * 1e3 * magnification_h,
        f64::from(radius_m) * 1e3 * magnification_v,
    );
    let on_sensor = blur_v / blur_h;
    for (sensor_mm, expected) in [((3.0, 3.0), on_sensor), ((3.0, 3.0 * squeeze), on_sensor / squeeze)] {
        let shot = Shot {
            f_number: Some(4.0),
            spp: 256,
            ..anamorphic_shot(sensor_mm, LensFocus::SensorDepthMm(infinity))
        };
        let image = shoot(point_source(distance_m, radius_m), &shot);
        let measured = aspect(&image, sensor_mm, source_mm);
        assert!(
            (measured / expected - 1.0).abs() < 0.05,
            "bokeh on a {sensor_mm:?} mm sensor: height over width {measured:.4}, first-order optics {expected:.4}"
        );
    }
}
