//! The built-in robots of SPEC §3.2.
//!
//! * `denso-vm6083` — the 6-DOF industrial arm of the AXBAM work: standard DH table
//!   of Paul Table C.1 (App. C.1.1), link meshes in DH frames (embedded in the
//!   binary), one enclosing capsule and one bounding ellipsoid per link
//!   (A§3.2.1.4), and the Hokuyo URG-04LX scanner on the flange (A eq. 3.10).
//! * `point3` — Pudney's mobile point robot (P§4.3, Fig. 39a): three orthogonal
//!   prismatic joints and 26 range finders at the control point.
//! * `arm4` — Pudney's four-link manipulator arm (P§4.3, Fig. 39b, Fig. 40): six
//!   revolute joints, 17 range finders around the control point and 116 on links
//!   2–4.
//!
//! Built-ins are constructed once per process and cloned (meshes are shared).

use crate::bounds::{enclosing_capsule, enclosing_ellipsoid, enclosing_ellipsoid_of, unit_or_z};
use crate::dh::DhRow;
use crate::error::RobotError;
use crate::mesh::parse_embedded_obj;
use crate::model::{
    CollisionShape, Joint, JointLimits, Link, LinkId, RangeFinderMount, Robot, ScannerMount,
};
use geom::primitives::cuboid;
use geom::{Capsule, Ellipsoid, Isometry3, Point3, Real, TriMesh, Vector3};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
use std::sync::OnceLock;

/// Names accepted by [`builtin`].
pub const NAMES: [&str; 3] = ["denso-vm6083", "point3", "arm4"];

/// The names accepted by [`builtin`].
pub fn builtin_names() -> &'static [&'static str] {
    &NAMES
}

/// A built-in robot by name: `"denso-vm6083"`, `"point3"` or `"arm4"`.
///
/// ```
/// let arm = robot::builtin("arm4")?;
/// assert_eq!((arm.dof(), arm.range_finders.len()), (6, 133));
/// assert!(robot::builtin("puma").unwrap_err().to_string().contains("denso-vm6083"));
/// # Ok::<(), robot::RobotError>(())
/// ```
pub fn builtin(name: &str) -> Result<Robot, RobotError> {
    static VM6083: OnceLock<Result<Robot, RobotError>> = OnceLock::new();
    static POINT3: OnceLock<Result<Robot, RobotError>> = OnceLock::new();
    static ARM4: OnceLock<Result<Robot, RobotError>> = OnceLock::new();
    match name {
        "denso-vm6083" => VM6083.get_or_init(denso_vm6083).clone(),
        "point3" => POINT3.get_or_init(point3).clone(),
        "arm4" => ARM4.get_or_init(arm4).clone(),
        _ => Err(RobotError::UnknownBuiltin {
            name: name.to_owned(),
            valid: NAMES.join(", "),
        }),
    }
}

/// The Denso VM-6083 DH table (Paul Table C.1): a, d, α, state at zero, limits.
pub fn denso_vm6083_dh() -> [DhRow; 6] {
    let a = [0.18, 0.385, -0.1, 0.0, 0.0, 0.0];
    let d = [0.475, 0.0, 0.0, 0.445, 0.0, 0.084];
    let alpha = [-FRAC_PI_2, 0.0, FRAC_PI_2, -FRAC_PI_2, FRAC_PI_2, 0.0];
    let offset = [0.0, -FRAC_PI_2, FRAC_PI_2, 0.0, 0.0, 0.0];
    let limits_deg = [
        (-170.0, 170.0),
        (-90.0, 135.0),
        (-80.0, 165.0),
        (-185.0, 185.0),
        (-120.0, 120.0),
        (-360.0, 360.0),
    ];
    std::array::from_fn(|i| {
        DhRow::new(a[i], d[i], alpha[i], offset[i])
            .with_limits(JointLimits::from_degrees(limits_deg[i].0, limits_deg[i].1))
    })
}

/// The VM-6083 link meshes (OBJ, metres, link-local DH frames), embedded so the
/// built-in robot works from any working directory.
const VM6083_OBJ: [&str; 7] = [
    include_str!("../../../data/robots/denso_vm6083/DensoVM6083Link0.obj"),
    include_str!("../../../data/robots/denso_vm6083/DensoVM6083Link1.obj"),
    include_str!("../../../data/robots/denso_vm6083/DensoVM6083Link2.obj"),
    include_str!("../../../data/robots/denso_vm6083/DensoVM6083Link3.obj"),
    include_str!("../../../data/robots/denso_vm6083/DensoVM6083Link4.obj"),
    include_str!("../../../data/robots/denso_vm6083/DensoVM6083Link5.obj"),
    include_str!("../../../data/robots/denso_vm6083/DensoVM6083Link6.obj"),
];

