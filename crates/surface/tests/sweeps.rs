#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
//! Acceptance 1–2: scripted point3 sweeps of the built-in scenes, with and
//! without range noise, checked after every update; the final cube, block1 and
//! block2 models against the ground truth.

mod support;

use geom::{Point3, Real, Vector3};
use support::{Face, Sweep, faces, feed_checked, sweep_sets, table, world};
use surface::{SegmentId, SurfaceConfig, SurfaceModel};

const LAMBDA: Real = 0.05;

fn model_with_table() -> SurfaceModel {
    let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
    m.add_initial_segment(&table()).unwrap();
    m
}

fn run(scene: &str, sweep: &Sweep) -> SurfaceModel {
    let sets = sweep_sets(scene, sweep);
    assert!(sets.len() > 100, "{scene}: only {} sets", sets.len());
    let mut m = model_with_table();
    feed_checked(&mut m, &sets);
    m
}

/// A true plane of the scene: its faces (rectangles) grouped by plane.
struct TruePlane {
    normal: Vector3,
    offset: Real,
    rects: Vec<Face>,
}

fn true_planes(scene: &str) -> Vec<TruePlane> {
    let mut planes: Vec<TruePlane> = Vec::new();
    for f in faces(scene) {
        let n = f.normal().into_inner();
        let d = n.dot(&f.origin.coords);
        match planes
            .iter_mut()
            .find(|p| p.normal.dot(&n) > 0.999 && (p.offset - d).abs() < 1e-6)
        {
            Some(p) => p.rects.push(f),
            None => planes.push(TruePlane {
                normal: n,
                offset: d,
                rects: vec![f],
            }),
        }
    }
    planes
}

/// Sample points of a plane's true surface on a `step` grid.
fn samples(scene: &str, plane: &TruePlane, step: Real) -> Vec<Point3> {
    let w = world(scene);
    let mesh = w.as_scene().unwrap();
    let mut out = Vec::new();
    for f in &plane.rects {
        let (lu, lv) = (f.u.norm(), f.v.norm());
        let (nu, nv) = ((lu / step).ceil() as usize, (lv / step).ceil() as usize);
        for i in 0..=nu {
            for j in 0..=nv {
                let p = f.origin + f.u * (i as Real / nu as Real) + f.v * (j as Real / nv as Real);
                if mesh.closest_point(&p, 1e-6).is_some() {
                    out.push(p);
                }
            }
        }
    }
    out
}

/// The polygon segments modelling a true plane: normal within μ, centroid within λ.
fn polygons_of(m: &SurfaceModel, plane: &TruePlane) -> Vec<SegmentId> {
    let cos_mu = 10f64.to_radians().cos();
    m.segments()
        .filter(|s| !s.is_initial())
        .filter_map(|s| s.as_polygon().map(|p| (s.id(), p)))
        .filter(|(_, p)| {
            p.normal().dot(&plane.normal) > cos_mu
                && (plane.normal.dot(&p.centroid().coords) - plane.offset).abs() < LAMBDA
        })
        .map(|(id, _)| id)
        .collect()
}

/// How strictly a final model is judged.
#[derive(Clone, Copy, PartialEq)]
enum Judge {
    /// Acceptance 2: exactly one polygon per plane and no other polygon.
    Strict,
    /// Noisy sweeps: one dominant polygon per plane; other (small) polygons may
    /// remain but represent at most `max_stray` of the points.
    Noisy { max_stray: Real },
}

