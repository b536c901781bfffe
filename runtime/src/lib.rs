//! `prf-runtime`: the cell runtime of the Program Reuse Framework. `#![no_std]`, no
//! allocation, no clock, no IPC: a pure function of (blob bytes, task, time, measured state).
//!
//! - [`load`]: [`Runtime::load`] validates a blob and reads it in place;
//! - [`task`]: the task T and its symbolic feasibility (Sec. 6.1);
//! - [`task_block`]: a task as bytes (for a controller that reads it from flash);
//! - [`task_plan`]: forward search over the blob's action templates;
//! - [`skill_plan`]: SkillPlan-PTT (Alg. 4), decomposed and pruned;
//! - [`plan`](mod@plan): all of the above in order, giving a [`plan::Plan`] and its [`program::Program`];
//!   [`plan::Planner`] plans several tasks, integrating the candidates they share once
//!   ([`recall`]);
//! - [`executor`]: the 1 kHz state machine, with [`reverse`] for the reversed arm motions;
//! - [`recover`]: after a fault, where the cell is in its program and the way back along the
//!   certified path ([`retract`]);
//! - [`stream`]: a setpoint as a fixed-size record (firmware → host comparison);
//! - [`figures`]: the firmware's measured figures as one record for the host;
//! - [`ideal`]: an ideal cell (exact arm, fixed-rate gripper and platform) to run programs
//!   against without hardware.
//!
//! # Example
//!
//! Load a blob, plan the task of a task block, and execute the program on the ideal cell (a
//! controller does the same from flash, with its own clock and plant):
//!
//! ```
//! use embassy_time::{Duration, Instant};
//! use prf_runtime::{Executor, ExecutorConfig, Runtime, ideal::IdealCell, plan, reverse::Reversal};
//!
//! let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../fuzz");
//! let blob = std::fs::read(format!("{dir}/data/smoke.blob")).unwrap(); // `prf learn` writes it
//! let block = std::fs::read(format!("{dir}/seeds/task_block/task-00.bin")).unwrap(); // `prf plan --task-block`
//! let rt = Runtime::load(&blob).expect("a valid blob");
//! let task = prf_runtime::task_block::decode(&block).expect("a valid task block");
//! let p = plan(&rt, &task).expect("a symbolically feasible task");
//! assert!(p.skills.feasible, "J* = {} m", p.skills.j);
//!
//! let mut reversal = Box::new(Reversal::new()); // static memory on a controller
//! let program = p.program.expect("a program");
//! let mut ex = Executor::new(&rt, program, &task.home, ExecutorConfig::default(), &mut reversal);
//! let mut cell = IdealCell::new(rt.model.home, &task.home, rt.config.rdmp.dt);
//! let mut now = Instant::from_ticks(0);
//! loop {
//!     let sp = ex.step(now, &mut cell).expect("the ideal cell never fails");
//!     if sp.is_final() {
//!         break;
//!     }
//!     now += Duration::from_millis(1); // one tick: 1 kHz
//! }
//! assert!(ex.done() && ex.fault().is_none());
//! ```
#![no_std]

pub mod executor;
pub mod figures;
pub mod ideal;
pub mod load;
pub mod plan;
pub mod program;
pub mod recall;
pub mod recover;
pub mod retract;
pub mod reverse;
pub mod skill_plan;
pub mod stream;
pub mod task;
pub mod task_block;
pub mod task_plan;

pub use executor::{Executor, ExecutorConfig, Fault, Measured, Mode, Setpoint};
pub use load::{LoadError, Runtime, RuntimeConfig};
pub use plan::{Plan, PlanError, Planner, plan};
pub use prf_shared as shared;
pub use task::{Placed, Task};
