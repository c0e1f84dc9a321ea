//! Scenarios: a robot, its sensors, a ground-truth scene and the parameters of
//! every stage, as one TOML file (SPEC §5). Every built-in is printable as such a
//! file (`surveyor scenario show NAME`), which is the documented way to make a
//! new scene: print one, edit it, pass the file.

use crate::SimError;
use crate::range_sensors::RangeSensorsSpec;
use geom::{Isometry3, Real};
use map::RegionsConfig;
use robot::{LoadedMesh, Robot, ScannerMount};
use scene::{PoseSpec, SamplingConfig, SceneError, SceneSpec, World, builtin};
use sensor::{ScannerConfig, SweepConfig};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A complete scenario.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Short name.
    pub name: String,
    /// One line saying what it is.
    #[serde(default)]
    pub description: String,
    /// The robot and where it starts.
    pub robot: RobotSpec,
    /// The tilting laser scanner and its sweep (AXBAM scenarios).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scanner: Option<ScannerSpec>,
    /// Single-point range finders added to the robot, and the range noise of
    /// every reading (surface following; see [`crate::range_sensors`]).
    #[serde(default, skip_serializing_if = "RangeSensorsSpec::is_empty")]
    pub range_sensors: RangeSensorsSpec,
    /// Regions of interest A1 ⊂ A2 ⊂ A3 (A§4.2.1), when the method uses them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub regions: Option<RegionsConfig>,
    /// A-priori planar polygons for the surface model (P§4.3), vertices in the
    /// world frame, anticlockwise about the outward normal.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub initial_segments: Vec<Vec<[Real; 3]>>,
    /// How results are scored against the ground truth.
    #[serde(default)]
    pub metrics: MetricsConfig,
    /// AXBAM exploration parameters (A Table 6.1 by default): the `[explore]`
    /// table, with `[explore.plan]` (n_Q, ...) and `[explore.prediction]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub explore: Option<explore::ExploreConfig>,
    /// The ground truth.
    pub scene: SceneSpec,
}

/// Which robot, where, and in which pose it starts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// A built-in robot (`denso-vm6083`, `point3`, `arm4`), or
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preset: Option<String>,
    /// a URDF file (path relative to the scenario file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub urdf: Option<PathBuf>,
    /// For a URDF: the link to use as the tool (default: the chain's leaf).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tip: Option<String>,
    /// Where the robot base stands in the world (`world_from_base`).
    #[serde(default)]
    pub base_pose: PoseSpec,
    /// Start joint values, radians (metres for prismatic joints).
    pub start_joints: Vec<Real>,
}

/// The tilting scanner of an AXBAM scenario.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ScannerSpec {
    /// The scanner model.
    #[serde(default)]
    pub config: ScannerConfig,
    /// The sweep.
    #[serde(default)]
    pub sweep: SweepConfig,
    /// Scanner placement on the robot's tool link (`tool_from_scanner`); the
    /// built-in VM-6083 carries its own, URDF robots need one (default: the tool frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mount: Option<PoseSpec>,
}

/// How results are scored (SPEC §6).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MetricsConfig {
    /// A true-surface sample counts as covered when a measured point lies within
    /// this distance, metres.
    pub covered_within_m: Real,
    /// Ground-truth sampling (density, seed, exposed faces only). Its `region`,
    /// when unset, defaults to the scenario's A2 region.
    pub sampling: SamplingConfig,
}

impl Default for MetricsConfig {
    fn default() -> Self {
        Self {
            covered_within_m: 0.010,
            sampling: SamplingConfig::default(),
        }
    }
}

impl MetricsConfig {
    /// Check the fields: `covered_within_m` a finite distance > 0, and the
    /// sampling settings (see [`SamplingConfig::validate`]). Errors name the
    /// field (`metrics.covered_within_m`, `metrics.sampling.samples_per_m2`).
    pub fn validate(&self) -> Result<(), SimError> {
        let fail = |message: String| SimError::Scenario {
            source_name: "metrics".into(),
            message,
        };
        if !(self.covered_within_m.is_finite() && self.covered_within_m > 0.0) {
            return Err(fail(format!(
                "metrics.covered_within_m: expected a finite distance > 0 (metres), got {}",
                self.covered_within_m
            )));
        }
        self.sampling
            .validate()
            .map_err(|e| fail(format!("metrics.{e}")))
    }
}

