//! `prf-files`: the cell's files, read and written with errors that name the file and line:
//! the dataset of robot programs ([`dataset`]: manifest JSON, task JSON, trajectory CSV) and the
//! robot ([`robot`]: URDF + collision-sphere file), and [`progress`], the callback through which
//! long work reports. Formats: `docs/formats.md`.

pub mod atomic;
pub mod bag;
pub mod dataset;
pub mod progress;
pub mod robot;

pub use progress::{OnProgress, Progress};

/// 1-based line of the first occurrence of `needle` in `text`: where a semantic error in a
/// JSON file is reported.
pub fn line_of(text: &str, needle: &str) -> Option<usize> {
    text.find(needle)
        .map(|i| text[..i].matches('\n').count() + 1)
}
