//! The robot model as plain data: fixed joint transforms, axes, limits, collision spheres.
//!
//! A later tool fills [`RobotModel`] from a URDF plus a sphere file; [`RobotModel::kmr_iiwa14`]
//! is the built-in default, a KUKA KMR iiwa: KMP 200 platform with an LBR iiwa 14 R820 and a
//! parallel gripper. Frames (DESIGN.md): base `b` on the floor under the platform centre, arm
//! base (URDF `link_0`) on the platform deck, links 1..7, flange, TCP `e`.

use crate::NA;
use crate::se3::{Pose, pose_from_xyz_rpy};
use nalgebra::{Unit, Vector3};

/// Maximum number of collision spheres of a model.
pub const MAX_SPHERES: usize = 48;

/// Index of the arm base frame (URDF `link_0`) in link-indexed data.
pub const LINK_ARM_BASE: usize = 0;
/// Index of the tool frame (the flange; the gripper is rigidly attached to it).
pub const LINK_TOOL: usize = NA + 1;
/// Number of frames returned by forward kinematics: arm base, links 1..=7, tool (flange).
pub const N_FRAMES: usize = NA + 2;

/// What is wrong with a robot model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelError {
    /// Non-finite origin or axis, lower ≥ upper, or a non-positive speed limit.
    Joint {
        /// The joint, 0-based.
        joint: usize,
    },
    /// Non-finite mount, flange or TCP transform.
    Transform,
    /// Sphere `index` names a frame that does not exist or has a bad centre or radius.
    Sphere {
        /// The sphere's index.
        index: usize,
    },
    /// The sphere margin is negative or not finite.
    SphereMargin,
    /// The home configuration is outside the limits of `joint`.
    Home {
        /// The joint, 0-based.
        joint: usize,
    },
}

impl core::fmt::Display for ModelError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ModelError::Joint { joint } => write!(
                f,
                "joint A{}: non-finite origin or axis, lower limit not below upper, or speed limit not positive",
                joint + 1
            ),
            ModelError::Transform => write!(f, "the mount, flange or TCP transform is not finite"),
            ModelError::Sphere { index } => write!(
                f,
                "collision sphere {index} names no frame of the robot or has a bad centre or radius"
            ),
            ModelError::SphereMargin => {
                write!(f, "the sphere margin is negative or not finite")
            }
            ModelError::Home { joint } => write!(
                f,
                "the home configuration is outside the limits of joint A{}",
                joint + 1
            ),
        }
    }
}

impl core::error::Error for ModelError {}

/// One revolute joint: `T_i^{i−1} = origin · Rot(axis, q_i)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Joint {
    /// Fixed transform of the joint frame in the parent link frame (URDF `<origin>`).
    pub origin: Pose,
    /// Rotation axis in the joint frame (URDF `<axis>`).
    pub axis: Unit<Vector3<f64>>,
    /// Position limits, rad.
    pub lower: f64,
    /// Upper position limit, rad.
    pub upper: f64,
    /// Speed limit, rad/s.
    pub max_speed: f64,
}

impl Joint {
    /// A placeholder to fill in (identity origin, z axis, zero limits): not a valid joint.
    pub fn unset() -> Joint {
        Joint {
            origin: Pose::identity(),
            axis: Vector3::z_axis(),
            lower: 0.0,
            upper: 0.0,
            max_speed: 0.0,
        }
    }
}

/// A collision sphere rigidly attached to one frame (see [`LINK_ARM_BASE`], [`LINK_TOOL`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Frame index: 0 = arm base, 1..=7 = links, 8 = tool (flange).
    pub link: u8,
    /// Centre in that frame, m.
    pub centre: Vector3<f64>,
    /// Radius, m.
    pub radius: f64,
}

/// The mobile platform's body as an axis-aligned box in the base frame `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlatformBox {
    /// Box centre in the base frame, m.
    pub centre: Vector3<f64>,
    /// Box half extents, m.
    pub half_extents: Vector3<f64>,
}

/// Kinematic and collision model of a mobile manipulator with a 7-axis arm.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotModel {
    /// Arm base (URDF `link_0`) in the platform base frame `b`.
    pub mount: Pose,
    /// The seven arm joints, base to flange.
    pub joints: [Joint; NA],
    /// Flange in the frame of link 7.
    pub flange: Pose,
    /// TCP `e` in the flange frame.
    pub tcp: Pose,
    /// Conservative collision geometry: every point of the real link surface lies inside the
    /// union of the spheres of its link. Sphere centres are the risk control points.
    pub spheres: heapless::Vec<Sphere, MAX_SPHERES>,
    /// The platform body.
    pub platform: PlatformBox,
    /// Home configuration q_a,H of the arm.
    pub home: [f64; NA],
    /// How far at least every sphere reaches beyond the link surface it covers, m (the
    /// fit's margin; 0 when the robot file does not state it).
    pub sphere_margin: f64,
}

