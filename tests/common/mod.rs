//! What the end-to-end tests share: a scratch directory per test process, the example
//! cell's two-demonstration blob in it, and the reference rating of a joint stream.

use prf_sim::blob_of_demonstrations;
use prf_sim::world::World;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// This test process's directory, `<temp>/prf-<test binary>-<pid>`.
#[allow(dead_code)] // not every test binary that shares this module needs a directory
pub fn dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let exe = std::env::current_exe().expect("test executable");
        let name = exe.file_stem().and_then(|s| s.to_str()).unwrap_or("test");
        let d = std::env::temp_dir().join(format!("prf-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("temp dir");
        d
    })
}

/// The blob learned from the paper's two diverse demonstrations of the example cell (Part1
/// CNC → Printer, Part2 Printer → Table), written once into [`dir`]: all 18 tasks are
/// feasible on it.
#[allow(dead_code)] // not every test binary that shares this module needs a blob
pub fn blob() -> &'static Path {
    static BLOB: OnceLock<PathBuf> = OnceLock::new();
    BLOB.get_or_init(|| {
        let world = World::example();
        let chosen: Vec<_> = world
            .afforded_tasks()
            .into_iter()
            .filter(|a| {
                let t = &a.task;
                let key = (
                    world.parts[t.part].id.as_str(),
                    world.locations[t.from].kind.as_str(),
                    world.locations[t.to].kind.as_str(),
                );
                (a.approach_from, a.approach_to, a.grasp) == (0, 0, 0)
                    && (key == ("Part1", "CNC", "Printer") || key == ("Part2", "Printer", "Table"))
            })
            .collect();
        let bytes =
            blob_of_demonstrations(&world, &chosen, &prf_files::progress::quiet).expect("blob");
        let path = dir().join("cell.blob");
        std::fs::write(&path, bytes).expect("write blob");
        path
    })
}

/// Peak (position, speed, acceleration, jerk) ratios to the KMR iiwa's limits of an arm stream
/// sampled at 1 ms that stands still before its first and after its last sample: plain third
/// differences of the padded stream, independent of `prf_shared::limits::ArmMeter`.
#[allow(dead_code)] // not every test binary that shares this module rates streams
pub fn stream_ratios(stream: &[[f64; 7]], model: &prf_shared::robot::RobotModel) -> [f64; 4] {
    let l = prf_shared::limits::MotionLimits::kmr_iiwa(model);
    let dt = 1e-3;
    let mut p = vec![stream[0]; 3];
    p.extend_from_slice(stream);
    p.extend([*stream.last().expect("a stream"); 3]);
    let mut r = [0.0f64; 4];
    for k in 3..p.len() {
        for j in 0..7 {
            let (lo, hi) = (model.joints[j].lower, model.joints[j].upper);
            let d1 = p[k][j] - p[k - 1][j];
            let d2 = p[k][j] - 2.0 * p[k - 1][j] + p[k - 2][j];
            let d3 = p[k][j] - 3.0 * p[k - 1][j] + 3.0 * p[k - 2][j] - p[k - 3][j];
            r[0] = r[0].max((2.0 * p[k][j] - lo - hi).abs() / (hi - lo));
            r[1] = r[1].max(d1.abs() / dt / l.arm_speed[j]);
            r[2] = r[2].max(d2.abs() / (dt * dt) / l.arm_acceleration[j]);
            r[3] = r[3].max(d3.abs() / (dt * dt * dt) / l.arm_jerk[j]);
        }
    }
    r
}

/// Largest per-joint distance of `q` from the segment a–b (joint space).
#[allow(dead_code)] // not every test binary that shares this module needs it
pub fn chord_distance(q: &[f64; 7], a: &[f64; 7], b: &[f64; 7]) -> f64 {
    let (mut ab, mut aq) = (0.0, 0.0);
    for j in 0..7 {
        ab += (b[j] - a[j]) * (b[j] - a[j]);
        aq += (q[j] - a[j]) * (b[j] - a[j]);
    }
    let t = if ab > 0.0 {
        (aq / ab).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (0..7).fold(0.0f64, |m, j| {
        m.max((q[j] - a[j] - t * (b[j] - a[j])).abs())
    })
}
