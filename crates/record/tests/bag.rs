//! Bags written and read back, a run's bag fed by hand, robots' bags as
//! input, and broken files.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use record::bag::msg::{JointState, LaserScan, MarkerArray, TfMessage};
use record::bag::{BagConfig, BagError, BagWriter, RunBag, read_bag, topics};
use std::io::Cursor;

fn joint_state(q: &[f64]) -> JointState {
    JointState {
        header: record::bag::msg::Header::new(1_500_000_000, ""),
        name: vec!["a".into(), "b".into()],
        position: q.to_vec(),
        ..JointState::default()
    }
}

#[test]
fn messages_come_back_as_written() {
    let mut w = BagWriter::new(Cursor::new(Vec::new())).unwrap();
    w.write("/joint_states", 5, &joint_state(&[0.25, -1.0]))
        .unwrap();
    w.write("/joint_states", 7, &joint_state(&[0.5, -1.5]))
        .unwrap();
    let scan = LaserScan {
        ranges: vec![1.0, f32::INFINITY],
        intensities: vec![3.0, 0.0],
        angle_min: -0.5,
        angle_max: 0.5,
        angle_increment: 1.0,
        ..LaserScan::default()
    };
    w.write("/scan", 9, &scan).unwrap();
    // One topic, one type.
    assert!(matches!(
        w.write("/scan", 10, &joint_state(&[0.0, 0.0])),
        Err(BagError::TopicType { .. })
    ));
    let bytes = w.finish().unwrap().into_inner();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("b.mcap");
    std::fs::write(&path, &bytes).unwrap();
    let all = read_bag(&path, &|_| true).unwrap();
    assert_eq!(all.len(), 3);
    assert_eq!(all[1].log_time_ns, 7);
    assert_eq!(all[1].type_name, "sensor_msgs/msg/JointState");
    assert_eq!(
        all[1].decode::<JointState>().unwrap(),
        joint_state(&[0.5, -1.5])
    );
    assert_eq!(all[2].decode::<LaserScan>().unwrap(), scan);
    // The wrong type is refused by name, not misread.
    assert!(matches!(
        all[2].decode::<JointState>(),
        Err(BagError::Decode { .. })
    ));
    let scans = read_bag(&path, &|t| t == "/scan").unwrap();
    assert_eq!(scans.len(), 1);
}

#[test]
fn a_joint_state_has_rosidl_s_cdr_layout() {
    // Hand-encoded: header (stamp 1 s 5e8 ns, frame "") then name[],
    // position[] (8-aligned), velocity[], effort[].
    let mut want: Vec<u8> = vec![0, 1, 0, 0];
    want.extend(1i32.to_le_bytes());
    want.extend(500_000_000u32.to_le_bytes());
    want.extend(1u32.to_le_bytes()); // frame_id: length 1 (the NUL)
    want.extend([0, 0, 0, 0]); // NUL + 3 bytes padding to 4
    want.extend(2u32.to_le_bytes()); // name: 2 strings
    want.extend(2u32.to_le_bytes());
    want.extend(b"a\0");
    want.extend([0, 0]); // pad
    want.extend(2u32.to_le_bytes());
    want.extend(b"b\0");
    want.extend([0, 0]); // pad: 36 bytes past the header
    want.extend(2u32.to_le_bytes()); // position: 2 doubles, at 40 (8-aligned)
    want.extend(0.25f64.to_le_bytes());
    want.extend((-1.0f64).to_le_bytes());
    want.extend(0u32.to_le_bytes());
    want.extend(0u32.to_le_bytes());
    assert_eq!(
        record::bag::encode(&joint_state(&[0.25, -1.0])).unwrap(),
        want
    );
}

#[test]
fn broken_files_get_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("none.mcap");
    let e = read_bag(&missing, &|_| true).unwrap_err().to_string();
    assert!(e.contains("none.mcap"), "{e}");
    let junk = dir.path().join("junk.mcap");
    std::fs::write(&junk, b"not a bag at all").unwrap();
    let e = read_bag(&junk, &|_| true).unwrap_err().to_string();
    assert!(e.contains("junk.mcap"), "{e}");
    let mut w = BagWriter::new(Cursor::new(Vec::new())).unwrap();
    for k in 0..200 {
        w.write("/joint_states", k, &joint_state(&[k as f64, 0.0]))
            .unwrap();
    }
    let bytes = w.finish().unwrap().into_inner();
    let cut = dir.path().join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = read_bag(&cut, &|_| true).unwrap_err().to_string();
    assert!(e.contains("cut.mcap"), "{e}");
    assert!(record::bag::decode::<JointState>(&[0, 1]).is_err());
    assert!(record::bag::decode::<JointState>(&[9, 9, 9, 9, 0, 0]).is_err());
}

