//! Position DMPs in R^N (Eq. 1): τż = α_z(β_z(g − y) − z) + f(ζ), τẏ = z.

use super::forcing::{Ahead, Forcing};
use super::phase::{Basis, Phase};
use super::{DmpError, DmpParams, check_demo, sample_derivatives, spring};
use nalgebra::SVector;

/// A trained N-dimensional position DMP.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositionDmp<const N: usize> {
    /// Gains, bases and duration.
    pub params: DmpParams,
    /// Demonstrated duration τ, s.
    pub tau: f64,
    /// The learned forcing term.
    pub forcing: Forcing<N>,
}

/// State of a position DMP during integration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositionState<const N: usize> {
    /// Position y.
    pub y: SVector<f64, N>,
    /// Scaled velocity z = τẏ.
    pub z: SVector<f64, N>,
    /// Goal g.
    pub goal: SVector<f64, N>,
    /// D = g − y0 of this integration (Eq. 3).
    pub amplitude: SVector<f64, N>,
}

impl<const N: usize> PositionDmp<N> {
    /// Train (Eq. 4): fits the forcing term of a demonstration y_k sampled every `dt` seconds,
    /// `sample(k)` for k in 0..n. τ is the demonstration's duration (n−1)Δt.
    pub fn train(
        params: &DmpParams,
        dt: f64,
        n: usize,
        sample: impl Fn(usize) -> SVector<f64, N>,
    ) -> Result<Self, DmpError> {
        check_demo(params, n, dt)?;
        let tau = (n - 1) as f64 * dt;
        let (y0, goal) = (sample(0), sample(n - 1));
        let basis = Basis::new(params)?;
        let forcing = Forcing::fit(params, &basis, &(goal - y0), n, |k| {
            let (v, a) = sample_derivatives(n, k, dt, |j| (sample(j + 1) - sample(j)) / dt);
            let zeta = libm::exp(-params.alpha_zeta * k as f64 * dt / tau);
            // f = τ²ÿ − α_z(β_z(g − y) − τẏ)
            let f =
                a * (tau * tau) - ((goal - sample(k)) * params.beta_z - v * tau) * params.alpha_z;
            (zeta, f)
        })?;
        Ok(PositionDmp {
            params: *params,
            tau,
            forcing,
        })
    }

    /// Initial state and phase of an integration from `y0` to `goal` with step `dt`.
    pub fn start(
        &self,
        y0: &SVector<f64, N>,
        goal: &SVector<f64, N>,
        dt: f64,
    ) -> Result<(PositionState<N>, Phase), DmpError> {
        self.start_on(None, y0, goal, dt)
    }

    /// [`PositionDmp::start`] with the phase's bases taken from `basis` when they are this
    /// DMP's ([`Phase::new_on`]).
    pub fn start_on(
        &self,
        basis: Option<&Basis>,
        y0: &SVector<f64, N>,
        goal: &SVector<f64, N>,
        dt: f64,
    ) -> Result<(PositionState<N>, Phase), DmpError> {
        if y0.iter().chain(goal.iter()).any(|v| !v.is_finite()) {
            return Err(DmpError::NonFinite { sample: 0 });
        }
        Ok((
            PositionState::new(y0, goal),
            Phase::new_on(basis, &self.params, self.tau, dt)?,
        ))
    }

    /// Integrate (Eq. 5) as a whole trajectory: writes y at t = 0, Δt, …, τ into `out` and
    /// returns the number of samples (round(τ/Δt) + 1).
    pub fn integrate(
        &self,
        y0: &SVector<f64, N>,
        goal: &SVector<f64, N>,
        dt: f64,
        out: &mut [SVector<f64, N>],
    ) -> Result<usize, DmpError> {
        let (mut state, mut phase) = self.start(y0, goal, dt)?;
        let need = phase.n_steps + 1;
        if out.len() < need {
            return Err(DmpError::BufferTooSmall { need });
        }
        out[0] = state.y;
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
            out[phase.step] = state.y;
        }
        Ok(need)
    }
}

impl<const N: usize> PositionState<N> {
    /// At rest at `y0`, heading for `goal`.
    pub fn new(y0: &SVector<f64, N>, goal: &SVector<f64, N>) -> Self {
        PositionState {
            y: *y0,
            z: SVector::zeros(),
            goal: *goal,
            amplitude: goal - y0,
        }
    }

    /// One Heun step from phase ζ_k to ζ_{k+1}; returns the mean velocity ẏ over the step, so
    /// that y_{k+1} = y_k + Δt·ẏ exactly. `ahead` carries f(ζ_{k+1}) to the next step.
    #[inline]
    pub fn step(
        &mut self,
        p: &DmpParams,
        forcing: &Forcing<N>,
        tau: f64,
        dt: f64,
        phase: &Phase,
        ahead: &mut Ahead<N>,
    ) -> SVector<f64, N> {
        let h = dt / tau;
        let f1 = forcing.current(phase, &self.amplitude, *ahead);
        let zd1 = spring(p, &(self.goal - self.y), &self.z, &f1);
        let (y_pred, z_pred) = (self.y + self.z * h, self.z + zd1 * h);
        let f2 = forcing.eval(phase.next(), &self.amplitude);
        *ahead = Some((phase.step + 1, f2));
        let zd2 = spring(p, &(self.goal - y_pred), &z_pred, &f2);
        let vel = (self.z + z_pred) * (0.5 / tau);
        self.y += vel * dt;
        self.z += (zd1 + zd2) * (0.5 * h);
        vel
    }
}
