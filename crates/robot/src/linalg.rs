//! Generalised inverses of Jacobians and the null-space projector (P§3.3).
//!
//! Pudney eq. 3 resolves a control-point motion `ẋ` into actuator changes
//!
//! ```text
//! θ̇ = J⁺ ẋ + α (I − J⁺ J) z
//! ```
//!
//! where `J⁺` is the Moore–Penrose pseudo-inverse ([`pseudo_inverse`]) and
//! `I − J⁺J` ([`null_space_projector`]) projects the reconfiguration vector `z`
//! onto the null space of `J`, so the second term moves the links without moving
//! the control point. Near singularities [`damped_pseudo_inverse`] trades a little
//! accuracy for bounded joint speeds.
//!
//! None of these functions panic: non-finite input gives a NaN-filled result of the
//! right shape, which callers detect with `iter().all(|v| v.is_finite())`.

use geom::Real;
use nalgebra::DMatrix;

/// Sweep cap of the one-sided Jacobi SVD (it converges in a handful of sweeps; the
/// cap only bounds pathological input).
const JACOBI_MAX_SWEEPS: usize = 100;

/// Default singular-value cut-off used when [`null_space_projector`] must
/// recompute a pseudo-inverse itself.
pub const DEFAULT_PINV_TOLERANCE: Real = 1e-10;

fn nan_matrix(rows: usize, cols: usize) -> DMatrix<Real> {
    DMatrix::from_element(rows, cols, Real::NAN)
}

/// One-sided (Hestenes) Jacobi SVD of a tall matrix `t` (r × c, r ≥ c): returns
/// `(G, W)` with `t W = G`, `W` orthogonal and the columns of `G` mutually
/// orthogonal, so `σ_i = ‖g_i‖` and `t = U Σ Wᵀ` with `u_i = g_i / σ_i`.
/// Chosen over bidiagonal QR for its high relative accuracy on small matrices.
fn jacobi_svd(t: &DMatrix<Real>) -> (DMatrix<Real>, DMatrix<Real>) {
    let (rows, cols) = t.shape();
    let mut g = t.clone();
    let mut w = DMatrix::<Real>::identity(cols, cols);
    for _ in 0..JACOBI_MAX_SWEEPS {
        let mut rotated = false;
        for p in 0..cols {
            for q in (p + 1)..cols {
                let (mut alpha, mut beta, mut gamma) = (0.0, 0.0, 0.0);
                for k in 0..rows {
                    let (a, b) = (g[(k, p)], g[(k, q)]);
                    alpha += a * a;
                    beta += b * b;
                    gamma += a * b;
                }
                if gamma == 0.0 || gamma.abs() <= Real::EPSILON * (alpha * beta).sqrt() {
                    continue;
                }
                rotated = true;
                let zeta = (beta - alpha) / (2.0 * gamma);
                let tan = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                let cos = 1.0 / (1.0 + tan * tan).sqrt();
                let sin = cos * tan;
                for m in [&mut g, &mut w] {
                    for k in 0..m.nrows() {
                        let (a, b) = (m[(k, p)], m[(k, q)]);
                        m[(k, p)] = cos * a - sin * b;
                        m[(k, q)] = sin * a + cos * b;
                    }
                }
            }
        }
        if !rotated {
            break;
        }
    }
    (g, w)
}

/// The Moore–Penrose pseudo-inverse `J⁺` (n × m for an m × n `j`) by a one-sided
/// Jacobi SVD; singular values at or below `tol` are treated as zero.
///
/// ```
/// use nalgebra::DMatrix;
/// let j = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.0, 0.0, 2.0, 0.0]);
/// let p = robot::pseudo_inverse(&j, 1e-12);
/// assert!((&j * &p - DMatrix::<f64>::identity(2, 2)).norm() < 1e-12);
/// ```
pub fn pseudo_inverse(j: &DMatrix<Real>, tol: Real) -> DMatrix<Real> {
    let (m, n) = j.shape();
    if m == 0 || n == 0 {
        return DMatrix::zeros(n, m);
    }
    if !j.iter().all(|v| v.is_finite()) {
        return nan_matrix(n, m);
    }
    // Work on the tall orientation t (r × c): t = U Σ Wᵀ, t⁺ = W Σ⁻² Gᵀ over the
    // kept singular values (G = U Σ).
    let wide = m < n;
    let t = if wide { j.transpose() } else { j.clone() };
    let (g, w) = jacobi_svd(&t);
    let mut t_pinv = DMatrix::zeros(t.ncols(), t.nrows());
    for i in 0..t.ncols() {
        let sigma_sq = g.column(i).norm_squared();
        if sigma_sq.sqrt() > tol {
            t_pinv += w.column(i) * g.column(i).transpose() / sigma_sq;
        }
    }
    if wide { t_pinv.transpose() } else { t_pinv }
}

