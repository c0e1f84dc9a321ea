//! The occupancy grid: ray integration, region counts, H1 (A eq. 4.10–4.11)
//! with occlusion importance (A§4.2.1), H2 (A eq. 4.13–4.14), prediction rays,
//! bad input and determinism.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code may panic

use geom::{Isometry3, Point3, Real, Translation3, UnitQuaternion, Vector3, unit};
use map::traverse::segment_voxels;
use map::{
    MapError, OcclusionConfig, OccupancyConfig, OccupancyGrid, Region, RegionBox, RegionsConfig,
    VoxelKey, VoxelState,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use scene::{MaterialId, Scene, TriMesh, default_materials, primitives::cuboid};
use sensor::Sweep;
use sensor::{Scanner, ScannerConfig, SweepConfig};
use std::f64::consts::LN_2;

fn cube(c: Real, h: Real) -> RegionBox {
    RegionBox {
        min: [c - h; 3],
        max: [c + h; 3],
    }
}

/// Voxel 1 m; A3 = [−2, 2]³ (64 voxels), A2 = [−1, 1]³ (8), A1 = [0, 1]³ (1).
fn tiny_config() -> OccupancyConfig {
    OccupancyConfig {
        voxel_m: 1.0,
        regions: RegionsConfig {
            a1: RegionBox {
                min: [0.0; 3],
                max: [1.0; 3],
            },
            a2: cube(0.0, 1.0),
            a3: cube(0.0, 2.0),
        },
        weights: [0.6, 0.35, 0.05],
        occlusion: OcclusionConfig {
            enabled: false,
            ..OcclusionConfig::default()
        },
        free_misses_m: None,
    }
}

/// Every key of the grid.
fn all_keys(grid: &OccupancyGrid) -> Vec<VoxelKey> {
    let g = grid.geometry();
    let [x0, y0, z0] = g.key_min().coords();
    let [nx, ny, nz] = g.dims().map(|d| d as i32);
    let mut out = Vec::new();
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                out.push(VoxelKey::new(x0 + x, y0 + y, z0 + z));
            }
        }
    }
    out
}

fn count_state(grid: &OccupancyGrid, s: VoxelState) -> u64 {
    all_keys(grid)
        .into_iter()
        .filter(|k| grid.state(*k) == s)
        .count() as u64
}

#[test]
fn one_ray_frees_its_path_and_occupies_its_end() {
    let mut grid = OccupancyGrid::new(tiny_config()).unwrap();
    assert_eq!(grid.geometry().dims(), [4, 4, 4]);
    let (o, p) = (Point3::new(-1.5, 0.5, 0.5), Point3::new(1.5, 0.5, 0.5));
    let stats = grid.integrate_points(&[o], &[p]).unwrap();
    assert_eq!(stats.newly_known, 4);
    assert_eq!(stats.newly_occupied, 1);
    for x in -2..=0 {
        assert_eq!(grid.state(VoxelKey::new(x, 0, 0)), VoxelState::Free);
    }
    assert_eq!(grid.state(VoxelKey::new(1, 0, 0)), VoxelState::Occupied);
    assert_eq!(count_state(&grid, VoxelState::Unknown), 60);
    grid.check_invariants().unwrap();
    // Hand computation of eq. 4.10 / 4.11 (regions nested):
    // n_u,A1 = 1 − 1 = 0; n_u,A2 = 8 − 2 = 6; n_u,A3 = 64 − 4 = 60.
    assert_eq!(grid.counts(Region::A1).unknown, 0);
    assert_eq!(grid.counts(Region::A2).unknown, 6);
    assert_eq!(grid.counts(Region::A3).unknown, 60);
    assert_eq!(grid.h1_unweighted(), 60.0 * LN_2);
    let expect = (0.6 * 0.0 + 0.35 * 6.0 + 0.05 * 60.0) * LN_2;
    assert!(
        (grid.h1_weighted() - expect).abs() < 1e-12,
        "{}",
        grid.h1_weighted()
    );
}

