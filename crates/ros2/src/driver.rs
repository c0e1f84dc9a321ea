//! The `hw` traits over a ROS 2 robot: joint states in, joint trajectories
//! out, scans and range readings in.

use crate::serve::{CLOCK_TOPIC, EXACT_RANGES_TOPIC, SENSE_TOPIC};
use crate::{Ros2Error, Ros2Node};
use geom::{Isometry3, Real};
use hw::{Arm, HwError, LineScanner, RangeSensors, ScanReadings};
use record::bag::msg::{
    Clock, Float64MultiArray, Header, JointState, JointTrajectory, JointTrajectoryPoint, LaserScan,
    Range, StdString, Time,
};
use robot::Robot;
use ros2_client::{Publisher, Subscription};
use scenario::ros2::Ros2Spec;
use sensor::SensorPoint;
use std::cell::Cell;
use std::time::{Duration, Instant};

/// How the driver talks to its robot.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DriverConfig {
    /// Topics, joint names, tolerance, timeout and planned joint speed
    /// (a scenario's `[ros2]` table).
    pub ros2: Ros2Spec,
    /// Ask for each scan, reading and noise seed on the sense topic (a
    /// lockstep `surveyor sim-robot`), instead of taking the next ones the
    /// robot publishes, and wait for each motion to end exactly on its goal
    /// (a simulated arm gets there; the tolerance is for real ones).
    pub lockstep: bool,
}

impl DriverConfig {
    /// A move is done when every joint is this close to its goal, radians.
    pub fn tolerance_rad(&self) -> Real {
        if self.lockstep {
            0.0
        } else {
            self.ros2.tolerance_rad
        }
    }
}

/// A ROS 2 robot as `hw` hardware.
pub struct Ros2Hardware {
    robot: Robot,
    world_from_base: Isometry3,
    bearings: Vec<Real>,
    config: DriverConfig,
    names: Vec<String>,
    q: Vec<Real>,
    states: Subscription<JointState>,
    scans: Subscription<LaserScan>,
    ranges: Vec<Subscription<Range>>,
    trajectories: Publisher<JointTrajectory>,
    sense: Option<Publisher<StdString>>,
    exact: Option<Subscription<Float64MultiArray>>,
    /// The robot's `/clock`, when it publishes one.
    clock: Subscription<Clock>,
    /// Its latest time, nanoseconds, and when that came (wall time).
    robot_now: Cell<Option<(u64, Instant)>>,
    node: Ros2Node,
}

impl std::fmt::Debug for Ros2Hardware {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Ros2Hardware")
            .field("robot", &self.robot.name)
            .field("q", &self.q)
            .finish_non_exhaustive()
    }
}

fn device(message: String) -> HwError {
    HwError::Device {
        device: "ROS 2 robot".to_owned(),
        message,
    }
}

/// A timeout of `seconds` begun now. On a robot that publishes `/clock`
/// it runs on that clock (`use_sim_time`): a robot running faster or
/// slower than real time gets its timeouts in its own seconds, and one
/// whose clock stops advancing times out after `seconds` of wall time
/// without a new `/clock` message. Without `/clock` it runs on the wall
/// clock. A setting that is no duration (negative, not finite, too long)
/// waits a day rather than panicking.
struct Wait {
    seconds: Real,
    wall: Instant,
    /// The robot's time when the wait began (or when its clock was first
    /// heard during the wait).
    robot_from: Cell<Option<u64>>,
}

/// The longest timeout, seconds.
const LONGEST_WAIT_S: Real = 86_400.0;

impl Wait {
    /// Whether the wait is over, the robot's clock standing at
    /// `robot_now` (its time and when that was heard; `None` without one).
    fn over(&self, robot_now: Option<(u64, Instant)>) -> bool {
        let seconds = if self.seconds.is_finite() && self.seconds >= 0.0 {
            self.seconds.min(LONGEST_WAIT_S)
        } else {
            LONGEST_WAIT_S
        };
        match robot_now {
            None => self.wall.elapsed().as_secs_f64() > seconds,
            Some((now, heard)) => {
                let from = self.robot_from.get().unwrap_or(now);
                self.robot_from.set(Some(from));
                now.saturating_sub(from) as Real * 1e-9 > seconds
                    || heard.elapsed().as_secs_f64() > seconds
            }
        }
    }
}

