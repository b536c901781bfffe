//! The `ruckig` crate's wrapper (cxx, with std and a heap), kept callable as the reference the
//! shim is tested against and the baseline `prf bench-cell` times it against (feature
//! `baseline`; never in the controller build).

use std::vec;

use ruckig::{ControlInterface, InputParameter, OutputParameter, Ruckig, Synchronization};

use crate::online::{Code, DT, RuckigError};

/// [`crate::Online`]'s interface over the `ruckig` crate (dynamic DoFs).
pub struct Online<const N: usize> {
    ruckig: Ruckig,
    input: InputParameter,
    output: OutputParameter,
}

impl<const N: usize> Online<N> {
    pub fn new(
        position: &[f64; N],
        speed: &[f64; N],
        acceleration: &[f64; N],
        jerk: &[f64; N],
    ) -> Self {
        let mut input = InputParameter::new(N);
        input.current_position = position.to_vec();
        input.target_position = position.to_vec();
        input.max_velocity = speed.to_vec();
        input.max_acceleration = acceleration.to_vec();
        input.max_jerk = jerk.to_vec();
        Online {
            ruckig: Ruckig::new_direct(N, DT),
            input,
            output: OutputParameter::new_direct(N),
        }
    }

    pub fn set_state(&mut self, p: &[f64; N], v: &[f64; N], a: &[f64; N]) {
        self.input.current_position.copy_from_slice(p);
        self.input.current_velocity.copy_from_slice(v);
        self.input.current_acceleration.copy_from_slice(a);
    }

    pub fn set_phase_synchronised(&mut self) {
        self.input.synchronization = Synchronization::Phase;
    }

    pub fn go_to(&mut self, target: &[f64; N]) {
        self.input.control_interface = ControlInterface::Position;
        self.input.target_position = target.to_vec();
        self.input.target_velocity = vec![0.0; N];
        self.input.target_acceleration = vec![0.0; N];
    }

    pub fn track(&mut self, p: &[f64; N], v: &[f64; N], gain: f64) {
        self.input.control_interface = ControlInterface::Velocity;
        for j in 0..N {
            let m = 0.98 * self.input.max_velocity[j];
            self.input.target_velocity[j] =
                (v[j] + gain * (p[j] - self.input.current_position[j])).clamp(-m, m);
        }
        self.input.target_acceleration.fill(0.0);
    }

    pub fn brake(&mut self) {
        self.input.control_interface = ControlInterface::Velocity;
        self.input.target_velocity.fill(0.0);
        self.input.target_acceleration.fill(0.0);
    }

    pub fn step(&mut self) -> Result<bool, RuckigError> {
        let finished = match self.ruckig.update(&mut self.input, &mut self.output) {
            ruckig::Result::Working => false,
            ruckig::Result::Finished => true,
            e => {
                return Err(RuckigError::new(
                    Code::from_result(e as i32),
                    &self.input.current_position,
                ));
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
}
