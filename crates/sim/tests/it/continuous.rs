//! Continuous motion (issue 46): a scanner scanning while the arm turns at
//! its speed limit, each beam placed at the pose of its own moment, against
//! the walls of a room it stands in.

use geom::primitives::cuboid;
use geom::{Isometry3, Point3, Real};
use hw::LineScanner;
use hw::motion::{LineMotion, place_moving_scan};
use robot::timing::MotionLimits;
use scene::{MaterialId, Scene, World, default_materials};
use sensor::{Scanner, ScannerConfig, SweepBuilder};
use sim::SimRig;
use std::sync::Arc;

/// The room's inside: x and y in [−3, 3], z in [−1, 3] (walls 0.2 m thick).
const LO: [Real; 3] = [-3.0, -3.0, -1.0];
const HI: [Real; 3] = [3.0, 3.0, 3.0];

fn room() -> Scene {
    let t = 0.2;
    let mut objects = Vec::new();
    for axis in 0..3 {
        for (k, side) in [LO[axis] - t, HI[axis]].into_iter().enumerate() {
            let (mut lo, mut hi) = ([-3.5, -3.5, -1.5], [3.5, 3.5, 3.5]);
            lo[axis] = side;
            hi[axis] = side + t;
            objects.push((
                format!("wall{axis}{k}"),
                MaterialId(0),
                cuboid(Point3::from(lo), Point3::from(hi)),
            ));
        }
    }
    Scene::from_objects(default_materials(), objects).unwrap()
}

/// Distance from a point to the room's walls (the nearest of the six
/// planes).
fn off_the_walls(p: &Point3) -> Real {
    (0..3)
        .flat_map(|a| [(p[a] - LO[a]).abs(), (HI[a] - p[a]).abs()])
        .fold(Real::INFINITY, Real::min)
}

/// The motion of the tests below: the DENSO turns its base and its
/// wrist's two joints through 2 rad each at their limit of 1 rad/s (and
/// 2 rad/s²), in 2.5 s; and the scanner without its materials' range bias.
fn turning_motion() -> (LineMotion, ScannerConfig) {
    let q0 = vec![-1.0, -0.3, 1.9, 0.0, -0.8, 0.0];
    let q1 = vec![1.0, -0.3, 1.9, 2.0, 1.2, 0.0];
    let motion = LineMotion::new(&MotionLimits::uniform(6, 1.0, 2.0), &q0, &q1);
    assert!((motion.duration_s() - 2.5).abs() < 1e-12);
    let config = ScannerConfig {
        material_range_bias: false,
        ..ScannerConfig::default()
    };
    (motion, config)
}

/// The DENSO in the room at the start of [`turning_motion`], seed 7.
fn rig_in_the_room(robot: &robot::Robot, q0: &[Real], config: ScannerConfig) -> SimRig {
    SimRig::new(
        robot.clone(),
        Arc::new(World::Mesh(room())),
        Isometry3::identity(),
        q0,
        Some(Scanner::new(config).unwrap()),
        7,
    )
    .unwrap()
}

