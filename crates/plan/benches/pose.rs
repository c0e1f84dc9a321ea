//! Stage Two pose selection (Paul §3.3.2; §6.3.2: ~100 ms for 20 LM
//! iterations; our target ≤ 5 ms per pose): a disc on a wall in front of the
//! VM-6083, a 0.1 m grid known free elsewhere.
//!
//! * `select` — the default selection: ten candidate starts by inverse
//!   kinematics, ranked, LM until the first valid result.
//! * `select_every_start` — LM from all five best-ranked starts.
//! * `lm_from_nearby` — one LM run alone from a valid pose with the base
//!   turned by 2° (the view misses the centre by ~2.5 cm).
//! * `lm_off_unknown` — one LM run alone from a valid pose made unsafe by an
//!   unexplored voxel just inside a forearm or wrist ellipsoid: `g₄` is
//!   active and the differences measure `dist(Q)` again.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use geom::{Isometry3, Point3, Real, Vector3};
use map::{OccupancyConfig, OccupancyGrid, RegionsConfig, VoxelKey};
use plan::{PlanConfig, PoseConfig, PoseSelector, Safety, Target};
use std::hint::black_box;

fn walled_grid() -> OccupancyGrid {
    walled_grid_with_unknown(None)
}

fn walled_grid_with_unknown(unknown: Option<VoxelKey>) -> OccupancyGrid {
    let mut g = OccupancyGrid::new(OccupancyConfig {
        voxel_m: 0.1,
        regions: RegionsConfig::around([0.0, 0.0, 0.475], [1.1, 1.6, 2.1]),
        ..OccupancyConfig::default()
    })
    .unwrap();
    let geometry = *g.geometry();
    let [nx, ny, nz] = geometry.dims();
    let k0 = geometry.key_min().coords();
    for z in 0..nz as i32 {
        for y in 0..ny as i32 {
            for x in 0..nx as i32 {
                let key = VoxelKey::new(k0[0] + x, k0[1] + y, k0[2] + z);
                if Some(key) != unknown {
                    g.mark_free(key).unwrap();
                }
            }
        }
    }
    let mut origins = Vec::new();
    let mut points = Vec::new();
    for iy in -8..8 {
        for iz in 0..14 {
            let (y, z) = (0.05 + 0.1 * Real::from(iy), 0.05 + 0.1 * Real::from(iz));
            origins.push(Point3::new(0.35, y, z));
            points.push(Point3::new(0.75, y, z));
        }
    }
    g.integrate_points(&origins, &points).unwrap();
    g
}

fn bench(c: &mut Criterion) {
    let robot = robot::builtin("denso-vm6083").unwrap();
    let safety = Safety::new(
        robot,
        Isometry3::identity(),
        &PlanConfig::default(),
        vec![1.0; 6],
    )
    .unwrap();
    let grid = walled_grid();
    let target = Target::new(Point3::new(0.7, 0.3, 0.8), -Vector3::x()).unwrap();
    let start = [0.0, 0.0, 1.57, 0.0, 1.0, 0.0];

    let default = PoseSelector::new(&safety, PoseConfig::default()).unwrap();
    let every = PoseSelector::new(
        &safety,
        PoseConfig {
            stop_at_valid: false,
            ..PoseConfig::default()
        },
    )
    .unwrap();
    let one = PoseSelector::new(
        &safety,
        PoseConfig {
            starts: 1,
            ..PoseConfig::default()
        },
    )
    .unwrap();
    let solution = default.select(&grid, &target, &start).unwrap();
    assert!(solution.valid());
    let mut nearby = solution.joints().to_vec();
    nearby[0] += 2f64.to_radians();
    let iterations =
        |s: &plan::PoseSolution| -> Vec<usize> { s.runs.iter().map(|r| r.iterations).collect() };
    let lm = one.select(&grid, &target, &nearby).unwrap();
    assert!(lm.valid());
    eprintln!(
        "LM iterations per run: select {:?}, select_every_start {:?}, lm_from_nearby {:?}",
        iterations(&solution),
        iterations(&every.select(&grid, &target, &start).unwrap()),
        iterations(&lm),
    );

    // A voxel just inside a forearm or wrist ellipsoid (links 3..) of a valid
    // pose, left unexplored.
    let other = Target::new(Point3::new(0.7, -0.2, 0.7), -Vector3::x()).unwrap();
    let q = default
        .select(&grid, &other, &start)
        .unwrap()
        .joints()
        .to_vec();
    let ellipsoids = safety.ellipsoids(&q).unwrap();
    let geometry = *grid.geometry();
    let [nx, ny, nz] = geometry.dims();
    let k0 = geometry.key_min().coords();
    let mut near = None;
    for z in 0..nz as i32 {
        for y in 0..ny as i32 {
            for x in 0..nx as i32 {
                let key = VoxelKey::new(k0[0] + x, k0[1] + y, k0[2] + z);
                let c = key.center(0.1);
                let d = ellipsoids[2..]
                    .iter()
                    .map(|e| e.algebraic_distance(&c))
                    .fold(Real::INFINITY, Real::min);
                if (0.6..0.95).contains(&d)
                    && grid.state(key) == map::VoxelState::Free
                    && near.is_none_or(|(_, best)| d > best)
                {
                    near = Some((key, d));
                }
            }
        }
    }
    let unknown_grid = walled_grid_with_unknown(near.map(|(k, _)| k));
    let off = one.select(&unknown_grid, &other, &q).unwrap();
    assert!(off.valid());
    eprintln!("LM iterations: lm_off_unknown {:?}", iterations(&off));

    let mut group = c.benchmark_group("pose");
    group.bench_function("select", |b| {
        b.iter(|| {
            default
                .select(black_box(&grid), black_box(&target), &start)
                .unwrap()
        });
    });
    group.bench_function("select_every_start", |b| {
        b.iter(|| {
            every
                .select(black_box(&grid), black_box(&target), &start)
                .unwrap()
        });
    });
    group.bench_function("lm_from_nearby", |b| {
        b.iter(|| {
            one.select(black_box(&grid), black_box(&target), &nearby)
                .unwrap()
        });
    });
    group.bench_function("lm_off_unknown", |b| {
        b.iter(|| {
            one.select(black_box(&unknown_grid), black_box(&other), &q)
                .unwrap()
        });
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
