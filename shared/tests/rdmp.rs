//! RDMPs (Alg. 1 and 2) on joint-space demonstrations of the iiwa 14.

mod common;

use common::{deg, joint_demo};
use nalgebra::{Isometry3, Translation3, Vector3};
use prf_shared::dmp::DmpParams;
use prf_shared::kinematics::{ArmKinematics, Chain};
use prf_shared::rdmp::{
    Rdmp, RdmpConfig, RdmpError, RdmpRun, integrate, null_space_coordinate, shift_toward,
};
use prf_shared::robot::RobotModel;
use prf_shared::se3::{exp, log};
use prf_shared::{JointVector, NA};

const DEMO_DT: f64 = 0.01;

struct Fixture {
    model: RobotModel,
    demo: Vec<[f64; NA]>,
    gamma: Vec<f64>,
    rdmp: Rdmp,
    cfg: RdmpConfig,
}

/// A 2.5 s reach from a folded pose to a table-height grasp with an elbow swivel on the way;
/// the grasp sits mid-workspace (shoulder–wrist 0.6 of 0.82 m; q4 stays ≥ 35° from its limit) so ±10 cm goals are reachable.
fn fixture() -> Fixture {
    let model = RobotModel::kmr_iiwa14();
    let cfg = RdmpConfig::default();
    let demo = joint_demo(
        deg([-40.0, 20.0, 10.0, -80.0, 10.0, 50.0, -20.0]),
        deg([20.0, 42.0, -15.0, -85.0, -20.0, 60.0, 30.0]),
        0.5,
        2.5,
        DEMO_DT,
    );
    let mut gamma = vec![0.0; demo.len()];
    null_space_coordinate(&model, &demo, cfg.min_manipulability, &mut gamma).unwrap();
    let rdmp = Rdmp::train(&model, &demo, &gamma, DEMO_DT, &DmpParams::default()).unwrap();
    Fixture {
        model,
        demo,
        gamma,
        rdmp,
        cfg,
    }
}

fn tcp(model: &RobotModel, q: &JointVector) -> Isometry3<f64> {
    ArmKinematics::new(model, q).tcp
}

#[test]
fn reproduces_its_demonstration() {
    let f = fixture();
    let q0 = JointVector::from(f.demo[0]);
    let goal = tcp(&f.model, &JointVector::from(*f.demo.last().unwrap()));
    let ratio = (DEMO_DT / f.cfg.dt).round() as usize;
    let (mut sq, mut max, mut count) = (0.0, 0.0f64, 0usize);
    let mut gamma_gap = 0.0f64;
    integrate(&f.model, &f.rdmp, &q0, &goal, &f.cfg, |s| {
        if s.step % ratio == 0 {
            let d = s.q - JointVector::from(f.demo[s.step / ratio]);
            sq += d.norm_squared() / NA as f64;
            max = max.max(d.amax());
            count += 1;
        }
        gamma_gap = gamma_gap.max((s.gamma_dmp - s.gamma_measured).abs());
    })
    .unwrap();
    let rmse = (sq / count as f64).sqrt();
    println!(
        "RDMP reproduction: joint RMSE {rmse:.2e} rad, max {max:.2e} rad, γ gap {gamma_gap:.1e}"
    );
    assert!(rmse < 1e-3 && max < 5e-3, "RMSE {rmse} rad, max {max} rad");
    assert!(gamma_gap < 1e-3, "γ gap {gamma_gap}");
}

#[test]
fn null_space_coordinate_follows_trained_gamma() {
    // Recompute γ along the executed path with the training code (Alg. 1) and compare with
    // the demonstration's γ(t): the swivel was reproduced, not just the TCP path.
    let f = fixture();
    assert!(
        f.gamma.last().unwrap().abs() > 0.05
            || f.gamma.iter().fold(0.0f64, |m, g| m.max(g.abs())) > 0.1,
        "demo has no null-space motion"
    );
    let q0 = JointVector::from(f.demo[0]);
    let goal = tcp(&f.model, &JointVector::from(*f.demo.last().unwrap()));
    let ratio = (DEMO_DT / f.cfg.dt).round() as usize;
    let mut path = vec![f.demo[0]];
    integrate(&f.model, &f.rdmp, &q0, &goal, &f.cfg, |s| {
        if s.step % ratio == 0 {
            path.push(s.q.into());
        }
    })
    .unwrap();
    let mut gamma = vec![0.0; path.len()];
    null_space_coordinate(&f.model, &path, f.cfg.min_manipulability, &mut gamma).unwrap();
    let max = gamma
        .iter()
        .zip(&f.gamma)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!("γ along the executed path vs demonstration: max gap {max:.2e}");
    assert!(max < 2e-3, "{max}");
}

