//! Forward kinematics, TCP pose and the geometric Jacobian: the one home of FK.
//!
//! Arm quantities are expressed in the arm base frame (URDF `link_0`), as the paper's
//! T_e^b = F_a(q_a); [`platform_pose`] gives T_b = F_m(q_m) and [`arm_base_pose`] chains both.

mod chain;
mod frame;
pub mod quaternion;

pub use chain::{Chain, PERMUTATION_TOLERANCE};
pub use frame::{Frame, quaternion_of};

use crate::robot::{LINK_TOOL, N_FRAMES, RobotModel, Sphere};
use crate::se3::Pose;
use crate::{Jacobian, JointVector, NA};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};

/// Everything one kinematics evaluation yields at a configuration q_a.
#[derive(Clone, Copy, Debug)]
pub struct ArmKinematics {
    /// Frames in the arm base frame: 0 = arm base (identity), 1..=7 = links, 8 = flange.
    pub frames: [Frame; N_FRAMES],
    /// TCP pose T_e in the arm base frame.
    pub tcp: Pose,
}

impl ArmKinematics {
    /// Every frame and the TCP at the arm base: a place for [`Chain::kinematics_into`].
    pub fn identity() -> ArmKinematics {
        ArmKinematics {
            frames: [Frame::identity(); N_FRAMES],
            tcp: Pose::identity(),
        }
    }

    /// Forward kinematics of `model` at q: [`Chain::kinematics`] of the model's chain. A
    /// caller that evaluates many configurations builds the [`Chain`] once and calls that.
    pub fn new(model: &RobotModel, q: &JointVector) -> Self {
        Chain::new(model).kinematics(model, q)
    }

    /// Geometric Jacobian of the TCP, 6×7, rows [v; ω] in the arm base frame:
    /// column i = [z_i × (p_e − p_i); z_i], z_i the axis of joint i (a column of frame i + 1).
    pub fn jacobian(&self, model: &RobotModel) -> Jacobian {
        let pe = self.tcp.translation.vector;
        let mut j = Jacobian::zeros();
        for (i, joint) in model.joints.iter().enumerate() {
            let f = &self.frames[i + 1];
            let z = joint_axis(f, &joint.axis, is_z(&joint.axis));
            column_into(&mut j, i, &z, &pe, &f.origin);
        }
        j
    }

    /// Centres of the model's collision spheres in the arm base frame, written to `out`
    /// (which should hold `model.spheres.len()` entries; extra entries are left untouched).
    /// A sphere on a frame that does not exist (see [`RobotModel::validate`]) is skipped.
    pub fn sphere_centres(&self, model: &RobotModel, out: &mut [Vector3<f64>]) {
        for (s, o) in model.spheres.iter().zip(out.iter_mut()) {
            if let Some(frame) = self.frames.get(s.link as usize) {
                *o = frame.transform_point(&s.centre);
            }
        }
    }

    /// Centres of the collision spheres in the frame where the arm base is at `base`
    /// (`base · frame · centre`), written to `out` like [`ArmKinematics::sphere_centres`].
    /// Each frame is composed once, not once per sphere.
    pub fn sphere_centres_in(&self, model: &RobotModel, base: &Pose, out: &mut [Vector3<f64>]) {
        let mut frames = FramesIn::new(self, base);
        for (s, o) in model.spheres.iter().zip(out.iter_mut()) {
            if let Some(p) = frames.point(s.link as usize, &s.centre) {
                *o = p;
            }
        }
    }
}

impl Chain {
    /// Forward kinematics: T_i = T_{i−1} · origin_i · Rot(axis_i, q_i) as rotation matrices
    /// (see [`Frame`]), then the flange and the TCP; the TCP's rotation as a quaternion
    /// ([`quaternion_of`]).
    pub fn kinematics(&self, model: &RobotModel, q: &JointVector) -> ArmKinematics {
        let mut kin = ArmKinematics::identity();
        self.kinematics_into(model, q, &mut kin);
        kin
    }

    /// [`Chain::kinematics`] written into `kin`, for a caller that keeps it where it is used
    /// (returned, the 920 bytes are copied once more).
    #[inline(always)]
    pub fn kinematics_into(&self, model: &RobotModel, q: &JointVector, kin: &mut ArmKinematics) {
        let tcp = self.walk(model, q, |k, f| kin.frames[k] = *f);
        kin.tcp = tcp.pose();
    }

