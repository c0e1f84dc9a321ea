//! Coverage of the true surfaces as a run folder records it (SPEC §6); the
//! judge that measures it is `sim`'s.

use geom::{Aabb, Real};
use serde::{Deserialize, Serialize};

/// Coverage of one material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialCoverage {
    /// Material name.
    pub material: String,
    /// True-surface samples of this material.
    pub samples: usize,
    /// Of which covered.
    pub covered: usize,
}

/// Coverage of the true surfaces.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CoverageReport {
    /// Samples of the true surfaces considered.
    pub samples: usize,
    /// Samples with a measured point within the threshold.
    pub covered: usize,
    /// The threshold, metres.
    pub covered_within_m: Real,
    /// The region the samples were restricted to.
    pub region: Option<Aabb>,
    /// Density actually sampled, per m²: the configured one, or less when the
    /// sampling budget (`max_samples`) capped it.
    pub samples_per_m2: Real,
    /// `true` when the budget lowered the density.
    pub density_capped: bool,
    /// Per material, in the scene's table order (materials with no samples omitted).
    pub per_material: Vec<MaterialCoverage>,
}

impl CoverageReport {
    /// Covered fraction in `[0, 1]` (0 when there are no samples).
    pub fn fraction(&self) -> Real {
        if self.samples == 0 {
            0.0
        } else {
            self.covered as Real / self.samples as Real
        }
    }
}