/// Scanner body on the VM-6083 flange (flange frame, metres): x, y ∈ ±0.025,
/// z ∈ [0, 0.07].
pub const VM6083_SCANNER_BODY: ([Real; 3], [Real; 3]) =
    ([-0.025, -0.025, 0.0], [0.025, 0.025, 0.07]);

/// Scanner origin on the VM-6083 flange (flange frame, metres).
pub const VM6083_FLANGE_FROM_SCANNER_M: [Real; 3] = [0.0, 0.0, 0.05];

/// The seven VM-6083 link meshes in their link frames (base first), the last one
/// including the scanner body on the flange. The meshes were made with `d6 = 0.09`
/// (SOURCES §3.1), so link 6 sits 6 mm off the Table C.1 flange.
pub fn denso_vm6083_link_meshes() -> Result<Vec<TriMesh>, RobotError> {
    let mut meshes = Vec::with_capacity(VM6083_OBJ.len());
    for (i, text) in VM6083_OBJ.iter().enumerate() {
        let mut mesh = parse_embedded_obj(text, &format!("DensoVM6083Link{i}.obj (embedded)"))?;
        if i == 6 {
            let (lo, hi) = VM6083_SCANNER_BODY;
            mesh.append(&cuboid(Point3::from(lo), Point3::from(hi)));
        }
        meshes.push(mesh);
    }
    Ok(meshes)
}

fn denso_vm6083() -> Result<Robot, RobotError> {
    let mut robot = Robot::from_dh("denso-vm6083", &denso_vm6083_dh())?;
    let meshes = denso_vm6083_link_meshes()?;
    for (i, (link, mesh)) in robot.links.iter_mut().zip(&meshes).enumerate() {
        let no_fit = |what: &str| RobotError::MeshData {
            what: format!("DensoVM6083Link{i}.obj (embedded)"),
            message: format!("cannot fit a bounding {what}"),
        };
        let capsule = enclosing_capsule(&mesh.vertices).ok_or_else(|| no_fit("capsule"))?;
        link.collision = vec![CollisionShape::Capsule(capsule)];
        link.ellipsoid =
            Some(enclosing_ellipsoid(&mesh.vertices).ok_or_else(|| no_fit("ellipsoid"))?);
    }
    let [x, y, z] = VM6083_FLANGE_FROM_SCANNER_M;
    robot.scanner = Some(ScannerMount {
        link: LinkId(6),
        link_from_scanner: Isometry3::translation(x, y, z),
    });
    robot.validate()?;
    Ok(robot)
}

/// Sensing range of Pudney's range finders (P§4.3).
pub const PUDNEY_SENSOR_RANGE_M: Real = 0.2;

fn point3() -> Result<Robot, RobotError> {
    let limits = Some(JointLimits::symmetric(10.0));
    let joints = vec![
        Joint::prismatic("x", Isometry3::identity(), Vector3::x_axis(), limits),
        Joint::prismatic("y", Isometry3::identity(), Vector3::y_axis(), limits),
        Joint::prismatic("z", Isometry3::identity(), Vector3::z_axis(), limits),
    ];
    let radius = 0.02;
    let mut body = Link::new("body");
    body.collision = vec![CollisionShape::Capsule(Capsule::new(
        Point3::origin(),
        Point3::origin(),
        radius,
    ))];
    body.ellipsoid = Some(Ellipsoid::new(
        Isometry3::identity(),
        Vector3::repeat(radius),
    ));
    let mut range_finders = Vec::with_capacity(26);
    for i in -1..=1 {
        for j in -1..=1 {
            for k in -1..=1 {
                if (i, j, k) == (0, 0, 0) {
                    continue;
                }
                range_finders.push(RangeFinderMount {
                    link: LinkId(3),
                    origin: Point3::origin(),
                    axis: unit_or_z(Vector3::new(Real::from(i), Real::from(j), Real::from(k))),
                    max_range_m: PUDNEY_SENSOR_RANGE_M,
                });
            }
        }
    }
    let robot = Robot {
        name: "point3".to_owned(),
        links: vec![
            Link::new("base"),
            Link::new("x_carriage"),
            Link::new("y_carriage"),
            body,
        ],
        joints,
        tool: (LinkId(3), Isometry3::identity()),
        scanner: None,
        range_finders,
        warnings: Vec::new(),
    };
    robot.validate()?;
    Ok(robot)
}