/// Names of the built-in scenarios.
pub const BUILTIN_NAMES: [&str; 7] = builtin::NAMES;

fn deg(v: [Real; 6]) -> Vec<Real> {
    v.iter().map(|d| d.to_radians()).collect()
}

/// A built-in scenario by name.
pub fn builtin_scenario(name: &str) -> Option<Scenario> {
    let scene = builtin::scene(name)?;
    let (description, robot, scanner, regions, initial, sampling_region) = match name {
        "bridge1" | "bridge2" | "bridge3" => {
            // Regions centred on the first joint's shoulder height (d1), sized by
            // the VM-6083's reach (~1.1 m) and the 0.5 m grit-blast stream.
            let regions = RegionsConfig::around([0.0, 0.0, 0.475], [1.1, 1.6, 2.1]);
            let description = match name {
                "bridge1" => {
                    "steel bridge channel: two I-beams, timber deck, plate, sheet, scaffold, hose (A§6.3)"
                }
                "bridge2" => "bridge1 plus a timber crossbeam behind the robot (A§6.4)",
                _ => "bridge2 plus a front crossbeam and a hanging timber lattice (A§6.5)",
            };
            (
                description,
                RobotSpec {
                    preset: Some("denso-vm6083".into()),
                    urdf: None,
                    tip: None,
                    base_pose: PoseSpec::default(),
                    start_joints: deg([0.0, -55.0, 165.0, 0.0, -110.0, 0.0]),
                },
                Some(ScannerSpec::default()),
                Some(regions),
                Vec::new(),
                Some(regions.a2.aabb()),
            )
        }
        _ => {
            // Surface following (P§4.3): point robot 0.1 above the top face's
            // centre, the table z = 0 as an initial segment.
            let (top, description) = match name {
                "cube" => (
                    [0.0, 0.0, 1.0],
                    "Pudney's Cube: 1 m cube on a table (P§4.3, Fig. 41)",
                ),
                "block1" => (
                    [-0.3, 0.0, 0.8],
                    "Pudney's Block1: L-shaped block (P Fig. 42)",
                ),
                "block2" => (
                    [0.025, 0.0, 0.6],
                    "Pudney's Block2: block with two chamfered edges (P Fig. 43)",
                ),
                _ => (
                    [0.0, 0.0, 0.8],
                    "Pudney's curved surface: a cylinder (P Fig. 50–51)",
                ),
            };
            let table = vec![
                [-2.0, -2.0, 0.0],
                [2.0, -2.0, 0.0],
                [2.0, 2.0, 0.0],
                [-2.0, 2.0, 0.0],
            ];
            (
                description,
                RobotSpec {
                    preset: Some("point3".into()),
                    urdf: None,
                    tip: None,
                    base_pose: PoseSpec::default(),
                    start_joints: vec![top[0], top[1], top[2] + 0.1],
                },
                None,
                None,
                vec![table],
                None,
            )
        }
    };
    let metrics = MetricsConfig {
        sampling: SamplingConfig {
            region: sampling_region,
            ..SamplingConfig::default()
        },
        ..MetricsConfig::default()
    };
    // The exploration scenes carry Table 6.1's parameters, so `scenario show`
    // prints every one of them.
    let explore = regions.map(|_| explore::ExploreConfig::default());
    Some(Scenario {
        name: name.to_owned(),
        description: description.to_owned(),
        robot,
        range_sensors: RangeSensorsSpec::default(),
        scanner,
        regions,
        initial_segments: initial,
        metrics,
        explore,
        scene,
    })
}

/// A scenario and the folder its relative paths are resolved against.
#[derive(Clone, Debug)]
pub struct LoadedScenario {
    /// The scenario.
    pub scenario: Scenario,
    /// Folder of the file (the working directory for built-ins).
    pub base_dir: PathBuf,
}

impl Scenario {
    /// Parse a scenario from TOML text and [validate](Self::validate) it;
    /// `source` names the file in errors.
    pub fn from_toml(text: &str, source: &str) -> Result<Self, SimError> {
        let scenario: Self = toml::from_str(text).map_err(|e| SimError::Scenario {
            source_name: source.to_owned(),
            message: e.to_string(),
        })?;
        scenario.validate().map_err(|e| match e {
            SimError::Scenario { message, .. } => SimError::Scenario {
                source_name: source.to_owned(),
                message,
            },
            other => other,
        })?;
        Ok(scenario)
    }

