//! Lens prescriptions: the lens model every format's reader produces
//! (surfaces from front to back, each with its shape, thickness, medium
//! and clear aperture), its validation ([`LensPrescription::from_rows`],
//! one for every format) and the built-in lenses. The table format itself
//! is [`super::table`]'s.

use super::surface::{Meridian, SurfaceShape, Toric};
use crate::error::{Error, Result};
use crate::glass::{self, Dispersion};

/// One row of a table as read, before validation: what
/// [`LensPrescription::from_rows`] builds a lens from.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TableRow {
    /// Where the row came from, for errors ("line 4", "surface 7").
    pub location: String,
    /// Signed vertex radius, mm (0: the stop; infinite: a flat).
    pub radius_mm: f64,
    /// Distance to the next surface's vertex, mm.
    pub thickness_mm: f64,
    /// Index behind the surface at the d line (0 or 1 for air).
    pub ior_d: f64,
    /// Clear aperture diameter, mm.
    pub aperture_diameter_mm: f64,
    /// The glass column: a catalogue name or an Abbe number.
    pub glass: Option<String>,
    /// Its shape beyond the vertex radius.
    pub shape: SurfaceShape,
}

/// Radii at least this large (mm) are flats: over a 100 mm aperture such a
/// sphere departs from its tangent plane by less than a nanometre.
pub const FLAT_RADIUS_MM: f64 = 1e10;

impl TableRow {
    /// A row with these columns, read at `location`.
    pub(crate) fn new(
        location: String,
        radius_mm: f64,
        thickness_mm: f64,
        ior_d: f64,
        aperture_diameter_mm: f64,
        glass: Option<String>,
        shape: SurfaceShape,
    ) -> TableRow {
        TableRow {
            location,
            radius_mm,
            thickness_mm,
            ior_d,
            aperture_diameter_mm,
            glass,
            shape,
        }
    }
}

/// One surface of a prescription.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensSurface {
    /// Signed radius of curvature in mm at the vertex: positive when the
    /// centre of curvature lies behind the vertex (toward the sensor); 0 for
    /// the aperture stop, infinite for a flat.
    pub radius_mm: f64,
    /// Its shape beyond the vertex radius (spherical unless aspheric).
    pub shape: SurfaceShape,
    /// Axial distance from this surface's vertex to the next one's, in mm
    /// (the last surface's value is not used: the sensor is placed by focusing).
    pub thickness_mm: f64,
    /// The medium behind the surface: its index against wavelength
    /// (`Dispersion::Constant(1.0)` for air).
    pub medium: Dispersion,
    /// Clear aperture diameter in mm.
    pub aperture_diameter_mm: f64,
}

impl LensSurface {
    /// True for the aperture stop.
    pub fn is_stop(&self) -> bool {
        self.radius_mm == 0.0
    }

    /// Index of refraction of the medium behind the surface at the d line.
    pub fn ior_d(&self) -> f64 {
        self.medium.n_d()
    }

    /// Vertex curvature, 1/mm (0 for the stop and flats).
    pub fn curvature(&self) -> f64 {
        if self.radius_mm == 0.0 {
            0.0
        } else {
            1.0 / self.radius_mm
        }
    }

    /// Sag (mm, toward the sensor) at `height_mm` from the axis in
    /// `meridian` (a cylinder is flat in the one it does not curve in);
    /// `None` where the surface does not reach.
    pub fn sag_mm(&self, height_mm: f64, meridian: Meridian) -> Option<f64> {
        match self.shape {
            SurfaceShape::Cylindrical(axis) if axis.curved_meridian() != meridian => Some(0.0),
            SurfaceShape::Toric(toric) => {
                let point = meridian.across() * height_mm;
                toric
                    .sag_and_gradient(self.curvature(), point.x, point.y)
                    .map(|(z, _, _)| z)
            }
            _ => self.shape.sag(self.curvature(), height_mm * height_mm),
        }
    }
}

