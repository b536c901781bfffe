//! How far the learned Ω+ field lies above the exact Ω+ (`prf field-error`): the field of
//! each location type against the union of its dilated demonstrated balls
//! ([`prf_learn::exact`]), at random points near the boundary, with the millimetres split by
//! where they come from.
//!
//! For a point x, three values of the signed distance, each an upper bound of the next:
//! - **field**: the blob's lookup (8 corner feature balls, certificates, quantized);
//! - **features**: min over the feature balls (the demonstrated spheres thinned to the
//!   feature spacing), unquantized: what the field could give if every lookup read them all;
//! - **exact**: min over every demonstrated ball (Eq. 14).
//!
//! field − features is the cost of the grid (one ball per node, 8 nodes per lookup) and of
//! quantization (certificates can make it negative); features − exact is the cost of
//! thinning. field − exact below 0 would mean the field is not conservative.
//!
//! What decides a risk, though, is the field at a robot sphere's centre, where sdf + r_j is
//! compared with 0 (Eq. 16), r_j deep inside Ω+. So a second set of points are demonstrated
//! spheres moved by up to a few millimetres, as a part placed off its demonstrated pose moves
//! them: per point the sphere's risk term sdf + r_j by the field and by the exact Ω+, and
//! whether each certifies it (≤ 0).

use prf_learn::Knowledge;
use prf_learn::exact::BallUnion;
use prf_learn::learn::Learner;
use prf_shared::field::DistanceField;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

/// Points are kept within this distance of the boundary, beyond ε (the band the planner's
/// decisions are made in: a robot sphere at risk 0 is at most ε inside a demonstrated one).
pub const BAND_BEYOND_EPSILON: f64 = 0.03;

/// The three distances at one point, m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub field: f64,
    pub features: f64,
    pub exact: f64,
}

/// Quantiles of a set of values, m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    pub min: f64,
    pub median: f64,
    pub p95: f64,
    pub max: f64,
}

impl Spread {
    /// The spread of `v` (NaN for none).
    pub fn of(mut v: Vec<f64>) -> Spread {
        if v.is_empty() {
            return Spread {
                min: f64::NAN,
                median: f64::NAN,
                p95: f64::NAN,
                max: f64::NAN,
            };
        }
        v.sort_by(f64::total_cmp);
        let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
        Spread {
            min: v[0],
            median: at(0.5),
            p95: at(0.95),
            max: v[v.len() - 1],
        }
    }
}

/// What was measured for one location type.
#[derive(Clone, Debug)]
pub struct TypeError {
    pub name: String,
    /// Demonstrated balls, feature balls.
    pub balls: (usize, usize),
    /// The points, each within ε + [`BAND_BEYOND_EPSILON`] of the boundary.
    pub samples: Vec<Sample>,
    /// Demonstrated spheres moved: (field, exact) risk terms sdf + r_j, m.
    pub moved: Vec<(f64, f64)>,
}

impl TypeError {
    /// field − exact.
    pub fn total(&self) -> Spread {
        Spread::of(self.samples.iter().map(|s| s.field - s.exact).collect())
    }

    /// field − features: the grid and quantization.
    pub fn grid(&self) -> Spread {
        Spread::of(self.samples.iter().map(|s| s.field - s.features).collect())
    }

    /// features − exact: the thinning.
    pub fn thinning(&self) -> Spread {
        Spread::of(self.samples.iter().map(|s| s.features - s.exact).collect())
    }

    /// Of the moved spheres the exact Ω+ certifies (risk term ≤ 0), the share the field
    /// certifies too, and how many the exact Ω+ certifies.
    pub fn moved_certified(&self) -> (f64, usize) {
        let exact: Vec<&(f64, f64)> = self.moved.iter().filter(|m| m.1 <= 0.0).collect();
        let field = exact.iter().filter(|m| m.0 <= 0.0).count();
        (field as f64 / exact.len().max(1) as f64, exact.len())
    }

    /// Share of the points where the field is within `tol` of the exact distance.
    pub fn within(&self, tol: f64) -> f64 {
        let n = self.samples.len().max(1) as f64;
        self.samples
            .iter()
            .filter(|s| s.field - s.exact <= tol)
            .count() as f64
            / n
    }
}

/// A random unit vector.
fn direction(rng: &mut StdRng) -> nalgebra::Vector3<f64> {
    loop {
        let v = nalgebra::Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let n = v.norm();
        if n > 1e-3 && n <= 1.0 {
            return v / n;
        }
    }
}

/// Measures every location type of `knowledge` (what `learner` learned) that has a field:
/// `points` random points per type near the boundary of its Ω+, and `points` demonstrated
/// spheres each moved by a random vector of length up to `moved_by`, m (seeded).
pub fn measure(
    learner: &Learner,
    knowledge: &Knowledge,
    points: usize,
    moved_by: f64,
    seed: u64,
) -> Vec<TypeError> {
    let epsilon = knowledge.config.workspace.epsilon;
    let mut out = Vec::new();
    for (t, lt) in knowledge.location_types.iter().enumerate() {
        let (Some(sweep), Some(field)) = (learner.sweep(t), lt.field.as_ref()) else {
            continue;
        };
        let name = &lt.name;
        let exact = BallUnion::dilated(&sweep.spheres, epsilon);
        let features = BallUnion::new(sweep.features().iter().map(|(c, r)| (*c, r + epsilon)));
        let field = field.field();
        let mut rng = StdRng::seed_from_u64(seed ^ t as u64);
        let band = epsilon + BAND_BEYOND_EPSILON;
        let mut samples = Vec::with_capacity(points);
        let mut tries = 0;
        while samples.len() < points && tries < 100 * points {
            tries += 1;
            let s = sweep.spheres.get(rng.random_range(0..sweep.spheres.len()));
            let u = direction(&mut rng);
            let x = s.centre + u * (s.radius + epsilon + rng.random_range(-band..band));
            let e = exact.distance(&x);
            if e.abs() > band {
                continue;
            }
            samples.push(Sample {
                field: field.distance(&x),
                features: features.distance(&x),
                exact: e,
            });
        }
        let moved = (0..points)
            .map(|_| {
                let s = sweep.spheres.get(rng.random_range(0..sweep.spheres.len()));
                // Uniform in the ball of radius `moved_by`.
                let x = s.centre
                    + direction(&mut rng) * moved_by * rng.random_range(0.0..=1.0f64).cbrt();
                (field.distance(&x) + s.radius, exact.distance(&x) + s.radius)
            })
            .collect();
        out.push(TypeError {
            name: name.clone(),
            balls: (exact.len(), features.len()),
            samples,
            moved,
        });
    }
    out
}
