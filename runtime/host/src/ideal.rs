//! Running a planned program tick by tick against the runtime's ideal cell
//! ([`prf_runtime::ideal`]) on the host, for `prf plan --export`, the benches and the tests;
//! the simulated iiwa controller with servo dynamics is `firmware-sim`.

use embassy_time::Instant;
use prf_runtime::Runtime;
use prf_runtime::executor::{Executor, ExecutorConfig, Fault, Measured, Plant, Setpoint};
pub use prf_runtime::ideal::IdealCell;
use prf_runtime::program::Program;
use prf_runtime::reverse::Reversal;
use prf_shared::motion::Sample;
use prf_shared::se3::Pose;

/// What running a program gave.
pub struct Execution {
    /// The measured cell after every tick, at 1 kHz (dataset trajectory format).
    pub samples: Vec<Sample>,
    /// Every setpoint, as the plant passed it on ([`Plant::emitted`]).
    pub setpoints: Vec<Setpoint>,
    pub fault: Option<Fault>,
}

/// Runs `program` from the platform at `home` on the ideal cell until it is done, faults, or
/// `max_ticks`.
pub fn execute(
    rt: &Runtime<'_>,
    program: &Program,
    home: &Pose,
    cfg: ExecutorConfig,
    max_ticks: usize,
) -> Execution {
    let mut cell = IdealCell::new(rt.model.home, home, rt.config.rdmp.dt);
    let Ok(run) = execute_on(rt, program, home, cfg, max_ticks, &mut cell);
    run
}

/// [`execute`] against any plant (one tick per 1 ms of simulated time); stops at the plant's
/// first error.
pub fn execute_on<P: Plant>(
    rt: &Runtime<'_>,
    program: &Program,
    home: &Pose,
    cfg: ExecutorConfig,
    max_ticks: usize,
    plant: &mut P,
) -> Result<Execution, P::Error> {
    let mut reversal = Box::new(Reversal::new());
    let ex = Executor::new(rt, program.clone(), home, cfg, &mut reversal);
    drive(rt, ex, max_ticks, plant)
}

/// A recovery program ([`prf_runtime::recover`]) on `plant`, whose state is `start`:
/// [`execute_on`] with [`Executor::resuming`].
pub fn resume_on<P: Plant>(
    rt: &Runtime<'_>,
    program: &Program,
    home: &Pose,
    cfg: ExecutorConfig,
    max_ticks: usize,
    plant: &mut P,
) -> Result<Execution, P::Error> {
    let start: Measured = plant.measured();
    let mut reversal = Box::new(Reversal::new());
    let ex = Executor::resuming(rt, program.clone(), home, &start, cfg, &mut reversal);
    drive(rt, ex, max_ticks, plant)
}

/// Steps `ex` on `plant` until its program is over or `max_ticks`.
fn drive<P: Plant>(
    rt: &Runtime<'_>,
    mut ex: Executor<'_, '_>,
    max_ticks: usize,
    plant: &mut P,
) -> Result<Execution, P::Error> {
    let dt = rt.config.rdmp.dt;
    let tick = embassy_time::Duration::from_micros((dt * 1e6).round() as u64);
    let mut now = Instant::from_ticks(0);
    let (mut samples, mut setpoints) = (Vec::new(), Vec::new());
    for k in 0..max_ticks {
        let sp = ex.step(now, plant)?;
        let sp = plant.emitted(&sp);
        setpoints.push(sp);
        let m = plant.measured();
        samples.push(Sample {
            t: k as f64 * dt,
            base: m.base,
            arm: m.arm,
            gripper: m.gripper,
        });
        if sp.is_final() {
            break;
        }
        now += tick;
    }
    Ok(Execution {
        samples,
        setpoints,
        fault: ex.fault(),
    })
}
