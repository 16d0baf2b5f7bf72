//! The lenses the program ships, by the names every front end takes: the
//! built-in tables and the lentil database's designs, each with its source.
//! The one list the CLI's `lens --list`, Python's `builtin_lenses()` and the
//! viewer's lens menu show.

use super::lentil;
use super::prescription::{LensPrescription, BUILTIN_LENSES};
use super::system::LensSystem;
use crate::error::Result;

/// Where each built-in table is from (the tables' own headers say the same).
const BUILTIN_SOURCES: [(&str, &str); 4] = [
    (
        "dgauss50",
        "double Gauss, Tronnier, US 2,673,491 (Smith, Modern Lens Design, p. 312), scaled to 50 mm",
    ),
    (
        "wide22",
        "38-degree wide angle, Nakamura (Smith, Modern Lens Design, p. 360), scaled to 22 mm",
    ),
    (
        "tele250",
        "super-achromat telephoto, Sigler (Smith, Modern Lens Design, p. 175), scaled to 250 mm",
    ),
    (
        "fisheye10",
        "16 mm f/4 155.9-degree fisheye, Muller (Smith, Modern Lens Design, p. 164), scaled to 10 mm",
    ),
];

/// The lentil ids from here on are its tests, not designs (its legend).
const LENTIL_TEST_IDS_FROM: &str = "9000";

/// A lens the program ships.
#[derive(Clone, Debug, PartialEq)]
pub struct ShippedLens {
    /// What `--lens` (and Python, and the viewer) call it.
    pub name: String,
    /// Where the prescription is from.
    pub source: String,
}

/// Every shipped lens, built-ins first: the lentil designs whose surfaces
/// lenspath traces (not its test entries, nor, yet, its anamorphics).
pub fn shipped() -> Result<Vec<ShippedLens>> {
    let mut lenses: Vec<ShippedLens> = BUILTIN_SOURCES
        .iter()
        .map(|(name, source)| ShippedLens {
            name: name.to_string(),
            source: source.to_string(),
        })
        .collect();
    for entry in lentil::entries()? {
        if entry.id.as_str() >= LENTIL_TEST_IDS_FROM || entry.unsupported_geometry.is_some() {
            continue;
        }
        let patent = entry.patent.map_or(String::new(), |p| format!(", patent {p}"));
        lenses.push(ShippedLens {
            name: format!("{}{}", lentil::PREFIX, entry.id),
            source: format!("{}{patent} (lentil lens database)", entry.title),
        });
    }
    Ok(lenses)
}

/// True when `name` is a shipped lens's name.
pub fn is_shipped(name: &str) -> bool {
    BUILTIN_LENSES.iter().any(|(n, _)| *n == name)
        || shipped().is_ok_and(|lenses| lenses.iter().any(|l| l.name == name))
}

/// One line of `lenspath lens --list`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LensListing {
    /// Its name.
    pub name: String,
    /// Paraxial effective focal length, mm.
    pub focal_length_mm: f64,
    /// Paraxial f-number wide open.
    pub f_number: f64,
    /// Glass elements (each glass between two surfaces; a cemented doublet is two).
    pub elements: usize,
    /// True when some surface is aspheric.
    pub aspheric: bool,
    /// Where it is from.
    pub source: String,
}

/// The figures of every shipped lens.
pub fn listing() -> Result<Vec<LensListing>> {
    shipped()?
        .into_iter()
        .map(|lens| {
            let prescription = LensPrescription::load(&lens.name)?;
            let paraxial = LensSystem::new(&prescription).paraxial()?;
            let surfaces = prescription.surfaces();
            Ok(LensListing {
                focal_length_mm: paraxial.effective_focal_length_mm,
                f_number: paraxial.f_number,
                elements: surfaces.iter().filter(|s| s.ior_d() > 1.0).count(),
                aspheric: surfaces.iter().any(|s| s.shape != super::SurfaceShape::Spherical),
                name: lens.name,
                source: lens.source,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every shipped lens loads, images (a positive focal length, an
    /// f-number), and the built-in tables are all listed with a source.
    #[test]
    fn every_shipped_lens_is_listed_with_its_figures() {
        let listing = listing().unwrap();
        assert_eq!(listing.len(), 4 + 16);
        for (name, _) in BUILTIN_LENSES {
            assert!(listing.iter().any(|l| l.name == name), "{name}");
        }
        for lens in &listing {
            assert!(lens.focal_length_mm > 0.0 && lens.f_number > 0.5, "{lens:?}");
            assert!(lens.elements >= 1 && !lens.source.is_empty(), "{lens:?}");
            assert!(is_shipped(&lens.name));
        }
        let dgauss = &listing[0];
        assert_eq!((dgauss.name.as_str(), dgauss.elements), ("dgauss50", 6));
        assert!(listing.iter().any(|l| l.aspheric && l.name == "lentil:0014"));
        assert!(!is_shipped("lentil:9993") && !is_shipped("lentil:2001"));
    }
}
