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
//!    squared residuals (MSE) of the two fits ([`Features`]);
//! 5. refuses a patch that is not flat: the RMS distance of its points from
//!    their plane ([`PatchGeometry::plane_rms_m`]) above the largest among
//!    the training observations ([`Lrc::plane_rms_limit_m`], times
//!    [`LrcConfig::max_plane_rms_ratio`]). App. B assumes the targeted
//!    surface flat; a patch over an edge, a corner, a second surface or a
//!    curve gives features of no material.
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
//! belief of the map consumes (Paul eq. 4.15). Features whose squared
//! Mahalanobis distance from every material's density exceeds
//! [`LrcConfig::max_mahalanobis_sq`] (χ²₄'s 99th percentile) are refused
//! ([`ClassifyError::Atypical`]): under a uniform prior the posterior of an
//! observation unlike every material still names one of them, confidently.
//! [`Lrc::check_geometry`] runs the geometric checks alone, to predict from
//! a simulated observation of the map whether a pose can serve the LRC;
//! [`Lrc::geometry_passes`] decides the same faster (no fits, and it stops
//! counting returns once there are enough), for the many such predictions
//! of Stage Two's choice.
//!
//! The fits weigh equal bins of incidence equally ([`LrcConfig::fit_bins`]),
//! so how densely a pose samples each incidence does not bend the curves.
//! An observation must hold the returns of several scans (a sweep, or part
//! of one): a single scan line does not define the patch's plane.
//!
//! # Training data
//!
//! [`Lrc::train`] simulates observations with the very scanner model the
//! simulator uses ([`Scanner::scan`](crate::Scanner::scan) with its [`ReflectionModel`](crate::ReflectionModel) and range
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

use geom::Real;
use nalgebra::Matrix4;
use serde::{Deserialize, Serialize};

mod cache;
mod features;
mod training;

pub use cache::{LRC_CACHE_FORMAT, LrcCacheOutcome};
use features::coverage_terms;
pub use features::{
    COVERAGE_TERMS, Features, Observation, ObservedReturn, PatchGeometry, extract_features,
};
pub use training::{ObservationSetup, TrainingConfig, TrainingSample, simulate_observation};

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
    /// Largest plane residual accepted, as a multiple of the largest one
    /// among the training observations ([`Lrc::plane_rms_limit_m`]): the
    /// features assume a flat patch of one surface, and a patch that takes
    /// in an edge, a corner, a second surface or a curve is not one.
    pub max_plane_rms_ratio: Real,
    /// Largest squared Mahalanobis distance of the features from the
    /// nearest material's density (χ² with 4 degrees of freedom for an
    /// observation like the training ones; 13.28 is its 99th percentile):
    /// features unlike every material's are refused rather than given to
    /// the least unlike one with a confident posterior.
    pub max_mahalanobis_sq: Real,
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
            max_plane_rms_ratio: 1.0,
            max_mahalanobis_sq: CHI2_4_P99,
        }
    }
}

