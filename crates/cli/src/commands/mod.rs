//! Argument definitions and the one library call behind each command.

mod blast;
mod explore;
mod follow;
mod maps;
mod mjcf;
mod model;
mod on_robot;
mod output;
mod robot_server;

use anyhow::{Context, Result, anyhow, bail};
use clap::{Args, Parser, Subcommand};
use geom::Real;
use geom::math::isometry_to_rows;
use indicatif::{ProgressBar, ProgressStyle};
use output::Staged;
use scenario::{BUILTIN_NAMES, LoadedScenario, RobotChoice, Scenario, builtin_scenario};
use serde::Serialize;
use sim::scan_job::ScanSetup;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Explore an unknown structure with a robot and range sensors, and build a model
/// of its surfaces (Pudney 1994 surface following; Paul 2010 AXBAM exploration).
#[derive(Debug, Parser)]
#[command(
    name = "surveyor",
    version,
    propagate_version = true,
    args_override_self = true
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// List the built-in scenarios or print one as a TOML scenario file.
    #[command(subcommand)]
    Scenario(ScenarioCmd),
    /// Forward kinematics: the pose of every link frame for given joint values.
    Fk(FkArgs),
    /// One tilt sweep of the laser scanner from a pose, written as PLY and scored
    /// against the ground truth.
    Scan(ScanArgs),
    /// Bulk ray casting: first-hit distance of every ray in a binary file.
    Raycast(RaycastArgs),
    /// Write the ray-casting benchmark workload (structure mesh and rays).
    RaycastFixture(FixtureArgs),
    /// Fuse scan files into the occupancy grid and the TSDF mesh (Paul §4.2, §5.1.1).
    Map(maps::MapArgs),
    /// Scale-Like Discs of a point cloud (Paul §5.2).
    Sld(maps::SldArgs),
    /// Segment a disc map into surfaces (Paul §5.3, Algorithm 1).
    Segment(maps::SegmentArgs),
    /// Pudney's incremental surface model from a stream of sensor sets (P ch. 2).
    Model(model::ModelArgs),
    /// Pudney's surface following (P ch. 3) in a simulated world: the model, the
    /// steps, the path and a run summary scored against the ground truth.
    Follow(Box<follow::FollowArgs>),
    /// AXBAM exploration (Paul ch. 3, 4, 6): information-driven viewpoints over
    /// the voxel map and the arm's configuration space, moving only through
    /// known free space; the viewpoints, cloud, mesh and a run summary.
    Explore(explore::ExploreArgs),
    /// The grit-blasting plan over an explore run's map (Paul App. A): a nozzle
    /// pose per disc in A2, each segment's targets ordered by the GA.
    PlanBlast(blast::PlanBlastArgs),
    /// Write RUN_DIR/report.html: one self-contained page (works offline)
    /// with a WebGL 3-D view of the run and the plots of its series.
    Report(ReportArgs),
    /// The simulator as a ROS 2 robot (--ros2): a scenario's robot publishes its
    /// joint states, scans and range readings and executes joint trajectories.
    SimRobot(robot_server::SimRobotArgs),
}

#[derive(Debug, Args)]
struct ReportArgs {
    /// A run folder written by `surveyor explore` or `surveyor follow`.
    run_dir: PathBuf,
}

#[derive(Debug, Subcommand)]
enum ScenarioCmd {
    /// List the built-in scenarios.
    List,
    /// Print a scenario (built-in name or file) as TOML: edit it to make your own.
    Show {
        /// Built-in name or scenario file.
        name: String,
    },
    /// Write the scenario as a MuJoCo model (MJCF): the arm's chain with
    /// masses, armature and torque limits, its scanner, tool and range
    /// finders as sites, the scene's solids as geoms; and beside it
    /// (FILE.json) what a physics robot serving it over ROS 2 needs.
    Mjcf(mjcf::MjcfArgs),
}

/// Joint values given on the command line.
#[derive(Debug, Args)]
struct JointArgs {
    /// Joint values, comma separated: radians (metres for prismatic joints).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, num_args = 1)]
    joints: Option<Vec<Real>>,
    /// Read --joints as degrees (revolute joints; prismatic joints stay in metres).
    #[arg(long)]
    deg: bool,
}

