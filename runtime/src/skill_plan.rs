//! SkillPlan-PTT (Alg. 4), decomposed and pruned.
//!
//! The paper's grid evaluates J = max(r_Pick, r_Place) over stances(ℓ1) × stances(ℓ2) ×
//! grasps × K_Pick × K_Place. r_Pick depends only on (stance 1, grasp, pick skill) and r_Place
//! only on (stance 2, grasp, place skill), so per grasp the optimum is the maximum of two
//! independent minima: a sum of work instead of a product. Two prunings keep the optimum:
//! - an integration stops as soon as its running risk reaches the side's best so far or the
//!   best J of an earlier grasp (risk only grows along a trajectory, so it cannot win);
//! - a side stops at risk 0, and the search stops at J = 0.
//!
//! **Admissible bounds** ([`Side::bound`]) skip integrations that cannot win. The stream of a
//! candidate starts at q_a,H and ends with its TCP within [`REACH_POSITION`] and
//! [`REACH_ANGLE`] of its goal (a candidate that ends farther away did not reach it and is
//! refused, [`Evaluation::Missed`]). So, before integrating, its risk is at least that of
//! q_a,H at its stance, and at least that of the spheres rigid with the TCP (link 7 and the
//! tool) anywhere within the reach tolerance of the goal pose
//! ([`Field::distance_lower_within`]). A candidate whose bound reaches the limit it would
//! have to beat is skipped exactly as a pruned one (it cannot win, and ties go to earlier
//! candidates), and so is a grasp whose two sides' smallest bounds reach the best J so far:
//! the optimum and the tie order stay the brute-force grid's.
//!
//! **Budget.** With [`PlanBudget`] the search stops once the RDMP steps spent (failed
//! integrations included) reach the budget, within an integration if need be, and says what it
//! knows: the best plan found (an upper bound of J*) and the smallest bound of what was not
//! searched (a lower bound of J*).
//!
//! **Decide first** ([`Search::DecideFirst`], the default). The question a task asks first is
//! whether J* ≤ the risk threshold. The search runs once with every candidate pruned as soon
//! as its risk exceeds the threshold: no field lookups after that (its integration still runs
//! to the end, where its time scale, and so the stream rated, is settled), no later grasp
//! searched for a better J, no place side for a pick side above the threshold. If that finds
//! a plan, it is the optimum's own choice (the optimum
//! search's sides keep the first candidate of least risk, and every candidate it could prefer
//! is at most the threshold too, so neither search stops it); otherwise J* > threshold is
//! proven, and the optimum search runs for the best risky plan in what is left of the budget.
//! Either way [`SkillPlan::decided`] says the feasibility is known even if that second search
//! runs out. [`Search::Optimum`] is the single search, kept as the baseline.
//!
//! **Order and ties.** Candidates of a side for a grasp are ordered stance-major (blob order
//! of the stances); within a stance, skills learned at this location type come first, then
//! the others, each group by the distance of the skill's demonstrated TCP goal to the
//! candidate's goal (|Δp| + 0.1 m/rad · ∠ΔR), then by blob index: the skill whose
//! demonstration ended nearest is tried first. Of the plans with the least J the one chosen
//! minimises, in this order, the grasp index, r_Pick, the pick candidate's position, r_Place,
//! the place candidate's position. (Among equally risky plans the safest pick and place are
//! preferred.) The brute-force test sorts the full grid by this key. Grasps are searched in
//! the order of their admissible bound, then index; a grasp of smaller index than the best
//! plan's needs only to equal its J, so the choice is the one index order would make.
//!
//! The risk is that of exactly the trajectory the executor will run: the RDMP integrated from
//! q_a,H with the executor's step Δt, at every configuration including q_a,H (the reversed
//! motion and the gripper wait revisit the same configurations).

use crate::load::{LoadError, Runtime};
use crate::recall::{Candidate, Recall};
use crate::task::{Resolved, Task};
use crate::task_plan::{Action, ActionPlan, FROM, HOME, TO};
use prf_shared::field::Field;
use prf_shared::kinematics::{ArmKinematics, tcp_rigid_spheres};
use prf_shared::limits::LimitRatios;
use prf_shared::motion::{Goal, GoalContext, MotionClass, PhysicalState};
use prf_shared::rdmp::{Rdmp, RdmpError, RdmpRun};
use prf_shared::risk::{RiskAccumulator, eta};
use prf_shared::se3::{Pose, angle_between, pose_from_array};
pub use prf_shared::timing::{ArmTiming, MAX_TIME_SCALE};
use prf_shared::timing::{TimingError, pace_observed};
use prf_shared::{JointVector, blob::MAX_AFFORDANCES};

/// The classes a part-transportation plan uses.
pub const PTT_CLASSES: [&str; 3] = ["Pick", "Place", "Move"];
/// Skills ordered per pass over a class ([`Side::candidates`]): the candidates come in pages
/// of this many, each page one pass over the class's skills, so a class of any size is
/// ordered in fixed memory (1 KiB), and a search that stops early (risk 0) pays one pass.
pub const ORDER_PAGE: usize = 64;
/// Weight of the rotation in the goal distance that orders skills, m/rad.
pub const ROTATION_WEIGHT: f64 = 0.1;
/// Maximum (stance, grasp) goals of one side.
pub const MAX_GOALS: usize = 64;
/// A candidate reaches its goal when its final TCP is this close to the goal position, m.
/// The RDMP's closed loop ends the example cell's candidates within 0.21 mm and 0.57 mrad
/// (`every_timed_candidate_ends_on_its_goal`); the tighter the tolerance, the tighter
/// [`goal_bound`] (it proves more offsets risky without integrating: 1 mm and 5 mrad proved
/// 136 of the 206 risky ones of a ±20 mm, ±10° envelope, these 154).
pub const REACH_POSITION: f64 = 5e-4;
/// ... and this close to the goal orientation, rad.
pub const REACH_ANGLE: f64 = 1.5e-3;

