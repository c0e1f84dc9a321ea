//! Continuous motion (SPEC §3.9): the arm runs one timed straight-line
//! motion while the scanner scans all along, and each beam is placed at
//! the pose of its own moment.
//!
//! A stop-and-go scan waits for the arm to settle, scans standing, and
//! moves on: on the README run 0.34 s a step, of which 0.1 s scanning. A
//! [`LineMotion`] runs the straight joint line `from` → `to` on one
//! trapezoidal profile within the joints' limits; the scanner takes a scan
//! every `scan_time`, beam `i` at `stamp + i · time_increment`
//! (`sensor_msgs/LaserScan`); the arm reports its joints every
//! [`JOINT_STATE_PERIOD_S`] ([`JointSample`]s), and
//! [`robot::moving::beam_poses`] places each beam between them.
//!
//! Hardware that can do it answers [`LineScanner::moving`] with a
//! [`MovingScanner`]; [`scan_line`] drives it, with the same guard as a
//! stop-and-go [`crate::scan_motion`] but on a receding horizon: before
//! the motion and after each scan the guard sees where the arm is and
//! where it would come to rest if it went on for one more scan and then
//! braked; when that is not safe, the arm brakes at once, and comes to
//! rest where the previous check said it could.

use crate::{Arm, HwError, LineScanner, ScanReadings, StepGuard};
use geom::{Isometry3, Real};
use robot::Robot;
pub use robot::moving::JointSample;
use robot::timing::{MotionLimits, Profile};
use sensor::SweepBuilder;

/// How often an arm reports its joints while it moves, seconds (100 Hz,
/// the rate of most arms' `joint_states`).
pub const JOINT_STATE_PERIOD_S: Real = 0.01;

/// A straight joint-space motion on a timed profile.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LineMotion {
    /// Where it starts.
    pub from: Vec<Real>,
    /// Where the line goes (the arm comes to rest short of it once the
    /// motion is [braked](LineMotion::braked)).
    pub to: Vec<Real>,
    /// `s(t)` along the line.
    pub profile: Profile,
}

impl LineMotion {
    /// The motion `from` → `to` as fast as `limits` allow.
    pub fn new(limits: &MotionLimits, from: &[Real], to: &[Real]) -> Self {
        Self {
            from: from.to_vec(),
            to: to.to_vec(),
            profile: limits.profile(from, to),
        }
    }

    /// Seconds from start to rest.
    pub fn duration_s(&self) -> Real {
        self.profile.duration_s
    }

    /// The joints `t` seconds after the start (at rest after the end).
    pub fn at(&self, t: Real) -> Vec<Real> {
        self.on_line(self.profile.fraction(t))
    }

    /// Where the arm comes to rest.
    pub fn end(&self) -> Vec<Real> {
        if self.profile.end() >= 1.0 {
            self.to.clone()
        } else {
            self.on_line(self.profile.end())
        }
    }

    fn on_line(&self, s: Real) -> Vec<Real> {
        self.from
            .iter()
            .zip(&self.to)
            .map(|(a, b)| a + (b - a) * s)
            .collect()
    }

    /// The motion braked at `t` ([`Profile::braked`]).
    #[must_use]
    pub fn braked(&self, t: Real) -> Self {
        Self {
            profile: self.profile.braked(t),
            ..self.clone()
        }
    }

    /// The joint states an arm on this motion reports from `t0` to `t1`
    /// (seconds): every multiple of [`JOINT_STATE_PERIOD_S`] from the last
    /// at or before `t0` to the first at or after `t1`.
    pub fn samples(&self, t0: Real, t1: Real) -> Vec<JointSample> {
        sampled(t0, t1, JOINT_STATE_PERIOD_S, |t| self.at(t))
    }
}

/// The joints `at(t)` of an arm sampled every `period_s` seconds from the
/// last multiple of it at or before `t0` to the first at or after `t1`.
pub fn sampled(
    t0: Real,
    t1: Real,
    period_s: Real,
    mut at: impl FnMut(Real) -> Vec<Real>,
) -> Vec<JointSample> {
    let p = period_s;
    let (a, b) = ((t0 / p).floor() as i64, (t1 / p).ceil() as i64);
    (a..=b.max(a))
        .map(|m| {
            let t = m as Real * p;
            JointSample { t_s: t, q: at(t) }
        })
        .collect()
}

