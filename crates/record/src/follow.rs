//! The files of a surface-following run (`surveyor follow`) that record
//! owns: the steps (`steps.csv`, [`StepRow`]), the control-point path
//! (`path.ply`) and the summary (`run.json`, [`FollowSummary`]); the
//! model's own files are `surface`'s layout, written through
//! [`crate::folder`].

use crate::RecordError;
use crate::table::Table;
use geom::{Point3, Real};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;
use surface::{EdgeKey, SegmentId};

/// One row per step.
pub const STEPS_CSV: &str = "steps.csv";
/// The control-point path.
pub const PATH_PLY: &str = "path.ply";
/// The model (`surface::ModelJson`).
pub const SURFACE_MODEL_JSON: &str = "surface_model.json";
/// The model as a mesh.
pub const SURFACE_MODEL_OBJ: &str = "surface_model.obj";

/// Time spent in one step of the follower, microseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StepTimes {
    /// Surface-model update.
    pub update_us: Real,
    /// Change tracking and the direction algorithm.
    pub direction_us: Real,
    /// Control-point motion, link proximities and actuator changes.
    pub kinematics_us: Real,
}

impl StepTimes {
    /// The step's whole time.
    pub fn total_us(&self) -> Real {
        self.update_us + self.direction_us + self.kinematics_us
    }
}

/// `run.json`'s `robot_time_s` of a surface-following run, seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FollowRobotTime {
    /// All of it: the steps' robot times added up.
    pub total: Real,
    /// Moving between the steps' poses.
    pub moving: Real,
    /// Standing to read the range finders.
    pub sensing: Real,
    /// Standing while the follower decides (wall time, or a stated figure
    /// per step with timings off).
    pub deciding: Real,
}

impl FollowRobotTime {
    /// The summary of a robot clock's split (`hw::clock::RobotClock`,
    /// read with `robot::timing::RobotTime`): a follower reads its sensors
    /// standing, as a sweep does.
    pub fn of(spent: &robot::timing::RobotTime) -> Self {
        Self {
            total: spent.total_s(),
            moving: spent.moving_s + spent.moving_while_scanning_s,
            sensing: spent.standing_to_sweep_s,
            deciding: spent.deciding_s,
        }
    }
}

impl std::fmt::Display for FollowRobotTime {
    /// `1907 s (moving 1839 s, sensing 65 s, deciding 3 s)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:.0} s (moving {:.0} s, sensing {:.0} s, deciding {:.0} s)",
            self.total, self.moving, self.sensing, self.deciding
        )
    }
}

/// One step of a run (a row of `steps.csv`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepRow {
    /// 0-based step number.
    pub step: u64,
    /// The name of the motion mode that produced the direction (`surface`,
    /// `segment`, `edge`, `point`, `gap`).
    pub mode: String,
    /// The control point when the set was taken (world frame).
    pub control_point: Point3,
    /// The joints when the set was taken.
    pub joints: Vec<Real>,
    /// Sensor points in the set.
    pub set_size: usize,
    /// Wall time of the step's parts (`None`: not recorded).
    pub times: Option<StepTimes>,
    /// The follower's link clearance from the model (within its influence
    /// distance), metres.
    pub link_clearance_m: Option<Real>,
    /// The current segment.
    pub current_segment: Option<SegmentId>,
    /// The current edge.
    pub current_edge: Option<EdgeKey>,
    /// The step's robot time (the reading, the decision, the motion), by
    /// the robot clock (`hw::clock`), seconds.
    #[serde(default)]
    pub robot_time_s: Real,
}

/// `steps.csv`: `step,mode,x,y,z,q1..q{dof},set_size,update_us,direction_us,
/// kinematics_us,link_clearance_m,current_segment,current_edge,robot_time_s`; empty
/// fields for no value (the times when they were not recorded).
pub fn steps_csv(rows: &[StepRow], dof: usize) -> String {
    let mut out = String::from("step,mode,x,y,z");
    for i in 1..=dof {
        let _ = write!(out, ",q{i}");
    }
    out.push_str(
        ",set_size,update_us,direction_us,kinematics_us,link_clearance_m,current_segment,current_edge,\
         robot_time_s\n",
    );
    let opt = |v: Option<String>| v.unwrap_or_default();
    for r in rows {
        let p = r.control_point;
        let _ = write!(out, "{},{},{},{},{}", r.step, r.mode, p.x, p.y, p.z);
        for q in &r.joints {
            let _ = write!(out, ",{q}");
        }
        let _ = write!(out, ",{}", r.set_size);
        match &r.times {
            Some(t) => {
                let _ = write!(
                    out,
                    ",{:.3},{:.3},{:.3}",
                    t.update_us, t.direction_us, t.kinematics_us
                );
            }
            None => out.push_str(",,,"),
        }
        let _ = writeln!(
            out,
            ",{},{},{},{}",
            opt(r.link_clearance_m.map(|v| v.to_string())),
            opt(r.current_segment.map(|s| s.0.to_string())),
            opt(r.current_edge.map(|e| e.0.to_string())),
            r.robot_time_s
        );
    }
    out
}

