//! `surveyor map`, `sld` and `segment`: occupancy + TSDF maps from scan files
//! (Paul §4.2, §5.1.1), Scale-Like Discs and map segmentation (§5.2–5.3).

use anyhow::{Context, Result, bail};
use clap::Args;
use geom::Real;
use map::segment::{SegmentConfig, load_poses_csv, save_segments_json, segment_discs};
use map::sld::{SldConfig, generate_discs, load_discs_csv, load_points, save_discs_csv};
use map::{MapConfig, Mapper};
use sensor::Sweep;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, Args)]
pub struct SldArgs {
    /// Point cloud or mesh: PLY (a `scan` output's `ox oy oz` orient the normals
    /// toward the sensor; a mesh such as `map`'s mesh.ply orients them by its
    /// faces, as Paul §5.2 makes discs from the fused mesh), PCD, text, OBJ, STL.
    #[arg(long)]
    input: PathBuf,
    /// Disc radius μ, metres (also the voxel size of the hash).
    #[arg(long, default_value_t = 0.04)]
    radius: Real,
    /// Points a disc needs (n_min).
    #[arg(long, default_value_t = 8)]
    min_points: usize,
    /// Seed of the home-point draws.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output CSV (`cx,cy,cz,nx,ny,nz,radius,points`).
    #[arg(long)]
    out: PathBuf,
}

pub fn sld(a: &SldArgs) -> Result<()> {
    let loaded = load_points(&a.input)?;
    let cfg = SldConfig {
        radius_m: a.radius,
        min_points: a.min_points,
        ..SldConfig::default()
    };
    let t0 = Instant::now();
    let result = generate_discs(&loaded.points, loaded.orientation(), &cfg, a.seed)?;
    let elapsed = t0.elapsed().as_secs_f64();
    save_discs_csv(&a.out, &result.discs, &[])
        .with_context(|| format!("writing {}", a.out.display()))?;
    say!(
        "{} discs from {} points ({:.2} % registered) in {:.1} ms → {}",
        result.discs.len(),
        loaded.points.len(),
        100.0 * result.registered_fraction(),
        1000.0 * elapsed,
        a.out.display()
    )?;
    Ok(())
}

#[derive(Debug, Args)]
pub struct SegmentArgs {
    /// Discs CSV written by `surveyor sld`.
    #[arg(long)]
    discs: PathBuf,
    /// One manipulator pose per disc (CSV `q1,...,q6`, radians): enables the τq graph.
    #[arg(long)]
    poses: Option<PathBuf>,
    /// τθ: largest angle between linked discs' normals, degrees.
    #[arg(long, default_value_t = 5.0)]
    tau_theta_deg: Real,
    /// τd: largest distance between linked discs' centres, metres.
    #[arg(long, default_value_t = 0.2)]
    tau_d: Real,
    /// τp: largest centre-to-plane distance between linked discs, metres.
    #[arg(long, default_value_t = 0.05)]
    tau_p: Real,
    /// τq: largest joint difference per joint between linked discs' poses, degrees.
    #[arg(
        long,
        value_delimiter = ',',
        num_args = 1,
        default_value = "8,10,14,20,20,20"
    )]
    tau_q_deg: Vec<Real>,
    /// Output JSON (`{"segments": [[disc index, ...], ...]}`).
    #[arg(long)]
    out: PathBuf,
}

pub fn segment(a: &SegmentArgs) -> Result<()> {
    let discs = load_discs_csv(&a.discs)?;
    let poses = a.poses.as_deref().map(load_poses_csv).transpose()?;
    let Ok(tau_q_deg) = <[Real; 6]>::try_from(a.tau_q_deg.as_slice()) else {
        bail!(
            "--tau-q-deg takes six comma-separated angles, got {}",
            a.tau_q_deg.len()
        );
    };
    let cfg = SegmentConfig {
        tau_theta_deg: a.tau_theta_deg,
        tau_d_m: a.tau_d,
        tau_p_m: a.tau_p,
        tau_q_deg,
    };
    let t0 = Instant::now();
    let segments = segment_discs(&discs, poses.as_deref(), &cfg)?;
    let elapsed = t0.elapsed().as_secs_f64();
    save_segments_json(&a.out, &segments)?;
    let largest = segments.iter().map(Vec::len).max().unwrap_or(0);
    say!(
        "{} segments from {} discs (largest {} discs{}) in {:.1} ms → {}",
        segments.len(),
        discs.len(),
        largest,
        if poses.is_some() { ", with poses" } else { "" },
        1000.0 * elapsed,
        a.out.display()
    )?;
    Ok(())
}

