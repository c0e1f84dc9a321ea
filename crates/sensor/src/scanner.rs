//! The Hokuyo URG-04LX 2-D laser scanner (Paul Table C.2, eq. 4.7 / 5.1).
//!
//! Scanner frame (A eq. 3.10): `z` is the centre ray, `y` the ±90° ray, `x` the
//! normal of the scan plane. Ray `i` at bearing `θ_i` has direction
//! `(0, −sin θ_i, cos θ_i)`, so a return at range `r_i` is the point
//! `[0, −r_i sin θ_i, r_i cos θ_i]` of A eq. 4.7.

use crate::SensorError;
use crate::reflection::ReflectionModel;
use geom::{Isometry3, Point3, Ray, Real, UnitVector3, Vector3};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use scene::{Material, MaterialId, RayCast, default_materials};
use serde::{Deserialize, Serialize};

/// Range noise: σ = `sigma_near_m` up to `near_limit_m`, then
/// `relative_far × range` (Table C.2: 10 mm to 1 m, 1 % to 4 m).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RangeNoise {
    /// Add noise at all.
    pub enabled: bool,
    /// σ below `near_limit_m`, metres.
    pub sigma_near_m: Real,
    /// Where the relative regime starts, metres.
    pub near_limit_m: Real,
    /// σ as a fraction of the range beyond `near_limit_m`.
    pub relative_far: Real,
}

impl Default for RangeNoise {
    fn default() -> Self {
        Self {
            enabled: true,
            sigma_near_m: 0.010,
            near_limit_m: 1.0,
            relative_far: 0.01,
        }
    }
}

impl RangeNoise {
    /// σ at a range (0 when disabled).
    pub fn sigma_m(&self, range_m: Real) -> Real {
        if !self.enabled {
            0.0
        } else if range_m <= self.near_limit_m {
            self.sigma_near_m
        } else {
            self.relative_far * range_m
        }
    }
}

/// Most rays one scan may have ([`ScannerConfig::ray_count`]): the budget
/// [`ScannerConfig::validate`] holds a configuration to before anything is
/// allocated. The URG-04LX has 769 bearings (683 usable); 10 000 is a 0.024°
/// step over the full ±120° field, finer than any 2-D scanner this models.
pub const MAX_RAYS_PER_SCAN: usize = 10_000;

/// Configuration of the scanner.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScannerConfig {
    /// Angle between rays, degrees (0.36° for the URG-04LX).
    pub angular_step_deg: Real,
    /// Half of the usable field, degrees; at most 120. The default, 61.38°, gives
    /// the thesis' 342 rays per scan.
    pub half_fov_deg: Real,
    /// Shortest range reported, metres.
    pub min_range_m: Real,
    /// Longest range reported, metres.
    pub max_range_m: Real,
    /// Range noise.
    pub noise: RangeNoise,
    /// Intensity and range-bias model.
    pub reflection: ReflectionModel,
    /// Apply the material-dependent range bias of the reflection model.
    pub material_range_bias: bool,
    /// Seconds one scan takes (`sensor_msgs/LaserScan.scan_time`; the
    /// URG-04LX of A§5.1 scans at 10 Hz: 0.1 s). The robot clock counts it
    /// per scan.
    pub scan_time_s: Real,
}

impl Default for ScannerConfig {
    fn default() -> Self {
        Self {
            angular_step_deg: 0.36,
            half_fov_deg: 61.38,
            min_range_m: 0.02,
            max_range_m: 4.0,
            noise: RangeNoise::default(),
            reflection: ReflectionModel::default(),
            material_range_bias: true,
            scan_time_s: 0.1,
        }
    }
}

impl ScannerConfig {
    /// The full ±120° field (667 rays, ±119.88°).
    pub fn full_field() -> Self {
        Self {
            half_fov_deg: 120.0,
            ..Self::default()
        }
    }

