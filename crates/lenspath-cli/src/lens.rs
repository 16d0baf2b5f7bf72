//! `lenspath lens`: first-order and real-ray data of a lens, focusing, the
//! exit-pupil sampling efficiency, and a layout plot.

use std::path::PathBuf;

use clap::Args;
use lenspath::fs::write_text;
use lenspath::lens::plot::{focal_shift_svg, layout_svg};
use lenspath::lens::wave_analysis::{WaveAnalysis, WaveAnalysisSettings, WeightedWavelength};
use lenspath::lens::wave_plot::{mtf_svg, psf_svg};
use lenspath::lens::{AnalysisSettings, LensPrescription, LensSystem, FULL_FRAME_MM};
use lenspath::lens_report::{LensReport, LensReportSettings};
use lenspath::{Error, Result};

use crate::flags::{parse_sensor, SensorSize};
use crate::Outcome;

/// Options of `lenspath lens`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct LensArgs {
    /// Shipped lens (see --list: dgauss50, triplet50, tessar100, nikon-z14, lentil:0001 ...), any lentil database entry (lentil:0014), a Zemax .zmx file or a lens table file.
    #[arg(required_unless_present = "list")]
    lens: Option<String>,
    /// List the shipped lenses (name, focal length, f-number, elements, source) instead.
    #[arg(long, conflicts_with = "lens")]
    list: bool,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
    /// Also write the lens layout (elements, stop, sensor, ray fans; at the F, d and C lines when the glasses disperse) as SVG.
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// Also write the chromatic focal shift (paraxial focus against wavelength, 400-700 nm) as SVG.
    #[arg(long, value_name = "FILE")]
    focal_shift_plot: Option<PathBuf>,
    /// Also write the lens as a lenspath table (thickness to the next surface, glass and aspheric columns): how a Zemax file or a lentil entry is converted.
    #[arg(long, value_name = "FILE")]
    write_table: Option<PathBuf>,
    /// Sensor WIDTHxHEIGHT in mm (field of view, pupil sampling).
    #[arg(long, default_value_t = SensorSize::from(FULL_FRAME_MM), value_parser = parse_sensor)]
    sensor: SensorSize,
    /// Stop down to this f-number before analysing (default: wide open).
    #[arg(long, value_name = "N")]
    fstop: Option<f64>,
    /// Height of the near-axis real rays, mm (the CS184 lens simulator used 0.1 mm).
    #[arg(long, value_name = "MM", default_value_t = AnalysisSettings::default().ray_height_mm)]
    ray_height_mm: f64,
    /// Distance of the close-focus object in front of the aperture stop, mm (default: 5 x focal length).
    #[arg(long, value_name = "MM")]
    close_object_mm: Option<f64>,
    /// Also print the sensor position (mm behind the stop) that focuses this distance (m, from the sensor).
    #[arg(long, value_name = "M")]
    focus_distance_m: Option<f64>,
    /// Deprecated: --focus-distance-m (the same metres).
    #[arg(long, value_name = "M", hide = true, conflicts_with = "focus_distance_m")]
    focus_distance: Option<f64>,
    /// Also print the focus distance (m, from the sensor) of a sensor this many mm behind the stop.
    #[arg(long, value_name = "MM")]
    sensor_depth: Option<f64>,
    /// Also the wave-optics analysis at these field angles (degrees, comma-separated): RMS wavefront, Strehl, Zernike, MTF and MTF50, with the sensor at --sensor-depth or the infinity focus.
    #[arg(long, value_name = "FIELD_DEG", value_delimiter = ',')]
    mtf: Vec<f64>,
    /// Also the PSF at this field angle (degrees); its figures join --mtf's, and --psf-plot draws it.
    #[arg(long, value_name = "FIELD_DEG")]
    psf: Option<f64>,
    /// Wavelengths of the wave-optics analysis, nm (comma-separated; default: the lens's design wavelength).
    #[arg(long, value_name = "NM", value_delimiter = ',')]
    wavelength_nm: Vec<f64>,
    /// Weights of --wavelength-nm, one each (default: equal).
    #[arg(long, value_name = "W", value_delimiter = ',', requires = "wavelength_nm")]
    wavelength_weights: Vec<f64>,
    /// The MTF's frequencies, cycles per mm (comma-separated; default: 0 to 100 every 5).
    #[arg(long, value_name = "PER_MM", value_delimiter = ',')]
    mtf_frequencies: Vec<f64>,
    /// Also the MTF through focus at this frequency (cycles per mm), over ±4 Rayleigh depths of focus.
    #[arg(long, value_name = "PER_MM")]
    through_focus: Option<f64>,
    /// Pupil samples a side for the wave-optics analysis.
    #[arg(long, value_name = "N", default_value_t = WaveAnalysisSettings::default().pupil_samples)]
    pupil_samples: usize,
    /// Write the MTF of the --mtf fields as SVG.
    #[arg(long, value_name = "FILE", requires = "mtf")]
    mtf_plot: Option<PathBuf>,
    /// Write sections of the --psf field's PSF as SVG.
    #[arg(long, value_name = "FILE", requires = "psf")]
    psf_plot: Option<PathBuf>,
}

