//! ISET lens files (`.json`): the lens format of ISETCam / isetlens and of
//! ISET3d's pbrt cameras (`omni`, `realistic`).
//!
//! A JSON object whose `surfaces` array lists the surfaces front to back,
//! each with `radius` (mm; 0 for the stop), `thickness` (mm, to the next
//! surface), `ior` (the index behind it: a number, 0 for the stop, or a
//! table `[[wavelengths_nm…], [indices…]]`), `semi_aperture` (mm), and
//! optionally `conic_constant` and `aspheric_coefficients` (A4, A6, … on
//! the conic, as lentil and most lens tables list them) and `transform` (a
//! 4 × 3 column-major matrix, which must be the identity). ISET3d lets
//! `radius`, `conic_constant` and `semi_aperture` be [x, y] pairs for
//! anamorphic surfaces; pairs must be equal here until those are traced.
//! An index table becomes the Abbe model through its d-line index and its V_d
//! (interpolated at the d, F and C lines; a table that does not span 486–656
//! nm gives a constant index at the d line, or its nearest wavelength).

use std::path::Path;

use serde_json::Value;

use super::prescription::{LensPrescription, TableRow};
use super::surface::SurfaceShape;
use crate::error::{Error, Result};
use crate::glass::{C_LINE_NM, D_LINE_NM, F_LINE_NM};

/// Reads the ISET lens file at `path`.
pub fn load(path: &Path) -> Result<LensPrescription> {
    let text = crate::fs::read_text(path, crate::FileKind::Lens)?;
    parse(&text, &path.to_string_lossy())
}

/// Parses an ISET lens file's text; `source` names it in errors.
pub fn parse(text: &str, source: &str) -> Result<LensPrescription> {
    let fail = |message: String| Error::Parse {
        kind: crate::FileKind::Lens,
        path: source.into(),
        message,
    };
    let json: Value = serde_json::from_str(text).map_err(|e| fail(format!("not valid JSON: {e}")))?;
    let surfaces = json
        .get("surfaces")
        .and_then(Value::as_array)
        .ok_or_else(|| fail("no \"surfaces\" array (an ISET lens file lists its surfaces there)".into()))?;
    let rows = surfaces
        .iter()
        .enumerate()
        .map(|(i, surface)| row(surface, &format!("surfaces[{i}]")))
        .collect::<std::result::Result<Vec<_>, String>>()
        .map_err(fail)?;
    LensPrescription::from_rows(source, rows)
}

/// One surface object as a table row; errors name `location` and the key.
fn row(surface: &Value, location: &str) -> std::result::Result<TableRow, String> {
    let number = |key: &str, required: bool| -> std::result::Result<Option<f64>, String> {
        let value = match surface.get(key) {
            None | Some(Value::Null) if !required => return Ok(None),
            None | Some(Value::Null) => return Err(format!("{location}: no \"{key}\"")),
            Some(v) => v,
        };
        let single = |v: &Value| {
            v.as_f64()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("{location}.{key}: {v} is not a finite number"))
        };
        match value {
            Value::Array(pair) if pair.len() == 2 => {
                let (x, y) = (single(&pair[0])?, single(&pair[1])?);
                if x != y {
                    return Err(format!(
                        "{location}.{key}: [{x}, {y}] differs in x and y (an anamorphic surface), which is not traced yet"
                    ));
                }
                Ok(Some(x))
            }
            v => single(v).map(Some),
        }
    };
    if let Some(transform) = surface.get("transform").filter(|t| !t.is_null()) {
        let identity = serde_json::json!([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]);
        let as_numbers = |v: &Value| -> Option<Vec<f64>> {
            v.as_array()?
                .iter()
                .map(|c| {
                    c.as_array()
                        .map(|c| c.iter().filter_map(Value::as_f64).collect::<Vec<_>>())
                })
                .collect::<Option<Vec<_>>>()
                .map(|cols| cols.concat())
        };
        if as_numbers(transform) != as_numbers(&identity) {
            return Err(format!(
                "{location}.transform: a tilted or decentred surface (a transform other than the identity) is not supported"
            ));
        }
    }
    let radius_mm = number("radius", true)?.expect("required");
    let thickness_mm = number("thickness", true)?.expect("required");
    let aperture_diameter_mm = 2.0 * number("semi_aperture", true)?.expect("required");
    let conic = number("conic_constant", false)?.unwrap_or(0.0);
    let terms: Vec<f64> = match surface.get("aspheric_coefficients") {
        None | Some(Value::Null) => Vec::new(),
        Some(Value::Array(a)) => a
            .iter()
            .map(|v| {
                v.as_f64()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| format!("{location}.aspheric_coefficients: {v} is not a finite number"))
            })
            .collect::<std::result::Result<_, _>>()?,
        Some(v) => return Err(format!("{location}.aspheric_coefficients: {v} is not an array")),
    };
    let shape = SurfaceShape::from_terms(conic, 4, &terms).ok_or_else(|| {
        format!(
            "{location}.aspheric_coefficients: {} terms (A4 … A20 is 9 at most)",
            terms.len()
        )
    })?;
    let (ior_d, glass) = index(surface.get("ior"), location)?;
    Ok(TableRow::new(
        location.to_string(),
        radius_mm,
        thickness_mm,
        ior_d,
        aperture_diameter_mm,
        glass,
        shape,
    ))
}