/// LBR iiwa 14 R820 joint origins (URDF: xyz, rpy), all axes z.
const IIWA14_JOINTS: [([f64; 3], [f64; 3]); NA] = {
    use core::f64::consts::{FRAC_PI_2 as H, PI};
    [
        ([0.0, 0.0, 0.1575], [0.0, 0.0, 0.0]),
        ([0.0, 0.0, 0.2025], [H, 0.0, PI]),
        ([0.0, 0.2045, 0.0], [H, 0.0, PI]),
        ([0.0, 0.0, 0.2155], [H, 0.0, 0.0]),
        ([0.0, 0.1845, 0.0], [-H, PI, 0.0]),
        ([0.0, 0.0, 0.2155], [H, 0.0, 0.0]),
        ([0.0, 0.081, 0.0], [-H, PI, 0.0]),
    ]
};
/// Position limits ±deg and speed limits deg/s of the iiwa 14 R820.
const IIWA14_LIMIT_DEG: [f64; NA] = [170.0, 120.0, 170.0, 120.0, 170.0, 120.0, 175.0];
const IIWA14_SPEED_DEG: [f64; NA] = [85.0, 85.0, 100.0, 75.0, 130.0, 135.0, 135.0];

/// The margin `tools/fit_spheres.py` adds to every fitted radius, m.
const IIWA14_SPHERE_MARGIN: f64 = 0.002;

/// Collision spheres (frame, centre, radius), m. Links 0..=7 (36 spheres) were fitted to the
/// iiwa 14 STL meshes by `tools/fit_spheres.py`: every triangle inside one sphere, 2 mm margin
/// (verified by the test `spheres_cover_meshes`), each link's union reaching at most 16–48 mm
/// beyond its body (the link, what its neighbours occupy at every joint angle, and the deck;
/// 36–77 mm with the earlier fit of 21). Frame 8 covers the project's parallel gripper envelope:
/// body cylinder r = 0.045, z ∈ [0, 0.09], and two fingers 0.015 × 0.024 × 0.07 at x = ±0.0375,
/// z ∈ [0.09, 0.16] (flange frame).
#[rustfmt::skip]
const IIWA14_SPHERES: [(u8, [f64; 3], f64); 42] = [
    (0, [-0.005, 0.002, 0.051], 0.143), (0, [-0.076, 0.001, 0.076], 0.104),
    (0, [-0.068, 0.007, 0.045], 0.108),
    (1, [0.003, -0.026, 0.195], 0.100), (1, [0.003, -0.009, 0.006], 0.100),
    (1, [0.003, -0.045, 0.101], 0.078), (1, [0.000, -0.033, 0.066], 0.080),
    (1, [0.005, -0.049, 0.149], 0.083),
    (2, [0.001, 0.018, 0.039], 0.103), (2, [-0.001, 0.186, 0.008], 0.084),
    (2, [-0.002, 0.105, 0.041], 0.079), (2, [-0.003, -0.008, 0.042], 0.099),
    (2, [0.016, 0.151, 0.014], 0.063),
    (3, [-0.002, 0.032, 0.198], 0.088), (3, [0.000, 0.009, 0.049], 0.089),
    (3, [-0.002, 0.046, 0.133], 0.075), (3, [-0.004, 0.029, 0.222], 0.084),
    (3, [0.004, -0.019, 0.014], 0.072),
    (4, [-0.001, 0.008, 0.041], 0.087), (4, [-0.006, 0.153, 0.011], 0.080),
    (4, [-0.002, 0.088, 0.044], 0.075), (4, [0.006, 0.171, -0.014], 0.075),
    (4, [0.004, -0.011, 0.000], 0.075),
    (5, [-0.003, 0.008, 0.037], 0.091), (5, [0.009, 0.061, 0.192], 0.068),
    (5, [0.002, 0.058, 0.125], 0.059), (5, [-0.011, 0.069, 0.238], 0.051),
    (5, [0.037, 0.060, 0.231], 0.037),
    (6, [0.000, 0.028, -0.002], 0.078), (6, [0.003, -0.014, 0.006], 0.078),
    (6, [-0.003, -0.008, -0.042], 0.066), (6, [0.003, -0.037, 0.020], 0.061),
    (7, [-0.004, -0.003, -0.003], 0.059), (7, [0.009, 0.008, 0.006], 0.051),
    (7, [-0.011, 0.017, 0.006], 0.043), (7, [0.008, -0.014, 0.020], 0.039),
    (8, [0.0, 0.0, 0.0225], 0.051), (8, [0.0, 0.0, 0.0675], 0.051),
    (8, [0.0375, 0.0, 0.1075], 0.023), (8, [0.0375, 0.0, 0.1425], 0.023),
    (8, [-0.0375, 0.0, 0.1075], 0.023), (8, [-0.0375, 0.0, 0.1425], 0.023),
];