    /// Check the fields.
    pub fn validate(&self) -> Result<(), SensorError> {
        let check = |ok: bool, field, expected, v: Real| {
            if ok {
                Ok(())
            } else {
                Err(SensorError::Config {
                    field,
                    expected,
                    got: v.to_string(),
                })
            }
        };
        check(
            self.angular_step_deg.is_finite() && self.angular_step_deg > 0.0,
            "angular_step_deg",
            "a positive angle",
            self.angular_step_deg,
        )?;
        check(
            self.scan_time_s.is_finite() && self.scan_time_s > 0.0 && self.scan_time_s <= 10.0,
            "scan_time_s",
            "seconds in (0, 10]",
            self.scan_time_s,
        )?;
        check(
            self.half_fov_deg.is_finite() && (0.0..=120.0).contains(&self.half_fov_deg),
            "half_fov_deg",
            "an angle in [0, 120]",
            self.half_fov_deg,
        )?;
        check(
            self.min_range_m.is_finite() && self.min_range_m >= 0.0,
            "min_range_m",
            "a non-negative distance",
            self.min_range_m,
        )?;
        check(
            self.max_range_m.is_finite()
                && self.max_range_m > self.min_range_m
                && self.max_range_m <= 1000.0,
            "max_range_m",
            "a distance greater than min_range_m, at most 1000 metres",
            self.max_range_m,
        )?;
        let n = self.noise;
        // A range noise of a metre (or of the whole range) makes every
        // return noise: the ceilings keep a scan a measurement.
        check(
            n.sigma_near_m.is_finite() && (0.0..=1.0).contains(&n.sigma_near_m),
            "noise.sigma_near_m",
            "a standard deviation in [0, 1] metres",
            n.sigma_near_m,
        )?;
        check(
            n.near_limit_m.is_finite()
                && n.near_limit_m >= 0.0
                && n.near_limit_m <= self.max_range_m,
            "noise.near_limit_m",
            "a distance in [0, max_range_m]",
            n.near_limit_m,
        )?;
        check(
            n.relative_far.is_finite() && (0.0..=0.5).contains(&n.relative_far),
            "noise.relative_far",
            "a fraction of the range in [0, 0.5]",
            n.relative_far,
        )?;
        let r = &self.reflection;
        for (ok, field, expected, v) in [
            (
                r.peak_intensity > 0.0,
                "reflection.peak_intensity",
                "a finite intensity > 0",
                r.peak_intensity,
            ),
            (
                (0.0..=1.0).contains(&r.diffuse_weight),
                "reflection.diffuse_weight",
                "a weight in [0, 1] (the diffuse part no brighter than the specular lobe's peak)",
                r.diffuse_weight,
            ),
            (
                r.lobe_min_rad > 0.0,
                "reflection.lobe_min_rad",
                "a finite angle > 0 (radians)",
                r.lobe_min_rad,
            ),
            (
                r.lobe_per_roughness_rad >= 0.0,
                "reflection.lobe_per_roughness_rad",
                "a finite angle >= 0 (radians)",
                r.lobe_per_roughness_rad,
            ),
            (
                r.reference_range_m > 0.0,
                "reflection.reference_range_m",
                "a finite distance > 0",
                r.reference_range_m,
            ),
            (
                (0.0..1.0).contains(&r.intensity_noise_rel),
                "reflection.intensity_noise_rel",
                "a relative standard deviation in [0, 1)",
                r.intensity_noise_rel,
            ),
            (
                (0.0..1.0).contains(&r.specular_range_bias_m),
                "reflection.specular_range_bias_m",
                "a range bias in [0, 1) m",
                r.specular_range_bias_m,
            ),
            (
                (0.0..1.0).contains(&r.roughness_range_bias_m),
                "reflection.roughness_range_bias_m",
                "a range bias in [0, 1) m",
                r.roughness_range_bias_m,
            ),
        ] {
            check(ok && v.is_finite(), field, expected, v)?;
        }
        let rays = self.ray_count();
        if rays > MAX_RAYS_PER_SCAN {
            return Err(SensorError::Budget {
                field: "angular_step_deg",
                value: self.angular_step_deg.to_string(),
                count: rays,
                what: "rays per scan",
                limit: MAX_RAYS_PER_SCAN,
            });
        }
        Ok(())
    }

    /// Rays per scan, `⌊2h/step⌋ + 1`, computed without allocating (saturates
    /// at `usize::MAX` for a step too small to count).
    pub fn ray_count(&self) -> usize {
        let steps = (2.0 * self.half_fov_deg / self.angular_step_deg + 1e-9).floor();
        if steps.is_finite() && steps >= 0.0 {
            (steps as usize).saturating_add(1)
        } else {
            usize::MAX
        }
    }

