//! Serial chains from URDF files (SPEC §3.2).
//!
//! Supported: `<link>` with `<collision>` (`<origin>` + `<geometry>`: `box`,
//! `cylinder` (a closed 24-segment mesh), `sphere` (a zero-length capsule), the common
//! `capsule` extension, and `mesh` with `filename` and optional `scale`), and
//! `<joint>` of type `fixed`, `revolute`, `continuous` (revolute without limits) and
//! `prismatic` with `<origin xyz rpy>` (fixed-axis roll, pitch, yaw), `<axis xyz>`
//! (default `1 0 0`) and `<limit lower upper velocity>` (the velocity bounds
//! the robot clock's motions, [`crate::timing`]). `floating` and `planar` joints are
//! rejected when they lie on the chain; a `<mimic>` joint is kept as an independent
//! joint, with a warning. A link's `<inertial>` is kept ([`crate::Inertial`]: a
//! physics model's masses). Other elements (`visual`, `gazebo`,
//! `transmission`…) are ignored.
//!
//! The chain runs from the root link (the one link that is no joint's child) to
//! the `tip` link, or — without a tip — down the tree as long as it does not branch.
//! Links off the chain are ignored.
//!
//! Mesh filenames: `package://<pkg>/<rest>` resolves to `<urdf dir>/<rest>`,
//! `file://<path>` and absolute paths are used as they are, relative paths are
//! relative to the URDF's directory. Mesh files are read by the caller's
//! [`MeshLoader`] ([`Robot::from_urdf_file_with`]); files it skips (an unread
//! format such as COLLADA `.dae`, or no loader at all with
//! [`Robot::from_urdf_file`]) add a note to [`Robot::warnings`] and contribute no
//! shape. A link left without any shape gets an automatic capsule from its origin
//! to the next joint's origin (radius [`DEFAULT_LINK_RADIUS_M`]), so every link has
//! a shape.
//!
//! Every error names the file and line (and the element and attribute) at fault.

use crate::bounds::enclosing_ellipsoid_of;
use crate::dh::DEFAULT_LINK_RADIUS_M;
use crate::error::RobotError;
use crate::mesh::{LoadedMesh, MeshLoader, NoMeshLoader, urdf_cylinder};
use crate::model::{CollisionShape, Inertial, Joint, JointKind, JointLimits, Link, LinkId, Robot};
use geom::math::isometry_from_xyz_rpy;
use geom::primitives::cuboid;
use geom::{Capsule, Isometry3, Point3, Real, TriMesh, Vector3, unit};
use roxmltree::{Document, Node};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

impl Robot {
    /// Load the serial chain from the root link to `tip` (or to the single leaf of
    /// an unbranched tree) of the URDF file at `path`, without reading mesh files
    /// (their geometry is skipped with a warning; see [`Robot::from_urdf_file_with`]).
    ///
    /// ```
    /// let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/robots/ur5/ur5_robot.urdf"));
    /// let ur5 = robot::Robot::from_urdf_file(path, Some("tool0"))?;
    /// assert_eq!(ur5.dof(), 6);
    /// # Ok::<(), robot::RobotError>(())
    /// ```
    pub fn from_urdf_file(path: &Path, tip: Option<&str>) -> Result<Robot, RobotError> {
        Self::from_urdf_file_with(path, tip, &NoMeshLoader)
    }

