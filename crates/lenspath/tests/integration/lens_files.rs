//! Lens files from other tools (`tests/data/lenses/`, README there): Zemax
//! files read as rayoptics reads them, refused where they hold what lenspath
//! cannot trace, and written back out as lenspath tables.

use std::path::PathBuf;

use glam::DVec3;
use lenspath::lens::{Direction, LensPrescription, LensRay, LensSystem, SurfaceShape, TableConvention};

fn file(name: &str) -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/lenses")
        .join(name);
    path.to_string_lossy().into_owned()
}

/// Paraxial EFL and BFL, and where rays parallel to the axis at 1 and 4 mm
/// cross the plane 10 mm behind the rear vertex, against rayoptics 0.9.8
/// reading the same file at the d line (`bench/peers/lens_vs_rayoptics.py`).
/// rayoptics has no L-TIM28, so US 8,427,765's third glass was given
/// lenspath's n_d for it there; every other index is each tool's own catalogue's.
#[test]
fn zemax_files_trace_as_rayoptics_reads_them() {
    let cases = [
        (
            "US08427765-1.ZMX",
            30.805689090641838,
            21.447226401072694,
            [0.3716700112266848, 1.4934088264822056],
        ),
        (
            "US00583336-2-scaled.zmx",
            49.388975846763365,
            41.60051190450003,
            [0.6403366800320967, 2.5966145316447635],
        ),
    ];
    for (name, efl, bfl, heights) in cases {
        let lens = LensSystem::new(&LensPrescription::load(&file(name)).unwrap());
        let p = lens.paraxial().unwrap();
        assert!(
            (p.effective_focal_length_mm / efl - 1.0).abs() < 1e-9,
            "{name}: EFL {p:?}"
        );
        assert!((p.back_focal_distance_mm / bfl - 1.0).abs() < 1e-9, "{name}: BFL {p:?}");
        for (height, expected) in [1.0, 4.0].into_iter().zip(heights) {
            let ray = LensRay {
                origin: DVec3::new(height, 0.0, lens.front_z_mm() - 50.0),
                direction: DVec3::Z,
            };
            let out = lens.trace(&ray, Direction::ToSensor).expect("passes");
            let at = out.at_z(lens.rear_z_mm() + 10.0).unwrap().x;
            assert!(
                (at - expected).abs() < 1e-8,
                "{name} at {height} mm: {at} vs {expected}"
            );
        }
    }
}

/// What the readers make of each file: the asphere with its conic and
/// terms, the stop, the glasses by maker; a UTF-16 file like any other.
/// ISET3d's copies of two Zemax samples put the stop on a curved surface's
/// vertex (thickness 0 between them), so that surface's rim lies beyond the
/// stop plane. Paraxial EFL and BFL against rayoptics 0.9.8 given the same
/// surfaces and indices; and real rays parallel to the axis through 90% of
/// the entrance pupil all pass (they were all blocked while the stop moved a
/// ray to its plane), those at 110% none.
#[test]
fn a_stop_on_a_curved_vertex_clips_at_the_entrance_pupil() {
    let cases = [
        ("iset3d-cooke40deg-zemax.json", 49.9887473573, 42.4043647839),
        ("iset3d-petzval-zemax.json", 99.8876422269, 15.1955944457),
    ];
    for (name, efl, bfl) in cases {
        let lens = LensSystem::new(&LensPrescription::load(&file(name)).unwrap());
        let p = lens.paraxial().unwrap();
        assert!((p.effective_focal_length_mm / efl - 1.0).abs() < 1e-9, "{name}: {p:?}");
        assert!((p.back_focal_distance_mm / bfl - 1.0).abs() < 1e-9, "{name}: {p:?}");
        let passing = |fraction: f64| {
            (0..16)
                .filter(|k| {
                    let azimuth = f64::from(*k) * std::f64::consts::TAU / 16.0;
                    let h = fraction * 0.5 * p.entrance_pupil_diameter_mm;
                    let ray = LensRay {
                        origin: DVec3::new(h * azimuth.cos(), h * azimuth.sin(), lens.front_z_mm() - 10.0),
                        direction: DVec3::Z,
                    };
                    lens.trace(&ray, Direction::ToSensor).is_some()
                })
                .count()
        };
        assert_eq!((passing(0.9), passing(1.1)), (16, 0), "{name}");
    }
}

