//! Optical glass: the index of refraction as a function of wavelength, and
//! the six makers' catalogues (Schott, Ohara, Hoya, CDGM, Sumita, Hikari;
//! 1,609 glasses from the refractiveindex.info database, CC0, embedded from
//! `data/glass/catalogue.tsv`, written by `scripts/glass_catalogue.py`).
//!
//! Used by dielectric materials and by lens prescriptions alike: a glass is
//! named (`N-BK7`, `ohara:S-LAH59`) or given by n_d and V_d, from which a
//! two-term Cauchy model is built.

use std::sync::OnceLock;

use crate::error::{Error, Result};

/// The Fraunhofer lines lens designers quote, `(name, wavelength_nm)`:
/// g (mercury), F (hydrogen), d (helium), C (hydrogen).
pub const FRAUNHOFER_LINES: [(&str, f64); 4] = [("g", G_LINE_NM), ("F", F_LINE_NM), ("d", D_LINE_NM), ("C", C_LINE_NM)];
/// The g line, nm.
pub const G_LINE_NM: f64 = 435.8343;
/// The d line, nm, where n_d is given.
pub const D_LINE_NM: f64 = 587.5618;
/// The F line, nm.
pub const F_LINE_NM: f64 = 486.1327;
/// The C line, nm.
pub const C_LINE_NM: f64 = 656.2725;

/// The catalogues in the order a bare glass name is looked up.
pub const MAKERS: [&str; 6] = ["schott", "ohara", "hoya", "cdgm", "sumita", "hikari"];

/// Most terms a catalogue formula has (the polynomial's seven pairs).
const MAX_TERMS: usize = 7;

/// An index of refraction as a function of wavelength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Dispersion {
    /// The same index at every wavelength (no dispersion).
    Constant(f64),
    /// Sellmeier (refractiveindex.info formula 2, the makers' own):
    /// n² − 1 = c₀ + Σ Bᵢ λ² / (λ² − Cᵢ), λ in µm.
    Sellmeier {
        /// c₀.
        constant: f64,
        /// (Bᵢ, Cᵢ) pairs; the first `count` are used.
        terms: [(f64, f64); MAX_TERMS],
        /// How many pairs there are.
        count: usize,
    },
    /// Polynomial (refractiveindex.info formula 3, the Schott/Ohara
    /// "Laurent" form): n² = c₀ + Σ aᵢ λ^eᵢ, λ in µm.
    Polynomial {
        /// c₀.
        constant: f64,
        /// (aᵢ, eᵢ) pairs; the first `count` are used.
        terms: [(f64, f64); MAX_TERMS],
        /// How many pairs there are.
        count: usize,
    },
    /// Cauchy's n = a + b / λ² (λ in µm), fitted by [`Dispersion::from_abbe`]
    /// to n_d and the Abbe number V_d = (n_d − 1) / (n_F − n_C).
    Cauchy {
        /// a.
        a: f64,
        /// b, µm².
        b: f64,
    },
}

impl Dispersion {
    /// The Cauchy model through n_d with Abbe number V_d: the model lens
    /// tables with only (n_d, V_d) get. Refuses n_d ≤ 1 and V_d ≤ 0; V_d =
    /// ∞ (written 0 nowhere; use [`Dispersion::Constant`]) is no dispersion.
    pub fn from_abbe(n_d: f64, v_d: f64) -> Result<Self> {
        if !(n_d > 1.0 && n_d.is_finite()) {
            return Err(Error::InvalidArgument(format!(
                "n_d must be a finite number above 1, got {n_d}"
            )));
        }
        if !(v_d > 0.0 && v_d.is_finite()) {
            return Err(Error::InvalidArgument(format!(
                "V_d must be a positive Abbe number, got {v_d}"
            )));
        }
        let inv2 = |nm: f64| 1.0 / (nm * 1e-3).powi(2);
        let b = (n_d - 1.0) / v_d / (inv2(F_LINE_NM) - inv2(C_LINE_NM));
        Ok(Dispersion::Cauchy {
            a: n_d - b * inv2(D_LINE_NM),
            b,
        })
    }

