//! `surveyor model`: Pudney's incremental surface model (P ch. 2) fed from a
//! file of sensor sets, with per-update timing.

use anyhow::{Context, Result, anyhow};
use clap::Args;
use geom::Real;
use std::fs::File;
use std::io::BufReader;
use std::path::PathBuf;
use std::time::Instant;
use surface::{
    SurfaceConfig, SurfaceModel, UpdateTimes, read_initial_segments_json, read_sets_jsonl,
};

#[derive(Debug, Args)]
pub struct ModelArgs {
    /// Sensor sets, one JSON object per line:
    /// `{"points": [[x,y,z], ...], "axes": [[ax,ay,az], ...]}`.
    #[arg(long)]
    sets: PathBuf,
    /// Linear resolution λ, metres.
    #[arg(long, default_value_t = 0.05)]
    lambda: Real,
    /// Angular resolution μ, degrees.
    #[arg(long, default_value_t = 10.0)]
    mu_deg: Real,
    /// Redundancy count ψ (P§2.9): a segment S₁ that fails to share edges with a
    /// larger S₂ is deleted if it holds fewer than ψ points ...
    #[arg(long, default_value_t = 20.0)]
    psi: Real,
    /// ... and fewer than φ times S₂'s points (P§2.9; a ratio, not a distance).
    #[arg(long, default_value_t = 0.05)]
    phi: Real,
    /// A-priori segments (P§4.3): `{"segments": [[[x,y,z], ...], ...]}`, each
    /// anticlockwise about its outward normal.
    #[arg(long)]
    initial: Option<PathBuf>,
    /// Run the invariant checker after every update.
    #[arg(long)]
    check: bool,
    /// Folder for surface_model.json, surface_model.obj and stats.json.
    #[arg(long)]
    out: PathBuf,
}

pub fn model(a: &ModelArgs) -> Result<()> {
    let file = File::open(&a.sets).with_context(|| format!("opening {}", a.sets.display()))?;
    let sets = read_sets_jsonl(BufReader::new(file), &a.sets.display().to_string())?;
    let config = SurfaceConfig {
        lambda: a.lambda,
        mu_deg: a.mu_deg,
        psi: a.psi,
        phi: a.phi,
        ..SurfaceConfig::default()
    };
    let mut model = SurfaceModel::new(config)?;
    if let Some(path) = &a.initial {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        for (k, vertices) in read_initial_segments_json(&text, &path.display().to_string())?
            .iter()
            .enumerate()
        {
            model
                .add_initial_segment(vertices)
                .with_context(|| format!("{}: initial segment {k}", path.display()))?;
        }
    }
    let pb = super::progress_bar(sets.len() as u64, "modelling");
    let mut times_us = Vec::with_capacity(sets.len());
    for (k, set) in sets.iter().enumerate() {
        let t0 = Instant::now();
        model
            .update(set)
            .with_context(|| format!("{}: set on line {}", a.sets.display(), k + 1))?;
        times_us.push(1e6 * t0.elapsed().as_secs_f64());
        if a.check {
            model
                .check_invariants()
                .map_err(|e| anyhow!("invariant violated after the set on line {}: {e}", k + 1))?;
        }
        pb.set_position(k as u64 + 1);
    }
    pb.finish_and_clear();
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let json = serde_json::to_string_pretty(&model.to_model_json())?;
    write(&a.out.join("surface_model.json"), json.as_bytes())?;
    write(&a.out.join("surface_model.obj"), model.to_obj().as_bytes())?;
    let times = UpdateTimes::from_micros(&times_us);
    let stats = model.stats().to_json(times);
    write(
        &a.out.join("stats.json"),
        serde_json::to_string_pretty(&stats)?.as_bytes(),
    )?;
    say!(
        "{} sets → {} segments ({} polygons, {} points), {} shared-edge pairs, {} corner vertices → {}",
        sets.len(),
        stats.segments,
        stats.polygons,
        stats.points,
        stats.shared_edge_pairs,
        stats.corner_vertices,
        a.out.display()
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

fn write(path: &std::path::Path, bytes: &[u8]) -> Result<()> {
    std::fs::write(path, bytes).with_context(|| format!("writing {}", path.display()))
}
