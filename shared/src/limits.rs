//! Motion limits of the KMR iiwa: the one home of the speed, acceleration and jerk limits that
//! the demonstration generator, the dataset check, the cell's Ruckig output stage and the
//! simulated joint controller all obey.

use crate::NA;
use crate::robot::RobotModel;

/// Speed, acceleration and jerk limits of the arm axes and the platform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionLimits {
    /// Arm joint position limits (lower, upper), rad.
    pub arm_position: [(f64, f64); NA],
    /// Arm joint speed limits, rad/s.
    pub arm_speed: [f64; NA],
    /// Arm joint acceleration limits, rad/s².
    pub arm_acceleration: [f64; NA],
    /// Arm joint jerk limits, rad/s³.
    pub arm_jerk: [f64; NA],
    /// Platform speed limits: x, y (m/s), yaw (rad/s).
    pub base_speed: [f64; 3],
    /// Platform acceleration limits: m/s², m/s², rad/s².
    pub base_acceleration: [f64; 3],
    /// Platform jerk limits: m/s³, m/s³, rad/s³.
    pub base_jerk: [f64; 3],
}

impl MotionLimits {
    /// The KMR iiwa: arm speeds from the model (the iiwa 14 data sheet); accelerations of
    /// 2 × the speed limit per second (full speed in 0.5 s) and jerks of 100 × the
    /// acceleration limit per second (full acceleration in 10 ms); platform 0.5 m/s, 0.5 rad/s, 0.5 m/s²,
    /// 0.5 rad/s², 1 m/s³, 1 rad/s³ (the KMR omniMove's safe speed is below its 0.9 m/s maximum).
    pub fn kmr_iiwa(model: &RobotModel) -> Self {
        let arm_speed: [f64; NA] = core::array::from_fn(|j| model.joints[j].max_speed);
        let arm_acceleration = arm_speed.map(|v| 2.0 * v);
        MotionLimits {
            arm_position: core::array::from_fn(|j| (model.joints[j].lower, model.joints[j].upper)),
            arm_speed,
            arm_acceleration,
            arm_jerk: arm_acceleration.map(|a| 100.0 * a),
            base_speed: [0.5, 0.5, 0.5],
            base_acceleration: [0.5, 0.5, 0.5],
            base_jerk: [1.0, 1.0, 1.0],
        }
    }
}

/// Peak ratios of a joint stream to its limits: 1.0 is at the limit, above is a violation.
/// Position is rated by the distance from the middle of the range (1.0 at either limit).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LimitRatios {
    /// max |2q − (lower + upper)| / (upper − lower).
    pub position: f64,
    /// max |q̇| / speed limit.
    pub speed: f64,
    /// max |q̈| / acceleration limit.
    pub acceleration: f64,
    /// max |q⃛| / jerk limit.
    pub jerk: f64,
}

impl LimitRatios {
    /// The largest of the four ratios.
    pub fn max(&self) -> f64 {
        self.position
            .max(self.speed)
            .max(self.acceleration)
            .max(self.jerk)
    }

    /// True when no limit is exceeded (every ratio ≤ 1; NaN is not within).
    pub fn within(&self) -> bool {
        self.max() <= 1.0
    }
}

impl core::fmt::Display for LimitRatios {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "position {:.3}, speed {:.3}, acceleration {:.3}, jerk {:.3} of the limits",
            self.position, self.speed, self.acceleration, self.jerk
        )
    }
}

/// Rates an arm joint stream sampled every Δt against [`MotionLimits`] by backward finite
/// differences: q̇_k = (q_k − q_{k−1})/Δt, q̈_k = (q̇_k − q̇_{k−1})/Δt, q⃛_k = (q̈_k − q̈_{k−1})/Δt.
/// The stream starts at rest (before it the arm stood still at its first sample) and
/// [`ArmMeter::stop`] rates the arm coming to rest after the last sample, so a stream rated
/// within limits can be joined to standstill on both sides. Allocation-free, O(7) per sample.
#[derive(Clone, Copy, Debug)]
pub struct ArmMeter {
    /// 1/(upper − lower), midpoint, 1/speed, 1/acceleration, 1/jerk per joint.
    inv_range: [f64; NA],
    middle: [f64; NA],
    inv_speed: [f64; NA],
    inv_acceleration: [f64; NA],
    inv_jerk: [f64; NA],
    dt: f64,
    q: [f64; NA],
    v: [f64; NA],
    a: [f64; NA],
    /// The last third difference.
    jerk: [f64; NA],
    ratios: LimitRatios,
}