impl JointArgs {
    /// The joint values in radians and metres: with `--deg`, the values of
    /// `robot`'s revolute joints are converted, its prismatic joints' kept
    /// (`robot` is built only then).
    fn values(&self, robot: impl FnOnce() -> Result<robot::Robot>) -> Result<Option<Vec<Real>>> {
        let Some(q) = &self.joints else {
            if self.deg {
                bail!("--deg applies to --joints, which is not given");
            }
            return Ok(None);
        };
        let robot = robot()?;
        let kinds: Vec<robot::JointKind> = robot
            .joints
            .iter()
            .filter(|j| j.is_actuated())
            .map(|j| j.kind)
            .collect();
        let mut out = Vec::with_capacity(q.len());
        for (i, v) in q.iter().enumerate() {
            let prismatic = matches!(kinds.get(i), Some(robot::JointKind::Prismatic));
            let value = if self.deg && !prismatic {
                v.to_radians()
            } else {
                *v
            };
            // Issue 48: `fk --deg` took 1e308 as it was.
            let (limit, what) = if prismatic {
                (MAX_PRISMATIC_JOINT_M, "1000 m")
            } else if self.deg {
                (MAX_REVOLUTE_JOINT_RAD, "720° (two turns)")
            } else {
                (MAX_REVOLUTE_JOINT_RAD, "4π rad (two turns)")
            };
            // (Not finite: the robot's own check names the joint.)
            if value.is_finite() && value.abs() > limit {
                bail!("--joints value {} ({v}) is beyond ±{what}", i + 1);
            }
            out.push(value);
        }
        Ok(Some(out))
    }
}

/// Largest revolute joint value `--joints` takes, radians (two turns either
/// way, past any arm's joint range).
const MAX_REVOLUTE_JOINT_RAD: Real = 4.0 * std::f64::consts::PI;
/// Largest prismatic joint value `--joints` takes, metres.
const MAX_PRISMATIC_JOINT_M: Real = 1000.0;

#[derive(Debug, Args)]
struct FkArgs {
    /// Built-in robot name (denso-vm6083, point3, arm4) or a URDF file.
    #[arg(long)]
    robot: String,
    /// For a URDF: the link to treat as the tip (default: the chain's leaf).
    #[arg(long)]
    tip: Option<String>,
    #[command(flatten)]
    joints: JointArgs,
    /// Print one JSON object: "tip", "frames" [{name, pose}], "sensor" (4×4
    /// row-major base-frame transforms).
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
struct ScanArgs {
    /// Built-in scenario name or scenario file (its robot, base pose and
    /// scanner; --robot, --tip and --base-* belong to --scene).
    #[arg(
        long,
        conflicts_with_all = ["scene", "robot", "tip", "base_xyz", "base_rpy_deg"]
    )]
    scenario: Option<String>,
    /// A mesh (OBJ, STL, PLY) or point cloud (PCD, PLY, text) placed as-is in the
    /// world frame, instead of a scenario.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// With --scene: built-in robot name or URDF file (default denso-vm6083).
    #[arg(long)]
    robot: Option<String>,
    /// With --scene and a URDF --robot: the link to treat as the tip (default:
    /// the chain's leaf); the scanner is mounted on it.
    #[arg(long)]
    tip: Option<String>,
    /// With --scene: where the robot base stands in the world, metres.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, num_args = 1)]
    base_xyz: Option<Vec<Real>>,
    /// With --scene: base orientation, roll/pitch/yaw in degrees (fixed axes x, y, z).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, num_args = 1)]
    base_rpy_deg: Option<Vec<Real>>,
    #[command(flatten)]
    joints: JointArgs,
    /// Total tilt of the sweep, degrees (default: the scenario's, 60).
    #[arg(long, allow_negative_numbers = true)]
    tilt_deg: Option<Real>,
    /// Seed of the sensor noise.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::commands::whole::<u64>, default_value_t = 0)]
    seed: u64,
    /// Output PLY (vertex properties x y z intensity ox oy oz scan ray material;
    /// see `sensor::scan_file`). A missing folder is created.
    #[arg(long)]
    out: PathBuf,
}

