//! Marching cubes (Lorensen & Cline 1987) with a case table generated from one
//! face rule, so that the surface is closed across cubes and consistently
//! wound.
//!
//! Corners of a cube are numbered by their offsets, `c = x + 2y + 4z`. A
//! corner is *inside* when its signed distance is negative (behind the
//! measured surface). The table is built, once, from this rule on each of the
//! six faces: walking a face's boundary anticlockwise about its outward
//! normal, every run of inside corners is cut off by one segment from the
//! crossing where the walk enters the run to the crossing where it leaves it.
//! On a face with two diagonally opposite inside corners this separates them;
//! the choice depends only on the face's four signs, so the two cubes sharing
//! a face always cut it alike and the mesh has no cracks (the classic 1987
//! table resolves such faces inconsistently and leaves holes). The segments
//! chain into closed loops around the cube, each triangulated as a fan. Loop
//! direction makes every triangle wind anticlockwise seen from outside
//! (positive distance): right-hand normals point out of the solid, toward the
//! sensor.

use std::sync::OnceLock;

/// The two corners and the axis of each of the 12 cube edges; the first
/// corner is the one at the lower end.
pub const EDGES: [(u8, u8, u8); 12] = [
    (0, 1, 0),
    (2, 3, 0),
    (4, 5, 0),
    (6, 7, 0),
    (0, 2, 1),
    (1, 3, 1),
    (4, 6, 1),
    (5, 7, 1),
    (0, 4, 2),
    (1, 5, 2),
    (2, 6, 2),
    (3, 7, 2),
];

/// Offset of corner `c`.
#[inline]
pub const fn corner_offset(c: u8) -> [i32; 3] {
    [(c & 1) as i32, ((c >> 1) & 1) as i32, ((c >> 2) & 1) as i32]
}

/// The surface pieces of each of the 256 sign configurations.
pub struct CaseTable {
    cases: Vec<Case>,
}

/// The surface inside one cube configuration: closed loops of crossing edges
/// and their triangulation.
#[derive(Clone, Debug, Default)]
pub struct Case {
    /// Each loop's crossing edges in order (anticlockwise seen from outside).
    pub loops: Vec<Vec<u8>>,
    /// Triangles; a vertex `v < 12` lies on edge `v`, a vertex `12 + l` is the
    /// centre of loop `l`.
    pub triangles: Vec<[u8; 3]>,
}

impl CaseTable {
    /// The surface of configuration `mask` (bit `c` set: corner `c` inside).
    #[inline]
    pub fn case(&self, mask: u8) -> &Case {
        &self.cases[usize::from(mask)]
    }
}

/// The case table, built on first use.
pub fn case_table() -> &'static CaseTable {
    static TABLE: OnceLock<CaseTable> = OnceLock::new();
    TABLE.get_or_init(|| CaseTable {
        cases: (0..=255u8).map(build_case).collect(),
    })
}

fn edge_between(a: u8, b: u8) -> u8 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    EDGES
        .iter()
        .position(|&(p, q, _)| p == lo && q == hi)
        .map_or(u8::MAX, |e| e as u8)
}

/// The four corners of face (`axis`, `side`) in anticlockwise order about the
/// face's outward normal.
fn face_corners(axis: usize, side: u8) -> [u8; 4] {
    let u = (axis + 1) % 3;
    let w = (axis + 2) % 3;
    let corner = |du: u8, dw: u8| (side << axis) | (du << u) | (dw << w);
    // (e_u, e_w, e_axis) is right-handed: anticlockwise about +e_axis runs
    // (0,0) → (1,0) → (1,1) → (0,1) in (u, w); about −e_axis the reverse.
    if side == 1 {
        [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]
    } else {
        [corner(0, 0), corner(0, 1), corner(1, 1), corner(1, 0)]
    }
}