/// The backward differences of a stream at a sample: velocity, acceleration and jerk per
/// joint, computed once per sample for both its rating and its record.
#[derive(Clone, Copy, Debug, Default)]
struct Differences {
    v: [f64; NA],
    a: [f64; NA],
    jerk: [f64; NA],
}

impl ArmMeter {
    /// A meter for a stream that starts at rest at `q0`, sampled every `dt` seconds.
    pub fn at_rest(limits: &MotionLimits, dt: f64, q0: &[f64; NA]) -> Self {
        let inv = |x: &[f64; NA]| x.map(|v| 1.0 / v);
        let mut m = ArmMeter {
            inv_range: limits.arm_position.map(|(l, u)| 2.0 / (u - l)),
            middle: limits.arm_position.map(|(l, u)| 0.5 * (l + u)),
            inv_speed: inv(&limits.arm_speed),
            inv_acceleration: inv(&limits.arm_acceleration),
            inv_jerk: inv(&limits.arm_jerk),
            dt,
            q: *q0,
            v: [0.0; NA],
            a: [0.0; NA],
            jerk: [0.0; NA],
            ratios: LimitRatios::default(),
        };
        m.ratios.position = m.rate(q0).position;
        m
    }

    /// The ratios of `q` alone as the next sample (nothing is recorded).
    pub fn rate(&self, q: &[f64; NA]) -> LimitRatios {
        self.rate_next(q, &self.next(q))
    }

    /// The backward differences (velocity, acceleration, jerk) with `q` as the next sample.
    fn next(&self, q: &[f64; NA]) -> Differences {
        let h = 1.0 / self.dt;
        let mut d = Differences::default();
        for j in 0..NA {
            d.v[j] = (q[j] - self.q[j]) * h;
            d.a[j] = (d.v[j] - self.v[j]) * h;
            d.jerk[j] = (d.a[j] - self.a[j]) * h;
        }
        d
    }

    /// The ratios of the next sample `q`, whose differences are `d`.
    fn rate_next(&self, q: &[f64; NA], d: &Differences) -> LimitRatios {
        let rate = |x: &[f64; NA], of: &[f64; NA], inv: &[f64; NA]| {
            peak(&core::array::from_fn(|j| f64::abs(x[j] - of[j]) * inv[j]))
        };
        const ZERO: [f64; NA] = [0.0; NA];
        LimitRatios {
            position: rate(q, &self.middle, &self.inv_range),
            speed: rate(&d.v, &ZERO, &self.inv_speed),
            acceleration: rate(&d.a, &ZERO, &self.inv_acceleration),
            jerk: rate(&d.jerk, &ZERO, &self.inv_jerk),
        }
    }

    /// [`ArmMeter::rate_next`] as a fold of [`nan_max`] over the joints from zero: the previous
    /// implementation, kept as the tests' reference.
    #[cfg(test)]
    fn rate_next_folded(&self, q: &[f64; NA], d: &Differences) -> LimitRatios {
        let mut r = LimitRatios::default();
        for j in 0..NA {
            r.position = nan_max(
                r.position,
                f64::abs(q[j] - self.middle[j]) * self.inv_range[j],
            );
            r.speed = nan_max(r.speed, f64::abs(d.v[j]) * self.inv_speed[j]);
            r.acceleration = nan_max(r.acceleration, f64::abs(d.a[j]) * self.inv_acceleration[j]);
            r.jerk = nan_max(r.jerk, f64::abs(d.jerk[j]) * self.inv_jerk[j]);
        }
        r
    }

    /// Rates the next sample.
    pub fn push(&mut self, q: &[f64; NA]) {
        let d = self.next(q);
        let r = self.rate_next(q, &d);
        self.record(q, &d, &r);
    }

