//! Host-side library of the PRF cell runtime: the ground-truth world and demonstration
//! generator, the dataset format, validation, and the tools behind the `prf` binary.

pub mod dataset;
pub mod demogen;
pub mod validate;
pub mod world;
