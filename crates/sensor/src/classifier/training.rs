//! Training data (Paul App. B): observations simulated with the scanner
//! model over random patch poses within the LRC's constraints, and
//! [`Lrc::train`], which fits the per-material models to them.

use super::features::{Features, Observation, ObservedReturn, extract_features};
use super::{Lrc, LrcConfig, LrcError};
use crate::scanner::{Scanner, ScannerConfig};
use geom::{
    Isometry3, Matrix3, Point3, Ray, Real, Translation3, UnitQuaternion, UnitVector3, Vector3,
};
use rand::{Rng, RngExt, SeedableRng};
use scene::{Hit, Material, MaterialId, RayCast};
use serde::{Deserialize, Serialize};

/// One training observation: its features and the incidence coverage of
/// its fitted returns ([`PatchGeometry::incidence_span_rad`](super::PatchGeometry::incidence_span_rad)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainingSample {
    /// The four features.
    pub features: Features,
    /// Smallest and largest fitted incidence, radians.
    pub coverage_rad: (Real, Real),
    /// [`PatchGeometry::plane_rms_m`](super::PatchGeometry::plane_rms_m) of the observation, metres.
    pub plane_rms_m: Real,
}

/// How training observations are drawn (see [`Lrc::train`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrainingConfig {
    /// Usable observations per material.
    pub observations_per_material: usize,
    /// Radius of the flat target patch, metres.
    pub patch_radius_m: Real,
    /// Tilt step of the simulated sweeps, degrees (0.4°: the sweep default).
    pub sweep_step_deg: Real,
    /// Largest tilt either side of the target, degrees (α/2 = 30°, Table 6.1).
    pub sweep_half_deg: Real,
    /// Ridge added to every (standardised) covariance diagonal.
    pub ridge: Real,
}

impl Default for TrainingConfig {
    fn default() -> Self {
        Self {
            observations_per_material: 120,
            patch_radius_m: 0.18,
            sweep_step_deg: 0.4,
            sweep_half_deg: 30.0,
            ridge: 1e-3,
        }
    }
}

/// The pose of a simulated observation of a flat patch (see
/// [`simulate_observation`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ObservationSetup {
    /// Range from the scanner to the patch centre along the centre ray, m.
    pub range_m: Real,
    /// Incidence of the centre ray on the patch, radians.
    pub incidence_rad: Real,
    /// Direction, about the centre ray, in which the surface is tilted,
    /// relative to the scan plane, radians (0: the tilt lies in the scan
    /// plane; π/2: along the nodding direction).
    pub tilt_direction_rad: Real,
    /// Radius of the flat patch, metres.
    pub patch_radius_m: Real,
    /// Tilt step of the sweep, degrees (0: a single scan).
    pub sweep_step_deg: Real,
    /// Largest tilt either side of the centre, degrees.
    pub sweep_half_deg: Real,
}

impl Default for ObservationSetup {
    fn default() -> Self {
        Self {
            range_m: 0.5,
            incidence_rad: 0.0,
            tilt_direction_rad: 0.0,
            patch_radius_m: 0.18,
            sweep_step_deg: 0.4,
            sweep_half_deg: 30.0,
        }
    }
}

/// A flat disc-shaped patch of one material: the world of a simulated
/// observation.
struct Patch {
    centre: Point3,
    normal: UnitVector3,
    radius_m: Real,
    material: Material,
}

impl RayCast for Patch {
    fn cast_ray(&self, ray: &Ray, max_range_m: Real) -> Option<Hit> {
        let denom = ray.dir.dot(&self.normal);
        if denom.abs() < 1e-12 {
            return None;
        }
        let t = (self.centre - ray.origin).dot(&self.normal) / denom;
        if !(t > 0.0 && t <= max_range_m) {
            return None;
        }
        let point = ray.point_at(t);
        if (point - self.centre).norm() > self.radius_m {
            return None;
        }
        let normal = if denom > 0.0 {
            -self.normal
        } else {
            self.normal
        };
        Some(Hit {
            distance: t,
            point,
            normal,
            material: Some(MaterialId(0)),
            object: Some(scene::ObjectId(0)),
            element: 0,
        })
    }

