//! The paper's Sec. 6.3 (Fig. 5): how many tasks become feasible as demonstrations are
//! learned one at a time, in random orders.
//!
//! An episode adds the dataset's demonstrations in a seeded random order to a [`Learner`]
//! (incremental Learn, Alg. 3). After each step it compiles the blob, loads the runtime and
//! counts, over the world's tasks (nominal part and location poses):
//! - **symbolically feasible afforded tasks**: (task, stance at ℓ1, stance at ℓ2, grasp) with
//!   every affordance learned, of a task the runtime accepts symbolically (Sec. 6.1) — the
//!   grid SkillPlan-PTT searches;
//! - **physically feasible afforded tasks**: those whose pick side (stance at ℓ1, grasp) and
//!   place side (stance at ℓ2, grasp) each have a candidate skill at risk ≤ the threshold;
//! - **physically feasible tasks**: tasks with at least one such afforded task (J* ≤ the
//!   threshold, what `plan` reports).
//!
//! A side's feasibility is an existence question, so it is decided without searching for the
//! minimum: a candidate is pruned as soon as its risk exceeds the threshold, and the side stops
//! at the first that stays within it (its witness). A candidate's stream depends only on its
//! RDMP, goal and arm base; only its rating depends on the field. So the answers are cached
//! exactly across the steps of an episode:
//! - a witness keeps its stream: after a field change it still holds if none of its spheres is
//!   in a cell whose lookup may have risen (`raised_cells`), else it is re-rated without
//!   integrating;
//! - a rejected candidate keeps one configuration that exceeded: re-checked first after a
//!   field change;
//! - failing, missing the goal or being too fast holds in every field.
//!
//! Across episodes the same is shared per exact (RDMP, goal, arm base) ([`Shared`]); the
//! learned stances and grasps are quantized ([`prf_learn::affordance::quantized`]), so a
//! candidate has the same bits whatever the order of the episode. Nothing
//! assumes the field grows monotonically (the encoded field does not, exactly); the
//! from-scratch count ([`Setup::from_scratch`]) decides everything anew.

use anyhow::{Context, Result, anyhow};
use prf_files::dataset::Dataset;
use prf_learn::learn::{Learner, Lessons};
use prf_learn::workspace::LearnedField;
use prf_learn::{LearnConfig, compile};
use prf_runtime::Runtime;
use prf_runtime::skill_plan::{PttClasses, PttSides, Side};
use prf_runtime::task_plan::plan_actions;
use prf_shared::robot::RobotModel;
use prf_sim::tasks::{FloorTask, world_tasks};
use prf_sim::world::World;
use rand::seq::SliceRandom;
use rand::{SeedableRng, rngs::StdRng};
use rayon::prelude::*;
use std::collections::{BTreeSet, HashMap, HashSet};
use std::time::Instant;

/// The three counts of a step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Counts {
    /// Symbolically feasible afforded tasks.
    pub symbolic_afforded: usize,
    /// Physically feasible afforded tasks.
    pub physical_afforded: usize,
    /// Physically feasible tasks.
    pub physical_tasks: usize,
}

/// One step of an episode.
#[derive(Clone, Debug)]
pub struct Step {
    /// The demonstration added at this step (index into the dataset).
    pub demonstration: usize,
    pub counts: Counts,
    /// RDMP integrations the counting ran.
    pub integrations: u64,
    /// Wall time of the incremental learn (+ compile) and of the counting, s.
    pub learn_s: f64,
    pub count_s: f64,
}

/// One episode: the order drawn and a step per demonstration.
#[derive(Clone, Debug)]
pub struct Episode {
    pub seed: u64,
    pub steps: Vec<Step>,
}

/// Which side of a PTT plan.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Role {
    Pick,
    Place,
}

/// A side of a task at one stance and grasp: the location instance (index in the world),
/// the part instance, the role and the blob's stance and grasp indices. Affordance and RDMP
/// indices only grow within an episode, so the key names the same goal at every step.
type SideKey = (usize, usize, Role, usize, usize);

mod field_change;
mod side;

use field_change::raised_cells;
pub use side::Shared;
use side::{At, SideState, side_feasible};

