//! The cofactor null-space basis against an SVD reference, and its continuity.

mod common;

use common::deg;
use nalgebra::{SMatrix, Vector6};
use prf_shared::kinematics::ArmKinematics;
use prf_shared::nullspace::{kernel, pinv_apply};
use prf_shared::robot::RobotModel;
use prf_shared::{Jacobian, JointVector};
use rand::{RngExt, SeedableRng, rngs::StdRng};

fn jac(model: &RobotModel, q: &JointVector) -> Jacobian {
    ArmKinematics::new(model, q).jacobian(model)
}

#[test]
fn kernel_agrees_with_svd_and_manipulability() {
    let model = RobotModel::kmr_iiwa14();
    let mut rng = StdRng::seed_from_u64(3);
    for _ in 0..200 {
        let q = JointVector::from_fn(|i, _| {
            let j = &model.joints[i];
            rng.random_range(j.lower..j.upper)
        });
        let j = jac(&model, &q);
        let k = kernel(&j);
        // Reference: the right singular vector of the smallest singular value of the 7×7
        // zero-padded Jacobian, and Yoshikawa's sqrt(det(J Jᵀ)).
        let mut padded = SMatrix::<f64, 7, 7>::zeros();
        padded.fixed_view_mut::<6, 7>(0, 0).copy_from(&j);
        let svd = padded.svd(false, true);
        let vt = svd.v_t.unwrap();
        let i_min = svd.singular_values.imin();
        let v_ref = vt.row(i_min).transpose();
        let w_ref = (j * j.transpose()).determinant().max(0.0).sqrt();
        // Orientation: the generalized cross product c_i = (−1)^i det(J without column i).
        let cofactors = JointVector::from_fn(|i, _| {
            let minor = SMatrix::<f64, 6, 6>::from_fn(|r, c| j[(r, if c < i { c } else { c + 1 })]);
            if i % 2 == 0 {
                minor.determinant()
            } else {
                -minor.determinant()
            }
        });
        assert!(
            (cofactors - k.direction * k.manipulability).norm() < 1e-9 * w_ref.max(1e-3),
            "not the cross product"
        );
        assert!(
            (k.manipulability - w_ref).abs() <= 1e-9 * w_ref.max(1e-3),
            "{} vs {w_ref}",
            k.manipulability
        );
        if w_ref > 1e-3 {
            assert!((k.direction.dot(&v_ref).abs() - 1.0).abs() < 1e-9);
            assert!((j * k.direction).norm() < 1e-12);
            assert!((k.direction.norm() - 1.0).abs() < 1e-12);
        }
    }
}

#[test]
fn kernel_is_sign_continuous_along_a_path() {
    let model = RobotModel::kmr_iiwa14();
    let (a, b) = (
        deg([-60.0, 30.0, -40.0, -90.0, 50.0, 40.0, -60.0]),
        deg([70.0, 75.0, 60.0, -30.0, -60.0, 100.0, 80.0]),
    );
    let mut prev = kernel(&jac(&model, &a)).direction;
    let mut svd_flips = 0;
    let mut prev_svd: Option<JointVector> = None;
    for k in 1..=2000 {
        let q = a + (b - a) * (k as f64 / 2000.0);
        let j = jac(&model, &q);
        let ker = kernel(&j);
        assert!(
            ker.manipulability > 1e-3,
            "path passes near a singularity at step {k}"
        );
        // Consecutive directions differ by a small angle, never by a sign.
        assert!(ker.direction.dot(&prev) > 0.99, "flip at step {k}");
        prev = ker.direction;
        let mut padded = SMatrix::<f64, 7, 7>::zeros();
        padded.fixed_view_mut::<6, 7>(0, 0).copy_from(&j);
        let svd = padded.svd(false, true);
        let v = JointVector::from_iterator(
            svd.v_t
                .unwrap()
                .row(svd.singular_values.imin())
                .iter()
                .copied(),
        );
        if let Some(p) = prev_svd {
            svd_flips += usize::from(v.dot(&p) < 0.0);
        }
        prev_svd = Some(v);
    }
    // Not an assertion on the SVD library, only context for the log: its basis may flip.
    println!("SVD basis sign flips along the path: {svd_flips}");
}