    /// [`Robot::from_urdf_file`], reading collision mesh files with `meshes`.
    pub fn from_urdf_file_with(
        path: &Path,
        tip: Option<&str>,
        meshes: &dyn MeshLoader,
    ) -> Result<Robot, RobotError> {
        let xml = std::fs::read_to_string(path).map_err(|e| RobotError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let base_dir = path.parent().unwrap_or_else(|| Path::new("."));
        Self::from_urdf_str_with(&xml, base_dir, &path.display().to_string(), tip, meshes)
    }

    /// Load a URDF from text without reading mesh files. Mesh paths resolve
    /// against `base_dir`; `source_name` (usually the file path) prefixes every
    /// error message.
    pub fn from_urdf_str(
        xml: &str,
        base_dir: &Path,
        source_name: &str,
        tip: Option<&str>,
    ) -> Result<Robot, RobotError> {
        Self::from_urdf_str_with(xml, base_dir, source_name, tip, &NoMeshLoader)
    }

    /// [`Robot::from_urdf_str`], reading collision mesh files with `meshes`.
    pub fn from_urdf_str_with(
        xml: &str,
        base_dir: &Path,
        source_name: &str,
        tip: Option<&str>,
        meshes: &dyn MeshLoader,
    ) -> Result<Robot, RobotError> {
        let doc = Document::parse(xml).map_err(|e| {
            let pos = e.pos();
            RobotError::Xml {
                file: source_name.to_owned(),
                line: pos.row,
                column: pos.col,
                message: e.to_string(),
            }
        })?;
        let mut parser = Parser {
            doc: &doc,
            file: source_name,
            base_dir,
            meshes,
            warnings: Vec::new(),
        };
        parser.robot(tip)
    }
}

/// A `<joint>` as first read: structure only.
struct RawJoint<'a, 'input> {
    node: Node<'a, 'input>,
    name: &'a str,
    kind: &'a str,
    parent: &'a str,
    child: &'a str,
}

struct Parser<'a, 'input> {
    doc: &'a Document<'input>,
    file: &'a str,
    base_dir: &'a Path,
    meshes: &'a dyn MeshLoader,
    warnings: Vec<String>,
}

/// One collision element after parsing.
enum Geometry {
    Capsule(Capsule),
    Mesh(TriMesh),
}

impl<'a, 'input> Parser<'a, 'input> {
    fn line(&self, node: Node) -> u32 {
        self.doc.text_pos_at(node.range().start).row
    }

    fn urdf_error(&self, node: Node, message: String) -> RobotError {
        RobotError::Urdf {
            file: self.file.to_owned(),
            line: self.line(node),
            message,
        }
    }

    fn missing(&self, node: Node, attribute: &str) -> RobotError {
        RobotError::MissingAttribute {
            file: self.file.to_owned(),
            line: self.line(node),
            element: node.tag_name().name().to_owned(),
            attribute: attribute.to_owned(),
        }
    }

    fn attr(&self, node: Node<'a, 'input>, name: &str) -> Result<&'a str, RobotError> {
        node.attribute(name).ok_or_else(|| self.missing(node, name))
    }

    fn bad_value(
        &self,
        node: Node,
        attribute: &str,
        value: &str,
        expected: &'static str,
    ) -> RobotError {
        let line = node.attribute_node(attribute).map_or_else(
            || self.line(node),
            |a| self.doc.text_pos_at(a.range().start).row,
        );
        RobotError::BadValue {
            file: self.file.to_owned(),
            line,
            element: node.tag_name().name().to_owned(),
            attribute: attribute.to_owned(),
            value: value.to_owned(),
            expected,
        }
    }

    fn required_child(
        &self,
        node: Node<'a, 'input>,
        name: &str,
    ) -> Result<Node<'a, 'input>, RobotError> {
        child(node, name).ok_or_else(|| RobotError::MissingElement {
            file: self.file.to_owned(),
            line: self.line(node),
            element: node.tag_name().name().to_owned(),
            child: name.to_owned(),
        })
    }

    /// `N` finite numbers separated by whitespace; `default` when the attribute is
    /// absent (`None` → missing-attribute error).
    fn reals<const N: usize>(
        &self,
        node: Node<'a, 'input>,
        name: &str,
        default: Option<[Real; N]>,
    ) -> Result<[Real; N], RobotError> {
        let Some(text) = node.attribute(name) else {
            return default.ok_or_else(|| self.missing(node, name));
        };
        let expected = match N {
            1 => "a finite number",
            3 => "3 finite numbers separated by spaces",
            _ => "finite numbers separated by spaces",
        };
        let mut out = [0.0; N];
        let mut count = 0;
        for word in text.split_whitespace() {
            if count == N {
                return Err(self.bad_value(node, name, text, expected));
            }
            match word.parse::<Real>() {
                Ok(v) if v.is_finite() => out[count] = v,
                _ => return Err(self.bad_value(node, name, text, expected)),
            }
            count += 1;
        }
        if count != N {
            return Err(self.bad_value(node, name, text, expected));
        }
        Ok(out)
    }

