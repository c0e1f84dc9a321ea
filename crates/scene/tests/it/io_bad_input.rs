//! Bad input never panics and gives an error naming the file, and the line,
//! element or field at fault, with what was expected (SPEC §2).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "test helpers outside #[test] functions fail the test on any error"
)]

use crate::io_fixtures;

use io_fixtures::{data, pcd_ascii, pcd_binary, pcd_compressed, ply_ascii, ply_binary, write};
use proptest::prelude::*;
use scene::io;
use scene::{SceneError, TriMesh};
use std::path::{Path, PathBuf};

/// The error's message; fails the test when the call succeeded.
fn message<T: std::fmt::Debug>(result: Result<T, SceneError>) -> String {
    match result {
        Ok(v) => panic!("expected an error, got {v:?}"),
        Err(e) => e.to_string(),
    }
}

/// Assert `msg` contains every one of `parts`.
#[track_caller]
fn assert_mentions(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "message {msg:?} does not mention {p:?}");
    }
}

fn load_any(path: &Path) -> Result<(), SceneError> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    match ext {
        "obj" | "stl" => io::load_mesh(path, 1.0).map(|_| ()),
        _ => io::load_cloud(path).map(|_| ()),
    }
}

/// Every prefix of `bytes` at `stride`, plus the last few lengths, written to
/// `dir/name` and loaded with `load`, must fail with a message naming the file
/// and saying it is truncated (or too short).
fn assert_prefixes_fail(
    dir: &Path,
    name: &str,
    bytes: &[u8],
    stride: usize,
    load: impl Fn(&Path) -> Result<(), SceneError>,
) {
    let path = dir.join(name);
    let n = bytes.len();
    let lengths = (1..n)
        .step_by(stride)
        .chain((1..=9).map(|k| n.saturating_sub(k)))
        .filter(|&l| l > 0 && l < n);
    let mut tried = 0;
    for len in lengths {
        std::fs::write(&path, &bytes[..len]).unwrap();
        let msg = match load(&path) {
            Ok(()) => panic!("{name} cut to {len} of {n} bytes loaded without error"),
            Err(e) => e.to_string(),
        };
        assert!(
            msg.contains(name),
            "{name} cut to {len}: {msg:?} does not name the file"
        );
        assert!(
            msg.contains("truncated") || msg.contains("too short"),
            "{name} cut to {len}: {msg:?} does not say it is truncated"
        );
        tried += 1;
    }
    assert!(tried > 20, "{name}: only {tried} prefixes");
}

// ---------------------------------------------------------------------------
// Truncated binary files of every kind.

#[test]
fn truncated_compressed_pcd_files() {
    let dir = tempfile::tempdir().unwrap();
    // PCL pads compressed files (to whole pages for the mOSD scans): cutting
    // the padding after the LZF stream loses nothing, so only cuts into the
    // header, the size words or the stream are tested.
    let mosd = std::fs::read(data("pointclouds/mosd_learn0.pcd")).unwrap();
    let mosd = &mosd[..compressed_end(&mosd)];
    assert_prefixes_fail(dir.path(), "mosd.pcd", mosd, mosd.len() / 40, |p| {
        io::load_cloud(p).map(|_| ())
    });
    let milk = std::fs::read(data("pointclouds/pcl_milk.pcd")).unwrap();
    let milk = &milk[..compressed_end(&milk)];
    assert_prefixes_fail(dir.path(), "milk.pcd", milk, 509, |p| {
        io::load_cloud(p).map(|_| ())
    });
    assert_prefixes_fail(dir.path(), "fixture.pcd", &pcd_compressed(), 1, |p| {
        io::load_cloud(p).map(|_| ())
    });
}

