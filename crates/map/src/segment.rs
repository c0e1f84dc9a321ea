//! Map segmentation by clustering Scale-Like Discs (Paul §5.3, eq. 5.10–5.18,
//! Algorithm 1).
//!
//! Two discs `s_i`, `s_j` are linked when all four binary graphs of §5.3.1
//! link them:
//!
//! | graph | measure | link when |
//! |---|---|---|
//! | `δθB` (eq. 5.10–5.11) | angle between normals `acos(n⃗_i · n⃗_j)` | `≤ τθ` |
//! | `δdB` (eq. 5.12–5.13) | distance between centres `‖P̂_i − P̂_j‖` | `≤ τd` |
//! | `δpB` (eq. 5.14–5.15) | mean distance from each centre, along its normal, to the other disc's plane | `≤ τp` |
//! | `δqB` (eq. 5.16–5.17) | per-joint difference of the manipulator poses `|q_k,i − q_k,j|` | `≤ τq_k` for every joint `k` |
//!
//! and the combined graph is their conjunction without self-links,
//! `B = δθB ∧ δdB ∧ δpB ∧ δqB ∧ ¬I` (eq. 5.18). The pose graph `δqB` takes
//! part only when a pose per disc is supplied (the poses come from a pose
//! selection module, Paul App. A); without poses it is all ones. Segments are
//! the connected components of `B` (Algorithm 1).
//!
//! # Implementation
//!
//! Algorithm 1 grows each segment breadth-first from a random unregistered
//! root; the components do not depend on the roots or the visiting order, so
//! [`segment_discs`] computes the same partition with a union-find over the
//! links of `B` and returns it in a canonical order: members ascending,
//! segments ordered by their smallest member. The links are found with a
//! uniform grid of cell `τd` (a link needs `δd ≤ τd`, so only discs in
//! neighbouring cells are compared): thousands of discs take milliseconds,
//! not the `n²` pairs of the thesis' matrices.
//!
//! Joint differences are plain absolute differences of the joint values
//! (no wrapping modulo 2π): they measure how far each joint must turn between
//! the two poses, which is what matters for a joint range wider than 2π.
//!
//! # Files
//!
//! Segment files (`SEGMENTS.json`) and pose files (`POSES.csv`) are read and
//! written by [`crate::segment_io`].
//!
//! ```
//! use geom::{Point3, UnitVector3, Vector3};
//! use map::segment::{segment_discs, SegmentConfig};
//! use map::sld::{Disc, DiscId};
//!
//! let up = UnitVector3::new_unchecked(Vector3::z());
//! let disc = |x: f64, z: f64| Disc { centre: Point3::new(x, 0.0, z), normal: up, radius_m: 0.04, points: 20 };
//! // A floor strip of four discs 5 cm apart, and a step 10 cm higher.
//! let discs = [disc(0.0, 0.0), disc(0.05, 0.0), disc(0.10, 0.0), disc(0.15, 0.0), disc(0.2, 0.1)];
//! let segments = segment_discs(&discs, None, &SegmentConfig::default())?;
//! let ids = |v: &[usize]| v.iter().copied().map(DiscId).collect::<Vec<_>>();
//! assert_eq!(segments, vec![ids(&[0, 1, 2, 3]), ids(&[4])]);
//! # Ok::<(), map::MapError>(())
//! ```

use crate::MapError;
use crate::sld::{Disc, DiscId};
use geom::Real;
use serde::{Deserialize, Serialize};

/// A manipulator pose for a disc: six joint angles, radians.
pub type JointPose = [Real; 6];

/// Largest `τd` ([`SegmentConfig::tau_d_m`]), metres: fifty times Paul's
/// 0.2 m; past it every pair of a structure's discs would be compared
/// (issue 48: 1e308 was taken as it was).
pub const MAX_TAU_D_M: Real = 10.0;

/// Thresholds of the four binary graphs (Paul Table 5.2 / Table 6.1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SegmentConfig {
    /// `τθ`: largest angle between linked normals, degrees (5°).
    pub tau_theta_deg: Real,
    /// `τd`: largest distance between linked centres, metres (0.2).
    pub tau_d_m: Real,
    /// `τp`: largest mean centre-to-plane distance, metres (0.05).
    pub tau_p_m: Real,
    /// `τq`: largest difference per joint between linked poses, degrees
    /// (8, 10, 14, 20, 20, 20).
    #[serde(deserialize_with = "geom::exact::array")]
    pub tau_q_deg: [Real; 6],
}

impl Default for SegmentConfig {
    fn default() -> Self {
        Self {
            tau_theta_deg: 5.0,
            tau_d_m: 0.2,
            tau_p_m: 0.05,
            tau_q_deg: [8.0, 10.0, 14.0, 20.0, 20.0, 20.0],
        }
    }
}