fn build_case(mask: u8) -> Case {
    let inside = |c: u8| (mask >> c) & 1 == 1;
    // next[e] = the crossing edge that follows e along the surface boundary;
    // face[e] = the face whose segment leaves e.
    let mut next = [u8::MAX; 12];
    let mut face = [u8::MAX; 12];
    for axis in 0..3 {
        for side in 0..2u8 {
            let q = face_corners(axis, side);
            let edge = |k: usize| edge_between(q[k % 4], q[(k + 1) % 4]);
            let entry = |k: usize| !inside(q[k % 4]) && inside(q[(k + 1) % 4]);
            let exit = |k: usize| inside(q[k % 4]) && !inside(q[(k + 1) % 4]);
            for k in 0..4 {
                if entry(k)
                    && let Some(d) = (1..4).find(|d| exit(k + d))
                {
                    next[usize::from(edge(k))] = edge(k + d);
                    face[usize::from(edge(k))] = (2 * axis) as u8 + side;
                }
            }
        }
    }
    let mut case = Case::default();
    let mut seen = [false; 12];
    for start in 0..12u8 {
        if next[usize::from(start)] == u8::MAX || seen[usize::from(start)] {
            continue;
        }
        let mut ring = Vec::new();
        let mut e = start;
        while e != u8::MAX && !seen[usize::from(e)] {
            seen[usize::from(e)] = true;
            ring.push(e);
            e = next[usize::from(e)];
        }
        // A loop crossing one face twice (an ambiguous face whose two inside
        // corners this cube connects) would, fanned from a vertex, put a
        // diagonal on that face, where the neighbouring cube may put the same
        // one: fan it from its centre instead, keeping every edge shared
        // between cubes a face segment.
        let mut faces: Vec<u8> = ring.iter().map(|&e| face[usize::from(e)]).collect();
        faces.sort_unstable();
        let revisits = faces.windows(2).any(|w| w[0] == w[1]);
        let l = case.loops.len() as u8;
        let n = ring.len();
        if revisits {
            for k in 0..n {
                case.triangles.push([12 + l, ring[k], ring[(k + 1) % n]]);
            }
        } else {
            for k in 1..n.saturating_sub(1) {
                case.triangles.push([ring[0], ring[k], ring[k + 1]]);
            }
        }
        case.loops.push(ring);
    }
    case
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_crossing_edge_is_used_by_one_loop() {
        let t = case_table();
        for mask in 0..=255u8 {
            let crossing: Vec<u8> = (0..12u8)
                .filter(|&e| {
                    let (a, b, _) = EDGES[usize::from(e)];
                    ((mask >> a) & 1) != ((mask >> b) & 1)
                })
                .collect();
            let case = t.case(mask);
            let tris = &case.triangles;
            let mut used: Vec<u8> = case.loops.iter().flatten().copied().collect();
            let n_used = used.len();
            used.sort_unstable();
            used.dedup();
            assert_eq!(used.len(), n_used, "an edge in two loops");
            assert_eq!(used, crossing, "mask {mask:#010b}");
            if crossing.is_empty() {
                assert!(tris.is_empty());
            }
        }
        assert_eq!(t.case(1).triangles.len(), 1);
        assert_eq!(t.case(!1).triangles.len(), 1);
    }

    #[test]
    fn single_corner_triangle_faces_away_from_the_inside_corner() {
        let t = case_table();
        for c in 0..8u8 {
            let tri = t.case(1 << c).triangles[0];
            let mid = |e: u8| {
                let (a, b, _) = EDGES[usize::from(e)];
                let (pa, pb) = (corner_offset(a), corner_offset(b));
                [0, 1, 2].map(|k| 0.5 * f64::from(pa[k] + pb[k]))
            };
            let [p, q, r] = tri.map(mid);
            let u = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
            let v = [r[0] - p[0], r[1] - p[1], r[2] - p[2]];
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let o = corner_offset(c).map(f64::from);
            let away = [p[0] - o[0], p[1] - o[1], p[2] - o[2]];
            let dot = n[0] * away[0] + n[1] * away[1] + n[2] * away[2];
            assert!(dot > 0.0, "corner {c}");
        }
    }
}
