//! `surveyor explore`: AXBAM exploration (Paul ch. 3, 4, 6) in a simulated
//! world ([`sim::explore_job`]) or on a ROS 2 robot ([`super::on_robot`]),
//! with its outputs in a folder.

use anyhow::{Context, Result, bail};
use clap::Args;
use scenario::job::JobError;
use scenario::job::explore::{ExploreOptions, OracleOption};
use scenario::{RobotChoice, Scenario};
use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;

#[derive(Debug, Args)]
#[command(after_help = "\
Outputs in --out: viewpoints.csv (one row per viewpoint: k, stage, joints, f1-f4, H1, weighted \
H1, H2, H3, the weighted H1 predicted and obtained, candidates, Pareto front, unreachable \
choices, voxels predicted and revealed, A1 coverage so far, joint travel, waypoints, \
decision_ms, plan_ms, sweep_ms, integrate_ms, Stage Two's target disc), cloud.ply (every \
measured point with its ray origin), mesh.ply (the TSDF mesh), discs.csv (the Scale-Like Discs \
of the Stage One mesh with segment, viewpoint, true material, material posterior, H3 and LRC \
observations), segments.json, run.json (viewpoints per stage, terminations, collisions, \
unsafe_configurations with their dist(Q), min_clearance_m, coverage of A1, A2, A3, per \
material and of the observable surfaces, material_accuracy, decision_ms, wall_s, and timings: seconds per phase, which the command also prints at the end; absent with --no-timings), and \
blast_plan.json and blast_plan.csv (Paul App. A: a nozzle pose for every disc in A2 that has one, \
within the tool's angle, stream length and aim limits and dist(Q) > 1 on the final map, the discs \
without one listed, each segment's targets ordered by the GA, with the nearest-neighbour and 2-opt \
costs beside it), \
scenario.toml and blast_inputs.json (what `surveyor plan-blast --run` reads), candidates.csv \
(f1-f4 of every candidate of every Stage One decision, on the Pareto front or not, chosen or \
not), path.csv (the executed motions' waypoints), report.html (`surveyor report`: one page that \
opens offline, a WebGL 3-D view of the run and its plots), \
checkpoint.json, rewritten after every viewpoint of either stage: after an interruption \
(Ctrl-C, kill, power), the same command with --resume continues the run, and with --no-timings \
its outputs are byte-identical to an uninterrupted run's. --resume refuses a checkpoint that was \
edited, or written for another scenario content, robot, seed, --stages or parameters.

