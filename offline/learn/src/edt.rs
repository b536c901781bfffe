//! Exact Euclidean distance transform of sampled functions (Felzenszwalb & Huttenlocher,
//! "Distance Transforms of Sampled Functions", 2012): D(p) = min_q (|p − q|² + f(q)) on a
//! regular grid, separable into 1-D lower envelopes of parabolas, linear time per axis.

/// Stands for +∞ in inputs (no site); kept finite so the envelope arithmetic stays exact.
pub const FAR: f64 = 1e20;

/// 1-D transform of `f` (length n) into `d`: d(p) = min_q ((p − q)² + f(q)), in grid units.
/// `v` (n) and `z` (n + 1) are scratch.
fn transform_1d(f: &[f64], d: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    if n == 0 {
        return;
    }
    let mut k = 0;
    v[0] = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        // Intersection of the parabola from q with the rightmost one of the envelope; pop
        // parabolas it hides (z[0] = −∞ stops the loop).
        let mut s;
        loop {
            let p = v[k];
            s = ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q - p) as f64);
            if s <= z[k] {
                k -= 1;
            } else {
                break;
            }
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    let mut k = 0;
    for (p, out) in d.iter_mut().enumerate() {
        while z[k + 1] < p as f64 {
            k += 1;
        }
        let q = v[k];
        *out = ((p as f64 - q as f64).powi(2) + f[q]).min(FAR);
    }
}

/// 3-D transform in place of `f` on a grid of `dims` nodes (x-major: index
/// (i·ny + j)·nz + k), in squared grid units. Sites have finite values (0 for plain
/// distance), non-sites [`FAR`].
pub fn transform_3d(f: &mut [f64], dims: [usize; 3]) {
    let [nx, ny, nz] = dims;
    assert_eq!(f.len(), nx * ny * nz, "grid size");
    let n = nx.max(ny).max(nz);
    let (mut line, mut out) = (vec![0.0; n], vec![0.0; n]);
    let (mut v, mut z) = (vec![0usize; n], vec![0.0; n + 1]);
    let mut pass =
        |len: usize, count: usize, index: &dyn Fn(usize, usize) -> usize, f: &mut [f64]| {
            for c in 0..count {
                for t in 0..len {
                    line[t] = f[index(c, t)];
                }
                transform_1d(&line[..len], &mut out[..len], &mut v, &mut z);
                for t in 0..len {
                    f[index(c, t)] = out[t];
                }
            }
        };
    pass(nz, nx * ny, &|c, t| c * nz + t, f);
    pass(ny, nx * nz, &|c, t| ((c / nz) * ny + t) * nz + c % nz, f);
    pass(nx, ny * nz, &|c, t| (t * ny + c / nz) * nz + c % nz, f);
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    #[test]
    fn equals_brute_force() {
        let mut rng = StdRng::seed_from_u64(7);
        for trial in 0..20 {
            let dims = [
                rng.random_range(1..9),
                rng.random_range(1..9),
                rng.random_range(1..9),
            ];
            let n = dims[0] * dims[1] * dims[2];
            let f: Vec<f64> = (0..n)
                .map(|_| match rng.random_range(0..10) {
                    0 => 0.0,
                    1 => rng.random_range(0.0..5.0),
                    _ => FAR,
                })
                .collect();
            let mut d = f.clone();
            transform_3d(&mut d, dims);
            let at = |i: usize| {
                [
                    i / (dims[1] * dims[2]),
                    (i / dims[2]) % dims[1],
                    i % dims[2],
                ]
            };
            for p in 0..n {
                let pp = at(p);
                let mut best = FAR;
                for q in 0..n {
                    if f[q] >= FAR {
                        continue;
                    }
                    let qq = at(q);
                    let r2: usize = (0..3).map(|a| pp[a].abs_diff(qq[a]).pow(2)).sum();
                    best = best.min(r2 as f64 + f[q]);
                }
                assert!(
                    (d[p] - best).abs() < 1e-9 || (best >= FAR && d[p] >= FAR * 0.5),
                    "trial {trial} dims {dims:?} node {pp:?}: {} vs {best}",
                    d[p]
                );
            }
        }
    }
}
