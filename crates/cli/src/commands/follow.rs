//! `surveyor follow`: Pudney's surface following (P ch. 3) in a simulated
//! world, one episode ([`sim::follow_job`]), or on a ROS 2 robot
//! (`--ros2`, [`super::on_robot::follow_job`]), with its outputs in a
//! folder.

use super::output::{config_toml, load_config};
use anyhow::{Context, Result, bail};
use clap::Args;
use follow::{GapTargetRule, RunEnd, SliceLineRule, SliceRule};
use geom::Real;
use indicatif::{ProgressBar, ProgressStyle};
use record::follow::FollowSummary;
use scenario::job::follow::{
    DEFAULT_MAX_SETS, FollowRun, FollowRunConfig, FollowRunOptions, FollowSetup, ScanFigures,
    StartPose, SurfaceFigures, check_follow_out, follow_with,
};
use scenario::{RobotChoice, Scenario};
use serde::Serialize;
use sim::follow_job::SimFollow;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(Debug, Args)]
#[command(after_help = "\
Outputs in --out: surface_model.json and surface_model.obj (the model), steps.csv (one row per \
step: step, mode, x, y, z, q1..qn, set_size, update_us, direction_us, kinematics_us, \
link_clearance_m, current_segment, current_edge), path.ply (the control-point path, vertices \
and edges), run.json (sets, steps, completed, termination, collisions, min_clearance_m, \
a_priori_faces (the normals of the true faces given as initial segments because the robot \
cannot reach them), guard (what the safety guard did: taken, scaled, retreated, held), modelled_m2 and \
sets_per_m2 (the true area within λ of the model, and sets per square metre of it), \
step_us, modes, the score against the true scene, the options; for a point-cloud world, \
which has no true surface, min_scan_clearance_m and scan_close_poses: the links' clearance \
from the scan points and the poses closer than δ/2, and model_to_scan_max_m, \
model_to_scan_within_lambda and model_to_scan: the model polygons' distances to the scan), model_snapshots.json (the model \
after evenly spaced numbers of sensor sets, 3 to 6 of them, and at the end: Pudney Figs 44 and \
46), scenario.toml (the scenario as given, paths made absolute; not for --scene) and \
report.html (surveyor report: the model, its shared edges, the path, the evolution, the modes \
and step times).

The same inputs and --seed give the same run; only the wall-clock columns of steps.csv \
(update_us, direction_us, kinematics_us) and run.json's step times differ. With --no-timings \
those columns are written empty and those times 0, and steps.csv, surface_model.json and \
run.json are then byte-identical from run to run.

