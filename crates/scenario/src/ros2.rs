//! The `[ros2]` table: how `surveyor explore --ros2`, `surveyor follow
//! --ros2` and `surveyor sim-robot --ros2` talk to a ROS 2 robot — its
//! topics, the ROS names of its joints, and when a motion counts as done.
//!
//! ```toml
//! [ros2]
//! joint_states_topic = "/joint_states"
//! scan_topic = "/scan"
//! range_topic_prefix = "/range/finder_"   # + the finder's index
//! trajectory_topic = "/joint_trajectory_controller/joint_trajectory"
//! joint_names = []        # the robot's own names, in its joint order
//! tolerance_rad = 0.001   # a motion is done when every joint is this close
//! path_tolerance_rad = 0.05  # a joint farther off its trajectory stops the run
//! timeout_s = 10.0        # past a motion's planned time, or a sensing wait
//! joint_speed = 1.0       # rad/s a trajectory's time is planned at
//! ```

use geom::Real;
use serde::{Deserialize, Serialize};

/// Longest wait a `[ros2]` table may set, seconds (an hour).
pub const MAX_TIMEOUT_S: Real = 3600.0;

/// Largest joint-goal tolerance a `[ros2]` table may set, radians: a
/// looser one would let the loop plan from a pose the arm is not at.
pub const MAX_TOLERANCE_RAD: Real = 0.05;

/// Largest path tolerance a `[ros2]` table may set, radians.
pub const MAX_PATH_TOLERANCE_RAD: Real = 0.5;

/// Fastest planned joint speed, rad/s.
pub const MAX_JOINT_SPEED: Real = 10.0;

/// The `[ros2]` table (every field has a default: ROS 2's usual topics).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Ros2Spec {
    /// `sensor_msgs/JointState` of the arm.
    pub joint_states_topic: String,
    /// `sensor_msgs/LaserScan` of the scanner.
    pub scan_topic: String,
    /// `sensor_msgs/Range` of range finder `k`: this prefix and `k`.
    pub range_topic_prefix: String,
    /// Where `trajectory_msgs/JointTrajectory` goals go (a `ros2_control`
    /// joint trajectory controller).
    pub trajectory_topic: String,
    /// The robot's joints by their ROS names, in the robot model's joint
    /// order (empty: the model's own names).
    pub joint_names: Vec<String>,
    /// A motion is done when every joint is this close to its goal, radians.
    pub tolerance_rad: Real,
    /// A joint reported farther than this from where its trajectory has it
    /// (while it runs, and after it while the arm settles) stops the run:
    /// the arm is held where it is and the loop ends with an error naming
    /// the joint (ros2_control's path tolerance), radians. At least
    /// `tolerance_rad`.
    pub path_tolerance_rad: Real,
    /// How long past a motion's planned time (or for a scan or reading) to
    /// wait before stopping with an error, seconds.
    pub timeout_s: Real,
    /// The joint speed a trajectory's time is planned at, rad/s.
    pub joint_speed: Real,
}

impl Default for Ros2Spec {
    fn default() -> Self {
        Self {
            joint_states_topic: "/joint_states".into(),
            scan_topic: "/scan".into(),
            range_topic_prefix: "/range/finder_".into(),
            trajectory_topic: "/joint_trajectory_controller/joint_trajectory".into(),
            joint_names: Vec::new(),
            tolerance_rad: 1e-3,
            path_tolerance_rad: 0.05,
            timeout_s: 10.0,
            joint_speed: 1.0,
        }
    }
}

impl Ros2Spec {
    /// The topic of range finder `k`.
    pub fn range_topic(&self, k: usize) -> String {
        format!("{}{k}", self.range_topic_prefix)
    }

    /// The ROS names of a robot's joints whose model names are `model`:
    /// `joint_names` when given (checked against the count), else `model`.
    pub fn ros_joint_names(&self, model: &[&str]) -> Result<Vec<String>, String> {
        if self.joint_names.is_empty() {
            return Ok(model.iter().map(|&s| s.to_owned()).collect());
        }
        if self.joint_names.len() != model.len() {
            return Err(format!(
                "ros2.joint_names: {} names for a robot of {} joints ({model:?})",
                self.joint_names.len(),
                model.len()
            ));
        }
        Ok(self.joint_names.clone())
    }

