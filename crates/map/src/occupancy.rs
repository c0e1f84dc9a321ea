//! The tri-state occupancy grid and its entropies (A§4.1–4.3).
//!
//! # Model
//!
//! Each voxel of the grid over region A3 is **unknown**, **free** or
//! **occupied**, with probabilities of occupancy 0.5, 0 and 1 (A§4.2). A
//! measured ray frees every voxel it passes through before the hit and
//! occupies the voxel holding the hit ([`traverse`](crate::traverse) gives the
//! exact voxel sequence). Rays without a return carve nothing: a missing
//! return is as likely a dark or specular surface as empty space.
//!
//! **Occupied is sticky.** States only move up the order unknown < free <
//! occupied: a later ray passing through an occupied voxel does not free it.
//! Paul's model assumes a static structure and a sensor that detects every
//! surface in view (A§4.2); a voxel that once returned a surface point holds
//! a surface, and a later ray crossing that voxel has almost always grazed
//! the part of the 10 mm cube in front of the surface (neighbouring rays of a
//! sweep cross surface voxels at shallow angles all the time) rather than
//! found the surface gone. Freeing on pass-through would punch holes in every
//! obliquely seen wall. The price: a spurious return in free space stays
//! occupied; the occupied count is then an upper bound. Because the update is
//! a maximum in a fixed order, the result of integrating rays does not depend
//! on their order, which is what lets a sweep be integrated in parallel and
//! still give bit-identical maps and counts.
//!
//! # Entropies
//!
//! * [`OccupancyGrid::h1_unweighted`] — A eq. 4.8–4.10: a known voxel carries
//!   no information and an unknown one `ln 2`, so `H1 = n_u ln 2` over every
//!   voxel of the grid (A3). Natural logarithms (nats) throughout.
//! * [`OccupancyGrid::h1_weighted`] — A eq. 4.11 with the occlusion
//!   importance of A§4.2.1:
//!
//!   `H1 = ln 2 · Σ_k c_wk · ñ_u,Ak`, with `ñ_u,Ak = Σ_{unknown j ∈ A_k} ι_j`.
//!
//!   The regions are nested (A1 ⊂ A2 ⊂ A3) and `n_u,Ak` counts every unknown
//!   voxel of `A_k`, as eq. 4.11 is written, so an unknown voxel of A1
//!   contributes `c_w1 + c_w2 + c_w3 = 1` (times `ln 2`), one of A2 \ A1
//!   `c_w2 + c_w3 = 0.4` and one of A3 \ A2 `c_w3 = 0.05` with the default
//!   weights {0.6, 0.35, 0.05}. The importance `ι_j` is 1 for an ordinary
//!   voxel and [`OcclusionConfig::importance`] for a voxel flagged as
//!   occluded: one that was still unknown when the segment between two
//!   grid-adjacent returns with a large range differential (`|r_{i,j} −
//!   r_{i+1,j}|` or `|r_{i,j} − r_{i,j+1}|` above
//!   [`OcclusionConfig::range_jump_m`]) passed through it (A§4.2.1, Fig. 4.5,
//!   eq. 4.12). Without flags, the formula is exactly eq. 4.11.
//! * [`OccupancyGrid::h2`] — A eq. 4.13–4.14 from a supplied per-voxel
//!   probability of C-space interference `P(x_c)` (computed by the exploration
//!   stage from the roadmap's node usage): the binary entropy of the
//!   one-sided probability `P(x_c)/2`, summed over **unknown** voxels only
//!   ("geometric voxels which are known to be free or occupied contain
//!   neither geometric information nor C-space information", A§4.3). See
//!   [`h2_term`] for the reading of eq. 4.14.
//!
//! # Storage
//!
//! States are packed two bits per voxel in a dense array over A3, stored in
//! 8³ bricks for cache locality along rays: 420³ ≈ 74 M voxels at 10 mm take
//! 19 MB, a flag bit per voxel for occlusion importance another 9.5 MB.
//! Dense beats sparse blocks here: rays cross mostly free space, every voxel
//! of A3 is touched within a few sweeps, and the exploration stage will cast
//! rays of ~1 500 candidate viewpoints through the grid, where a state lookup
//! must be an index computation and one load, not a hash probe. The C-space
//! probabilities, which exist only for voxels the arm can reach, live in
//! sparse 8³ blocks behind a dense block index. Region counts are maintained
//! incrementally on every state change, so entropies are O(1) (H2 is a pass
//! over the stored probabilities).
//!
//! # Parallel integration
//!
//! The rays of a sweep are integrated in parallel. A voxel already at or
//! above its new state costs one plain load; a change is an atomic OR on
//! its 64-bit word, whose returned old value tells exactly one thread that it
//! made the change and must count it. Counts are integers summed per thread,
//! so maps, counts and entropies are identical for any thread count.

use crate::MapError;
use crate::key::VoxelKey;
use crate::regions::{Region, RegionsConfig};
use crate::stats::{OccupancyReport, RegionReport};
use crate::sweep::{check_point_list, list_range_jumps, range_jumps};
use crate::traverse::Walk;
use geom::{Aabb, Point3, Real, UnitVector3, Vector3};
use rayon::prelude::*;
use sensor::Sweep;
use serde::{Deserialize, Serialize};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// The state of a voxel (A§4.2: probability of occupancy 0.5, 0, 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum VoxelState {
    /// Never crossed by a ray nor hit.
    Unknown,
    /// Crossed by a ray before its hit.
    Free,
    /// Holds a measured surface point.
    Occupied,
}

impl VoxelState {
    /// Probability of occupancy `P(x_o)`.
    pub const fn occupancy_probability(self) -> Real {
        match self {
            Self::Unknown => 0.5,
            Self::Free => 0.0,
            Self::Occupied => 1.0,
        }
    }
}

const BITS_UNKNOWN: u64 = 0b00;
const BITS_FREE: u64 = 0b01;
const BITS_OCCUPIED: u64 = 0b11;

/// Occlusion importance (A§4.2.1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OcclusionConfig {
    /// Flag occluded voxels at all.
    pub enabled: bool,
    /// A range differential between grid-adjacent returns above this is an
    /// occlusion edge, metres. The default, 0.1 m, is ten times the near-range
    /// noise and needs a surface seen within ~7° of grazing to arise between
    /// neighbouring rays of one surface at 2 m.
    pub range_jump_m: Real,
    /// Importance `ι` of a flagged unknown voxel in eq. 4.11 (an ordinary
    /// voxel has 1). Paul gives no value; 2 makes an occluded voxel count
    /// double.
    pub importance: Real,
    /// For plain point lists (no grid): consecutive points with the same ray
    /// origin whose directions are at most this many degrees apart count as
    /// neighbouring rays of a scan. 0 skips occlusion weighting for lists.
    pub list_neighbour_max_deg: Real,
}

impl Default for OcclusionConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            range_jump_m: 0.10,
            importance: 2.0,
            list_neighbour_max_deg: 1.0,
        }
    }
}

