//! Exact voxel traversal of a segment (Amanatides & Woo 1987), the ray
//! integration of A§4.2 ("if a ray passes through a voxel it is determined to
//! be free", Fig. 4.3).
//!
//! # The rule
//!
//! Voxels are half-open cubes `[k, k+1)` per axis (in voxel units), so every
//! point of space lies in exactly one voxel and a point on a face belongs to
//! the voxel above it. The walk of the segment `a → b` visits:
//!
//! 1. the voxel holding `a`, then every voxel the segment enters, in order,
//!    ending with the voxel holding `b`;
//! 2. when the segment crosses two or three voxel faces at the same parameter
//!    (it passes exactly through a voxel edge or corner), the crossings are
//!    taken one axis at a time in the order **x, then y, then z**. The walk
//!    then also visits the one or two voxels that the segment only touches at
//!    that edge or corner, so consecutive voxels always share a face (a
//!    6-connected walk). Ties are decided on the computed crossing
//!    parameters, which are exact in the cases that arise by construction
//!    (segments on grid planes, through lattice edges or corners with equal
//!    direction components); a near-tie goes to whichever crossing computes
//!    first, and either order is a valid walk through voxels the segment
//!    touches.
//!
//! Consequences: a segment lying exactly on a grid plane `x = k` visits only
//! voxels with x-index `k` (the voxels above the plane); a segment starting on
//! a face and moving down the axis visits the voxel above the face first (it
//! holds the start point), then the voxel below; a zero-length segment visits
//! the voxel holding its point. The number of voxels visited is exactly
//! `1 + Σ_axis |⌊b⌋ − ⌊a⌋|`: the walk counts the face crossings per axis from
//! the end voxels, so it always ends in the voxel holding `b` however the
//! floating-point parameters round.

use crate::key::VoxelKey;
use geom::{Point3, Real};
use std::ops::ControlFlow;

/// The state of a walk in voxel units: the current voxel and the next face
/// crossing on each axis. Plain scalar fields (no arrays indexed by a runtime
/// axis) so that, inlined into a loop, the whole state lives in registers.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Walk {
    cx: i64,
    cy: i64,
    cz: i64,
    sx: i64,
    sy: i64,
    sz: i64,
    /// Segment parameter (0 at `a`, 1 at `b`) of the next face crossing per
    /// axis; ∞ once the axis has no crossing left.
    tx: Real,
    ty: Real,
    tz: Real,
    /// Parameter between consecutive crossings.
    dx: Real,
    dy: Real,
    dz: Real,
    /// Face crossings left per axis.
    rx: u64,
    ry: u64,
    rz: u64,
}

/// `⌊x⌋` for `|x| < 2⁶³` without a libm call (the x86-64 baseline has no
/// rounding instruction).
#[inline]
pub(crate) fn floor(x: Real) -> Real {
    let t = x as i64 as Real;
    if t > x { t - 1.0 } else { t }
}

/// Per axis: start cell, step, first crossing, crossing interval, crossings.
#[inline]
fn axis_walk(a: Real, b: Real) -> (i64, i64, Real, Real, u64) {
    let c0 = floor(a);
    let c1 = floor(b);
    // ⌊b⌋ > ⌊a⌋ implies b > a (and vice versa), so no division by zero.
    if c1 > c0 {
        let inv = 1.0 / (b - a);
        (c0 as i64, 1, (c0 + 1.0 - a) * inv, inv, (c1 - c0) as u64)
    } else if c1 < c0 {
        let inv = 1.0 / (a - b);
        (c0 as i64, -1, (a - c0) * inv, inv, (c0 - c1) as u64)
    } else {
        (c0 as i64, 0, Real::INFINITY, Real::INFINITY, 0)
    }
}

impl Walk {
    /// The walk from `a` to `b`, both in voxel units (voxel size 1). The
    /// coordinates must be finite and small enough for an `i64`.
    #[inline]
    pub fn new(a: [Real; 3], b: [Real; 3]) -> Self {
        let (cx, sx, tx, dx, rx) = axis_walk(a[0], b[0]);
        let (cy, sy, ty, dy, ry) = axis_walk(a[1], b[1]);
        let (cz, sz, tz, dz, rz) = axis_walk(a[2], b[2]);
        Self {
            cx,
            cy,
            cz,
            sx,
            sy,
            sz,
            tx,
            ty,
            tz,
            dx,
            dy,
            dz,
            rx,
            ry,
            rz,
        }
    }