/// The DENSO arm with its scanner, fed a move, a scan and a move back at
/// the stamps the robot clock gave them: a joint state and TF per move
/// (with the start, and where the second move began after the scan), and
/// one scan message with its scan time.
#[test]
fn a_run_bag_logs_moves_and_scans_at_their_stamps() {
    let robot = robot::builtin("denso-vm6083").unwrap();
    let q0 = vec![0.0, -0.96, 2.88, 0.0, -1.92, 0.0];
    let mut q1 = q0.clone();
    q1[4] += 0.5;
    let mut bag = RunBag::new(
        &robot,
        &geom::Isometry3::translation(1.0, 0.0, 0.0),
        &q0,
        &[-0.1, 0.0, 0.1],
        BagConfig::default(),
    )
    .unwrap();
    bag.moved(0, 2_000_000_000, &q1);
    bag.scanned(
        2_000_000_000,
        0.1,
        &[Some(1.0), None, Some(2.0)],
        &[1.0, 0.0, 2.0],
    );
    bag.moved(2_100_000_000, 4_100_000_000, &q0);
    bag.write(topics::DISCS, 3, &MarkerArray::default())
        .unwrap();
    let bytes = bag.finish().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("r.mcap");
    std::fs::write(&path, bytes).unwrap();
    let all = read_bag(&path, &|_| true).unwrap();
    let on = |t: &str| all.iter().filter(|m| m.topic == t).collect::<Vec<_>>();
    // The start; the first move's end; where the second began (after the
    // scan) and where it ended.
    let states: Vec<(u64, Vec<f64>)> = on(topics::JOINT_STATES)
        .iter()
        .map(|m| {
            let s = m.decode::<JointState>().unwrap();
            (s.header.stamp.to_nanos().unwrap(), s.position)
        })
        .collect();
    assert_eq!(
        states,
        vec![
            (0, q0.clone()),
            (2_000_000_000, q1.clone()),
            (2_100_000_000, q1.clone()),
            (4_100_000_000, q0.clone())
        ]
    );
    assert_eq!(on(topics::TF).len(), 4);
    let tf = on(topics::TF)[1].decode::<TfMessage>().unwrap();
    assert_eq!(
        tf.transforms[0].header.stamp.to_nanos(),
        Some(2_000_000_000)
    );
    assert_eq!(tf.transforms.len(), robot.joints.len());
    let scans = on(topics::SCAN);
    assert_eq!(scans.len(), 1);
    let s = scans[0].decode::<LaserScan>().unwrap();
    assert_eq!(s.ranges, vec![1.0, f32::INFINITY, 2.0]);
    assert!((s.angle_increment - 0.1).abs() < 1e-7);
    assert!((s.scan_time - 0.1).abs() < 1e-7);
    assert_eq!(s.header.stamp.to_nanos(), Some(2_000_000_000));
    assert_eq!(s.header.frame_id, record::bag::SCANNER_FRAME);
    let statics = on(topics::TF_STATIC)[0].decode::<TfMessage>().unwrap();
    assert_eq!(
        statics.transforms[0].header.frame_id,
        record::bag::ROOT_FRAME
    );
    assert_eq!(statics.transforms[0].transform.translation.x, 1.0);
}

/// The laser frame's rays are the scanner's: bearing θ along
/// `(cos θ, sin θ, 0)` in `scanner` is `(0, −sin θ, cos θ)` in our frame.
#[test]
fn the_laser_frame_turns_rays_onto_ours() {
    let r = record::bag::scanner_from_laser();
    for t in [-1.0f64, -0.3, 0.0, 0.7] {
        let ours = r * geom::Vector3::new(t.cos(), t.sin(), 0.0);
        assert!((ours - geom::Vector3::new(0.0, -t.sin(), t.cos())).norm() < 1e-12);
    }
}