#[test]
fn truncated_binary_pcd_files() {
    // The milk carton as an uncompressed binary PCD.
    let milk = io::load_cloud(&data("pointclouds/pcl_milk.pcd")).unwrap();
    let n = milk.points.len();
    let mut bytes = format!(
        "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\n\
         VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary\n"
    )
    .into_bytes();
    for p in &milk.points {
        for c in [p.x, p.y, p.z] {
            bytes.extend_from_slice(&(c as f32).to_le_bytes());
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let full = write(dir.path(), "whole.pcd", &bytes);
    assert_eq!(io::load_cloud(&full).unwrap(), milk);
    assert_prefixes_fail(dir.path(), "milkbin.pcd", &bytes, 997, |p| {
        io::load_cloud(p).map(|_| ())
    });
    assert_prefixes_fail(dir.path(), "fixture.pcd", &pcd_binary(), 1, |p| {
        io::load_cloud(p).map(|_| ())
    });
}

#[test]
fn truncated_binary_stl_files() {
    let dir = tempfile::tempdir().unwrap();
    for (name, stride) in [
        ("base", 13),
        ("shoulder", 499),
        ("upper_arm", 499),
        ("forearm", 499),
        ("wrist_1", 499),
        ("wrist_2", 499),
        ("wrist_3", 499),
    ] {
        let bytes =
            std::fs::read(data(&format!("robots/ur5/meshes/ur5/collision/{name}.stl"))).unwrap();
        assert_prefixes_fail(dir.path(), &format!("{name}.stl"), &bytes, stride, |p| {
            io::load_mesh(p, 1.0).map(|_| ())
        });
    }
}

#[test]
fn truncated_binary_ply_files() {
    let dir = tempfile::tempdir().unwrap();
    // A real mesh written as binary little-endian PLY.
    let truss = io::load_mesh(&data("meshes/truss_bridge_meters.obj"), 1.0).unwrap();
    let ply = dir.path().join("whole.ply");
    io::write_mesh_ply(&ply, &truss).unwrap();
    let bytes = std::fs::read(&ply).unwrap();
    assert_prefixes_fail(dir.path(), "truss.ply", &bytes, 61, |p| {
        io::load_mesh(p, 1.0).map(|_| ())
    });
    // As a cloud and as a table the face section must be complete too.
    assert_prefixes_fail(dir.path(), "truss_cloud.ply", &bytes, 613, |p| {
        io::load_cloud(p).map(|_| ())
    });
    assert_prefixes_fail(dir.path(), "truss_table.ply", &bytes, 613, |p| {
        io::read_ply_vertices(p).map(|_| ())
    });
    // The hand-written fixtures, both byte orders, every length.
    for (name, big) in [("le.ply", false), ("be.ply", true)] {
        let fixture = ply_binary(big);
        assert_prefixes_fail(dir.path(), name, &fixture, 1, |p| {
            io::load_mesh(p, 1.0).map(|_| ())
        });
    }
    // A vertex table from the writer.
    let mut table = Vec::new();
    let xs: Vec<f32> = (0..100).map(|i| i as f32).collect();
    io::write_ply_vertices(&mut table, &["x", "y", "z", "ox"], &[&xs, &xs, &xs, &xs]).unwrap();
    assert_prefixes_fail(dir.path(), "table.ply", &table, 7, |p| {
        io::read_ply_vertices(p).map(|_| ())
    });
}

#[test]
fn truncation_messages_say_where_and_how_much() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = ply_binary(false);
    // Cut two bytes into the face section: the vertex rows are complete.
    let body = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let vertex_bytes: usize = io_fixtures::VERTICES
        .iter()
        .map(|v| 12 + 24 + 1 + 4 + 1 + 2 * v.4.len())
        .sum();
    let path = write(dir.path(), "cut.ply", &bytes[..body + vertex_bytes + 2]);
    let msg = message(io::load_mesh(&path, 1.0));
    assert_mentions(
        &msg,
        &[
            "cut.ply",
            "element 'face' row 0 (of 3)",
            "list 'vertex_indices' of 4 indices",
            "needs 16 bytes, only 1 left",
        ],
    );

    let stl = std::fs::read(data("robots/ur5/meshes/ur5/collision/base.stl")).unwrap();
    let path = write(dir.path(), "cut.stl", &stl[..1000]);
    let msg = message(io::load_mesh(&path, 1.0));
    assert_mentions(
        &msg,
        &[
            "cut.stl",
            "578 triangles = 28984 bytes",
            "the file has 1000",
        ],
    );

    let milk = std::fs::read(data("pointclouds/pcl_milk.pcd")).unwrap();
    let path = write(dir.path(), "cut.pcd", &milk[..50_000]);
    let msg = message(io::load_cloud(&path));
    assert_mentions(&msg, &["cut.pcd", "compressed bytes but only", "truncated"]);
}

// ---------------------------------------------------------------------------
// Garbled headers, empty and zero-point files.

#[test]
fn garbled_headers_name_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &str, &[&str]); 14] = [
        (
            "a.ply",
            "plyx\nformat ascii 1.0\nend_header\n",
            &[":1:", "first line must be 'ply'"],
        ),
        (
            "b.ply",
            "ply\nformat binary_middle_endian 1.0\nend_header\n",
            &[":2:", "binary_middle_endian", "expected ascii"],
        ),
        (
            "c.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float33 x\nend_header\n",
            &[":4:", "unknown property type 'float33'"],
        ),
        (
            "d.ply",
            "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
            &[":3:", "before any 'element'"],
        ),
        (
            "e.ply",
            "ply\nformat ascii 1.0\nelement vertex many\nend_header\n",
            &[":3:", "'many' is not a non-negative integer"],
        ),
        (
            "f.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int idx\nend_header\n",
            &[":4:", "count type must be an integer"],
        ),
        (
            "g.ply",
            "ply\nelement vertex 0\nend_header\n",
            &[":3:", "no 'format' line"],
        ),
        (
            "h.ply",
            "ply\nformat ascii 1.0\nelement face 0\nend_header\n",
            &["no 'vertex' element"],
        ),
        (
            "i.pcd",
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n",
            &[":3:", "SIZE has 2 values but FIELDS names 3"],
        ),
        (
            "j.pcd",
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 2 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n",
            &[":4:", "field 'y': TYPE F with SIZE 2"],
        ),
        (
            "k.pcd",
            "VERSION 0.9\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n",
            &[":1:", "unsupported PCD version '0.9'"],
        ),
        (
            "l.pcd",
            "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nBOGUS 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
            &[":4:", "'BOGUS'"],
        ),
        (
            "m.pcd",
            "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 2\nPOINTS 3\nDATA ascii\n",
            &[":6:", "POINTS 3 does not equal WIDTH 2 × HEIGHT 2"],
        ),
        (
            "n.pcd",
            "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA zipped\n",
            &[":5:", "DATA 'zipped'"],
        ),
    ];
    for (name, text, parts) in cases {
        let path = write(dir.path(), name, text.as_bytes());
        let msg = message(io::load_cloud(&path));
        assert_mentions(&msg, &[name]);
        assert_mentions(&msg, parts);
    }
    // A PCD without x.
    let path = write(
        dir.path(),
        "o.pcd",
        b"FIELDS a y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n",
    );
    assert_mentions(
        &message(io::load_cloud(&path)),
        &["o.pcd", "no field 'x'", "fields: a y z"],
    );
    // Integer coordinates.
    let path = write(
        dir.path(),
        "p.pcd",
        b"FIELDS x y z\nSIZE 4 4 4\nTYPE F U F\nPOINTS 1\nDATA ascii\n1 2 3\n",
    );
    assert_mentions(
        &message(io::load_cloud(&path)),
        &[
            "p.pcd",
            "field 'y' must be a single float",
            "found SIZE 4 TYPE U COUNT 1",
        ],
    );
}