/// A scan taken while the arm moved.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MovingScan {
    /// What the scanner reported.
    pub readings: ScanReadings,
    /// When its first beam was measured, seconds after the motion began.
    pub start_s: Real,
    /// Seconds between one beam and the next.
    pub time_increment_s: Real,
    /// The joints the arm reported, from before its first beam to after
    /// its last.
    pub joints: Vec<JointSample>,
}

/// The seconds between one beam and the next of a scanner that takes a
/// scan every `scan_time_s` over a whole turn with `bearings_rad` equally
/// spaced (the URG-04LX turns once in 0.1 s: 0.1 ms per 0.36° step).
pub fn time_increment_s(scan_time_s: Real, bearings_rad: &[Real]) -> Real {
    match (bearings_rad.first(), bearings_rad.last()) {
        (Some(a), Some(b)) if bearings_rad.len() > 1 => {
            let step = (b - a).abs() / (bearings_rad.len() - 1) as Real;
            scan_time_s * step / std::f64::consts::TAU
        }
        _ => 0.0,
    }
}

/// An arm and scanner that scan while the arm moves (see the module docs).
pub trait MovingScanner {
    /// Start `motion` from where the arm stands, the scanner scanning from
    /// its start on.
    fn start_motion(&mut self, motion: &LineMotion) -> Result<(), HwError>;
    /// The next scan of the motion, once it is complete; `None` when the
    /// arm has come to rest (the last scan is the one under way when it
    /// did).
    fn next_scan(&mut self) -> Result<Option<MovingScan>, HwError>;
    /// Brake at once, as hard as the motion's profile allows; returns the
    /// motion as the arm now runs it. Its scans until the arm rests still
    /// come from [`MovingScanner::next_scan`].
    fn brake(&mut self) -> Result<LineMotion, HwError>;
    /// Seconds of the motion, at most, from the end of the scan
    /// [`MovingScanner::next_scan`] returned last to the moment a brake
    /// asked after it takes hold: 0 (the default) for hardware that brakes
    /// on the spot, more for a robot on a link, which states what it
    /// measured. [`scan_line`]'s guard looks that much further ahead.
    fn brake_lag_s(&mut self) -> Real {
        0.0
    }
}

impl<T: MovingScanner + ?Sized> MovingScanner for &mut T {
    fn start_motion(&mut self, motion: &LineMotion) -> Result<(), HwError> {
        (**self).start_motion(motion)
    }

    fn next_scan(&mut self) -> Result<Option<MovingScan>, HwError> {
        (**self).next_scan()
    }

    fn brake(&mut self) -> Result<LineMotion, HwError> {
        (**self).brake()
    }

    fn brake_lag_s(&mut self) -> Real {
        (**self).brake_lag_s()
    }
}

/// Add a scan taken while the arm moved to `builder`, each beam at the
/// scanner pose of its own moment ([`robot::moving::beam_poses`]).
pub fn place_moving_scan(
    robot: &Robot,
    world_from_base: &Isometry3,
    scan: &MovingScan,
    builder: &mut SweepBuilder,
) -> Result<(), HwError> {
    let r = &scan.readings;
    let poses = robot::moving::beam_poses(
        robot,
        world_from_base,
        &scan.joints,
        scan.start_s,
        scan.time_increment_s,
        r.ranges_m.len(),
    )?;
    builder.push_scan_posed(
        &poses,
        &r.ranges_m,
        &r.intensities,
        r.truth_materials.as_deref(),
    )?;
    Ok(())
}

/// How a [`scan_line`] went.
#[derive(Clone, Debug, PartialEq)]
pub struct ScannedLine {
    /// Scans taken.
    pub scans: usize,
    /// Where the arm came to rest: the line's end, or short of it when
    /// the guard braked it.
    pub reached: Vec<Real>,
    /// The arm ran the whole line.
    pub completed: bool,
}

