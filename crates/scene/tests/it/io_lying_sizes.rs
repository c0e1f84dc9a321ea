//! Size fields must match the data exactly (issue 8 §2): a PLY element count,
//! PCD `POINTS` / `WIDTH × HEIGHT`, PCD compressed size or binary STL triangle
//! count that is smaller than the data is an error naming the file, the place
//! and what was declared against what was found, never a silent truncation; a
//! count far larger than the file could hold is an error before anything is
//! allocated for it.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "test helpers outside #[test] functions fail the test on any error"
)]

use crate::io_fixtures;

use io_fixtures::{data, write};
use scene::SceneError;
use scene::io;
use std::fmt::Write as _;
use std::path::Path;

/// The error's message; fails the test when the call succeeded.
#[track_caller]
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

/// Every reader that accepts a `.ply` file must refuse `path` with a message
/// holding `parts`.
#[track_caller]
fn every_ply_reader_refuses(path: &Path, parts: &[&str]) {
    for msg in [
        message(io::load_cloud(path)),
        message(io::load_cloud_or_mesh_vertices(path)),
        message(io::read_ply_vertices(path)),
    ] {
        assert_mentions(&msg, parts);
    }
}

/// `n` distinct points on a helix (float coordinates exact in f32).
fn helix(n: usize) -> [Vec<f32>; 3] {
    let t: Vec<f32> = (0..n).map(|i| i as f32 * 0.25).collect();
    [
        t.iter().map(|t| (t * 0.5).cos()).collect(),
        t.iter().map(|t| (t * 0.5).sin()).collect(),
        t.clone(),
    ]
}

/// Replace the first occurrence of `from` in `bytes` (a header) by `to`.
fn patch(bytes: &[u8], from: &str, to: &str) -> Vec<u8> {
    let at = bytes
        .windows(from.len())
        .position(|w| w == from.as_bytes())
        .unwrap_or_else(|| panic!("{from:?} not found"));
    let mut out = bytes[..at].to_vec();
    out.extend_from_slice(to.as_bytes());
    out.extend_from_slice(&bytes[at + from.len()..]);
    out
}

// ---------------------------------------------------------------------------
// PLY

#[test]
fn ply_binary_vertex_count_smaller_than_the_data() {
    // The case: 51 642 points written, the header says 100.
    let dir = tempfile::tempdir().unwrap();
    let n = 51_642;
    let [x, y, z] = helix(n);
    let mut ply = Vec::new();
    io::write_ply_vertices(&mut ply, &["x", "y", "z"], &[&x, &y, &z]).unwrap();
    let honest = write(dir.path(), "honest.ply", &ply);
    assert_eq!(io::load_cloud(&honest).unwrap().points.len(), n);

    let lie = patch(
        &ply,
        &format!("element vertex {n}\n"),
        "element vertex 100\n",
    );
    let body = lie.len() - 12 * n;
    let path = write(dir.path(), "scan.ply", &lie);
    // 51 542 rows of 12 bytes are left over, starting right after row 99.
    every_ply_reader_refuses(
        &path,
        &[
            "scan.ply",
            "618504 bytes of data after the declared elements",
            "= 51542 more 'vertex' rows of 12 bytes",
            "the header declares 100 'vertex' rows",
            &format!("end at byte {} of {}", body + 1200, lie.len()),
        ],
    );

    // Big-endian, with a face element: one trailing byte is enough.
    let mut be = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\n\
                   property float y\nproperty float z\nelement face 1\n\
                   property list uchar int vertex_indices\nend_header\n"
        .to_vec();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        be.extend_from_slice(&v.to_be_bytes());
    }
    be.push(3);
    for i in [0i32, 1, 2] {
        be.extend_from_slice(&i.to_be_bytes());
    }
    let ok = write(dir.path(), "tri.ply", &be);
    assert_eq!(io::load_mesh(&ok, 1.0).unwrap().triangles, [[0, 1, 2]]);
    be.push(0);
    let path = write(dir.path(), "tri_plus.ply", &be);
    let parts = [
        "tri_plus.ply",
        "1 bytes of data after the declared elements",
        "3 'vertex' rows, 1 'face' rows",
    ];
    every_ply_reader_refuses(&path, &parts);
    assert_mentions(&message(io::load_mesh(&path, 1.0)), &parts);
}

