//! What several subcommands take: the task (`--part --from --to`), the floor plan (`--world`),
//! and a blob loaded into the runtime with errors that name the file.

use anyhow::{Context, bail};
use prf_runtime::skill_plan::PlanBudget;
use prf_runtime::{Runtime, RuntimeConfig};
use prf_sim::tasks::FloorTask;
use prf_sim::world::World;
use std::path::{Path, PathBuf};

/// How skill planning searches ([`prf_runtime::skill_plan::Search`]).
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SearchArg {
    /// Prove or refute J* ≤ threshold first; the optimum only when refuted.
    #[default]
    DecideFirst,
    /// Only prove or refute J* ≤ threshold (a refuted task has no plan to show).
    Decide,
    /// The optimum search alone (the baseline).
    Optimum,
}

impl From<SearchArg> for prf_runtime::skill_plan::Search {
    fn from(s: SearchArg) -> Self {
        match s {
            SearchArg::DecideFirst => Self::DecideFirst,
            SearchArg::Decide => Self::Decide,
            SearchArg::Optimum => Self::Optimum,
        }
    }
}

/// How much skill planning may do per task, and how it searches.
#[derive(clap::Args, Debug, Clone)]
pub struct PlanningArgs {
    /// Planning budget per task, RDMP integration steps, 0 for none. When it runs out the
    /// answer is the best plan found and a lower bound of J*: risky when that bound is above
    /// the threshold, otherwise not decided.
    #[arg(long, default_value_t = PlanBudget::HOST.steps)]
    pub budget_steps: u64,
    /// How each task is searched: decide-first proves or refutes risk ≤ threshold before it
    /// looks for the least risky plan; optimum is the single search it replaced (the baseline).
    #[arg(long, value_enum, default_value_t)]
    pub search: SearchArg,
}

impl PlanningArgs {
    /// The runtime settings these give, on top of `config`.
    pub fn config(&self, config: RuntimeConfig) -> RuntimeConfig {
        RuntimeConfig {
            plan_budget: budget(self.budget_steps),
            search: self.search.into(),
            ..config
        }
    }
}

/// The planning budget of a `--budget-steps` flag: 0 is none.
pub fn budget(steps: u64) -> PlanBudget {
    match steps {
        0 => PlanBudget::UNLIMITED,
        steps => PlanBudget { steps },
    }
}

/// One task of the floor plan: a part from one location to another.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct TaskArgs {
    /// Part instance id, e.g. Part1.
    #[arg(long)]
    pub part: Option<String>,
    /// Location instance the part is at, e.g. CNC1.
    #[arg(long)]
    pub from: Option<String>,
    /// Location instance the part goes to, e.g. Table1.
    #[arg(long)]
    pub to: Option<String>,
}

impl TaskArgs {
    /// The task named, or None when none of the three is given; an error when only some are.
    pub fn task(&self, world: &World) -> anyhow::Result<Option<FloorTask>> {
        match (&self.part, &self.from, &self.to) {
            (None, None, None) => Ok(None),
            (Some(part), Some(from), Some(to)) => Ok(Some(FloorTask::new(world, part, from, to)?)),
            _ => bail!("--part, --from and --to name a task together: give all three"),
        }
    }

    /// The task named; an error when it is not given.
    pub fn required(&self, world: &World) -> anyhow::Result<FloorTask> {
        match self.task(world)? {
            Some(t) => Ok(t),
            None => bail!(
                "name the task with --part, --from and --to (e.g. --part Part1 --from CNC1 --to Table1)"
            ),
        }
    }
}

/// The cell's world file.
/// How the host cell's 1 kHz loop is paced.
#[derive(clap::Args, Debug, Clone)]
pub struct PacingArgs {
    /// How the loop waits for its tick: in its own thread (clock_nanosleep to the absolute
    /// tick time) or woken by an alarm thread (embassy-time's std driver design).
    #[arg(long, value_enum, default_value = "in-thread")]
    pub wait: WaitKind,
    /// With --wait in-thread: sleep to this many µs before each tick, then busy-wait.
    #[arg(long, default_value_t = 0)]
    pub spin_us: u64,
    /// Run the loop thread as SCHED_FIFO (priority 1–99, default 80) with memory locked,
    /// where the process may; the report says what was granted.
    #[arg(
        long,
        value_name = "PRIORITY",
        num_args = 0..=1,
        default_missing_value = "80",
        value_parser = clap::value_parser!(i32).range(1..=99)
    )]
    pub realtime: Option<i32>,
}

/// `--wait` values.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum WaitKind {
    InThread,
    AlarmThread,
}

impl PacingArgs {
    /// Sets the cell's pacing.
    pub fn apply(&self, cfg: &mut prf_host::cell::CellConfig) {
        cfg.wait = match self.wait {
            WaitKind::InThread => prf_host::pacing::Wait::InThread {
                spin_us: self.spin_us,
            },
            WaitKind::AlarmThread => prf_host::pacing::Wait::AlarmThread,
        };
        cfg.realtime = self.realtime;
    }
}

#[derive(clap::Args, Debug, Clone, Default)]
pub struct WorldArgs {
    /// World file (JSON: floor plan, location poses, the platform's home, obstacles, parts),
    /// or `plant` for the built-in plant (twelve locations of four types, three part types);
    /// default: the built-in example cell (`example`).
    #[arg(long)]
    pub world: Option<PathBuf>,
}

impl WorldArgs {
    /// Loads `--world` ([`World::named`]), or the built-in example.
    pub fn load(&self) -> anyhow::Result<World> {
        match &self.world {
            Some(p) => Ok(World::named(p)?),
            None => Ok(World::example()),
        }
    }
}

/// The bytes of a blob file.
pub fn read_blob(path: &Path) -> anyhow::Result<Vec<u8>> {
    std::fs::read(path).with_context(|| format!("reading the blob {}", path.display()))
}

/// The runtime on a blob's bytes; a corrupt blob is an error naming the file.
pub fn runtime<'b>(
    bytes: &'b [u8],
    path: &Path,
    config: RuntimeConfig,
) -> anyhow::Result<Runtime<'b>> {
    Runtime::load_with(bytes, config)
        .with_context(|| format!("loading the blob {}", path.display()))
}
