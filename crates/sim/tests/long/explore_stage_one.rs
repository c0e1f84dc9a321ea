//! AXBAM exploration on bridge1 (issue 10): the information prediction
//! against the gain each candidate's sweep really brings (acceptance 3), a
//! Stage One run's safety audit, information history and determinism
//! (acceptance 7), the UR5 run (acceptance 6), Stage Two's views, H3 and
//! material accuracy (acceptance 2), and issue 11's blast plan over that
//! run (poses re-measured, orders compared, reachability).
//!
//! They take seconds in release and a minute or more in a debug build, so
//! they are ignored by `cargo test` and run by `.ci/run` in its release step:
//! `cargo test --release -p sim --test long explore_stage_one -- --ignored --nocapture`.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may panic

use hw::{Arm, tilt_sweep};
use scenario::Scenario;
use scenario::job::explore::{ExploreOptions, ExploreOutcome};
use sim::SimRig;
use sim::explore_job::run_exploration;
use std::sync::Arc;

/// Options with the C-space model cached once for the long tests (each
/// would otherwise build it again).
fn cached() -> ExploreOptions {
    ExploreOptions {
        cspace_cache: Some(
            std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("cspace-denso-vm6083.json"),
        ),
        ..ExploreOptions::default()
    }
}

/// Ranks with ties averaged (1-based).
fn ranks(v: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
            j += 1;
        }
        for k in &idx[i..=j] {
            r[*k] = (i + j) as f64 / 2.0 + 1.0;
        }
        i = j + 1;
    }
    r
}

