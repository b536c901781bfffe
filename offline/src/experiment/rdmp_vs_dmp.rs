//! The paper's Sec. 4.3 (Fig. 3 and 4): the risk of RDMP and joint-space DMP trajectories
//! generalised to new goals around a single demonstration.
//!
//! Per approach of the cell (a location type and one of its stances): a ground-truth
//! demonstration of the afforded task that picks there with the part at its nominal pose and
//! the first grasp, generated from q_a,H by the cell's motion planner; Ω+ learned from it
//! (ε = r_d − r, 0.02 m in the example cell); TrainRDMP (Alg. 1) and a joint-space DMP
//! (Eq. 4) on its Pick arm motion. Then, for each goal of a horizontal grid centred at the
//! demonstrated TCP goal (same height and orientation): IntegrateRDMP (Alg. 2) from q_a,H,
//! the DMP (Eq. 5) from q_a,H to the RDMP's final configuration, and the risk (Eq. 16) of
//! both in Ω+. Goals the ground-truth IK cannot reach are kept and marked.
//!
//! Beyond the paper, a third trajectory per goal: the RDMP shifted along its null space
//! ([`Rdmp::shifted`]) by the amount that brings the paper's final configuration toward the
//! demonstration's last one ([`shift_toward`]), so the arm moves no more than the new goal
//! needs. Near the demonstrated goal (within [`EXACT_WITHIN`]) every risk is also rated in
//! the exact Ω+ (the dilated demonstrated balls, [`BallUnion`]), so the field's part of a
//! risk shows beside the motion's.

use anyhow::{Context, Result, anyhow, bail};
use nalgebra::{SVector, Translation3, Vector3};
use prf_files::dataset::{Dataset, Demonstration};
use prf_learn::capsule::DEDUP;
use prf_learn::exact::BallUnion;
use prf_learn::learn::{Learner, learn_into, location_kinds};
use prf_learn::workspace::LearnedField;
use prf_learn::{LearnConfig, skills};
use prf_shared::dmp::PositionDmp;
use prf_shared::field::DistanceField;
use prf_shared::kinematics::{ArmKinematics, arm_base_pose, tcp_rigid_spheres};
use prf_shared::rdmp::{Rdmp, RdmpConfig, integrate, shift_toward};
use prf_shared::risk::RiskAccumulator;
use prf_shared::robot::RobotModel;
use prf_shared::se3::{Pose, pose_from_array};
use prf_shared::{JointVector, NA};
use prf_sim::demogen::ik::{IkConfig, solutions};
use prf_sim::world::{AffordedTask, World};
use rayon::prelude::*;

/// The link whose origin stands for whole-arm motion (the paper's elbow, link 4).
pub const ELBOW_LINK: usize = 4;
/// Elbow traces keep one sample per this many integration steps.
pub const TRACE_EVERY: usize = 40;
/// The DMP reached the RDMP's final configuration when every joint ends this close, rad (a
/// DMP converges to its goal; at t = τ it is 0.1–0.3 mrad short on these motions).
pub const DMP_REACH: f64 = 1e-3;
/// The RDMP reached a goal when its final TCP is this close in position, m ...
pub const REACH_POSITION: f64 = 1e-3;
/// ... and in orientation, rad (0.5°).
pub const REACH_ANGLE: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// Goals within this offset (in x and in y) of the demonstrated one are also rated in the
/// exact Ω+, m (its exhaustive lookups made the whole grid take 116 s instead of 16 s).
pub const EXACT_WITHIN: f64 = 0.03;

/// The grid of new goals: `n` × `n` offsets in [−half_extent, half_extent]² (arm base frame
/// x and y, which are horizontal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GoalGrid {
    /// Half the side of the square, m.
    pub half_extent: f64,
    /// Goals per side (odd, so the demonstrated goal is one of them).
    pub n: usize,
}

impl Default for GoalGrid {
    /// ±0.1 m at 10 mm: 21 × 21 = 441 goals.
    fn default() -> Self {
        GoalGrid {
            half_extent: 0.1,
            n: 21,
        }
    }
}

