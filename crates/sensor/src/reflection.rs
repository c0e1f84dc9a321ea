//! Return intensity and range bias versus angle of incidence.
//!
//! After the Hancock model Paul uses (A App. B, Fig. B.1): the return is a
//! specular lobe around normal incidence plus a diffuse part. The material's
//! reflectance `C_r` weights the lobe and its roughness `ψ` sets the lobe's
//! width, so that, as App. B observes, a more reflective surface raises the
//! centre of the intensity curve (most at 0°) and lowers its edges, while a
//! rougher surface raises the edges with negligible effect at 0°. Range errors
//! follow the same lobe: strong specular returns read short near normal
//! incidence, rough surfaces read long at grazing angles. The classifier of
//! A App. B fits second-order polynomials to exactly these curves.

use geom::Real;
use scene::Material;
use serde::{Deserialize, Serialize};

/// Parameters of the reflection model.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ReflectionModel {
    /// Intensity of a fully specular (`C_r = 1`) surface at normal incidence at
    /// the reference range, in the scanner's intensity units.
    pub peak_intensity: Real,
    /// Weight of the diffuse part relative to the lobe.
    pub diffuse_weight: Real,
    /// Lobe half-width (one standard deviation) of a perfectly smooth surface, rad.
    pub lobe_min_rad: Real,
    /// Lobe width added per unit roughness, rad.
    pub lobe_per_roughness_rad: Real,
    /// Range at which intensities are quoted, m (intensity falls as `1/r²`).
    pub reference_range_m: Real,
    /// Relative standard deviation of intensity noise.
    pub intensity_noise_rel: Real,
    /// Range under-estimate of a fully specular surface at normal incidence, m.
    pub specular_range_bias_m: Real,
    /// Range over-estimate per unit roughness at grazing incidence, m.
    pub roughness_range_bias_m: Real,
}

impl Default for ReflectionModel {
    fn default() -> Self {
        Self {
            peak_intensity: 4000.0,
            diffuse_weight: 0.6,
            lobe_min_rad: 0.06,
            lobe_per_roughness_rad: 0.5,
            reference_range_m: 1.0,
            intensity_noise_rel: 0.02,
            specular_range_bias_m: 0.006,
            roughness_range_bias_m: 0.004,
        }
    }
}

impl ReflectionModel {
    fn lobe(&self, m: &Material, incidence_rad: Real) -> Real {
        let w = self.lobe_min_rad + self.lobe_per_roughness_rad * m.roughness;
        (-0.5 * (incidence_rad / w).powi(2)).exp()
    }

    /// Expected intensity (no noise) of a return from `m` at `incidence_rad`
    /// (angle between the ray and the surface normal) and `range_m`.
    pub fn intensity(&self, m: &Material, incidence_rad: Real, range_m: Real) -> Real {
        let phi = incidence_rad.abs().min(std::f64::consts::FRAC_PI_2);
        let spec = m.reflectance * self.lobe(m, phi);
        let diffuse = (1.0 - m.reflectance) * self.diffuse_weight * phi.cos();
        let r = range_m.max(0.05);
        self.peak_intensity * (spec + diffuse) * (self.reference_range_m / r).powi(2)
    }

    /// Expected range error (measured minus true), metres.
    pub fn range_bias_m(&self, m: &Material, incidence_rad: Real) -> Real {
        let phi = incidence_rad.abs().min(std::f64::consts::FRAC_PI_2);
        -self.specular_range_bias_m * m.reflectance * self.lobe(m, phi)
            + self.roughness_range_bias_m * m.roughness * (1.0 - phi.cos())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_shapes_follow_appendix_b() {
        let model = ReflectionModel::default();
        let shiny = Material::new("a", 0.9, 0.3);
        let dull = Material::new("b", 0.3, 0.3);
        // More reflective: higher at 0°, lower at the edges.
        assert!(model.intensity(&shiny, 0.0, 1.0) > model.intensity(&dull, 0.0, 1.0));
        assert!(model.intensity(&shiny, 0.7, 1.0) < model.intensity(&dull, 0.7, 1.0));
        // Rougher: same centre (within 1 %), higher edges.
        let smooth = Material::new("c", 0.5, 0.1);
        let rough = Material::new("d", 0.5, 0.9);
        let c0 = model.intensity(&smooth, 0.0, 1.0);
        let c1 = model.intensity(&rough, 0.0, 1.0);
        assert!((c0 - c1).abs() / c0 < 0.01);
        assert!(model.intensity(&rough, 0.35, 1.0) > model.intensity(&smooth, 0.35, 1.0));
        // 1/r² with range.
        let i1 = model.intensity(&dull, 0.2, 0.5);
        let i2 = model.intensity(&dull, 0.2, 1.0);
        assert!((i1 / i2 - 4.0).abs() < 1e-12);
        // Range bias: specular reads short at 0°, rough reads long at grazing.
        assert!(model.range_bias_m(&shiny, 0.0) < 0.0);
        assert!(model.range_bias_m(&rough, 1.2) > 0.0);
    }
}
