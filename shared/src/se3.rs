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
    log_angle(r).0
}

/// [`log`] and the angle θ it scaled the axis with. Below [`SMALL_TAN2`] θ/s = 2 atan(t)/s,
/// t = s/w, comes from its series in t² (no atan2; the square root for θ only, which [`log`]
/// drops).
#[inline(always)]
fn log_angle(r: &Rot) -> (Vector3<f64>, f64) {
    let q = r.quaternion();
    // q and −q are the same rotation: take the representative with w ≥ 0, so θ ≤ π.
    let (w, v) = if q.w >= 0.0 {
        (q.w, q.imag())
    } else {
        (-q.w, -q.imag())
    };
    let ss = v.norm_squared();
    if ss < SMALL_TAN2 * w * w {
        // 2 atan(t)/t = 2 Σ (−t²)ⁿ/(2n+1), to t⁸: at t ≤ 1/64 the next term, t¹⁰/11, is
        // below 1e-19.
        let inv = 1.0 / w;
        let t2 = ss * inv * inv;
        let series = 1.0 + t2 * (-1.0 / 3.0 + t2 * (0.2 + t2 * (-1.0 / 7.0 + t2 * (1.0 / 9.0))));
        let k = 2.0 * inv * series;
        return (v * k, k * crate::float::sqrt(ss));
    }
    let s = crate::float::sqrt(ss);
    let theta = 2.0 * crate::float::atan2(s, w);
    (v * (theta / s), theta)
}

/// tan²(θ/2) below which [`log`] takes its series: θ < 2 atan(1/64) ≈ 1.8°.
const SMALL_TAN2: f64 = 1.0 / 4096.0;

/// (θ/2)² below which [`exp`] takes its series: θ < 1/16 rad.
const SMALL_HALF_ANGLE2: f64 = 1.0 / 1024.0;

/// SO(3) exponential of a rotation vector θ·a: the quaternion (cos(θ/2), a sin(θ/2)).
pub fn exp(v: &Vector3<f64>) -> Rot {
    let x2 = 0.25 * v.norm_squared();
    if x2 < SMALL_HALF_ANGLE2 {
        // x = θ/2 < 1/32: cos x and sin(x)/(2x) by their series to x⁸ (the next terms are
        // below 1e-22); no square root, sine, cosine or division. (The angles of a tick.)
        let c = 1.0 + x2 * (-0.5 + x2 * (1.0 / 24.0 + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40320.0))));
        let k = 0.5
            * (1.0
                + x2 * (-1.0 / 6.0
                    + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362880.0)))));
        return UnitQuaternion::new_unchecked(Quaternion::new(c, v.x * k, v.y * k, v.z * k));
    }
    let theta = norm(v);
    let half = 0.5 * theta;
    let (s, c) = (libm::sin(half), libm::cos(half));
    let k = s / theta;
    UnitQuaternion::new_unchecked(Quaternion::new(c, v.x * k, v.y * k, v.z * k))
}

/// Rotation vector of `r` on the branch closest to `reference`.
///
/// `log` is unique only up to adding 2πk along the axis. Rotation DMPs integrate a continuous
/// error vector, so they pick the representative nearest to the previous one ("unwrapping");
/// this is what lets a rotation DMP reproduce motions with more than 180° of travel.
/// Inlined: a rotation DMP's step takes two (30 instructions fewer a step than the call).
#[inline(always)]
pub fn log_near(r: &Rot, reference: &Vector3<f64>) -> Vector3<f64> {
    let (v, theta) = log_angle(r);
    if within_half_turn(&v, theta, reference) {
        v
    } else {
        unwrap_near(v, reference)
    }
}

/// True when `reference` is surely within π of θ along the axis of `v` = θ·a, so that
/// [`unwrap_near`] would add 0·2π and return `v` bit for bit: |ref·v − θ²| < 3θ, i.e. the
/// reference's component along a within 3 rad of θ, a margin of 0.14 rad over the rounding
/// of both ways of computing it (≤ 1e-8 rad for |ref| < 1e6 rad). It needs neither the square
/// root, the divisions nor the rounding of the unwrapping, which sit on the RDMP step's
/// critical path. θ ≥ 2e-6 keeps [`unwrap_near`] on its branch that uses v's own axis, whose
/// zeros carry v's signs (so adding 0·a leaves even a −0 component as it is).
#[inline(always)]
fn within_half_turn(v: &Vector3<f64>, theta: f64, reference: &Vector3<f64>) -> bool {
    theta >= 2e-6 && reference.norm_squared() < 1e12 && {
        let off = reference.dot(v) - theta * theta;
        off.abs() < 3.0 * theta
    }
}