/// A lens: its surfaces from front to back. Only [`LensPrescription::parse`]
/// and [`LensPrescription::load`] make one, so every prescription has been
/// validated (one stop, sane numbers, air behind the last surface).
#[derive(Clone, Debug, PartialEq)]
pub struct LensPrescription {
    /// Where it came from (a built-in name or a file path).
    pub(crate) name: String,
    /// Surfaces from the scene side to the sensor side.
    pub(crate) surfaces: Vec<LensSurface>,
    /// Each surface's index column and glass column as the table gave them
    /// (what [`LensPrescription::table_text`] writes back).
    pub(crate) columns: Vec<(f64, Option<String>)>,
}

/// Built-in lens tables: name, table. The first four are the textbook
/// prescriptions pbrt and the CS184 course ship; [`super::library`] lists
/// every one with its source.
pub const BUILTIN_LENSES: [(&str, &str); 10] = [
    ("dgauss50", include_str!("../../lenses/dgauss50.dat")),
    ("wide22", include_str!("../../lenses/wide22.dat")),
    ("tele250", include_str!("../../lenses/tele250.dat")),
    ("fisheye10", include_str!("../../lenses/fisheye10.dat")),
    ("werfel100", include_str!("../../lenses/werfel100.dat")),
    ("triplet50", include_str!("../../lenses/triplet50.dat")),
    ("tessar100", include_str!("../../lenses/tessar100.dat")),
    ("asph31", include_str!("../../lenses/asph31.dat")),
    ("nikon-z14", include_str!("../../lenses/nikon-z14.dat")),
    ("achromat100", include_str!("../../lenses/achromat100.dat")),
];

