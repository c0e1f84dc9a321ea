//! Oracles for `scene::io`: meshes written as PLY and OBJ read back identically,
//! PLY vertex tables round-trip, and the three PLY encodings, the three PCD
//! encodings and the text layouts of one hand-written dataset agree.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "test helpers outside #[test] functions fail the test on any error"
)]

use geom::{Point3, Vector3};
use proptest::prelude::*;
use scene::io::{self, PlyTable};
use scene::{PointCloud, TriMesh};

use crate::io_fixtures;
use io_fixtures::*;

/// The triangles of `m` as coordinate triples (independent of vertex numbering).
fn soup(m: &TriMesh) -> Vec<[Point3; 3]> {
    m.triangles
        .iter()
        .map(|t| t.map(|i| m.vertices[i as usize]))
        .collect()
}

// ---------------------------------------------------------------------------
// Meshes: PLY and OBJ writers against the readers.

#[test]
fn real_meshes_round_trip_through_ply_and_obj() {
    let dir = tempfile::tempdir().unwrap();
    for rel in [
        "meshes/004_sugar_box_textured.obj",
        "meshes/truss_bridge_meters.obj",
        "robots/ur5/meshes/ur5/collision/forearm.stl",
    ] {
        let original = io::load_mesh(&data(rel), 1.0).unwrap();
        let ply = dir.path().join("m.ply");
        let obj = dir.path().join("m.obj");
        io::write_mesh_ply(&ply, &original).unwrap();
        io::write_mesh_obj(&obj, &original).unwrap();
        let from_ply = io::load_mesh(&ply, 1.0).unwrap();
        let from_obj = io::load_mesh(&obj, 1.0).unwrap();
        // Every loaded coordinate is an f32, so both formats are exact.
        assert_eq!(from_ply, original, "{rel} via PLY");
        assert_eq!(soup(&from_obj), soup(&original), "{rel} via OBJ");
        assert_eq!(soup(&from_obj), soup(&from_ply), "{rel}: PLY and OBJ agree");
        // OBJ numbers vertices by first use; for a mesh already in that order
        // (one loaded from OBJ) the round trip is the identity.
        if rel.starts_with("meshes/") {
            assert_eq!(from_obj, original, "{rel} via OBJ, exactly");
        }
        // Reading the PLY as a cloud gives the vertices.
        let cloud = io::load_cloud(&ply).unwrap();
        assert_eq!(cloud.points, original.vertices);
    }
}

