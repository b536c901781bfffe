//! `prf plan`: plan a task (or all tasks of the floor plan) with the no_std runtime on a blob,
//! print the choice, and optionally export the program at 1 kHz.

use crate::cli::args::{PlanningArgs, TaskArgs, WorldArgs, read_blob, runtime};
use anyhow::{Context, bail};
use prf_files::dataset::trajectory_csv;
use prf_runtime::executor::planar;
use prf_runtime::plan::{Plan, PlanError, Planner, plan};
use prf_runtime::program::Program;
use prf_runtime::recall::HOST_SLOTS;
use prf_runtime::skill_plan::MAX_TIME_SCALE;
use prf_runtime::{Runtime, RuntimeConfig};
use prf_shared::motion::Param;
use prf_sim::navigation::{PartTracker, drive_phases, execute_navigating, part_size};
use prf_sim::tasks::{FloorTask, world_tasks};
use prf_sim::world::World;
use prf_sim::world::geometry::Cell;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The blob (from `prf learn`).
    pub blob: PathBuf,
    /// The task (all three of --part, --from, --to), unless --all.
    #[command(flatten)]
    pub task: TaskArgs,
    /// Plan every task of the floor plan (18 in the example cell) and print a table. One
    /// planner plans them all: a pick or place candidate that tasks share is integrated once
    /// and recalled after ("recall" column); the plans are those of each task on its own.
    #[arg(long, conflicts_with_all = ["part", "from", "to", "export", "mcap"])]
    pub all: bool,
    /// Write the program at 1 kHz, executed on an ideal cell (the arm exact, the platform
    /// navigating on the world's floor map), as a dataset trajectory CSV.
    #[arg(long)]
    pub export: Option<PathBuf>,
    /// Write the executed program as a ROS 2 bag (MCAP) for Foxglove or rerun: the robot
    /// description, joint states, the platform on /tf, the locations, both workspaces as point
    /// clouds, the obstacles and the part as markers, the gripper and the risk along the
    /// program (see `prf export-mcap --help`).
    #[arg(long)]
    pub mcap: Option<PathBuf>,
    /// Rate of the bag's joint states and transforms, Hz (the program runs at 1 kHz; the
    /// risk is the largest of each interval).
    #[arg(long, default_value_t = 100.0)]
    pub mcap_rate: f64,
    /// Write the task as a task block (for the cell-controller firmware: flash it at the TASK
    /// region, 0x003F0000 on mps2-an500).
    #[arg(long, conflicts_with = "all")]
    pub task_block: Option<PathBuf>,
    /// The floor plan (its obstacles are not read).
    #[command(flatten)]
    pub world: WorldArgs,
    /// A task is physically feasible when J* is at most this risk, m.
    #[arg(long, default_value_t = 0.0)]
    pub threshold: f64,
    /// The clearance the plan must guarantee, m; refused when stricter than the blob's r (what
    /// a risk-0 plan guarantees).
    #[arg(long)]
    pub clearance: Option<f64>,
    /// Planning budget and search.
    #[command(flatten)]
    pub planning: PlanningArgs,
}

