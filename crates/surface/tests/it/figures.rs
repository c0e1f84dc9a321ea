//! Focused reproductions of the thesis figures, operation by operation
//! (acceptance 3). Fissures (Fig. 15–16), perimeter extension (Fig. 8–9) and
//! polygon combination (Fig. 10–13) also have unit tests next to their code.
//! Single operations are reached through `surface::testing`, which exists for
//! these tests only.

#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use geom::{Point3, Real, Vector3, unit};
use surface::testing::{ModelInternals, ShareOutcome, merge_point_polygon};
use surface::{
    Concavity, MergeFailure, SegmentId, SegmentKind, SensorSet, SurfaceConfig, SurfaceModel,
};

fn p(x: Real, y: Real, z: Real) -> Point3 {
    Point3::new(x, y, z)
}

fn model() -> SurfaceModel {
    SurfaceModel::new(SurfaceConfig::default()).unwrap()
}

fn set(points: &[Point3], axis: Vector3) -> SensorSet {
    let a = unit(axis).unwrap();
    SensorSet::new(points.to_vec(), vec![a; points.len()]).unwrap()
}

/// P Fig. 5–6(a): two point segments whose points are collinear merge into a
/// point segment at the weighted centroid.
#[test]
fn fig6a_point_plus_point_is_a_point() {
    let mut m = model();
    m.update(&set(&[p(0.0, 0.0, 0.0), p(0.02, 0.0, 0.0)], -Vector3::z()))
        .unwrap();
    // Both points merged (their distance is below λ).
    assert_eq!(m.len(), 1);
    m.update(&set(&[p(0.03, 0.0, 0.0)], -Vector3::z())).unwrap();
    let s = m.segments().next().unwrap();
    let pt = s.as_point().expect("collinear points make a point segment");
    assert_eq!(s.points(), 3);
    // The centroid lies nearer the side with more points.
    assert!((pt.centroid().x - 0.05 / 3.0).abs() < 1e-12);
    assert!((pt.sensing_axis().z + 1.0).abs() < 1e-12);
    m.check_invariants().unwrap();
}

/// P Fig. 5–6(b): points spread over a plane make the diamond of the two largest
/// eigen-axes, outward normal against the sensing axes.
#[test]
fn fig5_fig6b_point_plus_point_is_a_diamond() {
    let mut m = model();
    let pts = [p(0.0, 0.0, 1.0), p(0.03, 0.0, 1.0), p(0.0, 0.02, 1.0)];
    m.update(&set(&pts, -Vector3::z())).unwrap();
    assert_eq!(m.len(), 1);
    let s = m.segments().next().unwrap();
    let g = s.as_polygon().expect("planar points make a polygon");
    assert_eq!(g.len(), 4);
    assert!(
        (g.normal().z - 1.0).abs() < 1e-9,
        "outward normal faces the sensors"
    );
    let pca = s.moments().pca().unwrap();
    let c = pca.centroid;
    let (r1, r2) = (pca.eigenvalues[2].sqrt(), pca.eigenvalues[1].sqrt());
    let v: Vec<Point3> = g.vertices().collect();
    // Opposite vertices are c ± √u·v along the two largest eigen-axes.
    assert!(((v[0] - c).norm() - r1).abs() < 1e-12 && ((v[2] - c).norm() - r1).abs() < 1e-12);
    assert!(((v[1] - c).norm() - r2).abs() < 1e-12 && ((v[3] - c).norm() - r2).abs() < 1e-12);
    assert!(((v[0] - c) + (v[2] - c)).norm() < 1e-12);
    assert_eq!(g.initial_plane().normal, g.normal());
    m.check_invariants().unwrap();
    // Seen from below, the same points face down.
    let mut m = model();
    m.update(&set(&pts, Vector3::z())).unwrap();
    let g = m.segments().next().unwrap().as_polygon().unwrap().clone();
    assert!((g.normal().z + 1.0).abs() < 1e-9);
    m.check_invariants().unwrap();
}

