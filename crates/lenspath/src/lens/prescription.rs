//! Lens prescriptions: the pbrt / CS184 table format, its older
//! distance-from-previous variant, validation and the built-in lenses.
//!
//! One row per refracting surface from the front (scene side) to the back
//! (sensor side): curvature radius, thickness to the next surface, index of
//! refraction of the medium behind the surface, aperture diameter, all in mm.
//! Radius 0 marks the aperture stop (its index column is 0 or 1: air).

use std::path::Path;

use crate::error::{Error, Result};

/// One surface of a prescription.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensSurface {
    /// Signed radius of curvature in mm: positive when the centre of curvature
    /// lies behind the vertex (toward the sensor); 0 for the aperture stop.
    pub radius_mm: f64,
    /// Axial distance from this surface's vertex to the next one's, in mm
    /// (the last surface's value is not used: the sensor is placed by focusing).
    pub thickness_mm: f64,
    /// Index of refraction of the medium behind the surface (1 = air).
    pub ior: f64,
    /// Clear aperture diameter in mm.
    pub aperture_diameter_mm: f64,
}

impl LensSurface {
    /// True for the aperture stop.
    pub fn is_stop(&self) -> bool {
        self.radius_mm == 0.0
    }
}

/// How a table's second column is to be read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableConvention {
    /// `ThicknessToNext` unless the first row's second column is 0, which
    /// only the older convention writes (a front element cannot be 0 mm thick).
    Auto,
    /// pbrt-v3/v4 and CS184: column 2 is the distance to the next surface.
    ThicknessToNext,
    /// The older unscaled tables (`dgauss.dat`, ...): column 2 is the distance
    /// from the previous surface, 0 on the first row.
    DistanceFromPrevious,
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
}

/// Built-in lenses: name, table (the published prescriptions scaled as pbrt ships them).
pub const BUILTIN_LENSES: [(&str, &str); 4] = [
    ("dgauss50", include_str!("../../lenses/dgauss50.dat")),
    ("wide22", include_str!("../../lenses/wide22.dat")),
    ("tele250", include_str!("../../lenses/tele250.dat")),
    ("fisheye10", include_str!("../../lenses/fisheye10.dat")),
];

impl LensPrescription {
    /// A built-in lens by name, or else the table file at `name_or_path`.
    pub fn load(name_or_path: &str) -> Result<LensPrescription> {
        if let Some((name, table)) = BUILTIN_LENSES.iter().find(|(n, _)| *n == name_or_path) {
            return LensPrescription::parse(table, name, TableConvention::ThicknessToNext);
        }
        let path = Path::new(name_or_path);
        if !path.exists() {
            let names: Vec<&str> = BUILTIN_LENSES.iter().map(|(n, _)| *n).collect();
            return Err(Error::InvalidArgument(format!(
                "unknown lens '{name_or_path}': not a built-in lens ({}) nor an existing file",
                names.join(", ")
            )));
        }
        let text = crate::io::read_text(path, crate::FileKind::Lens)?;
        LensPrescription::parse(&text, name_or_path, TableConvention::Auto)
    }

    /// Parses a table; `source` names it in errors.
    pub fn parse(text: &str, source: &str, convention: TableConvention) -> Result<LensPrescription> {
        let fail = |line: usize, message: String| Error::Parse {
            kind: crate::FileKind::Lens,
            path: source.into(),
            message: format!("line {line}: {message}"),
        };
        // Rows: (line number, four numbers).
        let mut rows: Vec<(usize, [f64; 4])> = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let fields: Vec<&str> = line.split_whitespace().collect();
            if fields.len() != 4 {
                return Err(fail(
                    i + 1,
                    format!(
                        "expected 4 columns (radius, thickness, index, aperture), found {}",
                        fields.len()
                    ),
                ));
            }
            let mut row = [0.0; 4];
            for (k, (field, name)) in fields
                .iter()
                .zip(["radius", "thickness", "index", "aperture"])
                .enumerate()
            {
                let value: f64 = field
                    .parse()
                    .map_err(|_| fail(i + 1, format!("{name} '{field}' is not a number")))?;
                if !value.is_finite() {
                    return Err(fail(i + 1, format!("{name} '{field}' is not finite")));
                }
                row[k] = value;
            }
            rows.push((i + 1, row));
        }
        if rows.is_empty() {
            return Err(Error::Parse {
                kind: crate::FileKind::Lens,
                path: source.into(),
                message: "no surfaces".into(),
            });
        }
        let older = match convention {
            TableConvention::Auto => rows.len() > 1 && rows[0].1[1] == 0.0,
            TableConvention::ThicknessToNext => false,
            TableConvention::DistanceFromPrevious => true,
        };
        if older {
            // Shift column 2 up one row; the last surface gets 0.
            for k in 0..rows.len() {
                rows[k].1[1] = rows.get(k + 1).map_or(0.0, |r| r.1[1]);
            }
        }

