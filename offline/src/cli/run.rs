//! `prf run`: plan one task with the runtime and execute it in real time on the host cell,
//! against a running `firmware-sim` (or one started for the run with `--spawn-firmware`).

use crate::cli::args::{PacingArgs, PlanningArgs, TaskArgs, WorldArgs, read_blob, runtime};
use crate::cli::child::{ChildGuard, spawn_firmware};
use anyhow::{Context, bail};
use prf_host::cell::{Cell, CellConfig, CellReport};
use prf_runtime::executor::planar;
use prf_runtime::plan::plan;
use prf_runtime::recover::{RecoverConfig, Situation, locate};
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
    /// Cell name: the iceoryx2 services are `prf/<cell>/…`; must match firmware-sim's --cell.
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
    /// Start from where an earlier run of this task stopped (a fault, a killed process): tell
    /// from the measured state where the arm is on the task's certified motions, retract it
    /// along the certified path to q_a,H at a reduced speed, and complete the task. With the
    /// cell already at q_a,H this is an ordinary run.
    #[arg(long)]
    pub recover: bool,
    /// After a fault during this run, recover as `--recover` does once the controller
    /// answers again with the arm at rest, and complete the task (one attempt).
    #[arg(long)]
    pub auto_recover: bool,
    /// Planning budget and search.
    #[command(flatten)]
    pub planning: PlanningArgs,
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let world = a.world.load()?;
    let bytes = read_blob(&a.blob)?;
    let rt = runtime(&bytes, &a.blob, a.planning.config(Default::default()))?;
    let ft = a.task.required(&world)?;
    let p = plan(&rt, &ft.task()).map_err(|e| anyhow::anyhow!("task {}: {e}", ft.label()))?;
    let (Some(program), true) = (&p.program, p.skills.feasible) else {
        let s = &p.skills;
        if !s.decided {
            let best = if s.j.is_finite() {
                format!("the best found has J = {:.1} mm", s.j * 1e3)
            } else {
                "none found yet".into()
            };
            bail!(
                "task {}: no risk-0 plan found within the planning budget of {} steps (J* ≥ {:.1} mm; {best}); nothing to run (--budget-steps 0 searches to the end)",
                ft.label(),
                rt.config.plan_budget.steps,
                s.lower * 1e3
            );
        }
        bail!(
            "task {}: physically infeasible (J* ≥ {:.1} mm); nothing to run",
            ft.label(),
            s.lower * 1e3
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
    let task = ft.task();
    let mut report = if a.recover {
        recover(&mut cell, &rt, &task, &p, &ft.home)?
    } else {
        cell.execute(&rt, program, &ft.home)?
    };
    if let (true, Some(f)) = (a.auto_recover, &report.fault) {
        println!("{}", report.summary());
        println!("fault: {f}; recovering once the arm is at rest");
        cell.wait_at_rest(std::time::Duration::from_secs(10))?;
        report = recover(&mut cell, &rt, &task, &p, &ft.home)?;
    }
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

/// Locates the cell in `plan`'s program from its measured state, says what the recovery will
/// do, and runs the recovery program (retraction, then the rest of the task).
fn recover(
    cell: &mut Cell,
    rt: &prf_runtime::Runtime<'_>,
    task: &prf_runtime::Task<'_>,
    plan: &prf_runtime::Plan,
    home: &prf_shared::se3::Pose,
) -> anyhow::Result<CellReport> {
    let m = cell.measured();
    let r = locate(rt, task, plan, &m, &RecoverConfig::new(&cell.cfg.executor))
        .map_err(|e| anyhow::anyhow!("cannot recover on cell {:?}: {e}", cell.cfg.cell))?;
    let held = if r.holding {
        "holding the part"
    } else {
        "gripper open"
    };
    match r.situation {
        Situation::AtHome => println!(
            "recover: the arm is at q_a,H ({held}): nothing to retract; resuming at segment {}",
            r.resume_at
        ),
        Situation::OnPath {
            segment,
            step,
            steps,
            gap,
            gap_risk,
        } => println!(
            "recover: the arm is {:.1} mrad from step {step} of {steps} of segment {segment}'s certified motion ({held}); moving onto it (risk {:.1} mm) and back along it to q_a,H, then resuming at segment {}",
            gap * 1e3,
            gap_risk * 1e3,
            r.resume_at
        ),
    }
    Ok(cell.resume(rt, &r.program, home)?)
}
