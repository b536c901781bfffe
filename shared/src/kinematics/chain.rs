//! How forward kinematics composes a [`RobotModel`]'s fixed rotations, read once from the
//! model: a few bytes per joint, so a run can keep its own copy.

use super::frame::Frame;
use crate::NA;
use crate::robot::RobotModel;
use crate::se3::Pose;
use nalgebra::{Matrix3, Unit, Vector3};

/// How far an entry of a fixed rotation may lie from 0 or ±1 and still be read as that value.
/// URDF states origins as decimal roll-pitch-yaw angles, so π/2 comes in rounded and the
/// iiwa's origin rotations are signed permutations only to about 1e-16; taking them as exact
/// moves no point of the arm by more than 1e-12 of its distance from the joint.
pub const PERMUTATION_TOLERANCE: f64 = 1e-12;

/// A fixed rotation M as FK applies it, R ↦ R M.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Turn {
    /// M = I (a flange or TCP without a turn).
    Identity,
    /// M is a signed permutation (every iiwa origin): column j of R M is `sign[j]` (±1) times
    /// column `index[j]` of R, with no products to round.
    Columns { index: [u8; 3], sign: [i8; 3] },
    /// Any other rotation: the model's quaternion as a matrix, and a matrix product.
    General,
}

impl Turn {
    /// The turn of `r`: [`Turn::Columns`] when every column of its matrix is ± a distinct unit
    /// axis within [`PERMUTATION_TOLERANCE`], [`Turn::Identity`] for the identity.
    fn of(r: &nalgebra::UnitQuaternion<f64>) -> Turn {
        let m = r.to_rotation_matrix().into_inner();
        let mut index = [0u8; 3];
        let mut sign = [0i8; 3];
        let mut used = [false; 3];
        for c in 0..3 {
            let col = m.column(c);
            let near = |v: f64, to: f64| (v.abs() - to).abs() <= PERMUTATION_TOLERANCE;
            let Some(r) = (0..3).find(|&r| near(col[r], 1.0)) else {
                return Turn::General;
            };
            if used[r] || !(0..3).all(|k| k == r || near(col[k], 0.0)) {
                return Turn::General;
            }
            used[r] = true;
            index[c] = r as u8;
            sign[c] = if col[r] > 0.0 { 1 } else { -1 };
        }
        if index == [0, 1, 2] && sign == [1; 3] {
            Turn::Identity
        } else {
            Turn::Columns { index, sign }
        }
    }

    /// The columns of R M, M the rotation this turn was read from.
    #[inline(always)]
    fn after(
        &self,
        r: &Matrix3<f64>,
        rotation: &nalgebra::UnitQuaternion<f64>,
    ) -> [Vector3<f64>; 3] {
        match self {
            Turn::Identity => [r.column(0).into(), r.column(1).into(), r.column(2).into()],
            Turn::Columns { index, sign } => {
                let col = |j: usize| r.column(index[j] as usize) * f64::from(sign[j]);
                [col(0), col(1), col(2)]
            }
            Turn::General => {
                let p = r * rotation.to_rotation_matrix().into_inner();
                [p.column(0).into(), p.column(1).into(), p.column(2).into()]
            }
        }
    }
}

/// A fixed translation t as FK applies it, p ↦ p + R t.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Shift {
    /// `Along(k)`: t_k is t's only non-zero component (every iiwa origin, flange and TCP),
    /// applied as p + t_k · column k of R. The products left out are of zeros, so this is
    /// R t + p to the sign of a zero.
    Along(u8),
    /// Any other t: R t + p.
    General,
}

impl Shift {
    /// The shift of `t`: [`Shift::Along`] its one non-zero axis (x for t = 0).
    fn of(t: &Vector3<f64>) -> Shift {
        let mut nonzero = (0..3).filter(|&k| t[k] != 0.0);
        match (nonzero.next(), nonzero.next()) {
            (Some(k), None) => Shift::Along(k as u8),
            (None, _) => Shift::Along(0),
            _ => Shift::General,
        }
    }

