//! The surface follower (P ch. 3): each step it updates the surface model
//! with the sensor set just taken (P ch. 2), tracks what the update changed
//! (P§3.4.6), chooses the surface-following direction in one of the five
//! motion modes (P§3.4, Fig. 28, Fig. 38), turns it into a control-point
//! motion (P§3.2) and that into actuator changes (P§3.3), and checks its
//! progress every τ steps (P§3.4.7).

use crate::FollowError;
use crate::actuator::{
    LinkBody, LinkProximity, SwitchContact, actuator_change_bounded, joint_limit_gradient,
    largest_link_weight, link_bodies, link_proximities, reconfiguration,
};
use crate::config::{FollowConfig, GapTargetRule, Objective};
use crate::guard::{Guard, GuardAction, GuardCounts};
use crate::motion::control_point_motion;
use crate::path::{EdgePath, surface_edges};
use crate::query::{EdgeRef, ModelPoint, closest_model_point, closest_on_segment};
use geom::{Isometry3, Point3, Real, UnitVector3, Vector3};
use nalgebra::Matrix6xX;
use robot::{LinkId, Robot};
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};
use std::time::Instant;
use surface::{ChangeLog, EdgeKey, SegmentId, SensorSet, SurfaceModel};

mod changes;
mod edge_following;
mod gap_following;
mod point_following;
mod progress;
mod segment_following;
mod surface_following;

/// The five motion modes (P§3.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Current surface following (P§3.4.1).
    Surface,
    /// Current segment following (P§3.4.2).
    Segment,
    /// Current edge following (P§3.4.3).
    Edge,
    /// Point following (P§3.4.4).
    Point,
    /// Gap following (P§3.4.5).
    Gap,
}

impl Mode {
    /// Name used in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Surface => "surface",
            Self::Segment => "segment",
            Self::Edge => "edge",
            Self::Point => "point",
            Self::Gap => "gap",
        }
    }
}

/// Why following stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// The current surface is complete (P§3.4: the algorithm's own rule) and
    /// no other incomplete surface lies within sensing range.
    SurfaceComplete,
    /// The current surface was deleted by surface modelling (P§3.4.6) and no
    /// other incomplete surface lies within sensing range.
    SurfaceDeleted,
    /// No incomplete surface within sensing range at the start.
    NoSurfaceInRange,
    /// The model has no point near the control point to follow.
    ModelOutOfReach,
}

impl Termination {
    /// Name used in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::SurfaceComplete => "surface_complete",
            Self::SurfaceDeleted => "surface_deleted",
            Self::NoSurfaceInRange => "no_surface_in_range",
            Self::ModelOutOfReach => "model_out_of_reach",
        }
    }
}

pub use record::StepTimes;

/// What one step decided.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Step {
    /// The actuator change θ̇ to apply (zeros once terminated).
    pub dq: Vec<Real>,
    /// The mode that produced the direction.
    pub mode: Mode,
    /// The control point before the motion (world frame).
    pub control_point: Point3,
    /// The control-point motion ẋ asked of the kinematics.
    pub motion: Vector3,
    /// Sensor points in this step's set.
    pub set_size: usize,
    /// Distance from the control point to the model.
    pub model_distance: Real,
    /// Smallest distance of a link (outside the control-point zone) from the
    /// model, within the influence distance (`None`: none that close).
    pub link_clearance: Option<Real>,
    /// The current segment.
    pub current_segment: Option<SegmentId>,
    /// The current edge.
    pub current_edge: Option<EdgeKey>,
    /// Set when following has finished.
    pub termination: Option<Termination>,
    /// What the safety guard did with the actuator change.
    pub guard: GuardAction,
    /// Timings.
    pub times: StepTimes,
}

/// Slices of current edge following (P§3.4.3, Fig. 31): slabs of width λ/2
/// (or as [`crate::config::SliceRule`] says) perpendicular to the slice
/// line, numbered along it.
#[derive(Clone, Debug, PartialEq)]
struct SliceLine {
    point: Point3,
    dir: UnitVector3,
    /// The slices' width, fixed with the line.
    width: Real,
    used: BTreeSet<i64>,
}

impl SliceLine {
    fn param(&self, p: &Point3) -> Real {
        (p - self.point).dot(&self.dir)
    }

    fn foot(&self, p: &Point3) -> Point3 {
        self.point + self.dir.into_inner() * self.param(p)
    }
}

/// Gap following's state (P§3.4.5).
#[derive(Clone, Debug, PartialEq)]
struct Gap {
    /// Mode gap following was called from (Edge or Point).
    from: Mode,
    targets: Vec<Point3>,
    next: usize,
    sensor: Option<usize>,
    steps_on_target: u32,
}

