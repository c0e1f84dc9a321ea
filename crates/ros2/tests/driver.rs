//! The driver against `serve_robot` over DDS on loopback (issue 26): a
//! lockstep simulated robot served in a thread, driven through the `hw`
//! traits, gives exactly what the same rig gives in process — the joints,
//! each scan's ranges and intensities, each range finder's reading and its
//! point — with the noise seeded the same way: a simulated sensor reports
//! the float32 values its ROS 2 message carries.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use hw::{Arm, LineScanner, RangeSensors};
use ros2::{DriverConfig, Ros2Config, Ros2Hardware, Ros2Node, ServeConfig, serve_robot};
use scenario::Scenario;
use sim::SimRig;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

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
            ros2: scenario::ros2::Ros2Spec {
                joint_speed: 10.0,
                timeout_s: 30.0,
                ..scenario::ros2::Ros2Spec::default()
            },
            lockstep: true,
            limits: None,
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
            assert_eq!(got.ranges_m, want.ranges_m);
            assert_eq!(got.intensities, want.intensities);
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
                    assert_eq!(g, w);
                }
                other => panic!("a reading on one side only: {other:?}"),
            }
        }
    }
    stop.store(true, Ordering::Relaxed);
}

#[test]
fn the_live_view_reaches_a_subscriber() {
    use record::bag::msg::{MarkerArray, PointCloud2, TfMessage};
    use record::bag::topics;
    let config = Ros2Config {
        domain_id: domain(25),
        loopback_only: true,
    };
    let loaded = Scenario::load("bridge1").unwrap();
    let rig = SimRig::with_every_sensor(&loaded, 7).unwrap();
    let robot = rig.robot().clone();
    let mut live = ros2::LiveView::new(
        Ros2Node::new("live", &config).unwrap(),
        &robot,
        &rig.world_from_base(),
    )
    .unwrap();
    // A late subscriber: /tf_static is latched, the rest comes after it
    // matched.
    let mut node = Ros2Node::new("viewer", &config).unwrap();
    let tf = node.subscription::<TfMessage>(topics::TF).unwrap();
    let tf_static = node
        .latched_subscription::<TfMessage>(topics::TF_STATIC)
        .unwrap();
    let sweeps = node.subscription::<PointCloud2>(topics::SWEEP).unwrap();
    let discs = node.subscription::<MarkerArray>(topics::DISCS).unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
    while node.publishers_of(&tf) == 0 || node.publishers_of(&discs) == 0 {
        assert!(std::time::Instant::now() < deadline, "no match");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(200));
    let q = rig.joints();
    live.frames(&q);
    let point = sensor::SweepPoint {
        point: geom::Point3::new(1.0, 2.0, 3.0),
        origin: geom::Point3::origin(),
        intensity: 0.5,
        material: None,
        cell: None,
    };
    live.sweep([&point]);
    live.markers(topics::DISCS, MarkerArray::default());
    live.markers("/elsewhere", MarkerArray::default());
    assert_eq!(live.messages_sent(), 3);
    assert!(live.first_failure().unwrap().starts_with("/elsewhere"));
    let take = |what: &str, f: &mut dyn FnMut() -> bool| {
        while !f() {
            assert!(std::time::Instant::now() < deadline, "no {what}");
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
    };
    let mut frames = None;
    take("/tf", &mut || {
        frames = tf.take().unwrap().map(|(m, _)| m);
        frames.is_some()
    });
    let want = record::bag::link_frames(0, &robot, &q);
    let got = frames.unwrap();
    assert_eq!(got.transforms.len(), want.transforms.len());
    for (g, w) in got.transforms.iter().zip(&want.transforms) {
        assert_eq!(g.transform, w.transform);
        assert_eq!(g.child_frame_id, w.child_frame_id);
    }
    let mut statics = None;
    take("/tf_static", &mut || {
        statics = tf_static.take().unwrap().map(|(m, _)| m);
        statics.is_some()
    });
    assert_eq!(
        statics.unwrap().transforms,
        record::bag::static_frames(&robot, &rig.world_from_base()).transforms
    );
    let mut cloud = None;
    take("/surveyor/sweep", &mut || {
        cloud = sweeps.take().unwrap().map(|(m, _)| m);
        cloud.is_some()
    });
    assert_eq!(cloud.unwrap().width, 1);
    take("/surveyor/discs", &mut || discs.take().unwrap().is_some());
}

/// Issue 46 acceptance 4's clock: a robot served five times faster than
/// real time publishes `/clock`, stamps on it and moves on it, and the
/// driver follows it: a motion of 1 rad at 1 rad/s takes a robot second
/// (a fifth of one of wall time), and a timeout of 10 s runs out after 10
/// robot seconds, long before 10 s of wall time.
#[test]
fn the_driver_follows_a_faster_robot_s_clock() {
    let loaded = Scenario::load("bridge1").unwrap();
    let config = Ros2Config {
        domain_id: domain(75),
        loopback_only: true,
    };
    let stop = Arc::new(AtomicBool::new(false));
    let served = SimRig::with_every_sensor(&loaded, 7).unwrap();
    let robot = served.robot().clone();
    let world_from_base = served.world_from_base();
    let bearings = served.bearings_rad().to_vec();
    let serve = ServeConfig {
        joint_speed: 1.0,
        rate: 5.0,
        // No scan in this test's time: a scan request must time out.
        scan_period_s: 1e6,
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
    let mut driver = Ros2Hardware::new(
        Ros2Node::new("driver", &config).unwrap(),
        &robot,
        &world_from_base,
        &bearings,
        DriverConfig {
            ros2: scenario::ros2::Ros2Spec {
                joint_speed: 1.0,
                timeout_s: 10.0,
                ..scenario::ros2::Ros2Spec::default()
            },
            lockstep: false,
            limits: None,
        },
    )
    .unwrap();
    // The served robot's /clock is heard from the start.
    let before = driver
        .robot_clock_ns()
        .unwrap()
        .expect("the robot's /clock");
    let wall = std::time::Instant::now();
    let mut q = driver.joints();
    q[0] += 1.0;
    driver.move_to(&q).unwrap();
    let robot_s = (driver.robot_clock_ns().unwrap().unwrap() - before) as f64 * 1e-9;
    let wall_s = wall.elapsed().as_secs_f64();
    assert!(
        robot_s >= 0.98,
        "1 rad at 1 rad/s in {robot_s} robot seconds"
    );
    assert!(
        wall_s < 0.6 * robot_s,
        "{wall_s} s of wall time for {robot_s} robot seconds at 5 times real time"
    );
    // No scan comes: the timeout is the robot's 10 s.
    let before = driver.robot_clock_ns().unwrap().unwrap();
    let wall = std::time::Instant::now();
    let e = driver.scan().unwrap_err().to_string();
    let robot_s = (driver.robot_clock_ns().unwrap().unwrap() - before) as f64 * 1e-9;
    let wall_s = wall.elapsed().as_secs_f64();
    assert!(e.contains("no scan before the timeout"), "{e}");
    assert!(robot_s >= 10.0, "timed out after {robot_s} robot seconds");
    assert!(wall_s < 10.0, "timed out after {wall_s} s of wall time");
    stop.store(true, Ordering::Relaxed);
}

/// A served robot runs a trajectory of several points on their times (as
/// a `ros2_control` joint trajectory controller does), on its own clock:
/// at 5 times real time, the joint states it stamps follow the
/// piecewise-linear path of the points' times, and it takes the
/// trajectory's 3 s of robot time from leaving the start to the goal.
#[test]
fn a_served_robot_follows_a_trajectory_s_times() {
    use record::bag::msg::{JointState, JointTrajectory, JointTrajectoryPoint, Time};
    let loaded = Scenario::load("bridge1").unwrap();
    let config = Ros2Config {
        domain_id: domain(100),
        loopback_only: true,
    };
    let stop = Arc::new(AtomicBool::new(false));
    let served = SimRig::with_every_sensor(&loaded, 7).unwrap();
    let robot = served.robot().clone();
    let start = served.joints();
    let serve = ServeConfig {
        joint_speed: 10.0,
        rate: 5.0,
        state_period_s: 0.02,
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
    let spec = scenario::ros2::Ros2Spec::default();
    let mut node = Ros2Node::new("planner", &config).unwrap();
    let states = node
        .subscription::<JointState>(&spec.joint_states_topic)
        .unwrap();
    let commands = node
        .publisher::<JointTrajectory>(&spec.trajectory_topic)
        .unwrap();
    let t0 = std::time::Instant::now();
    while node.subscriptions_of(&commands) == 0 || node.publishers_of(&states) == 0 {
        assert!(
            t0.elapsed().as_secs() < 30,
            "the served robot never matched"
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let names: Vec<String> = robot.joint_names().iter().map(|&n| n.to_owned()).collect();
    // Joint 1 by 0.5 rad in 1 s, then joint 2 by 1 rad in the next 2 s.
    let mid: Vec<f64> = start
        .iter()
        .enumerate()
        .map(|(i, q)| if i == 0 { q + 0.5 } else { *q })
        .collect();
    let goal: Vec<f64> = mid
        .iter()
        .enumerate()
        .map(|(i, q)| if i == 1 { q + 1.0 } else { *q })
        .collect();
    let path = |t: f64| -> Vec<f64> {
        let (a, b, s) = if t <= 1.0 {
            (&start, &mid, t.max(0.0))
        } else {
            (&mid, &goal, ((t - 1.0) / 2.0).min(1.0))
        };
        a.iter().zip(b).map(|(x, y)| x + s * (y - x)).collect()
    };
    let point = |q: &[f64], s: f64| JointTrajectoryPoint {
        positions: q.to_vec(),
        time_from_start: Time::from_nanos((s * 1e9) as u64),
        ..JointTrajectoryPoint::default()
    };
    commands
        .publish(JointTrajectory {
            joint_names: names.clone(),
            points: vec![point(&mid, 1.0), point(&goal, 3.0)],
            ..JointTrajectory::default()
        })
        .unwrap();
    // Every state until the goal, by its stamp.
    let mut seen: Vec<(f64, Vec<f64>)> = Vec::new();
    let t0 = std::time::Instant::now();
    loop {
        assert!(t0.elapsed().as_secs() < 30, "the goal was never reached");
        let Some((js, _)) = states.take().unwrap() else {
            std::thread::sleep(std::time::Duration::from_millis(1));
            continue;
        };
        let q: Vec<f64> = names
            .iter()
            .map(|n| js.position[js.name.iter().position(|x| x == n).unwrap()])
            .collect();
        let t = js.header.stamp.to_nanos().unwrap() as f64 * 1e-9;
        let at_goal = q == goal;
        seen.push((t, q));
        if at_goal {
            break;
        }
    }
    // When the robot took the trajectory: from the first state on the
    // way, joint 1 having moved at 0.5 rad/s since.
    let first = seen.iter().position(|(_, q)| *q != start).unwrap();
    let (t1, q1) = &seen[first];
    let t_took = t1 - (q1[0] - start[0]) / 0.5;
    let t_goal = seen.last().unwrap().0;
    // The goal is stamped in the first turn of the loop at or after 3 s.
    let took = t_goal - t_took;
    assert!(
        (3.0 - 1e-6..3.2).contains(&took),
        "the trajectory took {took} robot seconds"
    );
    let moving = &seen[first..seen.len() - 1];
    assert!(moving.len() > 5, "{} states on the way", moving.len());
    for (t, q) in moving {
        let want = path(t - t_took);
        let error = q
            .iter()
            .zip(&want)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        // Each state is the position due at its own stamp.
        assert!(error < 1e-6, "at {} s: {q:?} against {want:?}", t - t_took);
    }
    stop.store(true, Ordering::Relaxed);
}

/// An arm that does not move when sent a trajectory (seized, or too weak):
/// the driver sees its joint states leave the path it sent by more than
/// the path tolerance, sends a one-point trajectory holding the arm where
/// it stands, and stops with an error naming the joint. Then the arm falls
/// silent: the next motion stops after the timeout, saying no joint state
/// came. A stand-in robot of a few lines publishes the states (no
/// `/clock`: the wall clock times the run).
#[test]
fn an_arm_off_its_path_is_held_and_a_silent_one_is_reported() {
    use record::bag::msg::{Header, JointState, JointTrajectory};
    let loaded = Scenario::load("bridge1").unwrap();
    let config = Ros2Config {
        domain_id: domain(125),
        loopback_only: true,
    };
    let rig = SimRig::with_every_sensor(&loaded, 7).unwrap();
    let robot = rig.robot().clone();
    let start = rig.joints();
    let names: Vec<String> = robot.joint_names().iter().map(|&n| n.to_owned()).collect();
    let spec = scenario::ros2::Ros2Spec {
        timeout_s: 1.0,
        ..scenario::ros2::Ros2Spec::default()
    };
    let silent = Arc::new(AtomicBool::new(false));
    let sent = Arc::new(std::sync::Mutex::new(Vec::<JointTrajectory>::new()));
    {
        let (silent, sent, spec) = (Arc::clone(&silent), Arc::clone(&sent), spec.clone());
        let (names, start) = (names.clone(), start.clone());
        std::thread::spawn(move || {
            let mut node = Ros2Node::new("seized", &config).unwrap();
            let states = node
                .publisher::<JointState>(&spec.joint_states_topic)
                .unwrap();
            let commands = node
                .subscription::<JointTrajectory>(&spec.trajectory_topic)
                .unwrap();
            while !silent.load(Ordering::Relaxed) {
                states
                    .publish(JointState {
                        header: Header::new(ros2::wall_clock_ns(), ""),
                        name: names.clone(),
                        position: start.clone(),
                        ..JointState::default()
                    })
                    .unwrap();
                while let Some((t, _)) = commands.take().unwrap() {
                    sent.lock().unwrap().push(t);
                }
                std::thread::sleep(std::time::Duration::from_millis(10));
            }
        });
    }
    let mut driver = Ros2Hardware::new(
        Ros2Node::new("driver", &config).unwrap(),
        &robot,
        &rig.world_from_base(),
        &[],
        DriverConfig {
            ros2: spec,
            lockstep: false,
            limits: None,
        },
    )
    .unwrap();
    let mut goal = start.clone();
    goal[1] += 0.5;
    let e = driver.move_to(&goal).unwrap_err().to_string();
    assert!(
        e.contains(&format!("joint {} was", names[1])) && e.contains("off its trajectory"),
        "{e}"
    );
    assert!(e.contains("the path tolerance is 0.05"), "{e}");
    // The hold: one point, where the arm stands, after the motion.
    let t0 = std::time::Instant::now();
    let hold = loop {
        if let Some(last) = sent.lock().unwrap().last().filter(|t| t.points.len() == 1) {
            break last.clone();
        }
        assert!(t0.elapsed().as_secs() < 10, "no hold was sent");
        std::thread::sleep(std::time::Duration::from_millis(10));
    };
    assert_eq!(hold.points[0].positions, start);
    assert!(sent.lock().unwrap()[0].points.len() > 1, "the motion first");
    // Silent: the states stop, the next motion stops after the timeout.
    // (A goal 0.01 rad away: never off the path by the tolerance, never
    // reached by an arm that stands still.)
    silent.store(true, Ordering::Relaxed);
    std::thread::sleep(std::time::Duration::from_millis(50));
    let mut near = start.clone();
    near[2] += 0.01;
    let wall = std::time::Instant::now();
    let e = driver.move_to(&near).unwrap_err().to_string();
    let waited = wall.elapsed().as_secs_f64();
    assert!(e.contains("no joint state on /joint_states for"), "{e}");
    assert!(waited < 10.0, "gave up after {waited} s");
}
