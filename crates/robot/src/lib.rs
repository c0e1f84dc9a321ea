#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`model`] | [`Robot`], [`Link`], [`Joint`], [`JointKind`], [`JointLimits`], [`CollisionShape`], [`RangeFinderMount`], [`ScannerMount`], [`PosedShape`]; [`Robot::fk_into`], [`Robot::jacobian_into`], [`Robot::min_algebraic_distance`] |
//! | [`posture`] | [`Posture`]: joints and link frames kept in step |
//! | [`dh`] | [`DhRow`], [`Robot::from_dh`] (standard DH, Corke convention; Paul Table C.1) |
//! | [`urdf`] | [`Robot::from_urdf_file`], [`Robot::from_urdf_str`] |
//! | [`timing`] | [`timing::MotionLimits`], [`timing::Profile`]: how long a motion takes within the joints' velocity and acceleration limits (the robot clock) |
//! | [`moving`] | [`moving::JointSample`], [`moving::beam_poses`]: where each beam of a scan taken while the arm moved was measured from |
//! | [`mod@builtin`] | [`builtin()`], [`builtin_names`]: `denso-vm6083`, `point3`, `arm4` |
//! | [`linalg`] | [`pseudo_inverse`], [`damped_pseudo_inverse`], [`null_space_projector`] (Pudney eq. 3, P§3.3) |
//! | [`bounds`] | [`bounds::enclosing_capsule`], [`bounds::enclosing_ellipsoid`] (Khachiyan MVEE; A§3.2.1.4) |
//! | [`mesh`] | [`MeshLoader`] (how URDF mesh files are read), URDF primitive meshes |
//! | [`error`] | [`RobotError`] |
//!
//! Frames are named `a_from_b` (SPEC §2): [`Robot::forward_kinematics`] returns
//! `base_from_link` for every link, so `p_base = base_from_link[i] * p_link`.

pub mod bounds;
pub mod builtin;
pub mod dh;
pub mod error;
pub mod linalg;
pub mod mesh;
pub mod model;
pub mod moving;
pub mod posture;
pub mod reach;
pub mod timing;
pub mod urdf;

pub use builtin::{builtin, builtin_names};
pub use dh::DhRow;
pub use error::RobotError;
pub use linalg::{damped_pseudo_inverse, null_space_projector, pseudo_inverse};
pub use mesh::{LoadedMesh, MeshLoader, NoMeshLoader};
pub use model::{
    CollisionShape, Inertial, Joint, JointKind, JointLimits, Link, LinkId, PosedShape,
    RangeFinderMount, Robot, ScannerMount,
};
pub use posture::Posture;
pub use reach::ReachBound;
