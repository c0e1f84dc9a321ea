//! Per-set update time of the surface model on the scripted point3 sweeps of
//! the cube and block1 scenes (acceptance 4), and of the cube under range noise
//! σ = λ/5 (`cube-noisy`, issue 9).
//!
//! Run with `cargo bench -p surface --bench update`. First, each stream is
//! replayed once and every update timed: the bench prints the median, 95th
//! percentile and maximum per update, for point3's sensor sets (9–17 points over a
//! face) and for the same points regrouped into sets of 26. Then criterion
//! estimates the time of one update of a sensor set, and of a 26-point set, over
//! a mix of model states (every 8th set of the stream, each applied to a copy of
//! the model as it was just before that set); its `estimates.json` under
//! `target/criterion/` holds the median.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

#[path = "../tests/support/mod.rs"]
mod support;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Instant;
use support::{Sweep, sweep_sets, table};
use surface::{SensorSet, SurfaceConfig, SurfaceModel, UpdateTimes};

fn fresh_model() -> SurfaceModel {
    let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
    m.add_initial_segment(&table()).unwrap();
    m
}

/// Time every update of a replay; print the summaries.
fn replay_times(scene: &str, sets: &[SensorSet]) {
    let mut m = fresh_model();
    let mut all = Vec::with_capacity(sets.len());
    let mut full = Vec::new();
    for s in sets {
        let t0 = Instant::now();
        black_box(m.update(s).unwrap());
        let us = t0.elapsed().as_secs_f64() * 1e6;
        all.push(us);
        if s.len() == 26 {
            full.push(us);
        }
    }
    let a = UpdateTimes::from_micros(&all);
    print!(
        "{scene}: {} sets, update µs median {:.1} p95 {:.1} max {:.1}",
        all.len(),
        a.median,
        a.p95,
        a.max
    );
    if !full.is_empty() && full.len() < all.len() {
        let f = UpdateTimes::from_micros(&full);
        print!(
            "; {} sets of 26 points: median {:.1} p95 {:.1} max {:.1}",
            full.len(),
            f.median,
            f.p95,
            f.max
        );
    }
    println!("; final {:?}", m.stats());
}

/// The sweep's points in stream order, regrouped into sets of exactly 26
/// (point3 sees 9–17 points at a time over a face: consecutive sensor sets are
/// joined, so each set holds 26 nearby points, the size of a full point3 set).
fn regroup_26(sets: &[SensorSet]) -> Vec<SensorSet> {
    let points: Vec<_> = sets.iter().flat_map(|s| s.points.iter().copied()).collect();
    let axes: Vec<_> = sets.iter().flat_map(|s| s.axes.iter().copied()).collect();
    points
        .chunks_exact(26)
        .zip(axes.chunks_exact(26))
        .map(|(p, a)| SensorSet::new(p.to_vec(), a.to_vec()).unwrap())
        .collect()
}

fn bench_scene(c: &mut Criterion, scene: &str, sweep: &Sweep, label: &str) {
    let raw = sweep_sets(scene, sweep);
    replay_times(&format!("{label} (sensor sets)"), &raw);
    let sets = regroup_26(&raw);
    replay_times(&format!("{label} (26-point sets)"), &sets);
    bench_sets(c, &format!("update/{label}/sensor set"), &raw, |_| true);
    bench_sets(c, &format!("update/{label}/26-point set"), &sets, |s| {
        s.len() == 26
    });
}

/// Criterion: one update, over snapshots of the model before every 8th set of
/// `sets` (those `keep` accepts).
fn bench_sets(
    c: &mut Criterion,
    name: &str,
    sets: &[SensorSet],
    keep: impl Fn(&SensorSet) -> bool,
) {
    let mut m = fresh_model();
    let mut cases = Vec::new();
    for (k, s) in sets.iter().enumerate() {
        if k % 8 == 0 && keep(s) {
            cases.push((m.clone(), s.clone()));
        }
        m.update(s).unwrap();
    }
    let mut next = 0usize;
    c.bench_function(name, |b| {
        b.iter_batched(
            || {
                next = (next + 1) % cases.len();
                cases[next].clone()
            },
            // The model is returned so that it is dropped outside the measurement.
            |(mut model, set)| {
                let log = model.update(&set).unwrap();
                (model, black_box(log))
            },
            BatchSize::SmallInput,
        );
    });
}

fn benches(c: &mut Criterion) {
    // `SURFACE_BENCH_SCENES=block1,cube-noisy` limits the cases (for profiling).
    let only = std::env::var("SURFACE_BENCH_SCENES").ok();
    // The noisy case: range noise σ = λ/5 (issue 9).
    let noisy = Sweep {
        noise_sigma: 0.01,
        seed: 7,
        ..Sweep::default()
    };
    for (scene, sweep, label) in [
        ("cube", Sweep::default(), "cube"),
        ("block1", Sweep::default(), "block1"),
        ("cube", noisy, "cube-noisy"),
    ] {
        if only
            .as_deref()
            .is_none_or(|o| o.split(',').any(|x| x == label))
        {
            bench_scene(c, scene, &sweep, label);
        }
    }
}

criterion_group!(update, benches);
criterion_main!(update);
