//! Safe manipulator poses (A§3.2.1.4, eq. 3.4–3.6): the smallest algebraic
//! distance `dist(Q)` from the links' bounding ellipsoids to every voxel that
//! is occupied **or unknown**; a pose is usable only when `dist(Q) > 1`, and a
//! motion only when every configuration checked along it is.

use crate::roadmap::{MotionChecker, weighted_distance};
use crate::{PlanConfig, PlanError};
use geom::{Ellipsoid, Isometry3, Real};
use map::{OccupancyGrid, VoxelKey};
use robot::Robot;

/// The ellipsoid safety measure of one robot placed in the world.
#[derive(Clone, Debug)]
pub struct Safety {
    robot: Robot,
    world_from_base: Isometry3,
    weights: Vec<Real>,
    check_step_m: Real,
    cap: Real,
}

impl Safety {
    /// The measure for `robot` at `world_from_base`, checking motions every
    /// `config.check_step_m` of the distance with joint weights `weights` (the
    /// roadmap's).
    pub fn new(
        robot: Robot,
        world_from_base: Isometry3,
        config: &PlanConfig,
        weights: Vec<Real>,
    ) -> Result<Self, PlanError> {
        config.validate(robot.dof())?;
        if weights.len() != robot.dof() || weights.iter().any(|w| !(w.is_finite() && *w > 0.0)) {
            return Err(PlanError::config(
                "plan.joint_weights",
                "one positive finite weight per joint",
                format!("{weights:?}"),
            ));
        }
        Ok(Self {
            robot,
            world_from_base,
            weights,
            check_step_m: config.check_step_m,
            cap: config.safety_cap,
        })
    }

    /// The robot.
    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// Where the robot's base stands in the world (the grid's frame).
    pub fn world_from_base(&self) -> &Isometry3 {
        &self.world_from_base
    }

    /// The largest value [`Safety::dist`] resolves.
    pub fn cap(&self) -> Real {
        self.cap
    }

    /// The bounding ellipsoids of the moving links (the base and the links
    /// fixed to it never move and are not checked, as in eq. 3.5's
    /// `i ∈ {1, …, 6}`; see `Robot::mounted_links`) at `q`, in the world frame.
    pub fn ellipsoids(&self, q: &[Real]) -> Result<Vec<Ellipsoid>, PlanError> {
        Ok(self.posed_links(q)?.into_iter().map(|(_, e)| e).collect())
    }

    /// `dist(Q)` of eq. 3.5 over the voxel centres of `grid` that are occupied
    /// or unknown (everything outside the grid counts as unknown), capped at
    /// [`Safety::cap`].
    pub fn dist(&self, grid: &OccupancyGrid, q: &[Real]) -> Result<Real, PlanError> {
        self.dist_of_links(grid, q, 1..usize::MAX, self.cap, Real::NEG_INFINITY)
    }

    /// `dist(Q)` over the ellipsoids of the links with index in `links` only
    /// (link 0 never counts), resolved up to `bound` (at most the cap), and
    /// returned as soon as a value at or below `stop_at` is found (a pose
    /// already known unsafe need not be measured exactly). Used when only some
    /// links move, as during a tilt sweep.
    pub fn dist_of_links(
        &self,
        grid: &OccupancyGrid,
        q: &[Real],
        links: std::ops::Range<usize>,
        bound: Real,
        stop_at: Real,
    ) -> Result<Real, PlanError> {
        let mut best = bound.min(self.cap);
        for (link, e) in self.posed_links(q)? {
            if !links.contains(&link) {
                continue;
            }
            best = best.min(ellipsoid_dist(grid, &e, best, stop_at));
            if best <= stop_at {
                break;
            }
        }
        Ok(best)
    }

    /// The bounding ellipsoids of the moving links at `q` in the world frame,
    /// each with its link's index (as [`Safety::ellipsoids`], one forward
    /// kinematics for callers that measure links one by one with
    /// [`Safety::ellipsoid_dist`]).
    pub fn posed_links(&self, q: &[Real]) -> Result<Vec<(usize, Ellipsoid)>, PlanError> {
        let frames = self.robot.forward_kinematics(q)?;
        Ok(self.posed_links_in(&frames))
    }

    /// [`Safety::posed_links`] of the link frames `frames` (the robot's
    /// forward kinematics at some `q`), for callers that need the frames
    /// for more than the links.
    pub fn posed_links_in(&self, frames: &[Isometry3]) -> Vec<(usize, Ellipsoid)> {
        let mounted = self.robot.mounted_links();
        self.robot
            .posed_ellipsoids(frames)
            .into_iter()
            .filter(|(link, _)| link.index() >= mounted)
            .map(|(link, e)| (link.index(), e.transformed(&self.world_from_base)))
            .collect()
    }

