//! The image sensor against theory: the camera equation on a uniform scene,
//! the photon transfer curve of rendered flat fields (EMVA 1288), full-well
//! saturation, fixed patterns and temporal noise, and the DNG it writes.

use std::sync::atomic::AtomicBool;

use glam::Vec3;
use lenspath::accel::BvhSettings;
use lenspath::camera::{Camera, CameraPose, LensFocus, Radiometry, RealisticCamera, RealisticCameraSettings};
use lenspath::film::{Image, PixelRect};
use lenspath::integrator::Integrator;
use lenspath::lens::LensPrescription;
use lenspath::lights::Light;
use lenspath::math::Rgb;
use lenspath::render::{render, FilmResponse, RenderSettings};
use lenspath::scene::Scene;
use lenspath::sensor::raw_file::write_raw;
use lenspath::sensor::response::{electrons_per_energy, IDEAL_SENSOR};
use lenspath::sensor::{capture, Cfa, RawFrame, SensorSettings, SpectralResponse};
use lenspath::spectrum::Emission;

const PIXELS: (u32, u32) = (96, 64);
const F_NUMBER: f64 = 8.0;
/// The IMX363's pixel pitch, mm: the sensor is 96 × 64 of its pixels.
const PITCH_MM: f64 = 0.0014;

fn camera() -> RealisticCamera {
    RealisticCamera::new(
        CameraPose::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y),
        PIXELS.0,
        PIXELS.1,
        &RealisticCameraSettings {
            f_number: Some(F_NUMBER),
            radiometry: Radiometry::Physical,
            ..RealisticCameraSettings::new(
                LensPrescription::load("dgauss50").unwrap(),
                (PITCH_MM * f64::from(PIXELS.0), PITCH_MM * f64::from(PIXELS.1)),
                LensFocus::Distance(1e9),
            )
        },
    )
    .unwrap()
}

/// A uniform white sky (radiance 1 in scene units) through `camera` onto
/// the film of `response`, the pixels of `crop` (`None`: all).
fn flat_field(camera: &RealisticCamera, response: &'static SpectralResponse, crop: Option<PixelRect>) -> Image {
    let scene = Scene {
        lights: vec![Light::Environment {
            radiance: Rgb::ONE.into(),
        }],
        ..Default::default()
    };
    let settings = RenderSettings {
        width: PIXELS.0,
        height: PIXELS.1,
        spp: 16,
        integrator: Integrator::path(1, 1),
        crop,
        depth: false,
        film: FilmResponse::Sensor(response),
        ..Default::default()
    };
    let compiled = scene.compile(&BvhSettings::default()).unwrap();
    render(&compiled, camera, &settings, &|_, _| {}, &AtomicBool::new(false))
        .unwrap()
        .image
}

/// The camera equation (Slater 1980; ISO 12232's H = q·L·t/N² with q =
/// π/4 on the axis of a lens without losses): at the centre of the sensor,
/// behind a lens at f/8 focused at infinity, a pixel collects
/// π/(4N²) · A · t · ∫ L(λ) QE(λ) λ/(hc) dλ electrons. The right side is
/// integrated here at 1 nm from the sky's spectrum and the sensor's
/// quantum efficiency; the left is the rendered film (Monte Carlo over
/// wavelengths and the exit pupil) times the sensor's conversion.
#[test]
fn the_centre_of_a_uniform_scene_collects_what_the_camera_equation_says() {
    let camera = camera();
    let response = SpectralResponse::named(IDEAL_SENSOR).unwrap();
    let sensor = SensorSettings::new(response);
    let centre = PixelRect {
        x0: PIXELS.0 / 2 - 4,
        y0: PIXELS.1 / 2 - 4,
        width: 8,
        height: 8,
    };
    let image = flat_field(&camera, response, Some(centre));
    let radiometry = camera.film_radiometry().unwrap();
    let electrons = image.mean()[1] * sensor.electrons_per_reading(&radiometry);

    let sky = Emission::from(Rgb::ONE).spectrum();
    let per_um2_s_sr: f64 = (360..=830)
        .map(|nm| {
            f64::from(sky.at(nm as f32))
                * sensor.radiance_per_scene_unit()
                * sensor.peak_qe
                * response.relative_qe(nm as f32).y
                * electrons_per_energy(f64::from(nm))
        })
        .sum();
    let expected = std::f64::consts::PI / (4.0 * F_NUMBER * F_NUMBER)
        * radiometry.pixel_area_um2()
        * sensor.exposure_time_s
        * per_um2_s_sr;
    eprintln!(
        "camera equation: {electrons:.1} e- rendered, {expected:.1} theory, ratio {:.5}",
        electrons / expected
    );
    assert!(
        (electrons / expected - 1.0).abs() < 0.01,
        "{electrons:.1} e- at the centre, the camera equation says {expected:.1}"
    );
    // The pixel pitch is the sensor's over the image's.
    assert!((radiometry.pixel_pitch_um.0 - 1000.0 * PITCH_MM).abs() < 1e-9);
}

