//! Kinematics against independent references: Bullet's FK (committed fixture), a textbook DH
//! model of the iiwa 14, finite differences, and the real link meshes.

mod common;

use common::{deg, fixture};
use nalgebra::{Matrix3, Matrix4, Quaternion, UnitQuaternion, Vector3};
use prf_shared::kinematics::quaternion::QuaternionKinematics;
use prf_shared::kinematics::{ArmKinematics, Chain, arm_base_pose, platform_pose, quaternion_of};
use prf_shared::robot::{LINK_TOOL, RobotModel};
use prf_shared::se3::Pose;
use prf_shared::se3::log;
use prf_shared::{JointVector, NA};
use rand::{RngExt, SeedableRng, rngs::StdRng};

fn random_q(rng: &mut StdRng, model: &RobotModel) -> JointVector {
    JointVector::from_fn(|i, _| {
        let j = &model.joints[i];
        rng.random_range(j.lower..j.upper)
    })
}

#[test]
fn fk_matches_pybullet() {
    let model = RobotModel::kmr_iiwa14();
    let rows = fixture("iiwa14_fk_pybullet.csv");
    assert!(rows.len() >= 20);
    for row in rows {
        let q = JointVector::from_fn(|i, _| row[i]);
        let k = ArmKinematics::new(&model, &q);
        for link in 1..=NA {
            let r = &row[NA + 7 * (link - 1)..NA + 7 * link];
            let p = Vector3::new(r[0], r[1], r[2]);
            let rot = UnitQuaternion::from_quaternion(Quaternion::new(r[3], r[4], r[5], r[6]));
            let f = k.frames[link].pose();
            let dp = (f.translation.vector - p).norm();
            let dr = log(&(f.rotation * rot.inverse())).norm();
            // Bullet stores link frames in single precision in places: 1e-6 m / 1e-6 rad.
            assert!(
                dp < 1e-6 && dr < 1e-6,
                "link {link} q={q:?}: {dp} m, {dr} rad"
            );
        }
    }
}

/// Standard DH of the LBR iiwa 14 R820: d = [0.36, 0, 0.42, 0, 0.40, 0, 0.126], a = 0.
fn dh_flange(q: &JointVector) -> Matrix4<f64> {
    use std::f64::consts::FRAC_PI_2 as H;
    let d = [0.36, 0.0, 0.42, 0.0, 0.40, 0.0, 0.126];
    let alpha = [-H, H, H, -H, -H, H, 0.0];
    let mut t = Matrix4::identity();
    for i in 0..NA {
        let (st, ct) = q[i].sin_cos();
        let (sa, ca) = alpha[i].sin_cos();
        #[rustfmt::skip]
        let a = Matrix4::new(
            ct, -st * ca, st * sa, 0.0,
            st, ct * ca, -ct * sa, 0.0,
            0.0, sa, ca, d[i],
            0.0, 0.0, 0.0, 1.0,
        );
        t *= a;
    }
    t
}

#[test]
fn flange_matches_dh_model() {
    let model = RobotModel::kmr_iiwa14();
    let mut rng = StdRng::seed_from_u64(1);
    // The DH flange frame equals ours up to one constant rotation (different frame axes,
    // same joint angles and signs).
    let offset = {
        let ours = ArmKinematics::new(&model, &JointVector::zeros()).frames[LINK_TOOL].pose();
        ours.rotation.to_rotation_matrix().matrix().transpose()
            * dh_flange(&JointVector::zeros()).fixed_view::<3, 3>(0, 0)
    };
    for _ in 0..200 {
        let q = random_q(&mut rng, &model);
        let dh = dh_flange(&q);
        let ours = ArmKinematics::new(&model, &q).frames[LINK_TOOL].pose();
        let dp = (ours.translation.vector - dh.fixed_view::<3, 1>(0, 3)).norm();
        let dr = (ours.rotation.to_rotation_matrix().matrix() * offset
            - dh.fixed_view::<3, 3>(0, 0))
        .norm();
        assert!(dp < 1e-12 && dr < 1e-12, "q={q:?}: {dp} m, {dr}");
    }
}

