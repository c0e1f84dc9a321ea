//! A whole surface-following step (issue 9 acceptance 7): model update +
//! change tracking and direction + control-point motion and actuator changes,
//! sensing excluded as Pudney excluded it. Each robot is run for a while in
//! its scene first, then single steps are timed from clones of that state.
//!
//! `cargo bench -p follow --bench step`

#[path = "../tests/support/mod.rs"]
mod support;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use follow::FollowConfig;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    for (scene, robot, warm) in [("cube", "point3", 150), ("block1", "arm4", 150)] {
        let mut run = support::Run::new(scene, robot, FollowConfig::default(), 1);
        for _ in 0..warm {
            run.step();
        }
        let readings = run.readings();
        let q = run.q.clone();
        c.bench_function(&format!("step/{robot}/{scene}"), |b| {
            b.iter_batched(
                || run.follower.clone(),
                |mut f| black_box(f.step(&q, &readings).map(|s| s.dq)),
                BatchSize::SmallInput,
            );
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