/// The exact cache of side decisions across the steps of an episode.
#[derive(Default)]
struct Cache {
    sides: HashMap<SideKey, SideState>,
    /// Per location type (blob index): its field at the last step, the version (bumped when
    /// the field changes) and, when only some cells changed, those whose lookup may have
    /// risen (None: every cell may have).
    types: Vec<TypeState>,
}

/// A location type's field at the last step, its version and the cells that may have risen
/// in its last change.
#[derive(Default)]
struct TypeState {
    field: Option<LearnedField>,
    version: u64,
    raised: Option<HashSet<u32>>,
}

impl Cache {
    /// Bumps the version of every location type whose field changed and notes which cells
    /// may now look up a larger distance.
    fn observe(&mut self, fields: &[Option<LearnedField>]) {
        self.types.resize_with(fields.len(), TypeState::default);
        for (state, f) in self.types.iter_mut().zip(fields) {
            if state.field.as_ref() == f.as_ref() {
                continue;
            }
            state.version += 1;
            state.raised = match (&state.field, f) {
                (Some(old), Some(new)) => raised_cells(old, new),
                _ => None,
            };
            state.field = f.clone();
        }
    }
}

/// The counts on a blob with the cache of the episode (a fresh cache decides everything
/// anew), and per task whether it is physically feasible.
fn count(
    rt: &Runtime<'_>,
    world: &World,
    tasks: &[FloorTask],
    cache: &mut Cache,
    shared: &Shared,
    integrations: &mut u64,
) -> Result<(Counts, Vec<bool>)> {
    let mut counts = Counts::default();
    let mut feasible = vec![false; tasks.len()];
    let Some(classes) = PttClasses::of(rt) else {
        return Ok((counts, feasible));
    };
    let actions_ok = matches!(plan_actions(rt), Ok(Some(a)) if classes.matches(&a));
    if !actions_ok {
        return Ok((counts, feasible));
    }
    for (i, ft) in tasks.iter().enumerate() {
        let task = ft.task();
        let Ok(Ok(resolved)) = task.resolve(rt) else {
            continue;
        };
        let Ok(sides) = PttSides::new(rt, &task, &resolved, &classes) else {
            continue;
        };
        let (n1, n2, ng) = (
            sides.pick.arm_bases.len(),
            sides.place.arm_bases.len(),
            sides.grasps,
        );
        counts.symbolic_afforded += n1 * n2 * ng;
        let from = world.location_index(&ft.from.0).unwrap_or(usize::MAX);
        let to = world.location_index(&ft.to.0).unwrap_or(usize::MAX);
        let part = world.part_index(&ft.part.0).unwrap_or(usize::MAX);
        let mut decide = |side: &Side<'_>, role, location, t: usize, s, g| -> Result<bool> {
            let state = cache.sides.entry((location, part, role, s, g)).or_default();
            let field = cache
                .types
                .get(t)
                .ok_or_else(|| anyhow!("location type {t} has no field"))?;
            side_feasible(&At { rt, side, s, g }, state, field, shared, integrations)
        };
        let mut any = false;
        for g in 0..ng {
            let mut pick = vec![false; n1];
            for (s, ok) in pick.iter_mut().enumerate() {
                *ok = decide(&sides.pick, Role::Pick, from, resolved.from_type, s, g)?;
            }
            if !pick.iter().any(|&p| p) {
                continue;
            }
            let mut place = vec![false; n2];
            for (s, ok) in place.iter_mut().enumerate() {
                *ok = decide(&sides.place, Role::Place, to, resolved.to_type, s, g)?;
            }
            let n = pick.iter().filter(|&&p| p).count() * place.iter().filter(|&&p| p).count();
            counts.physical_afforded += n;
            any |= n > 0;
        }
        counts.physical_tasks += any as usize;
        feasible[i] = any;
    }
    Ok((counts, feasible))
}

/// The learned fields per location type.
fn fields(k: &prf_learn::Knowledge) -> Vec<Option<LearnedField>> {
    k.location_types.iter().map(|t| t.field.clone()).collect()
}

