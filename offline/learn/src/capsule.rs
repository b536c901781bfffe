//! Certificate capsules: the swept path of one robot sphere cut into pieces straight enough
//! that a capsule around each lies inside the demonstrated balls along it (Sec. 4.1's Ω+,
//! the union of the balls B(c, r + ε) of every demonstrated robot sphere).
//!
//! A piece runs from sample c_0 = a to c_n = b of one robot sphere's path. With the samples'
//! projections t_i onto [a, b] ascending, every point p(t) of the segment has a sample within
//! h of it, where h is the largest over consecutive pairs of max_t min(|p(t) − c_i|,
//! |p(t) − c_{i+1}|) (each |p(t) − c_i|² = (t − t_i)² + d_i², d_i the sample's distance from
//! the segment). So the capsule {x : dist(x, [a, b]) ≤ r + ε − h} lies inside ∪ B(c_i, r + ε):
//! each point of it is within r + ε − h of some p(t), and p(t) within h of some c_i.
//!
//! The samples of each robot sphere that a path adds to the sweep are cut in aligned windows
//! of [`WINDOW`], halved until each piece deviates at most [`TOLERANCE`]: a sample's capsule
//! depends only on its window of that path's new samples, so adding a path never changes the
//! capsules of another, and an addition replayed from its kept samples cuts them alike.

use nalgebra::Vector3;

/// Samples of one robot sphere's path per window (the longest piece).
pub const WINDOW: usize = 64;
/// The largest deviation h of a piece, m: a capsule's radius is r + ε − h (and the sweep's
/// de-duplication, [`DEDUP`]), so the reuse margin it certifies is about ε − 2h.
pub const TOLERANCE: f64 = 0.0012;
/// How far a demonstrated sphere may lie from the one the sweep keeps for it (two centres of
/// one 0.2 mm key differ by at most 0.2 mm per axis), m: taken off every capsule's radius, so a
/// capsule lies inside the balls of the sweep's own spheres too.
pub const DEDUP: f64 = 0.000_35;

/// A piece of a robot sphere's path: the segment [a, b] and its deviation h (with
/// [`DEDUP`]): the capsule of radius r + ε − `loss` around it lies inside Ω+.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    pub a: Vector3<f64>,
    pub b: Vector3<f64>,
    pub loss: f64,
}

impl Capsule {
    /// The piece that is one sample: its ball.
    pub fn ball(c: &Vector3<f64>) -> Self {
        Capsule {
            a: *c,
            b: *c,
            loss: DEDUP,
        }
    }
}

/// max over t ∈ [0, Δ] of min(√(t² + d0²), √((Δ − t)² + d1²)): the farthest a point of the
/// segment between two consecutive samples' projections (Δ apart, at distances d0 and d1
/// from the segment) is from the nearer of the two.
fn pair_deviation(delta: f64, d0: f64, d1: f64) -> f64 {
    if delta <= 0.0 {
        return d0.max(d1);
    }
    // The first grows with t, the second shrinks: the maximum of their minimum is where they
    // cross, or an end of the interval.
    let x = (delta * delta + d1 * d1 - d0 * d0) / (2.0 * delta);
    if x <= 0.0 {
        delta.hypot(d1)
    } else if x >= delta {
        delta.hypot(d0)
    } else {
        x.hypot(d0)
    }
}

/// The deviation h of the piece `c` (its first sample to its last; at least every sample's
/// distance from the segment), or None when the samples' projections onto its line are not
/// ascending within the segment.
pub fn deviation(c: &[Vector3<f64>]) -> Option<f64> {
    let (a, b) = (c[0], c[c.len() - 1]);
    let e = b - a;
    let length = e.norm();
    if length < 1e-9 {
        return None;
    }
    let u = e / length;
    let mut h: f64 = 0.0;
    let (mut t0, mut d0) = (0.0, 0.0);
    for p in &c[1..c.len() - 1] {
        let v = p - a;
        let t = v.dot(&u);
        if !(t >= t0 && t <= length) {
            return None;
        }
        let d = (v - u * t).norm();
        h = h.max(pair_deviation(t - t0, d0, d)).max(d);
        (t0, d0) = (t, d);
    }
    Some(h.max(pair_deviation(length - t0, d0, 0.0)))
}