#[derive(Debug, Args)]
struct RaycastArgs {
    /// The mesh to cast against (OBJ, STL, PLY).
    #[arg(long)]
    scene: PathBuf,
    /// Rays: little-endian f32, six per ray (origin xyz, unit direction xyz).
    #[arg(long)]
    rays: PathBuf,
    /// Output: one little-endian f32 per ray, the first-hit distance, +inf on a miss.
    #[arg(long)]
    out: PathBuf,
    /// Worker threads, 1 to 256 (default: all cores).
    #[arg(long, allow_negative_numbers = true, value_parser = crate::commands::whole::<usize>)]
    threads: Option<usize>,
    /// Casts of the whole batch; the median time is reported (median of 5
    /// after the BVH build, the protocol the Embree comparison of the README
    /// uses), 1 to 1000.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::commands::whole::<usize>, default_value_t = 5)]
    repeat: usize,
}

#[derive(Debug, Args)]
struct FixtureArgs {
    /// Folder to write `structure.ply` and `rays.bin` into.
    #[arg(long)]
    out: PathBuf,
    /// Number of rays (at most scene::fixtures::MAX_FIXTURE_RAYS, 10 million).
    #[arg(long, allow_negative_numbers = true, value_parser = crate::commands::whole::<usize>, default_value_t = 1_000_000)]
    rays: usize,
    /// Seed of the ray directions and origins.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::commands::whole::<u64>, default_value_t = 1)]
    seed: u64,
}

/// A whole number ≥ 0 from the command line, refused with a message that
/// says so (clap's own parser takes `-1` for another flag).
pub(crate) fn whole<T: std::str::FromStr>(s: &str) -> Result<T, String> {
    s.trim()
        .parse::<T>()
        .map_err(|_| format!("expected a whole number ≥ 0, got `{s}`"))
}

/// Most worker threads `raycast` starts.
const MAX_THREADS: usize = 256;
/// Most casts `raycast --repeat` takes.
const MAX_REPEAT: usize = 1000;

/// Run a parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Scenario(ScenarioCmd::List) => {
            for name in BUILTIN_NAMES {
                let s = builtin_scenario(name).ok_or_else(|| anyhow!("missing built-in {name}"))?;
                say!("{name:<10} {}", s.description)?;
            }
            Ok(())
        }
        Command::Scenario(ScenarioCmd::Show { name }) => {
            let loaded = Scenario::load(&name)?;
            put!("{}", loaded.scenario.to_toml()?)?;
            Ok(())
        }
        Command::Scenario(ScenarioCmd::Mjcf(a)) => mjcf::mjcf(&a),
        Command::Fk(a) => fk(&a),
        Command::Scan(a) => scan(&a),
        Command::Raycast(a) => raycast(&a),
        Command::RaycastFixture(a) => raycast_fixture(&a),
        Command::Map(a) => maps::map(&a),
        Command::Sld(a) => maps::sld(&a),
        Command::Segment(a) => maps::segment(&a),
        Command::Model(a) => model::model(&a),
        Command::Report(a) => {
            let path = report::write(&a.run_dir)?;
            say!("{}", path.display())?;
            Ok(())
        }
        Command::Follow(a) => follow::follow(&a),
        Command::Explore(a) => explore::explore(&a),
        Command::PlanBlast(a) => blast::plan_blast(&a),
        Command::SimRobot(a) => robot_server::sim_robot(&a),
    }
}

#[derive(Serialize)]
struct NamedPose {
    name: String,
    pose: [[Real; 4]; 4],
}

#[derive(Serialize)]
struct FkOutput {
    tip: [[Real; 4]; 4],
    frames: Vec<NamedPose>,
    #[serde(skip_serializing_if = "Option::is_none")]
    sensor: Option<[[Real; 4]; 4]>,
    /// Joints outside their limits (empty when the pose is within them).
    outside_limits: Vec<LimitViolation>,
}

/// A joint value outside its limits (radians, or metres for prismatic joints).
#[derive(Serialize)]
struct LimitViolation {
    joint: String,
    index: usize,
    value: Real,
    min: Real,
    max: Real,
    message: String,
}

/// Print what reading the robot's URDF noted (a joint without limits, a
/// mesh not read) to stderr.
fn warn_about(robot: &robot::Robot) {
    for w in &robot.warnings {
        note!("warning: {w}");
    }
}

