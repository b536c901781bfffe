//! The ground-truth world: the example cell's structure, its file's error messages, and the
//! geometry primitives against brute force.

mod common;

use nalgebra::Vector3;
use prf_shared::robot::RobotModel;
use prf_sim::world::geometry::{Cell, Contact, Obstacle, box_signed_distance};
use prf_sim::world::{World, planar};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use std::path::Path;

#[test]
fn example_cell_has_the_papers_18_tasks_and_64_afforded_tasks() {
    let w = World::example();
    assert_eq!(w.tasks().len(), 18);
    assert_eq!(w.afforded_tasks().len(), 64);
    let approaches = |t: &str| {
        let lt = &w.location_types[w.location_type_index(t).expect("type")];
        lt.approaches
            .iter()
            .map(|a| a.name.as_str())
            .collect::<Vec<_>>()
    };
    assert_eq!(approaches("CNC"), ["front", "side"]);
    assert_eq!(approaches("Printer"), ["front"]);
    assert_eq!(approaches("Table"), ["side"]);
    for p in &w.part_types {
        let grasps: Vec<_> = p.grasps.iter().map(|g| g.name.as_str()).collect();
        assert_eq!(grasps, ["top", "angle"], "{}", p.name);
    }
    // At least two instances of each type, so same-type transfers exist.
    for t in &w.location_types {
        assert!(
            w.locations.iter().filter(|l| l.kind == t.name).count() >= 2,
            "{}",
            t.name
        );
    }
    let same_type = w
        .tasks()
        .iter()
        .filter(|t| w.location_type(t.from).name == w.location_type(t.to).name)
        .count();
    assert_eq!(same_type, 6);
    assert!((w.clearance.epsilon() - 0.02).abs() < 1e-12);
    // No task starts and ends at the same instance.
    assert!(w.tasks().iter().all(|t| t.from != t.to));
}

fn parse_err(text: &str) -> String {
    World::parse(text, Path::new("cell.json"))
        .expect_err("must be rejected")
        .to_string()
}

/// Line (1-based) of the first line containing `needle`.
fn line_with(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("needle")
        + 1
}

/// The built-in plant (`--world plant`): twelve locations of four types, three part types,
/// tasks between every ordered pair of distinct locations; at every stance the platform keeps
/// the 60 mm the stances are designed with from every box of the plant, neighbours included.
#[test]
fn the_plant_has_twelve_locations_of_four_types_and_tasks_between_every_pair() {
    let w = World::plant();
    assert_eq!(w.locations.len(), 12);
    assert_eq!(w.location_types.len(), 4);
    assert_eq!(w.part_types.len(), 3);
    for t in &w.location_types {
        let n = w.locations.iter().filter(|l| l.kind == t.name).count();
        assert_eq!(n, 3, "{} instances of {}", n, t.name);
    }
    let tasks = w.tasks();
    assert_eq!(tasks.len(), 3 * 12 * 11);
    let mut pairs: Vec<_> = tasks.iter().map(|t| (t.part, t.from, t.to)).collect();
    pairs.sort_unstable();
    pairs.dedup();
    assert_eq!(pairs.len(), tasks.len(), "each task once");
    assert!(tasks.iter().all(|t| t.from != t.to));
    for (stance, r) in stance_clearances(&w) {
        assert!(
            r.world >= 0.06 - 1e-9,
            "{stance}: {} {:?}",
            r.world,
            r.world_contact
        );
    }
}

/// Per stance of `w` ("location.approach"), the robot's clearance there with the arm at home.
fn stance_clearances(w: &World) -> Vec<(String, prf_sim::world::geometry::ClearanceReport)> {
    let cell = Cell::new(w, &RobotModel::kmr_iiwa14());
    let mut out = Vec::new();
    for (i, loc) in w.locations.iter().enumerate() {
        for a in &w.location_type(i).approaches {
            let p = w.location_pose(i) * a.stance.pose();
            let r = cell.clearance(planar(&p), &cell.model.home);
            out.push((format!("{}.{}", loc.id, a.name), r));
        }
    }
    out
}

#[test]
fn world_errors_name_file_line_and_value() {
    let good = prf_sim::world::EXAMPLE_WORLD;
    // A box with min ≥ max.
    let bad = good.replace(
        "\"bed\", \"min\": [-0.80, -0.50, 0.60], \"max\": [-0.10, 0.50, 0.85]",
        "\"bed\", \"min\": [-0.80, -0.50, 0.90], \"max\": [-0.10, 0.50, 0.85]",
    );
    assert_ne!(bad, good);
    let msg = parse_err(&bad);
    assert!(
        msg.starts_with(&format!("cell.json:{}:", line_with(&bad, "\"bed\""))),
        "{msg}"
    );
    assert!(msg.contains("0.9") && msg.contains("bed"), "{msg}");
    // A location of an unknown type.
    let bad = good.replace(
        "\"id\": \"Table2\", \"type\": \"Table\"",
        "\"id\": \"Table2\", \"type\": \"Desk\"",
    );
    let msg = parse_err(&bad);
    assert!(
        msg.starts_with(&format!("cell.json:{}:", line_with(&bad, "\"Table2\""))),
        "{msg}"
    );
    assert!(msg.contains("Desk"), "{msg}");
    // Clearances out of order.
    let bad = good.replace("\"demonstration\": 0.05", "\"demonstration\": 0.01");
    let msg = parse_err(&bad);
    assert!(msg.contains("0.01") && msg.contains("acceptable"), "{msg}");
    // Syntax error: serde's line and column.
    let bad = good.replacen("\"version\": 1,", "\"version\": 1,,", 1);
    let msg = parse_err(&bad);
    assert!(
        msg.starts_with(&format!("cell.json:{}:", line_with(&bad, "\"version\""))),
        "{msg}"
    );
    // An unknown field is refused, not ignored.
    let bad = good.replacen("\"version\": 1,", "\"version\": 1, \"colour\": \"red\",", 1);
    assert!(parse_err(&bad).contains("colour"));
    // A missing world file names the path.
    let msg = World::load(Path::new("/nonexistent/cell.json"))
        .expect_err("missing")
        .to_string();
    assert!(msg.contains("/nonexistent/cell.json"), "{msg}");
}

