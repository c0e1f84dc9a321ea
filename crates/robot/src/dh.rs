//! Robots from standard (distal) Denavit–Hartenberg tables, Corke convention:
//!
//! ```text
//! ⁱ⁻¹Tᵢ = Rz(qᵢ + offsetᵢ) · Tz(dᵢ) · Tx(aᵢ) · Rx(αᵢ)
//! ```
//!
//! as in Paul Table C.1 (the Denso VM-6083, whose "state at zero" column is the
//! offset) and eq. 3.4 / 3.9. Every joint is revolute.

use crate::bounds::enclosing_ellipsoid_of;
use crate::error::RobotError;
use crate::model::{CollisionShape, Joint, JointKind, JointLimits, Link, LinkId, Robot};
use geom::{Capsule, Isometry3, Point3, Real, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Radius (metres) of the automatic link capsules of DH and URDF robots whose links
/// have no geometry of their own.
pub const DEFAULT_LINK_RADIUS_M: Real = 0.04;

/// One row of a standard DH table (metres, radians).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DhRow {
    /// Link length `a` (along the new x axis).
    pub a: Real,
    /// Link offset `d` (along the previous z axis).
    pub d: Real,
    /// Link twist `α` (about the new x axis).
    pub alpha: Real,
    /// Joint angle at `q = 0` (the "state at zero").
    pub offset: Real,
    /// Joint limits on `q`.
    pub limits: Option<JointLimits>,
}

impl DhRow {
    /// A row without limits.
    pub fn new(a: Real, d: Real, alpha: Real, offset: Real) -> Self {
        Self {
            a,
            d,
            alpha,
            offset,
            limits: None,
        }
    }

    /// The same row with limits.
    pub fn with_limits(self, limits: JointLimits) -> Self {
        Self {
            limits: Some(limits),
            ..self
        }
    }

    /// The fixed part `Tz(d) · Tx(a) · Rx(α)` of the row's transform.
    pub fn post(&self) -> Isometry3 {
        Isometry3::from_parts(
            Translation3::new(self.a, 0.0, self.d),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), self.alpha),
        )
    }
}

impl Robot {
    /// A revolute serial chain from a standard DH table. Links are named
    /// `base_link`, `link1`…`linkN`, joints `joint1`…`jointN`; the tool is the last
    /// link's frame. Each moving link gets automatic capsules (radius
    /// [`DEFAULT_LINK_RADIUS_M`]) along its `d` and `a` offsets and an ellipsoid
    /// around them; replace `links[i].collision` / `.ellipsoid` for real geometry.
    ///
    /// ```
    /// use robot::{DhRow, Robot};
    /// // A planar two-link arm with unit links.
    /// let arm = Robot::from_dh("planar2", &[DhRow::new(1.0, 0.0, 0.0, 0.0), DhRow::new(1.0, 0.0, 0.0, 0.0)])?;
    /// let tool = arm.tool_pose(&[std::f64::consts::FRAC_PI_2, 0.0])?;
    /// assert!((tool.translation.vector - geom::Vector3::new(0.0, 2.0, 0.0)).norm() < 1e-12);
    /// # Ok::<(), robot::RobotError>(())
    /// ```
    pub fn from_dh(name: &str, table: &[DhRow]) -> Result<Robot, RobotError> {
        let mut links = vec![Link::new("base_link")];
        let mut joints = Vec::with_capacity(table.len());
        for (row, r) in table.iter().enumerate() {
            let bad = |message: String| RobotError::InvalidDh { row, message };
            for (field, v) in [
                ("a", r.a),
                ("d", r.d),
                ("alpha", r.alpha),
                ("offset", r.offset),
            ] {
                if !v.is_finite() {
                    return Err(bad(format!("{field} = {v}: expected a finite number")));
                }
            }
            if let Some(l) = r.limits
                && !l.is_valid()
            {
                return Err(bad(format!(
                    "limits [{}, {}]: expected finite min ≤ max",
                    l.min, l.max
                )));
            }
            let post = r.post();
            joints.push(Joint {
                name: format!("joint{}", row + 1),
                kind: JointKind::Revolute,
                origin: Isometry3::identity(),
                axis: Vector3::z_axis(),
                post,
                offset: r.offset,
                limits: r.limits,
                max_velocity: None,
            });
            // The physical link runs from the previous frame's origin along z by d,
            // then along x by a, to this frame's origin; in this frame's coordinates:
            let link_from_rotated = post.inverse();
            let start = link_from_rotated * Point3::origin();
            let knee = link_from_rotated * Point3::new(0.0, 0.0, r.d);
            let end = Point3::origin();
            let mut capsules = Vec::new();
            if r.d != 0.0 {
                capsules.push(Capsule::new(start, knee, DEFAULT_LINK_RADIUS_M));
            }
            if r.a != 0.0 || capsules.is_empty() {
                capsules.push(Capsule::new(knee, end, DEFAULT_LINK_RADIUS_M));
            }
            let mut link = Link::new(&format!("link{}", row + 1));
            link.ellipsoid = enclosing_ellipsoid_of(&capsules, &[]);
            link.collision = capsules.into_iter().map(CollisionShape::Capsule).collect();
            links.push(link);
        }
        let robot = Robot {
            name: name.to_owned(),
            tool: (LinkId(links.len() - 1), Isometry3::identity()),
            links,
            joints,
            scanner: None,
            range_finders: Vec::new(),
            warnings: Vec::new(),
        };
        robot.validate()?;
        Ok(robot)
    }
}
