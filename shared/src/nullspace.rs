//! Compact null-space basis of the 6×7 Jacobian (Sec. 4.2.1) without an SVD.
//!
//! For J ∈ R^{6×7} of rank 6 the kernel is spanned by the generalized cross product of its
//! rows, c_i = (−1)^i det(J without column i) (0-based i). Two facts make it the right basis:
//! - J c = 0 (each row of J dotted with c is a determinant with a repeated row), and c is a
//!   polynomial in J, so it is continuous along a trajectory: no arbitrary sign flip as with
//!   the SVD basis of Alg. 1/2;
//! - |c| = sqrt(det(J Jᵀ)) (Cauchy–Binet), Yoshikawa's manipulability: the singularity measure
//!   comes for free.
//!
//! M(q) = c/|c| is then the orthonormal basis of Eq. (21), M⁺ = Mᵀ, and since M spans ker J,
//! Eq. (22) reduces to γ̇ = Mᵀ q̇.

use crate::linalg::det6;
use crate::{Jacobian, JointVector};
use nalgebra::{Cholesky, Matrix6, Vector6};

/// Unit kernel direction M(q) and manipulability sqrt(det(J Jᵀ)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kernel {
    /// Unit vector spanning ker J (zero if J is rank deficient).
    pub direction: JointVector,
    pub manipulability: f64,
}

/// Kernel of a 6×7 Jacobian by the generalized cross product of its rows.
pub fn kernel(j: &Jacobian) -> Kernel {
    let mut c = JointVector::zeros();
    for skip in 0..7 {
        let mut m = [[0.0; 6]; 6];
        for (r, row) in m.iter_mut().enumerate() {
            let mut k = 0;
            for col in 0..7 {
                if col != skip {
                    row[k] = j[(r, col)];
                    k += 1;
                }
            }
        }
        let d = det6(m);
        c[skip] = if skip % 2 == 0 { d } else { -d };
    }
    let w = c.norm();
    let direction = if w > 0.0 { c / w } else { JointVector::zeros() };
    Kernel {
        direction,
        manipulability: w,
    }
}

/// Minimum-norm solution J⁺ V = Jᵀ (J Jᵀ)⁻¹ V of J q̇ = V; `None` if J J^T is not positive
/// definite (rank-deficient J).
pub fn pinv_apply(j: &Jacobian, v: &Vector6<f64>) -> Option<JointVector> {
    let jjt: Matrix6<f64> = j * j.transpose();
    let chol = Cholesky::new(jjt)?;
    Some(j.transpose() * chol.solve(v))
}
