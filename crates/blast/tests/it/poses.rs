//! App. A.1's blast poses against independent oracles: poses for a grid
//! of discs on a wall re-measured in closed form from the nozzle's forward
//! kinematics, and bad tools refused.

use blast::{BlastPoses, BlastTool};
use geom::{Isometry3, Point3, Real, Vector3};
use map::{OccupancyConfig, OccupancyGrid, RegionsConfig};
use plan::{PlanConfig, PoseConfig, Safety, Target};

/// The wall's face: occupied voxels fill x ∈ [0.7, 0.8).
const WALL_X: Real = 0.7;

/// A pose of the arm well inside its limits, scanner looking forward and down.
const START: [Real; 6] = [0.0, 0.0, 1.57, 0.0, 1.0, 0.0];

fn vm6083() -> robot::Robot {
    robot::builtin("denso-vm6083").unwrap()
}

fn safety() -> Safety {
    Safety::new(
        vm6083(),
        Isometry3::identity(),
        &PlanConfig::default(),
        vec![1.0; 6],
    )
    .unwrap()
}

/// Free everywhere except a wall of occupied voxels at x ∈ [0.7, 0.8),
/// y ∈ [−0.8, 0.8), z ∈ [0, 1.4), measured by rays from x = 0.35.
fn walled_grid() -> OccupancyGrid {
    let mut g = OccupancyGrid::new(OccupancyConfig {
        voxel_m: 0.1,
        regions: RegionsConfig::around([0.0, 0.0, 0.475], [1.1, 1.6, 2.1]),
        ..OccupancyConfig::default()
    })
    .unwrap();
    let keys: Vec<_> = g.geometry().keys().collect();
    for k in keys {
        g.mark_free(k).unwrap();
    }
    let mut origins = Vec::new();
    let mut points = Vec::new();
    for iy in -8..8 {
        for iz in 0..14 {
            let (y, z) = (0.05 + 0.1 * Real::from(iy), 0.05 + 0.1 * Real::from(iz));
            origins.push(Point3::new(0.35, y, z));
            points.push(Point3::new(WALL_X + 0.05, y, z));
        }
    }
    g.integrate_points(&origins, &points).unwrap();
    g
}

fn wall_target(y: Real, z: Real) -> Target {
    Target::new(Point3::new(WALL_X, y, z), -Vector3::x()).unwrap()
}

/// App. A.1: blast poses for a grid of discs on the wall, each re-measured
/// in closed form from the nozzle's forward kinematics (the stream from the
/// nozzle tip along its z axis meets the plane x = 0.7 at t = (0.7 − oₓ)/zₓ).
#[test]
fn blast_poses_hit_wall_discs_within_the_tool_limits() {
    let grid = walled_grid();
    let tool = BlastTool::default();
    let blast = BlastPoses::new(
        &vm6083(),
        Isometry3::identity(),
        &PlanConfig::default(),
        vec![1.0; 6],
        &PoseConfig::default(),
        tool,
    )
    .unwrap();
    let robot = vm6083();
    let offset = geom::math::isometry_from_xyz_rpy(tool.translation_m, [0.0; 3]);
    let (mut targets, mut valid) = (0, 0);
    for iy in -3..=3 {
        for iz in 0..=8 {
            let (y, z) = (0.1 * Real::from(iy), 0.3 + 0.1 * Real::from(iz));
            let target = wall_target(y, z);
            targets += 1;
            let solution = blast.select(&grid, &target, &START).unwrap();
            let m = blast.measure(&grid, &target, solution.joints()).unwrap();
            assert_eq!(m.valid, solution.valid(), "({y}, {z}): {m:?}");
            if !solution.valid() {
                continue;
            }
            valid += 1;
            let nozzle = robot.tool_pose(solution.joints()).unwrap() * offset;
            let o = Point3::from(nozzle.translation.vector);
            let dir = nozzle.rotation * Vector3::z();
            let t = (WALL_X - o.x) / dir.x;
            let hit = o + dir * t;
            let phi = dir.x.clamp(-1.0, 1.0).acos().to_degrees();
            let aim = (hit - target.centre).norm();
            assert!(phi < tool.phi_max_deg, "φ {phi}");
            assert!((tool.d_min_m..=tool.d_max_m).contains(&t), "d {t}");
            assert!(aim <= tool.rho_min_m + 1e-9, "aim {aim}");
            assert!(
                safety().dist(&grid, solution.joints()).unwrap() > 1.0,
                "dist(Q)"
            );
            assert!((phi - m.phi_deg).abs() < 1e-6 && (t - m.d_m).abs() < 1e-9);
            assert!((aim - m.aim_error_m).abs() < 1e-9);
        }
    }
    eprintln!("blast poses: {valid} of {targets} wall discs");
    assert!(valid * 100 >= 95 * targets, "{valid} of {targets}");
}

#[test]
fn bad_blast_tools_are_refused() {
    let ok = BlastTool::default();
    assert!(ok.validate().is_ok());
    for bad in [
        BlastTool {
            translation_m: [0.0, Real::NAN, 0.1],
            ..ok
        },
        BlastTool { d_min_m: 0.6, ..ok },
        BlastTool {
            phi_max_deg: -5.0,
            ..ok
        },
    ] {
        let e = bad.validate().unwrap_err().to_string();
        assert!(!e.is_empty());
        assert!(
            BlastPoses::new(
                &vm6083(),
                Isometry3::identity(),
                &PlanConfig::default(),
                vec![1.0; 6],
                &PoseConfig::default(),
                bad,
            )
            .is_err(),
            "{bad:?}"
        );
    }
}

