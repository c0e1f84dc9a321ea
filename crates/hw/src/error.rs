//! The hardware traits' one error type.

use geom::Real;

/// What hardware can refuse or fail at. A failed call leaves the hardware
/// where it was (an arm that refuses a move has not moved).
#[derive(Debug, thiserror::Error)]
pub enum HwError {
    /// The robot model refused the joints (wrong length, not finite,
    /// outside the limits).
    #[error(transparent)]
    Robot(#[from] robot::RobotError),
    /// A sensor configuration or its data are invalid.
    #[error(transparent)]
    Sensor(#[from] sensor::SensorError),
    /// A scan was asked of a robot without a scanner.
    #[error("the robot carries no scanner")]
    NoScanner,
    /// The sweep's tilt joint does not exist.
    #[error("tilt joint {joint} does not exist: the robot has {dof} joints")]
    TiltJoint {
        /// 1-based joint number asked for.
        joint: usize,
        /// Joints the robot has.
        dof: usize,
    },
    /// A setting of the hardware is invalid.
    #[error("{what}: {message}")]
    Setting {
        /// The setting.
        what: String,
        /// What is wrong.
        message: String,
    },
    /// A scripted double was asked for something its script does not hold
    /// (another command than the one recorded, or more of them).
    #[error("script: {message}")]
    Script {
        /// What differs.
        message: String,
    },
    /// A move ended away from its goal (a real arm stopped short, or a
    /// driver timed out).
    #[error(
        "the arm stopped short of its goal: joint {joint} is {error:.4} from it \
         (the tolerance is {tolerance})"
    )]
    NotReached {
        /// The joint farthest from the goal, by name.
        joint: String,
        /// Its difference from the goal (radians or metres).
        error: Real,
        /// The tolerance it had to be within.
        tolerance: Real,
    },
    /// A joint strayed from the trajectory it was sent (an arm too weak or
    /// blocked, a controller that lags): the driver held the arm where it
    /// stood.
    #[error(
        "joint {joint} was {error:.4} off its trajectory {at_s:.3} s into the motion \
         (the path tolerance is {tolerance}): the arm was stopped where it stood"
    )]
    OffPath {
        /// The joint farthest off, by name.
        joint: String,
        /// How far off it was (radians or metres).
        error: Real,
        /// The path tolerance.
        tolerance: Real,
        /// When, seconds from the motion's start.
        at_s: Real,
    },
    /// The device failed (a driver's own error, as text).
    #[error("{device}: {message}")]
    Device {
        /// The device.
        device: String,
        /// What happened.
        message: String,
    },
}
