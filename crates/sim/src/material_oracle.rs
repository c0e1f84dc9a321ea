//! The material oracle: what share of Stage Two's surfaces (A2) any safe
//! pose could identify within the LRC's constraints, and what a greedy
//! choice of viewpoints that knows the true scene identifies after `n` of
//! them, with the run's robot, scanner, LRC and safety rule (SPEC §3.8,
//! issue 44).
//!
//! - **Samples**: true-surface samples of A2 (the scenario's metric
//!   sampling, [`MATERIAL_SAMPLES_PER_M2`]), each with its point, normal and
//!   true material.
//! - **LRC**: the run's (`explore::lrc`: `[explore.pose]`'s constraints,
//!   the run's training), trained with seed 0.
//! - **Pool**: the start, the roadmap's nodes, and *aimed poses*: Stage
//!   Two's pose selection (LM, `[explore.pose]`) from the start, aimed at
//!   one sample per [`AIM_CELL_M`] cell and facing, on a perfect map (the
//!   planning voxels a true surface passes through occupied, every other
//!   one free), its valid solutions kept. A pose is *clear* when it and its
//!   whole tilt sweep obey the run's rule on the true scene: `dist(Q) > 1`
//!   on the perfect map and the links' capsules Stage Two's clearance
//!   (`stage_two_clearance_m`) or more from the true surface
//!   ([`crate::oracle`]'s rule with Stage Two's clearance).
//! - **Observations**: the sweep of every clear pose (and the start's),
//!   simulated on the true scene with noise seeded by the pose's index; for
//!   each sample in view (its own surface facing the sweep's scanner within
//!   the LRC's range and incidence, widened by the scanner's travel through
//!   the sweep), the returns within the patch radius whose ray origin is on
//!   the sample's side, classified by the LRC; an accepted observation's
//!   posterior is kept.
//! - **Greedy**: each sample's belief starts uniform and fuses observations
//!   by Bayes as the run's belief does (`map::material::bayes_update`, the
//!   same likelihood floor); a sample is identified when its most probable
//!   material has `p ≥ 0.8` ([`explore::IDENTIFIED_P`]). The start's sweep
//!   first, then each next viewpoint the clear pose that adds the most
//!   identified samples (net of any it un-identifies; ties to the lower
//!   index), up to [`MATERIAL_ORACLE_MAX_VIEWPOINTS`] or until none adds one.
//! - **Identifiable**: the samples one observation identifies on its own,
//!   from some clear pose (or the start), and those the greedy identifies.
//!
//! [`MaterialOracleJob`] computes it beside a run (cached in a file like the
//! coverage oracle), and [`compare`] puts the run's own identification on
//! the same samples beside it: `run.json`'s `material_identification`.

use crate::SimError;
use crate::oracle::{TruthRule, idle_priority, simulated_sweep};
use explore::{ExploreRun, IDENTIFIED_P, PatchIndex, Setup};
use geom::{Aabb, Point3, Real, UnitVector3, Vector3};
use map::material::{argmax, bayes_update};
use rayon::prelude::*;
use record::explore::{MaterialIdentification, MaterialOracle};
use scenario::{LoadedScenario, MetricsConfig};
use scene::World;
use sensor::classifier::LrcConfig;
use serde::{Deserialize, Serialize};
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Density of the oracle's true-surface samples of A2, per m²: one per
/// 10 cm square, against a patch of radius 0.18 m (about ten samples share
/// a patch). Every sample in view of a pose is one classification of a
/// patch of thousands of returns: at 400 per m² the oracle of bridge1 took
/// 170 s of CPU, four times what this density takes.
pub const MATERIAL_SAMPLES_PER_M2: Real = 100.0;

/// Edge of the cells that spread the aimed poses' targets, metres: one
/// target per cell and facing (the normal's dominant axis and sign).
pub const AIM_CELL_M: Real = 0.15;

/// Most viewpoints the oracle's greedy choice takes (it stops sooner when
/// no viewpoint adds an identified sample).
pub const MATERIAL_ORACLE_MAX_VIEWPOINTS: usize = 40;

/// A run disc stands for a sample when its centre lies within the disc's
/// radius plus this much of the sample, metres.
pub const RUN_DISC_MARGIN_M: Real = 0.01;

/// … and the cosine between its seen side and the sample's normal is above
/// this.
pub const RUN_DISC_MIN_COS: Real = 0.5;

/// Format of the cache file; a file of another format is made again.
const CACHE_FORMAT: u32 = 1;

/// The rule's name in `run.json`.
const RULE: &str = "dist(Q) > 1 on the true scene's voxels and Stage Two's clearance";

/// A true-surface sample of A2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialSample {
    /// Position.
    pub point: Point3,
    /// Outward unit normal.
    pub normal: UnitVector3,
    /// True material (index into the scene's material table).
    pub material: usize,
}

