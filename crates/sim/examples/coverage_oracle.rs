//! An upper bound on what Stage One's viewpoint choice can cover: the A1
//! coverage (SPEC §6) reached by choosing each next sweep *knowing the true
//! scene*, greedily (the pose whose simulated sweep covers the most samples
//! not yet covered), among the start pose and the C-space model's roadmap
//! nodes, the same pool Stage One chooses from (less its local candidates).
//!
//! `cargo run --release -p sim --example coverage_oracle -- [SCENARIO] [SWEEPS] [EXTRA]`
//! (default `bridge1 12 0`; `SWEEPS` counts the start pose's sweep, as
//! `surveyor explore` counts viewpoints; `EXTRA` more poses drawn uniformly
//! within the joint limits join the pool, seeded, to see how much a denser
//! pool would add).
//!
//! A pose counts when its links and its whole tilt sweep are clear of the
//! scene, under two rules printed side by side: *contact*, the links' collision
//! shapes touch no true surface; *ellipsoid*, the thesis' `dist(Q) > 1`
//! (eq. 3.5) against the centres of the planning voxels that hold a true
//! surface, with no voxel unknown: the planner with a perfect map. The noise
//! of each sweep is seeded by the pose's index, as a run's is by the viewpoint.

use explore::Setup;
use geom::{Isometry3, Real};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use map::VoxelKey;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use robot::Robot;
use scene::World;
use sim::explore_job::{ExploreOptions, explore_setup};
use std::collections::HashSet;
use std::sync::Arc;

/// Tilt step at which a sweep's configurations are checked, degrees.
const CHECK_TILT_DEG: Real = 2.0;

/// Density of the true-surface points that mark planning voxels occupied.
const VOXEL_MARK_PER_M2: Real = 10_000.0;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("bridge1", String::as_str);
    let sweeps: usize = args.get(1).map_or(Ok(12), |s| s.parse())?;
    let extra: usize = args.get(2).map_or(Ok(0), |s| s.parse())?;
    let loaded = scenario::Scenario::load(name)?;
    // One cache file per scenario, named after it (a path's separators too).
    let stem: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let (setup, world) = explore_setup(
        &loaded,
        &ExploreOptions {
            cspace_cache: Some(std::env::temp_dir().join(format!("surveyor-oracle-{stem}.json"))),
            ..ExploreOptions::default()
        },
    )?;
    let scene = world
        .as_scene()
        .ok_or("the oracle needs a scene with true surfaces")?;

    // The A1 samples of SPEC §6, as `surveyor explore` scores them.
    let mut metrics = loaded.scenario.metrics;
    metrics.sampling.region = Some(setup.regions.a1.aabb());
    let samples: Vec<[Real; 3]> = scene::SurfaceSampler::new(scene, &metrics.sampling)?
        .flatten()
        .map(|s| [s.point.x, s.point.y, s.point.z])
        .collect();
    let tree: ImmutableKdTree<Real, 3> = ImmutableKdTree::new_from_slice(&samples);
    let r2 = metrics.covered_within_m.powi(2);

    // The planning voxels a true surface passes through (in A3).
    let voxel = setup.config.planning_voxel_m;
    let mut marks = metrics.sampling;
    marks.region = Some(setup.regions.a3.aabb());
    marks.samples_per_m2 = VOXEL_MARK_PER_M2;
    marks.exposed_only = false;
    let occupied: HashSet<VoxelKey> = scene::SurfaceSampler::new(scene, &marks)?
        .flatten()
        .filter_map(|s| VoxelKey::of_point(&s.point, voxel))
        .collect();

    let robot = &setup.robot;
    let world_from_base = setup.world_from_base;
    let safety = setup.stage.model().safety();
    let scanner = loaded.scenario.scanner.clone().unwrap_or_default().config;
    let mut poses: Vec<Vec<Real>> = vec![setup.start.clone()];
    poses.extend(setup.stage.model().roadmap().nodes().map(<[Real]>::to_vec));
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let limits = robot.limits();
    for _ in 0..extra {
        poses.push(
            limits
                .iter()
                .map(|l| l.map_or(0.0, |l| rng.random_range(l.min..=l.max)))
                .collect(),
        );
    }
    let words = samples.len().div_ceil(64);

    // Per pose: (clear by contact, clear by ellipsoid, samples its sweep covers).
    let per_pose: Vec<(bool, bool, Vec<u64>)> = poses
        .par_iter()
        .enumerate()
        .map(|(i, q)| -> Result<_, String> {
            let checks = sweep_configurations(&setup, q);
            let mut contact = true;
            let mut ellipsoid = true;
            for c in &checks {
                let frames = robot.forward_kinematics(c).map_err(|e| e.to_string())?;
                contact &= plan::contact::robot_contacts(robot, &frames, &world_from_base, scene)
                    .is_empty();
                ellipsoid &= plan::interfering_voxels(safety, c, voxel)
                    .map_err(|e| e.to_string())?
                    .iter()
                    .all(|k| !occupied.contains(k));
            }
            let mut bits = vec![0u64; words];
            // The start's sweep is taken whatever the rules say (a run takes it).
            if i == 0 || contact || ellipsoid {
                let points =
                    simulated_sweep(&setup, &world, robot, &world_from_base, &scanner, q, i)?;
                for p in points {
                    for n in tree.within_unsorted::<SquaredEuclidean>(&[p.x, p.y, p.z], r2) {
                        let k = n.item as usize;
                        bits[k / 64] |= 1 << (k % 64);
                    }
                }
            }
            Ok((contact, ellipsoid, bits))
        })
        .collect::<Result<_, _>>()?;

    let n = samples.len() as Real;
    let pct = |covered: usize| 100.0 * covered as Real / n;
    println!(
        "{name}: {} A1 samples; {} poses (start, roadmap nodes, {extra} more)",
        samples.len(),
        poses.len()
    );
    for (rule, pick) in [("contact", 0usize), ("ellipsoid", 1)] {
        let clear: Vec<usize> = (0..poses.len())
            .filter(|&i| {
                if pick == 0 {
                    per_pose[i].0
                } else {
                    per_pose[i].1
                }
            })
            .collect();
        let mut all = per_pose[0].2.clone();
        for &i in &clear {
            or_into(&mut all, &per_pose[i].2);
        }
        println!(
            "\n{rule} rule: {} poses clear with their sweep{}; all of their sweeps and the start's together cover {:.1} %",
            clear.len(),
            if clear.first() == Some(&0) {
                ""
            } else {
                " (the start pose is not)"
            },
            pct(count(&all))
        );
        let mut have = per_pose[0].2.clone();
        print!("greedy, sweeps 1..={sweeps}:  {:.1}", pct(count(&have)));
        for _ in 1..sweeps {
            let Some((best, gain)) = clear
                .par_iter()
                .map(|&i| (i, gain(&per_pose[i].2, &have)))
                .max_by_key(|&(i, g)| (g, std::cmp::Reverse(i)))
            else {
                break;
            };
            if gain == 0 {
                break;
            }
            or_into(&mut have, &per_pose[best].2);
            print!(" {:.1}", pct(count(&have)));
        }
        println!(" %");
        // No start sweep plus `sweeps - 1` poses of the pool cover more than
        // the greedy set plus the `sweeps - 1` largest gains over it
        // (coverage is submodular), nor more than all of them together.
        let mut gains: Vec<usize> = clear.iter().map(|&i| gain(&per_pose[i].2, &have)).collect();
        gains.sort_unstable_by(|a, b| b.cmp(a));
        let bound = (count(&have) + gains.iter().take(sweeps.saturating_sub(1)).sum::<usize>())
            .min(count(&all));
        println!(
            "no {sweeps} sweeps of these poses cover more than {:.1} %",
            pct(bound)
        );
    }
    Ok(())
}

