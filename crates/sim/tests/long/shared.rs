//! Runs more than one long test judges, made once per test binary.
//!
//! bridge1, seed 0, Stage One to its own end and 8 Stage Two viewpoints
//! ([`bridge1_both_stages`]): the Stage One of the coverage-oracle test
//! (`explore_oracle`, which ran it alone before: Stage One does not depend
//! on whether Stage Two follows) and the Stage Two test's run
//! (`explore_stage_one::stage_two_aims_at_discs_safely_and_lowers_the_material_information`).
//! Both made the same Stage One, 20 s of a release build each.

use scenario::Scenario;
use scenario::job::explore::{ExploreOptions, ExploreOutcome};
use sim::explore_job::run_exploration;
use std::path::Path;
use std::sync::OnceLock;

/// `CARGO_TARGET_TMPDIR`, where the long tests cache what they build.
pub fn tmp() -> &'static Path {
    Path::new(env!("CARGO_TARGET_TMPDIR"))
}

/// The options of [`bridge1_both_stages`]: the C-space model cached, the
/// scenario's Stage One with room to end by its own rule (after 8 viewpoints
/// no disc is targetable yet: the arm has not seen enough free space to
/// reach a valid pose), 8 Stage Two viewpoints whose transits scan every 2°,
/// no oracle (the coverage
/// oracle's test computes it on its own: with Stage Two the run would also
/// compute the material oracle, which no test here reads).
pub fn bridge1_both_stages_options() -> ExploreOptions {
    let loaded = Scenario::load("bridge1").unwrap();
    let mut config = loaded.scenario.explore.clone().unwrap();
    config.max_viewpoints = 40;
    config.stage_two_max_viewpoints = 8;
    // Stage Two scans on its way (every 2°) and classifies those scans.
    config.stage_two_scan_step_deg = 2.0;
    ExploreOptions {
        seed: 0,
        config: Some(config),
        stage_two: true,
        cspace_cache: Some(tmp().join("cspace-denso-vm6083.json")),
        ..ExploreOptions::default()
    }
}

/// The bridge1 run of both stages (see [`bridge1_both_stages_options`]).
pub fn bridge1_both_stages() -> &'static ExploreOutcome {
    static RUN: OnceLock<ExploreOutcome> = OnceLock::new();
    RUN.get_or_init(|| {
        let loaded = Scenario::load("bridge1").unwrap();
        run_exploration(&loaded, &bridge1_both_stages_options(), &mut |_| {}).unwrap()
    })
}
