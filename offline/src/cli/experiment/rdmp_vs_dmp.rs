//! `prf experiment rdmp-vs-dmp`: the tables, CSVs and charts of Sec. 4.3 (Fig. 3 and 4).

use super::RdmpVsDmpArgs;
use crate::cli::progress::Bar;
use anyhow::{Context, Result};
use prf_offline::experiment::rdmp_vs_dmp::{
    ApproachResult, Ending, GoalGrid, GoalOutcome, Trajectory, elbow_x, experiment, workspace_slice,
};
use prf_offline::plots::{self, HeatMap, Histogram, LinePlot, Series};
use prf_sim::world::World;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// "CNC front" → "cnc_front".
fn slug(name: &str) -> String {
    name.to_lowercase().replace(' ', "_")
}

pub fn run(a: &RdmpVsDmpArgs) -> Result<()> {
    anyhow::ensure!(
        a.goals >= 1 && a.goals % 2 == 1,
        "--goals {} must be odd, so that the demonstrated goal is on the grid",
        a.goals
    );
    anyhow::ensure!(
        a.half_extent >= 0.0 && a.half_extent.is_finite(),
        "--half-extent {} must be a distance ≥ 0 m",
        a.half_extent
    );
    let grid = GoalGrid {
        half_extent: a.half_extent,
        n: a.goals,
    };
    let world = World::example();
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let t0 = Instant::now();
    let bar = Bar::new("approaches", "approaches", a.quiet);
    let results = experiment(&world, grid, a.seed, &|p| bar.report(p))?;
    bar.finish();
    let elapsed = t0.elapsed().as_secs_f64();
    let csv = a.out.join("rdmp_vs_dmp.csv");
    prf_files::atomic::write(&csv, goals_csv(&results))
        .with_context(|| format!("writing {}", csv.display()))?;
    let summary = a.out.join("summary.csv");
    prf_files::atomic::write(&summary, summary_csv(&results))
        .with_context(|| format!("writing {}", summary.display()))?;
    let mut written = 0;
    for r in &results {
        written += charts(r, &a.out)?;
    }
    println!(
        "RDMP vs DMP (Sec. 4.3): {} approaches, {} × {} goals at {:.0} mm spacing (±{:.0} mm around the demonstrated goal, horizontal, arm base frame), ε = 0.02 m",
        results.len(),
        grid.n,
        grid.n,
        grid.spacing() * 1e3,
        grid.half_extent * 1e3
    );
    print!("{}", summary_table(&results));
    println!(
        "{:.1} s; wrote {}, {} and {written} charts (SVG + PNG) to {}",
        elapsed,
        csv.display(),
        summary.display(),
        a.out.display()
    );
    Ok(())
}

fn ending_name(e: &Ending) -> &'static str {
    match e {
        Ending::Reached => "reached",
        Ending::Missed { .. } | Ending::MissedJoints { .. } => "missed",
        Ending::Failed(_) => "failed",
    }
}

/// One row per goal and primitive.
fn goals_csv(results: &[ApproachResult]) -> String {
    let mut s = String::from(
        "approach,dx_m,dy_m,ik_reachable,primitive,ending,risk_m,exact_risk_m,null_shift_rad,end_error,end_angle_error_rad,failure\n",
    );
    for r in results {
        for g in &r.goals {
            let mut row = |name: &str, t: &Trajectory, shift: f64| {
                let (p, ang) = match t.ending {
                    Ending::Missed { position, angle } => (position, angle),
                    Ending::MissedJoints { error } => (error, 0.0),
                    _ => (0.0, 0.0),
                };
                let why = match &t.ending {
                    Ending::Failed(w) => w.replace(',', ";"),
                    _ => String::new(),
                };
                let _ = writeln!(
                    s,
                    "{},{:.4},{:.4},{},{name},{},{:.6},{},{shift:.6},{p:.6},{ang:.6},{why}",
                    r.name,
                    g.dx,
                    g.dy,
                    g.reachable,
                    ending_name(&t.ending),
                    t.risk,
                    t.exact_risk.map_or(String::new(), |e| format!("{e:.6}"))
                );
            };
            row("rdmp", &g.rdmp, 0.0);
            if let Some((shift, t)) = &g.shifted {
                row("rdmp_shifted", t, *shift);
            }
            if let Some(d) = &g.dmp {
                row("dmp", d, 0.0);
            }
        }
    }
    s
}

