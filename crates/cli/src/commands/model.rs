//! `surveyor model`: Pudney's incremental surface model (P ch. 2) fed from a
//! file of sensor sets, with per-update timing ([`mod@surface::replay`]).

use super::output::{Staged, config_toml, load_config};
use anyhow::{Context, Result, bail};
use clap::Args;
use geom::Real;
use std::fs::File;
use std::io::BufReader;
use std::path::PathBuf;
use surface::{
    InitialSegments, ReplayError, ReplayOptions, SurfaceConfig, read_initial_segments_located,
    read_sets_jsonl_limited,
};

#[derive(Debug, Args)]
pub struct ModelArgs {
    /// Sensor sets, one JSON object per line:
    /// `{"points": [[x,y,z], ...], "axes": [[ax,ay,az], ...]}`.
    #[arg(long, required_unless_present_any = ["print_config", "bag"], conflicts_with = "bag")]
    sets: Option<PathBuf>,
    /// A robot's ROS 2 bag (MCAP) instead of a sets file: its `sensor_msgs/Range`
    /// readings, one set per stamp, each point `range` along its frame's x axis,
    /// placed by the bag's /tf_static and /tf (a `surveyor follow` run's `run.mcap`,
    /// or one recorded on a robot).
    #[arg(long)]
    bag: Option<PathBuf>,
    /// With --bag: the Range topics to read (comma-separated; default: every
    /// topic of that type).
    #[arg(long, value_delimiter = ',', requires = "bag")]
    range_topics: Vec<String>,
    /// With --bag: skip a damaged chunk or a bad message (one that does not
    /// decode or holds values no sensor gives) and say how many were lost,
    /// instead of refusing the bag.
    #[arg(long, requires = "bag")]
    skip_bad_messages: bool,
    /// The whole model configuration (TOML, fields of `SurfaceConfig`).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Print the configuration in effect as TOML and exit.
    #[arg(long)]
    print_config: bool,
    /// Linear resolution λ, metres [config: lambda].
    #[arg(long, allow_negative_numbers = true)]
    lambda: Option<Real>,
    /// Angular resolution μ, degrees [config: mu_deg].
    #[arg(long, allow_negative_numbers = true)]
    mu_deg: Option<Real>,
    /// Redundancy count ψ (P§2.9): a segment S₁ that fails to share edges with a
    /// larger S₂ is deleted if it holds fewer than ψ points ... [config: psi]
    #[arg(long, allow_negative_numbers = true)]
    psi: Option<Real>,
    /// ... and fewer than φ times S₂'s points (P§2.9; a ratio, not a distance)
    /// [config: phi].
    #[arg(long, allow_negative_numbers = true)]
    phi: Option<Real>,
    /// A-priori segments (P§4.3): `{"segments": [[[x,y,z], ...], ...]}`, each
    /// anticlockwise about its outward normal; no two may overlap on the same
    /// surface (initial segments never merge).
    #[arg(long)]
    initial: Option<PathBuf>,
    /// Run the invariant checker after every update.
    #[arg(long)]
    check: bool,
    /// Folder for surface_model.json, surface_model.obj and stats.json.
    #[arg(long, required_unless_present = "print_config")]
    out: Option<PathBuf>,
}

