//! Learn (Alg. 3): the pass over the dataset that drives every motion class of
//! [`prf_shared::motion::CLASSES`] and collects affordances, workspaces and skills.

use crate::affordance::AffordanceSet;
use crate::skills::{self, ArmSkill, Skill};
use crate::workspace::{self, LearnedField, Sweep, WorkspaceConfig};
use prf_files::dataset::{Dataset, Demonstration, Placed};
use prf_files::{OnProgress, Progress};
use prf_shared::JointVector;
use prf_shared::dmp::DmpParams;
use prf_shared::kinematics::{ArmKinematics, arm_base_pose, platform_pose};
use prf_shared::motion::{CLASSES, Frame, Instance, MotionClass, TaskLocation};
use prf_shared::robot::RobotModel;
use prf_shared::se3::{Pose, pose_from_array};
use rayon::prelude::*;
use std::time::Instant;

/// Settings of Learn.
#[derive(Clone, Copy, Debug, PartialEq)]
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

/// One instance of a class in one demonstration, with what it teaches.
struct Lesson {
    class: &'static str,
    location_type: Option<usize>,
    part_type: usize,
    affordance: Option<(Frame, Pose)>,
    /// Arm configurations of the instance and the arm base in the location frame.
    sweep: Option<(Vec<[f64; 7]>, Pose)>,
    arm: Option<(Vec<[f64; 7]>, f64, prf_shared::rdmp::Rdmp)>,
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

/// Alg. 3, lines 5–16 for one demonstration.
fn lessons(
    model: &RobotModel,
    ds: &Dataset,
    d: &Demonstration,
    cfg: &LearnConfig,
) -> Result<Vec<Lesson>, LearnError> {
    let kinds: Vec<String> = location_kinds(ds);
    let part_kinds = part_kinds(ds);
    let part_type = part_kinds
        .iter()
        .position(|k| *k == d.task.part.kind)
        .ok_or_else(|| LearnError::PartType {
            demonstration: d.id.clone(),
            kind: d.task.part.kind.clone(),
        })?;
    let mut out = Vec::new();
    for m in CLASSES.iter() {
        let mut instances = Vec::new();
        m.segment(&d.samples, &mut |i| instances.push(i));
        for inst in instances {
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
            let sweep = if m.learns_workspace() {
                match (inst.location, fr.workspace) {
                    (Some(l), Frame::Location) => {
                        let loc = pose_from_array(location_of(d, l).pose).ok_or_else(|| {
                            LearnError::BadPose {
                                demonstration: d.id.clone(),
                                what: "location",
                            }
                        })?;
                        let s = &d.samples[inst.at];
                        let path = d.samples[inst.range.clone()]
                            .iter()
                            .map(|s| s.arm)
                            .collect();
                        Some((path, loc.inverse() * arm_base_pose(model, s.base)))
                    }
                    _ => None,
                }
            } else {
                None
            };
            let arm = match (&inst.arm, m.generators().iter().any(|g| g.learnable())) {
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
            };
            out.push(Lesson {
                class: m.name(),
                location_type,
                part_type,
                affordance,
                sweep,
                arm,
            });
        }
    }
    Ok(out)
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

/// Learn (Alg. 3) on a dataset read for `model`.
pub fn learn(
    ds: &Dataset,
    model: &RobotModel,
    cfg: &LearnConfig,
    progress: OnProgress<'_>,
) -> Result<Knowledge, LearnError> {
    let clearance_demo = resolve_clearance_demo(ds.clearance_demo, cfg.clearance_demo)?;
    let mut wc = cfg.workspace;
    wc.epsilon = clearance_demo - cfg.clearance_acceptable;
    if !(wc.epsilon >= 0.0) {
        return Err(LearnError::Clearance {
            acceptable: cfg.clearance_acceptable,
            demo: clearance_demo,
        });
    }
    progress(Progress::Total(
        (ds.demonstrations.len() + location_kinds(ds).len()) as u64,
    ));
    let t0 = Instant::now();
    // Lines 4–16, in parallel over demonstrations; merged in dataset order (deterministic).
    let per_demo: Vec<Vec<Lesson>> = ds
        .demonstrations
        .par_iter()
        .map(|d| {
            let l = lessons(model, ds, d, cfg);
            progress(Progress::Done(1));
            l
        })
        .collect::<Result<_, LearnError>>()?;
    let t_segment = t0.elapsed().as_secs_f64();
    let kinds = location_kinds(ds);
    let mut location_types: Vec<LocationTypeKnowledge> = kinds
        .iter()
        .map(|k| LocationTypeKnowledge {
            name: k.clone(),
            stances: AffordanceSet::default(),
            field: None,
            instances: 0,
        })
        .collect();
    let mut part_types: Vec<PartTypeKnowledge> = part_kinds(ds)
        .into_iter()
        .map(|name| PartTypeKnowledge {
            name,
            grasps: AffordanceSet::default(),
        })
        .collect();
    let mut paths: Vec<Vec<(Vec<[f64; 7]>, Pose)>> = vec![Vec::new(); kinds.len()];
    let mut arms: Vec<ArmSkill> = Vec::new();
    let mut skill_set: Vec<Skill> = Vec::new();
    let mut instances: Vec<(&'static str, usize)> = CLASSES.iter().map(|c| (c.name(), 0)).collect();
    for (d, lessons) in ds.demonstrations.iter().zip(per_demo) {
        for l in lessons {
            if let Some(c) = instances.iter_mut().find(|c| c.0 == l.class) {
                c.1 += 1;
            }
            // Line 9: A_{f_r}^{f_a}.
            match (l.affordance, l.location_type) {
                (Some((Frame::Part, p)), _) => {
                    part_types[l.part_type].grasps.insert(p);
                }
                (Some((Frame::Location, p)), Some(t)) => {
                    location_types[t].stances.insert(p);
                }
                _ => {}
            }
            // Line 11: Ω+ of the workspace frame.
            if let (Some(s), Some(t)) = (l.sweep, l.location_type) {
                location_types[t].instances += 1;
                paths[t].push(s);
            }
            // Lines 13–16: the skill (a set: equal arm motions are stored once).
            let rdmp = l.arm.map(|(path, dt, rdmp)| {
                skills::find_same(&arms, &path, dt).unwrap_or_else(|| {
                    arms.push(ArmSkill { rdmp, path, dt });
                    arms.len() - 1
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
                    d.id.clone()
                } else {
                    String::new()
                },
                shared: false,
            };
            if !skill_set
                .iter()
                .any(|k| k.class == skill.class && k.rdmp == skill.rdmp)
            {
                skill_set.push(skill);
            }
        }
    }
    // Line 20: K ← share(K).
    skills::share(&mut skill_set);
    let t1 = Instant::now();
    let fields: Vec<Option<LearnedField>> = paths
        .par_iter()
        .map(|ps| {
            let mut sweep = Sweep::default();
            for (path, base) in ps {
                sweep.add_path(model, base, path, wc.resample);
            }
            let f = workspace::build_field(&sweep, &wc);
            progress(Progress::Done(1));
            f
        })
        .collect();
    for (t, f) in location_types.iter_mut().zip(fields) {
        t.field = f;
    }
    let t_workspace = t1.elapsed().as_secs_f64();
    let mut config = *cfg;
    config.workspace = wc;
    Ok(Knowledge {
        robot: model.clone(),
        description: ds.description.clone().unwrap_or_default(),
        config,
        clearance_demo,
        location_types,
        part_types,
        arms,
        skills: skill_set,
        instances,
        demonstrations: ds.demonstrations.len(),
        timings: vec![
            ("segment + train skills", t_segment),
            ("workspaces", t_workspace),
        ],
    })
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