/// `may_reach` is a proof of unreachability: every wall disc with a pose
/// passes it, and on the line from the shoulder it changes at the reach
/// bound plus the stream, hand-computed from the bound's radius.
#[test]
fn may_reach_refuses_only_discs_out_of_reach() {
    let grid = walled_grid();
    let tool = BlastTool::default();
    let robot = vm6083();
    let blast = BlastPoses::new(
        &robot,
        Isometry3::identity(),
        &PlanConfig::default(),
        vec![1.0; 6],
        &PoseConfig::default(),
        tool,
    )
    .unwrap();
    for iy in -3..=3 {
        for iz in 0..=8 {
            let target = wall_target(0.1 * Real::from(iy), 0.3 + 0.1 * Real::from(iz));
            if blast.select(&grid, &target, &START).unwrap().valid() {
                assert!(blast.may_reach(&target), "{target:?}");
            }
        }
    }
    // A disc facing the robot on the x axis at shoulder height: the nearest
    // centre of the bound is the shoulder at (0.18, 0, 0.475), and the
    // nearest tip position d_max in front of the disc.
    let nozzle = blast.robot().scanner.unwrap();
    let bound = blast
        .robot()
        .reach_bound(nozzle.link, &nozzle.link_from_scanner, 360)
        .unwrap();
    let edge = 0.18 + bound.radius + tool.d_max_m + tool.rho_min_m;
    let facing = |x: Real| Target::new(Point3::new(x, 0.0, 0.475), -Vector3::x()).unwrap();
    assert!(blast.may_reach(&facing(edge - 0.005)));
    assert!(!blast.may_reach(&facing(edge + 0.005)));
    // Far away, whatever it faces.
    for n in [Vector3::x(), -Vector3::x(), Vector3::z()] {
        let far = Target::new(Point3::new(-2.6, 0.5, 0.4), n).unwrap();
        assert!(!blast.may_reach(&far));
    }
    // A disc facing away from the robot at shoulder height on the x axis:
    // the tip stands beyond it, and the wrist centre (Table C.1: d₆ = 0.084
    // behind the flange, the nozzle 0.15 m in front of it) 0.234 m farther
    // along the stream, so at least s = d_min + 0.234 from the disc along
    // a direction within φ_max of +x: beyond x + s cos φ_max, while every
    // centre of the bound (the shoulder's circle) has x ≤ 0.18. The
    // wrist's bound is the arm to the wrist centre.
    let wrist = blast
        .robot()
        .reach_bound(robot::LinkId(4), &Isometry3::identity(), 360)
        .unwrap();
    let s = tool.d_min_m + 0.234;
    let phi = tool.phi_max_deg.to_radians();
    let within = wrist.radius + tool.rho_min_m;
    let away = |x: Real| Target::new(Point3::new(x, 0.0, 0.475), Vector3::x()).unwrap();
    let refused = 0.18 + within - s * phi.cos() + 0.005;
    assert!(!blast.may_reach(&away(refused)));
    // The tip alone would have taken it: d_min in front of it is within
    // the tip's bound of the shoulder.
    assert!(refused + tool.d_min_m - 0.18 < bound.radius);
    // Nearer, the wrist at s along φ_max (towards −z) is within its bound
    // of the shoulder: (x − 0.18 + s cos φ)² + (s sin φ)² = within².
    let taken = 0.18 - s * phi.cos() + ((within - 0.005).powi(2) - (s * phi.sin()).powi(2)).sqrt();
    assert!(blast.may_reach(&away(taken)));
}

/// Every target that some configuration within the limits blasts within
/// the tool's limits passes `may_reach`: 20 000 random configurations of
/// the VM-6083, each nozzle pose (forward kinematics) aimed at a disc
/// placed at a random stream length along it, within a random aim error,
/// facing back at a random angle below φ_max.
#[test]
fn may_reach_passes_every_target_a_configuration_reaches() {
    use rand::{RngExt, SeedableRng};
    let tool = BlastTool::default();
    let robot = vm6083();
    let base = Isometry3::translation(0.3, -0.2, 0.1);
    let blast = BlastPoses::new(
        &robot,
        base,
        &PlanConfig::default(),
        vec![1.0; 6],
        &PoseConfig::default(),
        tool,
    )
    .unwrap();
    let limits = blast.robot().limits();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let phi_max = tool.phi_max_deg.to_radians();
    let random_dir =
        |rng: &mut rand_chacha::ChaCha8Rng| Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
    for _ in 0..20_000 {
        let q: Vec<Real> = limits
            .iter()
            .map(|l| {
                let l = l.unwrap();
                rng.random_range(l.min..=l.max)
            })
            .collect();
        let nozzle = base * blast.robot().scanner_pose(&q).unwrap().unwrap();
        let tip = Point3::from(nozzle.translation.vector);
        let w = nozzle.rotation * Vector3::z();
        // A normal within φ_max of −w (near the limit half the time).
        let side = w.cross(&random_dir(&mut rng));
        let Some(side) = side.try_normalize(1e-6) else {
            continue;
        };
        let phi = phi_max * rng.random_range(0.0..0.999_f64).sqrt();
        let normal = -w * phi.cos() + side * phi.sin();
        let d = rng.random_range(tool.d_min_m..=tool.d_max_m);
        let hit = tip + w * d;
        // The centre within ρ_min of the hit, in the disc's plane.
        let off = normal.cross(&random_dir(&mut rng));
        let off = off.try_normalize(1e-6).unwrap_or_else(Vector3::zeros);
        let centre = hit + off * (tool.rho_min_m * rng.random_range(0.0..1.0));
        let target = Target::new(centre, normal).unwrap();
        assert!(blast.may_reach(&target), "q = {q:?}: {target:?}");
    }
}
