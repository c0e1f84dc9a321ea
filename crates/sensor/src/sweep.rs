//! The tilt angles of a 3-D sweep: one joint (joint 5 of the VM-6083 by
//! default) nods the 2-D scanner through α while scans are taken at a fixed
//! tilt step (A§5.1.1, Fig. 5.2; α = 60° in A Table 6.1).

use crate::SensorError;
use geom::Real;
use serde::{Deserialize, Serialize};

/// How to sweep.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SweepConfig {
    /// Total tilt α, degrees.
    pub tilt_deg: Real,
    /// Tilt between consecutive scans, degrees.
    pub step_deg: Real,
    /// The tilting joint, 1-based (5 = the VM-6083's fifth joint).
    pub joint: usize,
}

impl Default for SweepConfig {
    fn default() -> Self {
        Self {
            tilt_deg: 60.0,
            step_deg: 0.4,
            joint: 5,
        }
    }
}

impl SweepConfig {
    /// Check the fields.
    pub fn validate(&self) -> Result<(), SensorError> {
        if !(self.tilt_deg.is_finite() && self.tilt_deg >= 0.0 && self.tilt_deg <= 360.0) {
            return Err(SensorError::Config {
                field: "tilt_deg",
                expected: "a value in [0, 360]",
                got: self.tilt_deg.to_string(),
            });
        }
        if !(self.step_deg.is_finite() && self.step_deg > 0.0) {
            return Err(SensorError::Config {
                field: "step_deg",
                expected: "a positive angle",
                got: self.step_deg.to_string(),
            });
        }
        if self.joint == 0 {
            return Err(SensorError::Config {
                field: "joint",
                expected: "a 1-based joint number",
                got: "0".into(),
            });
        }
        Ok(())
    }

    /// Number of scans in a sweep: `⌊α / step⌋ + 1`.
    pub fn scan_count(&self) -> usize {
        (self.tilt_deg / self.step_deg + 1e-9).floor() as usize + 1
    }

    /// The tilt joint's values, radians, centred on `centre_rad` and shifted as
    /// little as needed to stay inside `limits` (when the window fits).
    pub fn tilt_values(&self, centre_rad: Real, limits: Option<(Real, Real)>) -> Vec<Real> {
        let alpha = self.tilt_deg.to_radians();
        let step = self.step_deg.to_radians();
        let mut start = centre_rad - 0.5 * alpha;
        if let Some((lo, hi)) = limits
            && hi - lo >= alpha
        {
            start = start.clamp(lo, hi - alpha);
        }
        (0..self.scan_count())
            .map(|k| start + step * k as Real)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_sweep_has_151_scans_over_60_degrees() {
        let s = SweepConfig::default();
        assert_eq!(s.scan_count(), 151);
        let t = s.tilt_values(0.0, None);
        assert!((t[0] + 30f64.to_radians()).abs() < 1e-12);
        assert!((t[150] - 30f64.to_radians()).abs() < 1e-9);
        // Near a limit the window slides inside it.
        let lim = (-120f64.to_radians(), 120f64.to_radians());
        let t = s.tilt_values(-110f64.to_radians(), Some(lim));
        assert!((t[0] - lim.0).abs() < 1e-12);
        assert!(t.iter().all(|v| *v >= lim.0 - 1e-12 && *v <= lim.1 + 1e-12));
        assert!(SweepConfig { step_deg: 0.0, ..s }.validate().is_err());
    }
}
