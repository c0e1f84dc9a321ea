//! [`RunBag`]: a run's bag, written as the hardware acts. A loop's
//! hardware is tapped (`hw::script::Tap`) and each event handed here:
//! every motion becomes a `sensor_msgs/JointState` on `/joint_states` and
//! the robot's link frames on `/tf` where it ends (and where it began, when
//! sensing took time since the last state, so that states interpolated to a
//! reading's stamp give the pose it was taken at); every scan a
//! `sensor_msgs/LaserScan` on `/scan`; every reading of the range finders a
//! `sensor_msgs/Range` per finder. Every event comes with its stamp on the
//! robot clock (`hw::clock::RobotClock`, which times the hardware the
//! recorder taps), so a simulated run's bag is the same for the same seed.

use super::file::BagWriter;
use super::msg::{
    Header, JointState, LaserScan, PointCloud2, PointField, Range, TfMessage, Transform,
    TransformStamped,
};
use super::{BagError, topics};
use geom::{Isometry3, Real};
use robot::Robot;
use sensor::SweepPoint;
use std::io::Cursor;

/// The frame everything is placed in (the scenario's world frame).
pub const ROOT_FRAME: &str = "map";
/// The 2-D scanner's frame in ROS's laser convention: rays in its x–y
/// plane, bearing 0 along x.
pub const SCANNER_FRAME: &str = "scanner";

/// How a [`RunBag`] describes its sensors.
#[derive(Clone, Debug, PartialEq)]
pub struct BagConfig {
    /// Shortest and longest range the scanner reports, metres.
    pub scan_range_m: (Real, Real),
    /// How far past its nominal range a range finder may report, metres:
    /// added to each `Range.max_range`, so that a reading the hardware gave
    /// is never outside the range its message states (a simulated finder
    /// with range noise σ reports up to its range plus the noise: 10σ).
    pub finder_range_slack_m: Real,
}

impl Default for BagConfig {
    fn default() -> Self {
        Self {
            scan_range_m: (0.02, 5.6),
            finder_range_slack_m: 0.0,
        }
    }
}

/// A run's bag being written, in memory (see the module docs). A failure
/// to record never stops the run: the first one is kept and returned by
/// [`RunBag::finish`].
pub struct RunBag {
    robot: Robot,
    config: BagConfig,
    bag: BagWriter<Cursor<Vec<u8>>>,
    joint_names: Vec<String>,
    /// Where the arm is.
    q: Vec<Real>,
    /// Bearings of the scanner's rays, radians.
    bearings: Vec<Real>,
    /// Stamp of the last joint state written.
    last_state_ns: u64,
    error: Option<BagError>,
}

impl std::fmt::Debug for RunBag {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RunBag")
            .field("bag", &self.bag)
            .field("last_state_ns", &self.last_state_ns)
            .finish_non_exhaustive()
    }
}

impl RunBag {
    /// The bag of `robot`, placed at `world_from_base`, starting at joints
    /// `q` with a scanner of `bearings` (empty without one): the static
    /// frames on `/tf_static`, then the joints where they stand.
    pub fn new(
        robot: &Robot,
        world_from_base: &Isometry3,
        q: &[Real],
        bearings: &[Real],
        config: BagConfig,
    ) -> Result<Self, BagError> {
        let slack = config.finder_range_slack_m;
        if !(slack.is_finite() && slack >= 0.0) {
            return Err(BagError::Config(format!(
                "finder_range_slack_m = {slack}: expected a finite value, at least 0"
            )));
        }
        let mut bag = Self {
            robot: robot.clone(),
            config,
            bag: BagWriter::new(Cursor::new(Vec::new()))?,
            joint_names: robot.joint_names().iter().map(|&s| s.to_owned()).collect(),
            q: q.to_vec(),
            bearings: bearings.to_vec(),
            last_state_ns: 0,
            error: None,
        };
        bag.write_static(world_from_base)?;
        bag.write_joints(0, q)?;
        Ok(bag)
    }

    /// Keep the first failure.
    fn keep(&mut self, result: Result<(), BagError>) {
        if let Err(e) = result
            && self.error.is_none()
        {
            self.error = Some(e);
        }
    }

    /// The arm moved from `start_ns` to `end_ns` and reports `reached`:
    /// the joints where it stood at the start (when time passed since the
    /// last state written), then where it ended.
    pub fn moved(&mut self, start_ns: u64, end_ns: u64, reached: &[Real]) {
        if start_ns > self.last_state_ns {
            let from = self.q.clone();
            let r = self.write_joints(start_ns, &from);
            self.keep(r);
        }
        self.q = reached.to_vec();
        let r = self.write_joints(end_ns.max(start_ns), reached);
        self.keep(r);
    }

