//! Aperture shapes: what the opening at the aperture stop looks like, and how
//! to sample it by importance.
//!
//! Shapes live in the stop's own coordinates scaled to its radius: the unit
//! disk, x right and y up as seen looking into the scene (camera space). The
//! stop's circle always clips them, as the iris does a mask placed in it.
//! Light through the stop follows the open area: an aperture's
//! [`Aperture::open_fraction`] is its transmitted area over the full circle's,
//! so a hexagon passes 3√3/(2π) ≈ 83% and a half-open mask half.
//!
//! A point out of focus beyond the focus plane images as the shape as it lies
//! here (a mask image as displayed, top row up); one nearer than the focus
//! plane as the shape turned by 180°.

use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::Arc;

use glam::{DVec2, Vec2};

use crate::error::{Error, Result};
use crate::sampling::{concentric_disk, Distribution1D};

/// Resolution of the raster that curved blades are sampled from.
const CURVED_RASTER: usize = 512;
/// Sub-samples per side for a raster pixel's coverage.
const COVERAGE_SUBSAMPLES: usize = 4;

/// A grayscale transmission map laid over the stop's bounding square.
#[derive(Clone, PartialEq)]
pub struct ApertureMask {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Transmission in [0, 1], row-major from the top row (+y) down.
    pub values: Vec<f32>,
}

impl std::fmt::Debug for ApertureMask {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ApertureMask({}x{})", self.width, self.height)
    }
}

impl ApertureMask {
    /// A mask from `values` (row-major, top row first), checked.
    pub fn new(width: usize, height: usize, values: Vec<f32>) -> Result<ApertureMask> {
        if width == 0 || height == 0 || values.len() != width * height {
            return Err(Error::InvalidArgument(format!(
                "aperture mask of {width}x{height} pixels needs {} values, got {}",
                width * height,
                values.len()
            )));
        }
        if let Some(bad) = values.iter().find(|v| !(0.0..=1.0).contains(*v)) {
            return Err(Error::InvalidArgument(format!(
                "aperture mask values must be transmissions in [0, 1], found {bad}"
            )));
        }
        if values.iter().all(|&v| v == 0.0) {
            return Err(Error::InvalidArgument(
                "aperture mask is completely closed (all black)".into(),
            ));
        }
        Ok(ApertureMask { width, height, values })
    }
}

impl ApertureShape {
    /// A [`ApertureShape::Mask`] from `width` × `height` transmissions, row
    /// by row from the top (values above 1 count as 1).
    pub fn mask(width: usize, height: usize, values: Vec<f32>) -> Result<ApertureShape> {
        if values.iter().any(|v| !v.is_finite() || *v < 0.0) {
            return Err(Error::InvalidArgument(
                "aperture mask values must be finite and not negative".into(),
            ));
        }
        let values = values.into_iter().map(|v| v.min(1.0)).collect();
        Ok(ApertureShape::Mask(Arc::new(ApertureMask::new(width, height, values)?)))
    }
}

/// The shape of the opening at the aperture stop.
#[derive(Clone, Debug, PartialEq)]
pub enum ApertureShape {
    /// The stop's own circle.
    Circle,
    /// An iris of `count` blades: a regular polygon inscribed in the stop
    /// circle, a corner at the top before `rotation_deg` (counter-clockwise).
    /// `curvature` bends the blades' edges out toward the circle: 0 straight,
    /// 1 on the circle (the sagitta is that fraction of the circle's).
    Blades {
        /// Number of blades, at least 3.
        count: u32,
        /// Rotation, degrees counter-clockwise.
        rotation_deg: f64,
        /// Edge curvature in [0, 1].
        curvature: f64,
    },
    /// A star of `points` points on the stop circle, the notches between them
    /// at `inner_ratio` of its radius; a point at the top before `rotation_deg`.
    Star {
        /// Number of points, at least 3.
        points: u32,
        /// Radius of the notches over the radius of the points, in (0, 1].
        inner_ratio: f64,
        /// Rotation, degrees counter-clockwise.
        rotation_deg: f64,
    },
    /// A transmission map over the stop's bounding square.
    Mask(Arc<ApertureMask>),
}

