//! The host's embassy-time driver: `now` is CLOCK_MONOTONIC in µs, and pending timers wait in
//! one fixed-capacity queue (embassy-time-queue-utils, 8 entries, nothing allocated).
//!
//! Who wakes an expired timer is the waiting side's choice ([`crate::pacing::Wait`]):
//! - the waiting thread itself: [`sleep_until`] sleeps with
//!   `clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)` (then optionally spins) and [`serve`]
//!   wakes what expired — no other thread is involved;
//! - an alarm thread ([`start_alarm_thread`]) that sleeps on a condition variable until the
//!   next expiration and wakes the waiter from there: embassy-time's own std driver works this
//!   way, and it stays callable as the baseline (one binary can link one driver only).

use embassy_time_driver::Driver;
use embassy_time_queue_utils::Queue;
use rustix::time::{ClockId, Timespec};
use std::sync::{Condvar, Mutex, MutexGuard, Once};
use std::task::Waker;
use std::time::Duration;

struct HostDriver {
    queue: Mutex<Queue>,
    /// Signalled when a timer earlier than every other is scheduled (for the alarm thread).
    earlier: Condvar,
}

embassy_time_driver::time_driver_impl!(static DRIVER: HostDriver = HostDriver {
    queue: Mutex::new(Queue::new()),
    earlier: Condvar::new(),
});

/// CLOCK_MONOTONIC in µs: the driver's ticks (1 MHz).
pub fn now_us() -> u64 {
    let t = rustix::time::clock_gettime(ClockId::Monotonic);
    t.tv_sec as u64 * 1_000_000 + t.tv_nsec as u64 / 1_000
}

/// The queue, also after a panic elsewhere poisoned the lock (its contents stay valid: every
/// update is a single call into the queue).
fn queue() -> MutexGuard<'static, Queue> {
    DRIVER.queue.lock().unwrap_or_else(|e| e.into_inner())
}

impl Driver for HostDriver {
    fn now(&self) -> u64 {
        now_us()
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
        if queue().schedule_wake(at, waker) {
            self.earlier.notify_one();
        }
    }
}

/// Wakes every timer that expired by now; returns the next expiration (µs, `u64::MAX`: none).
pub fn serve() -> u64 {
    queue().next_expiration(now_us())
}

/// Sleeps the calling thread until CLOCK_MONOTONIC reaches `at` µs: an absolute
/// `clock_nanosleep` to `spin_us` before `at` (no drift, interruptions resumed), then a busy
/// wait for the rest.
pub fn sleep_until(at: u64, spin_us: u64) {
    let wake = at.saturating_sub(spin_us);
    let request = Timespec {
        tv_sec: (wake / 1_000_000) as _,
        tv_nsec: ((wake % 1_000_000) * 1_000) as _,
    };
    while now_us() < wake {
        // EINTR (a signal, e.g. SIGSTOP/SIGCONT) resumes the same absolute sleep.
        if rustix::thread::clock_nanosleep_absolute(ClockId::Monotonic, &request).is_ok() {
            break;
        }
    }
    while now_us() < at {
        std::hint::spin_loop();
    }
}

/// Starts the alarm thread once per process (the baseline way of waking timers).
pub fn start_alarm_thread() {
    static STARTED: Once = Once::new();
    STARTED.call_once(|| {
        std::thread::Builder::new()
            .name("prf-alarm".into())
            .spawn(alarm_thread)
            .map(drop)
            .unwrap_or_else(|e| eprintln!("prf: the timer alarm thread did not start: {e}"));
    });
}

/// Wakes expired timers, then waits on the condition variable until the next expiration or
/// an earlier timer is scheduled (like embassy-time's std driver).
fn alarm_thread() {
    let mut q = queue();
    loop {
        let now = now_us();
        let next = q.next_expiration(now);
        let wait = Duration::from_micros(next.saturating_sub(now).min(1_000_000));
        q = match DRIVER.earlier.wait_timeout(q, wait) {
            Ok((g, _)) => g,
            Err(e) => e.into_inner().0,
        };
    }
}