    fn material(&self, id: MaterialId) -> Option<&Material> {
        (id.0 == 0).then_some(&self.material)
    }
}

/// Simulate the observation of a flat patch of `material` with the scanner
/// model `scanner` (noise and reflection model included): the patch is the
/// disc of radius `setup.patch_radius_m` about the origin with normal `+z`;
/// the scanner sits at `setup.range_m` along a direction at
/// `setup.incidence_rad` from the normal and sweeps (nods about its `y` axis)
/// across the patch. Only the bearings and tilts that can reach the patch are
/// simulated. The observation's target is the patch centre.
pub fn simulate_observation<R: Rng + ?Sized>(
    setup: &ObservationSetup,
    material: &Material,
    scanner: &ScannerConfig,
    rng: &mut R,
) -> Result<Observation, crate::SensorError> {
    let bad = |field: &'static str, v: Real| crate::SensorError::Config {
        field,
        expected: "a finite, positive value",
        got: v.to_string(),
    };
    if !(setup.range_m.is_finite() && setup.range_m > 0.0) {
        return Err(bad("range_m", setup.range_m));
    }
    if !(setup.patch_radius_m.is_finite() && setup.patch_radius_m > 0.0) {
        return Err(bad("patch_radius_m", setup.patch_radius_m));
    }
    if !(setup.incidence_rad.is_finite() && setup.tilt_direction_rad.is_finite()) {
        return Err(bad("incidence_rad", setup.incidence_rad));
    }
    if !(setup.sweep_step_deg.is_finite()
        && setup.sweep_step_deg >= 0.0
        && setup.sweep_half_deg.is_finite()
        && setup.sweep_half_deg >= 0.0)
    {
        return Err(bad("sweep_step_deg", setup.sweep_step_deg));
    }
    let patch = Patch {
        centre: Point3::origin(),
        normal: UnitVector3::new_unchecked(Vector3::z()),
        radius_m: setup.patch_radius_m,
        material: material.clone(),
    };
    // Angular radius of the patch seen from the scanner (all of the field
    // when the scanner is within the patch's radius of its centre).
    let reach_deg = if setup.patch_radius_m < setup.range_m {
        (setup.patch_radius_m / setup.range_m).asin().to_degrees() + 1.0
    } else {
        180.0
    };
    let step = scanner.angular_step_deg;
    // Keep the bearing grid of the full field: an odd number of steps.
    let half_fov = if reach_deg < scanner.half_fov_deg {
        let k = ((reach_deg / step - 0.5).ceil()).max(0.0);
        ((k + 0.5) * step).min(scanner.half_fov_deg)
    } else {
        scanner.half_fov_deg
    };
    let model = Scanner::new(ScannerConfig {
        half_fov_deg: half_fov,
        ..*scanner
    })?;

    // Centre ray c from the scanner to the patch centre; scanner z = c.
    let (s, co) = setup.incidence_rad.sin_cos();
    let c = -Vector3::new(s, 0.0, co);
    let origin = Point3::from(-c * setup.range_m);
    // Scan plane: contains c and a direction rotated by the tilt direction
    // about c from the plane of incidence.
    let in_plane = Vector3::new(co, 0.0, -s); // ⟂ c, in the plane of incidence
    let rot =
        UnitQuaternion::from_axis_angle(&UnitVector3::new_unchecked(c), setup.tilt_direction_rad);
    let y_axis = rot * in_plane;
    let x_axis = y_axis.cross(&c);
    let basis = Matrix3::from_columns(&[x_axis, y_axis, c]);
    let world_from_scanner_rot =
        UnitQuaternion::from_rotation_matrix(&geom::Rotation3::from_matrix_unchecked(basis));

    let tilt_half = setup.sweep_half_deg.min(reach_deg);
    let tilts: Vec<Real> = if setup.sweep_step_deg > 0.0 {
        let k = (tilt_half / setup.sweep_step_deg).floor() as i64;
        (-k..=k).map(|i| i as Real * setup.sweep_step_deg).collect()
    } else {
        vec![0.0]
    };
    let mut returns = Vec::new();
    for t in tilts {
        let pose = Isometry3::from_parts(
            Translation3::from(origin.coords),
            world_from_scanner_rot
                * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), t.to_radians()),
        );
        let scan = model.scan(&patch, &pose, rng);
        for (ray, ret) in model.rays(&pose).iter().zip(&scan.returns) {
            if let Some(r) = ret {
                returns.push(ObservedReturn {
                    origin: ray.origin,
                    direction: ray.dir,
                    range_m: r.range_m,
                    intensity: r.intensity,
                });
            }
        }
    }
    Ok(Observation {
        returns,
        target: Some(Point3::origin()),
    })
}

