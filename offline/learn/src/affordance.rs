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
/// normalized), the quaternion's sign chosen: q and −q are one rotation, and of the two the
/// one whose first non-zero component (w, i, j, k) is positive is kept. [`pose_to_array`]
/// makes w ≥ 0, which leaves the sign of a half turn (w rounded to 0) to rounding.
pub fn quantized(p: &Pose) -> Pose {
    // + 0.0: −0 and +0 are one value.
    let mut a = pose_to_array(p).map(|v| (v / QUANTUM).round() * QUANTUM + 0.0);
    if a[3..].iter().find(|v| **v != 0.0).is_some_and(|v| *v < 0.0) {
        for v in &mut a[3..] {
            *v = -*v + 0.0;
        }
    }
    pose_from_array(a).unwrap_or(*p)
}

/// True if `a` and `b` are equal within the tolerances.
pub fn same(a: &Pose, b: &Pose) -> bool {
    let d = a.inverse() * b;
    d.translation.vector.norm() < TRANSLATION_TOL && log(&d.rotation).norm() < ROTATION_TOL
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
    use prf_shared::se3::pose_bits;

    fn pose(w: f64, i: f64, j: f64, k: f64) -> Pose {
        Isometry3::from_parts(
            Translation3::new(0.0, 0.0, 0.1),
            UnitQuaternion::from_quaternion(Quaternion::new(w, i, j, k)),
        )
    }

    /// A half turn reached from either side of w = 0, or as −q, is one learned pose, bit for
    /// bit (the example's "top" grasps are half turns about x): the order programs come in
    /// does not choose its sign.
    #[test]
    fn a_half_turn_is_quantized_to_one_sign() {
        for (i, j, k) in [
            (1.0, 0.0, 0.0),
            (0.0, -1.0, 0.0),
            (0.6, 0.0, -0.8),
            (0.0, 0.0, 1.0),
        ] {
            let a = quantized(&pose(1e-9, i, j, k));
            assert_eq!(pose_bits(&a), pose_bits(&quantized(&pose(-1e-9, i, j, k))));
            assert_eq!(pose_bits(&a), pose_bits(&quantized(&pose(0.0, -i, -j, -k))));
            let first = [a.rotation.i, a.rotation.j, a.rotation.k]
                .into_iter()
                .find(|v| *v != 0.0);
            assert!(
                a.rotation.w == 0.0 && first.is_some_and(|v| v > 0.0),
                "{a:?}"
            );
        }
        // Not a half turn: w > 0 already chooses the sign, as before.
        let q = quantized(&pose(0.5, -0.5, 0.5, -0.5));
        assert_eq!(
            pose_bits(&q),
            pose_bits(&quantized(&pose(-0.5, 0.5, -0.5, 0.5)))
        );
        assert!(q.rotation.w > 0.0 && q.rotation.i < 0.0);
    }
}
