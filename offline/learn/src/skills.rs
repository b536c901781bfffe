//! Skill learning (Alg. 3, lines 12–16, 20): TrainRDMP on every Pick and Place arm motion,
//! the skill set K per class (duplicates stored once), and share().

use prf_shared::JointVector;
use prf_shared::dmp::DmpParams;
use prf_shared::kinematics::ArmKinematics;
use prf_shared::limits::MotionLimits;
use prf_shared::motion::{Sample, class};
use prf_shared::rdmp::{Rdmp, RdmpConfig, RdmpError, null_space_coordinate};
use prf_shared::robot::RobotModel;
use prf_shared::timing::pace;

/// A trained arm motion and where it came from.
#[derive(Clone, Debug)]
pub struct ArmSkill {
    pub rdmp: Rdmp,
    /// The demonstrated joint path (for de-duplication and reports), shared with every
    /// [`crate::Knowledge`] taken of the learner: copies of all 64 paths were 3 MB of new
    /// memory per `prf learn --add`, about 1.5 ms of page faults.
    pub path: std::sync::Arc<Vec<[f64; 7]>>,
    pub dt: f64,
}

/// One skill κ = (m, π): class, RDMP (if its generators are learnable), provenance.
#[derive(Clone, Debug, PartialEq)]
pub struct Skill {
    pub class: &'static str,
    pub rdmp: Option<usize>,
    pub location_type: Option<usize>,
    pub part_type: Option<usize>,
    pub demo: String,
    /// Made by share() from a skill of another class.
    pub shared: bool,
}

/// The forward arm motion `samples` as a uniformly sampled path: the samples themselves when
/// their spacing is uniform, otherwise linearly re-sampled at their mean spacing.
pub fn uniform_path(samples: &[Sample]) -> (Vec<[f64; 7]>, f64) {
    let n = samples.len();
    let dt = (samples[n - 1].t - samples[0].t) / (n - 1).max(1) as f64;
    let uniform = samples
        .windows(2)
        .all(|w| ((w[1].t - w[0].t) - dt).abs() < 1e-6 * dt.max(1e-9) + 1e-9);
    if uniform {
        return (samples.iter().map(|s| s.arm).collect(), dt);
    }
    let mut out = Vec::with_capacity(n);
    let mut j = 0;
    for k in 0..n {
        let t = samples[0].t + k as f64 * dt;
        while j + 2 < n && samples[j + 1].t < t {
            j += 1;
        }
        let (a, b) = (&samples[j], &samples[j + 1]);
        let u = ((t - a.t) / (b.t - a.t)).clamp(0.0, 1.0);
        out.push(core::array::from_fn(|i| {
            a.arm[i] + (b.arm[i] - a.arm[i]) * u
        }));
    }
    (out, dt)
}

/// TrainRDMP (Alg. 1) on a uniformly sampled joint path, then paced: τ is scaled by the
/// smallest factor at which the RDMP's reproduction of its demonstration (from the path's
/// first configuration to its last TCP pose, at the runtime's 1 kHz) keeps every joint within
/// the robot's limits ([`prf_shared::timing::pace`]), so a skill is stored at a pace it can be
/// executed at. A skill that cannot be paced keeps its demonstrated τ; the planner refuses it
/// wherever it is too fast.
pub fn train(
    model: &RobotModel,
    path: &[[f64; 7]],
    dt: f64,
    params: &DmpParams,
    min_manipulability: f64,
) -> Result<Rdmp, RdmpError> {
    let mut gamma = vec![0.0; path.len()];
    null_space_coordinate(model, path, min_manipulability, &mut gamma)?;
    let rdmp = Rdmp::train(model, path, &gamma, dt, params)?;
    let (q0, q1) = (
        JointVector::from(path[0]),
        JointVector::from(path[path.len() - 1]),
    );
    let goal = ArmKinematics::new(model, &q1).tcp;
    let limits = MotionLimits::kmr_iiwa(model);
    Ok(
        match pace(model, &limits, &RdmpConfig::default(), &rdmp, &q0, &goal) {
            Ok(t) => rdmp.time_scaled(t.scale),
            Err(_) => rdmp,
        },
    )
}

/// Index of an arm skill with the same path (within 1e-9 rad) in `arms`.
pub fn find_same(arms: &[ArmSkill], path: &[[f64; 7]], dt: f64) -> Option<usize> {
    arms.iter().position(|a| {
        a.path.len() == path.len()
            && (a.dt - dt).abs() < 1e-12
            && a.path
                .iter()
                .zip(path)
                .all(|(x, y)| x.iter().zip(y).all(|(u, v)| (u - v).abs() < 1e-9))
    })
}

/// share() (Sec. 5.3.3): every skill of a class that shares its motion generators with
/// another class is duplicated into that class (Pick ↔ Place: only the gripper action
/// differs), unless an equal skill is there already.
pub fn share(skills: &mut Vec<Skill>) {
    let originals: Vec<Skill> = skills.clone();
    for s in &originals {
        let Some(other) = class(s.class).and_then(|c| c.shares_with()) else {
            continue;
        };
        let exists = skills.iter().any(|k| k.class == other && k.rdmp == s.rdmp);
        if !exists {
            skills.push(Skill {
                class: class(other).map(|c| c.name()).unwrap_or(other),
                shared: true,
                ..s.clone()
            });
        }
    }
}
