//! `surveyor plan-blast`: the grit-blasting plan (Paul App. A) over the map of
//! a `surveyor explore` run folder ([`blast`], read through [`record`]).

use anyhow::{Context, Result};
use blast::{BlastConfig, BlastTool};
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
#[command(after_help = "\
Reads, from the --run folder written by `surveyor explore`: scenario.toml (the robot, its \
placement and the region A2) and blast_inputs.json (the discs, their segments and start joints, \
and the planning grid at the end of the run). Writes blast_plan.json and blast_plan.csv into \
--out: a nozzle pose for every disc in A2 that has one (within the tool's angle, stream length \
and aim limits, dist(Q) > 1 against the run's occupied and unknown voxels), the discs without \
one listed, each segment's targets ordered by the GA with the nearest-neighbour and 2-opt costs \
beside it. With the default tool and seed the plan is the one `surveyor explore` wrote.

--tool FILE.toml holds any of the BlastTool fields (the rest keep their defaults):
  translation_m = [0.0, 0.0, 0.15]   # nozzle tip on the flange, metres
  rpy_deg = [0.0, 0.0, 0.0]          # nozzle orientation on the flange
  phi_max_deg = 30.0                 # largest angle between stream and surface normal
  d_min_m = 0.2                      # shortest effective stream
  d_max_m = 0.5                      # longest effective stream
  rho_min_m = 0.015                  # largest miss of the disc centre
  nozzle_radius_m = 0.03             # the nozzle's collision capsule
  aim_scale_m = 0.01                 # scale of the aim cost's sigmoid (g3)")]
pub struct PlanBlastArgs {
    /// A folder written by `surveyor explore`.
    #[arg(long)]
    run: PathBuf,
    /// The nozzle and its limits (TOML; default: the built-in tool).
    #[arg(long)]
    tool: Option<PathBuf>,
    /// Seed of the GA (each segment mixes in its index).
    #[arg(long, allow_negative_numbers = true, value_parser = crate::commands::whole::<u64>, default_value_t = 0)]
    seed: u64,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// The tool of a `--tool` file.
fn load_tool(path: &Path) -> Result<BlastTool> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("--tool {}: cannot read the file", path.display()))?;
    let tool: BlastTool = toml::from_str(&text).map_err(|e| {
        anyhow::anyhow!(
            "--tool {}: {} (expected the fields of a blast tool; see `surveyor plan-blast --help`)",
            path.display(),
            e.to_string().trim_end()
        )
    })?;
    tool.validate()
        .with_context(|| format!("--tool {}", path.display()))?;
    Ok(tool)
}

pub fn plan_blast(args: &PlanBlastArgs) -> Result<()> {
    super::output::check_out_dir(&args.out)?;
    let mut config = BlastConfig::default();
    if let Some(path) = &args.tool {
        config.tool = load_tool(path)?;
    }
    config.ga.seed = args.seed;
    let t = std::time::Instant::now();
    let plan = scenario::job::explore::plan_blast_run(&args.run, &config)?;
    let seconds = t.elapsed().as_secs_f64();
    let mut staged = super::output::Staged::new();
    staged.ensure_dir(&args.out)?;
    std::fs::write(
        staged.file_in(&args.out, record::blast::BLAST_PLAN_JSON)?,
        plan.to_json()?,
    )?;
    std::fs::write(
        staged.file_in(&args.out, record::blast::BLAST_PLAN_CSV)?,
        plan.csv(),
    )?;
    staged.commit()?;
    say!(
        "{}; {seconds:.1} s; outputs in {}",
        plan.summary(),
        args.out.display()
    )?;
    Ok(())
}