#[test]
fn zemax_surfaces_glasses_and_encodings() {
    let lens = LensPrescription::load(&file("US08427765-1.ZMX")).unwrap();
    let asphere = lens
        .surfaces()
        .iter()
        .find_map(|s| match s.shape {
            SurfaceShape::EvenAsphere(a) => Some((s.radius_mm, a)),
            _ => None,
        })
        .expect("surface 4 is an even asphere");
    assert_eq!(asphere.1.conic, 0.02);
    assert_eq!(asphere.1.coefficients[1..3], [1.10721e-5, 1.837e-7]);
    assert!((asphere.0 - 1.0 / 1.11781801922647e-1).abs() < 1e-12);
    // Edmund's achromat pair is UTF-16; its stop is a flat of its own.
    let pair = LensPrescription::load(&file("edmund-55278.zmx")).unwrap();
    assert_eq!(pair.surfaces().len(), 7);
    assert!(pair.surfaces()[0].is_stop());
    let table = pair.table_text();
    assert!(
        table.contains("schott:SF5") && table.contains("schott:N-BK7"),
        "{table}"
    );
    // Edmund gives its EFL as 52.24 mm in the file's DBDT line.
    let efl = LensSystem::new(&pair).paraxial().unwrap().effective_focal_length_mm;
    assert!((efl - 52.24).abs() < 0.01, "{efl}");
}

/// A Zemax file with TOROIDAL surfaces (a toric front, radius of rotation
/// 25 mm, and a cylinder: PARM 1 = 0) against rayoptics 0.9.8 reading the
/// same file (its `YToroid`): where skew rays from 50 mm in front of the stop
/// cross the plane 10 mm behind the rear vertex.
#[test]
fn a_toroidal_zemax_file_traces_as_rayoptics_reads_it() {
    let prescription = LensPrescription::load(&file("toric-doublet.zmx")).unwrap();
    let shapes: Vec<_> = prescription.surfaces().iter().map(|s| s.shape).collect();
    assert!(
        matches!(shapes[1], SurfaceShape::Toric(t) if t.rotation_radius_mm == 25.0)
            && matches!(shapes[2], SurfaceShape::Cylindrical(_)),
        "{shapes:?}"
    );
    let lens = LensSystem::new(&prescription);
    let rayoptics = [
        ([3.0, 0.0], [0.0, 0.0], [1.6578589014660354, 0.0]),
        ([0.0, 3.0], [0.0, 0.0], [0.0, 2.1815918145151674]),
        ([2.0, -3.0], [0.03, 0.05], [2.438535871956864, 0.531420621228403]),
        ([-5.0, 4.0], [0.06, -0.03], [-0.08104550931727705, 1.2775900612649351]),
    ];
    for (start, slope, expected) in rayoptics {
        let ray = LensRay {
            origin: DVec3::new(start[0], start[1], lens.front_z_mm() - 50.0),
            direction: DVec3::new(slope[0], slope[1], 1.0).normalize(),
        };
        let out = lens.trace(&ray, Direction::ToSensor).expect("passes");
        let behind = out.at_z(lens.rear_z_mm() + 10.0).unwrap();
        assert!(
            (behind.x - expected[0]).abs() < 1e-9 && (behind.y - expected[1]).abs() < 1e-9,
            "{start:?} {slope:?}: {behind} vs rayoptics {expected:?}"
        );
    }
}