impl Ros2Hardware {
    /// The robot `robot` (placed at `world_from_base`, its scanner's rays at
    /// `bearings`) on `node`: waits for its first joint state.
    pub fn new(
        mut node: Ros2Node,
        robot: &Robot,
        world_from_base: &Isometry3,
        bearings: &[Real],
        config: DriverConfig,
    ) -> Result<Self, Ros2Error> {
        let spec = &config.ros2;
        let names = crate::ros_joint_names(spec, robot)?;
        let states = node.subscription::<JointState>(&spec.joint_states_topic)?;
        let scans = node.subscription::<LaserScan>(&spec.scan_topic)?;
        let ranges = (0..robot.range_finders.len())
            .map(|k| node.subscription::<Range>(&spec.range_topic(k)))
            .collect::<Result<_, _>>()?;
        let trajectories = node.publisher::<JointTrajectory>(&spec.trajectory_topic)?;
        let clock = node.clock_subscription::<Clock>(CLOCK_TOPIC)?;
        let (sense, exact) = if config.lockstep {
            (
                Some(node.publisher::<StdString>(SENSE_TOPIC)?),
                Some(node.subscription::<Float64MultiArray>(EXACT_RANGES_TOPIC)?),
            )
        } else {
            (None, None)
        };
        let mut hw = Self {
            robot: robot.clone(),
            world_from_base: *world_from_base,
            bearings: bearings.to_vec(),
            names,
            q: Vec::new(),
            config,
            states,
            scans,
            ranges,
            trajectories,
            sense,
            exact,
            clock,
            robot_now: Cell::new(None),
            node,
        };
        let wait = hw.wait(hw.config.ros2.timeout_s);
        hw.q = hw.poll(&wait, "joint state", || hw.latest_state())?;
        hw.wait_for_the_robot(&wait)?;
        // A robot that publishes a clock is timed on it from the start.
        if hw.node.publishers_of(&hw.clock) > 0 {
            hw.poll(&wait, CLOCK_TOPIC, || {
                hw.hear_the_clock()?;
                Ok(hw.robot_now.get())
            })?;
        }
        Ok(hw)
    }

    /// The robot's time on its `/clock`, nanoseconds (`None` when it
    /// publishes none).
    pub fn robot_clock_ns(&self) -> Result<Option<u64>, HwError> {
        self.hear_the_clock()?;
        Ok(self.robot_now.get().map(|(t, _)| t))
    }

    /// Take the `/clock` messages that came: the newest is the robot's time.
    fn hear_the_clock(&self) -> Result<(), HwError> {
        while let Some((c, _)) = self
            .clock
            .take()
            .map_err(|e| device(format!("{CLOCK_TOPIC}: {e:?}")))?
        {
            if let Some(t) = c.clock.to_nanos() {
                self.robot_now.set(Some((t, Instant::now())));
            }
        }
        Ok(())
    }

    /// A timeout of `seconds` from now, on the robot's clock ([`Wait`]).
    fn wait(&self, seconds: Real) -> Wait {
        // A failure to read the clock shows at the next read.
        let _ = self.hear_the_clock();
        Wait {
            seconds,
            wall: Instant::now(),
            robot_from: Cell::new(self.robot_now.get().map(|(t, _)| t)),
        }
    }

    /// Whether `wait` is over.
    fn over(&self, wait: &Wait) -> Result<bool, HwError> {
        self.hear_the_clock()?;
        Ok(wait.over(self.robot_now.get()))
    }

    /// What `take` gives, once it gives something, or an error once `wait`
    /// is over.
    fn poll<T>(
        &self,
        wait: &Wait,
        what: &str,
        mut take: impl FnMut() -> Result<Option<T>, HwError>,
    ) -> Result<T, HwError> {
        loop {
            if let Some(v) = take()? {
                return Ok(v);
            }
            if self.over(wait)? {
                return Err(device(format!("no {what} before the timeout")));
            }
            std::thread::sleep(Duration::from_micros(200));
        }
    }