/// Point following's four slices (P§3.4.4).
#[derive(Clone, Debug, PartialEq)]
struct PointSlices {
    centre: Point3,
    dirs: [UnitVector3; 4],
    used: [bool; 4],
    current: Option<usize>,
}

/// Marks of P§3.4: unreachable segments and edges, unclosable edges and point
/// segments.
#[derive(Clone, Debug, Default, PartialEq)]
struct Marks {
    /// Unreachable segments, each with whether the control point has since
    /// been closest to something else (only then does being brought closest
    /// to it again re-mark it incomplete).
    unreachable_segments: BTreeMap<SegmentId, bool>,
    unclosable_points: BTreeSet<SegmentId>,
    /// Unreachable edges, with the same flag.
    unreachable_edges: BTreeMap<EdgeKey, bool>,
    unclosable_edges: BTreeSet<EdgeKey>,
}

/// The direction-algorithm state.
#[allow(clippy::struct_excessive_bools)] // the thesis' flags, named as it names them
#[derive(Clone, Debug, PartialEq)]
struct State {
    mode: Mode,
    started: bool,
    surface: BTreeSet<SegmentId>,
    segment: Option<SegmentId>,
    path: Option<EdgePath>,
    path_follow: usize,
    edge: Option<EdgeKey>,
    edge_segment: Option<SegmentId>,
    follow: Option<EdgeKey>,
    /// Current direction along the current segment's perimeter: `true` =
    /// anticlockwise (increasing edge index).
    anticlockwise: bool,
    /// Flag of P§3.4.2/3: any incomplete follow edge may become the current edge.
    any_edge: bool,
    slices: Option<SliceLine>,
    slice: Option<i64>,
    /// Flag of P§3.4.3: set when a new current slice is chosen, cleared once
    /// within ρ of the current point.
    approaching: bool,
    point: Option<PointSlices>,
    gap: Option<Gap>,
}

impl State {
    fn new() -> Self {
        Self {
            mode: Mode::Surface,
            started: false,
            surface: BTreeSet::new(),
            segment: None,
            path: None,
            path_follow: 0,
            edge: None,
            edge_segment: None,
            follow: None,
            anticlockwise: true,
            any_edge: true,
            slices: None,
            slice: None,
            approaching: true,
            point: None,
            gap: None,
        }
    }
}

/// Progress checks (P§3.4.7).
#[derive(Clone, Debug, PartialEq)]
struct Progress {
    counter: u32,
    stored: Vec<Real>,
    reset_requested: bool,
    /// The stall watch (our addition to P§3.4.7): steps since `watched`
    /// was stored, never reset by a change of goal.
    watch_counter: u32,
    watched: Vec<Real>,
    /// Steps of repositioning left (`FollowConfig::reposition_steps`).
    reposition_left: u32,
    /// The step before which no new repositioning starts.
    reposition_after: u64,
    /// Goals given up since a progress check last found the robot moved
    /// (`FollowConfig::reposition_after_give_ups`).
    give_ups_in_a_row: u32,
}

/// A direction with an optional step limit (P§3.4.3, P§3.4.5).
#[derive(Clone, Copy, Debug)]
struct Directive {
    dir: Vector3,
    step_limit: Option<Real>,
}

enum Flow {
    Go(Directive),
    Again,
    Stop(Termination),
}

/// Pudney's surface follower for one robot.
///
/// Construct it with the robot, where its base stands, the surface model to
/// grow (with any a-priori initial segments) and the parameters; then call
/// [`Follower::step`] with the joints and the readings of every range finder
/// after each motion until a step reports a [`Termination`].
#[derive(Clone, Debug)]
pub struct Follower {
    robot: Robot,
    world_from_base: Isometry3,
    config: FollowConfig,
    model: SurfaceModel,
    bodies: Vec<LinkBody>,
    /// Range finders at the control point (gap following's controlled sensors).
    cp_sensors: Vec<usize>,
    sensing_range: Real,
    state: State,
    marks: Marks,
    progress: Progress,
    last_points: Vec<Point3>,
    /// Every point sensed so far, kept for `gap_targets = "sensed"` only.
    sensed: Option<gap_following::SensedPoints>,
    steps: u64,
    finished: Option<Termination>,
    frames: Vec<Isometry3>,
    jacobian: Matrix6xX<Real>,
    guard: Guard,
}

