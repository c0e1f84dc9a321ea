//! Paul's map pipeline end to end (A§5.1.1–5.3): nodding sweeps of bridge1
//! fused in the TSDF, Scale-Like Discs from the mesh vertices (the "fused mesh
//! map" SLDs are generated from, §5.2) oriented by the mesh's face normals,
//! and their segmentation, against the ground-truth scene.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use crate::sld_support as support;

use geom::{Point3, Real, Vector3};
use map::segment::{SegmentConfig, segment_discs, segment_of_disc};
use map::sld::{Orientation, SldConfig, SldResult, generate_discs, voxel_index};
use std::collections::{BTreeMap, HashSet};

struct MeshDiscs {
    world: scene::World,
    points: Vec<Point3>,
    faces: Vec<u32>,
    result: SldResult,
    truth: Vec<support::DiscTruth>,
}

/// Six sweeps fused at 10 mm, the mesh vertices of the robot's section of
/// the channel (|x| ≤ 1 m), their discs, and each disc's truth (the face of a
/// vertex is the closest scene face).
fn mesh_discs(noise: bool) -> MeshDiscs {
    let mut scanner = sensor::ScannerConfig::default();
    scanner.noise.enabled = noise;
    scanner.material_range_bias = noise;
    let (world, mesh) = support::tsdf_mesh_bridge1(scanner, 6, 0.01, 11);
    let normals = mesh.vertex_normals();
    let (points, normals): (Vec<Point3>, Vec<Vector3>) = mesh
        .vertices
        .iter()
        .zip(&normals)
        .filter(|(p, _)| p.x.abs() <= 1.0)
        .map(|(p, n)| (*p, *n))
        .unzip();
    let result = generate_discs(
        &points,
        Orientation::ReferenceNormals(&normals),
        &SldConfig::default(),
        1,
    )
    .unwrap();
    let scene = world.as_scene().unwrap();
    let faces = support::closest_faces(scene, &points, 0.2);
    let truth = support::disc_truths(scene, &points, &faces, &result.discs, &result.homes);
    MeshDiscs {
        world,
        points,
        faces,
        result,
        truth,
    }
}

#[test]
fn mesh_vertex_discs_register_everything_and_face_the_sensor() {
    for noise in [false, true] {
        let m = mesh_discs(noise);
        let r = &m.result;
        assert!(m.points.len() > 50_000, "{} vertices", m.points.len());
        assert!(
            r.registered_fraction() >= 0.99,
            "{}",
            r.registered_fraction()
        );
        let mut seen = HashSet::new();
        assert!(
            r.homes
                .iter()
                .all(|&h| seen.insert(voxel_index(&m.points[h as usize], 0.04).unwrap()))
        );
        let pure: Vec<Real> = m
            .truth
            .iter()
            .filter(|t| t.pure)
            .map(|t| t.error_deg)
            .collect();
        let within = pure.iter().filter(|e| **e <= 5.0).count() as Real / pure.len() as Real;
        let flipped = pure.iter().filter(|e| **e > 90.0).count();
        eprintln!(
            "noise {noise}: {} vertices, {} discs, registered {:.4}, {} pure, {:.3} within 5°, median {:.2}°, {flipped} flipped",
            m.points.len(),
            r.discs.len(),
            r.registered_fraction(),
            pure.len(),
            within,
            support::quantile(&pure, 0.5),
        );
        // The mesh's winding faces the sensors, so do the discs.
        assert!(flipped * 200 <= pure.len(), "{flipped} flipped");
        if noise {
            // 10 mm range noise survives fusion as mesh bumps of a few mm
            // (136 k vertices against 88 k noise-free): normals are
            // noise-limited, as on the raw cloud (see tests/sld.rs).
            assert!(support::quantile(&pure, 0.5) < 5.0);
        } else {
            // Noise-free, the TSDF's sub-voxel surface gives the faces'
            // normals: 99 % of pure discs within 5°.
            assert!(within >= 0.97, "{within} within 5°");
        }
    }
}

/// The roof and the top flanges' undersides 20 mm below it, through the
/// noisy pipeline: Paul's τp = 50 mm joins them (the step is below τp), and a
/// τp below the step, which the fused mesh's few-mm accuracy allows, parts
/// them.
#[test]
fn fused_mesh_segments_part_roof_and_flange_undersides_below_the_step() {
    let m = mesh_discs(true);
    let scene = m.world.as_scene().unwrap();
    let class: Vec<Option<&str>> = m
        .truth
        .iter()
        .zip(&m.result.homes)
        .map(|(t, &h)| {
            let face = m.faces[h as usize];
            let n = support::face_normal(scene, face);
            let offset =
                (n.dot(&scene.mesh().triangle(face as usize).a.coords) * 100.0).round() / 100.0;
            t.pure
                .then_some(match format!("{}@{offset}", t.group).as_str() {
                    "roof-z@-1.52" => Some("roof"),
                    "left_beam-z@-1.5" | "right_beam-z@-1.5" => Some("underside"),
                    _ => None,
                })
                .flatten()
        })
        .collect();
    // Segment holding most roof discs, and what else it holds.
    let roof_segment = |tau_p_m: Real| {
        let cfg = SegmentConfig {
            tau_p_m,
            ..SegmentConfig::default()
        };
        let segments = segment_discs(&m.result.discs, None, &cfg).unwrap();
        let of = segment_of_disc(&segments, m.result.discs.len());
        let mut count: BTreeMap<usize, usize> = BTreeMap::new();
        for (i, c) in class.iter().enumerate() {
            if *c == Some("roof") {
                *count.entry(of[i].unwrap()).or_default() += 1;
            }
        }
        let total: usize = count.values().sum();
        let (&seg, &n) = count.iter().max_by_key(|(_, n)| **n).unwrap();
        let undersides = segments[seg]
            .iter()
            .filter(|&&i| class[i.0] == Some("underside"))
            .count();
        (total, n, undersides)
    };
    let (total, n, undersides) = roof_segment(0.05);
    eprintln!(
        "τp 50 mm: roof segment holds {n} of {total} roof discs and {undersides} underside discs"
    );
    assert!(undersides >= 20);
    let (total, n, undersides) = roof_segment(0.002);
    eprintln!(
        "τp 2 mm: roof segment holds {n} of {total} roof discs and {undersides} underside discs"
    );
    assert!(n * 10 >= total * 8, "roof shattered: {n} of {total}");
    assert_eq!(undersides, 0);
}