#[test]
fn occupied_is_sticky_and_integration_is_order_independent() {
    let cfg = tiny_config();
    let hit = (Point3::new(-1.5, 0.5, 0.5), Point3::new(0.5, 0.5, 0.5));
    let through = (Point3::new(-1.5, 0.5, 0.5), Point3::new(1.5, 0.5, 0.5));
    let mut a = OccupancyGrid::new(cfg).unwrap();
    a.integrate_points(&[hit.0], &[hit.1]).unwrap();
    a.integrate_points(&[through.0], &[through.1]).unwrap();
    let mut b = OccupancyGrid::new(cfg).unwrap();
    b.integrate_points(&[through.0, hit.0], &[through.1, hit.1])
        .unwrap();
    // The later ray through (0, 0, 0) does not free it.
    assert_eq!(a.state(VoxelKey::new(0, 0, 0)), VoxelState::Occupied);
    for k in all_keys(&a) {
        assert_eq!(a.state(k), b.state(k), "{k}");
    }
    assert_eq!(a.counts(Region::A3), b.counts(Region::A3));
    a.check_invariants().unwrap();
    b.check_invariants().unwrap();
}

#[test]
fn grid_walk_matches_the_free_walk_and_clips_to_a3() {
    let cfg = OccupancyConfig {
        voxel_m: 0.25,
        ..tiny_config()
    };
    let mut grid = OccupancyGrid::new(cfg).unwrap();
    // Starts outside A3, ends inside: only the part inside is integrated.
    let (o, p) = (Point3::new(-3.0, -2.6, 0.3), Point3::new(1.1, 0.7, -0.4));
    grid.integrate_points(&[o], &[p]).unwrap();
    let walk = segment_voxels(&o, &p, 0.25);
    let inside: Vec<VoxelKey> = walk
        .iter()
        .copied()
        .filter(|k| grid.geometry().contains(*k))
        .collect();
    let (last, before) = inside.split_last().unwrap();
    assert_eq!(grid.state(*last), VoxelState::Occupied);
    for k in before {
        assert_eq!(grid.state(*k), VoxelState::Free, "{k}");
    }
    assert_eq!(count_state(&grid, VoxelState::Free), before.len() as u64);
    // A ray ending outside A3 frees its inside part and occupies nothing.
    let mut grid2 = OccupancyGrid::new(cfg).unwrap();
    grid2
        .integrate_points(&[Point3::new(0.1, 0.1, 0.1)], &[Point3::new(5.0, 0.1, 0.1)])
        .unwrap();
    assert_eq!(count_state(&grid2, VoxelState::Occupied), 0);
    assert_eq!(count_state(&grid2, VoxelState::Free), 8); // x cells 0..8
    grid.check_invariants().unwrap();
    grid2.check_invariants().unwrap();
}

/// A slab whose underside is the plane z = `z` (4 m × 4 m).
fn slab(z: Real, y_min: Real) -> TriMesh {
    cuboid(Point3::new(-2.0, y_min, z), Point3::new(2.0, 2.0, z + 0.05))
}

fn sweep_of(scene: &Scene, pose: &Isometry3, noise: bool, seed: u64) -> Sweep {
    let mut config = ScannerConfig::default();
    config.noise.enabled = noise;
    config.material_range_bias = noise;
    let scanner = Scanner::new(config).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    scanner
        .nodding_sweep(scene, pose, &SweepConfig::default(), &mut rng)
        .unwrap()
}

fn room_config(voxel_m: Real, occlusion: bool) -> OccupancyConfig {
    OccupancyConfig {
        voxel_m,
        regions: RegionsConfig::around([0.0, 0.0, 1.0], [0.8, 1.3, 2.2]),
        weights: [0.6, 0.35, 0.05],
        occlusion: OcclusionConfig {
            enabled: occlusion,
            ..OcclusionConfig::default()
        },
        free_misses_m: None,
    }
}

