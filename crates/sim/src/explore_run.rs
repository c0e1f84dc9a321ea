//! AXBAM Stage One in a simulated world (A§3.2, Fig. 6.3 left): sweep from
//! the start pose, then decide, move, sweep and integrate until the 1 % rule
//! (A§3.2.4) or the budget, through the hardware traits ([`Arm`],
//! [`LineScanner`](crate::LineScanner)) so a real arm and scanner take the simulation's place.
//!
//! Every executed motion (paths and sweeps) is checked twice: against the
//! map of that moment at configurations no farther apart than half the
//! planner's step (`dist(Q) ≤ 1` counts as an unsafe configuration), and
//! against the ground-truth scene with the robot's collision shapes.

use crate::metrics::{CoverageReport, CoverageTracker};
use crate::rig::Arm;
use crate::safety::{min_clearance, motion_contacts, smallest_link_radius};
use crate::scenario::LoadedScenario;
use crate::{SimError, SimRig, tilt_sweep};
use explore::{ExploreConfig, StageOne, Termination};
use geom::{Isometry3, Real};
use map::{TsdfConfig, TsdfMap};
use plan::{CacheOutcome, CspaceModel, PlanConfig, Safety};
use robot::Robot;
use scene::{Scene, TriMesh};
use sensor::{Scanner, SweepPoint};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// How to run.
#[derive(Clone, Debug, Default)]
pub struct ExploreOptions {
    /// Seed of the scanner noise.
    pub seed: u64,
    /// Override of the Stage One viewpoint budget.
    pub max_viewpoints: Option<usize>,
    /// Where the C-space model is cached (`None`: built every run).
    pub cspace_cache: Option<PathBuf>,
    /// Stage One parameters instead of the scenario's `[explore]` table
    /// (`None`: the scenario's, or the defaults).
    pub config: Option<ExploreConfig>,
    /// TSDF of the output mesh.
    pub tsdf: TsdfConfig,
    /// Record wall-clock times (off: the time columns are 0, so outputs are
    /// the same byte for byte for the same inputs).
    pub timings: bool,
    /// Write a checkpoint here after every viewpoint.
    pub checkpoint: Option<PathBuf>,
    /// Continue the run recorded in `checkpoint` (which must exist).
    pub resume: bool,
    /// Run Stage Two after Stage One.
    pub stage_two: bool,
}

/// What a checkpoint holds: enough to rebuild the run's state by replaying
/// its viewpoints' sweeps (the simulation is seeded per viewpoint, so the
/// same sweeps come back) and to continue as if never stopped.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Checkpoint {
    format: u32,
    /// FNV-1a 64 of the checkpoint's JSON with this field 0: a checkpoint
    /// edited by hand is refused (its records are replayed without audit).
    checksum: u64,
    scenario: String,
    /// The scenario as run (`scenario.toml`'s text, the robot included).
    scenario_toml: String,
    /// Whether Stage Two follows Stage One.
    stage_two: bool,
    seed: u64,
    config: ExploreConfig,
    sweep: sensor::SweepConfig,
    viewpoints: Vec<ViewpointRecord>,
    collisions: usize,
    unsafe_configurations: Vec<UnsafeConfiguration>,
    min_clearance_m: Real,
    /// Stage Two: the discs already tried as targets, ascending.
    #[serde(default)]
    stage_two_tried: Vec<usize>,
}

/// Version of the checkpoint format (2: checksum, scenario text, stages).
const CHECKPOINT_FORMAT: u32 = 2;

/// FNV-1a, 64 bits: a checksum that is the same on every platform.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    })
}

impl Checkpoint {
    /// The checksum of `self` (its own `checksum` field taken as 0).
    fn digest(&self) -> Result<u64, serde_json::Error> {
        let text = serde_json::to_string(&Self {
            checksum: 0,
            ..self.clone()
        })?;
        Ok(fnv1a(text.as_bytes()))
    }

    fn write(&self, path: &Path) -> Result<(), SimError> {
        let err = |e: &dyn std::fmt::Display| SimError::InvalidArgument {
            what: path.display().to_string(),
            message: format!("cannot write the checkpoint: {e}"),
        };
        let sealed = Self {
            checksum: self.digest().map_err(|e| err(&e))?,
            ..self.clone()
        };
        let text = serde_json::to_string(&sealed).map_err(|e| err(&e))?;
        let tmp = path.with_extension("tmp");
        std::fs::write(&tmp, text).map_err(|e| err(&e))?;
        std::fs::rename(&tmp, path).map_err(|e| err(&e))
    }

    fn read(path: &Path) -> Result<Self, SimError> {
        let err = |message: String| SimError::InvalidArgument {
            what: path.display().to_string(),
            message,
        };
        let text = std::fs::read(path)
            .map_err(|e| err(format!("cannot read the checkpoint to resume from: {e}")))?;
        let rerun = "; run again without --resume";
        // The format first: an older checkpoint lacks today's fields.
        let format = serde_json::from_slice::<serde_json::Value>(&text)
            .ok()
            .and_then(|v| v.get("format").and_then(serde_json::Value::as_u64));
        if let Some(f) = format.filter(|f| *f != u64::from(CHECKPOINT_FORMAT)) {
            return Err(err(format!(
                "checkpoint format {f} (this version reads {CHECKPOINT_FORMAT}){rerun}"
            )));
        }
        let c: Self = serde_json::from_slice(&text).map_err(|e| {
            err(format!(
                "not a checkpoint of `surveyor explore` ({e}){rerun}"
            ))
        })?;
        match c.digest() {
            Ok(d) if d == c.checksum => Ok(c),
            _ => Err(err(format!(
                "the checkpoint was changed after it was written (its checksum does not match){rerun}"
            ))),
        }
    }
}

/// The noise seed of viewpoint `k`'s sweep.
fn viewpoint_seed(seed: u64, k: usize) -> u64 {
    seed ^ 0xa076_1d64_78bd_642f_u64.wrapping_mul(k as u64 + 1)
}

/// One viewpoint of the run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewpointRecord {
    /// 0 for the start pose's sweep.
    pub k: usize,
    /// 1 (Stage One).
    pub stage: u8,
    /// Joints at the viewpoint.
    pub joints: Vec<Real>,
    /// `[f1, f2, f3, f4]` of the chosen candidate (`None` at the start).
    pub f: Option<[Real; 4]>,
    /// Stage Two: the disc aimed at (index into the disc map).
    pub target_disc: Option<usize>,
    /// `H3` over every disc voxel after the viewpoint (eq. 4.17): every Stage
    /// Two row, and Stage One's last, once Stage One's sweeps are classified
    /// on its map (Stage Two's baseline); `None` on the other rows.
    pub h3: Option<Real>,
    /// Unweighted H1 (eq. 4.10) after the sweep.
    pub h1: Real,
    /// Weighted H1 (eq. 4.11) after the sweep.
    pub h1_weighted: Real,
    /// H2 (eq. 4.14) after the sweep.
    pub h2: Real,
    /// Weighted H1 the decision predicted would remain (f1).
    pub predicted_h1_weighted: Option<Real>,
    /// Safe candidates scored, Pareto front size, candidates dropped as
    /// unreachable.
    pub candidates: usize,
    /// Size of the Pareto front.
    pub front: usize,
    /// Chosen candidates without a safe path.
    pub unreachable: usize,
    /// Unknown voxels the sweep was predicted to reveal.
    pub predicted_revealed: usize,
    /// Voxels the sweep actually made known.
    pub revealed: u64,
    /// Share of the true surfaces in A1 covered by the points so far (scenes
    /// with a ground truth).
    pub coverage_a1: Option<Real>,
    /// Σ|Δq| of the motion to the viewpoint, radians.
    pub joint_travel: Real,
    /// Waypoints of the motion (2 for a direct one).
    pub waypoints: usize,
    /// The motion's waypoints (joints), from the previous viewpoint's pose
    /// to this one's (empty at the start).
    #[serde(default)]
    pub path: Vec<Vec<Real>>,
    /// Stage One: `[f1, f2, f3, f4]` of every candidate the decision scored,
    /// in its order, and whether it was on the first Pareto front (Fig. 6.6).
    #[serde(default)]
    pub scored: Vec<ScoredCandidate>,
    /// Wall times, ms (0 when timings are off).
    pub decision_ms: Real,
    /// Choice and path planning, ms.
    pub plan_ms: Real,
    /// Sweep (simulated scanning), ms.
    pub sweep_ms: Real,
    /// Integration into the planning grid and the TSDF, ms.
    pub integrate_ms: Real,
}