#[test]
fn reaches_new_goals_within_10_cm() {
    // 26 directions (axes, edge and corner diagonals), each a goal 10 cm from the
    // demonstrated one, with the goal orientation tilted by up to 0.1 rad as well.
    let f = fixture();
    let q0 = JointVector::from(f.demo[0]);
    let demo_goal = tcp(&f.model, &JointVector::from(*f.demo.last().unwrap()));
    let mut worst = (0.0f64, 0.0f64);
    let mut count = 0;
    for dx in [-1.0, 0.0, 1.0] {
        for dy in [-1.0, 0.0, 1.0] {
            for dz in [-1.0, 0.0, 1.0] {
                let dir = Vector3::new(dx, dy, dz);
                if dir.norm() == 0.0 {
                    continue;
                }
                let offset = dir.normalize() * 0.1;
                let tilt = exp(&(Vector3::new(dy, -dx, dz) * 0.1 / dir.norm()));
                let goal = Isometry3::from_parts(
                    Translation3::from(demo_goal.translation.vector + offset),
                    tilt * demo_goal.rotation,
                );
                let q = integrate(&f.model, &f.rdmp, &q0, &goal, &f.cfg, |_| {})
                    .unwrap_or_else(|e| panic!("goal offset {offset:?}: {e:?}"));
                let end = tcp(&f.model, &q);
                let dp = (end.translation.vector - goal.translation.vector).norm();
                let dr = log(&(end.rotation * goal.rotation.inverse())).norm();
                worst = (worst.0.max(dp), worst.1.max(dr));
                count += 1;
            }
        }
    }
    assert_eq!(count, 26);
    println!(
        "new goals: worst end error {:.2e} m, {:.2e} deg",
        worst.0,
        worst.1.to_degrees()
    );
    assert!(worst.0 < 1e-3 && worst.1 < 0.5f64.to_radians(), "{worst:?}");
}

#[test]
fn goal_through_a_singularity_is_reported() {
    let f = fixture();
    let q0 = JointVector::from(f.demo[0]);
    let demo_goal = tcp(&f.model, &JointVector::from(*f.demo.last().unwrap()));
    // 1.5 m further out: beyond the arm's 1.27 m reach, it must stretch through the boundary
    // singularity (or hit a limit) and say so instead of integrating garbage.
    let goal = Isometry3::from_parts(
        Translation3::from(demo_goal.translation.vector + Vector3::new(1.5, 0.0, 0.0)),
        demo_goal.rotation,
    );
    match integrate(&f.model, &f.rdmp, &q0, &goal, &f.cfg, |_| {}) {
        Err(RdmpError::Singular {
            manipulability,
            step,
        }) => {
            assert!(manipulability < f.cfg.min_manipulability && step > 0);
        }
        other => panic!("expected a singularity error, got {other:?}"),
    }
}

#[test]
fn refused_step_leaves_the_run_unchanged() {
    // Joint 1 may move only 2° further than its start: the reach must hit that limit, and
    // retrying must give the same refusal (no half-advanced DMP or γ state).
    let mut f = fixture();
    let q0 = JointVector::from(f.demo[0]);
    let goal = tcp(&f.model, &JointVector::from(*f.demo.last().unwrap()));
    f.model.joints[0].upper = q0[0] + 2f64.to_radians();
    let mut run = RdmpRun::new(&f.model, &f.rdmp, &q0, &goal, &f.cfg).unwrap();
    let err = loop {
        match run.step(&f.model, &f.rdmp, &f.cfg) {
            Ok(_) => assert!(!run.finished(), "limit never reached"),
            Err(e) => break e,
        }
    };
    assert!(
        matches!(err, RdmpError::JointLimit { joint: 0, .. }),
        "{err:?}"
    );
    let (q_before, pose_before, progress) = (*run.q(), run.dmp_pose(), run.progress());
    assert_eq!(run.step(&f.model, &f.rdmp, &f.cfg).unwrap_err(), err);
    assert_eq!(
        (*run.q(), run.dmp_pose(), run.progress()),
        (q_before, pose_before, progress)
    );
    // No trace at all (velocities, orientation, γ, the carried forcing values): with the limit
    // lifted, the refused run continues bit for bit as a run that was never refused.
    let mut free = f.model.clone();
    free.joints[0].upper = f64::INFINITY;
    let mut reference = RdmpRun::new(&free, &f.rdmp, &q0, &goal, &f.cfg).unwrap();
    while reference.progress() != progress {
        reference.step(&free, &f.rdmp, &f.cfg).unwrap();
    }
    while !reference.finished() {
        assert_eq!(
            run.step(&free, &f.rdmp, &f.cfg).unwrap(),
            reference.step(&free, &f.rdmp, &f.cfg).unwrap()
        );
    }
    assert!(run.finished());
}

