//! Blast poses (Paul App. A.1): a joint configuration from which a
//! grit-blasting nozzle on the robot's flange hits a disc target within the
//! tool's limits, by Levenberg–Marquardt on the sigmoid costs of eq. A.1–A.5.
//!
//! Eq. A.1–A.5 are Stage Two's `g₁…g₄` and `g₆` (A§3.3, eq. 3.14–3.17 and
//! 3.19) with the blast stream in place of the scanner's centre ray and the
//! tool's angle `φ_max`, stream length `[d_min, d_max]` and aim tolerance
//! `ρ_min` in place of the LRC's; there is no tilt sweep (Stage Two's `g₅`).
//! So a [`BlastPoses`] is a [`PoseSelector`] on a copy of the robot whose
//! "scanner" is the nozzle ([`BlastTool::mount`]) with its `g₅` switched off
//! (no tilt room asked for). [`BlastPoses::measure`] re-measures a pose from
//! the nozzle's forward kinematics and [`Safety::dist`], independently of the
//! optimiser.
//!
//! The nozzle is part of the arm for `dist(Q)` (eq. A.4): the tool link's
//! bounding ellipsoid is replaced by one enclosing both the old ellipsoid
//! and the nozzle's capsule ([`BlastTool::robot_with_nozzle`]), so the
//! safety rule of eq. 3.5, ellipsoids against occupied and unknown voxels,
//! covers the nozzle too.

use geom::{Isometry3, Real};
use map::OccupancyGrid;
use plan::{PlanConfig, PlanError, PoseConfig, PoseSelector, PoseSolution, Safety, Target};
use robot::{ReachBound, Robot, ScannerMount};
use serde::{Deserialize, Serialize};

/// A grit-blasting nozzle on the robot's tool link (its flange) and the
/// limits of an effective blast (App. A.1, Fig. A.1). The thesis gives no
/// values; the defaults are ours: a nozzle 0.15 m long on the flange axis,
/// φ < 30°, a stream of 0.2–0.5 m, aim within 15 mm (Stage Two's `ρ_min`),
/// and a nozzle capsule of radius 30 mm (a blast nozzle with its hose
/// fitting is a few centimetres thick).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BlastTool {
    /// Nozzle tip in the tool-link frame, metres; the stream leaves it along
    /// the nozzle frame's `z` axis.
    #[serde(deserialize_with = "geom::exact::array")]
    pub translation_m: [Real; 3],
    /// Nozzle orientation in the tool-link frame: roll, pitch, yaw, degrees
    /// (URDF convention).
    #[serde(deserialize_with = "geom::exact::array")]
    pub rpy_deg: [Real; 3],
    /// Largest angle between the stream and the surface normal, `φ_max`.
    pub phi_max_deg: Real,
    /// Shortest effective stream, `d_min`, metres.
    pub d_min_m: Real,
    /// Longest effective stream, `d_max`, metres.
    pub d_max_m: Real,
    /// Largest distance from where the stream hits to the disc centre,
    /// `ρ_min`, metres.
    pub rho_min_m: Real,
    /// Radius of the nozzle's collision capsule, metres: the segment from
    /// the tool frame's origin (the flange) to the nozzle tip, this thick.
    pub nozzle_radius_m: Real,
    /// Scale of the aim cost's sigmoid (`g₃` of eq. A.3), metres. Ours:
    /// 10 mm, a miss by `ρ_min` costs 0.5, by 5 cm 0.97, and the cost still
    /// pulls at 10 cm. Stage Two's 3 mm saturates within 4 cm of the
    /// centre; an LM run that strays further while it fixes the angle and
    /// the range has nothing to bring it back (on bridge1's run, most failed
    /// runs ended 0.26–0.78 m off with every other limit met). With 10 mm
    /// the plan of that run has poses for 5898 discs instead of 5515 (five
    /// first starts; 5896 with [`crate::BLAST_STARTS`]), in less time.
    pub aim_scale_m: Real,
}

impl Default for BlastTool {
    fn default() -> Self {
        Self {
            translation_m: [0.0, 0.0, 0.15],
            rpy_deg: [0.0; 3],
            phi_max_deg: 30.0,
            d_min_m: 0.2,
            d_max_m: 0.5,
            rho_min_m: 0.015,
            nozzle_radius_m: 0.03,
            aim_scale_m: 0.01,
        }
    }
}