/// Every point of `scans`, placed at the pose of its beam's moment and at
/// the pose of its scan's stamp, as its distance off the walls in σ of the
/// scanner's noise at its range; asserts the first lie on the walls within
/// the noise (none beyond 5σ, 0.8σ root mean square) and the second do
/// not (1.3σ or more root mean square, more than 50 beyond 4σ).
fn moments_place_on_the_walls_and_stamps_do_not(
    robot: &robot::Robot,
    scans: &[hw::motion::MovingScan],
    bearings: &[Real],
    noise: &sensor::RangeNoise,
) {
    let world = Isometry3::identity();
    let (mut moving, mut whole) = (
        SweepBuilder::new(bearings).unwrap(),
        SweepBuilder::new(bearings).unwrap(),
    );
    for scan in scans {
        place_moving_scan(robot, &world, scan, &mut moving).unwrap();
        let at_stamp = robot::moving::beam_poses(
            robot,
            &world,
            &scan.joints,
            scan.start_s,
            0.0,
            bearings.len(),
        )
        .unwrap();
        let r = &scan.readings;
        whole
            .push_scan_posed(&at_stamp, &r.ranges_m, &r.intensities, None)
            .unwrap();
    }
    let off = |b: SweepBuilder| -> Vec<(Real, Real)> {
        let sweep = b.finish().unwrap();
        sweep
            .points()
            .iter()
            .map(|p| (off_the_walls(&p.point), noise.sigma_m(p.range_m())))
            .collect()
    };
    let (moving, whole) = (off(moving), off(whole));
    assert!(moving.len() > 5_000, "{} points", moving.len());
    // Root mean square of the distance in σ: about 1 for points off by
    // noise alone.
    let rms = |v: &[(Real, Real)]| {
        (v.iter().map(|(d, s)| (d / s).powi(2)).sum::<Real>() / v.len() as Real).sqrt()
    };
    let beyond = |v: &[(Real, Real)], k: Real| v.iter().filter(|(d, s)| d / s > k).count();
    assert_eq!(beyond(&moving, 5.0), 0);
    assert!(rms(&moving) < 1.0, "{}", rms(&moving));
    assert!(rms(&whole) > 1.3, "{}", rms(&whole));
    assert!(beyond(&whole, 4.0) > 50, "{}", beyond(&whole, 4.0));
}

/// [`turning_motion`] scanning all along: 25 scans, each beam 0.1 ms
/// after the one before, so a scan's last beam is 0.067 rad of each
/// joint's turn after its first.
/// Placed at the pose of their moment (joint states every 10 ms,
/// interpolated), every point lies on the walls within 5σ of the scanner's
/// noise, at 0.8σ root mean square. Placed at the pose of the scan's
/// stamp, as a scan taken standing is, the same points lie 1.4σ off root
/// mean square, 65 of them beyond 4σ and up to 0.22 m: the test tells the
/// two placements apart.
#[test]
fn beams_placed_at_their_moment_lie_on_the_walls_and_whole_scans_do_not() {
    let robot = robot::builtin("denso-vm6083").unwrap();
    let (motion, config) = turning_motion();
    let noise = config.noise;
    let mut rig = rig_in_the_room(&robot, &motion.from, config);
    let bearings = rig.bearings_rad().to_vec();
    let arm = rig.moving().unwrap();
    arm.start_motion(&motion).unwrap();
    let mut scans = Vec::new();
    while let Some(scan) = arm.next_scan().unwrap() {
        scans.push(scan);
    }
    assert_eq!(scans.len(), 25);
    // The arm rests at the end of the line.
    assert_eq!(hw::Arm::joints(&rig), motion.to);
    moments_place_on_the_walls_and_stamps_do_not(&robot, &scans, &bearings, &noise);
}

