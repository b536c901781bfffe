//! `prf`: host tools of the PRF cell runtime.

mod bench;
mod cli;
mod synthetic;

use clap::{Parser, Subcommand};
use cli::{
    check_dataset, demo, envelope, experiment, export_mcap, field_error, firmware, generate,
    import_bag, inspect, learn, plan, rdmp_demo, run, view,
};

#[global_allocator]
static ALLOCATOR: bench::alloc_count::Counting = bench::alloc_count::Counting;

/// PRF — program a robot cell by reusing its old programs.
///
/// Without a subcommand, runs `prf demo`: the full pipeline on the built-in example cell.
#[derive(Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// The main job: generate (or reuse) the example cell's dataset, learn the blob, start
    /// firmware-sim, plan all 18 tasks and execute them in real time over shared memory.
    Demo(demo::Args),
    /// Kinematics + RDMP demonstration on the built-in KMR iiwa 14: FK, null space, RDMP
    /// training, reproduction and generalisation to new goals, singularity handling.
    RdmpDemo(rdmp_demo::Args),
    /// Micro-benchmarks of the math core (medians, with the paper's SVD formulation as the
    /// baseline in the same process).
    Bench(bench::math::Args),
    /// Generate the demonstration dataset of a cell (default: the built-in example cell, all
    /// 64 afforded tasks) with the ground-truth motion planner.
    Gen(generate::Args),
    /// Validate a dataset directory (format, ids, time, limits); with `--world`, re-check every
    /// program against the ground-truth cell.
    CheckDataset(check_dataset::Args),
    /// Import a ROS 2 bag (MCAP, CDR: JointState, Odometry or /tf) with a task annotation as a
    /// dataset, resampled onto each program's clock.
    ImportBag(import_bag::Args),
    /// Write a dataset or a blob's knowledge as a ROS 2 bag (MCAP) for Foxglove or rerun:
    /// robot description, joint states, /tf, workspaces as point clouds, obstacles, parts and
    /// stances as markers (`prf plan --mcap` writes a planned program with its risk).
    ExportMcap(export_mcap::Args),
    /// Draw a planned program in its cell as PNG and SVG, from above and from the side: the
    /// robot's spheres at keyframes, the TCP path, the workspaces, obstacles and the part.
    View(view::Args),
    /// Learn affordances, workspaces and skills from a dataset (Alg. 3) and compile the blob.
    Learn(learn::Args),
    /// Validate a blob and print its contents and size by section.
    Inspect(inspect::Args),
    /// Plan a task with the runtime (task plan, SkillPlan-PTT with minimum risk), print the
    /// choice, optionally export the program at 1 kHz; `--all` plans every task of the cell.
    Plan(plan::Args),
    /// The part-pose envelope of a task: which offsets of the part's nominal pose (x, y, yaw)
    /// at one of its location types still plan at risk 0 with the blob (table, CSV, SVG).
    Envelope(envelope::Args),
    /// How far each learned Ω+ field lies above the exact Ω+ (every dilated demonstrated
    /// ball) near its boundary, and which part of the representation the millimetres come from.
    FieldError(field_error::Args),
    /// The paper's evaluation on the example cell: `rdmp-vs-dmp` (Sec. 4.3, Fig. 3–4) and
    /// `monte-carlo` (Sec. 6.3, Fig. 5; `--world plant` on the plant), as tables, CSV and
    /// charts (SVG + PNG).
    Experiment(experiment::Args),
    /// Plan one task and execute it in real time on the host cell (1 kHz, embassy-time, Ruckig
    /// output stage) against firmware-sim over iceoryx2 shared memory.
    Run(run::Args),
    /// Host cell figures: setpoint latency through iceoryx2 against a Unix socket, the 1 kHz
    /// loop's jitter and deadline misses against firmware-sim (beside a probe thread's: the
    /// machine's own stalls), Ruckig's per-update cost.
    BenchCell(bench::cell::Args),
    /// Learning and planning against the archive's size: per N programs of a generated
    /// archive (`--vary`: each taught its own way) or your own (`--archive`), `prf learn`'s
    /// wall time, peak memory and blob, and the host time to plan each task of the world on
    /// it (table, CSV, charts).
    BenchLearn(bench::learn_scale::Args),
    /// Run tasks on the cell-controller firmware (Cortex-M7 under QEMU mps2-an500, blob flashed
    /// into its region) and check each against the host: executor tick, planning and RAM
    /// budgets, and the setpoint stream bit for bit. Installs QEMU and the toolchain if
    /// missing.
    Firmware(firmware::Args),
    /// Receiving side of `prf bench-cell`'s latency comparison.
    #[command(hide = true)]
    IpcPeer(bench::cell::PeerArgs),
    /// The simulated iiwa joint controller (same as the `prf-firmware-sim` binary).
    FirmwareSim(prf_firmware_sim::cli::Args),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    if cli.command.as_ref().is_some_and(Command::only_prints) {
        die_quietly_on_a_closed_pipe();
    }
    match cli.command {
        None => demo::run(&demo::Args::default()),
        Some(Command::Demo(args)) => demo::run(&args),
        Some(Command::RdmpDemo(args)) => rdmp_demo::run(&args),
        Some(Command::Bench(args)) => bench::math::run(&args),
        Some(Command::Gen(args)) => generate::run(&args),
        Some(Command::CheckDataset(args)) => check_dataset::run(&args),
        Some(Command::ImportBag(args)) => import_bag::run(&args),
        Some(Command::ExportMcap(args)) => export_mcap::run(&args),
        Some(Command::View(args)) => view::run(&args),
        Some(Command::Learn(args)) => learn::run(&args),
        Some(Command::Inspect(args)) => inspect::run(&args),
        Some(Command::Plan(args)) => plan::run(&args),
        Some(Command::Envelope(args)) => envelope::run(&args),
        Some(Command::Experiment(args)) => experiment::run(&args),
        Some(Command::FieldError(args)) => field_error::run(&args),
        Some(Command::Run(args)) => run::run(&args),
        Some(Command::BenchCell(args)) => bench::cell::run(&args),
        Some(Command::BenchLearn(args)) => bench::learn_scale::run(&args),
        Some(Command::Firmware(args)) => firmware::run(&args),
        Some(Command::IpcPeer(args)) => bench::cell::peer(&args),
        Some(Command::FirmwareSim(args)) => Ok(prf_firmware_sim::cli::run(&args)?),
    }
}

impl Command {
    /// Commands that compute and print, without processes, sockets or pipes of their own to
    /// write to: a closed stdout may end them by SIGPIPE. The cell's commands keep Rust's
    /// default (SIGPIPE ignored), so that a dead peer is an error they report.
    fn only_prints(&self) -> bool {
        matches!(
            self,
            Command::RdmpDemo(_)
                | Command::Bench(_)
                | Command::Gen(_)
                | Command::CheckDataset(_)
                | Command::ImportBag(_)
                | Command::ExportMcap(_)
                | Command::Learn(_)
                | Command::Inspect(_)
                | Command::Plan(_)
                | Command::Envelope(_)
                | Command::Experiment(_)
                | Command::FieldError(_)
        )
    }
}

/// `prf … | head` ends the way Unix tools do when the reader closes the pipe: SIGPIPE ends
/// the process quietly. (Rust ignores SIGPIPE by default, and `println!` then panics on the
/// EPIPE error.)
#[allow(unsafe_code)] // One libc call: the signal's disposition.
fn die_quietly_on_a_closed_pipe() {
    // SAFETY: restores the default disposition of one signal before any thread starts; no
    // handler runs Rust code.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
