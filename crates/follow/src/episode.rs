//! The surface-following episode (P ch. 3): a [`Follower`] driven through
//! the hardware traits ([`hw::Arm`] + [`hw::RangeSensors`]) until it
//! terminates, a budget of sensor sets is used up or a stop flag is raised,
//! with a [`Judge`] that checks every pose and motion where something knows
//! the truth (a simulator; [`NoJudge`] for a real robot).

use crate::guard::GuardCounts;
use crate::{FollowError, Follower, Termination};
use geom::{Point3, Real};
use hw::clock::{Activity, RobotClock};
use hw::{Arm, RangeSensors};
use record::StepRow;
use std::sync::atomic::{AtomicBool, Ordering};

/// Checks a run against a ground truth.
pub trait Judge {
    /// The arm stands at `q`: the start (`step` `None`) or the end of step
    /// `step`'s motion.
    fn pose(&mut self, step: Option<u64>, q: &[Real]) -> Result<(), FollowError>;
    /// Step `step` is about to move the arm from `a` to `b`.
    fn motion(&mut self, step: u64, a: &[Real], b: &[Real]) -> Result<(), FollowError>;
}

/// No ground truth: nothing is judged (a real robot).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoJudge;

impl Judge for NoJudge {
    fn pose(&mut self, _: Option<u64>, _: &[Real]) -> Result<(), FollowError> {
        Ok(())
    }

    fn motion(&mut self, _: u64, _: &[Real], _: &[Real]) -> Result<(), FollowError> {
        Ok(())
    }
}

/// Why a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum RunEnd {
    /// The follower stopped (P§3.4).
    Follower(Termination),
    /// The budget of sensor sets was used up.
    MaxSets,
    /// The stop flag was raised.
    Interrupted,
    /// A step or a move failed after the run had started; the steps before it
    /// are kept.
    Error(String),
}

impl RunEnd {
    /// Name used in files: the follower's termination, `max_sets`,
    /// `interrupted` or `error`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Follower(t) => t.name(),
            Self::MaxSets => "max_sets",
            Self::Interrupted => "interrupted",
            Self::Error(_) => "error",
        }
    }
}

/// What [`run_episode`] recorded.
#[derive(Clone, Debug, PartialEq)]
pub struct Episode {
    /// One row per step.
    pub rows: Vec<StepRow>,
    /// Why it ended.
    pub end: RunEnd,
    /// The joints at the end.
    pub end_joints: Vec<Real>,
    /// What the follower's safety guard did.
    pub guard: GuardCounts,
}

/// How [`run_episode`] runs.
#[derive(Clone, Debug)]
pub struct EpisodeOptions {
    /// Most sensor sets to take (one per step).
    pub max_sets: u64,
    /// Keep the steps' wall times in the rows (off: `None`, so the rows are
    /// the same for the same inputs).
    pub timings: bool,
    /// The robot clock the hardware runs on (`hw::clock::Timed`): each
    /// step's decision is counted on it, and each row gets the step's
    /// robot time.
    pub clock: RobotClock,
}

/// Robot time a step's decision counts when timings are off, seconds (a
/// step takes 0.05–0.3 ms of wall time here; Pudney's took 75–280 ms,
/// P Table 1).
pub const UNTIMED_STEP_DECISION_S: Real = 0.001;

/// Drive `follower` through the hardware until it terminates,
/// `options.max_sets` sensor sets have been taken, or `stop` is raised
/// (checked before every step). Each step: read every range finder,
/// [`Follower::step`], let the judge check the motion to the new pose,
/// record the row, move, let the judge check the pose reached.
///
/// Errors before the first step (reading the joints, the start pose's
/// checks) are returned; a failure once the run is under way ends it with
/// [`RunEnd::Error`], keeping the steps so far.
pub fn run_episode<H: Arm + RangeSensors + ?Sized>(
    hw: &mut H,
    follower: &mut Follower,
    judge: &mut dyn Judge,
    options: &EpisodeOptions,
    stop: &AtomicBool,
    progress: &mut dyn FnMut(&StepRow, &Follower),
) -> Result<Episode, FollowError> {
    let mut q = hw.joints();
    follower.robot().check_joints(&q)?;
    judge.pose(None, &q)?;
    let mut rows = Vec::new();
    let clock = &options.clock;
    let end = loop {
        if stop.load(Ordering::Relaxed) {
            break RunEnd::Interrupted;
        }
        if rows.len() as u64 >= options.max_sets {
            break RunEnd::MaxSets;
        }
        let began = clock.now_ns();
        clock.set_activity(Activity::StandingToSweep);
        let readings = match hw.read_all() {
            Ok(r) => r,
            Err(e) => break RunEnd::Error(e.to_string()),
        };
        let points: Vec<Option<Point3>> = readings.iter().map(|r| r.map(|s| s.point)).collect();
        let step = match follower.step(&q, &points) {
            Ok(s) => s,
            Err(e) => break RunEnd::Error(e.to_string()),
        };
        let decided_s = if options.timings {
            step.times.total_us() * 1e-6
        } else {
            UNTIMED_STEP_DECISION_S
        };
        clock.stand(Activity::Deciding, decided_s);
        let n = rows.len() as u64;
        let step_time = |r: &mut StepRow| r.robot_time_s = (clock.now_ns() - began) as Real * 1e-9;
        rows.push(StepRow {
            step: n,
            mode: step.mode.name().to_owned(),
            control_point: step.control_point,
            joints: q.clone(),
            set_size: step.set_size,
            times: options.timings.then_some(step.times),
            link_clearance_m: step.link_clearance,
            current_segment: step.current_segment,
            current_edge: step.current_edge,
            robot_time_s: 0.0,
        });
        if let Some(t) = step.termination {
            if let Some(r) = rows.last_mut() {
                step_time(r);
                progress(r, follower);
            }
            break RunEnd::Follower(t);
        }
        let next: Vec<Real> = q.iter().zip(&step.dq).map(|(a, d)| a + d).collect();
        if let Err(e) = judge.motion(n, &q, &next) {
            break RunEnd::Error(e.to_string());
        }
        clock.set_activity(Activity::Moving);
        let moved = hw.move_to(&next);
        if let Some(r) = rows.last_mut() {
            step_time(r);
        }
        if let Err(e) = moved {
            break RunEnd::Error(format!("step {n}: moving to the next pose: {e}"));
        }
        q = hw.joints();
        if let Err(e) = judge.pose(Some(n), &q) {
            break RunEnd::Error(e.to_string());
        }
        if let Some(r) = rows.last() {
            progress(r, follower);
        }
    };
    Ok(Episode {
        rows,
        end,
        end_joints: q,
        guard: follower.guard_counts(),
    })
}
