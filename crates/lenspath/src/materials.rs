//! Materials and their BSDFs, evaluated in the local shading frame (normal = +z).
//!
//! A [`Material`] is what a scene says (RGB colours, as every scene format
//! gives them); [`SpectralMaterial`] is its spectra, fitted once when the
//! scene is compiled; [`Bsdf`] is those spectra at one path's wavelengths,
//! made at each hit, whose `eval`, `pdf` and `sample` the path tracer calls.
//!
//! Formulas follow pbrt-v4 (Pharr, Jakob, Humphreys, *Physically Based
//! Rendering*, 4th ed., ch. 9): `DiffuseBxDF`, `DielectricBxDF` (smooth),
//! `ConductorBxDF` with the Trowbridge–Reitz (GGX) distribution and
//! visible-normal sampling (Heitz 2018). Diffuse and conductor surfaces are
//! two-sided; the dielectric tells its sides apart by the sign of cosθ.

use std::f32::consts::{FRAC_1_PI, PI};

use glam::{Vec2, Vec3};

use crate::error::{Error, Result};
use crate::glass::Dispersion;
use crate::math::Rgb;
use crate::sampling::cosine_hemisphere;
use crate::spectrum::metals::Metal;
use crate::spectrum::{SampledSpectrum, SampledWavelengths, Spectrum};

/// Roughness below which a conductor is treated as a perfect specular reflector.
const SMOOTH_ALPHA: f32 = 1e-3;

/// A surface material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian reflector.
    Diffuse {
        /// Hemispherical reflectance in [0, 1].
        reflectance: Rgb,
    },
    /// Perfect specular mirror.
    Mirror {
        /// Reflectance in [0, 1].
        reflectance: Rgb,
    },
    /// Smooth dielectric interface (glass, water): Fresnel reflection and refraction.
    /// The two tints scale the lobes as Mitsuba 3's `specular_reflectance` and
    /// `specular_transmittance` do (1 for clear glass).
    Dielectric {
        /// Index of refraction inside over outside against wavelength
        /// (`Dispersion::Constant(1.5)` for plain glass, a catalogue glass's
        /// dispersion for real glass, which splits white light).
        eta: Dispersion,
        /// Tint of the reflected lobe in [0, 1].
        reflectance: Rgb,
        /// Tint of the transmitted lobe in [0, 1].
        transmittance: Rgb,
    },
    /// Metal: microfacet conductor with a complex index of refraction per channel.
    Conductor {
        /// Real part of the IOR per RGB channel.
        eta: Rgb,
        /// Absorption coefficient (imaginary part) per RGB channel.
        k: Rgb,
        /// Trowbridge–Reitz roughness α (0 = polished mirror).
        alpha: f32,
    },
    /// Metal with measured spectral n + ik (gold, silver, copper,
    /// aluminium): a microfacet conductor like [`Material::Conductor`].
    MeasuredConductor {
        /// Which metal.
        metal: Metal,
        /// Trowbridge–Reitz roughness α (0 = polished mirror).
        alpha: f32,
    },
}

/// A direction sampled from a BSDF.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Incident direction (local frame).
    pub wi: Vec3,
    /// BSDF value for (wo, wi), at the path's wavelengths.
    pub f: SampledSpectrum,
    /// Density of `wi` per solid angle (a discrete probability for specular lobes).
    pub pdf: f32,
    /// True for a Dirac delta lobe (mirror, glass).
    pub specular: bool,
    /// Relative index of refraction crossed (1 for reflection).
    pub eta: f32,
}

impl Material {
    /// A conductor as a scene or a caller describes it: RGB `eta` and `k`,
    /// or a measured `metal` by name (see [`Metal::from_name`]), with GGX
    /// roughness `alpha`. The rule every front end's conductor goes through.
    pub fn conductor(eta: Option<Rgb>, k: Option<Rgb>, metal: Option<&str>, alpha: f32) -> Result<Self> {
        match (eta, k, metal) {
            (Some(eta), Some(k), None) => Ok(Material::Conductor { eta, k, alpha }),
            (None, None, Some(name)) => Ok(Material::MeasuredConductor {
                metal: Metal::from_name(name)?,
                alpha,
            }),
            _ => Err(Error::InvalidArgument(
                "a conductor needs either eta and k (RGB) or metal (a name such as \"gold\")".into(),
            )),
        }
    }

    /// Clear glass-like dielectric of relative index `eta`, untinted.
    pub fn clear_dielectric(eta: f32) -> Self {
        Material::Dielectric {
            eta: Dispersion::Constant(f64::from(eta)),
            reflectance: Rgb::ONE,
            transmittance: Rgb::ONE,
        }
    }
}

