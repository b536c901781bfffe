//! Canonical system and Gaussian bases (Sec. 3.2).
//!
//! τζ̇ = −α_ζ ζ has the exact solution ζ(t) = exp(−α_ζ t/τ): for a fixed step Δt the phase is
//! advanced by one multiplication with exp(−α_ζ Δt/τ), no drift. Bases
//! ψ_i(ζ) = exp(−h_i (ζ − c_i)²) with centres c_i = exp(−α_ζ (i−1)/(n_g−1)) and widths
//! h_i = 2/(c_{i+1} − c_i)², h_{n_g} = h_{n_g−1}, evenly spaced in time.

use super::{DmpError, DmpParams, MAX_BASES};

/// Bases whose exponent exceeds this contribute e^{−36} ≈ 2e-16 of their peak, below f64
/// resolution of the sum: skipped (no `exp` call).
const NEGLIGIBLE_EXPONENT: f64 = 36.0;

/// A basis whose computed exponent h_i (ζ − c_i)² is at least this is skipped by a margin far
/// above the exponent's rounding (four roundings, ~1e-15 relative): [`Basis::candidates`]
/// finds the run's ends on it.
const CLEARLY_NEGLIGIBLE: f64 = NEGLIGIBLE_EXPONENT * (1.0 + 1e-6);

/// Centres and widths of the n_g Gaussian bases.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Basis {
    /// Number of bases n_g.
    pub n: usize,
    /// Centres c_i in phase.
    pub centres: [f64; MAX_BASES],
    /// Widths h_i.
    pub widths: [f64; MAX_BASES],
    /// True if both ends of the windows c_i ± √([`CLEARLY_NEGLIGIBLE`]/h_i) fall with i, with
    /// room to spare (as with centres spread evenly in time): the bases that can be active at
    /// ζ are then a contiguous run ([`Basis::candidates`]).
    sorted: bool,
    /// The phase rate α_ζ the centres were spread with ([`Basis::is_for`]).
    alpha_zeta: f64,
}

/// Normalised, phase-gated activations φ_i(ζ) = ψ_i(ζ) ζ / Σ_j ψ_j(ζ); non-zero only in
/// `first..last`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Features {
    /// φ_i, zero outside `first..last`.
    pub values: [f64; MAX_BASES],
    /// First non-zero basis.
    pub first: usize,
    /// One past the last non-zero basis.
    pub last: usize,
}

impl Features {
    /// No basis active: a forcing term of zero.
    pub const ZERO: Features = Features {
        values: [0.0; MAX_BASES],
        first: 0,
        last: 0,
    };
}

impl Basis {
    /// The bases of `p`, centres spread evenly in time.
    pub fn new(p: &DmpParams) -> Result<Self, DmpError> {
        check(p)?;
        let n = p.n_basis;
        let mut centres = [0.0; MAX_BASES];
        let mut widths = [0.0; MAX_BASES];
        for (i, c) in centres.iter_mut().take(n).enumerate() {
            *c = libm::exp(-p.alpha_zeta * i as f64 / (n - 1) as f64);
        }
        for i in 0..n - 1 {
            let d = centres[i + 1] - centres[i];
            widths[i] = 2.0 / (d * d);
        }
        widths[n - 1] = widths[n - 2];
        let sorted = windows_fall(&centres[..n]);
        Ok(Basis {
            n,
            centres,
            widths,
            sorted,
            alpha_zeta: p.alpha_zeta,
        })
    }

    /// True if these are the bases of `p`: [`Basis::new`] depends only on n_g and α_ζ, so
    /// it would compute these same values (n_g exponentials) again.
    pub fn is_for(&self, p: &DmpParams) -> bool {
        self.n == p.n_basis && self.alpha_zeta.to_bits() == p.alpha_zeta.to_bits()
    }

    /// The exponent h_i (ζ − c_i)² of basis i and the sign of ζ − c_i, computed as
    /// [`Basis::features_into`] computes it.
    #[inline(always)]
    fn exponent(&self, i: usize, zeta: f64) -> (f64, f64) {
        let d = zeta - self.centres[i];
        (d, self.widths[i] * d * d)
    }