/// P§2.4.1: opposing sensing axes (the points are on two sides of a thin sheet)
/// do not merge.
#[test]
fn opposing_sensing_axes_do_not_merge() {
    let mut m = model();
    let a = SensorSet::new(
        vec![p(0.0, 0.0, 0.0), p(0.01, 0.0, 0.0)],
        vec![unit(-Vector3::z()).unwrap(), unit(Vector3::z()).unwrap()],
    )
    .unwrap();
    m.update(&a).unwrap();
    assert_eq!(m.len(), 2);
    m.check_invariants().unwrap();
}

/// P Fig. 7: a point whose merger would tilt the plane more than μ from the
/// initial plane does not merge.
#[test]
fn fig7_initial_plane_drift_fails_the_merger() {
    let mut m = model();
    let id = m.insert_test_polygon(
        &[
            p(0.0, 0.0, 0.0),
            p(0.04, 0.0, 0.0),
            p(0.04, 0.04, 0.0),
            p(0.0, 0.04, 0.0),
        ],
        4,
    );
    m.treat_all_as_old();
    let g = m.poly(id).unwrap().clone();
    // A point well above the small polygon tilts the fit by more than μ.
    let centroid = p(0.06, 0.02, 0.03);
    let moments = m
        .get(id)
        .unwrap()
        .moments()
        .merged(&geom::Moments::from_point(&centroid));
    let pca = moments.pca().unwrap();
    let mut k = 1000;
    let mut fresh = || {
        k += 1;
        surface::EdgeKey(k)
    };
    let r = merge_point_polygon(&m, centroid, -Vector3::z(), &g, &pca, moments.m, &mut fresh);
    assert_eq!(r.err(), Some(MergeFailure::Drift));
}

/// P Fig. 9(a): a point just outside a polygon extends its perimeter, through
/// the public update.
#[test]
fn fig9a_point_extends_polygon() {
    let mut m = model();
    let mut pts = Vec::new();
    for i in 0..5 {
        for j in 0..5 {
            pts.push(p(0.02 * Real::from(i), 0.02 * Real::from(j), 0.0));
        }
    }
    m.update(&set(&pts, -Vector3::z())).unwrap();
    let before = m.segments().next().unwrap().as_polygon().unwrap().area();
    let log = m.update(&set(&[p(0.1, 0.04, 0.0)], -Vector3::z())).unwrap();
    assert_eq!(log.mergers.len(), 1);
    let g = m.segments().next().unwrap().as_polygon().unwrap().clone();
    assert!(g.area() > before);
    assert!(
        g.vertices().any(|v| (v - p(0.1, 0.04, 0.0)).norm() < 1e-9),
        "the point became a vertex"
    );
    // Changed edges are reported with their pre-update addresses.
    assert!(!log.changed_edges.is_empty());
    m.check_invariants().unwrap();
}

/// Two squares side by side: top of a cube (z = 1) and its +x side, each
/// stopping short of the edge by less than λ.
fn cube_edge(m: &mut SurfaceModel, gap_top: Real, gap_side: Real) -> (SegmentId, SegmentId) {
    let x1 = 0.5 - gap_top;
    let top = m.insert_test_polygon(
        &[
            p(-0.5, -0.4, 1.0),
            p(x1, -0.4, 1.0),
            p(x1, 0.3, 1.0),
            p(-0.5, 0.3, 1.0),
        ],
        200,
    );
    let z1 = 1.0 - gap_side;
    let side = m.insert_test_polygon(
        &[
            p(0.5, -0.3, 0.2),
            p(0.5, 0.4, 0.2),
            p(0.5, 0.4, z1),
            p(0.5, -0.3, z1),
        ],
        200,
    );
    (top, side)
}