/// Mean and temporal variance, DN, of two frames of the same exposure
/// (EMVA 1288 §6.3: the difference of two frames cancels the fixed
/// patterns and the scene's own non-uniformity).
fn mean_and_temporal_variance(a: &RawFrame, b: &RawFrame) -> (f64, f64) {
    let n = a.dn.len() as f64;
    let mean = a.dn.iter().chain(&b.dn).map(|&v| f64::from(v)).sum::<f64>() / (2.0 * n) - f64::from(a.black_level_dn);
    let diffs: Vec<f64> =
        a.dn.iter()
            .zip(&b.dn)
            .map(|(&x, &y)| f64::from(x) - f64::from(y))
            .collect();
    let d_mean = diffs.iter().sum::<f64>() / n;
    let variance = diffs.iter().map(|d| (d - d_mean).powi(2)).sum::<f64>() / (n - 1.0) / 2.0;
    (mean, variance)
}

fn frame_pair(image: &Image, camera: &RealisticCamera, sensor: &SensorSettings) -> (RawFrame, RawFrame) {
    frame_pair_seeded(image, camera, sensor, 1)
}

/// Mean and temporal variance pooled over four frame pairs: 4 × 6144
/// differences, so a variance is known to about 1% (one pair's 1.8% left
/// the fitted gain 1–3% off, depending on the noise's seeds).
fn pooled_mean_and_variance(image: &Image, camera: &RealisticCamera, sensor: &SensorSettings) -> (f64, f64) {
    let (m, v) = (0..4u64)
        .map(|p| {
            let (a, b) = frame_pair_seeded(image, camera, sensor, 2 * p + 1);
            mean_and_temporal_variance(&a, &b)
        })
        .fold((0.0, 0.0), |(m, v), (pm, pv)| (m + pm, v + pv));
    (m / 4.0, v / 4.0)
}

/// Frames `first_seed` and the next of one exposure.
fn frame_pair_seeded(
    image: &Image,
    camera: &RealisticCamera,
    sensor: &SensorSettings,
    first_seed: u64,
) -> (RawFrame, RawFrame) {
    let radiometry = camera.film_radiometry().unwrap();
    let shot = |frame_seed| {
        let settings = SensorSettings {
            frame_seed,
            ..sensor.clone()
        };
        capture(image, (0, 0), &radiometry, &settings).unwrap()
    };
    (shot(first_seed), shot(first_seed + 1))
}