/// Run `motion` on `rig` with the scanner scanning all along, each scan
/// placed into `builder` beam by beam ([`place_moving_scan`]). Before the
/// motion and after each scan, `guard(at, rest, builder)` sees where the
/// arm is, where it would come to rest if it went on for one more scan
/// (`scan_time_s`) and then braked, and what was scanned so far; when it
/// says no, the arm brakes at once (before the motion: it does not
/// start). An error when `rig` cannot scan while moving.
pub fn scan_line<R: LineScanner + ?Sized>(
    rig: &mut R,
    robot: &Robot,
    world_from_base: &Isometry3,
    motion: &LineMotion,
    scan_time_s: Real,
    builder: &mut SweepBuilder,
    guard: &mut StepGuard<'_>,
) -> Result<ScannedLine, HwError> {
    let hw = rig.moving().ok_or_else(|| HwError::Setting {
        what: "continuous motion".into(),
        message: "this hardware cannot scan while the arm moves; use stop-and-go motion".into(),
    })?;
    // Where the arm rests if it runs one more scan, and the hardware's
    // lag, before it brakes.
    let horizon =
        |m: &LineMotion, t: Real, lag: Real| m.braked(t + scan_time_s + lag.max(0.0)).end();
    if !guard(
        &motion.from,
        &horizon(motion, 0.0, hw.brake_lag_s()),
        builder,
    ) {
        return Ok(ScannedLine {
            scans: 0,
            reached: motion.from.clone(),
            completed: false,
        });
    }
    hw.start_motion(motion)?;
    let mut running = motion.clone();
    let (mut scans, mut braked) = (0, false);
    while let Some(scan) = hw.next_scan()? {
        place_moving_scan(robot, world_from_base, &scan, builder)?;
        scans += 1;
        let now = scan.start_s + scan_time_s;
        if !braked
            && now < running.duration_s()
            && !guard(
                &running.at(now),
                &horizon(&running, now, hw.brake_lag_s()),
                builder,
            )
        {
            running = hw.brake()?;
            braked = true;
        }
    }
    Ok(ScannedLine {
        scans,
        reached: running.end(),
        completed: !braked,
    })
}

