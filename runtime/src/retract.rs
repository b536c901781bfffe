//! The motions of a recovery (issue 18): back onto the certified path, then along it backwards
//! at a reduced speed, one setpoint per tick.
//!
//! - [`Connect`]: from the configuration where the arm stopped to the nearest configuration of
//!   the certified motion, a straight line in joint space with the minimum-jerk profile
//!   s(τ) = 10τ³ − 15τ⁴ + 6τ⁵, timed so that every joint stays within a fraction of its speed,
//!   acceleration and jerk limits (the profile's peaks are 1.875, 5.774 and 60 times
//!   D/T, D/T², D/T³).
//! - [`Playback`]: the certified samples P_0 = q_k, P_1 = q_{k−1}, …, P_k = q_0 (from
//!   [`crate::reverse::Reversal`]) played at a rate r ≤ 1 sample per tick that ramps from 0 up to
//!   its maximum with s(τ) (so the playback starts at rest), interpolated between samples with
//!   a Catmull-Rom cubic. Every certified sample is passed exactly, and no more than one new
//!   sample is needed per tick.

use prf_shared::NA;
use prf_shared::limits::MotionLimits;

/// The fraction of the limits (and samples per tick) a retraction uses by default, and in
/// place of a value outside (0, 1].
pub const DEFAULT_SPEED: f64 = 0.25;

/// `x` if it is in (0, 1], else [`DEFAULT_SPEED`] (never faster on bad input).
fn speed_or_default(x: f64) -> f64 {
    if x > 0.0 && x <= 1.0 {
        x
    } else {
        DEFAULT_SPEED
    }
}

/// Minimum-jerk profile s(τ), τ ∈ [0, 1].
fn min_jerk(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * t * (10.0 + t * (-15.0 + 6.0 * t))
}

/// A straight joint-space move between two configurations at rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Connect {
    from: [f64; NA],
    to: [f64; NA],
    /// Ticks of the move (≥ 1).
    ticks: u32,
    /// Ticks done.
    done: u32,
}

impl Connect {
    /// The move from `from` to `to` with every joint within `fraction` (0 < fraction ≤ 1, else
    /// [`DEFAULT_SPEED`]) of its speed, acceleration and jerk limits, at `dt` s per tick.
    pub fn new(
        from: [f64; NA],
        to: [f64; NA],
        limits: &MotionLimits,
        fraction: f64,
        dt: f64,
    ) -> Self {
        let fraction = speed_or_default(fraction);
        let mut t: f64 = 0.0;
        for j in 0..NA {
            let d = f64::abs(to[j] - from[j]);
            let (v, a, jk) = (
                fraction * limits.arm_speed[j],
                fraction * limits.arm_acceleration[j],
                fraction * limits.arm_jerk[j],
            );
            t = t
                .max(1.875 * d / v)
                .max(prf_shared::float::sqrt(5.7735 * d / a))
                .max(libm::cbrt(60.0 * d / jk));
        }
        // NaN (a degenerate limit) counts as one tick: the executor's checks stop bad input.
        let ticks = libm::ceil(t / dt);
        let ticks = if ticks >= 1.0 && ticks < u32::MAX as f64 {
            ticks as u32
        } else {
            1
        };
        Connect {
            from,
            to,
            ticks,
            done: 0,
        }
    }

    /// Ticks the move takes.
    pub fn ticks(&self) -> u32 {
        self.ticks
    }

    /// The next setpoint; `to` exactly on the last tick.
    pub fn setpoint(&mut self) -> [f64; NA] {
        self.done = (self.done + 1).min(self.ticks);
        if self.done == self.ticks {
            return self.to;
        }
        let s = min_jerk(self.done as f64 / self.ticks as f64);
        core::array::from_fn(|j| self.from[j] + s * (self.to[j] - self.from[j]))
    }

    /// True once `to` was emitted.
    pub fn finished(&self) -> bool {
        self.done >= self.ticks
    }
}

/// A ramped, interpolated playback of a sample sequence (see the module).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Playback {
    /// P_{i−1} … P_{i+3}: the Catmull-Rom window and one sample ahead (P_{−1} extrapolated,
    /// the last sample repeated).
    buf: [[f64; NA]; 5],
    /// Samples handed in so far, P_0 included (P_0 … P_{known−1}).
    known: u32,
    /// Index i of the sample the playback left last.
    i: u32,
    /// Samples in all (k + 1: P_0 … P_k).
    samples: u32,
    /// Position between P_i and P_{i+1}, [0, 1).
    u: f64,
    /// Maximum rate, samples per tick (≤ 1), and the ramp's ticks.
    rate: f64,
    ramp: u32,
    tick: u32,
}

