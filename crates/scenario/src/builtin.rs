//! The built-in scenarios (SPEC §4): the AXBAM bridge channels and Pudney's
//! surface-following objects, each printable as a scenario file.

use crate::file::{MetricsConfig, RobotSpec, ScannerSpec, Scenario};
use crate::range_sensors::RangeSensorsSpec;
use geom::Real;
use map::RegionsConfig;
use scene::{PoseSpec, SamplingConfig, builtin};

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
                    timing: None,
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
                    timing: None,
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
        follow: None,
        surface: None,
        ros2: None,
        scene,
    })
}
