//! `prf experiment monte-carlo` (Sec. 6.3) and incremental learning, against independent
//! references: batch learning of the same demonstrations (the blob's bytes), a from-scratch
//! count at every step, the runtime's own planner (`plan`) for task feasibility, and a
//! brute-force rating of every candidate for afforded-task feasibility.

mod common;

use prf_offline::experiment::monte_carlo::{Counts, Setup};
use prf_runtime::Runtime;
use prf_runtime::plan::plan;
use prf_runtime::skill_plan::{Evaluation, PttClasses, PttSides, evaluate_arm_motion};
use prf_sim::demogen::generate_dataset;
use prf_sim::world::World;
use std::sync::OnceLock;

/// Afforded tasks of the example cell (see `prf gen --list`): the two pairs of Sec. 7.1
/// (0 + 32: Part1 and Part2 CNC → CNC; 8 + 54: Part1 CNC → Printer, Part2 Printer → Table)
/// and others over every location type, approach and grasp.
const SELECTION: [usize; 12] = [0, 32, 8, 54, 5, 13, 18, 27, 41, 47, 60, 63];

/// The experiment on those demonstrations (generated once per test binary).
fn setup() -> &'static Setup {
    static SETUP: OnceLock<Setup> = OnceLock::new();
    SETUP.get_or_init(|| {
        let world = World::example();
        let all = world.afforded_tasks();
        let selection: Vec<_> = SELECTION.iter().map(|&i| all[i]).collect();
        let dataset = generate_dataset(&world, &selection, 1, 100.0, &|_| {}).unwrap();
        Setup::new(world, dataset).unwrap()
    })
}

#[test]
fn incremental_learning_gives_the_blob_batch_learning_gives() {
    let s = setup();
    for seed in [3, 4] {
        let order = s.order(seed);
        for j in [1, 5, order.len()] {
            let batch = s.from_scratch(&order[..j]).unwrap().blob;
            let incremental = s.incremental_blob(&order[..j]).unwrap();
            assert!(
                batch == incremental,
                "seed {seed}, {j} demonstrations: the blobs differ ({} and {} bytes)",
                batch.len(),
                incremental.len()
            );
        }
    }
}

/// Every stance and grasp learned, as bits, sorted.
fn affordance_bits(k: &prf_learn::Knowledge) -> Vec<[u64; 7]> {
    let sets = k
        .location_types
        .iter()
        .map(|t| &t.stances)
        .chain(k.part_types.iter().map(|p| &p.grasps));
    let mut out: Vec<[u64; 7]> = sets
        .flat_map(|a| a.poses.iter())
        .map(|p| prf_shared::se3::pose_to_array(p).map(f64::to_bits))
        .collect();
    out.sort_unstable();
    out
}

/// Programs that reach the same stance or grasp differ by log rounding; the learned poses
/// (quantized) do not, so an episode's candidates are the same bits whatever the order — what
/// lets the episodes share them.
#[test]
fn learned_stances_and_grasps_are_the_same_bits_in_every_order() {
    let s = setup();
    let learn = |order: &[usize]| {
        let ds = prf_files::dataset::Dataset {
            demonstrations: order
                .iter()
                .map(|&i| s.dataset.demonstrations[i].clone())
                .collect(),
            ..s.dataset.clone()
        };
        prf_learn::learn(&ds, &s.model, &s.config, &|_| {}).unwrap()
    };
    let reference = affordance_bits(&learn(&s.order(0)));
    for seed in [1, 2, 3] {
        assert_eq!(
            affordance_bits(&learn(&s.order(seed))),
            reference,
            "order {seed}"
        );
    }
}

/// Per task: whether the runtime's planner finds J* ≤ the threshold on `blob`.
fn planner_feasible(s: &Setup, blob: &[u8]) -> Vec<bool> {
    let rt = Runtime::load(blob).unwrap();
    s.tasks()
        .iter()
        .map(|t| plan(&rt, &t.task()).is_ok_and(|p| p.skills.feasible))
        .collect()
}

