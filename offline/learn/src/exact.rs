//! The reference Ω+: the dilated demonstrated balls themselves, searched exhaustively, to
//! measure the learned field ([`prf_shared::field`]) against.
//!
//! Ω+ = Ω ⊕ B_ε(0) (Eq. 14) with Ω the union of the robot spheres over the demonstrated
//! configurations (Eq. 12) is the union of the balls B(c_j, r_j + ε). Its distance
//! d(x) = min_j (|x − c_j| − r_j − ε) is the exact signed distance outside Ω+; inside, it is
//! the depth of the deepest single ball, an upper bound of the union's signed distance (the
//! union can be deeper where balls overlap). So it is never below the true signed distance,
//! as the field's contract asks, and a sphere it rates at risk 0 (Eq. 16) lies inside one
//! demonstrated ball: the check an independent evaluation of Eq. 14–16 makes.
//!
//! The balls are bucketed in a grid of cubes so that a lookup reads the cubes nearest first
//! and stops when no unread ball can be nearer; [`BallUnion::distance_brute`] reads every
//! ball (the tests compare the two).

use crate::in_file::Spheres;
use nalgebra::Vector3;
use prf_shared::field::{DistanceField, Hint};

/// Edge of the bucket cubes, m.
pub const BUCKET: f64 = 0.05;

/// A union of balls with exhaustive lookups of min_j (|x − c_j| − R_j).
#[derive(Clone, Debug)]
pub struct BallUnion {
    /// (centre, radius R_j), bucket by bucket.
    balls: Vec<(Vector3<f64>, f64)>,
    /// Bucket b holds `balls[start[b]..start[b + 1]]`, sorted by depth at its centre.
    start: Vec<u32>,
    /// Per bucket, its largest radius (0 for an empty bucket).
    largest: Vec<f64>,
    origin: Vector3<f64>,
    dims: [i64; 3],
    /// The largest radius of all.
    r_max: f64,
}

impl BallUnion {
    /// The union of `balls` (centre, radius).
    pub fn new(balls: impl IntoIterator<Item = (Vector3<f64>, f64)>) -> Self {
        let mut balls: Vec<(Vector3<f64>, f64)> = balls
            .into_iter()
            .filter(|(c, r)| c.iter().all(|v| v.is_finite()) && r.is_finite())
            .collect();
        let lo = balls
            .iter()
            .fold(Vector3::repeat(f64::INFINITY), |a, (c, _)| a.inf(c));
        let hi = balls
            .iter()
            .fold(Vector3::repeat(f64::NEG_INFINITY), |a, (c, _)| a.sup(c));
        let origin = if balls.is_empty() {
            Vector3::zeros()
        } else {
            lo
        };
        let dims: [i64; 3] = core::array::from_fn(|a| {
            if balls.is_empty() {
                1
            } else {
                ((hi[a] - lo[a]) / BUCKET).floor() as i64 + 1
            }
        });
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let bucket = |c: &Vector3<f64>| -> usize {
            let i: [i64; 3] =
                core::array::from_fn(|a| (((c[a] - origin[a]) / BUCKET) as i64).min(dims[a] - 1));
            ((i[0] * dims[1] + i[1]) * dims[2] + i[2]) as usize
        };
        let centre_of = |b: usize| -> Vector3<f64> {
            let b = b as i64;
            let (i, j, k) = (
                b / (dims[1] * dims[2]),
                (b / dims[2]) % dims[1],
                b % dims[2],
            );
            origin + (Vector3::new(i as f64, j as f64, k as f64) + Vector3::repeat(0.5)) * BUCKET
        };
        let depth = |b: usize, (c, r): &(Vector3<f64>, f64)| (centre_of(b) - c).norm() - r;
        balls.sort_by(|x, y| {
            let (bx, by) = (bucket(&x.0), bucket(&y.0));
            bx.cmp(&by).then(depth(bx, x).total_cmp(&depth(by, y)))
        });
        let mut start = vec![0u32; n + 1];
        let mut largest = vec![0.0f64; n];
        for (c, r) in &balls {
            let b = bucket(c);
            start[b + 1] += 1;
            largest[b] = largest[b].max(*r);
        }
        for b in 0..n {
            start[b + 1] += start[b];
        }
        let r_max = balls.iter().map(|(_, r)| *r).fold(0.0, f64::max);
        BallUnion {
            balls,
            start,
            largest,
            origin,
            dims,
            r_max,
        }
    }

    /// The demonstrated spheres of a sweep dilated by ε: Ω+ of Eq. 14.
    pub fn dilated(spheres: &Spheres, epsilon: f64) -> Self {
        BallUnion::new(spheres.iter().map(|s| (s.centre, s.radius + epsilon)))
    }

    /// Number of balls.
    pub fn len(&self) -> usize {
        self.balls.len()
    }

    pub fn is_empty(&self) -> bool {
        self.balls.is_empty()
    }

    /// min_j (|x − c_j| − R_j) over every ball, one by one (∞ for no ball).
    pub fn distance_brute(&self, x: &Vector3<f64>) -> f64 {
        self.balls
            .iter()
            .map(|(c, r)| (x - c).norm() - r)
            .fold(f64::INFINITY, f64::min)
    }