/// A Stage One choice waiting for its sweep: the choice, every candidate
/// scored, the front size, unreachable choices, decision and plan ms.
type Pending = (
    explore::Choice,
    Vec<ScoredCandidate>,
    usize,
    usize,
    Real,
    Real,
);

/// One candidate of a Stage One decision, as scored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScoredCandidate {
    /// `[f1, f2, f3, f4]`.
    pub f: [Real; 4],
    /// On the Pareto front of the decision's first choice.
    pub front: bool,
}

/// A configuration found unsafe along an executed motion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UnsafeConfiguration {
    /// Viewpoint whose motion or sweep it was on.
    pub viewpoint: usize,
    /// The joints.
    pub joints: Vec<Real>,
    /// Its `dist(Q)` against the map of that moment.
    pub dist: Real,
}

/// The whole run.
#[derive(Clone, Debug)]
pub struct ExploreRun {
    /// Scenario name.
    pub scenario: String,
    /// Per viewpoint.
    pub viewpoints: Vec<ViewpointRecord>,
    /// Why Stage One stopped.
    pub termination: Termination,
    /// Why Stage Two stopped (`None` when it did not run).
    pub stage_two_termination: Option<String>,
    /// Ground-truth contacts along executed motions.
    pub collisions: usize,
    /// Configurations with `dist(Q) ≤ 1` along executed motions.
    pub unsafe_configurations: Vec<UnsafeConfiguration>,
    /// Smallest ground-truth clearance of the links at the viewpoints and
    /// along motions' checked configurations, metres (search radius 0.5 m).
    pub min_clearance_m: Real,
    /// `(H1 weighted, H2)` before the first sweep.
    pub initial_information: (Real, Real),
    /// How the C-space model was obtained.
    pub cspace: String,
    /// Every measured point.
    pub cloud: Vec<SweepPoint>,
    /// The TSDF mesh.
    pub mesh: TriMesh,
    /// Coverage of the true surfaces in A1, A2, A3 (scenes with a ground truth).
    pub coverage: Option<[CoverageReport; 3]>,
    /// Per region A1, A2, A3: the samples observable from some collision-free
    /// roadmap pose's scanner position, and of those the covered ones (see
    /// [`CoverageTracker::set_observable_from`]).
    pub observable: Vec<(usize, usize)>,
    /// The map products of Stage One (A§5.2–5.3): the mesh's Scale-Like
    /// Discs and their segments.
    pub discs: DiscMap,
    /// The planning grid at the end of the run (occupancy at
    /// `planning_voxel_m`, with H1 and H2): what later plans, such as blast
    /// plans, must respect.
    pub grid: map::OccupancyGrid,
    /// Wall time of the whole run, seconds (0 when timings are off).
    pub wall_s: Real,
}

/// Scale-Like Discs of the TSDF mesh (A§5.2, Table 6.1: μ = 0.04 m, n_min =
/// 8), each with the viewpoint that saw it (the viewpoint of the nearest
/// measured point) and its segment (A§5.3, with the pose graph τq over those
/// viewpoints' joints).
#[derive(Clone, Debug, Default)]
pub struct DiscMap {
    /// The discs.
    pub discs: Vec<map::Disc>,
    /// Per disc: the viewpoint (index into `viewpoints`) that saw it.
    pub viewpoint: Vec<usize>,
    /// Per disc: its segment (index into `segments`).
    pub segment: Vec<usize>,
    /// The segments: disc indices, ascending.
    pub segments: Vec<Vec<map::DiscId>>,
    /// Per disc: the material of the nearest true surface within 0.05 m
    /// (index into the scene's table; scenes with a ground truth).
    pub true_material: Vec<Option<usize>>,
    /// The scene's material names.
    pub material_names: Vec<String>,
    /// Per disc: the material posterior (one probability per material of
    /// the scene, uniform until an LRC observation updates it; empty for
    /// worlds without materials).
    pub posterior: Vec<Vec<Real>>,
    /// Per disc: the material information remaining `H3` (eq. 4.16, summed
    /// over the disc's voxels).
    pub h3: Vec<Real>,
    /// Per disc: LRC observations that updated it.
    pub observations: Vec<usize>,
    /// `H3` over every disc voxel (eq. 4.17; a voxel shared by two discs
    /// counts once), when materials were identified.
    pub h3_total: Option<Real>,
}

impl DiscMap {
    /// The share of the discs with at least one LRC observation and a known
    /// true material whose most probable material is the true one (`None`
    /// without such discs).
    pub fn material_accuracy(&self) -> Option<Real> {
        let mut n = 0usize;
        let mut right = 0usize;
        for ((p, t), o) in self
            .posterior
            .iter()
            .zip(&self.true_material)
            .zip(&self.observations)
        {
            let (Some(t), true) = (t, *o > 0) else {
                continue;
            };
            n += 1;
            let best = p
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))
                .map(|(i, _)| i);
            right += usize::from(best == Some(*t));
        }
        (n > 0).then(|| right as Real / n as Real)
    }
}

/// Material identification with the LRC (A§3.3, App. B): every disc is
/// targeted in every sweep whose scanner passed within the LRC's range of it;
/// the returns within the training patch radius of its centre form an
/// observation, and each one the LRC accepts (range, incidence, enough
/// points) updates the belief of the disc's voxels (eq. 4.15). The LRC is
/// trained on the scene's materials with the simulator's scanner model. Stage
/// One's sweeps identify some materials this way ("some surfaces also had
/// their material-types identified", A§3.3); Stage Two aims at the discs
/// with the most information left.
struct Materials {
    lrc: sensor::Lrc,
    belief: map::MaterialBelief,
    /// Per disc: whether the mapped surface within the LRC's patch radius of
    /// its centre is flat enough for the LRC (see [`flat_patches`]).
    flat: Vec<bool>,
    patch_m: Real,
    reach_m: Real,
}

impl Materials {
    /// `None` for a scene without materials or a map without discs.
    fn new(
        d: &mut DiscMap,
        mesh: &TriMesh,
        pose: &plan::PoseConfig,
        scene: &Scene,
        scanner: &sensor::ScannerConfig,
        seed: u64,
    ) -> Result<Option<Self>, SimError> {
        use sensor::classifier::{LrcConfig, TrainingConfig};
        d.observations = vec![0; d.discs.len()];
        let materials = scene.materials();
        if materials.is_empty() || d.discs.is_empty() {
            return Ok(None);
        }
        // The LRC's validity domain is Stage Two's constraints (Table 6.1:
        // φ_max, d_min, d_max), read from one place, `[explore.pose]`.
        let config = LrcConfig {
            min_range_m: pose.d_min_m,
            max_range_m: pose.d_max_m,
            max_incidence_deg: pose.phi_max_deg,
            ..LrcConfig::default()
        };
        let training = TrainingConfig {
            observations_per_material: LRC_TRAINING_OBSERVATIONS,
            ..TrainingConfig::default()
        };
        let lrc = sensor::Lrc::train(config, &training, materials, scanner, seed).map_err(|e| {
            SimError::InvalidArgument {
                what: "material classifier".into(),
                message: e.to_string(),
            }
        })?;
        let mut belief = map::MaterialBelief::new(map::MaterialConfig {
            n_materials: materials.len(),
            ..map::MaterialConfig::default()
        })?;
        for disc in &d.discs {
            belief.insert_disc(disc);
        }
        let patch_m = training.patch_radius_m;
        let flat = flat_patches(
            &d.discs,
            &mesh.vertices,
            patch_m,
            lrc.plane_rms_limit_m * config.max_plane_rms_ratio,
        );
        Ok(Some(Self {
            lrc,
            belief,
            flat,
            patch_m,
            reach_m: config.max_range_m + patch_m,
        }))
    }

