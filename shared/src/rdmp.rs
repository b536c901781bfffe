//! Redundancy DMPs (Sec. 4.2): TrainRDMP (Alg. 1) and IntegrateRDMP (Alg. 2).
//!
//! A joint-space demonstration q(t) is split into the TCP trajectory (p(t), R(t)) in the arm
//! base frame and the compact null-space coordinate γ(t) = ∫ Mᵀ(q) dq (Eq. 22, with M from
//! [`crate::nullspace`]); each is encoded as a DMP. Integration drives the three DMPs together
//! and maps their velocities back to the joints, q̇ = J⁺V + Mγ̇, one step per tick.
//!
//! Differences from the letter of Alg. 2, each for accuracy on the robot:
//! - the twist V = [ṗ; ω] is the DMPs' own velocity over the step (no numerical
//!   differentiation of R(t)), and M comes from the cofactor kernel instead of an SVD;
//! - closed-loop IK: V gets `gain` × the pose error between the DMP pose and FK(q), so the
//!   Euler step q ← q + q̇Δt does not drift away from the DMP's TCP path;
//! - γ is measured along the executed path with the same trapezoid rule used in training, and
//!   γ̇ gets `gain` × (γ_DMP − γ_measured): the null-space motion follows the trained γ(t).
//!
//! Singular configurations (manipulability below [`RdmpConfig::min_manipulability`]), joint
//! limits and non-finite values stop integration with a typed [`RdmpError`].

use crate::dmp::{
    Ahead, Basis, DmpError, DmpParams, Forcing, MAX_BASES, MIN_SAMPLES, Phase, PositionDmp,
    PositionState, RotationDmp, RotationState,
};
use crate::kinematics::{ArmKinematics, Chain, Frame};
use crate::nullspace::{JacobianQr, kernel};
use crate::robot::RobotModel;
use crate::se3::{Pose, Rot};
use crate::{Jacobian, JointVector, NA};
use nalgebra::{Isometry3, Translation3, Vector1, Vector3, Vector6};

/// A trained RDMP, w_RDMP = (w_p, w_R, w_γ, γ_g) (Alg. 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rdmp {
    /// TCP position in the arm base frame.
    pub position: PositionDmp<3>,
    /// TCP rotation in the arm base frame.
    pub rotation: RotationDmp,
    /// Compact null-space coordinate γ (γ(0) = 0).
    pub gamma: PositionDmp<1>,
    /// Null-space goal γ_g = γ(t̄), reused unchanged for new goals.
    pub gamma_goal: f64,
    /// Null-space shift δ (beyond the paper, 0 for its RDMP): the run tracks
    /// γ_DMP(t) + δ·h(t/τ), h the minimum-jerk ramp from 0 to 1 ([`shift_ramp`]), so the arm
    /// ends δ along the null space from where the paper's RDMP would leave it. Not learned
    /// (0 in a decoded skill): set per run with [`Rdmp::shifted`]; the planner and executor
    /// run the paper's RDMP.
    pub gamma_shift: f64,
}

impl Rdmp {
    /// An RDMP with no motion (zero weights, default parameters): storage to decode into.
    pub fn empty() -> Self {
        let params = DmpParams::default();
        let forcing = |scaled| Forcing {
            weights: [[0.0; MAX_BASES]; 3],
            scaled: [scaled; 3],
        };
        Rdmp {
            position: PositionDmp {
                params,
                tau: 1.0,
                forcing: forcing(true),
            },
            rotation: RotationDmp {
                params,
                tau: 1.0,
                forcing: forcing(true),
                travel: Vector3::zeros(),
            },
            gamma: PositionDmp {
                params,
                tau: 1.0,
                forcing: Forcing {
                    weights: [[0.0; MAX_BASES]],
                    scaled: [true],
                },
            },
            gamma_goal: 0.0,
            gamma_shift: 0.0,
        }
    }
}

/// Settings of an RDMP integration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RdmpConfig {
    /// Integration step Δt, s (the executor's tick).
    pub dt: f64,
    /// Feedback gain on pose and γ errors, 1/s; gain·Δt must stay well below 1.
    pub gain: f64,
    /// Configurations with sqrt(det(J Jᵀ)) below this are reported as singular.
    pub min_manipulability: f64,
}