impl BlastTool {
    /// Check every field.
    pub fn validate(&self) -> Result<(), PlanError> {
        let bad = |field: &'static str, expected: &'static str, got: String| PlanError::Config {
            field,
            expected,
            got,
        };
        if !self
            .translation_m
            .iter()
            .chain(&self.rpy_deg)
            .all(|v| v.is_finite())
        {
            return Err(bad(
                "tool.translation_m / tool.rpy_deg",
                "finite values",
                format!("{:?} / {:?}", self.translation_m, self.rpy_deg),
            ));
        }
        // The capsule is round about the tip, which stands at least d_min
        // from the surface: at d_min or thicker it touches the surface at
        // every pose (a 1 m nozzle searched for 191 s and planned 0 discs).
        if !(self.nozzle_radius_m.is_finite()
            && self.nozzle_radius_m > 0.0
            && self.nozzle_radius_m < self.d_min_m)
        {
            return Err(bad(
                "tool.nozzle_radius_m",
                "a positive radius less than tool.d_min_m",
                self.nozzle_radius_m.to_string(),
            ));
        }
        if !(self.aim_scale_m.is_finite() && self.aim_scale_m > 0.0) {
            return Err(bad(
                "tool.aim_scale_m",
                "a positive finite length",
                self.aim_scale_m.to_string(),
            ));
        }
        // The limits are checked with the pose configuration they become.
        self.pose_config(&PoseConfig::default()).validate()
    }

    /// The nozzle as the "scanner" of `robot`: on its tool link, at the tool
    /// frame followed by this offset.
    pub fn mount(&self, robot: &Robot) -> ScannerMount {
        let (link, link_from_tool) = robot.tool;
        let deg = self.rpy_deg.map(Real::to_radians);
        ScannerMount {
            link,
            link_from_scanner: link_from_tool
                * geom::math::isometry_from_xyz_rpy(self.translation_m, deg),
        }
    }

    /// The nozzle's collision capsule in the tool link's frame: from the
    /// tool frame's origin (the flange) to the nozzle tip, of radius
    /// [`BlastTool::nozzle_radius_m`].
    pub fn nozzle_capsule(&self, robot: &Robot) -> geom::Capsule {
        let flange = robot.tool.1;
        let tip = self.mount(robot).link_from_scanner;
        geom::Capsule::new(
            geom::Point3::from(flange.translation.vector),
            geom::Point3::from(tip.translation.vector),
            self.nozzle_radius_m,
        )
    }

    /// `robot` carrying this nozzle: its "scanner" is the nozzle
    /// ([`BlastTool::mount`]) and the tool link's bounding ellipsoid is the
    /// smallest one enclosing both the link's old ellipsoid and the nozzle's
    /// capsule (each represented by points whose convex hull contains it,
    /// [`robot::bounds::capsule_sample_points`]; the old ellipsoid as the
    /// image of a sampled unit sphere). Fails when no ellipsoid can be fitted.
    pub fn robot_with_nozzle(&self, robot: &Robot) -> Result<Robot, PlanError> {
        let mut out = robot.clone();
        out.scanner = Some(self.mount(robot));
        let link = robot.tool.0.index();
        let capsule = self.nozzle_capsule(robot);
        let mut points = robot::bounds::capsule_sample_points(&capsule);
        if let Some(old) = robot.links.get(link).and_then(|l| l.ellipsoid) {
            let origin = geom::Point3::origin();
            let sphere =
                robot::bounds::capsule_sample_points(&geom::Capsule::new(origin, origin, 1.0));
            points.extend(
                sphere
                    .iter()
                    .map(|p| old.pose * geom::Point3::from(p.coords.component_mul(&old.radii))),
            );
        }
        let fitted =
            robot::bounds::enclosing_ellipsoid(&points).ok_or_else(|| PlanError::Robot {
                robot: robot.name.clone(),
                message: "cannot fit an ellipsoid around the tool link and the nozzle".into(),
            })?;
        let slot = out.links.get_mut(link).ok_or_else(|| PlanError::Robot {
            robot: robot.name.clone(),
            message: format!("no tool link {link}"),
        })?;
        slot.ellipsoid = Some(fitted);
        Ok(out)
    }

    /// `base`'s LM settings with this tool's limits, its aim scale and no
    /// tilt room.
    pub fn pose_config(&self, base: &PoseConfig) -> PoseConfig {
        PoseConfig {
            phi_max_deg: self.phi_max_deg,
            d_min_m: self.d_min_m,
            d_max_m: self.d_max_m,
            rho_min_m: self.rho_min_m,
            tilt_room_deg: 0.0,
            rho_scale_m: self.aim_scale_m,
            ..base.clone()
        }
    }
}