impl Follower {
    /// A follower for `robot` standing at `world_from_base`, growing `model`.
    /// The robot needs range finders at its control point (on the tool link
    /// within δ of the tool point).
    pub fn new(
        robot: Robot,
        world_from_base: Isometry3,
        model: SurfaceModel,
        config: FollowConfig,
    ) -> Result<Self, FollowError> {
        config.validate()?;
        let (tool_link, tool) = robot.tool;
        let tool_point = Point3::from(tool.translation.vector);
        let cp_sensors: Vec<usize> = robot
            .range_finders
            .iter()
            .enumerate()
            .filter(|(_, m)| {
                m.link == tool_link && (m.origin - tool_point).norm() <= config.desired_distance_m
            })
            .map(|(i, _)| i)
            .collect();
        if cp_sensors.is_empty() {
            return Err(FollowError::NoControlPointSensor {
                robot: robot.name.clone(),
                link: tool_link.index(),
                within_m: config.desired_distance_m,
            });
        }
        let sensing_range = cp_sensors
            .iter()
            .map(|&i| robot.range_finders[i].max_range_m)
            .fold(0.0, Real::max);
        let bodies = link_bodies(&robot);
        let dof = robot.dof();
        let sensed = (config.gap_targets == GapTargetRule::Sensed)
            .then(|| gap_following::SensedPoints::new(0.5 * model.config().lambda));
        let mut guard = Guard::new(&config);
        guard.keep_given(&model);
        Ok(Self {
            robot,
            world_from_base,
            config,
            model,
            bodies,
            cp_sensors,
            sensing_range,
            state: State::new(),
            marks: Marks::default(),
            progress: Progress {
                counter: 0,
                stored: Vec::new(),
                reset_requested: true,
                watch_counter: 0,
                watched: Vec::new(),
                reposition_left: 0,
                reposition_after: 0,
                give_ups_in_a_row: 0,
            },
            last_points: Vec::new(),
            sensed,
            steps: 0,
            finished: None,
            frames: Vec::new(),
            jacobian: Matrix6xX::zeros(dof),
            guard,
        })
    }

    /// Mark initial segments of the model as the object's own faces, given a
    /// priori (P§4.3: faces the robot cannot reach): the safety guard takes
    /// every other initial segment (a table the object stands on) to go on
    /// past its edges ([`FollowConfig::guard_initial_extension_m`]), so the
    /// links never pass round its edge to behind it, and these not (the
    /// robot works round the object's edges). Ids that are not initial
    /// segments are ignored.
    pub fn mark_object_faces(&mut self, ids: &[surface::SegmentId]) {
        self.guard.set_object_faces(ids);
    }

    /// How often the safety guard took, scaled, replaced or held a change.
    pub fn guard_counts(&self) -> GuardCounts {
        self.guard.counts()
    }

    /// How many segments deleted as redundant (P§2.9) the safety guard
    /// keeps as surface.
    pub fn guard_ghosts(&self) -> usize {
        self.guard.ghosts()
    }

    /// The surface model so far.
    pub fn model(&self) -> &SurfaceModel {
        &self.model
    }

    /// The model, consuming the follower.
    pub fn into_model(self) -> SurfaceModel {
        self.model
    }

