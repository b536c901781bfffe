//! `prf demo`, the main job: the whole pipeline on the built-in example cell with no
//! arguments. Generate the dataset (cached), learn and compile the blob, start firmware-sim,
//! plan every task and execute each feasible one in real time over iceoryx2 shared memory,
//! and print one row per task.

use crate::cli::args::runtime;
use crate::cli::child::{ChildGuard, spawn_firmware};
use crate::cli::progress::Bar;
use anyhow::{Context, bail};
use prf_files::dataset::Dataset;
use prf_host::cell::{Cell, CellConfig};
use prf_learn::compile;
use prf_learn::{LearnConfig, learn};
use prf_runtime::Runtime;
use prf_runtime::executor::planar;
use prf_runtime::plan::plan;
use prf_shared::robot::RobotModel;
use prf_sim::demogen::generate_dataset;
use prf_sim::tasks::{FloorTask, world_tasks};
use prf_sim::world::World;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Args, Debug, Default)]
pub struct Args {
    /// Working directory: the dataset is cached here, the blob and the controller's log are
    /// written here.
    #[arg(long, default_value = "target/prf-demo")]
    pub dir: PathBuf,
    /// Execute only these tasks (1-based, as listed; e.g. --task 1 --task 7).
    #[arg(long)]
    pub task: Vec<usize>,
    /// Generate the dataset again even if it is cached.
    #[arg(long)]
    pub regenerate: bool,
}

