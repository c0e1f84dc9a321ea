//! Errors of the robot crate.
//!
//! Every variant names what is at fault — the joint, the link, the URDF file and
//! line, the element and attribute — and what was expected, so the message alone
//! tells the user what to fix (SPEC §2).

use geom::Real;
use std::path::PathBuf;

/// What can go wrong building a robot or evaluating its kinematics.
///
/// Errors are plain data (`Clone`, `PartialEq`) so callers can store and compare
/// them; operating-system errors are kept as their message.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RobotError {
    /// A joint vector of the wrong length.
    #[error("expected {expected} joint values (one per actuated joint), got {got}")]
    JointCount {
        /// Number of actuated joints of the robot.
        expected: usize,
        /// Length of the vector given.
        got: usize,
    },
    /// A joint value that is NaN or infinite.
    #[error("joint {joint} (q[{index}]) is {value}: joint values must be finite")]
    NonFiniteJoint {
        /// Name of the joint.
        joint: String,
        /// Index in the joint vector.
        index: usize,
        /// The offending value.
        value: Real,
    },
    /// A joint value outside its joint's limits. The message gives revolute
    /// values in degrees and radians, prismatic ones in metres.
    #[error("joint {joint} (q[{index}]) is {}, outside its limits [{}, {}]", show(*.revolute, *.value), show(*.revolute, *.min), show(*.revolute, *.max))]
    OutsideLimits {
        /// Name of the joint.
        joint: String,
        /// Index in the joint vector.
        index: usize,
        /// The value (radians or metres).
        value: Real,
        /// Lower limit.
        min: Real,
        /// Upper limit.
        max: Real,
        /// `true` for a revolute joint (radians), `false` for prismatic (metres).
        revolute: bool,
    },
    /// A query point that is NaN or infinite.
    #[error("point {index} is not finite: ({x}, {y}, {z})")]
    NonFinitePoint {
        /// Index of the point in the slice given.
        index: usize,
        /// x coordinate.
        x: Real,
        /// y coordinate.
        y: Real,
        /// z coordinate.
        z: Real,
    },
    /// A link index past the end of the chain.
    #[error("link index {link} is out of range: robot '{robot}' has {links} links")]
    LinkOutOfRange {
        /// The robot.
        robot: String,
        /// The index given.
        link: usize,
        /// Number of links.
        links: usize,
    },
    /// [`crate::builtin()`] was asked for a robot it does not know.
    #[error("unknown built-in robot '{name}': valid names are {valid}")]
    UnknownBuiltin {
        /// The name asked for.
        name: String,
        /// The valid names, comma separated.
        valid: String,
    },
    /// A DH table row that cannot describe a joint.
    #[error("DH row {row} (joint {}): {message}", row + 1)]
    InvalidDh {
        /// 0-based row index.
        row: usize,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A robot whose parts do not fit together (indices out of range, bad limits…).
    #[error("robot '{robot}': {message}")]
    InvalidRobot {
        /// The robot.
        robot: String,
        /// What is wrong.
        message: String,
    },
    /// A file could not be read.
    #[error("{}: cannot read: {message}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        message: String,
    },
    /// The URDF is not well-formed XML.
    #[error("{file}:{line}:{column}: malformed XML: {message}")]
    Xml {
        /// The URDF (file path or source name).
        file: String,
        /// 1-based line.
        line: u32,
        /// 1-based column.
        column: u32,
        /// The XML parser's message.
        message: String,
    },
    /// A required attribute is missing.
    #[error("{file}:{line}: <{element}> is missing the attribute '{attribute}'")]
    MissingAttribute {
        /// The URDF.
        file: String,
        /// 1-based line of the element.
        line: u32,
        /// Element name.
        element: String,
        /// Attribute name.
        attribute: String,
    },
    /// A required child element is missing.
    #[error("{file}:{line}: <{element}> is missing its <{child}> element")]
    MissingElement {
        /// The URDF.
        file: String,
        /// 1-based line of the parent element.
        line: u32,
        /// Parent element name.
        element: String,
        /// Child element expected (or the alternatives, separated by `|`).
        child: String,
    },
    /// An attribute whose value cannot be used.
    #[error("{file}:{line}: <{element} {attribute}=\"{value}\">: expected {expected}")]
    BadValue {
        /// The URDF.
        file: String,
        /// 1-based line of the attribute.
        line: u32,
        /// Element name.
        element: String,
        /// Attribute name.
        attribute: String,
        /// The text found.
        value: String,
        /// What was expected.
        expected: &'static str,
    },
    /// A joint type the URDF format does not define.
    #[error(
        "{file}:{line}: joint '{joint}' has unknown type '{kind}' (expected fixed, revolute, continuous, prismatic, floating or planar)"
    )]
    UnknownJointType {
        /// The URDF.
        file: String,
        /// 1-based line of the joint.
        line: u32,
        /// Joint name.
        joint: String,
        /// The type found.
        kind: String,
    },
    /// A joint type a serial chain cannot use (floating, planar).
    #[error(
        "{file}:{line}: joint '{joint}' is {kind}: only fixed, revolute, continuous and prismatic joints can form the chain"
    )]
    UnsupportedJointType {
        /// The URDF.
        file: String,
        /// 1-based line of the joint.
        line: u32,
        /// Joint name.
        joint: String,
        /// The type found.
        kind: String,
    },
    /// The kinematic tree branches and no tip link was named.
    #[error(
        "{file}: the kinematic tree branches at link '{at}' and no tip link was given; choose the tip among the leaf links: {leaves}"
    )]
    BranchingTree {
        /// The URDF.
        file: String,
        /// The first link with several child joints.
        at: String,
        /// Leaf links, comma separated.
        leaves: String,
    },
    /// A structural URDF problem (unknown link, duplicate name, several roots, bad tip…).
    #[error("{file}:{line}: {message}")]
    Urdf {
        /// The URDF.
        file: String,
        /// 1-based line of the element at fault.
        line: u32,
        /// What is wrong.
        message: String,
    },
    /// A collision mesh referenced by a URDF is missing or unreadable.
    #[error("{file}:{line}: mesh '{mesh}' (resolved to {}): {message}", path.display())]
    MeshFile {
        /// The URDF.
        file: String,
        /// 1-based line of the `<mesh>` element.
        line: u32,
        /// The filename as written in the URDF.
        mesh: String,
        /// Where it was looked for.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// Mesh data that cannot be used (parse failure, bad indices, non-finite vertices).
    #[error("{what}: {message}")]
    MeshData {
        /// The mesh (file or name).
        what: String,
        /// What is wrong.
        message: String,
    },
}

/// A joint value in the user's units: degrees (and radians) for a revolute
/// joint, metres for a prismatic one.
fn show(revolute: bool, v: Real) -> String {
    if revolute {
        format!("{:.4}° ({v:.6} rad)", v.to_degrees())
    } else {
        format!("{v:.6} m")
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn error_stays_small() {
        // Under clippy's result_large_err threshold, so callers' private functions
        // returning Result<_, RobotError> need no boxing.
        assert!(std::mem::size_of::<super::RobotError>() < 128);
    }
}