    fn real(
        &self,
        node: Node<'a, 'input>,
        name: &str,
        default: Option<Real>,
    ) -> Result<Real, RobotError> {
        self.reals::<1>(node, name, default.map(|d| [d]))
            .map(|[v]| v)
    }

    fn positive(&self, node: Node<'a, 'input>, name: &str) -> Result<Real, RobotError> {
        let v = self.real(node, name, None)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.bad_value(node, name, &v.to_string(), "a positive number"))
        }
    }

    /// The `<origin>` child of `node` (identity when absent).
    fn origin(&self, node: Node<'a, 'input>) -> Result<Isometry3, RobotError> {
        match child(node, "origin") {
            None => Ok(Isometry3::identity()),
            Some(o) => {
                let xyz = self.reals::<3>(o, "xyz", Some([0.0; 3]))?;
                if xyz.iter().any(|v| v.abs() > geom::MAX_COORDINATE_M) {
                    return Err(self.bad_value(
                        o,
                        "xyz",
                        o.attribute("xyz").unwrap_or(""),
                        "3 numbers within ±1e7 m (geom::MAX_COORDINATE_M)",
                    ));
                }
                let rpy = self.reals::<3>(o, "rpy", Some([0.0; 3]))?;
                Ok(isometry_from_xyz_rpy(xyz, rpy))
            }
        }
    }

    #[allow(
        clippy::too_many_lines,
        reason = "reads the URDF document in its own order (links, joints, the chain to the tip, limits, collision shapes), each error naming its element and line; split, the steps would pass the half-built robot between them"
    )]
    fn robot(&mut self, tip: Option<&str>) -> Result<Robot, RobotError> {
        let root = self.doc.root_element();
        if root.tag_name().name() != "robot" {
            return Err(self.urdf_error(
                root,
                format!(
                    "the root element is <{}>: expected <robot>",
                    root.tag_name().name()
                ),
            ));
        }
        let name = root.attribute("name").unwrap_or(self.file).to_owned();

        // Links and joints by name, in document order.
        let mut links: Vec<(&'a str, Node<'a, 'input>)> = Vec::new();
        let mut link_index: HashMap<&'a str, usize> = HashMap::new();
        let mut joints: Vec<RawJoint<'a, 'input>> = Vec::new();
        for node in root.children().filter(Node::is_element) {
            match node.tag_name().name() {
                "link" => {
                    let n = self.attr(node, "name")?;
                    if link_index.insert(n, links.len()).is_some() {
                        return Err(self.urdf_error(node, format!("a second link is called '{n}'")));
                    }
                    links.push((n, node));
                }
                "joint" => joints.push(self.raw_joint(node)?),
                _ => {}
            }
        }
        if links.is_empty() {
            return Err(self.urdf_error(root, "the robot has no <link>".to_owned()));
        }

        // Tree structure: the joint above each link, the joints below it.
        let mut parent_joint: HashMap<&str, usize> = HashMap::new();
        let mut child_joints: HashMap<&str, Vec<usize>> = HashMap::new();
        let mut joint_names: HashSet<&str> = HashSet::new();
        for (j, raw) in joints.iter().enumerate() {
            if !joint_names.insert(raw.name) {
                return Err(
                    self.urdf_error(raw.node, format!("a second joint is called '{}'", raw.name))
                );
            }
            for l in [raw.parent, raw.child] {
                if !link_index.contains_key(l) {
                    return Err(self.urdf_error(
                        raw.node,
                        format!(
                            "joint '{}' refers to link '{l}', which is not defined",
                            raw.name
                        ),
                    ));
                }
            }
            if let Some(&other) = parent_joint.get(raw.child) {
                return Err(self.urdf_error(
                    raw.node,
                    format!(
                        "link '{}' is the child of both joint '{}' and joint '{}': a URDF must be a tree",
                        raw.child, joints[other].name, raw.name
                    ),
                ));
            }
            parent_joint.insert(raw.child, j);
            child_joints.entry(raw.parent).or_default().push(j);
        }

        // The chain of joint indices from the root down to the tip.
        let chain: Vec<usize> = if let Some(tip) = tip {
            let Some(_) = link_index.get(tip) else {
                let names: Vec<&str> = links.iter().map(|(n, _)| *n).collect();
                return Err(self.urdf_error(
                    root,
                    format!(
                        "tip link '{tip}' is not defined; the links are: {}",
                        names.join(", ")
                    ),
                ));
            };
            let mut up = Vec::new();
            let mut at = tip;
            while let Some(&j) = parent_joint.get(at) {
                if up.len() > joints.len() {
                    return Err(self.urdf_error(
                        joints[j].node,
                        format!("the joints above link '{tip}' form a cycle"),
                    ));
                }
                up.push(j);
                at = joints[j].parent;
            }
            up.reverse();
            up
        } else {
            let roots: Vec<&str> = links
                .iter()
                .map(|(n, _)| *n)
                .filter(|n| !parent_joint.contains_key(n))
                .collect();
            let start = match roots.as_slice() {
                [only] => *only,
                [] => {
                    return Err(self.urdf_error(
                        root,
                        "every link has a parent joint: the joints form a cycle".to_owned(),
                    ));
                }
                many => {
                    return Err(self.urdf_error(
                        root,
                        format!(
                            "the URDF has several root links ({}); name a tip link to pick a chain",
                            many.join(", ")
                        ),
                    ));
                }
            };
            let mut down = Vec::new();
            let mut at = start;
            loop {
                match child_joints.get(at).map(Vec::as_slice) {
                    None | Some([]) => break,
                    Some([j]) => {
                        if down.len() > joints.len() {
                            break;
                        }
                        down.push(*j);
                        at = joints[*j].child;
                    }
                    Some(_) => {
                        let leaves: Vec<&str> = links
                            .iter()
                            .map(|(n, _)| *n)
                            .filter(|n| child_joints.get(n).is_none_or(Vec::is_empty))
                            .collect();
                        return Err(RobotError::BranchingTree {
                            file: self.file.to_owned(),
                            at: at.to_owned(),
                            leaves: leaves.join(", "),
                        });
                    }
                }
            }
            down
        };

        // Chain links: the root (parent of the first joint, or the tip alone), then
        // each joint's child.
        let first_link = match (chain.first(), tip) {
            (Some(&j), _) => joints[j].parent,
            (None, Some(t)) => t,
            (None, None) => links
                .iter()
                .map(|(n, _)| *n)
                .find(|n| !parent_joint.contains_key(n))
                .unwrap_or(links[0].0),
        };
        let mut chain_links = vec![first_link];
        chain_links.extend(chain.iter().map(|&j| joints[j].child));

        let mut robot_joints = Vec::with_capacity(chain.len());
        for &j in &chain {
            robot_joints.push(self.joint(&joints[j])?);
        }
        let mut robot_links = Vec::with_capacity(chain_links.len());
        for (k, link_name) in chain_links.iter().enumerate() {
            let node = link_index
                .get(link_name)
                .and_then(|&i| links.get(i))
                .map(|(_, node)| *node)
                .ok_or_else(|| {
                    self.urdf_error(root, format!("link '{link_name}' is not defined"))
                })?;
            let next_origin = robot_joints.get(k).map(|j: &Joint| j.origin);
            robot_links.push(self.link(node, link_name, next_origin)?);
        }

        let robot = Robot {
            name,
            tool: (LinkId(robot_links.len() - 1), Isometry3::identity()),
            links: robot_links,
            joints: robot_joints,
            scanner: None,
            range_finders: Vec::new(),
            warnings: std::mem::take(&mut self.warnings),
        };
        robot.validate()?;
        Ok(robot)
    }

    fn raw_joint(&self, node: Node<'a, 'input>) -> Result<RawJoint<'a, 'input>, RobotError> {
        let name = self.attr(node, "name")?;
        let kind = self.attr(node, "type")?;
        if !matches!(
            kind,
            "fixed" | "revolute" | "continuous" | "prismatic" | "floating" | "planar"
        ) {
            return Err(RobotError::UnknownJointType {
                file: self.file.to_owned(),
                line: self.line(node),
                joint: name.to_owned(),
                kind: kind.to_owned(),
            });
        }
        let parent = self.attr(self.required_child(node, "parent")?, "link")?;
        let child = self.attr(self.required_child(node, "child")?, "link")?;
        Ok(RawJoint {
            node,
            name,
            kind,
            parent,
            child,
        })
    }

    fn joint(&mut self, raw: &RawJoint<'a, 'input>) -> Result<Joint, RobotError> {
        let node = raw.node;
        let kind = match raw.kind {
            "fixed" => JointKind::Fixed,
            "revolute" | "continuous" => JointKind::Revolute,
            "prismatic" => JointKind::Prismatic,
            other => {
                return Err(RobotError::UnsupportedJointType {
                    file: self.file.to_owned(),
                    line: self.line(node),
                    joint: raw.name.to_owned(),
                    kind: other.to_owned(),
                });
            }
        };
        let origin = self.origin(node)?;
        if kind != JointKind::Fixed && child(node, "mimic").is_some() {
            self.warnings.push(format!(
                "{}:{}: joint '{}' has <mimic>, which is not supported; it is treated as an independent joint",
                self.file,
                self.line(node),
                raw.name
            ));
        }
        if kind == JointKind::Fixed {
            return Ok(Joint::fixed(raw.name, origin));
        }
        let axis = match child(node, "axis") {
            None => Vector3::x_axis(),
            Some(a) => {
                let xyz = self.reals::<3>(a, "xyz", Some([1.0, 0.0, 0.0]))?;
                unit(Vector3::from(xyz)).ok_or_else(|| {
                    self.bad_value(
                        a,
                        "xyz",
                        a.attribute("xyz").unwrap_or(""),
                        "a non-zero axis vector",
                    )
                })?
            }
        };
        let limits = if raw.kind == "continuous" {
            None
        } else {
            match child(node, "limit") {
                Some(l) if l.has_attribute("lower") || l.has_attribute("upper") => {
                    let lower = self.real(l, "lower", Some(0.0))?;
                    let upper = self.real(l, "upper", Some(0.0))?;
                    if lower > upper {
                        return Err(self.urdf_error(
                            l,
                            format!(
                                "joint '{}': <limit lower=\"{lower}\" upper=\"{upper}\">: expected lower ≤ upper",
                                raw.name
                            ),
                        ));
                    }
                    Some(JointLimits::new(lower, upper))
                }
                _ => {
                    self.warnings.push(format!(
                        "{}:{}: {} joint '{}' has no <limit lower upper>; treated as unlimited",
                        self.file,
                        self.line(node),
                        raw.kind,
                        raw.name
                    ));
                    None
                }
            }
        };
        let max_velocity = self.max_velocity(node, raw.name)?;
        let joint = match kind {
            JointKind::Prismatic => Joint::prismatic(raw.name, origin, axis, limits),
            _ => Joint::revolute(raw.name, origin, axis, limits),
        };
        Ok(Joint {
            max_velocity,
            ..joint
        })
    }

    /// A joint's `<limit velocity>`: `None` when absent, or 0 (which some
    /// URDFs write for "not given"; a warning says so); an error when
    /// negative or not a number.
    fn max_velocity(
        &mut self,
        node: Node<'a, 'input>,
        joint: &str,
    ) -> Result<Option<Real>, RobotError> {
        let Some(l) = child(node, "limit").filter(|l| l.has_attribute("velocity")) else {
            return Ok(None);
        };
        let v = self.real(l, "velocity", None)?;
        if v < 0.0 {
            return Err(self.bad_value(l, "velocity", &v.to_string(), "a speed of at least 0"));
        }
        if v == 0.0 {
            self.warnings.push(format!(
                "{}:{}: joint '{joint}' has <limit velocity=\"0\">; taken as not given",
                self.file,
                self.line(l)
            ));
            return Ok(None);
        }
        Ok(Some(v))
    }

    fn link(
        &mut self,
        node: Node<'a, 'input>,
        name: &str,
        next_joint_origin: Option<Isometry3>,
    ) -> Result<Link, RobotError> {
        let mut capsules = Vec::new();
        let mut meshes = Vec::new();
        for collision in node
            .children()
            .filter(|c| c.is_element() && c.tag_name().name() == "collision")
        {
            match self.collision(collision, name)? {
                Some(Geometry::Capsule(c)) => capsules.push(c),
                Some(Geometry::Mesh(m)) if !m.is_empty() => meshes.push(m),
                Some(Geometry::Mesh(_)) | None => {}
            }
        }
        if capsules.is_empty() && meshes.is_empty() {
            let end = next_joint_origin
                .map_or_else(Point3::origin, |o| Point3::from(o.translation.vector));
            capsules.push(Capsule::new(Point3::origin(), end, DEFAULT_LINK_RADIUS_M));
        }
        let vertices: Vec<Point3> = meshes
            .iter()
            .flat_map(|m| m.vertices.iter().copied())
            .collect();
        let ellipsoid = enclosing_ellipsoid_of(&capsules, &vertices);
        let mut collision: Vec<CollisionShape> =
            capsules.into_iter().map(CollisionShape::Capsule).collect();
        collision.extend(
            meshes
                .into_iter()
                .map(|m| CollisionShape::Mesh(Arc::new(m))),
        );
        Ok(Link {
            name: name.to_owned(),
            collision,
            ellipsoid,
            inertial: self.inertial(node)?,
        })
    }

    /// A link's `<inertial>` (`<mass value>`, `<origin>`, `<inertia ixx …
    /// izz>`, absent attributes 0), `None` without one or with a mass of 0.
    fn inertial(&self, node: Node<'a, 'input>) -> Result<Option<Inertial>, RobotError> {
        let Some(i) = child(node, "inertial") else {
            return Ok(None);
        };
        let Some(m) = child(i, "mass") else {
            return Ok(None);
        };
        let mass_kg = self.real(m, "value", None)?;
        if mass_kg < 0.0 {
            return Err(self.bad_value(m, "value", &mass_kg.to_string(), "a mass ≥ 0"));
        }
        if mass_kg == 0.0 {
            return Ok(None);
        }
        let mut inertia = [0.0; 6];
        if let Some(t) = child(i, "inertia") {
            for (v, k) in inertia
                .iter_mut()
                .zip(["ixx", "iyy", "izz", "ixy", "ixz", "iyz"])
            {
                *v = self.real(t, k, Some(0.0))?;
            }
        }
        Ok(Some(Inertial {
            mass_kg,
            link_from_com: self.origin(i)?,
            inertia,
        }))
    }

    fn collision(
        &mut self,
        node: Node<'a, 'input>,
        link: &str,
    ) -> Result<Option<Geometry>, RobotError> {
        let link_from_geometry = self.origin(node)?;
        let geometry = self.required_child(node, "geometry")?;
        let Some(shape) = geometry.children().find(Node::is_element) else {
            return Err(RobotError::MissingElement {
                file: self.file.to_owned(),
                line: self.line(geometry),
                element: "geometry".to_owned(),
                child: "box|cylinder|sphere|mesh".to_owned(),
            });
        };
        Ok(Some(match shape.tag_name().name() {
            "box" => {
                let size = self.reals::<3>(shape, "size", None)?;
                if size.iter().any(|s| *s < 0.0) {
                    return Err(self.bad_value(
                        shape,
                        "size",
                        shape.attribute("size").unwrap_or(""),
                        "three sizes ≥ 0",
                    ));
                }
                let h = Vector3::from(size) * 0.5;
                Geometry::Mesh(
                    cuboid(Point3::from(-h), Point3::from(h)).transformed(&link_from_geometry),
                )
            }
            "cylinder" => {
                let radius = self.positive(shape, "radius")?;
                let length = self.positive(shape, "length")?;
                let what = format!("{}:{}: <cylinder>", self.file, self.line(shape));
                Geometry::Mesh(
                    urdf_cylinder(radius, length, &what)?.transformed(&link_from_geometry),
                )
            }
            "sphere" => {
                let radius = self.positive(shape, "radius")?;
                let c = Point3::from(link_from_geometry.translation.vector);
                Geometry::Capsule(Capsule::new(c, c, radius))
            }
            "capsule" => {
                let radius = self.positive(shape, "radius")?;
                let length = self.real(shape, "length", None)?;
                let h = 0.5 * length.max(0.0);
                Geometry::Capsule(Capsule::new(
                    link_from_geometry * Point3::new(0.0, 0.0, -h),
                    link_from_geometry * Point3::new(0.0, 0.0, h),
                    radius,
                ))
            }
            "mesh" => {
                let filename = self.attr(shape, "filename")?;
                let scale = self.reals::<3>(shape, "scale", Some([1.0; 3]))?;
                let path = resolve_mesh_path(self.base_dir, filename);
                let line = self.line(shape);
                let mesh_error = |message: String| RobotError::MeshFile {
                    file: self.file.to_owned(),
                    line,
                    mesh: filename.to_owned(),
                    path: path.clone(),
                    message,
                };
                let mut mesh = match self.meshes.load(&path).map_err(mesh_error)? {
                    LoadedMesh::Mesh(m) => m,
                    LoadedMesh::Skipped(reason) => {
                        self.warnings.push(format!(
                            "{}:{line}: link '{link}': mesh '{filename}' not read ({reason}); \
                             this geometry is skipped",
                            self.file
                        ));
                        return Ok(None);
                    }
                };
                mesh.scale(Vector3::from(scale));
                let mesh = mesh.transformed(&link_from_geometry);
                Geometry::Mesh(mesh)
            }
            other => {
                return Err(self.urdf_error(
                    shape,
                    format!("unknown geometry <{other}> in link '{link}': expected box, cylinder, sphere or mesh"),
                ));
            }
        }))
    }
}

