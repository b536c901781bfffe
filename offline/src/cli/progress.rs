//! Progress bars: the one style of every long command, fed by the libraries' progress
//! callback ([`prf_files::Progress`]).

use indicatif::{ProgressBar, ProgressStyle};
use prf_files::Progress;

/// A progress bar `WHAT [bar] pos/len UNIT, elapsed`, hidden when `quiet`.
pub struct Bar(ProgressBar);

impl Bar {
    pub fn new(what: &str, unit: &str, quiet: bool) -> Self {
        if quiet {
            return Bar(ProgressBar::hidden());
        }
        let template = format!("{what} {{bar:40}} {{pos}}/{{len}} {unit}, {{elapsed}}");
        let style = ProgressStyle::with_template(&template)
            .unwrap_or_else(|_| ProgressStyle::default_bar());
        Bar(ProgressBar::new(0).with_style(style))
    }

    /// The callback for a library: sets the length, advances.
    pub fn report(&self, p: Progress) {
        match p {
            Progress::Total(n) => self.0.set_length(n),
            Progress::Done(n) => self.0.inc(n),
        }
    }

    /// One unit done (for loops in the CLI itself).
    pub fn inc(&self) {
        self.0.inc(1);
    }

    /// Runs `f` (which prints) with the bar hidden meanwhile.
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        self.0.suspend(f)
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        self.0.finish_and_clear();
    }
}