    /// Records `q` as the next sample if it keeps every limit (true); otherwise the meter is
    /// left as it was (false).
    pub fn try_push(&mut self, q: &[f64; NA]) -> bool {
        let d = self.next(q);
        let r = self.rate_next(q, &d);
        let ok = r.within();
        if ok {
            self.record(q, &d, &r);
        }
        ok
    }

    /// Takes `q`, whose differences are `d` and ratios `r`, as the next sample.
    fn record(&mut self, q: &[f64; NA], d: &Differences, r: &LimitRatios) {
        self.q = *q;
        self.v = d.v;
        self.a = d.a;
        self.jerk = d.jerk;
        let m = &mut self.ratios;
        m.position = nan_max(m.position, r.position);
        m.speed = nan_max(m.speed, r.speed);
        m.acceleration = nan_max(m.acceleration, r.acceleration);
        m.jerk = nan_max(m.jerk, r.jerk);
    }

    /// Finite-difference velocity and acceleration at the last sample.
    pub fn state(&self) -> (&[f64; NA], &[f64; NA], &[f64; NA]) {
        (&self.q, &self.v, &self.a)
    }

    /// The state at the last sample of the cubic through the last four samples (its constant
    /// jerk is the last third difference): (q, q̇ + q̈Δt/2 + q⃛Δt²/3, q̈ + q⃛Δt) in the
    /// backward differences above. A trajectory that continues from it with |q⃛| ≤ the jerk
    /// limit is C² across the seam, so every third difference that straddles the seam — a
    /// B-spline-weighted mean of q⃛ — stays within the jerk limit too (the backward-difference
    /// state itself would add −q̈/(2Δt) to the first one).
    pub fn continuous_state(&self) -> ([f64; NA], [f64; NA], [f64; NA]) {
        let dt = self.dt;
        let v = core::array::from_fn(|j| {
            self.v[j] + self.a[j] * dt / 2.0 + self.jerk[j] * dt * dt / 3.0
        });
        let a = core::array::from_fn(|j| self.a[j] + self.jerk[j] * dt);
        (self.q, v, a)
    }

    /// The ratios that stopping after the last sample would add (the arm then holds that
    /// sample: two more samples bring speed and acceleration to zero).
    pub fn stop_ratios(&self) -> LimitRatios {
        let mut m = *self;
        m.ratios = LimitRatios::default();
        m.stop();
        m.ratios
    }

    /// Rates coming to rest at the last sample (the arm holds it from now on).
    pub fn stop(&mut self) {
        let q = self.q;
        self.push(&q);
        self.push(&q);
    }

    /// The peak ratios so far.
    pub fn ratios(&self) -> LimitRatios {
        self.ratios
    }

    /// The last sample.
    pub fn last(&self) -> &[f64; NA] {
        &self.q
    }
}

/// The largest of `x` and 0, NaN if any of `x` is (a NaN sample must not rate as within
/// limits): the [`nan_max`] fold from 0, as independent maxima and one NaN test instead of
/// a chain of branches.
#[inline(always)]
fn peak(x: &[f64; NA]) -> f64 {
    let m = x.iter().fold(0.0, |m, &v| if v > m { v } else { m });
    if x.iter().fold(false, |nan, v| nan | v.is_nan()) {
        f64::NAN
    } else {
        m
    }
}

