//! The surface follower (P ch. 3): each step it updates the surface model
//! with the sensor set just taken (P ch. 2), tracks what the update changed
//! (P§3.4.6), chooses the surface-following direction in one of the five
//! motion modes (P§3.4, Fig. 28, Fig. 38), turns it into a control-point
//! motion (P§3.2) and that into actuator changes (P§3.3), and checks its
//! progress every τ steps (P§3.4.7).

use crate::FollowError;
use crate::actuator::{
    LinkBody, LinkProximity, SwitchContact, actuator_change, link_bodies, link_proximities,
    reconfiguration,
};
use crate::config::{FollowConfig, Objective};
use crate::motion::control_point_motion;
use crate::path::{EdgePath, shortest_edge_path, surface_edges};
use crate::query::{
    EdgeRef, Feature, ModelPoint, closest_model_point, closest_on_perimeter, closest_on_segment,
    edge_by_key,
};
use geom::{Isometry3, Point3, Real, Segment3, UnitVector3, Vector3, polygon2, unit};
use nalgebra::Matrix6xX;
use robot::{JointKind, LinkId, Robot};
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};
use std::time::Instant;
use surface::{ChangeLog, EdgeKey, SegmentId, SensorSet, SurfaceModel};

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
    /// Timings.
    pub times: StepTimes,
}

