//! Placing the control point for a start pose: damped least squares on the
//! control point's position and the tool axis (a pose for `--start x,y,z`
//! with arm robots; not part of Pudney's algorithm, which starts wherever the
//! robot is).

use crate::FollowError;
use geom::{Isometry3, Point3, Real, UnitVector3, Vector3};
use nalgebra::{DMatrix, DVector};
use robot::Robot;

/// Joints that put the control point at `target` (world frame) with the tool
/// z axis along `axis`, starting from each of `seeds` in turn and keeping the
/// first that converges (position within 1 mm, axis within 1°) inside the
/// joint limits. Errors when none converges.
pub fn place_tool(
    robot: &Robot,
    world_from_base: &Isometry3,
    target: &Point3,
    axis: &UnitVector3,
    seeds: &[Vec<Real>],
) -> Result<Vec<Real>, FollowError> {
    let base_target = world_from_base.inverse_transform_point(target);
    let base_axis = world_from_base.inverse_transform_vector(axis);
    let dof = robot.dof();
    let (tool_link, tool) = robot.tool;
    let tool_point = Point3::from(tool.translation.vector);
    for seed in seeds {
        if seed.len() != dof {
            continue;
        }
        let mut q = robot.clamp_to_limits(seed);
        for _ in 0..400 {
            let frames = robot.forward_kinematics(&q)?;
            let pose = frames[tool_link.0] * tool;
            let p = Point3::from(pose.translation.vector);
            let z = pose.rotation * Vector3::z();
            let e_pos = base_target - p;
            let e_rot = z.cross(&base_axis);
            if e_pos.norm() < 1e-3 && z.dot(&base_axis) > (1.0_f64).to_radians().cos() {
                if robot.within_limits(&q) {
                    return Ok(q);
                }
                break;
            }
            let j = robot.jacobian(&q, tool_link, &tool_point)?;
            let jm = DMatrix::from_fn(6, dof, |r, c| j[(r, c)]);
            let mut e = DVector::zeros(6);
            for k in 0..3 {
                e[k] = e_pos[k];
                e[k + 3] = e_rot[k];
            }
            let dq = robot::damped_pseudo_inverse(&jm, 0.05) * e;
            let n = dq.norm();
            let scale = if n > 0.2 { 0.2 / n } else { 1.0 };
            for (qi, d) in q.iter_mut().zip(dq.iter()) {
                *qi += d * scale;
            }
            q = robot.clamp_to_limits(&q);
        }
    }
    Err(FollowError::Unplaceable {
        robot: robot.name.clone(),
        target: *target,
        axis: axis.into_inner(),
        guesses: seeds.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arm4_reaches_above_the_cube_pointing_down() {
        let robot = robot::builtin("arm4").unwrap();
        let base = Isometry3::translation(-1.6, 0.0, 0.0);
        let target = Point3::new(0.0, 0.0, 1.1);
        let down = -Vector3::z_axis();
        let q = place_tool(
            &robot,
            &base,
            &target,
            &down,
            &[vec![0.0, 0.8, 0.0, 1.0, 0.0, 1.0]],
        )
        .unwrap();
        // Oracle: forward kinematics.
        let pose = base * robot.tool_pose(&q).unwrap();
        assert!((Point3::from(pose.translation.vector) - target).norm() < 1e-3);
        assert!((pose.rotation * Vector3::z()).dot(&down) > 0.999);
    }
}
