//! Small bags of both kinds a robot brings, for the bag tests.
#![allow(
    clippy::unwrap_used,
    dead_code,
    reason = "test helpers fail the test on any error; each test uses some"
)]

use record::bag::{
    BagWriter, SCANNER_FRAME, joint_state, laser_scan, link_frames, point_cloud, range,
    static_frames, topics,
};
use std::io::Cursor;

/// The explore bag's file name.
pub const EXPLORE: &str = "explore.mcap";
/// The follow bag's file name.
pub const FOLLOW: &str = "follow.mcap";

/// The writer the builders hand to `more`.
pub type Writer = BagWriter<Cursor<Vec<u8>>>;

/// A built-in robot.
pub fn robot(name: &str) -> robot::Robot {
    robot::builtin(name).unwrap()
}

/// Chunks of about this many bytes (uncompressed): several per bag.
const CHUNK_BYTES: u64 = 1500;

/// The robot's joint names, owned.
pub fn joint_names(robot: &robot::Robot) -> Vec<String> {
    robot
        .joint_names()
        .iter()
        .map(|s| (*s).to_owned())
        .collect()
}

/// A bag writer in chunks of [`CHUNK_BYTES`].
fn writer() -> Writer {
    BagWriter::with_chunk_size(Cursor::new(Vec::new()), Some(CHUNK_BYTES)).unwrap()
}

/// An explore run's bag: the arm moving through six joint states (0 to
/// 5 s), a scan of 12 bearings every 0.25 s between them, a sweep cloud
/// every 2 s; then what `more` writes.
pub fn explore_bag(more: &dyn Fn(&mut Writer)) -> Vec<u8> {
    let robot = robot("denso-vm6083");
    let names = joint_names(&robot);
    let mut w = writer();
    let base = geom::Isometry3::translation(0.5, 0.0, 0.0);
    w.write(topics::TF_STATIC, 0, &static_frames(&robot, &base))
        .unwrap();
    let bearings: Vec<f64> = (0..12).map(|i| -0.6 + 0.1 * f64::from(i)).collect();
    let second = 1_000_000_000;
    for k in 0..6u32 {
        let t = u64::from(k) * second;
        let q = [
            0.1 * f64::from(k),
            -0.96,
            2.88 - 0.05 * f64::from(k),
            0.0,
            -1.92,
            0.0,
        ];
        w.write(topics::JOINT_STATES, t, &joint_state(t, &names, &q))
            .unwrap();
        if k == 5 {
            break;
        }
        for s in 0..4u32 {
            let ts = t + u64::from(s) * second / 4;
            let ranges: Vec<Option<f64>> = (0..12)
                .map(|i| (i % 5 != 3).then(|| 1.0 + 0.05 * f64::from(i + s)))
                .collect();
            let intensities: Vec<f64> = (0..12).map(f64::from).collect();
            let mut scan = laser_scan(ts, &bearings, &ranges, &intensities, (0.1, 10.0), 0.1);
            SCANNER_FRAME.clone_into(&mut scan.header.frame_id);
            w.write(topics::SCAN, ts, &scan).unwrap();
        }
        if k % 2 == 1 {
            let tm = t + second - 1;
            w.write(topics::SWEEP, tm, &point_cloud(tm, [])).unwrap();
        }
    }
    more(&mut w);
    w.finish().unwrap().into_inner()
}

/// A follow run's bag: the point robot moving through ten joint states (0
/// to 0.9 s), its links on `/tf` with each, four range finders read at
/// each; then what `more` writes.
pub fn follow_bag(more: &dyn Fn(&mut Writer)) -> Vec<u8> {
    let robot = robot("point3");
    let names = joint_names(&robot);
    let mut w = writer();
    w.write(
        topics::TF_STATIC,
        0,
        &static_frames(&robot, &geom::Isometry3::identity()),
    )
    .unwrap();
    for k in 0..10u32 {
        let t = u64::from(k) * 100_000_000;
        let q: Vec<f64> = (0..robot.dof())
            .map(|j| 0.01 * f64::from(k) * (j as f64 + 1.0))
            .collect();
        w.write(topics::JOINT_STATES, t, &joint_state(t, &names, &q))
            .unwrap();
        w.write(topics::TF, t, &link_frames(t, &robot, &q)).unwrap();
        for j in 0..4 {
            let d = (j != 2).then(|| 0.5 + 0.01 * f64::from(k));
            w.write(&topics::range_finder(j), t, &range(t, j, 2.0, d))
                .unwrap();
        }
    }
    more(&mut w);
    w.finish().unwrap().into_inner()
}
