//! What Stage Two could identify knowing the true scene
//! ([`sim::material_oracle`]): the share of A2's true surfaces some safe
//! pose identifies within the LRC's constraints, and the greedy oracle's
//! identified share viewpoint by viewpoint, with the pool's make-up and
//! the time it took.
//!
//! `cargo run --release -p sim --example material_oracle -- [SCENARIO]`
//! (default `bridge1`; the C-space model and the LRC of seed 0 from their
//! default caches).

use scenario::job::explore::{ExploreOptions, explore_setup};
use sim::material_oracle::MaterialPool;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("bridge1", String::as_str);
    let loaded = scenario::Scenario::load(name)?;
    let (setup, world) = explore_setup(
        &loaded,
        &ExploreOptions {
            cspace_cache: Some(ExploreOptions::default_cspace_cache(&loaded)?),
            ..ExploreOptions::default()
        },
    )?;
    let (lrc, obtained) = explore::train_lrc(
        &setup.materials,
        &setup.scanner,
        &setup.config.pose,
        0,
        Some(&ExploreOptions::default_lrc_cache(0)),
    )?;
    println!("{name}: the LRC {obtained}");
    let t = Instant::now();
    let pool = MaterialPool::new(
        &setup,
        &world,
        &setup.scanner,
        &loaded.scenario.metrics,
        &lrc,
    )?;
    let pool_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let oracle = pool.oracle();
    let greedy_s = t.elapsed().as_secs_f64();
    let (targets, aimed) = pool.aimed();
    let clear = pool.clear();
    let observations: usize = (0..pool.poses()).map(|i| pool.observations(i)).sum();
    println!(
        "{} A2 samples ({:.0} per m²); {} poses: the start, {} roadmap nodes, {aimed} aimed poses (valid for {aimed} of {targets} targets); {} clear; {observations} accepted observations",
        oracle.samples,
        oracle.samples_per_m2,
        oracle.poses,
        oracle.poses - 1 - aimed,
        clear.len()
    );
    let curve: Vec<String> = oracle
        .identified_after_viewpoints
        .iter()
        .map(|c| format!("{:.1}", 100.0 * c))
        .collect();
    println!(
        "identifiable {:.1} %; greedy, viewpoints 1..: {} %; accuracy {}",
        100.0 * oracle.identifiable,
        curve.join(" "),
        oracle
            .accuracy
            .map_or_else(|| "–".to_owned(), |a| format!("{:.1} %", 100.0 * a))
    );
    println!("pool {pool_s:.1} s, greedy {greedy_s:.2} s (wall)");
    Ok(())
}
