//! The output stage between the executor and the joint controller, one for the host cell and
//! the Cortex-M7 firmware: the executor's [`Plant`], whose measured state is the newest joint
//! state. A setpoint that keeps the emitted stream within the position, speed, acceleration
//! and jerk limits (rated by finite differences at 1 ms, as the controller sees it) passes
//! unchanged: a planned program is certified within the limits, so what is emitted is what
//! was certified. Otherwise Ruckig shapes it (the safety net; every shaped tick is counted),
//! and on a fault or a stop request Ruckig brakes from the emitted state.

use core::convert::Infallible;

use prf_runtime::executor::{Measured, Mode, Plant, Setpoint};
use prf_shared::NA;
use prf_shared::limits::{ArmMeter, LimitRatios, MotionLimits};

use crate::online::{DT, Online, RuckigError};

/// Position gain of the safety net's tracking, 1/s (see [`Online::track`]).
pub const TRACKING_GAIN: f64 = 20.0;

/// The output stage (see the module).
pub struct OutputStage {
    ruckig: Online<NA>,
    /// Rates the emitted stream; its state is the emitted setpoint.
    meter: ArmMeter,
    measured: Measured,
    /// Brake instead of tracking (a fault, or a stop on request).
    stopping: bool,
    /// The output is at rest (set by the last command).
    settled: bool,
    /// Ruckig holds the emitted state (it emitted the last sample, or took the stream over).
    ruckig_current: bool,
    /// Ticks whose setpoint Ruckig had to change, and the largest change, rad.
    shaped: u64,
    max_shaping: f64,
}

impl OutputStage {
    /// At rest at `q`.
    pub fn new(q: &[f64; NA], limits: &MotionLimits, measured: Measured) -> Self {
        let l = limits;
        OutputStage {
            ruckig: Online::new(q, &l.arm_speed, &l.arm_acceleration, &l.arm_jerk),
            meter: ArmMeter::at_rest(limits, DT, q),
            measured,
            stopping: false,
            settled: false,
            ruckig_current: true,
            shaped: 0,
            max_shaping: 0.0,
        }
    }

    /// The joint state the executor sees next.
    pub fn set_measured(&mut self, m: Measured) {
        self.measured = m;
    }

    /// From now on brake to rest, whatever the executor commands.
    pub fn stop(&mut self) {
        self.stopping = true;
    }

    pub fn stopping(&self) -> bool {
        self.stopping
    }

    /// The emitted stream is at rest.
    pub fn settled(&self) -> bool {
        self.settled
    }

    /// The emitted position and velocity.
    pub fn output(&self) -> ([f64; NA], [f64; NA]) {
        let (q, v, _) = self.meter.state();
        (*q, *v)
    }

    /// `sp` with the emitted arm position and velocity: what leaves the controller.
    pub fn emitted(&self, sp: &Setpoint) -> Setpoint {
        let (arm, arm_velocity) = self.output();
        Setpoint {
            arm,
            arm_velocity,
            ..*sp
        }
    }

    /// Ticks Ruckig shaped, and the largest change it made to a setpoint, rad.
    pub fn shaped(&self) -> (u64, f64) {
        (self.shaped, self.max_shaping)
    }

    /// The emitted stream's worst ratios to the limits so far.
    pub fn ratios(&self) -> LimitRatios {
        self.meter.ratios()
    }

    /// Gives Ruckig the emitted stream's state if passed setpoints moved it on since Ruckig's
    /// last sample: the state of the cubic through the last four samples
    /// ([`ArmMeter::continuous_state`]), so the stream stays C² and within the jerk limit
    /// across the seam. Passing setpoints costs nothing per tick.
    fn take_over(&mut self) {
        if !self.ruckig_current {
            let (q, v, a) = self.meter.continuous_state();
            self.ruckig.set_state(&q, &v, &a);
            self.ruckig_current = true;
        }
    }

    /// Emits Ruckig's next sample. Where Ruckig reaches a target at rest (`to_rest`: a brake,
    /// or landing on a reference at rest) the stage holds that sample exactly (Ruckig's own
    /// samples at rest may still differ in the last bits). It is settled once the emitted
    /// samples stand still — finite-difference velocity and acceleration zero — so the last
    /// setpoint of a stop carries q̇ = 0.
    fn emit_ruckig(&mut self, to_rest: bool) -> Result<(), RuckigError> {
        let reached = self.ruckig.step()?;
        let q = *self.ruckig.position();
        if reached && to_rest {
            self.ruckig.set_state(&q, &[0.0; NA], &[0.0; NA]);
        }
        self.meter.push(&q);
        let (_, v, a) = self.meter.state();
        self.settled = reached && v.iter().chain(a).all(|x| *x == 0.0);
        Ok(())
    }
}

impl Plant for OutputStage {
    type Error = RuckigError;