#[test]
fn misses_free_their_rays_up_to_the_set_range_and_no_farther() {
    // A slab at z = 1 over y ≥ 0 only: rays toward y < 0 return nothing.
    let scene =
        Scene::from_mesh("half", slab(1.0, 0.0), default_materials(), MaterialId(0)).unwrap();
    let sweep = sweep_of(&scene, &Isometry3::identity(), false, 2);
    let shape = sweep.grid_shape().unwrap();
    let misses = (shape.scans * shape.rays_per_scan) as usize - sweep.len();
    assert!(misses > 1000, "{misses}");
    let mut plain = OccupancyGrid::new(room_config(0.05, false)).unwrap();
    let mut freeing = OccupancyGrid::new(OccupancyConfig {
        free_misses_m: Some(1.5),
        ..room_config(0.05, false)
    })
    .unwrap();
    let a = plain.integrate_sweep(&sweep);
    let b = freeing.integrate_sweep(&sweep);
    assert_eq!(b.rays, a.rays + misses);
    freeing.check_invariants().unwrap();
    // Returns occupy the same voxels; misses only add free ones.
    for k in all_keys(&freeing) {
        let (p, f) = (plain.state(k), freeing.state(k));
        if p != VoxelState::Unknown {
            assert_eq!(p, f, "{k}");
        }
    }
    assert!(freeing.counts(Region::A3).free > plain.counts(Region::A3).free);
    // Along a missed ray (the scanner's frame is the world's: the centre ray is
    // +z, bearing θ goes toward −y sin θ): free to 1.5 m, unknown beyond.
    let bearing = 0.5f64; // toward y < 0, where nothing is.
    let dir = sensor::beam_direction(bearing);
    let key = |t: Real| freeing.key_of(&Point3::from(dir * t)).unwrap();
    assert_eq!(freeing.state(key(0.5)), VoxelState::Free);
    assert_eq!(freeing.state(key(1.4)), VoxelState::Free);
    assert_eq!(freeing.state(key(1.7)), VoxelState::Unknown);
    assert_eq!(plain.state(key(1.4)), VoxelState::Unknown);
    // A list without its grid cannot name its misses: nothing is freed.
    let mut listed = OccupancyGrid::new(OccupancyConfig {
        free_misses_m: Some(1.5),
        ..room_config(0.05, false)
    })
    .unwrap();
    listed.integrate_sweep(&sweep.without_grid());
    assert_eq!(listed.counts(Region::A3), plain.counts(Region::A3));
    // The range is checked.
    assert!(
        OccupancyGrid::new(OccupancyConfig {
            free_misses_m: Some(-1.0),
            ..room_config(0.05, false)
        })
        .is_err()
    );
}

#[test]
fn h1_unweighted_is_n_u_ln2_after_a_real_sweep() {
    let scene =
        Scene::from_mesh("slab", slab(1.0, -2.0), default_materials(), MaterialId(0)).unwrap();
    let sweep = sweep_of(&scene, &Isometry3::identity(), true, 1);
    let mut grid = OccupancyGrid::new(room_config(0.05, true)).unwrap();
    let stats = grid.integrate_sweep(&sweep);
    assert!(stats.rays > 40_000, "{}", stats.rays);
    grid.check_invariants().unwrap();
    let n_u = count_state(&grid, VoxelState::Unknown);
    assert_eq!(grid.h1_unweighted(), n_u as Real * LN_2);
    assert_eq!(
        count_state(&grid, VoxelState::Free) + count_state(&grid, VoxelState::Occupied) + n_u,
        grid.geometry().voxel_count() as u64
    );
    // The slab underside is occupied right above the scanner, free below.
    let at = |z: Real| grid.state(grid.key_of(&Point3::new(0.01, 0.01, z)).unwrap());
    assert_eq!(at(1.01), VoxelState::Occupied);
    assert_eq!(at(0.5), VoxelState::Free);
    assert_eq!(at(1.5), VoxelState::Unknown);
}

/// eq. 4.11 by brute force: each unknown voxel weighs the sum of the weights
/// of the regions holding it, times its importance.
fn h1_weighted_brute_force(grid: &OccupancyGrid, importance: Real) -> Real {
    let w = grid.config().weights;
    all_keys(grid)
        .into_iter()
        .filter(|k| grid.state(*k) == VoxelState::Unknown)
        .map(|k| {
            let region = grid.region_of(k).unwrap();
            let c: Real = w[region.index()..].iter().sum();
            let iota = if grid.is_important(k) {
                importance
            } else {
                1.0
            };
            c * iota
        })
        .sum::<Real>()
        * LN_2
}