/// The same motion on the same rig served as a ROS 2 robot (`surveyor
/// sim-robot`, issue 46) at 5 times real time on its `/clock`, its scanner
/// running free (a scan every 0.1 s, each beam cast from where the arm was
/// at its moment), driven through the driver's continuous motion: the
/// motion goes out as one timed trajectory, and each scan comes back with
/// the joint states around it (here every 10 ms of robot time). The
/// points placed by the driver lie on the walls as they do in process, and
/// placed whole they do not; the arm rests at the end of the line, and
/// the motion takes its 2.5 s of robot time (with the driver's 0.02 s
/// lead and the robot's 10 ms ticks), half a second of wall time.
#[test]
fn over_ros2_moving_scans_land_on_the_walls() {
    use ros2::{DriverConfig, Ros2Config, Ros2Hardware, Ros2Node, ServeConfig, serve_robot};
    use std::sync::atomic::{AtomicBool, Ordering};
    let robot = robot::builtin("denso-vm6083").unwrap();
    let (motion, config) = turning_motion();
    let noise = config.noise;
    let served = rig_in_the_room(&robot, &motion.from, config);
    let bearings = served.bearings_rad().to_vec();
    let ros = Ros2Config {
        domain_id: 60 + (std::process::id() % 40) as u16,
        loopback_only: true,
    };
    let stop = Arc::new(AtomicBool::new(false));
    let serve = ServeConfig {
        rate: 5.0,
        tick_s: 0.002,
        state_period_s: 0.01,
        scan_range_m: (config.min_range_m, config.max_range_m),
        ..ServeConfig::default()
    };
    {
        let (stop, robot) = (Arc::clone(&stop), robot.clone());
        std::thread::spawn(move || {
            let mut rig = served;
            let mut node = Ros2Node::new("served", &ros).unwrap();
            serve_robot(&mut rig, &robot, &mut node, &serve, &stop, &mut |m| {
                eprintln!("{m}");
            })
            .unwrap();
        });
    }
    let mut driver = Ros2Hardware::new(
        Ros2Node::new("driver", &ros).unwrap(),
        &robot,
        &Isometry3::identity(),
        &bearings,
        DriverConfig {
            ros2: scenario::ros2::Ros2Spec {
                timeout_s: 10.0,
                ..scenario::ros2::Ros2Spec::default()
            },
            lockstep: false,
            limits: None,
        },
    )
    .unwrap();
    let before = driver.robot_clock_ns().unwrap().unwrap();
    let wall = std::time::Instant::now();
    let arm = driver.moving().unwrap();
    arm.start_motion(&motion).unwrap();
    let mut scans = Vec::new();
    while let Some(scan) = arm.next_scan().unwrap() {
        scans.push(scan);
    }
    let robot_s = (driver.robot_clock_ns().unwrap().unwrap() - before) as Real * 1e-9;
    let wall_s = wall.elapsed().as_secs_f64();
    stop.store(true, Ordering::Relaxed);
    // A scan begins every 0.1 s of the free-running scanner, so 24 or 25
    // begin within the motion's 2.5 s.
    assert!((24..=25).contains(&scans.len()), "{} scans", scans.len());
    for (a, b) in hw::Arm::joints(&driver).iter().zip(&motion.to) {
        assert!((a - b).abs() < 1e-9, "rests at {a}, not {b}");
    }
    assert!((2.5..2.8).contains(&robot_s), "{robot_s} robot seconds");
    assert!(wall_s < 0.3 * robot_s, "{wall_s} s of wall time");
    moments_place_on_the_walls_and_stamps_do_not(&robot, &scans, &bearings, &noise);
}

/// A guard that refuses after five scans brakes the arm at once: it comes
/// to rest where the last check it passed said it would (the horizon of
/// one more scan and braking), short of the line's end, and the clock
/// counts the motion, its scans and the settling allowance.
#[test]
fn a_refusing_guard_brakes_the_arm_where_the_last_check_allowed() {
    use hw::clock::{Activity, RobotClock, RobotTiming, Timed};
    let robot = robot::builtin("denso-vm6083").unwrap();
    let q0 = vec![-1.0, -0.3, 1.9, 0.0, -0.8, 0.0];
    let q1 = vec![1.0, -0.3, 1.9, 0.0, -0.8, 0.0];
    let rig = SimRig::new(
        robot.clone(),
        Arc::new(World::Mesh(room())),
        Isometry3::identity(),
        &q0,
        Some(Scanner::new(ScannerConfig::default()).unwrap()),
        7,
    )
    .unwrap();
    let limits = MotionLimits::uniform(6, 1.0, 2.0);
    let timing = RobotTiming {
        limits: limits.clone(),
        settle_s: 0.05,
        scan_time_s: 0.1,
        reading_period_s: 0.01,
    };
    let clock = RobotClock::default();
    clock.set_activity(Activity::MovingWhileScanning);
    let mut hw = Timed::new(rig, timing, clock.clone());
    let motion = LineMotion::new(&limits, &q0, &q1);
    let mut builder = SweepBuilder::new(hw.bearings_rad()).unwrap();
    let mut allowed: Vec<Vec<Real>> = Vec::new();
    let done = hw::motion::scan_line(
        &mut hw,
        &robot,
        &Isometry3::identity(),
        &motion,
        0.1,
        &mut builder,
        &mut |_, rest, b| {
            let ok = b.scan_count() < 5;
            if ok {
                allowed.push(rest.to_vec());
            }
            ok
        },
    )
    .unwrap();
    assert!(!done.completed);
    let last = allowed.last().unwrap();
    assert!(
        (done.reached[0] - last[0]).abs() < 1e-9,
        "{done:?} {last:?}"
    );
    assert!(done.reached[0] < 1.0);
    assert_eq!(hw::Arm::joints(&hw), done.reached);
    // Braked 0.5 s in, after the fifth scan, just as it reached 1 rad/s:
    // braking at 2 rad/s² takes 0.5 s more. The scans run on to rest at
    // 1.0 s (ten in all), then 0.05 s to settle.
    let braked = motion.braked(0.5);
    assert!((braked.duration_s() - 1.0).abs() < 1e-12);
    assert_eq!(builder.scan_count(), 10);
    assert_eq!(clock.now_ns(), 1_050_000_000);
    assert!((clock.spent().moving_while_scanning_s - 1.05).abs() < 1e-9);
}

