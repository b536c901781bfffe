//! The previous forward kinematics, by unit quaternions: kept as the benchmark's baseline
//! (`prf bench`) and as a second implementation the tests compare [`super::Chain`] with.

use crate::robot::{LINK_TOOL, N_FRAMES, RobotModel};
use crate::se3::Pose;
use crate::{Jacobian, JointVector, NA};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// Frames and TCP as poses: 0 = arm base, 1..=7 = links, 8 = flange.
#[derive(Clone, Copy, Debug)]
pub struct QuaternionKinematics {
    /// Frames in the arm base frame.
    pub frames: [Pose; N_FRAMES],
    /// TCP pose in the arm base frame.
    pub tcp: Pose,
}

impl QuaternionKinematics {
    /// T_i = T_{i−1} · origin_i · Rot(axis_i, q_i), Rot(a, θ) = [cos θ/2, a sin θ/2]; about z
    /// the product with it takes 8 products instead of 16.
    pub fn new(model: &RobotModel, q: &JointVector) -> Self {
        let mut frames = [Pose::identity(); N_FRAMES];
        for i in 0..NA {
            let j = &model.joints[i];
            let (s, c) = libm::sincos(0.5 * q[i]);
            let mut f = frames[i] * j.origin;
            let a = j.axis.into_inner();
            f.rotation = if a == Vector3::z() {
                times_z_rotation(&f.rotation, s, c)
            } else {
                let a = a * s;
                f.rotation * UnitQuaternion::new_unchecked(Quaternion::new(c, a.x, a.y, a.z))
            };
            frames[i + 1] = f;
        }
        frames[LINK_TOOL] = frames[NA] * model.flange;
        let tcp = frames[LINK_TOOL] * model.tcp;
        QuaternionKinematics { frames, tcp }
    }

    /// Geometric Jacobian of the TCP, column i = [z_i × (p_e − p_i); z_i].
    pub fn jacobian(&self, model: &RobotModel) -> Jacobian {
        let pe = self.tcp.translation.vector;
        let mut jac = Jacobian::zeros();
        for i in 0..NA {
            let f = &self.frames[i + 1];
            let z = f.rotation * model.joints[i].axis.into_inner();
            let v = z.cross(&(pe - f.translation.vector));
            jac.fixed_view_mut::<3, 1>(0, i).copy_from(&v);
            jac.fixed_view_mut::<3, 1>(3, i).copy_from(&z);
        }
        jac
    }
}

/// r ⊗ [c, 0, 0, s]: a rotation by θ about z (s = sin θ/2, c = cos θ/2) after r.
#[inline(always)]
fn times_z_rotation(r: &UnitQuaternion<f64>, s: f64, c: f64) -> UnitQuaternion<f64> {
    let (w, x, y, z) = (r.w, r.i, r.j, r.k);
    UnitQuaternion::new_unchecked(Quaternion::new(
        w * c - z * s,
        x * c + y * s,
        y * c - x * s,
        z * c + w * s,
    ))
}
