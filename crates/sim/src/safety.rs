//! Ground-truth collision checks of the robot against the scene (SPEC §6
//! "Safety"): the robot's link shapes (capsules, or meshes from a URDF) against
//! the scene's triangles.

use geom::{Isometry3, Real, Triangle};
use robot::{LinkId, PosedShape, Robot};
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
/// (`base_from_link`, from forward kinematics), one contact per link. The base
/// link (link 0) is skipped: it is mounted on the scene.
pub fn robot_contacts(
    robot: &Robot,
    base_from_link: &[Isometry3],
    world_from_base: &Isometry3,
    scene: &Scene,
) -> Vec<Contact> {
    let mut found: Vec<Contact> = Vec::new();
    for shape in robot.posed_collision_shapes(base_from_link) {
        let (link, face) = match shape {
            PosedShape::Capsule { link, capsule } => {
                if link == LinkId(0) || found.iter().any(|c| c.link == link) {
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
                if link == LinkId(0) || found.iter().any(|c| c.link == link) {
                    continue;
                }
                let world_from_link = world_from_base * base_from_link;
                let tris: Vec<Triangle> = mesh
                    .triangles
                    .iter()
                    .map(|t| {
                        Triangle::new(
                            world_from_link * mesh.vertices[t[0] as usize],
                            world_from_link * mesh.vertices[t[1] as usize],
                            world_from_link * mesh.vertices[t[2] as usize],
                        )
                    })
                    .collect();
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

/// Smallest distance between the robot's capsules (links ≥ 1) and the scene,
/// looking no farther than `search_m` (returns `search_m` when nothing is closer).
pub fn min_clearance(
    robot: &Robot,
    base_from_link: &[Isometry3],
    world_from_base: &Isometry3,
    scene: &Scene,
    search_m: Real,
) -> Real {
    let mut best = search_m;
    for shape in robot.posed_collision_shapes(base_from_link) {
        if let PosedShape::Capsule { link, capsule } = shape {
            if link == LinkId(0) {
                continue;
            }
            let c = capsule.transformed(world_from_base);
            for face in scene.triangles_near(&c.bounding_box().loosened(best)) {
                let d = c.distance_to_triangle(&scene.mesh().triangle(face as usize));
                best = best.min(d.max(0.0));
            }
        }
    }
    best
}
