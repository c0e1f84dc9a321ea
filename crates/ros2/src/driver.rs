//! The `hw` traits over a ROS 2 robot: joint states in, joint trajectories
//! out, scans and range readings in.

use crate::serve::{CLOCK_TOPIC, EXACT_RANGES_TOPIC, SENSE_TOPIC};
use crate::{Ros2Error, Ros2Node};
use geom::{Isometry3, Real};
use hw::motion::{JOINT_STATE_PERIOD_S, JointSample, LineMotion, MovingScan, MovingScanner};
use hw::{Arm, HwError, LineScanner, RangeSensors, ScanReadings};
use record::bag::msg::{
    Clock, Float64MultiArray, Header, JointState, JointTrajectory, JointTrajectoryPoint, LaserScan,
    Range, StdString, Time,
};
use robot::Robot;
use robot::timing::MotionLimits;
use ros2_client::{Publisher, Subscription};
use scenario::ros2::Ros2Spec;
use sensor::SensorPoint;
use std::cell::{Cell, RefCell};
use std::collections::VecDeque;
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
    /// The joints' velocity and acceleration limits each motion is timed
    /// within (`None`: the robot's own, [`MotionLimits::of`]). Without
    /// lockstep every motion goes out as a trajectory of its profile
    /// within them; a lockstep robot is sent the goal alone, at the
    /// `joint_speed` of `ros2`.
    pub limits: Option<MotionLimits>,
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
    /// The joint states received lately, stamped (robot time, ns), oldest
    /// first: a scan taken while the arm moved is placed between them.
    states_heard: RefCell<VecDeque<(u64, Vec<Real>)>>,
    /// The stamp of the joint state that showed the arm at the goal of its
    /// last motion: a scan begun before it is stale.
    arrived_ns: u64,
    /// The continuous motion under way.
    moving: Option<Moving>,
    /// The limits motions are timed within.
    limits: MotionLimits,
    /// Robot seconds from a scan's end to a brake asked after it taking
    /// hold, the most measured so far ([`MovingScanner::brake_lag_s`]).
    brake_lag_s: Real,
    node: Ros2Node,
}

/// A continuous motion on a ROS 2 robot.
#[derive(Debug)]
struct Moving {
    /// The motion as the arm runs it (braked, once it is).
    motion: LineMotion,
    /// When it began on the robot's clock (its trajectory's stamp), ns.
    t0_ns: u64,
    /// When the scan returned last ended (its first beam and the scan
    /// time), ns.
    last_end_ns: Option<u64>,
}

/// Robot seconds between sending a timed motion and its start (the
/// trajectory's header stamp): the time to reach the robot, with room.
const MOTION_LEAD_S: Real = 0.02;

/// Joint states the driver keeps (at 100 Hz, 20 s of them): a moving scan
/// needs those of its own 0.1 s.
const STATES_KEPT: usize = 2000;

/// Messages of the joint-state and scan topics DDS keeps for the driver
/// until it takes them: a motion's every state and scan, while the loop
/// works on one scan (the default QoS keeps 10).
const TOPIC_DEPTH: usize = 1000;

/// Nanoseconds of `seconds` (0 for less).
fn ns(seconds: Real) -> u64 {
    (seconds.max(0.0) * 1e9).round() as u64
}

