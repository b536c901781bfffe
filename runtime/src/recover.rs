//! Recovery after a fault (issue 18): where a stopped cell is in a task's program, told from
//! its measured state alone (so it works after either process was restarted), and the program
//! that brings it back and completes the task.
//!
//! The platform tells the side (the pick or the place stance of the plan), the gripper whether
//! the part is held, and the arm where it stopped on that side's certified motion: the nearest
//! configuration q_k of the forward RDMP stream (re-integrated exactly as planned). The
//! recovery program starts with a [`Segment::Retract`]: a straight move onto q_k (whose risk
//! is checked in the side's workspace, Eq. 16, like the certified motion's), then q_k … q_0 =
//! q_a,H played back at a reduced speed, every configuration certified by the plan. Then it
//! resumes the task's program:
//!
//! | side | gripper | the arm was | resumes at |
//! |---|---|---|---|
//! | pick | open | reaching for the part | the reach (again) |
//! | pick | closed | retracting with it | the drive to the place stance |
//! | place | closed | reaching to put it down | the reach (again) |
//! | place | open | retracting after it | the drive home |
//!
//! With the arm already at q_a,H nothing is retracted: holding the part, the task resumes at
//! the drive to the place stance; at the place stance with the gripper open, at the drive
//! home; else from its start. A gripper between open and closed, an arm away from q_a,H with
//! the platform at neither stance, or an arm too far from its path are refused: the recovery
//! says what it cannot tell or do.

use crate::executor::{ExecutorConfig, Measured, planar, wrap};
use crate::load::{LoadError, Runtime};
use crate::plan::Plan;
use crate::program::{Program, ProgramError, Segment};
use crate::skill_plan::{PttClasses, PttSides, SkillPlanError, trace_rdmp};
use crate::task::Task;
use prf_shared::kinematics::ArmKinematics;
use prf_shared::rdmp::RdmpError;
use prf_shared::risk::RiskAccumulator;
use prf_shared::se3::Pose;
use prf_shared::{JointVector, NA};

/// Tolerances of the recovery.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecoverConfig {
    /// The arm may be at most this far (largest joint difference, rad) from the nearest
    /// configuration of its certified motion.
    pub max_gap: f64,
    /// The arm is at q_a,H within this (largest joint difference, rad).
    pub at_home: f64,
    /// The platform is at a stance within this distance, m, …
    pub stance_position: f64,
    /// … and this yaw, rad.
    pub stance_yaw: f64,
    /// Spacing of the configurations at which the move onto the path is checked, rad.
    pub check_step: f64,
    /// The gripper is open at or below this (the executor's) …
    pub gripper_open: f64,
    /// … and closed at or above this.
    pub gripper_closed: f64,
}

impl RecoverConfig {
    /// The defaults, with the executor's gripper thresholds.
    pub fn new(executor: &ExecutorConfig) -> Self {
        RecoverConfig {
            max_gap: 0.1,
            at_home: 0.01,
            stance_position: 0.02,
            stance_yaw: 0.02,
            check_step: 1e-3,
            gripper_open: executor.gripper_open,
            gripper_closed: executor.gripper_closed,
        }
    }
}

/// Where the cell was found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Situation {
    /// The arm is at q_a,H: nothing to retract.
    AtHome,
    /// The arm is `gap` rad from step `step` (of `steps`) of the certified motion of segment
    /// `segment`; the straight move onto it has risk `gap_risk`, m.
    OnPath {
        /// The Arm segment.
        segment: u8,
        /// The step k the arm returns to.
        step: u32,
        /// Steps of the motion.
        steps: u32,
        /// Largest joint difference to q_k, rad.
        gap: f64,
        /// Risk of the move onto q_k, m.
        gap_risk: f64,
    },
}

/// What a recovery will do.
#[derive(Clone, Debug, PartialEq)]
pub struct Recovery {
    /// Where the cell was found.
    pub situation: Situation,
    /// The gripper holds the part.
    pub holding: bool,
    /// The index of the task program's segment the recovery resumes at.
    pub resume_at: usize,
    /// The recovery program: the retraction (if any), then the task's segments from
    /// `resume_at`.
    pub program: Program,
}

