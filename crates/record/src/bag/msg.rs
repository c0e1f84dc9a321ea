//! The ROS 2 message types a run's bag holds, as serde structs in the field
//! order of their `.msg` definitions (ROS 2 Humble), with those definitions
//! in `ros2msg` form (the schema text MCAP and rosbag2 store beside each
//! channel). CDR encoding follows the field order, so a struct here and its
//! definition must agree field by field; the tests decode our bags with
//! independent readers (`mcap-ros2-support`, `rosbags`) to check that.

use serde::{Deserialize, Serialize};

/// A ROS 2 message type: its name and its `ros2msg` definition (the type's
/// own fields first, then every type it uses, each after a separator line).
pub trait RosMessage: Serialize {
    /// `package/msg/Type`.
    const TYPE: &'static str;
    /// The `ros2msg` schema text.
    fn definition() -> String;
}

/// `builtin_interfaces/msg/Time`: seconds and nanoseconds since the epoch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Time {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds past `sec`, below 10⁹.
    pub nanosec: u32,
}

impl Time {
    /// The time `ns` nanoseconds after the epoch (seconds saturate at `i32::MAX`).
    pub fn from_nanos(ns: u64) -> Self {
        Self {
            sec: i32::try_from(ns / 1_000_000_000).unwrap_or(i32::MAX),
            nanosec: (ns % 1_000_000_000) as u32,
        }
    }

    /// Nanoseconds since the epoch (`None` before it).
    pub fn to_nanos(self) -> Option<u64> {
        u64::try_from(self.sec)
            .ok()
            .map(|s| s * 1_000_000_000 + u64::from(self.nanosec))
    }
}

/// `builtin_interfaces/msg/Duration`.
pub type Duration = Time;

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// When the data was taken.
    pub stamp: Time,
    /// The frame the data is in.
    pub frame_id: String,
}

impl Header {
    /// A header at `stamp_ns` in `frame`.
    pub fn new(stamp_ns: u64, frame: &str) -> Self {
        Self {
            stamp: Time::from_nanos(stamp_ns),
            frame_id: frame.to_owned(),
        }
    }
}

/// `std_msgs/msg/ColorRGBA`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ColorRgba {
    /// Red, 0–1.
    pub r: f32,
    /// Green, 0–1.
    pub g: f32,
    /// Blue, 0–1.
    pub b: f32,
    /// Opacity, 0–1.
    pub a: f32,
}

/// `geometry_msgs/msg/Vector3` (also the layout of `geometry_msgs/msg/Point`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `geometry_msgs/msg/Point`.
pub type Point = Vector3;

/// `geometry_msgs/msg/Quaternion`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// i part.
    pub x: f64,
    /// j part.
    pub y: f64,
    /// k part.
    pub z: f64,
    /// Real part.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

/// `geometry_msgs/msg/Pose`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

/// `geometry_msgs/msg/Transform`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// Translation.
    pub translation: Vector3,
    /// Rotation.
    pub rotation: Quaternion,
}

impl From<&geom::Isometry3> for Transform {
    fn from(iso: &geom::Isometry3) -> Self {
        let t = iso.translation.vector;
        let q = iso.rotation.coords;
        Self {
            translation: Vector3 {
                x: t.x,
                y: t.y,
                z: t.z,
            },
            rotation: Quaternion {
                x: q.x,
                y: q.y,
                z: q.z,
                w: q.w,
            },
        }
    }
}

impl From<&geom::Isometry3> for Pose {
    fn from(iso: &geom::Isometry3) -> Self {
        let t = Transform::from(iso);
        Self {
            position: t.translation,
            orientation: t.rotation,
        }
    }
}

/// `geometry_msgs/msg/TransformStamped`: `header.frame_id` from `child_frame_id`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TransformStamped {
    /// Stamp and parent frame.
    pub header: Header,
    /// The frame placed.
    pub child_frame_id: String,
    /// `parent_from_child`.
    pub transform: Transform,
}

/// `tf2_msgs/msg/TFMessage` (topics `/tf` and `/tf_static`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TfMessage {
    /// The transforms.
    pub transforms: Vec<TransformStamped>,
}

/// `sensor_msgs/msg/JointState`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointState {
    /// Stamp (frame unused).
    pub header: Header,
    /// Joint names.
    pub name: Vec<String>,
    /// Radians or metres, per name.
    pub position: Vec<f64>,
    /// Per name, or empty.
    pub velocity: Vec<f64>,
    /// Per name, or empty.
    pub effort: Vec<f64>,
}

