//! Follow a built-in scene with a built-in robot in a simulated world and print
//! what happens (a development aid): `cargo run --release -p follow --example
//! trace -- cube point3 3000`.

use follow::{FollowConfig, Follower, Mode};
use geom::{Isometry3, Point3, Real};
use rand::SeedableRng;
use sensor::RangeFinder;
use std::collections::BTreeMap;
use surface::{SurfaceConfig, SurfaceModel};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let scene_name = args.get(1).map_or("cube", String::as_str);
    let robot_name = args.get(2).map_or("point3", String::as_str);
    let max: usize = args.get(3).map_or(Ok(3000), |s| s.parse())?;
    let noise: Real = args.get(4).map_or(Ok(0.0), |s| s.parse())?;
    let world = scene::builtin::scene(scene_name)
        .ok_or("unknown scene")?
        .build(std::path::Path::new("."))?;
    let scene = world.as_scene().ok_or("not a mesh scene")?.clone();
    let robot = robot::builtin(robot_name)?;
    let mut model = SurfaceModel::new(SurfaceConfig::default())?;
    model.add_initial_segment(&[
        Point3::new(-2.0, -2.0, 0.0),
        Point3::new(2.0, -2.0, 0.0),
        Point3::new(2.0, 2.0, 0.0),
        Point3::new(-2.0, 2.0, 0.0),
    ])?;
    let top = match scene_name {
        "cube" => [0.0, 0.0, 1.0],
        "block1" => [-0.3, 0.0, 0.8],
        "block2" => [0.025, 0.0, 0.6],
        _ => [0.0, 0.0, 0.8],
    };
    let (base, mut q): (Isometry3, Vec<Real>) = if robot_name == "point3" {
        (Isometry3::identity(), vec![top[0], top[1], top[2] + 0.1])
    } else {
        let base = Isometry3::translation(-1.6, 0.0, 0.0);
        let target = Point3::new(top[0], top[1], top[2] + 0.1);
        let q = follow::place_tool(
            &robot,
            &base,
            &target,
            &-geom::Vector3::z_axis(),
            &[vec![0.0, 0.8, 0.0, 1.0, 0.0, 1.0]],
        )?;
        (base, q)
    };
    let mut follower = Follower::new(robot.clone(), base, model, FollowConfig::default())?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let mut modes: BTreeMap<Mode, usize> = BTreeMap::new();
    let mut total_us = 0.0;
    let mut parts = [0.0; 3];
    let mut collisions = 0;
    let mut min_clear = Real::INFINITY;
    let t = std::time::Instant::now();
    let mut steps = 0;
    let mut last_key = String::new();
    for k in 0..max {
        let frames = robot.forward_kinematics(&q)?;
        let readings: Vec<Option<Point3>> = robot
            .range_finders
            .iter()
            .map(|m| {
                RangeFinder {
                    origin: m.origin,
                    axis: m.axis,
                    max_range_m: m.max_range_m,
                    noise_sigma_m: noise,
                }
                .measure(&world, &(base * frames[m.link.0]), &mut rng)
                .map(|s| s.point)
            })
            .collect();
        let step = follower.step(&q, &readings)?;
        steps += 1;
        total_us += step.times.update_us + step.times.direction_us + step.times.kinematics_us;
        *modes.entry(step.mode).or_default() += 1;
        parts[0] += step.times.update_us;
        parts[1] += step.times.direction_us;
        parts[2] += step.times.kinematics_us;
        if let Some(term) = step.termination {
            println!("terminated at step {k}: {term:?}");
            break;
        }
        for (qi, d) in q.iter_mut().zip(&step.dq) {
            *qi += d;
        }
        let frames = robot.forward_kinematics(&q)?;
        for shape in robot.posed_collision_shapes(&frames) {
            if let robot::PosedShape::Capsule { link, capsule } = shape {
                if link.0 == 0 {
                    continue;
                }
                let c = capsule.transformed(&base);
                let d = scene
                    .closest_point(&c.segment.a, 5.0)
                    .map_or(5.0, |x| x.0)
                    .min(scene.closest_point(&c.segment.b, 5.0).map_or(5.0, |x| x.0));
                let _ = d;
                if scene.capsule_contact(&c, 0.0).is_some() {
                    collisions += 1;
                }
                if let Some((_, dd)) = scene.capsule_contact(&c, 0.3) {
                    min_clear = min_clear.min(dd - c.radius);
                }
            }
        }
        if std::env::var("RLE").is_ok() {
            let key = format!(
                "{:?} {:?} {:?}",
                step.mode, step.current_segment, step.current_edge
            );
            if key != last_key {
                println!(
                    "{k}: {key} cp ({:.3},{:.3},{:.3}) model {}",
                    step.control_point.x,
                    step.control_point.y,
                    step.control_point.z,
                    follower.model().len()
                );
                last_key = key;
            }
        }
        if k % 100 == 0 || std::env::var("TRACE").is_ok() {
            println!(
                "{k}: {:?} cp ({:.3},{:.3},{:.3}) seg {:?} edge {:?} model {} segs",
                step.mode,
                step.control_point.x,
                step.control_point.y,
                step.control_point.z,
                step.current_segment,
                step.current_edge,
                follower.model().len()
            );
        }
    }
    println!(
        "mean µs: update {:.1} direction {:.1} kinematics {:.1}",
        parts[0] / steps as Real,
        parts[1] / steps as Real,
        parts[2] / steps as Real
    );
    let st = follower.model().stats();
    println!(
        "{steps} steps in {:.2} s wall; mean step {:.1} µs; modes {modes:?}; collisions {collisions}; min clearance {min_clear:.3}",
        t.elapsed().as_secs_f64(),
        total_us / steps as Real
    );
    for seg in follower.model().segments() {
        if let Some(p) = seg.as_polygon() {
            println!(
                "  {:?}: {} vertices, {} points, area {:.3}, n {:?}",
                seg.id(),
                p.len(),
                seg.points(),
                p.area(),
                p.normal().into_inner().as_slice()
            );
        }
    }
    println!(
        "model: {} segments, {} polygons, {} shared pairs, {} corners",
        st.segments, st.polygons, st.shared_edge_pairs, st.corner_vertices
    );
    Ok(())
}