    /// Ray bearings `θ_i`, radians, symmetric about 0 (to float32 rounding)
    /// and inside the field: `n = ⌊2h/step⌋ + 1` rays, `θ_i = θ_0 + i·Δθ` with the first bearing
    /// and the step in float32, as a ROS 2 `sensor_msgs/LaserScan` carries
    /// them (`angle_min`, `angle_increment`): a reader of the scan's message
    /// gets the bearings the scanner used, bit for bit.
    pub fn bearings_rad(&self) -> Vec<Real> {
        let steps = (2.0 * self.half_fov_deg / self.angular_step_deg + 1e-9).floor() as usize;
        let first = crate::float32((-(steps as Real) * 0.5 * self.angular_step_deg).to_radians());
        let step = crate::float32(self.angular_step_deg.to_radians());
        (0..=steps).map(|i| first + i as Real * step).collect()
    }
}

/// One return of a scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanReturn {
    /// Measured range (with noise and bias), metres.
    pub range_m: Real,
    /// Measured point in the world frame (`world_from_scanner · [0, −r sin θ, r cos θ]`).
    pub point: Point3,
    /// Return intensity.
    pub intensity: Real,
    /// Ground truth for simulation and metrics: the range without noise.
    pub true_range_m: Real,
    /// Ground truth: angle of incidence on the surface, radians.
    pub incidence_rad: Real,
    /// Ground truth: material of the surface hit, when the world knows it.
    pub material: Option<MaterialId>,
}

/// One scan: the scanner pose and one slot per bearing (`None`: no return).
#[derive(Clone, Debug, PartialEq)]
pub struct Scan {
    /// Where the scanner was.
    pub world_from_scanner: Isometry3,
    /// Returns in bearing order.
    pub returns: Vec<Option<ScanReturn>>,
}

impl Scan {
    /// Ranges, intensities and ground-truth materials per bearing, as a
    /// scanner driver would report them.
    pub fn readings(&self) -> (Vec<Option<Real>>, Vec<Real>, Vec<Option<MaterialId>>) {
        let ranges = self.returns.iter().map(|r| r.map(|r| r.range_m)).collect();
        let intensities = self
            .returns
            .iter()
            .map(|r| r.map_or(0.0, |r| r.intensity))
            .collect();
        let materials = self
            .returns
            .iter()
            .map(|r| r.and_then(|r| r.material))
            .collect();
        (ranges, intensities, materials)
    }

    /// Append this scan to a sweep under construction.
    pub fn push_to(&self, builder: &mut crate::SweepBuilder) -> Result<(), SensorError> {
        let (ranges, intensities, materials) = self.readings();
        builder.push_scan(
            &self.world_from_scanner,
            &ranges,
            &intensities,
            Some(&materials),
        )
    }
}

/// A URG-04LX model ready to scan.
#[derive(Clone, Debug)]
pub struct Scanner {
    config: ScannerConfig,
    bearings: Vec<Real>,
    dirs: Vec<UnitVector3>,
    fallback_material: Material,
}