impl SegmentConfig {
    /// Check the fields: finite, `τθ ∈ [0, 180]`, `0 < τd ≤` [`MAX_TAU_D_M`],
    /// `τp ≥ 0`, `τq ≥ 0`.
    pub fn validate(&self) -> Result<(), MapError> {
        let bad = |field, expected, got: Real| {
            Err(MapError::stage_config("segment", field, expected, got))
        };
        if !(self.tau_theta_deg.is_finite() && (0.0..=180.0).contains(&self.tau_theta_deg)) {
            return bad("tau_theta_deg", "an angle in [0, 180]", self.tau_theta_deg);
        }
        if !(self.tau_d_m.is_finite() && self.tau_d_m > 0.0 && self.tau_d_m <= MAX_TAU_D_M) {
            return bad(
                "tau_d_m",
                "a positive distance of at most 10 m (MAX_TAU_D_M)",
                self.tau_d_m,
            );
        }
        if !(self.tau_p_m.is_finite() && self.tau_p_m >= 0.0) {
            return bad("tau_p_m", "a non-negative distance", self.tau_p_m);
        }
        for (k, &t) in self.tau_q_deg.iter().enumerate() {
            if !(t.is_finite() && t >= 0.0) {
                return Err(MapError::stage_config(
                    "segment",
                    "tau_q_deg",
                    "non-negative angles",
                    format!("joint {}: {t}", k + 1),
                ));
            }
        }
        Ok(())
    }

    /// The thresholds in SI units.
    fn thresholds(&self) -> Thresholds {
        Thresholds {
            cos_theta: self.tau_theta_deg.to_radians().cos(),
            d2: self.tau_d_m * self.tau_d_m,
            p: self.tau_p_m,
            q: self.tau_q_deg.map(Real::to_radians),
        }
    }
}

struct Thresholds {
    cos_theta: Real,
    d2: Real,
    p: Real,
    q: [Real; 6],
}

/// The four measures of §5.3.1 between two discs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairMeasures {
    /// `δθ_ij`, the angle between the normals, radians (eq. 5.10).
    pub dtheta_rad: Real,
    /// `δd_ij`, the distance between the centres, metres (eq. 5.12).
    pub dd_m: Real,
    /// `δp_ij`, the mean centre-to-plane distance along the normals, metres
    /// (eq. 5.14); infinite for perpendicular normals.
    pub dp_m: Real,
    /// `δQ_ij`, the per-joint pose differences, radians (eq. 5.16), when poses
    /// are given.
    pub dq_rad: Option<[Real; 6]>,
}

/// The measures of eq. 5.10, 5.12, 5.14 and 5.16 between discs `a` and `b`.
pub fn pair_measures(a: &Disc, b: &Disc, poses: Option<(&JointPose, &JointPose)>) -> PairMeasures {
    let cos = a.normal.dot(&b.normal);
    PairMeasures {
        dtheta_rad: cos.clamp(-1.0, 1.0).acos(),
        dd_m: (a.centre - b.centre).norm(),
        dp_m: centre_to_plane_m(a, b),
        dq_rad: poses.map(|(qa, qb)| std::array::from_fn(|k| (qa[k] - qb[k]).abs())),
    }
}

/// `δp_ij` of eq. 5.14: the normal line from each centre meets the other
/// disc's plane; the mean of the two distances along the normals. Infinite
/// when the normals are perpendicular (the lines never meet the planes).
pub fn centre_to_plane_m(a: &Disc, b: &Disc) -> Real {
    let cos = a.normal.dot(&b.normal);
    if cos.abs() <= Real::EPSILON {
        return Real::INFINITY;
    }
    let ab = b.centre - a.centre;
    // Line a + t n_a meets plane b at t = (b − a)·n_b / (n_a·n_b); likewise for b.
    let t_ab = ab.dot(&b.normal) / cos;
    let t_ba = -ab.dot(&a.normal) / cos;
    0.5 * (t_ab.abs() + t_ba.abs())
}

#[inline]
fn linked_with(
    a: &Disc,
    b: &Disc,
    poses: Option<(&JointPose, &JointPose)>,
    t: &Thresholds,
) -> bool {
    let d = b.centre - a.centre;
    if d.norm_squared() > t.d2 {
        return false;
    }
    if a.normal.dot(&b.normal) < t.cos_theta {
        return false;
    }
    if centre_to_plane_m(a, b) > t.p {
        return false;
    }
    match poses {
        Some((qa, qb)) => (0..6).all(|k| (qa[k] - qb[k]).abs() <= t.q[k]),
        None => true,
    }
}

