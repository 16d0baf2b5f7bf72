//! The lentil lens database (Zeno Pelgrims' lentil, `polynomial-optics/
//! database/lenses.json`, MIT): 24 designs from patents, each surface with
//! its radius, thickness, n_d, V_d, glass name and semi-diameter. It is
//! embedded (`lenses/lentil/`, with its licence) and read as `lentil:0004`.
//!
//! How its fields become a prescription: the patent's surfaces
//! (`optical-elements-patent`) front to back; `housing-radius` is a
//! semi-diameter; `material` `iris` is the stop, `air` (or no index) air;
//! a glass takes its catalogue formula when the maker's catalogues know its
//! name (or its `N-` successor) with an n_d within 0.005 of the table's,
//! else the Abbe model through its n_d and V_d; radii of 99999 mm and more
//! are the database's flats; a housing wider than its surface's hemisphere
//! is cut to the hemisphere. `aspherical-equation` holds A4, A6, A8, A10 on a
//! sphere (conic 0), as lentil's own tracer reads it. Where the database
//! departs from its patent and the patent's figures show it (one radius of
//! 0005), the patent's value is read. `cyl-x` and `cyl-y` (the anamorphic
//! designs 2001–2004) are cylinders with their axis along x or y, as lentil's
//! own tracer reads them (`cyl-y` curves in the x–z plane).

use std::collections::BTreeMap;
use std::sync::OnceLock;

use serde::Deserialize;

use super::prescription::{LensPrescription, TableRow, GLASS_ND_TOLERANCE};
use super::surface::{CylinderAxis, SurfaceShape};
use crate::error::{Error, Result};
use crate::glass;

/// The database, as lentil publishes it.
const DATABASE: &str = include_str!("../../lenses/lentil/lenses.json");

/// What `lentil:` prefixes a database id with.
pub const PREFIX: &str = "lentil:";

/// Radii at least this large are the database's way of writing a flat.
const FLAT_RADIUS_MM: f64 = 99_999.0;

/// Radii read differently from the database (id, surface from 1, radius
/// mm). 0005's third surface: the database changed the patent's 58.28 mm to
/// 40.28 after comparing it with the patent's drawing (its `notes-to-self`);
/// with the patent's value the lens has the patent's focal length (14.28 mm
/// for 14.2; 15.32 with the database's).
const CORRECTED_RADII: [(&str, usize, f64); 1] = [("0005", 3, 58.28)];

/// One database entry (the fields read here).
#[derive(Deserialize)]
struct Entry {
    company: Option<String>,
    #[serde(rename = "product-name")]
    product_name: Option<String>,
    year: Option<serde_json::Value>,
    #[serde(rename = "patent-number")]
    patent_number: Option<String>,
    #[serde(rename = "focal-length-mm-patent")]
    focal_length_mm_patent: Option<f64>,
    #[serde(rename = "optical-elements-patent")]
    elements: Vec<Element>,
}

/// One surface of an entry.
#[derive(Deserialize)]
struct Element {
    radius: f64,
    thickness: f64,
    ior: Option<f64>,
    abbe: Option<f64>,
    material: Option<String>,
    #[serde(rename = "housing-radius")]
    housing_radius: f64,
    #[serde(rename = "lens-geometry")]
    geometry: String,
    #[serde(rename = "aspherical-equation")]
    aspherical_equation: Option<Vec<f64>>,
}

/// What the database says about one lens besides its surfaces.
#[derive(Clone, Debug, PartialEq)]
pub struct LentilEntry {
    /// The id, as `lentil:` takes it ("0004").
    pub id: String,
    /// "maker product-name year", as the database gives them.
    pub title: String,
    /// The patent the prescription is from, when the database names one.
    pub patent: Option<String>,
    /// The focal length the database gives (most designs are scaled to 100 mm).
    pub focal_length_mm: Option<f64>,
    /// Whether it has cylindrical surfaces.
    pub anamorphic: bool,
}

/// The database, parsed once (a test reads every entry).
fn database() -> &'static BTreeMap<String, Entry> {
    static DATABASE_ENTRIES: OnceLock<BTreeMap<String, Entry>> = OnceLock::new();
    DATABASE_ENTRIES.get_or_init(|| serde_json::from_str(DATABASE).expect("the embedded lentil database parses"))
}

/// Every entry of the database, in id order.
pub fn entries() -> Vec<LentilEntry> {
    database()
        .iter()
        .map(|(id, e)| {
            let year = e.year.as_ref().map(|y| y.to_string()).unwrap_or_default();
            let title = [
                e.company.as_deref().unwrap_or("unknown"),
                e.product_name.as_deref().unwrap_or(""),
                &year,
            ]
            .iter()
            .filter(|s| !s.is_empty())
            .copied()
            .collect::<Vec<_>>()
            .join(" ");
            let anamorphic = e.elements.iter().any(|el| el.geometry.starts_with("cyl-"));
            LentilEntry {
                id: id.clone(),
                title,
                patent: e.patent_number.clone().filter(|p| !p.is_empty()),
                focal_length_mm: e.focal_length_mm_patent,
                anamorphic,
            }
        })
        .collect()
}