/// The first child element of `node` called `name`.
fn child<'a, 'input>(node: Node<'a, 'input>, name: &str) -> Option<Node<'a, 'input>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == name)
}

/// Where a URDF mesh filename points, relative to the URDF's directory `base_dir`.
///
/// ```
/// use std::path::{Path, PathBuf};
/// let dir = Path::new("/robots/ur5");
/// assert_eq!(robot::urdf::resolve_mesh_path(dir, "package://ur_description/meshes/a.stl"),
///            PathBuf::from("/robots/ur5/meshes/a.stl"));
/// assert_eq!(robot::urdf::resolve_mesh_path(dir, "meshes/a.stl"), PathBuf::from("/robots/ur5/meshes/a.stl"));
/// assert_eq!(robot::urdf::resolve_mesh_path(dir, "file:///tmp/a.stl"), PathBuf::from("/tmp/a.stl"));
/// ```
pub fn resolve_mesh_path(base_dir: &Path, filename: &str) -> PathBuf {
    if let Some(rest) = filename.strip_prefix("package://") {
        let rest = rest.split_once('/').map_or(rest, |(_package, rest)| rest);
        return base_dir.join(rest);
    }
    let path = Path::new(filename.strip_prefix("file://").unwrap_or(filename));
    if path.is_absolute() {
        path.to_path_buf()
    } else {
        base_dir.join(path)
    }
}