#[test]
fn ply_ascii_counts_smaller_than_the_data() {
    let dir = tempfile::tempdir().unwrap();
    let header = |vertices: usize, faces: usize| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex {vertices}\nproperty float x\n\
             property float y\nproperty float z\nelement face {faces}\n\
             property list uchar int vertex_indices\nend_header\n"
        )
    };
    let mut rows = String::new();
    for i in 0..200 {
        writeln!(rows, "{i} {} 0", i % 7).unwrap();
    }
    // 200 vertex rows, the header declares 100 and no faces: 100 rows left
    // over, the first on line 9 + 100 + 1 (the header has 9 lines).
    let path = write(
        dir.path(),
        "a.ply",
        format!("{}{rows}", header(100, 0)).as_bytes(),
    );
    every_ply_reader_refuses(
        &path,
        &[
            "a.ply:110:",
            "100 more non-blank lines after the declared elements",
            "100 'vertex' rows, 0 'face' rows",
        ],
    );
    // With all 200 declared it loads (blank trailing lines are fine).
    let path = write(
        dir.path(),
        "all.ply",
        format!("{}{rows}\n\n  \n", header(200, 0)).as_bytes(),
    );
    assert_eq!(io::read_ply_vertices(&path).unwrap().len(), 200);

    // A face too many: the second face row is line 9 + 3 + 2.
    let text = format!("{}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n", header(3, 1));
    let path = write(dir.path(), "face.ply", text.as_bytes());
    let msg = message(io::load_mesh(&path, 1.0));
    assert_mentions(
        &msg,
        &[
            "face.ply:14:",
            "1 more non-blank line after",
            "3 'vertex' rows, 1 'face' rows",
        ],
    );
}

#[test]
fn ply_counts_larger_than_the_data() {
    // Already errors before this issue; kept as a check of both directions.
    let dir = tempfile::tempdir().unwrap();
    let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                property float z\nend_header\n0 0 0\n1 0 0\n";
    let path = write(dir.path(), "short.ply", text.as_bytes());
    every_ply_reader_refuses(
        &path,
        &[
            "short.ply",
            "file ends in element 'vertex' after 2 of 3 rows",
        ],
    );
    let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
                    property float y\nproperty float z\nend_header\n"
        .to_vec();
    bin.extend_from_slice(&[0u8; 24]);
    let path = write(dir.path(), "short_bin.ply", &bin);
    every_ply_reader_refuses(
        &path,
        &[
            "short_bin.ply",
            "element 'vertex' row 2 (of 3), property 'x': needs 4 bytes, only 0 left",
        ],
    );
}

// ---------------------------------------------------------------------------
// PCD

fn pcd_header(points: &str, data: &str) -> String {
    format!(
        "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n\
         {points}\nVIEWPOINT 0 0 0 1 0 0 0\nDATA {data}\n"
    )
}

#[test]
fn pcd_ascii_points_smaller_than_the_data() {
    let dir = tempfile::tempdir().unwrap();
    let rows = "0 0 0\n1 0 0\n2 0 0\n3 0 0\n4 0 0\n";
    let ok = write(
        dir.path(),
        "ok.pcd",
        format!(
            "{}{rows}\n",
            pcd_header("WIDTH 5\nHEIGHT 1\nPOINTS 5", "ascii")
        )
        .as_bytes(),
    );
    assert_eq!(io::load_cloud(&ok).unwrap().points.len(), 5);
    // POINTS 3 (and WIDTH 3) for five rows; the header has 11 lines.
    let path = write(
        dir.path(),
        "p3.pcd",
        format!(
            "{}{rows}",
            pcd_header("WIDTH 3\nHEIGHT 1\nPOINTS 3", "ascii")
        )
        .as_bytes(),
    );
    assert_mentions(
        &message(io::load_cloud(&path)),
        &[
            "p3.pcd:15:",
            "2 more non-blank lines after the 3 points the header declares (POINTS 3)",
        ],
    );
    // No POINTS line (10 header lines): WIDTH × HEIGHT = 2 × 2 for five rows.
    let path = write(
        dir.path(),
        "wh.pcd",
        format!("{}{rows}", pcd_header("WIDTH 2\nHEIGHT 2", "ascii")).as_bytes(),
    );
    assert_mentions(
        &message(io::load_cloud(&path)),
        &["wh.pcd:15:", "1 more non-blank line after the 4 points"],
    );
}

