//! Measured complex indices of refraction n + ik of metals, by name, for
//! conductors: gold, silver and copper (Johnson & Christy 1972) and
//! aluminium (Rakić et al. 1998), from the refractiveindex.info database
//! (CC0; `data/metals/`, see `data/README.md`).

use std::sync::{Arc, OnceLock};

use super::{Spectrum, Tabulated};
use crate::error::{Error, Result};

/// A metal with measured optical constants.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Metal {
    /// Gold, Au.
    Gold,
    /// Silver, Ag.
    Silver,
    /// Copper, Cu.
    Copper,
    /// Aluminium, Al.
    Aluminium,
}

/// Every metal with its chemical symbol and the names it answers to.
pub const METALS: [(Metal, &str, &[&str]); 4] = [
    (Metal::Gold, "Au", &["gold"]),
    (Metal::Silver, "Ag", &["silver"]),
    (Metal::Copper, "Cu", &["copper"]),
    (Metal::Aluminium, "Al", &["aluminium", "aluminum"]),
];

impl Metal {
    /// The metal named by its symbol (`Au`) or English name (`gold`), any case.
    pub fn from_name(name: &str) -> Result<Self> {
        let lower = name.trim().to_ascii_lowercase();
        METALS
            .iter()
            .find(|(_, symbol, names)| symbol.to_ascii_lowercase() == lower || names.contains(&lower.as_str()))
            .map(|m| m.0)
            .ok_or_else(|| {
                let known: Vec<String> = METALS.iter().map(|(_, s, n)| format!("{s} ({})", n[0])).collect();
                Error::InvalidArgument(format!("unknown metal '{name}': known are {}", known.join(", ")))
            })
    }

    /// Its chemical symbol.
    pub fn symbol(self) -> &'static str {
        METALS.iter().find(|m| m.0 == self).map(|m| m.1).unwrap_or("?")
    }

    /// The real and imaginary parts of its index of refraction, η and k, as
    /// spectra (linear between the measured wavelengths).
    pub fn eta_k(self) -> (Spectrum, Spectrum) {
        static TABLES: OnceLock<Vec<(Arc<Tabulated>, Arc<Tabulated>)>> = OnceLock::new();
        let tables = TABLES.get_or_init(|| {
            [AU, AG, CU, AL]
                .iter()
                .map(|text| {
                    let (eta, k) = parse_nk(text);
                    (
                        Arc::new(Tabulated::new(&eta).expect("the embedded metal tables are valid")),
                        Arc::new(Tabulated::new(&k).expect("the embedded metal tables are valid")),
                    )
                })
                .collect()
        });
        let (eta, k) = &tables[self as usize];
        (Spectrum::Tabulated(eta.clone()), Spectrum::Tabulated(k.clone()))
    }
}

const AU: &str = include_str!("../../data/metals/Au.yml");
const AG: &str = include_str!("../../data/metals/Ag.yml");
const CU: &str = include_str!("../../data/metals/Cu.yml");
const AL: &str = include_str!("../../data/metals/Al.yml");

/// `(wavelength_nm, value)` rows of a table.
type Pairs = Vec<(f32, f32)>;

/// The `(wavelength_nm, n)` and `(wavelength_nm, k)` rows of a
/// refractiveindex.info `tabulated nk` file (wavelengths there are µm),
/// kept between 300 and 900 nm, where rendering needs them.
fn parse_nk(text: &str) -> (Pairs, Pairs) {
    let (mut eta, mut k) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let numbers: Vec<f32> = line.split_whitespace().filter_map(|v| v.parse().ok()).collect();
        if let [micrometres, n, kappa] = numbers[..] {
            let nm = micrometres * 1000.0;
            if (300.0..=900.0).contains(&nm) {
                eta.push((nm, n));
                k.push((nm, kappa));
            }
        }
    }
    (eta, k)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::fresnel_complex;

    /// Normal-incidence reflectance from the tables against published values
    /// (Johnson & Christy's gold is ~0.38 at 450 nm, ~0.97 at 700 nm; silver
    /// above 0.95 across the visible; aluminium ~0.92), and names resolve.
    #[test]
    fn measured_metals_reflect_as_published() {
        let reflectance = |m: Metal, l: f32| {
            let (eta, k) = m.eta_k();
            fresnel_complex(1.0, eta.at(l), k.at(l))
        };
        assert!((reflectance(Metal::Gold, 450.0) - 0.38).abs() < 0.03);
        assert!(reflectance(Metal::Gold, 700.0) > 0.95);
        assert!(reflectance(Metal::Silver, 500.0) > 0.95);
        assert!((reflectance(Metal::Aluminium, 550.0) - 0.916).abs() < 0.01);
        assert!(reflectance(Metal::Copper, 450.0) < 0.65 && reflectance(Metal::Copper, 700.0) > 0.9);
        assert_eq!(Metal::from_name("GOLD").unwrap(), Metal::Gold);
        assert_eq!(Metal::from_name("al").unwrap(), Metal::Aluminium);
        let e = Metal::from_name("unobtainium").unwrap_err().to_string();
        assert!(e.contains("Au (gold)"), "{e}");
    }
}
