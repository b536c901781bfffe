//! The host tools behind `prf` that tests use too: the firmware runner ([`firmware`]: build
//! the cell-controller firmware, run it under QEMU, read its figures and setpoint stream) and
//! the part-pose envelope of a task ([`envelope`]).

pub mod envelope;
pub mod firmware;