/// What a risk-0 plan on this blob guarantees (Sec. 4.1): every sphere inside Ω+ is within
/// ε = r_d − r of a demonstrated one, so it keeps r from whatever the programs kept r_d from.
/// Refuses a `required` clearance stricter than r.
fn clearance_guarantee(rt: &Runtime<'_>, required: Option<f64>) -> anyhow::Result<()> {
    let p = &rt.blob.payload;
    let (r_d, r) = (p.clearance_demo, p.clearance_acceptable);
    println!(
        "clearance: a risk-0 plan keeps ≥ r = {:.0} mm from every obstacle the programs kept r_d = {:.0} mm from (workspaces dilated by ε = {:.0} mm)",
        r * 1e3,
        r_d * 1e3,
        (r_d - r) * 1e3
    );
    match required {
        Some(c) if !(c <= r) => bail!(
            "--clearance {:.0} mm is stricter than the {:.0} mm this blob guarantees at risk 0: learn it again with --clearance {c} (needs r_d ≥ {c} m)",
            c * 1e3,
            r * 1e3
        ),
        _ => Ok(()),
    }
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let world = a.world.load()?;
    let bytes = read_blob(&a.blob)?;
    let t0 = Instant::now();
    let config = a.planning.config(RuntimeConfig {
        risk_threshold: a.threshold,
        ..RuntimeConfig::default()
    });
    let rt = runtime(&bytes, &a.blob, config)?;
    let load = t0.elapsed();
    println!(
        "blob {}: {} KiB, loaded in {:.0} µs; runtime state {} B",
        a.blob.display(),
        bytes.len() / 1024,
        load.as_secs_f64() * 1e6,
        std::mem::size_of::<Runtime>()
    );
    clearance_guarantee(&rt, a.clearance)?;
    if a.all {
        return plan_all(&rt, &world);
    }
    let ft = a.task.required(&world)?;
    if let Some(path) = &a.task_block {
        let block = ft.task_block()?;
        prf_files::atomic::write(path, &block)
            .with_context(|| format!("writing {}", path.display()))?;
        println!(
            "task block: {} B written to {}",
            block.len(),
            path.display()
        );
    }
    let t0 = Instant::now();
    let result = plan(&rt, &ft.task());
    let took = t0.elapsed().as_secs_f64();
    let p = match result {
        Ok(p) => p,
        Err(e) => {
            println!("task {}: {e}", ft.label());
            return Ok(());
        }
    };
    print_plan(&rt, &ft, &p, took)?;
    if a.export.is_some() || a.mcap.is_some() {
        let Some(program) = &p.program else {
            bail!("no program to export: no skill integrates for this task");
        };
        let samples = execute(&world, &rt, &ft, program)?;
        if let Some(path) = &a.export {
            prf_files::atomic::write(path, trajectory_csv(&samples))
                .with_context(|| format!("writing {}", path.display()))?;
            println!(
                "program: {:.2} s at 1 kHz on an ideal cell (arm exact, platform navigating on the floor map keeping {:.0} mm) ({} samples) written to {}",
                samples.len() as f64 * 1e-3,
                world.clearance.acceptable * 1e3,
                samples.len(),
                path.display()
            );
        }
        if let Some(path) = &a.mcap {
            crate::cli::export_mcap::program(&world, &rt, &ft, &p, &samples, a.mcap_rate, path)?;
        }
    }
    Ok(())
}

/// Runs `program` on the ideal cell whose platform navigates on `world`'s floor map, prints
/// each drive's corners and clearances; the samples at 1 kHz.
pub(crate) fn execute(
    world: &World,
    rt: &Runtime<'_>,
    ft: &FloorTask,
    program: &Program,
) -> anyhow::Result<Vec<prf_files::dataset::Sample>> {
    let (run, drives) = execute_navigating(world, rt, program, ft, 10_000_000)
        .with_context(|| format!("task {}", ft.label()))?;
    if let Some(f) = run.fault {
        bail!("the program faulted on the ideal cell: {f}");
    }
    let cell = Cell::new(world, &rt.model);
    let part = PartTracker::new(part_size(world, &ft.part.1), ft.part_pose);
    for (d, ph) in drives.iter().zip(drive_phases(&cell, &run.samples, part)) {
        println!(
            "  drive {:.1}–{:.1} s to ({:.3} m, {:.3} m, {:.1}°): {} corners, clearance {:.1} mm{}",
            ph.t.0,
            ph.t.1,
            d.goal[0],
            d.goal[1],
            d.goal[2].to_degrees(),
            d.path.len(),
            ph.min.robot * 1e3,
            if ph.holding {
                format!(", held part {:.1} mm", ph.min.part * 1e3)
            } else {
                String::new()
            }
        );
    }
    Ok(run.samples)
}

/// "stance 0 (x 1.20 m, y −0.85 m, yaw 90.0°)".
fn stance(i: u8, pose: &prf_shared::se3::Pose) -> String {
    let p = planar(pose);
    format!(
        "stance {i} (x {:.3} m, y {:.3} m, yaw {:.1}°)",
        p[0],
        p[1],
        p[2].to_degrees()
    )
}