impl Playback {
    /// A playback of `samples` samples starting at rest at `first` (= P_0), at most `rate`
    /// samples per tick (0 < rate ≤ 1, else [`DEFAULT_SPEED`]), reached after `ramp` ticks. The samples after the
    /// first are handed in one at a time by [`Playback::feed`].
    pub fn new(first: [f64; NA], samples: u32, rate: f64, ramp: u32) -> Self {
        let rate = speed_or_default(rate);
        Playback {
            buf: [first; 5],
            known: 1,
            i: 0,
            samples: samples.max(1),
            u: 0.0,
            rate,
            ramp: ramp.max(1),
            tick: 0,
        }
    }

    /// True while the playback lacks a sample it may need at the next tick: hand it in with
    /// [`Playback::feed`] first (three at the start, then at most one per tick).
    pub fn wants(&self) -> bool {
        self.known < self.samples && self.known < self.i + 4
    }

    /// Hands in the next sample (P_1, P_2, … in order).
    pub fn feed(&mut self, q: [f64; NA]) {
        if !self.wants() {
            return;
        }
        let slot = (self.known + 1 - self.i) as usize;
        // After the last sample the window repeats it.
        let end = if self.known + 1 == self.samples {
            5
        } else {
            slot + 1
        };
        for s in self.buf.get_mut(slot..end).unwrap_or(&mut []) {
            *s = q;
        }
        if self.known == 1 {
            // P_{−1} continues the motion's line through P_0 (the Catmull-Rom tangent at P_0
            // is then the motion's own).
            let p0 = self.buf[1];
            self.buf[0] = core::array::from_fn(|j| 2.0 * p0[j] - q[j]);
        }
        self.known += 1;
    }

    /// True once P_k was emitted.
    pub fn finished(&self) -> bool {
        self.i + 1 >= self.samples
    }

    /// The next setpoint (call when [`Playback::wants`] is false).
    pub fn setpoint(&mut self) -> [f64; NA] {
        if self.finished() {
            return self.buf[1];
        }
        self.tick = self.tick.saturating_add(1);
        self.u += self.rate * min_jerk(self.tick as f64 / self.ramp as f64);
        if self.u >= 1.0 {
            self.u -= 1.0;
            self.i += 1;
            self.buf.copy_within(1.., 0);
            if self.finished() {
                return self.buf[1];
            }
        }
        let w = [self.buf[0], self.buf[1], self.buf[2], self.buf[3]];
        catmull_rom(&w, self.u)
    }
}

