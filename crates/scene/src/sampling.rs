//! Uniform area sampling of a scene's surfaces, the ground truth of the
//! coverage metric (SPEC §6).

use crate::error::SceneError;
use crate::material::MaterialId;
use crate::world::{FaceId, ObjectId, Scene};
use geom::triangle::Triangle;
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
    /// The triangle.
    pub face: FaceId,
    /// The object.
    pub object: ObjectId,
    /// Material.
    pub material: MaterialId,
}

/// Default of [`SamplingConfig::max_samples`]: ten million samples, about 25 s
/// of coverage scoring on two cores and 250 m² at the SPEC §6 density.
pub const DEFAULT_MAX_SAMPLES: usize = 10_000_000;

/// Most samples [`SamplingConfig::max_samples`] may allow: scoring (a
/// nearest-point query per sample) stays within minutes, and a coverage
/// tracker holding them within a few gigabytes.
pub const MAX_SAMPLES_CEILING: usize = 50_000_000;

/// Samples a [`SurfaceSampler`] draws per chunk unless told otherwise (about
/// 16 MB of [`SurfaceSample`]s).
pub const DEFAULT_SAMPLE_CHUNK: usize = 1 << 18;

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
    /// Budget of samples drawn: when `samples_per_m2` times the area of the
    /// faces meeting `region` exceeds it, the density is lowered to
    /// `max_samples / area` (see [`SurfaceSampler::samples_per_m2`]), so any
    /// scene is scored in bounded time. Memory is bounded by streaming anyway.
    pub max_samples: usize,
}

impl Default for SamplingConfig {
    fn default() -> Self {
        Self {
            samples_per_m2: 40_000.0,
            region: None,
            exposed_only: true,
            seed: 0,
            max_samples: DEFAULT_MAX_SAMPLES,
        }
    }
}

impl SamplingConfig {
    /// Check the fields: a finite positive density, a non-empty finite region,
    /// a budget of at least one sample. Errors name the field (`sampling.…`).
    pub fn validate(&self) -> Result<(), SceneError> {
        if !(self.samples_per_m2.is_finite() && self.samples_per_m2 > 0.0) {
            return Err(SceneError::invalid(
                "sampling.samples_per_m2",
                format!(
                    "expected a finite density > 0 (samples per m²), got {}",
                    self.samples_per_m2
                ),
            ));
        }
        if let Some(r) = &self.region {
            let finite = r.min.iter().chain(r.max.iter()).all(|v| v.is_finite());
            if !finite || (0..3).any(|i| r.min[i] > r.max[i]) {
                return Err(SceneError::invalid(
                    "sampling.region",
                    format!(
                        "expected a finite box with min <= max on every axis, got min {:?} max {:?}",
                        r.min.coords.as_slice(),
                        r.max.coords.as_slice()
                    ),
                ));
            }
        }
        if self.max_samples == 0 || self.max_samples > MAX_SAMPLES_CEILING {
            return Err(SceneError::invalid(
                "sampling.max_samples",
                format!(
                    "expected 1 to {MAX_SAMPLES_CEILING} samples, got {}",
                    self.max_samples
                ),
            ));
        }
        Ok(())
    }
}

/// Offset from the surface used to test whether a face is exposed.
const EXPOSURE_PROBE_M: Real = 1e-4;

/// A face being sampled: its triangle and how many samples it still owes.
#[derive(Clone, Copy, Debug)]
struct FaceCursor {
    face: usize,
    tri: Triangle,
    normal: UnitVector3,
    left: usize,
}

/// Uniform area sampling as a stream of chunks, so that any density and any
/// scene is sampled in bounded memory (see [`sample_surfaces`] for the rule).
/// The samples, and their order, do not depend on the chunk size.
///
/// ```
/// use scene::{SamplingConfig, Scene, SurfaceSampler, default_materials, MaterialId};
/// use geom::{Point3, primitives::cuboid};
/// let cube = cuboid(Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 1.0, 1.0));
/// let scene = Scene::from_mesh("cube", cube, default_materials(), MaterialId(0)).unwrap();
/// // 10¹² samples per m² asked for, at most 6 000 drawn: 1 000 per m².
/// let cfg = SamplingConfig { samples_per_m2: 1e12, max_samples: 6_000, ..SamplingConfig::default() };
/// let sampler = SurfaceSampler::new(&scene, &cfg).unwrap();
/// assert!(sampler.is_capped());
/// assert!((sampler.samples_per_m2() - 1_000.0).abs() < 1e-9);
/// let n: usize = sampler.map(|chunk| chunk.len()).sum();
/// assert!((6_000 - 12..=6_000 + 12).contains(&n));
/// ```
#[derive(Debug)]
pub struct SurfaceSampler<'a> {
    scene: &'a Scene,
    region: Option<Aabb>,
    exposed_only: bool,
    density: Real,
    capped: bool,
    rng: ChaCha8Rng,
    next_face: usize,
    current: Option<FaceCursor>,
    chunk: usize,
}

