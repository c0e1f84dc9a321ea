//! The robot model: a serial chain of links and joints, its forward kinematics and
//! geometric Jacobians, and its link shapes posed in the base frame.
//!
//! Frames follow the rerun spelling of SPEC §2: `base_from_link[i]` maps points in
//! link `i`'s frame into the base frame, so `p_base = base_from_link[i] * p_link`.
//! Joint `i` joins `links[i]` (parent) to `links[i + 1]` (child):
//!
//! ```text
//! base_from_link[i + 1] = base_from_link[i] * origin_i * motion_i(q + offset_i) * post_i
//! ```
//!
//! which covers both URDF joints (`origin` = `<origin>`, `post` = identity) and
//! standard DH joints (`origin` = identity, motion = `Rz`, `post` = `Tz(d) Tx(a) Rx(α)`).
//! The forward kinematics is Paul eq. 3.4 / 3.9; the Jacobian is the velocity
//! relation `ẋ = J θ̇` of Pudney eq. 2 (P§3.3), with the revolute columns
//! `â_k × (x − q_k)` of Pudney eq. 5.

use crate::error::RobotError;
use geom::{
    Capsule, Ellipsoid, Isometry3, Point3, Real, Translation3, TriMesh, UnitQuaternion,
    UnitVector3, Vector3,
};
use nalgebra::{Matrix6xX, Quaternion};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// How a joint moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointKind {
    /// No motion; takes no entry in the joint vector.
    Fixed,
    /// Rotation about the axis (radians).
    Revolute,
    /// Translation along the axis (metres).
    Prismatic,
}

/// The range a joint may move through: radians for revolute joints, metres for
/// prismatic joints.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointLimits {
    /// Lowest allowed value.
    pub min: Real,
    /// Highest allowed value.
    pub max: Real,
}

impl JointLimits {
    /// Limits `[min, max]`.
    pub fn new(min: Real, max: Real) -> Self {
        Self { min, max }
    }

    /// Limits given in degrees (user-facing tables), stored in radians.
    pub fn from_degrees(min_deg: Real, max_deg: Real) -> Self {
        Self::new(min_deg.to_radians(), max_deg.to_radians())
    }

    /// `±bound`.
    pub fn symmetric(bound: Real) -> Self {
        Self::new(-bound, bound)
    }

    /// `true` when `value` lies in `[min, max]`.
    #[inline]
    pub fn contains(&self, value: Real) -> bool {
        value >= self.min && value <= self.max
    }

    /// `value` clamped into `[min, max]`.
    #[inline]
    pub fn clamp(&self, value: Real) -> Real {
        value.max(self.min).min(self.max)
    }

    /// `max − min`.
    pub fn span(&self) -> Real {
        self.max - self.min
    }

    /// `true` when both bounds are finite and `min ≤ max`.
    pub fn is_valid(&self) -> bool {
        self.min.is_finite() && self.max.is_finite() && self.min <= self.max
    }
}

/// One joint of the chain. The child link's frame is
/// `parent * origin * motion(q + offset) * post`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Joint {
    /// Name (URDF joint name, or `joint1`… for DH robots).
    pub name: String,
    /// How it moves.
    pub kind: JointKind,
    /// Parent link frame → joint frame (URDF `<origin>`; identity for DH).
    pub origin: Isometry3,
    /// Motion axis in the joint frame (URDF `<axis>`; z for DH).
    pub axis: UnitVector3,
    /// Fixed transform after the motion (DH: `Tz(d) Tx(a) Rx(α)`; identity for URDF).
    pub post: Isometry3,
    /// Added to the joint value before the motion (the DH "state at zero").
    pub offset: Real,
    /// Allowed range of the joint value `q` (before `offset`), if limited.
    pub limits: Option<JointLimits>,
    /// The fastest the joint may move, rad/s (m/s for a prismatic joint):
    /// the URDF's `<limit velocity>`, a built-in robot's published figure;
    /// `None` where none is known ([`crate::timing`] then takes a stated
    /// conservative value).
    pub max_velocity: Option<Real>,
}

