//! The cell's own stalls (its process or the whole host stopped): a gap of more than
//! [`OWN_STALL`] between two of the cell's polls.
//!
//! - **Silence.** Whether the controller spoke during the cell's stall is unknown — on a
//!   shared host it was usually stopped too — so the gap is not counted as the controller's
//!   silence: the controller is judged on the time the cell listens ([`Silence`]). A controller
//!   that really is silent is still a fault once the cell has listened `silent_after_ms`; one
//!   that kept running meanwhile answers at once, with its watchdog's trip if the cell's stall
//!   was long enough to trip it.
//! - **Schedule.** A controller that kept running coasted through the missed cycles and takes
//!   the late setpoints in their place, so the cell catches up tick by tick. One that was
//!   stopped too (`firmware-sim` resynchronises its cycle after ten periods) did not move: a
//!   burst of catch-up setpoints would run the stream ahead of it. The cell skips those ticks
//!   instead ([`ticks_to_skip`]): time stopped for both, and the stream resumes where it was.

use std::time::{Duration, Instant};

/// A gap between two polls longer than this is the cell's own stall: twice the lag (ten
/// periods) after which `firmware-sim` stops catching up and resynchronises its cycle, so that
/// a freeze of the whole host that the controller caught up with (it coasted through every
/// missed cycle) is never taken for one it skipped.
pub const OWN_STALL: Duration = Duration::from_millis(20);

/// The controller's silence since its last fresh joint state, over the time the cell listened.
#[derive(Clone, Debug)]
pub struct Silence {
    listened: Duration,
    polled: Instant,
    /// The cell's own stalls since the last fresh joint state: not counted in `listened`.
    unheard: Duration,
    /// The last poll came after a stall.
    after_stall: bool,
    stalls: u64,
    longest: Duration,
}

impl Silence {
    /// Silence starting at `now`, as if a fresh joint state had just come.
    pub fn new(now: Instant) -> Self {
        Silence {
            listened: Duration::ZERO,
            polled: now,
            unheard: Duration::ZERO,
            after_stall: false,
            stalls: 0,
            longest: Duration::ZERO,
        }
    }

    /// Records a poll at `now` that brought a `fresh` joint state or none; returns how long
    /// the controller has been silent while the cell listened.
    pub fn poll(&mut self, now: Instant, fresh: bool) -> Duration {
        let gap = now.saturating_duration_since(self.polled);
        self.polled = now;
        self.after_stall = gap > OWN_STALL;
        if self.after_stall {
            self.stalls += 1;
            self.longest = self.longest.max(gap);
            self.unheard += gap;
        } else {
            self.listened += gap;
        }
        if fresh {
            self.listened = Duration::ZERO;
            self.unheard = Duration::ZERO;
        }
        self.listened
    }

    /// How long the controller has been silent while the cell listened, as of the last poll.
    pub fn listened(&self) -> Duration {
        self.listened
    }

    /// The last poll came after the cell's own stall.
    pub fn after_stall(&self) -> bool {
        self.after_stall
    }

    /// The cell's own stalls not counted in the current silence.
    pub fn unheard(&self) -> Duration {
        self.unheard
    }

    /// How many times the cell stalled (gaps longer than [`OWN_STALL`]), and the longest gap.
    pub fn own_stalls(&self) -> (u64, Duration) {
        (self.stalls, self.longest)
    }
}

/// Ticks to skip after the cell's own stall, which made it `missed` periods late, when the
/// controller ran `cycles` cycles meanwhile. A controller that ran at least half of them ran
/// throughout (the shortfall is jitter): 0, the cell catches up. One that ran fewer was
/// stopped too and resynchronised: the ticks it did not run are skipped, and the few it did
/// (it coasted through them) are caught up.
pub fn ticks_to_skip(missed: u64, cycles: u64) -> u64 {
    if cycles < missed / 2 {
        missed - cycles
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Duration = Duration::from_millis(1);

    /// Polls every `step` from `t` `n` times without a fresh state; the last silence.
    fn polls(s: &mut Silence, t: &mut Instant, step: Duration, n: u32) -> Duration {
        let mut silent = Duration::ZERO;
        for _ in 0..n {
            *t += step;
            silent = s.poll(*t, false);
        }
        silent
    }

    #[test]
    fn silence_grows_with_on_time_polls_and_a_fresh_state_ends_it() {
        let mut t = Instant::now();
        let mut s = Silence::new(t);
        assert_eq!(polls(&mut s, &mut t, MS, 100), 100 * MS);
        t += MS;
        assert_eq!(s.poll(t, true), Duration::ZERO);
        assert_eq!(polls(&mut s, &mut t, 3 * MS, 5), 15 * MS);
        assert_eq!(s.own_stalls(), (0, Duration::ZERO));
    }

    /// The CI failure this module answers: the host froze for 112 ms with a state stamped just
    /// before it; the cell's first poll after it finds only that (stale) one.
    #[test]
    fn the_cells_own_stall_is_not_the_controllers_silence() {
        let mut t = Instant::now();
        let mut s = Silence::new(t);
        polls(&mut s, &mut t, MS, 2);
        t += 112 * MS;
        assert_eq!(s.poll(t, false), 2 * MS);
        assert!(s.after_stall());
        assert_eq!(s.unheard(), 112 * MS);
        assert_eq!(s.own_stalls(), (1, 112 * MS));
        // A controller that stays silent is judged on what the cell hears after the stall.
        assert_eq!(polls(&mut s, &mut t, MS, 98), 100 * MS);
        assert!(!s.after_stall());
        t += MS;
        s.poll(t, true);
        assert_eq!(s.unheard(), Duration::ZERO);
        assert_eq!(s.own_stalls(), (1, 112 * MS));
    }

    /// A starving cell (25 ms stalls between 5 ms of listening) still faults a silent
    /// controller: the listening adds up.
    #[test]
    fn a_starving_cell_still_hears_a_silent_controller() {
        let mut t = Instant::now();
        let mut s = Silence::new(t);
        let mut silent = Duration::ZERO;
        for _ in 0..20 {
            silent = polls(&mut s, &mut t, MS, 5);
            t += 25 * MS;
            s.poll(t, false);
        }
        assert_eq!(silent, 100 * MS);
        assert_eq!(s.own_stalls(), (20, 25 * MS));
        // A gap of exactly OWN_STALL is still listening.
        assert_eq!(polls(&mut s, &mut t, OWN_STALL, 1), 100 * MS + OWN_STALL);
    }

    #[test]
    fn ticks_are_skipped_only_for_cycles_the_controller_did_not_run() {
        assert_eq!(ticks_to_skip(112, 0), 112, "the host froze");
        assert_eq!(
            ticks_to_skip(200, 2),
            198,
            "it resumed first and ran two cycles"
        );
        assert_eq!(ticks_to_skip(21, 21), 0, "the controller coasted through");
        assert_eq!(ticks_to_skip(21, 19), 0, "… with jitter");
        assert_eq!(ticks_to_skip(200, 150), 0, "it ran most of the time");
    }
}