impl Lrc {
    /// Train on simulated observations: for every material, draw poses
    /// uniformly inside the constraints of `config` (range in
    /// `[min_range_m, max_range_m]`, centre-ray incidence in
    /// `[0, max_incidence_deg)`, any tilt direction), simulate each with
    /// [`simulate_observation`] and `scanner` (the simulator's own model),
    /// keep the observations the constraints accept, and [`Lrc::fit`] their
    /// features. Deterministic for a seed.
    pub fn train(
        config: LrcConfig,
        training: &TrainingConfig,
        materials: &[Material],
        scanner: &ScannerConfig,
        seed: u64,
    ) -> Result<Self, LrcError> {
        config.validate()?;
        scanner.validate().map_err(|e| LrcError::Config {
            field: "scanner",
            expected: "a valid scanner configuration",
            got: e.to_string(),
        })?;
        let wanted = training.observations_per_material;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut samples = Vec::with_capacity(materials.len());
        for material in materials {
            let mut s = Vec::with_capacity(wanted);
            let mut attempts = 0usize;
            while s.len() < wanted {
                attempts += 1;
                if attempts > 20 * wanted.max(1) {
                    return Err(LrcError::Training {
                        material: material.name.clone(),
                        message: format!(
                            "only {} of {attempts} simulated observations satisfy the constraints",
                            s.len()
                        ),
                    });
                }
                let setup = random_setup(&config, training, &mut rng);
                let obs =
                    simulate_observation(&setup, material, scanner, &mut rng).map_err(|e| {
                        LrcError::Training {
                            material: material.name.clone(),
                            message: e.to_string(),
                        }
                    })?;
                if let Ok((features, geometry)) = extract_features(&obs, &config) {
                    s.push(TrainingSample {
                        features,
                        coverage_rad: geometry.incidence_span_rad,
                        plane_rms_m: geometry.plane_rms_m,
                    });
                }
            }
            samples.push(s);
        }
        let names: Vec<String> = materials.iter().map(|m| m.name.clone()).collect();
        Self::fit(config, &names, &samples, training.ridge)
    }
}

/// A random pose inside the constraints (see [`Lrc::train`]).
fn random_setup<R: Rng + ?Sized>(
    config: &LrcConfig,
    training: &TrainingConfig,
    rng: &mut R,
) -> ObservationSetup {
    let hi_range = config.max_range_m.min(4.0);
    let range_m = rng.random_range(config.min_range_m..=hi_range);
    let incidence_rad = rng.random_range(0.0..config.max_incidence_deg.to_radians());
    let tilt_direction_rad = rng.random_range(0.0..std::f64::consts::TAU);
    ObservationSetup {
        range_m,
        incidence_rad,
        tilt_direction_rad,
        patch_radius_m: training.patch_radius_m,
        sweep_step_deg: training.sweep_step_deg,
        sweep_half_deg: training.sweep_half_deg,
    }
}
