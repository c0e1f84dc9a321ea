//! Byte-level fuzzing of every scene reader (issue 8 §2): PLY (ASCII, both
//! binary orders), PCD (ascii, binary, binary_compressed), OBJ, STL (binary and
//! ASCII), text clouds (.csv .xyz .txt .pts) and rays files. Small real and
//! generated files are damaged byte by byte (flips, inserts, deletes, cuts,
//! header numbers replaced by huge, negative or NaN values, repeated runs)
//! or replaced by random bytes, then loaded through every entry point that
//! accepts them. Nothing may panic, and every `Ok` must be self-consistent and
//! agree with the file's own size fields (no silent truncation).
//!
//! `cargo test -p scene --test it fuzz` runs 512 cases per format;
//! `cargo test -p scene --test it fuzz -- --ignored` runs 20 000 per format.
//! The mutator and runner are `testkit::fuzz` (`FUZZ_SEED=<n>` replays a run).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "test helpers fail the test on any error"
)]

use crate::io_fixtures;

use io_fixtures::{data, pcd_ascii, pcd_binary, pcd_compressed, ply_ascii, ply_binary};
use proptest::prelude::*;
use scene::io;
use scene::{PointCloud, SceneError, TriMesh};
use std::path::Path;
use testkit::{CASES, LONG_CASES, Run, fuzz, names_source};

// ---------------------------------------------------------------------------
// Seeds

fn read(rel: &str) -> Vec<u8> {
    std::fs::read(data(rel)).unwrap()
}

/// The first `n` points of PCL's ASCII bunny, with the header made to match.
fn bunny(n: usize) -> Vec<u8> {
    let text = String::from_utf8(read("pointclouds/pcl_bun0.pcd")).unwrap();
    let mut out = String::new();
    let mut points = 0;
    for line in text.lines() {
        let line = match line.split_whitespace().next() {
            Some("WIDTH") => format!("WIDTH {n}"),
            Some("POINTS") => format!("POINTS {n}"),
            _ => line.to_owned(),
        };
        let is_point = line.starts_with(|c: char| c == '-' || c.is_ascii_digit());
        if is_point {
            if points == n {
                break;
            }
            points += 1;
        }
        out.push_str(&line);
        out.push('\n');
    }
    out.into_bytes()
}

/// A real binary STL cut to its first `n` triangles (count field fixed).
fn stl_binary(n: u32) -> Vec<u8> {
    let mut stl = read("robots/ur5/meshes/ur5/collision/wrist_3.stl");
    stl.truncate(84 + 50 * n as usize);
    stl[80..84].copy_from_slice(&n.to_le_bytes());
    stl
}

fn ply_seeds() -> Vec<(&'static str, Vec<u8>)> {
    let dir = tempfile::tempdir().unwrap();
    let block = io::load_mesh(&data("meshes/cinder_block_meters.obj"), 1.0).unwrap();
    let mesh_path = dir.path().join("block.ply");
    io::write_mesh_ply(&mesh_path, &block).unwrap();
    let mut cols = Vec::new();
    let x = [0.0f32, 1.0, 2.0, 3.0];
    let y = [0.5f32, -0.5, 0.25, 1e-3];
    io::write_ply_vertices(&mut cols, &["x", "y", "z", "ox"], &[&x, &y, &x, &y]).unwrap();
    vec![
        ("a.ply", ply_ascii()),
        ("le.ply", ply_binary(false)),
        ("be.ply", ply_binary(true)),
        ("block.ply", std::fs::read(&mesh_path).unwrap()),
        ("cols.ply", cols),
    ]
}

fn pcd_seeds() -> Vec<(&'static str, Vec<u8>)> {
    vec![
        ("a.pcd", pcd_ascii()),
        ("b.pcd", pcd_binary()),
        ("c.pcd", pcd_compressed()),
        ("bunny.pcd", bunny(12)),
    ]
}