/// Configuration of the occupancy grid.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OccupancyConfig {
    /// Voxel edge, metres.
    pub voxel_m: Real,
    /// Regions of interest; the grid covers A3.
    pub regions: RegionsConfig,
    /// Region weights `{c_w1, c_w2, c_w3}` of eq. 4.11 (A Table 6.1).
    #[serde(deserialize_with = "geom::exact::array")]
    pub weights: [Real; 3],
    /// Occlusion importance.
    pub occlusion: OcclusionConfig,
    /// A ray of a gridded sweep that returned nothing frees the voxels along
    /// it up to this distance, metres (Paul's perfect-detection model: no
    /// return means no surface within range; set it a little short of the
    /// scanner's range so noise at the far end cannot free a surface).
    /// `None` (the default): rays without a return change nothing.
    pub free_misses_m: Option<Real>,
}

impl Default for OccupancyConfig {
    fn default() -> Self {
        Self {
            voxel_m: 0.01,
            regions: RegionsConfig::default(),
            weights: [0.6, 0.35, 0.05],
            occlusion: OcclusionConfig::default(),
            free_misses_m: None,
        }
    }
}

impl OccupancyConfig {
    /// The default configuration at another voxel size.
    pub fn with_voxel_m(voxel_m: Real) -> Self {
        Self {
            voxel_m,
            ..Self::default()
        }
    }

    /// Check every field.
    pub fn validate(&self) -> Result<(), MapError> {
        if !(self.voxel_m.is_finite() && self.voxel_m > 0.0) {
            return Err(MapError::config(
                "occupancy.voxel_m",
                "a positive length",
                self.voxel_m,
            ));
        }
        self.regions.validate()?;
        if self.weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
            return Err(MapError::config(
                "occupancy.weights",
                "three finite, non-negative weights",
                format!("{:?}", self.weights),
            ));
        }
        if let Some(r) = self.free_misses_m
            && !(r.is_finite() && r > 0.0)
        {
            return Err(MapError::config(
                "occupancy.free_misses_m",
                "a positive length, or absent",
                r,
            ));
        }
        let o = &self.occlusion;
        if !(o.range_jump_m.is_finite() && o.range_jump_m > 0.0) {
            return Err(MapError::config(
                "occupancy.occlusion.range_jump_m",
                "a positive length",
                o.range_jump_m,
            ));
        }
        if !(o.importance.is_finite() && o.importance >= 0.0) {
            return Err(MapError::config(
                "occupancy.occlusion.importance",
                "a finite, non-negative factor",
                o.importance,
            ));
        }
        if !(o.list_neighbour_max_deg.is_finite()
            && (0.0..=180.0).contains(&o.list_neighbour_max_deg))
        {
            return Err(MapError::config(
                "occupancy.occlusion.list_neighbour_max_deg",
                "an angle in [0, 180] degrees",
                o.list_neighbour_max_deg,
            ));
        }
        Ok(())
    }
}

/// Most voxels a grid may have (2³² voxels: 1 GiB of states).
pub const MAX_GRID_VOXELS: u64 = 1 << 32;

/// Voxels per brick edge and per brick.
const BRICK: usize = 8;
const BRICK_VOXELS: usize = BRICK * BRICK * BRICK;

/// Where the grid lies: voxel size, lowest key, voxels per axis. The grid is
/// region A3 widened to whole voxels.
///
/// Voxels are stored brick by brick: 8 × 8 × 8 voxels (128 bytes of states)
/// are contiguous, so a ray crossing 300 voxels touches ~40 cache-line pairs
/// and the rays of a scan share most of them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridGeometry {
    voxel_m: Real,
    key_min: [i32; 3],
    dims: [usize; 3],
    /// Bricks per axis (`⌈dims / 8⌉`).
    bricks: [usize; 3],
}

impl GridGeometry {
    /// The grid of voxels of size `voxel_m` covering `region`: keys
    /// `⌊min/v⌋ … ⌈max/v⌉ − 1` per axis (with a 10⁻⁶-voxel tolerance so that
    /// a boundary on a voxel face, up to rounding, adds no layer).
    fn covering(min: [Real; 3], max: [Real; 3], voxel_m: Real) -> Result<Self, MapError> {
        let mut key_min = [0i32; 3];
        let mut dims = [0usize; 3];
        for ax in 0..3 {
            let lo = (min[ax] / voxel_m + 1e-6).floor();
            let hi = (max[ax] / voxel_m - 1e-6).ceil().max(lo + 1.0);
            let limit = Real::from(i32::MAX / 2);
            if lo.abs() > limit || hi.abs() > limit {
                return Err(MapError::config(
                    "occupancy.regions.a3",
                    "a region within 10⁹ voxels of the origin",
                    format!("{min:?}..{max:?}"),
                ));
            }
            key_min[ax] = lo as i32;
            dims[ax] = (hi - lo) as usize;
        }
        let n = dims.iter().map(|d| *d as u64).product::<u64>();
        if n > MAX_GRID_VOXELS {
            return Err(MapError::config(
                "occupancy.voxel_m",
                "a voxel size giving at most 2^32 voxels over region A3",
                format!("{voxel_m} m ({dims:?} voxels)"),
            ));
        }
        Ok(Self {
            voxel_m,
            key_min,
            dims,
            bricks: dims.map(|d| d.div_ceil(BRICK)),
        })
    }

    /// Voxel edge, metres.
    pub fn voxel_m(&self) -> Real {
        self.voxel_m
    }

    /// Voxels per axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The lowest key of the grid.
    pub fn key_min(&self) -> VoxelKey {
        VoxelKey::new(self.key_min[0], self.key_min[1], self.key_min[2])
    }

