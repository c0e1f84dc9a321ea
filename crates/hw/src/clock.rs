//! The robot clock (SPEC §3.9, §6): how long a real arm would take to do
//! what a loop asks, and what the time went on.
//!
//! [`Timed`] puts any hardware on a [`RobotClock`]: each motion takes its
//! straight-line profile within the joints' velocity and acceleration
//! limits ([`robot::timing::MotionLimits`]) and a settling allowance once
//! the arm has moved, each scan the scanner's `scan_time`, each reading of
//! the range finders their period. The loop says what the robot is doing
//! ([`RobotClock::set_activity`]) and how long it stood still deciding
//! ([`RobotClock::stand`]), so the time splits as `run.json`'s
//! `robot_time_s` does. A recorder tapping the timed hardware
//! (`record::bag::RunBag`) stamps each event from the same clock
//! ([`RobotClock::last_interval`]).
//!
//! ```
//! use hw::clock::{Activity, RobotClock, RobotTiming, Timed};
//! use hw::script::{Event, Replay, Script};
//! use hw::Arm;
//! use robot::timing::MotionLimits;
//!
//! let script = Script {
//!     start_joints: vec![0.0, 0.0],
//!     bearings_rad: vec![],
//!     events: vec![Event::Moved { goal: vec![2.0, 0.0], reached: vec![2.0, 0.0] }],
//! };
//! let timing = RobotTiming {
//!     limits: MotionLimits::uniform(2, 1.0, 2.0),
//!     settle_s: 0.05,
//!     scan_time_s: 0.1,
//!     reading_period_s: 0.01,
//! };
//! let clock = RobotClock::default();
//! let mut arm = Timed::new(Replay::new(script), timing, clock.clone());
//! clock.set_activity(Activity::Moving);
//! arm.move_to(&[2.0, 0.0])?;
//! // 2 rad at 1 rad/s and 2 rad/s²: 2.5 s, then 0.05 s to settle.
//! assert_eq!(clock.now_ns(), 2_550_000_000);
//! assert_eq!(clock.last_interval(), (0, 2_500_000_000));
//! clock.stand(Activity::Deciding, 1.0);
//! assert!((clock.spent().moving_s - 2.55).abs() < 1e-9);
//! assert!((clock.spent().total_s() - 3.55).abs() < 1e-9);
//! # Ok::<(), hw::HwError>(())
//! ```

use crate::motion::{LineMotion, MovingScan, MovingScanner};
use crate::{Arm, HwError, LineScanner, RangeSensors, ScanReadings};
use geom::Real;
use robot::timing::MotionLimits;
pub use robot::timing::RobotTime;
use sensor::SensorPoint;
use std::sync::{Arc, Mutex, PoisonError};

/// What the robot is doing while its clock runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Activity {
    /// Moving with the scanner taking scans on the way (a transit that
    /// scans).
    MovingWhileScanning,
    /// Moving without scanning (a transit, or returning after a sweep).
    #[default]
    Moving,
    /// Sweeping the scanner at a viewpoint: the tilt's motions and its scans.
    StandingToSweep,
    /// Standing still while the loop integrates what it measured and
    /// decides where to go.
    Deciding,
}

/// The figures a robot's time is counted with.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotTiming {
    /// Velocity and acceleration limits of every joint.
    pub limits: MotionLimits,
    /// Seconds an arm takes to settle at the end of each motion (the
    /// MuJoCo UR5 of issue 46 ran each stop 14–23 ms past its plan).
    pub settle_s: Real,
    /// Seconds one scan takes (`sensor_msgs/LaserScan.scan_time`; the
    /// URG-04LX of A§5.1: 0.1 s).
    pub scan_time_s: Real,
    /// Seconds one reading of every range finder takes.
    pub reading_period_s: Real,
}

/// Seconds one reading of every range finder takes, where nothing states
/// it (a single-point triangulation or time-of-flight finder answers within
/// milliseconds; Pudney's sensors were simulated).
pub const DEFAULT_READING_PERIOD_S: Real = 0.01;
/// Default settling allowance per stop, seconds.
pub const DEFAULT_SETTLE_S: Real = 0.05;
/// The longest settling allowance, scan time or reading period a robot
/// may state, seconds.
pub const MAX_PERIOD_S: Real = 60.0;