/// max that propagates NaN (a NaN sample must not rate as within limits).
#[inline]
fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else if b > a {
        b
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::{vec, vec::Vec};

    fn limits() -> MotionLimits {
        MotionLimits {
            arm_position: [(-2.0, 2.0); NA],
            arm_speed: [1.0; NA],
            arm_acceleration: [2.0; NA],
            arm_jerk: [200.0; NA],
            base_speed: [0.5; 3],
            base_acceleration: [0.5; 3],
            base_jerk: [1.0; 3],
        }
    }

    /// Brute force: the whole stream padded with two rest samples on each side, third
    /// differences of the padded array.
    fn reference(q: &[f64], lim: &MotionLimits, dt: f64) -> LimitRatios {
        let mut p = vec![q[0]; 3];
        p.extend_from_slice(q);
        p.extend([q[q.len() - 1]; 2]);
        let d = |x: &[f64]| x.windows(2).map(|w| (w[1] - w[0]) / dt).collect::<Vec<_>>();
        let (v, a) = (d(&p), d(&d(&p)));
        let j = d(&a);
        let m = |x: &[f64], l: f64| x.iter().fold(0.0f64, |m, v| m.max(v.abs() / l));
        LimitRatios {
            position: m(q, 2.0),
            speed: m(&v, lim.arm_speed[0]),
            acceleration: m(&a, lim.arm_acceleration[0]),
            jerk: m(&j, lim.arm_jerk[0]),
        }
    }

    #[test]
    fn the_meter_matches_third_differences_of_the_padded_stream() {
        let lim = limits();
        let dt = 1e-3;
        // A smooth rise, then an acceleration step, then an abrupt stop.
        let q: Vec<f64> = (0..400)
            .map(|k| {
                let t = k as f64 * dt;
                if t < 0.2 {
                    0.5 * t * t
                } else {
                    0.02 + 0.2 * (t - 0.2)
                }
            })
            .collect();
        let mut m = ArmMeter::at_rest(&lim, dt, &[q[0]; NA]);
        for &x in &q[1..] {
            m.push(&[x; NA]);
        }
        m.stop();
        let want = reference(&q, &lim, dt);
        let got = m.ratios();
        for (g, w) in [
            (got.position, want.position),
            (got.speed, want.speed),
            (got.acceleration, want.acceleration),
            (got.jerk, want.jerk),
        ] {
            assert!((g - w).abs() <= 1e-9 * w.max(1.0), "{got:?} vs {want:?}");
        }
        // The abrupt stop at 0.2 rad/s: 200 rad/s² in one tick.
        assert!(got.acceleration > 99.0 && !got.within());
    }

    #[test]
    fn try_push_records_only_samples_within_the_limits() {
        let mut m = ArmMeter::at_rest(&limits(), 1e-3, &[0.0; NA]);
        // 1 mm/ms from rest is 1000 rad/s² in one tick: refused, nothing recorded.
        assert!(!m.try_push(&[1e-3; NA]));
        assert_eq!(m.state().0, &[0.0; NA]);
        assert_eq!(m.ratios().max(), 0.0);
        // A jerk-limited start (j = 100 rad/s³ for one tick) is taken.
        let q = 100.0 * 1e-9 / 6.0;
        assert!(m.try_push(&[q; NA]));
        assert_eq!(m.state().0, &[q; NA]);
        assert!(m.ratios().within() && m.ratios().jerk > 0.0);
    }

    #[test]
    fn a_nan_sample_is_not_within_limits() {
        let mut m = ArmMeter::at_rest(&limits(), 1e-3, &[0.0; NA]);
        let mut q = [0.0; NA];
        q[3] = f64::NAN;
        m.push(&q);
        assert!(!m.ratios().within());
    }

    /// The ratios of a sample are those of the `nan_max` fold, bit for bit (NaN where it
    /// gives NaN), on samples and differences that mix zeros of both signs, infinities, NaN
    /// and values of every size.
    #[test]
    fn the_rating_is_the_folds_bit_for_bit() {
        use rand::{RngExt, SeedableRng, rngs::StdRng};
        let mut rng = StdRng::seed_from_u64(20);
        let specials = [
            0.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            1e-300,
        ];
        let value = |rng: &mut StdRng| match rng.random_range(0..10) {
            0 => specials[rng.random_range(0..specials.len())],
            _ => rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-8..8)),
        };
        let bits = |r: LimitRatios| {
            [r.position, r.speed, r.acceleration, r.jerk]
                .map(|x| if x.is_nan() { u64::MAX } else { x.to_bits() })
        };
        for _ in 0..200_000 {
            let m = ArmMeter::at_rest(&limits(), 1e-3, &core::array::from_fn(|_| value(&mut rng)));
            let q = core::array::from_fn(|_| value(&mut rng));
            let d = Differences {
                v: core::array::from_fn(|_| value(&mut rng)),
                a: core::array::from_fn(|_| value(&mut rng)),
                jerk: core::array::from_fn(|_| value(&mut rng)),
            };
            assert_eq!(
                bits(m.rate_next(&q, &d)),
                bits(m.rate_next_folded(&q, &d)),
                "{q:?} {d:?}"
            );
        }
    }
}