    /// Number of voxels.
    pub fn voxel_count(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// Every voxel key of the grid, x fastest, then y, then z (the order
    /// [`OccupancyGrid::from_states`] and stored grids use).
    pub fn keys(&self) -> impl Iterator<Item = VoxelKey> + use<> {
        let k0 = self.key_min;
        let [nx, ny, nz] = self.dims.map(|n| n as i32);
        (0..nz).flat_map(move |z| {
            (0..ny).flat_map(move |y| {
                (0..nx).map(move |x| VoxelKey::new(k0[0] + x, k0[1] + y, k0[2] + z))
            })
        })
    }

    /// The box the grid covers.
    pub fn aabb(&self) -> Aabb {
        let v = self.voxel_m;
        let lo = self.key_min.map(|k| Real::from(k) * v);
        let hi = [0, 1, 2].map(|ax| (Real::from(self.key_min[ax]) + self.dims[ax] as Real) * v);
        Aabb::new(Point3::from(lo), Point3::from(hi))
    }

    /// `true` when the key names a voxel of the grid.
    #[inline]
    pub fn contains(&self, key: VoxelKey) -> bool {
        self.cell(key).is_some()
    }

    /// The grid voxel holding `p`, if any.
    pub fn key_of(&self, p: &Point3) -> Option<VoxelKey> {
        VoxelKey::of_point(p, self.voxel_m).filter(|k| self.contains(*k))
    }

    /// Grid-local cell of a key.
    #[inline]
    fn cell(&self, key: VoxelKey) -> Option<[usize; 3]> {
        let k = key.coords();
        let mut c = [0usize; 3];
        for ax in 0..3 {
            let d = i64::from(k[ax]) - i64::from(self.key_min[ax]);
            if d < 0 || d as usize >= self.dims[ax] {
                return None;
            }
            c[ax] = d as usize;
        }
        Some(c)
    }

    /// A dense index of the voxel, `< slot_count()`, for callers keeping
    /// their own per-voxel scratch (visit stamps); `None` outside the grid.
    #[inline]
    pub fn slot_of(&self, key: VoxelKey) -> Option<usize> {
        self.cell(key).map(|c| self.index(c))
    }

    /// Storage slots, padding of the last bricks included: the range of
    /// [`GridGeometry::slot_of`].
    pub fn slot_count(&self) -> usize {
        self.bricks.iter().product::<usize>() * BRICK_VOXELS
    }

    /// Storage slot of a cell: brick-major, then x, y, z inside the brick.
    #[inline]
    fn index(&self, c: [usize; 3]) -> usize {
        let brick = (c[0] >> 3) + self.bricks[0] * ((c[1] >> 3) + self.bricks[1] * (c[2] >> 3));
        (brick << 9) | (c[0] & 7) | ((c[1] & 7) << 3) | ((c[2] & 7) << 6)
    }

    #[inline]
    fn key(&self, c: [i64; 3]) -> VoxelKey {
        VoxelKey::new(
            (c[0] + i64::from(self.key_min[0])) as i32,
            (c[1] + i64::from(self.key_min[1])) as i32,
            (c[2] + i64::from(self.key_min[2])) as i32,
        )
    }

    /// `p` in grid-local voxel units (the grid spans `[0, dims]`).
    #[inline]
    fn local(&self, p: &Point3) -> [Real; 3] {
        [0, 1, 2].map(|ax| p[ax] / self.voxel_m - Real::from(self.key_min[ax]))
    }

    /// The part of segment `a → b` (local units) inside the grid box, as
    /// `(start, end, end_is_b)`, or `None` when it misses the box.
    #[inline]
    fn clip(&self, a: [Real; 3], b: [Real; 3]) -> Option<([Real; 3], [Real; 3], bool)> {
        let mut t0: Real = 0.0;
        let mut t1: Real = 1.0;
        for ax in 0..3 {
            let n = self.dims[ax] as Real;
            let d = b[ax] - a[ax];
            if d == 0.0 {
                if a[ax] < 0.0 || a[ax] > n {
                    return None;
                }
            } else {
                let ta = -a[ax] / d;
                let tb = (n - a[ax]) / d;
                let (near, far) = if ta <= tb { (ta, tb) } else { (tb, ta) };
                t0 = t0.max(near);
                t1 = t1.min(far);
            }
        }
        if t0 > t1 {
            return None;
        }
        let lerp = |t: Real| [0, 1, 2].map(|ax| a[ax] + t * (b[ax] - a[ax]));
        let start = if t0 == 0.0 { a } else { lerp(t0) };
        let (end, whole) = if t1 == 1.0 {
            (b, true)
        } else {
            (lerp(t1), false)
        };
        Some((start, end, whole))
    }

    #[inline]
    fn in_range(&self, c: [i64; 3]) -> bool {
        (c[0] as u64) < self.dims[0] as u64
            && (c[1] as u64) < self.dims[1] as u64
            && (c[2] as u64) < self.dims[2] as u64
    }
}

/// Voxel counts of one region (nested: A2 includes A1's voxels).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RegionCounts {
    /// Voxels in the region.
    pub total: u64,
    /// Free voxels.
    pub free: u64,
    /// Unknown voxels `n_u`.
    pub unknown: u64,
    /// Occupied voxels.
    pub occupied: u64,
    /// Unknown voxels flagged as occluded (importance `ι`).
    pub important_unknown: u64,
}

/// What one integration changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct IntegrationStats {
    /// Rays with a return that were integrated.
    pub rays: usize,
    /// Voxels that were unknown before the call and are known after it.
    pub newly_known: u64,
    /// Voxels that became occupied (from unknown or free). Like every field
    /// here, independent of the order rays were integrated in: a voxel both
    /// freed and hit within one call counts once, as occupied.
    pub newly_occupied: u64,
    /// Occlusion segments cast (range jumps found).
    pub range_jumps: usize,
    /// Unknown voxels newly flagged as occluded.
    pub newly_important: u64,
    /// Rays that lie wholly outside the grid (A3) and changed nothing.
    pub rays_outside: usize,
}

/// Per-shell count changes of one worker (shell = innermost region).
#[derive(Clone, Copy, Debug, Default)]
struct Delta {
    free: [i64; 3],
    occupied: [i64; 3],
    important_unknown: [i64; 3],
    newly_occupied: u64,
    newly_important: u64,
    rays_outside: usize,
}

impl Delta {
    fn add(mut self, o: Self) -> Self {
        for s in 0..3 {
            self.free[s] += o.free[s];
            self.occupied[s] += o.occupied[s];
            self.important_unknown[s] += o.important_unknown[s];
        }
        self.newly_occupied += o.newly_occupied;
        self.newly_important += o.newly_important;
        self.rays_outside += o.rays_outside;
        self
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct ShellCounts {
    total: u64,
    free: u64,
    occupied: u64,
    important_unknown: u64,
}

/// Read access to packed states and flags shared by the integration workers.
/// Writes are atomic ORs, so concurrent rays may touch the same word.
struct Cells<'a> {
    geometry: &'a GridGeometry,
    states: &'a [AtomicU64],
    flags: &'a [AtomicU64],
    shell: &'a [Vec<u8>; 3],
    /// Some voxel has ever been flagged (else flag lookups are skipped).
    any_flags: bool,
}

impl Cells<'_> {
    #[inline]
    fn shell_of(&self, c: [i64; 3]) -> usize {
        let s = &self.shell;
        usize::from(
            s[0][c[0] as usize]
                .max(s[1][c[1] as usize])
                .max(s[2][c[2] as usize]),
        )
    }

    #[inline]
    fn state_bits(&self, idx: usize) -> u64 {
        (self.states[idx >> 5].load(Relaxed) >> ((idx & 31) * 2)) & 3
    }

    #[inline]
    fn flagged(&self, idx: usize) -> bool {
        (self.flags[idx >> 6].load(Relaxed) >> (idx & 63)) & 1 == 1
    }

    /// Raise voxel `idx` (cell `c`) to `bits`, counting the change. The
    /// common case, a voxel already at or above `bits`, is one load.
    #[inline]
    fn raise(&self, idx: usize, c: [i64; 3], bits: u64, delta: &mut Delta) {
        let cur = (self.states[idx >> 5].load(Relaxed) >> ((idx & 31) * 2)) & 3;
        if cur | bits != cur {
            self.transition(idx, c, bits, delta);
        }
    }