impl Joint {
    /// A fixed joint placing the child at `origin` in the parent frame.
    pub fn fixed(name: &str, origin: Isometry3) -> Self {
        Self {
            name: name.to_owned(),
            kind: JointKind::Fixed,
            origin,
            axis: Vector3::z_axis(),
            post: Isometry3::identity(),
            offset: 0.0,
            limits: None,
            max_velocity: None,
        }
    }

    /// A revolute joint about `axis` (joint frame) at `origin` (parent frame).
    pub fn revolute(
        name: &str,
        origin: Isometry3,
        axis: UnitVector3,
        limits: Option<JointLimits>,
    ) -> Self {
        Self {
            kind: JointKind::Revolute,
            axis,
            limits,
            ..Self::fixed(name, origin)
        }
    }

    /// A prismatic joint along `axis` (joint frame) at `origin` (parent frame).
    pub fn prismatic(
        name: &str,
        origin: Isometry3,
        axis: UnitVector3,
        limits: Option<JointLimits>,
    ) -> Self {
        Self {
            kind: JointKind::Prismatic,
            ..Self::revolute(name, origin, axis, limits)
        }
    }

    /// `true` for revolute and prismatic joints (they take an entry of `q`).
    #[inline]
    pub fn is_actuated(&self) -> bool {
        self.kind != JointKind::Fixed
    }

    /// `parent_from_child` at joint value `q` (ignored for fixed joints).
    #[inline]
    pub fn parent_from_child(&self, q: Real) -> Isometry3 {
        let joint_from_child = match self.kind {
            JointKind::Fixed => self.post,
            JointKind::Revolute => {
                let (s, c) = (0.5 * (q + self.offset)).sin_cos();
                let a = self.axis;
                if a.x == 0.0 && a.y == 0.0 && a.z == 1.0 {
                    // The DH case, rotation about z, written out: the quaternion
                    // (c, 0, 0, s) times post's, and post's translation rotated by θ.
                    let (cos, sin) = (c * c - s * s, 2.0 * s * c);
                    let t = self.post.translation.vector;
                    let p = self.post.rotation.quaternion();
                    Isometry3::from_parts(
                        Translation3::new(cos * t.x - sin * t.y, sin * t.x + cos * t.y, t.z),
                        UnitQuaternion::new_unchecked(Quaternion::new(
                            c * p.w - s * p.k,
                            c * p.i - s * p.j,
                            c * p.j + s * p.i,
                            c * p.k + s * p.w,
                        )),
                    )
                } else {
                    // Unit quaternion of the rotation by θ about the axis, written out.
                    let rot = UnitQuaternion::new_unchecked(Quaternion::new(
                        c,
                        a.x * s,
                        a.y * s,
                        a.z * s,
                    ));
                    Isometry3::from_parts(
                        Translation3::from(rot * self.post.translation.vector),
                        rot * self.post.rotation,
                    )
                }
            }
            JointKind::Prismatic => Isometry3::from_parts(
                Translation3::from(
                    self.axis.into_inner() * (q + self.offset) + self.post.translation.vector,
                ),
                self.post.rotation,
            ),
        };
        if is_identity(&self.origin) {
            joint_from_child
        } else {
            self.origin * joint_from_child
        }
    }
}

/// `true` when `iso` is exactly the identity (DH joints' `origin`), so the
/// multiplication can be skipped.
#[inline]
fn is_identity(iso: &Isometry3) -> bool {
    let q = iso.rotation.quaternion();
    let t = &iso.translation.vector;
    q.w == 1.0 && q.i == 0.0 && q.j == 0.0 && q.k == 0.0 && t.x == 0.0 && t.y == 0.0 && t.z == 0.0
}

/// A collision shape in its link's frame.
#[derive(Clone, Debug, PartialEq)]
pub enum CollisionShape {
    /// A capsule (a sphere when both ends coincide).
    Capsule(Capsule),
    /// A triangle mesh, shared between robot copies.
    Mesh(Arc<TriMesh>),
}

