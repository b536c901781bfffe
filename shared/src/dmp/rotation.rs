//! Rotation DMPs on SO(3) (Eq. 2): τη̇ = α_z(β_z log(R_g R⁻¹) − η) + f(ζ), τṘ = η̂R.
//!
//! The goal error e = log(R_g R⁻¹) is kept continuous (unwrapped past π with
//! [`crate::se3::log_near`]), in training and in integration, so a demonstration that turns by
//! more than 180° is learned and reproduced the way it went, without flipping to the short
//! way round. The initial error of a new integration is taken on the branch closest to the
//! demonstrated travel.

use super::forcing::{Ahead, Forcing};
use super::phase::{Basis, Phase};
use super::{DmpError, DmpParams, check_demo, sample_derivatives, spring};
use crate::se3::{Rot, exp, log, log_near};
use nalgebra::Vector3;

/// A trained rotation DMP.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotationDmp {
    /// Gains, bases and duration.
    pub params: DmpParams,
    /// Demonstrated duration τ, s.
    pub tau: f64,
    /// The learned forcing term.
    pub forcing: Forcing<3>,
    /// Demonstrated initial goal error e(0), unwrapped: its norm is the total rotation travel.
    pub travel: Vector3<f64>,
}

/// State of a rotation DMP during integration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotationState {
    /// Orientation R.
    pub r: Rot,
    /// Scaled angular velocity η = τω (world frame).
    pub eta: Vector3<f64>,
    /// Goal orientation R_g.
    pub goal: Rot,
    /// D_R = log(R_g R(0)⁻¹) of this integration (Eq. 3).
    pub amplitude: Vector3<f64>,
    /// Last goal error, the reference for unwrapping.
    pub error: Vector3<f64>,
}

impl RotationDmp {
    /// Train (Eq. 4) on rotations R_k sampled every `dt` seconds, `sample(k)` for k in 0..n.
    pub fn train(
        params: &DmpParams,
        dt: f64,
        n: usize,
        sample: impl Fn(usize) -> Rot,
    ) -> Result<Self, DmpError> {
        check_demo(params, n, dt)?;
        let tau = (n - 1) as f64 * dt;
        let goal = sample(n - 1);
        // Unwrap e_k = log(R_g R_k⁻¹) backwards from e_{n−1} = 0; `errors(k)` is only ever
        // called in descending k.
        let unwrapped = |reference: &mut Vector3<f64>, k: usize| {
            *reference = log_near(&(goal * sample(k).inverse()), reference);
            *reference
        };
        let mut e = Vector3::zeros();
        for k in (0..n).rev() {
            unwrapped(&mut e, k);
        }
        let travel = e;
        let basis = Basis::new(params)?;
        let omega_half = |j: usize| log(&(sample(j + 1) * sample(j).inverse())) / dt;
        let mut e = Vector3::zeros();
        let forcing = Forcing::fit(params, &basis, &travel, n, |i| {
            let k = n - 1 - i;
            let e_k = unwrapped(&mut e, k);
            let (w, a) = sample_derivatives(n, k, dt, omega_half);
            let zeta = libm::exp(-params.alpha_zeta * k as f64 * dt / tau);
            // f = τ²ω̇ − α_z(β_z e − τω)
            let f = a * (tau * tau) - (e_k * params.beta_z - w * tau) * params.alpha_z;
            (zeta, f)
        })?;
        Ok(RotationDmp {
            params: *params,
            tau,
            forcing,
            travel,
        })
    }

    /// Initial state and phase of an integration from `r0` to `goal` with step `dt`.
    pub fn start(&self, r0: &Rot, goal: &Rot, dt: f64) -> Result<(RotationState, Phase), DmpError> {
        if r0
            .coords
            .iter()
            .chain(goal.coords.iter())
            .any(|v| !v.is_finite())
        {
            return Err(DmpError::NonFinite { sample: 0 });
        }
        Ok((
            RotationState::new(r0, goal, &self.travel),
            Phase::new(&self.params, self.tau, dt)?,
        ))
    }

    /// Integrate (Eq. 5) as a whole trajectory into `out`; returns the number of samples.
    pub fn integrate(
        &self,
        r0: &Rot,
        goal: &Rot,
        dt: f64,
        out: &mut [Rot],
    ) -> Result<usize, DmpError> {
        let (mut state, mut phase) = self.start(r0, goal, dt)?;
        let need = phase.n_steps + 1;
        if out.len() < need {
            return Err(DmpError::BufferTooSmall { need });
        }
        out[0] = state.r;
        let mut ahead = None;
        while !phase.finished() {
            state.step(
                &self.params,
                &self.forcing,
                self.tau,
                dt,
                &phase,
                &mut ahead,
            );
            phase.advance();
            out[phase.step] = state.r;
        }
        Ok(need)
    }
}

impl RotationState {
    /// Starts at `r0`; the initial error is taken on the branch nearest `travel`.
    pub fn new(r0: &Rot, goal: &Rot, travel: &Vector3<f64>) -> Self {
        let e0 = log_near(&(goal * r0.inverse()), travel);
        RotationState {
            r: *r0,
            eta: Vector3::zeros(),
            goal: *goal,
            amplitude: e0,
            error: e0,
        }
    }

    /// One Heun step on SO(3) from ζ_k to ζ_{k+1}; returns the mean angular velocity ω over
    /// the step, so that R_{k+1} = exp(Δt·ω) R_k exactly. `ahead` carries f(ζ_{k+1}) to the
    /// next step.
    #[inline]
    pub fn step(
        &mut self,
        p: &DmpParams,
        forcing: &Forcing<3>,
        tau: f64,
        dt: f64,
        phase: &Phase,
        ahead: &mut Ahead<3>,
    ) -> Vector3<f64> {
        let h = dt / tau;
        let e1 = log_near(&(self.goal * self.r.inverse()), &self.error);
        let f1 = forcing.current(phase, &self.amplitude, *ahead);
        let etad1 = spring(p, &e1, &self.eta, &f1);
        let r_pred = exp(&(self.eta * h)) * self.r;
        let eta_pred = self.eta + etad1 * h;
        let e2 = log_near(&(self.goal * r_pred.inverse()), &e1);
        let f2 = forcing.eval(phase.next(), &self.amplitude);
        *ahead = Some((phase.step + 1, f2));
        let etad2 = spring(p, &e2, &eta_pred, &f2);
        let omega = (self.eta + eta_pred) * (0.5 / tau);
        self.r = exp(&(omega * dt)) * self.r;
        self.eta += (etad1 + etad2) * (0.5 * h);
        self.error = e1;
        omega
    }
}