/// The photon transfer curve (Janesick 2007; EMVA 1288 §6.3) of a rendered
/// flat field at 12 exposure times: temporal variance against mean signal
/// is a line whose slope is the system gain 1/K (DN per e⁻) and whose
/// intercept, with the dark frames', gives the read noise; in the shot-noise
/// regime the SNR is √N; past the full well the signal stops.
#[test]
fn the_photon_transfer_curve_gives_back_the_gain_and_the_read_noise() {
    let camera = camera();
    let response = SpectralResponse::named("sony_ilce_7m3").unwrap();
    let image = flat_field(&camera, response, None);
    let radiometry = camera.film_radiometry().unwrap();
    // ISO 220: analogue gain 4, so the 5 e⁻ read noise is 3.4 DN, well above quantisation.
    let sensor = SensorSettings {
        iso: 220.0,
        bit_depth: 12,
        ..SensorSettings::new(response)
    };
    let k = sensor.electrons_per_dn(&radiometry);
    // Exposure times from 1% to 70% of the ADC's range at the brightest pixel's green.
    let brightest = image.rgb.iter().fold(0.0f32, |m, &v| m.max(v)) as f64;
    let range_e = f64::from(sensor.white_level_dn() - sensor.black_level_dn) * k;
    let t_full = range_e / (brightest * sensor.electrons_per_reading(&radiometry) / sensor.exposure_time_s);
    let points: Vec<(f64, f64)> = (0..12)
        .map(|i| {
            let exposure = SensorSettings {
                exposure_time_s: t_full * (0.01 + 0.69 * f64::from(i) / 11.0),
                ..sensor.clone()
            };
            pooled_mean_and_variance(&image, &camera, &exposure)
        })
        .collect();
    // Least-squares line through (mean, variance).
    let n = points.len() as f64;
    let (sx, sy) = points.iter().fold((0.0, 0.0), |(sx, sy), (x, y)| (sx + x, sy + y));
    let (mx, my) = (sx / n, sy / n);
    let sxy: f64 = points.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = points.iter().map(|(x, _)| (x - mx).powi(2)).sum();
    let slope = sxy / sxx;
    let k_measured = 1.0 / slope;
    eprintln!("photon transfer: {k_measured:.4} e-/DN measured, {k:.4} set");
    assert!(
        (k_measured / k - 1.0).abs() < 0.02,
        "conversion gain {k_measured:.4} e-/DN from the curve, {k:.4} set"
    );

    // Read noise from a pair of dark frames, less quantisation's 1/12 DN².
    let dark = Image {
        rgb: vec![0.0; image.rgb.len()],
        ..image.clone()
    };
    let (_, dark_variance) = pooled_mean_and_variance(&dark, &camera, &sensor);
    let read_noise = k_measured * (dark_variance - 1.0 / 12.0).sqrt();
    eprintln!("read noise: {read_noise:.3} e- measured, {} set", sensor.read_noise_e);
    assert!(
        (read_noise / sensor.read_noise_e - 1.0).abs() < 0.05,
        "read noise {read_noise:.3} e- measured, {} set",
        sensor.read_noise_e
    );

    // Shot-noise regime: SNR = √(signal in electrons) at the brightest level.
    let (mean, variance) = points[11];
    let dark_part = dark_variance;
    let snr = mean / (variance - dark_part).sqrt();
    let electrons = mean * k;
    assert!(
        (snr / electrons.sqrt() - 1.0).abs() < 0.03,
        "SNR {snr:.1} at {electrons:.0} e-, √N = {:.1}",
        electrons.sqrt()
    );

    // Past the full well (6000 e⁻ in a 1.4 µm pixel), at gain 1/2 into 12
    // bits, the signal stops there and only read noise is left.
    let unity = SensorSettings {
        iso: sensor.unity_gain_iso / 2.0,
        exposure_time_s: t_full * 40.0,
        ..sensor.clone()
    };
    let (a, b) = frame_pair(&image, &camera, &unity);
    let (mean, variance) = mean_and_temporal_variance(&a, &b);
    let full_well_dn = unity.full_well_e(&radiometry) / unity.electrons_per_dn(&radiometry);
    assert!(full_well_dn + f64::from(unity.black_level_dn) < f64::from(unity.white_level_dn()));
    assert!(
        (mean - full_well_dn).abs() < 1.0,
        "saturated at {mean:.2} DN, full well {full_well_dn:.2}"
    );
    let read_only = (unity.read_noise_e / unity.electrons_per_dn(&radiometry)).powi(2) + 1.0 / 12.0;
    assert!(
        variance < 1.5 * read_only,
        "variance {variance:.3} DN² past the full well"
    );
}