/// Afforded tasks feasible on `blob`, by rating every candidate of every side in full.
fn brute_force_afforded(blob: &[u8]) -> (usize, usize) {
    let s = setup();
    let rt = Runtime::load(blob).unwrap();
    let classes = PttClasses::of(&rt).unwrap();
    let (mut symbolic, mut physical) = (0, 0);
    for t in s.tasks() {
        let task = t.task();
        let Ok(Ok(resolved)) = task.resolve(&rt) else {
            continue;
        };
        let Ok(sides) = PttSides::new(&rt, &task, &resolved, &classes) else {
            continue;
        };
        let feasible = |side: &prf_runtime::skill_plan::Side<'_>, st: usize, g: usize| {
            let mut min = f64::INFINITY;
            side.candidates(&rt, g, |stance, k| {
                if stance as usize == st
                    && let Ok(Some(rdmp)) = rt.skill_rdmp(k as usize)
                    && let Evaluation::Risk { risk, .. } = evaluate_arm_motion(
                        &rt,
                        &rdmp,
                        side.goal(st, g).unwrap(),
                        &side.field,
                        &side.arm_bases[st],
                        f64::INFINITY,
                        usize::MAX,
                    )
                {
                    min = min.min(risk);
                }
                true
            })
            .unwrap();
            min <= rt.config.risk_threshold
        };
        for g in 0..sides.grasps {
            for s1 in 0..sides.pick.arm_bases.len() {
                for s2 in 0..sides.place.arm_bases.len() {
                    symbolic += 1;
                    if feasible(&sides.pick, s1, g) && feasible(&sides.place, s2, g) {
                        physical += 1;
                    }
                }
            }
        }
    }
    (symbolic, physical)
}

#[test]
fn counts_along_episodes_equal_from_scratch_learning_and_planning_at_every_step() {
    let s = setup();
    for seed in [11, 12] {
        let order = s.order(seed);
        let episode = s.episode(seed, &order, order.len()).unwrap();
        let mut last = Counts::default();
        for (j, step) in episode.steps.iter().enumerate() {
            let scratch = s.from_scratch(&order[..=j]).unwrap();
            assert_eq!(step.counts, scratch.counts, "seed {seed}, step {}", j + 1);
            // Tasks: the planner's own verdict.
            let planned = planner_feasible(s, &scratch.blob);
            assert_eq!(scratch.feasible, planned, "seed {seed}, step {}", j + 1);
            assert_eq!(
                step.counts.physical_tasks,
                planned.iter().filter(|f| **f).count()
            );
            // The counts never fall as demonstrations are added (Sec. 6.3: workspaces and
            // skill sets only grow).
            assert!(
                step.counts.symbolic_afforded >= last.symbolic_afforded
                    && step.counts.physical_afforded >= last.physical_afforded
                    && step.counts.physical_tasks >= last.physical_tasks,
                "seed {seed}, step {}: {:?} after {last:?}",
                j + 1,
                step.counts
            );
            assert!(step.counts.physical_afforded <= step.counts.symbolic_afforded);
            assert!(step.counts.symbolic_afforded <= 64 && step.counts.physical_tasks <= 18);
            last = step.counts;
        }
    }
}

#[test]
fn afforded_task_counts_equal_a_brute_force_rating_of_every_candidate() {
    let s = setup();
    let order = s.order(21);
    for j in [3, 7] {
        let scratch = s.from_scratch(&order[..j]).unwrap();
        let (symbolic, physical) = brute_force_afforded(&scratch.blob);
        assert_eq!(scratch.counts.symbolic_afforded, symbolic, "step {j}");
        assert_eq!(scratch.counts.physical_afforded, physical, "step {j}");
    }
}

#[test]
fn two_similar_programs_solve_only_cnc_tasks_and_two_diverse_ones_all_18() {
    let s = setup();
    let [(_, similar), (_, diverse)] = s.special_cases();
    let similar = s.from_scratch(&similar.unwrap()).unwrap();
    for (t, feasible) in s.tasks().iter().zip(&similar.feasible) {
        let cnc_only = t.from.1 == "CNC" && t.to.1 == "CNC";
        assert_eq!(*feasible, cnc_only, "{}", t.label());
    }
    assert_eq!(similar.counts.physical_tasks, 2);
    let diverse = s.from_scratch(&diverse.unwrap()).unwrap();
    assert_eq!(diverse.counts.physical_tasks, 18);
    assert!(diverse.feasible.iter().all(|f| *f));
}

#[test]
fn the_command_writes_fig_5_and_csvs_that_hold_its_counts() {
    let tmp = common::TempDir::new("monte-carlo");
    let dir = tmp.path();
    let stdout = common::run_prf(
        &[
            "experiment",
            "monte-carlo",
            "--episodes",
            "2",
            "--steps",
            "5",
            "--check-steps",
            "2,5",
            "-q",
        ],
        dir,
    );
    assert!(stdout.contains("step  5 of the first episode from scratch: same counts"));
    common::assert_charts(dir, &["afforded".into(), "tasks".into()]);
    let episodes = std::fs::read_to_string(dir.join("episodes.csv")).unwrap();
    let rows: Vec<Vec<&str>> = episodes
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 10);
    // steps.csv: per step the mean, min and max of each count over the episodes.
    let steps = std::fs::read_to_string(dir.join("steps.csv")).unwrap();
    for line in steps.lines().skip(1) {
        let f: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
        let at: Vec<&Vec<&str>> = rows
            .iter()
            .filter(|r| r[2].parse::<f64>().unwrap() == f[0])
            .collect();
        for (c, col) in [4, 5, 6].into_iter().enumerate() {
            let v: Vec<f64> = at.iter().map(|r| r[col].parse().unwrap()).collect();
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            assert!((f[1 + 3 * c] - mean).abs() < 1e-3, "{line}");
            assert_eq!(
                f[2 + 3 * c],
                v.iter().copied().fold(f64::INFINITY, f64::min)
            );
            assert_eq!(
                f[3 + 3 * c],
                v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            );
        }
    }
}