impl LensPrescription {
    /// A lens from rows already read (by [`LensPrescription::parse`] or an
    /// importer of another format), validated; errors name `source` and the
    /// row's location.
    pub(crate) fn from_rows(source: &str, rows: Vec<TableRow>) -> Result<LensPrescription> {
        let fail = |location: &str, message: String| Error::Parse {
            kind: crate::FileKind::Lens,
            path: source.into(),
            message: format!("{location}: {message}"),
        };
        if rows.is_empty() {
            return Err(Error::Parse {
                kind: crate::FileKind::Lens,
                path: source.into(),
                message: "no surfaces".into(),
            });
        }

        let mut surfaces = Vec::with_capacity(rows.len());
        let columns = rows.iter().map(|r| (r.ior_d, r.glass.clone())).collect();
        let mut stop_line: Option<&str> = None;
        for row in &rows {
            let line = row.location.as_str();
            let (radius_mm, thickness_mm, ior, aperture_diameter_mm, shape) = (
                row.radius_mm,
                row.thickness_mm,
                row.ior_d,
                row.aperture_diameter_mm,
                row.shape,
            );
            let glass_column = row.glass.as_deref();
            if aperture_diameter_mm <= 0.0 {
                return Err(fail(
                    line,
                    format!("aperture {aperture_diameter_mm} mm must be positive"),
                ));
            }
            if thickness_mm < 0.0 {
                return Err(fail(line, format!("thickness {thickness_mm} mm is negative")));
            }
            // What a table's reader already refuses, for every other reader too.
            for (name, value) in [
                ("thickness", thickness_mm),
                ("index", ior),
                ("aperture", aperture_diameter_mm),
            ] {
                if !value.is_finite() {
                    return Err(fail(line, format!("{name} {value} is not finite")));
                }
            }
            if radius_mm.is_nan() {
                return Err(fail(line, "radius is not a number".into()));
            }
            // Tables write a flat as a huge radius too (1e20, 1e18): its
            // sphere's centre is beyond what f64 can intersect with.
            let radius_mm = if radius_mm.abs() >= FLAT_RADIUS_MM {
                f64::INFINITY.copysign(radius_mm)
            } else {
                radius_mm
            };
            if glass_column.is_some() && ior <= 1.0 {
                return Err(fail(
                    line,
                    "a fifth column (glass name or Abbe number) belongs only on rows with glass behind them (index above 1)".into(),
                ));
            }
            let ior = if radius_mm == 0.0 {
                if let Some(first) = stop_line {
                    return Err(fail(line, format!("a second aperture stop (the first is on {first})")));
                }
                stop_line = Some(line);
                if shape != SurfaceShape::Spherical {
                    return Err(fail(line, "the aperture stop cannot be aspheric".into()));
                }
                // The stop sits in air; tables write 0 or 1.
                if ior != 0.0 && ior != 1.0 {
                    return Err(fail(
                        line,
                        format!("the aperture stop must be in air (index 0 or 1), not {ior}"),
                    ));
                }
                1.0
            } else {
                if ior < 1.0 {
                    return Err(fail(line, format!("index of refraction {ior} is below 1")));
                }
                // A cylinder's curved section is its radius's circle too.
                let spherical = matches!(shape, SurfaceShape::Spherical | SurfaceShape::Cylindrical(_));
                if spherical && aperture_diameter_mm > 2.0 * radius_mm.abs() {
                    return Err(fail(
                        line,
                        format!(
                            "aperture {aperture_diameter_mm} mm is wider than its sphere (radius {} mm)",
                            radius_mm.abs()
                        ),
                    ));
                }
                if let SurfaceShape::Toric(toric) = shape {
                    if !toric_reaches(&toric, radius_mm, 0.5 * aperture_diameter_mm) {
                        return Err(fail(
                            line,
                            format!(
                                "aperture {aperture_diameter_mm} mm is wider than the toric surface (radius {radius_mm} mm, rotation radius {} mm) reaches",
                                toric.rotation_radius_mm
                            ),
                        ));
                    }
                } else if !spherical
                    && shape
                        .sag(1.0 / radius_mm, 0.25 * aperture_diameter_mm * aperture_diameter_mm)
                        .is_none()
                {
                    return Err(fail(
                        line,
                        format!(
                            "aperture {aperture_diameter_mm} mm is wider than the asphere's base conic (radius {radius_mm} mm) reaches"
                        ),
                    ));
                }
                ior
            };
            let medium = match glass_column {
                None => Dispersion::Constant(ior),
                Some(column) => medium_of(column, ior).map_err(|m| fail(line, m))?,
            };
            surfaces.push(LensSurface {
                radius_mm,
                shape,
                thickness_mm,
                medium,
                aperture_diameter_mm,
            });
        }
        let (last_line, last) = (rows[rows.len() - 1].location.as_str(), surfaces[surfaces.len() - 1]);
        if last.medium != Dispersion::Constant(1.0) {
            return Err(fail(
                last_line,
                format!(
                    "the last surface must leave the light in air (index 1) for the sensor, not {}",
                    last.ior_d()
                ),
            ));
        }
        if stop_line.is_none() {
            return Err(Error::Parse {
                kind: crate::FileKind::Lens,
                path: source.into(),
                message: "no aperture stop (a row with radius 0)".into(),
            });
        }
        Ok(LensPrescription {
            name: source.to_string(),
            surfaces,
            columns,
        })
    }

    /// The same lens with every length multiplied by `factor`.
    pub fn scaled(&self, factor: f64) -> LensPrescription {
        LensPrescription {
            name: format!("{} x{factor}", self.name),
            surfaces: self
                .surfaces
                .iter()
                .map(|s| LensSurface {
                    radius_mm: s.radius_mm * factor,
                    shape: s.shape.scaled(factor),
                    thickness_mm: s.thickness_mm * factor,
                    medium: s.medium,
                    aperture_diameter_mm: s.aperture_diameter_mm * factor,
                })
                .collect(),
            columns: self.columns.clone(),
        }
    }

    /// Where it came from (a built-in name or a file path).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Surfaces from the scene side to the sensor side.
    pub fn surfaces(&self) -> &[LensSurface] {
        &self.surfaces
    }

    /// Index of the aperture stop.
    pub fn stop_index(&self) -> usize {
        self.surfaces.iter().position(LensSurface::is_stop).expect("validated")
    }

    /// True when some glass's index changes with wavelength (a fifth column).
    pub fn is_dispersive(&self) -> bool {
        self.surfaces.iter().any(|s| !s.medium.is_constant())
    }

