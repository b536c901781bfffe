//! Learn (Alg. 3): the pass over the dataset that drives every motion class of
//! [`prf_shared::motion::CLASSES`] and collects affordances, workspaces and skills.

use crate::affordance::AffordanceSet;
use crate::skills::{self, ArmSkill, Skill};
use crate::workspace::{self, LearnedField, PathSphere, Sweep, SweptPath, WorkspaceConfig};
use prf_files::dataset::{Dataset, DatasetDir, Demonstration, Placed};
use prf_files::{OnProgress, Progress};
use prf_shared::dmp::DmpParams;
use prf_shared::kinematics::{ArmKinematics, arm_base_pose, platform_pose};
use prf_shared::motion::{CLASSES, Frame, Instance, MotionClass, TaskLocation};
use prf_shared::robot::RobotModel;
use prf_shared::se3::{Pose, pose_from_array};
use prf_shared::{JointVector, NA};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

mod journal;
mod stored;

use journal::Grown;
pub use stored::KbFile;
use stored::Slot;

/// Settings of Learn.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LearnConfig {
    /// r_d to learn with, m: None takes the dataset's stated r_d; a value must not exceed it
    /// (a smaller one is more conservative). The workspaces are dilated by ε = r_d − r.
    pub clearance_demo: Option<f64>,
    /// The true acceptable clearance r, m.
    pub clearance_acceptable: f64,
    pub workspace: WorkspaceConfig,
    pub dmp: DmpParams,
    /// Arm motions with manipulability below this cannot be trained (Alg. 1 needs a null
    /// space).
    pub min_manipulability: f64,
}

impl Default for LearnConfig {
    fn default() -> Self {
        LearnConfig {
            clearance_demo: None,
            clearance_acceptable: 0.03,
            workspace: WorkspaceConfig::default(),
            // 30 bases reproduce these 2.6–4.1 s motions; 40 would cost 26 KiB more blob.
            dmp: DmpParams {
                n_basis: 30,
                ..DmpParams::default()
            },
            min_manipulability: prf_shared::rdmp::RdmpConfig::default().min_manipulability,
        }
    }
}

/// What was learned about a location type.
#[derive(Clone, Debug)]
pub struct LocationTypeKnowledge {
    pub name: String,
    /// A_b^ℓ: platform stances relative to the location.
    pub stances: AffordanceSet,
    /// Ω+ (None if no arm motion happened at this type).
    pub field: Option<LearnedField>,
    /// Instances that swept the workspace.
    pub instances: usize,
}

/// What was learned about a part type.
#[derive(Clone, Debug)]
pub struct PartTypeKnowledge {
    pub name: String,
    /// A_e^p: TCP poses relative to the part.
    pub grasps: AffordanceSet,
}

