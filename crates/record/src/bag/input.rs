//! A robot's bag as input: the laser scans of a bag placed by the robot's
//! joint states ([`sweeps_from_bag`], for `surveyor map --bag`).

use super::msg::{JointState, LaserScan, PointCloud2, TfMessage, Transform};
use super::{
    BadMessages, BagError, BagMessage, ROOT_FRAME, Skipped, read_bag_with, scanner_from_laser,
    topics,
};
use geom::{Isometry3, Real};
use robot::Robot;
use sensor::{Sweep, SweepBuilder};
use std::collections::HashMap;
use std::path::Path;

/// Which topics and frames [`sweeps_from_bag`] reads.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScanTopics {
    /// `sensor_msgs/LaserScan` topic.
    pub scan: String,
    /// `sensor_msgs/JointState` topic.
    pub joints: String,
    /// The robot link whose frame the scans are in (ROS's laser convention:
    /// rays in its x–y plane). `None`: the scans' `frame_id`, a link of the
    /// robot or a frame `/tf_static` places on one.
    pub scanner_link: Option<String>,
}

impl Default for ScanTopics {
    fn default() -> Self {
        Self {
            scan: topics::SCAN.to_owned(),
            joints: topics::JOINT_STATES.to_owned(),
            scanner_link: None,
        }
    }
}

/// Scans placed in the world, grouped into sweeps.
#[derive(Clone, Debug)]
pub struct BagSweeps {
    /// The sweeps, in time order.
    pub sweeps: Vec<Sweep>,
    /// Where the robot's base stands (from `/tf_static`, else identity).
    pub world_from_base: Isometry3,
    /// Whether `world_from_base` came from the bag's `/tf_static`.
    pub base_from_bag: bool,
    /// The link the scanner is on and the laser frame on it.
    pub scanner_link: String,
    /// Scans placed.
    pub scans: usize,
    /// Scans outside the joint states' time span (not placed).
    pub unplaced: usize,
    /// Damaged chunks and bad messages skipped ([`BadMessages::Skip`]).
    pub skipped: Skipped,
}

/// Largest number of scans in one sweep when the bag does not mark sweeps.
pub const MAX_SCANS_PER_SWEEP: usize = 10_000;
/// A pause between scans longer than this starts a new sweep when the bag
/// does not mark sweeps, seconds.
pub const SWEEP_GAP_S: Real = 1.0;

/// The stamp of a message: its header's, or (a zero or negative stamp)
/// when logged. A `nanosec` of 10⁹ or more is refused, not taken as
/// extra seconds.
fn stamp_of(header: &super::msg::Header, log_time_ns: u64) -> Result<u64, String> {
    if header.stamp.nanosec >= 1_000_000_000 {
        return Err(format!(
            "header stamp {} s {} ns: nanosec must be below 10⁹",
            header.stamp.sec, header.stamp.nanosec
        ));
    }
    Ok(match header.stamp.to_nanos() {
        Some(0) | None => log_time_ns,
        Some(t) => t,
    })
}

/// Reads a bag's messages one by one: a bad one refuses the bag, naming
/// it, or is skipped and counted ([`BadMessages`]).
struct Gate<'a> {
    path: &'a Path,
    mode: BadMessages,
    skipped: Skipped,
}

impl Gate<'_> {
    /// `Ok(Some(value))` for a good message, `Ok(None)` for a bad one
    /// skipped, or the error naming it.
    fn check<T>(&mut self, m: &BagMessage, r: Result<T, String>) -> Result<Option<T>, BagError> {
        match r {
            Ok(v) => Ok(Some(v)),
            Err(message) => match self.mode {
                BadMessages::Refuse => Err(BagError::Message {
                    path: self.path.to_owned(),
                    at: m.name(),
                    message,
                }),
                BadMessages::Skip => {
                    self.skipped.add(1, format!("{}: {message}", m.name()));
                    Ok(None)
                }
            },
        }
    }
}

/// `m` decoded as `M`, the decoding error in words.
fn decoded<M: super::msg::RosMessage + serde::de::DeserializeOwned>(
    m: &BagMessage,
) -> Result<M, String> {
    m.decode::<M>().map_err(|e| e.to_string())
}

