//! The example cell's dataset, end to end: `prf gen`'s 64 demonstrations are written, read back
//! through the validating reader, and every program is re-evaluated independently of the
//! planner that made it: densely re-sampled between the stored samples (no collision sphere
//! moves more than 1 mm between checks), it must keep r_d from every true obstacle and the
//! floor, its self clearance, its joint limits, and its speed and acceleration limits; and it
//! must really pick the part at its start pose and release it at its goal pose with one of the
//! part's grasps.

mod common;

use common::TempDir;
use prf_files::dataset::{Dataset, Demonstration};
use prf_shared::JointVector;
use prf_shared::kinematics::{ArmKinematics, arm_base_pose};
use prf_shared::nullspace::kernel;
use prf_shared::rdmp::RdmpConfig;
use prf_shared::robot::RobotModel;
use prf_shared::se3::{Pose, pose_error, pose_from_array};
use prf_sim::demogen::{generate_archive, generate_dataset};
use prf_sim::validate::{self, LIMIT_TOLERANCE, MotionLimits};
use prf_sim::world::World;
use prf_sim::world::geometry::Cell;
use rayon::prelude::*;

/// TCP pose in the world of a sample.
fn tcp(model: &RobotModel, base: [f64; 3], arm: [f64; 7]) -> Pose {
    arm_base_pose(model, base) * ArmKinematics::new(model, &JointVector::from(arm)).tcp
}

/// Checks that the gripper closes once with the TCP on a grasp of the part at its start pose,
/// and opens once with the TCP on the same grasp at the goal pose.
fn check_grip_events(world: &World, model: &RobotModel, d: &Demonstration) {
    let part_type = &world.part_types[world.part_type_index(&d.task.part.kind).expect("type")];
    let start = pose_from_array(d.task.part.pose).expect("part pose");
    let goal = pose_from_array(d.task.goal).expect("goal pose");
    let events: Vec<usize> = (1..d.samples.len())
        .filter(|&k| d.samples[k].gripper != d.samples[k - 1].gripper)
        .collect();
    assert_eq!(events.len(), 2, "{}: one close and one open", d.id);
    let (close, open) = (&d.samples[events[0]], &d.samples[events[1]]);
    assert_eq!((close.gripper, open.gripper), (1.0, 0.0), "{}", d.id);
    let grasp_of = |part: &Pose, s: &prf_files::dataset::Sample| {
        let rel = part.inverse() * tcp(model, s.base, s.arm);
        part_type
            .grasps
            .iter()
            .position(|g| {
                let (dp, dr) = pose_error(&g.tcp.pose(), &rel);
                dp.norm() < 1e-6 && dr.norm() < 1e-6
            })
            .unwrap_or_else(|| {
                panic!(
                    "{}: TCP at t = {} is on no grasp of {}: {rel:?}",
                    d.id, s.t, part_type.name
                )
            })
    };
    assert_eq!(
        grasp_of(&start, close),
        grasp_of(&goal, open),
        "{}: same grasp",
        d.id
    );
}

