//! The material oracle (`sim::material_oracle`, issue 44) on a scene whose
//! answer the geometry gives: a timber wall 0.75 m in front of the robot,
//! wider and taller than the arm can reach around, A2 a 0.7 m square of it
//! (its front and its back). Nothing can see the back, so no back sample is
//! identified and the identifiable share is at most the front's share; the
//! middle of the front lies 0.5 m ahead of scanner positions well inside
//! the arm's workspace, within every LRC constraint, so the oracle must
//! identify nearly all of it, and as timber. Then `--no-oracle`
//! (`OracleOption::Off`) leaves the material oracle out of a run, and the
//! oracle on puts it in `run.json` and in its cache beside the coverage
//! oracle's.
//!
//! `cargo test --release -p sim --test long material_oracle -- --ignored --nocapture`

use geom::Real;
use scenario::Scenario;
use scenario::job::explore::{ExploreOptions, OracleOption, explore_setup};
use sim::explore_job::run_exploration;
use sim::material_oracle::{MaterialPool, cache_beside, material_samples};
use std::path::{Path, PathBuf};

/// The wall scene: the five default materials, the wall timber; a small
/// roadmap (100 nodes) and short stages so a run takes seconds.
const WALL: &str = r#"
name = "wall"
description = "a timber wall 0.75 m in front of the robot (material oracle test)"

[robot]
preset = "denso-vm6083"
start_joints = [0.0, -0.9599310885968813, 2.8797932657906435, 0.0, -1.9198621771937625, 0.0]

[regions.a1]
min = [-0.3, -0.3, 0.3]
max = [0.7, 0.3, 0.9]

[regions.a2]
min = [-0.35, -0.35, 0.25]
max = [0.85, 0.35, 0.95]

[regions.a3]
min = [-1.2, -1.2, -0.5]
max = [1.5, 1.2, 1.8]

[[scene.materials]]
name = "painted_metal"
reflectance = 0.5
roughness = 0.35

[[scene.materials]]
name = "timber"
reflectance = 0.3
roughness = 0.7

[[scene.materials]]
name = "concrete"
reflectance = 0.15
roughness = 0.95

[[scene.materials]]
name = "plastic"
reflectance = 0.6
roughness = 0.2

[[scene.materials]]
name = "stainless_steel"
reflectance = 0.9
roughness = 0.05

[[scene.objects]]
name = "wall"
material = "timber"

[scene.objects.shape]
kind = "box"
min = [0.75, -1.5, -0.5]
max = [0.8, 1.5, 2.0]

[explore]
max_viewpoints = 3
stage_two_max_viewpoints = 2

[explore.plan]
n_q = 100
"#;

/// The wall scenario written to `dir`.
fn wall(dir: &Path) -> PathBuf {
    let path = dir.join("wall.toml");
    std::fs::write(&path, WALL).unwrap();
    path
}

fn tmp() -> &'static Path {
    Path::new(env!("CARGO_TARGET_TMPDIR"))
}

#[test]
#[ignore = "seconds in release, with its C-space model cached; run by .ci/run"]
fn the_material_oracle_identifies_what_the_geometry_allows_on_a_wall() {
    let dir = tempfile::tempdir().unwrap();
    let loaded = Scenario::load(wall(dir.path()).to_str().unwrap()).unwrap();
    let options = ExploreOptions {
        cspace_cache: Some(tmp().join("cspace-wall.json")),
        ..ExploreOptions::default()
    };
    let (setup, world) = explore_setup(&loaded, &options).unwrap();
    let timber = setup
        .materials
        .iter()
        .position(|m| m.name == "timber")
        .unwrap();
    let (lrc, _) = explore::train_lrc(
        &setup.materials,
        &setup.scanner,
        &setup.config.pose,
        0,
        Some(&tmp().join("lrc-seed0.json")),
    )
    .unwrap();
    let metrics = loaded.scenario.metrics;
    let t = std::time::Instant::now();
    let pool = MaterialPool::new(&setup, &world, &setup.scanner, &metrics, &lrc).unwrap();
    let oracle = pool.oracle();
    let (targets, aimed) = pool.aimed();
    println!(
        "{} samples, {} poses ({} clear, {aimed} aimed of {targets} targets): identifiable {:.3}, greedy {:?}, accuracy {:?}; {:.1} s",
        oracle.samples,
        oracle.poses,
        oracle.clear_poses,
        oracle.identifiable,
        oracle.identified_after_viewpoints,
        oracle.accuracy,
        t.elapsed().as_secs_f64()
    );

    // The samples are the wall's front and back in A2, and no others.
    let samples = pool.samples();
    let (again, _) = material_samples(&world, &metrics, setup.regions.a2.aabb()).unwrap();
    assert_eq!(again, samples);
    let front = |s: &sim::material_oracle::MaterialSample| s.normal.x < -0.99;
    let back = |s: &sim::material_oracle::MaterialSample| s.normal.x > 0.99;
    assert!(samples.iter().all(|s| front(s) || back(s)));
    assert!(samples.iter().all(|s| s.material == timber));
    let n = samples.len() as Real;
    let fronts = samples.iter().filter(|s| front(s)).count() as Real;
    // 0.98 m² at 100 per m².
    assert!((80.0..120.0).contains(&n), "{n} samples");

    // Which samples are identified: alone by a usable pose, or at the end
    // of the greedy choice.
    let (_, belief) = pool.greedy(sim::material_oracle::MATERIAL_ORACLE_MAX_VIEWPOINTS);
    let k = setup.materials.len();
    let alone = pool.identified_alone();
    let identified: Vec<bool> = belief
        .chunks_exact(k)
        .zip(&alone)
        .map(|(p, &a)| a || p.iter().copied().fold(0.0, Real::max) >= explore::IDENTIFIED_P)
        .collect();
    let count = |pick: &dyn Fn(&sim::material_oracle::MaterialSample) -> bool| {
        let mut total = 0usize;
        let mut found = 0usize;
        for (s, &i) in samples.iter().zip(&identified) {
            if pick(s) {
                total += 1;
                found += usize::from(i);
            }
        }
        (found, total)
    };
    assert!(
        (oracle.identifiable - count(&|_| true).0 as Real / n).abs() < 1e-12,
        "the identifiable share is the samples identified alone or by the greedy choice"
    );
    // No pose sees the back: nothing there is identified, and the
    // identifiable share is at most the front's.
    assert_eq!(count(&back).0, 0);
    assert!(oracle.identifiable <= fronts / n + 1e-12);
    // The middle of the front, in reach head-on from 0.5 m: nearly all.
    let middle = |s: &sim::material_oracle::MaterialSample| {
        front(s) && s.point.y.abs() <= 0.25 && (0.35..=0.85).contains(&s.point.z)
    };
    let (found, total) = count(&middle);
    assert!(total > 15, "{total}");
    assert!(
        found as Real >= 0.9 * total as Real,
        "{found} of {total} samples in the middle of the front"
    );
    // The greedy rises at every viewpoint and stays within the identifiable.
    let curve = &oracle.identified_after_viewpoints;
    assert!(curve.len() >= 2, "{curve:?}");
    assert!(curve.windows(2).all(|w| w[1] > w[0]), "{curve:?}");
    assert!(*curve.last().unwrap() <= oracle.identifiable + 1e-12);
    assert!(oracle.accuracy.unwrap() >= 0.95, "{:?}", oracle.accuracy);
    assert!(aimed > 0 && oracle.clear_poses > aimed / 2);
}