/// Read `steps.csv` back (the times to the nanosecond, as written).
pub fn read_steps(path: &Path) -> Result<Vec<StepRow>, RecordError> {
    let t = Table::read(path)?;
    let step = t.indices("step")?;
    let mode = t.text("mode")?;
    let [x, y, z] = [t.numbers("x")?, t.numbers("y")?, t.numbers("z")?];
    let joints = crate::viewpoints::joint_columns(&t)?;
    let set_size = t.indices("set_size")?;
    let times = [
        t.optional("update_us")?,
        t.optional("direction_us")?,
        t.optional("kinematics_us")?,
    ];
    let clearance = t.optional("link_clearance_m")?;
    let segment = t.optional_indices("current_segment")?;
    let edge = t.optional_indices("current_edge")?;
    // Runs written before the robot clock have no robot time.
    let robot_time = if t.has("robot_time_s") {
        t.numbers("robot_time_s")?
    } else {
        vec![0.0; t.len()]
    };
    let id = |v: Option<usize>, what: &str, line: usize| -> Result<Option<u32>, RecordError> {
        v.map(|v| {
            u32::try_from(v).map_err(|_| RecordError::Field {
                file: t.source.clone(),
                line,
                field: what.to_owned(),
                message: format!("expected an id below 2^32, found {v}"),
            })
        })
        .transpose()
    };
    (0..t.len())
        .map(|i| {
            let times = match (times[0][i], times[1][i], times[2][i]) {
                (Some(u), Some(d), Some(k)) => Some(StepTimes {
                    update_us: u,
                    direction_us: d,
                    kinematics_us: k,
                }),
                _ => None,
            };
            Ok(StepRow {
                step: step[i] as u64,
                mode: mode[i].to_owned(),
                control_point: Point3::new(x[i], y[i], z[i]),
                joints: joints[i].clone(),
                set_size: set_size[i],
                times,
                link_clearance_m: clearance[i],
                current_segment: id(segment[i], "current_segment", i + 2)?.map(SegmentId),
                current_edge: id(edge[i], "current_edge", i + 2)?.map(EdgeKey),
                robot_time_s: robot_time[i],
            })
        })
        .collect()
}

/// `path.ply`: the control point at every step, then where the run ended
/// (when that differs from the last step's), as ASCII PLY vertices joined
/// by edges in order.
pub fn path_ply(rows: &[StepRow], end_control_point: &Point3) -> String {
    let mut pts: Vec<Point3> = rows.iter().map(|r| r.control_point).collect();
    if pts.last() != Some(end_control_point) {
        pts.push(*end_control_point);
    }
    let edges = pts.len().saturating_sub(1);
    let mut out = format!(
        "ply\nformat ascii 1.0\ncomment surveyor follow: control-point path ({} steps)\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nelement edge {edges}\nproperty int vertex1\nproperty int vertex2\nend_header\n",
        rows.len(),
        pts.len()
    );
    for p in &pts {
        let _ = writeln!(out, "{} {} {}", p.x, p.y, p.z);
    }
    for i in 0..edges {
        let _ = writeln!(out, "{} {}", i, i + 1);
    }
    out
}

/// A ground-truth contact during a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Collision {
    /// The step whose motion touched the scene (`None`: the start pose).
    pub step: Option<u64>,
    /// Name of the link.
    pub link: String,
    /// Where along the step's joint motion (`0` start, `1` end).
    pub t: Real,
}

/// Mean, median and 95th percentile of step times, microseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StepTimeStats {
    /// Mean.
    pub mean: Real,
    /// Median.
    pub median: Real,
    /// 95th percentile (nearest rank).
    pub p95: Real,
}

impl StepTimeStats {
    /// Summarise samples (zeros for none).
    pub fn from_micros(samples: &[Real]) -> Self {
        if samples.is_empty() {
            return Self::default();
        }
        let t = surface::UpdateTimes::from_micros(samples);
        Self {
            mean: samples.iter().sum::<Real>() / samples.len() as Real,
            median: t.median,
            p95: t.p95,
        }
    }
}

