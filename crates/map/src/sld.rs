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
//! and home points). Points are sorted once by voxel key into contiguous
//! memory; a neighbourhood is nine binary searches over the sorted keys (the
//! three voxels along `x` are adjacent keys). Paul reports 54 916 points →
//! 1 636 discs in 5.5 s (Table 5.1); see the crate README for our figures.
//!
//! # Files
//!
//! [`write_discs_csv`] / [`parse_discs_csv`] (and the path versions
//! [`save_discs_csv`], [`load_discs_csv`]) use the header
//! `cx,cy,cz,nx,ny,nz,radius,points`, optionally followed by extra numeric
//! columns ([`ExtraColumn`]: segment, material posterior, …) that the reader
//! ignores. [`load_points`] reads a cloud file and, for PLY scans carrying
//! `ox oy oz` columns, the sensor origin of every point; a mesh file's
//! vertices come with their faces' normals.
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
//! # Ok::<(), map::sld::SldError>(())
//! ```

use geom::{Pca, Plane, Point3, Real, UnitVector3, Vector3, unit};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

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
    pub fn validate(&self) -> Result<(), SldError> {
        let bad = |field: &'static str, expected: &'static str, got: String| {
            Err(SldError::Config {
                field,
                expected,
                got,
            })
        };
        if !(self.radius_m.is_finite() && self.radius_m > 0.0) {
            return bad("radius_m", "a positive distance", self.radius_m.to_string());
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

/// Errors of SLD generation and disc files.
#[derive(Debug, thiserror::Error)]
pub enum SldError {
    /// A configuration field is out of range.
    #[error("SLD config `{field}`: expected {expected}, got {got}")]
    Config {
        /// The field.
        field: &'static str,
        /// What is accepted.
        expected: &'static str,
        /// What was given.
        got: String,
    },
    /// An input point (or its origin / reference normal) is not finite.
    #[error("{what} {index} is not finite")]
    NonFinite {
        /// `point`, `sensor origin`, `reference normal` or `viewpoint`.
        what: &'static str,
        /// Its index.
        index: usize,
    },
    /// A point is too far from the origin for the voxel hash (±2²⁰ voxels).
    #[error("point {index} is too far from the origin for voxels of {radius_m} m")]
    OutOfRange {
        /// The point.
        index: usize,
        /// The voxel size.
        radius_m: Real,
    },
    /// A per-point slice has the wrong length.
    #[error("{what}: expected {expected} entries (one per point), got {got}")]
    LengthMismatch {
        /// Which input.
        what: &'static str,
        /// Number of points.
        expected: usize,
        /// Length given.
        got: usize,
    },
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// A disc or cloud file is malformed.
    #[error("{source_name}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Parse {
        /// The file (or a label for in-memory text).
        source_name: String,
        /// 1-based line, when known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
}

/// Offset and width of one packed voxel coordinate.
const KEY_BITS: u32 = 21;
const KEY_OFFSET: i64 = 1 << (KEY_BITS - 1);
/// Largest |voxel index| accepted (one less than the packing allows, so the
/// neighbour keys of every voxel exist).
const KEY_LIMIT: i64 = KEY_OFFSET - 2;

#[inline]
fn pack(x: i64, y: i64, z: i64) -> u64 {
    (((z + KEY_OFFSET) as u64) << (2 * KEY_BITS))
        | (((y + KEY_OFFSET) as u64) << KEY_BITS)
        | ((x + KEY_OFFSET) as u64)
}

#[inline]
fn voxel_of(p: &Point3, inv_mu: Real) -> [i64; 3] {
    [
        (p.x * inv_mu).floor() as i64,
        (p.y * inv_mu).floor() as i64,
        (p.z * inv_mu).floor() as i64,
    ]
}

/// The voxel key of a point for voxels of size `radius_m`, as integer indices
/// `⌊p / μ⌋` (Paul §5.2: `p = [130, −25, 35]`, `μ = 10` → `[13, −3, 3]`).
pub fn voxel_index(p: &Point3, radius_m: Real) -> [i64; 3] {
    voxel_of(p, 1.0 / radius_m)
}

/// Points sorted by voxel, with the voxel table (compressed rows).
struct VoxelTable {
    /// Sorted unique voxel keys.
    keys: Vec<u64>,
    /// `starts[v]..starts[v + 1]` are the slots of voxel `v`.
    starts: Vec<u32>,
    /// Point coordinates in slot order.
    points: Vec<Point3>,
    /// Input index of each slot.
    index: Vec<u32>,
    /// Voxel indices `[x, y, z]` of each voxel.
    coords: Vec<[i64; 3]>,
}

impl VoxelTable {
    fn build(points: &[Point3], radius_m: Real) -> Result<Self, SldError> {
        let inv_mu = 1.0 / radius_m;
        let mut order: Vec<(u64, u32)> = Vec::with_capacity(points.len());
        for (i, p) in points.iter().enumerate() {
            if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
                return Err(SldError::NonFinite {
                    what: "point",
                    index: i,
                });
            }
            let [x, y, z] = voxel_of(p, inv_mu);
            if x.abs() > KEY_LIMIT || y.abs() > KEY_LIMIT || z.abs() > KEY_LIMIT {
                return Err(SldError::OutOfRange { index: i, radius_m });
            }
            order.push((pack(x, y, z), i as u32));
        }
        order.sort_unstable();
        let mut keys = Vec::new();
        let mut starts = Vec::new();
        let mut coords = Vec::new();
        let mut sorted = Vec::with_capacity(points.len());
        let mut index = Vec::with_capacity(points.len());
        for (slot, &(key, i)) in order.iter().enumerate() {
            if keys.last() != Some(&key) {
                keys.push(key);
                starts.push(slot as u32);
                coords.push(voxel_of(&points[i as usize], inv_mu));
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
            coords,
        })
    }

    /// Slot ranges of the (up to) 27 voxels around voxel `v`, pushed to `out`
    /// as up to nine contiguous runs (the three voxels along `x` are adjacent
    /// keys, hence adjacent in the sorted table).
    fn neighbourhood(&self, index: &KeyIndex, v: usize, out: &mut Vec<(u32, u32)>) {
        out.clear();
        let [x, y, z] = self.coords[v];
        for dz in -1..=1 {
            for dy in -1..=1 {
                let mut first = None;
                let mut last = 0;
                for dx in -1..=1 {
                    if let Some(i) = index.get(&self.keys, pack(x + dx, y + dy, z + dz)) {
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

    fn new(keys: &[u64]) -> Self {
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

    #[inline]
    fn home(&self, key: u64) -> usize {
        (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> self.shift) as usize
    }

    #[inline]
    fn get(&self, keys: &[u64], key: u64) -> Option<u32> {
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

fn check_orientation(o: Orientation<'_>, n: usize) -> Result<OrientInput<'_>, SldError> {
    let finite = |v: &Vector3| v.x.is_finite() && v.y.is_finite() && v.z.is_finite();
    match o {
        Orientation::SensorOrigins(origins) => {
            if origins.len() != n {
                return Err(SldError::LengthMismatch {
                    what: "sensor origins",
                    expected: n,
                    got: origins.len(),
                });
            }
            if let Some(index) = origins.iter().position(|p| !finite(&p.coords)) {
                return Err(SldError::NonFinite {
                    what: "sensor origin",
                    index,
                });
            }
            Ok(OrientInput::Origins(origins))
        }
        Orientation::Viewpoint(v) => {
            if !finite(&v.coords) {
                return Err(SldError::NonFinite {
                    what: "viewpoint",
                    index: 0,
                });
            }
            Ok(OrientInput::Viewpoint(v))
        }
        Orientation::ReferenceNormals(normals) => {
            if normals.len() != n {
                return Err(SldError::LengthMismatch {
                    what: "reference normals",
                    expected: n,
                    got: normals.len(),
                });
            }
            if let Some(index) = normals.iter().position(|v| !finite(v)) {
                return Err(SldError::NonFinite {
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
) -> Result<SldResult, SldError> {
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

/// An extra numeric column of a disc file (segment index, a material
/// probability, …), written after the eight contract columns.
#[derive(Clone, Debug, PartialEq)]
pub struct ExtraColumn {
    /// Header name (no commas, not one of the contract names).
    pub name: String,
    /// One value per disc.
    pub values: Vec<Real>,
}

/// The contract header of disc files.
pub const DISC_CSV_HEADER: [&str; 8] = ["cx", "cy", "cz", "nx", "ny", "nz", "radius", "points"];

/// Write discs as CSV: header `cx,cy,cz,nx,ny,nz,radius,points`, then the
/// `extra` columns, one row per disc. Values use Rust's shortest round-trip
/// formatting, so [`parse_discs_csv`] reads back identical discs.
///
/// Fails with [`std::io::ErrorKind::InvalidInput`], before writing anything,
/// when an extra column has the wrong length or a bad name.
pub fn write_discs_csv(
    writer: &mut impl Write,
    discs: &[Disc],
    extra: &[ExtraColumn],
) -> std::io::Result<()> {
    for (k, c) in extra.iter().enumerate() {
        let bad_name = c.name.is_empty()
            || c.name.contains([',', '\n', '\r', '"'])
            || DISC_CSV_HEADER.contains(&c.name.as_str())
            || extra[..k].iter().any(|o| o.name == c.name);
        if bad_name || c.values.len() != discs.len() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!(
                    "extra column `{}`: needs a unique name without commas and {} values (has {})",
                    c.name,
                    discs.len(),
                    c.values.len()
                ),
            ));
        }
    }
    let mut line = DISC_CSV_HEADER.join(",");
    for c in extra {
        line.push(',');
        line.push_str(&c.name);
    }
    line.push('\n');
    writer.write_all(line.as_bytes())?;
    for (i, d) in discs.iter().enumerate() {
        line.clear();
        let _ = write!(
            line,
            "{},{},{},{},{},{},{},{}",
            d.centre.x,
            d.centre.y,
            d.centre.z,
            d.normal.x,
            d.normal.y,
            d.normal.z,
            d.radius_m,
            d.points
        );
        for c in extra {
            let _ = write!(line, ",{}", c.values[i]);
        }
        line.push('\n');
        writer.write_all(line.as_bytes())?;
    }
    Ok(())
}

/// [`write_discs_csv`] into a new file at `path`.
pub fn save_discs_csv(path: &Path, discs: &[Disc], extra: &[ExtraColumn]) -> Result<(), SldError> {
    let io = |source| SldError::Io {
        path: path.to_owned(),
        source,
    };
    let mut buf = Vec::new();
    write_discs_csv(&mut buf, discs, extra).map_err(io)?;
    std::fs::write(path, buf).map_err(io)
}

/// Read discs from CSV text with at least the contract columns
/// `cx,cy,cz,nx,ny,nz,radius,points` (in any order; other columns are
/// ignored). Normals are re-normalised; a zero or non-finite normal, a
/// non-finite centre, a non-positive radius or a non-integer point count is
/// an error naming `source_name` and the line.
pub fn parse_discs_csv(text: &str, source_name: &str) -> Result<Vec<Disc>, SldError> {
    let err = |line: Option<usize>, message: String| SldError::Parse {
        source_name: source_name.to_owned(),
        line,
        message,
    };
    let mut lines = text.lines().enumerate();
    let (_, header) = lines
        .by_ref()
        .find(|(_, l)| !l.trim().is_empty())
        .ok_or_else(|| err(None, "empty file: expected a header line".into()))?;
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut col = [0usize; 8];
    for (k, want) in DISC_CSV_HEADER.iter().enumerate() {
        col[k] = names.iter().position(|n| n == want).ok_or_else(|| {
            err(
                Some(1),
                format!(
                    "missing column `{want}` (header must contain {})",
                    DISC_CSV_HEADER.join(",")
                ),
            )
        })?;
    }
    let mut discs = Vec::new();
    for (i, raw) in lines {
        let line_no = i + 1;
        if raw.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = raw.split(',').map(str::trim).collect();
        if fields.len() < names.len() {
            return Err(err(
                Some(line_no),
                format!("expected {} fields, found {}", names.len(), fields.len()),
            ));
        }
        let mut v = [0.0; 7];
        for k in 0..7 {
            let s = fields[col[k]];
            v[k] = s
                .parse::<Real>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    err(
                        Some(line_no),
                        format!(
                            "field `{}`: expected a finite number, found `{s}`",
                            DISC_CSV_HEADER[k]
                        ),
                    )
                })?;
        }
        let s = fields[col[7]];
        let points = s.parse::<usize>().map_err(|_| {
            err(
                Some(line_no),
                format!("field `points`: expected a non-negative integer, found `{s}`"),
            )
        })?;
        let normal = unit(Vector3::new(v[3], v[4], v[5]))
            .ok_or_else(|| err(Some(line_no), "the normal (nx, ny, nz) is zero".into()))?;
        if v[6] <= 0.0 {
            return Err(err(
                Some(line_no),
                format!(
                    "field `radius`: expected a positive distance, found {}",
                    v[6]
                ),
            ));
        }
        discs.push(Disc {
            centre: Point3::new(v[0], v[1], v[2]),
            normal,
            radius_m: v[6],
            points,
        });
    }
    Ok(discs)
}

/// Read a disc CSV file (see [`parse_discs_csv`]).
pub fn load_discs_csv(path: &Path) -> Result<Vec<Disc>, SldError> {
    let text = std::fs::read_to_string(path).map_err(|source| SldError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse_discs_csv(&text, &path.display().to_string())
}

/// Points of a cloud file, with the sensor origin of every point when the
/// file carries them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadedPoints {
    /// The points.
    pub points: Vec<Point3>,
    /// Per-point sensor origins (PLY columns `ox oy oz`, as written by
    /// `surveyor scan`), when present.
    pub origins: Option<Vec<Point3>>,
    /// Per-point normals, when the file has them.
    pub normals: Option<Vec<Vector3>>,
}

impl LoadedPoints {
    /// The best orientation these points allow: sensor origins, else the
    /// file's normals, else [`Orientation::Canonical`].
    pub fn orientation(&self) -> Orientation<'_> {
        if let Some(o) = &self.origins {
            Orientation::SensorOrigins(o)
        } else if let Some(n) = &self.normals {
            Orientation::ReferenceNormals(n)
        } else {
            Orientation::Canonical
        }
    }
}

/// Read a point cloud (any format `scene::io::load_cloud_or_mesh_vertices`
/// reads: PLY, PCD, text, OBJ/STL vertices) and, for a PLY file with `ox`,
/// `oy`, `oz` vertex properties, the per-point sensor origins.
pub fn load_points(path: &Path) -> Result<LoadedPoints, SldError> {
    let scene_err = |e: scene::SceneError| SldError::Parse {
        source_name: path.display().to_string(),
        line: None,
        message: e.to_string(),
    };
    let is_ply = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if is_ply {
        let table = scene::io::read_ply_vertices(path).map_err(scene_err)?;
        if sensor::Sweep::is_scan_table(&table) {
            let sweep =
                sensor::Sweep::from_ply_table(path, &table).map_err(|e| SldError::Parse {
                    source_name: path.display().to_string(),
                    line: None,
                    message: match e {
                        sensor::SensorError::ScanFile { message, .. } => message,
                        other => other.to_string(),
                    },
                })?;
            return Ok(LoadedPoints {
                points: sweep.positions(),
                origins: Some(sweep.origins()),
                normals: None,
            });
        }
    }
    let cloud = scene::io::load_cloud_or_mesh_vertices(path).map_err(scene_err)?;
    let origins = None;
    Ok(LoadedPoints {
        points: cloud.points,
        origins,
        normals: cloud.normals,
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
            [13, -3, 3]
        );
    }

    #[test]
    fn packed_keys_order_x_fastest() {
        assert_eq!(pack(1, 0, 0), pack(0, 0, 0) + 1);
        assert!(pack(-1, 1, 0) > pack(5, 0, 0));
        assert!(pack(0, -5, 1) > pack(9, 9, 0));
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