/// P Fig. 14: after a merger tilts a polygon, its shared edges are repositioned
/// onto the new intersection line (the checker verifies them on the line).
#[test]
fn fig14_repositioning_after_merger() {
    let mut m = model();
    let (top, side) = cube_edge(&mut m, 0.02, 0.03);
    assert_eq!(m.form_shared_edges(top, side), ShareOutcome::Formed(1));
    let before: Vec<Point3> = m.poly(side).unwrap().vertices().collect();
    // Points above the top's far half tilt its plane slightly (within μ).
    let pts: Vec<Point3> = (0..6)
        .map(|k| p(-0.4 + 0.05 * Real::from(k), 0.0, 1.004))
        .collect();
    let log = m.update(&set(&pts, -Vector3::z())).unwrap();
    assert!(!log.mergers.is_empty());
    m.check_invariants().unwrap();
    let new_top = log.resolve(top).unwrap();
    assert_ne!(new_top, top);
    assert!(
        m.poly(new_top).unwrap().neighbours().contains(&side),
        "the shared edge survives"
    );
    let after: Vec<Point3> = m.poly(side).unwrap().vertices().collect();
    assert_ne!(
        before, after,
        "the neighbour's shared edge moved onto the new line"
    );
    assert!(m.max_line_offset(new_top) < 1e-9);
}

/// P Fig. 17: corresponding shared edges across a convex edge.
#[test]
fn fig17_shared_edges_formed() {
    let mut m = model();
    let (top, side) = cube_edge(&mut m, 0.02, 0.03);
    assert_eq!(m.form_shared_edges(top, side), ShareOutcome::Formed(1));
    m.check_invariants().unwrap();
    let t = m.poly(top).unwrap();
    let i = t
        .nodes()
        .iter()
        .position(|n| n.edge.share.is_some())
        .unwrap();
    let (a, b) = t.edge_points(i).unwrap();
    // Convex: the top's edge runs along n_top × n_side = +y.
    assert!(b.y > a.y);
    // A second attempt finds nothing new (no progress possible).
    assert_eq!(m.form_shared_edges(top, side), ShareOutcome::Formed(0));
}

/// P Fig. 19: a perimeter section holding two pairs of corresponding shared
/// edges is extended to one longer pair, which replaces both.
#[test]
fn fig19_formation_replaces_shared_edges() {
    let mut m = model();
    // The top has a notch deeper than λ in its edge, so two pairs form first.
    let top = m.insert_test_polygon(
        &[
            p(-0.5, -0.4, 1.0),
            p(0.47, -0.4, 1.0),
            p(0.47, -0.05, 1.0),
            p(0.41, -0.05, 1.0),
            p(0.41, 0.05, 1.0),
            p(0.47, 0.05, 1.0),
            p(0.47, 0.3, 1.0),
            p(-0.5, 0.3, 1.0),
        ],
        300,
    );
    let side = m.insert_test_polygon(
        &[
            p(0.5, -0.3, 0.2),
            p(0.5, 0.4, 0.2),
            p(0.5, 0.4, 0.97),
            p(0.5, -0.3, 0.97),
        ],
        300,
    );
    assert_eq!(m.form_shared_edges(top, side), ShareOutcome::Formed(2));
    m.check_invariants().unwrap();
    let old: Vec<_> = m
        .poly(top)
        .unwrap()
        .nodes()
        .iter()
        .filter_map(|n| n.edge.share.map(|s| s.pair))
        .collect();
    assert_eq!(old.len(), 2);
    // New points fill the notch (done here directly: the notch's bottom vertices go).
    m.retain_nodes(top, &mut |n| (n.position.x - 0.41).abs() > 1e-9);
    m.check_invariants().unwrap();
    assert_eq!(m.form_shared_edges(top, side), ShareOutcome::Formed(1));
    m.check_invariants().unwrap();
    let t = m.poly(top).unwrap();
    assert_eq!(t.shared_edge_count(), 1, "one pair replaces both");
    assert!(
        t.nodes()
            .iter()
            .all(|n| n.edge.share.is_none_or(|s| !old.contains(&s.pair)))
    );
    let i = t
        .nodes()
        .iter()
        .position(|n| n.edge.share.is_some())
        .unwrap();
    let (a, b) = t.edge_points(i).unwrap();
    assert!(
        (a.y + 0.3).abs() < 1e-9 && (b.y - 0.3).abs() < 1e-9,
        "{a} {b}"
    );
}

