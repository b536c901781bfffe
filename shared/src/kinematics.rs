//! Forward kinematics, TCP pose and the geometric Jacobian: the one home of FK.
//!
//! Arm quantities are expressed in the arm base frame (URDF `link_0`), as the paper's
//! T_e^b = F_a(q_a); [`platform_pose`] gives T_b = F_m(q_m) and [`arm_base_pose`] chains both.

use crate::robot::{LINK_TOOL, N_FRAMES, RobotModel};
use crate::se3::Pose;
use crate::{Jacobian, JointVector, NA};
use nalgebra::{Isometry3, Matrix3, Quaternion, Translation3, UnitQuaternion, Vector3};

/// Everything one kinematics evaluation yields at a configuration q_a.
#[derive(Clone, Copy, Debug)]
pub struct ArmKinematics {
    /// Frames in the arm base frame: 0 = arm base (identity), 1..=7 = links, 8 = flange.
    pub frames: [Pose; N_FRAMES],
    /// TCP pose T_e in the arm base frame.
    pub tcp: Pose,
}

impl ArmKinematics {
    /// Forward kinematics: T_i = T_{i−1} · origin_i · Rot(axis_i, q_i).
    ///
    /// Rot(a, θ) = [cos θ/2, a sin θ/2] with both from one `libm::sincos` (one range
    /// reduction; the same bits on the host and on the controller). About a z axis, as every
    /// iiwa joint turns, the product with it is `times_z_rotation`.
    pub fn new(model: &RobotModel, q: &JointVector) -> Self {
        let mut kin = ArmKinematics {
            frames: [Pose::identity(); N_FRAMES],
            tcp: Pose::identity(),
        };
        let frames = &mut kin.frames;
        for i in 0..NA {
            let j = &model.joints[i];
            let (s, c) = libm::sincos(0.5 * q[i]);
            let mut f = frames[i] * j.origin;
            let a = j.axis.into_inner();
            f.rotation = if is_z(&a) {
                times_z_rotation(&f.rotation, s, c)
            } else {
                let a = a * s;
                f.rotation * UnitQuaternion::new_unchecked(Quaternion::new(c, a.x, a.y, a.z))
            };
            frames[i + 1] = f;
        }
        frames[LINK_TOOL] = frames[NA] * model.flange;
        kin.tcp = frames[LINK_TOOL] * model.tcp;
        kin
    }

    /// [`ArmKinematics::new`] with the general quaternion product for every joint: the
    /// previous implementation, kept as the benchmark's baseline (`prf bench`).
    pub fn new_general(model: &RobotModel, q: &JointVector) -> Self {
        let mut frames = [Pose::identity(); N_FRAMES];
        for i in 0..NA {
            let j = &model.joints[i];
            let (s, c) = libm::sincos(0.5 * q[i]);
            let a = j.axis.into_inner() * s;
            let rot = UnitQuaternion::new_unchecked(Quaternion::new(c, a.x, a.y, a.z));
            frames[i + 1] = frames[i] * j.origin * rot;
        }
        frames[LINK_TOOL] = frames[NA] * model.flange;
        let tcp = frames[LINK_TOOL] * model.tcp;
        ArmKinematics { frames, tcp }
    }

    /// Geometric Jacobian of the TCP, 6×7, rows [v; ω] in the arm base frame:
    /// column i = [z_i × (p_e − p_i); z_i].
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

    /// Centres of the model's collision spheres in the arm base frame, written to `out`
    /// (which should hold `model.spheres.len()` entries; extra entries are left untouched).
    /// A sphere on a frame that does not exist (see [`RobotModel::validate`]) is skipped.
    pub fn sphere_centres(&self, model: &RobotModel, out: &mut [Vector3<f64>]) {
        for (s, o) in model.spheres.iter().zip(out.iter_mut()) {
            if let Some(frame) = self.frames.get(s.link as usize) {
                *o = frame.transform_point(&s.centre.into()).coords;
            }
        }
    }

    /// Centres of the collision spheres in the frame where the arm base is at `base`
    /// (`base · frame · centre`), written to `out` like [`ArmKinematics::sphere_centres`].
    /// Each frame is composed and turned into a matrix once, not once per sphere.
    pub fn sphere_centres_in(&self, model: &RobotModel, base: &Pose, out: &mut [Vector3<f64>]) {
        let mut frames = FramesIn::new(self, base);
        for (s, o) in model.spheres.iter().zip(out.iter_mut()) {
            if let Some(p) = frames.point(s.link as usize, &s.centre) {
                *o = p;
            }
        }
    }
}

/// The frames of one [`ArmKinematics`] where the arm base is at `base`, each composed
/// (`base · frame`) and turned into a matrix once, on its first use.
pub struct FramesIn<'a> {
    kin: &'a ArmKinematics,
    base: &'a Pose,
    built: [Option<(Matrix3<f64>, Vector3<f64>)>; N_FRAMES],
}

impl<'a> FramesIn<'a> {
    /// No frame composed yet.
    pub fn new(kin: &'a ArmKinematics, base: &'a Pose) -> Self {
        FramesIn {
            kin,
            base,
            built: [None; N_FRAMES],
        }
    }

    /// `base · frame · c` for frame `link`; `None` if there is no such frame.
    #[inline]
    pub fn point(&mut self, link: usize, c: &Vector3<f64>) -> Option<Vector3<f64>> {
        let (kin, base) = (self.kin, self.base);
        let (r, t) = self.built.get_mut(link)?.get_or_insert_with(|| {
            let f = base * kin.frames[link];
            (
                f.rotation.to_rotation_matrix().into_inner(),
                f.translation.vector,
            )
        });
        Some(*r * c + *t)
    }
}

/// True if `a` is exactly the z axis (0, 0, 1).
#[inline(always)]
fn is_z(a: &Vector3<f64>) -> bool {
    a.x == 0.0 && a.y == 0.0 && a.z == 1.0
}

/// r ⊗ [c, 0, 0, s]: a rotation by θ about z (s = sin θ/2, c = cos θ/2) after r, in 8
/// products instead of the general product's 16.
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
            let local = k.frames[s.link as usize].inverse_transform_point(&(*c).into());
            assert!((local.coords - s.centre).norm() < 1e-12);
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