/// The decision variables of SkillPlan-PTT: indices of stance at ℓ1, stance at ℓ2 and grasp
/// in the blob's affordance lists, and the blob indices of the pick and place skills.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Choice {
    /// Stance at ℓ1.
    pub stance_from: u8,
    /// Stance at ℓ2.
    pub stance_to: u8,
    /// Grasp.
    pub grasp: u8,
    /// Pick skill (blob index).
    pub pick_skill: u16,
    /// Place skill (blob index).
    pub place_skill: u16,
}

/// Counts of the work done.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PlanStats {
    /// RDMP integrations started.
    pub integrations: u32,
    /// ... of which stopped early by the bound.
    pub pruned: u32,
    /// ... of which failed (singular, joint limit, non-finite).
    pub failed: u32,
    /// ... of which exceeded a joint limit even at [`MAX_TIME_SCALE`].
    pub too_fast: u32,
    /// ... of which ended too far from their goal ([`Evaluation::Missed`]).
    pub missed: u32,
    /// Candidates not integrated because their admissible bound could not win.
    pub bounded: u32,
    /// Integration steps taken in total.
    pub steps: u64,
    /// Integrations the paper's full grid would run (2 per grid point).
    pub grid_integrations: u64,
    /// Candidates answered by a [`Recall`] instead of integrated.
    pub recalled: u32,
    /// Steps charged to the [`PlanBudget`]: `steps` and those the recalled evaluations took
    /// when they were integrated (so a plan does not depend on what was planned before it).
    pub charged: u64,
}

impl PlanStats {
    /// Counts an integration that came to `e`.
    fn count(&mut self, e: &Evaluation) {
        self.integrations += 1;
        self.steps += e.steps() as u64;
        self.charged += e.steps() as u64;
        match e {
            Evaluation::Pruned { .. } => self.pruned += 1,
            Evaluation::Failed { .. } => self.failed += 1,
            Evaluation::TooFast { .. } => self.too_fast += 1,
            Evaluation::Missed { .. } => self.missed += 1,
            Evaluation::Risk { .. } | Evaluation::Capped { .. } => {}
        }
    }
}

/// The result of SkillPlan-PTT.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkillPlan {
    /// The optimum; `None` when no candidate integrates at all.
    pub choice: Option<Choice>,
    /// J* = max(r_Pick, r_Place) of the choice (∞ without a choice), m.
    pub j: f64,
    /// Risk r_Pick of the chosen pick motion, m.
    pub r_pick: f64,
    /// Risk r_Place of the chosen place motion, m.
    pub r_place: f64,
    /// Timing of the chosen pick and place motions.
    pub timing: Option<(ArmTiming, ArmTiming)>,
    /// J* ≤ the configured risk threshold.
    pub feasible: bool,
    /// The work done.
    pub stats: PlanStats,
    /// The budget ran out before the search ended: J* is at least this (m) and at most `j`.
    pub exhausted: Option<f64>,
    /// J* is at least this, m: `j` when the search ended, the smallest bound of what was not
    /// searched when the budget ran out, just above the threshold when [`Search::Decide`]
    /// refuted it, ∞ when no candidate integrates at all.
    pub lower: f64,
    /// Whether `feasible` is proven: a plan within the threshold was found, or J* is known to
    /// exceed it (`lower` above it), even if `exhausted`.
    pub decided: bool,
}

/// How SkillPlan-PTT searches (see the module): both give the same plan when J* is within
/// the risk threshold and the budget lasts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Search {
    /// Prove or refute J* ≤ threshold first, then search the optimum only if it is refuted.
    #[default]
    DecideFirst,
    /// Only prove or refute J* ≤ threshold: a refuted task has no plan, and `lower` just
    /// above the threshold (what an envelope needs).
    Decide,
    /// The optimum search alone (the baseline).
    Optimum,
}

/// How much work one task's skill planning may do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlanBudget {
    /// RDMP integration steps, all candidates and time scales together, steps of failed
    /// integrations included; no integration continues past it.
    pub steps: u64,
}

impl PlanBudget {
    /// No limit.
    pub const UNLIMITED: PlanBudget = PlanBudget { steps: u64::MAX };
    /// The host tools' default: 2,000,000 steps, 1–2 s on one core, enough to decide the
    /// example cell's tasks with their parts a few millimetres off ([`Search::DecideFirst`]).
    pub const HOST: PlanBudget = PlanBudget { steps: 2_000_000 };
}