/// Correlation across pixels of two frames' deviations from their means.
fn correlation(a: &RawFrame, b: &RawFrame) -> f64 {
    let mean = |f: &RawFrame| f.dn.iter().map(|&v| f64::from(v)).sum::<f64>() / f.dn.len() as f64;
    let (ma, mb) = (mean(a), mean(b));
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (&x, &y) in a.dn.iter().zip(&b.dn) {
        let (x, y) = (f64::from(x) - ma, f64::from(y) - mb);
        ab += x * y;
        aa += x * x;
        bb += y * y;
    }
    ab / (aa * bb).sqrt()
}

/// A frame is a function of its seeds and each pixel's place: the same
/// seeds give the same frame, a crop gives the full frame's pixels (and
/// its mosaic's phase), a new frame seed new temporal noise over the same
/// fixed pattern, a new fixed-pattern seed another sensor.
#[test]
fn frames_are_bit_identical_per_seed_and_share_their_fixed_pattern() {
    let camera = camera();
    let response = SpectralResponse::named("nikon_d850").unwrap();
    let radiometry = camera.film_radiometry().unwrap();
    let sensor = SensorSettings {
        prnu: 0.05,
        cfa: Cfa::Mono,
        ..SensorSettings::new(response)
    };
    // A flat reading of half the full well, so the only structure is the sensor's.
    let reading = (0.5 * sensor.full_well_e(&radiometry) / sensor.electrons_per_reading(&radiometry)) as f32;
    let image = Image {
        rgb: vec![reading; (3 * PIXELS.0 * PIXELS.1) as usize],
        ..flat_field(&camera, response, None)
    };
    let shot = |frame_seed, fixed_pattern_seed| {
        let s = SensorSettings {
            frame_seed,
            fixed_pattern_seed,
            ..sensor.clone()
        };
        capture(&image, (0, 0), &radiometry, &s).unwrap()
    };
    assert_eq!(shot(1, 0), shot(1, 0));
    let (a, b, other_sensor) = (shot(1, 0), shot(2, 0), shot(3, 9));
    assert_ne!(a.dn, b.dn);
    let same_pattern = correlation(&a, &b);
    let other_pattern = correlation(&a, &other_sensor);
    assert!(
        same_pattern > 0.5,
        "frames of one sensor correlate by {same_pattern:.3}"
    );
    assert!(
        other_pattern.abs() < 0.05,
        "two sensors' frames correlate by {other_pattern:.3}"
    );

    // A crop at an odd place: the full frame's pixels, the mosaic's phase moved.
    let bayer = SensorSettings {
        cfa: Cfa::Rggb,
        ..sensor.clone()
    };
    let full = capture(&image, (0, 0), &radiometry, &bayer).unwrap();
    let crop = Image {
        width: 5,
        height: 3,
        rgb: vec![reading; 45],
        depth: vec![0.0; 15],
        ..image.clone()
    };
    let cropped = capture(&crop, (7, 3), &radiometry, &bayer).unwrap();
    assert_eq!(cropped.cfa, Cfa::Bggr);
    for y in 0..3 {
        for x in 0..5 {
            assert_eq!(cropped.dn[y * 5 + x], full.dn[(y + 3) * PIXELS.0 as usize + x + 7]);
        }
    }
}