#[test]
fn empty_files() {
    let dir = tempfile::tempdir().unwrap();
    for (name, parts) in [
        ("e.ply", &["e.ply", "empty file"][..]),
        ("e.pcd", &["e.pcd", "empty file"]),
        ("e.stl", &["e.stl", "empty file"]),
        ("e.obj", &["e.obj", "no faces"]),
        ("e.txt", &["e.txt", "no points"]),
        ("e.csv", &["e.csv", "no points"]),
    ] {
        let path = write(dir.path(), name, b"");
        assert_mentions(&message(load_any(&path)), parts);
    }
    let path = write(dir.path(), "m.ply", b"");
    assert_mentions(
        &message(io::load_mesh(&path, 1.0)),
        &["m.ply", "empty file"],
    );
}

#[test]
fn files_without_points_or_triangles() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &[u8], &[&str]); 9] = [
        (
            "a.ply",
            b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n\
              property float z\nend_header\n",
            &["a.ply", "no points"],
        ),
        (
            "b.pcd",
            b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 0\nPOINTS 0\nDATA ascii\n",
            &["b.pcd", "no points"],
        ),
        (
            "c.pcd",
            b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 2\nDATA ascii\nnan nan nan\nnan 0 0\n",
            &[
                "c.pcd",
                "none of the file's 2 points has finite coordinates",
            ],
        ),
        (
            "d.pcd",
            b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 0\nDATA binary_compressed\n",
            &["d.pcd", "no points"],
        ),
        (
            "e.txt",
            b"# only a comment\n\n   \n",
            &["e.txt", "no points"],
        ),
        ("f.pts", b"0\n", &["f.pts", "no points"]),
        (
            "g.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\n",
            &["g.obj", "no faces (3 vertices)"],
        ),
        (
            "h.stl",
            b"solid x\nendsolid x\n",
            &["h.stl", "no triangles"],
        ),
        ("i.stl", &[0u8; 84], &["i.stl", "no triangles"]),
    ];
    for (name, bytes, parts) in cases {
        let path = write(dir.path(), name, bytes);
        assert_mentions(&message(load_any(&path)), parts);
    }
    // A PLY mesh without faces, and one with an empty face element.
    let path = write(
        dir.path(),
        "j.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
          property float z\nend_header\n0 0 0\n",
    );
    // `Invalid` (not `Parse`): callers fall back to load_cloud on this variant.
    let e = io::load_mesh(&path, 1.0).unwrap_err();
    assert!(matches!(e, SceneError::Invalid { .. }), "{e:?}");
    assert_mentions(&e.to_string(), &["j.ply", "no 'face' element"]);
    assert_eq!(io::load_cloud(&path).unwrap().points.len(), 1);
    let path = write(
        dir.path(),
        "k.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
          property float z\nelement face 0\nproperty list uchar int vertex_indices\n\
          end_header\n0 0 0\n",
    );
    let e = io::load_mesh(&path, 1.0).unwrap_err();
    assert!(matches!(e, SceneError::Invalid { .. }), "{e:?}");
    assert_mentions(&e.to_string(), &["k.ply", "no triangles"]);
}

// ---------------------------------------------------------------------------
// NaN coordinates and wrong column counts.