/// A laser scan's rays must be usable: some ranges, finite bearings, and
/// no NaN intensity.
fn check_scan(scan: &LaserScan) -> Result<(), String> {
    if scan.ranges.is_empty() {
        return Err("a LaserScan without ranges".into());
    }
    if !(scan.angle_min.is_finite() && scan.angle_increment.is_finite()) {
        return Err(format!(
            "bearings not finite (angle_min {}, angle_increment {})",
            scan.angle_min, scan.angle_increment
        ));
    }
    let last = f64::from(scan.angle_min)
        + (scan.ranges.len() - 1) as f64 * f64::from(scan.angle_increment);
    if last.abs() > 4.0 * std::f64::consts::PI
        || f64::from(scan.angle_min).abs() > 4.0 * std::f64::consts::PI
    {
        return Err(format!(
            "bearings from {} to {last} rad, beyond ±4π",
            scan.angle_min
        ));
    }
    if scan.range_min.is_nan() || scan.range_max.is_nan() {
        return Err(format!(
            "range_min {} and range_max {} must be numbers",
            scan.range_min, scan.range_max
        ));
    }
    if let Some(i) = scan.intensities.iter().position(|v| !v.is_finite()) {
        return Err(format!("intensity {i} is {}", scan.intensities[i]));
    }
    Ok(())
}

/// A transform must be finite with a unit quaternion (within tf2's
/// tolerance: its squared norm within 0.01 of 1).
fn check_tf(tf: &TfMessage) -> Result<(), String> {
    for t in &tf.transforms {
        let (v, q) = (&t.transform.translation, &t.transform.rotation);
        let name = format!(
            "the transform of `{}` in `{}`",
            t.child_frame_id, t.header.frame_id
        );
        if !(v.x.is_finite() && v.y.is_finite() && v.z.is_finite()) {
            return Err(format!(
                "{name}: translation ({}, {}, {}) not finite",
                v.x, v.y, v.z
            ));
        }
        let n2 = q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w;
        if !n2.is_finite() || (n2 - 1.0).abs() > 0.01 {
            return Err(format!(
                "{name}: quaternion ({}, {}, {}, {}) is not a unit quaternion",
                q.x, q.y, q.z, q.w
            ));
        }
    }
    Ok(())
}

fn isometry(t: &Transform) -> Isometry3 {
    // `check_tf` has refused a quaternion far from unit length.
    let q = nalgebra::Quaternion::new(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z);
    Isometry3::from_parts(
        nalgebra::Translation3::new(t.translation.x, t.translation.y, t.translation.z),
        nalgebra::UnitQuaternion::from_quaternion(q),
    )
}

