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
