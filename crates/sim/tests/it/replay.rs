//! Issue 23 acceptance 2: both loops run on hardware that is not the
//! simulator. A session of the simulated rig is recorded
//! ([`hw::script::Recorder`]), kept as data (JSON), and played back by a
//! [`hw::script::Replay`], which answers every command with what was
//! recorded and refuses any other; the loop on the replay must do exactly
//! what it did on the simulator. (The exploration's replay is in the long
//! tests, `long/explore_stage_one.rs`.)

use follow::{EpisodeOptions, NoJudge};
use hw::script::{Event, Recorder, Replay, Script};
use scenario::Scenario;
use sim::follow_job::{FollowRunOptions, SimFollow};
use std::sync::atomic::AtomicBool;

/// A script through JSON, as a driver test would keep it.
pub fn through_json(script: &Script) -> Script {
    serde_json::from_str(&serde_json::to_string(script).unwrap()).unwrap()
}

#[test]
fn surface_following_on_a_replayed_session_repeats_the_simulated_run() {
    let loaded = Scenario::load("block1").unwrap();
    let options = FollowRunOptions {
        noise_sigma_m: Some(0.002),
        seed: 7,
        timings: false,
        ..FollowRunOptions::default()
    };
    let setup = SimFollow::from_scenario(&loaded, &options).unwrap();
    let episode = EpisodeOptions {
        max_sets: 300,
        timings: false,
        clock: hw::clock::RobotClock::default(),
    };
    let stop = AtomicBool::new(false);
    let mut recorder = Recorder::new(setup.rig.clone(), Vec::new());
    let mut on_sim = setup.follower().unwrap();
    let a = follow::run_episode(
        &mut recorder,
        &mut on_sim,
        &mut NoJudge,
        &episode,
        &stop,
        &mut |_, _| {},
    )
    .unwrap();
    let (_, script) = recorder.into_parts();
    let reads = script
        .events
        .iter()
        .filter(|e| matches!(e, Event::Read(_)))
        .count();
    assert_eq!(reads, a.rows.len());
    assert_eq!(a.rows.len(), 300, "{:?}", a.end);

    let mut replay = Replay::new(through_json(&script));
    let mut on_replay = setup.follower().unwrap();
    let b = follow::run_episode(
        &mut replay,
        &mut on_replay,
        &mut NoJudge,
        &episode,
        &stop,
        &mut |_, _| {},
    )
    .unwrap();
    assert_eq!(replay.remaining(), 0);
    assert_eq!(a, b);
    assert_eq!(
        on_sim.model().to_model_json(),
        on_replay.model().to_model_json()
    );

    // A replay answers only what was recorded: a session cut short ends the
    // run with the script's error, after the steps it holds.
    let mut short = through_json(&script);
    short.events.truncate(2 * 100 + 1);
    let mut replay = Replay::new(short);
    let c = follow::run_episode(
        &mut replay,
        &mut setup.follower().unwrap(),
        &mut NoJudge,
        &episode,
        &stop,
        &mut |_, _| {},
    )
    .unwrap();
    match &c.end {
        follow::RunEnd::Error(e) => assert!(e.contains("script"), "{e}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(c.rows[..], a.rows[..c.rows.len()]);
}
