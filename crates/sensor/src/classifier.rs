//! The Laser Range Classifier (LRC) of Paul App. B: material identification
//! from how return intensity and range error vary with the angle of
//! incidence (SPEC §3.3).
//!
//! # Observation → features
//!
//! An [`Observation`] is the set of returns of one scan, or of a sweep, that
//! hit a target patch: per return the ray (origin and direction), the
//! measured range and the intensity. [`extract_features`] then, *from the
//! observation alone* (never from the simulator's ground truth):
//!
//! 1. fits a plane to the measured points (PCA; the normal is turned toward
//!    the sensor), which App. B assumes flat within the ±20° of incidence used;
//! 2. checks the validity constraints of Table 6.1: the range from the sensor
//!    to the target `d ∈ [0.25, 0.8]` m ([`LrcConfig::min_range_m`],
//!    [`LrcConfig::max_range_m`]) and the incidence of the ray to the target
//!    `φ < 42°` ([`LrcConfig::max_incidence_deg`]);
//! 3. for every return computes the estimated incidence `acos |n⃗·r̂|`, the
//!    range to the fitted plane along the ray, the range error (measured
//!    minus plane range) and the intensity compensated for the `1/r²` law of
//!    the [`ReflectionModel`](crate::ReflectionModel) (scaled to [`LrcConfig::reference_range_m`]),
//!    and keeps the returns with incidence within ±20°
//!    ([`LrcConfig::fit_window_deg`]); enough of them must remain
//!    ([`LrcConfig::min_points`]) and they must span a curve
//!    ([`LrcConfig::min_span_deg`]);
//! 4. fits second-order polynomials `y = a₀ + a₁φ + a₂φ²` (φ in radians,
//!    unsigned: the curves are even in φ) to intensity and to range error;
//!    the four features are the quadratic coefficients `a₂` and the mean
//!    squared residuals (MSE) of the two fits ([`Features`]).
//!
//! # Features → posterior
//!
//! "Likelihoods are calculated from probability density functions (of the
//! four parameters …) derived from training data" (App. B). [`Lrc`] models
//! each material's features as a multivariate Gaussian over
//! `(a₂ᴵ, ln MSEᴵ, a₂ʳ, ln MSEʳ)` (a log-normal in each MSE, which is a
//! positive, skewed quantity) whose mean depends on which part of the ±20°
//! window the observation covered ([`MaterialModel`]: a pose that sees the
//! surface from 12° to 20° only samples the outer part of the curves),
//! fitted to simulated observations, and returns the Bayes posterior under a
//! uniform prior ([`Lrc::classify`]) — the probability vector the material
//! belief of the map consumes (Paul eq. 4.15).
//!
//! The fits weigh equal bins of incidence equally ([`LrcConfig::fit_bins`]),
//! so how densely a pose samples each incidence does not bend the curves.
//! An observation must hold the returns of several scans (a sweep, or part
//! of one): a single scan line does not define the patch's plane.
//!
//! # Training data
//!
//! [`Lrc::train`] simulates observations with the very scanner model the
//! simulator uses ([`Scanner::scan`] with its [`ReflectionModel`](crate::ReflectionModel) and range
//! noise) on a flat disc-shaped target patch of each material
//! ([`simulate_observation`]), from random poses inside the constraints. The
//! patch is finite ([`TrainingConfig::patch_radius_m`], 0.18 m by default): a
//! structure's faces are, and a finite patch is what makes range matter — at
//! 0.5 m a 0.18 m patch spans exactly the ±20° window, which is App. B's
//! "a targeted surface must be within ≈ 500 mm"; farther away the curve is
//! seen over a narrower window and the fits degrade.
//!
//! ```
//! use rand::SeedableRng;
//! use scene::default_materials;
//! use sensor::classifier::{simulate_observation, Lrc, LrcConfig, ObservationSetup, TrainingConfig};
//! use sensor::ScannerConfig;
//!
//! let materials = default_materials();
//! let scanner = ScannerConfig::default();
//! // A quick training run (the defaults use 120 observations per material
//! // and 0.4° sweeps).
//! let training = TrainingConfig { observations_per_material: 30, sweep_step_deg: 1.2, ..TrainingConfig::default() };
//! let lrc = Lrc::train(LrcConfig::default(), &training, &materials, &scanner, 1)?;
//! // Stainless steel seen from 0.5 m, 10° off its normal.
//! let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
//! let setup = ObservationSetup { incidence_rad: 0.17, sweep_step_deg: 1.2, ..ObservationSetup::default() };
//! let obs = simulate_observation(&setup, &materials[4], &scanner, &mut rng)?;
//! let result = lrc.classify(&obs)?;
//! assert_eq!(lrc.material_names()[result.best()], "stainless_steel");
//! assert!((result.posterior.iter().sum::<f64>() - 1.0).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::scanner::{Scanner, ScannerConfig};
use crate::sweep::Sweep;
use geom::{
    Isometry3, Matrix3, Pca, Point3, Ray, Real, Translation3, UnitQuaternion, UnitVector3, Vector3,
};
use nalgebra::Matrix4;
use rand::{Rng, RngExt, SeedableRng};
use scene::{Hit, Material, MaterialId, RayCast};
use serde::{Deserialize, Serialize};

