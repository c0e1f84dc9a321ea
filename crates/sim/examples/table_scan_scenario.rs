//! A surface-following scenario from a labelled scan of objects on a table
//! (an organized PCD with a `label` field, as the mOSD captures in `data/`):
//! the table plane fitted to the points labelled 1 is the world frame and the
//! initial segment (P§4.3), and point3 starts 0.1 m above the top of the
//! object with the most points. Prints the scenario file.
//!
//! `cargo run --release -p sim --example table_scan_scenario -- SCAN.pcd NAME [CLOUD_PATH]`
//! (`CLOUD_PATH`: the cloud's path as the file should name it, relative to
//! the scenario file; default SCAN.pcd as given). This is how
//! `data/scenarios/mosd_boxes5.toml` was made; `tests/it/mosd_scenario.rs`
//! re-runs the fit.

use geom::{Point3, Real};
use scenario::table_fit::{fit_table, points_labelled};
use std::collections::BTreeMap;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(scan), Some(name)) = (args.first(), args.get(1)) else {
        return Err("usage: table_scan_scenario SCAN.pcd NAME [CLOUD_PATH]".into());
    };
    let cloud_path = args.get(2).unwrap_or(scan);
    let cloud = scene::io::load_cloud(std::path::Path::new(scan))?;
    let labels = cloud.labels.clone().ok_or("the scan has no label field")?;
    let table = points_labelled(&cloud.points, &labels, 1);
    let fit = fit_table(&table, &Point3::origin(), 0.02)?;
    // The object with the most points, in the table frame.
    let mut objects: BTreeMap<i64, Vec<Point3>> = BTreeMap::new();
    for (p, l) in cloud.points.iter().zip(&labels) {
        if *l >= 2 {
            objects.entry(*l).or_default().push(fit.world_from_scan * p);
        }
    }
    let (label, points) = objects
        .iter()
        .max_by_key(|(l, pts)| (pts.len(), std::cmp::Reverse(**l)))
        .ok_or("no object points (labels 2 and up)")?;
    let top_z = points
        .iter()
        .map(|p| p.z)
        .fold(Real::NEG_INFINITY, Real::max);
    let mut near_top: Vec<&Point3> = points.iter().filter(|p| p.z > top_z - 0.02).collect();
    near_top.sort_by(|a, b| a.z.total_cmp(&b.z));
    let top = near_top[near_top.len() / 2].z;
    let k = near_top.len() as Real;
    let cx = near_top.iter().map(|p| p.x).sum::<Real>() / k;
    let cy = near_top.iter().map(|p| p.y).sum::<Real>() / k;
    let t = fit.world_from_scan.translation.vector;
    let (roll, pitch, yaw) = fit.world_from_scan.rotation.euler_angles();
    println!("# point3 follows a real scan as a point-cloud world: {scan}, made by");
    println!(
        "# `cargo run --release -p sim --example table_scan_scenario -- {}`.",
        args.join(" ")
    );
    println!(
        "# Table plane: PCA fit to the {} points labelled 1 ({:.1} mm RMS, {:.1} mm 95th",
        fit.points,
        1000.0 * fit.rms_m,
        1000.0 * fit.p95_m
    );
    println!("# percentile off the plane), the world frame (z up, table at z = 0) and, as its");
    println!("# convex hull with vertices closer than 2 cm merged, the initial segment (P§4.3).");
    println!(
        "# Start: 0.1 m above the top of object {label} ({} points; median height of its points",
        points.len()
    );
    println!("# within 2 cm of its highest, at their mean x, y).");
    println!("name = \"{name}\"");
    println!(
        "description = \"point3 over a real scan of objects on a table ({})\"",
        std::path::Path::new(scan)
            .file_name()
            .map_or_else(|| scan.clone(), |f| f.to_string_lossy().into_owned())
    );
    let verts: Vec<String> = fit
        .polygon
        .iter()
        .map(|v| format!("[{:.6}, {:.6}, 0.0]", v.x, v.y))
        .collect();
    println!("initial_segments = [[{}]]", verts.join(", "));
    println!();
    println!("[robot]");
    println!("preset = \"point3\"");
    println!("start_joints = [{cx:.4}, {cy:.4}, {:.4}]", top + 0.1);
    println!();
    println!("[scene.point_cloud]");
    println!("file = \"{cloud_path}\"");
    println!();
    println!("[scene.point_cloud.pose]");
    println!("translation = [{:.9}, {:.9}, {:.9}]", t.x, t.y, t.z);
    println!(
        "rpy_deg = [{:.9}, {:.9}, {:.9}]",
        roll.to_degrees(),
        pitch.to_degrees(),
        yaw.to_degrees()
    );
    println!();
    println!("# One camera view is a shell: it leaves sides unseen (a box's back, the part of a");
    println!("# box another hides), and point3's 26 range finders pass edges and corners between");
    println!("# their beams, so the body meets scan points no reading has touched. On these scans");
    println!("# the safety guard keeps 0.04 m (default 0.02 m) from what is known and a step is");
    println!("# at most 0.05 m (default 0.1 m), so the robot senses again before it goes far");
    println!("# into what it has not seen: the body kept 35 mm from every scan point in 19 of");
    println!("# 24 runs from shifted starts and under noise, and 26.9 mm at worst (the defaults:");
    println!(
        "# none, one touching). Issue 45 acceptance 6; crates/follow/README.md, \"Real scans\"."
    );
    println!("[follow]");
    println!("guard_margin_m = 0.04");
    println!("max_step_m = 0.05");
    Ok(())
}