/// What an arm motion candidate came to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Evaluation {
    /// Fully integrated within the limits: its risk (Eq. 16) and timing.
    Risk {
        /// Risk (Eq. 16), m.
        risk: f64,
        /// Time scale, ticks and limit ratios of the motion.
        timing: ArmTiming,
        /// Integration steps taken (all time scales tried).
        steps: usize,
    },
    /// Its risk reached the bound: it cannot win.
    Pruned {
        /// Integration steps taken (all time scales tried).
        steps: usize,
    },
    /// The RDMP could not be integrated.
    Failed {
        /// Why.
        error: RdmpError,
        /// Integration steps taken (all time scales tried).
        steps: usize,
    },
    /// The stream ended with its TCP farther from the goal than [`REACH_POSITION`] or
    /// [`REACH_ANGLE`]: it does not reach the goal.
    Missed {
        /// Final TCP position error, m.
        position: f64,
        /// Final TCP orientation error, rad.
        angle: f64,
        /// Integration steps taken (all time scales tried).
        steps: usize,
    },
    /// Even at [`MAX_TIME_SCALE`] the stream would exceed a joint limit.
    TooFast {
        /// The last time scale tried.
        scale: f64,
        /// The ratios it reached (a run stops early once no scale up to the bound can help).
        ratios: LimitRatios,
        /// Integration steps taken (all time scales tried).
        steps: usize,
    },
    /// The step cap ran out first: nothing is known about the candidate.
    Capped {
        /// Integration steps taken (all of the cap).
        steps: usize,
    },
}

impl Evaluation {
    /// Integration steps the evaluation took.
    pub fn steps(&self) -> usize {
        match *self {
            Evaluation::Risk { steps, .. }
            | Evaluation::Pruned { steps }
            | Evaluation::Failed { steps, .. }
            | Evaluation::Missed { steps, .. }
            | Evaluation::TooFast { steps, .. }
            | Evaluation::Capped { steps } => steps,
        }
    }
}

/// Why planning stopped with an error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SkillPlanError {
    /// The blob could not be read.
    Load(LoadError),
    /// The action plan is not Move, Pick, Move, Place, Move.
    UnsupportedPlan,
    /// More stances × grasps than [`MAX_GOALS`].
    TooManyAffordances,
}

impl core::fmt::Display for SkillPlanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SkillPlanError::Load(e) => write!(f, "{e}"),
            SkillPlanError::UnsupportedPlan => write!(
                f,
                "the action plan is not Move, Pick, Move, Place, Move (the only plan SkillPlan-PTT takes)"
            ),
            SkillPlanError::TooManyAffordances => write!(
                f,
                "more stances × grasps than the planner holds ({MAX_GOALS})"
            ),
        }
    }
}

impl core::error::Error for SkillPlanError {}

impl From<LoadError> for SkillPlanError {
    fn from(e: LoadError) -> Self {
        SkillPlanError::Load(e)
    }
}

impl From<prf_shared::blob::BlobError> for SkillPlanError {
    fn from(e: prf_shared::blob::BlobError) -> Self {
        SkillPlanError::Load(e.into())
    }
}

/// Evaluates an arm motion candidate: integrates `rdmp` from q_a,H to `goal` (arm base frame)
/// with the runtime's step, slowed down by the smallest time scale at which its emitted
/// stream keeps every joint within position, speed, acceleration and jerk limits
/// ([`prf_shared::timing::pace_observed`]), and takes the risk in `field` (arm base at
/// `arm_base`, field frame) of exactly that stream. [`Evaluation::Pruned`] once the running
/// risk of the final stream reaches `bound` (∞: never): the timing is settled first, so a
/// pruned candidate is one the full evaluation would also rate at ≥ `bound`. At most `cap`
/// integration steps ([`Evaluation::Capped`]).
pub fn evaluate_arm_motion(
    rt: &Runtime<'_>,
    rdmp: &Rdmp,
    goal: &Pose,
    field: &Field<'_>,
    arm_base: &Pose,
    bound: f64,
    cap: usize,
) -> Evaluation {
    let observe = |_: &mut (), _: &ArmKinematics, _: f64| {};
    evaluate_arm_motion_observed(rt, rdmp, goal, field, arm_base, bound, cap, || (), observe).0
}

/// [`evaluate_arm_motion`] that also shows `observe` every configuration of every run (its
/// kinematics and the run's risk so far, which stops growing once it reaches `bound`), each
/// run with a `fresh()` state; returns the state of the final run (the rated stream's).
#[allow(clippy::too_many_arguments)]
pub fn evaluate_arm_motion_observed<S>(
    rt: &Runtime<'_>,
    rdmp: &Rdmp,
    goal: &Pose,
    field: &Field<'_>,
    arm_base: &Pose,
    bound: f64,
    cap: usize,
    mut fresh: impl FnMut() -> S,
    mut observe: impl FnMut(&mut S, &ArmKinematics, f64),
) -> (Evaluation, S) {
    if !(bound > 0.0) {
        // Risk is never negative: nothing reaches below 0, whatever its timing.
        return (Evaluation::Pruned { steps: 0 }, fresh());
    }
    let (model, cfg) = (&rt.model, &rt.config.rdmp);
    let q0 = JointVector::from(model.home);
    // Per run: the risk so far, whether it is still below the bound, the last TCP.
    let paced = pace_observed(
        model,
        &rt.limits,
        cfg,
        rdmp,
        &q0,
        goal,
        cap,
        true,
        || (RiskAccumulator::default(), true, Pose::identity(), fresh()),
        Some(
            |(acc, below, last, state): &mut (RiskAccumulator, bool, Pose, S),
             kin: &ArmKinematics| {
                *last = kin.tcp;
                if *below && acc.add(model, field, arm_base, kin) >= bound {
                    *below = false;
                }
                observe(state, kin, acc.risk());
            },
        ),
    );
    let ((acc, below, last, state), steps) = (paced.observer, paced.steps);
    let (position, angle) = (
        (last.translation.vector - goal.translation.vector).norm(),
        angle_between(&last.rotation, &goal.rotation),
    );
    let evaluation = match paced.timing {
        Ok(_) if !(position <= REACH_POSITION && angle <= REACH_ANGLE) => Evaluation::Missed {
            position,
            angle,
            steps,
        },
        Ok(timing) if below => Evaluation::Risk {
            risk: acc.risk(),
            timing,
            steps,
        },
        Ok(_) => Evaluation::Pruned { steps },
        Err(TimingError::Rdmp(error)) => Evaluation::Failed { error, steps },
        Err(TimingError::TooFast { scale, ratios }) => Evaluation::TooFast {
            scale,
            ratios,
            steps,
        },
        Err(TimingError::Capped) => Evaluation::Capped { steps },
    };
    (evaluation, state)
}