#[test]
fn jacobian_matches_finite_differences() {
    let model = RobotModel::kmr_iiwa14();
    let mut rng = StdRng::seed_from_u64(2);
    let h = 1e-6;
    for _ in 0..100 {
        let q = random_q(&mut rng, &model);
        let jac = ArmKinematics::new(&model, &q).jacobian(&model);
        for i in 0..NA {
            let (mut qp, mut qm) = (q, q);
            qp[i] += h;
            qm[i] -= h;
            let (tp, tm) = (
                ArmKinematics::new(&model, &qp).tcp,
                ArmKinematics::new(&model, &qm).tcp,
            );
            let v = (tp.translation.vector - tm.translation.vector) / (2.0 * h);
            let w = log(&(tp.rotation * tm.rotation.inverse())) / (2.0 * h);
            let col = jac.column(i);
            let err = (col.fixed_rows::<3>(0) - v).norm() + (col.fixed_rows::<3>(3) - w).norm();
            assert!(err < 1e-8, "column {i} at {q:?}: {err}");
        }
    }
}

/// Union-of-spheres coverage slack (radius − distance, best sphere) of a point of `link`.
fn slack(model: &RobotModel, link: u8, p: Vector3<f64>) -> f64 {
    model
        .spheres
        .iter()
        .filter(|s| s.link == link)
        .map(|s| s.radius - (p - s.centre).norm())
        .fold(f64::NEG_INFINITY, f64::max)
}

#[test]
fn spheres_cover_meshes() {
    let model = RobotModel::kmr_iiwa14();
    let rows = fixture("iiwa14_mesh_points.csv");
    let mut per_link = [0usize; 8];
    for r in &rows {
        let link = r[0] as u8;
        per_link[link as usize] += 1;
        let s = slack(&model, link, Vector3::new(r[1], r[2], r[3]));
        assert!(
            s >= 0.0,
            "link {link} point {r:?} outside its spheres by {:.4} m",
            -s
        );
    }
    assert!(per_link.iter().all(|&n| n >= 200), "{per_link:?}");
}

#[test]
fn spheres_cover_gripper_envelope() {
    // The envelope documented in robot.rs: body cylinder r = 0.045, z ∈ [0, 0.09]; fingers
    // 0.015 × 0.024 × 0.07 centred at x = ±0.0375, z ∈ [0.09, 0.16] (flange frame).
    let model = RobotModel::kmr_iiwa14();
    let tool = LINK_TOOL as u8;
    for i in 0..=36 {
        let a = i as f64 / 36.0 * std::f64::consts::TAU;
        for j in 0..=18 {
            let z = 0.09 * j as f64 / 18.0;
            for r in [0.0, 0.045] {
                let p = Vector3::new(r * a.cos(), r * a.sin(), z);
                assert!(slack(&model, tool, p) >= 0.0, "body point {p:?}");
            }
        }
    }
    for side in [-1.0, 1.0] {
        for ix in 0..=4 {
            for iy in 0..=4 {
                for iz in 0..=20 {
                    let p = Vector3::new(
                        side * 0.0375 + (ix as f64 / 4.0 - 0.5) * 0.015,
                        (iy as f64 / 4.0 - 0.5) * 0.024,
                        0.09 + 0.07 * iz as f64 / 20.0,
                    );
                    assert!(slack(&model, tool, p) >= 0.0, "finger point {p:?}");
                }
            }
        }
    }
}

#[test]
fn platform_and_mount_compose() {
    let model = RobotModel::kmr_iiwa14();
    let q_m = [1.0, -2.0, std::f64::consts::FRAC_PI_2];
    let base = platform_pose(q_m);
    // The arm sits 0.33 m ahead of the platform centre: with yaw 90° that is +y in the world.
    let arm = arm_base_pose(&model, q_m).translation.vector;
    assert!(
        (arm - Vector3::new(1.0, -2.0 + 0.33, 0.70)).norm() < 1e-12,
        "{arm:?}"
    );
    assert!((base.translation.vector - Vector3::new(1.0, -2.0, 0.0)).norm() < 1e-12);
}

