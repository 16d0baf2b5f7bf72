//! The exit pupil as the camera samples it: per patch of the sensor (a
//! radial band for a rotationally symmetric lens, a tile of one quadrant for
//! an anamorphic one), a grid of the rear-plane cells that rays get through
//! (found by tracing), and the fitted rear-plane → stop map that shaped
//! apertures are sampled through.

use glam::{DMat2, DMat3, DVec2, DVec3, Vec2};

use crate::lens::{Direction, LensRay, LensSystem};
use crate::spectrum::{D_LINE_NM, LAMBDA_MAX_NM, LAMBDA_MIN_NM};

/// Radial bands of the sensor, each with its own pupil grid.
pub(super) const PUPIL_BANDS: usize = 16;

/// Cells per side of a band's pupil grid.
pub(super) const PUPIL_GRID: usize = 48;

/// Tiles per side of the sensor quadrant an anamorphic lens's pupils are
/// kept for (each traced at its corners and centre).
pub(super) const PUPIL_TILES_PER_SIDE: usize = 8;

/// How a patch's pupil grid is turned onto a film point in it: the grid
/// holds the pupil of points in its own frame (on +x for a band, in the
/// first quadrant for a tile), which the lens's symmetry carries to the
/// rest. An orthogonal map, so its inverse is its transpose.
#[derive(Clone, Copy, Debug)]
pub(super) struct FilmFrame(DMat2);

impl FilmFrame {
    /// Rotated by the film point's azimuth (a unit vector): a rotationally symmetric lens.
    #[inline(always)]
    pub(super) fn rotated(azimuth: DVec2) -> FilmFrame {
        FilmFrame(DMat2::from_cols(azimuth, azimuth.perp()))
    }

    /// Mirrored by the signs (±1) of the film point's x and y: a lens
    /// symmetric about the x–z and y–z planes (an anamorphic one's cylinders are).
    #[inline(always)]
    pub(super) fn mirrored(signs: DVec2) -> FilmFrame {
        FilmFrame(DMat2::from_diagonal(signs))
    }

    /// A rear-plane point in the grid's frame, in lens coordinates.
    #[inline(always)]
    pub(super) fn film_from_grid(self, q: DVec2) -> DVec2 {
        self.0 * q
    }

    /// A rear-plane point in lens coordinates, in the grid's frame.
    #[inline(always)]
    pub(super) fn grid_from_film(self, q: DVec2) -> DVec2 {
        self.0.transpose() * q
    }
}

/// The part of the sensor one pupil grid serves, in the grid's frame (mm).
#[derive(Clone, Copy, Debug)]
pub(super) enum FilmPatch {
    /// Film points at radii `r0 ..= r0 + width` on +x.
    Band { r0: f64, width: f64 },
    /// Film points in the rectangle from `min` to `min + size`.
    Tile { min: DVec2, size: DVec2 },
}

impl FilmPatch {
    /// The film points the pupil's drift is measured between: a band's two
    /// edges, a tile's corners in the order (0, 0), (1, 0), (0, 1), (1, 1).
    fn anchors(&self) -> Vec<DVec2> {
        match *self {
            FilmPatch::Band { r0, width } => vec![DVec2::new(r0, 0.0), DVec2::new(r0 + width, 0.0)],
            FilmPatch::Tile { min, size } => [DVec2::ZERO, DVec2::X, DVec2::Y, DVec2::ONE]
                .map(|t| min + t * size)
                .to_vec(),
        }
    }

    /// Its middle: a band's middle radius, a tile's centre.
    fn middle(&self) -> DVec2 {
        match *self {
            FilmPatch::Band { r0, width } => DVec2::new(r0 + 0.5 * width, 0.0),
            FilmPatch::Tile { min, size } => min + 0.5 * size,
        }
    }

    /// The film points whose pupils are traced: the anchors and the middle.
    fn film_points(&self) -> Vec<DVec2> {
        let mut points = self.anchors();
        points.push(self.middle());
        points
    }
}

/// Points per side when first bounding a band's pupil on the rear plane.
pub(super) const BOUNDING_GRID: usize = 48;

/// Share of a shaped aperture's samples drawn from the pupil grid (defensive
/// sampling: covers whatever the affine stop map misses).
pub(super) const GRID_SHARE: f64 = 0.1;

