//! The C-space model and the safety measure against second methods: brute
//! force over every voxel with `robot::Robot::min_algebraic_distance` (eq.
//! 3.5 written independently), eq. 4.13 recomputed voxel by voxel, and the
//! cache read back.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use geom::{Isometry3, Point3, Real};
use map::{OccupancyConfig, OccupancyGrid, RegionsConfig, VoxelKey, VoxelState};
use plan::{CacheOutcome, CspaceModel, PlanConfig, Safety, interfering_voxels};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const VOXEL: Real = 0.1;

fn vm6083() -> robot::Robot {
    robot::builtin("denso-vm6083").unwrap()
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

/// A grid with free space everywhere except unknown voxels where `unknown`
/// holds and one occupied slab (a wall at x ∈ [0.6, 0.7)).
fn explored_grid(unknown: impl Fn(&Point3) -> bool) -> OccupancyGrid {
    let mut g = grid();
    for k in keys(&g) {
        let c = k.center(VOXEL);
        if !unknown(&c) {
            g.mark_free(k).unwrap();
        }
    }
    // Occupy the wall by measuring it: rays from x = 0.3 ending in it.
    let mut origins = Vec::new();
    let mut points = Vec::new();
    for iy in -6..6 {
        for iz in 0..12 {
            let (y, z) = (0.05 + 0.1 * Real::from(iy), 0.05 + 0.1 * Real::from(iz));
            origins.push(Point3::new(0.35, y, z));
            points.push(Point3::new(0.65, y, z));
        }
    }
    g.integrate_points(&origins, &points).unwrap();
    g
}

fn random_q(robot: &robot::Robot, rng: &mut ChaCha8Rng) -> Vec<Real> {
    robot
        .limits()
        .iter()
        .map(|l| {
            let l = l.unwrap();
            rng.random_range(l.min..l.max)
        })
        .collect()
}

#[test]
fn dist_matches_brute_force_over_every_unsafe_voxel() {
    let robot = vm6083();
    let config = PlanConfig {
        safety_cap: 4.0,
        ..PlanConfig::default()
    };
    let safety = Safety::new(robot.clone(), Isometry3::identity(), &config, vec![1.0; 6]).unwrap();
    // Unknown: everything above z = 1.2 and a pocket near the base.
    let g = explored_grid(|c| c.z > 1.2 || (c - Point3::new(-0.4, 0.3, 0.3)).norm() < 0.2);
    let unsafe_centres: Vec<Point3> = keys(&g)
        .into_iter()
        .filter(|k| g.state(*k) != VoxelState::Free)
        .map(|k| k.center(VOXEL))
        .collect();
    assert!(keys(&g).iter().any(|k| g.state(*k) == VoxelState::Occupied));
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut below_one = 0;
    for _ in 0..40 {
        let q = random_q(&robot, &mut rng);
        let ours = safety.dist(&g, &q).unwrap();
        let brute = robot
            .min_algebraic_distance(&q, &unsafe_centres)
            .unwrap()
            .min(4.0);
        // Voxels beyond the grid count as unknown for `dist`; the grid
        // reaches 2.1 m from the shoulder, farther than twice any ellipsoid
        // radius from an arm of 1 m reach, so none is within the cap.
        assert!((ours - brute).abs() < 1e-9, "q {q:?}: {ours} vs {brute}");
        below_one += usize::from(ours <= 1.0);
    }
    // Both kinds of pose occur.
    assert!(below_one > 0 && below_one < 40, "{below_one}");
}

/// `dist` of one ellipsoid as eq. 3.5 is first written: every voxel of the
/// ellipsoid's bounding box (scaled to `bound`) scanned in z, y, x order,
/// the local coordinates stepped voxel by voxel along x, the first value at
/// or below `stop_at` returned.
fn dist_scanning_the_box(
    grid: &OccupancyGrid,
    e: &geom::Ellipsoid,
    bound: Real,
    stop_at: Real,
) -> Real {
    let v = grid.geometry().voxel_m();
    let reach = geom::Ellipsoid::new(e.pose, e.radii * bound.sqrt()).bounding_box();
    let (Some(lo), Some(hi)) = (
        VoxelKey::of_point(&reach.min, v),
        VoxelKey::of_point(&reach.max, v),
    ) else {
        return 0.0;
    };
    let (lo, hi) = (lo.coords(), hi.coords());
    let inv = e.pose.rotation.inverse();
    let scale = e.radii.map(|r| 1.0 / r);
    let step_x = (inv * geom::Vector3::new(v, 0.0, 0.0)).component_mul(&scale);
    let mut best = bound;
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            let first = VoxelKey::new(lo[0], y, z).center(v);
            let mut s =
                (inv * (first - Point3::from(e.pose.translation.vector))).component_mul(&scale);
            for x in lo[0]..=hi[0] {
                let d = s.norm_squared();
                if d < best && grid.state(VoxelKey::new(x, y, z)) != VoxelState::Free {
                    best = d;
                    if best <= stop_at {
                        return best;
                    }
                }
                s += step_x;
            }
        }
    }
    best
}