fn obj_seeds() -> Vec<(&'static str, Vec<u8>)> {
    vec![
        (
            "t.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0 1\nvt 0 0\nvn 0 0 1\nf 1 2 3\nf 2/1 4/1/1 3//1\n\
              f -1 -2 -3\n"
                .to_vec(),
        ),
        ("block.obj", read("meshes/cinder_block_meters.obj")),
    ]
}

fn stl_seeds() -> Vec<(&'static str, Vec<u8>)> {
    let mut solid = stl_binary(4);
    solid[..6].copy_from_slice(b"solid ");
    vec![
        ("b.stl", stl_binary(6)),
        ("solid_header.stl", solid),
        (
            "a.stl",
            b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n\
              endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\n\
              vertex 0 1 0\nendloop\nendfacet\nendsolid t\n"
                .to_vec(),
        ),
    ]
}

fn text_seeds() -> Vec<(&'static str, Vec<u8>)> {
    let beams = String::from_utf8(read("pointclouds/pc2beam_steel_beams_test_points.txt")).unwrap();
    let beams: String = beams.lines().take(8).flat_map(|l| [l, "\n"]).collect();
    vec![
        ("t.csv", b"x,y,z,label\n1,2,3,4\n5,6,7,8\n".to_vec()),
        (
            "cc.txt",
            b"//X,Y,Z,Nx,Ny,Nz,intensity\n1 2 3 0 0 1 0.5\n4 5 6 1 0 0 7\n".to_vec(),
        ),
        ("t.pts", b"2\n1 2 3 4\n5 6 7 8\n".to_vec()),
        ("beams.xyz", beams.into_bytes()),
    ]
}

fn ray_seeds() -> Vec<(&'static str, Vec<u8>)> {
    let rays = scene::fixtures::incoherent_rays(4, 3);
    vec![(
        "rays.bin",
        rays.iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
    )]
}

// ---------------------------------------------------------------------------
// Checks: no panic; every Ok self-consistent and true to the file's sizes.

fn fail(msg: String) -> TestCaseError {
    TestCaseError::fail(msg)
}

fn check_cloud(cloud: &PointCloud) -> Result<(), TestCaseError> {
    let n = cloud.points.len();
    prop_assert!(n > 0, "an Ok cloud without points");
    prop_assert!(cloud.points.iter().all(|p| p.iter().all(|c| c.is_finite())));
    if let Some(normals) = &cloud.normals {
        prop_assert_eq!(normals.len(), n);
        prop_assert!(normals.iter().all(|v| v.iter().all(|c| c.is_finite())));
    }
    if let Some(labels) = &cloud.labels {
        prop_assert_eq!(labels.len(), n);
    }
    if let Some(intensities) = &cloud.intensities {
        prop_assert_eq!(intensities.len(), n);
    }
    Ok(())
}

fn check_mesh(mesh: &TriMesh) -> Result<(), TestCaseError> {
    prop_assert!(!mesh.triangles.is_empty(), "an Ok mesh without triangles");
    prop_assert!(
        mesh.vertices
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite()))
    );
    let n = mesh.vertices.len();
    prop_assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < n));
    Ok(())
}

/// An error must name the file.
fn check_error(e: &SceneError, path: &Path) -> Result<(), TestCaseError> {
    let name = path.file_name().unwrap().to_str().unwrap();
    names_source(e, name)
}

/// The header lines of a text header ending at the first line whose first
/// word is `last` (`end_header`, `DATA`), and the offset after that line.
fn header_lines(bytes: &[u8], last: &str) -> Option<(Vec<String>, usize)> {
    let mut lines = Vec::new();
    let mut pos = 0;
    while let Some(nl) = bytes[pos..].iter().position(|&b| b == b'\n') {
        let line = std::str::from_utf8(&bytes[pos..pos + nl]).ok()?.to_owned();
        pos += nl + 1;
        let first = line.split_whitespace().next().map(str::to_owned);
        lines.push(line);
        if first.as_deref() == Some(last) {
            return Some((lines, pos));
        }
    }
    None
}