#[derive(Debug, Args)]
pub struct MapArgs {
    /// Sweeps written by `surveyor scan` (PLY with per-point ray origins `ox oy oz`
    /// and the `scan ray` grid cell, which the occlusion weights of Paul §4.2.1 use).
    #[arg(long, num_args = 1.., required = true)]
    scans: Vec<PathBuf>,
    /// Scenario (built-in name or file) whose regions of interest A1 ⊂ A2 ⊂ A3
    /// bound the grid (default: the bridge scenarios' regions).
    #[arg(long)]
    scenario: Option<String>,
    /// Voxel edge of both maps, metres.
    #[arg(long, default_value_t = 0.01)]
    voxel: Real,
    /// Folder for `mesh.ply` and `occupancy.json`.
    #[arg(long)]
    out: PathBuf,
}

pub fn map(a: &MapArgs) -> Result<()> {
    let mut config = MapConfig::default().with_voxel_m(a.voxel);
    if let Some(name) = &a.scenario {
        let loaded = sim::Scenario::load(name)?;
        match loaded.scenario.regions {
            Some(regions) => config.occupancy.regions = regions,
            None => bail!("scenario {name} defines no regions of interest"),
        }
    }
    let mut mapper = Mapper::new(&config)?;
    for path in &a.scans {
        let sweep = Sweep::read_ply(path)?;
        let t0 = Instant::now();
        let summary = mapper.integrate_sweep(&sweep);
        say!(
            "{}: {} points integrated in {:.1} ms ({} voxels newly known, {} occlusion segments ({}), {} TSDF voxel updates)",
            path.display(),
            sweep.len(),
            1000.0 * t0.elapsed().as_secs_f64(),
            summary.occupancy.newly_known,
            summary.occupancy.range_jumps,
            if sweep.grid_shape().is_some() {
                "scan grid"
            } else {
                "no grid in the file: list neighbours only"
            },
            summary.tsdf.voxel_updates
        )?;
        if sweep.is_empty() {
            eprintln!("warning: {} holds no points", path.display());
        } else if summary.occupancy.rays_outside == sweep.len() {
            let b = mapper.occupancy().geometry().aabb();
            eprintln!(
                "warning: {}: all {} rays lie outside the map (A3 = [{:.2}, {:.2}] × [{:.2}, {:.2}] × [{:.2}, {:.2}] m): \
                 nothing was integrated; check the scan's frame or pass --scenario with its regions",
                path.display(),
                sweep.len(),
                b.min.x,
                b.max.x,
                b.min.y,
                b.max.y,
                b.min.z,
                b.max.z
            );
        }
    }
    let t0 = Instant::now();
    let outputs = mapper.outputs();
    let t_mesh = t0.elapsed().as_secs_f64();
    outputs.write(&a.out)?;
    let r = &outputs.report;
    say!(
        "mesh: {} vertices, {} triangles (extracted in {:.1} ms) → {}",
        outputs.mesh.vertices.len(),
        outputs.mesh.len(),
        1000.0 * t_mesh,
        a.out.join("mesh.ply").display()
    )?;
    for region in &r.regions {
        say!(
            "{}: {} free, {} unknown, {} occupied of {} voxels",
            region.region.name(),
            region.free,
            region.unknown,
            region.occupied,
            region.total
        )?;
    }
    say!(
        "H1 {:.1} nats (eq. 4.10), weighted {:.1} (eq. 4.11) → {}",
        r.h1_unweighted,
        r.h1_weighted,
        a.out.join("occupancy.json").display()
    )?;
    Ok(())
}