    /// Indices of the bases that can be active at ζ, in order: with sorted windows, the run
    /// between the bases clearly above ζ (a prefix) and those clearly below it (a suffix),
    /// each end found by walking from the run `near` (that of a nearby ζ: an RDMP step's
    /// phase moves it by a basis at most; any guess gives the same run, since each end is
    /// where a predicate holding on a prefix or a suffix changes); else all n. Every basis
    /// left out has an exponent ≥ 36 (by sortedness, with a margin beyond rounding), so
    /// summing over the run gives the same bits as summing over all n. Stores nothing per
    /// basis.
    fn candidates(&self, zeta: f64, near: &core::ops::Range<usize>) -> core::ops::Range<usize> {
        if !self.sorted {
            return 0..self.n;
        }
        let clear = |i: usize, side: f64| {
            let (d, x) = self.exponent(i, zeta);
            d * side > 0.0 && x >= CLEARLY_NEGLIGIBLE
        };
        let mut start = near.start.min(self.n);
        while start > 0 && !clear(start - 1, -1.0) {
            start -= 1;
        }
        while start < self.n && clear(start, -1.0) {
            start += 1;
        }
        let mut end = near.end.clamp(start, self.n);
        while end > start && clear(end - 1, 1.0) {
            end -= 1;
        }
        while end < self.n && !clear(end, 1.0) {
            end += 1;
        }
        start..end
    }

    /// φ(ζ) for all bases.
    pub fn features(&self, zeta: f64) -> Features {
        let mut out = Features::ZERO;
        self.features_into(zeta, &mut out);
        out
    }

    /// [`Basis::features`] written over `out` in place (no features temporary to copy),
    /// testing only the `Basis::candidates` at ζ, found from the run `out` held before.
    pub fn features_into(&self, zeta: f64, out: &mut Features) {
        let near = out.first..out.last;
        self.features_among(self.candidates(zeta, &near), zeta, out);
    }

    /// [`Basis::features_into`] testing every basis, one at a time, and skipping the
    /// exponential of each negligible one: the implementation before the window, kept as the
    /// benchmark's baseline and the tests' reference (the same bits).
    pub fn features_testing_all(&self, zeta: f64, out: &mut Features) {
        out.values[out.first..out.last].fill(0.0);
        let (mut first, mut last) = (usize::MAX, 0);
        let mut sum = 0.0;
        for i in 0..self.n {
            let (_, x) = self.exponent(i, zeta);
            if x < NEGLIGIBLE_EXPONENT {
                let psi = crate::float::exp_neg(x);
                out.values[i] = psi;
                sum += psi;
                first = first.min(i);
                last = i + 1;
            }
        }
        if sum <= 0.0 {
            *out = Features::ZERO;
            return;
        }
        let k = zeta / sum;
        for v in &mut out.values[first..last] {
            *v *= k;
        }
        out.first = first;
        out.last = last;
    }

    /// φ(ζ) from the bases in `among` (a superset of the active ones, in order), in three
    /// passes over them and the last features' run when the two meet: each ψ_i (zero where
    /// the exponent is ≥ [`NEGLIGIBLE_EXPONENT`]) with no branch, which the host's vector
    /// unit takes two at a time; their sum, in index order (the zeros add nothing); the
    /// normalisation. Every entry outside the passes was zero before and stays so.
    #[inline(always)]
    fn features_among(&self, among: core::ops::Range<usize>, zeta: f64, out: &mut Features) {
        let old = out.first..out.last;
        let span = if !old.is_empty() && old.start <= among.end && among.start <= old.end {
            // The runs meet (a step moves the window by a basis at most).
            among.start.min(old.start)..among.end.max(old.end)
        } else {
            // A jump (a run started or moved elsewhere): clear the old run instead.
            out.values[old].fill(0.0);
            among
        };
        let values = &mut out.values[span.clone()];
        let bases = self.centres[span.clone()]
            .iter()
            .zip(&self.widths[span.clone()]);
        for (v, (c, h)) in values.iter_mut().zip(bases) {
            let d = zeta - c;
            let x = h * d * d;
            let psi = crate::float::exp_neg(x);
            *v = if x < NEGLIGIBLE_EXPONENT { psi } else { 0.0 };
        }
        let sum = values.iter().fold(0.0, |s, v| s + v);
        if !(sum > 0.0) {
            // Far beyond the last centre (ζ → 0): the gated forcing term is zero.
            (out.first, out.last) = (0, 0);
            return;
        }
        let first = values.iter().position(|v| *v > 0.0).unwrap_or(0);
        let last = values.iter().rposition(|v| *v > 0.0).map_or(0, |i| i + 1);
        let k = zeta / sum;
        for v in &mut values[first..last] {
            *v *= k;
        }
        (out.first, out.last) = (span.start + first, span.start + last);
    }
}

/// The parameters a [`Basis`] and a [`Phase`] need: 2 ≤ n_g ≤ [`MAX_BASES`], and the rates
/// and gains positive and finite.
fn check(p: &DmpParams) -> Result<(), DmpError> {
    let positive = |x: f64| x > 0.0 && x.is_finite();
    let valid = (2..=MAX_BASES).contains(&p.n_basis)
        && positive(p.alpha_zeta)
        && positive(p.alpha_z)
        && positive(p.beta_z);
    if valid {
        Ok(())
    } else {
        Err(DmpError::BadParams)
    }
}