    /// Classify every disc in reach of `sweep` and update the beliefs.
    fn observe(&mut self, d: &mut DiscMap, sweep: &sensor::Sweep) -> Result<(), SimError> {
        use rayon::prelude::*;
        let pts = sweep.points();
        if pts.is_empty() {
            return Ok(());
        }
        let coords: Vec<[Real; 3]> = pts
            .iter()
            .map(|p| [p.point.x, p.point.y, p.point.z])
            .collect();
        let tree: kiddo::ImmutableKdTree<Real, 3> = kiddo::ImmutableKdTree::new_from_slice(&coords);
        let origin = pts[pts.len() / 2].origin;
        let (lrc, patch, reach) = (&self.lrc, self.patch_m, self.reach_m);
        let results: Vec<(usize, Vec<Real>)> = d
            .discs
            .par_iter()
            .enumerate()
            .filter(|(_, disc)| (disc.centre - origin).norm() <= reach)
            .filter_map(|(i, disc)| {
                let obs = patch_observation(pts, &tree, &disc.centre, patch);
                lrc.classify(&obs).ok().map(|r| (i, r.posterior))
            })
            .collect();
        for (i, posterior) in results {
            for key in self.belief.disc_voxels(&d.discs[i]) {
                self.belief.update(key, &posterior)?;
            }
            d.observations[i] += 1;
        }
        Ok(())
    }

    /// The material information remaining on disc `i` (eq. 4.16 over its
    /// voxels).
    fn h3(&self, d: &DiscMap, i: usize) -> Real {
        self.belief.h3_disc(&d.discs[i])
    }

    /// `H3` over every disc voxel (eq. 4.17).
    fn h3_total(&self) -> Real {
        self.belief.h3_total()
    }

    /// Write the posteriors and `H3` into the disc map.
    fn finish(&self, d: &mut DiscMap) {
        d.posterior = d
            .discs
            .iter()
            .map(|disc| self.belief.disc_probabilities(disc).unwrap_or_default())
            .collect();
        d.h3 = d
            .discs
            .iter()
            .map(|disc| self.belief.h3_disc(disc))
            .collect();
        d.h3_total = Some(self.h3_total());
    }
}

/// Whether the robot's collision capsules stay `clearance_m` or more from
/// `map` (the mapped surface) at every configuration checked along
/// `waypoints` and through the tilt sweep `(lo, hi)` at its end.
fn clear_of_map(
    robot: &Robot,
    world_from_base: &Isometry3,
    map: &scene::World,
    safety: &Safety,
    waypoints: &[Vec<Real>],
    (lo, hi): (Vec<Real>, Vec<Real>),
    clearance_m: Real,
) -> Result<bool, SimError> {
    let (Some(map), true) = (map.as_scene(), clearance_m > 0.0) else {
        return Ok(true);
    };
    let Some(goal) = waypoints.last() else {
        return Ok(true);
    };
    let sweep = [goal.clone(), lo, hi];
    for pair in waypoints.windows(2).chain(sweep.windows(2)) {
        for c in safety.interpolate(&pair[0], &pair[1]) {
            let frames = robot.forward_kinematics(&c)?;
            if min_clearance(robot, &frames, world_from_base, map, clearance_m) < clearance_m {
                return Ok(false);
            }
        }
    }
    Ok(true)
}

/// Poses the arm has stood at that are tried as the last waypoint before a
/// goal the roadmap cannot reach.
const VISITED_BRIDGES: usize = 5;

/// A safe path from `from` to `goal`: the roadmap's (a direct motion, or A*
/// through the roadmap), or else through one of the poses the arm has
/// already stood at (`visited`; the [`VISITED_BRIDGES`] nearest to the goal,
/// nearest first) from which a straight motion reaches the goal. A Stage Two
/// pose is chosen by LM anywhere in free space, often beside a viewpoint
/// the arm took but far from every roadmap node whose surroundings are known
/// free.
fn path_via_visited(
    roadmap: &plan::Roadmap,
    visited: &[&[Real]],
    from: &[Real],
    goal: &[Real],
    link_k: usize,
    checker: &mut dyn plan::MotionChecker,
) -> Option<plan::Path> {
    if let Some(path) = roadmap.plan(from, goal, link_k, checker) {
        return Some(path);
    }
    let mut near: Vec<(Real, &[Real])> = visited
        .iter()
        .map(|v| (roadmap.distance(v, goal), *v))
        .collect();
    near.sort_by(|a, b| a.0.total_cmp(&b.0));
    near.dedup_by(|a, b| a.1 == b.1);
    for (d, v) in near.into_iter().take(VISITED_BRIDGES) {
        if v == from || !checker.motion_ok(v, goal) {
            continue;
        }
        if let Some(mut path) = roadmap.plan(from, v, link_k, checker) {
            path.waypoints.push(goal.to_vec());
            path.cost += d;
            return Some(path);
        }
    }
    None
}

/// Per disc: whether the vertices of the mapped surface `vertices` within
/// `radius_m` of its centre lie within `limit_m` RMS of their plane of best
/// fit. The LRC refuses an observation of a patch that is not flat (an edge,
/// a corner, a second surface or a curve within its patch), so a disc whose
/// mapped surroundings are not flat is not worth a Stage Two viewpoint: it
/// cannot be identified within the LRC's constraints.
fn flat_patches(
    discs: &[map::Disc],
    vertices: &[geom::Point3],
    radius_m: Real,
    limit_m: Real,
) -> Vec<bool> {
    use rayon::prelude::*;
    if vertices.is_empty() {
        return vec![false; discs.len()];
    }
    let coords: Vec<[Real; 3]> = vertices.iter().map(|p| [p.x, p.y, p.z]).collect();
    let tree: kiddo::ImmutableKdTree<Real, 3> = kiddo::ImmutableKdTree::new_from_slice(&coords);
    discs
        .par_iter()
        .map(|disc| {
            let c = disc.centre;
            let near = tree
                .within_unsorted::<kiddo::SquaredEuclidean>(&[c.x, c.y, c.z], radius_m * radius_m);
            let offsets: Vec<geom::Vector3> =
                near.iter().map(|n| vertices[n.item as usize] - c).collect();
            offsets.len() >= 3
                && geom::Pca::of_offsets(&offsets)
                    .is_some_and(|p| p.eigenvalues[0].max(0.0).sqrt() <= limit_m)
        })
        .collect()
}

/// The returns of `points` within `radius_m` of `target`, as an LRC
/// observation ([`patch_observation`] with its own kd-tree).
fn sweep_patch(
    points: &[SweepPoint],
    target: &geom::Point3,
    radius_m: Real,
) -> sensor::Observation {
    let coords: Vec<[Real; 3]> = points
        .iter()
        .map(|p| [p.point.x, p.point.y, p.point.z])
        .collect();
    let tree: kiddo::ImmutableKdTree<Real, 3> = kiddo::ImmutableKdTree::new_from_slice(&coords);
    patch_observation(points, &tree, target, radius_m)
}