impl ApertureShape {
    /// Parses `circle`, `blades:N[:ROTATION[:CURVATURE]]` or
    /// `star:N[:INNER_RATIO[:ROTATION]]` (the CLI's and scene files' spelling).
    pub fn parse(text: &str) -> Result<ApertureShape> {
        let fail = |why: String| {
            Error::InvalidArgument(format!(
                "aperture shape '{text}': {why}; expected circle, blades:N[:ROTATION_DEG[:CURVATURE]] or star:N[:INNER_RATIO[:ROTATION_DEG]]"
            ))
        };
        let mut parts = text.split(':');
        let kind = parts.next().unwrap_or_default().trim().to_ascii_lowercase();
        let numbers = parts
            .map(|p| {
                p.trim()
                    .parse::<f64>()
                    .map_err(|_| fail(format!("'{p}' is not a number")))
            })
            .collect::<Result<Vec<f64>>>()?;
        let count = |n: Option<&f64>| match n {
            Some(&n) if n.fract() == 0.0 && (3.0..=64.0).contains(&n) => Ok(n as u32),
            Some(n) => Err(fail(format!("the count must be a whole number from 3 to 64, got {n}"))),
            None => Err(fail("missing the count".into())),
        };
        let shape = match (kind.as_str(), numbers.len()) {
            ("circle", 0) => ApertureShape::Circle,
            ("blades" | "star", 0) => return Err(fail("missing the count".into())),
            ("blades", 1..=3) => ApertureShape::Blades {
                count: count(numbers.first())?,
                rotation_deg: numbers.get(1).copied().unwrap_or(0.0),
                curvature: numbers.get(2).copied().unwrap_or(0.0),
            },
            ("star", 1..=3) => ApertureShape::Star {
                points: count(numbers.first())?,
                inner_ratio: numbers.get(1).copied().unwrap_or(0.5),
                rotation_deg: numbers.get(2).copied().unwrap_or(0.0),
            },
            _ => return Err(fail("unknown shape or wrong number of values".into())),
        };
        shape.validate()?;
        Ok(shape)
    }

    /// The spelling [`ApertureShape::parse`] reads back to this shape exactly
    /// (`None` for a mask, which is an image, not a spelling).
    pub fn spelling(&self) -> Option<String> {
        match self {
            ApertureShape::Circle => Some("circle".into()),
            ApertureShape::Blades {
                count,
                rotation_deg,
                curvature,
            } => Some(format!("blades:{count}:{rotation_deg}:{curvature}")),
            ApertureShape::Star {
                points,
                inner_ratio,
                rotation_deg,
            } => Some(format!("star:{points}:{inner_ratio}:{rotation_deg}")),
            ApertureShape::Mask(_) => None,
        }
    }

    fn validate(&self) -> Result<()> {
        let bad = |why: String| Err(Error::InvalidArgument(format!("aperture shape: {why}")));
        match *self {
            ApertureShape::Blades {
                count,
                rotation_deg,
                curvature,
            } => {
                if count < 3 {
                    return bad(format!("an iris needs at least 3 blades, got {count}"));
                }
                if !(0.0..=1.0).contains(&curvature) {
                    return bad(format!("blade curvature must be in [0, 1], got {curvature}"));
                }
                if !rotation_deg.is_finite() {
                    return bad(format!("rotation must be finite, got {rotation_deg}"));
                }
            }
            ApertureShape::Star {
                points,
                inner_ratio,
                rotation_deg,
            } => {
                if points < 3 {
                    return bad(format!("a star needs at least 3 points, got {points}"));
                }
                if !(inner_ratio > 0.0 && inner_ratio <= 1.0) {
                    return bad(format!("star inner ratio must be in (0, 1], got {inner_ratio}"));
                }
                if !rotation_deg.is_finite() {
                    return bad(format!("rotation must be finite, got {rotation_deg}"));
                }
            }
            ApertureShape::Circle | ApertureShape::Mask(_) => {}
        }
        Ok(())
    }
}

