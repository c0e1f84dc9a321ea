//! A run's bag against what the hardware reported (issue 26): the range
//! readings of `run.mcap`, placed by its own frames
//! (`record::bag::sets_from_bag`, what `surveyor model --bag` reads), are
//! the sensor points the simulated rig gave the loop, logged independently
//! by `hw::script::Recorder`.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use hw::script::{Event, Recorder, Tap};
use hw::{Arm, RangeSensors};
use scenario::Scenario;
use sim::follow_job::{FollowRunOptions, SimFollow};

#[test]
fn range_readings_in_the_bag_are_the_rig_s_sensor_points() {
    for (scene, robot) in [("block1", "arm4"), ("cube", "point3")] {
        let options = FollowRunOptions {
            robot: Some(robot.into()),
            noise_sigma_m: Some(0.002),
            ..FollowRunOptions::default()
        };
        let mut setup =
            SimFollow::from_scenario(&Scenario::load(scene).unwrap(), &options).unwrap();
        let model = setup.rig.robot().clone();
        let start = setup.job.start_joints.clone();
        let mut bag = setup.rig.run_bag().unwrap();
        let clock = hw::clock::RobotClock::default();
        let timed = hw::clock::Timed::new(&mut setup.rig, setup.job.timing.clone(), clock.clone());
        let mut rec = Tap::with_sink(Recorder::new(timed, Vec::new()), |e: &Event| {
            scenario::job::bag_event(&mut bag, &clock, e);
        });
        // Wander around the start, reading at every pose.
        for k in 0..40 {
            let t = f64::from(k) * 0.05;
            let q: Vec<f64> = start
                .iter()
                .enumerate()
                .map(|(j, v)| v + 0.05 * (t + j as f64).sin())
                .collect();
            rec.move_to(&q).unwrap();
            rec.read_all().unwrap();
        }
        let (logged, _) = rec.into_parts();
        let (_, script) = logged.into_parts();
        let bytes = bag.finish().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run.mcap");
        std::fs::write(&path, bytes).unwrap();
        let read =
            record::bag::sets_from_bag(&path, &[], usize::MAX, record::bag::BadMessages::Refuse)
                .unwrap();
        assert_eq!(read.topics.len(), model.range_finders.len());
        let reported: Vec<Vec<sensor::SensorPoint>> = script
            .events
            .iter()
            .filter_map(|e| match e {
                Event::Read(r) => Some(r.iter().flatten().copied().collect::<Vec<_>>()),
                _ => None,
            })
            .filter(|r: &Vec<_>| !r.is_empty())
            .collect();
        assert!(reported.len() > 10, "{scene}: {} sets", reported.len());
        assert_eq!(read.sets.len(), reported.len(), "{scene}");
        let mut worst: f64 = 0.0;
        for (set, want) in read.sets.iter().zip(&reported) {
            assert_eq!(set.len(), want.len());
            for ((p, a), w) in set.points.iter().zip(&set.axes).zip(want) {
                worst = worst.max((p - w.point).norm());
                assert!((a.into_inner() - w.axis.into_inner()).norm() < 1e-9);
            }
        }
        // Ranges are 32-bit floats in sensor_msgs/Range: 0.3 m to ~2e-8 m.
        assert!(worst < 1e-6, "{scene}: {worst} m");
    }
}
