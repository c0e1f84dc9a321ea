//! Scenarios: a robot, its sensors, a ground-truth scene and the parameters of
//! every stage, as one TOML file (SPEC §5). Every built-in is printable as such a
//! file (`surveyor scenario show NAME`), which is the documented way to make a
//! new scene: print one, edit it, pass the file.

use crate::range_sensors::RangeSensorsSpec;
use crate::{BUILTIN_NAMES, RobotChoice, ScenarioError, builtin_scenario, mount_scanner};
use geom::{Isometry3, Real};
use map::RegionsConfig;
use robot::Robot;
use scene::{PoseSpec, SamplingConfig, SceneSpec, World};
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
    #[serde(deserialize_with = "geom::exact::vec_of_vec_of_arrays")]
    pub initial_segments: Vec<Vec<[Real; 3]>>,
    /// How results are scored against the ground truth.
    #[serde(default)]
    pub metrics: MetricsConfig,
    /// AXBAM exploration parameters (A Table 6.1 by default): the `[explore]`
    /// table, with `[explore.plan]` (n_Q, ...) and `[explore.prediction]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub explore: Option<explore::ExploreConfig>,
    /// Surface-following parameters of this scene (the `[follow]` table of
    /// `surveyor follow --config`; P ch. 3 defaults when absent). A
    /// `--config` file replaces this table and `[surface]` as a whole.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub follow: Option<follow::FollowConfig>,
    /// Surface-model parameters of this scene (the `[surface]` table of
    /// `surveyor follow --config`; P ch. 2 defaults when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface: Option<surface::SurfaceConfig>,
    /// How `--ros2` talks to the robot: topics, joint names, tolerances
    /// (the `[ros2]` table; ROS 2's usual topics when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ros2: Option<crate::ros2::Ros2Spec>,
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
    /// The robot clock's figures where they differ from the robot's own
    /// (`[robot.timing]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timing: Option<TimingSpec>,
}

/// `[robot.timing]`: the robot clock's figures for this robot. Each one
/// left out is the robot's own: a URDF's `<limit velocity>` per joint, and
/// otherwise the stated conservative values of `robot::timing` (1 rad/s,
/// 2 rad/s²; 0.25 m/s, 1 m/s² for prismatic joints) and a settling
/// allowance of 0.05 s per stop.
///
/// ```toml
/// [robot.timing]
/// velocity = [3.15, 3.15, 3.15, 3.2, 3.2, 3.2]    # rad/s per joint
/// acceleration = [2.0, 2.0, 2.0, 4.0, 4.0, 4.0]   # rad/s² per joint
/// settle_s = 0.05
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct TimingSpec {
    /// Largest speed per joint, rad/s (m/s for prismatic joints).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity: Option<Vec<Real>>,
    /// Largest acceleration per joint, rad/s² (m/s²).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub acceleration: Option<Vec<Real>>,
    /// Seconds the arm takes to settle after each motion.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settle_s: Option<Real>,
}

