//! `prf-host`: the no_std runtime on a PC.
//!
//! - [`cell`]: the host cell, the executor in a 1 kHz loop streaming setpoints through a
//!   Ruckig output stage over iceoryx2 to the joint controller (receive → tick → output stage →
//!   send);
//! - [`liveness`]: whether the controller's process is alive, asked off the loop;
//! - [`stall`]: the cell's own stalls: the controller's silence counted while the cell
//!   listened, and the ticks skipped when the controller was stopped too;
//! - [`pacing`]: embassy-time's `Ticker` without an async executor, optionally real-time;
//! - [`realtime`]: `SCHED_FIFO` and `mlockall` for the loop thread, where allowed;
//! - [`time_driver`]: the embassy-time driver (CLOCK_MONOTONIC, absolute sleeps);
//! - [`ideal`]: a program run tick by tick on the runtime's ideal cell (`prf plan --export`,
//!   tests);
//! - [`stats`]: percentiles of timing samples.

pub mod cell;
pub mod ideal;
pub mod liveness;
pub mod pacing;
pub mod realtime;
pub mod stall;
pub mod stats;
pub mod time_driver;
