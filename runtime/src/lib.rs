//! `prf-runtime`: the cell runtime (blob loading, task planning, fixed-rate executor).
//! `#![no_std]`, no allocation. Its modules arrive with the runtime issue; for now it re-exports
//! the math core it is built on.
#![no_std]

pub use prf_shared as shared;