/// The output of Learn: A, Ω, K, with the robot model and figures.
#[derive(Clone, Debug)]
pub struct Knowledge {
    pub robot: RobotModel,
    pub description: String,
    pub config: LearnConfig,
    /// The r_d learned with, m (the dataset's, or a smaller one asked for).
    pub clearance_demo: f64,
    pub location_types: Vec<LocationTypeKnowledge>,
    pub part_types: Vec<PartTypeKnowledge>,
    pub arms: Vec<ArmSkill>,
    pub skills: Vec<Skill>,
    /// Instances found per class, in [`CLASSES`] order.
    pub instances: Vec<(&'static str, usize)>,
    pub demonstrations: usize,
    /// Wall time of the learning steps, s.
    pub timings: Vec<(&'static str, f64)>,
}

impl Knowledge {
    /// The knowledge with only the RDMPs in `keep` (indices into [`Knowledge::arms`]) and the
    /// skills that use them or have none (a fixed generator such as BaseMove), RDMP indices
    /// renumbered in order. Dropping a skill removes a candidate from every plan; it never
    /// changes another's risk.
    pub fn keeping_rdmps(&self, keep: &std::collections::BTreeSet<usize>) -> Knowledge {
        let renumbered: std::collections::HashMap<usize, usize> = keep
            .iter()
            .enumerate()
            .map(|(new, &old)| (old, new))
            .collect();
        Knowledge {
            arms: keep
                .iter()
                .filter_map(|&i| self.arms.get(i).cloned())
                .collect(),
            skills: self
                .skills
                .iter()
                .filter_map(|s| match s.rdmp {
                    None => Some(s.clone()),
                    Some(r) => Some(Skill {
                        rdmp: Some(*renumbered.get(&r)?),
                        ..s.clone()
                    }),
                })
                .collect(),
            ..self.clone()
        }
    }
}

/// One instance of a class in one demonstration, with what it teaches: what Alg. 3 lines
/// 5–16 compute from the demonstration alone (in parallel, and once for any number of
/// learners that add it).
#[derive(Clone, Debug)]
pub struct Lesson {
    class: &'static str,
    location_type: Option<usize>,
    part_type: usize,
    affordance: Option<(Frame, Pose)>,
    /// The instance's robot spheres in the location frame, in sweep order.
    sweep: Option<Arc<SweptPath>>,
    arm: Option<ArmLesson>,
}

/// A learnable arm motion's lesson: its uniform joint path, time step and trained RDMP.
type ArmLesson = (Vec<[f64; 7]>, f64, prf_shared::rdmp::Rdmp);

/// The lessons of one demonstration.
#[derive(Clone, Debug)]
pub struct Lessons {
    /// The demonstration's id.
    pub demonstration: String,
    /// Its [`fingerprint`].
    pub fingerprint: u32,
    lessons: Vec<Lesson>,
}

impl Lessons {
    /// The location types whose workspaces these lessons grow (their swept spheres), ascending.
    pub fn swept_types(&self) -> Vec<usize> {
        let mut types: Vec<usize> = self
            .lessons
            .iter()
            .filter(|l| l.sweep.is_some())
            .filter_map(|l| l.location_type)
            .collect();
        types.sort_unstable();
        types.dedup();
        types
    }
}

fn location_of(d: &Demonstration, l: TaskLocation) -> &Placed {
    match l {
        TaskLocation::From => &d.task.from,
        TaskLocation::To => &d.task.to,
    }
}

/// Why Learn refused a dataset.
#[derive(Debug, thiserror::Error)]
pub enum LearnError {
    #[error(
        "the acceptable clearance r = {acceptable} m exceeds the programs' clearance r_d = {demo} m"
    )]
    Clearance { acceptable: f64, demo: f64 },
    #[error(
        "the dataset does not state r_d, the clearance its programs kept from every obstacle: add \"clearance_demo_m\" (metres) to its manifest.json. Learning dilates the workspaces by ε = r_d − r, and an r_d larger than the programs kept makes risk 0 unsafe, so it is never guessed (check it with `prf check-dataset --world`)"
    )]
    NoClearance,
    #[error(
        "r_d = {requested} m is larger than the dataset's stated r_d = {stated} m: ε = r_d − r would exceed what the programs kept, and risk 0 would no longer guarantee clearance r (a smaller r_d is allowed)"
    )]
    ClearanceAboveStated { requested: f64, stated: f64 },
    #[error("demonstration {demonstration}: the {what} pose is not a valid pose")]
    BadPose {
        demonstration: String,
        what: &'static str,
    },
    #[error(
        "the dataset is of another cell: location types {locations:?} and part types {parts:?}, the knowledge base's are {kb_locations:?} and {kb_parts:?}"
    )]
    OtherCell {
        locations: Vec<String>,
        parts: Vec<String>,
        kb_locations: Vec<String>,
        kb_parts: Vec<String>,
    },
    #[error(
        "the dataset states r_d = {stated} m, below the knowledge base's r_d = {kb} m: its programs kept less clearance than the workspaces were dilated for (ε = r_d − r), so adding them would make risk 0 unsafe; learn everything again with the smaller r_d"
    )]
    ClearanceBelowKb { stated: f64, kb: f64 },
    #[error(
        "demonstration {id} is already in the knowledge base (as {as_id}: the same task and trajectory); adding it twice would count its affordances twice"
    )]
    AlreadyAdded { id: String, as_id: String },
    #[error("demonstration {demonstration}: part type {kind} is not among the dataset's parts")]
    PartType { demonstration: String, kind: String },
    #[error(
        "demonstration {demonstration} (lines {first}–{last} of its trajectory): {class} arm motion cannot be trained: {error}"
    )]
    Skill {
        demonstration: String,
        first: usize,
        last: usize,
        class: &'static str,
        error: prf_shared::rdmp::RdmpError,
    },
    #[error(transparent)]
    Kb(#[from] crate::kb::KbError),
    #[error(transparent)]
    Dataset(#[from] prf_files::dataset::DatasetError),
}

/// Pose of frame `f` at sample `at` of an instance.
fn frame_pose(
    model: &RobotModel,
    d: &Demonstration,
    inst: &Instance,
    f: Frame,
) -> Result<Option<Pose>, LearnError> {
    let s = &d.samples[inst.at];
    let placed = |p: &[f64; 7]| {
        pose_from_array(*p).ok_or_else(|| LearnError::BadPose {
            demonstration: d.id.clone(),
            what: "part or location",
        })
    };
    Ok(match f {
        Frame::World => Some(Pose::identity()),
        Frame::Base => Some(platform_pose(s.base)),
        Frame::Tcp => Some(
            arm_base_pose(model, s.base) * ArmKinematics::new(model, &JointVector::from(s.arm)).tcp,
        ),
        Frame::Part => match inst.location {
            Some(TaskLocation::From) => Some(placed(&d.task.part.pose)?),
            Some(TaskLocation::To) => Some(placed(&d.task.goal)?),
            None => None,
        },
        Frame::Location => match inst.location {
            Some(l) => Some(placed(&location_of(d, l).pose)?),
            None => None,
        },
    })
}

/// CSV line of sample `k` (line 1 is the header).
fn line(k: usize) -> usize {
    k + 2
}

/// A demonstration's lesson part that failed: the index of the instance it failed on, and why.
type Failed = (usize, LearnError);

/// Alg. 3, lines 5–11 for one demonstration, with the location and part types named in
/// `kinds` and `part_kinds`: its instances segmented per class, then each one's affordance
/// and swept spheres (in parallel), its arm motion left to [`arm_lessons`]. The first
/// failure in instance order.
fn shapes(
    model: &RobotModel,
    kinds: &[String],
    part_kinds: &[String],
    d: &Demonstration,
    cfg: &LearnConfig,
) -> Result<Lessons, Failed> {
    let Some(part_type) = part_kinds.iter().position(|k| *k == d.task.part.kind) else {
        let (demonstration, kind) = (d.id.clone(), d.task.part.kind.clone());
        return Err((
            0,
            LearnError::PartType {
                demonstration,
                kind,
            },
        ));
    };
    let per_instance: Vec<Result<Lesson, Failed>> = instances(d)
        .into_par_iter()
        .enumerate()
        .map(|(i, (m, inst))| shape(model, kinds, d, cfg, m, inst, part_type).map_err(|e| (i, e)))
        .collect();
    Ok(Lessons {
        demonstration: d.id.clone(),
        fingerprint: fingerprint(d),
        lessons: per_instance.into_iter().collect::<Result<_, _>>()?,
    })
}

/// Alg. 3, lines 12–16 for one demonstration: the trained RDMP of each of its instances
/// ([`arm_lesson`]), in instance order; the first failure in that order.
fn arm_lessons(
    model: &RobotModel,
    d: &Demonstration,
    cfg: &LearnConfig,
) -> Result<Vec<Option<ArmLesson>>, Failed> {
    let per_instance: Vec<Result<Option<ArmLesson>, Failed>> = instances(d)
        .into_par_iter()
        .enumerate()
        .map(|(i, (m, inst))| arm_lesson(model, d, cfg, m, &inst).map_err(|e| (i, e)))
        .collect();
    per_instance.into_iter().collect()
}

/// A demonstration's lessons from its [`shapes`] and [`arm_lessons`]; if either failed, the
/// failure on the earlier instance, its shape's before its arm's (what learning the
/// instances one by one would report).
fn joined(
    shapes: Result<Lessons, Failed>,
    arms: Result<Vec<Option<ArmLesson>>, Failed>,
) -> Result<Lessons, LearnError> {
    match (shapes, arms) {
        (Ok(mut lessons), Ok(arms)) => {
            for (l, arm) in lessons.lessons.iter_mut().zip(arms) {
                l.arm = arm;
            }
            Ok(lessons)
        }
        (Err((i, e)), Err((j, _))) if i <= j => Err(e),
        (_, Err((_, e))) | (Err((_, e)), _) => Err(e),
    }
}

/// Alg. 3 line 5 for demonstration `d`: every instance of every class, class by class.
fn instances(d: &Demonstration) -> Vec<(&'static dyn MotionClass, Instance)> {
    let mut instances = Vec::new();
    for m in CLASSES.iter() {
        m.segment(&d.samples, &mut |i| instances.push((*m, i)));
    }
    instances
}

/// The location whose workspace instance `inst` of class `m` sweeps (line 11), if any.
fn swept_location(m: &dyn MotionClass, inst: &Instance) -> Option<TaskLocation> {
    let in_location = m.frames().workspace == Frame::Location;
    inst.location
        .filter(|_| m.learns_workspace() && in_location)
}

/// The location types whose workspaces the lessons of `d` grow, ascending, from its
/// segmentation alone: [`Lessons::swept_types`] before the lessons are learned.
fn swept_types_of(kinds: &[String], d: &Demonstration) -> Vec<usize> {
    let mut types: Vec<usize> = instances(d)
        .iter()
        .filter_map(|(m, inst)| swept_location(*m, inst))
        .filter_map(|l| kinds.iter().position(|k| *k == location_of(d, l).kind))
        .collect();
    types.sort_unstable();
    types.dedup();
    types
}

/// The lesson of instance `inst` of class `m` in demonstration `d` but for its arm motion:
/// its affordance and the spheres it sweeps.
fn shape(
    model: &RobotModel,
    kinds: &[String],
    d: &Demonstration,
    cfg: &LearnConfig,
    m: &'static dyn MotionClass,
    inst: Instance,
    part_type: usize,
) -> Result<Lesson, LearnError> {
    let location_type = inst
        .location
        .and_then(|l| kinds.iter().position(|k| *k == location_of(d, l).kind));
    let fr = m.frames();
    let affordance = match (
        frame_pose(model, d, &inst, fr.robot)?,
        frame_pose(model, d, &inst, fr.affordance)?,
    ) {
        (Some(r), Some(a)) => Some((fr.affordance, a.inverse() * r)),
        _ => None,
    };
    let sweep = match swept_location(m, &inst) {
        None => None,
        Some(l) => {
            let loc =
                pose_from_array(location_of(d, l).pose).ok_or_else(|| LearnError::BadPose {
                    demonstration: d.id.clone(),
                    what: "location",
                })?;
            let s = &d.samples[inst.at];
            let path: Vec<[f64; 7]> = d.samples[inst.range.clone()]
                .iter()
                .map(|s| s.arm)
                .collect();
            let base = loc.inverse() * arm_base_pose(model, s.base);
            Some(Arc::new(SweptPath::of(
                model,
                &base,
                &path,
                cfg.workspace.resample,
            )))
        }
    };
    Ok(Lesson {
        class: m.name(),
        location_type,
        part_type,
        affordance,
        sweep,
        arm: None,
    })
}

/// The RDMP instance `inst` of class `m` in demonstration `d` teaches (TrainRDMP, Alg. 1),
/// with its uniform path and time step; None for a class without a learnable arm motion.
fn arm_lesson(
    model: &RobotModel,
    d: &Demonstration,
    cfg: &LearnConfig,
    m: &'static dyn MotionClass,
    inst: &Instance,
) -> Result<Option<ArmLesson>, LearnError> {
    Ok(
        match (&inst.arm, m.generators().iter().any(|g| g.learnable())) {
            (Some(a), true) => {
                let (path, dt) = skills::uniform_path(&d.samples[a.forward.clone()]);
                let rdmp = skills::train(model, &path, dt, &cfg.dmp, cfg.min_manipulability)
                    .map_err(|error| LearnError::Skill {
                        demonstration: d.id.clone(),
                        first: line(a.forward.start),
                        last: line(a.forward.end - 1),
                        class: m.name(),
                        error,
                    })?;
                Some((path, dt, rdmp))
            }
            _ => None,
        },
    )
}

/// Location types in first-appearance order of the manifest.
pub fn location_kinds(ds: &Dataset) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for l in &ds.locations {
        if !v.contains(&l.kind) {
            v.push(l.kind.clone());
        }
    }
    v
}