/// "skill 12 (Pick, learned from d003 at CNC with Part1)".
fn skill(rt: &Runtime<'_>, k: u16) -> anyhow::Result<String> {
    let s = rt
        .blob
        .skill(k as usize)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let class = rt
        .blob
        .class(s.class as usize)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let loc = match s.location_type {
        Some(t) => rt
            .blob
            .location_type(t as usize)
            .map(|l| l.name)
            .unwrap_or("?"),
        None => "?",
    };
    let part = match s.part_type {
        Some(t) => rt.blob.part_type(t as usize).map(|p| p.name).unwrap_or("?"),
        None => "?",
    };
    let shared = if s.shared { ", via share()" } else { "" };
    Ok(format!(
        "skill {k} ({}, learned from {} at {loc} with {part}{shared})",
        class.name, s.demo
    ))
}

fn mm(x: f64) -> String {
    if x.is_finite() {
        format!("{:.1} mm", x * 1e3)
    } else {
        "∞".into()
    }
}

fn print_plan(rt: &Runtime<'_>, ft: &FloorTask, p: &Plan, took: f64) -> anyhow::Result<()> {
    let names = ["home".to_string(), ft.from.0.clone(), ft.to.0.clone()];
    let actions: Vec<String> = p
        .actions
        .iter()
        .map(|a| {
            let class = rt.class_code(a.class as usize).map_or("?", |c| c.name());
            let params = rt
                .blob
                .class(a.class as usize)
                .map(|c| c.action.params)
                .unwrap_or_default();
            let args: Vec<&str> = a.args[..a.n_args as usize]
                .iter()
                .zip(&params)
                .map(|(&b, kind)| match kind {
                    Param::Part => ft.part.0.as_str(),
                    Param::Location => names[b as usize].as_str(),
                })
                .collect();
            format!("{class}({})", args.join(", "))
        })
        .collect();
    let s = &p.skills;
    println!("task {}", ft.label());
    println!("  action plan: {}", actions.join(", "));
    let class = match (s.feasible, s.decided) {
        (true, _) => "physically feasible",
        (false, true) => "symbolically feasible, physically infeasible",
        (false, false) => "symbolically feasible, physical feasibility not decided",
    };
    println!(
        "  {class}: J* = {} (r_pick {}, r_place {}; threshold {})",
        mm(s.j),
        mm(s.r_pick),
        mm(s.r_place),
        mm(rt.config.risk_threshold)
    );
    if s.exhausted.is_some() {
        let verdict = if s.decided {
            "risky (proven)"
        } else {
            "not decided"
        };
        println!(
            "  {verdict}: J* ≥ {} after {} integrations: the planning budget of {} steps ran out (the plan below is the best found, J = {}; --budget-steps 0 searches to the end)",
            mm(s.lower),
            s.stats.integrations,
            rt.config.plan_budget.steps,
            mm(s.j)
        );
    }
    if let (Some(c), Some((p1, p2))) = (s.choice, p.stances) {
        println!("  at {}: {}", ft.from.0, stance(c.stance_from, &p1));
        println!("  at {}: {}", ft.to.0, stance(c.stance_to, &p2));
        println!("  grasp {} of {}", c.grasp, ft.part.1);
        println!("  pick:  {}", skill(rt, c.pick_skill)?);
        println!("  place: {}", skill(rt, c.place_skill)?);
    }
    if let Some((t1, t2)) = s.timing {
        for (what, t) in [("pick", t1), ("place", t2)] {
            println!(
                "  {what} timing: τ × {:.3} ({:.2} s), emitted stream at {}",
                t.scale,
                t.steps as f64 * rt.config.rdmp.dt,
                t.ratios
            );
        }
    }
    if s.choice.is_none() && s.stats.too_fast > 0 {
        println!(
            "  refused: {} candidate motions would exceed a joint limit even slowed down to τ × {MAX_TIME_SCALE}",
            s.stats.too_fast
        );
    }
    let st = &s.stats;
    println!(
        "  work: {} RDMP integrations ({} pruned, {} failed, {} too fast, {} missed their goal), {} skipped by their bound, {} steps, {:.1} ms; the paper's grid: {} integrations ({:.0}× more)",
        st.integrations,
        st.pruned,
        st.failed,
        st.too_fast,
        st.missed,
        st.bounded,
        st.steps,
        took * 1e3,
        st.grid_integrations,
        st.grid_integrations as f64 / st.integrations.max(1) as f64
    );
    if let Some(program) = &p.program {
        println!(
            "  program: {} segments, {:.2} s of arm motion",
            program.segments.len(),
            program.arm_ticks() as f64 * rt.config.rdmp.dt
        );
    }
    Ok(())
}