fn fk(a: &FkArgs) -> Result<()> {
    let robot = RobotChoice::parse(&a.robot, a.tip.as_deref())?.build()?;
    warn_about(&robot);
    let q = a
        .joints
        .values(|| Ok(robot.clone()))?
        .ok_or_else(|| anyhow!("--joints is required ({} values)", robot.dof()))?;
    let frames = robot.forward_kinematics(&q)?;
    let out = FkOutput {
        tip: isometry_to_rows(&robot.tool_pose(&q)?),
        frames: robot
            .links
            .iter()
            .zip(&frames)
            .map(|(l, f)| NamedPose {
                name: l.name.clone(),
                pose: isometry_to_rows(f),
            })
            .collect(),
        sensor: robot.scanner_pose(&q)?.map(|p| isometry_to_rows(&p)),
        outside_limits: robot
            .limit_violations(&q)
            .into_iter()
            .filter_map(|e| match &e {
                robot::RobotError::OutsideLimits {
                    joint,
                    index,
                    value,
                    min,
                    max,
                    ..
                } => Some(LimitViolation {
                    joint: joint.clone(),
                    index: *index,
                    value: *value,
                    min: *min,
                    max: *max,
                    message: e.to_string(),
                }),
                _ => None,
            })
            .collect(),
    };
    if a.json {
        say!("{}", serde_json::to_string(&out)?)?;
    } else {
        let show = |name: &str, m: &[[Real; 4]; 4]| {
            say!(
                "{name:<16} xyz [{:+.6}, {:+.6}, {:+.6}]  z-axis [{:+.4}, {:+.4}, {:+.4}]",
                m[0][3],
                m[1][3],
                m[2][3],
                m[0][2],
                m[1][2],
                m[2][2]
            )
        };
        for f in &out.frames {
            show(&f.name, &f.pose)?;
        }
        show("tip", &out.tip)?;
        if let Some(s) = &out.sensor {
            show("scanner", s)?;
        }
        for v in &out.outside_limits {
            say!("warning: {}", v.message)?;
        }
    }
    Ok(())
}

/// `--skip-bad-messages` as the bag reader's choice.
fn bad_messages(skip: bool) -> record::bag::BadMessages {
    if skip {
        record::bag::BadMessages::Skip
    } else {
        record::bag::BadMessages::Refuse
    }
}

/// Skips [`say_skipped`] lists one by one; the rest are counted.
const SHOWN: usize = 10;

/// Say what reading the bag at `path` skipped (nothing when nothing was).
fn say_skipped(path: &Path, skipped: &record::bag::Skipped) -> Result<()> {
    if skipped.what.is_empty() {
        return Ok(());
    }
    say!(
        "{}: skipped {} messages ({} damaged chunks and bad messages):",
        path.display(),
        skipped.messages,
        skipped.what.len()
    )?;
    for what in skipped.what.iter().take(SHOWN) {
        say!("  {what}")?;
    }
    if skipped.what.len() > SHOWN {
        say!("  and {} more", skipped.what.len() - SHOWN)?;
    }
    Ok(())
}

fn progress_bar(len: u64, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    if let Ok(style) = ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} {elapsed}") {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_message(what.to_owned());
    pb
}