/// Why no recovery is possible from the measured state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RecoverError {
    /// The plan has no program (it was infeasible) or not Move, Pick, Move, Place, Move.
    NoProgram,
    /// The measured state has a non-finite value.
    NonFinite,
    /// The gripper is between open and closed: whether it holds the part is unknown.
    HalfGripped {
        /// The measured gripper, 0 open … 1 closed.
        gripper: f64,
    },
    /// The arm is away from q_a,H but the platform is at neither stance of the task.
    NoStance {
        /// The platform [x, y, yaw].
        base: [f64; 3],
        /// Largest joint difference to q_a,H, rad.
        gap: f64,
    },
    /// The arm is `gap` rad from the nearest configuration (step `step`) of the certified
    /// motion of segment `segment`: more than allowed.
    OffPath {
        /// The Arm segment.
        segment: u8,
        /// The nearest step.
        step: u32,
        /// Largest joint difference to it, rad.
        gap: f64,
    },
    /// The straight move onto the path would have risk `risk`, m.
    GapRisk {
        /// The risk, m.
        risk: f64,
    },
    /// Re-integrating the certified motion failed.
    Rdmp(RdmpError),
    /// The blob could not be read.
    Load(LoadError),
    /// The task's workspaces could not be set up.
    Skill(SkillPlanError),
    /// The recovery program does not fit.
    Program(ProgramError),
}

impl core::fmt::Display for RecoverError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            RecoverError::NoProgram => write!(
                f,
                "the task has no program to recover along (it is infeasible or not Move, Pick, Move, Place, Move)"
            ),
            RecoverError::NonFinite => write!(f, "the measured state is not finite"),
            RecoverError::HalfGripped { gripper } => write!(
                f,
                "the gripper stopped between open and closed ({gripper:.2}): whether it holds the part cannot be told; open or close it by hand, then recover"
            ),
            RecoverError::NoStance { base, gap } => write!(
                f,
                "the arm is {gap:.3} rad from q_a,H but the platform, at ({:.3} m, {:.3} m, {:.1}°), is at neither stance of this task: no certified path back is known; move the arm to q_a,H by hand",
                base[0],
                base[1],
                base[2].to_degrees()
            ),
            RecoverError::OffPath { segment, step, gap } => write!(
                f,
                "the arm is {gap:.3} rad from its certified path (nearest: step {step} of segment {segment}), more than a recovery may bridge; move it by hand"
            ),
            RecoverError::GapRisk { risk } => write!(
                f,
                "the straight move back onto the certified path has risk {:.1} mm: refused; move the arm by hand",
                risk * 1e3
            ),
            RecoverError::Rdmp(e) => write!(f, "re-integrating the certified motion failed: {e}"),
            RecoverError::Load(e) => write!(f, "{e}"),
            RecoverError::Skill(e) => write!(f, "{e}"),
            RecoverError::Program(e) => write!(f, "{e}"),
        }
    }
}

impl core::error::Error for RecoverError {}

/// Largest joint difference, rad.
fn gap(a: &[f64; NA], b: &[f64; NA]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max(f64::abs(x - y)))
}

/// The nearest configuration of a certified motion to a measured one.
#[derive(Clone, Copy)]
struct Nearest {
    step: u32,
    gap: f64,
    q: [f64; NA],
}

/// The nearest configuration of the forward motion of Arm segment `seg` to `q`.
fn nearest_on_path(
    rt: &Runtime<'_>,
    seg: &Segment,
    q: &[f64; NA],
) -> Result<Nearest, RecoverError> {
    let &Segment::Arm {
        skill,
        goal,
        steps,
        scale,
    } = seg
    else {
        return Err(RecoverError::NoProgram);
    };
    let rdmp = rt
        .skill_rdmp(skill as usize)
        .map_err(RecoverError::Load)?
        .ok_or(RecoverError::NoProgram)?;
    let mut best = Nearest {
        step: 0,
        gap: f64::INFINITY,
        q: rt.model.home,
    };
    let mut step = 0;
    trace_rdmp(rt, &rdmp, &goal, scale, steps, |qk| {
        let qk: [f64; NA] = (*qk).into();
        let d = gap(&qk, q);
        if d < best.gap {
            best = Nearest {
                step,
                gap: d,
                q: qk,
            };
        }
        step += 1;
    })
    .map_err(RecoverError::Rdmp)?;
    Ok(best)
}

/// Risk (Eq. 16) of the straight joint-space move from `a` to `b`, checked every
/// `step` rad, in `field` with the arm base at `arm_base`.
fn line_risk(
    rt: &Runtime<'_>,
    field: &prf_shared::field::Field<'_>,
    arm_base: &Pose,
    a: &[f64; NA],
    b: &[f64; NA],
    step: f64,
) -> f64 {
    let n = libm::ceil(gap(a, b) / step).clamp(1.0, 1e6) as usize;
    let mut acc = RiskAccumulator::default();
    for i in 0..=n {
        let s = i as f64 / n as f64;
        let q = JointVector::from(core::array::from_fn(|j| a[j] + s * (b[j] - a[j])));
        acc.add(
            &rt.model,
            field,
            arm_base,
            &ArmKinematics::new(&rt.model, &q),
        );
    }
    acc.risk()
}