    /// The origin of f · (t, ·): R t + p, f = (R, p).
    #[inline(always)]
    fn after(&self, f: &Frame, t: &Vector3<f64>) -> Vector3<f64> {
        match *self {
            Shift::Along(k) => {
                let k = k as usize;
                f.rotation.column(k) * t[k] + f.origin
            }
            Shift::General => f.transform_point(t),
        }
    }
}

/// How FK composes one model: how each joint origin's, the flange's and the TCP's rotation
/// is applied (a signed permutation's columns, none, or a general rotation) and which joints
/// turn about z. The translations, general rotations and other axes are read from the model
/// itself, so [`Chain::kinematics`] takes the model this chain was read from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chain {
    origins: [Turn; NA],
    /// How each joint origin's translation is applied.
    shifts: [Shift; NA],
    /// Joint i turns about z (the two columns it mixes are turned in place).
    about_z: [bool; NA],
    flange: (Turn, Shift),
    tcp: (Turn, Shift),
    /// The joints' turns, shifts and axes are the iiwa's ([`IIWA`]): FK takes them as
    /// constants, so a turn's columns are picked in registers, not by an index read from
    /// memory.
    iiwa: bool,
}

/// How the KUKA iiwa's URDF turns and shifts at its seven joints (every joint about z):
/// the pattern [`Chain::new`] reads from [`RobotModel::kmr_iiwa14`] (test
/// `the_iiwa_pattern_is_the_kmr_iiwa14s`).
const IIWA: [(Turn, Shift); NA] = {
    const fn turn(s0: i8, s2: i8) -> Turn {
        Turn::Columns {
            index: [0, 2, 1],
            sign: [s0, 1, s2],
        }
    }
    [
        (Turn::Identity, Shift::Along(2)),
        (turn(-1, 1), Shift::Along(2)),
        (turn(-1, 1), Shift::Along(1)),
        (turn(1, -1), Shift::Along(2)),
        (turn(-1, 1), Shift::Along(1)),
        (turn(1, -1), Shift::Along(2)),
        (turn(-1, 1), Shift::Along(1)),
    ]
};

impl Chain {
    /// The chain of `model`.
    pub fn new(model: &RobotModel) -> Chain {
        let origins = core::array::from_fn(|i| Turn::of(&model.joints[i].origin.rotation));
        let shifts =
            core::array::from_fn(|i| Shift::of(&model.joints[i].origin.translation.vector));
        let about_z = core::array::from_fn(|i| super::is_z(&model.joints[i].axis));
        let iiwa = about_z == [true; NA] && (0..NA).all(|i| (origins[i], shifts[i]) == IIWA[i]);
        Chain {
            origins,
            shifts,
            about_z,
            flange: fixed_of(&model.flange),
            tcp: fixed_of(&model.tcp),
            iiwa,
        }
    }

    /// Frame i + 1 from frame i: T_{i+1} = T_i · origin_i · Rot(axis_i, q_i), given
    /// (sin q_i, cos q_i) as `sc` ([`crate::float::sincos`]: the same bits on the host and on
    /// the controller).
    #[inline(always)]
    pub(super) fn joint(&self, model: &RobotModel, i: usize, f: &Frame, sc: (f64, f64)) -> Frame {
        let how = (self.origins[i], self.shifts[i], self.about_z[i]);
        joint_as(how, model, i, f, sc)
    }

    /// [`Chain::joint`] of an iiwa chain ([`IIWA`]), joint `I`: the same bits, its turn and
    /// shift constants.
    #[inline(always)]
    pub(super) fn iiwa_joint<const I: usize>(
        model: &RobotModel,
        f: &Frame,
        sc: (f64, f64),
    ) -> Frame {
        let (turn, shift) = IIWA[I];
        joint_as((turn, shift, true), model, I, f, sc)
    }

    /// True if FK may take this chain's joints as the iiwa's ([`Chain::iiwa_joint`]).
    #[inline(always)]
    pub(super) fn is_iiwa(&self) -> bool {
        self.iiwa
    }