pub fn model(a: &ModelArgs) -> Result<()> {
    // clap leaves `requires` unchecked beside `required_unless_present_any`:
    // checked by hand.
    if a.bag.is_none() {
        if !a.range_topics.is_empty() {
            bail!("--range-topics applies with --bag (the Range topics of the bag to read)");
        }
        if a.skip_bad_messages {
            bail!("--skip-bad-messages applies with --bag");
        }
    }
    let mut config: SurfaceConfig = load_config(a.config.as_deref())?;
    for (flag, field) in [
        (a.lambda, &mut config.lambda),
        (a.mu_deg, &mut config.mu_deg),
        (a.psi, &mut config.psi),
        (a.phi, &mut config.phi),
    ] {
        if let Some(v) = flag {
            *field = v;
        }
    }
    if a.print_config {
        put!("{}", config_toml(&config)?)?;
        return Ok(());
    }
    let Some(out) = &a.out else {
        bail!("--out is required");
    };
    config.validate()?;
    let (sets_path, sets) = match (&a.bag, &a.sets) {
        (Some(bag), _) => {
            let read = record::bag::sets_from_bag(
                bag,
                &a.range_topics,
                config.max_set_points,
                super::bad_messages(a.skip_bad_messages),
            )?;
            super::say_skipped(bag, &read.skipped)?;
            say!(
                "{}: {} sets from {} Range topics ({} readings with a return, {} without)",
                bag.display(),
                read.sets.len(),
                read.topics.len(),
                read.points,
                read.misses
            )?;
            (bag, read.sets)
        }
        (None, Some(sets_path)) => {
            let file = File::open(sets_path)
                .with_context(|| format!("opening {}", sets_path.display()))?;
            let sets = read_sets_jsonl_limited(
                BufReader::new(file),
                &sets_path.display().to_string(),
                config.max_set_points,
            )?;
            (sets_path, sets)
        }
        (None, None) => bail!("--sets (or --bag) and --out are required"),
    };
    if sets.is_empty() {
        bail!(
            "{}: no sensor sets ({})",
            sets_path.display(),
            if a.bag.is_some() {
                "no Range reading with a return"
            } else {
                "expected one JSON object per line"
            }
        );
    }
    let initial = match &a.initial {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("reading {}", path.display()))?;
            read_initial_segments_located(&text, &path.display().to_string())?
        }
        None => InitialSegments::default(),
    };
    let pb = super::progress_bar(sets.len() as u64, "modelling");
    let options = ReplayOptions {
        check_invariants: a.check,
    };
    let replayed = surface::replay(config, &initial.segments, &sets, options, &mut |done| {
        pb.set_position(done as u64);
    });
    pb.finish_and_clear();
    // Initial segments by file, line and index (`segments[i]`, as the file
    // reader names them).
    let initial_path = a.initial.as_deref().unwrap_or(sets_path).display();
    let line = |i: usize| initial.lines.get(i).copied().unwrap_or(1);
    let replayed = replayed.map_err(|e| match e {
        ReplayError::Initial { index, source } => anyhow::anyhow!(
            "{initial_path}:{}: segments[{index}]: {source}",
            line(index)
        ),
        ReplayError::InitialOverlap {
            index,
            other,
            area_m2,
        } => anyhow::anyhow!(
            "{initial_path}:{}: segments[{index}] overlaps segments[{other}] (line {}) over {area_m2:.3e} m² of the same surface: both face the same way (within μ/2) and lie within λ of each other there; initial segments never merge (P§4.3), so that surface would be modelled twice (give it once, or as tiles that only touch)",
            line(index),
            line(other)
        ),
        ReplayError::Set { index, source } => {
            anyhow::anyhow!(
                "{}: set on line {}: {source}",
                sets_path.display(),
                index + 1
            )
        }
        ReplayError::Invariant { index, message } => anyhow::anyhow!(
            "invariant violated after the set on line {}: {message}",
            index + 1
        ),
        other => other.into(),
    })?;
    let mut staged = Staged::new();
    staged.ensure_dir(out)?;
    for (name, text) in replayed.outputs()? {
        let path = staged.file_in(out, name)?;
        std::fs::write(&path, text)
            .with_context(|| format!("writing {}", out.join(name).display()))?;
    }
    staged.commit()?;
    let times = replayed.times();
    let stats = replayed.stats();
    say!(
        "{} sets → {} segments ({} polygons, {} points), {} shared-edge pairs, {} corner vertices → {}",
        sets.len(),
        stats.segments,
        stats.polygons,
        stats.points,
        stats.shared_edge_pairs,
        stats.corner_vertices,
        out.display()
    )?;
    say!(
        "update time: median {:.1} µs, 95th percentile {:.1} µs, max {:.1} µs{}",
        times.median,
        times.p95,
        times.max,
        if a.check {
            " (invariants checked after every update)"
        } else {
            ""
        }
    )?;
    Ok(())
}