impl GoalGrid {
    /// The offsets along one axis, m.
    pub fn offsets(&self) -> Vec<f64> {
        let n = self.n.max(1);
        if n == 1 {
            return vec![0.0];
        }
        (0..n)
            .map(|i| -self.half_extent + 2.0 * self.half_extent * i as f64 / (n - 1) as f64)
            .collect()
    }

    /// Spacing, m.
    pub fn spacing(&self) -> f64 {
        if self.n > 1 {
            2.0 * self.half_extent / (self.n - 1) as f64
        } else {
            0.0
        }
    }
}

/// One approach of the cell: a location type, one of its stances, and the afforded task
/// whose demonstration picks there.
#[derive(Clone, Debug)]
pub struct Approach {
    /// "CNC front".
    pub name: String,
    pub task: AffordedTask,
}

/// Every approach of the world: per location type and stance, the first afforded task that
/// picks there with the first part and grasp and places at another location type (so the
/// pick location's Ω+ is learned from the pick alone).
pub fn approaches(world: &World) -> Vec<Approach> {
    let mut out = Vec::new();
    let all = world.afforded_tasks();
    for t in &world.location_types {
        for (a, approach) in t.approaches.iter().enumerate() {
            let found = all.iter().find(|x| {
                let (from, to) = (
                    world.location_type(x.task.from),
                    world.location_type(x.task.to),
                );
                from.name == t.name
                    && to.name != t.name
                    && x.approach_from == a
                    && x.grasp == 0
                    && x.task.part == 0
            });
            if let Some(task) = found {
                out.push(Approach {
                    name: format!("{} {}", t.name, approach.name),
                    task: *task,
                });
            }
        }
    }
    out
}

/// How an integration ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Ending {
    /// Within [`REACH_POSITION`] and [`REACH_ANGLE`] of the goal (for the DMP: within
    /// [`DMP_REACH`] of the RDMP's final configuration in every joint).
    Reached,
    /// Integrated, but ended this far from the goal (m, rad).
    Missed { position: f64, angle: f64 },
    /// The DMP integrated, but ended this far from its goal configuration (largest joint
    /// error, rad).
    MissedJoints { error: f64 },
    /// Could not be integrated.
    Failed(String),
}

/// A generalised trajectory.
#[derive(Clone, Debug)]
pub struct Trajectory {
    pub ending: Ending,
    /// Risk (Eq. 16) in the approach's Ω+, m (NaN when it failed).
    pub risk: f64,
    /// The same risk in the exact Ω+ (the dilated demonstrated balls, [`BallUnion`]), m;
    /// None beyond [`EXACT_WITHIN`] and when it failed.
    pub exact_risk: Option<f64>,
    /// Final configuration.
    pub end: [f64; NA],
    /// (t, elbow x in the arm base frame) every [`TRACE_EVERY`] steps.
    pub elbow: Vec<(f64, f64)>,
}

/// The outcome at one goal of the grid.
#[derive(Clone, Debug)]
pub struct GoalOutcome {
    /// Offset from the demonstrated goal, arm base frame, m.
    pub dx: f64,
    pub dy: f64,
    /// The ground-truth IK found a configuration for the goal.
    pub reachable: bool,
    pub rdmp: Trajectory,
    /// The RDMP shifted along its null space toward the demonstration's last configuration,
    /// and the shift δ (rad; None when the RDMP failed or ended singular).
    pub shifted: Option<(f64, Trajectory)>,
    /// The DMP to the RDMP's final configuration (None when the RDMP failed).
    pub dmp: Option<Trajectory>,
    /// A lower bound of the exact risk of any motion that ends at the goal, m ([`tcp_floor`]).
    pub floor: f64,
}

/// Everything measured on one approach.
#[derive(Clone, Debug)]
pub struct ApproachResult {
    pub name: String,
    /// The afforded task's label.
    pub label: String,
    /// The demonstrated Pick arm motion, uniformly sampled every `dt`.
    pub demo: Vec<[f64; NA]>,
    pub dt: f64,
    /// The demonstrated TCP goal, arm base frame.
    pub goal: Pose,
    /// The arm base in the location frame.
    pub arm_base: Pose,
    /// Ω+ of the location type, learned from the demonstration alone.
    pub field: LearnedField,
    /// The same Ω+ exactly: the demonstrated balls dilated by ε.
    pub exact: BallUnion,
    pub goals: Vec<GoalOutcome>,
    pub grid: GoalGrid,
}

