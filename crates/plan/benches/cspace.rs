//! Building and loading the C-space model (issue 10 acceptance 4: n_Q = 1571
//! built in ≤ 60 s, loaded from cache in ≤ 1 s) and `dist(Q)` of one pose.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use geom::Isometry3;
use plan::{CspaceModel, PlanConfig};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let robot = robot::builtin("denso-vm6083").unwrap();
    let config = PlanConfig::default();
    let voxel_m = 0.05;
    let world_from_base = Isometry3::identity();
    let mut group = c.benchmark_group("cspace");
    group.sample_size(10);
    group.bench_function("build_n1571", |b| {
        b.iter(|| {
            CspaceModel::build(&robot, &world_from_base, voxel_m, black_box(&config)).unwrap()
        });
    });
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cspace.json");
    let model = CspaceModel::build(&robot, &world_from_base, voxel_m, &config).unwrap();
    model.save(&path).unwrap();
    group.bench_function("load_n1571", |b| {
        b.iter(|| {
            CspaceModel::load(black_box(&path), &robot, &world_from_base, voxel_m, &config).unwrap()
        });
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
