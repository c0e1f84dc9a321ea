//! What integration needs from a sweep ([`sensor::Sweep`], the workspace's
//! one sweep type): checked point lists, and the range jumps between
//! neighbouring rays that the occlusion weighting of A§4.2.1 flags.
//!
//! A sweep that keeps its (scan, ray) grid (A eq. 4.12) gives its neighbours
//! exactly: `|r_{i,j} − r_{i+1,j}|` along a scan and `|r_{i,j} − r_{i,j+1}|`
//! across scans. A plain list (a foreign cloud with ray origins) gives only
//! the neighbours that can be recovered from its order.

use crate::MapError;
use crate::occupancy::OcclusionConfig;
use geom::math::is_finite_point;
use geom::{Point3, Real, Vector3};
use sensor::Sweep;

/// The occlusion segments of a sweep (A§4.2.1): pairs of neighbouring
/// returns whose ranges differ by more than
/// [`OcclusionConfig::range_jump_m`], as point pairs. Neighbours are the grid
/// neighbours when the sweep keeps its grid, else the list neighbours
/// recoverable from its order (none when
/// [`OcclusionConfig::list_neighbour_max_deg`] is 0).
pub fn range_jumps(sweep: &Sweep, occlusion: &OcclusionConfig) -> Vec<(Point3, Point3)> {
    let range_jump_m = occlusion.range_jump_m;
    let list_max_angle_rad = occlusion.list_neighbour_max_deg.to_radians();
    let pts = sweep.points();
    if sweep.grid_shape().is_some() {
        sweep
            .grid_neighbours()
            .into_iter()
            .filter(|&(k, l)| (pts[k].range_m() - pts[l].range_m()).abs() > range_jump_m)
            .map(|(k, l)| (pts[k].point, pts[l].point))
            .collect()
    } else if list_max_angle_rad > 0.0 {
        list_range_jumps(
            &sweep.origins(),
            &sweep.positions(),
            range_jump_m,
            list_max_angle_rad,
        )
    } else {
        Vec::new()
    }
}

/// Check a point list with per-point ray origins: same length, not empty,
/// every coordinate finite. `what` names the input in errors.
pub(crate) fn check_point_list(
    what: &str,
    origins: &[Point3],
    points: &[Point3],
) -> Result<(), MapError> {
    if points.is_empty() {
        return Err(MapError::input(what, "no points"));
    }
    if origins.len() != points.len() {
        return Err(MapError::input(
            what,
            format!(
                "{} origins for {} points: every point needs the origin of its ray",
                origins.len(),
                points.len()
            ),
        ));
    }
    if let Some(i) = points.iter().position(|p| !is_finite_point(p)) {
        return Err(MapError::input(
            what,
            format!("point {i} has a non-finite coordinate"),
        ));
    }
    if let Some(i) = origins.iter().position(|p| !is_finite_point(p)) {
        return Err(MapError::input(
            what,
            format!("origin {i} has a non-finite coordinate"),
        ));
    }
    Ok(())
}

/// Pairs of consecutive points of a plain list that look like neighbouring
/// rays of one scan and whose ranges differ by more than `range_jump_m`.
///
/// A point list has no grid, so the grid is recovered where it safely can be:
/// points `k` and `k + 1` count as neighbours along a scan when they share the
/// same origin exactly (one scan: one scanner position) and their ray
/// directions are at most `max_angle_rad` apart (adjacent bearings; a gap of
/// missing returns or a jump to the next scan row is wider). Neighbours across
/// scans cannot be recovered from a list and are skipped.
pub(crate) fn list_range_jumps(
    origins: &[Point3],
    points: &[Point3],
    range_jump_m: Real,
    max_angle_rad: Real,
) -> Vec<(Point3, Point3)> {
    let cos_max = max_angle_rad.cos();
    let mut out = Vec::new();
    for k in 1..points.len() {
        if origins[k] != origins[k - 1] {
            continue;
        }
        let a: Vector3 = points[k - 1] - origins[k - 1];
        let b: Vector3 = points[k] - origins[k];
        let (ra, rb) = (a.norm(), b.norm());
        if ra == 0.0 || rb == 0.0 || (ra - rb).abs() <= range_jump_m {
            continue;
        }
        if a.dot(&b) >= cos_max * ra * rb {
            out.push((points[k - 1], points[k]));
        }
    }
    out
}
