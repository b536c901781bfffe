//! Place(part p, location ℓ) (Sec. 5.3.3): Pick's motion around a gripper open.

use super::pick::{ARM_FRAMES, carry};
use super::segment::{TaskLocation, arm_instance, gripper_events};
use super::symbolic::{ActionTemplate, Atom, Param, StateVar::*, Value};
use super::{
    Frames, Generator, Goal, GoalContext, Initial, Instance, MotionClass, PhysicalState, Sample,
};
use crate::JointVector;
use crate::kinematics::ArmKinematics;
use crate::robot::RobotModel;

/// Place(p, ℓ): the arm puts part p down at location ℓ.
pub struct Place;

impl MotionClass for Place {
    fn name(&self) -> &'static str {
        "Place"
    }

    fn frames(&self) -> Frames {
        ARM_FRAMES
    }

    fn learns_workspace(&self) -> bool {
        true
    }

    fn action(&self) -> ActionTemplate {
        ActionTemplate::new(
            "Place",
            &[Param::Part, Param::Location],
            &[
                Atom::new(At, &[0, 1], Value::False),
                Atom::new(RobAt, &[1], Value::True),
                Atom::new(Holding, &[], Value::Param(0)),
            ],
            &[
                Atom::new(At, &[0, 1], Value::True),
                Atom::new(RobAt, &[1], Value::True),
                Atom::new(Holding, &[], Value::Nothing),
            ],
        )
    }

    fn generators(&self) -> &'static [Generator] {
        &[
            Generator::ArmRdmp,
            Generator::Grip { close: false },
            Generator::ArmRdmpReversed,
        ]
    }

    fn segment(&self, program: &[Sample], out: &mut dyn FnMut(Instance)) {
        gripper_events(program, false, |k| {
            if let Some(i) = arm_instance(program, k, TaskLocation::To) {
                out(i)
            }
        });
    }

    fn shares_with(&self) -> Option<&'static str> {
        Some("Pick")
    }

    /// Y = {q_a,H}.
    fn initial(&self, model: &RobotModel, _x: &PhysicalState) -> Initial {
        Initial::Arm(JointVector::from(model.home))
    }

    /// G = {T_B⁻¹ T_p,g T_e^p}: the TCP pose that puts the held part at its goal, with T_e^p
    /// the grasp held (without one, the TCP's pose on the part, T_p⁻¹ T_B F_a(q_a)).
    fn goals(&self, x: &PhysicalState, cx: &GoalContext<'_>, out: &mut dyn FnMut(Goal)) {
        let arm_base = x.base * cx.model.mount;
        let grasp = x.grasp.unwrap_or_else(|| {
            x.part.inverse() * arm_base * ArmKinematics::new(cx.model, &x.arm).tcp
        });
        out(Goal::Tcp {
            pose: arm_base.inverse() * cx.part_goal * grasp,
            grasp,
        });
    }

    /// Gripper open; the part stays where the TCP put it.
    fn transition(&self, model: &RobotModel, x: &PhysicalState, g: &Goal) -> PhysicalState {
        carry(model, x, g, 0.0)
    }
}
