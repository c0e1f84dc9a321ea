//! Truncated signed distance fusion of sweeps and mesh extraction (A§5.1.1).
//!
//! Paul fuses scans with a volumetric signed-distance method (Curless &
//! Levoy, the thesis' ref. 42, improved by Webb, ref. 43) on a sparse index
//! of small grids, and extracts a mesh whose vertices feed the Scale-Like
//! Discs (A§5.2). This is that pipeline in voxblox's form:
//!
//! * **Storage**: a hash map of [`BlockKey`] → block of `b³` voxels (`b` =
//!   [`TsdfConfig::block_size`], a power of two, 8 by default), each voxel a
//!   signed distance and a weight; memory follows the observed surface, not
//!   the volume.
//! * **Integration** ([`TsdfIntegrator::Simple`], voxblox's "simple"): for
//!   each return `p` measured from origin `o`, the voxels the ray crosses
//!   within the truncation band `p ± τ·d̂` ([`traverse`](crate::traverse)
//!   walk) receive the projective distance `s = (p − c)·d̂` of their centre
//!   `c` (positive in front of the surface), clamped to `τ`, with weight `w`
//!   (1, or `1/r²`, linearly dropping to 0 between one voxel and `τ` behind
//!   the surface), and keep the running weighted average
//!   `D ← (W D + w s)/(W + w)`, `W ← min(W + w, W_max)`.
//!   [`TsdfIntegrator::Merged`] (voxblox's "merged") first bundles the
//!   returns that end in the same voxel into one ray from their mean origin
//!   to their mean point, weighing their count: for dense input (depth
//!   frames) the cost follows the surface voxels, not the returns.
//! * **Determinism with parallelism**: a first parallel pass lists the blocks
//!   each ray's band crosses; a stable counting sort gives every block its
//!   rays in input order; then blocks run in parallel, each walking its rays
//!   in order and applying the updates that fall inside it. Every voxel is
//!   updated by one block, in ray order, so the map is bit-identical whatever
//!   the thread count, and no buffer of per-voxel updates is ever built.
//! * **Mesh**: [marching cubes](crate::marching_cubes) over the lattice of
//!   voxel centres, block by block (in parallel) including the cubes that
//!   straddle block borders (corners read from the neighbouring blocks); a
//!   cube is meshed only when its eight corners are observed (`W ≥`
//!   [`TsdfConfig::mesh_min_weight`]), and blocks whose observed distances
//!   share one sign are skipped. Vertices are identified by the lattice edge
//!   (or lattice point, when a distance is exactly 0) they lie on: welded
//!   through dense per-block tables, and through one hash map only for those
//!   that cubes of another block can share. The mesh has no duplicate
//!   vertices; triangles that collapse are dropped. Where the observed
//!   surface is closed, the mesh is watertight (every edge shared by exactly
//!   two triangles, wound oppositely). Triangles wind anticlockwise seen from
//!   the free side (normals point toward the sensor, out of the solid).

use crate::MapError;
use crate::hash::FxHashMap;
use crate::key::{BlockKey, VoxelKey};
use crate::marching_cubes::{EDGES, case_table, corner_offset};
use crate::sweep::check_point_list;
use crate::traverse::{MAX_VOXEL_COORD, Walk, to_voxel_units};
use geom::{Point3, Real, Vector3};
use rayon::prelude::*;
use scene::TriMesh;
use sensor::Sweep;
use serde::{Deserialize, Serialize};

/// How much a single observation counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TsdfWeighting {
    /// Every observation weighs 1.
    Constant,
    /// Weight `1/r²` (r in metres): near, more precise returns count more.
    InverseSquare,
}

/// How returns become ray updates (voxblox's integrators).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TsdfIntegrator {
    /// Every return casts its own band ("simple"): the most detail, the cost
    /// grows with the number of returns.
    Simple,
    /// Returns ending in the same voxel are merged first into one ray from
    /// their mean origin to their mean point, weighing their count
    /// ("merged"): dense inputs (depth frames, repeated sweeps of one
    /// surface) cost per surface voxel instead of per return.
    Merged,
}

