//! `prf`: host tools of the PRF cell runtime.

mod bench;
mod check;
mod demo;
mod generate;
mod learn_cmd;
mod plan_cmd;
mod plot;
mod synthetic;

use clap::{Parser, Subcommand};

/// PRF — program a robot cell by reusing its old programs.
///
/// Without a subcommand, runs `prf demo`.
#[derive(Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Kinematics + RDMP demonstration on the built-in KMR iiwa 14: FK, null space, RDMP
    /// training, reproduction and generalisation to new goals, singularity handling.
    Demo(demo::Args),
    /// Micro-benchmarks of the math core (medians, with the paper's SVD formulation as the
    /// baseline in the same process).
    Bench(bench::Args),
    /// Generate the demonstration dataset of a cell (default: the built-in example cell, all
    /// 64 afforded tasks) with the ground-truth motion planner.
    Gen(generate::Args),
    /// Validate a dataset directory (format, ids, time, limits); with `--world`, re-check every
    /// program against the ground-truth cell.
    CheckDataset(check::Args),
    /// Learn affordances, workspaces and skills from a dataset (Alg. 3) and compile the blob.
    Learn(learn_cmd::Args),
    /// Validate a blob and print its contents and size by section.
    Inspect(learn_cmd::InspectArgs),
    /// Plan a task with the runtime (task plan, SkillPlan-PTT with minimum risk), print the
    /// choice, optionally export the program at 1 kHz; `--all` plans every task of the cell.
    Plan(plan_cmd::Args),
}

fn main() -> anyhow::Result<()> {
    match Cli::parse().command {
        None => demo::run(&demo::Args::default()),
        Some(Command::Demo(args)) => demo::run(&args),
        Some(Command::Bench(args)) => bench::run(&args),
        Some(Command::Gen(args)) => generate::run(&args),
        Some(Command::CheckDataset(args)) => check::run(&args),
        Some(Command::Learn(args)) => learn_cmd::run(&args),
        Some(Command::Inspect(args)) => learn_cmd::inspect(&args),
        Some(Command::Plan(args)) => plan_cmd::run(&args),
    }
}
