//! Damaged bags and bad messages (issue 48): each case the campaign found
//! is refused with a message naming the bag and where (the chunk's offset
//! and the topics it held, or the message's topic, index and log time), or,
//! with bad messages skipped, read on and counted.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

mod support;

use record::bag::msg::{Header, LaserScan, PointCloud2, Range, RosMessage, TfMessage};
use record::bag::{
    BadMessages, BagSweeps, ScanTopics, joint_state, laser_scan, range, sets_from_bag,
    static_frames, sweeps_from_bag, topics,
};
use serde::Serialize;
use std::marker::PhantomData;
use std::path::{Path, PathBuf};
use support::{EXPLORE, FOLLOW, Writer, explore_bag, follow_bag, joint_names, robot};

/// A message of `M`'s type cut after its first four bytes (a count of
/// five, or a stamp's seconds): it does not decode as `M`.
#[derive(Serialize)]
struct Cut<M>(u32, PhantomData<M>);

impl<M: RosMessage> RosMessage for Cut<M> {
    const TYPE: &'static str = M::TYPE;
    fn definition() -> String {
        M::definition()
    }
}

/// A LaserScan's fields up to its ranges, which it declares 2³¹ of.
#[derive(Serialize)]
struct HugeScan(Header, [f32; 7], u32);

impl RosMessage for HugeScan {
    const TYPE: &'static str = LaserScan::TYPE;
    fn definition() -> String {
        LaserScan::definition()
    }
}

fn cut<M>() -> Cut<M> {
    Cut(5, PhantomData)
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn sweeps(path: &Path, mode: BadMessages) -> Result<BagSweeps, record::bag::BagError> {
    sweeps_from_bag(path, &robot("denso-vm6083"), &ScanTopics::default(), mode)
}

/// The scan of the explore bag at `t` (in its scanner frame), changed by `f`.
fn scan_at(t: u64, f: impl Fn(&mut LaserScan)) -> LaserScan {
    let bearings: Vec<f64> = (0..12).map(|i| -0.6 + 0.1 * f64::from(i)).collect();
    let mut s = laser_scan(t, &bearings, &[Some(1.0); 12], &[1.0; 12], (0.1, 10.0), 0.1);
    record::bag::SCANNER_FRAME.clone_into(&mut s.header.frame_id);
    f(&mut s);
    s
}

const LATE: u64 = 4_900_000_000;

/// A bad-message case: its name, where the error must say it is, what it
/// must say, and what writes the bad message.
type Case<'a> = (&'a str, &'a str, &'a str, Box<dyn Fn(&mut Writer)>);

