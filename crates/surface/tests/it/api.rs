#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]
//! The public API: updates and change logs, outputs, refused input, degenerate
//! input.

use geom::{Point3, UnitVector3, Vector3, unit};
use surface::{
    ModelJson, SegmentJson, SensorSet, SurfaceConfig, SurfaceError, SurfaceModel, UpdateTimes,
    read_initial_segments_json, read_sets_jsonl,
};

fn down() -> UnitVector3 {
    unit(-Vector3::z()).unwrap()
}

/// A raster of 3×3 point3-like sets over the plane z = 0.
fn plane_sets(n: usize) -> Vec<SensorSet> {
    let mut sets = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (cx, cy) = (0.03 * i as f64, 0.03 * j as f64);
            let mut pts = Vec::new();
            let mut axes = Vec::new();
            for a in -1..=1 {
                for b in -1..=1 {
                    pts.push(Point3::new(
                        cx + 0.1 * f64::from(a),
                        cy + 0.1 * f64::from(b),
                        0.0,
                    ));
                    axes.push(unit(Vector3::new(f64::from(a), f64::from(b), -1.0)).unwrap());
                }
            }
            sets.push(SensorSet::new(pts, axes).unwrap());
        }
    }
    sets
}

#[test]
fn a_plane_becomes_one_polygon_and_the_log_tracks_it() {
    let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
    let mut current = None;
    for s in plane_sets(12) {
        let log = m.update(&s).unwrap();
        m.check_invariants().unwrap();
        // The follower's view: the segment it tracks is resolved through mergers.
        if let Some(c) = current {
            current = log.resolve(c);
        }
        if current.is_none() {
            current = m
                .segments()
                .find(|s| s.as_polygon().is_some())
                .map(surface::Segment::id);
        }
        for &(seg, idx) in &log.changed_edges {
            assert!(seg.0 < log.created.first().map_or(u32::MAX, |c| c.0));
            let _ = idx;
        }
    }
    assert_eq!(m.len(), 1);
    let id = current.unwrap();
    let g = m.polygon(id).unwrap();
    assert!(g.area() > 0.5 * 0.5);
    assert!((g.normal().z - 1.0).abs() < 1e-9);
    assert_eq!(m.points_fed(), 12 * 12 * 9);
    assert_eq!(m.segment(id).unwrap().points(), m.points_fed());
    // Edge keys locate edges.
    let key = g.edge(0).unwrap().key;
    assert_eq!(m.locate_edge(key), Some((id, 0)));
}

