//! A scenario as a MuJoCo model (MJCF, issue 47): the arm's kinematic chain
//! with masses, armature and torque limits, its scanner, tool and range
//! finders as sites, and the scene's solids as geoms, so that a physics
//! simulator can stand in for the robot (`surveyor scenario mjcf`).
//!
//! The model follows [`robot::Robot`] exactly: link `i + 1`'s body sits at
//! `joint.parent_from_child(0)` in its parent's (so MuJoCo's `qpos = 0` is
//! our `q = 0`), and its joint turns about `post⁻¹ · axis` through
//! `post⁻¹ · 0` (see [`robot::Joint`]: `origin · motion(q + offset) · post`
//! is `child(0) · post⁻¹ · motion(q) · post`). Capsules stay capsules (a
//! sphere when both ends meet), link meshes are inline mesh assets.
//!
//! Masses: a link's stated inertial (a URDF's `<inertial>`, [`robot::Inertial`])
//! where it has one, else its shapes at [`MjcfConfig::density_kg_m3`], and a
//! link without either [`MjcfConfig::min_mass_kg`]. Each actuated joint has
//! [`MjcfConfig::armature`] and a torque (force) limit of
//! [`MjcfConfig::torque_margin`] times the most gravity could ask of it with
//! the arm stretched out (a bound by the triangle inequality, see
//! [`torque_limits`]), stated in the file as `actuatorfrcrange` and as its
//! motor's `ctrlrange`.
//!
//! The scene's solids, in the world frame: a box is a `box` geom, an
//! I-beam three (its flanges and web), a cylinder the same faceted prism the
//! ground truth has (a convex mesh: MuJoCo's rays and contacts see exactly
//! our triangles), a prism one convex mesh or, when its profile is not
//! convex, one triangular prism per triangle of its profile, and a mesh
//! file one mesh (rays see its triangles; MuJoCo's contacts see its convex
//! hull, which the model's notes say). A point-cloud world has no solids
//! and is refused.
//!
//! Names tell contacts apart: arm geoms are `arm/LINK/K` (collision group 1:
//! `contype 1`, `conaffinity 2`; the links mounted on the scene,
//! [`robot::Robot::mounted_links`], collide with nothing), scene geoms are
//! `scene/OBJECT` or `scene/OBJECT/PART` (group 0: `contype 2`,
//! `conaffinity 1`), so only arm–scene pairs make contacts. Sites are
//! `scanner` (the scanner frame: z the centre ray, rays
//! `(0, −sin θ, cos θ)`), `tool` and `finder_K` (its z axis the sensing
//! axis). The keyframe `start` holds the start joints.
//!
//! [`MjcfModel::sidecar`] holds what a simulator serving the model as a
//! ROS 2 robot needs beside it (JSON): the joints' ROS names, limits and
//! start, the `[ros2]` topics and tolerance, the scanner's bearings, ranges,
//! timing, noise and reflection model, each range finder, and each scene
//! geom's material.

use crate::LoadedScenario;
use crate::ScenarioError;
use geom::primitives::triangulate;
use geom::{Isometry3, Matrix3, Point2, Point3, Real, TriMesh, UnitQuaternion, Vector3};
use robot::{CollisionShape, JointKind, Robot};
use scene::{ObjectSpec, ShapeSpec};
use serde::Serialize;
use std::fmt::Write as _;

/// Standard gravity, m/s² (MuJoCo's default, written in the file).
pub const GRAVITY_M_S2: Real = 9.81;

/// How the model's physical figures are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MjcfConfig {
    /// Density of the links' collision shapes, kg/m³. The shapes enclose
    /// the links (the VM-6083's capsules hold its castings, motors and the
    /// air between), so the default is an envelope's, not aluminium's.
    pub density_kg_m3: Real,
    /// Mass of a moving link without shapes, kg (and the inertia of a
    /// sphere of 1 cm about it).
    pub min_mass_kg: Real,
    /// Rotor inertia reflected through the gears, kg·m² (kg for prismatic
    /// joints), on every actuated joint.
    pub armature: Real,
    /// Torque limits are this many times the gravity bound.
    pub torque_margin: Real,
    /// The least torque (force) limit, N·m (N).
    pub min_torque: Real,
    /// Physics time step, seconds.
    pub timestep_s: Real,
}

impl Default for MjcfConfig {
    fn default() -> Self {
        Self {
            density_kg_m3: 500.0,
            min_mass_kg: 0.01,
            armature: 0.05,
            torque_margin: 3.0,
            min_torque: 1.0,
            timestep_s: 0.002,
        }
    }
}

/// The robot a model holds and where it stands: what the simulator's rig
/// of the scenario has (`--robot` may put another robot there).
#[derive(Clone, Debug)]
pub struct MjcfArm<'a> {
    /// The robot, its scanner mounted and its range finders added.
    pub robot: &'a Robot,
    /// Where its base stands in the world.
    pub world_from_base: Isometry3,
    /// Its start joints (the model's `start` keyframe).
    pub start_joints: &'a [Real],
    /// The range finders' noise σ, metres.
    pub range_noise_sigma_m: Real,
}

/// A written model: the MJCF text, its sidecar and what the reader should
/// know about it.
#[derive(Clone, Debug)]
pub struct MjcfModel {
    /// The MJCF document.
    pub xml: String,
    /// What serving it needs beside the model (write it as JSON).
    pub sidecar: Sidecar,
    /// Where the model differs from our simulator's (e.g. a mesh's contacts
    /// on its convex hull).
    pub notes: Vec<String>,
}

/// One actuated joint, in the robot's joint order.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SidecarJoint {
    /// The model's (and MJCF's) name.
    pub name: String,
    /// Its ROS name (the `[ros2]` table's `joint_names`, else the model's).
    pub ros_name: String,
    /// `revolute` or `prismatic`.
    pub kind: JointKind,
    /// Start value.
    pub start: Real,
    /// Lowest value, when limited.
    pub min: Option<Real>,
    /// Highest value, when limited.
    pub max: Option<Real>,
    /// Torque (force) limit, N·m (N).
    pub torque_limit: Real,
}

