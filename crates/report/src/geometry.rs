//! Geometry made small enough to display: points to the millimetre, the
//! cloud subsampled, meshes simplified by vertex clustering, convex outlines.

use geom::{Point3, Real, TriMesh, Vector3};
use rustc_hash::{FxHashMap, FxHashSet};

/// A coordinate rounded to the millimetre, as `f32` so it prints short.
#[allow(clippy::cast_possible_truncation)]
pub fn mm(x: Real) -> f32 {
    ((x * 1000.0).round() / 1000.0) as f32
}

/// Columns x, y, z of points, to the millimetre.
pub fn columns<'a>(points: impl IntoIterator<Item = &'a Point3>) -> [Vec<f32>; 3] {
    let mut out = [Vec::new(), Vec::new(), Vec::new()];
    for p in points {
        for (c, v) in out.iter_mut().zip([p.x, p.y, p.z]) {
            c.push(mm(v));
        }
    }
    out
}

/// Polyline columns with `None` between pieces (plotly breaks the line there).
#[derive(Debug, Default)]
pub struct Polylines {
    /// x, y, z.
    pub xyz: [Vec<Option<f32>>; 3],
}

impl Polylines {
    /// Append one polyline.
    pub fn push(&mut self, points: &[Point3]) {
        if points.len() < 2 {
            return;
        }
        for p in points {
            for (c, v) in self.xyz.iter_mut().zip([p.x, p.y, p.z]) {
                c.push(Some(mm(v)));
            }
        }
        for c in &mut self.xyz {
            c.push(None);
        }
    }

    /// No line pushed.
    pub fn is_empty(&self) -> bool {
        self.xyz[0].is_empty()
    }
}

/// Every `stride`-th of `n` items, the stride chosen so at most `max` remain.
pub fn stride_for(n: usize, max: usize) -> usize {
    n.div_ceil(max.max(1)).max(1)
}