    /// Check every field; errors name it by its TOML path.
    pub fn validate(&self) -> Result<(), String> {
        for (field, topic) in [
            ("joint_states_topic", &self.joint_states_topic),
            ("scan_topic", &self.scan_topic),
            ("range_topic_prefix", &self.range_topic_prefix),
            ("trajectory_topic", &self.trajectory_topic),
        ] {
            let ok = topic.len() > 1
                && topic.len() <= 200
                && topic.starts_with('/')
                && !topic.ends_with('/')
                && !topic.contains("//")
                && topic
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '/')
                && !topic
                    .split('/')
                    .any(|part| part.starts_with(|c: char| c.is_ascii_digit()));
            if !ok {
                return Err(format!(
                    "ros2.{field}: expected an absolute ROS 2 topic name (`/` and words of letters, digits and `_`, none starting with a digit, at most 200 characters), got {topic:?}"
                ));
            }
        }
        for (i, n) in self.joint_names.iter().enumerate() {
            if n.is_empty() || n.len() > 200 || self.joint_names[..i].contains(n) {
                return Err(format!(
                    "ros2.joint_names[{i}]: expected a joint name of 1 to 200 characters, given once, got {n:?}"
                ));
            }
        }
        let within = |field: &str, v: Real, max: Real, unit: &str| {
            if v.is_finite() && v > 0.0 && v <= max {
                Ok(())
            } else {
                Err(format!(
                    "ros2.{field}: expected more than 0 and at most {max} {unit}, got {v}"
                ))
            }
        };
        within(
            "tolerance_rad",
            self.tolerance_rad,
            MAX_TOLERANCE_RAD,
            "radians",
        )?;
        within(
            "path_tolerance_rad",
            self.path_tolerance_rad,
            MAX_PATH_TOLERANCE_RAD,
            "radians",
        )?;
        if self.path_tolerance_rad < self.tolerance_rad {
            return Err(format!(
                "ros2.path_tolerance_rad: expected at least tolerance_rad ({}), got {}",
                self.tolerance_rad, self.path_tolerance_rad
            ));
        }
        within("timeout_s", self.timeout_s, MAX_TIMEOUT_S, "seconds")?;
        within("joint_speed", self.joint_speed, MAX_JOINT_SPEED, "rad/s")?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::Ros2Spec;

    #[test]
    fn the_defaults_are_ros_2_s_usual_topics_and_valid() {
        let s = Ros2Spec::default();
        s.validate().unwrap();
        assert_eq!(s.range_topic(3), "/range/finder_3");
        assert_eq!(s.ros_joint_names(&["a", "b"]).unwrap(), ["a", "b"]);
    }

    #[test]
    fn bad_fields_are_named() {
        let bad = |f: &dyn Fn(&mut Ros2Spec), field: &str| {
            let mut s = Ros2Spec::default();
            f(&mut s);
            let e = s.validate().unwrap_err();
            assert!(e.starts_with(&format!("ros2.{field}:")), "{e}");
        };
        bad(&|s| s.scan_topic = "scan".into(), "scan_topic");
        bad(&|s| s.scan_topic = "/scan/".into(), "scan_topic");
        bad(
            &|s| s.joint_states_topic = "/a b".into(),
            "joint_states_topic",
        );
        bad(
            &|s| s.trajectory_topic = "/arm/2nd".into(),
            "trajectory_topic",
        );
        bad(
            &|s| s.joint_names = vec!["a".into(), "a".into()],
            "joint_names[1]",
        );
        bad(&|s| s.tolerance_rad = 0.0, "tolerance_rad");
        bad(&|s| s.tolerance_rad = 0.2, "tolerance_rad");
        bad(&|s| s.timeout_s = Real::NAN, "timeout_s");
        bad(&|s| s.path_tolerance_rad = 0.6, "path_tolerance_rad");
        bad(&|s| s.path_tolerance_rad = 0.0005, "path_tolerance_rad");
        bad(&|s| s.joint_speed = 11.0, "joint_speed");
        let s = Ros2Spec {
            joint_names: vec!["x".into()],
            ..Ros2Spec::default()
        };
        let e = s.ros_joint_names(&["a", "b"]).unwrap_err();
        assert!(e.contains("1 names for a robot of 2 joints"), "{e}");
    }

    #[test]
    fn a_scenario_file_s_table_is_read_checked_and_written_back() {
        let base = crate::builtin_scenario("bridge1")
            .unwrap()
            .to_toml()
            .unwrap();
        let text = format!(
            "{base}\n[ros2]\nscan_topic = \"/urg/scan\"\njoint_names = [\"j1\", \"j2\", \"j3\", \"j4\", \"j5\", \"j6\"]\n"
        );
        let s = crate::Scenario::from_toml(&text, "my.toml").unwrap();
        let spec = s.ros2.clone().unwrap();
        assert_eq!(spec.scan_topic, "/urg/scan");
        assert_eq!(spec.trajectory_topic, Ros2Spec::default().trajectory_topic);
        let back = crate::Scenario::from_toml(&s.to_toml().unwrap(), "again").unwrap();
        assert_eq!(back.ros2, s.ros2);
        let e = crate::Scenario::from_toml(&format!("{base}\n[ros2]\ntimeout_s = -1\n"), "my.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("ros2.timeout_s"), "{e}");
        let e = crate::Scenario::from_toml(&format!("{base}\n[ros2]\ntopic = \"/x\"\n"), "my.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("topic"), "{e}");
    }

    use geom::Real;
}
