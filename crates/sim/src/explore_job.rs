//! AXBAM exploration of a scenario in the simulator: the scenario's robot
//! and scanner as a [`SimRig`] in its ground-truth world, the job of
//! [`scenario::job::explore`] driving it, and an [`ExploreJudge`] that
//! checks every executed motion against the truth (contacts, clearance)
//! and measures what the sweeps cover, beside the coverage and material
//! oracles. [`explore()`] is the whole `surveyor explore` job in the
//! simulator: the run, then its run folder staged with the blast plan
//! (Paul App. A), written whole or not at all
//! ([`scenario::job::explore::explore_with`]).

use crate::metrics::{CoverageReport, CoverageTracker};
use crate::{SimError, SimRig};
use blast::BlastPlan;
use explore::{Judge, SafetyTally, Setup};
use geom::{Isometry3, Point3, Real, Vector3};
use plan::contact::{min_clearance, motion_contacts, robot_contacts, smallest_link_radius};
use rayon::prelude::*;
use robot::Robot;
use scenario::LoadedScenario;
use scenario::job::explore::{
    ExploreJob, ExploreOptions, ExploreOutcome, Finish, OracleOption, explore_setup, explore_with,
    run_loop, run_options,
};
use scene::{Scene, World};
use sensor::{Scanner, Sweep};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// Clearance search radius of the judge, metres.
const CLEARANCE_SEARCH_M: Real = 0.5;

/// Cell size of the observability test, metres.
const OBSERVABLE_CELL_M: Real = 0.05;

/// A disc's true material is that of the true surface a ray from this far
/// out on its seen side meets within twice this distance, or else of the
/// nearest true surface within this distance of its centre, metres.
const TRUE_MATERIAL_SEARCH_M: Real = 0.05;

/// The ground truth's judgement of an exploration: contacts of the robot's
/// collision shapes with the true scene along every executed motion, the
/// smallest clearance at the configurations the loop checked, and the
/// coverage of the true surfaces in A1, A2, A3 with an observability upper
/// bound (the samples some collision-free roadmap pose's scanner position
/// sees). A point-cloud world has no surfaces to judge against: nothing is
/// tallied then.
#[derive(Debug)]
pub struct ExploreJudge {
    robot: Robot,
    world: Arc<World>,
    world_from_base: Isometry3,
    contact_step: Real,
    collisions: usize,
    min_clearance_m: Real,
    trackers: Vec<CoverageTracker>,
}

impl ExploreJudge {
    /// The judge of `setup` in `world`, with the scenario's `metrics`.
    pub fn new(
        setup: &Setup,
        world: Arc<World>,
        metrics: &scenario::MetricsConfig,
    ) -> Result<Self, SimError> {
        let robot = setup.robot.clone();
        let world_from_base = setup.world_from_base;
        let mut trackers = Vec::new();
        if let Some(scene) = world.as_scene() {
            let eyes = observation_points(
                &robot,
                &world_from_base,
                scene,
                setup.stage.model().roadmap(),
                &setup.start,
            )?;
            let r = &setup.regions;
            // The three regions' trackers side by side (each is its own).
            trackers = [r.a1, r.a2, r.a3]
                .par_iter()
                .map(|b| {
                    let mut m = *metrics;
                    m.sampling.region = Some(b.aabb());
                    let mut t = CoverageTracker::new(scene, &m)?;
                    t.set_observable_from(scene, &eyes, setup.reach_m, OBSERVABLE_CELL_M);
                    Ok(t)
                })
                .collect::<Result<_, SimError>>()?;
        }
        Ok(Self {
            contact_step: smallest_link_radius(&robot).map_or(0.01, |r| 0.5 * r),
            robot,
            world,
            world_from_base,
            collisions: 0,
            min_clearance_m: CLEARANCE_SEARCH_M,
            trackers,
        })
    }

    /// Coverage of the true surfaces in A1, A2, A3 (mesh worlds).
    pub fn coverage(&self) -> Option<[CoverageReport; 3]> {
        match self.trackers.as_slice() {
            [a1, a2, a3] => Some([a1.report(), a2.report(), a3.report()]),
            _ => None,
        }
    }

    /// Per region A1, A2, A3: the samples observable from some
    /// collision-free roadmap pose's scanner position, and of those the
    /// covered ones (see [`CoverageTracker::set_observable_from`]).
    pub fn observable(&self) -> Vec<(usize, usize)> {
        self.trackers
            .iter()
            .filter_map(CoverageTracker::observable_counts)
            .collect()
    }
}

