//! The LRC: features and posterior of one observation (the per-target cost
//! of Stage Two), and simulating one observation.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use scene::default_materials;
use sensor::ScannerConfig;
use sensor::classifier::{Lrc, LrcConfig, ObservationSetup, TrainingConfig, simulate_observation};
use std::hint::black_box;

fn classifier(c: &mut Criterion) {
    let materials = default_materials();
    let scanner = ScannerConfig::default();
    let training = TrainingConfig {
        observations_per_material: 60,
        ..TrainingConfig::default()
    };
    let lrc = Lrc::train(LrcConfig::default(), &training, &materials, &scanner, 1).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    // A full 0.4° sweep of a patch from 0.5 m, 15° off its normal.
    let setup = ObservationSetup {
        incidence_rad: 15f64.to_radians(),
        ..ObservationSetup::default()
    };
    let obs = simulate_observation(&setup, &materials[1], &scanner, &mut rng).unwrap();
    let mut group = c.benchmark_group("lrc");
    group.bench_function(format!("classify ({} returns)", obs.returns.len()), |b| {
        b.iter(|| lrc.classify(black_box(&obs)).unwrap());
    });
    group.bench_function("simulate observation (0.4° sweep, 0.5 m)", |b| {
        b.iter(|| simulate_observation(&setup, &materials[1], &scanner, &mut rng).unwrap());
    });
    group.finish();
}

criterion_group!(benches, classifier);
criterion_main!(benches);