#[test]
fn nan_coordinates_are_errors_outside_pcd() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "n.txt", b"1 2 3\n4 NaN 6\n");
    assert_mentions(
        &message(io::load_cloud(&path)),
        &["n.txt:2:", "column 2 (y) is NaN"],
    );
    let path = write(dir.path(), "n.csv", b"1,2,3,0,0,1\n4,5,6,0,inf,0\n");
    assert_mentions(
        &message(io::load_cloud(&path)),
        &["n.csv:2:", "column 5 (ny) is inf"],
    );

    let ply = b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                property float z\nend_header\n0 0 0\n1 nan 1\n";
    let path = write(dir.path(), "n.ply", ply);
    assert_mentions(
        &message(io::load_cloud(&path)),
        &["n.ply:9:", "row 1", "property 'y' is NaN"],
    );
    let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty double x\n\
                    property double y\nproperty double z\nend_header\n"
        .to_vec();
    for c in [0.0f64, 1.0, f64::INFINITY] {
        bin.extend_from_slice(&c.to_le_bytes());
    }
    let path = write(dir.path(), "nb.ply", &bin);
    assert_mentions(
        &message(io::load_cloud(&path)),
        &["nb.ply", "vertex 0", "property 'z' is inf"],
    );
    // The generic table reader does not judge values.
    assert_eq!(
        io::read_ply_vertices(&path).unwrap().columns[2],
        [f64::INFINITY]
    );

    let path = write(
        dir.path(),
        "n.obj",
        b"v 0 0 0\nv 1 0 0\n# c\nv 0 nan 0\nf 1 2 3\n",
    );
    assert_mentions(
        &message(io::load_mesh(&path, 1.0)),
        &["n.obj:4:", "not finite"],
    );
    let path = write(
        dir.path(),
        "big.obj",
        b"v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    assert_mentions(
        &message(io::load_mesh(&path, 1.0)),
        &["big.obj:2:", "not finite"],
    );

    // Binary STL with a NaN corner.
    let mut stl = vec![0u8; 84];
    stl[80] = 1;
    for c in [
        0.0f32,
        0.0,
        1.0,
        0.0,
        0.0,
        0.0,
        1.0,
        0.0,
        0.0,
        0.0,
        f32::NAN,
        0.0,
    ] {
        stl.extend_from_slice(&c.to_le_bytes());
    }
    stl.extend_from_slice(&[0, 0]);
    let path = write(dir.path(), "n.stl", &stl);
    assert_mentions(
        &message(io::load_mesh(&path, 1.0)),
        &["n.stl", "non-finite"],
    );

    // Scaling finite coordinates out of range is caught too.
    let path = write(
        dir.path(),
        "s.obj",
        b"v 0 0 0\nv 3e38 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    assert_mentions(
        &message(io::load_mesh(&path, 1e300)),
        &["s.obj", "non-finite"],
    );
}

#[test]
fn wrong_column_counts_and_non_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &[u8], &[&str]); 10] = [
        (
            "a.txt",
            b"1 2 3\n4 5 6\n7 8\n",
            &[
                "a.txt:3:",
                "found 2 values, expected 3 (x y z) as fixed by line 1",
            ],
        ),
        (
            "b.txt",
            b"1 2 3 4\n",
            &["b.txt:1:", "found 4 values; expected 3 (x y z), 6"],
        ),
        (
            "rgb.xyz",
            b"1 2 3 0 0 1\n1 2 3 255 128 0\n",
            &["rgb.xyz:2:", "column 4 (nx) is 255", "colours?"],
        ),
        (
            "c.txt",
            b"1 2 3\n4 five 6\n",
            &["c.txt:2:", "column 2 (y): 'five' is not a number"],
        ),
        (
            "d.csv",
            b"x,y,z\n1,,3\n",
            &["d.csv:2:", "column 2 (y) is empty"],
        ),
        (
            "e.txt",
            b"1 2 3 0 0 1 2.5\n",
            &["e.txt:1:", "label 2.5 is not an integer"],
        ),
        (
            "f.csv",
            b"a,b,c\n1,2,3\n",
            &["f.csv:1:", "names no 'x' column"],
        ),
        (
            "g.pts",
            b"3\n1 2 3\n",
            &["g.pts:1:", "declares 3 points but the file has 1"],
        ),
        (
            "h.pcd",
            b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 2\nDATA ascii\n1 2 3\n4 5\n",
            &["h.pcd:7:", "point 1: found 2 values, expected 3"],
        ),
        (
            "i.pcd",
            b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 3\nDATA ascii\n1 2 3\n4 5 6\n",
            &["i.pcd:8:", "expected 3 points after DATA, found 2"],
        ),
    ];
    for (name, bytes, parts) in cases {
        let path = write(dir.path(), name, bytes);
        assert_mentions(&message(io::load_cloud(&path)), parts);
    }

    let head = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                property uchar z\nelement face 1\nproperty list uchar int vertex_indices\n\
                end_header\n";
    let ply_cases: [(&str, &[&str]); 7] = [
        (
            "0 0 0\n1 1\n3 0 1 0\n",
            &[":11:", "row 1", "property 'z' is missing"],
        ),
        (
            "0 0 0\n1 1 1 1\n3 0 1 0\n",
            &[":11:", "too many values: expected 3, the line has 4"],
        ),
        (
            "0 0 0\n1 one 1\n3 0 1 0\n",
            &[":11:", "property 'y': 'one' is not a number"],
        ),
        (
            "0 0 0\n1 1 256\n3 0 1 0\n",
            &[":11:", "256 is out of range for uchar"],
        ),
        (
            "0 0 0\n1 1 1\n4 0 1 0\n",
            &[":12:", "list 'vertex_indices' declares 4 items"],
        ),
        (
            "0 0 0\n1 1 1\n3 0 1 2\n",
            &[
                ":12:",
                "vertex index 2 is out of range (the file has 2 vertices)",
            ],
        ),
        ("0 0 0\n1 1 1\n2 0 1\n", &[":12:", "face 0 has 2 vertices"]),
    ];
    for (i, (body, parts)) in ply_cases.iter().enumerate() {
        let name = format!("p{i}.ply");
        let path = write(dir.path(), &name, format!("{head}{body}").as_bytes());
        let msg = message(io::load_mesh(&path, 1.0));
        assert_mentions(&msg, &[&name]);
        assert_mentions(&msg, parts);
    }

    let obj_cases: [(&str, &[&str]); 6] = [
        (
            "v 0 0 0\nv 1 0 0\nf 1 2 3\n",
            &[":3:", "face refers to vertex 3 but the file has 2"],
        ),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", &[":4:", "index 0"]),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n",
            &[":4:", "relative index -4"],
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
            &[":4:", "face has 2 vertices"],
        ),
        (
            "v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            &[":1:", "vertex has 2 values"],
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 x 0\nf 1 2 3\n",
            &[":3:", "'x' is not a number"],
        ),
    ];
    for (i, (text, parts)) in obj_cases.iter().enumerate() {
        let name = format!("o{i}.obj");
        let path = write(dir.path(), &name, text.as_bytes());
        let msg = message(io::load_mesh(&path, 1.0));
        assert_mentions(&msg, &[&name]);
        assert_mentions(&msg, parts);
    }
}