#[test]
fn outputs_have_the_contract_layout() {
    let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
    m.add_initial_segment(&[
        Point3::new(-2.0, -2.0, -0.5),
        Point3::new(2.0, -2.0, -0.5),
        Point3::new(2.0, 2.0, -0.5),
        Point3::new(-2.0, 2.0, -0.5),
    ])
    .unwrap();
    for s in plane_sets(6) {
        m.update(&s).unwrap();
    }
    m.update(&SensorSet::new(vec![Point3::new(5.0, 5.0, 5.0)], vec![down()]).unwrap())
        .unwrap();
    let json = m.to_model_json();
    let text = serde_json::to_string(&json).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let segs = v["segments"].as_array().unwrap();
    let poly = segs
        .iter()
        .find(|s| s["kind"] == "polygon" && s["initial"] == false)
        .unwrap();
    for key in [
        "id", "kind", "points", "initial", "centroid", "normal", "vertices", "edges",
    ] {
        assert!(poly.get(key).is_some(), "missing {key}");
    }
    let e = &poly["edges"][0];
    for key in ["shared_with", "corresponding_edge", "corner_start"] {
        assert!(e.get(key).is_some(), "missing edges[].{key}");
    }
    let point = segs.iter().find(|s| s["kind"] == "point").unwrap();
    for key in ["id", "kind", "points", "centroid", "sensing_axis"] {
        assert!(point.get(key).is_some(), "missing {key}");
    }
    assert!(
        v["surfaces"]
            .as_array()
            .unwrap()
            .iter()
            .all(serde_json::Value::is_array)
    );
    let back: ModelJson = serde_json::from_str(&text).unwrap();
    assert_eq!(back.segments.len(), json.segments.len());
    assert_eq!(back.surfaces, json.surfaces);
    assert!(json.segments.iter().any(|s| matches!(
        s,
        SegmentJson::Polygon {
            initial: true,
            points: 0,
            ..
        }
    )));
    // OBJ: one group per segment, triangles for polygons.
    let obj = m.to_obj();
    assert_eq!(obj.lines().filter(|l| l.starts_with("g ")).count(), m.len());
    assert!(obj.lines().any(|l| l.starts_with("f ")));
    // The triangles cover each polygon: their areas sum to its own.
    let mut verts: Vec<Point3> = Vec::new();
    let mut tri_area = 0.0;
    for line in obj.lines() {
        let mut f = line.split_whitespace();
        match f.next() {
            Some("v") => {
                let c: Vec<f64> = f.map(|x| x.parse().unwrap()).collect();
                verts.push(Point3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let [a, b, c] =
                    [0, 1, 2].map(|_| verts[f.next().unwrap().parse::<usize>().unwrap() - 1]);
                tri_area += 0.5 * (b - a).cross(&(c - a)).norm();
            }
            _ => {}
        }
    }
    let poly_area: f64 = m
        .segments()
        .filter_map(|s| s.as_polygon())
        .map(|p| p.area().abs())
        .sum();
    assert!(poly_area > 0.0);
    assert!(
        (tri_area - poly_area).abs() < 1e-9 * poly_area.max(1.0),
        "{tri_area} vs {poly_area}"
    );
    // Stats.
    let st = m.stats();
    assert_eq!(st.segments, m.len());
    assert_eq!(st.polygons + st.points, st.segments);
    let sj = st.to_json(UpdateTimes::from_micros(&[10.0, 20.0, 30.0]));
    let v: serde_json::Value = serde_json::to_value(sj).unwrap();
    for key in [
        "updates",
        "update_us",
        "segments",
        "polygons",
        "points",
        "shared_edge_pairs",
        "corner_vertices",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["update_us"]["median"], 20.0);
}

#[test]
fn bad_input_is_refused_and_leaves_the_model_unchanged() {
    let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
    m.update(&plane_sets(1)[0]).unwrap();
    let before = m.to_model_json();
    let nan = SensorSet {
        points: vec![Point3::new(f64::NAN, 0.0, 0.0)],
        axes: vec![down()],
    };
    assert!(matches!(
        m.update(&nan),
        Err(SurfaceError::SensorSet { .. })
    ));
    // Beyond ±1e7 m (geom::MAX_COORDINATE_M).
    let far = SensorSet {
        points: vec![Point3::new(1e30, 0.0, 0.0)],
        axes: vec![down()],
    };
    let err = m.update(&far).unwrap_err();
    assert!(err.to_string().contains("points[0]"), "{err}");
    let mismatch = SensorSet {
        points: vec![Point3::origin(); 2],
        axes: vec![down()],
    };
    assert!(m.update(&mismatch).is_err());
    let not_unit = SensorSet {
        points: vec![Point3::origin()],
        axes: vec![UnitVector3::new_unchecked(Vector3::new(0.0, 0.0, 2.0))],
    };
    let err = m.update(&not_unit).unwrap_err();
    assert!(err.to_string().contains("axes[0]"), "{err}");
    assert_eq!(m.to_model_json(), before);
    assert_eq!(m.updates(), 1);
    assert!(
        SurfaceModel::new(SurfaceConfig {
            mu_deg: 95.0,
            ..SurfaceConfig::default()
        })
        .is_err()
    );
    // Initial segments: too few, non-planar, self-crossing.
    assert!(
        m.add_initial_segment(&[Point3::origin(), Point3::new(1.0, 0.0, 0.0)])
            .is_err()
    );
    assert!(
        m.add_initial_segment(&[
            Point3::origin(),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.1),
            Point3::new(0.0, 1.0, 0.0)
        ])
        .is_err()
    );
    assert!(
        m.add_initial_segment(&[
            Point3::origin(),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0)
        ])
        .is_err()
    );
    assert_eq!(m.to_model_json(), before);
    m.check_invariants().unwrap();
}

