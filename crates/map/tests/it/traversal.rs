//! Exact voxel traversal: hand-computed sequences for the awkward cases, and
//! properties against a brute-force oracle.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code may panic

use geom::{Point3, Real};
use map::VoxelKey;
use map::traverse::segment_voxels;
use proptest::prelude::*;

fn k(x: i32, y: i32, z: i32) -> VoxelKey {
    VoxelKey::new(x, y, z)
}

fn p(x: Real, y: Real, z: Real) -> Point3 {
    Point3::new(x, y, z)
}

fn walk(a: Point3, b: Point3) -> Vec<VoxelKey> {
    segment_voxels(&a, &b, 1.0)
}

#[test]
fn axis_aligned_rays_both_directions() {
    assert_eq!(
        walk(p(0.5, 0.5, 0.5), p(3.5, 0.5, 0.5)),
        [k(0, 0, 0), k(1, 0, 0), k(2, 0, 0), k(3, 0, 0)]
    );
    assert_eq!(
        walk(p(2.5, 0.5, 0.5), p(-1.5, 0.5, 0.5)),
        [k(2, 0, 0), k(1, 0, 0), k(0, 0, 0), k(-1, 0, 0), k(-2, 0, 0)]
    );
    assert_eq!(
        walk(p(0.5, 0.5, -0.5), p(0.5, 0.5, -2.5)),
        [k(0, 0, -1), k(0, 0, -2), k(0, 0, -3)]
    );
}

#[test]
fn rays_along_grid_planes_take_the_voxels_above_the_plane() {
    // On the plane y = 1: y-index 1 throughout.
    assert_eq!(
        walk(p(0.5, 1.0, 0.5), p(3.5, 1.0, 0.5)),
        [k(0, 1, 0), k(1, 1, 0), k(2, 1, 0), k(3, 1, 0)]
    );
    // On the grid line y = 1, z = 2 (two planes), going down x.
    assert_eq!(
        walk(p(2.5, 1.0, 2.0), p(0.5, 1.0, 2.0)),
        [k(2, 1, 2), k(1, 1, 2), k(0, 1, 2)]
    );
    // In the plane z = 0, diagonal through lattice corners.
    assert_eq!(
        walk(p(0.0, 0.0, 0.0), p(2.0, 2.0, 0.0)),
        [k(0, 0, 0), k(1, 0, 0), k(1, 1, 0), k(2, 1, 0), k(2, 2, 0)]
    );
}

#[test]
fn corners_and_edges_are_crossed_x_then_y_then_z() {
    // Through the edge x = 1, y = 1.
    assert_eq!(
        walk(p(0.5, 0.5, 0.5), p(1.5, 1.5, 0.5)),
        [k(0, 0, 0), k(1, 0, 0), k(1, 1, 0)]
    );
    // Through the corner (1, 1, 1).
    assert_eq!(
        walk(p(0.5, 0.5, 0.5), p(1.5, 1.5, 1.5)),
        [k(0, 0, 0), k(1, 0, 0), k(1, 1, 0), k(1, 1, 1)]
    );
    // The same edge backwards: x is still crossed first.
    assert_eq!(
        walk(p(1.5, 1.5, 0.5), p(0.5, 0.5, 0.5)),
        [k(1, 1, 0), k(0, 1, 0), k(0, 0, 0)]
    );
    // Through the corner (1, 0, 1) with mixed signs: x up, z down... from
    // (0.5, 0.5, 1.5) to (1.5, 0.5, 0.5) crosses x = 1 and z = 1 together.
    assert_eq!(
        walk(p(0.5, 0.5, 1.5), p(1.5, 0.5, 0.5)),
        [k(0, 0, 1), k(1, 0, 1), k(1, 0, 0)]
    );
    // Starting on a corner and moving down both axes: the start voxel, then
    // x, then y at t = 0, and again at the next corner.
    assert_eq!(
        walk(p(2.0, 2.0, 0.5), p(0.0, 0.0, 0.5)),
        [k(2, 2, 0), k(1, 2, 0), k(1, 1, 0), k(0, 1, 0), k(0, 0, 0)]
    );
}

#[test]
fn general_diagonal_by_hand() {
    // x crosses at t = 0.4 and 0.9, y at t = 0.5.
    assert_eq!(
        walk(p(0.2, 0.5, 0.5), p(2.2, 1.5, 0.5)),
        [k(0, 0, 0), k(1, 0, 0), k(1, 1, 0), k(2, 1, 0)]
    );
}

#[test]
fn segments_starting_or_ending_on_a_face() {
    // Start on x = 1 going up: the start belongs to voxel 1.
    assert_eq!(
        walk(p(1.0, 0.5, 0.5), p(2.5, 0.5, 0.5)),
        [k(1, 0, 0), k(2, 0, 0)]
    );
    // Start on x = 1 going down: voxel 1 (holds the start), then 0.
    assert_eq!(
        walk(p(1.0, 0.5, 0.5), p(0.5, 0.5, 0.5)),
        [k(1, 0, 0), k(0, 0, 0)]
    );
    // End on x = 2 going up: the end belongs to voxel 2.
    assert_eq!(
        walk(p(0.5, 0.5, 0.5), p(2.0, 0.5, 0.5)),
        [k(0, 0, 0), k(1, 0, 0), k(2, 0, 0)]
    );
    // End on x = 1 going down: voxel 1 holds the end.
    assert_eq!(
        walk(p(2.5, 0.5, 0.5), p(1.0, 0.5, 0.5)),
        [k(2, 0, 0), k(1, 0, 0)]
    );
}