/// P Fig. 20(a), 21: a convex pair of non-neighbours, decided by the registers.
#[test]
fn fig20a_convex_by_registers() {
    let mut m = model();
    let (top, side) = cube_edge(&mut m, 0.02, 0.03);
    let (convex, concave) = m.registers_between(top, side).unwrap();
    assert!(convex > 0.5 && concave == 0.0, "{convex} {concave}");
    let line = m.line_between(top, side).unwrap();
    assert_eq!(m.concavity(top, side, &line), Concavity::Convex);
}

/// P Fig. 20(b): a concave pair (the inside corner of block1's step).
#[test]
fn fig20b_concave_by_registers() {
    let mut m = model();
    let floor = m.insert_test_polygon(
        &[
            p(0.02, -0.3, 0.4),
            p(0.6, -0.3, 0.4),
            p(0.6, 0.3, 0.4),
            p(0.02, 0.3, 0.4),
        ],
        200,
    );
    let wall = m.insert_test_polygon(
        &[
            p(0.0, -0.3, 0.43),
            p(0.0, 0.3, 0.43),
            p(0.0, 0.3, 0.8),
            p(0.0, -0.3, 0.8),
        ],
        200,
    );
    let line = m.line_between(floor, wall).unwrap();
    assert_eq!(m.concavity(floor, wall, &line), Concavity::Concave);
    assert_eq!(m.form_shared_edges(floor, wall), ShareOutcome::Formed(1));
    m.check_invariants().unwrap();
}

/// P Fig. 22: centroids say convex (each centroid inside the other's plane), but
/// local to their overlap on the intersection line the segments meet concavely,
/// and the registers decide concave.
#[test]
fn fig22_registers_override_centroids() {
    let mut m = model();
    // S1: a U in the plane z = 0 (normal +z), bulk at x < 0, an arm whose left
    // edge runs along x = 0.005 in -y.
    let s1 = m.insert_test_polygon(
        &[
            p(-1.0, -0.5, 0.0),
            p(-0.2, -0.5, 0.0),
            p(-0.2, 0.5, 0.0),
            p(0.005, 0.5, 0.0),
            p(0.005, -0.5, 0.0),
            p(0.3, -0.5, 0.0),
            p(0.3, 0.7, 0.0),
            p(-1.0, 0.7, 0.0),
        ],
        400,
    );
    // S2: a U in the plane x = 0 (normal +x), bulk at z < 0, an arm whose
    // bottom edge runs along z = 0.005 in +y.
    let s2 = m.insert_test_polygon(
        &[
            p(0.0, -0.5, -1.0),
            p(0.0, 0.7, -1.0),
            p(0.0, 0.7, 0.3),
            p(0.0, -0.5, 0.3),
            p(0.0, -0.5, 0.005),
            p(0.0, 0.5, 0.005),
            p(0.0, 0.5, -0.2),
            p(0.0, -0.5, -0.2),
        ],
        400,
    );
    m.check_invariants().unwrap();
    let (a, b) = (m.poly(s1).unwrap().clone(), m.poly(s2).unwrap().clone());
    assert!(
        b.plane().signed_distance(&a.centroid()) < 0.0
            && a.plane().signed_distance(&b.centroid()) < 0.0
    );
    let (convex, concave) = m.registers_between(s1, s2).unwrap();
    assert!(concave > convex, "{convex} {concave}");
    let line = m.line_between(s1, s2).unwrap();
    assert_eq!(m.concavity(s1, s2, &line), Concavity::Concave);
}