Ctrl-C stops the run after the current step and writes the outputs of the steps so far \
(termination \"interrupted\").")]
pub struct FollowArgs {
    /// Built-in scenario name (cube, block1, block2, cylinder, ...) or scenario file.
    #[arg(long, required_unless_present_any = ["scene", "print_config"], conflicts_with = "scene")]
    scenario: Option<String>,
    /// A mesh (OBJ, STL, PLY) or point cloud (PCD, PLY, text) placed as-is in the
    /// world frame, instead of a scenario. The robot (point3 unless --robot) starts
    /// δ above the centre of the top of its bounding box; without --initial the
    /// model starts with a table at the bottom of the bounding box (a square one
    /// box size, at least 0.5 m, beyond it on every side).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// With --scene: scale factor applied to the file's coordinates [default: 1].
    #[arg(long)]
    scale: Option<Real>,
    /// A-priori segments instead of the scenario's: `{"segments": [[[x,y,z], ...], ...]}`,
    /// each anticlockwise about its outward normal; no two may overlap on the
    /// same surface (initial segments never merge).
    #[arg(long)]
    initial: Option<PathBuf>,
    /// Another robot: point3, arm4 or a URDF file (FILE.urdf). On the built-in
    /// scenes arm4 stands at (-1.6, 0, 0), and unless --initial is given the
    /// true faces it cannot bring its control point to from there (an
    /// inverse-kinematics test, a few seconds) are given as initial segments
    /// and left out of the score (run.json's a_priori_faces); without
    /// --start/--joints the robot starts with its control point where the
    /// scenario's robot has it, tool down.
    #[arg(long)]
    robot: Option<String>,
    /// Start with the control point here (world frame, metres), tool pointing down.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        num_args = 1,
        conflicts_with = "joints"
    )]
    start: Option<Vec<Real>>,
    /// Start at these joint values (radians, metres for prismatic joints).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, num_args = 1)]
    joints: Option<Vec<Real>>,
    /// Range noise σ of every reading, metres (default: the scenario's).
    #[arg(long, allow_negative_numbers = true)]
    noise_m: Option<Real>,
    /// Seed of the range noise.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::commands::whole::<u64>, default_value_t = 0)]
    seed: u64,
    /// Most sensor sets to take (one per step).
    #[arg(long, allow_negative_numbers = true, value_parser = crate::commands::whole::<u64>, default_value_t = DEFAULT_MAX_SETS)]
    max_sets: u64,
    /// Parameters (TOML): a `[follow]` table (FollowConfig: desired_distance_m,
    /// max_step_m, ...) and a [surface] table (SurfaceConfig: lambda, mu_deg, ...).
    /// Without it, the scenario file's own `[follow]` and `[surface]` tables
    /// (the defaults where it has none); with it, both of those are replaced.
    #[arg(long)]
    config: Option<PathBuf>,
    /// How current edge following cuts slices (P§3.4.3): `thesis`, Pudney's
    /// slices λ/2 wide, or `lattice`, as wide as the control point's sensor
    /// lattice on the current face allows (our addition). Overrides the
    /// `[follow] slices` of --config [default: thesis].
    #[arg(long, value_parser = ["thesis", "lattice"])]
    slices: Option<String>,
    /// When a changed current edge keeps its slice line (P§3.4.3,
    /// P§3.4.6): `thesis`, within λ of the line with a used slice through
    /// it, or `outward`, also while the edge only moves outward, the
    /// current slice kept (our addition). Overrides `[follow] slice_line`
    /// [default: thesis].
    #[arg(long, value_parser = ["thesis", "outward"])]
    slice_line: Option<String>,
    /// Which gap-following targets count as detected (P§3.4.5): `thesis`,
    /// a point sensed near it while aimed at, or `sensed`, also a point any
    /// earlier set sensed within λ/2 (our addition). Overrides `[follow]
    /// gap_targets` [default: thesis].
    #[arg(long, value_parser = ["thesis", "sensed"])]
    gap_targets: Option<String>,
    /// Print the configuration in effect as TOML and exit.
    #[arg(long)]
    print_config: bool,
    /// Write the timing columns of steps.csv empty and run.json's step times
    /// as 0 (byte-identical reruns).
    #[arg(long)]
    no_timings: bool,
    /// Output folder (created if missing).
    #[arg(long, required_unless_present = "print_config")]
    out: Option<PathBuf>,
    #[command(flatten)]
    ros2: super::on_robot::Ros2Flags,
}

/// The options of the run from the flags, each checked with the flag named.
fn options(a: &FollowArgs, config: FollowRunConfig) -> Result<FollowRunOptions> {
    let start = match (&a.start, &a.joints) {
        (Some(_), Some(_)) => bail!("give --start or --joints, not both"),
        (Some(p), None) => Some(StartPose::ControlPoint(super::three(
            Some(p),
            "--start",
            "metres",
            scene::MAX_COORDINATE_M,
        )?)),
        (None, Some(q)) => {
            if let Some(i) = q.iter().position(|v| !v.is_finite()) {
                bail!(
                    "--joints: joint {} is {}; expected a finite value",
                    i + 1,
                    q[i]
                );
            }
            Some(StartPose::Joints(q.clone()))
        }
        (None, None) => None,
    };
    if let Some(s) = a.noise_m
        && !(s.is_finite() && (0.0..=scenario::range_sensors::MAX_NOISE_SIGMA_M).contains(&s))
    {
        bail!("--noise-m {s}: expected a standard deviation from 0 to 1 metre");
    }
    if a.max_sets == 0 {
        bail!("--max-sets 0: expected at least 1 sensor set");
    }
    if a.scale.is_some() && a.scene.is_none() {
        bail!("--scale applies to a --scene file only");
    }
    if let Some(s) = a.scale
        && !(s.is_finite() && s > 0.0)
    {
        bail!("--scale {s}: expected a finite factor > 0");
    }
    if let Some(r) = &a.robot
        && !matches!(
            RobotChoice::parse(r, None)?.builtin_name(),
            None | Some("point3" | "arm4")
        )
    {
        bail!("--robot {r}: unknown robot; expected point3, arm4 or a URDF file (FILE.urdf)");
    }
    let initial_segments = match &a.initial {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("reading {}", path.display()))?;
            let segs = surface::read_initial_segments_json(&text, &path.display().to_string())?;
            Some(
                segs.iter()
                    .map(|s| s.iter().map(|p| [p.x, p.y, p.z]).collect())
                    .collect(),
            )
        }
        None => None,
    };
    Ok(FollowRunOptions {
        seed: a.seed,
        max_sets: a.max_sets,
        noise_sigma_m: a.noise_m,
        robot: a.robot.clone(),
        start,
        initial_segments,
        timings: !a.no_timings,
        config,
    })
}

