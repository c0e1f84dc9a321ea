//! `surveyor explore`: AXBAM exploration (Paul ch. 3, 4, 6) in a simulated
//! world ([`sim::explore_run`]), with its outputs in a folder.

use anyhow::{Context, Result, bail};
use clap::Args;
use sim::Scenario;
use sim::explore_run::{ExploreOptions, run_exploration};
use std::path::PathBuf;

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
material and of the observable surfaces, material_accuracy, decision_ms, wall_s), and \
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
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Most Stage One viewpoints (the start pose's sweep included).
    #[arg(long)]
    max_viewpoints: Option<usize>,
    /// Stages to run: `one` (geometry) or `both` (then materials).
    #[arg(long, default_value = "both")]
    stages: String,
    /// Where to cache the C-space model [default: a file in the system's
    /// temporary folder named after the robot]; it is rebuilt when its inputs
    /// differ.
    #[arg(long)]
    cspace_cache: Option<PathBuf>,
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
        let spec = &mut loaded.scenario.robot;
        if robot.to_ascii_lowercase().ends_with(".urdf") {
            let link = args.scanner_link.clone().context(
                "--robot FILE.urdf needs --scanner-link LINK (the link carrying the scanner)",
            )?;
            let path = std::fs::canonicalize(robot)
                .with_context(|| format!("--robot {robot}: cannot read the URDF file"))?;
            spec.preset = None;
            spec.urdf = Some(path);
            spec.tip = Some(link);
        } else {
            if args.scanner_link.is_some() {
                bail!("--scanner-link applies to URDF robots; `{robot}` is a built-in robot");
            }
            spec.preset = Some(robot.clone());
            spec.urdf = None;
            spec.tip = None;
        }
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
    // One cache file per robot (a URDF by its file name), so runs that
    // alternate robots do not rebuild each other's model.
    let spec = &loaded.scenario.robot;
    let robot_name = spec.preset.clone().unwrap_or_else(|| {
        let stem = spec
            .urdf
            .as_ref()
            .and_then(|p| p.file_stem())
            .map(|s| s.to_string_lossy().into_owned());
        format!("urdf-{}", stem.unwrap_or_default())
    });
    let cache = args
        .cspace_cache
        .clone()
        .unwrap_or_else(|| std::env::temp_dir().join(format!("surveyor-cspace-{robot_name}.json")));
    let options = ExploreOptions {
        seed: args.seed,
        max_viewpoints: args.max_viewpoints,
        cspace_cache: Some(cache),
        timings: !args.no_timings,
        checkpoint: Some(args.out.join("checkpoint.json")),
        resume: args.resume,
        stage_two,
        ..ExploreOptions::default()
    };
    for foreign in ["steps.csv", "surface_model.json"] {
        if args.out.join(foreign).exists() {
            bail!(
                "{}: holds a `surveyor follow` run ({foreign}); give another --out",
                args.out.display()
            );
        }
    }
    if args.resume && !args.out.join("checkpoint.json").is_file() {
        bail!(
            "--resume: {} holds no checkpoint.json (no run to continue there; run without --resume)",
            args.out.display()
        );
    }
    super::output::create_out_dir(&args.out)?;
    let t = std::time::Instant::now();
    let run = run_exploration(&loaded, &options, &mut |r| {
        eprintln!(
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
    })?;
    run.write(&args.out)
        .with_context(|| format!("writing {}", args.out.display()))?;
    // The scenario as run (with any --robot, its paths made absolute:
    // `scenario.toml`) and the map products `plan-blast --run` reads; the
    // report rebuilds the robot and scene from the same scenario file.
    sim::blast::write_blast_inputs(&run, &loaded, &args.out)
        .with_context(|| format!("writing {}", args.out.display()))?;
    // The maintenance plan over the map (Paul App. A): a nozzle pose for
    // every disc in A2 that has one, each segment's targets ordered by the GA.
    let blast = match (loaded.scenario.regions, run.discs.discs.is_empty()) {
        (Some(regions), false) => {
            let plan = sim::blast::plan_blast(
                &run,
                &loaded.build_robot()?,
                loaded.scenario.world_from_base(),
                &regions.a2,
                &sim::blast::BlastConfig::default(),
            )?;
            plan.write(&args.out)?;
            Some(plan)
        }
        _ => None,
    };
    let json = run.run_json();
    let per_stage = |k: u8| run.viewpoints.iter().filter(|r| r.stage == k).count();
    println!(
        "{}: stage one ended ({}) after {} viewpoints; {} collisions, {} unsafe configurations (both stages), min clearance {:.3} m; C-space model {}",
        loaded.scenario.name,
        json["termination"].as_str().unwrap_or(""),
        per_stage(1),
        run.collisions,
        run.unsafe_configurations.len(),
        run.min_clearance_m,
        run.cspace
    );
    if let Some(end) = &run.stage_two_termination {
        println!(
            "stage two ended ({end}) after {} viewpoints; material right on {} of the discs the LRC observed",
            per_stage(2),
            run.discs
                .material_accuracy()
                .map_or("none".into(), |a| format!("{:.1} %", 100.0 * a))
        );
    }
    if let Some(c) = &run.coverage {
        println!(
            "coverage of the true surfaces: A1 {:.1} %, A2 {:.1} %, A3 {:.1} %",
            100.0 * c[0].fraction(),
            100.0 * c[1].fraction(),
            100.0 * c[2].fraction()
        );
        if let Some((n, covered)) = run.observable.first() {
            println!(
                "A1 surfaces observable from some collision-free roadmap pose: {:.1} % of them; {:.1} % of those covered",
                100.0 * *n as f64 / c[0].samples.max(1) as f64,
                100.0 * *covered as f64 / (*n).max(1) as f64
            );
        }
    }
    if let Some(plan) = &blast {
        println!("{}", plan.summary());
    }
    let report = report::write(&args.out)?;
    println!("report: {}", report.display());
    println!(
        "{} points, mesh of {} triangles; {:.1} s; outputs in {}",
        run.cloud.len(),
        run.mesh.triangles.len(),
        t.elapsed().as_secs_f64(),
        args.out.display()
    );
    Ok(())
}