Stage Two (the default --stages both) follows Stage One: the scanner is aimed (LM pose \
selection) at the disc with the most material information left that a valid, reachable pose \
can target and whose observation, predicted by simulating the sweep on the Stage One mesh, the \
material classifier can use; the sweep is classified and the beliefs updated, until no disc can \
be targeted or the budget ([explore] stage_two_max_viewpoints) is spent. --stages one stops \
after Stage One.")]
pub struct ExploreArgs {
    /// Built-in scenario (bridge1, bridge2, bridge3) or scenario file.
    #[arg(long, default_value = "bridge1")]
    scenario: String,
    /// Another robot than the scenario's: a built-in name or a URDF file
    /// (FILE.urdf, with --scanner-link). The scenario's start joints must fit
    /// it (a scenario file gives them in `[robot] start_joints`).
    #[arg(long)]
    robot: Option<String>,
    /// With a URDF --robot: the link carrying the scanner (its frame's z axis
    /// is the centre ray); the scenario's `[scanner]` mount applies on it.
    #[arg(long, requires = "robot")]
    scanner_link: Option<String>,
    /// Seed of the scanner noise.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::commands::whole::<u64>, default_value_t = 0)]
    seed: u64,
    /// Most Stage One viewpoints (the start pose's sweep included).
    #[arg(long, allow_negative_numbers = true, value_parser = crate::commands::whole::<usize>)]
    max_viewpoints: Option<usize>,
    /// Stages to run: `one` (geometry) or `both` (then materials).
    #[arg(long, default_value = "both")]
    stages: String,
    /// Where to cache the C-space model [default: a file in the system's
    /// temporary folder named after the robot]; it is rebuilt when its inputs
    /// differ.
    #[arg(long)]
    cspace_cache: Option<PathBuf>,
    /// Where to cache the trained material classifier (LRC) [default: a
    /// file in the system's temporary folder named after the seed]; it is
    /// trained again when its inputs (materials, scanner, constraints,
    /// seed) differ.
    #[arg(long)]
    lrc_cache: Option<PathBuf>,
    /// How Stage One chooses its viewpoints: `information` (the most
    /// information predicted, scanning while the arm moves, links kept
    /// `[explore] stage_one_clearance_m` from measured points) or `thesis`
    /// (Paul's rank sum on the Pareto front, scans at viewpoints only,
    /// dist(Q) > 1 alone).
    #[arg(long, default_value = "information")]
    stage_one: String,
    /// Skip the coverage and material oracles (run.json's coverage.oracle:
    /// what greedy sweeps chosen knowing the true scene cover; and with
    /// Stage Two, material_identification.oracle: what greedy viewpoints
    /// chosen knowing the true scene identify; each computed once per scene,
    /// robot and scanner and cached).
    #[arg(long)]
    no_oracle: bool,
    /// Where to cache the coverage oracle [default: a file in the system's
    /// temporary folder named after the scenario]; it is computed again when
    /// its inputs differ. The material oracle is cached beside it
    /// (`<stem>-materials.json`).
    #[arg(long)]
    oracle_cache: Option<PathBuf>,
    /// Write zeros in the time columns so outputs are byte-identical run to run.
    #[arg(long)]
    no_timings: bool,
    /// Continue the interrupted run whose checkpoint is in --out (same
    /// scenario, seed and parameters): the viewpoints recorded there are
    /// replayed and the run goes on as if never stopped.
    #[arg(long)]
    resume: bool,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    ros2: super::on_robot::Ros2Flags,
}

