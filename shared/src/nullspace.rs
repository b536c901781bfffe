//! Compact null-space basis of the 6×7 Jacobian (Sec. 4.2.1) without an SVD.
//!
//! For J ∈ R^{6×7} of rank 6 the kernel is spanned by the generalized cross product of its
//! rows, c_i = (−1)^i det(J without column i) (0-based i). Two facts make it the right basis:
//! - c is a polynomial in J, so it is continuous along a trajectory: no arbitrary sign flip
//!   as with the SVD basis of Alg. 1/2;
//! - |c| = sqrt(det(J Jᵀ)) (Cauchy–Binet), Yoshikawa's manipulability: the singularity
//!   measure comes for free.
//!
//! M(q) = c/|c| is then the orthonormal basis of Eq. (21), M⁺ = Mᵀ, and since M spans ker J,
//! Eq. (22) reduces to γ̇ = Mᵀ q̇.
//!
//! c is computed from one Householder QR of Jᵀ = Q [R; 0] (Q = H_0 ⋯ H_5, 7×7): with
//! q_7 = Q e_7, [J; q_7ᵀ]ᵀ = Q [[R, 0], [0, 1]], so det([J; q_7ᵀ]) = det Q · det R, and since
//! det([J; cᵀ]) = |c|² > 0 the cofactor vector is c = det Q · det R · q_7. The same
//! factorisation gives the minimum-norm solution J⁺V = Q [R⁻ᵀV; 0], so one QR per tick
//! serves both M and J⁺ (Alg. 2, line 22).

use crate::{Jacobian, JointVector};
use nalgebra::Vector6;

/// Relative size of R's smallest diagonal entry below which J counts as rank deficient.
pub const RANK_TOLERANCE: f64 = 1e-10;

/// Unit kernel direction M(q) and manipulability sqrt(det(J Jᵀ)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kernel {
    /// Unit vector spanning ker J, oriented as the generalized cross product (zero if J is
    /// rank deficient).
    pub direction: JointVector,
    /// Manipulability √det(J Jᵀ).
    pub manipulability: f64,
}

/// Householder QR of Jᵀ (7×6).
#[derive(Clone, Copy, Debug)]
pub struct JacobianQr {
    /// Householder vectors v_k (entries k..7 used), H_k = I − β_k v_k v_kᵀ.
    v: [[f64; 7]; 6],
    beta: [f64; 6],
    /// Upper-triangular R, row-major.
    r: [[f64; 6]; 6],
    /// det Q = (−1)^(number of reflections applied).
    det_q: f64,
}

impl JacobianQr {
    /// The QR of Jᵀ: the six Householder steps unrolled for the 7 × 6 shape (`householder`),
    /// with short dependency chains: dot products summed pairwise, β = 2/vᵀv taken as
    /// 1/(‖a_k‖(‖a_k‖ + |a_kk|)) from the column's norm (no second sum), and the products
    /// vᵀc = a_kᵀc − α c_k of the other columns summed before α is known. The same
    /// factorisation as [`JacobianQr::new_looped`] to rounding (test
    /// `the_step_qr_agrees_with_the_previous_one`).
    pub fn new(j: &Jacobian) -> Self {
        Self::new_beside(j, |_| {})
    }

    /// [`JacobianQr::new`], calling `beside(k)` after Householder step k (0..6): work
    /// independent of J placed there runs while the next steps wait on their square root and
    /// division (the RDMP step's DMPs, [`crate::rdmp::RdmpRun::step`]). The same bits.
    ///
    /// Jᵀ is held as its rows, J's columns (`j.data.0`, one joint's six entries each), and
    /// every step works along them: each row's products with the pivot column and its update
    /// are element-wise over the columns, which the host's vector unit takes two at a time,
    /// where the columns' dot products were sums across one array. Each entry is computed by
    /// the operations, in the order, of the column-wise form.
    #[inline(always)]
    pub fn new_beside(j: &Jacobian, mut beside: impl FnMut(usize)) -> Self {
        // a[row] is row `row` of Jᵀ: a[row][c] = Jᵀ(row, c) = J(c, row).
        let mut a = j.data.0;
        let mut qr = JacobianQr {
            v: [[0.0; 7]; 6],
            beta: [0.0; 6],
            r: [[0.0; 6]; 6],
            det_q: 1.0,
        };
        householder::<0>(&mut a, &mut qr);
        beside(0);
        householder::<1>(&mut a, &mut qr);
        beside(1);
        householder::<2>(&mut a, &mut qr);
        beside(2);
        householder::<3>(&mut a, &mut qr);
        beside(3);
        householder::<4>(&mut a, &mut qr);
        beside(4);
        householder::<5>(&mut a, &mut qr);
        beside(5);
        qr
    }

