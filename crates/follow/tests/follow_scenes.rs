//! The follower in simulated built-in scenes (P§4.3), checked against the
//! ground truth: the robot never touches the scene, the model keeps its
//! invariants, the top face gets modelled, redundancy keeps arm4's links off
//! block1 (issue 9, acceptance 2), and runs are deterministic.

mod support;

use follow::{FollowConfig, Mode};
use geom::{Point3, Real};
use support::Run;

/// Fraction of a 1 cm grid over the cube's top face lying within λ of a model
/// polygon whose normal is within μ of +z.
fn top_covered(run: &Run) -> Real {
    let model = run.follower.model();
    let lambda = model.config().lambda;
    let cos_mu = model.config().mu_deg.to_radians().cos();
    let polys: Vec<_> = model
        .segments()
        .filter_map(|s| s.as_polygon())
        .filter(|p| !p.is_initial() && p.normal().z > cos_mu)
        .collect();
    let (mut n, mut hit) = (0, 0);
    for i in 0..=100 {
        for j in 0..=100 {
            let p = Point3::new(
                -0.5 + 0.01 * Real::from(i),
                -0.5 + 0.01 * Real::from(j),
                1.0,
            );
            n += 1;
            if polys.iter().any(|g| g.distance_to_point(&p) < lambda) {
                hit += 1;
            }
        }
    }
    Real::from(hit) / Real::from(n)
}

#[test]
fn point3_follows_the_cube_top_safely_with_a_valid_model() {
    let mut run = Run::new("cube", "point3", FollowConfig::default(), 1);
    let mut modes = std::collections::BTreeSet::new();
    for k in 0..400 {
        let step = run.step();
        assert!(
            step.termination.is_none(),
            "step {k}: stopped early: {:?}",
            step.termination
        );
        modes.insert(step.mode);
        run.follower
            .model()
            .check_invariants()
            .unwrap_or_else(|e| panic!("step {k}: {e}"));
        // The control point (the robot's body) never meets the true surface.
        assert!(run.clearance() > 0.0, "step {k}: point3 touches the cube");
        // The control point keeps near δ from the model (P§3.2): never closer
        // than half of it.
        assert!(
            step.model_distance > 0.05,
            "step {k}: {} from the model",
            step.model_distance
        );
    }
    // The top face is being modelled: 59 % of it within λ after 400 sets
    // today (Pudney's whole cube took 693 sets; completion is issue 9's open
    // work), so this guards against regressions only.
    let top = top_covered(&run);
    assert!(top > 0.5, "top face {:.1} % covered", 100.0 * top);
    // The run went beyond the first surface: edges followed, gaps closed.
    assert!(
        modes.contains(&Mode::Edge) && modes.contains(&Mode::Gap),
        "{modes:?}"
    );
}

/// Issue 9 acceptance 2: on block1 with arm4 the null-space term (α) keeps
/// the links off the surface; with α = 0 they collide or come clearly closer.
#[test]
fn redundancy_keeps_arm4_off_block1() {
    let run_with = |alpha: Real| {
        let cfg = FollowConfig {
            alpha,
            ..FollowConfig::default()
        };
        let mut run = Run::new("block1", "arm4", cfg, 1);
        let mut min_clearance = Real::INFINITY;
        for _ in 0..500 {
            if run.step().termination.is_some() {
                break;
            }
            min_clearance = min_clearance.min(run.clearance());
        }
        min_clearance
    };
    let with = run_with(FollowConfig::default().alpha);
    let without = run_with(0.0);
    println!("min link clearance: α = 7000 {with:.3} m, α = 0 {without:.3} m");
    assert!(with > 0.0, "collision with redundancy on: {with}");
    assert!(
        without < 0.0 || without < with - 0.02,
        "α = 0 gave {without}, default {with}"
    );
}

#[test]
fn same_seed_same_run() {
    let trace = || {
        let mut run = Run::new("cube", "point3", FollowConfig::default(), 7);
        run.noise_m = 0.01;
        let cps: Vec<Point3> = (0..120).map(|_| run.step().control_point).collect();
        let json = serde_json::to_string(&run.follower.model().to_model_json()).unwrap();
        (cps, json)
    };
    assert_eq!(trace(), trace());
}
