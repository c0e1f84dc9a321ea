//! Issue 24 acceptance 1: which faces arm4 on its post at x = −1.6 m can
//! bring its control point to, decided by the inverse-kinematics test of
//! `scenario::job::reach` and re-run here. The faces it cannot reach are the
//! ones to give as initial segments (Pudney gave his objects' occluded faces
//! so, P§4.3).

use geom::Isometry3;
use scenario::Scenario;
use scenario::job::reach::{ReachConfig, face_reachability};
use sim::follow_job::{ARM4_BASE_XYZ, ARM4_SEED};
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

/// The outline of a true face is its boundary loop, anticlockwise about its
/// outward normal, without collinear vertices: the cube's +x face is the
/// square x = 0.5, y, z in [−0.5, 0.5] × [0, 1].
#[test]
fn a_face_outline_is_its_boundary_anticlockwise_about_its_normal() {
    let world = Scenario::load("cube").unwrap().build_world().unwrap();
    let scene = world.as_scene().unwrap();
    let faces = scene::faces::true_faces(scene);
    let plus_x = faces.iter().find(|f| f.normal.x > 0.99).unwrap();
    let outline = scene::faces::face_outline(scene, plus_x).unwrap();
    assert_eq!(outline.len(), 4, "{outline:?}");
    for p in &outline {
        assert!(
            (p.x - 0.5).abs() < 1e-9 && (p.y.abs() - 0.5).abs() < 1e-9,
            "{p:?}"
        );
        assert!(p.z.abs() < 1e-9 || (p.z - 1.0).abs() < 1e-9, "{p:?}");
    }
    // Anticlockwise about +x: the signed area's normal points along +x.
    let mut n = geom::Vector3::zeros();
    for i in 0..4 {
        n += outline[i].coords.cross(&outline[(i + 1) % 4].coords);
    }
    assert!(n.x > 1.9, "{n:?}");
}

/// `surveyor follow --scenario cube --robot arm4` gives the +x face, out of
/// arm4's reach from its post, as an initial segment beside the table.
#[test]
fn arm4_on_the_cube_is_given_the_far_face() {
    let loaded = Scenario::load("cube").unwrap();
    let options = sim::follow_job::FollowRunOptions {
        robot: Some("arm4".to_owned()),
        ..sim::follow_job::FollowRunOptions::default()
    };
    let setup = sim::follow_job::FollowSetup::from_scenario(&loaded, &options).unwrap();
    assert_eq!(setup.a_priori_faces.len(), 1);
    assert_eq!(setup.a_priori_faces[0].normal, [1.0, 0.0, 0.0]);
    assert_eq!(
        setup.initial_segments.len(),
        loaded.scenario.initial_segments.len() + 1
    );
}
