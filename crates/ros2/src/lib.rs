#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | item | what |
//! |---|---|
//! | [`Ros2Config`] | domain id (`ROS_DOMAIN_ID`) and loopback-only discovery |
//! | [`Ros2Node`] | a ROS 2 node over RustDDS, publishers and subscriptions of `record::bag::msg` types with ROS 2's default QoS |
//! | [`serve_robot`], [`ServeConfig`] | any hardware served as a ROS 2 robot: `/joint_states`, `/scan`, `Range`s, and `JointTrajectory` executed (one point at a joint speed, several on their times), its time on `/clock` |
//! | [`Ros2Hardware`], [`DriverConfig`] | the `hw` traits over a ROS 2 robot: trajectories out, joint states, scans and ranges in (lockstep with `sim-robot`, or the next ones a real robot publishes) |
//! | [`LiveView`] | what a run builds, published as it goes: `/tf`, sweeps, viewpoint, disc and surface-model markers |
//! | [`Ros2Error`] | what can fail |

mod driver;
mod live;
mod node;
mod serve;

pub use driver::{DriverConfig, Ros2Hardware};
pub use live::{LiveView, wall_clock_ns};
pub use node::{Ros2Config, Ros2Node};
pub use serve::{
    CLOCK_PERIOD_S, CLOCK_TOPIC, EXACT_RANGES_TOPIC, MAX_RATE, SENSE_TOPIC, ServeConfig,
    ServeStats, serve_robot,
};

/// What can fail talking ROS 2.
#[derive(Debug, thiserror::Error)]
pub enum Ros2Error {
    /// `ROS_DOMAIN_ID` is not a domain id.
    #[error("ROS_DOMAIN_ID={value}: expected a whole number from 0 to 232")]
    DomainId {
        /// What it held.
        value: String,
    },
    /// A DDS participant, node, topic, publisher or subscription could not be made.
    #[error("creating the ROS 2 {what}: {message}")]
    Create {
        /// Which.
        what: String,
        /// Why.
        message: String,
    },
    /// A message could not be sent or received.
    #[error("{topic}: {message}")]
    Transfer {
        /// The topic.
        topic: String,
        /// Why.
        message: String,
    },
    /// A setting is out of its range.
    #[error("{what}: {message}")]
    Config {
        /// Which setting.
        what: String,
        /// What is wrong.
        message: String,
    },
    /// The hardware refused or failed.
    #[error(transparent)]
    Hw(#[from] hw::HwError),
}

/// The joints of `robot` by their ROS names under `spec` (a scenario's
/// `[ros2]` table), the table checked first.
fn ros_joint_names(
    spec: &scenario::ros2::Ros2Spec,
    robot: &robot::Robot,
) -> Result<Vec<String>, Ros2Error> {
    let bad = |message: String| Ros2Error::Config {
        what: "[ros2]".into(),
        message,
    };
    spec.validate().map_err(bad)?;
    spec.ros_joint_names(&robot.joint_names()).map_err(bad)
}
