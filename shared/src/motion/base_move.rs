//! Move(location ℓ0, location ℓ1) (Sec. 5.3.3): the platform drives itself to a stance.

use super::segment::{base_periods, next_action_location};
use super::symbolic::{ActionTemplate, Atom, Param, StateVar::*, Value};
use super::{
    Frame, Frames, Generator, Goal, GoalContext, Initial, Instance, MotionClass, PhysicalState,
    Sample,
};
use crate::robot::RobotModel;

/// Move(ℓ1, ℓ2): the platform drives from one location to another.
pub struct Move;

impl MotionClass for Move {
    fn name(&self) -> &'static str {
        "Move"
    }

    /// Platform `b` relative to the destination ℓ1; origin and workspace at the world `o`.
    fn frames(&self) -> Frames {
        Frames {
            robot: Frame::Base,
            affordance: Frame::Location,
            workspace: Frame::World,
            origin: Frame::World,
        }
    }

    fn learns_workspace(&self) -> bool {
        false
    }

    fn action(&self) -> ActionTemplate {
        ActionTemplate::new(
            "Move",
            &[Param::Location, Param::Location],
            &[
                Atom::new(RobAt, &[0], Value::True),
                Atom::new(RobAt, &[1], Value::False),
            ],
            &[
                Atom::new(RobAt, &[0], Value::False),
                Atom::new(RobAt, &[1], Value::True),
            ],
        )
    }

    fn generators(&self) -> &'static [Generator] {
        &[Generator::BaseMove]
    }

    /// Every period of platform motion; it arrives where the gripper acts next.
    fn segment(&self, program: &[Sample], out: &mut dyn FnMut(Instance)) {
        base_periods(program, |start, end| {
            out(Instance {
                range: start..end + 1,
                at: end,
                arm: None,
                location: next_action_location(program, end),
            })
        });
    }

    fn shares_with(&self) -> Option<&'static str> {
        None
    }

    /// Y = {T_b}.
    fn initial(&self, _model: &RobotModel, x: &PhysicalState) -> Initial {
        Initial::Base(x.base)
    }

    /// G = {T_ℓ1 T_b^ℓ1 : T_b^ℓ1 ∈ A_b^ℓ1}.
    fn goals(&self, _x: &PhysicalState, cx: &GoalContext<'_>, out: &mut dyn FnMut(Goal)) {
        for s in cx.stances {
            out(Goal::Base(cx.location * s));
        }
    }

    /// The platform at g; a held part (gripper closed) rides along.
    fn transition(&self, _model: &RobotModel, x: &PhysicalState, g: &Goal) -> PhysicalState {
        let Goal::Base(goal) = g else {
            return *x;
        };
        let part = if x.gripper >= 0.5 {
            goal * x.base.inverse() * x.part
        } else {
            x.part
        };
        PhysicalState {
            base: *goal,
            part,
            ..*x
        }
    }
}
