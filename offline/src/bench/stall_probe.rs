//! The machine's own stalls, measured beside the 1 kHz loop: a probe thread that wakes every
//! period on an absolute schedule and does nothing else. Its late wake-ups are what the
//! machine (the kernel, a hypervisor, other load) takes from any thread with its scheduling,
//! so its deadline misses are the floor the loop's cannot go below on this machine.

use prf_host::realtime::RealTime;
use prf_host::stats::percentiles;
use prf_host::time_driver::{now_us, sleep_until};
use std::num::NonZeroU64;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;

/// The probe's period, µs (the loop's).
const PERIOD_US: u64 = 1_000;

/// Wake-ups recorded at most (10 minutes at 1 kHz; later ones are counted, not kept).
const RECORDED: usize = 600_000;

/// What the probe saw.
pub struct ProbeFigures {
    /// Wake-ups.
    pub wakes: u64,
    /// Wake-up lateness p50 and p99, µs.
    pub late_p50: f64,
    pub late_p99: f64,
    /// The largest lateness, µs.
    pub late_max: f64,
    /// Wake-ups after the next period began: the ticks a loop with no work would have missed.
    pub misses: u64,
    /// The probe's scheduling, in words.
    pub scheduling: String,
}

impl ProbeFigures {
    /// Misses per wake-up, %.
    pub fn miss_percent(&self) -> f64 {
        self.misses as f64 / self.wakes.max(1) as f64 * 100.0
    }
}

/// A running probe; [`StallProbe::stop`] ends it and gives its figures.
pub struct StallProbe {
    stop: Arc<AtomicBool>,
    thread: JoinHandle<ProbeFigures>,
}

impl StallProbe {
    /// Starts the probe thread, `SCHED_FIFO` at `priority` if given (and granted), sleeping
    /// with the loop's absolute `clock_nanosleep` ([`sleep_until`], timer slack 1 ns, no
    /// spin: the misses it counts are late by a whole period) but not through the
    /// embassy-time driver, whose queue and lock it would share with the loop.
    pub fn start(priority: Option<i32>) -> std::io::Result<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::Builder::new()
            .name("prf-stall-probe".into())
            .spawn(move || probe(priority, &flag))?;
        Ok(StallProbe { stop, thread })
    }

    /// Stops the probe and returns what it saw.
    pub fn stop(self) -> ProbeFigures {
        self.stop.store(true, Ordering::Relaxed);
        self.thread
            .join()
            .unwrap_or_else(|_| unreachable!("the probe's loop does not panic"))
    }
}

/// The probe's loop: the k-th wake-up is due at start + k·period (a late one does not move
/// the schedule, as the loop's ticker does not).
fn probe(priority: Option<i32>, stop: &AtomicBool) -> ProbeFigures {
    let realtime = priority.map(RealTime::enter_scheduling);
    // Woken at the deadline, as the loop's thread is (`prf_host::pacing::Parker`), not up to
    // the normal threads' 50 µs of timer slack later.
    let _ = rustix::thread::set_current_timer_slack(NonZeroU64::new(1));
    let scheduling = match &realtime {
        Some(r) => r.status.split(',').next().unwrap_or_default().to_string(),
        None => "normal scheduling".to_string(),
    };
    let mut late = Vec::with_capacity(RECORDED);
    let (mut wakes, mut misses, mut late_max) = (0u64, 0u64, 0u64);
    let start = now_us();
    // At least one wake-up, however soon it is stopped.
    loop {
        let due = start + (wakes + 1) * PERIOD_US;
        sleep_until(due, 0);
        let l = now_us().saturating_sub(due);
        wakes += 1;
        misses += u64::from(l >= PERIOD_US);
        late_max = late_max.max(l);
        if late.len() < RECORDED {
            late.push(l as f64);
        }
        if stop.load(Ordering::Relaxed) {
            break;
        }
    }
    drop(realtime);
    let p = percentiles(&mut late);
    ProbeFigures {
        wakes,
        late_p50: p[0],
        late_p99: p[1],
        late_max: late_max as f64,
        misses,
        scheduling,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The probe wakes, never ahead of its schedule (at most once per period of the time it
    /// ran), and its figures add up: no more misses than wake-ups, the percentiles ordered
    /// and within the largest lateness.
    #[test]
    fn the_probe_counts_its_wake_ups() {
        let t0 = std::time::Instant::now();
        let probe = StallProbe::start(None).unwrap();
        std::thread::sleep(std::time::Duration::from_millis(50));
        let f = probe.stop();
        let ran_ms = t0.elapsed().as_millis() as u64;
        assert!(
            f.wakes >= 1 && f.wakes <= ran_ms + 1,
            "{} wake-ups in {ran_ms} ms",
            f.wakes
        );
        assert!(f.misses <= f.wakes);
        assert!(f.late_p50 <= f.late_p99 && f.late_p99 <= f.late_max);
        assert_eq!(f.scheduling, "normal scheduling");
    }
}
