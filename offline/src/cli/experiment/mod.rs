//! `prf experiment`: the paper's evaluation on the example cell (Fig. 5 also on another
//! world), as tables, CSV and charts.

use crate::cli::args::WorldArgs;
use anyhow::Result;
use std::path::PathBuf;

mod monte_carlo;
mod rdmp_vs_dmp;

#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// Sec. 4.3 (Fig. 3 and 4): risk of RDMP and joint-space DMP trajectories generalised to a
    /// grid of new goals around one demonstration, for every approach of the example cell.
    RdmpVsDmp(RdmpVsDmpArgs),
    /// Sec. 6.3 (Fig. 5): feasible tasks and afforded tasks as the demonstrations are learned
    /// one at a time in random orders (incremental learning, an exact cache across steps),
    /// with the two cases of Sec. 7.1 and a from-scratch check of sampled steps; `--world
    /// plant` asks it of the plant.
    MonteCarlo(MonteCarloArgs),
}

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(clap::Args, Debug)]
pub struct RdmpVsDmpArgs {
    /// Output directory (CSV, SVG and PNG charts).
    #[arg(short, long, default_value = "target/prf-experiment/rdmp-vs-dmp")]
    pub out: PathBuf,
    /// Half the side of the square of new goals around the demonstrated one, m.
    #[arg(long, default_value_t = 0.1)]
    pub half_extent: f64,
    /// Goals per side of the square (odd: the demonstrated goal is one of them).
    #[arg(long, default_value_t = 21)]
    pub goals: usize,
    /// Seed of the ground-truth planner that makes the demonstrations.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print nothing but errors and the summary table.
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(clap::Args, Debug)]
pub struct MonteCarloArgs {
    /// Output directory (CSV, SVG and PNG charts).
    #[arg(short, long, default_value = "target/prf-experiment/monte-carlo")]
    pub out: PathBuf,
    /// Episodes (random orders of the demonstrations).
    #[arg(long, default_value_t = 50)]
    pub episodes: usize,
    /// Seed of the first episode's order (episode e uses seed + e).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Steps per episode (default: every demonstration).
    #[arg(long)]
    pub steps: Option<usize>,
    /// The dataset (default: generated in memory with planner seed 1: on the example cell its
    /// 64 afforded tasks, as `prf gen` and `prf demo` make them; on another world
    /// `--programs` of its afforded tasks drawn at random, each taught its own way, as
    /// `prf gen --random N --vary` makes them).
    #[arg(long)]
    pub dataset: Option<PathBuf>,
    #[command(flatten)]
    pub world: WorldArgs,
    /// Programs generated for a world other than the example when no `--dataset` is given.
    #[arg(long, default_value_t = 96)]
    pub programs: usize,
    /// Steps of the first episode re-counted from scratch (batch learn, every side decided
    /// anew) to check the incremental counts and to time both, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "2,8,32")]
    pub check_steps: Vec<usize>,
    /// Print nothing but errors and the tables.
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(a: &Args) -> Result<()> {
    match &a.command {
        Command::RdmpVsDmp(a) => rdmp_vs_dmp::run(a),
        Command::MonteCarlo(a) => monte_carlo::run(a),
    }
}
