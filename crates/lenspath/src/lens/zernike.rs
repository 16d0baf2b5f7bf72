//! A least-squares Zernike fit of a [`Wavefront`], in the Fringe (University
//! of Arizona) ordering that Zemax OpticStudio's "Zernike Fringe
//! Coefficients" and optiland's `ZernikeFringe` use: 37 terms, each
//! R_n^m(ρ)·cos(mθ) or ·sin(mθ) un-normalised (1 at the pupil's rim where
//! the angular factor is 1), θ from the +x axis toward +y, ρ the grid
//! circle's radius fraction (Wyant & Creath, "Basic wavefront aberration
//! theory for optical metrology", *Applied Optics and Optical Engineering*
//! XI, 1992, table 13.2).

use super::wavefront::Wavefront;
use crate::error::{Error, Result};

/// The number of Fringe terms fitted.
pub const FRINGE_TERMS: usize = 37;

/// The Fringe coefficients of a wavefront, waves; `coefficients[j - 1]` is Z_j.
#[derive(Clone, Debug, PartialEq)]
pub struct ZernikeFit {
    /// Z1 (piston) to Z37, waves.
    pub coefficients: Vec<f64>,
    /// RMS of what the 37 terms leave unexplained, waves.
    pub residual_rms_waves: f64,
}

/// The radial degree n and the signed azimuthal order m of Fringe term
/// `j` (1-based): m > 0 a cosine, m < 0 a sine term.
pub fn fringe_indices(j: usize) -> (u32, i32) {
    if j == FRINGE_TERMS {
        return (12, 0);
    }
    // Group g holds n + |m| = 2g, |m| falling from g to 0, the cosine before the sine.
    let mut k = 1;
    for g in 0u32.. {
        for m in (0..=g).rev() {
            let n = 2 * g - m;
            let signs: &[i32] = if m == 0 { &[0] } else { &[1, -1] };
            for &sign in signs {
                if k == j {
                    return (n, sign * m as i32);
                }
                k += 1;
            }
        }
    }
    unreachable!("every index lands in a group")
}

/// Fringe term `j` (1-based) at pupil polar coordinates (ρ, θ).
pub fn fringe_term(j: usize, rho: f64, theta: f64) -> f64 {
    let (n, m) = fringe_indices(j);
    let radial = radial_polynomial(n, m.unsigned_abs(), rho);
    match m {
        0 => radial,
        m if m > 0 => radial * (f64::from(m) * theta).cos(),
        m => radial * (f64::from(-m) * theta).sin(),
    }
}

/// R_n^m(ρ) = Σ_k (−1)^k (n−k)! / (k! ((n+m)/2−k)! ((n−m)/2−k)!) ρ^(n−2k) (Born & Wolf §9.2.1).
fn radial_polynomial(n: u32, m: u32, rho: f64) -> f64 {
    let factorial = |v: u32| (1..=v).map(f64::from).product::<f64>();
    (0..=(n - m) / 2)
        .map(|k| {
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            sign * factorial(n - k) / (factorial(k) * factorial((n + m) / 2 - k) * factorial((n - m) / 2 - k))
                * rho.powi((n - 2 * k) as i32)
        })
        .sum()
}

/// The mean of term `j`'s square over the unit disc: 1/(n+1) for m = 0,
/// 1/(2(n+1)) otherwise, so Σ c_j²·this over j ≥ 2 is the fitted wavefront's variance.
pub fn fringe_mean_square(j: usize) -> f64 {
    let (n, m) = fringe_indices(j);
    let angular = if m == 0 { 1.0 } else { 0.5 };
    angular / f64::from(n + 1)
}

impl Wavefront {
    /// The 37 Fringe coefficients by least squares over the samples inside the pupil.
    pub fn zernike_fringe(&self) -> Result<ZernikeFit> {
        let grid = self.grid();
        let (half, radius) = (0.5 * (grid as f64 - 1.0), 0.5 * grid as f64);
        let mut normal = vec![0.0; FRINGE_TERMS * FRINGE_TERMS];
        let mut rhs = vec![0.0; FRINGE_TERMS];
        let mut samples = Vec::new();
        for (k, &w) in self.opd_waves().iter().enumerate().filter(|(_, w)| !w.is_nan()) {
            let (x, y) = (((k % grid) as f64 - half) / radius, ((k / grid) as f64 - half) / radius);
            let (rho, theta) = (x.hypot(y), y.atan2(x));
            let terms: Vec<f64> = (1..=FRINGE_TERMS).map(|j| fringe_term(j, rho, theta)).collect();
            for a in 0..FRINGE_TERMS {
                rhs[a] += terms[a] * w;
                for b in 0..=a {
                    normal[a * FRINGE_TERMS + b] += terms[a] * terms[b];
                }
            }
            samples.push((terms, w));
        }
        let coefficients = cholesky_solve(&mut normal, &mut rhs).ok_or_else(|| {
            Error::InvalidArgument(format!(
                "a Zernike fit needs a pupil that the 37 terms can tell apart; {} samples pass",
                samples.len()
            ))
        })?;
        let residual_ss: f64 = samples
            .iter()
            .map(|(terms, w)| {
                let fitted: f64 = terms.iter().zip(&coefficients).map(|(t, c)| t * c).sum();
                (w - fitted) * (w - fitted)
            })
            .sum();
        Ok(ZernikeFit {
            coefficients,
            residual_rms_waves: (residual_ss / samples.len() as f64).sqrt(),
        })
    }
}

