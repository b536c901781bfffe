//! `prf bench`: medians of the math core's hot paths, each with a baseline run in the same
//! process where one exists (the paper's SVD formulation of Alg. 1/2).
//!
//! Each case times batches of calls with `Instant` and reports per-call figures over many
//! batches: median, 10th and 90th percentile. Timing lives here, not in tests.

use crate::synthetic;
use anyhow::Result;
use nalgebra::{SMatrix, Vector3, Vector6};
use prf_host::stats::{percentiles, quantile};
use prf_shared::dmp::{Basis, DmpParams, Features};
use prf_shared::kinematics::quaternion::QuaternionKinematics;
use prf_shared::kinematics::{ArmKinematics, Chain};
use prf_shared::nullspace::{JacobianQr, kernel, pinv_apply};
use prf_shared::rdmp::{Rdmp, RdmpConfig, RdmpRun, integrate, null_space_coordinate};
use prf_shared::robot::RobotModel;
use prf_shared::se3::{Pose, Rot, exp, log, log_near, unwrap_near};
use prf_shared::{Jacobian, JointVector};
use std::hint::black_box;
use std::time::{Duration, Instant};

#[derive(clap::Args)]
pub struct Args {
    /// Measuring time per case, s.
    #[arg(long, default_value_t = 1.0)]
    seconds: f64,
    /// Also benchmark the runtime on this blob (from `prf learn`): load, planning of every
    /// task of the example cell, executor ticks, RAM.
    #[arg(long)]
    blob: Option<std::path::PathBuf>,
    /// Only step the bench's 2 s reach this many times (runs restarted as they finish) and
    /// print the mean time per step: a loop to profile (`perf record`, `valgrind
    /// --tool=callgrind`) or to time whole processes of two builds against each other.
    #[arg(long, value_name = "N")]
    profile_steps: Option<u64>,
}

/// Per-call statistics in nanoseconds.
struct Stats {
    median: f64,
    p10: f64,
    p90: f64,
}

/// Times `batch` calls of `f` per sample for about `seconds`; returns per-call statistics.
fn measure(seconds: f64, batch: usize, mut f: impl FnMut()) -> Stats {
    for _ in 0..batch {
        f(); // warm-up
    }
    let budget = Duration::from_secs_f64(seconds);
    let start = Instant::now();
    let mut per_call = Vec::new();
    while start.elapsed() < budget || per_call.len() < 20 {
        let t = Instant::now();
        for _ in 0..batch {
            f();
        }
        per_call.push(t.elapsed().as_nanos() as f64 / batch as f64);
    }
    per_call.sort_by(f64::total_cmp);
    let at = |q: f64| quantile(&per_call, q);
    Stats {
        median: at(0.5),
        p10: at(0.1),
        p90: at(0.9),
    }
}

