//! Parameters of the surface model (P§2.3, P§4.3) and the tolerances derived from
//! them.

use crate::error::SurfaceError;
use geom::Real;
use serde::{Deserialize, Serialize};

/// Default of [`SurfaceConfig::max_set_points`].
pub const DEFAULT_MAX_SET_POINTS: usize = 4096;

/// Most points [`SurfaceConfig::max_set_points`] may allow: a set's update
/// grows with the square of its points (16 384 points update in seconds;
/// 200 000 did not finish).
pub const MAX_SET_POINTS_CEILING: usize = 16_384;

/// Largest λ accepted, metres: the resolution of a model of a structure a
/// robot follows, not of a landscape.
pub const MAX_LAMBDA_M: Real = 10.0;

/// Smallest λ accepted, metres: below a millimetre, under the range
/// finders' noise, every reading stays a point segment of its own (issue 48:
/// λ = 10⁻¹² gave 600 point segments without a word).
pub const MIN_LAMBDA_M: Real = 1e-3;

/// Parameters of the surface model. Defaults are Pudney's (P§4.3): λ = 0.05,
/// μ = 10°, ψ = 20, φ = 0.05.
///
/// ```
/// use surface::SurfaceConfig;
/// let fine = SurfaceConfig { lambda: 0.02, ..SurfaceConfig::default() };
/// assert_eq!(fine.mu_deg, 10.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SurfaceConfig {
    /// Linear resolution λ, metres (P§2.3): gaps narrower than λ are filled, and
    /// points must lie within λ (as a standard deviation, `s² < λ²`) of the point
    /// or plane that represents them (P§2.2).
    pub lambda: Real,
    /// Angular resolution μ, degrees (P§2.3): planar polygons whose outward
    /// normals differ by less than μ may merge; by more than μ they may share edges.
    pub mu_deg: Real,
    /// Redundancy count threshold ψ (P§2.9): when a failed attempt to share edges
    /// between non-neighbours `S₁`, `S₂` (`n₁ < n₂` points) leaves `S₁` suspect,
    /// `S₁` is redundant if `n₁ < ψ` and `n₁/n₂ < φ`.
    pub psi: Real,
    /// Redundancy ratio threshold φ (P§2.9): the `n₁/n₂ < φ` half of the test
    /// above, a ratio of point counts (not a distance).
    pub phi: Real,
    /// Collinearity threshold as a fraction of λ (P§2.2 "collinear → point"):
    /// points whose spread across their principal axis, `√u₂`, is below
    /// `collinear_fraction · λ`, or below twice their spread off the plane
    /// (`√u₂ < 2√u₁`, no well-defined plane), are represented by a point segment.
    pub collinear_fraction: Real,
    /// Most points one sensor set may hold; [`SurfaceModel::update`](crate::SurfaceModel::update)
    /// and [`read_sets_jsonl_limited`](crate::read_sets_jsonl_limited) refuse
    /// bigger sets. An update's time grows with the set's size and, because
    /// every point first becomes a segment, faster than linearly when many
    /// points fall within λ of each other: 4 096 points dense on 1 m² take about
    /// 0.8 s, 100 000 about 45 s (release build). The default, 4 096, is 150
    /// times Pudney's 26-sensor sets (P§4.3) and five URG-04LX scan lines.
    pub max_set_points: usize,
    /// The order in which a new point segment tries its merger candidates
    /// (P§2.3 step 2(a)).
    pub merge_order: MergeOrder,
    /// Our addition (issue 45), off by default: when a shared edge between
    /// segments that share none yet would be refused only because the
    /// perimeter it leaves is not valid, a section end vertex within
    /// `λ·10⁻²` of its point on the line is moved onto the line and ends
    /// the shared edge (see [`crate::share`]). Without it a vertex a few
    /// `λ·10⁻⁴` off the line would be joined to its projection by an edge
    /// shorter than the perimeters' separation tolerance allows, and the
    /// pair can stay without a shared edge (the scripted noisy cube, seed 3).
    /// Off by default because it changes the models the follower builds
    /// (`crates/surface/README.md` measures it).
    pub snap_near_line_ends: bool,
}

/// The order in which a new point segment tries the segments near it for a
/// merger (P§2.3 step 2(a)). Pudney processed them "in the order in which they
/// are stored in memory", having said that the operation yielding the best
/// result, the shortest gap first, should be tried first but is too costly
/// to find (P§2.3). For a point and the polygons near it the shortest gap is
/// cheap: the distance to each plane.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MergeOrder {
    /// The polygons nearest the point's plane first (ties and everything else
    /// in id order). Our rule, the default: where two faces meet at a fold of
    /// less than about 45°, a point near the fold lies within λ of both
    /// planes and of a polygon that straddles the fold; in id order it joined
    /// whichever polygon was oldest, which let a straddling polygon grow over
    /// both faces (block2's 30° chamfer and its top fused at a plane between
    /// them). Nearest first, each point joins its own face.
    #[default]
    NearestPlane,
    /// Id order, oldest first (P§2.3: the order of storage).
    Thesis,
}

impl Default for SurfaceConfig {
    fn default() -> Self {
        Self {
            lambda: 0.05,
            mu_deg: 10.0,
            psi: 20.0,
            phi: 0.05,
            collinear_fraction: 0.1,
            max_set_points: DEFAULT_MAX_SET_POINTS,
            merge_order: MergeOrder::default(),
            snap_near_line_ends: false,
        }
    }
}