/// `prf learn --max-blob-bytes` ([`prf_offline::budget::fit`]) on the 12 demonstrations:
/// a blob that fits is the unbudgeted one, byte for byte; tighter budgets (one the
/// witnesses' skills meet, one that takes a smaller margin) give a blob within them whose
/// lost tasks are
/// exactly those the runtime's planner no longer finds feasible, and whose risk-0 programs
/// keep r from the true cell; a budget nothing fits is an error that says how small it got.
#[test]
fn a_budgeted_blob_fits_and_makes_feasible_what_its_report_says() {
    use prf_offline::budget::fit;
    use prf_sim::world::geometry::Cell;
    let s = setup();
    let learn = || {
        let mut learner = prf_learn::learn::Learner::new(&s.dataset, &s.model, &s.config).unwrap();
        let k =
            prf_learn::learn::learn_into(&mut learner, &s.dataset.demonstrations, &|_| {}).unwrap();
        (learner, k)
    };
    let (mut learner, k) = learn();
    let full = prf_learn::compile(&k).unwrap();
    let fitted = fit(&mut learner, k, &s.world, full.len(), &|_| {}, &|_| {}).unwrap();
    assert!(fitted.blob == full && fitted.rungs.is_empty());
    let reference = s
        .from_scratch(&(0..s.len()).collect::<Vec<_>>())
        .unwrap()
        .counts;
    let before = planner_feasible(s, &full);
    let cell = Cell::new(&s.world, &s.model);
    let mut margins = Vec::new();
    // A byte less than the blob: the witnesses' skills fit at the learned margins; then a
    // byte less than they take there: a workspace must go down the ladder.
    let mut budget = full.len() - 1;
    for _ in 0..2 {
        let (mut learner, k) = learn();
        let f = fit(&mut learner, k, &s.world, budget, &|_| {}, &|_| {}).unwrap();
        let rung = f.rungs.last().expect("a rung");
        assert!(f.blob.len() <= budget, "{} > {budget} bytes", f.blob.len());
        assert_eq!(f.reference, reference);
        let learned = s.config.workspace.certify_margin;
        if rung.margins.iter().all(|(_, m)| *m == learned) {
            // The learned fields, the witnesses' skills: what was feasible stays so.
            assert_eq!(rung.counts, reference, "budget {budget}");
        }
        let after = planner_feasible(s, &f.blob);
        let lost: Vec<String> = s
            .tasks()
            .iter()
            .zip(before.iter().zip(&after))
            .filter(|(_, (was, is))| **was && !**is)
            .map(|(t, _)| t.label())
            .collect();
        assert_eq!(f.lost, lost, "budget {budget}");
        // Risk 0 on recertified workspaces, against the true cell (the first blob's fields
        // are the learned ones).
        let rt = Runtime::load(&f.blob).unwrap();
        for t in s.tasks().iter().filter(|_| !margins.is_empty()) {
            let p = plan(&rt, &t.task()).unwrap();
            if p.skills.feasible {
                let (worst, contact) =
                    prf_offline::ground_truth::arm_clearance(&rt, &cell, t, &p).unwrap();
                let r = s.world.clearance.acceptable;
                assert!(
                    worst >= r,
                    "{}: {:.1} mm from {contact}",
                    t.label(),
                    worst * 1e3
                );
            }
        }
        margins.push(rung.margins.clone());
        budget = f.rungs[0].witnesses - 1;
    }
    // The first fitted at the learned margins, the second needed a smaller one somewhere.
    let learned = s.config.workspace.certify_margin;
    assert!(margins[0].iter().all(|(_, m)| *m == learned), "{margins:?}");
    assert!(margins[1].iter().any(|(_, m)| *m < learned), "{margins:?}");
    let (mut learner, k) = learn();
    let error = fit(&mut learner, k, &s.world, 10_000, &|_| {}, &|_| {})
        .err()
        .expect("10 kB is too small");
    assert!(
        error.to_string().contains("does not fit 10000 bytes"),
        "{error}"
    );
}
