//! The host tools behind `prf` that tests use too: the firmware runner ([`firmware`]: build
//! the cell-controller firmware, run it under QEMU, read its figures and setpoint stream).

pub mod firmware;