/// [`log_near`]'s unwrapping of `v` = log(r): the representative v + 2πk·a nearest to
/// `reference` (the general path, and the whole of `log_near` before its shortcut).
pub fn unwrap_near(v: Vector3<f64>, reference: &Vector3<f64>) -> Vector3<f64> {
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

    /// A random unit axis (uniform in the cube, normalised).
    fn random_axis(rng: &mut rand::rngs::StdRng) -> Vector3<f64> {
        use rand::RngExt;
        Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)).normalize()
    }

    /// `exp` and `log` below their series thresholds (θ < 1/16 rad, θ < 1.8°) against the
    /// closed forms with libm's sine, cosine and atan2: within 2 ε per component (exp) and
    /// 4 ε of |v| (log); either side of the thresholds too.
    #[test]
    fn the_series_branches_agree_with_the_closed_forms() {
        use rand::{RngExt, SeedableRng, rngs::StdRng};
        let mut rng = StdRng::seed_from_u64(3);
        for i in 0..100_000 {
            let axis = random_axis(&mut rng);
            let theta = match i % 3 {
                0 => rng.random_range(0.0..0.07),
                1 => rng.random_range(0.0..1e-6),
                _ => 2.0 * libm::atan(1.0 / 64.0) * rng.random_range(0.9..1.1),
            };
            let v = axis * theta;
            let q = exp(&v);
            let t = v.norm();
            let (s, c) = (libm::sin(0.5 * t), libm::cos(0.5 * t));
            let closed = Quaternion::new(c, v.x * s / t, v.y * s / t, v.z * s / t);
            assert!(
                (q.coords - closed.coords).amax() <= 2.0 * f64::EPSILON,
                "exp({v:?})"
            );
            let (w, u) = (q.w, q.imag());
            let sn = u.norm();
            let closed = u * (2.0 * libm::atan2(sn, w) / sn);
            let e = (log(&q) - closed).norm();
            assert!(
                e <= 4.0 * f64::EPSILON * closed.norm(),
                "log of exp({v:?}): {e:e}"
            );
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

    /// `log_near`'s shortcut returns what the unwrapping alone returns, bit for bit, and is
    /// taken: random rotations (near the identity and near π among them) against references
    /// on the axis 2πk away, around the ±π boundaries of the unwrapping, off the axis, tiny,
    /// zero, huge and NaN.
    #[test]
    fn log_near_is_the_unwrapping_bit_for_bit() {
        use rand::{RngExt, SeedableRng, rngs::StdRng};
        let mut rng = StdRng::seed_from_u64(7);
        let (mut shortcut, mut cases) = (0, 0);
        for i in 0..20_000 {
            let axis = random_axis(&mut rng);
            let angle = match i % 4 {
                0 => rng.random_range(0.0..1e-5),
                1 => PI - rng.random_range(0.0..1e-6),
                _ => rng.random_range(0.0..PI),
            };
            let r = exp(&(axis * angle));
            let v = log(&r);
            let a = v.normalize();
            let off = Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            let k = rng.random_range(-3..=3) as f64;
            let along = v.norm() + k * core::f64::consts::TAU;
            let edge = if rng.random_bool(0.5) { PI } else { 3.0 };
            let references = [
                a * along,
                a * (v.norm() + edge + rng.random_range(-1e-9..1e-9)),
                a * (v.norm() - edge + rng.random_range(-1e-9..1e-9)),
                a * along + off * rng.random_range(0.0..4.0),
                off * 1e-10,
                Vector3::zeros(),
                a * 1e7,
                Vector3::new(f64::NAN, 0.0, 0.0),
            ];
            for reference in &references {
                let fast = log_near(&r, reference);
                let general = unwrap_near(v, reference);
                assert_eq!(
                    fast.map(f64::to_bits),
                    general.map(f64::to_bits),
                    "angle {angle}, axis {axis:?}, reference {reference:?}"
                );
                let theta = log_angle(&r).1;
                shortcut += usize::from(within_half_turn(&v, theta, reference));
                cases += 1;
            }
        }
        assert!(
            shortcut > cases / 4 && shortcut < cases,
            "{shortcut} of {cases}"
        );
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