impl RobotTiming {
    /// `robot`'s limits ([`MotionLimits::of`]) with the default settling
    /// allowance, a scanner of `scan_time_s` and range finders read every
    /// `reading_period_s`.
    pub fn of(robot: &robot::Robot, scan_time_s: Real, reading_period_s: Real) -> Self {
        Self {
            limits: MotionLimits::of(robot),
            settle_s: DEFAULT_SETTLE_S,
            scan_time_s,
            reading_period_s,
        }
    }

    /// An error unless the limits fit a `dof`-joint arm and every period
    /// is finite, at least 0 and at most [`MAX_PERIOD_S`].
    pub fn check(&self, dof: usize) -> Result<(), String> {
        self.limits.check(dof)?;
        for (name, v) in [
            ("settle_s", self.settle_s),
            ("scan_time_s", self.scan_time_s),
            ("reading_period_s", self.reading_period_s),
        ] {
            if !(v.is_finite() && (0.0..=MAX_PERIOD_S).contains(&v)) {
                return Err(format!(
                    "{name} = {v}: expected seconds from 0 to {MAX_PERIOD_S}"
                ));
            }
        }
        Ok(())
    }

    /// Seconds the motion `from` → `to` takes, settling included (none
    /// when the arm does not move).
    pub fn motion_s(&self, from: &[Real], to: &[Real]) -> Real {
        let d = self.limits.duration_s(from, to);
        if d > 0.0 { d + self.settle_s } else { 0.0 }
    }
}

#[derive(Debug, Default)]
struct ClockState {
    now_ns: u64,
    activity: Activity,
    /// Nanoseconds per activity, in [`Activity`]'s order.
    spent_ns: [u64; 4],
    last: (u64, u64),
}

/// The robot clock at one moment ([`RobotClock::mark`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClockMark([u64; 4]);

/// A shared robot clock: every handle sees and advances the same time.
#[derive(Clone, Debug, Default)]
pub struct RobotClock(Arc<Mutex<ClockState>>);

fn ns(seconds: Real) -> u64 {
    (seconds.max(0.0) * 1e9).round() as u64
}

fn index(a: Activity) -> usize {
    match a {
        Activity::MovingWhileScanning => 0,
        Activity::Moving => 1,
        Activity::StandingToSweep => 2,
        Activity::Deciding => 3,
    }
}

impl RobotClock {
    fn with<T>(&self, f: impl FnOnce(&mut ClockState) -> T) -> T {
        f(&mut self.0.lock().unwrap_or_else(PoisonError::into_inner))
    }

    /// Nanoseconds since the clock started.
    pub fn now_ns(&self) -> u64 {
        self.with(|s| s.now_ns)
    }

    /// Seconds since the clock started.
    pub fn now_s(&self) -> Real {
        self.now_ns() as Real * 1e-9
    }

    /// Count what follows as `activity`; returns what was counted before.
    pub fn set_activity(&self, activity: Activity) -> Activity {
        self.with(|s| std::mem::replace(&mut s.activity, activity))
    }

    /// Let `seconds` pass on the current activity; returns when they
    /// began and ended, nanoseconds.
    pub fn pass(&self, seconds: Real) -> (u64, u64) {
        self.with(|s| {
            let start = s.now_ns;
            let d = ns(seconds);
            s.now_ns += d;
            s.spent_ns[index(s.activity)] += d;
            s.last = (start, s.now_ns);
            s.last
        })
    }

    /// Let the clock run on the current activity until `t_ns` (nothing
    /// when it is there already); the event's interval is when it began
    /// and `t_ns`.
    fn pass_until(&self, began_ns: u64, t_ns: u64) {
        self.with(|s| {
            let d = t_ns.saturating_sub(s.now_ns);
            s.now_ns += d;
            s.spent_ns[index(s.activity)] += d;
            s.last = (began_ns, t_ns);
        });
    }

