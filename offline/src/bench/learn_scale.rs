//! `prf bench-learn`: learning and planning against the size of the archive (issue 66). One
//! archive of the largest N programs is generated (`prf gen --random N`, with `--vary` each
//! taught its own way); per N, a dataset of its first N programs is learned by a child
//! `prf learn` without a budget, whose wall time and peak memory (the kernel's `ru_maxrss` of
//! the child) are measured; then every task of the world is planned on that blob, each on its
//! own (a fresh planner: nothing recalled from another task), timed on the host. A table, a
//! CSV and three charts (learning time, memory and planning time against N).

use crate::cli::args::WorldArgs;
use crate::cli::generate::drawn;
use crate::cli::progress::Bar;
use anyhow::{Context, bail};
use prf_files::dataset::{MANIFEST, Manifest};
use prf_offline::plots::{self, ScalingPlot};
use prf_runtime::Runtime;
use prf_runtime::plan::plan;
use prf_sim::demogen::generate;
use prf_sim::tasks::world_tasks;
use prf_sim::world::World;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub world: WorldArgs,
    /// Archive sizes to learn, e.g. `64,256,1000`.
    #[arg(long, value_delimiter = ',', default_values_t = [64, 256, 1000])]
    pub n: Vec<usize>,
    /// Teach each program its own way (`prf gen --vary`); without it a task taught again is
    /// the same motion.
    #[arg(long)]
    pub vary: bool,
    /// Seed of the draws and the planners.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// An archive already written (a dataset directory, e.g. by `prf gen --random N --vary`)
    /// to take the first N programs of, instead of generating one.
    #[arg(long)]
    pub archive: Option<PathBuf>,
    /// Output directory: the archive, per N a dataset of its first N programs and the blob
    /// learned from it, `learn_scale.csv` and the charts.
    #[arg(short, long, default_value = "learn-scale")]
    pub output: PathBuf,
    /// Print nothing but the table and errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// What learning N programs took, and planning on what they taught.
struct Row {
    n: usize,
    wall_s: f64,
    peak_mib: f64,
    blob_kib: f64,
    planned: Planned,
}

/// Every task of the world planned on a blob, each on its own.
struct Planned {
    /// Median and largest host time per task, ms.
    median_ms: f64,
    max_ms: f64,
    /// Tasks physically feasible, of how many.
    feasible: usize,
    tasks: usize,
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let mut sizes = a.n.clone();
    sizes.retain(|&n| n > 0);
    sizes.sort_unstable();
    sizes.dedup();
    let Some(&most) = sizes.last().filter(|&&n| n > 0) else {
        bail!("--n: give at least one archive size above 0");
    };
    let world = a.world.load()?;
    let all = match &a.archive {
        Some(dir) => dir.clone(),
        None => write_archive(a, &world, most)?,
    };
    // The per-N datasets name the archive's files by absolute path.
    let all = std::fs::canonicalize(&all)
        .with_context(|| format!("{}: no archive there", all.display()))?;
    let held = archive_manifest(&all)?.demonstrations.len();
    if held < most {
        bail!(
            "{}: the archive holds {held} programs, fewer than --n {most}",
            all.display()
        );
    }
    let mut rows = Vec::new();
    for &n in &sizes {
        let dir = a.output.join(format!("n{n}"));
        first_programs(&all, n, &dir)?;
        let blob = a.output.join(format!("n{n}.blob"));
        let (wall_s, peak_kib) = learn_measured(&dir, &blob)?;
        let bytes = std::fs::read(&blob).with_context(|| format!("reading {}", blob.display()))?;
        let row = Row {
            n,
            wall_s,
            peak_mib: peak_kib as f64 / 1024.0,
            blob_kib: bytes.len() as f64 / 1024.0,
            planned: plan_every_task(&world, &bytes)
                .with_context(|| format!("planning on {}", blob.display()))?,
        };
        if !a.quiet {
            eprintln!(
                "learned {n} programs: {:.1} s, peak {:.0} MiB; planning {:.1} ms per task (median)",
                row.wall_s, row.peak_mib, row.planned.median_ms
            );
        }
        rows.push(row);
    }
    print!("{}", table(&rows));
    write_csv(&a.output.join("learn_scale.csv"), &rows)?;
    charts(&a.output, &rows, a.vary)?;
    Ok(())
}