    /// The newest joint state received (in the robot's joint order), if any.
    fn latest_state(&self) -> Result<Option<Vec<Real>>, HwError> {
        let mut latest = None;
        while let Some((js, _)) = self
            .states
            .take()
            .map_err(|e| device(format!("{}: {e:?}", self.config.ros2.joint_states_topic)))?
        {
            let mut q = Vec::with_capacity(self.names.len());
            for n in &self.names {
                let i = js.name.iter().position(|x| x == n).ok_or_else(|| {
                    device(format!(
                        "{} names no joint `{n}`",
                        self.config.ros2.joint_states_topic
                    ))
                })?;
                q.push(js.position.get(i).copied().unwrap_or(Real::NAN));
            }
            latest = Some(q);
        }
        Ok(latest)
    }

    /// Wait until the robot's sensors' topics and its command topics match
    /// ours: a message sent before would be lost (ROS 2's default QoS is
    /// volatile), and a lockstep robot's noise would go out of step.
    fn wait_for_the_robot(&self, wait: &Wait) -> Result<(), HwError> {
        let mut missing: Vec<String>;
        loop {
            missing = Vec::new();
            if !self.bearings.is_empty() && self.node.publishers_of(&self.scans) == 0 {
                missing.push(self.config.ros2.scan_topic.clone());
            }
            for (k, s) in self.ranges.iter().enumerate() {
                if self.node.publishers_of(s) == 0 {
                    missing.push(self.config.ros2.range_topic(k));
                }
            }
            if self.node.subscriptions_of(&self.trajectories) == 0 {
                missing.push(self.config.ros2.trajectory_topic.clone());
            }
            if let Some(p) = &self.sense
                && self.node.subscriptions_of(p) == 0
            {
                missing.push(SENSE_TOPIC.to_owned());
            }
            if let Some(s) = &self.exact
                && !self.ranges.is_empty()
                && self.node.publishers_of(s) == 0
            {
                missing.push(EXACT_RANGES_TOPIC.to_owned());
            }
            if missing.is_empty() {
                return Ok(());
            }
            if self.over(wait)? {
                return Err(device(format!(
                    "the robot answers on /joint_states but not on {} (nothing matched before the timeout)",
                    missing.join(", ")
                )));
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Ask a lockstep robot for `what`.
    fn ask(&self, what: String) -> Result<(), HwError> {
        if let Some(p) = &self.sense {
            p.publish(StdString { data: what })
                .map_err(|e| device(format!("{SENSE_TOPIC}: {e:?}")))?;
        }
        Ok(())
    }

    fn timeout(&self) -> Wait {
        self.wait(self.config.ros2.timeout_s)
    }
}

impl Arm for Ros2Hardware {
    fn joints(&self) -> Vec<Real> {
        self.q.clone()
    }

    fn move_to(&mut self, q: &[Real]) -> Result<(), HwError> {
        self.robot.check_joints(q)?;
        let far = self
            .q
            .iter()
            .zip(q)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, Real::max);
        let secs = far / self.config.ros2.joint_speed;
        let msg = JointTrajectory {
            header: Header::default(),
            joint_names: self.names.clone(),
            points: vec![JointTrajectoryPoint {
                positions: q.to_vec(),
                time_from_start: Time::from_nanos((secs * 1e9) as u64),
                ..JointTrajectoryPoint::default()
            }],
        };
        self.trajectories
            .publish(msg)
            .map_err(|e| device(format!("{}: {e:?}", self.config.ros2.trajectory_topic)))?;
        let wait = self.wait(secs + self.config.ros2.timeout_s);
        let tolerance = self.config.tolerance_rad();
        let mut error = far;
        loop {
            if let Some(now) = self.latest_state()? {
                error = now
                    .iter()
                    .zip(q)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, Real::max);
                self.q = now;
                if error <= tolerance {
                    return Ok(());
                }
            }
            if self.over(&wait)? {
                return Err(HwError::NotReached { error });
            }
            std::thread::sleep(Duration::from_micros(200));
        }
    }
}

impl LineScanner for Ros2Hardware {
    fn bearings_rad(&self) -> &[Real] {
        &self.bearings
    }

