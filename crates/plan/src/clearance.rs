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
use rustc_hash::{FxHashMap, FxHashSet};

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

/// The measured points, indexed for clearance queries.
#[derive(Clone, Debug, Default)]
pub struct PointClearance {
    kept: FxHashSet<[i32; 3]>,
    cells: FxHashMap<[i32; 3], Vec<Point3>>,
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
            if self.kept.insert(key(p, POINT_DEDUP_M)) {
                self.cells.entry(key(p, CELL_M)).or_default().push(*p);
                if let Some(a) = added.as_deref_mut() {
                    a.insert(std::iter::once(p));
                }
            }
        }
    }

    /// Forget every point (the allocations are kept).
    pub fn clear(&mut self) {
        self.kept.clear();
        self.cells.clear();
    }

    /// Points kept.
    pub fn len(&self) -> usize {
        self.kept.len()
    }

    /// No point kept.
    pub fn is_empty(&self) -> bool {
        self.kept.is_empty()
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
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        let Some(points) = self.cells.get(&[x, y, z]) else {
                            continue;
                        };
                        // No point of a cell is nearer than its centre less
                        // half its diagonal (the distance is 1-Lipschitz).
                        let centre = Point3::new(
                            (Real::from(x) + 0.5) * CELL_M,
                            (Real::from(y) + 0.5) * CELL_M,
                            (Real::from(z) + 0.5) * CELL_M,
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