/// PLY: the `element vertex N` count of the header, when it has one such line.
fn declared_vertices(bytes: &[u8]) -> Option<usize> {
    let (lines, _) = header_lines(bytes, "end_header")?;
    let counts: Vec<usize> = lines
        .iter()
        .filter_map(|l| match l.split_whitespace().collect::<Vec<_>>()[..] {
            ["element", "vertex", n] => n.parse().ok(),
            _ => None,
        })
        .collect();
    match counts[..] {
        [n] => Some(n),
        _ => None,
    }
}

fn check_ply(path: &Path, bytes: &[u8]) -> Result<(), TestCaseError> {
    match io::read_ply_vertices(path) {
        Ok(table) => {
            prop_assert!(table.columns.iter().all(|c| c.len() == table.len()));
            prop_assert_eq!(table.names.len(), table.columns.len());
            if let Some(n) = declared_vertices(bytes) {
                prop_assert_eq!(table.len(), n, "vertex rows vs the header's count");
            }
        }
        Err(e) => check_error(&e, path)?,
    }
    for cloud in [io::load_cloud(path), io::load_cloud_or_mesh_vertices(path)] {
        match cloud {
            Ok(cloud) => {
                check_cloud(&cloud)?;
                if let Some(n) = declared_vertices(bytes) {
                    prop_assert_eq!(cloud.points.len(), n);
                }
            }
            Err(e) => check_error(&e, path)?,
        }
    }
    match io::load_mesh(path, 1.0) {
        Ok(mesh) => check_mesh(&mesh)?,
        Err(e) => check_error(&e, path)?,
    }
    Ok(())
}

fn check_pcd(path: &Path, bytes: &[u8]) -> Result<(), TestCaseError> {
    let header = io::read_pcd_header(path);
    if let Err(e) = &header {
        check_error(e, path)?;
    }
    match io::load_cloud(path) {
        Ok(cloud) => {
            check_cloud(&cloud)?;
            let header = header.map_err(|e| fail(format!("cloud loads, header fails: {e}")))?;
            prop_assert!(cloud.points.len() <= header.points);
            prop_assert_eq!(header.points, header.width * header.height);
            let (_, body) = header_lines(bytes, "DATA").ok_or_else(|| fail("no DATA".into()))?;
            let rest = &bytes[body..];
            match header.data {
                io::PcdData::Binary => {
                    let point: usize = header.fields.iter().map(|f| f.size * f.count).sum();
                    prop_assert_eq!(rest.len(), header.points * point, "binary body length");
                }
                io::PcdData::Ascii => {
                    let rows = rest
                        .split(|&b| b == b'\n')
                        .filter(|l| !l.trim_ascii().is_empty())
                        .count();
                    prop_assert_eq!(rows, header.points, "ascii rows");
                }
                io::PcdData::BinaryCompressed => {
                    let size = u32::from_le_bytes(rest[..4].try_into().unwrap()) as usize;
                    prop_assert!(rest[8 + size..].iter().all(|&b| b == 0), "data after block");
                }
            }
        }
        Err(e) => check_error(&e, path)?,
    }
    Ok(())
}

fn check_mesh_file(path: &Path, bytes: &[u8]) -> Result<(), TestCaseError> {
    match io::load_mesh(path, 1.0) {
        Ok(mesh) => {
            check_mesh(&mesh)?;
            let is_stl = path.extension().is_some_and(|e| e == "stl");
            if is_stl && !bytes.trim_ascii_start().starts_with(b"solid") {
                let count = u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as usize;
                prop_assert_eq!(bytes.len(), 84 + 50 * count, "binary STL size");
                prop_assert_eq!(mesh.triangles.len(), count);
            }
        }
        Err(e) => check_error(&e, path)?,
    }
    match io::load_cloud_or_mesh_vertices(path) {
        Ok(cloud) => check_cloud(&cloud)?,
        Err(e) => check_error(&e, path)?,
    }
    Ok(())
}