#[test]
fn occlusion_importance_raises_voxels_between_points_across_a_range_jump() {
    // Two walls: a near one at z = 1 covering y ≥ 0 (rays with θ < 0), a far one
    // at z = 2 behind it. The scan plane is y–z; the sweep nods it about y.
    let mut mesh = slab(1.0, 0.0);
    let far = slab(2.0, -2.0);
    let n = mesh.vertices.len() as u32;
    mesh.vertices.extend(&far.vertices);
    mesh.triangles
        .extend(far.triangles.iter().map(|t| t.map(|v| v + n)));
    let scene = Scene::from_mesh("walls", mesh, default_materials(), MaterialId(0)).unwrap();
    let sweep = sweep_of(&scene, &Isometry3::identity(), false, 2);

    let mut plain = OccupancyGrid::new(room_config(0.05, false)).unwrap();
    let mut weighted = OccupancyGrid::new(room_config(0.05, true)).unwrap();
    plain.integrate_sweep(&sweep);
    let stats = weighted.integrate_sweep(&sweep);
    weighted.check_invariants().unwrap();
    assert!(stats.range_jumps > 100, "{}", stats.range_jumps);
    assert!(stats.newly_important > 50, "{}", stats.newly_important);

    // Same states either way; only the importance differs.
    let keys = all_keys(&weighted);
    for k in &keys {
        assert_eq!(plain.state(*k), weighted.state(*k));
    }
    // Flagged voxels are unknown and lie on a segment between the two points of
    // a jump: between the walls, behind the near wall's edge (y ≈ 0).
    let jumps = map::range_jumps(&sweep, &weighted.config().occlusion);
    let mut on_segments = std::collections::HashSet::new();
    for (p, q) in &jumps {
        on_segments.extend(segment_voxels(p, q, 0.05));
    }
    let flagged: Vec<VoxelKey> = keys
        .iter()
        .copied()
        .filter(|k| weighted.is_important(*k))
        .collect();
    assert_eq!(
        flagged.len() as u64,
        weighted.counts(Region::A3).important_unknown
    );
    for k in &flagged {
        assert_eq!(weighted.state(*k), VoxelState::Unknown);
        assert!(on_segments.contains(k), "{k}");
        let c = k.center(0.05);
        assert!(c.z > 0.95 && c.z < 2.05 && c.y.abs() < 0.2, "{c}");
    }
    // eq. 4.11 with importance, by brute force, and the rise over the plain map.
    let iota = weighted.config().occlusion.importance;
    let brute = h1_weighted_brute_force(&weighted, iota);
    assert!((weighted.h1_weighted() - brute).abs() < 1e-9 * brute);
    assert!(weighted.h1_weighted() > plain.h1_weighted());
    // The per-voxel term a prediction credits sums to the same H1.
    let per_voxel: Real = keys
        .iter()
        .filter(|k| weighted.state(**k) == VoxelState::Unknown)
        .map(|k| weighted.h1_weight(*k))
        .sum();
    assert!((per_voxel - weighted.h1_weighted()).abs() < 1e-9 * brute);
    // Slots are a dense one-to-one index of the voxels.
    let g = weighted.geometry();
    let mut slots: Vec<usize> = keys.iter().map(|k| g.slot_of(*k).unwrap()).collect();
    slots.sort_unstable();
    slots.dedup();
    assert_eq!(slots.len(), keys.len());
    assert!(*slots.last().unwrap() < g.slot_count());
    let rise: Real = flagged
        .iter()
        .map(|k| {
            let r = weighted.region_of(*k).unwrap();
            weighted.config().weights[r.index()..].iter().sum::<Real>() * (iota - 1.0)
        })
        .sum::<Real>()
        * LN_2;
    assert!((weighted.h1_weighted() - plain.h1_weighted() - rise).abs() < 1e-9 * brute);
    assert_eq!(weighted.h1_unweighted(), plain.h1_unweighted());
}

