//! Stage Two pose selection (A§3.3) against independent oracles: view
//! geometry worked out by hand from a scanner pose, each cost's shape at
//! hand-picked points, and selected poses re-measured from
//! `Robot::scanner_pose` (a ray meeting the plane `x = 0.7` in closed form) and
//! `Safety::dist`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use geom::{Isometry3, Point3, Real, UnitVector3, Vector3};
use map::{OccupancyConfig, OccupancyGrid, RegionsConfig, VoxelKey};
use plan::pose::sigmoid;
use plan::{
    PlanConfig, PlanError, PoseConfig, PoseSelector, PoseTermination, Safety, Target, view_geometry,
};
use robot::JointLimits;

const VOXEL: Real = 0.1;
/// The wall's face: occupied voxels fill x ∈ [0.7, 0.8).
const WALL_X: Real = 0.7;

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

fn grid() -> OccupancyGrid {
    OccupancyGrid::new(OccupancyConfig {
        voxel_m: VOXEL,
        regions: RegionsConfig::around([0.0, 0.0, 0.475], [1.1, 1.6, 2.1]),
        ..OccupancyConfig::default()
    })
    .unwrap()
}

/// Every voxel key of the grid.
fn keys(grid: &OccupancyGrid) -> Vec<VoxelKey> {
    let g = grid.geometry();
    let [nx, ny, nz] = g.dims();
    let k0 = g.key_min().coords();
    let mut out = Vec::with_capacity(nx * ny * nz);
    for z in 0..nz as i32 {
        for y in 0..ny as i32 {
            for x in 0..nx as i32 {
                out.push(VoxelKey::new(k0[0] + x, k0[1] + y, k0[2] + z));
            }
        }
    }
    out
}

/// Free everywhere except a wall of occupied voxels at x ∈ [0.7, 0.8),
/// y ∈ [−0.8, 0.8), z ∈ [0, 1.4), measured by rays from x = 0.35.
fn walled_grid() -> OccupancyGrid {
    walled_grid_with_unknown(&[])
}

