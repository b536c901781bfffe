//! `prf-ruckig`: jerk-limited motion with Ruckig, the official C++ core through the project's
//! own C ABI (`shim/prf_ruckig.cpp`, vendored core in `vendor/ruckig`): compile-time 3 or 7
//! axes, no exceptions, no heap, the same code on the host and on the Cortex-M7 (`no_std`).
//!
//! - [`Online`]: one online generator, stepped once per 1 ms cycle (the platform's drive, the
//!   arm's brake, the output stage's safety net).
//! - [`OutputStage`]: between the executor and the joint controller, on both platforms;
//!   [`StagedCell`] puts it in front of the ideal cell (the firmware, the host's reference).
//! - `baseline` (feature): the `ruckig` crate's wrapper, the reference of the tests and the
//!   baseline of `prf bench-cell`.
#![no_std]

#[cfg(any(test, feature = "baseline"))]
extern crate std;

#[cfg(any(test, feature = "baseline"))]
pub mod baseline;
// The FFI: the only unsafe code, each block with its reason.
#[allow(unsafe_code)]
mod ffi;
#[allow(unsafe_code)]
mod online;
pub mod output_stage;
mod storage;

pub use online::{Code, DT, Online, RuckigError};
pub use output_stage::{OutputStage, StagedCell, TRACKING_GAIN};

#[cfg(test)]
mod tests;
