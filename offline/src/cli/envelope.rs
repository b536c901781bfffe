//! `prf envelope`: the part-pose envelope of a task ([`prf_offline::envelope`]) as a table
//! per yaw, a CSV of every offset and a map (SVG and PNG).

use crate::cli::args::{SearchArg, TaskArgs, WorldArgs, budget, read_blob, runtime};
use crate::cli::progress::Bar;
use anyhow::{Context, bail};
use plotters::coord::Shift;
use plotters::prelude::*;
use prf_offline::envelope::{Cell, Grid, Options, Outcome, map, safe_square};
use prf_offline::plots::{self, Chart};
use prf_sim::tasks::{FloorTask, world_tasks};
use prf_sim::world::World;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The end of the task whose part pose moves.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum End {
    /// Where the part is picked up (--from).
    From,
    /// Where it is put down (--to).
    To,
}

impl End {
    /// "pick" or "place".
    fn side(self) -> &'static str {
        match self {
            End::From => "pick",
            End::To => "place",
        }
    }
}

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The blob (from `prf learn`).
    pub blob: PathBuf,
    /// The task (all three of --part, --from, --to).
    #[command(flatten)]
    pub task: TaskArgs,
    /// The floor plan.
    #[command(flatten)]
    pub world: WorldArgs,
    /// Whose nominal part pose moves: the location type of --from or of --to (every location
    /// of that type).
    #[arg(long, value_enum, default_value = "from")]
    pub at: End,
    /// Largest offset along x and y of the location frame, mm.
    #[arg(long, default_value_t = 40.0)]
    pub range_mm: f64,
    /// Grid step along x and y, mm.
    #[arg(long, default_value_t = 10.0)]
    pub step_mm: f64,
    /// Yaw offsets about the vertical, degrees, comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "-10,-5,0,5,10"
    )]
    pub yaw_deg: Vec<f64>,
    /// Planning budget per offset, RDMP steps, 0 for none (the default: every offset is
    /// decided, the search being finite). An offset that spends it undecided is shown as
    /// not known to be safe.
    #[arg(long, default_value_t = 0)]
    pub budget_steps: u64,
    /// How each offset is searched: decide only proves or refutes risk 0 (risky offsets get
    /// no J); decide-first also finds the least risky plan of a risky offset; optimum is
    /// the baseline.
    #[arg(long, value_enum, default_value = "decide")]
    pub search: SearchArg,
    /// Execute every safe offset's program and measure it against the true cell of the
    /// moved part (the world file's boxes and floor): arm, gripper, held part and drives must
    /// keep r. The command fails, naming the offsets, if one does not.
    #[arg(long)]
    pub check: bool,
    /// Output directory (envelope.csv, envelope.svg, envelope.png; with --all one of each
    /// per task and side, named after them, and summary.csv).
    #[arg(short, long, default_value = "target/prf-envelope")]
    pub out: PathBuf,
    /// Every task of the cell, the pick and the place side each (instead of one task and
    /// --at): a table of the safe squares per task, side and yaw.
    #[arg(long, conflicts_with_all = ["part", "from", "to", "at"])]
    pub all: bool,
}

/// What one task and side came to: per yaw the safe offsets, all offsets and the safe square.
struct Summary {
    task: String,
    side: String,
    yaws: Vec<(usize, usize, Option<f64>)>,
    /// With --check: the safe offsets' programs against the true cell.
    truth: Option<Checked>,
}