    /// A scan began at `start_ns` and took `scan_time_s`: ranges (`None`:
    /// no return) and intensities per bearing.
    pub fn scanned(
        &mut self,
        start_ns: u64,
        scan_time_s: Real,
        ranges_m: &[Option<Real>],
        intensities: &[Real],
    ) {
        let msg = laser_scan(
            start_ns,
            &self.bearings,
            ranges_m,
            intensities,
            self.config.scan_range_m,
            scan_time_s,
        );
        let r = self.bag.write(topics::SCAN, start_ns, &msg);
        self.keep(r);
    }

    /// The arm, moving, reported joints `q` at `stamp_ns` (a state at or
    /// before the last one written is dropped: a moving scan's states
    /// overlap the next one's).
    pub fn passed(&mut self, stamp_ns: u64, q: &[Real]) {
        if stamp_ns > self.last_state_ns {
            self.q = q.to_vec();
            let r = self.write_joints(stamp_ns, q);
            self.keep(r);
        }
    }

    /// A continuous motion ended at `end_ns` with the arm at rest at `q`
    /// (its last state, unless a scan's states reach past it).
    pub fn rested(&mut self, end_ns: u64, q: &[Real]) {
        self.passed(end_ns, q);
        self.q = q.to_vec();
    }

    /// A scan taken while the arm moved began at `start_ns` and took
    /// `scan_time_s`, beam `i` measured `i · time_increment_s` after the
    /// first (`LaserScan.time_increment`); the arm's states around it come
    /// through [`RunBag::passed`].
    pub fn scanned_moving(
        &mut self,
        start_ns: u64,
        (scan_time_s, time_increment_s): (Real, Real),
        ranges_m: &[Option<Real>],
        intensities: &[Real],
    ) {
        let mut msg = laser_scan(
            start_ns,
            &self.bearings,
            ranges_m,
            intensities,
            self.config.scan_range_m,
            scan_time_s,
        );
        msg.time_increment = time_increment_s as f32;
        let r = self.bag.write(topics::SCAN, start_ns, &msg);
        self.keep(r);
    }

    /// Every range finder was read at `stamp_ns`: the distance per finder
    /// (`None`: nothing in range).
    pub fn read(&mut self, stamp_ns: u64, distances_m: &[Option<Real>]) {
        for (k, reading) in distances_m.iter().enumerate() {
            let max = self
                .robot
                .range_finders
                .get(k)
                .map_or(0.0, |f| f.max_range_m + self.config.finder_range_slack_m);
            let r = self.bag.write(
                &topics::range_finder(k),
                stamp_ns,
                &range(stamp_ns, k, max, *reading),
            );
            self.keep(r);
        }
    }

    /// `/tf_static`: [`static_frames`].
    fn write_static(&mut self, world_from_base: &Isometry3) -> Result<(), BagError> {
        self.bag.write(
            topics::TF_STATIC,
            0,
            &static_frames(&self.robot, world_from_base),
        )
    }

    /// `/joint_states` and `/tf` at `q`, stamped `now`.
    fn write_joints(&mut self, now: u64, q: &[Real]) -> Result<(), BagError> {
        self.last_state_ns = now;
        self.bag.write(
            topics::JOINT_STATES,
            now,
            &joint_state(now, &self.joint_names, q),
        )?;
        self.bag
            .write(topics::TF, now, &link_frames(now, &self.robot, q))
    }

    /// Add a sweep's points as a `sensor_msgs/PointCloud2` on
    /// [`topics::SWEEP`] (world frame; `x`, `y`, `z`, `intensity` as
    /// 32-bit floats), stamped `stamp_ns`.
    pub fn sweep<'a>(
        &mut self,
        stamp_ns: u64,
        points: impl IntoIterator<Item = &'a SweepPoint>,
    ) -> Result<(), BagError> {
        self.bag
            .write(topics::SWEEP, stamp_ns, &point_cloud(stamp_ns, points))
    }

    /// Write `msg` on `topic` at `stamp_ns` (markers and the like).
    pub fn write<M: super::msg::RosMessage>(
        &mut self,
        topic: &str,
        stamp_ns: u64,
        msg: &M,
    ) -> Result<(), BagError> {
        self.bag.write(topic, stamp_ns, msg)
    }

    /// The finished bag's bytes, or the first failure to record.
    pub fn finish(self) -> Result<Vec<u8>, BagError> {
        if let Some(e) = self.error {
            return Err(e);
        }
        Ok(self.bag.finish()?.into_inner())
    }
}

