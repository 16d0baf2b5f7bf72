//! Diffraction in the render against the Airy pattern: a distant point
//! through a stopped-down singlet (near the diffraction limit at f/32)
//! images to the Airy disc, its first dark ring at 1.22 λN holding 83.8 %
//! of the light; the weights of a sample's other wavelengths stay unbiased;
//! the image is the same for any thread count.

use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;

use glam::Vec3;
use lenspath::accel::BvhSettings;
use lenspath::camera::{CameraPose, LensFocus, RealisticCamera, RealisticCameraSettings};
use lenspath::film::{Filter, Image};
use lenspath::integrator::Integrator;
use lenspath::lens::{LensPrescription, LensSystem, TableConvention};
use lenspath::lights::Light;
use lenspath::math::Rgb;
use lenspath::render::{render, FilmResponse, RenderSettings};
use lenspath::scene::{CompiledScene, Scene};

/// An f = 100 mm biconvex singlet of a glass that does not disperse (one focus for every wavelength).
const SINGLET: &str = "0 2 0 6.25\n103.36 4 1.5168 20\n-103.36 95 1 20\n";
const F_NUMBER: f64 = 32.0;
const WAVELENGTH_NM: f64 = 550.0;
/// Pixels across the square sensor crop, 1 µm each: ±2.2 first-ring radii.
const PIXELS: u32 = 96;

/// An emitting disc 2 µm in radius on the sensor: a sphere of 2 cm 1 km away.
fn distant_point() -> CompiledScene {
    crate::chromatic_images::distant_disc(0.0, 0.02)
}

fn singlet_camera(diffraction: bool, pixels: u32) -> RealisticCamera {
    let lens = LensPrescription::parse(SINGLET, "singlet", TableConvention::ThicknessToNext).unwrap();
    let focus = LensSystem::new(&lens)
        .with_f_number(F_NUMBER)
        .unwrap()
        .paraxial()
        .unwrap()
        .rear_focal_point_z_mm;
    let sensor_mm = f64::from(pixels) * 1e-3;
    let settings = RealisticCameraSettings {
        f_number: Some(F_NUMBER),
        diffraction,
        ..RealisticCameraSettings::new(lens, (sensor_mm, sensor_mm), LensFocus::SensorDepthMm(focus))
    };
    RealisticCamera::new(
        CameraPose::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y),
        pixels,
        pixels,
        &settings,
    )
    .unwrap()
}

fn shoot(
    scene: &CompiledScene,
    camera: &RealisticCamera,
    pixels: u32,
    spp: u32,
    film: FilmResponse,
    threads: usize,
) -> Image {
    let settings = RenderSettings {
        width: pixels,
        height: pixels,
        spp,
        integrator: Integrator::path(1, 1),
        seed: 5,
        filter: Filter::Box,
        depth: false,
        film,
        threads: Some(threads),
        ..Default::default()
    };
    render(scene, camera, &settings, &|_, _| {}, &AtomicBool::new(false))
        .unwrap()
        .image
}

/// Bessel function of the first kind, J_n(x) = (1/π) ∫₀^π cos(nτ − x sin τ) dτ (DLMF 10.9.2).
fn bessel_j(n: f64, x: f64) -> f64 {
    let steps = 4000;
    (0..steps)
        .map(|k| {
            let t = PI * (f64::from(k) + 0.5) / f64::from(steps);
            (n * t - x * t.sin()).cos()
        })
        .sum::<f64>()
        / f64::from(steps)
}

/// The Airy pattern's energy within v = π r / (λN): 1 − J₀(v)² − J₁(v)² (Born & Wolf §8.5.2).
fn airy_encircled_energy(v: f64) -> f64 {
    1.0 - bessel_j(0.0, v).powi(2) - bessel_j(1.0, v).powi(2)
}

/// The image's sum within `radius_um` of its centre, and its mean per 1 µm ring out to `rings`.
fn radial(image: &Image, radius_um: f64, rings: usize) -> (f64, Vec<f64>) {
    let centre = f64::from(image.width) / 2.0;
    let (mut inside, mut sums, mut counts) = (0.0, vec![0.0; rings], vec![0usize; rings]);
    for y in 0..image.height {
        for x in 0..image.width {
            let r = (f64::from(x) + 0.5 - centre).hypot(f64::from(y) + 0.5 - centre);
            let v = f64::from(image.pixel(x, y)[0]);
            if r < radius_um {
                inside += v;
            }
            if (r as usize) < rings {
                sums[r as usize] += v;
                counts[r as usize] += 1;
            }
        }
    }
    (
        inside,
        sums.iter().zip(counts).map(|(s, c)| s / c.max(1) as f64).collect(),
    )
}

