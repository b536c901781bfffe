//! `prf run`: plan one task with the runtime and execute it in real time on the host cell,
//! against a running `firmware-sim` (or one started for the run with `--spawn-firmware`).

use crate::cli::args::{PacingArgs, TaskArgs, WorldArgs, read_blob, runtime};
use crate::cli::child::{ChildGuard, spawn_firmware};
use anyhow::{Context, bail};
use prf_host::cell::{Cell, CellConfig};
use prf_runtime::executor::planar;
use prf_runtime::plan::plan;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The blob (from `prf learn`).
    pub blob: PathBuf,
    #[command(flatten)]
    pub task: TaskArgs,
    #[command(flatten)]
    pub world: WorldArgs,
    #[command(flatten)]
    pub pacing: PacingArgs,
    /// Cell name: the iceoryx2 services are prf/<cell>/…; must match firmware-sim's --cell.
    #[arg(long, default_value = "cell")]
    pub cell: String,
    /// Start firmware-sim for this run (as `prf firmware-sim`), with the platform at home.
    #[arg(long)]
    pub spawn_firmware: bool,
    /// Milliseconds without a joint state before the cell checks whether firmware-sim's process
    /// is alive (and stops with a fault if not).
    #[arg(long, default_value_t = 3.0)]
    pub dead_after: f64,
    /// Milliseconds without a joint state before the cell stops with a fault regardless.
    #[arg(long, default_value_t = 100.0)]
    pub silent_after: f64,
    /// Brake and end the run after this many seconds.
    #[arg(long)]
    pub stop_after: Option<f64>,
    /// Write the report as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let world = a.world.load()?;
    let bytes = read_blob(&a.blob)?;
    let rt = runtime(&bytes, &a.blob, Default::default())?;
    let ft = a.task.required(&world)?;
    let p = plan(&rt, &ft.task()).map_err(|e| anyhow::anyhow!("task {}: {e}", ft.label()))?;
    let (Some(program), true) = (&p.program, p.skills.feasible) else {
        bail!(
            "task {}: physically infeasible (J* = {:.1} mm); nothing to run",
            ft.label(),
            p.skills.j * 1e3
        );
    };
    let _child = if a.spawn_firmware {
        let log = std::env::temp_dir().join(format!("prf-firmware-sim-{}.log", a.cell));
        Some(ChildGuard(spawn_firmware(
            &a.cell,
            planar(&ft.home),
            &log,
            a.world.world.as_deref(),
        )?))
    } else {
        None
    };
    let mut cfg = CellConfig::new(&a.cell);
    cfg.alloc_probe = Some(crate::bench::alloc_count::thread_allocations);
    cfg.dead_after_ms = a.dead_after;
    cfg.silent_after_ms = a.silent_after;
    cfg.stop_after = a.stop_after.map(std::time::Duration::from_secs_f64);
    a.pacing.apply(&mut cfg);
    let mut cell = Cell::connect(cfg, &rt)?;
    println!(
        "task {}: J* = {:.1} mm, {} segments; running on cell {:?}",
        ft.label(),
        p.skills.j * 1e3,
        program.segments.len(),
        a.cell
    );
    let report = cell.execute(&rt, program, &ft.home)?;
    if a.spawn_firmware {
        cell.shutdown()?;
    }
    if let Some(path) = &a.json {
        prf_files::atomic::write(path, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    println!("{}", report.summary());
    println!("paced by {}", report.pacing);
    match &report.fault {
        Some(f) => bail!("task {}: {f}", ft.label()),
        None if report.stopped => {
            println!("stopped on request (--stop-after)");
            Ok(())
        }
        None => Ok(()),
    }
}