/// Issue 48: an initial segment that overlaps another on the same surface is
/// refused, naming it and the common area (worked out by hand for these
/// rectangles), and the model is as before; initial segments that only touch,
/// face each other, lie on parallel planes farther apart than λ, or cross at
/// an angle are kept.
#[test]
fn overlapping_initial_segments_are_refused() {
    // Anticlockwise about +z (or about −z with `down`), at height z.
    let rect = |x0: f64, y0: f64, x1: f64, y1: f64, z: f64| {
        vec![
            Point3::new(x0, y0, z),
            Point3::new(x1, y0, z),
            Point3::new(x1, y1, z),
            Point3::new(x0, y1, z),
        ]
    };
    let down = |mut v: Vec<Point3>| {
        v.reverse();
        v
    };
    let lambda = SurfaceConfig::default().lambda;
    let tilt = 4.0_f64.to_radians();
    let refused: [(&str, Vec<Point3>, f64); 5] = [
        ("the same square", rect(0.0, 0.0, 1.0, 1.0, 0.0), 1.0),
        ("a quarter", rect(0.5, 0.5, 1.5, 1.5, 0.0), 0.25),
        ("a square inside", rect(0.2, 0.2, 0.4, 0.6, 0.0), 0.08),
        ("0.9 λ above", rect(0.5, 0.0, 1.5, 1.0, 0.9 * lambda), 0.5),
        // Rising 4° along x from x = 0.5 (μ/2 is 5°), the planes 0.017 m
        // apart at the common part's centroid: measured in the tilted plane,
        // where the first square's half beyond x = 0.5 is cos 4° as wide.
        (
            "tilted by 4°",
            vec![
                Point3::new(0.5, 0.0, 0.0),
                Point3::new(1.5, 0.0, tilt.tan()),
                Point3::new(1.5, 1.0, tilt.tan()),
                Point3::new(0.5, 1.0, 0.0),
            ],
            0.5 * tilt.cos(),
        ),
    ];
    for (what, square, area) in refused {
        let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
        let first = m
            .add_initial_segment(&rect(0.0, 0.0, 1.0, 1.0, 0.0))
            .unwrap();
        let before = m.to_model_json();
        match m.add_initial_segment(&square) {
            Err(SurfaceError::InitialOverlap { other, area_m2 }) => {
                assert_eq!(other, first, "{what}");
                assert!((area_m2 - area).abs() < 1e-9, "{what}: {area_m2}");
            }
            other => panic!("{what}: {other:?}"),
        }
        assert_eq!(m.to_model_json(), before, "{what}");
        m.check_invariants().unwrap();
    }
    let kept: [(&str, Vec<Point3>); 6] = [
        ("a tile beside it", rect(1.0, 0.0, 2.0, 1.0, 0.0)),
        ("a tile at its corner", rect(1.0, 1.0, 2.0, 2.0, 0.0)),
        ("its underside", down(rect(0.0, 0.0, 1.0, 1.0, 0.0))),
        (
            "a shelf 1.1 λ above",
            rect(0.0, 0.0, 1.0, 1.0, 1.1 * lambda),
        ),
        (
            "a wall through it",
            vec![
                Point3::new(0.5, -0.5, -0.5),
                Point3::new(0.5, 1.5, -0.5),
                Point3::new(0.5, 1.5, 0.5),
                Point3::new(0.5, -0.5, 0.5),
            ],
        ),
        ("far away", rect(5.0, 5.0, 6.0, 6.0, 0.0)),
    ];
    for (what, square) in kept {
        let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
        m.add_initial_segment(&rect(0.0, 0.0, 1.0, 1.0, 0.0))
            .unwrap();
        m.add_initial_segment(&square)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        m.check_invariants().unwrap();
    }
}

#[test]
fn degenerate_input_is_handled() {
    let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
    // Empty set, a single point, the same point many times, collinear points,
    // points far apart, points at huge coordinates.
    m.update(&SensorSet::default()).unwrap();
    m.update(&SensorSet::new(vec![Point3::new(0.1, 0.2, 0.3)], vec![down()]).unwrap())
        .unwrap();
    m.update(&SensorSet::new(vec![Point3::new(1.0, 1.0, 1.0); 30], vec![down(); 30]).unwrap())
        .unwrap();
    let line: Vec<Point3> = (0..30)
        .map(|k| Point3::new(2.0 + 0.003 * f64::from(k), 0.0, 0.0))
        .collect();
    m.update(&SensorSet::new(line, vec![down(); 30]).unwrap())
        .unwrap();
    let far: Vec<Point3> = (0..26)
        .map(|k| Point3::new(f64::from(k) * 10.0, 0.0, 0.0))
        .collect();
    m.update(&SensorSet::new(far, vec![down(); 26]).unwrap())
        .unwrap();
    // Near the ±1e7 m limit of input coordinates (geom::MAX_COORDINATE_M).
    let huge: Vec<Point3> = (0..26)
        .map(|k| {
            Point3::new(
                9.99e6 + 0.01 * f64::from(k % 5),
                9.99e6 + 0.01 * f64::from(k / 5),
                -9.99e6,
            )
        })
        .collect();
    m.update(&SensorSet::new(huge, vec![down(); 26]).unwrap())
        .unwrap();
    // Points exactly on top of a polygon's vertices and edges.
    for s in plane_sets(3) {
        m.update(&s).unwrap();
        m.update(&s).unwrap();
    }
    m.check_invariants().unwrap();
    // The repeated point is one point segment of 30 points.
    assert!(
        m.segments()
            .any(|s| s.points() == 30 && s.as_point().is_some())
    );
}