/// Configuration of the TSDF.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TsdfConfig {
    /// Voxel edge, metres.
    pub voxel_m: Real,
    /// Truncation distance `τ`, metres (3–5 voxels: wider than the range noise,
    /// narrower than the thinnest gap worth keeping).
    pub truncation_m: Real,
    /// Voxels per block edge: a power of two from 2 to 64.
    pub block_size: usize,
    /// Weight cap `W_max`: older observations fade once reached.
    pub max_weight: Real,
    /// Returns nearer than this are skipped, metres.
    pub min_range_m: Real,
    /// Returns farther than this are skipped, metres.
    pub max_range_m: Real,
    /// Observation weight.
    pub weighting: TsdfWeighting,
    /// Simple or merged integration.
    pub integrator: TsdfIntegrator,
    /// Let the weight drop linearly to 0 from one voxel to `τ` behind the
    /// surface (voxblox's drop-off), so thin objects seen from both sides keep
    /// both faces.
    pub dropoff: bool,
    /// A voxel takes part in meshing when its weight reaches this.
    pub mesh_min_weight: Real,
}

/// The longest truncation band, in voxels each side of a surface (voxblox
/// uses 2–4): every voxel of the band is stored, so a finer voxel at the same
/// truncation multiplies the memory by the cube of the ratio.
pub const MAX_TRUNCATION_VOXELS: Real = 64.0;

impl Default for TsdfConfig {
    fn default() -> Self {
        Self {
            voxel_m: 0.01,
            truncation_m: 0.04,
            block_size: 8,
            max_weight: 1000.0,
            min_range_m: 0.02,
            max_range_m: 4.0,
            weighting: TsdfWeighting::Constant,
            integrator: TsdfIntegrator::Simple,
            dropoff: true,
            mesh_min_weight: 0.5,
        }
    }
}

impl TsdfConfig {
    /// The default configuration at another voxel size, truncation 4 voxels.
    pub fn with_voxel_m(voxel_m: Real) -> Self {
        Self {
            voxel_m,
            truncation_m: 4.0 * voxel_m,
            ..Self::default()
        }
    }

    /// Check every field.
    pub fn validate(&self) -> Result<(), MapError> {
        let positive = |v: Real| v.is_finite() && v > 0.0;
        if !positive(self.voxel_m) {
            return Err(MapError::config(
                "tsdf.voxel_m",
                "a positive length",
                self.voxel_m,
            ));
        }
        if !(self.truncation_m.is_finite()
            && self.truncation_m >= self.voxel_m
            && self.truncation_m <= MAX_TRUNCATION_VOXELS * self.voxel_m)
        {
            return Err(MapError::config(
                "tsdf.truncation_m",
                "a length of 1 to 64 voxels (tsdf.voxel_m)",
                self.truncation_m,
            ));
        }
        if !((2..=64).contains(&self.block_size) && self.block_size.is_power_of_two()) {
            return Err(MapError::config(
                "tsdf.block_size",
                "a block edge of 2, 4, 8, 16, 32 or 64 voxels",
                self.block_size,
            ));
        }
        if !positive(self.max_weight) {
            return Err(MapError::config(
                "tsdf.max_weight",
                "a positive weight",
                self.max_weight,
            ));
        }
        if !(self.min_range_m.is_finite() && self.min_range_m >= 0.0) {
            return Err(MapError::config(
                "tsdf.min_range_m",
                "a non-negative length",
                self.min_range_m,
            ));
        }
        if !(self.max_range_m.is_finite() && self.max_range_m > self.min_range_m) {
            return Err(MapError::config(
                "tsdf.max_range_m",
                "a length greater than min_range_m",
                self.max_range_m,
            ));
        }
        if !(self.mesh_min_weight.is_finite() && self.mesh_min_weight > 0.0) {
            return Err(MapError::config(
                "tsdf.mesh_min_weight",
                "a positive weight",
                self.mesh_min_weight,
            ));
        }
        Ok(())
    }
}