/// Acceptance 2 for a scene: one polygon per swept plane with normal within μ
/// and ≥ 95 % coverage within λ; shared edges between every two adjacent planes;
/// corner vertices where three planes meet; no other (redundant) polygon.
fn check_acceptance(scene: &str, m: &SurfaceModel, judge: Judge) {
    let planes = true_planes(scene);
    let mut owner: Vec<SegmentId> = Vec::new();
    for (k, plane) in planes.iter().enumerate() {
        let mut ids = polygons_of(m, plane);
        ids.sort_by_key(|id| std::cmp::Reverse(m.segment(*id).unwrap().points()));
        match judge {
            Judge::Strict => assert_eq!(
                ids.len(),
                1,
                "{scene}: plane {k} (n = {:?}) has polygons {ids:?}",
                plane.normal
            ),
            Judge::Noisy { .. } => assert!(!ids.is_empty(), "{scene}: plane {k} has no polygon"),
        }
        let p = m.polygon(ids[0]).unwrap();
        let angle = p
            .normal()
            .dot(&plane.normal)
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees();
        assert!(angle < 10.0, "{scene}: plane {k} normal off by {angle}°");
        let pts = samples(scene, plane, 0.02);
        let covered = pts
            .iter()
            .filter(|q| p.distance_to_point(q) < LAMBDA)
            .count();
        let frac = covered as Real / pts.len() as Real;
        assert!(
            frac >= 0.95,
            "{scene}: plane {k} covered {:.1} %",
            100.0 * frac
        );
        owner.push(ids[0]);
    }
    // No other ordinary polygon (or, noisy, few points in others).
    let others: Vec<_> = m
        .segments()
        .filter(|s| s.as_polygon().is_some() && !s.is_initial() && !owner.contains(&s.id()))
        .map(|s| (s.id(), s.points()))
        .collect();
    match judge {
        Judge::Strict => assert!(
            others.is_empty(),
            "{scene}: redundant polygons left: {others:?}"
        ),
        Judge::Noisy { max_stray } => {
            let stray: u64 = others.iter().map(|o| o.1).sum::<u64>()
                + m.segments()
                    .filter(|s| s.as_point().is_some())
                    .map(surface::Segment::points)
                    .sum::<u64>();
            let frac = stray as Real / m.points_fed() as Real;
            println!(
                "{scene}: {} stray polygons with {:.2} % of the points",
                others.len(),
                100.0 * frac
            );
            assert!(
                frac <= max_stray,
                "{scene}: {:.2} % of the points in stray segments",
                100.0 * frac
            );
        }
    }
    // Adjacent planes (their rectangles touch along more than 0.1 m) share edges.
    let w = world(scene);
    let mesh = w.as_scene().unwrap();
    for (a, pa) in planes.iter().enumerate() {
        for (b, pb) in planes.iter().enumerate().skip(a + 1) {
            if pa.normal.dot(&pb.normal).abs() > 0.999 {
                continue;
            }
            let line_len = touching_length(pa, pb, mesh);
            if line_len < 0.1 {
                continue;
            }
            let sa = m.polygon(owner[a]).unwrap();
            assert!(
                sa.neighbours().contains(&owner[b]),
                "{scene}: planes {a} and {b} meet along {line_len:.2} m but their polygons share no edge"
            );
        }
    }
    // Corners where three planes meet: every polygon of the three has a corner
    // vertex there (noisy: at least half of them).
    let (mut expected, mut found) = (0usize, 0usize);
    let mut missing = Vec::new();
    for (a, pa) in planes.iter().enumerate() {
        for (b, pb) in planes.iter().enumerate().skip(a + 1) {
            for (c, pc) in planes.iter().enumerate().skip(b + 1) {
                let Some(x) = three_planes(pa, pb, pc) else {
                    continue;
                };
                if [pa, pb, pc].iter().any(|p| !on_surface(p, &x, mesh)) {
                    continue;
                }
                for k in [a, b, c] {
                    let p = m.polygon(owner[k]).unwrap();
                    let near = p
                        .nodes()
                        .iter()
                        .any(|n| n.corner.is_some() && (n.position - x).norm() < LAMBDA);
                    expected += 1;
                    if near {
                        found += 1;
                    } else {
                        missing.push(format!(
                            "plane {k} at {:.3?} (planes {a}, {b}, {c})",
                            x.coords.as_slice()
                        ));
                    }
                }
            }
        }
    }
    println!("{scene}: {found} of {expected} corner vertices");
    match judge {
        Judge::Strict => assert!(
            missing.is_empty(),
            "{scene}: no corner vertex of {missing:?}"
        ),
        Judge::Noisy { .. } => assert!(
            2 * found >= expected,
            "{scene}: corner vertices missing: {missing:?}"
        ),
    }
}