/// The laser scans of the bag at `path`, each placed at the scanner pose of
/// `robot` at the joints interpolated (linearly, per joint) to the scan's
/// stamp, grouped into sweeps: at the bag's sweep clouds
/// ([`topics::SWEEP`], which `surveyor` runs write) when it has them, else
/// at pauses longer than [`SWEEP_GAP_S`] and every [`MAX_SCANS_PER_SWEEP`]
/// scans. Ranges outside `[range_min, range_max]` or not finite are no
/// return. Errors name the bag and what is wrong: a missing topic, a joint
/// of the robot missing from the joint states, time going backwards, a
/// scanner frame not on the robot, a damaged chunk, and a bad message (one
/// that does not decode, a stamp's nanosec of 10⁹ or more, a scan without
/// ranges or with bearings or intensities not finite, a joint value not
/// finite or more than [`JOINT_LIMIT_SLACK`] past its limits, a transform
/// not finite or with no unit quaternion), naming its topic, index and log
/// time; with [`BadMessages::Skip`] the bad ones are skipped and counted.
pub fn sweeps_from_bag(
    path: &Path,
    robot: &Robot,
    topics_in: &ScanTopics,
    bad_messages: BadMessages,
) -> Result<BagSweeps, BagError> {
    let bad = |message: String| BagError::Bag {
        path: path.to_owned(),
        message,
    };
    let wanted = |t: &str| {
        t == topics_in.scan || t == topics_in.joints || t == topics::TF_STATIC || t == topics::SWEEP
    };
    let contents = read_bag_with(path, &wanted, bad_messages)?;
    let messages = contents.messages;
    let mut gate = Gate {
        path,
        mode: bad_messages,
        skipped: contents.skipped,
    };
    let on = |t: &str| -> Vec<&BagMessage> { messages.iter().filter(|m| m.topic == t).collect() };
    let mut statics = FrameTree::default();
    for m in on(topics::TF_STATIC) {
        let tf = decoded::<TfMessage>(m).and_then(|tf| check_tf(&tf).map(|()| tf));
        if let Some(tf) = gate.check(m, tf)? {
            statics.apply(tf);
        }
    }
    let states = joint_states(&on(&topics_in.joints), robot, &mut gate)?;
    let mut scans = Vec::new();
    for m in on(&topics_in.scan) {
        let scan = decoded::<LaserScan>(m).and_then(|scan| {
            check_scan(&scan)?;
            let t = stamp_of(&scan.header, m.log_time_ns)?;
            Ok((scan, t))
        });
        if let Some((scan, t)) = gate.check(m, scan)? {
            scans.push((m, scan, t));
        }
    }
    let Some((_, first, _)) = scans.first() else {
        return Err(bad(format!(
            "no `sensor_msgs/msg/LaserScan` on {}",
            topics_in.scan
        )));
    };
    if states.is_empty() {
        return Err(bad(format!(
            "no `sensor_msgs/msg/JointState` on {}",
            topics_in.joints
        )));
    }
    let frame = first.header.frame_id.clone();
    let (link, link_from_laser, link_name) =
        scanner_on(robot, &statics, &frame, topics_in.scanner_link.as_deref()).map_err(&bad)?;
    let link_from_scanner = link_from_laser * scanner_from_laser().inverse();
    // The base in the world: up the static frames from the base link.
    let base = robot.links.first().map_or("", |l| l.name.as_str());
    let placed_base = statics.root_from(base).ok();
    let base_from_bag = placed_base.is_some();
    let world_from_base = placed_base.unwrap_or_else(Isometry3::identity);
    // Sweep boundaries.
    let mut marks = Vec::new();
    for m in on(topics::SWEEP) {
        let t = decoded::<PointCloud2>(m).and_then(|c| stamp_of(&c.header, m.log_time_ns));
        if let Some(t) = gate.check(m, t)? {
            marks.push(t);
        }
    }
    let mut sweeps = Vec::new();
    let mut builder: Option<(SweepBuilder, Vec<Real>)> = None;
    let mut last_t: Option<u64> = None;
    let mut mark = 0;
    let (mut placed, mut unplaced) = (0, 0);
    let mut frames = Vec::new();
    for (m, scan, t) in &scans {
        let t = *t;
        if let Some(prev) = last_t
            && t < prev
        {
            return Err(bad(format!(
                "{}: time goes backwards ({t} ns after {prev} ns)",
                m.name()
            )));
        }
        let Some(q) = joints_at(&states, t) else {
            unplaced += 1;
            continue;
        };
        let (bearings, ranges, intensities) = super::scan_rays(scan);
        // A new sweep at a mark, a pause, a change of bearings or the cap.
        let past_mark = if marks.is_empty() {
            last_t.is_some_and(|p| (t - p) as Real * 1e-9 > SWEEP_GAP_S)
        } else {
            let mut crossed = false;
            while mark < marks.len() && t > marks[mark] {
                mark += 1;
                crossed = true;
            }
            crossed
        };
        last_t = Some(t);
        if let Some((b, old)) = builder.take() {
            if past_mark || *old != bearings || b.scan_count() >= MAX_SCANS_PER_SWEEP {
                if b.scan_count() > 0 {
                    sweeps.push(b.finish()?);
                }
            } else {
                builder = Some((b, old));
            }
        }
        let (b, _) = match &mut builder {
            Some(x) => x,
            None => builder.insert((SweepBuilder::new(&bearings)?, bearings)),
        };
        let mut pose_at = |q: &[Real]| -> Result<Isometry3, BagError> {
            robot.fk_into(q, &mut frames)?;
            Ok(world_from_base * frames[link.0] * link_from_scanner)
        };
        let increment = Real::from(scan.time_increment);
        if increment > 0.0 && ranges.len() > 1 {
            // Taken while the arm moved: each beam at the pose of its own
            // moment, between the states around it.
            let last = t.saturating_add(ns_of(increment * (ranges.len() - 1) as Real));
            let Some(around) = states_over(&states, t, last) else {
                unplaced += 1;
                continue;
            };
            let times: Vec<Real> = around
                .iter()
                .map(|(s, _)| (*s as i128 - t as i128) as Real * 1e-9)
                .collect();
            let poses = around
                .iter()
                .map(|(_, q)| pose_at(q))
                .collect::<Result<Vec<_>, _>>()?;
            let beams =
                robot::moving::interpolate_beams(&times, &poses, 0.0, increment, ranges.len());
            b.push_scan_posed(&beams, &ranges, &intensities, None)?;
        } else {
            b.push_scan(&pose_at(&q)?, &ranges, &intensities, None)?;
        }
        placed += 1;
    }
    if let Some((b, _)) = builder
        && b.scan_count() > 0
    {
        sweeps.push(b.finish()?);
    }
    Ok(BagSweeps {
        sweeps,
        world_from_base,
        base_from_bag,
        scanner_link: link_name,
        scans: placed,
        unplaced,
        skipped: gate.skipped,
    })
}

