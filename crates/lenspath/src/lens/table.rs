//! The lens table format (pbrt's and CS184's `.dat`): reading one into a
//! [`LensPrescription`] and writing one back, with its older
//! distance-from-previous variant.
//!
//! One row per refracting surface from the front (scene side) to the back
//! (sensor side): curvature radius, thickness to the next surface, index of
//! refraction of the medium behind the surface (n_d, at 587.56 nm), aperture
//! diameter, all in mm. Radius 0 marks the aperture stop (its index column is
//! 0 or 1: air).
//!
//! A glass row may have a fifth column saying how its glass disperses: a
//! catalogue glass name (`N-BK7`, `ohara:S-LAH59`; see [`crate::glass::find`]
//! for the search order), whose own formula is then used (its n_d must agree
//! with the third column within 0.005), or an Abbe number V_d (the two-term
//! Cauchy model through n_d and V_d, [`Dispersion::from_abbe`]). Four-column
//! tables read exactly as before: every glass a constant index.
//!
//! After those columns a row may give its surface an aspheric shape with
//! `key=value` words (the even asphere of [`EvenAsphere`]): `conic=K` for
//! the conic constant and `a2=`, `a4=`, … `a20=` for the polynomial
//! coefficients, in mm^(1−order). A radius of `inf` is a flat surface (radius
//! 0 stays the stop, as in pbrt and CS184 tables). `cylinder=x` or
//! `cylinder=y` makes the surface a cylinder of the row's radius with its
//! axis along x or y (lentil's `cyl-x`, `cyl-y`): `cylinder=y` curves in
//! the horizontal meridian, across the sensor's width. `toric=x:R` (or
//! `toric=y:R`) is that cylinder with its axis bent into an arc of radius R
//! mm, a toric surface ([`Toric`]): it curves with the row's radius in one
//! meridian and with R in the other (Zemax's TOROIDAL, whose profile is the
//! y–z one, is `toric=x:R`).

use super::prescription::{LensPrescription, TableRow, FLAT_RADIUS_MM};
use super::surface::{CylinderAxis, EvenAsphere, SurfaceShape, Toric};
use crate::error::{Error, Result};

/// How a table's second column is to be read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableConvention {
    /// `ThicknessToNext` unless the first row is a surface whose second
    /// column is 0, which only the older convention writes (a front element
    /// cannot be 0 mm thick; a front stop on the first vertex can).
    Auto,
    /// pbrt-v3/v4 and CS184: column 2 is the distance to the next surface.
    ThicknessToNext,
    /// The older unscaled tables (`dgauss.dat`, ...): column 2 is the distance
    /// from the previous surface, 0 on the first row.
    DistanceFromPrevious,
}

impl LensPrescription {
    /// Parses a table; `source` names it in errors.
    pub fn parse(text: &str, source: &str, convention: TableConvention) -> Result<LensPrescription> {
        // A byte-order mark (some Windows editors write one) is not part of line 1.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let fail = |line: usize, message: String| Error::Parse {
            kind: crate::FileKind::Lens,
            path: source.into(),
            message: format!("line {line}: {message}"),
        };
        let mut rows: Vec<TableRow> = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let fields: Vec<&str> = line.split_whitespace().collect();
            let (keyed, plain): (Vec<&str>, Vec<&str>) = fields.iter().partition(|f| f.contains('='));
            if plain.len() != 4 && plain.len() != 5 {
                return Err(fail(
                    i + 1,
                    format!(
                        "expected 4 columns (radius, thickness, index, aperture) and an optional fifth (glass name or Abbe number), found {}",
                        plain.len()
                    ),
                ));
            }
            if fields[..plain.len()].iter().any(|f| f.contains('=')) {
                return Err(fail(
                    i + 1,
                    "aspheric terms (key=value) come after the numeric columns and the glass".into(),
                ));
            }
            let mut row = [0.0; 4];
            for (k, (field, name)) in plain[..4]
                .iter()
                .zip(["radius", "thickness", "index", "aperture"])
                .enumerate()
            {
                let value: f64 = field
                    .parse()
                    .map_err(|_| fail(i + 1, format!("{name} '{field}' is not a number")))?;
                // An infinite radius is a flat; nothing else may be infinite.
                if value.is_nan() || (value.is_infinite() && k != 0) {
                    return Err(fail(i + 1, format!("{name} '{field}' is not finite")));
                }
                row[k] = value;
            }
            let shape = aspheric_terms(&keyed).map_err(|m| fail(i + 1, m))?;
            rows.push(TableRow::new(
                format!("line {}", i + 1),
                row[0],
                row[1],
                row[2],
                row[3],
                plain.get(4).map(|g| g.to_string()),
                shape,
            ));
        }
        let older = match convention {
            TableConvention::Auto => rows.len() > 1 && rows[0].thickness_mm == 0.0 && rows[0].radius_mm != 0.0,
            TableConvention::ThicknessToNext => false,
            TableConvention::DistanceFromPrevious => true,
        };
        if older {
            // Shift column 2 up one row; the last surface gets 0.
            for k in 0..rows.len() {
                rows[k].thickness_mm = rows.get(k + 1).map_or(0.0, |r| r.thickness_mm);
            }
        }
        LensPrescription::from_rows(source, rows)
    }

    /// The table in the pbrt / CS184 convention (thickness to the next
    /// surface), one row per surface with the glass column where one was
    /// given: [`LensPrescription::parse`] with
    /// [`TableConvention::ThicknessToNext`] reads it back to this lens, bit
    /// for bit (numbers are written in their shortest exact form).
    pub fn table_text(&self) -> String {
        self.surfaces
            .iter()
            .zip(&self.columns)
            .map(|(s, (index, glass))| {
                let glass = glass.as_deref().map_or(String::new(), |g| format!(" {g}"));
                let mut terms = String::new();
                if let SurfaceShape::Cylindrical(axis) = &s.shape {
                    terms += &format!(" cylinder={}", axis.spelling());
                }
                if let SurfaceShape::Toric(t) = &s.shape {
                    terms += &format!(" toric={}:{}", t.axis.spelling(), t.rotation_radius_mm);
                }
                if let SurfaceShape::EvenAsphere(a) = &s.shape {
                    if a.conic != 0.0 {
                        terms += &format!(" conic={}", a.conic);
                    }
                    for (value, order) in a.coefficients.iter().zip(EvenAsphere::ORDERS) {
                        if *value != 0.0 {
                            terms += &format!(" a{order}={value:e}");
                        }
                    }
                }
                format!(
                    "{} {} {} {}{glass}{terms}\n",
                    s.radius_mm, s.thickness_mm, index, s.aperture_diameter_mm
                )
            })
            .collect()
    }
}