/// A sweep in one motion: tilt joint `j` from `q0` (where the arm was
/// sent last) out to `lo`, across to `hi` on one timed motion within
/// `limits` with the scanner scanning all along ([`scan_line`], no
/// guard: the caller checked the sweep), and back to `q0`. Each beam is
/// placed at the pose of its moment.
#[allow(clippy::too_many_arguments)]
pub fn tilt_sweep_moving<R: Arm + LineScanner + ?Sized>(
    rig: &mut R,
    robot: &Robot,
    world_from_base: &Isometry3,
    q0: &[Real],
    j: usize,
    (lo, hi): (Real, Real),
    limits: &MotionLimits,
    scan_time_s: Real,
) -> Result<sensor::Sweep, HwError> {
    if j >= q0.len() {
        return Err(HwError::TiltJoint {
            joint: j + 1,
            dof: q0.len(),
        });
    }
    let (mut a, mut b) = (q0.to_vec(), q0.to_vec());
    a[j] = lo;
    b[j] = hi;
    rig.move_to(&a)?;
    let mut builder = SweepBuilder::new(rig.bearings_rad())?;
    let motion = LineMotion::new(limits, &a, &b);
    scan_line(
        rig,
        robot,
        world_from_base,
        &motion,
        scan_time_s,
        &mut builder,
        &mut |_, _, _| true,
    )?;
    rig.move_to(q0)?;
    Ok(builder.finish()?)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// A 1 rad motion at 1 rad/s and 2 rad/s² braked 0.25 s in (still
    /// speeding up at 0.5 rad/s): it rests 0.0625 + 0.0625 rad along, at
    /// 0.5 s; samples every 10 ms cover any interval.
    #[test]
    fn a_braked_line_by_hand() {
        let limits = MotionLimits::uniform(2, 1.0, 2.0);
        let m = LineMotion::new(&limits, &[0.0, 0.0], &[1.0, -0.5]);
        assert!((m.duration_s() - 1.5).abs() < 1e-12);
        let b = m.braked(0.25);
        assert!((b.duration_s() - 0.5).abs() < 1e-12);
        let end = b.end();
        assert!((end[0] - 0.125).abs() < 1e-12 && (end[1] + 0.0625).abs() < 1e-12);
        // Braked while cruising at 1 rad/s, 1 s in: 0.75 rad done, 0.25 to rest.
        let c = m.braked(1.0);
        assert!((c.end()[0] - 1.0).abs() < 1e-12 && (c.duration_s() - 1.5).abs() < 1e-12);
        let c = m.braked(0.9);
        assert!((c.end()[0] - 0.9).abs() < 1e-12);
        assert!((c.at(10.0)[0] - 0.9).abs() < 1e-12);
        let s = m.samples(0.123, 0.2);
        assert_eq!(s.first().unwrap().t_s, 0.12);
        assert!((s.last().unwrap().t_s - 0.2).abs() < 1e-12);
        assert_eq!(s.len(), 9);
        assert_eq!(m.end(), vec![1.0, -0.5]);
    }

    #[test]
    fn a_beam_s_time_is_its_share_of_a_turn() {
        let c = sensor::ScannerConfig::default();
        let dt = time_increment_s(0.1, &c.bearings_rad());
        assert!(
            (dt - 0.1 * c.angular_step_deg / 360.0).abs() < 1e-10,
            "{dt}"
        );
        assert_eq!(time_increment_s(0.1, &[0.0]), 0.0);
    }

    /// A recorded continuous motion played back on the clock: 0.04 rad at
    /// 2 rad/s² is a triangle of 2·√0.02 = 0.283 s; three scans start
    /// before it ends (at 0, 0.1 and 0.2 s), the last ends at 0.3 s, and
    /// the arm has settled at 0.333 s. A motion other than the one
    /// recorded is refused.
    #[test]
    fn a_replayed_motion_on_the_clock() {
        use crate::clock::{Activity, RobotClock, RobotTiming, Timed};
        use crate::script::{Event, Replay, Script};
        let limits = MotionLimits::uniform(2, 1.0, 2.0);
        let motion = LineMotion::new(&limits, &[0.0, 0.0], &[0.04, 0.0]);
        let scan = |k: usize| MovingScan {
            readings: ScanReadings {
                ranges_m: vec![Some(1.0), None],
                intensities: vec![0.5, 0.0],
                truth_materials: None,
            },
            start_s: k as Real * 0.1,
            time_increment_s: 0.01,
            joints: motion.samples(k as Real * 0.1, k as Real * 0.1 + 0.01),
        };
        let script = Script {
            start_joints: vec![0.0, 0.0],
            bearings_rad: vec![-0.1, 0.1],
            events: vec![
                Event::MotionStarted(motion.clone()),
                Event::ScannedMoving(scan(0)),
                Event::ScannedMoving(scan(1)),
                Event::ScannedMoving(scan(2)),
                Event::MotionEnded(motion.end()),
            ],
        };
        let timing = RobotTiming {
            limits: limits.clone(),
            settle_s: 0.05,
            scan_time_s: 0.1,
            reading_period_s: 0.01,
        };
        let clock = RobotClock::default();
        clock.set_activity(Activity::MovingWhileScanning);
        let mut hw = Timed::new(Replay::new(script.clone()), timing, clock.clone());
        let m = hw.moving().unwrap();
        m.start_motion(&motion).unwrap();
        for k in 0..3 {
            assert_eq!(m.next_scan().unwrap(), Some(scan(k)));
            assert_eq!(clock.now_ns(), (k as u64 + 1) * 100_000_000);
        }
        assert_eq!(m.next_scan().unwrap(), None);
        let d = 2.0 * 0.02_f64.sqrt();
        assert!((motion.duration_s() - d).abs() < 1e-12);
        assert_eq!(clock.now_ns(), ((d + 0.05) * 1e9).round() as u64);
        assert_eq!(clock.last_interval(), (0, (d * 1e9).round() as u64));
        assert_eq!(crate::Arm::joints(&hw), vec![0.04, 0.0]);
        let mut other = Replay::new(script);
        let e = other
            .start_motion(&LineMotion::new(&limits, &[0.0, 0.0], &[0.05, 0.0]))
            .unwrap_err();
        assert!(
            e.to_string().contains("a continuous motion to [0.05, 0.0]"),
            "{e}"
        );
    }
}