/// The returns of `points` (indexed by `tree`) within `radius_m` of
/// `target`, in point order: `sensor::Observation::from_sweep` through a
/// kd-tree.
fn patch_observation(
    points: &[SweepPoint],
    tree: &kiddo::ImmutableKdTree<Real, 3>,
    target: &geom::Point3,
    radius_m: Real,
) -> sensor::Observation {
    let near = tree.within_unsorted::<kiddo::SquaredEuclidean>(
        &[target.x, target.y, target.z],
        radius_m * radius_m,
    );
    let mut idx: Vec<usize> = near.iter().map(|n| n.item as usize).collect();
    idx.sort_unstable();
    let returns = idx
        .iter()
        .filter_map(|&k| {
            let p = &points[k];
            let (direction, range_m) =
                geom::UnitVector3::try_new_and_get(p.point - p.origin, 1e-12)?;
            Some(sensor::classifier::ObservedReturn {
                origin: p.origin,
                direction,
                range_m,
                intensity: p.intensity,
            })
        })
        .collect();
    sensor::Observation {
        returns,
        target: Some(*target),
    }
}

/// Simulated observations per material the LRC is trained on.
const LRC_TRAINING_OBSERVATIONS: usize = 60;

/// Misses free space this much short of the scanner's range, metres (three
/// σ of the URG-04LX's 1 % noise at 4 m, rounded up).
const MISS_MARGIN_M: Real = 0.15;

/// Clearance search radius, metres.
const CLEARANCE_SEARCH_M: Real = 0.5;

/// Everything a Stage One run starts from: the scenario's robot, world,
/// sweep and parameters, the C-space model (built or loaded), the planning
/// state at the start pose and a simulated rig there.
#[derive(Debug)]
pub struct StageOneSetup {
    /// The robot (scanner mounted).
    pub robot: Robot,
    /// The ground truth.
    pub world: Arc<scene::World>,
    /// Where the robot's base stands.
    pub world_from_base: Isometry3,
    /// Stage One's parameters (scenario or options, sweep from the scanner).
    pub config: ExploreConfig,
    /// The regions of interest.
    pub regions: map::RegionsConfig,
    /// How far misses free space and predictions cast, metres.
    pub reach_m: Real,
    /// The start pose.
    pub start: Vec<Real>,
    /// The planning state before the first sweep.
    pub stage: StageOne,
    /// The simulated arm and scanner at the start pose.
    pub rig: SimRig,
    /// How the C-space model was obtained.
    pub cspace: String,
}

impl StageOneSetup {
    /// The setup of `loaded` under `options` (seed, budget, parameters, cache).
    pub fn new(loaded: &LoadedScenario, options: &ExploreOptions) -> Result<Self, SimError> {
        let s = &loaded.scenario;
        let robot = loaded.build_robot()?;
        let world = Arc::new(loaded.build_world()?);
        let world_from_base = s.world_from_base();
        let spec = s.scanner.clone().unwrap_or_default();
        let mut config = options
            .config
            .clone()
            .or_else(|| s.explore.clone())
            .unwrap_or_default();
        config.sweep = spec.sweep;
        if let Some(n) = options.max_viewpoints {
            config.max_viewpoints = n;
        }
        let regions = s.regions.ok_or_else(|| SimError::Scenario {
            source_name: s.name.clone(),
            message: "exploration needs regions of interest ([regions] a1, a2, a3)".into(),
        })?;
        // Rays without a return free space up to a little short of the range
        // (map's perfect-detection reading), and predictions cast as far.
        let reach_m = (spec.config.max_range_m - MISS_MARGIN_M).max(spec.config.min_range_m);
        let occupancy = map::OccupancyConfig {
            regions,
            free_misses_m: Some(reach_m),
            ..map::OccupancyConfig::default()
        };
        let start = s.robot.start_joints.clone();
        robot
            .check_within_limits(&start)
            .map_err(|e| SimError::Scenario {
                source_name: s.name.clone(),
                message: format!("robot.start_joints: {e}"),
            })?;
        // Exploration assumes only that the start pose is safe (A§6.1); one
        // that touches the scene is a mistake in the scenario.
        if let Some(scene) = world.as_scene() {
            let frames = robot.forward_kinematics(&start)?;
            if let Some(c) =
                crate::safety::robot_contacts(&robot, &frames, &world_from_base, scene).first()
            {
                return Err(SimError::Scenario {
                    source_name: s.name.clone(),
                    message: format!(
                        "robot.start_joints: the start pose puts link {} ({}) into the scene (object {}); exploration starts from a safe pose",
                        c.link.index(),
                        robot.links[c.link.index()].name,
                        scene.object(c.object).map_or("?", |o| o.name.as_str())
                    ),
                });
            }
        }
        let voxel = config.planning_voxel_m;
        let (model, outcome) = match &options.cspace_cache {
            Some(path) => {
                CspaceModel::load_or_build(path, &robot, &world_from_base, voxel, &config.plan)?
            }
            None => (
                CspaceModel::build(&robot, &world_from_base, voxel, &config.plan)?,
                CacheOutcome::Built("no cache file".into()),
            ),
        };
        let cspace = match outcome {
            CacheOutcome::Loaded => "loaded from cache".to_owned(),
            CacheOutcome::Built(why) => format!("built ({why})"),
        };
        let scanner = Scanner::new(spec.config)?;
        let bearings = scanner.bearings_rad().to_vec();
        let stage = StageOne::new(
            model,
            &occupancy,
            &bearings,
            reach_m,
            config.clone(),
            &start,
        )?;
        let rig = SimRig::new(
            robot.clone(),
            Arc::clone(&world),
            world_from_base,
            &start,
            Some(scanner),
            options.seed,
        )?;
        Ok(Self {
            robot,
            world,
            world_from_base,
            config,
            regions,
            reach_m,
            start,
            stage,
            rig,
            cspace,
        })
    }
}

