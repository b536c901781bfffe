//! Timing of an RDMP motion within the joint limits: the stream an RDMP integration emits at
//! 1 kHz is rated against [`MotionLimits`] ([`ArmMeter`]), and an RDMP too fast for them is
//! slowed down by scaling its time constant τ ([`Rdmp::time_scaled`]: the same path, speeds
//! ÷ s, accelerations ÷ s², jerks ÷ s³). A motion runs for its τ and then on until the arm can
//! stop within the jerk limit (the DMPs settle on their goals), so the stream starts and ends
//! at rest.
//!
//! The compiler paces every learned skill this way on its own demonstration; the planner times
//! every candidate motion the same way before it takes its risk.

use crate::kinematics::ArmKinematics;
use crate::limits::{ArmMeter, LimitRatios, MotionLimits};
use crate::rdmp::{Rdmp, RdmpConfig, RdmpError, RdmpRun};
use crate::robot::RobotModel;
use crate::se3::Pose;
use crate::{JointVector, NA};

/// Largest time scale applied to a motion before it is refused as too fast: τ at most 4 × the
/// RDMP's own.
pub const MAX_TIME_SCALE: f64 = 4.0;
/// Time scales tried per motion before it is refused as too fast.
pub const MAX_TRIALS: usize = 4;

/// How an arm motion is timed: the time scale of its RDMP, its ticks (τ × scale, then on until
/// the arm can stop within the jerk limit, at most τ more) and the limit ratios of exactly the
/// stream it emits, standstill before and after included.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmTiming {
    /// Time scale s (τ_run = s · τ), ≥ 1.
    pub scale: f64,
    /// Ticks of the motion.
    pub steps: u32,
    /// Peak ratios of position, speed, acceleration and jerk to the limits (all ≤ 1).
    pub ratios: LimitRatios,
}

/// What one integration at a fixed time scale came to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Run {
    /// Integrated to rest within the limits.
    Within(ArmTiming),
    /// The stream exceeds a limit: the ratios reached after `steps` steps (the run stops
    /// early once even [`MAX_TIME_SCALE`] could not help).
    TooFast {
        /// Steps taken.
        steps: usize,
        /// Peak ratios reached.
        ratios: LimitRatios,
    },
    /// The RDMP could not be integrated after `steps` steps.
    Failed {
        /// Why.
        error: RdmpError,
        /// Steps taken.
        steps: usize,
    },
    /// The step cap was reached before the run ended.
    Capped,
}

/// Integrates `rdmp` (already time-scaled by `scale`) from `q0` to `goal` (arm base frame),
/// rating its stream, and shows `observe` (if any) the kinematics of every configuration it
/// emits, q0 first and the final one last, as long as the stream stays within the limits (a
/// run that leaves them ends [`Run::TooFast`], and what it observed is of no use). Without an
/// observer each step computes the TCP and Jacobian alone ([`RdmpRun::step`]), not every
/// frame: the same stream.
#[allow(clippy::too_many_arguments)]
pub fn run_at(
    model: &RobotModel,
    limits: &MotionLimits,
    cfg: &RdmpConfig,
    rdmp: &Rdmp,
    q0: &JointVector,
    goal: &Pose,
    scale: f64,
    cap: usize,
    mut observe: Option<impl FnMut(&ArmKinematics)>,
) -> Run {
    let mut run = match RdmpRun::new(model, rdmp, q0, goal, cfg) {
        Ok(r) => r,
        Err(error) => return Run::Failed { error, steps: 0 },
    };
    let nominal = run.progress().1;
    let mut meter = ArmMeter::at_rest(limits, cfg.dt, &(*q0).into());
    let mut steps = 0;
    // The ratios last found hopeful: they only grow, and only a new peak needs a new look.
    let mut hopeful = None;
    // Still within the limits: once not, the run is too fast whatever follows, and nothing
    // more is shown to `observe` (a run that is not the rated one has no use for it).
    let mut within = true;
    // Each step shows the FK of the configuration it leaves: q_0 … q_{n−1}; q_n comes last.
    loop {
        if steps >= cap {
            return Run::Capped;
        }
        let step = match observe.as_mut() {
            Some(observe) if within => run.step_observed(model, rdmp, cfg, observe),
            _ => run.step(model, rdmp, cfg),
        };
        let q = match step {
            Ok(s) => s.q,
            Err(error) => return Run::Failed { error, steps },
        };
        steps += 1;
        meter.push(&q.into());
        let ratios = meter.ratios();
        if hopeful != Some(ratios) {
            if hopeless(&ratios, scale) {
                return Run::TooFast { steps, ratios };
            }
            hopeful = Some(ratios);
            within = ratios.within();
        }
        if steps >= nominal {
            if meter.stop_ratios().within() || steps >= 2 * nominal {
                break;
            }
            run.set_steps(steps + 1);
        }
    }
    meter.stop();
    if !meter.ratios().within() {
        return Run::TooFast {
            steps,
            ratios: meter.ratios(),
        };
    }
    if let Some(observe) = observe.as_mut() {
        let q: [f64; NA] = *meter.last();
        observe(&ArmKinematics::new(model, &JointVector::from(q)));
    }
    Run::Within(ArmTiming {
        scale,
        steps: steps as u32,
        ratios: meter.ratios(),
    })
}

