//! Real third-party data as worlds: meshes are scanned by the VM-6083, clouds
//! are ray-cast by the ε rule (P§4.2) from their own sensor's viewpoint.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use geom::{Point3, Ray, Real, Vector3, unit};
use scene::{RayCast, World};
use sim::scan_job::{ScanSetup, world_from_file};
use std::path::PathBuf;

fn data(rel: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/")).join(rel)
}

/// Rays from `origin` in a cone of half-angle `half_deg` around `axis`, on a grid.
fn fan(origin: Point3, axis: Vector3, half_deg: Real, n: usize) -> Vec<Ray> {
    let axis = unit(axis).unwrap();
    let u = geom::math::any_perpendicular(&axis);
    let v = axis.cross(&u);
    let t = half_deg.to_radians().tan();
    let mut rays = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let a = t * (2.0 * i as Real / (n - 1) as Real - 1.0);
            let b = t * (2.0 * j as Real / (n - 1) as Real - 1.0);
            rays.push(Ray::new(
                origin,
                unit(axis.into_inner() + u.into_inner() * a + v * b).unwrap(),
            ));
        }
    }
    rays
}

#[test]
fn real_meshes_are_scanned_by_the_arm() {
    let deg = |v: [Real; 6]| -> Vec<Real> { v.iter().map(|d| d.to_radians()).collect() };
    // The truss bridge surrounds the origin (deck at z ≈ 0): sweep from the start pose.
    let setup = ScanSetup::from_scene_file(
        &data("meshes/truss_bridge_meters.obj"),
        "denso-vm6083",
        None,
        geom::Isometry3::identity(),
        deg([0.0, -55.0, 165.0, 0.0, -110.0, 0.0]),
        Some(20.0),
        1,
    )
    .unwrap();
    let out = setup.run(&mut |_, _| {}).unwrap();
    assert!(out.sweep.len() > 1000, "{}", out.sweep.len());
    let scene = setup.world.as_scene().unwrap();
    let acc = sim::metrics::accuracy(scene, &out.sweep.positions(), 0.5);
    assert!(acc.distances.unwrap().mean_m < 0.03, "{acc:?}");
    // Small objects: cast the scanner's own rays at them from 0.5 m.
    for file in [
        "meshes/cinder_block_meters.obj",
        "meshes/004_sugar_box_textured.obj",
        "meshes/2x4x48_meters.obj",
    ] {
        let world = world_from_file(&data(file)).unwrap();
        let scene = world.as_scene().unwrap();
        let c = scene.bounding_box().center();
        let rays = fan(c + Vector3::new(0.0, 0.0, 0.5), -Vector3::z(), 10.0, 30);
        let hits = world.cast_rays(&rays, 4.0).into_iter().flatten().count();
        assert!(hits > 50, "{file}: {hits} hits");
    }
}

#[test]
fn real_clouds_answer_rays_by_the_epsilon_rule() {
    // mOSD and the milk carton are depth-camera frames: cast from the camera
    // (origin) along +z, the optical axis.
    for (file, half) in [
        ("pointclouds/mosd_learn0.pcd", 20.0),
        ("pointclouds/mosd_learn5.pcd", 20.0),
        ("pointclouds/mosd_learn17.pcd", 20.0),
        ("pointclouds/pcl_milk.pcd", 3.0),
    ] {
        let world = world_from_file(&data(file)).unwrap();
        let World::Cloud(cloud) = &world else {
            panic!("{file} should load as a cloud")
        };
        assert!(
            cloud.epsilon() > 0.0 && cloud.epsilon() < 0.2,
            "{file}: ε {}",
            cloud.epsilon()
        );
        let axis = if file.contains("milk") {
            // The carton sits off-axis: aim at the cloud's centre.
            cloud.cloud().bounding_box().center().coords
        } else {
            Vector3::z()
        };
        let rays = fan(Point3::origin(), axis, half, 25);
        let hits: Vec<_> = world.cast_rays(&rays, 4.0).into_iter().flatten().collect();
        assert!(hits.len() > 300, "{file}: {} hits", hits.len());
        for (h, r) in hits.iter().zip(&rays) {
            // A hit is a cloud point within ε of some ray (the matching one is
            // checked in the unit tests); here: real points, in range.
            assert!(h.distance > 0.3 && h.distance < 2.0, "{file}: {h:?} {r:?}");
        }
    }
    // pc2beam is a TLS crop in site coordinates: cast along the negated normals
    // from 0.5 m in front of points of each beam.
    let world = world_from_file(&data("pointclouds/pc2beam_steel_beams_test_points.txt")).unwrap();
    let World::Cloud(cloud) = &world else {
        panic!("pc2beam should load as a cloud")
    };
    let pts = &cloud.cloud().points;
    let normals = cloud.cloud().normals.as_ref().unwrap();
    let mut hits = 0;
    for k in (0..pts.len()).step_by(97) {
        let n = unit(normals[k]).unwrap();
        let ray = Ray::new(pts[k] + n.into_inner() * 0.5, -n);
        if let Some(h) = world.cast_ray(&ray, 4.0) {
            hits += 1;
            assert!(
                h.distance <= 0.5 + 1e-9,
                "nothing can be hit behind the aimed point"
            );
        }
    }
    assert!(hits * 10 > (pts.len() / 97) * 9, "{hits} hits");
}