/// Run AXBAM on a scenario: Stage One, then Stage Two when
/// `options.stage_two`, then the map products. `progress` sees each
/// viewpoint's record as it completes.
pub fn run_exploration(
    loaded: &LoadedScenario,
    options: &ExploreOptions,
    progress: &mut dyn FnMut(&ViewpointRecord),
) -> Result<ExploreRun, SimError> {
    let t_run = Instant::now();
    let s = &loaded.scenario;
    let StageOneSetup {
        robot,
        world,
        world_from_base,
        config,
        regions,
        reach_m: reach,
        start,
        mut stage,
        mut rig,
        cspace,
    } = StageOneSetup::new(loaded, options)?;
    let scenario_toml = loaded.standalone().to_toml()?;
    let mut replay = std::collections::VecDeque::<ViewpointRecord>::default();
    let mut replay_two = std::collections::VecDeque::<ViewpointRecord>::default();
    let mut tried_before = Vec::new();
    let mut restored = None;
    if options.resume {
        let path = options
            .checkpoint
            .as_ref()
            .ok_or_else(|| SimError::InvalidArgument {
                what: "resume".into(),
                message: "no checkpoint file given".into(),
            })?;
        let c = Checkpoint::read(path)?;
        let mut mine = config.clone();
        mine.sweep = c.config.sweep;
        let stages = |two: bool| if two { "both" } else { "one" };
        let differs = if c.scenario != s.name {
            Some(format!(
                "the scenario ({} then, {} now)",
                c.scenario, s.name
            ))
        } else if c.seed != options.seed {
            Some(format!("--seed ({} then, {} now)", c.seed, options.seed))
        } else if c.stage_two != options.stage_two {
            Some(format!(
                "--stages ({} then, {} now)",
                stages(c.stage_two),
                stages(options.stage_two)
            ))
        } else if c.scenario_toml != scenario_toml {
            Some(
                "the scenario's content (the file, or --robot, changed since the checkpoint)"
                    .to_owned(),
            )
        } else if c.config != mine || c.sweep != config.sweep {
            Some("the exploration parameters ([explore], --max-viewpoints)".to_owned())
        } else {
            None
        };
        if let Some(what) = differs {
            return Err(SimError::InvalidArgument {
                what: path.display().to_string(),
                message: format!(
                    "the checkpoint is of another run: {what} differs; resume with the same \
                     scenario, robot, --seed, --stages and parameters, or run again without --resume"
                ),
            });
        }
        let (one, two): (Vec<_>, Vec<_>) = c.viewpoints.iter().cloned().partition(|r| r.stage == 1);
        replay = one.into();
        replay_two = two.into();
        tried_before.clone_from(&c.stage_two_tried);
        restored = Some(c);
    }
    let mut tsdf = TsdfMap::new(options.tsdf)?;
    let scene = world.as_scene();
    let check_step = 0.5 * config.plan.check_step_m;
    let fine = Safety::new(
        robot.clone(),
        world_from_base,
        &PlanConfig {
            check_step_m: check_step,
            ..config.plan.clone()
        },
        stage.model().roadmap().weights().to_vec(),
    )?;
    let contact_step = smallest_link_radius(&robot).map_or(0.01, |r| 0.5 * r);
    let mut audit = Audit {
        robot: &robot,
        world_from_base,
        scene,
        fine: &fine,
        contact_step,
        collisions: 0,
        unsafe_configurations: Vec::new(),
        min_clearance_m: CLEARANCE_SEARCH_M,
    };
    if let Some(c) = restored {
        audit.collisions = c.collisions;
        audit.unsafe_configurations = c.unsafe_configurations;
        audit.min_clearance_m = c.min_clearance_m;
    }
    let timed = |t: Instant| {
        if options.timings {
            t.elapsed().as_secs_f64() * 1e3
        } else {
            0.0
        }
    };

    let mut trackers = match scene {
        Some(scene) => {
            let eyes = observation_points(
                &robot,
                &world_from_base,
                scene,
                stage.model().roadmap(),
                &start,
            )?;
            let mut out = Vec::with_capacity(3);
            for b in [regions.a1, regions.a2, regions.a3] {
                let mut m = s.metrics;
                m.sampling.region = Some(b.aabb());
                let mut t = CoverageTracker::new(scene, &m)?;
                t.set_observable_from(scene, &eyes, reach, OBSERVABLE_CELL_M);
                out.push(t);
            }
            out
        }
        None => Vec::new(),
    };
    let mut viewpoints = Vec::new();
    let mut cloud: Vec<SweepPoint> = Vec::new();
    let mut cloud_viewpoint: Vec<usize> = Vec::new();
    let mut sweeps: Vec<sensor::Sweep> = Vec::new();
    let save = |viewpoints: &[ViewpointRecord],
                audit: &Audit<'_>,
                tried: &[usize]|
     -> Result<(), SimError> {
        match &options.checkpoint {
            Some(path) => Checkpoint {
                format: CHECKPOINT_FORMAT,
                checksum: 0,
                scenario: s.name.clone(),
                scenario_toml: scenario_toml.clone(),
                stage_two: options.stage_two,
                seed: options.seed,
                config: config.clone(),
                sweep: config.sweep,
                viewpoints: viewpoints.to_vec(),
                collisions: audit.collisions,
                unsafe_configurations: audit.unsafe_configurations.clone(),
                min_clearance_m: audit.min_clearance_m,
                stage_two_tried: tried.to_vec(),
            }
            .write(path),
            None => Ok(()),
        }
    };
    let mut q = start.clone();
    let mut pending: Option<Pending> = None;
    let termination = loop {
        let k = viewpoints.len();
        // Replayed viewpoints: the arm is put where it stood and its sweep
        // taken again (same seed, same points); its record and audit come
        // from the checkpoint.
        let replayed = replay.pop_front();
        if let Some(r) = &replayed {
            rig.move_to(&r.joints)?;
            q.clone_from(&r.joints);
        } else {
            // The sweep at the current pose, audited against the map it is
            // taken in.
            let (lo, hi) = stage.sweep_range(&q);
            audit.motion(stage.grid(), k, &q, &lo)?;
            audit.motion(stage.grid(), k, &lo, &hi)?;
            audit.motion(stage.grid(), k, &hi, &q)?;
        }
        rig.reseed(viewpoint_seed(options.seed, k));
        let t = Instant::now();
        let sweep = tilt_sweep(
            &mut rig,
            &robot,
            &world_from_base,
            &config.sweep,
            &mut |_, _| {},
        )?;
        let sweep_ms = timed(t);
        let t = Instant::now();
        let stats = stage.integrate(&sweep);
        tsdf.integrate_sweep(&sweep);
        let integrate_ms = timed(t);
        cloud.extend_from_slice(sweep.points());
        cloud_viewpoint.resize(cloud.len(), k);
        sweeps.push(sweep.clone());
        let positions = sweep.positions();
        for t in &mut trackers {
            t.add_points(&positions);
        }
        let was_replayed = replayed.is_some();
        let record = if let Some(r) = replayed {
            r
        } else {
            let (h1w, h2) = stage.information();
            let mut record = ViewpointRecord {
                k,
                stage: 1,
                joints: q.clone(),
                f: None,
                h1: stage.grid().h1_unweighted(),
                h1_weighted: h1w,
                h2,
                h3: None,
                target_disc: None,
                predicted_h1_weighted: None,
                candidates: 0,
                front: 0,
                unreachable: 0,
                predicted_revealed: 0,
                revealed: stats.newly_known,
                coverage_a1: trackers.first().map(CoverageTracker::fraction),
                joint_travel: 0.0,
                waypoints: 0,
                path: Vec::new(),
                scored: Vec::new(),
                decision_ms: 0.0,
                plan_ms: 0.0,
                sweep_ms,
                integrate_ms,
            };
            if let Some((choice, scored, front, unreachable, decision_ms, plan_ms)) = pending.take()
            {
                record.f = Some(choice.candidate.f);
                record.predicted_h1_weighted = Some(choice.candidate.f[0]);
                record.predicted_revealed = choice.candidate.revealed;
                record.candidates = scored.len();
                record.front = front;
                record.unreachable = unreachable;
                record.joint_travel = choice.path.joint_travel();
                record.waypoints = choice.path.waypoints.len();
                record.path.clone_from(&choice.path.waypoints);
                record.scored = scored;
                record.decision_ms = decision_ms;
                record.plan_ms = plan_ms;
            }
            record
        };
        progress(&record);
        viewpoints.push(record);
        if !replay.is_empty() {
            continue;
        }
        // A replayed viewpoint is in the checkpoint already (with any Stage
        // Two viewpoints after it).
        if !was_replayed {
            save(&viewpoints, &audit, &[])?;
        }
        if let Some(t) = stage.termination() {
            break t;
        }
        let t = Instant::now();
        let decision = stage.decide(&q)?;
        let decision_ms = timed(t);
        let plan_ms = if options.timings {
            decision.plan_ms
        } else {
            0.0
        };
        let Some(choice) = decision.choice else {
            break Termination::NoSafeCandidate;
        };
        // Move along the path, auditing each motion against the map as it is.
        for w in choice.path.waypoints.windows(2) {
            audit.motion(stage.grid(), k + 1, &w[0], &w[1])?;
            rig.move_to(&w[1])?;
        }
        q = rig.joints();
        let scored = decision
            .candidates
            .iter()
            .zip(&decision.on_front)
            .map(|(c, &front)| ScoredCandidate { f: c.f, front })
            .collect();
        pending = Some((
            choice,
            scored,
            decision.front_size,
            decision.unreachable,
            decision_ms,
            plan_ms,
        ));
    };

    let mesh = tsdf.extract_mesh();
    let mut discs = disc_map(
        &mesh,
        &cloud,
        &cloud_viewpoint,
        &viewpoints,
        scene,
        &config.mapping,
        options.seed,
    )?;
    let mut materials = match scene {
        Some(scene) => {
            let scanner_config = s.scanner.clone().unwrap_or_default().config;
            Materials::new(
                &mut discs,
                &mesh,
                &config.pose,
                scene,
                &scanner_config,
                options.seed,
            )?
        }
        None => None,
    };
    if let Some(m) = &mut materials {
        for sweep in &sweeps {
            m.observe(&mut discs, sweep)?;
        }
        // Stage One's last row holds H3 once its sweeps are classified on
        // the map Stage One built: the baseline of Stage Two's curve.
        if let Some(last) = viewpoints.last_mut() {
            last.h3 = Some(m.h3_total());
        }
    }
    // Stage Two (A§3.3): aim the scanner at the disc with the most material
    // information left that a valid, reachable pose can target; sweep,
    // classify, update; until none can be targeted or the budget is spent.
    let mut stage_two_end = None;
    if let (true, Some(m)) = (options.stage_two, materials.as_mut()) {
        let safety = stage.model().safety().clone();
        let selector = plan::PoseSelector::new(&safety, config.pose.clone())?;
        let mut tried = vec![false; discs.discs.len()];
        for &i in &tried_before {
            if let Some(t) = tried.get_mut(i) {
                *t = true;
            }
        }
        // The map as the scanner would see it: a simulated sweep of the
        // mapped surface (Stage One's mesh) from a candidate pose, with the
        // scanner's own model and noise, predicts the observation the LRC
        // will get; a pose whose predicted observation fails the LRC's
        // geometric checks (range, incidence, returns and span in the fit
        // window, flatness) is not a viewpoint for that disc.
        let map_world = Arc::new(scene::World::Mesh(Scene::from_mesh(
            "map",
            mesh.clone(),
            vec![scene::Material::new("map", 0.5, 0.5)],
            scene::MaterialId(0),
        )?));
        let mut probe = SimRig::new(
            robot.clone(),
            Arc::clone(&map_world),
            world_from_base,
            &q,
            Some(Scanner::new(s.scanner.clone().unwrap_or_default().config)?),
            options.seed,
        )?;
        let a2 = regions.a2;
        let uniform = (discs.material_names.len() as Real).ln();
        let end = loop {
            if viewpoints.iter().filter(|r| r.stage == 2).count() >= config.stage_two_max_viewpoints
            {
                break "viewpoint_budget";
            }
            let k = viewpoints.len();
            // A replayed viewpoint: the arm is put where it stood (its
            // record and audit come from the checkpoint).
            let replayed = replay_two.pop_front();
            let chosen = if let Some(r) = &replayed {
                rig.move_to(&r.joints)?;
                q.clone_from(&r.joints);
                None
            } else {
                let mut ranked: Vec<(usize, Real)> = (0..discs.discs.len())
                    .filter(|&i| !tried[i] && m.flat[i] && a2.contains(&discs.discs[i].centre))
                    .map(|i| (i, m.h3(&discs, i)))
                    .filter(|(i, h)| {
                        let voxels = m.belief.disc_voxels(&discs.discs[*i]).len() as Real;
                        *h > config.significant_h3 * uniform * voxels
                    })
                    .collect();
                ranked.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
                let t = Instant::now();
                let mut found = None;
                // One map for the whole decision: every motion checked while
                // trying one disc is known when trying the next.
                let mut checker =
                    plan::MemoChecker::new(stage.model().safety().checker(stage.grid()));
                for &(i, _) in ranked.iter().take(config.stage_two_target_attempts) {
                    tried[i] = true;
                    let target = plan::Target::from_disc(&discs.discs[i]);
                    let solution = selector.select(stage.grid(), &target, &q)?;
                    if !solution.valid() {
                        continue;
                    }
                    let goal = solution.joints().to_vec();
                    if stage.sweep_dist(&goal)?.is_none() {
                        continue;
                    }
                    probe.move_to(&goal)?;
                    probe.reseed(viewpoint_seed(options.seed, k) ^ i as u64);
                    let predicted = tilt_sweep(
                        &mut probe,
                        &robot,
                        &world_from_base,
                        &config.sweep,
                        &mut |_, _| {},
                    )?;
                    let check = m.lrc.check_geometry(
                        &sweep_patch(predicted.points(), &discs.discs[i].centre, m.patch_m),
                        &m.lrc.config,
                    );
                    if check.is_err() {
                        continue;
                    }
                    let visited: Vec<&[Real]> =
                        viewpoints.iter().map(|r| r.joints.as_slice()).collect();
                    if let Some(path) = path_via_visited(
                        stage.model().roadmap(),
                        &visited,
                        &q,
                        &goal,
                        config.link_k,
                        &mut checker,
                    ) && clear_of_map(
                        &robot,
                        &world_from_base,
                        &map_world,
                        &fine,
                        &path.waypoints,
                        stage.sweep_range(&goal),
                        config.stage_two_clearance_m,
                    )? {
                        found = Some((i, path));
                        break;
                    }
                }
                let decision_ms = timed(t);
                let Some((target, path)) = found else {
                    break "no_targetable_disc";
                };
                for w in path.waypoints.windows(2) {
                    audit.motion(stage.grid(), k, &w[0], &w[1])?;
                    rig.move_to(&w[1])?;
                }
                q = rig.joints();
                let (lo, hi) = stage.sweep_range(&q);
                audit.motion(stage.grid(), k, &q, &lo)?;
                audit.motion(stage.grid(), k, &lo, &hi)?;
                audit.motion(stage.grid(), k, &hi, &q)?;
                Some((target, path, decision_ms, ranked.len()))
            };
            rig.reseed(viewpoint_seed(options.seed, k));
            let t = Instant::now();
            let sweep = tilt_sweep(
                &mut rig,
                &robot,
                &world_from_base,
                &config.sweep,
                &mut |_, _| {},
            )?;
            let sweep_ms = timed(t);
            let t = Instant::now();
            let stats = stage.integrate(&sweep);
            tsdf.integrate_sweep(&sweep);
            m.observe(&mut discs, &sweep)?;
            let integrate_ms = timed(t);
            cloud.extend_from_slice(sweep.points());
            let positions = sweep.positions();
            for t in &mut trackers {
                t.add_points(&positions);
            }
            let (h1w, h2) = stage.information();
            let record = match (replayed, chosen) {
                (Some(r), _) => r,
                (None, None) => unreachable!("a viewpoint is replayed or chosen"),
                (None, Some((target, path, decision_ms, candidates))) => ViewpointRecord {
                    k,
                    stage: 2,
                    joints: q.clone(),
                    f: None,
                    h1: stage.grid().h1_unweighted(),
                    h1_weighted: h1w,
                    h2,
                    h3: Some(m.h3_total()),
                    target_disc: Some(target),
                    predicted_h1_weighted: None,
                    candidates,
                    front: 0,
                    unreachable: 0,
                    predicted_revealed: 0,
                    revealed: stats.newly_known,
                    coverage_a1: trackers.first().map(CoverageTracker::fraction),
                    joint_travel: path.joint_travel(),
                    waypoints: path.waypoints.len(),
                    path: path.waypoints.clone(),
                    scored: Vec::new(),
                    decision_ms,
                    plan_ms: 0.0,
                    sweep_ms,
                    integrate_ms,
                },
            };
            progress(&record);
            viewpoints.push(record);
            if replay_two.is_empty() {
                let tried: Vec<usize> = (0..tried.len()).filter(|&i| tried[i]).collect();
                save(&viewpoints, &audit, &tried)?;
            }
        };
        stage_two_end = Some(end.to_owned());
    }
    if let Some(m) = &materials {
        m.finish(&mut discs);
    }
    let mesh = tsdf.extract_mesh();
    let coverage = match trackers.as_slice() {
        [a1, a2, a3] => Some([a1.report(), a2.report(), a3.report()]),
        _ => None,
    };
    let observable = trackers
        .iter()
        .filter_map(CoverageTracker::observable_counts)
        .collect::<Vec<_>>();
    Ok(ExploreRun {
        scenario: s.name.clone(),
        viewpoints,
        termination,
        stage_two_termination: stage_two_end,
        collisions: audit.collisions,
        unsafe_configurations: audit.unsafe_configurations,
        min_clearance_m: audit.min_clearance_m,
        initial_information: stage.initial_information(),
        cspace,
        cloud,
        mesh,
        discs,
        coverage,
        observable,
        grid: stage.grid().clone(),
        wall_s: if options.timings {
            t_run.elapsed().as_secs_f64()
        } else {
            0.0
        },
    })
}