pub fn follow(a: &FollowArgs) -> Result<()> {
    // The scenario's own [follow] and [surface] tables unless --config
    // replaces them.
    let loaded = a.scenario.as_deref().map(Scenario::load).transpose()?;
    let mut config: FollowRunConfig = match (&a.config, &loaded) {
        (None, Some(l)) => FollowRunConfig::of_scenario(&l.scenario),
        (path, _) => load_config(path.as_deref())?,
    };
    match a.slices.as_deref() {
        None => {}
        Some("thesis") => config.follow.slices = SliceRule::Thesis,
        Some("lattice") => config.follow.slices = SliceRule::Lattice,
        Some(other) => bail!("--slices {other}: expected thesis or lattice"),
    }
    match a.slice_line.as_deref() {
        None => {}
        Some("thesis") => config.follow.slice_line = SliceLineRule::Thesis,
        Some("outward") => config.follow.slice_line = SliceLineRule::Outward,
        Some(other) => bail!("--slice-line {other}: expected thesis or outward"),
    }
    match a.gap_targets.as_deref() {
        None => {}
        Some("thesis") => config.follow.gap_targets = GapTargetRule::Thesis,
        Some("sensed") => config.follow.gap_targets = GapTargetRule::Sensed,
        Some(other) => bail!("--gap-targets {other}: expected thesis or sensed"),
    }
    if a.print_config {
        put!("{}", config_toml(&config)?)?;
        return Ok(());
    }
    let Some(out) = &a.out else {
        bail!("--out is required");
    };
    check_follow_out(out)?;
    let opts = options(a, config)?;
    // The scenario as given (its paths made absolute), for the report's
    // ground truth; a --scene run has none.
    let mut scenario_toml = None;
    // How --ros2 talks to the robot: the scenario's [ros2] table.
    let mut spec = scenario::ros2::Ros2Spec::default();
    let setup = match (&loaded, &a.scene) {
        (_, Some(file)) => FollowSetup::from_scene_file(file, a.scale.unwrap_or(1.0), &opts)?,
        (Some(loaded), None) => {
            scenario_toml = Some(loaded.standalone().to_toml()?);
            spec = loaded.scenario.ros2.clone().unwrap_or_default();
            FollowSetup::from_scenario(loaded, &opts)?
        }
        (None, None) => bail!("give --scenario NAME|FILE or --scene FILE"),
    };
    super::warn_about(&setup.robot);
    // The in-process run's rig, made before the run as its setup is.
    let simulated = if a.ros2.ros2 {
        None
    } else {
        Some(SimFollow::new(setup.clone())?)
    };
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        if let Err(e) = ctrlc::set_handler(move || stop.store(true, Ordering::Relaxed)) {
            note!("note: Ctrl-C will end the run without writing outputs ({e})");
        }
    }
    let pb = ProgressBar::new(opts.max_sets);
    if let Ok(style) =
        ProgressStyle::with_template("{msg:>28} [{bar:30}] {pos}/{len} sets {elapsed}")
    {
        pb.set_style(style.progress_chars("=> "));
    }
    let mut progress = |row: &record::StepRow, follower: &follow::Follower| {
        pb.set_position(row.step + 1);
        if row.step.is_multiple_of(10) {
            pb.set_message(format!(
                "{} · {} segments",
                row.mode,
                follower.model().len()
            ));
        }
    };
    let mut report =
        |staging: &record::Staging| report::write_staged(staging).map_err(|e| e.to_string());
    let Some(simulated) = simulated else {
        let run = super::on_robot::follow_job(
            &a.ros2,
            &spec,
            setup,
            scenario_toml,
            out,
            &stop,
            &mut progress,
            &mut report,
        );
        pb.finish_and_clear();
        let (run, live) = run?;
        super::on_robot::say_follow_live(&live, &run)?;
        say_summary(&run, out, a.no_timings)?;
        return say_end(&run, out);
    };
    let run = follow_with(
        scenario_toml,
        out,
        |stop, progress| simulated.run(stop, progress),
        &stop,
        &mut progress,
        &mut report,
    );
    pb.finish_and_clear();
    let run = run?;
    let summary = say_summary(&run, out, a.no_timings)?;
    if let Some(score) = &run.score {
        say!(
            "model: {} segments; coverage {:.1}% of the counted faces ({:.1}% within λ of any polygon), shared edges {:.1}%, {} of {} corners",
            run.model.len(),
            100.0 * score.coverage,
            100.0 * score.within_lambda,
            100.0 * score.edge_coverage,
            score.corners_found,
            score.corners.len()
        )?;
    }
    if let Some(scan) = &run.scan_score {
        let clearance = match (summary.min_scan_clearance_m, summary.scan_close_poses) {
            (Some(d), Some(n)) => format!(
                "links at least {d:.4} m from the scan points ({n} poses closer than δ/2 = {:.3} m)",
                0.5 * run.options.config.follow.desired_distance_m
            ),
            _ => "link clearance from the scan not measured (no link capsules)".to_owned(),
        };
        let model = match scan.max_m {
            Some(m) => format!(
                "model polygons at most {m:.4} m from the scan, {:.1}% of their area and {:.1}% of their vertices within λ = {} m, {} of {} polygons beyond λ",
                100.0 * scan.within_lambda_fraction,
                100.0 * scan.vertices_within_lambda_fraction,
                scan.config.lambda_m,
                scan.polygons_beyond_lambda,
                scan.polygons.len()
            ),
            None => "no model polygons to check against the scan".to_owned(),
        };
        say!("scan: {clearance}; {model}")?;
    }
    say_end(&run, out)
}

