//! The robot model compiled from the shipped URDF + sphere file equals the built-in model.

use prf_files::robot;
use prf_shared::JointVector;
use prf_shared::kinematics::ArmKinematics;
use prf_shared::robot::RobotModel;
use rand::{RngExt, SeedableRng, rngs::StdRng};

#[test]
fn urdf_model_has_the_built_in_kinematics() {
    let urdf = robot::example().expect("shipped files");
    let built_in = RobotModel::kmr_iiwa14();
    let close = |a: &prf_shared::se3::Pose, b: &prf_shared::se3::Pose| {
        let d = a.inverse() * b;
        d.translation.vector.norm() < 1e-12 && d.rotation.angle() < 1e-12
    };
    assert!(close(&urdf.mount, &built_in.mount) && close(&urdf.flange, &built_in.flange));
    assert!(close(&urdf.tcp, &built_in.tcp));
    assert_eq!(urdf.spheres, built_in.spheres);
    assert_eq!(urdf.platform, built_in.platform);
    for (a, b) in urdf.home.iter().zip(&built_in.home) {
        assert!((a - b).abs() < 1e-12);
    }
    for (a, b) in urdf.joints.iter().zip(&built_in.joints) {
        assert!((a.lower - b.lower).abs() < 1e-12 && (a.upper - b.upper).abs() < 1e-12);
        assert!((a.max_speed - b.max_speed).abs() < 1e-12);
    }
    let mut rng = StdRng::seed_from_u64(1);
    for _ in 0..200 {
        let q = JointVector::from_fn(|i, _| {
            rng.random_range(built_in.joints[i].lower..built_in.joints[i].upper)
        });
        let (a, b) = (
            ArmKinematics::new(&urdf, &q),
            ArmKinematics::new(&built_in, &q),
        );
        for (fa, fb) in a.frames.iter().zip(&b.frames) {
            assert!(close(&fa.pose(), &fb.pose()), "frames differ at {q:?}");
        }
        assert!(close(&a.tcp, &b.tcp));
        assert!((a.jacobian(&urdf) - b.jacobian(&built_in)).norm() < 1e-12);
    }
}

#[test]
fn robot_file_errors_name_the_file_and_line() {
    let bad = robot::EXAMPLE_SPHERES.replace("\"iiwa_link_3\"", "\"iiwa_link_9\"");
    let e = robot::parse(robot::EXAMPLE_URDF, "r.urdf", &bad, "s.json")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("s.json:") && e.contains("iiwa_link_9"), "{e}");
    let line: usize = e.split(':').nth(1).unwrap().parse().unwrap();
    assert_eq!(
        bad.lines().nth(line - 1).map(|l| l.contains("iiwa_link_9")),
        Some(true)
    );
    let e = robot::parse(
        "<robot name=\"x\"></robot>",
        "r.urdf",
        robot::EXAMPLE_SPHERES,
        "s.json",
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("r.urdf:"), "{e}");
    let no_joint = robot::EXAMPLE_URDF.replace("type=\"revolute\"", "type=\"fixed\"");
    assert!(robot::parse(&no_joint, "r.urdf", robot::EXAMPLE_SPHERES, "s.json").is_err());
    // A joint whose child is its own parent link (found by fuzzing: the chain walk looped
    // forever) is refused.
    let looped = robot::EXAMPLE_URDF
        .replacen(
            "<child link=\"iiwa_link_3\"/>",
            "<child link=\"iiwa_link_2\"/>",
            1,
        )
        .replacen("<link name=\"iiwa_link_3\"/>", "", 1);
    assert_ne!(looped, robot::EXAMPLE_URDF);
    let e = robot::parse(&looped, "r.urdf", robot::EXAMPLE_SPHERES, "s.json")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("r.urdf:") && e.contains("loop"), "{e}");
}

/// The sphere file states its fit margin; the model carries it (the blob and `prf inspect`
/// show it) and refuses a negative one.
#[test]
fn the_sphere_margin_is_read_and_checked() {
    let urdf = robot::example().expect("shipped files");
    assert_eq!(urdf.sphere_margin, 0.002);
    assert_eq!(urdf.sphere_margin, RobotModel::kmr_iiwa14().sphere_margin);
    let negative = robot::EXAMPLE_SPHERES.replace("\"margin_m\": 0.002", "\"margin_m\": -0.001");
    let e = robot::parse(robot::EXAMPLE_URDF, "r.urdf", &negative, "s.json")
        .unwrap_err()
        .to_string();
    assert!(e.contains("sphere margin"), "{e}");
    let unstated = robot::EXAMPLE_SPHERES.replace("  \"margin_m\": 0.002,\n", "");
    let m = robot::parse(robot::EXAMPLE_URDF, "r.urdf", &unstated, "s.json").expect("optional");
    assert_eq!(m.sphere_margin, 0.0);
}