/// P Fig. 20(c) / §2.6.1: equal registers leave the concavity undecided.
#[test]
fn fig20c_undecided() {
    let mut m = model();
    // Two squares crossing at right angles, perpendicular to the line's
    // direction near it: no edge projects onto the line with length.
    let s1 = m.insert_test_polygon(
        &[
            p(-0.2, -0.2, 0.0),
            p(0.2, -0.2, 0.0),
            p(0.2, 0.2, 0.0),
            p(-0.2, 0.2, 0.0),
        ],
        100,
    );
    let s2 = m.insert_test_polygon(
        &[
            p(0.0, -0.2, -0.2),
            p(0.0, 0.2, -0.2),
            p(0.0, 0.2, 0.2),
            p(0.0, -0.2, 0.2),
        ],
        100,
    );
    let (convex, concave) = m.registers_between(s1, s2).unwrap();
    assert_eq!(convex, concave);
    let line = m.line_between(s1, s2).unwrap();
    assert_eq!(m.concavity(s1, s2, &line), Concavity::Undecided);
}

/// Four roof faces around an apex whose planes do not meet in one point.
fn roof(m: &mut SurfaceModel) -> Vec<SegmentId> {
    let heights = [1.0, 1.003, 1.0, 1.006];
    let slope: Real = 0.5;
    let mut ids = Vec::new();
    for (i, h) in heights.iter().enumerate() {
        let th = Real::from(u8::try_from(i).unwrap()) * std::f64::consts::FRAC_PI_2;
        let (c, s) = (th.cos(), th.sin());
        // Plane: z = h - slope·(x c + y s).
        let z = |x: Real, y: Real| h - slope * (x * c + y * s);
        // Sector between the diagonals at th ± 45°, inset by 1 cm, radius 0.4.
        let dir = |a: Real| (a.cos(), a.sin());
        let inset = 0.01;
        let (l, r) = (
            dir(th - std::f64::consts::FRAC_PI_4),
            dir(th + std::f64::consts::FRAC_PI_4),
        );
        let off =
            |d: (Real, Real), sign: Real| (d.0 + sign * inset * d.1, d.1 - sign * inset * d.0);
        let (l0, r0) = (
            off((l.0 * 0.04, l.1 * 0.04), -1.0),
            off((r.0 * 0.04, r.1 * 0.04), 1.0),
        );
        let (lm, rm) = (
            off((l.0 * 0.1, l.1 * 0.1), -1.0),
            off((r.0 * 0.1, r.1 * 0.1), 1.0),
        );
        let (l1, r1) = (
            off((l.0 * 0.4, l.1 * 0.4), -1.0),
            off((r.0 * 0.4, r.1 * 0.4), 1.0),
        );
        let pts2 = [l0, lm, l1, r1, rm, r0];
        let pts: Vec<Point3> = pts2.iter().map(|&(x, y)| p(x, y, z(x, y))).collect();
        ids.push(m.insert_test_polygon(&pts, 300));
    }
    ids
}

/// P Fig. 23–24: a corner cycle over four segments forms four corner vertices,
/// one per segment at the intersection of its own two lines; the planes do not
/// meet in one point, so the corner vertices do not coincide.
#[test]
fn fig23_four_segment_corner_cycle() {
    let mut m = model();
    let ids = roof(&mut m);
    m.check_invariants().unwrap();
    for k in 0..4 {
        let (a, b) = (ids[k], ids[(k + 1) % 4]);
        assert_eq!(
            m.form_shared_edges(a, b),
            ShareOutcome::Formed(1),
            "pair {k}"
        );
        m.check_invariants().unwrap();
    }
    assert_eq!(m.form_corners(ids[0]), 1);
    m.check_invariants().unwrap();
    let corners: Vec<Point3> = ids
        .iter()
        .map(|id| {
            let g = m.poly(*id).unwrap();
            assert_eq!(g.corner_count(), 1);
            g.nodes()
                .iter()
                .find(|n| n.corner.is_some())
                .unwrap()
                .position
        })
        .collect();
    for i in 0..4 {
        for j in i + 1..4 {
            assert!(
                (corners[i] - corners[j]).norm() > 1e-4,
                "corners {i} and {j} coincide"
            );
        }
        // Each is where its segment's plane meets both neighbours' planes.
        let (prev, next) = (ids[(i + 3) % 4], ids[(i + 1) % 4]);
        let c = m.corner_point(prev, ids[i], next).unwrap();
        assert!((c - corners[i]).norm() < 1e-9);
    }
    assert_eq!(m.stats().corner_vertices, 4);
}

