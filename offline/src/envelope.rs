//! The part-pose envelope of a task (issue 22, item 3): which offsets of the part's nominal pose
//! at a location type (x, y in the location frame, yaw about the vertical) still plan at risk
//! 0 with a blob. It answers the cell engineer's first question: how precisely must a part be
//! placed for the learned programs to apply.

use crate::ground_truth::{TrueClearance, true_clearance};
use prf_runtime::plan::plan;
use prf_runtime::skill_plan::{PlanBudget, Search, SkillPlan};
use prf_runtime::{Runtime, RuntimeConfig};
use prf_sim::tasks::{FloorTask, FloorTaskError};
use prf_sim::world::World;
use rayon::prelude::*;

/// What planning at one offset gave.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome {
    /// A risk-0 plan: reuse is safe here.
    Safe,
    /// J* > 0 is proven: the best plan found has risk `j` (m; ∞ when the budget ran out
    /// before one was found) and J* is at least `lower` (m; `j` when the optimum is known).
    Risky { j: f64, lower: f64 },
    /// The budget ran out before J* > 0 or J* = 0 was proven: J* is at least this (m).
    Unknown(f64),
    /// No plan at all (nothing integrates, or the task is refused).
    NoPlan,
}

impl Outcome {
    /// What a skill plan says of its offset.
    pub fn of(s: &SkillPlan) -> Self {
        if s.feasible {
            Outcome::Safe
        } else if !s.decided {
            Outcome::Unknown(s.lower)
        } else if s.lower == f64::INFINITY {
            Outcome::NoPlan
        } else {
            Outcome::Risky {
                j: s.j,
                lower: s.lower,
            }
        }
    }
}

/// One offset of the grid and its outcome.
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    /// Offset along the location frame's x and y, m, and about its vertical, rad.
    pub dx: f64,
    pub dy: f64,
    pub dyaw: f64,
    pub outcome: Outcome,
    /// RDMP integrations and steps the plan took.
    pub integrations: u32,
    pub steps: u64,
    /// A safe offset's program against the true cell, when [`Options::check`] asked for it
    /// (or why it could not be executed).
    pub truth: Option<Result<TrueClearance, String>>,
}

/// How [`map`] plans each offset.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// The work each plan may do.
    pub budget: PlanBudget,
    /// How each plan searches.
    pub search: Search,
    /// Execute each safe offset's program and measure it against the true cell.
    pub check: bool,
}

/// The grid to map: offsets −range…range in `step` along x and y, and the given yaws.
#[derive(Clone, Debug)]
pub struct Grid {
    pub range: f64,
    pub step: f64,
    pub yaws: Vec<f64>,
}

impl Grid {
    /// Offsets along one axis, from −range to range.
    pub fn offsets(&self) -> Vec<f64> {
        let n = (self.range / self.step).round() as i64;
        (-n..=n).map(|i| i as f64 * self.step).collect()
    }
}

/// The world with the nominal part pose of location type `kind` moved by (dx, dy) in its
/// frame and turned by `dyaw` (every location of that type).
pub fn shifted(world: &World, kind: &str, dx: f64, dy: f64, dyaw: f64) -> World {
    let mut w = world.clone();
    for t in w.location_types.iter_mut().filter(|t| t.name == kind) {
        t.part_pose.xyz[0] += dx;
        t.part_pose.xyz[1] += dy;
        t.part_pose.rpy_deg[2] += dyaw.to_degrees();
    }
    w
}

/// Plans task (`part`, `from`, `to`) at every offset of `grid` of the part pose at location
/// type `kind` as `options` say, in parallel; `done` is called once per offset.
pub fn map(
    blob: &[u8],
    world: &World,
    kind: &str,
    task: (&str, &str, &str),
    grid: &Grid,
    options: Options,
    done: &(dyn Fn() + Sync),
) -> Result<Vec<Cell>, FloorTaskError> {
    // Names are checked once, up front.
    FloorTask::new(world, task.0, task.1, task.2)?;
    let axis = grid.offsets();
    let offsets: Vec<(f64, f64, f64)> = grid
        .yaws
        .iter()
        .flat_map(|&yaw| {
            let axis = &axis;
            axis.iter()
                .flat_map(move |&y| axis.iter().map(move |&x| (x, y, yaw)))
        })
        .collect();
    let config = RuntimeConfig {
        plan_budget: options.budget,
        search: options.search,
        ..RuntimeConfig::default()
    };
    Ok(offsets
        .par_iter()
        .map(|&(dx, dy, dyaw)| {
            let w = shifted(world, kind, dx, dy, dyaw);
            let cell = |outcome, integrations, steps| Cell {
                dx,
                dy,
                dyaw,
                outcome,
                integrations,
                steps,
                truth: None,
            };
            let out = match (
                Runtime::load_with(blob, config),
                FloorTask::new(&w, task.0, task.1, task.2),
            ) {
                (Ok(rt), Ok(ft)) => match plan(&rt, &ft.task()) {
                    Ok(p) => {
                        let s = &p.skills;
                        let mut c = cell(Outcome::of(s), s.stats.integrations, s.stats.steps);
                        if options.check && c.outcome == Outcome::Safe {
                            c.truth = Some(
                                true_clearance(&w, &rt, &ft, &p).map_err(|e| format!("{e:#}")),
                            );
                        }
                        c
                    }
                    Err(_) => cell(Outcome::NoPlan, 0, 0),
                },
                _ => cell(Outcome::NoPlan, 0, 0),
            };
            done();
            out
        })
        .collect())
}

/// The largest r such that every offset with |dx|, |dy| ≤ r at yaw `dyaw` is safe (None when
/// the nominal pose itself is not).
pub fn safe_square(cells: &[Cell], dyaw: f64) -> Option<f64> {
    let slice: Vec<&Cell> = cells.iter().filter(|c| c.dyaw == dyaw).collect();
    let mut radii: Vec<f64> = slice.iter().map(|c| c.dx.abs().max(c.dy.abs())).collect();
    radii.sort_by(f64::total_cmp);
    radii.dedup();
    let mut best = None;
    for r in radii {
        let all = slice
            .iter()
            .filter(|c| c.dx.abs().max(c.dy.abs()) <= r + 1e-12)
            .all(|c| c.outcome == Outcome::Safe);
        if !all {
            break;
        }
        best = Some(r);
    }
    best
}