/// Figures of one primitive over the goals it integrated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    /// Goals it integrated, reached (within tolerance), of all.
    pub integrated: usize,
    pub reached: usize,
    pub goals: usize,
    pub mean_risk: f64,
    pub max_risk: f64,
    /// Integrated goals at risk 0.
    pub zero: usize,
    /// Goals rated in the exact Ω+ ([`EXACT_WITHIN`]), and those at exact risk 0.
    pub exact_rated: usize,
    pub exact_zero: usize,
}

impl Summary {
    /// The figures of `trajectories` over `goals` goals.
    fn of<'a>(goals: usize, trajectories: impl Iterator<Item = &'a Trajectory>) -> Summary {
        let ts: Vec<&Trajectory> = trajectories.collect();
        let ok: Vec<f64> = ts
            .iter()
            .filter(|t| !matches!(t.ending, Ending::Failed(_)))
            .map(|t| t.risk)
            .collect();
        let exact: Vec<f64> = ts.iter().filter_map(|t| t.exact_risk).collect();
        Summary {
            integrated: ok.len(),
            reached: ts.iter().filter(|t| t.ending == Ending::Reached).count(),
            goals,
            mean_risk: ok.iter().sum::<f64>() / ok.len().max(1) as f64,
            max_risk: ok.iter().copied().fold(0.0, f64::max),
            zero: ok.iter().filter(|r| **r == 0.0).count(),
            exact_rated: exact.len(),
            exact_zero: exact.iter().filter(|r| **r == 0.0).count(),
        }
    }
}

/// The summaries of one approach's three primitives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summaries {
    /// The paper's RDMP.
    pub rdmp: Summary,
    /// The RDMP shifted along its null space.
    pub shifted: Summary,
    /// The joint-space DMP.
    pub dmp: Summary,
}

impl ApproachResult {
    /// Summaries of the RDMP, the shifted RDMP and the DMP.
    pub fn summaries(&self) -> Summaries {
        let n = self.goals.len();
        Summaries {
            rdmp: Summary::of(n, self.goals.iter().map(|g| &g.rdmp)),
            shifted: Summary::of(
                n,
                self.goals
                    .iter()
                    .filter_map(|g| g.shifted.as_ref().map(|s| &s.1)),
            ),
            dmp: Summary::of(n, self.goals.iter().filter_map(|g| g.dmp.as_ref())),
        }
    }

    /// Goals whose [`GoalOutcome::floor`] is 0: the most any motion could bring to risk 0
    /// (the others are proven above 0).
    pub fn floor_zero(&self) -> usize {
        self.goals.iter().filter(|g| !(g.floor > 0.0)).count()
    }

    /// Share of goals with both trajectories integrated where the RDMP's risk ≤ the DMP's.
    pub fn rdmp_not_worse(&self) -> f64 {
        let both: Vec<(f64, f64)> = self
            .goals
            .iter()
            .filter_map(|g| g.dmp.as_ref().map(|d| (g.rdmp.risk, d.risk)))
            .filter(|(r, d)| r.is_finite() && d.is_finite())
            .collect();
        both.iter().filter(|(r, d)| r <= d).count() as f64 / both.len().max(1) as f64
    }
}

/// The elbow's x in the arm base frame.
pub fn elbow_x(model: &RobotModel, q: &JointVector) -> f64 {
    ArmKinematics::new(model, q).frames[ELBOW_LINK].origin.x
}

/// Rates a trajectory one configuration at a time: its risk in Ω+ and its elbow trace, from
/// one forward kinematics per configuration.
struct Rater<'a, F> {
    model: &'a RobotModel,
    field: &'a F,
    exact: Option<&'a BallUnion>,
    arm_base: &'a Pose,
    acc: RiskAccumulator,
    exact_acc: RiskAccumulator,
    elbow: Vec<(f64, f64)>,
}

impl<'a, F: DistanceField> Rater<'a, F> {
    fn new(
        model: &'a RobotModel,
        field: &'a F,
        exact: Option<&'a BallUnion>,
        arm_base: &'a Pose,
    ) -> Self {
        Rater {
            model,
            field,
            exact,
            arm_base,
            acc: RiskAccumulator::default(),
            exact_acc: RiskAccumulator::default(),
            elbow: Vec::new(),
        }
    }

