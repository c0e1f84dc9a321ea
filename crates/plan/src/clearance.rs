//! Clearance from measured points: the robot's collision capsules kept a
//! distance from every point the scanner has measured, on top of `dist(Q)`
//! (eq. 3.5). `dist(Q) > 1` is measured to the centres of the planning grid's
//! voxels, so on its own it lets a link pass within millimetres of a surface
//! the scanner has seen (a surface may lie anywhere in its voxel); the
//! measured points say where the surface is.

use crate::roadmap::MotionChecker;
use crate::safety::Safety;
use geom::{Isometry3, Point3, Real};
use robot::{PosedShape, Robot};
use rustc_hash::FxHashMap;

/// Measured points are kept one per cube of this side, metres: a point
/// stands for the others within `√3 · 0.01 / 2 ≈ 9 mm` of it (the range
/// noise of the bridge scenes' scanner is 10 mm).
pub const POINT_DEDUP_M: Real = 0.01;

/// Side of the cells the kept points are looked up by, metres.
const CELL_M: Real = 0.05;

/// Half a cell's diagonal, metres (with a margin for rounding).
const CELL_HALF_DIAGONAL_M: Real = 0.5 * 1.732_050_808 * CELL_M + 1e-9;

fn key(p: &Point3, side: Real) -> [i32; 3] {
    [p.x, p.y, p.z].map(|v| (v / side).floor() as i32)
}

/// Dedup cubes per cell side.
const PER_CELL: i64 = 5;
const _: () = assert!(
    (CELL_M / POINT_DEDUP_M - PER_CELL as Real).abs() < 1e-9
        && PER_CELL * PER_CELL * PER_CELL <= 128
);

/// The cell (of [`CELL_M`]) that records whether the dedup cube (of
/// [`POINT_DEDUP_M`]) with key `k` is taken, and its bit there: the cell
/// that contains the cube on the integer lattice (`k` divided by
/// [`PER_CELL`], rounded down), so each cube has one bit wherever its
/// points fall by their own cell key.
fn dedup_slot(k: [i32; 3]) -> ([i32; 3], u32) {
    let mut home = [0i32; 3];
    let mut bit = 0;
    for (axis, scale) in [(2, PER_CELL * PER_CELL), (1, PER_CELL), (0, 1)] {
        let v = i64::from(k[axis]);
        let c = v.div_euclid(PER_CELL);
        // |c| ≤ |v| / 5 + 1 fits an i32; the remainder is in 0..PER_CELL.
        home[axis] = c as i32;
        bit += ((v - c * PER_CELL) * scale) as u32;
    }
    (home, bit)
}

/// Cells per brick side (a brick's cells are one `u64`'s bits).
const PER_BRICK: i32 = 4;

/// The brick holding the cell with key `c`, and the cell's bit in it.
fn brick_of(c: [i32; 3]) -> ([i32; 3], u32) {
    let mut brick = [0i32; 3];
    let mut bit = 0;
    for (axis, scale) in [(2, PER_BRICK * PER_BRICK), (1, PER_BRICK), (0, 1)] {
        brick[axis] = c[axis].div_euclid(PER_BRICK);
        bit += c[axis].rem_euclid(PER_BRICK) * scale;
    }
    (brick, bit as u32)
}

/// The kept points of one cell, and the dedup cubes it records as taken.
#[derive(Clone, Debug, Default)]
struct Cell {
    taken: u128,
    points: Vec<Point3>,
}

/// The measured points, indexed for clearance queries.
#[derive(Clone, Debug, Default)]
pub struct PointClearance {
    /// By cell key ([`CELL_M`]): the points kept there, and which dedup
    /// cubes the cell records as taken ([`dedup_slot`]; one hash lookup
    /// for most points, where a set of cubes beside the cells took two).
    cells: FxHashMap<[i32; 3], Cell>,
    /// By brick key ([`brick_of`]): which of its cells hold points, so a
    /// query looks up only those (most cells around the arm are empty).
    bricks: FxHashMap<[i32; 3], u64>,
    kept: usize,
}

impl PointClearance {
    /// No points.
    pub fn new() -> Self {
        Self::default()
    }