/// What the surface follower's safety guard (`follow::guard`) did with the
/// steps' actuator changes, counted over a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GuardCounts {
    /// Changes taken as they were.
    pub taken: u64,
    /// Changes scaled down.
    pub scaled: u64,
    /// Retreats instead of the change.
    pub retreated: u64,
    /// Steps held still.
    pub held: u64,
}

/// `run.json` of a surface-following run. `O` is the run's options, `S` the
/// model's score against a true scene and `M` its distances to a scan
/// (`sim`'s types); a reader that only shows them takes the defaults,
/// [`serde_json::Value`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FollowSummary<O = serde_json::Value, S = serde_json::Value, M = serde_json::Value> {
    /// Version of the run folder's format ([`crate::FORMAT_VERSION`]).
    pub format_version: u32,
    /// The scenario name, or the scene file.
    pub scenario: String,
    /// The robot.
    pub robot: String,
    /// Seed of the range noise.
    pub seed: u64,
    /// Sensor sets taken (one per step).
    pub sets: usize,
    /// Of which sets without any point.
    pub empty_sets: usize,
    /// Follower steps (rows of `steps.csv`).
    pub steps: usize,
    /// The follower reported the current surface complete.
    pub completed: bool,
    /// Why the run ended (the follower's termination, `max_sets`,
    /// `interrupted` or `error`).
    pub termination: String,
    /// The error that ended the run, when it was one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Poses or motions with a ground-truth contact: the start pose, and each
    /// step whose motion or end pose touched the scene (`null` without a mesh
    /// ground truth).
    pub collisions: Option<usize>,
    /// The contacts (per link at a pose, the first along a motion).
    pub collision_list: Vec<Collision>,
    /// Smallest ground-truth clearance of the links, metres.
    pub min_clearance_m: Option<Real>,
    /// Point-cloud worlds: smallest distance of the link capsules from the
    /// scan points over the poses visited, metres (`null` for mesh worlds).
    pub min_scan_clearance_m: Option<Real>,
    /// Point-cloud worlds: poses at which a link capsule came closer than
    /// δ/2 to a scan point (`null` for mesh worlds).
    pub scan_close_poses: Option<usize>,
    /// Point-cloud worlds: the largest distance from a non-initial model
    /// polygon to the nearest scan point, metres.
    pub model_to_scan_max_m: Option<Real>,
    /// Point-cloud worlds: the area fraction of the non-initial model
    /// polygons within λ of a scan point.
    pub model_to_scan_within_lambda: Option<Real>,
    /// Configurations checked along the motions.
    pub motion_checks: usize,
    /// Outward normals of the true faces the robot cannot reach from where
    /// it stands, given a priori as initial segments and not scored.
    #[serde(default)]
    pub a_priori_faces: Vec<[Real; 3]>,
    /// What the safety guard did (all zero when it is off).
    #[serde(default)]
    pub guard: GuardCounts,
    /// Surface area modelled, m²: in a mesh world the counted faces' area
    /// within λ of a model polygon; in a point-cloud world the non-initial
    /// model polygons' area within λ of a scan point.
    #[serde(default)]
    pub modelled_m2: Option<Real>,
    /// Sets taken per square metre modelled (`sets / modelled_m2`; `null`
    /// when nothing is modelled or there is nothing to judge it by).
    #[serde(default)]
    pub sets_per_m2: Option<Real>,
    /// Wall time per step (update + direction + kinematics), µs.
    pub step_us: StepTimeStats,
    /// The robot time of the run (the steps' sum; the robot clock,
    /// `hw::clock`): in all and per activity, seconds.
    #[serde(default)]
    pub robot_time_s: FollowRobotTime,
    /// Mean time of each part of a step, µs.
    pub part_mean_us: StepTimes,
    /// Steps per mode.
    pub modes: BTreeMap<String, u64>,
    /// Start joints.
    pub start_joints: Vec<Real>,
    /// End joints.
    pub end_joints: Vec<Real>,
    /// The model's counts.
    pub model: surface::ModelStats,
    /// The model scored against the ground truth (mesh worlds).
    pub score: Option<S>,
    /// The model's polygons against the scan points, per polygon
    /// (point-cloud worlds).
    pub model_to_scan: Option<M>,
    /// The options (with the configuration in effect).
    pub options: O,
}

impl<O: Serialize, S: Serialize, M: Serialize> FollowSummary<O, S, M> {
    /// `run.json`'s text: pretty JSON in field order, a final newline.
    pub fn to_json(&self) -> Result<String, RecordError> {
        crate::pretty_json(self, crate::explore::RUN_JSON)
    }
}
