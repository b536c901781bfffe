//! Host-side library of the PRF cell runtime: the ground-truth world and demonstration
//! generator, the dataset format, validation, and the tools behind the `prf` binary.

pub mod cell;
pub mod compile;
pub mod dataset;
pub mod demogen;
pub mod execute;
pub mod firmware;
pub mod learn;
pub mod robot_file;
pub mod tasks;
pub mod validate;
pub mod world;

/// 1-based line of the first occurrence of `needle` in `text`: where a semantic error in a
/// JSON file is reported.
pub(crate) fn line_of(text: &str, needle: &str) -> Option<usize> {
    text.find(needle)
        .map(|i| text[..i].matches('\n').count() + 1)
}