/// The scanner of the model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SidecarScanner {
    /// The site of its frame.
    pub site: String,
    /// Its beams' bearings, radians (`(0, −sin θ, cos θ)` in the site frame).
    pub bearings_rad: Vec<Real>,
    /// Seconds between beams (`LaserScan.time_increment`, float32).
    pub time_increment_s: Real,
    /// The scanner model: ranges, noise, reflection, scan time.
    pub config: sensor::ScannerConfig,
}

/// A range finder of the model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SidecarFinder {
    /// Its site (z axis the sensing axis).
    pub site: String,
    /// Its range, metres.
    pub max_range_m: Real,
}

/// What a simulator serving the model as a ROS 2 robot needs beside it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Sidecar {
    /// The scenario's name.
    pub scenario: String,
    /// The robot's name.
    pub robot: String,
    /// The actuated joints, in order (MJCF joints and motors of these names).
    pub joints: Vec<SidecarJoint>,
    /// Topics, ROS joint names and the tolerance a driver waits for.
    pub ros2: crate::ros2::Ros2Spec,
    /// The scanner, when the robot carries one.
    pub scanner: Option<SidecarScanner>,
    /// The range finders.
    pub range_finders: Vec<SidecarFinder>,
    /// The range finders' noise σ, metres.
    pub range_noise_sigma_m: Real,
    /// The material table.
    pub materials: Vec<scene::Material>,
    /// Each scene geom's material, by geom name.
    pub scene_geoms: Vec<(String, String)>,
    /// The figures the model was made with.
    pub config: MjcfConfig,
    /// Mass of each link's body, kg (0 for links mounted on the scene).
    pub link_masses_kg: Vec<(String, Real)>,
}

/// A link's mass, centre of mass and inertia about it, in the link frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MassProperties {
    /// kg.
    pub mass_kg: Real,
    /// Centre of mass, link frame.
    pub com: Point3,
    /// Inertia about the centre of mass, link axes, kg·m².
    pub inertia: Matrix3,
}

impl MassProperties {
    /// A uniform capsule around `a b` of `radius` at `density` (a sphere
    /// when `a = b`): cylinder `πr²h`, two half-spheres `4/3 πr³`.
    pub fn capsule(a: &Point3, b: &Point3, radius: Real, density: Real) -> Self {
        let axis = b - a;
        let h = axis.norm();
        let r2 = radius * radius;
        let m_cyl = density * std::f64::consts::PI * r2 * h;
        let m_sph = density * 4.0 / 3.0 * std::f64::consts::PI * r2 * radius;
        let i_axis = m_cyl * r2 / 2.0 + m_sph * 2.0 / 5.0 * r2;
        let i_perp = m_cyl * (r2 / 4.0 + h * h / 12.0)
            + m_sph * (2.0 / 5.0 * r2 + h * h / 4.0 + 3.0 / 8.0 * h * radius);
        let uu = if h > 0.0 {
            let u = axis / h;
            u * u.transpose()
        } else {
            Matrix3::zeros()
        };
        Self {
            mass_kg: m_cyl + m_sph,
            com: Point3::from((a.coords + b.coords) / 2.0),
            inertia: Matrix3::identity() * i_perp + uu * (i_axis - i_perp),
        }
    }

    /// A closed, outward-wound mesh of uniform `density` (the divergence
    /// theorem over the tetrahedra from the origin); `None` when it holds
    /// no volume (open or inside out).
    pub fn mesh(mesh: &TriMesh, density: Real) -> Option<Self> {
        let (mut volume, mut first, mut second) = (0.0, Vector3::zeros(), Matrix3::zeros());
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize].coords);
            let v = a.dot(&b.cross(&c)) / 6.0;
            let s = a + b + c;
            volume += v;
            first += s * (v / 4.0);
            second +=
                (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose())
                    * (v / 20.0);
        }
        if !(volume.is_finite() && volume > 1e-12) {
            return None;
        }
        let com = first / volume;
        let c = second * density;
        let about_origin = Matrix3::identity() * c.trace() - c;
        let mass_kg = density * volume;
        Some(Self {
            mass_kg,
            com: Point3::from(com),
            inertia: about_origin - shift(mass_kg, &com),
        })
    }

    /// What a model states (a URDF's `<inertial>`), in the link frame.
    pub fn stated(i: &robot::Inertial) -> Self {
        let [xx, yy, zz, xy, xz, yz] = i.inertia;
        let in_com = Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz);
        let r = i.link_from_com.rotation.to_rotation_matrix();
        Self {
            mass_kg: i.mass_kg,
            com: Point3::from(i.link_from_com.translation.vector),
            inertia: r.matrix() * in_com * r.matrix().transpose(),
        }
    }

    /// A solid box spanning `lo`–`hi` (link axes) of `density`.
    pub fn aabb(lo: &Point3, hi: &Point3, density: Real) -> Self {
        let d = hi - lo;
        let mass_kg = density * d.x * d.y * d.z;
        let k = mass_kg / 12.0;
        Self {
            mass_kg,
            com: Point3::from((lo.coords + hi.coords) / 2.0),
            inertia: Matrix3::from_diagonal(&Vector3::new(
                k * (d.y * d.y + d.z * d.z),
                k * (d.x * d.x + d.z * d.z),
                k * (d.x * d.x + d.y * d.y),
            )),
        }
    }

    /// The parts as one body.
    pub fn sum(parts: &[Self]) -> Option<Self> {
        let mass_kg: Real = parts.iter().map(|p| p.mass_kg).sum();
        if mass_kg.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let com = parts
            .iter()
            .fold(Vector3::zeros(), |acc, p| acc + p.com.coords * p.mass_kg)
            / mass_kg;
        let inertia = parts.iter().fold(Matrix3::zeros(), |acc, p| {
            acc + p.inertia + shift(p.mass_kg, &(p.com.coords - com))
        });
        Some(Self {
            mass_kg,
            com: Point3::from(com),
            inertia,
        })
    }
}

