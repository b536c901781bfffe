//! The subcommands of `prf`, one file each, and what they share: the task and world
//! arguments and blob loading ([`args`]), progress bars ([`progress`]), and the firmware-sim
//! child process ([`child`]).

pub mod args;
pub mod check_dataset;
pub mod child;
pub mod demo;
pub mod envelope;
pub mod experiment;
pub mod export_mcap;
pub mod field_error;
pub mod firmware;
pub mod generate;
pub mod import_bag;
pub mod inspect;
pub mod learn;
pub mod plan;
pub mod progress;
pub mod rdmp_demo;
pub mod run;
pub mod view;
