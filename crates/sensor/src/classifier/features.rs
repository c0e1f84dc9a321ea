//! Observation → features (Paul App. B): the returns on a target patch, the
//! patch's plane, range and incidence, and the second-order fits of intensity
//! and range error versus incidence whose coefficients and residuals are the
//! LRC's four features.

use super::{ClassifyError, LrcConfig};
use crate::sweep::Sweep;
use geom::{Matrix3, Pca, Point3, Real, UnitVector3, Vector3};
use serde::{Deserialize, Serialize};

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
    /// Root-mean-square distance of the observation's points from its
    /// fitted plane, metres: the range noise alone on a flat patch, more
    /// where the patch takes in an edge, a corner or a curved surface.
    pub plane_rms_m: Real,
}

/// Least-squares `y = b₀ + b₁u + b₂u²`; returns `(b, mse)`.
pub(super) fn quadratic_fit(u: &[Real], y: &[Real]) -> Option<([Real; 3], Real)> {
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

/// The patch's plane and the target's range and incidence (steps 1 and 2
/// of [`extract_features`]), with the observation's returns checked.
struct Patch {
    centroid: Point3,
    normal: UnitVector3,
    range_m: Real,
    incidence_rad: Real,
    plane_rms_m: Real,
}

/// The returns checked, then steps 1 and 2 of [`extract_features`] with
/// their constraints.
fn plane_of(obs: &Observation, cfg: &LrcConfig) -> Result<Patch, ClassifyError> {
    let n = obs.returns.len();
    if n < cfg.min_points.max(3) {
        return Err(too_few(n, cfg));
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
    Ok(Patch {
        centroid,
        normal,
        range_m,
        incidence_rad,
        plane_rms_m: pca.eigenvalues[0].max(0.0).sqrt(),
    })
}

fn too_few(found: usize, cfg: &LrcConfig) -> ClassifyError {
    ClassifyError::TooFewPoints {
        found,
        needed: cfg.min_points,
        window_deg: cfg.fit_window_deg,
    }
}

/// The distance from `r`'s origin to the plane along its ray, when the ray
/// meets the plane in front of it (step 3's test of a return).
fn plane_range(r: &ObservedReturn, plane: &Patch, cos: Real) -> Option<Real> {
    let range = (plane.centroid - r.origin).dot(&plane.normal) / -cos;
    (!range.is_nan() && range > 0.0).then_some(range)
}

/// Whether the returns of `obs` inside the fit window are enough, and span
/// enough incidence, for the fits (what [`extract_features`] decides,
/// without the features): `Ok` exactly when its steps 1–3 pass. The window
/// test compares cosines (an arc cosine only within 10⁻⁹ of the window's
/// edge) and stops as soon as both counts are met.
pub(super) fn check_window(obs: &Observation, cfg: &LrcConfig) -> Result<Real, ClassifyError> {
    let plane = plane_of(obs, cfg)?;
    let window = cfg.fit_window_deg.to_radians();
    let cos_window = window.cos();
    let inside = |cos: Real| {
        if cos > cos_window + 1e-9 {
            true
        } else if cos < cos_window - 1e-9 {
            false
        } else {
            cos.min(1.0).acos() <= window
        }
    };
    // The incidence span from the extreme cosines (acos decreases).
    let span_deg =
        |lo_cos: Real, hi_cos: Real| (lo_cos.min(1.0).acos() - hi_cos.min(1.0).acos()).to_degrees();
    let (mut used, mut lo_cos, mut hi_cos) = (0usize, Real::INFINITY, Real::NEG_INFINITY);
    for r in &obs.returns {
        let cos = -r.direction.dot(&plane.normal);
        if cos <= 1e-9 || !inside(cos) || plane_range(r, &plane, cos).is_none() {
            continue;
        }
        used += 1;
        lo_cos = lo_cos.min(cos);
        hi_cos = hi_cos.max(cos);
        if used >= cfg.min_points && used % 16 == 0 && span_deg(lo_cos, hi_cos) >= cfg.min_span_deg
        {
            return Ok(plane.plane_rms_m);
        }
    }
    if used < cfg.min_points {
        return Err(too_few(used, cfg));
    }
    let span = span_deg(lo_cos, hi_cos);
    if span < cfg.min_span_deg {
        return Err(ClassifyError::NarrowIncidence {
            span_deg: span,
            needed_deg: cfg.min_span_deg,
        });
    }
    Ok(plane.plane_rms_m)
}

/// Features of an observation, with the constraints of `cfg` enforced (see
/// the [module docs](crate::classifier) for the steps).
pub fn extract_features(
    obs: &Observation,
    cfg: &LrcConfig,
) -> Result<(Features, PatchGeometry), ClassifyError> {
    let plane = plane_of(obs, cfg)?;
    let window = cfg.fit_window_deg.to_radians();
    let n = obs.returns.len();

    // 3. Per-return incidence, plane range, range error, compensated intensity.
    let mut u = Vec::with_capacity(n);
    let mut intensity = Vec::with_capacity(n);
    let mut range_error = Vec::with_capacity(n);
    let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
    for r in &obs.returns {
        let cos = -r.direction.dot(&plane.normal);
        if cos <= 1e-9 {
            continue; // the ray runs away from the fitted plane
        }
        let phi = cos.min(1.0).acos();
        if phi > window {
            continue;
        }
        let Some(plane_range) = plane_range(r, &plane, cos) else {
            continue;
        };
        lo = lo.min(phi);
        hi = hi.max(phi);
        u.push(phi / window);
        let k = plane_range / cfg.reference_range_m;
        intensity.push(r.intensity * k * k);
        range_error.push(r.range_m - plane_range);
    }
    if u.len() < cfg.min_points {
        return Err(too_few(u.len(), cfg));
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
            normal: plane.normal,
            range_m: plane.range_m,
            incidence_rad: plane.incidence_rad,
            points_used: u.len(),
            incidence_span_rad: (lo, hi),
            plane_rms_m: plane.plane_rms_m,
        },
    ))
}

/// Number of regressors of the coverage-conditioned mean (see [`MaterialModel`](super::MaterialModel)).
pub const COVERAGE_TERMS: usize = 4;

/// The regressors `g = (1, l, l², h)` of an incidence coverage `(l, h)` (the
/// smallest and largest fitted incidence, as fractions of the fit window).
pub(super) fn coverage_terms(
    coverage_rad: (Real, Real),
    window_rad: Real,
) -> [Real; COVERAGE_TERMS] {
    let l = coverage_rad.0 / window_rad;
    let h = coverage_rad.1 / window_rad;
    [1.0, l, l * l, h]
}