/// Files with what lenspath cannot trace are refused with the line and the
/// reason, whatever their encoding.
#[test]
fn unsupported_zemax_files_are_refused_by_line() {
    let cases = [
        (
            "thorlabs-354710-C.zmx",
            "line 84: glass D-ZK3M is in none of lenspath's catalogues",
        ),
        (
            "thorlabs-ASL5040-UV.zmx",
            "line 76: surface type QED_TYPE is not supported (STANDARD, EVENASPH and TOROIDAL are)",
        ),
        ("HoO-V2C18Ex46.zmx", "line 80: surface type COORDBRK is not supported"),
        ("HoO-V2C18Ex03.zmx", "line 86: mirrors are not supported"),
    ];
    for (name, expected) in cases {
        let err = LensPrescription::load(&file(name)).unwrap_err().to_string();
        assert!(err.contains(name) && err.contains(expected), "{name}: {err}");
    }
}

/// Malformed files give one clear error naming the line.
#[test]
fn malformed_zemax_text_names_the_line() {
    let cases: [(&str, &str); 10] = [
        ("SURF 0\n  DISZ INFINITY\nSURF 1\n", "SURF blocks"),
        ("MODE NSC\n", "line 1: only sequential files"),
        ("UNIT FURLONG\n", "line 1: unknown lens unit"),
        (
            "SURF 0\nSURF 1\n  CURV x\nSURF 2\n",
            "line 3: CURV: curvature 'x' is not a finite number",
        ),
        (
            "SURF 0\nSURF 1\n  TYPE EVENASPH\n  PARM 9 1\nSURF 2\n",
            "line 4: EVENASPH has parameters 1 to 8",
        ),
        (
            "SURF 0\nSURF 1\n  TYPE TOROIDAL\n  PARM 1 30\n  PARM 2 1e-4\nSURF 2\n",
            "line 5: TOROIDAL parameter 2 (a profile polynomial term) is not supported",
        ),
        (
            "SURF 0\nSURF 1\n  TYPE TOROIDAL\n  XDAT 1 3 0 0\nSURF 2\n",
            "line 4: TOROIDAL extra data 1 (Zernike terms) is not supported",
        ),
        (
            "SURF 0\nSURF 1\n  TYPE TOROIDAL\n  CONI -1\nSURF 2\n",
            "line 2: a TOROIDAL surface with a conic (-1) is not supported",
        ),
        (
            "SURF 0\nSURF 1\n  DIAM 5\n  GLAS ___BLANK 1 0 0.5 40\n  DISZ 2\nSURF 2\n  DIAM 5\nSURF 3\n",
            "line 4: model glass n_d 0.5",
        ),
        (
            "SURF 0\nSURF 1\n  STOP\n  DIAM 0\nSURF 2\n",
            "line 2: aperture 0 mm must be positive",
        ),
    ];
    for (text, expected) in cases {
        let err = lenspath::lens::zemax::parse(text.as_bytes(), "bad.zmx")
            .unwrap_err()
            .to_string();
        assert!(err.contains("bad.zmx") && err.contains(expected), "{text:?}: {err}");
    }
    // Units: the same lens in inches is 25.4 times the size.
    let lens = |unit: &str| {
        let text = format!(
            "UNIT {unit}\nSURF 0\n  DISZ INFINITY\nSURF 1\n  STOP\n  DIAM 0.4\nSURF 2\n  CURV 0.1\n  DISZ 0.3\n  GLAS ___BLANK 1 0 1.5 60\n  DIAM 1\nSURF 3\n  CURV -0.1\n  DISZ 5\n  DIAM 1\nSURF 4\n"
        );
        let p = lenspath::lens::zemax::parse(text.as_bytes(), "u.zmx").unwrap();
        LensSystem::new(&p).paraxial().unwrap().effective_focal_length_mm
    };
    assert!((lens("IN") / lens("MM") - 25.4).abs() < 1e-9);
}

/// A converted lens written as a table reads back to the same lens.
#[test]
fn converted_lenses_write_back_as_tables() {
    for source in [file("US08427765-1.ZMX"), "lentil:0014".into(), "lentil:0007".into()] {
        let lens = LensPrescription::load(&source).unwrap();
        let again = LensPrescription::parse(&lens.table_text(), &source, TableConvention::ThicknessToNext).unwrap();
        assert_eq!(again.surfaces(), lens.surfaces(), "{source}");
    }
}