/// Discs of `mesh`, each tied to the viewpoint of the nearest point of
/// `cloud`, and segmented with those viewpoints' joints as the pose graph.
fn disc_map(
    mesh: &TriMesh,
    cloud: &[SweepPoint],
    cloud_viewpoint: &[usize],
    viewpoints: &[ViewpointRecord],
    scene: Option<&Scene>,
    mapping: &explore::MappingConfig,
    seed: u64,
) -> Result<DiscMap, SimError> {
    use kiddo::{ImmutableKdTree, SquaredEuclidean};
    if mesh.vertices.is_empty() || cloud.is_empty() {
        return Ok(DiscMap::default());
    }
    let normals = mesh.vertex_normals();
    let sld = map::generate_discs(
        &mesh.vertices,
        map::Orientation::ReferenceNormals(&normals),
        &mapping.sld,
        seed,
    )?;
    let pts: Vec<[Real; 3]> = cloud
        .iter()
        .map(|p| [p.point.x, p.point.y, p.point.z])
        .collect();
    let tree: ImmutableKdTree<Real, 3> = ImmutableKdTree::new_from_slice(&pts);
    let viewpoint: Vec<usize> = sld
        .discs
        .iter()
        .map(|d| {
            let n =
                tree.approx_nearest_one::<SquaredEuclidean>(&[d.centre.x, d.centre.y, d.centre.z]);
            cloud_viewpoint[n.item as usize]
        })
        .collect();
    let poses: Vec<map::segment::JointPose> = viewpoint
        .iter()
        .map(|&k| {
            let mut pose = [0.0; 6];
            for (slot, v) in pose.iter_mut().zip(&viewpoints[k].joints) {
                *slot = *v;
            }
            pose
        })
        .collect();
    let dof6 = viewpoints.first().is_some_and(|r| r.joints.len() == 6);
    let segments = map::segment_discs(
        &sld.discs,
        dof6.then_some(poses.as_slice()),
        &mapping.segment,
    )?;
    let mut segment = vec![0; sld.discs.len()];
    for (s, members) in segments.iter().enumerate() {
        for d in members {
            segment[d.0] = s;
        }
    }
    let (true_material, material_names) = match scene {
        Some(scene) => (
            sld.discs
                .iter()
                .map(|d| {
                    scene
                        .closest_point(&d.centre, 0.05)
                        .map(|(_, face, _)| usize::from(scene.triangle_material(face).0))
                })
                .collect(),
            scene.materials().iter().map(|m| m.name.clone()).collect(),
        ),
        None => (vec![None; sld.discs.len()], Vec::new()),
    };
    Ok(DiscMap {
        discs: sld.discs,
        viewpoint,
        segment,
        segments,
        true_material,
        material_names,
        ..DiscMap::default()
    })
}