/// Every task of `world` planned on `blob`, each with a fresh planner (nothing recalled).
fn plan_every_task(world: &World, blob: &[u8]) -> anyhow::Result<Planned> {
    let rt = Runtime::load(blob).map_err(|e| anyhow::anyhow!("loading the blob: {e}"))?;
    let tasks = world_tasks(world);
    let mut ms = Vec::with_capacity(tasks.len());
    let mut feasible = 0;
    for t in &tasks {
        let t0 = Instant::now();
        let p = plan(&rt, &t.task());
        ms.push(t0.elapsed().as_secs_f64() * 1e3);
        feasible += p.is_ok_and(|p| p.skills.feasible) as usize;
    }
    ms.sort_by(f64::total_cmp);
    Ok(Planned {
        median_ms: ms.get(ms.len() / 2).copied().unwrap_or(0.0),
        max_ms: ms.last().copied().unwrap_or(0.0),
        feasible,
        tasks: tasks.len(),
    })
}

/// Generates the archive of `most` programs drawn over the world's afforded tasks into
/// `OUTPUT/archive`.
fn write_archive(a: &Args, world: &World, most: usize) -> anyhow::Result<PathBuf> {
    let selection = drawn(&world.afforded_tasks(), most, a.seed);
    let bar = Bar::new("generating", "programs", a.quiet);
    let archive = generate(world, &selection, a.seed, 100.0, a.vary, &|p| bar.report(p))?;
    bar.finish();
    let all = a.output.join("archive");
    archive
        .write(&all)
        .with_context(|| format!("{}: cannot write the archive", all.display()))?;
    Ok(all)
}

/// The manifest of the archive in `all`.
fn archive_manifest(all: &Path) -> anyhow::Result<Manifest> {
    let path = all.join(MANIFEST);
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    Ok(prf_files::dataset::parse_manifest(&path, &text)?)
}

/// A dataset in `dir` of the first `n` programs of the archive in `all` (an absolute path):
/// its manifest, naming the archive's files, not copies.
fn first_programs(all: &Path, n: usize, dir: &Path) -> anyhow::Result<()> {
    let mut manifest = archive_manifest(all)?;
    manifest.demonstrations.truncate(n);
    let at = |f: &str| all.join(f).to_string_lossy().into_owned();
    for e in &mut manifest.demonstrations {
        (e.task, e.trajectory) = (at(&e.task), at(&e.trajectory));
    }
    std::fs::create_dir_all(dir)?;
    prf_files::atomic::write(&dir.join(MANIFEST), serde_json::to_vec_pretty(&manifest)?)
        .with_context(|| format!("writing {}", dir.join(MANIFEST).display()))
}

/// `prf learn DIR -o BLOB` as a child process: its wall time (s) and peak resident memory
/// (KiB, as the kernel counted it for the child alone). Its standard error goes to
/// `BLOB.log`, shown when it fails.
fn learn_measured(dir: &Path, blob: &Path) -> anyhow::Result<(f64, u64)> {
    let exe = std::env::current_exe().context("locating the prf executable")?;
    let log = blob.with_extension("log");
    let t0 = Instant::now();
    let child = Command::new(exe)
        .arg("learn")
        .arg(dir)
        .arg("-o")
        .arg(blob)
        .args(["--max-blob-bytes", "0", "--quiet"])
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&log)?)
        .spawn()
        .context("starting prf learn")?;
    let (status, peak_kib) = wait_with_peak(child.id())?;
    let wall = t0.elapsed().as_secs_f64();
    if status != 0 {
        let said = std::fs::read_to_string(&log).unwrap_or_default();
        bail!("prf learn {} failed ({status}): {said}", dir.display());
    }
    Ok((wall, peak_kib))
}