/// Where the cell measured as `m` is in `plan`'s program for `task`, and the program that
/// recovers from there (see the module).
pub fn locate(
    rt: &Runtime<'_>,
    task: &Task<'_>,
    plan: &Plan,
    m: &Measured,
    cfg: &RecoverConfig,
) -> Result<Recovery, RecoverError> {
    let program = plan.program.as_ref().ok_or(RecoverError::NoProgram)?;
    let ((p1, p2), choice) = plan
        .stances
        .zip(plan.skills.choice)
        .ok_or(RecoverError::NoProgram)?;
    let finite = m.arm.iter().chain(&m.base).all(|v| v.is_finite()) && m.gripper.is_finite();
    if !finite {
        return Err(RecoverError::NonFinite);
    }
    let holding = if m.gripper >= cfg.gripper_closed {
        true
    } else if m.gripper <= cfg.gripper_open {
        false
    } else {
        return Err(RecoverError::HalfGripped { gripper: m.gripper });
    };
    let segs = &program.segments;
    let mut arms = segs
        .iter()
        .enumerate()
        .filter(|(_, s)| matches!(s, Segment::Arm { .. }))
        .map(|(i, _)| i);
    let (Some(a1), Some(a2)) = (arms.next(), arms.next()) else {
        return Err(RecoverError::NoProgram);
    };
    // The drive after an arm segment's reversal.
    let drive_after = |a: usize| {
        segs.iter()
            .skip(a)
            .position(|s| matches!(s, Segment::Base { .. }))
            .map_or(segs.len(), |k| a + k)
    };
    let at = |p: &Pose| {
        let g = planar(p);
        libm::hypot(m.base[0] - g[0], m.base[1] - g[1]) <= cfg.stance_position
            && f64::abs(wrap(m.base[2] - g[2])) <= cfg.stance_yaw
    };
    let home_gap = gap(&m.arm, &rt.model.home);
    if home_gap <= cfg.at_home {
        let resume_at = if holding {
            drive_after(a1)
        } else if at(&p2) && !at(&p1) {
            drive_after(a2)
        } else {
            0
        };
        return Ok(Recovery {
            situation: Situation::AtHome,
            holding,
            resume_at,
            program: program
                .resumed(None, resume_at)
                .map_err(RecoverError::Program)?,
        });
    }
    // The side: the stance the platform is at; at both (one stance serving both locations),
    // the motion the arm is nearer to.
    let mut best: Option<(usize, bool, Nearest)> = None;
    for (a, pick, stance) in [(a1, true, &p1), (a2, false, &p2)] {
        if !at(stance) {
            continue;
        }
        let seg = segs.get(a).ok_or(RecoverError::NoProgram)?;
        let near = nearest_on_path(rt, seg, &m.arm)?;
        if best.is_none_or(|b| near.gap < b.2.gap) {
            best = Some((a, pick, near));
        }
    }
    let Some((
        a,
        pick,
        Nearest {
            step,
            gap,
            q: q_step,
        },
    )) = best
    else {
        return Err(RecoverError::NoStance {
            base: m.base,
            gap: home_gap,
        });
    };
    if !(gap <= cfg.max_gap) {
        return Err(RecoverError::OffPath {
            segment: a as u8,
            step,
            gap,
        });
    }
    // The move onto the path, checked in the side's workspace.
    let classes = PttClasses::of(rt).ok_or(RecoverError::NoProgram)?;
    let sides = PttSides::new(rt, task, &plan.resolved, &classes).map_err(RecoverError::Skill)?;
    let (side, stance) = if pick {
        (&sides.pick, choice.stance_from)
    } else {
        (&sides.place, choice.stance_to)
    };
    let arm_base = side
        .arm_bases
        .get(stance as usize)
        .ok_or(RecoverError::NoProgram)?;
    let gap_risk = line_risk(rt, &side.field, arm_base, &m.arm, &q_step, cfg.check_step);
    if !(gap_risk <= rt.config.risk_threshold) {
        return Err(RecoverError::GapRisk { risk: gap_risk });
    }
    let Some(&Segment::Arm {
        skill,
        goal,
        steps,
        scale,
    }) = segs.get(a)
    else {
        return Err(RecoverError::NoProgram);
    };
    // Reaching (pick with the gripper open, place holding the part): do it again; retracting
    // after the gripper acted: go on with the next drive.
    let resume_at = if pick != holding { a } else { drive_after(a) };
    let retract = Segment::Retract {
        skill,
        goal,
        steps,
        scale,
        from: step,
    };
    Ok(Recovery {
        situation: Situation::OnPath {
            segment: a as u8,
            step,
            steps,
            gap,
            gap_risk,
        },
        holding,
        resume_at,
        program: program
            .resumed(Some(retract), resume_at)
            .map_err(RecoverError::Program)?,
    })
}
