//! The jobs that run a scenario on any hardware: set it up from the
//! scenario, drive a loop over the `hw` traits on the robot clock, record
//! `run.mcap`, and write the run folder. A robot's run needs no simulator;
//! `sim` runs the same jobs on its `SimRig` and judges them against the
//! ground truth.
//!
//! | module | the job |
//! |---|---|
//! | [`explore`] | AXBAM exploration: [`explore::HardwareExplore`], [`explore::explore_with`] |
//! | [`follow`] | surface following: [`follow::FollowSetup`], [`follow::HardwareFollow`], [`follow::follow_with`] |
//! | [`reach`] | which true faces a follower can reach ([`reach::unreachable_faces`], given a priori) |

pub mod explore;
pub mod follow;
pub mod reach;

use geom::Real;

/// What can go wrong running a scenario's job (on the simulator, whose
/// jobs fail the same way, or on a robot).
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// A scenario file or field is invalid.
    #[error("scenario {source_name}: {message}")]
    Scenario {
        /// The file or scenario name.
        source_name: String,
        /// What is wrong.
        message: String,
    },
    /// A scenario could not be read or built.
    #[error(transparent)]
    ScenarioFile(Box<crate::ScenarioError>),
    /// The hardware (a robot, the simulated rig) refused or failed.
    #[error(transparent)]
    Hw(Box<hw::HwError>),
    /// A run-folder file could not be written or read.
    #[error(transparent)]
    Record(Box<record::RecordError>),
    /// Blast planning failed.
    #[error(transparent)]
    Blast(Box<blast::BlastError>),
    /// The robot model rejected something.
    #[error(transparent)]
    Robot(Box<robot::RobotError>),
    /// The scene could not be built or loaded.
    #[error(transparent)]
    Scene(#[from] scene::SceneError),
    /// An argument of a library call is invalid.
    #[error("{what}: {message}")]
    InvalidArgument {
        /// The argument.
        what: String,
        /// What is wrong.
        message: String,
    },
    /// A sensor configuration is invalid.
    #[error(transparent)]
    Sensor(#[from] sensor::SensorError),
    /// Planning (the C-space model, safety) failed.
    #[error(transparent)]
    Plan(Box<plan::PlanError>),
    /// Exploration failed.
    #[error(transparent)]
    Explore(Box<::explore::ExploreError>),
    /// A map refused a value.
    #[error(transparent)]
    Map(Box<map::MapError>),
}

// Boxed: the planning, exploration, scenario, hardware, record and robot
// errors are large (120 bytes and more), and `JobError` is returned on every
// path.
impl From<crate::ScenarioError> for JobError {
    fn from(e: crate::ScenarioError) -> Self {
        Self::ScenarioFile(Box::new(e))
    }
}

impl From<hw::HwError> for JobError {
    fn from(e: hw::HwError) -> Self {
        Self::Hw(Box::new(e))
    }
}

impl From<record::RecordError> for JobError {
    fn from(e: record::RecordError) -> Self {
        Self::Record(Box::new(e))
    }
}

impl From<robot::RobotError> for JobError {
    fn from(e: robot::RobotError) -> Self {
        Self::Robot(Box::new(e))
    }
}

impl From<plan::PlanError> for JobError {
    fn from(e: plan::PlanError) -> Self {
        Self::Plan(Box::new(e))
    }
}

impl From<::explore::ExploreError> for JobError {
    fn from(e: ::explore::ExploreError) -> Self {
        Self::Explore(Box::new(e))
    }
}

impl From<blast::BlastError> for JobError {
    fn from(e: blast::BlastError) -> Self {
        Self::Blast(Box::new(e))
    }
}

// A run's bag is a run-folder file.
impl From<record::bag::BagError> for JobError {
    fn from(e: record::bag::BagError) -> Self {
        Self::Record(Box::new(e.into()))
    }
}

impl From<map::MapError> for JobError {
    fn from(e: map::MapError) -> Self {
        Self::Map(Box::new(e))
    }
}

/// An error unless hardware at joints `q` stands at `start`, every joint
/// within `tolerance` radians: a loop starts from the pose its setup checked.
pub fn check_stands_at(q: &[Real], start: &[Real], tolerance: Real) -> Result<(), String> {
    let there =
        q.len() == start.len() && q.iter().zip(start).all(|(a, b)| (a - b).abs() <= tolerance);
    if there {
        Ok(())
    } else {
        let noisier = if tolerance > 0.0 {
            " (a robot whose joint states are noisier than that needs a larger [ros2] tolerance_rad)"
        } else {
            ""
        };
        Err(format!(
            "stands at joints {q:?}, not at the run's start joints {start:?} (within {tolerance} rad): a run starts from the pose its setup checked{noisier}"
        ))
    }
}

fn ns(seconds: Real) -> u64 {
    (seconds.max(0.0) * 1e9).round() as u64
}

/// Hand one event of tapped hardware (`hw::script::Tap` around a
/// `hw::clock::Timed`) to a run's bag, stamped by the robot clock the
/// hardware runs on: the event's interval is the clock's last.
pub fn bag_event(
    bag: &mut record::bag::RunBag,
    clock: &hw::clock::RobotClock,
    event: &hw::script::Event,
) {
    use hw::script::Event;
    let (start, end) = clock.last_interval();
    match event {
        Event::Moved { reached, .. } => bag.moved(start, end, reached),
        Event::Scanned(s) => bag.scanned(
            start,
            end.saturating_sub(start) as Real * 1e-9,
            &s.ranges_m,
            &s.intensities,
        ),
        Event::Read(readings) => {
            let d: Vec<Option<Real>> = readings.iter().map(|r| r.map(|p| p.distance_m)).collect();
            bag.read(start, &d);
        }
        Event::ScannedMoving(s) => {
            // The motion began `start_s` before the scan (the clock's
            // interval is the scan's).
            let began = start.saturating_sub(ns(s.start_s));
            for j in &s.joints {
                bag.passed(began + ns(j.t_s), &j.q);
            }
            bag.scanned_moving(
                start,
                (end.saturating_sub(start) as Real * 1e-9, s.time_increment_s),
                &s.readings.ranges_m,
                &s.readings.intensities,
            );
        }
        Event::MotionEnded(q) => bag.rested(end, q),
        Event::Seeded(_) | Event::MotionStarted(_) | Event::Braked(_) => {}
    }
}
