//! Link collision shapes and bounding ellipsoids: enclosure of the link geometry,
//! the algebraic distance of Paul eq. 3.5, URDF geometry, built-in sensor layouts.

// Helpers and statics outside #[test] functions unwrap too: a failure is a test failure.
#![allow(clippy::unwrap_used)]

use crate::common;
use common::scene_meshes;

use geom::{Ellipsoid, Isometry3, Point3, Real, Vector3};
use robot::{CollisionShape, Joint, JointKind, Link, PosedShape, Robot};
use std::f64::consts::FRAC_PI_2;
use std::path::Path;

fn collision_points(link: &Link) -> Vec<Point3> {
    let mut pts = Vec::new();
    for s in &link.collision {
        match s {
            CollisionShape::Mesh(m) => pts.extend(m.vertices.iter().copied()),
            CollisionShape::Capsule(c) => pts.extend([c.segment.a, c.segment.b]),
        }
    }
    pts
}

#[test]
fn vm6083_capsules_and_ellipsoids_enclose_every_vertex() {
    let robot = robot::builtin("denso-vm6083").unwrap();
    let meshes = robot::builtin::denso_vm6083_link_meshes().unwrap();
    assert_eq!(meshes.len(), robot.links.len());
    let triangles: Vec<usize> = meshes.iter().map(|m| m.triangles.len()).collect();
    // SOURCES §3.1 triangle counts; link 6 adds the 12 triangles of the scanner box.
    assert_eq!(triangles, [188, 376, 392, 232, 1280, 344, 164 + 12]);
    for (i, (link, mesh)) in robot.links.iter().zip(&meshes).enumerate() {
        let [CollisionShape::Capsule(capsule)] = link.collision.as_slice() else {
            panic!("link {i}: expected one capsule, got {:?}", link.collision);
        };
        let e = link.ellipsoid.unwrap();
        let mut worst_capsule = Real::MIN;
        let mut worst_ellipsoid: Real = 0.0;
        for v in &mesh.vertices {
            worst_capsule = worst_capsule.max(capsule.distance_to_point(v));
            worst_ellipsoid = worst_ellipsoid.max(e.algebraic_distance(v));
        }
        assert!(
            worst_capsule <= 0.0,
            "link {i}: a vertex is {worst_capsule} m outside its capsule"
        );
        assert!(
            worst_ellipsoid <= 1.0,
            "link {i}: a vertex has algebraic distance {worst_ellipsoid}"
        );
        // Both are tight: some vertex touches each surface.
        assert!(
            worst_capsule > -1e-3,
            "link {i}: capsule loose by {worst_capsule}"
        );
        assert!(
            worst_ellipsoid > 0.99,
            "link {i}: ellipsoid loose ({worst_ellipsoid})"
        );
        // And not absurdly large.
        let bb = mesh.bounding_box();
        let box_volume = (bb.max - bb.min).iter().product::<Real>();
        assert!(e.volume() < 3.0 * box_volume.max(1e-9), "link {i}");
    }
    // The scanner body is inside link 6's shapes.
    let flange = &robot.links[6];
    let top = Point3::new(0.025, -0.025, 0.07);
    assert!(flange.ellipsoid.unwrap().algebraic_distance(&top) <= 1.0);
    // Link names and the tool.
    let names: Vec<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "base_link",
            "link1",
            "link2",
            "link3",
            "link4",
            "link5",
            "link6"
        ]
    );
    assert_eq!(robot.tool, (robot::LinkId(6), Isometry3::identity()));
}

#[test]
fn posed_shapes_follow_the_links() {
    let robot = robot::builtin("denso-vm6083").unwrap();
    let q = [0.4, -0.3, 1.0, 0.2, -0.6, 0.9];
    let frames = robot.forward_kinematics(&q).unwrap();
    let shapes = robot.posed_collision_shapes(&frames);
    assert_eq!(shapes.len(), 7);
    for shape in &shapes {
        let PosedShape::Capsule { link, capsule } = shape else {
            panic!("capsules only")
        };
        let CollisionShape::Capsule(local) = &robot.links[link.0].collision[0] else {
            unreachable!()
        };
        assert!((capsule.segment.a - frames[link.0] * local.segment.a).norm() < 1e-12);
        assert_eq!(shape.link(), *link);
    }
    let ellipsoids = robot.posed_ellipsoids(&frames);
    assert_eq!(
        ellipsoids.iter().map(|(i, _)| i.0).collect::<Vec<_>>(),
        [0, 1, 2, 3, 4, 5, 6]
    );
    // A posed ellipsoid gives the same algebraic distance as the local one.
    let p_link = Point3::new(0.05, 0.02, -0.1);
    let (i, posed) = ellipsoids[4];
    let local = robot.links[i.0].ellipsoid.unwrap();
    assert!(
        (posed.algebraic_distance(&(frames[i.0] * p_link)) - local.algebraic_distance(&p_link))
            .abs()
            < 1e-9
    );
}