impl Default for RdmpConfig {
    fn default() -> Self {
        RdmpConfig {
            dt: 1e-3,
            gain: 50.0,
            min_manipulability: 0.01,
        }
    }
}

/// Why an RDMP could not be trained or integrated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RdmpError {
    /// The underlying DMP failed.
    Dmp(DmpError),
    /// Demonstration sample `sample` is too close to a singularity for a null space.
    SingularDemonstration {
        /// The sample index.
        sample: usize,
        /// Manipulability there.
        manipulability: f64,
    },
    /// Integration reached a near-singular configuration at step `step`.
    Singular {
        /// The step index.
        step: usize,
        /// Manipulability there.
        manipulability: f64,
    },
    /// Integration would leave the position limits of `joint` at step `step`.
    JointLimit {
        /// The step index.
        step: usize,
        /// The joint, 0-based.
        joint: usize,
        /// The value it would take, rad.
        value: f64,
    },
    /// A non-finite value appeared (input or integration) at step/sample `step`.
    NonFinite {
        /// The step or sample index.
        step: usize,
    },
    /// Buffers of different lengths were passed where equal lengths are needed.
    LengthMismatch,
    /// [`RdmpConfig`] out of range (gain < 0, gain·Δt ≥ 1, NaN).
    BadConfig,
    /// `step` was called after the last step.
    Finished,
}

impl core::fmt::Display for RdmpError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            RdmpError::Dmp(e) => write!(f, "{e}"),
            RdmpError::SingularDemonstration {
                sample,
                manipulability,
            } => write!(
                f,
                "demonstration sample {sample} is too close to a singularity (manipulability {manipulability:.2e})"
            ),
            RdmpError::Singular {
                step,
                manipulability,
            } => write!(
                f,
                "the arm reached a near-singular configuration at step {step} (manipulability {manipulability:.2e})"
            ),
            RdmpError::JointLimit { step, joint, value } => write!(
                f,
                "joint A{} would leave its position limits at step {step} ({value:.4} rad)",
                joint + 1
            ),
            RdmpError::NonFinite { step } => {
                write!(f, "a value is not finite (NaN or infinite) at step {step}")
            }
            RdmpError::LengthMismatch => {
                write!(
                    f,
                    "buffers of different lengths where equal lengths are needed"
                )
            }
            RdmpError::BadConfig => write!(
                f,
                "RDMP settings out of range (null-space gain negative or gain × Δt ≥ 1, or NaN)"
            ),
            RdmpError::Finished => write!(f, "the motion already reached its last step"),
        }
    }
}

impl core::error::Error for RdmpError {}

impl From<DmpError> for RdmpError {
    fn from(e: DmpError) -> Self {
        RdmpError::Dmp(e)
    }
}

/// Increment of γ between two configurations (trapezoid rule for ∫ Mᵀ(q) dq, Eq. 22).
#[inline]
fn gamma_increment(m0: &JointVector, m1: &JointVector, q0: &JointVector, q1: &JointVector) -> f64 {
    0.5 * (m0 + m1).dot(&(q1 - q0))
}

/// Alg. 1, lines 3–13: the compact null-space coordinate γ_k along a sampled joint trajectory,
/// written to `gamma` (same length as `q`), γ_0 = 0.
pub fn null_space_coordinate(
    model: &RobotModel,
    q: &[[f64; NA]],
    min_manipulability: f64,
    gamma: &mut [f64],
) -> Result<(), RdmpError> {
    if gamma.len() != q.len() {
        return Err(RdmpError::LengthMismatch);
    }
    let chain = Chain::new(model);
    let mut prev: Option<(JointVector, JointVector)> = None;
    let mut acc = 0.0;
    for (k, (qk, g)) in q.iter().zip(gamma.iter_mut()).enumerate() {
        if qk.iter().any(|v| !v.is_finite()) {
            return Err(RdmpError::NonFinite { step: k });
        }
        let qv = JointVector::from(*qk);
        let ker = kernel(&chain.kinematics(model, &qv).jacobian(model));
        if !(ker.manipulability >= min_manipulability) {
            return Err(RdmpError::SingularDemonstration {
                sample: k,
                manipulability: ker.manipulability,
            });
        }
        if let Some((m0, q0)) = prev {
            acc += gamma_increment(&m0, &ker.direction, &q0, &qv);
        }
        *g = acc;
        prev = Some((ker.direction, qv));
    }
    Ok(())
}

