//! Integer keys of voxels and blocks.
//!
//! A [`VoxelKey`] names the half-open cube
//! `[k·v, (k+1)·v)` on each axis of a lattice of voxel size `v` anchored at the
//! world origin: `key = ⌊p / v⌋` component-wise. Keys are global (not relative
//! to a grid corner), so the occupancy grid, the TSDF and later per-voxel
//! layers agree on a voxel's name whenever they share a voxel size. A
//! [`BlockKey`] names a cube of `b × b × b` voxels (`b` = block size):
//! `block = ⌊key / b⌋`. The two are distinct types and never bare integer
//! triples (STYLE §6).

use geom::{Point3, Real};
use serde::{Deserialize, Serialize};
use std::fmt;

/// The integer coordinates of one voxel: the voxel `⌊p / v⌋` holding point `p`
/// at voxel size `v`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct VoxelKey([i32; 3]);

impl VoxelKey {
    /// The key with these integer coordinates.
    #[inline]
    pub const fn new(x: i32, y: i32, z: i32) -> Self {
        Self([x, y, z])
    }

    /// The integer coordinates `[x, y, z]`.
    #[inline]
    pub const fn coords(self) -> [i32; 3] {
        self.0
    }

    /// The voxel holding `p` at voxel size `voxel_m`: `⌊p / v⌋` (a point on a
    /// voxel face belongs to the voxel above it). `None` when a coordinate is
    /// not finite or the key would not fit an `i32`.
    pub fn of_point(p: &Point3, voxel_m: Real) -> Option<Self> {
        let mut k = [0i32; 3];
        for (ax, slot) in k.iter_mut().enumerate() {
            let u = (p[ax] / voxel_m).floor();
            if !(u.is_finite() && u >= Real::from(i32::MIN) && u <= Real::from(i32::MAX)) {
                return None;
            }
            *slot = u as i32;
        }
        Some(Self(k))
    }

    /// The voxel's centre at voxel size `voxel_m`.
    #[inline]
    pub fn center(self, voxel_m: Real) -> Point3 {
        Point3::new(
            (Real::from(self.0[0]) + 0.5) * voxel_m,
            (Real::from(self.0[1]) + 0.5) * voxel_m,
            (Real::from(self.0[2]) + 0.5) * voxel_m,
        )
    }

    /// The key `d` voxels away.
    #[inline]
    pub const fn offset(self, dx: i32, dy: i32, dz: i32) -> Self {
        Self([self.0[0] + dx, self.0[1] + dy, self.0[2] + dz])
    }

    /// The block holding this voxel for blocks of `2^shift` voxels a side
    /// (an arithmetic shift: floor division, also for negative keys).
    #[inline]
    pub const fn block_of_pow2(self, shift: u32) -> BlockKey {
        BlockKey([self.0[0] >> shift, self.0[1] >> shift, self.0[2] >> shift])
    }

    /// The block holding this voxel for blocks of `block_size` voxels a side.
    #[inline]
    pub fn block(self, block_size: i32) -> BlockKey {
        BlockKey([
            self.0[0].div_euclid(block_size),
            self.0[1].div_euclid(block_size),
            self.0[2].div_euclid(block_size),
        ])
    }

    /// `true` when the two voxels share a face.
    pub fn is_face_neighbour(self, other: Self) -> bool {
        let d: i64 = (0..3)
            .map(|ax| (i64::from(self.0[ax]) - i64::from(other.0[ax])).abs())
            .sum();
        d == 1
    }
}

impl fmt::Display for VoxelKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}, {}, {})", self.0[0], self.0[1], self.0[2])
    }
}

/// The integer coordinates of one block of `b × b × b` voxels (TSDF blocks,
/// per-block storage of the occupancy grid's sparse layers).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct BlockKey([i32; 3]);

impl BlockKey {
    /// The key with these integer coordinates.
    #[inline]
    pub const fn new(x: i32, y: i32, z: i32) -> Self {
        Self([x, y, z])
    }

    /// The integer coordinates `[x, y, z]`.
    #[inline]
    pub const fn coords(self) -> [i32; 3] {
        self.0
    }

    /// The key `d` blocks away.
    #[inline]
    pub const fn offset(self, dx: i32, dy: i32, dz: i32) -> Self {
        Self([self.0[0] + dx, self.0[1] + dy, self.0[2] + dz])
    }

    /// The block's lowest voxel for blocks of `block_size` voxels a side.
    #[inline]
    pub const fn first_voxel(self, block_size: i32) -> VoxelKey {
        VoxelKey([
            self.0[0] * block_size,
            self.0[1] * block_size,
            self.0[2] * block_size,
        ])
    }
}

impl fmt::Display for BlockKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "block ({}, {}, {})", self.0[0], self.0[1], self.0[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_floor_and_blocks_round_down() {
        let k = VoxelKey::of_point(&Point3::new(0.13, -0.025, 0.0), 0.01).unwrap();
        assert_eq!(k.coords(), [13, -3, 0]);
        assert_eq!(k.block(8).coords(), [1, -1, 0]);
        assert_eq!(VoxelKey::new(-8, -9, 7).block(8).coords(), [-1, -2, 0]);
        for k in [
            VoxelKey::new(-8, -9, 7),
            VoxelKey::new(-1, 0, 17),
            VoxelKey::new(63, -64, -65),
        ] {
            assert_eq!(k.block_of_pow2(3), k.block(8));
        }
        assert_eq!(BlockKey::new(-1, 2, 0).first_voxel(8).coords(), [-8, 16, 0]);
        assert!(VoxelKey::of_point(&Point3::new(f64::NAN, 0.0, 0.0), 0.01).is_none());
        assert!(VoxelKey::of_point(&Point3::new(1e300, 0.0, 0.0), 0.01).is_none());
        let c = VoxelKey::new(1, 2, 3).center(0.5);
        assert_eq!(c, Point3::new(0.75, 1.25, 1.75));
        assert!(VoxelKey::new(0, 0, 0).is_face_neighbour(VoxelKey::new(0, -1, 0)));
        assert!(!VoxelKey::new(0, 0, 0).is_face_neighbour(VoxelKey::new(1, 1, 0)));
    }
}