#[test]
fn limits_are_the_iiwa14_datasheet() {
    let model = RobotModel::kmr_iiwa14();
    let lim = [170.0, 120.0, 170.0, 120.0, 170.0, 120.0, 175.0];
    let speed = [85.0, 85.0, 100.0, 75.0, 130.0, 135.0, 135.0];
    for i in 0..NA {
        assert!((model.joints[i].upper - f64::to_radians(lim[i])).abs() < 1e-15);
        assert!((model.joints[i].lower + f64::to_radians(lim[i])).abs() < 1e-15);
        assert!((model.joints[i].max_speed - f64::to_radians(speed[i])).abs() < 1e-15);
    }
    assert_eq!(
        model
            .limit_violation(&deg([0.0, 121.0, 0.0, 0.0, 0.0, 0.0, 0.0]).into())
            .map(|v| v.0),
        Some(1)
    );
    assert_eq!(model.limit_violation(&[f64::NAN; NA]).map(|v| v.0), Some(0));
    assert!(model.limit_violation(&model.home).is_none());
}

/// The iiwa (every origin a signed permutation, every axis z); joint 4 about −z (Rodrigues'
/// matrix); joint 3's origin turned off the permutations and the flange and TCP turned (matrix
/// products).
fn three_models() -> [RobotModel; 3] {
    let model = RobotModel::kmr_iiwa14();
    let mut flipped = model.clone();
    flipped.joints[3].axis = -Vector3::z_axis();
    let mut tilted = model.clone();
    tilted.joints[2].origin.rotation *= UnitQuaternion::from_euler_angles(0.3, -0.2, 0.1);
    tilted.flange.rotation = UnitQuaternion::from_euler_angles(0.0, 0.0, 0.7);
    tilted.tcp.rotation = UnitQuaternion::from_euler_angles(0.0, 0.4, 0.0);
    [model, flipped, tilted]
}

/// FK by rotation matrices against the previous implementation by unit quaternions (a second
/// implementation): the iiwa (every origin a signed permutation, every axis z), a joint about
/// −z (Rodrigues' matrix), and an origin turned 0.3 rad off the permutations (a matrix
/// product). Every frame, the TCP and the Jacobian agree to 1e-13, and the frames' rotations
/// stay orthonormal to 1e-14 (what the risk's travel bound allows for).
#[test]
fn matrix_fk_matches_quaternion_fk() {
    let mut rng = StdRng::seed_from_u64(20);
    let mut worst = (0.0f64, 0.0f64);
    for m in &three_models() {
        for _ in 0..2000 {
            let q = random_q(&mut rng, m);
            let (ours, reference) = (ArmKinematics::new(m, &q), QuaternionKinematics::new(m, &q));
            let apart = |a: &Pose, b: &Pose| {
                let dp = (a.translation.vector - b.translation.vector).norm();
                dp.max(log(&(a.rotation * b.rotation.inverse())).norm())
            };
            for (a, b) in ours.frames.iter().zip(&reference.frames) {
                worst.0 = worst.0.max(apart(&a.pose(), b));
                let gram = a.rotation.transpose() * a.rotation - Matrix3::identity();
                worst.1 = worst.1.max(gram.norm());
            }
            worst.0 = worst.0.max(apart(&ours.tcp, &reference.tcp));
            let dj = (ours.jacobian(m) - reference.jacobian(m)).abs().max();
            worst.0 = worst.0.max(dj);
        }
    }
    assert!(
        worst.0 < 1e-13,
        "frames, TCP or Jacobian {:e} apart",
        worst.0
    );
    assert!(worst.1 < 1e-14, "RᵀR − I up to {:e}", worst.1);
}

