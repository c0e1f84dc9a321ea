//! Hardware doubles that are not a simulator: [`Recorder`] wraps any
//! hardware and logs what it did ([`Script`]; a [`Tap`] hands each event
//! to any other [`Sink`] as it happens); [`Replay`] plays such a log
//! back as hardware of its own, checking that every command is the one
//! recorded. A loop driven by a [`Replay`] of a run repeats that run
//! without the hardware (or simulator) that made it, which is how the
//! tests show that a driver can replace the simulator, and how a driver
//! author can check a new driver against a recorded session.
//!
//! ```
//! use hw::script::{Event, Replay, Script};
//! use hw::{Arm, LineScanner, ScanReadings};
//!
//! let scan = ScanReadings { ranges_m: vec![Some(1.0), None], intensities: vec![0.5, 0.0], truth_materials: None };
//! let script = Script {
//!     start_joints: vec![0.0, 0.0],
//!     bearings_rad: vec![-0.1, 0.1],
//!     events: vec![
//!         Event::Moved { goal: vec![0.5, 0.0], reached: vec![0.5, 0.0] },
//!         Event::Scanned(scan.clone()),
//!     ],
//! };
//! let mut hw = Replay::new(script);
//! assert!(hw.move_to(&[0.4, 0.0]).is_err()); // not the recorded command
//! hw.move_to(&[0.5, 0.0])?;
//! assert_eq!(hw.joints(), vec![0.5, 0.0]);
//! assert_eq!(hw.scan()?, scan);
//! assert!(hw.scan().is_err()); // the script is over
//! # Ok::<(), hw::HwError>(())
//! ```

use crate::motion::{LineMotion, MovingScan, MovingScanner};
use crate::{Arm, HwError, LineScanner, RangeSensors, ScanReadings};
use geom::Real;
use sensor::SensorPoint;
use serde::{Deserialize, Serialize};

/// One thing the hardware did, in the order it did it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Event {
    /// The arm was sent to `goal` and reported `reached` afterwards.
    Moved {
        /// The commanded joints.
        goal: Vec<Real>,
        /// The joints the arm reported after the move.
        reached: Vec<Real>,
    },
    /// A scan was taken.
    Scanned(ScanReadings),
    /// Every range finder was read.
    Read(Vec<Option<SensorPoint>>),
    /// The scanner's noise was seeded ([`LineScanner::seed_noise`]).
    Seeded(u64),
    /// A continuous motion began ([`crate::motion`]).
    MotionStarted(LineMotion),
    /// A scan taken while the arm moved.
    ScannedMoving(MovingScan),
    /// The arm was braked; the motion as it then ran.
    Braked(LineMotion),
    /// The continuous motion ended with the arm at rest at these joints.
    MotionEnded(Vec<Real>),
}

/// A log of hardware: where the arm started, the scanner's bearings and
/// the events.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Script {
    /// The joints when recording began.
    pub start_joints: Vec<Real>,
    /// The scanner's bearings, radians (empty without a scanner).
    pub bearings_rad: Vec<Real>,
    /// What happened.
    pub events: Vec<Event>,
}

/// Where a [`Tap`] hands each event: a closure, or a [`Script`] (which
/// keeps them).
pub trait Sink {
    /// One thing the hardware did.
    fn event(&mut self, event: &Event);
}

impl<F: FnMut(&Event)> Sink for F {
    fn event(&mut self, event: &Event) {
        self(event);
    }
}

impl Sink for Script {
    fn event(&mut self, event: &Event) {
        self.events.push(event.clone());
    }
}

/// Any hardware, tapped: every successful call is handed to a [`Sink`] as
/// it happens (a run's bag is written this way, `record::bag`), and the
/// hardware answers as it would alone.
#[derive(Clone, Debug)]
pub struct Tap<H, S> {
    inner: H,
    sink: S,
    /// The continuous motion under way (its end is where the arm rests).
    running: Option<LineMotion>,
}

/// Any hardware, logged: every successful call is appended to a [`Script`].
pub type Recorder<H> = Tap<H, Script>;

