//! Zemax OpticStudio sequential lens files (`.zmx`): the subset lens
//! makers and patent collections publish.
//!
//! Read: `UNIT` (MM, CM, IN, METER), and per `SURF` block `TYPE` (STANDARD,
//! EVENASPH or TOROIDAL), `CURV` (curvature, 1/unit), `DISZ` (thickness to
//! the next surface), `GLAS`, `DIAM` (semi-diameter), `CONI` (conic
//! constant), `PARM k` (EVENASPH: the coefficient of r^2k; TOROIDAL: 1 is
//! the radius of rotation, 0 for a cylinder) and `STOP`. A TOROIDAL surface
//! is read with a circular profile only: a conic, profile polynomial terms
//! (PARM 2–9) or Zernike terms (XDAT) on it are refused. Other commands (notes,
//! fields, wavelengths, tolerances, coatings, drawing) do not change the
//! lens and are skipped; anything that would change it and is not read here
//! (other surface types, mirrors, non-sequential mode) is refused, naming
//! the line. Files may be UTF-8 or UTF-16 (OpticStudio writes either).
//!
//! How a file becomes a prescription: surface 0 (the object) and the last
//! (the image) are dropped; a glass is its catalogue formula when one of
//! lenspath's catalogues has its name (or its `N-` successor, or the part
//! before an `_` as in `L-TIM28_MOLD`), a model glass (solve type 1, or
//! `___BLANK`) the Abbe model through the n_d and V_d its line gives, and a
//! glass no catalogue has is refused, by name (the n_d and V_d on its line
//! are whatever a model glass last left there);
//! flat surfaces with air on both sides and no stop do nothing and are
//! dropped; a stop on a curved surface becomes a flat stop of that
//! surface's semi-diameter at its vertex, or at its rim when the surface
//! bulges forward (as a lens mount is), because lenspath's stop is a flat
//! disc of its own.

use std::path::Path;

use super::prescription::{LensPrescription, TableRow};
use super::surface::{CylinderAxis, SurfaceShape, Toric};
use crate::error::{Error, Result};
use crate::glass;

/// A `GLAS` line: the name, n_d and V_d when it is a model glass, its line.
struct ZGlass {
    name: String,
    model: Option<(f64, f64)>,
    line: usize,
}

/// One `SURF` block as read.
#[derive(Default)]
struct ZSurface {
    /// The line of its `SURF`.
    line: usize,
    curvature: f64,
    thickness: f64,
    glass: Option<ZGlass>,
    semi_diameter: f64,
    conic: f64,
    aspheric: bool,
    /// A TOROIDAL surface: its profile in the y–z plane swept round an axis
    /// parallel to y, PARM 1 (the radius of rotation) behind the vertex.
    toroidal: bool,
    /// PARM 1..8: EVENASPH's coefficients of r², r⁴, …, r¹⁶; TOROIDAL's
    /// radius of rotation in PARM 1.
    parm: [f64; 8],
    stop: bool,
}

/// Reads the `.zmx` file at `path`.
pub fn load(path: &Path) -> Result<LensPrescription> {
    let bytes = std::fs::read(path).map_err(|e| crate::fs::io_error(path, e))?;
    parse(&bytes, &path.to_string_lossy())
}

/// The text of a file OpticStudio wrote: UTF-16 (little or big endian,
/// with its byte-order mark) or else UTF-8, invalid bytes replaced (they
/// can only be in names and notes, which are not read).
fn decode(bytes: &[u8]) -> String {
    let utf16 = |big_endian: bool| {
        let units: Vec<u16> = bytes[2..]
            .chunks_exact(2)
            .map(|c| match big_endian {
                true => u16::from_be_bytes([c[0], c[1]]),
                false => u16::from_le_bytes([c[0], c[1]]),
            })
            .collect();
        String::from_utf16_lossy(&units)
    };
    match bytes {
        [0xFF, 0xFE, ..] => utf16(false),
        [0xFE, 0xFF, ..] => utf16(true),
        [0xEF, 0xBB, 0xBF, rest @ ..] => String::from_utf8_lossy(rest).into_owned(),
        _ => String::from_utf8_lossy(bytes).into_owned(),
    }
}

