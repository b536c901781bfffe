//! Progress of long work (generating, learning, checking), reported through a callback so that
//! the libraries draw nothing: the CLI turns it into a progress bar.

/// What a long computation reports: how many units it will do, then each unit done.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// The work has this many units in all.
    Total(u64),
    /// This many more units are done.
    Done(u64),
}

/// The callback a computation reports to; it is called from worker threads too.
pub type OnProgress<'a> = &'a (dyn Fn(Progress) + Sync);

/// A callback that shows nothing.
pub fn quiet(_: Progress) {}