/// Prints the shipped lenses: a header line, then one line each (or a JSON array).
fn list(json: bool) -> Result<Outcome> {
    let lenses = lenspath::lens::library::listing()?;
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&lenses).map_err(|e| Error::InvalidArgument(e.to_string()))?
        );
        return Ok(Outcome::Done);
    }
    println!(
        "{:<14} {:>8} {:>8} {:>6} {:>8} {:>11}  source",
        "name", "f (mm)", "source f", "f/", "elements", "sensor (mm)"
    );
    for l in lenses {
        let aspheric = if l.aspheric { ", aspheric" } else { "" };
        let sensor = format!("{}x{}", round_mm(l.sensor_mm.0), round_mm(l.sensor_mm.1));
        println!(
            "{:<14} {:>8.2} {:>8.2} {:>6.2} {:>8} {:>11}  {}{aspheric}",
            l.name, l.focal_length_mm, l.source_focal_length_mm, l.f_number, l.elements, sensor, l.source
        );
    }
    Ok(Outcome::Done)
}

/// A sensor side for the listing: at most three decimals, no trailing zeros.
fn round_mm(mm: f64) -> String {
    let text = format!("{mm:.3}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Runs `lenspath lens`.
pub fn run(mut args: LensArgs) -> Result<Outcome> {
    if let Some(m) = args.focus_distance.take() {
        eprintln!("warning: --focus-distance is deprecated here; use --focus-distance-m (the same metres)");
        args.focus_distance_m = Some(m);
    }
    if !(args.ray_height_mm > 0.0 && args.ray_height_mm.is_finite()) {
        return Err(Error::InvalidArgument(format!(
            "--ray-height-mm must be positive, got {}",
            args.ray_height_mm
        )));
    }
    if let Some(d) = args.close_object_mm.filter(|d| !(*d > 0.0 && d.is_finite())) {
        return Err(Error::InvalidArgument(format!(
            "--close-object-mm must be positive, got {d}"
        )));
    }
    let Some(lens) = &args.lens else {
        return list(args.json);
    };
    let prescription = LensPrescription::load(lens)?;
    let wide_open = LensSystem::new(&prescription);
    let system = match args.fstop {
        Some(n) => wide_open.with_f_number(n)?,
        None => wide_open,
    };
    let sensor_mm = (args.sensor.width_mm, args.sensor.height_mm);
    let settings = LensReportSettings {
        analysis: AnalysisSettings {
            ray_height_mm: args.ray_height_mm,
            close_object_distance_mm: args.close_object_mm,
            sensor_mm,
        },
        focus_distance_m: args.focus_distance_m,
        sensor_depth_mm: args.sensor_depth,
    };
    let report = LensReport::new(&system, &settings)?.with_passing_fractions(&prescription, args.fstop)?;
    let wave_settings = wave_settings(&args)?;
    let mut fields_deg = args.mtf.clone();
    fields_deg.extend(args.psf.filter(|f| !args.mtf.contains(f)));
    let report = report.with_wave_analysis(&system, &fields_deg, &wave_settings)?;
    if let Some(path) = &args.mtf_plot {
        let mtf_fields: Vec<WaveAnalysis> = report.wave[..args.mtf.len()].to_vec();
        write_text(path, &mtf_svg(prescription.name(), &mtf_fields))?;
    }
    if let (Some(path), Some(field_deg)) = (&args.psf_plot, args.psf) {
        let result = WaveAnalysis::with_psf(
            &system,
            &WaveAnalysisSettings {
                field_deg,
                through_focus_frequency_per_mm: None,
                ..wave_settings.clone()
            },
        )?;
        write_text(path, &psf_svg(prescription.name(), &result))?;
    }

    if let Some(path) = &args.plot {
        let diagonal = sensor_mm.0.hypot(sensor_mm.1);
        write_text(path, &layout_svg(&system, &report.analysis, diagonal))?;
    }
    if let Some(path) = &args.write_table {
        let header = format!(
            "# {} as a lenspath table: radius, thickness to the next surface, n_d, aperture diameter (mm), glass; aspheric terms, a cylinder's axis or a toric surface's\n",
            prescription.name()
        );
        write_text(path, &(header + &prescription.table_text()))?;
    }
    if let Some(path) = &args.focal_shift_plot {
        write_text(path, &focal_shift_svg(&system)?)?;
    }
    if args.json {
        println!("{}", report.to_json());
        return Ok(Outcome::Done);
    }
    print_report(&report);
    Ok(Outcome::Done)
}

/// The wave-optics settings the flags ask for (the field is set per field).
fn wave_settings(args: &LensArgs) -> Result<WaveAnalysisSettings> {
    let weights = match args.wavelength_weights.len() {
        0 => vec![1.0; args.wavelength_nm.len()],
        n if n == args.wavelength_nm.len() => args.wavelength_weights.clone(),
        n => {
            return Err(Error::InvalidArgument(format!(
                "--wavelength-weights gives {n} weights for {} wavelengths",
                args.wavelength_nm.len()
            )))
        }
    };
    let defaults = WaveAnalysisSettings::default();
    Ok(WaveAnalysisSettings {
        spectrum: args
            .wavelength_nm
            .iter()
            .zip(weights)
            .map(|(&wavelength_nm, weight)| WeightedWavelength { wavelength_nm, weight })
            .collect(),
        sensor_depth_mm: args.sensor_depth,
        pupil_samples: args.pupil_samples,
        frequencies_per_mm: if args.mtf_frequencies.is_empty() {
            defaults.frequencies_per_mm.clone()
        } else {
            args.mtf_frequencies.clone()
        },
        through_focus_frequency_per_mm: args.through_focus,
        ..defaults
    })
}

/// `report` as the text `lenspath lens` prints.
fn print_report(report: &LensReport) {
    let (a, sensor_mm) = (&report.analysis, (report.sensor_width_mm, report.sensor_height_mm));
    let lines = ["g", "F", "d", "C"].map(|name| (name, report.lines[name]));
    println!("lens                      {}", report.lens);
    println!("                          positions in mm along the axis from the aperture stop, + toward the sensor");
    println!("paraxial");
    println!("  effective focal length  {:.4} mm", a.effective_focal_length_mm);
    println!("  f-number                f/{:.3}", a.f_number);
    println!(
        "  back focal distance     {:.4} mm (rear vertex to F')",
        a.back_focal_distance_mm
    );
    println!(
        "  front focal distance    {:.4} mm (F to front vertex)",
        a.front_focal_distance_mm
    );
    println!(
        "  principal planes        P {:.4} mm, P' {:.4} mm",
        a.front_principal_plane_mm, a.rear_principal_plane_mm
    );
    println!(
        "  entrance pupil          at {:.4} mm, {:.4} mm across",
        a.entrance_pupil_mm, a.entrance_pupil_diameter_mm
    );
    println!(
        "  exit pupil              at {:.4} mm, {:.4} mm across",
        a.exit_pupil_mm, a.exit_pupil_diameter_mm
    );
    println!(
        "  field of view           {:.2} deg diagonal, {:.2} deg horizontal ({}x{} mm sensor)",
        a.diagonal_fov_deg, a.horizontal_fov_deg, sensor_mm.0, sensor_mm.1
    );
    if let Some(anamorphic) = &a.anamorphic {
        println!(
            "anamorphic                squeeze {:.4}x (vertical over horizontal focal length)",
            anamorphic.squeeze
        );
        for (name, m) in [
            ("horizontal", &anamorphic.horizontal),
            ("vertical", &anamorphic.vertical),
        ] {
            println!(
                "  {name:<10}              EFL {:.4} mm, f/{:.3}, field {:.2} deg, infinity focus {:.4} mm",
                m.effective_focal_length_mm, m.f_number, m.field_of_view_deg, m.infinity_focus_mm
            );
        }
    }
    println!("colour (paraxial)");
    for (name, l) in lines {
        println!(
            "  {name} line {:9.4} nm     EFL {:.4} mm, BFD {:.4} mm",
            l.wavelength_nm, l.effective_focal_length_mm, l.back_focal_distance_mm
        );
    }
    println!(
        "  longitudinal colour     {:.4} mm (BFD F - BFD C)",
        report.longitudinal_color_mm
    );
    println!(
        "  lateral colour          {:.4} mm (F - C chief ray heights at {:.2} mm image height)",
        report.lateral_color_mm, report.lateral_color_field_height_mm
    );
    println!("real rays at {} mm height", a.ray_height_mm);
    if a.anamorphic.is_some() {
        println!("                          focus positions midway between the two meridians' line foci");
    }
    println!("  infinity focus          sensor at {:.4} mm", a.infinity_focus_mm);
    println!(
        "  close focus             sensor at {:.4} mm (object {:.4} mm in front of the stop)",
        a.close_focus_mm, a.close_focus_object_distance_mm
    );
    println!("  focal length |P'-F'|    {:.4} mm", a.focal_length_mm);
    println!(
        "  lens vertices           front {:.4} mm, rear {:.4} mm",
        a.front_vertex_mm, a.rear_vertex_mm
    );
    if let Some(p) = &report.passing {
        println!(
            "rays through (inf. focus) {:.1}% at the centre, {:.1}% at the corner",
            100.0 * p.passing_fraction_centre,
            100.0 * p.passing_fraction_corner
        );
    }
    let focus = &report.focus;
    if let (Some(m), Some(z)) = (focus.focus_distance_m, focus.sensor_depth_for_focus_distance_mm) {
        println!("focus at {m} m             sensor at {z:.4} mm");
    }
    if let (Some(z), Some(d)) = (focus.sensor_depth_mm, focus.focus_distance_for_sensor_depth_m) {
        match d {
            Some(m) => println!("sensor at {z} mm          focuses at {m:.6} m"),
            None => println!("sensor at {z} mm          focuses beyond infinity (nearer than the infinity focus)"),
        }
    }
    report.wave.iter().for_each(print_wave_analysis);
}

/// One field's wave-optics figures as text.
fn print_wave_analysis(w: &WaveAnalysis) {
    println!(
        "wave optics at {}°          sensor at {:.4} mm, f/{:.3} working, PSF samples {:.3} x {:.3} µm",
        w.field_deg, w.sensor_depth_mm, w.working_f_number, w.psf_spacing_um[0], w.psf_spacing_um[1]
    );
    println!("  wavelength (nm)  weight  RMS (waves)  Strehl  pupil through");
    for m in &w.wavelengths {
        println!(
            "  {:>15.2}  {:>6.3}  {:>11.4}  {:>6.4}  {:>12.1}%",
            m.wavelength_nm,
            m.weight,
            m.rms_wavefront_waves,
            m.strehl_ratio,
            100.0 * m.pupil_passing_fraction
        );
    }
    let per_mm = |f: Option<f64>| f.map_or("beyond the grid".to_string(), |f| format!("{f:.1}/mm"));
    println!(
        "  Strehl {:.4}, MTF50 tangential {}, sagittal {}",
        w.strehl_ratio,
        per_mm(w.mtf50_tangential_per_mm),
        per_mm(w.mtf50_sagittal_per_mm)
    );
    println!("  cycles/mm  tangential  sagittal  diffraction limit");
    for s in &w.mtf {
        println!(
            "  {:>9.1}  {:>10.4}  {:>8.4}  {:>17.4}",
            s.frequency_per_mm, s.tangential, s.sagittal, s.diffraction_limit
        );
    }
    if let Some(frequency) = w.through_focus_frequency_per_mm {
        let best = |pick: fn(&lenspath::lens::wave_analysis::ThroughFocusSample) -> f64| {
            w.through_focus
                .iter()
                .max_by(|a, b| pick(a).total_cmp(&pick(b)))
                .map(|s| (s.sensor_depth_mm, pick(s)))
        };
        if let (Some(t), Some(s)) = (best(|s| s.tangential), best(|s| s.sagittal)) {
            println!(
                "  through focus at {frequency}/mm: tangential peaks {:.4} at {:.4} mm, sagittal {:.4} at {:.4} mm",
                t.1, t.0, s.1, s.0
            );
        }
    }
}