/// Slices of current edge following (P§3.4.3, Fig. 31): slabs of width λ/2
/// perpendicular to the slice line, numbered along it.
#[derive(Clone, Debug, PartialEq)]
struct SliceLine {
    point: Point3,
    dir: UnitVector3,
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
    steps: u64,
    finished: Option<Termination>,
    frames: Vec<Isometry3>,
    jacobian: Matrix6xX<Real>,
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
            return Err(FollowError::Robot(format!(
                "robot '{}' has no range finder at its control point (on link {} within δ = {} m of the tool point)",
                robot.name, tool_link, config.desired_distance_m
            )));
        }
        let sensing_range = cp_sensors
            .iter()
            .map(|&i| robot.range_finders[i].max_range_m)
            .fold(0.0, Real::max);
        let bodies = link_bodies(&robot);
        let dof = robot.dof();
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
            },
            last_points: Vec::new(),
            steps: 0,
            finished: None,
            frames: Vec::new(),
            jacobian: Matrix6xX::zeros(dof),
        })
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
            return Err(FollowError::Robot(format!(
                "expected {} readings (one per range finder), got {}",
                self.robot.range_finders.len(),
                readings.len()
            )));
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
        self.robot
            .jacobian_into(frames, tool_link, tool_in_link, &mut self.jacobian);
        let z = reconfiguration(
            &self.robot,
            frames,
            self.config.objective,
            proximities,
            switches,
            &self.config,
        );
        actuator_change(
            &self.robot,
            q,
            &self.jacobian,
            motion,
            &z,
            &guards,
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

    // ---- P§3.4.7: progress -------------------------------------------------

    fn reset_progress(&mut self) {
        self.progress.reset_requested = true;
    }

    fn check_progress(&mut self, q: &[Real]) {
        if self.progress.reset_requested || self.progress.stored.len() != q.len() {
            self.progress = Progress {
                counter: 0,
                stored: q.to_vec(),
                reset_requested: false,
            };
            return;
        }
        self.progress.counter += 1;
        if self.progress.counter < self.config.progress_steps {
            return;
        }
        self.progress.counter = 0;
        let kinds = self.robot.joint_kinds();
        let (mut rev, mut pri, mut has_rev, mut has_pri) = (0.0, 0.0, false, false);
        for ((k, a), b) in kinds.iter().zip(q).zip(&self.progress.stored) {
            match k {
                JointKind::Revolute => {
                    rev += (a - b) * (a - b);
                    has_rev = true;
                }
                JointKind::Prismatic => {
                    pri += (a - b) * (a - b);
                    has_pri = true;
                }
                JointKind::Fixed => {}
            }
        }
        let insufficient = (!has_rev || rev.sqrt() < self.config.ceiling_revolute_rad())
            && (!has_pri || pri.sqrt() < self.config.ceiling_prismatic_m);
        self.progress.stored = q.to_vec();
        if insufficient {
            self.give_up();
        }
    }

    /// The give-up actions of P§3.4.7.
    fn give_up(&mut self) {
        match self.state.mode {
            Mode::Surface => {
                if let Some(s) = self.state.segment.take() {
                    self.marks.unreachable_segments.insert(s, false);
                }
                self.state.path = None;
            }
            Mode::Segment => {
                if let Some(e) = self.state.edge.take() {
                    self.marks.unreachable_edges.insert(e, false);
                }
            }
            Mode::Edge => self.slice_used(),
            Mode::Point => {
                if let Some(p) = self.state.point.as_mut()
                    && let Some(k) = p.current.take()
                {
                    p.used[k] = true;
                }
            }
            Mode::Gap => {
                if let Some(g) = self.state.gap.as_mut() {
                    g.next += 1;
                    g.sensor = None;
                }
            }
        }
        self.reset_progress();
    }

    // ---- P§3.4.6: surface modelling changes --------------------------------

    fn track_changes(&mut self, log: &ChangeLog) {
        // An edge only leaves the model through a change the log records
        // (removal of its perimeter section, or deletion of its segment);
        // mergers carry unchanged edges, keys and all, into the new segment.
        let changed: BTreeSet<EdgeKey> = log.changed_edge_keys.iter().copied().collect();
        // The current segment through mergers and deletions.
        if let Some(s) = self.state.segment {
            if let Some(n) = log.resolve(s) {
                self.state.segment = Some(n);
            } else {
                self.state.segment = None;
                self.state.edge = None;
                self.state.follow = None;
                self.state.path = None;
                self.state.gap = None;
                self.state.point = None;
                self.state.mode = Mode::Surface;
            }
        }
        if let Some(s) = self.state.edge_segment {
            self.state.edge_segment = log.resolve(s);
        }
        // Marks follow their segments through mergers as the current segment
        // does (P§3.4.6 says so only of the current segment; the thesis is
        // silent on marks). A segment merged with an unreachable one is
        // unreachable until the control point is brought closest to it
        // (P§3.4.1's re-marking), and an unclosable point segment stays
        // unclosable while it is still a point segment. Dropping the marks
        // let a robot standing still, re-sensing the same points (so merging
        // its goal every step), take up the goal it just gave up at once.
        let mut unreachable: BTreeMap<SegmentId, bool> = BTreeMap::new();
        for (s, left) in std::mem::take(&mut self.marks.unreachable_segments) {
            if let Some(n) = log.resolve(s)
                && self.model.segment(n).is_some()
            {
                // Still-stuck (`left` false) wins when two marks merge.
                let e = unreachable.entry(n).or_insert(left);
                *e = *e && left;
            }
        }
        self.marks.unreachable_segments = unreachable;
        self.marks.unclosable_points = std::mem::take(&mut self.marks.unclosable_points)
            .into_iter()
            .filter_map(|s| log.resolve(s))
            .filter(|s| {
                self.model
                    .segment(*s)
                    .is_some_and(|g| g.as_point().is_some())
            })
            .collect();
        if let Some(e) = self.state.edge
            && changed.contains(&e)
        {
            // The current edge changed: choose another (P§3.4).
            self.state.edge = None;
        }
        if let Some(e) = self.state.follow
            && changed.contains(&e)
        {
            self.state.follow = None;
        }
        // The path's target and the owners of its edges through mergers, as
        // the current segment (P§3.4.6): a target merged with new points is
        // still the goal, and recomputing the path on every merger reset the
        // progress check (P§3.4.7) of a robot standing still for good.
        if let Some(path) = self.state.path.as_mut() {
            let from = self.state.path_follow.min(path.edges.len());
            let broken = path.edges[from..].iter().any(|e| changed.contains(&e.key));
            let target = log
                .resolve(path.target)
                .filter(|t| self.model.segment(*t).is_some());
            match target {
                Some(t) if !broken => {
                    path.target = t;
                    for e in &mut path.edges {
                        e.segment = log.resolve(e.segment).unwrap_or(e.segment);
                        e.shared_with = e.shared_with.map(|n| log.resolve(n).unwrap_or(n));
                    }
                }
                _ => self.state.path = None,
            }
        }
        // The current surface: what its members became, and everything now
        // connected to them.
        if self.state.started {
            let members: Vec<SegmentId> = self
                .state
                .surface
                .iter()
                .filter_map(|s| log.resolve(*s))
                .filter(|s| self.model.segment(*s).is_some())
                .collect();
            self.state.surface = self.component_of(&members);
        }
    }

    fn component_of(&self, seeds: &[SegmentId]) -> BTreeSet<SegmentId> {
        let mut seen: BTreeSet<SegmentId> = seeds.iter().copied().collect();
        let mut stack: Vec<SegmentId> = seeds.to_vec();
        while let Some(s) = stack.pop() {
            if let Some(p) = self.model.polygon(s) {
                for n in p.neighbours() {
                    if self.model.segment(n).is_some() && seen.insert(n) {
                        stack.push(n);
                    }
                }
            }
        }
        seen
    }

    /// Re-mark as incomplete what the control point is *subsequently* brought
    /// closest to (P§3.4.1, P§3.4.2): a mark made while the control point was
    /// stuck next to its goal must not be undone at once, or a stalled robot
    /// gives up and takes up the same goal forever.
    fn remark(&mut self, c: &ModelPoint) {
        let closest_edge = match c.feature {
            Feature::Edge(i) => self
                .model
                .polygon(c.segment)
                .and_then(|p| p.edge(i))
                .map(|e| e.key),
            _ => None,
        };
        self.marks.unreachable_segments.retain(|s, left| {
            if *s == c.segment {
                !*left
            } else {
                *left = true;
                true
            }
        });
        self.marks.unreachable_edges.retain(|e, left| {
            if Some(*e) == closest_edge {
                !*left
            } else {
                *left = true;
                true
            }
        });
    }

    // ---- completeness (P§3.4) ----------------------------------------------

    fn edge_complete(&self, e: &EdgeRef) -> bool {
        e.shared_with.is_some()
            || self.marks.unreachable_edges.contains_key(&e.key)
            || self.marks.unclosable_edges.contains(&e.key)
            // A-priori segments (P§4.3) stand for known surface: their free
            // edges are where the description stops, not the border of an
            // unexposed region, so they never call the robot.
            || self.model.segment(e.segment).is_some_and(surface::Segment::is_initial)
    }

    fn segment_complete(&self, id: SegmentId) -> bool {
        if self.marks.unreachable_segments.contains_key(&id)
            || self.marks.unclosable_points.contains(&id)
        {
            return true;
        }
        let Some(seg) = self.model.segment(id) else {
            return true;
        };
        if seg.is_initial() {
            return true;
        }
        let Some(poly) = seg.as_polygon() else {
            return false;
        };
        (0..poly.len()).all(|i| {
            poly.edge(i).is_none_or(|e| {
                e.share.is_some()
                    || self.marks.unreachable_edges.contains_key(&e.key)
                    || self.marks.unclosable_edges.contains(&e.key)
            })
        })
    }

    fn edges_of(&self, id: SegmentId) -> Vec<EdgeRef> {
        surface_edges(&self.model, &[id])
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

    /// Current surface following (P§3.4.1).
    fn surface_following(&mut self, cp: &Point3, closest: &ModelPoint) -> Flow {
        let tol = self.model.config().lambda * 0.5;
        if let Some(s) = self.state.segment
            && (self.segment_complete(s) || !self.state.surface.contains(&s))
        {
            self.state.segment = None;
            self.state.path = None;
        }
        if self.state.path.is_none() {
            let surface: Vec<SegmentId> = self.state.surface.iter().copied().collect();
            let goals: BTreeSet<SegmentId> = surface
                .iter()
                .copied()
                .filter(|s| !self.segment_complete(*s))
                .collect();
            if goals.is_empty() {
                return self.next_surface(cp);
            }
            if goals.contains(&closest.segment) {
                return self.reach_segment(closest.segment);
            }
            let edges = surface_edges(&self.model, &surface);
            if let Some(path) = shortest_edge_path(&edges, cp, tol, |s| goals.contains(&s)) {
                self.state.segment = Some(path.target);
                self.state.path = Some(path);
                self.state.path_follow = 0;
                self.reset_progress();
            } else {
                // No edge path (a point segment, or goals not connected
                // by edges): head straight for the nearest goal.
                let nearest = goals
                    .iter()
                    .filter_map(|s| closest_on_segment(&self.model, *s, cp))
                    .min_by(|a, b| {
                        a.distance
                            .total_cmp(&b.distance)
                            .then(a.segment.cmp(&b.segment))
                    });
                let Some(n) = nearest else {
                    return self.next_surface(cp);
                };
                if n.distance <= self.config.stray_m {
                    return self.reach_segment(n.segment);
                }
                self.state.segment = Some(n.segment);
                return Flow::Go(Directive {
                    dir: n.point - cp,
                    step_limit: None,
                });
            }
        }
        let Some(path) = self.state.path.clone() else {
            return Flow::Again;
        };
        if closest.segment == path.target {
            return self.reach_segment(path.target);
        }
        // The follow edge: the furthest path edge from the follow edge on that
        // is within ρ of the control point (it never moves backwards).
        let rho = self.config.stray_m;
        let mut follow = self.state.path_follow.min(path.edges.len() - 1);
        for (k, e) in path.edges.iter().enumerate().skip(follow) {
            if e.distance_to(cp) < rho {
                follow = k;
            }
        }
        if follow != self.state.path_follow {
            self.state.path_follow = follow;
            self.reset_progress();
        }
        let e = path.edges[follow];
        let along = if path.forward[follow] {
            e.b - e.a
        } else {
            e.a - e.b
        };
        let mut owners = vec![e.segment];
        owners.extend(e.shared_with);
        Flow::Go(self.towards_and_along(cp, &e, &along, &owners))
    }

    /// The current surface is complete. Pudney stops here (Fig. 28); we first
    /// apply Fig. 28's first line again: an incomplete surface still within
    /// sensing range becomes the current surface. Under range noise the
    /// first sets of a face form small polygons whose planes differ by more
    /// than μ, so they neither merge nor share edges, and every slice of such a
    /// fragment finds model outside its edges (P§3.4.3): the fragment the
    /// robot started on was complete after a few steps and the run ended with
    /// 1 % of the cube modelled. Only an empty neighbourhood ends the run.
    fn next_surface(&mut self, cp: &Point3) -> Flow {
        match self.choose_surface(cp) {
            Ok(()) => {
                self.state.segment = None;
                self.state.path = None;
                self.reset_progress();
                Flow::Again
            }
            Err(_) => Flow::Stop(Termination::SurfaceComplete),
        }
    }

    fn reach_segment(&mut self, s: SegmentId) -> Flow {
        self.state.segment = Some(s);
        self.state.path = None;
        self.state.edge = None;
        self.state.follow = None;
        self.state.gap = None;
        self.state.mode = if self
            .model
            .segment(s)
            .is_some_and(|g| g.as_point().is_some())
        {
            self.state.point = None;
            Mode::Point
        } else {
            Mode::Segment
        };
        self.reset_progress();
        Flow::Again
    }

    /// Eq. 6 with the rule that keeps the control point outside the planes of
    /// the segments the followed edge belongs to (Fig. 29, Fig. 30).
    fn towards_and_along(
        &self,
        cp: &Point3,
        e: &EdgeRef,
        along: &Vector3,
        owners: &[SegmentId],
    ) -> Directive {
        for &s in owners {
            if let Some(poly) = self.model.polygon(s)
                && poly.plane().signed_distance(cp) < 0.0
            {
                let (q, feature) = closest_on_perimeter(poly, cp);
                if let Feature::Edge(i) = feature
                    && let Some((a, b)) = poly.edge_points(i)
                {
                    let v1 = cp - q;
                    let v2 = b - a;
                    let s = v1.cross(&v2);
                    if s.norm() > 1e-12 {
                        return Directive {
                            dir: s,
                            step_limit: None,
                        };
                    }
                }
            }
        }
        let foot = e.segment3().closest_point(cp);
        let v1 = foot - cp;
        let d = v1.norm();
        let (delta, rho) = (self.config.desired_distance_m, self.config.stray_m);
        let r = if d <= delta {
            0.0
        } else if d < rho {
            (d - delta) / (rho - delta)
        } else {
            1.0
        };
        let u1 = if d > 1e-12 { v1 / d } else { Vector3::zeros() };
        let n2 = along.norm();
        let u2 = if n2 > 1e-12 {
            along / n2
        } else {
            Vector3::zeros()
        };
        Directive {
            dir: u1 * r + u2 * (1.0 - r),
            step_limit: None,
        }
    }

    /// Current segment following (P§3.4.2).
    fn segment_following(&mut self, cp: &Point3) -> Flow {
        let Some(seg) = self.state.segment else {
            self.state.mode = Mode::Surface;
            return Flow::Again;
        };
        let Some(segment) = self.model.segment(seg) else {
            self.state.segment = None;
            self.state.mode = Mode::Surface;
            return Flow::Again;
        };
        if segment.as_point().is_some() {
            return self.reach_segment(seg);
        }
        let edges = self.edges_of(seg);
        if edges.is_empty() || self.segment_complete(seg) {
            self.state.mode = Mode::Surface;
            self.state.path = None;
            return Flow::Again;
        }
        let n = edges.len();
        let position = |key: EdgeKey| edges.iter().position(|e| e.key == key);
        let current = self.state.edge.and_then(position);
        let current_ok = current.is_some_and(|i| !self.edge_complete(&edges[i]));
        let nearest = (0..n)
            .min_by(|&i, &j| {
                edges[i]
                    .distance_to(cp)
                    .total_cmp(&edges[j].distance_to(cp))
                    .then(i.cmp(&j))
            })
            .unwrap_or(0);
        let mut ce = match current {
            Some(i) if current_ok => i,
            _ => {
                // The incomplete edge closest to f via the perimeter.
                let perimeter = Perimeter::new(&edges);
                let pick = (0..n)
                    .filter(|&i| !self.edge_complete(&edges[i]))
                    .map(|i| (perimeter.distance(nearest, i), i))
                    .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
                    .map(|(_, i)| i);
                let Some(i) = pick else {
                    self.state.mode = Mode::Surface;
                    self.state.path = None;
                    return Flow::Again;
                };
                if edges[i].length() <= 1e-9 {
                    // Zero-length edges are marked unclosable (P§3.4.2).
                    self.marks.unclosable_edges.insert(edges[i].key);
                    return Flow::Again;
                }
                self.set_current_edge(&edges[i]);
                self.state.follow = Some(edges[nearest].key);
                self.state.anticlockwise = shorter_anticlockwise(nearest, i, n, &edges);
                self.reset_progress();
                i
            }
        };
        let mut follow = if let Some(f) = self.state.follow.and_then(position) {
            f
        } else {
            self.state.follow = Some(edges[nearest].key);
            self.state.anticlockwise = shorter_anticlockwise(nearest, ce, n, &edges);
            self.reset_progress();
            nearest
        };
        // Advance the follow edge towards the current edge in the current
        // direction: the furthest within ρ.
        let rho = self.config.stray_m;
        let mut k = follow;
        let mut best = follow;
        for _ in 0..n {
            if edges[k].distance_to(cp) < rho {
                best = k;
            }
            if k == ce {
                break;
            }
            k = if self.state.anticlockwise {
                (k + 1) % n
            } else {
                (k + n - 1) % n
            };
        }
        if best != follow {
            follow = best;
            self.state.follow = Some(edges[follow].key);
            self.reset_progress();
        }
        if self.state.any_edge && follow != ce && !self.edge_complete(&edges[follow]) {
            self.set_current_edge(&edges[follow]);
            ce = follow;
        }
        if follow == ce {
            self.state.mode = Mode::Edge;
            return Flow::Again;
        }
        let e = edges[follow];
        let along = if self.state.anticlockwise {
            e.b - e.a
        } else {
            e.a - e.b
        };
        Flow::Go(self.towards_and_along(cp, &e, &along, &[seg]))
    }

    /// Choose `e` as the current edge, testing whether the slice line can be
    /// kept (P§3.4.3, Fig. 33).
    fn set_current_edge(&mut self, e: &EdgeRef) {
        let lambda = self.model.config().lambda;
        let width = 0.5 * lambda;
        let retained = self.state.slices.as_ref().is_some_and(|line| {
            let same_segment = self.state.edge_segment == Some(e.segment);
            let near =
                (e.a - line.foot(&e.a)).norm() < lambda && (e.b - line.foot(&e.b)).norm() < lambda;
            let dir = e.b - e.a;
            let aligned =
                unit(dir).is_some_and(|d| d.dot(&line.dir) > std::f64::consts::FRAC_PI_4.cos());
            let (ka, kb) = slice_range(line, e, width);
            let any_used = (ka..=kb).any(|k| line.used.contains(&k));
            same_segment && near && aligned && any_used
        });
        if !retained {
            let dir = unit(e.b - e.a).unwrap_or_else(Vector3::x_axis);
            self.state.slices = Some(SliceLine {
                point: e.a,
                dir,
                used: BTreeSet::new(),
            });
            self.state.any_edge = true;
        }
        self.state.edge = Some(e.key);
        self.state.edge_segment = Some(e.segment);
        self.state.slice = None;
    }

    fn slice_used(&mut self) {
        if let (Some(line), Some(k)) = (self.state.slices.as_mut(), self.state.slice.take()) {
            line.used.insert(k);
        }
        self.state.any_edge = false;
    }

    /// Current edge following (P§3.4.3).
    fn edge_following(&mut self, cp: &Point3, closest: &ModelPoint) -> Flow {
        let Some(key) = self.state.edge else {
            self.state.mode = Mode::Segment;
            return Flow::Again;
        };
        let Some(e) = edge_by_key(&self.model, key, self.state.segment) else {
            self.state.edge = None;
            self.state.mode = Mode::Segment;
            return Flow::Again;
        };
        if self.edge_complete(&e) {
            self.state.edge = None;
            self.state.mode = Mode::Segment;
            return Flow::Again;
        }
        let lambda = self.model.config().lambda;
        let width = 0.5 * lambda;
        let rho = self.config.stray_m;
        for _ in 0..64 {
            let Some(line) = self.state.slices.clone() else {
                self.set_current_edge(&e);
                continue;
            };
            let (ka, kb) = slice_range(&line, &e, width);
            if self
                .state
                .slice
                .is_none_or(|k| line.used.contains(&k) || k < ka || k > kb)
            {
                // Choose the current slice: unused, through the edge, next to
                // a used one when there is one (used slices grow as a block).
                let unused: Vec<i64> = (ka..=kb).filter(|k| !line.used.contains(k)).collect();
                if unused.is_empty() {
                    self.marks.unclosable_edges.insert(key);
                    self.state.edge = None;
                    self.state.mode = Mode::Segment;
                    return Flow::Again;
                }
                let adjacent: Vec<i64> = unused
                    .iter()
                    .copied()
                    .filter(|k| line.used.contains(&(k - 1)) || line.used.contains(&(k + 1)))
                    .collect();
                let pool = if adjacent.is_empty() {
                    &unused
                } else {
                    &adjacent
                };
                let at = (line.param(cp) / width).floor() as i64;
                let k = pool
                    .iter()
                    .copied()
                    .min_by_key(|k| ((k - at).abs(), *k))
                    .unwrap_or(ka);
                self.state.slice = Some(k);
                self.state.approaching = true;
                self.reset_progress();
            }
            let Some(k) = self.state.slice else {
                continue;
            };
            let current_point = Self::current_point(&line, &e, k, width);
            if self.little_unexposed(&e, &line, &current_point, lambda) {
                self.slice_used();
                continue;
            }
            let d = (cp - current_point).norm();
            if d > rho {
                if self.state.approaching {
                    return Flow::Go(Directive {
                        dir: current_point - cp,
                        step_limit: None,
                    });
                }
                self.slice_used();
                continue;
            }
            self.state.approaching = false;
            let t = line.param(cp);
            let (lo, hi) = (k as Real * width, (k + 1) as Real * width);
            if t >= lo && t < hi {
                if self.outside_edge(closest, &e, &line) {
                    let targets = self.gap_targets(&current_point, closest, lambda);
                    self.state.gap = Some(Gap {
                        from: Mode::Edge,
                        targets,
                        next: 0,
                        sensor: None,
                        steps_on_target: 0,
                    });
                    self.state.mode = Mode::Gap;
                    return Flow::Again;
                }
                let u = cp - line.foot(cp);
                return Flow::Go(Directive {
                    dir: line.dir.cross(&u),
                    step_limit: None,
                });
            }
            let centre = 0.5 * (lo + hi);
            let off = centre - t;
            return Flow::Go(Directive {
                dir: line.dir.into_inner() * off.signum(),
                step_limit: (off.abs() < self.config.max_step_m).then_some(off.abs()),
            });
        }
        self.state.mode = Mode::Segment;
        Flow::Again
    }

    /// The current edge point nearest the centre of slice `k`.
    fn current_point(line: &SliceLine, e: &EdgeRef, k: i64, width: Real) -> Point3 {
        let centre = (k as Real + 0.5) * width;
        let (ta, tb) = (line.param(&e.a), line.param(&e.b));
        if (tb - ta).abs() < 1e-12 {
            return Point3::from((e.a.coords + e.b.coords) * 0.5);
        }
        let s = ((centre - ta) / (tb - ta)).clamp(0.0, 1.0);
        e.segment3().point_at(s)
    }

    /// Whether model point `c` lies outside the current edge (P§3.4.3, Fig. 32).
    fn outside_edge(&self, c: &ModelPoint, e: &EdgeRef, line: &SliceLine) -> bool {
        if c.segment != e.segment {
            return true;
        }
        let Some(poly) = self.model.polygon(e.segment) else {
            return true;
        };
        let (ta, tb) = (line.param(&e.a), line.param(&e.b));
        let t = line.param(&c.point);
        if !(t > ta.min(tb) && t < ta.max(tb)) {
            return false;
        }
        let dir = e.b - e.a;
        let q = c.point - e.segment3().closest_point(&c.point);
        dir.cross(&poly.normal()).dot(&q) > 1e-12
    }

    /// The slice holds little unexposed surface: part of the model outside
    /// the current edge within λ/2 of the current point (P§3.4.3).
    fn little_unexposed(
        &self,
        e: &EdgeRef,
        line: &SliceLine,
        current_point: &Point3,
        lambda: Real,
    ) -> bool {
        let radius = 0.5 * lambda;
        let mut ids = self.model.segments_near(current_point, radius);
        ids.sort_unstable();
        for id in ids {
            if id == e.segment {
                // Other perimeter parts of the current segment that lie
                // outside the current edge.
                let Some(poly) = self.model.polygon(id) else {
                    continue;
                };
                for i in 0..poly.len() {
                    if i == e.index {
                        continue;
                    }
                    if let Some((a, b)) = poly.edge_points(i) {
                        let q = Segment3::new(a, b).closest_point(current_point);
                        if (q - current_point).norm() < radius {
                            let c = ModelPoint {
                                segment: id,
                                point: q,
                                distance: 0.0,
                                feature: Feature::Edge(i),
                            };
                            if self.outside_edge(&c, e, line) {
                                return true;
                            }
                        }
                    }
                }
            } else if let Some(c) = closest_on_segment(&self.model, id, current_point)
                && c.distance < radius
            {
                return true;
            }
        }
        false
    }

    /// Target points of gap following (P§3.4.5, Fig. 35–36), from the gap
    /// point towards the current point every λ/2.
    fn gap_targets(
        &self,
        current_point: &Point3,
        closest: &ModelPoint,
        lambda: Real,
    ) -> Vec<Point3> {
        let gap_point = match self.model.polygon(closest.segment) {
            None => closest.point,
            Some(poly) => {
                let projected = poly.plane().project(current_point);
                let frame = poly.frame();
                let pts = poly.points_2d(&frame);
                let (p2, c2) = (frame.to_2d(&projected), frame.to_2d(&closest.point));
                let n = pts.len();
                let mut best: Option<(Real, Point3)> = None;
                for i in 0..n {
                    let hit = match polygon2::intersect_segments(
                        &p2,
                        &c2,
                        &pts[i],
                        &pts[(i + 1) % n],
                        1e-12,
                    ) {
                        polygon2::SegmentIntersection::Point { s, .. } => Some(s),
                        polygon2::SegmentIntersection::Overlap { s0, .. } => Some(s0),
                        polygon2::SegmentIntersection::None => None,
                    };
                    if let Some(s) = hit {
                        let x = frame.to_3d(&(p2 + (c2 - p2) * s));
                        let d = (x - projected).norm();
                        if best.is_none_or(|b| d < b.0) {
                            best = Some((d, x));
                        }
                    }
                }
                best.map_or(closest.point, |b| b.1)
            }
        };
        let span = current_point - gap_point;
        let len = span.norm();
        let spacing = 0.5 * lambda;
        let count = (len / spacing).floor() as usize + 1;
        (0..count.min(1000))
            .map(|i| {
                if len > 0.0 {
                    gap_point + span * ((i as Real * spacing) / len)
                } else {
                    gap_point
                }
            })
            .collect()
    }

    /// Point following (P§3.4.4).
    fn point_following(&mut self, cp: &Point3, closest: &ModelPoint) -> Flow {
        let Some(seg) = self.state.segment else {
            self.state.mode = Mode::Surface;
            return Flow::Again;
        };
        let Some(point) = self.model.segment(seg).and_then(|s| s.as_point().copied()) else {
            // It became a planar polygon: on to its edges; the slice line is
            // not retained.
            self.state.point = None;
            self.state.edge = None;
            self.state.slices = None;
            self.state.mode = Mode::Segment;
            return Flow::Again;
        };
        let c = point.centroid();
        if self.state.point.as_ref().is_none_or(|p| p.centre != c) {
            let towards = cp - c;
            let n = unit(towards).unwrap_or_else(Vector3::z_axis);
            let helper = if n.x.abs() < 0.9 {
                Vector3::x()
            } else {
                Vector3::y()
            };
            let v1 = unit(n.cross(&helper)).unwrap_or_else(Vector3::x_axis);
            let v3 = unit(n.cross(&v1)).unwrap_or_else(Vector3::y_axis);
            let used = self.state.point.as_ref().map_or([false; 4], |p| p.used);
            self.state.point = Some(PointSlices {
                centre: c,
                dirs: [v1, -v1, v3, -v3],
                used,
                current: None,
            });
        }
        let Some(ps) = self.state.point.as_mut() else {
            return Flow::Again;
        };
        if ps.current.is_none() {
            if let Some(k) = (0..4).find(|&k| !ps.used[k]) {
                ps.current = Some(k);
                self.reset_progress();
            } else {
                self.marks.unclosable_points.insert(seg);
                self.state.point = None;
                self.state.mode = Mode::Surface;
                return Flow::Again;
            }
        }
        let Some(ps) = self.state.point.clone() else {
            return Flow::Again;
        };
        let Some(k) = ps.current else {
            return Flow::Again;
        };
        // A departure made explicit: Pudney puts no limit on the distance
        // along a point-following slice; we deem it used beyond ρ, as in
        // current edge following, so a point that never grows cannot hold the
        // robot forever.
        if (cp - c).norm() > self.config.stray_m {
            if let Some(p) = self.state.point.as_mut() {
                p.used[k] = true;
                p.current = None;
            }
            return Flow::Again;
        }
        if closest.segment != seg {
            let lambda = self.model.config().lambda;
            let targets = self.gap_targets(&c, closest, lambda);
            self.state.gap = Some(Gap {
                from: Mode::Point,
                targets,
                next: 0,
                sensor: None,
                steps_on_target: 0,
            });
            self.state.mode = Mode::Gap;
            return Flow::Again;
        }
        let v = ps.dirs[k];
        let foot = c + v.into_inner() * (cp - c).dot(&v);
        let u = cp - foot;
        Flow::Go(Directive {
            dir: v.cross(&u),
            step_limit: None,
        })
    }

    /// Gap following (P§3.4.5).
    fn gap_following(&mut self, cp: &Point3) -> Flow {
        let Some(gap) = self.state.gap.clone() else {
            self.state.mode = Mode::Segment;
            return Flow::Again;
        };
        let lambda = self.model.config().lambda;
        match gap.from {
            Mode::Point => {
                let still_point = self
                    .state
                    .segment
                    .and_then(|s| self.model.segment(s))
                    .is_some_and(|s| s.as_point().is_some());
                if !still_point {
                    self.state.gap = None;
                    self.state.edge = None;
                    self.state.mode = Mode::Segment;
                    return Flow::Again;
                }
            }
            _ => {
                if self.state.edge.is_none() {
                    self.state.gap = None;
                    self.state.mode = Mode::Segment;
                    return Flow::Again;
                }
            }
        }
        let mut gap = gap;
        loop {
            let Some(&target) = gap.targets.get(gap.next) else {
                // All targets used: the gap was not closed.
                self.state.gap = None;
                if gap.from == Mode::Point {
                    if let Some(p) = self.state.point.as_mut()
                        && let Some(k) = p.current.take()
                    {
                        p.used[k] = true;
                    }
                    self.state.mode = Mode::Point;
                } else {
                    self.slice_used();
                    self.state.follow = None;
                    self.state.mode = Mode::Segment;
                }
                return Flow::Again;
            };
            // Detection counts from the sets taken after the target was
            // chosen: the set in hand was taken before the sensor was aimed
            // (and the gap point itself is a model point, sensed already).
            let detected = gap.steps_on_target > 0
                && self
                    .last_points
                    .iter()
                    .any(|p| (p - target).norm() < 0.5 * lambda);
            let patience = self.config.target_patience_steps;
            if detected || (patience > 0 && gap.steps_on_target >= patience) {
                gap.next += 1;
                gap.sensor = None;
                gap.steps_on_target = 0;
                continue;
            }
            if gap.sensor.is_none() {
                gap.sensor = self.controlled_sensor(&target);
                self.reset_progress();
            }
            let Some(sensor) = gap.sensor else {
                gap.next += 1;
                continue;
            };
            let Some(axis_point) = self.axis_point(sensor, &target) else {
                gap.next += 1;
                gap.sensor = None;
                continue;
            };
            let dir = target - axis_point;
            let d = dir.norm();
            // A gap we fill (P§3.4.5 gives up a target "after some time"):
            // once the controlled sensor's axis passes within `AIM` of the
            // target at the pose the set in hand was taken from, that set is
            // what aiming at the target yields, and with the sensor on target
            // the robot stands still (σ ≤ d), so later sets repeat it. No
            // point near the target in it: give the target up now rather
            // than idle until the progress check (P§3.4.7) or the patience.
            if d < AIM_FRACTION * lambda {
                gap.next += 1;
                gap.sensor = None;
                gap.steps_on_target = 0;
                continue;
            }
            gap.steps_on_target += 1;
            self.state.gap = Some(gap);
            let _ = cp;
            return Flow::Go(Directive {
                dir,
                step_limit: (d < self.config.max_step_m).then_some(d),
            });
        }
    }

    /// The control-point sensor whose sensing axis is closest to `target`.
    fn controlled_sensor(&self, target: &Point3) -> Option<usize> {
        self.cp_sensors
            .iter()
            .filter_map(|&i| self.axis_point(i, target).map(|p| ((p - target).norm(), i)))
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
            .map(|(_, i)| i)
    }

    /// The point of sensor `i`'s sensing axis (origin to range) closest to
    /// `target`, at the current pose.
    fn axis_point(&self, i: usize, target: &Point3) -> Option<Point3> {
        let m = self.robot.range_finders.get(i)?;
        let frame = self.frames.get(m.link.0)?;
        let o = frame * m.origin;
        let a = frame.rotation * m.axis;
        Some(Segment3::new(o, o + a.into_inner() * m.max_range_m).closest_point(target))
    }
}

/// Gap following deems the controlled sensor aimed at its target when its
/// sensing axis passes within this fraction of λ of it (λ/20 = 2.5 mm at
/// Pudney's λ; the detection radius is λ/2).
const AIM_FRACTION: Real = 0.05;

/// Lengths of the anticlockwise and clockwise routes along a perimeter of
/// `n` edges from edge `from` to edge `to` (the edges passed on the way and
/// `to` itself).
fn routes(from: usize, to: usize, n: usize, edges: &[EdgeRef]) -> (Real, Real) {
    let mut ccw = 0.0;
    let mut k = from;
    while k != to {
        k = (k + 1) % n;
        ccw += edges[k].length();
    }
    let mut cw = 0.0;
    let mut k = from;
    while k != to {
        k = (k + n - 1) % n;
        cw += edges[k].length();
    }
    (ccw, cw)
}

/// Cumulative edge lengths of a perimeter, for route lengths in O(1).
struct Perimeter {
    /// `cum[k]`: total length of edges `0..k`.
    cum: Vec<Real>,
}

impl Perimeter {
    fn new(edges: &[EdgeRef]) -> Self {
        let mut cum = Vec::with_capacity(edges.len() + 1);
        let mut total = 0.0;
        cum.push(0.0);
        for e in edges {
            total += e.length();
            cum.push(total);
        }
        Self { cum }
    }

    /// Distance from edge `from` to edge `to` via the perimeter, the shorter
    /// way (as [`routes`] counts it: the edges passed and `to` itself).
    fn distance(&self, from: usize, to: usize) -> Real {
        let total = self.cum[self.cum.len() - 1];
        // Anticlockwise: edges from+1 ..= to (wrapping).
        let ccw = if to >= from {
            self.cum[to + 1] - self.cum[from + 1]
        } else {
            total - self.cum[from + 1] + self.cum[to + 1]
        };
        // Clockwise: edges to ..= from-1 (wrapping).
        let cw = if from >= to {
            self.cum[from] - self.cum[to]
        } else {
            total - self.cum[to] + self.cum[from]
        };
        ccw.min(cw)
    }
}

/// Whether the anticlockwise route from edge `from` to edge `to` is the
/// shorter (by length) of the two.
fn shorter_anticlockwise(from: usize, to: usize, n: usize, edges: &[EdgeRef]) -> bool {
    let (ccw, cw) = routes(from, to, n, edges);
    ccw <= cw
}

/// Slice numbers through edge `e` (inclusive range).
fn slice_range(line: &SliceLine, e: &EdgeRef, width: Real) -> (i64, i64) {
    let (ta, tb) = (line.param(&e.a), line.param(&e.b));
    let lo = (ta.min(tb) / width).floor() as i64;
    let hi = ((ta.max(tb) / width).ceil() as i64 - 1).max(lo);
    (lo, hi)
}

/// Counts per mode, for run summaries.
pub type ModeCounts = BTreeMap<Mode, u64>;

#[cfg(test)]
mod tests {
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
    fn floor_follower() -> (Follower, SegmentId) {
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