/// P§2.8: unsharing an edge at a corner makes every corresponding corner vertex
/// a non-corner vertex; a vertex left joining edges shared with two different
/// neighbours is duplicated.
#[test]
fn unsharing_dissolves_the_corner_cycle() {
    let mut m = model();
    let ids = roof(&mut m);
    for k in 0..4 {
        m.form_shared_edges(ids[k], ids[(k + 1) % 4]);
    }
    assert_eq!(m.form_corners(ids[0]), 1);
    let pair = m
        .poly(ids[0])
        .unwrap()
        .nodes()
        .iter()
        .find_map(|n| n.edge.share.filter(|s| s.neighbour == ids[1]))
        .unwrap()
        .pair;
    let n_before = m.poly(ids[2]).unwrap().len();
    m.unshare_pair_committed(ids[0], pair);
    m.check_invariants().unwrap();
    assert_eq!(m.stats().corner_vertices, 0);
    assert!(!m.are_neighbours(ids[0], ids[1]));
    // Segments 2 and 3 keep two shared edges each joined at a former corner: the
    // vertex was duplicated (P§2.8), adding a short edge.
    assert_eq!(m.poly(ids[2]).unwrap().len(), n_before + 1);
}

/// P Fig. 25–26, §2.9: a small polygon between others, for which shared edges
/// cannot be formed, is deleted as redundant (n₁ < ψ and n₁/n₂ < φ).
#[test]
fn fig25_redundant_segment_deleted() {
    let mut m = model();
    let big = m.insert_test_polygon(
        &[
            p(-0.2, -0.2, 0.0),
            p(0.2, -0.2, 0.0),
            p(0.2, 0.2, 0.0),
            p(-0.2, 0.2, 0.0),
        ],
        400,
    );
    let small = m.insert_test_polygon(
        &[
            p(0.0, -0.02, -0.02),
            p(0.0, 0.02, -0.02),
            p(0.0, 0.02, 0.02),
            p(0.0, -0.02, 0.02),
        ],
        5,
    );
    m.mark_modified(small);
    m.begin();
    m.shared_edges_of(small);
    m.commit();
    assert!(m.get(small).is_none(), "the redundant segment is deleted");
    assert!(m.get(big).is_some());
    assert_eq!(m.deleted_in_update(), &[small]);
    // The deleted polygon is kept as it was (a follower's safety guard
    // still needs the surface it stood for).
    let gone = m.deleted_by_last_update();
    assert_eq!(gone.len(), 1);
    assert_eq!(gone[0].id(), small);
    let corners: Vec<_> = gone[0].as_polygon().unwrap().vertices().collect();
    assert_eq!(corners.len(), 4);
    for c in [p(0.0, -0.02, -0.02), p(0.0, 0.02, 0.02)] {
        assert!(corners.iter().any(|v| (v - c).norm() < 1e-9), "{c:?} kept");
    }
    assert_eq!(m.points_deleted(), 5);
    m.check_invariants().unwrap();
    // With more points it is not redundant.
    let mut m = model();
    m.insert_test_polygon(
        &[
            p(-0.2, -0.2, 0.0),
            p(0.2, -0.2, 0.0),
            p(0.2, 0.2, 0.0),
            p(-0.2, 0.2, 0.0),
        ],
        400,
    );
    let small = m.insert_test_polygon(
        &[
            p(0.0, -0.02, -0.02),
            p(0.0, 0.02, -0.02),
            p(0.0, 0.02, 0.02),
            p(0.0, -0.02, 0.02),
        ],
        30,
    );
    m.begin();
    m.shared_edges_of(small);
    m.commit();
    assert!(m.get(small).is_some());
}

