//! An ideal cell to run a program against without hardware: the arm follows its setpoints
//! exactly, the gripper moves at a fixed rate, the platform drives in a straight line at the
//! KMR's speed. The host's `prf plan --export` and tests, and the cell-controller firmware, run
//! the same plant, so their setpoint streams can be compared number for number.

use crate::executor::{Measured, Plant, Setpoint, planar, wrap};
use prf_shared::NA;
use prf_shared::se3::Pose;

/// Platform speed, m/s, and yaw rate, rad/s, of the ideal cell (KMR 200: 0.5 m/s).
pub const BASE_SPEED: f64 = 0.5;
/// Yaw rate of the ideal platform, rad/s.
pub const BASE_YAW_RATE: f64 = 0.5;
/// Gripper travel per second (full stroke in 0.5 s).
pub const GRIPPER_RATE: f64 = 2.0;

/// The state of the ideal cell.
#[derive(Clone, Copy, Debug)]
pub struct IdealCell {
    /// The state the executor measures.
    pub measured: Measured,
    /// The tick, s.
    pub dt: f64,
}

impl IdealCell {
    /// At rest with the arm at `arm`, the platform at `home` and the gripper open, ticked
    /// every `dt` s.
    pub fn new(arm: [f64; NA], home: &Pose, dt: f64) -> Self {
        IdealCell {
            measured: Measured {
                arm,
                base: planar(home),
                gripper: 0.0,
            },
            dt,
        }
    }

    /// Advances the cell by one tick under setpoint `sp`.
    pub fn apply(&mut self, sp: &Setpoint) {
        let dt = self.dt;
        let m = &mut self.measured;
        m.arm = sp.arm;
        let target = if sp.close_gripper { 1.0 } else { 0.0 };
        let dg = (target - m.gripper).clamp(-GRIPPER_RATE * dt, GRIPPER_RATE * dt);
        m.gripper += dg;
        let (dx, dy) = (sp.base_goal[0] - m.base[0], sp.base_goal[1] - m.base[1]);
        let d = libm::hypot(dx, dy);
        let step = (BASE_SPEED * dt).min(d);
        if d > 0.0 {
            m.base[0] += dx / d * step;
            m.base[1] += dy / d * step;
        }
        let dyaw = wrap(sp.base_goal[2] - m.base[2]);
        m.base[2] += dyaw.clamp(-BASE_YAW_RATE * dt, BASE_YAW_RATE * dt);
    }
}

impl Plant for IdealCell {
    type Error = core::convert::Infallible;

    fn measured(&self) -> Measured {
        self.measured
    }

    fn command(&mut self, sp: &Setpoint) -> Result<(), Self::Error> {
        self.apply(sp);
        Ok(())
    }
}