    /// The axis of joint i in the arm base frame, from frame i + 1 ([`super::joint_axis`]).
    #[inline(always)]
    pub(super) fn axis_of(&self, model: &RobotModel, i: usize, f: &Frame) -> Vector3<f64> {
        super::joint_axis(f, &model.joints[i].axis, self.about_z[i])
    }

    /// The flange frame from link 7's.
    #[inline(always)]
    pub(super) fn flange_frame(&self, model: &RobotModel, f: &Frame) -> Frame {
        fixed(&self.flange, &model.flange, f)
    }

    /// The TCP frame from the flange's.
    #[inline(always)]
    pub(super) fn tcp_frame(&self, model: &RobotModel, f: &Frame) -> Frame {
        fixed(&self.tcp, &model.tcp, f)
    }
}

/// Frame i + 1 from frame i as `how` (the origin's turn and shift, and whether the joint
/// turns about z) gives it, the joint's angle given as its sine and cosine: [`Chain::joint`].
#[inline(always)]
fn joint_as(
    (turn_of_origin, shift, about_z): (Turn, Shift, bool),
    model: &RobotModel,
    i: usize,
    f: &Frame,
    (s, c): (f64, f64),
) -> Frame {
    let joint = &model.joints[i];
    let origin = shift.after(f, &joint.origin.translation.vector);
    let rotation = match (&turn_of_origin, about_z) {
        // [σ0 r_i0, σ1 r_i1, σ2 r_i2] · Rot(z, q), the signs σ moved onto c and s (exact,
        // as σ = ±1): the third column stays.
        (Turn::Columns { index, sign }, true) => {
            let r = |j: usize| f.rotation.column(index[j] as usize);
            let (s0, s1) = (f64::from(sign[0]), f64::from(sign[1]));
            let (r0, r1) = (r(0), r(1));
            Matrix3::from_columns(&[
                r0 * (c * s0) + r1 * (s * s1),
                r1 * (c * s1) - r0 * (s * s0),
                r(2) * f64::from(sign[2]),
            ])
        }
        (turn, true) => {
            let [a0, a1, a2] = turn.after(&f.rotation, &joint.origin.rotation);
            Matrix3::from_columns(&[a0 * c + a1 * s, a1 * c - a0 * s, a2])
        }
        (turn, false) => {
            let a = turn.after(&f.rotation, &joint.origin.rotation);
            Matrix3::from_columns(&a) * rodrigues(&joint.axis, s, c)
        }
    };
    Frame { rotation, origin }
}

/// How FK applies the fixed transform `p`.
fn fixed_of(p: &Pose) -> (Turn, Shift) {
    (Turn::of(&p.rotation), Shift::of(&p.translation.vector))
}

/// f · p for a fixed transform p applied as `how` ([`fixed_of`]).
#[inline(always)]
fn fixed(how: &(Turn, Shift), p: &Pose, f: &Frame) -> Frame {
    let (turn, shift) = how;
    let origin = shift.after(f, &p.translation.vector);
    let rotation = match turn {
        Turn::Identity => f.rotation,
        turn => Matrix3::from_columns(&turn.after(&f.rotation, &p.rotation)),
    };
    Frame { rotation, origin }
}

