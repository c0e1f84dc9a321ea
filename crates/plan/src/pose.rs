//! Stage Two pose selection (A§3.3, eq. 3.9–3.20): a joint vector `Q` from
//! which the scanner's centre ray meets a Scale-Like Disc within the Laser
//! Range Classifier's constraints, found by Levenberg–Marquardt on six
//! sigmoid costs.
//!
//! # What each piece computes
//!
//! * [`view_geometry`] — eq. 3.11–3.13 for one scanner pose `⁰T_s(Q)` (eq.
//!   3.9–3.10) and one [`Target`] `{P̂ᵢ, n⃗ᵢ}`: the centre ray's intersection
//!   `p_a` with the disc's plane, the range `d = ‖p_a − p₁‖` and the angle of
//!   incidence `φ`.
//! * [`PoseConfig::g1_orientation`] … [`PoseConfig::g6_limits`] — the six
//!   costs of eq. 3.14–3.19 with the sigmoid scales this module adds.
//! * [`PoseSelector::evaluate`] — every quantity and cost of one `Q`, the
//!   objective `g(Q) = Σ (gᵢ(Q) − ĝᵢ)²` of eq. 3.20 and which LRC constraints
//!   hold ([`Constraints`]).
//! * [`PoseSelector::select`] — LM (crate `levenberg-marquardt`) on the
//!   residuals `rᵢ = gᵢ(Q) − ĝᵢ` over the joints, from several starts; the
//!   best result as a [`PoseSolution`].
//!
//! # Readings of the printed equations
//!
//! Each is also in the crate README, "Where we fill gaps".
//!
//! * **Eq. 3.11, sign.** Printed `p_a = p₁ − (p₃ − p₁) n⃗·(P̂ − p₁) / n⃗·(p₃ −
//!   p₁)`. The point `p₁ + t (p₃ − p₁)` with `t = n⃗·(P̂ − p₁) / n⃗·(p₃ − p₁)`
//!   is the one on the plane (substitute it into `n⃗·(x − P̂) = 0`); the printed
//!   minus gives its mirror image behind the scanner. We use `+`. A ray that
//!   is parallel to the plane or meets it behind the scanner (`t ≤ 0`) has no
//!   `p_a`; then `d = ρ = ∞` and `g₂ = g₃ = 1`, the limit of a ray that grazes
//!   the plane ever farther away.
//! * **Eq. 3.11–3.13, `p₂`.** The text takes `p₂` "from column three" of eq.
//!   3.10 but writes `[n_x, n_y, n_z]` (column one, the scan plane's normal).
//!   Column three, `[a_x, a_y, a_z]`, is the centre ray, so `p₂` is the
//!   scanner frame's `z` axis in the world and `p₃ = p₁ + p₂`.
//! * **Eq. 3.13, `φ`.** Printed `φ = arccos(n⃗ᵢ · p₂)`. Disc normals point out
//!   of the surface toward the sensors that saw it ([`map::Orientation`]), and
//!   the centre ray points from the scanner to the surface, so a head-on view
//!   has `n⃗ᵢ · p₂ = −1` and the printed formula gives 180°. The angle of
//!   incidence (Fig. 3.3) is `φ = arccos(−n⃗ᵢ · p₂)`; `φ > 90°` is a view of
//!   the back of the disc.
//! * **Eq. 3.12 vs the text.** §3.3.1.2 says `d` is the distance to the centre
//!   `P̂ᵢ`; eq. 3.12 writes `‖p_a − p₁‖`. We follow the equation. Whenever
//!   the accuracy constraint holds the two differ by at most `ρ_min`.
//! * **Eq. 3.15, the range cost.** Printed `1 − σ(d − d_min) + σ(d_max − d)`
//!   is ≈ 1 inside `[d_min, d_max]`, ≈ 0 above `d_max` and ≈ 2 below
//!   `d_min`, the opposite of "a cost function for minimum and maximum
//!   constraints" (Fig. 3.4b). The evident intent is the general form of
//!   §3.3.1 (and of eq. 3.19): `1 − σ(d − d_min) + σ(d − d_max)`, low inside,
//!   high outside.
//! * **Eq. 3.16, the accuracy cost.** Printed `1 − σ(‖p_a − P̂ᵢ‖ − ρ_min)` is
//!   §3.3.1's *minimum* constraint: low when the ray misses the centre by
//!   more than `ρ_min`. The text asks for the opposite ("within ρ_min"), a
//!   maximum constraint: `σ(‖p_a − P̂ᵢ‖ − ρ_min)`. We also normalise it so a
//!   perfect aim costs exactly 0: `(σ(…) − σ₀) / (1 − σ₀)`, `σ₀ = σ(−ρ_min/s)`
//!   (0.0067 with the default scale; the cost at `ρ_min` becomes 0.4966).
//!   Unnormalised, `ĝ₃ = 0` is out of reach by a residual of `σ₀` sitting on
//!   the cone point of `‖p_a − P̂ᵢ‖`, where no step can lower it: the aimed
//!   starts (below) arrive exactly there, and LM rejected every trial step
//!   until its step tolerance ended the run, a dozen to thirty evaluations
//!   for nothing. The other costs' values at their ideal are below 5·10⁻⁵
//!   and at smooth or flat minima; they are left as printed.
//! * **Eq. 3.18, the tilt cost.** Printed `σ(q_t − q_t,max)`, "q_t less than
//!   q_t,max". The sweep tilts joint `q_t` through `α` centred on the pose
//!   (`sensor::SweepConfig::tilt_values` centres the window on the pose and
//!   only shifts it when it would leave the joint's limits), so the pose needs
//!   `α/2` of travel on *both* sides inside the limits. We read `q_t,max` as
//!   that requirement on the room `min(q_t − q_t,min, q_t,max' − q_t)` left to
//!   the nearer limit: `g₅ = σ(tilt_room − room)`. With symmetric limits `±L`
//!   this is exactly eq. 3.18 on `|q_t|` with `q_t,max = L − α/2` (VM-6083:
//!   `|q₅| ≤ 90°`).
//! * **Eq. 3.19** is used as printed (it has the right signs).
//! * **Sigmoid scales.** The printed sigmoids have slope ¼ per unit of their
//!   argument; with radians and metres they would be almost flat over the
//!   whole workspace (`g₃` would change by 0.004 between a perfect aim and a
//!   miss by 15 mm). Every sigmoid here is `σ((x − x_bound)/s)` with a scale
//!   `s` per cost ([`PoseConfig`]'s `*_scale*` fields): the cost is ½ at the
//!   bound, 0.12 / 0.88 two scales inside / outside, below 0.01 / above 0.99
//!   beyond 4.6 scales.
//! * **Hard joint limits** ("enforced in implementation", §3.3.1.6): the
//!   kinematic costs `g₁…g₄` are evaluated at `Q` clamped into the limits,
//!   `g₅` and `g₆` at `Q` itself, so a step past a limit changes nothing but
//!   `g₆`, which pushes back. The returned joints are clamped and every value
//!   is recomputed there, so a solution never leaves the limits.
//!
//! # The solver
//!
//! * **Residuals** `rᵢ = gᵢ(Q) − ĝᵢ`, `i = 1…6` (eq. 3.20), over the `dof`
//!   joints; `ĝᵢ = 0` by default as in the thesis. LM is given seven
//!   numbers: `r₃` enters as the 2-vector `r₃ u`, `u` the unit vector in the
//!   disc's plane from `P̂ᵢ` toward `p_a`. The sum of squares is eq. 3.20's
//!   `g(Q)` exactly, but near a perfect aim `r₃ u ≈ g₃′(0) (p_a − P̂ᵢ)` is
//!   smooth where `r₃` alone has a cone point: with the scalar, LM crept
//!   along the valley `p_a = P̂ᵢ` (a blind step at the apex, then a step back)
//!   and most runs went to the iteration limit; with the vector they stop
//!   by the gradient test (169 targets on a wall: median 8 iterations, at
//!   most 28; Paul reports 20 and 27).
//! * **Termination** as Table 6.1's LM row: at most
//!   [`PoseConfig::max_iterations`] iterations (one Jacobian each), or when
//!   the gradient of eq. 3.20's `g`, `‖∇g‖∞ = ‖2 Jᵀ r‖∞`, is at most
//!   [`PoseConfig::gradient_tolerance`] (§6.3.2: "the improvement gradient
//!   reaching the specified tolerance level"). The crate's own `gtol` is a
//!   cosine between `r` and the columns of `J`; on a sigmoid's tail a
//!   residual and its own derivative are parallel (`r ≈ eˣ`, `∂r ≈ eˣ/s`), so
//!   the cosine stays near 1 while the residual shrinks, and with it the
//!   median run went to the iteration limit. It is switched off.
//! * **Trust region.** The crate's first step bound (100, with column
//!   scaling) threw the arm across the workspace and spent about a dozen
//!   evaluations per run shrinking back; we take `0.1 ‖Q‖` radians in joint
//!   space without rescaling (every parameter is an angle).
//! * **Jacobian** by forward differences of step
//!   [`PoseConfig::difference_step_rad`] (taken backward at an upper limit).
//!   `dist(Q)` (eq. 3.5) is a minimum over finitely many voxel centres of a
//!   smooth function of `Q`: continuous, smooth between kinks where the
//!   nearest voxel changes, flat where it reaches the search bound. A step
//!   much smaller than the spacing of those kinks measures the slope of the
//!   voxel that is nearest now (exactly the piece LM is standing on); a step
//!   of the order of a voxel would instead average unrelated pieces and blur
//!   the other costs, whose sigmoids switch over millimetres. LM's trust
//!   region absorbs the slope changes at kinks.
//! * **`dist(Q)` is bounded** at `1 + 10 · dist_scale` (3 by default, where
//!   `g₄ < 5·10⁻⁵`; at most [`Safety::cap`]): farther voxels cannot change
//!   `g₄`, and not visiting them bounds the work
//!   ([`Safety::dist_of_links`]). Each link is measured on its own up to the
//!   bound plus a margin of 0.5. The difference of joint `j` measures again
//!   only the links it moves that were within that reach, against the
//!   distance of the links that did not move: a link beyond it cannot come
//!   within the bound by a step of at most 1e-4 rad. In open space the
//!   differences then cost no voxel visits at all.
//! * **Starts.** The sigmoids are flat far from their bounds (a miss by 5 cm
//!   saturates `g₃`), so LM refines a viewpoint near a good one rather than
//!   finding one from anywhere: §3.3.1 calls it "a fine tuning optimisation
//!   approach", and §3.3 notes that inverse kinematics would do if there
//!   were no obstacles and one viewpoint. The candidates are the given start
//!   (clamped into the limits) and nine *aimed starts*: damped Gauss–Newton
//!   inverse kinematics from the given start, ignoring obstacles, toward the
//!   centre ray through `P̂ᵢ` along a chosen direction, at a range in the
//!   middle of `[d_min, d_max]` (15 %–60 % of the way), with the tilting
//!   joint's room plus 10° and every joint 10° inside its limits (the roll
//!   about the ray is free). The directions are the normal and eight at
//!   `φ_max/2` around it, starting toward the robot's shoulder. The
//!   candidates are ranked by `g(Q)` (ties: the earlier one) and LM runs from
//!   the best [`PoseConfig::starts`] in that order, stopping at the first
//!   result that meets every constraint ([`PoseConfig::stop_at_valid`]).
//!   Everything is deterministic.
//! * **The best run** is one that meets every constraint, then the lowest
//!   `g(Q)`, then the earliest run.
//!
//! ```
//! use geom::{Isometry3, Point3, Vector3};
//! use map::{OccupancyConfig, OccupancyGrid, RegionsConfig};
//! use plan::{PlanConfig, PoseConfig, PoseSelector, Safety, Target};
//!
//! let robot = robot::builtin("denso-vm6083")?;
//! let safety = Safety::new(robot, Isometry3::identity(), &PlanConfig::default(), vec![1.0; 6])?;
//! let selector = PoseSelector::new(&safety, PoseConfig::default())?;
//! // A grid where nothing is known: every pose is unsafe (g4), but the
//! // geometry of the view is still optimised.
//! let grid = OccupancyGrid::new(OccupancyConfig {
//!     voxel_m: 0.1,
//!     regions: RegionsConfig::around([0.0, 0.0, 0.475], [1.1, 1.6, 2.1]),
//!     ..OccupancyConfig::default()
//! })?;
//! let target = Target::new(Point3::new(0.7, 0.0, 0.5), Vector3::new(-1.0, 0.0, 0.0))?;
//! let start = [0.0, 0.3, 1.2, 0.0, 0.8, 0.0];
//! let solution = selector.select(&grid, &target, &start)?;
//! let view = &solution.pose.view;
//! assert!(view.phi_rad < 42f64.to_radians());
//! assert!(view.hit.is_some_and(|h| h.rho_m <= 0.015));
//! assert!(!solution.pose.constraints.safety);
//! assert!(!solution.pose.constraints.all());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::{PlanError, Safety};
use geom::{Isometry3, Point3, Real, UnitVector3, Vector3};
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt, TerminationReason};
use map::OccupancyGrid;
use nalgebra::storage::Owned;
use nalgebra::{DMatrix, DVector, Dyn, Matrix6xX, OMatrix, SVector, U7};
use robot::{JointLimits, Robot};
use serde::{Deserialize, Serialize};
use std::cell::Cell;

