//! Closed triangle meshes of the shapes scenes are made of: boxes, prisms from a
//! 2-D profile, I-beams, cylinders. All have outward normals (positive volume).

use crate::math::{Isometry3, Point2, Point3, Real, Rotation3, UnitVector3, Vector3, unit};
use crate::mesh::{MeshError, TriMesh};
use crate::polygon2::{is_simple, orient2d, signed_area};

/// The box `[min, max]` (12 triangles).
pub fn cuboid(min: Point3, max: Point3) -> TriMesh {
    let profile = [
        Point2::new(min.y, min.z),
        Point2::new(max.y, min.z),
        Point2::new(max.y, max.z),
        Point2::new(min.y, max.z),
    ];
    // A box is a prism of its y-z rectangle along x; a rectangle never fails.
    prism_x(&profile, min.x, max.x).unwrap_or_default()
}

/// A prism: the simple polygon `profile` in the (y, z) plane extruded along x
/// from `x0` to `x1`. Either winding of the profile is accepted.
pub fn prism_x(profile: &[Point2], x0: Real, x1: Real) -> Result<TriMesh, MeshError> {
    let mut prof: Vec<Point2> = profile.to_vec();
    // Drop a repeated closing vertex.
    if prof.len() > 3 && prof.first() == prof.last() {
        prof.pop();
    }
    if prof.len() < 3 || !is_simple(&prof, 1e-12) {
        return Err(MeshError::new(
            "prism profile",
            "expected a simple polygon of at least 3 distinct vertices",
        ));
    }
    if !(x1 - x0).is_finite() || (x1 - x0).abs() <= 0.0 {
        return Err(MeshError::new(
            "prism extent",
            format!("expected two different finite ends, got {x0} and {x1}"),
        ));
    }
    if signed_area(&prof) < 0.0 {
        prof.reverse();
    }
    let (lo, hi) = if x0 < x1 { (x0, x1) } else { (x1, x0) };
    let n = prof.len() as u32;
    let mut vertices = Vec::with_capacity(2 * prof.len());
    for p in &prof {
        vertices.push(Point3::new(lo, p.x, p.y));
    }
    for p in &prof {
        vertices.push(Point3::new(hi, p.x, p.y));
    }
    let mut triangles = Vec::new();
    // Profile anticlockwise in (y, z) runs anticlockwise about +x: the cap at
    // `hi` keeps that winding, the cap at `lo` is reversed.
    for [a, b, c] in triangulate(&prof) {
        triangles.push([n + a, n + b, n + c]);
        triangles.push([a, c, b]);
    }
    for i in 0..n {
        let j = (i + 1) % n;
        // Side quad lo_i, lo_j, hi_j, hi_i: (lo_j - lo_i) × (hi_j - lo_i) points
        // to the right of the anticlockwise profile edge, i.e. outward.
        triangles.push([i, j, n + j]);
        triangles.push([i, n + j, n + i]);
    }
    let mut mesh = TriMesh {
        vertices,
        triangles,
    };
    if mesh.signed_volume() < 0.0 {
        mesh.flip();
    }
    Ok(mesh)
}

/// Which world axis a prism is extruded along.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// Extrude along x; the profile is given in (y, z).
    X,
    /// Extrude along y; the profile is given in (x, z).
    Y,
    /// Extrude along z; the profile is given in (x, y).
    Z,
}

/// A prism along a world axis, the profile given in the other two coordinates
/// in increasing order ((y, z) for x, (x, z) for y, (x, y) for z).
pub fn prism(axis: Axis, profile: &[Point2], from: Real, to: Real) -> Result<TriMesh, MeshError> {
    let mut mesh = prism_x(profile, from, to)?;
    // prism_x puts profile (u, v) at (y, z) and extrusion on x; permute coordinates.
    for v in &mut mesh.vertices {
        let (w, a, b) = (v.x, v.y, v.z);
        *v = match axis {
            Axis::X => Point3::new(w, a, b),
            Axis::Y => Point3::new(a, w, b),
            Axis::Z => Point3::new(a, b, w),
        };
    }
    // An odd permutation (x→y swap) mirrors the mesh: restore outward winding.
    if mesh.signed_volume() < 0.0 {
        mesh.flip();
    }
    Ok(mesh)
}