/// Issue 9, beyond P§2.9: a small polygon lying on a larger one's surface
/// (within λ of its plane, on both sides of it) is deleted as redundant
/// where it would otherwise share edges with it; a small polygon of a new face beside the
/// larger one's edge (on one side of its plane) is kept.
#[test]
fn stray_on_a_face_is_deleted() {
    let big_square = [
        p(-0.2, -0.2, 0.0),
        p(0.2, -0.2, 0.0),
        p(0.2, 0.2, 0.0),
        p(-0.2, 0.2, 0.0),
    ];
    // A noisy stray: 6 points on the face fitted by a plane tilted 45° about
    // y, crossing the face's plane; it ends 1 cm inside the face's edge.
    let mut m = model();
    let big = m.insert_test_polygon(&big_square, 400);
    let stray = m.insert_test_polygon(
        &[
            p(0.15, -0.03, 0.02),
            p(0.19, -0.03, -0.02),
            p(0.19, 0.03, -0.02),
            p(0.15, 0.03, 0.02),
        ],
        6,
    );
    let n = m.poly(stray).unwrap().normal();
    assert!(n.x > 0.5 && n.z > 0.5, "tilted outward: {n:?}");
    m.mark_modified(big);
    m.begin();
    m.shared_edges_of(big);
    m.commit();
    assert!(m.get(stray).is_none(), "the stray is deleted");
    assert_eq!(m.deleted_in_update(), &[stray]);
    assert_eq!(m.points_deleted(), 6);
    m.check_invariants().unwrap();
    // The first polygon of the +x side below the face's edge: it lies within
    // λ of the face's plane, but all on its inner side, and forms shared edges
    // with the face instead.
    let mut m = model();
    let big = m.insert_test_polygon(&big_square, 400);
    let side = m.insert_test_polygon(
        &[
            p(0.2, -0.03, -0.04),
            p(0.2, 0.03, -0.04),
            p(0.2, 0.03, -0.01),
            p(0.2, -0.03, -0.01),
        ],
        6,
    );
    m.mark_modified(big);
    m.begin();
    m.shared_edges_of(big);
    m.commit();
    assert!(m.get(side).is_some(), "a new face beside the edge is kept");
    assert!(m.are_neighbours(big, side));
    m.check_invariants().unwrap();
}

/// Issue 9, beyond P§2.4.2: while a polygon represents fewer than ψ points its
/// initial plane follows its plane of best fit; from ψ points on it stays
/// fixed. The drift check still applies to each merger (Fig. 7 above).
#[test]
fn young_polygon_initial_plane_follows_its_fit() {
    let square = [
        p(0.0, 0.0, 0.0),
        p(0.04, 0.0, 0.0),
        p(0.04, 0.04, 0.0),
        p(0.0, 0.04, 0.0),
    ];
    // A point slightly above the polygon's edge tilts the fit by less than μ.
    let point = p(0.05, 0.02, 0.002);
    for (points, follows) in [(8, true), (40, false)] {
        let mut m = model();
        let id = m.insert_test_polygon(&square, points);
        let g = m.poly(id).unwrap().clone();
        let moments = m
            .get(id)
            .unwrap()
            .moments()
            .merged(&geom::Moments::from_point(&point));
        let pca = moments.pca().unwrap();
        let mut k = 1000;
        let mut fresh = || {
            k += 1;
            surface::EdgeKey(k)
        };
        let (merged, _) =
            merge_point_polygon(&m, point, -Vector3::z(), &g, &pca, moments.m, &mut fresh).unwrap();
        assert!(
            merged.normal().dot(&g.normal()) < 1.0 - 1e-9,
            "the fit tilted"
        );
        let init = merged.initial_plane();
        if follows {
            assert!((init.normal.dot(&merged.normal()) - 1.0).abs() < 1e-12);
            assert!(init.signed_distance(&merged.centroid()).abs() < 1e-12);
        } else {
            assert_eq!(init, g.initial_plane());
        }
    }
}