    /// The TCP pose alone, with the bits of [`Chain::kinematics`]' `tcp`.
    #[inline]
    pub fn tcp(&self, model: &RobotModel, q: &JointVector) -> Pose {
        self.walk(model, q, |_, _| {}).pose()
    }

    /// The TCP frame and the Jacobian alone (what an RDMP step needs), with the bits of
    /// [`Chain::kinematics`]' `tcp` (as [`Frame::pose`]) and [`ArmKinematics::jacobian`]: the
    /// same frames, computed alike, but only each joint's axis and origin kept.
    #[inline(always)]
    pub fn tcp_and_jacobian(&self, model: &RobotModel, q: &JointVector) -> (Frame, Jacobian) {
        let mut axes = [(Vector3::zeros(), Vector3::zeros()); NA];
        let tcp = self.walk(model, q, |k, f| {
            if let Some(a) = axes.get_mut(k.wrapping_sub(1)) {
                *a = (self.axis_of(model, k - 1, f), f.origin);
            }
        });
        let pe = tcp.origin;
        let mut j = Jacobian::zeros();
        for (i, (z, o)) in axes.iter().enumerate() {
            column_into(&mut j, i, z, &pe, o);
        }
        (tcp, j)
    }

    /// The TCP frame of `kin` (computed by this chain): its flange frame times the TCP's
    /// transform, with the bits [`Chain::tcp_and_jacobian`] gives.
    #[inline(always)]
    pub fn tcp_frame_of(&self, model: &RobotModel, kin: &ArmKinematics) -> Frame {
        self.tcp_frame(model, &kin.frames[LINK_TOOL])
    }

    /// Computes frames 1..=8 in order, showing each to `visit` with its index; returns the
    /// TCP frame. Each joint's sine and cosine ([`crate::float::sincos`]) are taken where the
    /// joint is composed; an iiwa's chain is composed with its turns as constants
    /// ([`Chain::iiwa_joint`]; the same bits as the loop). The two together took the RDMP step
    /// × 0.92–0.95 on an AMD EPYC VM, each alone × 1.00–1.01 (`prf bench --profile-steps`).
    #[inline(always)]
    fn walk(
        &self,
        model: &RobotModel,
        q: &JointVector,
        mut visit: impl FnMut(usize, &Frame),
    ) -> Frame {
        let mut f = Frame::identity();
        let sincos = |i: usize| crate::float::sincos(q[i]);
        if self.is_iiwa() {
            // The iiwa's turns as constants, joint by joint (the same bits as the loop).
            macro_rules! iiwa_joints {
                ($($i:literal)*) => {$(
                    f = Chain::iiwa_joint::<$i>(model, &f, sincos($i));
                    visit($i + 1, &f);
                )*};
            }
            iiwa_joints!(0 1 2 3 4 5 6);
        } else {
            for i in 0..NA {
                f = self.joint(model, i, &f, sincos(i));
                visit(i + 1, &f);
            }
        }
        f = self.flange_frame(model, &f);
        visit(LINK_TOOL, &f);
        self.tcp_frame(model, &f)
    }
}

/// The axis `axis` of a joint in the arm base frame, from the frame that follows the joint
/// (which turns about it): that frame's third column when `about_z`.
#[inline(always)]
fn joint_axis(f: &Frame, axis: &Vector3<f64>, about_z: bool) -> Vector3<f64> {
    if about_z {
        f.rotation.column(2).into()
    } else {
        f.rotation * axis
    }
}

/// Column i of the geometric Jacobian, [z_i × (p_e − p_i); z_i] (six entries in a row in
/// memory: J is column-major).
#[inline(always)]
fn column_into(j: &mut Jacobian, i: usize, z: &Vector3<f64>, pe: &Vector3<f64>, o: &Vector3<f64>) {
    let v = z.cross(&(pe - o));
    j.data.0[i] = [v.x, v.y, v.z, z.x, z.y, z.z];
}

/// The frames of one [`ArmKinematics`] where the arm base is at `base`, each composed
/// (`base · frame`) once, on its first use.
pub struct FramesIn<'a> {
    kin: &'a ArmKinematics,
    base: Frame,
    built: [Option<Frame>; N_FRAMES],
}

impl<'a> FramesIn<'a> {
    /// No frame composed yet.
    pub fn new(kin: &'a ArmKinematics, base: &Pose) -> Self {
        FramesIn {
            kin,
            base: Frame::of_pose(base),
            built: [None; N_FRAMES],
        }
    }