/// The lens `lentil:<id>` names.
pub fn load(id: &str) -> Result<LensPrescription> {
    let source = format!("{PREFIX}{id}");
    let Some(entry) = database().get(id) else {
        let ids: Vec<&str> = database().keys().map(String::as_str).collect();
        return Err(Error::InvalidArgument(format!(
            "unknown lens '{source}': the lentil database has {}",
            ids.join(", ")
        )));
    };
    let mut rows = entry
        .elements
        .iter()
        .enumerate()
        .map(|(i, element)| row(element, &format!("surface {}", i + 1)))
        .collect::<std::result::Result<Vec<_>, String>>()
        .map_err(|message| Error::Parse {
            kind: crate::FileKind::Lens,
            path: source.clone().into(),
            message,
        })?;
    for (corrected_id, surface, radius_mm) in CORRECTED_RADII {
        if corrected_id == id {
            rows[surface - 1].radius_mm = radius_mm;
        }
    }
    LensPrescription::from_rows(&source, rows)
}

/// One database surface as a table row.
fn row(element: &Element, location: &str) -> std::result::Result<TableRow, String> {
    let material = element.material.as_deref().unwrap_or("air");
    let stop = material.eq_ignore_ascii_case("iris");
    let cylinder_axis = element
        .geometry
        .strip_prefix("cyl-")
        .and_then(CylinderAxis::from_spelling);
    let shape = match (element.geometry.as_str(), cylinder_axis) {
        (_, Some(axis)) => SurfaceShape::Cylindrical(axis),
        ("spherical", _) => SurfaceShape::Spherical,
        ("aspherical", _) => {
            let terms = element.aspherical_equation.as_deref().unwrap_or(&[]);
            if terms.len() > 4 {
                return Err(format!(
                    "{location}: {} aspheric terms (lentil gives A4, A6, A8, A10)",
                    terms.len()
                ));
            }
            SurfaceShape::from_terms(0.0, 4, terms).expect("four terms from h⁴ fit")
        }
        (other, None) => {
            return Err(format!(
                "{location}: unknown lens geometry '{other}' (spherical, aspherical, cyl-x and cyl-y are known)"
            ))
        }
    };
    let radius_mm = if stop {
        0.0
    } else if element.radius.abs() >= FLAT_RADIUS_MM {
        f64::INFINITY
    } else {
        element.radius
    };
    let in_air = stop || material.eq_ignore_ascii_case("air") || element.ior.is_none_or(|n| n == 1.0);
    let (ior_d, glass) = if in_air {
        (1.0, None)
    } else {
        let n_d = element.ior.expect("checked above");
        (n_d, glass_column(material, n_d, element.abbe))
    };
    // A housing wider than its hemisphere (0015's) holds the glass by its
    // rim: the clear aperture is the whole hemisphere.
    let aperture_diameter_mm = match shape {
        SurfaceShape::Spherical | SurfaceShape::Cylindrical(_) if !stop => {
            (2.0 * element.housing_radius).min(2.0 * radius_mm.abs())
        }
        _ => 2.0 * element.housing_radius,
    };
    Ok(TableRow::new(
        location.to_string(),
        radius_mm,
        element.thickness,
        ior_d,
        aperture_diameter_mm,
        glass,
        shape,
    ))
}

