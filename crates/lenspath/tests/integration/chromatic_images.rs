//! Colour in rendered images against the lens analysis, through a singlet
//! whose glass disperses: a distant point rendered at the F and C lines
//! comes to its sharpest focus at sensor positions as far apart as the
//! paraxial longitudinal colour `BFD(F) − BFD(C)` says, and off the axis its
//! F and C images lie as far apart as the lateral colour says; an achromat
//! of the same focal length blurs colour less by the factor the analysis
//! gives.

use std::sync::atomic::AtomicBool;

use glam::{DMat3, DVec3, Vec3};
use lenspath::accel::BvhSettings;
use lenspath::camera::{CameraPose, LensFocus, RealisticCamera, RealisticCameraSettings};
use lenspath::film::{Filter, Image, PixelRect};
use lenspath::glass::{C_LINE_NM, D_LINE_NM, F_LINE_NM, G_LINE_NM};
use lenspath::integrator::Integrator;
use lenspath::lens::chromatic::ChromaticAnalysis;
use lenspath::lens::{LensPrescription, LensSystem, TableConvention};
use lenspath::materials::Material;
use lenspath::math::Rgb;
use lenspath::render::{render, FilmResponse, RenderSettings};
use lenspath::scene::{CompiledScene, Scene};
use lenspath::shapes::Sphere;

/// An f = 100 mm biconvex N-BK7 singlet behind a 6.25 mm stop (f/16): its
/// longitudinal colour is about −f / V_d = −1.56 mm.
const SINGLET: &str = "0 2 0 6.25\n103.36 4 1.5168 20 N-BK7\n-103.36 95 1 20\n";

/// Sensor crop (mm) and pixels: 10 µm pixels, wide enough for the blur
/// circle 1.5 mm from focus at f/16.
const SENSOR_MM: f64 = 1.28;
const PIXELS: u32 = 128;

/// An emitting sphere of `radius` metres 1 km away, `x` metres off the
/// axis: its image is a disc `radius` / 5 mm across through an f = 100 mm
/// lens, and its focus is the infinity focus within 0.01 mm. A disc's image
/// moves neither the centroid nor the best focus of the lens's blur (it adds
/// a constant to the second moment); a larger one is hit by more camera rays.
pub(crate) fn distant_disc(x: f32, radius: f32) -> CompiledScene {
    Scene {
        spheres: vec![Sphere {
            center: Vec3::new(x, 0.0, 1000.0),
            radius,
            material: 0,
            emission: Some(Rgb::ONE.into()),
        }],
        materials: vec![Material::Diffuse { reflectance: Rgb::ZERO }],
        ..Default::default()
    }
    .compile(&BvhSettings::default())
    .unwrap()
}

/// Where and how a shot is taken.
struct Shot {
    /// Sensor width and height, mm (square).
    sensor_mm: f64,
    /// Pixels across (square).
    pixels: u32,
    /// The rectangle of pixels rendered (`None`: all).
    crop: Option<PixelRect>,
    /// Whether the lens's glasses disperse.
    dispersion: bool,
}

/// The on-axis shots: the sensor crop ([`SENSOR_MM`], [`PIXELS`]) whole.
const AXIAL: Shot = Shot {
    sensor_mm: SENSOR_MM,
    pixels: PIXELS,
    crop: None,
    dispersion: true,
};

/// The image at `wavelength_nm` with the sensor `sensor_depth_mm` behind the stop.
fn shoot(
    scene: &CompiledScene,
    lens: &LensPrescription,
    sensor_depth_mm: f64,
    wavelength_nm: f64,
    shot: &Shot,
) -> Image {
    let pose = CameraPose::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y);
    let camera_settings = RealisticCameraSettings {
        dispersion: shot.dispersion,
        ..RealisticCameraSettings::new(
            lens.clone(),
            (shot.sensor_mm, shot.sensor_mm),
            LensFocus::SensorDepthMm(sensor_depth_mm),
        )
    };
    let camera = match shot.crop {
        None => RealisticCamera::new(pose, shot.pixels, shot.pixels, &camera_settings),
        Some(region) => RealisticCamera::for_region(pose, shot.pixels, shot.pixels, &camera_settings, region),
    }
    .unwrap();
    let settings = RenderSettings {
        width: shot.pixels,
        height: shot.pixels,
        spp: 64,
        integrator: Integrator::path(1, 1),
        seed: 3,
        filter: Filter::Box,
        crop: shot.crop,
        depth: false,
        film: FilmResponse::radiance(Some(wavelength_nm as f32)),
        ..Default::default()
    };
    render(scene, &camera, &settings, &|_, _| {}, &AtomicBool::new(false))
        .unwrap()
        .image
}