/// True if the windows c_i ± √([`CLEARLY_NEGLIGIBLE`]/h_i) fall strictly with i at both
/// ends, by more than 1e-9 of their radii (far beyond the exponent's rounding). Since
/// h_i = 2/(c_{i+1} − c_i)² (h_{n−1} = h_{n−2}), the radius is √(T/2)·|c_{i+1} − c_i| to a few
/// ulps: one square root, not one per basis (libm's is software on the controller).
fn windows_fall(centres: &[f64]) -> bool {
    let k = crate::float::sqrt(CLEARLY_NEGLIGIBLE / 2.0);
    let n = centres.len();
    let radius = |i: usize| {
        let i = i.min(n - 2);
        k * f64::abs(centres[i + 1] - centres[i])
    };
    (1..n).all(|i| {
        let (r0, r1) = (radius(i - 1), radius(i));
        let room = 1e-9 * (r0 + r1);
        let (c0, c1) = (centres[i - 1], centres[i]);
        c1 - r1 < c0 - r0 - room && c1 + r1 < c0 + r0 - room
    })
}

/// Share of τ over which the forcing term fades linearly to zero after τ. The demonstration
/// defines f only on [0, τ]; a program typically stops still decelerating, so f(τ) ≠ 0, and a
/// motion that runs on past τ (to come to a stop within the jerk limit) must not keep it.
/// Fading keeps the acceleration continuous (jerk ≈ a(τ)/(FADE·τ)) and, scaling with τ, lets
/// a time-scaled motion's jerk fall with the cube of the scale like the rest of it. On the
/// example cell 0.005 τ (15–25 ms) ends every timed candidate within 0.29 mm of its goal and
/// slows none; a cut in one step slows some (a jerk step), 0.01 τ doubles the end error.
pub const FADE: f64 = 0.005;

/// Phase of one integration: ζ and the features at the current and the next step.
#[derive(Clone, Copy, Debug)]
pub struct Phase {
    /// The Gaussian bases.
    pub basis: Basis,
    /// Step index k (time kΔt).
    pub step: usize,
    /// Number of steps of the whole motion, round(τ/Δt) unless a caller runs it on.
    pub n_steps: usize,
    /// round(τ/Δt): the steps the forcing term was trained over. Beyond them it fades out.
    end: usize,
    /// Steps over which the forcing term fades to zero after `end` ([`FADE`] × τ).
    fade: usize,
    decay: f64,
    /// ζ_k and ζ_{k+1}.
    pub zeta: f64,
    /// ζ_{k+1}.
    pub zeta_next: f64,
    /// φ(ζ_k) and φ(ζ_{k+1}), at `features[now]` and `features[1 − now]`: advancing flips
    /// `now` instead of copying.
    features: [Features; 2],
    now: usize,
    /// `features[now]` holds φ(ζ_{k+2}) instead of φ(ζ_k) ([`Phase::prepare`]).
    prepared: bool,
}

impl Phase {
    /// Phase for a motion of duration `tau` integrated with step `dt`.
    pub fn new(p: &DmpParams, tau: f64, dt: f64) -> Result<Self, DmpError> {
        Phase::new_on(None, p, tau, dt)
    }

    /// [`Phase::new`] with the bases copied from `basis` when they are `p`'s
    /// ([`Basis::is_for`]): the same phase, bit for bit, without the n_g exponentials.
    pub fn new_on(
        basis: Option<&Basis>,
        p: &DmpParams,
        tau: f64,
        dt: f64,
    ) -> Result<Self, DmpError> {
        let mut phase = Phase::unset(basis, p, tau, dt)?;
        let [current, next] = &mut phase.features;
        phase.basis.features_into(1.0, current);
        phase.basis.features_into(phase.zeta_next, next);
        Ok(phase)
    }

    /// The phase at step 0 with no features computed yet (all zero), for [`Phase::new`] and
    /// [`Phase::resume`] to fill in place.
    fn unset(basis: Option<&Basis>, p: &DmpParams, tau: f64, dt: f64) -> Result<Self, DmpError> {
        if !(dt > 0.0 && tau >= dt && tau.is_finite()) {
            return Err(DmpError::BadParams);
        }
        check(p)?;
        let decay = libm::exp(-p.alpha_zeta * dt / tau);
        let end = libm::round(tau / dt) as usize;
        Ok(Phase {
            basis: match basis {
                Some(b) if b.is_for(p) => *b,
                _ => Basis::new(p)?,
            },
            step: 0,
            n_steps: end,
            end,
            fade: (libm::round(FADE * tau / dt) as usize).max(1),
            decay,
            zeta: 1.0,
            zeta_next: decay,
            features: [Features::ZERO; 2],
            now: 0,
            prepared: false,
        })
    }