#[test]
fn files_parse_with_line_numbers() {
    let text = "{\"points\": [[0,0,0]], \"axes\": [[0,0,-1]]}\n\n{\"points\": [[0,0,0]], \"axes\": [[0,0,-1], [0,0,-1]]}\n";
    let err = read_sets_jsonl(text.as_bytes(), "sets.jsonl").unwrap_err();
    assert!(err.to_string().starts_with("sets.jsonl:3: axes"), "{err}");
    let segs = read_initial_segments_json(r#"{"segments": [[[0,0,0],[1,0,0],[1,1,0]]]}"#, "i.json")
        .unwrap();
    assert_eq!(segs.len(), 1);
    assert!(read_initial_segments_json("{", "i.json").is_err());
}

#[test]
fn updates_are_deterministic() {
    let run = || {
        let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
        for s in plane_sets(8) {
            m.update(&s).unwrap();
        }
        serde_json::to_string(&m.to_model_json()).unwrap()
    };
    assert_eq!(run(), run());
}

/// `n` points on z = 1 over a `side` × `side` square, seeded.
fn square_set(n: usize, side: f64) -> SensorSet {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let points = (0..n)
        .map(|_| {
            Point3::new(
                rng.random_range(0.0..side),
                rng.random_range(0.0..side),
                1.0,
            )
        })
        .collect();
    SensorSet::new(points, vec![down(); n]).unwrap()
}

#[test]
fn a_set_over_max_set_points_is_refused_naming_the_limit() {
    let config = SurfaceConfig {
        max_set_points: 100,
        ..SurfaceConfig::default()
    };
    let mut m = SurfaceModel::new(config).unwrap();
    m.update(&square_set(100, 0.5)).unwrap();
    let before = m.to_model_json();
    let err = m.update(&square_set(101, 0.5)).unwrap_err();
    assert_eq!(
        err,
        SurfaceError::SetTooLarge {
            points: 101,
            limit: 100
        }
    );
    assert!(err.to_string().contains("max_set_points = 100"), "{err}");
    assert_eq!(m.to_model_json(), before);
    assert_eq!(m.updates(), 1);
    // The default admits Pudney's 26-point sets with room to spare, and is checked.
    assert_eq!(SurfaceConfig::default().max_set_points, 4096);
    assert!(
        SurfaceModel::new(SurfaceConfig {
            max_set_points: 0,
            ..SurfaceConfig::default()
        })
        .is_err()
    );
}

#[test]
fn reading_a_set_over_the_limit_names_the_line() {
    let line = |n: usize| {
        let pts = vec!["[0,0,1]"; n].join(",");
        let axes = vec!["[0,0,-1]"; n].join(",");
        format!("{{\"points\": [{pts}], \"axes\": [{axes}]}}\n")
    };
    let text = format!("{}\n{}", line(3), line(4));
    assert_eq!(
        surface::read_sets_jsonl_limited(text.as_bytes(), "s.jsonl", 4)
            .unwrap()
            .len(),
        2
    );
    let err = surface::read_sets_jsonl_limited(text.as_bytes(), "s.jsonl", 3).unwrap_err();
    assert!(
        matches!(&err, SurfaceError::Parse { line: 3, field, .. } if field == "points"),
        "{err}"
    );
    assert!(
        err.to_string()
            .starts_with("s.jsonl:3: points: 4 points, more than max_set_points = 3"),
        "{err}"
    );
    // The unlimited reader applies the default limit.
    let big = line(surface::DEFAULT_MAX_SET_POINTS + 1);
    let err = read_sets_jsonl(big.as_bytes(), "big.jsonl").unwrap_err();
    assert!(err.to_string().contains("max_set_points = 4096"), "{err}");
}
