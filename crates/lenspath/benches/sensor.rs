//! The sensor stage of a 24-megapixel frame (6000 × 4000, a full-frame
//! camera's): capture (fixed patterns, shot and read noise, gain, the
//! mosaic) and development (white balance, Malvar–He–Cutler demosaicking,
//! colour matrix), on every core. Target (issue 32): under 1 s on 2 cores,
//! so it never dominates a render.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use lenspath::camera::FilmRadiometry;
use lenspath::film::Image;
use lenspath::sensor::develop::develop;
use lenspath::sensor::{capture, SensorSettings, SpectralResponse};

const WIDTH: u32 = 6000;
const HEIGHT: u32 = 4000;

/// A film with detail and every exposure level from black to past the full
/// well (a diagonal ramp times a grating, `full_well` the reading that fills
/// it): the noise and clipping branches are all taken.
fn film(full_well: f32) -> Image {
    let rgb = (0..HEIGHT)
        .flat_map(|y| (0..WIDTH).map(move |x| (x, y)))
        .flat_map(|(x, y)| {
            let ramp = (x + y) as f32 / (WIDTH + HEIGHT) as f32;
            let v = 1.2 * full_well * ramp * (1.0 + 0.5 * (0.3 * x as f32).sin());
            [0.6 * v, v, 0.8 * v]
        })
        .collect();
    Image {
        width: WIDTH,
        height: HEIGHT,
        rgb,
        depth: Vec::new(),
        spp_min: 1,
        spp_requested: 1,
    }
}

fn sensor_stage(c: &mut Criterion) {
    // 36 × 24 mm over 6000 × 4000: 6 µm pixels behind f/2.8.
    let optics = FilmRadiometry {
        irradiance_per_reading_sr: std::f64::consts::PI / (4.0 * 2.8 * 2.8),
        pixel_pitch_um: (6.0, 6.0),
    };
    let sensor = SensorSettings::new(SpectralResponse::named("sony_ilce_7m3").unwrap());
    let film = film((sensor.full_well_e(&optics) / sensor.electrons_per_reading(&optics)) as f32);
    let frame = capture(&film, (0, 0), &optics, &sensor).unwrap();
    let mut group = c.benchmark_group("sensor_24mp");
    group.sample_size(10);
    group.throughput(Throughput::Elements(u64::from(WIDTH * HEIGHT)));
    group.bench_function("capture", |b| {
        b.iter(|| capture(&film, (0, 0), &optics, &sensor).unwrap())
    });
    group.bench_function("develop", |b| b.iter(|| develop(&frame, &sensor.development)));
    group.bench_function("capture_and_develop", |b| {
        b.iter(|| develop(&capture(&film, (0, 0), &optics, &sensor).unwrap(), &sensor.development))
    });
    group.finish();
}

criterion_group!(benches, sensor_stage);
criterion_main!(benches);