/// The shape that a row's `key=value` words give its surface: spherical
/// when there are none.
fn aspheric_terms(words: &[&str]) -> std::result::Result<SurfaceShape, String> {
    if words.is_empty() {
        return Ok(SurfaceShape::Spherical);
    }
    if let [word] = words {
        if let Some(axis) = word.strip_prefix("cylinder=") {
            return CylinderAxis::from_spelling(axis)
                .map(SurfaceShape::Cylindrical)
                .ok_or_else(|| format!("cylinder={axis}: the cylinder's axis is x or y"));
        }
        if let Some(value) = word.strip_prefix("toric=") {
            return toric_of(value);
        }
    }
    let mut asphere = EvenAsphere::SPHERE;
    let mut seen: Vec<&str> = Vec::new();
    for word in words {
        let (key, value) = word.split_once('=').expect("keyed words contain '='");
        let shape = match key {
            "cylinder" => Some("cylindrical"),
            "toric" => Some("toric"),
            _ => None,
        };
        if let Some(shape) = shape {
            return Err(format!("a {shape} surface takes no aspheric terms"));
        }
        let number: f64 = value
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| format!("aspheric term {key} = '{value}' is not a finite number"))?;
        if seen.contains(&key) {
            return Err(format!("aspheric term {key} is given twice"));
        }
        seen.push(key);
        let slot = match key {
            "conic" => &mut asphere.conic,
            _ => {
                let order = key.strip_prefix('a').and_then(|o| o.parse::<u32>().ok());
                match order.and_then(|o| EvenAsphere::ORDERS.iter().position(|&x| x == o)) {
                    Some(index) => &mut asphere.coefficients[index],
                    None => {
                        return Err(format!(
                            "unknown aspheric term '{key}' (conic, a2, a4, ... a20 are known)"
                        ))
                    }
                }
            }
        };
        *slot = number;
    }
    Ok(SurfaceShape::EvenAsphere(asphere))
}

