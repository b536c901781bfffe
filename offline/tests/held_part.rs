//! The held part in the ground-truth check (`prf_sim::validate::check_held_part`) on a real
//! demonstration of the example cell: the part is clear of every box but its supports and
//! rests exactly on them; moved up or down relative to the gripper by a known distance, the
//! check reports exactly that distance against the supports.

use nalgebra::Translation3;
use prf_shared::robot::RobotModel;
use prf_sim::demogen::{GenConfig, Generator};
use prf_sim::navigation::{PartTracker, part_size};
use prf_sim::validate::{self, MotionLimits};
use prf_sim::world::World;
use prf_sim::world::geometry::Cell;

/// Demonstration 0 of the example cell (the generator checks the held part itself).
fn demo(
    world: &World,
) -> (
    prf_files::dataset::TaskRecord,
    Vec<prf_files::dataset::Sample>,
) {
    let model = RobotModel::kmr_iiwa14();
    let cfg = GenConfig::new(MotionLimits::kmr_iiwa(&model));
    let generator = Generator::new(world, &model, cfg);
    let a = world.afforded_tasks()[0];
    generator
        .generate(&a, 1)
        .expect("demonstration 0 generates")
}

#[test]
fn the_held_part_is_clear_and_rests_on_its_supports() {
    let world = World::example();
    let cell = Cell::new(&world, &RobotModel::kmr_iiwa14());
    let (task, samples) = demo(&world);
    let size = part_size(&world, &task.part.kind);
    let start = prf_shared::se3::pose_from_array(task.part.pose).expect("pose");
    let r_d = world.clearance.demonstration;

    let r = validate::check_held_part(&cell, &samples, PartTracker::new(size, start), 0.002);
    eprintln!(
        "held part: {:.1} mm from {} at {:.2} s; against its supports {:.2e} m ({}), {} configurations",
        r.min * 1e3,
        r.obstacle,
        r.min_t,
        r.support,
        r.support_name,
        r.configurations
    );
    assert!(r.configurations > 1000, "the part was held");
    assert!(r.min >= r_d, "{:.1} mm < r_d", r.min * 1e3);
    assert!(r.support.abs() <= validate::SINK_TOLERANCE, "{}", r.support);

    // The part recorded 3 mm higher (or lower) than it is: held 3 mm higher (lower) in the
    // gripper, it floats 3 mm above (sinks 3 mm into) the surfaces it is picked from and put
    // down on.
    for dz in [0.003, -0.003] {
        let shifted = Translation3::new(0.0, 0.0, dz) * start;
        let r = validate::check_held_part(&cell, &samples, PartTracker::new(size, shifted), 0.002);
        assert!(
            (r.support - dz).abs() < 1e-6,
            "shifted by {dz} m: {} m against the supports",
            r.support
        );
    }
}