/// Dimensions of an I-section.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IBeamSection {
    /// Overall depth (outer face of one flange to the other).
    pub depth: Real,
    /// Flange width.
    pub flange_width: Real,
    /// Flange thickness.
    pub flange_thickness: Real,
    /// Web thickness.
    pub web_thickness: Real,
}

/// An I-beam from `from` to `to`, the points being the middle of the bottom
/// flange's outer face at either end; `up` points from the bottom flange to the
/// top one (made perpendicular to the beam axis).
pub fn i_beam(
    from: &Point3,
    to: &Point3,
    up: &Vector3,
    s: &IBeamSection,
) -> Result<TriMesh, MeshError> {
    let dims = [s.depth, s.flange_width, s.flange_thickness, s.web_thickness];
    if dims.iter().any(|v| !v.is_finite() || *v <= 0.0)
        || 2.0 * s.flange_thickness >= s.depth
        || s.web_thickness >= s.flange_width
    {
        return Err(MeshError::new(
            "i_beam",
            "expected positive dimensions with 2·flange_thickness < depth and web_thickness < flange_width",
        ));
    }
    let axis = unit(to - from)
        .ok_or_else(|| MeshError::new("i_beam", "`from` and `to` must be different points"))?;
    let up = unit(up - axis.into_inner() * axis.dot(up))
        .ok_or_else(|| MeshError::new("i_beam", "`up` must not be parallel to the beam"))?;
    let side = UnitVector3::new_unchecked(up.cross(&axis));
    let (hw, hf, tf, d) = (
        0.5 * s.web_thickness,
        0.5 * s.flange_width,
        s.flange_thickness,
        s.depth,
    );
    // Profile in (side, up) coordinates, anticlockwise.
    let profile = [
        Point2::new(-hf, 0.0),
        Point2::new(hf, 0.0),
        Point2::new(hf, tf),
        Point2::new(hw, tf),
        Point2::new(hw, d - tf),
        Point2::new(hf, d - tf),
        Point2::new(hf, d),
        Point2::new(-hf, d),
        Point2::new(-hf, d - tf),
        Point2::new(-hw, d - tf),
        Point2::new(-hw, tf),
        Point2::new(-hf, tf),
    ];
    let mut mesh = prism_x(&profile, 0.0, (to - from).norm())?;
    // Local frame: x = beam axis, y = side, z = up.
    let rot =
        Rotation3::from_basis_unchecked(&[axis.into_inner(), side.into_inner(), up.into_inner()]);
    let pose = Isometry3::from_parts(from.coords.into(), rot.into());
    mesh.transform(&pose);
    if mesh.signed_volume() < 0.0 {
        mesh.flip();
    }
    Ok(mesh)
}

/// A closed cylinder of `radius` from `from` to `to` with `segments` sides.
pub fn cylinder(
    from: &Point3,
    to: &Point3,
    radius: Real,
    segments: u32,
) -> Result<TriMesh, MeshError> {
    if !(radius.is_finite() && radius > 0.0) || segments < 3 {
        return Err(MeshError::new(
            "cylinder",
            format!("expected radius > 0 and at least 3 segments, got {radius} and {segments}"),
        ));
    }
    let axis = unit(to - from)
        .ok_or_else(|| MeshError::new("cylinder", "`from` and `to` must be different points"))?;
    let profile: Vec<Point2> = (0..segments)
        .map(|i| {
            let a = std::f64::consts::TAU * Real::from(i) / Real::from(segments);
            Point2::new(radius * a.cos(), radius * a.sin())
        })
        .collect();
    let mut mesh = prism_x(&profile, 0.0, (to - from).norm())?;
    let u = crate::math::any_perpendicular(&axis);
    let v = axis.cross(&u);
    let rot = Rotation3::from_basis_unchecked(&[axis.into_inner(), u.into_inner(), v]);
    mesh.transform(&Isometry3::from_parts(from.coords.into(), rot.into()));
    if mesh.signed_volume() < 0.0 {
        mesh.flip();
    }
    Ok(mesh)
}