/// The DNG read back by an independent TIFF reader: the mosaic and the tags
/// a raw developer needs (CFA photometric interpretation, pattern, black and
/// white levels, D65 colour matrix).
#[test]
fn the_dng_holds_the_mosaic_and_what_a_developer_needs() {
    let camera = camera();
    let response = SpectralResponse::named("canon_eos_5d_mkiv").unwrap();
    let image = flat_field(&camera, response, None);
    let sensor = SensorSettings {
        cfa: Cfa::Grbg,
        ..SensorSettings::new(response)
    };
    let frame = capture(&image, (0, 0), &camera.film_radiometry().unwrap(), &sensor).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("frame.dng");
    write_raw(&path, &frame).unwrap();

    let bytes = std::fs::read(&path).unwrap();
    let ifd = read_ifd(&bytes);
    let tag = |t: u16| {
        ifd.iter()
            .find(|e| e.0 == t)
            .unwrap_or_else(|| panic!("tag {t} missing"))
            .1
            .clone()
    };
    assert_eq!(tag(262), vec![32803.0], "PhotometricInterpretation: CFA");
    assert_eq!(tag(33422), vec![1.0, 0.0, 2.0, 1.0], "CFAPattern: GRBG");
    assert_eq!(tag(50714), vec![64.0], "BlackLevel");
    assert_eq!(tag(50717), vec![1023.0], "WhiteLevel");
    assert_eq!(tag(50778), vec![21.0], "CalibrationIlluminant1: D65");
    assert_eq!(tag(50706), vec![1.0, 4.0, 0.0, 0.0], "DNGVersion");
    assert!((tag(33434)[0] - sensor.exposure_time_s).abs() < 1e-6, "ExposureTime");
    assert_eq!(tag(34855), vec![sensor.iso], "ISOSpeedRatings");
    let m = frame.xyz_to_camera;
    for (i, v) in tag(50721).iter().enumerate() {
        assert!((v - m.row(i / 3)[i % 3]).abs() < 1e-6, "ColorMatrix1[{i}] {v}");
    }
    let start = tag(273)[0] as usize;
    let pixels: Vec<u16> = bytes[start..start + 2 * frame.dn.len()]
        .chunks(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]))
        .collect();
    assert_eq!(pixels, frame.dn);
    // A camera's green reads white from D65 in the neutral with the others below it.
    assert!(
        frame.as_shot_neutral.y == 1.0 && frame.as_shot_neutral.x < 1.0 && frame.as_shot_neutral.z < 1.0,
        "{}",
        frame.as_shot_neutral
    );
}