fn scan(a: &ScanArgs) -> Result<()> {
    let t0 = Instant::now();
    let setup = match (&a.scenario, &a.scene) {
        (_, Some(file)) => {
            let robot = a.robot.as_deref().unwrap_or("denso-vm6083");
            let q = a
                .joints
                .values(|| Ok(RobotChoice::parse(robot, a.tip.as_deref())?.build()?))?
                .ok_or_else(|| anyhow!("--joints is required with --scene"))?;
            let base = scene::PoseSpec {
                translation: three(a.base_xyz.as_deref(), "--base-xyz", "metres", 1e6)?,
                rpy_deg: three(a.base_rpy_deg.as_deref(), "--base-rpy-deg", "degrees", 1e6)?,
            };
            ScanSetup::from_scene_file(
                file,
                robot,
                a.tip.as_deref(),
                base.isometry(),
                q,
                a.tilt_deg,
                a.seed,
            )?
        }
        (Some(name), None) => {
            let loaded: LoadedScenario = Scenario::load(name)?;
            if loaded.scenario.scanner.is_none()
                && matches!(
                    loaded.scenario.robot.preset.as_deref(),
                    Some("point3" | "arm4")
                )
            {
                bail!(
                    "{name} is a surface-following scenario (Pudney): its {} robot carries \
                     single-point range finders, not a laser scanner. It is for `surveyor \
                     follow`; `scan` sweeps the scanner of the AXBAM scenarios (bridge1, \
                     bridge2, bridge3) or of a robot on a --scene",
                    loaded.scenario.robot.preset.as_deref().unwrap_or("")
                );
            }
            let q = a.joints.values(|| Ok(loaded.build_robot()?))?;
            ScanSetup::from_scenario(&loaded, q, a.tilt_deg, a.seed)?
        }
        (None, None) => bail!("give --scenario NAME|FILE or --scene FILE"),
    };
    warn_about(&setup.robot);
    let t_setup = t0.elapsed();
    let pb = progress_bar(setup.sweep.scan_count() as u64, "sweeping");
    let t1 = Instant::now();
    let outcome = setup.run(&mut |done, _| pb.set_position(done as u64))?;
    pb.finish_and_clear();
    let t_sweep = t1.elapsed();
    let mut staged = Staged::new();
    outcome
        .sweep
        .write_ply(&staged.file(&a.out)?)
        .with_context(|| format!("writing {}", a.out.display()))?;
    let sweep = &outcome.sweep;
    let shape = sweep.grid_shape().unwrap_or(sensor::GridShape {
        scans: 0,
        rays_per_scan: 0,
    });
    say!(
        "{} points from {} scans × {} rays ({:.0}° tilt) → {}",
        sweep.len(),
        shape.scans,
        shape.rays_per_scan,
        setup.sweep.tilt_deg,
        a.out.display()
    )?;
    if let scene::World::Cloud(c) = setup.world.as_ref() {
        say!(
            "the world is a point cloud of {} points, hit by the ε rule with ε = {:.4} m (P§4.2)",
            c.cloud().points.len(),
            c.epsilon()
        )?;
    }
    for c in &outcome.contacts {
        let object = setup
            .world
            .as_scene()
            .and_then(|s| s.object(c.object))
            .map_or_else(|| format!("{}", c.object.0), |o| format!("'{}'", o.name));
        say!(
            "WARNING: link {} ({}) touches the scene (object {object})",
            c.link,
            setup.robot.links[c.link.0].name,
        )?;
    }
    let t2 = Instant::now();
    let spinner = ProgressBar::new_spinner();
    spinner.set_message("scoring against the ground truth");
    spinner.enable_steady_tick(std::time::Duration::from_millis(100));
    let scores = setup.score(sweep);
    spinner.finish_and_clear();
    let scores = scores?;
    staged.commit()?;
    let t_score = t2.elapsed();
    match scores {
        Some(s) => {
            let cov = &s.coverage;
            let region = cov.region.map_or_else(
                || "whole scene".to_owned(),
                |r| {
                    format!(
                        "[{:.2},{:.2}]×[{:.2},{:.2}]×[{:.2},{:.2}]",
                        r.min.x, r.max.x, r.min.y, r.max.y, r.min.z, r.max.z
                    )
                },
            );
            say!(
                "coverage {:.1}% of {} true-surface samples within {:.0} mm (exposed faces in {region})",
                100.0 * cov.fraction(),
                cov.samples,
                1000.0 * cov.covered_within_m
            )?;
            for m in &cov.per_material {
                say!(
                    "  {:<16} {:5.1}% of {}",
                    m.material,
                    100.0 * m.covered as Real / m.samples.max(1) as Real,
                    m.samples
                )?;
            }
            if cov.density_capped {
                say!(
                    "  (sampled at {:.0} per m², lowered to keep within metrics.sampling.max_samples)",
                    cov.samples_per_m2
                )?;
            }
            say!("accuracy: {}", s.accuracy)?;
        }
        None => say!("(point-cloud world: no true surface to score against)")?,
    }
    say!(
        "time: setup {:.3} s, sweep {:.3} s, scoring {:.3} s",
        t_setup.as_secs_f64(),
        t_sweep.as_secs_f64(),
        t_score.as_secs_f64()
    )?;
    Ok(())
}

