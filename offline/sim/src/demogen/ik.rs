//! Inverse kinematics of the 7-axis arm with a consistent choice among the redundant
//! solutions: Newton steps on the TCP error through J⁺, with the self-motion (the null space,
//! Sec. 4.2.1) driven toward a preferred configuration (the home pose q_a,H). From several
//! deterministic seeds the converged solution closest to the preferred configuration wins.

use prf_shared::kinematics::ArmKinematics;
use prf_shared::nullspace::JacobianQr;
use prf_shared::robot::RobotModel;
use prf_shared::se3::{Pose, pose_error};
use prf_shared::{JointVector, NA};

/// Why no IK solution was returned.
#[derive(Clone, Debug, PartialEq)]
pub enum IkError {
    /// No seed converged within the joint limits: the pose is out of reach.
    Unreachable {
        position_error: f64,
        rotation_error: f64,
    },
    /// Solutions exist but every one failed the caller's acceptance test (e.g. collision).
    Rejected { solutions: usize, reason: String },
}

impl std::fmt::Display for IkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            IkError::Unreachable {
                position_error,
                rotation_error,
            } => write!(
                f,
                "unreachable: best residual {:.1} mm, {:.2} deg",
                position_error * 1e3,
                rotation_error.to_degrees()
            ),
            IkError::Rejected { solutions, reason } => {
                write!(
                    f,
                    "all {solutions} IK solutions rejected; the closest to home: {reason}"
                )
            }
        }
    }
}

/// Tolerances and effort of the solver.
#[derive(Clone, Copy, Debug)]
pub struct IkConfig {
    /// Position tolerance, m.
    pub position_tol: f64,
    /// Rotation tolerance, rad.
    pub rotation_tol: f64,
    pub max_iterations: usize,
    /// Null-space gain toward the preferred configuration per iteration.
    pub null_gain: f64,
    /// Margin kept from joint limits, rad.
    pub limit_margin: f64,
}

impl Default for IkConfig {
    fn default() -> Self {
        IkConfig {
            position_tol: 1e-7,
            rotation_tol: 1e-7,
            max_iterations: 400,
            null_gain: 0.3,
            limit_margin: 2f64.to_radians(),
        }
    }
}

/// Solves from one seed. Returns the configuration and the final residuals.
fn solve_from(
    model: &RobotModel,
    target: &Pose,
    seed: &JointVector,
    preferred: &JointVector,
    cfg: &IkConfig,
) -> (JointVector, f64, f64) {
    let mut q = *seed;
    let clamp = |q: &mut JointVector| {
        for i in 0..NA {
            let j = &model.joints[i];
            q[i] = q[i].clamp(j.lower + cfg.limit_margin, j.upper - cfg.limit_margin);
        }
    };
    clamp(&mut q);
    for _ in 0..cfg.max_iterations {
        let kin = ArmKinematics::new(model, &q);
        let (dp, dr) = pose_error(target, &kin.tcp);
        let (ep, er) = (dp.norm(), dr.norm());
        let qr = JacobianQr::new(&kin.jacobian(model));
        // Limit the Cartesian step so Newton stays in its region of validity.
        let scale = (0.1 / ep.max(1e-12)).min(0.3 / er.max(1e-12)).min(1.0);
        let mut v = nalgebra::Vector6::zeros();
        v.fixed_rows_mut::<3>(0).copy_from(&(dp * scale));
        v.fixed_rows_mut::<3>(3).copy_from(&(dr * scale));
        let Some(task) = qr.pinv_apply(&v) else {
            // Singular: nudge toward the preferred configuration and retry.
            q += (preferred - q) * 0.1;
            continue;
        };
        let m = qr.kernel().direction;
        let null = m * (m.dot(&(preferred - q)) * cfg.null_gain);
        let step = task + null;
        q += step;
        clamp(&mut q);
        if ep < cfg.position_tol && er < cfg.rotation_tol && null.norm() < 1e-6 {
            break;
        }
    }
    let kin = ArmKinematics::new(model, &q);
    let (dp, dr) = pose_error(target, &kin.tcp);
    (q, dp.norm(), dr.norm())
}

/// Deterministic seeds with their null-space targets: the preferred configuration and joint-1 /
/// elbow variants drawn toward it, then swivel variants (joint 3 turned) that keep their own
/// swivel, so the solution set spans the self-motion manifold.
fn seeds(preferred: &JointVector) -> Vec<(JointVector, JointVector)> {
    let mut out = vec![(*preferred, *preferred)];
    let attracted: [[f64; NA]; 6] = [
        [0.6, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [-0.6, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, 0.5, 0.8, 0.0, 0.0, 0.0, 0.0],
        [0.0, 0.5, -0.8, 0.0, 0.0, 0.0, 0.0],
        [0.0, 0.3, 0.0, -0.5, 0.8, 0.5, 0.0],
        [0.0, 0.3, 0.0, -0.5, -0.8, 0.5, 0.0],
    ];
    for o in attracted {
        out.push((preferred + JointVector::from(o), *preferred));
    }
    for swivel in [-1.2, -0.8, -0.4, 0.4, 0.8, 1.2] {
        for q1 in [-0.4, 0.0, 0.4] {
            let s = preferred + JointVector::from([q1, 0.0, swivel, 0.0, -swivel, 0.0, 0.0]);
            out.push((s, s));
        }
    }
    out
}

/// All distinct converged solutions for `target` (TCP in the arm base frame), sorted by
/// distance to `preferred` (closest first).
pub fn solutions(
    model: &RobotModel,
    target: &Pose,
    preferred: &JointVector,
    cfg: &IkConfig,
) -> Result<Vec<JointVector>, IkError> {
    let mut found: Vec<JointVector> = Vec::new();
    let (mut best_p, mut best_r) = (f64::INFINITY, f64::INFINITY);
    for (seed, attractor) in seeds(preferred) {
        let (q, ep, er) = solve_from(model, target, &seed, &attractor, cfg);
        if ep < cfg.position_tol * 10.0 && er < cfg.rotation_tol * 10.0 {
            if !found.iter().any(|f| (f - q).norm() < 1e-3) {
                found.push(q);
            }
        } else if ep + er < best_p + best_r {
            best_p = ep;
            best_r = er;
        }
    }
    if found.is_empty() {
        return Err(IkError::Unreachable {
            position_error: best_p,
            rotation_error: best_r,
        });
    }
    found.sort_by(|a, b| (a - preferred).norm().total_cmp(&(b - preferred).norm()));
    Ok(found)
}

/// The solution closest to `preferred` that `accept` admits (`accept` says why not).
pub fn solve(
    model: &RobotModel,
    target: &Pose,
    preferred: &JointVector,
    cfg: &IkConfig,
    accept: impl Fn(&JointVector) -> Result<(), String>,
) -> Result<JointVector, IkError> {
    let all = solutions(model, target, preferred, cfg)?;
    let mut first_reason = None;
    for q in &all {
        match accept(q) {
            Ok(()) => return Ok(*q),
            Err(reason) => {
                first_reason.get_or_insert(reason);
            }
        }
    }
    Err(IkError::Rejected {
        solutions: all.len(),
        reason: first_reason.unwrap_or_default(),
    })
}