/// `B_ij` of eq. 5.18 for two distinct discs: every graph links them. (The
/// diagonal `¬I` is the caller's: a disc is never linked to itself in
/// [`links`] or [`segment_discs`].)
pub fn linked(
    a: &Disc,
    b: &Disc,
    poses: Option<(&JointPose, &JointPose)>,
    cfg: &SegmentConfig,
) -> bool {
    linked_with(a, b, poses, &cfg.thresholds())
}

fn check_inputs(
    discs: &[Disc],
    poses: Option<&[JointPose]>,
    cfg: &SegmentConfig,
) -> Result<(), MapError> {
    cfg.validate()?;
    let finite = |v: &[Real]| v.iter().all(|x| x.is_finite());
    if let Some(index) = discs
        .iter()
        .position(|d| !(finite(d.centre.coords.as_slice()) && finite(d.normal.as_slice())))
    {
        return Err(MapError::NonFinite {
            what: "disc",
            index,
        });
    }
    if let Some(p) = poses {
        if p.len() != discs.len() {
            return Err(MapError::PoseCount {
                poses: p.len(),
                discs: discs.len(),
            });
        }
        if let Some(index) = p.iter().position(|q| !finite(q)) {
            return Err(MapError::NonFinite {
                what: "pose",
                index,
            });
        }
    }
    Ok(())
}

/// Cell of a grid of edge `cell` (saturating far from the origin).
#[inline]
fn cell_of(p: &geom::Point3, inv: Real) -> [i64; 3] {
    [
        (p.x * inv).floor() as i64,
        (p.y * inv).floor() as i64,
        (p.z * inv).floor() as i64,
    ]
}

/// Every link `(i, j)`, `i < j`, of the combined graph `B` (eq. 5.18), sorted.
pub fn links(
    discs: &[Disc],
    poses: Option<&[JointPose]>,
    cfg: &SegmentConfig,
) -> Result<Vec<(u32, u32)>, MapError> {
    check_inputs(discs, poses, cfg)?;
    let mut out = Vec::new();
    for_each_link(discs, poses, cfg, |i, j| out.push((i.min(j), i.max(j))));
    out.sort_unstable();
    Ok(out)
}

/// Call `f(i, j)` once for every link of `B` (inputs already checked).
fn for_each_link(
    discs: &[Disc],
    poses: Option<&[JointPose]>,
    cfg: &SegmentConfig,
    mut f: impl FnMut(u32, u32),
) {
    let t = cfg.thresholds();
    let inv = 1.0 / cfg.tau_d_m;
    // Sort discs by cell (lexicographic z, y, x); cells along x are adjacent.
    let mut order: Vec<([i64; 3], u32)> = discs
        .iter()
        .enumerate()
        .map(|(i, d)| {
            let [x, y, z] = cell_of(&d.centre, inv);
            ([z, y, x], i as u32)
        })
        .collect();
    order.sort_unstable();
    let keys: Vec<[i64; 3]> = order.iter().map(|o| o.0).collect();
    for &([z, y, x], i) in &order {
        let a = &discs[i as usize];
        let qa = poses.map(|p| &p[i as usize]);
        for dz in -1..=1 {
            for dy in -1..=1 {
                let lo = [z + dz, y + dy, x.saturating_sub(1)];
                let hi = [z + dz, y + dy, x.saturating_add(1)];
                let s = keys.partition_point(|k| *k < lo);
                let e = s + keys[s..].partition_point(|k| *k <= hi);
                for &(_, j) in &order[s..e] {
                    if j <= i {
                        continue;
                    }
                    let b = &discs[j as usize];
                    let pq = qa.zip(poses.map(|p| &p[j as usize]));
                    if linked_with(a, b, pq, &t) {
                        f(i, j);
                    }
                }
            }
        }
    }
}

/// Union-find with path halving and union by size.
struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }

    fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[x as usize];
            self.parent[x as usize] = self.parent[p as usize];
            x = self.parent[x as usize];
        }
        x
    }

    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return;
        }
        let (big, small) = if self.size[ra as usize] >= self.size[rb as usize] {
            (ra, rb)
        } else {
            (rb, ra)
        };
        self.parent[small as usize] = big;
        self.size[big as usize] += self.size[small as usize];
    }
}

/// Connected components of the graph on `n` nodes with the given undirected
/// edges (self-loops ignored), in canonical order: members ascending,
/// components ordered by their smallest member. Edges naming a node `≥ n`
/// are ignored.
pub fn connected_components(n: usize, edges: &[(u32, u32)]) -> Vec<Vec<usize>> {
    let mut uf = UnionFind::new(n);
    for &(a, b) in edges {
        if (a as usize) < n && (b as usize) < n {
            uf.union(a, b);
        }
    }
    components_of(&mut uf, n)
}