/// The damped (Levenberg–Marquardt / singularity-robust) pseudo-inverse
/// `Jᵀ (J Jᵀ + λ² I)⁻¹` for an m × n `j` with m ≤ n, or the equal
/// `(Jᵀ J + λ² I)⁻¹ Jᵀ` when n < m (whichever system is smaller). Tends to
/// [`pseudo_inverse`] as `damping → 0` away from singularities; with zero damping at
/// a singularity it falls back to the SVD pseudo-inverse.
///
/// ```
/// use nalgebra::DMatrix;
/// let j = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.0, 0.0, 2.0, 0.0]);
/// let damped = robot::damped_pseudo_inverse(&j, 1e-6);
/// assert!((damped - robot::pseudo_inverse(&j, 1e-12)).norm() < 1e-9);
/// ```
pub fn damped_pseudo_inverse(j: &DMatrix<Real>, damping: Real) -> DMatrix<Real> {
    let (m, n) = j.shape();
    if m == 0 || n == 0 {
        return DMatrix::zeros(n, m);
    }
    if !(j.iter().all(|v| v.is_finite()) && damping.is_finite()) {
        return nan_matrix(n, m);
    }
    let l2 = damping * damping;
    let jt = j.transpose();
    let solved = if m <= n {
        let a = j * &jt + DMatrix::identity(m, m) * l2;
        // Jᵀ A⁻¹ = (A⁻¹ J)ᵀ since A is symmetric.
        a.cholesky().map(|c| c.solve(j).transpose())
    } else {
        let a = &jt * j + DMatrix::identity(n, n) * l2;
        a.cholesky().map(|c| c.solve(&jt))
    };
    solved.unwrap_or_else(|| pseudo_inverse(j, DEFAULT_PINV_TOLERANCE))
}

/// The null-space projector `I − J⁺ J` (n × n) of Pudney eq. 3, from `j` (m × n) and
/// its pseudo-inverse `j_pinv` (n × m). For the Moore–Penrose inverse it is
/// symmetric and idempotent and `J N = 0`.
///
/// If `j_pinv` does not have the shape n × m it is recomputed from `j` with
/// [`pseudo_inverse`] rather than panicking.
///
/// ```
/// use nalgebra::DMatrix;
/// let j = DMatrix::from_row_slice(1, 2, &[1.0, 1.0]);
/// let n = robot::null_space_projector(&j, &robot::pseudo_inverse(&j, 1e-12));
/// assert!((&j * &n).norm() < 1e-12);
/// ```
pub fn null_space_projector(j: &DMatrix<Real>, j_pinv: &DMatrix<Real>) -> DMatrix<Real> {
    let (m, n) = j.shape();
    if j_pinv.shape() == (n, m) {
        DMatrix::identity(n, n) - j_pinv * j
    } else {
        DMatrix::identity(n, n) - pseudo_inverse(j, DEFAULT_PINV_TOLERANCE) * j
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The four Penrose conditions, to `tol`.
    fn penrose(j: &DMatrix<Real>, p: &DMatrix<Real>, tol: Real) {
        assert!((j * p * j - j).amax() < tol, "J J⁺ J ≠ J");
        assert!((p * j * p - p).amax() < tol, "J⁺ J J⁺ ≠ J⁺");
        assert!(
            ((j * p).transpose() - j * p).amax() < tol,
            "J J⁺ not symmetric"
        );
        assert!(
            ((p * j).transpose() - p * j).amax() < tol,
            "J⁺ J not symmetric"
        );
    }

    #[test]
    #[allow(clippy::unreadable_literal)] // digits as printed from the failing case
    fn penrose_conditions_to_full_precision() {
        // A VM-6083 flange position Jacobian on which nalgebra 0.34's bidiagonal SVD
        // reconstructs only to ~1e-9; the Jacobi SVD holds to rounding.
        let j = DMatrix::from_row_slice(
            3,
            6,
            &[
                0.06685060099773615,
                -0.15669468357490998,
                0.21972684596530354,
                0.02958574991044695,
                0.02100266556176374,
                0.0,
                -0.693261845939722,
                -0.027629500447832335,
                0.038743771329655716,
                0.032696369720762314,
                0.056337284342431786,
                0.0,
                0.0,
                -0.5143381257881889,
                -0.46822499433783327,
                -0.041994600663075664,
                0.05866002414098288,
                0.0,
            ],
        );
        penrose(&j, &pseudo_inverse(&j, 1e-10), 1e-13);
        let t = j.transpose();
        penrose(&t, &pseudo_inverse(&t, 1e-10), 1e-13);
        // Pseudo-random square, wide and tall matrices.
        let mut x: Real = 0.5;
        let mut next = || {
            x = (x * 3.7 + 0.123).fract();
            x - 0.5
        };
        for (m, n) in [(6, 6), (3, 7), (7, 2), (1, 5)] {
            let a = DMatrix::from_fn(m, n, |_, _| next());
            penrose(&a, &pseudo_inverse(&a, 1e-12), 1e-12);
        }
    }

    #[test]
    fn rank_deficient_and_tall() {
        // Rank 1: the pseudo-inverse satisfies the four Penrose conditions.
        let j = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 4.0]);
        let p = pseudo_inverse(&j, 1e-12);
        assert!((&j * &p * &j - &j).norm() < 1e-12);
        assert!((&p * &j * &p - &p).norm() < 1e-12);
        assert!(((&j * &p).transpose() - &j * &p).norm() < 1e-12);
        // Zero damping at the singularity falls back to the SVD inverse.
        assert!((damped_pseudo_inverse(&j, 0.0) - &p).norm() < 1e-9);
        // Tall matrices use the n × n system.
        let t = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        assert!((damped_pseudo_inverse(&t, 1e-7) - pseudo_inverse(&t, 1e-12)).norm() < 1e-9);
        // Non-finite input: NaNs of the right shape, no panic.
        let bad = DMatrix::from_row_slice(1, 2, &[Real::NAN, 1.0]);
        assert_eq!(pseudo_inverse(&bad, 1e-9).shape(), (2, 1));
        assert!(damped_pseudo_inverse(&bad, 0.1)[(0, 0)].is_nan());
        // Wrong-shape pinv is recomputed.
        let n = null_space_projector(&t, &DMatrix::zeros(1, 1));
        assert!((&t * &n).norm() < 1e-12);
    }
}