/// A rigid body of the chain.
#[derive(Clone, Debug, PartialEq)]
pub struct Link {
    /// Name (URDF link name, or `base_link`, `link1`… for DH robots).
    pub name: String,
    /// Collision shapes in the link frame (may be empty for virtual links).
    pub collision: Vec<CollisionShape>,
    /// Bounding ellipsoid in the link frame, for the AXBAM safety distance (A eq. 3.5).
    pub ellipsoid: Option<Ellipsoid>,
    /// Mass properties, when the model states them (a URDF's `<inertial>`);
    /// kinematics never uses them, a physics model of the robot does
    /// (the MJCF of `scenario::mjcf`).
    pub inertial: Option<Inertial>,
}

/// A link's mass properties as a URDF's `<inertial>` states them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inertial {
    /// Mass, kg.
    pub mass_kg: Real,
    /// The inertia frame in the link frame: its origin is the centre of mass.
    pub link_from_com: Isometry3,
    /// Inertia about the centre of mass, in the inertia frame's axes, kg·m²:
    /// `[ixx, iyy, izz, ixy, ixz, iyz]`.
    pub inertia: [Real; 6],
}

impl Link {
    /// A link with no shapes.
    pub fn new(name: &str) -> Self {
        Self {
            name: name.to_owned(),
            collision: Vec::new(),
            ellipsoid: None,
            inertial: None,
        }
    }
}

/// Index of a link in [`Robot::links`] (0 is the base). Serialised as the bare
/// index.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
#[serde(transparent)]
pub struct LinkId(pub usize);

impl LinkId {
    /// The index into [`Robot::links`] (and into `base_from_link`).
    #[inline]
    pub fn index(self) -> usize {
        self.0
    }
}

impl std::fmt::Display for LinkId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// A single-point range finder fixed to a link (P§1.2): it measures along `axis`
/// from `origin`, both in the link frame, up to `max_range_m`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RangeFinderMount {
    /// The link carrying the sensor.
    pub link: LinkId,
    /// Sensor origin `s` in the link frame.
    pub origin: Point3,
    /// Sensing axis `â` in the link frame.
    pub axis: UnitVector3,
    /// Sensing range (metres).
    pub max_range_m: Real,
}

impl RangeFinderMount {
    /// Origin and axis in the base frame, given the link frames from
    /// [`Robot::fk_into`]; `None` when the link index is out of range.
    pub fn in_base(&self, base_from_link: &[Isometry3]) -> Option<(Point3, UnitVector3)> {
        let base_from_this = base_from_link.get(self.link.0)?;
        Some((
            base_from_this * self.origin,
            base_from_this.rotation * self.axis,
        ))
    }
}

/// Where the 2-D laser scanner sits. Scanner frame (Paul eq. 3.10): z = centre
/// ray, y = the ±90° ray, x = normal of the scan plane.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScannerMount {
    /// The link carrying the scanner.
    pub link: LinkId,
    /// Scanner frame in the link frame.
    pub link_from_scanner: Isometry3,
}

/// A collision shape posed in the base frame.
#[derive(Clone, Debug, PartialEq)]
pub enum PosedShape {
    /// A capsule already moved into the base frame.
    Capsule {
        /// The link.
        link: LinkId,
        /// The capsule in the base frame.
        capsule: Capsule,
    },
    /// A mesh with the transform that places it (vertices stay in the link frame).
    Mesh {
        /// The link.
        link: LinkId,
        /// The mesh, in the link frame.
        mesh: Arc<TriMesh>,
        /// Link frame in the base frame.
        base_from_link: Isometry3,
    },
}

impl PosedShape {
    /// The link the shape belongs to.
    pub fn link(&self) -> LinkId {
        match self {
            Self::Capsule { link, .. } | Self::Mesh { link, .. } => *link,
        }
    }
}

/// A serial-chain robot: links, joints, control point (tool), sensors.
///
/// `links[0]` is the base; joint `i` joins `links[i]` to `links[i + 1]`. Fixed
/// joints are allowed anywhere; only revolute and prismatic joints take an entry of
/// the joint vector `q`, in chain order.
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    /// Name (built-in name, URDF `<robot name>`, or as given to [`Robot::from_dh`]).
    pub name: String,
    /// Links, base first.
    pub links: Vec<Link>,
    /// Joints; `joints.len() == links.len() - 1`.
    pub joints: Vec<Joint>,
    /// Control point / flange: link index and `link_from_tool`.
    pub tool: (LinkId, Isometry3),
    /// The 2-D laser scanner, if the robot carries one.
    pub scanner: Option<ScannerMount>,
    /// Single-point range finders.
    pub range_finders: Vec<RangeFinderMount>,
    /// Non-fatal notes from loading (e.g. a mesh format that could not be read).
    pub warnings: Vec<String>,
}