/// Parameters of Stage Two pose selection. `Default` is Paul's Table 6.1
/// where the thesis gives a value; the rest are ours and say why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PoseConfig {
    /// Largest angle of incidence `φ_max`, degrees (A Table 6.1: 42°).
    pub phi_max_deg: Real,
    /// Shortest range `d_min`, metres (A Table 6.1: 250 mm).
    pub d_min_m: Real,
    /// Longest range `d_max`, metres (A Table 6.1: 800 mm).
    pub d_max_m: Real,
    /// Largest miss of the disc centre `ρ_min`, metres (A Table 6.1: 15 mm).
    pub rho_min_m: Real,
    /// The tilting joint `q_t`, 1-based (A§3.3.1.5: the fifth joint; the same
    /// joint as `sensor::SweepConfig::joint`).
    pub tilt_joint: usize,
    /// Travel the tilting joint needs on each side of the pose, inside its
    /// limits, degrees: half the sweep's `α` (A Table 6.1: α = 60°, so 30°).
    pub tilt_room_deg: Real,
    /// Most LM runs, from the best-ranked of the ten candidate starts (the
    /// given start and nine aimed starts; module docs). Ours: Paul reports
    /// one run per viewpoint. 5: in our tests the first run almost always
    /// succeeds; the others are for targets where it does not. With 1, LM
    /// runs from the given start alone (no aimed starts are made).
    pub starts: usize,
    /// Stop after the first run (in start order) whose result meets every
    /// constraint; `false` runs from every start and keeps the best. Paul runs
    /// LM once per viewpoint; further starts matter only when a run fails.
    pub stop_at_valid: bool,
    /// Most LM iterations per run (A Table 6.1: 50).
    pub max_iterations: usize,
    /// LM's gradient tolerance (A Table 6.1: 1e-4): a run stops when
    /// `‖∇g‖∞ = ‖2 Jᵀ r‖∞` falls to it, `g` being eq. 3.20's objective.
    pub gradient_tolerance: Real,
    /// Desired values `ĝ₁ … ĝ₆` (A eq. 3.20: all zero).
    #[serde(deserialize_with = "geom::exact::array")]
    pub desired: [Real; 6],
    /// Scale of `g₁`'s sigmoid, degrees: `g₁ = σ((φ − φ_max)/s)`. 2°: a view
    /// 9° inside `φ_max` costs 0.01.
    pub phi_scale_deg: Real,
    /// Scale of `g₂`'s sigmoids, metres. 20 mm: the cost is below 0.01 from
    /// 0.34 m to 0.71 m and below 10⁻⁵ from 0.48 m to 0.57 m.
    pub d_scale_m: Real,
    /// Scale of `g₃`'s sigmoid, metres. 3 mm: a perfect aim costs
    /// `σ(−5) = 0.007`, a miss by `ρ_min` 0.5, by twice `ρ_min` 0.993.
    pub rho_scale_m: Real,
    /// Scale of `g₄`'s sigmoid, in units of the algebraic distance (eq. 3.5,
    /// 1 on an ellipsoid's surface, 0 at its centre). 0.2: a voxel centre at
    /// an ellipsoid's centre costs 0.993, at `dist = 2` (1.41 ellipsoid radii)
    /// 0.007.
    pub dist_scale: Real,
    /// Scale of `g₅`'s sigmoid, degrees. 2°, as `g₁`.
    pub tilt_scale_deg: Real,
    /// Scale of `g₆`'s sigmoids, degrees. 2°, as `g₁`.
    pub joint_scale_deg: Real,
    /// Forward-difference step of the numerical Jacobian, radians (metres
    /// for prismatic joints), at most 1e-4. 1e-6: far below the spacing of
    /// `dist(Q)`'s kinks and the millimetre widths of the sigmoids, far above
    /// rounding.
    pub difference_step_rad: Real,
    /// Give a run up when, at its [`GIVE_UP_AFTER`]th iteration or later,
    /// the aim misses the disc centre by more than this many `g₃` scales
    /// ([`PoseConfig::rho_scale_m`]), or the centre ray meets no plane; 0
    /// (the default, as Paul) never gives up. Ours, for the blast plan (10:
    /// [`PoseTermination::GaveUp`] says why).
    pub give_up_scales: Real,
    /// The aimed starts' inverse kinematics takes back a step that raises
    /// its cost and halves its step bound (a monotone damped Gauss–Newton);
    /// `false` (the default) keeps the bound fixed and runs to convergence
    /// or 100 iterations. Ours, for the blast plan: with the fixed bound,
    /// 70 % of the 57 672 runs of bridge1's plan went to the limit swinging
    /// between two poses (80 iterations a run on average, 37 % of the
    /// plan's CPU time); backtracking ends them in 30, and the plan has
    /// poses for 5879 discs instead of 5890. Stage Two keeps Paul's
    /// behaviour: its decisions change with the starts, and its material
    /// accuracy on bridge1 fell from 95.1 % to 92.9 % in one such run.
    pub aim_backtracking: bool,
}