// ---------------------------------------------------------------------------
// Extensions, missing files, bad arguments.

#[test]
fn unknown_extensions_and_missing_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "cloud.las", b"whatever");
    let e = io::load_cloud(&path).unwrap_err();
    assert!(matches!(e, SceneError::Unsupported { .. }));
    assert_mentions(&e.to_string(), &["cloud.las", ".ply, .pcd, .txt"]);
    let e = io::load_mesh(&dir.path().join("noext"), 1.0).unwrap_err();
    assert_mentions(&e.to_string(), &["noext", ".obj, .stl or .ply"]);
    // Mesh formats are not clouds (but see load_cloud_or_mesh_vertices).
    let e = io::load_cloud(&data("meshes/cinder_block_meters.obj")).unwrap_err();
    assert!(matches!(e, SceneError::Unsupported { .. }));
    let e = io::load_mesh(&data("pointclouds/pcl_milk.pcd"), 1.0).unwrap_err();
    assert!(matches!(e, SceneError::Unsupported { .. }));
    let e = io::load_cloud_or_mesh_vertices(&path).unwrap_err();
    assert!(matches!(e, SceneError::Unsupported { .. }));

    let missing = dir.path().join("missing.pcd");
    let e = io::load_cloud(&missing).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }));
    assert_mentions(&e.to_string(), &["missing.pcd"]);
    assert_mentions(
        &message(io::read_ply_vertices(&dir.path().join("m.ply"))),
        &["m.ply"],
    );
    assert_mentions(&message(io::read_pcd_header(&missing)), &["missing.pcd"]);

    for scale in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let msg = message(io::load_mesh(
            &data("meshes/cinder_block_meters.obj"),
            scale,
        ));
        assert_mentions(
            &msg,
            &["cinder_block_meters.obj", "scale", "finite and positive"],
        );
    }
}

// ---------------------------------------------------------------------------
// Corrupt and lying compressed PCD data.

/// Offset of the first byte after the `DATA` line.
fn pcd_body(bytes: &[u8]) -> usize {
    let data = bytes.windows(5).position(|w| w == b"DATA ").unwrap();
    data + bytes[data..].iter().position(|&b| b == b'\n').unwrap() + 1
}

/// Offset just past the LZF stream of a `binary_compressed` PCD file.
fn compressed_end(bytes: &[u8]) -> usize {
    let body = pcd_body(bytes);
    body + 8 + u32::from_le_bytes(bytes[body..body + 4].try_into().unwrap()) as usize
}

fn with_u32(bytes: &[u8], at: usize, value: u32) -> Vec<u8> {
    let mut b = bytes.to_vec();
    b[at..at + 4].copy_from_slice(&value.to_le_bytes());
    b
}

#[test]
fn corrupt_lzf_payloads() {
    let dir = tempfile::tempdir().unwrap();
    let milk = std::fs::read(data("pointclouds/pcl_milk.pcd")).unwrap();
    let body = pcd_body(&milk);
    let stream = body + 8;

    // The first LZF byte is always a literal-run control byte; turning it into
    // a back-reference points before the start of the output.
    let mut b = milk.clone();
    b[stream] ^= 0xE0;
    let path = write(dir.path(), "flip0.pcd", &b);
    assert_mentions(
        &message(io::load_cloud(&path)),
        &["flip0.pcd", "LZF decompression", "corrupt data"],
    );

    // Flipping bytes anywhere never panics; most flips are caught (a flip
    // inside a literal run just changes a value and cannot be detected).
    let mut caught = 0;
    let len = milk.len() - stream;
    for k in 0..300 {
        let mut b = milk.clone();
        b[stream + k * len / 300] ^= 0xFF;
        let path = write(dir.path(), "flip.pcd", &b);
        if let Err(e) = io::load_cloud(&path) {
            // A flip that decodes to an absurd coordinate is caught by the
            // coordinate limit instead.
            let e = e.to_string();
            if e.contains("beyond") {
                assert_mentions(&e, &["flip.pcd", "point"]);
            } else {
                assert_mentions(&e, &["flip.pcd", "binary_compressed"]);
            }
            caught += 1;
        }
    }
    assert!(caught > 30, "only {caught} of 300 flips detected");
}

