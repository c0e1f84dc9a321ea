//! Build (or load) the C-space model of a built-in robot and print what it
//! holds: `cargo run --release -p plan --example cspace -- [robot] [n_q] [voxel_m] [cache.json]`.

use geom::Isometry3;
use plan::{CspaceModel, PlanConfig};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("denso-vm6083", String::as_str);
    let n_q = args.get(1).map_or(Ok(1571), |s| s.parse())?;
    let voxel_m = args.get(2).map_or(Ok(0.05), |s| s.parse())?;
    let robot = robot::builtin(name)?;
    let frames = robot.forward_kinematics(&vec![0.0; robot.dof()])?;
    for (link, e) in robot.posed_ellipsoids(&frames) {
        println!(
            "link {}: ellipsoid radii {:.3} {:.3} {:.3} m",
            link.index(),
            e.radii.x,
            e.radii.y,
            e.radii.z
        );
    }
    let config = PlanConfig {
        n_q,
        ..PlanConfig::default()
    };
    let t = Instant::now();
    let (model, outcome) = match args.get(3) {
        Some(path) => CspaceModel::load_or_build(
            std::path::Path::new(path),
            &robot,
            &Isometry3::identity(),
            voxel_m,
            &config,
        )?,
        None => (
            CspaceModel::build(&robot, &Isometry3::identity(), voxel_m, &config)?,
            plan::CacheOutcome::Built("no cache file given".into()),
        ),
    };
    let took = t.elapsed();
    let map = model.roadmap();
    let usage = model.usage();
    let (lo, hi) = usage
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &l| (a.min(l), b.max(l)));
    let inter = model.interference();
    let per_node: f64 = inter
        .voxels_per_node
        .iter()
        .map(|&v| f64::from(v))
        .sum::<f64>()
        / inter.voxels_per_node.len() as f64;
    println!("{outcome:?} in {:.2} s", took.as_secs_f64());
    println!(
        "{} nodes, {} edges, {} component(s); joint weights {:.3?} m/rad",
        map.len(),
        map.edges().len(),
        map.components(),
        map.weights()
    );
    println!("L(c_i) from {lo:.2e} to {hi:.2e}");
    println!(
        "{} voxels interfere with some node; {per_node:.0} voxels per node on average; max P(x_c) {:.3}",
        inter.probabilities.len(),
        inter.probabilities.iter().map(|p| p.1).fold(0.0, f64::max)
    );
    Ok(())
}