impl Robot {
    /// Number of links that never move: the base link and the links joined
    /// to it by fixed joints before the first actuated joint (a URDF's `world`
    /// and `base_link`). They are mounted on the scene, so contact and safety
    /// checks leave them out.
    ///
    /// ```
    /// assert_eq!(robot::builtin("denso-vm6083")?.mounted_links(), 1);
    /// # Ok::<(), robot::RobotError>(())
    /// ```
    pub fn mounted_links(&self) -> usize {
        self.joints
            .iter()
            .position(Joint::is_actuated)
            .map_or(self.links.len(), |j| j + 1)
    }

    /// Number of actuated joints (length of `q`).
    #[inline]
    pub fn dof(&self) -> usize {
        self.joints.iter().filter(|j| j.is_actuated()).count()
    }

    /// Names of the actuated joints, in `q` order.
    pub fn joint_names(&self) -> Vec<&str> {
        self.actuated().map(|j| j.name.as_str()).collect()
    }

    /// Limits of the actuated joints, in `q` order.
    pub fn limits(&self) -> Vec<Option<JointLimits>> {
        self.actuated().map(|j| j.limits).collect()
    }

    /// Kinds of the actuated joints, in `q` order.
    pub fn joint_kinds(&self) -> Vec<JointKind> {
        self.actuated().map(|j| j.kind).collect()
    }

