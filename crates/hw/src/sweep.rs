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
    let j = cfg.joint - 1;
    if j >= q0.len() {
        return Err(HwError::TiltJoint {
            joint: cfg.joint,
            dof: q0.len(),
        });
    }
    let limits = robot
        .limits()
        .get(j)
        .copied()
        .flatten()
        .map(|l| (l.min, l.max));
    let tilts = cfg.tilt_values(q0[j], limits);
    let mut builder = SweepBuilder::new(rig.bearings_rad())?;
    let mut q = q0.clone();
    for (k, &t) in tilts.iter().enumerate() {
        q[j] = t;
        rig.move_to(&q)?;
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
        progress(k + 1, tilts.len());
    }
    rig.move_to(&q0)?;
    Ok(builder.finish()?)
}

/// Scan while moving: take the arm from where it stands to `to` in equal
/// steps of at most `step_rad` on every joint, scanning after each step (a
/// line scanner keeps scanning while the arm moves; the Hokuyo of A§5.1
/// delivers a scan every 100 ms), each scan added to `builder` at the
/// scanner pose of the joints the arm reports. Returns the number of scans.
pub fn scan_motion<R: Arm + LineScanner + ?Sized>(
    rig: &mut R,
    robot: &Robot,
    world_from_base: &Isometry3,
    to: &[geom::Real],
    step_rad: geom::Real,
    builder: &mut SweepBuilder,
) -> Result<usize, HwError> {
    let from = rig.joints();
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
        rig.move_to(&q)?;
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
    }
    Ok(steps)
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
        let n = scan_motion(&mut rig, &robot, &world, &to, 0.1, &mut builder).unwrap();
        assert_eq!(n, 5);
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
            scan_motion(&mut rig, &robot, &world, &to, 0.1, &mut builder).unwrap(),
            1
        );
    }
}