/// Brute-force distance from `p` to a box: the nearest of many points on (or in) the box.
fn brute_box_distance(p: &Vector3<f64>, half: &Vector3<f64>, rng: &mut StdRng) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..20_000 {
        // A random point on a random face.
        let axis = rng.random_range(0..3);
        let sign = if rng.random_range(0..2) == 0 {
            -1.0
        } else {
            1.0
        };
        let mut s = Vector3::new(
            rng.random_range(-half.x..half.x),
            rng.random_range(-half.y..half.y),
            rng.random_range(-half.z..half.z),
        );
        s[axis] = sign * half[axis];
        best = best.min((s - p).norm());
    }
    let inside = (0..3).all(|k| p[k].abs() <= half[k]);
    if inside { -best } else { best }
}

#[test]
fn box_distance_matches_brute_force() {
    let mut rng = StdRng::seed_from_u64(3);
    let half = Vector3::new(0.4, 0.1, 0.25);
    for _ in 0..40 {
        let p = Vector3::new(
            rng.random_range(-0.8..0.8),
            rng.random_range(-0.5..0.5),
            rng.random_range(-0.6..0.6),
        );
        let exact = box_signed_distance(&p, &half);
        let brute = brute_box_distance(&p, &half, &mut rng);
        // Sampling can only overestimate |distance|; 20k samples get within a few mm.
        assert!(
            exact.abs() <= brute.abs() + 1e-12,
            "{p:?}: {exact} vs {brute}"
        );
        assert!((exact - brute).abs() < 0.01, "{p:?}: {exact} vs {brute}");
    }
}

#[test]
fn rotated_obstacle_distance_is_frame_independent() {
    let o = Obstacle::new(
        0,
        "b".into(),
        Vector3::new(1.0, 2.0, 0.5),
        0.7,
        Vector3::new(0.3, 0.1, 0.5),
    );
    // A point 0.2 m beyond the box's local +x face, in world coordinates.
    let local = Vector3::new(0.5, 0.05, 0.2);
    let (s, c) = 0.7f64.sin_cos();
    let world = Vector3::new(
        1.0 + c * local.x - s * local.y,
        2.0 + s * local.x + c * local.y,
        0.5 + local.z,
    );
    assert!((o.signed_distance(&world) - 0.2).abs() < 1e-12);
}

#[test]
fn platform_clearance_is_exact_at_the_stances() {
    // Every stance of the example world is designed with a 60 mm gap between the platform and
    // the location's nearest box, and the arm at home keeps more than that.
    let w = World::example();
    for (stance, r) in stance_clearances(&w) {
        assert!(
            (r.world - 0.06).abs() < 1e-9,
            "{stance}: {} {:?}",
            r.world,
            r.world_contact
        );
        assert!(
            matches!(r.world_contact, Contact::Platform { .. }),
            "{:?}",
            r.world_contact
        );
        assert!(r.self_ > w.clearance.self_collision);
    }
}

#[test]
fn self_collision_is_detected() {
    let model = RobotModel::kmr_iiwa14();
    let w = World::example();
    let cell = Cell::new(&w, &model);
    let home = [w.home.x, w.home.y, 0.0];
    let deg = |d: [f64; 7]| d.map(f64::to_radians);
    // Gripper folded back onto the upper arm: joints 4 and 6 at their limits, joint 3 turned
    // 90° so that the fingers sink into link 2 (46 mm deep with the spheres; with joint 3 at
    // 0 they pass it 0.6 mm apart, since issue 23's tighter spheres).
    let r = cell.clearance(home, &deg([0.0, 30.0, 90.0, -120.0, 0.0, 120.0, 0.0]));
    assert!(r.self_ < 0.0, "{r:?}");
    assert!(
        matches!(r.self_contact, Contact::SelfSpheres { .. }),
        "{r:?}"
    );
    // Gripper reaching down into the own platform (TCP at z = 0.51 m, deck at 0.70 m).
    let r = cell.clearance(home, &deg([0.0, 120.0, 0.0, -120.0, 0.0, -120.0, 0.0]));
    assert!(r.self_ < 0.0, "{r:?}");
    assert!(
        matches!(r.self_contact, Contact::SelfPlatform { .. }),
        "{r:?}"
    );
    let r = cell.clearance(home, &model.home);
    assert!(r.self_ > 0.05 && r.world > 0.5, "{r:?}");
}

#[test]
fn home_is_in_the_free_aisle() {
    // At home nothing is nearer than the floor under the arm base (0.63 m).
    let w = World::example();
    let cell = Cell::new(&w, &RobotModel::kmr_iiwa14());
    let home = [w.home.x, w.home.y, w.home.yaw_deg.to_radians()];
    let r = cell.clearance(home, &cell.model.home);
    assert!(matches!(r.world_contact, Contact::Floor { .. }), "{r:?}");
    assert!(r.world > 0.6, "{r:?}");
}