/// How an [`Aperture`] is sampled.
#[derive(Clone, Debug)]
enum Sampler {
    /// The unit disk, by Shirley's concentric map.
    Disk,
    /// A polygon star-shaped about the origin: a fan of triangles from it, one
    /// picked in proportion to its area, then a uniform point in it.
    Fan {
        vertices: Vec<DVec2>,
        triangles: Distribution1D,
    },
    /// A raster of transmissions over [-1, 1]²: a pixel picked in proportion
    /// to its value (rows, then columns), then a uniform point in it.
    Raster {
        width: usize,
        height: usize,
        /// Transmission integrated over the part of each pixel inside the
        /// stop's circle, over the pixel's area: what is sampled.
        values: Vec<f32>,
        /// The fraction of each pixel inside the stop's circle.
        circle_coverage: Vec<f32>,
        rows: Distribution1D,
        columns: Vec<Distribution1D>,
        /// ∑ value · pixel area.
        open_area: f64,
    },
}

/// An aperture shape ready to sample: points on the unit disk distributed in
/// proportion to the transmission, never by rejection.
#[derive(Clone, Debug)]
pub struct Aperture {
    shape: ApertureShape,
    sampler: Sampler,
    open_fraction: f64,
}

impl Aperture {
    /// Prepares `shape` for sampling.
    pub fn new(shape: &ApertureShape) -> Result<Aperture> {
        shape.validate()?;
        let sampler = match shape {
            ApertureShape::Circle => Sampler::Disk,
            ApertureShape::Blades {
                count,
                rotation_deg,
                curvature,
            } if *curvature == 0.0 => fan(polygon_vertices(*count, 1.0, *rotation_deg)),
            &ApertureShape::Blades {
                count,
                rotation_deg,
                curvature,
            } => {
                let n = CURVED_RASTER;
                let inside = |p| inside_curved_blades(count, rotation_deg, curvature, p);
                raster(n, n, coverage_raster(n, n, inside))?
            }
            ApertureShape::Star {
                points,
                inner_ratio,
                rotation_deg,
            } => fan(polygon_vertices(*points, *inner_ratio, *rotation_deg)),
            ApertureShape::Mask(mask) => {
                // The stop's circle clips the mask: each pixel's value is
                // weighted by how much of it lies inside.
                let (w, h) = (mask.width, mask.height);
                let inside = circle_coverage(w, h);
                let values = mask.values.iter().zip(inside).map(|(v, c)| v * c).collect();
                raster(w, h, values)?
            }
        };
        if let Sampler::Fan { vertices, .. } = &sampler {
            let area: f64 = fan_areas(vertices).iter().sum();
            if area.is_nan() || area <= 0.0 {
                return Err(Error::InvalidArgument("aperture shape has no open area".into()));
            }
        }
        let open_fraction = match &sampler {
            Sampler::Disk => 1.0,
            Sampler::Fan { vertices, .. } => fan_areas(vertices).iter().sum::<f64>() / PI,
            Sampler::Raster { open_area, .. } => open_area / PI,
        };
        Ok(Aperture {
            shape: shape.clone(),
            sampler,
            open_fraction,
        })
    }

    /// The shape it samples.
    pub fn shape(&self) -> &ApertureShape {
        &self.shape
    }

    /// Whether it is the plain circle (the cameras' fast path).
    pub fn is_circle(&self) -> bool {
        matches!(self.sampler, Sampler::Disk)
    }

    /// Transmitted area over the unit disk's area π.
    pub fn open_fraction(&self) -> f64 {
        self.open_fraction
    }

