//! The tilt angles of a 3-D sweep: one joint (joint 5 of the VM-6083 by
//! default) nods the 2-D scanner through α while scans are taken at a fixed
//! tilt step (A§5.1.1, Fig. 5.2; α = 60° in A Table 6.1).

use crate::{ScannerConfig, SensorError};
use geom::Real;
use serde::{Deserialize, Serialize};

/// Most scans one sweep may have ([`SweepConfig::scan_count`]), checked by
/// [`SweepConfig::validate`]: a 0.0036° step over the full 360°. The default
/// sweep has 151.
pub const MAX_SCANS_PER_SWEEP: usize = 100_000;

/// Most rays (scans × rays per scan) one sweep may cast, checked by
/// [`SweepConfig::validate_with`]. A sweep keeps every return, about 100 bytes
/// each, so this is ~400 MB; the default sweep casts 151 × 342 = 51 642.
pub const MAX_RAYS_PER_SWEEP: usize = 4_000_000;

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
        let scans = self.scan_count();
        if scans > MAX_SCANS_PER_SWEEP {
            return Err(SensorError::Budget {
                field: "step_deg",
                value: self.step_deg.to_string(),
                count: scans,
                what: "scans per sweep",
                limit: MAX_SCANS_PER_SWEEP,
            });
        }
        Ok(())
    }

    /// [`Self::validate`] and [`ScannerConfig::validate`], then the sweep's total
    /// ray count against [`MAX_RAYS_PER_SWEEP`].
    pub fn validate_with(&self, scanner: &ScannerConfig) -> Result<(), SensorError> {
        self.validate()?;
        scanner.validate()?;
        let rays = self.scan_count().saturating_mul(scanner.ray_count());
        if rays > MAX_RAYS_PER_SWEEP {
            return Err(SensorError::Budget {
                field: "step_deg",
                value: self.step_deg.to_string(),
                count: rays,
                what: "rays per sweep (scans × rays per scan)",
                limit: MAX_RAYS_PER_SWEEP,
            });
        }
        Ok(())
    }

    /// Number of scans in a sweep: `⌊α / step⌋ + 1` (saturating at `usize::MAX`
    /// for a step too small to count).
    pub fn scan_count(&self) -> usize {
        let steps = (self.tilt_deg / self.step_deg + 1e-9).floor();
        if steps.is_finite() && steps >= 0.0 {
            (steps as usize).saturating_add(1)
        } else {
            usize::MAX
        }
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

    #[test]
    fn sweeps_over_budget_are_refused_before_allocating() {
        // Issue 8: step_deg = 1e-7 asked for 6·10⁸ scans and aborted the process.
        let tiny = SweepConfig {
            step_deg: 1e-7,
            ..SweepConfig::default()
        };
        assert_eq!(tiny.scan_count(), 600_000_001);
        let err = tiny.validate().unwrap_err().to_string();
        assert_eq!(
            err,
            "sensor config `step_deg` = 0.0000001 gives 600000001 scans per sweep, more than the limit of 100000"
        );
        // The limit itself: 360° at 0.0036° is 100 001 scans, 0.00360002° fits.
        let at = |step_deg| SweepConfig {
            tilt_deg: 360.0,
            step_deg,
            joint: 5,
        };
        assert_eq!(at(0.0036).scan_count(), 100_001);
        assert!(at(0.0036).validate().is_err());
        assert_eq!(at(0.003_600_02).scan_count(), 100_000);
        assert!(at(0.003_600_02).validate().is_ok());
        // Scans × rays: the default scanner (342 rays) over 20 000 scans is 6.8 M rays.
        let scanner = ScannerConfig::default();
        assert_eq!(scanner.ray_count(), 342);
        assert!(SweepConfig::default().validate_with(&scanner).is_ok());
        let long = SweepConfig {
            step_deg: 60.0 / 20_000.0,
            ..SweepConfig::default()
        };
        assert!(long.validate().is_ok());
        let err = long.validate_with(&scanner).unwrap_err().to_string();
        assert!(err.contains("6840342 rays per sweep"), "{err}");
        assert!(err.contains("limit of 4000000"), "{err}");
    }
}