/// The configurations of an evaluated arm motion, q_a,H first: the stream the executor emits
/// for it (for checks and exports).
pub fn trace_arm_motion(
    rt: &Runtime<'_>,
    rdmp: &Rdmp,
    goal: &Pose,
    timing: &ArmTiming,
    visit: impl FnMut(&JointVector),
) -> Result<(), RdmpError> {
    trace_rdmp(rt, rdmp, goal, timing.scale, timing.steps, visit)
}

/// The configurations of `rdmp` time-scaled by `scale`, run from q_a,H to `goal` for
/// `steps` steps, q_a,H first: what the executor emits for an Arm segment.
pub fn trace_rdmp(
    rt: &Runtime<'_>,
    rdmp: &Rdmp,
    goal: &Pose,
    scale: f64,
    steps: u32,
    mut visit: impl FnMut(&JointVector),
) -> Result<(), RdmpError> {
    let (model, cfg) = (&rt.model, &rt.config.rdmp);
    let rdmp = rdmp.time_scaled(scale);
    let q0 = JointVector::from(model.home);
    let mut run = RdmpRun::new(model, &rdmp, &q0, goal, cfg)?;
    run.set_steps(steps as usize);
    visit(&q0);
    while !run.finished() {
        visit(&run.step(model, &rdmp, cfg)?.q);
    }
    Ok(())
}

/// A lower bound of the risk of any stream that ends with its TCP within [`REACH_POSITION`]
/// and [`REACH_ANGLE`] of `goal` (arm base frame; arm base at `arm_base` in the field's
/// frame): the spheres rigid with the TCP (link 7 and the tool) end within
/// REACH_POSITION + REACH_ANGLE · (their distance from the TCP) of where they are at the goal,
/// and the field is bounded below over that ball.
pub fn goal_bound(
    model: &prf_shared::robot::RobotModel,
    field: &Field<'_>,
    arm_base: &Pose,
    goal: &Pose,
) -> f64 {
    let mut excess = f64::NEG_INFINITY;
    for (sphere, c) in tcp_rigid_spheres(model, goal) {
        let lever = (c - goal.translation.vector).norm();
        let delta = REACH_POSITION + REACH_ANGLE * lever;
        let d = field.distance_lower_within(&arm_base.transform_point(&c.into()).coords, delta);
        // NaN (a non-finite goal): no bound.
        if d.is_nan() {
            return 0.0;
        }
        excess = excess.max(d + sphere.radius);
    }
    eta(excess)
}

/// One side of the search (Pick at ℓ1 or Place at ℓ2): its workspace, the arm base of each
/// stance in the location frame, the arm-base-frame goal of each (stance, grasp), and the
/// ordered skills.
pub struct Side<'a> {
    /// The side's location type (blob index).
    pub location_type: usize,
    /// The side's workspace Ω+ as a distance field (location frame).
    pub field: Field<'a>,
    /// Arm base of each stance, location frame.
    pub arm_bases: heapless::Vec<Pose, MAX_AFFORDANCES>,
    /// Goal of (stance s, grasp g) at s · grasps + g.
    pub goals: heapless::Vec<Pose, MAX_GOALS>,
    /// Number of grasps.
    pub grasps: usize,
    /// World pose of the platform at each stance (the Move goal).
    pub platform: heapless::Vec<Pose, MAX_AFFORDANCES>,
    /// The side's motion class (blob index).
    pub class: usize,
    /// How many skills of the class have an RDMP: the side's K.
    pub skills: usize,
    /// Admissible bound of (stance s, grasp g) at s · grasps + g (see [`Side::bound`]).
    pub bounds: heapless::Vec<f64, MAX_GOALS>,
}

impl<'a> Side<'a> {
    fn new(
        rt: &Runtime<'a>,
        location_type: usize,
        grasps: usize,
        class: usize,
    ) -> Result<Self, SkillPlanError> {
        let mut skills = 0;
        class_rdmps(rt, class, |_, _, _| skills += 1)?;
        Ok(Side {
            location_type,
            // Symbolic feasibility checked the workspace exists.
            field: rt
                .workspace(location_type)?
                .ok_or(SkillPlanError::UnsupportedPlan)?,
            arm_bases: heapless::Vec::new(),
            goals: heapless::Vec::new(),
            grasps,
            platform: heapless::Vec::new(),
            class,
            skills,
            bounds: heapless::Vec::new(),
        })
    }