/// Validity constraints and fitting parameters of the LRC (Paul App. B,
/// Table 6.1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LrcConfig {
    /// Shortest range to the target, metres (Table 6.1: 0.25).
    pub min_range_m: Real,
    /// Longest range to the target, metres (Table 6.1: 0.8).
    pub max_range_m: Real,
    /// Largest incidence `φ` of the ray to the target, degrees (Table 6.1:
    /// `φ_max` = 42°); an observation must have `φ <` this.
    pub max_incidence_deg: Real,
    /// Returns with estimated incidence within ± this are fitted, degrees
    /// (App. B: ±20°).
    pub fit_window_deg: Real,
    /// Fewest returns inside the window ("enough points").
    pub min_points: usize,
    /// Smallest spread (largest minus smallest incidence) of the fitted
    /// returns, degrees: a curve needs a range of incidence.
    pub min_span_deg: Real,
    /// Range to which intensities are compensated by the `1/r²` law, metres.
    pub reference_range_m: Real,
    /// The fits weigh `fit_bins` equal bins of incidence equally (their
    /// mean returns), so that how densely a pose samples each incidence does
    /// not bend the curve; 0 fits every return with equal weight.
    pub fit_bins: usize,
}

impl Default for LrcConfig {
    fn default() -> Self {
        Self {
            min_range_m: 0.25,
            max_range_m: 0.8,
            max_incidence_deg: 42.0,
            fit_window_deg: 20.0,
            min_points: 50,
            min_span_deg: 5.0,
            reference_range_m: 1.0,
            fit_bins: 20,
        }
    }
}

impl LrcConfig {
    /// A configuration that accepts any range and incidence (for studying
    /// the classifier outside its constraints): the fit window stays ±20°
    /// unless changed.
    pub fn permissive() -> Self {
        Self {
            min_range_m: 0.0,
            max_range_m: Real::INFINITY,
            max_incidence_deg: 90.0,
            min_points: 10,
            min_span_deg: 0.0,
            ..Self::default()
        }
    }

    /// Check the fields.
    pub fn validate(&self) -> Result<(), LrcError> {
        let bad = |field: &'static str, expected: &'static str, got: Real| {
            Err(LrcError::Config {
                field,
                expected,
                got: got.to_string(),
            })
        };
        if !(self.min_range_m >= 0.0 && self.min_range_m.is_finite()) {
            return bad("min_range_m", "a non-negative distance", self.min_range_m);
        }
        if self.max_range_m.is_nan() || self.max_range_m <= self.min_range_m {
            return bad(
                "max_range_m",
                "a distance above min_range_m",
                self.max_range_m,
            );
        }
        if !(self.max_incidence_deg > 0.0 && self.max_incidence_deg <= 90.0) {
            return bad(
                "max_incidence_deg",
                "an angle in (0, 90]",
                self.max_incidence_deg,
            );
        }
        if !(self.fit_window_deg > 0.0 && self.fit_window_deg <= 90.0) {
            return bad("fit_window_deg", "an angle in (0, 90]", self.fit_window_deg);
        }
        if self.min_points < 4 {
            return bad(
                "min_points",
                "at least 4 (three coefficients and a residual)",
                self.min_points as Real,
            );
        }
        if !(self.min_span_deg >= 0.0 && self.min_span_deg <= self.fit_window_deg) {
            return bad(
                "min_span_deg",
                "an angle in [0, fit_window_deg]",
                self.min_span_deg,
            );
        }
        if !(self.reference_range_m > 0.0 && self.reference_range_m.is_finite()) {
            return bad(
                "reference_range_m",
                "a positive distance",
                self.reference_range_m,
            );
        }
        Ok(())
    }
}

