//! A planned program: the concatenation of the skills of a skill plan (Sec. 6.1,
//! q(t) = ∪ κ_i(y_i0, g_i)), as the segments the executor runs. Each action contributes its
//! class's generator sequence π (Sec. 5.3.1).

use crate::load::{LoadError, Runtime};
use crate::reverse::{MAX_STEPS, ReverseError};
use crate::skill_plan::ArmTiming;
use crate::task_plan::ActionPlan;
use prf_shared::motion::{Generator, Goal};
use prf_shared::se3::Pose;

/// Maximum segments of a program.
pub const MAX_SEGMENTS: usize = 24;

/// One executor segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Segment {
    /// π_BaseMove: the platform drives itself to `goal` (world); the arm holds.
    Base {
        /// Platform goal in the world.
        goal: Pose,
    },
    /// π_ArmRDMP: skill `skill`'s RDMP, slowed down by `scale`, from the current arm
    /// configuration to `goal` (arm base frame), `steps` ticks.
    Arm {
        /// Blob index of the skill.
        skill: u16,
        /// TCP goal in the arm base frame.
        goal: Pose,
        /// Ticks of the motion.
        steps: u32,
        /// Time scale τ / τ_demonstrated ([`prf_shared::rdmp::Rdmp::time_scaled`]).
        scale: f64,
    },
    /// π_Grip: command the gripper and wait for it.
    Grip {
        /// Close (else open).
        close: bool,
    },
    /// ¬π_ArmRDMP: the preceding Arm segment backwards.
    Reverse {
        /// Ticks of the motion.
        steps: u32,
    },
    /// A recovery's retraction ([`crate::recover`]): the arm back onto step `from` of the
    /// certified motion of an Arm segment (the fields are that segment's), then along it
    /// backwards to q_a,H at a reduced speed ([`crate::retract`]).
    Retract {
        /// Blob index of the skill.
        skill: u16,
        /// TCP goal in the arm base frame.
        goal: Pose,
        /// Ticks of the whole forward motion.
        steps: u32,
        /// Its time scale.
        scale: f64,
        /// The step k the arm returns to, 0 ≤ k ≤ steps.
        from: u32,
    },
}

/// The parameters an action was realized with: its goal and, for RDMP generators, its skill
/// and the timing the planner certified.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Realization {
    /// The goal the action was realized with.
    pub goal: Goal,
    /// The skill and its timing (RDMP generators only).
    pub skill: Option<(u16, ArmTiming)>,
}

/// Why a skill plan cannot be turned into a program.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ProgramError {
    /// The blob could not be read.
    Load(LoadError),
    /// Action `action` lacks the goal kind or skill its generators need.
    Realization {
        /// Index of the action in the plan.
        action: usize,
    },
    /// An arm motion is too long to be played backwards.
    Reverse(ReverseError),
    /// More segments than [`MAX_SEGMENTS`].
    TooLong,
}

impl core::fmt::Display for ProgramError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ProgramError::Load(e) => write!(f, "{e}"),
            ProgramError::Realization { action } => write!(
                f,
                "action {action} of the plan lacks the goal or skill its motion needs"
            ),
            ProgramError::Reverse(e) => write!(f, "an arm motion cannot be reversed: {e}"),
            ProgramError::TooLong => {
                write!(f, "the program has more than {MAX_SEGMENTS} segments")
            }
        }
    }
}

impl core::error::Error for ProgramError {}

impl From<LoadError> for ProgramError {
    fn from(e: LoadError) -> Self {
        ProgramError::Load(e)
    }
}

/// A program: the segments the executor runs, in order.
#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    /// The segments.
    pub segments: heapless::Vec<Segment, MAX_SEGMENTS>,
}

impl Program {
    /// Chains the generators of each action with its realization.
    pub fn new(
        rt: &Runtime<'_>,
        actions: &ActionPlan,
        realized: &[Realization],
    ) -> Result<Self, ProgramError> {
        let mut segments = heapless::Vec::new();
        for (i, a) in actions.iter().enumerate() {
            let bad = ProgramError::Realization { action: i };
            let class = rt.class_code(a.class as usize).ok_or(bad)?;
            let r = realized.get(i).ok_or(bad)?;
            let mut arm_steps = 0u32;
            for g in class.generators() {
                let seg = match (g, r.goal, r.skill) {
                    (Generator::BaseMove, Goal::Base(goal), _) => Segment::Base { goal },
                    (Generator::ArmRdmp, Goal::Tcp { pose: goal, .. }, Some((skill, timing))) => {
                        rt.blob
                            .skill(skill as usize)
                            .map_err(LoadError::from)?
                            .rdmp
                            .ok_or(bad)?;
                        let steps = timing.steps as usize;
                        if steps > MAX_STEPS {
                            return Err(ProgramError::Reverse(ReverseError::TooLong { steps }));
                        }
                        arm_steps = timing.steps;
                        Segment::Arm {
                            skill,
                            goal,
                            steps: arm_steps,
                            scale: timing.scale,
                        }
                    }
                    (Generator::ArmRdmpReversed, Goal::Tcp { .. }, Some(_)) => {
                        Segment::Reverse { steps: arm_steps }
                    }
                    (Generator::Grip { close }, _, _) => Segment::Grip { close: *close },
                    _ => return Err(bad),
                };
                segments.push(seg).map_err(|_| ProgramError::TooLong)?;
            }
        }
        Ok(Program { segments })
    }

    /// The program a recovery runs: `first` (a retraction), then this program's segments from
    /// index `at` on.
    pub fn resumed(&self, first: Option<Segment>, at: usize) -> Result<Program, ProgramError> {
        let mut segments = heapless::Vec::new();
        let rest = self.segments.get(at..).unwrap_or(&[]);
        for s in first.iter().chain(rest) {
            segments.push(*s).map_err(|_| ProgramError::TooLong)?;
        }
        Ok(Program { segments })
    }

    /// Ticks the arm segments take (the rest waits on the platform and the gripper).
    pub fn arm_ticks(&self) -> u64 {
        self.segments
            .iter()
            .map(|s| match s {
                Segment::Arm { steps, .. } | Segment::Reverse { steps } => *steps as u64,
                Segment::Retract { from, .. } => *from as u64,
                _ => 0,
            })
            .sum()
    }
}