/// `Safety::ellipsoid_dist` looks only at the voxels that are not free, yet
/// gives the box scan's number to the bit, early stops included: the blast
/// plans and Stage Two's poses, found by LM on it, stay the same.
#[test]
fn ellipsoid_dist_equals_the_box_scan_to_the_bit() {
    let robot = vm6083();
    let config = PlanConfig {
        safety_cap: 4.0,
        ..PlanConfig::default()
    };
    let safety = Safety::new(robot.clone(), Isometry3::identity(), &config, vec![1.0; 6]).unwrap();
    let g = explored_grid(|c| c.z > 1.2 || (c - Point3::new(-0.4, 0.3, 0.3)).norm() < 0.2);
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let (mut compared, mut stopped) = (0, 0);
    for _ in 0..60 {
        let q = random_q(&robot, &mut rng);
        for (_, e) in safety.posed_links(&q).unwrap() {
            // Some ellipsoids also beyond the grid's edge (all unknown there).
            for shift in [0.0, 1.9] {
                let mut e = e;
                e.pose.translation.vector.x += shift;
                for (bound, stop_at) in [(4.0, Real::NEG_INFINITY), (4.0, 1.0), (2.0, 0.3)] {
                    let ours = safety.ellipsoid_dist(&g, &e, bound, stop_at);
                    let scan = dist_scanning_the_box(&g, &e, bound, stop_at);
                    assert_eq!(ours.to_bits(), scan.to_bits(), "q {q:?}: {ours} vs {scan}");
                    compared += 1;
                    stopped += usize::from(stop_at.is_finite() && ours <= stop_at);
                }
            }
        }
    }
    assert!(compared > 1000 && stopped > 10, "{compared} {stopped}");
}

#[test]
fn interfering_voxels_are_exactly_the_centres_inside_an_ellipsoid() {
    let robot = vm6083();
    let config = PlanConfig::default();
    let safety = Safety::new(robot.clone(), Isometry3::identity(), &config, vec![1.0; 6]).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let all = keys(&grid());
    for _ in 0..5 {
        let q = random_q(&robot, &mut rng);
        let ours = interfering_voxels(&safety, &q, VOXEL).unwrap();
        let mut brute: Vec<VoxelKey> = all
            .iter()
            .copied()
            .filter(|k| {
                robot
                    .min_algebraic_distance(&q, &[k.center(VOXEL)])
                    .unwrap()
                    < 1.0
            })
            .collect();
        brute.sort_unstable();
        assert_eq!(ours, brute);
        assert!(!ours.is_empty());
    }
}

