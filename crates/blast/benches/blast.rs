//! Issue 11, acceptance 2: `plan-blast` for one segment of 500 discs in
//! ≤ 2 s (Paul's system needed minutes). The workload is
//! [`blast::plan_blast`], what `surveyor plan-blast` runs: a
//! nozzle pose for every disc (App. A.1) and the segment's order by nearest
//! neighbour, 2-opt and the GA (App. A.2).
//!
//! The segment: 500 discs (25 × 20, 4 cm apart) on the underside of a roof
//! at z = 1.52 m above the VM-6083, as bridge1's deck, x ∈ [−0.48, 0.48],
//! y ∈ [−0.38, 0.38]; a 0.1 m grid, occupied in the roof's layer and free
//! elsewhere; every disc's LM starts from bridge1's start pose (the scanner
//! pointing up at the roof).
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use blast::{BlastConfig, BlastInputs, plan_blast};
use criterion::{Criterion, criterion_group, criterion_main};
use geom::{Isometry3, Point3, Real, UnitVector3, Vector3};
use map::{OccupancyConfig, OccupancyGrid, RegionBox, RegionsConfig, VoxelKey};
use std::hint::black_box;

fn roof_segment() -> BlastInputs {
    let mut grid = OccupancyGrid::new(OccupancyConfig {
        voxel_m: 0.1,
        regions: RegionsConfig::around([0.0, 0.0, 0.475], [1.1, 1.6, 2.1]),
        ..OccupancyConfig::default()
    })
    .unwrap();
    let g = *grid.geometry();
    let [nx, ny, nz] = g.dims();
    let k0 = g.key_min().coords();
    let (mut origins, mut points) = (Vec::new(), Vec::new());
    for z in 0..nz as i32 {
        for y in 0..ny as i32 {
            for x in 0..nx as i32 {
                let key = VoxelKey::new(k0[0] + x, k0[1] + y, k0[2] + z);
                let c = key.center(0.1);
                if (1.5..1.6).contains(&c.z) {
                    origins.push(c + Vector3::new(0.01, 0.0, 0.0));
                    points.push(c);
                } else {
                    grid.mark_free(key).unwrap();
                }
            }
        }
    }
    grid.integrate_points(&origins, &points).unwrap();
    let mut discs = Vec::new();
    for i in 0..25 {
        for j in 0..20 {
            discs.push(map::Disc {
                centre: Point3::new(
                    -0.48 + 0.04 * Real::from(i),
                    -0.38 + 0.04 * Real::from(j),
                    1.52,
                ),
                normal: UnitVector3::new_normalize(-Vector3::z()),
                radius_m: 0.02,
                points: 20,
            });
        }
    }
    let start: Vec<Real> = [0.0, -55.0, 165.0, 0.0, -110.0, 0.0]
        .iter()
        .map(|d: &Real| d.to_radians())
        .collect();
    let n = discs.len();
    BlastInputs::new(
        discs,
        vec![start; n],
        vec![(0..n).map(map::DiscId).collect()],
        grid,
        "roof segment",
    )
    .unwrap()
}

fn bench(c: &mut Criterion) {
    let robot = robot::builtin("denso-vm6083").unwrap();
    let inputs = roof_segment();
    let a2 = RegionBox {
        min: [-2.0, -2.0, -1.0],
        max: [2.0, 2.0, 3.0],
    };
    let config = BlastConfig::default();
    let plan = plan_blast(&inputs, &robot, Isometry3::identity(), &a2, &config).unwrap();
    let s = &plan.segments[0];
    eprintln!(
        "roof segment: {} of {} discs with a pose; path cost nearest neighbour {:.2}, 2-opt {:.2}, GA {:.2}",
        plan.discs_with_pose,
        plan.discs_in_scope,
        s.cost_nearest_neighbour,
        s.cost_two_opt,
        s.cost_ga
    );
    let mut group = c.benchmark_group("blast");
    group.sample_size(10);
    group.bench_function("plan_blast_500_discs", |b| {
        b.iter(|| {
            black_box(
                plan_blast(
                    black_box(&inputs),
                    &robot,
                    Isometry3::identity(),
                    &a2,
                    &config,
                )
                .unwrap(),
            )
        });
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