/// Errors of LRC configuration and training.
#[derive(Debug, thiserror::Error)]
pub enum LrcError {
    /// A configuration field is out of range.
    #[error("LRC config `{field}`: expected {expected}, got {got}")]
    Config {
        /// The field.
        field: &'static str,
        /// What is accepted.
        expected: &'static str,
        /// What was given.
        got: String,
    },
    /// Training could not produce a model for a material.
    #[error("LRC training, material `{material}`: {message}")]
    Training {
        /// The material.
        material: String,
        /// What went wrong.
        message: String,
    },
}

/// Why an observation cannot be classified (the LRC's constraints, A App. B).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ClassifyError {
    /// The target is outside the range constraint.
    #[error("target at {range_m:.3} m is outside the LRC range [{min_m}, {max_m}] m")]
    OutOfRange {
        /// Estimated range to the target, metres.
        range_m: Real,
        /// Lower limit.
        min_m: Real,
        /// Upper limit.
        max_m: Real,
    },
    /// The ray to the target meets the surface too obliquely.
    #[error("incidence {incidence_deg:.1}° at the target is not below the LRC limit {max_deg}°")]
    TooOblique {
        /// Estimated incidence at the target, degrees.
        incidence_deg: Real,
        /// The limit.
        max_deg: Real,
    },
    /// Too few returns (overall, or inside the fit window).
    #[error("{found} returns inside the ±{window_deg}° window, the LRC needs {needed}")]
    TooFewPoints {
        /// Returns available.
        found: usize,
        /// Returns needed.
        needed: usize,
        /// The fit window, degrees.
        window_deg: Real,
    },
    /// The returns inside the window span too narrow a range of incidence.
    #[error("the fitted returns span {span_deg:.1}° of incidence, the LRC needs {needed_deg}°")]
    NarrowIncidence {
        /// Spread of incidence, degrees.
        span_deg: Real,
        /// Spread needed.
        needed_deg: Real,
    },
    /// A return holds a non-finite or negative value.
    #[error("return {index}: `{field}` is not valid")]
    InvalidReturn {
        /// The return.
        index: usize,
        /// The field.
        field: &'static str,
    },
    /// The points do not define a plane or a fit (collinear, singular).
    #[error("the returns do not define a plane and a fit")]
    Degenerate,
    /// The feature vector has no finite likelihood under any material.
    #[error("the features are not finite")]
    NonFiniteFeatures,
}

/// One return of an observation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObservedReturn {
    /// Ray origin (the scanner position), world frame.
    pub origin: Point3,
    /// Unit ray direction, world frame.
    pub direction: UnitVector3,
    /// Measured range, metres.
    pub range_m: Real,
    /// Measured intensity.
    pub intensity: Real,
}

impl ObservedReturn {
    /// The measured point.
    pub fn point(&self) -> Point3 {
        self.origin + self.direction.into_inner() * self.range_m
    }
}

/// The returns of a scan or sweep on one target patch.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Observation {
    /// The returns.
    pub returns: Vec<ObservedReturn>,
    /// The targeted point (e.g. a disc centre), if known; otherwise the
    /// centroid of the returns is the target.
    pub target: Option<Point3>,
}

impl Observation {
    /// The returns of a sweep whose measured point lies within
    /// `patch_radius_m` of `target`.
    pub fn from_sweep(sweep: &Sweep, target: &Point3, patch_radius_m: Real) -> Self {
        let returns = sweep
            .points()
            .iter()
            .filter(|p| (p.point - target).norm() <= patch_radius_m)
            .filter_map(|p| {
                let (direction, range_m) = UnitVector3::try_new_and_get(p.point - p.origin, 1e-12)?;
                Some(ObservedReturn {
                    origin: p.origin,
                    direction,
                    range_m,
                    intensity: p.intensity,
                })
            })
            .collect();
        Self {
            returns,
            target: Some(*target),
        }
    }
}

