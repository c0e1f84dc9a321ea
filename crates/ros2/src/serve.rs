//! Any hardware served as a ROS 2 robot (`surveyor sim-robot`): it
//! publishes its joint states, its scans and its range readings, and
//! executes the joint trajectories it is sent.

use crate::{Ros2Error, Ros2Node};
use geom::Real;
use hw::{Arm, HwError, LineScanner, RangeSensors};
use record::bag::msg::JointTrajectory;
use robot::Robot;
use ros2_client::Publisher;
use scenario::ros2::Ros2Spec;
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// How a served robot behaves.
#[derive(Clone, Debug, PartialEq)]
pub struct ServeConfig {
    /// Speed of the fastest joint of a one-point trajectory, rad/s (m/s for
    /// prismatic joints), whatever its time; a trajectory of several points
    /// follows their times (a point not timed after its predecessor runs at
    /// this speed).
    pub joint_speed: Real,
    /// Between joint-state messages, seconds (a state is also published
    /// the moment a trajectory point is reached).
    pub state_period_s: Real,
    /// Between two turns of the serving loop (motion, requests), seconds.
    pub tick_s: Real,
    /// Between scans, seconds (the Hokuyo's 0.1 s).
    pub scan_period_s: Real,
    /// Between readings of the range finders, seconds.
    pub range_period_s: Real,
    /// The scanner's shortest and longest range, metres.
    pub scan_range_m: (Real, Real),
    /// How far past its range a range finder may report (its noise), metres.
    pub finder_range_slack_m: Real,
    /// Sense only when asked on [`SENSE_TOPIC`] (a `std_msgs/String`:
    /// `scan`, `ranges` or `seed N`), in the order asked, instead of on
    /// the periods: a simulated robot then draws its noise in the sequence
    /// an in-process run does (our driver in lockstep, [`crate::Ros2Hardware`]).
    pub lockstep: bool,
    /// Topics and the joints' ROS names (a scenario's `[ros2]` table).
    pub ros2: Ros2Spec,
    /// Robot seconds per second of wall time (1: real time; at most
    /// [`MAX_RATE`]): motions, periods and stamps run on the robot's own
    /// clock, published on [`CLOCK_TOPIC`].
    pub rate: Real,
}

/// Where a served robot publishes its clock (`rosgraph_msgs/Clock`, every
/// [`CLOCK_PERIOD_S`] of robot time): the time of its stamps, which a
/// driver follows for its timeouts ([`crate::Ros2Hardware`]).
pub const CLOCK_TOPIC: &str = "/clock";

/// Robot seconds between two `/clock` messages of a served robot (at most
/// one a turn of its loop): a lockstep robot turns every 0.5 ms, and a
/// clock that fine would only load the DDS link.
pub const CLOCK_PERIOD_S: Real = 0.005;

/// Fastest [`ServeConfig::rate`]: a served robot's loop turns every
/// `tick_s` of wall time, so its motions move `rate · tick_s ·
/// joint_speed` a turn.
pub const MAX_RATE: Real = 100.0;

/// The topic a lockstep robot takes its sensing requests on.
pub const SENSE_TOPIC: &str = "/surveyor/sense";

/// Where a lockstep robot also sends each reading of its range finders at
/// full precision (`std_msgs/Float64MultiArray`: per finder the distance
/// and the point's x, y, z in the world frame, NaN without a return):
/// `sensor_msgs/Range` carries float32, and Pudney's follower takes other
/// turns on differences that small, so a run driving a simulated robot
/// over ROS 2 could not be the in-process run without it.
pub const EXACT_RANGES_TOPIC: &str = "/surveyor/ranges";

impl ServeConfig {
    /// An error unless the rate is above 0 and at most [`MAX_RATE`].
    pub fn check(&self) -> Result<(), Ros2Error> {
        if self.rate.is_finite() && self.rate > 0.0 && self.rate <= MAX_RATE {
            return Ok(());
        }
        Err(Ros2Error::Config {
            what: "rate".into(),
            message: format!(
                "expected robot seconds per wall second in (0, {MAX_RATE}], got {}",
                self.rate
            ),
        })
    }
}