/// Part types in first-appearance order of the manifest.
pub fn part_kinds(ds: &Dataset) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for p in &ds.parts {
        if !v.contains(&p.kind) {
            v.push(p.kind.clone());
        }
    }
    v
}

/// The r_d to learn with (Sec. 4.1): the dataset's `stated` one, or a `requested` one no
/// larger. A dataset that does not state it is refused.
pub fn resolve_clearance_demo(
    stated: Option<f64>,
    requested: Option<f64>,
) -> Result<f64, LearnError> {
    let stated = stated.ok_or(LearnError::NoClearance)?;
    match requested {
        Some(requested) if requested > stated => {
            Err(LearnError::ClearanceAboveStated { requested, stated })
        }
        Some(requested) => Ok(requested),
        None => Ok(stated),
    }
}

/// Learn (Alg. 3) on a dataset read for `model`: every demonstration's lessons (in
/// parallel), added in dataset order to a [`Learner`].
pub fn learn(
    ds: &Dataset,
    model: &RobotModel,
    cfg: &LearnConfig,
    progress: OnProgress<'_>,
) -> Result<Knowledge, LearnError> {
    let mut learner = Learner::new(ds, model, cfg)?;
    learn_into(&mut learner, &ds.demonstrations, progress)
}

/// Demonstrations [`learn_dir`] reads and learns at once: enough to keep every core busy,
/// few enough that their samples and swept spheres (about 3 MB each on the example cell)
/// stay far below what learning keeps.
pub const CHUNK: usize = 32;

/// [`learn`] on the dataset in a directory, read and learned `chunk` demonstrations at a
/// time (the next chunk read while one is learned): the memory follows what is learned, not
/// how many programs were read. The same knowledge as [`learn`] on the whole dataset, and
/// the learner, for a knowledge base.
pub fn learn_dir(
    dir: &DatasetDir,
    model: &RobotModel,
    cfg: &LearnConfig,
    chunk: usize,
    progress: OnProgress<'_>,
) -> Result<(Knowledge, Learner), LearnError> {
    let mut learner = Learner::new(&dir.header(), model, cfg)?;
    let types = learner.location_kinds.len();
    progress(Progress::Total((dir.len() + types) as u64));
    let chunk = chunk.max(1);
    let range = |start: usize| start..(start + chunk).min(dir.len());
    let t0 = Instant::now();
    let mut next = (!dir.is_empty()).then(|| dir.read(range(0), model));
    let mut start = 0;
    while let Some(demos) = next.take() {
        let demos = demos?;
        start += demos.len();
        let (read, absorbed) = rayon::join(
            || (start < dir.len()).then(|| dir.read(range(start), model)),
            || learner.absorb(&demos, progress),
        );
        absorbed?;
        next = read;
    }
    let t_lessons = t0.elapsed().as_secs_f64();
    let (knowledge, t_fields) = timed(|| learner.knowledge(progress));
    let mut knowledge = knowledge?;
    knowledge.timings = vec![("lessons", t_lessons), ("workspaces", t_fields)];
    Ok((knowledge, learner))
}

/// [`learn`] into an existing learner: `demos`' lessons (in parallel), added in order, then
/// the fields of the location types they touch rebuilt (`prf learn --add`, [`crate::kb`]).
pub fn learn_into(
    learner: &mut Learner,
    demos: &[Demonstration],
    progress: OnProgress<'_>,
) -> Result<Knowledge, LearnError> {
    learn_lessons_into(learner, demos, progress).map(|(k, _)| k)
}

/// [`learn_into`], also giving the demonstrations' lessons (for [`Learner::addition`]).
///
/// TrainRDMP (Alg. 3 lines 12–16, pacing most of it) runs beside the rest, which does not
/// wait for the skills: the affordances and swept spheres (lines 5–11, beside them the stored
/// sweeps they grow read from the file), added in dataset order, then the fields of the types
/// they touch rebuilt. The skills are added last, in the same order, so the state is what
/// adding the lessons one by one gives. On an error the learner is left part-way (its
/// sweeps may have grown without the skills): drop it.
pub fn learn_lessons_into(
    learner: &mut Learner,
    demos: &[Demonstration],
    progress: OnProgress<'_>,
) -> Result<(Knowledge, Vec<Lessons>), LearnError> {
    progress(Progress::Total(
        (demos.len() + learner.location_kinds.len()) as u64,
    ));
    let (robot, cfg) = (learner.robot.clone(), learner.config);
    let mut skilled = (Vec::new(), 0.0);
    let skills = || {
        timed(|| {
            demos
                .par_iter()
                .map(|d| {
                    let arms = arm_lessons(&robot, d, &cfg);
                    progress(Progress::Done(1));
                    arms
                })
                .collect::<Vec<_>>()
        })
    };
    // The skills are queued after the stored sweeps' read, by the thread that read them, so
    // the workspaces (which wait for the read) are not kept waiting by the skills.
    let ((shapes, grown), t_grown) = rayon::scope(|s| {
        timed(|| {
            learner.grow(demos, progress, || {
                s.spawn(|_| skilled = skills());
            })
        })
    });
    let (arms, t_arms) = skilled;
    let lessons = shapes
        .into_iter()
        .zip(arms)
        .map(|(s, a)| joined(s, a))
        .collect::<Result<Vec<Lessons>, LearnError>>()?;
    grown?;
    for l in &lessons {
        learner.add_skills(l);
    }
    let mut knowledge = learner.assemble();
    knowledge.timings = vec![("skills", t_arms), ("workspaces", t_grown)];
    Ok((knowledge, lessons))
}