/// The oracle's samples of `world` (a scene) in `a2`: the scenario's metric
/// sampling (`metrics`: its seed, exposed faces only when it says so) at
/// [`MATERIAL_SAMPLES_PER_M2`], and the density drawn.
pub fn material_samples(
    world: &World,
    metrics: &MetricsConfig,
    a2: Aabb,
) -> Result<(Vec<MaterialSample>, Real), SimError> {
    let scene = world.as_scene().ok_or_else(|| SimError::InvalidArgument {
        what: "material oracle".into(),
        message: "needs a scene with true surfaces, not a point cloud".into(),
    })?;
    let mut config = metrics.sampling;
    config.region = Some(a2);
    config.samples_per_m2 = MATERIAL_SAMPLES_PER_M2;
    let sampler = scene::SurfaceSampler::new(scene, &config)?;
    let density = sampler.samples_per_m2();
    let samples = sampler
        .flatten()
        .map(|s| MaterialSample {
            point: s.point,
            normal: s.normal,
            material: usize::from(s.material.0),
        })
        .collect();
    Ok((samples, density))
}

/// The accepted LRC observations of one pose's sweep: the samples observed
/// and, `n_t` per sample, the posteriors.
#[derive(Clone, Debug, Default, PartialEq)]
struct PoseObservations {
    samples: Vec<u32>,
    posteriors: Vec<Real>,
}

impl PoseObservations {
    fn iter(&self, n: usize) -> impl Iterator<Item = (usize, &[Real])> {
        self.samples
            .iter()
            .zip(self.posteriors.chunks_exact(n))
            .map(|(&s, p)| (s as usize, p))
    }
}

/// Every pose of the oracle's pool with its accepted observations.
#[derive(Debug)]
pub struct MaterialPool {
    samples: Vec<MaterialSample>,
    samples_per_m2: Real,
    n_materials: usize,
    min_likelihood: Real,
    aimed_targets: usize,
    aimed_poses: usize,
    /// Per pose (the start first, then the roadmap's nodes, then the aimed
    /// poses): clear under the rule, and the observations of its sweep
    /// (empty when not clear, except the start's, which a run always takes).
    per_pose: Vec<(bool, PoseObservations)>,
}

/// Whether belief `p` identifies a material.
fn identified(p: &[Real]) -> bool {
    p.iter().copied().fold(0.0, Real::max) >= IDENTIFIED_P
}

/// The facing class of a normal: its dominant axis and sign (0–5).
fn facing_class(n: &Vector3) -> u8 {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + u8::from(n[axis as usize] < 0.0)
}

/// The aimed poses' targets: the first sample (in sample order) of each
/// [`AIM_CELL_M`] cell and facing class, in order of first appearance.
fn aim_targets(samples: &[MaterialSample]) -> Vec<usize> {
    let mut seen: HashSet<([i64; 3], u8)> = HashSet::new();
    let mut out = Vec::new();
    for (i, s) in samples.iter().enumerate() {
        let cell = [0, 1, 2].map(|a| (s.point[a] / AIM_CELL_M).floor() as i64);
        if seen.insert((cell, facing_class(&s.normal.into_inner()))) {
            out.push(i);
        }
    }
    out
}

/// Where the scanner of `setup`'s robot can be at all, world frame
/// ([`robot::ReachBound`]; `None` when the arm has no bound).
fn scanner_reach(setup: &Setup) -> Option<robot::ReachBound> {
    let mount = setup.robot.scanner?;
    let bound = setup
        .robot
        .reach_bound(mount.link, &mount.link_from_scanner, REACH_SAMPLES)?;
    Some(robot::ReachBound {
        centres: bound
            .centres
            .iter()
            .map(|c| setup.world_from_base * c)
            .collect(),
        radius: bound.radius,
    })
}

/// Samples of the first joint's range in the scanner's reach bound.
const REACH_SAMPLES: usize = 360;

/// `false` when no configuration puts the scanner where its centre ray
/// meets `target` within the pose selection's constraints `pose` (range,
/// incidence, aim): the scanner's reach bound `reach` against the sector of
/// such scanner positions ([`blast::poses::tip_gap`]), within `ρ_min`.
/// Pose selection for such a target cannot succeed, whatever the map.
fn may_aim(
    reach: Option<&robot::ReachBound>,
    target: &plan::Target,
    pose: &plan::PoseConfig,
) -> bool {
    let n = target.normal.into_inner();
    reach.is_none_or(|reach| {
        reach.may_reach(pose.rho_min_m + 1e-9, |p| {
            blast::poses::tip_gap(
                p - target.centre,
                n,
                pose.phi_max_deg.to_radians(),
                pose.d_min_m,
                pose.d_max_m,
            )
        })
    })
}