/// Waits for child `pid`: its exit status (or 128 + the signal) and peak resident memory,
/// KiB (`wait4`'s `ru_maxrss`).
fn wait_with_peak(pid: u32) -> anyhow::Result<(i32, u64)> {
    let mut status = 0;
    // SAFETY: `usage` is a plain C struct the call fills; `pid` is our own child, waited for
    // once (its `Child` handle is never waited on).
    #[allow(unsafe_code)]
    let (r, usage) = unsafe {
        let mut usage: libc::rusage = std::mem::zeroed();
        let r = libc::wait4(pid as libc::pid_t, &mut status, 0, &mut usage);
        (r, usage)
    };
    if r < 0 {
        return Err(std::io::Error::last_os_error()).context("waiting for prf learn");
    }
    let code = if libc::WIFEXITED(status) {
        libc::WEXITSTATUS(status)
    } else {
        128 + libc::WTERMSIG(status)
    };
    Ok((code, usage.ru_maxrss.max(0) as u64))
}

/// The rows as a Markdown table.
fn table(rows: &[Row]) -> String {
    let mut out = String::from(
        "| programs | learn wall | peak memory | blob | planning per task, median / max | tasks feasible |\n|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let p = &r.planned;
        out += &format!(
            "| {} | {:.1} s | {:.0} MiB | {:.1} KiB | {:.1} / {:.1} ms | {} of {} |\n",
            r.n, r.wall_s, r.peak_mib, r.blob_kib, p.median_ms, p.max_ms, p.feasible, p.tasks
        );
    }
    out
}

fn write_csv(path: &Path, rows: &[Row]) -> anyhow::Result<()> {
    let mut text = String::from(
        "programs,learn_wall_s,peak_memory_mib,blob_kib,plan_median_ms,plan_max_ms,tasks_feasible,tasks\n",
    );
    for r in rows {
        let p = &r.planned;
        text += &format!(
            "{},{:.3},{:.1},{:.1},{:.3},{:.3},{},{}\n",
            r.n, r.wall_s, r.peak_mib, r.blob_kib, p.median_ms, p.max_ms, p.feasible, p.tasks
        );
    }
    prf_files::atomic::write(path, text.as_bytes())
        .with_context(|| format!("writing {}", path.display()))
}

/// `learn_time`, `learn_memory` and `plan_time` (SVG and PNG) in `dir`.
fn charts(dir: &Path, rows: &[Row], vary: bool) -> anyhow::Result<()> {
    let x_label = if vary {
        "programs in the archive, each taught its own way"
    } else {
        "programs in the archive"
    };
    let time: Vec<(usize, f64)> = rows.iter().map(|r| (r.n, r.wall_s)).collect();
    plots::save(
        &ScalingPlot {
            title: "prf learn: wall time against the archive's size",
            x_label,
            y_label: "wall time, s",
            name: "read, learn and compile",
            points: &time,
        },
        &dir.join("learn_time"),
    )?;
    let memory: Vec<(usize, f64)> = rows.iter().map(|r| (r.n, r.peak_mib)).collect();
    plots::save(
        &ScalingPlot {
            title: "prf learn: peak memory against the archive's size",
            x_label,
            y_label: "peak resident memory, MiB",
            name: "peak resident memory",
            points: &memory,
        },
        &dir.join("learn_memory"),
    )?;
    let planning: Vec<(usize, f64)> = rows.iter().map(|r| (r.n, r.planned.median_ms)).collect();
    plots::save(
        &ScalingPlot {
            title: "prf plan: host time per task against the archive's size",
            x_label,
            y_label: "median planning time per task, ms",
            name: "every task of the world, each planned alone",
            points: &planning,
        },
        &dir.join("plan_time"),
    )?;
    Ok(())
}