impl Rdmp {
    /// TrainRDMP (Alg. 1) on a joint-space demonstration `q` sampled every `dt` seconds, with
    /// its null-space coordinate `gamma` from [`null_space_coordinate`].
    pub fn train(
        model: &RobotModel,
        q: &[[f64; NA]],
        gamma: &[f64],
        dt: f64,
        params: &DmpParams,
    ) -> Result<Self, RdmpError> {
        let n = q.len();
        if gamma.len() != n {
            return Err(RdmpError::LengthMismatch);
        }
        if n < MIN_SAMPLES {
            return Err(DmpError::TooFewSamples {
                got: n,
                need: MIN_SAMPLES,
            }
            .into());
        }
        if let Some(k) = q.iter().position(|s| s.iter().any(|v| !v.is_finite())) {
            return Err(RdmpError::NonFinite { step: k });
        }
        let chain = Chain::new(model);
        let tcp = |k: usize| chain.tcp(model, &JointVector::from(q[k]));
        let position = PositionDmp::train(params, dt, n, |k| tcp(k).translation.vector)?;
        let rotation = RotationDmp::train(params, dt, n, |k| tcp(k).rotation)?;
        let gamma_dmp = PositionDmp::train(params, dt, n, |k| Vector1::new(gamma[k]))?;
        Ok(Rdmp {
            position,
            rotation,
            gamma: gamma_dmp,
            gamma_goal: gamma[n - 1],
            gamma_shift: 0.0,
        })
    }

    /// The same RDMP with null-space shift δ = `shift` ([`Rdmp::gamma_shift`]).
    pub fn shifted(&self, shift: f64) -> Self {
        Rdmp {
            gamma_shift: shift,
            ..*self
        }
    }

    /// Demonstrated duration τ, s.
    pub fn duration(&self) -> f64 {
        self.position.tau
    }

    /// The same RDMP slowed down by `scale` ≥ 1: every DMP's time constant τ becomes
    /// scale · τ (Eqs. 1, 2 and the canonical system). The continuous trajectory is the same
    /// path, y_s(t) = y(t / scale): speeds fall by 1/scale, accelerations by 1/scale², jerks by
    /// 1/scale³.
    pub fn time_scaled(&self, scale: f64) -> Self {
        let mut r = *self;
        r.position.tau *= scale;
        r.rotation.tau *= scale;
        r.gamma.tau *= scale;
        r
    }
}

/// The minimum-jerk ramp h(s) = 10s³ − 15s⁴ + 6s⁵ of s = t/τ clamped to [0, 1]: from 0 to 1
/// with zero velocity and acceleration at both ends, so a shifted run starts and ends at rest
/// like the paper's.
#[inline]
pub fn shift_ramp(s: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    s * s * s * (10.0 + s * (6.0 * s - 15.0))
}

/// The null-space shift that moves a run ending at `end` toward the configuration
/// `reference` (e.g. the demonstration's last), to first order: Mᵀ(end) · (reference − end),
/// the part of the difference a self-motion can take up (γ̇ = Mᵀq̇, Eq. 22). Shifting the run
/// by it ([`Rdmp::shifted`]) leaves the TCP goal as it is. None at a singular `end`.
pub fn shift_toward(
    model: &RobotModel,
    end: &JointVector,
    reference: &JointVector,
    min_manipulability: f64,
) -> Option<f64> {
    let ker = kernel(&Chain::new(model).kinematics(model, end).jacobian(model));
    let shift = ker.direction.dot(&(reference - end));
    (ker.manipulability >= min_manipulability && shift.is_finite()).then_some(shift)
}