#[test]
fn bad_input_gives_typed_errors() {
    let f = fixture();
    let goal = tcp(&f.model, &JointVector::from(*f.demo.last().unwrap()));
    let nan = JointVector::from_element(f64::NAN);
    assert!(matches!(
        RdmpRun::new(&f.model, &f.rdmp, &nan, &goal, &f.cfg),
        Err(RdmpError::NonFinite { .. })
    ));
    let mut bad_demo = f.demo.clone();
    bad_demo[20][3] = f64::INFINITY;
    let mut g = vec![0.0; bad_demo.len()];
    assert_eq!(
        null_space_coordinate(&f.model, &bad_demo, 0.01, &mut g),
        Err(RdmpError::NonFinite { step: 20 })
    );
    assert_eq!(
        null_space_coordinate(&f.model, &f.demo, 0.01, &mut g[1..]),
        Err(RdmpError::LengthMismatch)
    );
    let stretched = vec![[0.0; NA]; 10];
    let mut g = vec![0.0; 10];
    assert!(matches!(
        null_space_coordinate(&f.model, &stretched, 0.01, &mut g),
        Err(RdmpError::SingularDemonstration { sample: 0, .. })
    ));
    let mut run = RdmpRun::new(
        &f.model,
        &f.rdmp,
        &JointVector::from(f.demo[0]),
        &goal,
        &f.cfg,
    )
    .unwrap();
    while !run.finished() {
        run.step(&f.model, &f.rdmp, &f.cfg).unwrap();
    }
    assert_eq!(
        run.step(&f.model, &f.rdmp, &f.cfg).unwrap_err(),
        RdmpError::Finished
    );
}

/// A run started on another run's bases steps as a run that computed its own, bit for bit,
/// when they are the same DMP parameters; bases of other parameters are not taken.
#[test]
fn a_run_started_on_reused_bases_steps_as_a_fresh_one() {
    let f = fixture();
    let q0 = JointVector::from(f.demo[0]);
    let goal = tcp(&f.model, &JointVector::from(*f.demo.last().unwrap()))
        * Translation3::new(0.03, -0.02, 0.01);
    let bits = |run: &mut RdmpRun| -> Vec<u64> {
        let mut out = Vec::new();
        while !run.finished() {
            let s = run.step(&f.model, &f.rdmp, &f.cfg).unwrap();
            out.extend(s.q.iter().chain(s.qd.iter()).map(|v| v.to_bits()));
        }
        out
    };
    let fresh = bits(&mut RdmpRun::new(&f.model, &f.rdmp, &q0, &goal, &f.cfg).unwrap());
    // The bases of a run of another RDMP with the same parameters (another duration).
    let other = f.rdmp.time_scaled(1.7);
    let donor = RdmpRun::new(&f.model, &other, &q0, &goal, &f.cfg).unwrap();
    assert!(donor.basis().is_for(&f.rdmp.position.params));
    let chain = Chain::new(&f.model);
    let start_on = |basis: Option<&prf_shared::dmp::Basis>| {
        RdmpRun::new_on(basis, &chain, &f.model, &f.rdmp, &q0, &goal, &f.cfg)
    };
    let mut reused = start_on(Some(donor.basis()));
    assert_eq!(bits(reused.as_mut().unwrap()), fresh);
    // Bases of other parameters are not taken: 20 bases, or another phase rate.
    for params in [
        DmpParams {
            n_basis: 20,
            ..f.rdmp.position.params
        },
        DmpParams {
            alpha_zeta: f.rdmp.position.params.alpha_zeta * (1.0 + f64::EPSILON),
            ..f.rdmp.position.params
        },
    ] {
        let basis = prf_shared::dmp::Basis::new(&params).unwrap();
        assert!(!basis.is_for(&f.rdmp.position.params));
        let mut run = start_on(Some(&basis)).unwrap();
        assert_eq!(bits(&mut run), fresh);
    }
    // Bad parameters are refused as without reused bases.
    let mut bad = f.rdmp;
    bad.position.params.alpha_z = f64::NAN;
    assert!(RdmpRun::new(&f.model, &bad, &q0, &goal, &f.cfg).is_err());
    assert_eq!(
        RdmpRun::new_on(
            Some(donor.basis()),
            &Chain::new(&f.model),
            &f.model,
            &bad,
            &q0,
            &goal,
            &f.cfg
        )
        .err(),
        RdmpRun::new(&f.model, &bad, &q0, &goal, &f.cfg).err()
    );
}