/// The four LRC features (App. B).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Features {
    /// Quadratic coefficient of intensity (compensated to the reference
    /// range) versus incidence, intensity units per rad².
    pub intensity_quadratic: Real,
    /// Mean squared residual of the intensity fit.
    pub intensity_mse: Real,
    /// Quadratic coefficient of range error versus incidence, m per rad².
    pub range_quadratic: Real,
    /// Mean squared residual of the range-error fit, m².
    pub range_mse: Real,
}

impl Features {
    /// The vector the likelihoods are over: `(a₂ᴵ, ln MSEᴵ, a₂ʳ, ln MSEʳ)`
    /// (MSEs floored at 10⁻³⁰⁰ so a perfect fit stays finite).
    pub fn model_vector(&self) -> [Real; 4] {
        [
            self.intensity_quadratic,
            self.intensity_mse.max(1e-300).ln(),
            self.range_quadratic,
            self.range_mse.max(1e-300).ln(),
        ]
    }
}

/// What the LRC estimated about the target geometry.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchGeometry {
    /// Fitted plane normal, toward the sensor.
    pub normal: UnitVector3,
    /// Range from the (mean) sensor position to the target, metres.
    pub range_m: Real,
    /// Incidence of the ray to the target, radians.
    pub incidence_rad: Real,
    /// Returns inside the fit window.
    pub points_used: usize,
    /// Smallest and largest incidence of the fitted returns, radians.
    pub incidence_span_rad: (Real, Real),
}

/// Least-squares `y = b₀ + b₁u + b₂u²`; returns `(b, mse)`.
fn quadratic_fit(u: &[Real], y: &[Real]) -> Option<([Real; 3], Real)> {
    let mut ata = Matrix3::zeros();
    let mut aty = Vector3::zeros();
    for (&x, &v) in u.iter().zip(y) {
        let row = Vector3::new(1.0, x, x * x);
        ata += row * row.transpose();
        aty += row * v;
    }
    // Singular when the abscissae take fewer than three distinct values
    // (relative to their [0, 1] scale).
    let n = u.len() as Real;
    let det = ata.determinant() / (n * n * n);
    if u.len() < 3 || det.is_nan() || det <= 1e-12 {
        return None;
    }
    let chol = ata.cholesky()?;
    let b = chol.solve(&aty);
    if !b.iter().all(|v| v.is_finite()) {
        return None;
    }
    let mse = u
        .iter()
        .zip(y)
        .map(|(&x, &v)| {
            let r = v - (b[0] + b[1] * x + b[2] * x * x);
            r * r
        })
        .sum::<Real>()
        / u.len() as Real;
    Some(([b[0], b[1], b[2]], mse))
}

/// [`quadratic_fit`] of the means of `bins` equal bins of `u ∈ [0, 1]`
/// (every non-empty bin weighs the same, whatever its number of returns),
/// with the MSE over all returns; `bins = 0` fits the returns directly.
fn binned_quadratic_fit(u: &[Real], y: &[Real], bins: usize) -> Option<([Real; 3], Real)> {
    if bins == 0 {
        return quadratic_fit(u, y);
    }
    let mut sum_u = vec![0.0; bins];
    let mut sum_y = vec![0.0; bins];
    let mut count = vec![0usize; bins];
    for (&x, &v) in u.iter().zip(y) {
        let b = ((x * bins as Real) as usize).min(bins - 1);
        sum_u[b] += x;
        sum_y[b] += v;
        count[b] += 1;
    }
    let (mu, my): (Vec<Real>, Vec<Real>) = (0..bins)
        .filter(|&b| count[b] > 0)
        .map(|b| (sum_u[b] / count[b] as Real, sum_y[b] / count[b] as Real))
        .unzip();
    let (b, _) = quadratic_fit(&mu, &my)?;
    let mse = u
        .iter()
        .zip(y)
        .map(|(&x, &v)| {
            let r = v - (b[0] + b[1] * x + b[2] * x * x);
            r * r
        })
        .sum::<Real>()
        / u.len() as Real;
    Some((b, mse))
}