/// The factor by which a stream that reached `r` must be slowed down: speed scales with 1/s,
/// acceleration with 1/s², jerk with 1/s³.
fn slow_down(r: &LimitRatios) -> f64 {
    r.speed
        .max(crate::float::sqrt(r.acceleration))
        .max(libm::cbrt(r.jerk))
}

/// True when even [`MAX_TIME_SCALE`] cannot bring a stream at `scale` within the limits (or a
/// ratio is NaN): integrating on would be wasted.
fn hopeless(r: &LimitRatios, scale: f64) -> bool {
    !(scale * slow_down(r) <= MAX_TIME_SCALE && r.position <= 1.0)
}

/// The next time scale to try after a stream at `scale` reached `ratios` (the scaling laws
/// with a 2 % margin, at least 2 % slower); `None` beyond [`MAX_TIME_SCALE`].
pub fn next_scale(scale: f64, ratios: &LimitRatios) -> Option<f64> {
    let next = scale * (1.02 * slow_down(ratios)).max(1.02);
    (next <= MAX_TIME_SCALE).then_some(next)
}

/// Why a motion could not be timed within the limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimingError {
    /// Even slowed down to the last scale tried the stream exceeds a limit.
    TooFast {
        /// The last time scale tried.
        scale: f64,
        /// The ratios it reached.
        ratios: LimitRatios,
    },
    /// The RDMP could not be integrated.
    Rdmp(RdmpError),
    /// The step cap ran out before the timing was settled.
    Capped,
}

impl core::fmt::Display for TimingError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            TimingError::TooFast { scale, ratios } => write!(
                f,
                "the motion exceeds a joint limit even slowed down to τ × {scale:.2} ({ratios})"
            ),
            TimingError::Rdmp(e) => write!(f, "{e}"),
            TimingError::Capped => {
                write!(f, "the step budget ran out before the timing was settled")
            }
        }
    }
}

impl core::error::Error for TimingError {}

/// A motion timed by [`pace_observed`]: the timing (or why there is none), the observer of the
/// last run (the one whose stream is the timing's) and the steps of all runs.
#[derive(Clone, Copy, Debug)]
pub struct Paced<O> {
    /// The timing within the limits, or why there is none.
    pub timing: Result<ArmTiming, TimingError>,
    /// What observed the last run.
    pub observer: O,
    /// Integration steps of all runs.
    pub steps: usize,
}

/// Steps of the probe run at [`MAX_TIME_SCALE`] that [`pace_observed`] takes first.
pub const PROBE_STEPS: usize = 3;