    fn emitted(&self, sp: &Setpoint) -> Setpoint {
        OutputStage::emitted(self, sp)
    }

    fn measured(&self) -> Measured {
        self.measured
    }

    /// Passes the setpoint when it keeps the stream within the limits, else shapes it with
    /// Ruckig (tracking a moving reference, landing on one at rest); brakes on a fault or a
    /// stop request.
    fn command(&mut self, sp: &Setpoint) -> Result<(), RuckigError> {
        if sp.mode == Mode::Fault || self.stopping {
            self.take_over();
            self.ruckig.brake();
            return self.emit_ruckig(true);
        }
        if self.meter.try_push(&sp.arm) {
            self.ruckig_current = false;
            let (_, v, a) = self.meter.state();
            self.settled = v.iter().chain(a).all(|x| *x == 0.0);
            return Ok(());
        }
        self.take_over();
        let to_rest = sp.arm_velocity.iter().all(|v| *v == 0.0);
        if to_rest {
            // A reference at rest: land on it exactly (position interface), after which its
            // setpoints pass again.
            self.ruckig.go_to(&sp.arm);
        } else {
            self.ruckig.track(&sp.arm, &sp.arm_velocity, TRACKING_GAIN);
        }
        self.emit_ruckig(to_rest)?;
        let (q, _, _) = self.meter.state();
        let off = q
            .iter()
            .zip(&sp.arm)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        self.shaped += 1;
        self.max_shaping = self.max_shaping.max(off);
        Ok(())
    }
}

/// The [`OutputStage`] in front of a plant that cannot refuse a setpoint (the ideal cell): the
/// firmware's cell, and the host's reference of the firmware's stream. The plant measures, the
/// stage passes or shapes, the plant takes what was emitted.
pub struct StagedCell<P> {
    pub stage: OutputStage,
    pub plant: P,
}

impl<P: Plant<Error = Infallible>> StagedCell<P> {
    /// The stage at rest at the plant's measured arm position.
    pub fn new(plant: P, limits: &MotionLimits) -> Self {
        let m = plant.measured();
        StagedCell {
            stage: OutputStage::new(&m.arm, limits, m),
            plant,
        }
    }
}

impl<P: Plant<Error = Infallible>> Plant for StagedCell<P> {
    type Error = RuckigError;

    fn measured(&self) -> Measured {
        self.plant.measured()
    }

    fn command(&mut self, sp: &Setpoint) -> Result<(), RuckigError> {
        self.stage.set_measured(self.plant.measured());
        self.stage.command(sp)?;
        let Ok(()) = self.plant.command(&self.stage.emitted(sp));
        Ok(())
    }