/// Say the run's summary line (sets, termination, collisions, step and
/// robot times); the summary, for the lines that follow.
fn say_summary<S, M>(
    run: &FollowRun<S, M>,
    out: &Path,
    no_timings: bool,
) -> Result<FollowSummary<FollowRunOptions, S, M>>
where
    S: SurfaceFigures + Serialize + Clone,
    M: ScanFigures + Serialize + Clone,
{
    let summary = run.summary();
    let collisions = summary
        .collisions
        .map_or_else(|| "no ground truth for".to_owned(), |n| n.to_string());
    let times = step_times(&summary.step_us, no_timings);
    say!(
        "{} sets, termination {}, {collisions} collisions, {times}; robot time {} → {}",
        summary.sets,
        summary.termination,
        summary.robot_time_s,
        out.display()
    )?;
    Ok(summary)
}

/// Say where the report is, and fail when the run stopped on an error.
fn say_end<S, M>(run: &FollowRun<S, M>, out: &Path) -> Result<()> {
    say!(
        "report: {}",
        out.join(record::folder::REPORT_HTML).display()
    )?;
    if let RunEnd::Error(e) = &run.episode.end {
        bail!(
            "the run stopped on an error after {} steps (the outputs of those steps are in {}): {e}",
            run.episode.rows.len(),
            out.display()
        );
    }
    Ok(())
}

/// The run's step times as the summary line says them.
fn step_times(step_us: &record::follow::StepTimeStats, no_timings: bool) -> String {
    if no_timings {
        "step times not recorded (--no-timings)".to_owned()
    } else {
        format!(
            "mean step {:.1} µs (median {:.1}, 95th percentile {:.1})",
            step_us.mean, step_us.median, step_us.p95
        )
    }
}