/// Capsule radius of the arm4 links (metres).
pub const ARM4_LINK_RADIUS_M: Real = 0.05;

fn arm4() -> Result<Robot, RobotError> {
    let limits = Some(JointLimits::symmetric(PI));
    let up = Isometry3::translation(0.0, 0.0, 1.0);
    let id = Isometry3::identity();
    let (z, y) = (Vector3::z_axis(), Vector3::y_axis());
    let joints = vec![
        Joint::revolute("joint1", up, z, limits), // yaw at the top of the post
        Joint::revolute("joint2", id, y, limits), // pitch
        Joint::revolute("joint3", up, z, limits), // roll about link 2
        Joint::revolute("joint4", id, y, limits), // pitch
        Joint::revolute("joint5", up, z, limits), // roll about link 3
        Joint::revolute("joint6", id, y, limits), // pitch
    ];
    // Each physical link runs along its local z from 0 to 1. The last one
    // ends at the control point, its tip (SPEC §3.2): the 17 range finders
    // there sit on the end of the body, so its capsule's axis stops one
    // radius short of the tip (with the axis to 1 the body's rounded end
    // stood 5 cm past the sensors, round the control point).
    let rod = |length: Real| {
        let c = Capsule::new(
            Point3::origin(),
            Point3::new(0.0, 0.0, length),
            ARM4_LINK_RADIUS_M,
        );
        let mut l = Link::new("");
        l.ellipsoid = enclosing_ellipsoid_of(&[c], &[]);
        l.collision = vec![CollisionShape::Capsule(c)];
        l
    };
    let named = |mut l: Link, name: &str| {
        name.clone_into(&mut l.name);
        l
    };
    let links = vec![
        named(rod(1.0), "link1"), // the immobile post (base)
        Link::new("shoulder"),
        named(rod(1.0), "link2"),
        Link::new("elbow"),
        named(rod(1.0), "link3"),
        Link::new("wrist"),
        named(rod(1.0 - ARM4_LINK_RADIUS_M), "link4"),
    ];
    let tip = Point3::new(0.0, 0.0, 1.0);
    let mut range_finders = Vec::with_capacity(133);
    let mut add = |link: usize, origin: Point3, dir: Vector3| {
        range_finders.push(RangeFinderMount {
            link: LinkId(link),
            origin,
            axis: unit_or_z(dir),
            max_range_m: PUDNEY_SENSOR_RANGE_M,
        });
    };
    // Control point: the tool axis, a ring of 8 at 45°, a ring of 8 at 90° (Fig. 40b).
    add(6, tip, Vector3::z());
    for polar in [FRAC_PI_4, FRAC_PI_2] {
        for k in 0..8 {
            let azimuth = FRAC_PI_4 * Real::from(k);
            add(
                6,
                tip,
                Vector3::new(
                    polar.sin() * azimuth.cos(),
                    polar.sin() * azimuth.sin(),
                    polar.cos(),
                ),
            );
        }
    }
    // Links 2, 3, 4: rings of 4 radial sensors on the link surface every 0.1 m
    // (Fig. 40c); link 4 stops short of the control-point zone.
    for (link, rings) in [(2, 10), (4, 10), (6, 9)] {
        for ring in 0..rings {
            let along = 0.05 + 0.1 * Real::from(ring);
            for k in 0..4 {
                let azimuth = FRAC_PI_2 * Real::from(k);
                let radial = Vector3::new(azimuth.cos(), azimuth.sin(), 0.0);
                add(
                    link,
                    Point3::new(0.0, 0.0, along) + radial * ARM4_LINK_RADIUS_M,
                    radial,
                );
            }
        }
    }
    let robot = Robot {
        name: "arm4".to_owned(),
        links,
        joints,
        tool: (LinkId(6), Isometry3::translation(0.0, 0.0, 1.0)),
        scanner: None,
        range_finders,
        warnings: Vec::new(),
    };
    robot.validate()?;
    Ok(robot)
}
