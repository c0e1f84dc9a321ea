//! `surveyor map`, `sld` and `segment`: occupancy + TSDF maps from scan files
//! (Paul §4.2, §5.1.1), Scale-Like Discs and map segmentation (§5.2–5.3).
//!
//! Each stage's whole configuration comes from its library `*Config`
//! (`Default`, or `--config FILE.toml`); the flags override single fields.

use super::output::{Staged, config_toml, load_config};
use anyhow::{Context, Result, bail};
use clap::Args;
use geom::Real;
use map::segment::{SegmentConfig, segment_discs};
use map::segment_io::{load_poses_csv, save_segments_json};
use map::sld::{SldConfig, generate_discs};
use map::sld_io::{load_discs_csv, load_points, save_discs_csv};
use map::{MapConfig, Mapper};
use sensor::Sweep;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, Args)]
pub struct SldArgs {
    /// Point cloud or mesh: PLY (a `scan` output's `ox oy oz` orient the normals
    /// toward the sensor; a mesh such as `map`'s mesh.ply orients them by its
    /// faces, as Paul §5.2 makes discs from the fused mesh), PCD, text, OBJ, STL.
    #[arg(long, required_unless_present = "print_config")]
    input: Option<PathBuf>,
    /// The whole SLD configuration (TOML, fields of `SldConfig`; see --print-config).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Print the configuration in effect as TOML and exit.
    #[arg(long)]
    print_config: bool,
    /// Disc radius μ, metres (also the voxel size of the hash) [config: radius_m].
    #[arg(long, allow_negative_numbers = true)]
    radius: Option<Real>,
    /// Points a disc needs, n_min [config: min_points].
    #[arg(long, allow_negative_numbers = true, value_parser = crate::commands::whole::<usize>)]
    min_points: Option<usize>,
    /// Seed of the home-point draws.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::commands::whole::<u64>, default_value_t = 0)]
    seed: u64,
    /// Output CSV (`cx,cy,cz,nx,ny,nz,radius,points`).
    #[arg(long, required_unless_present = "print_config")]
    out: Option<PathBuf>,
}

pub fn sld(a: &SldArgs) -> Result<()> {
    let mut cfg: SldConfig = load_config(a.config.as_deref())?;
    if let Some(r) = a.radius {
        cfg.radius_m = r;
    }
    if let Some(n) = a.min_points {
        cfg.min_points = n;
    }
    if a.print_config {
        put!("{}", config_toml(&cfg)?)?;
        return Ok(());
    }
    let (Some(input), Some(out)) = (&a.input, &a.out) else {
        bail!("--input and --out are required");
    };
    cfg.validate()?;
    let loaded = load_points(input)?;
    if loaded.points.is_empty() {
        bail!("{}: no points", input.display());
    }
    let t0 = Instant::now();
    let result = generate_discs(&loaded.points, loaded.orientation(), &cfg, a.seed)?;
    let elapsed = t0.elapsed().as_secs_f64();
    let mut staged = Staged::new();
    save_discs_csv(&staged.file(out)?, &result.discs, &[])
        .with_context(|| format!("writing {}", out.display()))?;
    staged.commit()?;
    say!(
        "{} discs from {} points ({:.2} % registered) in {:.1} ms → {}",
        result.discs.len(),
        loaded.points.len(),
        100.0 * result.registered_fraction(),
        1000.0 * elapsed,
        out.display()
    )?;
    Ok(())
}

#[derive(Debug, Args)]
pub struct SegmentArgs {
    /// Discs CSV written by `surveyor sld`.
    #[arg(long, required_unless_present = "print_config")]
    discs: Option<PathBuf>,
    /// One manipulator pose per disc (CSV `q1,...,q6`, radians): enables the τq graph.
    #[arg(long)]
    poses: Option<PathBuf>,
    /// The whole segmentation configuration (TOML, fields of `SegmentConfig`).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Print the configuration in effect as TOML and exit.
    #[arg(long)]
    print_config: bool,
    /// τθ: largest angle between linked discs' normals, degrees [config: tau_theta_deg].
    #[arg(long, allow_negative_numbers = true)]
    tau_theta_deg: Option<Real>,
    /// τd: largest distance between linked discs' centres, metres [config: tau_d_m].
    #[arg(long, allow_negative_numbers = true)]
    tau_d: Option<Real>,
    /// τp: largest centre-to-plane distance between linked discs, metres [config: tau_p_m].
    #[arg(long, allow_negative_numbers = true)]
    tau_p: Option<Real>,
    /// τq: largest joint difference per joint between linked discs' poses,
    /// degrees, six comma-separated values [config: tau_q_deg].
    #[arg(long, value_delimiter = ',', num_args = 1, allow_hyphen_values = true)]
    tau_q_deg: Option<Vec<Real>>,
    /// Output JSON (`{"segments": [[disc index, ...], ...]}`).
    #[arg(long, required_unless_present = "print_config")]
    out: Option<PathBuf>,
}

