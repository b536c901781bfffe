//! `prf run`: plan one task with the runtime and execute it in real time on the host cell,
//! against a running `firmware-sim` (or one started for the run with `--spawn-firmware`).

use anyhow::{Context, bail};
use prf_offline::cell::{Cell, CellConfig, CellReport};
use prf_offline::tasks::FloorTask;
use prf_runtime::Runtime;
use prf_runtime::executor::planar;
use prf_runtime::plan::plan;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The blob (from `prf learn`).
    pub blob: PathBuf,
    /// Part instance id, e.g. Part1.
    #[arg(long)]
    pub part: String,
    /// Location instance the part is at, e.g. CNC1.
    #[arg(long)]
    pub from: String,
    /// Location instance the part goes to, e.g. Table1.
    #[arg(long)]
    pub to: String,
    /// Floor plan (world file); default: the built-in example cell.
    #[arg(long)]
    pub world: Option<PathBuf>,
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

/// Starts `prf firmware-sim` as a child process of this one.
pub fn spawn_firmware(cell: &str, base: [f64; 3], log: &Path) -> anyhow::Result<Child> {
    let exe = std::env::current_exe().context("locating the prf executable")?;
    Command::new(exe)
        .args([
            "firmware-sim",
            "--cell",
            cell,
            "--exit-with-parent",
            "--log",
        ])
        .arg(log)
        .arg(format!("--base={},{},{}", base[0], base[1], base[2]))
        .stdout(Stdio::null())
        .spawn()
        .context("starting prf firmware-sim")
}

/// "11.2 s, tracking ≤ 1.3 mrad, lost 0, repeated 0, deadline misses 0, latency p50 6 µs".
pub fn summary(r: &CellReport) -> String {
    format!(
        "{:.1} s, max tracking error {:.2} mrad, lost {}, repeated {}, refused {}, deadline misses {}, wake-up late p50 {:.0} µs p99 {:.0} µs max {:.0} µs, setpoint latency p50 {:.1} µs p99 {:.1} µs max {:.0} µs",
        r.duration_s,
        r.max_tracking_error * 1e3,
        r.lost,
        r.repeated,
        r.rejected,
        r.deadline_misses,
        r.wake_late_us[0],
        r.wake_late_us[1],
        r.wake_late_us[3],
        r.latency_us[0],
        r.latency_us[1],
        r.latency_us[3]
    )
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let world = crate::generate::load_world(&a.world)?;
    let bytes = std::fs::read(&a.blob).with_context(|| format!("reading {}", a.blob.display()))?;
    let rt = Runtime::load(&bytes).map_err(|e| anyhow::anyhow!("{}: {e}", a.blob.display()))?;
    let ft = FloorTask::new(&world, &a.part, &a.from, &a.to)?;
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
        Some(ChildGuard(spawn_firmware(&a.cell, planar(&ft.home), &log)?))
    } else {
        None
    };
    let mut cfg = CellConfig::new(&a.cell);
    cfg.dead_after_ms = a.dead_after;
    cfg.silent_after_ms = a.silent_after;
    cfg.stop_after = a.stop_after.map(std::time::Duration::from_secs_f64);
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
        std::fs::write(path, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    println!("{}", summary(&report));
    match &report.fault {
        Some(f) => bail!("task {}: {f}", ft.label()),
        None if report.stopped => {
            println!("stopped on request (--stop-after)");
            Ok(())
        }
        None => Ok(()),
    }
}

/// Kills the child when dropped (an error path must not leave a controller running).
pub struct ChildGuard(pub Child);

impl Drop for ChildGuard {
    fn drop(&mut self) {
        // A child that already exited after SHUTDOWN is reaped; otherwise it is killed.
        let exited = matches!(self.0.try_wait(), Ok(Some(_)));
        if !exited {
            std::thread::sleep(std::time::Duration::from_millis(50));
            if !matches!(self.0.try_wait(), Ok(Some(_))) {
                let _ = self.0.kill();
            }
        }
        let _ = self.0.wait();
    }
}