impl RobotModel {
    /// The built-in KMR iiwa with an LBR iiwa 14 R820 and a parallel gripper.
    ///
    /// Project choices (not vendor data): arm mounted at (0.33, 0, 0.70) on the KMP 200 deck
    /// (box 1.08 × 0.63 × 0.70 m), flange 0.045 m beyond joint 7, TCP 0.15 m beyond the flange
    /// between the finger pads, home q_a,H folded over the platform.
    pub fn kmr_iiwa14() -> Self {
        let joints = core::array::from_fn(|i| {
            let (xyz, rpy) = IIWA14_JOINTS[i];
            Joint {
                origin: pose_from_xyz_rpy(xyz, rpy),
                axis: Vector3::z_axis(),
                lower: -IIWA14_LIMIT_DEG[i].to_radians(),
                upper: IIWA14_LIMIT_DEG[i].to_radians(),
                max_speed: IIWA14_SPEED_DEG[i].to_radians(),
            }
        });
        let mut spheres = heapless::Vec::new();
        for &(link, c, radius) in &IIWA14_SPHERES {
            // Capacity 48 > 42 entries: cannot fail.
            let _ = spheres.push(Sphere {
                link,
                centre: Vector3::new(c[0], c[1], c[2]),
                radius,
            });
        }
        let home_deg = [0.0, -60.0, 0.0, -110.0, 0.0, 90.0, 0.0];
        RobotModel {
            mount: pose_from_xyz_rpy([0.33, 0.0, 0.70], [0.0; 3]),
            joints,
            flange: pose_from_xyz_rpy([0.0, 0.0, 0.045], [0.0; 3]),
            tcp: pose_from_xyz_rpy([0.0, 0.0, 0.15], [0.0; 3]),
            spheres,
            platform: PlatformBox {
                centre: Vector3::new(0.0, 0.0, 0.35),
                half_extents: Vector3::new(0.54, 0.315, 0.35),
            },
            home: home_deg.map(|d: f64| d.to_radians()),
            sphere_margin: IIWA14_SPHERE_MARGIN,
        }
    }

    /// Checks the data a URDF or blob may get wrong: finite transforms, ordered limits,
    /// positive speeds, sphere frames that exist and positive finite radii.
    pub fn validate(&self) -> Result<(), ModelError> {
        let finite_pose = |p: &Pose| {
            p.translation
                .vector
                .iter()
                .chain(p.rotation.coords.iter())
                .all(|v| v.is_finite())
        };
        for (i, j) in self.joints.iter().enumerate() {
            let ok = finite_pose(&j.origin)
                && j.axis.iter().all(|v| v.is_finite())
                && j.lower < j.upper
                && j.max_speed > 0.0
                && j.max_speed.is_finite();
            if !ok {
                return Err(ModelError::Joint { joint: i });
            }
        }
        if !(finite_pose(&self.mount) && finite_pose(&self.flange) && finite_pose(&self.tcp)) {
            return Err(ModelError::Transform);
        }
        if !(self.sphere_margin >= 0.0 && self.sphere_margin.is_finite()) {
            return Err(ModelError::SphereMargin);
        }
        for (i, s) in self.spheres.iter().enumerate() {
            let ok = (s.link as usize) < N_FRAMES
                && s.centre.iter().all(|v| v.is_finite())
                && s.radius > 0.0
                && s.radius.is_finite();
            if !ok {
                return Err(ModelError::Sphere { index: i });
            }
        }
        match self.limit_violation(&self.home) {
            Some((joint, _)) => Err(ModelError::Home { joint }),
            None => Ok(()),
        }
    }

    /// First joint whose value is outside its position limits, with the value.
    pub fn limit_violation(&self, q: &[f64; NA]) -> Option<(usize, f64)> {
        self.joints
            .iter()
            .zip(q)
            .position(|(j, &v)| !(v >= j.lower && v <= j.upper))
            .map(|i| (i, q[i]))
    }
}
