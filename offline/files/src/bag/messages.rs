//! The ROS 2 messages `prf import-bag` reads, as their CDR layout (field order and types of
//! the `.msg` definitions; fixed arrays are unprefixed, sequences and strings have a u32
//! length), decoded with `cdr-encoding`.

use serde::{Deserialize, Serialize};

/// Schema names as rosbag2 records them.
pub const JOINT_STATE: &str = "sensor_msgs/msg/JointState";
pub const ODOMETRY: &str = "nav_msgs/msg/Odometry";
pub const TF_MESSAGE: &str = "tf2_msgs/msg/TFMessage";

/// `builtin_interfaces/msg/Time`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
pub struct Time {
    pub sec: i32,
    pub nanosec: u32,
}

impl Time {
    /// Nanoseconds since the epoch.
    pub fn ns(&self) -> i64 {
        self.sec as i64 * 1_000_000_000 + self.nanosec as i64
    }
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Header {
    pub stamp: Time,
    pub frame_id: String,
}

/// `sensor_msgs/msg/JointState`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct JointState {
    pub header: Header,
    pub name: Vec<String>,
    pub position: Vec<f64>,
    pub velocity: Vec<f64>,
    pub effort: Vec<f64>,
}

/// `geometry_msgs/msg/Point` and `Vector3` (the same layout).
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
pub struct Xyz {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

impl Quaternion {
    /// Rotation about the vertical axis, rad.
    pub fn yaw(&self) -> f64 {
        let (x, y, z, w) = (self.x, self.y, self.z, self.w);
        (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
    }
}

/// `geometry_msgs/msg/Pose`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
pub struct Pose {
    pub position: Xyz,
    pub orientation: Quaternion,
}

/// `float64[36]` row-major covariance.
type Covariance = [[f64; 6]; 6];

/// `geometry_msgs/msg/PoseWithCovariance`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
pub struct PoseWithCovariance {
    pub pose: Pose,
    pub covariance: Covariance,
}

/// `geometry_msgs/msg/Twist`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
pub struct Twist {
    pub linear: Xyz,
    pub angular: Xyz,
}

/// `geometry_msgs/msg/TwistWithCovariance`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
pub struct TwistWithCovariance {
    pub twist: Twist,
    pub covariance: Covariance,
}

/// `nav_msgs/msg/Odometry`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Odometry {
    pub header: Header,
    pub child_frame_id: String,
    pub pose: PoseWithCovariance,
    pub twist: TwistWithCovariance,
}

/// `geometry_msgs/msg/Transform`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
pub struct Transform {
    pub translation: Xyz,
    pub rotation: Quaternion,
}

/// `geometry_msgs/msg/TransformStamped`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct TransformStamped {
    pub header: Header,
    pub child_frame_id: String,
    pub transform: Transform,
}

/// `tf2_msgs/msg/TFMessage`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct TfMessage {
    pub transforms: Vec<TransformStamped>,
}

// ---- messages `prf export-mcap` writes (the readers above are used too) ----

/// `std_msgs/msg/String`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct StringMsg {
    pub data: String,
}

/// `std_msgs/msg/Float64`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
pub struct Float64 {
    pub data: f64,
}

/// `std_msgs/msg/ColorRGBA`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
pub struct ColorRgba {
    pub r: f32,
    pub g: f32,
    pub b: f32,
    pub a: f32,
}

/// `builtin_interfaces/msg/Duration`.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize)]
pub struct RosDuration {
    pub sec: i32,
    pub nanosec: u32,
}

/// `sensor_msgs/msg/PointField`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct PointField {
    pub name: String,
    pub offset: u32,
    pub datatype: u8,
    pub count: u32,
}

/// `sensor_msgs/msg/PointField` datatype of a float32.
pub const FLOAT32: u8 = 7;

/// `sensor_msgs/msg/PointCloud2`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct PointCloud2 {
    pub header: Header,
    pub height: u32,
    pub width: u32,
    pub fields: Vec<PointField>,
    pub is_bigendian: bool,
    pub point_step: u32,
    pub row_step: u32,
    pub data: Vec<u8>,
    pub is_dense: bool,
}

