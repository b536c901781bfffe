//! Running a planned program tick by tick against an ideal cell on the host: the arm follows
//! its setpoints exactly, the gripper moves at a fixed rate, the platform drives in a straight
//! line at the KMR's speed. For `prf plan --export` and the executor tests; the simulated iiwa
//! controller with servo dynamics is `firmware-sim`.

use embassy_time::Instant;
use prf_runtime::Runtime;
use prf_runtime::executor::{Executor, ExecutorConfig, Fault, Measured, Mode, Setpoint, wrap};
use prf_runtime::program::Program;
use prf_runtime::reverse::Reversal;
use prf_shared::motion::Sample;
use prf_shared::se3::Pose;

/// Platform speed, m/s, and yaw rate, rad/s, of the ideal cell (KMR 200: 0.5 m/s).
pub const BASE_SPEED: f64 = 0.5;
pub const BASE_YAW_RATE: f64 = 0.5;
/// Gripper travel per second (full stroke in 0.5 s).
pub const GRIPPER_RATE: f64 = 2.0;

/// The state of the ideal cell.
#[derive(Clone, Copy, Debug)]
pub struct IdealCell {
    pub measured: Measured,
}

impl IdealCell {
    pub fn new(arm: [f64; 7], home: &Pose) -> Self {
        IdealCell {
            measured: Measured {
                arm,
                base: prf_runtime::executor::planar(home),
                gripper: 0.0,
            },
        }
    }

    /// Advances the cell by `dt` under setpoint `sp`.
    pub fn apply(&mut self, sp: &Setpoint, dt: f64) {
        let m = &mut self.measured;
        m.arm = sp.arm;
        let target = if sp.close_gripper { 1.0 } else { 0.0 };
        let dg = (target - m.gripper).clamp(-GRIPPER_RATE * dt, GRIPPER_RATE * dt);
        m.gripper += dg;
        let (dx, dy) = (sp.base_goal[0] - m.base[0], sp.base_goal[1] - m.base[1]);
        let d = dx.hypot(dy);
        let step = (BASE_SPEED * dt).min(d);
        if d > 0.0 {
            m.base[0] += dx / d * step;
            m.base[1] += dy / d * step;
        }
        let dyaw = wrap(sp.base_goal[2] - m.base[2]);
        m.base[2] += dyaw.clamp(-BASE_YAW_RATE * dt, BASE_YAW_RATE * dt);
    }
}

/// What running a program gave.
pub struct Execution {
    /// The measured cell after every tick, at 1 kHz (dataset trajectory format).
    pub samples: Vec<Sample>,
    /// Every setpoint.
    pub setpoints: Vec<Setpoint>,
    pub fault: Option<Fault>,
}

/// Runs `program` from the platform at `home` until it is done, faults, or `max_ticks`.
pub fn execute(
    rt: &Runtime<'_>,
    program: &Program,
    home: &Pose,
    cfg: ExecutorConfig,
    max_ticks: usize,
) -> Execution {
    let mut reversal = Box::new(Reversal::new());
    let mut ex = Executor::new(rt, program.clone(), home, cfg, &mut reversal);
    let mut cell = IdealCell::new(rt.model.home, home);
    let dt = rt.config.rdmp.dt;
    let tick = embassy_time::Duration::from_micros((dt * 1e6).round() as u64);
    let mut now = Instant::from_ticks(0);
    let (mut samples, mut setpoints) = (Vec::new(), Vec::new());
    for k in 0..max_ticks {
        let sp = ex.tick(now, &cell.measured);
        cell.apply(&sp, dt);
        setpoints.push(sp);
        samples.push(Sample {
            t: k as f64 * dt,
            base: cell.measured.base,
            arm: cell.measured.arm,
            gripper: cell.measured.gripper,
        });
        if matches!(sp.mode, Mode::Done | Mode::Fault) {
            break;
        }
        now += tick;
    }
    Execution {
        samples,
        setpoints,
        fault: ex.fault(),
    }
}
