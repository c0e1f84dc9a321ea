//! A sweep of bridge1 from its start pose, scenario files, and ground-truth
//! contacts of the VM-6083.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use geom::{Point3, Real};
use plan::contact::robot_contacts;
use scenario::LoadedScenario;
use scenario::{BUILTIN_NAMES, Scenario, builtin_scenario};
use sim::scan_job::ScanSetup;

fn bridge1() -> LoadedScenario {
    LoadedScenario {
        scenario: builtin_scenario("bridge1").unwrap(),
        base_dir: ".".into(),
    }
}

#[test]
fn every_builtin_scenario_round_trips_through_toml() {
    for name in BUILTIN_NAMES {
        let s = builtin_scenario(name).unwrap();
        let text = s.to_toml().unwrap();
        let back = Scenario::from_toml(&text, name).unwrap();
        assert_eq!(back, s, "{name}");
        // And it builds: robot, start pose, world.
        let loaded = LoadedScenario {
            scenario: back,
            base_dir: ".".into(),
        };
        let robot = loaded.build_robot().unwrap();
        assert_eq!(robot.dof(), loaded.scenario.robot.start_joints.len());
        loaded.build_world().unwrap();
    }
}

#[test]
fn scenario_errors_name_the_file_and_field() {
    let mut s = builtin_scenario("bridge1").unwrap();
    s.robot.start_joints.pop();
    let loaded = LoadedScenario {
        scenario: s,
        base_dir: ".".into(),
    };
    let err = loaded.build_robot().unwrap_err().to_string();
    assert!(err.contains("start_joints"), "{err}");
    let err = Scenario::from_toml(
        "name = \"x\"\n[robot]\nstart_joints = [0]\nbogus = 1\n",
        "my.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("my.toml") && err.contains("bogus"), "{err}");
    let err = Scenario::load("no-such-scenario").unwrap_err().to_string();
    assert!(err.contains("bridge1"), "{err}");
}

#[test]
fn bridge1_start_sweep_sees_roof_webs_and_flanges_with_materials() {
    let loaded = bridge1();
    // Without noise every point lies on the surface it came from, so the object
    // nearest to it is the object hit (thin parts like the 4 mm sheet included).
    let mut setup = ScanSetup::from_scenario(&loaded, None, None, 7).unwrap();
    setup.scanner.noise.enabled = false;
    setup.scanner.material_range_bias = false;
    let outcome = setup.run(&mut |_, _| {}).unwrap();
    assert!(outcome.contacts.is_empty(), "{:?}", outcome.contacts);
    let sweep = &outcome.sweep;
    let shape = sweep.grid_shape().unwrap();
    assert_eq!(shape.scans, 151);
    assert_eq!(shape.rays_per_scan, 342);
    assert_eq!(sweep.scanner_poses().len(), 151);
    let scene = setup.world.as_scene().unwrap();
    let name_of = |p: &Point3| {
        let (_, face, _) = scene.closest_point(p, 0.2).unwrap();
        scene.objects()[scene.triangle_object(face).index()]
            .name
            .clone()
    };
    let mut roof = 0;
    let (mut left_web, mut right_web, mut left_flange, mut right_flange) = (0, 0, 0, 0);
    let mut disagree = 0;
    for p in sweep.points() {
        let mat = &scene
            .material(p.material.expect("simulated material"))
            .unwrap()
            .name;
        let name = name_of(&p.point);
        // The material the scanner reported is the material of the object the
        // point lies on (bar ties exactly on the junction of two objects).
        let object_material = {
            let o = scene.objects().iter().find(|o| o.name == name).unwrap();
            &scene.material(o.material).unwrap().name
        };
        disagree += usize::from(mat != object_material);
        let q = p.point;
        match name.as_str() {
            "roof" => roof += 1,
            // The containment sheet covers the right web over x ∈ [-1.5, 1.5], the
            // whole stretch a sweep from the start pose can see: the sheet is what
            // the scanner sees of that web.
            "sheet" => right_web += 1,
            "left_beam" | "right_beam" => {
                let web = (q.y.abs() - 0.75).abs() < 0.03 && q.z > 0.83 && q.z < 1.49;
                let flange = q.y.abs() > 0.6 && (q.z < 0.83 || q.z > 1.49);
                match (name.as_str(), web, flange) {
                    ("left_beam", true, _) => left_web += 1,
                    ("right_beam", true, _) => right_web += 1,
                    ("left_beam", _, true) => left_flange += 1,
                    ("right_beam", _, true) => right_flange += 1,
                    _ => {}
                }
            }
            _ => {}
        }
    }
    assert!(
        disagree * 1000 < sweep.len(),
        "{disagree} material mismatches"
    );
    assert!(roof > 1000, "roof {roof}");
    assert!(
        left_web > 100 && right_web > 100,
        "webs {left_web} {right_web}"
    );
    assert!(
        left_flange > 100 && right_flange > 100,
        "flanges {left_flange} {right_flange}"
    );
    // With noise, points stay near the true surface (σ 10 mm, 1 % beyond 1 m).
    let noisy = ScanSetup::from_scenario(&loaded, None, None, 7).unwrap();
    let sweep = &noisy.run(&mut |_, _| {}).unwrap().sweep;
    let scores = noisy.score(sweep).unwrap().unwrap();
    let mean_m = scores.accuracy.distances.unwrap().mean_m;
    assert!(mean_m < 0.012, "{:?}", scores.accuracy);
    assert!(scores.coverage.fraction() > 0.05 && scores.coverage.fraction() < 0.95);
}

#[test]
fn same_seed_same_sweep() {
    let loaded = bridge1();
    let a = ScanSetup::from_scenario(&loaded, None, Some(4.0), 3).unwrap();
    let b = ScanSetup::from_scenario(&loaded, None, Some(4.0), 3).unwrap();
    let c = ScanSetup::from_scenario(&loaded, None, Some(4.0), 4).unwrap();
    let sa = a.run(&mut |_, _| {}).unwrap().sweep;
    let sb = b.run(&mut |_, _| {}).unwrap().sweep;
    let sc = c.run(&mut |_, _| {}).unwrap().sweep;
    assert_eq!(sa, sb);
    assert_ne!(sa, sc);
}

#[test]
fn vm6083_contacts_against_the_bridge() {
    let loaded = bridge1();
    let robot = loaded.build_robot().unwrap();
    let world = loaded.build_world().unwrap();
    let scene = world.as_scene().unwrap();
    let base = loaded.scenario.world_from_base();
    let deg = |v: [Real; 6]| -> Vec<Real> { v.iter().map(|d| d.to_radians()).collect() };
    // Clear poses: the start pose and a few others well inside the channel.
    for q in [
        loaded.scenario.robot.start_joints.clone(),
        deg([0.0, 0.0, 90.0, 0.0, 0.0, 0.0]),
        deg([30.0, -30.0, 120.0, 0.0, -60.0, 0.0]),
    ] {
        let frames = robot.forward_kinematics(&q).unwrap();
        let c = robot_contacts(&robot, &frames, &base, scene);
        assert!(c.is_empty(), "{q:?}: {c:?}");
    }
    // Into the walls: the forearm stretched sideways through the left web
    // (y = 0.744, forearm at z ≈ 0.91 from y 0.37 to 0.82), and folded down
    // through the floor (wrist at z ≈ -0.16).
    for (q, wall) in [
        (
            deg([90.0, 30.0, 60.0, 0.0, 30.0, 0.0]),
            ["left_beam", "plate"].as_slice(),
        ),
        (
            deg([0.0, 120.0, 60.0, 0.0, 0.0, 0.0]),
            ["floor", "platform"].as_slice(),
        ),
    ] {
        let frames = robot.forward_kinematics(&q).unwrap();
        let tip = robot.tool_pose(&q).unwrap().translation.vector;
        let c = robot_contacts(&robot, &frames, &base, scene);
        assert!(
            !c.is_empty(),
            "{q:?} (tool at {tip:?}) should touch {wall:?}"
        );
        let names: Vec<&str> = c
            .iter()
            .map(|c| scene.objects()[c.object.index()].name.as_str())
            .collect();
        assert!(names.iter().any(|n| wall.contains(n)), "{names:?}");
    }
}

#[test]
fn coverage_tracker_matches_coverage_of_all_points_after_each_batch() {
    use sim::metrics::{CoverageTracker, coverage};
    let loaded = bridge1();
    let mut metrics = loaded.scenario.metrics;
    metrics.sampling.samples_per_m2 = 2000.0;
    metrics.sampling.region = Some(loaded.scenario.regions.unwrap().a1.aabb());
    let scene_world = loaded.build_world().unwrap();
    let scene = scene_world.as_scene().unwrap();
    let mut tracker = CoverageTracker::new(scene, &metrics).unwrap();
    assert_eq!(tracker.fraction(), 0.0);
    let mut all: Vec<Point3> = Vec::new();
    // The third batch repeats the first: its cells are covered already and
    // skipped (`CoverageTracker` looks only in cells with uncovered samples).
    for q1 in [0.0f64, 60.0, 0.0] {
        let joints: Vec<Real> = [q1, -55.0, 165.0, 0.0, -110.0, 0.0]
            .iter()
            .map(|d| d.to_radians())
            .collect();
        let setup = ScanSetup::from_scenario(&loaded, Some(joints), Some(20.0), 1).unwrap();
        let points = setup.run(&mut |_, _| {}).unwrap().sweep.positions();
        tracker.add_points(&points);
        all.extend(&points);
        let direct = coverage(scene, &all, &metrics).unwrap();
        assert_eq!(tracker.report(), direct);
        assert!(direct.covered > 0);
        // `bits_of` (the oracle's: cells whose samples are all marked are
        // skipped) marks as many samples as there are covered.
        let bits = tracker.bits_of(&all);
        let marked: u32 = bits.iter().map(|w| w.count_ones()).sum();
        assert_eq!(marked as usize, direct.covered);
    }
}
