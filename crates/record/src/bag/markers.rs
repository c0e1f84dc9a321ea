//! `visualization_msgs/MarkerArray`s of what a run made: its viewpoints
//! (an arrow along each scanner's centre ray), its discs (flat cylinders,
//! coloured by material) and its surface model (polygon outlines, points).

use super::ROOT_FRAME;
use super::msg::{ColorRgba, Header, Marker, MarkerArray, Pose, Vector3};
use geom::{Isometry3, Point3, Real, UnitVector3};

/// One arrow per scanner pose (world frame), along the centre ray (the
/// scanner frame's z, A eq. 3.10), 0.3 m long; namespace `viewpoints`,
/// ids in order.
pub fn viewpoints(stamp_ns: u64, scanner_poses: &[Isometry3]) -> MarkerArray {
    // The arrow marker points along its pose's x: turn our z onto it.
    let x_from_z = super::scanner_from_laser();
    let markers = scanner_poses
        .iter()
        .enumerate()
        .map(|(k, pose)| Marker {
            header: Header::new(stamp_ns, ROOT_FRAME),
            ns: "viewpoints".to_owned(),
            id: i32::try_from(k).unwrap_or(i32::MAX),
            kind: Marker::ARROW,
            pose: Pose::from(&(pose * x_from_z)),
            scale: Vector3 {
                x: 0.3,
                y: 0.02,
                z: 0.02,
            },
            color: ColorRgba {
                r: 1.0,
                g: 0.6,
                b: 0.0,
                a: 1.0,
            },
            ..Marker::default()
        })
        .collect();
    MarkerArray { markers }
}

/// A disc to draw: centre, normal, radius, and its material (an index into
/// the run's materials, `None` when unknown).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiscMark {
    /// Centre, world frame.
    pub centre: Point3,
    /// Unit normal.
    pub normal: UnitVector3,
    /// Radius, metres.
    pub radius: Real,
    /// Material index.
    pub material: Option<usize>,
}

/// Distinct colours for material indices (unknown: grey).
fn material_colour(material: Option<usize>) -> ColorRgba {
    const PALETTE: [(f32, f32, f32); 8] = [
        (0.12, 0.47, 0.71),
        (1.0, 0.5, 0.05),
        (0.17, 0.63, 0.17),
        (0.84, 0.15, 0.16),
        (0.58, 0.4, 0.74),
        (0.55, 0.34, 0.29),
        (0.89, 0.47, 0.76),
        (0.74, 0.74, 0.13),
    ];
    let (r, g, b) = material.map_or((0.5, 0.5, 0.5), |m| PALETTE[m % PALETTE.len()]);
    ColorRgba { r, g, b, a: 1.0 }
}

/// One flat cylinder (2 mm thick) per disc, on the disc's plane, coloured
/// by material; namespace `discs`, ids in order.
pub fn discs(stamp_ns: u64, discs: &[DiscMark]) -> MarkerArray {
    let markers = discs
        .iter()
        .enumerate()
        .map(|(k, d)| {
            let rotation = super::run::turn_onto(&geom::Vector3::z_axis(), &d.normal);
            let pose = Isometry3::from_parts(d.centre.coords.into(), rotation);
            Marker {
                header: Header::new(stamp_ns, ROOT_FRAME),
                ns: "discs".to_owned(),
                id: i32::try_from(k).unwrap_or(i32::MAX),
                kind: Marker::CYLINDER,
                pose: Pose::from(&pose),
                scale: Vector3 {
                    x: 2.0 * d.radius,
                    y: 2.0 * d.radius,
                    z: 0.002,
                },
                color: material_colour(d.material),
                ..Marker::default()
            }
        })
        .collect();
    MarkerArray { markers }
}

/// The surface model: one `LINE_LIST` of each polygon's perimeter
/// (namespace `polygons`, id the segment id; initial segments grey, the
/// rest blue) and one `POINTS` marker of the point segments (namespace
/// `points`).
pub fn surface_model(stamp_ns: u64, model: &surface::ModelJson) -> MarkerArray {
    use surface::SegmentJson;
    let point = |p: &[Real; 3]| super::msg::Point {
        x: p[0],
        y: p[1],
        z: p[2],
    };
    let base = |ns: &str, id: u32, kind: i32, color: ColorRgba| Marker {
        header: Header::new(stamp_ns, ROOT_FRAME),
        ns: ns.to_owned(),
        id: i32::try_from(id).unwrap_or(i32::MAX),
        kind,
        scale: Vector3 {
            x: 0.004,
            y: 0.004,
            z: 0.004,
        },
        color,
        ..Marker::default()
    };
    let mut markers = Vec::new();
    let mut points = base(
        "points",
        0,
        Marker::POINTS,
        ColorRgba {
            r: 1.0,
            g: 0.2,
            b: 0.2,
            a: 1.0,
        },
    );
    for segment in &model.segments {
        match segment {
            SegmentJson::Polygon {
                id,
                initial,
                vertices,
                ..
            } => {
                let grey = if *initial { 0.6 } else { 0.1 };
                let mut m = base(
                    "polygons",
                    *id,
                    Marker::LINE_LIST,
                    ColorRgba {
                        r: grey,
                        g: if *initial { 0.6 } else { 0.4 },
                        b: if *initial { 0.6 } else { 0.9 },
                        a: 1.0,
                    },
                );
                for (i, v) in vertices.iter().enumerate() {
                    m.points.push(point(v));
                    m.points.push(point(&vertices[(i + 1) % vertices.len()]));
                }
                markers.push(m);
            }
            SegmentJson::Point { centroid, .. } => points.points.push(point(centroid)),
        }
    }
    if !points.points.is_empty() {
        markers.push(points);
    }
    MarkerArray { markers }
}
