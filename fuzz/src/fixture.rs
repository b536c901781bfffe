//! What the harnesses plan and execute against: a real blob (`fuzz/data/smoke.blob`, learned
//! by `prf learn` from four programs of the example cell) and the example cell's 18 tasks.

use prf_runtime::skill_plan::PlanBudget;
use prf_runtime::{Runtime, RuntimeConfig, Task, plan};
use prf_sim::tasks::{FloorTask, world_tasks};
use prf_sim::world::World;
use std::sync::LazyLock;

/// The committed blob (regenerate with `scripts/fuzz.sh seeds` when the format changes).
pub static BLOB: &[u8] = include_bytes!("../data/smoke.blob");

/// RDMP steps one plan may take: a hostile blob or task costs at most this (a feasible
/// example task needs 6,000–7,600).
pub const PLAN_BUDGET_STEPS: u64 = 20_000;

/// The runtime's settings with the planning budget.
pub fn config() -> RuntimeConfig {
    RuntimeConfig {
        plan_budget: PlanBudget {
            steps: PLAN_BUDGET_STEPS,
        },
        ..RuntimeConfig::default()
    }
}

/// The committed blob, loaded once.
pub static RUNTIME: LazyLock<Runtime<'static>> = LazyLock::new(|| {
    Runtime::load_with(BLOB, config()).unwrap_or_else(|e| {
        panic!(
            "fuzz/data/smoke.blob does not load ({e}): regenerate it with `scripts/fuzz.sh seeds`"
        )
    })
});

/// The example cell's tasks on its floor plan.
pub static TASKS: LazyLock<Vec<FloorTask>> = LazyLock::new(|| world_tasks(&World::example()));

/// Plans `task` on `rt`: an answer must be a plan whose risk is a number ≥ 0 or an error
/// that reads as English.
pub fn check_plan(rt: &Runtime<'_>, task: &Task<'_>) {
    match plan(rt, task) {
        Ok(p) => {
            let j = p.skills.j;
            assert!(j >= 0.0, "a plan with risk J* = {j}");
            assert!(
                !p.skills.feasible || j <= rt.config.risk_threshold,
                "a feasible plan with risk J* = {j} above the threshold"
            );
        }
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}
