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