/// `f`'s result and its wall time, s.
fn timed<R>(f: impl FnOnce() -> R) -> (R, f64) {
    let t0 = Instant::now();
    let r = f();
    (r, t0.elapsed().as_secs_f64())
}

/// Learn (Alg. 3) one demonstration at a time: the state after the demonstrations added so
/// far. Adding a demonstration merges its [`Lessons`] (affordances, skills) and queues its
/// spheres for the location types it touches; [`Learner::knowledge`] adds them to those types'
/// sweeps and rebuilds only their fields, one type per thread. Adding in dataset order gives
/// exactly what [`learn`] gives on the dataset ([`learn`] is this, in one pass).
#[derive(Clone, Debug)]
pub struct Learner {
    robot: RobotModel,
    description: String,
    config: LearnConfig,
    clearance_demo: f64,
    location_kinds: Vec<String>,
    part_kinds: Vec<String>,
    location_types: Vec<LocationTypeKnowledge>,
    part_types: Vec<PartTypeKnowledge>,
    /// Per location type, its sweep (left in the file by [`Learner::open`] until needed).
    sweeps: Vec<Slot>,
    /// Per location type, the spheres added since the last field build, in order.
    pending: Vec<Vec<Arc<SweptPath>>>,
    /// Per location type, whether its sweep grew since its field was built
    /// ([`Learner::absorb`] grows sweeps without building).
    unbuilt: Vec<bool>,
    /// Per location type, the certification margin its field is built with where it is not
    /// the configuration's ([`Learner::recertify_type`], a flash budget's); not saved.
    margins: Vec<Option<f64>>,
    /// Per location type, the paths its last field build grew its sweep by and which of
    /// their spheres were new (what an addition records of them, [`Learner::addition`]).
    grown: Vec<Grown>,
    arms: Vec<ArmSkill>,
    /// K before share().
    skills: Vec<Skill>,
    instances: Vec<(&'static str, usize)>,
    demonstrations: usize,
    /// The demonstrations added, in order: id and [`fingerprint`].
    ids: Vec<(String, u32)>,
}

impl Learner {
    /// An empty learner for the types of dataset `ds` (its demonstrations are not added).
    pub fn new(ds: &Dataset, model: &RobotModel, cfg: &LearnConfig) -> Result<Self, LearnError> {
        let clearance_demo = resolve_clearance_demo(ds.clearance_demo, cfg.clearance_demo)?;
        let mut config = *cfg;
        config.workspace.epsilon = clearance_demo - cfg.clearance_acceptable;
        if !(config.workspace.epsilon >= 0.0) {
            return Err(LearnError::Clearance {
                acceptable: cfg.clearance_acceptable,
                demo: clearance_demo,
            });
        }
        config.workspace.certify_margin = config.workspace.margin_for(config.workspace.epsilon);
        let location_kinds = location_kinds(ds);
        let part_kinds = part_kinds(ds);
        Ok(Learner {
            robot: model.clone(),
            description: ds.description.clone().unwrap_or_default(),
            config,
            clearance_demo,
            location_types: location_kinds
                .iter()
                .map(|k| LocationTypeKnowledge {
                    name: k.clone(),
                    stances: AffordanceSet::default(),
                    field: None,
                    instances: 0,
                })
                .collect(),
            part_types: part_kinds
                .iter()
                .map(|name| PartTypeKnowledge {
                    name: name.clone(),
                    grasps: AffordanceSet::default(),
                })
                .collect(),
            sweeps: vec![
                Slot::Ready(Box::new(Sweep::new(config.workspace.feature_spacing)));
                location_kinds.len()
            ],
            pending: vec![Vec::new(); location_kinds.len()],
            unbuilt: vec![false; location_kinds.len()],
            margins: vec![None; location_kinds.len()],
            grown: vec![Grown::default(); location_kinds.len()],
            location_kinds,
            part_kinds,
            arms: Vec::new(),
            skills: Vec::new(),
            instances: CLASSES.iter().map(|c| (c.name(), 0)).collect(),
            demonstrations: 0,
            ids: Vec::new(),
        })
    }

    /// Alg. 3 lines 5–16 on demonstration `d` alone (segmentation, affordances, the swept
    /// spheres, TrainRDMP): what [`Learner::add`] merges. Independent of what was added.
    pub fn lessons(&self, d: &Demonstration) -> Result<Lessons, LearnError> {
        let (shapes, arms) = rayon::join(
            || self.shapes(d),
            || arm_lessons(&self.robot, d, &self.config),
        );
        joined(shapes, arms)
    }

    /// [`shapes`] of `d` with this learner's types.
    fn shapes(&self, d: &Demonstration) -> Result<Lessons, Failed> {
        shapes(
            &self.robot,
            &self.location_kinds,
            &self.part_kinds,
            d,
            &self.config,
        )
    }

    /// The part of [`learn_lessons_into`] that does not wait for the skills: the [`shapes`]
    /// of `demos` (in parallel; beside them, the stored sweeps they grow are read,
    /// [`Learner::read_ahead`]), added in order if none failed, then the fields they touch
    /// rebuilt. The shapes, and whether the sweeps were read and the fields rebuilt.
    ///
    /// `queue` is called once, by the thread that read, right after the read: the work it
    /// queues there (the skills) follows the read on that thread. Queued on the thread that
    /// learns the shapes, it was that thread's next job once the shapes were done; a rayon
    /// thread waiting in a join runs its own queue first, so a late read had the fields wait
    /// for a whole skill (4 of 6 traced runs of d063's `--add`: learning 20–24 ms, against
    /// 14–18 ms in the other two).
    fn grow(
        &mut self,
        demos: &[Demonstration],
        progress: OnProgress<'_>,
        queue: impl FnOnce() + Send,
    ) -> (Vec<Result<Lessons, Failed>>, Result<(), LearnError>) {
        let (shapes, read) = rayon::join(
            || demos.par_iter().map(|d| self.shapes(d)).collect::<Vec<_>>(),
            || {
                let read = self.read_ahead(demos);
                queue();
                read
            },
        );
        if shapes.iter().any(Result::is_err) {
            return (shapes, Ok(()));
        }
        for l in shapes.iter().flatten() {
            self.add_shapes(l);
        }
        let built = self.install_and_rebuild(read, progress);
        (shapes, built)
    }

