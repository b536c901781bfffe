//! Target `dataset`: the readers of a dataset's three kinds of file — the manifest, a task
//! record (JSON) and a trajectory (CSV) — on text that is not what they expect.
//!
//! Input: one byte choosing the file (0 manifest, 1 task record, 2 trajectory; modulo 3), then
//! its text. A task record is checked against the example dataset's manifest, a trajectory
//! against the example robot. What a reader accepts must keep its promises: unit quaternions,
//! finite samples strictly increasing in time within the joint limits and a gripper in [0, 1].

use prf_files::dataset::{Manifest, parse_manifest, parse_task, parse_trajectory};
use prf_shared::robot::RobotModel;
use std::path::Path;
use std::sync::LazyLock;

/// The manifest task records are checked against.
static MANIFEST: LazyLock<Manifest> = LazyLock::new(|| {
    let text = include_str!("../seeds/dataset/manifest.bin");
    parse_manifest(Path::new("manifest.json"), &text[1..]).expect("the seed manifest reads")
});

pub fn run(data: &[u8]) {
    let Some((&kind, bytes)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    match kind % 3 {
        0 => match parse_manifest(Path::new("manifest.json"), text) {
            Ok(m) => {
                if let Some(r_d) = m.clearance_demo_m {
                    assert!(r_d > 0.0 && r_d.is_finite(), "accepted r_d = {r_d}");
                }
            }
            Err(e) => named(&e.to_string(), "manifest.json"),
        },
        1 => match parse_task(Path::new("d000.task.json"), text, &MANIFEST) {
            Ok(t) => {
                for p in [&t.part.pose, &t.from.pose, &t.to.pose, &t.goal] {
                    let n = p[3..].iter().map(|v| v * v).sum::<f64>().sqrt();
                    assert!(p.iter().all(|v| v.is_finite()) && (n - 1.0).abs() < 1e-3);
                }
            }
            Err(e) => named(&e.to_string(), "d000.task.json"),
        },
        _ => {
            let model = RobotModel::kmr_iiwa14();
            match parse_trajectory(Path::new("d000.csv"), text, &model) {
                Ok(samples) => {
                    assert!(samples.len() >= 2);
                    for w in samples.windows(2) {
                        assert!(
                            w[1].t > w[0].t,
                            "time not increasing: {} → {}",
                            w[0].t,
                            w[1].t
                        );
                    }
                    for s in &samples {
                        assert!(s.t.is_finite() && s.base.iter().all(|v| v.is_finite()));
                        assert_eq!(model.limit_violation(&s.arm), None);
                        assert!((0.0..=1.0).contains(&s.gripper));
                    }
                }
                Err(e) => named(&e.to_string(), "d000.csv"),
            }
        }
    }
}

/// An error message names the file it is about.
fn named(message: &str, file: &str) {
    assert!(message.contains(file), "{message:?} does not name {file}");
}