    /// Adds a stance: the platform at `platform` (world) next to a location at `location`,
    /// with room for its goals.
    fn add_stance(
        &mut self,
        location: Pose,
        platform: Pose,
        model: &prf_shared::robot::RobotModel,
    ) -> Result<(), SkillPlanError> {
        // At most MAX_AFFORDANCES stances come from the blob.
        let _ = self.platform.push(platform);
        let _ = self
            .arm_bases
            .push(location.inverse() * platform * model.mount);
        for _ in 0..self.grasps {
            self.goals
                .push(Pose::identity())
                .map_err(|_| SkillPlanError::TooManyAffordances)?;
        }
        Ok(())
    }

    /// A lower bound of the risk of every candidate of stance `s` and grasp `g`, known without
    /// integrating (see the module): 0 where none is known.
    pub fn bound(&self, s: usize, g: usize) -> f64 {
        self.bounds
            .get(s * self.grasps + g)
            .filter(|_| g < self.grasps)
            .copied()
            .unwrap_or(0.0)
    }

    /// The smallest bound of grasp `g` over the stances: a lower bound of the side's minimum.
    pub fn grasp_bound(&self, g: usize) -> f64 {
        (0..self.arm_bases.len())
            .map(|s| self.bound(s, g))
            .fold(f64::INFINITY, f64::min)
    }

    /// Computes [`Side::bound`] for every (stance, grasp) once the goals are known.
    fn compute_bounds(&mut self, model: &prf_shared::robot::RobotModel) {
        let q0 = ArmKinematics::new(model, &JointVector::from(model.home));
        self.bounds.clear();
        for (s, base) in self.arm_bases.iter().enumerate() {
            let start = RiskAccumulator::default().add(model, &self.field, base, &q0);
            for g in 0..self.grasps {
                let goal = self.goals[s * self.grasps + g];
                let end = goal_bound(model, &self.field, base, &goal);
                // Capacity: one bound per goal.
                let _ = self.bounds.push(start.max(end));
            }
        }
    }

    /// The goal of stance `s` and grasp `g`.
    pub fn goal(&self, s: usize, g: usize) -> Option<&Pose> {
        self.goals
            .get(s * self.grasps + g)
            .filter(|_| g < self.grasps)
    }

    /// Candidates of the side in their documented order: (stance, skill), until `visit`
    /// says stop ([`Side::candidates_in`] pages of [`ORDER_PAGE`]).
    pub fn candidates(
        &self,
        rt: &Runtime<'_>,
        grasp: usize,
        visit: impl FnMut(u8, u16) -> bool,
    ) -> Result<(), SkillPlanError> {
        self.candidates_in::<ORDER_PAGE>(rt, grasp, visit)
    }

    /// [`Side::candidates`] ordered in pages of `P`: per stance, the `P` least keys above
    /// the last page's, each page from one pass over the class. Every `P` gives the order
    /// of a full sort; `P` trades passes for memory.
    pub fn candidates_in<const P: usize>(
        &self,
        rt: &Runtime<'_>,
        grasp: usize,
        mut visit: impl FnMut(u8, u16) -> bool,
    ) -> Result<(), SkillPlanError> {
        for s in 0..self.arm_bases.len() {
            let Some(goal) = self.goal(s, grasp) else {
                continue;
            };
            let mut after: Option<Ranked> = None;
            loop {
                let page = self.page::<P>(rt, goal, after)?;
                for r in &page {
                    if !visit(s as u8, r.skill) {
                        return Ok(());
                    }
                }
                match page.last() {
                    Some(&last) if page.is_full() => after = Some(last),
                    _ => break,
                }
            }
        }
        Ok(())
    }

    /// The `P` least keys of the class's skills for `goal` above `after`, sorted.
    fn page<const P: usize>(
        &self,
        rt: &Runtime<'_>,
        goal: &Pose,
        after: Option<Ranked>,
    ) -> Result<heapless::Vec<Ranked, P>, SkillPlanError> {
        // A max-heap: its top is the key the next smaller one replaces.
        let mut least: heapless::BinaryHeap<Ranked, heapless::binary_heap::Max, P> =
            heapless::BinaryHeap::new();
        let mut result: Result<(), SkillPlanError> = Ok(());
        class_rdmps(rt, self.class, |skill, rdmp, learned_at| {
            let demo = match rt.blob.rdmp_goal(rdmp as usize) {
                Ok(d) => d,
                Err(e) => return result = Err(e.into()),
            };
            let key = Ranked {
                elsewhere: learned_at != Some(self.location_type as u8),
                distance: (goal.translation.vector - demo.translation.vector).norm()
                    + ROTATION_WEIGHT * angle_between(&goal.rotation, &demo.rotation),
                skill,
            };
            if after.is_some_and(|a| key <= a) {
                return;
            }
            if let Err(key) = least.push(key)
                && least.peek().is_some_and(|top| key < *top)
            {
                least.pop();
                let _ = least.push(key);
            }
        })?;
        result?;
        let mut page = least.into_vec();
        page.sort_unstable();
        Ok(page)
    }
}

/// The order of a side's candidates within a stance: skills learned at the side's location
/// type first, then by the distance of their demonstrated TCP goal to the candidate's goal,
/// then by blob index (unique, so the order is total).
#[derive(Clone, Copy, Debug)]
struct Ranked {
    elsewhere: bool,
    distance: f64,
    skill: u16,
}