impl Default for ServeConfig {
    fn default() -> Self {
        Self {
            joint_speed: 1.0,
            state_period_s: 0.02,
            tick_s: 0.005,
            scan_period_s: 0.1,
            range_period_s: 0.1,
            scan_range_m: (0.02, 5.6),
            finder_range_slack_m: 0.0,
            lockstep: false,
            ros2: Ros2Spec::default(),
            rate: 1.0,
        }
    }
}

/// What a served robot did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ServeStats {
    /// Joint states published.
    pub states: u64,
    /// Scans published.
    pub scans: u64,
    /// Readings of all range finders published.
    pub readings: u64,
    /// Trajectories accepted.
    pub trajectories: u64,
    /// Trajectories refused (unknown joints, a pose the arm refused).
    pub refused: u64,
}

pub(crate) fn now_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX))
}

fn transfer(topic: &str, e: impl std::fmt::Debug) -> Ros2Error {
    Ros2Error::Transfer {
        topic: topic.to_owned(),
        message: format!("{e:?}"),
    }
}

/// The trajectory's points as joint vectors in the order of `names` (the
/// joints of `robot`, by their ROS names), or why not.
fn waypoints(
    t: &JointTrajectory,
    names: &[String],
    robot: &str,
    q: &[Real],
) -> Result<Vec<Vec<Real>>, String> {
    let index: Vec<Option<usize>> = names
        .iter()
        .map(|n| t.joint_names.iter().position(|x| x == n))
        .collect();
    if let Some(unknown) = t.joint_names.iter().find(|n| !names.contains(n)) {
        return Err(format!(
            "joint `{unknown}` is not a joint of {robot} ({names:?})"
        ));
    }
    t.points
        .iter()
        .enumerate()
        .map(|(k, p)| {
            if p.positions.len() != t.joint_names.len() {
                return Err(format!(
                    "point {k}: {} positions for {} joints",
                    p.positions.len(),
                    t.joint_names.len()
                ));
            }
            // Joints the trajectory leaves out stay where they are.
            Ok(index
                .iter()
                .zip(q)
                .map(|(i, &now)| i.map_or(now, |i| p.positions[i]))
                .collect())
        })
        .collect()
}

/// Range readings at full precision: per finder `[d, x, y, z]`, NaN
/// without a return ([`EXACT_RANGES_TOPIC`]).
pub fn exact_readings(
    readings: &[Option<sensor::SensorPoint>],
) -> record::bag::msg::Float64MultiArray {
    let data = readings
        .iter()
        .flat_map(|r| match r {
            Some(p) => [p.distance_m, p.point.x, p.point.y, p.point.z],
            None => [Real::NAN; 4],
        })
        .collect();
    record::bag::msg::Float64MultiArray {
        data,
        ..record::bag::msg::Float64MultiArray::default()
    }
}

/// The arm's path on the robot's clock: straight joint-space segments
/// between timed knots (robot seconds), those of the trajectory under way
/// ahead and, behind the arm, the last [`PATH_MEMORY_S`] of where it went,
/// so that a scan can cast each beam from where the arm was at its moment.
#[derive(Debug)]
struct Execution {
    /// `(due, joints, a trajectory point)`, in time order.
    knots: VecDeque<(Real, Vec<Real>, bool)>,
    /// The robot time the arm was last moved to ([`Execution::at`]).
    last_t: Real,
}

/// Robot seconds of the arm's past path a served robot keeps.
const PATH_MEMORY_S: Real = 2.0;

impl Execution {
    /// The arm standing at `q` from robot time `t`.
    fn standing(t: Real, q: Vec<Real>) -> Self {
        Self {
            knots: VecDeque::from([(t, q, false)]),
            last_t: t,
        }
    }