/// Most [`PoseConfig::starts`]: the given start and the nine aimed ones
/// (more would run no more LM).
pub const MAX_STARTS: usize = 10;
/// Most [`PoseConfig::max_iterations`] (A Table 6.1: 50; each iteration
/// costs a numerical Jacobian, about a millisecond on bridge1).
pub const MAX_LM_ITERATIONS: usize = 10_000;

/// The iteration from which [`PoseConfig::give_up_scales`] applies (ours:
/// the first steps of a run from a start aimed elsewhere may swing the aim
/// far before it settles).
pub const GIVE_UP_AFTER: usize = 5;

impl Default for PoseConfig {
    fn default() -> Self {
        Self {
            phi_max_deg: 42.0,
            d_min_m: 0.25,
            d_max_m: 0.8,
            rho_min_m: 0.015,
            tilt_joint: 5,
            tilt_room_deg: 30.0,
            starts: 5,
            stop_at_valid: true,
            max_iterations: 50,
            gradient_tolerance: 1e-4,
            desired: [0.0; 6],
            phi_scale_deg: 2.0,
            d_scale_m: 0.02,
            rho_scale_m: 0.003,
            dist_scale: 0.2,
            tilt_scale_deg: 2.0,
            joint_scale_deg: 2.0,
            difference_step_rad: 1e-6,
            give_up_scales: 0.0,
            aim_backtracking: false,
        }
    }
}

/// `σ(x) = 1 / (1 + e^{−x})`, without overflow for large `|x|` (`σ(±∞)` is
/// 1 or 0).
#[inline]
pub fn sigmoid(x: Real) -> Real {
    if x >= 0.0 {
        1.0 / (1.0 + (-x).exp())
    } else {
        let e = x.exp();
        e / (1.0 + e)
    }
}

impl PoseConfig {
    /// Check every field (the robot-dependent `tilt_joint` is checked again by
    /// [`PoseSelector::new`]).
    pub fn validate(&self) -> Result<(), PlanError> {
        let positive = |field: &'static str, v: Real| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(PlanError::config(field, "a positive finite value", v))
            }
        };
        if !(self.phi_max_deg.is_finite() && self.phi_max_deg > 0.0 && self.phi_max_deg <= 90.0) {
            return Err(PlanError::config(
                "pose.phi_max_deg",
                "an angle in (0°, 90°]",
                self.phi_max_deg,
            ));
        }
        positive("pose.d_min_m", self.d_min_m)?;
        positive("pose.d_max_m", self.d_max_m)?;
        if self.d_max_m <= self.d_min_m {
            return Err(PlanError::config(
                "pose.d_max_m",
                "greater than pose.d_min_m",
                self.d_max_m,
            ));
        }
        positive("pose.rho_min_m", self.rho_min_m)?;
        if self.tilt_joint == 0 {
            return Err(PlanError::config(
                "pose.tilt_joint",
                "a 1-based joint number",
                0,
            ));
        }
        if !(self.tilt_room_deg.is_finite() && self.tilt_room_deg >= 0.0) {
            return Err(PlanError::config(
                "pose.tilt_room_deg",
                "a finite angle ≥ 0",
                self.tilt_room_deg,
            ));
        }
        if !(1..=MAX_STARTS).contains(&self.starts) {
            return Err(PlanError::config(
                "pose.starts",
                "from 1 to 10 (the given start and nine aimed ones)",
                self.starts,
            ));
        }
        if !(1..=MAX_LM_ITERATIONS).contains(&self.max_iterations) {
            return Err(PlanError::config(
                "pose.max_iterations",
                "from 1 to 10 000 (MAX_LM_ITERATIONS)",
                self.max_iterations,
            ));
        }
        if !(self.gradient_tolerance.is_finite() && self.gradient_tolerance >= 0.0) {
            return Err(PlanError::config(
                "pose.gradient_tolerance",
                "a finite value ≥ 0",
                self.gradient_tolerance,
            ));
        }
        if self.desired.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(PlanError::config(
                "pose.desired",
                "six finite values ≥ 0",
                format!("{:?}", self.desired),
            ));
        }
        positive("pose.phi_scale_deg", self.phi_scale_deg)?;
        positive("pose.d_scale_m", self.d_scale_m)?;
        positive("pose.rho_scale_m", self.rho_scale_m)?;
        positive("pose.dist_scale", self.dist_scale)?;
        positive("pose.tilt_scale_deg", self.tilt_scale_deg)?;
        positive("pose.joint_scale_deg", self.joint_scale_deg)?;
        if !(self.difference_step_rad.is_finite()
            && self.difference_step_rad > 0.0
            && self.difference_step_rad <= 1e-4)
        {
            return Err(PlanError::config(
                "pose.difference_step_rad",
                "a step in (0, 1e-4]",
                self.difference_step_rad,
            ));
        }
        if !(self.give_up_scales.is_finite() && self.give_up_scales >= 0.0) {
            return Err(PlanError::config(
                "pose.give_up_scales",
                "a finite number ≥ 0 (0: never)",
                self.give_up_scales,
            ));
        }
        Ok(())
    }

    /// `g₁` (eq. 3.14): `σ((φ − φ_max)/s)`, a maximum constraint on the angle
    /// of incidence `φ` (radians).
    pub fn g1_orientation(&self, phi_rad: Real) -> Real {
        sigmoid((phi_rad - self.phi_max_deg.to_radians()) / self.phi_scale_deg.to_radians())
    }

    /// `g₂` (eq. 3.15, read as Fig. 3.4b): `1 − σ((d − d_min)/s) + σ((d −
    /// d_max)/s)`, low inside `[d_min, d_max]`. `d = ∞` (no intersection)
    /// costs 1.
    pub fn g2_range(&self, d_m: Real) -> Real {
        let s = self.d_scale_m;
        sigmoid((self.d_min_m - d_m) / s) + sigmoid((d_m - self.d_max_m) / s)
    }

    /// `g₃` (eq. 3.16, read as a maximum constraint, normalised):
    /// `(σ((ρ − ρ_min)/s) − σ₀) / (1 − σ₀)` with `ρ = ‖p_a − P̂ᵢ‖` and `σ₀ =
    /// σ(−ρ_min/s)`, so a perfect aim costs exactly 0 (½ − 0.003 at `ρ_min`
    /// with the defaults). `ρ = ∞` (no intersection) costs 1.
    pub fn g3_accuracy(&self, rho_m: Real) -> Real {
        let floor = sigmoid(-self.rho_min_m / self.rho_scale_m);
        (sigmoid((rho_m - self.rho_min_m) / self.rho_scale_m) - floor) / (1.0 - floor)
    }

    /// `g₄` (eq. 3.17): `1 − σ((dist(Q) − 1)/s)`, a minimum constraint on the
    /// algebraic distance of eq. 3.5.
    pub fn g4_safety(&self, dist: Real) -> Real {
        sigmoid((1.0 - dist) / self.dist_scale)
    }

    /// The travel the tilting joint has on its nearer side at `q_t`:
    /// `min(q_t − q_min, q_max − q_t)` (negative outside the limits, `+∞`
    /// without limits).
    pub fn tilt_room(q_t: Real, limits: Option<JointLimits>) -> Real {
        limits.map_or(Real::INFINITY, |l| (q_t - l.min).min(l.max - q_t))
    }

    /// `g₅` (eq. 3.18, read as room on both sides): `σ((tilt_room −
    /// room(q_t))/s)`, see [`PoseConfig::tilt_room`].
    pub fn g5_tilt(&self, q_t: Real, limits: Option<JointLimits>) -> Real {
        let room = Self::tilt_room(q_t, limits);
        sigmoid((self.tilt_room_deg.to_radians() - room) / self.tilt_scale_deg.to_radians())
    }

    /// `g₆` (eq. 3.19): `Σᵢ (1 − σ((qᵢ − q_i,min)/s) + σ((qᵢ − q_i,max)/s))²`
    /// over the joints with limits (an unlimited joint adds 0).
    pub fn g6_limits(&self, q: &[Real], limits: &[Option<JointLimits>]) -> Real {
        let s = self.joint_scale_deg.to_radians();
        q.iter()
            .zip(limits)
            .filter_map(|(v, l)| l.map(|l| sigmoid((l.min - v) / s) + sigmoid((v - l.max) / s)))
            .map(|c| c * c)
            .sum()
    }
}

