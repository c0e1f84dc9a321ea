//! An upper bound on what Stage One's viewpoint choice can cover
//! ([`sim::oracle`]): the A1 coverage (SPEC §6) reached by choosing each next
//! sweep *knowing the true scene*, greedily, among the start pose and the
//! C-space model's roadmap nodes, under the run's safety rule and the contact
//! rule side by side, with a bound on any choice of as many sweeps.
//!
//! `cargo run --release -p sim --example coverage_oracle -- [SCENARIO] [SWEEPS] [EXTRA]`
//! (default `bridge1 12 0`; `SWEEPS` counts the start pose's sweep, as
//! `surveyor explore` counts viewpoints; `EXTRA` more poses drawn uniformly
//! within the joint limits join the pool, seeded, to see how much a denser
//! pool would add).

use scenario::job::explore::{ExploreOptions, explore_setup};
use sim::oracle::{OraclePool, OracleRule};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("bridge1", String::as_str);
    let sweeps: usize = args.get(1).map_or(Ok(12), |s| s.parse())?;
    let extra: usize = args.get(2).map_or(Ok(0), |s| s.parse())?;
    let loaded = scenario::Scenario::load(name)?;
    let (setup, world) = explore_setup(
        &loaded,
        &ExploreOptions {
            cspace_cache: Some(ExploreOptions::default_cspace_cache(&loaded)?),
            ..ExploreOptions::default()
        },
    )?;
    let scanner = loaded.scenario.scanner.clone().unwrap_or_default().config;
    let pool = OraclePool::new(&setup, &world, &scanner, &loaded.scenario.metrics, extra)?;
    println!(
        "{name}: {} A1 samples; {} poses (start, roadmap nodes, {extra} more)",
        pool.samples(),
        pool.poses()
    );
    for rule in [OracleRule::Run, OracleRule::Contact] {
        let clear = pool.clear(rule);
        println!(
            "\n{} rule: {} poses clear with their sweep{}; all of their sweeps and the start's together cover {:.1} %",
            rule.name(),
            clear.len(),
            if clear.first() == Some(&0) {
                ""
            } else {
                " (the start pose is not)"
            },
            100.0 * pool.all(rule)
        );
        let (curve, have) = pool.greedy(rule, sweeps);
        let curve: Vec<String> = curve.iter().map(|c| format!("{:.1}", 100.0 * c)).collect();
        println!("greedy, sweeps 1..={sweeps}:  {} %", curve.join(" "));
        println!(
            "no {sweeps} sweeps of these poses cover more than {:.1} %",
            100.0 * pool.bound(rule, sweeps, &have)
        );
    }
    Ok(())
}
