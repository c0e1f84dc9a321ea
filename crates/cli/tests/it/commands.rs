//! The command contract, exercised through the built binary.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use crate::support;

use std::fmt::Write as _;
use std::path::Path;
use support::{data, fails, ok, surveyor};

type M4 = [[f64; 4]; 4];

fn mul(a: &M4, b: &M4) -> M4 {
    let mut c = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            c[i][j] = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn json_matrix(v: &serde_json::Value) -> M4 {
    let mut m = [[0.0; 4]; 4];
    for (i, row) in v.as_array().unwrap().iter().enumerate() {
        for (j, x) in row.as_array().unwrap().iter().enumerate() {
            m[i][j] = x.as_f64().unwrap();
        }
    }
    m
}

fn assert_close(a: &M4, b: &M4, tol: f64) {
    for i in 0..4 {
        for j in 0..4 {
            assert!((a[i][j] - b[i][j]).abs() < tol, "{a:?}\n vs\n{b:?}");
        }
    }
}

/// Standard DH link transform Rz(θ) Tz(d) Tx(a) Rx(α).
fn dh(theta: f64, d: f64, a: f64, alpha: f64) -> M4 {
    let (s, c) = theta.sin_cos();
    let (sa, ca) = alpha.sin_cos();
    [
        [c, -s * ca, s * sa, a * c],
        [s, c * ca, -c * sa, a * s],
        [0.0, sa, ca, d],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// URDF joint: Trans(xyz) · Rz(y) Ry(p) Rx(r) · Rot(axis, q).
fn urdf(xyz: [f64; 3], rpy: [f64; 3], axis: [f64; 3], q: f64) -> M4 {
    let rot = |ax: [f64; 3], t: f64| -> [[f64; 3]; 3] {
        let (s, c) = t.sin_cos();
        let [x, y, z] = ax;
        let v = 1.0 - c;
        [
            [c + x * x * v, x * y * v - z * s, x * z * v + y * s],
            [y * x * v + z * s, c + y * y * v, y * z * v - x * s],
            [z * x * v - y * s, z * y * v + x * s, c + z * z * v],
        ]
    };
    let r3 = |m: [[f64; 3]; 3], t: [f64; 3]| -> M4 {
        [
            [m[0][0], m[0][1], m[0][2], t[0]],
            [m[1][0], m[1][1], m[1][2], t[1]],
            [m[2][0], m[2][1], m[2][2], t[2]],
            [0.0, 0.0, 0.0, 1.0],
        ]
    };
    let origin = mul(
        &mul(
            &r3(rot([0.0, 0.0, 1.0], rpy[2]), xyz),
            &r3(rot([0.0, 1.0, 0.0], rpy[1]), [0.0; 3]),
        ),
        &r3(rot([1.0, 0.0, 0.0], rpy[0]), [0.0; 3]),
    );
    mul(&origin, &r3(rot(axis, q), [0.0; 3]))
}

#[test]
fn fk_json_matches_independent_dh_and_urdf_chains() {
    let a = [0.18, 0.385, -0.1, 0.0, 0.0, 0.0];
    let d = [0.475, 0.0, 0.0, 0.445, 0.0, 0.084];
    let pi = std::f64::consts::PI;
    let alpha = [-pi / 2.0, 0.0, pi / 2.0, -pi / 2.0, pi / 2.0, 0.0];
    let offset = [0.0, -pi / 2.0, pi / 2.0, 0.0, 0.0, 0.0];
    for q in [
        [0.0; 6],
        [0.3, -0.7, 1.9, 0.2, -1.1, 2.5],
        [-2.0, 1.2, -0.5, 3.0, 1.9, -5.0],
    ] {
        let arg = q.map(|v| v.to_string()).join(",");
        let out = ok(&["fk", "--robot", "denso-vm6083", "--joints", &arg, "--json"]);
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        let mut t: M4 = dh(0.0, 0.0, 0.0, 0.0);
        let frames = v["frames"].as_array().unwrap();
        assert_eq!(frames.len(), 7);
        for i in 0..6 {
            t = mul(&t, &dh(q[i] + offset[i], d[i], a[i], alpha[i]));
            assert_close(&json_matrix(&frames[i + 1]["pose"]), &t, 1e-9);
        }
        assert_close(&json_matrix(&v["tip"]), &t, 1e-9);
        // The scanner: 5 cm along the flange's z axis, same axes.
        let scanner = mul(&t, &dh(0.0, 0.05, 0.0, 0.0));
        assert_close(&json_matrix(&v["sensor"]), &scanner, 1e-9);
    }
    // UR5 URDF, tip tool0: its joint origins and axes typed in.
    let h = 1.570_796_325;
    let q = [0.4, -1.1, 1.3, -0.6, 0.9, 2.2];
    let chain = [
        urdf([0.0, 0.0, 0.089_159], [0.0; 3], [0.0, 0.0, 1.0], q[0]),
        urdf([0.0, 0.13585, 0.0], [0.0, h, 0.0], [0.0, 1.0, 0.0], q[1]),
        urdf([0.0, -0.1197, 0.425], [0.0; 3], [0.0, 1.0, 0.0], q[2]),
        urdf([0.0, 0.0, 0.39225], [0.0, h, 0.0], [0.0, 1.0, 0.0], q[3]),
        urdf([0.0, 0.093, 0.0], [0.0; 3], [0.0, 0.0, 1.0], q[4]),
        urdf([0.0, 0.0, 0.09465], [0.0; 3], [0.0, 1.0, 0.0], q[5]),
        urdf([0.0, 0.0823, 0.0], [-h, 0.0, 0.0], [0.0, 0.0, 1.0], 0.0),
    ];
    let tool0 = chain
        .iter()
        .fold(dh(0.0, 0.0, 0.0, 0.0), |acc, m| mul(&acc, m));
    let arg = q.map(|v| v.to_string()).join(",");
    let urdf_path = data("robots/ur5/ur5_robot.urdf");
    let out = ok(&[
        "fk", "--robot", &urdf_path, "--tip", "tool0", "--joints", &arg, "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_close(&json_matrix(&v["tip"]), &tool0, 1e-9);
    assert!(v.get("sensor").is_none());
    let names: Vec<&str> = v["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].as_str().unwrap())
        .collect();
    assert_eq!(names.first(), Some(&"world"));
    assert_eq!(names.last(), Some(&"tool0"));
}

#[test]
fn fk_errors_are_clear() {
    let e = fails(&["fk", "--robot", "denso-vm6083", "--joints", "0,0,0"]);
    assert!(e.contains('6') && e.contains('3'), "{e}");
    let e = fails(&["fk", "--robot", "ghost", "--joints", "0"]);
    assert!(e.contains("denso-vm6083"), "{e}");
    let e = fails(&["fk", "--robot", "/nonexistent/robot.urdf", "--joints", "0"]);
    assert!(e.contains("/nonexistent/robot.urdf"), "{e}");
}

#[test]
fn scenario_show_parses_back() {
    let list = ok(&["scenario", "list"]);
    assert!(list.lines().count() == 7 && list.contains("bridge3"));
    let dir = tempfile::tempdir().unwrap();
    let text = ok(&["scenario", "show", "block2"]);
    let path = dir.path().join("b2.toml");
    std::fs::write(&path, &text).unwrap();
    let again = ok(&["scenario", "show", path.to_str().unwrap()]);
    assert_eq!(text, again);
}

fn read_ply_columns(path: &Path) -> scene::io::PlyTable {
    scene::io::read_ply_vertices(path).unwrap()
}

#[test]
fn scan_writes_the_contracted_ply_and_scores_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.ply");
    let stdout = ok(&[
        "scan",
        "--scenario",
        "bridge1",
        "--tilt-deg",
        "6",
        "--seed",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        stdout.contains("points") && stdout.contains("coverage") && stdout.contains("accuracy"),
        "{stdout}"
    );
    let t = read_ply_columns(&out);
    assert_eq!(
        t.names,
        [
            "x",
            "y",
            "z",
            "intensity",
            "ox",
            "oy",
            "oz",
            "scan",
            "ray",
            "material"
        ]
    );
    let n: usize = stdout.split_whitespace().next().unwrap().parse().unwrap();
    assert_eq!(t.len(), n);
    // The grid: 6° at 0.4° per scan is 16 scans of 342 rays, scan-major.
    let (scans, rays) = (t.column("scan").unwrap(), t.column("ray").unwrap());
    assert!(scans.iter().all(|s| (0.0..16.0).contains(s)));
    assert!(rays.iter().all(|r| (0.0..342.0).contains(r)));
    assert!(
        scans
            .iter()
            .zip(rays)
            .zip(scans.iter().zip(rays).skip(1))
            .all(|(a, b)| a < b)
    );
    // Ray origins are the scanner: ~5 cm above the flange at (0.317, 0, 0.72).
    let oz = t.column("oz").unwrap();
    assert!(oz.iter().all(|z| (z - 0.77).abs() < 0.05));
    // With --scene, a mesh placed as-is and a robot base placed by the user.
    let out2 = dir.path().join("t.ply");
    let stdout = ok(&[
        "scan",
        "--scene",
        &data("meshes/cinder_block_meters.obj"),
        "--base-xyz",
        "-0.6,0,-0.3",
        "--deg",
        "--joints",
        "0,-55,165,0,-110,0",
        "--out",
        out2.to_str().unwrap(),
    ]);
    assert!(stdout.contains("coverage"), "{stdout}");
    // Bad input.
    let e = fails(&[
        "scan",
        "--scenario",
        "bridge1",
        "--joints",
        "1,2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(e.contains("expected 6"), "{e}");
    let e = fails(&[
        "scan",
        "--scene",
        "/no/such.obj",
        "--joints",
        "0,0,0,0,0,0",
        "--out",
        "x.ply",
    ]);
    assert!(e.contains("/no/such.obj"), "{e}");
}

#[test]
fn raycast_round_trip_against_a_known_plane() {
    let dir = tempfile::tempdir().unwrap();
    // A 2 m square at z = 1 as an OBJ.
    let obj = dir.path().join("plane.obj");
    std::fs::write(
        &obj,
        "v -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let rays: Vec<[f32; 6]> = vec![
        [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        [0.5, 0.5, -1.0, 0.0, 0.0, 1.0],
        [0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        [0.0, 0.0, 0.0, 0.6, 0.0, 0.8],
    ];
    let bytes: Vec<u8> = rays
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let rays_path = dir.path().join("rays.bin");
    std::fs::write(&rays_path, bytes).unwrap();
    let out = dir.path().join("d.bin");
    let stdout = ok(&[
        "raycast",
        "--scene",
        obj.to_str().unwrap(),
        "--rays",
        rays_path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--threads",
        "1",
    ]);
    assert!(stdout.contains("Mrays/s"), "{stdout}");
    assert!(stdout.contains("median of 5 casts"), "{stdout}");
    let d: Vec<f32> = std::fs::read(&out)
        .unwrap()
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    assert_eq!(d.len(), 4);
    assert!((d[0] - 1.0).abs() < 1e-6 && (d[1] - 2.0).abs() < 1e-6);
    assert!(d[2].is_infinite() && d[2] > 0.0);
    assert!((d[3] - 1.25).abs() < 1e-6);
    // A file that is not whole rays.
    std::fs::write(&rays_path, [0u8; 30]).unwrap();
    let e = fails(&[
        "raycast",
        "--scene",
        obj.to_str().unwrap(),
        "--rays",
        rays_path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(e.contains("rays.bin") && e.contains("30 bytes"), "{e}");
}

#[test]
fn map_applies_occlusion_weights_over_the_scan_grid() {
    // A hand-built sweep: 3 scans × 4 rays 0.36° apart, nodding 0.5° per scan
    // about the scanner's y axis, 0.5 m above the base. Ranges (m):
    //   scan 0: 1 1 2 2
    //   scan 1: 1 1 2 2
    //   scan 2: 1 1 1 1
    // Range jumps > 0.1 m between grid neighbours: ray 1→2 in scans 0 and 1,
    // and scan 1→2 at rays 2 and 3: four occlusion segments (Paul §4.2.1).
    let dir = tempfile::tempdir().unwrap();
    let step = 0.36f64.to_radians();
    let bearings: Vec<f64> = (0..4).map(|i| (f64::from(i) - 1.5) * step).collect();
    let poses: Vec<geom::Isometry3> = (0..3)
        .map(|j| {
            geom::Isometry3::from_parts(
                geom::Translation3::new(0.0, 0.0, 0.5),
                geom::UnitQuaternion::from_axis_angle(
                    &geom::Vector3::y_axis(),
                    (0.5 * f64::from(j)).to_radians(),
                ),
            )
        })
        .collect();
    let r = |v: f64| Some(v);
    let ranges = [
        r(1.0),
        r(1.0),
        r(2.0),
        r(2.0),
        r(1.0),
        r(1.0),
        r(2.0),
        r(2.0),
        r(1.0),
        r(1.0),
        r(1.0),
        r(1.0),
    ];
    let sweep = sensor::Sweep::from_range_grid(&bearings, &poses, &ranges).unwrap();
    // `surveyor map` of one sweep written to a scan file: (stdout, stderr).
    let map_of = |sweep: &sensor::Sweep, name: &str| {
        let file = dir.path().join(format!("{name}.ply"));
        sweep.write_ply(&file).unwrap();
        let out_dir = dir.path().join(name);
        let o = surveyor(&[
            "map",
            "--scans",
            file.to_str().unwrap(),
            "--voxel",
            "0.05",
            "--out",
            out_dir.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (
            String::from_utf8_lossy(&o.stdout).into_owned(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (out, _) = map_of(&sweep, "grid");
    assert!(out.contains("4 occlusion segments (scan grid)"), "{out}");
    // Without the grid only the two jumps along a scan are recoverable.
    let (out, _) = map_of(&sweep.without_grid(), "list");
    assert!(out.contains("2 occlusion segments (no grid"), "{out}");

    // A sweep wholly outside the map's regions is integrated as nothing, with
    // a warning.
    let far = sensor::Sweep::from_points(
        sweep
            .points()
            .iter()
            .map(|p| sensor::SweepPoint {
                point: p.point + geom::Vector3::new(100.0, 0.0, 0.0),
                origin: p.origin + geom::Vector3::new(100.0, 0.0, 0.0),
                ..*p
            })
            .collect(),
    )
    .unwrap();
    let (_, err) = map_of(&far, "far");
    assert!(
        err.contains("far.ply") && err.contains("all 12 rays lie outside the occupancy map"),
        "{err}"
    );
}

#[test]
fn map_sld_and_segment_follow_their_contracts() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).display().to_string();
    // Two short sweeps from different poses.
    for (name, joints) in [
        ("a.ply", "0,-55,165,0,-110,0"),
        ("b.ply", "40,-55,165,0,-110,0"),
    ] {
        ok(&[
            "scan",
            "--scenario",
            "bridge1",
            "--deg",
            "--joints",
            joints,
            "--tilt-deg",
            "10",
            "--out",
            &p(name),
        ]);
    }
    let out = ok(&[
        "map",
        "--scans",
        &p("a.ply"),
        &p("b.ply"),
        "--scenario",
        "bridge1",
        "--voxel",
        "0.02",
        "--out",
        &p("maps"),
    ]);
    assert_eq!(out.matches("points integrated in").count(), 2, "{out}");
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("maps/occupancy.json")).unwrap(),
    )
    .unwrap();
    let regions = report["regions"].as_array().unwrap();
    assert_eq!(regions.len(), 3);
    for r in regions {
        let sum = r["free"].as_u64().unwrap()
            + r["unknown"].as_u64().unwrap()
            + r["occupied"].as_u64().unwrap();
        assert_eq!(sum, r["total"].as_u64().unwrap());
    }
    // H1 unweighted = n_u ln 2 over A3 (eq. 4.10).
    let n_u = regions[2]["unknown"].as_f64().unwrap();
    assert!(
        (report["h1_unweighted"].as_f64().unwrap() - n_u * std::f64::consts::LN_2).abs()
            < 1e-6 * n_u
    );
    let mesh = scene::io::load_mesh(&dir.path().join("maps/mesh.ply"), 1.0).unwrap();
    assert!(mesh.len() > 1000);

    let out = ok(&[
        "sld",
        "--input",
        &p("a.ply"),
        "--seed",
        "2",
        "--out",
        &p("discs.csv"),
    ]);
    assert!(
        out.contains("discs from") && out.contains("% registered"),
        "{out}"
    );
    let csv = std::fs::read_to_string(dir.path().join("discs.csv")).unwrap();
    assert!(csv.starts_with("cx,cy,cz,nx,ny,nz,radius,points"));
    let discs = csv.lines().count() - 1;
    assert!(discs > 50);

    // Discs of the fused mesh face the sensor by the mesh's winding: the
    // roof's (z = 1.52, seen from below) point down.
    ok(&[
        "sld",
        "--input",
        &p("maps/mesh.ply"),
        "--out",
        &p("mesh_discs.csv"),
    ]);
    let text = std::fs::read_to_string(dir.path().join("mesh_discs.csv")).unwrap();
    let roof: Vec<f64> = text
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .map(|v| v.parse().unwrap())
                .collect::<Vec<f64>>()
        })
        .filter(|d| d[2] > 1.45 && d[5].abs() > 0.9)
        .map(|d| d[5])
        .collect();
    assert!(roof.len() > 20, "{} roof discs", roof.len());
    assert!(roof.iter().all(|nz| *nz < 0.0), "{roof:?}");

    let out = ok(&[
        "segment",
        "--discs",
        &p("discs.csv"),
        "--out",
        &p("segments.json"),
    ]);
    assert!(out.contains("segments from"), "{out}");
    let seg: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("segments.json")).unwrap())
            .unwrap();
    let mut members: Vec<u64> = seg["segments"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| s.as_array().unwrap().iter().map(|i| i.as_u64().unwrap()))
        .collect();
    members.sort_unstable();
    assert_eq!(
        members,
        (0..discs as u64).collect::<Vec<_>>(),
        "every disc in exactly one segment"
    );

    // Bad input: a cloud without ray origins cannot be mapped; τq needs six values.
    let e = fails(&[
        "map",
        "--scans",
        &data("pointclouds/pcl_milk.pcd"),
        "--out",
        &p("m2"),
    ]);
    assert!(e.contains("pcl_milk.pcd"), "{e}");
    let e = fails(&[
        "segment",
        "--discs",
        &p("discs.csv"),
        "--tau-q-deg",
        "1,2",
        "--out",
        &p("s.json"),
    ]);
    assert!(e.contains("six"), "{e}");
}

#[test]
fn model_builds_one_polygon_from_a_plane_patch() {
    let dir = tempfile::tempdir().unwrap();
    // Eight sets of 25 points on the plane z = 0.5, seen from above, overlapping
    // along x: one planar polygon with outward normal +z must represent them all.
    let mut lines = String::new();
    for s in 0..8 {
        let mut points = Vec::new();
        for k in 0..25 {
            let x = 0.03 * f64::from(s) + 0.02 * f64::from(k % 5);
            let y = 0.02 * f64::from(k / 5);
            points.push(format!("[{x},{y},0.5]"));
        }
        let axes = vec!["[0,0,-1]"; points.len()];
        writeln!(
            lines,
            "{{\"points\": [{}], \"axes\": [{}]}}",
            points.join(","),
            axes.join(",")
        )
        .unwrap();
    }
    let sets = dir.path().join("sets.jsonl");
    std::fs::write(&sets, lines).unwrap();
    let out = dir.path().join("model");
    let stdout = ok(&[
        "model",
        "--sets",
        sets.to_str().unwrap(),
        "--check",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(stdout.contains("8 sets"), "{stdout}");
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("surface_model.json")).unwrap())
            .unwrap();
    let segments = model["segments"].as_array().unwrap();
    assert_eq!(segments.len(), 1, "{model}");
    let poly = &segments[0];
    assert_eq!(poly["kind"], "polygon");
    assert_eq!(poly["points"], 200);
    assert_eq!(poly["initial"], false);
    let normal: Vec<f64> = serde_json::from_value(poly["normal"].clone()).unwrap();
    assert!((normal[2] - 1.0).abs() < 1e-9, "{normal:?}");
    let vertices: Vec<[f64; 3]> = serde_json::from_value(poly["vertices"].clone()).unwrap();
    assert_eq!(poly["edges"].as_array().unwrap().len(), vertices.len());
    // Anticlockwise about +z: positive shoelace area; all vertices on the plane;
    // the polygon spans the sampled extent (x ∈ [0, 0.29], y ∈ [0, 0.08]) within λ.
    let area: f64 = (0..vertices.len())
        .map(|i| {
            let (a, b) = (vertices[i], vertices[(i + 1) % vertices.len()]);
            0.5 * (a[0] * b[1] - b[0] * a[1])
        })
        .sum();
    assert!(area > 0.5 * 0.29 * 0.08, "area {area}");
    for v in &vertices {
        assert!((v[2] - 0.5).abs() < 1e-9);
        assert!(
            v[0] > -0.05 && v[0] < 0.34 && v[1] > -0.05 && v[1] < 0.13,
            "{v:?}"
        );
    }
    assert_eq!(model["surfaces"].as_array().unwrap().len(), 1);
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("stats.json")).unwrap()).unwrap();
    assert_eq!(stats["updates"], 8);
    assert_eq!(stats["polygons"], 1);
    assert_eq!(stats["segments"], 1);
    assert_eq!(stats["points"], 0); // point segments
    assert!(stats["update_us"]["median"].as_f64().unwrap() > 0.0);
    let obj = std::fs::read_to_string(out.join("surface_model.obj")).unwrap();
    assert_eq!(
        obj.lines().filter(|l| l.starts_with("v ")).count(),
        vertices.len()
    );
    assert!(obj.lines().any(|l| l.starts_with("f ")));

    // A malformed set names the file and the line and writes nothing.
    let bad = dir.path().join("bad.jsonl");
    std::fs::write(
        &bad,
        "{\"points\": [[0,0,0]], \"axes\": [[0,0,-1]]}\n{\"points\": [[0,0,0]], \"axes\": []}\n",
    )
    .unwrap();
    let out2 = dir.path().join("model2");
    let err = fails(&[
        "model",
        "--sets",
        bad.to_str().unwrap(),
        "--out",
        out2.to_str().unwrap(),
    ]);
    assert!(err.contains("bad.jsonl") && err.contains('2'), "{err}");
    assert!(!out2.exists());
}
