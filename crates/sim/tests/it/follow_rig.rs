//! The simulation side of surface following (issue 9): seeded range noise,
//! range finders declared in a scenario for any robot, and contact checks
//! along a joint-space motion.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use geom::primitives::cuboid;
use geom::{Isometry3, Point3, Real, Vector3};
use hw::{Arm, RangeSensors};
use plan::contact::{motion_contacts, motion_travel_bound, robot_contacts, smallest_link_radius};
use scenario::range_sensors::{RangeSensorSpec, RangeSensorsSpec, SensorRingSpec};
use scenario::{LoadedScenario, Scenario};
use scene::{MaterialId, Scene, World, default_materials};
use sim::SimRig;
use std::sync::Arc;

fn boxes(list: &[([Real; 3], [Real; 3])]) -> Scene {
    let objects = list
        .iter()
        .enumerate()
        .map(|(i, (lo, hi))| {
            (
                format!("box{i}"),
                MaterialId(0),
                cuboid(Point3::from(*lo), Point3::from(*hi)),
            )
        })
        .collect();
    Scene::from_objects(default_materials(), objects).unwrap()
}

/// point3 0.1 above a flat floor (top at z = 0), reading `n` times at
/// different (x, y); returns the readings of the sensor pointing straight down.
fn floor_readings(seed: u64, sigma: Real, n: usize) -> Vec<Real> {
    let world = Arc::new(World::Mesh(boxes(&[([-2.0, -2.0, -0.1], [2.0, 2.0, 0.0])])));
    let robot = robot::builtin("point3").unwrap();
    let down = robot
        .range_finders
        .iter()
        .position(|m| (m.axis.into_inner() + Vector3::z()).norm() < 1e-12)
        .unwrap();
    let mut rig = SimRig::new(
        robot,
        world,
        Isometry3::identity(),
        &[0.0, 0.0, 0.1],
        None,
        seed,
    )
    .unwrap();
    rig.set_range_noise_sigma_m(sigma).unwrap();
    (0..n)
        .map(|i| {
            let t = i as Real * 0.001;
            rig.move_to(&[t.sin(), t.cos() * 0.5, 0.1]).unwrap();
            rig.read_all().unwrap()[down].unwrap().distance_m
        })
        .collect()
}

#[test]
fn range_noise_is_seeded_and_has_the_given_sigma() {
    let sigma = 0.005;
    let a = floor_readings(7, sigma, 4000);
    assert_eq!(
        a,
        floor_readings(7, sigma, 4000),
        "same seed, same readings"
    );
    assert_ne!(
        a,
        floor_readings(8, sigma, 4000),
        "another seed, other noise"
    );
    // Errors of the readings against the true 0.1 m.
    let n = a.len() as Real;
    let mean = a.iter().map(|d| d - 0.1).sum::<Real>() / n;
    let std = (a.iter().map(|d| (d - 0.1 - mean).powi(2)).sum::<Real>() / (n - 1.0)).sqrt();
    // Standard errors: σ/√n for the mean, σ/√(2n) for the deviation; 5 of each.
    assert!(mean.abs() < 5.0 * sigma / n.sqrt(), "mean error {mean}");
    assert!(
        (std - sigma).abs() < 5.0 * sigma / (2.0 * n).sqrt(),
        "std {std}"
    );
    // σ = 0: exact.
    assert!(
        floor_readings(7, 0.0, 50)
            .iter()
            .all(|d| (d - 0.1).abs() < 1e-12)
    );
}

#[test]
fn bad_noise_is_refused_and_leaves_the_rig_unchanged() {
    let world = Arc::new(World::Mesh(boxes(&[([-1.0, -1.0, -0.1], [1.0, 1.0, 0.0])])));
    let robot = robot::builtin("point3").unwrap();
    let mut rig = SimRig::new(
        robot,
        world,
        Isometry3::identity(),
        &[0.0, 0.0, 0.1],
        None,
        1,
    )
    .unwrap();
    rig.set_range_noise_sigma_m(0.01).unwrap();
    for bad in [-0.001, Real::NAN, Real::INFINITY] {
        let e = rig.set_range_noise_sigma_m(bad).unwrap_err().to_string();
        assert!(e.contains("noise_sigma_m"), "{e}");
        assert_eq!(rig.range_noise_sigma_m(), 0.01);
    }
    // In a scenario file the field is named by its TOML path.
    let mut s = scenario::builtin_scenario("cube").unwrap();
    s.range_sensors.noise_sigma_m = -1.0;
    let text = s.to_toml().unwrap();
    assert!(text.contains("[range_sensors]"));
    let e = Scenario::from_toml(&text, "c.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("c.toml") && e.contains("range_sensors.noise_sigma_m"),
        "{e}"
    );
}