fn summary_csv(results: &[ApproachResult]) -> String {
    let mut s = String::from(
        "approach,primitive,goals,ik_reachable,integrated,reached,mean_risk_m,max_risk_m,risk_0,exact_rated,exact_risk_0,share_rdmp_not_worse\n",
    );
    for r in results {
        let all = r.summaries();
        let reachable = r.goals.iter().filter(|g| g.reachable).count();
        for (name, x) in [
            ("rdmp", all.rdmp),
            ("rdmp_shifted", all.shifted),
            ("dmp", all.dmp),
        ] {
            let _ = writeln!(
                s,
                "{},{name},{},{reachable},{},{},{:.6},{:.6},{},{},{},{:.4}",
                r.name,
                x.goals,
                x.integrated,
                x.reached,
                x.mean_risk,
                x.max_risk,
                x.zero,
                x.exact_rated,
                x.exact_zero,
                r.rdmp_not_worse()
            );
        }
    }
    s
}

/// Per approach a row per primitive: reached, mean/max risk, goals at risk 0 in the field and
/// in the exact Ω+ (near the demonstrated goal), and how often the RDMP is not worse.
fn summary_table(results: &[ApproachResult]) -> String {
    let mut s = format!(
        "  {:<15} {:>9} {:<13} {:>9} {:>15} {:>8} {:>14} {:>10}\n",
        "approach",
        "IK reach",
        "primitive",
        "reached",
        "mean/max risk",
        "risk 0",
        "exact risk 0",
        "RDMP ≤ DMP"
    );
    let mut floors = String::new();
    for r in results {
        let all = r.summaries();
        let reachable = r.goals.iter().filter(|g| g.reachable).count();
        let rows = [
            ("RDMP", all.rdmp),
            ("RDMP+shift", all.shifted),
            ("DMP", all.dmp),
        ];
        for (i, (name, x)) in rows.iter().enumerate() {
            let first = i == 0;
            let _ = writeln!(
                s,
                "  {:<15} {:>9} {:<13} {:>9} {:>15} {:>8} {:>14} {:>10}",
                if first { r.name.as_str() } else { "" },
                if first {
                    format!("{reachable}/{}", x.goals)
                } else {
                    String::new()
                },
                name,
                format!("{}/{}", x.reached, x.goals),
                format!("{:.1}/{:.1} mm", x.mean_risk * 1e3, x.max_risk * 1e3),
                x.zero,
                format!("{}/{}", x.exact_zero, x.exact_rated),
                if first {
                    format!("{:.0} %", r.rdmp_not_worse() * 100.0)
                } else {
                    String::new()
                }
            );
        }
        let _ = write!(
            floors,
            "{}{}: {}/{}",
            if floors.is_empty() { "" } else { ", " },
            r.name,
            r.floor_zero(),
            r.goals.len()
        );
    }
    let _ = writeln!(
        s,
        "  goals not proven above risk 0 for every motion (the spheres rigid with the TCP end outside the exact Ω+ at the others): {floors}"
    );
    s
}

