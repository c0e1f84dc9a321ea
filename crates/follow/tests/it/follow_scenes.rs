//! The follower in simulated built-in scenes (P§4.3), checked against the
//! ground truth: the robot never touches the scene, the model keeps its
//! invariants and lies within λ of the truth, redundancy keeps arm4's links
//! off block1 (issue 9, acceptance 2), and runs are deterministic. Completing
//! the cube within 1.5 × Pudney's set count (acceptance 1) is written out but
//! ignored while it fails; completion itself is checked by
//! `sim/tests/follow_complete.rs`.

use crate::support;

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
    // Noise-free, every model vertex lies within λ (the model's linear
    // resolution) of the true surface.
    let model = run.follower.model();
    for seg in model.segments().filter(|s| !s.is_initial()) {
        if let Some(p) = seg.as_polygon() {
            for v in p.vertices() {
                let (d, _, _) = run.scene.closest_point(&v, 1.0).unwrap();
                assert!(
                    d < model.config().lambda,
                    "{:?}: vertex {v:?} is {d} m off the cube",
                    seg.id()
                );
            }
        }
    }
    // The run went beyond the first surface: edges followed, gaps closed.
    assert!(
        modes.contains(&Mode::Edge) && modes.contains(&Mode::Gap),
        "{modes:?}"
    );
}

/// Issue 9 acceptance 1 for point3 on the cube, as far as this crate can
/// judge it: the run ends by the algorithm's own rule within 1.5 × Pudney's
/// 693 sets with the top face ≥ 95 % modelled. Open: the run completes (with
/// every face, edge and corner, `sim/tests/follow_complete.rs`) but needs
/// ~4500 sets (measured 2026-11-24): the faces built from the follower's sets
/// keep long narrow slits inside already-sensed area (on the −y face after
/// 2700 sets: a channel 0.01–0.07 m wide running ~1.5 m into the face), and
/// the follower spends most of its sets on their edges.
#[test]
#[ignore = "issue 9 open: the cube completes (sim/tests/follow_complete.rs) but in ~4500 sets, not within 1.5 × Pudney's 693"]
fn point3_completes_the_cube() {
    let mut run = Run::new("cube", "point3", FollowConfig::default(), 1);
    let budget = 1040; // 1.5 × 693
    let mut ended = None;
    for _ in 0..budget {
        if let Some(t) = run.step().termination {
            ended = Some(t);
            break;
        }
    }
    let top = top_covered(&run);
    println!(
        "after {} sets: {ended:?}, top {:.1} %",
        run.follower.steps(),
        100.0 * top
    );
    assert_eq!(ended, Some(follow::Termination::SurfaceComplete));
    assert!(top >= 0.95, "top face {:.1} % covered", 100.0 * top);
}

/// Issue 9 acceptance 2 and issue 24 acceptance 8: on block1 with arm4 the
/// null-space term (α) keeps the links off the surface; with α = 0 they
/// collide (eq. 3 alone) or come clearly closer (with our link guard and
/// safety guard, which must not hide what redundancy does). Measured
/// 2026-11-27 with the ceilings shared (`task_share` 0.15): eq. 3 alone
/// 32 mm against −28 mm (α = 0), the link guard 33 against −41 mm over 500
/// steps; every default over the whole run 17 against 0 mm (the α = 0 arm
/// touches block1 with the safety guard on: surface no reading had
/// touched), and the links outside the control point's zone 19 against
/// 1 mm. (This harness gives no face a priori; `surveyor follow` does.)
#[test]
fn redundancy_keeps_arm4_off_block1() {
    // The smallest clearance over `steps` steps (or the whole run) of links
    // outside the control point's ball of radius `zone` (0: the whole arm).
    let run_with = |alpha: Real, link_margin_m: Real, guard: bool, steps: usize, zone: Real| {
        let cfg = FollowConfig {
            alpha,
            link_margin_m,
            guard,
            ..FollowConfig::default()
        };
        let mut run = Run::new("block1", "arm4", cfg, 1);
        let mut min_clearance = Real::INFINITY;
        for _ in 0..steps {
            if run.step().termination.is_some() {
                break;
            }
            min_clearance = min_clearance.min(run.clearance_outside_control_zone(zone));
        }
        min_clearance
    };
    let margin = FollowConfig::default().link_margin_m;
    let alpha = FollowConfig::default().alpha;
    let pair = |margin, guard, steps, zone| {
        (
            run_with(alpha, margin, guard, steps, zone),
            run_with(0.0, margin, guard, steps, zone),
        )
    };
    // Pudney's scheme alone (no safety guard, our link guard held back to
    // the link's own radius): the null-space term is what keeps the links off.
    let (with, without) = pair(0.0, false, 500, 0.0);
    println!("eq. 3 alone: min link clearance α = {alpha} {with:.3} m, α = 0 {without:.3} m");
    assert!(with > 0.0, "collision with redundancy on: {with}");
    assert!(without < 0.0, "α = 0 did not collide: {without}");
    // The link guard without the safety guard: α = 0 collides too.
    let (with, without) = pair(margin, false, 500, 0.0);
    println!("link guard: min link clearance α = {alpha} {with:.3} m, α = 0 {without:.3} m");
    assert!(with > 0.0, "collision with redundancy on: {with}");
    assert!(without < 0.6 * with, "α = 0 gave {without}, default {with}");
    // Every default (the safety guard too), over the whole run: the whole
    // arm, and the links outside the control point's zone, which are what
    // the null-space term moves.
    let whole = 20_000;
    let (with, without) = pair(margin, true, whole, 0.0);
    println!("defaults: min link clearance α = {alpha} {with:.3} m, α = 0 {without:.3} m");
    assert!(without < 0.6 * with, "α = 0 gave {without}, default {with}");
    let zone = FollowConfig::default().desired_distance_m;
    let (with, without) = pair(margin, true, whole, zone);
    println!(
        "defaults, links outside the control zone: min clearance α = {alpha} {with:.3} m, α = 0 {without:.3} m"
    );
    assert!(without < 0.6 * with, "α = 0 gave {without}, default {with}");
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