impl Ord for Ranked {
    fn cmp(&self, o: &Self) -> core::cmp::Ordering {
        self.elsewhere
            .cmp(&o.elsewhere)
            .then(self.distance.total_cmp(&o.distance))
            .then(self.skill.cmp(&o.skill))
    }
}

impl PartialOrd for Ranked {
    fn partial_cmp(&self, o: &Self) -> Option<core::cmp::Ordering> {
        Some(self.cmp(o))
    }
}

impl PartialEq for Ranked {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o).is_eq()
    }
}

impl Eq for Ranked {}

/// The blob's stances T_b^ℓ of location type `t`.
fn stances(
    rt: &Runtime<'_>,
    t: usize,
) -> Result<heapless::Vec<Pose, MAX_AFFORDANCES>, SkillPlanError> {
    let mut out = heapless::Vec::new();
    for s in rt.blob.location_type(t)?.stances.iter() {
        // Blob::parse checked every stance is a finite unit-quaternion pose.
        let s =
            pose_from_array(*s).ok_or(LoadError::Blob(prf_shared::blob::BlobError::Reference {
                section: prf_shared::blob::Section::LocationTypes,
                index: t,
            }))?;
        let _ = out.push(s);
    }
    Ok(out)
}

/// Shows `visit` each skill of class `class` that has an RDMP: (skill, RDMP, the location
/// type it was learned at), in blob order.
fn class_rdmps(
    rt: &Runtime<'_>,
    class: usize,
    mut visit: impl FnMut(u16, u16, Option<u8>),
) -> Result<(), SkillPlanError> {
    for k in 0..rt.blob.payload.skills.len() {
        let s = rt.blob.skill(k)?;
        if let (true, Some(r)) = (s.class as usize == class, s.rdmp) {
            visit(k as u16, r, s.location_type);
        }
    }
    Ok(())
}

/// The blob class indices of Pick, Place and Move and their code.
pub struct PttClasses {
    /// Pick: blob class index and code.
    pub pick: (usize, &'static dyn MotionClass),
    /// Place: blob class index and code.
    pub place: (usize, &'static dyn MotionClass),
    /// Move: blob class index and code.
    pub moves: (usize, &'static dyn MotionClass),
}

impl PttClasses {
    /// The three classes of a blob; None if it lacks one.
    pub fn of(rt: &Runtime<'_>) -> Option<Self> {
        let get = |name| {
            let i = rt.class_index(name)?;
            Some((i, rt.class_code(i)?))
        };
        Some(PttClasses {
            pick: get("Pick")?,
            place: get("Place")?,
            moves: get("Move")?,
        })
    }

    /// Whether `plan` is Move(ℓ0, ℓ1), Pick(p, ℓ1), Move(ℓ1, ℓ2), Place(p, ℓ2), Move(ℓ2, ℓ0).
    pub fn matches(&self, plan: &ActionPlan) -> bool {
        let a = |class: usize, args: &[u8]| Action {
            class: class as u8,
            args: [args[0], args[1], 0],
            n_args: 2,
        };
        let expected = [
            a(self.moves.0, &[HOME, FROM]),
            a(self.pick.0, &[0, FROM]),
            a(self.moves.0, &[FROM, TO]),
            a(self.place.0, &[0, TO]),
            a(self.moves.0, &[TO, HOME]),
        ];
        plan.as_slice() == expected
    }
}

/// GoalContext of an action at `location` with the given affordances.
fn context<'c>(
    model: &'c prf_shared::robot::RobotModel,
    task: &Task<'_>,
    location: Pose,
    stances: &'c [Pose],
    grasps: &'c [Pose],
) -> GoalContext<'c> {
    GoalContext {
        model,
        part_goal: task.goal,
        location,
        stances,
        grasps,
    }
}

/// Grasp `g` (T_e^p) of part type `part_type`; `None` past the last.
pub fn grasp(rt: &Runtime<'_>, part_type: usize, g: usize) -> Result<Option<Pose>, SkillPlanError> {
    // Blob::parse checked every grasp is a finite unit-quaternion pose.
    Ok(rt
        .blob
        .part_type(part_type)?
        .grasps
        .get(g)
        .and_then(|g| pose_from_array(*g)))
}

/// The two sides of a PTT plan, with goals from the classes' Y, G and Φ_x.
pub struct PttSides<'a> {
    /// The pick side, at ℓ1.
    pub pick: Side<'a>,
    /// The place side, at ℓ2.
    pub place: Side<'a>,
    /// Number of grasps.
    pub grasps: usize,
}

