//! The lenses the program ships, by the names every front end takes, each
//! with its source, the focal length that source gives, and the sensor it is
//! listed with. The one list the CLI's `lens --list`, Python's
//! `builtin_lenses()` and the viewer's lens menu show.
//!
//! A lens is shipped when its prescription reproduces its source: the
//! computed focal length within 1% of the source's, and an image circle that
//! reaches the listed sensor's corners (or the listing says it does not: a
//! circular fisheye); a test checks both for every entry. The lentil
//! database's other designs stay readable as `lentil:<id>` but are not
//! shipped, because their tables do not give their patents' focal lengths
//! (paraxial, lenspath and rayoptics agree): 0003 86.19 mm for 100 (the
//! database notes it is unscaled), 0007 25.96 for 25.4, 0008 53.35 for 51.6,
//! 0012 122.18 for 100, 0014 9.71 for 6.0. 0005 is shipped with the patent's
//! third radius (see [`super::lentil`]). Nor are its anamorphic designs:
//! 2004 (US 6,310,731, the one complete anamorphic prime) is 31.488 mm
//! across the sensor's width (rayoptics 31.4876) for the database's 31 (a
//! 1.6% gap that the database's two digits may or may not explain), 60.55 mm
//! across its height, and covers the 22 × 18.6 mm anamorphic frame; 2001 is
//! 4.01 / 8.97 mm for 25.4 (the database notes it is "not in working order"),
//! 2002 is a rear attachment with no stop, and 2003 joins it to 0001 (141.75
//! / 103.45 mm for 100; the attachment stretches the width, not squeezes it).

use super::lentil;
use super::prescription::LensPrescription;
use super::system::LensSystem;
use super::FULL_FRAME_MM;
use crate::error::Result;

/// A lens the program ships.
#[derive(Clone, Debug, PartialEq)]
pub struct ShippedLens {
    /// What `--lens` (and Python, and the viewer) call it.
    pub name: String,
    /// Where the prescription is from.
    pub source: String,
    /// The focal length the source gives, mm.
    pub source_focal_length_mm: f64,
    /// The sensor (width, height, mm) it is listed with.
    pub sensor_mm: (f64, f64),
    /// True for a circular fisheye: its image circle lies inside the sensor,
    /// whose corners stay dark.
    pub image_circle_inside_sensor: bool,
}

/// A built-in table: name, source, the source's focal length (mm), sensor,
/// and whether the image circle lies inside the sensor. The tables' own
/// headers say the same.
type TableListing = (&'static str, &'static str, f64, (f64, f64), bool);

const TABLES: [TableListing; 10] = [
    (
        "dgauss50",
        "double Gauss, Tronnier, US 2,673,491 (Smith, Modern Lens Design, p. 312), scaled to 50 mm",
        50.0,
        FULL_FRAME_MM,
        false,
    ),
    (
        "wide22",
        "38-degree wide angle, Nakamura (Smith, Modern Lens Design, p. 360), scaled to 22 mm",
        22.0,
        FULL_FRAME_MM,
        false,
    ),
    (
        "tele250",
        "super-achromat telephoto, Sigler (Smith, Modern Lens Design, p. 175), scaled to 250 mm",
        250.0,
        FULL_FRAME_MM,
        false,
    ),
    (
        "fisheye10",
        "16 mm f/4 155.9-degree fisheye, Muller (Smith, Modern Lens Design, p. 164), scaled to 10 mm; a circular image",
        10.0,
        FULL_FRAME_MM,
        true,
    ),
    (
        "werfel100",
        "double Gauss f/1.25, Werfel, US 2,771,006 (Smith, Modern Lens Design, p. 304)",
        100.1,
        FULL_FRAME_MM,
        false,
    ),
    (
        "triplet50",
        "Cooke triplet 50 mm f/4, J. Sasian's design (rayoptics model 'Sasian Triplet')",
        50.0,
        FULL_FRAME_MM,
        false,
    ),
    (
        "tessar100",
        "Tessar 100 mm f/5.45, the Zemax sample lens (ISET3d data/lens/zemax)",
        100.0,
        FULL_FRAME_MM,
        false,
    ),
    (
        "asph31",
        "30.8 mm f/2.1 with an even asphere, US 8,427,765 (rayoptics test data)",
        30.8,
        (23.6, 15.6),
        false,
    ),
    (
        "nikon-z14",
        "Nikon Nikkor Z 14-30 mm f/4 S at 14.42 mm, four even aspheres, JP 2019-008031 example 1 (rayoptics test data)",
        14.42,
        FULL_FRAME_MM,
        false,
    ),
    (
        "achromat100",
        "cemented achromat 25 x 100 mm, Edmund Optics #32-327 (rayoptics test data)",
        100.0,
        FULL_FRAME_MM,
        false,
    ),
];