/// `sensor_msgs/msg/CompressedImage` (a marker's texture; empty here).
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct CompressedImage {
    pub header: Header,
    pub format: String,
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/UVCoordinate`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
pub struct UvCoordinate {
    pub u: f32,
    pub v: f32,
}

/// `visualization_msgs/msg/MeshFile`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct MeshFile {
    pub filename: String,
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/Marker` (ROS 2 Humble and later).
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Marker {
    pub header: Header,
    pub ns: String,
    pub id: i32,
    #[serde(rename = "type")]
    pub kind: i32,
    pub action: i32,
    pub pose: Pose,
    pub scale: Xyz,
    pub color: ColorRgba,
    pub lifetime: RosDuration,
    pub frame_locked: bool,
    pub points: Vec<Xyz>,
    pub colors: Vec<ColorRgba>,
    pub texture_resource: String,
    pub texture: CompressedImage,
    pub uv_coordinates: Vec<UvCoordinate>,
    pub text: String,
    pub mesh_resource: String,
    pub mesh_file: MeshFile,
    pub mesh_use_embedded_materials: bool,
}

/// Marker types and actions used.
pub const ARROW: i32 = 0;
pub const CUBE: i32 = 1;
pub const SPHERE: i32 = 2;
pub const ADD: i32 = 0;

/// `visualization_msgs/msg/MarkerArray`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct MarkerArray {
    pub markers: Vec<Marker>,
}

pub const STRING: &str = "std_msgs/msg/String";
pub const FLOAT64: &str = "std_msgs/msg/Float64";
pub const POINT_CLOUD2: &str = "sensor_msgs/msg/PointCloud2";
pub const MARKER_ARRAY: &str = "visualization_msgs/msg/MarkerArray";

/// The `.msg` definition of `schema` as rosbag2 stores it (`ros2msg`: the message, then each
/// message it uses after a line of 80 `=` and `MSG: <name>`), for the schemas written here.
pub fn definition(schema: &str) -> Option<String> {
    const TIME: &str = "builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n";
    const HEADER: &str = "std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n";
    const VECTOR3: &str = "geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";
    const POINT: &str = "geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n";
    const QUATERNION: &str =
        "geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n";
    const POSE: &str = "geometry_msgs/Pose\nPoint position\nQuaternion orientation\n";
    const COLOR: &str = "std_msgs/ColorRGBA\nfloat32 r\nfloat32 g\nfloat32 b\nfloat32 a\n";
    let (main, deps): (&str, &[&str]) = match schema {
        STRING => ("string data\n", &[]),
        FLOAT64 => ("float64 data\n", &[]),
        JOINT_STATE => (
            "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n",
            &[HEADER, TIME],
        ),
        TF_MESSAGE => (
            "geometry_msgs/TransformStamped[] transforms\n",
            &[
                "geometry_msgs/TransformStamped\nstd_msgs/Header header\nstring child_frame_id\nTransform transform\n",
                HEADER,
                TIME,
                "geometry_msgs/Transform\nVector3 translation\nQuaternion rotation\n",
                VECTOR3,
                QUATERNION,
            ],
        ),
        POINT_CLOUD2 => (
            "std_msgs/Header header\nuint32 height\nuint32 width\nPointField[] fields\nbool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n",
            &[
                HEADER,
                TIME,
                "sensor_msgs/PointField\nuint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\nuint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count\n",
            ],
        ),
        MARKER_ARRAY => (
            "Marker[] markers\n",
            &[
                "visualization_msgs/Marker\nint32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\nint32 LINE_STRIP=4\nint32 LINE_LIST=5\nint32 CUBE_LIST=6\nint32 SPHERE_LIST=7\nint32 POINTS=8\nint32 TEXT_VIEW_FACING=9\nint32 MESH_RESOURCE=10\nint32 TRIANGLE_LIST=11\nint32 ADD=0\nint32 MODIFY=0\nint32 DELETE=2\nint32 DELETEALL=3\nstd_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\ngeometry_msgs/Pose pose\ngeometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\nbuiltin_interfaces/Duration lifetime\nbool frame_locked\ngeometry_msgs/Point[] points\nstd_msgs/ColorRGBA[] colors\nstring texture_resource\nsensor_msgs/CompressedImage texture\nUVCoordinate[] uv_coordinates\nstring text\nstring mesh_resource\nMeshFile mesh_file\nbool mesh_use_embedded_materials\n",
                HEADER,
                TIME,
                POSE,
                POINT,
                QUATERNION,
                VECTOR3,
                COLOR,
                "builtin_interfaces/Duration\nint32 sec\nuint32 nanosec\n",
                "sensor_msgs/CompressedImage\nstd_msgs/Header header\nstring format\nuint8[] data\n",
                "visualization_msgs/UVCoordinate\nfloat32 u\nfloat32 v\n",
                "visualization_msgs/MeshFile\nstring filename\nuint8[] data\n",
            ],
        ),
        _ => return None,
    };
    let mut text = main.to_string();
    for d in deps {
        text.push_str(&"=".repeat(80));
        text.push_str("\nMSG: ");
        text.push_str(d);
    }
    Some(text)
}