fn ring(
    link: &str,
    centre: [Real; 3],
    axis: [Real; 3],
    radius_m: Real,
    count: u32,
    tilt_deg: Real,
) -> SensorRingSpec {
    SensorRingSpec {
        link: link.into(),
        centre,
        axis,
        radius_m,
        count,
        tilt_deg,
        phase_deg: 0.0,
        max_range_m: 0.2,
    }
}

#[test]
fn rings_reproduce_arm4s_control_point_sensors() {
    // arm4's 17 control-point sensors, written out independently in
    // robot::builtin: the tool axis, 8 at 45°, 8 at 90°, at the tip of link 4.
    let arm4 = robot::builtin("arm4").unwrap();
    let spec = RangeSensorsSpec {
        noise_sigma_m: 0.0,
        sensors: vec![RangeSensorSpec {
            link: "link4".into(),
            origin: [0.0, 0.0, 1.0],
            axis: [0.0, 0.0, 2.0],
            max_range_m: 0.2,
        }],
        rings: vec![
            ring("link4", [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], 0.0, 8, 45.0),
            ring("link4", [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], 0.0, 8, 90.0),
        ],
    };
    let mounts = spec.mounts(&arm4).unwrap();
    assert_eq!(mounts.len(), 17);
    for (m, want) in mounts.iter().zip(&arm4.range_finders[..17]) {
        assert_eq!(m.link, want.link);
        assert!((m.origin - want.origin).norm() < 1e-12);
        assert!(
            (m.axis.into_inner() - want.axis.into_inner()).norm() < 1e-12,
            "{m:?} {want:?}"
        );
        assert_eq!(m.max_range_m, want.max_range_m);
    }
}

#[test]
fn ring_mounts_by_hand() {
    let arm4 = robot::builtin("arm4").unwrap();
    // A ring about the link's x axis: reference direction y, then z = x × y.
    let r = ring("link2", [0.1, 0.0, 0.0], [3.0, 0.0, 0.0], 0.05, 4, 90.0);
    let spec = RangeSensorsSpec {
        rings: vec![r.clone()],
        ..RangeSensorsSpec::default()
    };
    let m = spec.mounts(&arm4).unwrap();
    let link2 = arm4.link_index("link2").unwrap();
    let want = [
        ([0.1, 0.05, 0.0], [0.0, 1.0, 0.0]),
        ([0.1, 0.0, 0.05], [0.0, 0.0, 1.0]),
        ([0.1, -0.05, 0.0], [0.0, -1.0, 0.0]),
        ([0.1, 0.0, -0.05], [0.0, 0.0, -1.0]),
    ];
    assert_eq!(m.len(), 4);
    for (m, (o, a)) in m.iter().zip(want) {
        assert_eq!(m.link, link2);
        assert!((m.origin - Point3::from(o)).norm() < 1e-12, "{m:?}");
        assert!(
            (m.axis.into_inner() - Vector3::from(a)).norm() < 1e-12,
            "{m:?}"
        );
    }
    // Tilted 45° towards the radial direction, phase 90°: the first sensor at z.
    let h = 0.5f64.sqrt();
    let tilted = SensorRingSpec {
        tilt_deg: 45.0,
        phase_deg: 90.0,
        ..r.clone()
    };
    let spec = RangeSensorsSpec {
        rings: vec![tilted],
        ..RangeSensorsSpec::default()
    };
    let m = spec.mounts(&arm4).unwrap();
    assert!((m[0].origin - Point3::new(0.1, 0.0, 0.05)).norm() < 1e-12);
    assert!((m[0].axis.into_inner() - Vector3::new(h, 0.0, h)).norm() < 1e-12);
    assert!((m[1].axis.into_inner() - Vector3::new(h, -h, 0.0)).norm() < 1e-12);
    // Tilt 0: every axis along the ring axis.
    let along = SensorRingSpec { tilt_deg: 0.0, ..r };
    let spec = RangeSensorsSpec {
        rings: vec![along],
        ..RangeSensorsSpec::default()
    };
    assert!(
        spec.mounts(&arm4)
            .unwrap()
            .iter()
            .all(|m| (m.axis.x - 1.0).abs() < 1e-12)
    );
}

