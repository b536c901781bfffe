//! Target `robot`: the robot files — a URDF and its collision-sphere file — read into the
//! runtime's robot model.
//!
//! Input: one byte choosing the file to fuzz (even: the URDF, with the example sphere file;
//! odd: the sphere file, with the example URDF), then its text. An accepted model must give
//! finite forward kinematics and sphere centres at its home configuration.

use nalgebra::Vector3;
use prf_files::robot::{EXAMPLE_SPHERES, EXAMPLE_URDF, parse};
use prf_shared::kinematics::ArmKinematics;
use prf_shared::robot::MAX_SPHERES;

pub fn run(data: &[u8]) {
    let Some((&kind, bytes)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    let (urdf, spheres) = if kind % 2 == 0 {
        (text, EXAMPLE_SPHERES)
    } else {
        (EXAMPLE_URDF, text)
    };
    match parse(urdf, "robot.urdf", spheres, "robot.spheres.json") {
        Ok(model) => {
            let k = ArmKinematics::new(&model, &model.home.into());
            let mut centres = [Vector3::zeros(); MAX_SPHERES];
            k.sphere_centres(&model, &mut centres[..model.spheres.len()]);
            let finite = k.tcp.translation.vector.iter().all(|v| v.is_finite())
                && centres.iter().all(|c| c.iter().all(|v| v.is_finite()));
            assert!(
                finite,
                "an accepted model with non-finite kinematics at home: {model:?}"
            );
        }
        Err(e) => {
            let message = e.to_string();
            let file = if kind % 2 == 0 {
                "robot.urdf"
            } else {
                "robot.spheres.json"
            };
            assert!(message.contains(file), "{message:?} does not name {file}");
        }
    }
}