fn plan_all(rt: &Runtime<'_>, world: &World) -> anyhow::Result<()> {
    let tasks = world_tasks(world);
    println!(
        "{:>2}  {:<24} {:<10} {:>9}  {:>7} {:>7} {:>5}  {:>5} {:>5}  {:>5} {:>6}  {:>6} {:>6} {:>9}  {:>8}",
        "#",
        "task",
        "class",
        "J*",
        "stance1",
        "stance2",
        "grasp",
        "pick",
        "place",
        "τ×",
        "limit",
        "integr",
        "recall",
        "grid",
        "ms"
    );
    let (mut total_ms, mut integrations, mut grid, mut feasible) = (0.0, 0u64, 0u64, 0);
    let (mut bounded, mut steps, mut recalled) = (0u64, 0u64, 0u64);
    let mut slots = vec![None; HOST_SLOTS];
    let mut planner = Planner::new(rt, &mut slots);
    for (i, ft) in tasks.iter().enumerate() {
        let t0 = Instant::now();
        let result = planner.plan(&ft.task());
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        total_ms += ms;
        match result {
            Ok(p) => {
                let s = &p.skills;
                integrations += s.stats.integrations as u64;
                recalled += s.stats.recalled as u64;
                bounded += s.stats.bounded as u64;
                steps += s.stats.steps;
                grid += s.stats.grid_integrations;
                feasible += s.feasible as usize;
                let c = s.choice;
                let f = |v: Option<String>| v.unwrap_or_else(|| "-".into());
                let (scale, limit) = s.timing.map_or((None, None), |(a, b)| {
                    let scale = a.scale.max(b.scale);
                    let limit = a.ratios.max().max(b.ratios.max());
                    (Some(format!("{scale:.3}")), Some(format!("{limit:.3}")))
                });
                println!(
                    "{:>2}  {:<24} {:<10} {:>9}  {:>7} {:>7} {:>5}  {:>5} {:>5}  {:>5} {:>6}  {:>6} {:>6} {:>9}  {:>8.1}",
                    i,
                    ft.label(),
                    match (s.feasible, s.decided) {
                        (true, _) => "feasible",
                        (false, true) => "risky",
                        (false, false) => "undecided",
                    },
                    s.exhausted
                        .map_or_else(|| mm(s.j), |l| format!("≥{}", mm(l))),
                    f(c.map(|c| c.stance_from.to_string())),
                    f(c.map(|c| c.stance_to.to_string())),
                    f(c.map(|c| c.grasp.to_string())),
                    f(c.map(|c| c.pick_skill.to_string())),
                    f(c.map(|c| c.place_skill.to_string())),
                    f(scale),
                    f(limit),
                    s.stats.integrations,
                    s.stats.recalled,
                    s.stats.grid_integrations,
                    ms
                );
            }
            Err(e @ PlanError::Infeasible(_)) => {
                println!("{:>2}  {:<24} {e}", i, ft.label());
            }
            Err(e) => println!("{:>2}  {:<24} error: {e}", i, ft.label()),
        }
    }
    println!(
        "{feasible}/{} physically feasible; planning {:.1} ms in total; {} RDMP integrations of {steps} steps ({recalled} candidates recalled from earlier tasks, {bounded} skipped by their bound) against the paper's grid of {} ({:.0}× fewer)",
        tasks.len(),
        total_ms,
        integrations,
        grid,
        grid as f64 / integrations.max(1) as f64
    );
    Ok(())
}
