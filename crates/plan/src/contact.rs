//! Ground-truth collision checks of the robot against the scene (SPEC §6
//! "Safety"): the robot's link shapes (capsules, or meshes from a URDF) against
//! the scene's triangles, at one configuration ([`robot_contacts`]) or along a
//! straight joint-space motion ([`motion_contacts`]).

use crate::PlanError;
use geom::{Aabb, Isometry3, Real, TriMesh, Triangle};
use robot::{CollisionShape, JointKind, LinkId, PosedShape, Robot};
use scene::{FaceId, ObjectId, Scene};
use serde::Serialize;

/// A link touching the scene.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Contact {
    /// The link.
    pub link: LinkId,
    /// A scene triangle it touches.
    pub face: FaceId,
    /// The scene object of that triangle.
    pub object: ObjectId,
}

/// Every link in contact with the scene at the given link frames
/// (`base_from_link`, from forward kinematics), one contact per link. The
/// links that never move ([`Robot::mounted_links`]: the base, and a URDF's
/// links fixed to it) are skipped: they are mounted on the scene.
pub fn robot_contacts(
    robot: &Robot,
    base_from_link: &[Isometry3],
    world_from_base: &Isometry3,
    scene: &Scene,
) -> Vec<Contact> {
    let mounted = robot.mounted_links();
    let mut found: Vec<Contact> = Vec::new();
    for shape in robot.posed_collision_shapes(base_from_link) {
        let (link, face) = match shape {
            PosedShape::Capsule { link, capsule } => {
                if link.index() < mounted || found.iter().any(|c| c.link == link) {
                    continue;
                }
                let c = capsule.transformed(world_from_base);
                (link, scene.capsule_contact(&c, 0.0).map(|(f, _)| f))
            }
            PosedShape::Mesh {
                link,
                mesh,
                base_from_link,
            } => {
                if link.index() < mounted || found.iter().any(|c| c.link == link) {
                    continue;
                }
                let tris = world_triangles(&mesh, &(world_from_base * base_from_link));
                (link, scene.triangles_contact(&tris).map(|(f, _)| f))
            }
        };
        if let Some(face) = face {
            found.push(Contact {
                link,
                face,
                object: scene.triangle_object(face),
            });
        }
    }
    found
}

/// A link mesh's triangles in the world frame.
fn world_triangles(mesh: &TriMesh, world_from_link: &Isometry3) -> Vec<Triangle> {
    mesh.triangles
        .iter()
        .map(|t| {
            Triangle::new(
                world_from_link * mesh.vertices[t[0] as usize],
                world_from_link * mesh.vertices[t[1] as usize],
                world_from_link * mesh.vertices[t[2] as usize],
            )
        })
        .collect()
}

/// Smallest distance between the robot's collision shapes (capsules and
/// meshes of the moving links, see [`Robot::mounted_links`]) and the scene,
/// looking no farther than `search_m` (returns `search_m` when nothing is closer).
pub fn min_clearance(
    robot: &Robot,
    base_from_link: &[Isometry3],
    world_from_base: &Isometry3,
    scene: &Scene,
    search_m: Real,
) -> Real {
    let mounted = robot.mounted_links();
    let mut best = search_m;
    for shape in robot.posed_collision_shapes(base_from_link) {
        match shape {
            PosedShape::Capsule { link, capsule } => {
                if link.index() < mounted {
                    continue;
                }
                let c = capsule.transformed(world_from_base);
                for face in scene.triangles_near(&c.bounding_box().loosened(best)) {
                    let d = c.distance_to_triangle(&scene.mesh().triangle(face as usize));
                    best = best.min(d.max(0.0));
                }
            }
            PosedShape::Mesh {
                link,
                mesh,
                base_from_link,
            } => {
                if link.index() < mounted {
                    continue;
                }
                let tris = world_triangles(&mesh, &(world_from_base * base_from_link));
                let boxes: Vec<Aabb> = tris
                    .iter()
                    .map(|t| Aabb::from_points([&t.a, &t.b, &t.c]))
                    .collect();
                let bounds = boxes.iter().fold(Aabb::empty(), |b, t| b.merged(t));
                for face in scene.triangles_near(&bounds.loosened(best)) {
                    let other = scene.mesh().triangle(face as usize);
                    let near = Aabb::from_points([&other.a, &other.b, &other.c]);
                    for (t, b) in tris.iter().zip(&boxes) {
                        // A triangle whose box is farther than `best` from
                        // the scene triangle's cannot come closer.
                        if b.loosened(best).intersects(&near) {
                            best = best.min(t.distance_to_triangle(&other).max(0.0));
                        }
                    }
                }
            }
        }
    }
    best
}

/// Most configurations [`motion_contacts`] checks along one motion; a finer
/// step is refused (a motion that needs more should be split by the caller).
pub const MAX_MOTION_CHECKS: usize = 1_000_000;

