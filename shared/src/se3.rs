//! Poses and rotations: SE(3) as `Isometry3<f64>`, SO(3) as unit quaternions.
//!
//! Serialized poses are `[x, y, z, qw, qx, qy, qz]` (DESIGN.md, "Frames and units").
//! [`log`] returns the principal rotation vector (angle in [0, π]) computed with `atan2`, so it is
//! accurate near 0 and near π and independent of the quaternion sign (no double-cover flips).

use crate::float::norm;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};

/// A rigid transform; `T_a^b` maps coordinates in frame `a` to frame `b`.
pub type Pose = Isometry3<f64>;
/// A rotation.
pub type Rot = UnitQuaternion<f64>;

/// Wraps an angle to (−π, π].
pub fn wrap(a: f64) -> f64 {
    let two_pi = 2.0 * core::f64::consts::PI;
    let r = a - two_pi * libm::floor((a + core::f64::consts::PI) / two_pi);
    if r <= -core::f64::consts::PI {
        r + two_pi
    } else {
        r
    }
}

/// Pose from URDF `xyz` and `rpy` (R = Rz(yaw) · Ry(pitch) · Rx(roll)).
pub fn pose_from_xyz_rpy(xyz: [f64; 3], rpy: [f64; 3]) -> Pose {
    Isometry3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    )
}

/// Pose from its serialized form `[x, y, z, qw, qx, qy, qz]`; the quaternion is normalized.
/// Returns `None` for non-finite values or a zero quaternion.
pub fn pose_from_array(a: [f64; 7]) -> Option<Pose> {
    if a.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let q = Quaternion::new(a[3], a[4], a[5], a[6]);
    let n = q.norm();
    if n < 1e-9 {
        return None;
    }
    Some(Isometry3::from_parts(
        Translation3::new(a[0], a[1], a[2]),
        UnitQuaternion::new_unchecked(q / n),
    ))
}

/// Serialized form `[x, y, z, qw, qx, qy, qz]` of a pose, with qw ≥ 0.
pub fn pose_to_array(p: &Pose) -> [f64; 7] {
    let t = p.translation.vector;
    let mut q = *p.rotation.quaternion();
    if q.w < 0.0 {
        q = -q;
    }
    [t.x, t.y, t.z, q.w, q.i, q.j, q.k]
}

/// A pose's translation and quaternion (x, y, z, i, j, k, w) as bits, the sign as it is: equal
/// bits, the same pose to every computation (a key for results computed from it).
pub fn pose_bits(p: &Pose) -> [u64; 7] {
    let (t, q) = (&p.translation.vector, &p.rotation.coords);
    [t.x, t.y, t.z, q.x, q.y, q.z, q.w].map(f64::to_bits)
}

/// SO(3) logarithm: the rotation vector θ·a with θ ∈ [0, π].
pub fn log(r: &Rot) -> Vector3<f64> {
    let q = r.quaternion();
    // q and −q are the same rotation: take the representative with w ≥ 0, so θ ≤ π.
    let (w, v) = if q.w >= 0.0 {
        (q.w, q.imag())
    } else {
        (-q.w, -q.imag())
    };
    let s = norm(&v);
    if s < 1e-12 {
        // θ = 2·atan2(s, w) ≈ 2s/w; the series keeps full precision near the identity.
        return v * (2.0 / w);
    }
    v * (2.0 * libm::atan2(s, w) / s)
}

/// SO(3) exponential of a rotation vector.
pub fn exp(v: &Vector3<f64>) -> Rot {
    let theta = norm(v);
    let half = 0.5 * theta;
    let (s, c) = (libm::sin(half), libm::cos(half));
    // sin(θ/2)/θ → 1/2 as θ → 0 (series to 4th order below 1e-4).
    let k = if theta < 1e-4 {
        0.5 - theta * theta / 48.0
    } else {
        s / theta
    };
    UnitQuaternion::new_unchecked(Quaternion::new(c, v.x * k, v.y * k, v.z * k))
}

/// Rotation vector of `r` on the branch closest to `reference`.
///
/// `log` is unique only up to adding 2πk along the axis. Rotation DMPs integrate a continuous
/// error vector, so they pick the representative nearest to the previous one ("unwrapping");
/// this is what lets a rotation DMP reproduce motions with more than 180° of travel.
pub fn log_near(r: &Rot, reference: &Vector3<f64>) -> Vector3<f64> {
    let v = log(r);
    let theta = norm(&v);
    let axis = if theta > 1e-9 {
        v / theta
    } else {
        let rn = norm(reference);
        if rn < 1e-9 {
            return v;
        }
        reference / rn
    };
    let along = reference.dot(&axis);
    let k = crate::float::round((along - theta) / core::f64::consts::TAU);
    v + axis * (k * core::f64::consts::TAU)
}

/// The angle of the rotation between `a` and `b`, rad in [0, π] (nalgebra's `angle_to`, with
/// libm's atan2: the same bits on every platform).
pub fn angle_between(a: &Rot, b: &Rot) -> f64 {
    let q = (a.inverse() * b).into_inner();
    2.0 * libm::atan2(norm(&q.imag()), f64::abs(q.w))
}

/// Pose error `(p_d − p, log(R_d R⁻¹))` of `actual` with respect to `desired`, both in the same
/// frame: the world-frame twist direction that moves `actual` onto `desired`.
pub fn pose_error(desired: &Pose, actual: &Pose) -> (Vector3<f64>, Vector3<f64>) {
    (
        desired.translation.vector - actual.translation.vector,
        log(&(desired.rotation * actual.rotation.inverse())),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::PI;

    #[test]
    fn log_exp_round_trip_including_near_pi() {
        for &angle in &[0.0, 1e-10, 1e-5, 0.3, 2.0, PI - 1e-9, PI] {
            let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
            let v = axis * angle;
            let back = log(&exp(&v));
            assert!(
                (back - v).norm() < 1e-12 || (angle > PI - 1e-8),
                "{angle}: {back:?}"
            );
            assert!((back.norm() - angle).abs() < 1e-12, "{angle}");
        }
    }

    #[test]
    fn log_is_sign_independent() {
        let r = exp(&Vector3::new(0.2, 1.0, -0.4));
        let neg = UnitQuaternion::new_unchecked(-*r.quaternion());
        assert!((log(&r) - log(&neg)).norm() < 1e-15);
    }

    #[test]
    fn log_near_unwraps_past_pi() {
        let axis = Vector3::z();
        // 200° about +z is represented by log as −160°; near +190° it must unwrap to +200°.
        let r = exp(&(axis * (200f64).to_radians()));
        let v = log_near(&r, &(axis * (190f64).to_radians()));
        assert!((v.z - (200f64).to_radians()).abs() < 1e-12);
    }

    #[test]
    fn pose_array_round_trip() {
        let p = pose_from_xyz_rpy([0.1, -0.2, 0.3], [0.4, -0.5, 2.9]);
        let q = pose_from_array(pose_to_array(&p)).unwrap();
        assert!((p.to_homogeneous() - q.to_homogeneous()).norm() < 1e-14);
        assert!(pose_from_array([0.0, 0.0, f64::NAN, 1.0, 0.0, 0.0, 0.0]).is_none());
        assert!(pose_from_array([0.0; 7]).is_none());
    }
}