    /// Adds configuration `q` at step `k` (time k·Δt).
    fn add(&mut self, k: usize, q: &JointVector) {
        let kin = ArmKinematics::new(self.model, q);
        self.acc.add(self.model, self.field, self.arm_base, &kin);
        if let Some(exact) = self.exact {
            self.exact_acc.add(self.model, exact, self.arm_base, &kin);
        }
        if k.is_multiple_of(TRACE_EVERY) {
            let dt = RdmpConfig::default().dt;
            self.elbow
                .push((k as f64 * dt, kin.frames[ELBOW_LINK].origin.x));
        }
    }

    /// The trajectory that ended at `end` as `ending`.
    fn finish(self, ending: Ending, end: [f64; NA]) -> Trajectory {
        Trajectory {
            ending,
            risk: self.acc.risk(),
            exact_risk: self.exact.map(|_| self.exact_acc.risk()),
            end,
            elbow: self.elbow,
        }
    }
}

/// A trajectory that could not be integrated.
fn failed(model: &RobotModel, why: String) -> Trajectory {
    Trajectory {
        ending: Ending::Failed(why),
        risk: f64::NAN,
        exact_risk: None,
        end: model.home,
        elbow: Vec::new(),
    }
}

/// Points per sphere at which [`tcp_floor`] looks for a witness outside Ω+.
pub const FLOOR_POINTS: usize = 96;

/// A lower bound of the exact risk (Eq. 16 with the true signed distance of Ω+) of every
/// motion whose TCP ends at `goal` (arm base frame): the spheres rigid with the TCP (link 7
/// and the tool) are there whatever the arm does, and a point p of such a sphere (centre c,
/// radius r) outside Ω+ at distance d > 0 (where the distance to the union of balls is exact)
/// gives sdf(c) + r ≥ d − |p − c| + r ≥ d, the signed distance being 1-Lipschitz. Points are
/// [`FLOOR_POINTS`] of each sphere's surface (a Fibonacci lattice) and its centre; every
/// distance is taken [`DEDUP`] less, as a demonstrated sphere the sweep dropped lies within it
/// of a kept one.
pub fn tcp_floor(model: &RobotModel, exact: &BallUnion, arm_base: &Pose, goal: &Pose) -> f64 {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let direction = |i: usize| {
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / FLOOR_POINTS as f64;
        let (rho, phi) = ((1.0 - z * z).sqrt(), golden * i as f64);
        Vector3::new(rho * phi.cos(), rho * phi.sin(), z)
    };
    let mut floor = 0.0f64;
    for (s, c) in tcp_rigid_spheres(model, goal) {
        let c = arm_base.transform_point(&c.into()).coords;
        // The centre, when it is outside too, gives the sphere's term itself.
        let centre = exact.distance(&c);
        let at_centre = if centre > 0.0 { centre + s.radius } else { 0.0 };
        let outside = (0..FLOOR_POINTS)
            .map(|i| exact.distance(&(c + direction(i) * s.radius)))
            .fold(at_centre, f64::max);
        floor = floor.max(outside - DEDUP);
    }
    floor
}

/// IntegrateRDMP from q_a,H to `goal`, with its risk and elbow trace.
fn rdmp_trajectory(
    model: &RobotModel,
    rdmp: &Rdmp,
    goal: &Pose,
    field: &impl DistanceField,
    exact: Option<&BallUnion>,
    arm_base: &Pose,
) -> Trajectory {
    let q0 = JointVector::from(model.home);
    let mut rater = Rater::new(model, field, exact, arm_base);
    rater.add(0, &q0);
    let q = match integrate(model, rdmp, &q0, goal, &RdmpConfig::default(), |s| {
        rater.add(s.step, &s.q)
    }) {
        Ok(q) => q,
        Err(e) => return failed(model, e.to_string()),
    };
    let tcp = ArmKinematics::new(model, &q).tcp;
    let position = (tcp.translation.vector - goal.translation.vector).norm();
    let angle = tcp.rotation.angle_to(&goal.rotation);
    let ending = if position <= REACH_POSITION && angle <= REACH_ANGLE {
        Ending::Reached
    } else {
        Ending::Missed { position, angle }
    };
    rater.finish(ending, q.into())
}

