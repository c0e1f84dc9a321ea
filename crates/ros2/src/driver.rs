//! The `hw` traits over a ROS 2 robot: joint states in, joint trajectories
//! out, scans and range readings in.

use crate::serve::SENSE_TOPIC;
use crate::{Ros2Error, Ros2Node, TRAJECTORY_TOPIC};
use geom::{Isometry3, Real};
use hw::{Arm, HwError, LineScanner, RangeSensors, ScanReadings};
use record::bag::msg::{
    Header, JointState, JointTrajectory, JointTrajectoryPoint, LaserScan, Range, StdString, Time,
};
use record::bag::topics;
use robot::Robot;
use ros2_client::{Publisher, Subscription};
use sensor::SensorPoint;
use std::time::{Duration, Instant};

/// How the driver talks to its robot.
#[derive(Clone, Debug, PartialEq)]
pub struct DriverConfig {
    /// A move is done when every joint is this close to its goal, radians.
    pub tolerance_rad: Real,
    /// The joint speed a trajectory's time is planned at, rad/s.
    pub joint_speed: Real,
    /// How long past a move's planned time (or a sensing request) to wait
    /// before giving up, seconds.
    pub timeout_s: Real,
    /// Ask for each scan, reading and noise seed on the sense topic (a
    /// lockstep `surveyor sim-robot`), instead of taking the next ones the
    /// robot publishes.
    pub lockstep: bool,
}

impl Default for DriverConfig {
    fn default() -> Self {
        Self {
            tolerance_rad: 1e-3,
            joint_speed: 1.0,
            timeout_s: 10.0,
            lockstep: false,
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
    _node: Ros2Node,
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

/// `seconds` from now; a setting that is no duration (negative, not
/// finite, too long) waits a day rather than panicking.
fn after(seconds: Real) -> Instant {
    let day = Duration::from_secs(86_400);
    let wait = Duration::try_from_secs_f64(seconds).unwrap_or(day).min(day);
    Instant::now() + wait
}

fn poll<T>(
    deadline: Instant,
    what: &str,
    mut take: impl FnMut() -> Result<Option<T>, HwError>,
) -> Result<T, HwError> {
    loop {
        if let Some(v) = take()? {
            return Ok(v);
        }
        if Instant::now() > deadline {
            return Err(device(format!("no {what} before the timeout")));
        }
        std::thread::sleep(Duration::from_micros(200));
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
        let states = node.subscription::<JointState>(topics::JOINT_STATES)?;
        let scans = node.subscription::<LaserScan>(topics::SCAN)?;
        let ranges = (0..robot.range_finders.len())
            .map(|k| node.subscription::<Range>(&topics::range_finder(k)))
            .collect::<Result<_, _>>()?;
        let trajectories = node.publisher::<JointTrajectory>(TRAJECTORY_TOPIC)?;
        let sense = if config.lockstep {
            Some(node.publisher::<StdString>(SENSE_TOPIC)?)
        } else {
            None
        };
        let mut hw = Self {
            robot: robot.clone(),
            world_from_base: *world_from_base,
            bearings: bearings.to_vec(),
            names: robot.joint_names().iter().map(|&s| s.to_owned()).collect(),
            q: Vec::new(),
            config,
            states,
            scans,
            ranges,
            trajectories,
            sense,
            _node: node,
        };
        let deadline = after(hw.config.timeout_s);
        hw.q = poll(deadline, "joint state", || hw.latest_state())?;
        Ok(hw)
    }

    /// The newest joint state received (in the robot's joint order), if any.
    fn latest_state(&self) -> Result<Option<Vec<Real>>, HwError> {
        let mut latest = None;
        while let Some((js, _)) = self
            .states
            .take()
            .map_err(|e| device(format!("{}: {e:?}", topics::JOINT_STATES)))?
        {
            let mut q = Vec::with_capacity(self.names.len());
            for n in &self.names {
                let i = js.name.iter().position(|x| x == n).ok_or_else(|| {
                    device(format!("{} names no joint `{n}`", topics::JOINT_STATES))
                })?;
                q.push(js.position.get(i).copied().unwrap_or(Real::NAN));
            }
            latest = Some(q);
        }
        Ok(latest)
    }

    /// Ask a lockstep robot for `what`.
    fn ask(&self, what: String) -> Result<(), HwError> {
        if let Some(p) = &self.sense {
            p.publish(StdString { data: what })
                .map_err(|e| device(format!("{SENSE_TOPIC}: {e:?}")))?;
        }
        Ok(())
    }

    fn deadline(&self) -> Instant {
        after(self.config.timeout_s)
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
        let secs = far / self.config.joint_speed;
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
            .map_err(|e| device(format!("{TRAJECTORY_TOPIC}: {e:?}")))?;
        let deadline = after(secs + self.config.timeout_s);
        let tolerance = self.config.tolerance_rad;
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
            if Instant::now() > deadline {
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
                .map_err(|e| device(format!("{}: {e:?}", topics::SCAN)))
        };
        // Scans published before the arm stood here are stale.
        while take(&self.scans)?.is_some() {}
        self.ask("scan".to_owned())?;
        let scan = poll(self.deadline(), "scan", || take(&self.scans))?;
        let (bearings, ranges_m, intensities) = record::bag::scan_rays(&scan);
        if bearings.len() != self.bearings.len() {
            return Err(device(format!(
                "{}: {} rays, the scanner has {}",
                topics::SCAN,
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
        for s in &self.ranges {
            while s
                .take()
                .map_err(|e| device(format!("range: {e:?}")))?
                .is_some()
            {}
        }
        self.ask("ranges".to_owned())?;
        let frames = self.robot.forward_kinematics(&self.q)?;
        let deadline = self.deadline();
        let mut out = Vec::with_capacity(self.ranges.len());
        for (k, (s, m)) in self
            .ranges
            .iter()
            .zip(&self.robot.range_finders)
            .enumerate()
        {
            let topic = topics::range_finder(k);
            let r = poll(deadline, &topic, || {
                s.take()
                    .map(|m| m.map(|(m, _)| m))
                    .map_err(|e| device(format!("{topic}: {e:?}")))
            })?;
            let d = Real::from(r.range);
            if !(d.is_finite() && d >= Real::from(r.min_range) && d <= Real::from(r.max_range)) {
                out.push(None);
                continue;
            }
            let world_from_link = self.world_from_base
                * frames
                    .get(m.link.0)
                    .ok_or_else(|| device(format!("range finder {k} on no link")))?;
            let sensor = world_from_link * m.origin;
            let axis = world_from_link * m.axis;
            out.push(Some(SensorPoint {
                point: sensor + axis.into_inner() * d,
                axis,
                sensor,
                distance_m: d,
            }));
        }
        Ok(out)
    }
}
