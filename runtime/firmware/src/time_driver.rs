//! embassy-time on SysTick: the time driver of the firmware.
//!
//! SysTick counts the core clock down and interrupts once per control tick
//! ([`board::TICK_HZ`]); the interrupt counts periods, so the time is
//! periods × counts-per-period + the count within the period (64 bits, monotonic, at the full
//! clock resolution, converted to embassy ticks). Timers (embassy's generic queue) are checked
//! and woken on that interrupt: alarms resolve to control-tick boundaries, which are exactly
//! where a [`embassy_time::Ticker`] aligned with [`aligned_ticker`] expires.

use crate::board::{SYSTICK_HZ, TICK_HZ};
use core::cell::RefCell;
use core::task::Waker;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::{SCB, SYST};
use critical_section::{CriticalSection, Mutex};
use embassy_time::{Duration, Instant, Ticker};
use embassy_time_driver::Driver;
use embassy_time_queue_utils::queue_generic::ConstGenericQueue;

/// SysTick counts per control tick.
pub const COUNTS_PER_PERIOD: u32 = SYSTICK_HZ / TICK_HZ;
/// SysTick counts per embassy tick.
const COUNTS_PER_EMBASSY_TICK: u64 = SYSTICK_HZ as u64 / embassy_time_driver::TICK_HZ;
const _: () = assert!(SYSTICK_HZ.is_multiple_of(TICK_HZ) && COUNTS_PER_PERIOD <= 0x0100_0000);
const _: () = assert!((SYSTICK_HZ as u64).is_multiple_of(embassy_time_driver::TICK_HZ));

struct State {
    /// SysTick periods elapsed.
    periods: u64,
    /// Earliest pending alarm (embassy ticks), u64::MAX if none.
    alarm: u64,
    timers: ConstGenericQueue<4>,
}

struct SysTickDriver {
    state: Mutex<RefCell<State>>,
}

embassy_time_driver::time_driver_impl!(static DRIVER: SysTickDriver = SysTickDriver {
    state: Mutex::new(RefCell::new(State {
        periods: 0,
        alarm: u64::MAX,
        timers: ConstGenericQueue::new(),
    })),
});

/// SysTick counts since [`start`], inside a critical section.
fn counts_in(state: &State) -> u64 {
    let mut value = SYST::get_current();
    let mut periods = state.periods;
    // A wrap whose interrupt has not run yet (we are in a critical section): count it.
    if SCB::is_pendst_pending() {
        value = SYST::get_current();
        periods += 1;
    }
    periods * COUNTS_PER_PERIOD as u64 + (COUNTS_PER_PERIOD - 1 - value) as u64
}

/// SysTick counts (core clock cycles) since [`start`].
pub fn counts() -> u64 {
    critical_section::with(|cs| counts_in(&DRIVER.state.borrow_ref(cs)))
}

impl SysTickDriver {
    fn wake_expired(&self, cs: CriticalSection) {
        let mut s = self.state.borrow_ref_mut(cs);
        let now = counts_in(&s) / COUNTS_PER_EMBASSY_TICK;
        if now >= s.alarm {
            s.alarm = s.timers.next_expiration(now);
        }
    }
}

impl Driver for SysTickDriver {
    fn now(&self) -> u64 {
        counts() / COUNTS_PER_EMBASSY_TICK
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
        critical_section::with(|cs| {
            let mut s = self.state.borrow_ref_mut(cs);
            if s.timers.schedule_wake(at, waker) {
                let now = counts_in(&s) / COUNTS_PER_EMBASSY_TICK;
                s.alarm = s.timers.next_expiration(now);
            }
        })
    }
}

/// Starts SysTick on the core clock, one interrupt per control tick; time 0 is a period
/// boundary.
pub fn start(mut syst: SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(COUNTS_PER_PERIOD - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
    // The counter reads 0 until its first reload: from then on it counts down monotonically.
    while SYST::get_current() == 0 {}
}

/// A ticker of `period` (a whole number of control ticks) whose expiries fall on SysTick
/// interrupts, so it wakes exactly on time; and its first expiry, SysTick counts.
pub fn aligned_ticker(period: Duration) -> (Ticker, u64) {
    let tick = embassy_time_driver::TICK_HZ / TICK_HZ as u64;
    let now = Instant::now().as_ticks();
    let boundary = Instant::from_ticks(now - now % tick);
    let mut ticker = Ticker::every(period);
    // reset_at(d) expires at d + period.
    ticker.reset_at(boundary);
    let first = (boundary + period).as_ticks() * COUNTS_PER_EMBASSY_TICK;
    (ticker, first)
}

#[cortex_m_rt::exception]
fn SysTick() {
    critical_section::with(|cs| {
        DRIVER.state.borrow_ref_mut(cs).periods += 1;
        DRIVER.wake_expired(cs);
    });
}