/// Features of an observation, with the constraints of `cfg` enforced (see
/// the [module docs](self) for the steps).
pub fn extract_features(
    obs: &Observation,
    cfg: &LrcConfig,
) -> Result<(Features, PatchGeometry), ClassifyError> {
    let window = cfg.fit_window_deg.to_radians();
    let too_few = |found| ClassifyError::TooFewPoints {
        found,
        needed: cfg.min_points,
        window_deg: cfg.fit_window_deg,
    };
    let n = obs.returns.len();
    if n < cfg.min_points.max(3) {
        return Err(too_few(n));
    }
    let finite3 = |v: &Vector3| v.x.is_finite() && v.y.is_finite() && v.z.is_finite();
    for (index, r) in obs.returns.iter().enumerate() {
        let field = if !finite3(&r.origin.coords) {
            Some("origin")
        } else if !finite3(&r.direction) || (r.direction.norm() - 1.0).abs() > 1e-6 {
            Some("direction")
        } else if !(r.range_m.is_finite() && r.range_m > 0.0) {
            Some("range_m")
        } else if !(r.intensity.is_finite() && r.intensity >= 0.0) {
            Some("intensity")
        } else {
            None
        };
        if let Some(field) = field {
            return Err(ClassifyError::InvalidReturn { index, field });
        }
    }
    if let Some(t) = obs.target
        && !finite3(&t.coords)
    {
        return Err(ClassifyError::InvalidReturn {
            index: 0,
            field: "target",
        });
    }

    // 1. Plane of the patch (PCA about the centroid, relative to the first
    //    point for precision), normal toward the sensors.
    let base = obs.returns[0].point();
    let offsets: Vec<Vector3> = obs.returns.iter().map(|r| r.point() - base).collect();
    let origin =
        Point3::from(obs.returns.iter().map(|r| r.origin.coords).sum::<Vector3>() / n as Real);
    let pca = Pca::of_offsets(&offsets).ok_or(ClassifyError::Degenerate)?;
    let centroid = base + pca.centroid.coords;
    let (mid, top) = (pca.eigenvalues[1], pca.eigenvalues[2]);
    if mid.is_nan() || mid <= 1e-12 * top.max(1e-300) {
        return Err(ClassifyError::Degenerate);
    }
    let mut normal: Vector3 = pca.axes[0].into_inner();
    if normal.dot(&(origin - centroid)) < 0.0 {
        normal = -normal;
    }
    let normal = geom::unit(normal).ok_or(ClassifyError::Degenerate)?;
    // A single scan line fits "the plane" of the scan itself, which contains
    // the sensor: no surface patch to speak of.
    let to_origin = origin - centroid;
    if normal.dot(&to_origin) < 0.1 * to_origin.norm() {
        return Err(ClassifyError::Degenerate);
    }

    // 2. Range and incidence at the target (projected onto the plane).
    let target = obs.target.unwrap_or(centroid);
    let target = target - normal.into_inner() * (target - centroid).dot(&normal);
    let to_sensor = origin - target;
    let range_m = to_sensor.norm();
    if !(cfg.min_range_m..=cfg.max_range_m).contains(&range_m) {
        return Err(ClassifyError::OutOfRange {
            range_m,
            min_m: cfg.min_range_m,
            max_m: cfg.max_range_m,
        });
    }
    let incidence_rad = (to_sensor.dot(&normal) / range_m).clamp(-1.0, 1.0).acos();
    if incidence_rad.to_degrees() >= cfg.max_incidence_deg {
        return Err(ClassifyError::TooOblique {
            incidence_deg: incidence_rad.to_degrees(),
            max_deg: cfg.max_incidence_deg,
        });
    }

    // 3. Per-return incidence, plane range, range error, compensated intensity.
    let mut u = Vec::with_capacity(n);
    let mut intensity = Vec::with_capacity(n);
    let mut range_error = Vec::with_capacity(n);
    let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
    for r in &obs.returns {
        let cos = -r.direction.dot(&normal);
        if cos <= 1e-9 {
            continue; // the ray runs away from the fitted plane
        }
        let phi = cos.min(1.0).acos();
        if phi > window {
            continue;
        }
        let plane_range = (centroid - r.origin).dot(&normal) / -cos;
        if plane_range.is_nan() || plane_range <= 0.0 {
            continue;
        }
        lo = lo.min(phi);
        hi = hi.max(phi);
        u.push(phi / window);
        let k = plane_range / cfg.reference_range_m;
        intensity.push(r.intensity * k * k);
        range_error.push(r.range_m - plane_range);
    }
    if u.len() < cfg.min_points {
        return Err(too_few(u.len()));
    }
    let span = hi - lo;
    if span.to_degrees() < cfg.min_span_deg {
        return Err(ClassifyError::NarrowIncidence {
            span_deg: span.to_degrees(),
            needed_deg: cfg.min_span_deg,
        });
    }

    // 4. Second-order fits; coefficients back in per-rad² units.
    let (bi, mse_i) =
        binned_quadratic_fit(&u, &intensity, cfg.fit_bins).ok_or(ClassifyError::Degenerate)?;
    let (br, mse_r) =
        binned_quadratic_fit(&u, &range_error, cfg.fit_bins).ok_or(ClassifyError::Degenerate)?;
    let w2 = window * window;
    Ok((
        Features {
            intensity_quadratic: bi[2] / w2,
            intensity_mse: mse_i,
            range_quadratic: br[2] / w2,
            range_mse: mse_r,
        },
        PatchGeometry {
            normal,
            range_m,
            incidence_rad,
            points_used: u.len(),
            incidence_span_rad: (lo, hi),
        },
    ))
}