/// A contact found along a motion.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MotionContact {
    /// Where along the motion, `q = q0 + t (q1 − q0)`, `t ∈ [0, 1]`.
    pub t: Real,
    /// The joint values there.
    pub q: Vec<Real>,
    /// The link touching the scene.
    pub contact: Contact,
}

/// The result of [`motion_contacts`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MotionCheck {
    /// The first contact along the motion (smallest `t`), if any.
    pub first_contact: Option<MotionContact>,
    /// Configurations checked (both end poses included).
    pub checks: usize,
    /// Upper bound on how far any point of a link with collision shapes moves
    /// over the whole motion, metres.
    pub travel_bound_m: Real,
    /// Upper bound on how far any such point moves between two consecutive
    /// checks (`travel_bound_m / (checks − 1)`, at most the requested step).
    pub step_bound_m: Real,
}

impl MotionCheck {
    /// `true` when no checked configuration touches the scene.
    pub fn is_clear(&self) -> bool {
        self.first_contact.is_none()
    }
}

/// The smallest capsule radius of the links that are checked for contacts
/// (the moving ones); `None` when no such link has a capsule. Half of it is a
/// good `max_step_m` for [`motion_contacts`].
pub fn smallest_link_radius(robot: &Robot) -> Option<Real> {
    robot
        .links
        .iter()
        .skip(robot.mounted_links())
        .flat_map(|l| &l.collision)
        .filter_map(|s| match s {
            CollisionShape::Capsule(c) => Some(c.radius),
            CollisionShape::Mesh(_) => None,
        })
        .min_by(Real::total_cmp)
}

/// Largest distance from a link's frame origin to any point of its collision
/// shapes (0 without shapes).
fn link_extent(link: &robot::Link) -> Real {
    link.collision
        .iter()
        .map(|s| match s {
            CollisionShape::Capsule(c) => {
                c.segment.a.coords.norm().max(c.segment.b.coords.norm()) + c.radius
            }
            CollisionShape::Mesh(m) => m
                .vertices
                .iter()
                .map(|v| v.coords.norm())
                .fold(0.0, Real::max),
        })
        .fold(0.0, Real::max)
}

/// Upper bound on how far any point of a link with collision shapes (links ≥ 1)
/// moves along the straight joint-space motion from `q0` to `q1`.
///
/// The bound: with `q(t) = q0 + t Δq`, a point `P` on link `k` moves at
/// `|Ṗ| ≤ Σ_j |Δq_j| L_j(k)`, where for a prismatic joint `L_j = 1` and for a
/// revolute joint `L_j(k) = ‖P − A_j‖` bounded by the distance from a point
/// `A_j` of the joint axis along the chain: `‖post_j‖` (+ prismatic travel) to
/// the next link frame, then `‖origin_m‖ + ‖post_m‖` (+ `max_t |q_m(t) +
/// offset_m|` for prismatic joints `m`) per further joint, plus the largest
/// distance of a collision-shape point from link `k`'s frame origin. The
/// travel over `[0, 1]` is at most `Σ_j |Δq_j| max_k L_j(k)` (the triangle
/// inequality along the chain; joint angles between the end poses never
/// matter, so the bound holds for every intermediate configuration).
pub fn motion_travel_bound(robot: &Robot, q0: &[Real], q1: &[Real]) -> Result<Real, PlanError> {
    robot.check_joints(q0)?;
    robot.check_joints(q1)?;
    let n = robot.joints.len();
    // Per joint: its actuated index (if any).
    let mut index = vec![None; n];
    let mut next = 0;
    for (i, j) in robot.joints.iter().enumerate() {
        if j.is_actuated() {
            index[i] = Some(next);
            next += 1;
        }
    }
    // Largest |q + offset| of each prismatic joint over the motion (linear in t).
    let prismatic_travel = |i: usize| -> Real {
        let j = &robot.joints[i];
        match (j.kind, index[i]) {
            (JointKind::Prismatic, Some(k)) => {
                (q0[k] + j.offset).abs().max((q1[k] + j.offset).abs())
            }
            _ => 0.0,
        }
    };
    let extents: Vec<Real> = robot.links.iter().map(link_extent).collect();
    let has_shapes: Vec<bool> = robot
        .links
        .iter()
        .map(|l| !l.collision.is_empty())
        .collect();
    let mut total = 0.0;
    for (i, joint) in robot.joints.iter().enumerate() {
        let Some(k) = index[i] else { continue };
        let dq = (q1[k] - q0[k]).abs();
        if dq == 0.0 {
            continue;
        }
        // Links moved by joint i are links i + 1 .. n; only those with shapes count.
        let lever = match joint.kind {
            JointKind::Prismatic => {
                if has_shapes[i + 1..].iter().any(|&h| h) {
                    1.0
                } else {
                    0.0
                }
            }
            JointKind::Revolute => {
                let mut reach = joint.post.translation.vector.norm();
                let mut best: Real = 0.0;
                for link in i + 1..=n {
                    if link > i + 1 {
                        let m = link - 1; // the joint between link − 1 and link
                        let jm = &robot.joints[m];
                        reach += jm.origin.translation.vector.norm()
                            + jm.post.translation.vector.norm()
                            + prismatic_travel(m);
                    }
                    if has_shapes[link] {
                        best = best.max(reach + extents[link]);
                    }
                }
                best
            }
            JointKind::Fixed => 0.0,
        };
        total += dq * lever;
    }
    Ok(total)
}