impl MaterialPool {
    /// The pool of `setup` in `world` (a scene with materials) with the
    /// scanner `scanner`, the metric sampling `metrics` and the classifier
    /// `lrc` (trained on the scene's materials, in their order).
    pub fn new(
        setup: &Setup,
        world: &Arc<World>,
        scanner: &sensor::ScannerConfig,
        metrics: &MetricsConfig,
        lrc: &sensor::Lrc,
    ) -> Result<Self, SimError> {
        let rule = TruthRule::new(setup, world, metrics, "material oracle")?;
        let n_materials = setup.materials.len();
        if n_materials == 0 || lrc.materials.len() != n_materials {
            return Err(SimError::InvalidArgument {
                what: "material oracle".into(),
                message: format!(
                    "needs the scene's materials ({n_materials}) and an LRC trained on them ({})",
                    lrc.materials.len()
                ),
            });
        }
        let (samples, samples_per_m2) = material_samples(world, metrics, setup.regions.a2.aabb())?;
        if let Some(s) = samples.iter().find(|s| s.material >= n_materials) {
            return Err(SimError::InvalidArgument {
                what: "material oracle".into(),
                message: format!(
                    "a sample of material {} in a table of {n_materials}",
                    s.material
                ),
            });
        }

        // Stage Two's pose selection on the perfect map, from the start.
        let grid = rule.perfect_map()?;
        let selector =
            plan::PoseSelector::new(setup.stage.model().safety(), setup.config.pose.clone())?;
        let targets = aim_targets(&samples);
        let reach = scanner_reach(setup);
        let aimed: Vec<Option<Vec<Real>>> = targets
            .par_iter()
            .map(|&i| {
                let s = &samples[i];
                let target = plan::Target::new(s.point, s.normal.into_inner())?;
                if !may_aim(reach.as_ref(), &target, &setup.config.pose) {
                    return Ok(None);
                }
                let solution = selector.select(&grid, &target, &setup.start)?;
                Ok(solution.valid().then(|| solution.joints().to_vec()))
            })
            .collect::<Result<_, plan::PlanError>>()?;
        let aimed: Vec<Vec<Real>> = aimed.into_iter().flatten().collect();

        let mut poses: Vec<Vec<Real>> = vec![setup.start.clone()];
        poses.extend(setup.stage.model().roadmap().nodes().map(<[Real]>::to_vec));
        let aimed_poses = aimed.len();
        poses.extend(aimed);

        let coords: Vec<[Real; 3]> = samples
            .iter()
            .map(|s| [s.point.x, s.point.y, s.point.z])
            .collect();
        let observer = Observer {
            setup,
            world,
            scanner,
            lrc,
            samples: &samples,
            sample_tree: kiddo::ImmutableKdTree::new_from_slice(&coords),
            patch_m: explore::patch_radius_m(),
        };
        let clearance_m = setup.config.stage_two_clearance_m;
        let per_pose = poses
            .par_iter()
            .enumerate()
            .map(|(i, q)| {
                let clear = rule.sweep_clear(q, clearance_m)?;
                let observations = if i == 0 || clear {
                    observer.observe(q, i as u64)?
                } else {
                    PoseObservations::default()
                };
                Ok((clear, observations))
            })
            .collect::<Result<_, SimError>>()?;
        Ok(Self {
            samples,
            samples_per_m2,
            n_materials,
            min_likelihood: map::MaterialConfig::default().min_likelihood,
            aimed_targets: targets.len(),
            aimed_poses,
            per_pose,
        })
    }

    /// The A2 samples.
    pub fn samples(&self) -> &[MaterialSample] {
        &self.samples
    }

    /// Poses in the pool.
    pub fn poses(&self) -> usize {
        self.per_pose.len()
    }

    /// Targets the aimed poses were sought for, and the valid poses found.
    pub fn aimed(&self) -> (usize, usize) {
        (self.aimed_targets, self.aimed_poses)
    }

    /// The clear poses (the start counted when it is).
    pub fn clear(&self) -> Vec<usize> {
        (0..self.per_pose.len())
            .filter(|&i| self.per_pose[i].0)
            .collect()
    }

    /// Accepted observations of pose `i`'s sweep.
    pub fn observations(&self, i: usize) -> usize {
        self.per_pose.get(i).map_or(0, |p| p.1.samples.len())
    }

    /// The poses whose observations count: the start and the clear ones.
    fn usable(&self) -> Vec<usize> {
        (0..self.per_pose.len())
            .filter(|&i| i == 0 || self.per_pose[i].0)
            .collect()
    }

    fn share(&self, n: usize) -> Real {
        n as Real / self.samples.len().max(1) as Real
    }

    /// How many more samples pose `i`'s observations fused into `belief`
    /// identify (those it un-identifies taken off).
    fn gain(&self, belief: &[Real], i: usize) -> isize {
        let n = self.n_materials;
        let mut p = vec![0.0; n];
        let mut gain = 0isize;
        for (s, z) in self.per_pose[i].1.iter(n) {
            let before = &belief[s * n..(s + 1) * n];
            p.copy_from_slice(before);
            if bayes_update(&mut p, z, self.min_likelihood) {
                gain += isize::from(identified(&p)) - isize::from(identified(before));
            }
        }
        gain
    }

    /// Fuse pose `i`'s observations into `belief`.
    fn fuse(&self, belief: &mut [Real], i: usize) {
        let n = self.n_materials;
        for (s, z) in self.per_pose[i].1.iter(n) {
            bayes_update(&mut belief[s * n..(s + 1) * n], z, self.min_likelihood);
        }
    }