/// A continuous motion recorded in a run's bag (joint states every 10 ms,
/// each `LaserScan` with its `time_increment`), after a scan taken
/// standing: read back as `surveyor map --bag` reads it, every point is
/// where the loop placed it (within 1 µm; the bag's stamps are whole
/// nanoseconds).
#[test]
fn a_bag_places_moving_scans_where_the_loop_did() {
    use hw::clock::{Activity, RobotClock, RobotTiming, Timed};
    use hw::script::{Event, Tap};
    let robot = robot::builtin("denso-vm6083").unwrap();
    let q0 = vec![-1.0, -0.3, 1.9, 0.0, -0.8, 0.0];
    let q1 = vec![0.2, -0.3, 1.9, 0.7, -0.4, 0.0];
    let world = Isometry3::translation(0.1, -0.2, 0.3);
    let rig = SimRig::new(
        robot.clone(),
        Arc::new(World::Mesh(room())),
        world,
        &q0,
        Some(Scanner::new(ScannerConfig::default()).unwrap()),
        3,
    )
    .unwrap();
    let mut bag = rig.run_bag().unwrap();
    let limits = MotionLimits::uniform(6, 1.0, 2.0);
    let timing = RobotTiming {
        limits: limits.clone(),
        settle_s: 0.05,
        scan_time_s: 0.1,
        reading_period_s: 0.01,
    };
    let clock = RobotClock::default();
    clock.set_activity(Activity::MovingWhileScanning);
    let timed = Timed::new(rig, timing, clock.clone());
    let mut hw = Tap::with_sink(timed, |e: &Event| {
        scenario::job::bag_event(&mut bag, &clock, e);
    });
    let bearings = hw.bearings_rad().to_vec();
    let mut builder = SweepBuilder::new(&bearings).unwrap();
    let standing = hw.scan().unwrap();
    let pose = world * robot.scanner_pose(&q0).unwrap().unwrap();
    builder
        .push_scan(&pose, &standing.ranges_m, &standing.intensities, None)
        .unwrap();
    let done = hw::motion::scan_line(
        &mut hw,
        &robot,
        &world,
        &LineMotion::new(&limits, &q0, &q1),
        0.1,
        &mut builder,
        &mut |_, _, _| true,
    )
    .unwrap();
    assert!(done.completed && done.scans > 10);
    drop(hw);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    std::fs::write(&path, bag.finish().unwrap()).unwrap();
    let read = record::bag::sweeps_from_bag(
        &path,
        &robot,
        &record::bag::ScanTopics::default(),
        record::bag::BadMessages::Refuse,
    )
    .unwrap();
    assert_eq!(read.scans, done.scans + 1);
    let placed: Vec<Point3> = read
        .sweeps
        .iter()
        .flat_map(|s| s.points().iter().map(|p| p.point))
        .collect();
    let looped = builder.finish().unwrap();
    assert_eq!(placed.len(), looped.len());
    let worst = placed
        .iter()
        .zip(looped.points())
        .map(|(a, b)| (a - b.point).norm())
        .fold(0.0, Real::max);
    assert!(worst < 1e-6, "{worst}");
}
