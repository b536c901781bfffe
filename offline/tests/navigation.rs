//! The simulated platform's navigation (`prf_sim::navigation`) on the example cell, checked
//! against the ground-truth geometry it is built on.

use nalgebra::Vector3;
use prf_shared::robot::RobotModel;
use prf_sim::navigation::{CHECK_STEP, Drive, NavError, Navigator};
use prf_sim::world::World;
use prf_sim::world::geometry::{Cell, HeldPart};

fn stance(world: &World, loc: &str, approach: usize) -> [f64; 3] {
    let i = world.location_index(loc).expect("location");
    let a = &world.location_type(i).approaches[approach];
    let s = world.location_pose(i) * a.stance.pose();
    [
        s.translation.x,
        s.translation.y,
        s.rotation.euler_angles().2,
    ]
}

/// The drive body's clearance without a part is the ground-truth clearance of the same
/// configuration (`Cell::clearance`: arm spheres, platform prism, floor), to rounding.
#[test]
fn drive_clearance_is_the_ground_truth_clearance() {
    let world = World::example();
    let model = RobotModel::kmr_iiwa14();
    let cell = Cell::new(&world, &model);
    let body = cell.drive_body(&model.home, &[]);
    let home = [world.home.x, world.home.y, 0.0];
    for (k, q) in [
        home,
        stance(&world, "CNC1", 1),
        stance(&world, "Table1", 0),
        [1.2, -0.7, 0.4],
    ]
    .into_iter()
    .enumerate()
    {
        let d = cell.drive_clearance(&body, q);
        let truth = cell.clearance(q, &model.home).world;
        assert!(
            (d.robot - truth).abs() < 1e-12,
            "pose {k}: {} vs {truth}",
            d.robot
        );
        assert_eq!(d.part, f64::INFINITY);
    }
}

/// The spheres of a held part contain its box: every point of a 5 mm grid over the box lies in
/// some sphere.
#[test]
fn held_part_spheres_cover_the_part() {
    let world = World::example();
    for t in &world.part_types {
        for g in &t.grasps {
            let grasp = g.tcp.pose();
            let part = HeldPart::new(t.size, &grasp);
            let n = t.size.map(|s| (s / 0.005).round() as usize);
            for i in 0..=n[0] {
                for j in 0..=n[1] {
                    for k in 0..=n[2] {
                        let p = Vector3::new(
                            -t.size[0] / 2.0 + t.size[0] * i as f64 / n[0] as f64,
                            -t.size[1] / 2.0 + t.size[1] * j as f64 / n[1] as f64,
                            t.size[2] * k as f64 / n[2] as f64,
                        );
                        let in_tcp = grasp.inverse().transform_point(&p.into()).coords;
                        assert!(
                            part.spheres
                                .iter()
                                .any(|(c, r)| (in_tcp - c).norm() <= r + 1e-12),
                            "{} {}: {p:?} uncovered",
                            t.name,
                            g.name
                        );
                    }
                }
            }
        }
    }
}

/// The first drive of a task that needs a detour (home → CNC1's side stance): the same path
/// every time, every pose of it (re-sampled at 1 mm) at least the stated clearance less half
/// the check step from every box, and followed by Ruckig exactly to the goal.
#[test]
fn a_detour_is_planned_deterministically_and_clear() {
    let world = World::example();
    let model = RobotModel::kmr_iiwa14();
    let cell = Cell::new(&world, &model);
    let r = world.clearance.acceptable;
    let home = [world.home.x, world.home.y, 0.0];
    let goal = stance(&world, "CNC1", 1);
    let plan = || {
        let nav = Navigator::new(&cell, cell.drive_body(&model.home, &[]), r);
        nav.plan(home, goal).expect("path")
    };
    let t0 = std::time::Instant::now();
    let path = plan();
    let took = t0.elapsed();
    assert!(path.len() > 2, "a detour: {path:?}");
    assert_eq!(plan(), path, "deterministic");
    let nav = Navigator::new(&cell, cell.drive_body(&model.home, &[]), r);
    assert!(!nav.segment_ok(home, goal), "the straight line is blocked");
    let mut drive = Drive::new(home, &prf_shared::limits::MotionLimits::kmr_iiwa(&model));
    drive.follow(&path);
    let mut min = f64::INFINITY;
    for _ in 0..200_000 {
        let p = drive.step().expect("ruckig");
        min = min.min(nav.clearance_at(p));
        if drive.arrived() {
            break;
        }
    }
    assert!(drive.arrived());
    let end = drive.pose();
    let off = [
        end[0] - goal[0],
        end[1] - goal[1],
        prf_shared::se3::wrap(end[2] - goal[2]),
    ];
    assert!(off.iter().all(|d| d.abs() < 1e-9), "{end:?} vs {goal:?}");
    println!(
        "detour: {} corners, planned in {:.1} ms, smallest clearance on the way {:.1} mm",
        path.len(),
        took.as_secs_f64() * 1e3,
        min * 1e3
    );
    assert!(min >= r - CHECK_STEP / 2.0, "{min}");
}

/// A goal inside a machine is refused with a typed error, not driven to.
#[test]
fn an_unreachable_goal_is_a_typed_error() {
    let world = World::example();
    let model = RobotModel::kmr_iiwa14();
    let cell = Cell::new(&world, &model);
    let nav = Navigator::new(&cell, cell.drive_body(&model.home, &[]), 0.03);
    let i = world.location_index("CNC1").unwrap();
    let inside = world.location_pose(i).translation;
    let e = nav
        .plan([world.home.x, world.home.y, 0.0], [inside.x, inside.y, 0.0])
        .unwrap_err();
    assert!(matches!(e, NavError::Blocked { end: "goal", .. }), "{e}");
    assert!(e.to_string().contains("keeps only"), "{e}");
}
