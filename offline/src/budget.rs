//! A blob within a flash budget (`prf learn --max-blob-bytes`, issue 66): the most certified
//! workspaces and the fewest skills that keep the world's afforded tasks as feasible as the
//! unbudgeted blob makes them.
//!
//! Two things are given up, each only shrinking what rates risk 0 (never a new way to say
//! risk 0):
//! - **skills no side needs**: per side of every afforded task (a location instance, stance,
//!   grasp and part), the first candidate in the planner's order at risk ≤ the threshold is
//!   its witness; only the witnesses' RDMPs and their skills are kept. Each feasible side
//!   keeps its witness (a candidate's stream depends only on its RDMP, goal and arm base),
//!   and no side gains one, so the same afforded tasks stay physically feasible (checked
//!   again on the blob written);
//! - **certification margin, workspace by workspace** ([`Learner::recertify_type`]): when
//!   the skills alone do not fit, a workspace is rebuilt one rung down a ladder of margins
//!   ([`MARGINS`]), and another, until the blob fits (with every skill if they fit, else with
//!   the witnesses'): of those with the largest margin, the largest workspace first. So the
//!   margins come down together, the blob stops shrinking as soon as it fits, and the
//!   small workspaces, lowered last, keep a rung more where the budget allows it. A smaller margin stores fewer
//!   certificates: part poses farther from the demonstrated ones rate a risk sooner. The
//!   afforded tasks each rung still makes feasible are counted anew (with every skill, then
//!   its witnesses kept), and the report names the tasks lost.

use crate::experiment::monte_carlo::{Counts, Witnessed, witnessed};
use anyhow::{Result, anyhow, bail};
use prf_files::progress::{OnProgress, Progress};
use prf_learn::learn::Learner;
use prf_learn::{Knowledge, compile};
use prf_sim::tasks::world_tasks;
use prf_sim::world::World;

/// The certification margins tried below the learned one, m, largest first.
pub const MARGINS: [f64; 6] = [0.012, 0.008, 0.005, 0.003, 0.002, 0.001];

/// One rung of the ladder: the workspaces' margins and what the blob came to.
#[derive(Clone, Debug)]
pub struct Rung {
    /// Per location type (blob order): its name and the certification margin of its field, m.
    pub margins: Vec<(String, f64)>,
    /// Bytes of the blob with every skill.
    pub all_skills: usize,
    /// Bytes of the blob with the witnesses' skills only.
    pub witnesses: usize,
    /// The afforded tasks this rung makes physically feasible.
    pub counts: Counts,
}

impl Rung {
    /// The margins as "CNC 12, Printer 17 mm".
    pub fn margins_mm(&self) -> String {
        let each: Vec<String> = self
            .margins
            .iter()
            .map(|(name, m)| format!("{name} {:.0}", m * 1e3))
            .collect();
        format!("{} mm", each.join(", "))
    }
}

/// A blob within the budget and what it gave up.
pub struct Fitted {
    /// The blob written.
    pub blob: Vec<u8>,
    /// The knowledge it was compiled from.
    pub knowledge: Knowledge,
    /// Bytes of the unbudgeted blob.
    pub unbudgeted: usize,
    /// What the unbudgeted blob makes feasible.
    pub reference: Counts,
    /// The rungs tried, the last one's blob written.
    pub rungs: Vec<Rung>,
    /// Tasks physically feasible on the unbudgeted blob but not on this one (labels).
    pub lost: Vec<String>,
}