/// A material's spectra, fitted to its RGB colours once, when the scene is
/// compiled (spectral upsampling costs about 0.1 ms a colour).
#[derive(Clone, Debug, PartialEq)]
pub enum SpectralMaterial {
    /// Lambertian reflector.
    Diffuse {
        /// Reflectance spectrum in [0, 1].
        reflectance: Spectrum,
    },
    /// Perfect specular mirror.
    Mirror {
        /// Reflectance spectrum in [0, 1].
        reflectance: Spectrum,
    },
    /// Smooth dielectric.
    Dielectric {
        /// Index of refraction inside over outside against wavelength.
        eta: Dispersion,
        /// Tint of the reflected lobe.
        reflectance: Spectrum,
        /// Tint of the transmitted lobe.
        transmittance: Spectrum,
    },
    /// Microfacet conductor.
    Conductor {
        /// Real part of the index of refraction.
        eta: Spectrum,
        /// Imaginary part (absorption).
        k: Spectrum,
        /// Trowbridge–Reitz roughness α.
        alpha: f32,
    },
}

impl SpectralMaterial {
    /// The spectra of `material`: reflectances and tints upsampled to
    /// bounded spectra, a conductor's RGB η and k to unbounded ones.
    pub fn new(material: &Material) -> Self {
        match *material {
            Material::Diffuse { reflectance } => SpectralMaterial::Diffuse {
                reflectance: Spectrum::reflectance(reflectance),
            },
            Material::Mirror { reflectance } => SpectralMaterial::Mirror {
                reflectance: Spectrum::reflectance(reflectance),
            },
            Material::Dielectric {
                eta,
                reflectance,
                transmittance,
            } => SpectralMaterial::Dielectric {
                eta,
                reflectance: Spectrum::reflectance(reflectance),
                transmittance: Spectrum::reflectance(transmittance),
            },
            Material::Conductor { eta, k, alpha } => SpectralMaterial::Conductor {
                eta: Spectrum::unbounded(eta),
                k: Spectrum::unbounded(k),
                alpha,
            },
            Material::MeasuredConductor { metal, alpha } => {
                let (eta, k) = metal.eta_k();
                SpectralMaterial::Conductor { eta, k, alpha }
            }
        }
    }

    /// True for a glass whose index depends on the wavelength (its BSDF
    /// keeps only the hero wavelength).
    pub fn disperses(&self) -> bool {
        matches!(self, SpectralMaterial::Dielectric { eta, .. } if !eta.is_constant())
    }

    /// The BSDF at the wavelengths `lambda`. A dispersive dielectric bends
    /// each wavelength its own way, so it keeps only the hero wavelength
    /// (pbrt-v4's rule, unbiased: see [`SampledWavelengths::terminate_secondary`]).
    #[inline(always)]
    pub fn bsdf(&self, lambda: &mut SampledWavelengths) -> Bsdf {
        match self {
            SpectralMaterial::Diffuse { reflectance } => Bsdf::Diffuse {
                reflectance: reflectance.sample(lambda),
            },
            SpectralMaterial::Mirror { reflectance } => Bsdf::Mirror {
                reflectance: reflectance.sample(lambda),
            },
            SpectralMaterial::Dielectric {
                eta,
                reflectance,
                transmittance,
            } => {
                let eta = match eta {
                    Dispersion::Constant(n) => *n as f32,
                    dispersive => {
                        lambda.terminate_secondary();
                        dispersive.index(f64::from(lambda.hero_nm())) as f32
                    }
                };
                Bsdf::Dielectric {
                    eta,
                    reflectance: reflectance.sample(lambda),
                    transmittance: transmittance.sample(lambda),
                }
            }
            SpectralMaterial::Conductor { eta, k, alpha } => Bsdf::Conductor {
                eta: eta.sample(lambda),
                k: k.sample(lambda),
                alpha: *alpha,
            },
        }
    }
}

/// A material at one path's wavelengths: the BSDF the path tracer samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// Lambertian reflector.
    Diffuse {
        /// Reflectance at each wavelength.
        reflectance: SampledSpectrum,
    },
    /// Perfect specular mirror.
    Mirror {
        /// Reflectance at each wavelength.
        reflectance: SampledSpectrum,
    },
    /// Smooth dielectric (Fresnel reflection and refraction).
    Dielectric {
        /// Index of refraction inside over outside.
        eta: f32,
        /// Tint of the reflected lobe.
        reflectance: SampledSpectrum,
        /// Tint of the transmitted lobe.
        transmittance: SampledSpectrum,
    },
    /// GGX microfacet conductor.
    Conductor {
        /// Real part of the index of refraction at each wavelength.
        eta: SampledSpectrum,
        /// Imaginary part at each wavelength.
        k: SampledSpectrum,
        /// Trowbridge–Reitz roughness α (0 = polished mirror).
        alpha: f32,
    },
}