/// One integration step's output: the joint setpoint at step `step`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RdmpStep {
    /// Step index k of `q` (time kΔt).
    pub step: usize,
    /// Joint setpoint at step k.
    pub q: JointVector,
    /// Joint velocity that led from step k−1 to k.
    pub qd: JointVector,
    /// γ of the DMP at step k−1 and as measured along the path up to k−1.
    pub gamma_dmp: f64,
    /// γ measured along the path up to k−1.
    pub gamma_measured: f64,
    /// Manipulability at step k−1.
    pub manipulability: f64,
}

/// IntegrateRDMP (Alg. 2) one step at a time: the executor's per-tick state.
#[derive(Clone, Copy, Debug)]
pub struct RdmpRun {
    q: JointVector,
    position: PositionState<3>,
    rotation: RotationState,
    gamma: PositionState<1>,
    phase: Phase,
    /// Position's, rotation's and γ's f(ζ_{k+1}) of the last step ([`Forcing::current`]); not
    /// in a checkpoint (a resumed run evaluates its first f(ζ_k), to the same bits).
    ahead: (Ahead<3>, Ahead<3>, Ahead<1>),
    gamma_measured: f64,
    /// (M, q) of the previous step, for the trapezoid γ measurement.
    previous: Option<(JointVector, JointVector)>,
    /// How FK composes the model the run started with (the model every step is given).
    chain: Chain,
}

/// The integration state of an [`RdmpRun`] without its derived tables (bases, features):
/// about a quarter of its size, and [`RdmpRun::resume`] continues from it bit-identically.
/// The executor keeps these to replay a motion backwards (Pick's and Place's reversal).
#[derive(Clone, Copy, Debug)]
pub struct RdmpCheckpoint {
    q: JointVector,
    position: PositionState<3>,
    rotation: RotationState,
    gamma: PositionState<1>,
    step: usize,
    n_steps: usize,
    zeta: f64,
    zeta_next: f64,
    gamma_measured: f64,
    previous: Option<(JointVector, JointVector)>,
}

impl RdmpRun {
    /// The state to resume from later.
    pub fn checkpoint(&self) -> RdmpCheckpoint {
        RdmpCheckpoint {
            q: self.q,
            position: self.position,
            rotation: self.rotation,
            gamma: self.gamma,
            step: self.phase.step,
            n_steps: self.phase.n_steps,
            zeta: self.phase.zeta,
            zeta_next: self.phase.zeta_next,
            gamma_measured: self.gamma_measured,
            previous: self.previous,
        }
    }

    /// Continues an integration of `rdmp` from a checkpoint taken with the same RDMP and
    /// step Δt on `model`: the following steps equal those of the original run bit for bit.
    pub fn resume(
        model: &RobotModel,
        rdmp: &Rdmp,
        cfg: &RdmpConfig,
        c: &RdmpCheckpoint,
    ) -> Result<Self, RdmpError> {
        let p = &rdmp.position;
        let mut phase = Phase::resume(&p.params, p.tau, cfg.dt, c.step, c.zeta, c.zeta_next)?;
        phase.n_steps = c.n_steps;
        Ok(RdmpRun {
            q: c.q,
            position: c.position,
            rotation: c.rotation,
            gamma: c.gamma,
            phase,
            ahead: (None, None, None),
            gamma_measured: c.gamma_measured,
            previous: c.previous,
            chain: Chain::new(model),
        })
    }

    /// [`RdmpRun::resume`] in place, for a run of the same RDMP and step Δt: keeps this run's
    /// bases (the costly part of a resume) and continues bit-identically from `c`.
    pub fn resume_from(&mut self, c: &RdmpCheckpoint) {
        self.phase.seek(c.step, c.zeta, c.zeta_next);
        self.phase.n_steps = c.n_steps;
        self.q = c.q;
        self.position = c.position;
        self.rotation = c.rotation;
        self.gamma = c.gamma;
        self.ahead = (None, None, None);
        self.gamma_measured = c.gamma_measured;
        self.previous = c.previous;
    }

    /// Starts an integration from joint configuration `q0` towards the TCP goal `goal`
    /// (arm base frame).
    pub fn new(
        model: &RobotModel,
        rdmp: &Rdmp,
        q0: &JointVector,
        goal: &Pose,
        cfg: &RdmpConfig,
    ) -> Result<Self, RdmpError> {
        Self::new_on(None, &Chain::new(model), model, rdmp, q0, goal, cfg)
    }

