//! Surface following of a scenario or a scene file in the simulator: the
//! robot as a [`SimRig`] in the ground-truth world, the job of
//! [`scenario::job::follow`] driving it, and a [`FollowJudge`] checking every
//! pose and motion against the truth (contacts, clearance) or, for a
//! point-cloud world, against the scan points.
//!
//! * [`SimFollow`] puts a [`FollowSetup`] (a scenario or a scene file, a
//!   robot and a start pose, from [`FollowRunOptions`]) on a rig;
//!   [`SimFollow::run`] runs the episode, judges it and scores the model
//!   ([`FollowRun`]).
//! * [`FollowRun::write`] stages the run folder (`surface_model.json`/`.obj`,
//!   `steps.csv`, `path.ply`, `run.json`, `model_snapshots.json`); [`follow()`]
//!   is the whole `surveyor follow` job.
//!
//! Determinism: the rig's noise is seeded and the follower is deterministic, so
//! the same inputs and seed give the same `steps.csv` and `surface_model.json`
//! byte for byte, except for the wall-clock timing columns of `steps.csv` and
//! the step times of `run.json`; with [`FollowRunOptions::timings`] off those
//! columns are written empty and those times are 0, so every file repeats.

use crate::scan_check::{
    ModelScanConfig, ModelScanScore, ScanIndex, model_to_scan, scan_clearance,
};
use crate::surface_score::{
    SurfaceScore, SurfaceScoreConfig, TrueFace, not_resting_on, score_surface_model,
};
use crate::{SimError, SimRig};
use follow::{FollowError, Follower};
use geom::{Isometry3, Real};
use plan::contact::{min_clearance, motion_contacts, robot_contacts, smallest_link_radius};
use record::follow::FollowSummary;
use record::{Collision, StepRow};
use robot::Robot;
use scenario::LoadedScenario;
use scenario::job::follow::{ScanFigures, SurfaceFigures};
use scene::World;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

pub use scenario::job::follow::{
    ARM4_BASE_XYZ, ARM4_SEED, DEFAULT_MAX_SETS, FollowRunConfig, FollowRunError, FollowRunOptions,
    FollowSetup, Judgement, StartPose, check_follow_out, follow_with,
};

/// Ground-truth clearance is searched no farther than this from the links, metres.
pub const CLEARANCE_SEARCH_M: Real = 1.0;

/// Step of [`motion_contacts`] for robots without link capsules, metres.
pub const MOTION_STEP_WITHOUT_CAPSULES_M: Real = 0.01;

/// A finished simulated run: the episode, its judgement, the model and its
/// scores against the true scene or the scan.
pub type FollowRun = scenario::job::follow::FollowRun<SurfaceScore, ModelScanScore>;

/// `run.json` of a simulated surface-following run.
pub type FollowRunSummary = FollowSummary<FollowRunOptions, SurfaceScore, ModelScanScore>;

impl SurfaceFigures for SurfaceScore {
    fn modelled_m2(&self) -> Real {
        self.modelled_m2
    }
}

impl ScanFigures for ModelScanScore {
    fn max_m(&self) -> Option<Real> {
        self.max_m
    }

    fn within_lambda_fraction(&self) -> Real {
        self.within_lambda_fraction
    }

    fn modelled_m2(&self) -> Real {
        self.polygons
            .iter()
            .map(|p| p.area_m2 * p.within_lambda_fraction)
            .sum()
    }
}

/// A run ready to start in the simulator: the setup of any hardware's job,
/// and the rig, the setup's robot and range finders in its world at the
/// start joints.
#[derive(Clone, Debug)]
pub struct SimFollow {
    /// What the job starts from.
    pub job: FollowSetup,
    /// The simulated robot and sensors in the ground-truth world.
    pub rig: SimRig,
}

impl SimFollow {
    /// `job` on a rig: its robot at its start joints in its world, the range
    /// noise `job.noise_sigma_m` drawn from `job.options.seed`.
    pub fn new(job: FollowSetup) -> Result<Self, FollowRunError> {
        let mut rig = SimRig::new(
            job.robot.clone(),
            Arc::clone(&job.world),
            job.world_from_base,
            &job.start_joints,
            None,
            job.options.seed,
        )?;
        rig.set_range_noise_sigma_m(job.noise_sigma_m)?;
        Ok(Self { job, rig })
    }

