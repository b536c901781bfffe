//! The per-joint position servo of the simulated iiwa, a drive's cascade: a position loop
//! commands a velocity, q̇_cmd = q̇_ref + s(e), e = q_ref − q, s(e) = sign(e)·min(K_p|e|,
//! √(2·a_max·|e|)); a velocity loop commands the acceleration q̈ = q̈_ref + K_v(q̇_cmd − q̇),
//! saturated at the joint's acceleration and speed limits. With K_p = ω/(2ζ), K_v = 2ζω the
//! small-error loop is the second-order q̈ = q̈_ref + ω²e + 2ζω·ė; the √ branch is the braking
//! curve that keeps a large error from overshooting into a limit cycle under saturation.
//! Integrated with semi-implicit Euler in sub-steps (ω·h ≪ 1).

use prf_shared::NA;

/// Servo parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ServoConfig {
    /// Closed-loop bandwidth, Hz (ω = 2π·bandwidth).
    pub bandwidth_hz: f64,
    /// Damping ratio ζ.
    pub damping: f64,
    /// Integration sub-steps per controller cycle.
    pub substeps: u32,
}

impl Default for ServoConfig {
    /// 20 Hz, critically damped: a stiff industrial position loop.
    fn default() -> Self {
        ServoConfig {
            bandwidth_hz: 20.0,
            damping: 1.0,
            substeps: 10,
        }
    }
}

/// The arm's seven joint servos.
#[derive(Clone, Debug)]
pub struct ArmServo {
    pub cfg: ServoConfig,
    pub q: [f64; NA],
    pub qd: [f64; NA],
    /// Last commanded acceleration (for the brake's initial state).
    pub qdd: [f64; NA],
    speed: [f64; NA],
    acceleration: [f64; NA],
}

impl ArmServo {
    /// At rest at `q`, with the joints' speed and acceleration limits.
    pub fn new(cfg: ServoConfig, q: [f64; NA], speed: [f64; NA], acceleration: [f64; NA]) -> Self {
        ArmServo {
            cfg,
            q,
            qd: [0.0; NA],
            qdd: [0.0; NA],
            speed,
            acceleration,
        }
    }

    /// Advances by `dt` towards the reference (q_ref, q̇_ref, q̈_ref).
    pub fn step(&mut self, q_ref: &[f64; NA], qd_ref: &[f64; NA], qdd_ref: &[f64; NA], dt: f64) {
        let w = 2.0 * core::f64::consts::PI * self.cfg.bandwidth_hz;
        let (kp, kv) = (w / (2.0 * self.cfg.damping), 2.0 * self.cfg.damping * w);
        let n = self.cfg.substeps.max(1);
        let h = dt / n as f64;
        for _ in 0..n {
            for j in 0..NA {
                let e = q_ref[j] - self.q[j];
                let a_max = self.acceleration[j];
                let s = (kp * e.abs()).min((2.0 * a_max * e.abs()).sqrt());
                let v_cmd = qd_ref[j] + s.copysign(e);
                let a = (qdd_ref[j] + kv * (v_cmd - self.qd[j])).clamp(-a_max, a_max);
                self.qdd[j] = a;
                self.qd[j] = (self.qd[j] + a * h).clamp(-self.speed[j], self.speed[j]);
                self.q[j] += self.qd[j] * h;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A step response of the linear loop matches the closed form of a critically damped
    /// second-order system, q(t) = 1 − (1 + ωt)e^(−ωt), to the integration error.
    #[test]
    fn step_response_matches_closed_form() {
        let cfg = ServoConfig {
            bandwidth_hz: 5.0,
            damping: 1.0,
            substeps: 100,
        };
        let mut s = ArmServo::new(cfg, [0.0; NA], [1e9; NA], [1e9; NA]);
        let w = 2.0 * core::f64::consts::PI * 5.0;
        for k in 1..=200 {
            s.step(&[1.0; NA], &[0.0; NA], &[0.0; NA], 1e-3);
            let t = k as f64 * 1e-3;
            let exact = 1.0 - (1.0 + w * t) * (-w * t).exp();
            assert!(
                (s.q[0] - exact).abs() < 1e-3,
                "t {t}: {} vs {exact}",
                s.q[0]
            );
        }
    }

    /// Saturation: a far reference is approached at no more than the speed and acceleration
    /// limits.
    #[test]
    fn respects_speed_and_acceleration_limits() {
        let mut s = ArmServo::new(ServoConfig::default(), [0.0; NA], [1.0; NA], [2.0; NA]);
        let mut qd_prev = [0.0; NA];
        for _ in 0..10000 {
            s.step(&[3.0; NA], &[0.0; NA], &[0.0; NA], 1e-3);
            for j in 0..NA {
                assert!(s.qd[j].abs() <= 1.0 + 1e-12);
                assert!((s.qd[j] - qd_prev[j]).abs() / 1e-3 <= 2.0 + 1e-9);
            }
            qd_prev = s.qd;
        }
        assert!((s.q[0] - 3.0).abs() < 1e-3, "settles: {}", s.q[0]);
    }
}