impl Judge for ExploreJudge {
    fn motion(
        &mut self,
        _viewpoint: usize,
        a: &[Real],
        b: &[Real],
        checked: &[Vec<Real>],
    ) -> Result<(), explore::ExploreError> {
        let Some(scene) = self.world.as_scene() else {
            return Ok(());
        };
        for c in checked {
            let frames = self.robot.forward_kinematics(c)?;
            self.min_clearance_m = self.min_clearance_m.min(min_clearance(
                &self.robot,
                &frames,
                &self.world_from_base,
                scene,
                self.min_clearance_m,
            ));
        }
        let check = motion_contacts(
            &self.robot,
            a,
            b,
            &self.world_from_base,
            scene,
            self.contact_step,
        )?;
        if !check.is_clear() {
            self.collisions += 1;
        }
        Ok(())
    }

    fn sweep(&mut self, sweep: &Sweep) {
        let positions = sweep.positions();
        self.trackers
            .par_iter_mut()
            .for_each(|t| t.add_points(&positions));
    }

    fn coverage_a1(&self) -> Option<Real> {
        self.trackers.first().map(CoverageTracker::fraction)
    }

    fn true_material(&self, centre: &Point3, facing: &Vector3) -> Option<usize> {
        use scene::RayCast;
        let scene = self.world.as_scene()?;
        // The surface the scanner saw: a ray from the seen side of the disc
        // back through its centre. The nearest triangle alone mislabels a
        // disc on a thin surface over another (the 4 mm containment sheet
        // on bridge1's web: the disc's centre, within the map's error of
        // the sheet, is as near the web behind it).
        let seen = geom::UnitVector3::try_new(*facing, 1e-9).and_then(|n| {
            let ray = geom::Ray::new(centre + n.into_inner() * TRUE_MATERIAL_SEARCH_M, -n);
            scene.cast_ray(&ray, 2.0 * TRUE_MATERIAL_SEARCH_M)
        });
        match seen {
            Some(hit) => hit.material.map(|m| usize::from(m.0)),
            None => scene
                .closest_point(centre, TRUE_MATERIAL_SEARCH_M)
                .map(|(_, face, _)| usize::from(scene.triangle_material(face).0)),
        }
    }

    fn tally(&self) -> SafetyTally {
        match self.world.as_scene() {
            Some(_) => SafetyTally {
                collisions: Some(self.collisions),
                min_clearance_m: Some(self.min_clearance_m),
            },
            None => SafetyTally::default(),
        }
    }

    fn restore(&mut self, tally: SafetyTally) {
        self.collisions = tally.collisions.unwrap_or(0);
        self.min_clearance_m = tally.min_clearance_m.unwrap_or(CLEARANCE_SEARCH_M);
    }
}

/// Where a scanner could look from: the scanner position at the start and at
/// every roadmap node where no link touches the true scene.
fn observation_points(
    robot: &Robot,
    world_from_base: &Isometry3,
    scene: &Scene,
    roadmap: &plan::Roadmap,
    start: &[Real],
) -> Result<Vec<Point3>, SimError> {
    let mut out = Vec::new();
    for q in std::iter::once(start).chain(roadmap.nodes()) {
        let frames = robot.forward_kinematics(q)?;
        if !robot_contacts(robot, &frames, world_from_base, scene).is_empty() {
            continue;
        }
        if let Some(pose) = robot.scanner_pose(q)? {
            out.push(Point3::from((world_from_base * pose).translation.vector));
        }
    }
    Ok(out)
}

/// A scenario's exploration, ready to run: the setup, the simulated rig at
/// the start pose, its judge and how to run.
#[derive(Debug)]
pub struct SimExplore {
    /// The scenario as given.
    pub loaded: LoadedScenario,
    /// What the loop starts from.
    pub setup: Setup,
    /// The ground truth.
    pub world: Arc<World>,
    /// The simulated arm and scanner at the start pose.
    pub rig: SimRig,
    /// The ground truth's judge.
    pub judge: ExploreJudge,
    /// How the loop runs.
    pub run_options: explore::RunOptions,
    /// Whether the coverage oracle is computed, and its cache.
    pub oracle: OracleOption,
}

impl SimExplore {
    /// The exploration of `loaded` under `options` (seed, budget,
    /// parameters, cache): [`explore_setup`], the rig at the start pose and
    /// the judge.
    pub fn new(loaded: &LoadedScenario, options: &ExploreOptions) -> Result<Self, SimError> {
        let s = &loaded.scenario;
        let (setup, world) = explore_setup(loaded, options)?;
        let spec = s.scanner.clone().unwrap_or_default();
        let robot = setup.robot.clone();
        let world_from_base = setup.world_from_base;
        let start = setup.start.clone();
        let rig = SimRig::new(
            robot,
            Arc::clone(&world),
            world_from_base,
            &start,
            Some(Scanner::new(spec.config)?),
            options.seed,
        )?;
        let judge = ExploreJudge::new(&setup, Arc::clone(&world), &s.metrics)?;
        let run_options = run_options(loaded, options)?;
        Ok(Self {
            loaded: loaded.clone(),
            setup,
            world,
            rig,
            judge,
            run_options,
            oracle: options.oracle.clone(),
        })
    }

