#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`poses`] | [`BlastTool`] (the nozzle and its limits), [`BlastPoses`]: a pose that blasts a disc (App. A.1, eq. A.1–A.5), [`BlastMeasure`] |
//! | [`sequence`] | the order of a segment's targets: [`sequence::genetic`] (App. A.2), [`sequence::nearest_neighbour`], [`sequence::two_opt`] |
//! | [`plans`] | [`BlastInputs`] (discs, segments, start joints, grid), [`plan_blast`]: the plan of every disc in A2, [`discs_with_pose`] on any grid |

pub mod plans;
pub mod poses;
pub mod sequence;

pub use plans::{
    BLAST_GIVE_UP_SCALES, BLAST_STARTS, BlastConfig, BlastInputs, BlastInputsFile, BlastPlan,
    discs_with_pose, plan_blast,
};
pub use poses::{BlastMeasure, BlastPoses, BlastTool};

/// What can go wrong planning blasting.
#[derive(Debug, thiserror::Error)]
pub enum BlastError {
    /// The pose selection or its settings (the tool, LM) refused.
    #[error(transparent)]
    Plan(#[from] plan::PlanError),
    /// The map refused a value.
    #[error(transparent)]
    Map(#[from] map::MapError),
    /// Kinematics failed.
    #[error(transparent)]
    Robot(#[from] robot::RobotError),
    /// A stored file was malformed.
    #[error(transparent)]
    Record(#[from] record::RecordError),
    /// Inputs that do not agree (a segment naming a missing disc, ...).
    #[error("{what}: {message}")]
    Invalid {
        /// What.
        what: String,
        /// What is wrong.
        message: String,
    },
    /// The robot has no nozzle mount.
    #[error("the robot carries no nozzle")]
    NoNozzle,
}