/// Safe offsets' programs executed in the true cell: how many, their smallest clearance (m),
/// and each offset that did not keep r (or could not be executed).
struct Checked {
    programs: usize,
    min: f64,
    failed: Vec<String>,
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    if !(a.range_mm >= 0.0 && a.step_mm > 0.0 && a.yaw_deg.iter().all(|y| y.is_finite())) {
        bail!(
            "--range-mm must be ≥ 0 and --step-mm > 0 (got {} and {}), --yaw-deg finite",
            a.range_mm,
            a.step_mm
        );
    }
    let world = a.world.load()?;
    let bytes = read_blob(&a.blob)?;
    // Fails with the file's name on a corrupt blob.
    runtime(&bytes, &a.blob, Default::default())?;
    let grid = Grid {
        range: a.range_mm * 1e-3,
        step: a.step_mm * 1e-3,
        yaws: a.yaw_deg.iter().map(|d| d.to_radians()).collect(),
    };
    if !a.all {
        let ft = a.task.required(&world)?;
        let s = envelope(a, &world, &bytes, &ft, a.at, &grid, &a.out.join("envelope"))?;
        return verdict(&[s], world.clearance.acceptable);
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let mut summaries = Vec::new();
    for ft in world_tasks(&world) {
        for end in [End::From, End::To] {
            let name = format!(
                "envelope-{}-{}-{}-{}",
                ft.part.0,
                ft.from.0,
                ft.to.0,
                end.side()
            );
            summaries.push(envelope(
                a,
                &world,
                &bytes,
                &ft,
                end,
                &grid,
                &a.out.join(name),
            )?);
            println!();
        }
    }
    print_summary(&summaries, &grid);
    let csv = a.out.join("summary.csv");
    prf_files::atomic::write(&csv, summary_csv(&summaries, &grid))
        .with_context(|| format!("writing {}", csv.display()))?;
    println!("wrote {}", csv.display());
    verdict(&summaries, world.clearance.acceptable)
}

/// With --check: one line over every task and side checked, and an error naming the offsets
/// whose programs came closer than r.
fn verdict(summaries: &[Summary], r: f64) -> anyhow::Result<()> {
    let checked: Vec<_> = summaries
        .iter()
        .filter_map(|s| s.truth.as_ref().map(|t| (s, t)))
        .collect();
    if checked.is_empty() {
        return Ok(());
    }
    let n: usize = checked.iter().map(|(_, t)| t.programs).sum();
    let min = checked
        .iter()
        .map(|(_, t)| t.min)
        .fold(f64::INFINITY, f64::min);
    let failed: Vec<String> = checked
        .iter()
        .flat_map(|(s, t)| {
            t.failed
                .iter()
                .map(move |f| format!("{} {}: {f}", s.task, s.side))
        })
        .collect();
    if summaries.len() > 1 {
        println!(
            "true cell, every task and side: {n} risk-0 programs executed, smallest clearance {:.1} mm (r = {:.0} mm)",
            min * 1e3,
            r * 1e3
        );
    }
    if !failed.is_empty() {
        bail!(
            "{} risk-0 programs do not keep r = {:.0} mm in the true cell:\n  {}",
            failed.len(),
            r * 1e3,
            failed.join("\n  ")
        );
    }
    Ok(())
}

/// Maps task `ft` with the part moved at `end` over `grid`: the tables, `<stem>.csv` and the
/// map `<stem>.svg`/`.png`.
fn envelope(
    a: &Args,
    world: &World,
    bytes: &[u8],
    ft: &FloorTask,
    end: End,
    grid: &Grid,
    stem: &Path,
) -> anyhow::Result<Summary> {
    let (location, kind) = match end {
        End::From => &ft.from,
        End::To => &ft.to,
    };
    let n = grid.offsets().len().pow(2) * grid.yaws.len();
    println!(
        "task {}: the part pose at every {kind} (here {location}) moved by up to ±{:.0} mm in x and y (step {:.0} mm) and turned by {:?}°; {n} plans, {}",
        ft.label(),
        a.range_mm,
        a.step_mm,
        a.yaw_deg,
        match a.budget_steps {
            0 => "each searched to the end".to_string(),
            n => format!("budget {n} steps each"),
        }
    );
    let bar = Bar::new("planning", "offsets", false);
    bar.report(prf_files::Progress::Total(n as u64));
    let cells = map(
        bytes,
        world,
        kind,
        (&ft.part.0, &ft.from.0, &ft.to.0),
        grid,
        Options {
            budget: budget(a.budget_steps),
            search: a.search.into(),
            check: a.check,
        },
        &|| bar.inc(),
    )?;
    bar.finish();
    print_tables(&cells, grid);
    let truth = a
        .check
        .then(|| check_report(&cells, world.clearance.acceptable));
    if let Some(dir) = stem.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let csv = stem.with_extension("csv");
    prf_files::atomic::write(&csv, to_csv(&cells))
        .with_context(|| format!("writing {}", csv.display()))?;
    let title = format!(
        "{}: part pose at {kind} ({location}) moved; green risk 0, orange risky, grey budget spent, red no plan",
        ft.label()
    );
    let [svg, png] = plots::save(
        &EnvelopeMap {
            cells: &cells,
            grid,
            title: &title,
        },
        stem,
    )?;
    println!(
        "wrote {}, {} and {}",
        csv.display(),
        svg.display(),
        png.display()
    );
    let yaws = grid.yaws.iter().map(|&yaw| tally(&cells, yaw)).collect();
    Ok(Summary {
        truth,
        task: ft.label(),
        side: format!("{} ({kind})", end.side()),
        yaws,
    })
}

/// The safe offsets' programs against the true cell, measured against `r`; printed.
fn check_report(cells: &[Cell], r: f64) -> Checked {
    let (mut n, mut min, mut failed) = (0, f64::INFINITY, Vec::new());
    for c in cells {
        let at = format!(
            "({:+.1}, {:+.1}) mm {:+.1}°",
            c.dx * 1e3,
            c.dy * 1e3,
            c.dyaw.to_degrees()
        );
        match &c.truth {
            None => {}
            Some(Ok(t)) => {
                n += 1;
                min = min.min(t.min());
                if !t.keeps(r) {
                    failed.push(format!(
                        "{at}: arm {:.1} mm ({}), held part {:.1} mm, drives {:.1} mm",
                        t.arm * 1e3,
                        t.arm_contact,
                        t.held * 1e3,
                        t.drives * 1e3
                    ));
                }
            }
            Some(Err(e)) => failed.push(format!("{at}: {e}")),
        }
    }
    println!(
        "true cell: {n} risk-0 programs executed, smallest clearance {:.1} mm (r = {:.0} mm), {} below r",
        min * 1e3,
        r * 1e3,
        failed.len()
    );
    Checked {
        programs: n,
        min,
        failed,
    }
}

/// The safe square, m, as the summary shows it: "±x mm", or "–" when the nominal pose is not
/// safe.
fn square(s: Option<f64>) -> String {
    s.map_or("–".into(), |r| format!("±{:.0} mm", r * 1e3))
}

/// One row per task and side: per yaw the safe square and the safe offsets.
fn print_summary(summaries: &[Summary], grid: &Grid) {
    println!("safe square around the nominal pose (and offsets at risk 0) per task, side and yaw:");
    let mut head = format!("{:<28} {:<16}", "task", "side");
    for yaw in &grid.yaws {
        let _ = write!(head, " {:>16}", format!("yaw {:+.1}°", yaw.to_degrees()));
    }
    println!("{head}");
    for s in summaries {
        let mut row = format!("{:<28} {:<16}", s.task, s.side);
        for (safe, all, sq) in &s.yaws {
            let _ = write!(row, " {:>16}", format!("{} ({safe}/{all})", square(*sq)));
        }
        println!("{row}");
    }
}

fn summary_csv(summaries: &[Summary], grid: &Grid) -> String {
    let mut out = String::from("task,side,dyaw_deg,safe,offsets,safe_square_mm\n");
    for s in summaries {
        for (yaw, (safe, all, sq)) in grid.yaws.iter().zip(&s.yaws) {
            let _ = writeln!(
                out,
                "{},{},{:.2},{safe},{all},{}",
                s.task,
                s.side,
                yaw.to_degrees(),
                sq.map_or(String::new(), |r| format!("{:.1}", r * 1e3))
            );
        }
    }
    out
}

fn symbol(o: &Outcome) -> char {
    match o {
        Outcome::Safe => '●',
        Outcome::Risky { .. } => '·',
        Outcome::Unknown(_) => '?',
        Outcome::NoPlan => 'x',
    }
}

/// At yaw `yaw`: the offsets at risk 0, all offsets, and the safe square ([`safe_square`]).
fn tally(cells: &[Cell], yaw: f64) -> (usize, usize, Option<f64>) {
    let at_yaw = cells.iter().filter(|c| c.dyaw == yaw);
    let safe = at_yaw
        .clone()
        .filter(|c| c.outcome == Outcome::Safe)
        .count();
    (safe, at_yaw.count(), safe_square(cells, yaw))
}

/// One table per yaw: rows y (top: +range), columns x; and the safe square.
fn print_tables(cells: &[Cell], grid: &Grid) {
    let axis = grid.offsets();
    println!("● risk 0 (safe)  · risky  ? budget spent, not shown safe  x no plan");
    for &yaw in &grid.yaws {
        let slice: Vec<&Cell> = cells.iter().filter(|c| c.dyaw == yaw).collect();
        let (safe, all, square) = tally(cells, yaw);
        let square = square.map_or("none (the nominal pose is not safe)".into(), |r| {
            format!("|dx|, |dy| ≤ {:.0} mm", r * 1e3)
        });
        println!(
            "\nyaw {:+.1}°: {safe}/{all} offsets safe; safe square around the nominal pose: {square}",
            yaw.to_degrees()
        );
        let mut head = String::from("  dy\\dx mm");
        for x in &axis {
            let _ = write!(head, "{:>5.0}", x * 1e3);
        }
        println!("{head}");
        for y in axis.iter().rev() {
            let mut row = format!("{:>10.0}", y * 1e3);
            for x in &axis {
                let c = slice.iter().find(|c| c.dx == *x && c.dy == *y);
                let _ = write!(row, "{:>5}", c.map_or(' ', |c| symbol(&c.outcome)));
            }
            println!("{row}");
        }
    }
}

fn to_csv(cells: &[Cell]) -> String {
    let mut s = String::from(
        "dx_mm,dy_mm,dyaw_deg,outcome,j_mm,j_lower_mm,integrations,steps,true_clearance_mm\n",
    );
    for c in cells {
        let (name, j, lower) = match c.outcome {
            Outcome::Safe => ("safe", Some(0.0), Some(0.0)),
            Outcome::Risky { j, lower } => {
                ("risky", Some(j).filter(|j| j.is_finite()), Some(lower))
            }
            Outcome::Unknown(l) => ("budget", None, Some(l)),
            Outcome::NoPlan => ("no_plan", None, None),
        };
        let mm = |v: Option<f64>| v.map_or(String::new(), |v| format!("{:.3}", v * 1e3));
        let _ = writeln!(
            s,
            "{:.1},{:.1},{:.2},{name},{},{},{},{},{}",
            c.dx * 1e3,
            c.dy * 1e3,
            c.dyaw.to_degrees(),
            mm(j),
            mm(lower),
            c.integrations,
            c.steps,
            mm(c.truth
                .as_ref()
                .and_then(|t| t.as_ref().ok())
                .map(|t| t.min()))
        );
    }
    s
}

/// One panel per yaw: a square per offset, green safe, orange risky, grey not shown safe,
/// red no plan.
struct EnvelopeMap<'a> {
    cells: &'a [Cell],
    grid: &'a Grid,
    title: &'a str,
}