pub fn explore(args: &ExploreArgs) -> Result<()> {
    if args.max_viewpoints == Some(0) {
        bail!("--max-viewpoints 0: expected at least 1 (the start pose's sweep is one)");
    }
    let stage_two = match args.stages.as_str() {
        "one" => false,
        "both" => true,
        other => bail!("--stages {other}: expected `one` or `both`"),
    };
    let mut loaded = Scenario::load(&args.scenario)?;
    if let Some(robot) = &args.robot {
        let choice = RobotChoice::parse(robot, args.scanner_link.as_deref())?;
        match (&choice, &args.scanner_link) {
            (RobotChoice::Urdf { .. }, None) => {
                bail!("--robot FILE.urdf needs --scanner-link LINK (the link carrying the scanner)")
            }
            (RobotChoice::Builtin(_), Some(_)) => {
                bail!("--scanner-link applies to URDF robots; `{robot}` is a built-in robot")
            }
            _ => {}
        }
        loaded
            .set_robot(&choice)
            .with_context(|| format!("--robot {robot}"))?;
        let dof = loaded.build_robot()?.dof();
        if dof != loaded.scenario.robot.start_joints.len() {
            bail!(
                "--robot {robot} has {dof} joints but the scenario's start pose has {}: give the start pose in a scenario file ([robot] start_joints)",
                loaded.scenario.robot.start_joints.len()
            );
        }
    }
    if loaded.scenario.robot.urdf.is_some() {
        super::warn_about(&loaded.build_robot()?);
    }
    let options = run_options(args, &loaded, stage_two)?;
    let t = std::time::Instant::now();
    let (hardware, live) = super::on_robot::connect_explore(&args.ros2, &loaded)?.unzip();
    let start_tolerance = args
        .ros2
        .start_tolerance(&loaded.scenario.ros2.clone().unwrap_or_default());
    let watcher = live.clone();
    let make = |options: &ExploreOptions| job(&loaded, options, hardware, watcher, start_tolerance);
    let (outcome, blast) = scenario::job::explore::explore_with(
        &options,
        &args.out,
        make,
        &mut |r| {
            note!(
                "stage {}, viewpoint {:>2}: H1 {:>9.1} (weighted {:>8.1}), H2 {:>7.3}, H3 {}, revealed {:>6}, A1 covered {}, {} candidates, decision {:>6.0} ms",
                r.stage,
                r.k,
                r.h1,
                r.h1_weighted,
                r.h2,
                r.h3.map_or("-".into(), |h| format!("{h:.0}")),
                r.revealed,
                r.coverage_a1
                    .map_or("-".into(), |c| format!("{:.1} %", 100.0 * c)),
                r.candidates,
                r.decision_ms
            );
        },
        &mut report::in_two_steps,
    )?;
    let run = &outcome.run;
    let summary = outcome.summary();
    let per_stage = |k: u8| run.viewpoints.iter().filter(|r| r.stage == k).count();
    say!(
        "{}: stage one ended ({}) after {} viewpoints; {}, {} unsafe configurations (both stages), {}; C-space model {}",
        loaded.scenario.name,
        summary.termination,
        per_stage(1),
        summary.collisions.map_or_else(
            || "collisions not judged (no true surfaces)".to_owned(),
            |c| format!("{c} collisions")
        ),
        run.unsafe_configurations.len(),
        summary.min_clearance_m.map_or_else(
            || "clearance not judged".to_owned(),
            |m| format!("min clearance {m:.3} m")
        ),
        run.cspace
    )?;
    if let Some(lrc) = &run.lrc {
        say!("material classifier (LRC) {lrc}")?;
    }
    if summary.termination == explore::Termination::NoSafeCandidate.name() {
        let local = loaded
            .scenario
            .explore
            .as_ref()
            .map_or(explore::ExploreConfig::default().local_candidates, |e| {
                e.local_candidates
            });
        say!(
            "no contending viewpoint had a safe sweep and a safe path from the arm's last pose{}",
            if local == 0 {
                ": [explore] local_candidates = 0 leaves only the roadmap's nodes (Paul's \
                 method), whose sweeps from a crouched start reach space not yet seen"
            } else {
                ""
            }
        )?;
    }
    if let Some(end) = &run.stage_two_termination {
        say!(
            "stage two ended ({end}) after {} viewpoints; material right on {} of the discs the LRC observed",
            per_stage(2),
            run.discs.material_accuracy().map_or_else(
                || {
                    if args.ros2.ros2 {
                        "(not judged: no true materials)".into()
                    } else {
                        "none".into()
                    }
                },
                |a| format!("{:.1} %", 100.0 * a)
            )
        )?;
    }
    say_coverage(&outcome)?;
    if let Some(live) = &live {
        super::on_robot::publish_markers(live, &loaded, run)?;
    }
    if let Some(plan) = &blast {
        say!("{}", plan.summary())?;
    }
    say!(
        "report: {}",
        args.out.join(record::folder::REPORT_HTML).display()
    )?;
    say!(
        "{} points, mesh of {} triangles; {:.1} s; outputs in {}",
        run.cloud.len(),
        run.mesh.triangles.len(),
        t.elapsed().as_secs_f64(),
        args.out.display()
    )?;
    say!(
        "robot time (run.json's robot_time_s): {}",
        record::explore::RobotTimeSummary::of(&run.viewpoints)
    )?;
    if let Some(timings) = &run.timings {
        say!(
            "where the time went (run.json's timings):\n{}",
            timings.table()
        )?;
    }
    Ok(())
}