#[test]
fn interference_probability_is_eq_4_13() {
    let robot = vm6083();
    let config = PlanConfig {
        n_q: 80,
        ..PlanConfig::default()
    };
    let model = CspaceModel::build(&robot, &Isometry3::identity(), VOXEL, &config).unwrap();
    let usage = model.usage();
    let total: Real = usage.iter().sum();
    // Recompute P(x_c) of sampled voxels from each node's own voxel list.
    let lists: Vec<Vec<VoxelKey>> = model
        .roadmap()
        .nodes()
        .map(|q| interfering_voxels(model.safety(), q, VOXEL).unwrap())
        .collect();
    let probs = &model.interference().probabilities;
    assert!(probs.len() > 100);
    for (k, p) in probs.iter().step_by(37) {
        let l: Real = lists
            .iter()
            .zip(usage)
            .filter(|(list, _)| list.binary_search(k).is_ok())
            .map(|(_, l)| l)
            .sum();
        assert!((p - l / total).abs() < 1e-12, "{k:?}: {p} vs {}", l / total);
    }
    // L sums to the mean number of nodes on a path: at least 2 (its ends).
    assert!(total >= 2.0, "{total}");
    // The interference counts agree with the lists.
    for (i, list) in lists.iter().enumerate() {
        assert_eq!(model.interference().voxels_per_node[i] as usize, list.len());
    }
}

#[test]
fn the_cache_round_trips_and_refuses_other_inputs() {
    let robot = vm6083();
    let config = PlanConfig {
        n_q: 50,
        ..PlanConfig::default()
    };
    let base = Isometry3::identity();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sub").join("cspace.json");
    let (built, outcome) =
        CspaceModel::load_or_build(&path, &robot, &base, VOXEL, &config).unwrap();
    assert!(matches!(outcome, CacheOutcome::Built(_)), "{outcome:?}");
    let (loaded, outcome) =
        CspaceModel::load_or_build(&path, &robot, &base, VOXEL, &config).unwrap();
    assert_eq!(outcome, CacheOutcome::Loaded);
    assert_eq!(loaded.roadmap().to_parts(), built.roadmap().to_parts());
    assert_eq!(loaded.usage(), built.usage());
    assert_eq!(loaded.interference(), built.interference());
    // Building again gives the same model (deterministic).
    let again = CspaceModel::build(&robot, &base, VOXEL, &config).unwrap();
    assert_eq!(again.interference(), built.interference());
    assert_eq!(again.usage(), built.usage());

    // Changed inputs invalidate the file.
    let other_seed = PlanConfig {
        seed: 1,
        ..config.clone()
    };
    let why = CspaceModel::load(&path, &robot, &base, VOXEL, &other_seed).unwrap_err();
    assert!(why.contains("other inputs"), "{why}");
    assert!(CspaceModel::load(&path, &robot, &base, 0.05, &config).is_err());
    let moved = Isometry3::translation(0.0, 0.0, 0.1);
    assert!(CspaceModel::load(&path, &robot, &moved, VOXEL, &config).is_err());
    let mut narrower = robot.clone();
    narrower.joints[0].limits = Some(robot::JointLimits::from_degrees(-90.0, 90.0));
    assert!(CspaceModel::load(&path, &narrower, &base, VOXEL, &config).is_err());

    // A damaged file is rebuilt over, saying why.
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, &text[..text.len() / 2]).unwrap();
    let (_, outcome) = CspaceModel::load_or_build(&path, &robot, &base, VOXEL, &config).unwrap();
    match outcome {
        CacheOutcome::Built(why) => assert!(why.contains("not a C-space cache"), "{why}"),
        CacheOutcome::Loaded => panic!("a truncated file was loaded"),
    }
    assert_eq!(
        CspaceModel::load_or_build(&path, &robot, &base, VOXEL, &config)
            .unwrap()
            .1,
        CacheOutcome::Loaded
    );
}

