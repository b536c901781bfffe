//! Pick(part p, location ℓ) (Sec. 5.3.3): reach the part from q_a,H with a learned RDMP,
//! close the gripper, play the motion back.

use super::segment::{TaskLocation, arm_instance, gripper_events};
use super::symbolic::{ActionTemplate, Atom, Param, StateVar::*, Value};
use super::{
    Frame, Frames, Generator, Goal, GoalContext, Initial, Instance, MotionClass, PhysicalState,
    Sample,
};
use crate::JointVector;
use crate::kinematics::ArmKinematics;
use crate::robot::RobotModel;

/// Pick(p, ℓ): the arm takes part p at location ℓ.
pub struct Pick;

/// Frames of Pick and Place: TCP `e` relative to the part `p`; workspace swept in the
/// platform frame `b`, stored in the location frame ℓ.
pub(super) const ARM_FRAMES: Frames = Frames {
    robot: Frame::Tcp,
    affordance: Frame::Part,
    workspace: Frame::Location,
    origin: Frame::Base,
};

impl MotionClass for Pick {
    fn name(&self) -> &'static str {
        "Pick"
    }

    fn frames(&self) -> Frames {
        ARM_FRAMES
    }

    fn learns_workspace(&self) -> bool {
        true
    }

    fn action(&self) -> ActionTemplate {
        ActionTemplate::new(
            "Pick",
            &[Param::Part, Param::Location],
            &[
                Atom::new(At, &[0, 1], Value::True),
                Atom::new(RobAt, &[1], Value::True),
                Atom::new(Holding, &[], Value::Nothing),
            ],
            &[
                Atom::new(At, &[0, 1], Value::False),
                Atom::new(RobAt, &[1], Value::True),
                Atom::new(Holding, &[], Value::Param(0)),
            ],
        )
    }

    fn generators(&self) -> &'static [Generator] {
        &[
            Generator::ArmRdmp,
            Generator::Grip { close: true },
            Generator::ArmRdmpReversed,
        ]
    }

    fn segment(&self, program: &[Sample], out: &mut dyn FnMut(Instance)) {
        gripper_events(program, true, |k| {
            if let Some(i) = arm_instance(program, k, TaskLocation::From) {
                out(i)
            }
        });
    }

    fn shares_with(&self) -> Option<&'static str> {
        Some("Place")
    }

    /// Y = {q_a,H}.
    fn initial(&self, model: &RobotModel, _x: &PhysicalState) -> Initial {
        Initial::Arm(JointVector::from(model.home))
    }

    /// G = {T_B⁻¹ T_p T_e^p : T_e^p ∈ A_e^p}, with T_B the arm base in the world.
    fn goals(&self, x: &PhysicalState, cx: &GoalContext<'_>, out: &mut dyn FnMut(Goal)) {
        let arm_base = x.base * cx.model.mount;
        for g in cx.grasps {
            out(Goal::Tcp {
                pose: arm_base.inverse() * x.part * g,
                grasp: *g,
            });
        }
    }

    /// Gripper closed; the part follows the TCP from g back to F_a(q_a).
    fn transition(&self, model: &RobotModel, x: &PhysicalState, g: &Goal) -> PhysicalState {
        carry(model, x, g, 1.0)
    }
}

/// Φ_x of Pick and Place: platform and arm unchanged, the gripper set to `gripper`, and the
/// part where the goal's grasp T_e^p puts it against the TCP: picking, after the motion back
/// to F_a(q_a) (T_p ← T_B F_a(q_a) (T_e^p)⁻¹, the grasp held); placing, at the goal
/// (T_p ← T_B g (T_e^p)⁻¹, nothing held).
pub(super) fn carry(
    model: &RobotModel,
    x: &PhysicalState,
    g: &Goal,
    gripper: f64,
) -> PhysicalState {
    let Goal::Tcp { pose, grasp } = g else {
        return *x;
    };
    let arm_base = x.base * model.mount;
    let closed = gripper >= 0.5;
    let tcp = if closed {
        ArmKinematics::new(model, &x.arm).tcp
    } else {
        *pose
    };
    PhysicalState {
        gripper,
        part: arm_base * tcp * grasp.inverse(),
        grasp: closed.then_some(*grasp),
        ..*x
    }
}