/// The coverage of the true surfaces, the observable share and the oracle,
/// when the world has true surfaces.
fn say_coverage(outcome: &scenario::job::explore::ExploreOutcome) -> Result<()> {
    if let Some(c) = &outcome.coverage {
        say!(
            "coverage of the true surfaces: A1 {:.1} %, A2 {:.1} %, A3 {:.1} %",
            100.0 * c[0].fraction(),
            100.0 * c[1].fraction(),
            100.0 * c[2].fraction()
        )?;
        if let Some((n, covered)) = outcome.observable.first() {
            say!(
                "A1 surfaces observable from some collision-free roadmap pose: {:.1} % of them; {:.1} % of those covered",
                100.0 * *n as f64 / c[0].samples.max(1) as f64,
                100.0 * *covered as f64 / (*n).max(1) as f64
            )?;
        }
    }
    if let Some(o) = outcome.coverage_summary().and_then(|c| c.oracle) {
        say!(
            "coverage oracle (greedy sweeps knowing the true scene): A1 {:.1} % after 12 sweeps, {:.1} % after {}; Stage One {:.0} % of its 12-sweep coverage after 12 viewpoints, {:.0} % at its end",
            100.0 * o.a1_after_12,
            100.0 * o.a1_after_stage_one_viewpoints,
            o.stage_one_viewpoints,
            100.0 * o.ratio_after_12,
            100.0 * o.ratio_at_stage_one_end
        )?;
    }
    if let Some(m) = &outcome.material_identification {
        let percent =
            |r: Option<f64>| r.map_or_else(|| "–".to_owned(), |r| format!("{:.0} %", 100.0 * r));
        say!(
            "material oracle (viewpoints chosen knowing the true scene): {:.1} % of A2 identifiable, {:.1} % after 10 viewpoints, {:.1} % after {}; the run identified {:.1} % ({} discs at p ≥ 0.8, {} right): {} of the identifiable, {} of the oracle after 10, {} after as many",
            100.0 * m.oracle.identifiable,
            100.0 * m.oracle_after_10,
            100.0 * m.oracle_after_stage_two_viewpoints,
            m.stage_two_viewpoints,
            100.0 * m.identified,
            m.discs_identified,
            percent(m.accuracy),
            percent(m.ratio_to_identifiable),
            percent(m.ratio_after_10),
            percent(m.ratio_after_stage_two_viewpoints)
        )?;
    }
    Ok(())
}

/// The exploration of `loaded` under `options`: on `hardware` when given,
/// else in the simulator.
fn job(
    loaded: &scenario::LoadedScenario,
    options: &ExploreOptions,
    hardware: Option<ros2::Ros2Hardware>,
    live: Option<Rc<RefCell<ros2::LiveView>>>,
    start_tolerance: geom::Real,
) -> Result<Job, JobError> {
    Ok(match hardware {
        Some(hw) => Job::Hardware(Box::new(super::on_robot::explore_job(
            loaded,
            options,
            hw,
            live,
            start_tolerance,
        )?)),
        None => Job::Sim(Box::new(sim::explore_job::SimExplore::new(
            loaded, options,
        )?)),
    })
}

/// The exploration of the simulator, or of a ROS 2 robot.
enum Job {
    Sim(Box<sim::explore_job::SimExplore>),
    Hardware(Box<scenario::job::explore::HardwareExplore<ros2::Ros2Hardware>>),
}

impl scenario::job::explore::ExploreJob for Job {
    fn run_job(
        self,
        progress: &mut dyn FnMut(&record::ViewpointRecord),
    ) -> Result<scenario::job::explore::ExploreOutcome, JobError> {
        match self {
            Self::Sim(j) => j.run(progress),
            Self::Hardware(j) => j.run(progress),
        }
    }
}

/// How to run: the caches (given, or the defaults), seed, budget, stages.
fn run_options(
    args: &ExploreArgs,
    loaded: &scenario::LoadedScenario,
    stage_two: bool,
) -> Result<ExploreOptions> {
    let cspace_cache = match &args.cspace_cache {
        Some(path) => path.clone(),
        None => ExploreOptions::default_cspace_cache(loaded)?,
    };
    let Some(config) = ExploreOptions::stage_one_config(loaded, &args.stage_one) else {
        bail!(
            "--stage-one {}: expected `information` or `thesis`",
            args.stage_one
        );
    };
    Ok(ExploreOptions {
        seed: args.seed,
        max_viewpoints: args.max_viewpoints,
        config,
        // A ROS 2 robot's world is not known: no oracle.
        oracle: if args.no_oracle || args.ros2.ros2 {
            OracleOption::Off
        } else {
            OracleOption::On(Some(
                args.oracle_cache
                    .clone()
                    .unwrap_or_else(|| ExploreOptions::default_oracle_cache(loaded)),
            ))
        },
        cspace_cache: Some(cspace_cache),
        lrc_cache: Some(
            args.lrc_cache
                .clone()
                .unwrap_or_else(|| ExploreOptions::default_lrc_cache(args.seed)),
        ),
        timings: !args.no_timings,
        resume: args.resume,
        stage_two,
        ..ExploreOptions::default()
    })
}