#[test]
fn range_jumps_use_both_grid_directions() {
    // Hand-built grid: 2 scans × 3 rays, ranges in metres.
    let bearings = vec![-0.1, 0.0, 0.1];
    let poses = vec![Isometry3::identity(), Isometry3::identity()];
    let r = |v: Real| Some(v);
    let ranges = vec![r(1.0), r(1.0), r(3.0), r(1.0), None, r(1.05)];
    let sweep = Sweep::from_range_grid(&bearings, &poses, &ranges).unwrap();
    // Rays 0.1 rad (5.7°) apart count as list neighbours; 0.2 rad do not.
    let occ = OcclusionConfig {
        range_jump_m: 0.1,
        list_neighbour_max_deg: 10.0,
        ..OcclusionConfig::default()
    };
    let jumps = map::range_jumps(&sweep, &occ);
    // Along scan 0: ray 1 → 2 (1 → 3). Across scans: ray 2 of scan 0 → 1 (3 → 1.05).
    let at = |scan, ray| sweep.points()[sweep.find(sensor::GridCell { scan, ray }).unwrap()].point;
    // The point of ray 2 in scan 0, by A eq. 4.7: 3·(0, −sin 0.1, cos 0.1).
    assert!((at(0, 2) - Point3::new(0.0, -3.0 * 0.1f64.sin(), 3.0 * 0.1f64.cos())).norm() < 1e-12);
    assert_eq!(jumps.len(), 2);
    assert_eq!(jumps[0], (at(0, 1), at(0, 2)));
    assert_eq!(jumps[1], (at(0, 2), at(1, 2)));

    // The same grid through a scan file keeps its grid, hence its jumps; the
    // same points without their cells lose the jump across scans.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("grid.ply");
    sweep.write_ply(&path).unwrap();
    let back = Sweep::read_ply(&path).unwrap();
    assert_eq!(map::range_jumps(&back, &occ).len(), 2);
    assert_eq!(map::range_jumps(&sweep.without_grid(), &occ).len(), 1);
}

#[test]
fn h2_sums_binary_entropy_of_half_p_over_unknown_voxels() {
    let mut grid = OccupancyGrid::new(tiny_config()).unwrap();
    grid.integrate_points(
        &[Point3::new(-1.5, 0.5, 0.5)],
        &[Point3::new(1.5, 0.5, 0.5)],
    )
    .unwrap();
    // Two unknown voxels, one free, one occupied.
    let unknown_a = VoxelKey::new(0, 1, 0);
    let unknown_b = VoxelKey::new(-2, -2, -2);
    let free = VoxelKey::new(0, 0, 0);
    let occupied = VoxelKey::new(1, 0, 0);
    grid.set_cspace_probabilities([
        (unknown_a, 0.5),
        (unknown_b, 1.0),
        (free, 0.8),
        (occupied, 0.9),
    ])
    .unwrap();
    // By hand: q = P/2; h = −q ln q − (1−q) ln(1−q).
    let h_a = -(0.25f64 * 0.25f64.ln()) - 0.75 * 0.75f64.ln(); // 0.562335…
    let h_b = LN_2;
    assert!((h_a - 0.562_335_144_618_808_4).abs() < 1e-12);
    assert!((grid.h2() - (h_a + h_b)).abs() < 1e-7, "{}", grid.h2());
    assert_eq!(grid.cspace_information(free), 0.0);
    assert!((grid.cspace_information(unknown_a) - h_a).abs() < 1e-7);
    // Bad values change nothing.
    let before = grid.h2();
    let err = grid
        .set_cspace_probabilities([(VoxelKey::new(-1, 1, 1), 0.3), (unknown_a, 1.5)])
        .unwrap_err();
    assert!(matches!(err, MapError::Probability { value, .. } if value == 1.5));
    assert!(matches!(
        grid.set_cspace_probability(VoxelKey::new(9, 0, 0), 0.5)
            .unwrap_err(),
        MapError::OutsideGrid { .. }
    ));
    assert_eq!(grid.h2(), before);
    assert_eq!(grid.cspace_probability(VoxelKey::new(-1, 1, 1)), 0.0);
    // Sensing an unknown voxel removes its C-space information.
    grid.integrate_points(&[Point3::new(0.5, 1.5, 0.5)], &[Point3::new(0.5, 1.5, 1.5)])
        .unwrap();
    assert_eq!(grid.state(unknown_a), VoxelState::Free);
    assert!((grid.h2() - h_b).abs() < 1e-7);
}