impl<H: Arm> Tap<H, Script> {
    /// Start logging `inner` from its current joints. `bearings_rad` are
    /// the scanner's (empty when `inner` has none).
    pub fn new(inner: H, bearings_rad: Vec<Real>) -> Self {
        let sink = Script {
            start_joints: inner.joints(),
            bearings_rad,
            events: Vec::new(),
        };
        Self {
            inner,
            sink,
            running: None,
        }
    }

    /// The log so far.
    pub fn script(&self) -> &Script {
        &self.sink
    }
}

impl<H, S: Sink> Tap<H, S> {
    /// Hand every call of `inner` to `sink`.
    pub fn with_sink(inner: H, sink: S) -> Self {
        Self {
            inner,
            sink,
            running: None,
        }
    }

    /// The hardware tapped.
    pub fn inner(&self) -> &H {
        &self.inner
    }

    /// The hardware and the sink (for a [`Recorder`], the log).
    pub fn into_parts(self) -> (H, S) {
        (self.inner, self.sink)
    }
}

impl<H: Arm, S: Sink> Arm for Tap<H, S> {
    fn joints(&self) -> Vec<Real> {
        self.inner.joints()
    }

    fn move_to(&mut self, q: &[Real]) -> Result<(), HwError> {
        self.inner.move_to(q)?;
        self.sink.event(&Event::Moved {
            goal: q.to_vec(),
            reached: self.inner.joints(),
        });
        Ok(())
    }

    fn clock_ns(&self) -> Option<u64> {
        self.inner.clock_ns()
    }
}

impl<H: LineScanner, S: Sink> LineScanner for Tap<H, S> {
    fn bearings_rad(&self) -> &[Real] {
        self.inner.bearings_rad()
    }

    fn scan(&mut self) -> Result<ScanReadings, HwError> {
        let scan = self.inner.scan()?;
        self.sink.event(&Event::Scanned(scan.clone()));
        Ok(scan)
    }