pub fn segment(a: &SegmentArgs) -> Result<()> {
    let mut cfg: SegmentConfig = load_config(a.config.as_deref())?;
    if let Some(v) = a.tau_theta_deg {
        cfg.tau_theta_deg = v;
    }
    if let Some(v) = a.tau_d {
        cfg.tau_d_m = v;
    }
    if let Some(v) = a.tau_p {
        cfg.tau_p_m = v;
    }
    if let Some(q) = &a.tau_q_deg {
        let Ok(q) = <[Real; 6]>::try_from(q.as_slice()) else {
            bail!(
                "--tau-q-deg takes six comma-separated angles, got {}",
                q.len()
            );
        };
        cfg.tau_q_deg = q;
    }
    if a.print_config {
        put!("{}", config_toml(&cfg)?)?;
        return Ok(());
    }
    if a.tau_q_deg.is_some() && a.poses.is_none() {
        bail!(
            "--tau-q-deg applies with --poses (τq compares the poses of two discs; without poses the pose graph is not used)"
        );
    }
    let (Some(discs_path), Some(out)) = (&a.discs, &a.out) else {
        bail!("--discs and --out are required");
    };
    cfg.validate()?;
    let discs = load_discs_csv(discs_path)?;
    if discs.is_empty() {
        bail!("{}: no discs (the file has no rows)", discs_path.display());
    }
    let poses = a.poses.as_deref().map(load_poses_csv).transpose()?;
    let t0 = Instant::now();
    let segments = segment_discs(&discs, poses.as_deref(), &cfg)?;
    let elapsed = t0.elapsed().as_secs_f64();
    let mut staged = Staged::new();
    save_segments_json(&staged.file(out)?, &segments)?;
    staged.commit()?;
    let largest = segments.iter().map(Vec::len).max().unwrap_or(0);
    say!(
        "{} segments from {} discs (largest {} discs{}) in {:.1} ms → {}",
        segments.len(),
        discs.len(),
        largest,
        if poses.is_some() { ", with poses" } else { "" },
        1000.0 * elapsed,
        out.display()
    )?;
    Ok(())
}

#[derive(Debug, Args)]
pub struct MapArgs {
    /// Sweeps written by `surveyor scan` (PLY with per-point ray origins `ox oy oz`
    /// and the `scan ray` grid cell, which the occlusion weights of Paul §4.2.1 use).
    #[arg(long, num_args = 1.., required_unless_present_any = ["print_config", "bag"], conflicts_with = "bag")]
    scans: Vec<PathBuf>,
    /// A robot's ROS 2 bag (MCAP) instead of scan files: its `sensor_msgs/LaserScan`s
    /// placed by the `sensor_msgs/JointState`s interpolated to each scan's stamp
    /// (a `surveyor explore` run's `run.mcap`, or one recorded on a robot). Also
    /// writes the scans' points as `cloud.ply` and the mesh's discs as `discs.csv`.
    #[arg(long, requires = "robot")]
    bag: Option<PathBuf>,
    /// With --bag: the robot, a built-in name or FILE.urdf.
    #[arg(long, requires = "bag")]
    robot: Option<String>,
    /// With --bag: the link whose frame the scans are in (ROS's laser convention:
    /// rays in its x–y plane). Default: the scans' frame_id, a link of the robot
    /// or a frame the bag's /tf_static places on one.
    #[arg(long, requires = "bag")]
    scanner_link: Option<String>,
    /// With --bag: the LaserScan topic.
    #[arg(long, default_value = record::bag::topics::SCAN, requires = "bag")]
    scan_topic: String,
    /// With --bag: the JointState topic.
    #[arg(long, default_value = record::bag::topics::JOINT_STATES, requires = "bag")]
    joints_topic: String,
    /// With --bag: skip a damaged chunk or a bad message (one that does not
    /// decode or holds values no sensor gives) and say how many were lost,
    /// instead of refusing the bag.
    #[arg(long, requires = "bag")]
    skip_bad_messages: bool,
    /// Scenario (built-in name or file) whose regions of interest A1 ⊂ A2 ⊂ A3
    /// bound the grid (default: the config's, which are the bridge scenarios').
    #[arg(long)]
    scenario: Option<String>,
    /// The whole map configuration (TOML, fields of `MapConfig`: tables `[occupancy]`, `[tsdf]`).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Print the configuration in effect as TOML and exit.
    #[arg(long)]
    print_config: bool,
    /// Voxel edge of both maps, metres (the TSDF truncation follows at four
    /// voxels) [config: occupancy.voxel_m, tsdf.voxel_m].
    #[arg(long, allow_negative_numbers = true)]
    voxel: Option<Real>,
    /// Folder for `mesh.ply` and `occupancy.json`.
    #[arg(long, required_unless_present = "print_config")]
    out: Option<PathBuf>,
}