/// What a blob makes physically feasible over a world's tasks, every side decided anew, with
/// the RDMPs that show it.
#[derive(Clone, Debug)]
pub struct Witnessed {
    pub counts: Counts,
    /// Per task of [`world_tasks`], physically feasible.
    pub feasible: Vec<bool>,
    /// The RDMP (blob index) of a witness of every side the count found feasible: with only
    /// these RDMPs' skills the same sides have the same witnesses (a candidate's stream
    /// depends on its RDMP, goal and arm base alone), and no side gains one.
    pub rdmps: BTreeSet<usize>,
}

/// [`Witnessed`] of `blob`, compiled from `knowledge` (whose fields it reads), over the tasks
/// of `world`.
pub fn witnessed(
    world: &World,
    knowledge: &prf_learn::Knowledge,
    blob: &[u8],
) -> Result<Witnessed> {
    let rt = Runtime::load(blob).map_err(|e| anyhow!("loading the blob: {e}"))?;
    let mut cache = Cache::default();
    cache.observe(&fields(knowledge));
    let (counts, feasible) = count(
        &rt,
        world,
        &world_tasks(world),
        &mut cache,
        &Shared::default(),
        &mut 0,
    )?;
    let rdmps = cache
        .sides
        .values()
        .filter_map(|s| s.witness_rdmp().map(usize::from))
        .collect();
    Ok(Witnessed {
        counts,
        feasible,
        rdmps,
    })
}

/// A from-scratch count ([`Setup::from_scratch`]).
pub struct Scratch {
    pub counts: Counts,
    /// Per task of [`Setup::tasks`], physically feasible.
    pub feasible: Vec<bool>,
    /// The blob batch learning made.
    pub blob: Vec<u8>,
    /// Wall time of learn + compile + count, s.
    pub seconds: f64,
}

/// The experiment's fixed inputs: the dataset, every demonstration's lessons (computed once
/// for all episodes), the world's tasks.
pub struct Setup {
    pub world: World,
    pub dataset: Dataset,
    pub model: RobotModel,
    pub config: LearnConfig,
    learner: Learner,
    lessons: Vec<Lessons>,
    tasks: Vec<FloorTask>,
    /// What the episodes learn about candidates, whatever the field.
    shared: Shared,
}

impl Setup {
    /// Reads what every episode shares; trains every demonstration's skills once.
    pub fn new(world: World, dataset: Dataset) -> Result<Self> {
        let model = RobotModel::kmr_iiwa14();
        let config = LearnConfig::default();
        let learner = Learner::new(&dataset, &model, &config)?;
        let lessons = dataset
            .demonstrations
            .par_iter()
            .map(|d| learner.lessons(d))
            .collect::<Result<Vec<_>, _>>()?;
        let tasks = world_tasks(&world);
        Ok(Setup {
            world,
            dataset,
            model,
            config,
            learner,
            lessons,
            tasks,
            shared: Shared::default(),
        })
    }

    /// Number of demonstrations.
    pub fn len(&self) -> usize {
        self.lessons.len()
    }

    /// Whether the dataset has no demonstrations.
    pub fn is_empty(&self) -> bool {
        self.lessons.is_empty()
    }

