//! Dynamical movement primitives (Sec. 3.2, Eqs. 1–5).
//!
//! - [`phase`]: canonical system τζ̇ = −α_ζ ζ and the n_g Gaussian bases;
//! - [`forcing`]: the forcing term f(ζ) = D Σ w_i ψ_i(ζ) / Σ ψ_i(ζ) · ζ (Eq. 3) and its
//!   regression (Train, Eq. 4);
//! - [`position`]: position DMPs in R^n (Eq. 1);
//! - [`rotation`]: rotation DMPs on SO(3) (Eq. 2).
//!
//! Integration (Eq. 5) is offered one step at a time, the runtime's per-tick call, and as a
//! whole trajectory written into a caller buffer. Each step is Heun's method (explicit
//! trapezoid, on the rotation group for SO(3)): second order, so a 1 kHz integration reproduces
//! a demonstration to well below a millimetre, with one new basis evaluation per step.

pub mod forcing;
pub mod phase;
pub mod position;
pub mod rotation;

pub use forcing::{Ahead, Forcing};
pub use phase::{Basis, Features, Phase};
pub use position::{PositionDmp, PositionState};
pub use rotation::{RotationDmp, RotationState};

/// Maximum number of Gaussian bases n_g.
pub const MAX_BASES: usize = 50;

/// Gains and basis count shared by every DMP of a skill.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DmpParams {
    /// Number of Gaussian bases n_g (2..=[`MAX_BASES`]).
    pub n_basis: usize,
    /// Spring gain α_z.
    pub alpha_z: f64,
    /// Damping ratio term β_z; α_z/4 makes Eq. (1) critically damped.
    pub beta_z: f64,
    /// Canonical decay α_ζ: the phase falls from 1 to e^{−α_ζ} over the duration τ.
    pub alpha_zeta: f64,
    /// Guard for D = diag(g − y0) ≈ 0: a coordinate whose demonstrated amplitude |g − y0| is
    /// below this (m for positions, rad for rotations and γ) learns its forcing term unscaled
    /// (D_i := 1) instead of dividing by a near-zero amplitude; its shape is then reproduced
    /// as demonstrated, whatever the new goal.
    pub min_amplitude: f64,
    /// Ridge regularisation of the weight regression, relative to the largest Gram diagonal.
    pub ridge: f64,
}

impl Default for DmpParams {
    fn default() -> Self {
        DmpParams {
            n_basis: 40,
            alpha_z: 25.0,
            beta_z: 25.0 / 4.0,
            alpha_zeta: 4.0,
            min_amplitude: 0.01,
            ridge: 1e-9,
        }
    }
}

/// Why a DMP could not be trained or integrated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DmpError {
    /// Parameters out of range (n_basis, gains, time step).
    BadParams,
    /// A demonstration needs at least this many samples.
    TooFewSamples {
        /// Samples given.
        got: usize,
        /// Samples needed.
        need: usize,
    },
    /// A demonstration sample or an integration input is NaN or infinite.
    NonFinite {
        /// The sample index.
        sample: usize,
    },
    /// The weight regression is singular even after regularisation.
    IllConditioned,
    /// An output buffer is shorter than the trajectory (`need` samples).
    BufferTooSmall {
        /// Samples the trajectory has.
        need: usize,
    },
}

impl core::fmt::Display for DmpError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DmpError::BadParams => write!(
                f,
                "DMP parameters out of range (number of basis functions, gains or time step)"
            ),
            DmpError::TooFewSamples { got, need } => write!(
                f,
                "the demonstration has {got} samples, a DMP needs at least {need}"
            ),
            DmpError::NonFinite { sample } => {
                write!(f, "sample {sample} is not finite (NaN or infinite)")
            }
            DmpError::IllConditioned => write!(
                f,
                "the DMP weight regression is singular even after regularisation"
            ),
            DmpError::BufferTooSmall { need } => {
                write!(
                    f,
                    "the output buffer is too short: the trajectory has {need} samples"
                )
            }
        }
    }
}

impl core::error::Error for DmpError {}

/// Minimum number of samples of a demonstration.
pub const MIN_SAMPLES: usize = 5;

/// The transformation system's right-hand side τż = α_z(β_z e − z) + f (Eqs. 1, 2) with e the
/// goal error (g − y, or log(R_g R⁻¹) on SO(3)).
#[inline]
pub(crate) fn spring<const N: usize>(
    p: &DmpParams,
    e: &nalgebra::SVector<f64, N>,
    z: &nalgebra::SVector<f64, N>,
    f: &nalgebra::SVector<f64, N>,
) -> nalgebra::SVector<f64, N> {
    (e * p.beta_z - z) * p.alpha_z + f
}

/// Velocity and acceleration at sample k of a uniformly sampled demonstration, from the
/// half-step velocities `half(j)` between samples j and j+1 (j in 0..n−1): v_k is their mean,
/// a_k their difference over Δt (the compact second difference); the end samples take their
/// neighbour's acceleration and the adjacent half-step velocity.
pub(crate) fn sample_derivatives<const N: usize>(
    n: usize,
    k: usize,
    dt: f64,
    half: impl Fn(usize) -> nalgebra::SVector<f64, N>,
) -> (nalgebra::SVector<f64, N>, nalgebra::SVector<f64, N>) {
    let kk = k.clamp(1, n - 2);
    let (before, after) = (half(kk - 1), half(kk));
    let a = (after - before) / dt;
    let v = if k == 0 {
        half(0)
    } else if k + 1 == n {
        half(n - 2)
    } else {
        (before + after) * 0.5
    };
    (v, a)
}

/// Checks a demonstration's sample count and time step.
pub(crate) fn check_demo(p: &DmpParams, n: usize, dt: f64) -> Result<(), DmpError> {
    if n < MIN_SAMPLES {
        return Err(DmpError::TooFewSamples {
            got: n,
            need: MIN_SAMPLES,
        });
    }
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(DmpError::BadParams);
    }
    phase::Basis::new(p).map(|_| ())
}
