//! Program generation (Sec. 6): task validation, symbolic feasibility, task planning,
//! SkillPlan-PTT, and the program the executor runs.

use crate::load::{LoadError, Runtime};
use crate::program::{Program, ProgramError, Realization};
use crate::recall::{Kept, Recall};
use crate::skill_plan::{
    self, PttClasses, PttSides, SkillPlan, SkillPlanError, plan_skills_within,
};
use crate::task::{MissingList, Resolved, Task, TaskError};
use crate::task_plan::{ActionPlan, plan_actions};
use prf_shared::motion::Goal;
use prf_shared::se3::Pose;

/// A planned task.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The task's names resolved to blob indices.
    pub resolved: Resolved,
    /// The action plan (Move, Pick, Move, Place, Move).
    pub actions: ActionPlan,
    /// The skill plan: choice, J*, feasibility, work counts.
    pub skills: SkillPlan,
    /// The program of the choice (also when J* exceeds the threshold, for inspection).
    pub program: Option<Program>,
    /// Platform poses (world) of the chosen stances at ℓ1 and ℓ2.
    pub stances: Option<(Pose, Pose)>,
}

/// Why no plan came out.
#[derive(Clone, Debug, PartialEq)]
pub enum PlanError<'t> {
    /// The task itself is malformed.
    Task(TaskError),
    /// Symbolically infeasible: the blob lacks what is listed.
    Infeasible(MissingList<'t>),
    /// The action templates cannot reach the goal state.
    NoActionPlan,
    /// SkillPlan-PTT failed.
    Skill(SkillPlanError),
    /// The chosen skills do not form a program.
    Program(ProgramError),
    /// The blob could not be read.
    Load(LoadError),
}

impl From<LoadError> for PlanError<'_> {
    fn from(e: LoadError) -> Self {
        PlanError::Load(e)
    }
}

impl From<SkillPlanError> for PlanError<'_> {
    fn from(e: SkillPlanError) -> Self {
        PlanError::Skill(e)
    }
}

impl core::fmt::Display for PlanError<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PlanError::Task(e) => write!(f, "bad task: {e}"),
            PlanError::Infeasible(missing) => {
                write!(f, "symbolically infeasible: missing ")?;
                for (i, m) in missing.iter().enumerate() {
                    if i > 0 {
                        write!(f, ", ")?;
                    }
                    write!(f, "{m}")?;
                }
                Ok(())
            }
            PlanError::NoActionPlan => write!(f, "no action plan reaches the goal state"),
            PlanError::Skill(e) => write!(f, "skill planning failed: {e}"),
            PlanError::Program(e) => write!(f, "the chosen skills do not form a program: {e}"),
            PlanError::Load(e) => write!(f, "{e}"),
        }
    }
}

/// A `PlanError` borrows the task's names (`Missing<'t>`), so it converts into a `'static`
/// error box only once the task outlives it; callers format it (`{e}`) instead.
impl core::error::Error for PlanError<'_> {}

/// Plans `task`: validation, symbolic feasibility (Sec. 6.1), forward task planning,
/// SkillPlan-PTT (Alg. 4), program.
// Without a heap the list of missing items travels by value (about 200 bytes).
#[allow(clippy::result_large_err)]
pub fn plan<'t>(rt: &Runtime<'_>, task: &Task<'t>) -> Result<Plan, PlanError<'t>> {
    plan_recalling(rt, task, None)
}

/// Plans task after task on one runtime, keeping the evaluations of arm motion candidates
/// for the tasks after them ([`crate::recall`]): a pick or place side that several tasks
/// share is integrated once. Each plan is the one [`plan`] gives; only
/// [`crate::skill_plan::PlanStats`] differ (integrations and steps done, candidates
/// recalled).
pub struct Planner<'r, 'a, 's> {
    rt: &'r Runtime<'a>,
    recall: Recall<'s>,
}

impl<'r, 'a, 's> Planner<'r, 'a, 's> {
    /// A planner on `rt` that has evaluated nothing yet and keeps evaluations in `slots`
    /// (208 B each; the host tools give [`crate::recall::HOST_SLOTS`]).
    pub fn new(rt: &'r Runtime<'a>, slots: &'s mut [Option<Kept>]) -> Self {
        Planner {
            rt,
            recall: Recall::new(slots),
        }
    }

    /// Plans `task` as [`plan`] does, recalling what earlier tasks evaluated.
    #[allow(clippy::result_large_err)]
    pub fn plan<'t>(&mut self, task: &Task<'t>) -> Result<Plan, PlanError<'t>> {
        plan_recalling(self.rt, task, Some(&mut self.recall))
    }
}

/// [`plan`], with evaluations recalled and kept in `recall` when given.
#[allow(clippy::result_large_err)]
fn plan_recalling<'t>(
    rt: &Runtime<'_>,
    task: &Task<'t>,
    recall: Option<&mut Recall<'_>>,
) -> Result<Plan, PlanError<'t>> {
    task.validate().map_err(PlanError::Task)?;
    let resolved = task.resolve(rt)?.map_err(PlanError::Infeasible)?;
    let actions = plan_actions(rt)?.ok_or(PlanError::NoActionPlan)?;
    let classes = PttClasses::of(rt).ok_or(PlanError::Skill(SkillPlanError::UnsupportedPlan))?;
    if !classes.matches(&actions) {
        return Err(PlanError::Skill(SkillPlanError::UnsupportedPlan));
    }
    let sides = PttSides::new(rt, task, &resolved, &classes)?;
    let skills = plan_skills_within(rt, &sides, rt.config.plan_budget, recall)?;
    let (mut program, mut stances) = (None, None);
    if let (Some(c), Some((t1, t2))) = (skills.choice, skills.timing) {
        let (s1, s2, g) = (
            c.stance_from as usize,
            c.stance_to as usize,
            c.grasp as usize,
        );
        let missing = SkillPlanError::UnsupportedPlan;
        let p1 = *sides.pick.platform.get(s1).ok_or(missing)?;
        let p2 = *sides.place.platform.get(s2).ok_or(missing)?;
        let pick_goal = *sides.pick.goal(s1, g).ok_or(missing)?;
        let place_goal = *sides.place.goal(s2, g).ok_or(missing)?;
        let grasp = skill_plan::grasp(rt, resolved.part_type, g)?.ok_or(missing)?;
        let realized = [
            Realization {
                goal: Goal::Base(p1),
                skill: None,
            },
            Realization {
                goal: Goal::Tcp {
                    pose: pick_goal,
                    grasp,
                },
                skill: Some((c.pick_skill, t1)),
            },
            Realization {
                goal: Goal::Base(p2),
                skill: None,
            },
            Realization {
                goal: Goal::Tcp {
                    pose: place_goal,
                    grasp,
                },
                skill: Some((c.place_skill, t2)),
            },
            Realization {
                goal: Goal::Base(task.home),
                skill: None,
            },
        ];
        program = Some(Program::new(rt, &actions, &realized).map_err(PlanError::Program)?);
        stances = Some((p1, p2));
    }
    Ok(Plan {
        resolved,
        actions,
        skills,
        program,
        stances,
    })
}