    /// The greedy choice: the start's sweep, then up to `viewpoints − 1`
    /// more, each the clear pose (not chosen before) whose observations
    /// identify the most more samples (ties to the lower index), stopping
    /// when none adds one. Returns the identified share after each
    /// viewpoint and the belief at the end (`n_t` per sample).
    pub fn greedy(&self, viewpoints: usize) -> (Vec<Real>, Vec<Real>) {
        let n = self.n_materials;
        let mut belief = vec![1.0 / n as Real; n * self.samples.len()];
        let count = |b: &[Real]| b.chunks_exact(n).filter(|p| identified(p)).count();
        self.fuse(&mut belief, 0);
        let mut curve = vec![self.share(count(&belief))];
        let mut chosen = vec![false; self.per_pose.len()];
        chosen[0] = true;
        let clear = self.clear();
        for _ in 1..viewpoints {
            let Some((best, g)) = clear
                .par_iter()
                .filter(|&&i| !chosen[i])
                .map(|&i| (i, self.gain(&belief, i)))
                .max_by_key(|&(i, g)| (g, std::cmp::Reverse(i)))
            else {
                break;
            };
            if g <= 0 {
                break;
            }
            chosen[best] = true;
            self.fuse(&mut belief, best);
            curve.push(self.share(count(&belief)));
        }
        (curve, belief)
    }

    /// Per sample: whether one observation of some usable pose identifies
    /// it on its own (from the uniform prior).
    pub fn identified_alone(&self) -> Vec<bool> {
        let n = self.n_materials;
        let mut out = vec![false; self.samples.len()];
        let mut p = vec![0.0; n];
        for i in self.usable() {
            for (s, z) in self.per_pose[i].1.iter(n) {
                if out[s] {
                    continue;
                }
                p.fill(1.0 / n as Real);
                out[s] = bayes_update(&mut p, z, self.min_likelihood) && identified(&p);
            }
        }
        out
    }

    /// The oracle as `run.json` gives it.
    pub fn oracle(&self) -> MaterialOracle {
        let n = self.n_materials;
        let (curve, belief) = self.greedy(MATERIAL_ORACLE_MAX_VIEWPOINTS);
        let mut identifiable = self.identified_alone();
        let (mut found, mut right) = (0usize, 0usize);
        for ((s, p), alone) in self
            .samples
            .iter()
            .zip(belief.chunks_exact(n))
            .zip(&mut identifiable)
        {
            if identified(p) {
                *alone = true;
                found += 1;
                right += usize::from(argmax(p) == s.material);
            }
        }
        MaterialOracle {
            rule: RULE.to_owned(),
            poses: self.per_pose.len(),
            clear_poses: self.clear().len(),
            aimed_poses: self.aimed_poses,
            samples: self.samples.len(),
            samples_per_m2: self.samples_per_m2,
            identifiable: self.share(identifiable.iter().filter(|&&b| b).count()),
            identified_after_viewpoints: curve,
            accuracy: (found > 0).then(|| right as Real / found as Real),
        }
    }
}

/// What a pose's sweep is simulated and classified with.
struct Observer<'a> {
    setup: &'a Setup,
    world: &'a Arc<World>,
    scanner: &'a sensor::ScannerConfig,
    lrc: &'a sensor::Lrc,
    samples: &'a [MaterialSample],
    /// The samples' points, indexed.
    sample_tree: kiddo::ImmutableKdTree<Real, 3>,
    patch_m: Real,
}

impl Observer<'_> {
    /// The accepted observations of the sweep from `q` (noise seeded by
    /// `seed`): for each sample in view of the sweep's scanner
    /// ([`in_view`]) with returns within the patch radius, the patch of
    /// returns around it from its side, classified. A sweep with no sample
    /// in view is not simulated.
    fn observe(&self, q: &[Real], seed: u64) -> Result<PoseObservations, SimError> {
        let mut out = PoseObservations::default();
        // Where the sweep's scans are taken from: the scanner at each of
        // its tilts (`hw::tilt_sweep` scans there).
        let setup = self.setup;
        let j = setup.stage.tilt_joint();
        let mut c = q.to_vec();
        let mut origins = Vec::new();
        for t in setup.stage.sweep_tilts(q) {
            c[j] = t;
            if let Some(pose) = setup.robot.scanner_pose(&c)? {
                origins.push(Point3::from(
                    (setup.world_from_base * pose).translation.vector,
                ));
            }
        }
        let Some(&mid) = origins.get(origins.len() / 2) else {
            return Ok(out);
        };
        let travel_m = origins
            .iter()
            .map(|o| (o - mid).norm())
            .fold(0.0, Real::max);
        let lrc = &self.lrc.config;
        let reach_m = lrc.max_range_m + travel_m;
        let mut candidates: Vec<usize> = self
            .sample_tree
            .within_unsorted::<kiddo::SquaredEuclidean>(&[mid.x, mid.y, mid.z], reach_m * reach_m)
            .iter()
            .map(|n| n.item as usize)
            .filter(|&k| in_view(&self.samples[k], &mid, travel_m, lrc))
            .collect();
        if candidates.is_empty() {
            return Ok(out);
        }
        candidates.sort_unstable();
        let sweep = simulated_sweep(setup, self.world, self.scanner, q, seed)?;
        let index = PatchIndex::new(sweep.points());
        for k in candidates {
            let s = &self.samples[k];
            // An empty patch is refused: not worth gathering.
            if index.nearest_m(&s.point) > self.patch_m {
                continue;
            }
            let obs = index.observation(&s.point, self.patch_m, Some(&s.normal));
            if let Ok(c) = self.lrc.classify(&obs) {
                out.samples.push(k as u32);
                out.posteriors.extend_from_slice(&c.posterior);
            }
        }
        Ok(out)
    }
}

