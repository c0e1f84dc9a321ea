//! The driver against `serve_robot` over DDS on loopback (issue 26): a
//! lockstep simulated robot served in a thread, driven through the `hw`
//! traits, gives what the same rig gives in process — the joints exactly,
//! each scan's ranges and intensities to their 32 bits (what `LaserScan`
//! carries), each range finder's reading to its 32 bits and its point to
//! a micrometre — with the noise seeded the same way.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use hw::{Arm, LineScanner, RangeSensors};
use ros2::{DriverConfig, Ros2Config, Ros2Hardware, Ros2Node, ServeConfig, serve_robot};
use scenario::Scenario;
use sim::SimRig;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

fn f32_of(x: f64) -> f64 {
    f64::from(x as f32)
}

/// Serve `scenario`'s rig (seed 7) in lockstep in a thread on `domain`;
/// the driver to it and the same rig in process.
fn pair(scenario: &str, domain: u16) -> (Ros2Hardware, SimRig, Arc<AtomicBool>) {
    let loaded = Scenario::load(scenario).unwrap();
    let config = Ros2Config {
        domain_id: domain,
        loopback_only: true,
    };
    let stop = Arc::new(AtomicBool::new(false));
    let served = SimRig::with_every_sensor(&loaded, 7).unwrap();
    let twin = SimRig::with_every_sensor(&loaded, 7).unwrap();
    let robot = served.robot().clone();
    let serve = ServeConfig {
        joint_speed: 10.0,
        scan_range_m: served.scan_range_m().unwrap_or((0.0, 1e9)),
        finder_range_slack_m: 1.0,
        lockstep: true,
        ..ServeConfig::default()
    };
    {
        let stop = Arc::clone(&stop);
        let robot = robot.clone();
        std::thread::spawn(move || {
            let mut rig = served;
            let mut node = Ros2Node::new("served", &config).unwrap();
            serve_robot(&mut rig, &robot, &mut node, &serve, &stop, &mut |m| {
                eprintln!("{m}");
            })
            .unwrap();
        });
    }
    let driver = Ros2Hardware::new(
        Ros2Node::new("driver", &config).unwrap(),
        &robot,
        &twin.world_from_base(),
        twin.bearings_rad(),
        DriverConfig {
            tolerance_rad: 0.0,
            joint_speed: 10.0,
            timeout_s: 30.0,
            lockstep: true,
        },
    )
    .unwrap();
    (driver, twin, stop)
}

fn domain(offset: u16) -> u16 {
    100 + offset + (std::process::id() % 50) as u16
}

#[test]
fn a_lockstep_scanner_over_dds_gives_the_in_process_scans() {
    let (mut driver, mut twin, stop) = pair("bridge1", domain(0));
    assert_eq!(driver.joints(), twin.joints());
    let start = twin.joints();
    for (k, dq) in [
        [0.0, 0.0, 0.0, 0.0, 0.3, 0.0],
        [0.2, 0.05, 0.0, 0.0, 0.1, 0.0],
    ]
    .iter()
    .enumerate()
    {
        let q: Vec<f64> = start.iter().zip(dq).map(|(a, b)| a + b).collect();
        driver.seed_noise(40 + k as u64);
        twin.seed_noise(40 + k as u64);
        driver.move_to(&q).unwrap();
        twin.move_to(&q).unwrap();
        assert_eq!(driver.joints(), q, "the arm stands exactly at the goal");
        for _ in 0..3 {
            let (got, want) = (driver.scan().unwrap(), twin.scan().unwrap());
            assert_eq!(got.ranges_m.len(), want.ranges_m.len());
            let hits = want.ranges_m.iter().flatten().count();
            assert!(hits > 50, "{hits} returns");
            for (g, w) in got.ranges_m.iter().zip(&want.ranges_m) {
                assert_eq!(*g, w.map(f32_of));
            }
            for (g, w) in got.intensities.iter().zip(&want.intensities) {
                assert_eq!(*g, f32_of(*w));
            }
        }
    }
    stop.store(true, Ordering::Relaxed);
}

#[test]
fn lockstep_range_finders_over_dds_give_the_in_process_points() {
    let (mut driver, mut twin, stop) = pair("block1", domain(50));
    let start = twin.joints();
    for k in 0..5 {
        // Across block1's top at the start's height (point3: x, y, z).
        let t = f64::from(k) * 0.02;
        let q = vec![start[0] + t, start[1] - t, start[2]];
        driver.seed_noise(9);
        twin.seed_noise(9);
        driver.move_to(&q).unwrap();
        twin.move_to(&q).unwrap();
        let (got, want) = (driver.read_all().unwrap(), twin.read_all().unwrap());
        assert_eq!(got.len(), want.len());
        assert!(want.iter().flatten().count() >= 5);
        for (g, w) in got.iter().zip(&want) {
            match (g, w) {
                (None, None) => {}
                (Some(g), Some(w)) => {
                    assert_eq!(g.distance_m, f32_of(w.distance_m));
                    assert!((g.point - w.point).norm() < 1e-6, "{g:?} vs {w:?}");
                    assert!((g.axis.into_inner() - w.axis.into_inner()).norm() < 1e-12);
                }
                other => panic!("a reading on one side only: {other:?}"),
            }
        }
    }
    stop.store(true, Ordering::Relaxed);
}
