//! The benchmark subcommands: `prf bench` (the math core and the runtime, [`math`]) and
//! `prf bench-cell` (the host cell, [`cell`]), with the allocation counter they report.

pub mod alloc_count;
pub mod cell;
pub mod learn_scale;
pub mod math;
pub mod stall_probe;