/// One TSDF voxel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TsdfVoxel {
    /// Weighted mean signed distance to the surface, metres (positive in
    /// front, toward the sensors), within `±τ`.
    pub distance_m: f32,
    /// Accumulated weight (0: never observed).
    pub weight: f32,
}

#[derive(Clone, Debug)]
struct Block {
    key: BlockKey,
    voxels: Box<[TsdfVoxel]>,
}

/// What one integration did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TsdfStats {
    /// Returns integrated.
    pub points: usize,
    /// Returns skipped for their range.
    pub skipped: usize,
    /// Voxel updates applied.
    pub voxel_updates: usize,
    /// Blocks allocated.
    pub new_blocks: usize,
}

/// A sparse block TSDF. See the [module docs](self).
#[derive(Clone)]
pub struct TsdfMap {
    config: TsdfConfig,
    index: FxHashMap<BlockKey, u32>,
    blocks: Vec<Block>,
}

impl std::fmt::Debug for TsdfMap {
    /// A summary: the blocks hold millions of voxels.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TsdfMap")
            .field("config", &self.config)
            .field("blocks", &self.blocks.len())
            .finish_non_exhaustive()
    }
}

impl TsdfMap {
    /// An empty map.
    pub fn new(config: TsdfConfig) -> Result<Self, MapError> {
        config.validate()?;
        Ok(Self {
            config,
            index: FxHashMap::default(),
            blocks: Vec::new(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &TsdfConfig {
        &self.config
    }

    /// Number of allocated blocks.
    pub fn block_count(&self) -> usize {
        self.blocks.len()
    }

    /// Keys of the allocated blocks, sorted.
    pub fn block_keys(&self) -> Vec<BlockKey> {
        let mut keys: Vec<BlockKey> = self.blocks.iter().map(|b| b.key).collect();
        keys.sort_unstable();
        keys
    }

    /// A voxel (`None` where no block is allocated).
    pub fn voxel(&self, key: VoxelKey) -> Option<TsdfVoxel> {
        let shift = self.config.block_size.trailing_zeros();
        let b = self.index.get(&key.block_of_pow2(shift))?;
        Some(self.blocks[*b as usize].voxels[local_index(key, shift)])
    }

    /// Integrate a sweep (every return along its ray).
    pub fn integrate_sweep(&mut self, sweep: &Sweep) -> TsdfStats {
        self.integrate_checked(&sweep.origins(), &sweep.positions())
    }

    /// Integrate points measured along rays from per-point `origins`. Fails,
    /// changing nothing, on empty or mismatched lists or non-finite
    /// coordinates.
    pub fn integrate_points(
        &mut self,
        origins: &[Point3],
        points: &[Point3],
    ) -> Result<TsdfStats, MapError> {
        check_point_list("point list", origins, points)?;
        Ok(self.integrate_checked(origins, points))
    }

    /// The rays to cast: one per return in range (simple), or one per voxel
    /// holding returns (merged), in first-seen order; and the count skipped.
    fn rays_to_cast(&self, origins: &[Point3], points: &[Point3]) -> (Vec<RayIn>, usize) {
        let cfg = &self.config;
        let in_range = |o: &Point3, p: &Point3| {
            let r = (p - o).norm();
            r > 0.0 && r >= cfg.min_range_m && r <= cfg.max_range_m
        };
        let mut rays = Vec::with_capacity(points.len());
        let mut skipped = 0;
        match cfg.integrator {
            TsdfIntegrator::Simple => {
                for (o, p) in origins.iter().zip(points) {
                    if in_range(o, p) {
                        rays.push(RayIn {
                            origin: *o,
                            point: *p,
                            count: 1.0,
                        });
                    } else {
                        skipped += 1;
                    }
                }
            }
            TsdfIntegrator::Merged => {
                let mut slot: FxHashMap<VoxelKey, usize> = FxHashMap::default();
                for (o, p) in origins.iter().zip(points) {
                    let key = VoxelKey::of_point(p, cfg.voxel_m);
                    let Some(key) = key.filter(|_| in_range(o, p)) else {
                        skipped += 1;
                        continue;
                    };
                    let i = *slot.entry(key).or_insert_with(|| {
                        rays.push(RayIn {
                            origin: Point3::origin(),
                            point: Point3::origin(),
                            count: 0.0,
                        });
                        rays.len() - 1
                    });
                    let r = &mut rays[i];
                    r.origin += o.coords;
                    r.point += p.coords;
                    r.count += 1.0;
                }
                for r in &mut rays {
                    r.origin /= r.count;
                    r.point /= r.count;
                }
            }
        }
        (rays, skipped)
    }

    fn integrate_checked(&mut self, origins: &[Point3], points: &[Point3]) -> TsdfStats {
        let (rays, mut skipped) = self.rays_to_cast(origins, points);
        let rays = rays.as_slice();
        let cfg = self.config;
        let bs = cfg.block_size as i32;
        let shift = cfg.block_size.trailing_zeros();
        // 1. The blocks each ray's band crosses, in parallel, in ray order.
        let chunks: Vec<(Vec<(u32, BlockKey)>, usize)> = rays
            .par_chunks(1024)
            .enumerate()
            .map(|(ci, chunk)| {
                let mut out = Vec::with_capacity(chunk.len() * 2);
                let mut skipped = 0;
                for (k, ray_in) in chunk.iter().enumerate() {
                    let ray = (ci * 1024 + k) as u32;
                    let Some(band) = Band::new(&cfg, ray_in) else {
                        skipped += 1;
                        continue;
                    };
                    let mut last = None;
                    band.walk_keys(|key| {
                        let b = key.block_of_pow2(shift);
                        if last != Some(b) {
                            // The walk is monotone per axis: a block once left is never re-entered.
                            out.push((ray, b));
                            last = Some(b);
                        }
                    });
                }
                (out, skipped)
            })
            .collect();
        skipped += chunks.iter().map(|c| c.1).sum::<usize>();
        // 2. Block indices (new blocks allocated in first-seen order) and a
        //    stable counting sort of (ray, block) pairs by block.
        let first_new = self.blocks.len();
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(chunks.iter().map(|c| c.0.len()).sum());
        for (ray_blocks, _) in &chunks {
            for &(ray, bk) in ray_blocks {
                let bi = if let Some(i) = self.index.get(&bk) {
                    *i
                } else {
                    let i = self.blocks.len() as u32;
                    self.index.insert(bk, i);
                    self.blocks.push(Block {
                        key: bk,
                        voxels: vec![TsdfVoxel::default(); cfg.block_size.pow(3)]
                            .into_boxed_slice(),
                    });
                    i
                };
                pairs.push((ray, bi));
            }
        }
        drop(chunks);
        let nb = self.blocks.len();
        let mut start = vec![0usize; nb + 1];
        for &(_, b) in &pairs {
            start[b as usize + 1] += 1;
        }
        for b in 0..nb {
            start[b + 1] += start[b];
        }
        let mut fill = start.clone();
        let mut rays_of = vec![0u32; pairs.len()];
        for &(ray, b) in &pairs {
            rays_of[fill[b as usize]] = ray;
            fill[b as usize] += 1;
        }
        // 3. Each block walks its rays in ray order and applies the updates of
        //    its own voxels; blocks in parallel. Every voxel belongs to one
        //    block, so each update is applied once, in ray order.
        let max_w = cfg.max_weight as f32;
        let updates: usize = self
            .blocks
            .par_iter_mut()
            .enumerate()
            .map(|(b, block)| {
                let first = block.key.first_voxel(bs).coords();
                let mut applied = 0;
                for &ray in &rays_of[start[b]..start[b + 1]] {
                    let Some(band) = Band::new(&cfg, &rays[ray as usize]) else {
                        continue;
                    };
                    band.walk_within(first, bs, |l, sdf, w| {
                        let v = &mut block.voxels[(l[0] + bs * (l[1] + bs * l[2])) as usize];
                        let total = v.weight + w;
                        v.distance_m = (v.distance_m * v.weight + sdf * w) / total;
                        v.weight = total.min(max_w);
                        applied += 1;
                    });
                }
                applied
            })
            .sum();
        TsdfStats {
            points: points.len() - skipped,
            skipped,
            voxel_updates: updates,
            new_blocks: self.blocks.len() - first_new,
        }
    }

    /// Extract the zero level set as a welded triangle mesh (see the [module
    /// docs](self)). Deterministic: blocks are meshed in key order.
    pub fn extract_mesh(&self) -> TriMesh {
        let mut order: Vec<usize> = (0..self.blocks.len()).collect();
        order.sort_unstable_by_key(|&i| self.blocks[i].key);
        let pieces: Vec<BlockMesh> = order
            .par_iter()
            .map(|&bi| self.mesh_block(&self.blocks[bi]))
            .collect();
        // Weld: vertices inside a block are its own; only vertices that cubes
        // of other blocks can share go through the global map.
        let (n_verts, n_tris, n_border) = pieces.iter().fold((0, 0, 0), |acc, p| {
            (
                acc.0 + p.vertices.len(),
                acc.1 + p.triangles.len(),
                acc.2 + p.border.iter().filter(|b| b.is_some()).count(),
            )
        });
        let mut shared: FxHashMap<VertexKey, u32> = FxHashMap::default();
        shared.reserve(n_border);
        let mut mesh = TriMesh {
            vertices: Vec::with_capacity(n_verts),
            triangles: Vec::with_capacity(n_tris),
        };
        let mut global = Vec::new();
        for piece in pieces {
            global.clear();
            for (p, border) in piece.vertices.iter().zip(&piece.border) {
                let fresh = mesh.vertices.len() as u32;
                let id = match border {
                    Some(key) => *shared.entry(*key).or_insert(fresh),
                    None => fresh,
                };
                if id == fresh {
                    mesh.vertices.push(*p);
                }
                global.push(id);
            }
            for t in &piece.triangles {
                let idx = t.map(|i| global[i as usize]);
                if idx[0] == idx[1] || idx[1] == idx[2] || idx[0] == idx[2] {
                    continue;
                }
                let [a, b, c] = idx.map(|i| mesh.vertices[i as usize]);
                if (b - a).cross(&(c - a)).norm_squared() == 0.0 {
                    continue;
                }
                mesh.triangles.push(idx);
            }
        }
        mesh
    }

    /// Marching cubes over the cubes whose lowest corner lies in `block`,
    /// with vertices welded inside the block (dense tables over its lattice
    /// edges and points) and tagged with their global key where another
    /// block's cubes can share them.
    fn mesh_block(&self, block: &Block) -> BlockMesh {
        let bs = self.config.block_size;
        let voxel_m = self.config.voxel_m;
        let mut out = BlockMesh::default();
        // Blocks whose observed distances all have one sign hold no surface.
        let Some(samples) = self.gather(block, self.config.mesh_min_weight as f32) else {
            return out;
        };
        let table = case_table();
        let first = block.key.first_voxel(bs as i32);
        let n = bs + 1;
        let corner: [usize; 8] = std::array::from_fn(|c| {
            let o = corner_offset(c as u8).map(|v| v as usize);
            o[0] + n * (o[1] + n * o[2])
        });
        // Local vertex of each lattice edge (3 per lattice point) and point.
        let mut edge_slot = vec![u32::MAX; n * n * n * 3];
        let mut point_slot = vec![u32::MAX; n * n * n];
        let interior = |l: [i32; 3], axis: Option<usize>| {
            (0..3).all(|b| {
                if Some(b) == axis {
                    l[b] >= 0 && l[b] < bs as i32
                } else {
                    l[b] >= 1 && l[b] < bs as i32
                }
            })
        };
        for z in 0..bs {
            for y in 0..bs {
                for x in 0..bs {
                    let at = x + n * (y + n * z);
                    let d: [f32; 8] = std::array::from_fn(|c| samples[at + corner[c]]);
                    // NaN: unobserved; a cube is meshed only when all eight are observed.
                    if d.iter().any(|v| v.is_nan()) {
                        continue;
                    }
                    let mask = (0..8).fold(0u8, |m, c| m | (u8::from(d[c] < 0.0) << c));
                    if mask == 0 || mask == 255 {
                        continue;
                    }
                    let base = first.offset(x as i32, y as i32, z as i32);
                    let case = table.case(mask);
                    let mut local = [u32::MAX; 12];
                    let mut vertex = |e: u8, out: &mut BlockMesh| -> u32 {
                        if local[usize::from(e)] != u32::MAX {
                            return local[usize::from(e)];
                        }
                        let (key, p) = edge_vertex(base, e, &d, voxel_m);
                        let (slot, border) = match key {
                            VertexKey::Edge(k, axis) => {
                                let l = lattice(k, first);
                                let i = (l[0] as usize + n * (l[1] as usize + n * l[2] as usize))
                                    * 3
                                    + usize::from(axis);
                                (&mut edge_slot[i], !interior(l, Some(usize::from(axis))))
                            }
                            VertexKey::Corner(k) => {
                                let l = lattice(k, first);
                                let i = l[0] as usize + n * (l[1] as usize + n * l[2] as usize);
                                (&mut point_slot[i], !interior(l, None))
                            }
                        };
                        if *slot == u32::MAX {
                            *slot = out.vertices.len() as u32;
                            out.vertices.push(p);
                            out.border.push(border.then_some(key));
                        }
                        local[usize::from(e)] = *slot;
                        *slot
                    };
                    let mut centre = [u32::MAX; 4];
                    for tri in &case.triangles {
                        let idx = tri.map(|v| {
                            if v < 12 {
                                return vertex(v, &mut out);
                            }
                            let l = usize::from(v - 12);
                            if centre[l] == u32::MAX {
                                let ring = &case.loops[l];
                                let sum = ring.iter().fold(Vector3::zeros(), |acc, &e| {
                                    acc + edge_vertex(base, e, &d, voxel_m).1.coords
                                });
                                centre[l] = out.vertices.len() as u32;
                                out.vertices.push(Point3::from(sum / ring.len() as Real));
                                out.border.push(None);
                            }
                            centre[l]
                        });
                        out.triangles.push(idx);
                    }
                }
            }
        }
        out
    }

    /// The `(b+1)³` distances a block's cubes read (its own voxels and the
    /// first layer of the +x/+y/+z neighbours), NaN where unobserved; `None`
    /// when the observed ones all have the same sign (no surface).
    fn gather(&self, block: &Block, min_w: f32) -> Option<Vec<f32>> {
        let bs = self.config.block_size;
        let n = bs + 1;
        let mut out = vec![f32::NAN; n * n * n];
        let neighbours: [Option<&Block>; 8] = std::array::from_fn(|c| {
            let o = corner_offset(c as u8);
            self.index
                .get(&block.key.offset(o[0], o[1], o[2]))
                .map(|&i| &self.blocks[i as usize])
        });
        let (mut negative, mut positive) = (false, false);
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let (bx, by, bz) = (
                        usize::from(x == bs),
                        usize::from(y == bs),
                        usize::from(z == bs),
                    );
                    let Some(b) = neighbours[bx | (by << 1) | (bz << 2)] else {
                        continue;
                    };
                    // x ≤ bs: the last layer is the neighbour's first.
                    let wrap = |v: usize| if v == bs { 0 } else { v };
                    let (lx, ly, lz) = (wrap(x), wrap(y), wrap(z));
                    let v = b.voxels[lx + bs * (ly + bs * lz)];
                    if v.weight >= min_w {
                        out[x + n * (y + n * z)] = v.distance_m;
                        negative |= v.distance_m < 0.0;
                        positive |= v.distance_m >= 0.0;
                    }
                }
            }
        }
        (negative && positive).then_some(out)
    }

    /// Check the block index and every voxel: finite distances within `±τ`,
    /// weights in `[0, W_max]`.
    pub fn check_invariants(&self) -> Result<(), geom::InvariantViolation> {
        self.invariant_detail()
            .map_err(|d| geom::InvariantViolation::new("TSDF", d))
    }

    /// The check of `check_invariants`, the failure as text.
    fn invariant_detail(&self) -> Result<(), String> {
        if self.index.len() != self.blocks.len() {
            return Err(format!(
                "{} index entries for {} blocks",
                self.index.len(),
                self.blocks.len()
            ));
        }
        let tau = self.config.truncation_m as f32 * (1.0 + 1e-6);
        let max_w = self.config.max_weight as f32;
        for (i, b) in self.blocks.iter().enumerate() {
            if self.index.get(&b.key) != Some(&(i as u32)) {
                return Err(format!("{} is not indexed at {i}", b.key));
            }
            if b.voxels.len() != self.config.block_size.pow(3) {
                return Err(format!("{} has {} voxels", b.key, b.voxels.len()));
            }
            for v in &b.voxels {
                if !(v.distance_m.is_finite() && v.distance_m.abs() <= tau) {
                    return Err(format!("{}: distance {} beyond ±τ", b.key, v.distance_m));
                }
                if !(v.weight >= 0.0 && v.weight <= max_w) {
                    return Err(format!("{}: weight {}", b.key, v.weight));
                }
            }
        }
        Ok(())
    }
}

#[inline]
fn local_index(key: VoxelKey, shift: u32) -> usize {
    let k = key.coords();
    let mask = (1i32 << shift) - 1;
    let l = k.map(|v| (v & mask) as usize);
    l[0] | (l[1] << shift) | (l[2] << (2 * shift))
}

/// A ray to integrate: a return, or the mean of the returns merged into one
/// voxel and how many they were.
#[derive(Clone, Copy, Debug)]
struct RayIn {
    origin: Point3,
    point: Point3,
    count: Real,
}

/// The truncation band of one return, in voxel units: the part of its ray
/// within `τ` of the measured point, and the observation's weight.
#[derive(Clone, Copy, Debug)]
struct Band {
    /// The measured point, voxel units.
    point: [Real; 3],
    /// Unit ray direction.
    dir: Vector3,
    start: [Real; 3],
    end: [Real; 3],
    base_weight: Real,
    /// `τ`, voxel units.
    truncation: Real,
    voxel_m: Real,
    dropoff: bool,
}

impl Band {
    /// The band of a ray to cast; `None` when it has zero length or lies
    /// beyond a billion voxels from the origin.
    #[inline]
    fn new(cfg: &TsdfConfig, ray: &RayIn) -> Option<Self> {
        let v: Vector3 = ray.point - ray.origin;
        let r = v.norm();
        if r == 0.0 {
            return None;
        }
        let dir = v / r;
        let point = to_voxel_units(&ray.point, cfg.voxel_m)?;
        let tau = cfg.truncation_m / cfg.voxel_m;
        let back = tau.min(r / cfg.voxel_m);
        let start = [0, 1, 2].map(|ax| point[ax] - dir[ax] * back);
        let end = [0, 1, 2].map(|ax| point[ax] + dir[ax] * tau);
        if start.iter().chain(&end).any(|c| c.abs() > MAX_VOXEL_COORD) {
            return None;
        }
        Some(Self {
            point,
            dir,
            start,
            end,
            base_weight: ray.count
                * match cfg.weighting {
                    TsdfWeighting::Constant => 1.0,
                    TsdfWeighting::InverseSquare => 1.0 / (r * r),
                },
            truncation: tau,
            voxel_m: cfg.voxel_m,
            dropoff: cfg.dropoff,
        })
    }