    /// Add measured points (world frame); non-finite ones are ignored.
    pub fn insert<'a>(&mut self, points: impl IntoIterator<Item = &'a Point3>) {
        self.insert_noting(points, None);
    }

    /// [`PointClearance::insert`], and the points it keeps also into
    /// `added`: a clearance from this index after the call is then the
    /// smaller of the one before it and the one from `added` (when `added`
    /// was empty before; the distances of a point do not depend on what
    /// else is kept).
    pub fn insert_noting<'a>(
        &mut self,
        points: impl IntoIterator<Item = &'a Point3>,
        mut added: Option<&mut PointClearance>,
    ) {
        for p in points {
            if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
                continue;
            }
            // The first point of each dedup cube is kept.
            let (home, bit) = dedup_slot(key(p, POINT_DEDUP_M));
            let cell = self.cells.entry(home).or_default();
            if cell.taken & (1u128 << bit) != 0 {
                continue;
            }
            cell.taken |= 1u128 << bit;
            self.kept += 1;
            let own = key(p, CELL_M);
            if own == home {
                cell.points.push(*p);
            } else {
                // Rounding put it in a cell beside its cube's.
                self.cells.entry(own).or_default().points.push(*p);
            }
            let (brick, bit) = brick_of(own);
            *self.bricks.entry(brick).or_default() |= 1u64 << bit;
            if let Some(a) = added.as_deref_mut() {
                a.insert(std::iter::once(p));
            }
        }
    }

    /// Forget every point (the allocations are kept).
    pub fn clear(&mut self) {
        self.cells.clear();
        self.bricks.clear();
        self.kept = 0;
    }

    /// Points kept.
    pub fn len(&self) -> usize {
        self.kept
    }

    /// No point kept.
    pub fn is_empty(&self) -> bool {
        self.kept == 0
    }

    /// [`PointClearance::robot_clearance`] of `safety`'s robot at the
    /// configuration `q`, placed as `safety` places it, up to `search_m` (0
    /// when its kinematics fail).
    pub fn configuration_clearance(&self, safety: &Safety, q: &[Real], search_m: Real) -> Real {
        let robot = safety.robot();
        robot.forward_kinematics(q).map_or(0.0, |frames| {
            self.robot_clearance(robot, &frames, safety.world_from_base(), search_m)
        })
    }

    /// The smallest distance from the collision capsules of `robot`'s moving
    /// links (posed by `base_from_link`, placed by `world_from_base`) to the
    /// kept points, or `search_m` when none is closer (0 when a point is
    /// inside a capsule). The links before the first actuated joint stand
    /// on whatever carries the robot and are left out, as
    /// [`crate::contact::min_clearance`] leaves them.
    /// The cells looked in grow as the cube of `search_m` past each
    /// capsule: callers search as far as the clearance they need.
    pub fn robot_clearance(
        &self,
        robot: &Robot,
        base_from_link: &[Isometry3],
        world_from_base: &Isometry3,
        search_m: Real,
    ) -> Real {
        let mounted = robot.mounted_links();
        let mut best = search_m;
        for shape in robot.posed_collision_shapes(base_from_link) {
            let PosedShape::Capsule { link, capsule } = shape else {
                continue;
            };
            if link.index() < mounted {
                continue;
            }
            let c = capsule.transformed(world_from_base);
            let b = c.bounding_box().loosened(best);
            let (lo, hi) = (key(&b.min, CELL_M), key(&b.max, CELL_M));
            // The cells of the box that hold points, brick by brick (the
            // minimum does not depend on the order).
            let (blo, bhi) = (brick_of(lo).0, brick_of(hi).0);
            for bx in blo[0]..=bhi[0] {
                for by in blo[1]..=bhi[1] {
                    for bz in blo[2]..=bhi[2] {
                        let Some(&mask) = self.bricks.get(&[bx, by, bz]) else {
                            continue;
                        };
                        let mut bits = mask;
                        while bits != 0 {
                            let bit = bits.trailing_zeros() as i32;
                            bits &= bits - 1;
                            let cell = [
                                bx * PER_BRICK + bit % PER_BRICK,
                                by * PER_BRICK + (bit / PER_BRICK) % PER_BRICK,
                                bz * PER_BRICK + bit / (PER_BRICK * PER_BRICK),
                            ];
                            if (0..3).any(|k| cell[k] < lo[k] || cell[k] > hi[k]) {
                                continue;
                            }
                            let Some(Cell { points, .. }) = self.cells.get(&cell) else {
                                continue;
                            };
                            // No point of a cell is nearer than its centre
                            // less half its diagonal (the distance is
                            // 1-Lipschitz).
                            let centre = Point3::new(
                                (Real::from(cell[0]) + 0.5) * CELL_M,
                                (Real::from(cell[1]) + 0.5) * CELL_M,
                                (Real::from(cell[2]) + 0.5) * CELL_M,
                            );
                            if c.distance_to_point(&centre) - CELL_HALF_DIAGONAL_M >= best {
                                continue;
                            }
                            for p in points {
                                best = best.min(c.distance_to_point(p).max(0.0));
                            }
                        }
                    }
                }
            }
        }
        best
    }
}