/// Seconds from `t0_ns` to `t_ns` (negative before it).
fn seconds_from(t0_ns: u64, t_ns: u64) -> Real {
    (i128::from(t_ns) - i128::from(t0_ns)) as Real * 1e-9
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
        let states =
            node.subscription_keeping::<JointState>(&spec.joint_states_topic, TOPIC_DEPTH)?;
        let scans = node.subscription_keeping::<LaserScan>(&spec.scan_topic, TOPIC_DEPTH)?;
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
        let limits = config
            .limits
            .clone()
            .unwrap_or_else(|| MotionLimits::of(robot));
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
            states_heard: RefCell::new(VecDeque::new()),
            arrived_ns: 0,
            moving: None,
            limits,
            brake_lag_s: MOTION_LEAD_S,
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

    /// The robot's time now, nanoseconds: its `/clock` where it publishes
    /// one, the wall clock otherwise (a robot in real time stamps on it).
    fn robot_now_ns(&self) -> Result<u64, HwError> {
        self.hear_the_clock()?;
        Ok(self
            .robot_now
            .get()
            .map_or_else(crate::serve::now_ns, |(t, _)| t))
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

    /// The newest joint state received (in the robot's joint order), if
    /// any; every state received is kept with its stamp.
    fn latest_state(&self) -> Result<Option<Vec<Real>>, HwError> {
        Ok(self.latest_stamped()?.map(|(_, q)| q))
    }

    /// [`Ros2Hardware::latest_state`] with its stamp (robot time, ns).
    fn latest_stamped(&self) -> Result<Option<(u64, Vec<Real>)>, HwError> {
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
            let stamp = js.header.stamp.to_nanos().unwrap_or(0);
            let mut heard = self.states_heard.borrow_mut();
            heard.push_back((stamp, q.clone()));
            while heard.len() > STATES_KEPT {
                heard.pop_front();
            }
            latest = Some((stamp, q));
        }
        Ok(latest)
    }

    /// The joint states from the last stamped at or before `from_ns` to
    /// the first at or after `to_ns`, once one at or after it has come.
    fn states_over(&self, from_ns: u64, to_ns: u64) -> Option<Vec<(u64, Vec<Real>)>> {
        let heard = self.states_heard.borrow();
        let last = heard.iter().position(|(t, _)| *t >= to_ns)?;
        let first = heard.iter().rposition(|(t, _)| *t <= from_ns).unwrap_or(0);
        Some(heard.range(first..=last).cloned().collect())
    }

    /// Wait until the arm reports it stands within the tolerance of `q`
    /// (or the timeout of `wait`), and take where it stands.
    fn settle_at(&mut self, q: &[Real], wait: &Wait) -> Result<(), HwError> {
        let tolerance = self.config.tolerance_rad();
        let mut error = self
            .q
            .iter()
            .zip(q)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, Real::max);
        loop {
            if let Some((stamp, now)) = self.latest_stamped()? {
                error = now
                    .iter()
                    .zip(q)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, Real::max);
                self.q = now;
                if error <= tolerance {
                    self.arrived_ns = stamp;
                    return Ok(());
                }
            }
            if self.over(wait)? {
                return Err(HwError::NotReached { error });
            }
            std::thread::sleep(Duration::from_micros(200));
        }
    }

    /// Send the arm along `motion` from `from_s` seconds into it on,
    /// `from_s` due at `stamp_ns` on the robot's clock: one trajectory of
    /// the motion's joints every [`JOINT_STATE_PERIOD_S`] and at its end.
    fn send_motion(&self, motion: &LineMotion, stamp_ns: u64, from_s: Real) -> Result<(), HwError> {
        let d = motion.duration_s();
        let mut times: Vec<Real> = (1..)
            .map(|k| k as Real * JOINT_STATE_PERIOD_S)
            .skip_while(|&t| t <= from_s)
            .take_while(|&t| t < d)
            .collect();
        times.push(d.max(from_s));
        let msg = JointTrajectory {
            header: Header::new(stamp_ns, ""),
            joint_names: self.names.clone(),
            points: times
                .iter()
                .map(|&t| JointTrajectoryPoint {
                    // The last point is where the motion rests, exactly.
                    positions: if t >= d { motion.end() } else { motion.at(t) },
                    time_from_start: Time::from_nanos(ns(t - from_s)),
                    ..JointTrajectoryPoint::default()
                })
                .collect(),
        };
        self.trajectories
            .publish(msg)
            .map_err(|e| device(format!("{}: {e:?}", self.config.ros2.trajectory_topic)))
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
        if !self.config.lockstep {
            // The motion's profile within the joints' limits.
            let motion = LineMotion::new(&self.limits, &self.q, q);
            let t0 = self.robot_now_ns()? + ns(MOTION_LEAD_S);
            self.send_motion(&motion, t0, 0.0)?;
            let wait = self.wait(MOTION_LEAD_S + motion.duration_s() + self.config.ros2.timeout_s);
            return self.settle_at(q, &wait);
        }
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
        self.settle_at(q, &wait)
    }

    /// The robot's clock, unless the robot is a lockstep simulator (a run
    /// on it is then the in-process run, timed by the same model).
    fn clock_ns(&self) -> Option<u64> {
        if self.config.lockstep {
            return None;
        }
        self.robot_now_ns().ok()
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
        // Scans begun before the arm stood here are stale.
        self.ask("scan".to_owned())?;
        let arrived = self.arrived_ns;
        let scan = self.poll(&self.timeout(), "scan", || {
            while let Some(scan) = take(&self.scans)? {
                if scan.header.stamp.to_nanos().unwrap_or(0) >= arrived {
                    return Ok(Some(scan));
                }
            }
            Ok(None)
        })?;
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

    /// A robot whose scanner runs free while its arm follows a timed
    /// trajectory; a lockstep simulator scans only when asked, so it
    /// cannot.
    fn moving(&mut self) -> Option<&mut dyn MovingScanner> {
        if self.config.lockstep || self.bearings.is_empty() {
            None
        } else {
            Some(self)
        }
    }
}

fn not_moving() -> HwError {
    HwError::Setting {
        what: "continuous motion".into(),
        message: "a scan or a brake asked before a motion began".into(),
    }
}