    /// The current voxel.
    #[inline]
    pub fn cell(&self) -> [i64; 3] {
        [self.cx, self.cy, self.cz]
    }

    /// Number of voxels the walk visits, the first included.
    #[inline]
    pub fn len(&self) -> u64 {
        1 + self.rx + self.ry + self.rz
    }

    /// Move to the next voxel; returns `false` at the end. The axis with the
    /// smallest next crossing goes first; ties (edge and corner crossings) go
    /// to the lowest axis. An axis with no crossing left has its next
    /// crossing at ∞, so when every axis is done the x branch sees `rx = 0`.
    #[inline]
    pub fn advance(&mut self) -> bool {
        if self.tx <= self.ty && self.tx <= self.tz {
            if self.rx == 0 {
                return false;
            }
            self.cx += self.sx;
            self.rx -= 1;
            self.tx = if self.rx == 0 {
                Real::INFINITY
            } else {
                self.tx + self.dx
            };
        } else if self.ty <= self.tz {
            if self.ry == 0 {
                return false;
            }
            self.cy += self.sy;
            self.ry -= 1;
            self.ty = if self.ry == 0 {
                Real::INFINITY
            } else {
                self.ty + self.dy
            };
        } else {
            if self.rz == 0 {
                return false;
            }
            self.cz += self.sz;
            self.rz -= 1;
            self.tz = if self.rz == 0 {
                Real::INFINITY
            } else {
                self.tz + self.dz
            };
        }
        true
    }
}

/// Largest coordinate, in voxels, that a walk accepts: far beyond any map, far
/// inside `i32`.
pub(crate) const MAX_VOXEL_COORD: Real = 1.0e9;

/// `p / voxel_m` when it is finite and within [`MAX_VOXEL_COORD`].
#[inline]
pub(crate) fn to_voxel_units(p: &Point3, voxel_m: Real) -> Option<[Real; 3]> {
    let u = [p.x / voxel_m, p.y / voxel_m, p.z / voxel_m];
    u.iter()
        .all(|c| c.is_finite() && c.abs() <= MAX_VOXEL_COORD)
        .then_some(u)
}

/// Visit the voxels (of size `voxel_m`, global keys) that the segment `a → b`
/// passes through, in order, following the rule of the [module docs](self).
/// `visit` may stop the walk early with [`ControlFlow::Break`], whose value is
/// returned. Nothing is visited when a coordinate is not finite or lies
/// beyond a billion voxels from the origin.
pub fn walk_segment<B>(
    a: &Point3,
    b: &Point3,
    voxel_m: Real,
    mut visit: impl FnMut(VoxelKey) -> ControlFlow<B>,
) -> Option<B> {
    let (Some(ua), Some(ub)) = (to_voxel_units(a, voxel_m), to_voxel_units(b, voxel_m)) else {
        return None;
    };
    let mut w = Walk::new(ua, ub);
    loop {
        let c = w.cell();
        if let ControlFlow::Break(v) = visit(VoxelKey::new(c[0] as i32, c[1] as i32, c[2] as i32)) {
            return Some(v);
        }
        if !w.advance() {
            return None;
        }
    }
}

/// The voxels of [`walk_segment`] as a list.
///
/// ```
/// use geom::Point3;
/// use map::traverse::segment_voxels;
/// use map::VoxelKey;
/// // Through the corner (1, 1, 0): x is crossed first, so (1, 0, 0) comes between.
/// let keys = segment_voxels(&Point3::new(0.5, 0.5, 0.5), &Point3::new(1.5, 1.5, 0.5), 1.0);
/// assert_eq!(keys, [VoxelKey::new(0, 0, 0), VoxelKey::new(1, 0, 0), VoxelKey::new(1, 1, 0)]);
/// ```
pub fn segment_voxels(a: &Point3, b: &Point3, voxel_m: Real) -> Vec<VoxelKey> {
    let mut out = Vec::new();
    let _: Option<()> = walk_segment(a, b, voxel_m, |k| {
        out.push(k);
        ControlFlow::Continue(())
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn walk_length_counts_crossings() {
        let w = Walk::new([0.5, 0.5, 0.5], [3.5, -1.5, 0.5]);
        assert_eq!(w.len(), 1 + 3 + 2);
        let w = Walk::new([0.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
        assert_eq!(w.len(), 1);
    }
}