/// P§4.3: initial segments represent no points, never merge, but share edges.
#[test]
fn initial_segments_share_but_never_merge() {
    let mut m = model();
    let table = m
        .add_initial_segment(&[
            p(-2.0, -2.0, 0.0),
            p(2.0, -2.0, 0.0),
            p(2.0, 2.0, 0.0),
            p(-2.0, 2.0, 0.0),
        ])
        .unwrap();
    // Points on the table do not merge into it.
    let pts: Vec<Point3> = (0..5).map(|k| p(0.01 * Real::from(k), 0.0, 0.0)).collect();
    m.update(&set(&pts, -Vector3::z())).unwrap();
    assert_eq!(m.segment(table).unwrap().points(), 0);
    assert!(
        m.segments()
            .filter(|s| s.id() != table)
            .all(|s| s.points() > 0)
    );
    m.check_invariants().unwrap();
    // A wall standing on a table whose edge runs along its foot shares an edge.
    let mut m = model();
    let table = m
        .add_initial_segment(&[
            p(0.02, -0.5, 0.0),
            p(1.0, -0.5, 0.0),
            p(1.0, 0.5, 0.0),
            p(0.02, 0.5, 0.0),
        ])
        .unwrap();
    let wall = m.insert_test_polygon(
        &[
            p(0.0, -0.4, 0.03),
            p(0.0, 0.4, 0.03),
            p(0.0, 0.4, 0.5),
            p(0.0, -0.4, 0.5),
        ],
        100,
    );
    assert_eq!(m.form_shared_edges(wall, table), ShareOutcome::Formed(1));
    m.check_invariants().unwrap();
    assert!(
        matches!(m.segment(table).unwrap().kind(), SegmentKind::Polygon(g) if g.is_initial() && g.shared_edge_count() == 1)
    );
}

/// P§2.4.3 "merging neighbours": neighbours are dissolved before their merger is
/// attempted; the merger result shares no edge with itself.
#[test]
fn neighbours_are_dissolved_then_merged() {
    let mut m = model();
    // Two halves of a gently folded sheet (fold 12°), sharing an edge; a merger
    // is attempted as if a plane change had brought them within μ.
    let a = m.insert_test_polygon(
        &[
            p(-0.4, -0.2, 0.0),
            p(0.0, -0.2, 0.0),
            p(0.0, 0.2, 0.0),
            p(-0.4, 0.2, 0.0),
        ],
        200,
    );
    let t: Real = 12f64.to_radians().tan();
    let b = m.insert_test_polygon(
        &[
            p(0.02, -0.2, 0.02 * t),
            p(0.4, -0.2, 0.4 * t),
            p(0.4, 0.2, 0.4 * t),
            p(0.02, 0.2, 0.02 * t),
        ],
        200,
    );
    assert_eq!(m.form_shared_edges(a, b), ShareOutcome::Formed(1));
    assert!(m.are_neighbours(a, b));
    let c = m.try_merge(a, b).unwrap();
    m.clear_pending();
    m.check_invariants().unwrap();
    let g = m.poly(c).unwrap();
    assert!(g.neighbours().is_empty());
    assert_eq!(m.segment(c).unwrap().points(), 400);
    // Polygons 25° apart, whose merged plane would drift more than μ from
    // either, do not merge, and stay dissolved.
    let mut m = model();
    let t: Real = 25f64.to_radians().tan();
    let a = m.insert_test_polygon(
        &[
            p(-0.4, -0.2, 0.0),
            p(0.0, -0.2, 0.0),
            p(0.0, 0.2, 0.0),
            p(-0.4, 0.2, 0.0),
        ],
        200,
    );
    let b = m.insert_test_polygon(
        &[
            p(0.02, -0.2, 0.02 * t),
            p(0.4, -0.2, 0.4 * t),
            p(0.4, 0.2, 0.4 * t),
            p(0.02, 0.2, 0.02 * t),
        ],
        200,
    );
    assert_eq!(m.form_shared_edges(a, b), ShareOutcome::Formed(1));
    assert_eq!(m.try_merge(a, b), Err(MergeFailure::Drift));
    assert!(!m.are_neighbours(a, b));
    m.check_invariants().unwrap();
}
