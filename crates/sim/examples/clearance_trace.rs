//! Each link's true clearance at every pose of a follow run (a development
//! aid): `cargo run --release -p sim --example clearance_trace -- block2
//! DIR/steps.csv [below_m]` prints, for every step where some link of arm4
//! (on its post, `sim::follow_job::ARM4_BASE_XYZ`) comes closer to the true
//! scene than `below_m` (0.025 by default), the step, the mode, the closest
//! link, its clearance, where along the link's axis the closest point lies
//! (0 at the joint, 1 at the far end), the scene triangle's normal and the
//! follower's own link clearance from the model (`link_clearance_m`,
//! measured from the capsule axis); and at the end the smallest clearance
//! of each link over the run.

use geom::{Isometry3, Real, Segment3};
use robot::PosedShape;
use scenario::Scenario;
use sim::follow_job::ARM4_BASE_XYZ;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("block2", String::as_str);
    let steps = args
        .get(2)
        .ok_or("usage: clearance_trace SCENE STEPS_CSV [below_m]")?;
    let below: Real = args.get(3).map_or(Ok(0.025), |s| s.parse())?;
    let scenario = Scenario::load(name)?;
    let world = scenario.build_world()?;
    let scene = world.as_scene().ok_or("the scenario has no mesh")?;
    let robot = robot::builtin("arm4")?;
    let base = Isometry3::translation(ARM4_BASE_XYZ[0], ARM4_BASE_XYZ[1], ARM4_BASE_XYZ[2]);
    let rows = record::follow::read_steps(std::path::Path::new(steps))?;
    let mounted = robot.mounted_links();
    let mut frames = Vec::new();
    let mut per_link: Vec<(Real, u64)> = vec![(Real::INFINITY, 0); robot.links.len()];
    for r in &rows {
        robot.fk_into(&r.joints, &mut frames)?;
        let mut best: Option<(Real, usize, Real, geom::Vector3, geom::Point3, geom::Point3)> = None;
        for shape in robot.posed_collision_shapes(&frames) {
            let PosedShape::Capsule { link, capsule } = shape else {
                continue;
            };
            if link.index() < mounted {
                continue;
            }
            let c = capsule.transformed(&base);
            for face in scene.triangles_near(&c.bounding_box().loosened(0.2)) {
                let tri = scene.mesh().triangle(face as usize);
                let d = c.distance_to_triangle(&tri);
                if d < per_link[link.index()].0 {
                    per_link[link.index()] = (d, r.step);
                }
                if best.is_none_or(|b| d < b.0) {
                    // Where along the axis: the closest of 41 samples.
                    let s: &Segment3 = &c.segment;
                    let t = (0..=40)
                        .map(|i| Real::from(i) / 40.0)
                        .min_by(|a, b| {
                            tri.distance_to_point(&s.point_at(*a))
                                .total_cmp(&tri.distance_to_point(&s.point_at(*b)))
                        })
                        .unwrap_or(0.0);
                    let n = tri
                        .normal()
                        .map_or(geom::Vector3::zeros(), geom::UnitVector3::into_inner);
                    let on_axis = s.point_at(t);
                    let on_scene = tri.closest_point(&on_axis);
                    best = Some((d, link.index(), t, n, on_axis, on_scene));
                }
            }
        }
        if let Some((d, link, t, n, on_axis, on_scene)) = best
            && d < below
        {
            println!(
                "step {:5} {:7} link {:10} {:6.1} mm at {:.2} normal ({:5.2},{:5.2},{:5.2}) model {} q [{}] axis ({:.4},{:.4},{:.4}) scene ({:.4},{:.4},{:.4})",
                r.step,
                r.mode,
                robot.links[link].name,
                1000.0 * d,
                t,
                n.x,
                n.y,
                n.z,
                r.link_clearance_m
                    .map_or("-".to_owned(), |v| format!("{:.1} mm", 1000.0 * v)),
                r.joints
                    .iter()
                    .map(|v| format!("{v:.2}"))
                    .collect::<Vec<_>>()
                    .join(","),
                on_axis.x,
                on_axis.y,
                on_axis.z,
                on_scene.x,
                on_scene.y,
                on_scene.z
            );
        }
    }
    for (k, (d, step)) in per_link.iter().enumerate() {
        if d.is_finite() {
            println!(
                "link {:10} smallest {:6.1} mm at step {step}",
                robot.links[k].name,
                1000.0 * d
            );
        }
    }
    Ok(())
}