fn arb_mesh() -> impl Strategy<Value = TriMesh> {
    (3usize..40).prop_flat_map(|n| {
        let vertex = prop::array::uniform3(-1.0e4f32..1.0e4)
            .prop_map(|c| Point3::new(f64::from(c[0]), f64::from(c[1]), f64::from(c[2])));
        let n32 = n as u32;
        (
            prop::collection::vec(vertex, n),
            prop::collection::vec(prop::array::uniform3(0..n32), 1..60),
        )
            .prop_map(|(vertices, triangles)| TriMesh::new(vertices, triangles, "arb").unwrap())
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn random_meshes_round_trip(mesh in arb_mesh()) {
        let dir = tempfile::tempdir().unwrap();
        let ply = dir.path().join("m.ply");
        let obj = dir.path().join("m.OBJ");
        io::write_mesh_ply(&ply, &mesh).unwrap();
        io::write_mesh_obj(&obj, &mesh).unwrap();
        let from_ply = io::load_mesh(&ply, 1.0).unwrap();
        let from_obj = io::load_mesh(&obj, 1.0).unwrap();
        prop_assert_eq!(&from_ply, &mesh);
        prop_assert_eq!(soup(&from_obj), soup(&mesh));
    }

    #[test]
    fn ply_vertex_tables_round_trip(
        columns in (1usize..6, 0usize..50).prop_flat_map(|(k, n)| {
            prop::collection::vec(
                ("[a-z_][a-z0-9_]{0,11}", prop::collection::vec(any::<f32>(), n)),
                k,
            )
        })
    ) {
        // Property names must be distinct.
        let mut names: Vec<String> = Vec::new();
        for (i, (name, _)) in columns.iter().enumerate() {
            names.push(if names.contains(name) { format!("{name}_{i}") } else { name.clone() });
        }
        let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
        let col_refs: Vec<&[f32]> = columns.iter().map(|(_, c)| c.as_slice()).collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("table.ply");
        io::write_ply_vertices_file(&path, &name_refs, &col_refs).unwrap();
        let table = io::read_ply_vertices(&path).unwrap();
        prop_assert_eq!(&table.names, &names);
        prop_assert_eq!(table.columns.len(), columns.len());
        for ((_, written), read) in columns.iter().zip(&table.columns) {
            prop_assert_eq!(read.len(), written.len());
            for (w, r) in written.iter().zip(read) {
                // Bit-exact, NaN payloads included.
                prop_assert_eq!((*r as f32).to_bits(), w.to_bits());
            }
        }
        // The in-memory writer produces the same bytes as the file writer.
        let mut buf = Vec::new();
        io::write_ply_vertices(&mut buf, &name_refs, &col_refs).unwrap();
        prop_assert_eq!(buf, std::fs::read(&path).unwrap());
    }
}

// ---------------------------------------------------------------------------
// PLY: the dataset of `io_fixtures` in the three encodings.

fn expected_table() -> PlyTable {
    let names = ["x", "y", "z", "nx", "ny", "nz", "intensity", "label"];
    let mut columns = vec![Vec::new(); names.len()];
    for (p, n, i, l, _) in VERTICES {
        let row = [
            f64::from(p[0]),
            f64::from(p[1]),
            f64::from(p[2]),
            n[0],
            n[1],
            n[2],
            f64::from(i),
            f64::from(l),
        ];
        for (c, v) in columns.iter_mut().zip(row) {
            c.push(v);
        }
    }
    PlyTable {
        names: names.iter().map(|s| (*s).to_owned()).collect(),
        columns,
    }
}

#[test]
fn ply_encodings_agree() {
    let dir = tempfile::tempdir().unwrap();
    let le = write(dir.path(), "le.ply", &ply_binary(false));
    let be = write(dir.path(), "be.ply", &ply_binary(true));
    let ascii = write(dir.path(), "ascii.PLY", &ply_ascii());

    let table = io::read_ply_vertices(&le).unwrap();
    assert_eq!(table, expected_table());
    assert_eq!(
        table.column("label"),
        Some(&[-3.0, 7.0, 7.0, 0.0, 2.0e6][..])
    );
    assert_eq!(io::read_ply_vertices(&be).unwrap(), table);
    assert_eq!(io::read_ply_vertices(&ascii).unwrap(), table);

    let mesh = io::load_mesh(&le, 1.0).unwrap();
    // Fans: quad → 2, triangle → 1, pentagon → 3.
    assert_eq!(
        mesh.triangles,
        [
            [0, 1, 2],
            [0, 2, 3],
            [3, 2, 4],
            [0, 1, 2],
            [0, 2, 4],
            [0, 4, 3]
        ]
    );
    assert_eq!(
        mesh.vertices[4],
        Point3::new(0.75, 3.0, f64::from(1.0e-3f32))
    );
    assert_eq!(io::load_mesh(&be, 1.0).unwrap(), mesh);
    assert_eq!(io::load_mesh(&ascii, 1.0).unwrap(), mesh);

    let cloud = io::load_cloud(&le).unwrap();
    assert_eq!(cloud.points, mesh.vertices);
    assert_eq!(cloud.labels, Some(vec![-3, 7, 7, 0, 2_000_000]));
    assert_eq!(cloud.intensities, Some(vec![10.0, 20.0, 30.0, 255.0, 0.0]));
    assert_eq!(
        cloud.normals.as_ref().unwrap()[4],
        Vector3::new(0.6, 0.8, 0.0)
    );
    assert_eq!(io::load_cloud(&be).unwrap(), cloud);
    assert_eq!(io::load_cloud(&ascii).unwrap(), cloud);
}

#[test]
fn ply_ascii_floats_are_rounded_like_binary_floats() {
    // 0.1 is not an f32; a `float` property holds the nearest f32 in any encoding.
    let dir = tempfile::tempdir().unwrap();
    let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                property double z\nend_header\n0.1 0.2 0.3\n";
    let path = write(dir.path(), "a.ply", text.as_bytes());
    let c = io::load_cloud(&path).unwrap();
    assert_eq!(
        c.points[0],
        Point3::new(f64::from(0.1f32), f64::from(0.2f32), 0.3)
    );
}

#[test]
fn ply_vertex_index_name_and_type_aliases() {
    let dir = tempfile::tempdir().unwrap();
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement face 1\n\
                  property list uint16 uint32 vertex_index\nelement vertex 3\n\
                  property int8 x\nproperty uint8 y\nproperty int16 z\nend_header\n"
        .to_vec();
    b.extend_from_slice(&3u16.to_le_bytes());
    for i in [2u32, 1, 0] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    for (x, y, z) in [(-1i8, 0u8, 0i16), (1, 0, 0), (0, 255, -300)] {
        b.extend_from_slice(&x.to_le_bytes());
        b.push(y);
        b.extend_from_slice(&z.to_le_bytes());
    }
    let path = write(dir.path(), "t.ply", &b);
    let m = io::load_mesh(&path, 0.5).unwrap();
    assert_eq!(m.triangles, [[2, 1, 0]]);
    assert_eq!(
        m.vertices,
        [
            Point3::new(-0.5, 0.0, 0.0),
            Point3::new(0.5, 0.0, 0.0),
            Point3::new(0.0, 127.5, -150.0)
        ]
    );
}

// ---------------------------------------------------------------------------
// PCD: the organized 3×2 cloud of `io_fixtures` in the three encodings.

fn expected_pcd_cloud() -> PointCloud {
    let valid: Vec<_> = pcd_points()
        .into_iter()
        .filter(|p| p.0[0].is_finite())
        .collect();
    let v3 = |a: [f32; 3]| [f64::from(a[0]), f64::from(a[1]), f64::from(a[2])];
    PointCloud {
        points: valid.iter().map(|p| Point3::from(v3(p.0))).collect(),
        normals: Some(valid.iter().map(|p| Vector3::from(v3(p.1))).collect()),
        labels: Some(valid.iter().map(|p| i64::from(p.2)).collect()),
        intensities: Some(valid.iter().map(|p| p.3).collect()),
    }
}

#[test]
fn pcd_encodings_agree_and_drop_nan_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let expected = expected_pcd_cloud();
    assert_eq!(expected.points.len(), 5);
    for (name, bytes) in [
        ("ascii.pcd", pcd_ascii()),
        ("binary.pcd", pcd_binary()),
        ("compressed.PCD", pcd_compressed()),
    ] {
        let path = write(dir.path(), name, &bytes);
        let cloud = io::load_cloud(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(cloud, expected, "{name}");
        let h = io::read_pcd_header(&path).unwrap();
        assert_eq!((h.width, h.height, h.points), (3, 2, 6));
        assert_eq!(
            h.cloud_from_sensor.translation.vector,
            Vector3::new(1.0, 2.0, 3.0)
        );
        assert_eq!(h.fields[9].count, 3);
    }
}

#[test]
fn pcd_double_coordinates_signed_labels_and_nan_normals() {
    // F8 coordinates (one no f32 holds: 1234567.891 would read 1234567.875),
    // I2 labels, one finite point with a NaN normal: the normals are dropped
    // rather than carrying NaN.
    let dir = tempfile::tempdir().unwrap();
    let text = "VERSION .7\nFIELDS x y z label normal_x normal_y normal_z\nSIZE 8 8 8 2 4 4 4\n\
                TYPE F F F I F F F\nWIDTH 3\nPOINTS 3\nDATA ascii\n\
                0.1 0.2 0.3 -5 0 0 1\nnan nan nan 0 nan nan nan\n1234567.891 -2 3 7 nan nan nan\n";
    let path = write(dir.path(), "d.pcd", text.as_bytes());
    let c = io::load_cloud(&path).unwrap();
    assert_eq!(
        c.points,
        [
            Point3::new(0.1, 0.2, 0.3),
            Point3::new(1_234_567.891, -2.0, 3.0)
        ]
    );
    assert_eq!(c.labels, Some(vec![-5, 7]));
    assert_eq!(c.normals, None);
}

// ---------------------------------------------------------------------------
// Text clouds.

#[test]
fn text_layouts() {
    let dir = tempfile::tempdir().unwrap();
    let xyz = write(
        dir.path(),
        "a.xyz",
        b"# a comment\n1 2 3\n\n  4\t5 6   # trailing comment\r\n-7e-1 8.5 +9\n",
    );
    let c = io::load_cloud(&xyz).unwrap();
    assert_eq!(
        c.points,
        [
            Point3::new(1.0, 2.0, 3.0),
            Point3::new(4.0, 5.0, 6.0),
            Point3::new(-0.7, 8.5, 9.0)
        ]
    );
    assert!(c.normals.is_none() && c.labels.is_none());

    let csv = write(
        dir.path(),
        "b.csv",
        b"x, y, z, nx, ny, nz, label\n1,2,3,0,0,1,5\n4, 5, 6, 1, 0, 0, -2\n",
    );
    let named = io::load_cloud(&csv).unwrap();
    let txt = write(dir.path(), "b.txt", b"1 2 3 0 0 1 5\n4 5 6 1 0 0 -2\n");
    let positional = io::load_cloud(&txt).unwrap();
    assert_eq!(named, positional);
    assert_eq!(named.labels, Some(vec![5, -2]));
    assert_eq!(
        named.normals.as_ref().unwrap()[1],
        Vector3::new(1.0, 0.0, 0.0)
    );

    // Names in any order, unknown columns ignored.
    let reordered = write(
        dir.path(),
        "c.csv",
        b"label,red,Z,Y,X,normal_z,normal_y,normal_x\n5,0.1,3,2,1,1,0,0\n-2,0.2,6,5,4,0,0,1\n",
    );
    assert_eq!(io::load_cloud(&reordered).unwrap(), named);

    // CloudCompare's header; colours named, so not taken for normals.
    let cc = write(
        dir.path(),
        "e.txt",
        b"//X,Y,Z,R,G,B\n1,2,3,255,0,0\n4,5,6,0,255,0\n",
    );
    let c = io::load_cloud(&cc).unwrap();
    assert_eq!(c.points[1], Point3::new(4.0, 5.0, 6.0));
    assert!(c.normals.is_none());

    // Leica PTS: count line, x y z intensity r g b.
    let pts = write(
        dir.path(),
        "d.pts",
        b"2\n1 2 3 -1200 10 20 30\n4 5 6 37 0 0 0\n",
    );
    let c = io::load_cloud(&pts).unwrap();
    assert_eq!(c.points.len(), 2);
    assert_eq!(c.intensities, Some(vec![-1200.0, 37.0]));
    assert!(c.normals.is_none());
}

/// `sample_cloud_points` gives `load_cloud`'s points `.step_by(stride)`: on
/// the three encodings of the hand-written file (the binary ones read row
/// by row, the ASCII one whole) and on a cloud as `surveyor explore` writes
/// it, for several strides; a truncated file or a non-finite point read
/// is an error naming the vertex.
#[test]
fn sampled_cloud_points_are_every_stride_th() {
    let dir = tempfile::tempdir().unwrap();
    let le = write(dir.path(), "le.ply", &ply_binary(false));
    let be = write(dir.path(), "be.ply", &ply_binary(true));
    let ascii = write(dir.path(), "ascii.PLY", &ply_ascii());
    let n = 1001;
    let col = |k: f32| (0..n).map(|i| k * i as f32 + 0.25).collect::<Vec<f32>>();
    let cols = [col(0.5), col(-1.0), col(2.0), col(0.1), col(0.2), col(0.3)];
    let names = ["x", "y", "z", "origin_x", "origin_y", "origin_z"];
    let big = dir.path().join("cloud.ply");
    io::write_ply_vertices_file(&big, &names, &cols.each_ref().map(Vec::as_slice)).unwrap();
    for path in [&le, &be, &ascii, &big] {
        let all = io::load_cloud(path).unwrap().points;
        for stride in [1, 2, 3, 7, 1000, 5000] {
            let (count, got) = io::sample_cloud_points(path, |c| {
                assert_eq!(c, all.len());
                stride
            })
            .unwrap();
            assert_eq!(count, all.len());
            let expected: Vec<Point3> = all.iter().step_by(stride).copied().collect();
            assert_eq!(got, expected, "{} stride {stride}", path.display());
        }
    }
    // Cut inside vertex 1000's row: the stride that reaches it says so.
    let bytes = std::fs::read(&big).unwrap();
    let cut = write(dir.path(), "cut.ply", &bytes[..bytes.len() - 4]);
    assert!(io::sample_cloud_points(&cut, |_| 7).is_ok());
    let e = io::sample_cloud_points(&cut, |_| 5)
        .unwrap_err()
        .to_string();
    assert!(e.contains("vertex 1000") && e.contains("truncated"), "{e}");
    // A NaN as vertex 3's x (six floats a row): an error when read, not
    // when skipped.
    let body = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let mut nan = bytes.clone();
    nan[body + 3 * 24..body + 3 * 24 + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let nan = write(dir.path(), "nan.ply", &nan);
    let e = io::sample_cloud_points(&nan, |_| 1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("vertex 3") && e.contains("non-finite"), "{e}");
    assert!(io::sample_cloud_points(&nan, |_| 2).is_ok());
}
