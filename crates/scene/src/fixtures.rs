//! Reproducible workloads for benchmarks and cross-engine comparisons.
//!
//! [`benchmark_structure`] is the ~66 000-triangle structure the ray-casting
//! figures are quoted on (I-beams, plates and a finely tessellated sphere), and
//! [`incoherent_rays`] the million random rays cast at it. Both are
//! deterministic, so the same workload can be written to files
//! (`surveyor raycast` formats) and run through other engines.

use crate::error::SceneError;
use crate::mesh::TriMesh;
use crate::primitives::{IBeamSection, cuboid, i_beam};
use geom::{Point3, Real, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A UV sphere with `lat` bands and `lon` sectors (closed, outward normals).
pub fn uv_sphere(centre: Point3, radius: Real, lat: u32, lon: u32) -> TriMesh {
    let mut vertices = vec![centre + Vector3::new(0.0, 0.0, radius)];
    for i in 1..lat {
        let theta = std::f64::consts::PI * Real::from(i) / Real::from(lat);
        for j in 0..lon {
            let phi = std::f64::consts::TAU * Real::from(j) / Real::from(lon);
            vertices.push(
                centre
                    + Vector3::new(
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    ) * radius,
            );
        }
    }
    vertices.push(centre - Vector3::new(0.0, 0.0, radius));
    let south = vertices.len() as u32 - 1;
    let ring = |i: u32, j: u32| 1 + (i - 1) * lon + (j % lon);
    let mut triangles = Vec::new();
    for j in 0..lon {
        triangles.push([0, ring(1, j), ring(1, j + 1)]);
        triangles.push([south, ring(lat - 1, j + 1), ring(lat - 1, j)]);
    }
    for i in 1..lat - 1 {
        for j in 0..lon {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            triangles.push([a, c, d]);
            triangles.push([a, d, b]);
        }
    }
    TriMesh {
        vertices,
        triangles,
    }
}

/// The benchmark structure: twelve 4 m I-beams in a frame, eight steel plates and
/// a sphere of 65 024 triangles; 65 648 triangles in all, within a 5 m box.
pub fn benchmark_structure() -> TriMesh {
    let mut m = TriMesh::default();
    let s = IBeamSection {
        depth: 0.3,
        flange_width: 0.15,
        flange_thickness: 0.012,
        web_thickness: 0.008,
    };
    for k in 0..4 {
        let y = -1.5 + Real::from(k);
        for (z, up) in [(0.0, Vector3::z()), (2.5, -Vector3::z())] {
            if let Ok(b) = i_beam(&Point3::new(-2.0, y, z), &Point3::new(2.0, y, z), &up, &s) {
                m.append(&b);
            }
        }
        if let Ok(b) = i_beam(
            &Point3::new(-2.0, y, 0.3),
            &Point3::new(-2.0, y, 2.2),
            &Vector3::x(),
            &s,
        ) {
            m.append(&b);
        }
    }
    for k in 0..8 {
        let x = -1.8 + 0.5 * Real::from(k);
        m.append(&cuboid(
            Point3::new(x, -2.0, 0.4 + 0.2 * Real::from(k % 3)),
            Point3::new(x + 0.3, -1.99, 1.0 + 0.2 * Real::from(k % 3)),
        ));
    }
    m.append(&uv_sphere(Point3::new(0.3, 0.2, 1.2), 0.8, 128, 256));
    m
}

/// Most rays [`incoherent_rays_checked`] makes: ten times the benchmark's
/// million, 240 MB as `[f32; 6]` (and as much again as a `rays.bin` buffer).
pub const MAX_FIXTURE_RAYS: usize = 10_000_000;

/// [`incoherent_rays`] for a count from the user: more than
/// [`MAX_FIXTURE_RAYS`] is refused before allocating.
///
/// ```
/// let err = scene::fixtures::incoherent_rays_checked(100_000_000_000, 1).unwrap_err();
/// assert!(err.to_string().starts_with("rays: expected at most 10000000"));
/// assert_eq!(scene::fixtures::incoherent_rays_checked(3, 1).unwrap().len(), 3);
/// assert!(scene::fixtures::incoherent_rays_checked(0, 1).is_err());
/// ```
pub fn incoherent_rays_checked(n: usize, seed: u64) -> Result<Vec<[f32; 6]>, SceneError> {
    if n > MAX_FIXTURE_RAYS {
        return Err(SceneError::invalid(
            "rays",
            format!(
                "expected at most {MAX_FIXTURE_RAYS} rays (MAX_FIXTURE_RAYS, 24 bytes each), got {n}"
            ),
        ));
    }
    if n == 0 {
        return Err(SceneError::invalid(
            "rays",
            "expected at least 1 ray (a file of none is no workload), got 0",
        ));
    }
    Ok(incoherent_rays(n, seed))
}

/// `n` rays with origins uniform in the 6 m box around the structure and
/// directions uniform on the sphere: six f32 per ray (origin, unit direction).
/// Allocates `24 n` bytes; for a count from the user, use
/// [`incoherent_rays_checked`].
pub fn incoherent_rays(n: usize, seed: u64) -> Vec<[f32; 6]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let o = [
                rng.random_range(-3.0f32..3.0),
                rng.random_range(-3.0f32..3.0),
                rng.random_range(-1.5f32..4.0),
            ];
            let d = loop {
                let v = [
                    rng.random_range(-1.0f32..1.0),
                    rng.random_range(-1.0f32..1.0),
                    rng.random_range(-1.0f32..1.0),
                ];
                let n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
                if n2 > 1e-4 && n2 <= 1.0 {
                    let n = n2.sqrt();
                    break [v[0] / n, v[1] / n, v[2] / n];
                }
            };
            [o[0], o[1], o[2], d[0], d[1], d[2]]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn structure_is_the_advertised_size_and_closed() {
        let m = benchmark_structure();
        assert_eq!(m.len(), 65_648);
        assert_eq!(m.boundary_edge_count(), 0);
        // An inscribed polyhedron: slightly less than the ball's volume.
        let sphere = uv_sphere(Point3::origin(), 1.0, 128, 256);
        let v = sphere.signed_volume();
        let ball = 4.0 / 3.0 * std::f64::consts::PI;
        assert!(v < ball && (ball - v) / ball < 1e-3);
    }
}
