//! A synthetic joint-space demonstration for `prf rdmp-demo` and the math benches, which need
//! no cell: a minimum-jerk reach with an elbow swivel.

use prf_shared::profile::min_jerk;
use prf_shared::{JointVector, NA};

/// Start and end of the built-in reach, deg: folded to a mid-workspace grasp, with margin to
/// every joint limit and to the reach boundary.
pub const REACH_START_DEG: [f64; NA] = [-40.0, 20.0, 10.0, -80.0, 10.0, 50.0, -20.0];
pub const REACH_END_DEG: [f64; NA] = [20.0, 42.0, -15.0, -85.0, -20.0, 60.0, 30.0];
/// Peak swivel added on joint 3, rad (null-space motion the RDMP must keep).
pub const SWIVEL: f64 = 0.5;

/// The reach sampled every `dt` over `duration` seconds.
pub fn reach(duration: f64, dt: f64) -> Vec<[f64; NA]> {
    let rad = |d: [f64; NA]| JointVector::from(d.map(f64::to_radians));
    let (a, b) = (rad(REACH_START_DEG), rad(REACH_END_DEG));
    let n = (duration / dt).round() as usize + 1;
    (0..n)
        .map(|k| {
            let s = min_jerk(k as f64 / (n - 1) as f64);
            let swivel = SWIVEL * (std::f64::consts::PI * s).sin().powi(2);
            let q =
                a + (b - a) * s + JointVector::from_fn(|i, _| if i == 2 { swivel } else { 0.0 });
            q.into()
        })
        .collect()
}
