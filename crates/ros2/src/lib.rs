#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | item | what |
//! |---|---|
//! | [`Ros2Config`] | domain id (`ROS_DOMAIN_ID`) and loopback-only discovery |
//! | [`Ros2Node`] | a ROS 2 node over RustDDS, publishers and subscriptions of `record::bag::msg` types with ROS 2's default QoS |
//! | [`serve_robot`], [`ServeConfig`] | any hardware served as a ROS 2 robot: `/joint_states`, `/scan`, `Range`s, and `JointTrajectory` executed at a joint speed |
//! | [`Ros2Error`] | what can fail |

mod node;
mod serve;

pub use node::{Ros2Config, Ros2Node, TRAJECTORY_TOPIC};
pub use serve::{ServeConfig, ServeStats, serve_robot};

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
    /// The hardware refused or failed.
    #[error(transparent)]
    Hw(#[from] hw::HwError),
}