    /// The robot stands still for `seconds` doing `activity` (the current
    /// activity is kept for what follows).
    pub fn stand(&self, activity: Activity, seconds: Real) {
        let before = self.set_activity(activity);
        self.pass(seconds);
        self.set_activity(before);
    }

    /// When the last event began and ended, nanoseconds (a motion's end
    /// is before its settling allowance).
    pub fn last_interval(&self) -> (u64, u64) {
        self.with(|s| s.last)
    }

    /// Robot time so far, per activity.
    pub fn spent(&self) -> RobotTime {
        self.with(|s| {
            let [a, b, c, d] = s.spent_ns.map(|n| n as Real * 1e-9);
            RobotTime {
                moving_while_scanning_s: a,
                moving_s: b,
                standing_to_sweep_s: c,
                deciding_s: d,
            }
        })
    }

    /// A mark of the clock now, for [`RobotClock::since`].
    pub fn mark(&self) -> ClockMark {
        ClockMark(self.with(|s| s.spent_ns))
    }

    /// The robot time since `mark`, per activity. It is counted in whole
    /// nanoseconds, so it is the same whatever the clock read at the mark
    /// (a resumed run's clock, which ran through the replay, gives each
    /// new viewpoint the time the uninterrupted run gave it).
    pub fn since(&self, mark: &ClockMark) -> RobotTime {
        let now = self.with(|s| s.spent_ns);
        let d: [Real; 4] = std::array::from_fn(|i| now[i].saturating_sub(mark.0[i]) as Real * 1e-9);
        RobotTime {
            moving_while_scanning_s: d[0],
            moving_s: d[1],
            standing_to_sweep_s: d[2],
            deciding_s: d[3],
        }
    }
}

/// Any hardware on a [`RobotClock`] (see the module docs); it answers as
/// the hardware alone would.
///
/// Hardware with a clock of its own ([`Arm::clock_ns`]: a robot over a
/// link) is timed on it instead of the model: each call takes the time
/// the robot's clock ran during it, a continuous motion the time from its
/// start to its rest. What the loop does between calls, the robot standing
/// still, is counted as the loop says ([`RobotClock::stand`]), so a robot
/// run faster than real time is timed as it would be in real time.
#[derive(Debug)]
pub struct Timed<H> {
    inner: H,
    timing: RobotTiming,
    clock: RobotClock,
    /// The continuous motion under way, when it began, nanoseconds, and
    /// the hardware's clock then (when it has one).
    motion: Option<(u64, LineMotion, Option<u64>)>,
}

impl<H> Timed<H> {
    /// `inner` timed by `timing` on `clock`.
    pub fn new(inner: H, timing: RobotTiming, clock: RobotClock) -> Self {
        Self {
            inner,
            timing,
            clock,
            motion: None,
        }
    }

    /// The clock.
    pub fn clock(&self) -> &RobotClock {
        &self.clock
    }

    /// The hardware timed.
    pub fn into_inner(self) -> H {
        self.inner
    }

    /// The hardware timed, borrowed.
    pub fn inner(&self) -> &H {
        &self.inner
    }
}

/// Seconds from `h0` to `h1` on a hardware clock.
fn seconds_between(h0: u64, h1: Option<u64>) -> Real {
    h1.map_or(0.0, |h1| h1.saturating_sub(h0) as Real * 1e-9)
}

impl<H: Arm> Timed<H> {
    /// `call` on the hardware, timed on its own clock when it has one
    /// (`None` then leaves the timing to the model).
    fn measured<T>(
        &mut self,
        call: impl FnOnce(&mut H) -> Result<T, HwError>,
    ) -> Result<(T, Option<Real>), HwError> {
        let h0 = self.inner.clock_ns();
        let v = call(&mut self.inner)?;
        Ok((v, h0.map(|h0| seconds_between(h0, self.inner.clock_ns()))))
    }
}

impl<H: Arm> Arm for Timed<H> {
    fn joints(&self) -> Vec<Real> {
        self.inner.joints()
    }