/// The glass column for `material`: its catalogue name when a catalogue
/// knows it (or its lead-free `N-` successor) at this n_d, else the Abbe
/// number, else nothing (a constant index).
fn glass_column(material: &str, n_d: f64, abbe: Option<f64>) -> Option<String> {
    let known = glass::find_as_written(material)
        .find(|g| (g.dispersion.n_d() - n_d).abs() <= GLASS_ND_TOLERANCE)
        .map(|g| g.name.to_string());
    known.or_else(|| abbe.filter(|v| *v > 0.0).map(|v| v.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::{Direction, LensRay, LensSystem, Meridian};
    use glam::DVec3;

    /// Every entry reads and traces (but 9994, one of lentil's test
    /// entries, and 2002, a rear anamorphic attachment, which have no stop); the four with cylinders are the
    /// anamorphic ones, with a focal length of their own in each meridian.
    #[test]
    fn every_entry_reads_and_the_cylindrical_ones_are_anamorphic() {
        let mut read = 0;
        for entry in entries() {
            match load(&entry.id) {
                Ok(lens) => {
                    let system = LensSystem::new(&lens);
                    let [h, v] = Meridian::BOTH.map(|m| system.paraxial_in(m).unwrap().effective_focal_length_mm);
                    assert!(h.is_finite() && h != 0.0 && v.is_finite(), "{}: {h} {v}", entry.id);
                    assert_eq!(entry.anamorphic, !lens.is_rotationally_symmetric(), "{}", entry.id);
                    assert_eq!(
                        entry.anamorphic,
                        (h - v).abs() > 1e-3 * h.abs(),
                        "{}: {h} {v}",
                        entry.id
                    );
                    read += 1;
                }
                Err(e) if ["9991", "9994", "2002"].contains(&entry.id.as_str()) => {
                    assert!(e.to_string().contains("no aperture stop"), "{e}")
                }
                Err(e) => panic!("{}: {e}", entry.id),
            }
        }
        assert_eq!(read, 21);
        assert_eq!(entries().iter().filter(|e| e.anamorphic).count(), 5);
    }

    /// 0014, the aspheric fisheye (A4–A10 on four surfaces), against
    /// rayoptics 0.9.8 given the same surfaces (`EvenPolynomial` profiles;
    /// `bench/peers/lens_vs_rayoptics.py`): paraxial EFL and BFL, and where
    /// real rays from 50 mm in front of the front vertex (height there, angle
    /// to the axis) cross the plane 10 mm behind the rear vertex.
    #[test]
    fn the_aspheric_fisheye_traces_as_rayoptics_does() {
        let lens = LensSystem::new(&load("0014").unwrap());
        let p = lens.paraxial().unwrap();
        assert!((p.effective_focal_length_mm - 9.70923672367538).abs() < 1e-11, "{p:?}");
        assert!((p.back_focal_distance_mm - 14.012334366854805).abs() < 1e-11, "{p:?}");
        let rayoptics = [
            (0.5, 0.0, 0.20669124563489527),
            (2.0, 0.0, 0.8638586234056271),
            (-4.0, 20.0, 3.3348646847284926),
            (-12.0, 40.0, 5.441903328107687),
            (-8.0, 40.0, 6.886265613262266),
            (-16.0, 60.0, 9.551730985383196),
        ];
        // The same surfaces as spheres, to show the aspheric terms matter.
        let mut spherical = load("0014").unwrap();
        for s in &mut spherical.surfaces {
            s.shape = SurfaceShape::Spherical;
        }
        let spherical = LensSystem::new(&spherical);
        let mut largest_aspheric_effect: f64 = 0.0;
        for (height_mm, angle_deg, expected) in rayoptics {
            let a = f64::to_radians(angle_deg);
            let ray = LensRay {
                origin: DVec3::new(height_mm - a.tan() * 50.0, 0.0, lens.front_z_mm() - 50.0),
                direction: DVec3::new(a.sin(), 0.0, a.cos()),
            };
            let at = |system: &LensSystem| {
                let out = system.trace(&ray, Direction::ToSensor).expect("passes");
                out.at_z(system.rear_z_mm() + 10.0).unwrap().x
            };
            let ours = at(&lens);
            assert!(
                (ours - expected).abs() < 1e-9,
                "{height_mm} mm, {angle_deg}°: {ours} vs rayoptics {expected}"
            );
            largest_aspheric_effect = largest_aspheric_effect.max((at(&spherical) - ours).abs());
        }
        assert!(largest_aspheric_effect > 0.05, "{largest_aspheric_effect}");
    }

    /// 2004, the anamorphic prime (US 6,310,731; its cylinders curve in the
    /// x–z plane), against rayoptics 0.9.8 given the same surfaces (`XToroid`
    /// profiles with no sweep curvature; `bench/peers/lens_vs_rayoptics.py`):
    /// where skew rays from 50 mm in front of the front vertex cross the plane
    /// 10 mm behind the rear vertex, and the focal length in each meridian
    /// from a parallel ray 0.01 mm off the axis (paraxial here).
    #[test]
    fn the_anamorphic_prime_traces_as_rayoptics_does() {
        let lens = LensSystem::new(&load("2004").unwrap());
        let rayoptics = [
            ([3.0, 0.0], [0.0, 0.0], [3.1880515713126054, 0.0]),
            ([0.0, 3.0], [0.0, 0.0], [0.0, 1.6541723478410686]),
            ([2.0, -3.0], [0.03, 0.05], [5.926202663951171, 4.297583202441968]),
            ([-6.0, 4.0], [0.06, -0.03], [1.1588391027594482, -1.3569003412306446]),
            ([5.0, 5.0], [-0.08, -0.04], [-4.720651558119784, -1.9894628425375611]),
        ];
        for (start, slope, expected) in rayoptics {
            let mut hits = Vec::new();
            let out = lens.trace_visiting(&LensRay::skew(&lens, start, slope), Direction::ToSensor, |p| {
                hits.push(p)
            });
            let out = out.unwrap_or_else(|| panic!("{start:?} {slope:?} blocked: {hits:?}"));
            let behind = out.at_z(lens.rear_z_mm() + 10.0).unwrap();
            assert!(
                (behind.x - expected[0]).abs() < 1e-9 && (behind.y - expected[1]).abs() < 1e-9,
                "{start:?} {slope:?}: {behind} vs rayoptics {expected:?}"
            );
        }
        for (meridian, expected) in Meridian::BOTH.into_iter().zip([31.4876161486975, 60.55456794643544]) {
            let efl = lens.paraxial_in(meridian).unwrap().effective_focal_length_mm;
            assert!((efl - expected).abs() < 1e-5, "{meridian:?}: {efl} vs {expected}");
        }
    }

    #[test]
    fn an_unknown_id_lists_the_database() {
        let e = load("7777").unwrap_err().to_string();
        assert!(
            e.contains("lentil:7777") && e.contains("0001") && e.contains("2004"),
            "{e}"
        );
    }
}