    /// Check the numbers a TOML file can get wrong before anything is built or
    /// allocated: poses (finite, within ±[`scene::MAX_COORDINATE_M`]), start
    /// joints, the `[range_sensors]` table, initial segments, the scanner and
    /// its sweep (within the sensor budgets), the regions (nested boxes), the
    /// exploration settings and the metrics settings. Errors name the field by its TOML
    /// path (`robot.base_pose: translation[0]: ...`).
    pub fn validate(&self) -> Result<(), SimError> {
        let fail = |message: String| SimError::Scenario {
            source_name: self.name.clone(),
            message,
        };
        let pose = |p: &PoseSpec, what: &str| p.validate(what).map_err(|e| fail(e.to_string()));
        pose(&self.robot.base_pose, "robot.base_pose")?;
        for (i, j) in self.robot.start_joints.iter().enumerate() {
            if !j.is_finite() {
                return Err(fail(format!(
                    "robot.start_joints[{i}]: expected a finite joint value, got {j}"
                )));
            }
        }
        self.range_sensors.validate().map_err(fail)?;
        if let Some(scanner) = &self.scanner {
            if let Some(mount) = &scanner.mount {
                pose(mount, "scanner.mount")?;
            }
            scanner
                .config
                .validate()
                .map_err(|e| fail(format!("scanner.config: {e}")))?;
            scanner
                .sweep
                .validate_with(&scanner.config)
                .map_err(|e| fail(format!("scanner.sweep: {e}")))?;
        }
        for (s, verts) in self.initial_segments.iter().enumerate() {
            for (v, p) in verts.iter().enumerate() {
                if !p
                    .iter()
                    .all(|c| c.is_finite() && c.abs() <= scene::MAX_COORDINATE_M)
                {
                    return Err(fail(format!(
                        "initial_segments[{s}][{v}]: expected finite coordinates within ±{:e} m, got {p:?}",
                        scene::MAX_COORDINATE_M
                    )));
                }
            }
        }
        for o in &self.scene.objects {
            if let Some(p) = &o.pose {
                pose(p, &format!("scene.objects `{}` pose", o.name))?;
            }
        }
        if let Some(p) = self
            .scene
            .point_cloud
            .as_ref()
            .and_then(|c| c.pose.as_ref())
        {
            pose(p, "scene.point_cloud.pose")?;
        }
        if let Some(r) = &self.regions {
            r.validate().map_err(|e| fail(e.to_string()))?;
        }
        if let Some(e) = &self.explore {
            e.validate().map_err(|e| fail(e.to_string()))?;
        }
        self.metrics.validate().map_err(|e| match e {
            SimError::Scenario { message, .. } => fail(message),
            other => other,
        })
    }

    /// The scenario as TOML.
    pub fn to_toml(&self) -> Result<String, SimError> {
        toml::to_string(self).map_err(|e| SimError::Scenario {
            source_name: self.name.clone(),
            message: e.to_string(),
        })
    }

    /// A built-in by name or a scenario file by path.
    pub fn load(name_or_file: &str) -> Result<LoadedScenario, SimError> {
        if let Some(s) = builtin_scenario(name_or_file) {
            s.validate()?;
            return Ok(LoadedScenario {
                scenario: s,
                base_dir: PathBuf::from("."),
            });
        }
        let path = Path::new(name_or_file);
        if !path.exists() {
            return Err(SimError::Scenario {
                source_name: name_or_file.to_owned(),
                message: format!(
                    "no such built-in scenario or file (built-ins: {})",
                    BUILTIN_NAMES.join(", ")
                ),
            });
        }
        let text = std::fs::read_to_string(path).map_err(|e| SimError::Scenario {
            source_name: path.display().to_string(),
            message: e.to_string(),
        })?;
        let scenario = Self::from_toml(&text, &path.display().to_string())?;
        Ok(LoadedScenario {
            scenario,
            base_dir: path
                .parent()
                .map_or_else(|| PathBuf::from("."), Path::to_path_buf),
        })
    }

    /// `world_from_base`.
    pub fn world_from_base(&self) -> Isometry3 {
        self.robot.base_pose.isometry()
    }
}