#[test]
fn prediction_ray_lists_unknown_voxels_until_an_occupied_one() {
    let mut grid = OccupancyGrid::new(tiny_config()).unwrap();
    // Free (−2..0, 0, 0), occupied (1, 0, 0).
    grid.integrate_points(
        &[Point3::new(-1.5, 0.5, 0.5)],
        &[Point3::new(1.5, 0.5, 0.5)],
    )
    .unwrap();
    let mut seen = Vec::new();
    let dir = unit(Vector3::new(1.0, 0.0, 0.0)).unwrap();
    let run = grid.cast_through_unknown(&Point3::new(-1.5, 0.5, 0.5), &dir, 10.0, |k| seen.push(k));
    assert_eq!(run.unknown, 0);
    assert_eq!(run.blocked_by, Some(VoxelKey::new(1, 0, 0)));
    // Along y = 1.5: all unknown to the grid's edge.
    seen.clear();
    let run = grid.cast_through_unknown(&Point3::new(-1.5, 1.5, 0.5), &dir, 10.0, |k| seen.push(k));
    assert_eq!(run.unknown, 4);
    assert_eq!(run.blocked_by, None);
    assert_eq!(
        seen,
        (-2..=1).map(|x| VoxelKey::new(x, 1, 0)).collect::<Vec<_>>()
    );
    // Limited by range.
    let run = grid.cast_through_unknown(&Point3::new(-1.5, 1.5, 0.5), &dir, 1.2, |_| {});
    assert_eq!(run.unknown, 2);
    // The slots given beside the keys, and the information table read by
    // them, agree with the per-key calls.
    let table = grid.information_by_slot();
    let mut slots = 0;
    grid.cast_through_unknown_slots(&Point3::new(-1.5, 1.5, 0.5), &dir, 10.0, |k, slot| {
        assert_eq!(grid.geometry().slot_of(k), Some(slot));
        assert_eq!(table[slot], [grid.h1_weight(k), grid.cspace_information(k)]);
        slots += 1;
    });
    assert_eq!(slots, 4);
    for k in all_keys(&grid) {
        let slot = grid.geometry().slot_of(k).unwrap();
        let expected = match grid.state(k) {
            VoxelState::Unknown => [grid.h1_weight(k), grid.cspace_information(k)],
            _ => [0.0, 0.0],
        };
        assert_eq!(table[slot], expected, "{k:?}");
    }
}

#[test]
fn bad_input_is_an_error_and_changes_nothing() {
    let mut grid = OccupancyGrid::new(tiny_config()).unwrap();
    grid.integrate_points(
        &[Point3::new(-1.5, 0.5, 0.5)],
        &[Point3::new(1.5, 0.5, 0.5)],
    )
    .unwrap();
    let before = grid.counts(Region::A3);
    let o = Point3::new(0.5, 0.5, 0.5);
    let nan = Point3::new(Real::NAN, 0.0, 0.0);
    let e = grid
        .integrate_points(&[o, o], &[Point3::new(1.5, 1.5, 1.5), nan])
        .unwrap_err();
    assert!(e.to_string().contains("point 1"), "{e}");
    let e = grid.integrate_points(&[o], &[o, o]).unwrap_err();
    assert!(e.to_string().contains("1 origins for 2 points"), "{e}");
    let e = grid.integrate_points(&[], &[]).unwrap_err();
    assert!(e.to_string().contains("no points"), "{e}");
    let e = grid.integrate_points(&[nan], &[o]).unwrap_err();
    assert!(e.to_string().contains("origin 0"), "{e}");
    assert_eq!(grid.counts(Region::A3), before);
    grid.check_invariants().unwrap();

    // Sweep grids are checked on construction.
    let id = Isometry3::identity();
    let e = Sweep::from_range_grid(&[0.0, 0.1], &[id], &[Some(1.0)]).unwrap_err();
    assert!(
        e.to_string()
            .contains("1 ranges given for 1 scans of 2 rays"),
        "{e}"
    );
    let e = Sweep::from_range_grid(&[0.0], &[id], &[Some(Real::NAN)]).unwrap_err();
    assert!(e.to_string().contains("scan 0, ray 0"), "{e}");
    let e = Sweep::from_range_grid(&[0.0], &[id], &[Some(-1.0)]).unwrap_err();
    assert!(e.to_string().contains("non-negative"), "{e}");
    let e = Sweep::from_range_grid(&[], &[], &[]).unwrap_err();
    assert!(e.to_string().contains("no bearings"), "{e}");
    // A scan that hit nothing is an empty sweep, and integrates to nothing.
    let empty = Sweep::from_range_grid(&[0.0], &[id], &[None]).unwrap();
    assert!(empty.is_empty());
    let before = grid.counts(Region::A3);
    assert_eq!(grid.integrate_sweep(&empty).rays, 0);
    assert_eq!(grid.counts(Region::A3), before);
    let bad_pose = Isometry3::from_parts(
        Translation3::new(Real::INFINITY, 0.0, 0.0),
        UnitQuaternion::identity(),
    );
    let e = Sweep::from_range_grid(&[0.0], &[bad_pose], &[Some(1.0)]).unwrap_err();
    assert!(e.to_string().contains("scan 0"), "{e}");

    // Configs are checked.
    let e = OccupancyGrid::new(OccupancyConfig {
        voxel_m: 0.0,
        ..tiny_config()
    })
    .unwrap_err();
    assert!(e.to_string().contains("occupancy.voxel_m"), "{e}");
    let mut nested = tiny_config();
    nested.regions.a1 = cube(0.0, 1.5);
    let e = OccupancyGrid::new(nested).unwrap_err();
    assert!(e.to_string().contains("regions.a1"), "{e}");
    let e = OccupancyGrid::new(OccupancyConfig {
        voxel_m: 1e-4,
        ..OccupancyConfig::default()
    })
    .unwrap_err();
    assert!(e.to_string().contains("2^32"), "{e}");
    assert!(grid.mark_free(VoxelKey::new(5, 0, 0)).is_err());
}

