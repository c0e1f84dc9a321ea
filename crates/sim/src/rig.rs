//! The simulated robot: [`SimRig`] implements the hardware traits of `hw`
//! ([`Arm`], [`LineScanner`], [`RangeSensors`]) against a ground-truth
//! [`World`], so the loops above it cannot tell it from a real robot's
//! driver.

use crate::SimError;
use geom::{Isometry3, Real};
use hw::motion::{JointSample, LineMotion, MovingScan, MovingScanner};
use hw::{Arm, HwError, LineScanner, RangeSensors, ScanReadings};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use robot::{Posture, Robot};
use scenario::LoadedScenario;
use scene::World;
use sensor::{RangeFinder, Scanner, SensorPoint};
use std::sync::Arc;

/// A simulated robot with its sensors in a ground-truth world. Its scanner
/// reports what a ROS 2 `LaserScan` carries (float32 ranges and
/// intensities, [`ScanReadings::in_float32`]), so a run that drives it over
/// ROS 2 sees what a run in process does.
#[derive(Clone, Debug)]
pub struct SimRig {
    robot: Robot,
    world: Arc<World>,
    world_from_base: Isometry3,
    posture: Posture,
    scanner: Option<Scanner>,
    rng: ChaCha8Rng,
    range_noise_sigma_m: Real,
    /// The continuous motion under way and the scans taken on it.
    motion: Option<(LineMotion, usize)>,
    /// When a continuous motion's first scan begins, seconds after its
    /// start ([`SimRig::set_scan_phase_s`]).
    scan_phase_s: Real,
}

impl SimRig {
    /// The rig of a scenario: the robot of [`LoadedScenario::build_robot`]
    /// (with the `[range_sensors]` mounts) at its start joints, in the
    /// world of [`LoadedScenario::build_world`], with the scenario's range
    /// noise σ; `seed` drives all sensor noise. The scanner is not
    /// simulated (surface following uses range finders only).
    pub fn of_scenario(loaded: &LoadedScenario, seed: u64) -> Result<Self, SimError> {
        let robot = loaded.build_robot()?;
        let world = Arc::new(loaded.build_world()?);
        let mut rig = Self::new(
            robot,
            world,
            loaded.scenario.world_from_base(),
            &loaded.scenario.robot.start_joints,
            None,
            seed,
        )?;
        rig.set_range_noise_sigma_m(loaded.scenario.range_sensors.noise_sigma_m)?;
        Ok(rig)
    }

    /// A rig at joint values `q`. `seed` drives all sensor noise.
    pub fn new(
        robot: Robot,
        world: Arc<World>,
        world_from_base: Isometry3,
        q: &[Real],
        scanner: Option<Scanner>,
        seed: u64,
    ) -> Result<Self, SimError> {
        Ok(Self {
            posture: Posture::new(&robot, q)?,
            robot,
            world,
            world_from_base,
            scanner,
            rng: ChaCha8Rng::seed_from_u64(seed),
            range_noise_sigma_m: 0.0,
            motion: None,
            scan_phase_s: 0.0,
        })
    }

    /// Restart the sensor noise from `seed` (a runner that reseeds at fixed
    /// points, e.g. every viewpoint, can replay from any of them).
    pub fn reseed(&mut self, seed: u64) {
        self.rng = ChaCha8Rng::seed_from_u64(seed);
    }

    /// Set the standard deviation of the Gaussian noise added to every
    /// range-finder reading ([`RangeSensors::read_all`]), metres; 0 (the
    /// default) gives exact readings. The noise is drawn from the rig's seeded
    /// RNG, so the same seed, poses and reads give the same readings. An error
    /// (σ not finite, or negative) leaves the rig unchanged.
    pub fn set_range_noise_sigma_m(&mut self, sigma_m: Real) -> Result<(), SimError> {
        if !(sigma_m.is_finite()
            && (0.0..=scenario::range_sensors::MAX_NOISE_SIGMA_M).contains(&sigma_m))
        {
            return Err(SimError::InvalidArgument {
                what: "range noise σ (range_sensors.noise_sigma_m)".into(),
                message: format!("expected a standard deviation from 0 to 1 metre, got {sigma_m}"),
            });
        }
        self.range_noise_sigma_m = sigma_m;
        Ok(())
    }