    /// `base · frame · c` for frame `link`; `None` if there is no such frame.
    #[inline]
    pub fn point(&mut self, link: usize, c: &Vector3<f64>) -> Option<Vector3<f64>> {
        let (kin, base) = (self.kin, &self.base);
        let f = self
            .built
            .get_mut(link)?
            .get_or_insert_with(|| base.then(&kin.frames[link]));
        Some(f.transform_point(c))
    }
}

/// True if `a` is exactly the z axis (0, 0, 1).
#[inline(always)]
fn is_z(a: &Vector3<f64>) -> bool {
    a.x == 0.0 && a.y == 0.0 && a.z == 1.0
}

/// The spheres rigid with the TCP (link 7's and the tool's) when the TCP is at `tcp` (arm base
/// frame), each with its centre there: where every configuration that puts the TCP at `tcp`
/// has them, whatever the rest of the arm does.
pub fn tcp_rigid_spheres<'a>(
    model: &'a RobotModel,
    tcp: &Pose,
) -> impl Iterator<Item = (&'a Sphere, Vector3<f64>)> + 'a {
    let tool = tcp * model.tcp.inverse();
    let link7 = tool * model.flange.inverse();
    model.spheres.iter().filter_map(move |s| {
        let frame = match s.link as usize {
            LINK_TOOL => &tool,
            l if l == NA => &link7,
            _ => return None,
        };
        Some((s, frame.transform_point(&s.centre.into()).coords))
    })
}

/// Pose of the platform base frame `b` in the world from q_m = [x, y, yaw].
pub fn platform_pose(q_m: [f64; 3]) -> Pose {
    let (s, c) = libm::sincos(0.5 * q_m[2]);
    Isometry3::from_parts(
        Translation3::new(q_m[0], q_m[1], 0.0),
        UnitQuaternion::new_unchecked(Quaternion::new(c, 0.0, 0.0, s)),
    )
}

/// [x, y, yaw] of a platform pose: the inverse of [`platform_pose`].
pub fn planar(p: &Pose) -> [f64; 3] {
    // Yaw of the Z-Y-X Euler angles, with libm's atan2 (the same bits on every platform).
    let q = p.rotation.quaternion();
    let yaw = libm::atan2(
        2.0 * (q.w * q.k + q.i * q.j),
        1.0 - 2.0 * (q.j * q.j + q.k * q.k),
    );
    [p.translation.x, p.translation.y, yaw]
}

/// Pose of the arm base frame in the world.
pub fn arm_base_pose(model: &RobotModel, q_m: [f64; 3]) -> Pose {
    platform_pose(q_m) * model.mount
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_centres_follow_their_links() {
        let model = RobotModel::kmr_iiwa14();
        assert_eq!(model.validate(), Ok(()));
        let q = JointVector::from(model.home);
        let k = ArmKinematics::new(&model, &q);
        let mut out = [Vector3::zeros(); crate::robot::MAX_SPHERES];
        k.sphere_centres(&model, &mut out);
        for (s, c) in model.spheres.iter().zip(&out) {
            let f = &k.frames[s.link as usize];
            let local = f.rotation.tr_mul(&(c - f.origin));
            assert!((local - s.centre).norm() < 1e-12);
        }
        let mut bad = model.clone();
        bad.spheres[3].link = 42;
        assert_eq!(
            bad.validate(),
            Err(crate::robot::ModelError::Sphere { index: 3 })
        );
        k.sphere_centres(&bad, &mut out); // no panic
        let mut bad = model.clone();
        bad.joints[2].upper = f64::NAN;
        assert_eq!(
            bad.validate(),
            Err(crate::robot::ModelError::Joint { joint: 2 })
        );
    }

    #[test]
    fn zero_configuration_is_a_vertical_arm() {
        let model = RobotModel::kmr_iiwa14();
        let k = ArmKinematics::new(&model, &JointVector::zeros());
        // DH: d1 + d3 + d5 + d7 = 0.36 + 0.42 + 0.40 + 0.126 m straight up, plus the TCP offset.
        let p = k.tcp.translation.vector;
        assert!(
            (p - Vector3::new(0.0, 0.0, 1.306 + 0.15)).norm() < 1e-12,
            "{p:?}"
        );
    }
}