/// A [`MotionChecker`] that also keeps the robot's capsules `clearance_m`
/// from the measured points at every configuration `safety` checks along a
/// motion. The pose the arm stands at may already be closer (the scanner
/// may have measured a surface beside it since it got there): it passes,
/// and a motion from it passes when it never comes closer than the arm
/// stands, so the arm can always back away.
pub struct ClearanceChecker<'a, C> {
    inner: C,
    safety: &'a Safety,
    points: &'a PointClearance,
    clearance_m: Real,
    /// The pose the arm stands at and its clearance (up to `clearance_m`).
    here: (Vec<Real>, Real),
}

impl<'a, C> ClearanceChecker<'a, C> {
    /// `inner`'s checks and `clearance_m` from `points`, the arm standing
    /// at `here`.
    pub fn new(
        inner: C,
        safety: &'a Safety,
        points: &'a PointClearance,
        clearance_m: Real,
        here: &[Real],
    ) -> Self {
        let mut checker = Self {
            inner,
            safety,
            points,
            clearance_m,
            here: (here.to_vec(), clearance_m),
        };
        if clearance_m > 0.0 {
            checker.here.1 = checker.clearance(here).min(clearance_m);
        }
        checker
    }

    /// The clearance of the configuration `q`, up to `clearance_m` (0 when
    /// its kinematics fail).
    pub fn clearance(&self, q: &[Real]) -> Real {
        self.points
            .configuration_clearance(self.safety, q, self.clearance_m)
    }

    /// The clearance a configuration needs: `clearance_m`, or where the arm
    /// stands, no less than it has there.
    fn needed(&self, from_here: bool) -> Real {
        if from_here {
            self.here.1
        } else {
            self.clearance_m
        }
    }

    /// Whether the motion `a` → `b` keeps the clearance it needs at every
    /// configuration `safety` checks along it (the wrapped checker is not
    /// asked).
    pub fn motion_clears(&self, a: &[Real], b: &[Real]) -> bool {
        if self.clearance_m <= 0.0 {
            return true;
        }
        let from_here = a == self.here.0.as_slice() || b == self.here.0.as_slice();
        self.safety
            .interpolate(a, b)
            .iter()
            .all(|c| self.clears(c, from_here))
    }

    /// Whether configuration `c` has the clearance it needs on a motion
    /// that starts or ends where the arm stands (`from_here`) or not.
    pub fn clears(&self, c: &[Real], from_here: bool) -> bool {
        self.clearance_m <= 0.0 || self.clearance(c) >= self.needed(from_here)
    }
}