/// Parses a `.zmx` file's bytes; `source` names it in errors.
pub fn parse(bytes: &[u8], source: &str) -> Result<LensPrescription> {
    let fail = |line: usize, message: String| Error::Parse {
        kind: crate::FileKind::Lens,
        path: source.into(),
        message: format!("line {line}: {message}"),
    };
    let text = decode(bytes);
    let mut unit_mm = 1.0;
    let mut surfaces: Vec<ZSurface> = Vec::new();
    let mut in_surface = false;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let words: Vec<&str> = raw.split_whitespace().collect();
        let Some(&command) = words.first() else {
            continue;
        };
        let indented = raw.starts_with([' ', '\t']);
        let number = |k: usize, what: &str| -> Result<f64> {
            let word = words
                .get(k)
                .ok_or_else(|| fail(line, format!("{command} has no {what}")))?;
            if *word == "INFINITY" {
                return Ok(f64::INFINITY);
            }
            word.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| fail(line, format!("{command}: {what} '{word}' is not a finite number")))
        };
        if !indented {
            in_surface = false;
            match command {
                "SURF" => {
                    surfaces.push(ZSurface {
                        line,
                        ..ZSurface::default()
                    });
                    in_surface = true;
                }
                "MODE" if words.get(1) != Some(&"SEQ") => {
                    return Err(fail(line, "only sequential files (MODE SEQ) are lenses".into()));
                }
                "UNIT" => {
                    unit_mm = match words.get(1).copied() {
                        Some("MM") => 1.0,
                        Some("CM") => 10.0,
                        Some("IN") => 25.4,
                        Some("METER" | "M") => 1000.0,
                        other => {
                            return Err(fail(
                                line,
                                format!("unknown lens unit {other:?} (MM, CM, IN, METER are known)"),
                            ))
                        }
                    }
                }
                _ => {}
            }
            continue;
        }
        let Some(surface) = surfaces.last_mut().filter(|_| in_surface) else {
            continue;
        };
        match command {
            "TYPE" => match words.get(1).copied() {
                Some("STANDARD") => (surface.aspheric, surface.toroidal) = (false, false),
                Some("EVENASPH") => (surface.aspheric, surface.toroidal) = (true, false),
                Some("TOROIDAL") => (surface.aspheric, surface.toroidal) = (false, true),
                other => {
                    return Err(fail(
                        line,
                        format!(
                            "surface type {} is not supported (STANDARD, EVENASPH and TOROIDAL are)",
                            other.unwrap_or("(none)")
                        ),
                    ))
                }
            },
            "CURV" => surface.curvature = number(1, "curvature")?,
            "DISZ" => surface.thickness = number(1, "thickness")?,
            "DIAM" => surface.semi_diameter = number(1, "semi-diameter")?,
            "CONI" => surface.conic = number(1, "conic constant")?,
            "STOP" => surface.stop = true,
            "PARM" => {
                let k = number(1, "parameter number")?;
                let value = number(2, "value")?;
                if surface.aspheric {
                    if !((1.0..=8.0).contains(&k) && k.fract() == 0.0) {
                        return Err(fail(line, format!("EVENASPH has parameters 1 to 8, not {k}")));
                    }
                    surface.parm[k as usize - 1] = value;
                }
                if surface.toroidal && k == 1.0 {
                    surface.parm[0] = value;
                } else if surface.toroidal && value != 0.0 {
                    return Err(fail(
                        line,
                        format!("TOROIDAL parameter {k} (a profile polynomial term) is not supported: lenspath's toric profile is a circle"),
                    ));
                }
            }
            // TOROIDAL's extra data: 1 is its number of Zernike terms, 2 their
            // normalisation radius, from 3 on the terms.
            "XDAT" if surface.toroidal => {
                let k = number(1, "extra data number")?;
                let value = number(2, "value")?;
                if k != 2.0 && value != 0.0 {
                    return Err(fail(
                        line,
                        format!("TOROIDAL extra data {k} (Zernike terms) is not supported: lenspath's toric profile is a circle"),
                    ));
                }
            }
            "GLAS" => {
                let name = words.get(1).copied().unwrap_or("");
                if name == "MIRROR" {
                    return Err(fail(line, "mirrors are not supported (a lens refracts)".into()));
                }
                // A model glass (solve type 1, or the name ___BLANK) is its
                // n_d and V_d; for a catalogue glass those fields are stale.
                let model = words.get(2) == Some(&"1") || name == "___BLANK";
                let model = model
                    .then(|| Ok::<_, Error>((number(4, "n_d")?, number(5, "V_d")?)))
                    .transpose()?;
                surface.glass = Some(ZGlass {
                    name: name.to_string(),
                    model,
                    line,
                });
            }
            _ => {}
        }
    }
    if surfaces.len() < 3 {
        return Err(Error::Parse {
            kind: crate::FileKind::Lens,
            path: source.into(),
            message: format!(
                "{} SURF blocks: a lens needs the object, at least one surface and the image",
                surfaces.len()
            ),
        });
    }
    let lens_surfaces = &surfaces[1..surfaces.len() - 1];
    let has_stop = lens_surfaces.iter().any(|s| s.stop);
    let mut rows: Vec<TableRow> = Vec::new();
    let mut in_glass = false;
    for (k, s) in lens_surfaces.iter().enumerate() {
        // OpticStudio's default stop is surface 1.
        let stop = s.stop || (!has_stop && k == 0);
        let location = format!("line {}", s.line);
        let (ior_d, glass_column) = match &s.glass {
            Some(g) => glass_of(&g.name, g.model).map_err(|m| fail(g.line, m))?,
            None => (1.0, None),
        };
        let glass_behind = ior_d != 1.0;
        // STANDARD surfaces have a conic only; PARMs count on EVENASPH.
        let terms: &[f64] = if s.aspheric { &s.parm } else { &[] };
        let shape = match s.toroidal {
            true if s.conic != 0.0 => {
                return Err(fail(
                    s.line,
                    format!(
                        "a TOROIDAL surface with a conic ({}) is not supported: lenspath's toric profile is a circle",
                        s.conic
                    ),
                ))
            }
            // A radius of rotation of 0 is infinite: a cylinder, its axis along x.
            true if s.parm[0] == 0.0 && s.curvature != 0.0 => SurfaceShape::Cylindrical(CylinderAxis::X),
            true if s.parm[0] == 0.0 => SurfaceShape::Spherical,
            true => SurfaceShape::Toric(Toric {
                axis: CylinderAxis::X,
                rotation_radius_mm: s.parm[0],
            }),
            false => SurfaceShape::from_terms(s.conic, 2, terms).expect("eight terms from h² fit"),
        }
        .scaled(unit_mm);
        let radius_mm = if s.curvature == 0.0 {
            f64::INFINITY
        } else {
            unit_mm / s.curvature
        };
        let (thickness_mm, aperture_diameter_mm) = (s.thickness * unit_mm, 2.0 * s.semi_diameter * unit_mm);
        let flat = s.curvature == 0.0 && shape == SurfaceShape::Spherical;
        if flat && stop && !glass_behind && !in_glass {
            rows.push(TableRow::new(
                location,
                0.0,
                thickness_mm,
                1.0,
                aperture_diameter_mm,
                None,
                shape,
            ));
            continue;
        }
        if flat && !stop && !glass_behind && !in_glass {
            // Air on both sides: nothing happens here.
            if let Some(previous) = rows.last_mut() {
                previous.thickness_mm += thickness_mm;
            }
            continue;
        }
        if stop {
            if in_glass {
                return Err(fail(
                    s.line,
                    "the stop is inside glass (on a cemented surface), which lenspath's flat stop cannot be".into(),
                ));
            }
            // A flat stop at the vertex, or at the rim when the surface bulges forward.
            let rim_sag = shape
                .sag(1.0 / radius_mm, 0.25 * aperture_diameter_mm * aperture_diameter_mm)
                .unwrap_or(0.0);
            let ahead = (-rim_sag).max(0.0);
            if let Some(previous) = rows.last_mut() {
                if previous.thickness_mm < ahead {
                    return Err(fail(
                        s.line,
                        "no room in front of the stop surface for its flat stop".into(),
                    ));
                }
                previous.thickness_mm -= ahead;
            }
            rows.push(TableRow::new(
                format!("{location} (its stop)"),
                0.0,
                ahead,
                1.0,
                aperture_diameter_mm,
                None,
                SurfaceShape::Spherical,
            ));
        }
        rows.push(TableRow::new(
            location,
            radius_mm,
            thickness_mm,
            ior_d,
            aperture_diameter_mm,
            glass_column,
            shape,
        ));
        in_glass = glass_behind;
    }
    LensPrescription::from_rows(source, rows)
}

/// The index at the d line and the glass column for a `GLAS` line: a model
/// glass's (n_d, V_d), or the catalogue glass of its name.
fn glass_of(name: &str, model: Option<(f64, f64)>) -> std::result::Result<(f64, Option<String>), String> {
    if let Some((n_d, v_d)) = model {
        if !(n_d >= 1.0 && v_d > 0.0) {
            return Err(format!(
                "model glass n_d {n_d}, V_d {v_d}: n_d must be at least 1 and V_d positive"
            ));
        }
        return Ok((n_d, (n_d > 1.0).then(|| v_d.to_string())));
    }
    glass::find_as_written(name)
        .next()
        .map(|found| (found.dispersion.n_d(), Some(format!("{}:{}", found.maker, found.name))))
        .ok_or_else(|| {
            format!(
                "glass {name} is in none of lenspath's catalogues ({}); put a catalogue glass or a model glass (n_d, V_d) in its place",
                glass::MAKERS.join(", ")
            )
        })
}
