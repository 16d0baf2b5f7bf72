//! Lens prescriptions: the pbrt / CS184 table format, its older
//! distance-from-previous variant, validation and the built-in lenses.
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

use std::path::Path;

use super::surface::{CylinderAxis, EvenAsphere, Meridian, SurfaceShape, Toric};
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
    /// A built-in lens by name, an entry of the lentil database
    /// (`lentil:0004`, [`super::lentil`]), or else the file at `name_or_path`:
    /// a Zemax `.zmx` ([`super::zemax`]), an ISET `.json` ([`super::iset`])
    /// or a lens table.
    pub fn load(name_or_path: &str) -> Result<LensPrescription> {
        if let Some(id) = name_or_path.strip_prefix(super::lentil::PREFIX) {
            return super::lentil::load(id);
        }
        let extension = Path::new(name_or_path)
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
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
        match extension.as_deref() {
            Some("zmx") => return super::zemax::load(path),
            Some("json") => return super::iset::load(path),
            _ => {}
        }
        let text = crate::io::read_text(path, crate::FileKind::Lens)?;
        LensPrescription::parse(&text, name_or_path, TableConvention::Auto)
    }

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

    fn parse_err(text: &str) -> String {
        LensPrescription::parse(text, "test.dat", TableConvention::Auto)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn builtins_parse_with_one_stop() {
        for (name, table) in BUILTIN_LENSES {
            let lens = LensPrescription::load(name).unwrap();
            // Every row read (the cemented achromat has four, the others seven or more).
            let rows = table
                .lines()
                .filter(|l| !l.trim().is_empty() && !l.trim().starts_with('#'))
                .count();
            assert!(lens.surfaces.len() == rows && rows >= 4, "{name}");
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

    #[test]
    fn unknown_lens_name_lists_the_builtins() {
        let err = LensPrescription::load("no-such-lens").unwrap_err().to_string();
        assert!(err.contains("dgauss50") && err.contains("fisheye10"), "{err}");
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