/// Spearman's rank correlation: Pearson's on the ranks.
fn spearman(a: &[f64], b: &[f64]) -> f64 {
    let (ra, rb) = (ranks(a), ranks(b));
    let n = a.len() as f64;
    let (ma, mb) = (ra.iter().sum::<f64>() / n, rb.iter().sum::<f64>() / n);
    let cov: f64 = ra.iter().zip(&rb).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = ra.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = rb.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

#[test]
fn spearman_by_hand() {
    assert!((spearman(&[1.0, 2.0, 3.0], &[10.0, 20.0, 30.0]) - 1.0).abs() < 1e-12);
    assert!((spearman(&[1.0, 2.0, 3.0], &[3.0, 2.0, 1.0]) + 1.0).abs() < 1e-12);
    // d = (0, 1, −1, 0): 1 − 6·2 / (4·15) = 0.8.
    assert!((spearman(&[1.0, 2.0, 3.0, 4.0], &[1.0, 3.0, 2.0, 4.0]) - 0.8).abs() < 1e-12);
}

#[test]
#[ignore = "seconds in release; run by .ci/run"]
fn predicted_gain_ranks_candidates_like_the_gain_their_sweeps_bring() {
    // Three decisions along a run. At each, every candidate's motion (with
    // its scans) and sweep are simulated in the true scene and integrated
    // into a copy of the map: the weighted H1 they really remove is the
    // second method.
    let loaded = Scenario::load("bridge1").unwrap();
    // The sweep's prediction (A§4.2), as Paul made it: no scans on the way.
    // With them (the default) the prediction also credits 8 poses along the
    // straight motion, and against the motion's real 1° scans it ranked the
    // candidates of the second decision at Spearman 0.77 (2026-11-26): not
    // yet bounded here.
    let defaults = explore::ExploreConfig::default();
    let config = explore::ExploreConfig {
        motion_scan_step_deg: 0.0,
        prediction: explore::PredictionConfig {
            motion_poses: 0,
            ..defaults.prediction
        },
        ..defaults
    };
    let options = ExploreOptions {
        config: Some(config),
        ..cached()
    };
    let (setup, world) = scenario::job::explore::explore_setup(&loaded, &options).unwrap();
    let explore::Setup {
        robot,
        world_from_base: wfb,
        config,
        mut stage,
        start,
        ..
    } = setup;
    let scanner = sensor::Scanner::new(loaded.scenario.scanner.clone().unwrap().config).unwrap();
    let mut rig = SimRig::new(
        robot.clone(),
        Arc::clone(&world),
        wfb,
        &start,
        Some(scanner.clone()),
        0,
    )
    .unwrap();
    for decision in 0..3 {
        let sweep = tilt_sweep(&mut rig, &robot, &wfb, &config.sweep, &mut |_, _| {}).unwrap();
        stage.integrate(&sweep);
        let q = rig.joints();
        let d = stage.decide(&q, None, &[]).unwrap();
        let (h1, _) = stage.information();
        let stride = (d.candidates.len() / 40).max(1);
        let (mut predicted, mut obtained) = (Vec::new(), Vec::new());
        for c in d.candidates.iter().step_by(stride) {
            let mut trial = stage.clone();
            // The arm moves there in a straight joint motion, scanning as
            // it goes (what the prediction predicts), then sweeps.
            let mut other = SimRig::new(
                robot.clone(),
                Arc::clone(&world),
                wfb,
                &q,
                Some(scanner.clone()),
                1,
            )
            .unwrap();
            let step = config.motion_scan_step_deg.to_radians();
            if step > 0.0 {
                let mut on_the_way = sensor::SweepBuilder::new(scanner.bearings_rad()).unwrap();
                hw::scan_motion(
                    &mut other,
                    &robot,
                    &wfb,
                    (&q, &c.q),
                    step,
                    &mut on_the_way,
                    &mut |_, _, _| true,
                )
                .unwrap();
                trial.integrate_motion(&on_the_way.finish().unwrap());
            } else {
                other.move_to(&c.q).unwrap();
            }
            let sw = tilt_sweep(&mut other, &robot, &wfb, &config.sweep, &mut |_, _| {}).unwrap();
            trial.integrate(&sw);
            predicted.push(h1 - c.f[0]);
            obtained.push(h1 - trial.information().0);
        }
        let rho = spearman(&predicted, &obtained);
        println!(
            "decision {decision}: {} candidates compared, Spearman {rho:.3}",
            predicted.len()
        );
        assert!(predicted.len() >= 20, "{}", predicted.len());
        assert!(rho >= 0.8, "decision {decision}: Spearman {rho:.3}");
        let choice = d.choice.expect("a safe reachable candidate");
        for w in choice.path.waypoints.windows(2) {
            rig.move_to(&w[1]).unwrap();
        }
    }
}

fn run(seed: u64) -> ExploreOutcome {
    let loaded = Scenario::load("bridge1").unwrap();
    let options = ExploreOptions {
        seed,
        max_viewpoints: Some(8),
        ..cached()
    };
    run_exploration(&loaded, &options, &mut |_| {}).unwrap()
}

#[test]
#[ignore = "seconds in release; run by .ci/run"]
fn stage_one_moves_only_through_known_free_space_and_reduces_information() {
    let outcome = run(3);
    let a = &outcome.run;
    println!(
        "{} viewpoints, {}; A1 coverage {:.1} %",
        a.viewpoints.len(),
        a.termination.name(),
        100.0 * outcome.coverage.as_ref().unwrap()[0].fraction()
    );
    assert!(a.viewpoints.len() >= 3);
    assert_eq!(a.tally.collisions, Some(0));
    assert!(
        a.unsafe_configurations.is_empty(),
        "{:?}",
        a.unsafe_configurations
    );
    assert!(a.tally.min_clearance_m.unwrap() > 0.0);
    // Information only falls, and the arm really moved.
    for w in a.viewpoints.windows(2) {
        assert!(w[1].h1_weighted <= w[0].h1_weighted);
        assert!(w[1].h2 <= w[0].h2 + 1e-9);
        assert!(w[1].joint_travel > 0.0);
    }
    let (h10, h20) = a.initial_information;
    let last = a.viewpoints.last().unwrap();
    assert!(last.h1_weighted < h10 && last.h2 < h20);
    // The prediction never claims less than nothing, and the choice's f1 is
    // what its record says was predicted.
    for r in &a.viewpoints[1..] {
        let f = r.f.unwrap();
        assert_eq!(r.predicted_h1_weighted, Some(f[0]));
        assert!(f[3] > 1.0, "a chosen viewpoint with dist(Q) {}", f[3]);
    }
    // The map products: discs on the true surfaces, each in one segment and
    // tied to a viewpoint that was visited.
    let d = &a.discs;
    assert!(d.discs.len() > 1000, "{}", d.discs.len());
    let on_truth = d.true_material.iter().filter(|m| m.is_some()).count();
    assert!(
        on_truth * 100 >= d.discs.len() * 95,
        "{on_truth} of {}",
        d.discs.len()
    );
    assert!(d.viewpoint.iter().all(|k| *k < a.viewpoints.len()));
    let mut seen = vec![0usize; d.discs.len()];
    for (s, members) in d.segments.iter().enumerate() {
        for m in members {
            seen[m.0] += 1;
            assert_eq!(d.segment[m.0], map::SegmentId(s));
        }
    }
    assert!(seen.iter().all(|n| *n == 1));
    // Stage One's material identification: the LRC's most probable material
    // against the true one, over the discs it could observe.
    let observed = d.observations.iter().filter(|o| **o > 0).count();
    let accuracy = d.material_accuracy().unwrap();
    // Better than always naming the commonest true material of those discs.
    let mut counts = vec![0usize; d.material_names.len()];
    for (t, o) in d.true_material.iter().zip(&d.observations) {
        if let (Some(t), true) = (t, *o > 0) {
            counts[*t] += 1;
        }
    }
    let majority = *counts.iter().max().unwrap() as f64 / counts.iter().sum::<usize>() as f64;
    println!(
        "LRC observed {observed} discs; MAP material right on {:.1} % (commonest material {:.1} %)",
        100.0 * accuracy,
        100.0 * majority
    );
    // Stage One's views are not chosen for the LRC (Stage Two's job): the
    // accuracy is reported, not bounded (18 viewpoints of seed 0: 74.8 %
    // against 46 %; these 8: about the commonest material's share).
    assert!(observed >= 50, "{observed}");
    // Posteriors are distributions; an observed disc is surer than the
    // uniform prior (a disc's voxels may also be a neighbour's, so an
    // unobserved disc can have moved too).
    for p in &d.posterior {
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-9);
    }
    let sure = d
        .posterior
        .iter()
        .zip(&d.observations)
        .filter(|(p, o)| **o > 0 && p.iter().any(|v| *v > 0.5))
        .count();
    assert!(sure * 2 >= observed, "{sure} of {observed}");
    // The same seed gives the same outputs (timings off).
    let b = run(3);
    let csv = record::viewpoints::viewpoints_csv;
    assert_eq!(csv(&a.viewpoints), csv(&b.run.viewpoints));
    assert_eq!(outcome.summary(), b.summary());
}