/// Whether sample `s` is in view of a sweep whose scanner positions lie
/// within `travel_m` of `mid`, within the LRC's constraints `lrc`: its own
/// surface faces `mid`, at a range from `mid` within `[d_min, d_max]`
/// widened by the travel, and an incidence below `φ_max` widened by the
/// angle the travel subtends. The LRC checks range and incidence on the
/// plane it fits to the patch from the patch's mean origin; this asks the
/// same of the sample's own surface, so that an observation counts for a
/// sample only when its own surface is seen within the constraints (a
/// sample on a 6 mm edge is not identified by a patch of the face beside
/// it).
fn in_view(s: &MaterialSample, mid: &Point3, travel_m: Real, lrc: &LrcConfig) -> bool {
    let to_scanner = mid - s.point;
    let range_m = to_scanner.norm();
    if range_m > lrc.max_range_m + travel_m || range_m < lrc.min_range_m - travel_m {
        return false;
    }
    let cos = to_scanner.dot(&s.normal) / range_m.max(1e-12);
    if cos <= 0.0 {
        return false;
    }
    let sway_deg = if travel_m >= range_m {
        90.0
    } else {
        (travel_m / range_m).asin().to_degrees()
    };
    cos.min(1.0).acos().to_degrees() < lrc.max_incidence_deg + sway_deg
}

/// The cache file: the inputs the oracle was made for, and the oracle.
#[derive(Serialize, Deserialize)]
struct CacheFile {
    format: u32,
    inputs: String,
    oracle: MaterialOracle,
}

/// What the oracle depends on, as text: the scenario with what does not
/// matter to it left out (names, the `[explore]` table), the parameters of
/// the run it does depend on (the roadmap's, the planning voxel, Stage
/// Two's clearance and pose selection, the sweep), the LRC's constraints,
/// training and cache format, and the oracle's own constants. A scene's
/// mesh file enters by its path, not its content.
fn oracle_inputs(loaded: &LoadedScenario, setup: &Setup) -> Result<String, SimError> {
    let mut s = loaded.standalone();
    s.name.clear();
    s.description.clear();
    s.initial_segments.clear();
    s.explore = None;
    let c = &setup.config;
    Ok(format!(
        "plan = {:?}\nplanning_voxel_m = {:?}\nstage_two_clearance_m = {:?}\npose = {:?}\n\
         sweep = {:?}\nlrc = {:?}\ntraining = {:?}\nlrc_format = {}\nlrc_seed = 0\n\
         samples_per_m2 = {:?}\naim_cell_m = {:?}\nmax_viewpoints = {}\n{}",
        c.plan,
        c.planning_voxel_m,
        c.stage_two_clearance_m,
        c.pose,
        c.sweep,
        explore::lrc_config(&c.pose),
        explore::lrc::training_config(),
        sensor::classifier::LRC_CACHE_FORMAT,
        MATERIAL_SAMPLES_PER_M2,
        AIM_CELL_M,
        MATERIAL_ORACLE_MAX_VIEWPOINTS,
        s.to_toml()?
    ))
}

/// The oracle in `cache` when that file holds one made for `inputs`.
fn cached_oracle(cache: Option<&Path>, inputs: &str) -> Option<MaterialOracle> {
    let text = std::fs::read(cache?).ok()?;
    let file = serde_json::from_slice::<CacheFile>(&text).ok()?;
    (file.format == CACHE_FORMAT && file.inputs == inputs).then_some(file.oracle)
}

/// The material oracle computed: the LRC trained with seed 0 (or loaded
/// from `lrc_cache`), the pool, the oracle; written to `cache` with its
/// `inputs`.
fn compute_oracle(
    setup: &Setup,
    world: &Arc<World>,
    metrics: &MetricsConfig,
    caches: (Option<&Path>, Option<&Path>),
    inputs: String,
) -> Result<MaterialOracle, SimError> {
    let (cache, lrc_cache) = caches;
    let (lrc, _) = explore::train_lrc(
        &setup.materials,
        &setup.scanner,
        &setup.config.pose,
        0,
        lrc_cache,
    )?;
    let pool = MaterialPool::new(setup, world, &setup.scanner, metrics, &lrc)?;
    let oracle = pool.oracle();
    if let Some(path) = cache {
        write_cache(path, inputs, &oracle)?;
    }
    Ok(oracle)
}