    fn seed_noise(&mut self, seed: u64) {
        self.inner.seed_noise(seed);
        self.sink.event(&Event::Seeded(seed));
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

impl<H: LineScanner, S: Sink> MovingScanner for Tap<H, S> {
    fn start_motion(&mut self, motion: &LineMotion) -> Result<(), HwError> {
        let inner = self.inner.moving().ok_or_else(cannot_move_scanning)?;
        inner.start_motion(motion)?;
        self.running = Some(motion.clone());
        self.sink.event(&Event::MotionStarted(motion.clone()));
        Ok(())
    }

    fn next_scan(&mut self) -> Result<Option<MovingScan>, HwError> {
        let inner = self.inner.moving().ok_or_else(cannot_move_scanning)?;
        let scan = inner.next_scan()?;
        if let Some(s) = &scan {
            self.sink.event(&Event::ScannedMoving(s.clone()));
        } else {
            let end = self.running.take().map(|m| m.end()).unwrap_or_default();
            self.sink.event(&Event::MotionEnded(end));
        }
        Ok(scan)
    }

    fn brake(&mut self) -> Result<LineMotion, HwError> {
        let inner = self.inner.moving().ok_or_else(cannot_move_scanning)?;
        let braked = inner.brake()?;
        self.running = Some(braked.clone());
        self.sink.event(&Event::Braked(braked.clone()));
        Ok(braked)
    }

    fn brake_lag_s(&mut self) -> Real {
        self.inner.moving().map_or(0.0, MovingScanner::brake_lag_s)
    }
}

impl<H: RangeSensors, S: Sink> RangeSensors for Tap<H, S> {
    fn read_all(&mut self) -> Result<Vec<Option<SensorPoint>>, HwError> {
        let readings = self.inner.read_all()?;
        self.sink.event(&Event::Read(readings.clone()));
        Ok(readings)
    }
}

/// A [`Script`] played back as hardware: each call must be the next one
/// recorded (a move to exactly the recorded goal), and returns what was
/// recorded; anything else is an [`HwError::Script`] naming the event.
/// Seeding the noise is accepted whenever it comes (a replay has no noise).
#[derive(Clone, Debug)]
pub struct Replay {
    script: Script,
    next: usize,
    q: Vec<Real>,
}

impl Replay {
    /// Play `script` from its start.
    pub fn new(script: Script) -> Self {
        let q = script.start_joints.clone();
        Self { script, next: 0, q }
    }

    /// Events not played yet.
    pub fn remaining(&self) -> usize {
        self.script.events.len() - self.next
    }

    /// The next event other than a seed (skipped: a replay has no noise),
    /// or an error saying what was asked for.
    fn take(&mut self, asked: &str) -> Result<&Event, HwError> {
        while let Some(Event::Seeded(_)) = self.script.events.get(self.next) {
            self.next += 1;
        }
        let k = self.next;
        let event = self.script.events.get(k).ok_or_else(|| HwError::Script {
            message: format!(
                "{asked} asked after the script's last event ({} events)",
                self.script.events.len()
            ),
        })?;
        self.next += 1;
        Ok(event)
    }
}

fn mismatch(k: usize, asked: &str, event: &Event) -> HwError {
    let recorded = match event {
        Event::Moved { goal, .. } => format!("a move to {goal:?}"),
        Event::Scanned(_) => "a scan".to_owned(),
        Event::Read(_) => "a reading of the range finders".to_owned(),
        Event::Seeded(s) => format!("seeding the noise with {s}"),
        Event::MotionStarted(m) => format!("a continuous motion to {:?}", m.to),
        Event::ScannedMoving(_) => "a scan while moving".to_owned(),
        Event::Braked(_) => "braking".to_owned(),
        Event::MotionEnded(q) => format!("the end of a continuous motion at {q:?}"),
    };
    HwError::Script {
        message: format!("event {k}: {asked} asked, but the script recorded {recorded}"),
    }
}

impl Arm for Replay {
    fn joints(&self) -> Vec<Real> {
        self.q.clone()
    }

    fn move_to(&mut self, q: &[Real]) -> Result<(), HwError> {
        let asked = format!("a move to {q:?}");
        let k = self.next;
        let reached = match self.take(&asked)? {
            Event::Moved { goal, reached } if goal.as_slice() == q => reached.clone(),
            other => {
                let e = mismatch(k, &asked, other);
                self.next = k;
                return Err(e);
            }
        };
        self.q = reached;
        Ok(())
    }
}

impl LineScanner for Replay {
    fn bearings_rad(&self) -> &[Real] {
        &self.script.bearings_rad
    }

    fn scan(&mut self) -> Result<ScanReadings, HwError> {
        let k = self.next;
        match self.take("a scan")? {
            Event::Scanned(s) => Ok(s.clone()),
            other => {
                let e = mismatch(k, "a scan", other);
                self.next = k;
                Err(e)
            }
        }
    }
    fn moving(&mut self) -> Option<&mut dyn MovingScanner> {
        Some(self)
    }
}

/// A continuous motion played back: the motion asked must be the one
/// recorded; the scans and the braking are the recorded ones.
impl MovingScanner for Replay {
    fn start_motion(&mut self, motion: &LineMotion) -> Result<(), HwError> {
        let asked = format!("a continuous motion to {:?}", motion.to);
        let k = self.next;
        match self.take(&asked)? {
            Event::MotionStarted(m) if m == motion => Ok(()),
            other => {
                let e = mismatch(k, &asked, other);
                self.next = k;
                Err(e)
            }
        }
    }

    fn next_scan(&mut self) -> Result<Option<MovingScan>, HwError> {
        let k = self.next;
        let asked = "a scan while moving";
        let (scan, rest) = match self.take(asked)? {
            Event::ScannedMoving(s) => (Some(s.clone()), None),
            Event::MotionEnded(q) => (None, Some(q.clone())),
            other => {
                let e = mismatch(k, asked, other);
                self.next = k;
                return Err(e);
            }
        };
        if let Some(q) = rest {
            self.q = q;
        }
        Ok(scan)
    }

    fn brake(&mut self) -> Result<LineMotion, HwError> {
        let k = self.next;
        match self.take("braking")? {
            Event::Braked(m) => Ok(m.clone()),
            other => {
                let e = mismatch(k, "braking", other);
                self.next = k;
                Err(e)
            }
        }
    }
}

impl RangeSensors for Replay {
    fn read_all(&mut self) -> Result<Vec<Option<SensorPoint>>, HwError> {
        let k = self.next;
        match self.take("a reading of the range finders")? {
            Event::Read(r) => Ok(r.clone()),
            other => {
                let e = mismatch(k, "a reading of the range finders", other);
                self.next = k;
                Err(e)
            }
        }
    }
}