/// The image's light-weighted centroid, pixels from its top-left corner.
fn centroid_px(image: &Image) -> (f64, f64) {
    let (mut sum, mut first) = (0.0, [0.0; 2]);
    for y in 0..image.height {
        for x in 0..image.width {
            let v = f64::from(image.pixel(x, y)[0]);
            sum += v;
            first[0] += v * (f64::from(x) + 0.5);
            first[1] += v * (f64::from(y) + 0.5);
        }
    }
    (first[0] / sum, first[1] / sum)
}

/// Mean squared distance of the image's light from its centroid, mm².
fn second_moment_mm2(image: &Image) -> f64 {
    let pitch = SENSOR_MM / f64::from(PIXELS);
    let (cx, cy) = centroid_px(image);
    let (mut sum, mut second) = (0.0, 0.0);
    for y in 0..image.height {
        for x in 0..image.width {
            let v = f64::from(image.pixel(x, y)[0]);
            sum += v;
            second += v * ((f64::from(x) + 0.5 - cx).powi(2) + (f64::from(y) + 0.5 - cy).powi(2));
        }
    }
    second / sum * pitch * pitch
}

/// The sensor position of the sharpest image and how fast the spot grows
/// away from it: every ray's place on the sensor moves linearly with the
/// sensor's position, so the spot's second moment is a parabola
/// `a + c (z − vertex)²` in it; fitted by least squares, `(vertex, c)`.
fn sharpest_focus_mm(scene: &CompiledScene, lens: &LensPrescription, around_mm: f64, wavelength_nm: f64) -> (f64, f64) {
    let offsets: Vec<f64> = (-4..=4).map(|k| f64::from(k) * 0.35).collect();
    // Normal equations for m(z) = a + b t + c t², t = z − around.
    let (mut normal, mut rhs) = (DMat3::ZERO, DVec3::ZERO);
    for &t in &offsets {
        let m = second_moment_mm2(&shoot(scene, lens, around_mm + t, wavelength_nm, &AXIAL));
        let basis = DVec3::new(1.0, t, t * t);
        normal += DMat3::from_cols(basis * basis.x, basis * basis.y, basis * basis.z);
        rhs += basis * m;
    }
    let DVec3 { y: b, z: c, .. } = normal.inverse() * rhs;
    assert!(c > 0.0, "the spot does not shrink toward a focus at {wavelength_nm} nm");
    (around_mm - b / (2.0 * c), c)
}

/// Longitudinal colour, rendered: the F and C images of a distant point
/// are sharpest at sensor positions whose difference is the analysis's
/// `longitudinal_color_mm` within 10%.
#[test]
fn rendered_longitudinal_colour_matches_the_analysis() {
    let lens = LensPrescription::parse(SINGLET, "singlet", TableConvention::ThicknessToNext).unwrap();
    let system = LensSystem::new(&lens);
    let predicted = ChromaticAnalysis::new(&system, 1.0).unwrap().longitudinal_color_mm;
    assert!(predicted < -1.0, "an uncorrected singlet: {predicted} mm");
    let around = system.real_focus_at_infinity(0.1).unwrap().0;
    let scene = distant_disc(0.0, 0.5);
    let (f, _) = sharpest_focus_mm(&scene, &lens, around, F_LINE_NM);
    let (c, _) = sharpest_focus_mm(&scene, &lens, around, C_LINE_NM);
    let measured = f - c;
    eprintln!("longitudinal colour: rendered {measured:.4} mm, analysis {predicted:.4} mm");
    assert!(
        (measured / predicted - 1.0).abs() < 0.1,
        "sharpest F image at {f:.4} mm, C at {c:.4} mm: {measured:.4} mm apart; analysis {predicted:.4} mm"
    );
}

