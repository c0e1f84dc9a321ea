//! Uniform area sampling of a scene's surfaces, the ground truth of the
//! coverage metric (SPEC §6).

use crate::material::MaterialId;
use crate::world::Scene;
use geom::{Aabb, Point3, Real, UnitVector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// A point on the true surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceSample {
    /// Position.
    pub point: Point3,
    /// Outward unit normal of its triangle.
    pub normal: UnitVector3,
    /// Triangle index.
    pub face: u32,
    /// Object index.
    pub object: u32,
    /// Material.
    pub material: MaterialId,
}

/// How to sample.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SamplingConfig {
    /// Mean samples per square metre (40 000 = one per (5 mm)², the SPEC §6 minimum).
    pub samples_per_m2: Real,
    /// Keep only samples inside this box.
    pub region: Option<Aabb>,
    /// Drop samples on faces hidden inside or against another closed object
    /// (the web behind a plate bolted to it, a floor under a platform).
    pub exposed_only: bool,
    /// Seed of the sampling RNG.
    pub seed: u64,
}

impl Default for SamplingConfig {
    fn default() -> Self {
        Self {
            samples_per_m2: 40_000.0,
            region: None,
            exposed_only: true,
            seed: 0,
        }
    }
}

/// Offset from the surface used to test whether a face is exposed.
const EXPOSURE_PROBE_M: Real = 1e-4;

/// Sample the scene's surfaces uniformly by area. Deterministic for a seed:
/// triangles are visited in order, each receiving `area × density` samples
/// (stochastically rounded).
pub fn sample_surfaces(scene: &Scene, cfg: &SamplingConfig) -> Vec<SurfaceSample> {
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let mesh = scene.mesh();
    let mut out = Vec::new();
    for face in 0..mesh.len() {
        let tri = mesh.triangle(face);
        if let Some(region) = &cfg.region
            && !Aabb::from_points([&tri.a, &tri.b, &tri.c]).intersects(region)
        {
            continue;
        }
        let Some(normal) = tri.normal() else { continue };
        let expected = tri.area() * cfg.samples_per_m2;
        let n = expected.floor() as usize + usize::from(rng.random::<Real>() < expected.fract());
        let object = scene.triangle_object(face as u32);
        let material = scene.triangle_material(face as u32);
        for _ in 0..n {
            let p = geom::triangle::uniform_point(&tri, rng.random(), rng.random());
            if cfg.region.as_ref().is_some_and(|r| !r.contains_point(&p)) {
                continue;
            }
            out.push(SurfaceSample {
                point: p,
                normal,
                face: face as u32,
                object,
                material,
            });
        }
    }
    if cfg.exposed_only {
        out = out
            .into_par_iter()
            .filter(|s| is_exposed(scene, s))
            .collect();
    }
    out
}

/// `false` when the sample's face lies inside or flush against another closed
/// object: a probe just off the face, on its outer side, is inside that object.
pub fn is_exposed(scene: &Scene, s: &SurfaceSample) -> bool {
    if !scene.objects()[s.object as usize].closed {
        return true;
    }
    let probe = s.point + s.normal.into_inner() * EXPOSURE_PROBE_M;
    !scene.is_inside_closed_object(&probe, Some(s.object))
}
