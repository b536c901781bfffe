//! `prf-fuzz`: one harness per reader of outside bytes. Each takes arbitrary bytes, feeds them
//! to the real reader and whatever consumes what it accepts, and panics only when a property
//! the product promises is broken (everything else must come back as a typed error).
//!
//! libFuzzer drives them from `fuzz/libfuzzer` (`scripts/fuzz.sh`); the tests of this crate
//! replay the committed seeds (`fuzz/seeds/<target>`) and every crash found
//! (`fuzz/regressions/<target>`) through the same functions.

pub mod blob;
pub mod dataset;
pub mod joint_states;
pub mod kb;
pub mod robot;
pub mod seeds;
pub mod setpoints;
pub mod task_block;
pub mod world;

mod bytes;
mod fixture;

/// A harness: the bytes of one input.
pub type Harness = fn(&[u8]);

/// Every target: its name (the directory of its seeds and regressions) and its harness.
pub const TARGETS: [(&str, Harness); 8] = [
    ("blob", blob::run),
    ("task_block", task_block::run),
    ("setpoints", setpoints::run),
    ("joint_states", joint_states::run),
    ("dataset", dataset::run),
    ("world", world::run),
    ("robot", robot::run),
    ("kb", kb::run),
];