/// The Catmull-Rom cubic through w[1] (u = 0) and w[2] (u = 1).
fn catmull_rom(w: &[[f64; NA]; 4], u: f64) -> [f64; NA] {
    let (u2, u3) = (u * u, u * u * u);
    core::array::from_fn(|j| {
        let (p0, p1, p2, p3) = (w[0][j], w[1][j], w[2][j], w[3][j]);
        p1 + 0.5
            * (u * (p2 - p0)
                + u2 * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3)
                + u3 * (-p0 + 3.0 * p1 - 3.0 * p2 + p3))
    })
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use prf_shared::robot::RobotModel;
    use std::vec::Vec;

    /// Peak |Δq|/dt, |Δ²q|/dt², |Δ³q|/dt³ ratios to the limits of a stream at rest before and
    /// after.
    fn ratios(stream: &[[f64; NA]], limits: &MotionLimits, dt: f64) -> [f64; 3] {
        let (first, last) = (stream[0], *stream.last().unwrap());
        let mut p = std::vec![first; 3];
        p.extend_from_slice(stream);
        p.extend([last; 3]);
        let mut r = [0.0f64; 3];
        for k in 3..p.len() {
            for j in 0..NA {
                let d1 = p[k][j] - p[k - 1][j];
                let d2 = p[k][j] - 2.0 * p[k - 1][j] + p[k - 2][j];
                let d3 = p[k][j] - 3.0 * p[k - 1][j] + 3.0 * p[k - 2][j] - p[k - 3][j];
                r[0] = r[0].max(d1.abs() / dt / limits.arm_speed[j]);
                r[1] = r[1].max(d2.abs() / (dt * dt) / limits.arm_acceleration[j]);
                r[2] = r[2].max(d3.abs() / (dt * dt * dt) / limits.arm_jerk[j]);
            }
        }
        r
    }

    /// Largest per-joint distance of `q` from the segment a–b.
    fn chord_distance(q: &[f64; NA], a: &[f64; NA], b: &[f64; NA]) -> f64 {
        let (mut ab, mut aq) = (0.0, 0.0);
        for j in 0..NA {
            ab += (b[j] - a[j]) * (b[j] - a[j]);
            aq += (q[j] - a[j]) * (b[j] - a[j]);
        }
        let t = if ab > 0.0 {
            (aq / ab).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (0..NA).fold(0.0f64, |m, j| {
            m.max((q[j] - a[j] - t * (b[j] - a[j])).abs())
        })
    }

    #[test]
    fn a_connect_move_ends_exactly_and_keeps_its_fraction_of_the_limits() {
        let model = RobotModel::kmr_iiwa14();
        let limits = MotionLimits::kmr_iiwa(&model);
        let from = model.home;
        for (d, fraction) in [(0.001, 0.25), (0.1, 0.25), (0.5, 0.5), (1e-9, 0.25)] {
            let to: [f64; NA] =
                core::array::from_fn(|j| from[j] + d * [1.0, -0.7, 0.3, 1.0, -1.0, 0.5, 0.9][j]);
            let mut c = Connect::new(from, to, &limits, fraction, 1e-3);
            let mut stream = std::vec![from];
            while !c.finished() {
                stream.push(c.setpoint());
            }
            assert_eq!(*stream.last().unwrap(), to, "ends exactly");
            assert_eq!(stream.len() as u32, c.ticks() + 1);
            let r = ratios(&stream, &limits, 1e-3);
            // Discretisation adds a little to the continuous peaks.
            assert!(r.iter().all(|x| *x <= fraction * 1.05), "d {d}: {r:?}");
        }
    }

    #[test]
    fn a_speed_outside_0_to_1_means_the_default_never_faster() {
        let model = RobotModel::kmr_iiwa14();
        let limits = MotionLimits::kmr_iiwa(&model);
        let to: [f64; NA] = core::array::from_fn(|j| model.home[j] + 0.1);
        let ticks = |f: f64| Connect::new(model.home, to, &limits, f, 1e-3).ticks();
        for bad in [0.0, -1.0, 2.0, f64::NAN, f64::INFINITY] {
            assert_eq!(ticks(bad), ticks(DEFAULT_SPEED), "fraction {bad}");
            let p = Playback::new(model.home, 10, bad, 1);
            assert_eq!(p.rate, DEFAULT_SPEED, "rate {bad}");
        }
        assert!(ticks(1.0) < ticks(DEFAULT_SPEED));
    }

    #[test]
    fn a_playback_passes_every_sample_and_starts_and_ends_at_rest() {
        let model = RobotModel::kmr_iiwa14();
        let limits = MotionLimits::kmr_iiwa(&model);
        // Samples of a motion at 1 ms moving at about 0.9 of the speed limit of A1 at its start
        // (P_0), slowing to rest at its end (P_k) with acceleration and jerk going to 0, as a
        // reversed RDMP motion does.
        let k = 900usize;
        let samples: Vec<[f64; NA]> = (0..=k)
            .map(|i| {
                let s = 1.0 - i as f64 / k as f64;
                core::array::from_fn(|j| {
                    model.home[j] + 0.3 * s * s * s * s * [1.0, 0.5, -0.5, 0.8, 0.2, -0.3, 0.4][j]
                })
            })
            .collect();
        let mut p = Playback::new(samples[0], samples.len() as u32, 0.25, 1000);
        let mut fed = 1;
        let mut stream = std::vec![samples[0]];
        let mut guard = 0;
        while !p.finished() {
            while p.wants() {
                p.feed(samples[fed]);
                fed += 1;
            }
            stream.push(p.setpoint());
            guard += 1;
            assert!(guard < 100 * k, "playback does not end");
        }
        assert_eq!(fed, samples.len(), "every sample handed in");
        assert_eq!(*stream.last().unwrap(), samples[k], "ends at P_k exactly");
        // Every setpoint lies on the polyline of the samples, within 1e-7 rad (the samples are
        // ≤ 1.5 mrad apart), visiting its segments in order.
        let mut seg = 0;
        for q in &stream {
            let off = |i: usize| chord_distance(q, &samples[i], &samples[i + 1]);
            while seg + 1 < k && off(seg + 1) < off(seg) {
                seg += 1;
            }
            assert!(off(seg) <= 1e-7, "{} rad off the path", off(seg));
        }
        assert_eq!(seg, k - 1, "every segment visited");
        let r = ratios(&stream, &limits, 1e-3);
        assert!(r.iter().all(|x| *x <= 0.3), "{r:?}");
        // About 4 ticks per sample once ramped up.
        assert!(
            stream.len() > 4 * k && stream.len() < 4 * k + 1500,
            "{}",
            stream.len()
        );
    }
}