/// Each bad message of an explore bag (written after the good ones, on
/// `topic` as its 20th, 6th, 3rd... message): refused naming the bag, the
/// topic, the index and the log time, and what is wrong; skipped and
/// counted when asked, the rest mapped as the intact bag is.
#[test]
fn bad_messages_of_an_explore_bag_are_named_or_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let intact = sweeps(
        &write(dir.path(), EXPLORE, &explore_bag(&|_| {})),
        BadMessages::Refuse,
    )
    .unwrap();
    let joints = |q0: f64| {
        let names = joint_names(&robot("denso-vm6083"));
        joint_state(5_500_000_000, &names, &[q0, -0.96, 2.88, 0.0, -1.92, 0.0])
    };
    let tf_with = |w: f64| {
        let mut tf = static_frames(&robot("denso-vm6083"), &geom::Isometry3::identity());
        let q = &mut tf.transforms[0].transform.rotation;
        (q.x, q.y, q.z, q.w) = (0.0, 0.0, 0.0, w);
        tf
    };
    let cases: Vec<Case<'_>> = vec![
        (
            "cut_scan",
            "/scan message 20",
            "decoding a sensor_msgs/msg/LaserScan",
            Box::new(|w| w.write(topics::SCAN, LATE, &cut::<LaserScan>()).unwrap()),
        ),
        (
            "huge_scan",
            "/scan message 20",
            "decoding a sensor_msgs/msg/LaserScan",
            Box::new(|w| {
                let h = HugeScan(Header::new(LATE, "scanner"), [0.0; 7], 1 << 31);
                w.write(topics::SCAN, LATE, &h).unwrap();
            }),
        ),
        (
            "nan_bearings",
            "/scan message 20 (logged at 4.900000000 s)",
            "bearings not finite",
            Box::new(|w| {
                let s = scan_at(LATE, |s| s.angle_increment = f32::NAN);
                w.write(topics::SCAN, LATE, &s).unwrap();
            }),
        ),
        (
            "empty_scan",
            "/scan message 20",
            "without ranges",
            Box::new(|w| {
                let s = scan_at(LATE, |s| {
                    s.ranges.clear();
                    s.intensities.clear();
                });
                w.write(topics::SCAN, LATE, &s).unwrap();
            }),
        ),
        (
            "nan_intensity",
            "/scan message 20",
            "intensity 3 is NaN",
            Box::new(|w| {
                let s = scan_at(LATE, |s| s.intensities[3] = f32::NAN);
                w.write(topics::SCAN, LATE, &s).unwrap();
            }),
        ),
        (
            "nanosec",
            "/scan message 20",
            "nanosec must be below 10⁹",
            Box::new(|w| {
                let s = scan_at(LATE, |s| s.header.stamp.nanosec = 1_900_000_000);
                w.write(topics::SCAN, LATE, &s).unwrap();
            }),
        ),
        (
            "nan_joint",
            "/joint_states message 6 (logged at 5.500000000 s)",
            "joint `joint1` at NaN",
            Box::new(move |w| {
                w.write(topics::JOINT_STATES, 5_500_000_000, &joints(f64::NAN))
                    .unwrap();
            }),
        ),
        (
            "huge_joint",
            "/joint_states message 6",
            "joint `joint1` at 1e300, beyond its limits",
            Box::new(move |w| {
                w.write(topics::JOINT_STATES, 5_500_000_000, &joints(1e300))
                    .unwrap();
            }),
        ),
        (
            "nan_quaternion",
            "/tf_static message 1",
            "is not a unit quaternion",
            Box::new(move |w| w.write(topics::TF_STATIC, 1, &tf_with(f64::NAN)).unwrap()),
        ),
        (
            "zero_quaternion",
            "/tf_static message 1",
            "quaternion (0, 0, 0, 0) is not a unit quaternion",
            Box::new(move |w| w.write(topics::TF_STATIC, 1, &tf_with(0.0)).unwrap()),
        ),
        (
            "cut_tf_static",
            "/tf_static message 1",
            "decoding a tf2_msgs/msg/TFMessage",
            Box::new(|w| w.write(topics::TF_STATIC, 1, &cut::<TfMessage>()).unwrap()),
        ),
        (
            "cut_sweep",
            "/surveyor/sweep message 2",
            "decoding a sensor_msgs/msg/PointCloud2",
            Box::new(|w| {
                w.write(topics::SWEEP, LATE, &cut::<PointCloud2>()).unwrap();
            }),
        ),
    ];
    for (name, at, says, more) in cases {
        let file = format!("{name}.mcap");
        let path = write(dir.path(), &file, &explore_bag(&*more));
        let e = sweeps(&path, BadMessages::Refuse).unwrap_err().to_string();
        for part in [file.as_str(), at, says, "--skip-bad-messages"] {
            assert!(e.contains(part), "{name}: `{part}` not in {e}");
        }
        let read = sweeps(&path, BadMessages::Skip).unwrap();
        assert_eq!(read.skipped.messages, 1, "{name}");
        assert!(
            read.skipped.what[0].contains(at),
            "{name}: {:?}",
            read.skipped
        );
        assert_eq!(read.sweeps, intact.sweeps, "{name}");
    }
}

/// A follow bag's bad Range and `/tf` messages, a Range stamp past 10⁹ ns,
/// `/tf` missing (the range frames then reach a link, never `map`), and a
/// given topic that is not Range.
#[test]
fn bad_messages_of_a_follow_bag_are_named_or_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let sets = |path: &Path, topics_in: &[&str], mode: BadMessages| {
        let topics_in: Vec<String> = topics_in.iter().map(|s| (*s).to_owned()).collect();
        sets_from_bag(path, &topics_in, 1000, mode)
    };
    let intact = sets(
        &write(dir.path(), FOLLOW, &follow_bag(&|_| {})),
        &[],
        BadMessages::Refuse,
    )
    .unwrap();
    let late = 950_000_000;
    let cases: Vec<Case<'_>> = vec![
        (
            "cut_range",
            "/range/finder_1 message 10 (logged at 0.950000000 s)",
            "decoding a sensor_msgs/msg/Range",
            Box::new(move |w| {
                w.write(&topics::range_finder(1), late, &cut::<Range>())
                    .unwrap();
            }),
        ),
        (
            "cut_tf",
            "/tf message 10",
            "decoding a tf2_msgs/msg/TFMessage",
            Box::new(move |w| w.write(topics::TF, late, &cut::<TfMessage>()).unwrap()),
        ),
        (
            "range_nanosec",
            "/range/finder_0 message 10",
            "nanosec must be below 10⁹",
            Box::new(move |w| {
                let mut r = range(late, 0, 2.0, Some(0.5));
                r.header.stamp.nanosec = 1_500_000_000;
                w.write(&topics::range_finder(0), late, &r).unwrap();
            }),
        ),
    ];
    for (name, at, says, more) in cases {
        let file = format!("{name}.mcap");
        let path = write(dir.path(), &file, &follow_bag(&*more));
        let e = sets(&path, &[], BadMessages::Refuse)
            .err()
            .unwrap_or_else(|| panic!("{name}: read"))
            .to_string();
        for part in [file.as_str(), at, says] {
            assert!(e.contains(part), "{name}: `{part}` not in {e}");
        }
        let read = sets(&path, &[], BadMessages::Skip).unwrap();
        assert_eq!(read.skipped.messages, 1, "{name}");
        assert_eq!(read.sets, intact.sets, "{name}");
    }
    // Without /tf the range frames reach the links and stop there: no
    // readings placed "in their link frames as if those were the world".
    let point3 = robot("point3");
    let mut w = record::bag::BagWriter::new(std::io::Cursor::new(Vec::new())).unwrap();
    w.write(
        topics::TF_STATIC,
        0,
        &static_frames(&point3, &geom::Isometry3::identity()),
    )
    .unwrap();
    w.write(&topics::range_finder(0), 5, &range(5, 0, 2.0, Some(0.5)))
        .unwrap();
    let no_tf = write(dir.path(), "no_tf.mcap", &w.finish().unwrap().into_inner());
    let e = sets(&no_tf, &[], BadMessages::Refuse)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no_tf.mcap") && e.contains("which no transform places in `map`"),
        "{e}"
    );
    // A topic of another type, given as a Range topic.
    let path = dir.path().join(FOLLOW);
    let e = sets(&path, &["/tf"], BadMessages::Refuse)
        .unwrap_err()
        .to_string();
    assert!(e.contains("/tf is not `sensor_msgs/msg/Range`"), "{e}");
}

