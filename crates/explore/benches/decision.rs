//! One Stage One decision on bridge1 after the start pose's sweep, with the
//! default n_Q = 1571 (issue 10 acceptance 4: ≤ 1 s). The sweep is simulated
//! here with `scene` and `sensor` (the `sim` runner sits above this crate).
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use explore::{ExploreConfig, StageOne};
use geom::Isometry3;
use map::{OccupancyConfig, RegionsConfig};
use plan::CspaceModel;
use rand::SeedableRng;
use sensor::{Scanner, ScannerConfig, SweepBuilder, SweepConfig};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let world = scene::builtin::scene("bridge1")
        .unwrap()
        .build(std::path::Path::new("."))
        .unwrap();
    let robot = robot::builtin("denso-vm6083").unwrap();
    let config = ExploreConfig::default();
    let base = Isometry3::identity();
    let model = CspaceModel::build(&robot, &base, config.planning_voxel_m, &config.plan).unwrap();
    let scanner = Scanner::new(ScannerConfig::default()).unwrap();
    let reach = ScannerConfig::default().max_range_m - 0.15;
    let occupancy = OccupancyConfig {
        regions: RegionsConfig::around([0.0, 0.0, 0.475], [1.1, 1.6, 2.1]),
        free_misses_m: Some(reach),
        ..OccupancyConfig::default()
    };
    let start: Vec<f64> = [0.0f64, -55.0, 165.0, 0.0, -110.0, 0.0]
        .iter()
        .map(|d| d.to_radians())
        .collect();
    let mut stage = StageOne::new(
        model,
        &occupancy,
        scanner.bearings_rad(),
        reach,
        config,
        &start,
    )
    .unwrap();
    // The start pose's sweep: joint 5 nods through 60°.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let mut builder = SweepBuilder::new(scanner.bearings_rad()).unwrap();
    let sweep_cfg = SweepConfig::default();
    let lim = robot.limits()[4].unwrap();
    for t in sweep_cfg.tilt_values(start[4], Some((lim.min, lim.max))) {
        let mut q = start.clone();
        q[4] = t;
        let pose = robot.scanner_pose(&q).unwrap().unwrap();
        scanner
            .scan(&world, &pose, &mut rng)
            .push_to(&mut builder)
            .unwrap();
    }
    stage.integrate(&builder.finish().unwrap());
    let mut group = c.benchmark_group("stage_one");
    group.sample_size(10);
    group.bench_function("decision_n1571_bridge1_first", |b| {
        b.iter(|| stage.decide(black_box(&start), None, &[]).unwrap());
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