impl SurfaceConfig {
    /// Pudney's parameters with a different linear resolution λ.
    pub fn with_lambda(lambda: Real) -> Self {
        Self {
            lambda,
            ..Self::default()
        }
    }

    /// Check every field's range.
    pub fn validate(&self) -> Result<(), SurfaceError> {
        let bad = |field: &'static str, value: Real, expected: &'static str| {
            Err(SurfaceError::Config {
                field,
                value,
                expected,
            })
        };
        if !(self.lambda.is_finite() && (MIN_LAMBDA_M..=MAX_LAMBDA_M).contains(&self.lambda)) {
            return bad("lambda", self.lambda, "a length in [0.001, 10] metres");
        }
        if !(self.mu_deg.is_finite() && self.mu_deg > 0.0 && self.mu_deg < 90.0) {
            return bad("mu_deg", self.mu_deg, "an angle in (0, 90) degrees");
        }
        if !(self.psi.is_finite() && self.psi >= 0.0) {
            return bad("psi", self.psi, "a finite count >= 0");
        }
        if !(self.phi.is_finite() && self.phi >= 0.0) {
            return bad("phi", self.phi, "a finite ratio >= 0");
        }
        if !(self.collinear_fraction.is_finite()
            && self.collinear_fraction > 0.0
            && self.collinear_fraction < 1.0)
        {
            return bad(
                "collinear_fraction",
                self.collinear_fraction,
                "a fraction in (0, 1)",
            );
        }
        if self.max_set_points == 0 || self.max_set_points > MAX_SET_POINTS_CEILING {
            return bad(
                "max_set_points",
                self.max_set_points as Real,
                "a count from 1 to 16384",
            );
        }
        Ok(())
    }
}

/// Tolerances derived from λ and μ. Every geometric decision in the crate uses one
/// of these, never a bare constant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Tolerances {
    /// λ.
    pub lambda: Real,
    /// cos μ: normals closer than μ satisfy `n₁·n₂ > cos_mu`.
    pub cos_mu: Real,
    /// Coincidence length `λ·10⁻⁴`: two points closer than this are the same
    /// vertex; perimeters must keep non-adjacent edges farther apart than this and
    /// every edge longer than this (simplicity); contacts within it at the ends of
    /// a sight line do not block sight.
    pub eps: Real,
    /// Placement tolerance `max(λ·10⁻⁵, 10⁻⁹)`: vertices lie this close to their
    /// plane, shared-edge vertices to their intersection line, corner vertices to
    /// their corner point. Placement is exact up to rounding, so this only absorbs
    /// floating-point error.
    pub place: Real,
    /// Separation of a duplicated vertex (P§2.8): `λ·10⁻²`, capped at a quarter of
    /// the adjoining edges.
    pub split: Real,
    /// Collinearity: the middle covariance eigenvalue must reach
    /// `(collinear_fraction·λ)²` for a plane.
    pub min_spread_sq: Real,
    /// `sin(μ/2)`: planes whose normals are closer than μ/2 to parallel or
    /// antiparallel have no usable intersection line for shared edges (P§2.4.4
    /// dissolves 180° neighbours; the same guard protects near-0° ones).
    pub sin_parallel: Real,
    /// `sin μ`: a new plane must not contain its points' summed sensing axis to
    /// within μ (P§2.4.1: the outside must be decidable).
    pub sin_mu: Real,
    /// Sine of the smallest angle between two intersection lines that still
    /// defines a corner point (P§2.7 "must not be parallel"): `10⁻³`.
    pub sin_corner: Real,
    /// Collinearity length `collinear_fraction·λ` (P§2.2): perimeter vertices
    /// closer than this to the edge joining their neighbours are removed
    /// (see [`crate::fissure`]).
    pub collinear: Real,
    /// ψ (P§2.9) as a point count: a polygon representing fewer points is still
    /// "developing"; its initial plane follows its plane of best fit (see
    /// [`crate::merge`]).
    pub psi: Real,
}

impl Tolerances {
    pub fn new(config: &SurfaceConfig) -> Self {
        let lambda = config.lambda;
        let mu = config.mu_deg.to_radians();
        let spread = config.collinear_fraction * lambda;
        Self {
            lambda,
            cos_mu: mu.cos(),
            eps: lambda * 1e-4,
            place: (lambda * 1e-5).max(1e-9),
            split: lambda * 1e-2,
            min_spread_sq: spread * spread,
            sin_parallel: (0.5 * mu).sin(),
            sin_mu: mu.sin(),
            sin_corner: 1e-3,
            collinear: spread,
            psi: config.psi,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_pudneys() {
        let c = SurfaceConfig::default();
        assert_eq!((c.lambda, c.mu_deg, c.psi, c.phi), (0.05, 10.0, 20.0, 0.05));
        assert!(c.validate().is_ok());
        assert!(SurfaceConfig::with_lambda(-1.0).validate().is_err());
        // Issue 48: a λ of 10⁻¹² was taken as it was.
        let e = SurfaceConfig::with_lambda(1e-12)
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("lambda") && e.contains("[0.001, 10]"), "{e}");
        assert!(SurfaceConfig::with_lambda(MIN_LAMBDA_M).validate().is_ok());
        let t: SurfaceConfig = serde_json::from_str(r#"{"lambda": 0.02}"#).unwrap();
        assert_eq!(t.lambda, 0.02);
        assert_eq!(t.psi, 20.0);
        assert!(serde_json::from_str::<SurfaceConfig>(r#"{"lamda": 0.02}"#).is_err());
    }
}