#[test]
fn pseudo_inverse_is_minimum_norm_solution() {
    let model = RobotModel::kmr_iiwa14();
    let q = deg([10.0, 40.0, 5.0, -70.0, 3.0, 70.0, 0.0]);
    let j = jac(&model, &q);
    let v = Vector6::new(0.1, -0.2, 0.05, 0.3, 0.0, -0.1);
    let qd = pinv_apply(&j, &v).unwrap();
    assert!((j * qd - v).norm() < 1e-12);
    assert!(
        qd.dot(&kernel(&j).direction).abs() < 1e-12,
        "J⁺V has a null-space component"
    );
    assert!(pinv_apply(&jac(&model, &JointVector::zeros()), &v).is_none());
}

#[test]
fn stretched_arm_is_singular() {
    let model = RobotModel::kmr_iiwa14();
    assert!(kernel(&jac(&model, &JointVector::zeros())).manipulability < 1e-12);
    assert!(kernel(&jac(&model, &JointVector::from(model.home))).manipulability > 0.05);
}

/// The bit patterns of a kernel and an optional solution, for exact comparisons.
fn bits(k: &prf_shared::nullspace::Kernel, x: Option<JointVector>) -> Vec<u64> {
    let mut v: Vec<u64> = k.direction.iter().map(|x| x.to_bits()).collect();
    v.push(k.manipulability.to_bits());
    v.extend(x.iter().flat_map(|x| x.iter().map(|v| v.to_bits())));
    v.push(x.is_some() as u64);
    v
}

/// The RDMP step's QR (unrolled, short chains, Q applied to both vectors at once) agrees with
/// the generic loops it replaced to within rounding, scaled by J's condition number (from
/// nalgebra's SVD); its fused application of Q gives the bits of applying Q to one vector at
/// a time. On random configurations, singular ones (stretched arm, wrist aligned) and a zero
/// Jacobian.
#[test]
fn the_step_qr_agrees_with_the_previous_one() {
    use prf_shared::nullspace::JacobianQr;
    let model = RobotModel::kmr_iiwa14();
    let mut rng = StdRng::seed_from_u64(11);
    let mut jacobians: Vec<Jacobian> = (0..2000)
        .map(|_| {
            let q = JointVector::from_fn(|i, _| {
                let j = &model.joints[i];
                rng.random_range(j.lower..j.upper)
            });
            jac(&model, &q)
        })
        .collect();
    jacobians.push(jac(&model, &JointVector::zeros()));
    jacobians.push(jac(&model, &deg([0.0, 30.0, 0.0, -60.0, 0.0, 0.0, 0.0])));
    jacobians.push(Jacobian::zeros());
    let (mut singular, mut worst) = (0, 0.0f64);
    for j in &jacobians {
        let v = Vector6::from_fn(|_, _| rng.random_range(-1.0..1.0));
        let (new, old) = (JacobianQr::new(j), JacobianQr::new_looped(j));
        let (k, x) = new.kernel_and_pinv(&v);
        assert_eq!(bits(&new.kernel(), new.pinv_apply(&v)), bits(&k, x));
        assert_eq!(new.manipulability().to_bits(), k.manipulability.to_bits());
        let (k_old, x_old) = (old.kernel(), old.pinv_apply(&v));
        assert_eq!(x.is_none(), x_old.is_none());
        singular += x.is_none() as usize;
        let Some(x) = x else { continue };
        let x_old = x_old.unwrap();
        let sv = j.singular_values();
        let cond = sv.max() / sv.min();
        // Relative to rounding (ε) × the condition number.
        let scaled = |d: f64| d / (f64::EPSILON * cond);
        let e = scaled((k.direction - k_old.direction).norm())
            .max(scaled((x - x_old).norm() / x_old.norm()))
            .max(scaled(
                (k.manipulability - k_old.manipulability).abs() / k_old.manipulability,
            ));
        assert!(e < 10.0, "{e:.1} ε·cond apart (cond {cond:.3e})");
        worst = worst.max(e);
    }
    println!("worst difference: {worst:.2} ε·cond");
    assert!(singular >= 2, "the singular cases were not reached");
}