/// Ear-clipping triangulation of a simple anticlockwise polygon; returns vertex
/// index triples, anticlockwise. A vertex in line with its neighbours is
/// dropped without a triangle (perimeters often carry such vertices).
pub fn triangulate(poly: &[Point2]) -> Vec<[u32; 3]> {
    // Zero for twice a triangle's area, relative to the polygon's size.
    let scale = poly
        .iter()
        .map(|p| p.x.abs().max(p.y.abs()))
        .fold(0.0, Real::max)
        .max(1e-9);
    let eps = 1e-12 * scale * scale;
    let mut idx: Vec<u32> = (0..poly.len() as u32).collect();
    let mut out = Vec::with_capacity(poly.len().saturating_sub(2));
    let mut guard = 0usize;
    while idx.len() > 3 && guard < poly.len() * poly.len() {
        guard += 1;
        let n = idx.len();
        let mut clipped = false;
        for k in 0..n {
            let (ia, ib, ic) = (idx[(k + n - 1) % n], idx[k], idx[(k + 1) % n]);
            let (a, b, c) = (&poly[ia as usize], &poly[ib as usize], &poly[ic as usize]);
            let turn = orient2d(a, b, c);
            if turn.abs() <= eps {
                idx.remove(k); // in line with its neighbours
                clipped = true;
                break;
            }
            if turn < 0.0 {
                continue; // reflex corner
            }
            let blocked = idx.iter().any(|&j| {
                if j == ia || j == ib || j == ic {
                    return false;
                }
                let p = &poly[j as usize];
                orient2d(a, b, p) >= 0.0 && orient2d(b, c, p) >= 0.0 && orient2d(c, a, p) >= 0.0
            });
            if !blocked {
                out.push([ia, ib, ic]);
                idx.remove(k);
                clipped = true;
                break;
            }
        }
        if !clipped {
            break; // numerically degenerate remainder: fan it
        }
    }
    if idx.len() >= 3 {
        for k in 1..idx.len() - 1 {
            let t = [idx[0], idx[k], idx[k + 1]];
            let [a, b, c] = t.map(|i| &poly[i as usize]);
            if orient2d(a, b, c).abs() > eps {
                out.push(t);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertex_normals_point_out_along_the_corner_diagonal() {
        // A cuboid corner vertex touches its three faces through one or two
        // triangles each; whatever the split, every face contributes with its
        // triangles' area, so the normal points out of the corner octant.
        let m = cuboid(Point3::new(-1.0, -1.0, -1.0), Point3::new(1.0, 1.0, 1.0));
        let normals = m.vertex_normals();
        for (v, n) in m.vertices.iter().zip(&normals) {
            assert!((n.norm() - 1.0).abs() < 1e-12);
            for k in 0..3 {
                assert!(n[k] * v[k] > 0.1, "vertex {v:?} normal {n:?}");
            }
        }
        // A flat patch: +z for anticlockwise triangles seen from above, −z flipped.
        let mut patch = TriMesh::new(
            vec![
                Point3::new(0.0, 0.0, 2.0),
                Point3::new(1.0, 0.0, 2.0),
                Point3::new(1.0, 1.0, 2.0),
                Point3::new(0.0, 1.0, 2.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
            "patch",
        )
        .unwrap();
        assert!(
            patch
                .vertex_normals()
                .iter()
                .all(|n| (n.z - 1.0).abs() < 1e-12)
        );
        patch.flip();
        assert!(
            patch
                .vertex_normals()
                .iter()
                .all(|n| (n.z + 1.0).abs() < 1e-12)
        );
        let lonely = TriMesh::new(vec![Point3::origin()], vec![], "t").unwrap();
        assert_eq!(lonely.vertex_normals(), vec![Vector3::zeros()]);
    }

    #[test]
    fn cuboid_is_closed_with_outward_normals() {
        let m = cuboid(Point3::new(-1.0, -2.0, 0.0), Point3::new(1.0, 2.0, 3.0));
        assert_eq!(m.len(), 12);
        assert_eq!(m.boundary_edge_count(), 0);
        assert!((m.signed_volume() - 24.0).abs() < 1e-12);
        assert!((m.area() - 2.0 * (8.0 + 12.0 + 6.0)).abs() < 1e-12);
        // Every face normal points away from the centre.
        for t in m.iter_triangles() {
            let n = t.normal().unwrap();
            assert!(n.dot(&(t.centroid() - Point3::new(0.0, 0.0, 1.5))) > 0.0);
        }
    }

    #[test]
    fn l_prism_volume_and_area() {
        let l = [
            Point2::new(-0.6, 0.0),
            Point2::new(0.6, 0.0),
            Point2::new(0.6, 0.4),
            Point2::new(0.0, 0.4),
            Point2::new(0.0, 0.8),
            Point2::new(-0.6, 0.8),
        ];
        for axis in [Axis::X, Axis::Y, Axis::Z] {
            let m = prism(axis, &l, -0.35, 0.35).unwrap();
            assert_eq!(m.boundary_edge_count(), 0);
            let profile_area = 1.2 * 0.4 + 0.6 * 0.4;
            assert!((m.signed_volume() - profile_area * 0.7).abs() < 1e-12);
            let perimeter = 1.2 + 0.4 + 0.6 + 0.4 + 0.6 + 0.8;
            assert!((m.area() - (2.0 * profile_area + perimeter * 0.7)).abs() < 1e-12);
        }
        // Clockwise input is accepted too.
        let mut cw = l.to_vec();
        cw.reverse();
        assert!(prism(Axis::Y, &cw, 0.0, 1.0).unwrap().signed_volume() > 0.0);
        // Self-crossing profile is rejected.
        let bow = [
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(1.0, 0.0),
            Point2::new(0.0, 1.0),
        ];
        assert!(prism(Axis::X, &bow, 0.0, 1.0).is_err());
    }

    #[test]
    fn i_beam_matches_the_bridge_boxes() {
        // bridge1's left beam: flanges y [0.60, 0.90], web y [0.744, 0.756], z 0.80–1.52.
        let s = IBeamSection {
            depth: 0.72,
            flange_width: 0.30,
            flange_thickness: 0.02,
            web_thickness: 0.012,
        };
        let m = i_beam(
            &Point3::new(-2.0, 0.75, 0.80),
            &Point3::new(2.0, 0.75, 0.80),
            &Vector3::z(),
            &s,
        )
        .unwrap();
        let bb = m.bounding_box();
        assert!((bb.min - Point3::new(-2.0, 0.60, 0.80)).norm() < 1e-12);
        assert!((bb.max - Point3::new(2.0, 0.90, 1.52)).norm() < 1e-12);
        let area_profile = 2.0 * 0.30 * 0.02 + 0.012 * 0.68;
        assert!((m.signed_volume() - 4.0 * area_profile).abs() < 1e-12);
        assert_eq!(m.boundary_edge_count(), 0);
        // The web's faces are at y = 0.744 and 0.756.
        let web_face = m.iter_triangles().any(|t| {
            (t.a.y - 0.744).abs() < 1e-12
                && (t.b.y - 0.744).abs() < 1e-12
                && (t.c.y - 0.744).abs() < 1e-12
        });
        assert!(web_face);
    }

    #[test]
    fn cylinder_area_converges() {
        let m = cylinder(
            &Point3::new(0.0, 0.0, 0.0),
            &Point3::new(0.0, 0.0, 0.8),
            0.4,
            256,
        )
        .unwrap();
        let exact = std::f64::consts::TAU * 0.4 * 0.8 + 2.0 * std::f64::consts::PI * 0.16;
        assert!((m.area() - exact).abs() / exact < 1e-3);
        assert!(m.signed_volume() > 0.0);
        assert_eq!(m.boundary_edge_count(), 0);
        assert!(cylinder(&Point3::origin(), &Point3::origin(), 0.4, 8).is_err());
    }
}