/// Number of regressors of the coverage-conditioned mean (see [`MaterialModel`]).
pub const COVERAGE_TERMS: usize = 4;

/// The regressors `g = (1, l, l², h)` of an incidence coverage `(l, h)` (the
/// smallest and largest fitted incidence, as fractions of the fit window).
fn coverage_terms(coverage_rad: (Real, Real), window_rad: Real) -> [Real; COVERAGE_TERMS] {
    let l = coverage_rad.0 / window_rad;
    let h = coverage_rad.1 / window_rad;
    [1.0, l, l * l, h]
}

/// One material's feature density: a Gaussian over the standardised
/// [`Features::model_vector`] whose mean depends linearly on the incidence
/// coverage of the observation, `x ~ N(Bᵀ g(l, h), Σ)`.
///
/// A pose that sees the surface only from 12° to 20° samples the outer part
/// of the curves, and its quadratic coefficients differ from those of a pose
/// that sees 0°–20°: the coverage is known from the observation's geometry,
/// so the density is conditioned on it rather than blurred over it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialModel {
    /// Material name.
    pub name: String,
    /// Mean coefficients `B`: row `t` multiplies regressor `g_t`.
    pub coefficients: [[Real; 4]; COVERAGE_TERMS],
    /// Inverse of the residual covariance `Σ`, row-major.
    pub inverse_covariance: [[Real; 4]; 4],
    /// `ln det Σ`.
    pub log_det: Real,
    /// Training observations it was fitted to.
    pub samples: usize,
}

impl MaterialModel {
    /// The mean feature vector for coverage regressors `g`.
    fn mean(&self, g: &[Real; COVERAGE_TERMS]) -> [Real; 4] {
        std::array::from_fn(|k| {
            (0..COVERAGE_TERMS)
                .map(|t| g[t] * self.coefficients[t][k])
                .sum()
        })
    }

    /// `ln p(x | g)` up to the constant shared by all materials.
    fn log_likelihood(&self, x: &[Real; 4], g: &[Real; COVERAGE_TERMS]) -> Real {
        let mean = self.mean(g);
        let d: [Real; 4] = std::array::from_fn(|i| x[i] - mean[i]);
        let mut q = 0.0;
        for (i, row) in self.inverse_covariance.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                q += d[i] * v * d[j];
            }
        }
        -0.5 * (q + self.log_det)
    }
}

/// One training observation: its features and the incidence coverage of
/// its fitted returns ([`PatchGeometry::incidence_span_rad`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainingSample {
    /// The four features.
    pub features: Features,
    /// Smallest and largest fitted incidence, radians.
    pub coverage_rad: (Real, Real),
}

/// The result of a classification.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Classification {
    /// Posterior probability of each material (sums to 1), in the order of
    /// the materials the classifier was trained on.
    pub posterior: Vec<Real>,
    /// The features the posterior came from.
    pub features: Features,
    /// The estimated patch geometry.
    pub geometry: PatchGeometry,
}