    /// The actuated joints, in `q` order.
    pub fn actuated(&self) -> impl Iterator<Item = &Joint> + '_ {
        self.joints.iter().filter(|j| j.is_actuated())
    }

    /// Index of the link called `name`.
    pub fn link_index(&self, name: &str) -> Option<LinkId> {
        self.links.iter().position(|l| l.name == name).map(LinkId)
    }

    /// `Ok` when `q` has one finite value per actuated joint.
    ///
    /// ```
    /// let robot = robot::builtin("point3")?;
    /// assert!(robot.check_joints(&[0.0, 0.0]).is_err());
    /// let err = robot.check_joints(&[0.0, f64::NAN, 0.0]).unwrap_err();
    /// assert!(err.to_string().contains("NaN"));
    /// # Ok::<(), robot::RobotError>(())
    /// ```
    pub fn check_joints(&self, q: &[Real]) -> Result<(), RobotError> {
        let dof = self.dof();
        if q.len() != dof {
            return Err(RobotError::JointCount {
                expected: dof,
                got: q.len(),
            });
        }
        if let Some(index) = q.iter().position(|v| !v.is_finite()) {
            let joint = self
                .actuated()
                .nth(index)
                .map_or_else(|| format!("#{index}"), |j| j.name.clone());
            return Err(RobotError::NonFiniteJoint {
                joint,
                index,
                value: q[index],
            });
        }
        Ok(())
    }

    /// [`Robot::check_joints`], then every value within its joint's limits:
    /// the first one outside is an [`RobotError::OutsideLimits`] naming it.
    pub fn check_within_limits(&self, q: &[Real]) -> Result<(), RobotError> {
        self.check_joints(q)?;
        match self.limit_violations(q).into_iter().next() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// The joints of `q` outside their limits, as [`RobotError::OutsideLimits`]
    /// (empty when `q` is within limits or invalid).
    pub fn limit_violations(&self, q: &[Real]) -> Vec<RobotError> {
        if self.check_joints(q).is_err() {
            return Vec::new();
        }
        self.actuated()
            .zip(q)
            .enumerate()
            .filter_map(|(index, (j, &v))| {
                let l = j.limits?;
                (!l.contains(v)).then(|| RobotError::OutsideLimits {
                    joint: j.name.clone(),
                    index,
                    value: v,
                    min: l.min,
                    max: l.max,
                    revolute: matches!(j.kind, JointKind::Revolute),
                })
            })
            .collect()
    }

    /// `true` when `q` is valid ([`Robot::check_joints`]) and every value lies
    /// within its joint's limits.
    pub fn within_limits(&self, q: &[Real]) -> bool {
        self.check_joints(q).is_ok()
            && self
                .actuated()
                .zip(q)
                .all(|(j, &v)| j.limits.is_none_or(|l| l.contains(v)))
    }

    /// `q` with every value clamped into its joint's limits (unlimited joints and
    /// surplus values unchanged).
    pub fn clamp_to_limits(&self, q: &[Real]) -> Vec<Real> {
        let mut out = q.to_vec();
        for (v, j) in out.iter_mut().zip(self.actuated()) {
            if let Some(l) = j.limits {
                *v = l.clamp(*v);
            }
        }
        out
    }

    /// `base_from_link` for every link (Paul eq. 3.4), `links.len()` frames.
    pub fn forward_kinematics(&self, q: &[Real]) -> Result<Vec<Isometry3>, RobotError> {
        let mut frames = Vec::with_capacity(self.joints.len() + 1);
        self.fk_into(q, &mut frames)?;
        Ok(frames)
    }

    /// [`Robot::forward_kinematics`] into a caller-owned vector: no allocation when
    /// it already has capacity for `links.len()` frames. On error `base_from_link`
    /// is left unchanged.
    #[inline]
    pub fn fk_into(
        &self,
        q: &[Real],
        base_from_link: &mut Vec<Isometry3>,
    ) -> Result<(), RobotError> {
        self.check_joints(q)?;
        base_from_link.clear();
        let mut current = Isometry3::identity();
        base_from_link.push(current);
        let mut values = q.iter();
        for joint in &self.joints {
            let value = if joint.is_actuated() {
                values.next().copied().unwrap_or(0.0)
            } else {
                0.0
            };
            current *= joint.parent_from_child(value);
            base_from_link.push(current);
        }
        Ok(())
    }

    /// `base_from_tool`: the control point / flange frame (Paul eq. 3.9).
    pub fn tool_pose(&self, q: &[Real]) -> Result<Isometry3, RobotError> {
        let frames = self.forward_kinematics(q)?;
        let (link, link_from_tool) = self.tool;
        let base_from_tool_link = frames.get(link.0).ok_or_else(|| self.link_error(link))?;
        Ok(base_from_tool_link * link_from_tool)
    }

    /// `base_from_scanner` (Paul: `⁰T_s = ⁰T_f ᶠT_s`), `None` without a scanner.
    pub fn scanner_pose(&self, q: &[Real]) -> Result<Option<Isometry3>, RobotError> {
        if self.scanner.is_none() {
            self.check_joints(q)?;
            return Ok(None);
        }
        self.scanner_pose_in(&self.forward_kinematics(q)?)
    }

    /// [`Robot::scanner_pose`] in the link frames `frames` (this robot's
    /// [`Robot::forward_kinematics`] at some `q`): the same pose, without
    /// computing the frames again.
    pub fn scanner_pose_in(&self, frames: &[Isometry3]) -> Result<Option<Isometry3>, RobotError> {
        let Some(mount) = self.scanner else {
            return Ok(None);
        };
        let base_from_mount_link = frames
            .get(mount.link.0)
            .ok_or_else(|| self.link_error(mount.link))?;
        Ok(Some(base_from_mount_link * mount.link_from_scanner))
    }

    /// Geometric Jacobian of the point `point_in_link` fixed to link `link`: a 6 × dof
    /// matrix whose rows 0..3 give the point's linear velocity and rows 3..6 the
    /// link's angular velocity (base frame) per unit joint speed. Columns follow
    /// `q`; joints after `link` give zero columns.
    pub fn jacobian(
        &self,
        q: &[Real],
        link: LinkId,
        point_in_link: &Point3,
    ) -> Result<Matrix6xX<Real>, RobotError> {
        if link.0 >= self.links.len() {
            return Err(self.link_error(link));
        }
        let frames = self.forward_kinematics(q)?;
        let mut out = Matrix6xX::zeros(self.dof());
        self.jacobian_into(&frames, link, point_in_link, &mut out);
        Ok(out)
    }

    /// [`Robot::jacobian`] from link frames already computed by [`Robot::fk_into`],
    /// into a caller-owned matrix: no allocation when `out` already has `dof`
    /// columns (otherwise it is resized).
    ///
    /// Only joints whose parent frame is present in `base_from_link` contribute: a
    /// `link` past the end of `base_from_link` gives an all-zero matrix (use
    /// [`Robot::jacobian`] for a checked call).
    #[inline]
    pub fn jacobian_into(
        &self,
        base_from_link: &[Isometry3],
        link: LinkId,
        point_in_link: &Point3,
        out: &mut Matrix6xX<Real>,
    ) {
        let link = link.0;
        let dof = self.dof();
        if out.ncols() == dof {
            out.fill(0.0);
        } else {
            *out = Matrix6xX::zeros(dof);
        }
        let Some(base_from_target) = base_from_link.get(link) else {
            return;
        };
        let p = (base_from_target * point_in_link).coords;
        let mut column = 0;
        for (i, (joint, base_from_parent)) in self.joints.iter().zip(base_from_link).enumerate() {
            if i >= link || column >= dof {
                break;
            }
            if !joint.is_actuated() {
                continue;
            }
            // Joint axis and position in the base frame.
            let (axis, at) = if is_identity(&joint.origin) {
                (
                    base_from_parent.rotation * joint.axis.into_inner(),
                    base_from_parent.translation.vector,
                )
            } else {
                (
                    base_from_parent.rotation * (joint.origin.rotation * joint.axis.into_inner()),
                    base_from_parent
                        .transform_point(&Point3::from(joint.origin.translation.vector))
                        .coords,
                )
            };
            let mut col = out.column_mut(column);
            match joint.kind {
                JointKind::Revolute => {
                    let linear = axis.cross(&(p - at));
                    col[0] = linear.x;
                    col[1] = linear.y;
                    col[2] = linear.z;
                    col[3] = axis.x;
                    col[4] = axis.y;
                    col[5] = axis.z;
                }
                JointKind::Prismatic => {
                    col[0] = axis.x;
                    col[1] = axis.y;
                    col[2] = axis.z;
                }
                JointKind::Fixed => {}
            }
            column += 1;
        }
    }

    /// Position and unit axis in the base frame of joint `joint` (an index into
    /// [`Robot::joints`]), given the link frames: the `q_k` and `â_k` of Pudney
    /// eq. 5. `None` when out of range.
    pub fn joint_axis_in_base(
        &self,
        base_from_link: &[Isometry3],
        joint: usize,
    ) -> Option<(Point3, UnitVector3)> {
        let j = self.joints.get(joint)?;
        let base_from_joint = base_from_link.get(joint)? * j.origin;
        Some((
            Point3::from(base_from_joint.translation.vector),
            base_from_joint.rotation * j.axis,
        ))
    }

    /// Every link's collision shapes in the base frame, tagged with the link index.
    pub fn posed_collision_shapes(&self, base_from_link: &[Isometry3]) -> Vec<PosedShape> {
        let mut out = Vec::new();
        for (index, (link, frame)) in self.links.iter().zip(base_from_link).enumerate() {
            for shape in &link.collision {
                out.push(match shape {
                    CollisionShape::Capsule(c) => PosedShape::Capsule {
                        link: LinkId(index),
                        capsule: c.transformed(frame),
                    },
                    CollisionShape::Mesh(m) => PosedShape::Mesh {
                        link: LinkId(index),
                        mesh: Arc::clone(m),
                        base_from_link: *frame,
                    },
                });
            }
        }
        out
    }

    /// Every link's bounding ellipsoid in the base frame, tagged with the link index.
    pub fn posed_ellipsoids(&self, base_from_link: &[Isometry3]) -> Vec<(LinkId, Ellipsoid)> {
        self.links
            .iter()
            .zip(base_from_link)
            .enumerate()
            .filter_map(|(i, (link, frame))| {
                link.ellipsoid.map(|e| (LinkId(i), e.transformed(frame)))
            })
            .collect()
    }

    /// Paul eq. 3.5: the smallest algebraic distance between any of `points` (base
    /// frame) and the bounding ellipsoid of any link after the first (links 1..).
    /// Below 1 means a point is inside an ellipsoid. `+∞` when there are no points or
    /// no ellipsoids.
    ///
    /// ```
    /// let robot = robot::builtin("point3")?;
    /// // The point robot's ellipsoid is a sphere of radius 0.02 at the control point.
    /// let d = robot.min_algebraic_distance(&[0.0; 3], &[geom::Point3::new(0.04, 0.0, 0.0)])?;
    /// assert!((d - 4.0).abs() < 1e-9);
    /// # Ok::<(), robot::RobotError>(())
    /// ```
    pub fn min_algebraic_distance(
        &self,
        q: &[Real],
        points: &[Point3],
    ) -> Result<Real, RobotError> {
        if let Some(index) = points.iter().position(|p| !geom::math::is_finite_point(p)) {
            let p = points[index];
            return Err(RobotError::NonFinitePoint {
                index,
                x: p.x,
                y: p.y,
                z: p.z,
            });
        }
        let frames = self.forward_kinematics(q)?;
        let mut best = Real::INFINITY;
        for (link, frame) in self.links.iter().zip(&frames).skip(1) {
            let Some(e) = link.ellipsoid else { continue };
            let ellipsoid_from_base = (frame * e.pose).inverse();
            let inv_r = Vector3::new(1.0 / e.radii.x, 1.0 / e.radii.y, 1.0 / e.radii.z);
            for p in points {
                let local = (ellipsoid_from_base * p).coords.component_mul(&inv_r);
                best = best.min(local.norm_squared());
            }
        }
        Ok(best)
    }

    /// Checks that the parts fit together: one more link than joints, tool, scanner
    /// and sensors on existing links, finite transforms, valid limits, unique link
    /// names.
    pub fn validate(&self) -> Result<(), RobotError> {
        let bad = |message: String| RobotError::InvalidRobot {
            robot: self.name.clone(),
            message,
        };
        if self.links.len() != self.joints.len() + 1 {
            return Err(bad(format!(
                "a serial chain needs one more link than joints: {} links, {} joints",
                self.links.len(),
                self.joints.len()
            )));
        }
        let n = self.links.len();
        if self.tool.0.0 >= n {
            return Err(bad(format!(
                "tool link index {} out of range ({n} links)",
                self.tool.0
            )));
        }
        if !isometry_is_finite(&self.tool.1) {
            return Err(bad("tool transform is not finite".to_owned()));
        }
        if let Some(s) = self.scanner {
            if s.link.0 >= n {
                return Err(bad(format!(
                    "scanner link index {} out of range ({n} links)",
                    s.link
                )));
            }
            if !isometry_is_finite(&s.link_from_scanner) {
                return Err(bad("scanner transform is not finite".to_owned()));
            }
        }
        for (i, r) in self.range_finders.iter().enumerate() {
            if r.link.0 >= n {
                return Err(bad(format!(
                    "range finder {i} is on link {} but there are {n} links",
                    r.link
                )));
            }
            if !(geom::math::is_finite_point(&r.origin)
                && r.max_range_m > 0.0
                && r.max_range_m.is_finite())
            {
                return Err(bad(format!(
                    "range finder {i} has a non-finite origin or a non-positive range"
                )));
            }
        }
        for j in &self.joints {
            if !(isometry_is_finite(&j.origin)
                && isometry_is_finite(&j.post)
                && j.offset.is_finite())
            {
                return Err(bad(format!(
                    "joint {} has a non-finite transform or offset",
                    j.name
                )));
            }
            if let Some(l) = j.limits
                && !l.is_valid()
            {
                return Err(bad(format!(
                    "joint {} has limits [{}, {}]: expected finite min ≤ max",
                    j.name, l.min, l.max
                )));
            }
        }
        for (i, link) in self.links.iter().enumerate() {
            if self.links[..i].iter().any(|l| l.name == link.name) {
                return Err(bad(format!("two links are called '{}'", link.name)));
            }
        }
        Ok(())
    }

    fn link_error(&self, link: LinkId) -> RobotError {
        RobotError::LinkOutOfRange {
            robot: self.name.clone(),
            link: link.0,
            links: self.links.len(),
        }
    }
}

fn isometry_is_finite(iso: &Isometry3) -> bool {
    iso.translation.vector.iter().all(|v| v.is_finite())
        && iso.rotation.coords.iter().all(|v| v.is_finite())
}