/// `sensor_msgs/msg/LaserScan`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LaserScan {
    /// Stamp of the first ray and the scanner's frame.
    pub header: Header,
    /// Bearing of the first ray, radians.
    pub angle_min: f32,
    /// Bearing of the last ray, radians.
    pub angle_max: f32,
    /// Between rays, radians.
    pub angle_increment: f32,
    /// Between rays, seconds.
    pub time_increment: f32,
    /// Between scans, seconds.
    pub scan_time: f32,
    /// Shortest range reported, metres.
    pub range_min: f32,
    /// Longest range reported, metres.
    pub range_max: f32,
    /// Per ray, metres; `+inf` without a return (REP 117).
    pub ranges: Vec<f32>,
    /// Per ray.
    pub intensities: Vec<f32>,
}

/// `sensor_msgs/msg/PointField`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointField {
    /// Field name (`x`, `intensity` …).
    pub name: String,
    /// Byte offset in a point.
    pub offset: u32,
    /// [`PointField::FLOAT32`] and the like.
    pub datatype: u8,
    /// Elements in the field.
    pub count: u32,
}

impl PointField {
    /// `datatype` of a 32-bit float.
    pub const FLOAT32: u8 = 7;
}

/// `sensor_msgs/msg/PointCloud2`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointCloud2 {
    /// Stamp and frame.
    pub header: Header,
    /// Rows (1 for an unordered cloud).
    pub height: u32,
    /// Points per row.
    pub width: u32,
    /// Layout of a point.
    pub fields: Vec<PointField>,
    /// Byte order of `data`.
    pub is_bigendian: bool,
    /// Bytes per point.
    pub point_step: u32,
    /// Bytes per row.
    pub row_step: u32,
    /// The points.
    pub data: Vec<u8>,
    /// No invalid points.
    pub is_dense: bool,
}

/// `sensor_msgs/msg/Range` (ROS 2 Humble: no `variance`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Range {
    /// Stamp and the range finder's frame.
    pub header: Header,
    /// [`Range::INFRARED`] or ultrasound (0).
    pub radiation_type: u8,
    /// Cone angle, radians.
    pub field_of_view: f32,
    /// Shortest range, metres.
    pub min_range: f32,
    /// Longest range, metres.
    pub max_range: f32,
    /// Metres; `+inf` when nothing is in range (REP 117).
    pub range: f32,
}

impl Range {
    /// An infrared (optical) range finder.
    pub const INFRARED: u8 = 1;
}

/// `sensor_msgs/msg/CompressedImage` (inside a [`Marker`]; empty there).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CompressedImage {
    /// Stamp and frame.
    pub header: Header,
    /// Image format.
    pub format: String,
    /// Image bytes.
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/UVCoordinate`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct UvCoordinate {
    /// u.
    pub u: f32,
    /// v.
    pub v: f32,
}

/// `visualization_msgs/msg/MeshFile`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshFile {
    /// File name.
    pub filename: String,
    /// File bytes.
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/Marker` (ROS 2 Humble's fields).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    /// Stamp and frame.
    pub header: Header,
    /// Namespace.
    pub ns: String,
    /// Id within the namespace.
    pub id: i32,
    /// [`Marker::ARROW`] and the like.
    #[serde(rename = "type")]
    pub kind: i32,
    /// 0: add or modify.
    pub action: i32,
    /// Pose of the shape.
    pub pose: Pose,
    /// Size of the shape.
    pub scale: Vector3,
    /// Colour of the shape.
    pub color: ColorRgba,
    /// 0: forever.
    pub lifetime: Duration,
    /// Re-framed every update.
    pub frame_locked: bool,
    /// Points of list shapes.
    pub points: Vec<Point>,
    /// Per point colours.
    pub colors: Vec<ColorRgba>,
    /// Unused.
    pub texture_resource: String,
    /// Unused.
    pub texture: CompressedImage,
    /// Unused.
    pub uv_coordinates: Vec<UvCoordinate>,
    /// Text of text markers.
    pub text: String,
    /// Unused.
    pub mesh_resource: String,
    /// Unused.
    pub mesh_file: MeshFile,
    /// Unused.
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    /// An arrow along the pose's x axis.
    pub const ARROW: i32 = 0;
    /// A cylinder along the pose's z axis.
    pub const CYLINDER: i32 = 3;
    /// Line segments, two points each.
    pub const LINE_LIST: i32 = 5;
    /// Points.
    pub const POINTS: i32 = 8;
    /// Triangles, three points each.
    pub const TRIANGLE_LIST: i32 = 11;
}