impl Bsdf {
    /// True when the BSDF is made only of delta lobes, so light sampling cannot help.
    pub fn is_specular(&self) -> bool {
        match self {
            Bsdf::Diffuse { .. } => false,
            Bsdf::Mirror { .. } | Bsdf::Dielectric { .. } => true,
            Bsdf::Conductor { alpha, .. } => *alpha < SMOOTH_ALPHA,
        }
    }

    /// The BSDF value f(wo, wi) (zero for delta lobes).
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        if wo.z * wi.z <= 0.0 {
            return SampledSpectrum::ZERO;
        }
        match *self {
            Bsdf::Diffuse { reflectance } => reflectance * FRAC_1_PI,
            Bsdf::Conductor { eta, k, alpha } if alpha >= SMOOTH_ALPHA => {
                let (wo, wi) = upper(wo, wi);
                let Some(wm) = (wo + wi).try_normalize() else {
                    return SampledSpectrum::ZERO;
                };
                let ggx = Ggx { alpha };
                let fresnel = fresnel_complex4(wo.dot(wm).abs(), eta, k);
                fresnel * (ggx.d(wm) * ggx.g(wo, wi) / (4.0 * wo.z * wi.z))
            }
            _ => SampledSpectrum::ZERO,
        }
    }

    /// Density per solid angle with which [`Bsdf::sample`] returns `wi` (zero for delta lobes).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z * wi.z <= 0.0 {
            return 0.0;
        }
        match *self {
            Bsdf::Diffuse { .. } => wi.z.abs() * FRAC_1_PI,
            Bsdf::Conductor { alpha, .. } if alpha >= SMOOTH_ALPHA => {
                let (wo, wi) = upper(wo, wi);
                let Some(wm) = (wo + wi).try_normalize() else {
                    return 0.0;
                };
                Ggx { alpha }.visible_pdf(wo, wm) / (4.0 * wo.dot(wm).abs())
            }
            _ => 0.0,
        }
    }

    /// Samples an incident direction for `wo`; `uc` picks a lobe, `u` the direction.
    // Inlined into every copy of the path loop (see `render::render_tile`),
    // which the compiler does not do by itself once there are several.
    #[inline(always)]
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let side = wo.z.signum();
        match *self {
            Bsdf::Diffuse { reflectance } => {
                let mut wi = cosine_hemisphere(u);
                wi.z *= side;
                let pdf = wi.z.abs() * FRAC_1_PI;
                (pdf > 0.0).then_some(BsdfSample {
                    wi,
                    f: reflectance * FRAC_1_PI,
                    pdf,
                    specular: false,
                    eta: 1.0,
                })
            }
            Bsdf::Mirror { reflectance } => {
                let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                Some(BsdfSample {
                    wi,
                    f: reflectance / wi.z.abs(),
                    pdf: 1.0,
                    specular: true,
                    eta: 1.0,
                })
            }
            Bsdf::Conductor { eta, k, alpha } if alpha < SMOOTH_ALPHA => {
                let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                Some(BsdfSample {
                    wi,
                    f: fresnel_complex4(wi.z.abs(), eta, k) / wi.z.abs(),
                    pdf: 1.0,
                    specular: true,
                    eta: 1.0,
                })
            }
            Bsdf::Conductor { alpha, .. } => {
                let wo_up = wo * side;
                let ggx = Ggx { alpha };
                let wm = ggx.sample_visible_normal(wo_up, u);
                let wi_up = reflect(wo_up, wm);
                if wi_up.z <= 0.0 {
                    return None;
                }
                let pdf = ggx.visible_pdf(wo_up, wm) / (4.0 * wo_up.dot(wm).abs());
                let wi = wi_up * side;
                Some(BsdfSample {
                    wi,
                    f: self.eval(wo, wi),
                    pdf,
                    specular: false,
                    eta: 1.0,
                })
            }
            Bsdf::Dielectric {
                eta,
                reflectance,
                transmittance,
            } => {
                let ((reflected, p_reflect), (transmitted, p_transmit)) =
                    dielectric_lobes(wo, eta, reflectance, transmittance);
                let p_total = p_reflect + p_transmit;
                if p_total <= 0.0 {
                    return None;
                }
                // Pick a lobe in proportion to what it carries, so a tint of zero
                // (a refraction-only surface) wastes no paths (Mitsuba 3 `dielectric`).
                let (lobe, p_lobe) = if uc * p_total < p_reflect {
                    (Some(reflected), p_reflect)
                } else {
                    (transmitted, p_transmit)
                };
                lobe.map(|s| BsdfSample {
                    pdf: p_lobe / p_total,
                    ..s
                })
            }
        }
    }

    /// Both lobes of a smooth dielectric that reflects and transmits at
    /// `wo`, each with `pdf` 1: a path split here follows both, each
    /// weighted by what it carries (f·|cos θ|), where [`Bsdf::sample`]
    /// would pick one. `None` for every other BSDF, and where a lobe
    /// carries nothing (total internal reflection, a zero tint).
    #[inline(always)]
    pub fn split(&self, wo: Vec3) -> Option<[BsdfSample; 2]> {
        let Bsdf::Dielectric {
            eta,
            reflectance,
            transmittance,
        } = *self
        else {
            return None;
        };
        if wo.z == 0.0 {
            return None;
        }
        let ((reflected, p_reflect), (transmitted, p_transmit)) = dielectric_lobes(wo, eta, reflectance, transmittance);
        match transmitted {
            Some(transmitted) if p_reflect > 0.0 && p_transmit > 0.0 => Some([reflected, transmitted]),
            _ => None,
        }
    }
}