/// Write `oracle`, made for `inputs`, to the cache file `path` (whole or
/// not at all).
fn write_cache(path: &Path, inputs: String, oracle: &MaterialOracle) -> Result<(), SimError> {
    let file = CacheFile {
        format: CACHE_FORMAT,
        inputs,
        oracle: oracle.clone(),
    };
    let text = serde_json::to_vec(&file).map_err(|e| SimError::InvalidArgument {
        what: path.display().to_string(),
        message: format!("cannot encode the material oracle: {e}"),
    })?;
    record::output::replace_file(path, &text)?;
    Ok(())
}

/// The material oracle of the scenario `loaded` set up as `setup` in
/// `world`: read from `cache` when that file was made for the same inputs,
/// else computed (its LRC loaded from or written to `lrc_cache`, which
/// must be a cache of seed 0's LRC) and written there. The second value says
/// whether it was loaded.
pub fn material_oracle(
    loaded: &LoadedScenario,
    setup: &Setup,
    world: &Arc<World>,
    cache: Option<&Path>,
    lrc_cache: Option<&Path>,
) -> Result<(MaterialOracle, bool), SimError> {
    let inputs = oracle_inputs(loaded, setup)?;
    if let Some(oracle) = cached_oracle(cache, &inputs) {
        return Ok((oracle, true));
    }
    let metrics = &loaded.scenario.metrics;
    let oracle = compute_oracle(setup, world, metrics, (cache, lrc_cache), inputs)?;
    Ok((oracle, false))
}

/// The material oracle's cache beside the coverage oracle's `coverage`
/// cache: the same folder, `<its stem>-materials.json`
/// (`surveyor-oracle-bridge1.json` → `surveyor-oracle-bridge1-materials.json`).
pub fn cache_beside(coverage: &Path) -> PathBuf {
    let stem = coverage
        .file_stem()
        .map_or_else(|| "oracle".into(), |s| s.to_string_lossy().into_owned());
    coverage.with_file_name(format!("{stem}-materials.json"))
}

/// The material oracle of [`material_oracle`], computed beside the caller
/// as the coverage oracle's [`crate::oracle::OracleJob`] is: read at once
/// when `cache` holds it, else computed on a thread of its own (a rayon
/// pool of its own, at idle priority) until [`MaterialOracleJob::finish`]
/// waits for it.
#[derive(Debug)]
pub struct MaterialOracleJob(JobState);

#[derive(Debug)]
enum JobState {
    Ready(MaterialOracle),
    Running(std::thread::JoinHandle<Result<MaterialOracle, SimError>>),
}

impl MaterialOracleJob {
    /// Read the oracle of `loaded` set up as `setup` in `world` from
    /// `cache`, or start computing it (a copy of `setup` goes to the
    /// thread; the LRC through `lrc_cache`, a cache of seed 0's LRC). Fails
    /// when the scenario cannot be described for the cache or the thread
    /// cannot start.
    pub fn start(
        loaded: &LoadedScenario,
        setup: &Setup,
        world: &Arc<World>,
        cache: Option<&Path>,
        lrc_cache: Option<&Path>,
    ) -> Result<Self, SimError> {
        let inputs = oracle_inputs(loaded, setup)?;
        if let Some(oracle) = cached_oracle(cache, &inputs) {
            return Ok(Self(JobState::Ready(oracle)));
        }
        let metrics = loaded.scenario.metrics;
        let (setup, world) = (setup.clone(), Arc::clone(world));
        let cache = cache.map(Path::to_path_buf);
        let lrc_cache = lrc_cache.map(Path::to_path_buf);
        let threads = rayon::current_num_threads();
        let handle = std::thread::Builder::new()
            .name("material-oracle".into())
            .spawn(move || {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .thread_name(|i| format!("material-oracle-{i}"))
                    .start_handler(|_| idle_priority())
                    .build()
                    .map_err(|e| SimError::InvalidArgument {
                        what: "material oracle".into(),
                        message: format!("cannot start its thread pool: {e}"),
                    })?;
                pool.install(|| {
                    compute_oracle(
                        &setup,
                        &world,
                        &metrics,
                        (cache.as_deref(), lrc_cache.as_deref()),
                        inputs,
                    )
                })
            })
            .map_err(|e| SimError::InvalidArgument {
                what: "material oracle".into(),
                message: format!("cannot start its thread: {e}"),
            })?;
        Ok(Self(JobState::Running(handle)))
    }

    /// The oracle, once computed (and written to the cache).
    pub fn finish(self) -> Result<MaterialOracle, SimError> {
        match self.0 {
            JobState::Ready(oracle) => Ok(oracle),
            // A panic in the oracle is a bug: it goes on as if the oracle
            // had run on this thread.
            JobState::Running(handle) => handle
                .join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p)),
        }
    }
}