impl Scanner {
    /// A scanner with a validated configuration.
    pub fn new(config: ScannerConfig) -> Result<Self, SensorError> {
        config.validate()?;
        let bearings = config.bearings_rad();
        let dirs = bearings
            .iter()
            .map(|t| UnitVector3::new_unchecked(crate::sweep::beam_direction(*t)))
            .collect();
        let fallback_material = default_materials()
            .into_iter()
            .next()
            .unwrap_or_else(|| Material::new("painted_metal", 0.5, 0.35));
        Ok(Self {
            config,
            bearings,
            dirs,
            fallback_material,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &ScannerConfig {
        &self.config
    }

    /// Ray bearings, radians.
    pub fn bearings_rad(&self) -> &[Real] {
        &self.bearings
    }

    /// Rays per scan.
    pub fn ray_count(&self) -> usize {
        self.bearings.len()
    }

    /// The scan's rays in the world frame.
    pub fn rays(&self, world_from_scanner: &Isometry3) -> Vec<Ray> {
        let origin = Point3::from(world_from_scanner.translation.vector);
        self.dirs
            .iter()
            .map(|d| Ray::new(origin, world_from_scanner.rotation * *d))
            .collect()
    }

    /// A nodding sweep without a robot (a scanner on a tilt unit): one scan at
    /// `world_from_mount · R_y(t)` for every tilt `t` of `sweep` centred on 0,
    /// i.e. the scan plane nods about the scanner's own y axis (the ±90° ray),
    /// as joint 5 nods it on the VM-6083 (A§5.1.1). Noise comes from `rng` in
    /// scan order. Fails when the sweep configuration is invalid.
    pub fn nodding_sweep<W: RayCast + ?Sized, R: Rng + ?Sized>(
        &self,
        world: &W,
        world_from_mount: &Isometry3,
        sweep: &crate::SweepConfig,
        rng: &mut R,
    ) -> Result<crate::Sweep, SensorError> {
        sweep.validate()?;
        let mut builder = crate::SweepBuilder::new(&self.bearings)?;
        for t in sweep.tilt_values(0.0, None) {
            let tilt = geom::UnitQuaternion::from_axis_angle(&Vector3::y_axis(), t);
            let scan = self.scan(world, &(world_from_mount * tilt), rng);
            scan.push_to(&mut builder)?;
        }
        builder.finish()
    }

    /// Scan the world from a pose. Rays are cast in parallel; noise is drawn
    /// from `rng` in bearing order, so a seed fixes the result.
    pub fn scan<W: RayCast + ?Sized, R: Rng + ?Sized>(
        &self,
        world: &W,
        world_from_scanner: &Isometry3,
        rng: &mut R,
    ) -> Scan {
        self.scan_rays(
            world,
            world_from_scanner,
            &self.rays(world_from_scanner),
            rng,
        )
    }

    /// Scan the world while the scanner moves: beam `i` from
    /// `world_from_scanner[i]` (one pose per bearing, the pose of the
    /// beam's own moment; a missing pose takes the last one given). The
    /// scan's pose is its first beam's. Noise as in [`Scanner::scan`].
    pub fn scan_posed<W: RayCast + ?Sized, R: Rng + ?Sized>(
        &self,
        world: &W,
        world_from_scanner: &[Isometry3],
        rng: &mut R,
    ) -> Scan {
        let first = world_from_scanner.first().copied().unwrap_or_default();
        let last = world_from_scanner.last().copied().unwrap_or_default();
        let rays: Vec<Ray> = self
            .dirs
            .iter()
            .enumerate()
            .map(|(i, d)| {
                let pose = world_from_scanner.get(i).unwrap_or(&last);
                Ray::new(Point3::from(pose.translation.vector), pose.rotation * *d)
            })
            .collect();
        self.scan_rays(world, &first, &rays, rng)
    }

    fn scan_rays<W: RayCast + ?Sized, R: Rng + ?Sized>(
        &self,
        world: &W,
        world_from_scanner: &Isometry3,
        rays: &[Ray],
        rng: &mut R,
    ) -> Scan {
        let hits = world.cast_rays(rays, self.config.max_range_m);
        let model = &self.config.reflection;
        let returns = rays
            .iter()
            .zip(hits)
            .map(|(ray, hit)| {
                // Draw both numbers for every ray so a miss does not shift the
                // noise of the rays after it.
                let n_range: Real = StandardNormal.sample(rng);
                let n_int: Real = StandardNormal.sample(rng);
                let hit = hit?;
                if hit.distance < self.config.min_range_m {
                    return None;
                }
                let material = hit
                    .material
                    .and_then(|id| world.material(id))
                    .unwrap_or(&self.fallback_material);
                let incidence = hit.normal.dot(&-ray.dir).clamp(-1.0, 1.0).acos();
                let bias = if self.config.material_range_bias {
                    model.range_bias_m(material, incidence)
                } else {
                    0.0
                };
                let range = hit.distance + bias + self.config.noise.sigma_m(hit.distance) * n_range;
                if !(self.config.min_range_m..=self.config.max_range_m).contains(&range) {
                    return None;
                }
                let expected = model.intensity(material, incidence, hit.distance);
                let intensity = (expected * (1.0 + model.intensity_noise_rel * n_int)).max(0.0);
                Some(ScanReturn {
                    range_m: range,
                    point: ray.point_at(range),
                    intensity,
                    true_range_m: hit.distance,
                    incidence_rad: incidence,
                    material: hit.material,
                })
            })
            .collect();
        Scan {
            world_from_scanner: *world_from_scanner,
            returns,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_count_matches_the_bearings_and_the_budget_is_checked_first() {
        for cfg in [ScannerConfig::default(), ScannerConfig::full_field()] {
            assert_eq!(cfg.ray_count(), cfg.bearings_rad().len());
        }
        assert_eq!(ScannerConfig::full_field().ray_count(), 667);
        // Issue 8: angular_step_deg = 1e-7 asked for 1.2·10⁹ rays and aborted.
        let tiny = ScannerConfig {
            angular_step_deg: 1e-7,
            ..ScannerConfig::default()
        };
        assert_eq!(tiny.ray_count(), 1_227_600_001);
        let err = Scanner::new(tiny).unwrap_err().to_string();
        assert_eq!(
            err,
            "sensor config `angular_step_deg` = 0.0000001 gives 1227600001 rays per scan, more than the limit of 10000"
        );
        // At the limit: ±120° at 0.024° is exactly 10 001 rays, 0.0240001° fits.
        let at = |angular_step_deg| ScannerConfig {
            angular_step_deg,
            ..ScannerConfig::full_field()
        };
        assert_eq!(at(0.024).ray_count(), 10_001);
        assert!(at(0.024).validate().is_err());
        assert_eq!(at(0.024_000_1).ray_count(), 10_000);
        assert_eq!(Scanner::new(at(0.024_000_1)).unwrap().ray_count(), 10_000);
    }

    #[test]
    fn noise_settings_must_be_finite_and_non_negative() {
        let with = |noise: RangeNoise| ScannerConfig {
            noise,
            ..ScannerConfig::default()
        };
        let base = RangeNoise::default();
        for (bad, field) in [
            (
                RangeNoise {
                    sigma_near_m: Real::NAN,
                    ..base
                },
                "noise.sigma_near_m",
            ),
            (
                RangeNoise {
                    sigma_near_m: -0.01,
                    ..base
                },
                "noise.sigma_near_m",
            ),
            (
                RangeNoise {
                    near_limit_m: Real::INFINITY,
                    ..base
                },
                "noise.near_limit_m",
            ),
            (
                RangeNoise {
                    relative_far: -1.0,
                    ..base
                },
                "noise.relative_far",
            ),
        ] {
            let err = with(bad).validate().unwrap_err().to_string();
            assert!(
                err.starts_with(&format!("sensor config `{field}`")),
                "{err}"
            );
        }
        // Zero noise is a valid (noise-free) setting.
        assert!(
            with(RangeNoise {
                sigma_near_m: 0.0,
                relative_far: 0.0,
                ..base
            })
            .validate()
            .is_ok()
        );
    }

    type Spoil = fn(&mut ReflectionModel);

    #[test]
    fn reflection_settings_are_checked() {
        let base = ReflectionModel::default();
        let cases: [(Spoil, &str); 10] = [
            (|r| r.peak_intensity = Real::NAN, "peak_intensity"),
            (|r| r.peak_intensity = -4000.0, "peak_intensity"),
            (|r| r.diffuse_weight = Real::NAN, "diffuse_weight"),
            // Issue 48: 7.0 was taken as it was.
            (|r| r.diffuse_weight = 7.0, "diffuse_weight"),
            (|r| r.lobe_min_rad = 0.0, "lobe_min_rad"),
            (
                |r| r.lobe_per_roughness_rad = Real::INFINITY,
                "lobe_per_roughness_rad",
            ),
            (|r| r.reference_range_m = Real::NAN, "reference_range_m"),
            (|r| r.intensity_noise_rel = -1.0, "intensity_noise_rel"),
            (
                |r| r.specular_range_bias_m = Real::NAN,
                "specular_range_bias_m",
            ),
            (
                |r| r.roughness_range_bias_m = Real::INFINITY,
                "roughness_range_bias_m",
            ),
        ];
        for (spoil, field) in cases {
            let mut reflection = base;
            spoil(&mut reflection);
            let cfg = ScannerConfig {
                reflection,
                ..ScannerConfig::default()
            };
            let err = cfg.validate().unwrap_err().to_string();
            assert!(
                err.starts_with(&format!("sensor config `reflection.{field}`")),
                "{err}"
            );
        }
        assert!(ScannerConfig::default().validate().is_ok());
    }
}