/// The smallest time scale on the ladder 1, [`next_scale`], … at which `rdmp` from `q0` to
/// `goal` stays within `limits`, with its timing. Each run gets a `fresh()` observer that
/// `observe` (if any) shows every configuration's kinematics; without one the runs step by
/// the TCP and Jacobian alone ([`run_at`]). At most `cap` steps in all runs together
/// ([`TimingError::Capped`] when they run out).
///
/// With `probe` (the planner's and the compiler's way), first the first [`PROBE_STEPS`] of
/// the slowest run the ladder may try. The stream leaves rest there with the DMPs' initial
/// accelerations, which fall as 1/s² with the time scale s (the first step's jerk, its
/// displacement ÷ Δt³, with them): a stream that leaves the limits at [`MAX_TIME_SCALE`]
/// within those steps leaves them at every faster scale too, so it is
/// [`TimingError::TooFast`] without a full run per rung. (Without the probe such a motion
/// takes a whole run at scale 1, its peak set in the first step, before the ladder learns
/// it; a test checks that both come to the same verdict.)
#[allow(clippy::too_many_arguments)]
pub fn pace_observed<O>(
    model: &RobotModel,
    limits: &MotionLimits,
    cfg: &RdmpConfig,
    rdmp: &Rdmp,
    q0: &JointVector,
    goal: &Pose,
    cap: usize,
    probe: bool,
    mut fresh: impl FnMut() -> O,
    mut observe: Option<impl FnMut(&mut O, &ArmKinematics)>,
) -> Paced<O> {
    let mut steps = 0;
    if probe {
        let slowest = rdmp.time_scaled(MAX_TIME_SCALE);
        let probe_cap = PROBE_STEPS.min(cap);
        steps = match run_at(
            model,
            limits,
            cfg,
            &slowest,
            q0,
            goal,
            MAX_TIME_SCALE,
            probe_cap,
            None::<fn(&ArmKinematics)>,
        ) {
            Run::TooFast { steps, ratios } => {
                return Paced {
                    timing: Err(TimingError::TooFast {
                        scale: MAX_TIME_SCALE,
                        ratios,
                    }),
                    observer: fresh(),
                    steps,
                };
            }
            Run::Within(t) => t.steps as usize,
            Run::Failed { steps, .. } => steps,
            Run::Capped => probe_cap,
        };
    }
    let mut scale = 1.0;
    let mut trials = 0;
    loop {
        let mut observer = fresh();
        let scaled = rdmp.time_scaled(scale);
        let left = cap.saturating_sub(steps);
        let shown = observe
            .as_mut()
            .map(|observe| |k: &ArmKinematics| observe(&mut observer, k));
        let run = run_at(model, limits, cfg, &scaled, q0, goal, scale, left, shown);
        trials += 1;
        let timing = match run {
            Run::Within(t) => {
                steps += t.steps as usize;
                Ok(t)
            }
            Run::Failed { error, steps: n } => {
                steps += n;
                Err(TimingError::Rdmp(error))
            }
            Run::Capped => {
                steps += left;
                Err(TimingError::Capped)
            }
            Run::TooFast { steps: n, ratios } => {
                steps += n;
                match next_scale(scale, &ratios) {
                    Some(s) if trials < MAX_TRIALS => {
                        scale = s;
                        continue;
                    }
                    _ => Err(TimingError::TooFast { scale, ratios }),
                }
            }
        };
        return Paced {
            timing,
            observer,
            steps,
        };
    }
}

/// [`pace_observed`] without an observer: its runs step by the TCP and Jacobian alone.
pub fn pace(
    model: &RobotModel,
    limits: &MotionLimits,
    cfg: &RdmpConfig,
    rdmp: &Rdmp,
    q0: &JointVector,
    goal: &Pose,
) -> Result<ArmTiming, TimingError> {
    pace_observed(
        model,
        limits,
        cfg,
        rdmp,
        q0,
        goal,
        usize::MAX,
        true,
        || (),
        None::<fn(&mut (), &ArmKinematics)>,
    )
    .timing
}