/// Re-evaluates program `d` independently of the planner that made it (`r`: its dense
/// re-check against the true cell): r_d from every obstacle, self clearance, joint, speed
/// and acceleration limits, the grasp and release, home at both ends, away from
/// singularities on one elbow branch, and the base still while the arm is out. Its smallest
/// manipulability.
fn check_program(
    world: &World,
    model: &RobotModel,
    d: &Demonstration,
    r: &validate::Report,
) -> f64 {
    let c = world.clearance;
    let mut min_manipulability = f64::INFINITY;
    assert!(
        r.min_world >= c.demonstration,
        "{}: clearance {:.4} m < r_d at t = {} ({:?})",
        d.id,
        r.min_world,
        r.min_world_t,
        r.world_contact
    );
    assert!(
        r.min_self >= c.self_collision,
        "{}: self clearance {:.4} m at t = {} ({:?})",
        d.id,
        r.min_self,
        r.min_self_t,
        r.self_contact
    );
    assert_eq!(r.limit_violation, None, "{}", d.id);
    assert!(
        r.max_speed_ratio <= 1.0 + LIMIT_TOLERANCE,
        "{}: speed {} at {:?}",
        d.id,
        r.max_speed_ratio,
        r.max_speed_at
    );
    assert!(
        r.max_acceleration_ratio <= 1.0 + LIMIT_TOLERANCE,
        "{}: acceleration {} at {:?}",
        d.id,
        r.max_acceleration_ratio,
        r.max_acceleration_at
    );

    check_grip_events(world, model, d);
    // Starts and ends at home, arm folded.
    let home = [world.home.x, world.home.y, world.home.yaw_deg.to_radians()];
    for s in [&d.samples[0], d.samples.last().expect("samples")] {
        for k in 0..3 {
            assert!(
                (s.base[k] - home[k]).abs() < 1e-9
                    || k == 2 && (prf_shared::se3::wrap(s.base[k] - home[k])).abs() < 1e-9,
                "{}",
                d.id
            );
        }
        assert!(
            (JointVector::from(s.arm) - JointVector::from(model.home)).norm() < 1e-9,
            "{}",
            d.id
        );
    }
    // Away from singularities, on one elbow branch: the arm motions are RDMP-trainable.
    for smp in &d.samples {
        let kin = ArmKinematics::new(model, &JointVector::from(smp.arm));
        let w = kernel(&kin.jacobian(model)).manipulability;
        min_manipulability = min_manipulability.min(w);
        assert!(
            w > 2.0 * RdmpConfig::default().min_manipulability,
            "{}: manipulability {w} at t = {}",
            d.id,
            smp.t
        );
        assert!(
            smp.arm[3] < 0.0,
            "{}: a4 = {} at t = {}",
            d.id,
            smp.arm[3],
            smp.t
        );
    }
    // The base drives only with the arm at home.
    for w in d.samples.windows(2) {
        let base_moves = (0..3).any(|k| (w[1].base[k] - w[0].base[k]).abs() > 1e-9);
        let arm_home = (JointVector::from(w[0].arm) - JointVector::from(model.home)).norm() < 1e-9;
        assert!(
            !base_moves || arm_home,
            "{}: base moves at t = {} with the arm out",
            d.id,
            w[0].t
        );
    }
    min_manipulability
}

#[test]
fn generated_dataset_is_collision_free_within_limits_and_does_the_task() {
    let world = World::example();
    let model = RobotModel::kmr_iiwa14();
    let afforded = world.afforded_tasks();
    let started = std::time::Instant::now();
    let dataset = generate_dataset(&world, &afforded, 1, 100.0, &prf_files::progress::quiet)
        .expect("generate");
    let generated = started.elapsed();
    assert_eq!(dataset.demonstrations.len(), 64);

    let dir = TempDir::new("example-cell");
    dataset.write(dir.path()).expect("write");
    let back = Dataset::read(dir.path(), &model).expect("the reader accepts what gen wrote");
    assert_eq!(back.demonstrations.len(), 64);

    let cell = Cell::new(&world, &model);
    let limits = MotionLimits::kmr_iiwa(&model);
    let c = world.clearance;
    let reports: Vec<_> = back
        .demonstrations
        .par_iter()
        .map(|d| validate::check(&cell, &limits, &d.samples, 0.001))
        .collect();
    let mut min_clearance = f64::INFINITY;
    let mut min_manipulability = f64::INFINITY;
    for (d, r) in back.demonstrations.iter().zip(&reports) {
        min_clearance = min_clearance.min(r.min_world);
        min_manipulability = min_manipulability.min(check_program(&world, &model, d, r));
    }
    let configurations: usize = reports.iter().map(|r| r.configurations).sum();
    println!(
        "64 demonstrations generated in {:.1} s; {configurations} configurations re-checked; smallest clearance {:.1} mm (r_d = {:.0} mm); smallest manipulability {:.3}",
        generated.as_secs_f64(),
        min_clearance * 1e3,
        c.demonstration * 1e3,
        min_manipulability
    );
}

#[test]
fn generation_is_deterministic_for_a_seed() {
    let world = World::example();
    let pick = [world.afforded_tasks()[13], world.afforded_tasks()[40]];
    let a = generate_dataset(&world, &pick, 7, 100.0, &prf_files::progress::quiet).expect("a");
    let b = generate_dataset(&world, &pick, 7, 100.0, &prf_files::progress::quiet).expect("b");
    assert!(a == b, "same seed, same programs");
    // Another seed may plan other paths (when the direct one is blocked), never another task.
    let c = generate_dataset(&world, &pick, 8, 100.0, &prf_files::progress::quiet).expect("c");
    for (x, y) in a.demonstrations.iter().zip(&c.demonstrations) {
        assert_eq!(
            (&x.task.part, &x.task.from, &x.task.to, x.task.goal),
            (&y.task.part, &y.task.from, &y.task.to, y.task.goal)
        );
    }
}