/// The d-line index and glass column of an `ior`: a number or a
/// `[[wavelengths_nm], [indices]]` table.
fn index(ior: Option<&Value>, location: &str) -> std::result::Result<(f64, Option<String>), String> {
    let bad = |what: &str| format!("{location}.ior: {what}");
    match ior {
        None | Some(Value::Null) => Err(bad("missing (0 or 1 for air, the index behind the surface otherwise)")),
        Some(Value::Number(n)) => {
            let n = n.as_f64().filter(|x| x.is_finite()).ok_or_else(|| bad("not finite"))?;
            Ok((n, None))
        }
        Some(Value::Array(table)) if table.len() == 2 => {
            let column = |v: &Value| -> Option<Vec<f64>> { v.as_array()?.iter().map(Value::as_f64).collect() };
            let (Some(nm), Some(n)) = (column(&table[0]), column(&table[1])) else {
                return Err(bad("a table must be [[wavelengths_nm...], [indices...]] of numbers"));
            };
            if nm.len() != n.len() || nm.is_empty() || nm.windows(2).any(|w| w[1] <= w[0]) {
                return Err(bad(
                    "a table needs as many indices as wavelengths, and increasing wavelengths",
                ));
            }
            let at = |wavelength: f64| -> f64 {
                if nm.len() == 1 {
                    return n[0];
                }
                let k = nm.partition_point(|&w| w < wavelength).clamp(1, nm.len() - 1);
                let t = ((wavelength - nm[k - 1]) / (nm[k] - nm[k - 1])).clamp(0.0, 1.0);
                n[k - 1] + t * (n[k] - n[k - 1])
            };
            let n_d = at(D_LINE_NM);
            let spans = nm[0] <= F_LINE_NM && nm[nm.len() - 1] >= C_LINE_NM;
            let v_d = (n_d - 1.0) / (at(F_LINE_NM) - at(C_LINE_NM));
            if spans && n_d > 1.0 && v_d.is_finite() && v_d > 0.0 {
                Ok((n_d, Some(v_d.to_string())))
            } else {
                Ok((n_d, None))
            }
        }
        Some(v) => Err(bad(&format!(
            "{v} is neither a number nor a [[wavelengths_nm], [indices]] table"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::LensSystem;

    /// The surfaces of isetlens's `dgauss.77deg.3.5201mm.json` (ISET/isetlens
    /// `data/lens/`, its layout as written there): the pbrt double Gauss's
    /// prescription scaled to a phone-sized 3.5 mm, which reads surface for
    /// surface as the scaled built-in table.
    const ISETLENS_DGAUSS: &str = r#"{
 "name": "dgauss.22deg.3.0mm",
 "description": " Description: multi element lens Focal length (mm) ",
 "type": "multi element lens",
 "surfaces": [
  {"radius": 2.06033, "thickness": 0.26283, "ior": 1.67, "semi_aperture": 0.88075},
  {"radius": 5.92969, "thickness": 0.00839, "ior": 1, "semi_aperture": 0.88075},
  {"radius": 1.34734, "thickness": 0.28135, "ior": 1.67, "semi_aperture": 0.80386},
  {"radius": 2.84986, "thickness": 0.22893, "ior": 1.699, "semi_aperture": 0.80386},
  {"radius": 0.89124, "thickness": 0.39878, "ior": 1, "semi_aperture": 0.66406},
  {"radius": 0, "thickness": 0.31455, "ior": 0, "semi_aperture": 0.595905},
  {"radius": -1.01321, "thickness": 0.08248, "ior": 1.603, "semi_aperture": 0.59416},
  {"radius": 2.84986, "thickness": 0.42395, "ior": 1.658, "semi_aperture": 0.69901},
  {"radius": -1.42493, "thickness": 0.01328, "ior": 1, "semi_aperture": 0.69901},
  {"radius": 30.55124, "thickness": 0.22508, "ior": 1.717, "semi_aperture": 0.69901},
  {"radius": -2.77716, "thickness": 0, "ior": 1, "semi_aperture": 0.69901}
 ]
}"#;

    #[test]
    fn an_isetlens_file_is_the_scaled_double_gauss() {
        let lens = parse(ISETLENS_DGAUSS, "dgauss.json").unwrap();
        let dgauss = LensPrescription::load("dgauss50").unwrap();
        let scale = 2.06033 / 29.475;
        for (a, b) in lens.surfaces().iter().zip(dgauss.surfaces()) {
            assert!((a.radius_mm - b.radius_mm * scale).abs() < 1e-4, "{a:?} {b:?}");
            assert_eq!(a.ior_d(), b.ior_d());
        }
        let efl = LensSystem::new(&lens).paraxial().unwrap().effective_focal_length_mm;
        let expected = LensSystem::new(&dgauss).paraxial().unwrap().effective_focal_length_mm * scale;
        assert!((efl / expected - 1.0).abs() < 1e-4, "{efl} vs {expected}");
    }

    /// An index table becomes the Abbe model through its d-line index and
    /// V_d; conic and aspheric terms make an even asphere.
    #[test]
    fn index_tables_and_aspheric_terms() {
        // N-BK7 at the F, d and C lines: n_d 1.5168, V_d 64.17.
        let text = r#"{"surfaces": [
            {"radius": 0, "thickness": 1, "ior": 0, "semi_aperture": 5},
            {"radius": 20, "thickness": 3, "semi_aperture": 6, "conic_constant": -0.5,
             "aspheric_coefficients": [1e-5, -2e-8],
             "ior": [[486.1327, 587.5618, 656.2725], [1.52238, 1.51680, 1.51432]]},
            {"radius": [-40, -40], "thickness": 30, "ior": 1, "semi_aperture": [6, 6]}
        ]}"#;
        let lens = parse(text, "t.json").unwrap();
        let glass = lens.surfaces()[1];
        assert!((glass.ior_d() - 1.5168).abs() < 1e-12);
        assert!((glass.medium.abbe_number() - 0.5168 / (1.52238 - 1.51432)).abs() < 1e-9);
        match glass.shape {
            SurfaceShape::EvenAsphere(a) => {
                assert_eq!((a.conic, a.coefficients[1], a.coefficients[2]), (-0.5, 1e-5, -2e-8))
            }
            other => panic!("aspheric, not {other:?}"),
        }
    }

    #[test]
    fn malformed_files_name_the_surface_and_key() {
        let cases = [
            ("{", "not valid JSON"),
            ("{\"lens\": []}", "no \"surfaces\" array"),
            (
                r#"{"surfaces": [{"thickness": 1, "ior": 0, "semi_aperture": 1}]}"#,
                "surfaces[0]: no \"radius\"",
            ),
            (
                r#"{"surfaces": [{"radius": "x", "thickness": 1, "ior": 0, "semi_aperture": 1}]}"#,
                "surfaces[0].radius: \"x\" is not a finite number",
            ),
            (
                r#"{"surfaces": [{"radius": [1, 2], "thickness": 1, "ior": 1.5, "semi_aperture": 1}]}"#,
                "surfaces[0].radius: [1, 2] differs in x and y",
            ),
            (
                r#"{"surfaces": [{"radius": 0, "thickness": 1, "ior": [[500], [1.5, 1.6]], "semi_aperture": 1}]}"#,
                "surfaces[0].ior: a table needs as many indices",
            ),
            (
                r#"{"surfaces": [{"radius": 0, "thickness": 1, "ior": 0, "semi_aperture": 1, "transform": [[1,0,0],[0,1,0],[0,0,1],[0,0.5,0]]}]}"#,
                "surfaces[0].transform: a tilted or decentred surface",
            ),
            (
                r#"{"surfaces": [{"radius": 0, "thickness": 1, "ior": 0, "semi_aperture": 0}]}"#,
                "surfaces[0]: aperture 0 mm must be positive",
            ),
        ];
        for (text, expected) in cases {
            let err = parse(text, "bad.json").unwrap_err().to_string();
            assert!(err.contains("bad.json") && err.contains(expected), "{text}: {err}");
        }
    }
}