#[test]
fn zero_length_and_scaled_voxels() {
    assert_eq!(walk(p(0.3, -0.2, 5.0), p(0.3, -0.2, 5.0)), [k(0, -1, 5)]);
    // 0.25 m voxels: u goes 0.4 → 2.4.
    assert_eq!(
        segment_voxels(&p(0.1, 0.1, 0.1), &p(0.6, 0.1, 0.1), 0.25),
        [k(0, 0, 0), k(1, 0, 0), k(2, 0, 0)]
    );
    // Non-finite input visits nothing.
    assert!(segment_voxels(&p(Real::NAN, 0.0, 0.0), &p(1.0, 0.0, 0.0), 1.0).is_empty());
}

/// The voxel (half-open cells) of each point of the segment, in order: the
/// cell of `a`, the cell at the middle of every interval between consecutive
/// face-crossing parameters, the cell of `b`, without consecutive repeats.
fn oracle(a: [Real; 3], b: [Real; 3]) -> Vec<[i64; 3]> {
    let mut ts = vec![0.0, 1.0];
    for ax in 0..3 {
        let (lo, hi) = (a[ax].min(b[ax]), a[ax].max(b[ax]));
        let mut plane = lo.floor() + 1.0;
        while plane <= hi {
            ts.push((plane - a[ax]) / (b[ax] - a[ax]));
            plane += 1.0;
        }
        // A start exactly on a face crossed downward is a crossing at t = 0.
        if a[ax] == a[ax].floor() && b[ax] < a[ax] {
            ts.push(0.0);
        }
    }
    ts.sort_by(Real::total_cmp);
    let cell = |t: Real| [0, 1, 2].map(|ax| (a[ax] + t * (b[ax] - a[ax])).floor() as i64);
    let mut out = vec![a.map(|v| v.floor() as i64)];
    for w in ts.windows(2) {
        if w[1] > w[0] {
            out.push(cell(0.5 * (w[0] + w[1])));
        }
    }
    out.push(b.map(|v| v.floor() as i64));
    out.dedup();
    out
}

fn coords(keys: &[VoxelKey]) -> Vec<[i64; 3]> {
    keys.iter().map(|k| k.coords().map(i64::from)).collect()
}

/// `true` when the closed unit cube of `c` meets the segment (slab test with a
/// tolerance for rounding).
fn touches(c: [i64; 3], a: [Real; 3], b: [Real; 3]) -> bool {
    let (mut t0, mut t1): (Real, Real) = (0.0, 1.0);
    let eps = 1e-9;
    for ax in 0..3 {
        let lo = c[ax] as Real - eps;
        let hi = c[ax] as Real + 1.0 + eps;
        let d = b[ax] - a[ax];
        if d == 0.0 {
            if a[ax] < lo || a[ax] > hi {
                return false;
            }
        } else {
            let (u, v) = ((lo - a[ax]) / d, (hi - a[ax]) / d);
            t0 = t0.max(u.min(v));
            t1 = t1.min(u.max(v));
        }
    }
    t0 <= t1 + eps
}

fn is_subsequence(needle: &[[i64; 3]], hay: &[[i64; 3]]) -> bool {
    let mut it = hay.iter();
    needle.iter().all(|n| it.any(|h| h == n))
}

fn check_laws(a: [Real; 3], b: [Real; 3], keys: &[VoxelKey]) {
    let cs = coords(keys);
    assert_eq!(cs[0], a.map(|v| v.floor() as i64));
    assert_eq!(*cs.last().unwrap(), b.map(|v| v.floor() as i64));
    let expected_len = 1
        + (0..3)
            .map(|ax| (b[ax].floor() - a[ax].floor()).abs() as usize)
            .sum::<usize>();
    assert_eq!(cs.len(), expected_len);
    for w in keys.windows(2) {
        assert!(w[0].is_face_neighbour(w[1]), "{} → {}", w[0], w[1]);
    }
    for c in &cs {
        assert!(touches(*c, a, b), "{c:?} does not touch {a:?} → {b:?}");
    }
    let mut sorted = cs.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert_eq!(sorted.len(), cs.len(), "a voxel is visited twice");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// General segments: the walk is exactly the oracle's sequence.
    #[test]
    fn walk_equals_oracle(
        a in prop::array::uniform3(-6.0f64..6.0),
        b in prop::array::uniform3(-6.0f64..6.0),
    ) {
        let keys = segment_voxels(&Point3::from(a), &Point3::from(b), 1.0);
        check_laws(a, b, &keys);
        prop_assert_eq!(coords(&keys), oracle(a, b));
    }

    /// World coordinates at 10 mm voxels: the same laws in voxel units.
    #[test]
    fn walk_at_10mm_equals_oracle(
        a in prop::array::uniform3(-2.0f64..2.0),
        b in prop::array::uniform3(-2.0f64..2.0),
    ) {
        let v = 0.01;
        let keys = segment_voxels(&Point3::from(a), &Point3::from(b), v);
        let (ua, ub) = (a.map(|c| c / v), b.map(|c| c / v));
        check_laws(ua, ub, &keys);
        prop_assert_eq!(coords(&keys), oracle(ua, ub));
    }

    /// Lattice-aligned segments (quarter-voxel coordinates): rays on grid
    /// planes, through edges and corners, starting and ending on faces. The
    /// walk keeps its laws and contains the oracle's half-open sequence, the
    /// extra voxels being the ones the tie rule steps through.
    #[test]
    fn lattice_segments_keep_the_laws(
        a in prop::array::uniform3(-12i32..12),
        b in prop::array::uniform3(-12i32..12),
    ) {
        let (a, b) = (a.map(|v| Real::from(v) * 0.25), b.map(|v| Real::from(v) * 0.25));
        let keys = segment_voxels(&Point3::from(a), &Point3::from(b), 1.0);
        check_laws(a, b, &keys);
        prop_assert!(is_subsequence(&oracle(a, b), &coords(&keys)));
    }
}