    /// [`RdmpRun::new`] with the phase's bases copied from `basis` when they are the RDMP's
    /// ([`Basis::is_for`]): the same run, bit for bit, without computing the n_g bases (the
    /// costly part of a start on a controller without a fast `exp`), and FK composed as
    /// `chain`, which must be `model`'s ([`Chain::new`]; the executor reads it once at load).
    pub fn new_on(
        basis: Option<&Basis>,
        chain: &Chain,
        model: &RobotModel,
        rdmp: &Rdmp,
        q0: &JointVector,
        goal: &Pose,
        cfg: &RdmpConfig,
    ) -> Result<Self, RdmpError> {
        if !(cfg.gain >= 0.0 && cfg.gain * cfg.dt < 1.0 && cfg.min_manipulability >= 0.0) {
            return Err(RdmpError::BadConfig);
        }
        if q0.iter().any(|v| !v.is_finite()) {
            return Err(RdmpError::NonFinite { step: 0 });
        }
        let start = chain.tcp(model, q0);
        // The three DMPs share one phase (the position DMP's, as in `step`): it is built once.
        let (position, phase) = rdmp.position.start_on(
            basis,
            &start.translation.vector,
            &goal.translation.vector,
            cfg.dt,
        )?;
        if goal.rotation.coords.iter().any(|v| !v.is_finite()) || !rdmp.gamma_goal.is_finite() {
            return Err(RdmpError::NonFinite { step: 0 });
        }
        let rotation = RotationState::new(&start.rotation, &goal.rotation, &rdmp.rotation.travel);
        let gamma = PositionState::new(&Vector1::zeros(), &Vector1::new(rdmp.gamma_goal));
        Ok(RdmpRun {
            q: *q0,
            position,
            rotation,
            gamma,
            phase,
            ahead: (None, None, None),
            gamma_measured: 0.0,
            previous: None,
            chain: *chain,
        })
    }

    /// The bases of this run's phase (to start the next run on, [`RdmpRun::new_on`]).
    pub fn basis(&self) -> &Basis {
        &self.phase.basis
    }

    /// Current joint configuration.
    pub fn q(&self) -> &JointVector {
        &self.q
    }

    /// Current TCP pose of the task-space DMPs (arm base frame).
    pub fn dmp_pose(&self) -> Pose {
        Isometry3::from_parts(Translation3::from(self.position.y), self.rotation.r)
    }

    /// (steps done, steps of the whole motion).
    pub fn progress(&self) -> (usize, usize) {
        (self.phase.step, self.phase.n_steps)
    }

    /// Sets the number of steps of the whole motion to `n` (at least the steps already taken):
    /// beyond τ the forcing term fades out ([`crate::dmp::phase::FADE`]) and the DMPs settle
    /// on their goals as the bare critically damped spring of Eq. (1), so a motion may run on
    /// until it is at rest.
    pub fn set_steps(&mut self, n: usize) {
        self.phase.n_steps = n.max(self.phase.step);
    }

    /// True once the last step was taken.
    pub fn finished(&self) -> bool {
        self.phase.finished()
    }

    /// Advances one step Δt (Alg. 2, lines 14–23, closed loop). FK computes the TCP and the
    /// Jacobian alone ([`Chain::tcp_and_jacobian`]), with the bits of
    /// [`RdmpRun::step_observed`]. (The two are written out: sharing their body through a
    /// closure cost 1 % of the step, 48 instructions.)
    pub fn step(
        &mut self,
        model: &RobotModel,
        rdmp: &Rdmp,
        cfg: &RdmpConfig,
    ) -> Result<RdmpStep, RdmpError> {
        if self.phase.finished() {
            return Err(RdmpError::Finished);
        }
        let moved = Moved::of(self);
        let (tcp, j) = self.chain.tcp_and_jacobian(model, &self.q);
        let result = self.advance(model, rdmp, cfg, &tcp, &j);
        if result.is_err() {
            moved.put_back(self);
        }
        result
    }