/// The main job: dataset → blob → controller → every task planned and executed.
pub fn run(a: &Args) -> anyhow::Result<()> {
    let dir = if a.dir.as_os_str().is_empty() {
        PathBuf::from("target/prf-demo")
    } else {
        a.dir.clone()
    };
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let world = World::example();
    let model = RobotModel::kmr_iiwa14();
    let tasks = world_tasks(&world);
    for &t in &a.task {
        if t == 0 || t > tasks.len() {
            bail!("--task {t}: the example cell has tasks 1..={}", tasks.len());
        }
    }
    let dataset = dataset(&dir, &world, &model, a.regenerate)?;
    let (blob, bytes) = blob(&dir, &dataset, &model)?;
    let rt = runtime(&bytes, &blob, Default::default())?;
    // The first task as a task block, for the firmware's self-contained image (its default).
    if let Some(first) = tasks.first() {
        let path = dir.join("task.bin");
        std::fs::write(&path, first.task_block()?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    // The controller, a process of its own, on a cell name no one else uses.
    let cell_name = format!("demo-{}", std::process::id());
    let log = dir.join("firmware-sim.log");
    let mut child = ChildGuard(spawn_firmware(
        &cell_name,
        planar(&world.home.pose()),
        &log,
        None,
    )?);
    let cfg = CellConfig {
        alloc_probe: Some(crate::bench::alloc_count::thread_allocations),
        ..CellConfig::new(&cell_name)
    };
    let mut cell = Cell::connect(cfg, &rt)?;
    println!(
        "firmware-sim: pid {}, cell {cell_name:?}, log {}",
        child.0.id(),
        log.display()
    );
    let (run, ok) = execute_all(&rt, &mut cell, &tasks, &a.task)?;
    cell.shutdown()?;
    let _ = child.0.wait();
    println!(
        "\n{ok} of {run} executed tasks completed; controller log: {}",
        log.display()
    );
    if ok < run {
        bail!("{} task(s) faulted", run - ok);
    }
    println!(
        "the same blob on the cell-controller firmware (Cortex-M7 under QEMU, timing budgets, \
         stream checked against the host): prf firmware {}",
        blob.display()
    );
    Ok(())
}

/// Step 1: the 64 afforded tasks of the example cell, by the ground-truth planner (cached in
/// `dir/dataset`).
fn dataset(
    dir: &Path,
    world: &World,
    model: &RobotModel,
    regenerate: bool,
) -> anyhow::Result<Dataset> {
    let ds_dir = dir.join("dataset");
    let marker = ds_dir.join(".complete");
    if marker.exists() && !regenerate {
        let ds = Dataset::read(&ds_dir, model)?;
        if ds.clearance_demo.is_some() {
            println!(
                "dataset: {} demonstrations cached in {} (--regenerate to make them again)",
                ds.demonstrations.len(),
                ds_dir.display()
            );
            return Ok(ds);
        }
        println!(
            "dataset: the cached one does not state r_d (an older format); generating it again"
        );
    }
    let t0 = Instant::now();
    let afforded = world.afforded_tasks();
    let b = Bar::new("generating", "demonstrations", false);
    let ds = generate_dataset(world, &afforded, 1, 100.0, &|p| b.report(p))?;
    b.finish();
    ds.write(&ds_dir)
        .with_context(|| format!("writing {}", ds_dir.display()))?;
    std::fs::write(&marker, b"")?;
    println!(
        "dataset: generated {} demonstrations into {} in {:.1} s",
        ds.demonstrations.len(),
        ds_dir.display(),
        t0.elapsed().as_secs_f64()
    );
    Ok(ds)
}

/// Step 2: learn and compile; the blob's path and bytes.
fn blob(dir: &Path, dataset: &Dataset, model: &RobotModel) -> anyhow::Result<(PathBuf, Vec<u8>)> {
    let t1 = Instant::now();
    let b = Bar::new("learning", "units", false);
    let knowledge = learn(dataset, model, &LearnConfig::default(), &|p| b.report(p))?;
    b.finish();
    let bytes = compile(&knowledge)?;
    let blob = dir.join("cell.blob");
    prf_files::atomic::write(&blob, &bytes)
        .with_context(|| format!("writing {}", blob.display()))?;
    println!(
        "blob: {} ({:.1} KiB) learned in {:.2} s",
        blob.display(),
        bytes.len() as f64 / 1024.0,
        t1.elapsed().as_secs_f64()
    );
    Ok((blob, bytes))
}

/// Step 3: plan every task (or those in `only`, 1-based) and execute each feasible one on the
/// cell, one row each; (executed, completed).
fn execute_all(
    rt: &Runtime<'_>,
    cell: &mut Cell,
    tasks: &[FloorTask],
    only: &[usize],
) -> anyhow::Result<(usize, usize)> {
    println!(
        "\n{:>2}  {:<22} {:<8} {:>7}  {:<10} {:>5} {:>8} {:>9} {:>8} {:>4} {:>6} {:>13}",
        "#",
        "task",
        "feasible",
        "J* mm",
        "stances",
        "grasp",
        "time s",
        "track mrad",
        "drive mm",
        "lost",
        "misses",
        "lat p50/p99 µs"
    );
    let (mut run, mut ok) = (0, 0);
    for (i, ft) in tasks.iter().enumerate() {
        if !only.is_empty() && !only.contains(&(i + 1)) {
            continue;
        }
        let label = ft.label();
        let p = match plan(rt, &ft.task()) {
            Ok(p) => p,
            Err(e) => {
                println!("{:>2}  {label:<22} no: {e}", i + 1);
                continue;
            }
        };
        let s = &p.skills;
        let choice = s.choice.map_or(("-".to_string(), "-".to_string()), |c| {
            (
                format!("{}/{}", c.stance_from, c.stance_to),
                c.grasp.to_string(),
            )
        });
        let head = format!(
            "{:>2}  {label:<22} {:<8} {:>7.1}  {:<10} {:>5}",
            i + 1,
            if s.feasible { "yes" } else { "no" },
            s.j * 1e3,
            choice.0,
            choice.1
        );
        let (true, Some(program)) = (s.feasible, &p.program) else {
            println!("{head}");
            continue;
        };
        run += 1;
        // Tasks start where the previous one ended: at home.
        let r = cell.execute(rt, program, &ft.home)?;
        let tail = format!(
            "{:>8.1} {:>9.2} {:>8} {:>4} {:>6} {:>6.1}/{:<6.1}",
            r.duration_s,
            r.max_tracking_error * 1e3,
            r.min_drive_clearance
                .map_or("-".to_string(), |c| format!("{:.1}", c * 1e3)),
            r.lost,
            r.deadline_misses,
            r.latency_us[0],
            r.latency_us[1]
        );
        match (&r.fault, r.completed) {
            (None, true) => {
                ok += 1;
                println!("{head} {tail}");
            }
            (f, _) => println!(
                "{head} {tail}  FAULT: {}",
                f.as_deref().unwrap_or("incomplete")
            ),
        }
    }
    Ok((run, ok))
}