    /// The order of an episode drawn with `seed`.
    pub fn order(&self, seed: u64) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.len()).collect();
        order.shuffle(&mut StdRng::seed_from_u64(seed));
        order
    }

    /// Runs one episode over the first `steps` demonstrations of `order`, incrementally and
    /// with the exact cache.
    pub fn episode(&self, seed: u64, order: &[usize], steps: usize) -> Result<Episode> {
        let mut learner = self.learner.clone();
        let mut cache = Cache::default();
        let mut out = Vec::with_capacity(steps);
        for &d in order.iter().take(steps) {
            let t0 = Instant::now();
            learner.add(&self.lessons[d]);
            let knowledge = learner.knowledge(&|_| {})?;
            let blob = compile(&knowledge)
                .with_context(|| format!("compiling after {}", self.lessons[d].demonstration))?;
            let learn_s = t0.elapsed().as_secs_f64();
            let t1 = Instant::now();
            cache.observe(&fields(&knowledge));
            let rt = Runtime::load(&blob).map_err(|e| anyhow!("loading the blob: {e}"))?;
            let mut integrations = 0;
            let (counts, _) = count(
                &rt,
                &self.world,
                &self.tasks,
                &mut cache,
                &self.shared,
                &mut integrations,
            )?;
            out.push(Step {
                demonstration: d,
                counts,
                integrations,
                learn_s,
                count_s: t1.elapsed().as_secs_f64(),
            });
        }
        Ok(Episode { seed, steps: out })
    }

    /// The counts after learning `subset` (in that order) from scratch: batch [`learn`] of a
    /// dataset holding just those demonstrations, and every side decided anew.
    ///
    /// [`learn`]: prf_learn::learn()
    pub fn from_scratch(&self, subset: &[usize]) -> Result<Scratch> {
        let t0 = Instant::now();
        let ds = Dataset {
            demonstrations: subset
                .iter()
                .map(|&i| self.dataset.demonstrations[i].clone())
                .collect(),
            ..self.dataset.clone()
        };
        let knowledge = prf_learn::learn(&ds, &self.model, &self.config, &|_| {})?;
        let blob = compile(&knowledge)?;
        let rt = Runtime::load(&blob).map_err(|e| anyhow!("loading the blob: {e}"))?;
        let mut integrations = 0;
        let mut cache = Cache::default();
        cache.observe(&fields(&knowledge));
        // Nothing shared: every candidate is decided anew.
        let (counts, feasible) = count(
            &rt,
            &self.world,
            &self.tasks,
            &mut cache,
            &Shared::default(),
            &mut integrations,
        )?;
        Ok(Scratch {
            counts,
            feasible,
            blob,
            seconds: t0.elapsed().as_secs_f64(),
        })
    }

    /// The demonstrations of the two cases of Sec. 7.1 (None where the dataset lacks one):
    /// two similar programs (Part1 CNC → CNC, Part2 CNC → CNC) and two diverse ones (Part1
    /// CNC → Printer, Part2 Printer → Table).
    pub fn special_cases(&self) -> [(&'static str, Option<[usize; 2]>); 2] {
        let find = |part: &str, from: &str, to: &str| {
            self.dataset.demonstrations.iter().position(|d| {
                d.task.part.id == part && d.task.from.kind == from && d.task.to.kind == to
            })
        };
        let pair = |a: Option<usize>, b: Option<usize>| Some([a?, b?]);
        [
            (
                "similar: Part1 CNC → CNC, Part2 CNC → CNC",
                pair(find("Part1", "CNC", "CNC"), find("Part2", "CNC", "CNC")),
            ),
            (
                "diverse: Part1 CNC → Printer, Part2 Printer → Table",
                pair(
                    find("Part1", "CNC", "Printer"),
                    find("Part2", "Printer", "Table"),
                ),
            ),
        ]
    }

    /// The blob after learning `subset` incrementally (one [`Learner::add`] per
    /// demonstration, the knowledge taken after each).
    pub fn incremental_blob(&self, subset: &[usize]) -> Result<Vec<u8>> {
        let mut learner = self.learner.clone();
        let mut blob = Vec::new();
        for &d in subset {
            learner.add(&self.lessons[d]);
            blob = compile(&learner.knowledge(&|_| {})?)?;
        }
        Ok(blob)
    }

    /// The world's tasks.
    pub fn tasks(&self) -> &[FloorTask] {
        &self.tasks
    }
}

/// Runs `episodes` episodes (seeds `seed`, `seed + 1`, …) in parallel; `progress` is told of
/// every episode done.
pub fn run(
    setup: &Setup,
    episodes: usize,
    steps: usize,
    seed: u64,
    progress: prf_files::OnProgress<'_>,
) -> Result<Vec<Episode>> {
    progress(prf_files::Progress::Total(episodes as u64));
    (0..episodes as u64)
        .into_par_iter()
        .map(|e| {
            let s = seed.wrapping_add(e);
            let r = setup.episode(s, &setup.order(s), steps);
            progress(prf_files::Progress::Done(1));
            r
        })
        .collect()
}