/// A smooth dielectric's reflected lobe and its transmitted one (none on
/// total internal reflection), each with `pdf` 1, beside the weight
/// [`Bsdf::sample`] picks it by: what it carries, the Fresnel term times the
/// tint's mean.
#[inline(always)]
fn dielectric_lobes(
    wo: Vec3,
    eta: f32,
    reflectance: SampledSpectrum,
    transmittance: SampledSpectrum,
) -> ((BsdfSample, f32), (Option<BsdfSample>, f32)) {
    let fresnel = fresnel_dielectric(wo.z, eta);
    let wi = Vec3::new(-wo.x, -wo.y, wo.z);
    let reflected = BsdfSample {
        wi,
        f: reflectance * (fresnel / wi.z.abs()),
        pdf: 1.0,
        specular: true,
        eta: 1.0,
    };
    // Radiance is compressed into the denser medium: divide by η² (pbrt-v4 §9.5.2).
    let transmitted = refract(wo, Vec3::Z, eta).map(|(wi, eta_rel)| BsdfSample {
        wi,
        f: transmittance * ((1.0 - fresnel) / wi.z.abs() / (eta_rel * eta_rel)),
        pdf: 1.0,
        specular: true,
        eta: eta_rel,
    });
    (
        (reflected, fresnel * mean(reflectance)),
        (transmitted, (1.0 - fresnel) * mean(transmittance)),
    )
}

/// Mean over the wavelengths.
#[inline]
fn mean(c: SampledSpectrum) -> f32 {
    c.element_sum() / 4.0
}

/// Both directions mirrored into the +z hemisphere (they share one already).
#[inline]
fn upper(wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
    if wo.z < 0.0 {
        (-wo, -wi)
    } else {
        (wo, wi)
    }
}

/// `wo` mirrored about `n`.
#[inline]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + 2.0 * wo.dot(n) * n
}

/// Refracts `wi` through the interface with normal `n` (Snell's law in vector
/// form, pbrt-v4 `Refract`). `eta` is the IOR on the side opposite to `n`
/// over the side of `n`. Returns the transmitted direction and the relative
/// IOR actually crossed, or `None` on total internal reflection.
#[inline]
pub fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    let mut cos_i = n.dot(wi);
    let (mut eta, mut n) = (eta, n);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wi / eta + (cos_i / eta - cos_t) * n, eta))
}

/// Unpolarised Fresnel reflectance of a dielectric interface (pbrt-v4 `FrDielectric`);
/// `cos_i < 0` means the ray arrives from inside.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let (mut cos_i, mut eta) = (cos_i.clamp(-1.0, 1.0), eta);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

#[derive(Clone, Copy, Debug)]
struct Complex {
    re: f32,
    im: f32,
}

impl Complex {
    fn new(re: f32, im: f32) -> Self {
        Complex { re, im }
    }
    fn add(self, o: Complex) -> Complex {
        Complex::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: Complex) -> Complex {
        Complex::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: Complex) -> Complex {
        Complex::new(self.re * o.re - self.im * o.im, self.re * o.im + self.im * o.re)
    }
    fn div(self, o: Complex) -> Complex {
        let s = 1.0 / (o.re * o.re + o.im * o.im);
        Complex::new(
            s * (self.re * o.re + self.im * o.im),
            s * (self.im * o.re - self.re * o.im),
        )
    }
    fn norm(self) -> f32 {
        self.re * self.re + self.im * self.im
    }
    /// Principal square root (pbrt-v4 `pstd::sqrt` for complex).
    fn sqrt(self) -> Complex {
        let n = self.norm().sqrt();
        if n == 0.0 {
            return Complex::new(0.0, 0.0);
        }
        let t1 = (0.5 * (n + self.re.abs())).sqrt();
        let t2 = 0.5 * self.im / t1;
        if self.re >= 0.0 {
            Complex::new(t1, t2)
        } else {
            Complex::new(t2.abs(), t1.copysign(self.im))
        }
    }
}