#[test]
#[ignore = "seconds in release; run by .ci/run"]
fn a_urdf_ur5_explores_a_bridge_sized_to_its_reach_safely() {
    // Issue 10 acceptance 6: data/scenarios/ur5_bridge.toml.
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/scenarios/ur5_bridge.toml"
    );
    let loaded = Scenario::load(path).unwrap();
    let options = ExploreOptions {
        max_viewpoints: Some(30),
        ..ExploreOptions::default()
    };
    let outcome = run_exploration(&loaded, &options, &mut |_| {}).unwrap();
    let run = &outcome.run;
    let a1 = outcome.coverage.as_ref().unwrap()[0].fraction();
    println!(
        "UR5: {} viewpoints, {}; A1 coverage {:.1} %",
        run.viewpoints.len(),
        run.termination.name(),
        100.0 * a1
    );
    assert_eq!(run.termination.name(), "information_converged");
    assert!(run.viewpoints.len() >= 4);
    assert_eq!(run.tally.collisions, Some(0));
    assert!(run.unsafe_configurations.is_empty());
    assert!(a1 > 0.3);
}

#[test]
#[ignore = "seconds in release; run by .ci/run"]
fn stage_two_aims_at_discs_safely_and_lowers_the_material_information() {
    // bridge1, seed 0: Stage One to its own end, then 8 Stage Two
    // viewpoints (the run the coverage-oracle test judges Stage One of).
    let outcome = crate::shared::bridge1_both_stages();
    let loaded = &outcome.loaded;
    let run = &outcome.run;
    let two: Vec<_> = run.viewpoints.iter().filter(|r| r.stage == 2).collect();
    println!(
        "stage two: {} viewpoints ({:?}); H3 {:?}; accuracy {:?}",
        two.len(),
        run.stage_two_termination,
        two.iter()
            .map(|r| r.h3.unwrap().round())
            .collect::<Vec<_>>(),
        run.discs.material_accuracy()
    );
    assert!(!two.is_empty());
    assert_eq!(run.tally.collisions, Some(0));
    assert!(run.unsafe_configurations.is_empty());
    // Each Stage Two viewpoint aimed at a disc: re-measure the view from the
    // joints it stood at (the LRC's constraints, Table 6.1).
    let robot = loaded.build_robot().unwrap();
    let wfb = loaded.scenario.world_from_base();
    for r in &two {
        let disc = &run.discs.discs[r.target_disc.unwrap()];
        let pose = wfb * robot.scanner_pose(&r.joints).unwrap().unwrap();
        let view = plan::view_geometry(&pose, &plan::Target::from_disc(disc));
        let hit = view.hit.expect("the centre ray meets the disc's plane");
        assert!(
            view.phi_rad.to_degrees() < 42.0 + 1e-6,
            "{}",
            view.phi_rad.to_degrees()
        );
        assert!((0.25..=0.8).contains(&hit.d_m), "{}", hit.d_m);
        assert!(hit.rho_m <= 0.015 + 1e-9, "{}", hit.rho_m);
        // The transit scanned on its way there (`stage_two_scan_step_deg`):
        // some of the viewpoint's points were measured from scanner
        // positions well away from where the sweep stood.
        let on_the_way = run
            .cloud
            .iter()
            .zip(&run.cloud_viewpoint)
            .filter(|(p, k)| **k == r.k && (p.origin.coords - pose.translation.vector).norm() > 0.1)
            .count();
        assert!(on_the_way > 100, "viewpoint {}: {on_the_way} points", r.k);
    }
    // The material information falls after every Stage Two viewpoint, from
    // where Stage One's sweeps left it (its last row).
    let one = run.viewpoints.iter().rfind(|r| r.stage == 1).unwrap();
    let mut before = one.h3.expect("Stage One's last row holds H3");
    for r in &two {
        let h3 = r.h3.unwrap();
        assert!(h3 < before, "viewpoint {}: H3 {before} → {h3}", r.k);
        before = h3;
    }
    // The most probable material is the true one on at least 90 % of the
    // discs the LRC could classify (the ground truth is the scene's).
    let accuracy = run.discs.material_accuracy().unwrap();
    assert!(accuracy >= 0.9, "material accuracy {accuracy}");
    // The run folder: every file, the discs read back, and the blast plan
    // the folder holds checked.
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("run");
    let staging = record::Staging::new(&folder).unwrap();
    let t = std::time::Instant::now();
    let plan = scenario::job::explore::write_run(outcome, &staging).unwrap();
    let seconds = t.elapsed().as_secs_f64();
    staging.commit().unwrap();
    for name in [
        "viewpoints.csv",
        "cloud.ply",
        "mesh.ply",
        "discs.csv",
        "segments.json",
        "run.json",
        "blast_plan.json",
    ] {
        assert!(folder.join(name).exists(), "{name}");
    }
    let discs = map::sld_io::load_discs_csv(&folder.join("discs.csv")).unwrap();
    assert_eq!(discs.len(), run.discs.discs.len());
    check_blast_plan(outcome, &plan.unwrap(), seconds);
}