/// [`measure`] of two cases in alternating batches, so that both meet the same machine load.
fn measure_pair(seconds: f64, batch: usize, a: impl FnMut(), b: impl FnMut()) -> (Stats, Stats) {
    let mut cases: [Box<dyn FnMut() + '_>; 2] = [Box::new(a), Box::new(b)];
    let [a, b] = measure_alternating(seconds, batch, &mut cases);
    (a, b)
}

/// [`measure`] of N cases in turn, batch by batch, so that all meet the same machine load.
fn measure_alternating<const N: usize>(
    seconds: f64,
    batch: usize,
    cases: &mut [Box<dyn FnMut() + '_>; N],
) -> [Stats; N] {
    let budget = Duration::from_secs_f64(seconds);
    let start = Instant::now();
    let mut times: [Vec<f64>; N] = std::array::from_fn(|_| Vec::new());
    let time = |f: &mut dyn FnMut(), out: &mut Vec<f64>| {
        let t = Instant::now();
        for _ in 0..batch {
            f();
        }
        out.push(t.elapsed().as_nanos() as f64 / batch as f64);
    };
    for f in cases.iter_mut() {
        time(f, &mut Vec::new()); // warm-up
    }
    while start.elapsed() < budget || times[0].len() < 10 {
        for (f, out) in cases.iter_mut().zip(&mut times) {
            time(f, out);
        }
    }
    times.map(|mut v| {
        v.sort_by(f64::total_cmp);
        Stats {
            median: quantile(&v, 0.5),
            p10: quantile(&v, 0.1),
            p90: quantile(&v, 0.9),
        }
    })
}

fn report(name: &str, s: &Stats, unit: &str) {
    let (k, u) = match unit {
        "µs" => (1e-3, "µs"),
        "ms" => (1e-6, "ms"),
        _ => (1.0, "ns"),
    };
    println!(
        "  {name:<44} median {:>9.3} {u}   p10 {:>9.3}   p90 {:>9.3}",
        s.median * k,
        s.p10 * k,
        s.p90 * k
    );
}

/// A case and its previous implementation (timed in alternating batches by [`measure_pair`]),
/// in ns, the ratio of their medians, and `bits`: how their results compare.
fn report_pair(
    (now_name, now): (&str, &Stats),
    (previous_name, previous): (&str, &Stats),
    bits: &str,
) {
    report(now_name, now, "ns");
    report(previous_name, previous, "ns");
    println!("  → {:.2}× faster ({bits})", previous.median / now.median);
}

/// What [`report_pair`] says of two implementations that give the same results.
const SAME_BITS: &str = "the same bits";

/// Baseline of Alg. 1/2 lines 6–10 as written: N = I − J⁺J, M = first column of U of SVD(N).
fn kernel_svd(j: &Jacobian) -> JointVector {
    let pinv = j.pseudo_inverse(1e-12).unwrap_or_else(|_| SMatrix::zeros());
    let n = SMatrix::<f64, 7, 7>::identity() - pinv * j;
    let svd = n.svd(true, false);
    let u = svd.u.unwrap();
    let i = svd.singular_values.imax();
    u.column(i).into()
}

/// The bench's RDMP: trained on the synthetic 2 s reach; its start and its goal.
fn reach_rdmp(model: &RobotModel, cfg: &RdmpConfig) -> Result<(Rdmp, JointVector, Pose)> {
    let demo = synthetic::reach(2.0, 0.01);
    let mut gamma = vec![0.0; demo.len()];
    null_space_coordinate(model, &demo, cfg.min_manipulability, &mut gamma)?;
    let rdmp = Rdmp::train(model, &demo, &gamma, 0.01, &DmpParams::default())?;
    let (first, last) = (demo[0], demo[demo.len() - 1]);
    let goal = ArmKinematics::new(model, &JointVector::from(last)).tcp;
    Ok((rdmp, JointVector::from(first), goal))
}

/// `--profile-steps N`: N steps of the reach in one loop, then the mean time per step.
fn profile_steps(n: u64) -> Result<()> {
    let (model, cfg) = (RobotModel::kmr_iiwa14(), RdmpConfig::default());
    let (rdmp, q0, goal) = reach_rdmp(&model, &cfg)?;
    let mut run = RdmpRun::new(&model, &rdmp, &q0, &goal, &cfg)?;
    let start = Instant::now();
    for _ in 0..n {
        if run.finished() {
            run = RdmpRun::new(&model, &rdmp, &q0, &goal, &cfg)?;
        }
        black_box(run.step(&model, &rdmp, &cfg)?);
    }
    let ns = start.elapsed().as_secs_f64() * 1e9 / n.max(1) as f64;
    println!("{n} RDMP steps of the 2 s reach: {ns:.1} ns per step");
    Ok(())
}

pub fn run(args: &Args) -> Result<()> {
    if let Some(n) = args.profile_steps {
        return profile_steps(n);
    }
    let secs = args.seconds.max(0.05);
    let model = RobotModel::kmr_iiwa14();
    let cfg = RdmpConfig::default();
    let configs: Vec<JointVector> = synthetic::reach(2.0, 0.01)
        .into_iter()
        .map(JointVector::from)
        .collect();
    let jacobians: Vec<Jacobian> = configs
        .iter()
        .map(|q| ArmKinematics::new(&model, q).jacobian(&model))
        .collect();
    println!(
        "prf bench — {} s per case, per-call figures (build: {})",
        secs,
        if cfg!(debug_assertions) {
            "debug, not representative"
        } else {
            "release"
        }
    );

    println!("\nkinematics");
    let mut i = 0;
    let (mut ia, mut ib) = (0, 0);
    let chain = Chain::new(&model);
    let (fk, quaternions) = measure_pair(
        secs,
        256,
        || {
            ia = (ia + 1) % configs.len();
            let k = chain.kinematics(&model, black_box(&configs[ia]));
            black_box(k.jacobian(&model));
        },
        || {
            ib = (ib + 1) % configs.len();
            let k = QuaternionKinematics::new(&model, black_box(&configs[ib]));
            black_box(k.jacobian(&model));
        },
    );
    report_pair(
        (
            "FK (all frames + TCP) + Jacobian, rotation matrices (now)",
            &fk,
        ),
        ("previous: unit quaternions", &quaternions),
        "within 1e-13, test matrix_fk_matches_quaternion_fk",
    );

    println!("\nGaussian bases φ(ζ) (Sec. 3.2), 40 bases, ζ along a 2 s motion");
    let basis = Basis::new(&DmpParams::default())?;
    let zetas: Vec<f64> = (0..2000)
        .map(|k| (-4.0 * k as f64 / 2000.0).exp())
        .collect();
    let (mut fa, mut fb) = (Features::ZERO, Features::ZERO);
    let (window, all) = measure_pair(
        secs,
        256,
        || {
            ia = (ia + 1) % zetas.len();
            basis.features_into(black_box(zetas[ia]), &mut fa);
            black_box(&fa);
        },
        || {
            ib = (ib + 1) % zetas.len();
            basis.features_testing_all(black_box(zetas[ib]), &mut fb);
            black_box(&fb);
        },
    );
    report_pair(
        ("bases in ζ's window only (now)", &window),
        ("previous: every basis tested", &all),
        SAME_BITS,
    );

    println!(
        "\nrotation error on the branch nearest the last one, log_near (the rotation DMP's error, Integrate (5))"
    );
    // A 2 s turn of 2.5 rad, each error taken against the previous one as the RDMP does.
    let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
    let errors: Vec<(Rot, Vector3<f64>)> = (1..2000)
        .map(|k| {
            let at = |k: usize| axis * (2.5 * (1.0 - k as f64 / 2000.0));
            (exp(&at(k)), at(k - 1))
        })
        .collect();
    let (shortcut, unwrapped) = measure_pair(
        secs,
        256,
        || {
            ia = (ia + 1) % errors.len();
            let (r, reference) = black_box(&errors[ia]);
            black_box(log_near(r, reference));
        },
        || {
            ib = (ib + 1) % errors.len();
            let (r, reference) = black_box(&errors[ib]);
            black_box(unwrap_near(log(r), reference));
        },
    );
    report_pair(
        ("within half a turn: no unwrapping (now)", &shortcut),
        ("previous: always unwrapped", &unwrapped),
        SAME_BITS,
    );

    println!("\nnull-space basis M(q) (Sec. 4.2.1)");
    let cof = measure(secs, 256, || {
        i = (i + 1) % jacobians.len();
        black_box(kernel(black_box(&jacobians[i])));
    });
    report("QR of Jᵀ → M(q), manipulability (ours)", &cof, "ns");
    let svd = measure(secs, 64, || {
        i = (i + 1) % jacobians.len();
        black_box(kernel_svd(black_box(&jacobians[i])));
    });
    report("baseline: N = I − J⁺J, SVD(N) (Alg. 1/2)", &svd, "ns");
    println!(
        "  → {:.1}× faster than the SVD baseline",
        svd.median / cof.median
    );

    println!("\nRDMP step's QR: M(q) and J⁺V from one factorisation");
    let v = Vector6::new(0.1, -0.2, 0.05, 0.3, 0.0, -0.1);
    let (now, looped) = measure_pair(
        secs,
        256,
        || {
            ia = (ia + 1) % jacobians.len();
            black_box(JacobianQr::new(black_box(&jacobians[ia])).kernel_and_pinv(&v));
        },
        || {
            ib = (ib + 1) % jacobians.len();
            let qr = JacobianQr::new_looped(black_box(&jacobians[ib]));
            black_box((qr.kernel(), qr.pinv_apply(&v)));
        },
    );
    report_pair(
        ("unrolled QR, pairwise sums, Q applied to both (now)", &now),
        ("previous: generic loops, Q applied twice", &looped),
        "within 10 ε·cond(J), test the_step_qr_agrees_with_the_previous_one",
    );

    println!("\npseudo-inverse solve J⁺V");
    let qr = measure(secs, 256, || {
        i = (i + 1) % jacobians.len();
        black_box(pinv_apply(black_box(&jacobians[i]), &v));
    });
    report("QR of Jᵀ → J⁺V = Q[R⁻ᵀV; 0] (ours)", &qr, "ns");
    let svdp = measure(secs, 64, || {
        i = (i + 1) % jacobians.len();
        black_box(jacobians[i].pseudo_inverse(1e-12).map(|p| p * v).ok());
    });
    report("baseline: SVD pseudo-inverse", &svdp, "ns");
    println!("  → {:.1}× faster", svdp.median / qr.median);

    println!("\nRDMP (Alg. 2), 2 s reach, Δt = 1 ms");
    let (rdmp, q0, goal) = reach_rdmp(&model, &cfg)?;
    let fresh = || RdmpRun::new(&model, &rdmp, &q0, &goal, &cfg).expect("start");
    let mut run = fresh();
    let step = measure(secs, 100, || {
        if run.finished() {
            run = fresh();
        }
        black_box(run.step(&model, &rdmp, &cfg).expect("step"));
    });
    report(
        "one RDMP step (FK, J, one QR → M and J⁺, 3 DMPs)",
        &step,
        "ns",
    );
    let whole = measure(secs, 1, || {
        black_box(integrate(&model, &rdmp, &q0, &goal, &cfg, |_| {}).expect("integrate"));
    });
    report("whole integration, 2000 steps", &whole, "µs");
    println!(
        "  → {:.2}% of a 1 ms tick per step; goal ≤ 400 ns per step: {}",
        step.median / 1e4,
        if step.median <= 400.0 {
            "met"
        } else {
            "NOT met"
        }
    );
    println!(
        "\nstatic memory: trained RDMP {} B, RdmpRun (per-tick state) {} B, RobotModel {} B",
        std::mem::size_of::<Rdmp>(),
        std::mem::size_of::<RdmpRun>(),
        std::mem::size_of::<RobotModel>()
    );
    match &args.blob {
        Some(path) => runtime(path, secs),
        None => {
            println!("\n(pass --blob cell.blob for the runtime figures)");
            Ok(())
        }
    }
}

/// The runtime on a blob: load, all tasks of the example cell, executor ticks, RAM.
fn runtime(path: &std::path::Path, secs: f64) -> Result<()> {
    use prf_host::ideal::IdealCell;
    use prf_runtime::Runtime;
    use prf_runtime::executor::{Executor, ExecutorConfig, Mode};
    use prf_runtime::plan::{Planner, plan};
    use prf_runtime::recall::HOST_SLOTS;
    use prf_runtime::reverse::Reversal;
    use prf_runtime::skill_plan::PttSides;
    use prf_shared::field::Lookups;
    use prf_sim::tasks::world_tasks;
    use prf_sim::world::World;

    let bytes = crate::cli::args::read_blob(path)?;
    println!(
        "\nruntime on {} ({} KiB)",
        path.display(),
        bytes.len() / 1024
    );
    let load = measure(secs, 1, || {
        black_box(Runtime::load(black_box(&bytes)).is_ok());
    });
    report(
        "Runtime::load (validate header, CRC, every record)",
        &load,
        "µs",
    );
    let rt = crate::cli::args::runtime(&bytes, path, Default::default())?;
    let tasks = world_tasks(&World::example());
    let (mut integrations, mut grid, mut steps, mut feasible) = (0u64, 0u64, 0u64, 0);
    let (mut recalled, mut alone) = (0u64, 0u64);
    let mut slots = vec![None; HOST_SLOTS];
    let mut planner = Planner::new(&rt, &mut slots);
    for ft in &tasks {
        if let Ok(p) = planner.plan(&ft.task()) {
            integrations += p.skills.stats.integrations as u64;
            recalled += p.skills.stats.recalled as u64;
            grid += p.skills.stats.grid_integrations;
            steps += p.skills.stats.steps;
            feasible += p.skills.feasible as usize;
        }
        if let Ok(p) = plan(&rt, &ft.task()) {
            alone += p.skills.stats.integrations as u64;
        }
    }
    let with = |lookups| {
        let config = prf_runtime::RuntimeConfig {
            lookups,
            ..Default::default()
        };
        crate::cli::args::runtime(&bytes, path, config)
    };
    let (anchored_rt, full_rt) = (with(Lookups::Anchored)?, with(Lookups::Full)?);
    let mut plan_all = |rt: &Runtime<'_>| {
        let mut planner = Planner::new(rt, &mut slots);
        for ft in &tasks {
            black_box(planner.plan(&ft.task()).is_ok());
        }
    };
    let plan_each = |rt: &Runtime<'_>| {
        for ft in &tasks {
            black_box(plan(rt, &ft.task()).is_ok());
        }
    };
    let [all, each, anchored, full] = measure_alternating(
        secs.max(2.0) * 4.0,
        1,
        &mut [
            Box::new(|| plan_all(&rt)),
            Box::new(|| plan_each(&rt)),
            Box::new(|| plan_each(&anchored_rt)),
            Box::new(|| plan_each(&full_rt)),
        ],
    );
    report(
        &format!("plan all {} tasks (one core, one Planner)", tasks.len()),
        &all,
        "ms",
    );
    report("previous: each task planned on its own", &each, "ms");
    report(
        "baseline: on its own, anchored lookups, every sphere placed",
        &anchored,
        "ms",
    );
    report(
        "baseline: on its own, every sphere reads the field",
        &full,
        "ms",
    );
    println!(
        "  → {:.2}× faster than each task on its own, {:.2}× than the anchored lookups, {:.2}× than full lookups (the same plans)",
        each.median / all.median,
        anchored.median / all.median,
        full.median / all.median
    );
    println!(
        "  → {feasible}/{} feasible; {integrations} RDMP integrations ({steps} steps; {recalled} candidates recalled, {alone} integrations each on its own) against the paper's grid of {grid}: {:.0}× fewer; goal ≤ 60 ms: {}",
        tasks.len(),
        grid as f64 / integrations.max(1) as f64,
        if all.median <= 60e6 { "met" } else { "NOT met" }
    );
    bench_decide(&bytes, path, secs)?;
    // Executor steps on the program of task 3 (Part1 CNC1 → Table1, the firmware's reference
    // task) against an ideal cell, each step timed.
    let ft = &tasks[2];
    let p = plan(&rt, &ft.task()).map_err(|e| anyhow::anyhow!("{e}"))?;
    let program = p.program.ok_or_else(|| anyhow::anyhow!("no program"))?;
    let mut reversal = Box::new(Reversal::new());
    let mut ex = Executor::new(
        &rt,
        program,
        &ft.home,
        ExecutorConfig::default(),
        &mut reversal,
    );
    let mut cell = IdealCell::new(rt.model.home, &ft.home, 1e-3);
    let (mut arm, mut other) = (Vec::new(), Vec::new());
    let mut now = embassy_time::Instant::from_ticks(0);
    // Each drive step timed: the executor tick and the ideal cell's hand-off.
    loop {
        let t = Instant::now();
        let Ok(sp) = ex.step(now, black_box(&mut cell));
        let ns = t.elapsed().as_nanos() as f64;
        if sp.mode == Mode::Arm {
            arm.push(ns)
        } else {
            other.push(ns)
        }
        if sp.is_final() {
            break;
        }
        now += embassy_time::Duration::from_millis(1);
    }
    for (name, mut v) in [
        ("executor step, arm segments", arm),
        ("executor step, waiting segments", other),
    ] {
        let [p50, p99, _, max] = percentiles(&mut v);
        println!(
            "  {name:<44} median {:>9.3} µs   p99 {:>9.3}   max {:>9.3}   ({} ticks)",
            p50 * 1e-3,
            p99 * 1e-3,
            max * 1e-3,
            v.len()
        );
    }
    println!(
        "  (each step's time includes one pair of clock reads: median {:.3} µs alone)",
        clock_reads_ns() * 1e-3
    );
    println!(
        "\nruntime RAM: Runtime {} B, Executor {} B + reversal memory {} B, planner sides {} B (stack, while planning), a Planner's recall {} B per evaluation kept ({} slots on the host, heap)",
        std::mem::size_of::<Runtime>(),
        std::mem::size_of::<Executor>(),
        std::mem::size_of::<Reversal>(),
        std::mem::size_of::<PttSides>(),
        std::mem::size_of::<Option<prf_runtime::recall::Kept>>(),
        HOST_SLOTS
    );
    Ok(())
}