    /// The motion is timed from where the arm stands to the goal: its
    /// profile (the event's interval), then the settling allowance; on a
    /// clock of the hardware's, the time the call took.
    fn move_to(&mut self, q: &[Real]) -> Result<(), HwError> {
        let from = self.inner.joints();
        let ((), measured) = self.measured(|h| h.move_to(q))?;
        if let Some(d) = measured {
            self.clock.pass(d);
            return Ok(());
        }
        let d = self.timing.limits.duration_s(&from, q);
        let (start, end) = self.clock.pass(d);
        if d > 0.0 {
            self.clock.pass(self.timing.settle_s);
        }
        self.clock.with(|s| s.last = (start, end));
        Ok(())
    }
}

impl<H: Arm + LineScanner> LineScanner for Timed<H> {
    fn bearings_rad(&self) -> &[Real] {
        self.inner.bearings_rad()
    }

    fn scan(&mut self) -> Result<ScanReadings, HwError> {
        let (scan, measured) = self.measured(LineScanner::scan)?;
        self.clock.pass(measured.unwrap_or(self.timing.scan_time_s));
        Ok(scan)
    }

    fn seed_noise(&mut self, seed: u64) {
        self.inner.seed_noise(seed);
    }

    fn moving(&mut self) -> Option<&mut dyn MovingScanner> {
        if self.inner.moving().is_some() {
            Some(self)
        } else {
            None
        }
    }
}

fn cannot_move_scanning() -> HwError {
    HwError::Setting {
        what: "continuous motion".into(),
        message: "this hardware cannot scan while the arm moves".into(),
    }
}

/// A continuous motion on the clock: each scan ends `scan_time` after its
/// first beam (the event's interval is the scan's), and the motion's
/// end, the time its profile takes and then the settling allowance, with
/// the last scan's end if that is later. On a clock of the hardware's the
/// motion takes the time from its start to the arm's rest, the loop's work
/// between its scans included (the arm moved on meanwhile).
impl<H: Arm + LineScanner> MovingScanner for Timed<H> {
    fn start_motion(&mut self, motion: &LineMotion) -> Result<(), HwError> {
        let h0 = self.inner.clock_ns();
        let inner = self.inner.moving().ok_or_else(cannot_move_scanning)?;
        inner.start_motion(motion)?;
        self.motion = Some((self.clock.now_ns(), motion.clone(), h0));
        Ok(())
    }

    fn next_scan(&mut self) -> Result<Option<MovingScan>, HwError> {
        let inner = self.inner.moving().ok_or_else(cannot_move_scanning)?;
        let scan = inner.next_scan()?;
        let (t0, motion, h0) = self.motion.as_ref().ok_or_else(|| HwError::Script {
            message: "a scan of a continuous motion asked before the motion began".into(),
        })?;
        // The time the hardware's clock ran since the motion began.
        let measured = h0.map(|h0| t0 + ns(seconds_between(h0, self.inner.clock_ns())));
        if let Some(s) = &scan {
            let start = t0 + ns(s.start_s);
            let end = start + ns(self.timing.scan_time_s);
            self.clock
                .pass_until(start, measured.unwrap_or(end).max(end));
            self.clock.with(|s| s.last = (start, end));
        } else {
            let d = motion.duration_s();
            let end = t0 + ns(d);
            let settled = if d > 0.0 {
                end + ns(self.timing.settle_s)
            } else {
                end
            };
            let now = self.clock.now_ns();
            let (end, rest) = match measured {
                Some(m) => (m, m),
                None => (end, settled),
            };
            self.clock.pass_until(*t0, rest.max(now));
            self.clock.with(|s| s.last = (*t0, end.max(*t0)));
            self.motion = None;
        }
        Ok(scan)
    }

    fn brake(&mut self) -> Result<LineMotion, HwError> {
        let inner = self.inner.moving().ok_or_else(cannot_move_scanning)?;
        let braked = inner.brake()?;
        if let Some((_, m, _)) = &mut self.motion {
            m.clone_from(&braked);
        }
        Ok(braked)
    }

    fn brake_lag_s(&mut self) -> Real {
        self.inner.moving().map_or(0.0, MovingScanner::brake_lag_s)
    }
}