/// The cells of the rear plane that rays from one sensor patch get through,
/// relative to the pupil's centre, which moves linearly across the patch.
/// Film points are in the grid's frame ([`FilmFrame`]).
#[derive(Clone, Debug)]
pub(super) struct PupilGrid {
    /// The film point the centre is given for, mm.
    pub(super) film0: DVec2,
    /// Pupil centre on the rear plane for a film point at `film0`.
    pub(super) centre: DVec2,
    /// How far the centre moves per mm of film position (d centre / d film).
    pub(super) drift: DMat2,
    /// Lower corner of the grid, relative to the centre.
    pub(super) min: DVec2,
    /// Cell size.
    pub(super) cell: DVec2,
    /// Indices (`row · PUPIL_GRID + column`) of the usable cells.
    pub(super) cells: Vec<u32>,
    /// Whether each cell is usable, by index.
    pub(super) usable: Vec<bool>,
}

impl PupilGrid {
    pub(super) const EMPTY: PupilGrid = PupilGrid {
        film0: DVec2::ZERO,
        centre: DVec2::ZERO,
        drift: DMat2::ZERO,
        min: DVec2::ZERO,
        cell: DVec2::ONE,
        cells: Vec::new(),
        usable: Vec::new(),
    };

    pub(super) fn area(&self) -> f64 {
        self.cells.len() as f64 * self.cell.x * self.cell.y
    }

    /// The pupil's centre for the film point `film` (grid frame).
    #[inline(always)]
    pub(super) fn centre_at(&self, film: DVec2) -> DVec2 {
        self.centre + self.drift * (film - self.film0)
    }

    /// Whether `q` (rear plane) lies in a usable cell for the film point `film` (both in the grid's frame).
    pub(super) fn contains(&self, q: DVec2, film: DVec2) -> bool {
        // Subtracted one by one, as `sample` adds them, so a drawn point tests inside.
        let g = (q - self.centre - self.drift * (film - self.film0) - self.min) / self.cell;
        let n = PUPIL_GRID as f64;
        (0.0..n).contains(&g.x) && (0.0..n).contains(&g.y) && self.usable[g.y as usize * PUPIL_GRID + g.x as usize]
    }

    /// A uniform point in the usable cells from `u` in [0, 1)², for the film point `film` (grid frame).
    pub(super) fn sample(&self, u: Vec2, film: DVec2) -> DVec2 {
        let n = self.cells.len();
        let scaled = f64::from(u.x) * n as f64;
        let pick = (scaled as usize).min(n - 1);
        let cell = self.cells[pick] as usize;
        let (row, column) = (cell / PUPIL_GRID, cell % PUPIL_GRID);
        let offset = DVec2::new(scaled - pick as f64, f64::from(u.y));
        self.centre_at(film) + self.min + (DVec2::new(column as f64, row as f64) + offset) * self.cell
    }
}

/// Wavelengths, nm, at which a dispersive lens's pupil is bounded: the
/// transported range's ends and the d line. A glass's index is monotone in
/// wavelength over the range, so where a ray meets each surface moves
/// monotonically too, and the union of the pupils at the ends and the middle
/// covers the pupil at every wavelength between (the cells are kept when any
/// corner passes, which pads the union by a cell besides).
pub(super) const PUPIL_BOUND_WAVELENGTHS_NM: [f64; 3] = [LAMBDA_MIN_NM as f64, D_LINE_NM as f64, LAMBDA_MAX_NM as f64];

/// The lens at each wavelength its pupil is bounded at: at
/// [`PUPIL_BOUND_WAVELENGTHS_NM`] when it `disperses`, else the lens itself.
pub(super) fn bounding_systems(system: &LensSystem, disperses: bool) -> Vec<LensSystem> {
    if disperses {
        PUPIL_BOUND_WAVELENGTHS_NM
            .iter()
            .map(|&nm| system.at_wavelength(nm))
            .collect()
    } else {
        vec![system.clone()]
    }
}