/// `rosgraph_msgs/msg/Clock`: the time of a robot or a simulator on
/// `/clock`, which nodes with `use_sim_time` follow instead of their own
/// clock.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Clock {
    /// The robot's time now.
    pub clock: Time,
}

impl RosMessage for Clock {
    const TYPE: &'static str = "rosgraph_msgs/msg/Clock";
    fn definition() -> String {
        with_dependencies("builtin_interfaces/Time clock\n", &[D_TIME])
    }
}

/// `std_msgs/msg/String`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StdString {
    /// The text.
    pub data: String,
}

impl RosMessage for StdString {
    const TYPE: &'static str = "std_msgs/msg/String";
    fn definition() -> String {
        "string data\n".to_owned()
    }
}

/// `std_msgs/msg/MultiArrayDimension`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct MultiArrayDimension {
    /// Name of the dimension.
    pub label: String,
    /// Its size.
    pub size: u32,
    /// Its stride.
    pub stride: u32,
}

/// `std_msgs/msg/MultiArrayLayout`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct MultiArrayLayout {
    /// The dimensions (none: a flat array).
    pub dim: Vec<MultiArrayDimension>,
    /// Padding before the data.
    pub data_offset: u32,
}

/// `std_msgs/msg/Float64MultiArray`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Float64MultiArray {
    /// How `data` is laid out.
    pub layout: MultiArrayLayout,
    /// The values.
    pub data: Vec<f64>,
}

impl RosMessage for Float64MultiArray {
    const TYPE: &'static str = "std_msgs/msg/Float64MultiArray";
    fn definition() -> String {
        with_dependencies(
            "std_msgs/MultiArrayLayout layout\nfloat64[] data\n",
            &[
                (
                    "std_msgs/MultiArrayLayout",
                    "std_msgs/MultiArrayDimension[] dim\nuint32 data_offset\n",
                ),
                (
                    "std_msgs/MultiArrayDimension",
                    "string label\nuint32 size\nuint32 stride\n",
                ),
            ],
        )
    }
}

/// `trajectory_msgs/msg/JointTrajectoryPoint`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointTrajectoryPoint {
    /// Joint values, in `joint_names` order.
    pub positions: Vec<f64>,
    /// Per joint, or empty.
    pub velocities: Vec<f64>,
    /// Per joint, or empty.
    pub accelerations: Vec<f64>,
    /// Per joint, or empty.
    pub effort: Vec<f64>,
    /// When the point is to be reached, from the trajectory's start.
    pub time_from_start: Duration,
}

/// `trajectory_msgs/msg/JointTrajectory`: what a `ros2_control` joint
/// trajectory controller executes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointTrajectory {
    /// Stamp (zero: start now).
    pub header: Header,
    /// The joints the points give values for.
    pub joint_names: Vec<String>,
    /// The points, in time order.
    pub points: Vec<JointTrajectoryPoint>,
}

/// `visualization_msgs/msg/MarkerArray`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MarkerArray {
    /// The markers.
    pub markers: Vec<Marker>,
}

// The `.msg` texts: each type's own fields, with full type names.
const TIME: &str = "int32 sec\nuint32 nanosec\n";
const HEADER: &str = "builtin_interfaces/Time stamp\nstring frame_id\n";
const COLOR: &str = "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n";
const XYZ: &str = "float64 x\nfloat64 y\nfloat64 z\n";
const QUATERNION: &str = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n";
const POSE: &str = "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n";
const TRANSFORM: &str = "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n";
const TRANSFORM_STAMPED: &str =
    "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n";
const POINT_FIELD: &str = "uint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\n\
uint8 UINT32=6\nuint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count\n";
const COMPRESSED_IMAGE: &str = "std_msgs/Header header\nstring format\nuint8[] data\n";
const UV: &str = "float32 u\nfloat32 v\n";
const MESH_FILE: &str = "string filename\nuint8[] data\n";
const MARKER: &str = "int32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\n\
int32 LINE_STRIP=4\nint32 LINE_LIST=5\nint32 CUBE_LIST=6\nint32 SPHERE_LIST=7\nint32 POINTS=8\n\
int32 TEXT_VIEW_FACING=9\nint32 MESH_RESOURCE=10\nint32 TRIANGLE_LIST=11\nint32 ADD=0\n\
int32 MODIFY=0\nint32 DELETE=2\nint32 DELETEALL=3\n\
std_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\n\
geometry_msgs/Pose pose\ngeometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\n\
builtin_interfaces/Duration lifetime\nbool frame_locked\ngeometry_msgs/Point[] points\n\
std_msgs/ColorRGBA[] colors\nstring texture_resource\nsensor_msgs/CompressedImage texture\n\
visualization_msgs/UVCoordinate[] uv_coordinates\nstring text\nstring mesh_resource\n\
visualization_msgs/MeshFile mesh_file\nbool mesh_use_embedded_materials\n";

