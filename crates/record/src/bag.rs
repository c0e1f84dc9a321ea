//! `run.mcap`: the run's ROS 2 bag, and robots' bags read back, without a
//! ROS installation. Every run writes one: the joint states along every
//! executed motion, the robot's frames on `/tf`, every laser scan as a
//! `sensor_msgs/LaserScan` (with intensities), every reading of the range
//! finders as a `sensor_msgs/Range`, each viewpoint's sweep as a
//! `sensor_msgs/PointCloud2`, and marker arrays of the viewpoints, the discs
//! and the surface model. Messages are CDR-encoded with their `ros2msg`
//! definitions, the layout `ros2 bag record -s mcap` writes; the Python
//! packages `mcap-ros2-support` (Foxglove's) and `rosbags` read it
//! (`tests/python` checks both; no ROS installation was at hand to play it
//! with `ros2 bag play`).
//!
//! | item | what |
//! |---|---|
//! | [`msg`] | the ROS 2 message types (serde, in the field order of ROS 2 Humble's `.msg` files) and their `ros2msg` definitions |
//! | [`BagWriter`], [`read_bag`], [`BagMessage`] | MCAP files of CDR messages, written and read |
//! | [`RunBag`] | a run's bag written as its hardware acts (fed from `hw::script::Tap`), stamped on the robot clock |
//! | [`sweeps_from_bag`] | a robot's bag as sweeps: laser scans placed at the interpolated joint states (`surveyor map --bag`) |
//! | [`sets_from_bag`] | a robot's bag as Pudney's sensor sets: range readings placed by its frames (`surveyor model --bag`) |
//! | [`markers`] | marker arrays of viewpoints, discs and the surface model |
//! | [`topics`] | the topic names a run's bag uses |
//!
//! **Time.** A [`RunBag`]'s stamps are the robot clock's
//! (`hw::clock::RobotClock`): a motion lasts its profile within the joints'
//! velocity and acceleration limits, a scan the scanner's `scan_time` (0.1 s
//! for the Hokuyo of A§5.1). A simulated run's bag is therefore the same for
//! the same seed; the clock starts at 0.
//!
//! **Frames.** Everything is placed in [`ROOT_FRAME`] (`map`, the scenario's
//! world frame); `/tf_static` places the robot's base link there, the
//! [`SCANNER_FRAME`] on the scanner's link and each range finder's frame
//! ([`range_frame`], sensing along its x axis) on its link. The scanner
//! frame follows ROS's laser convention (rays in its x–y plane, bearing 0
//! along x); ours (A eq. 3.10, rays `(0, −sin θ, cos θ)`) is
//! [`scanner_from_laser`] away from it.

mod file;
mod input;
pub mod markers;
mod mcap_read;
pub mod msg;
mod run;

pub use file::{
    BadMessages, BagContents, BagMessage, BagWriter, MAX_BAG_BYTES, Skipped, decode, encode,
    read_bag, read_bag_with,
};
pub use input::{
    BagSweeps, JOINT_LIMIT_SLACK, MAX_SCANS_PER_SWEEP, MAX_UNLIMITED_JOINT, RangeSets, SWEEP_GAP_S,
    ScanTopics, sets_from_bag, sweeps_from_bag,
};
pub use run::{
    BagConfig, ROOT_FRAME, RunBag, SCANNER_FRAME, joint_state, laser_scan, link_frames,
    point_cloud, range, range_frame, scan_rays, scanner_from_laser, static_frames,
};

use std::path::PathBuf;

/// The topics of a run's bag.
pub mod topics {
    /// `sensor_msgs/JointState` where every motion ends (and where it began,
    /// when sensing took time since the last state).
    pub const JOINT_STATES: &str = "/joint_states";
    /// `tf2_msgs/TFMessage`: every link frame with each joint state.
    pub const TF: &str = "/tf";
    /// `tf2_msgs/TFMessage`: the base in the world, the scanner and each
    /// range finder on its link.
    pub const TF_STATIC: &str = "/tf_static";
    /// `sensor_msgs/LaserScan`: every scan.
    pub const SCAN: &str = "/scan";
    /// `sensor_msgs/PointCloud2`: each viewpoint's sweep, world frame.
    pub const SWEEP: &str = "/surveyor/sweep";
    /// `visualization_msgs/MarkerArray`: the viewpoints.
    pub const VIEWPOINTS: &str = "/surveyor/viewpoints";
    /// `visualization_msgs/MarkerArray`: the discs, by material.
    pub const DISCS: &str = "/surveyor/discs";
    /// `visualization_msgs/MarkerArray`: the surface model.
    pub const SURFACE_MODEL: &str = "/surveyor/surface_model";

    /// `sensor_msgs/Range` of range finder `k`.
    pub fn range_finder(k: usize) -> String {
        format!("/range/finder_{k}")
    }
}

/// What writing or reading a bag can fail at.
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    /// The MCAP writer failed.
    #[error("writing the bag: {0}")]
    Mcap(#[from] mcap::McapError),
    /// A message could not be encoded.
    #[error("encoding a {type_name}: {message}")]
    Encode {
        /// The message type.
        type_name: &'static str,
        /// Why.
        message: String,
    },
    /// A message could not be decoded.
    #[error("decoding a {type_name}: {message}")]
    Decode {
        /// The message type.
        type_name: &'static str,
        /// Why.
        message: String,
    },
    /// A topic was given a second type.
    #[error("topic {topic} carries {has}, not {given}")]
    TopicType {
        /// The topic.
        topic: String,
        /// Its type.
        has: &'static str,
        /// The type written.
        given: &'static str,
    },
    /// The file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is larger than [`MAX_BAG_BYTES`].
    #[error("{}: {bytes} bytes, more than the {} a bag may have", path.display(), MAX_BAG_BYTES)]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size.
        bytes: u64,
    },
    /// A scan could not be made into a sweep.
    #[error(transparent)]
    Sensor(#[from] sensor::SensorError),
    /// The robot refused joint values.
    #[error(transparent)]
    Robot(#[from] robot::RobotError),
    /// A bag's configuration is out of range.
    #[error("bag configuration: {0}")]
    Config(String),
    /// A message of the bag is bad (does not decode, or holds values no
    /// sensor gives).
    #[error("{}: {at}: {message} (--skip-bad-messages skips such messages and counts them)", path.display())]
    Message {
        /// The bag.
        path: PathBuf,
        /// The message: topic, index and log time ([`BagMessage::name`]).
        at: String,
        /// What is wrong.
        message: String,
    },
    /// The file is not a readable MCAP bag of ROS 2 messages.
    #[error("{}: {message}", path.display())]
    Bag {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}