    /// Where the path has the arm at robot time `t` (before its first
    /// knot at that knot, after its last at the last).
    fn position(&self, t: Real) -> Vec<Real> {
        let after = self.knots.partition_point(|k| k.0 <= t);
        match (
            after.checked_sub(1).map(|i| &self.knots[i]),
            self.knots.get(after),
        ) {
            (Some((t0, q0, _)), Some((t1, q1, _))) => {
                let s = if t1 > t0 {
                    ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                q0.iter().zip(q1).map(|(a, b)| a + s * (b - a)).collect()
            }
            (Some((_, q, _)), None) | (None, Some((_, q, _))) => q.clone(),
            (None, None) => Vec::new(),
        }
    }

    /// Take the trajectory of `points` received at robot time `now`, to
    /// begin at `begin` (its header's stamp; now when that is past or
    /// unset). Until it begins the path under way goes on (a `ros2_control`
    /// joint trajectory controller replaces the old trajectory from the new
    /// one's start); then a trajectory of one point is a move there at
    /// `joint_speed` (its fastest joint), whatever its time, and the points
    /// of a longer one are due at their `time_from_start` after `begin`, a
    /// point whose time is not after its predecessor's at `joint_speed`
    /// after it.
    fn replace(
        &mut self,
        points: Vec<Vec<Real>>,
        times_s: &[Real],
        (now, begin): (Real, Option<Real>),
        joint_speed: Real,
    ) {
        let begin = begin.map_or(now, |b| b.max(now));
        let here = self.position(begin);
        while self.knots.back().is_some_and(|k| k.0 >= begin) {
            self.knots.pop_back();
        }
        self.knots.push_back((begin, here.clone(), false));
        let timed = points.len() > 1;
        let (mut t, mut at) = (begin, here);
        for (p, &after) in points.into_iter().zip(times_s) {
            let far = at
                .iter()
                .zip(&p)
                .map(|(a, b)| (b - a).abs())
                .fold(0.0, Real::max);
            t = if timed && begin + after > t {
                begin + after
            } else {
                t + far / joint_speed
            };
            at.clone_from(&p);
            self.knots.push_back((t, p, true));
        }
    }

    /// Where the arm is due at robot time `t`, and whether a trajectory
    /// point was reached since the last call; `None` when it was at rest
    /// already then. Knots older than [`PATH_MEMORY_S`] are forgotten.
    fn at(&mut self, t: Real) -> Option<(Vec<Real>, bool)> {
        let since = std::mem::replace(&mut self.last_t, t);
        let end = self.knots.back().map_or(Real::NEG_INFINITY, |k| k.0);
        let reached = self.knots.iter().any(|k| k.2 && k.0 > since && k.0 <= t);
        let q = self.position(t);
        while self.knots.len() > 1 && self.knots[1].0 < t - PATH_MEMORY_S {
            self.knots.pop_front();
        }
        (end > since || reached).then_some((q, reached))
    }

    /// Put `hw` where the arm is due at robot time `t`; whether it reached
    /// a trajectory point since the last step. A pose the hardware refuses
    /// ends the trajectory there (the error says why).
    fn step<H: Arm>(&mut self, t: Real, hw: &mut H) -> Result<bool, HwError> {
        let Some((q, reached)) = self.at(t) else {
            return Ok(false);
        };
        if let Err(e) = hw.move_to(&q) {
            *self = Self::standing(t, hw.joints());
            return Err(e);
        }
        Ok(reached)
    }

    /// The arm's joints every `period_s` from `t0` to `t1` (robot time).
    fn samples(&self, t0: Real, t1: Real, period_s: Real) -> Vec<hw::motion::JointSample> {
        hw::motion::sampled(t0, t1, period_s, |t| self.position(t))
    }
}

/// The joint states due at robot time `t` (the robot's clock began at
/// `start_ns`), on `publisher`; how many. Not in lockstep they keep their
/// period of robot time, each with where `execution` had the arm at its
/// stamp: a turn of the serving loop that comes late (a loaded machine)
/// sends the states it owes, up to [`PATH_MEMORY_S`] of them, as a robot's
/// driver buffering its controller's states would. In lockstep a state
/// goes out when its period has passed, stamped now. Either way the arm
/// reaching a trajectory point sends `joints` (where it stands) at once.
fn publish_states(
    publisher: &Publisher<record::bag::msg::JointState>,
    (topic, names): (&str, &[String]),
    (execution, joints): (&Execution, &[Real]),
    (t, start_ns, reached): (Real, u64, bool),
    next_state: &mut Real,
    config: &ServeConfig,
) -> Result<u64, Ros2Error> {
    let stamp_at = |t: Real| start_ns.saturating_add((t * 1e9) as u64);
    let mut sent = 0;
    let mut send = |stamp: u64, q: &[Real]| {
        publisher
            .publish(record::bag::joint_state(stamp, names, q))
            .map_err(|e| transfer(topic, e))
            .map(|()| sent += 1)
    };
    if !config.lockstep && t >= *next_state {
        *next_state = next_state.max(t - PATH_MEMORY_S);
        while *next_state <= t {
            send(stamp_at(*next_state), &execution.position(*next_state))?;
            *next_state += config.state_period_s;
        }
    }
    if (config.lockstep && t >= *next_state) || reached {
        if config.lockstep {
            *next_state = t + config.state_period_s;
        }
        send(stamp_at(t), joints)?;
    }
    Ok(sent)
}

/// Robot seconds between the poses a scan's beams are cast from (each
/// beam's pose is interpolated between them).
const BEAM_POSE_PERIOD_S: Real = 0.001;

/// The execution of `trajectory` received at robot time `t` by `hw` (the
/// robot of `names`, its joints' ROS names), into `execution`, or why not.
/// A header stamp the robot's clock (which began at `start_ns`) has not
/// passed is when the trajectory begins.
fn take_trajectory<H: Arm>(
    execution: &mut Execution,
    trajectory: &JointTrajectory,
    (names, robot): (&[String], &str),
    hw: &H,
    (t, start_ns): (Real, u64),
    config: &ServeConfig,
) -> Result<(), String> {
    let begin = trajectory
        .header
        .stamp
        .to_nanos()
        .filter(|&ns| ns > 0)
        .map(|ns| (i128::from(ns) - i128::from(start_ns)) as Real * 1e-9);
    let points = waypoints(trajectory, names, robot, &hw.joints())?;
    let times: Vec<Real> = trajectory
        .points
        .iter()
        .map(|p| {
            p.time_from_start
                .to_nanos()
                .map_or(0.0, |ns| ns as Real * 1e-9)
        })
        .collect();
    execution.replace(points, &times, (t, begin), config.joint_speed);
    Ok(())
}

/// A served robot's scanner running free: a scan every period, published
/// once its last beam is measured, each beam cast from where the arm was
/// at its moment (hardware that cannot cast so scans where the arm is).
struct FreeScanner {
    /// When the next scan begins, robot seconds.
    next_s: Real,
    /// Between beams (as a `LaserScan` states it, float32), seconds.
    increment_s: Real,
    /// From a scan's first beam to its last, seconds.
    window_s: Real,
    period_s: Real,
    range_m: (Real, Real),
    bearings: Vec<Real>,
    start_ns: u64,
}

impl FreeScanner {
    fn new(config: &ServeConfig, bearings: &[Real], start_ns: u64) -> Self {
        let increment_s =
            sensor::float32(hw::motion::time_increment_s(config.scan_period_s, bearings));
        Self {
            next_s: 0.0,
            increment_s,
            window_s: bearings.len().saturating_sub(1) as Real * increment_s,
            period_s: config.scan_period_s,
            range_m: config.scan_range_m,
            bearings: bearings.to_vec(),
            start_ns,
        }
    }