/// The parallel-axis term of a mass `m` at `d` from the centre.
fn shift(m: Real, d: &Vector3) -> Matrix3 {
    (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * m
}

/// Each link's mass properties (`None` for a link mounted on the scene),
/// and the notes on how they were found.
pub fn link_masses(
    robot: &Robot,
    config: &MjcfConfig,
) -> (Vec<Option<MassProperties>>, Vec<String>) {
    let mounted = robot.mounted_links();
    let mut notes = Vec::new();
    let masses = robot
        .links
        .iter()
        .enumerate()
        .map(|(i, link)| {
            if i < mounted {
                return None;
            }
            if let Some(stated) = link.inertial {
                return Some(MassProperties::stated(&stated));
            }
            let parts: Vec<MassProperties> = link
                .collision
                .iter()
                .map(|shape| match shape {
                    CollisionShape::Capsule(c) => MassProperties::capsule(
                        &c.segment.a,
                        &c.segment.b,
                        c.radius,
                        config.density_kg_m3,
                    ),
                    CollisionShape::Mesh(m) => MassProperties::mesh(m, config.density_kg_m3)
                        .unwrap_or_else(|| {
                            notes.push(format!(
                                "link {}: a mesh holds no volume (open?); its mass is its bounding box's",
                                link.name
                            ));
                            let b = m.bounding_box();
                            MassProperties::aabb(&b.min, &b.max, config.density_kg_m3)
                        }),
                })
                .collect();
            Some(MassProperties::sum(&parts).unwrap_or_else(|| {
                let r = 0.01;
                MassProperties {
                    mass_kg: config.min_mass_kg,
                    com: Point3::origin(),
                    inertia: Matrix3::identity() * (0.4 * config.min_mass_kg * r * r),
                }
            }))
        })
        .collect();
    (masses, notes)
}

/// Each actuated joint's torque (force) limit: `margin · g · Σ m_b · r_b`
/// over the moving links `b` after it, `r_b` the farthest link `b`'s centre
/// of mass can be from the joint's point with the arm stretched out (the
/// translations of the chain from the joint to the link, plus a prismatic
/// joint's travel, plus the centre's offset: the triangle inequality); a
/// prismatic joint carries `margin · g · Σ m_b`. At least `min_torque`.
pub fn torque_limits(
    robot: &Robot,
    masses: &[Option<MassProperties>],
    config: &MjcfConfig,
) -> Vec<Real> {
    let travel = |j: &robot::Joint| match (j.kind, j.limits) {
        (JointKind::Prismatic, Some(l)) => (l.min + j.offset).abs().max((l.max + j.offset).abs()),
        _ => 0.0,
    };
    let mut out = Vec::new();
    for (ji, joint) in robot.joints.iter().enumerate() {
        if !joint.is_actuated() {
            continue;
        }
        let mut load = 0.0;
        // From the joint's point to link ji + 1's origin.
        let mut reach = joint.post.translation.vector.norm() + travel(joint);
        for b in ji + 1..robot.links.len() {
            if b > ji + 1 {
                let k = &robot.joints[b - 1];
                reach += k.origin.translation.vector.norm()
                    + k.post.translation.vector.norm()
                    + travel(k);
            }
            if let Some(Some(m)) = masses.get(b) {
                load += match joint.kind {
                    JointKind::Prismatic => m.mass_kg,
                    _ => m.mass_kg * (reach + m.com.coords.norm()),
                };
            }
        }
        out.push((config.torque_margin * GRAVITY_M_S2 * load).max(config.min_torque));
    }
    out
}

/// A number as MJCF takes it (Rust's shortest round-trip form).
fn num(v: Real) -> String {
    let v = if v == 0.0 { 0.0 } else { v };
    format!("{v}")
}

fn nums(vs: &[Real]) -> String {
    vs.iter().map(|&v| num(v)).collect::<Vec<_>>().join(" ")
}

fn pos(p: &Vector3) -> String {
    nums(&[p.x, p.y, p.z])
}

/// MuJoCo's `w x y z`.
fn quat(q: &UnitQuaternion) -> String {
    let q = q.quaternion();
    nums(&[q.w, q.i, q.j, q.k])
}

/// `pos="…" quat="…"` of a pose.
fn pose_attrs(iso: &Isometry3) -> String {
    format!(
        "pos=\"{}\" quat=\"{}\"",
        pos(&iso.translation.vector),
        quat(&iso.rotation)
    )
}

/// An XML attribute value.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A body's name: MuJoCo keeps `world` for its own.
fn body_name(link: &str) -> String {
    if link == "world" {
        "world_link".to_owned()
    } else {
        link.to_owned()
    }
}

/// The geoms of one scene object (world frame): a geom element each, and
/// mesh assets.
struct SceneGeoms {
    geoms: Vec<String>,
    assets: Vec<String>,
    names: Vec<String>,
}

const SCENE_CLASS: &str = "group=\"0\" contype=\"2\" conaffinity=\"1\"";

fn box_geom(name: &str, world_from_box: &Isometry3, half: &Vector3, material: &str) -> String {
    format!(
        "    <geom name=\"{}\" type=\"box\" {} size=\"{}\" material=\"{}\" {SCENE_CLASS}/>\n",
        esc(name),
        pose_attrs(world_from_box),
        pos(half),
        esc(material)
    )
}

fn mesh_asset(name: &str, mesh: &TriMesh) -> String {
    let vertex: Vec<Real> = mesh.vertices.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    let face: Vec<String> = mesh
        .triangles
        .iter()
        .flat_map(|t| t.map(|i| i.to_string()))
        .collect();
    format!(
        "    <mesh name=\"{}\" inertia=\"shell\" vertex=\"{}\" face=\"{}\"/>\n",
        esc(name),
        nums(&vertex),
        face.join(" ")
    )
}

fn mesh_geom(name: &str, material: &str) -> String {
    format!(
        "    <geom name=\"{0}\" type=\"mesh\" mesh=\"mesh/{0}\" material=\"{1}\" {SCENE_CLASS}/>\n",
        esc(name),
        esc(material)
    )
}

/// `true` when the closed polygon turns one way only (a convex profile).
fn convex(profile: &[Point2]) -> bool {
    let n = profile.len();
    let mut sign = 0.0;
    for i in 0..n {
        let (a, b, c) = (profile[i], profile[(i + 1) % n], profile[(i + 2) % n]);
        let cross = (b - a).perp(&(c - b));
        if cross != 0.0 {
            if sign * cross < 0.0 {
                return false;
            }
            sign = cross;
        }
    }
    true
}

fn scene_object(
    o: &ObjectSpec,
    base_dir: &std::path::Path,
    notes: &mut Vec<String>,
) -> Result<SceneGeoms, ScenarioError> {
    let world_from_object = o.pose.map_or_else(Isometry3::identity, |p| p.isometry());
    let name = format!("scene/{}", o.name);
    let material = &o.material;
    let mut out = SceneGeoms {
        geoms: Vec::new(),
        assets: Vec::new(),
        names: Vec::new(),
    };
    let bad = |message: String| ScenarioError::Scenario {
        source_name: format!("scene object `{}`", o.name),
        message,
    };
    // The shape's own checks first (the same errors as building the world).
    let whole = o.shape.mesh(base_dir).map_err(|e| bad(e.to_string()))?;
    let add_mesh = |out: &mut SceneGeoms, part: String, mesh: TriMesh| {
        let mut mesh = mesh;
        mesh.transform(&world_from_object);
        out.assets.push(mesh_asset(&format!("mesh/{part}"), &mesh));
        out.geoms.push(mesh_geom(&part, material));
        out.names.push(part);
    };
    match &o.shape {
        ShapeSpec::Box { min, max } => {
            let (lo, hi) = (Vector3::from(*min), Vector3::from(*max));
            let centre = world_from_object
                * Isometry3::translation(
                    Real::midpoint(lo.x, hi.x),
                    Real::midpoint(lo.y, hi.y),
                    Real::midpoint(lo.z, hi.z),
                );
            out.geoms
                .push(box_geom(&name, &centre, &((hi - lo) / 2.0), material));
            out.names.push(name);
        }
        ShapeSpec::IBeam {
            from,
            to,
            up,
            depth,
            flange_width,
            flange_thickness,
            web_thickness,
        } => {
            // The frame of `geom::primitives::i_beam`: x along the beam, z up.
            let (from, to, up) = (Point3::from(*from), Point3::from(*to), Vector3::from(*up));
            let not_a_beam = || bad("`from`, `to` and `up` do not make a beam's frame".into());
            let x = geom::unit(to - from).ok_or_else(not_a_beam)?.into_inner();
            let z = geom::unit(up - x * x.dot(&up))
                .ok_or_else(not_a_beam)?
                .into_inner();
            let y = z.cross(&x);
            let rot = geom::Rotation3::from_basis_unchecked(&[x, y, z]);
            let world_from_beam =
                world_from_object * Isometry3::from_parts(from.coords.into(), rot.into());
            let length = (to - from).norm();
            let (tf, d) = (*flange_thickness, *depth);
            let parts = [
                ("bottom_flange", *flange_width, 0.0, tf),
                ("web", *web_thickness, tf, d - tf),
                ("top_flange", *flange_width, d - tf, d),
            ];
            for (part, width, z0, z1) in parts {
                let centre = world_from_beam
                    * Isometry3::translation(length / 2.0, 0.0, Real::midpoint(z0, z1));
                let part_name = format!("{name}/{part}");
                out.geoms.push(box_geom(
                    &part_name,
                    &centre,
                    &Vector3::new(length / 2.0, width / 2.0, (z1 - z0) / 2.0),
                    material,
                ));
                out.names.push(part_name);
            }
        }
        ShapeSpec::Cylinder { .. } => add_mesh(&mut out, name, whole),
        ShapeSpec::Prism {
            axis,
            profile,
            from,
            to,
        } => {
            let profile: Vec<Point2> = profile.iter().map(|p| Point2::new(p[0], p[1])).collect();
            if convex(&profile) {
                add_mesh(&mut out, name, whole);
            } else {
                for (k, t) in triangulate(&profile).iter().enumerate() {
                    let tri = t.map(|i| profile[i as usize]);
                    let piece = geom::primitives::prism(*axis, &tri, *from, *to)
                        .map_err(|e| bad(e.to_string()))?;
                    add_mesh(&mut out, format!("{name}/{k}"), piece);
                }
            }
        }
        ShapeSpec::Mesh { file, .. } => {
            notes.push(format!(
                "scene object `{}` ({}): MuJoCo's rays see its triangles, its contacts its convex hull",
                o.name,
                file.display()
            ));
            add_mesh(&mut out, name, whole);
        }
    }
    Ok(out)
}

/// Colours of the materials in a viewer, by their index.
const PALETTE: [&str; 6] = [
    "0.45 0.55 0.7 1",
    "0.7 0.55 0.35 1",
    "0.6 0.6 0.6 1",
    "0.85 0.85 0.8 1",
    "0.8 0.8 0.85 1",
    "0.5 0.7 0.5 1",
];

/// The arm's nested bodies (link 0 at the base pose) and its motors;
/// link meshes go to `assets`.
fn arm_xml(
    arm: &MjcfArm<'_>,
    masses: &[Option<MassProperties>],
    torques: &[Real],
    config: &MjcfConfig,
    assets: &mut String,
    notes: &mut Vec<String>,
) -> (String, String) {
    let robot = arm.robot;
    let mounted = robot.mounted_links();
    let mut body = String::new();
    let mut close = 0;
    let mut actuators = String::new();
    let mut actuated = 0;
    for (i, link) in robot.links.iter().enumerate() {
        let indent = "  ".repeat(i + 2);
        let parent_from_this = if i == 0 {
            arm.world_from_base
        } else {
            robot.joints[i - 1].parent_from_child(0.0)
        };
        let _ = writeln!(
            body,
            "{indent}<body name=\"{}\" {}>",
            esc(&body_name(&link.name)),
            pose_attrs(&parent_from_this)
        );
        close += 1;
        let inner = format!("{indent}  ");
        if i > 0 {
            let j = &robot.joints[i - 1];
            if j.is_actuated() {
                let child_from_joint = j.post.inverse();
                let axis = child_from_joint.rotation * j.axis.into_inner();
                let at = child_from_joint.translation.vector;
                let kind = if j.kind == JointKind::Prismatic {
                    "slide"
                } else {
                    "hinge"
                };
                let range = j.limits.map_or_else(String::new, |l| {
                    format!(" range=\"{}\"", nums(&[l.min, l.max]))
                });
                let tau = torques[actuated];
                let _ = writeln!(
                    body,
                    "{inner}<joint name=\"{}\" type=\"{kind}\" pos=\"{}\" axis=\"{}\"{range} armature=\"{}\" actuatorfrcrange=\"{}\"/>",
                    esc(&j.name),
                    pos(&at),
                    pos(&axis),
                    num(config.armature),
                    nums(&[-tau, tau])
                );
                let _ = writeln!(
                    actuators,
                    "    <motor name=\"{0}\" joint=\"{0}\" ctrlrange=\"{1}\"/>",
                    esc(&j.name),
                    nums(&[-tau, tau])
                );
                actuated += 1;
            }
        }
        if let Some(m) = masses[i] {
            let k = &m.inertia;
            let _ = writeln!(
                body,
                "{inner}<inertial pos=\"{}\" mass=\"{}\" fullinertia=\"{}\"/>",
                pos(&m.com.coords),
                num(m.mass_kg),
                nums(&[
                    k[(0, 0)],
                    k[(1, 1)],
                    k[(2, 2)],
                    k[(0, 1)],
                    k[(0, 2)],
                    k[(1, 2)]
                ])
            );
        }
        let class = if i < mounted {
            "group=\"2\" contype=\"0\" conaffinity=\"0\""
        } else {
            "group=\"1\" contype=\"1\" conaffinity=\"2\""
        };
        for (k, shape) in link.collision.iter().enumerate() {
            let name = format!("arm/{}/{k}", link.name);
            match shape {
                CollisionShape::Capsule(c) => {
                    let (a, b) = (c.segment.a, c.segment.b);
                    if a == b {
                        let _ = writeln!(
                            body,
                            "{inner}<geom name=\"{}\" type=\"sphere\" pos=\"{}\" size=\"{}\" material=\"arm\" {class}/>",
                            esc(&name),
                            pos(&a.coords),
                            num(c.radius)
                        );
                    } else {
                        let _ = writeln!(
                            body,
                            "{inner}<geom name=\"{}\" type=\"capsule\" fromto=\"{}\" size=\"{}\" material=\"arm\" {class}/>",
                            esc(&name),
                            nums(&[a.x, a.y, a.z, b.x, b.y, b.z]),
                            num(c.radius)
                        );
                    }
                }
                CollisionShape::Mesh(m) => {
                    assets.push_str(&mesh_asset(&format!("mesh/{name}"), m));
                    let _ = writeln!(
                        body,
                        "{inner}<geom name=\"{0}\" type=\"mesh\" mesh=\"mesh/{0}\" material=\"arm\" {class}/>",
                        esc(&name)
                    );
                    if i >= mounted {
                        notes.push(format!(
                            "link {}: MuJoCo's contacts see its mesh's convex hull",
                            link.name
                        ));
                    }
                }
            }
        }
        if let Some(s) = robot.scanner.filter(|s| s.link.index() == i) {
            let _ = writeln!(
                body,
                "{inner}<site name=\"scanner\" {} size=\"0.01\"/>",
                pose_attrs(&s.link_from_scanner)
            );
        }
        if robot.tool.0.index() == i {
            let _ = writeln!(
                body,
                "{inner}<site name=\"tool\" {} size=\"0.005\"/>",
                pose_attrs(&robot.tool.1)
            );
        }
        for (k, f) in robot.range_finders.iter().enumerate() {
            if f.link.index() != i {
                continue;
            }
            // z along the sensing axis.
            let rot =
                UnitQuaternion::rotation_between(&Vector3::z(), &f.axis).unwrap_or_else(|| {
                    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
                });
            let iso = Isometry3::from_parts(f.origin.coords.into(), rot);
            let _ = writeln!(
                body,
                "{inner}<site name=\"finder_{k}\" {} size=\"0.003\"/>",
                pose_attrs(&iso)
            );
        }
    }
    for i in (0..close).rev() {
        let _ = writeln!(body, "{}</body>", "  ".repeat(i + 2));
    }

    (body, actuators)
}

/// What serving the model needs beside it.
fn sidecar(
    loaded: &LoadedScenario,
    arm: &MjcfArm<'_>,
    (ros2, ros_names): (crate::ros2::Ros2Spec, Vec<String>),
    (masses, torques): (&[Option<MassProperties>], &[Real]),
    scene_geoms: Vec<(String, String)>,
    config: &MjcfConfig,
) -> Sidecar {
    let (scenario, robot) = (&loaded.scenario, arm.robot);
    let scanner = match (robot.scanner, &scenario.scanner) {
        (Some(_), spec) => {
            let config = spec.clone().unwrap_or_default().config;
            let bearings_rad = config.bearings_rad();
            Some(SidecarScanner {
                site: "scanner".into(),
                time_increment_s: sensor::float32(hw::motion::time_increment_s(
                    config.scan_time_s,
                    &bearings_rad,
                )),
                bearings_rad,
                config,
            })
        }
        (None, _) => None,
    };
    Sidecar {
        scenario: scenario.name.clone(),
        robot: robot.name.clone(),
        joints: robot
            .actuated()
            .zip(&ros_names)
            .zip(arm.start_joints)
            .zip(torques)
            .map(|(((j, ros), &start), &torque_limit)| SidecarJoint {
                name: j.name.clone(),
                ros_name: ros.clone(),
                kind: j.kind,
                start,
                min: j.limits.map(|l| l.min),
                max: j.limits.map(|l| l.max),
                torque_limit,
            })
            .collect(),
        ros2,
        scanner,
        range_finders: robot
            .range_finders
            .iter()
            .enumerate()
            .map(|(k, f)| SidecarFinder {
                site: format!("finder_{k}"),
                max_range_m: f.max_range_m,
            })
            .collect(),
        range_noise_sigma_m: arm.range_noise_sigma_m,
        materials: scenario.scene.materials.clone(),
        scene_geoms,
        config: *config,
        link_masses_kg: robot
            .links
            .iter()
            .zip(masses)
            .map(|(l, m)| (body_name(&l.name), m.map_or(0.0, |m| m.mass_kg)))
            .collect(),
    }
}

/// The MuJoCo model of `loaded`'s scene with `arm` standing in it.
///
/// Errors: a point-cloud world (no solids), a scene object its own checks
/// refuse, start joints of the wrong count, a link or joint name MuJoCo
/// would take for another (names must be unique).
pub fn model(
    loaded: &LoadedScenario,
    arm: &MjcfArm<'_>,
    config: &MjcfConfig,
) -> Result<MjcfModel, ScenarioError> {
    let scenario = &loaded.scenario;
    let robot = arm.robot;
    let fail = |message: String| ScenarioError::Scenario {
        source_name: scenario.name.clone(),
        message,
    };
    let positive = |v: Real| v.is_finite() && v > 0.0;
    if !(positive(config.density_kg_m3)
        && positive(config.min_mass_kg)
        && config.armature.is_finite()
        && config.armature >= 0.0
        && positive(config.torque_margin)
        && positive(config.min_torque)
        && positive(config.timestep_s))
    {
        return Err(ScenarioError::InvalidArgument {
            what: "MjcfConfig".into(),
            message: format!("expected positive finite figures (armature ≥ 0), got {config:?}"),
        });
    }
    robot.validate()?;
    robot
        .check_joints(arm.start_joints)
        .map_err(|e| fail(format!("start joints: {e}")))?;
    if scenario.scene.point_cloud.is_some() {
        return Err(fail(
            "the scene is a point cloud: it has no solids for MuJoCo to collide with".into(),
        ));
    }
    if scenario.scene.objects.is_empty() {
        return Err(fail("the scene has no objects".into()));
    }
    for (i, j) in robot.joints.iter().enumerate() {
        if robot.joints[..i].iter().any(|k| k.name == j.name) {
            return Err(fail(format!("two joints are called `{}`", j.name)));
        }
    }
    let ros2 = scenario.ros2.clone().unwrap_or_default();
    let ros_names = ros2
        .ros_joint_names(&robot.joint_names())
        .map_err(|e| fail(format!("ros2: {e}")))?;
    let mut notes = Vec::new();
    let (masses, mass_notes) = link_masses(robot, config);
    notes.extend(mass_notes);
    let torques = torque_limits(robot, &masses, config);

    // Scene.
    let mut assets = String::new();
    let mut world = String::new();
    let mut scene_geoms = Vec::new();
    for o in &scenario.scene.objects {
        scenario
            .scene
            .material_id(&o.material)
            .map_err(|e| fail(format!("scene object `{}`: {e}", o.name)))?;
        let g = scene_object(o, &loaded.base_dir, &mut notes)?;
        assets.extend(g.assets);
        world.extend(g.geoms);
        scene_geoms.extend(g.names.into_iter().map(|n| (n, o.material.clone())));
    }
    for (i, (name, _)) in scene_geoms.iter().enumerate() {
        if scene_geoms[..i].iter().any(|(n, _)| n == name) {
            return Err(fail(format!("two scene geoms are called `{name}`")));
        }
    }
    for (i, m) in scenario.scene.materials.iter().enumerate() {
        let _ = writeln!(
            assets,
            "    <material name=\"{}\" rgba=\"{}\"/>",
            esc(&m.name),
            PALETTE[i % PALETTE.len()]
        );
    }
    let _ = writeln!(
        assets,
        "    <material name=\"arm\" rgba=\"0.9 0.5 0.1 1\"/>"
    );

    let (body, actuators) = arm_xml(arm, &masses, &torques, config, &mut assets, &mut notes);

    let mut xml = String::new();
    let _ = writeln!(
        xml,
        "<mujoco model=\"{} ({})\">",
        esc(&scenario.name),
        esc(&robot.name)
    );
    let _ = writeln!(
        xml,
        "  <!-- Written by surveyor (scenario::mjcf). Masses: the links' stated inertials (URDF), else their collision shapes at {} kg/m3 \
         (a moving link with neither {} kg); armature {} on every joint; torque limits {} times the \
         gravity bound with the arm stretched out (at least {}). Arm geoms arm/LINK/K (group 1), \
         scene geoms scene/OBJECT[/PART] (group 0): only arm-scene pairs collide. -->",
        num(config.density_kg_m3),
        num(config.min_mass_kg),
        num(config.armature),
        num(config.torque_margin),
        num(config.min_torque)
    );
    for n in &notes {
        let _ = writeln!(xml, "  <!-- note: {} -->", n.replace("--", "- -"));
    }
    let _ = writeln!(
        xml,
        "  <compiler angle=\"radian\" autolimits=\"true\" inertiafromgeom=\"false\"/>"
    );
    let _ = writeln!(
        xml,
        "  <option timestep=\"{}\" gravity=\"0 0 -{}\" integrator=\"implicitfast\"/>",
        num(config.timestep_s),
        num(GRAVITY_M_S2)
    );
    let _ = writeln!(xml, "  <asset>\n{assets}  </asset>");
    let _ = writeln!(xml, "  <worldbody>\n{world}{body}  </worldbody>");
    let _ = writeln!(xml, "  <actuator>\n{actuators}  </actuator>");
    let _ = writeln!(
        xml,
        "  <keyframe>\n    <key name=\"start\" qpos=\"{}\"/>\n  </keyframe>",
        nums(arm.start_joints)
    );
    xml.push_str("</mujoco>\n");

    let sidecar = sidecar(
        loaded,
        arm,
        (ros2, ros_names),
        (&masses, &torques),
        scene_geoms,
        config,
    );
    Ok(MjcfModel {
        xml,
        sidecar,
        notes,
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::Scenario;
    use geom::Capsule;
    use robot::{Joint, JointLimits, Link, LinkId};
    use std::f64::consts::PI;

    /// The value of `attr` in the element that holds `name="NAME"`.
    fn attr(xml: &str, name: &str, attr: &str) -> String {
        let at = xml
            .find(&format!("name=\"{name}\""))
            .unwrap_or_else(|| panic!("no element {name}"));
        let start = xml[..at].rfind('<').unwrap();
        let end = at + xml[at..].find('>').unwrap();
        let element = &xml[start..end];
        let key = format!(" {attr}=\"");
        let from = element
            .find(&key)
            .unwrap_or_else(|| panic!("{element}: no {attr}"))
            + key.len();
        element[from..from + element[from..].find('"').unwrap()].to_owned()
    }

    fn values(s: &str) -> Vec<Real> {
        s.split_whitespace().map(|v| v.parse().unwrap()).collect()
    }

    fn close(got: &[Real], want: &[Real]) {
        assert_eq!(got.len(), want.len(), "{got:?} against {want:?}");
        for (a, b) in got.iter().zip(want) {
            assert!(
                (a - b).abs() <= 1e-12 * b.abs().max(1.0),
                "{got:?} against {want:?}"
            );
        }
    }

    /// A two-link arm over one box: a post-mounted hinge about z 0.5 m up
    /// carrying a 1 m capsule along x (r 0.1), and at its end a hinge
    /// about y carrying a 0.4 m capsule hanging down (r 0.05).
    fn two_link_arm() -> Robot {
        let mut l1 = Link::new("upper");
        l1.collision = vec![CollisionShape::Capsule(Capsule::new(
            Point3::origin(),
            Point3::new(1.0, 0.0, 0.0),
            0.1,
        ))];
        let mut l2 = Link::new("lower");
        l2.collision = vec![CollisionShape::Capsule(Capsule::new(
            Point3::origin(),
            Point3::new(0.0, 0.0, -0.4),
            0.05,
        ))];
        let robot = Robot {
            name: "two".into(),
            links: vec![Link::new("post"), l1, l2],
            joints: vec![
                Joint::revolute(
                    "shoulder",
                    Isometry3::translation(0.0, 0.0, 0.5),
                    Vector3::z_axis(),
                    Some(JointLimits::new(-2.0, 2.0)),
                ),
                Joint::revolute(
                    "elbow",
                    Isometry3::translation(1.0, 0.0, 0.0),
                    Vector3::y_axis(),
                    None,
                ),
            ],
            tool: (LinkId(2), Isometry3::translation(0.0, 0.0, -0.4)),
            scanner: None,
            range_finders: Vec::new(),
            warnings: Vec::new(),
        };
        robot.validate().unwrap();
        robot
    }

    fn one_box() -> LoadedScenario {
        let text = r#"
name = "one_box"
[robot]
preset = "point3"
start_joints = [0.0, 0.0, 0.0]
[scene]
[[scene.objects]]
name = "block"
material = "timber"
shape = { kind = "box", min = [1.0, -0.5, 0.0], max = [2.0, 0.5, 0.4] }
"#;
        LoadedScenario {
            scenario: Scenario::from_toml(text, "one_box.toml").unwrap(),
            base_dir: ".".into(),
        }
    }

    #[test]
    fn a_two_link_arm_over_a_box_has_the_hand_computed_numbers() {
        let robot = two_link_arm();
        let arm = MjcfArm {
            robot: &robot,
            world_from_base: Isometry3::translation(0.0, 0.0, 0.1),
            start_joints: &[0.25, -0.5],
            range_noise_sigma_m: 0.0,
        };
        let config = MjcfConfig::default();
        let m = model(&one_box(), &arm, &config).unwrap();
        let xml = &m.xml;
        // The box: centre and half sizes, in the scene's collision group.
        close(&values(&attr(xml, "scene/block", "pos")), &[1.5, 0.0, 0.2]);
        close(&values(&attr(xml, "scene/block", "size")), &[0.5, 0.5, 0.2]);
        assert_eq!(attr(xml, "scene/block", "contype"), "2");
        assert_eq!(attr(xml, "scene/block", "material"), "timber");
        // The chain: the base where it stands, each body at its joint's
        // origin (q = 0), the axes, the limits.
        close(&values(&attr(xml, "post", "pos")), &[0.0, 0.0, 0.1]);
        close(&values(&attr(xml, "upper", "pos")), &[0.0, 0.0, 0.5]);
        close(&values(&attr(xml, "upper", "quat")), &[1.0, 0.0, 0.0, 0.0]);
        close(&values(&attr(xml, "lower", "pos")), &[1.0, 0.0, 0.0]);
        close(&values(&attr(xml, "shoulder", "axis")), &[0.0, 0.0, 1.0]);
        close(&values(&attr(xml, "elbow", "axis")), &[0.0, 1.0, 0.0]);
        close(&values(&attr(xml, "shoulder", "range")), &[-2.0, 2.0]);
        // No limits, no range.
        let elbow_joint = &xml[xml.find("<joint name=\"elbow\"").unwrap()..];
        assert!(!elbow_joint[..elbow_joint.find('>').unwrap()].contains(" range=\""));
        // Masses: ρ (π r² h + 4/3 π r³), centred on the capsule.
        let rho = config.density_kg_m3;
        let m1 = rho * PI * (0.01 * 1.0 + 4.0 / 3.0 * 0.001);
        let m2 = rho * PI * (0.0025 * 0.4 + 4.0 / 3.0 * 0.000_125);
        let inertial = |link: &str| {
            let at = xml.find(&format!("<body name=\"{link}\"")).unwrap();
            let rest = &xml[at..];
            let i = rest.find("<inertial").unwrap();
            let element = &rest[i..i + rest[i..].find('>').unwrap()];
            let get = |k: &str| {
                let from = element.find(&format!(" {k}=\"")).unwrap() + k.len() + 3;
                values(&element[from..from + element[from..].find('"').unwrap()])
            };
            (get("mass"), get("pos"), get("fullinertia"))
        };
        let (mass, com, inertia) = inertial("upper");
        close(&mass, &[m1]);
        close(&com, &[0.5, 0.0, 0.0]);
        // About the axis (x): cylinder m r²/2, half-spheres 2/5 m r².
        let (mc, ms) = (rho * PI * 0.01, rho * PI * 4.0 / 3.0 * 0.001);
        let i_axis = mc * 0.01 / 2.0 + ms * 0.4 * 0.01;
        let i_perp = mc * (0.01 / 4.0 + 1.0 / 12.0) + ms * (0.4 * 0.01 + 0.25 + 3.0 / 8.0 * 0.1);
        close(&inertia, &[i_axis, i_perp, i_perp, 0.0, 0.0, 0.0]);
        let (mass, com, _) = inertial("lower");
        close(&mass, &[m2]);
        close(&com, &[0.0, 0.0, -0.2]);
        // Torque limits: 3 g Σ m r, r the stretched-out reach of each centre.
        let g = GRAVITY_M_S2;
        let shoulder = 3.0 * g * (m1 * 0.5 + m2 * (1.0 + 0.2));
        let elbow = 3.0 * g * m2 * 0.2;
        close(
            &values(&attr(xml, "shoulder", "actuatorfrcrange")),
            &[-shoulder, shoulder],
        );
        close(
            &values(&attr(xml, "elbow", "actuatorfrcrange")),
            &[-elbow, elbow],
        );
        let motor = &xml[xml.find("<motor name=\"elbow\"").unwrap()..];
        let range = motor.split("ctrlrange=\"").nth(1).unwrap();
        close(
            &values(&range[..range.find('"').unwrap()]),
            &[-elbow, elbow],
        );
        close(&values(&attr(xml, "elbow", "armature")), &[config.armature]);
        // The post is mounted: no mass, and its shapes (none here) collide with nothing.
        assert!(
            !xml[xml.find("<body name=\"post\"").unwrap()
                ..xml.find("<body name=\"upper\"").unwrap()]
                .contains("<inertial")
        );
        close(
            &values(&attr(xml, "arm/upper/0", "fromto")),
            &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
        );
        assert_eq!(attr(xml, "arm/lower/0", "conaffinity"), "2");
        close(&values(&attr(xml, "tool", "pos")), &[0.0, 0.0, -0.4]);
        close(&values(&attr(xml, "start", "qpos")), &[0.25, -0.5]);
        // The sidecar: joints in order with their limits, the box's material.
        let s = &m.sidecar;
        assert_eq!(s.joints.len(), 2);
        assert_eq!(
            (s.joints[0].name.as_str(), s.joints[0].max),
            ("shoulder", Some(2.0))
        );
        assert_eq!(s.joints[1].min, None);
        assert_eq!(s.scene_geoms, vec![("scene/block".into(), "timber".into())]);
        assert!(s.scanner.is_none());
    }

    #[test]
    fn a_beam_is_three_boxes_and_bad_input_is_refused() {
        let robot = two_link_arm();
        let arm = MjcfArm {
            robot: &robot,
            world_from_base: Isometry3::identity(),
            start_joints: &[0.0, 0.0],
            range_noise_sigma_m: 0.0,
        };
        let bridge = Scenario::load("bridge1").unwrap();
        let m = model(&bridge, &arm, &MjcfConfig::default()).unwrap();
        // left_beam: from (-2, 0.75, 0.80) to (2, 0.75, 0.80), depth 0.72:
        // its web spans z 0.82 to 1.50, 0.012 thick, 4 m long.
        close(
            &values(&attr(&m.xml, "scene/left_beam/web", "pos")),
            &[0.0, 0.75, 1.16],
        );
        close(
            &values(&attr(&m.xml, "scene/left_beam/web", "size")),
            &[2.0, 0.006, 0.34],
        );
        close(
            &values(&attr(&m.xml, "scene/left_beam/top_flange", "pos")),
            &[0.0, 0.75, 1.51],
        );
        assert!(m.xml.contains("mesh=\"mesh/scene/blast_hose\""));
        // Two start joints for a two-joint arm; not one.
        let short = MjcfArm {
            start_joints: &[0.0],
            ..arm.clone()
        };
        let e = model(&bridge, &short, &MjcfConfig::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("start joints"), "{e}");
        let e = model(
            &bridge,
            &arm,
            &MjcfConfig {
                density_kg_m3: -1.0,
                ..MjcfConfig::default()
            },
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("MjcfConfig"), "{e}");
    }

    /// A stated inertial turned a quarter about z: x and y swap.
    #[test]
    fn a_stated_inertial_is_put_in_the_link_frame() {
        let m = MassProperties::stated(&robot::Inertial {
            mass_kg: 2.0,
            link_from_com: Isometry3::new(Vector3::new(0.1, 0.0, 0.2), Vector3::z() * (PI / 2.0)),
            inertia: [0.3, 0.2, 0.1, 0.0, 0.0, 0.0],
        });
        assert_eq!(m.mass_kg, 2.0);
        close(&[m.com.x, m.com.y, m.com.z], &[0.1, 0.0, 0.2]);
        close(
            &[
                m.inertia[(0, 0)],
                m.inertia[(1, 1)],
                m.inertia[(2, 2)],
                m.inertia[(0, 1)],
            ],
            &[0.2, 0.3, 0.1, 0.0],
        );
    }
}