    /// Begin each continuous motion's scans `phase_s` seconds after its
    /// start (0 by default: the first scan begins with the motion). A real
    /// scanner runs free, so its scans begin at any moment of their
    /// period when a motion starts (`surveyor sim-robot`'s do); a run's
    /// choices are sensitive to it. An error unless `phase_s` is in
    /// `[0, scan_time)`.
    pub fn set_scan_phase_s(&mut self, phase_s: Real) -> Result<(), SimError> {
        let period = self
            .scanner
            .as_ref()
            .map_or(0.0, |s| s.config().scan_time_s);
        if !(phase_s >= 0.0 && phase_s < period) {
            return Err(SimError::InvalidArgument {
                what: "scan phase".into(),
                message: format!("{phase_s} s: expected seconds in [0, {period}) (the scan time)"),
            });
        }
        self.scan_phase_s = phase_s;
        Ok(())
    }

    /// The range-finder noise σ in use, metres.
    pub fn range_noise_sigma_m(&self) -> Real {
        self.range_noise_sigma_m
    }

    /// The rig of a scenario's robot with every sensor it carries: its range
    /// finders, with the scenario's range noise ([`SimRig::of_scenario`]),
    /// and when the robot has a scanner mount, the scenario's scanner (the
    /// URG-04LX by default). What `surveyor sim-robot` serves.
    pub fn with_every_sensor(loaded: &LoadedScenario, seed: u64) -> Result<Self, SimError> {
        let mut rig = Self::of_scenario(loaded, seed)?;
        if rig.robot.scanner.is_some() {
            let spec = loaded.scenario.scanner.clone().unwrap_or_default();
            rig.scanner = Some(Scanner::new(spec.config)?);
        }
        Ok(rig)
    }

    /// The scanner's shortest and longest range, metres (`None` without one).
    pub fn scan_range_m(&self) -> Option<(Real, Real)> {
        self.scanner
            .as_ref()
            .map(|s| (s.config().min_range_m, s.config().max_range_m))
    }

    /// The robot model.
    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// The world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The world, shared.
    pub fn world_arc(&self) -> Arc<World> {
        Arc::clone(&self.world)
    }

    /// Where the base stands.
    pub fn world_from_base(&self) -> Isometry3 {
        self.world_from_base
    }

    /// `world_from_link` of every link at the current pose.
    pub fn world_frames(&self) -> Vec<Isometry3> {
        self.posture
            .base_from_link()
            .iter()
            .map(|f| self.world_from_base * f)
            .collect()
    }

    /// The scanner pose in the world at the current joints; `None` when
    /// the robot carries no scanner.
    pub fn world_from_scanner(&self) -> Option<Isometry3> {
        let base_from_scanner = self.posture.base_from_scanner(&self.robot)?;
        Some(self.world_from_base * base_from_scanner)
    }
}

impl Arm for SimRig {
    fn joints(&self) -> Vec<Real> {
        self.posture.joints().to_vec()
    }

    fn move_to(&mut self, q: &[Real]) -> Result<(), HwError> {
        Ok(self.posture.move_to(&self.robot, q)?)
    }
}

impl LineScanner for SimRig {
    fn bearings_rad(&self) -> &[Real] {
        self.scanner.as_ref().map_or(&[], |s| s.bearings_rad())
    }

    fn scan(&mut self) -> Result<ScanReadings, HwError> {
        let pose = self.world_from_scanner().ok_or(HwError::NoScanner)?;
        let scanner = self.scanner.as_ref().ok_or(HwError::NoScanner)?;
        let scan = scanner.scan(self.world.as_ref(), &pose, &mut self.rng);
        Ok(ScanReadings::of_simulated(&scan).in_float32())
    }

    fn seed_noise(&mut self, seed: u64) {
        self.reseed(seed);
    }

    fn moving(&mut self) -> Option<&mut dyn MovingScanner> {
        if self.scanner.is_some() {
            Some(self)
        } else {
            None
        }
    }

    /// Each beam cast from the scanner pose of its moment on `path`
    /// ([`robot::moving::beam_poses`]).
    fn scan_along(
        &mut self,
        path: &[JointSample],
        start_s: Real,
        time_increment_s: Real,
    ) -> Option<Result<ScanReadings, HwError>> {
        let scanner = self.scanner.as_ref()?;
        let poses = robot::moving::beam_poses(
            &self.robot,
            &self.world_from_base,
            path,
            start_s,
            time_increment_s,
            scanner.ray_count(),
        );
        Some(poses.map_err(HwError::from).map(|poses| {
            let scan = scanner.scan_posed(self.world.as_ref(), &poses, &mut self.rng);
            ScanReadings::of_simulated(&scan).in_float32()
        }))
    }
}

/// Seconds between the poses a moving scan's beams are cast from (each
/// beam's pose is interpolated between them; the loop places beams from
/// joint states ten times as far apart).
const TRUTH_PERIOD_S: Real = 0.001;