#[test]
fn a_point_through_a_diffraction_limited_lens_images_to_the_airy_disc() {
    let scene = distant_point();
    let camera = singlet_camera(true, PIXELS);
    let working = camera.diffraction().unwrap().working_f_number();
    assert!((working / F_NUMBER - 1.0).abs() < 0.01, "working f-number {working}");
    let image = shoot(
        &scene,
        &camera,
        PIXELS,
        2048,
        FilmResponse::radiance(Some(WAVELENGTH_NM as f32)),
        2,
    );
    let lambda_n_um = WAVELENGTH_NM * 1e-3 * working;
    let first_zero_um = 1.2197 * lambda_n_um;
    let outer_um = 45.0;
    let (at_zero, profile) = radial(&image, first_zero_um, 40);
    let (within_outer, _) = radial(&image, outer_um, 0);
    // Energy at the first zero over that within 45 µm, as the Airy pattern has it.
    let expected = airy_encircled_energy(PI * 1.2197) / airy_encircled_energy(PI * outer_um / lambda_n_um);
    let measured = at_zero / within_outer;
    assert!(
        (measured - expected).abs() < 0.01,
        "encircled energy {measured}, Airy {expected}"
    );
    // The first dark ring: the parabola through the darkest 1 µm ring near 1.22 λN and its two
    // neighbours (a wider fit leans outward: the Airy profile rises faster toward its centre).
    let darkest = (first_zero_um as usize - 3..=first_zero_um as usize + 3)
        .min_by(|&a, &b| profile[a].total_cmp(&profile[b]))
        .unwrap();
    let [before, at, after] = [darkest - 1, darkest, darkest + 1].map(|k| profile[k]);
    let zero_um = darkest as f64 + 0.5 + 0.5 * (before - after) / (before - 2.0 * at + after);
    eprintln!(
        "encircled energy {measured:.4} (Airy {expected:.4}); first zero {zero_um:.3} µm (Airy {first_zero_um:.3})"
    );
    assert!(
        (zero_um / first_zero_um - 1.0).abs() < 0.02,
        "first zero at {zero_um} µm, Airy {first_zero_um} µm"
    );
    // The first bright ring (1.635 λN, 1.75 % of the peak) stands out of the dark one.
    let ring = profile[(1.635 * lambda_n_um) as usize];
    assert!(
        ring > 3.0 * profile[first_zero_um as usize],
        "ring {ring}, zero {}",
        profile[first_zero_um as usize]
    );
    assert!(ring < 0.05 * profile[0], "ring {ring}, peak {}", profile[0]);
    // Without diffraction the lens's geometric image is all inside the Airy disc.
    let geometric = shoot(
        &scene,
        &singlet_camera(false, PIXELS),
        PIXELS,
        256,
        FilmResponse::radiance(Some(550.0)),
        2,
    );
    let (sharp, _) = radial(&geometric, 0.3 * first_zero_um, 0);
    let (all, _) = radial(&geometric, outer_um, 0);
    assert!(sharp / all > 0.99, "geometric image {}", sharp / all);
    // Diffraction moves light and keeps it: the same total within 45 µm, over the Airy share there.
    let ratio = within_outer / (all * airy_encircled_energy(PI * outer_um / lambda_n_um));
    eprintln!(
        "geometric image within 0.3 of the first zero {:.4}; energy ratio {ratio:.4}",
        sharp / all
    );
    assert!((ratio - 1.0).abs() < 0.03, "energy ratio {ratio}");
}

/// Under a uniform sky the image is uniform whatever spreads it: with the
/// pupil diffracting, every wavelength's weight (the hero's and the others',
/// through a lens that disperses and one that does not) leaves its colour
/// as it was.
#[test]
fn diffraction_keeps_the_colour_of_a_uniform_sky() {
    let sky = Scene {
        lights: vec![Light::Environment {
            radiance: Rgb::new(0.9, 0.6, 0.3).into(),
        }],
        ..Default::default()
    }
    .compile(&BvhSettings::default())
    .unwrap();
    for dispersion in [true, false] {
        let mean = |diffraction: bool| {
            let settings = RealisticCameraSettings {
                f_number: Some(8.0),
                dispersion,
                diffraction,
                ..RealisticCameraSettings::new(
                    LensPrescription::load("dgauss50").unwrap(),
                    (0.064, 0.064),
                    LensFocus::Distance(5.0),
                )
            };
            let camera =
                RealisticCamera::new(CameraPose::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y), 32, 32, &settings).unwrap();
            let image = shoot(&sky, &camera, 32, 64, FilmResponse::Srgb, 2);
            image.mean()
        };
        let (plain, diffracted) = (mean(false), mean(true));
        eprintln!("dispersion {dispersion}: sRGB means {plain:.4?} without, {diffracted:.4?} with diffraction");
        for channel in 0..3 {
            let change = diffracted[channel] / plain[channel] - 1.0;
            assert!(
                change.abs() < 0.01,
                "dispersion {dispersion}: channel {channel} {plain:?} → {diffracted:?}"
            );
        }
    }
}

#[test]
fn a_diffracting_render_is_the_same_for_any_thread_count() {
    let scene = distant_point();
    let camera = singlet_camera(true, 32);
    let film = FilmResponse::radiance(Some(500.0));
    let one = shoot(&scene, &camera, 32, 64, film, 1);
    let two = shoot(&scene, &camera, 32, 64, film, 2);
    assert!(one.rgb == two.rgb, "thread counts differ");
    assert!(one.rgb.iter().any(|&v| v > 0.0));
}