/// A definition: `main`, then each `(name, text)` dependency after the
/// separator rosbag2 writes.
fn with_dependencies(main: &str, deps: &[(&str, &str)]) -> String {
    let mut text = main.to_owned();
    for (name, body) in deps {
        text.push_str(&"=".repeat(80));
        text.push_str("\nMSG: ");
        text.push_str(name);
        text.push('\n');
        text.push_str(body);
    }
    text
}

const D_TIME: (&str, &str) = ("builtin_interfaces/Time", TIME);
const D_DURATION: (&str, &str) = ("builtin_interfaces/Duration", TIME);
const D_HEADER: (&str, &str) = ("std_msgs/Header", HEADER);
const D_COLOR: (&str, &str) = ("std_msgs/ColorRGBA", COLOR);
const D_VECTOR3: (&str, &str) = ("geometry_msgs/Vector3", XYZ);
const D_POINT: (&str, &str) = ("geometry_msgs/Point", XYZ);
const D_QUATERNION: (&str, &str) = ("geometry_msgs/Quaternion", QUATERNION);

impl RosMessage for JointState {
    const TYPE: &'static str = "sensor_msgs/msg/JointState";
    fn definition() -> String {
        with_dependencies(
            "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n",
            &[D_HEADER, D_TIME],
        )
    }
}

impl RosMessage for LaserScan {
    const TYPE: &'static str = "sensor_msgs/msg/LaserScan";
    fn definition() -> String {
        with_dependencies(
            "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\n\
float32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\n\
float32[] ranges\nfloat32[] intensities\n",
            &[D_HEADER, D_TIME],
        )
    }
}

impl RosMessage for PointCloud2 {
    const TYPE: &'static str = "sensor_msgs/msg/PointCloud2";
    fn definition() -> String {
        with_dependencies(
            "std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\n\
bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n",
            &[D_HEADER, D_TIME, ("sensor_msgs/PointField", POINT_FIELD)],
        )
    }
}

impl RosMessage for Range {
    const TYPE: &'static str = "sensor_msgs/msg/Range";
    fn definition() -> String {
        with_dependencies(
            "uint8 ULTRASOUND=0\nuint8 INFRARED=1\nstd_msgs/Header header\nuint8 radiation_type\n\
float32 field_of_view\nfloat32 min_range\nfloat32 max_range\nfloat32 range\n",
            &[D_HEADER, D_TIME],
        )
    }
}

impl RosMessage for TfMessage {
    const TYPE: &'static str = "tf2_msgs/msg/TFMessage";
    fn definition() -> String {
        with_dependencies(
            "geometry_msgs/TransformStamped[] transforms\n",
            &[
                ("geometry_msgs/TransformStamped", TRANSFORM_STAMPED),
                D_HEADER,
                D_TIME,
                ("geometry_msgs/Transform", TRANSFORM),
                D_VECTOR3,
                D_QUATERNION,
            ],
        )
    }
}

impl RosMessage for JointTrajectory {
    const TYPE: &'static str = "trajectory_msgs/msg/JointTrajectory";
    fn definition() -> String {
        with_dependencies(
            "std_msgs/Header header\nstring[] joint_names\ntrajectory_msgs/JointTrajectoryPoint[] points\n",
            &[
                D_HEADER,
                D_TIME,
                (
                    "trajectory_msgs/JointTrajectoryPoint",
                    "float64[] positions\nfloat64[] velocities\nfloat64[] accelerations\n\
float64[] effort\nbuiltin_interfaces/Duration time_from_start\n",
                ),
                D_DURATION,
            ],
        )
    }
}

impl RosMessage for MarkerArray {
    const TYPE: &'static str = "visualization_msgs/msg/MarkerArray";
    fn definition() -> String {
        with_dependencies(
            "visualization_msgs/Marker[] markers\n",
            &[
                ("visualization_msgs/Marker", MARKER),
                D_HEADER,
                D_TIME,
                ("geometry_msgs/Pose", POSE),
                D_POINT,
                D_QUATERNION,
                D_VECTOR3,
                D_COLOR,
                D_DURATION,
                ("sensor_msgs/CompressedImage", COMPRESSED_IMAGE),
                ("visualization_msgs/UVCoordinate", UV),
                ("visualization_msgs/MeshFile", MESH_FILE),
            ],
        )
    }
}
