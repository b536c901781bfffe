//! `prf experiment monte-carlo`: the tables, CSVs and charts of Sec. 6.3 (Fig. 5) and the two
//! cases of Sec. 7.1.

use super::MonteCarloArgs;
use crate::cli::generate::drawn;
use crate::cli::progress::Bar;
use anyhow::{Context, Result, bail};
use prf_files::dataset::Dataset;
use prf_offline::experiment::monte_carlo::{Counts, Episode, Setup, run as run_episodes};
use prf_offline::plots::{self, Band, BandPlot};
use prf_shared::robot::RobotModel;
use prf_sim::demogen::generate;
use std::fmt::Write as _;
use std::time::Instant;

/// Reads one count of a step.
type Count = fn(&Counts) -> usize;

/// The counts of Fig. 5 by name.
const KINDS: [(&str, Count); 3] = [
    ("symbolically feasible afforded tasks", |c| {
        c.symbolic_afforded
    }),
    ("physically feasible afforded tasks", |c| {
        c.physical_afforded
    }),
    ("physically feasible tasks", |c| c.physical_tasks),
];

pub fn run(a: &MonteCarloArgs) -> Result<()> {
    let world = a.world.load()?;
    // The paper's figures are of its example cell; other worlds are compared with nothing.
    let example = a
        .world
        .world
        .as_ref()
        .is_none_or(|w| w.as_os_str() == "example");
    let model = RobotModel::kmr_iiwa14();
    let dataset = match &a.dataset {
        Some(dir) => Dataset::read(dir, &model)
            .with_context(|| format!("reading the dataset {}", dir.display()))?,
        None => {
            // The example: each afforded task once; another world: an archive's draw.
            let selection = match example {
                true => world.afforded_tasks(),
                false => drawn(&world.afforded_tasks(), a.programs, 1),
            };
            let bar = Bar::new("generating", "demonstrations", a.quiet);
            let ds = generate(&world, &selection, 1, 100.0, !example, &|p| bar.report(p))?;
            bar.finish();
            ds
        }
    };
    let n = dataset.demonstrations.len();
    if n == 0 {
        bail!("the dataset has no demonstrations");
    }
    let steps = a.steps.unwrap_or(n).min(n);
    if a.episodes == 0 || steps == 0 {
        bail!("--episodes and --steps must be at least 1");
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let t0 = Instant::now();
    let setup = Setup::new(world, dataset)?;
    let t_setup = t0.elapsed().as_secs_f64();
    let bar = Bar::new("episodes", "episodes", a.quiet);
    let t1 = Instant::now();
    let episodes = run_episodes(&setup, a.episodes, steps, a.seed, &|p| bar.report(p))?;
    bar.finish();
    let t_episodes = t1.elapsed().as_secs_f64();
    let tasks = setup.tasks().len();
    let afforded = setup.world.afforded_tasks().len();

    let csv = a.out.join("episodes.csv");
    prf_files::atomic::write(&csv, episodes_csv(&setup, &episodes))
        .with_context(|| format!("writing {}", csv.display()))?;
    let per_step = a.out.join("steps.csv");
    prf_files::atomic::write(&per_step, steps_csv(&episodes, steps))
        .with_context(|| format!("writing {}", per_step.display()))?;
    charts(&episodes, steps, afforded, tasks, &a.out)?;

    println!(
        "Monte Carlo (Sec. 6.3): {} episodes × {steps} steps of {n} demonstrations, {tasks} tasks, {afforded} afforded tasks",
        a.episodes
    );
    print!("{}", until_table(&episodes, afforded, tasks, example));
    println!("Sec. 7.1, two demonstrations learned from scratch:");
    for (name, pair) in setup.special_cases() {
        match pair {
            Some(p) => {
                let s = setup.from_scratch(&p)?;
                let feasible: Vec<String> = setup
                    .tasks()
                    .iter()
                    .zip(&s.feasible)
                    .filter(|(_, f)| **f)
                    .map(|(t, _)| t.label())
                    .collect();
                // Named one by one only while the list stays readable (the example's 18).
                let which = match feasible.len() {
                    n if n == tasks => "all".to_string(),
                    n if n > 18 => format!("{n} tasks"),
                    _ => feasible.join(", "),
                };
                println!(
                    "  {name}: {} of {tasks} tasks physically feasible ({which}); {} of {afforded} afforded tasks",
                    s.counts.physical_tasks, s.counts.physical_afforded
                );
            }
            None => println!("  {name}: not in this dataset"),
        }
    }
    check_from_scratch(&setup, &episodes[0], &a.check_steps)?;
    let all: Vec<_> = episodes.iter().flat_map(|e| &e.steps).collect();
    let mean = |f: fn(&&prf_offline::experiment::monte_carlo::Step) -> f64| {
        all.iter().map(f).sum::<f64>() / all.len() as f64
    };
    println!(
        "time: {:.1} s wall for {} steps ({:.1} s setup: every demonstration's lessons), per step {:.1} ms learn + compile, {:.1} ms counting, {:.1} RDMP integrations",
        t_episodes + t_setup,
        all.len(),
        t_setup,
        mean(|s| s.learn_s) * 1e3,
        mean(|s| s.count_s) * 1e3,
        mean(|s| s.integrations as f64)
    );
    println!(
        "wrote {}, {} and the charts afforded.svg/.png, tasks.svg/.png to {}",
        csv.display(),
        per_step.display(),
        a.out.display()
    );
    Ok(())
}

/// Recounts the given steps of `episode` from scratch, fails if any count differs, and prints
/// both times.
fn check_from_scratch(setup: &Setup, episode: &Episode, at: &[usize]) -> Result<()> {
    let order: Vec<usize> = episode.steps.iter().map(|s| s.demonstration).collect();
    for &j in at.iter().filter(|&&j| j >= 1 && j <= order.len()) {
        let s = setup.from_scratch(&order[..j])?;
        let inc = &episode.steps[j - 1];
        if s.counts != inc.counts {
            bail!(
                "episode seed {}, step {j}: incremental counts {:?} differ from a from-scratch learn + plan {:?}",
                episode.seed,
                inc.counts,
                s.counts
            );
        }
        println!(
            "  step {j:>2} of the first episode from scratch: same counts; {:.0} ms (learn + compile + count) against {:.0} ms incremental",
            s.seconds * 1e3,
            (inc.learn_s + inc.count_s) * 1e3
        );
    }
    Ok(())
}

fn episodes_csv(setup: &Setup, episodes: &[Episode]) -> String {
    let mut s = String::from(
        "episode,seed,step,demonstration,symbolic_afforded,physical_afforded,physical_tasks,integrations,learn_ms,count_ms\n",
    );
    for (e, ep) in episodes.iter().enumerate() {
        for (j, st) in ep.steps.iter().enumerate() {
            let _ = writeln!(
                s,
                "{e},{},{},{},{},{},{},{},{:.2},{:.2}",
                ep.seed,
                j + 1,
                setup.dataset.demonstrations[st.demonstration].id,
                st.counts.symbolic_afforded,
                st.counts.physical_afforded,
                st.counts.physical_tasks,
                st.integrations,
                st.learn_s * 1e3,
                st.count_s * 1e3
            );
        }
    }
    s
}

/// Per step and count: mean, min and max over the episodes.
fn statistics(episodes: &[Episode], steps: usize, f: Count) -> Vec<(f64, f64, f64)> {
    (0..steps)
        .map(|j| {
            let v: Vec<f64> = episodes
                .iter()
                .filter_map(|e| e.steps.get(j))
                .map(|s| f(&s.counts) as f64)
                .collect();
            (
                v.iter().sum::<f64>() / v.len().max(1) as f64,
                v.iter().copied().fold(f64::INFINITY, f64::min),
                v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            )
        })
        .collect()
}

fn steps_csv(episodes: &[Episode], steps: usize) -> String {
    let mut s = String::from("step");
    for name in ["symbolic_afforded", "physical_afforded", "physical_tasks"] {
        let _ = write!(s, ",{name}_mean,{name}_min,{name}_max");
    }
    s.push('\n');
    let stats: Vec<_> = KINDS
        .iter()
        .map(|(_, f)| statistics(episodes, steps, *f))
        .collect();
    for j in 0..steps {
        let _ = write!(s, "{}", j + 1);
        for k in &stats {
            let _ = write!(s, ",{:.3},{},{}", k[j].0, k[j].1, k[j].2);
        }
        s.push('\n');
    }
    s
}

/// The first step at which `f` reaches `total`, per episode (None: never).
fn first_step(e: &Episode, total: usize, f: Count) -> Option<usize> {
    e.steps
        .iter()
        .position(|s| f(&s.counts) >= total)
        .map(|j| j + 1)
}

/// Steps until every (afforded) task is feasible, against the paper's statements.
/// Steps until each count is complete, beside the paper's figures when `paper` (the example).
fn until_table(episodes: &[Episode], afforded: usize, tasks: usize, paper: bool) -> String {
    let range = |f: Count, total: usize| {
        let v: Vec<Option<usize>> = episodes.iter().map(|e| first_step(e, total, f)).collect();
        let reached: Vec<usize> = v.iter().flatten().copied().collect();
        if reached.is_empty() {
            return "never".to_string();
        }
        let (lo, hi) = (
            reached.iter().min().copied().unwrap_or(0),
            reached.iter().max().copied().unwrap_or(0),
        );
        let mean = reached.iter().sum::<usize>() as f64 / reached.len() as f64;
        let never = v.len() - reached.len();
        let tail = if never > 0 {
            format!(", {never} episodes never")
        } else {
            String::new()
        };
        format!("{lo} to {hi} (mean {mean:.1}){tail}")
    };
    let mut s = format!(
        "  {:<58} {:<28} {}\n",
        "steps until …", "paper (Sec. 6.3.2)", "here"
    );
    let rows = [
        (
            format!("all {tasks} tasks are physically feasible"),
            "2 to 7",
            range(KINDS[2].1, tasks),
        ),
        (
            format!("all {afforded} afforded tasks are physically feasible"),
            "under 32 (half the data), worst case",
            range(KINDS[1].1, afforded),
        ),
        (
            format!("all {afforded} afforded tasks are symbolically feasible"),
            "far earlier than physically",
            range(KINDS[0].1, afforded),
        ),
    ];
    for (what, figure, here) in rows {
        let figure = if paper { figure } else { "—" };
        let _ = writeln!(s, "  {what:<58} {figure:<28} {here}");
    }
    s
}

/// Fig. 5a (afforded tasks) and 5b (tasks): mean line over the min–max band per step.
fn charts(
    episodes: &[Episode],
    steps: usize,
    afforded: usize,
    tasks: usize,
    dir: &std::path::Path,
) -> Result<()> {
    let band = |k: usize| Band {
        name: KINDS[k].0.to_string(),
        points: statistics(episodes, steps, KINDS[k].1)
            .into_iter()
            .enumerate()
            .map(|(j, (mean, lo, hi))| ((j + 1) as f64, mean, lo, hi))
            .collect(),
    };
    let title = format!("Afforded tasks feasible over {} episodes", episodes.len());
    plots::save(
        &BandPlot {
            title: &title,
            x_label: "demonstrations learned",
            y_label: "afforded tasks",
            bands: &[band(0), band(1)],
            references: &[(afforded as f64, format!("all {afforded}"))],
        },
        &dir.join("afforded"),
    )?;
    let title = format!("Tasks physically feasible over {} episodes", episodes.len());
    plots::save(
        &BandPlot {
            title: &title,
            x_label: "demonstrations learned",
            y_label: "tasks",
            bands: &[band(2)],
            references: &[(tasks as f64, format!("all {tasks}"))],
        },
        &dir.join("tasks"),
    )?;
    Ok(())
}