/// The charts of one approach (Fig. 3i–iv): risk maps, histograms, elbow x, workspace slice.
/// Returns how many charts were written.
fn charts(r: &ApproachResult, dir: &Path) -> Result<usize> {
    let stem = |what: &str| dir.join(format!("{}_{what}", slug(&r.name)));
    let offsets = r.grid.offsets();
    let risks = |pick: fn(&GoalOutcome) -> Option<&Trajectory>| -> Vec<Option<f64>> {
        r.goals
            .iter()
            .map(|g| {
                pick(g)
                    .filter(|t| !matches!(t.ending, Ending::Failed(_)) && g.reachable)
                    .map(|t| t.risk * 1e3)
            })
            .collect()
    };
    let rdmp = risks(|g| Some(&g.rdmp));
    let shifted = risks(|g| g.shifted.as_ref().map(|s| &s.1));
    let dmp = risks(|g| g.dmp.as_ref());
    let max = rdmp
        .iter()
        .chain(&shifted)
        .chain(&dmp)
        .flatten()
        .copied()
        .fold(0.0f64, f64::max)
        .max(1.0);
    for (name, file, values) in [
        ("RDMP", "rdmp", &rdmp),
        ("null-space-shifted RDMP", "rdmp_shifted", &shifted),
        ("DMP", "dmp", &dmp),
    ] {
        let title = format!("{}: {name} risk over new goals", r.name);
        plots::save(
            &HeatMap {
                title: &title,
                x_label: "goal Δx [m], arm base frame",
                y_label: "goal Δy [m]",
                value_label: "risk [mm]",
                xs: &offsets,
                ys: &offsets,
                values,
                max,
                marker: Some((0.0, 0.0)),
            },
            &stem(&format!("risk_{file}")),
        )?;
    }
    let samples = [
        ("RDMP", rdmp.iter().flatten().copied().collect()),
        ("RDMP+shift", shifted.iter().flatten().copied().collect()),
        ("DMP", dmp.iter().flatten().copied().collect()),
    ];
    let title = format!("{}: risk histogram over {} goals", r.name, r.goals.len());
    plots::save(
        &Histogram {
            title: &title,
            x_label: "risk [mm]",
            samples: &samples,
            bins: 20,
            max,
        },
        &stem("histogram"),
    )?;
    let model = prf_shared::robot::RobotModel::kmr_iiwa14();
    // Every DMP in one colour, every RDMP in another; the demonstration on top.
    let mut series: Vec<Series> = Vec::new();
    for (kind, colour) in [("DMP", 0), ("RDMP", 1)] {
        let traces = r.goals.iter().filter_map(|g| {
            if kind == "DMP" {
                g.dmp.as_ref()
            } else {
                Some(&g.rdmp)
            }
        });
        for (i, t) in traces.filter(|t| !t.elbow.is_empty()).enumerate() {
            series.push(Series {
                name: if i == 0 { kind.into() } else { String::new() },
                points: t.elbow.clone(),
                emphasis: false,
                colour,
            });
        }
    }
    let demo = Series {
        name: "demonstration".into(),
        points: r
            .demo
            .iter()
            .enumerate()
            .map(|(k, q)| {
                (
                    k as f64 * r.dt,
                    elbow_x(&model, &prf_shared::JointVector::from(*q)),
                )
            })
            .collect(),
        emphasis: true,
        colour: 2,
    };
    series.push(demo);
    let title = format!(
        "{}: elbow (link 4) x, demonstration and generalisations",
        r.name
    );
    plots::save(
        &LinePlot {
            title: &title,
            x_label: "t [s]",
            y_label: "elbow x [m], arm base frame",
            series: &series,
        },
        &stem("elbow"),
    )?;
    let (xs, ys, depth) = workspace_slice(r, 120);
    let goal = (r.arm_base * r.goal).translation;
    let title = format!("{}: Ω+ at the goal's height (z = {:.2} m)", r.name, goal.z);
    let depth_mm: Vec<Option<f64>> = depth.iter().map(|v| v.map(|d| d * 1e3)).collect();
    plots::save(
        &HeatMap {
            title: &title,
            x_label: "x [m], location frame",
            y_label: "y [m]",
            value_label: "depth inside Ω+ [mm]",
            xs: &xs,
            ys: &ys,
            values: &depth_mm,
            max: depth_mm.iter().flatten().copied().fold(1.0, f64::max),
            marker: Some((goal.x, goal.y)),
        },
        &stem("workspace"),
    )?;
    Ok(6)
}
