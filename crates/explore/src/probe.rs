//! A sweep predicted on the map: the scanner's own model (its rays, range
//! noise and intensities) cast at the surface Stage One mapped (its TSDF
//! mesh), from a pose the arm has not taken. Stage Two keeps a pose for a
//! disc only when the observation predicted this way is one the LRC can
//! use. The probe implements the hardware traits so that the prediction
//! nods the scanner exactly as a sweep of the real scanner does
//! ([`hw::tilt_sweep`]).

use geom::{Isometry3, Real};
use hw::{Arm, HwError, LineScanner, ScanReadings};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use robot::{Posture, Robot};
use scene::World;
use sensor::Scanner;
use std::sync::Arc;

/// The robot's scanner over a mapped surface.
pub(crate) struct MapProbe {
    robot: Robot,
    world: Arc<World>,
    world_from_base: Isometry3,
    posture: Posture,
    scanner: Scanner,
    rng: ChaCha8Rng,
}

impl MapProbe {
    /// The probe at joints `q` in the mapped `world`.
    pub(crate) fn new(
        robot: Robot,
        world: Arc<World>,
        world_from_base: Isometry3,
        q: &[Real],
        scanner: Scanner,
    ) -> Result<Self, HwError> {
        Ok(Self {
            posture: Posture::new(&robot, q)?,
            robot,
            world,
            world_from_base,
            scanner,
            rng: ChaCha8Rng::seed_from_u64(0),
        })
    }
}

impl Arm for MapProbe {
    fn joints(&self) -> Vec<Real> {
        self.posture.joints().to_vec()
    }

    fn move_to(&mut self, q: &[Real]) -> Result<(), HwError> {
        Ok(self.posture.move_to(&self.robot, q)?)
    }
}

impl LineScanner for MapProbe {
    fn bearings_rad(&self) -> &[Real] {
        self.scanner.bearings_rad()
    }

    fn scan(&mut self) -> Result<ScanReadings, HwError> {
        let base_from_scanner = self
            .posture
            .base_from_scanner(&self.robot)
            .ok_or(HwError::NoScanner)?;
        let pose = self.world_from_base * base_from_scanner;
        let scan = self.scanner.scan(self.world.as_ref(), &pose, &mut self.rng);
        Ok(ScanReadings::of_simulated(&scan))
    }

    fn seed_noise(&mut self, seed: u64) {
        self.rng = ChaCha8Rng::seed_from_u64(seed);
    }
}
