//! Timing RDMP motions within the joint limits (`prf_shared::timing`): a demonstration played
//! too fast is slowed down by scaling τ, not clipped.

mod common;

use common::{deg, joint_demo};
use prf_shared::dmp::DmpParams;
use prf_shared::kinematics::ArmKinematics;
use prf_shared::limits::MotionLimits;
use prf_shared::rdmp::{Rdmp, RdmpConfig, RdmpRun, null_space_coordinate};
use prf_shared::robot::RobotModel;
use prf_shared::timing::{ArmTiming, pace};
use prf_shared::{JointVector, NA};

/// The 2.5 s reach of the RDMP tests, sampled every `dt` (the same samples at a smaller `dt`
/// are the same motion played faster).
fn trained(model: &RobotModel, dt: f64) -> (Rdmp, Vec<[f64; NA]>) {
    let demo = joint_demo(
        deg([-40.0, 20.0, 10.0, -80.0, 10.0, 50.0, -20.0]),
        deg([20.0, 42.0, -15.0, -85.0, -20.0, 60.0, 30.0]),
        0.5,
        2.5,
        0.01,
    );
    let mut gamma = vec![0.0; demo.len()];
    null_space_coordinate(model, &demo, 0.01, &mut gamma).unwrap();
    let rdmp = Rdmp::train(model, &demo, &gamma, dt, &DmpParams::default()).unwrap();
    (rdmp, demo)
}

/// The stream of a timed motion, q0 first.
fn stream(
    model: &RobotModel,
    rdmp: &Rdmp,
    q0: &JointVector,
    demo_end: &[f64; NA],
    t: &ArmTiming,
) -> Vec<[f64; NA]> {
    let cfg = RdmpConfig::default();
    let goal = ArmKinematics::new(model, &JointVector::from(*demo_end)).tcp;
    let rdmp = rdmp.time_scaled(t.scale);
    let mut run = RdmpRun::new(model, &rdmp, q0, &goal, &cfg).unwrap();
    run.set_steps(t.steps as usize);
    let mut out = vec![(*q0).into()];
    while !run.finished() {
        out.push(run.step(model, &rdmp, &cfg).unwrap().q.into());
    }
    out
}

/// Third differences at 1 ms of the stream padded with standstill: (speed, acceleration,
/// jerk) ratios.
fn ratios(s: &[[f64; NA]], l: &MotionLimits) -> [f64; 3] {
    let dt = 1e-3;
    let mut p = vec![s[0]; 3];
    p.extend_from_slice(s);
    p.extend([*s.last().unwrap(); 3]);
    let mut r = [0.0f64; 3];
    for k in 3..p.len() {
        for j in 0..NA {
            let d1 = p[k][j] - p[k - 1][j];
            let d2 = d1 - (p[k - 1][j] - p[k - 2][j]);
            let d3 = d2 - (p[k - 1][j] - 2.0 * p[k - 2][j] + p[k - 3][j]);
            r[0] = r[0].max(d1.abs() / dt / l.arm_speed[j]);
            r[1] = r[1].max(d2.abs() / (dt * dt) / l.arm_acceleration[j]);
            r[2] = r[2].max(d3.abs() / (dt * dt * dt) / l.arm_jerk[j]);
        }
    }
    r
}

#[test]
fn a_fast_demonstration_is_slowed_down_not_clipped() {
    let model = RobotModel::kmr_iiwa14();
    let limits = MotionLimits::kmr_iiwa(&model);
    let cfg = RdmpConfig::default();
    // Played in 2.5 s, and the same samples in 1.25 s: twice as fast.
    let (normal, demo) = trained(&model, 0.01);
    let (fast, _) = trained(&model, 0.005);
    let q0 = JointVector::from(demo[0]);
    let end = demo[demo.len() - 1];
    let goal = ArmKinematics::new(&model, &JointVector::from(end)).tcp;
    let tn = pace(&model, &limits, &cfg, &normal, &q0, &goal).expect("normal");
    let tf = pace(&model, &limits, &cfg, &fast, &q0, &goal).expect("fast");
    println!(
        "normal: τ × {:.3}, {} ticks; fast: τ × {:.3}, {} ticks",
        tn.scale, tn.steps, tf.scale, tf.steps
    );
    // The fast one runs about as long as the normal one (its τ is half).
    assert!(
        tf.scale > 1.5,
        "the fast demonstration is slowed down: τ × {}",
        tf.scale
    );
    let pace_ratio = fast.duration() * tf.scale / (normal.duration() * tn.scale);
    assert!((pace_ratio - 1.0).abs() < 0.1, "{pace_ratio}");
    let (sn, sf) = (
        stream(&model, &normal, &q0, &end, &tn),
        stream(&model, &fast, &q0, &end, &tf),
    );
    for s in [&sn, &sf] {
        let r = ratios(s, &limits);
        assert!(r.iter().all(|x| *x <= 1.0 + 1e-9), "{r:?}");
    }
    // Not clipped: the slowed motion follows the normal one's path to its end.
    let dist = |a: &[f64; NA], b: &[f64; NA]| {
        a.iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
    };
    let mut j = 0;
    for q in &sf {
        while j + 1 < sn.len() && dist(q, &sn[j + 1]) <= dist(q, &sn[j]) {
            j += 1;
        }
        assert!(
            dist(q, &sn[j]) < 2e-3,
            "{} rad off the path",
            dist(q, &sn[j])
        );
    }
    assert!(dist(sf.last().unwrap(), sn.last().unwrap()) < 1e-4);
    // At its own pace the fast demonstration exceeds the limits.
    assert!(
        tf.scale > 1.0
            && ratios(
                &stream(&model, &fast, &q0, &end, &ArmTiming { scale: 1.0, ..tf }),
                &limits
            )
            .iter()
            .any(|x| *x > 1.0)
    );
}

/// `pace` steps by the TCP and Jacobian alone, `pace_observed` computes every frame for its
/// observer: the same streams, so the same timings, bit for bit, whichever rung they end on.
#[test]
fn pacing_without_an_observer_times_as_pacing_with_one() {
    use prf_shared::timing::pace_observed;
    let model = RobotModel::kmr_iiwa14();
    let limits = MotionLimits::kmr_iiwa(&model);
    let cfg = RdmpConfig::default();
    for dt in [0.01, 0.005, 0.002] {
        let (rdmp, demo) = trained(&model, dt);
        let q0 = JointVector::from(demo[0]);
        let end = JointVector::from(demo[demo.len() - 1]);
        let goal = ArmKinematics::new(&model, &end).tcp;
        let alone = pace(&model, &limits, &cfg, &rdmp, &q0, &goal);
        let observed = pace_observed(
            &model,
            &limits,
            &cfg,
            &rdmp,
            &q0,
            &goal,
            usize::MAX,
            true,
            || 0usize,
            Some(|n: &mut usize, _: &ArmKinematics| *n += 1),
        );
        assert_eq!(alone, observed.timing, "samples every {dt} s");
        if let Ok(t) = alone {
            // The observer saw q0 … q_n of the last run.
            assert_eq!(observed.observer, t.steps as usize + 1);
        }
    }
}