fn components_of(uf: &mut UnionFind, n: usize) -> Vec<Vec<usize>> {
    let mut slot = vec![u32::MAX; n];
    let mut out: Vec<Vec<usize>> = Vec::new();
    for i in 0..n {
        let r = uf.find(i as u32) as usize;
        if slot[r] == u32::MAX {
            slot[r] = out.len() as u32;
            out.push(Vec::new());
        }
        out[slot[r] as usize].push(i);
    }
    out
}

/// A map segment: its position in the segments [`segment_discs`] returns
/// (ordered by their smallest disc).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Hash,
    serde::Serialize,
    serde::Deserialize,
)]
#[serde(transparent)]
pub struct SegmentId(pub usize);

/// Segment the map: the connected components of `B = δθB ∧ δdB ∧ δpB ∧ δqB ∧
/// ¬I` (Paul eq. 5.18, Algorithm 1). `poses`, when given, holds one joint
/// pose per disc and enables `δqB`. Returns the segments as lists of disc
/// indices, members ascending, segments ordered by their smallest member.
pub fn segment_discs(
    discs: &[Disc],
    poses: Option<&[JointPose]>,
    cfg: &SegmentConfig,
) -> Result<Vec<Vec<DiscId>>, MapError> {
    check_inputs(discs, poses, cfg)?;
    let mut uf = UnionFind::new(discs.len());
    for_each_link(discs, poses, cfg, |i, j| uf.union(i, j));
    Ok(components_of(&mut uf, discs.len())
        .into_iter()
        .map(|members| members.into_iter().map(DiscId).collect())
        .collect())
}

/// For each disc, the index of its segment in `segments`.
pub fn segment_of_disc(segments: &[Vec<DiscId>], discs: usize) -> Vec<Option<usize>> {
    let mut out = vec![None; discs];
    for (s, members) in segments.iter().enumerate() {
        for &i in members {
            if let Some(slot) = out.get_mut(i.0) {
                *slot = Some(s);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom::{Point3, UnitVector3, Vector3};

    fn disc(c: [Real; 3], n: [Real; 3]) -> Disc {
        Disc {
            centre: Point3::from(c),
            normal: geom::unit(Vector3::from(n))
                .unwrap_or_else(|| UnitVector3::new_unchecked(Vector3::z())),
            radius_m: 0.04,
            points: 10,
        }
    }

    #[test]
    fn centre_to_plane_by_hand() {
        // Parallel planes 3 cm apart: both distances are 3 cm.
        let a = disc([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        let b = disc([0.1, 0.0, 0.03], [0.0, 0.0, 1.0]);
        assert!((centre_to_plane_m(&a, &b) - 0.03).abs() < 1e-12);
        // Tilted b: from a along z to plane b; from b along n_b to plane z = 0.
        let s = 0.1_f64;
        let b = disc([0.1, 0.0, 0.0], [s.sin(), 0.0, s.cos()]);
        // Line (0,0,t) meets plane n_b·(p − c_b) = 0 at t = 0.1 tan s.
        // Line c_b + t n_b meets z = 0 at t = 0: mean = 0.05 tan s.
        assert!((centre_to_plane_m(&a, &b) - 0.05 * s.tan()).abs() < 1e-12);
        let c = disc([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]);
        assert!(centre_to_plane_m(&a, &c).is_infinite());
    }

    #[test]
    fn pose_graph_is_per_joint() {
        let a = disc([0.0; 3], [0.0, 0.0, 1.0]);
        let b = disc([0.01, 0.0, 0.0], [0.0, 0.0, 1.0]);
        let cfg = SegmentConfig::default();
        let q0 = [0.0; 6];
        let mut q1 = [0.0; 6];
        q1[0] = 7.9f64.to_radians();
        assert!(linked(&a, &b, Some((&q0, &q1)), &cfg));
        q1[0] = 8.1f64.to_radians();
        assert!(!linked(&a, &b, Some((&q0, &q1)), &cfg));
        q1[0] = 0.0;
        q1[5] = -19.0f64.to_radians();
        assert!(linked(&a, &b, Some((&q0, &q1)), &cfg));
        assert!(linked(&a, &b, None, &cfg));
    }

    #[test]
    fn union_find_components_are_canonical() {
        let c = connected_components(6, &[(5, 3), (1, 4), (4, 0), (2, 2), (9, 1)]);
        assert_eq!(c, vec![vec![0, 1, 4], vec![2], vec![3, 5]]);
    }
}