    /// The sweeps `read` ahead installed, as the field builds would read them (in type
    /// order, those with new spheres), then the fields rebuilt ([`Learner::rebuild`]).
    fn install_and_rebuild(
        &mut self,
        read: Vec<(usize, Result<Sweep, crate::kb::KbError>)>,
        progress: OnProgress<'_>,
    ) -> Result<(), LearnError> {
        for (t, sweep) in read {
            if !self.pending[t].is_empty() {
                self.install(t, sweep?)?;
            }
        }
        Ok(self.rebuild(&|p| {
            if let Progress::Done(n) = p {
                progress(Progress::Done(n))
            }
        })?)
    }

    /// The sweeps still in the file of the location types the lessons of `demos` will grow
    /// ([`swept_types_of`]), decoded in type order ([`Learner::decode_stored`]): read while
    /// the lessons are learned, not after them.
    fn read_ahead(
        &self,
        demos: &[Demonstration],
    ) -> Vec<(usize, Result<Sweep, crate::kb::KbError>)> {
        // A learner with every sweep read (batch learning) segments no demonstration twice.
        if self.sweeps.iter().all(|s| s.ready().is_some()) {
            return Vec::new();
        }
        let mut types: Vec<usize> = demos
            .iter()
            .flat_map(|d| swept_types_of(&self.location_kinds, d))
            .collect();
        types.sort_unstable();
        types.dedup();
        types
            .into_iter()
            .filter_map(|t| Some((t, self.decode_stored(t)?)))
            .collect()
    }

    /// Merges a demonstration's lessons (Alg. 3 lines 9, 13–16) and queues its swept spheres
    /// (line 11) for [`Learner::knowledge`].
    pub fn add(&mut self, lessons: &Lessons) {
        self.add_shapes(lessons);
        self.add_skills(lessons);
    }

    /// [`Learner::add`] but for the skills: the demonstration and its instances counted, its
    /// affordances merged (line 9) and its swept spheres queued (line 11).
    fn add_shapes(&mut self, lessons: &Lessons) {
        self.demonstrations += 1;
        self.ids
            .push((lessons.demonstration.clone(), lessons.fingerprint));
        for l in &lessons.lessons {
            if let Some(c) = self.instances.iter_mut().find(|c| c.0 == l.class) {
                c.1 += 1;
            }
            // Line 9: A_{f_r}^{f_a}.
            match (l.affordance, l.location_type) {
                (Some((Frame::Part, p)), _) => {
                    self.part_types[l.part_type].grasps.insert(p);
                }
                (Some((Frame::Location, p)), Some(t)) => {
                    self.location_types[t].stances.insert(p);
                }
                _ => {}
            }
            // Line 11: Ω+ of the workspace frame.
            if let (Some(spheres), Some(t)) = (&l.sweep, l.location_type) {
                self.location_types[t].instances += 1;
                self.pending[t].push(spheres.clone());
            }
        }
    }

    /// The rest of [`Learner::add`]: the skills of `lessons` (lines 13–16; a set, equal arm
    /// motions stored once).
    fn add_skills(&mut self, lessons: &Lessons) {
        for l in &lessons.lessons {
            let rdmp = l.arm.as_ref().map(|(path, dt, rdmp)| {
                skills::find_same(&self.arms, path, *dt).unwrap_or_else(|| {
                    self.arms.push(ArmSkill {
                        rdmp: *rdmp,
                        path: Arc::new(path.clone()),
                        dt: *dt,
                    });
                    self.arms.len() - 1
                })
            });
            let learnable = prf_shared::motion::class(l.class)
                .is_some_and(|c| c.generators().iter().any(|g| g.learnable()));
            if learnable && rdmp.is_none() {
                continue;
            }
            let skill = Skill {
                class: l.class,
                rdmp,
                location_type: if learnable { l.location_type } else { None },
                part_type: if learnable { Some(l.part_type) } else { None },
                demo: if learnable {
                    lessons.demonstration.clone()
                } else {
                    String::new()
                },
                shared: false,
            };
            if !self
                .skills
                .iter()
                .any(|k| k.class == skill.class && k.rdmp == skill.rdmp)
            {
                self.skills.push(skill);
            }
        }
    }

    /// Demonstrations added so far.
    pub fn demonstrations(&self) -> usize {
        self.demonstrations
    }

    /// The demonstrations added so far, in order: id and [`fingerprint`].
    pub fn ids(&self) -> &[(String, u32)] {
        &self.ids
    }

    /// The robot model learned for.
    pub fn robot(&self) -> &RobotModel {
        &self.robot
    }

    /// The sweep of location type `t` (its demonstrated spheres and feature balls) once its
    /// field is built, None while it is still in the knowledge-base file or `t` is past the
    /// types.
    pub fn sweep(&self, t: usize) -> Option<&Sweep> {
        self.sweeps.get(t).and_then(Slot::ready)
    }

    /// Certifies the demonstrated spheres with `margin` from now on (capped as
    /// [`crate::workspace::WorkspaceConfig::margin_for`] says): every field is rebuilt by the
    /// next [`Learner::knowledge`]. A smaller margin stores fewer certificates (a smaller
    /// blob) and rates risk 0 over less of the space around the demonstrations.
    pub fn recertify(&mut self, margin: f64) {
        let w = &mut self.config.workspace;
        w.certify_margin = margin;
        w.certify_margin = w.margin_for(w.epsilon);
        self.margins.fill(None);
        self.unbuilt.fill(true);
    }

    /// [`Learner::recertify`] for location type `t` alone (its field is rebuilt by the next
    /// [`Learner::knowledge`]); the knowledge base keeps the configured margin.
    pub fn recertify_type(&mut self, t: usize, margin: f64) {
        let w = WorkspaceConfig {
            certify_margin: margin,
            ..self.config.workspace
        };
        if let (Some(m), Some(u)) = (self.margins.get_mut(t), self.unbuilt.get_mut(t)) {
            (*m, *u) = (Some(w.margin_for(w.epsilon)), true);
        }
    }

    /// The certification margin location type `t`'s field is built with, m.
    pub fn margin(&self, t: usize) -> f64 {
        self.workspace_config(t).certify_margin
    }

    /// The workspace settings location type `t`'s field is built with.
    fn workspace_config(&self, t: usize) -> WorkspaceConfig {
        let mut w = self.config.workspace;
        if let Some(Some(m)) = self.margins.get(t) {
            w.certify_margin = *m;
        }
        w
    }

    /// The location types' names, in type order.
    pub fn location_kinds(&self) -> &[String] {
        &self.location_kinds
    }