/// Per sample: the index of its run disc among `discs` (see
/// [`record::explore::MaterialIdentification`]): the nearest disc whose
/// centre lies within its radius plus [`RUN_DISC_MARGIN_M`] of the sample
/// and whose seen side (`facing`, else its normal) has a cosine above
/// [`RUN_DISC_MIN_COS`] with the sample's normal (ties: the lower index).
pub fn run_discs(samples: &[MaterialSample], d: &explore::DiscMap) -> Vec<Option<usize>> {
    if d.discs.is_empty() {
        return vec![None; samples.len()];
    }
    let coords: Vec<[Real; 3]> = d
        .discs
        .iter()
        .map(|c| [c.centre.x, c.centre.y, c.centre.z])
        .collect();
    let tree: kiddo::ImmutableKdTree<Real, 3> = kiddo::ImmutableKdTree::new_from_slice(&coords);
    let largest = d.discs.iter().map(|c| c.radius_m).fold(0.0, Real::max) + RUN_DISC_MARGIN_M;
    samples
        .par_iter()
        .map(|s| {
            let p = s.point;
            tree.within_unsorted::<kiddo::SquaredEuclidean>(&[p.x, p.y, p.z], largest * largest)
                .iter()
                .map(|n| n.item as usize)
                .filter(|&k| {
                    let disc = &d.discs[k];
                    let seen = d
                        .facing
                        .get(k)
                        .copied()
                        .unwrap_or_else(|| disc.normal.into_inner());
                    (disc.centre - p).norm() <= disc.radius_m + RUN_DISC_MARGIN_M
                        && seen.dot(&s.normal) > RUN_DISC_MIN_COS * seen.norm()
                })
                .map(|k| ((d.discs[k].centre - p).norm(), k))
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
                .map(|(_, k)| k)
        })
        .collect()
}