#[test]
fn min_algebraic_distance_by_hand() {
    // One revolute joint about z; link 1 carries an ellipsoid with semi-axes
    // (0.5, 0.1, 0.2) centred at (0.5, 0, 0). The base carries a huge ellipsoid,
    // which eq. 3.5 ignores (links 1.. only).
    let mut base = Link::new("base");
    base.ellipsoid = Some(Ellipsoid::new(Isometry3::identity(), Vector3::repeat(10.0)));
    let mut arm = Link::new("arm");
    arm.ellipsoid = Some(Ellipsoid::new(
        Isometry3::translation(0.5, 0.0, 0.0),
        Vector3::new(0.5, 0.1, 0.2),
    ));
    let robot = Robot {
        name: "one".to_owned(),
        links: vec![base, arm],
        joints: vec![Joint::revolute(
            "yaw",
            Isometry3::identity(),
            Vector3::z_axis(),
            None,
        )],
        tool: (robot::LinkId(1), Isometry3::identity()),
        scanner: None,
        range_finders: Vec::new(),
        warnings: Vec::new(),
    };
    robot.validate().unwrap();
    assert_eq!(robot.joints[0].kind, JointKind::Revolute);
    // At q = 90° the ellipsoid lies along +y, centred at (0, 0.5, 0).
    let q = [FRAC_PI_2];
    // (0, 1.5, 0): 1.0 along the long axis → (1.0 / 0.5)² = 4.
    let d = robot
        .min_algebraic_distance(&q, &[Point3::new(0.0, 1.5, 0.0)])
        .unwrap();
    assert!((d - 4.0).abs() < 1e-12, "{d}");
    // (0.3, 0.5, 0.4): 0.3 across (short axis 0.1) and 0.4 up (axis 0.2) → 9 + 4 = 13.
    let far = Point3::new(0.3, 0.5, 0.4);
    let d = robot.min_algebraic_distance(&q, &[far]).unwrap();
    assert!((d - 13.0).abs() < 1e-12, "{d}");
    // The minimum over points: add (0.05, 0.75, 0) → 0.25 + 0.25 = 0.5.
    let d = robot
        .min_algebraic_distance(&q, &[far, Point3::new(0.05, 0.75, 0.0)])
        .unwrap();
    assert!((d - 0.5).abs() < 1e-12, "{d}");
    assert_eq!(
        robot.min_algebraic_distance(&q, &[]).unwrap(),
        Real::INFINITY
    );
}