    /// Whether `ds`'s demonstrations may be added: the same cell (location and part types),
    /// a stated r_d at least the one learned with (programs that kept less clearance would
    /// make ε unsafe), and no program already added (by [`fingerprint`]: ids repeat across
    /// datasets).
    pub fn admits(&self, ds: &Dataset) -> Result<(), LearnError> {
        let (locations, parts) = (location_kinds(ds), part_kinds(ds));
        if locations != self.location_kinds || parts != self.part_kinds {
            return Err(LearnError::OtherCell {
                locations,
                parts,
                kb_locations: self.location_kinds.clone(),
                kb_parts: self.part_kinds.clone(),
            });
        }
        match ds.clearance_demo {
            None => return Err(LearnError::NoClearance),
            Some(r) if !(r >= self.clearance_demo) => {
                return Err(LearnError::ClearanceBelowKb {
                    stated: r,
                    kb: self.clearance_demo,
                });
            }
            Some(_) => {}
        }
        for d in &ds.demonstrations {
            let f = fingerprint(d);
            if let Some((id, _)) = self.ids.iter().find(|(_, g)| *g == f) {
                return Err(LearnError::AlreadyAdded {
                    id: d.id.clone(),
                    as_id: id.clone(),
                });
            }
        }
        Ok(())
    }

    /// The learner's whole state as a knowledge-base file ([`crate::kb`]). A sweep still in
    /// the file it was opened on is read first if additions changed it, and is otherwise
    /// saved as the bytes read.
    pub fn save(&mut self) -> Result<Vec<u8>, crate::kb::KbError> {
        use crate::kb::*;
        for t in 0..self.sweeps.len() {
            if self.sweeps[t].ready().is_none() && self.sweeps[t].unchanged().is_none() {
                self.read_sweep(t)?;
            }
        }
        let written: Vec<Option<Vec<u8>>> = self
            .sweeps
            .iter()
            .map(|s| s.ready().map(|s| section(&s.to_state())))
            .collect();
        let sections: Vec<&[u8]> = self
            .sweeps
            .iter()
            .zip(&written)
            .map(|(s, w)| w.as_deref().or(s.unchanged()).unwrap_or_default())
            .collect();
        let affordances = |a: &AffordanceSet| AffordanceState {
            poses: a.poses.iter().map(pose_state).collect(),
            counts: a.counts.clone(),
        };
        let v = |c: &nalgebra::Vector3<f64>| [c.x, c.y, c.z];
        let state = LearnerState {
            robot: RobotState::of(&self.robot),
            description: self.description.clone(),
            config: self.config,
            clearance_demo: self.clearance_demo,
            location_kinds: self.location_kinds.clone(),
            part_kinds: self.part_kinds.clone(),
            location_types: self
                .location_types
                .iter()
                .map(|t| (affordances(&t.stances), t.field.clone(), t.instances))
                .collect(),
            part_types: self
                .part_types
                .iter()
                .map(|p| affordances(&p.grasps))
                .collect(),
            pending: self
                .pending
                .iter()
                .map(|per| {
                    per.iter()
                        .map(|path| path.spheres().map(|s| (v(&s.centre), s.sphere)).collect())
                        .collect()
                })
                .collect(),
            arms: self
                .arms
                .iter()
                .map(|a| ArmState {
                    rdmp: RdmpState::of(&a.rdmp),
                    path: a.path.to_vec(),
                    dt: a.dt,
                })
                .collect(),
            skills: self
                .skills
                .iter()
                .map(|k| SkillState {
                    class: k.class.to_string(),
                    rdmp: k.rdmp,
                    location_type: k.location_type,
                    part_type: k.part_type,
                    demo: k.demo.clone(),
                    shared: k.shared,
                })
                .collect(),
            instances: self
                .instances
                .iter()
                .map(|(c, n)| (c.to_string(), *n))
                .collect(),
            demonstrations: self.demonstrations,
            ids: self.ids.clone(),
        };
        Ok(encode(&state, &sections))
    }

    /// The learner a knowledge-base file holds, every part of it read and checked: the base
    /// [`Learner::save`] wrote, then each addition after it ([`Learner::addition`]) replayed.
    pub fn load(bytes: &[u8]) -> Result<Self, crate::kb::KbError> {
        Self::read(bytes, None)
    }

    /// The learner of the file `bytes`; with `file` (the same bytes) its sweeps are left in
    /// it ([`Learner::open`]), without them read here.
    fn read(bytes: &[u8], file: Option<&KbFile>) -> Result<Self, crate::kb::KbError> {
        let decoded = crate::kb::decode(bytes)?;
        let mut learner = Self::from_state(decoded.base)?;
        for (t, range) in decoded.sweeps.into_iter().enumerate() {
            learner.sweeps[t] = match file {
                Some(f) => Slot::stored(f.clone(), range),
                None => {
                    let section = &bytes[range.clone()];
                    Slot::Ready(Box::new(learner.sweep_of(t, section, range.start, None)?))
                }
            };
        }
        for a in decoded.additions {
            learner.replay(a)?;
        }
        for t in 0..learner.sweeps.len() {
            learner.check_grid(t)?;
        }
        Ok(learner)
    }

    /// The learner of a knowledge base's core, its sweeps empty.
    fn from_state(mut st: crate::kb::LearnerState) -> Result<Self, crate::kb::KbError> {
        use crate::kb::*;
        let class = |name: &str| {
            CLASSES
                .iter()
                .map(|c| c.name())
                .find(|n| *n == name)
                .ok_or_else(|| KbError::Class(name.to_string()))
        };
        let affordances = |a: &AffordanceState| -> Result<AffordanceSet, KbError> {
            Ok(AffordanceSet {
                poses: a
                    .poses
                    .iter()
                    .map(|p| pose_of(*p))
                    .collect::<Result<_, _>>()?,
                counts: a.counts.clone(),
            })
        };
        let types = st.location_kinds.len();
        if st.location_types.len() != types || st.pending.len() != types {
            return Err(KbError::Decode(format!(
                "{types} location types, but {} type records, {} queues",
                st.location_types.len(),
                st.pending.len()
            )));
        }
        if st.part_types.len() != st.part_kinds.len() {
            return Err(KbError::Decode(format!(
                "{} part types, but {} grasp sets",
                st.part_kinds.len(),
                st.part_types.len()
            )));
        }
        // The fields and the arms' paths are moved out of the decoded state, not copied.
        let mut location_types = Vec::new();
        let kinds = st.location_kinds.iter();
        for (name, (stances, field, instances)) in kinds.zip(std::mem::take(&mut st.location_types))
        {
            location_types.push(LocationTypeKnowledge {
                name: name.clone(),
                stances: affordances(&stances)?,
                field,
                instances,
            });
        }
        let mut part_types = Vec::new();
        for (name, grasps) in st.part_kinds.iter().zip(&st.part_types) {
            part_types.push(PartTypeKnowledge {
                name: name.clone(),
                grasps: affordances(grasps)?,
            });
        }
        let mut arms = Vec::new();
        for a in std::mem::take(&mut st.arms) {
            arms.push(ArmSkill {
                rdmp: a
                    .rdmp
                    .rdmp()
                    .ok_or_else(|| KbError::Decode("an RDMP's weights are cut short".into()))?,
                path: Arc::new(a.path),
                dt: a.dt,
            });
        }
        let (n_types, n_parts) = (st.location_kinds.len(), st.part_kinds.len());
        let mut skill_list = Vec::new();
        for k in &st.skills {
            let fits = k.rdmp.is_none_or(|i| i < arms.len())
                && k.location_type.is_none_or(|t| t < n_types)
                && k.part_type.is_none_or(|p| p < n_parts);
            if !fits {
                return Err(KbError::Decode(format!(
                    "skill of {} names an RDMP, location type or part type that is not there",
                    k.demo
                )));
            }
            skill_list.push(Skill {
                class: class(&k.class)?,
                rdmp: k.rdmp,
                location_type: k.location_type,
                part_type: k.part_type,
                demo: k.demo.clone(),
                shared: k.shared,
            });
        }
        let mut instances = Vec::new();
        for (c, n) in &st.instances {
            instances.push((class(c)?, *n));
        }
        check_state(&st)?;
        let v = |c: [f64; 3]| nalgebra::Vector3::new(c[0], c[1], c[2]);

        let robot = st.robot.model()?;
        let empty = Sweep::new(st.config.workspace.feature_spacing);
        let sweeps = vec![Slot::Ready(Box::new(empty)); types];
        Ok(Learner {
            robot,
            description: st.description,
            config: st.config,
            clearance_demo: st.clearance_demo,
            location_kinds: st.location_kinds,
            part_kinds: st.part_kinds,
            location_types,
            part_types,
            sweeps,
            grown: vec![Grown::default(); types],
            unbuilt: vec![false; types],
            margins: vec![None; types],
            pending: st
                .pending
                .into_iter()
                .map(|per| {
                    per.into_iter()
                        .map(|path| {
                            Arc::new(SweptPath::new(
                                &path
                                    .into_iter()
                                    .map(|(c, sphere)| PathSphere {
                                        centre: v(c),
                                        sphere,
                                    })
                                    .collect::<Vec<_>>(),
                            ))
                        })
                        .collect()
                })
                .collect(),
            arms,
            skills: skill_list,
            instances,
            demonstrations: st.demonstrations,
            ids: st.ids,
        })
    }

