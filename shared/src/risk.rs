//! The risk of a trajectory in a learned workspace (Eq. 16): the one home of the risk,
//! used by learning, planning and tests alike.
//!
//! R(q(t), Ω+) = η(max_t max_j (sdf_Ω+(c_j(t)) + r_j)) with η(x) = max(x, 0): the deepest
//! any collision sphere (centre c_j, radius r_j) reaches out of the dilated safe workspace.
//! With a conservative field (see [`crate::field`]) a risk of 0 certifies that every sphere
//! stays inside Ω+.

use crate::field::{DistanceField, Hint};
use crate::kinematics::ArmKinematics;
use crate::robot::{MAX_SPHERES, RobotModel};
use crate::se3::Pose;
use nalgebra::Vector3;

/// η(x) = max(x, 0) (Sec. 4.1).
#[inline]
pub fn eta(x: f64) -> f64 {
    if x > 0.0 { x } else { 0.0 }
}

/// Running maximum of Eq. 16 along a trajectory, one configuration at a time (the planner's
/// per-step call; learning and the tests use it too).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RiskAccumulator {
    excess: f64,
    /// Per sphere, the lookup that settled it last (its term and anchor).
    hints: [Hint; MAX_SPHERES],
}

impl Default for RiskAccumulator {
    fn default() -> Self {
        RiskAccumulator {
            excess: f64::NEG_INFINITY,
            hints: [Hint::default(); MAX_SPHERES],
        }
    }
}

impl RiskAccumulator {
    /// Adds one configuration; returns the risk so far. A NaN makes the risk infinite (never
    /// certified).
    ///
    /// Only spheres that can raise the risk are looked up in full: a sphere whose lookup
    /// already shows sdf + r ≤ max(excess so far, 0) cannot change η(max), so the lookup
    /// stops there ([`DistanceField::distance_upto`]); a sphere still within the slack of its
    /// last settled lookup is not looked up at all (see [`Hint`]). The risk is exact; the
    /// excess is exact once positive and otherwise an upper bound ≤ 0.
    pub fn add(
        &mut self,
        model: &RobotModel,
        field: &impl DistanceField,
        arm_base: &Pose,
        kin: &ArmKinematics,
    ) -> f64 {
        let mut centres = [Vector3::zeros(); MAX_SPHERES];
        kin.sphere_centres_in(model, arm_base, &mut centres);
        self.add_centres(model, field, &centres)
    }

    /// [`RiskAccumulator::add`] on a configuration's sphere centres in the field's frame
    /// ([`ArmKinematics::sphere_centres_in`], one per sphere of `model`).
    pub fn add_centres(
        &mut self,
        model: &RobotModel,
        field: &impl DistanceField,
        centres: &[Vector3<f64>],
    ) -> f64 {
        for ((s, p), hint) in model.spheres.iter().zip(centres).zip(&mut self.hints) {
            let level = eta(self.excess);
            let stop = level - s.radius;
            let d = field.distance_upto(p, stop, hint);
            // Settled at or below the stop, the sphere cannot raise the risk: its bound (which
            // may be the stop itself, and (level − r) + r can round above level) is capped.
            let e = if d <= stop {
                (d + s.radius).min(level)
            } else {
                d + s.radius
            };
            if e.is_nan() {
                self.excess = f64::INFINITY;
                break;
            }
            self.excess = self.excess.max(e);
        }
        self.risk()
    }

    /// η(max excess); 0 for an empty trajectory.
    pub fn risk(&self) -> f64 {
        eta(self.excess)
    }

    /// The maximum excess before η: exact when positive; when ≤ 0 an upper bound (≤ 0).
    pub fn excess(&self) -> f64 {
        self.excess
    }
}
