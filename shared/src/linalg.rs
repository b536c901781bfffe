//! Small dense solvers on fixed-size arrays (no allocation): the Cholesky factorisation of the
//! DMP weight regression.

/// The matrix handed to [`cholesky_factor`] is not (numerically) positive definite.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NotPositiveDefinite;

/// In-place Cholesky factorisation A = L·Lᵀ of the leading `n × n` block (lower triangle used).
pub fn cholesky_factor<const M: usize>(
    a: &mut [[f64; M]; M],
    n: usize,
) -> Result<(), NotPositiveDefinite> {
    for j in 0..n {
        let mut d = a[j][j];
        for k in 0..j {
            d -= a[j][k] * a[j][k];
        }
        if !(d > 0.0) {
            return Err(NotPositiveDefinite);
        }
        let d = crate::float::sqrt(d);
        a[j][j] = d;
        for i in (j + 1)..n {
            let mut s = a[i][j];
            for k in 0..j {
                s -= a[i][k] * a[j][k];
            }
            a[i][j] = s / d;
        }
    }
    Ok(())
}

/// Solves L·Lᵀ x = b in place, with `l` from [`cholesky_factor`].
pub fn cholesky_solve<const M: usize>(l: &[[f64; M]; M], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i][k] * b[k];
        }
        b[i] = s / l[i][i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in (i + 1)..n {
            s -= l[k][i] * b[k];
        }
        b[i] = s / l[i][i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves_spd_system() {
        let mut a = [[0.0; 4]; 4];
        let x_true = [1.0, -2.0, 0.5, 3.0];
        for (i, row) in a.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = 1.0 / (1.0 + i as f64 + j as f64) + if i == j { 1.0 } else { 0.0 };
            }
        }
        let mut b = [0.0; 4];
        for i in 0..4 {
            b[i] = (0..4).map(|j| a[i][j] * x_true[j]).sum();
        }
        cholesky_factor(&mut a, 4).unwrap();
        cholesky_solve(&a, 4, &mut b);
        for i in 0..4 {
            assert!((b[i] - x_true[i]).abs() < 1e-12);
        }
        let mut neg = [[-1.0]];
        assert_eq!(cholesky_factor(&mut neg, 1), Err(NotPositiveDefinite));
    }
}