    /// A dielectric's index as a scene or a caller describes it, by exactly
    /// one of: `eta` (a constant), `glass` (a catalogue name, see [`find`]),
    /// `n_d` (a constant) with optionally `v_d` (then the Abbe model). The
    /// rule every front end's dielectric goes through.
    pub fn described(eta: Option<f64>, glass: Option<&str>, n_d: Option<f64>, v_d: Option<f64>) -> Result<Self> {
        let constant = |n: f64| {
            if n > 0.0 && n.is_finite() {
                Ok(Dispersion::Constant(n))
            } else {
                Err(Error::InvalidArgument(format!(
                    "an index of refraction must be positive, got {n}"
                )))
            }
        };
        match (eta, glass, n_d, v_d) {
            (Some(eta), None, None, None) => constant(eta),
            (None, Some(name), None, None) => Ok(find(name)?.dispersion),
            (None, None, Some(n_d), None) => constant(n_d),
            (None, None, Some(n_d), Some(v_d)) => Dispersion::from_abbe(n_d, v_d),
            (None, None, None, None) => Ok(Dispersion::Constant(1.5)),
            _ => Err(Error::InvalidArgument(
                "give a dielectric one of eta, glass, or n_d (with v_d for its dispersion)".into(),
            )),
        }
    }

    /// The index at `lambda_nm`.
    pub fn index(&self, lambda_nm: f64) -> f64 {
        let l = lambda_nm * 1e-3;
        let l2 = l * l;
        match *self {
            Dispersion::Constant(n) => n,
            Dispersion::Sellmeier { constant, terms, count } => {
                let sum: f64 = terms[..count].iter().map(|&(b, c)| b * l2 / (l2 - c)).sum();
                (1.0 + constant + sum).max(0.0).sqrt()
            }
            Dispersion::Polynomial { constant, terms, count } => {
                let sum: f64 = terms[..count].iter().map(|&(a, e)| a * l.powf(e)).sum();
                (constant + sum).max(0.0).sqrt()
            }
            Dispersion::Cauchy { a, b } => a + b / l2,
        }
    }

    /// True when the index does not change with wavelength.
    pub fn is_constant(&self) -> bool {
        matches!(self, Dispersion::Constant(_))
    }

    /// The index at the d line.
    pub fn n_d(&self) -> f64 {
        self.index(D_LINE_NM)
    }

    /// The Abbe number V_d = (n_d − 1) / (n_F − n_C) (∞ without dispersion).
    pub fn abbe_number(&self) -> f64 {
        (self.n_d() - 1.0) / (self.index(F_LINE_NM) - self.index(C_LINE_NM))
    }
}

/// A catalogue glass.
#[derive(Clone, Debug, PartialEq)]
pub struct Glass {
    /// Its maker's catalogue (`schott`, `ohara`, …).
    pub maker: &'static str,
    /// Its name in that catalogue (`N-BK7`).
    pub name: &'static str,
    /// Its index against wavelength.
    pub dispersion: Dispersion,
    /// The catalogue's n_d.
    pub n_d: f64,
    /// The catalogue's Abbe number V_d.
    pub v_d: f64,
    /// The six-digit glass code (nnnvvv) and density where given.
    pub glass_code: Option<&'static str>,
    /// Wavelengths, nm, over which the maker's formula holds.
    pub range_nm: (f64, f64),
    /// The extinction coefficient k (the imaginary part of the index)
    /// against wavelength, nm, ascending; empty where the catalogue gives none.
    pub extinction: Vec<(f64, f64)>,
}

const CATALOGUE_TSV: &str = include_str!("../data/glass/catalogue.tsv");

/// Fails unless `wavelength_nm` is a wavelength an index can be asked at: a
/// positive, finite number of nanometres (a dispersion formula gives
/// numbers for 0 or NaN too, which mean nothing).
pub fn check_wavelength_nm(wavelength_nm: f64) -> Result<()> {
    if !(wavelength_nm > 0.0 && wavelength_nm.is_finite()) {
        return Err(Error::InvalidArgument(format!(
            "a wavelength must be a positive number of nm, got {wavelength_nm}"
        )));
    }
    Ok(())
}