    /// `dist(Q)` of one posed ellipsoid `e` (from [`Safety::posed_links`]),
    /// resolved up to `bound` (at most the cap), returned early at or below
    /// `stop_at`: [`Safety::dist_of_links`] of that ellipsoid alone.
    pub fn ellipsoid_dist(
        &self,
        grid: &OccupancyGrid,
        e: &Ellipsoid,
        bound: Real,
        stop_at: Real,
    ) -> Real {
        ellipsoid_dist(grid, e, bound.min(self.cap), stop_at)
    }

    /// The smallest `dist(Q)` over the configurations checked along the
    /// straight joint-space motion `a → b` (ends included, at least every
    /// `check_step_m` of weighted distance). Stops early, returning the value
    /// found, once a configuration is at or below `stop_at`.
    pub fn motion_dist(
        &self,
        grid: &OccupancyGrid,
        a: &[Real],
        b: &[Real],
        stop_at: Real,
    ) -> Result<Real, PlanError> {
        let mut best = Real::INFINITY;
        for q in self.interpolate(a, b) {
            best = best.min(self.dist(grid, &q)?);
            if best <= stop_at {
                break;
            }
        }
        Ok(best)
    }

    /// The configurations checked along `a → b`: `n + 1` evenly spaced, `n`
    /// the fewest steps of at most `check_step_m` weighted distance.
    pub fn interpolate(&self, a: &[Real], b: &[Real]) -> Vec<Vec<Real>> {
        let len = weighted_distance(&self.weights, a, b);
        let steps = (len / self.check_step_m).ceil().max(1.0) as usize;
        (0..=steps)
            .map(|s| {
                let t = s as Real / steps as Real;
                a.iter().zip(b).map(|(x, y)| x + t * (y - x)).collect()
            })
            .collect()
    }

    /// A [`MotionChecker`] against `grid` (safe: `dist(Q) > 1`).
    pub fn checker<'a>(&'a self, grid: &'a OccupancyGrid) -> SafetyChecker<'a> {
        SafetyChecker {
            safety: self,
            grid,
            checked: 0,
        }
    }
}

/// Smallest algebraic distance from `e` to the centre of any occupied or
/// unknown voxel, among voxels within `bound` of it (larger values report
/// `bound`); returns early with the first value at or below `stop_at`.
fn ellipsoid_dist(grid: &OccupancyGrid, e: &Ellipsoid, bound: Real, stop_at: Real) -> Real {
    let v = grid.geometry().voxel_m();
    let reach = Ellipsoid::new(e.pose, e.radii * bound.sqrt()).bounding_box();
    let lo = VoxelKey::of_point(&reach.min, v);
    let hi = VoxelKey::of_point(&reach.max, v);
    let (Some(lo), Some(hi)) = (lo, hi) else {
        return 0.0;
    };
    let (lo, hi) = (lo.coords(), hi.coords());
    // s = diag(1/r) Rᵀ (p − c), stepped along x.
    let inv = e.pose.rotation.inverse();
    let scale = e.radii.map(|r| 1.0 / r);
    let to_local = |p: &geom::Point3| {
        (inv * (p - geom::Point3::from(e.pose.translation.vector))).component_mul(&scale)
    };
    let step_x = (inv * geom::Vector3::new(v, 0.0, 0.0)).component_mul(&scale);
    // Only the voxels that are not free count, found 64 at a time in a
    // row's bits; of those, only the ones whose distance can be below the
    // best so far: along a row `|s|²` is the quadratic `c + 2bt + at²` of
    // the voxel's step `t` from the row's first, so the steps where it is
    // within `ROW_MARGIN` of the best (widened by one voxel each way) are
    // found in closed form, and a row with none is skipped. In the rows
    // looked at, `s` is still stepped voxel by voxel from the row's first,
    // so every distance is the same number (to the bit) a scan of the whole
    // box gives, and so is the first one at or below `stop_at` in scan
    // order.
    let not_free = grid.not_free();
    let a = step_x.norm_squared();
    let mut best = bound;
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            let mut row: Option<(geom::Vector3, i32, i64, i64)> = None;
            let mut x0 = lo[0];
            while x0 <= hi[0] {
                let n = hi[0] - x0 + 1;
                let mut bits = not_free.row64(y, z, x0);
                if n < 64 {
                    bits &= (1u64 << n) - 1;
                }
                if bits == 0 {
                    x0 = x0.saturating_add(64);
                    continue;
                }
                let (s, x, t_lo, t_hi) = row.get_or_insert_with(|| {
                    let s0 = to_local(&VoxelKey::new(lo[0], y, z).center(v));
                    let (b, c) = (s0.dot(&step_x), s0.norm_squared());
                    let disc = b * b - a * (c - best - ROW_MARGIN);
                    let (t_lo, t_hi) = if disc < 0.0 {
                        (1, 0)
                    } else {
                        let r = disc.sqrt();
                        (
                            ((-b - r) / a).floor() as i64 - 1,
                            ((-b + r) / a).ceil() as i64 + 1,
                        )
                    };
                    (s0, lo[0], t_lo, t_hi)
                });
                // The steps `t` of this chunk's bits: `x0 − lo[0] + i`.
                let t0 = i64::from(x0) - i64::from(lo[0]);
                let keep_from = (*t_lo - t0).clamp(0, 64);
                let keep_to = (*t_hi - t0 + 1).clamp(0, 64);
                if keep_from >= keep_to {
                    bits = 0;
                } else {
                    if keep_to < 64 {
                        bits &= (1u64 << keep_to) - 1;
                    }
                    bits &= u64::MAX << keep_from;
                }
                while bits != 0 {
                    let at = x0 + bits.trailing_zeros() as i32;
                    bits &= bits - 1;
                    while *x < at {
                        *s += step_x;
                        *x += 1;
                    }
                    let d = s.norm_squared();
                    if d < best {
                        best = d;
                        if best <= stop_at {
                            return best;
                        }
                    }
                }
                x0 = x0.saturating_add(64);
            }
        }
    }
    best
}