    /// The atomic update behind [`Self::raise`]: the OR returns the word as it
    /// was, so when rays race on a voxel exactly one of them counts it.
    #[inline(never)]
    fn transition(&self, idx: usize, c: [i64; 3], bits: u64, delta: &mut Delta) {
        let shift = (idx & 31) * 2;
        let old = (self.states[idx >> 5].fetch_or(bits << shift, Relaxed) >> shift) & 3;
        let new = old | bits;
        if new == old {
            return;
        }
        let s = self.shell_of(c);
        if old == BITS_UNKNOWN && self.any_flags && self.flagged(idx) {
            delta.important_unknown[s] -= 1;
        }
        if new == BITS_OCCUPIED {
            delta.occupied[s] += 1;
            delta.newly_occupied += 1;
            if old == BITS_FREE {
                delta.free[s] -= 1;
            }
        } else {
            delta.free[s] += 1;
        }
    }

    /// Free the voxels of segment `o → p` (world frame) before its end and,
    /// when `hit`, occupy the voxel holding `p`. Parts outside the grid are
    /// skipped.
    #[inline]
    fn integrate_ray(&self, o: &Point3, p: &Point3, hit: bool, delta: &mut Delta) {
        let g = self.geometry;
        let Some((a, b, whole)) = g.clip(g.local(o), g.local(p)) else {
            delta.rays_outside += 1;
            return;
        };
        let end_hit = hit && whole;
        let mut w = Walk::new(a, b);
        let mut left = w.len();
        loop {
            left -= 1;
            let c = w.cell();
            if g.in_range(c) {
                let bits = if left == 0 && end_hit {
                    BITS_OCCUPIED
                } else {
                    BITS_FREE
                };
                self.raise(g.index(c.map(|v| v as usize)), c, bits, delta);
            }
            if !w.advance() {
                break;
            }
        }
    }

    /// Flag the still-unknown voxels of segment `p → q` as occluded.
    fn flag_segment(&self, p: &Point3, q: &Point3, delta: &mut Delta) {
        let g = self.geometry;
        let Some((a, b, _)) = g.clip(g.local(p), g.local(q)) else {
            return;
        };
        let mut w = Walk::new(a, b);
        loop {
            let cell = w.cell();
            if g.in_range(cell) {
                let idx = g.index(cell.map(|v| v as usize));
                if self.state_bits(idx) == BITS_UNKNOWN {
                    let bit = 1u64 << (idx & 63);
                    let old = self.flags[idx >> 6].fetch_or(bit, Relaxed);
                    if old & bit == 0 {
                        delta.important_unknown[self.shell_of(cell)] += 1;
                        delta.newly_important += 1;
                    }
                }
            }
            if !w.advance() {
                break;
            }
        }
    }
}

/// The outcome of casting a ray through the grid for prediction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UnknownRun {
    /// Unknown voxels passed before the ray ended or was blocked.
    pub unknown: u32,
    /// The first occupied voxel met, which ends the ray.
    pub blocked_by: Option<VoxelKey>,
}

/// The voxels of a grid that are not free (occupied or unknown; every voxel
/// outside the grid is unknown), 64 voxels of a row along x at a time
/// ([`OccupancyGrid::not_free`]).
#[derive(Clone, Copy, Debug)]
pub struct NotFree<'a> {
    rows: &'a NotFreeRows,
    key_min: [i64; 3],
    dims: [i64; 3],
}

impl NotFree<'_> {
    /// Bit `i` set when the voxel of key `(x0 + i, y, z)` is not free, for
    /// `i` in `0..64`: what [`OccupancyGrid::state`] says of each.
    #[inline]
    pub fn row64(&self, y: i32, z: i32, x0: i32) -> u64 {
        let cy = i64::from(y) - self.key_min[1];
        let cz = i64::from(z) - self.key_min[2];
        if cy < 0 || cy >= self.dims[1] || cz < 0 || cz >= self.dims[2] {
            return u64::MAX;
        }
        let words = self.rows.words;
        let row = &self.rows.bits[(cy + self.dims[1] * cz) as usize * words..][..words];
        // Words before and after the row are all unknown; so are the bits
        // past the grid's end in its last word.
        let word = |w: i64| {
            usize::try_from(w)
                .ok()
                .and_then(|w| row.get(w))
                .copied()
                .unwrap_or(u64::MAX)
        };
        let c = i64::from(x0) - self.key_min[0];
        let (w, shift) = (c.div_euclid(64), c.rem_euclid(64));
        if shift == 0 {
            word(w)
        } else {
            (word(w) >> shift) | (word(w + 1) << (64 - shift))
        }
    }
}

/// The occupancy grid over A3 with region counts, occlusion flags and C-space
/// probabilities. See the [module docs](self).
pub struct OccupancyGrid {
    config: OccupancyConfig,
    geometry: GridGeometry,
    /// Two bits per voxel, 32 voxels per word.
    states: Vec<AtomicU64>,
    /// One occlusion flag bit per voxel.
    flags: Vec<AtomicU64>,
    /// Per axis and cell, the innermost region (0, 1, 2) the cell's slab lies in.
    shell: [Vec<u8>; 3],
    counts: [ShellCounts; 3],
    cspace: CspaceField,
    /// Some voxel has been flagged as occluded.
    any_flags: bool,
    /// Per row of voxels along x, one bit per voxel that is not free, made
    /// on first use and dropped when a state changes
    /// ([`OccupancyGrid::not_free`]).
    not_free: OnceLock<NotFreeRows>,
}

/// The voxels that are not free, one bit per voxel, row by row along x:
/// row `y + ny·z` holds `words` words, bit `x` of the row in word `x / 64`;
/// the bits past the row's end are set (outside the grid is unknown).
#[derive(Clone, Debug)]
struct NotFreeRows {
    words: usize,
    bits: Vec<u64>,
}

impl std::fmt::Debug for OccupancyGrid {
    /// A summary: the voxel arrays hold tens of millions of entries.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OccupancyGrid")
            .field("config", &self.config)
            .field("geometry", &self.geometry)
            .field("counts", &Region::ALL.map(|r| self.counts(r)))
            .field("cspace_blocks", &self.cspace.blocks.len())
            .finish_non_exhaustive()
    }
}

impl Clone for OccupancyGrid {
    fn clone(&self) -> Self {
        let copy = |v: &[AtomicU64]| v.iter().map(|w| AtomicU64::new(w.load(Relaxed))).collect();
        Self {
            config: self.config,
            geometry: self.geometry,
            states: copy(&self.states),
            flags: copy(&self.flags),
            shell: self.shell.clone(),
            counts: self.counts,
            cspace: self.cspace.clone(),
            any_flags: self.any_flags,
            not_free: self.not_free.clone(),
        }
    }
}