/// Ground-truth contacts along the straight joint-space motion from `q0` to
/// `q1` (both included): [`robot_contacts`] at `q0 + (i/m)(q1 − q0)`,
/// `i = 0..=m`, with `m` the smallest count for which no point of any link
/// with collision shapes moves more than `max_step_m` between two checks, by
/// the bound of [`motion_travel_bound`]. Stops at the first contact.
///
/// What it guarantees: a scene point that comes deeper than `max_step_m`
/// inside a link capsule at any instant of the motion is inside that capsule
/// at one of the checks (the capsule's axis moves at most `max_step_m`), so a
/// link axis crossing a surface is caught whenever `max_step_m` ≤ the link
/// radius; use half the smallest link radius ([`smallest_link_radius`]).
/// Mesh links are checked exactly at the sampled configurations.
///
/// Errors: joint vectors of the wrong length or not finite; `max_step_m` not
/// a finite distance > 0; more than [`MAX_MOTION_CHECKS`] checks needed.
pub fn motion_contacts(
    robot: &Robot,
    q0: &[Real],
    q1: &[Real],
    world_from_base: &Isometry3,
    scene: &Scene,
    max_step_m: Real,
) -> Result<MotionCheck, PlanError> {
    if !(max_step_m.is_finite() && max_step_m > 0.0) {
        return Err(PlanError::InvalidArgument {
            what: "max_step_m".into(),
            message: format!("expected a finite distance > 0 (metres), got {max_step_m}"),
        });
    }
    let travel = motion_travel_bound(robot, q0, q1)?;
    let steps = (travel / max_step_m).ceil().max(1.0);
    if steps.is_nan() || steps >= MAX_MOTION_CHECKS as Real {
        return Err(PlanError::InvalidArgument {
            what: "max_step_m".into(),
            message: format!(
                "{max_step_m} m steps over a motion of up to {travel:.3} m need more than {MAX_MOTION_CHECKS} checks"
            ),
        });
    }
    // `steps` is a positive integer below MAX_MOTION_CHECKS.
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let steps = steps as usize;
    let mut q = q0.to_vec();
    let mut frames = Vec::with_capacity(robot.links.len());
    for i in 0..=steps {
        let t = i as Real / steps as Real;
        for (k, v) in q.iter_mut().enumerate() {
            *v = if i == steps {
                q1[k]
            } else {
                q0[k] + t * (q1[k] - q0[k])
            };
        }
        robot.fk_into(&q, &mut frames)?;
        if let Some(&contact) = robot_contacts(robot, &frames, world_from_base, scene).first() {
            return Ok(MotionCheck {
                first_contact: Some(MotionContact {
                    t,
                    q: q.clone(),
                    contact,
                }),
                checks: i + 1,
                travel_bound_m: travel,
                step_bound_m: travel / steps as Real,
            });
        }
    }
    Ok(MotionCheck {
        first_contact: None,
        checks: steps + 1,
        travel_bound_m: travel,
        step_bound_m: travel / steps as Real,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom::Point3;
    use geom::primitives::cuboid;
    use scene::{MaterialId, default_materials};
    use std::sync::Arc;

    /// point3 with its body swapped for a 0.1 m cube mesh centred on the
    /// control point, over a slab whose top is z = 0 (hand geometry): at
    /// z = 0.3 the gap between the cube's bottom and the slab, 0.25 m; with
    /// its centre 0.2 m past the slab's edge (its near face 0.15 m past), edge
    /// to edge, √(0.15² + 0.25²). Counting
    /// capsules only, the clearance was the search distance (1 m).
    #[test]
    fn mesh_links_count_in_the_clearance() {
        let mut robot = robot::builtin("point3").unwrap();
        let tool = robot.tool.0;
        let half = Point3::new(0.05, 0.05, 0.05);
        robot.links[tool.0].collision = vec![CollisionShape::Mesh(Arc::new(cuboid(
            Point3::origin() - half.coords,
            half,
        )))];
        let slab = cuboid(Point3::new(-1.0, -1.0, -0.1), Point3::new(1.0, 1.0, 0.0));
        let scene = Scene::from_mesh("slab", slab, default_materials(), MaterialId(0)).unwrap();
        let clearance = |q: [Real; 3]| {
            let frames = robot.forward_kinematics(&q).unwrap();
            min_clearance(&robot, &frames, &Isometry3::identity(), &scene, 1.0)
        };
        assert!((clearance([0.0, 0.0, 0.3]) - 0.25).abs() < 1e-12);
        let edge = (0.15_f64.powi(2) + 0.25_f64.powi(2)).sqrt();
        assert!((clearance([1.2, 0.0, 0.3]) - edge).abs() < 1e-12);
    }
}