/// The pupil grid for the film points of `patch`: the cells a ray gets
/// through at any of `systems` (one lens at several wavelengths,
/// [`bounding_systems`]).
pub(super) fn bound_pupil(systems: &[LensSystem], sensor_depth_mm: f64, patch: FilmPatch) -> PupilGrid {
    let films = patch.film_points();
    let system = &systems[0];
    let rear_z_mm = system.rear_z_mm();
    let passes_from = |film: DVec2, q: DVec2| {
        let ray = LensRay::between(
            DVec3::new(film.x, film.y, sensor_depth_mm),
            DVec3::new(q.x, q.y, rear_z_mm),
        );
        systems.iter().any(|s| s.trace(&ray, Direction::ToScene).is_some())
    };
    // 1. Where each film position's pupil lies, on a coarse grid over 1.5×
    // the rear aperture (pbrt's margin): the centroids of passing points.
    let reach = 1.5 * system.rear_aperture_radius_mm();
    let coarse = 2.0 * reach / (BOUNDING_GRID - 1) as f64;
    let scan = |film: DVec2, lo: DVec2, step: DVec2| {
        let mut points = Vec::new();
        for i in 0..BOUNDING_GRID {
            for j in 0..BOUNDING_GRID {
                let q = lo + DVec2::new(j as f64, i as f64) * step;
                if passes_from(film, q) {
                    points.push(q);
                }
            }
        }
        points
    };
    // The pupil of one film position: found on the coarse grid, then its
    // centroid and extent measured on a grid over just the pupil.
    let passing_at = |film: DVec2| {
        let coarse_points = scan(film, DVec2::splat(-reach), DVec2::splat(coarse));
        let (lo, hi) = coarse_points.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(a, b), &q| (a.min(q), b.max(q)),
        );
        if coarse_points.is_empty() {
            return None;
        }
        let (lo, hi) = (lo - coarse, hi + coarse);
        let step = (hi - lo) / (BOUNDING_GRID - 1) as f64;
        let fine = scan(film, lo, step);
        let (points, step) = if fine.is_empty() {
            (coarse_points, DVec2::splat(coarse))
        } else {
            (fine, step)
        };
        let centroid = points.iter().sum::<DVec2>() / points.len() as f64;
        Some((centroid, points, step))
    };
    // The pupils at the anchors: a band's edges, a tile's corners.
    let film0 = films[0];
    let anchors: Vec<_> = patch.anchors().into_iter().map(passing_at).collect();
    let (centre, drift) = match (patch, anchors.as_slice()) {
        (FilmPatch::Band { width, .. }, [Some(a), Some(b)]) => {
            (a.0, DMat2::from_cols((b.0 - a.0) / width, DVec2::ZERO))
        }
        (FilmPatch::Tile { size, .. }, [Some(c00), Some(c10), Some(c01), Some(c11)]) => (
            c00.0,
            DMat2::from_cols(
                ((c10.0 - c00.0) + (c11.0 - c01.0)) / (2.0 * size.x),
                ((c01.0 - c00.0) + (c11.0 - c10.0)) / (2.0 * size.y),
            ),
        ),
        // Some anchors see no pupil: hold the centre of those that do.
        _ => {
            let seen: Vec<DVec2> = anchors.iter().flatten().map(|a| a.0).collect();
            if seen.is_empty() {
                return PupilGrid::EMPTY;
            }
            (seen.iter().sum::<DVec2>() / seen.len() as f64, DMat2::ZERO)
        }
    };
    // 2. The pupil moves across the patch; follow it, so the grid only holds its shape.
    let passes = |q: DVec2| {
        films
            .iter()
            .any(|&film| passes_from(film, centre + drift * (film - film0) + q))
    };
    // 3. Bound it: the anchors' pupils about their centroids, widened by two
    // of their scan steps (the other positions' pupils lie between them).
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for (c, points, step) in anchors.iter().flatten() {
        for &q in points {
            lo = lo.min(q - *c - 2.0 * *step);
            hi = hi.max(q - *c + 2.0 * *step);
        }
    }
    // 4. Keep the cells any of whose corners or centre passes.
    let cell = (hi - lo) / PUPIL_GRID as f64;
    let corner_passes: Vec<bool> = (0..=PUPIL_GRID)
        .flat_map(|i| (0..=PUPIL_GRID).map(move |j| (i, j)))
        .map(|(i, j)| passes(lo + DVec2::new(j as f64, i as f64) * cell))
        .collect();
    let corner = |i: usize, j: usize| corner_passes[i * (PUPIL_GRID + 1) + j];
    let cells: Vec<u32> = (0..PUPIL_GRID * PUPIL_GRID)
        .filter(|&k| {
            let (i, j) = (k / PUPIL_GRID, k % PUPIL_GRID);
            corner(i, j)
                || corner(i + 1, j)
                || corner(i, j + 1)
                || corner(i + 1, j + 1)
                || passes(lo + DVec2::new(j as f64 + 0.5, i as f64 + 0.5) * cell)
        })
        .map(|k| k as u32)
        .collect();
    PupilGrid {
        film0,
        centre,
        drift,
        min: lo,
        cell,
        usable: (0..PUPIL_GRID * PUPIL_GRID)
            .map(|k| cells.binary_search(&(k as u32)).is_ok())
            .collect(),
        cells,
    }
}