fn on_surface(p: &TruePlane, x: &Point3, mesh: &scene::Scene) -> bool {
    (p.normal.dot(&x.coords) - p.offset).abs() < 1e-6
        && p.rects.iter().any(|f| {
            let d = x - f.origin;
            let (lu, lv) = (f.u.norm(), f.v.norm());
            let (a, b) = (d.dot(&f.u) / lu, d.dot(&f.v) / lv);
            a > -1e-6 && a < lu + 1e-6 && b > -1e-6 && b < lv + 1e-6
        })
        && mesh.closest_point(x, 1e-6).is_some()
}

fn three_planes(a: &TruePlane, b: &TruePlane, c: &TruePlane) -> Option<Point3> {
    let m = nalgebra::Matrix3::from_rows(&[
        a.normal.transpose(),
        b.normal.transpose(),
        c.normal.transpose(),
    ]);
    let x = m.try_inverse()? * Vector3::new(a.offset, b.offset, c.offset);
    Some(Point3::from(x))
}

/// Length along which two planes' true regions touch.
fn touching_length(a: &TruePlane, b: &TruePlane, mesh: &scene::Scene) -> Real {
    let Some(dir) = geom::unit(a.normal.cross(&b.normal)) else {
        return 0.0;
    };
    let mut count = 0;
    let step = 0.01;
    for f in &a.rects {
        for (o, e) in [
            (f.origin, f.u),
            (f.origin, f.v),
            (f.origin + f.u, f.v),
            (f.origin + f.v, f.u),
        ] {
            if (e.dot(&dir) / e.norm()).abs() < 0.999 {
                continue;
            }
            let n = (e.norm() / step) as usize;
            for i in 0..n {
                let x = o + e * ((i as Real + 0.5) / n as Real);
                if on_surface(b, &x, mesh) && on_surface(a, &x, mesh) {
                    count += 1;
                }
            }
        }
    }
    count as Real * step
}

fn noisy() -> Sweep {
    Sweep {
        noise_sigma: LAMBDA / 5.0,
        seed: 7,
        ..Sweep::default()
    }
}

#[test]
fn cube_sweep() {
    let m = run("cube", &Sweep::default());
    check_acceptance("cube", &m, Judge::Strict);
    let st = m.stats();
    assert_eq!(st.corner_vertices, 12);
}

#[test]
fn cube_sweep_noisy() {
    let m = run("cube", &noisy());
    check_acceptance("cube", &m, Judge::Noisy { max_stray: 0.02 });
}

#[test]
fn block1_sweep() {
    let m = run("block1", &Sweep::default());
    check_acceptance("block1", &m, Judge::Strict);
}

#[test]
fn block1_sweep_noisy() {
    let m = run("block1", &noisy());
    check_acceptance("block1", &m, Judge::Noisy { max_stray: 0.02 });
}

#[test]
fn block2_sweep() {
    let m = run("block2", &Sweep::default());
    check_acceptance("block2", &m, Judge::Strict);
}

#[test]
fn block2_sweep_noisy() {
    let m = run("block2", &noisy());
    check_acceptance("block2", &m, Judge::Noisy { max_stray: 0.02 });
}

#[test]
fn cylinder_sweep() {
    let m = run("cylinder", &Sweep::default());
    assert!(m.stats().polygons > 5);
}

#[test]
fn cylinder_sweep_noisy() {
    let m = run("cylinder", &noisy());
    assert!(m.stats().polygons > 5);
}

/// More sweeps (other seeds, noise levels and steps), invariants only. Run with
/// `cargo test -p surface --release --test sweeps -- --ignored`.
#[test]
#[ignore = "long: extra seeds and steps"]
fn stress_sweeps() {
    for scene in ["cube", "block1", "block2", "cylinder"] {
        for (seed, noise, step) in [
            (2, 0.01, 0.035),
            (3, 0.005, 0.035),
            (4, 0.01, 0.045),
            (5, 0.002, 0.03),
        ] {
            let sweep = Sweep {
                noise_sigma: noise,
                seed,
                step,
                ..Sweep::default()
            };
            let m = run(scene, &sweep);
            println!(
                "{scene} seed {seed} noise {noise} step {step}: {:?}",
                m.stats()
            );
        }
    }
}
