//! The traits themselves.

use crate::HwError;
use geom::Real;
use scene::MaterialId;
use sensor::SensorPoint;

/// A robot that reports its joints and moves.
pub trait Arm {
    /// Current joint values (radians / metres).
    fn joints(&self) -> Vec<Real>;
    /// Move to `q` and wait until there; errors leave the arm where it was.
    fn move_to(&mut self, q: &[Real]) -> Result<(), HwError>;
    /// The robot's own clock, nanoseconds, where it keeps one that the
    /// loop should be timed on (a robot over a link: its `/clock`, or the
    /// wall clock of real time); `None` (the default) for hardware timed
    /// by the model of [`crate::clock`] (a simulator in process).
    fn clock_ns(&self) -> Option<u64> {
        None
    }
}

/// One 2-D scan as a scanner reports it, in bearing order.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ScanReadings {
    /// Range per bearing, `None` without a return.
    pub ranges_m: Vec<Option<Real>>,
    /// Intensity per bearing (0 without a return).
    pub intensities: Vec<Real>,
    /// Ground truth a simulator can add: the material hit per bearing.
    pub truth_materials: Option<Vec<Option<MaterialId>>>,
}

impl ScanReadings {
    /// The readings of a scan simulated by `sensor::Scanner`, with the
    /// material each return hit.
    pub fn of_simulated(scan: &sensor::Scan) -> Self {
        Self {
            ranges_m: scan.returns.iter().map(|r| r.map(|r| r.range_m)).collect(),
            intensities: scan
                .returns
                .iter()
                .map(|r| r.map_or(0.0, |r| r.intensity))
                .collect(),
            truth_materials: Some(
                scan.returns
                    .iter()
                    .map(|r| r.and_then(|r| r.material))
                    .collect(),
            ),
        }
    }
}

impl ScanReadings {
    /// The readings as a ROS 2 scanner driver reports them: ranges and
    /// intensities in float32 (`sensor_msgs/LaserScan`). A simulated
    /// scanner reports so, and a run over ROS 2 sees what a run in process
    /// does.
    #[must_use]
    pub fn in_float32(mut self) -> Self {
        for r in self.ranges_m.iter_mut().flatten() {
            *r = sensor::float32(*r);
        }
        for i in &mut self.intensities {
            *i = sensor::float32(*i);
        }
        self
    }
}

/// A 2-D line scanner taking a scan at the robot's current pose.
pub trait LineScanner {
    /// Bearing of every slot, radians (scanner frame, A eq. 4.7).
    fn bearings_rad(&self) -> &[Real];
    /// Take one scan.
    fn scan(&mut self) -> Result<ScanReadings, HwError>;
    /// Restart the scanner's noise from `seed`. A loop calls it before each
    /// viewpoint's sweep, so a simulated scanner gives the same sweep when
    /// a run is resumed; real hardware has no seed and ignores it (the
    /// default).
    fn seed_noise(&mut self, seed: u64) {
        let _ = seed;
    }
    /// The scanner and its arm scanning while the arm moves
    /// ([`crate::motion`]), where the hardware can; `None` (the default)
    /// for hardware that scans standing only.
    fn moving(&mut self) -> Option<&mut dyn crate::motion::MovingScanner> {
        None
    }
    /// One scan taken while the arm went along `path` (its joints over
    /// time), beam `i` measured `start_s + i · time_increment_s` seconds
    /// into it, each from the scanner pose of its own moment: what a
    /// simulator serving a moving robot measures (`surveyor sim-robot`).
    /// `None` (the default) for a scanner that measures where the arm is.
    fn scan_along(
        &mut self,
        path: &[crate::motion::JointSample],
        start_s: Real,
        time_increment_s: Real,
    ) -> Option<Result<ScanReadings, HwError>> {
        let _ = (path, start_s, time_increment_s);
        None
    }
}

/// Single-point range finders mounted on the robot.
pub trait RangeSensors {
    /// One reading per mounted sensor at the current pose (`None`: nothing in range).
    fn read_all(&mut self) -> Result<Vec<Option<SensorPoint>>, HwError>;
}

// A loop that borrows hardware can hand the borrow to a wrapper (a
// recorder) that owns what it wraps.
impl<T: Arm + ?Sized> Arm for &mut T {
    fn joints(&self) -> Vec<Real> {
        (**self).joints()
    }

    fn move_to(&mut self, q: &[Real]) -> Result<(), HwError> {
        (**self).move_to(q)
    }

    fn clock_ns(&self) -> Option<u64> {
        (**self).clock_ns()
    }
}

impl<T: LineScanner + ?Sized> LineScanner for &mut T {
    fn bearings_rad(&self) -> &[Real] {
        (**self).bearings_rad()
    }

    fn scan(&mut self) -> Result<ScanReadings, HwError> {
        (**self).scan()
    }

    fn seed_noise(&mut self, seed: u64) {
        (**self).seed_noise(seed);
    }

    fn moving(&mut self) -> Option<&mut dyn crate::motion::MovingScanner> {
        (**self).moving()
    }

    fn scan_along(
        &mut self,
        path: &[crate::motion::JointSample],
        start_s: Real,
        time_increment_s: Real,
    ) -> Option<Result<ScanReadings, HwError>> {
        (**self).scan_along(path, start_s, time_increment_s)
    }
}

impl<T: RangeSensors + ?Sized> RangeSensors for &mut T {
    fn read_all(&mut self) -> Result<Vec<Option<SensorPoint>>, HwError> {
        (**self).read_all()
    }
}