    fn scan(&mut self) -> Result<ScanReadings, HwError> {
        let take = |s: &Subscription<LaserScan>| {
            s.take()
                .map(|m| m.map(|(m, _)| m))
                .map_err(|e| device(format!("{}: {e:?}", self.config.ros2.scan_topic)))
        };
        // Scans published before the arm stood here are stale.
        while take(&self.scans)?.is_some() {}
        self.ask("scan".to_owned())?;
        let scan = self.poll(&self.timeout(), "scan", || take(&self.scans))?;
        let (bearings, ranges_m, intensities) = record::bag::scan_rays(&scan);
        if bearings.len() != self.bearings.len() {
            return Err(device(format!(
                "{}: {} rays, the scanner has {}",
                self.config.ros2.scan_topic,
                bearings.len(),
                self.bearings.len()
            )));
        }
        Ok(ScanReadings {
            ranges_m,
            intensities,
            truth_materials: None,
        })
    }

    fn seed_noise(&mut self, seed: u64) {
        // A real robot has no seed; a lockstep simulator reseeds (a failure
        // to ask shows in the next request).
        let _ = self.ask(format!("seed {seed}"));
    }
}

impl RangeSensors for Ros2Hardware {
    fn read_all(&mut self) -> Result<Vec<Option<SensorPoint>>, HwError> {
        // Readings published before the arm stood here are stale.
        for s in &self.ranges {
            while s
                .take()
                .map_err(|e| device(format!("range: {e:?}")))?
                .is_some()
            {}
        }
        if let Some(s) = &self.exact {
            while s
                .take()
                .map_err(|e| device(format!("{EXACT_RANGES_TOPIC}: {e:?}")))?
                .is_some()
            {}
        }
        self.ask("ranges".to_owned())?;
        let frames = self.robot.forward_kinematics(&self.q)?;
        let wait = self.timeout();
        let mut messages = Vec::with_capacity(self.ranges.len());
        for (k, s) in self.ranges.iter().enumerate() {
            let topic = self.config.ros2.range_topic(k);
            messages.push(self.poll(&wait, &topic, || {
                s.take()
                    .map(|m| m.map(|(m, _)| m))
                    .map_err(|e| device(format!("{topic}: {e:?}")))
            })?);
        }
        // A lockstep robot's readings at full precision, each checked
        // against its `Range`.
        let exact = match &self.exact {
            Some(s) if !messages.is_empty() => {
                let e = self.poll(&wait, EXACT_RANGES_TOPIC, || {
                    s.take()
                        .map(|m| m.map(|(m, _)| m))
                        .map_err(|e| device(format!("{EXACT_RANGES_TOPIC}: {e:?}")))
                })?;
                if e.data.len() != 4 * messages.len() {
                    return Err(device(format!(
                        "{EXACT_RANGES_TOPIC}: {} values for {} range finders (expected 4 each)",
                        e.data.len(),
                        messages.len()
                    )));
                }
                Some(e.data)
            }
            _ => None,
        };
        let mut out = Vec::with_capacity(messages.len());
        for (k, (r, m)) in messages.iter().zip(&self.robot.range_finders).enumerate() {
            let world_from_link = self.world_from_base
                * frames
                    .get(m.link.0)
                    .ok_or_else(|| device(format!("range finder {k} on no link")))?;
            let (sensor, axis) = (world_from_link * m.origin, world_from_link * m.axis);
            let d = Real::from(r.range);
            let in_range =
                d.is_finite() && d >= Real::from(r.min_range) && d <= Real::from(r.max_range);
            let Some(exact) = &exact else {
                out.push(in_range.then(|| SensorPoint::along(sensor, axis, d)));
                continue;
            };
            let [e, x, y, z] = [0, 1, 2, 3].map(|i| exact[4 * k + i]);
            let agree = if e.is_nan() {
                !in_range
            } else {
                sensor::float32(e) == d
            };
            if !agree {
                return Err(device(format!(
                    "range finder {k}: its Range says {}, its reading at full precision {e}",
                    r.range
                )));
            }
            out.push((!e.is_nan()).then(|| SensorPoint {
                point: geom::Point3::new(x, y, z),
                axis,
                sensor,
                distance_m: e,
            }));
        }
        Ok(out)
    }
}
