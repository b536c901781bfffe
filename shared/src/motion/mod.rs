//! Motion classes (Sec. 5.1): the expert's templates that cut programs into behaviours and
//! generate new ones, m = (f_r, f_a, f_w, f_o, segment, α, π, Y, G, Φ_x).
//!
//! Each class is one module implementing [`MotionClass`]; [`CLASSES`] lists them. Learning
//! (offline), the blob compiler and the runtime all iterate over that list, so adding a class
//! means adding one module and one entry, not editing matches elsewhere.
//!
//! - [`pick`]: arm motion into a gripper close and its reversal (Sec. 5.3, Pick);
//! - [`place`]: the same around a gripper open (Place);
//! - [`base_move`]: each period of platform motion (Move).

pub mod base_move;
pub mod pick;
pub mod place;
pub mod segment;
pub mod symbolic;

pub use segment::{ArmSegment, Instance, TaskLocation};
pub use symbolic::{ActionTemplate, Atom, Param, StateVar, Value};

use crate::JointVector;
use crate::kinematics::ArmKinematics;
use crate::robot::RobotModel;
use crate::se3::Pose;

/// One row of a robot program: time, platform [x, y, yaw], arm joints, gripper (0 open,
/// 1 closed). The dataset's trajectory rows and the runtime's exported programs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Time, s.
    pub t: f64,
    /// Platform [x, y, yaw] in the world.
    pub base: [f64; 3],
    /// Arm joints, rad.
    pub arm: [f64; crate::NA],
    /// Gripper, 0 open … 1 closed.
    pub gripper: f64,
}

/// The reference frames a motion class names (Sec. 5.1: f_r, f_a, f_w, f_o).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frame {
    /// The world origin `o`.
    World,
    /// The platform base `b`.
    Base,
    /// The end effector (TCP) `e`.
    Tcp,
    /// The part `p` (at the instance: its pose before a pick, its goal pose after a place).
    Part,
    /// The location ℓ the instance happens at.
    Location,
}

/// (f_r, f_a, f_w, f_o): the affordance learned is T_{f_r}^{f_a} = T_{f_a}⁻¹ T_{f_r}; the
/// workspace swept in frame f_o is stored in frame f_w.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frames {
    /// f_r, the robot frame whose pose is learned.
    pub robot: Frame,
    /// f_a, the frame it is learned relative to.
    pub affordance: Frame,
    /// f_w, the frame the workspace is stored in.
    pub workspace: Frame,
    /// f_o, the frame the workspace is swept in.
    pub origin: Frame,
}

/// The motion generators a class chains (Sec. 5.3.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Generator {
    /// π_ArmRDMP(y0, g): a learned RDMP from q_a,H to a TCP goal.
    ArmRdmp,
    /// ¬π_ArmRDMP: the same motion played backwards.
    ArmRdmpReversed,
    /// π_Grip(y0, g): command the gripper closed (`true`) or open and wait for it.
    Grip {
        /// Close (else open).
        close: bool,
    },
    /// π_BaseMove(y0, g): the platform drives itself to a goal stance.
    BaseMove,
}

impl Generator {
    /// True for generators with learnable parameters (trained from the segment's arm motion).
    pub fn learnable(&self) -> bool {
        matches!(self, Generator::ArmRdmp | Generator::ArmRdmpReversed)
    }
}

/// The physical state x = [q, T_p] (Sec. 5.3.3): platform pose, arm, gripper, part pose, and
/// the grasp the part is held with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhysicalState {
    /// T_b, the platform in the world.
    pub base: Pose,
    /// Arm joints q_a.
    pub arm: JointVector,
    /// 0 open, 1 closed.
    pub gripper: f64,
    /// T_p, the part in the world.
    pub part: Pose,
    /// T_e^p, the grasp the part is held with (`None` while nothing is held). Carried so that
    /// the goals after a pick are the grasp's bits, not T_p's rounding through the pick:
    /// Place's goal at a stance is then the same whichever location the part came from.
    pub grasp: Option<Pose>,
}

impl PhysicalState {
    /// World pose of the TCP, T_b · mount · F_a(q_a).
    pub fn tcp(&self, model: &RobotModel) -> Pose {
        self.base * model.mount * ArmKinematics::new(model, &self.arm).tcp
    }
}

/// A goal g of a motion class.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Goal {
    /// TCP goal in the arm base frame (Pick, Place).
    Tcp {
        /// The TCP pose, arm base frame.
        pose: Pose,
        /// T_e^p, the grasp of the part the TCP reaches it with.
        grasp: Pose,
    },
    /// Platform goal in the world (Move).
    Base(Pose),
}

/// What the admissible goal sets G (Sec. 5.3.3, line 7 of each class) draw on: the task's
/// poses and the learned affordances.
pub struct GoalContext<'a> {
    /// The robot.
    pub model: &'a RobotModel,
    /// T_p,g: where the task wants the part.
    pub part_goal: Pose,
    /// T_ℓ of the location the action happens at (Move: the destination).
    pub location: Pose,
    /// Stances T_b^ℓ of that location's type.
    pub stances: &'a [Pose],
    /// Grasps T_e^p of the part's type.
    pub grasps: &'a [Pose],
}

/// A motion class (Sec. 5.1). Implementations are stateless unit structs.
pub trait MotionClass: Sync {
    /// Name of the class, also the head of its action template.
    fn name(&self) -> &'static str;
    /// (f_r, f_a, f_w, f_o).
    fn frames(&self) -> Frames;
    /// Whether Learn builds a workspace from this class's instances (Move's platform motion
    /// is neglected: the platform navigates with its own scanners, Sec. 6.2).
    fn learns_workspace(&self) -> bool;
    /// α = (head, pre, eff).
    fn action(&self) -> ActionTemplate;
    /// π: the generator sequence, parameterized by one (y0, g).
    fn generators(&self) -> &'static [Generator];
    /// segment(d): every instance of the class in a program.
    fn segment(&self, program: &[Sample], out: &mut dyn FnMut(Instance));
    /// share(): the class whose skills this class's skills also serve (Pick ↔ Place).
    fn shares_with(&self) -> Option<&'static str>;
    /// Y(x, T): the admissible initial condition from state `x`.
    fn initial(&self, model: &RobotModel, x: &PhysicalState) -> Initial;
    /// G(x, T): the admissible goals, each passed to `out`.
    fn goals(&self, x: &PhysicalState, cx: &GoalContext<'_>, out: &mut dyn FnMut(Goal));
    /// Φ_x(x, g): the state after the class ran with goal `g`.
    fn transition(&self, model: &RobotModel, x: &PhysicalState, g: &Goal) -> PhysicalState;
}

/// An initial condition y0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Initial {
    /// Arm configuration (Pick, Place: always q_a,H).
    Arm(JointVector),
    /// Platform pose (Move).
    Base(Pose),
}

/// The motion classes of part transportation, M = {Pick, Place, Move}.
pub static CLASSES: [&dyn MotionClass; 3] = [&pick::Pick, &place::Place, &base_move::Move];

/// The class called `name`.
pub fn class(name: &str) -> Option<&'static dyn MotionClass> {
    CLASSES.iter().copied().find(|c| c.name() == name)
}