#[test]
fn planned_paths_pass_only_through_known_free_space() {
    let robot = vm6083();
    let config = PlanConfig {
        n_q: 400,
        ..PlanConfig::default()
    };
    let model = CspaceModel::build(&robot, &Isometry3::identity(), VOXEL, &config).unwrap();
    let safety = model.safety();
    // Known free everywhere but the wall at x ∈ [0.6, 0.7) and the unknown
    // space beyond it.
    let g = explored_grid(|c| c.x > 0.7);
    let map = model.roadmap();
    let safe: Vec<plan::NodeId> = map
        .node_ids()
        .filter(|&i| safety.dist(&g, map.node(i)).unwrap() > 1.0)
        .collect();
    assert!(safe.len() > 20, "{}", safe.len());
    let mut planned = 0;
    let mut refused_direct = 0;
    for pair in safe.chunks(2).take(12) {
        let [a, b] = pair else { continue };
        let (qa, qb) = (map.node(*a), map.node(*b));
        let direct_ok = safety.motion_dist(&g, qa, qb, 1.0).unwrap() > 1.0;
        let mut checker = safety.checker(&g);
        let Some(path) = map.plan(qa, qb, 10, &mut checker) else {
            continue;
        };
        planned += 1;
        refused_direct += usize::from(!direct_ok);
        assert_eq!(path.waypoints.len() == 2, direct_ok);
        // An independent check of every motion, at a finer step than the
        // planner's.
        let fine = Safety::new(
            robot.clone(),
            Isometry3::identity(),
            &PlanConfig {
                check_step_m: 0.005,
                ..config.clone()
            },
            map.weights().to_vec(),
        )
        .unwrap();
        for w in path.waypoints.windows(2) {
            let d = fine.motion_dist(&g, &w[0], &w[1], 0.0).unwrap();
            assert!(d > 0.95, "a motion comes to dist {d}");
        }
    }
    assert!(planned >= 6, "{planned}");
    assert!(refused_direct >= 1, "no pair needed the roadmap");
}

/// A voxel size whose interference search would not fit is refused before
/// the roadmap is built, with the estimate checked against the voxels a
/// node really interferes with.
#[test]
fn too_fine_a_planning_voxel_is_refused_up_front() {
    let robot = vm6083();
    let config = PlanConfig::default();
    let e = CspaceModel::build(&robot, &Isometry3::identity(), 0.001, &config).unwrap_err();
    let text = e.to_string();
    assert!(
        text.contains("planning_voxel_m") && text.contains("pairs"),
        "{text}"
    );
    // The estimate (ellipsoid volume over voxel volume) against the count
    // at 0.1 m, where the pairs are 1571 × the voxels a node interferes
    // with: within a factor of two.
    let safety = Safety::new(
        robot.clone(),
        Isometry3::identity(),
        &config,
        vec![1.0; robot.dof()],
    )
    .unwrap();
    let q = vec![0.0; robot.dof()];
    let volume: Real = safety
        .ellipsoids(&q)
        .unwrap()
        .iter()
        .map(geom::Ellipsoid::volume)
        .sum();
    let counted = interfering_voxels(&safety, &q, VOXEL).unwrap().len() as Real;
    let estimated = volume / VOXEL.powi(3);
    assert!(
        (0.5..2.0).contains(&(counted / estimated)),
        "{counted} voxels counted, {estimated} estimated"
    );
    // The default voxel is well inside the budget.
    assert!(estimated * 1571.0 < plan::MAX_INTERFERENCE_PAIRS / 100.0);
}