        let mut surfaces = Vec::with_capacity(rows.len());
        let mut stop_line: Option<usize> = None;
        for &(line, [radius_mm, thickness_mm, ior, aperture_diameter_mm]) in &rows {
            if aperture_diameter_mm <= 0.0 {
                return Err(fail(
                    line,
                    format!("aperture {aperture_diameter_mm} mm must be positive"),
                ));
            }
            if thickness_mm < 0.0 {
                return Err(fail(line, format!("thickness {thickness_mm} mm is negative")));
            }
            let ior = if radius_mm == 0.0 {
                if let Some(first) = stop_line {
                    return Err(fail(
                        line,
                        format!("a second aperture stop (the first is on line {first})"),
                    ));
                }
                stop_line = Some(line);
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
                if aperture_diameter_mm > 2.0 * radius_mm.abs() {
                    return Err(fail(
                        line,
                        format!(
                            "aperture {aperture_diameter_mm} mm is wider than its sphere (radius {} mm)",
                            radius_mm.abs()
                        ),
                    ));
                }
                ior
            };
            surfaces.push(LensSurface {
                radius_mm,
                thickness_mm,
                ior,
                aperture_diameter_mm,
            });
        }
        let (last_line, last) = (rows[rows.len() - 1].0, surfaces[surfaces.len() - 1]);
        if last.ior != 1.0 {
            return Err(fail(
                last_line,
                format!(
                    "the last surface must leave the light in air (index 1) for the sensor, not {}",
                    last.ior
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
                    thickness_mm: s.thickness_mm * factor,
                    ior: s.ior,
                    aperture_diameter_mm: s.aperture_diameter_mm * factor,
                })
                .collect(),
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
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_err(text: &str) -> String {
        LensPrescription::parse(text, "test.dat", TableConvention::Auto)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn builtins_parse_with_one_stop() {
        for (name, _) in BUILTIN_LENSES {
            let lens = LensPrescription::load(name).unwrap();
            assert!(lens.surfaces.len() >= 7, "{name}");
            assert!(lens.surfaces[lens.stop_index()].is_stop());
        }
    }

    #[test]
    fn a_lens_file_that_is_not_text_is_named_in_the_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("binary.dat");
        std::fs::write(&path, b"50.0 5.0 1.5 20.0\n\xff\xfe 1 1 8\n").unwrap();
        let err = LensPrescription::load(path.to_str().unwrap()).unwrap_err().to_string();
        assert!(
            err.contains("binary.dat") && err.contains("not UTF-8 text (byte 18"),
            "{err}"
        );
    }

    #[test]
    fn comments_crlf_and_any_whitespace() {
        let text = "# a lens\r\n  10.0\t2  1.5   8\r\n-10 \t 1 1 8\r\n0 5 0 4\r\n";
        let lens = LensPrescription::parse(text, "t", TableConvention::Auto).unwrap();
        assert_eq!(lens.surfaces.len(), 3);
        assert_eq!(lens.surfaces[1].radius_mm, -10.0);
        assert_eq!(lens.surfaces[2].ior, 1.0);
    }

    #[test]
    fn older_convention_shifts_the_distances() {
        let newer = "10 2 1.5 8\n-10 3 1 8\n0 0 0 4\n";
        let older = "10 0 1.5 8\n-10 2 1 8\n0 3 0 4\n";
        let a = LensPrescription::parse(newer, "a", TableConvention::Auto).unwrap();
        let b = LensPrescription::parse(older, "b", TableConvention::Auto).unwrap();
        assert_eq!(a.surfaces, b.surfaces);
    }

    #[test]
    fn bad_tables_name_the_line_and_the_fault() {
        let cases = [
            ("10 2 1.5\n0 1 0 4\n", "line 1: expected 4 columns"),
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
        ];
        for (text, expected) in cases {
            let err = parse_err(text);
            assert!(
                err.contains("test.dat") && err.contains(expected),
                "{err:?} should contain {expected:?}"
            );
        }
    }

    #[test]
    fn unknown_lens_name_lists_the_builtins() {
        let err = LensPrescription::load("no-such-lens").unwrap_err().to_string();
        assert!(err.contains("dgauss50") && err.contains("fisheye10"), "{err}");
    }
}