/// Cell size of the observability test, metres.
const OBSERVABLE_CELL_M: Real = 0.05;

/// Where a scanner could look from: the scanner position at the start and at
/// every roadmap node where no link touches the true scene.
fn observation_points(
    robot: &Robot,
    world_from_base: &Isometry3,
    scene: &Scene,
    roadmap: &plan::Roadmap,
    start: &[Real],
) -> Result<Vec<geom::Point3>, SimError> {
    let mut out = Vec::new();
    for q in std::iter::once(start).chain(roadmap.nodes()) {
        let frames = robot.forward_kinematics(q)?;
        if !crate::safety::robot_contacts(robot, &frames, world_from_base, scene).is_empty() {
            continue;
        }
        if let Some(pose) = robot.scanner_pose(q)? {
            out.push(geom::Point3::from(
                (world_from_base * pose).translation.vector,
            ));
        }
    }
    Ok(out)
}

/// The safety audit of executed motions.
struct Audit<'a> {
    robot: &'a Robot,
    world_from_base: Isometry3,
    scene: Option<&'a Scene>,
    fine: &'a Safety,
    contact_step: Real,
    collisions: usize,
    unsafe_configurations: Vec<UnsafeConfiguration>,
    min_clearance_m: Real,
}

impl Audit<'_> {
    fn motion(
        &mut self,
        grid: &map::OccupancyGrid,
        viewpoint: usize,
        a: &[Real],
        b: &[Real],
    ) -> Result<(), SimError> {
        for c in self.fine.interpolate(a, b) {
            let d = self.fine.dist(grid, &c)?;
            if d <= 1.0 {
                self.unsafe_configurations.push(UnsafeConfiguration {
                    viewpoint,
                    joints: c.clone(),
                    dist: d,
                });
            }
            if let Some(scene) = self.scene {
                let frames = self.robot.forward_kinematics(&c)?;
                self.min_clearance_m = self.min_clearance_m.min(min_clearance(
                    self.robot,
                    &frames,
                    &self.world_from_base,
                    scene,
                    self.min_clearance_m,
                ));
            }
        }
        if let Some(scene) = self.scene {
            let check = motion_contacts(
                self.robot,
                a,
                b,
                &self.world_from_base,
                scene,
                self.contact_step,
            )?;
            if !check.is_clear() {
                self.collisions += 1;
            }
        }
        Ok(())
    }
}

impl ExploreRun {
    /// `viewpoints.csv`: one row per viewpoint.
    pub fn viewpoints_csv(&self) -> String {
        let dof = self.viewpoints.first().map_or(0, |r| r.joints.len());
        let mut out = String::from("k,stage");
        for j in 1..=dof {
            let _ = write!(out, ",q{j}");
        }
        out.push_str(
            ",f1,f2,f3,f4,h1,h1_weighted,h2,h3,predicted_h1_weighted,actual_h1_weighted,\
             candidates,front,unreachable,predicted_revealed,revealed,coverage_a1,joint_travel,waypoints,\
             decision_ms,plan_ms,sweep_ms,integrate_ms,target_disc\n",
        );
        let opt = |v: Option<Real>| v.map_or(String::new(), |x| format!("{x}"));
        for r in &self.viewpoints {
            let _ = write!(out, "{},{}", r.k, r.stage);
            for v in &r.joints {
                let _ = write!(out, ",{v}");
            }
            let f = r.f.map_or([None; 4], |f| f.map(Some));
            for v in f {
                let _ = write!(out, ",{}", opt(v));
            }
            let _ = writeln!(
                out,
                ",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.3},{:.3},{:.3},{:.3},{}",
                r.h1,
                r.h1_weighted,
                r.h2,
                opt(r.h3),
                opt(r.predicted_h1_weighted),
                r.h1_weighted,
                r.candidates,
                r.front,
                r.unreachable,
                r.predicted_revealed,
                r.revealed,
                opt(r.coverage_a1),
                r.joint_travel,
                r.waypoints,
                r.decision_ms,
                r.plan_ms,
                r.sweep_ms,
                r.integrate_ms,
                r.target_disc.map_or(String::new(), |t| t.to_string())
            );
        }
        out
    }

    /// `candidates.csv`: every candidate each Stage One decision scored
    /// (k is the viewpoint the decision chose), with `[f1, f2, f3, f4]`,
    /// whether it was on the Pareto front and whether it was chosen (Paul
    /// Fig. 6.6).
    pub fn candidates_csv(&self) -> String {
        let mut out = String::from("k,candidate,f1,f2,f3,f4,front,chosen\n");
        for r in &self.viewpoints {
            for (i, c) in r.scored.iter().enumerate() {
                let [f1, f2, f3, f4] = c.f;
                let _ = writeln!(
                    out,
                    "{},{i},{f1},{f2},{f3},{f4},{},{}",
                    r.k,
                    u8::from(c.front),
                    u8::from(r.f == Some(c.f))
                );
            }
        }
        out
    }

