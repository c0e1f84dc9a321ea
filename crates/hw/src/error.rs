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
    #[error("the arm stopped {error:.4} from its goal (joint-space, largest joint)")]
    NotReached {
        /// Largest joint difference from the goal.
        error: Real,
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