    /// A point of the unit disk's square for `u` in [0, 1)², with density
    /// proportional to the transmission; returns it and that density (per
    /// unit area, so it integrates to 1 over the square).
    pub fn sample(&self, u: Vec2) -> (DVec2, f64) {
        let p = match &self.sampler {
            Sampler::Disk => {
                let d = concentric_disk(u);
                DVec2::new(f64::from(d.x), f64::from(d.y))
            }
            Sampler::Fan { vertices, triangles } => {
                let (k, _, ux) = triangles.sample(u.x);
                let (a, b) = (vertices[k], vertices[(k + 1) % vertices.len()]);
                // Uniform in the triangle (origin, a, b): square-root warp.
                let (s, t) = (f64::from(ux).sqrt(), f64::from(u.y));
                a * (s * (1.0 - t)) + b * (s * t)
            }
            Sampler::Raster {
                width,
                height,
                rows,
                columns,
                ..
            } => {
                let (row, _, uy) = rows.sample(u.y);
                let (column, _, ux) = columns[row].sample(u.x);
                let x = -1.0 + 2.0 * (column as f64 + f64::from(ux)) / *width as f64;
                let y = 1.0 - 2.0 * (row as f64 + f64::from(uy)) / *height as f64;
                DVec2::new(x, y)
            }
        };
        (p, self.pdf(p))
    }

    /// The density [`Aperture::sample`] draws `p` with.
    pub fn pdf(&self, p: DVec2) -> f64 {
        match &self.sampler {
            Sampler::Disk => {
                if p.length_squared() <= 1.0 {
                    1.0 / PI
                } else {
                    0.0
                }
            }
            Sampler::Fan { .. } => {
                if self.transmission(p) > 0.0 {
                    1.0 / (self.open_fraction * PI)
                } else {
                    0.0
                }
            }
            Sampler::Raster { open_area, .. } => self.raster_value(p) / open_area,
        }
    }

    /// Transmission at `p` (unit-disk coordinates): 0 outside the stop circle.
    pub fn transmission(&self, p: DVec2) -> f64 {
        if p.length_squared() > 1.0 {
            return 0.0;
        }
        match &self.sampler {
            Sampler::Disk => 1.0,
            Sampler::Fan { vertices, .. } => {
                if inside_fan(vertices, p) {
                    1.0
                } else {
                    0.0
                }
            }
            Sampler::Raster { circle_coverage, .. } => {
                // The pixel's transmission where it is inside the circle: its
                // value spread over that part alone. (Its value as such would
                // count an edge pixel's coverage twice, once in the sampling
                // and once in the weight, and darken the shape's rim.)
                match self.raster_index(p) {
                    Some(i) if circle_coverage[i] > 0.0 => self.raster_value(p) / f64::from(circle_coverage[i]),
                    _ => 0.0,
                }
            }
        }
    }

    /// The raster pixel holding `p`, if it is on the square and the sampler a raster.
    fn raster_index(&self, p: DVec2) -> Option<usize> {
        let Sampler::Raster { width, height, .. } = &self.sampler else {
            return None;
        };
        let column = ((p.x + 1.0) * 0.5 * *width as f64).floor();
        let row = ((1.0 - p.y) * 0.5 * *height as f64).floor();
        if column < 0.0 || row < 0.0 || column >= *width as f64 || row >= *height as f64 {
            return None;
        }
        Some(row as usize * width + column as usize)
    }

    /// The raster's value at `p` (nearest pixel), 0 off the square.
    fn raster_value(&self, p: DVec2) -> f64 {
        match (&self.sampler, self.raster_index(p)) {
            (Sampler::Raster { values, .. }, Some(i)) => f64::from(values[i]),
            _ => 0.0,
        }
    }

    /// The transmission averaged over each pixel of a `width`×`height`
    /// raster of the square [-e, e]² for `half_extent` e (1: the unit disk's
    /// bounding square), 4×4 points per pixel, top row +y: the shape as a
    /// blur kernel.
    pub fn rasterize(&self, width: usize, height: usize, half_extent: f64) -> Vec<f32> {
        pixel_averages(width, height, |p| self.transmission(p * half_extent))
    }
}

/// Vertices of a regular polygon (`inner_ratio` = 1) or star, counter-clockwise,
/// a corner at the top rotated by `rotation_deg`.
fn polygon_vertices(count: u32, inner_ratio: f64, rotation_deg: f64) -> Vec<DVec2> {
    let start = FRAC_PI_2 + rotation_deg.rem_euclid(360.0).to_radians();
    let corner = |k: u32, r: f64, half: f64| {
        let a = start + TAU * (f64::from(k) + half) / f64::from(count);
        DVec2::new(a.cos(), a.sin()) * r
    };
    if inner_ratio >= 1.0 {
        (0..count).map(|k| corner(k, 1.0, 0.0)).collect()
    } else {
        (0..count)
            .flat_map(|k| [corner(k, 1.0, 0.0), corner(k, inner_ratio, 0.5)])
            .collect()
    }
}