/// Auto exposure, a camera's program mode: the frame's mean green lands at
/// 18% of the full well at the base ISO while the exposure time allows;
/// past the longest time the ISO makes up the rest, up to the highest.
#[test]
fn auto_exposure_meters_mid_grey_and_raises_the_iso_only_past_the_longest_time() {
    use lenspath::camera::FilmRadiometry;
    use lenspath::sensor::AutoExposure;
    let optics = FilmRadiometry {
        irradiance_per_reading_sr: std::f64::consts::PI / (4.0 * 4.0),
        pixel_pitch_um: (4.0, 4.0),
    };
    let auto = AutoExposure {
        max_exposure_time_s: 1.0 / 30.0,
        max_iso: 3520.0,
    };
    let sensor = SensorSettings {
        auto_exposure: Some(auto),
        bit_depth: 14,
        ..SensorSettings::new(SpectralResponse::named("sony_ilce_7m3").unwrap())
    };
    // The green reading that gives a mid-grey frame at the longest time and base ISO.
    let at_longest = SensorSettings {
        exposure_time_s: auto.max_exposure_time_s,
        ..sensor.clone()
    };
    let mid_grey = AutoExposure::MID_GREY * sensor.full_well_e(&optics) / at_longest.electrons_per_reading(&optics);
    let frame_of = |reading: f64| {
        let (w, h) = (64, 48);
        let film = Image {
            width: w,
            height: h,
            rgb: (0..w * h)
                .flat_map(|_| [0.5, 1.0, 0.7].map(|c| (c * reading) as f32))
                .collect(),
            depth: vec![f32::INFINITY; (w * h) as usize],
            spp_min: 1,
            spp_requested: 1,
        };
        capture(&film, (0, 0), &optics, &sensor).unwrap()
    };
    // Mean green over black as a fraction of the white level: the frame's
    // brightness (at the base ISO the white level is the full well).
    let green_fraction = |frame: &RawFrame| {
        let greens: Vec<f64> = (0..frame.height)
            .flat_map(|y| (0..frame.width).map(move |x| (x, y)))
            .filter(|&(x, y)| frame.cfa.channel(x, y) == 1)
            .map(|(x, y)| f64::from(frame.dn[(y * frame.width + x) as usize]) - f64::from(frame.black_level_dn))
            .collect();
        greens.iter().sum::<f64>() / greens.len() as f64 / f64::from(frame.white_level_dn)
    };
    for (light, expect_time, expect_iso) in [
        (16.0, auto.max_exposure_time_s / 16.0, 55.0),
        (1.0, auto.max_exposure_time_s, 55.0),
        (1.0 / 8.0, auto.max_exposure_time_s, 440.0),
        (1.0 / 1000.0, auto.max_exposure_time_s, 3520.0),
    ] {
        let frame = frame_of(mid_grey * light);
        eprintln!(
            "light ×{light}: {:.5} s at ISO {:.0}, mean green {:.4} of the white level",
            frame.exposure.exposure_time_s,
            frame.exposure.iso,
            green_fraction(&frame)
        );
        // The film is f32: the metered reading is the intended one to 1e-7.
        assert!(
            (frame.exposure.exposure_time_s / expect_time - 1.0).abs() < 1e-6,
            "{}",
            frame.exposure.exposure_time_s
        );
        assert!(
            (frame.exposure.iso / expect_iso - 1.0).abs() < 1e-6,
            "{}",
            frame.exposure.iso
        );
        if light >= 1.0 / 8.0 {
            // Mid-grey (the highest ISO cannot reach it at 1/1000 of the light).
            let fraction = green_fraction(&frame);
            assert!((fraction / AutoExposure::MID_GREY - 1.0).abs() < 0.01, "{fraction}");
        }
    }
}

/// The first IFD of a little-endian TIFF: (tag, values) of each entry
/// (TIFF 6.0 §2: a 12-byte entry holds tag, type, count and the values or
/// their offset), numbers as f64, rationals divided out.
fn read_ifd(bytes: &[u8]) -> Vec<(u16, Vec<f64>)> {
    assert_eq!(&bytes[..4], b"II*\0", "a little-endian TIFF");
    let u16_at = |o: usize| u16::from_le_bytes([bytes[o], bytes[o + 1]]);
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
    let ifd = u32_at(4) as usize;
    (0..usize::from(u16_at(ifd)))
        .map(|i| {
            let e = ifd + 2 + 12 * i;
            let (tag, kind, count) = (u16_at(e), u16_at(e + 2), u32_at(e + 4) as usize);
            let size = match kind {
                1 | 2 | 6 | 7 => 1,
                3 | 8 => 2,
                4 | 9 | 11 => 4,
                _ => 8,
            };
            let at = if size * count <= 4 {
                e + 8
            } else {
                u32_at(e + 8) as usize
            };
            let values = (0..count)
                .map(|k| {
                    let o = at + size * k;
                    match kind {
                        1 | 2 | 7 => f64::from(bytes[o]),
                        3 => f64::from(u16_at(o)),
                        4 => f64::from(u32_at(o)),
                        5 => f64::from(u32_at(o)) / f64::from(u32_at(o + 4)),
                        10 => f64::from(u32_at(o) as i32) / f64::from(u32_at(o + 4) as i32),
                        _ => f64::NAN,
                    }
                })
                .collect();
            (tag, values)
        })
        .collect()
}
