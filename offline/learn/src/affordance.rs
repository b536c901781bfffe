//! Affordance sets (Alg. 3, line 9): relative poses T_{f_r}^{f_a}, de-duplicated with a
//! tolerance (repeated programs reach the same stance and grasp up to log rounding).

use prf_shared::se3::{Pose, log, pose_from_array, pose_to_array};

/// Two affordances closer than this in translation (m) and rotation (rad) are one.
pub const TRANSLATION_TOL: f64 = 1e-3;
pub const ROTATION_TOL: f64 = 2e-3;

/// A set of poses with tolerance; keeps the first pose seen of each cluster ([`quantized`])
/// and counts how often each was demonstrated.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AffordanceSet {
    pub poses: Vec<Pose>,
    pub counts: Vec<usize>,
}

impl AffordanceSet {
    /// Adds `p`, quantized (or counts it if an equal one is present); returns its index.
    pub fn insert(&mut self, p: Pose) -> usize {
        let p = quantized(&p);
        if let Some(i) = self.find(&p) {
            self.counts[i] += 1;
            return i;
        }
        self.poses.push(p);
        self.counts.push(1);
        self.poses.len() - 1
    }

    /// Index of a pose equal to `p` within the tolerance.
    pub fn find(&self, p: &Pose) -> Option<usize> {
        self.poses.iter().position(|q| same(p, q))
    }

    pub fn len(&self) -> usize {
        self.poses.len()
    }

    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }
}

/// The step affordance poses are kept to: metres of translation, and per component of the
/// unit quaternion. Far below the tolerances, it makes programs that reach the same stance
/// or grasp up to log rounding give the same bits.
pub const QUANTUM: f64 = 1e-6;

/// `p` with its translation and quaternion rounded to [`QUANTUM`] (the quaternion then
/// normalized).
pub fn quantized(p: &Pose) -> Pose {
    // + 0.0: −0 and +0 are one value.
    pose_from_array(pose_to_array(p).map(|v| (v / QUANTUM).round() * QUANTUM + 0.0)).unwrap_or(*p)
}

/// True if `a` and `b` are equal within the tolerances.
pub fn same(a: &Pose, b: &Pose) -> bool {
    let d = a.inverse() * b;
    d.translation.vector.norm() < TRANSLATION_TOL && log(&d.rotation).norm() < ROTATION_TOL
}