/// `--no-oracle` (`OracleOption::Off`) leaves the material oracle out; the
/// oracle on computes it beside the run, writes it to its cache beside the
/// coverage oracle's, and reads it back the next time.
#[test]
#[ignore = "15 s in release, with its C-space model cached; run by .ci/run"]
fn no_oracle_skips_the_material_oracle_and_the_oracle_caches_it() {
    let dir = tempfile::tempdir().unwrap();
    let loaded = Scenario::load(wall(dir.path()).to_str().unwrap()).unwrap();
    let options = ExploreOptions {
        cspace_cache: Some(tmp().join("cspace-wall.json")),
        lrc_cache: Some(dir.path().join("lrc-seed0.json")),
        stage_two: true,
        ..ExploreOptions::default()
    };
    let off = run_exploration(&loaded, &options, &mut |_| {}).unwrap();
    assert!(off.material_identification.is_none());
    assert!(off.summary().material_identification.is_none());
    let coverage_cache = dir.path().join("oracle-wall.json");
    let cache = cache_beside(&coverage_cache);
    assert!(!cache.exists());
    let on = ExploreOptions {
        oracle: OracleOption::On(Some(coverage_cache)),
        ..options
    };
    let first = run_exploration(&loaded, &on, &mut |_| {}).unwrap();
    let m = first.material_identification.clone().unwrap();
    assert!(cache.is_file());
    println!(
        "the run: {:.3} identified, {} discs, {} Stage Two viewpoints; oracle {:.3}",
        m.identified, m.discs_identified, m.stage_two_viewpoints, m.oracle.identifiable
    );
    assert_eq!(
        m.stage_two_viewpoints,
        first.run.viewpoints.iter().filter(|v| v.stage == 2).count()
    );
    assert!((0.0..=1.0).contains(&m.identified));
    // Viewpoint by viewpoint: the share at Stage Two's start and after each
    // of its viewpoints, ending on the run's; each row's identified discs
    // are those marked since it, and the last row's those the final
    // posteriors (computed apart, from the belief's voxels) put at p ≥ 0.8.
    assert_eq!(
        m.identified_after_viewpoints.len(),
        m.stage_two_viewpoints + 1
    );
    assert_eq!(m.identified_after_viewpoints.last(), Some(&m.identified));
    let d = &first.run.discs;
    let rows: Vec<_> = first
        .run
        .viewpoints
        .iter()
        .filter(|v| v.discs_identified.is_some())
        .collect();
    assert_eq!(rows.len(), m.stage_two_viewpoints + 1);
    for r in &rows {
        let since = d
            .identified_at
            .iter()
            .filter(|a| a.is_some_and(|k| k <= r.k))
            .count();
        assert!(since <= r.discs_identified.unwrap(), "viewpoint {}", r.k);
    }
    let by_posterior = d
        .posterior
        .iter()
        .filter(|p| p.iter().copied().fold(0.0, f64::max) >= 0.8)
        .count();
    assert_eq!(rows.last().unwrap().discs_identified, Some(by_posterior));
    assert_eq!(first.summary().material_identification, Some(m.clone()));
    // The run's run.json is the same with or without the oracle but for
    // the oracles' entries.
    let mut without = first.summary();
    without.material_identification = None;
    if let Some(c) = &mut without.coverage {
        c.oracle = None;
    }
    assert_eq!(without, off.summary());
    // Read back from its cache the second time.
    let before = std::fs::metadata(&cache).unwrap().modified().unwrap();
    let second = run_exploration(&loaded, &on, &mut |_| {}).unwrap();
    assert_eq!(second.material_identification, Some(m));
    assert_eq!(
        std::fs::metadata(&cache).unwrap().modified().unwrap(),
        before
    );
}