    /// False for an anamorphic lens: one with a cylindrical surface.
    pub fn is_rotationally_symmetric(&self) -> bool {
        self.surfaces.iter().all(|s| s.shape.is_rotationally_symmetric())
    }
}

/// Whether the toric surface of vertex radius `radius_mm` is defined over
/// its whole aperture, of radius `aperture_radius_mm`: its profile circle
/// reaches the rim and every swept circle is wider than the aperture there
/// (checked on the rim, where both are tightest, every 1/256 turn).
fn toric_reaches(toric: &Toric, radius_mm: f64, aperture_radius_mm: f64) -> bool {
    let curvature = if radius_mm.is_finite() { 1.0 / radius_mm } else { 0.0 };
    (0..256).all(|k| {
        let angle = k as f64 * std::f64::consts::TAU / 256.0;
        let (x, y) = (aperture_radius_mm * angle.cos(), aperture_radius_mm * angle.sin());
        toric.sag_and_gradient(curvature, x, y).is_some()
    })
}

/// The most a named glass's n_d may differ from the table's index column.
pub(crate) const GLASS_ND_TOLERANCE: f64 = 5e-3;

/// The medium a table's fifth column names, behind a surface whose index
/// column says `n_d`: an Abbe number, or a catalogue glass.
fn medium_of(column: &str, n_d: f64) -> std::result::Result<Dispersion, String> {
    if let Ok(v_d) = column.parse::<f64>() {
        return Dispersion::from_abbe(n_d, v_d).map_err(|e| e.to_string());
    }
    let found = glass::find(column).map_err(|e| e.to_string())?;
    let catalogue_n_d = found.dispersion.n_d();
    if (catalogue_n_d - n_d).abs() > GLASS_ND_TOLERANCE {
        return Err(format!(
            "glass {}:{} has n_d {catalogue_n_d:.5}, but the index column says {n_d}",
            found.maker, found.name
        ));
    }
    Ok(found.dispersion)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::TableConvention;

    fn parse_err(text: &str) -> String {
        LensPrescription::parse(text, "test.dat", TableConvention::Auto)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn bad_tables_name_the_line_and_the_fault() {
        let cases = [
            ("10 2 1.5\n0 1 0 4\n", "line 1: expected 4 columns"),
            ("10 2 1.5 8 N-BK7 x\n0 1 0 4\n", "line 1: expected 4 columns"),
            ("10 2 1.5 8 N-BK8\n0 1 0 4\n", "line 1: unknown glass 'N-BK8'"),
            (
                "10 2 1.6 8 N-BK7\n0 1 0 4\n",
                "line 1: glass schott:N-BK7 has n_d 1.51680",
            ),
            ("10 2 1.5 8 -3\n0 1 0 4\n", "line 1: V_d must be a positive Abbe number"),
            ("10 2 1.5 8\n-10 1 1 8 N-BK7\n0 1 0 4\n", "line 2: a fifth column"),
            ("10 2 glass 8\n0 1 0 4\n", "line 1: index 'glass' is not a number"),
            ("10 2 NaN 8\n0 1 0 4\n", "line 1: index 'NaN' is not finite"),
            ("10 2 1.5 0\n0 1 0 4\n", "line 1: aperture 0 mm must be positive"),
            ("10 2 1.5 -3\n0 1 0 4\n", "line 1: aperture -3 mm must be positive"),
            (
                "# c\n10 2 1.5 30\n0 1 0 4\n",
                "line 2: aperture 30 mm is wider than its sphere",
            ),
            ("10 2 1.5 8\n-10 1 1 8\n", "no aperture stop"),
            (
                "0 2 0 8\n10 1 1.5 8\n0 1 0 4\n",
                "line 3: a second aperture stop (the first is on line 1)",
            ),
            ("10 2 0.5 8\n0 1 0 4\n", "line 1: index of refraction 0.5 is below 1"),
            ("10 -2 1.5 8\n0 1 0 4\n", "line 1: thickness -2 mm is negative"),
            (
                "0 1 0 4\n10 2 1.5 8\n",
                "line 2: the last surface must leave the light in air",
            ),
            ("# nothing\n", "no surfaces"),
            (
                "10 2 1.5 8 cylinder=z\n0 1 0 4\n",
                "line 1: cylinder=z: the cylinder's axis is x or y",
            ),
            (
                "10 2 1.5 8 cylinder=x a4=1e-5\n0 1 0 4\n",
                "line 1: a cylindrical surface takes no aspheric terms",
            ),
            (
                "10 2 1.5 30 cylinder=y\n0 1 0 4\n",
                "line 1: aperture 30 mm is wider than its sphere",
            ),
            (
                "10 2 1.5 8 toric=x\n0 1 0 4\n",
                "line 1: toric=x: write toric=AXIS:RADIUS",
            ),
            (
                "10 2 1.5 8 toric=z:30\n0 1 0 4\n",
                "line 1: toric=z:30: the axis is x or y",
            ),
            (
                "10 2 1.5 8 toric=x:0\n0 1 0 4\n",
                "line 1: toric=x:0: the rotation radius '0' is not a nonzero number of mm",
            ),
            (
                "10 2 1.5 8 toric=x:30 conic=-1\n0 1 0 4\n",
                "line 1: a toric surface takes no aspheric terms",
            ),
            (
                "30 2 1.5 20 toric=y:6\n0 1 0 4\n",
                "line 1: aperture 20 mm is wider than the toric surface (radius 30 mm, rotation radius 6 mm) reaches",
            ),
            (
                "10 2 1.5 8 a4=x\n0 1 0 4\n",
                "line 1: aspheric term a4 = 'x' is not a finite number",
            ),
            (
                "10 2 1.5 8 a4=inf\n0 1 0 4\n",
                "line 1: aspheric term a4 = 'inf' is not a finite number",
            ),
            ("10 2 1.5 8 a5=1\n0 1 0 4\n", "line 1: unknown aspheric term 'a5'"),
            (
                "10 2 1.5 8 a4=1 a4=2\n0 1 0 4\n",
                "line 1: aspheric term a4 is given twice",
            ),
            (
                "10 2 conic=1 1.5 8\n0 1 0 4\n",
                "line 1: aspheric terms (key=value) come after",
            ),
            (
                "10 2 1.5 8\n0 1 0 4 a4=1e-5\n",
                "line 2: the aperture stop cannot be aspheric",
            ),
            (
                "10 2 1.5 19 conic=4\n0 1 0 4\n",
                "line 1: aperture 19 mm is wider than the asphere's base conic",
            ),
            ("10 inf 1.5 8\n0 1 0 4\n", "line 1: thickness 'inf' is not finite"),
        ];
        for (text, expected) in cases {
            let err = parse_err(text);
            assert!(
                err.contains("test.dat") && err.contains(expected),
                "{err:?} should contain {expected:?}"
            );
        }
    }

    /// A fifth column gives a glass its dispersion; four columns keep the
    /// constant index they always had.
    #[test]
    fn glass_column_gives_dispersion() {
        let text = "30 4 1.5168 20 N-BK7\n-30 2 1.6727 20 32.2\n-80 1 1 20\n0 5 0 10\n";
        let lens = LensPrescription::parse(text, "t", TableConvention::Auto).unwrap();
        assert!(lens.is_dispersive());
        let bk7 = &lens.surfaces[0].medium;
        assert!((bk7.index(486.1327) - 1.52238).abs() < 1e-5);
        let flint = &lens.surfaces[1].medium;
        assert!((flint.n_d() - 1.6727).abs() < 1e-12 && (flint.abbe_number() - 32.2).abs() < 1e-9);
        let plain =
            LensPrescription::parse("30 4 1.5168 20\n-80 1 1 20\n0 5 0 10\n", "t", TableConvention::Auto).unwrap();
        assert!(!plain.is_dispersive());
        assert_eq!(plain.surfaces[0].medium, Dispersion::Constant(1.5168));
    }
}
