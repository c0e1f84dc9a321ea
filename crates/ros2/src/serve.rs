//! Any hardware served as a ROS 2 robot (`surveyor sim-robot`): it
//! publishes its joint states, its scans and its range readings, and
//! executes the joint trajectories it is sent.

use crate::{Ros2Error, Ros2Node};
use geom::Real;
use hw::{Arm, LineScanner, RangeSensors};
use record::bag::msg::JointTrajectory;
use robot::Robot;
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

/// A trajectory under way: where the last segment began (robot time,
/// seconds, and joints) and the points still ahead, each with the robot
/// time it is due.
#[derive(Debug, Default)]
struct Execution {
    from: (Real, Vec<Real>),
    ahead: VecDeque<(Real, Vec<Real>)>,
}

impl Execution {
    /// The execution of `points` received at robot time `now` with the arm
    /// at `q`. A trajectory of one point is a move there at `joint_speed`
    /// (its fastest joint), whatever its time; the points of a longer one
    /// are due at their `time_from_start` after `now` (as a `ros2_control`
    /// joint trajectory controller takes them), a point whose time is not
    /// after its predecessor's at `joint_speed` after it.
    fn new(
        points: Vec<Vec<Real>>,
        times_s: &[Real],
        now: Real,
        q: Vec<Real>,
        joint_speed: Real,
    ) -> Self {
        let timed = points.len() > 1;
        let mut ahead = VecDeque::with_capacity(points.len());
        let (mut t, mut at) = (now, q.clone());
        for (p, &after) in points.into_iter().zip(times_s) {
            let far = at
                .iter()
                .zip(&p)
                .map(|(a, b)| (b - a).abs())
                .fold(0.0, Real::max);
            t = if timed && now + after > t {
                now + after
            } else {
                t + far / joint_speed
            };
            at.clone_from(&p);
            ahead.push_back((t, p));
        }
        Self {
            from: (now, q),
            ahead,
        }
    }

    /// Where the arm is due at robot time `t`, and whether a point was
    /// reached on the way (those are then dropped); `None` when nothing is
    /// under way.
    fn at(&mut self, t: Real) -> Option<(Vec<Real>, bool)> {
        let mut reached = false;
        while let Some((due, _)) = self.ahead.front()
            && *due <= t
        {
            if let Some(point) = self.ahead.pop_front() {
                self.from = point;
            }
            reached = true;
        }
        let Some((due, q1)) = self.ahead.front() else {
            return reached.then(|| (self.from.1.clone(), true));
        };
        let (t0, q0) = &self.from;
        let s = if *due > *t0 {
            ((t - t0) / (due - t0)).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let q = q0.iter().zip(q1).map(|(a, b)| a + s * (b - a)).collect();
        Some((q, reached))
    }
}

/// The execution of `trajectory` received at robot time `t` by `hw` (the
/// robot of `names`, its joints' ROS names), or why not.
fn execution_of<H: Arm>(
    trajectory: &JointTrajectory,
    names: &[String],
    robot: &str,
    hw: &H,
    t: Real,
    config: &ServeConfig,
) -> Result<Execution, String> {
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
    Ok(Execution::new(
        points,
        &times,
        t,
        hw.joints(),
        config.joint_speed,
    ))
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
    let mut execution = Execution::default();
    let tick = Duration::try_from_secs_f64(config.tick_s)
        .unwrap_or(Duration::from_millis(5))
        .min(Duration::from_secs(1));
    let start = Instant::now();
    let start_ns = now_ns();
    let (mut next_state, mut next_scan, mut next_range, mut next_clock) = (0.0, 0.0, 0.0, 0.0);
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
            match execution_of(&trajectory, &names, &robot.name, hw, t, config) {
                Ok(e) => {
                    execution = e;
                    stats.trajectories += 1;
                }
                Err(why) => {
                    stats.refused += 1;
                    log(&format!("trajectory refused: {why}"));
                }
            }
        }
        let mut reached = false;
        if let Some((q, arrived)) = execution.at(t) {
            reached = arrived;
            if let Err(e) = hw.move_to(&q) {
                // A pose the hardware refuses ends the trajectory.
                stats.refused += 1;
                log(&format!("trajectory stopped: {e}"));
                execution = Execution::default();
                reached = false;
            }
        }
        if t >= next_state || reached {
            next_state = t + config.state_period_s;
            let msg = record::bag::joint_state(stamp, &names, &hw.joints());
            states
                .publish(msg)
                .map_err(|e| transfer(&spec.joint_states_topic, e))?;
            stats.states += 1;
        }
        let mut scan_now = !config.lockstep && !bearings.is_empty() && t >= next_scan;
        let mut read_now = !config.lockstep && !ranges.is_empty() && t >= next_range;
        if scan_now {
            next_scan = t + config.scan_period_s;
        }
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
            Some(r) if ready && !scan_now && !read_now => r
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
            let s = hw.scan()?;
            let msg = record::bag::laser_scan(
                stamp,
                &bearings,
                &s.ranges_m,
                &s.intensities,
                config.scan_range_m,
                config.scan_period_s,
            );
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
        // Two points due 1 s and 3 s after t = 10, from (0, 0).
        let mut e = Execution::new(
            vec![vec![1.0, 0.0], vec![1.0, 2.0]],
            &[1.0, 3.0],
            10.0,
            vec![0.0, 0.0],
            0.5,
        );
        close(e.at(10.5), &[0.5, 0.0], false);
        close(e.at(11.0), &[1.0, 0.0], true);
        close(e.at(12.0), &[1.0, 1.0], false);
        close(e.at(13.5), &[1.0, 2.0], true);
        assert!(e.at(14.0).is_none());
        // One point: at 0.5 rad/s, 2 rad take 4 s whatever its time.
        let mut e = Execution::new(vec![vec![2.0, 0.0]], &[0.1], 0.0, vec![0.0, 0.0], 0.5);
        close(e.at(1.0), &[0.5, 0.0], false);
        close(e.at(4.0), &[2.0, 0.0], true);
        // A point not timed after its predecessor runs at the joint speed:
        // 2 rad at 0.5 rad/s after the first point's 1 s.
        let mut e = Execution::new(
            vec![vec![1.0, 0.0], vec![1.0, 2.0]],
            &[1.0, 0.5],
            0.0,
            vec![0.0, 0.0],
            0.5,
        );
        // (The first point was passed on the way: reached.)
        close(e.at(3.0), &[1.0, 1.0], true);
        close(e.at(5.0), &[1.0, 2.0], true);
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