/// The joint-space DMP from q_a,H to `end`, with its risk and elbow trace.
fn dmp_trajectory(
    model: &RobotModel,
    dmp: &PositionDmp<NA>,
    end: &[f64; NA],
    field: &impl DistanceField,
    exact: Option<&BallUnion>,
    arm_base: &Pose,
) -> Trajectory {
    let dt = RdmpConfig::default().dt;
    let (y0, goal) = (SVector::from(model.home), SVector::from(*end));
    let (mut state, mut phase) = match dmp.start(&y0, &goal, dt) {
        Ok(s) => s,
        Err(e) => return failed(model, e.to_string()),
    };
    let mut rater = Rater::new(model, field, exact, arm_base);
    rater.add(0, &state.y);
    let mut ahead = None;
    while !phase.finished() {
        state.step(&dmp.params, &dmp.forcing, dmp.tau, dt, &phase, &mut ahead);
        phase.advance();
        rater.add(phase.step, &state.y);
    }
    let miss = (state.y - goal).amax();
    let ending = if miss <= DMP_REACH {
        Ending::Reached
    } else {
        Ending::MissedJoints { error: miss }
    };
    rater.finish(ending, state.y.into())
}

/// The Pick arm motion of a demonstration: its forward samples and the arm base (world) at
/// it.
fn pick_motion(model: &RobotModel, d: &Demonstration) -> Result<(Vec<[f64; NA]>, f64, Pose)> {
    let pick = prf_shared::motion::class("Pick").ok_or_else(|| anyhow!("no Pick class"))?;
    let mut found = None;
    pick.segment(&d.samples, &mut |inst| {
        if found.is_none() {
            found = inst.arm.map(|a| (a.forward, inst.at));
        }
    });
    let (forward, at) = found.ok_or_else(|| anyhow!("demonstration {} has no Pick", d.id))?;
    let (path, dt) = skills::uniform_path(&d.samples[forward]);
    Ok((path, dt, arm_base_pose(model, d.samples[at].base)))
}