    /// The next scan whose last beam robot time `t` has passed, if any (a
    /// scan begun longer ago than half the path kept is skipped: a loop
    /// that stalled).
    fn scan_due<H: LineScanner>(
        &mut self,
        t: Real,
        hw: &mut H,
        execution: &Execution,
    ) -> Result<Option<record::bag::msg::LaserScan>, Ros2Error> {
        while !self.bearings.is_empty() && t >= self.next_s + self.window_s {
            let begun = self.next_s;
            self.next_s += self.period_s;
            if t - begun > PATH_MEMORY_S / 2.0 {
                continue;
            }
            let path = execution.samples(begun, begun + self.window_s, BEAM_POSE_PERIOD_S);
            let (s, dt) = match hw.scan_along(&path, begun, self.increment_s) {
                Some(s) => (s?, self.increment_s),
                None => (hw.scan()?, 0.0),
            };
            let stamp = self.start_ns.saturating_add((begun * 1e9) as u64);
            return Ok(Some(self.message(stamp, &s, dt)));
        }
        Ok(None)
    }

    /// The `LaserScan` of `s`, begun at `stamp_ns`, its beams `dt`
    /// seconds apart.
    fn message(
        &self,
        stamp_ns: u64,
        s: &hw::ScanReadings,
        dt: Real,
    ) -> record::bag::msg::LaserScan {
        let mut msg = record::bag::laser_scan(
            stamp_ns,
            &self.bearings,
            &s.ranges_m,
            &s.intensities,
            self.range_m,
            self.period_s,
        );
        msg.time_increment = dt as f32;
        msg
    }
}

/// Serve `hw` (the hardware of `robot`) on `node` until `stop` is raised:
/// publish the joint states every `state_period_s` on `/joint_states`, a
/// scan every `scan_period_s` on `/scan` (when the hardware has a scanner)
/// and each range finder's reading every `range_period_s` on
/// `/range/finder_k` (when it has any), and execute each
/// `trajectory_msgs/JointTrajectory` sent to the trajectory topic: its
/// points in turn, on straight joint-space lines, a one-point trajectory at
/// `joint_speed`, a longer one on its points' times ([`ServeConfig`]), a
/// new trajectory replacing the one under way (as a `ros2_control`
/// trajectory controller does). Everything runs on the robot's clock,
/// `rate` times real time, published on [`CLOCK_TOPIC`] every
/// [`CLOCK_PERIOD_S`] of it. A point the hardware refuses ends the
/// trajectory there; `log` hears why.
pub fn serve_robot<H: Arm + LineScanner + RangeSensors>(
    hw: &mut H,
    robot: &Robot,
    node: &mut Ros2Node,
    config: &ServeConfig,
    stop: &AtomicBool,
    log: &mut dyn FnMut(&str),
) -> Result<ServeStats, Ros2Error> {
    let spec = &config.ros2;
    let names = crate::ros_joint_names(spec, robot)?;
    let states = node.publisher::<record::bag::msg::JointState>(&spec.joint_states_topic)?;
    let scans = node.publisher::<record::bag::msg::LaserScan>(&spec.scan_topic)?;
    let ranges: Vec<_> = (0..robot.range_finders.len())
        .map(|k| node.publisher::<record::bag::msg::Range>(&spec.range_topic(k)))
        .collect::<Result<_, _>>()?;
    let commands = node.subscription::<JointTrajectory>(&spec.trajectory_topic)?;
    let (requests, exact) = if config.lockstep {
        (
            Some(node.subscription::<record::bag::msg::StdString>(SENSE_TOPIC)?),
            Some(node.publisher::<record::bag::msg::Float64MultiArray>(EXACT_RANGES_TOPIC)?),
        )
    } else {
        (None, None)
    };
    config.check()?;
    let clock = node.clock_publisher::<record::bag::msg::Clock>(CLOCK_TOPIC)?;
    let bearings = hw.bearings_rad().to_vec();
    let mut stats = ServeStats::default();
    let mut execution = Execution::standing(0.0, hw.joints());
    let tick = Duration::try_from_secs_f64(config.tick_s)
        .unwrap_or(Duration::from_millis(5))
        .min(Duration::from_secs(1));
    let start = Instant::now();
    let start_ns = now_ns();
    let mut free = FreeScanner::new(config, &bearings, start_ns);
    let (mut next_state, mut next_range, mut next_clock) = (0.0, 0.0, 0.0);
    let mut ready = false;
    while !stop.load(Ordering::Relaxed) {
        // The robot's time: `rate` robot seconds per wall second.
        let t = config.rate * start.elapsed().as_secs_f64();
        let stamp = start_ns.saturating_add((t * 1e9) as u64);
        if t >= next_clock {
            next_clock = t + CLOCK_PERIOD_S;
            clock
                .publish(record::bag::msg::Clock {
                    clock: record::bag::msg::Time::from_nanos(stamp),
                })
                .map_err(|e| transfer(CLOCK_TOPIC, e))?;
        }
        while let Some((trajectory, _)) = commands
            .take()
            .map_err(|e| transfer(&spec.trajectory_topic, e))?
        {
            let taken = take_trajectory(
                &mut execution,
                &trajectory,
                (&names, &robot.name),
                hw,
                (t, start_ns),
                config,
            );
            match taken {
                Ok(()) => stats.trajectories += 1,
                Err(why) => {
                    stats.refused += 1;
                    log(&format!("trajectory refused: {why}"));
                }
            }
        }
        let reached = execution.step(t, hw).unwrap_or_else(|e| {
            stats.refused += 1;
            log(&format!("trajectory stopped: {e}"));
            false
        });
        stats.states += publish_states(
            &states,
            (&spec.joint_states_topic, &names),
            (&execution, &hw.joints()),
            (t, start_ns, reached),
            &mut next_state,
            config,
        )?;
        while !config.lockstep
            && let Some(msg) = free.scan_due(t, hw, &execution)?
        {
            scans
                .publish(msg)
                .map_err(|e| transfer(&spec.scan_topic, e))?;
            stats.scans += 1;
        }
        let mut scan_now = false;
        let mut read_now = !config.lockstep && !ranges.is_empty() && t >= next_range;
        if read_now {
            next_range = t + config.range_period_s;
        }
        // Requests are served one at a time, in order: a seed before the
        // scan asked after it.
        // A lockstep robot answers once whoever asks can hear the answer
        // (an answer sent before its subscription matched is lost).
        if !ready {
            ready = (bearings.is_empty() || node.subscriptions_of(&scans) > 0)
                && ranges.iter().all(|p| node.subscriptions_of(p) > 0)
                && (ranges.is_empty()
                    || exact.as_ref().is_none_or(|p| node.subscriptions_of(p) > 0));
        }
        let request = match &requests {
            Some(r) if ready && !read_now => r
                .take()
                .map_err(|e| transfer(SENSE_TOPIC, e))?
                .map(|(m, _)| m.data),
            _ => None,
        };
        match request
            .as_deref()
            .map(str::split_whitespace)
            .map(Iterator::collect::<Vec<_>>)
            .as_deref()
        {
            None => {}
            Some(["scan"]) if bearings.is_empty() => {
                log("sense request `scan`: this robot has no scanner");
            }
            Some(["scan"]) => scan_now = true,
            Some(["ranges"]) => read_now = true,
            Some(["seed", n]) => match n.parse::<u64>() {
                Ok(seed) => hw.seed_noise(seed),
                Err(_) => log(&format!("sense request `seed {n}`: not a seed")),
            },
            Some(other) => log(&format!(
                "sense request {other:?} not understood (scan, ranges or seed N)"
            )),
        }
        if scan_now {
            let msg = free.message(stamp, &hw.scan()?, 0.0);
            scans
                .publish(msg)
                .map_err(|e| transfer(&spec.scan_topic, e))?;
            stats.scans += 1;
        }
        if read_now {
            let readings = hw.read_all()?;
            for (k, (p, r)) in ranges.iter().zip(&readings).enumerate() {
                let max = robot.range_finders[k].max_range_m + config.finder_range_slack_m;
                let msg = record::bag::range(stamp, k, max, r.map(|r| r.distance_m));
                p.publish(msg)
                    .map_err(|e| transfer(&spec.range_topic(k), e))?;
            }
            if let Some(p) = &exact {
                p.publish(exact_readings(&readings))
                    .map_err(|e| transfer(EXACT_RANGES_TOPIC, e))?;
            }
            stats.readings += 1;
        }
        if request.is_some() {
            // Another request may be waiting: no sleep.
            continue;
        }
        std::thread::sleep(tick);
    }
    Ok(stats)
}

#[cfg(test)]
mod tests {
    use super::waypoints;
    use record::bag::msg::{JointTrajectory, JointTrajectoryPoint};

