//! Profiling aid: replays a scripted sweep regrouped into 26-point sets.
//! `cargo run --release -p surface --example profile_replay -- block1`
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

#[path = "../tests/support/mod.rs"]
mod support;

use surface::{SensorSet, SurfaceConfig, SurfaceModel};

fn main() {
    let scene = std::env::args().nth(1).unwrap_or_else(|| "block1".into());
    let raw = support::sweep_sets(&scene, &support::Sweep::default());
    let points: Vec<_> = raw.iter().flat_map(|s| s.points.iter().copied()).collect();
    let axes: Vec<_> = raw.iter().flat_map(|s| s.axes.iter().copied()).collect();
    let sets: Vec<SensorSet> = points
        .chunks_exact(26)
        .zip(axes.chunks_exact(26))
        .map(|(p, a)| SensorSet::new(p.to_vec(), a.to_vec()).unwrap())
        .collect();
    for _ in 0..5 {
        let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
        m.add_initial_segment(&support::table()).unwrap();
        for s in &sets {
            m.update(s).unwrap();
        }
        println!("{:?}", m.stats());
    }
}