/// A cemented N-BK7/SF5 achromat (the doublet `lens::chromatic`'s tests
/// check against rayoptics, scaled to f = 100 mm) behind the singlet's
/// f/16 stop: its F and C lines focus together, and what is left is the
/// secondary spectrum, largest at the blue end.
const ACHROMAT: &str = "0 2 0 6.25\n61.53 4.030 1.5168 25 N-BK7\n-44.503 2.519 1.6727 25 SF5\n-129.86 95 1 25\n";

/// Colour blur, rendered: with the sensor where the d line focuses, the g
/// line's (blue) image is blurred by its focus shift; its RMS radius grows
/// by `√c · |z_g − z_d|` (the parabola's curvature `c` times the measured
/// shift). The singlet's colour blur is larger than the achromat's by the
/// ratio of their paraxial shifts `BFD(g) − BFD(d)` (same focal length and
/// f-number, so the same cone of rays), within 10%.
#[test]
fn an_achromat_blurs_colour_less_than_a_singlet_by_the_analysis_factor() {
    let scene = distant_disc(0.0, 0.5);
    let colour_blur = |table: &str| {
        let lens = LensPrescription::parse(table, "lens", TableConvention::ThicknessToNext).unwrap();
        let system = LensSystem::new(&lens);
        let chromatic = ChromaticAnalysis::new(&system, 1.0).unwrap();
        let line = |name: &str| chromatic.lines.iter().find(|l| l.line == name).unwrap();
        assert!(
            (line("d").effective_focal_length_mm / 100.0 - 1.0).abs() < 0.01,
            "{chromatic:?}"
        );
        let predicted_shift = line("g").back_focal_distance_mm - line("d").back_focal_distance_mm;
        let focus = |nm: f64| {
            let around = system.at_wavelength(nm).real_focus_at_infinity(0.1).unwrap().0;
            sharpest_focus_mm(&scene, &lens, around, nm)
        };
        let ((g, curvature), (d, _)) = (focus(G_LINE_NM), focus(D_LINE_NM));
        (curvature.sqrt() * (g - d).abs(), g - d, predicted_shift)
    };
    let (singlet, singlet_shift, singlet_predicted) = colour_blur(SINGLET);
    let (achromat, achromat_shift, achromat_predicted) = colour_blur(ACHROMAT);
    let (measured, predicted) = (singlet / achromat, singlet_predicted / achromat_predicted);
    eprintln!(
        "g-line blur at the d focus: singlet {:.2} µm (shift {singlet_shift:.4} mm, paraxial {singlet_predicted:.4}), \
         achromat {:.2} µm (shift {achromat_shift:.4} mm, paraxial {achromat_predicted:.4}); ratio {measured:.3}, analysis {predicted:.3}",
        singlet * 1e3,
        achromat * 1e3
    );
    assert!(predicted.abs() > 5.0, "the achromat corrects colour: {predicted}");
    assert!(
        (measured / predicted.abs() - 1.0).abs() < 0.1,
        "colour blur ratio {measured:.3}, analysis {predicted:.3}"
    );
}

/// A monochromatic render through a lens without dispersion has the same
/// shape at any wavelength (only the source's brightness depends on it);
/// through the dispersive singlet, the F and C spots differ in size, unless
/// the camera's dispersion is switched off.
#[test]
fn monochromatic_renders_depend_on_the_wavelength_through_the_glass() {
    let scene = distant_disc(0.0, 0.5);
    let dispersive = LensPrescription::parse(SINGLET, "singlet", TableConvention::ThicknessToNext).unwrap();
    let plain_table = SINGLET.replace(" N-BK7", "");
    let plain = LensPrescription::parse(&plain_table, "plain", TableConvention::ThicknessToNext).unwrap();
    let z = LensSystem::new(&plain).real_focus_at_infinity(0.1).unwrap().0 + 0.5;
    let size = |lens: &LensPrescription, nm: f64| second_moment_mm2(&shoot(&scene, lens, z, nm, &AXIAL));
    let (blue, red) = (size(&plain, F_LINE_NM), size(&plain, C_LINE_NM));
    assert!((blue / red - 1.0).abs() < 1e-4, "plain lens: {blue} vs {red} mm²");
    let (blue, red) = (size(&dispersive, F_LINE_NM), size(&dispersive, C_LINE_NM));
    assert!(
        blue > 1.5 * red,
        "behind focus the F spot is the larger: {blue} vs {red} mm²"
    ); // With dispersion off the same lens has every glass at its d-line index: no colour.
    let off = Shot {
        dispersion: false,
        ..AXIAL
    };
    let size_off = |nm: f64| second_moment_mm2(&shoot(&scene, &dispersive, z, nm, &off));
    let (blue, red) = (size_off(F_LINE_NM), size_off(C_LINE_NM));
    assert!((blue / red - 1.0).abs() < 1e-4, "dispersion off: {blue} vs {red} mm²");
}