#[test]
fn builtin_sensor_layouts() {
    let point3 = robot::builtin("point3").unwrap();
    assert_eq!(point3.dof(), 3);
    assert_eq!(point3.range_finders.len(), 26);
    for (i, a) in point3.range_finders.iter().enumerate() {
        assert_eq!(
            (a.link, a.origin, a.max_range_m),
            (robot::LinkId(3), Point3::origin(), 0.2)
        );
        let d = a.axis.into_inner();
        // Each is a normalised (±1/0) grid direction, all distinct.
        let grid = d / d.amax();
        assert!(
            grid.iter()
                .all(|c| (c.abs() - c.abs().round()).abs() < 1e-12 && c.abs() <= 1.0)
        );
        assert!(
            point3.range_finders[..i]
                .iter()
                .all(|b| (b.axis.into_inner() - d).norm() > 1e-6)
        );
    }
    assert!(
        point3
            .limits()
            .iter()
            .all(|l| *l == Some(robot::JointLimits::new(-10.0, 10.0)))
    );

    let arm4 = robot::builtin("arm4").unwrap();
    assert_eq!(arm4.range_finders.len(), 133);
    let count = |link: robot::LinkId| arm4.range_finders.iter().filter(|r| r.link == link).count();
    let link = |name: &str| arm4.link_index(name).unwrap();
    assert_eq!([count(link("link2")), count(link("link3"))], [40, 40]);
    let tool_link = arm4.tool.0;
    assert_eq!(tool_link, link("link4"));
    let tip = arm4.tool.1 * Point3::origin();
    let at_tip: Vec<_> = arm4
        .range_finders
        .iter()
        .filter(|r| r.link == tool_link && r.origin == tip)
        .collect();
    assert_eq!(at_tip.len(), 17);
    assert_eq!(count(tool_link) - at_tip.len(), 36);
    // Tool-axis sensor, ring of 8 at 45°, ring of 8 at 90°.
    let mut angles: Vec<i64> = at_tip
        .iter()
        .map(|r| r.axis.z.acos().to_degrees().round() as i64)
        .collect();
    angles.sort_unstable();
    assert_eq!(angles, [vec![0], vec![45; 8], vec![90; 8]].concat());
    // Link sensors point radially (perpendicular to the link axis) from the surface.
    for r in arm4.range_finders.iter().filter(|r| r.origin != tip) {
        assert!(r.axis.z.abs() < 1e-12);
        assert!((r.origin.coords.xy().norm() - 0.05).abs() < 1e-12);
        assert!(r.origin.z > 0.0 && r.origin.z < (if r.link == tool_link { 0.86 } else { 0.96 }));
        assert_eq!(r.max_range_m, 0.2);
    }
    // Every physical link has a capsule of radius 0.05 and an enclosing ellipsoid.
    for name in ["link1", "link2", "link3", "link4"] {
        let l = &arm4.links[link(name).0];
        let [CollisionShape::Capsule(c)] = l.collision.as_slice() else {
            panic!("{name}")
        };
        assert_eq!(c.radius, 0.05);
        let e = l.ellipsoid.unwrap();
        for p in [
            c.segment.a - Vector3::z() * 0.05,
            c.segment.b + Vector3::z() * 0.05,
            c.segment.point_at(0.5) + Vector3::x() * 0.05,
        ] {
            assert!(e.algebraic_distance(&p) <= 1.0, "{name}: {p}");
        }
    }
    // Sensors come out in the base frame through the link frames.
    let frames = arm4.forward_kinematics(&[0.0; 6]).unwrap();
    let (origin, axis) = at_tip[0].in_base(&frames).unwrap();
    assert!((origin - Point3::new(0.0, 0.0, 4.0)).norm() < 1e-12 && axis.z > 1.0 - 1e-12);
}

#[test]
fn ur5_collision_meshes_and_ellipsoids() {
    let path = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/robots/ur5/ur5_robot.urdf"
    ));
    let robot = Robot::from_urdf_file_with(path, Some("tool0"), &scene_meshes).unwrap();
    assert!(robot.warnings.is_empty(), "{:?}", robot.warnings);
    assert_eq!(robot.name, "ur5");
    for (i, link) in robot.links.iter().enumerate() {
        assert!(
            !link.collision.is_empty(),
            "link {} has no shape",
            link.name
        );
        let is_mesh = matches!(link.collision[0], CollisionShape::Mesh(_));
        assert_eq!(is_mesh, (1..=7).contains(&i), "link {}", link.name);
        let e = link.ellipsoid.unwrap();
        for p in collision_points(link) {
            assert!(e.algebraic_distance(&p) <= 1.0, "link {}", link.name);
        }
    }
    // SOURCES §3.3 triangle counts of the collision STLs.
    let tris: Vec<usize> = robot.links[1..=7]
        .iter()
        .map(|l| match &l.collision[0] {
            CollisionShape::Mesh(m) => m.triangles.len(),
            CollisionShape::Capsule(_) => 0,
        })
        .collect();
    assert_eq!(tris, [578, 674, 1176, 1050, 702, 702, 446]);
}

const TRIANGLE_STL: &str = "solid t
facet normal 0 0 1
outer loop
vertex 0 0 0
vertex 1 0 0
vertex 0 1 0
endloop
endfacet
facet normal 0 -1 0
outer loop
vertex 0 0 0
vertex 0 0 1
vertex 1 0 0
endloop
endfacet
endsolid t
";