#[test]
fn bad_sensor_declarations_name_the_field() {
    let arm4 = robot::builtin("arm4").unwrap();
    let good = ring("link4", [0.0; 3], [0.0, 0.0, 1.0], 0.0, 8, 45.0);
    let check = |r: SensorRingSpec, field: &str| {
        let spec = RangeSensorsSpec {
            rings: vec![good.clone(), r],
            ..RangeSensorsSpec::default()
        };
        let e = spec.mounts(&arm4).unwrap_err();
        assert!(e.contains(field), "{e} should name {field}");
    };
    check(
        SensorRingSpec {
            link: "flange".into(),
            ..good.clone()
        },
        "range_sensors.rings[1].link: unknown link `flange`",
    );
    check(
        SensorRingSpec {
            count: 0,
            ..good.clone()
        },
        "rings[1].count",
    );
    check(
        SensorRingSpec {
            tilt_deg: 200.0,
            ..good.clone()
        },
        "rings[1].tilt_deg",
    );
    check(
        SensorRingSpec {
            axis: [0.0; 3],
            ..good.clone()
        },
        "rings[1].axis",
    );
    check(
        SensorRingSpec {
            radius_m: -0.1,
            ..good.clone()
        },
        "rings[1].radius_m",
    );
    check(
        SensorRingSpec {
            max_range_m: Real::NAN,
            ..good.clone()
        },
        "rings[1].max_range_m",
    );
    let spec = RangeSensorsSpec {
        sensors: vec![RangeSensorSpec {
            link: "nope".into(),
            origin: [0.0; 3],
            axis: [1.0, 0.0, 0.0],
            max_range_m: 0.2,
        }],
        ..RangeSensorsSpec::default()
    };
    let e = spec.mounts(&arm4).unwrap_err();
    assert!(
        e.contains("sensors[0].link: unknown link `nope`") && e.contains("link4"),
        "{e}"
    );
    // Through a scenario: the robot is unchanged on error, the file named.
    let mut s = scenario::builtin_scenario("cube").unwrap();
    s.range_sensors = spec;
    let loaded = LoadedScenario {
        scenario: s,
        base_dir: ".".into(),
    };
    let e = loaded.build_robot().unwrap_err().to_string();
    assert!(
        e.contains("cube") && e.contains("unknown link `nope`"),
        "{e}"
    );
}

#[test]
fn travel_bound_by_hand() {
    // point3: prismatic joints move every point by |Δq| each.
    let p3 = robot::builtin("point3").unwrap();
    let b = motion_travel_bound(&p3, &[0.0, 0.0, 0.0], &[0.3, -0.4, 0.1]).unwrap();
    assert!((b - 0.8).abs() < 1e-12);
    // arm4 yaw: the farthest point is link 4's far cap, which ends at the
    // tip, 3 m along the links from the yaw axis point (its axis stops one
    // 0.05 m radius short of it).
    let arm4 = robot::builtin("arm4").unwrap();
    let q0 = [0.0; 6];
    let mut q1 = q0;
    q1[0] = 0.5;
    let b = motion_travel_bound(&arm4, &q0, &q1).unwrap();
    assert!((b - 3.0 * 0.5).abs() < 1e-12, "{b}");
    // The arm stretched horizontally (joint 2 at 90°) moves its tip by the
    // chord 2·3·sin(0.25), within the bound.
    let mut a = q0;
    a[1] = std::f64::consts::FRAC_PI_2;
    let mut c = a;
    c[0] = 0.5;
    let tip = |q: &[Real]| arm4.tool_pose(q).unwrap().translation.vector;
    let moved = (tip(&c) - tip(&a)).norm();
    assert!((moved - 6.0 * (0.25f64).sin()).abs() < 1e-9);
    assert!(moved <= motion_travel_bound(&arm4, &a, &c).unwrap());
    assert_eq!(smallest_link_radius(&arm4), Some(0.05));
    assert_eq!(smallest_link_radius(&p3), Some(0.02));
}

