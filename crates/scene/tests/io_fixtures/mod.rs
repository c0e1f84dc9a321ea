//! Hand-written fixtures shared by the `io_*` integration tests: one PLY dataset
//! in three encodings, one organized PCD cloud in three encodings, and helpers.
#![allow(
    dead_code,
    reason = "each test file uses a different subset of these helpers"
)]
#![allow(
    clippy::unwrap_used,
    reason = "test helpers fail the test on any error"
)]

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A file of the repository's `data/` folder.
pub fn data(rel: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data")).join(rel)
}

/// Write `bytes` to `dir/name`.
pub fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

// ---------------------------------------------------------------------------
// PLY: one dataset in the three encodings.
//
// vertex: x y z (float), nx ny nz (double), intensity (uchar), label (int),
//         a list property `tags` (uchar count, short items) that is skipped
// face:   a quad, a triangle and a pentagon (uchar count, int indices), plus a
//         `flags` ushort after the list
// edge:   an extra element (int int char) that is skipped

/// Vertex rows: x y z nx ny nz intensity label tags.
/// One vertex row: position, normal, intensity, label, tags.
pub type VertexRow = ([f32; 3], [f64; 3], u8, i32, &'static [i16]);

pub const VERTICES: [VertexRow; 5] = [
    ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 10, -3, &[]),
    ([1.5, 0.0, 0.0], [0.0, 0.0, 1.0], 20, 7, &[1, -2]),
    ([1.5, 2.25, 0.0], [0.0, 1.0, 0.0], 30, 7, &[300]),
    ([0.0, 2.25, -0.125], [1.0, 0.0, 0.0], 255, 0, &[]),
    (
        [0.75, 3.0, 1.0e-3],
        [0.6, 0.8, 0.0],
        0,
        2_000_000,
        &[-1, -1, -1],
    ),
];
/// Faces (index lists) and their flags.
pub const FACES: [(&[i32], u16); 3] = [
    (&[0, 1, 2, 3], 1),
    (&[3, 2, 4], 65535),
    (&[0, 1, 2, 4, 3], 0),
];
pub const EDGES: [(i32, i32, i8); 2] = [(0, 1, -1), (3, 4, 5)];

pub fn ply_header(format: &str) -> String {
    format!(
        "ply\r\nformat {format} 1.0\ncomment hand-written fixture\nobj_info not a real scan\n\
         element vertex 5\nproperty float x\nproperty float32 y\nproperty float z\n\
         property double nx\nproperty float64 ny\nproperty double nz\n\
         property uchar intensity\nproperty int32 label\nproperty list uint8 int16 tags\n\
         element face 3\nproperty list uchar int vertex_indices\nproperty ushort flags\n\
         element edge 2\nproperty int vertex1\nproperty int vertex2\nproperty char crease\n\
         end_header\n"
    )
}

pub fn ply_ascii() -> Vec<u8> {
    let mut s = ply_header("ascii");
    for (p, n, i, l, tags) in VERTICES {
        write!(
            s,
            "{} {} {} {} {} {} {i} {l} {}",
            p[0],
            p[1],
            p[2],
            n[0],
            n[1],
            n[2],
            tags.len()
        )
        .unwrap();
        for t in tags {
            write!(s, " {t}").unwrap();
        }
        s.push('\n');
    }
    // A blank line between rows is tolerated.
    s.push('\n');
    for (f, flags) in FACES {
        write!(s, "{}", f.len()).unwrap();
        for i in f {
            write!(s, "  {i}").unwrap();
        }
        write!(s, " {flags}\r\n").unwrap();
    }
    for (a, b, c) in EDGES {
        writeln!(s, "{a} {b} {c}").unwrap();
    }
    s.into_bytes()
}

pub fn ply_binary(big_endian: bool) -> Vec<u8> {
    let mut b = ply_header(if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    })
    .into_bytes();
    macro_rules! put {
        ($v:expr) => {
            if big_endian {
                b.extend_from_slice(&$v.to_be_bytes())
            } else {
                b.extend_from_slice(&$v.to_le_bytes())
            }
        };
    }
    for (p, n, i, l, tags) in VERTICES {
        for c in p {
            put!(c);
        }
        for c in n {
            put!(c);
        }
        put!(i);
        put!(l);
        put!(tags.len() as u8);
        for t in tags {
            put!(*t);
        }
    }
    for (f, flags) in FACES {
        put!(f.len() as u8);
        for i in f {
            put!(*i);
        }
        put!(flags);
    }
    for (x, y, c) in EDGES {
        put!(x);
        put!(y);
        put!(c);
    }
    b
}