    /// Refuses a learner whose next field build of location type `t` would allocate a grid
    /// over [`MAX_GRID_NODES`]: its feature balls and its queued spheres (a sweep still in the
    /// file is checked when read).
    fn check_grid(&self, t: usize) -> Result<(), crate::kb::KbError> {
        let (Some(sweep), Some(queued)) = (self.sweeps[t].ready(), self.pending.get(t)) else {
            return Ok(());
        };
        let more = queued
            .iter()
            .flat_map(|p| p.spheres())
            .map(|p| (p.centre, self.robot.spheres[p.sphere as usize].radius));
        let nodes = sweep.grid_nodes(more, &self.config.workspace);
        if nodes > MAX_GRID_NODES {
            return Err(crate::kb::KbError::Decode(format!(
                "a workspace grid of {nodes} nodes (at most {MAX_GRID_NODES})"
            )));
        }
        Ok(())
    }

    /// What was learned so far (Alg. 3's output, line 20's share() included): the fields of
    /// the location types touched since the last call are rebuilt (in parallel; `progress`
    /// is told of each), the others kept. A touched type's sweep still in the file is read
    /// first, and may be refused ([`Learner::open`]).
    pub fn knowledge(&mut self, progress: OnProgress<'_>) -> Result<Knowledge, crate::kb::KbError> {
        self.rebuild(progress)?;
        Ok(self.assemble())
    }

    /// The first part of [`Learner::knowledge`]: the queued spheres added to their sweeps
    /// ([`Learner::grow_sweeps`]), then the fields of the types whose sweeps grew rebuilt, one
    /// type per thread.
    fn rebuild(&mut self, progress: OnProgress<'_>) -> Result<(), crate::kb::KbError> {
        self.grow_sweeps()?;
        // A type marked without growing ([`Learner::recertify`]) may still be in the file.
        for t in 0..self.sweeps.len() {
            if self.unbuilt[t] {
                self.read_sweep(t)?;
            }
        }
        let wcs: Vec<WorkspaceConfig> = (0..self.sweeps.len())
            .map(|t| self.workspace_config(t))
            .collect();
        let rebuilt: Vec<(usize, Option<LearnedField>)> = self
            .sweeps
            .par_iter_mut()
            .zip(self.unbuilt.par_iter())
            .enumerate()
            .filter(|(_, (_, unbuilt))| **unbuilt)
            .filter_map(|(t, (slot, _))| Some((t, slot.ready_mut()?)))
            .map(|(t, sweep)| {
                let f = workspace::build_field(sweep, &wcs[t]);
                progress(Progress::Done(1));
                (t, f)
            })
            .collect();
        for (t, f) in rebuilt {
            self.location_types[t].field = f;
            self.unbuilt[t] = false;
        }
        Ok(())
    }

    /// The queued spheres of each location type added to its sweep (one type per thread; a
    /// sweep still in the file is read first), the paths and their new spheres recorded for
    /// [`Learner::addition`], the queues emptied and the types marked for a field build.
    fn grow_sweeps(&mut self) -> Result<(), crate::kb::KbError> {
        for t in 0..self.sweeps.len() {
            if !self.pending[t].is_empty() {
                self.read_sweep(t)?;
            }
        }
        let robot = &self.robot;
        let wcs: Vec<WorkspaceConfig> = (0..self.sweeps.len())
            .map(|t| self.workspace_config(t))
            .collect();
        let grown: Vec<(usize, Grown)> = self
            .sweeps
            .par_iter_mut()
            .zip(self.pending.par_iter_mut())
            .zip(self.location_types.par_iter())
            .enumerate()
            .filter(|(_, ((_, pending), _))| !pending.is_empty())
            .filter_map(|(t, ((slot, pending), known))| {
                Some((t, slot.ready_mut()?, pending, known))
            })
            .map(|(t, sweep, pending, known)| {
                // The decisions of the last build recovered before its sweep grows.
                let paths: Vec<&SweptPath> = pending.iter().map(|p| p.as_ref()).collect();
                let fresh = sweep.grow(robot, &paths, known.field.as_ref(), &wcs[t]);
                let grown = Grown::new(pending, fresh);
                pending.clear();
                (t, grown)
            })
            .collect();
        for (t, grown) in grown {
            self.grown[t] = grown;
            self.unbuilt[t] = true;
        }
        Ok(())
    }

    /// Learns `demos` (Alg. 3 lines 5–16, in parallel; `progress` told of each) and adds
    /// them in order, their spheres moved into the sweeps at once: [`learn_into`] but for
    /// the fields, which the next [`Learner::knowledge`] builds. Nothing of `demos` is kept,
    /// so learning a dataset a chunk at a time ([`learn_dir`]) holds one chunk's programs
    /// and lessons, not the dataset's. On an error the learner is left part-way: drop it.
    fn absorb(
        &mut self,
        demos: &[Demonstration],
        progress: OnProgress<'_>,
    ) -> Result<(), LearnError> {
        let lessons = demos
            .par_iter()
            .map(|d| {
                let l = self.lessons(d);
                progress(Progress::Done(1));
                l
            })
            .collect::<Vec<_>>()
            .into_iter()
            .collect::<Result<Vec<Lessons>, LearnError>>()?;
        for l in &lessons {
            self.add(l);
        }
        Ok(self.grow_sweeps()?)
    }