/// The distance from the point at `v` (relative to a disc centre with unit
/// normal `n`) to the tip positions from which a stream through the centre
/// meets the disc at an angle below `phi_max` (radians) after a length in
/// `[d_min, d_max]`: the solid sector `{u d : ∠(u, n) ≤ φ_max, d ∈ [d_min,
/// d_max]}`. Within the cone the distance is radial; outside it, it is the
/// distance to the cone's boundary segment in the plane of `v` and `n` (the
/// sector's arcs end on that segment, so they are never nearer). The same
/// sector holds the scanner positions whose centre ray meets a Stage Two
/// target within the LRC's constraints (`sim::material_oracle` uses it so).
pub fn tip_gap(
    v: geom::Vector3,
    n: geom::Vector3,
    phi_max: Real,
    d_min: Real,
    d_max: Real,
) -> Real {
    let len = v.norm();
    let along = v.dot(&n);
    if along >= len * phi_max.cos() {
        return (d_min - len).max(len - d_max).max(0.0);
    }
    let side = v - n * along;
    let side_len = side.norm();
    let w = if side_len > 0.0 {
        side / side_len
    } else {
        // `v` straight behind the disc: every boundary ray is as near.
        n.cross(&geom::Vector3::x())
            .try_normalize(1e-9)
            .or_else(|| n.cross(&geom::Vector3::y()).try_normalize(1e-9))
            .unwrap_or_else(geom::Vector3::x)
    };
    let u = n * phi_max.cos() + w * phi_max.sin();
    let t = v.dot(&u).clamp(d_min, d_max);
    (v - u * t).norm()
}

/// The wrist of `robot` (carrying the nozzle `mount`, from `tool`):
/// where the origin of [`Robot::fixed_point_link`]'s link can be, its offset
/// along the nozzle's stream from the tip, and its distance from the
/// nozzle's axis. `None` when that point stands `d_min` or more in front
/// of the tip (its positions would not form a sector of the same kind) or
/// the arm has no bound.
fn wrist_reach(
    robot: &Robot,
    mount: &ScannerMount,
    tool: &BlastTool,
) -> Option<(ReachBound, Real, Real)> {
    let link = robot.fixed_point_link(mount.link)?;
    let frames = robot.forward_kinematics(&vec![0.0; robot.dof()]).ok()?;
    let nozzle = frames[mount.link.index()] * mount.link_from_scanner;
    let p = nozzle.inverse() * geom::Point3::from(frames[link.index()].translation.vector);
    // The sector's stream lengths for the wrist, `d − along`, must stay
    // positive for it to be the same kind of sector.
    if tool.d_min_m - p.z <= 0.0 {
        return None;
    }
    let bound = robot.reach_bound(link, &Isometry3::identity(), REACH_SAMPLES)?;
    Some((bound, p.z, p.x.hypot(p.y)))
}

/// A blast pose re-measured from the nozzle's forward kinematics.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlastMeasure {
    /// Angle between the stream and the disc normal, degrees.
    pub phi_deg: Real,
    /// Stream length from the nozzle to the disc's plane, metres.
    pub d_m: Real,
    /// Distance from where the stream meets the plane to the disc centre, m.
    pub aim_error_m: Real,
    /// `dist(Q)` of eq. 3.5 (capped).
    pub dist: Real,
    /// Every limit holds: `φ < φ_max`, `d ∈ [d_min, d_max]`, aim error
    /// `≤ ρ_min`, `dist(Q) > 1`.
    pub valid: bool,
}

/// Blast-pose selection for one robot, placement and tool.
#[derive(Debug)]
pub struct BlastPoses {
    safety: Safety,
    config: PoseConfig,
    tool: BlastTool,
    /// Where the nozzle tip can be at all, world frame (`None`: unbounded).
    reach: Option<ReachBound>,
    /// Where the arm's wrist can be, and where it stands from the tip.
    wrist: Option<WristReach>,
}

/// A point fixed to the nozzle behind its tip ([`Robot::fixed_point_link`]:
/// a spherical wrist's centre) and where it can be: with the nozzle's
/// direction known, a tip in front of a disc puts this point farther back
/// along the stream, which the arm may not reach although it reaches the
/// tip.
#[derive(Clone, Debug)]
struct WristReach {
    /// Where the point can be, world frame.
    bound: ReachBound,
    /// Its offset along the stream from the tip, metres (negative: behind).
    along_m: Real,
    /// Its distance from the nozzle's axis, metres.
    side_m: Real,
}

/// First-joint samples of the nozzle's reach bound: 1° steps over a
/// 360° joint (the VM-6083's 340° range: chords of 3 mm at its shoulder).
const REACH_SAMPLES: usize = 360;

