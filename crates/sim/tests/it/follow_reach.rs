//! Issue 24 acceptance 1: which faces arm4 on its post at x = −1.6 m can
//! bring its control point to, decided by the inverse-kinematics test of
//! `sim::follow_reach` and re-run here. The faces it cannot reach are the
//! ones to give as initial segments (Pudney gave his objects' occluded faces
//! so, P§4.3).

use geom::Isometry3;
use scenario::Scenario;
use sim::follow_job::{ARM4_BASE_XYZ, ARM4_SEED};
use sim::follow_reach::{ReachConfig, face_reachability};
use sim::surface_score::not_resting_on;

#[test]
fn arm4_on_its_post_reaches_every_face_of_the_cube_but_the_far_one() {
    let world = Scenario::load("cube").unwrap().build_world().unwrap();
    let scene = world.as_scene().unwrap();
    let robot = robot::builtin("arm4").unwrap();
    let [x, y, z] = ARM4_BASE_XYZ;
    let config = ReachConfig {
        spacing_m: 0.2,
        ..ReachConfig::default()
    };
    let reach = face_reachability(
        scene,
        &robot,
        &Isometry3::translation(x, y, z),
        &[ARM4_SEED.to_vec()],
        not_resting_on(0.0),
        &config,
    );
    // The five faces above the table: the bottom rests on it.
    assert_eq!(reach.len(), 5, "{reach:?}");
    for f in &reach {
        println!(
            "normal {:?}: {:.0} % of {} samples",
            f.normal,
            100.0 * f.fraction(),
            f.samples
        );
        if f.normal[0] > 0.99 {
            // The +x face: 1.1 m past the post's side of the cube.
            assert_eq!(f.reached, 0, "{f:?}");
        } else {
            assert!(f.fraction() >= 0.9, "{f:?}");
        }
    }
}