#[test]
fn mark_free_frees_unknown_and_keeps_occupied() {
    let mut grid = OccupancyGrid::new(tiny_config()).unwrap();
    grid.integrate_points(
        &[Point3::new(-1.5, 0.5, 0.5)],
        &[Point3::new(1.5, 0.5, 0.5)],
    )
    .unwrap();
    assert!(grid.mark_free(VoxelKey::new(1, 1, 1)).unwrap());
    assert!(!grid.mark_free(VoxelKey::new(1, 1, 1)).unwrap());
    assert!(!grid.mark_free(VoxelKey::new(1, 0, 0)).unwrap());
    assert_eq!(grid.state(VoxelKey::new(1, 0, 0)), VoxelState::Occupied);
    grid.check_invariants().unwrap();
}

#[test]
fn parallel_integration_is_deterministic() {
    let scene =
        Scene::from_mesh("slab", slab(1.0, -2.0), default_materials(), MaterialId(0)).unwrap();
    let pose = Isometry3::from_parts(
        Translation3::new(0.1, -0.2, 0.2),
        UnitQuaternion::from_euler_angles(0.3, -0.2, 0.4),
    );
    let sweep = sweep_of(&scene, &pose, true, 3);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut grid = OccupancyGrid::new(room_config(0.04, true)).unwrap();
            let stats = grid.integrate_sweep(&sweep);
            (grid, stats)
        })
    };
    let (a, sa) = run(1);
    let (b, sb) = run(2);
    assert_eq!(sa, sb);
    for r in Region::ALL {
        assert_eq!(a.counts(r), b.counts(r));
    }
    for k in all_keys(&a) {
        assert_eq!(a.state(k), b.state(k));
        assert_eq!(a.is_important(k), b.is_important(k));
    }
    assert_eq!(a.h1_weighted(), b.h1_weighted());
    a.check_invariants().unwrap();
}

#[test]
fn point_lists_recover_neighbours_along_a_scan() {
    // The same single scan as a grid and as a list: the along-scan jumps agree.
    let bearings: Vec<Real> = (0..5)
        .map(|i| (f64::from(i) - 2.0) * 0.36f64.to_radians())
        .collect();
    let ranges = vec![Some(1.0), Some(1.0), Some(2.0), Some(2.0), Some(1.0)];
    let sweep = Sweep::from_range_grid(&bearings, &[Isometry3::identity()], &ranges).unwrap();
    let (origins, points) = (sweep.origins(), sweep.positions());
    let cfg = room_config(0.05, true);
    let mut from_grid = OccupancyGrid::new(cfg).unwrap();
    let mut from_list = OccupancyGrid::new(cfg).unwrap();
    let sg = from_grid.integrate_sweep(&sweep);
    let sl = from_list.integrate_points(&origins, &points).unwrap();
    assert_eq!(sg.range_jumps, 2);
    assert_eq!(sl, sg);
    assert_eq!(from_grid.counts(Region::A3), from_list.counts(Region::A3));
    // Lists whose consecutive points are far apart in angle are not paired.
    let mut shuffled = OccupancyGrid::new(cfg).unwrap();
    let far = [points[0], Point3::new(0.0, 1.5, 0.5)];
    let s = shuffled.integrate_points(&[origins[0]; 2], &far).unwrap();
    assert_eq!(s.range_jumps, 0);
}