#[test]
fn a_motion_through_an_obstacle_between_clear_poses_is_caught() {
    // point3 (a 0.02 m sphere) crosses a 1 mm plate at x = 0: both end poses
    // are clear, the straight motion is not.
    let plate = boxes(&[([-0.0005, -1.0, -1.0], [0.0005, 1.0, 1.0])]);
    let p3 = robot::builtin("point3").unwrap();
    let id = Isometry3::identity();
    let (q0, q1) = ([-0.7, 0.0, 0.0], [0.7, 0.0, 0.0]);
    for q in [q0, q1] {
        assert!(robot_contacts(&p3, &p3.forward_kinematics(&q).unwrap(), &id, &plate).is_empty());
    }
    let step = 0.5 * smallest_link_radius(&p3).unwrap();
    let r = motion_contacts(&p3, &q0, &q1, &id, &plate, step).unwrap();
    let hit = r.first_contact.as_ref().expect("the crossing is caught");
    // First touch at x = −0.0205, t = 0.6795 / 1.4, found within one step.
    let t_touch = (0.7 - 0.0205) / 1.4;
    assert!(
        hit.t >= t_touch - 1e-12 && hit.t <= t_touch + step / 1.4 + 1e-12,
        "{hit:?}"
    );
    assert_eq!(hit.contact.link, robot::LinkId(3));
    assert!(r.step_bound_m <= step);
    // A clear motion (above the plate) checks every step and finds nothing.
    let r = motion_contacts(&p3, &[-0.7, 0.0, 1.1], &[0.7, 0.0, 1.1], &id, &plate, step).unwrap();
    assert!(r.is_clear());
    assert_eq!(r.checks, (1.4 / step).ceil() as usize + 1);

    // arm4 swinging horizontally through a thin post 2.5 m from its axis; the
    // end poses are clear of it.
    let post = boxes(&[(
        [
            2.5 * 0.5f64.sqrt() - 0.0005,
            2.5 * 0.5f64.sqrt() - 0.0005,
            0.0,
        ],
        [
            2.5 * 0.5f64.sqrt() + 0.0005,
            2.5 * 0.5f64.sqrt() + 0.0005,
            3.0,
        ],
    )]);
    let arm4 = robot::builtin("arm4").unwrap();
    let mut a = [0.0; 6];
    a[1] = std::f64::consts::FRAC_PI_2;
    let mut b = a;
    b[0] = std::f64::consts::FRAC_PI_2;
    for q in [a, b] {
        assert!(
            robot_contacts(&arm4, &arm4.forward_kinematics(&q).unwrap(), &id, &post).is_empty()
        );
    }
    let step = 0.5 * smallest_link_radius(&arm4).unwrap();
    let r = motion_contacts(&arm4, &a, &b, &id, &post, step).unwrap();
    assert!(r.first_contact.is_some(), "{r:?}");
    // Coarse steps (one check per end pose) miss it: the fine stepping matters.
    let coarse = motion_contacts(&arm4, &a, &b, &id, &post, 100.0).unwrap();
    assert!(coarse.is_clear() && coarse.checks == 2);
    // Bad step sizes are refused by name.
    for bad in [0.0, -1.0, Real::NAN, 1e-12] {
        let e = motion_contacts(&arm4, &a, &b, &id, &post, bad)
            .unwrap_err()
            .to_string();
        assert!(e.contains("max_step_m"), "{e}");
    }
}

#[test]
fn a_scenario_builds_a_rig_with_its_sensors_and_noise() {
    let mut s = scenario::builtin_scenario("cube").unwrap();
    s.range_sensors.noise_sigma_m = 0.003;
    s.range_sensors
        .rings
        .push(ring("body", [0.0; 3], [0.0, 0.0, -1.0], 0.0, 1, 0.0));
    let loaded = LoadedScenario {
        scenario: s,
        base_dir: ".".into(),
    };
    let mut rig = SimRig::of_scenario(&loaded, 3).unwrap();
    assert_eq!(rig.robot().range_finders.len(), 27);
    assert_eq!(rig.range_noise_sigma_m(), 0.003);
    assert_eq!(rig.joints(), vec![0.0, 0.0, 1.1]);
    // The added sensor looks down at the top face 0.1 below, with noise.
    let d = rig.read_all().unwrap()[26].unwrap().distance_m;
    assert!((d - 0.1).abs() < 5.0 * 0.003 && d != 0.1, "{d}");
    let again = SimRig::of_scenario(&loaded, 3).unwrap().read_all().unwrap()[26]
        .unwrap()
        .distance_m;
    assert_eq!(d, again);
}
