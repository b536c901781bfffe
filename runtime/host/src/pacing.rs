//! Pacing of the host cell's 1 kHz loop by embassy-time's `Ticker` without an async executor,
//! on the project's own embassy-time driver ([`crate::time_driver`]).
//!
//! The loop thread blocks on the ticker's future in one of two ways ([`Wait`]): it sleeps
//! itself to the next expiration with an absolute `clock_nanosleep` (optionally spinning the
//! last µs), or it parks until an alarm thread unparks it (the baseline: embassy-time's std
//! driver). [`crate::realtime::RealTime`] optionally makes it a real-time thread.

use crate::time_driver;
use std::future::Future;
use std::num::NonZeroU64;
use std::pin::pin;
use std::sync::Arc;
use std::task::{Context, Poll, Wake, Waker};
use std::thread::{self, Thread};

/// How the loop thread waits for its next tick.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wait {
    /// Sleeps in the loop's own thread: `clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)` to
    /// `spin_us` before the tick, then a busy wait (timer slack set to 1 ns).
    InThread { spin_us: u64 },
    /// Parks until an alarm thread wakes it (embassy-time's std driver design; the baseline).
    AlarmThread,
}

impl Default for Wait {
    fn default() -> Self {
        Wait::InThread { spin_us: 0 }
    }
}

impl core::fmt::Display for Wait {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Wait::InThread { spin_us: 0 } => write!(f, "clock_nanosleep in the loop thread"),
            Wait::InThread { spin_us } => write!(
                f,
                "clock_nanosleep in the loop thread, then {spin_us} µs spin"
            ),
            Wait::AlarmThread => write!(f, "alarm thread (embassy-time std driver design)"),
        }
    }
}

struct Unpark(Thread);

impl Wake for Unpark {
    fn wake(self: Arc<Self>) {
        self.0.unpark();
    }
    fn wake_by_ref(self: &Arc<Self>) {
        self.0.unpark();
    }
}

/// Runs futures to completion on the calling thread, sleeping while they are pending.
pub struct Parker {
    waker: Waker,
    wait: Wait,
    /// The thread's timer slack before [`Wait::InThread`] set it to 1 ns, to restore.
    slack: Option<u64>,
}

impl Parker {
    /// One waker for the thread, made once (nothing is allocated per wait).
    pub fn new(wait: Wait) -> Self {
        let slack = match wait {
            Wait::InThread { .. } => {
                let before = rustix::thread::current_timer_slack().ok();
                // Without slack the kernel wakes the sleeper at the deadline, not up to 50 µs
                // later (the default for normal threads).
                let _ = rustix::thread::set_current_timer_slack(NonZeroU64::new(1));
                before
            }
            Wait::AlarmThread => {
                time_driver::start_alarm_thread();
                None
            }
        };
        Parker {
            waker: Waker::from(Arc::new(Unpark(thread::current()))),
            wait,
            slack,
        }
    }

    pub fn block_on<F: Future>(&self, f: F) -> F::Output {
        let mut f = pin!(f);
        let mut cx = Context::from_waker(&self.waker);
        loop {
            if let Poll::Ready(v) = f.as_mut().poll(&mut cx) {
                return v;
            }
            match self.wait {
                Wait::InThread { spin_us } => match time_driver::serve() {
                    // Nothing scheduled: whatever it waits for must wake this thread.
                    u64::MAX => thread::park(),
                    next => {
                        time_driver::sleep_until(next, spin_us);
                        time_driver::serve();
                    }
                },
                Wait::AlarmThread => thread::park(),
            }
        }
    }
}

impl Drop for Parker {
    fn drop(&mut self) {
        if let Some(s) = self.slack {
            let _ = rustix::thread::set_current_timer_slack(NonZeroU64::new(s));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embassy_time::{Duration, Instant, Ticker, Timer};

    /// Both waits return no earlier than the timer's deadline, and a ticker's ticks keep
    /// their absolute schedule (no drift from late wake-ups). The schedule is read from
    /// before the ticker is made: its first deadline is one period after it is made, which
    /// a clock read after it may already have passed by a tick (CI saw tick 1 fail so, with
    /// the spin waking on the deadline itself).
    #[test]
    fn both_waits_wake_at_or_after_their_deadlines() {
        for wait in [Wait::InThread { spin_us: 20 }, Wait::AlarmThread] {
            let parker = Parker::new(wait);
            let t0 = Instant::now();
            parker.block_on(Timer::after(Duration::from_millis(5)));
            assert!(Instant::now() >= t0 + Duration::from_millis(5), "{wait}");
            let start = Instant::now();
            let mut ticker = Ticker::every(Duration::from_millis(1));
            for k in 1..=50u64 {
                parker.block_on(ticker.next());
                assert!(
                    Instant::now() >= start + Duration::from_millis(k),
                    "{wait}: tick {k}"
                );
            }
        }
    }

    #[test]
    fn in_thread_waits_restore_the_timer_slack() {
        let before = rustix::thread::current_timer_slack().unwrap();
        {
            let _p = Parker::new(Wait::InThread { spin_us: 0 });
            assert_eq!(rustix::thread::current_timer_slack().unwrap(), 1);
        }
        assert_eq!(rustix::thread::current_timer_slack().unwrap(), before);
    }
}
