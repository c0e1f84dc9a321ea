//! Scale-Like Discs (Paul §5.2, Fig. 5.4–5.6, eq. 5.3–5.9).
//!
//! A Scale-Like Disc (SLD) is a small planar disc `{P̂, n⃗}` of radius `μ`
//! that stands for the points of a surface around it; overlapping like the
//! scales of a fish, the discs of a cloud represent its surfaces compactly and
//! are the targets of material identification and maintenance planning.
//!
//! # Algorithm (Paul Fig. 5.4 and Fig. 5.5)
//!
//! [`generate_discs`] follows the thesis step by step:
//!
//! 1. **Voxel hash.** Every point `p` is assigned to the voxel `⌊p / μ⌋` (the
//!    voxel edge equals the disc radius `μ`, so discs of adjacent voxels
//!    partially overlap). Voxels live in a flat table sorted by key: no hash
//!    iteration order reaches the results.
//! 2. **Home point.** The occupied voxels are visited in a random order drawn
//!    from the seed. In a voxel that has no disc yet, an *unregistered* point is
//!    drawn at random as the home point `P̂_j` (Fig. 5.5a). A voxel whose
//!    points are all registered already (by overlapping discs of its
//!    neighbours) gets no disc.
//! 3. **Neighbourhood.** The home voxel and its `3³ − 1 = 26` neighbours are
//!    searched (Fig. 5.5b) for the points within `μ` of the home point: the
//!    sub-cloud `PG_j` of eq. 5.4, registered points included.
//! 4. **PCA.** The covariance of `PG_j` (eq. 5.5–5.7) is diagonalised
//!    (eq. 5.8); the eigenvector of the *smallest* eigenvalue is the disc
//!    normal (eq. 5.9, Fig. 5.5c). A neighbourhood whose two smallest
//!    eigenvalues vanish (collinear or coincident points) has no normal, and
//!    [`SldConfig::min_eigen_ratio`] optionally applies Paul's
//!    dimensionality-reduction test `λ_mid / λ_min`.
//! 5. **Registration.** The points of `PG_j` (all within `μ` of the home point)
//!    that also lie within `±μ` ([`SldConfig::plane_tolerance_m`]) of the
//!    fitted plane are registered to the disc (Fig. 5.5d). A disc needs at
//!    least `n_min` registered points ([`SldConfig::min_points`]).
//! 6. If the home point fails (too few points, no normal), it is marked as
//!    *considered* and another unregistered point of the same voxel is tried,
//!    until the voxel has a disc or none of its unregistered points is left.
//!    The run ends when every voxel has been visited: every point is then
//!    registered or has been considered as a home point.
//!
//! Each occupied voxel therefore holds at most one disc — the voxel of its
//! home point (Paul: "each occupied geometric voxel is limited to containing
//! only one SLD").
//!
//! # Centre and orientation
//!
//! The thesis characterises a disc by its home point and normal, `{P̂, n⃗}`,
//! and notes that `P̂` need not be the centre of mass of `PG_j`. We keep the
//! home point's position *in* the plane but project it onto the fitted plane
//! (`centre = P̂ − ((P̂ − PG̅_j)·n⃗) n⃗`): a raw home point carries the full
//! ±10 mm range noise of one laser return, the projection removes it, and the
//! disc still sits where the thesis puts it. [`SldResult::homes`] keeps the
//! index of every home point.
//!
//! PCA gives the normal's line but not its sign. [`Orientation`] chooses it:
//! toward the sensor that saw the registered points (per-point sensor origins,
//! SPEC §3.6), toward one viewpoint, along reference normals (mesh vertex
//! normals or a file's normals), or, when nothing is known, a canonical sign.
//! Paul makes discs from the vertices of the fused TSDF mesh (§5.1.1–5.2):
//! `Orientation::ReferenceNormals(&mesh.vertex_normals())` orients them by
//! the mesh's winding, which faces the sensors (`tests/fused_map.rs` runs the
//! whole pipeline on bridge1).
//!
//! # Determinism and speed
//!
//! The same points, orientation, configuration and seed give bit-identical
//! discs. The only randomness is a ChaCha8 stream from the seed (voxel order
//! and home points). Points are sorted once by [`VoxelKey`] (z, then y, then
//! x) into contiguous memory; a neighbourhood is 27 look-ups in an
//! open-addressing index of the keys, read as nine contiguous runs (the three
//! voxels along `x` are adjacent in the table). Paul reports 54 916 points →
//! 1 636 discs in 5.5 s (Table 5.1); see the crate README for our figures.
//!
//! # Files
//!
//! Disc CSV files and the point clouds discs are made from are read and
//! written by [`crate::sld_io`].
//!
//! ```
//! use geom::Point3;
//! use map::sld::{generate_discs, Orientation, SldConfig};
//!
//! // A 0.4 m × 0.4 m floor patch sampled every 1 cm, seen from above.
//! let points: Vec<Point3> = (0..40)
//!     .flat_map(|i| (0..40).map(move |j| Point3::new(i as f64 * 0.01, j as f64 * 0.01, 0.0)))
//!     .collect();
//! let view = Orientation::Viewpoint(Point3::new(0.2, 0.2, 1.0));
//! let result = generate_discs(&points, view, &SldConfig::default(), 7)?;
//! assert_eq!(result.registered, points.len());
//! assert!(result.discs.iter().all(|d| d.normal.z > 0.999));
//! # Ok::<(), map::MapError>(())
//! ```