/// What an RDMP step computes (the TCP and the Jacobian alone, `Chain::tcp_and_jacobian`), a
/// run's start (`Chain::tcp`) and what the planner observes (every frame, then
/// `ArmKinematics::jacobian`) are the same bits, so the executor emits what was certified.
#[test]
fn every_entry_point_gives_the_same_bits() {
    let bits = |p: &Pose| {
        let (t, r) = (p.translation.vector, p.rotation.quaternion());
        [t.x, t.y, t.z, r.w, r.i, r.j, r.k].map(f64::to_bits)
    };
    let mut rng = StdRng::seed_from_u64(22);
    for m in &three_models() {
        let chain = Chain::new(m);
        for _ in 0..500 {
            let q = random_q(&mut rng, m);
            let all = chain.kinematics(m, &q);
            let (tcp, j) = chain.tcp_and_jacobian(m, &q);
            assert_eq!(bits(&tcp.pose()), bits(&all.tcp), "q = {q:?}");
            assert_eq!(bits(&chain.tcp(m, &q)), bits(&all.tcp), "q = {q:?}");
            let same = j
                .iter()
                .zip(all.jacobian(m).iter())
                .all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same, "q = {q:?}");
        }
    }
}

/// The quaternion of a rotation matrix on each of its four branches (trace positive, or the
/// largest diagonal entry x, y or z): it rotates like the matrix.
#[test]
fn quaternion_of_a_matrix_rotates_alike() {
    let mut rng = StdRng::seed_from_u64(21);
    let v = Vector3::new(0.3, -1.2, 0.7);
    let mut branches = [false; 4];
    for k in 0..4000 {
        let angle = if k % 2 == 0 {
            3.1
        } else {
            rng.random_range(0.0..std::f64::consts::PI)
        };
        let axis = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let r = UnitQuaternion::from_scaled_axis(axis.normalize() * angle);
        let m = r.to_rotation_matrix().into_inner();
        let d = m.diagonal();
        branches[if m.trace() > 0.0 { 0 } else { 1 + d.imax() }] = true;
        let q = quaternion_of(&m);
        assert!((q.norm() - 1.0).abs() < 1e-15, "{m}");
        assert!((q * v - m * v).norm() < 1e-14, "{m}");
    }
    assert_eq!(branches, [true; 4]);
}

/// A frame's pose error (`Frame::error_from`, the RDMP step's) equals `se3::pose_error` of
/// its pose: the translation bit for bit, the rotation vector within 1e-15 rad below 1.8°
/// (where it comes from the matrix's skew part, a series in place of the quaternion) and bit
/// for bit above, at random configurations and errors from 1e-9 rad to π.
#[test]
fn a_frames_pose_error_is_pose_error_of_its_pose() {
    use prf_shared::se3::{exp, pose_error};
    let model = RobotModel::kmr_iiwa14();
    let chain = Chain::new(&model);
    let mut rng = StdRng::seed_from_u64(23);
    let (mut series, mut worst) = (0, 0.0f64);
    for i in 0..20_000 {
        let (frame, _) = chain.tcp_and_jacobian(&model, &random_q(&mut rng, &model));
        let axis = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)).normalize();
        let angle = match i % 4 {
            0 => rng.random_range(1e-9..1e-6),
            1 => rng.random_range(0.0..0.035),
            2 => rng.random_range(0.029..0.034),
            _ => rng.random_range(0.0..core::f64::consts::PI),
        };
        let pose = frame.pose();
        let mut desired = pose;
        desired.rotation = exp(&(axis * angle)) * pose.rotation;
        desired.translation.vector += Vector3::new(0.01, -0.02, 0.003) * (i % 7) as f64;
        let (e_p, e_r) = frame.error_from(&desired);
        let (want_p, want_r) = pose_error(&desired, &pose);
        assert_eq!(e_p, want_p);
        let d = (e_r - want_r).norm();
        if e_r != want_r {
            assert!(angle < 0.0315, "angle {angle}: {e_r:?} vs {want_r:?}");
            series += 1;
        }
        assert!(d <= 1e-15, "angle {angle}: {d:e} rad apart");
        worst = worst.max(d);
    }
    println!("series taken (and not bit-equal) {series} times; worst {worst:e} rad");
    assert!(series > 5_000, "the series branch was not reached");
}