const TETRA_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

#[test]
fn urdf_geometry_primitives_and_meshes() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("meshes")).unwrap();
    std::fs::write(dir.path().join("meshes/tri.stl"), TRIANGLE_STL).unwrap();
    std::fs::write(dir.path().join("meshes/tetra.OBJ"), TETRA_OBJ).unwrap();
    let xml = r#"<robot name="shapes">
  <link name="box_link">
    <collision><origin xyz="0 0 1"/><geometry><box size="0.2 0.4 0.6"/></geometry></collision>
  </link>
  <link name="cyl_link">
    <collision><origin rpy="1.5707963267948966 0 0"/><geometry><cylinder radius="0.1" length="2"/></geometry></collision>
  </link>
  <link name="sphere_link">
    <collision><origin xyz="0.5 0 0"/><geometry><sphere radius="0.3"/></geometry></collision>
  </link>
  <link name="stl_link">
    <collision><origin xyz="1 0 0"/><geometry><mesh filename="package://anything/meshes/tri.stl" scale="2 2 2"/></geometry></collision>
  </link>
  <link name="obj_link">
    <collision><geometry><mesh filename="meshes/tetra.OBJ"/></geometry></collision>
  </link>
  <link name="dae_link">
    <collision><geometry><mesh filename="meshes/fancy.dae"/></geometry></collision>
  </link>
  <link name="bare_link"/>
  <joint name="j1" type="revolute"><parent link="box_link"/><child link="cyl_link"/><axis xyz="0 0 2"/><limit lower="-1" upper="1"/></joint>
  <joint name="j2" type="continuous"><parent link="cyl_link"/><child link="sphere_link"/><axis xyz="0 1 0"/></joint>
  <joint name="j3" type="prismatic"><parent link="sphere_link"/><child link="stl_link"/><axis xyz="1 0 0"/><limit lower="0" upper="0.5"/></joint>
  <joint name="f1" type="fixed"><parent link="stl_link"/><child link="obj_link"/></joint>
  <joint name="f2" type="fixed"><parent link="obj_link"/><child link="dae_link"/><origin xyz="0 0 0.7"/></joint>
  <joint name="f3" type="fixed"><parent link="dae_link"/><child link="bare_link"/></joint>