/// `prf gen --vary`: the same afforded task taught four times gives four different arm
/// motions (other speeds, pre-grasp distance, via points), each passing the same
/// independent re-check as the example's programs; the same seed gives the same archive.
#[test]
fn an_archive_teaches_each_program_its_own_way() {
    let world = World::example();
    let model = RobotModel::kmr_iiwa14();
    let (cnc_to_table, printer_to_cnc) = (world.afforded_tasks()[13], world.afforded_tasks()[40]);
    let selection = [[cnc_to_table; 4], [printer_to_cnc; 4]].concat();
    let quiet = &prf_files::progress::quiet;
    let archive = generate_archive(&world, &selection, 3, 100.0, quiet).expect("archive");
    assert!(
        archive == generate_archive(&world, &selection, 3, 100.0, quiet).expect("again"),
        "same seed, same archive"
    );
    let cell = Cell::new(&world, &model);
    let limits = MotionLimits::kmr_iiwa(&model);
    for d in &archive.demonstrations {
        let r = validate::check(&cell, &limits, &d.samples, 0.001);
        check_program(&world, &model, d, &r);
    }
    // The first arm motion (home to the pre-grasp and on to the grasp) of each program.
    let reach = |d: &Demonstration| -> Vec<[f64; 7]> {
        let home = JointVector::from(model.home);
        let out = |s: &&prf_files::dataset::Sample| (JointVector::from(s.arm) - home).norm() > 1e-9;
        let first = d
            .samples
            .iter()
            .position(|s| out(&s))
            .expect("the arm moves");
        let back = first
            + d.samples[first..]
                .iter()
                .position(|s| s.gripper > 0.5)
                .expect("grip");
        d.samples[first..back].iter().map(|s| s.arm).collect()
    };
    for same in archive.demonstrations.chunks(4) {
        let reaches: Vec<_> = same.iter().map(reach).collect();
        for i in 0..4 {
            for j in i + 1..4 {
                assert_ne!(
                    reaches[i], reaches[j],
                    "{} and {} teach the same reach",
                    same[i].id, same[j].id
                );
            }
        }
    }
    let plain = generate_dataset(&world, &selection[..2], 3, 100.0, quiet).expect("plain");
    assert_eq!(
        reach(&plain.demonstrations[0]),
        reach(&plain.demonstrations[1]),
        "without --vary a task taught again is the same reach"
    );
}

/// The built-in plant's archive (`prf gen --world plant --vary`): programs at its new
/// location type (the conveyor) and with its third part type, each taught its own way, pass
/// the same independent re-check against the plant's true geometry.
#[test]
fn the_plants_programs_keep_r_d_and_do_their_tasks() {
    let world = World::plant();
    let model = RobotModel::kmr_iiwa14();
    let afforded = world.afforded_tasks();
    let labels = [
        "Part3 Conveyor1.front -> CNC3.side, grasp angle",
        "Part1 CNC2.front -> Conveyor3.front, grasp top",
        "Part2 Table3.side -> Printer3.front, grasp top",
        "Part3 Printer1.front -> Conveyor2.front, grasp top",
    ];
    let selection: Vec<_> = labels
        .iter()
        .map(|l| {
            *afforded
                .iter()
                .find(|a| world.label(a) == *l)
                .unwrap_or_else(|| panic!("{l} is an afforded task of the plant"))
        })
        .collect();
    let quiet = &prf_files::progress::quiet;
    let archive = generate_archive(&world, &selection, 5, 100.0, quiet).expect("plant archive");
    let cell = Cell::new(&world, &model);
    let limits = MotionLimits::kmr_iiwa(&model);
    for d in &archive.demonstrations {
        let r = validate::check(&cell, &limits, &d.samples, 0.001);
        check_program(&world, &model, d, &r);
    }
}

#[test]
fn sample_rate_is_configurable() {
    let world = World::example();
    let pick = [world.afforded_tasks()[0]];
    let d = generate_dataset(&world, &pick, 1, 250.0, &prf_files::progress::quiet).expect("gen");
    let s = &d.demonstrations[0].samples;
    assert!((s[1].t - s[0].t - 0.004).abs() < 1e-12);
    assert!(s.windows(2).all(|w| (w[1].t - w[0].t - 0.004).abs() < 1e-9));
}