/// A bag by hand: joint states at 0 s and 2 s, a scan at 1 s in the frame
/// of the scanner's link (ROS's laser convention). The scan is placed at
/// the joints halfway, by the robot's own forward kinematics; a bag with
/// time going backwards, without a joint of the robot, without scans, or
/// with scans in a frame not on the robot is refused by name.
#[test]
fn a_bag_s_scans_are_placed_at_interpolated_joints() {
    let robot = robot::builtin("denso-vm6083").unwrap();
    let link = robot.scanner.unwrap().link;
    let link_name = robot.links[link.0].name.clone();
    let names: Vec<String> = robot
        .joint_names()
        .iter()
        .map(ToString::to_string)
        .collect();
    let q0 = vec![0.0, -0.96, 2.88, 0.0, -1.92, 0.0];
    let q1 = vec![0.4, -0.9, 2.7, 0.2, -1.5, 0.3];
    let state = |t: u64, q: &[f64], names: &[String]| JointState {
        header: record::bag::msg::Header::new(t, ""),
        name: names.to_vec(),
        position: q.to_vec(),
        ..JointState::default()
    };
    let scan = |t: u64, frame: &str| LaserScan {
        header: record::bag::msg::Header::new(t, frame),
        angle_min: -0.5,
        angle_max: 0.5,
        angle_increment: 0.5,
        range_min: 0.1,
        range_max: 10.0,
        ranges: vec![1.0, f32::INFINITY, 2.5],
        intensities: vec![1.0, 0.0, 3.0],
        ..LaserScan::default()
    };
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, states: &[(u64, Vec<f64>, Vec<String>)], scans: &[(u64, &str)]| {
        let mut w = BagWriter::new(Cursor::new(Vec::new())).unwrap();
        for (t, q, n) in states {
            w.write(topics::JOINT_STATES, *t, &state(*t, q, n)).unwrap();
        }
        for (t, f) in scans {
            w.write(topics::SCAN, *t, &scan(*t, f)).unwrap();
        }
        let path = dir.path().join(name);
        std::fs::write(&path, w.finish().unwrap().into_inner()).unwrap();
        path
    };
    let good = write(
        "good.mcap",
        &[
            (0, q0.clone(), names.clone()),
            (2_000_000_000, q1.clone(), names.clone()),
        ],
        &[
            (1_000_000_000, link_name.as_str()),
            (3_000_000_000, link_name.as_str()),
        ],
    );
    let defaults = record::bag::ScanTopics::default();
    let got =
        record::bag::sweeps_from_bag(&good, &robot, &defaults, record::bag::BadMessages::Refuse)
            .unwrap();
    assert_eq!((got.scans, got.unplaced, got.sweeps.len()), (1, 1, 1));
    assert!(!got.base_from_bag);
    let mid: Vec<f64> = q0.iter().zip(&q1).map(|(a, b)| 0.5 * (a + b)).collect();
    let world_from_link = robot.forward_kinematics(&mid).unwrap()[link.0];
    let points = got.sweeps[0].points();
    assert_eq!(points.len(), 2);
    for (p, (r, t)) in points.iter().zip([(1.0f64, -0.5f64), (2.5, 0.5)]) {
        let want = world_from_link * geom::Point3::new(r * t.cos(), r * t.sin(), 0.0);
        assert!((p.point - want).norm() < 1e-6, "{:?} vs {want:?}", p.point);
        assert!((p.origin - world_from_link * geom::Point3::origin()).norm() < 1e-9);
    }
    assert_eq!(points[1].intensity, 3.0);
    let refused = |path: &std::path::Path, topics: &record::bag::ScanTopics, says: &str| {
        let e =
            record::bag::sweeps_from_bag(path, &robot, topics, record::bag::BadMessages::Refuse)
                .unwrap_err()
                .to_string();
        assert!(
            e.contains(says) && e.contains(path.to_str().unwrap()),
            "{e}"
        );
    };
    let backwards = write(
        "backwards.mcap",
        &[
            (2_000_000_000, q1.clone(), names.clone()),
            (1_000_000_000, q0.clone(), names.clone()),
        ],
        &[(1_500_000_000, link_name.as_str())],
    );
    refused(&backwards, &defaults, "time goes backwards");
    let short = write(
        "short.mcap",
        &[(0, q0[..5].to_vec(), names[..5].to_vec())],
        &[(0, link_name.as_str())],
    );
    refused(&short, &defaults, "has no joint `joint6`");
    let no_scans = write("no_scans.mcap", &[(0, q0.clone(), names.clone())], &[]);
    refused(
        &no_scans,
        &defaults,
        "no `sensor_msgs/msg/LaserScan` on /scan",
    );
    let elsewhere = write(
        "elsewhere.mcap",
        &[(0, q0.clone(), names.clone())],
        &[(0, "camera")],
    );
    refused(&elsewhere, &defaults, "frame `camera`");
    // The link given by name places them anyway.
    let given = record::bag::ScanTopics {
        scanner_link: Some(link_name.clone()),
        ..record::bag::ScanTopics::default()
    };
    assert_eq!(
        record::bag::sweeps_from_bag(&elsewhere, &robot, &given, record::bag::BadMessages::Refuse)
            .unwrap()
            .scans,
        1
    );
    let wrong = record::bag::ScanTopics {
        scanner_link: Some("nowhere".into()),
        ..record::bag::ScanTopics::default()
    };
    refused(&elsewhere, &wrong, "nowhere");
}

#[test]
fn a_run_bag_refuses_a_range_slack_it_cannot_state() {
    let robot = robot::builtin("point3").unwrap();
    for slack in [-1.0, f64::NAN] {
        let config = BagConfig {
            finder_range_slack_m: slack,
            ..BagConfig::default()
        };
        let e = RunBag::new(&robot, &geom::Isometry3::identity(), &[0.0; 3], &[], config)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bag configuration") && e.contains("finder_range_slack_m"),
            "{e}"
        );
    }
}
