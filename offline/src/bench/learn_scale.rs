//! `prf bench-learn`: learning against the size of the archive (issue 66). One archive of the
//! largest N programs is generated (`prf gen --random N`, with `--vary` each taught its own
//! way); per N, a dataset of its first N programs is learned by a child `prf learn`, whose
//! wall time and peak memory (the kernel's `ru_maxrss` of the child) are measured. A table, a
//! CSV and two charts (time and memory against N).

use crate::cli::args::WorldArgs;
use crate::cli::generate::drawn;
use crate::cli::progress::Bar;
use anyhow::{Context, bail};
use prf_files::dataset::{MANIFEST, Manifest};
use prf_offline::plots::{self, ScalingPlot};
use prf_sim::demogen::generate;
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
    /// Output directory: the archive, per N a dataset of its first N programs and the blob
    /// learned from it, `learn_scale.csv` and the charts.
    #[arg(short, long, default_value = "learn-scale")]
    pub output: PathBuf,
    /// Print nothing but the table and errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// What learning N programs took.
struct Row {
    n: usize,
    wall_s: f64,
    peak_mib: f64,
    blob_kib: f64,
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let mut sizes = a.n.clone();
    sizes.sort_unstable();
    sizes.dedup();
    let Some(&most) = sizes.last().filter(|&&n| n > 0) else {
        bail!("--n: give at least one archive size above 0");
    };
    let world = a.world.load()?;
    let selection = drawn(&world.afforded_tasks(), most, a.seed);
    let bar = Bar::new("generating", "programs", a.quiet);
    let archive = generate(&world, &selection, a.seed, 100.0, a.vary, &|p| {
        bar.report(p)
    })?;
    bar.finish();
    let all = a.output.join("archive");
    archive
        .write(&all)
        .with_context(|| format!("{}: cannot write the archive", all.display()))?;
    let mut rows = Vec::new();
    for &n in &sizes {
        let dir = a.output.join(format!("n{n}"));
        first_programs(&all, n, &dir)?;
        let blob = a.output.join(format!("n{n}.blob"));
        let (wall_s, peak_kib) = learn_measured(&dir, &blob)?;
        let blob_kib = std::fs::metadata(&blob)?.len() as f64 / 1024.0;
        let row = Row {
            n,
            wall_s,
            peak_mib: peak_kib as f64 / 1024.0,
            blob_kib,
        };
        if !a.quiet {
            eprintln!(
                "learned {n} programs: {:.1} s, peak {:.0} MiB",
                row.wall_s, row.peak_mib
            );
        }
        rows.push(row);
    }
    print!("{}", table(&rows));
    write_csv(&a.output.join("learn_scale.csv"), &rows)?;
    charts(&a.output, &rows, a.vary)?;
    Ok(())
}

/// A dataset in `dir` of the first `n` programs of the archive in `all`: its manifest, the
/// files named in the archive (`../archive/…`), not copied.
fn first_programs(all: &Path, n: usize, dir: &Path) -> anyhow::Result<()> {
    let path = all.join(MANIFEST);
    let text = std::fs::read_to_string(&path)?;
    let mut manifest: Manifest = prf_files::dataset::parse_manifest(&path, &text)?;
    manifest.demonstrations.truncate(n);
    let up = |f: &str| format!("../archive/{f}");
    for e in &mut manifest.demonstrations {
        (e.task, e.trajectory) = (up(&e.task), up(&e.trajectory));
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
        .arg("--quiet")
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
    let mut out =
        String::from("| programs | learn wall | peak memory | blob |\n|---|---|---|---|\n");
    for r in rows {
        out += &format!(
            "| {} | {:.1} s | {:.0} MiB | {:.1} KiB |\n",
            r.n, r.wall_s, r.peak_mib, r.blob_kib
        );
    }
    out
}

fn write_csv(path: &Path, rows: &[Row]) -> anyhow::Result<()> {
    let mut text = String::from("programs,learn_wall_s,peak_memory_mib,blob_kib\n");
    for r in rows {
        text += &format!(
            "{},{:.3},{:.1},{:.1}\n",
            r.n, r.wall_s, r.peak_mib, r.blob_kib
        );
    }
    prf_files::atomic::write(path, text.as_bytes())
        .with_context(|| format!("writing {}", path.display()))
}

/// `learn_time` and `learn_memory` (SVG and PNG) in `dir`.
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
    Ok(())
}