/// Areas of the fan triangles (origin, vᵢ, vᵢ₊₁).
fn fan_areas(vertices: &[DVec2]) -> Vec<f64> {
    (0..vertices.len())
        .map(|k| 0.5 * vertices[k].perp_dot(vertices[(k + 1) % vertices.len()]).abs())
        .collect()
}

fn fan(vertices: Vec<DVec2>) -> Sampler {
    let areas: Vec<f32> = fan_areas(&vertices).iter().map(|&a| a as f32).collect();
    Sampler::Fan {
        triangles: Distribution1D::new(&areas),
        vertices,
    }
}

/// Whether `p` lies in the polygon star-shaped about the origin with these
/// counter-clockwise vertices: in the fan triangle of its sector.
fn inside_fan(vertices: &[DVec2], p: DVec2) -> bool {
    let n = vertices.len();
    (0..n).any(|k| {
        let (a, b) = (vertices[k], vertices[(k + 1) % n]);
        // p within the sector between a and b, and on the origin's side of ab.
        a.perp_dot(p) >= 0.0 && p.perp_dot(b) >= 0.0 && (b - a).perp_dot(p - a) >= 0.0
    })
}

/// Whether `p` lies inside curved blades: in its sector, within the arc
/// through the two corners that bulges out by `curvature` of the circle's sagitta.
fn inside_curved_blades(count: u32, rotation_deg: f64, curvature: f64, p: DVec2) -> bool {
    if p.length_squared() > 1.0 {
        return false;
    }
    let half = PI / f64::from(count);
    // Angle from the nearest edge's midpoint direction.
    let start = FRAC_PI_2 + rotation_deg.rem_euclid(360.0).to_radians();
    let a = (p.y.atan2(p.x) - start - half).rem_euclid(2.0 * half) - half;
    let along = p.length() * a.cos();
    let across = p.length() * a.sin();
    let (chord_half, apothem) = (half.sin(), half.cos());
    let sagitta = curvature * (1.0 - apothem);
    if sagitta <= 0.0 {
        return along <= apothem;
    }
    // The arc's radius and centre (on the edge's bisector) from chord and sagitta.
    let radius = (chord_half * chord_half + sagitta * sagitta) / (2.0 * sagitta);
    let centre = apothem + sagitta - radius;
    (along - centre).hypot(across) <= radius
}

/// The mean of `f` over each pixel of a `w`×`h` raster of [-1, 1]² (top
/// row +y), from 4×4 points per pixel.
fn pixel_averages(w: usize, h: usize, f: impl Fn(DVec2) -> f64) -> Vec<f32> {
    let n = COVERAGE_SUBSAMPLES;
    (0..w * h)
        .map(|k| {
            let (row, column) = (k / w, k % w);
            let sum: f64 = (0..n * n)
                .map(|s| {
                    let x = -1.0 + 2.0 * (column as f64 + ((s % n) as f64 + 0.5) / n as f64) / w as f64;
                    let y = 1.0 - 2.0 * (row as f64 + ((s / n) as f64 + 0.5) / n as f64) / h as f64;
                    f(DVec2::new(x, y))
                })
                .sum();
            (sum / (n * n) as f64) as f32
        })
        .collect()
}

/// The fraction of each pixel that `inside` holds for.
fn coverage_raster(w: usize, h: usize, inside: impl Fn(DVec2) -> bool) -> Vec<f32> {
    pixel_averages(w, h, |p| f64::from(u8::from(inside(p))))
}

/// The fraction of each pixel inside the stop's (unit) circle.
fn circle_coverage(w: usize, h: usize) -> Vec<f32> {
    coverage_raster(w, h, |p| p.length_squared() <= 1.0)
}