impl BlastPoses {
    /// The nozzle `tool` on `robot` ([`BlastTool::robot_with_nozzle`]: its
    /// scanner, if any, is replaced by the nozzle, and the nozzle is inside
    /// the tool link's ellipsoid), placed at `world_from_base`, with `plan`'s
    /// safety settings and joint `weights`, and `pose`'s LM settings.
    pub fn new(
        robot: &Robot,
        world_from_base: Isometry3,
        plan: &PlanConfig,
        weights: Vec<Real>,
        pose: &PoseConfig,
        tool: BlastTool,
    ) -> Result<Self, PlanError> {
        tool.validate()?;
        let robot = tool.robot_with_nozzle(robot)?;
        let config = tool.pose_config(pose);
        config.validate()?;
        let mount = tool.mount(&robot);
        let in_world = |b: ReachBound| ReachBound {
            centres: b.centres.iter().map(|c| world_from_base * c).collect(),
            radius: b.radius,
        };
        let reach = robot
            .reach_bound(mount.link, &mount.link_from_scanner, REACH_SAMPLES)
            .map(in_world);
        let wrist = wrist_reach(&robot, &mount, &tool).map(|(bound, along_m, side_m)| WristReach {
            bound: in_world(bound),
            along_m,
            side_m,
        });
        Ok(Self {
            safety: Safety::new(robot, world_from_base, plan, weights)?,
            config,
            tool,
            reach,
            wrist,
        })
    }

    /// The same selection with `starts` LM runs at most
    /// ([`PoseConfig::starts`]).
    pub fn with_starts(&self, starts: usize) -> Result<Self, PlanError> {
        let config = PoseConfig {
            starts,
            ..self.config.clone()
        };
        config.validate()?;
        Ok(Self {
            safety: self.safety.clone(),
            config,
            tool: self.tool,
            reach: self.reach.clone(),
            wrist: self.wrist.clone(),
        })
    }

    /// The robot with the nozzle as its "scanner".
    pub fn robot(&self) -> &Robot {
        self.safety.robot()
    }

    /// `false` when no configuration within the joint limits puts the
    /// nozzle tip where its stream could meet `target` within the tool's
    /// angle, stream length and aim limits (the arm's reach bound,
    /// [`robot::ReachBound`], against the solid sector of tip positions
    /// from which a stream through the centre meets it within the limits),
    /// or none puts the wrist (a point fixed to the nozzle behind the tip,
    /// [`Robot::fixed_point_link`]) where it must then be: the same sector
    /// with the stream lengthened by the wrist's distance behind the tip
    /// (the stream's direction is the sector's), widened by its distance
    /// from the nozzle's axis. Such a target has no pose, whatever the map.
    /// `true` says only that it may have one.
    pub fn may_reach(&self, target: &Target) -> bool {
        let t = &self.tool;
        let phi_max = t.phi_max_deg.to_radians();
        let n = target.normal.into_inner();
        // The tip (or the wrist) stands within ρ_min of a point of the
        // sector around the centre (the aim's miss moves it sideways); a
        // nanometre for rounding.
        let tip = self.reach.as_ref().is_none_or(|reach| {
            reach.may_reach(t.rho_min_m + 1e-9, |p| {
                tip_gap(p - target.centre, n, phi_max, t.d_min_m, t.d_max_m)
            })
        });
        tip && self.wrist.as_ref().is_none_or(|w| {
            w.bound.may_reach(t.rho_min_m + w.side_m + 1e-8, |p| {
                tip_gap(
                    p - target.centre,
                    n,
                    phi_max,
                    t.d_min_m - w.along_m,
                    t.d_max_m - w.along_m,
                )
            })
        })
    }

    /// A pose from which the stream hits `target` within the tool's limits,
    /// starting from `start` (the LM runs of [`PoseSelector::select`]).
    pub fn select(
        &self,
        grid: &OccupancyGrid,
        target: &Target,
        start: &[Real],
    ) -> Result<PoseSolution, PlanError> {
        PoseSelector::new(&self.safety, self.config.clone())?.select(grid, target, start)
    }

    /// Re-measure the pose `q` against `target` and `grid`: the nozzle's
    /// pose by forward kinematics, the stream meeting the disc's plane, and
    /// `dist(Q)`.
    pub fn measure(
        &self,
        grid: &OccupancyGrid,
        target: &Target,
        q: &[Real],
    ) -> Result<BlastMeasure, PlanError> {
        let nozzle = self
            .robot()
            .scanner_pose(q)?
            .map(|p| self.safety.world_from_base() * p)
            .ok_or_else(|| PlanError::Robot {
                robot: self.robot().name.clone(),
                message: "no nozzle".into(),
            })?;
        let view = plan::view_geometry(&nozzle, target);
        let dist = self.safety.dist(grid, q)?;
        let phi_deg = view.phi_rad.to_degrees();
        let (d_m, aim_error_m) = view
            .hit
            .map_or((Real::INFINITY, Real::INFINITY), |h| (h.d_m, h.rho_m));
        let t = &self.tool;
        Ok(BlastMeasure {
            phi_deg,
            d_m,
            aim_error_m,
            dist,
            valid: phi_deg < t.phi_max_deg
                && (t.d_min_m..=t.d_max_m).contains(&d_m)
                && aim_error_m <= t.rho_min_m
                && dist > 1.0,
        })
    }
}
