//! Helpers shared by the prf-shared integration tests.
#![allow(dead_code)]

use prf_shared::{JointVector, NA};

/// Degrees to a joint vector in radians.
pub fn deg(v: [f64; NA]) -> JointVector {
    JointVector::from(v.map(|x: f64| x.to_radians()))
}

pub use prf_shared::profile::min_jerk;

/// A smooth joint-space demonstration from `a` to `b` with an elbow-swivel bump on joint 3
/// (null-space motion) of `bump` rad, sampled every `dt` over `duration` seconds.
pub fn joint_demo(
    a: JointVector,
    b: JointVector,
    bump: f64,
    duration: f64,
    dt: f64,
) -> Vec<[f64; NA]> {
    let n = (duration / dt).round() as usize + 1;
    (0..n)
        .map(|k| {
            let s = min_jerk(k as f64 / (n - 1) as f64);
            let mut q = a + (b - a) * s;
            q[2] += bump * (std::f64::consts::PI * s).sin().powi(2);
            q.into()
        })
        .collect()
}

/// Rows of a committed CSV fixture (comment lines start with '#').
pub fn fixture(name: &str) -> Vec<Vec<f64>> {
    let path = format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.starts_with('#') && !l.trim().is_empty())
        .map(|(i, l)| {
            l.split(',')
                .map(|v| {
                    v.trim()
                        .parse()
                        .unwrap_or_else(|_| panic!("{path}:{}: bad number {v:?}", i + 1))
                })
                .collect()
        })
        .collect()
}
