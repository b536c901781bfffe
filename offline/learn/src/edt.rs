//! Exact Euclidean distance transform of sampled functions (Felzenszwalb & Huttenlocher,
//! "Distance Transforms of Sampled Functions", 2012): D(p) = min_q (|p − q|² + f(q)) on a
//! regular grid, separable into 1-D lower envelopes of parabolas, linear time per axis.

use rayon::prelude::*;

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
/// distance), non-sites [`FAR`]. One axis after the other, each axis's lines transformed in
/// parallel (each line alike whichever thread takes it: the same bits as one at a time).
pub fn transform_3d(f: &mut [f64], dims: [usize; 3]) {
    let [nx, ny, nz] = dims;
    assert_eq!(f.len(), nx * ny * nz, "grid size");
    if f.is_empty() {
        return;
    }
    // Along z: each line is a contiguous run.
    f.par_chunks_mut(nz)
        .for_each_init(|| Lines::new(nz), |l, line| l.transform(line, 0, 1, nz));
    // Along y: each x slab holds its lines, nz apart.
    f.par_chunks_mut(ny * nz).for_each_init(
        || Lines::new(ny),
        |l, slab| {
            for k in 0..nz {
                l.transform(slab, k, nz, ny);
            }
        },
    );
    // Along x: a line crosses every slab, so each (j, k) line is transformed into `across`
    // (j-major, then k, then i), which the slabs then read back.
    let mut across = vec![0.0; f.len()];
    let read: &[f64] = f;
    across.par_chunks_mut(nz * nx).enumerate().for_each_init(
        || Lines::new(nx),
        |l, (j, row)| {
            for k in 0..nz {
                l.load(nx, |t| read[(t * ny + j) * nz + k]);
                l.run(nx);
                row[k * nx..(k + 1) * nx].copy_from_slice(&l.out[..nx]);
            }
        },
    );
    f.par_chunks_mut(ny * nz).enumerate().for_each(|(i, slab)| {
        for (jk, v) in slab.iter_mut().enumerate() {
            *v = across[jk * nx + i];
        }
    });
}

/// One thread's buffers for [`transform_1d`] of lines up to a length.
struct Lines {
    line: Vec<f64>,
    out: Vec<f64>,
    v: Vec<usize>,
    z: Vec<f64>,
}

impl Lines {
    fn new(n: usize) -> Self {
        Lines {
            line: vec![0.0; n],
            out: vec![0.0; n],
            v: vec![0; n],
            z: vec![0.0; n + 1],
        }
    }

    /// Reads a line of `len` values, value t from `at(t)`.
    fn load(&mut self, len: usize, at: impl Fn(usize) -> f64) {
        for (t, x) in self.line[..len].iter_mut().enumerate() {
            *x = at(t);
        }
    }

    /// Transforms the loaded line into `out`.
    fn run(&mut self, len: usize) {
        transform_1d(
            &self.line[..len],
            &mut self.out[..len],
            &mut self.v,
            &mut self.z,
        );
    }

    /// Transforms in place the line of `len` values of `data` from `start`, `stride` apart.
    fn transform(&mut self, data: &mut [f64], start: usize, stride: usize, len: usize) {
        self.load(len, |t| data[start + t * stride]);
        self.run(len);
        for (t, x) in self.out[..len].iter().enumerate() {
            data[start + t * stride] = *x;
        }
    }
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