/// The arm follows a continuous motion exactly; the scanner takes a scan
/// every `scan_time_s` from the motion's start, each beam cast from the
/// scanner pose of its own moment, until the arm rests.
impl MovingScanner for SimRig {
    fn start_motion(&mut self, motion: &LineMotion) -> Result<(), HwError> {
        scenario::job::check_stands_at(&self.joints(), &motion.from, 1e-9).map_err(|message| {
            HwError::Setting {
                what: "continuous motion".into(),
                message: format!("the arm {message}"),
            }
        })?;
        self.robot.check_within_limits(&motion.to)?;
        self.motion = Some((motion.clone(), 0));
        Ok(())
    }

    fn next_scan(&mut self) -> Result<Option<MovingScan>, HwError> {
        let scanner = self.scanner.as_ref().ok_or(HwError::NoScanner)?;
        let (motion, k) = self.motion.as_mut().ok_or_else(|| HwError::Setting {
            what: "continuous motion".into(),
            message: "a scan asked before a motion began".into(),
        })?;
        let scan_time = scanner.config().scan_time_s;
        let start = *k as Real * scan_time + self.scan_phase_s;
        if start >= motion.duration_s() {
            let end = motion.end();
            self.motion = None;
            self.posture.move_to(&self.robot, &end)?;
            return Ok(None);
        }
        *k += 1;
        let n = scanner.ray_count();
        // As a `LaserScan` states it (float32), so that a bag places the
        // beams where the loop did.
        let dt = sensor::float32(hw::motion::time_increment_s(
            scan_time,
            scanner.bearings_rad(),
        ));
        let last = start + (n.max(1) - 1) as Real * dt;
        let truth = hw::motion::sampled(start, last, TRUTH_PERIOD_S, |t| motion.at(t));
        let joints = motion.samples(start, last);
        let now = motion.at(start + scan_time);
        let readings = self
            .scan_along(&truth, start, dt)
            .ok_or(HwError::NoScanner)??;
        self.posture.move_to(&self.robot, &now)?;
        Ok(Some(MovingScan {
            readings,
            start_s: start,
            time_increment_s: dt,
            joints,
        }))
    }

    fn brake(&mut self) -> Result<LineMotion, HwError> {
        let scan_time = self
            .scanner
            .as_ref()
            .map_or(0.0, |s| s.config().scan_time_s);
        let (motion, k) = self.motion.as_mut().ok_or_else(|| HwError::Setting {
            what: "continuous motion".into(),
            message: "braking asked before a motion began".into(),
        })?;
        // At the end of the last scan taken.
        *motion = motion.braked(*k as Real * scan_time + self.scan_phase_s);
        Ok(motion.clone())
    }
}

impl RangeSensors for SimRig {
    fn read_all(&mut self) -> Result<Vec<Option<SensorPoint>>, HwError> {
        let sigma = self.range_noise_sigma_m;
        let Self {
            robot,
            world,
            world_from_base,
            rng,
            posture,
            ..
        } = self;
        let frames = posture.base_from_link();
        // Sensors in mount order, one noise draw per hit: the readings are a
        // function of the seed and the sequence of poses and reads.
        robot
            .range_finders
            .iter()
            .map(|m| {
                let base_from_link =
                    frames
                        .get(m.link.0)
                        .ok_or_else(|| robot::RobotError::InvalidRobot {
                            robot: robot.name.clone(),
                            message: format!(
                                "range finder on link {} out of range ({} links)",
                                m.link,
                                frames.len()
                            ),
                        })?;
                let rf = RangeFinder {
                    origin: m.origin,
                    axis: m.axis,
                    max_range_m: m.max_range_m,
                    noise_sigma_m: sigma,
                };
                let world_from_link = *world_from_base * base_from_link;
                Ok(rf.measure(world.as_ref(), &world_from_link, rng))
            })
            .collect()
    }
}

impl SimRig {
    /// The bag of a run of this rig from where it stands
    /// ([`record::bag::RunBag`]): its scanner's bearings and ranges, and
    /// range finders that report up to their range plus 10σ of the rig's
    /// range noise (a simulated reading can lie that far past it).
    pub fn run_bag(&self) -> Result<record::bag::RunBag, SimError> {
        let config = record::bag::BagConfig {
            scan_range_m: self
                .scan_range_m()
                .unwrap_or(record::bag::BagConfig::default().scan_range_m),
            finder_range_slack_m: 10.0 * self.range_noise_sigma_m,
        };
        Ok(record::bag::RunBag::new(
            &self.robot,
            &self.world_from_base,
            &self.joints(),
            self.bearings_rad(),
            config,
        )?)
    }
}
