//! Which robot: a built-in by name or a URDF file ([`RobotChoice`]), the one
//! place every command and scenario file makes that choice, and the scanner
//! mount a scenario puts on it.

use crate::ScenarioError;
use robot::{LoadedMesh, Robot, ScannerMount};
use scene::{PoseSpec, SceneError};
use std::path::{Path, PathBuf};

/// A robot as a user names it: a built-in (`denso-vm6083`, `point3`,
/// `arm4`) or a URDF file, whose chain ends at `tip` when given (the chain's
/// leaf otherwise).
///
/// ```
/// use scenario::RobotChoice;
///
/// let arm = RobotChoice::parse("arm4", None)?;
/// assert_eq!(arm, RobotChoice::Builtin("arm4".into()));
/// assert_eq!(arm.build()?.dof(), 6);
/// // A name ending in .urdf (any case) is a file.
/// assert!(matches!(RobotChoice::parse("my/ARM.URDF", Some("tool0"))?, RobotChoice::Urdf { .. }));
/// // A tip belongs to URDF robots only.
/// assert!(RobotChoice::parse("arm4", Some("link3")).is_err());
/// # Ok::<(), scenario::ScenarioError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RobotChoice {
    /// A built-in robot by name ([`robot::builtin_names`]).
    Builtin(String),
    /// A URDF file.
    Urdf {
        /// The file.
        path: PathBuf,
        /// The link treated as the tool (default: the chain's leaf).
        tip: Option<String>,
    },
}

/// `true` for a robot argument naming a URDF file (ends in `.urdf`, any case).
pub fn is_urdf_name(name: &str) -> bool {
    name.to_ascii_lowercase().ends_with(".urdf")
}

impl RobotChoice {
    /// The robot a command line names: a path ending in `.urdf` (any case) is
    /// a URDF file, anything else a built-in name. Refused: a tip with a
    /// built-in, and an existing file that is not a URDF nor a built-in's
    /// name. An unknown built-in name is refused by [`build`](Self::build),
    /// which lists the built-ins.
    pub fn parse(name_or_path: &str, tip: Option<&str>) -> Result<Self, ScenarioError> {
        if is_urdf_name(name_or_path) {
            return Ok(Self::Urdf {
                path: PathBuf::from(name_or_path),
                tip: tip.map(str::to_owned),
            });
        }
        if let Some(tip) = tip {
            return Err(robot_error(format!(
                "a tip link (`{tip}`) applies to URDF robots only; `{name_or_path}` is a built-in robot"
            )));
        }
        if Path::new(name_or_path).exists() && robot::builtin(name_or_path).is_err() {
            return Err(robot_error(format!(
                "`{name_or_path}` is a file but not a URDF (a robot file's name ends in .urdf), \
                 nor a built-in robot ({})",
                robot::builtin_names().join(", ")
            )));
        }
        Ok(Self::Builtin(name_or_path.to_owned()))
    }

    /// The choice of a scenario's `[robot]` table: exactly one of `preset`
    /// and `urdf` (a relative URDF path resolved against `base_dir`).
    pub fn of_spec(
        preset: Option<&str>,
        urdf: Option<&Path>,
        tip: Option<&str>,
        base_dir: &Path,
    ) -> Result<Self, ScenarioError> {
        match (preset, urdf) {
            (Some(name), None) => Ok(Self::Builtin(name.to_owned())),
            (None, Some(path)) => Ok(Self::Urdf {
                path: base_dir.join(path),
                tip: tip.map(str::to_owned),
            }),
            _ => Err(robot_error(
                "give exactly one of `preset` and `urdf`".to_owned(),
            )),
        }
    }

    /// The built-in's name, or `None` for a URDF.
    pub fn builtin_name(&self) -> Option<&str> {
        match self {
            Self::Builtin(name) => Some(name),
            Self::Urdf { .. } => None,
        }
    }

    /// A short name for cache files and messages: the built-in's name, or
    /// `urdf-<file stem>`.
    pub fn short_name(&self) -> String {
        match self {
            Self::Builtin(name) => name.clone(),
            Self::Urdf { path, .. } => format!(
                "urdf-{}",
                path.file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default()
            ),
        }
    }

    /// Build the robot; URDF collision meshes are read with
    /// [`scene_mesh_loader`].
    pub fn build(&self) -> Result<Robot, ScenarioError> {
        match self {
            Self::Builtin(name) => Ok(robot::builtin(name)?),
            Self::Urdf { path, tip } => Ok(Robot::from_urdf_file_with(
                path,
                tip.as_deref(),
                &scene_mesh_loader,
            )?),
        }
    }
}

fn robot_error(message: String) -> ScenarioError {
    ScenarioError::Scenario {
        source_name: "robot".into(),
        message,
    }
}

/// Reads URDF collision meshes with `scene`'s importer; formats it does not read
/// (COLLADA `.dae`, ...) are skipped with a warning on the robot.
pub fn scene_mesh_loader(path: &Path) -> Result<LoadedMesh, String> {
    match scene::io::load_mesh(path, 1.0) {
        Ok(mesh) => Ok(LoadedMesh::Mesh(mesh)),
        Err(SceneError::Unsupported { expected, .. }) => Ok(LoadedMesh::Skipped(format!(
            "not a mesh format surveyor reads ({expected})"
        ))),
        Err(e) => Err(e.to_string()),
    }
}

/// Give the robot a scanner: `tool_from_scanner` when given, else keep a
/// built-in mount, else the tool frame itself.
pub fn mount_scanner(robot: &mut Robot, tool_from_scanner: Option<&PoseSpec>) {
    let (tool_link, link_from_tool) = robot.tool;
    match (tool_from_scanner, &robot.scanner) {
        (Some(pose), _) => {
            robot.scanner = Some(ScannerMount {
                link: tool_link,
                link_from_scanner: link_from_tool * pose.isometry(),
            });
        }
        (None, Some(_)) => {}
        (None, None) => {
            robot.scanner = Some(ScannerMount {
                link: tool_link,
                link_from_scanner: link_from_tool,
            });
        }
    }
}