/// Runs the experiment on one approach whose demonstration is `demo` of `dataset` (the
/// dataset's other demonstrations are not used).
pub fn run_approach(
    model: &RobotModel,
    dataset: &Dataset,
    demo: usize,
    name: &str,
    label: &str,
    grid: GoalGrid,
) -> Result<ApproachResult> {
    let d = &dataset.demonstrations[demo];
    let single = Dataset {
        demonstrations: vec![d.clone()],
        ..dataset.clone()
    };
    let cfg = LearnConfig::default();
    let learning = || format!("learning from demonstration {}", d.id);
    let mut learner = Learner::new(&single, model, &cfg).with_context(learning)?;
    let knowledge =
        learn_into(&mut learner, &single.demonstrations, &|_| {}).with_context(learning)?;
    let t = location_kinds(&single)
        .iter()
        .position(|k| *k == d.task.from.kind)
        .ok_or_else(|| anyhow!("location type {} not in the dataset", d.task.from.kind))?;
    let sweep = learner.sweep(t).ok_or_else(|| {
        anyhow!(
            "demonstration {} swept nothing at {}",
            d.id,
            d.task.from.kind
        )
    })?;
    let exact = BallUnion::dilated(&sweep.spheres, knowledge.config.workspace.epsilon);
    let Some(field) = knowledge.location_types[t].field.clone() else {
        bail!(
            "demonstration {} swept no workspace at {}",
            d.id,
            d.task.from.kind
        );
    };
    let (path, dt, base_world) = pick_motion(model, d)?;
    let location =
        pose_from_array(d.task.from.pose).ok_or_else(|| anyhow!("{}: bad location pose", d.id))?;
    let arm_base = location.inverse() * base_world;
    let rdmp = skills::train(model, &path, dt, &cfg.dmp, cfg.min_manipulability)
        .map_err(|e| anyhow!("TrainRDMP on {}: {e}", d.id))?;
    let dmp = PositionDmp::<NA>::train(&cfg.dmp, dt, path.len(), |k| SVector::from(path[k]))
        .map_err(|e| anyhow!("training the DMP on {}: {e}", d.id))?;
    let demo_end = JointVector::from(path[path.len() - 1]);
    let goal = ArmKinematics::new(model, &demo_end).tcp;
    let offsets = grid.offsets();
    let cells: Vec<(f64, f64)> = offsets
        .iter()
        .flat_map(|&dy| offsets.iter().map(move |&dx| (dx, dy)))
        .collect();
    let view = field.field();
    let ik = IkConfig::default();
    let home = JointVector::from(model.home);
    let goals = cells
        .par_iter()
        .map(|&(dx, dy)| {
            let g = Pose::from_parts(
                Translation3::from(goal.translation.vector + Vector3::new(dx, dy, 0.0)),
                goal.rotation,
            );
            let reachable = solutions(model, &g, &home, &ik).is_ok();
            let near = (dx.abs() <= EXACT_WITHIN + 1e-9 && dy.abs() <= EXACT_WITHIN + 1e-9)
                .then_some(&exact);
            let rdmp_t = rdmp_trajectory(model, &rdmp, &g, &view, near, &arm_base);
            let integrated = !matches!(rdmp_t.ending, Ending::Failed(_));
            let shifted = integrated
                .then(|| shift_toward(model, &rdmp_t.end.into(), &demo_end, cfg.min_manipulability))
                .flatten()
                .map(|shift| {
                    let t =
                        rdmp_trajectory(model, &rdmp.shifted(shift), &g, &view, near, &arm_base);
                    (shift, t)
                });
            let dmp = integrated
                .then(|| dmp_trajectory(model, &dmp, &rdmp_t.end, &view, near, &arm_base));
            GoalOutcome {
                dx,
                dy,
                reachable,
                rdmp: rdmp_t,
                shifted,
                dmp,
                floor: tcp_floor(model, &exact, &arm_base, &g),
            }
        })
        .collect();
    Ok(ApproachResult {
        name: name.to_string(),
        label: label.to_string(),
        demo: path,
        dt,
        goal,
        arm_base,
        field,
        exact,
        goals,
        grid,
    })
}

/// Depth inside Ω+ (−sdf where negative, else 0) on the horizontal plane through the
/// demonstrated goal, location frame: (xs, ys, values) over the field's extent, `n` per side.
pub fn workspace_slice(r: &ApproachResult, n: usize) -> (Vec<f64>, Vec<f64>, Vec<Option<f64>>) {
    let f = r.field.field();
    let [nx, ny, _] = f.dims();
    let lo = f.node_position(0, 0, 0);
    let hi = f.node_position(nx - 1, ny - 1, 0);
    let z = (r.arm_base * r.goal).translation.z;
    let axis = |a: f64, b: f64| -> Vec<f64> {
        (0..n)
            .map(|i| a + (b - a) * (i as f64 + 0.5) / n as f64)
            .collect()
    };
    let (xs, ys) = (axis(lo.x, hi.x), axis(lo.y, hi.y));
    let values = ys
        .iter()
        .flat_map(|&y| xs.iter().map(move |&x| (x, y)))
        .map(|(x, y)| Some((-f.distance(&Vector3::new(x, y, z))).max(0.0)))
        .collect();
    (xs, ys, values)
}

/// The whole experiment on `world`: generates the approaches' demonstrations (planner seed
/// `seed`) and runs each; `progress` is told of every approach done.
pub fn experiment(
    world: &World,
    grid: GoalGrid,
    seed: u64,
    progress: prf_files::OnProgress<'_>,
) -> Result<Vec<ApproachResult>> {
    let model = RobotModel::kmr_iiwa14();
    let list = approaches(world);
    let selection: Vec<AffordedTask> = list.iter().map(|a| a.task).collect();
    let dataset = prf_sim::demogen::generate_dataset(world, &selection, seed, 100.0, &|_| {})?;
    progress(prf_files::Progress::Total(list.len() as u64));
    list.iter()
        .enumerate()
        .map(|(i, a)| {
            let r = run_approach(&model, &dataset, i, &a.name, &world.label(&a.task), grid);
            progress(prf_files::Progress::Done(1));
            r
        })
        .collect()
}