/// Which bridge1 surface a disc lies on, for issue 11's "roof and web
/// discs": the nearest true surface within 0.05 m of the disc's centre (the
/// tolerance of the discs' true materials) decides. A disc is a roof disc
/// when that surface belongs to the object `roof` (the deck underside,
/// SPEC §4: z = 1.52), and a web disc when it belongs to `left_beam` or
/// `right_beam` and lies on a web face: within the web's half-thickness
/// (6 mm) of the beam's centre plane y = ±0.75 and between the flanges
/// (0.82 < z < 1.50). Flanges, the plate and the containment sheet bolted
/// to the webs, the tubes, the hose, the floor and the platform are neither.
fn roof_or_web(scene: &scene::Scene, disc: &map::Disc) -> bool {
    let Some((_, face, p)) = scene.closest_point(&disc.centre, 0.05) else {
        return false;
    };
    let Some(object) = scene.object(scene.triangle_object(face)) else {
        return false;
    };
    match object.name.as_str() {
        "roof" => true,
        "left_beam" | "right_beam" => {
            (p.y.abs() - 0.75).abs() <= 0.006 + 1e-6 && p.z > 0.82 && p.z < 1.50
        }
        _ => false,
    }
}

/// The oracle of reachability on the run's map: the roof and web discs in
/// A2 without a pose in the plan (`planned`), each tried by 24 LM runs from
/// random joints within the limits. Returns (discs it finds a valid
/// re-measured pose for, discs tried).
fn oracle_misses(
    loaded: &scenario::LoadedScenario,
    run: &explore::ExploreRun,
    planned: &std::collections::HashSet<usize>,
    config: &blast::BlastConfig,
    scene: &scene::Scene,
) -> (usize, usize) {
    use rand::{RngExt, SeedableRng};
    use rayon::prelude::*;
    let robot = loaded.build_robot().unwrap();
    let a2 = loaded.scenario.regions.unwrap().a2;
    let poses = blast::BlastPoses::new(
        &robot,
        loaded.scenario.world_from_base(),
        &plan::PlanConfig::default(),
        vec![1.0; robot.dof()],
        &config.pose,
        config.tool,
    )
    .unwrap()
    .with_starts(1)
    .unwrap();
    let limits: Vec<(f64, f64)> = robot
        .limits()
        .iter()
        .map(|l| {
            l.map_or((-std::f64::consts::PI, std::f64::consts::PI), |l| {
                (l.min, l.max)
            })
        })
        .collect();
    let misses: Vec<usize> = (0..run.discs.discs.len())
        .filter(|i| !planned.contains(i))
        .filter(|&i| a2.contains(&run.discs.discs[i].centre))
        .filter(|&i| roof_or_web(scene, &run.discs.discs[i]))
        .collect();
    let found = misses
        .par_iter()
        .filter(|&&i| {
            let target = plan::Target::from_disc(&run.discs.discs[i]);
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(i as u64);
            (0..24).any(|_| {
                let start: Vec<f64> = limits
                    .iter()
                    .map(|&(lo, hi)| rng.random_range(lo..=hi))
                    .collect();
                let s = poses.select(&run.grid, &target, &start).unwrap();
                s.valid() && poses.measure(&run.grid, &target, s.joints()).unwrap().valid
            })
        })
        .count();
    (found, misses.len())
}