/// A raster sampler of `values` (transmission integrated over each pixel's
/// part inside the circle, over the pixel area).
fn raster(width: usize, height: usize, values: Vec<f32>) -> Result<Sampler> {
    let pixel_area = 4.0 / (width * height) as f64;
    let row_sums: Vec<f32> = values.chunks_exact(width).map(|r| r.iter().sum()).collect();
    let open_area = values.iter().map(|&v| f64::from(v)).sum::<f64>() * pixel_area;
    if open_area <= 0.0 {
        return Err(Error::InvalidArgument(
            "aperture mask is closed within the stop's circle".into(),
        ));
    }
    let columns = values
        .chunks_exact(width)
        .zip(&row_sums)
        .map(|(row, &sum)| {
            // A closed row is never picked; give it any valid distribution.
            if sum > 0.0 {
                Distribution1D::new(row)
            } else {
                Distribution1D::new(&vec![1.0; width])
            }
        })
        .collect();
    Ok(Sampler::Raster {
        width,
        height,
        rows: Distribution1D::new(&row_sums),
        columns,
        circle_coverage: circle_coverage(width, height),
        values,
        open_area,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn shapes() -> Vec<(ApertureShape, f64)> {
        let half_open: Vec<f32> = (0..64 * 64).map(|k| if k % 64 < 32 { 1.0 } else { 0.0 }).collect();
        let hexagon = 3.0 * 3f64.sqrt() / (2.0 * PI);
        // A star: 2N triangles of sides 1 and r at an angle π/N.
        let star = 5.0 * 0.4 * (PI / 5.0).sin() / PI;
        vec![
            (ApertureShape::Circle, 1.0),
            (ApertureShape::parse("blades:6").unwrap(), hexagon),
            (ApertureShape::parse("blades:6:15:1").unwrap(), 1.0),
            (ApertureShape::parse("star:5:0.4:10").unwrap(), star),
            (
                ApertureShape::Mask(Arc::new(ApertureMask::new(64, 64, half_open).unwrap())),
                0.5,
            ),
            // All open, coarse: most of its pixels are cut by the circle.
            (
                ApertureShape::Mask(Arc::new(ApertureMask::new(12, 12, vec![1.0; 144]).unwrap())),
                1.0,
            ),
        ]
    }

    /// ∫ f over the unit disk's square [-1, 1]², by the midpoint rule on an `m` × `m` grid.
    fn square_integral(m: u32, f: impl Fn(DVec2) -> f64) -> f64 {
        let cell = 2.0 / f64::from(m);
        (0..m * m)
            .map(|k| {
                let (i, j) = (f64::from(k % m), f64::from(k / m));
                f(DVec2::new(-1.0 + (i + 0.5) * cell, -1.0 + (j + 0.5) * cell)) * cell * cell
            })
            .sum()
    }

    /// The open fractions are the shapes' areas over π (a curved iris of
    /// curvature 1 is the circle), to raster accuracy for masks.
    #[test]
    fn open_fraction_is_the_area_over_the_circle() {
        for (shape, expected) in shapes() {
            let a = Aperture::new(&shape).unwrap();
            assert!(
                (a.open_fraction() - expected).abs() < 0.01 * expected,
                "{shape:?}: {}",
                a.open_fraction()
            );
        }
        let curved = Aperture::new(&ApertureShape::parse("blades:6:0:0.5").unwrap()).unwrap();
        assert!(
            (0.84..0.99).contains(&curved.open_fraction()),
            "{}",
            curved.open_fraction()
        );
    }

    /// Sampling matches the density it reports and covers what transmits:
    /// ∑ g(s) T(s) / pdf(s) / n estimates ∫ g T over the square, which a
    /// midpoint grid computes independently.
    #[test]
    fn samples_follow_their_density_and_cover_the_opening() {
        let g = |p: DVec2| 1.0 + p.x + 2.0 * p.y * p.y;
        for (shape, _) in shapes() {
            let a = Aperture::new(&shape).unwrap();
            let mut rng = Rng::new(11);
            let n = 200_000;
            let mut estimate = 0.0;
            for _ in 0..n {
                let (p, pdf) = a.sample(Vec2::new(rng.uniform(), rng.uniform()));
                assert!(
                    pdf > 0.0 && (pdf - a.pdf(p)).abs() < 1e-9 * pdf,
                    "{shape:?}: {pdf} vs {}",
                    a.pdf(p)
                );
                estimate += g(p) * a.transmission(p) / pdf;
            }
            estimate /= f64::from(n);
            let exact = square_integral(1000, |p| g(p) * a.transmission(p));
            assert!(
                (estimate - exact).abs() < 0.01 * exact,
                "{shape:?}: {estimate} vs {exact}"
            );
        }
    }

    /// The transmission is the shape: its integral is the open area, and
    /// the cameras' aperture weight T / (π pdf) averages the open fraction,
    /// also where the circle cuts a mask's pixels (an all-open mask must
    /// pass as much light as the circle).
    #[test]
    fn transmission_integrates_to_the_open_area() {
        for (shape, expected) in shapes() {
            let a = Aperture::new(&shape).unwrap();
            let area = square_integral(1200, |p| a.transmission(p));
            assert!(
                (area / PI - expected).abs() < 0.01 * expected,
                "{shape:?}: {}",
                area / PI
            );
            let mut rng = Rng::new(5);
            let n = 400_000;
            let weight: f64 = (0..n)
                .map(|_| {
                    let (p, pdf) = a.sample(Vec2::new(rng.uniform(), rng.uniform()));
                    a.transmission(p) / (PI * pdf)
                })
                .sum::<f64>()
                / f64::from(n);
            assert!(
                (weight - expected).abs() < 0.01 * expected,
                "{shape:?}: mean weight {weight}"
            );
        }
    }

    /// A corner of the blades points up, and rotation turns them counter-clockwise.
    #[test]
    fn shapes_are_placed_as_documented() {
        let up = DVec2::new(0.0, 0.95);
        let triangle = Aperture::new(&ApertureShape::parse("blades:3").unwrap()).unwrap();
        assert_eq!(triangle.transmission(up), 1.0);
        assert_eq!(triangle.transmission(-up), 0.0);
        let turned = Aperture::new(&ApertureShape::parse("blades:3:90").unwrap()).unwrap();
        assert_eq!(turned.transmission(DVec2::new(-0.95, 0.0)), 1.0);
        assert_eq!(turned.transmission(DVec2::new(0.95, 0.0)), 0.0);
        // A mask's top row is +y.
        let top_open: Vec<f32> = (0..16).map(|k| if k < 8 { 1.0 } else { 0.0 }).collect();
        let mask = Aperture::new(&ApertureShape::Mask(Arc::new(
            ApertureMask::new(4, 4, top_open).unwrap(),
        )))
        .unwrap();
        assert_eq!((mask.transmission(up * 0.5), mask.transmission(-up * 0.5)), (1.0, 0.0));
    }

    #[test]
    fn bad_shapes_are_clear_errors() {
        for (text, message) in [
            ("blades:2", "from 3 to 64"),
            ("blades:6.5", "whole number"),
            ("blades:6:0:2", "curvature must be in [0, 1]"),
            ("star:5:0", "inner ratio must be in (0, 1]"),
            ("star", "missing the count"),
            ("hexagon", "unknown shape"),
            ("blades:six", "'six' is not a number"),
        ] {
            let e = ApertureShape::parse(text).unwrap_err().to_string();
            assert!(e.contains(message), "{text}: {e}");
        }
        assert!(ApertureMask::new(2, 2, vec![0.0; 4])
            .unwrap_err()
            .to_string()
            .contains("closed"));
        assert!(ApertureMask::new(2, 2, vec![0.5; 3]).is_err());
    }

    /// Found by fuzzing: a rotation so large that adding the corners' angles
    /// to it did nothing, leaving a star of no area and an infinite density.
    /// Rotations are now taken modulo 360°.
    #[test]
    fn huge_rotations_keep_the_shape() {
        let text = format!("star:7:.04:10777{}", "7".repeat(24));
        let star = Aperture::new(&ApertureShape::parse(&text).unwrap()).unwrap();
        let (_, pdf) = star.sample(Vec2::new(0.3, 0.6));
        assert!(pdf.is_finite() && pdf > 0.0, "{pdf}");
    }
}
