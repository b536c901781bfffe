//! The clock both processes stamp messages with: CLOCK_MONOTONIC, which every process of one
//! machine shares (std's `Instant` has no absolute value to send).

/// CLOCK_MONOTONIC in ns.
pub fn now_ns() -> u64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::Monotonic);
    t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64
}
