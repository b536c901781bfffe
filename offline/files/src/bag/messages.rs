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
