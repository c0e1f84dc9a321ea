//! What a run is judged by when something knows the truth: a simulator's
//! ground truth watches every executed motion and every sweep. The loop
//! calls a [`Judge`] and records what it says; a real robot has no ground
//! truth and runs with [`NoJudge`].

use crate::ExploreError;
use geom::{Point3, Real, Vector3};
use sensor::Sweep;

/// The safety a judge has tallied so far (kept in the checkpoint, so a
/// resumed run goes on counting): `None` where nothing was judged.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SafetyTally {
    /// Motions along which the robot touched the true scene.
    pub collisions: Option<usize>,
    /// Smallest clearance of the robot's links from the true scene, metres.
    pub min_clearance_m: Option<Real>,
}

/// Watches a run against a ground truth.
pub trait Judge {
    /// The arm moved from `a` to `b` on its way to (or sweeping at)
    /// viewpoint `viewpoint`; `checked` are the configurations the loop
    /// checked along the motion against its own map.
    fn motion(
        &mut self,
        viewpoint: usize,
        a: &[Real],
        b: &[Real],
        checked: &[Vec<Real>],
    ) -> Result<(), ExploreError>;
    /// A sweep was taken (a replayed one too).
    fn sweep(&mut self, sweep: &Sweep);
    /// The share of A1's true surfaces covered so far.
    fn coverage_a1(&self) -> Option<Real>;
    /// The material (index into the run's material table) of the true
    /// surface a disc at `centre` stands for; `facing` is the disc's normal
    /// turned toward the scanner that saw it.
    fn true_material(&self, centre: &Point3, facing: &Vector3) -> Option<usize>;
    /// The tally so far.
    fn tally(&self) -> SafetyTally;
    /// Go on from a checkpoint's tally.
    fn restore(&mut self, tally: SafetyTally);
}

/// No ground truth: nothing is judged (a real robot).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoJudge;

impl Judge for NoJudge {
    fn motion(
        &mut self,
        _: usize,
        _: &[Real],
        _: &[Real],
        _: &[Vec<Real>],
    ) -> Result<(), ExploreError> {
        Ok(())
    }

    fn sweep(&mut self, _: &Sweep) {}

    fn coverage_a1(&self) -> Option<Real> {
        None
    }

    fn true_material(&self, _: &Point3, _: &Vector3) -> Option<usize> {
        None
    }

    fn tally(&self) -> SafetyTally {
        SafetyTally::default()
    }

    fn restore(&mut self, _: SafetyTally) {}
}