#[test]
fn lying_sizes_in_compressed_pcd_header() {
    let dir = tempfile::tempdir().unwrap();
    let milk = std::fs::read(data("pointclouds/pcl_milk.pcd")).unwrap();
    let body = pcd_body(&milk);
    let compressed = u32::from_le_bytes(milk[body..body + 4].try_into().unwrap());
    let uncompressed = u32::from_le_bytes(milk[body + 4..body + 8].try_into().unwrap());
    assert_eq!(uncompressed, 13_704 * 12);

    let cases: [(&str, Vec<u8>, &[&str]); 6] = [
        (
            "big_c.pcd",
            with_u32(&milk, body, (milk.len() - body - 8) as u32 + 1),
            &["the header says", "compressed bytes but only", "truncated"],
        ),
        (
            "huge_c.pcd",
            with_u32(&milk, body, u32::MAX),
            &["4294967295 compressed bytes but only"],
        ),
        (
            "small_c.pcd",
            with_u32(&milk, body, compressed / 2),
            &[
                "says 44418 compressed bytes but 92749 follow",
                "is data, not zero padding",
            ],
        ),
        (
            "zero_c.pcd",
            with_u32(&milk, body, 0),
            &["says 0 compressed bytes but 92749 follow"],
        ),
        (
            "big_u.pcd",
            with_u32(&milk, body + 4, uncompressed + 4),
            &["says 164452 uncompressed bytes but 13704 points × 12 bytes need 164448"],
        ),
        (
            "small_u.pcd",
            with_u32(&milk, body + 4, uncompressed - 12),
            &["says 164436 uncompressed bytes"],
        ),
    ];
    for (name, bytes, parts) in cases {
        let path = write(dir.path(), name, &bytes);
        let msg = message(io::load_cloud(&path));
        assert_mentions(&msg, &[name]);
        assert_mentions(&msg, parts);
    }

    // A header that claims far more points than the stream could ever hold is
    // refused before anything is allocated.
    let mut bomb =
        b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 300000000\nDATA binary_compressed\n"
            .to_vec();
    bomb.extend_from_slice(&16u32.to_le_bytes());
    bomb.extend_from_slice(&3_600_000_000u32.to_le_bytes());
    bomb.extend_from_slice(&[0u8; 16]);
    let path = write(dir.path(), "bomb.pcd", &bomb);
    assert_mentions(
        &message(io::load_cloud(&path)),
        &["bomb.pcd", "cannot hold 3600000000"],
    );
    // Same for a PLY whose vertex count is a lie.
    let mut ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n\
                    property float x\nproperty float y\nproperty float z\nend_header\n"
        .to_vec();
    ply.extend_from_slice(&[0u8; 36]);
    let path = write(dir.path(), "lie.ply", &ply);
    assert_mentions(
        &message(io::load_cloud(&path)),
        &[
            "lie.ply",
            "element 'vertex' row 3 (of 4000000000), property 'x': needs 4 bytes, only 0 left",
        ],
    );
}

// ---------------------------------------------------------------------------
// STL detection and OBJ inputs tobj alone would mishandle.

#[test]
fn stl_kinds() {
    let dir = tempfile::tempdir().unwrap();
    // A binary STL whose header starts with "solid" is still binary.
    let mut base = std::fs::read(data("robots/ur5/meshes/ur5/collision/base.stl")).unwrap();
    base[..12].copy_from_slice(b"solid base  ");
    let path = write(dir.path(), "solid_header.stl", &base);
    assert_eq!(io::load_mesh(&path, 1.0).unwrap().triangles.len(), 578);
    // …and a truncated one is reported as both possibilities failing.
    let path = write(dir.path(), "solid_cut.stl", &base[..5000]);
    assert_mentions(
        &message(io::load_mesh(&path, 1.0)),
        &[
            "solid_cut.stl",
            "not a valid ASCII STL",
            "578 triangles = 28984 bytes",
        ],
    );
    // ASCII with a bare `solid` line and CRLF endings.
    let ascii = "solid\r\n facet normal 0 0 1\r\n  outer loop\r\n   vertex 0 0 0\r\n   vertex 1 0 0\r\n\
                 vertex 0 1 0\r\n  endloop\r\n endfacet\r\nendsolid\r\n";
    let path = write(dir.path(), "bare.stl", ascii.as_bytes());
    let m = io::load_mesh(&path, 2.0).unwrap();
    assert_eq!(m.triangles.len(), 1);
    assert_eq!(m.vertices[1], geom::Point3::new(2.0, 0.0, 0.0));
    // Malformed ASCII.
    let path = write(
        dir.path(),
        "bad.stl",
        b"solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0\n",
    );
    assert_mentions(
        &message(io::load_mesh(&path, 1.0)),
        &["bad.stl", "ASCII STL"],
    );
    // Short garbage.
    let path = write(dir.path(), "short.stl", b"hello");
    assert_mentions(
        &message(io::load_mesh(&path, 1.0)),
        &["short.stl", "too short for a binary STL"],
    );
}