    /// The QR of Jᵀ as generic loops, each sum in index order and vᵀv summed again: the
    /// previous implementation, kept as the benchmark's baseline (`prf bench`) and the
    /// tests' reference for [`JacobianQr::new`].
    pub fn new_looped(j: &Jacobian) -> Self {
        // a = Jᵀ, column-major by construction: a[c][row] is Jᵀ(row, c) = J(c, row).
        let mut a = [[0.0; 7]; 6];
        for (c, col) in a.iter_mut().enumerate() {
            for (row, v) in col.iter_mut().enumerate() {
                *v = j[(c, row)];
            }
        }
        let mut v = [[0.0; 7]; 6];
        let mut beta = [0.0; 6];
        let mut r = [[0.0; 6]; 6];
        let mut det_q = 1.0;
        for k in 0..6 {
            let norm = crate::float::sqrt(a[k][k..].iter().map(|x| x * x).sum::<f64>());
            let alpha = if a[k][k] >= 0.0 { -norm } else { norm };
            let vk = &mut v[k];
            vk[k..].copy_from_slice(&a[k][k..]);
            vk[k] -= alpha;
            let vv: f64 = vk[k..].iter().map(|x| x * x).sum();
            if vv > 0.0 {
                beta[k] = 2.0 / vv;
                det_q = -det_q;
                for col in a.iter_mut().skip(k + 1) {
                    let s = beta[k] * (k..7).map(|i| vk[i] * col[i]).sum::<f64>();
                    for i in k..7 {
                        col[i] -= s * vk[i];
                    }
                }
            }
            r[k][k] = if vv > 0.0 { alpha } else { a[k][k] };
            for c in (k + 1)..6 {
                r[k][c] = a[c][k];
            }
        }
        JacobianQr { v, beta, r, det_q }
    }

    /// y ← Q y = H_0 ⋯ H_5 y for L vectors at once, held as L-tuples per row (`y[i][l]`: row
    /// i of vector l), element-wise over the tuple.
    #[inline(always)]
    fn apply_q<const L: usize>(&self, y: &mut [[f64; L]; 7]) {
        reflect::<5, L>(self, y);
        reflect::<4, L>(self, y);
        reflect::<3, L>(self, y);
        reflect::<2, L>(self, y);
        reflect::<1, L>(self, y);
        reflect::<0, L>(self, y);
    }

    /// det R = ± sqrt(det(J Jᵀ)).
    fn det_r(&self) -> f64 {
        (0..6).map(|k| self.r[k][k]).product()
    }

    /// Kernel of J, oriented as the generalized cross product of its rows.
    pub fn kernel(&self) -> Kernel {
        let mut q7 = E7.map(|x| [x]);
        self.apply_q(&mut q7);
        self.oriented(q7.map(|[x]| x))
    }

    /// The kernel from q_7 = Q e_7: c = det Q · det R · q_7, normalised.
    fn oriented(&self, q7: [f64; 7]) -> Kernel {
        let det = self.det_q * self.det_r();
        let w = f64::abs(det);
        let direction = if w > 0.0 {
            JointVector::from(q7) * (if det > 0.0 { 1.0 } else { -1.0 })
        } else {
            JointVector::zeros()
        };
        Kernel {
            direction,
            manipulability: w,
        }
    }

    /// Minimum-norm solution J⁺V = Q [R⁻ᵀV; 0] of J q̇ = V; `None` if J is numerically rank
    /// deficient (a diagonal entry of R below [`RANK_TOLERANCE`] × the largest one).
    pub fn pinv_apply(&self, v: &Vector6<f64>) -> Option<JointVector> {
        let mut y = self.r_inv_t(v)?.map(|x| [x]);
        self.apply_q(&mut y);
        finite(y.map(|[x]| x))
    }

    /// [R⁻ᵀV; 0] by forward substitution, multiplying by the diagonal's reciprocals (taken
    /// up front, off the substitution's chain); `None` if a diagonal entry of R is below
    /// [`RANK_TOLERANCE`] × the largest one. Inlined, as [`JacobianQr::kernel_and_pinv`] is.
    #[inline(always)]
    fn r_inv_t(&self, v: &Vector6<f64>) -> Option<[f64; 7]> {
        let scale = (0..6).map(|k| f64::abs(self.r[k][k])).fold(0.0, f64::max);
        let inv: [f64; 6] = core::array::from_fn(|k| 1.0 / self.r[k][k]);
        let mut y = [0.0; 7];
        for i in 0..6 {
            let d = self.r[i][i];
            if !(f64::abs(d) > RANK_TOLERANCE * scale) {
                return None;
            }
            let s: f64 = (0..i).map(|k| self.r[k][i] * y[k]).sum();
            y[i] = (v[i] - s) * inv[i];
        }
        Some(y)
    }
}

/// e_7.
const E7: [f64; 7] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];

/// `y` as a joint vector if every entry is finite.
fn finite(y: [f64; 7]) -> Option<JointVector> {
    let out = JointVector::from(y);
    out.iter().all(|x| x.is_finite()).then_some(out)
}

