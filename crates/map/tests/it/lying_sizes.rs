//! Issue 8 §2: `sld` on a PLY whose vertex count is smaller than its data
//! used 100 of 51 642 points without a word. [`map::sld_io::load_points`] now
//! refuses such a file, naming it and both counts.

#![allow(clippy::unwrap_used, reason = "tests fail on any error")]

use map::sld_io::load_points;

#[test]
fn load_points_refuses_a_ply_whose_vertex_count_is_too_small() {
    let n = 51_642;
    let t: Vec<f32> = (0..n).map(|i| i as f32 * 1e-3).collect();
    let zero = vec![0.0f32; n];
    let mut ply = Vec::new();
    // With sensor origins, as `surveyor scan` writes them.
    scene::io::write_ply_vertices(
        &mut ply,
        &["x", "y", "z", "ox", "oy", "oz"],
        &[&t, &zero, &t, &zero, &zero, &zero],
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let honest = dir.path().join("honest.ply");
    std::fs::write(&honest, &ply).unwrap();
    let loaded = load_points(&honest).unwrap();
    assert_eq!(loaded.points.len(), n);
    assert_eq!(loaded.origins.map(|o| o.len()), Some(n));

    let from = format!("element vertex {n}\n");
    let at = ply
        .windows(from.len())
        .position(|w| w == from.as_bytes())
        .unwrap();
    let mut lie = ply[..at].to_vec();
    lie.extend_from_slice(b"element vertex 100\n");
    lie.extend_from_slice(&ply[at + from.len()..]);
    let path = dir.path().join("scan.ply");
    std::fs::write(&path, &lie).unwrap();
    let msg = match load_points(&path) {
        Ok(l) => panic!("loaded {} of the file's {n} points", l.points.len()),
        Err(e) => e.to_string(),
    };
    for part in [
        "scan.ply",
        "= 51542 more 'vertex' rows of 24 bytes",
        "the header declares 100 'vertex' rows",
    ] {
        assert!(msg.contains(part), "{msg:?} does not mention {part:?}");
    }
}