/// The 99th percentile of χ² with 4 degrees of freedom.
pub const CHI2_4_P99: Real = 13.2767;

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
            max_plane_rms_ratio: Real::INFINITY,
            max_mahalanobis_sq: Real::INFINITY,
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
        if self.max_plane_rms_ratio.is_nan() || self.max_plane_rms_ratio < 1.0 {
            return bad(
                "max_plane_rms_ratio",
                "a ratio ≥ 1 (infinite: no limit)",
                self.max_plane_rms_ratio,
            );
        }
        if self.max_mahalanobis_sq.is_nan() || self.max_mahalanobis_sq <= 0.0 {
            return bad(
                "max_mahalanobis_sq",
                "a positive value (infinite: no limit)",
                self.max_mahalanobis_sq,
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
    /// The cache file of a trained model cannot be written
    /// ([`Lrc::load_or_train`]).
    #[error("LRC cache {path}: {message}")]
    Cache {
        /// The cache file.
        path: std::path::PathBuf,
        /// What went wrong.
        message: String,
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
    /// The patch is not flat: its points lie farther from their plane than
    /// those of any training observation.
    #[error(
        "the patch is not flat: {rms_m:.4} m RMS from its plane, the LRC accepts up to {limit_m:.4} m"
    )]
    NotFlat {
        /// RMS distance of the points from their plane, metres.
        rms_m: Real,
        /// The limit, metres.
        limit_m: Real,
    },
    /// The features are unlike every material's training observations.
    #[error(
        "the features are unlike every material (squared Mahalanobis distance {distance_sq:.1} to the nearest, limit {limit})"
    )]
    Atypical {
        /// Squared Mahalanobis distance to the nearest material's density.
        distance_sq: Real,
        /// The limit.
        limit: Real,
    },
    /// The points do not define a plane or a fit (collinear, singular).
    #[error("the returns do not define a plane and a fit")]
    Degenerate,
    /// The feature vector has no finite likelihood under any material.
    #[error("the features are not finite")]
    NonFiniteFeatures,
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

    /// The squared Mahalanobis distance of `x` from the mean at `g`.
    fn mahalanobis_sq(&self, x: &[Real; 4], g: &[Real; COVERAGE_TERMS]) -> Real {
        let mean = self.mean(g);
        let d: [Real; 4] = std::array::from_fn(|i| x[i] - mean[i]);
        let mut q = 0.0;
        for (i, row) in self.inverse_covariance.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                q += d[i] * v * d[j];
            }
        }
        q
    }
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
    /// Per material, the squared Mahalanobis distance of the features from
    /// its density's mean (χ² with 4 degrees of freedom for an observation
    /// of that material): how typical the observation is of each.
    pub mahalanobis_sq: Vec<Real>,
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
    /// The largest [`PatchGeometry::plane_rms_m`] among the training
    /// observations, metres (see [`LrcConfig::max_plane_rms_ratio`]).
    pub plane_rms_limit_m: Real,
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
                    && t.plane_rms_m.is_finite()
                    && t.plane_rms_m >= 0.0
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
        let plane_rms_limit_m = samples
            .iter()
            .flatten()
            .map(|t| t.plane_rms_m)
            .fold(0.0, Real::max);
        Ok(Self {
            config,
            feature_mean,
            feature_scale,
            materials,
            plane_rms_limit_m,
        })
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
        Ok(self.evaluate(features, coverage_rad)?.0)
    }

    /// The posterior (uniform prior) and each material's squared
    /// Mahalanobis distance.
    fn evaluate(
        &self,
        features: &Features,
        coverage_rad: (Real, Real),
    ) -> Result<(Vec<Real>, Vec<Real>), ClassifyError> {
        let x = features.model_vector();
        let z: [Real; 4] =
            std::array::from_fn(|k| (x[k] - self.feature_mean[k]) / self.feature_scale[k]);
        let g = coverage_terms(coverage_rad, self.config.fit_window_deg.to_radians());
        let q: Vec<Real> = self
            .materials
            .iter()
            .map(|m| m.mahalanobis_sq(&z, &g))
            .collect();
        // ln p(x | g) up to the constant shared by all materials.
        let log: Vec<Real> = self
            .materials
            .iter()
            .zip(&q)
            .map(|(m, q)| -0.5 * (q + m.log_det))
            .collect();
        let top = log.iter().copied().fold(Real::NEG_INFINITY, Real::max);
        if !top.is_finite() {
            return Err(ClassifyError::NonFiniteFeatures);
        }
        let w: Vec<Real> = log.iter().map(|l| (l - top).exp()).collect();
        let sum: Real = w.iter().sum();
        Ok((w.into_iter().map(|v| v / sum).collect(), q))
    }

    /// Classify an observation under this classifier's constraints.
    pub fn classify(&self, obs: &Observation) -> Result<Classification, ClassifyError> {
        self.classify_with(obs, &self.config)
    }

    /// The checks of [`Lrc::classify_with`] that depend on the geometry of
    /// the observation alone (range, incidence, returns and incidence span in
    /// the fit window, flatness), without the features' typicality: whether
    /// an observation of this shape could be classified at all. Used to
    /// predict, from a simulated observation of the map, whether a pose will
    /// give the LRC what it needs.
    pub fn check_geometry(
        &self,
        obs: &Observation,
        config: &LrcConfig,
    ) -> Result<PatchGeometry, ClassifyError> {
        let (_, geometry) = extract_features(obs, config)?;
        self.check_flat(geometry.plane_rms_m, config)?;
        Ok(geometry)
    }

    /// Whether [`Lrc::check_geometry`] passes, decided faster: the fit
    /// window's returns are counted (not fitted) and counting stops once
    /// there are enough of them over a wide enough incidence. The error, when
    /// there is one, is the first check that fails in this order, which may
    /// differ from `check_geometry`'s.
    pub fn geometry_passes(
        &self,
        obs: &Observation,
        config: &LrcConfig,
    ) -> Result<(), ClassifyError> {
        let plane_rms_m = features::check_window(obs, config)?;
        self.check_flat(plane_rms_m, config)
    }

    fn check_flat(&self, plane_rms_m: Real, config: &LrcConfig) -> Result<(), ClassifyError> {
        let limit_m = self.plane_rms_limit_m * config.max_plane_rms_ratio;
        if plane_rms_m > limit_m {
            return Err(ClassifyError::NotFlat {
                rms_m: plane_rms_m,
                limit_m,
            });
        }
        Ok(())
    }

    /// Classify under other constraints (e.g. [`LrcConfig::permissive`], to
    /// see how the classifier fares outside its validity domain).
    pub fn classify_with(
        &self,
        obs: &Observation,
        config: &LrcConfig,
    ) -> Result<Classification, ClassifyError> {
        let (features, geometry) = extract_features(obs, config)?;
        self.check_flat(geometry.plane_rms_m, config)?;
        let (posterior, mahalanobis_sq) = self.evaluate(&features, geometry.incidence_span_rad)?;
        let nearest = mahalanobis_sq
            .iter()
            .copied()
            .fold(Real::INFINITY, Real::min);
        if nearest > config.max_mahalanobis_sq {
            return Err(ClassifyError::Atypical {
                distance_sq: nearest,
                limit: config.max_mahalanobis_sq,
            });
        }
        Ok(Classification {
            posterior,
            features,
            geometry,
            mahalanobis_sq,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::features::quadratic_fit;
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
