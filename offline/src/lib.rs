//! The host tools behind `prf` that tests use too: the firmware runner ([`firmware`]: build
//! the cell-controller firmware, run it under QEMU, read its figures and setpoint stream), the
//! part-pose envelope of a task ([`envelope`]), planned programs against the true cell
//! ([`ground_truth`]), the learned field against the exact Ω+ ([`field_error`]), the paper's
//! experiments ([`experiment`]) and the charts they draw ([`plots`]).

pub mod budget;
pub mod envelope;
pub mod experiment;
pub mod export_mcap;
pub mod field_error;
pub mod firmware;
pub mod ground_truth;
pub mod memory_map;
pub mod plots;
pub mod view;
