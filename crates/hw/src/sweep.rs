//! Tilt sweeps through the hardware traits: nod the scanner with one joint
//! and collect each scan into a [`sensor::Sweep`] on its (scan, ray) grid
//! (A eq. 4.7 / 5.1, eq. 4.12).

use crate::{Arm, HwError, LineScanner};
use geom::Isometry3;
use robot::Robot;
use sensor::{Sweep, SweepBuilder, SweepConfig};

/// Sweep the scanner: tilt joint `cfg.joint` through `cfg.tilt_deg` around its
/// current value (shifted inside the joint's limits), scan at every step, and
/// return the arm to where it started. Each scan is placed at the scanner
/// pose of the joints the arm *reports* after the move, not the commanded
/// ones. `progress(done, total)` is called after each scan.
pub fn tilt_sweep<R: Arm + LineScanner + ?Sized>(
    rig: &mut R,
    robot: &Robot,
    world_from_base: &Isometry3,
    cfg: &SweepConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Sweep, HwError> {
    cfg.validate()?;
    let q0 = rig.joints();
    let j = tilt_joint(cfg, q0.len())?;
    let limits = robot
        .limits()
        .get(j)
        .copied()
        .flatten()
        .map(|l| (l.min, l.max));
    let tilts = cfg.tilt_values(q0[j], limits);
    tilt_sweep_through(rig, robot, world_from_base, &q0, j, &tilts, progress)
}

/// The 0-based index of `cfg`'s tilt joint on an arm of `dof` joints.
pub fn tilt_joint(cfg: &SweepConfig, dof: usize) -> Result<usize, HwError> {
    let j = cfg.joint.wrapping_sub(1);
    if j >= dof {
        return Err(HwError::TiltJoint {
            joint: cfg.joint,
            dof,
        });
    }
    Ok(j)
}

/// Sweep the scanner through the given values of joint `j` (0-based),
/// scanning at each, and return the arm to `q0`, where it was sent last
/// (the commands are made from it, not from the joints the arm reports
/// within its tolerance, so that joints the sweep does not move never
/// drift); each scan is placed as in [`tilt_sweep`]. `tilts` is not empty.
pub fn tilt_sweep_through<R: Arm + LineScanner + ?Sized>(
    rig: &mut R,
    robot: &Robot,
    world_from_base: &Isometry3,
    q0: &[geom::Real],
    j: usize,
    tilts: &[geom::Real],
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Sweep, HwError> {
    if j >= q0.len() {
        return Err(HwError::TiltJoint {
            joint: j + 1,
            dof: q0.len(),
        });
    }
    let mut builder = SweepBuilder::new(rig.bearings_rad())?;
    let mut q = q0.to_vec();
    for (k, &t) in tilts.iter().enumerate() {
        q[j] = t;
        rig.move_to(&q)?;
        scan_into(rig, robot, world_from_base, &mut builder)?;
        progress(k + 1, tilts.len());
    }
    rig.move_to(q0)?;
    Ok(builder.finish()?)
}

/// Scan where the arm stands and add the scan to `builder` at the scanner
/// pose of the joints the arm reports.
fn scan_into<R: Arm + LineScanner + ?Sized>(
    rig: &mut R,
    robot: &Robot,
    world_from_base: &Isometry3,
    builder: &mut SweepBuilder,
) -> Result<(), HwError> {
    let readings = rig.scan()?;
    let reached = rig.joints();
    let pose = robot
        .scanner_pose(&reached)?
        .map(|p| world_from_base * p)
        .ok_or(HwError::NoScanner)?;
    builder.push_scan(
        &pose,
        &readings.ranges_m,
        &readings.intensities,
        readings.truth_materials.as_deref(),
    )?;
    Ok(())
}

/// How a [`scan_motion`] went.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScannedMotion {
    /// Steps taken (a scan after each).
    pub steps: usize,
    /// The arm reached the goal (the guard never stopped it).
    pub completed: bool,
}

/// What [`scan_motion`] asks before each step: `(at, next, scanned)`, where
/// the arm is, where the step would take it, and what was scanned so far;
/// `false` keeps the arm where it is.
pub type StepGuard<'a> = dyn FnMut(&[geom::Real], &[geom::Real], &SweepBuilder) -> bool + 'a;

/// Scan while moving: take the arm along `(from, to)`, from where it was
/// sent last to `to`, in equal steps of at most `step_rad` on every joint, scanning after each step (a
/// line scanner keeps scanning while the arm moves; the Hokuyo of A§5.1
/// delivers a scan every 100 ms), each scan added to `builder` at the
/// scanner pose of the joints the arm reports. Before each step,
/// `guard(at, next, builder)` sees where the arm is, where the step would
/// take it, and what was scanned so far; when it says no, the arm stays.
pub fn scan_motion<R: Arm + LineScanner + ?Sized>(
    rig: &mut R,
    robot: &Robot,
    world_from_base: &Isometry3,
    (from, to): (&[geom::Real], &[geom::Real]),
    step_rad: geom::Real,
    builder: &mut SweepBuilder,
    guard: &mut StepGuard<'_>,
) -> Result<ScannedMotion, HwError> {
    let span = from
        .iter()
        .zip(to)
        .map(|(a, b)| (b - a).abs())
        .fold(0.0, geom::Real::max);
    let steps = if step_rad > 0.0 && span.is_finite() {
        (span / step_rad).ceil().max(1.0) as usize
    } else {
        1
    };
    for s in 1..=steps {
        let t = s as geom::Real / steps as geom::Real;
        let q: Vec<geom::Real> = if s == steps {
            to.to_vec()
        } else {
            from.iter().zip(to).map(|(a, b)| a + (b - a) * t).collect()
        };
        let at: Vec<geom::Real> = if s == 1 {
            from.to_vec()
        } else {
            let t = (s - 1) as geom::Real / steps as geom::Real;
            from.iter().zip(to).map(|(a, b)| a + (b - a) * t).collect()
        };
        if !guard(&at, &q, builder) {
            return Ok(ScannedMotion {
                steps: s - 1,
                completed: false,
            });
        }
        rig.move_to(&q)?;
        scan_into(rig, robot, world_from_base, builder)?;
    }
    Ok(ScannedMotion {
        steps,
        completed: true,
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::ScanReadings;
    use geom::Real;

    /// An arm that goes where it is told and a scanner that sees 1 m ahead.
    struct Rig {
        q: Vec<Real>,
        bearings: Vec<Real>,
        moves: Vec<Vec<Real>>,
    }

    impl Arm for Rig {
        fn joints(&self) -> Vec<Real> {
            self.q.clone()
        }
        fn move_to(&mut self, q: &[Real]) -> Result<(), HwError> {
            self.q = q.to_vec();
            self.moves.push(q.to_vec());
            Ok(())
        }
    }

    impl LineScanner for Rig {
        fn bearings_rad(&self) -> &[Real] {
            &self.bearings
        }
        fn scan(&mut self) -> Result<ScanReadings, HwError> {
            let n = self.bearings.len();
            Ok(ScanReadings {
                ranges_m: vec![Some(1.0); n],
                intensities: vec![0.5; n],
                truth_materials: None,
            })
        }
    }

    /// A motion of 0.5 rad on its largest joint at 0.1 rad a step: five
    /// equal steps, a scan after each at the scanner pose of the joints
    /// reached, ending at the goal.
    #[test]
    fn scan_motion_scans_after_every_step() {
        let robot = robot::builtin("denso-vm6083").unwrap();
        let from = vec![0.0, -0.5, 2.0, 0.0, -1.0, 0.0];
        let to = vec![0.2, -0.5, 2.0, 0.5, -1.0, -0.1];
        let mut rig = Rig {
            q: from.clone(),
            bearings: vec![-0.1, 0.0, 0.1],
            moves: Vec::new(),
        };
        let world = Isometry3::translation(0.0, 0.0, 0.2);
        let mut builder = SweepBuilder::new(&rig.bearings).unwrap();
        let mut seen = Vec::new();
        let n = scan_motion(
            &mut rig,
            &robot,
            &world,
            (&from, &to),
            0.1,
            &mut builder,
            &mut |at, _, b| {
                seen.push((at.to_vec(), b.scan_count()));
                true
            },
        )
        .unwrap();
        assert_eq!(
            n,
            ScannedMotion {
                steps: 5,
                completed: true
            }
        );
        // The guard saw each step's start and the scans before it.
        assert_eq!(seen.len(), 5);
        assert_eq!(seen[0], (from.clone(), 0));
        assert_eq!(seen[3], (rig.moves[2].clone(), 3));
        assert_eq!(rig.q, to);
        assert_eq!(rig.moves.len(), 5);
        for (k, q) in rig.moves.iter().enumerate() {
            let t = (k + 1) as Real / 5.0;
            for j in 0..6 {
                assert!((q[j] - (from[j] + t * (to[j] - from[j]))).abs() < 1e-12);
            }
        }
        let sweep = builder.finish().unwrap();
        assert_eq!(sweep.scanner_poses().len(), 5);
        assert_eq!(sweep.len(), 15);
        let last = world * robot.scanner_pose(&to).unwrap().unwrap();
        let got = sweep.scanner_poses()[4];
        assert!((got.translation.vector - last.translation.vector).norm() < 1e-12);
        // Every point 1 m from its scan's origin.
        for p in sweep.points() {
            assert!((p.range_m() - 1.0).abs() < 1e-12);
        }
        // Standing still: one scan where the arm stands.
        let mut builder = SweepBuilder::new(&rig.bearings).unwrap();
        assert_eq!(
            scan_motion(
                &mut rig,
                &robot,
                &world,
                (&to, &to),
                0.1,
                &mut builder,
                &mut |_, _, _| true
            )
            .unwrap()
            .steps,
            1
        );
        // A guard that refuses the third step: two steps, two scans, the
        // arm where the second left it.
        let mut rig = Rig {
            q: from.clone(),
            bearings: vec![0.0],
            moves: Vec::new(),
        };
        let mut builder = SweepBuilder::new(&rig.bearings).unwrap();
        let done = scan_motion(
            &mut rig,
            &robot,
            &world,
            (&from, &to),
            0.1,
            &mut builder,
            &mut |_, _, b| b.scan_count() < 2,
        )
        .unwrap();
        assert_eq!(
            done,
            ScannedMotion {
                steps: 2,
                completed: false
            }
        );
        assert_eq!(builder.scan_count(), 2);
        assert_eq!(rig.moves.len(), 2);
        assert_eq!(rig.q, rig.moves[1]);
    }
}