/// A Scale-Like Disc to identify (A§3.3): its centre `P̂ᵢ` and unit normal
/// `n⃗ᵢ`, world frame (the grid's). The normal points out of the surface,
/// toward the side it is seen from, as [`map::Disc`] normals do.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Target {
    /// Centre `P̂ᵢ`, world frame.
    pub centre: Point3,
    /// Unit normal `n⃗ᵢ`, world frame, out of the surface.
    pub normal: UnitVector3,
}

impl Target {
    /// A target at `centre` facing `normal` (any length but zero). Fails on a
    /// non-finite centre or a zero or non-finite normal.
    pub fn new(centre: Point3, normal: Vector3) -> Result<Self, PlanError> {
        let target_err = |field, got: String| PlanError::Target {
            field,
            expected: "finite coordinates (and a non-zero normal)",
            got,
        };
        if !geom::math::is_finite_point(&centre) {
            return Err(target_err("centre", format!("{centre:?}")));
        }
        let normal =
            geom::unit(normal).ok_or_else(|| target_err("normal", format!("{normal:?}")))?;
        Ok(Self { centre, normal })
    }

    /// The target of a disc from [`map::generate_discs`].
    pub fn from_disc(disc: &map::Disc) -> Self {
        Self {
            centre: disc.centre,
            normal: disc.normal,
        }
    }

    /// `Ok` when the centre is finite and the normal finite and of unit length
    /// (the fields are public, so a target may have been built by hand).
    pub fn check(&self) -> Result<(), PlanError> {
        Self::new(self.centre, self.normal.into_inner()).and_then(|t| {
            if (self.normal.norm() - 1.0).abs() <= 1e-9 {
                Ok(t)
            } else {
                Err(PlanError::Target {
                    field: "normal",
                    expected: "a unit vector",
                    got: format!("{:?}", self.normal.into_inner()),
                })
            }
        })?;
        Ok(())
    }
}

/// Where the centre ray meets the disc's plane (eq. 3.11–3.12).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlaneHit {
    /// `p_a`, world frame (eq. 3.11).
    pub point: Point3,
    /// `d = ‖p_a − p₁‖`, metres (eq. 3.12).
    pub d_m: Real,
    /// `ρ = ‖p_a − P̂ᵢ‖`, metres (the argument of eq. 3.16).
    pub rho_m: Real,
}

/// The view of a target from one scanner pose (eq. 3.11–3.13).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewGeometry {
    /// Angle of incidence `φ = arccos(−n⃗ᵢ · p₂)`, radians in `[0, π]` (eq.
    /// 3.13 with the normal toward the viewer).
    pub phi_rad: Real,
    /// The centre ray's intersection with the plane, `None` when the ray is
    /// parallel to it or meets it behind the scanner.
    pub hit: Option<PlaneHit>,
}

impl ViewGeometry {
    /// `d`, or `+∞` without an intersection.
    pub fn d_m(&self) -> Real {
        self.hit.map_or(Real::INFINITY, |h| h.d_m)
    }

    /// `ρ = ‖p_a − P̂ᵢ‖`, or `+∞` without an intersection.
    pub fn rho_m(&self) -> Real {
        self.hit.map_or(Real::INFINITY, |h| h.rho_m)
    }
}

/// Eq. 3.11–3.13 for the scanner at `world_from_scanner` (its `z` axis is the
/// centre ray, eq. 3.10) looking at `target`: `p₁` the scanner origin, `p₂`
/// the centre ray's unit direction, `p_a = p₁ + t p₂` with `t = n⃗ᵢ·(P̂ᵢ −
/// p₁) / n⃗ᵢ·p₂` (the sign of eq. 3.11 corrected), `d = ‖p_a − p₁‖` and `φ =
/// arccos(−n⃗ᵢ·p₂)`.
pub fn view_geometry(world_from_scanner: &Isometry3, target: &Target) -> ViewGeometry {
    let p1 = Point3::from(world_from_scanner.translation.vector);
    let p2 = world_from_scanner.rotation * Vector3::z();
    let n = target.normal.into_inner();
    let along = n.dot(&p2);
    let phi_rad = (-along).clamp(-1.0, 1.0).acos();
    let t = n.dot(&(target.centre - p1)) / along;
    let hit = (t.is_finite() && t > 0.0).then(|| {
        let point = p1 + p2 * t;
        PlaneHit {
            point,
            d_m: (point - p1).norm(),
            rho_m: (point - target.centre).norm(),
        }
    });
    ViewGeometry { phi_rad, hit }
}

/// Which LRC and manipulator constraints a pose meets (A§6.2.2 items 1–6).
#[allow(clippy::struct_excessive_bools)] // one flag per constraint of A§6.2.2, each reported
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Constraints {
    /// `φ < φ_max`.
    pub orientation: bool,
    /// `d_min ≤ d ≤ d_max` (false without an intersection).
    pub range: bool,
    /// `‖p_a − P̂ᵢ‖ ≤ ρ_min` (false without an intersection).
    pub accuracy: bool,
    /// `dist(Q) > 1`.
    pub safety: bool,
    /// The tilting joint has `tilt_room_deg` of travel on both sides.
    pub tilt_room: bool,
    /// Every joint within its limits.
    pub limits: bool,
}