#[test]
fn pcd_binary_points_smaller_than_the_data() {
    let dir = tempfile::tempdir().unwrap();
    let head = pcd_header("WIDTH 4\nHEIGHT 1\nPOINTS 4", "binary");
    let mut bytes = head.clone().into_bytes();
    for i in 0..6 {
        for c in [i as f32, 0.5, -1.0] {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    let path = write(dir.path(), "b.pcd", &bytes);
    assert_mentions(
        &message(io::load_cloud(&path)),
        &[
            "b.pcd",
            "POINTS 4 × 12 bytes per point = 48 bytes after the header, but the file has 72",
            "24 bytes after the last declared point (= 2 more points",
            &format!("from byte {}", head.len() + 48),
        ],
    );
    // One stray byte.
    bytes.truncate(head.len() + 48);
    let ok = write(dir.path(), "ok.pcd", &bytes);
    assert_eq!(io::load_cloud(&ok).unwrap().points.len(), 4);
    bytes.push(b'\n');
    let path = write(dir.path(), "nl.pcd", &bytes);
    assert_mentions(
        &message(io::load_cloud(&path)),
        &["nl.pcd", "1 bytes after the last declared point"],
    );
}

/// Offset of the first byte after the `DATA` line.
fn pcd_body(bytes: &[u8]) -> usize {
    let data = bytes.windows(5).position(|w| w == b"DATA ").unwrap();
    data + bytes[data..].iter().position(|&b| b == b'\n').unwrap() + 1
}

#[test]
fn pcd_compressed_sizes_smaller_than_the_data() {
    let dir = tempfile::tempdir().unwrap();
    let milk = std::fs::read(data("pointclouds/pcl_milk.pcd")).unwrap();
    let body = pcd_body(&milk);
    let compressed = u32::from_le_bytes(milk[body..body + 4].try_into().unwrap()) as usize;
    let end = body + 8 + compressed;
    // PCL's own file carries zero padding after the block: accepted, and the
    // same cloud as without it.
    assert!(milk.len() > end && milk[end..].iter().all(|&b| b == 0));
    let bare = write(dir.path(), "bare.pcd", &milk[..end]);
    let reference = io::load_cloud(&bare).unwrap();
    assert_eq!(
        io::load_cloud(&data("pointclouds/pcl_milk.pcd")).unwrap(),
        reference
    );
    // Data after the block: a second copy of the stream appended.
    let mut twice = milk[..end].to_vec();
    twice.extend_from_slice(&milk[body + 8..end]);
    let path = write(dir.path(), "twice.pcd", &twice);
    assert_mentions(
        &message(io::load_cloud(&path)),
        &[
            "twice.pcd",
            &format!(
                "says {compressed} compressed bytes but {} follow",
                2 * compressed
            ),
            &format!("byte {end} (after the compressed block) is data"),
        ],
    );
    // POINTS smaller than the data the (consistent) sizes describe: the LZF
    // stream does not fit the smaller output.
    let small = patch(&milk, "POINTS 13704", "POINTS 13000");
    let small = patch(&small, "WIDTH 13704", "WIDTH 13000");
    let small = {
        let mut b = small;
        let at = pcd_body(&b) + 4;
        b[at..at + 4].copy_from_slice(&(13_000u32 * 12).to_le_bytes());
        b
    };
    let path = write(dir.path(), "fewer.pcd", &small);
    assert_mentions(
        &message(io::load_cloud(&path)),
        &["fewer.pcd", "LZF decompression", "into 156000 failed"],
    );
}

// ---------------------------------------------------------------------------
// STL

#[test]
fn binary_stl_count_must_match_the_file_size() {
    let dir = tempfile::tempdir().unwrap();
    let base = std::fs::read(data("robots/ur5/meshes/ur5/collision/base.stl")).unwrap();
    assert_eq!(base.len(), 84 + 50 * 578);
    // The count says 500 of the 578 triangles.
    let mut lie = base.clone();
    lie[80..84].copy_from_slice(&500u32.to_le_bytes());
    let path = write(dir.path(), "base500.stl", &lie);
    for msg in [
        message(io::load_mesh(&path, 1.0)),
        message(io::load_cloud_or_mesh_vertices(&path)),
    ] {
        assert_mentions(
            &msg,
            &[
                "base500.stl",
                "the header declares 500 triangles = 25084 bytes, the file has 28984",
                "3900 bytes after the last declared triangle, = 78 more triangles",
            ],
        );
    }
    // Trailing bytes that are not whole triangles.
    let mut tail = base.clone();
    tail.extend_from_slice(b"\n\n");
    let path = write(dir.path(), "tail.stl", &tail);
    assert_mentions(
        &message(io::load_mesh(&path, 1.0)),
        &["tail.stl", "2 bytes after the last declared triangle)"],
    );
    // A count larger than the data (already an error).
    lie[80..84].copy_from_slice(&600u32.to_le_bytes());
    let path = write(dir.path(), "base600.stl", &lie);
    assert_mentions(
        &message(io::load_mesh(&path, 1.0)),
        &["base600.stl", "truncated", "600 triangles = 30084 bytes"],
    );
}

// ---------------------------------------------------------------------------
// Absurd counts in small files: errors before any allocation sized by them.

#[test]
fn huge_declared_counts_in_small_files() {
    let dir = tempfile::tempdir().unwrap();
    // 4e9 and 1e18: the second would overflow `Vec::with_capacity` (a panic)
    // if any reader sized a buffer from the header.
    for count in ["4000000000", "1000000000000000000"] {
        let cases: Vec<(&str, Vec<u8>, &str)> = vec![
            (
                "bin.ply",
                {
                    let mut b = format!(
                        "ply\nformat binary_little_endian 1.0\nelement vertex {count}\n\
                         property float x\nproperty float y\nproperty float z\n\
                         property list uchar int tags\nend_header\n"
                    )
                    .into_bytes();
                    b.resize(b.len() + 64, 0);
                    b
                },
                "binary data truncated or corrupt: element 'vertex' row 4",
            ),
            (
                "ascii.ply",
                format!(
                    "ply\nformat ascii 1.0\nelement vertex {count}\nproperty float x\n\
                     property float y\nproperty float z\nend_header\n0 0 0\n1 1 1\n"
                )
                .into_bytes(),
                "file ends in element 'vertex' after 2 of",
            ),
            (
                "faces.ply",
                format!(
                    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
                     property float y\nproperty float z\nelement face {count}\n\
                     property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n\
                     3 0 1 2\n"
                )
                .into_bytes(),
                "file ends in element 'face' after 1 of",
            ),
            (
                "ascii.pcd",
                format!("{}0 0 0\n", pcd_header(&format!("POINTS {count}"), "ascii")).into_bytes(),
                "after DATA, found 1 (file truncated?)",
            ),
            (
                "bin.pcd",
                {
                    let mut b = pcd_header(&format!("POINTS {count}"), "binary").into_bytes();
                    b.resize(b.len() + 64, 0);
                    b
                },
                "binary data truncated",
            ),
        ];
        for (name, bytes, part) in cases {
            assert!(bytes.len() < 400, "{name}: {} bytes", bytes.len());
            let path = write(dir.path(), name, &bytes);
            let msg = if name == "faces.ply" {
                message(io::load_mesh(&path, 1.0))
            } else {
                message(io::load_cloud(&path))
            };
            assert_mentions(&msg, &[name, count, part]);
        }
    }
    // An ASCII PCD whose skipped field claims 2^32 - 1 values per point
    // (found by tests/fuzz.rs: the reader reserved 2^32 + 2 token slots, a
    // 64 GiB allocation, and aborted).
    let path = write(
        dir.path(),
        "count.pcd",
        b"FIELDS x y z rgb\nSIZE 4 4 4 1\nTYPE F F F U\nCOUNT 1 1 1 4294967295\nPOINTS 1\n\
          DATA ascii\n1 2 3 4\n",
    );
    assert_mentions(
        &message(io::load_cloud(&path)),
        &[
            "count.pcd:7:",
            "point 0: found 4 values, expected 4294967298",
        ],
    );
    // A binary STL claiming u32::MAX triangles in 200 bytes.
    let mut stl = vec![0u8; 200];
    stl[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
    let path = write(dir.path(), "huge.stl", &stl);
    assert_mentions(
        &message(io::load_mesh(&path, 1.0)),
        &["huge.stl", "binary STL truncated", "4294967295 triangles"],
    );
    // A .pts count line of 4e9 over two points.
    let path = write(dir.path(), "huge.pts", b"4000000000\n1 2 3\n4 5 6\n");
    assert_mentions(
        &message(io::load_cloud(&path)),
        &[
            "huge.pts:1:",
            "declares 4000000000 points but the file has 2",
        ],
    );
}

/// Issue 48: an ASCII PLY whose `format` line names another version was
/// read; a face of 255 vertices (the most a `uchar` count holds) is meant:
/// faces of up to `MAX_FACE_VERTICES` are read and fan-triangulated, and
/// the vertex tables `sld` reads check the face section whole.
#[test]
fn ply_format_versions_and_large_faces() {
    let dir = tempfile::tempdir().unwrap();
    for version in ["7.5", "banana", "2"] {
        let path = write(
            dir.path(),
            &format!("v{version}.ply"),
            format!(
                "ply\nformat ascii {version}\nelement vertex 3\nproperty float x\n\
                 property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
            )
            .as_bytes(),
        );
        every_ply_reader_refuses(&path, &[&format!("v{version}.ply:2"), "expected 1.0"]);
    }
    let mut text = String::from(
        "ply\nformat ascii 1.0\nelement vertex 255\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
    );
    for i in 0..255 {
        let a = f64::from(i) * std::f64::consts::TAU / 255.0;
        writeln!(text, "{} {} 0", a.cos(), a.sin()).unwrap();
    }
    text.push_str("255");
    for i in 0..255 {
        write!(text, " {i}").unwrap();
    }
    text.push('\n');
    let path = write(dir.path(), "fan.ply", text.as_bytes());
    assert_eq!(io::read_ply_vertices(&path).unwrap().len(), 255);
    // One value short of the 255 declared: refused by line.
    let short = text.replace(" 254\n", "\n");
    let path = write(dir.path(), "short.ply", short.as_bytes());
    every_ply_reader_refuses(&path, &["short.ply", "declares 255 items"]);
}
