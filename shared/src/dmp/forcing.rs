//! Forcing term (Eq. 3) and its regression (Train, Eq. 4).

use super::{DmpError, DmpParams, MAX_BASES, phase::Basis, phase::Features};
use crate::linalg::{cholesky_factor, cholesky_solve};
use nalgebra::SVector;

/// The f(ζ_{k+1}) a step evaluated (Heun's corrector) and its k + 1, kept for the next step's
/// f(ζ_k) ([`Forcing::current`]). None: evaluate it.
pub type Ahead<const N: usize> = Option<(usize, SVector<f64, N>)>;

/// Trained forcing weights of an N-dimensional DMP.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Forcing<const N: usize> {
    /// w_i per coordinate (only the first n_g are used).
    pub weights: [[f64; MAX_BASES]; N],
    /// Per coordinate: true if the forcing term is scaled by D_i = g_i − y0_i (Eq. 3); false if
    /// the demonstrated amplitude was below [`DmpParams::min_amplitude`] (guard, D_i := 1).
    pub scaled: [bool; N],
}

impl<const N: usize> Forcing<N> {
    /// f(ζ) given the features φ(ζ) and the amplitude D = g − y0 of this integration. One
    /// pass over the active bases sums every coordinate (each in index order, as a pass per
    /// coordinate would: the same bits), reading each φ_i once.
    #[inline]
    pub fn eval(&self, phi: &Features, amplitude: &SVector<f64, N>) -> SVector<f64, N> {
        let mut s = [0.0; N];
        for i in phi.first..phi.last {
            let p = phi.values[i];
            for (s, w) in s.iter_mut().zip(&self.weights) {
                *s += w[i] * p;
            }
        }
        SVector::<f64, N>::from_fn(|c, _| {
            if self.scaled[c] {
                s[c] * amplitude[c]
            } else {
                s[c]
            }
        })
    }

    /// f(ζ_k) at the phase's step k: the value `ahead` holds when it is for this step (the
    /// previous step's corrector evaluated the same features φ(ζ_k), which the phase keeps
    /// unchanged: the same bits), else evaluated. A phase moved elsewhere
    /// ([`super::Phase::seek`]) has another step, and `None` always evaluates.
    #[inline]
    pub fn current(
        &self,
        phase: &super::Phase,
        amplitude: &SVector<f64, N>,
        ahead: Ahead<N>,
    ) -> SVector<f64, N> {
        match ahead {
            Some((k, f)) if k == phase.step => f,
            _ => self.eval(phase.current(), amplitude),
        }
    }

    /// Least-squares fit of the weights to forcing targets f_k at phases ζ_k (ridge
    /// regularised). `sample(k)` gives (ζ_k, f_k) for k in 0..n; `amplitude` is the
    /// demonstration's D = g − y0 that Eq. (3) divides out.
    pub fn fit(
        p: &DmpParams,
        basis: &Basis,
        amplitude: &SVector<f64, N>,
        n: usize,
        mut sample: impl FnMut(usize) -> (f64, SVector<f64, N>),
    ) -> Result<Self, DmpError> {
        let nb = basis.n;
        let scaled: [bool; N] = core::array::from_fn(|c| f64::abs(amplitude[c]) >= p.min_amplitude);
        let mut gram = [[0.0; MAX_BASES]; MAX_BASES];
        let mut rhs = [[0.0; MAX_BASES]; N];
        for k in 0..n {
            let (zeta, f) = sample(k);
            if !zeta.is_finite() || f.iter().any(|v| !v.is_finite()) {
                return Err(DmpError::NonFinite { sample: k });
            }
            let phi = basis.features(zeta);
            for i in phi.first..phi.last {
                for j in phi.first..=i {
                    gram[i][j] += phi.values[i] * phi.values[j];
                }
                for c in 0..N {
                    let target = if scaled[c] { f[c] / amplitude[c] } else { f[c] };
                    rhs[c][i] += phi.values[i] * target;
                }
            }
        }
        let max_diag = (0..nb).map(|i| gram[i][i]).fold(0.0, f64::max);
        let lambda = p.ridge * max_diag.max(1e-300);
        for (i, row) in gram.iter_mut().enumerate().take(nb) {
            row[i] += lambda;
        }
        cholesky_factor(&mut gram, nb).map_err(|_| DmpError::IllConditioned)?;
        let mut weights = [[0.0; MAX_BASES]; N];
        for c in 0..N {
            cholesky_solve(&gram, nb, &mut rhs[c][..nb]);
            weights[c][..nb].copy_from_slice(&rhs[c][..nb]);
        }
        Ok(Forcing { weights, scaled })
    }
}