impl Constraints {
    /// Every constraint holds: the viewpoint is valid.
    pub fn all(&self) -> bool {
        self.orientation
            && self.range
            && self.accuracy
            && self.safety
            && self.tilt_room
            && self.limits
    }
}

/// Everything pose selection knows about one joint vector.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseEvaluation {
    /// The joint vector `Q`.
    pub joints: Vec<Real>,
    /// `⁰T_s(Q)` placed in the world: the scanner frame (eq. 3.10), at `Q`
    /// clamped into the limits.
    pub world_from_scanner: Isometry3,
    /// `p_a`, `d`, `φ` (eq. 3.11–3.13).
    pub view: ViewGeometry,
    /// `dist(Q)` (eq. 3.5), resolved up to [`PoseSelector::dist_bound`].
    pub dist: Real,
    /// Travel of the tilting joint toward its nearer limit, radians.
    pub tilt_room_rad: Real,
    /// `g₁ … g₆` (eq. 3.14–3.19).
    pub g: [Real; 6],
    /// `g(Q) = Σ (gᵢ − ĝᵢ)²` (eq. 3.20).
    pub objective: Real,
    /// The constraints met.
    pub constraints: Constraints,
}

/// Why an LM run stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum PoseTermination {
    /// The gradient tolerance was reached (Table 6.1's second LM parameter).
    GradientTolerance,
    /// The objective or the step became too small to change (the crate's
    /// `ftol` / `xtol`).
    Converged,
    /// All residuals are zero.
    ResidualsZero,
    /// The iteration limit was reached (Table 6.1's first LM parameter).
    IterationLimit,
    /// No further improvement was possible in floating point, or the
    /// evaluation budget ran out.
    Stalled,
    /// The aim strayed beyond [`PoseConfig::give_up_scales`]: the sigmoid
    /// of `g₃` is flat there (at ten scales its slope is 5·10⁻⁵ of its
    /// largest), so nothing brings the aim back while the other costs are
    /// met. On bridge1's blast plan, with ten scales of 10 mm after five
    /// iterations, 4 of 5893 successful runs (of 26 638) would have been
    /// given up, and a third of all iterations are saved: failed runs
    /// drift off and end by the gradient test a dozen iterations later.
    GaveUp,
}

/// One LM run of a [`PoseSolution`].
#[derive(Clone, Debug, PartialEq)]
pub struct PoseRun {
    /// Which candidate it started from: 0 the given start, 1 the aim along
    /// the normal, 2–9 the tilted aims (module docs, "Starts").
    pub start_index: usize,
    /// The joint vector LM started from.
    pub start: Vec<Real>,
    /// LM iterations (Jacobian evaluations).
    pub iterations: usize,
    /// Why it stopped.
    pub termination: PoseTermination,
    /// `g(Q)` at its result.
    pub objective: Real,
    /// Its result met every constraint.
    pub valid: bool,
}

/// The selected pose and how it was found.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseSolution {
    /// The best result (see the module docs for "best").
    pub pose: PoseEvaluation,
    /// Index into `runs` of the run that found it.
    pub best_run: usize,
    /// Every LM run, in the order they ran (best-ranked start first).
    pub runs: Vec<PoseRun>,
}

impl PoseSolution {
    /// The selected joints.
    pub fn joints(&self) -> &[Real] {
        &self.pose.joints
    }

    /// Every constraint holds at the selected pose.
    pub fn valid(&self) -> bool {
        self.pose.constraints.all()
    }

    /// LM iterations of the run that found the selected pose.
    pub fn iterations(&self) -> usize {
        self.runs.get(self.best_run).map_or(0, |r| r.iterations)
    }
}

/// Stage Two pose selection for one placed robot ([`Safety`]).
#[derive(Clone, Debug)]
pub struct PoseSelector<'a> {
    safety: &'a Safety,
    config: PoseConfig,
    limits: Vec<Option<JointLimits>>,
    /// Index into `q` of the tilting joint.
    tilt: usize,
    /// Per actuated joint: the first link it moves (links from there on move).
    first_moved_link: Vec<usize>,
    link_count: usize,
    dist_bound: Real,
}