    /// `path.csv`: the executed motions, one row per waypoint (k is the
    /// viewpoint the motion reached; the start pose is k 0's only row).
    pub fn path_csv(&self) -> String {
        let dof = self.viewpoints.first().map_or(0, |r| r.joints.len());
        let mut out = String::from("k,stage,waypoint");
        for j in 1..=dof {
            let _ = write!(out, ",q{j}");
        }
        out.push('\n');
        for r in &self.viewpoints {
            let start = [r.joints.clone()];
            let rows = if r.path.is_empty() {
                &start[..]
            } else {
                &r.path[..]
            };
            for (i, q) in rows.iter().enumerate() {
                let _ = write!(out, "{},{},{i}", r.k, r.stage);
                for v in q {
                    let _ = write!(out, ",{v}");
                }
                out.push('\n');
            }
        }
        out
    }

    /// `run.json`'s summary.
    pub fn run_json(&self) -> serde_json::Value {
        // Median and largest decision time of the viewpoints `pick` selects.
        let decisions = |pick: &dyn Fn(&ViewpointRecord) -> bool| {
            let mut sorted: Vec<Real> = self
                .viewpoints
                .iter()
                .filter(|r| pick(r))
                .map(|r| r.decision_ms)
                .collect();
            sorted.sort_by(Real::total_cmp);
            (
                sorted.get(sorted.len() / 2).copied().unwrap_or(0.0),
                sorted.last().copied().unwrap_or(0.0),
            )
        };
        let (median, max) = decisions(&|r| r.f.is_some());
        let (median2, max2) = decisions(&|r| r.stage == 2);
        let share = |k: usize| {
            self.observable.get(k).map(|(n, c)| {
                if *n == 0 {
                    0.0
                } else {
                    *c as Real / *n as Real
                }
            })
        };
        let coverage = self.coverage.as_ref().map(|[a1, a2, a3]| {
            serde_json::json!({
                "A1": a1.fraction(),
                "A2": a2.fraction(),
                "A3": a3.fraction(),
                "observable": {
                    "A1": share(0),
                    "A2": share(1),
                    "A3": share(2),
                    "A1_observable_share": self.observable.first().map(|(n, _)| *n as Real / a1.samples.max(1) as Real),
                },
                "A1_per_material": a1.per_material.iter().map(|m| {
                    (m.material.clone(), if m.samples == 0 { 0.0 } else { m.covered as Real / m.samples as Real })
                }).collect::<std::collections::BTreeMap<_, _>>(),
                "reports": [a1, a2, a3],
            })
        });
        serde_json::json!({
            "scenario": self.scenario,
            "viewpoints": {
                "stage_one": self.viewpoints.iter().filter(|r| r.stage == 1).count(),
                "stage_two": self.viewpoints.iter().filter(|r| r.stage == 2).count(),
            },
            "termination": self.termination.name(),
            "stage_two_termination": self.stage_two_termination,
            "collisions": self.collisions,
            "unsafe_configurations": self.unsafe_configurations.len(),
            "unsafe_configuration_list": self.unsafe_configurations,
            "min_clearance_m": self.min_clearance_m,
            "initial_information": {"H1_weighted": self.initial_information.0, "H2": self.initial_information.1},
            "points": self.cloud.len(),
            "mesh_triangles": self.mesh.triangles.len(),
            "discs": self.discs.discs.len(),
            "segments": self.discs.segments.len(),
            "materials": self.discs.material_names,
            "coverage": coverage,
            "material_accuracy": self.discs.material_accuracy(),
            "discs_observed_by_lrc": self.discs.observations.iter().filter(|o| **o > 0).count(),
            "h3": self.discs.h3_total,
            "decision_ms": {"median": median, "max": max},
            "stage_two_decision_ms": {"median": median2, "max": max2},
            "wall_s": self.wall_s,
        })
    }

    /// Write `viewpoints.csv`, `candidates.csv`, `path.csv`, `cloud.ply`,
    /// `mesh.ply`, `discs.csv`, `segments.json` and `run.json` into `dir`
    /// (created if needed).
    pub fn write(&self, dir: &Path) -> Result<(), SimError> {
        let io = |path: &Path, e: &dyn std::fmt::Display| SimError::InvalidArgument {
            what: path.display().to_string(),
            message: format!("cannot write: {e}"),
        };
        std::fs::create_dir_all(dir).map_err(|e| io(dir, &e))?;
        for (name, text) in [
            ("viewpoints.csv", self.viewpoints_csv()),
            ("candidates.csv", self.candidates_csv()),
            ("path.csv", self.path_csv()),
        ] {
            let csv = dir.join(name);
            std::fs::write(&csv, text).map_err(|e| io(&csv, &e))?;
        }
        let cols: [Vec<f32>; 6] = [
            self.cloud.iter().map(|p| p.point.x as f32).collect(),
            self.cloud.iter().map(|p| p.point.y as f32).collect(),
            self.cloud.iter().map(|p| p.point.z as f32).collect(),
            self.cloud.iter().map(|p| p.origin.x as f32).collect(),
            self.cloud.iter().map(|p| p.origin.y as f32).collect(),
            self.cloud.iter().map(|p| p.origin.z as f32).collect(),
        ];
        let refs: Vec<&[f32]> = cols.iter().map(Vec::as_slice).collect();
        scene::io::write_ply_vertices_file(
            &dir.join("cloud.ply"),
            &["x", "y", "z", "origin_x", "origin_y", "origin_z"],
            &refs,
        )?;
        scene::io::write_mesh_ply(&dir.join("mesh.ply"), &self.mesh)?;
        let d = &self.discs;
        let column = |name: &str, values: Vec<Real>| map::sld_io::ExtraColumn {
            name: name.to_owned(),
            values,
        };
        let extra = [
            column("segment", d.segment.iter().map(|v| *v as Real).collect()),
            column(
                "viewpoint",
                d.viewpoint.iter().map(|v| *v as Real).collect(),
            ),
            column(
                "true_material",
                d.true_material
                    .iter()
                    .map(|m| m.map_or(-1.0, |v| v as Real))
                    .collect(),
            ),
        ];
        let mut extra = extra.to_vec();
        for (m, name) in d.material_names.iter().enumerate() {
            if d.posterior.len() == d.discs.len() {
                extra.push(column(
                    &format!("p_{name}"),
                    d.posterior
                        .iter()
                        .map(|p| p.get(m).copied().unwrap_or(0.0))
                        .collect(),
                ));
            }
        }
        if d.h3.len() == d.discs.len() {
            extra.push(column("h3", d.h3.clone()));
            extra.push(column(
                "lrc_observations",
                d.observations.iter().map(|v| *v as Real).collect(),
            ));
        }
        map::sld_io::save_discs_csv(&dir.join("discs.csv"), &d.discs, &extra)?;
        map::segment_io::save_segments_json(&dir.join("segments.json"), &d.segments)?;
        let json = dir.join("run.json");
        let text =
            serde_json::to_string_pretty(&self.run_json()).map_err(|e| io(&json, &e))? + "\n";
        std::fs::write(&json, text).map_err(|e| io(&json, &e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patch_observation_equals_from_sweep() {
        // A sweep of bridge1 from the start pose; patches around some points.
        let loaded = crate::Scenario::load("bridge1").unwrap();
        let setup =
            crate::scan_job::ScanSetup::from_scenario(&loaded, None, Some(10.0), 1).unwrap();
        let sweep = setup.run(&mut |_, _| {}).unwrap().sweep;
        let pts = sweep.points();
        let coords: Vec<[Real; 3]> = pts
            .iter()
            .map(|p| [p.point.x, p.point.y, p.point.z])
            .collect();
        let tree = kiddo::ImmutableKdTree::new_from_slice(&coords);
        for k in (0..pts.len()).step_by(pts.len() / 7) {
            let target = pts[k].point + geom::Vector3::new(0.01, -0.02, 0.0);
            let a = patch_observation(pts, &tree, &target, 0.18);
            let b = sensor::Observation::from_sweep(&sweep, &target, 0.18);
            assert!(!a.returns.is_empty());
            assert_eq!(a, b);
        }
    }
}