/// The affine map s = A q + b from rear-plane points q to the points s where
/// rays from a film point cross the stop (both in the patch's frame),
/// least-squares fitted at the two ends of a sensor band (interpolated
/// between them by the film point's x) or at the centre of a tile.
#[derive(Clone, Copy, Debug)]
pub(super) struct StopMap {
    pub(super) r0: f64,
    pub(super) width: f64,
    pub(super) ends: [(DMat2, DVec2); 2],
}

impl StopMap {
    /// A and b for the film point `film` (the patch's frame).
    pub(super) fn at(&self, film: DVec2) -> (DMat2, DVec2) {
        let t = ((film.x - self.r0) / self.width).clamp(0.0, 1.0);
        let ([a0, a1], [b0, b1]) = ([self.ends[0].0, self.ends[1].0], [self.ends[0].1, self.ends[1].1]);
        (a0 * (1.0 - t) + a1 * t, b0.lerp(b1, t))
    }
}

/// Fits the [`StopMap`] of a patch from rays through its grid's usable cells.
pub(super) fn fit_stop_map(
    system: &LensSystem,
    sensor_depth_mm: f64,
    grid: &PupilGrid,
    patch: FilmPatch,
) -> Option<StopMap> {
    let fit_at = |film: DVec2| {
        // Normal equations of the two least-squares problems s.x, s.y ~ (q.x, q.y, 1).
        let (mut m, mut rhs_x, mut rhs_y, mut n) = (DMat3::ZERO, DVec3::ZERO, DVec3::ZERO, 0);
        for &k in &grid.cells {
            let (row, column) = ((k as usize / PUPIL_GRID) as f64, (k as usize % PUPIL_GRID) as f64);
            let q = grid.centre_at(film) + grid.min + (DVec2::new(column, row) + 0.5) * grid.cell;
            let ray = LensRay::between(
                DVec3::new(film.x, film.y, sensor_depth_mm),
                DVec3::new(q.x, q.y, system.rear_z_mm()),
            );
            if let Some((_, s)) = system.trace_via_stop(&ray, Direction::ToScene) {
                let v = DVec3::new(q.x, q.y, 1.0);
                m += DMat3::from_cols(v * v.x, v * v.y, v);
                rhs_x += v * s.x;
                rhs_y += v * s.y;
                n += 1;
            }
        }
        if n < 3 || m.determinant().abs() < 1e-300 {
            return None;
        }
        let inverse = m.inverse();
        let (cx, cy) = (inverse * rhs_x, inverse * rhs_y);
        let a = DMat2::from_cols(DVec2::new(cx.x, cy.x), DVec2::new(cx.y, cy.y));
        (a.determinant().abs() > 1e-12).then_some((a, DVec2::new(cx.z, cy.z)))
    };
    let (r0, width, start, end) = match patch {
        FilmPatch::Band { r0, width } => (
            r0,
            width,
            fit_at(DVec2::new(r0, 0.0)),
            fit_at(DVec2::new(r0 + width, 0.0)),
        ),
        // One fit at the middle, which any width interpolates with itself.
        FilmPatch::Tile { .. } => {
            let fit = fit_at(patch.middle());
            (patch.middle().x, 1.0, fit, fit)
        }
    };
    let ends = match (start, end) {
        (Some(a), Some(b)) => [a, b],
        (Some(a), None) | (None, Some(a)) => [a, a],
        (None, None) => return None,
    };
    Some(StopMap { r0, width, ends })
}