/// A continuous motion over ROS 2: the motion goes out as one
/// `JointTrajectory` of its joints every 10 ms, stamped to begin
/// 20 ms (`MOTION_LEAD_S`) ahead on the robot's clock; each `LaserScan` begun
/// while it runs comes back with the joint states around its beams
/// (`time_increment` apart from the header's stamp); braking sends the
/// braked rest of the profile, stamped where it departs from the motion.
impl MovingScanner for Ros2Hardware {
    fn start_motion(&mut self, motion: &LineMotion) -> Result<(), HwError> {
        let tolerance = self.config.tolerance_rad().max(1e-9);
        scenario::job::check_stands_at(&self.q, &motion.from, tolerance).map_err(|message| {
            HwError::Setting {
                what: "continuous motion".into(),
                message: format!("the arm {message}"),
            }
        })?;
        self.robot.check_joints(&motion.to)?;
        let t0 = self.robot_now_ns()? + ns(MOTION_LEAD_S);
        self.send_motion(motion, t0, 0.0)?;
        self.moving = Some(Moving {
            motion: motion.clone(),
            t0_ns: t0,
            last_end_ns: None,
        });
        Ok(())
    }

    fn next_scan(&mut self) -> Result<Option<MovingScan>, HwError> {
        let now = self.robot_now_ns()?;
        let m = self.moving.as_mut().ok_or_else(not_moving)?;
        if let Some(end) = m.last_end_ns {
            // The loop worked on the last scan until now: a brake asked
            // then would have taken hold a lead later.
            let lag = seconds_from(end, now) + MOTION_LEAD_S;
            self.brake_lag_s = self.brake_lag_s.max(lag);
        }
        let (t0, d) = (m.t0_ns, m.motion.duration_s());
        let t_end = t0 + ns(d);
        let topic = self.config.ros2.scan_topic.clone();
        let wait = self.wait(d + self.config.ros2.timeout_s);
        let mut scan_time = 0.1;
        loop {
            while let Some((scan, _)) = self
                .scans
                .take()
                .map_err(|e| device(format!("{topic}: {e:?}")))?
            {
                let stamp = scan.header.stamp.to_nanos().unwrap_or(0);
                if Real::from(scan.scan_time) > 0.0 {
                    scan_time = Real::from(scan.scan_time);
                }
                if stamp < t0 {
                    continue;
                }
                if stamp >= t_end {
                    return self.rest();
                }
                return self.moving_scan(&scan, stamp).map(Some);
            }
            // A scanner that fell silent: the arm has rested once the
            // robot's time is a scan past the motion's end.
            if self.robot_now_ns()? >= t_end + ns(2.0 * scan_time) {
                return self.rest();
            }
            if self.over(&wait)? {
                return Err(device(format!("no {topic} before the timeout")));
            }
            std::thread::sleep(Duration::from_micros(200));
        }
    }

    fn brake(&mut self) -> Result<LineMotion, HwError> {
        let now = self.robot_now_ns()?;
        let m = self.moving.as_ref().ok_or_else(not_moving)?;
        let tb = seconds_from(m.t0_ns, now + ns(MOTION_LEAD_S)).max(0.0);
        let braked = m.motion.braked(tb);
        let t0 = m.t0_ns;
        if braked.duration_s() > tb && braked != m.motion {
            self.send_motion(&braked, t0 + ns(tb), tb)?;
        }
        if let Some(m) = &mut self.moving {
            m.motion = braked.clone();
        }
        Ok(braked)
    }

    fn brake_lag_s(&mut self) -> Real {
        self.brake_lag_s
    }
}

impl Ros2Hardware {
    /// The scan `scan`, begun at `stamp` (ns) during the motion under way,
    /// with the joint states around its beams, once they have come.
    fn moving_scan(&mut self, scan: &LaserScan, stamp: u64) -> Result<MovingScan, HwError> {
        let m = self.moving.as_mut().ok_or_else(not_moving)?;
        let t0 = m.t0_ns;
        let (bearings, ranges_m, intensities) = record::bag::scan_rays(scan);
        if bearings.len() != self.bearings.len() {
            return Err(device(format!(
                "{}: {} rays, the scanner has {}",
                self.config.ros2.scan_topic,
                bearings.len(),
                self.bearings.len()
            )));
        }
        let increment = Real::from(scan.time_increment).max(0.0);
        let last = stamp + ns(increment * bearings.len().saturating_sub(1) as Real);
        m.last_end_ns = Some(stamp + ns(Real::from(scan.scan_time)));
        let wait = self.timeout();
        let around = self.poll(&wait, &self.config.ros2.joint_states_topic, || {
            self.latest_stamped()?;
            Ok(self.states_over(stamp, last))
        })?;
        Ok(MovingScan {
            readings: ScanReadings {
                ranges_m,
                intensities,
                truth_materials: None,
            },
            start_s: seconds_from(t0, stamp),
            time_increment_s: increment,
            joints: around
                .into_iter()
                .map(|(t, q)| JointSample {
                    t_s: seconds_from(t0, t),
                    q,
                })
                .collect(),
        })
    }

    /// The motion under way is over: wait for the arm to report its rest.
    fn rest(&mut self) -> Result<Option<MovingScan>, HwError> {
        let m = self.moving.take().ok_or_else(not_moving)?;
        let wait = self.timeout();
        self.settle_at(&m.motion.end(), &wait)?;
        Ok(None)
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