#[test]
fn obj_inputs_that_trip_tobj() {
    use std::fmt::Write as _;
    let dir = tempfile::tempdir().unwrap();
    // `f 1/0/1` makes tobj compute usize::MAX * 2 (a panic in debug builds);
    // texture and normal references are not used, so this loads.
    let path = write(
        dir.path(),
        "vt0.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/0/1 2/0/1 3/0/1\nf -3//1 -2//1 -1//1\n",
    );
    let m = io::load_mesh(&path, 1.0).unwrap();
    assert_eq!(m.triangles, [[0, 1, 2], [0, 1, 2]]);
    // Groups, materials, lines, w and colours; a quad is fan-triangulated.
    let path = write(
        dir.path(),
        "mixed.obj",
        b"mtllib missing.mtl\no a\nv 0 0 0 2\nv 2 0 0 0.5 0.5 0.5\nv 2 2 0\nv 0 2 0\n\
          usemtl red\ng b\nf 1 2 3 4\nl 1 3\ns off\n",
    );
    let m = io::load_mesh(&path, 1.0).unwrap();
    assert_eq!(m.triangles, [[0, 1, 2], [0, 2, 3]]);
    assert_eq!(m.vertices[0], geom::Point3::new(0.0, 0.0, 0.0));
    assert_eq!(m.vertices[1], geom::Point3::new(2.0, 0.0, 0.0));
    let path = write(
        dir.path(),
        "w0.obj",
        b"v 1 1 1 0\nv 0 0 0\nv 1 0 0\nf 1 2 3\n",
    );
    assert_mentions(
        &message(io::load_mesh(&path, 1.0)),
        &["w0.obj:1:", "weight w = 0"],
    );
    // A face of more vertices than MAX_FACE_VERTICES (one of 200 000 took
    // minutes to triangulate); one at the limit loads. The same disc as an
    // OBJ and as an ASCII PLY: vertex lines, then the face's indices.
    for (n, ok) in [
        (io::MAX_FACE_VERTICES, true),
        (io::MAX_FACE_VERTICES + 1, false),
    ] {
        let disc = |vertex: &str, first: usize, face: String| {
            let mut text = String::new();
            for i in 0..n {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                writeln!(text, "{vertex}{} {} 0", a.cos(), a.sin()).unwrap();
            }
            text.push_str(&face);
            for i in first..first + n {
                write!(text, " {i}").unwrap();
            }
            text.push('\n');
            text
        };
        let obj = disc("v ", 1, "f".into());
        let ply = format!(
            "ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\n\
             property float z\nelement face 1\nproperty list ushort int vertex_indices\nend_header\n{}",
            disc("", 0, n.to_string())
        );
        for (name, text, says) in [
            ("disc.obj", obj, "face has 4097 vertices"),
            ("disc.ply", ply, "face 0 has 4097 vertices"),
        ] {
            let got = io::load_mesh(&write(dir.path(), name, text.as_bytes()), 1.0);
            if ok {
                assert_eq!(got.unwrap().triangles.len(), n - 2, "{name}");
            } else {
                assert_mentions(&message(got), &[name, says, "4096"]);
            }
        }
    }
}

// ---------------------------------------------------------------------------
// Writers leave nothing behind on bad input.

#[test]
fn writers_check_before_touching_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.ply");
    let x = [1.0f32, 2.0];
    let short = [1.0f32];
    for (names, columns, part) in [
        (
            &["x", "y"][..],
            &[&x[..], &short[..]][..],
            "column 'y' has 1 values but column 'x' has 2",
        ),
        (&["x"], &[&x[..], &x[..]], "1 property names but 2 columns"),
        (&["x", "x"], &[&x[..], &x[..]], "'x' appears twice"),
        (&["a b"], &[&x[..]], "not a PLY word"),
        (&[], &[], "no columns"),
    ] {
        let msg = message(io::write_ply_vertices_file(&path, names, columns));
        assert_mentions(&msg, &["t.ply", part]);
        assert!(!path.exists());
        let mut buf = Vec::new();
        let e = io::write_ply_vertices(&mut buf, names, columns).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
        assert!(buf.is_empty());
    }
    // Built field by field: TriMesh::new would refuse it.
    let mut bad = TriMesh {
        vertices: vec![geom::Point3::new(0.0, f64::NAN, 0.0); 3],
        triangles: vec![[0, 1, 2]],
    };
    let obj = dir.path().join("m.obj");
    assert_mentions(
        &message(io::write_mesh_ply(&path, &bad)),
        &["t.ply", "vertex 0"],
    );
    assert_mentions(
        &message(io::write_mesh_obj(&obj, &bad)),
        &["m.obj", "not finite"],
    );
    bad.vertices = vec![geom::Point3::new(1e39, 0.0, 0.0); 3];
    assert_mentions(&message(io::write_mesh_ply(&path, &bad)), &["32-bit float"]);
    bad.vertices = vec![geom::Point3::origin(); 2];
    assert_mentions(
        &message(io::write_mesh_obj(&obj, &bad)),
        &["triangle 0 refers to a vertex beyond the 2"],
    );
    assert!(!path.exists() && !obj.exists());
    // An unwritable destination is an I/O error naming it.
    let e = io::write_mesh_obj(
        &dir.path().join("no/such/dir.obj"),
        &io::load_mesh(&data("meshes/cinder_block_meters.obj"), 1.0).unwrap(),
    )
    .unwrap_err();
    assert!(matches!(e, SceneError::Write { .. }));
    assert_mentions(&e.to_string(), &["dir.obj", "cannot write"]);
}

// ---------------------------------------------------------------------------
// Random damage to small files of every kind: errors, never panics.