    /// A run of a scenario in the simulator ([`FollowSetup::from_scenario`]).
    pub fn from_scenario(
        loaded: &LoadedScenario,
        options: &FollowRunOptions,
    ) -> Result<Self, FollowRunError> {
        Self::new(FollowSetup::from_scenario(loaded, options)?)
    }

    /// A run over a scene file in the simulator
    /// ([`FollowSetup::from_scene_file`]).
    pub fn from_scene_file(
        path: &Path,
        scale: Real,
        options: &FollowRunOptions,
    ) -> Result<Self, FollowRunError> {
        Self::new(FollowSetup::from_scene_file(path, scale, options)?)
    }

    /// The follower for this run ([`FollowSetup::follower`]).
    pub fn follower(&self) -> Result<Follower, FollowRunError> {
        self.job.follower()
    }

    /// Run the episode on the rig ([`FollowSetup::run_episode`]), judged by
    /// a [`FollowJudge`], and score the model against the ground truth when
    /// the world is a mesh scene; when it is a point cloud, measure the
    /// links' clearance from the scan points at every pose and the model
    /// polygons' distances to the scan ([`model_to_scan`], with the surface
    /// model's λ). `progress` is called after every step; raising `stop`
    /// ends the run after the current step.
    pub fn run(
        self,
        stop: &AtomicBool,
        progress: &mut dyn FnMut(&StepRow, &Follower),
    ) -> Result<FollowRun, FollowRunError> {
        let Self { job, rig } = self;
        let world = Arc::clone(&job.world);
        let mut judge = FollowJudge::new(
            job.robot.clone(),
            Arc::clone(&world),
            job.world_from_base,
            0.5 * job.options.config.follow.desired_distance_m,
        )?;
        let support_z = job.support_z;
        let bag = job.run_bag()?;
        let mut run: FollowRun = job.run_episode(rig, bag, &mut judge, stop, progress)?;
        let (score, scan_score) = score(&run, support_z, &world, &judge)?;
        run.judgement = judge.judgement();
        run.score = score;
        run.scan_score = scan_score;
        Ok(run)
    }
}

/// The model of `run` scored against the true scene (mesh worlds; faces
/// resting on a support at `support_z` and the a-priori faces not counted)
/// or against the scan points (point-cloud worlds).
fn score(
    run: &FollowRun,
    support_z: Real,
    world: &World,
    judge: &FollowJudge,
) -> Result<(Option<SurfaceScore>, Option<ModelScanScore>), FollowRunError> {
    let model = &run.model;
    let score = match world.as_scene() {
        Some(scene) => {
            let surface = model.config();
            let cfg = SurfaceScoreConfig {
                lambda_m: surface.lambda,
                mu_deg: surface.mu_deg,
                ..SurfaceScoreConfig::default()
            };
            let resting = not_resting_on(support_z);
            let given = &run.a_priori_faces;
            Some(score_surface_model(scene, model, &cfg, &|f: &TrueFace| {
                resting(f) && !given.iter().any(|g| g.face == f.id)
            })?)
        }
        None => None,
    };
    let scan_score = match &judge.scan {
        Some(index) => {
            let cfg = ModelScanConfig {
                lambda_m: model.config().lambda,
                ..ModelScanConfig::default()
            };
            Some(model_to_scan(model, index, &cfg)?)
        }
        None => None,
    };
    Ok((score, scan_score))
}

/// The ground truth's judge of a surface-following run. On a mesh world it
/// checks every pose ([`robot_contacts`]) and the straight joint motion to
/// it ([`motion_contacts`], steps of half the smallest link radius, or
/// [`MOTION_STEP_WITHOUT_CAPSULES_M`]) against the true scene, and keeps the
/// smallest clearance. A point-cloud world has no solid truth: every pose's
/// link clearance from the scan points is measured instead
/// ([`scan_clearance`]), and the poses closer than δ/2 counted.
#[derive(Debug)]
pub struct FollowJudge {
    robot: Robot,
    world: Arc<World>,
    world_from_base: Isometry3,
    /// The scan points of a point-cloud world.
    scan: Option<ScanIndex>,
    motion_step: Real,
    scan_close_m: Real,
    frames: Vec<Isometry3>,
    judgement: Judgement,
    scan_close: usize,
}

