//! `prf gen`: writes the demonstration dataset of a cell.

use crate::cli::args::WorldArgs;
use crate::cli::progress::Bar;
use anyhow::{Context, bail};
use prf_shared::robot::RobotModel;
use prf_sim::demogen::generate;
use prf_sim::world::AffordedTask;
use prf_sim::world::floorplan::floorplan_svg;
use prf_sim::world::geometry::Cell;
use rand::{RngExt, SeedableRng, rngs::StdRng};
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output directory.
    #[arg(short, long, default_value = "dataset")]
    pub output: PathBuf,
    #[command(flatten)]
    pub world: WorldArgs,
    /// Only these afforded tasks, by index (see --list), e.g. `0,5,10-12`.
    #[arg(long, conflicts_with = "random")]
    pub only: Option<String>,
    /// N afforded tasks drawn at random (with replacement; each with its own planner seed).
    #[arg(long)]
    pub random: Option<usize>,
    /// Seed of the planners (and of --random).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Teach each program its own way (arm speeds, pre-grasp distance, a via point), as an
    /// archive holds a task taught again on another day; without it every program of an
    /// afforded task is the same motion.
    #[arg(long)]
    pub vary: bool,
    /// Sample rate of the trajectories, Hz.
    #[arg(long, default_value_t = 100.0)]
    pub rate: f64,
    /// List the world's tasks and afforded tasks and exit.
    #[arg(long)]
    pub list: bool,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Parses `0,5,10-12` into indices below `n`.
fn parse_selection(s: &str, n: usize) -> anyhow::Result<Vec<usize>> {
    let mut out = Vec::new();
    for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (a, b) = match part.split_once('-') {
            Some((a, b)) => (a.trim(), b.trim()),
            None => (part, part),
        };
        let a: usize = a
            .parse()
            .with_context(|| format!("--only: {part:?} is not an index"))?;
        let b: usize = b
            .parse()
            .with_context(|| format!("--only: {part:?} is not an index"))?;
        if a > b || b >= n {
            bail!("--only: {part:?} is outside 0..{}", n - 1);
        }
        out.extend(a..=b);
    }
    Ok(out)
}

/// `n` of the `afforded` tasks drawn at random with replacement (`prf gen --random N`): the
/// same draws for the same seed, a longer draw starting with a shorter one's.
pub fn drawn(afforded: &[AffordedTask], n: usize, seed: u64) -> Vec<AffordedTask> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..n)
        .map(|_| afforded[rng.random_range(0..afforded.len())])
        .collect()
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let world = args.world.load()?;
    let afforded = world.afforded_tasks();
    if args.list {
        use std::io::Write;
        let mut text = format!(
            "{} tasks, {} afforded tasks\n",
            world.tasks().len(),
            afforded.len()
        );
        for (i, a) in afforded.iter().enumerate() {
            text += &format!("{i:4}  {}\n", world.label(a));
        }
        // A closed pipe (`prf gen --list | head`) is not an error.
        let _ = std::io::stdout().lock().write_all(text.as_bytes());
        return Ok(());
    }
    if !(args.rate > 0.0 && args.rate.is_finite()) {
        bail!("--rate must be positive, got {}", args.rate);
    }
    let selection: Vec<AffordedTask> = if let Some(n) = args.random {
        drawn(&afforded, n, args.seed)
    } else if let Some(s) = &args.only {
        parse_selection(s, afforded.len())?
            .into_iter()
            .map(|i| afforded[i])
            .collect()
    } else {
        afforded.clone()
    };
    let bar = Bar::new("generating", "demonstrations", args.quiet);
    let start = Instant::now();
    let dataset = generate(&world, &selection, args.seed, args.rate, args.vary, &|p| {
        bar.report(p)
    })?;
    bar.finish();
    dataset
        .write(&args.output)
        .with_context(|| format!("{}: cannot write the dataset", args.output.display()))?;
    let cell = Cell::new(&world, &RobotModel::kmr_iiwa14());
    let plan = args.output.join("floorplan.svg");
    prf_files::atomic::write(&plan, floorplan_svg(&world, &cell, &dataset.demonstrations))
        .with_context(|| format!("{}: cannot write", plan.display()))?;
    if !args.quiet {
        let seconds: f64 = dataset
            .demonstrations
            .iter()
            .map(|d| d.samples.last().map_or(0.0, |s| s.t))
            .sum();
        println!(
            "wrote {} demonstrations ({:.0} s of robot programs) to {} in {:.1} s; top view: {}",
            dataset.demonstrations.len(),
            seconds,
            args.output.display(),
            start.elapsed().as_secs_f64(),
            plan.display()
        );
    }
    Ok(())
}