impl LoadedScenario {
    /// The scenario with its relative file paths (URDF, meshes, point
    /// cloud) resolved against its folder: what a run folder keeps as
    /// `scenario.toml`, readable from anywhere.
    pub fn standalone(&self) -> Scenario {
        let mut s = self.scenario.clone();
        if let Some(urdf) = &mut s.robot.urdf {
            let joined = self.base_dir.join(&*urdf);
            *urdf = std::path::absolute(&joined).unwrap_or(joined);
        }
        s.scene = s.scene.rebased(&self.base_dir);
        s
    }

    /// Build the ground-truth world.
    pub fn build_world(&self) -> Result<World, SimError> {
        Ok(self.scenario.scene.build(&self.base_dir)?)
    }

    /// Build the robot, with the scanner mounted when the scenario has one and
    /// the scenario's `[range_sensors]` appended to its range finders, and
    /// check the start pose against it.
    pub fn build_robot(&self) -> Result<Robot, SimError> {
        let spec = &self.scenario.robot;
        let mut robot = build_robot(
            spec.preset.as_deref(),
            spec.urdf
                .as_deref()
                .map(|p| self.base_dir.join(p))
                .as_deref(),
            spec.tip.as_deref(),
        )?;
        if let Some(scanner) = &self.scenario.scanner {
            mount_scanner(&mut robot, scanner.mount.as_ref());
        }
        self.scenario
            .range_sensors
            .apply(&mut robot)
            .map_err(|message| SimError::Scenario {
                source_name: self.scenario.name.clone(),
                message,
            })?;
        robot
            .check_joints(&spec.start_joints)
            .map_err(|e| SimError::Scenario {
                source_name: self.scenario.name.clone(),
                message: format!("robot.start_joints: {e}"),
            })?;
        Ok(robot)
    }
}

impl LoadedScenario {
    /// A simulated rig for the scenario: the robot of [`build_robot`](Self::build_robot)
    /// (with the `[range_sensors]` mounts) at its start joints, in the world of
    /// [`build_world`](Self::build_world), with the scenario's range noise σ;
    /// `seed` drives all sensor noise. The scanner is not simulated (surface
    /// following uses range finders only).
    pub fn build_rig(&self, seed: u64) -> Result<crate::SimRig, SimError> {
        let robot = self.build_robot()?;
        let world = std::sync::Arc::new(self.build_world()?);
        let mut rig = crate::SimRig::new(
            robot,
            world,
            self.scenario.world_from_base(),
            &self.scenario.robot.start_joints,
            None,
            seed,
        )?;
        rig.set_range_noise_sigma_m(self.scenario.range_sensors.noise_sigma_m)?;
        Ok(rig)
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

/// A robot from a preset name or a URDF file (exactly one of them); URDF
/// collision meshes are read with [`scene_mesh_loader`].
pub fn build_robot(
    preset: Option<&str>,
    urdf: Option<&Path>,
    tip: Option<&str>,
) -> Result<Robot, SimError> {
    match (preset, urdf) {
        (Some(name), None) => Ok(robot::builtin(name)?),
        (None, Some(path)) => Ok(Robot::from_urdf_file_with(path, tip, &scene_mesh_loader)?),
        _ => Err(SimError::Scenario {
            source_name: "robot".into(),
            message: "give exactly one of `preset` and `urdf`".into(),
        }),
    }
}

/// A robot named on a command line: a built-in name (`denso-vm6083`, `point3`,
/// `arm4`) or a URDF file (a path ending in `.urdf`, any case), whose chain
/// ends at `tip` when given (the chain's leaf otherwise). `tip` with a built-in
/// robot is an error.
pub fn robot_by_name_or_urdf(name_or_path: &str, tip: Option<&str>) -> Result<Robot, SimError> {
    if name_or_path.to_ascii_lowercase().ends_with(".urdf") {
        build_robot(None, Some(Path::new(name_or_path)), tip)
    } else if let Some(tip) = tip {
        Err(SimError::Scenario {
            source_name: "robot".into(),
            message: format!(
                "a tip link (`{tip}`) applies to URDF robots only; `{name_or_path}` is a built-in robot"
            ),
        })
    } else if Path::new(name_or_path).exists() && robot::builtin(name_or_path).is_err() {
        Err(SimError::Scenario {
            source_name: "robot".into(),
            message: format!(
                "`{name_or_path}` is a file but not a URDF (a robot file's name ends in .urdf), \
                 nor a built-in robot ({})",
                robot::builtin_names().join(", ")
            ),
        })
    } else {
        build_robot(Some(name_or_path), None, None)
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