/// The singlet with its stop 20 mm in front: off the axis the chief ray
/// crosses the glass away from its centre, so each colour is magnified
/// differently (lateral colour about −h / V_d at image height h).
const SINGLET_STOP_IN_FRONT: &str = "0 20 0 12.5\n103.36 4 1.5168 40 N-BK7\n-103.36 95 1 40\n";

/// Lateral colour, rendered: a distant point whose d-line image is 10 mm
/// off the axis images at the F and C lines, on the d line's image plane,
/// with centroids as far apart radially as the analysis's
/// `lateral_color_mm` within 10%.
#[test]
fn rendered_lateral_colour_matches_the_analysis() {
    let lens = LensPrescription::parse(SINGLET_STOP_IN_FRONT, "singlet", TableConvention::ThicknessToNext).unwrap();
    let system = LensSystem::new(&lens);
    let field_height_mm = 10.0;
    let chromatic = ChromaticAnalysis::new(&system, field_height_mm).unwrap();
    let d = chromatic.lines.iter().find(|l| l.line == "d").unwrap();
    let image_z = system.rear_z_mm() + d.back_focal_distance_mm;
    // The object on the camera's +x side (scene −X: the camera's right is
    // forward × up), at the field angle whose d-line image height is 10 mm.
    let tan_field = field_height_mm / d.effective_focal_length_mm;
    let scene = distant_disc(-1000.0 * tan_field as f32, 1.0);
    // A 24 mm sensor of 5 µm pixels, rendered only around the image.
    let (sensor_mm, pixels) = (24.0, 4800u32);
    let pitch = sensor_mm / f64::from(pixels);
    let centre_px = f64::from(pixels) / 2.0;
    let expected_column = (centre_px + field_height_mm / pitch) as u32;
    let crop = PixelRect {
        x0: expected_column - 64,
        y0: pixels / 2 - 64,
        width: 128,
        height: 128,
    };
    let shot = Shot {
        sensor_mm,
        pixels,
        crop: Some(crop),
        dispersion: true,
    };
    // Distance from the axis of each line's centroid, mm.
    let radius_mm = |nm: f64| {
        let (x, y) = centroid_px(&shoot(&scene, &lens, image_z, nm, &shot));
        let (x, y) = (f64::from(crop.x0) + x - centre_px, f64::from(crop.y0) + y - centre_px);
        x.hypot(y) * pitch
    };
    let (f, c) = (radius_mm(F_LINE_NM), radius_mm(C_LINE_NM));
    // The analysis's figure as a difference of distances from the axis (the
    // lens inverts, so its signed heights are negative here).
    let height = |nm: f64| {
        system
            .at_wavelength(nm)
            .paraxial_chief_ray_height(tan_field, image_z)
            .abs()
    };
    let predicted = height(F_LINE_NM) - height(C_LINE_NM);
    assert!(
        (predicted.abs() / chromatic.lateral_color_mm.abs() - 1.0).abs() < 1e-9 && predicted.abs() > 0.02,
        "{chromatic:?}"
    );
    let measured = f - c;
    eprintln!("lateral colour: rendered {measured:.5} mm, analysis {predicted:.5} mm");
    assert!(
        (measured / predicted - 1.0).abs() < 0.1,
        "F image {f:.5} mm off the axis, C {c:.5} mm: {measured:.5} mm apart; analysis {predicted:.5} mm"
    );
}
