//! Which faces of a built-in surface-following scene a robot can bring its
//! control point to (`scenario::job::reach`), from arm4's post beside it or
//! from a mount above it:
//! `cargo run --release -p sim --example follow_reach -- block1 [post|above]`.

use geom::{Isometry3, Real, Translation3, UnitQuaternion, Vector3};
use scenario::Scenario;
use scenario::job::reach::{ReachConfig, face_reachability};
use sim::follow_job::{ARM4_BASE_XYZ, ARM4_SEED};
use sim::surface_score::not_resting_on;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("cube", String::as_str);
    let mount = args.get(2).map_or("post", String::as_str);
    let scenario = Scenario::load(name)?;
    let world = scenario.build_world()?;
    let scene = world.as_scene().ok_or("the scenario has no mesh")?;
    let robot = robot::builtin("arm4")?;
    let base = match mount {
        "post" => Isometry3::translation(ARM4_BASE_XYZ[0], ARM4_BASE_XYZ[1], ARM4_BASE_XYZ[2]),
        "above" => {
            let h: Real = args.get(3).map_or(Ok(3.2), |s| s.parse())?;
            Isometry3::from_parts(
                Translation3::new(0.0, 0.0, h),
                UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI),
            )
        }
        other => return Err(format!("mount {other}: expected post or above").into()),
    };
    let t = std::time::Instant::now();
    let reach = face_reachability(
        scene,
        &robot,
        &base,
        &[ARM4_SEED.to_vec()],
        not_resting_on(0.0),
        &ReachConfig::default(),
    );
    for f in &reach {
        println!(
            "face {:2} normal ({:5.2},{:5.2},{:5.2}) {:.2} m²: {:3} of {:3} samples reached ({:.0} %)",
            f.face,
            f.normal[0],
            f.normal[1],
            f.normal[2],
            f.area_m2,
            f.reached,
            f.samples,
            100.0 * f.fraction()
        );
    }
    println!("{:.1} s", t.elapsed().as_secs_f64());
    Ok(())
}