/// Every catalogue glass, in [`MAKERS`] order.
pub fn catalogue() -> &'static [Glass] {
    static GLASSES: OnceLock<Vec<Glass>> = OnceLock::new();
    GLASSES.get_or_init(|| {
        CATALOGUE_TSV
            .lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .map(|line| parse_row(line).unwrap_or_else(|| panic!("bad embedded glass row: {line}")))
            .collect()
    })
}

/// One row of the embedded catalogue.
fn parse_row(line: &'static str) -> Option<Glass> {
    let fields: Vec<&'static str> = line.split('\t').collect();
    let [maker, name, formula, min_um, max_um, nd, vd, code, coefficients, k] = fields[..] else {
        return None;
    };
    let extinction = match k {
        "-" => Vec::new(),
        pairs => pairs
            .split(' ')
            .map(|pair| {
                let (um, k) = pair.split_once(':')?;
                Some((um.parse::<f64>().ok()? * 1e3, k.parse::<f64>().ok()?))
            })
            .collect::<Option<_>>()?,
    };
    let numbers: Vec<f64> = coefficients.split(' ').map(|c| c.parse().ok()).collect::<Option<_>>()?;
    let (&constant, pairs) = numbers.split_first()?;
    let mut terms = [(0.0, 0.0); MAX_TERMS];
    let count = pairs.len() / 2;
    if count > MAX_TERMS || pairs.len() % 2 != 0 {
        return None;
    }
    for (slot, pair) in terms.iter_mut().zip(pairs.chunks_exact(2)) {
        *slot = (pair[0], pair[1]);
    }
    let dispersion = match formula {
        "2" => Dispersion::Sellmeier { constant, terms, count },
        "3" => Dispersion::Polynomial { constant, terms, count },
        _ => return None,
    };
    let maker = MAKERS.iter().find(|m| **m == maker)?;
    Some(Glass {
        maker,
        name,
        dispersion,
        n_d: nd.parse().ok()?,
        v_d: vd.parse().ok()?,
        glass_code: (code != "-").then_some(code),
        range_nm: (min_um.parse::<f64>().ok()? * 1e3, max_um.parse::<f64>().ok()? * 1e3),
        extinction,
    })
}

/// The catalogue glasses a lens file may mean by `name`, as lens files
/// write glass names: the name itself, its lead-free `N-` successor (BK7 →
/// N-BK7), and the part before a `_` (Zemax's `SF5_SCHOTT`-style
/// suffixes), in that order.
pub fn find_as_written(name: &str) -> impl Iterator<Item = &'static Glass> {
    let before_underscore = name.split('_').next().unwrap_or(name).to_string();
    [name.to_string(), format!("N-{name}"), before_underscore]
        .into_iter()
        .filter_map(|candidate| find(&candidate).ok())
}

/// The glass named `name`: `N-BK7` (the first maker in [`MAKERS`] order
/// with that name), or `maker:name` (`ohara:S-LAH59`); any case.
pub fn find(name: &str) -> Result<&'static Glass> {
    let query = name.trim();
    let (maker, glass) = match query.split_once(':') {
        Some((maker, glass)) => (Some(maker.trim().to_ascii_lowercase()), glass.trim()),
        None => (None, query),
    };
    if let Some(m) = &maker {
        if !MAKERS.contains(&m.as_str()) {
            return Err(Error::InvalidArgument(format!(
                "unknown glass maker '{m}' in '{name}': known are {}",
                MAKERS.join(", ")
            )));
        }
    }
    let matches = |g: &&Glass| maker.as_deref().is_none_or(|m| m == g.maker) && g.name.eq_ignore_ascii_case(glass);
    if let Some(found) = catalogue().iter().find(matches) {
        return Ok(found);
    }
    let upper = glass.to_ascii_uppercase();
    let mut similar: Vec<String> = catalogue()
        .iter()
        .filter(|g| g.name.to_ascii_uppercase().contains(&upper) || upper.contains(&g.name.to_ascii_uppercase()))
        .map(|g| format!("{}:{}", g.maker, g.name))
        .take(6)
        .collect();
    similar.dedup();
    let hint = if similar.is_empty() {
        String::new()
    } else {
        format!(" (similar: {})", similar.join(", "))
    };
    Err(Error::InvalidArgument(format!(
        "unknown glass '{name}': not in the {} catalogues{hint}",
        MAKERS.join(", ")
    )))
}