impl<'a> PttSides<'a> {
    /// Both sides of `task`, with goals from the classes' Y, G and Φ_x.
    pub fn new(
        rt: &Runtime<'a>,
        task: &Task<'_>,
        r: &Resolved,
        c: &PttClasses,
    ) -> Result<Self, SkillPlanError> {
        let model = &rt.model;
        let mut grasps: heapless::Vec<Pose, MAX_AFFORDANCES> = heapless::Vec::new();
        for g in rt.blob.part_type(r.part_type)?.grasps.iter() {
            // Blob::parse checked every grasp is a finite unit-quaternion pose.
            if let Some(g) = pose_from_array(*g) {
                let _ = grasps.push(g);
            }
        }
        let from = stances(rt, r.from_type)?;
        let to = stances(rt, r.to_type)?;
        let start = PhysicalState {
            base: task.home,
            arm: JointVector::from(model.home),
            gripper: 0.0,
            part: task.part.pose,
            grasp: None,
        };
        let n = grasps.len();
        let mut pick = Side::new(rt, r.from_type, n, c.pick.0)?;
        let mut place = Side::new(rt, r.to_type, n, c.place.0)?;
        let (mv, pk, pl) = (c.moves.1, c.pick.1, c.place.1);
        let mut result = Ok(());
        // Move(ℓ0, ℓ1) to each stance; Pick's goals there, one per grasp (Alg. 4 line 7).
        let at_from = context(model, task, task.from.pose, &from, &grasps);
        let mut after_pick: heapless::Vec<PhysicalState, MAX_AFFORDANCES> = heapless::Vec::new();
        mv.goals(&start, &at_from, &mut |stance| {
            let x = mv.transition(model, &start, &stance);
            let s = pick.arm_bases.len();
            result = result.and(pick.add_stance(task.from.pose, x.base, model));
            let mut g = 0;
            pk.goals(&x, &at_from, &mut |goal| {
                if let (Goal::Tcp { pose, .. }, Some(slot)) = (goal, pick.goals.get_mut(s * n + g))
                {
                    *slot = pose;
                }
                // The state after Pick and its effect on Place depend on the grasp only
                // (Alg. 4 line 8): take it at the first stance.
                if s == 0 {
                    let _ = after_pick.push(pk.transition(model, &x, &goal));
                }
                g += 1;
            });
        });
        // Move(ℓ1, ℓ2) to each stance; Place's goal there for each grasp.
        let at_to = context(model, task, task.to.pose, &to, &grasps);
        for (g, held) in after_pick.iter().enumerate() {
            let mut s = 0;
            mv.goals(held, &at_to, &mut |stance| {
                let x = mv.transition(model, held, &stance);
                if g == 0 {
                    result = result.and(place.add_stance(task.to.pose, x.base, model));
                }
                pl.goals(&x, &at_to, &mut |goal| {
                    if let (Goal::Tcp { pose, .. }, Some(slot)) =
                        (goal, place.goals.get_mut(s * n + g))
                    {
                        *slot = pose;
                    }
                });
                s += 1;
            });
        }
        result?;
        pick.compute_bounds(model);
        place.compute_bounds(model);
        Ok(PttSides {
            pick,
            place,
            grasps: grasps.len(),
        })
    }
}

/// The best candidate of one side found so far: (risk, stance, skill, timing).
type Best = Option<(f64, u8, u16, ArmTiming)>;

/// min over the side's candidates of r for grasp `grasp`, counting only candidates with
/// r < `bound`; the first candidate in order wins ties. Candidates whose [`Side::bound`]
/// reaches the limit are not integrated. Stops when `stats.charged` reaches `budget` (before
/// or within an integration); the flag says it did. Candidates `recall` decides are not
/// integrated either, but charged the steps they took.
fn side_minimum(
    rt: &Runtime<'_>,
    side: &Side<'_>,
    grasp: usize,
    bound: f64,
    budget: u64,
    stats: &mut PlanStats,
    mut recall: Option<&mut Recall<'_>>,
) -> Result<(Best, bool), SkillPlanError> {
    let mut best: Best = None;
    let mut exhausted = false;
    let mut result = Ok(());
    side.candidates(rt, grasp, |s, k| {
        let limit = best.map_or(bound, |b| b.0.min(bound));
        if side.bound(s as usize, grasp) >= limit {
            stats.bounded += 1;
            return true;
        }
        if stats.charged >= budget {
            exhausted = true;
            return false;
        }
        let (Some(goal), Ok(Some(rdmp))) =
            (side.goal(s as usize, grasp), rt.skill_rdmp(k as usize))
        else {
            result = Err(SkillPlanError::UnsupportedPlan);
            return false;
        };
        let arm_base = &side.arm_bases[s as usize];
        let candidate = Candidate::new(side.location_type, k, arm_base, goal);
        let left = budget - stats.charged;
        let recalled = recall.as_deref().and_then(|r| r.get(&candidate, limit));
        let e = match recalled.filter(|e| e.steps() as u64 <= left) {
            Some(e) => {
                stats.recalled += 1;
                stats.charged += e.steps() as u64;
                e
            }
            None => {
                let cap = left.min(usize::MAX as u64) as usize;
                let e = evaluate_arm_motion(rt, &rdmp, goal, &side.field, arm_base, limit, cap);
                stats.count(&e);
                if let Some(r) = recall.as_deref_mut() {
                    r.keep(candidate, limit, &e);
                }
                e
            }
        };
        match e {
            Evaluation::Risk { risk, timing, .. } if risk < limit => {
                best = Some((risk, s, k, timing));
                if risk <= 0.0 {
                    return false;
                }
            }
            Evaluation::Capped { .. } => {
                exhausted = true;
                return false;
            }
            _ => {}
        }
        true
    })?;
    result?;
    Ok((best, exhausted))
}

/// SkillPlan-PTT (Alg. 4) over the two sides: the decomposed, pruned grid search, without a
/// budget.
pub fn plan_skills(rt: &Runtime<'_>, sides: &PttSides<'_>) -> Result<SkillPlan, SkillPlanError> {
    plan_skills_within(rt, sides, PlanBudget::UNLIMITED, None)
}