/// The lentil designs shipped, with their sensors: full frame for those
/// scaled to a camera focal length; 0015 and 0016, which the database keeps
/// at the patents' f = 1 mm, with the frame of a 16 mm fisheye and a 35 mm
/// lens scaled the same way.
const LENTIL_SHIPPED: [(&str, (f64, f64)); 11] = [
    ("0001", FULL_FRAME_MM),
    ("0002", FULL_FRAME_MM),
    ("0004", FULL_FRAME_MM),
    ("0005", FULL_FRAME_MM),
    ("0006", FULL_FRAME_MM),
    ("0009", FULL_FRAME_MM),
    ("0010", FULL_FRAME_MM),
    ("0011", FULL_FRAME_MM),
    ("0013", FULL_FRAME_MM),
    ("0015", (36.0 / 16.0, 24.0 / 16.0)),
    ("0016", (36.0 / 35.0, 24.0 / 35.0)),
];

/// Every shipped lens: the built-in tables, then the lentil designs (made
/// once: the viewer and the binding ask often).
pub fn shipped() -> &'static [ShippedLens] {
    static SHIPPED: std::sync::OnceLock<Vec<ShippedLens>> = std::sync::OnceLock::new();
    SHIPPED.get_or_init(shipped_lenses)
}

fn shipped_lenses() -> Vec<ShippedLens> {
    let tables = TABLES
        .iter()
        .map(|&(name, source, focal, sensor_mm, inside)| ShippedLens {
            name: name.to_string(),
            source: source.to_string(),
            source_focal_length_mm: focal,
            sensor_mm,
            image_circle_inside_sensor: inside,
        });
    let entries = lentil::entries();
    let lentil = LENTIL_SHIPPED.iter().map(move |&(id, sensor_mm)| {
        let entry = entries
            .iter()
            .find(|e| e.id == id)
            .expect("shipped lentil ids are in the database (tested)");
        let patent = entry.patent.as_ref().map_or(String::new(), |p| format!(", patent {p}"));
        ShippedLens {
            name: format!("{}{id}", lentil::PREFIX),
            source: format!("{}{patent} (lentil lens database)", entry.title),
            source_focal_length_mm: entry
                .focal_length_mm
                .expect("shipped lentil entries give a focal length (tested)"),
            sensor_mm,
            image_circle_inside_sensor: false,
        }
    });
    tables.chain(lentil).collect()
}

/// True when `name` is a shipped lens's name.
pub fn is_shipped(name: &str) -> bool {
    shipped().iter().any(|l| l.name == name)
}

/// One line of `lenspath lens --list`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LensListing {
    /// Its name.
    pub name: String,
    /// Paraxial effective focal length, mm.
    pub focal_length_mm: f64,
    /// The focal length its source gives, mm.
    pub source_focal_length_mm: f64,
    /// Paraxial f-number wide open.
    pub f_number: f64,
    /// Glass elements (each glass between two surfaces; a cemented doublet is two).
    pub elements: usize,
    /// True when some surface is aspheric.
    pub aspheric: bool,
    /// The sensor it is listed with (width, height, mm).
    pub sensor_mm: (f64, f64),
    /// True for a circular fisheye (the image circle lies inside the sensor).
    pub image_circle_inside_sensor: bool,
    /// Where it is from.
    pub source: String,
}

/// The figures of every shipped lens.
pub fn listing() -> Result<Vec<LensListing>> {
    shipped()
        .iter()
        .map(|lens| {
            let prescription = LensPrescription::load(&lens.name)?;
            let paraxial = LensSystem::new(&prescription).paraxial()?;
            let surfaces = prescription.surfaces();
            Ok(LensListing {
                focal_length_mm: paraxial.effective_focal_length_mm,
                source_focal_length_mm: lens.source_focal_length_mm,
                f_number: paraxial.f_number,
                elements: surfaces.iter().filter(|s| s.ior_d() > 1.0).count(),
                aspheric: surfaces
                    .iter()
                    .any(|s| matches!(s.shape, super::SurfaceShape::EvenAsphere(_))),
                sensor_mm: lens.sensor_mm,
                image_circle_inside_sensor: lens.image_circle_inside_sensor,
                name: lens.name.clone(),
                source: lens.source.clone(),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::BUILTIN_LENSES;

    /// Every built-in table and shipped lentil entry is listed, loads and
    /// images with the focal length its source gives, within 1% (the
    /// issue's bound; the figures are in the module doc).
    #[test]
    fn every_shipped_lens_has_its_sources_focal_length() {
        let listing = listing().unwrap();
        assert!(listing.len() >= 20, "{}", listing.len());
        for (name, _) in BUILTIN_LENSES {
            assert!(listing.iter().any(|l| l.name == name), "{name} is not listed");
        }
        for lens in &listing {
            let off = lens.focal_length_mm / lens.source_focal_length_mm - 1.0;
            assert!(
                off.abs() < 0.01,
                "{}: {} mm for {} mm",
                lens.name,
                lens.focal_length_mm,
                lens.source_focal_length_mm
            );
            assert!(
                lens.f_number > 0.5 && lens.elements >= 2 && !lens.source.is_empty(),
                "{lens:?}"
            );
            assert!(is_shipped(&lens.name));
        }
        let dgauss = &listing[0];
        assert_eq!((dgauss.name.as_str(), dgauss.elements), ("dgauss50", 6));
        assert!(listing.iter().filter(|l| l.aspheric).count() >= 2);
        for unshipped in ["lentil:9993", "lentil:2001", "lentil:0014"] {
            assert!(!is_shipped(unshipped), "{unshipped}");
        }
    }
}
