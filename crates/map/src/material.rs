//! Per-voxel material-type belief and the material information `H3`
//! (Paul §4.4, eq. 4.15–4.17).
//!
//! Only voxels that hold a surface carry a belief ("it is not necessary to
//! hold a material-type belief about a surface that doesn't exist", §4.4), so
//! [`MaterialBelief`] is sparse: a table of occupied [`VoxelKey`]s, each with
//! a probability `P(ʲx_m)` for every one of the `n_t` materials (`n_t = 5`,
//! Table 6.1), initialised uniform (no a-priori knowledge).
//!
//! # Update (eq. 4.15)
//!
//! An LRC observation `z` of voxel `j` is a probability vector over the
//! materials (the classifier's posterior under a uniform class prior, which is
//! its normalised likelihood `P(z | x_m)`). Bayes' theorem gives
//!
//! ```text
//! P(ʲx_m | z) = P(z | x_m) P(ʲx_m) / P(z),   P(z) = Σ_m P(z | x_m) P(ʲx_m)
//! ```
//!
//! with `P(z | x_m)` taken as the LRC's output for material `m`, clamped below
//! at [`MaterialConfig::min_likelihood`] so that a single overconfident
//! misclassification cannot drive a material to exactly zero forever (the
//! thesis models the LRC as fallible, "a stochastic function"). With the clamp
//! at 0 the update is eq. 4.15 verbatim.
//!
//! # Information remaining (eq. 4.16–4.17)
//!
//! Per voxel, `H3(ʲM) = −Σ_m P(ʲx_m) ln P(ʲx_m)` (natural logarithm). The
//! thesis writes eq. 4.16 without the minus sign and puts it in eq. 4.17,
//! `H3(M) = −Σ_j H3(ʲM)`; we return the information remaining as a positive
//! number at every level: [`MaterialBelief::h3_voxel`] ≥ 0, at most `ln n_t`
//! for the uniform prior; [`MaterialBelief::h3_total`] is their sum (eq. 4.17);
//! [`MaterialBelief::h3_disc`] sums the voxels a disc covers ("summing the
//! information remaining in the voxels which the SLD represents").
//!
//! The decision `ʲx̂_m` is the most probable material
//! ([`MaterialBelief::map_estimate`]).
//!
//! ```
//! use geom::Point3;
//! use map::material::{MaterialBelief, MaterialConfig};
//!
//! let mut belief = MaterialBelief::new(MaterialConfig::default())?;
//! let key = belief.key_of(&Point3::new(0.1, 0.2, 1.5))?;
//! belief.insert_surface(key);
//! assert!((belief.h3_voxel(key).unwrap() - 5f64.ln()).abs() < 1e-12);
//! // The LRC says "timber" with 70 % confidence.
//! belief.update(key, &[0.1, 0.7, 0.1, 0.05, 0.05])?;
//! assert_eq!(belief.map_estimate(key), Some(1));
//! assert!(belief.h3_voxel(key).unwrap() < 5f64.ln());
//! # Ok::<(), map::MapError>(())
//! ```

use crate::MapError;
pub use crate::key::VoxelKey;
use crate::sld::Disc;
use geom::{Point3, Real, Vector3};
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};

/// Parameters of the material belief.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MaterialConfig {
    /// Number of material types `n_t` (Table 6.1: 5).
    pub n_materials: usize,
    /// Edge of a material voxel, metres. Keys are global ([`VoxelKey`]), so
    /// with the occupancy grid's voxel size (1 cm by default) a belief voxel
    /// is an occupied voxel of the grid.
    pub voxel_m: Real,
    /// Floor on each likelihood `P(z | x_m)` of an update (0: eq. 4.15 verbatim).
    pub min_likelihood: Real,
}

impl Default for MaterialConfig {
    fn default() -> Self {
        Self {
            n_materials: 5,
            voxel_m: 0.01,
            min_likelihood: 1e-3,
        }
    }
}

impl MaterialConfig {
    /// Check the fields.
    pub fn validate(&self) -> Result<(), MapError> {
        let bad = |field, expected, got: String| {
            Err(MapError::stage_config("material", field, expected, got))
        };
        if !(1..=u16::MAX as usize).contains(&self.n_materials) {
            return bad(
                "n_materials",
                "1 to 65535 materials",
                self.n_materials.to_string(),
            );
        }
        if !(self.voxel_m.is_finite() && self.voxel_m > 0.0) {
            return bad("voxel_m", "a positive size", self.voxel_m.to_string());
        }
        if !(self.min_likelihood.is_finite() && (0.0..1.0).contains(&self.min_likelihood)) {
            return bad(
                "min_likelihood",
                "a value in [0, 1)",
                self.min_likelihood.to_string(),
            );
        }
        Ok(())
    }
}

/// The material belief of every surface voxel (see the [module docs](self)).
///
/// Voxels are kept in insertion order (a hash index only serves look-ups), so
/// sums such as [`MaterialBelief::h3_total`] are bit-reproducible.
#[derive(Clone, Debug)]
pub struct MaterialBelief {
    cfg: MaterialConfig,
    keys: Vec<VoxelKey>,
    index: FxHashMap<VoxelKey, u32>,
    /// `n_t` probabilities per voxel, voxel-major.
    probs: Vec<Real>,
    /// Cached `H3(ʲM)` per voxel.
    h3: Vec<Real>,
}