/// The median time of an empty region timed as the executor's steps are (100,000 of them), ns.
fn clock_reads_ns() -> f64 {
    let mut v: Vec<f64> = (0..100_000)
        .map(|_| {
            let t = Instant::now();
            black_box(());
            t.elapsed().as_nanos() as f64
        })
        .collect();
    percentiles(&mut v)[0]
}

/// Proving a task risky: Part1 CNC1 → Table1 with the part moved (−15, −10) mm at the CNCs
/// (no risk-0 plan), searched by each [`Search`](prf_runtime::skill_plan::Search); the verdict
/// alone is timed against the optimum search (the baseline).
fn bench_decide(bytes: &[u8], path: &std::path::Path, secs: f64) -> Result<()> {
    use prf_runtime::Runtime;
    use prf_runtime::plan::plan;
    use prf_runtime::skill_plan::Search;
    use prf_sim::world::World;
    let world = prf_offline::envelope::shifted(&World::example(), "CNC", -0.015, -0.01, 0.0);
    let ft = prf_sim::tasks::FloorTask::new(&world, "Part1", "CNC1", "Table1")?;
    let task = ft.task();
    let with = |search| {
        let config = prf_runtime::RuntimeConfig {
            search,
            ..Default::default()
        };
        crate::cli::args::runtime(bytes, path, config)
    };
    let searches = [Search::Decide, Search::Optimum, Search::DecideFirst];
    let rts: Vec<Runtime<'_>> = searches.map(with).into_iter().collect::<Result<_>>()?;
    for (rt, search) in rts.iter().zip(searches) {
        let p = plan(rt, &task).map_err(|e| anyhow::anyhow!("{e}"))?.skills;
        let j = if p.j.is_finite() {
            format!("{:.2} mm", p.j * 1e3)
        } else {
            "not searched".into()
        };
        println!(
            "  {search:?}: feasible {}, decided {}, J* {j}, {} integrations, {} steps",
            p.feasible, p.decided, p.stats.integrations, p.stats.steps
        );
    }
    let one = |rt: &Runtime<'_>| black_box(plan(rt, &task).is_ok());
    let [decide, optimum] = measure_alternating(
        secs,
        1,
        &mut [
            Box::new(|| {
                one(&rts[0]);
            }),
            Box::new(|| {
                one(&rts[1]);
            }),
        ],
    );
    let label = ft.label();
    report(
        &format!("prove {label} risky, part moved (−15, −10) mm"),
        &decide,
        "ms",
    );
    report("baseline: the optimum search alone", &optimum, "ms");
    println!(
        "  → the verdict {:.2}× faster than the baseline (decide-first adds the optimum search to it)",
        optimum.median / decide.median
    );
    Ok(())
}