/// The checkers' answers together (in parallel) are their answers one by
/// one, with the same number of configurations checked; and a search whose
/// checker remembers, and so answers A*'s questions about a node's edges
/// together, finds the same paths as one asking one at a time.
#[test]
fn answers_together_are_the_answers_one_by_one() {
    use plan::{ClearanceChecker, MemoChecker, MotionChecker, PointClearance};
    let robot = vm6083();
    let config = PlanConfig {
        n_q: 400,
        ..PlanConfig::default()
    };
    let model = CspaceModel::build(&robot, &Isometry3::identity(), VOXEL, &config).unwrap();
    let safety = model.safety();
    let g = explored_grid(|c| c.x > 0.7);
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let qs: Vec<Vec<Real>> = (0..300).map(|_| random_q(&robot, &mut rng)).collect();
    let refs: Vec<&[Real]> = qs.iter().map(Vec::as_slice).collect();
    let motions: Vec<(&[Real], &[Real])> = refs.chunks(2).map(|p| (p[0], p[1])).collect();
    // Measured points on the wall's face, for the clearance.
    let mut points = PointClearance::new();
    let wall: Vec<Point3> = (0..400)
        .map(|k| {
            Point3::new(
                0.6,
                -1.0 + 0.005 * Real::from(k),
                0.2 + 0.003 * Real::from(k),
            )
        })
        .collect();
    points.insert(wall.iter());
    let (mut one, mut all) = (safety.checker(&g), safety.checker(&g));
    let each: Vec<bool> = refs.iter().map(|q| one.pose_ok(q)).collect();
    assert_eq!(all.poses_ok(&refs), each);
    assert!(each.iter().any(|&ok| ok) && each.iter().any(|&ok| !ok));
    let each: Vec<bool> = motions
        .iter()
        .map(|(a, b)| one.motion_may_be_ok(a, b))
        .collect();
    assert_eq!(all.motions_may_be_ok(&motions), each);
    assert!(each.iter().any(|&ok| ok) && each.iter().any(|&ok| !ok));
    assert_eq!(one.configurations_checked(), all.configurations_checked());
    let here = refs[0];
    let clearance = |c| ClearanceChecker::new(c, safety, &points, 0.1, here);
    let (mut one, mut all) = (clearance(safety.checker(&g)), clearance(safety.checker(&g)));
    let each: Vec<bool> = refs.iter().map(|q| one.pose_ok(q)).collect();
    assert_eq!(all.poses_ok(&refs), each);
    // Paths: the roadmap's nodes in pairs, safe or not.
    let map = model.roadmap();
    let mut memo = MemoChecker::new(clearance(safety.checker(&g)));
    let mut found = 0;
    for pair in map.node_ids().collect::<Vec<_>>().chunks(2).take(40) {
        let [a, b] = pair else { continue };
        let (qa, qb) = (map.node(*a), map.node(*b));
        let mut plain = clearance(safety.checker(&g));
        let expected = map.plan(qa, qb, 10, &mut plain);
        found += usize::from(expected.is_some());
        assert_eq!(map.plan(qa, qb, 10, &mut memo), expected);
    }
    // Some reached, some not (29 of 40).
    assert!((3..40).contains(&found), "{found}");
}

/// A pose is safe for the motion checker exactly when `dist(Q)` measured
/// up to the cap is above 1 (the checker resolves it only up to 1), on
/// poses on both sides of 1 and some close to it.
#[test]
fn a_safe_pose_is_one_whose_full_dist_is_above_one() {
    use plan::MotionChecker;
    let robot = vm6083();
    let config = PlanConfig::default();
    let safety = Safety::new(robot.clone(), Isometry3::identity(), &config, vec![1.0; 6]).unwrap();
    let g = explored_grid(|c| c.z > 1.2 || (c - Point3::new(-0.4, 0.3, 0.3)).norm() < 0.2);
    let mut checker = safety.checker(&g);
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let (mut safe, mut unsafe_, mut near) = (0, 0, 0);
    for _ in 0..400 {
        let q = random_q(&robot, &mut rng);
        let full = safety.dist(&g, &q).unwrap();
        assert_eq!(checker.pose_ok(&q), full > 1.0, "q {q:?}: dist {full}");
        if full > 1.0 {
            safe += 1;
        } else {
            unsafe_ += 1;
        }
        near += usize::from((0.8..1.5).contains(&full));
    }
    assert!(
        safe > 20 && unsafe_ > 20 && near > 5,
        "{safe} {unsafe_} {near}"
    );
}
