//! `prf-ruckig`: jerk-limited motion with Ruckig (the official C++ library through the `ruckig` crate): the
//! platform's drive to a goal pose and the arm's stop trajectory. One [`Online`] generator per
//! use, stepped once per 1 ms cycle (Ruckig's online interface: it re-plans only when the
//! target changes).

use ruckig::{ControlInterface, InputParameter, OutputParameter, Ruckig};

/// Ruckig refused an update: its result code and the state it was given.
#[derive(Debug, thiserror::Error)]
#[error("Ruckig could not compute the next cycle ({code}) from position {position:?}")]
pub struct RuckigError {
    pub code: String,
    pub position: Vec<f64>,
}

/// Controller cycle of Ruckig, s.
pub const DT: f64 = 1e-3;

/// One online trajectory generator over `n` axes.
pub struct Online {
    ruckig: Ruckig,
    input: InputParameter,
    output: OutputParameter,
}

impl Online {
    /// At rest at `position`, with the given limits.
    pub fn new(position: &[f64], speed: &[f64], acceleration: &[f64], jerk: &[f64]) -> Self {
        let n = position.len();
        let mut input = InputParameter::new(n);
        input.current_position = position.to_vec();
        input.target_position = position.to_vec();
        input.max_velocity = speed.to_vec();
        input.max_acceleration = acceleration.to_vec();
        input.max_jerk = jerk.to_vec();
        Online {
            ruckig: Ruckig::new_direct(n, DT),
            input,
            output: OutputParameter::new_direct(n),
        }
    }

    /// Restarts from the state (position, velocity, acceleration): copied in place, no
    /// allocation.
    pub fn set_state(&mut self, p: &[f64], v: &[f64], a: &[f64]) {
        self.input.current_position.copy_from_slice(p);
        self.input.current_velocity.copy_from_slice(v);
        self.input.current_acceleration.copy_from_slice(a);
    }

    /// Rest-to-rest moves follow the straight line between start and target in every axis
    /// (Ruckig's phase synchronisation).
    pub fn set_phase_synchronised(&mut self) {
        self.input.synchronization = ruckig::Synchronization::Phase;
    }

    /// Drive to `target` (position interface), arriving at rest.
    pub fn go_to(&mut self, target: &[f64]) {
        self.input.control_interface = ControlInterface::Position;
        self.input.target_position = target.to_vec();
        self.input.target_velocity = vec![0.0; target.len()];
        self.input.target_acceleration = vec![0.0; target.len()];
    }

    /// Track a moving reference (position p, velocity v): the cell's output stage. Ruckig's
    /// velocity interface steers, jerk-limited, to the velocity v + K·(p − position), within
    /// the speed limit. (Its position interface would plan to reach the state (p, v) as if it
    /// stood still, and lags a moving reference by hundreds of ms.)
    pub fn track(&mut self, p: &[f64], v: &[f64], gain: f64) {
        self.input.control_interface = ControlInterface::Velocity;
        self.input.target_velocity = (0..p.len())
            .map(|j| {
                // 2 % below the limit: a jerk-limited approach may overshoot its target speed.
                let m = 0.98 * self.input.max_velocity[j];
                (v[j] + gain * (p[j] - self.input.current_position[j])).clamp(-m, m)
            })
            .collect();
        self.input.target_acceleration = vec![0.0; p.len()];
    }

    /// Brake to standstill as fast as the acceleration and jerk limits allow (velocity
    /// interface, target velocity 0).
    pub fn brake(&mut self) {
        let n = self.input.degrees_of_freedom;
        self.input.control_interface = ControlInterface::Velocity;
        self.input.target_velocity = vec![0.0; n];
        self.input.target_acceleration = vec![0.0; n];
    }

    /// One cycle: the new (position, velocity, acceleration). True once the target is reached.
    pub fn step(&mut self) -> Result<bool, RuckigError> {
        let r = self.ruckig.update(&mut self.input, &mut self.output);
        let finished = match r {
            ruckig::Result::Working => false,
            ruckig::Result::Finished => true,
            e => {
                return Err(RuckigError {
                    code: format!("{e:?}"),
                    position: self.input.current_position.clone(),
                });
            }
        };
        self.output.pass_to_input(&mut self.input);
        Ok(finished)
    }

    pub fn position(&self) -> &[f64] {
        &self.output.new_position
    }
    pub fn velocity(&self) -> &[f64] {
        &self.output.new_velocity
    }
    pub fn acceleration(&self) -> &[f64] {
        &self.output.new_acceleration
    }
    /// The current state as the input holds it (also before the first step).
    pub fn current(&self) -> (&[f64], &[f64], &[f64]) {
        (
            &self.input.current_position,
            &self.input.current_velocity,
            &self.input.current_acceleration,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A platform-like move: reaches the goal exactly, at rest, within every limit, and a
    /// brake from full speed stops within the limits.
    #[test]
    fn go_to_and_brake_stay_within_limits() {
        let lim = ([0.5; 3], [0.5; 3], [1.0; 3]);
        let mut m = Online::new(&[0.0; 3], &lim.0, &lim.1, &lim.2);
        m.go_to(&[2.0, -1.0, 0.5]);
        let (mut v0, mut a0) = (vec![0.0; 3], vec![0.0; 3]);
        let mut steps = 0;
        while !m.step().unwrap() {
            steps += 1;
            for k in 0..3 {
                assert!(m.velocity()[k].abs() <= 0.5 + 1e-9);
                assert!(m.acceleration()[k].abs() <= 0.5 + 1e-9);
                assert!((m.acceleration()[k] - a0[k]).abs() / DT <= 1.0 + 1e-6);
                assert!(((m.velocity()[k] - v0[k]) / DT).abs() <= 0.5 + 1e-3);
            }
            v0 = m.velocity().to_vec();
            a0 = m.acceleration().to_vec();
            assert!(steps < 20_000);
        }
        for (p, g) in m.position().iter().zip([2.0, -1.0, 0.5]) {
            assert!((p - g).abs() < 1e-9);
        }
        // brake from (0, 0.5, 0) moving
        m.set_state(&[0.0; 3], &[0.5, -0.5, 0.2], &[0.0; 3]);
        m.brake();
        let mut n = 0;
        while !m.step().unwrap() {
            n += 1;
            assert!(n < 5000);
        }
        assert!(m.velocity().iter().all(|v| v.abs() < 1e-9));
    }
}
