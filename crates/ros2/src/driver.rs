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
    /// Where the clock stood when its rate was last measured (robot ns,
    /// wall time).
    clock_mark: Cell<Option<(u64, Instant)>>,
    /// Robot seconds per wall second, as last measured over
    /// [`RATE_WINDOW_S`] (1 until then, and without a clock).
    clock_rate: Cell<Real>,
    /// The joint states received lately, stamped (robot time, ns), oldest
    /// first: a scan taken while the arm moved is placed between them.
    states_heard: RefCell<VecDeque<(u64, Vec<Real>)>>,
    /// When the last joint state came (wall time).
    state_heard_at: Cell<Option<Instant>>,
    /// The stamp of the joint state that showed the arm at the goal of its
    /// last motion: a scan begun before it is stale.
    arrived_ns: u64,
    /// The continuous motion under way.
    moving: Option<Moving>,
    /// The last motion sent and when it began on the robot's clock (ns):
    /// every joint state is checked against it (its goal once it is over).
    path: RefCell<Option<(LineMotion, u64)>>,
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

/// Wall seconds a timed motion is sent ahead of its start at least: on a
/// robot whose clock runs faster than real time, [`MOTION_LEAD_S`] of its
/// time can be less than a message takes to arrive
/// ([`Ros2Hardware::lead_s`]).
const MOTION_LEAD_WALL_S: Real = 0.005;

/// How far back along a motion's path a joint state is matched, in motion
/// leads (the path check of [`Ros2Hardware::check_path`]): 0.2 s at real
/// time, 50 ms of wall time on a fast clock.
const PATH_SLACK_LEADS: Real = 10.0;

/// Points of that stretch of path a joint state is compared with.
const PATH_SAMPLES: usize = 10;

/// Wall seconds over which the robot clock's rate is measured.
const RATE_WINDOW_S: Real = 0.25;