impl<'a> PoseSelector<'a> {
    /// A selector for the robot and placement of `safety`. Fails when `config`
    /// is out of range, the robot has no scanner, or `tilt_joint` is not one
    /// of its joints.
    pub fn new(safety: &'a Safety, config: PoseConfig) -> Result<Self, PlanError> {
        config.validate()?;
        let robot = safety.robot();
        if robot.scanner.is_none() {
            return Err(PlanError::Robot {
                robot: robot.name.clone(),
                message: "Stage Two pose selection needs a scanner".into(),
            });
        }
        let dof = robot.dof();
        if config.tilt_joint > dof {
            return Err(PlanError::config(
                "pose.tilt_joint",
                "one of the robot's joints (1-based)",
                format!("{} for a robot with {dof} joints", config.tilt_joint),
            ));
        }
        let first_moved_link = robot
            .joints
            .iter()
            .enumerate()
            .filter(|(_, j)| j.is_actuated())
            .map(|(i, _)| i + 1)
            .collect();
        let dist_bound = (1.0 + 10.0 * config.dist_scale).min(safety.cap());
        Ok(Self {
            safety,
            limits: robot.limits(),
            tilt: config.tilt_joint - 1,
            first_moved_link,
            link_count: robot.links.len(),
            dist_bound,
            config,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &PoseConfig {
        &self.config
    }

    /// `dist(Q)` is resolved up to this value: `1 + 10 · dist_scale`, at most
    /// [`Safety::cap`] (beyond it `g₄ < 5·10⁻⁵`).
    pub fn dist_bound(&self) -> Real {
        self.dist_bound
    }

    fn robot(&self) -> &Robot {
        self.safety.robot()
    }

    /// Every quantity and cost at `q` against `grid` and `target` (kinematic
    /// costs at `q` clamped into the limits, joint costs at `q`; see the module
    /// docs). Fails on a wrong joint count, non-finite joints or a bad target.
    pub fn evaluate(
        &self,
        grid: &OccupancyGrid,
        target: &Target,
        q: &[Real],
    ) -> Result<PoseEvaluation, PlanError> {
        target.check()?;
        self.robot().check_joints(q)?;
        let point = self.point(grid, target, q)?;
        Ok(self.evaluation(q, &point))
    }

    /// LM pose selection for `target` from `start` (clamped into the joint
    /// limits): the candidate starts (the given one and, when
    /// [`PoseConfig::starts`] > 1, the nine aimed ones) ranked by `g(Q)`, LM
    /// from the best ones in turn, the best result (module docs, "The
    /// solver"). A target out of reach gives a solution whose
    /// [`PoseSolution::valid`] is false, not an error. Fails on a wrong joint
    /// count, non-finite joints or a bad target.
    pub fn select(
        &self,
        grid: &OccupancyGrid,
        target: &Target,
        start: &[Real],
    ) -> Result<PoseSolution, PlanError> {
        target.check()?;
        self.robot().check_joints(start)?;
        let q0 = self.robot().clamp_to_limits(start);
        let mut candidates = vec![q0.clone()];
        if self.config.starts > 1 {
            let shoulder = self.shoulder_in_world(&q0)?;
            for ray in self.aim_rays(target, &shoulder) {
                candidates.push(self.aimed_start(&q0, target, &ray)?);
            }
        }
        let mut ranked = Vec::with_capacity(candidates.len());
        for (k, q) in candidates.into_iter().enumerate() {
            let objective = self.point(grid, target, &q)?.residuals.norm_squared();
            ranked.push((objective, k, q));
        }
        ranked.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        ranked.truncate(self.config.starts);
        let starts: Vec<(usize, Vec<Real>)> = ranked.into_iter().map(|(_, k, q)| (k, q)).collect();
        let mut runs = Vec::with_capacity(starts.len());
        let mut best: Option<(usize, PoseEvaluation)> = None;
        for (k, s) in starts {
            let (q, iterations, termination) = self.run_lm(grid, target, &s)?;
            let q = self.robot().clamp_to_limits(&q);
            let point = self.point(grid, target, &q)?;
            let eval = self.evaluation(&q, &point);
            runs.push(PoseRun {
                start_index: k,
                start: s,
                iterations,
                termination,
                objective: eval.objective,
                valid: eval.constraints.all(),
            });
            let better = best.as_ref().is_none_or(|(_, b)| {
                let (a_ok, b_ok) = (eval.constraints.all(), b.constraints.all());
                (a_ok && !b_ok) || (a_ok == b_ok && eval.objective < b.objective)
            });
            let valid = eval.constraints.all();
            if better {
                best = Some((runs.len() - 1, eval));
            }
            if valid && self.config.stop_at_valid {
                break;
            }
        }
        let (best_run, pose) =
            best.ok_or_else(|| PlanError::config("pose.starts", "at least 1", 0))?;
        Ok(PoseSolution {
            pose,
            best_run,
            runs,
        })
    }

    /// One LM run from `start`: the best joints evaluated, iterations, why it
    /// stopped.
    fn run_lm(
        &self,
        grid: &OccupancyGrid,
        target: &Target,
        start: &[Real],
    ) -> Result<(Vec<Real>, usize, PoseTermination), PlanError> {
        let x = DVector::from_column_slice(start);
        let point = self.point(grid, target, start)?;
        let objective = point.residuals.norm_squared();
        let problem = Problem {
            selector: self,
            grid,
            target,
            x: x.clone(),
            point: Some(point),
            jacobians: Cell::new(0),
            stop: Cell::new(None),
            best: (objective, x),
        };
        // The gradient test is ours (in `jacobian`), so the crate's
        // scale-invariant `gtol` is off.
        let lm = LevenbergMarquardt::new()
            .with_gtol(0.0)
            .with_scale_diag(false)
            .with_stepbound(STEP_BOUND)
            .with_patience(self.config.max_iterations.max(10));
        let (problem, report) = lm.minimize(problem);
        let iterations = problem.jacobians.get();
        let termination = problem.stop.get().unwrap_or(match report.termination {
            TerminationReason::Converged { .. } => PoseTermination::Converged,
            TerminationReason::ResidualsZero => PoseTermination::ResidualsZero,
            _ => PoseTermination::Stalled,
        });
        Ok((problem.best.1.as_slice().to_vec(), iterations, termination))
    }

    /// The residuals and what they were computed from, at `x`.
    fn point(&self, grid: &OccupancyGrid, target: &Target, x: &[Real]) -> Result<Point, PlanError> {
        let qc = self.robot().clamp_to_limits(x);
        // Each link measured up to the bound plus the margin, so the
        // differences know which links cannot come within the bound.
        let reach = self.dist_bound + DIST_MARGIN;
        let mut link_dist = vec![reach; self.link_count];
        for d in link_dist.iter_mut().skip(1) {
            *d = reach.min(self.safety.cap());
        }
        let frames = self.robot().forward_kinematics(&qc)?;
        for (k, e) in self.safety.posed_links_in(&frames) {
            if let Some(d) = link_dist.get_mut(k).filter(|_| k >= 1) {
                *d = self.safety.ellipsoid_dist(grid, &e, *d, Real::NEG_INFINITY);
            }
        }
        // still[k] = min over links 1..k, up to the bound (link 0 never counts).
        let mut still = vec![self.dist_bound; self.link_count + 1];
        for k in 2..=self.link_count {
            still[k] = still[k - 1].min(link_dist[k - 1]);
        }
        let dist = still[self.link_count];
        let (world_from_scanner, view) = self.view(target, &frames)?;
        Ok(Point {
            residuals: self.residuals(x, target, &view, dist),
            world_from_scanner,
            view,
            dist,
            link_dist,
            still,
        })
    }

    /// The scanner pose in the world and the view of `target` with the
    /// link frames `frames` (the forward kinematics at the joints).
    fn view(
        &self,
        target: &Target,
        frames: &[Isometry3],
    ) -> Result<(Isometry3, ViewGeometry), PlanError> {
        let base_from_scanner =
            self.robot()
                .scanner_pose_in(frames)?
                .ok_or_else(|| PlanError::Robot {
                    robot: self.robot().name.clone(),
                    message: "Stage Two pose selection needs a scanner".into(),
                })?;
        let world_from_scanner = self.safety.world_from_base() * base_from_scanner;
        Ok((
            world_from_scanner,
            view_geometry(&world_from_scanner, target),
        ))
    }

    /// `rᵢ = gᵢ − ĝᵢ` from the kinematic quantities and the raw joints `x`,
    /// with `r₃` written as the 2-vector `r₃ u` (components 2 and 3), `u` the
    /// unit vector in the disc's plane from `P̂ᵢ` toward `p_a` (the plane's
    /// first axis without an intersection). `Σ` of the squares is eq. 3.20's
    /// `g(Q)` unchanged; where `ρ = ‖p_a − P̂ᵢ‖` has a cone point at a perfect
    /// aim, `r₃ u ≈ g₃′(0) (p_a − P̂ᵢ)` is smooth (module docs).
    fn residuals(&self, x: &[Real], target: &Target, view: &ViewGeometry, dist: Real) -> Residuals {
        let g = self.costs(x, view, dist);
        let r = |i: usize| g[i] - self.config.desired[i];
        let frame = geom::PlaneFrame::new(target.centre, target.normal);
        let (e1, e2) = (frame.u.into_inner(), frame.v.into_inner());
        let (u1, u2) = match view.hit {
            Some(h) if h.rho_m > 0.0 => {
                let v = (h.point - target.centre) / h.rho_m;
                (v.dot(&e1), v.dot(&e2))
            }
            _ => (1.0, 0.0),
        };
        Residuals::from([r(0), r(1), r(2) * u1, r(2) * u2, r(3), r(4), r(5)])
    }

    fn costs(&self, x: &[Real], view: &ViewGeometry, dist: Real) -> [Real; 6] {
        let c = &self.config;
        [
            c.g1_orientation(view.phi_rad),
            c.g2_range(view.d_m()),
            c.g3_accuracy(view.rho_m()),
            c.g4_safety(dist),
            c.g5_tilt(x[self.tilt], self.limits[self.tilt]),
            c.g6_limits(x, &self.limits),
        ]
    }

    fn evaluation(&self, q: &[Real], point: &Point) -> PoseEvaluation {
        let c = &self.config;
        let view = point.view;
        let g = self.costs(q, &view, point.dist);
        let tilt_room_rad = PoseConfig::tilt_room(q[self.tilt], self.limits[self.tilt]);
        let d = view.d_m();
        let constraints = Constraints {
            orientation: view.phi_rad < c.phi_max_deg.to_radians(),
            range: d >= c.d_min_m && d <= c.d_max_m,
            accuracy: view.rho_m() <= c.rho_min_m,
            safety: point.dist > 1.0,
            tilt_room: tilt_room_rad >= c.tilt_room_deg.to_radians(),
            limits: self.robot().within_limits(q),
        };
        PoseEvaluation {
            joints: q.to_vec(),
            world_from_scanner: point.world_from_scanner,
            view,
            dist: point.dist,
            tilt_room_rad,
            g,
            objective: point.residuals.norm_squared(),
            constraints,
        }
    }

    /// The Jacobian of the residuals at `x` (whose evaluation is `at`) by
    /// forward differences, backward where the step would pass the upper
    /// joint limit.
    fn jacobian_at(
        &self,
        grid: &OccupancyGrid,
        target: &Target,
        x: &[Real],
        at: &Point,
    ) -> Result<Jacobian, PlanError> {
        let h = self.config.difference_step_rad;
        let mut out = Jacobian::zeros(x.len());
        let mut xp = x.to_vec();
        for j in 0..x.len() {
            let step = match self.limits[j] {
                Some(l) if x[j] + h > l.max => -h,
                _ => h,
            };
            xp[j] = x[j] + step;
            let r = self.residuals_moved(grid, target, &xp, j, at)?;
            xp[j] = x[j];
            out.set_column(j, &((r - at.residuals) / step));
        }
        Ok(out)
    }

    /// The residuals at `xp`, which differs from the point `at` in joint `j`
    /// only by a difference step. Links before the joint do not move; a moved
    /// link that was beyond the bound plus the margin cannot come within the
    /// bound by one step (see `DIST_MARGIN`), so only the others are measured.
    fn residuals_moved(
        &self,
        grid: &OccupancyGrid,
        target: &Target,
        xp: &[Real],
        j: usize,
        at: &Point,
    ) -> Result<Residuals, PlanError> {
        let qc = self.robot().clamp_to_limits(xp);
        let frames = self.robot().forward_kinematics(&qc)?;
        let first = self.first_moved_link[j].min(self.link_count);
        let mut dist = at.still[first];
        if (first..self.link_count).any(|k| at.link_dist[k] < self.dist_bound + DIST_MARGIN) {
            dist = dist.min(self.safety.cap());
            for (k, e) in self.safety.posed_links_in(&frames) {
                if (first..self.link_count).contains(&k)
                    && at.link_dist[k] < self.dist_bound + DIST_MARGIN
                {
                    dist = self
                        .safety
                        .ellipsoid_dist(grid, &e, dist, Real::NEG_INFINITY);
                }
            }
        }
        let (_, view) = self.view(target, &frames)?;
        Ok(self.residuals(xp, target, &view, dist))
    }

    /// The origin of link 1's frame (the shoulder of an arm), world frame.
    fn shoulder_in_world(&self, q: &[Real]) -> Result<Point3, PlanError> {
        let frames = self.robot().forward_kinematics(q)?;
        let base_from_link1 = frames.get(1).copied().unwrap_or_else(Isometry3::identity);
        Ok(self.safety.world_from_base() * Point3::from(base_from_link1.translation.vector))
    }

    /// The aimed ray directions (world, unit, from the scanner toward the
    /// target): along the normal, then [`AIM_TURNS_DEG`] around it at
    /// `φ_max/2`, the turns measured from the direction toward the shoulder.
    fn aim_rays(&self, target: &Target, shoulder: &Point3) -> Vec<Vector3> {
        let n = target.normal.into_inner();
        let frame = geom::PlaneFrame::with_u_axis(
            target.centre,
            target.normal,
            &(shoulder - target.centre),
        );
        let (u, w) = (frame.u.into_inner(), frame.v.into_inner());
        let beta = 0.5 * self.config.phi_max_deg.to_radians();
        std::iter::once(-n)
            .chain(AIM_TURNS_DEG.iter().map(|psi| {
                let psi = psi.to_radians();
                let side = u * psi.cos() + w * psi.sin();
                -(n * beta.cos() + side * beta.sin())
            }))
            .collect()
    }

    /// Damped Gauss–Newton inverse kinematics from `q0` (within the limits)
    /// toward a view of `target` along `ray` (world, unit): the centre ray
    /// through `P̂ᵢ` and along `ray`, the range inside the middle of `[d_min,
    /// d_max]`, the tilting joint with its room plus a margin, every joint a
    /// margin inside its limits; the roll about the ray is free and obstacles
    /// are ignored (LM sees them). At most 100 iterations, each step at most
    /// 0.2 rad; returns the last iterate, converged or not. With
    /// [`PoseConfig::aim_backtracking`], a step that raises the sum of
    /// squares is taken back and the bound halved, the run ends when a step
    /// lowers it by a millionth or less or the bound falls below 1e-4 rad,
    /// and returns the last pose whose cost did not rise.
    fn aimed_start(
        &self,
        q0: &[Real],
        target: &Target,
        ray: &Vector3,
    ) -> Result<Vec<Real>, PlanError> {
        const ITERATIONS: usize = 100;
        const DAMPING: Real = 0.03;
        /// Metres per radian: weighs direction, tilt and limit rows against
        /// the aiming rows (about the arm's wrist-to-scanner lever).
        const LEVER_M: Real = 0.3;
        const MAX_STEP_RAD: Real = 0.2;
        /// The step bound below which a run that keeps raising the cost
        /// stops.
        const MIN_BOUND_RAD: Real = 1e-4;
        /// A step that lowers the cost by at most this fraction ends the
        /// run.
        const COST_TOLERANCE: Real = 1e-6;
        const MARGIN_DEG: Real = 10.0;
        let robot = self.robot();
        let Some(mount) = robot.scanner else {
            return Ok(q0.to_vec());
        };
        let c = &self.config;
        let base_from_world = self.safety.world_from_base().inverse();
        let centre = base_from_world * target.centre;
        let ray = base_from_world.rotation * ray;
        let span = c.d_max_m - c.d_min_m;
        let (d_lo, d_hi) = (c.d_min_m + 0.15 * span, c.d_min_m + 0.6 * span);
        let margin = MARGIN_DEG.to_radians();
        let room_goal = c.tilt_room_deg.to_radians() + margin;
        let point_in_link = Point3::from(mount.link_from_scanner.translation.vector);
        let n = q0.len();
        let mut q = q0.to_vec();
        let mut frames = Vec::with_capacity(robot.links.len());
        let mut jac = Matrix6xX::zeros(n);
        let mut row = vec![0.0; n];
        // The normal equations, filled afresh each iteration.
        let mut normal = DMatrix::<Real>::zeros(n, n);
        let mut gradient = DVector::<Real>::zeros(n);
        // The step's bound, halved each time a step raised the cost (the
        // step is taken back), and the last pose whose cost did not rise.
        let mut bound = MAX_STEP_RAD;
        let mut kept: Option<(Vec<Real>, Real)> = None;
        for _ in 0..ITERATIONS {
            robot.fk_into(&q, &mut frames)?;
            let Some(base_from_link) = frames.get(mount.link.index()) else {
                break;
            };
            robot.jacobian_into(&frames, mount.link, &point_in_link, &mut jac);
            let scanner = base_from_link * mount.link_from_scanner;
            let p = Point3::from(scanner.translation.vector);
            let a = scanner.rotation * Vector3::z();
            let w = centre - p;
            let s = w.dot(&a);
            normal.fill(0.0);
            normal.fill_diagonal(DAMPING * DAMPING);
            gradient.fill(0.0);
            let mut cost = 0.0;
            let mut add = |row: &[Real], r: Real| {
                cost += r * r;
                for (i, gi) in row.iter().enumerate() {
                    gradient[i] += gi * r;
                    for (k, gk) in row.iter().enumerate() {
                        normal[(i, k)] += gi * gk;
                    }
                }
            };
            // Per joint: d(p) = v_j, d(a) = ω_j × a.
            let dv = |j: usize| Vector3::new(jac[(0, j)], jac[(1, j)], jac[(2, j)]);
            let da = |j: usize| Vector3::new(jac[(3, j)], jac[(4, j)], jac[(5, j)]).cross(&a);
            let ds = |j: usize| -dv(j).dot(&a) + w.dot(&da(j));
            // Aim: the offset of P̂ from the ray, e = w − s a.
            let e = w - a * s;
            for axis in 0..3 {
                for (j, g) in row.iter_mut().enumerate() {
                    let de = -dv(j) - a * ds(j) - da(j) * s;
                    *g = de[axis];
                }
                add(&row, e[axis]);
            }
            // Direction: LEVER (a − ray).
            for axis in 0..3 {
                for (j, g) in row.iter_mut().enumerate() {
                    *g = LEVER_M * da(j)[axis];
                }
                add(&row, LEVER_M * (a[axis] - ray[axis]));
            }
            // Range: s inside [d_lo, d_hi].
            let r = s - s.clamp(d_lo, d_hi);
            if r != 0.0 {
                for (j, g) in row.iter_mut().enumerate() {
                    *g = ds(j);
                }
                add(&row, r);
            }
            // Tilt room and limit margins.
            for (j, limits) in self.limits.iter().enumerate() {
                let Some(l) = limits else { continue };
                row.fill(0.0);
                if j == self.tilt {
                    let (room, slope) = if q[j] - l.min < l.max - q[j] {
                        (q[j] - l.min, 1.0)
                    } else {
                        (l.max - q[j], -1.0)
                    };
                    if room < room_goal {
                        row[j] = -LEVER_M * slope;
                        add(&row, LEVER_M * (room_goal - room));
                    }
                } else if q[j] > l.max - margin || q[j] < l.min + margin {
                    let edge = if q[j] > l.max - margin {
                        l.max - margin
                    } else {
                        l.min + margin
                    };
                    row[j] = LEVER_M;
                    add(&row, LEVER_M * (q[j] - edge));
                }
            }
            let backtrack = self.config.aim_backtracking;
            if backtrack
                && let Some((back, was)) = &kept
                && cost > *was
            {
                q.clone_from(back);
                bound *= 0.5;
                if bound < MIN_BOUND_RAD {
                    break;
                }
                continue;
            }
            if backtrack {
                let settled = kept
                    .as_ref()
                    .is_some_and(|(_, was)| was - cost <= COST_TOLERANCE * was);
                kept = Some((q.clone(), cost));
                if settled {
                    break;
                }
            }
            let Some(mut step) = solve_normal(&normal, &gradient) else {
                break;
            };
            let largest = step.amax();
            if !largest.is_finite() {
                break;
            }
            if largest > bound {
                step *= bound / largest;
            }
            for (v, d) in q.iter_mut().zip(step.iter()) {
                *v += d;
            }
            q = robot.clamp_to_limits(&q);
            if largest < 1e-7 {
                break;
            }
        }
        Ok(kept.map_or(q, |(q, _)| q))
    }
}

/// `x` with `normal · x = −gradient` by Cholesky (`None` when `normal` is
/// not positive definite). Six unknowns (every arm we ship) are solved on
/// the stack; nalgebra's decomposition is the same generic code for both,
/// so the numbers are too.
fn solve_normal(normal: &DMatrix<Real>, gradient: &DVector<Real>) -> Option<DVector<Real>> {
    if normal.nrows() == 6 && normal.ncols() == 6 && gradient.len() == 6 {
        let m = nalgebra::Matrix6::from_iterator(normal.iter().copied());
        let g = nalgebra::Vector6::from_iterator(gradient.iter().copied());
        let x = m.cholesky()?.solve(&(-g));
        return Some(DVector::from_column_slice(x.as_slice()));
    }
    Some(normal.clone().cholesky()?.solve(&(-gradient)))
}

/// Links are measured at the evaluated point up to `dist_bound +
/// DIST_MARGIN`. A link beyond that is skipped in the differences: one step
/// of at most 1e-4 rad changes a link's algebraic distance by far less than
/// 0.5 (for an ellipsoid of a few centimetres at a metre's reach the rate is
/// a few hundred per radian), so it stays beyond the bound and `g₄` does not
/// see it.
const DIST_MARGIN: Real = 0.5;

/// LM's first trust region is `STEP_BOUND · ‖Q‖` radians (joint space, no
/// rescaling: every parameter is an angle): a tenth, so the first step cannot
/// swing the arm across the workspace (the crate's default, 100 with column
/// scaling, spent a dozen evaluations shrinking the region on every run).
const STEP_BOUND: Real = 0.1;

/// Turns (degrees) of the tilted aims around the normal, from the direction
/// toward the robot's shoulder: toward it, to either side, away, then the
/// diagonals.
const AIM_TURNS_DEG: [Real; 8] = [0.0, 90.0, -90.0, 180.0, 45.0, -45.0, 135.0, -135.0];

/// The residual vector: `r₁, r₂`, `r₃` as a 2-vector in the disc's plane,
/// `r₄, r₅, r₆` (see [`PoseSelector::residuals`]).
type Residuals = SVector<Real, 7>;
/// Its Jacobian, 7 × dof.
type Jacobian = OMatrix<Real, U7, Dyn>;

/// One evaluation of the residuals and what the Jacobian reuses.
#[derive(Clone, Debug)]
struct Point {
    residuals: Residuals,
    world_from_scanner: Isometry3,
    view: ViewGeometry,
    /// `dist(Q)` up to the bound.
    dist: Real,
    /// Per link (index 0 unused), its own `dist` up to the bound plus
    /// [`DIST_MARGIN`].
    link_dist: Vec<Real>,
    /// `still[k]`: `dist` over links `1..k` only (those that do not move when
    /// a joint moving link `k` onward moves), up to the bound.
    still: Vec<Real>,
}

/// The least-squares problem of one LM run.
struct Problem<'s, 'a> {
    selector: &'s PoseSelector<'a>,
    grid: &'s OccupancyGrid,
    target: &'s Target,
    x: DVector<Real>,
    /// The evaluation at `x` (`None` when it failed).
    point: Option<Point>,
    /// Jacobians computed so far (one per LM iteration).
    jacobians: Cell<usize>,
    /// Set when this problem ended the run (iteration limit, gradient test).
    stop: Cell<Option<PoseTermination>>,
    /// The lowest objective evaluated and where.
    best: (Real, DVector<Real>),
}

impl LeastSquaresProblem<Real, U7, Dyn> for Problem<'_, '_> {
    type ResidualStorage = Owned<Real, U7>;
    type JacobianStorage = Owned<Real, U7, Dyn>;
    type ParameterStorage = Owned<Real, Dyn>;

    fn set_params(&mut self, x: &DVector<Real>) {
        self.x.copy_from(x);
        self.point = self
            .selector
            .point(self.grid, self.target, self.x.as_slice())
            .ok()
            .filter(|p| p.residuals.iter().all(|v| v.is_finite()));
        if let Some(p) = &self.point {
            let objective = p.residuals.norm_squared();
            if objective < self.best.0 {
                self.best = (objective, self.x.clone());
            }
        }
    }

    fn params(&self) -> DVector<Real> {
        self.x.clone()
    }

    fn residuals(&self) -> Option<Residuals> {
        self.point.as_ref().map(|p| p.residuals)
    }

    fn jacobian(&self) -> Option<Jacobian> {
        let config = &self.selector.config;
        let point = self.point.as_ref()?;
        if self.jacobians.get() >= config.max_iterations {
            self.stop.set(Some(PoseTermination::IterationLimit));
            return None;
        }
        self.jacobians.set(self.jacobians.get() + 1);
        if config.give_up_scales > 0.0 && self.jacobians.get() >= GIVE_UP_AFTER {
            let miss = point.view.hit.map_or(Real::INFINITY, |h| h.rho_m);
            if miss > config.give_up_scales * config.rho_scale_m {
                self.stop.set(Some(PoseTermination::GaveUp));
                return None;
            }
        }
        let jacobian = self
            .selector
            .jacobian_at(self.grid, self.target, self.x.as_slice(), point)
            .ok()?;
        // ∇g = 2 Jᵀ r for g = Σ rᵢ² (eq. 3.20).
        let gradient = (jacobian.transpose() * point.residuals * 2.0).amax();
        if gradient <= config.gradient_tolerance {
            self.stop.set(Some(PoseTermination::GradientTolerance));
            return None;
        }
        Some(jacobian)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The stack solve of six unknowns gives the heap solve's numbers to
    /// the bit, on random damped normal equations `JᵀJ + λ²I` (and a
    /// matrix that is not positive definite is refused by both).
    #[test]
    fn six_unknowns_on_the_stack_match_the_heap_to_the_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..500 {
            let j = DMatrix::<Real>::from_fn(9, 6, |_, _| rng.random_range(-1.0..1.0));
            let mut normal = j.transpose() * &j;
            for d in 0..6 {
                normal[(d, d)] += 0.03 * 0.03;
            }
            let gradient = DVector::<Real>::from_fn(6, |_, _| rng.random_range(-1.0..1.0));
            let heap = normal.clone().cholesky().unwrap().solve(&(-&gradient));
            let stack = solve_normal(&normal, &gradient).unwrap();
            assert_eq!(heap.as_slice(), stack.as_slice());
        }
        let not_definite = DMatrix::<Real>::from_diagonal_element(6, 6, -1.0);
        assert!(not_definite.clone().cholesky().is_none());
        assert!(solve_normal(&not_definite, &DVector::zeros(6)).is_none());
    }
}