/// Three comma-separated values of `flag`, each finite and within `±limit`
/// (`[0, 0, 0]` when the flag is absent).
fn three(v: Option<&[Real]>, flag: &str, unit: &str, limit: Real) -> Result<[Real; 3]> {
    match v {
        None => Ok([0.0; 3]),
        Some(&[x, y, z]) => {
            for (axis, value) in ["first", "second", "third"].iter().zip([x, y, z]) {
                if !(value.is_finite() && value.abs() <= limit) {
                    bail!(
                        "{flag}: the {axis} value is {value}; expected a finite number of {unit} within ±{limit:e}"
                    );
                }
            }
            Ok([x, y, z])
        }
        Some(other) => bail!(
            "{flag} takes three comma-separated values, got {}",
            other.len()
        ),
    }
}

fn read_rays(path: &Path) -> Result<Vec<[f32; 6]>> {
    Ok(scene::io::rays::read_rays(path)?)
}

fn raycast(a: &RaycastArgs) -> Result<()> {
    let t0 = Instant::now();
    let mesh = scene::io::load_mesh(&a.scene, 1.0)?;
    let t_load = t0.elapsed();
    let t1 = Instant::now();
    let n_tris = mesh.len();
    let scene = scene::Scene::from_mesh(
        "scene",
        mesh,
        scene::default_materials(),
        scene::MaterialId(0),
    )?;
    let t_build = t1.elapsed();
    let rays = read_rays(&a.rays)?;
    if rays.is_empty() {
        bail!("{}: no rays", a.rays.display());
    }
    let mut out = vec![0f32; rays.len()];
    let threads = match a.threads {
        None => rayon::current_num_threads().max(1),
        Some(t @ 1..=MAX_THREADS) => t,
        Some(t) => bail!("--threads {t}: expected 1 to {MAX_THREADS}"),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("starting the thread pool")?;
    if !(1..=MAX_REPEAT).contains(&a.repeat) {
        bail!("--repeat {}: expected 1 to {MAX_REPEAT}", a.repeat);
    }
    let mut times = Vec::with_capacity(a.repeat);
    for _ in 0..a.repeat {
        let t2 = Instant::now();
        pool.install(|| scene.cast_rays_f32(&rays, f32::INFINITY, &mut out));
        times.push(t2.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let t_cast = times[times.len() / 2];
    let bytes: Vec<u8> = out.iter().flat_map(|d| d.to_le_bytes()).collect();
    let mut staged = Staged::new();
    std::fs::write(staged.file(&a.out)?, bytes)
        .with_context(|| format!("writing {}", a.out.display()))?;
    staged.commit()?;
    let hits = out.iter().filter(|d| d.is_finite()).count();
    say!(
        "{} rays against {} triangles on {} thread{}: {:.3} s, {:.2} Mrays/s ({} hits; median of {} casts)",
        rays.len(),
        n_tris,
        threads,
        if threads == 1 { "" } else { "s" },
        t_cast,
        rays.len() as f64 / t_cast.max(1e-12) / 1e6,
        hits,
        times.len()
    )?;
    say!(
        "time: load {:.3} s, BVH build {:.3} s",
        t_load.as_secs_f64(),
        t_build.as_secs_f64()
    )?;
    Ok(())
}

fn raycast_fixture(a: &FixtureArgs) -> Result<()> {
    // Checked before anything is written, so a refused count leaves no files.
    let rays = scene::fixtures::incoherent_rays_checked(a.rays, a.seed).context("--rays")?;
    let mut staged = Staged::new();
    staged.ensure_dir(&a.out)?;
    let mesh = scene::fixtures::benchmark_structure();
    let mesh_path = a.out.join("structure.ply");
    scene::io::write_mesh_ply(&staged.file(&mesh_path)?, &mesh)?;
    let rays_path = a.out.join("rays.bin");
    scene::io::rays::write_rays(&staged.file(&rays_path)?, &rays)?;
    staged.commit()?;
    say!(
        "{} ({} triangles), {} ({} rays)",
        mesh_path.display(),
        mesh.len(),
        rays_path.display(),
        rays.len()
    )?;
    Ok(())
}