/// Rot(a, θ) = c I + s [a]× + (1 − c) a aᵀ (Rodrigues), from s = sin θ, c = cos θ.
fn rodrigues(a: &Unit<Vector3<f64>>, s: f64, c: f64) -> Matrix3<f64> {
    let (x, y, z) = (a.x, a.y, a.z);
    let v = 1.0 - c;
    Matrix3::new(
        c + x * x * v,
        x * y * v - z * s,
        x * z * v + y * s,
        y * x * v + z * s,
        c + y * y * v,
        y * z * v - x * s,
        z * x * v - y * s,
        z * y * v + x * s,
        c + z * z * v,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    /// The iiwa's origins read as signed permutations, its flange and TCP as the identity;
    /// a turn 1e-9 rad off a permutation, or any other, is taken as it is.
    #[test]
    fn origins_are_read_as_permutations_only_when_they_are() {
        let model = RobotModel::kmr_iiwa14();
        let chain = Chain::new(&model);
        assert!(
            chain.origins[1..]
                .iter()
                .all(|t| matches!(t, Turn::Columns { .. }))
        );
        assert_eq!(chain.origins[0], Turn::Identity);
        assert_eq!(
            (chain.flange.0, chain.tcp.0),
            (Turn::Identity, Turn::Identity)
        );
        assert_eq!(chain.about_z, [true; NA]);
        let half = core::f64::consts::FRAC_PI_2;
        let quarter_about_x = UnitQuaternion::from_euler_angles(half, 0.0, 0.0);
        assert_eq!(
            Turn::of(&quarter_about_x),
            Turn::Columns {
                index: [0, 2, 1],
                sign: [1, 1, -1]
            }
        );
        let off = UnitQuaternion::from_euler_angles(half + 1e-9, 0.0, 0.0);
        assert_eq!(Turn::of(&off), Turn::General);
        assert_eq!(
            Turn::of(&UnitQuaternion::from_euler_angles(0.3, 0.0, 0.0)),
            Turn::General
        );
    }

    /// [`IIWA`] is the pattern read from the iiwa's model, and FK through it gives the bits of
    /// the general joint-by-joint chain at random configurations; a model off the pattern
    /// (one origin turned otherwise) takes the general chain.
    #[test]
    fn the_iiwa_pattern_is_the_kmr_iiwa14s() {
        let model = RobotModel::kmr_iiwa14();
        let chain = Chain::new(&model);
        assert!(chain.iiwa);
        let general = Chain {
            iiwa: false,
            ..chain
        };
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        for _ in 0..200 {
            let q = crate::JointVector::from_fn(|_, _| {
                seed = seed
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 6.0
            });
            let (tcp, j) = chain.tcp_and_jacobian(&model, &q);
            let (tcp_g, j_g) = general.tcp_and_jacobian(&model, &q);
            assert_eq!(
                (tcp.rotation, tcp.origin, j),
                (tcp_g.rotation, tcp_g.origin, j_g)
            );
            let (k, k_g) = (chain.kinematics(&model, &q), general.kinematics(&model, &q));
            assert_eq!(k.frames, k_g.frames);
        }
        let mut other = model.clone();
        other.joints[3].origin.rotation =
            UnitQuaternion::from_euler_angles(-core::f64::consts::FRAC_PI_2, 0.0, 0.0);
        assert!(!Chain::new(&other).iiwa);
    }

    /// The iiwa's translations (origins, flange, TCP) lie on one axis each; a translation off
    /// the axes is applied whole, and either way the origin is R t + p.
    #[test]
    fn translations_on_one_axis_are_read_as_such() {
        let model = RobotModel::kmr_iiwa14();
        let chain = Chain::new(&model);
        let along = |s: &Shift| matches!(s, Shift::Along(_));
        assert!(
            chain
                .shifts
                .iter()
                .chain([&chain.flange.1, &chain.tcp.1])
                .all(along)
        );
        assert_eq!(Shift::of(&Vector3::new(0.0, 0.2045, 0.0)), Shift::Along(1));
        assert_eq!(Shift::of(&Vector3::zeros()), Shift::Along(0));
        assert_eq!(Shift::of(&Vector3::new(1e-9, 0.0, 0.3)), Shift::General);
        let f = Frame {
            rotation: *UnitQuaternion::from_euler_angles(0.3, -1.1, 2.0)
                .to_rotation_matrix()
                .matrix(),
            origin: Vector3::new(0.1, -0.2, 0.7),
        };
        for t in [
            Vector3::new(0.0, 0.0, 0.2155),
            Vector3::new(0.3, -0.1, 0.02),
        ] {
            let shift = Shift::of(&t);
            assert_eq!(shift.after(&f, &t), f.rotation * t + f.origin, "{shift:?}");
        }
    }
}