/// How far a glass lies from (n_d, V_d) on a glass map: (Δn_d / 0.01)² +
/// (ΔV_d / 1)², the weighting of a glass map's axes.
fn map_distance(g: &Glass, n_d: f64, v_d: f64) -> f64 {
    ((g.n_d - n_d) / 0.01).powi(2) + (g.v_d - v_d).powi(2)
}

/// The catalogue glass nearest to (n_d, V_d) on a glass map (see `map_distance`).
pub fn nearest(n_d: f64, v_d: f64) -> &'static Glass {
    catalogue()
        .iter()
        .min_by(|a, b| map_distance(a, n_d, v_d).total_cmp(&map_distance(b, n_d, v_d)))
        .expect("the embedded catalogue is not empty")
}

/// Each maker's glass nearest to (n_d, V_d), in [`MAKERS`] order: the
/// equivalents a designer would look at.
pub fn nearest_of_each_maker(n_d: f64, v_d: f64) -> Vec<&'static Glass> {
    MAKERS
        .iter()
        .filter_map(|maker| {
            catalogue()
                .iter()
                .filter(|g| g.maker == *maker)
                .min_by(|a, b| map_distance(a, n_d, v_d).total_cmp(&map_distance(b, n_d, v_d)))
        })
        .collect()
}

impl Glass {
    /// The internal transmittance (no surface reflections) of `thickness_mm`
    /// of this glass at `wavelength_nm`: exp(−4π·k·d/λ) (Beer–Lambert with
    /// the absorption coefficient 4πk/λ; Born & Wolf, §14.1), k interpolated
    /// linearly between the catalogue's wavelengths. `None` outside them.
    pub fn internal_transmittance(&self, wavelength_nm: f64, thickness_mm: f64) -> Option<f64> {
        let table = &self.extinction;
        let (first, last) = (table.first()?, table.last()?);
        if !(first.0..=last.0).contains(&wavelength_nm) {
            return None;
        }
        let above = table
            .partition_point(|&(nm, _)| nm < wavelength_nm)
            .max(1)
            .min(table.len() - 1);
        let ((nm0, k0), (nm1, k1)) = (table[above - 1], table[above]);
        let k = if nm1 > nm0 {
            k0 + (k1 - k0) * (wavelength_nm - nm0) / (nm1 - nm0)
        } else {
            k0
        };
        Some((-4.0 * std::f64::consts::PI * k * thickness_mm * 1e6 / wavelength_nm).exp())
    }
    /// Relative partial dispersion P_g,F = (n_g − n_F) / (n_F − n_C), from
    /// its formula (Schott, TIE-29): how far from the normal line its
    /// secondary spectrum lies.
    pub fn partial_dispersion_g_f(&self) -> f64 {
        let n = |nm| self.dispersion.index(nm);
        (n(G_LINE_NM) - n(F_LINE_NM)) / (n(F_LINE_NM) - n(C_LINE_NM))
    }
}