    /// The same exploration with the simulated scanner's scans beginning
    /// `phase_s` seconds into each continuous motion
    /// ([`SimRig::set_scan_phase_s`]).
    pub fn with_scan_phase_s(mut self, phase_s: Real) -> Result<Self, SimError> {
        self.rig.set_scan_phase_s(phase_s)?;
        Ok(self)
    }

    /// Run it; `progress` sees each viewpoint's record as it completes.
    pub fn run(
        self,
        progress: &mut dyn FnMut(&record::ViewpointRecord),
    ) -> Result<ExploreOutcome, SimError> {
        let Self {
            loaded,
            setup,
            world,
            rig,
            mut judge,
            run_options,
            oracle,
        } = self;
        let t = Instant::now();
        let pending = match &oracle {
            OracleOption::On(cache) if world.as_scene().is_some() => Some(
                crate::oracle::OracleJob::start(&loaded, &setup, &world, cache.as_deref())?,
            ),
            _ => None,
        };
        // The material oracle judges Stage Two: computed when it runs in a
        // scene with materials. Its LRC is the run's of seed 0, whose cache
        // is the run's own only when the run's seed is 0.
        let materials = match &oracle {
            OracleOption::On(cache)
                if run_options.stage_two
                    && world.as_scene().is_some()
                    && !setup.materials.is_empty() =>
            {
                let lrc_cache = setup.lrc_cache.as_deref().filter(|_| run_options.seed == 0);
                let cache = cache.as_deref().map(crate::material_oracle::cache_beside);
                Some(crate::material_oracle::MaterialOracleJob::start(
                    &loaded,
                    &setup,
                    &world,
                    cache.as_deref(),
                    lrc_cache,
                )?)
            }
            _ => None,
        };
        let loaded_s = t.elapsed().as_secs_f64();
        let metrics = loaded.scenario.metrics;
        let a2 = setup.regions.a2;
        let bag = rig.run_bag()?;
        // A computed oracle runs beside the exploration (it depends on the
        // scenario and the setup only): the run waits for it at the end.
        // A failed run does not wait (the oracle's thread is left to end
        // with the process; its cache file is written whole or not at all).
        let (mut run, bag) =
            run_loop(&loaded, setup, rig, &mut judge, bag, &run_options, progress)?;
        let t = Instant::now();
        let oracle = pending.map(crate::oracle::OracleJob::finish).transpose()?;
        let material_identification = match materials {
            Some(job) => {
                let oracle = job.finish()?;
                let (samples, _) =
                    crate::material_oracle::material_samples(&world, &metrics, a2.aabb())?;
                Some(crate::material_oracle::compare(oracle, &samples, &run, &a2))
            }
            None => None,
        };
        if let Some(t_run) = &mut run.timings {
            t_run.oracle_s = loaded_s + t.elapsed().as_secs_f64();
        }
        Ok(ExploreOutcome {
            bag,
            coverage: judge.coverage(),
            observable: judge.observable(),
            oracle,
            material_identification,
            run,
            loaded,
        })
    }
}

/// Run an exploration of `loaded` under `options`.
pub fn run_exploration(
    loaded: &LoadedScenario,
    options: &ExploreOptions,
    progress: &mut dyn FnMut(&record::ViewpointRecord),
) -> Result<ExploreOutcome, SimError> {
    SimExplore::new(loaded, options)?.run(progress)
}

/// The whole `surveyor explore` job: check the output folder (not a file,
/// not a `surveyor follow` run, holding a checkpoint when resuming), run the
/// exploration of `loaded` with its checkpoint in `out`, stage the run
/// folder ([`scenario::job::explore::write_run`]), let `finish` add files to the staged folder
/// (the report, see [`Finish`]), and move everything into place,
/// `run.json` last.
pub fn explore(
    loaded: &LoadedScenario,
    options: &ExploreOptions,
    out: &Path,
    progress: &mut dyn FnMut(&record::ViewpointRecord),
    finish: &mut Finish<'_>,
) -> Result<(ExploreOutcome, Option<BlastPlan>), SimError> {
    explore_with(
        options,
        out,
        |options| SimExplore::new(loaded, options),
        progress,
        finish,
    )
}

impl ExploreJob for SimExplore {
    fn run_job(
        self,
        progress: &mut dyn FnMut(&record::ViewpointRecord),
    ) -> Result<ExploreOutcome, SimError> {
        self.run(progress)
    }
}