// ---------------------------------------------------------------------------
// PCD: one organized 3×2 cloud in the three encodings.

/// (x, y, z, normal, label, intensity) per pixel; pixel 2 is invalid (NaN).
pub fn pcd_points() -> Vec<([f32; 3], [f32; 3], u32, f32)> {
    vec![
        ([0.5, -0.25, 1.0], [0.0, 0.0, -1.0], 1, 0.5),
        ([0.5, 0.0, 1.25], [0.0, 0.6, -0.8], 20, 1.0),
        ([f32::NAN, f32::NAN, f32::NAN], [f32::NAN; 3], 0, 0.0),
        ([-0.125, 0.0, 2.0], [1.0, 0.0, 0.0], 30, 2.0),
        ([0.0, 0.0, 0.75], [0.0, 1.0, 0.0], 20, 4.0),
        ([3.0, -1.0, 9.5], [0.0, 0.0, 1.0], 4_000_000_000, 8.0),
    ]
}

/// Fields: x y z (F4), normal_x…z (F4), label (U4), intensity (F4), rgb (U4,
/// ignored), `_` padding of 3 bytes (U1 × 3, ignored).
pub fn pcd_header(data: &str) -> String {
    format!(
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n\
         FIELDS x y z normal_x normal_y normal_z label intensity rgb _\n\
         SIZE 4 4 4 4 4 4 4 4 4 1\nTYPE F F F F F F U F U U\nCOUNT 1 1 1 1 1 1 1 1 1 3\n\
         WIDTH 3\nHEIGHT 2\nVIEWPOINT 1 2 3 0 0 0 1\nPOINTS 6\nDATA {data}\n"
    )
}

/// The fields of point `p` as little-endian bytes, one entry per field.
pub fn pcd_field_bytes(p: &([f32; 3], [f32; 3], u32, f32)) -> Vec<Vec<u8>> {
    let mut f: Vec<Vec<u8>> = Vec::new();
    for c in p.0.iter().chain(&p.1) {
        f.push(c.to_le_bytes().to_vec());
    }
    f.push(p.2.to_le_bytes().to_vec());
    f.push(p.3.to_le_bytes().to_vec());
    f.push(0x00ff_8000u32.to_le_bytes().to_vec());
    f.push(vec![0xAA, 0xBB, 0xCC]);
    f
}

pub fn pcd_ascii() -> Vec<u8> {
    let mut s = pcd_header("ascii");
    for p in pcd_points() {
        let v: Vec<String> = p.0.iter().chain(&p.1).map(|c| format!("{c}")).collect();
        writeln!(s, "{} {} {} 4.2108e+06 1 2 3", v.join(" "), p.2, p.3).unwrap();
    }
    s.into_bytes()
}

pub fn pcd_binary() -> Vec<u8> {
    let mut b = pcd_header("binary").into_bytes();
    for p in pcd_points() {
        for f in pcd_field_bytes(&p) {
            b.extend_from_slice(&f);
        }
    }
    b
}

/// Structure-of-arrays layout, LZF-compressed, with the two size words.
pub fn pcd_compressed() -> Vec<u8> {
    let points = pcd_points();
    let per_point: Vec<Vec<Vec<u8>>> = points.iter().map(pcd_field_bytes).collect();
    let mut soa = Vec::new();
    for field in 0..per_point[0].len() {
        for p in &per_point {
            soa.extend_from_slice(&p[field]);
        }
    }
    let packed = lzf::compress(&soa).unwrap();
    let mut b = pcd_header("binary_compressed").into_bytes();
    b.extend_from_slice(&(packed.len() as u32).to_le_bytes());
    b.extend_from_slice(&(soa.len() as u32).to_le_bytes());
    b.extend_from_slice(&packed);
    b
}