impl FollowJudge {
    /// The judge of `robot` standing at `world_from_base` in `world`; poses
    /// closer than `scan_close_m` to a scan point are counted.
    pub fn new(
        robot: Robot,
        world: Arc<World>,
        world_from_base: Isometry3,
        scan_close_m: Real,
    ) -> Result<Self, SimError> {
        let scan = match world.as_ref() {
            World::Cloud(c) => Some(ScanIndex::new(&c.cloud().points)?),
            World::Mesh(_) => None,
        };
        Ok(Self {
            motion_step: smallest_link_radius(&robot)
                .map_or(MOTION_STEP_WITHOUT_CAPSULES_M, |r| 0.5 * r),
            frames: Vec::with_capacity(robot.links.len()),
            robot,
            world,
            world_from_base,
            scan,
            scan_close_m,
            judgement: Judgement::default(),
            scan_close: 0,
        })
    }

    /// What it found so far.
    pub fn judgement(&self) -> Judgement {
        let measured_scan = self.scan.is_some() && self.judgement.min_scan_clearance_m.is_some();
        Judgement {
            scan_close_poses: measured_scan.then_some(self.scan_close),
            ..self.judgement.clone()
        }
    }
}

fn judge_error(e: impl std::error::Error + Send + Sync + 'static) -> FollowError {
    FollowError::Judge(Box::new(e))
}

impl follow::Judge for FollowJudge {
    fn pose(&mut self, step: Option<u64>, q: &[Real]) -> Result<(), FollowError> {
        let scene = self.world.as_scene();
        if scene.is_some() || self.scan.is_some() {
            self.robot.fk_into(q, &mut self.frames)?;
        }
        let j = &mut self.judgement;
        if let Some(s) = &self.scan
            && let Some(d) = scan_clearance(&self.robot, &self.frames, &self.world_from_base, s)
        {
            j.min_scan_clearance_m = Some(j.min_scan_clearance_m.map_or(d, |m: Real| m.min(d)));
            if d < self.scan_close_m {
                self.scan_close += 1;
            }
        }
        if let Some(scene) = scene {
            for c in robot_contacts(&self.robot, &self.frames, &self.world_from_base, scene) {
                j.collisions.push(Collision {
                    step,
                    link: self.robot.links[c.link.0].name.clone(),
                    t: 1.0,
                });
            }
            let d = min_clearance(
                &self.robot,
                &self.frames,
                &self.world_from_base,
                scene,
                CLEARANCE_SEARCH_M,
            );
            j.min_clearance_m = Some(j.min_clearance_m.map_or(d, |m: Real| m.min(d)));
        }
        Ok(())
    }

    fn motion(&mut self, step: u64, a: &[Real], b: &[Real]) -> Result<(), FollowError> {
        let Some(scene) = self.world.as_scene() else {
            return Ok(());
        };
        let m = motion_contacts(
            &self.robot,
            a,
            b,
            &self.world_from_base,
            scene,
            self.motion_step,
        )
        .map_err(judge_error)?;
        self.judgement.motion_checks += m.checks;
        // Both end poses are checked with every link on their own (the start
        // as the previous step's end); here only a contact strictly inside
        // the motion. (`motion_contacts` stops at the first contact, so a
        // motion that starts in contact is not searched further.)
        if let Some(c) = m.first_contact.filter(|c| c.t > 0.0 && c.t < 1.0) {
            self.judgement.collisions.push(Collision {
                step: Some(step),
                link: self.robot.links[c.contact.link.0].name.clone(),
                t: c.t,
            });
        }
        Ok(())
    }
}

/// The whole `surveyor follow` job in the simulator: check the output
/// folder (not a file, not a `surveyor explore` run), run `setup`'s
/// episode, stage the run folder with `scenario_toml` (the scenario as
/// given, for the report's ground truth; none for a scene file), let
/// `finish` add files (the report), and move everything into place,
/// `run.json` last ([`follow_with`]).
pub fn follow(
    setup: SimFollow,
    scenario_toml: Option<String>,
    out: &Path,
    stop: &AtomicBool,
    progress: &mut dyn FnMut(&StepRow, &Follower),
    finish: &mut dyn FnMut(&record::Staging) -> Result<(), String>,
) -> Result<FollowRun, FollowRunError> {
    follow_with(
        scenario_toml,
        out,
        |stop, progress| setup.run(stop, progress),
        stop,
        progress,
        finish,
    )
}