/// A mesh simplified by vertex clustering on a grid of `cell` metres: every
/// vertex moves to the mean of its cell's vertices and triangles that
/// collapse are dropped.
pub fn cluster(mesh: &TriMesh, cell: Real) -> TriMesh {
    let mut index: FxHashMap<[i64; 3], u32> = FxHashMap::default();
    let mut sums: Vec<(Vector3, Real)> = Vec::new();
    #[allow(clippy::cast_possible_truncation)]
    let key = |p: &Point3| {
        [
            (p.x / cell).floor() as i64,
            (p.y / cell).floor() as i64,
            (p.z / cell).floor() as i64,
        ]
    };
    let mut remap = Vec::with_capacity(mesh.vertices.len());
    for p in &mesh.vertices {
        let next = u32::try_from(sums.len()).unwrap_or(u32::MAX);
        let id = *index.entry(key(p)).or_insert(next);
        if id == next {
            sums.push((Vector3::zeros(), 0.0));
        }
        let s = &mut sums[id as usize];
        s.0 += p.coords;
        s.1 += 1.0;
        remap.push(id);
    }
    let vertices = sums.iter().map(|(s, n)| Point3::from(s / *n)).collect();
    let mut seen = FxHashSet::default();
    let triangles = mesh
        .triangles
        .iter()
        .map(|t| t.map(|v| remap[v as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .filter(|t| {
            let mut k = *t;
            k.sort_unstable();
            seen.insert(k)
        })
        .collect();
    TriMesh {
        vertices,
        triangles,
    }
}

/// `mesh` simplified (cells from 1 cm, doubling) until it has at most
/// `max_triangles`; returns it and the cell used (0 when untouched).
pub fn simplify(mesh: &TriMesh, max_triangles: usize) -> (TriMesh, Real) {
    if mesh.triangles.len() <= max_triangles {
        return (mesh.clone(), 0.0);
    }
    let mut cell = 0.01;
    loop {
        let m = cluster(mesh, cell);
        if m.triangles.len() <= max_triangles || cell > 1.0 {
            return (m, cell);
        }
        cell *= 2.0;
    }
}

pub use geom::math::basis_from_normal as plane_basis;

/// Triangles (indices into `poly`, anticlockwise) covering a simple 2-D
/// polygon of either orientation: `geom`'s ear clipping on the polygon made
/// anticlockwise.
pub fn triangulate(poly: &[[Real; 2]]) -> Vec<[usize; 3]> {
    let n = poly.len();
    let flat: Vec<geom::Point2> = poly.iter().map(|p| geom::Point2::new(p[0], p[1])).collect();
    let reversed = geom::polygon2::signed_area(&flat) < 0.0;
    let at = |k: usize| if reversed { n - 1 - k } else { k };
    let pts: Vec<geom::Point2> = (0..n).map(|k| flat[at(k)]).collect();
    geom::primitives::triangulate(&pts)
        .into_iter()
        .map(|t| t.map(|k| at(k as usize)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Crossing-number point-in-polygon test.
    fn inside(poly: &[[Real; 2]], p: [Real; 2]) -> bool {
        let n = poly.len();
        let mut odd = false;
        for i in 0..n {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            if (a[1] > p[1]) != (b[1] > p[1])
                && p[0] < a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
            {
                odd = !odd;
            }
        }
        odd
    }

    fn area_of(poly: &[[Real; 2]], tris: &[[usize; 3]]) -> Real {
        tris.iter()
            .map(|t| {
                let tri = [poly[t[0]], poly[t[1]], poly[t[2]]];
                let a =
                    2.0 * geom::polygon2::signed_area(&tri.map(|p| geom::Point2::new(p[0], p[1])));
                assert!(a > 0.0, "a triangle is not anticlockwise: {t:?}");
                0.5 * a
            })
            .sum()
    }

    #[test]
    fn triangles_cover_concave_polygons_exactly() {
        // An L with collinear vertices along its edges, a comb (three deep
        // notches), and both again clockwise.
        let l = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 2.0],
            [1.0, 3.0],
            [0.0, 3.0],
            [0.0, 1.5],
        ];
        let mut comb = vec![[0.0, 0.0], [7.0, 0.0], [7.0, 3.0]];
        for t in (0..3).rev() {
            let x = 2.0 * f64::from(t) + 1.0;
            comb.extend([[x + 1.0, 3.0], [x + 1.0, 0.5], [x, 0.5], [x, 3.0]]);
        }
        comb.push([0.0, 3.0]);
        for (poly, area) in [(l, 4.0), (comb, 21.0 - 3.0 * 2.5)] {
            assert!(
                (geom::polygon2::signed_area(
                    &poly
                        .iter()
                        .map(|p| geom::Point2::new(p[0], p[1]))
                        .collect::<Vec<_>>()
                ) - area)
                    .abs()
                    < 1e-12
            );
            let tris = triangulate(&poly);
            assert!((area_of(&poly, &tris) - area).abs() < 1e-9, "{tris:?}");
            // Every triangle lies inside: its centroid is not in a notch.
            for t in &tris {
                let c = [0, 1].map(|k| t.iter().map(|&v| poly[v][k]).sum::<Real>() / 3.0);
                assert!(inside(&poly, c), "{t:?}");
            }
            let mut rev = poly.clone();
            rev.reverse();
            let tris = triangulate(&rev);
            assert!((area_of(&rev, &tris) - area).abs() < 1e-9, "{tris:?}");
        }
    }

    #[test]
    fn clustering_keeps_a_plane_a_plane() {
        // A 1 m square grid of 0.01 m cells at z = 0.3, two triangles each.
        let n = 101;
        let mut vertices = Vec::new();
        for i in 0..n {
            for j in 0..n {
                vertices.push(Point3::new(f64::from(i) * 0.01, f64::from(j) * 0.01, 0.3));
            }
        }
        let mut triangles = Vec::new();
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                let v = i * n + j;
                triangles.push([v, v + n, v + 1]);
                triangles.push([v + 1, v + n, v + n + 1]);
            }
        }
        let mesh = TriMesh {
            vertices,
            triangles,
        };
        let (m, cell) = simplify(&mesh, 5000);
        assert!(cell > 0.0 && m.triangles.len() <= 5000 && m.triangles.len() > 500);
        assert!(m.vertices.iter().all(|p| (p.z - 0.3).abs() < 1e-12));
        // Area is roughly kept (vertex means pull the border in by < a cell).
        let area: Real = m
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| m.vertices[v as usize]);
                0.5 * (b - a).cross(&(c - a)).norm()
            })
            .sum();
        assert!(area > 0.8 && area <= 1.0 + 1e-9, "{area}");
    }
}