fn fixtures() -> Vec<(&'static str, Vec<u8>)> {
    let mut stl = std::fs::read(data("robots/ur5/meshes/ur5/collision/wrist_3.stl")).unwrap();
    stl.truncate(84 + 50 * 6);
    stl[80..84].copy_from_slice(&6u32.to_le_bytes());
    vec![
        ("a.ply", ply_ascii()),
        ("le.ply", ply_binary(false)),
        ("be.ply", ply_binary(true)),
        ("a.pcd", pcd_ascii()),
        ("b.pcd", pcd_binary()),
        ("c.pcd", pcd_compressed()),
        (
            "t.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2/1 4/1 3/1\n".to_vec(),
        ),
        ("b.stl", stl),
        (
            "a.stl",
            b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n\
              endloop\nendfacet\nendsolid t\n"
                .to_vec(),
        ),
        ("t.csv", b"x,y,z,label\n1,2,3,4\n5,6,7,8\n".to_vec()),
        ("t.pts", b"2\n1 2 3 4\n5 6 7 8\n".to_vec()),
    ]
}

fn load_everything(path: &Path) {
    for r in [
        load_any(path),
        io::load_cloud_or_mesh_vertices(path).map(|_| ()),
        if path.extension().is_some_and(|e| e == "ply") {
            io::load_mesh(path, 1.0).map(|_| ())
        } else {
            Ok(())
        },
        if path.extension().is_some_and(|e| e == "ply") {
            io::read_ply_vertices(path).map(|_| ())
        } else {
            Ok(())
        },
    ] {
        if let Err(e) = r {
            let name = path.file_name().unwrap().to_str().unwrap();
            assert!(e.to_string().contains(name), "{e} does not name {name}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn damaged_files_never_panic(
        which in 0usize..11,
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6),
        cut in prop::option::of(any::<prop::sample::Index>()),
    ) {
        let (name, mut bytes) = fixtures().swap_remove(which);
        for (at, value) in edits {
            let i = at.index(bytes.len());
            bytes[i] = value;
        }
        if let Some(cut) = cut {
            bytes.truncate(cut.index(bytes.len()));
        }
        let dir = tempfile::tempdir().unwrap();
        let path: PathBuf = write(dir.path(), name, &bytes);
        load_everything(&path);
    }
}

#[test]
fn undamaged_fixtures_load() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in fixtures() {
        let path = write(dir.path(), name, &bytes);
        load_any(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}

#[test]
fn absurd_header_numbers_do_not_hang_or_overflow() {
    let dir = tempfile::tempdir().unwrap();
    // COUNT × SIZE beyond usize.
    let path = write(
        dir.path(),
        "count.pcd",
        b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 18446744073709551615\nPOINTS 1\n\
          DATA binary\n",
    );
    assert_mentions(
        &message(io::load_cloud(&path)),
        &["count.pcd:4:", "overflows"],
    );
    // WIDTH × HEIGHT beyond usize.
    let path = write(
        dir.path(),
        "wh.pcd",
        b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 18446744073709551615\nHEIGHT 2\nDATA ascii\n",
    );
    assert_mentions(&message(io::load_cloud(&path)), &["wh.pcd:4:", "overflows"]);
    // Elements with no properties and enormous counts are nothing to read.
    let path = write(
        dir.path(),
        "empty_rows.ply",
        b"ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\n\
          element junk 18446744073709551615\nend_header\n",
    );
    assert_mentions(
        &message(io::load_cloud(&path)),
        &["empty_rows.ply", "no property 'x'"],
    );
    // A list count far beyond the data.
    let mut ply = b"ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\n\
                    property float y\nproperty float z\nelement face 1\n\
                    property list uint uint vertex_indices\nend_header\n"
        .to_vec();
    ply.extend_from_slice(&[0u8; 12]);
    ply.extend_from_slice(&u32::MAX.to_be_bytes());
    let path = write(dir.path(), "list.ply", &ply);
    assert_mentions(
        &message(io::load_mesh(&path, 1.0)),
        &[
            "list.ply",
            "list 'vertex_indices' of 4294967295 indices",
            "needs 17179869180 bytes, only 0 left",
        ],
    );
}

/// Coordinates beyond ±MAX_COORDINATE_M (as scenario shapes) and scenes of
/// no area are errors, not scenes of 0 samples.
#[test]
fn far_coordinates_and_arealess_meshes_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let far = write(
        dir.path(),
        "far.obj",
        b"v 1e30 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    assert_mentions(
        &message(io::load_mesh(&far, 1.0)),
        &["far.obj", "vertex 0", "beyond", "1e7"],
    );
    // The limit applies after scaling.
    let unit = write(
        dir.path(),
        "unit.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    assert!(io::load_mesh(&unit, 1e6).is_ok());
    assert_mentions(
        &message(io::load_mesh(&unit, 1e12)),
        &["unit.obj", "beyond"],
    );
    // A scene of no area: the file reads, the scene is refused.
    let flat = write(
        dir.path(),
        "flat.obj",
        b"v 0 0 0\nv 0 0 0\nv 0 0 0\nf 1 2 3\n",
    );
    for (mesh, what) in [
        (io::load_mesh(&unit, 1e-300).unwrap(), "scaled to nothing"),
        (io::load_mesh(&flat, 1.0).unwrap(), "three equal vertices"),
    ] {
        let e = scene::Scene::from_mesh(
            "flat",
            mesh,
            scene::default_materials(),
            scene::MaterialId(0),
        )
        .map(|_| ())
        .expect_err(what);
        assert_mentions(&e.to_string(), &["flat", "no area", "degenerate"]);
    }
    let cloud = write(dir.path(), "far.txt", b"1 0 0\n1e300 0 0\n0 1 0\n");
    assert_mentions(
        &message(io::load_cloud(&cloud)),
        &["far.txt", "point 1", "beyond"],
    );
}