/// [`walled_grid`] with the voxels `unknown` left unexplored.
fn walled_grid_with_unknown(unknown: &[VoxelKey]) -> OccupancyGrid {
    let mut g = grid();
    for k in keys(&g) {
        if !unknown.contains(&k) {
            g.mark_free(k).unwrap();
        }
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

/// A pose of the arm well inside its limits, scanner looking forward and down.
const START: [Real; 6] = [0.0, 0.0, 1.57, 0.0, 1.0, 0.0];

fn wall_target(y: Real, z: Real) -> Target {
    Target::new(Point3::new(WALL_X, y, z), -Vector3::x()).unwrap()
}

/// Unit vector `b` perpendicular to `a`.
fn perpendicular(a: &Vector3) -> Vector3 {
    let helper = if a.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    geom::unit(a.cross(&helper)).unwrap().into_inner()
}

#[test]
fn view_geometry_matches_hand_computation() {
    let robot = vm6083();
    let q = [0.3, 0.2, 1.2, 0.4, 0.9, -0.5];
    let pose = robot.scanner_pose(&q).unwrap().unwrap();
    let p1 = Point3::from(pose.translation.vector);
    let a = pose.rotation * Vector3::z();
    let b = perpendicular(&a);
    // The plane's normal is tilted θ = 20° from −a toward −b; its centre
    // lies 0.5 m along the ray and 0.1 m aside along b. On the ray p1 + t a,
    // n·(x − P̂) = 0 gives −cos θ (t − 0.5) + 0.1 sin θ = 0, so
    // t = 0.5 + 0.1 tan θ, and the miss is |(t − 0.5) a − 0.1 b| = 0.1 / cos θ.
    let theta = 20f64.to_radians();
    let normal = -(a * theta.cos() + b * theta.sin());
    let centre = p1 + a * 0.5 + b * 0.1;
    let target = Target::new(centre, normal).unwrap();
    let view = view_geometry(&pose, &target);
    let t = 0.5 + 0.1 * theta.tan();
    let hit = view.hit.unwrap();
    assert!((hit.point - (p1 + a * t)).norm() < 1e-12, "{hit:?}");
    assert!((hit.d_m - t).abs() < 1e-12);
    assert!((hit.rho_m - 0.1 / theta.cos()).abs() < 1e-12);
    assert!((view.phi_rad - theta).abs() < 1e-12);
    // p_a lies on the plane, in front of the scanner (the printed minus of
    // eq. 3.11 would put it at p1 − t a, behind).
    assert!(normal.dot(&(hit.point - centre)).abs() < 1e-12);
    assert!((hit.point - p1).dot(&a) > 0.0);

    // Seen from behind: the normal turned toward the far side, φ = 160°.
    let back = Target::new(centre, -normal).unwrap();
    let v = view_geometry(&pose, &back);
    assert!((v.phi_rad - (180f64 - 20.0).to_radians()).abs() < 1e-12);
    // The plane behind the scanner: no intersection, d = ρ = ∞.
    let behind = Target::new(p1 - a * 0.5, normal).unwrap();
    let v = view_geometry(&pose, &behind);
    assert!(v.hit.is_none());
    assert!(v.d_m().is_infinite() && v.rho_m().is_infinite());
    // A ray parallel to the plane: no intersection either.
    let parallel = Target::new(p1 + b * 0.3, b).unwrap();
    assert!(view_geometry(&pose, &parallel).hit.is_none());
}

#[test]
fn costs_are_low_inside_high_outside_and_half_at_the_bounds() {
    let c = PoseConfig::default();
    let deg = |d: Real| d.to_radians();
    // g1: φ < 42°.
    assert!(c.g1_orientation(deg(20.0)) < 0.01);
    assert!(c.g1_orientation(deg(60.0)) > 0.99);
    assert!((c.g1_orientation(deg(42.0)) - 0.5).abs() < 1e-12);
    // g2: 0.25 m ≤ d ≤ 0.8 m (low inside, high on both sides).
    assert!(c.g2_range(0.5) < 0.01);
    assert!(c.g2_range(0.1) > 0.99 && c.g2_range(1.2) > 0.99);
    assert!((c.g2_range(0.25) - 0.5).abs() < 1e-9);
    assert!((c.g2_range(0.8) - 0.5).abs() < 1e-9);
    assert!((c.g2_range(Real::INFINITY) - 1.0).abs() < 1e-12);
    // g3: ‖p_a − P̂‖ ≤ 15 mm, normalised to 0 at a perfect aim: with
    // σ₀ = σ(−15 mm / 3 mm) = 1 / (1 + e⁵), the cost at ρ_min is
    // (½ − σ₀) / (1 − σ₀) ≈ 0.4966.
    let floor = 1.0 / (1.0 + 5f64.exp());
    assert_eq!(c.g3_accuracy(0.0), 0.0);
    assert!(c.g3_accuracy(0.002) < 0.01);
    assert!(c.g3_accuracy(0.05) > 0.99);
    assert!((c.g3_accuracy(0.015) - (0.5 - floor) / (1.0 - floor)).abs() < 1e-12);
    assert_eq!(c.g3_accuracy(Real::INFINITY), 1.0);
    // g4: dist(Q) > 1.
    assert!(c.g4_safety(3.0) < 0.01);
    assert!(c.g4_safety(0.0) > 0.99);
    assert!((c.g4_safety(1.0) - 0.5).abs() < 1e-12);
    // g5: 30° of room on both sides of q5 inside ±120°, i.e. |q5| ≤ 90°.
    let l5 = Some(JointLimits::from_degrees(-120.0, 120.0));
    assert!(c.g5_tilt(0.0, l5) < 0.01);
    assert!(c.g5_tilt(deg(60.0), l5) < 0.01);
    assert!(c.g5_tilt(deg(110.0), l5) > 0.99);
    assert!(c.g5_tilt(deg(-110.0), l5) > 0.99);
    assert!((c.g5_tilt(deg(90.0), l5) - 0.5).abs() < 1e-12);
    assert!((c.g5_tilt(deg(-90.0), l5) - 0.5).abs() < 1e-12);
    assert_eq!(c.g5_tilt(5.0, None), 0.0);
    // g6: Σ over joints of the squared min/max cost (eq. 3.19).
    let limits = vec![Some(JointLimits::from_degrees(-90.0, 90.0)); 6];
    assert!(c.g6_limits(&[0.0; 6], &limits) < 1e-12);
    let mut q = [0.0; 6];
    q[2] = deg(110.0);
    assert!(c.g6_limits(&q, &limits) > 0.99);
    q[2] = deg(90.0);
    assert!((c.g6_limits(&q, &limits) - 0.25).abs() < 1e-9);
    q[4] = deg(-90.0);
    assert!((c.g6_limits(&q, &limits) - 0.5).abs() < 1e-9);
    // The sigmoid itself: σ(0) = ½, symmetric, no overflow.
    assert_eq!(sigmoid(0.0), 0.5);
    assert!((sigmoid(2.0) + sigmoid(-2.0) - 1.0).abs() < 1e-15);
    assert_eq!(sigmoid(1e6), 1.0);
    assert_eq!(sigmoid(-1e6), 0.0);
}

/// The LRC constraints re-measured without the pose module: the scanner pose
/// from the robot, the ray meeting the wall plane x = 0.7 in closed form,
/// dist(Q) from `Safety::dist`.
fn check_independently(safety: &Safety, grid: &OccupancyGrid, target: &Target, q: &[Real]) {
    let config = PoseConfig::default();
    let robot = safety.robot();
    assert!(robot.within_limits(q), "{q:?}");
    let pose = robot.scanner_pose(q).unwrap().unwrap();
    let p1 = Point3::from(pose.translation.vector);
    let a = pose.rotation * Vector3::z();
    // Normal −x: the angle of incidence is that between a and +x.
    let phi = a.x.clamp(-1.0, 1.0).acos();
    assert!(
        phi < config.phi_max_deg.to_radians(),
        "φ {}°",
        phi.to_degrees()
    );
    assert!(p1.x < WALL_X && a.x > 0.0, "scanner {p1:?} ray {a:?}");
    let t = (WALL_X - p1.x) / a.x;
    let p_a = p1 + a * t;
    let d = (p_a - p1).norm();
    assert!(
        (config.d_min_m..=config.d_max_m).contains(&d),
        "d {d} from {p1:?}"
    );
    let rho = (p_a - target.centre).norm();
    assert!(rho <= config.rho_min_m, "ρ {rho}");
    let dist = safety.dist(grid, q).unwrap();
    assert!(dist > 1.0, "dist {dist}");
    let q5 = q[4].to_degrees();
    assert!(
        q5.abs() <= 90.0,
        "q5 {q5}° leaves less than 30° of tilt room"
    );
}

#[test]
fn selected_poses_meet_every_constraint_on_the_wall() {
    let safety = safety();
    let grid = walled_grid();
    let selector = PoseSelector::new(&safety, PoseConfig::default()).unwrap();
    assert!(safety.dist(&grid, &START).unwrap() > 1.0);
    for (y, z) in [
        (0.0, 0.5),
        (0.3, 0.8),
        (-0.3, 0.3),
        (0.2, 1.1),
        (-0.5, 0.6),
        (0.5, 0.2),
    ] {
        let target = wall_target(y, z);
        let solution = selector.select(&grid, &target, &START).unwrap();
        assert!(solution.valid(), "target ({y}, {z}): {:?}", solution.pose);
        check_independently(&safety, &grid, &target, solution.joints());
        // What the solution reports agrees with the re-measurement.
        let pose = &solution.pose;
        let scanner = safety
            .robot()
            .scanner_pose(solution.joints())
            .unwrap()
            .unwrap();
        let hit = pose.view.hit.unwrap();
        let p1 = Point3::from(scanner.translation.vector);
        assert!((hit.d_m - (hit.point - p1).norm()).abs() < 1e-9);
        assert!((hit.rho_m - (hit.point - target.centre).norm()).abs() < 1e-9);
        let dist = safety
            .dist(&grid, solution.joints())
            .unwrap()
            .min(selector.dist_bound());
        assert!((pose.dist - dist).abs() < 1e-9, "{} vs {dist}", pose.dist);
        assert!(solution.iterations() <= 50);
        assert!(solution.runs.iter().all(|r| r.iterations <= 50));
        assert!(pose.objective < 1e-3, "g = {}", pose.objective);
    }
}

#[test]
fn every_start_kept_best_is_valid_too() {
    let safety = safety();
    let grid = walled_grid();
    let config = PoseConfig {
        stop_at_valid: false,
        ..PoseConfig::default()
    };
    let selector = PoseSelector::new(&safety, config).unwrap();
    let target = wall_target(0.1, 0.7);
    let solution = selector.select(&grid, &target, &START).unwrap();
    assert_eq!(solution.runs.len(), 5);
    assert!(solution.valid());
    check_independently(&safety, &grid, &target, solution.joints());
    // The best run has the lowest objective among the valid runs.
    let best = &solution.runs[solution.best_run];
    assert!(best.valid);
    for run in solution.runs.iter().filter(|r| r.valid) {
        assert!(best.objective <= run.objective);
    }
}

#[test]
fn lm_alone_recovers_from_a_nearby_invalid_start() {
    // Only the given start: the aimed starts play no part. A valid pose with
    // the base turned by 2°, which swings the ray ~2.5 cm off the centre.
    let safety = safety();
    let grid = walled_grid();
    let target = wall_target(0.2, 0.6);
    let valid = PoseSelector::new(&safety, PoseConfig::default())
        .unwrap()
        .select(&grid, &target, &START)
        .unwrap();
    assert!(valid.valid());
    let one = PoseSelector::new(
        &safety,
        PoseConfig {
            starts: 1,
            ..PoseConfig::default()
        },
    )
    .unwrap();
    let mut start = valid.joints().to_vec();
    start[0] += 2f64.to_radians();
    let before = one.evaluate(&grid, &target, &start).unwrap();
    assert!(!before.constraints.accuracy, "{:?}", before.view);
    let after = one.select(&grid, &target, &start).unwrap();
    assert_eq!(after.runs.len(), 1);
    assert!(after.valid(), "{:?}", after.pose);
    assert!(after.iterations() > 0);
    check_independently(&safety, &grid, &target, after.joints());
}

#[test]
fn lm_alone_moves_the_arm_off_unexplored_space() {
    // A valid pose, then one voxel near the surface of a forearm or wrist
    // ellipsoid left unknown: the pose becomes unsafe (dist(Q) < 1) while the
    // view is unchanged. LM from that pose alone must restore dist(Q) > 1 and
    // keep the view.
    let safety = safety();
    let grid = walled_grid();
    let target = wall_target(-0.2, 0.7);
    let valid = PoseSelector::new(&safety, PoseConfig::default())
        .unwrap()
        .select(&grid, &target, &START)
        .unwrap();
    assert!(valid.valid());
    let q = valid.joints().to_vec();
    let ellipsoids = safety.ellipsoids(&q).unwrap();
    // Links 3.. (ellipsoids[2..]): the forearm and the wrist.
    let (key, _) = keys(&grid)
        .into_iter()
        .filter(|k| grid.state(*k) == map::VoxelState::Free)
        .filter_map(|k| {
            let c = k.center(VOXEL);
            let near = ellipsoids[2..]
                .iter()
                .map(|e| e.algebraic_distance(&c))
                .fold(Real::INFINITY, Real::min);
            (0.6..0.95).contains(&near).then_some((k, near))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .expect("a free voxel just inside a forearm or wrist ellipsoid");
    let grid = walled_grid_with_unknown(&[key]);
    let before = safety.dist(&grid, &q).unwrap();
    assert!(before < 1.0, "{before}");
    let one = PoseSelector::new(
        &safety,
        PoseConfig {
            starts: 1,
            ..PoseConfig::default()
        },
    )
    .unwrap();
    let eval = one.evaluate(&grid, &target, &q).unwrap();
    assert!(!eval.constraints.safety);
    assert!(eval.constraints.accuracy && eval.constraints.orientation);
    let after = one.select(&grid, &target, &q).unwrap();
    assert!(after.valid(), "{:?}", after.pose);
    check_independently(&safety, &grid, &target, after.joints());
}

/// The blast plan's settings (backtracking aimed starts, runs given up when
/// the aim strays ten scales) still solve every wall target, re-measured.
#[test]
fn backtracking_starts_with_give_up_solve_the_wall() {
    let safety = safety();
    let grid = walled_grid();
    let config = PoseConfig {
        aim_backtracking: true,
        give_up_scales: 10.0,
        ..PoseConfig::default()
    };
    let selector = PoseSelector::new(&safety, config).unwrap();
    for (y, z) in [(0.0, 0.5), (0.3, 0.8), (-0.3, 0.3), (0.2, 1.1), (-0.5, 0.6)] {
        let target = wall_target(y, z);
        let solution = selector.select(&grid, &target, &START).unwrap();
        assert!(solution.valid(), "target ({y}, {z}): {:?}", solution.pose);
        check_independently(&safety, &grid, &target, solution.joints());
    }
}

/// The give-up rule as stated: from a start whose aim misses the target by
/// two centimetres, LM alone with a threshold far below that miss stops at
/// the iteration the rule starts at, and without the rule the same run goes
/// on and succeeds.
#[test]
fn a_run_whose_aim_strays_is_given_up() {
    let safety = safety();
    let grid = walled_grid();
    let target = wall_target(0.2, 0.6);
    let valid = PoseSelector::new(&safety, PoseConfig::default())
        .unwrap()
        .select(&grid, &target, &START)
        .unwrap();
    let mut start = valid.joints().to_vec();
    start[0] += 2f64.to_radians();
    let one = |give_up_scales| {
        PoseSelector::new(
            &safety,
            PoseConfig {
                starts: 1,
                give_up_scales,
                ..PoseConfig::default()
            },
        )
        .unwrap()
        .select(&grid, &target, &start)
        .unwrap()
    };
    let before = PoseSelector::new(&safety, PoseConfig::default())
        .unwrap()
        .evaluate(&grid, &target, &start)
        .unwrap();
    assert!(before.view.hit.unwrap().rho_m > 0.02, "{:?}", before.view);
    let free = one(0.0);
    assert!(free.valid(), "{:?}", free.pose);
    assert!(free.runs[0].iterations > plan::pose::GIVE_UP_AFTER);
    // A micrometre: every run that has not hit the centre by then stops.
    let strict = one(1e-3);
    assert_eq!(strict.runs[0].termination, PoseTermination::GaveUp);
    assert_eq!(strict.runs[0].iterations, plan::pose::GIVE_UP_AFTER);
}

#[test]
fn give_up_scales_must_be_finite_and_not_negative() {
    let safety = safety();
    for bad in [-1.0, Real::NAN, Real::INFINITY] {
        let config = PoseConfig {
            give_up_scales: bad,
            ..PoseConfig::default()
        };
        let err = PoseSelector::new(&safety, config).unwrap_err();
        assert!(
            matches!(
                err,
                PlanError::Config {
                    field: "pose.give_up_scales",
                    ..
                }
            ),
            "{bad}: {err}"
        );
    }
}

#[test]
fn target_out_of_reach_is_flagged_not_an_error() {
    let safety = safety();
    let grid = walled_grid();
    let selector = PoseSelector::new(&safety, PoseConfig::default()).unwrap();
    let target = Target::new(Point3::new(3.0, 0.0, 0.5), -Vector3::x()).unwrap();
    let solution = selector.select(&grid, &target, &START).unwrap();
    assert!(!solution.valid());
    assert!(!solution.pose.constraints.all());
    assert_eq!(solution.runs.len(), 5);
    assert!(solution.runs.iter().all(|r| !r.valid));
    assert!(safety.robot().within_limits(solution.joints()));
    assert!(solution.pose.objective.is_finite());
}

#[test]
fn same_inputs_give_identical_results() {
    let safety = safety();
    let grid = walled_grid();
    let config = PoseConfig {
        stop_at_valid: false,
        ..PoseConfig::default()
    };
    let target = wall_target(-0.2, 0.9);
    let a = PoseSelector::new(&safety, config.clone())
        .unwrap()
        .select(&grid, &target, &START)
        .unwrap();
    let b = PoseSelector::new(&safety, config)
        .unwrap()
        .select(&grid, &target, &START)
        .unwrap();
    assert_eq!(a, b);
    let far = Target::new(Point3::new(3.0, 0.0, 0.5), -Vector3::x()).unwrap();
    let selector = PoseSelector::new(&safety, PoseConfig::default()).unwrap();
    assert_eq!(
        selector.select(&grid, &far, &START).unwrap(),
        selector.select(&grid, &far, &START).unwrap()
    );
}

#[test]
fn bad_inputs_are_typed_errors() {
    let safety = safety();
    let grid = walled_grid();
    let selector = PoseSelector::new(&safety, PoseConfig::default()).unwrap();
    let target = wall_target(0.0, 0.5);

    let err = Target::new(Point3::new(Real::NAN, 0.0, 0.0), Vector3::x()).unwrap_err();
    assert!(
        matches!(
            err,
            PlanError::Target {
                field: "centre",
                ..
            }
        ),
        "{err}"
    );
    let err = Target::new(Point3::origin(), Vector3::zeros()).unwrap_err();
    assert!(
        matches!(
            err,
            PlanError::Target {
                field: "normal",
                ..
            }
        ),
        "{err}"
    );
    let err = Target::new(Point3::origin(), Vector3::new(Real::INFINITY, 0.0, 0.0)).unwrap_err();
    assert!(
        matches!(
            err,
            PlanError::Target {
                field: "normal",
                ..
            }
        ),
        "{err}"
    );
    // Built by hand past the constructor.
    let nan_centre = Target {
        centre: Point3::new(0.7, Real::NAN, 0.5),
        normal: -Vector3::x_axis(),
    };
    let err = selector.select(&grid, &nan_centre, &START).unwrap_err();
    assert!(
        matches!(
            err,
            PlanError::Target {
                field: "centre",
                ..
            }
        ),
        "{err}"
    );
    let not_unit = Target {
        centre: Point3::new(0.7, 0.0, 0.5),
        normal: UnitVector3::new_unchecked(Vector3::new(-2.0, 0.0, 0.0)),
    };
    let err = selector.evaluate(&grid, &not_unit, &START).unwrap_err();
    assert!(
        matches!(
            err,
            PlanError::Target {
                field: "normal",
                ..
            }
        ),
        "{err}"
    );

    let err = selector.select(&grid, &target, &START[..5]).unwrap_err();
    assert!(matches!(err, PlanError::Kinematics(_)), "{err}");
    let mut nan = START;
    nan[2] = Real::NAN;
    assert!(matches!(
        selector.select(&grid, &target, &nan).unwrap_err(),
        PlanError::Kinematics(_)
    ));
    assert!(selector.evaluate(&grid, &target, &[0.0; 7]).is_err());

    // A start outside the limits is clamped, not refused.
    let mut wide = START;
    wide[0] = 4.0;
    assert!(selector.select(&grid, &target, &wide).is_ok());

    // Configuration errors name the field.
    for (config, field) in [
        (
            PoseConfig {
                phi_max_deg: 0.0,
                ..PoseConfig::default()
            },
            "pose.phi_max_deg",
        ),
        (
            PoseConfig {
                d_max_m: 0.2,
                ..PoseConfig::default()
            },
            "pose.d_max_m",
        ),
        (
            PoseConfig {
                rho_scale_m: -1.0,
                ..PoseConfig::default()
            },
            "pose.rho_scale_m",
        ),
        (
            PoseConfig {
                starts: 0,
                ..PoseConfig::default()
            },
            "pose.starts",
        ),
        (
            PoseConfig {
                desired: [0.0, 0.0, Real::NAN, 0.0, 0.0, 0.0],
                ..PoseConfig::default()
            },
            "pose.desired",
        ),
        (
            PoseConfig {
                tilt_joint: 7,
                ..PoseConfig::default()
            },
            "pose.tilt_joint",
        ),
        (
            PoseConfig {
                difference_step_rad: 0.01,
                ..PoseConfig::default()
            },
            "pose.difference_step_rad",
        ),
    ] {
        let err = PoseSelector::new(&safety, config).unwrap_err();
        assert!(
            matches!(err, PlanError::Config { field: f, .. } if f == field),
            "{field}: {err}"
        );
    }
    // A robot without a scanner.
    let arm4 = robot::builtin("arm4").unwrap();
    let dof = arm4.dof();
    let arm4_safety = Safety::new(
        arm4,
        Isometry3::identity(),
        &PlanConfig::default(),
        vec![1.0; dof],
    )
    .unwrap();
    assert!(matches!(
        PoseSelector::new(&arm4_safety, PoseConfig::default()).unwrap_err(),
        PlanError::Robot { .. }
    ));
}

#[test]
fn config_reads_partial_files_and_refuses_unknown_fields() {
    let config: PoseConfig = serde_json::from_str(r#"{"phi_max_deg": 30.0}"#).unwrap();
    assert_eq!(
        config,
        PoseConfig {
            phi_max_deg: 30.0,
            ..PoseConfig::default()
        }
    );
    assert!(serde_json::from_str::<PoseConfig>(r#"{"phi_max": 30.0}"#).is_err());
    let d = PoseConfig::default();
    assert_eq!(
        (d.phi_max_deg, d.d_min_m, d.d_max_m, d.rho_min_m),
        (42.0, 0.25, 0.8, 0.015)
    );
    assert_eq!(
        (
            d.max_iterations,
            d.gradient_tolerance,
            d.tilt_joint,
            d.desired
        ),
        (50, 1e-4, 5, [0.0; 6])
    );
    d.validate().unwrap();
}

#[test]
fn target_from_a_disc() {
    let disc = map::Disc {
        centre: Point3::new(0.7, 0.1, 0.4),
        normal: -Vector3::x_axis(),
        radius_m: 0.04,
        points: 12,
    };
    let t = Target::from_disc(&disc);
    assert_eq!((t.centre, t.normal), (disc.centre, disc.normal));
    t.check().unwrap();
}

/// Issue 48: `starts` and `max_iterations` had no stated ceiling.
#[test]
fn pose_starts_and_iterations_have_ceilings() {
    for (config, field) in [
        (
            PoseConfig {
                starts: 1_000_000,
                ..PoseConfig::default()
            },
            "pose.starts",
        ),
        (
            PoseConfig {
                max_iterations: 1_000_000_000,
                ..PoseConfig::default()
            },
            "pose.max_iterations",
        ),
    ] {
        let e = config.validate().unwrap_err().to_string();
        assert!(e.contains(field), "{e}");
    }
    let most = PoseConfig {
        starts: plan::MAX_STARTS,
        max_iterations: plan::MAX_LM_ITERATIONS,
        ..PoseConfig::default()
    };
    assert!(most.validate().is_ok());
}