impl<C: MotionChecker> MotionChecker for ClearanceChecker<'_, C> {
    fn pose_ok(&mut self, q: &[Real]) -> bool {
        if self.clearance_m <= 0.0 {
            return self.inner.pose_ok(q);
        }
        let here = q == self.here.0.as_slice();
        self.inner.pose_ok(q) && (here || self.clearance(q) >= self.clearance_m)
    }

    fn motion_ok(&mut self, a: &[Real], b: &[Real]) -> bool {
        self.inner.motion_ok(a, b) && self.motion_clears(a, b)
    }

    /// The wrapped checker's answer alone: the clearance is left to
    /// `motion_ok` on the path a search finds.
    fn motion_may_be_ok(&mut self, a: &[Real], b: &[Real]) -> bool {
        self.inner.motion_may_be_ok(a, b)
    }

    /// The wrapped checker's answers, then the clearance of the poses they
    /// pass, in parallel.
    fn poses_ok(&mut self, qs: &[&[Real]]) -> Vec<bool> {
        use rayon::prelude::*;
        let inner = self.inner.poses_ok(qs);
        if self.clearance_m <= 0.0 {
            return inner;
        }
        let (points, safety, clearance_m) = (self.points, self.safety, self.clearance_m);
        let here = self.here.0.as_slice();
        qs.par_iter()
            .zip(inner)
            .map(|(q, ok)| {
                ok && (*q == here
                    || points.configuration_clearance(safety, q, clearance_m) >= clearance_m)
            })
            .collect()
    }

    fn motions_may_be_ok(&mut self, motions: &[(&[Real], &[Real])]) -> Vec<bool> {
        self.inner.motions_may_be_ok(motions)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::{PlanConfig, Safety};
    use geom::Vector3;
    use rustc_hash::FxHashSet;

    /// The index keeps the first point of each 1 cm cube and files it by
    /// its 5 cm cell, as a set of cube keys beside a map of cells does
    /// (brute force): random points, and points on and around the cubes'
    /// and cells' faces, where rounding may file a point in a cell beside
    /// its cube's.
    #[test]
    fn the_index_keeps_the_first_point_of_each_cube() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut pts: Vec<Point3> = (0..20_000)
            .map(|_| {
                Point3::new(
                    rng.random_range(-0.3..0.3),
                    rng.random_range(-0.3..0.3),
                    rng.random_range(-0.3..0.3),
                )
            })
            .collect();
        for i in -40..40 {
            for eps in [0.0, 1e-17, -1e-17, 1e-12, -1e-12] {
                let v = Real::from(i) * 0.01 + eps;
                pts.push(Point3::new(v, -v, 0.5 * v));
                pts.push(Point3::new(v, 0.05, -0.05));
            }
        }
        pts.push(Point3::new(Real::NAN, 0.0, 0.0));
        let mut index = PointClearance::new();
        for chunk in pts.chunks(777) {
            index.insert(chunk.iter());
        }
        let mut seen = FxHashSet::default();
        let mut cells: FxHashMap<[i32; 3], Vec<Point3>> = FxHashMap::default();
        for p in pts.iter().filter(|p| p.x.is_finite()) {
            if seen.insert(key(p, POINT_DEDUP_M)) {
                cells.entry(key(p, CELL_M)).or_default().push(*p);
            }
        }
        assert_eq!(index.len(), seen.len());
        let filed: FxHashMap<[i32; 3], Vec<Point3>> = index
            .cells
            .iter()
            .filter(|(_, c)| !c.points.is_empty())
            .map(|(k, c)| (*k, c.points.clone()))
            .collect();
        assert_eq!(filed, cells);
        // The bricks name exactly the cells that hold points.
        let mut named = 0;
        for (brick, mask) in &index.bricks {
            named += mask.count_ones() as usize;
            for bit in 0..64u32 {
                if mask & (1u64 << bit) != 0 {
                    let b = bit as i32;
                    let cell = [
                        brick[0] * PER_BRICK + b % PER_BRICK,
                        brick[1] * PER_BRICK + (b / PER_BRICK) % PER_BRICK,
                        brick[2] * PER_BRICK + b / (PER_BRICK * PER_BRICK),
                    ];
                    assert_eq!(brick_of(cell), (*brick, bit));
                    assert!(cells.contains_key(&cell), "{cell:?}");
                }
            }
        }
        assert_eq!(named, cells.len());
    }

    /// The clearance against the smallest capsule distance over every
    /// point (brute force): the VM-6083 at random poses among points
    /// scattered around it, for several search radii.
    #[test]
    fn robot_clearance_is_the_brute_force_minimum() {
        use rand::{RngExt, SeedableRng};
        let robot = robot::builtin("denso-vm6083").unwrap();
        let world = Isometry3::translation(0.2, -0.1, 0.0);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let pts: Vec<Point3> = (0..30_000)
            .map(|_| {
                Point3::new(
                    rng.random_range(-1.2..1.6),
                    rng.random_range(-1.4..1.2),
                    rng.random_range(-0.2..1.8),
                )
            })
            .collect();
        let mut index = PointClearance::new();
        index.insert(pts.iter());
        let kept: Vec<Point3> = index
            .cells
            .values()
            .flat_map(|c| c.points.iter().copied())
            .collect();
        let mounted = robot.mounted_links();
        let limits = robot.limits();
        for _ in 0..40 {
            let q: Vec<Real> = limits
                .iter()
                .map(|l| {
                    let l = l.unwrap();
                    rng.random_range(l.min..l.max)
                })
                .collect();
            let frames = robot.forward_kinematics(&q).unwrap();
            let capsules: Vec<geom::Capsule> = robot
                .posed_collision_shapes(&frames)
                .into_iter()
                .filter_map(|s| match s {
                    PosedShape::Capsule { link, capsule } if link.index() >= mounted => {
                        Some(capsule.transformed(&world))
                    }
                    _ => None,
                })
                .collect();
            for search in [0.02, 0.05, 0.2] {
                let expected = kept
                    .iter()
                    .flat_map(|p| capsules.iter().map(|c| c.distance_to_point(p).max(0.0)))
                    .fold(search, Real::min);
                let got = index.robot_clearance(&robot, &frames, &world, search);
                assert_eq!(got, expected, "q = {q:?}, search {search}");
            }
        }
    }

    /// The clearance to points against the capsule distance by hand: for
    /// each capsule of the VM-6083 at a pose, points placed at known
    /// distances off the middle of its axis, perpendicular to it.
    #[test]
    fn robot_clearance_is_the_nearest_capsule_surface() {
        let robot = robot::builtin("denso-vm6083").unwrap();
        let q = [0.3, -0.5, 2.0, 0.2, -1.0, 0.4];
        let frames = robot.forward_kinematics(&q).unwrap();
        let world = Isometry3::translation(0.5, -0.2, 0.1);
        let mounted = robot.mounted_links();
        let capsules: Vec<geom::Capsule> = robot
            .posed_collision_shapes(&frames)
            .into_iter()
            .filter_map(|s| match s {
                PosedShape::Capsule { link, capsule } if link.index() >= mounted => {
                    Some(capsule.transformed(&world))
                }
                _ => None,
            })
            .collect();
        assert!(capsules.len() >= 4);
        for (i, c) in capsules.iter().enumerate() {
            let axis = c.segment.b - c.segment.a;
            // A sphere (no axis) gets any direction.
            let axis = if axis.norm() > 1e-9 {
                axis
            } else {
                Vector3::new(1.0, 0.0, 0.0)
            };
            let side = axis.cross(&Vector3::new(0.3, 0.5, 0.8));
            let side = side / side.norm();
            let mid = c.segment.a + 0.5 * (c.segment.b - c.segment.a);
            let p = mid + side * (c.radius + 0.04);
            let mut points = PointClearance::new();
            points.insert([p].iter());
            let expected = capsules
                .iter()
                .map(|o| o.distance_to_point(&p).max(0.0))
                .fold(0.5, Real::min);
            let got = points.robot_clearance(&robot, &frames, &world, 0.5);
            assert!(
                (got - expected).abs() < 1e-12,
                "capsule {i}: {got} vs {expected}"
            );
            assert!(got <= 0.04 + 1e-12);
        }
        // Nothing within the search radius: the radius.
        let far = PointClearance::new();
        assert_eq!(far.robot_clearance(&robot, &frames, &world, 0.3), 0.3);
    }

    /// Points closer than 1 cm to a kept one are not kept again; NaN is
    /// ignored.
    #[test]
    fn points_are_kept_one_per_centimetre() {
        let mut points = PointClearance::new();
        let a = Point3::new(0.001, 0.001, 0.001);
        let b = Point3::new(0.004, 0.002, 0.003);
        let c = Point3::new(0.5, 0.0, 0.0);
        points.insert([a, b, c, Point3::new(Real::NAN, 0.0, 0.0)].iter());
        assert_eq!(points.len(), 2);
    }

    /// The clearance after [`PointClearance::insert_noting`] is the smaller
    /// of the one before and the one from the noted points alone, at many
    /// poses, in batches of random points around the arm; a batch inserted
    /// again keeps and notes nothing.
    #[test]
    fn noted_points_give_the_clearance_of_all() {
        use rand::{RngExt, SeedableRng};
        let robot = robot::builtin("denso-vm6083").unwrap();
        let safety = Safety::new(
            robot,
            Isometry3::identity(),
            &PlanConfig::default(),
            vec![1.0; 6],
        )
        .unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut all = PointClearance::new();
        let mut added = PointClearance::new();
        let poses: Vec<Vec<Real>> = (0..20)
            .map(|_| (0..6).map(|_| rng.random_range(-1.5..1.5)).collect())
            .collect();
        let mut checked = 0;
        for _ in 0..30 {
            let batch: Vec<Point3> = (0..200)
                .map(|_| {
                    Point3::new(
                        rng.random_range(-0.8..0.8),
                        rng.random_range(-0.8..0.8),
                        rng.random_range(-0.2..1.2),
                    )
                })
                .collect();
            let before: Vec<Real> = poses
                .iter()
                .map(|q| all.configuration_clearance(&safety, q, 0.2))
                .collect();
            added.clear();
            all.insert_noting(batch.iter(), Some(&mut added));
            // Again: nothing is kept twice, nothing noted.
            let mut again = PointClearance::new();
            all.insert_noting(batch.iter(), Some(&mut again));
            assert!(again.is_empty());
            for (q, b) in poses.iter().zip(before) {
                let now = all.configuration_clearance(&safety, q, 0.2);
                let new = added.configuration_clearance(&safety, q, 0.2);
                assert_eq!(now, b.min(new));
                checked += usize::from(now < 0.2);
            }
        }
        assert!(
            checked > 100,
            "only {checked} poses had a point within reach"
        );
    }

    /// A checker that admits everything, under the clearance rule.
    struct Free;
    impl MotionChecker for Free {
        fn pose_ok(&mut self, _: &[Real]) -> bool {
            true
        }
        fn motion_ok(&mut self, _: &[Real], _: &[Real]) -> bool {
            true
        }
    }

    /// A motion that sweeps a link through a measured point is refused; the
    /// pose the arm stands at passes even when closer than the clearance,
    /// and a motion from it that backs away passes while one that comes
    /// closer does not.
    #[test]
    fn motions_keep_the_clearance_and_may_back_away() {
        let robot = robot::builtin("denso-vm6083").unwrap();
        let safety = Safety::new(
            robot.clone(),
            Isometry3::identity(),
            &PlanConfig::default(),
            vec![1.0; 6],
        )
        .unwrap();
        let here = [0.0, -0.5, 2.0, 0.0, -1.0, 0.0];
        // A point 3 cm off the forearm's capsule, on the side the base
        // turns it towards for positive q1 (+y at q1 = 0).
        let frames = robot.forward_kinematics(&here).unwrap();
        let capsules: Vec<geom::Capsule> = robot
            .posed_collision_shapes(&frames)
            .into_iter()
            .filter_map(|s| match s {
                PosedShape::Capsule { link, capsule } if link.index() >= robot.mounted_links() => {
                    Some(capsule)
                }
                _ => None,
            })
            .collect();
        let longest = capsules
            .iter()
            .max_by(|a, b| a.segment.length().total_cmp(&b.segment.length()))
            .unwrap();
        let mid = longest.segment.a + 0.5 * (longest.segment.b - longest.segment.a);
        let p = mid + Vector3::new(0.0, longest.radius + 0.03, 0.0);
        let mut points = PointClearance::new();
        points.insert([p].iter());
        let mut checker = ClearanceChecker::new(Free, &safety, &points, 0.05, &here);
        let now = checker.clearance(&here);
        assert!(now <= 0.03 + 1e-9, "{now}");
        // Standing there is allowed.
        assert!(checker.pose_ok(&here));
        // A motion from here passes exactly when it never comes closer than
        // the arm stands; turning the base towards the point is refused.
        for q1 in [-0.3, 0.3] {
            let to = [q1, -0.5, 2.0, 0.0, -1.0, 0.0];
            let rule = safety
                .interpolate(&here, &to)
                .iter()
                .all(|c| checker.clearance(c) >= now);
            assert_eq!(checker.motion_ok(&here, &to), rule, "q1 = {q1}");
            assert_eq!(checker.motion_ok(&to, &here), rule, "q1 = {q1}, back");
        }
        let toward = [0.3, -0.5, 2.0, 0.0, -1.0, 0.0];
        assert!(checker.clearance(&toward) < now);
        assert!(!checker.motion_ok(&here, &toward));
        // Elsewhere the full clearance is needed.
        assert!(!checker.pose_ok(&toward));
        // Without a clearance, the inner checker's answer.
        let mut off = ClearanceChecker::new(Free, &safety, &points, 0.0, &here);
        assert!(off.motion_ok(&here, &toward) && off.pose_ok(&toward));
    }
}