</robot>"#;
    let path = dir.path().join("shapes.urdf");
    std::fs::write(&path, xml).unwrap();
    // No tip: the chain is unbranched down to its single leaf.
    let robot = Robot::from_urdf_file_with(&path, None, &scene_meshes).unwrap();
    assert_eq!(robot.links.len(), 7);
    assert_eq!(robot.dof(), 3);
    assert_eq!(
        robot.joints[0].axis.into_inner(),
        Vector3::z(),
        "axis normalised"
    );
    assert_eq!(
        robot.limits(),
        [
            Some(robot::JointLimits::new(-1.0, 1.0)),
            None,
            Some(robot::JointLimits::new(0.0, 0.5))
        ]
    );
    let mesh = |i: usize| match &robot.links[i].collision[..] {
        [CollisionShape::Mesh(m)] => m.clone(),
        other => panic!("link {i}: {other:?}"),
    };
    // Box: 8 corners shifted up by the origin.
    let b = mesh(0);
    assert_eq!((b.vertices.len(), b.triangles.len()), (8, 12));
    let bb = b.bounding_box();
    assert!(
        (bb.min - Point3::new(-0.1, -0.2, 0.7)).norm() < 1e-12
            && (bb.max - Point3::new(0.1, 0.2, 1.3)).norm() < 1e-12
    );
    // Cylinder: 24 segments, turned by the rpy so its axis runs along −y..y.
    let c = mesh(1);
    // 24 side quads and two 24-gon caps of 22 triangles each.
    assert_eq!(c.triangles.len(), 2 * 24 + 2 * 22);
    let cb = c.bounding_box();
    assert!((cb.max.y - 1.0).abs() < 1e-12 && (cb.max.z - 0.1).abs() < 1e-12);
    // Sphere: a zero-length capsule at the origin's position.
    let [CollisionShape::Capsule(s)] = &robot.links[2].collision[..] else {
        panic!()
    };
    assert_eq!(
        (s.segment.a, s.segment.b, s.radius),
        (Point3::new(0.5, 0.0, 0.0), Point3::new(0.5, 0.0, 0.0), 0.3)
    );
    // STL: scaled by 2, then moved by the origin; package:// resolved next to the URDF.
    let t = mesh(3);
    assert_eq!(t.triangles.len(), 2);
    assert!(
        t.vertices.contains(&Point3::new(3.0, 0.0, 0.0))
            && t.vertices.contains(&Point3::new(1.0, 2.0, 0.0))
    );
    // OBJ (extension matched case-insensitively), relative path.
    assert_eq!(mesh(4).triangles.len(), 4);
    // .dae: a warning naming file, line and mesh, and the automatic capsule from the
    // link origin to the next joint's origin.
    assert_eq!(robot.warnings.len(), 1, "{:?}", robot.warnings);
    assert!(
        robot.warnings[0].contains("shapes.urdf:18") && robot.warnings[0].contains("fancy.dae"),
        "{}",
        robot.warnings[0]
    );
    let [CollisionShape::Capsule(auto)] = &robot.links[5].collision[..] else {
        panic!()
    };
    assert_eq!(
        (auto.segment.a, auto.segment.b, auto.radius),
        (Point3::origin(), Point3::origin(), 0.04)
    );
    let [CollisionShape::Capsule(bare)] = &robot.links[6].collision[..] else {
        panic!()
    };
    assert_eq!(bare.radius, 0.04);
    // obj_link's auto capsule would run to (0, 0, 0.7) — it has a mesh, so none.
    assert_eq!(robot.links[4].collision.len(), 1);
    // Every link has an ellipsoid enclosing its collision geometry.
    for link in &robot.links {
        let e = link.ellipsoid.unwrap_or_else(|| panic!("{}", link.name));
        for p in collision_points(link) {
            assert!(e.algebraic_distance(&p) <= 1.0, "{}", link.name);
        }
    }
    // Tool = tip link frame.
    assert_eq!(robot.tool, (robot::LinkId(6), Isometry3::identity()));
    // The prismatic joint moves along x.
    let a = robot.tool_pose(&[0.0, 0.0, 0.0]).unwrap();
    let b = robot.tool_pose(&[0.0, 0.0, 0.25]).unwrap();
    assert!(
        (b.translation.vector - a.translation.vector - Vector3::new(0.25, 0.0, 0.0)).norm() < 1e-12
    );
}

/// A link's `<inertial>` is kept as the URDF states it (mass, inertia
/// frame, the six inertia entries, 0 where left out); a link without one,
/// or with a mass of 0, has none, and a negative mass is refused naming
/// the line.
#[test]
fn urdf_inertials_are_kept() {
    let urdf = |inertial: &str| {
        format!(
            r#"<robot name="r">
  <link name="base"/>
  <link name="arm">{inertial}</link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1"/></joint>
</robot>"#
        )
    };
    let load = |text: &str| Robot::from_urdf_str(text, Path::new("."), "t.urdf", None);
    let robot = load(&urdf(
        r#"<inertial><mass value="2.5"/><origin xyz="0.1 0 0.2" rpy="0 0 1.5707963267948966"/>
        <inertia ixx="0.3" iyy="0.2" izz="0.1" ixz="0.01"/></inertial>"#,
    ))
    .unwrap();
    assert!(robot.links[0].inertial.is_none());
    let i = robot.links[1].inertial.unwrap();
    assert_eq!(i.mass_kg, 2.5);
    assert_eq!(i.inertia, [0.3, 0.2, 0.1, 0.0, 0.01, 0.0]);
    let t = i.link_from_com.translation.vector;
    assert_eq!((t.x, t.y, t.z), (0.1, 0.0, 0.2));
    assert!((i.link_from_com.rotation.angle() - FRAC_PI_2).abs() < 1e-12);
    let zero = load(&urdf(r#"<inertial><mass value="0"/></inertial>"#)).unwrap();
    assert!(zero.links[1].inertial.is_none());
    let e = load(&urdf(r#"<inertial><mass value="-1"/></inertial>"#))
        .unwrap_err()
        .to_string();
    assert!(e.contains("t.urdf:3") && e.contains("mass"), "{e}");
}