/// The configurations of the tilt sweep from `q`: every `CHECK_TILT_DEG` of
/// the sweep joint's range, ends included, and `q` itself.
fn sweep_configurations(setup: &Setup, q: &[Real]) -> Vec<Vec<Real>> {
    let (lo, hi) = setup.stage.sweep_range(q);
    let j = setup.config.sweep.joint - 1;
    let steps = ((hi[j] - lo[j]) / CHECK_TILT_DEG.to_radians())
        .ceil()
        .max(1.0) as usize;
    let mut out = vec![q.to_vec()];
    for s in 0..=steps {
        let mut c = lo.clone();
        c[j] = lo[j] + (hi[j] - lo[j]) * s as Real / steps as Real;
        out.push(c);
    }
    out
}

/// The points of the sweep from `q`, simulated with noise seeded by `seed`.
fn simulated_sweep(
    setup: &Setup,
    world: &Arc<World>,
    robot: &Robot,
    world_from_base: &Isometry3,
    scanner: &sensor::ScannerConfig,
    q: &[Real],
    seed: usize,
) -> Result<Vec<geom::Point3>, String> {
    let scanner = sensor::Scanner::new(*scanner).map_err(|e| e.to_string())?;
    let mut rig = sim::SimRig::new(
        robot.clone(),
        Arc::clone(world),
        *world_from_base,
        q,
        Some(scanner),
        seed as u64,
    )
    .map_err(|e| e.to_string())?;
    let sweep = hw::tilt_sweep(
        &mut rig,
        robot,
        world_from_base,
        &setup.config.sweep,
        &mut |_, _| {},
    )
    .map_err(|e| e.to_string())?;
    Ok(sweep.positions())
}

fn count(bits: &[u64]) -> usize {
    bits.iter().map(|w| w.count_ones() as usize).sum()
}

fn gain(bits: &[u64], have: &[u64]) -> usize {
    bits.iter()
        .zip(have)
        .map(|(a, b)| (a & !b).count_ones() as usize)
        .sum()
}

fn or_into(into: &mut [u64], bits: &[u64]) {
    for (a, b) in into.iter_mut().zip(bits) {
        *a |= b;
    }
}