impl Chart for EnvelopeMap<'_> {
    fn size(&self) -> (u32, u32) {
        (300 * self.grid.yaws.len().max(1) as u32, 380)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()>
    where
        DB::ErrorType: 'static,
    {
        let n = self.grid.yaws.len().max(1);
        root.fill(&WHITE)?;
        let root = root.titled(self.title, ("sans-serif", 16))?;
        let half = self.grid.step * 500.0;
        let lim = self.grid.range * 1e3 + half;
        for (panel, &yaw) in root.split_evenly((1, n)).iter().zip(&self.grid.yaws) {
            let mut chart = ChartBuilder::on(panel)
                .caption(format!("yaw {:+.1}°", yaw.to_degrees()), ("sans-serif", 14))
                .margin(8)
                .margin_right(24)
                .x_label_area_size(30)
                .y_label_area_size(40)
                .build_cartesian_2d(-lim..lim, -lim..lim)?;
            chart
                .configure_mesh()
                .x_desc("dx mm")
                .y_desc("dy mm")
                .x_label_formatter(&|v| format!("{v:.0}"))
                .y_label_formatter(&|v| format!("{v:.0}"))
                .disable_mesh()
                .draw()?;
            chart.draw_series(self.cells.iter().filter(|c| c.dyaw == yaw).map(|c| {
                let colour = match c.outcome {
                    Outcome::Safe => RGBColor(46, 160, 67),
                    Outcome::Risky { .. } => RGBColor(240, 140, 30),
                    Outcome::Unknown(_) => RGBColor(170, 170, 170),
                    Outcome::NoPlan => RGBColor(200, 40, 40),
                };
                let (x, y) = (c.dx * 1e3, c.dy * 1e3);
                Rectangle::new(
                    [
                        (x - half * 0.9, y - half * 0.9),
                        (x + half * 0.9, y + half * 0.9),
                    ],
                    colour.filled(),
                )
            }))?;
        }
        Ok(())
    }
}