use crate::{MapError, VoxelKey};
use geom::{Pca, Plane, Point3, Real, UnitVector3, Vector3, unit};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Parameters of SLD generation (Paul §5.2.1, Table 6.1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SldConfig {
    /// Disc radius and voxel edge `μ`, metres (Table 6.1: 0.04).
    pub radius_m: Real,
    /// Minimum number of registered points `n_min` of a disc (Table 6.1: 8).
    pub min_points: usize,
    /// Registration band about the fitted plane, metres; `None` uses `μ`
    /// (Fig. 5.5d: "register points within ±μ of the plane").
    pub plane_tolerance_m: Option<Real>,
    /// Paul's dimensionality-reduction test: a neighbourhood becomes a disc
    /// only when `λ_mid ≥ min_eigen_ratio · λ_min` (eigenvalues of eq. 5.8).
    /// The default, 1, accepts every neighbourhood with a defined normal.
    pub min_eigen_ratio: Real,
}

impl Default for SldConfig {
    fn default() -> Self {
        Self {
            radius_m: 0.04,
            min_points: 8,
            plane_tolerance_m: None,
            min_eigen_ratio: 1.0,
        }
    }
}

impl SldConfig {
    /// The configuration with another radius `μ`.
    pub fn with_radius_m(radius_m: Real) -> Self {
        Self {
            radius_m,
            ..Self::default()
        }
    }

    /// The registration band actually used, metres.
    pub fn plane_tolerance(&self) -> Real {
        self.plane_tolerance_m.unwrap_or(self.radius_m)
    }

    /// Check the fields.
    pub fn validate(&self) -> Result<(), MapError> {
        let bad =
            |field, expected, got: String| Err(MapError::stage_config("SLD", field, expected, got));
        if !(self.radius_m.is_finite() && self.radius_m > 0.0 && self.radius_m <= MAX_RADIUS_M) {
            return bad(
                "radius_m",
                "a distance in (0, 10] metres",
                self.radius_m.to_string(),
            );
        }
        if self.min_points < 3 {
            return bad(
                "min_points",
                "at least 3 (a plane needs three points)",
                self.min_points.to_string(),
            );
        }
        if let Some(t) = self.plane_tolerance_m
            && !(t.is_finite() && t > 0.0)
        {
            return bad("plane_tolerance_m", "a positive distance", t.to_string());
        }
        if !(self.min_eigen_ratio.is_finite() && self.min_eigen_ratio >= 1.0) {
            return bad(
                "min_eigen_ratio",
                "a finite ratio ≥ 1",
                self.min_eigen_ratio.to_string(),
            );
        }
        Ok(())
    }
}

/// Index of a disc in the list [`generate_discs`] returned (and in a discs
/// file's rows). Serialised as the bare index.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
#[serde(transparent)]
pub struct DiscId(pub usize);

/// Largest disc radius μ accepted, metres (Paul's is 0.04; a disc metres
/// wide no longer follows a surface).
pub const MAX_RADIUS_M: Real = 10.0;

/// One Scale-Like Disc `{P̂, n⃗}` (Paul Fig. 5.6).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Disc {
    /// Centre: the home point projected onto the fitted plane.
    pub centre: Point3,
    /// Unit normal (eigenvector of the smallest covariance eigenvalue), oriented
    /// by the [`Orientation`] given to [`generate_discs`].
    pub normal: UnitVector3,
    /// Radius `μ`, metres.
    pub radius_m: Real,
    /// Number of points registered to this disc.
    pub points: usize,
}

