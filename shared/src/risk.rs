//! The risk of a trajectory in a learned workspace (Eq. 16): the one home of the risk,
//! used by learning, planning and tests alike.
//!
//! R(q(t), Ω+) = η(max_t max_j (sdf_Ω+(c_j(t)) + r_j)) with η(x) = max(x, 0): the deepest
//! any collision sphere (centre c_j, radius r_j) reaches out of the dilated safe workspace.
//! With a conservative field (see [`crate::field`]) a risk of 0 certifies that every sphere
//! stays inside Ω+.

use crate::field::{DistanceField, Hint};
use crate::float::norm;
use crate::kinematics::{ArmKinematics, Frame, FramesIn};
use crate::robot::{MAX_SPHERES, N_FRAMES, RobotModel};
use crate::se3::Pose;
use core::f64::consts::FRAC_1_SQRT_2;
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
    /// How far each sphere may have moved since its last lookup.
    travel: Travel,
    /// Spheres placed and looked up; spheres settled by their leash.
    counts: (u64, u64),
}

impl Default for RiskAccumulator {
    fn default() -> Self {
        RiskAccumulator {
            excess: f64::NEG_INFINITY,
            hints: [Hint::default(); MAX_SPHERES],
            travel: Travel::default(),
            counts: (0, 0),
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
    /// last settled lookup is not looked up at all (see [`Hint`]), and a sphere that cannot
    /// have left that slack since (`Travel`) is not even placed. The risk is exact; the
    /// excess is exact once positive and otherwise an upper bound ≤ 0.
    pub fn add(
        &mut self,
        model: &RobotModel,
        field: &impl DistanceField,
        arm_base: &Pose,
        kin: &ArmKinematics,
    ) -> f64 {
        let n = model.spheres.len().min(MAX_SPHERES);
        // Bit i: sphere i is to be placed and looked up.
        let mut placed = if n == 0 { 0 } else { u64::MAX >> (64 - n) };
        let mut leashed = f64::NEG_INFINITY;
        if field.settles_by_travel() {
            self.travel.step(kin, arm_base);
            // First, without branching, the spheres settled by their leash (their lookup would
            // end in the anchor's first test, with its value) and max(d + r) of them.
            let Travel { moved, leashes, .. } = &self.travel;
            for (i, (s, leash)) in model.spheres.iter().zip(leashes).enumerate() {
                let held = moved.get(s.link as usize).is_some_and(|m| leash.holds(m));
                let settled = self.hints[i].settled() + s.radius;
                leashed = if held && settled > leashed {
                    settled
                } else {
                    leashed
                };
                placed &= !(u64::from(held) << i);
            }
            self.counts.1 += (n - placed.count_ones() as usize) as u64;
        } else {
            self.travel.last = None;
        }
        let Travel { moved, leashes, .. } = &mut self.travel;
        // Then the others in their order, each placed and looked up.
        let mut frames = FramesIn::new(kin, arm_base);
        while placed != 0 {
            let i = placed.trailing_zeros() as usize;
            placed &= placed - 1;
            let (s, hint, leash) = (&model.spheres[i], &mut self.hints[i], &mut leashes[i]);
            self.counts.0 += 1;
            let link = s.link as usize;
            let level = eta(self.excess);
            let stop = level - s.radius;
            let p = frames.point(link, &s.centre).unwrap_or_else(Vector3::zeros);
            let d = field.distance_upto(&p, stop, hint);
            let m = moved.get(link).copied().unwrap_or_default();
            leash.tie(field.settled_within(&p, stop, hint), &s.centre, m);
            if !raise(&mut self.excess, d, stop, level, s.radius) {
                break;
            }
        }
        // A leashed sphere's d is at most its stop, so its term min(d + r, level) never
        // raises the level the others meet; taken last, capped at the final level, it leaves
        // the excess as it would have in its turn (the levels differ only where both are ≤ 0
        // before the final level is positive, and then the term is below it).
        self.excess = self.excess.max(leashed.min(eta(self.excess)));
        self.risk()
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
            if !raise(&mut self.excess, d, stop, level, s.radius) {
                break;
            }
        }
        self.risk()
    }

    /// (spheres placed and looked up, spheres settled by their leash) by [`RiskAccumulator::add`]
    /// so far.
    pub fn counts(&self) -> (u64, u64) {
        self.counts
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

/// Takes a sphere's lookup `d` (against `stop` = `level` − `radius`) into the running maximum
/// `excess`; false once it is NaN (the risk is then infinite).
#[inline(always)]
fn raise(excess: &mut f64, d: f64, stop: f64, level: f64, radius: f64) -> bool {
    // Settled at or below the stop, the sphere cannot raise the risk: its bound (which may be
    // the stop itself, and (level − r) + r can round above level) is capped.
    let e = if d <= stop {
        (d + radius).min(level)
    } else {
        d + radius
    };
    if e.is_nan() {
        *excess = f64::INFINITY;
        return false;
    }
    *excess = excess.max(e);
    true
}

/// An allowance added to each frame's ‖ΔR‖ for rounding: FK's rotation matrices are products
/// of at most nine rotations and lie within about 5e-15 of a rotation (δ), and the spectral
/// norm of a difference of two such matrices exceeds ‖·‖_F / √2 by at most (2 + √2) δ.
const TURN_ROUNDING: f64 = 2e-14;

/// Bounds of how far each collision sphere's centre moved since its last lookup, from the
/// motion of its frame between the configurations added.
///
/// A point at distance ρ from its frame's origin moves by at most |Δt| + ‖ΔR‖·ρ when the frame
/// moves by (ΔR, Δt). For two rotations θ apart, ΔR = R_a (I − R_aᵀ R_b) has the singular
/// values 2 sin(θ/2), 2 sin(θ/2) and 0, so ‖ΔR‖ = ‖ΔR‖_F / √2; [`TURN_ROUNDING`] covers how
/// far FK's matrices are from rotations. Summed over the configurations, Σ|Δt| + ρ Σ‖ΔR‖
/// bounds the distance from the centre of the last lookup; while it stays below the room that
/// lookup left ([`DistanceField::settled_within`]), the lookup is skipped.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Travel {
    /// The previous configuration's frames and arm base, `None` before the first.
    last: Option<([Frame; N_FRAMES], Pose)>,
    /// Per frame, (Σ|Δt|, Σ‖ΔR‖) over the configurations added.
    moved: [(f64, f64); N_FRAMES],
    /// Per sphere, its room since its last lookup.
    leashes: [Leash; MAX_SPHERES],
}

impl Default for Travel {
    fn default() -> Self {
        Travel {
            last: None,
            moved: [(0.0, 0.0); N_FRAMES],
            leashes: [Leash::default(); MAX_SPHERES],
        }
    }
}

impl Travel {
    /// Adds the motion of every frame from the last configuration to `kin`. A new arm base
    /// (or the first configuration) unties every leash.
    fn step(&mut self, kin: &ArmKinematics, base: &Pose) {
        match &self.last {
            Some((frames, last)) if last == base => {
                for ((a, b), m) in frames.iter().zip(&kin.frames).zip(&mut self.moved) {
                    let turn = crate::float::sqrt((b.rotation - a.rotation).norm_squared());
                    m.0 += norm(&(b.origin - a.origin));
                    m.1 += turn * FRAC_1_SQRT_2 + TURN_ROUNDING;
                }
            }
            _ => self.leashes.iter_mut().for_each(|l| l.room = 0.0),
        }
        self.last = Some((kin.frames, *base));
    }
}

/// A sphere's room around its last lookup, and where its frame's sums stood then.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Leash {
    /// The frame's (Σ|Δt|, Σ‖ΔR‖) at the lookup.
    from: (f64, f64),
    /// ρ: the centre's distance from its frame's origin.
    arm: f64,
    /// How far the centre may move; 0: none.
    room: f64,
}

impl Leash {
    /// True if the centre cannot have moved as far as the room since the lookup.
    #[inline(always)]
    fn holds(&self, moved: &(f64, f64)) -> bool {
        (moved.0 - self.from.0) + self.arm * (moved.1 - self.from.1) < self.room
    }