/// `v` in a message: in exponent form when it is huge or tiny.
fn short(v: Real) -> String {
    if v.is_finite() && v != 0.0 && !(1e-4..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// How far a joint state may pass its joint's limits, radians or metres
/// (encoders read a little past a limit); a value further out, or not
/// finite, is a bad message. Joints without limits may read up to
/// [`MAX_UNLIMITED_JOINT`].
pub const JOINT_LIMIT_SLACK: Real = 0.1;
/// Largest magnitude a joint without limits may read, radians or metres.
pub const MAX_UNLIMITED_JOINT: Real = 1e3;

/// The joint states of `messages` as `(stamp, q)` in the
/// robot's joint order; an error for a missing joint, a length mismatch or
/// time going backwards; a bad message (see [`sweeps_from_bag`]) through
/// `gate`.
fn joint_states(
    messages: &[&BagMessage],
    robot: &Robot,
    gate: &mut Gate<'_>,
) -> Result<Vec<(u64, Vec<Real>)>, BagError> {
    let bad = |message: String| BagError::Bag {
        path: gate.path.to_owned(),
        message,
    };
    let names = robot.joint_names();
    let limits: Vec<_> = robot.actuated().map(|j| j.limits).collect();
    let mut states: Vec<(u64, Vec<Real>)> = Vec::with_capacity(messages.len());
    for m in messages {
        let Some(js) = gate.check(m, decoded::<JointState>(m))? else {
            continue;
        };
        if js.position.len() != js.name.len() {
            return Err(bad(format!(
                "{}: {} names but {} positions",
                m.name(),
                js.name.len(),
                js.position.len()
            )));
        }
        let mut q = Vec::with_capacity(names.len());
        for n in &names {
            let i = js.name.iter().position(|x| x == n).ok_or_else(|| {
                bad(format!(
                    "{} has no joint `{n}` of robot {} (it names {:?})",
                    m.name(),
                    robot.name,
                    js.name
                ))
            })?;
            q.push(js.position[i]);
        }
        let checked = stamp_of(&js.header, m.log_time_ns).and_then(|t| {
            for ((n, v), l) in names.iter().zip(&q).zip(&limits) {
                let ok = match l {
                    Some(l) => {
                        *v >= l.min - JOINT_LIMIT_SLACK && *v <= l.max + JOINT_LIMIT_SLACK
                    }
                    None => v.abs() <= MAX_UNLIMITED_JOINT,
                };
                if !ok {
                    return Err(match l {
                        Some(l) => format!(
                            "joint `{n}` at {}, beyond its limits [{}, {}] by more than {JOINT_LIMIT_SLACK}",
                            short(*v),
                            l.min,
                            l.max
                        ),
                        None => format!(
                            "joint `{n}` at {}, beyond ±{MAX_UNLIMITED_JOINT}",
                            short(*v)
                        ),
                    });
                }
            }
            Ok(t)
        });
        let Some(t) = gate.check(m, checked)? else {
            continue;
        };
        if let Some((last, _)) = states.last()
            && t < *last
        {
            return Err(bad(format!(
                "{}: time goes backwards ({t} ns after {last} ns)",
                m.name()
            )));
        }
        states.push((t, q));
    }
    Ok(states)
}

/// The link the scans of `frame` are on, the laser frame in that link and
/// the link's name: `given` (a link), else `frame` itself when it is a
/// link, else the link `statics` places `frame` on.
fn scanner_on(
    robot: &Robot,
    statics: &FrameTree,
    frame: &str,
    given: Option<&str>,
) -> Result<(robot::LinkId, Isometry3, String), String> {
    if let Some(l) = given {
        let id = robot
            .link_index(l)
            .ok_or_else(|| format!("--scanner-link {l} is not a link of robot {}", robot.name))?;
        return Ok((id, Isometry3::identity(), l.to_owned()));
    }
    if let Some(id) = robot.link_index(frame) {
        return Ok((id, Isometry3::identity(), frame.to_owned()));
    }
    if let Some((parent, t)) = statics.0.get(frame)
        && let Some(id) = robot.link_index(parent)
    {
        return Ok((id, *t, parent.clone()));
    }
    Err(format!(
        "the scans' frame `{frame}` is neither a link of robot {} nor placed on one by {}; give the scanner's link",
        robot.name,
        topics::TF_STATIC
    ))
}

fn ns_of(seconds: Real) -> u64 {
    (seconds.max(0.0) * 1e9).round() as u64
}

/// The states from the last at or before `t0` to the first at or after
/// `t1` (`None` when they do not span the interval).
fn states_over(states: &[(u64, Vec<Real>)], t0: u64, t1: u64) -> Option<&[(u64, Vec<Real>)]> {
    let a = states.partition_point(|(s, _)| *s <= t0).checked_sub(1)?;
    let b = states.partition_point(|(s, _)| *s < t1);
    (b < states.len()).then(|| &states[a..=b])
}

/// The joints at `t`, interpolated between the states around it (`None`
/// outside their span).
fn joints_at(states: &[(u64, Vec<Real>)], t: u64) -> Option<Vec<Real>> {
    // The last state at or before t.
    let i = states.partition_point(|(s, _)| *s <= t).checked_sub(1)?;
    let (t0, q0) = &states[i];
    if *t0 == t {
        return Some(q0.clone());
    }
    let (t1, q1) = states.get(i + 1)?;
    let w = (t - t0) as Real / (t1 - t0) as Real;
    Some(q0.iter().zip(q1).map(|(a, b)| a + w * (b - a)).collect())
}

/// Range readings of a bag as Pudney's sensor sets.
#[derive(Clone, Debug)]
pub struct RangeSets {
    /// One set per stamp at which some range finder had a return, in time
    /// order (readings without a return leave no point; a stamp with none
    /// gives no set, as a follower does not update its model then).
    pub sets: Vec<surface::SensorSet>,
    /// The `sensor_msgs/Range` topics read.
    pub topics: Vec<String>,
    /// Readings with a return.
    pub points: usize,
    /// Readings without one (`+inf`, or outside `[min_range, max_range]`).
    pub misses: usize,
    /// Damaged chunks and bad messages skipped ([`BadMessages::Skip`]).
    pub skipped: Skipped,
}

/// The frames of `/tf_static` and `/tf` as they stand at some moment:
/// child → (parent, `parent_from_child`).
#[derive(Default)]
struct FrameTree(HashMap<String, (String, Isometry3)>);

impl FrameTree {
    fn apply(&mut self, tf: TfMessage) {
        for t in tf.transforms {
            self.0.insert(
                t.child_frame_id,
                (t.header.frame_id, isometry(&t.transform)),
            );
        }
    }

    /// `map_from_frame` ([`ROOT_FRAME`]) up the tree; an error saying where
    /// the chain stops short of the root (an unknown frame, a frame no
    /// transform places, a cycle).
    fn root_from(&self, frame: &str) -> Result<Isometry3, String> {
        let mut pose = Isometry3::identity();
        let mut at = frame;
        let mut hops = 0;
        while at != ROOT_FRAME {
            let Some((parent, t)) = self.0.get(at) else {
                return Err(if hops == 0 {
                    format!("frame `{frame}` is not placed by any transform")
                } else {
                    format!(
                        "frame `{frame}` is placed up to `{at}`, which no transform places in `{ROOT_FRAME}`"
                    )
                });
            };
            pose = t * pose;
            at = parent;
            hops += 1;
            if hops > self.0.len() {
                return Err(format!("frame `{frame}`'s transforms form a cycle"));
            }
        }
        Ok(pose)
    }
}

/// The `sensor_msgs/Range` readings of the bag at `path` (on `topics_in`,
/// or every topic of that type when empty) as sensor sets: the readings of
/// one stamp form a set, each point `range` along its frame's x axis
/// (ROS's convention), placed in [`ROOT_FRAME`] by `/tf_static` and the
/// `/tf` in force at its stamp; a set holds at most `max_set_points`
/// points. Errors name the bag and what is wrong (no Range topic, a given
/// topic of another type, a frame that no transform places in
/// [`ROOT_FRAME`], time going backwards, a damaged chunk, and a bad
/// message as [`sweeps_from_bag`] says, naming its topic, index and log
/// time; with [`BadMessages::Skip`] the bad ones are skipped and counted).
pub fn sets_from_bag(
    path: &Path,
    topics_in: &[String],
    max_set_points: usize,
    bad_messages: BadMessages,
) -> Result<RangeSets, BagError> {
    let bad = |message: String| BagError::Bag {
        path: path.to_owned(),
        message,
    };
    let contents = read_bag_with(path, &|_| true, bad_messages)?;
    let messages = contents.messages;
    let mut gate = Gate {
        path,
        mode: bad_messages,
        skipped: contents.skipped,
    };
    let range_type = <super::msg::Range as super::msg::RosMessage>::TYPE;
    for t in topics_in {
        if let Some(m) = messages
            .iter()
            .find(|m| m.topic == *t && m.type_name != range_type)
        {
            return Err(bad(format!(
                "{t} is not `{range_type}` (it carries `{}`)",
                m.type_name
            )));
        }
    }
    let is_range = |m: &BagMessage| {
        if topics_in.is_empty() {
            m.type_name == range_type
        } else {
            topics_in.contains(&m.topic)
        }
    };
    let mut topics: Vec<String> = messages
        .iter()
        .filter(|m| is_range(m))
        .map(|m| m.topic.clone())
        .collect();
    topics.sort();
    topics.dedup();
    if let Some(missing) = topics_in.iter().find(|t| !topics.contains(t)) {
        return Err(bad(format!("no messages on {missing}")));
    }
    if topics.is_empty() {
        return Err(bad(format!("no `{range_type}` topic")));
    }
    // Transforms and readings in log-time order (stable: a transform logged
    // with a reading's stamp before it applies to it).
    let mut order: Vec<&BagMessage> = messages
        .iter()
        .filter(|m| is_range(m) || m.topic == topics::TF || m.topic == topics::TF_STATIC)
        .collect();
    order.sort_by_key(|m| m.log_time_ns);
    let mut tree = FrameTree::default();
    let mut sets = Vec::new();
    let mut current: Option<(u64, Vec<geom::Point3>, Vec<geom::UnitVector3>)> = None;
    let (mut points, mut misses) = (0, 0);
    let flush = |current: &mut Option<(u64, Vec<geom::Point3>, Vec<geom::UnitVector3>)>,
                 sets: &mut Vec<surface::SensorSet>|
     -> Result<(), BagError> {
        if let Some((t, p, a)) = current.take()
            && !p.is_empty()
        {
            let set = surface::SensorSet::new(p, a)
                .map_err(|e| bad(format!("the readings stamped {t} ns: {e}")))?;
            sets.push(set);
        }
        Ok(())
    };
    for m in order {
        if m.topic == topics::TF || m.topic == topics::TF_STATIC {
            let tf = decoded::<TfMessage>(m).and_then(|tf| check_tf(&tf).map(|()| tf));
            if let Some(tf) = gate.check(m, tf)? {
                tree.apply(tf);
            }
            continue;
        }
        let r = decoded::<super::msg::Range>(m).and_then(|r| {
            let t = stamp_of(&r.header, m.log_time_ns)?;
            Ok((r, t))
        });
        let Some((r, t)) = gate.check(m, r)? else {
            continue;
        };
        match &current {
            Some((ct, _, _)) if *ct == t => {}
            Some((ct, _, _)) if t < *ct => {
                return Err(bad(format!(
                    "{}: time goes backwards ({t} ns after {ct} ns)",
                    m.name()
                )));
            }
            _ => {
                flush(&mut current, &mut sets)?;
                current = Some((t, Vec::new(), Vec::new()));
            }
        }
        let range = Real::from(r.range);
        if !(range.is_finite()
            && range >= Real::from(r.min_range)
            && range <= Real::from(r.max_range))
        {
            misses += 1;
            continue;
        }
        let pose = tree.root_from(&r.header.frame_id).map_err(|e| {
            bad(format!(
                "{}: {e} (by {} or {}) at {t} ns",
                m.name(),
                topics::TF_STATIC,
                topics::TF
            ))
        })?;
        let axis = pose * geom::Vector3::x_axis();
        let Some((_, p, a)) = &mut current else {
            continue;
        };
        if p.len() >= max_set_points {
            return Err(bad(format!(
                "more than {max_set_points} readings stamped {t} ns (the model's max_set_points)"
            )));
        }
        p.push(pose * geom::Point3::new(range, 0.0, 0.0));
        a.push(axis);
        points += 1;
    }
    flush(&mut current, &mut sets)?;
    Ok(RangeSets {
        sets,
        topics,
        points,
        misses,
        skipped: gate.skipped,
    })
}