/// The shape `toric=AXIS:RADIUS` gives (`value` is what follows `toric=`):
/// a cylinder when the rotation radius is infinite (or a flat's huge one).
fn toric_of(value: &str) -> std::result::Result<SurfaceShape, String> {
    let usage = "write toric=AXIS:RADIUS (the axis x or y, the rotation radius in mm)";
    let (axis, radius) = value.split_once(':').ok_or_else(|| format!("toric={value}: {usage}"))?;
    let axis = CylinderAxis::from_spelling(axis).ok_or_else(|| format!("toric={value}: the axis is x or y"))?;
    let rotation_radius_mm: f64 = radius
        .parse()
        .ok()
        .filter(|r: &f64| !r.is_nan() && *r != 0.0)
        .ok_or_else(|| format!("toric={value}: the rotation radius '{radius}' is not a nonzero number of mm"))?;
    if rotation_radius_mm.abs() >= FLAT_RADIUS_MM {
        return Ok(SurfaceShape::Cylindrical(axis));
    }
    Ok(SurfaceShape::Toric(Toric {
        axis,
        rotation_radius_mm,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comments_crlf_and_any_whitespace() {
        let text = "# a lens\r\n  10.0\t2  1.5   8\r\n-10 \t 1 1 8\r\n0 5 0 4\r\n";
        let lens = LensPrescription::parse(text, "t", TableConvention::Auto).unwrap();
        assert_eq!(lens.surfaces.len(), 3);
        assert_eq!(lens.surfaces[1].radius_mm, -10.0);
        assert_eq!(lens.surfaces[2].ior_d(), 1.0);
    }

    #[test]
    fn a_front_stop_on_the_first_vertex_is_not_the_older_convention() {
        // A cemented achromat with its stop on the front vertex, as lens files give them.
        let table = "0 0 0 24\n61.47 6 1.5168 24\n-44.64 2.5 1.6727 24\n-129.94 95.95 1 24\n";
        let lens = LensPrescription::parse(table, "t", TableConvention::Auto).unwrap();
        let thicknesses: Vec<f64> = lens.surfaces.iter().map(|s| s.thickness_mm).collect();
        assert_eq!(thicknesses, [0.0, 6.0, 2.5, 95.95]);
    }

    /// A byte-order mark before line 1 is ignored, and a flat written as a
    /// huge radius (1e20, as some tables do) is the same lens as `inf`.
    #[test]
    fn a_byte_order_mark_and_huge_radii_read_as_intended() {
        let flat = "50 5 1.5 20\n0 5 0 18\ninf 40 1 20\n";
        let reference = LensPrescription::parse(flat, "a", TableConvention::Auto).unwrap();
        for table in [
            format!("\u{feff}# made on Windows\n{flat}"),
            flat.replace("inf", "1e20"),
            flat.replace("inf", "-1e18"),
        ] {
            let lens = LensPrescription::parse(&table, "b", TableConvention::Auto).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(lens.surfaces.len(), 3);
            assert_eq!(lens.surfaces[2].curvature(), 0.0, "{table}");
            assert_eq!(
                lens.surfaces.iter().map(|s| s.thickness_mm).collect::<Vec<_>>(),
                reference.surfaces.iter().map(|s| s.thickness_mm).collect::<Vec<_>>()
            );
        }
    }

    #[test]
    fn older_convention_shifts_the_distances() {
        let newer = "10 2 1.5 8\n-10 3 1 8\n0 0 0 4\n";
        let older = "10 0 1.5 8\n-10 2 1 8\n0 3 0 4\n";
        let a = LensPrescription::parse(newer, "a", TableConvention::Auto).unwrap();
        let b = LensPrescription::parse(older, "b", TableConvention::Auto).unwrap();
        assert_eq!(a.surfaces, b.surfaces);
    }

    /// A table written back by `table_text` reads as the same lens, glass
    /// columns, older conventions, toric surfaces and built-ins included.
    #[test]
    fn table_text_reads_back_to_the_same_lens() {
        let older = "# r axpos n ap\n20 0 1.5 10\n-20 3 1 10\n0 2 0 6\n";
        let aspheric =
            "0 1 0 20\n12.5 4 1.5168 20 N-BK7 conic=-0.6 a4=1.25e-5 a20=-3e-31\ninf 2 1 20 a2=0.001 a6=7e-9\n";
        let tables = [
            LensPrescription::parse(aspheric, "aspheric", TableConvention::ThicknessToNext).unwrap(),
            crate::lens::lentil::load("0014").unwrap(),
            crate::lens::lentil::load("2004").unwrap(),
            LensPrescription::load("dgauss50").unwrap(),
            LensPrescription::parse(older, "older", TableConvention::Auto).unwrap(),
            LensPrescription::parse(
                "0 4 0 20\n40 6 1.62 24 toric=x:25.125\n-30 2.5 1.72 24 toric=y:-55\n-90 30 1 24\n",
                "toric",
                TableConvention::ThicknessToNext,
            )
            .unwrap(),
            LensPrescription::parse(
                "61.07 4 1.5168 25 N-BK7\n-44.17 2.5 1.6727 25 schott:SF5\n-128.89 1 1 25\n0 5 0 20\n",
                "achromat",
                TableConvention::ThicknessToNext,
            )
            .unwrap(),
        ];
        for lens in tables {
            let text = lens.table_text();
            let again = LensPrescription::parse(&text, lens.name(), TableConvention::ThicknessToNext).unwrap();
            assert_eq!(again, lens, "{text}");
        }
    }
}