impl Classification {
    /// Index of the most probable material (ties: the lowest index).
    pub fn best(&self) -> usize {
        let mut best = 0;
        for (i, &p) in self.posterior.iter().enumerate() {
            if p > self.posterior[best] {
                best = i;
            }
        }
        best
    }
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
            object: Some(0),
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

/// The trained Laser Range Classifier.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Lrc {
    /// Constraints and fitting parameters used for classification.
    pub config: LrcConfig,
    /// Per-feature offset and scale of the standardisation.
    pub feature_mean: [Real; 4],
    /// Per-feature scale of the standardisation.
    pub feature_scale: [Real; 4],
    /// One density per material, in material order.
    pub materials: Vec<MaterialModel>,
}

impl Lrc {
    /// Fit the per-material densities to training samples: `samples[m]`
    /// holds the observations of material `m`, named `names[m]`. Features are
    /// standardised over all samples; each material gets the least-squares
    /// coverage-conditioned mean and the residual covariance (plus `ridge` on
    /// the diagonal) of its samples ([`MaterialModel`]). Needs at least 10
    /// samples per material.
    pub fn fit(
        config: LrcConfig,
        names: &[String],
        samples: &[Vec<TrainingSample>],
        ridge: Real,
    ) -> Result<Self, LrcError> {
        config.validate()?;
        if names.len() != samples.len() || names.is_empty() {
            return Err(LrcError::Config {
                field: "materials",
                expected: "one sample set per material name, at least one material",
                got: format!("{} names, {} sample sets", names.len(), samples.len()),
            });
        }
        if !(ridge.is_finite() && ridge >= 0.0) {
            return Err(LrcError::Config {
                field: "ridge",
                expected: "a finite value ≥ 0",
                got: ridge.to_string(),
            });
        }
        let window = config.fit_window_deg.to_radians();
        for (name, s) in names.iter().zip(samples) {
            if s.len() < 10 {
                return Err(LrcError::Training {
                    material: name.clone(),
                    message: format!("{} samples, need at least 10", s.len()),
                });
            }
            let finite = |t: &TrainingSample| {
                t.features.model_vector().iter().all(|v| v.is_finite())
                    && t.coverage_rad.0.is_finite()
                    && t.coverage_rad.1.is_finite()
            };
            if !s.iter().all(finite) {
                return Err(LrcError::Training {
                    material: name.clone(),
                    message: "a training sample is not finite".into(),
                });
            }
        }
        let all: Vec<[Real; 4]> = samples
            .iter()
            .flatten()
            .map(|t| t.features.model_vector())
            .collect();
        let count = all.len() as Real;
        let feature_mean: [Real; 4] =
            std::array::from_fn(|k| all.iter().map(|x| x[k]).sum::<Real>() / count);
        let feature_scale: [Real; 4] = std::array::from_fn(|k| {
            let var = all
                .iter()
                .map(|x| (x[k] - feature_mean[k]).powi(2))
                .sum::<Real>()
                / count;
            if var > 0.0 { var.sqrt() } else { 1.0 }
        });
        let mut materials = Vec::with_capacity(names.len());
        for (name, s) in names.iter().zip(samples) {
            let rows = s.len();
            let g = nalgebra::DMatrix::<Real>::from_fn(rows, COVERAGE_TERMS, |r, t| {
                coverage_terms(s[r].coverage_rad, window)[t]
            });
            let x = nalgebra::DMatrix::<Real>::from_fn(rows, 4, |r, k| {
                (s[r].features.model_vector()[k] - feature_mean[k]) / feature_scale[k]
            });
            // Least squares B = (GᵀG + εI)⁻¹ GᵀX (a tiny ε keeps a set of
            // identical coverages solvable: the mean is then constant).
            let gtg = g.transpose() * &g
                + nalgebra::DMatrix::<Real>::identity(COVERAGE_TERMS, COVERAGE_TERMS) * 1e-9;
            let chol = gtg.cholesky().ok_or_else(|| LrcError::Training {
                material: name.clone(),
                message: "the coverage regressors are degenerate".into(),
            })?;
            let b = chol.solve(&(g.transpose() * &x));
            let residual = &x - &g * &b;
            let dof = (rows - COVERAGE_TERMS).max(1) as Real;
            let mut cov =
                Matrix4::<Real>::from_fn(|i, j| residual.column(i).dot(&residual.column(j)) / dof);
            cov += Matrix4::identity() * ridge;
            let chol = cov.cholesky().ok_or_else(|| LrcError::Training {
                material: name.clone(),
                message: "the feature covariance is singular (add a ridge)".into(),
            })?;
            let log_det = 2.0 * chol.l().diagonal().iter().map(|v| v.ln()).sum::<Real>();
            let inv = chol.inverse();
            materials.push(MaterialModel {
                name: name.clone(),
                coefficients: std::array::from_fn(|t| std::array::from_fn(|k| b[(t, k)])),
                inverse_covariance: std::array::from_fn(|i| std::array::from_fn(|j| inv[(i, j)])),
                log_det,
                samples: rows,
            });
        }
        Ok(Self {
            config,
            feature_mean,
            feature_scale,
            materials,
        })
    }

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
                    });
                }
            }
            samples.push(s);
        }
        let names: Vec<String> = materials.iter().map(|m| m.name.clone()).collect();
        Self::fit(config, &names, &samples, training.ridge)
    }

    /// Material names, in posterior order.
    pub fn material_names(&self) -> Vec<&str> {
        self.materials.iter().map(|m| m.name.as_str()).collect()
    }

    /// The posterior over materials of features observed with the given
    /// incidence coverage (uniform prior).
    pub fn posterior(
        &self,
        features: &Features,
        coverage_rad: (Real, Real),
    ) -> Result<Vec<Real>, ClassifyError> {
        let x = features.model_vector();
        let z: [Real; 4] =
            std::array::from_fn(|k| (x[k] - self.feature_mean[k]) / self.feature_scale[k]);
        let g = coverage_terms(coverage_rad, self.config.fit_window_deg.to_radians());
        let log: Vec<Real> = self
            .materials
            .iter()
            .map(|m| m.log_likelihood(&z, &g))
            .collect();
        let top = log.iter().copied().fold(Real::NEG_INFINITY, Real::max);
        if !top.is_finite() {
            return Err(ClassifyError::NonFiniteFeatures);
        }
        let w: Vec<Real> = log.iter().map(|l| (l - top).exp()).collect();
        let sum: Real = w.iter().sum();
        Ok(w.into_iter().map(|v| v / sum).collect())
    }

    /// Classify an observation under this classifier's constraints.
    pub fn classify(&self, obs: &Observation) -> Result<Classification, ClassifyError> {
        self.classify_with(obs, &self.config)
    }

    /// Classify under other constraints (e.g. [`LrcConfig::permissive`], to
    /// see how the classifier fares outside its validity domain).
    pub fn classify_with(
        &self,
        obs: &Observation,
        config: &LrcConfig,
    ) -> Result<Classification, ClassifyError> {
        let (features, geometry) = extract_features(obs, config)?;
        Ok(Classification {
            posterior: self.posterior(&features, geometry.incidence_span_rad)?,
            features,
            geometry,
        })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadratic_fit_recovers_a_parabola() {
        let u: Vec<Real> = (0..50).map(|i| i as Real / 49.0).collect();
        let y: Vec<Real> = u.iter().map(|x| 3.0 - 2.0 * x + 0.5 * x * x).collect();
        let (b, mse) = quadratic_fit(&u, &y).unwrap_or(([0.0; 3], 1.0));
        assert!(
            (b[0] - 3.0).abs() < 1e-9 && (b[1] + 2.0).abs() < 1e-9 && (b[2] - 0.5).abs() < 1e-9
        );
        assert!(mse < 1e-20);
        assert!(quadratic_fit(&[0.5; 10], &[1.0; 10]).is_none());
    }

    #[test]
    fn config_defaults_follow_table_6_1() {
        let c = LrcConfig::default();
        assert_eq!(
            (c.min_range_m, c.max_range_m, c.max_incidence_deg),
            (0.25, 0.8, 42.0)
        );
        assert_eq!(c.fit_window_deg, 20.0);
        assert!(c.validate().is_ok());
        assert!(LrcConfig::permissive().validate().is_ok());
        assert!(
            LrcConfig {
                max_range_m: 0.1,
                ..c
            }
            .validate()
            .is_err()
        );
    }
}