fn check_text(path: &Path, _bytes: &[u8]) -> Result<(), TestCaseError> {
    for cloud in [io::load_cloud(path), io::load_cloud_or_mesh_vertices(path)] {
        match cloud {
            Ok(cloud) => check_cloud(&cloud)?,
            Err(e) => check_error(&e, path)?,
        }
    }
    Ok(())
}

fn check_rays(_name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    let path = Path::new("fuzz/rays.bin");
    match io::rays::parse_rays(path, bytes) {
        Ok(rays) => {
            prop_assert_eq!(rays.len() * 24, bytes.len());
            for r in &rays {
                prop_assert!(r.iter().all(|v| v.is_finite()));
                let n2 = r[3] * r[3] + r[4] * r[4] + r[5] * r[5];
                prop_assert!((n2 - 1.0).abs() <= 1e-3);
            }
        }
        Err(e) => check_error(&e, path)?,
    }
    Ok(())
}

/// Write the input to a temporary file named like its seed and run `check`.
fn via_file(
    check: fn(&Path, &[u8]) -> Result<(), TestCaseError>,
) -> impl Fn(&str, &[u8]) -> Result<(), TestCaseError> {
    move |name, bytes| {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        check(&path, bytes)
    }
}

// ---------------------------------------------------------------------------
// The tests: CASES per format here, LONG_CASES with --ignored.

#[test]
fn fuzz_ply() {
    fuzz(Run::Short(CASES), ply_seeds(), via_file(check_ply));
}

#[test]
fn fuzz_pcd() {
    fuzz(Run::Short(CASES), pcd_seeds(), via_file(check_pcd));
}

#[test]
fn fuzz_obj() {
    fuzz(Run::Short(CASES), obj_seeds(), via_file(check_mesh_file));
}

#[test]
fn fuzz_stl() {
    fuzz(Run::Short(CASES), stl_seeds(), via_file(check_mesh_file));
}

#[test]
fn fuzz_text_clouds() {
    fuzz(Run::Short(CASES), text_seeds(), via_file(check_text));
}

#[test]
fn fuzz_rays() {
    fuzz(Run::Short(CASES), ray_seeds(), check_rays);
}

#[test]
#[ignore = "long fuzz run (20 000 cases per format, minutes in debug): cargo test -p scene --test it fuzz -- --ignored"]
fn fuzz_long() {
    fuzz(Run::Long(LONG_CASES), ply_seeds(), via_file(check_ply));
    fuzz(Run::Long(LONG_CASES), pcd_seeds(), via_file(check_pcd));
    fuzz(
        Run::Long(LONG_CASES),
        obj_seeds(),
        via_file(check_mesh_file),
    );
    fuzz(
        Run::Long(LONG_CASES),
        stl_seeds(),
        via_file(check_mesh_file),
    );
    fuzz(Run::Long(LONG_CASES), text_seeds(), via_file(check_text));
    fuzz(Run::Long(LONG_CASES), ray_seeds(), check_rays);
}

/// The seeds themselves load (so the fuzz starts from valid files).
#[test]
fn seeds_are_valid() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in ply_seeds()
        .into_iter()
        .chain(pcd_seeds())
        .chain(text_seeds())
    {
        let path = io_fixtures::write(dir.path(), name, &bytes);
        io::load_cloud(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    for (name, bytes) in obj_seeds().into_iter().chain(stl_seeds()) {
        let path = io_fixtures::write(dir.path(), name, &bytes);
        io::load_mesh(&path, 1.0).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    assert_eq!(
        io::rays::parse_rays(Path::new("r"), &ray_seeds()[0].1)
            .unwrap()
            .len(),
        4
    );
}
