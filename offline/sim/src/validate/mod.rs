//! Independent re-evaluation of a recorded program against the ground-truth cell: clearance
//! to every obstacle, the floor and the robot itself, joint limits, speeds and accelerations.
//!
//! It reads only the stored samples and re-samples densely between them (linear
//! interpolation, fine enough that no collision sphere moves more than `resolution` between
//! two checks), so it does not trust the planner that made the program.

mod held;

pub use held::{PartReport, SINK_TOLERANCE, SUPPORT_GAP, check_held_part};

use crate::world::geometry::{Cell, Contact};
use prf_files::dataset::Sample;
use prf_shared::NA;
pub use prf_shared::limits::MotionLimits;
use prf_shared::se3::wrap;

/// Relative tolerance on speed and acceleration limits: finite differences of stored samples
/// (9 decimals) carry rounding noise of about 1e-5 in acceleration at 100 Hz.
pub const LIMIT_TOLERANCE: f64 = 1e-3;

/// The smallest clearances and largest limit ratios found along a program.
#[derive(Clone, Debug)]
pub struct Report {
    /// Smallest clearance to the environment, m, the time and what it was measured against.
    pub min_world: f64,
    pub min_world_t: f64,
    pub world_contact: Contact,
    /// Smallest self clearance, m.
    pub min_self: f64,
    pub min_self_t: f64,
    pub self_contact: Contact,
    /// First joint-limit violation: (time, joint 1..7, value).
    pub limit_violation: Option<(f64, usize, f64)>,
    /// Largest |q̇| / limit over arm and base axes (finite differences), with time and axis
    /// name.
    pub max_speed_ratio: f64,
    pub max_speed_at: (f64, &'static str),
    /// Largest |q̈| / limit (second differences).
    pub max_acceleration_ratio: f64,
    pub max_acceleration_at: (f64, &'static str),
    /// Configurations evaluated.
    pub configurations: usize,
}

const AXES: [&str; 3 + NA] = [
    "base_x", "base_y", "base_yaw", "a1", "a2", "a3", "a4", "a5", "a6", "a7",
];

fn axes(s: &Sample) -> [f64; 3 + NA] {
    std::array::from_fn(|k| if k < 3 { s.base[k] } else { s.arm[k - 3] })
}

/// `b − a` per axis, the yaw along the shorter turn (logs may wrap it to (−π, π]).
fn delta(a: &[f64; 3 + NA], b: &[f64; 3 + NA]) -> [f64; 3 + NA] {
    std::array::from_fn(|k| {
        let d = b[k] - a[k];
        if k == 2 { wrap(d) } else { d }
    })
}

impl Report {
    /// Does the program keep `world_clearance` from the environment, `self_clearance` from
    /// itself, its joint limits and its speed and acceleration limits (within `tolerance`,
    /// relative)?
    pub fn ok(&self, world_clearance: f64, self_clearance: f64, tolerance: f64) -> bool {
        self.min_world >= world_clearance
            && self.min_self >= self_clearance
            && self.limit_violation.is_none()
            && self.max_speed_ratio <= 1.0 + tolerance
            && self.max_acceleration_ratio <= 1.0 + tolerance
    }
}

/// Checks `samples` in `cell`, re-sampling so that no sphere centre moves more than
/// `resolution` (m) between checks.
pub fn check(cell: &Cell, limits: &MotionLimits, samples: &[Sample], resolution: f64) -> Report {
    let (levers, yaw_lever) = cell.motion_levers();
    let mut r = Report {
        min_world: f64::INFINITY,
        min_world_t: 0.0,
        world_contact: Contact::None,
        min_self: f64::INFINITY,
        min_self_t: 0.0,
        self_contact: Contact::None,
        limit_violation: None,
        max_speed_ratio: 0.0,
        max_speed_at: (0.0, ""),
        max_acceleration_ratio: 0.0,
        max_acceleration_at: (0.0, ""),
        configurations: 0,
    };
    let speed: [f64; 3 + NA] = std::array::from_fn(|k| {
        if k < 3 {
            limits.base_speed[k]
        } else {
            limits.arm_speed[k - 3]
        }
    });
    let accel: [f64; 3 + NA] = std::array::from_fn(|k| {
        if k < 3 {
            limits.base_acceleration[k]
        } else {
            limits.arm_acceleration[k - 3]
        }
    });
    let eval = |t: f64, base: [f64; 3], arm: &[f64; NA], r: &mut Report| {
        let c = cell.clearance(base, arm);
        r.configurations += 1;
        if c.world < r.min_world {
            r.min_world = c.world;
            r.min_world_t = t;
            r.world_contact = c.world_contact;
        }
        if c.self_ < r.min_self {
            r.min_self = c.self_;
            r.min_self_t = t;
            r.self_contact = c.self_contact;
        }
    };
    for (i, s) in samples.iter().enumerate() {
        if r.limit_violation.is_none()
            && let Some((j, v)) = cell.model.limit_violation(&s.arm)
        {
            r.limit_violation = Some((s.t, j + 1, v));
        }
        let Some(next) = samples.get(i + 1) else {
            eval(s.t, s.base, &s.arm, &mut r);
            break;
        };
        let dt = next.t - s.t;
        let (a, b) = (axes(s), axes(next));
        let d = delta(&a, &b);
        for k in 0..3 + NA {
            let ratio = d[k].abs() / dt / speed[k];
            if ratio > r.max_speed_ratio {
                r.max_speed_ratio = ratio;
                r.max_speed_at = (s.t, AXES[k]);
            }
        }
        if let Some(prev) = i.checked_sub(1).map(|p| &samples[p]) {
            let d0 = delta(&axes(prev), &a);
            let (h0, h1) = (s.t - prev.t, dt);
            for k in 0..3 + NA {
                let acc = 2.0 * (d[k] / h1 - d0[k] / h0) / (h0 + h1);
                let ratio = acc.abs() / accel[k];
                if ratio > r.max_acceleration_ratio {
                    r.max_acceleration_ratio = ratio;
                    r.max_acceleration_at = (s.t, AXES[k]);
                }
            }
        }
        let moved: f64 = (0..NA).map(|j| levers[j] * d[3 + j].abs()).sum::<f64>()
            + d[0].hypot(d[1])
            + yaw_lever * d[2].abs();
        let n = ((moved / resolution).ceil() as usize).max(1);
        for k in 0..n {
            let u = k as f64 / n as f64;
            let lerp = |x: f64, y: f64| x + (y - x) * u;
            let base = std::array::from_fn(|m| s.base[m] + d[m] * u);
            let arm = std::array::from_fn(|m| lerp(s.arm[m], next.arm[m]));
            eval(lerp(s.t, next.t), base, &arm, &mut r);
        }
    }
    r
}