impl Disc {
    /// The disc's plane.
    pub fn plane(&self) -> Plane {
        Plane::from_point_normal(&self.centre, self.normal)
    }

    /// Euclidean distance from `p` to the disc (the solid disc, not its plane).
    pub fn distance_to_point(&self, p: &Point3) -> Real {
        let d = p - self.centre;
        let h = d.dot(&self.normal);
        let in_plane = d - self.normal.into_inner() * h;
        let r = in_plane.norm();
        let outside = (r - self.radius_m).max(0.0);
        (h * h + outside * outside).sqrt()
    }
}

/// How to choose the sign of each disc normal.
#[derive(Clone, Copy, Debug)]
pub enum Orientation<'a> {
    /// The sensor origin of every point (one per point): a normal points toward
    /// the sensors that saw its registered points (SPEC §3.6), i.e. along the
    /// sum of `origin_i − p_i` over them.
    SensorOrigins(&'a [Point3]),
    /// One viewpoint for the whole cloud (e.g. a PCD `VIEWPOINT`, or the robot
    /// base for a map seen from inside): normals point toward it.
    Viewpoint(Point3),
    /// A reference normal per point (mesh vertex normals, a file's normals):
    /// a disc normal agrees with the sum of its registered points' references.
    ReferenceNormals(&'a [Vector3]),
    /// Nothing is known: canonical sign, the normal's component of largest
    /// magnitude is positive (consistent, but not "outward").
    Canonical,
}

/// What [`generate_discs`] returns.
#[derive(Clone, Debug, PartialEq)]
pub struct SldResult {
    /// The discs, in generation order.
    pub discs: Vec<Disc>,
    /// Index (into the input points) of each disc's home point.
    pub homes: Vec<u32>,
    /// Number of points registered to at least one disc.
    pub registered: usize,
    /// For every input point, the first disc that registered it.
    pub per_point_disc: Vec<Option<u32>>,
    /// Number of occupied voxels of size `μ`.
    pub occupied_voxels: usize,
}

impl SldResult {
    /// Registered points as a fraction of all points (1 for an empty cloud).
    pub fn registered_fraction(&self) -> Real {
        if self.per_point_disc.is_empty() {
            1.0
        } else {
            self.registered as Real / self.per_point_disc.len() as Real
        }
    }
}

/// Largest |voxel index| of the SLD hash: `2²⁰ − 2`, so every voxel's
/// neighbours are in range too and [`KeyIndex`] hashes a key as one word.
const KEY_LIMIT: i32 = (1 << 20) - 2;

/// The voxel `⌊p · inv_mu⌋` holding `p`, `None` when a coordinate is not
/// finite or beyond ±[`KEY_LIMIT`] voxels.
#[inline]
fn voxel_of(p: &Point3, inv_mu: Real) -> Option<VoxelKey> {
    let limit = Real::from(KEY_LIMIT);
    let axis = |c: Real| {
        let u = (c * inv_mu).floor();
        // NaN fails the comparison; an in-range float converts exactly.
        (u.abs() <= limit).then_some(u as i32)
    };
    Some(VoxelKey::new(axis(p.x)?, axis(p.y)?, axis(p.z)?))
}

/// The voxel of a point for voxels of size `radius_m`, `⌊p / μ⌋` (Paul
/// §5.2: `p = [130, −25, 35]`, `μ = 10` → `[13, −3, 3]`), as
/// [`generate_discs`] computes it. `None` when the point is not finite or
/// more than `2²⁰ − 2` voxels from the origin on an axis (the points
/// [`generate_discs`] refuses).
pub fn voxel_index(p: &Point3, radius_m: Real) -> Option<VoxelKey> {
    voxel_of(p, 1.0 / radius_m)
}

/// Offset of each coordinate in a [`RowWord`].
const WORD_OFFSET: i32 = 1 << 20;
/// Bits of each coordinate in a [`RowWord`].
const WORD_BITS: u32 = 21;
const WORD_MASK: u64 = (1 << WORD_BITS) - 1;

/// A [`VoxelKey`] within ±([`KEY_LIMIT`] + 1) as one word: each coordinate
/// offset by `2²⁰` into 21 bits, `z` highest. The word's integer order is
/// the voxel table's order — `z`, then `y`, then `x` — so the three voxels
/// along `x` of a neighbourhood row are adjacent in the table; and it is the
/// input of [`KeyIndex`]'s hash. It sorts and hashes; the table itself holds
/// [`VoxelKey`]s.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct RowWord(u64);

impl RowWord {
    /// The word of `key` (every coordinate within ±([`KEY_LIMIT`] + 1)).
    #[inline]
    fn of(key: VoxelKey) -> Self {
        let [x, y, z] = key.coords().map(|c| u64::from((c + WORD_OFFSET) as u32));
        Self((z << (2 * WORD_BITS)) | (y << WORD_BITS) | x)
    }

    /// The key of the word.
    #[inline]
    fn key(self) -> VoxelKey {
        let axis = |shift: u32| ((self.0 >> shift) & WORD_MASK) as i32 - WORD_OFFSET;
        VoxelKey::new(axis(0), axis(WORD_BITS), axis(2 * WORD_BITS))
    }
}

/// Points sorted by voxel, with the voxel table (compressed rows).
struct VoxelTable {
    /// The occupied voxels, unique, in [`RowWord`] order.
    keys: Vec<VoxelKey>,
    /// `starts[v]..starts[v + 1]` are the slots of voxel `v`.
    starts: Vec<u32>,
    /// Point coordinates in slot order.
    points: Vec<Point3>,
    /// Input index of each slot.
    index: Vec<u32>,
}

impl VoxelTable {
    fn build(points: &[Point3], radius_m: Real) -> Result<Self, MapError> {
        let inv_mu = 1.0 / radius_m;
        let mut order: Vec<(RowWord, u32)> = Vec::with_capacity(points.len());
        for (i, p) in points.iter().enumerate() {
            if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
                return Err(MapError::NonFinite {
                    what: "point",
                    index: i,
                });
            }
            let key = voxel_of(p, inv_mu).ok_or(MapError::OutOfRange { index: i, radius_m })?;
            order.push((RowWord::of(key), i as u32));
        }
        // Ties (points of one voxel) in input order: the table is a function
        // of the points alone.
        order.sort_unstable();
        let mut keys = Vec::new();
        let mut starts = Vec::new();
        let mut sorted = Vec::with_capacity(points.len());
        let mut index = Vec::with_capacity(points.len());
        let mut last = None;
        for (slot, &(word, i)) in order.iter().enumerate() {
            if last != Some(word) {
                last = Some(word);
                keys.push(word.key());
                starts.push(slot as u32);
            }
            sorted.push(points[i as usize]);
            index.push(i);
        }
        starts.push(order.len() as u32);
        Ok(Self {
            keys,
            starts,
            points: sorted,
            index,
        })
    }

    /// Slot ranges of the (up to) 27 voxels around voxel `v`, pushed to `out`
    /// as up to nine contiguous runs (the three voxels along `x` are adjacent
    /// in [`RowWord`] order, hence in the table).
    fn neighbourhood(&self, index: &KeyIndex, v: usize, out: &mut Vec<(u32, u32)>) {
        out.clear();
        let key = self.keys[v];
        for dz in -1..=1 {
            for dy in -1..=1 {
                let mut first = None;
                let mut last = 0;
                for dx in -1..=1 {
                    if let Some(i) = index.get(&self.keys, key.offset(dx, dy, dz)) {
                        first.get_or_insert(i);
                        last = i;
                    }
                }
                if let Some(first) = first {
                    out.push((self.starts[first as usize], self.starts[last as usize + 1]));
                }
            }
        }
    }
}