    /// The robot.
    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// The parameters.
    pub fn config(&self) -> &FollowConfig {
        &self.config
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Why following stopped, once it has.
    pub fn termination(&self) -> Option<Termination> {
        self.finished
    }

    /// The current surface's incomplete edges (P§3.4): unshared, not marked
    /// unreachable or unclosable, on segments not marked unreachable.
    pub fn incomplete_edges(&self) -> Vec<EdgeRef> {
        let surface: Vec<SegmentId> = self
            .state
            .surface
            .iter()
            .copied()
            .filter(|s| !self.marks.unreachable_segments.contains_key(s))
            .collect();
        surface_edges(&self.model, &surface)
            .into_iter()
            .filter(|e| !self.edge_complete(e))
            .collect()
    }

    /// How many segments and edges are marked unreachable or unclosable:
    /// `(unreachable segments, unclosable points, unreachable edges,
    /// unclosable edges)`.
    pub fn mark_counts(&self) -> (usize, usize, usize, usize) {
        (
            self.marks.unreachable_segments.len(),
            self.marks.unclosable_points.len(),
            self.marks.unreachable_edges.len(),
            self.marks.unclosable_edges.len(),
        )
    }

    /// The control point (world frame) at joints `q`.
    pub fn control_point(&self, q: &[Real]) -> Result<Point3, FollowError> {
        let tool = self.robot.tool_pose(q)?;
        Ok(self.world_from_base * Point3::from(tool.translation.vector))
    }

    /// Each range finder's origin and axis (world frame) at joints `q`.
    pub fn sensor_rays(&self, q: &[Real]) -> Result<Vec<(Point3, UnitVector3)>, FollowError> {
        let frames = self.robot.forward_kinematics(q)?;
        Ok(self
            .robot
            .range_finders
            .iter()
            .filter_map(|m| m.in_base(&frames))
            .map(|(o, a)| (self.world_from_base * o, self.world_from_base.rotation * a))
            .collect())
    }

    /// One step: `q` are the joints now, `readings[i]` the point range finder
    /// `i` of [`Robot::range_finders`] sensed at `q` (world frame), `None`
    /// without a return. Returns the actuator change to apply before the next
    /// step. Errors (a wrong joint vector, a non-finite reading) leave the
    /// follower unchanged.
    pub fn step(&mut self, q: &[Real], readings: &[Option<Point3>]) -> Result<Step, FollowError> {
        self.robot.check_joints(q)?;
        if readings.len() != self.robot.range_finders.len() {
            return Err(FollowError::Readings {
                expected: self.robot.range_finders.len(),
                got: readings.len(),
            });
        }
        let t0 = Instant::now();
        let mut frames = Vec::with_capacity(self.robot.links.len());
        self.robot.fk_into(q, &mut frames)?;
        for f in &mut frames {
            *f = self.world_from_base * *f;
        }
        // Gap following aims sensors at the pose the set was taken from.
        self.frames.clone_from(&frames);
        let (tool_link, tool) = self.robot.tool;
        let tool_in_link = Point3::from(tool.translation.vector);
        let cp = frames[tool_link.0] * tool_in_link;
        // The set of sensor points (P eq. 1), with their sensing axes.
        let mut points = Vec::new();
        let mut axes = Vec::new();
        for (m, r) in self.robot.range_finders.iter().zip(readings) {
            if let Some(p) = r {
                let axis = frames[m.link.0].rotation * m.axis;
                points.push(*p);
                axes.push(axis);
            }
        }
        let set_size = points.len();
        let log = if points.is_empty() {
            ChangeLog::default()
        } else {
            let set = SensorSet::new(points.clone(), axes)?;
            self.model.update(&set)?
        };
        self.guard.remember(&self.model, &points);
        if let Some(sensed) = self.sensed.as_mut() {
            sensed.insert(&points);
        }
        self.last_points = points;
        let t1 = Instant::now();
        let mut termination = self.finished;
        let mut directive = Directive {
            dir: Vector3::zeros(),
            step_limit: Some(0.0),
        };
        let closest = self.closest_to(&cp);
        if termination.is_none() {
            self.track_changes(&log);
            match closest {
                None => termination = Some(Termination::ModelOutOfReach),
                Some(c) => {
                    self.remark(&c);
                    match self.direction(&cp, &c) {
                        Ok(d) => directive = d,
                        Err(t) => termination = Some(t),
                    }
                }
            }
        }
        let t2 = Instant::now();
        let mode = self.state.mode;
        let mut motion = Vector3::zeros();
        let mut dq = vec![0.0; self.robot.dof()];
        let mut link_clearance = None;
        let mut guard = GuardAction::None;
        if termination.is_none()
            && let Some(c) = closest
        {
            let mut sigma = self.config.max_step_m;
            if let Some(l) = directive.step_limit {
                sigma = sigma.min(l);
            }
            motion = control_point_motion(
                &cp,
                &c.point,
                &directive.dir,
                self.config.desired_distance_m,
                sigma,
            );
            let proximities = link_proximities(
                &self.model,
                &self.bodies,
                &frames,
                &cp,
                tool_link,
                self.config.desired_distance_m,
                self.config.influence_m,
            );
            link_clearance = proximities
                .iter()
                .map(|p| p.distance)
                .min_by(Real::total_cmp);
            let switches = if self.config.objective == Objective::ProximitySwitches {
                self.switch_contacts(&frames, readings, tool_link, &cp)
            } else {
                Vec::new()
            };
            dq = self.kinematics(
                q,
                &frames,
                tool_link,
                &tool_in_link,
                &motion,
                &proximities,
                &switches,
            );
            if self.config.guard {
                (dq, guard) = self.guard.check(
                    &self.robot,
                    &self.world_from_base,
                    &self.bodies,
                    &self.model,
                    &self.config,
                    q,
                    dq,
                );
            }
            self.check_progress(q);
        }
        self.finished = termination;
        self.steps += 1;
        let t3 = Instant::now();
        let us = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e6;
        Ok(Step {
            dq,
            mode,
            control_point: cp,
            motion,
            set_size,
            model_distance: closest.map_or(Real::INFINITY, |c| c.distance),
            link_clearance,
            current_segment: self.state.segment,
            current_edge: self.state.edge,
            termination,
            guard,
            times: StepTimes {
                update_us: us(t0, t1),
                direction_us: us(t1, t2),
                kinematics_us: us(t2, t3),
            },
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn kinematics(
        &mut self,
        q: &[Real],
        frames: &[Isometry3],
        tool_link: LinkId,
        tool_in_link: &Point3,
        motion: &Vector3,
        proximities: &[LinkProximity],
        switches: &[SwitchContact],
    ) -> Vec<Real> {
        // `frames` are world frames, so the Jacobians are in the world frame.
        let margin = self.config.link_margin_m;
        let dof = self.robot.dof();
        let mut guards = Vec::new();
        for p in proximities {
            let away = p.on_link - p.on_model;
            if p.distance >= p.radius + margin || p.distance <= 0.0 {
                continue;
            }
            let Some(frame) = frames.get(p.link.0) else {
                continue;
            };
            let in_link = frame.inverse_transform_point(&p.on_link);
            self.robot
                .jacobian_into(frames, p.link, &in_link, &mut self.jacobian);
            let n = away / p.distance;
            guards.push(nalgebra::DVector::from_fn(dof, |k, _| {
                n.x * self.jacobian[(0, k)]
                    + n.y * self.jacobian[(1, k)]
                    + n.z * self.jacobian[(2, k)]
            }));
        }
        // The joint-limit term, for robots with joints to spare (point3's
        // three joints have no null space to take it in). While
        // repositioning before a give-up (P§3.4.7, `reposition_steps`) the
        // gain is at least `reposition_gain`.
        let repositioning = self.progress.reposition_left > 0;
        if repositioning {
            self.progress.reposition_left -= 1;
        }
        let joint_term =
            self.robot.dof() > 3 && (self.config.joint_limit_gain > 0.0 || repositioning);
        // The bounds on the joint-limit term (`joint_limit_keeps_links_off`):
        // every link within the influence distance may come at most as far
        // closer as it is beyond its radius plus the link margin (a velocity
        // damper at one step's scale), so no link is brought within the
        // margin by it and none already within it closer.
        // Only while the term acts: it is zero otherwise.
        let mut bounds = Vec::new();
        if self.config.joint_limit_keeps_links_off && joint_term {
            for p in proximities {
                if p.distance <= 0.0 {
                    continue;
                }
                let Some(frame) = frames.get(p.link.0) else {
                    continue;
                };
                let in_link = frame.inverse_transform_point(&p.on_link);
                self.robot
                    .jacobian_into(frames, p.link, &in_link, &mut self.jacobian);
                let n = (p.on_link - p.on_model) / p.distance;
                let row = nalgebra::DVector::from_fn(dof, |k, _| {
                    n.x * self.jacobian[(0, k)]
                        + n.y * self.jacobian[(1, k)]
                        + n.z * self.jacobian[(2, k)]
                });
                bounds.push((row, (p.distance - p.radius - margin).max(0.0)));
            }
        }
        self.robot
            .jacobian_into(frames, tool_link, tool_in_link, &mut self.jacobian);
        let mut z = reconfiguration(
            &self.robot,
            frames,
            self.config.objective,
            proximities,
            switches,
            &self.config,
        );
        // The joint-limit term yields to link avoidance where a link is near
        // the model (`joint_limit_yield`): there the null space is the links'.
        let mut z_bounded = nalgebra::DVector::zeros(dof);
        if joint_term {
            let w = largest_link_weight(self.config.objective, proximities, switches, &self.config);
            let share = 1.0 - self.config.joint_limit_yield * w;
            let gradient = if repositioning {
                let config = FollowConfig {
                    joint_limit_gain: self
                        .config
                        .joint_limit_gain
                        .max(self.config.reposition_gain),
                    ..self.config
                };
                joint_limit_gradient(&self.robot, q, &config)
            } else {
                joint_limit_gradient(&self.robot, q, &self.config)
            };
            // Bounded by the link guard's rows when asked
            // (`joint_limit_keeps_links_off`), else summed into z.
            if self.config.joint_limit_keeps_links_off {
                z_bounded = gradient * share;
            } else {
                z += gradient * share;
            }
        }
        actuator_change_bounded(
            &self.robot,
            q,
            &self.jacobian,
            motion,
            &z,
            &z_bounded,
            &guards,
            &bounds,
            &self.config,
        )
        .iter()
        .copied()
        .collect()
    }

    /// App. B: the link range finders read as proximity switches; one that
    /// returns a point is "object present", its field centre half its range
    /// along its axis.
    fn switch_contacts(
        &self,
        frames: &[Isometry3],
        readings: &[Option<Point3>],
        tool_link: LinkId,
        cp: &Point3,
    ) -> Vec<SwitchContact> {
        let mut out = Vec::new();
        for (i, (m, r)) in self.robot.range_finders.iter().zip(readings).enumerate() {
            if r.is_none() || self.cp_sensors.contains(&i) {
                continue;
            }
            let origin = frames[m.link.0] * m.origin;
            if m.link == tool_link && (origin - cp).norm() < self.config.desired_distance_m {
                continue;
            }
            let axis = frames[m.link.0].rotation * m.axis;
            out.push(SwitchContact {
                link: m.link,
                position: origin,
                field_centre: origin + axis.into_inner() * (0.5 * m.max_range_m),
            });
        }
        out
    }

    fn closest_to(&self, cp: &Point3) -> Option<ModelPoint> {
        let near = 2.0 * self.config.stray_m.max(self.sensing_range);
        closest_model_point(&self.model, cp, near)
            .or_else(|| closest_model_point(&self.model, cp, 50.0 * near))
    }

    // ---- the direction algorithm (P§3.4, Fig. 28, Fig. 38) -----------------

    fn direction(&mut self, cp: &Point3, closest: &ModelPoint) -> Result<Directive, Termination> {
        if !self.state.started {
            self.choose_surface(cp)?;
        }
        if self.state.surface.is_empty() {
            // P§3.4.6 stops when the current surface is deleted; as for a
            // complete one ([`Self::next_surface`]), an incomplete surface
            // within sensing range takes its place first.
            if self.choose_surface(cp).is_err() {
                return Err(Termination::SurfaceDeleted);
            }
            self.state.segment = None;
            self.state.path = None;
            self.reset_progress();
        }
        // Mode switches within one step are bounded; a cycle would be a bug,
        // and the step then moves nowhere rather than spinning.
        for _ in 0..32 {
            let flow = match self.state.mode {
                Mode::Surface => self.surface_following(cp, closest),
                Mode::Segment => self.segment_following(cp),
                Mode::Edge => self.edge_following(cp, closest),
                Mode::Point => self.point_following(cp, closest),
                Mode::Gap => self.gap_following(cp),
            };
            match flow {
                Flow::Go(d) => return Ok(d),
                Flow::Again => {}
                Flow::Stop(t) => return Err(t),
            }
        }
        Ok(Directive {
            dir: Vector3::zeros(),
            step_limit: None,
        })
    }

    /// "current surface = incomplete surface within sensing range of control
    /// point" (Fig. 28).
    fn choose_surface(&mut self, cp: &Point3) -> Result<(), Termination> {
        let mut ids = self.model.segments_near(cp, self.sensing_range);
        ids.sort_unstable();
        let mut best: Option<(Real, SegmentId)> = None;
        for id in ids {
            if self.segment_complete(id) {
                continue;
            }
            if let Some(c) = closest_on_segment(&self.model, id, cp)
                && c.distance <= self.sensing_range
                && best.is_none_or(|b| c.distance < b.0)
            {
                best = Some((c.distance, id));
            }
        }
        let Some((_, id)) = best else {
            return Err(Termination::NoSurfaceInRange);
        };
        self.state.surface = self.component_of(&[id]);
        self.state.started = true;
        self.state.mode = Mode::Surface;
        Ok(())
    }
}

/// Counts per mode, for run summaries.
pub type ModeCounts = BTreeMap<Mode, u64>;

#[cfg(test)]
mod tests {
    use super::segment_following::{Perimeter, routes};
    use super::*;

    /// Gap following at point3 standing at (0, 0, 0.1): the range finder
    /// pointing straight down has its axis through (0, 0, 0.05) (hand
    /// geometry: origin at the control point, axis −z), so the first target
    /// is aimed at; the set in hand holds nothing within λ/2 of it (its only
    /// point, (0, 0, 0.0), is 0.05 away), so that target is given up at once
    /// and the step aims at the second target instead of standing still.
    #[test]
    fn an_aimed_target_without_a_point_near_it_is_given_up_at_once() {
        let robot = robot::builtin("point3").expect("point3");
        let model = SurfaceModel::new(surface::SurfaceConfig::default()).expect("model");
        let mut f = Follower::new(robot, Isometry3::identity(), model, FollowConfig::default())
            .expect("follower");
        let q = [0.0, 0.0, 0.1];
        f.frames = f.robot.forward_kinematics(&q).expect("fk");
        let cp = f.control_point(&q).expect("cp");
        assert!((cp - Point3::new(0.0, 0.0, 0.1)).norm() < 1e-12);
        f.last_points = vec![Point3::new(0.0, 0.0, 0.0)];
        let first = Point3::new(0.0, 0.0, 0.05);
        let second = Point3::new(0.06, 0.0, 0.0);
        f.state.edge = Some(EdgeKey(7));
        f.state.mode = Mode::Gap;
        f.state.gap = Some(Gap {
            from: Mode::Edge,
            targets: vec![first, second],
            next: 0,
            sensor: None,
            steps_on_target: 0,
        });
        let Flow::Go(d) = f.gap_following(&cp) else {
            panic!("gap following should direct the control point");
        };
        let gap = f.state.gap.clone().expect("still gap following");
        assert_eq!(gap.next, 1, "the aimed-at first target is given up");
        assert_eq!(gap.steps_on_target, 1);
        // Towards the second target: a positive step, not the zero step
        // limit of an already aimed sensor.
        assert!(d.dir.norm() > 1e-3);
        assert!(d.step_limit.is_none_or(|l| l > 1e-3));
    }

    /// `gap_targets = "sensed"`: point3 at (0, 0, 0.1) following a gap of
    /// edge following whose first target, (0.3, 0, 0), lies 0.02 from a
    /// point an earlier set sensed, (0.3, 0.02, 0) (less than λ/2 =
    /// 0.025): that target counts as detected before any step is spent on
    /// it, and the step aims at the second, (0.4, 0, 0), 0.1 from every
    /// sensed point. The thesis rule, and a gap of point following under
    /// the new rule, aim at the first target.
    #[test]
    fn a_target_an_earlier_set_sensed_is_detected_at_once() {
        let robot = robot::builtin("point3").expect("point3");
        let first = Point3::new(0.3, 0.0, 0.0);
        let second = Point3::new(0.4, 0.0, 0.0);
        let cases = [
            (GapTargetRule::Sensed, Mode::Edge, 1),
            (GapTargetRule::Thesis, Mode::Edge, 0),
            (GapTargetRule::Sensed, Mode::Point, 0),
        ];
        for (rule, from, next) in cases {
            let model = SurfaceModel::new(surface::SurfaceConfig::default()).expect("model");
            let config = FollowConfig {
                gap_targets: rule,
                ..FollowConfig::default()
            };
            let mut f =
                Follower::new(robot.clone(), Isometry3::identity(), model, config).expect("f");
            let q = [0.0, 0.0, 0.1];
            f.frames = f.robot.forward_kinematics(&q).expect("fk");
            let cp = f.control_point(&q).expect("cp");
            if let Some(s) = f.sensed.as_mut() {
                s.insert(&[Point3::new(0.3, 0.02, 0.0), Point3::new(0.5, 0.0, 0.0)]);
            }
            f.last_points = vec![Point3::new(0.0, 0.0, 0.0)];
            f.state.edge = Some(EdgeKey(7));
            // Point following's gaps need a point segment as the current one.
            if from == Mode::Point {
                let set =
                    SensorSet::new(vec![Point3::new(0.0, 0.0, 0.0)], vec![-Vector3::z_axis()])
                        .expect("set");
                f.model.update(&set).expect("update");
                f.state.segment = f.model.segments().next().map(surface::Segment::id);
            }
            f.state.mode = Mode::Gap;
            f.state.gap = Some(Gap {
                from,
                targets: vec![first, second],
                next: 0,
                sensor: None,
                steps_on_target: 0,
            });
            let Flow::Go(_) = f.gap_following(&cp) else {
                panic!("{rule:?} {from:?}: gap following should direct the control point");
            };
            let gap = f.state.gap.clone().expect("still gap following");
            assert_eq!(gap.next, next, "{rule:?} from {from:?}");
        }
    }

    /// The O(1) route length equals walking the perimeter both ways.
    #[test]
    fn perimeter_distance_equals_walking() {
        let pts: Vec<Point3> = [0.0, 0.3, 0.35, 1.2, 1.5, 2.9]
            .iter()
            .enumerate()
            .map(|(k, a): (usize, &Real)| Point3::new(a.cos() * (1.0 + k as Real), a.sin(), 0.0))
            .collect();
        let n = pts.len();
        let edges: Vec<EdgeRef> = (0..n)
            .map(|i| EdgeRef {
                key: EdgeKey(i as u32),
                segment: SegmentId(1),
                index: i,
                a: pts[i],
                b: pts[(i + 1) % n],
                shared_with: None,
            })
            .collect();
        let p = Perimeter::new(&edges);
        for from in 0..n {
            for to in 0..n {
                let (ccw, cw) = routes(from, to, n, &edges);
                assert!(
                    (p.distance(from, to) - ccw.min(cw)).abs() < 1e-12,
                    "{from} → {to}"
                );
            }
        }
    }

    /// point3 over the floor z = 0 after a few steps: a model with a polygon.
    pub(super) fn floor_follower() -> (Follower, SegmentId) {
        let robot = robot::builtin("point3").unwrap();
        let model = SurfaceModel::new(surface::SurfaceConfig::default()).unwrap();
        let mut f =
            Follower::new(robot, Isometry3::identity(), model, FollowConfig::default()).unwrap();
        let mut q = vec![0.0, 0.0, 0.15];
        for _ in 0..20 {
            let readings: Vec<Option<Point3>> = f
                .sensor_rays(&q)
                .unwrap()
                .iter()
                .map(|(o, a)| {
                    let t = -o.z / a.z;
                    (a.z < 0.0 && t <= 0.2).then(|| o + a.into_inner() * t)
                })
                .collect();
            let step = f.step(&q, &readings).unwrap();
            for (qi, d) in q.iter_mut().zip(&step.dq) {
                *qi += d;
            }
        }
        let poly = f
            .model
            .segments()
            .find(|s| s.as_polygon().is_some())
            .map(surface::Segment::id)
            .unwrap();
        (f, poly)
    }

    /// A step with a reading count other than one per range finder is a
    /// typed error that leaves the follower as it was.
    #[test]
    fn a_wrong_reading_count_is_refused_unchanged() {
        let (mut f, _) = floor_follower();
        let (steps, segments) = (f.steps(), f.model.segments().count());
        let n = f.robot.range_finders.len();
        match f.step(&[0.0, 0.0, 0.15], &vec![None; n - 1]) {
            Err(FollowError::Readings { expected, got }) => {
                assert_eq!((expected, got), (n, n - 1));
            }
            other => panic!("{other:?}"),
        }
        assert_eq!((f.steps(), f.model.segments().count()), (steps, segments));
    }

    /// P§3.4.6: a path whose target was merged keeps going to what the target
    /// became (before, it was dropped and recomputed, which reset the progress
    /// check every step of a robot that stood still); one whose target was
    /// deleted is dropped.
    #[test]
    fn the_path_target_follows_mergers() {
        let (mut f, poly) = floor_follower();
        let gone = SegmentId(u32::MAX - 1);
        let other = SegmentId(u32::MAX - 2);
        assert!(f.model.segment(gone).is_none());
        let log = ChangeLog {
            mergers: vec![surface::Merger {
                from: [gone, other],
                into: poly,
            }],
            ..ChangeLog::default()
        };
        let path = EdgePath {
            edges: Vec::new(),
            forward: Vec::new(),
            target: gone,
        };
        f.state.path = Some(path.clone());
        f.track_changes(&log);
        assert_eq!(f.state.path.as_ref().map(|p| p.target), Some(poly));
        // Deleted: no successor, no path.
        f.state.path = Some(path);
        let log = ChangeLog {
            deleted: vec![gone],
            ..ChangeLog::default()
        };
        f.track_changes(&log);
        assert!(f.state.path.is_none());
    }

    /// Marks follow mergers: an unreachable segment's successor is
    /// unreachable (its flag kept); an unclosable point segment merged into a
    /// polygon is not a point any more and its mark goes.
    #[test]
    fn segment_marks_follow_mergers() {
        let (mut f, poly) = floor_follower();
        let (a, b) = (SegmentId(u32::MAX - 1), SegmentId(u32::MAX - 2));
        f.marks.unreachable_segments.insert(a, true);
        f.marks.unclosable_points.insert(b);
        let log = ChangeLog {
            mergers: vec![surface::Merger {
                from: [a, b],
                into: poly,
            }],
            ..ChangeLog::default()
        };
        f.track_changes(&log);
        assert_eq!(
            f.marks.unreachable_segments.iter().collect::<Vec<_>>(),
            vec![(&poly, &true)]
        );
        assert!(f.marks.unclosable_points.is_empty());
        assert!(f.segment_complete(poly));
    }
}