    /// The rest of [`Learner::knowledge`]: the knowledge as it stands, K after share().
    fn assemble(&self) -> Knowledge {
        let mut skill_set = self.skills.clone();
        // Line 20: K ← share(K).
        skills::share(&mut skill_set);
        Knowledge {
            robot: self.robot.clone(),
            description: self.description.clone(),
            config: self.config,
            clearance_demo: self.clearance_demo,
            location_types: self.location_types.clone(),
            part_types: self.part_types.clone(),
            arms: self.arms.clone(),
            skills: skill_set,
            instances: self.instances.clone(),
            demonstrations: self.demonstrations,
            timings: Vec::new(),
        }
    }
}

/// The most nodes a loaded knowledge base's workspace grid may have (about 200 MB of splat;
/// the example cell's have about 0.2 M).
const MAX_GRID_NODES: usize = 16 << 20;

/// The numbers of a knowledge base that size what learning allocates or index what it
/// reads: settings in range (lengths within [0, 1] m, the voxel within [1 mm, 1 m]), queued
/// spheres finite within 100 m, the robot's radii in (0, 1] m, sphere indices of the robot
/// (the sweeps: [`check_sweep`]).
fn check_state(st: &crate::kb::LearnerState) -> Result<(), crate::kb::KbError> {
    let bad = |what: &str| Err(crate::kb::KbError::Decode(format!("{what} out of range")));
    let w = &st.config.workspace;
    let non_negative = |x: f64| (0.0..=1.0).contains(&x);
    let positive = |x: f64| x.is_finite() && x > 0.0;
    let settings = (1e-3..=1.0).contains(&w.voxel)
        && positive(w.feature_spacing)
        && positive(w.resample)
        && [w.epsilon, w.reach, w.far, w.certify_margin]
            .into_iter()
            .all(non_negative);
    if !settings {
        return bad("a workspace setting");
    }
    let point = within_100_m;
    if !st.robot.radii().all(|r| r > 0.0 && r <= 1.0) {
        return bad("a robot sphere's radius");
    }
    let spheres = st.robot.spheres();
    let swept = |(c, i): &([f64; 3], u8)| point(c) && (*i as usize) < spheres;
    if !st.pending.iter().flatten().flatten().all(swept) {
        return bad("a queued sphere");
    }
    Ok(())
}

/// Why a location type's sweep in a knowledge base is refused, if it is: a swept sphere or
/// feature ball not finite within 100 m or with a radius outside (0, 1] m, a piece of path
/// not within 100 m or one a sphere names that is not there, or a feature spacing other
/// than the settings'.
fn check_sweep(s: &crate::kb::SweepState<'_>, w: &WorkspaceConfig) -> Result<(), String> {
    let ball = |(c, r): &([f64; 3], f64)| within_100_m(c) && *r > 0.0 && *r <= 1.0;
    let sample = |x: &workspace::SphereSample| ball(&(x.centre.into(), x.radius));
    // The example cell's Table holds 338 k spheres: checked on every core.
    if !s.spheres.all(sample) || !s.features.iter().all(ball) {
        return Err("holds a swept sphere out of range".into());
    }
    let capsules = s.capsules.len() as u32;
    let piece = |k: &crate::capsule::Capsule| {
        within_100_m(&k.a.into()) && within_100_m(&k.b.into()) && (0.0..=1.0).contains(&k.loss)
    };
    if !s.spheres.all(|x| x.capsule < capsules) || !s.capsules.all(piece) {
        return Err("holds a piece of path out of range".into());
    }
    if s.feature_spacing != w.feature_spacing {
        return Err(format!(
            "has feature spacing {} m, the settings' is {} m",
            s.feature_spacing, w.feature_spacing
        ));
    }
    Ok(())
}

/// Whether a swept sphere's centre in a knowledge base is finite and within 100 m.
fn within_100_m(c: &[f64; 3]) -> bool {
    // NaN and ±∞ fail the comparison; `&`, not `&&`: three comparisons, no branches.
    (c[0].abs() <= 100.0) & (c[1].abs() <= 100.0) & (c[2].abs() <= 100.0)
}

/// CRC-32 of a demonstration's program: its task (the part, the two locations — id, type
/// and pose each — and the goal) and its trajectory (every sample's bits). The same program
/// has the same fingerprint whatever its id or note; the same trajectory for another part
/// or location is another program (it teaches that part's grasps, that location's stances).
pub fn fingerprint(d: &Demonstration) -> u32 {
    // The blob's CRC-32 by carry-less multiplication ([`crate::kb`]): the task's strings
    // after their lengths (u32 LE), then every f64 in little-endian, the samples one at a time.
    let mut digest = crc32fast::Hasher::new();
    let task = &d.task;
    for placed in [&task.part, &task.from, &task.to] {
        for text in [&placed.id, &placed.kind] {
            digest.update(&(text.len() as u32).to_le_bytes());
            digest.update(text.as_bytes());
        }
        placed
            .pose
            .iter()
            .for_each(|v| digest.update(&v.to_le_bytes()));
    }
    task.goal
        .iter()
        .for_each(|v| digest.update(&v.to_le_bytes()));
    let mut bytes = [0u8; 8 * (2 + 3 + NA)];
    for s in &d.samples {
        let values = [s.t, s.gripper].into_iter().chain(s.base).chain(s.arm);
        for (b, v) in bytes.chunks_exact_mut(8).zip(values) {
            b.copy_from_slice(&v.to_le_bytes());
        }
        digest.update(&bytes);
    }
    digest.finalize()
}

/// Skills per class, in [`CLASSES`] order.
pub fn skills_per_class(k: &Knowledge) -> Vec<(&'static str, usize, usize)> {
    CLASSES
        .iter()
        .map(|c: &&dyn MotionClass| {
            let of = k.skills.iter().filter(|s| s.class == c.name());
            (
                c.name(),
                of.clone().count(),
                of.filter(|s| s.shared).count(),
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{Failed, LearnError, Lessons, joined};

    fn failed(i: usize, what: &'static str) -> Failed {
        let demonstration = "d000".to_string();
        (
            i,
            LearnError::BadPose {
                demonstration,
                what,
            },
        )
    }

    fn what(r: Result<Lessons, LearnError>) -> &'static str {
        match r {
            Err(LearnError::BadPose { what, .. }) => what,
            other => panic!("{other:?}"),
        }
    }

    /// A demonstration's first failure is the one learning its instances one by one meets:
    /// the earlier instance's, and on one instance its shape's before its arm's.
    #[test]
    fn the_first_failure_by_instance_is_reported() {
        let ok = || {
            Ok(Lessons {
                demonstration: "d000".into(),
                fingerprint: 0,
                lessons: Vec::new(),
            })
        };
        assert_eq!(what(joined(Err(failed(1, "shape")), Ok(vec![]))), "shape");
        assert_eq!(what(joined(ok(), Err(failed(1, "arm")))), "arm");
        assert_eq!(
            what(joined(Err(failed(2, "shape")), Err(failed(1, "arm")))),
            "arm"
        );
        assert_eq!(
            what(joined(Err(failed(1, "shape")), Err(failed(1, "arm")))),
            "shape"
        );
        assert_eq!(
            what(joined(Err(failed(0, "shape")), Err(failed(3, "arm")))),
            "shape"
        );
        assert!(joined(ok(), Ok(vec![])).is_ok());
    }
}