/// Householder step K of [`JacobianQr::new`] on the rows of Jᵀ below K, with the loop bounds
/// known at compile time. H_K = I − β v vᵀ with v = a_K − α e_K, α = −sign(a_KK)‖a_K‖ (a_K:
/// column K, rows K..7), so vᵀv = 2‖a_K‖(‖a_K‖ + |a_KK|). The products a_Kᵀa_c of every
/// column c ≥ K (‖a_K‖² among them) are one pairwise sum over the rows of a_rK · row r.
#[inline(always)]
fn householder<const K: usize>(a: &mut [[f64; 6]; 7], qr: &mut JacobianQr) {
    let d = tree::<K, _>(
        |r| {
            let x = a[r][K];
            a[r].map(|y| x * y)
        },
        |p, q| core::array::from_fn(|c| p[c] + q[c]),
    );
    let norm = crate::float::sqrt(d[K]);
    let akk = a[K][K];
    let alpha = if akk >= 0.0 { -norm } else { norm };
    let mut vk = [0.0; 7];
    for r in K..7 {
        vk[r] = a[r][K];
    }
    vk[K] -= alpha;
    if norm > 0.0 {
        let beta = 1.0 / (norm * (norm + f64::abs(akk)));
        qr.beta[K] = beta;
        qr.det_q = -qr.det_q;
        let mut s = [0.0; 6];
        for c in K + 1..6 {
            s[c] = beta * (d[c] - alpha * a[K][c]);
        }
        for r in K..7 {
            for c in K + 1..6 {
                a[r][c] -= s[c] * vk[r];
            }
        }
    }
    qr.r[K][K] = if norm > 0.0 { alpha } else { akk };
    qr.r[K][K + 1..].copy_from_slice(&a[K][K + 1..]);
    qr.v[K] = vk;
}

/// Σ_{i ≥ K} p(i) summed pairwise (a tree of depth 3 at most), `add` adding two terms.
#[inline(always)]
fn tree<const K: usize, T: Copy>(p: impl Fn(usize) -> T, add: impl Fn(T, T) -> T) -> T {
    let s = |i: usize, j: usize| add(p(i), p(j));
    match K {
        0 => add(add(s(0, 1), s(2, 3)), add(s(4, 5), p(6))),
        1 => add(add(s(1, 2), s(3, 4)), s(5, 6)),
        2 => add(add(s(2, 3), s(4, 5)), p(6)),
        3 => add(s(3, 4), s(5, 6)),
        4 => add(s(4, 5), p(6)),
        5 => s(5, 6),
        _ => p(6),
    }
}

/// y ← H_K y, reflection K of Q ([`JacobianQr::apply_q`]), for each of the L vectors in `y`:
/// s = β v_Kᵀy summed pairwise ([`tree`]), then y − s v_K.
#[inline(always)]
fn reflect<const K: usize, const L: usize>(qr: &JacobianQr, y: &mut [[f64; L]; 7]) {
    let beta = qr.beta[K];
    if beta != 0.0 {
        let vk = &qr.v[K];
        let d = tree::<K, _>(
            |i| y[i].map(|y| vk[i] * y),
            |p, q| core::array::from_fn(|l| p[l] + q[l]),
        );
        let s = d.map(|d| beta * d);
        for i in K..7 {
            for l in 0..L {
                y[i][l] -= s[l] * vk[i];
            }
        }
    }
}

impl JacobianQr {
    /// Manipulability √det(J Jᵀ) = |det R| (the one of [`JacobianQr::kernel`]), without
    /// applying Q.
    pub fn manipulability(&self) -> f64 {
        f64::abs(self.det_q * self.det_r())
    }

    /// [`JacobianQr::kernel`] and [`JacobianQr::pinv_apply`] of `v` in one pass over the
    /// reflections of Q (Alg. 2, line 22: M and J⁺V from one factorisation), bit for bit.
    /// Inlined into the RDMP step, its only caller on the robot, with the substitution: the
    /// step's end runs without two calls (x86-64 saves no floating-point register across a
    /// call, so the values live across one go through the stack): × 0.971 of the step on
    /// an AMD EPYC VM, 186 instructions fewer (`prf bench --profile-steps`).
    #[inline(always)]
    pub fn kernel_and_pinv(&self, v: &Vector6<f64>) -> (Kernel, Option<JointVector>) {
        let solved = self.r_inv_t(v);
        let y = solved.unwrap_or([0.0; 7]);
        // (q_7, J⁺V) row by row: Q e_7 and Q [R⁻ᵀV; 0].
        let mut pairs: [[f64; 2]; 7] = core::array::from_fn(|i| [E7[i], y[i]]);
        self.apply_q(&mut pairs);
        let (q7, y) = (pairs.map(|p| p[0]), pairs.map(|p| p[1]));
        (self.oriented(q7), solved.and(finite(y)))
    }
}

/// Kernel of a 6×7 Jacobian (see the module documentation).
pub fn kernel(j: &Jacobian) -> Kernel {
    JacobianQr::new(j).kernel()
}

/// Minimum-norm solution J⁺V of J q̇ = V; `None` if J is numerically rank deficient.
pub fn pinv_apply(j: &Jacobian, v: &Vector6<f64>) -> Option<JointVector> {
    JacobianQr::new(j).pinv_apply(v)
}