/// Open-addressing index from voxel key to voxel number (look-ups only: its
/// layout never reaches the results).
struct KeyIndex {
    shift: u32,
    slots: Vec<u32>,
}

impl KeyIndex {
    const EMPTY: u32 = u32::MAX;

    fn new(keys: &[VoxelKey]) -> Self {
        let capacity = (2 * keys.len()).next_power_of_two().max(2);
        let mut index = Self {
            shift: 64 - capacity.trailing_zeros(),
            slots: vec![Self::EMPTY; capacity],
        };
        for (i, &k) in keys.iter().enumerate() {
            let mut s = index.home(k);
            while index.slots[s] != Self::EMPTY {
                s = (s + 1) & (capacity - 1);
            }
            index.slots[s] = i as u32;
        }
        index
    }

    /// The home slot of a key (every key looked up is within
    /// ±([`KEY_LIMIT`] + 1)): its [`RowWord`], Fibonacci-hashed.
    #[inline]
    fn home(&self, key: VoxelKey) -> usize {
        (RowWord::of(key).0.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> self.shift) as usize
    }

    #[inline]
    fn get(&self, keys: &[VoxelKey], key: VoxelKey) -> Option<u32> {
        let mask = self.slots.len() - 1;
        let mut s = self.home(key);
        loop {
            let i = self.slots[s];
            if i == Self::EMPTY {
                return None;
            }
            if keys[i as usize] == key {
                return Some(i);
            }
            s = (s + 1) & mask;
        }
    }
}