    /// The buckets at Chebyshev distance `k` from bucket `c` (coordinates may lie outside the
    /// grid; those are skipped).
    fn shell(&self, c: [i64; 3], k: i64, mut visit: impl FnMut(usize) -> bool) -> bool {
        let lo: [i64; 3] = core::array::from_fn(|a| (c[a] - k).max(0));
        let hi: [i64; 3] = core::array::from_fn(|a| (c[a] + k).min(self.dims[a] - 1));
        for i in lo[0]..=hi[0] {
            for j in lo[1]..=hi[1] {
                let on_face = (i - c[0]).abs() == k || (j - c[1]).abs() == k;
                let mut l = lo[2];
                while l <= hi[2] {
                    if on_face || (l - c[2]).abs() == k {
                        let b = ((i * self.dims[1] + j) * self.dims[2] + l) as usize;
                        if !visit(b) {
                            return false;
                        }
                        l += 1;
                    } else {
                        // Inside the shell: jump to its far face.
                        l = c[2] + k;
                    }
                }
            }
        }
        true
    }

    /// Distance from `x` to bucket `b`'s cube.
    fn to_bucket(&self, x: &Vector3<f64>, b: usize) -> f64 {
        let b = b as i64;
        let idx = [
            b / (self.dims[1] * self.dims[2]),
            (b / self.dims[2]) % self.dims[1],
            b % self.dims[2],
        ];
        let mut d2 = 0.0;
        for a in 0..3 {
            let lo = self.origin[a] + idx[a] as f64 * BUCKET;
            let e = (lo - x[a]).max(x[a] - lo - BUCKET).max(0.0);
            d2 += e * e;
        }
        // Less a rounding allowance: a centre may lie a hair outside its bucket's cube.
        d2.sqrt() - 1e-12
    }

    /// min_j (|x − c_j| − R_j), or the first value found at most `stop`.
    fn lookup(&self, x: &Vector3<f64>, stop: f64) -> f64 {
        if self.balls.is_empty() || !x.iter().all(|v| v.is_finite()) {
            return if self.balls.is_empty() {
                f64::INFINITY
            } else {
                f64::NAN
            };
        }
        let c: [i64; 3] = core::array::from_fn(|a| {
            ((x[a] - self.origin[a]) / BUCKET).floor().clamp(-1e9, 1e9) as i64
        });
        // Shells past this one lie wholly outside the grid.
        let last = (0..3)
            .map(|a| c[a].max(self.dims[a] - 1 - c[a]).max(-c[a]))
            .max()
            .unwrap_or(0);
        let mut best = f64::INFINITY;
        for k in 0..=last {
            let done = !self.shell(c, k, |b| {
                if self.to_bucket(x, b) - self.largest[b] >= best {
                    return true;
                }
                for (centre, r) in &self.balls[self.start[b] as usize..self.start[b + 1] as usize] {
                    best = best.min((x - centre).norm() - r);
                    if best <= stop {
                        return false;
                    }
                }
                true
            });
            // Every unread ball is at least k buckets of x away.
            if done || best <= k as f64 * BUCKET - self.r_max {
                break;
            }
        }
        best
    }
}

impl DistanceField for BallUnion {
    fn distance(&self, p: &Vector3<f64>) -> f64 {
        self.lookup(p, f64::NEG_INFINITY)
    }

    fn distance_upto(&self, p: &Vector3<f64>, stop: f64, _hint: &mut Hint) -> f64 {
        self.lookup(p, stop)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    /// Balls along a few random walks (as swept spheres lie), of radii 50–150 mm.
    fn walks(rng: &mut StdRng) -> Vec<(Vector3<f64>, f64)> {
        let mut balls = Vec::new();
        for _ in 0..6 {
            let mut c = Vector3::new(
                rng.random_range(-0.5..0.5),
                rng.random_range(-0.5..0.5),
                rng.random_range(0.0..1.0),
            );
            let r = rng.random_range(0.05..0.15);
            for _ in 0..300 {
                c += Vector3::new(
                    rng.random_range(-0.004..0.004),
                    rng.random_range(-0.004..0.004),
                    rng.random_range(-0.004..0.004),
                );
                balls.push((c, r));
            }
        }
        balls
    }

    #[test]
    fn the_bucketed_lookup_is_the_brute_force_minimum() {
        let mut rng = StdRng::seed_from_u64(3);
        let u = BallUnion::new(walks(&mut rng));
        assert_eq!(u.len(), 1800);
        for _ in 0..3000 {
            // Inside, near and far (up to 2 m outside the balls' box).
            let x = Vector3::new(
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
                rng.random_range(-1.5..2.5),
            ) * if rng.random_bool(0.7) { 0.4 } else { 1.0 };
            let (fast, brute) = (u.distance(&x), u.distance_brute(&x));
            assert_eq!(fast, brute, "at {x:?}");
        }
    }

    #[test]
    fn a_lookup_with_a_stop_returns_an_upper_bound_at_most_the_stop_or_the_exact_value() {
        let mut rng = StdRng::seed_from_u64(4);
        let u = BallUnion::new(walks(&mut rng));
        for _ in 0..2000 {
            let x = Vector3::new(
                rng.random_range(-0.8..0.8),
                rng.random_range(-0.8..0.8),
                rng.random_range(-0.3..1.3),
            );
            let stop = rng.random_range(-0.15..0.1);
            let exact = u.distance_brute(&x);
            let v = u.distance_upto(&x, stop, &mut Hint::default());
            if exact > stop {
                assert_eq!(v, exact);
            } else {
                assert!(v <= stop && v >= exact, "{v} against {exact}, stop {stop}");
            }
        }
    }

    #[test]
    fn no_ball_is_infinitely_far_and_nan_stays_nan() {
        let empty = BallUnion::new([]);
        assert!(empty.is_empty());
        assert_eq!(empty.distance(&Vector3::zeros()), f64::INFINITY);
        let one = BallUnion::new([(Vector3::zeros(), 0.1)]);
        assert!(one.distance(&Vector3::repeat(f64::NAN)).is_nan());
        assert!((one.distance(&Vector3::new(0.3, 0.0, 0.0)) - 0.2).abs() < 1e-15);
    }
}
