//! Tilt sweeps: nod the scanner with one joint and turn each scan into world
//! points (A eq. 4.7 / 5.1), keeping the (scan, ray) grid (eq. 4.12).

use crate::SimError;
use crate::rig::{Arm, LineScanner};
use geom::{Isometry3, Point3, Real};
use robot::Robot;
use scene::MaterialId;
use sensor::SweepConfig;

/// One measured point of a sweep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepPoint {
    /// The point, world frame.
    pub point: Point3,
    /// Origin of the ray that measured it (the scanner), world frame.
    pub origin: Point3,
    /// Return intensity.
    pub intensity: Real,
    /// Measured range, metres.
    pub range_m: Real,
    /// Ground-truth material, when the scanner is simulated.
    pub material: Option<MaterialId>,
    /// Scan index (tilt step) `j`.
    pub scan: u32,
    /// Ray index (bearing) `i`.
    pub ray: u32,
}

/// A complete sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    /// Ray bearings `θ_i`, radians.
    pub bearings_rad: Vec<Real>,
    /// Tilt joint value of each scan, radians.
    pub tilts_rad: Vec<Real>,
    /// `world_from_scanner` of each scan.
    pub scanner_poses: Vec<Isometry3>,
    /// Range grid `R_{θ,α}` (A eq. 4.12), row `j` = scan `j`: `ranges[j·n + i]`.
    pub ranges: Vec<Option<Real>>,
    /// The returns as points, in scan-major order.
    pub points: Vec<SweepPoint>,
}

impl Sweep {
    /// Rays per scan.
    pub fn rays_per_scan(&self) -> usize {
        self.bearings_rad.len()
    }

    /// Range of ray `i` in scan `j`.
    pub fn range(&self, scan: usize, ray: usize) -> Option<Real> {
        self.ranges
            .get(scan * self.bearings_rad.len() + ray)
            .copied()
            .flatten()
    }

    /// The measured points alone.
    pub fn positions(&self) -> Vec<Point3> {
        self.points.iter().map(|p| p.point).collect()
    }
}

/// Sweep the scanner: tilt joint `cfg.joint` through `cfg.tilt_deg` around its
/// current value (shifted inside the joint's limits), scan at every step, and
/// return the arm to where it started. `progress(done, total)` is called after
/// each scan.
pub fn tilt_sweep<R: Arm + LineScanner>(
    rig: &mut R,
    robot: &Robot,
    world_from_base: &Isometry3,
    cfg: &SweepConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Sweep, SimError> {
    cfg.validate()?;
    let q0 = rig.joints();
    let j = cfg.joint - 1;
    if j >= q0.len() {
        return Err(SimError::TiltJoint {
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
    let bearings = rig.bearings_rad().to_vec();
    let n = bearings.len();
    let (sin, cos): (Vec<Real>, Vec<Real>) = bearings.iter().map(|t| (t.sin(), t.cos())).unzip();
    let mut sweep = Sweep {
        bearings_rad: bearings,
        tilts_rad: tilts.clone(),
        scanner_poses: Vec::with_capacity(tilts.len()),
        ranges: Vec::with_capacity(tilts.len() * n),
        points: Vec::new(),
    };
    let mut q = q0.clone();
    for (k, &t) in tilts.iter().enumerate() {
        q[j] = t;
        rig.move_to(&q)?;
        let readings = rig.scan()?;
        if readings.ranges_m.len() != n {
            return Err(SimError::ScanLength {
                expected: n,
                got: readings.ranges_m.len(),
            });
        }
        // The pose the arm reports, not the one commanded.
        let reached = rig.joints();
        let pose = robot
            .scanner_pose(&reached)?
            .map(|p| world_from_base * p)
            .ok_or(SimError::NoScanner)?;
        let origin = Point3::from(pose.translation.vector);
        for (i, r) in readings.ranges_m.iter().enumerate() {
            sweep.ranges.push(*r);
            if let Some(r) = r {
                let local = Point3::new(0.0, -r * sin[i], r * cos[i]);
                sweep.points.push(SweepPoint {
                    point: pose * local,
                    origin,
                    intensity: readings.intensities.get(i).copied().unwrap_or(0.0),
                    range_m: *r,
                    material: readings
                        .truth_materials
                        .as_ref()
                        .and_then(|m| m.get(i).copied().flatten()),
                    scan: k as u32,
                    ray: i as u32,
                });
            }
        }
        sweep.scanner_poses.push(pose);
        progress(k + 1, tilts.len());
    }
    rig.move_to(&q0)?;
    Ok(sweep)
}
