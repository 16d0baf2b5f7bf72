//! A node's primitive range split in place at its SAH plane (Hoare's
//! scheme), with the binning's own arithmetic so each primitive goes to the
//! side its bin is on.

use glam::Vec3A;

use crate::math::Bounds3;

/// Splits a primitive range at a bin plane with the binning's own arithmetic
/// (the same IEEE operations per lane), so each primitive goes where its bin is.
pub(super) struct Partition {
    pub(super) axis_min: f32,
    pub(super) axis_scale: f32,
    pub(super) plane: f32,
}

impl Partition {
    /// [`Partition::run`] along `axis`.
    #[inline(always)]
    pub(super) fn run_along<const BOXES: bool>(&self, axis: usize, bounds: &mut [Bounds3], order: &mut [u32]) -> Sides {
        match axis {
            0 => self.run::<0, BOXES>(bounds, order),
            1 => self.run::<1, BOXES>(bounds, order),
            _ => self.run::<2, BOXES>(bounds, order),
        }
    }

    /// Partitions `bounds` (and `order` alike) in place; returns the split
    /// index, the centroid bounds of both sides and, with `BOXES`, their
    /// bounds.
    fn run<const A: usize, const BOXES: bool>(&self, bounds: &mut [Bounds3], order: &mut [u32]) -> Sides {
        // Hoare's scheme: scan in from both ends and swap only pairs that are
        // both on the wrong side (a quarter of a random range, where moving
        // every right-side primitive to the end would swap half of it).
        let (mut i, mut j) = (0, bounds.len());
        let (mut lcb, mut rcb) = (Bounds3::EMPTY, Bounds3::EMPTY);
        let (mut lb, mut rb) = (Bounds3::EMPTY, Bounds3::EMPTY);
        // The binning puts x in bin trunc(min(x, last)); for x ≥ 0 and an
        // integer plane ≤ last that bin is left of the plane iff x < plane.
        let left = |c: Vec3A| (c[A] - self.axis_min) * self.axis_scale < self.plane;
        'scan: loop {
            // The first primitive from the left that belongs right...
            let right_centroid = loop {
                if i == j {
                    break 'scan;
                }
                let c = bounds[i].centroid();
                if !left(c) {
                    break c;
                }
                lcb = lcb.grow(c);
                if BOXES {
                    lb = lb.union(bounds[i]);
                }
                i += 1;
            };
            // ...and the first from the right that belongs left.
            let left_centroid = loop {
                j -= 1;
                if j == i {
                    rcb = rcb.grow(right_centroid);
                    if BOXES {
                        rb = rb.union(bounds[i]);
                    }
                    break 'scan;
                }
                let c = bounds[j].centroid();
                if left(c) {
                    break c;
                }
                rcb = rcb.grow(c);
                if BOXES {
                    rb = rb.union(bounds[j]);
                }
            };
            bounds.swap(i, j);
            order.swap(i, j);
            lcb = lcb.grow(left_centroid);
            rcb = rcb.grow(right_centroid);
            if BOXES {
                lb = lb.union(bounds[i]);
                rb = rb.union(bounds[j]);
            }
            i += 1;
        }
        Sides {
            mid: i,
            centroid_bounds: [lcb, rcb],
            bounds: [lb, rb],
        }
    }
}

/// A partition's result: where the right side starts, and both sides'
/// centroid bounds and (if asked for) bounds.
pub(super) struct Sides {
    pub(super) mid: usize,
    pub(super) centroid_bounds: [Bounds3; 2],
    pub(super) bounds: [Bounds3; 2],
}