/// Solves the symmetric positive-definite system whose lower triangle is in
/// `matrix` (row-major), in place; `None` when it is singular.
fn cholesky_solve(matrix: &mut [f64], rhs: &mut [f64]) -> Option<Vec<f64>> {
    let n = rhs.len();
    for j in 0..n {
        let diagonal = matrix[j * n + j] - (0..j).map(|k| matrix[j * n + k].powi(2)).sum::<f64>();
        if diagonal <= 1e-12 * matrix[j * n + j].abs().max(f64::MIN_POSITIVE) {
            return None;
        }
        matrix[j * n + j] = diagonal.sqrt();
        for i in j + 1..n {
            let dot: f64 = (0..j).map(|k| matrix[i * n + k] * matrix[j * n + k]).sum();
            matrix[i * n + j] = (matrix[i * n + j] - dot) / matrix[j * n + j];
        }
    }
    for i in 0..n {
        rhs[i] = (rhs[i] - (0..i).map(|k| matrix[i * n + k] * rhs[k]).sum::<f64>()) / matrix[i * n + i];
    }
    for i in (0..n).rev() {
        rhs[i] = (rhs[i] - (i + 1..n).map(|k| matrix[k * n + i] * rhs[k]).sum::<f64>()) / matrix[i * n + i];
    }
    Some(rhs.to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fringe_ordering_is_the_published_one() {
        // Wyant & Creath table 13.2: Z4 defocus, Z9 primary spherical, Z16 and Z25 the next, Z10 trefoil, Z36/Z37.
        let expected = [
            (1, (0, 0)),
            (2, (1, 1)),
            (3, (1, -1)),
            (4, (2, 0)),
            (5, (2, 2)),
            (7, (3, 1)),
            (9, (4, 0)),
            (10, (3, 3)),
            (12, (4, 2)),
            (16, (6, 0)),
            (17, (4, 4)),
            (25, (8, 0)),
            (26, (5, 5)),
            (36, (10, 0)),
            (37, (12, 0)),
        ];
        for (j, indices) in expected {
            assert_eq!(fringe_indices(j), indices, "Z{j}");
        }
        // Z9 = 6ρ⁴ − 6ρ² + 1, Z8 = (3ρ³ − 2ρ) sin θ.
        let (rho, theta) = (0.7_f64, 0.4_f64);
        assert!((fringe_term(9, rho, theta) - (6.0 * rho.powi(4) - 6.0 * rho * rho + 1.0)).abs() < 1e-12);
        assert!((fringe_term(8, rho, theta) - (3.0 * rho.powi(3) - 2.0 * rho) * theta.sin()).abs() < 1e-12);
    }

    #[test]
    fn a_wavefront_made_of_known_terms_is_fitted_back_and_its_rms_follows() {
        let grid = 64;
        let mut wavefront = Wavefront::diffraction_limited(grid, 4.0, 550.0);
        let truth = [(4, 0.3), (5, -0.12), (8, 0.07), (9, 0.2), (16, -0.05), (37, 0.01)];
        let (half, radius) = (0.5 * (grid as f64 - 1.0), 0.5 * grid as f64);
        wavefront.map_opd(|k, _| {
            let (x, y) = (((k % grid) as f64 - half) / radius, ((k / grid) as f64 - half) / radius);
            truth
                .iter()
                .map(|&(j, c)| c * fringe_term(j, x.hypot(y), y.atan2(x)))
                .sum()
        });
        let fit = wavefront.zernike_fringe().unwrap();
        for j in 1..=FRINGE_TERMS {
            let expected = truth.iter().find(|t| t.0 == j).map_or(0.0, |t| t.1);
            assert!(
                (fit.coefficients[j - 1] - expected).abs() < 1e-9,
                "Z{j}: {} against {expected}",
                fit.coefficients[j - 1]
            );
        }
        assert!(fit.residual_rms_waves < 1e-9);
        // The disc's sampled variance and Σ c²·⟨Z²⟩ agree to the sampling's accuracy.
        let from_terms: f64 = (2..=FRINGE_TERMS)
            .map(|j| fit.coefficients[j - 1].powi(2) * fringe_mean_square(j))
            .sum::<f64>()
            .sqrt();
        assert!(
            (from_terms / wavefront.rms_waves() - 1.0).abs() < 0.02,
            "{from_terms} from the terms, {} sampled",
            wavefront.rms_waves()
        );
    }
}