    fn trajectory(names: &[&str], points: &[&[f64]]) -> JointTrajectory {
        JointTrajectory {
            joint_names: names.iter().map(|&n| n.to_owned()).collect(),
            points: points
                .iter()
                .map(|p| JointTrajectoryPoint {
                    positions: p.to_vec(),
                    ..JointTrajectoryPoint::default()
                })
                .collect(),
            ..JointTrajectory::default()
        }
    }

    #[test]
    fn a_trajectory_runs_on_its_times_and_a_single_point_at_the_joint_speed() {
        use super::Execution;
        let close = |got: Option<(Vec<f64>, bool)>, want: &[f64], reached: bool| {
            let (q, r) = got.unwrap();
            assert_eq!(r, reached, "{q:?}");
            for (a, b) in q.iter().zip(want) {
                assert!((a - b).abs() < 1e-12, "{q:?} against {want:?}");
            }
        };
        let run = |points: Vec<Vec<f64>>, times: &[f64], now: f64, begin: Option<f64>| {
            let mut e = Execution::standing(now, vec![0.0, 0.0]);
            e.replace(points, times, (now, begin), 0.5);
            e
        };
        // Two points due 1 s and 3 s after t = 10, from (0, 0).
        let mut e = run(
            vec![vec![1.0, 0.0], vec![1.0, 2.0]],
            &[1.0, 3.0],
            10.0,
            None,
        );
        close(e.at(10.5), &[0.5, 0.0], false);
        close(e.at(11.0), &[1.0, 0.0], true);
        close(e.at(12.0), &[1.0, 1.0], false);
        // Where the arm was, and where it is due.
        assert_eq!(e.position(10.5), vec![0.5, 0.0]);
        assert_eq!(e.position(12.5), vec![1.0, 1.5]);
        close(e.at(13.5), &[1.0, 2.0], true);
        assert!(e.at(14.0).is_none());
        // What is older than the memory is forgotten.
        assert_eq!(e.position(10.5), vec![1.0, 0.0]);
        // One point: at 0.5 rad/s, 2 rad take 4 s whatever its time.
        let mut e = run(vec![vec![2.0, 0.0]], &[0.1], 0.0, None);
        close(e.at(1.0), &[0.5, 0.0], false);
        close(e.at(4.0), &[2.0, 0.0], true);
        // A point not timed after its predecessor runs at the joint speed:
        // 2 rad at 0.5 rad/s after the first point's 1 s.
        let mut e = run(vec![vec![1.0, 0.0], vec![1.0, 2.0]], &[1.0, 0.5], 0.0, None);
        // (The first point was passed on the way: reached.)
        close(e.at(3.0), &[1.0, 1.0], true);
        close(e.at(5.0), &[1.0, 2.0], true);
        // A trajectory stamped to begin later: the one under way runs on
        // until then (here 1 s of the move to (2, 0) at 0.5 rad/s), and
        // the new one's times count from its stamp. A stamp already past
        // begins now.
        let mut e = run(vec![vec![2.0, 0.0]], &[0.0], 0.0, None);
        close(e.at(0.5), &[0.25, 0.0], false);
        e.replace(
            vec![vec![0.5, 0.0], vec![0.5, 1.0]],
            &[0.5, 1.5],
            (0.5, Some(1.0)),
            0.5,
        );
        close(e.at(1.0), &[0.5, 0.0], false);
        close(e.at(1.5), &[0.5, 0.0], true);
        close(e.at(2.0), &[0.5, 0.5], false);
        let mut e = run(vec![vec![2.0, 0.0]], &[0.0], 0.0, None);
        e.replace(
            vec![vec![0.0, 0.0], vec![0.0, 1.0]],
            &[1.0, 2.0],
            (1.0, Some(0.2)),
            0.5,
        );
        close(e.at(1.5), &[0.25, 0.0], false);
        close(e.at(3.0), &[0.0, 1.0], true);
    }

    #[test]
    fn trajectory_points_become_joint_vectors_in_the_robot_s_order() {
        let robot = robot::builtin("point3").unwrap();
        let names = robot.joint_names();
        let owned: Vec<String> = names.iter().map(|&s| s.to_owned()).collect();
        let q = [0.1, 0.2, 0.3];
        let at = |t: &JointTrajectory| waypoints(t, &owned, &robot.name, &q);
        // Reordered names, one joint left out (it stays where it is).
        let t = trajectory(&[names[2], names[0]], &[&[3.0, 1.0], &[6.0, 4.0]]);
        assert_eq!(
            at(&t).unwrap(),
            vec![vec![1.0, 0.2, 3.0], vec![4.0, 0.2, 6.0]]
        );
        let e = at(&trajectory(&["elbow"], &[&[1.0]])).unwrap_err();
        assert!(e.contains("joint `elbow`"), "{e}");
        let e = at(&trajectory(&[names[0]], &[&[1.0, 2.0]])).unwrap_err();
        assert!(e.contains("point 0: 2 positions for 1 joints"), "{e}");
    }
}
