//! Running a planned program tick by tick against the runtime's ideal cell
//! ([`prf_runtime::ideal`]) on the host, for `prf plan --export`, the benches and the tests;
//! the simulated iiwa controller with servo dynamics is `firmware-sim`.

use embassy_time::Instant;
use prf_runtime::Runtime;
use prf_runtime::executor::{Executor, ExecutorConfig, Fault, Setpoint};
pub use prf_runtime::ideal::IdealCell;
use prf_runtime::program::Program;
use prf_runtime::reverse::Reversal;
use prf_shared::motion::Sample;
use prf_shared::se3::Pose;

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
    let dt = rt.config.rdmp.dt;
    let mut cell = IdealCell::new(rt.model.home, home, dt);
    let tick = embassy_time::Duration::from_micros((dt * 1e6).round() as u64);
    let mut now = Instant::from_ticks(0);
    let (mut samples, mut setpoints) = (Vec::new(), Vec::new());
    for k in 0..max_ticks {
        let Ok(sp) = ex.step(now, &mut cell);
        setpoints.push(sp);
        samples.push(Sample {
            t: k as f64 * dt,
            base: cell.measured.base,
            arm: cell.measured.arm,
            gripper: cell.measured.gripper,
        });
        if sp.is_final() {
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