/// The frames that do not move (`/tf_static`, stamped 0): `robot`'s base
/// at `world_from_base` in [`ROOT_FRAME`], its scanner's [`SCANNER_FRAME`]
/// and each range finder's [`range_frame`] (sensing along x) on their
/// links.
pub fn static_frames(robot: &Robot, world_from_base: &Isometry3) -> TfMessage {
    let base = robot.links.first().map_or("base_link", |l| &l.name);
    let mut transforms = vec![stamped(0, ROOT_FRAME, base, world_from_base)];
    if let Some(mount) = robot.scanner
        && let Some(link) = robot.links.get(mount.link.0)
    {
        let laser = mount.link_from_scanner * scanner_from_laser();
        transforms.push(stamped(0, &link.name, SCANNER_FRAME, &laser));
    }
    for (k, finder) in robot.range_finders.iter().enumerate() {
        if let Some(link) = robot.links.get(finder.link.0) {
            // ROS's range frame measures along its x axis.
            let turn = turn_onto(&geom::Vector3::x_axis(), &finder.axis);
            let pose = Isometry3::from_parts(finder.origin.coords.into(), turn);
            transforms.push(stamped(0, &link.name, &range_frame(k), &pose));
        }
    }
    TfMessage { transforms }
}

/// The shortest rotation taking `from` onto `to` (opposite: half a turn
/// about an axis square to `from`).
pub(super) fn turn_onto(
    from: &geom::UnitVector3,
    to: &geom::UnitVector3,
) -> nalgebra::UnitQuaternion<Real> {
    nalgebra::UnitQuaternion::rotation_between(from, to).unwrap_or_else(|| {
        let square = from.cross(&geom::Vector3::x());
        let square = if square.norm() > 0.5 {
            square
        } else {
            from.cross(&geom::Vector3::y())
        };
        nalgebra::UnitQuaternion::from_axis_angle(
            &geom::UnitVector3::new_normalize(square),
            std::f64::consts::PI,
        )
    })
}

/// A `sensor_msgs/JointState` of the joints `names` at `q`.
pub fn joint_state(stamp_ns: u64, names: &[String], q: &[Real]) -> JointState {
    JointState {
        header: Header::new(stamp_ns, ""),
        name: names.to_vec(),
        position: q.to_vec(),
        velocity: Vec::new(),
        effort: Vec::new(),
    }
}

/// `/tf` of `robot` at `q`: each joint's `parent_from_child`, parent link
/// to child link.
pub fn link_frames(stamp_ns: u64, robot: &Robot, q: &[Real]) -> TfMessage {
    let mut values = q.iter();
    let mut transforms = Vec::with_capacity(robot.joints.len());
    for (k, joint) in robot.joints.iter().enumerate() {
        let value = if joint.is_actuated() {
            values.next().copied().unwrap_or(0.0)
        } else {
            0.0
        };
        let (Some(parent), Some(child)) = (robot.links.get(k), robot.links.get(k + 1)) else {
            continue;
        };
        transforms.push(stamped(
            stamp_ns,
            &parent.name,
            &child.name,
            &joint.parent_from_child(value),
        ));
    }
    TfMessage { transforms }
}

/// A `sensor_msgs/LaserScan` in [`SCANNER_FRAME`]: rays at evenly spaced
/// `bearings` (radians), `+inf` where there is no return, the scanner's
/// `(shortest, longest)` range and its period.
pub fn laser_scan(
    stamp_ns: u64,
    bearings: &[Real],
    ranges_m: &[Option<Real>],
    intensities: &[Real],
    range_m: (Real, Real),
    period_s: Real,
) -> LaserScan {
    let n = bearings.len();
    let first = bearings.first().copied().unwrap_or(0.0);
    let last = bearings.last().copied().unwrap_or(0.0);
    let increment = if n > 1 {
        (last - first) / (n - 1) as Real
    } else {
        0.0
    };
    LaserScan {
        header: Header::new(stamp_ns, SCANNER_FRAME),
        angle_min: first as f32,
        angle_max: last as f32,
        angle_increment: increment as f32,
        time_increment: 0.0,
        scan_time: period_s as f32,
        range_min: range_m.0 as f32,
        range_max: range_m.1 as f32,
        ranges: ranges_m
            .iter()
            .map(|r| r.map_or(f32::INFINITY, |r| r as f32))
            .collect(),
        intensities: intensities.iter().map(|&i| i as f32).collect(),
    }
}

