//! `prf firmware`: run tasks on the cell-controller firmware under QEMU (mps2-an500,
//! Cortex-M7, `-icount shift=0`) with a blob flashed into its region, and check each against
//! the host runtime: the timing and RAM budgets, and the setpoint stream bit for bit.

use crate::cli::args::{TaskArgs, WorldArgs};
use crate::cli::progress::Bar;
use anyhow::bail;
use indicatif::ProgressBar;
use prf_offline::firmware::{
    self, GOAL_CORE_MAX, GOAL_CORE_MEAN, GOAL_TICK_INSTRUCTIONS, MAX_PLANNING_INSTRUCTIONS,
    MAX_STATIC_RAM, MAX_TICK_INSTRUCTIONS, STREAM_TOLERANCE, TaskReport,
};
use prf_sim::tasks::world_tasks;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The blob (e.g. target/prf-demo/cell.blob, written by `prf demo`).
    pub blob: PathBuf,
    /// One task (all three of --part, --from, --to); without them: every task.
    #[command(flatten)]
    pub task: TaskArgs,
    #[command(flatten)]
    pub world: WorldArgs,
    /// Where the task blocks and the firmware's setpoint streams are written.
    #[arg(long, default_value = "target/prf-firmware")]
    pub dir: PathBuf,
    /// QEMU runs at a time.
    #[arg(long, default_value_t = 2)]
    pub jobs: usize,
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let world = a.world.load()?;
    let tasks = match a.task.task(&world)? {
        Some(t) => vec![t],
        None => world_tasks(&world),
    };
    if !a.blob.is_file() {
        bail!(
            "{}: no such blob (write one with `prf demo` or `prf learn`)",
            a.blob.display()
        );
    }
    let (bytes, region) = (
        std::fs::metadata(&a.blob)?.len(),
        prf_offline::memory_map::blob_region_bytes(),
    );
    if bytes > region as u64 {
        bail!(
            "{}: the blob is {bytes} bytes and the controller's BLOB region (memory.x) holds {region}: compile it to fit with `prf learn … --max-blob-bytes {region}` (the default)",
            a.blob.display()
        );
    }
    std::fs::create_dir_all(&a.dir)?;
    let spinner = ProgressBar::new_spinner()
        .with_message("building the firmware (scripts/firmware.sh build)");
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    let elf = firmware::build()?;
    spinner.finish_with_message(format!("firmware: {}", elf.display()));
    let bar = Bar::new("QEMU", "tasks", false);
    bar.report(prf_files::Progress::Total(tasks.len() as u64));
    let reports = firmware::check_tasks(&elf, &a.blob, &tasks, &a.dir, a.jobs, |_| bar.inc());
    bar.finish();
    println!(
        "{:<26} {:>7} {:>9} {:>8} {:>7} {:>8} {:>13} {:>7} {:>8}  {:>9} {:>6}  check",
        "task",
        "ticks",
        "plan Mi",
        "tick max",
        "mean",
        "arm mean",
        "arm core",
        "RAM KiB",
        "crc32",
        "|Δq| max",
        "limit"
    );
    let mut failed = 0;
    let (mut max_tick, mut max_plan, mut max_ram) = (0, 0, 0);
    // The arm ticks without the output stage: the largest mean and the largest max.
    let (mut core_mean, mut core_max) = (0, 0);
    for r in &reports {
        match r {
            Ok(r) => {
                let ok = print_row(r);
                failed += !ok as usize;
                if let Some(f) = &r.run.figures {
                    max_tick = max_tick.max(f.tick_max);
                    max_plan = max_plan.max(f.planning_instructions);
                    max_ram = max_ram.max(f.ram_total);
                    core_mean = core_mean.max(f.by_mode[1].core_mean);
                    core_max = core_max.max(f.by_mode[1].core_max);
                }
            }
            Err(e) => {
                failed += 1;
                println!("error: {e:#}");
            }
        }
    }
    println!(
        "\nmax over {} tasks: executor tick {max_tick} instructions (budget {MAX_TICK_INSTRUCTIONS}, goal {GOAL_TICK_INSTRUCTIONS}); arm tick without the output stage mean {core_mean}, max {core_max} (goal {GOAL_CORE_MEAN} / {GOAL_CORE_MAX}); planning {:.1} M (bound {:.0} M); static RAM {:.1} KiB (budget {} KiB)",
        reports.len(),
        max_plan as f64 / 1e6,
        MAX_PLANNING_INSTRUCTIONS as f64 / 1e6,
        max_ram as f64 / 1024.0,
        MAX_STATIC_RAM / 1024
    );
    println!(
        "(instructions under qemu-system-arm -icount shift=0; arm core: the arm ticks' mean/max without the output stage and the hand-off to the cell; |Δq|: firmware vs host setpoints, allowed {STREAM_TOLERANCE:e} rad (0: bit for bit); limit: the firmware stream's peak ratio to the position, speed, acceleration and jerk limits, 1 ms finite differences; streams in {})",
        a.dir.display()
    );
    if failed > 0 {
        bail!("{failed} of {} tasks failed a check", reports.len());
    }
    Ok(())
}

/// Prints one task's row; true if it passed every check.
fn print_row(r: &TaskReport) -> bool {
    let Some(f) = &r.run.figures else {
        println!(
            "{:<26} firmware exited {:?} without its report:\n{}",
            r.label, r.run.status, r.run.stdout
        );
        return false;
    };
    let mut violations = firmware::violations(f);
    if let Ok(c) = &r.comparison
        && !c.emitted.within()
    {
        violations.push(format!("the stream exceeds the limits: {}", c.emitted));
    }
    let (diff, limit, verdict) = match &r.comparison {
        Ok(c) => (
            format!("{:.2e}", c.arm),
            format!("{:.3}", c.emitted.max()),
            if violations.is_empty() {
                "ok".to_string()
            } else {
                violations.join("; ")
            },
        ),
        Err(e) => ("-".into(), "-".into(), format!("stream: {e}")),
    };
    println!(
        "{:<26} {:>7} {:>9.1} {:>8} {:>7} {:>8} {:>13} {:>7.1} {:>8}  {:>9} {:>6}  {}",
        r.label,
        f.ticks,
        f.planning_instructions as f64 / 1e6,
        f.tick_max,
        f.tick_mean,
        f.by_mode[1].mean,
        format!("{}/{}", f.by_mode[1].core_mean, f.by_mode[1].core_max),
        f.ram_total as f64 / 1024.0,
        format!("{:08x}", f.crc32),
        diff,
        limit,
        verdict
    );
    violations.is_empty() && r.comparison.is_ok()
}