pub fn map(a: &MapArgs) -> Result<()> {
    // clap leaves `requires` unchecked here (`--bag` and `--robot` require
    // each other and `--bag` conflicts with `--scans`): checked by hand.
    if a.robot.is_some() && a.bag.is_none() {
        bail!("--robot applies with --bag (the robot whose joint states place the bag's scans)");
    }
    if a.skip_bad_messages && a.bag.is_none() {
        bail!("--skip-bad-messages applies with --bag");
    }
    let mut config: MapConfig = load_config(a.config.as_deref())?;
    if let Some(v) = a.voxel {
        config = config.with_voxel_m(v);
    }
    if let Some(name) = &a.scenario {
        let loaded = scenario::Scenario::load(name)?;
        match loaded.scenario.regions {
            Some(regions) => config.occupancy.regions = regions,
            None => bail!("scenario {name} defines no regions of interest"),
        }
    }
    if a.print_config {
        put!("{}", config_toml(&config)?)?;
        return Ok(());
    }
    let Some(out) = &a.out else {
        bail!("--out is required");
    };
    let mut mapper = Mapper::new(&config)?;
    let from_bag = a.bag.is_some();
    let inputs: Vec<(String, Sweep)> = match &a.bag {
        Some(path) => sweeps_of_bag(a, path)?
            .sweeps
            .into_iter()
            .enumerate()
            .map(|(k, s)| (format!("{} sweep {k}", path.display()), s))
            .collect(),
        None => a
            .scans
            .iter()
            .map(|p| Ok((p.display().to_string(), Sweep::read_ply(p)?)))
            .collect::<Result<_>>()?,
    };
    for (path, sweep) in &inputs {
        let t0 = Instant::now();
        let summary = mapper.integrate_sweep(sweep);
        say!(
            "{}: {} points integrated in {:.1} ms ({} voxels newly known, {} occlusion segments ({}), {} TSDF voxel updates)",
            path,
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
            note!("warning: {path} holds no points");
        } else if summary.occupancy.rays_outside == sweep.len() {
            let b = mapper.occupancy().geometry().aabb();
            note!(
                "warning: {}: all {} rays lie outside the occupancy map (A3 = [{:.2}, {:.2}] × [{:.2}, {:.2}] × [{:.2}, {:.2}] m): \
                 nothing was integrated into it (the TSDF mesh is not bounded by A3); check the scan's frame or pass --scenario with its regions",
                path,
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
    let mut staged = Staged::new();
    staged.ensure_dir(out)?;
    scene::io::write_mesh_ply(&staged.file_in(out, "mesh.ply")?, &outputs.mesh)?;
    let json = staged.file_in(out, "occupancy.json")?;
    std::fs::write(&json, outputs.report.to_json() + "\n")
        .with_context(|| format!("writing {}", out.join("occupancy.json").display()))?;
    let discs = if from_bag {
        let points: Vec<sensor::SweepPoint> = inputs
            .iter()
            .flat_map(|(_, s)| s.points().iter().copied())
            .collect();
        record::explore::write_cloud(&staged.file_in(out, record::explore::CLOUD_PLY)?, &points)?;
        // Paul §5.2: the discs of the fused mesh.
        let normals = outputs.mesh.vertex_normals();
        let sld = generate_discs(
            &outputs.mesh.vertices,
            map::Orientation::ReferenceNormals(&normals),
            &SldConfig::default(),
            0,
        )?;
        save_discs_csv(&staged.file_in(out, "discs.csv")?, &sld.discs, &[])?;
        Some((points.len(), sld.discs.len()))
    } else {
        None
    };
    staged.commit()?;
    if let Some((points, discs)) = discs {
        say!(
            "{points} points → {}; {discs} discs of the mesh → {}",
            out.join(record::explore::CLOUD_PLY).display(),
            out.join("discs.csv").display()
        )?;
    }
    let r = &outputs.report;
    say!(
        "mesh: {} vertices, {} triangles (extracted in {:.1} ms) → {}",
        outputs.mesh.vertices.len(),
        outputs.mesh.len(),
        1000.0 * t_mesh,
        out.join("mesh.ply").display()
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
        out.join("occupancy.json").display()
    )?;
    Ok(())
}

/// The sweeps of `--bag` for `--robot`, after saying what was read.
fn sweeps_of_bag(a: &MapArgs, path: &std::path::Path) -> Result<record::bag::BagSweeps> {
    let Some(name) = &a.robot else {
        bail!("--bag needs --robot");
    };
    let robot = scenario::RobotChoice::parse(name, None)?.build()?;
    let topics = record::bag::ScanTopics {
        scan: a.scan_topic.clone(),
        joints: a.joints_topic.clone(),
        scanner_link: a.scanner_link.clone(),
    };
    let t0 = Instant::now();
    let b = record::bag::sweeps_from_bag(
        path,
        &robot,
        &topics,
        super::bad_messages(a.skip_bad_messages),
    )?;
    super::say_skipped(path, &b.skipped)?;
    say!(
        "{}: {} scans placed on link {} of {} in {} sweeps ({} outside the joint states' span){} in {:.1} ms",
        path.display(),
        b.scans,
        b.scanner_link,
        robot.name,
        b.sweeps.len(),
        b.unplaced,
        if b.base_from_bag {
            ", base placed by the bag's /tf_static"
        } else {
            ", base at the origin (no /tf_static for it)"
        },
        1000.0 * t0.elapsed().as_secs_f64()
    )?;
    if b.sweeps.is_empty() {
        bail!("{}: no scan could be placed", path.display());
    }
    Ok(b)
}