/// Fresnel reflectance of a conductor with complex IOR `eta + i·k` (pbrt-v4 `FrComplex`).
pub fn fresnel_complex(cos_i: f32, eta: f32, k: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let eta = Complex::new(eta, k);
    let cos_c = Complex::new(cos_i, 0.0);
    let sin2_t = Complex::new(1.0 - cos_i * cos_i, 0.0).div(eta.mul(eta));
    let cos_t = Complex::new(1.0, 0.0).sub(sin2_t).sqrt();
    let r_parl = eta.mul(cos_c).sub(cos_t).div(eta.mul(cos_c).add(cos_t));
    let r_perp = cos_c.sub(eta.mul(cos_t)).div(cos_c.add(eta.mul(cos_t)));
    0.5 * (r_parl.norm() + r_perp.norm())
}

/// [`fresnel_complex`] at each wavelength.
fn fresnel_complex4(cos_i: f32, eta: SampledSpectrum, k: SampledSpectrum) -> SampledSpectrum {
    SampledSpectrum::new(
        fresnel_complex(cos_i, eta.x, k.x),
        fresnel_complex(cos_i, eta.y, k.y),
        fresnel_complex(cos_i, eta.z, k.z),
        fresnel_complex(cos_i, eta.w, k.w),
    )
}

/// Isotropic Trowbridge–Reitz (GGX) microfacet distribution (pbrt-v4 §9.6).
#[derive(Clone, Copy, Debug)]
struct Ggx {
    alpha: f32,
}

impl Ggx {
    /// Microfacet normal density D(wm).
    fn d(&self, wm: Vec3) -> f32 {
        let cos2 = wm.z * wm.z;
        if cos2 <= 0.0 {
            return 0.0;
        }
        let tan2 = (1.0 - cos2).max(0.0) / cos2;
        let a2 = self.alpha * self.alpha;
        let e = 1.0 + tan2 / a2;
        1.0 / (PI * a2 * cos2 * cos2 * e * e)
    }

    /// Smith's Λ(w).
    fn lambda(&self, w: Vec3) -> f32 {
        let cos2 = w.z * w.z;
        if cos2 <= 0.0 {
            return f32::INFINITY;
        }
        let tan2 = (1.0 - cos2).max(0.0) / cos2;
        0.5 * ((1.0 + self.alpha * self.alpha * tan2).sqrt() - 1.0)
    }

    fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing G(wo, wi).
    fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Density of visible normals D_wo(wm) = G1(wo) max(0, wo·wm) D(wm) / cosθo.
    fn visible_pdf(&self, wo: Vec3, wm: Vec3) -> f32 {
        self.g1(wo) / wo.z.abs() * self.d(wm) * wo.dot(wm).max(0.0)
    }