    fn emitted(&self, sp: &Setpoint) -> Setpoint {
        self.stage.emitted(sp)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embassy_time::Instant;
    use prf_shared::limits::LimitRatios;
    use std::vec::Vec;

    fn limits() -> MotionLimits {
        MotionLimits {
            arm_position: [(-3.0, 3.0); NA],
            arm_speed: [1.0; NA],
            arm_acceleration: [2.0; NA],
            arm_jerk: [200.0; NA],
            base_speed: [0.5; 3],
            base_acceleration: [0.5; 3],
            base_jerk: [1.0; 3],
        }
    }

    fn setpoint(seq: u32, arm: [f64; NA], mode: Mode) -> Setpoint {
        Setpoint {
            seq,
            t: Instant::from_ticks(seq as u64),
            arm,
            arm_velocity: [0.0; NA],
            close_gripper: false,
            base_goal: [0.0; 3],
            mode,
            segment: 0,
        }
    }

    fn at_rest(q: &[f64; NA]) -> Measured {
        Measured {
            arm: *q,
            base: [0.0; 3],
            gripper: 0.0,
        }
    }

    /// Independent rating of an emitted stream that starts and ends at rest (its first sample
    /// is the rest position): third differences of the stream padded with rest samples.
    fn rate(stream: &[[f64; NA]], l: &MotionLimits) -> LimitRatios {
        let mut r = LimitRatios::default();
        for j in 0..NA {
            let mut p: Vec<f64> = [stream[0][j]; 3].to_vec();
            p.extend(stream.iter().map(|q| q[j]));
            p.extend([stream[stream.len() - 1][j]; 3]);
            let d = |x: &[f64]| x.windows(2).map(|w| (w[1] - w[0]) / DT).collect::<Vec<_>>();
            let (v, a) = (d(&p), d(&d(&p)));
            let k = d(&a);
            let m = |x: &[f64]| x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            r.speed = r.speed.max(m(&v) / l.arm_speed[j]);
            r.acceleration = r.acceleration.max(m(&a) / l.arm_acceleration[j]);
            r.jerk = r.jerk.max(m(&k) / l.arm_jerk[j]);
        }
        r
    }

    /// Commands the `stream` (ticks 1, 2, …) from rest at `q0`, then faults until the stage is
    /// at rest; asserts nothing was shaped and returns every emitted sample.
    fn stream_then_fault(stream: &[[f64; NA]], q0: [f64; NA], l: &MotionLimits) -> Vec<[f64; NA]> {
        let mut stage = OutputStage::new(&q0, l, at_rest(&q0));
        let mut out = std::vec![q0];
        for (k, q) in stream.iter().enumerate() {
            stage
                .command(&setpoint(k as u32 + 1, *q, Mode::Arm))
                .unwrap();
            out.push(stage.output().0);
        }
        assert_eq!(stage.shaped().0, 0, "the stream passes");
        let moving = stage.output().1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(moving > 0.1, "moving at {moving} rad/s");
        let mut k = stream.len() as u32 + 1;
        while !stage.settled() {
            stage.command(&setpoint(k, q0, Mode::Fault)).unwrap();
            out.push(stage.output().0);
            k += 1;
            assert!(k < 5000, "still moving");
        }
        out
    }

    /// A smooth move within the limits (quintic smoothstep, 0.3 rad in 3 s) passes bit for
    /// bit, and nothing is shaped.
    #[test]
    fn a_certified_stream_passes_unchanged() {
        let l = limits();
        let q0 = [0.1; NA];
        let mut stage = OutputStage::new(&q0, &l, at_rest(&q0));
        let n = 3000;
        for k in 1..=n + 10 {
            let s = (k.min(n) as f64 / n as f64).clamp(0.0, 1.0);
            let s = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
            let q = q0.map(|x| x + 0.3 * s);
            let sp = setpoint(k as u32, q, Mode::Arm);
            stage.command(&sp).unwrap();
            assert_eq!(stage.emitted(&sp).arm, q, "tick {k}");
        }
        assert_eq!(stage.shaped(), (0, 0.0));
        assert!(stage.settled());
        assert!(stage.ratios().within());
    }

    /// A step of 0.2 rad is shaped: the emitted stream stays within every limit (rated
    /// independently), reaches the step, and from there passes the setpoints again.
    #[test]
    fn a_step_is_shaped_within_the_limits() {
        let l = limits();
        let q0 = [0.0; NA];
        let mut stage = OutputStage::new(&q0, &l, at_rest(&q0));
        let goal = [0.2; NA];
        let mut out = std::vec![q0];
        for k in 1..=3000 {
            stage.command(&setpoint(k, goal, Mode::Arm)).unwrap();
            out.push(stage.output().0);
        }
        let (shaped, max) = stage.shaped();
        assert!(shaped > 0 && max > 0.1, "{shaped} ticks shaped, max {max}");
        let r = rate(&out, &l);
        assert!(r.max() <= 1.0 + 1e-9, "{r}");
        let last = out[out.len() - 1];
        assert!(last.iter().all(|q| (q - 0.2).abs() < 1e-9), "{last:?}");
        let before = stage.shaped().0;
        stage.command(&setpoint(3001, goal, Mode::Arm)).unwrap();
        assert_eq!(stage.shaped().0, before, "at the goal the setpoint passes");
    }

    /// A fault mid-motion: Ruckig brakes from the emitted state to rest, within the limits.
    #[test]
    fn a_fault_brakes_to_rest_within_the_limits() {
        let l = limits();
        let stream: Vec<[f64; NA]> = (1..=1000)
            .map(|k| {
                let t = k as f64 * DT;
                [0.2 * t * t * t / (1.0 + t * t); NA]
            })
            .collect();
        let r = rate(&stream_then_fault(&stream, [0.0; NA], &l), &l);
        assert!(r.max() <= 1.0 + 1e-9, "{r}");
    }

    /// A fault while the stream accelerates at 0.9 of the limit: the brake takes over from the
    /// stream's continuous state, so the third differences across the seam keep the jerk limit
    /// (from the backward-difference state the first one would be q̈/(2Δt) = 900 rad/s³,
    /// 4.5× the limit).
    #[test]
    fn a_fault_at_full_acceleration_brakes_within_the_jerk_limit() {
        let l = limits();
        let q0 = [0.0; NA];
        let (jerk, ramp) = (150.0, 0.012); // reaches 1.8 rad/s² in 12 ms
        let q_of = |t: f64| {
            if t <= ramp {
                jerk * t * t * t / 6.0
            } else {
                let (a, v, p) = (
                    jerk * ramp,
                    jerk * ramp * ramp / 2.0,
                    jerk * ramp.powi(3) / 6.0,
                );
                let s = t - ramp;
                p + v * s + a * s * s / 2.0
            }
        };
        let stream: Vec<[f64; NA]> = (1..=200).map(|k| [q_of(k as f64 * DT); NA]).collect();
        let out = stream_then_fault(&stream, q0, &l);
        let r = rate(&out, &l);
        assert!(r.max() <= 1.0 + 1e-9, "{r}");
    }
}