/// Cuts samples `lo..=hi` of one robot sphere's path `c` into pieces of deviation at most
/// [`TOLERANCE`], halving where it is exceeded; a single sample is its own ball. Each piece
/// is (first, last, capsule); consecutive pieces share their end sample.
fn cut(c: &[Vector3<f64>], lo: usize, hi: usize, out: &mut Vec<(usize, usize, Capsule)>) {
    if lo < hi
        && let Some(h) = deviation(&c[lo..=hi]).filter(|h| *h <= TOLERANCE)
    {
        out.push((
            lo,
            hi,
            Capsule {
                a: c[lo],
                b: c[hi],
                loss: h + DEDUP,
            },
        ));
    } else if hi - lo <= 1 {
        for i in lo..=hi {
            out.push((i, i, Capsule::ball(&c[i])));
        }
    } else {
        let mid = (lo + hi) / 2;
        cut(c, lo, mid, out);
        cut(c, mid, hi, out);
    }
}

/// The pieces of one robot sphere's path `c`: window w covers samples w·[`WINDOW`] to the
/// next window's first. Returns, per sample, the index (into the second vector) of the first
/// piece holding it, and the capsules.
pub fn pieces(c: &[Vector3<f64>]) -> (Vec<u32>, Vec<Capsule>) {
    let mut of = vec![u32::MAX; c.len()];
    let mut capsules = Vec::new();
    let mut cuts = Vec::new();
    for lo in (0..c.len()).step_by(WINDOW) {
        cuts.clear();
        cut(c, lo, (lo + WINDOW).min(c.len() - 1), &mut cuts);
        for &(first, last, capsule) in &cuts {
            for o in &mut of[first..=last] {
                if *o == u32::MAX {
                    *o = capsules.len() as u32;
                }
            }
            capsules.push(capsule);
        }
    }
    (of, capsules)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// A wavy arc sampled every ~2 mm, as a robot sphere's re-sampled path.
    fn arc(n: usize, radius: f64, wobble: f64) -> Vec<Vector3<f64>> {
        (0..n)
            .map(|i| {
                let s = i as f64 * 0.002 / radius;
                Vector3::new(
                    radius * s.cos(),
                    radius * s.sin(),
                    wobble * (i as f64 * 0.7).sin(),
                )
            })
            .collect()
    }

    /// Brute force: the largest distance from a point of [a, b] (every 1 µm) to the nearest
    /// sample.
    fn farthest(c: &[Vector3<f64>], a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
        let n = ((b - a).norm() / 1e-6).ceil().max(1.0) as usize;
        (0..=n)
            .map(|k| {
                let p = a + (b - a) * (k as f64 / n as f64);
                c.iter()
                    .map(|s| (p - s).norm())
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
    }

    /// Every piece's deviation bounds the brute-force farthest point of its segment from the
    /// samples it covers, and every sample lies within the tolerance of its capsule.
    #[test]
    fn a_piece_lies_within_its_deviation_of_its_samples() {
        let mut rng = StdRng::seed_from_u64(5);
        for _ in 0..40 {
            let c = arc(
                rng.random_range(2..80),
                rng.random_range(0.05..1.0),
                rng.random_range(0.0..0.001),
            );
            let mut cuts = Vec::new();
            cut(&c, 0, c.len() - 1, &mut cuts);
            for (first, last, k) in &cuts {
                let brute = farthest(&c[*first..=*last], &k.a, &k.b);
                assert!(brute <= k.loss - DEDUP + 1e-6, "{brute} > {}", k.loss);
                assert!(k.loss - DEDUP <= TOLERANCE);
            }
            let (of, capsules) = pieces(&c);
            for (s, &o) in c.iter().zip(&of) {
                let k = &capsules[o as usize];
                let p = prf_shared::field::nearest_on_segment(s, &k.a, &k.b);
                assert!((p - s).norm() <= TOLERANCE + 1e-12);
            }
        }
    }

    /// A straight path at 2 mm is one capsule per window; a path doubling back is cut where it
    /// turns (projections must ascend).
    #[test]
    fn straight_paths_are_whole_windows_and_reversals_are_cut() {
        let line: Vec<Vector3<f64>> = (0..65)
            .map(|i| Vector3::new(i as f64 * 0.002, 0.0, 0.0))
            .collect();
        let (_, capsules) = pieces(&line);
        assert_eq!(capsules.len(), 2);
        let mut back = line.clone();
        back.extend(line.iter().rev().skip(1).take(10));
        let (of, capsules) = pieces(&back);
        for (s, &o) in back.iter().zip(&of) {
            let k = &capsules[o as usize];
            assert!(
                (prf_shared::field::nearest_on_segment(s, &k.a, &k.b) - s).norm() < 1e-12,
                "a sample off its straight capsule"
            );
        }
        assert!(deviation(&back[60..70]).is_none());
        assert!(deviation(&back[58..66]).is_none());
    }
}