impl RobotSpec {
    /// The robot clock's figures for `robot` (loaded from this spec) with
    /// a scanner taking `scan_time_s` a scan and range finders read every
    /// `reading_period_s`: the robot's own, overridden by `[robot.timing]`;
    /// an error names the field and what was expected.
    pub fn timing(
        &self,
        robot: &robot::Robot,
        scan_time_s: Real,
        reading_period_s: Real,
    ) -> Result<hw::clock::RobotTiming, String> {
        let mut timing = hw::clock::RobotTiming::of(robot, scan_time_s, reading_period_s);
        if let Some(spec) = &self.timing {
            if let Some(v) = &spec.velocity {
                timing.limits.velocity.clone_from(v);
            }
            if let Some(a) = &spec.acceleration {
                timing.limits.acceleration.clone_from(a);
            }
            if let Some(s) = spec.settle_s {
                timing.settle_s = s;
            }
        }
        timing
            .check(robot.dof())
            .map_err(|e| format!("robot.timing: {e}"))?;
        Ok(timing)
    }
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
    pub fn validate(&self) -> Result<(), ScenarioError> {
        let fail = |message: String| ScenarioError::Scenario {
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
    pub fn from_toml(text: &str, source: &str) -> Result<Self, ScenarioError> {
        let scenario: Self = toml::from_str(text).map_err(|e| ScenarioError::Scenario {
            source_name: source.to_owned(),
            message: e.to_string(),
        })?;
        scenario.validate().map_err(|e| match e {
            ScenarioError::Scenario { message, .. } => ScenarioError::Scenario {
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
    pub fn validate(&self) -> Result<(), ScenarioError> {
        let fail = |message: String| ScenarioError::Scenario {
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
        if let Some(t) = &self.robot.timing {
            let figures = t.velocity.iter().chain(&t.acceleration).flatten();
            if let Some(v) = figures
                .copied()
                .find(|v| !(v.is_finite() && *v > 0.0 && *v <= robot::timing::MAX_LIMIT))
            {
                return Err(fail(format!(
                    "robot.timing: a velocity or acceleration of {v}: expected more than 0 and at most {}",
                    robot::timing::MAX_LIMIT
                )));
            }
            if let Some(s) = t.settle_s
                && !(s.is_finite() && (0.0..=hw::clock::MAX_PERIOD_S).contains(&s))
            {
                return Err(fail(format!(
                    "robot.timing.settle_s = {s}: expected seconds from 0 to {}",
                    hw::clock::MAX_PERIOD_S
                )));
            }
        }
        self.range_sensors.validate().map_err(fail)?;
        if let Some(ros2) = &self.ros2 {
            ros2.validate().map_err(fail)?;
        }
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
        if let Some(f) = &self.follow {
            f.validate().map_err(|e| fail(format!("follow: {e}")))?;
        }
        if let Some(c) = &self.surface {
            c.validate().map_err(|e| fail(format!("surface: {e}")))?;
        }
        self.metrics.validate().map_err(|e| match e {
            ScenarioError::Scenario { message, .. } => fail(message),
            other => other,
        })
    }

    /// The scenario as TOML.
    pub fn to_toml(&self) -> Result<String, ScenarioError> {
        toml::to_string(self).map_err(|e| ScenarioError::Scenario {
            source_name: self.name.clone(),
            message: e.to_string(),
        })
    }

    /// A built-in by name or a scenario file by path.
    pub fn load(name_or_file: &str) -> Result<LoadedScenario, ScenarioError> {
        if let Some(s) = builtin_scenario(name_or_file) {
            s.validate()?;
            return Ok(LoadedScenario {
                scenario: s,
                base_dir: PathBuf::from("."),
            });
        }
        let path = Path::new(name_or_file);
        if !path.exists() {
            return Err(ScenarioError::Scenario {
                source_name: name_or_file.to_owned(),
                message: format!(
                    "no such built-in scenario or file (built-ins: {})",
                    BUILTIN_NAMES.join(", ")
                ),
            });
        }
        let text = std::fs::read_to_string(path).map_err(|e| ScenarioError::Scenario {
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

    /// The scenario's robot as a [`RobotChoice`] (a URDF path resolved
    /// against the scenario's folder).
    pub fn robot_choice(&self) -> Result<RobotChoice, ScenarioError> {
        let spec = &self.scenario.robot;
        RobotChoice::of_spec(
            spec.preset.as_deref(),
            spec.urdf.as_deref(),
            spec.tip.as_deref(),
            &self.base_dir,
        )
    }

    /// Put `choice` in the scenario's `[robot]` table in place of its robot
    /// (a URDF path made absolute, so the scenario still finds it from its
    /// run folder), keeping the base pose and start joints.
    pub fn set_robot(&mut self, choice: &RobotChoice) -> Result<(), ScenarioError> {
        let spec = &mut self.scenario.robot;
        match choice {
            RobotChoice::Builtin(name) => {
                spec.preset = Some(name.clone());
                spec.urdf = None;
                spec.tip = None;
            }
            RobotChoice::Urdf { path, tip } => {
                let path = std::fs::canonicalize(path).map_err(|e| ScenarioError::Scenario {
                    source_name: path.display().to_string(),
                    message: format!("cannot read the URDF file: {e}"),
                })?;
                spec.preset = None;
                spec.urdf = Some(path);
                spec.tip.clone_from(tip);
            }
        }
        Ok(())
    }

    /// Build the ground-truth world.
    pub fn build_world(&self) -> Result<World, ScenarioError> {
        Ok(self.scenario.scene.build(&self.base_dir)?)
    }

    /// Build the robot, with the scanner mounted when the scenario has one and
    /// the scenario's `[range_sensors]` appended to its range finders, and
    /// check the start pose against it.
    pub fn build_robot(&self) -> Result<Robot, ScenarioError> {
        let spec = &self.scenario.robot;
        let mut robot = self.robot_choice()?.build()?;
        if let Some(scanner) = &self.scenario.scanner {
            mount_scanner(&mut robot, scanner.mount.as_ref());
        }
        self.scenario
            .range_sensors
            .apply(&mut robot)
            .map_err(|message| ScenarioError::Scenario {
                source_name: self.scenario.name.clone(),
                message,
            })?;
        robot
            .check_joints(&spec.start_joints)
            .map_err(|e| ScenarioError::Scenario {
                source_name: self.scenario.name.clone(),
                message: format!("robot.start_joints: {e}"),
            })?;
        Ok(robot)
    }

    /// The robot clock's figures for `robot` (as [`Self::build_robot`]
    /// built it): its joints' limits with `[robot.timing]`, the scanner's
    /// `scan_time_s` (the URG-04LX's 0.1 s without a scanner section) and
    /// the range finders' [`hw::clock::DEFAULT_READING_PERIOD_S`].
    pub fn robot_timing(&self, robot: &Robot) -> Result<hw::clock::RobotTiming, ScenarioError> {
        let scan_time_s = self.scenario.scanner.as_ref().map_or_else(
            || ScannerConfig::default().scan_time_s,
            |s| s.config.scan_time_s,
        );
        self.scenario
            .robot
            .timing(robot, scan_time_s, hw::clock::DEFAULT_READING_PERIOD_S)
            .map_err(|message| ScenarioError::Scenario {
                source_name: self.scenario.name.clone(),
                message,
            })
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// `[robot.timing]` overrides the robot's own figures; left out, the
    /// DENSO's are the stated conservative ones and the scanner's scan
    /// time the URG-04LX's. Bad figures are refused naming the field.
    #[test]
    fn robot_timing_overrides_and_refusals() {
        let bridge = Scenario::load("bridge1").unwrap();
        let robot = bridge.build_robot().unwrap();
        let own = bridge.robot_timing(&robot).unwrap();
        assert_eq!(own.limits.velocity, vec![1.0; 6]);
        assert_eq!(own.limits.acceleration, vec![2.0; 6]);
        assert_eq!((own.settle_s, own.scan_time_s), (0.05, 0.1));
        let text = bridge.scenario.to_toml().unwrap().replace(
            "[robot.base_pose]",
            "[robot.timing]\nvelocity = [3.0, 3.0, 3.0, 5.0, 5.0, 6.0]\nsettle_s = 0.02\n\n[robot.base_pose]",
        );
        let loaded = LoadedScenario {
            scenario: Scenario::from_toml(&text, "timed.toml").unwrap(),
            base_dir: bridge.base_dir.clone(),
        };
        let t = loaded.robot_timing(&robot).unwrap();
        assert_eq!(t.limits.velocity, vec![3.0, 3.0, 3.0, 5.0, 5.0, 6.0]);
        assert_eq!((t.limits.acceleration[0], t.settle_s), (2.0, 0.02));
        // A velocity per joint, positive: five of six, a zero, a NaN.
        let short = text
            .replace("6.0]\nsettle_s", "]\nsettle_s")
            .replace(", 5.0]", "]");
        let loaded = LoadedScenario {
            scenario: Scenario::from_toml(&short, "short.toml").unwrap(),
            base_dir: bridge.base_dir.clone(),
        };
        let e = loaded.robot_timing(&robot).unwrap_err().to_string();
        assert!(
            e.contains("robot.timing") && e.contains("one per joint"),
            "{e}"
        );
        for bad in ["velocity = [0.0, 3.0", "velocity = [nan, 3.0"] {
            let e = Scenario::from_toml(&text.replace("velocity = [3.0, 3.0", bad), "bad.toml")
                .unwrap_err()
                .to_string();
            assert!(e.contains("bad.toml") && e.contains("robot.timing"), "{e}");
        }
        let e = Scenario::from_toml(
            &text.replace("settle_s = 0.02", "settle_s = -1"),
            "bad.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("robot.timing.settle_s = -1"), "{e}");
    }

    /// A scenario's `[follow]` and `[surface]` tables are the run's
    /// parameters, each field it leaves out at its default; a scenario
    /// without them gives the defaults; a bad value is refused naming the
    /// table.
    #[test]
    fn follow_and_surface_tables() {
        use crate::job::follow::FollowRunConfig;
        let block1 = Scenario::load("block1").unwrap().scenario;
        assert_eq!(
            FollowRunConfig::of_scenario(&block1),
            FollowRunConfig::default()
        );
        let text = format!(
            "{}\n[follow]\nguard_margin_m = 0.04\n\n[surface]\nlambda = 0.03\n",
            block1.to_toml().unwrap()
        );
        let own = Scenario::from_toml(&text, "own.toml").unwrap();
        let c = FollowRunConfig::of_scenario(&own);
        let d = FollowRunConfig::default();
        assert_eq!(c.follow.guard_margin_m, 0.04);
        assert_eq!(c.surface.lambda, 0.03);
        assert_eq!(c.follow.max_step_m, d.follow.max_step_m);
        assert_eq!(c.surface.mu_deg, d.surface.mu_deg);
        // Printed and read back, the tables stay.
        let again = Scenario::from_toml(&own.to_toml().unwrap(), "again.toml").unwrap();
        assert_eq!(FollowRunConfig::of_scenario(&again), c);
        for (bad, table) in [
            ("guard_margin_m = 0.04", "guard_margin_m = -1.0"),
            ("lambda = 0.03", "lambda = 0.0"),
        ] {
            let e = Scenario::from_toml(&text.replace(bad, table), "bad.toml")
                .unwrap_err()
                .to_string();
            let name = if bad.starts_with("guard") {
                "follow"
            } else {
                "surface"
            };
            assert!(e.contains("bad.toml") && e.contains(name), "{e}");
        }
    }
}