/// The blob of `knowledge` (learned by `learner`) within `budget` bytes, for the tasks of
/// `world`: unchanged when it fits, else skills and certificates given up as the module
/// says. `rung` is told of each rung tried, `progress` of each field rebuilt. An error when
/// even the smallest margins with the witnesses' skills alone do not fit, naming the
/// smallest size reached.
pub fn fit(
    learner: &mut Learner,
    knowledge: Knowledge,
    world: &World,
    budget: usize,
    progress: OnProgress<'_>,
    rung: &dyn Fn(&Rung),
) -> Result<Fitted> {
    let blob = compile(&knowledge)?;
    let unbudgeted = blob.len();
    if unbudgeted <= budget {
        return Ok(Fitted {
            blob,
            knowledge,
            unbudgeted,
            reference: Counts::default(),
            rungs: Vec::new(),
            lost: Vec::new(),
        });
    }
    same_types(world, &knowledge)?;
    let reference = witnessed(world, &knowledge, &blob)?;
    // Per location type its ladder: the learned margin, then the smaller ones of MARGINS.
    let ladders: Vec<Vec<f64>> = (0..knowledge.location_types.len())
        .map(|t| {
            let m = learner.margin(t);
            std::iter::once(m)
                .chain(MARGINS.into_iter().filter(|&x| x < m))
                .collect()
        })
        .collect();
    progress(Progress::Total(
        ladders.iter().map(|l| l.len() as u64 - 1).sum(),
    ));
    let mut level = vec![0; ladders.len()];
    let mut rungs = Vec::new();
    let mut all = (knowledge, blob, reference.clone());
    loop {
        let (k, blob, w) = &all;
        let kept = k.keeping_rdmps(&w.rdmps);
        let small = compile(&kept)?;
        let r = Rung {
            margins: k
                .location_types
                .iter()
                .zip(ladders.iter().zip(&level))
                .map(|(t, (ladder, &l))| (t.name.clone(), ladder[l]))
                .collect(),
            all_skills: blob.len(),
            witnesses: small.len(),
            counts: w.counts,
        };
        rung(&r);
        rungs.push(r);
        if blob.len() <= budget {
            let (k, blob, w) = all;
            return settle(world, &reference, k, blob, &w, unbudgeted, rungs);
        }
        if small.len() <= budget {
            return settle(world, &reference, kept, small, w, unbudgeted, rungs);
        }
        // Of the workspaces that can still go a rung lower, one with the largest margin, and
        // of those the largest: the margins come down together, the small workspaces last.
        let field_bytes = |t: usize| k.location_types[t].field.as_ref().map_or(0, |f| f.bytes());
        let Some(t) = (0..ladders.len())
            .filter(|&t| level[t] + 1 < ladders[t].len() && field_bytes(t) > 0)
            .max_by(|&a, &b| {
                let margin = |t: usize| ladders[t][level[t]];
                margin(a)
                    .total_cmp(&margin(b))
                    .then(field_bytes(a).cmp(&field_bytes(b)))
                    .then(b.cmp(&a))
            })
        else {
            break;
        };
        level[t] += 1;
        learner.recertify_type(t, ladders[t][level[t]]);
        let k = learner.knowledge(progress)?;
        let blob = compile(&k)?;
        let w = witnessed(world, &k, &blob)?;
        all = (k, blob, w);
    }
    let smallest = rungs
        .iter()
        .map(|r| r.witnesses)
        .min()
        .unwrap_or(unbudgeted);
    Err(anyhow!(
        "the knowledge does not fit {budget} bytes: with every workspace certified at {:.0} mm and only the skills the world's afforded tasks need, the blob is {smallest} bytes",
        MARGINS[MARGINS.len() - 1] * 1e3,
    ))
}

/// The fitted `blob` of `knowledge`, checked to make what its rung counted (`w`) feasible,
/// with the tasks lost against `reference`.
fn settle(
    world: &World,
    reference: &Witnessed,
    knowledge: Knowledge,
    blob: Vec<u8>,
    w: &Witnessed,
    unbudgeted: usize,
    rungs: Vec<Rung>,
) -> Result<Fitted> {
    let check = witnessed(world, &knowledge, &blob)?;
    if check.counts != w.counts {
        bail!(
            "the budgeted blob makes {:?} feasible where its rung counted {:?}",
            check.counts,
            w.counts
        );
    }
    let lost = world_tasks(world)
        .iter()
        .zip(reference.feasible.iter().zip(&check.feasible))
        .filter(|(_, (was, is))| **was && !**is)
        .map(|(t, _)| t.label())
        .collect();
    Ok(Fitted {
        blob,
        knowledge,
        unbudgeted,
        reference: reference.counts,
        rungs,
        lost,
    })
}

/// Every location and part type the knowledge has is the world's: the budget keeps the skills
/// the world's tasks need, so the world of another cell would keep the wrong ones.
fn same_types(world: &World, k: &Knowledge) -> Result<()> {
    let has_location = |n: &str| world.locations.iter().any(|l| l.kind == n);
    let has_part = |n: &str| world.parts.iter().any(|p| p.kind == n);
    let foreign = k
        .location_types
        .iter()
        .map(|t| ("location type", &t.name, has_location(&t.name)))
        .chain(
            k.part_types
                .iter()
                .map(|t| ("part type", &t.name, has_part(&t.name))),
        )
        .find(|(_, _, known)| !known);
    match foreign {
        Some((what, name, _)) => bail!(
            "the dataset taught a {what} {name} the world does not have: budget with the --world the programs were recorded in"
        ),
        None => Ok(()),
    }
}