/// Issue 11's blast plan over a run's map: poses for at least 95 % of the
/// roof and web discs the tool can reach on that map (a pose meeting every
/// rule exists, found by an oracle of random-start LM runs), and at least
/// 80 % of those it could reach if everything were known; every pose
/// re-measured in closed form (the stream from the nozzle tip meets the
/// disc's plane) and by `dist(Q)` on the run's grid with the nozzle's
/// ellipsoid (and without it); in every segment the GA's order costs no
/// more than 2-opt's, which costs no more than nearest neighbour's, and over
/// the run the GA is strictly cheaper than nearest neighbour. (That the same
/// seed gives the same plan is checked through the binary: `plan-blast` on
/// the run folder reproduces `explore`'s plan byte for byte, cli's
/// `plan_blast` test.)
fn check_blast_plan(outcome: &ExploreOutcome, plan: &blast::BlastPlan, seconds: f64) {
    use blast::BlastConfig;
    let (loaded, run) = (&outcome.loaded, &outcome.run);
    let robot = loaded.build_robot().unwrap();
    let wfb = loaded.scenario.world_from_base();
    let a2 = loaded.scenario.regions.unwrap().a2;
    let config = BlastConfig::default();
    let nn: f64 = plan.segments.iter().map(|s| s.cost_nearest_neighbour).sum();
    let opt: f64 = plan.segments.iter().map(|s| s.cost_two_opt).sum();
    let ga: f64 = plan.segments.iter().map(|s| s.cost_ga).sum();
    println!(
        "blast plan: {} of {} discs in A2 have a pose; {} segments; path cost nearest neighbour {nn:.2}, 2-opt {opt:.2}, GA {ga:.2}; {seconds:.1} s",
        plan.discs_with_pose,
        plan.discs_in_scope,
        plan.segments.len()
    );
    assert!(
        ga <= opt + 1e-9 && opt < nn,
        "GA {ga}, 2-opt {opt}, NN {nn}"
    );
    assert!(ga < nn);
    // Issue 11 asks for poses for 95 % of the roof and web discs the tool
    // can reach. One reading: those with a pose when all is known (the
    // ground truth's occupancy); the other, held to 95 % below: those with
    // a pose on the run's own map.
    let world = loaded.build_world().unwrap();
    let scene = world.as_scene().unwrap();
    let inputs = outcome.blast_inputs().unwrap();
    let reachable = sim::truth::reachable_discs(&inputs, &robot, wfb, &a2, scene, &config).unwrap();
    let planned: std::collections::HashSet<usize> = plan
        .segments
        .iter()
        .flat_map(|s| s.targets.iter().map(|t| t.disc))
        .collect();
    let of_reachable = reachable.iter().filter(|i| planned.contains(i)).count();
    let roof_web: Vec<usize> = reachable
        .iter()
        .copied()
        .filter(|&i| roof_or_web(scene, &run.discs.discs[i]))
        .collect();
    let of_roof_web = roof_web.iter().filter(|i| planned.contains(i)).count();
    let share = of_roof_web as f64 / roof_web.len().max(1) as f64;
    println!(
        "reachable with everything known: {} discs, the plan has a pose for {of_reachable} ({:.1} %); of them on the roof and the webs: {}, with a pose {of_roof_web} ({:.1} %)",
        reachable.len(),
        100.0 * of_reachable as f64 / reachable.len().max(1) as f64,
        roof_web.len(),
        100.0 * share
    );
    assert!(
        roof_web.len() >= 500,
        "{} roof and web discs",
        roof_web.len()
    );
    // Against everything known, this run gives 84.3 % (1056 of 1253): the
    // misses are poses blocked by voxels still unknown on the run's map
    // (sim README). The floor guards against losing ground meanwhile.
    assert!(share >= 0.80, "{:.1} %", 100.0 * share);
    // Reachable on the run's own map: a pose meeting every rule (g1-g5,
    // dist(Q) > 1 against the map's occupied and unknown voxels) exists. The
    // oracle: for every roof or web disc in A2 the plan has no pose for, 24
    // LM runs from random joints within the limits (seeded); a disc any of
    // them solves (re-measured) was reachable and missed.
    let (found_by_oracle, misses) = oracle_misses(loaded, run, &planned, &config, scene);
    let planned_roof_web = planned
        .iter()
        .filter(|&&i| roof_or_web(scene, &run.discs.discs[i]))
        .count();
    let share_map = planned_roof_web as f64 / (planned_roof_web + found_by_oracle).max(1) as f64;
    println!(
        "roof and web discs in A2 reachable on the run's map: the plan has {planned_roof_web}; of the {misses} it has none for, random-start LM finds a pose for {found_by_oracle}: {:.1} %",
        100.0 * share_map
    );
    assert!(share_map >= 0.95, "{:.1} %", 100.0 * share_map);
    // Independent re-measurement: the nozzle's pose from the flange's
    // forward kinematics, and dist(Q) by plan::Safety on the run's grid for
    // the bare arm and for the arm whose tool-link ellipsoid holds the
    // nozzle's capsule (checked to be inside it).
    let plain = plan::Safety::new(
        robot.clone(),
        wfb,
        &plan::PlanConfig::default(),
        vec![1.0; 6],
    )
    .unwrap();
    let tool = config.tool;
    let with_nozzle = plan::Safety::new(
        tool.robot_with_nozzle(&robot).unwrap(),
        wfb,
        &plan::PlanConfig::default(),
        vec![1.0; 6],
    )
    .unwrap();
    let tool_link = robot.tool.0.index();
    let nozzle_ellipsoid = with_nozzle.robot().links[tool_link].ellipsoid.unwrap();
    let capsule = tool.nozzle_capsule(&robot);
    for p in robot::bounds::capsule_sample_points(&capsule) {
        assert!(nozzle_ellipsoid.algebraic_distance(&p) <= 1.0 + 1e-9);
    }
    let offset = geom::math::isometry_from_xyz_rpy(tool.translation_m, [0.0; 3]);
    let mut listed = 0;
    for s in &plan.segments {
        listed += s.targets.len() + s.no_pose.len();
        assert!(s.cost_ga <= s.cost_two_opt + 1e-9, "segment {}", s.segment);
        assert!(s.cost_two_opt <= s.cost_nearest_neighbour + 1e-9);
        for t in &s.targets {
            let disc = &run.discs.discs[t.disc];
            let nozzle = wfb * robot.tool_pose(&t.joints).unwrap() * offset;
            let o = geom::Point3::from(nozzle.translation.vector);
            let dir = nozzle.rotation * geom::Vector3::z();
            let n = disc.normal.into_inner();
            let along = (disc.centre - o).dot(&n) / dir.dot(&n);
            let hit = o + dir * along;
            let phi = (-dir.dot(&n)).clamp(-1.0, 1.0).acos().to_degrees();
            let aim = (hit - disc.centre).norm();
            assert!(phi < tool.phi_max_deg, "disc {}: φ {phi}", t.disc);
            assert!((tool.d_min_m..=tool.d_max_m).contains(&along), "d {along}");
            assert!(aim <= tool.rho_min_m + 1e-9, "aim {aim}");
            assert!(plain.dist(&run.grid, &t.joints).unwrap() > 1.0);
            assert!(with_nozzle.dist(&run.grid, &t.joints).unwrap() > 1.0);
            assert!(robot.within_limits(&t.joints));
            assert!((t.phi_deg - phi).abs() < 1e-6 && (t.d_m - along).abs() < 1e-9);
        }
    }
    // Every disc in A2 is in the plan, with a pose or listed without one.
    assert_eq!(listed, plan.discs_in_scope);
}