/// `−Σ p ln p` (0 ln 0 = 0).
fn entropy(p: &[Real]) -> Real {
    -p.iter()
        .filter(|&&v| v > 0.0)
        .map(|&v| v * v.ln())
        .sum::<Real>()
}

impl MaterialBelief {
    /// An empty belief map.
    pub fn new(cfg: MaterialConfig) -> Result<Self, MapError> {
        cfg.validate()?;
        Ok(Self {
            cfg,
            keys: Vec::new(),
            index: FxHashMap::default(),
            probs: Vec::new(),
            h3: Vec::new(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &MaterialConfig {
        &self.cfg
    }

    /// Number of voxels with a belief (`n_m`).
    pub fn len(&self) -> usize {
        self.keys.len()
    }

    /// `true` when no voxel has a belief.
    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    /// The voxels with a belief, in insertion order.
    pub fn keys(&self) -> &[VoxelKey] {
        &self.keys
    }

    /// The key of the voxel holding `p`.
    pub fn key_of(&self, p: &Point3) -> Result<VoxelKey, MapError> {
        VoxelKey::of_point(p, self.cfg.voxel_m).ok_or(MapError::BadPoint {
            x: p.x,
            y: p.y,
            z: p.z,
        })
    }

    /// Give `key` the uniform prior if it has no belief yet (a newly occupied
    /// surface voxel). Returns `true` when it was inserted.
    pub fn insert_surface(&mut self, key: VoxelKey) -> bool {
        if self.index.contains_key(&key) {
            return false;
        }
        let n = self.cfg.n_materials;
        self.index.insert(key, self.keys.len() as u32);
        self.keys.push(key);
        self.probs.extend(std::iter::repeat_n(1.0 / n as Real, n));
        self.h3.push((n as Real).ln());
        true
    }

    /// Insert every voxel a disc covers ([`MaterialBelief::disc_voxels`]).
    pub fn insert_disc(&mut self, disc: &Disc) {
        for key in self.disc_voxels(disc) {
            self.insert_surface(key);
        }
    }

    /// The probabilities `P(ʲx_m)` of a voxel.
    pub fn probabilities(&self, key: VoxelKey) -> Option<&[Real]> {
        let n = self.cfg.n_materials;
        self.index
            .get(&key)
            .map(|&i| &self.probs[i as usize * n..(i as usize + 1) * n])
    }

    /// Bayes update of one voxel with an LRC observation (eq. 4.15). A voxel
    /// without a belief is first given the uniform prior. On error the belief
    /// is unchanged.
    pub fn update(&mut self, key: VoxelKey, observation: &[Real]) -> Result<(), MapError> {
        let n = self.cfg.n_materials;
        self.check_observation(observation)?;
        let i = if let Some(&i) = self.index.get(&key) {
            i as usize
        } else {
            // Check the evidence against the uniform prior before inserting.
            let floor = self.cfg.min_likelihood;
            if observation.iter().all(|&l| l.max(floor) <= 0.0) {
                return Err(MapError::NoEvidence { key });
            }
            self.insert_surface(key);
            self.keys.len() - 1
        };
        let p = &mut self.probs[i * n..(i + 1) * n];
        if !bayes_update(p, observation, self.cfg.min_likelihood) {
            return Err(MapError::NoEvidence { key });
        }
        self.h3[i] = entropy(p);
        Ok(())
    }

    fn check_observation(&self, observation: &[Real]) -> Result<(), MapError> {
        if observation.len() != self.cfg.n_materials {
            return Err(MapError::ObservationLength {
                expected: self.cfg.n_materials,
                got: observation.len(),
            });
        }
        if let Some((index, &value)) = observation
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(MapError::ObservationValue { index, value });
        }
        Ok(())
    }

    /// Update every distinct voxel holding one of `points` once with the same
    /// observation (one LRC classification is one piece of evidence per
    /// voxel, however many of its rays fell in the voxel). Voxels are updated
    /// in the order of their first point. Non-finite points are an error and
    /// nothing is updated.
    pub fn update_points(
        &mut self,
        points: &[Point3],
        observation: &[Real],
    ) -> Result<usize, MapError> {
        self.check_observation(observation)?;
        let mut keys = Vec::with_capacity(points.len());
        for p in points {
            let k = self.key_of(p)?;
            if !keys.contains(&k) {
                keys.push(k);
            }
        }
        // Validate the evidence for every voxel first, so an error leaves
        // every belief unchanged.
        let n = self.cfg.n_materials;
        let floor = self.cfg.min_likelihood;
        for &k in &keys {
            let ok = match self.index.get(&k) {
                Some(&i) => {
                    let p = &self.probs[i as usize * n..(i as usize + 1) * n];
                    p.iter()
                        .zip(observation)
                        .map(|(&a, &l)| a * l.max(floor))
                        .sum::<Real>()
                        > 0.0
                }
                None => observation.iter().any(|&l| l.max(floor) > 0.0),
            };
            if !ok {
                return Err(MapError::NoEvidence { key: k });
            }
        }
        for &k in &keys {
            self.update(k, observation)?;
        }
        Ok(keys.len())
    }

    /// `H3(ʲM) = −Σ_m P(ʲx_m) ln P(ʲx_m)` of one voxel (eq. 4.16, sign such
    /// that the information remaining is positive), `None` without a belief.
    pub fn h3_voxel(&self, key: VoxelKey) -> Option<Real> {
        self.slot(key).map(|i| self.h3[i])
    }

    /// Where voxel `key`'s belief is kept, `None` without one. A voxel keeps
    /// its slot for the belief's life (voxels are only ever added), so a
    /// caller that reads the same voxels many times may look them up once.
    pub fn slot(&self, key: VoxelKey) -> Option<usize> {
        self.index.get(&key).map(|&i| i as usize)
    }

    /// The material probabilities of the voxel in `slot` ([`Self::slot`]).
    ///
    /// # Panics
    /// When `slot` is not one of this belief's.
    pub fn probabilities_in(&self, slot: usize) -> &[Real] {
        let n = self.cfg.n_materials;
        &self.probs[slot * n..(slot + 1) * n]
    }

    /// `H3` of the voxel in `slot` ([`Self::slot`]).
    ///
    /// # Panics
    /// When `slot` is not one of this belief's.
    pub fn h3_in(&self, slot: usize) -> Real {
        self.h3[slot]
    }

    /// `H3(M)`: the information remaining over all belief voxels (eq. 4.17).
    pub fn h3_total(&self) -> Real {
        self.h3.iter().sum()
    }

    /// The voxels a disc covers: every voxel whose centre is within half a
    /// voxel diagonal of the disc (a conservative disc–cube overlap test),
    /// sorted.
    pub fn disc_voxels(&self, disc: &Disc) -> Vec<VoxelKey> {
        let s = self.cfg.voxel_m;
        let half_diag = 0.5 * s * 3f64.sqrt();
        let r = Vector3::repeat(disc.radius_m + half_diag);
        let (Some(lo), Some(hi)) = (
            VoxelKey::of_point(&(disc.centre - r), s),
            VoxelKey::of_point(&(disc.centre + r), s),
        ) else {
            return Vec::new();
        };
        let ([x0, y0, z0], [x1, y1, z1]) = (lo.coords(), hi.coords());
        let mut out = Vec::new();
        for z in z0..=z1 {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let k = VoxelKey::new(x, y, z);
                    if disc.distance_to_point(&k.center(s)) <= half_diag {
                        out.push(k);
                    }
                }
            }
        }
        out.sort_unstable();
        out
    }

    /// The information remaining on a disc: the sum of `H3(ʲM)` over the
    /// belief voxels it covers ([`MaterialBelief::disc_voxels`]; covered
    /// voxels without a belief hold no surface and add nothing).
    pub fn h3_disc(&self, disc: &Disc) -> Real {
        self.disc_voxels(disc)
            .iter()
            .filter_map(|k| self.h3_voxel(*k))
            .sum()
    }

    /// The mean of the material probabilities of the belief voxels a disc
    /// covers (for `discs.csv`), `None` when it covers none.
    pub fn disc_probabilities(&self, disc: &Disc) -> Option<Vec<Real>> {
        let n = self.cfg.n_materials;
        let mut sum = vec![0.0; n];
        let mut count = 0usize;
        for k in self.disc_voxels(disc) {
            if let Some(p) = self.probabilities(k) {
                for (s, v) in sum.iter_mut().zip(p) {
                    *s += v;
                }
                count += 1;
            }
        }
        (count > 0).then(|| sum.into_iter().map(|s| s / count as Real).collect())
    }

    /// The most probable material of a voxel (ties: the lowest index), the
    /// decision `ʲx̂_m` of §4.4.1.
    pub fn map_estimate(&self, key: VoxelKey) -> Option<usize> {
        self.probabilities(key).map(argmax)
    }
}

/// Bayes' update of one belief `p` by an LRC observation (eq. 4.15), each
/// likelihood `P(z | x_m)` clamped below at `min_likelihood`
/// ([`MaterialConfig::min_likelihood`]): what [`MaterialBelief::update`]
/// does to a voxel. Returns `false`, `p` unchanged, when the evidence
/// `P(z)` is not positive and finite.
pub fn bayes_update(p: &mut [Real], observation: &[Real], min_likelihood: Real) -> bool {
    let evidence: Real = p
        .iter()
        .zip(observation)
        .map(|(&prior, &l)| prior * l.max(min_likelihood))
        .sum();
    if !(evidence > 0.0 && evidence.is_finite()) {
        return false;
    }
    for (prior, &l) in p.iter_mut().zip(observation) {
        *prior = *prior * l.max(min_likelihood) / evidence;
    }
    true
}

/// Index of the largest value (ties: the lowest index; NaN never wins).
pub fn argmax(p: &[Real]) -> usize {
    let mut best = 0;
    for (i, &v) in p.iter().enumerate() {
        if v > p[best] {
            best = i;
        }
    }
    best
}