    /// Visit the keys of the band's voxels, nothing else computed.
    #[inline]
    fn walk_keys(&self, mut visit: impl FnMut(VoxelKey)) {
        let mut w = Walk::new(self.start, self.end);
        loop {
            let c = w.cell();
            visit(VoxelKey::new(c[0] as i32, c[1] as i32, c[2] as i32));
            if !w.advance() {
                break;
            }
        }
    }

    /// Visit the band's voxels (the [`traverse`](crate::traverse) walk from
    /// `τ` before the point to `τ` behind it) that lie in the cube of `size`
    /// voxels from key `first`, each by its offset from `first`, with its
    /// projective distance in metres (clamped to `τ`) and weight; voxels
    /// more than `τ` behind the surface or of zero weight are skipped. The
    /// walk ends when it leaves the cube: it is monotone per axis, so a cube
    /// once left is never re-entered.
    #[inline]
    fn walk_within(&self, first: [i32; 3], size: i32, mut visit: impl FnMut([i32; 3], f32, f32)) {
        let tau = self.truncation;
        let mut w = Walk::new(self.start, self.end);
        let mut entered = false;
        loop {
            let c = w.cell();
            // Cells are within a billion voxels of the origin (`Band::new`).
            let l = [0, 1, 2].map(|ax| c[ax] as i32 - first[ax]);
            if l.iter().all(|v| (*v as u32) < size as u32) {
                entered = true;
                let sdf = (0..3)
                    .map(|ax| (self.point[ax] - (c[ax] as Real + 0.5)) * self.dir[ax])
                    .sum::<Real>();
                if sdf >= -tau {
                    let mut weight = self.base_weight;
                    if self.dropoff && sdf < -1.0 {
                        weight *= ((tau + sdf) / (tau - 1.0)).max(0.0);
                    }
                    if weight > 0.0 {
                        visit(l, (sdf.min(tau) * self.voxel_m) as f32, weight as f32);
                    }
                }
            } else if entered {
                break;
            }
            if !w.advance() {
                break;
            }
        }
    }
}

/// Where a mesh vertex lies on the lattice of voxel centres: on an edge
/// (lower voxel and axis), or exactly at a lattice point. (Loop centres are
/// private to their cube and need no key.)
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum VertexKey {
    Edge(VoxelKey, u8),
    Corner(VoxelKey),
}

/// The mesh of one block before welding across blocks.
#[derive(Debug, Default)]
struct BlockMesh {
    vertices: Vec<Point3>,
    /// The global key of vertices that cubes of other blocks may share.
    border: Vec<Option<VertexKey>>,
    triangles: Vec<[u32; 3]>,
}

/// `k − first`: a lattice point's coordinates in its block's `(b+1)³` table.
#[inline]
fn lattice(k: VoxelKey, first: VoxelKey) -> [i32; 3] {
    let (k, f) = (k.coords(), first.coords());
    [k[0] - f[0], k[1] - f[1], k[2] - f[2]]
}

/// The vertex on cube edge `e` of the cube whose lowest corner is voxel
/// `base`, from corner distances `d`.
#[inline]
fn edge_vertex(base: VoxelKey, e: u8, d: &[f32; 8], voxel_m: Real) -> (VertexKey, Point3) {
    let (ca, cb, axis) = EDGES[usize::from(e)];
    let oa = corner_offset(ca);
    let ka = base.offset(oa[0], oa[1], oa[2]);
    let (da, db) = (
        Real::from(d[usize::from(ca)]),
        Real::from(d[usize::from(cb)]),
    );
    let t = da / (da - db);
    let pa = ka.center(voxel_m);
    if t <= 0.0 {
        return (VertexKey::Corner(ka), pa);
    }
    let ob = corner_offset(cb);
    let kb = base.offset(ob[0], ob[1], ob[2]);
    if t >= 1.0 {
        return (VertexKey::Corner(kb), kb.center(voxel_m));
    }
    let mut p = pa;
    p[usize::from(axis)] += t * voxel_m;
    (VertexKey::Edge(ka, axis), p)
}