/// The records of an MCAP file: `(offset, opcode, body range)`.
fn records(bytes: &[u8]) -> Vec<(usize, u8, std::ops::Range<usize>)> {
    let mut out = Vec::new();
    let mut at = 8;
    while at + 9 <= bytes.len() {
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        out.push((at, bytes[at], at + 9..at + 9 + len));
        if bytes[at] == 0x02 {
            break;
        }
        at += 9 + len;
    }
    out
}

/// The campaign's panics and aborts: a Header record length of 2⁶⁴−1, a
/// chunk declaring 2⁶⁴−1 bytes uncompressed, and single bit flips across a
/// chunk's zstd data (which aborted with a huge allocation or panicked with
/// `capacity overflow`). Each is refused naming the offset; a damaged chunk
/// also names the topics it held, and with bad messages skipped its
/// messages are counted and the rest read.
#[test]
fn damaged_records_and_chunks_are_refused_by_offset() {
    let dir = tempfile::tempdir().unwrap();
    let good = explore_bag(&|_| {});
    let mut bytes = good.clone();
    bytes[9..17].copy_from_slice(&u64::MAX.to_le_bytes());
    let path = write(dir.path(), "header.mcap", &bytes);
    let e = sweeps(&path, BadMessages::Skip).unwrap_err().to_string();
    assert!(
        e.contains("header.mcap")
            && e.contains("offset 8: a record (opcode 0x01) of 18446744073709551615 bytes"),
        "{e}"
    );
    let chunks: Vec<_> = records(&good)
        .into_iter()
        .filter(|(_, op, _)| *op == 0x06)
        .collect();
    assert!(chunks.len() >= 3, "{}", chunks.len());
    let (offset, _, body) = chunks[1].clone();
    // Uncompressed size (after two times) set to 2⁶⁴−1.
    let mut bytes = good.clone();
    bytes[body.start + 16..body.start + 24].copy_from_slice(&u64::MAX.to_le_bytes());
    let path = write(dir.path(), "size.mcap", &bytes);
    let e = sweeps(&path, BadMessages::Refuse).unwrap_err().to_string();
    assert!(
        e.contains(&format!("the chunk at offset {offset} is damaged"))
            && e.contains("18446744073709551615 bytes uncompressed"),
        "{e}"
    );
    // Bit flips across the chunk's compressed data (after its 44-byte
    // header: times, sizes, CRC, "zstd", compressed size).
    let data = body.start + 44..body.end;
    let whole = sweeps(&write(dir.path(), "good.mcap", &good), BadMessages::Refuse).unwrap();
    for k in 0..16 {
        let at = data.start + k * (data.len() - 1) / 15;
        let mut bytes = good.clone();
        bytes[at] ^= 1 << (k % 8);
        let path = write(dir.path(), "flip.mcap", &bytes);
        let e = sweeps(&path, BadMessages::Refuse).unwrap_err().to_string();
        let read = sweeps(&path, BadMessages::Skip).unwrap();
        if e.contains("the data section's CRC") {
            // A flip the chunk's decompression does not see (in the zstd
            // frame's last bytes): its data are intact, the file's CRC not.
            assert_eq!(read.sweeps, whole.sweeps);
            assert_eq!(read.skipped.messages, 0);
            continue;
        }
        assert!(
            e.contains("flip.mcap")
                && e.contains(&format!("the chunk at offset {offset} is damaged"))
                && e.contains("on /scan"),
            "byte {at}: {e}"
        );
        assert!(read.skipped.messages > 0, "{:?}", read.skipped);
        assert!(read.skipped.what[0].contains(&format!("offset {offset}")));
        assert!(
            read.scans < whole.scans,
            "{} of {}",
            read.scans,
            whole.scans
        );
    }
}