/// SkillPlan-PTT within `budget`, searched as the runtime's [`Search`] says: the optimum of
/// the brute-force grid when the budget lasts; otherwise the best plan found and a lower bound
/// of J* ([`SkillPlan::exhausted`]). `recall` answers the candidates it holds and keeps the
/// others' evaluations (see [`crate::recall`]); a recalled evaluation is charged the steps it
/// took, so the plan is the one planned alone.
pub fn plan_skills_within(
    rt: &Runtime<'_>,
    sides: &PttSides<'_>,
    budget: PlanBudget,
    mut recall: Option<&mut Recall<'_>>,
) -> Result<SkillPlan, SkillPlanError> {
    let (pick, place) = (&sides.pick, &sides.place);
    let stats = PlanStats {
        grid_integrations: 2
            * (pick.arm_bases.len() * place.arm_bases.len() * sides.grasps) as u64
            * (pick.skills * place.skills) as u64,
        ..PlanStats::default()
    };
    let threshold = rt.config.risk_threshold;
    let optimum = |stats, recall| search(rt, sides, f64::INFINITY, budget, stats, recall);
    let decide = |stats, recall| search(rt, sides, threshold.next_up(), budget, stats, recall);
    let mut plan = match rt.config.search {
        Search::Optimum => optimum(stats, recall)?,
        Search::Decide => decide(stats, recall)?,
        Search::DecideFirst => {
            let first = decide(stats, recall.as_deref_mut())?;
            if first.choice.is_some() || first.exhausted.is_some() {
                first
            } else {
                // J* > threshold: the best risky plan, searched with what the budget has left.
                let mut second = optimum(first.stats, recall)?;
                second.lower = second.lower.max(first.lower);
                second.exhausted = second.exhausted.map(|lower| lower.max(first.lower));
                second
            }
        }
    };
    plan.decided = plan.feasible || plan.lower > threshold;
    Ok(plan)
}

/// The grasp loop of SkillPlan-PTT: the least J below `limit` (∞: the optimum), counting
/// onto `stats`, within `budget` steps in all.
fn search(
    rt: &Runtime<'_>,
    sides: &PttSides<'_>,
    limit: f64,
    budget: PlanBudget,
    mut stats: PlanStats,
    mut recall: Option<&mut Recall<'_>>,
) -> Result<SkillPlan, SkillPlanError> {
    let (pick, place) = (&sides.pick, &sides.place);
    // J of each grasp is at least the larger of its sides' smallest bounds.
    let grasp_bound = |g: usize| pick.grasp_bound(g).max(place.grasp_bound(g));
    // Grasps by bound (then index): the most promising first. The tie order is kept by the
    // bound each grasp must beat: the best J so far, or just above it for a grasp of smaller
    // index (which wins a tie).
    let mut order: heapless::Vec<(f64, usize), MAX_AFFORDANCES> = heapless::Vec::new();
    for g in 0..sides.grasps.min(MAX_AFFORDANCES) {
        let _ = order.push((grasp_bound(g), g));
    }
    order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    // (J, choice, r_pick, r_place, timings) of the best plan so far.
    type Plan = (f64, Choice, f64, f64, (ArmTiming, ArmTiming));
    let mut best: Option<Plan> = None;
    let mut exhausted = None;
    for (i, &(lower, g)) in order.iter().enumerate() {
        let bound = best.map_or(limit, |b| {
            if g < b.1.grasp as usize {
                b.0.next_up()
            } else {
                b.0
            }
        });
        if lower >= bound {
            stats.bounded +=
                (pick.arm_bases.len() * pick.skills + place.arm_bases.len() * place.skills) as u32;
            continue;
        }
        let mut side = |side| {
            let recall = recall.as_deref_mut();
            side_minimum(rt, side, g, bound, budget.steps, &mut stats, recall)
        };
        let (first, out) = side(pick)?;
        let second = match (first, out) {
            (Some(_), false) => side(place)?,
            _ => (None, out),
        };
        if second.1 {
            // Out of budget in this grasp: it and the grasps after it were not searched to
            // the end (their bounds are sorted, so this one's is the smallest).
            exhausted = Some(lower.min(best.map_or(f64::INFINITY, |b| b.0)));
            break;
        }
        let (Some((r_pick, s1, k1, t1)), Some((r_place, s2, k2, t2))) = (first, second.0) else {
            continue;
        };
        // Both sides are below `bound`, so this plan beats the best so far.
        let j = r_pick.max(r_place);
        let choice = Choice {
            stance_from: s1,
            stance_to: s2,
            grasp: g as u8,
            pick_skill: k1,
            place_skill: k2,
        };
        best = Some((j, choice, r_pick, r_place, (t1, t2)));
        // J = 0 cannot be beaten, except by a grasp of smaller index not searched yet.
        if j <= 0.0 && order[i + 1..].iter().all(|&(_, h)| h > g) {
            break;
        }
    }
    let (j, choice, r_pick, r_place, timing) = match best {
        Some((j, c, a, b, t)) => (j, Some(c), a, b, Some(t)),
        None => (f64::INFINITY, None, f64::INFINITY, f64::INFINITY, None),
    };
    Ok(SkillPlan {
        choice,
        j,
        r_pick,
        r_place,
        timing,
        feasible: j <= rt.config.risk_threshold,
        stats,
        exhausted,
        // Searched to the end: J* is the best found, or at least the limit if none beat it.
        lower: exhausted.unwrap_or(j.min(limit)),
        decided: false,
    })
}
