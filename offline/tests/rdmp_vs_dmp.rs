//! `prf experiment rdmp-vs-dmp` (Sec. 4.3): on one approach with a small grid, checked against
//! independent computations: the RDMP's end against forward kinematics of the goal, the DMP's
//! end against the RDMP's, and both risks against a second integration (the whole-trajectory
//! `rdmp::integrate` and `PositionDmp::integrate`) rated with `prf_shared::risk`. The command
//! writes every chart and CSVs that hold what its table prints.

mod common;

use nalgebra::{SVector, Vector3};
use prf_learn::skills;
use prf_offline::experiment::rdmp_vs_dmp::{
    DMP_REACH, Ending, GoalGrid, REACH_ANGLE, REACH_POSITION, approaches, run_approach, tcp_floor,
};
use prf_shared::dmp::PositionDmp;
use prf_shared::kinematics::ArmKinematics;
use prf_shared::rdmp::{RdmpConfig, integrate};
use prf_shared::risk::RiskAccumulator;
use prf_shared::robot::RobotModel;
use prf_shared::{JointVector, NA};
use prf_sim::world::World;

#[test]
fn rdmp_reaches_every_goal_and_the_dmp_its_end_with_the_risks_of_the_shared_rating() {
    let world = World::example();
    let model = RobotModel::kmr_iiwa14();
    let approach = approaches(&world).remove(0);
    assert_eq!(approach.name, "CNC front");
    let dataset =
        prf_sim::demogen::generate_dataset(&world, &[approach.task], 1, 100.0, &|_| {}).unwrap();
    let grid = GoalGrid {
        half_extent: 0.03,
        n: 7,
    };
    let r = run_approach(&model, &dataset, 0, &approach.name, "", grid).unwrap();
    assert_eq!(r.goals.len(), 49);

    let cfg = prf_learn::LearnConfig::default();
    let rdmp = skills::train(&model, &r.demo, r.dt, &cfg.dmp, cfg.min_manipulability).unwrap();
    let dmp = PositionDmp::<NA>::train(&cfg.dmp, r.dt, r.demo.len(), |k| SVector::from(r.demo[k]))
        .unwrap();
    let demo_goal = ArmKinematics::new(&model, &JointVector::from(*r.demo.last().unwrap())).tcp;
    let field = r.field.field();
    let home = JointVector::from(model.home);
    let rate = |qs: &[JointVector]| {
        let mut acc = RiskAccumulator::default();
        for q in qs {
            acc.add(&model, &field, &r.arm_base, &ArmKinematics::new(&model, q));
        }
        acc.risk()
    };
    for g in &r.goals {
        assert!(g.reachable, "goal ({}, {}) is reachable", g.dx, g.dy);
        assert_eq!(g.rdmp.ending, Ending::Reached, "goal ({}, {})", g.dx, g.dy);
        // The goal, rebuilt from the demonstration.
        let mut goal = demo_goal;
        goal.translation.vector += Vector3::new(g.dx, g.dy, 0.0);
        let end = ArmKinematics::new(&model, &JointVector::from(g.rdmp.end)).tcp;
        assert!((end.translation.vector - goal.translation.vector).norm() <= REACH_POSITION);
        assert!(end.rotation.angle_to(&goal.rotation) <= REACH_ANGLE);
        // A second integration, rated the same way.
        let mut qs = vec![home];
        let q_end = integrate(&model, &rdmp, &home, &goal, &RdmpConfig::default(), |s| {
            qs.push(s.q)
        })
        .unwrap();
        assert_eq!(<[f64; NA]>::from(q_end), g.rdmp.end);
        assert_eq!(rate(&qs), g.rdmp.risk, "RDMP risk at ({}, {})", g.dx, g.dy);

        let d = g.dmp.as_ref().expect("a DMP for every integrated goal");
        assert_eq!(d.ending, Ending::Reached);
        let miss = (0..NA)
            .map(|i| (d.end[i] - g.rdmp.end[i]).abs())
            .fold(0.0, f64::max);
        assert!(miss <= DMP_REACH, "DMP ends {miss} rad from the RDMP's end");
        let mut ys = vec![SVector::zeros(); 20_000];
        let n = dmp
            .integrate(
                &SVector::from(model.home),
                &SVector::from(g.rdmp.end),
                RdmpConfig::default().dt,
                &mut ys,
            )
            .unwrap();
        let qs: Vec<JointVector> = ys[..n].to_vec();
        assert_eq!(rate(&qs), d.risk, "DMP risk at ({}, {})", g.dx, g.dy);

        // The null-space-shifted RDMP reaches the same goal.
        let (_, shifted) = g
            .shifted
            .as_ref()
            .expect("a shift for every integrated goal");
        assert_eq!(
            shifted.ending,
            Ending::Reached,
            "shifted at ({}, {})",
            g.dx,
            g.dy
        );
        // Every trajectory's exact risk is at least the floor where it ends: the floor is a
        // lower bound of the true risk, and the exact union's per-ball depth an upper one.
        for t in [&g.rdmp, shifted, d] {
            let end = ArmKinematics::new(&model, &JointVector::from(t.end)).tcp;
            let floor = tcp_floor(&model, &r.exact, &r.arm_base, &end);
            let exact = t.exact_risk.expect("rated exactly within ±30 mm");
            assert!(
                floor <= exact,
                "floor {floor} > exact risk {exact} at ({}, {})",
                g.dx,
                g.dy
            );
            // ... and the field, conservative, never rates a trajectory the floor refutes 0.
            assert!(
                floor == 0.0 || t.risk > 0.0,
                "field risk 0 at ({}, {})",
                g.dx,
                g.dy
            );
        }
    }
    // The floor proves the corners (42 mm from the demonstrated goal, more than ε = 20 mm)
    // risky for any motion, and leaves the demonstrated goal open.
    let at = |dx: f64, dy: f64| r.goals.iter().find(|g| (g.dx, g.dy) == (dx, dy)).unwrap();
    assert!(at(0.03, 0.03).floor > 0.01, "{}", at(0.03, 0.03).floor);
    assert_eq!(at(0.0, 0.0).floor, 0.0);
    // The demonstrated goal itself: the RDMP reproduces the demonstration inside Ω+.
    let centre = &r.goals[24];
    assert_eq!((centre.dx, centre.dy), (0.0, 0.0));
    assert_eq!(centre.rdmp.risk, 0.0);
}