/// The run's identification on the oracle's `samples` beside `oracle`:
/// each sample takes its run disc's posterior ([`run_discs`]); the discs
/// with their centre in `a2` at `p ≥ 0.8` are counted; Stage Two's
/// viewpoints are the run's records of stage 2.
pub fn compare(
    oracle: MaterialOracle,
    samples: &[MaterialSample],
    run: &ExploreRun,
    a2: &map::RegionBox,
) -> MaterialIdentification {
    let d = &run.discs;
    let (mut found, mut right) = (0usize, 0usize);
    // Per identified sample: the viewpoint since which its disc has been.
    let mut since = Vec::new();
    for (s, disc) in samples.iter().zip(run_discs(samples, d)) {
        if let Some(k) = disc
            && let Some(p) = d.posterior.get(k)
            && !p.is_empty()
            && identified(p)
        {
            found += 1;
            right += usize::from(argmax(p) == s.material);
            since.push(d.identified_at.get(k).copied().flatten());
        }
    }
    // The share at Stage Two's start (Stage One's last row) and after each
    // of its viewpoints.
    let last_one = run.viewpoints.iter().rposition(|v| v.stage == 1);
    let rows = match (last_one, &run.stage_two_termination) {
        (Some(i), Some(_)) => &run.viewpoints[i..],
        _ => &[][..],
    };
    let total = samples.len().max(1) as Real;
    let curve = if d.identified_at.len() == d.discs.len() && !rows.is_empty() {
        rows.iter()
            .map(|v| since.iter().filter(|s| s.is_some_and(|k| k <= v.k)).count() as Real / total)
            .collect()
    } else {
        Vec::new()
    };
    let discs_identified = d
        .discs
        .iter()
        .zip(&d.posterior)
        .filter(|(disc, p)| a2.contains(&disc.centre) && !p.is_empty() && identified(p))
        .count();
    let stage_two = run.viewpoints.iter().filter(|v| v.stage == 2).count();
    MaterialIdentification::new(
        oracle,
        found as Real / total,
        (found > 0).then(|| right as Real / found as Real),
        discs_identified,
        stage_two,
        curve,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(material: usize) -> MaterialSample {
        MaterialSample {
            point: Point3::origin(),
            normal: UnitVector3::new_normalize(Vector3::z()),
            material,
        }
    }

    /// A pose of a hand-made pool: clear or not, and its observations
    /// (sample, posterior over two materials).
    type HandPose = (bool, Vec<(u32, [Real; 2])>);

    /// A pool of two materials over `samples`.
    fn pool(samples: Vec<MaterialSample>, poses: Vec<HandPose>) -> MaterialPool {
        MaterialPool {
            samples,
            samples_per_m2: 400.0,
            n_materials: 2,
            min_likelihood: 1e-3,
            aimed_targets: 0,
            aimed_poses: 0,
            per_pose: poses
                .into_iter()
                .map(|(clear, obs)| {
                    (
                        clear,
                        PoseObservations {
                            samples: obs.iter().map(|o| o.0).collect(),
                            posteriors: obs.iter().flat_map(|o| o.1).collect(),
                        },
                    )
                })
                .collect(),
        }
    }

    /// By hand: the start identifies s0 (0.9); pose 2 identifies s1 (0.9),
    /// pose 1 only brings s1 and s2 to 0.7; pose 3 identifies s3 but
    /// un-identifies s0 (net 0); pose 4 would identify s2 but is not clear.
    /// The greedy takes the start, then pose 2, then stops (no net gain);
    /// the identifiable samples are s0, s1 (greedy) and s3 (pose 3 alone).
    #[test]
    fn the_greedy_takes_net_gains_and_the_identifiable_add_single_views() {
        let p = pool(
            vec![sample(0), sample(1), sample(0), sample(0)],
            vec![
                (false, vec![(0, [0.9, 0.1])]),
                (true, vec![(1, [0.3, 0.7]), (2, [0.7, 0.3])]),
                (true, vec![(1, [0.1, 0.9])]),
                (true, vec![(0, [0.1, 0.9]), (3, [0.95, 0.05])]),
                (false, vec![(2, [0.99, 0.01])]),
            ],
        );
        let (curve, belief) = p.greedy(40);
        assert_eq!(curve, vec![0.25, 0.5]);
        assert!(curve.windows(2).all(|w| w[1] > w[0]));
        assert!((belief[2] - 0.1).abs() < 1e-3, "{belief:?}");
        assert_eq!(p.identified_alone(), vec![true, true, false, true]);
        let o = p.oracle();
        assert_eq!(o.identifiable, 0.75);
        assert_eq!(o.identified_after_viewpoints, curve);
        assert_eq!(o.accuracy, Some(1.0));
        assert_eq!((o.poses, o.clear_poses, o.samples), (5, 3, 4));
        // One viewpoint only: the start's.
        assert_eq!(p.greedy(1).0, vec![0.25]);
    }

    /// A greedy curve over random observations never falls, each step adds
    /// at least one sample, and it ends within the identifiable share.
    #[test]
    fn the_greedy_curve_rises_and_stays_within_the_identifiable_share() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let n = 60;
        let poses = (0..30)
            .map(|i| {
                let obs = (0..20)
                    .map(|_| {
                        let a: Real = rng.random_range(0.0..1.0);
                        (rng.random_range(0..n as u32), [a, 1.0 - a])
                    })
                    .collect();
                (i % 4 != 3, obs)
            })
            .collect();
        let p = pool((0..n).map(|i| sample(i % 2)).collect(), poses);
        let o = p.oracle();
        let curve = &o.identified_after_viewpoints;
        assert!(curve.len() > 2, "{curve:?}");
        assert!(
            curve
                .windows(2)
                .all(|w| w[1] >= w[0] + 1.0 / n as Real - 1e-12)
        );
        assert!(curve.last().copied().unwrap_or(0.0) <= o.identifiable);
    }

    /// The cache holds the oracle of its inputs: read back equal for the
    /// same inputs, not for others, nor from a file that is not a cache.
    #[test]
    fn the_cache_round_trips_for_its_inputs_only() {
        let dir = tempfile::tempdir().unwrap();
        let path = cache_beside(&dir.path().join("surveyor-oracle-x.json"));
        assert_eq!(path, dir.path().join("surveyor-oracle-x-materials.json"));
        let oracle = pool(vec![sample(0)], vec![(true, vec![(0, [0.9, 0.1])])]).oracle();
        assert_eq!(cached_oracle(Some(&path), "inputs"), None);
        write_cache(&path, "inputs".into(), &oracle).unwrap();
        assert_eq!(cached_oracle(Some(&path), "inputs"), Some(oracle));
        assert_eq!(cached_oracle(Some(&path), "other inputs"), None);
        assert_eq!(cached_oracle(None, "inputs"), None);
        std::fs::write(&path, "{").unwrap();
        assert_eq!(cached_oracle(Some(&path), "inputs"), None);
    }

    /// A sample takes the nearest disc within its radius plus 10 mm whose
    /// seen side agrees with its normal: not the back of a thin wall, not a
    /// disc too far.
    #[test]
    fn samples_take_the_nearest_agreeing_disc() {
        let up = UnitVector3::new_normalize(Vector3::z());
        let disc = |x: Real, z: Real| map::Disc {
            centre: Point3::new(x, 0.0, z),
            normal: up,
            radius_m: 0.04,
            points: 10,
        };
        let d = explore::DiscMap {
            // The back of a 4 mm wall (seen from below), a disc 45 mm away,
            // one 30 mm away, one 60 mm away.
            discs: vec![
                disc(0.0, -0.004),
                disc(0.045, 0.0),
                disc(0.03, 0.0),
                disc(0.06, 0.0),
            ],
            facing: vec![-Vector3::z(), Vector3::z(), Vector3::z(), Vector3::z()],
            ..explore::DiscMap::default()
        };
        let s = MaterialSample {
            point: Point3::origin(),
            normal: up,
            material: 0,
        };
        let far = MaterialSample {
            point: Point3::new(-0.06, 0.0, 0.0),
            ..s
        };
        assert_eq!(run_discs(&[s, far], &d), vec![Some(2), None]);
        assert_eq!(run_discs(&[s], &explore::DiscMap::default()), vec![None]);
    }

    #[test]
    fn aim_targets_take_one_sample_per_cell_and_facing() {
        let at = |x: Real, n: Vector3| MaterialSample {
            point: Point3::new(x, 0.01, 0.01),
            normal: UnitVector3::new_normalize(n),
            material: 0,
        };
        let samples = [
            at(0.01, Vector3::z()),
            at(0.1, Vector3::z()),
            at(0.1, -Vector3::z()),
            at(0.2, Vector3::new(0.1, 0.0, 1.0)),
            at(0.14, Vector3::x()),
        ];
        assert_eq!(aim_targets(&samples), vec![0, 2, 3, 4]);
    }
}
