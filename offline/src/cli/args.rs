//! What several subcommands take: the task (`--part --from --to`), the floor plan (`--world`),
//! and a blob loaded into the runtime with errors that name the file.

use anyhow::{Context, bail};
use prf_runtime::{Runtime, RuntimeConfig};
use prf_sim::tasks::FloorTask;
use prf_sim::world::World;
use std::path::{Path, PathBuf};

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
#[derive(clap::Args, Debug, Clone, Default)]
pub struct WorldArgs {
    /// World file (JSON: floor plan, location poses, the platform's home, obstacles, parts);
    /// default: the built-in example cell.
    #[arg(long)]
    pub world: Option<PathBuf>,
}

impl WorldArgs {
    /// Loads `--world`, or the built-in example.
    pub fn load(&self) -> anyhow::Result<World> {
        match &self.world {
            Some(p) => Ok(World::load(p)?),
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