impl OccupancyGrid {
    /// An all-unknown grid covering region A3.
    pub fn new(config: OccupancyConfig) -> Result<Self, MapError> {
        config.validate()?;
        let r = &config.regions;
        let geometry = GridGeometry::covering(r.a3.min, r.a3.max, config.voxel_m)?;
        let n = geometry.slot_count();
        let zeros = |words: usize| (0..words).map(|_| AtomicU64::new(0)).collect::<Vec<_>>();
        let shell = [0, 1, 2].map(|ax| {
            (0..geometry.dims[ax])
                .map(|i| {
                    let c = (Real::from(geometry.key_min[ax]) + i as Real + 0.5) * config.voxel_m;
                    if (r.a1.min[ax]..=r.a1.max[ax]).contains(&c) {
                        0u8
                    } else if (r.a2.min[ax]..=r.a2.max[ax]).contains(&c) {
                        1
                    } else {
                        2
                    }
                })
                .collect::<Vec<u8>>()
        });
        // Voxels whose innermost region is at most `l`: a product of per-axis counts.
        let within = |l: u8| -> u64 {
            shell
                .iter()
                .map(|s| s.iter().filter(|v| **v <= l).count() as u64)
                .product()
        };
        let (n0, n1, n2) = (within(0), within(1), within(2));
        let mut counts = [ShellCounts::default(); 3];
        counts[0].total = n0;
        counts[1].total = n1 - n0;
        counts[2].total = n2 - n1;
        let cspace = CspaceField::new(geometry.dims);
        Ok(Self {
            config,
            geometry,
            states: zeros(n.div_ceil(32)),
            flags: zeros(n.div_ceil(64)),
            shell,
            counts,
            cspace,
            any_flags: false,
            not_free: OnceLock::new(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &OccupancyConfig {
        &self.config
    }

    /// Where the grid lies.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// The grid voxel holding `p`, if `p` lies in the grid.
    pub fn key_of(&self, p: &Point3) -> Option<VoxelKey> {
        self.geometry.key_of(p)
    }

    /// The state of a voxel; [`VoxelState::Unknown`] outside the grid.
    #[inline]
    pub fn state(&self, key: VoxelKey) -> VoxelState {
        match self.geometry.cell(key) {
            Some(c) => decode(self.cells().state_bits(self.geometry.index(c))),
            None => VoxelState::Unknown,
        }
    }

    /// The voxels that are not free, row by row ([`NotFree::row64`]): what
    /// [`Self::state`] says of each, 64 voxels at a time. Made on first use
    /// after a change (a pass over the grid).
    pub fn not_free(&self) -> NotFree<'_> {
        let g = &self.geometry;
        NotFree {
            rows: self.not_free.get_or_init(|| self.not_free_rows()),
            key_min: g.key_min.map(i64::from),
            dims: g.dims.map(|d| d as i64),
        }
    }

    fn not_free_rows(&self) -> NotFreeRows {
        let g = &self.geometry;
        let cells = self.cells();
        let [nx, ny, nz] = g.dims;
        let words = nx.div_ceil(64);
        let mut bits = vec![0u64; words * ny * nz];
        for z in 0..nz {
            for y in 0..ny {
                let row = &mut bits[(y + ny * z) * words..][..words];
                for x in 0..words * 64 {
                    if x >= nx || decode(cells.state_bits(g.index([x, y, z]))) != VoxelState::Free {
                        row[x / 64] |= 1 << (x % 64);
                    }
                }
            }
        }
        NotFreeRows { words, bits }
    }

    /// The innermost region holding a voxel; `None` outside the grid.
    pub fn region_of(&self, key: VoxelKey) -> Option<Region> {
        let c = self.geometry.cell(key)?;
        Some(Region::ALL[self.cells().shell_of(c.map(|v| v as i64))])
    }

    /// `true` when the voxel was flagged as occluded while unknown (A§4.2.1).
    pub fn is_important(&self, key: VoxelKey) -> bool {
        self.geometry
            .cell(key)
            .is_some_and(|c| self.cells().flagged(self.geometry.index(c)))
    }

    fn cells(&self) -> Cells<'_> {
        Cells {
            geometry: &self.geometry,
            states: &self.states,
            flags: &self.flags,
            shell: &self.shell,
            any_flags: self.any_flags,
        }
    }

    fn apply(&mut self, d: &Delta) {
        // Every state change ends here: the rows of non-free voxels are
        // made again when next asked for.
        self.not_free = OnceLock::new();
        self.any_flags |= d.newly_important > 0;
        for s in 0..3 {
            let c = &mut self.counts[s];
            c.free = c.free.wrapping_add_signed(d.free[s]);
            c.occupied = c.occupied.wrapping_add_signed(d.occupied[s]);
            c.important_unknown = c
                .important_unknown
                .wrapping_add_signed(d.important_unknown[s]);
        }
    }

    /// Integrate a sweep: each return frees the voxels its ray crosses and
    /// occupies its own voxel; then, when occlusion weighting is on, the
    /// segments between neighbouring returns with a range jump flag the
    /// voxels they cross that are still unknown (A§4.2.1). Neighbours come
    /// from the sweep's (scan, ray) grid when it keeps one, else from the
    /// list order (see [`OcclusionConfig::list_neighbour_max_deg`]). Rays run
    /// in parallel; the result does not depend on the thread count.
    pub fn integrate_sweep(&mut self, sweep: &Sweep) -> IntegrationStats {
        let occ = &self.config.occlusion;
        let jumps = if occ.enabled {
            range_jumps(sweep, occ)
        } else {
            Vec::new()
        };
        let pts = sweep.points();
        let misses = match self.config.free_misses_m {
            Some(r) => miss_rays(sweep, r),
            None => Vec::new(),
        };
        let n = pts.len();
        self.integrate_checked(
            n + misses.len(),
            |k| {
                if k < n {
                    (pts[k].origin, pts[k].point, true)
                } else {
                    (misses[k - n].0, misses[k - n].1, false)
                }
            },
            &jumps,
        )
    }

    /// Integrate points measured along rays from per-point `origins` (a plain
    /// list: no grid). Occlusion weighting uses the neighbours recoverable
    /// from the list order (see [`OcclusionConfig::list_neighbour_max_deg`]).
    /// Fails, changing nothing, on empty or mismatched lists or non-finite
    /// coordinates.
    pub fn integrate_points(
        &mut self,
        origins: &[Point3],
        points: &[Point3],
    ) -> Result<IntegrationStats, MapError> {
        check_point_list("point list", origins, points)?;
        let occ = &self.config.occlusion;
        let jumps = if occ.enabled && occ.list_neighbour_max_deg > 0.0 {
            list_range_jumps(
                origins,
                points,
                occ.range_jump_m,
                occ.list_neighbour_max_deg.to_radians(),
            )
        } else {
            Vec::new()
        };
        Ok(self.integrate_checked(points.len(), |k| (origins[k], points[k], true), &jumps))
    }

    /// Integrate `n` checked rays (`ray(k)` = (origin, end, the end is a
    /// return)) and flag the occlusion segments `jumps`.
    fn integrate_checked(
        &mut self,
        n: usize,
        ray: impl Fn(usize) -> (Point3, Point3, bool) + Sync,
        jumps: &[(Point3, Point3)],
    ) -> IntegrationStats {
        let cells = self.cells();
        let delta = (0..n)
            .into_par_iter()
            .with_min_len(1024)
            .fold(Delta::default, |mut d, k| {
                let (o, p, hit) = ray(k);
                cells.integrate_ray(&o, &p, hit, &mut d);
                d
            })
            .reduce(Delta::default, Delta::add);
        let delta_outside = delta.rays_outside;
        let flag_delta = flag_segments(&cells, jumps);
        let total = delta.add(flag_delta);
        let unknown_before = self.counts(Region::A3).unknown;
        self.apply(&total);
        IntegrationStats {
            rays: n,
            newly_known: unknown_before - self.counts(Region::A3).unknown,
            newly_occupied: total.newly_occupied,
            range_jumps: jumps.len(),
            newly_important: total.newly_important,
            rays_outside: delta_outside,
        }
    }

    /// A grid of `config` whose `k`-th voxel (in [`GridGeometry::keys`]
    /// order) is in state `state(k, key)`: free voxels marked free, occupied
    /// ones hit by a return from inside the voxel (a stored grid read back,
    /// or a grid made from a ground truth).
    pub fn from_states(
        config: OccupancyConfig,
        state: impl Fn(usize, VoxelKey) -> VoxelState,
    ) -> Result<Self, MapError> {
        let mut grid = Self::new(config)?;
        let v = grid.geometry().voxel_m();
        let (mut origins, mut points) = (Vec::new(), Vec::new());
        let keys: Vec<VoxelKey> = grid.geometry().keys().collect();
        for (k, key) in keys.into_iter().enumerate() {
            match state(k, key) {
                VoxelState::Unknown => {}
                VoxelState::Free => {
                    grid.mark_free(key)?;
                }
                VoxelState::Occupied => {
                    let c = key.center(v);
                    // A return at the centre from inside the voxel: a hit.
                    origins.push(c + Vector3::new(0.1 * v, 0.0, 0.0));
                    points.push(c);
                }
            }
        }
        if !points.is_empty() {
            grid.integrate_points(&origins, &points)?;
        }
        Ok(grid)
    }

    /// Mark a voxel free without a measurement (the volume the manipulator
    /// itself occupies is known free from the start, A§4.2). Returns whether
    /// the state changed; an occupied voxel stays occupied.
    pub fn mark_free(&mut self, key: VoxelKey) -> Result<bool, MapError> {
        let c = self
            .geometry
            .cell(key)
            .ok_or(MapError::OutsideGrid { key })?;
        let idx = self.geometry.index(c);
        let mut d = Delta::default();
        self.cells()
            .raise(idx, c.map(|v| v as i64), BITS_FREE, &mut d);
        let changed = d.free.iter().any(|v| *v != 0);
        self.apply(&d);
        Ok(changed)
    }

    /// Counts of a region, nested: [`Region::A2`] includes A1's voxels and
    /// [`Region::A3`] is the whole grid.
    pub fn counts(&self, region: Region) -> RegionCounts {
        let mut r = RegionCounts::default();
        for s in &self.counts[..=region.index()] {
            r.total += s.total;
            r.free += s.free;
            r.occupied += s.occupied;
            r.important_unknown += s.important_unknown;
        }
        r.unknown = r.total - r.free - r.occupied;
        r
    }

    /// `H1 = n_u ln 2` over the whole grid (A eq. 4.10).
    pub fn h1_unweighted(&self) -> Real {
        self.counts(Region::A3).unknown as Real * std::f64::consts::LN_2
    }

    /// `H1 = ln 2 · Σ_k c_wk (n_u,Ak + (ι − 1) n_ui,Ak)`: A eq. 4.11 over the
    /// nested regions with occluded unknown voxels `n_ui` counted `ι` times
    /// (see the [module docs](self)).
    pub fn h1_weighted(&self) -> Real {
        let iota = self.config.occlusion.importance;
        Region::ALL
            .iter()
            .map(|&r| {
                let c = self.counts(r);
                self.config.weights[r.index()]
                    * (c.unknown as Real + (iota - 1.0) * c.important_unknown as Real)
            })
            .sum::<Real>()
            * std::f64::consts::LN_2
    }

    /// The term a voxel adds to [`OccupancyGrid::h1_weighted`] while it is
    /// unknown: `ln 2 · ι^[occluded] · Σ c_wk` over the regions holding it
    /// (an A1 voxel counts in A1, A2 and A3). 0 outside the grid. What a
    /// prediction credits for revealing the voxel (A§4.2).
    pub fn h1_weight(&self, key: VoxelKey) -> Real {
        let Some(inner) = self.region_of(key) else {
            return 0.0;
        };
        let w: Real = Region::ALL[inner.index()..]
            .iter()
            .map(|r| self.config.weights[r.index()])
            .sum();
        let iota = if self.is_important(key) {
            self.config.occlusion.importance
        } else {
            1.0
        };
        w * iota * std::f64::consts::LN_2
    }

    /// Set the probability of C-space interference `P(x_c)` of one voxel (A
    /// eq. 4.13). Fails, changing nothing, outside the grid or outside `[0, 1]`.
    /// Stored as `f32`.
    pub fn set_cspace_probability(&mut self, key: VoxelKey, p: Real) -> Result<(), MapError> {
        self.set_cspace_probabilities([(key, p)])
    }

    /// Set many `P(x_c)` at once (the exploration stage's voxel → probability
    /// map). All are checked before any is stored.
    pub fn set_cspace_probabilities(
        &mut self,
        values: impl IntoIterator<Item = (VoxelKey, Real)>,
    ) -> Result<(), MapError> {
        let mut checked = Vec::new();
        for (key, p) in values {
            let c = self
                .geometry
                .cell(key)
                .ok_or(MapError::OutsideGrid { key })?;
            if !(0.0..=1.0).contains(&p) {
                return Err(MapError::Probability { key, value: p });
            }
            checked.push((c, p as f32));
        }
        for (c, p) in checked {
            self.cspace.set(c, p);
        }
        Ok(())
    }

    /// `P(x_c)` of a voxel (0 where none was given).
    pub fn cspace_probability(&self, key: VoxelKey) -> Real {
        self.geometry
            .cell(key)
            .map_or(0.0, |c| Real::from(self.cspace.get(c)))
    }

    /// Per storage slot ([`GridGeometry::slot_of`]), what an unknown voxel
    /// there would reveal: `[`[`OccupancyGrid::h1_weight`]`,
    /// `[`OccupancyGrid::cspace_information`]`]` (zeros for known voxels and
    /// padding). The same numbers as those calls, looked up by slot: a
    /// prediction that visits many voxels reads them once made.
    pub fn information_by_slot(&self) -> Vec<[Real; 2]> {
        let g = &self.geometry;
        let mut out = vec![[0.0; 2]; g.slot_count()];
        for key in g.keys() {
            if let Some(slot) = g.slot_of(key)
                && self.state(key) == VoxelState::Unknown
            {
                out[slot] = [self.h1_weight(key), self.cspace_information(key)];
            }
        }
        out
    }

    /// The C-space information a voxel holds now: [`h2_term`] of its `P(x_c)`
    /// when unknown, 0 when known.
    pub fn cspace_information(&self, key: VoxelKey) -> Real {
        if self.state(key) == VoxelState::Unknown {
            h2_term(self.cspace_probability(key))
        } else {
            0.0
        }
    }

    /// `H2 = Σ_{unknown j} h(P(ʲx_c))` (A eq. 4.14, see [`h2_term`]). A pass
    /// over the stored probabilities, summed in a fixed order.
    pub fn h2(&self) -> Real {
        let cells = self.cells();
        let g = &self.geometry;
        let per_block: Vec<Real> = self
            .cspace
            .blocks
            .par_iter()
            .map(|b| {
                let mut sum = 0.0;
                for (l, &p) in b.values.iter().enumerate() {
                    if p <= 0.0 {
                        continue;
                    }
                    let c = [
                        b.origin[0] + (l & 7),
                        b.origin[1] + ((l >> 3) & 7),
                        b.origin[2] + (l >> 6),
                    ];
                    if c[0] >= g.dims[0] || c[1] >= g.dims[1] || c[2] >= g.dims[2] {
                        continue;
                    }
                    if cells.state_bits(g.index(c)) == BITS_UNKNOWN {
                        sum += h2_term(Real::from(p));
                    }
                }
                sum
            })
            .collect();
        per_block.iter().fold(0.0, |a, b| a + b)
    }

    /// Cast a ray for information prediction (A§4.2, Fig. 4.3): walk from
    /// `origin` along `dir` up to `max_range_m` (clipped to the grid), call
    /// `visit` on every unknown voxel passed, and stop at the first occupied
    /// voxel (known surfaces occlude). Free voxels are passed silently.
    pub fn cast_through_unknown(
        &self,
        origin: &Point3,
        dir: &UnitVector3,
        max_range_m: Real,
        mut visit: impl FnMut(VoxelKey),
    ) -> UnknownRun {
        self.cast_through_unknown_slots(origin, dir, max_range_m, |key, _| visit(key))
    }

    /// [`OccupancyGrid::cast_through_unknown`], `visit` also given each
    /// unknown voxel's storage slot ([`GridGeometry::slot_of`]).
    pub fn cast_through_unknown_slots(
        &self,
        origin: &Point3,
        dir: &UnitVector3,
        max_range_m: Real,
        mut visit: impl FnMut(VoxelKey, usize),
    ) -> UnknownRun {
        self.cast_slots(origin, dir, max_range_m, |key, slot, state| {
            if state == VoxelState::Unknown {
                visit(key, slot);
            }
        })
    }

    /// Cast a ray as [`OccupancyGrid::cast_through_unknown`] does, calling
    /// `visit` on every voxel passed in order, free and unknown, with its
    /// storage slot ([`GridGeometry::slot_of`]) and state, and last on the
    /// first occupied voxel, where the ray stops. What the information
    /// gains of a predicted sweep read (visibility, rear sides, frontiers).
    pub fn cast_slots(
        &self,
        origin: &Point3,
        dir: &UnitVector3,
        max_range_m: Real,
        mut visit: impl FnMut(VoxelKey, usize, VoxelState),
    ) -> UnknownRun {
        let mut run = UnknownRun::default();
        if !(max_range_m.is_finite() && max_range_m >= 0.0 && geom::math::is_finite_point(origin)) {
            return run;
        }
        let g = &self.geometry;
        let end = origin + dir.into_inner() * max_range_m;
        let Some((a, b, _)) = g.clip(g.local(origin), g.local(&end)) else {
            return run;
        };
        let cells = self.cells();
        let mut w = Walk::new(a, b);
        loop {
            let cell = w.cell();
            if g.in_range(cell) {
                let idx = g.index(cell.map(|v| v as usize));
                match cells.state_bits(idx) {
                    BITS_UNKNOWN => {
                        run.unknown += 1;
                        visit(g.key(cell), idx, VoxelState::Unknown);
                    }
                    BITS_OCCUPIED => {
                        let key = g.key(cell);
                        visit(key, idx, VoxelState::Occupied);
                        run.blocked_by = Some(key);
                        return run;
                    }
                    _ => visit(g.key(cell), idx, VoxelState::Free),
                }
            }
            if !w.advance() {
                return run;
            }
        }
    }

    /// The counts and entropies as a serialisable report (`occupancy.json`).
    pub fn report(&self) -> OccupancyReport {
        OccupancyReport {
            voxel_m: self.geometry.voxel_m,
            dims: self.geometry.dims,
            weights: self.config.weights,
            importance: self.config.occlusion.importance,
            regions: Region::ALL.map(|r| {
                let c = self.counts(r);
                RegionReport {
                    region: r,
                    total: c.total,
                    free: c.free,
                    unknown: c.unknown,
                    occupied: c.occupied,
                    important_unknown: c.important_unknown,
                }
            }),
            h1_unweighted: self.h1_unweighted(),
            h1_weighted: self.h1_weighted(),
            h2: self.h2(),
        }
    }

    /// Recount every voxel and compare with the incremental counts; check that
    /// no voxel holds the unused bit pattern. For tests (it reads the whole
    /// grid).
    pub fn check_invariants(&self) -> Result<(), geom::InvariantViolation> {
        self.invariant_detail()
            .map_err(|d| geom::InvariantViolation::new("occupancy grid", d))
    }

    /// The check of `check_invariants`, the failure as text.
    fn invariant_detail(&self) -> Result<(), String> {
        let cells = self.cells();
        let g = &self.geometry;
        let mut recount = [ShellCounts::default(); 3];
        for z in 0..g.dims[2] {
            for y in 0..g.dims[1] {
                for x in 0..g.dims[0] {
                    let c = [x, y, z];
                    let idx = g.index(c);
                    let s = cells.shell_of(c.map(|v| v as i64));
                    let r = &mut recount[s];
                    r.total += 1;
                    match cells.state_bits(idx) {
                        BITS_FREE => r.free += 1,
                        BITS_OCCUPIED => r.occupied += 1,
                        BITS_UNKNOWN => r.important_unknown += u64::from(cells.flagged(idx)),
                        bits => return Err(format!("voxel {c:?} holds state bits {bits:#b}")),
                    }
                }
            }
        }
        if recount != self.counts {
            return Err(format!(
                "incremental counts {:?} differ from a recount {:?}",
                self.counts, recount
            ));
        }
        Ok(())
    }
}

fn flag_segments(cells: &Cells<'_>, jumps: &[(Point3, Point3)]) -> Delta {
    jumps
        .par_chunks(256)
        .fold(Delta::default, |mut d, chunk| {
            for (p, q) in chunk {
                cells.flag_segment(p, q, &mut d);
            }
            d
        })
        .reduce(Delta::default, Delta::add)
}

#[inline]
fn decode(bits: u64) -> VoxelState {
    match bits {
        BITS_FREE => VoxelState::Free,
        BITS_OCCUPIED => VoxelState::Occupied,
        _ => VoxelState::Unknown,
    }
}

/// The rays of a gridded sweep that returned nothing, as (origin, point
/// `range_m` along the ray). Empty for a sweep without its grid (a list,
/// or a file).
fn miss_rays(sweep: &Sweep, range_m: Real) -> Vec<(Point3, Point3)> {
    if sweep.grid_shape().is_none() {
        return Vec::new();
    }
    sweep
        .misses()
        .iter()
        .map(|(o, d)| (*o, o + d * range_m))
        .collect()
}

/// The C-space information of one unknown voxel with interference probability
/// `p = P(x_c)` (A eq. 4.14): the binary entropy of the one-sided probability
/// `q = p / 2`,
///
/// `h(p) = −q ln q − (1 − q) ln(1 − q)`, `0 ln 0 = 0`,
///
/// which is 0 for `p = 0` (a voxel no pose interferes with) and rises to its
/// maximum `ln 2` at `p = 1`. Eq. 4.14 as printed writes the complement as
/// `(1 − P)/2`; that reading gives `½ ln 2` at `P = 0`, peaks at `P = ½` and
/// contradicts the text around it ("a one-sided uncertainty, 0 < P/2 < 0.5
/// … the maximum information remaining exists when P/2 = 0.5", voxels outside
/// the workspace have `P = 0` and carry no C-space information). We follow the
/// text: the complement of `P/2` is `1 − P/2`.
pub fn h2_term(p: Real) -> Real {
    let q = (p * 0.5).clamp(0.0, 0.5);
    let xlnx = |x: Real| if x > 0.0 { x * x.ln() } else { 0.0 };
    -xlnx(q) - xlnx(1.0 - q)
}

/// Sparse per-voxel `f32` values in 8³ blocks behind a dense block index.
#[derive(Clone, Debug)]
struct CspaceField {
    block_dims: [usize; 3],
    /// Dense over blocks: index into `blocks`, or `u32::MAX` when absent.
    index: Vec<u32>,
    blocks: Vec<CspaceBlock>,
}

#[derive(Clone, Debug)]
struct CspaceBlock {
    /// Grid-local cell of the block's first voxel.
    origin: [usize; 3],
    values: Box<[f32; 512]>,
}

impl CspaceField {
    fn new(dims: [usize; 3]) -> Self {
        let block_dims = dims.map(|d| d.div_ceil(8));
        Self {
            block_dims,
            index: vec![u32::MAX; block_dims[0] * block_dims[1] * block_dims[2]],
            blocks: Vec::new(),
        }
    }

    #[inline]
    fn locate(&self, c: [usize; 3]) -> (usize, usize) {
        let b = c.map(|v| v >> 3);
        let bi = b[0] + self.block_dims[0] * (b[1] + self.block_dims[1] * b[2]);
        let l = (c[0] & 7) | ((c[1] & 7) << 3) | ((c[2] & 7) << 6);
        (bi, l)
    }

    #[inline]
    fn get(&self, c: [usize; 3]) -> f32 {
        let (bi, l) = self.locate(c);
        match self.index[bi] {
            u32::MAX => 0.0,
            k => self.blocks[k as usize].values[l],
        }
    }

    fn set(&mut self, c: [usize; 3], p: f32) {
        let (bi, l) = self.locate(c);
        if self.index[bi] == u32::MAX {
            if p == 0.0 {
                return;
            }
            self.index[bi] = self.blocks.len() as u32;
            self.blocks.push(CspaceBlock {
                origin: c.map(|v| v & !7),
                values: Box::new([0.0; 512]),
            });
        }
        let k = self.index[bi] as usize;
        self.blocks[k].values[l] = p;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn h2_term_is_binary_entropy_of_half_p() {
        assert_eq!(h2_term(0.0), 0.0);
        assert!((h2_term(1.0) - std::f64::consts::LN_2).abs() < 1e-15);
        let q: Real = 0.15;
        let expect = -q * q.ln() - (1.0 - q) * (1.0 - q).ln();
        assert!((h2_term(0.3) - expect).abs() < 1e-15);
        // Monotone on [0, 1].
        let mut last = -1.0;
        for i in 0..=100 {
            let h = h2_term(f64::from(i) / 100.0);
            assert!(h > last);
            last = h;
        }
    }

    /// `not_free` marks exactly the voxels `state` calls not free,
    /// rows and ends beyond the grid included, and follows every change.
    #[test]
    fn not_free_in_row_agrees_with_state() {
        let g = OccupancyGrid::new(OccupancyConfig {
            voxel_m: 0.1,
            regions: RegionsConfig::around([0.0, 0.0, 0.0], [1.0, 2.0, 3.3]),
            ..OccupancyConfig::default()
        })
        .unwrap();
        let [nx, ny, nz] = g.geometry().dims();
        assert!(nx > 64, "{nx}: rows of more than one word");
        let k0 = g.geometry().key_min().coords();
        let check = |g: &OccupancyGrid| {
            for z in k0[2] - 1..=k0[2] + nz as i32 {
                for y in k0[1] - 1..=k0[1] + ny as i32 {
                    for x0 in [
                        k0[0] - 70,
                        k0[0] - 3,
                        k0[0],
                        k0[0] + 5,
                        k0[0] + 64,
                        k0[0] + 60,
                    ] {
                        let bits = g.not_free().row64(y, z, x0);
                        let expected = (0..64).fold(0u64, |b, i| {
                            let free = g.state(VoxelKey::new(x0 + i, y, z)) == VoxelState::Free;
                            b | (u64::from(!free) << i)
                        });
                        assert_eq!(bits, expected, "row y {y} z {z} from x {x0}");
                    }
                }
            }
        };
        check(&g);
        // A pattern of the three states; then a change after a look.
        let config = *g.config();
        let mut g = OccupancyGrid::from_states(config, |k, _| match k % 7 {
            0 | 3 => VoxelState::Unknown,
            5 => VoxelState::Occupied,
            _ => VoxelState::Free,
        })
        .unwrap();
        check(&g);
        assert!(g.not_free().row64(k0[1] + 1, k0[2] + 1, k0[0]).count_ones() > 10);
        let key = VoxelKey::new(k0[0] + 65, k0[1] + 2, k0[2] + 3);
        assert_eq!(g.state(key), VoxelState::Unknown, "{key:?}");
        g.mark_free(key).unwrap();
        check(&g);
        check(&g);
    }

    #[test]
    fn grid_covers_a3_in_whole_voxels() {
        let g = OccupancyGrid::new(OccupancyConfig::default()).unwrap();
        // A3 = [−2.1, 2.1]² × [−1.625, 2.575]: the half-voxel z bounds widen to 421.
        assert_eq!(g.geometry().dims(), [420, 420, 421]);
        assert_eq!(g.geometry().key_min(), VoxelKey::new(-210, -210, -163));
        assert_eq!(g.counts(Region::A3).total, 420 * 420 * 421);
        let a1 = g.counts(Region::A1).total;
        assert!((220 * 220 * 220..=220 * 220 * 221).contains(&a1), "{a1}");
        assert_eq!(g.state(VoxelKey::new(0, 0, 0)), VoxelState::Unknown);
        assert_eq!(g.region_of(VoxelKey::new(0, 0, 0)), Some(Region::A1));
        assert_eq!(g.region_of(VoxelKey::new(150, 0, 0)), Some(Region::A2));
        assert_eq!(g.region_of(VoxelKey::new(-200, 0, 0)), Some(Region::A3));
        assert_eq!(g.region_of(VoxelKey::new(-211, 0, 0)), None);
    }
}