#[test]
fn the_command_writes_every_chart_and_csvs_that_hold_its_table() {
    let tmp = common::TempDir::new("rdmp-vs-dmp");
    let dir = tmp.path();
    let stdout = common::run_prf(
        &[
            "experiment",
            "rdmp-vs-dmp",
            "--goals",
            "3",
            "--half-extent",
            "0.01",
            "-q",
        ],
        dir,
    );
    let mut charts = Vec::new();
    for approach in ["cnc_front", "cnc_side", "printer_front", "table_side"] {
        for chart in [
            "risk_rdmp",
            "risk_rdmp_shifted",
            "risk_dmp",
            "histogram",
            "elbow",
            "workspace",
        ] {
            charts.push(format!("{approach}_{chart}"));
        }
    }
    common::assert_charts(dir, &charts);
    let png = std::fs::read(dir.join("cnc_front_elbow.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    // Every goal of every approach, one row per primitive that ran.
    let goals = std::fs::read_to_string(dir.join("rdmp_vs_dmp.csv")).unwrap();
    let rows: Vec<Vec<&str>> = goals
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.iter().filter(|r| r[4] == "rdmp").count(), 4 * 9);
    // The summary CSV: RDMP reached per approach, as the table prints it.
    let summary = std::fs::read_to_string(dir.join("summary.csv")).unwrap();
    for line in summary.lines().skip(1).filter(|l| l.contains(",rdmp,")) {
        let f: Vec<&str> = line.split(',').collect();
        let (approach, goals, reached) = (f[0], f[2], f[5]);
        let counted = rows
            .iter()
            .filter(|r| r[0] == approach && r[4] == "rdmp" && r[5] == "reached")
            .count();
        assert_eq!(reached.parse::<usize>().unwrap(), counted);
        let printed = format!("{reached}/{goals}");
        assert!(
            stdout
                .lines()
                .any(|l| l.trim_start().starts_with(approach) && l.contains(&printed)),
            "the table prints {approach} {printed}:\n{stdout}"
        );
    }
}