    /// [`RdmpRun::step`], showing `observe` the kinematics of the configuration it steps
    /// from (so a caller that also needs FK of every configuration computes it once).
    pub fn step_observed(
        &mut self,
        model: &RobotModel,
        rdmp: &Rdmp,
        cfg: &RdmpConfig,
        observe: impl FnOnce(&ArmKinematics),
    ) -> Result<RdmpStep, RdmpError> {
        if self.phase.finished() {
            return Err(RdmpError::Finished);
        }
        // The DMPs step in place; a refused step puts back what they moved (`Moved`), so it
        // leaves the run unchanged without copying the states in and out on every step.
        let moved = Moved::of(self);
        let mut kin = ArmKinematics::identity();
        self.chain.kinematics_into(model, &self.q, &mut kin);
        observe(&kin);
        let tcp = self.chain.tcp_frame_of(model, &kin);
        let result = self.advance(model, rdmp, cfg, &tcp, &kin.jacobian(model));
        if result.is_err() {
            moved.put_back(self);
        }
        result
    }

    /// One part of the DMPs' Heun steps (Alg. 2, lines 14–21), into `out`: the position DMP
    /// (part 0), the rotation DMP (1), γ's (2), then the phase's next features φ(ζ_{k+2}) (3,
    /// [`Phase::prepare`], over the φ(ζ_k) the DMPs have read). None depends on q:
    /// [`RdmpRun::advance`] runs part i after Householder step i of the QR, whose chain (six
    /// square roots and divisions, each waiting on the step before) leaves the processor room
    /// for them. (The order before, the three DMPs before the QR and the features after it,
    /// was 8–9 % slower on an AMD EPYC VM: `prf bench --profile-steps`.)
    #[inline(always)]
    fn dmp_part(&mut self, part: usize, rdmp: &Rdmp, cfg: &RdmpConfig, out: &mut DmpVelocities) {
        let (phase, ahead) = (&self.phase, &mut self.ahead);
        match part {
            0 => {
                let p = &rdmp.position;
                out.v =
                    self.position
                        .step(&p.params, &p.forcing, p.tau, cfg.dt, phase, &mut ahead.0);
            }
            1 => {
                let r = &rdmp.rotation;
                out.w =
                    self.rotation
                        .step(&r.params, &r.forcing, r.tau, cfg.dt, phase, &mut ahead.1);
            }
            2 => {
                let g = &rdmp.gamma;
                out.g = self
                    .gamma
                    .step(&g.params, &g.forcing, g.tau, cfg.dt, phase, &mut ahead.2)[0];
            }
            3 => self.phase.prepare(),
            _ => {}
        }
    }