    /// Ties the leash at a lookup that left `room` around a centre at `centre` in its frame.
    #[inline(always)]
    fn tie(&mut self, room: f64, centre: &Vector3<f64>, moved: (f64, f64)) {
        self.room = room;
        if room > 0.0 {
            (self.from, self.arm) = (moved, norm(centre));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::JointVector;
    use crate::se3::pose_from_xyz_rpy;

    /// The travel bound against the centres' displacement computed from their positions,
    /// over random pairs of configurations 0.1 mrad to 1 rad apart.
    #[test]
    fn travel_bounds_every_centres_displacement() {
        let model = RobotModel::kmr_iiwa14();
        let base = pose_from_xyz_rpy([1.0, -2.0, 0.4], [0.0, 0.0, 2.5]);
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut r = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        };
        let (mut tightest, mut loosest) = (f64::INFINITY, 0.0f64);
        for trial in 0..3000 {
            let q0 = JointVector::from_fn(|_, _| 2.5 * r());
            let scale = [1e-4, 1e-2, 1.0][trial % 3];
            let q1 = q0 + JointVector::from_fn(|_, _| scale * r());
            let (k0, k1) = (
                ArmKinematics::new(&model, &q0),
                ArmKinematics::new(&model, &q1),
            );
            let mut travel = Travel::default();
            travel.step(&k0, &base);
            travel.step(&k1, &base);
            let mut c = [[Vector3::zeros(); MAX_SPHERES]; 2];
            k0.sphere_centres_in(&model, &base, &mut c[0]);
            k1.sphere_centres_in(&model, &base, &mut c[1]);
            for (i, s) in model.spheres.iter().enumerate() {
                let m = travel.moved[s.link as usize];
                let bound = m.0 + norm(&s.centre) * m.1;
                let moved = (c[1][i] - c[0][i]).norm();
                assert!(moved <= bound + 1e-13, "sphere {i}: {moved} > {bound}");
                if moved > 1e-6 {
                    (tightest, loosest) = (tightest.min(bound / moved), loosest.max(bound / moved));
                }
            }
        }
        // Not vacuous: some bounds are nearly tight.
        assert!(
            tightest < 1.01,
            "tightest bound {tightest}× the displacement"
        );
        assert!(loosest > 1.0);
    }
}