impl<'a> SurfaceSampler<'a> {
    /// A sampler for `scene` under a validated `cfg`, drawing
    /// [`DEFAULT_SAMPLE_CHUNK`] samples per chunk.
    pub fn new(scene: &'a Scene, cfg: &SamplingConfig) -> Result<Self, SceneError> {
        cfg.validate()?;
        let mesh = scene.mesh();
        let area: Real = (0..mesh.len())
            .map(|f| mesh.triangle(f))
            .filter(|t| Self::in_region(cfg.region.as_ref(), t) && t.normal().is_some())
            .map(|t| t.area())
            .sum();
        let budget = cfg.max_samples as Real;
        let capped = cfg.samples_per_m2 * area > budget;
        let density = if capped {
            budget / area
        } else {
            cfg.samples_per_m2
        };
        Ok(Self {
            scene,
            region: cfg.region,
            exposed_only: cfg.exposed_only,
            density,
            capped,
            rng: ChaCha8Rng::seed_from_u64(cfg.seed),
            next_face: 0,
            current: None,
            chunk: DEFAULT_SAMPLE_CHUNK,
        })
    }

    /// Draw at most `chunk` (at least 1) samples per chunk.
    #[must_use]
    pub fn with_chunk(mut self, chunk: usize) -> Self {
        self.chunk = chunk.max(1);
        self
    }

    /// The density actually sampled, per m²: the configured one, or less when
    /// [`SamplingConfig::max_samples`] capped it.
    pub fn samples_per_m2(&self) -> Real {
        self.density
    }

    /// `true` when the density was lowered to keep within `max_samples`.
    pub fn is_capped(&self) -> bool {
        self.capped
    }

    fn in_region(region: Option<&Aabb>, tri: &Triangle) -> bool {
        region.is_none_or(|r| Aabb::from_points([&tri.a, &tri.b, &tri.c]).intersects(r))
    }

    /// The next face owing samples (drawing its count), or `None` at the end.
    fn advance(&mut self) -> Option<FaceCursor> {
        let mesh = self.scene.mesh();
        while self.next_face < mesh.len() {
            let face = self.next_face;
            self.next_face += 1;
            let tri = mesh.triangle(face);
            if !Self::in_region(self.region.as_ref(), &tri) {
                continue;
            }
            let Some(normal) = tri.normal() else { continue };
            let expected = tri.area() * self.density;
            let left = expected.floor() as usize
                + usize::from(self.rng.random::<Real>() < expected.fract());
            return Some(FaceCursor {
                face,
                tri,
                normal,
                left,
            });
        }
        None
    }

    /// The next chunk of samples before the exposure filter; empty at the end.
    fn next_raw(&mut self) -> Vec<SurfaceSample> {
        let mut out = Vec::with_capacity(self.chunk.min(DEFAULT_SAMPLE_CHUNK));
        while out.len() < self.chunk {
            let mut cur = match self.current.take() {
                Some(c) => c,
                None => match self.advance() {
                    Some(c) => c,
                    None => break,
                },
            };
            let object = self.scene.triangle_object(FaceId(cur.face as u32));
            let material = self.scene.triangle_material(FaceId(cur.face as u32));
            while cur.left > 0 && out.len() < self.chunk {
                cur.left -= 1;
                let p =
                    geom::triangle::uniform_point(&cur.tri, self.rng.random(), self.rng.random());
                if self.region.as_ref().is_some_and(|r| !r.contains_point(&p)) {
                    continue;
                }
                out.push(SurfaceSample {
                    point: p,
                    normal: cur.normal,
                    face: FaceId(cur.face as u32),
                    object,
                    material,
                });
            }
            if cur.left > 0 {
                self.current = Some(cur);
            }
        }
        out
    }
}

impl Iterator for SurfaceSampler<'_> {
    type Item = Vec<SurfaceSample>;

    /// The next chunk (exposure-filtered when configured, so possibly shorter
    /// than the chunk size, even empty); `None` when every face is done.
    fn next(&mut self) -> Option<Vec<SurfaceSample>> {
        let raw = self.next_raw();
        if raw.is_empty() && self.current.is_none() && self.next_face >= self.scene.mesh().len() {
            return None;
        }
        if !self.exposed_only {
            return Some(raw);
        }
        let scene = self.scene;
        Some(
            raw.into_par_iter()
                .filter(|s| is_exposed(scene, s))
                .collect(),
        )
    }
}

/// Sample the scene's surfaces uniformly by area. Deterministic for a seed:
/// triangles are visited in order, each receiving `area × density` samples
/// (stochastically rounded), where the density is `cfg.samples_per_m2` capped
/// at `cfg.max_samples` over the sampled area. Holds every sample; stream a
/// [`SurfaceSampler`] instead to keep memory bounded.
pub fn sample_surfaces(
    scene: &Scene,
    cfg: &SamplingConfig,
) -> Result<Vec<SurfaceSample>, SceneError> {
    Ok(SurfaceSampler::new(scene, cfg)?.flatten().collect())
}

/// `false` when the sample's face lies inside or flush against another closed
/// object: a probe just off the face, on its outer side, is inside that object.
pub fn is_exposed(scene: &Scene, s: &SurfaceSample) -> bool {
    if !scene.objects()[s.object.index()].closed {
        return true;
    }
    let probe = s.point + s.normal.into_inner() * EXPOSURE_PROBE_M;
    !scene.is_inside_closed_object(&probe, Some(s.object))
}