    /// Samples a visible normal for `wo` in the upper hemisphere (Heitz 2018, pbrt-v4 `Sample_wm`).
    fn sample_visible_normal(&self, wo: Vec3, u: Vec2) -> Vec3 {
        let mut wh = Vec3::new(self.alpha * wo.x, self.alpha * wo.y, wo.z).normalize();
        if wh.z < 0.0 {
            wh = -wh;
        }
        let t1 = if wh.z < 0.99999 {
            Vec3::Z.cross(wh).normalize()
        } else {
            Vec3::X
        };
        let t2 = wh.cross(t1);
        let r = u.x.sqrt();
        let phi = 2.0 * PI * u.y;
        let mut p = Vec2::new(r * phi.cos(), r * phi.sin());
        let h = (1.0 - p.x * p.x).max(0.0).sqrt();
        let s = 0.5 * (1.0 + wh.z);
        p.y = (1.0 - s) * h + s * p.y;
        let pz = (1.0 - p.length_squared()).max(0.0).sqrt();
        let nh = p.x * t1 + p.y * t2 + pz * wh;
        Vec3::new(self.alpha * nh.x, self.alpha * nh.y, nh.z.max(1e-6)).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{uniform_sphere, Rng, UNIFORM_SPHERE_PDF};

    fn direction(theta_deg: f32, phi_deg: f32) -> Vec3 {
        let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
        Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
    }

    fn glossy_materials() -> Vec<Bsdf> {
        vec![
            Bsdf::Diffuse {
                reflectance: SampledSpectrum::new(0.8, 0.5, 0.2, 0.6),
            },
            // Gold, silver and copper at three roughnesses.
            Bsdf::Conductor {
                eta: SampledSpectrum::new(0.143, 0.374, 1.442, 0.5),
                k: SampledSpectrum::new(3.983, 2.385, 1.603, 2.0),
                alpha: 0.05,
            },
            Bsdf::Conductor {
                eta: SampledSpectrum::new(0.155, 0.117, 0.138, 0.13),
                k: SampledSpectrum::new(4.828, 3.122, 2.147, 4.0),
                alpha: 0.3,
            },
            Bsdf::Conductor {
                eta: SampledSpectrum::new(0.200, 0.924, 1.102, 0.3),
                k: SampledSpectrum::new(3.912, 2.452, 2.142, 3.5),
                alpha: 0.7,
            },
        ]
    }

    fn clear_glass(eta: f32) -> Bsdf {
        Bsdf::Dielectric {
            eta,
            reflectance: SampledSpectrum::ONE,
            transmittance: SampledSpectrum::ONE,
        }
    }

    /// ∫ pdf(wo, wi) dwi over the sphere, by uniform sampling, equals the
    /// probability that `sample` returns a direction (1 for diffuse; less for
    /// GGX, whose reflected visible normals can point below the horizon).
    #[test]
    fn pdf_integrates_to_the_sampling_probability() {
        let n = 400_000;
        // Uniform sampling cannot resolve very sharp lobes; those are covered
        // by the sample/eval agreement test.
        let resolvable = glossy_materials()
            .into_iter()
            .filter(|m| !matches!(m, Bsdf::Conductor { alpha, .. } if *alpha < 0.2));
        for m in resolvable {
            for theta in [0.0, 30.0, 60.0, 85.0, 120.0] {
                let wo = direction(theta, 20.0);
                let mut rng = Rng::new(11);
                let mut integral = 0.0f64;
                let mut successes = 0;
                for _ in 0..n {
                    let wi = uniform_sphere(rng.uniform(), rng.uniform());
                    integral += f64::from(m.pdf(wo, wi) / UNIFORM_SPHERE_PDF);
                    if m.sample(wo, rng.uniform(), Vec2::new(rng.uniform(), rng.uniform()))
                        .is_some()
                    {
                        successes += 1;
                    }
                }
                let integral = integral / n as f64;
                let probability = successes as f64 / n as f64;
                assert!(
                    (integral - probability).abs() < 0.03,
                    "{m:?} θo={theta}: ∫pdf = {integral}, P(sample) = {probability}"
                );
                if let Bsdf::Diffuse { .. } = m {
                    assert!((integral - 1.0).abs() < 0.01);
                }
            }
        }
    }

    #[test]
    fn sample_agrees_with_eval_and_pdf() {
        for m in glossy_materials() {
            let mut rng = Rng::new(5);
            for _ in 0..20_000 {
                let wo = uniform_sphere(rng.uniform(), rng.uniform());
                let Some(s) = m.sample(wo, rng.uniform(), Vec2::new(rng.uniform(), rng.uniform())) else {
                    continue;
                };
                let f = m.eval(wo, s.wi);
                let pdf = m.pdf(wo, s.wi);
                assert!(
                    (s.pdf - pdf).abs() <= 2e-3 * pdf.max(1.0),
                    "{m:?}: pdf {} vs {pdf}",
                    s.pdf
                );
                assert!((s.f - f).abs().max_element() <= 2e-3 * f.max_element().max(1.0));
            }
        }
    }

    #[test]
    fn bsdfs_are_reciprocal() {
        let mut rng = Rng::new(9);
        for m in glossy_materials() {
            for _ in 0..10_000 {
                let wo = uniform_sphere(rng.uniform(), rng.uniform());
                let wi = uniform_sphere(rng.uniform(), rng.uniform());
                let (a, b) = (m.eval(wo, wi), m.eval(wi, wo));
                assert!((a - b).abs().max_element() <= 1e-4 * a.max_element().max(1.0), "{m:?}");
            }
        }
    }

    /// Directional albedo E[f cosθ / pdf] never exceeds 1 (energy conservation);
    /// the Lambertian one equals its reflectance.
    #[test]
    fn albedo_is_at_most_one() {
        let mut materials = glossy_materials();
        // A conductor with a huge k reflects almost everything.
        materials.push(Bsdf::Conductor {
            eta: SampledSpectrum::splat(0.05),
            k: SampledSpectrum::splat(20.0),
            alpha: 0.2,
        });
        for m in materials {
            for theta in [5.0, 45.0, 80.0] {
                let wo = direction(theta, 0.0);
                let mut rng = Rng::new(1);
                let n = 100_000;
                let mut sum = glam::DVec4::ZERO;
                for _ in 0..n {
                    if let Some(s) = m.sample(wo, rng.uniform(), Vec2::new(rng.uniform(), rng.uniform())) {
                        sum += (s.f * s.wi.z.abs() / s.pdf).as_dvec4();
                    }
                }
                let albedo = (sum / n as f64).as_vec4();
                assert!(albedo.max_element() <= 1.0 + 5e-3, "{m:?} θ={theta}: albedo {albedo}");
                if let Bsdf::Diffuse { reflectance } = m {
                    assert!((albedo - reflectance).abs().max_element() < 1e-4);
                }
                if let Bsdf::Conductor { k, .. } = m {
                    if k.x == 20.0 && theta < 50.0 {
                        assert!(
                            albedo.x > 0.9,
                            "a near-perfect rough conductor loses too much: {albedo}"
                        );
                    }
                }
            }
        }
    }

    /// Glass: reflected plus transmitted energy (undoing the 1/η² radiance
    /// scaling) is exactly 1 from both sides, refraction obeys Snell's law, and
    /// beyond the critical angle everything reflects.
    #[test]
    fn dielectric_conserves_energy_and_obeys_snell() {
        let eta = 1.5;
        let glass = clear_glass(eta);
        for theta in [0.0, 20.0, 40.0, 41.0, 60.0, 89.0, 100.0, 130.0, 150.0, 179.0] {
            let wo = direction(theta, 35.0);
            let mut energy = 0.0;
            let n = 2000;
            for i in 0..n {
                let s = glass.sample(wo, (i as f32 + 0.5) / n as f32, Vec2::ZERO).unwrap();
                assert!(s.specular);
                let mut e = s.f.x * s.wi.z.abs() / s.pdf;
                if s.wi.z * wo.z < 0.0 {
                    let (eta_i, eta_t) = if wo.z > 0.0 { (1.0, eta) } else { (eta, 1.0) };
                    let sin_o = (1.0 - wo.z * wo.z).sqrt();
                    let sin_i = (1.0 - s.wi.z * s.wi.z).sqrt();
                    assert!(
                        (eta_i * sin_o - eta_t * sin_i).abs() < 1e-4,
                        "Snell violated at θ={theta}"
                    );
                    e *= (eta_t / eta_i) * (eta_t / eta_i);
                }
                energy += e;
            }
            assert!(
                (energy / n as f32 - 1.0).abs() < 1e-4,
                "θ={theta}: energy {}",
                energy / n as f32
            );
        }
        // From inside at 60° (critical angle 41.8°): total internal reflection.
        let wo = direction(180.0 - 60.0, 0.0);
        for u in [0.0, 0.5, 0.999] {
            let s = glass.sample(wo, u, Vec2::ZERO).unwrap();
            assert!(s.wi.z < 0.0 && (s.pdf - 1.0).abs() < 1e-6);
        }
        // Normal incidence: R = ((η-1)/(η+1))² = 0.04.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
    }

    /// Tinted glass returns F·R + (1 − F)·T/η² per channel (the expected value of
    /// f·cosθ/pdf over the lobe choice), including the refraction-only case R = 0.
    #[test]
    fn tinted_dielectric_weights_each_lobe_by_its_tint() {
        let eta = 1.45;
        for (reflectance, transmittance) in [
            (SampledSpectrum::ONE, SampledSpectrum::new(1.0, 0.75, 0.75, 0.5)),
            (SampledSpectrum::ZERO, SampledSpectrum::ONE),
            (SampledSpectrum::new(0.5, 1.0, 0.2, 0.1), SampledSpectrum::ZERO),
        ] {
            let glass = Bsdf::Dielectric {
                eta,
                reflectance,
                transmittance,
            };
            let wo = direction(50.0, 10.0);
            let fresnel = fresnel_dielectric(wo.z, eta);
            let expected = reflectance * fresnel + transmittance * ((1.0 - fresnel) / (eta * eta));
            let n = 4000;
            let mut sum = SampledSpectrum::ZERO;
            for i in 0..n {
                let s = glass.sample(wo, (i as f32 + 0.5) / n as f32, Vec2::ZERO).unwrap();
                sum += s.f * s.wi.z.abs() / s.pdf;
            }
            let got = sum / n as f32;
            assert!(
                (got - expected).abs().max_element() < 2e-3,
                "R={reflectance} T={transmittance}: {got} vs {expected}"
            );
            // Split, the two lobes carry exactly that expectation; a lobe
            // that carries nothing is no split.
            match glass.split(wo) {
                Some(lobes) => {
                    let carried: SampledSpectrum = lobes.iter().map(|s| s.f * s.wi.z.abs() / s.pdf).sum();
                    assert!(
                        (carried - expected).abs().max_element() < 1e-6,
                        "split: {carried} vs {expected}"
                    );
                    assert!(lobes[0].wi.z > 0.0 && lobes[1].wi.z < 0.0);
                }
                None => assert!(reflectance == SampledSpectrum::ZERO || transmittance == SampledSpectrum::ZERO),
            }
        }
        // Total internal reflection leaves one lobe: no split.
        assert!(clear_glass(1.5).split(direction(180.0 - 60.0, 0.0)).is_none());
        assert!(clear_glass(1.5).split(direction(180.0 - 30.0, 0.0)).is_some());
        let black = Bsdf::Dielectric {
            eta,
            reflectance: SampledSpectrum::ZERO,
            transmittance: SampledSpectrum::ZERO,
        };
        assert!(black.sample(direction(30.0, 0.0), 0.5, Vec2::ZERO).is_none());
    }

    /// A material's spectra at a path's wavelengths are its fitted spectra's
    /// values there, and a flat RGB gives a flat spectrum.
    #[test]
    fn spectral_material_evaluates_its_fitted_spectra() {
        let lambda = SampledWavelengths::new(SampledSpectrum::new(450.0, 520.0, 600.0, 680.0), SampledSpectrum::ONE);
        let orange = Rgb::new(0.8, 0.4, 0.1);
        let spectral = SpectralMaterial::new(&Material::Diffuse { reflectance: orange });
        let Bsdf::Diffuse { reflectance } = spectral.bsdf(&mut lambda.clone()) else {
            panic!("a diffuse material gives a diffuse BSDF");
        };
        let fitted = Spectrum::reflectance(orange);
        for i in 0..4 {
            assert_eq!(reflectance[i], fitted.at(lambda.lambda_nm[i]));
        }
        assert!(
            reflectance.w > reflectance.x,
            "orange reflects more red than blue: {reflectance}"
        );
        let grey = SpectralMaterial::new(&Material::Mirror {
            reflectance: Rgb::splat(0.3),
        });
        let Bsdf::Mirror { reflectance } = grey.bsdf(&mut lambda.clone()) else {
            panic!("a mirror gives a mirror");
        };
        assert!((reflectance - SampledSpectrum::splat(0.3)).abs().max_element() < 1e-6);
    }

    /// Real glass refracts each wavelength its own way and keeps only the
    /// hero: N-BK7 takes its datasheet index at the hero wavelength, and a
    /// constant index leaves the four wavelengths alone.
    #[test]
    fn dispersive_glass_keeps_the_hero_wavelength() {
        let bk7 = crate::glass::find("N-BK7").unwrap().dispersion;
        let glass = SpectralMaterial::new(&Material::Dielectric {
            eta: bk7,
            reflectance: Rgb::ONE,
            transmittance: Rgb::ONE,
        });
        let mut lambda = SampledWavelengths::sample_visible(0.1);
        let hero = lambda.hero_nm();
        let Bsdf::Dielectric { eta, .. } = glass.bsdf(&mut lambda) else {
            panic!("glass gives a dielectric");
        };
        assert!((f64::from(eta) - bk7.index(f64::from(hero))).abs() < 1e-6);
        assert!(lambda.secondary_terminated());
        let mut plain = SampledWavelengths::sample_visible(0.1);
        SpectralMaterial::new(&Material::clear_dielectric(1.5)).bsdf(&mut plain);
        assert!(!plain.secondary_terminated());
        // Light arriving at 45° refracts by Snell's law with Schott's
        // datasheet index of each line: blue (F, n = 1.52238) bends more than
        // red (C, n = 1.51432), 0.160° apart.
        let wo = Vec3::new(45f32.to_radians().sin(), 0.0, 45f32.to_radians().cos());
        let refracted_deg = |nm: f32| {
            let mut lambda =
                SampledWavelengths::new(SampledSpectrum::new(nm, 500.0, 600.0, 700.0), SampledSpectrum::ONE);
            let bsdf = glass.bsdf(&mut lambda);
            // uc near 1 picks the transmitted lobe (reflection takes the first F of [0, 1)).
            let s = bsdf.sample(wo, 0.999, Vec2::ZERO).unwrap();
            assert!(s.wi.z < 0.0, "transmitted");
            (-s.wi.z).acos().to_degrees()
        };
        let snell = |n: f32| (45f32.to_radians().sin() / n).asin().to_degrees();
        let (blue, red) = (refracted_deg(486.1327), refracted_deg(656.2725));
        assert!(
            (blue - snell(1.52238)).abs() < 2e-3,
            "F line {blue}° vs {}°",
            snell(1.52238)
        );
        assert!(
            (red - snell(1.51432)).abs() < 2e-3,
            "C line {red}° vs {}°",
            snell(1.51432)
        );
        assert!((red - blue - 0.160).abs() < 3e-3, "spread {}°", red - blue);
    }

    #[test]
    fn complex_fresnel_limits() {
        // k = 0 reduces to the dielectric formula.
        for c in [0.1, 0.5, 0.9, 1.0] {
            assert!((fresnel_complex(c, 1.5, 0.0) - fresnel_dielectric(c, 1.5)).abs() < 1e-5);
        }
        // Normal incidence: ((η-1)² + k²) / ((η+1)² + k²).
        let (eta, k) = (0.2f32, 3.9f32);
        let expected = ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k);
        assert!((fresnel_complex(1.0, eta, k) - expected).abs() < 1e-5);
        // Grazing incidence reflects everything.
        assert!((fresnel_complex(0.0, eta, k) - 1.0).abs() < 1e-4);
    }
}