    /// φ(ζ_k) (inside an RDMP step, once its DMPs have stepped: φ(ζ_{k+2}), `Phase::prepare`).
    pub fn current(&self) -> &Features {
        &self.features[self.now]
    }

    /// φ(ζ_{k+1}).
    pub fn next(&self) -> &Features {
        &self.features[1 - self.now]
    }

    /// Computes φ(ζ_{k+2}) ahead of [`Phase::advance`], over φ(ζ_k), which a step needs no
    /// more once its DMPs have stepped: the RDMP step calls it while its QR's dependency chain
    /// leaves the processor room. A step that is then refused calls [`Phase::unprepare`].
    #[inline(always)]
    pub(crate) fn prepare(&mut self) {
        if !self.prepared {
            let gate = self.gate(self.step + 2);
            let zeta = self.zeta_next * self.decay;
            gated_features(&self.basis, gate, zeta, &mut self.features[self.now]);
            self.prepared = true;
        }
    }

    /// Puts φ(ζ_k) back where [`Phase::prepare`] wrote φ(ζ_{k+2}) (for a step retried at k).
    #[cold]
    pub(crate) fn unprepare(&mut self) {
        if self.prepared {
            let gate = self.gate(self.step);
            gated_features(&self.basis, gate, self.zeta, &mut self.features[self.now]);
            self.prepared = false;
        }
    }

    /// Moves from step k to k+1: one basis evaluation, the old φ(ζ_k) becoming φ(ζ_{k+2}),
    /// unless `Phase::prepare` did it.
    pub fn advance(&mut self) {
        self.prepare();
        self.prepared = false;
        self.step += 1;
        self.zeta = self.zeta_next;
        self.zeta_next *= self.decay;
        self.now = 1 - self.now;
    }

    /// The weight of the forcing term at step `k`: 1 up to τ, then falling linearly to 0 over
    /// [`FADE`]·τ. Beyond, the DMP is the bare critically damped spring of Eq. (1) and settles
    /// on its goal; left on, f(ζ) decayed only with ζ and pushed a motion that ran on past τ
    /// millimetres off its goal and back.
    fn gate(&self, k: usize) -> f64 {
        if k <= self.end {
            1.0
        } else {
            (self.end + self.fade).saturating_sub(k) as f64 / self.fade as f64
        }
    }

    /// The phase at step `step` with ζ_k = `zeta`, ζ_{k+1} = `zeta_next` (from a saved
    /// [`Phase`]): bit-identical to the phase that was saved, since the features are a pure
    /// function of ζ.
    pub fn resume(
        p: &DmpParams,
        tau: f64,
        dt: f64,
        step: usize,
        zeta: f64,
        zeta_next: f64,
    ) -> Result<Self, DmpError> {
        let mut phase = Phase::unset(None, p, tau, dt)?;
        phase.seek(step, zeta, zeta_next);
        Ok(phase)
    }

    /// Moves this phase to step `step` with ζ_k = `zeta`, ζ_{k+1} = `zeta_next` of the same
    /// motion, keeping the basis: [`Phase::resume`] without recomputing the bases.
    pub fn seek(&mut self, step: usize, zeta: f64, zeta_next: f64) {
        self.step = step;
        self.zeta = zeta;
        self.zeta_next = zeta_next;
        let (now, then) = (self.gate(step), self.gate(step + 1));
        let [current, next] = &mut self.features;
        (self.now, self.prepared) = (0, false);
        gated_features(&self.basis, now, zeta, current);
        gated_features(&self.basis, then, zeta_next, next);
    }

    /// True once all `n_steps` steps are done.
    pub fn finished(&self) -> bool {
        self.step >= self.n_steps
    }
}

/// φ(`zeta`) weighted by `gate` ([`Phase::gate`]), written into `out` in place; at gate 0 no
/// basis is evaluated. Not inlined: inlined, its features temporary (416 B) raised the
/// Cortex-M7's stack high-water mark by 2.8 KiB (`prf firmware`).
#[inline(never)]
fn gated_features(basis: &Basis, gate: f64, zeta: f64, out: &mut Features) {
    if gate <= 0.0 {
        // An empty range: the forcing term sums nothing.
        out.values[out.first..out.last].fill(0.0);
        out.first = 0;
        out.last = 0;
        return;
    }
    basis.features_into(zeta, out);
    if gate < 1.0 {
        for v in &mut out.values[out.first..out.last] {
            *v *= gate;
        }
    }
}
