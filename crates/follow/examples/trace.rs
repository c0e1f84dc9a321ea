//! Follow a built-in scene with a built-in robot in a simulated world and print
//! what happens (a development aid; `surveyor follow` is the product):
//! `cargo run --release -p follow --example trace -- cube point3 3000 [noise_m] [alpha]`.
//! `RLE=1` prints every change of mode, current segment or current edge;
//! `COLL=1` every collision (`COLLX=1` adds which link points touch, with the
//! scene's and the model's distance there); `RANGE=a-b` steps a..b in detail
//! (how far the control point moved against the motion asked); `SENS=a-b` the
//! control point's range finders before steps a..b and where each sensed point
//! lies in the updated model (it reads the sensors an extra time, so with
//! noise the run differs from one without `SENS`); `NEAR=k` the segments near
//! the control point after step k.

#[path = "../tests/support/mod.rs"]
mod support;

use follow::{FollowConfig, Mode};
use geom::Real;
use std::collections::BTreeMap;

#[allow(
    clippy::too_many_lines,
    reason = "a development aid's one loop with its optional printouts, each a few lines"
)]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let scene_name = args.get(1).map_or("cube", String::as_str);
    let robot_name = args.get(2).map_or("point3", String::as_str);
    let max: usize = args.get(3).map_or(Ok(3000), |s| s.parse())?;
    let noise: Real = args.get(4).map_or(Ok(0.0), |s| s.parse())?;
    let alpha: Real = args.get(5).map_or(Ok(7000.0), |s| s.parse())?;
    let config = FollowConfig {
        alpha,
        ..FollowConfig::default()
    };
    let mut run = support::Run::new(scene_name, robot_name, config, 1);
    run.noise_m = noise;
    let mut modes: BTreeMap<Mode, usize> = BTreeMap::new();
    let mut parts = [0.0; 3];
    let mut all_us: Vec<Real> = Vec::new();
    let mut collisions = 0;
    let mut min_clear = Real::INFINITY;
    let rle = std::env::var("RLE").is_ok();
    let mut last_key = String::new();
    let t = std::time::Instant::now();
    let mut steps = 0;
    let mut last_cp = geom::Point3::origin();
    for k in 0..max {
        let sens = std::env::var("SENS").ok().and_then(|r| {
            let (a, b) = r.split_once('-')?;
            Some((a.parse::<usize>().ok()?..b.parse::<usize>().ok()?).contains(&k))
        });
        let mut sensed = Vec::new();
        if sens == Some(true) {
            // The control point's range finders (the first ones): ray and reading.
            let rays = run.follower.sensor_rays(&run.q)?;
            let readings = run.readings();
            sensed = readings.iter().flatten().copied().collect();
            for (i, ((o, a), r)) in rays.iter().zip(&readings).enumerate().take(17) {
                println!(
                    "    sensor {i:2} from ({:.3},{:.3},{:.3}) axis ({:.2},{:.2},{:.2}) {}",
                    o.x,
                    o.y,
                    o.z,
                    a.x,
                    a.y,
                    a.z,
                    r.map_or("-".to_owned(), |p| format!("hit at {:.3}", (p - o).norm()))
                );
            }
        }
        let step = run.step();
        steps += 1;
        for p in &sensed {
            // Where each point sensed for this step lies in the updated model.
            let model = run.follower.model();
            if let Some(c) = follow::query::closest_model_point(model, p, 1.0) {
                println!(
                    "    sensed ({:.3},{:.3},{:.3}): nearest model {:?} {:.3} away",
                    p.x, p.y, p.z, c.segment, c.distance
                );
            }
        }
        parts[0] += step.times.update_us;
        parts[1] += step.times.direction_us;
        parts[2] += step.times.kinematics_us;
        all_us.push(step.times.update_us + step.times.direction_us + step.times.kinematics_us);
        *modes.entry(step.mode).or_default() += 1;
        let key = format!(
            "{:?} {:?} {:?}",
            step.mode, step.current_segment, step.current_edge
        );
        if std::env::var("GUARD").is_ok() && step.guard != follow::GuardAction::Taken {
            println!("  {k} guard {:?} {:?}", step.guard, step.mode);
        }
        if (rle && key != last_key) || k % 100 == 0 {
            let c = step.control_point;
            println!(
                "{k}: {key} cp ({:.3},{:.3},{:.3}) model {}",
                c.x,
                c.y,
                c.z,
                run.follower.model().len()
            );
            last_key = key;
        }
        if let Some(term) = step.termination {
            println!("terminated at step {k}: {term:?}");
            break;
        }
        if std::env::var("NEAR")
            .ok()
            .and_then(|v| v.parse::<usize>().ok())
            == Some(k)
        {
            // The segments near the control point after this step's update.
            let cp = step.control_point;
            let model = run.follower.model();
            for g in model.segments() {
                if let Some(c) = follow::query::closest_on_segment(model, g.id(), &cp)
                    && c.distance < 0.2
                {
                    println!(
                        "    near {:?}: {} points, {}, closest ({:.3},{:.3},{:.3}) at {:.3}",
                        g.id(),
                        g.points(),
                        g.as_polygon().map_or("point".to_owned(), |p| format!(
                            "polygon n ({:.2},{:.2},{:.2}) {} vertices",
                            p.normal().x,
                            p.normal().y,
                            p.normal().z,
                            p.len()
                        )),
                        c.point.x,
                        c.point.y,
                        c.point.z,
                        c.distance
                    );
                }
            }
        }
        let prev_cp = last_cp;
        last_cp = step.control_point;
        let in_range = std::env::var("RANGE").ok().and_then(|r| {
            let (a, b) = r.split_once('-')?;
            Some((a.parse::<usize>().ok()?..b.parse::<usize>().ok()?).contains(&k))
        });
        if in_range == Some(true) {
            let dq = step.dq.iter().map(|d| d * d).sum::<Real>().sqrt();
            println!(
                "  {k} {:?} model_distance {:.4} moved ({:.4},{:.4},{:.4}) motion ({:.3},{:.3},{:.3}) |dq| {dq:.4} clear {:?}",
                step.mode,
                step.model_distance,
                step.control_point.x - prev_cp.x,
                step.control_point.y - prev_cp.y,
                step.control_point.z - prev_cp.z,
                step.motion.x,
                step.motion.y,
                step.motion.z,
                step.link_clearance
            );
        }
        let c = run.clearance();
        min_clear = min_clear.min(c);
        let near: Real = std::env::var("CLEAR")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(0.0);
        if c < near {
            collisions += 1;
            if std::env::var("COLL").is_ok() {
                let cp = step.control_point;
                println!(
                    "collision after step {k}: {:?} true clearance {c:.3}, model link clearance {:?}, cp ({:.3},{:.3},{:.3}) |dq| {:.4} motion {:.3}",
                    step.mode,
                    step.link_clearance,
                    cp.x,
                    cp.y,
                    cp.z,
                    step.dq.iter().map(|d| d * d).sum::<Real>().sqrt(),
                    step.motion.norm()
                );
                if std::env::var("COLLX").is_ok() {
                    run.explain_collision(near);
                }
            }
        }
    }
    let n = steps as Real;
    println!(
        "{steps} steps in {:.2} s wall; modes {modes:?}; collisions {collisions}; min clearance {min_clear:.3} m",
        t.elapsed().as_secs_f64()
    );
    println!(
        "mean µs: update {:.1} direction {:.1} kinematics {:.1}",
        parts[0] / n,
        parts[1] / n,
        parts[2] / n
    );
    all_us.sort_by(Real::total_cmp);
    if !all_us.is_empty() {
        println!(
            "step µs: median {:.1} p95 {:.1} max {:.1}",
            all_us[all_us.len() / 2],
            all_us[all_us.len() * 95 / 100],
            all_us[all_us.len() - 1]
        );
    }
    let inc = run.follower.incomplete_edges();
    println!(
        "incomplete edges: {} (total {:.3} m); marks (unreachable segments, unclosable points, unreachable edges, unclosable edges) {:?}",
        inc.len(),
        inc.iter().map(follow::query::EdgeRef::length).sum::<Real>(),
        run.follower.mark_counts()
    );
    for seg in run.follower.model().segments() {
        if let Some(p) = seg.as_polygon() {
            let n = p.normal();
            println!(
                "  {:?}: {} vertices, {} points, area {:.3}, normal ({:.3}, {:.3}, {:.3})",
                seg.id(),
                p.len(),
                seg.points(),
                p.area(),
                n.x,
                n.y,
                n.z
            );
        }
    }
    println!(
        "guard: {:?}, {} deleted segments kept",
        run.follower.guard_counts(),
        run.follower.guard_ghosts()
    );
    let st = run.follower.model().stats();
    println!(
        "model: {} segments, {} polygons, {} shared pairs, {} corners",
        st.segments, st.polygons, st.shared_edge_pairs, st.corner_vertices
    );
    Ok(())
}