impl<H: Arm + RangeSensors> RangeSensors for Timed<H> {
    fn read_all(&mut self) -> Result<Vec<Option<SensorPoint>>, HwError> {
        let (readings, measured) = self.measured(RangeSensors::read_all)?;
        self.clock
            .pass(measured.unwrap_or(self.timing.reading_period_s));
        Ok(readings)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::script::{Event, Replay, Script};

    /// A move, two scans, a reading and a decision, counted by hand:
    /// 0.04 rad at 2 rad/s² is a triangle of 2·√0.02 s, then 0.05 s to
    /// settle; 0.1 s a scan; 0.01 s a reading; 0.3 s deciding.
    #[test]
    fn every_event_takes_its_time_on_its_activity() {
        let scan = ScanReadings {
            ranges_m: vec![Some(1.0)],
            intensities: vec![0.5],
            truth_materials: None,
        };
        let script = Script {
            start_joints: vec![0.0, 0.0],
            bearings_rad: vec![0.0],
            events: vec![
                Event::Moved {
                    goal: vec![0.0, 0.04],
                    reached: vec![0.0, 0.04],
                },
                Event::Scanned(scan.clone()),
                Event::Scanned(scan),
                Event::Read(vec![None]),
            ],
        };
        let timing = RobotTiming {
            limits: MotionLimits::uniform(2, 1.0, 2.0),
            settle_s: 0.05,
            scan_time_s: 0.1,
            reading_period_s: 0.01,
        };
        let clock = RobotClock::default();
        let mut hw = Timed::new(Replay::new(script), timing, clock.clone());
        clock.set_activity(Activity::StandingToSweep);
        hw.move_to(&[0.0, 0.04]).unwrap();
        let motion = 2.0 * 0.02_f64.sqrt();
        assert_eq!(clock.last_interval(), (0, ns(motion)));
        hw.scan().unwrap();
        assert_eq!(
            clock.last_interval(),
            (ns(motion) + ns(0.05), ns(motion) + ns(0.05) + ns(0.1))
        );
        hw.scan().unwrap();
        clock.set_activity(Activity::Moving);
        hw.read_all().unwrap();
        clock.stand(Activity::Deciding, 0.3);
        let spent = clock.spent();
        assert!((spent.standing_to_sweep_s - (motion + 0.05 + 0.2)).abs() < 1e-9);
        assert!((spent.moving_s - 0.01).abs() < 1e-9);
        assert!((spent.deciding_s - 0.3).abs() < 1e-9);
        assert_eq!(spent.moving_while_scanning_s, 0.0);
        assert!((clock.now_s() - spent.total_s()).abs() < 1e-9);
        // A motion to where the arm stands takes no time, not even to settle.
        let before = clock.now_ns();
        let mut still = Timed::new(
            Replay::new(Script {
                start_joints: vec![0.0, 0.04],
                bearings_rad: vec![],
                events: vec![Event::Moved {
                    goal: vec![0.0, 0.04],
                    reached: vec![0.0, 0.04],
                }],
            }),
            hw.timing.clone(),
            clock.clone(),
        );
        still.move_to(&[0.0, 0.04]).unwrap();
        assert_eq!(clock.now_ns(), before);
        // Time since a mark is whole nanoseconds: the same on a clock that
        // read otherwise at the mark.
        let (a, b) = (RobotClock::default(), RobotClock::default());
        b.pass(1_234.567_890_123);
        let (ma, mb) = (a.mark(), b.mark());
        for c in [&a, &b] {
            c.pass(0.1);
            c.pass(0.123_456_789);
        }
        assert_eq!(a.since(&ma), b.since(&mb));
    }

    #[test]
    fn timing_check_names_the_figure() {
        let robot = robot::builtin("denso-vm6083").unwrap();
        let mut t = RobotTiming::of(&robot, 0.1, 0.01);
        assert!(t.check(6).is_ok());
        t.scan_time_s = -1.0;
        assert!(t.check(6).unwrap_err().contains("scan_time_s = -1"));
    }
}