/// The largest clock rate the lead grows with: a robot clock that jumps
/// (a simulator reset, a bag's clock replayed) leads motions by at most
/// this many times [`MOTION_LEAD_WALL_S`].
const MAX_LEAD_RATE: Real = 1000.0;

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
/// whose clock stops advancing times out after `silent_s` of wall time
/// (the configured timeout) without a new `/clock` message. Without
/// `/clock` it runs on the wall clock. A setting that is no duration
/// (negative, not finite, too long) waits a day rather than panicking.
struct Wait {
    seconds: Real,
    /// Wall seconds without a `/clock` message that end the wait.
    silent_s: Real,
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
        let bounded = |s: Real| {
            if s.is_finite() && s >= 0.0 {
                s.min(LONGEST_WAIT_S)
            } else {
                LONGEST_WAIT_S
            }
        };
        let seconds = bounded(self.seconds);
        match robot_now {
            None => self.wall.elapsed().as_secs_f64() > seconds,
            Some((now, heard)) => {
                let from = self.robot_from.get().unwrap_or(now);
                self.robot_from.set(Some(from));
                now.saturating_sub(from) as Real * 1e-9 > seconds
                    || heard.elapsed().as_secs_f64() > bounded(self.silent_s).min(seconds)
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
            clock_mark: Cell::new(None),
            clock_rate: Cell::new(1.0),
            states_heard: RefCell::new(VecDeque::new()),
            state_heard_at: Cell::new(None),
            arrived_ns: 0,
            moving: None,
            path: RefCell::new(None),
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
            // Its rate, before the first motion is led by it.
            let from = Instant::now();
            while from.elapsed().as_secs_f64() < 1.5 * RATE_WINDOW_S {
                hw.hear_the_clock()?;
                std::thread::sleep(Duration::from_millis(1));
            }
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
                let now = Instant::now();
                self.robot_now.set(Some((t, now)));
                match self.clock_mark.get() {
                    None => self.clock_mark.set(Some((t, now))),
                    Some((t0, at)) => {
                        let wall = now.duration_since(at).as_secs_f64();
                        if wall >= RATE_WINDOW_S {
                            self.clock_rate.set(seconds_from(t0, t) / wall);
                            self.clock_mark.set(Some((t, now)));
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Robot seconds between sending a timed motion and its start:
    /// [`MOTION_LEAD_S`], or [`MOTION_LEAD_WALL_S`] of wall time at the
    /// robot clock's rate where that is more.
    fn lead_s(&self) -> Real {
        let rate = self.clock_rate.get();
        let rate = if rate.is_finite() {
            rate.clamp(0.0, MAX_LEAD_RATE)
        } else {
            0.0
        };
        MOTION_LEAD_S.max(MOTION_LEAD_WALL_S * rate)
    }

    /// A timeout of `seconds` from now, on the robot's clock ([`Wait`]).
    fn wait(&self, seconds: Real) -> Wait {
        // A failure to read the clock shows at the next read.
        let _ = self.hear_the_clock();
        Wait {
            seconds,
            silent_s: self.config.ros2.timeout_s,
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
            self.state_heard_at.set(Some(Instant::now()));
            self.check_path(stamp, &q)?;
            let mut heard = self.states_heard.borrow_mut();
            heard.push_back((stamp, q.clone()));
            while heard.len() > STATES_KEPT {
                heard.pop_front();
            }
            latest = Some((stamp, q));
        }
        Ok(latest)
    }

    /// Check a joint state `q` stamped `stamp` against the path of the
    /// last motion sent (where it had the arm at the stamp or a little
    /// before): a joint farther off than the path tolerance stops the arm
    /// where it stands (a one-point trajectory to there, begun now) and the
    /// run with [`HwError::OffPath`].
    fn check_path(&self, stamp: u64, q: &[Real]) -> Result<(), HwError> {
        if self.config.lockstep {
            return Ok(());
        }
        let path = self.path.borrow();
        let Some((motion, t0)) = path.as_ref() else {
            return Ok(());
        };
        // Where the path had the arm over the last PATH_SLACK_LEADS leads:
        // a robot that began the trajectory late (on its arrival, not at
        // its stamp) lags by the time it took to come.
        let d = motion.duration_s();
        let t = seconds_from(*t0, stamp);
        let slack = PATH_SLACK_LEADS * self.lead_s();
        let off = |tau: Real| {
            let tau = tau.clamp(0.0, d);
            let due = if tau >= d {
                motion.end()
            } else {
                motion.at(tau)
            };
            q.iter()
                .zip(&due)
                .map(|(a, b)| (a - b).abs())
                .enumerate()
                // The farthest joint (a NaN position counts as farthest).
                .fold(
                    (0, 0.0),
                    |m, (j, e)| if e.is_nan() || e > m.1 { (j, e) } else { m },
                )
        };
        let (joint, error) = (0..=PATH_SAMPLES)
            .map(|k| off(t - slack * k as Real / PATH_SAMPLES as Real))
            .fold((0, Real::INFINITY), |m, o| if o.1 < m.1 { o } else { m });
        let tolerance = self.config.ros2.path_tolerance_rad;
        if error <= tolerance {
            return Ok(());
        }
        let hold = JointTrajectory {
            header: Header::default(),
            joint_names: self.names.clone(),
            points: vec![JointTrajectoryPoint {
                positions: q.to_vec(),
                ..JointTrajectoryPoint::default()
            }],
        };
        // The error says what happened; a failure to send the stop too.
        let sent = self.trajectories.publish(hold);
        Err(match sent {
            Ok(()) => HwError::OffPath {
                joint: self.names[joint].clone(),
                error,
                tolerance,
                at_s: seconds_from(*t0, stamp),
            },
            Err(e) => device(format!(
                "joint {} was {error:.4} off its trajectory, and the stop could not be sent: {}: {e:?}",
                self.names[joint], self.config.ros2.trajectory_topic
            )),
        })
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
        // The joint farthest from `q`, and how far.
        let farthest = |now: &[Real]| {
            now.iter()
                .zip(q)
                .map(|(a, b)| (a - b).abs())
                .enumerate()
                .fold((0, 0.0), |m, (j, e)| if e > m.1 { (j, e) } else { m })
        };
        let mut error = farthest(&self.q);
        loop {
            if let Some((stamp, now)) = self.latest_stamped()? {
                error = farthest(&now);
                self.q = now;
                // At rest there: the state before this one there too (an
                // arm swinging through its goal is not; a lockstep robot
                // ends exactly on it).
                let before = if self.config.lockstep {
                    Some(0.0)
                } else {
                    let heard = self.states_heard.borrow();
                    heard
                        .len()
                        .checked_sub(2)
                        .and_then(|k| heard.get(k))
                        .map(|(_, q)| farthest(q).1)
                };
                if error.1 <= tolerance && before.is_some_and(|e| e <= tolerance) {
                    self.arrived_ns = stamp;
                    return Ok(());
                }
            }
            if self.over(wait)? {
                // A robot that fell silent did not stop short: say so
                // (its states stopped for half the silence that ends a
                // wait, a robot at 100 Hz never does; or for half the wait
                // on a clock that runs on).
                let silent_s = self
                    .state_heard_at
                    .get()
                    .map_or(0.0, |at| at.elapsed().as_secs_f64());
                let newest = self.states_heard.borrow().back().map(|(t, _)| *t);
                let stale = match (self.robot_now.get(), newest) {
                    (Some((now, _)), Some(t)) => seconds_from(t, now) > 0.5 * wait.seconds,
                    _ => false,
                };
                if silent_s >= 0.5 * wait.silent_s.min(wait.seconds) || stale {
                    return Err(device(format!(
                        "no joint state on {} for {silent_s:.1} s of wall time (has the robot stopped?); \
                         the last one had joint {} {:.4} from its goal",
                        self.config.ros2.joint_states_topic, self.names[error.0], error.1
                    )));
                }
                return Err(HwError::NotReached {
                    joint: self.names[error.0].clone(),
                    error: error.1,
                    tolerance,
                });
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
            let lead = self.lead_s();
            let t0 = self.robot_now_ns()? + ns(lead);
            self.send_motion(&motion, t0, 0.0)?;
            *self.path.borrow_mut() = Some((motion.clone(), t0));
            let wait = self.wait(lead + motion.duration_s() + self.config.ros2.timeout_s);
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

/// The joints at `t_ns` from stamped joint states around it (oldest
/// first): linear between the two that bracket it, else the nearest.
fn interpolated(states: &[(u64, Vec<Real>)], t_ns: u64) -> Vec<Real> {
    let after = states.iter().position(|(t, _)| *t >= t_ns);
    match after {
        Some(0) => states[0].1.clone(),
        None => states.last().map(|(_, q)| q.clone()).unwrap_or_default(),
        Some(i) => {
            let ((t0, q0), (t1, q1)) = (&states[i - 1], &states[i]);
            let f = seconds_from(*t0, t_ns) / seconds_from(*t0, *t1).max(1e-12);
            q0.iter().zip(q1).map(|(a, b)| a + f * (b - a)).collect()
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
/// 20 ms (`MOTION_LEAD_S`; 5 ms of wall time where that is more) ahead on
/// the robot's clock; each `LaserScan` begun
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
        let t0 = self.robot_now_ns()? + ns(self.lead_s());
        self.send_motion(motion, t0, 0.0)?;
        *self.path.borrow_mut() = Some((motion.clone(), t0));
        self.moving = Some(Moving {
            motion: motion.clone(),
            t0_ns: t0,
            last_end_ns: None,
        });
        Ok(())
    }

    fn next_scan(&mut self) -> Result<Option<MovingScan>, HwError> {
        let now = self.robot_now_ns()?;
        let lead = self.lead_s();
        let m = self.moving.as_mut().ok_or_else(not_moving)?;
        if let Some(end) = m.last_end_ns {
            // The loop worked on the last scan until now: a brake asked
            // then would have taken hold a lead later.
            let lag = seconds_from(end, now) + lead;
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
        let tb = seconds_from(m.t0_ns, now + ns(self.lead_s())).max(0.0);
        let braked = m.motion.braked(tb);
        let t0 = m.t0_ns;
        if braked.duration_s() > tb && braked != m.motion {
            self.send_motion(&braked, t0 + ns(tb), tb)?;
            *self.path.borrow_mut() = Some((braked.clone(), t0));
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
        // Readings taken before the arm stood here are stale too (a robot
        // that publishes them in a burst may still be sending an older
        // one).
        let arrived = if self.config.lockstep {
            0
        } else {
            self.arrived_ns
        };
        for (k, s) in self.ranges.iter().enumerate() {
            let topic = self.config.ros2.range_topic(k);
            messages.push(self.poll(&wait, &topic, || {
                while let Some((m, _)) = s.take().map_err(|e| device(format!("{topic}: {e:?}")))? {
                    if m.header.stamp.to_nanos().unwrap_or(0) >= arrived {
                        return Ok(Some(m));
                    }
                }
                Ok(None)
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
        // Without lockstep each reading is placed where the arm stood at its
        // stamp (the joint states around it, interpolated): an arm within
        // the tolerance of its goal still moves by that much.
        let mut at_stamp: Vec<(u64, Vec<Isometry3>)> = Vec::new();
        for r in &messages {
            let stamp = r.header.stamp.to_nanos().unwrap_or(0);
            if self.config.lockstep || at_stamp.iter().any(|(t, _)| *t == stamp) {
                continue;
            }
            let around = self.poll(&wait, &self.config.ros2.joint_states_topic, || {
                self.latest_stamped()?;
                Ok(self.states_over(stamp, stamp))
            })?;
            let q = interpolated(&around, stamp);
            at_stamp.push((stamp, self.robot.forward_kinematics(&q)?));
        }
        for (k, (r, m)) in messages.iter().zip(&self.robot.range_finders).enumerate() {
            let stamp = r.header.stamp.to_nanos().unwrap_or(0);
            let frames = at_stamp
                .iter()
                .find(|(t, _)| *t == stamp)
                .map_or(&frames, |(_, f)| f);
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

#[cfg(test)]
mod tests {
    use super::interpolated;

    #[test]
    fn joints_between_two_states_are_interpolated_by_their_stamps() {
        let states = vec![(1_000, vec![0.0, 1.0]), (3_000, vec![1.0, 3.0])];
        // A quarter of the way: by hand, 0.25 and 1.5.
        assert_eq!(interpolated(&states, 1_500), vec![0.25, 1.5]);
        assert_eq!(interpolated(&states, 3_000), vec![1.0, 3.0]);
        // Outside them, the nearest.
        assert_eq!(interpolated(&states, 500), vec![0.0, 1.0]);
        assert_eq!(interpolated(&states, 9_000), vec![1.0, 3.0]);
        assert!(interpolated(&[], 9_000).is_empty());
    }
}