/// The Abbe diagram as SVG: every catalogue glass as a dot at (V_d, n_d),
/// V_d growing to the left as glass maps draw it, and `marked` glasses
/// (label, n_d, V_d) as labelled red rings.
pub fn abbe_diagram_svg(marked: &[(String, f64, f64)]) -> String {
    use std::fmt::Write as _;
    let (width, height, margin) = (900.0, 600.0, 50.0);
    let (v_range, n_range) = ((15.0, 100.0), (1.40, 2.10));
    let x = |v_d: f64| margin + (v_range.1 - v_d) / (v_range.1 - v_range.0) * (width - 2.0 * margin);
    let y = |n_d: f64| height - margin - (n_d - n_range.0) / (n_range.1 - n_range.0) * (height - 2.0 * margin);
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}">"#
    );
    let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        svg,
        r#"<text x="{margin}" y="24" font-family="sans-serif" font-size="15">Abbe diagram: {} catalogue glasses ({}), n_d against V_d</text>"#,
        catalogue().len(),
        MAKERS.join(", ")
    );
    for v in (20..=90).step_by(10) {
        let v = f64::from(v);
        let _ = writeln!(
            svg,
            r##"<line x1="{0:.1}" y1="{1}" x2="{0:.1}" y2="{2}" stroke="#ddd"/><text x="{0:.1}" y="{3}" font-family="sans-serif" font-size="12" text-anchor="middle">{v}</text>"##,
            x(v),
            margin,
            height - margin,
            height - margin + 16.0
        );
    }
    for k in 0..=7 {
        let n = n_range.0 + 0.1 * f64::from(k);
        let _ = writeln!(
            svg,
            r##"<line x1="{margin}" y1="{0:.1}" x2="{1}" y2="{0:.1}" stroke="#ddd"/><text x="{2}" y="{3:.1}" font-family="sans-serif" font-size="12" text-anchor="end">{n:.1}</text>"##,
            y(n),
            width - margin,
            margin - 6.0,
            y(n) + 4.0
        );
    }
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="{}" font-family="sans-serif" font-size="13" text-anchor="middle">V_d</text><text x="14" y="{}" font-family="sans-serif" font-size="13">n_d</text>"#,
        width / 2.0,
        height - 12.0,
        height / 2.0
    );
    for g in catalogue() {
        let _ = writeln!(
            svg,
            r##"<circle cx="{:.1}" cy="{:.1}" r="1.6" fill="#4a6fa5"><title>{}:{} n_d {} V_d {}</title></circle>"##,
            x(g.v_d),
            y(g.n_d),
            g.maker,
            g.name,
            g.n_d,
            g.v_d
        );
    }
    for (label, n_d, v_d) in marked {
        let _ = writeln!(
            svg,
            r##"<circle cx="{0:.1}" cy="{1:.1}" r="6" fill="none" stroke="#c00" stroke-width="2"/><text x="{2:.1}" y="{3:.1}" font-family="sans-serif" font-size="12" fill="#c00">{label}</text>"##,
            x(*v_d),
            y(*n_d),
            x(*v_d) + 8.0,
            y(*n_d) - 8.0
        );
    }
    svg.push_str("</svg>\n");
    svg
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Internal transmittance from the catalogue's k: N-BK7's data sheet
    /// (Schott) gives τi 0.997 through 10 mm and 0.992 through 25 mm at
    /// 400 nm; refractiveindex.info derived Schott's k from the 25 mm
    /// figures, printed to three decimals, so every tabulated wavelength gives
    /// back a three-decimal τi(25 mm) (a wrong unit or factor would not).
    #[test]
    fn internal_transmittance_follows_the_makers_figures() {
        let bk7 = find("schott:N-BK7").unwrap();
        let at_400 = |mm| bk7.internal_transmittance(400.0, mm).unwrap();
        assert!((at_400(10.0) - 0.997).abs() < 5e-4, "{}", at_400(10.0));
        assert!((at_400(25.0) - 0.992).abs() < 5e-4, "{}", at_400(25.0));
        assert!(bk7.extinction.len() >= 20);
        for &(nm, _) in &bk7.extinction {
            let per_mille = 1e3 * bk7.internal_transmittance(nm, 25.0).unwrap();
            assert!((per_mille - per_mille.round()).abs() < 0.05, "{nm} nm: {per_mille}");
        }
        // Thicker glass and shorter wavelengths absorb more; outside the table, no figure.
        assert!(bk7.internal_transmittance(320.0, 10.0).unwrap() < at_400(10.0));
        assert!(bk7.internal_transmittance(400.0, 50.0).unwrap() < at_400(25.0));
        assert_eq!(bk7.internal_transmittance(250.0, 10.0), None);
        assert!(catalogue().iter().all(|g| !g.extinction.is_empty()));
    }

    /// N-BK7's P_g,F from its formula is Schott's catalogue value 0.5349,
    /// and each maker's nearest glass to it is that maker's BK7 equivalent.
    #[test]
    fn partial_dispersion_and_equivalents() {
        let bk7 = find("N-BK7").unwrap();
        assert!(
            (bk7.partial_dispersion_g_f() - 0.5349).abs() < 5e-4,
            "{}",
            bk7.partial_dispersion_g_f()
        );
        let equivalents = nearest_of_each_maker(bk7.n_d, bk7.v_d);
        assert_eq!(equivalents.len(), MAKERS.len());
        assert_eq!(equivalents[0].name, "N-BK7");
        for g in &equivalents {
            assert!(
                (g.n_d - 1.5168).abs() < 0.01 && (g.v_d - 64.17).abs() < 2.0,
                "{}:{}",
                g.maker,
                g.name
            );
        }
        let svg = abbe_diagram_svg(&[("N-BK7".into(), bk7.n_d, bk7.v_d)]);
        assert_eq!(svg.matches("<circle").count(), catalogue().len() + 1);
    }

    /// Every one of the 1,609 glasses' formulas gives its maker's n_d to
    /// 1e-4 and V_d to 0.5%: the formulas and their coefficients are read
    /// right, for both kinds.
    #[test]
    fn every_catalogue_formula_gives_its_nd_and_vd() {
        let glasses = catalogue();
        assert_eq!(glasses.len(), 1609);
        for g in glasses {
            let n_d = g.dispersion.n_d();
            assert!(
                (n_d - g.n_d).abs() < 1e-4,
                "{}:{} n_d {n_d} vs {}",
                g.maker,
                g.name,
                g.n_d
            );
            let v_d = g.dispersion.abbe_number();
            assert!(
                (v_d / g.v_d - 1.0).abs() < 5e-3,
                "{}:{} V_d {v_d} vs {}",
                g.maker,
                g.name,
                g.v_d
            );
        }
    }

    /// N-BK7 against Schott's datasheet: n_F = 1.52238, n_C = 1.51432,
    /// n_g = 1.52668, and at 404.66 nm (h line) 1.53024.
    #[test]
    fn n_bk7_matches_the_schott_datasheet() {
        let bk7 = find("n-bk7").unwrap();
        assert_eq!((bk7.maker, bk7.name), ("schott", "N-BK7"));
        for (nm, n) in [
            (486.1327, 1.52238),
            (656.2725, 1.51432),
            (435.8343, 1.52668),
            (404.6561, 1.53024),
        ] {
            assert!((bk7.dispersion.index(nm) - n).abs() < 1e-5, "{nm} nm");
        }
        assert_eq!(find("ohara:S-LAH59").unwrap().maker, "ohara");
        let e = find("N-BK8").unwrap_err().to_string();
        assert!(e.contains("unknown glass 'N-BK8'") && e.contains("schott"), "{e}");
        assert!(find("zeiss:BK7")
            .unwrap_err()
            .to_string()
            .contains("unknown glass maker 'zeiss'"));
    }

    /// The Cauchy model from (n_d, V_d) reproduces both, and lands near a
    /// real glass with those numbers elsewhere in the visible.
    #[test]
    fn abbe_model_keeps_nd_and_vd() {
        let model = Dispersion::from_abbe(1.5168, 64.17).unwrap();
        assert!((model.n_d() - 1.5168).abs() < 1e-12);
        assert!((model.abbe_number() - 64.17).abs() < 1e-9);
        let bk7 = find("N-BK7").unwrap();
        assert!((model.index(450.0) - bk7.dispersion.index(450.0)).abs() < 5e-4);
        assert!(Dispersion::from_abbe(0.9, 50.0).is_err());
        assert!(Dispersion::from_abbe(1.5, 0.0).is_err());
        let near = nearest(1.5168, 64.17);
        assert!(
            (near.n_d - 1.5168).abs() < 2e-3 && (near.v_d - 64.17).abs() < 1.0,
            "{near:?}"
        );
    }
}