#[test]
fn a_null_space_shift_moves_the_arm_along_its_self_motion_to_the_reference() {
    // A goal 5 cm off the demonstrated one; the paper's RDMP ends at q_end. A reference
    // configuration 0.15 rad along the null space from q_end (same TCP to first order): the
    // shift toward it is 0.15, and the shifted run ends at the goal, nearer the reference,
    // with γ measured along its path (Alg. 1, independently) grown by the shift.
    let f = fixture();
    let q0 = JointVector::from(f.demo[0]);
    let demo_goal = tcp(&f.model, &JointVector::from(*f.demo.last().unwrap()));
    let goal = Isometry3::from_parts(
        Translation3::from(demo_goal.translation.vector + Vector3::new(0.03, -0.04, 0.0)),
        demo_goal.rotation,
    );
    let run = |rdmp: &Rdmp| {
        let mut path = vec![<[f64; NA]>::from(q0)];
        let end = integrate(&f.model, rdmp, &q0, &goal, &f.cfg, |s| {
            path.push(s.q.into())
        })
        .unwrap();
        (end, path)
    };
    let (end, path) = run(&f.rdmp);
    // Shift 0 is the paper's RDMP, bit for bit.
    assert_eq!(run(&f.rdmp.shifted(0.0)).1, path);
    let ker = prf_shared::nullspace::kernel(&ArmKinematics::new(&f.model, &end).jacobian(&f.model));
    let reference = end + ker.direction * 0.15;
    let shift = shift_toward(&f.model, &end, &reference, f.cfg.min_manipulability).unwrap();
    assert!((shift - 0.15).abs() < 1e-12, "{shift}");
    let (shifted_end, shifted_path) = run(&f.rdmp.shifted(shift));
    let at = tcp(&f.model, &shifted_end);
    let dp = (at.translation.vector - goal.translation.vector).norm();
    let dr = log(&(at.rotation * goal.rotation.inverse())).norm();
    assert!(dp < 1e-3 && dr < 0.5f64.to_radians(), "{dp} m, {dr} rad");
    let (before, after) = ((end - reference).norm(), (shifted_end - reference).norm());
    println!("null-space shift 0.15 rad: end {before:.4} → {after:.4} rad from the reference");
    assert!(after < 0.1 * before, "{before} → {after}");
    let gamma_end = |p: &[[f64; NA]]| {
        let mut g = vec![0.0; p.len()];
        null_space_coordinate(&f.model, p, f.cfg.min_manipulability, &mut g).unwrap();
        g[g.len() - 1]
    };
    let grown = gamma_end(&shifted_path) - gamma_end(&path);
    assert!(
        (grown - shift).abs() < 2e-3,
        "γ grew {grown}, shift {shift}"
    );
    // Starts and ends at rest like the paper's: the first and last steps barely move.
    let step =
        |p: &[[f64; NA]], k: usize| (JointVector::from(p[k + 1]) - JointVector::from(p[k])).amax();
    let n = shifted_path.len() - 2;
    assert!(step(&shifted_path, 0) <= step(&path, 0) + 1e-9);
    assert!(step(&shifted_path, n) < 1e-5, "{}", step(&shifted_path, n));
}

#[test]
fn the_shift_ramp_is_a_minimum_jerk_step() {
    // h(0) = 0, h(1) = 1, h' and h'' vanish at both ends (finite differences), monotone.
    let h = prf_shared::rdmp::shift_ramp;
    assert_eq!((h(0.0), h(1.0), h(-1.0), h(2.0)), (0.0, 1.0, 0.0, 1.0));
    let e = 1e-4;
    for s in [0.0, 1.0] {
        let d1 = (h(s + e) - h(s - e)) / (2.0 * e);
        let d2 = (h(s + e) - 2.0 * h(s) + h(s - e)) / (e * e);
        assert!(d1.abs() < 1e-6 && d2.abs() < 1e-2, "at {s}: {d1}, {d2}");
    }
    assert!((1..1000).all(|i| h(i as f64 / 1000.0) > h((i - 1) as f64 / 1000.0)));
    assert!((h(0.5) - 0.5).abs() < 1e-15);
}