/// The rays of a `LaserScan`: bearings (radians), ranges (`None` when not
/// finite or outside `[range_min, range_max]`, REP 117) and intensities
/// (zeros when the scan has none).
pub fn scan_rays(scan: &LaserScan) -> (Vec<Real>, Vec<Option<Real>>, Vec<Real>) {
    let n = scan.ranges.len();
    let bearings = (0..n)
        .map(|i| Real::from(scan.angle_min) + i as Real * Real::from(scan.angle_increment))
        .collect();
    let (lo, hi) = (Real::from(scan.range_min), Real::from(scan.range_max));
    let ranges = scan
        .ranges
        .iter()
        .map(|&r| {
            let r = Real::from(r);
            (r.is_finite() && r >= lo && r <= hi).then_some(r)
        })
        .collect();
    let intensities = if scan.intensities.len() == n {
        scan.intensities.iter().map(|&i| Real::from(i)).collect()
    } else {
        vec![0.0; n]
    };
    (bearings, ranges, intensities)
}

/// A `sensor_msgs/Range` of range finder `k` (in [`range_frame`]`(k)`):
/// `distance` or `+inf` for nothing in range, up to `max_range_m`.
pub fn range(stamp_ns: u64, k: usize, max_range_m: Real, distance: Option<Real>) -> Range {
    Range {
        header: Header::new(stamp_ns, &range_frame(k)),
        radiation_type: Range::INFRARED,
        field_of_view: 0.0,
        min_range: 0.0,
        max_range: max_range_m as f32,
        range: distance.map_or(f32::INFINITY, |d| d as f32),
    }
}

/// The frame of range finder `k` (its x axis is the sensing axis).
pub fn range_frame(k: usize) -> String {
    format!("range_finder_{k}")
}

/// `parent_from_child` stamped.
fn stamped(stamp_ns: u64, parent: &str, child: &str, iso: &Isometry3) -> TransformStamped {
    TransformStamped {
        header: Header::new(stamp_ns, parent),
        child_frame_id: child.to_owned(),
        transform: Transform::from(iso),
    }
}

/// Our scanner frame (A eq. 3.10: rays `(0, −sin θ, cos θ)`) from ROS's
/// laser frame (rays `(cos θ, sin θ, 0)`): the laser's x is our z, its y
/// our −y, its z our x.
pub fn scanner_from_laser() -> Isometry3 {
    let m = geom::Matrix3::new(0.0, 0.0, 1.0, 0.0, -1.0, 0.0, 1.0, 0.0, 0.0);
    let r = nalgebra::Rotation3::from_matrix_unchecked(m);
    Isometry3::from_parts(nalgebra::Translation3::identity(), r.into())
}

/// A `sensor_msgs/PointCloud2` of `points` in the world frame.
pub fn point_cloud<'a>(
    stamp_ns: u64,
    points: impl IntoIterator<Item = &'a SweepPoint>,
) -> PointCloud2 {
    const STEP: u32 = 16;
    let field = |name: &str, offset: u32| PointField {
        name: name.to_owned(),
        offset,
        datatype: PointField::FLOAT32,
        count: 1,
    };
    let mut data = Vec::new();
    for p in points {
        for v in [p.point.x, p.point.y, p.point.z, p.intensity] {
            data.extend_from_slice(&(v as f32).to_le_bytes());
        }
    }
    let width = u32::try_from(data.len() / STEP as usize).unwrap_or(u32::MAX);
    PointCloud2 {
        header: Header::new(stamp_ns, ROOT_FRAME),
        height: 1,
        width,
        fields: vec![
            field("x", 0),
            field("y", 4),
            field("z", 8),
            field("intensity", 12),
        ],
        is_bigendian: false,
        point_step: STEP,
        row_step: width.saturating_mul(STEP),
        data,
        is_dense: true,
    }
}

#[cfg(test)]
mod tests {
    use super::turn_onto;
    use geom::{UnitVector3, Vector3};

    #[test]
    fn a_turn_takes_one_direction_onto_another_even_its_opposite() {
        let dirs = [
            Vector3::x(),
            -Vector3::x(),
            Vector3::z(),
            -Vector3::z(),
            Vector3::new(0.3, -0.4, 0.8),
        ];
        for a in dirs {
            for b in dirs {
                let (a, b) = (UnitVector3::new_normalize(a), UnitVector3::new_normalize(b));
                let r = turn_onto(&a, &b);
                assert!(
                    (r * a.into_inner() - b.into_inner()).norm() < 1e-12,
                    "{a:?} → {b:?}"
                );
            }
        }
    }
}
