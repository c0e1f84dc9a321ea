//! Issue 25 acceptance 1–2: Stage One against the coverage oracle (greedy
//! sweeps chosen knowing the true scene, `sim::oracle`) on bridge1 and on a
//! channel variant Stage One was not tuned on (`data/scenarios/channel4.toml`):
//! after 12 viewpoints at least 85 % of the oracle's 12-sweep A1 coverage,
//! ended by the 1 % rule within 15 viewpoints with at least 95 % of it, no
//! collision, no unsafe configuration, the links 0.05 m or more from the
//! true surface on every executed motion. Paul's configuration
//! (`ExploreConfig::thesis_stage_one`) runs beside it on bridge1 and is
//! printed, not bounded.
//!
//! `cargo test --release -p sim --test long explore_oracle -- --ignored --nocapture`

use explore::ExploreConfig;
use scenario::Scenario;
use sim::explore_job::{ExploreOptions, OracleOption, run_exploration};
use std::path::Path;

/// Options with the C-space model and the oracle cached for the long tests.
fn options(name: &str, seed: u64) -> ExploreOptions {
    let tmp = Path::new(env!("CARGO_TARGET_TMPDIR"));
    ExploreOptions {
        seed,
        cspace_cache: Some(tmp.join("cspace-denso-vm6083.json")),
        oracle: OracleOption::On(Some(tmp.join(format!("oracle-{name}.json")))),
        ..ExploreOptions::default()
    }
}

/// Stage One on `scenario` with `config` (the scenario's own when `None`):
/// (A1 ratio to the oracle's 12 sweeps after 12 viewpoints, at the end,
/// viewpoints, termination), after checking its safety.
fn stage_one(
    scenario: &str,
    seed: u64,
    config: Option<ExploreConfig>,
) -> (f64, f64, usize, String, f64, usize) {
    let loaded = Scenario::load(scenario).unwrap();
    let name = loaded.scenario.name.clone();
    let outcome = run_exploration(
        &loaded,
        &ExploreOptions {
            config,
            ..options(&name, seed)
        },
        &mut |_| {},
    )
    .unwrap();
    let run = &outcome.run;
    let o = outcome.coverage_summary().unwrap().oracle.unwrap();
    let curve: Vec<String> = run
        .viewpoints
        .iter()
        .map(|v| format!("{:.1}", 100.0 * v.coverage_a1.unwrap()))
        .collect();
    println!(
        "{name} seed {seed}: {} viewpoints ({}), A1 % {}; oracle {:.1} % after 12 sweeps; ratio {:.2} after 12, {:.2} at the end; min clearance {:.3} m",
        run.viewpoints.len(),
        run.termination.name(),
        curve.join(" "),
        100.0 * o.a1_after_12,
        o.ratio_after_12,
        o.ratio_at_stage_one_end,
        run.tally.min_clearance_m.unwrap()
    );
    assert_eq!(run.tally.collisions, Some(0));
    println!(
        "{name}: {} unsafe configurations",
        run.unsafe_configurations.len()
    );
    // The oracle's curve is the greedy one: it never falls.
    assert!(o.oracle.a1_after_sweeps.windows(2).all(|w| w[1] >= w[0]));
    (
        o.ratio_after_12,
        o.ratio_at_stage_one_end,
        run.viewpoints.len(),
        run.termination.name().to_owned(),
        run.tally.min_clearance_m.unwrap(),
        run.unsafe_configurations.len(),
    )
}

#[test]
#[ignore = "minutes in release; run by .ci/run"]
fn stage_one_comes_near_the_oracle_on_bridge1_and_an_untuned_channel() {
    let scenes = [
        "bridge1".to_owned(),
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../data/scenarios/channel4.toml"
        )
        .to_owned(),
    ];
    for scene in &scenes {
        let (at_12, at_end, n, end, clearance, unsafe_configurations) = stage_one(scene, 0, None);
        assert!(clearance >= 0.05, "{scene}: {clearance:.3} m");
        assert_eq!(unsafe_configurations, 0, "{scene}");
        assert!(at_12 >= 0.85, "{scene}: {at_12:.3} of the oracle after 12");
        assert!(
            at_end >= 0.95,
            "{scene}: {at_end:.3} of the oracle at the end"
        );
        assert!(n <= 15, "{scene}: {n} viewpoints");
        assert_eq!(end, "information_converged", "{scene}");
    }
    // Paul's Stage One beside it (reported).
    let loaded = Scenario::load("bridge1").unwrap();
    let thesis = loaded
        .scenario
        .explore
        .clone()
        .unwrap_or_default()
        .thesis_stage_one();
    let (at_12, at_end, n, end, clearance, _) = stage_one("bridge1", 0, Some(thesis));
    println!(
        "Paul's configuration: {at_12:.2} after 12, {at_end:.2} at the end of {n} ({end}); min clearance {clearance:.3} m"
    );
}
