//! A rigid frame as forward kinematics composes it: a rotation matrix and an origin.

use crate::float::sqrt;
use crate::se3::Pose;
use nalgebra::{Isometry3, Matrix3, Quaternion, Translation3, UnitQuaternion, Vector3};

/// The frame x ↦ R x + p. FK chains these instead of quaternions: a joint about z mixes two
/// columns of R, an origin that is a signed permutation only picks columns, and the Jacobian
/// reads z_i as a column.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// R, the frame's axes as columns.
    pub rotation: Matrix3<f64>,
    /// p, the frame's origin.
    pub origin: Vector3<f64>,
}

impl Frame {
    /// The identity frame.
    pub fn identity() -> Frame {
        Frame {
            rotation: Matrix3::identity(),
            origin: Vector3::zeros(),
        }
    }

    /// The frame of a pose (its quaternion as a matrix).
    pub fn of_pose(p: &Pose) -> Frame {
        Frame {
            rotation: p.rotation.to_rotation_matrix().into_inner(),
            origin: p.translation.vector,
        }
    }

    /// The same frame as a pose, its rotation as a quaternion ([`quaternion_of`]).
    pub fn pose(&self) -> Pose {
        Isometry3::from_parts(
            Translation3::from(self.origin),
            quaternion_of(&self.rotation),
        )
    }

    /// The pose error (p_d − p, log(R_d Rᵀ)) of this frame with respect to `desired`:
    /// [`crate::se3::pose_error`] of [`Frame::pose`], to rounding. Below 1.8° the rotation
    /// vector comes from R_d Rᵀ's skew part w = sin θ · a as w · θ/sin θ (arcsin's series in
    /// |w|², through s⁸; the next term is below 2e-17): no quaternion of R, no square root,
    /// division or atan2 on the RDMP step's path from FK to the solve. Beyond, exactly
    /// `pose_error(desired, &self.pose())`.
    #[inline(always)]
    pub fn error_from(&self, desired: &Pose) -> (Vector3<f64>, Vector3<f64>) {
        let e_p = desired.translation.vector - self.origin;
        let rd = desired.rotation.to_rotation_matrix().into_inner();
        let r = &self.rotation;
        // (R_d Rᵀ)_ij: row i of R_d · row j of R.
        let m = |i: usize, j: usize| {
            rd[(i, 0)] * r[(j, 0)] + rd[(i, 1)] * r[(j, 1)] + rd[(i, 2)] * r[(j, 2)]
        };
        let w = Vector3::new(m(2, 1) - m(1, 2), m(0, 2) - m(2, 0), m(1, 0) - m(0, 1)) * 0.5;
        let s2 = w.norm_squared();
        // θ < 90° (tr > 1) with sin θ < 1/32.
        if s2 < SMALL_SIN2 && m(0, 0) + m(1, 1) + m(2, 2) > 1.0 {
            let k = 1.0
                + s2 * (1.0 / 6.0 + s2 * (3.0 / 40.0 + s2 * (5.0 / 112.0 + s2 * (35.0 / 1152.0))));
            return (e_p, w * k);
        }
        crate::se3::pose_error(desired, &self.pose())
    }

    /// R c + p: a point given in this frame, in the frame this one is given in.
    #[inline(always)]
    pub fn transform_point(&self, c: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * c + self.origin
    }

    /// self · other: `other` given in this frame, expressed where this frame is given.
    #[inline(always)]
    pub fn then(&self, other: &Frame) -> Frame {
        Frame {
            rotation: self.rotation * other.rotation,
            origin: self.transform_point(&other.origin),
        }
    }
}

/// sin²θ below which [`Frame::error_from`] takes its series: θ < asin(1/32) ≈ 1.8°.
const SMALL_SIN2: f64 = 1.0 / 1024.0;

/// The unit quaternion of a rotation matrix, from the largest of 1 + tr R and 1 + 2 R_ii − tr R
/// (so the square root and the division are well conditioned). Its sign is the one with
/// that component positive; q and −q are the same rotation. The square root is
/// [`crate::float::sqrt`], so host and controller give the same bits.
pub fn quaternion_of(m: &Matrix3<f64>) -> UnitQuaternion<f64> {
    let (xx, yy, zz) = (m[(0, 0)], m[(1, 1)], m[(2, 2)]);
    let trace = xx + yy + zz;
    let q = if trace > 0.0 {
        let s = 2.0 * sqrt(1.0 + trace);
        Quaternion::new(
            0.25 * s,
            (m[(2, 1)] - m[(1, 2)]) / s,
            (m[(0, 2)] - m[(2, 0)]) / s,
            (m[(1, 0)] - m[(0, 1)]) / s,
        )
    } else if xx > yy && xx > zz {
        let s = 2.0 * sqrt(1.0 + xx - yy - zz);
        Quaternion::new(
            (m[(2, 1)] - m[(1, 2)]) / s,
            0.25 * s,
            (m[(0, 1)] + m[(1, 0)]) / s,
            (m[(0, 2)] + m[(2, 0)]) / s,
        )
    } else if yy > zz {
        let s = 2.0 * sqrt(1.0 + yy - xx - zz);
        Quaternion::new(
            (m[(0, 2)] - m[(2, 0)]) / s,
            (m[(0, 1)] + m[(1, 0)]) / s,
            0.25 * s,
            (m[(1, 2)] + m[(2, 1)]) / s,
        )
    } else {
        let s = 2.0 * sqrt(1.0 + zz - xx - yy);
        Quaternion::new(
            (m[(1, 0)] - m[(0, 1)]) / s,
            (m[(0, 2)] + m[(2, 0)]) / s,
            (m[(1, 2)] + m[(2, 1)]) / s,
            0.25 * s,
        )
    };
    UnitQuaternion::new_unchecked(q)
}