/// How far above the best distance so far a row's closed-form minimum may
/// be and the row still be scanned: far more than the rounding of `s`
/// stepped along a row (a few ulps of `|s|` per step), so no voxel that the
/// scan would take is skipped.
const ROW_MARGIN: Real = 1e-9;

/// [`Safety`] against one grid, as the roadmap's motion checker.
#[derive(Debug)]
pub struct SafetyChecker<'a> {
    safety: &'a Safety,
    grid: &'a OccupancyGrid,
    checked: usize,
}

impl SafetyChecker<'_> {
    /// Configurations evaluated so far.
    pub fn configurations_checked(&self) -> usize {
        self.checked
    }
}

impl MotionChecker for SafetyChecker<'_> {
    fn pose_ok(&mut self, q: &[Real]) -> bool {
        self.checked += 1;
        safe_pose(self.safety, self.grid, q)
    }

    fn motion_ok(&mut self, a: &[Real], b: &[Real]) -> bool {
        for q in self.safety.interpolate(a, b) {
            if !self.pose_ok(&q) {
                return false;
            }
        }
        true
    }

    /// Every `COARSE_STRIDE`th configuration `motion_ok` checks, and the
    /// last: a subset, so `false` only where `motion_ok` is.
    fn motion_may_be_ok(&mut self, a: &[Real], b: &[Real]) -> bool {
        let (ok, checked) = coarse_motion(self.safety, self.grid, a, b);
        self.checked += checked;
        ok
    }

    /// In parallel (the answers depend on the configuration and the grid
    /// alone).
    fn poses_ok(&mut self, qs: &[&[Real]]) -> Vec<bool> {
        use rayon::prelude::*;
        let (safety, grid) = (self.safety, self.grid);
        self.checked += qs.len();
        qs.par_iter().map(|q| safe_pose(safety, grid, q)).collect()
    }

    /// In parallel, one motion per task.
    fn motions_may_be_ok(&mut self, motions: &[(&[Real], &[Real])]) -> Vec<bool> {
        use rayon::prelude::*;
        let (safety, grid) = (self.safety, self.grid);
        let answers: Vec<(bool, usize)> = motions
            .par_iter()
            .map(|(a, b)| coarse_motion(safety, grid, a, b))
            .collect();
        self.checked += answers.iter().map(|a| a.1).sum::<usize>();
        answers.into_iter().map(|a| a.0).collect()
    }
}

/// `dist(Q) > 1` at `q` ([`SafetyChecker`]'s `pose_ok`). Resolved only up
/// to the next number above 1: a voxel nearer than that is at or below 1
/// and ends the search, and no voxel farther can change the answer, so the
/// ellipsoids' boxes are those of `dist = 1`, a third of the cap's across
/// (the same answers as measuring up to the cap, in a ninth of the rows).
fn safe_pose(safety: &Safety, grid: &OccupancyGrid, q: &[Real]) -> bool {
    safety
        .dist_of_links(grid, q, 1..usize::MAX, 1.0f64.next_up(), 1.0)
        .is_ok_and(|d| d > 1.0)
}

/// [`SafetyChecker`]'s `motion_may_be_ok` of `a → b`, and the number of
/// configurations it checked.
fn coarse_motion(safety: &Safety, grid: &OccupancyGrid, a: &[Real], b: &[Real]) -> (bool, usize) {
    let checked = safety.interpolate(a, b);
    let n = checked.len();
    let mut count = 0;
    let ok = checked
        .iter()
        .enumerate()
        .filter(|(i, _)| i % COARSE_STRIDE == 0 || *i + 1 == n)
        .all(|(_, q)| {
            count += 1;
            safe_pose(safety, grid, q)
        });
    (ok, count)
}

/// A search's first look at a motion checks one configuration in this many.
const COARSE_STRIDE: usize = 4;