/// Issue 23 acceptance 2: the exploration loop (both stages) on hardware
/// that is not the simulator. A session of the simulated arm and scanner is
/// recorded ([`hw::script::Recorder`]), kept as JSON, and played back by a
/// [`hw::script::Replay`], which answers every command with what was
/// recorded and refuses any other: the run on the replay is the run on the
/// simulator, viewpoint for viewpoint and point for point (Stage One to the
/// 1 % rule, then two Stage Two viewpoints: after fewer Stage One viewpoints
/// no disc is targetable and Stage Two would move nothing).
#[test]
#[ignore = "seconds in release; run by .ci/run"]
fn exploration_on_a_replayed_session_repeats_the_simulated_run() {
    use hw::LineScanner;
    use hw::script::{Event, Recorder, Replay, Script};
    use record::viewpoints::{candidates_csv, path_csv, viewpoints_csv};
    let loaded = Scenario::load("bridge1").unwrap();
    let mut config = loaded.scenario.explore.clone().unwrap();
    config.max_viewpoints = 40;
    config.stage_two_max_viewpoints = 2;
    let options = ExploreOptions {
        seed: 2,
        config: Some(config),
        stage_two: true,
        ..cached()
    };
    let (setup, world) = scenario::job::explore::explore_setup(&loaded, &options).unwrap();
    let scanner = sensor::Scanner::new(setup.scanner).unwrap();
    let rig = SimRig::new(
        setup.robot.clone(),
        world,
        setup.world_from_base,
        &setup.start,
        Some(scanner),
        options.seed,
    )
    .unwrap();
    let run_options = explore::RunOptions {
        seed: options.seed,
        timings: false,
        stage_two: true,
        ..explore::RunOptions::default()
    };
    let bearings = rig.bearings_rad().to_vec();
    let mut recorder = Recorder::new(rig, bearings);
    let a = explore::run(
        setup,
        &mut recorder,
        &mut explore::NoJudge,
        &run_options,
        &mut |_| {},
    )
    .unwrap();
    let (_, script) = recorder.into_parts();
    let scans = script
        .events
        .iter()
        .filter(|e| matches!(e, Event::Scanned(_)))
        .count();
    let script: Script = serde_json::from_str(&serde_json::to_string(&script).unwrap()).unwrap();
    let (setup, _) = scenario::job::explore::explore_setup(&loaded, &options).unwrap();
    let mut replay = Replay::new(script);
    let b = explore::run(
        setup,
        &mut replay,
        &mut explore::NoJudge,
        &run_options,
        &mut |_| {},
    )
    .unwrap();
    println!(
        "replayed {} viewpoints ({} in Stage Two), {scans} scans, {} points",
        b.viewpoints.len(),
        b.viewpoints.iter().filter(|r| r.stage == 2).count(),
        b.cloud.len()
    );
    assert_eq!(replay.remaining(), 0);
    // Stage Two moved and scanned on the replay as on the rig.
    assert!(b.viewpoints.iter().any(|r| r.stage == 2));
    assert!(b.stage_two_termination.is_some());
    for csv in [viewpoints_csv, candidates_csv, path_csv] {
        assert_eq!(csv(&a.viewpoints), csv(&b.viewpoints));
    }
    assert_eq!(a.cloud, b.cloud);
    assert_eq!(a.mesh, b.mesh);
    assert_eq!(
        a.discs.table().to_csv().unwrap(),
        b.discs.table().to_csv().unwrap()
    );
    assert_eq!(a.stage_two_termination, b.stage_two_termination);
    assert_eq!(a.unsafe_configurations, b.unsafe_configurations);
    assert_eq!(b.tally, explore::SafetyTally::default());
}