    /// Step's work after the kinematics: the DMPs, the QR, the joint velocity (Alg. 2 line 7)
    /// and the checks; commits q, γ's measurement and the phase only on success. The work
    /// independent of q (the DMPs and the phase's next features, [`RdmpRun::dmp_part`]) runs
    /// between the QR's Householder steps, where the chain from q to q̇ leaves the processor
    /// idle.
    #[inline(always)]
    fn advance(
        &mut self,
        model: &RobotModel,
        rdmp: &Rdmp,
        cfg: &RdmpConfig,
        tcp: &Frame,
        j: &Jacobian,
    ) -> Result<RdmpStep, RdmpError> {
        let k = self.phase.step;
        let mut dmp = DmpVelocities {
            pose: self.dmp_pose(),
            gamma: self.gamma.y[0],
            v: Vector3::zeros(),
            w: Vector3::zeros(),
            g: 0.0,
        };
        let qr = JacobianQr::new_beside(j, |part| {
            self.dmp_part(part, rdmp, cfg, &mut dmp);
        });
        let manipulability = qr.manipulability();
        if !(manipulability >= cfg.min_manipulability) {
            return Err(RdmpError::Singular {
                step: k,
                manipulability,
            });
        }
        let (e_p, e_r) = tcp.error_from(&dmp.pose);
        let twist = join(&(dmp.v + e_p * cfg.gain), &(dmp.w + e_r * cfg.gain));
        let (ker, pinv) = qr.kernel_and_pinv(&twist);
        let mut gamma_measured = self.gamma_measured;
        if let Some((m0, q0)) = self.previous {
            gamma_measured += gamma_increment(&m0, &ker.direction, &q0, &self.q);
        }
        let (target, rate) = if rdmp.gamma_shift != 0.0 {
            // t/τ at steps k and k + 1 (τ of the position DMP, time-scaled with the others).
            let at = |k: usize| shift_ramp(k as f64 * cfg.dt / rdmp.position.tau);
            let (h0, h1) = (at(k), at(k + 1));
            (
                dmp.gamma + rdmp.gamma_shift * h0,
                dmp.g + rdmp.gamma_shift * (h1 - h0) / cfg.dt,
            )
        } else {
            (dmp.gamma, dmp.g)
        };
        let gamma_rate = rate + cfg.gain * (target - gamma_measured);
        let qd = pinv.ok_or(RdmpError::Singular {
            step: k,
            manipulability,
        })? + ker.direction * gamma_rate;
        let q = self.q + qd * cfg.dt;
        if q.iter().any(|v| !v.is_finite()) {
            return Err(RdmpError::NonFinite { step: k + 1 });
        }
        if let Some((joint, value)) = model.limit_violation(&q.into()) {
            return Err(RdmpError::JointLimit {
                step: k + 1,
                joint,
                value,
            });
        }
        self.phase.advance();
        self.gamma_measured = gamma_measured;
        self.previous = Some((ker.direction, self.q));
        self.q = q;
        Ok(RdmpStep {
            step: k + 1,
            q,
            qd,
            gamma_dmp: dmp.gamma,
            gamma_measured,
            manipulability: ker.manipulability,
        })
    }
}

/// One step's DMP outputs: the DMP pose and γ it stepped from, and the mean velocities over
/// the step (ṗ, ω, γ̇).
struct DmpVelocities {
    pose: Pose,
    gamma: f64,
    v: Vector3<f64>,
    w: Vector3<f64>,
    g: f64,
}

/// What a step's DMPs move (positions, velocities, orientation and the unwrapping reference):
/// kept before the step and put back when it is refused, with the phase's φ(ζ_k)
/// ([`Phase::unprepare`]). The carried forcing values need not be: they name the step they
/// belong to, and a retry at step k evaluates f(ζ_k) again.
#[derive(Clone, Copy)]
struct Moved {
    y: Vector3<f64>,
    z: Vector3<f64>,
    r: Rot,
    eta: Vector3<f64>,
    error: Vector3<f64>,
    gamma: Vector1<f64>,
    gamma_z: Vector1<f64>,
}

impl Moved {
    #[inline(always)]
    fn of(run: &RdmpRun) -> Self {
        let (p, r, g) = (&run.position, &run.rotation, &run.gamma);
        Moved {
            y: p.y,
            z: p.z,
            r: r.r,
            eta: r.eta,
            error: r.error,
            gamma: g.y,
            gamma_z: g.z,
        }
    }

    #[cold]
    fn put_back(&self, run: &mut RdmpRun) {
        (run.position.y, run.position.z) = (self.y, self.z);
        (run.rotation.r, run.rotation.eta, run.rotation.error) = (self.r, self.eta, self.error);
        (run.gamma.y, run.gamma.z) = (self.gamma, self.gamma_z);
        run.phase.unprepare();
    }
}

/// Stacks [v; ω].
#[inline]
fn join(v: &Vector3<f64>, w: &Vector3<f64>) -> Vector6<f64> {
    Vector6::new(v.x, v.y, v.z, w.x, w.y, w.z)
}

/// IntegrateRDMP (Alg. 2) as a whole trajectory: calls `out` for every step after q0 and
/// returns the final configuration.
pub fn integrate(
    model: &RobotModel,
    rdmp: &Rdmp,
    q0: &JointVector,
    goal: &Pose,
    cfg: &RdmpConfig,
    mut out: impl FnMut(&RdmpStep),
) -> Result<JointVector, RdmpError> {
    let mut run = RdmpRun::new(model, rdmp, q0, goal, cfg)?;
    while !run.finished() {
        out(&run.step(model, rdmp, cfg)?);
    }
    Ok(*run.q())
}