/// Per-point orientation input, checked.
enum OrientInput<'a> {
    Origins(&'a [Point3]),
    Viewpoint(Point3),
    Normals(&'a [Vector3]),
    Canonical,
}

fn check_orientation(o: Orientation<'_>, n: usize) -> Result<OrientInput<'_>, MapError> {
    let finite = |v: &Vector3| v.x.is_finite() && v.y.is_finite() && v.z.is_finite();
    match o {
        Orientation::SensorOrigins(origins) => {
            if origins.len() != n {
                return Err(MapError::LengthMismatch {
                    what: "sensor origins",
                    expected: n,
                    got: origins.len(),
                });
            }
            if let Some(index) = origins.iter().position(|p| !finite(&p.coords)) {
                return Err(MapError::NonFinite {
                    what: "sensor origin",
                    index,
                });
            }
            Ok(OrientInput::Origins(origins))
        }
        Orientation::Viewpoint(v) => {
            if !finite(&v.coords) {
                return Err(MapError::NonFinite {
                    what: "viewpoint",
                    index: 0,
                });
            }
            Ok(OrientInput::Viewpoint(v))
        }
        Orientation::ReferenceNormals(normals) => {
            if normals.len() != n {
                return Err(MapError::LengthMismatch {
                    what: "reference normals",
                    expected: n,
                    got: normals.len(),
                });
            }
            if let Some(index) = normals.iter().position(|v| !finite(v)) {
                return Err(MapError::NonFinite {
                    what: "reference normal",
                    index,
                });
            }
            Ok(OrientInput::Normals(normals))
        }
        Orientation::Canonical => Ok(OrientInput::Canonical),
    }
}

/// The canonical sign: the component of largest magnitude is positive.
fn canonical(n: Vector3) -> Vector3 {
    let a = n.abs();
    let c = if a.x >= a.y && a.x >= a.z {
        n.x
    } else if a.y >= a.z {
        n.y
    } else {
        n.z
    };
    if c < 0.0 { -n } else { n }
}

/// Generate Scale-Like Discs from `points` (a fused cloud or mesh vertices)
/// following Paul §5.2 (see the [module docs](self) for the steps).
///
/// `seed` fixes the voxel order and the home points: the same inputs and seed
/// give identical results. Errors: invalid configuration, non-finite input,
/// per-point slices of the wrong length, points beyond ±2²⁰ voxels.
pub fn generate_discs(
    points: &[Point3],
    orientation: Orientation<'_>,
    cfg: &SldConfig,
    seed: u64,
) -> Result<SldResult, MapError> {
    cfg.validate()?;
    let orient = check_orientation(orientation, points.len())?;
    let table = VoxelTable::build(points, cfg.radius_m)?;
    let key_index = KeyIndex::new(&table.keys);
    // Per-point orientation references in slot order (view vectors toward
    // the sensor, or reference normals), so the disc loop reads memory in
    // voxel order.
    let slot_reference: Vec<Vector3> = match &orient {
        OrientInput::Origins(origins) => table
            .index
            .iter()
            .map(|&i| origins[i as usize] - points[i as usize])
            .collect(),
        OrientInput::Normals(normals) => table.index.iter().map(|&i| normals[i as usize]).collect(),
        OrientInput::Viewpoint(_) | OrientInput::Canonical => Vec::new(),
    };
    let mu = cfg.radius_m;
    let mu2 = mu * mu;
    let tol = cfg.plane_tolerance();
    let n_voxels = table.keys.len();

    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut voxel_order: Vec<u32> = (0..n_voxels as u32).collect();
    for i in (1..voxel_order.len()).rev() {
        let j = rng.random_range(0..=i);
        voxel_order.swap(i, j);
    }

    let n = points.len();
    let mut registered = vec![false; n]; // by slot
    let mut considered = vec![false; n]; // by slot
    let mut per_point_disc: Vec<Option<u32>> = vec![None; n];
    let mut registered_count = 0usize;
    let mut discs = Vec::new();
    let mut homes = Vec::new();
    let mut runs = Vec::with_capacity(9);
    let mut near: Vec<u32> = Vec::with_capacity(512);
    let mut offsets: Vec<Vector3> = Vec::with_capacity(512);

    for &v in &voxel_order {
        let v = v as usize;
        let (s0, s1) = (table.starts[v] as usize, table.starts[v + 1] as usize);
        let mut runs_ready = false;
        loop {
            // Fig. 5.5a: a random unregistered (and not yet considered) point.
            let candidates = (s0..s1)
                .filter(|&s| !registered[s] && !considered[s])
                .count();
            if candidates == 0 {
                break;
            }
            let pick = rng.random_range(0..candidates);
            let Some(home_slot) = (s0..s1)
                .filter(|&s| !registered[s] && !considered[s])
                .nth(pick)
            else {
                break;
            };
            considered[home_slot] = true;
            let home = table.points[home_slot];

            // Fig. 5.5b–c: points within μ of the home point in the 27 voxels.
            if !runs_ready {
                table.neighbourhood(&key_index, v, &mut runs);
                runs_ready = true;
            }
            near.clear();
            offsets.clear();
            for &(a, b) in &runs {
                for s in a..b {
                    let d = table.points[s as usize] - home;
                    if d.norm_squared() <= mu2 {
                        near.push(s);
                        offsets.push(d);
                    }
                }
            }
            if near.len() < cfg.min_points {
                continue;
            }

            // Eq. 5.5–5.9: PCA about the mean (computed relative to the home
            // point for precision far from the origin).
            let Some(pca) = Pca::of_offsets(&offsets) else {
                continue;
            };
            let mean = pca.centroid.coords;
            let Some(normal) = pca.plane_normal(cfg.min_eigen_ratio) else {
                continue;
            };
            let normal = normal.into_inner();

            // Fig. 5.5d: register the points within ±tol of the plane.
            let mut members = 0usize;
            for d in &offsets {
                if (d - mean).dot(&normal).abs() <= tol {
                    members += 1;
                }
            }
            if members < cfg.min_points {
                continue;
            }

            // Orientation of the normal.
            let mut reference = Vector3::zeros();
            let mut oriented = true;
            match &orient {
                OrientInput::Origins(_) | OrientInput::Normals(_) => {
                    for (s, d) in near.iter().zip(&offsets) {
                        if (d - mean).dot(&normal).abs() <= tol {
                            reference += slot_reference[*s as usize];
                        }
                    }
                }
                OrientInput::Viewpoint(vp) => reference = vp - (home + mean),
                OrientInput::Canonical => oriented = false,
            }
            let signed = if oriented {
                if normal.dot(&reference) < 0.0 {
                    -normal
                } else {
                    normal
                }
            } else {
                canonical(normal)
            };
            let Some(unit_normal) = unit(signed) else {
                continue;
            };

            let disc_id = discs.len() as u32;
            for (s, d) in near.iter().zip(&offsets) {
                if (d - mean).dot(&normal).abs() <= tol {
                    let s = *s as usize;
                    if !registered[s] {
                        registered[s] = true;
                        registered_count += 1;
                        per_point_disc[table.index[s] as usize] = Some(disc_id);
                    }
                }
            }
            // Centre: the home point projected onto the fitted plane.
            let h = (-mean).dot(&unit_normal);
            let centre = home - unit_normal.into_inner() * h;
            discs.push(Disc {
                centre,
                normal: unit_normal,
                radius_m: mu,
                points: members,
            });
            homes.push(table.index[home_slot]);
            break;
        }
    }

    Ok(SldResult {
        discs,
        homes,
        registered: registered_count,
        per_point_disc,
        occupied_voxels: n_voxels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn voxel_index_matches_the_thesis_example() {
        // Paul §5.2: μ = 10 mm, p = [130, −25, 35] mm → [13, −3, 3].
        assert_eq!(
            voxel_index(&Point3::new(0.130, -0.025, 0.035), 0.010),
            Some(VoxelKey::new(13, -3, 3))
        );
        // The hash's range: ±(2²⁰ − 2) voxels, nothing beyond, no NaN.
        let edge = Real::from(KEY_LIMIT);
        assert_eq!(
            voxel_index(&Point3::new(edge + 0.5, -edge, 0.0), 1.0),
            Some(VoxelKey::new(KEY_LIMIT, -KEY_LIMIT, 0))
        );
        assert_eq!(voxel_index(&Point3::new(edge + 1.0, 0.0, 0.0), 1.0), None);
        assert_eq!(voxel_index(&Point3::new(0.0, -edge - 0.5, 0.0), 1.0), None);
        assert_eq!(voxel_index(&Point3::new(0.0, 0.0, Real::NAN), 1.0), None);
    }

    #[test]
    fn row_words_round_trip_and_order_z_y_x() {
        let edge = KEY_LIMIT + 1;
        let keys = [
            VoxelKey::new(0, 0, 0),
            VoxelKey::new(-edge, edge, -1),
            VoxelKey::new(edge, -edge, edge),
            VoxelKey::new(5, -3, 0),
            VoxelKey::new(-5, -3, 0),
            VoxelKey::new(9, 9, -1),
        ];
        for a in keys {
            assert_eq!(RowWord::of(a).key(), a);
            for b in keys {
                let [ax, ay, az] = a.coords();
                let [bx, by, bz] = b.coords();
                assert_eq!(
                    RowWord::of(a).cmp(&RowWord::of(b)),
                    (az, ay, ax).cmp(&(bz, by, bx)),
                    "{a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn table_orders_x_fastest_and_neighbourhoods_are_the_27_voxels() {
        // Points on a 5 × 5 × 5 lattice of unit voxels around the origin,
        // two per voxel, some voxels left empty, in a scrambled order.
        let mut points = Vec::new();
        for i in 0..125_i32 {
            let j = (i * 47) % 125;
            let (x, y, z) = (j % 5 - 2, (j / 5) % 5 - 2, j / 25 - 2);
            if (x + 2 * y + 3 * z).rem_euclid(4) == 0 {
                continue;
            }
            for f in [0.25, 0.75] {
                points.push(Point3::new(
                    Real::from(x) + f,
                    Real::from(y) + 0.5,
                    Real::from(z) + f,
                ));
            }
        }
        let table = VoxelTable::build(&points, 1.0).unwrap();
        // Sorted z, then y, then x: x neighbours are adjacent entries.
        for w in table.keys.windows(2) {
            let ([x0, y0, z0], [x1, y1, z1]) = (w[0].coords(), w[1].coords());
            assert!((z0, y0, x0) < (z1, y1, x1), "{} before {}", w[0], w[1]);
        }
        let index = KeyIndex::new(&table.keys);
        let mut runs = Vec::new();
        for (v, key) in table.keys.iter().enumerate() {
            table.neighbourhood(&index, v, &mut runs);
            let mut got: Vec<u32> = runs.iter().flat_map(|&(a, b)| a..b).collect();
            got.sort_unstable();
            // Brute force: every slot whose voxel is within one step per axis.
            let [x, y, z] = key.coords();
            let want: Vec<u32> = (0..points.len() as u32)
                .filter(|&s| {
                    let [a, b, c] = voxel_index(&table.points[s as usize], 1.0)
                        .unwrap()
                        .coords();
                    (a - x).abs() <= 1 && (b - y).abs() <= 1 && (c - z).abs() <= 1
                })
                .collect();
            assert_eq!(got, want, "voxel {key}");
        }
    }

    #[test]
    fn disc_distance() {
        let d = Disc {
            centre: Point3::origin(),
            normal: UnitVector3::new_unchecked(Vector3::z()),
            radius_m: 1.0,
            points: 3,
        };
        assert!((d.distance_to_point(&Point3::new(0.5, 0.0, 2.0)) - 2.0).abs() < 1e-12);
        assert!((d.distance_to_point(&Point3::new(4.0, 0.0, 4.0)) - 5.0).abs() < 1e-12);
    }
}
