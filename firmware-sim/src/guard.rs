//! Admission of setpoints: sequence bookkeeping (lost and repeated) and the limits a setpoint
//! must keep to be followed (finite, inside the joint limits, no faster than the speed limits
//! from the previous setpoint).

use prf_ipc::messages::{SetpointMsg, flags};
use prf_shared::NA;
use prf_shared::limits::MotionLimits;
use prf_shared::robot::RobotModel;

/// Relative slack on speed checks (rounding of the cell's jerk-limited output).
const SPEED_SLACK: f64 = 1e-3;

/// The floor a platform goal must lie on: |x|, |y| ≤ this, m.
pub const FLOOR_HALF_EXTENT: f64 = 1000.0;

/// The largest platform goal yaw, rad (two turns either way).
pub const MAX_GOAL_YAW: f64 = 4.0 * core::f64::consts::PI;

/// Why a setpoint was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Refusal {
    NonFinite,
    /// Joint `joint` (0-based) at `value` rad is outside its limits.
    JointLimit {
        joint: usize,
        value: f64,
    },
    /// Joint `joint` would move `step` rad in one cycle, above its speed limit.
    Jump {
        joint: usize,
        step: f64,
    },
    /// Joint `joint` is commanded at `speed` rad/s, above its limit.
    Speed {
        joint: usize,
        speed: f64,
    },
    /// The platform goal [x, y, yaw] is off the floor.
    BaseGoal {
        goal: [f64; 3],
    },
}

impl core::fmt::Display for Refusal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Refusal::NonFinite => write!(f, "non-finite setpoint"),
            Refusal::JointLimit { joint, value } => {
                write!(f, "A{} at {value:.4} rad is outside its limits", joint + 1)
            }
            Refusal::Jump { joint, step } => {
                write!(f, "A{} jumps {step:.4} rad in one cycle", joint + 1)
            }
            Refusal::Speed { joint, speed } => {
                write!(f, "A{} commanded at {speed:.4} rad/s", joint + 1)
            }
            Refusal::BaseGoal { goal: [x, y, yaw] } => write!(
                f,
                "platform goal ({x:.3e} m, {y:.3e} m, {yaw:.3e} rad) is off the floor (|x|, |y| ≤ {FLOOR_HALF_EXTENT} m, |yaw| ≤ 4π)"
            ),
        }
    }
}

/// What to do with a setpoint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Admission {
    Follow,
    /// Not newer than the last one: ignore.
    Repeated,
    Refuse(Refusal),
}

/// Sequence counters and the last admitted setpoint of a session.
#[derive(Clone, Debug)]
pub struct Guard {
    pub last_seq: u64,
    last_q: Option<[f64; NA]>,
    /// Setpoints lost (saturating), repeated and refused in this session.
    pub lost: u32,
    pub repeated: u32,
    pub rejected: u32,
    /// The most cycles a sequence gap can stand for: the watchdog's silence. A live session
    /// cannot have lost more, so a larger gap earns no larger step.
    max_gap: u64,
}

impl Default for Guard {
    /// With the controller's default watchdog of 100 cycles.
    fn default() -> Self {
        Guard::new(100)
    }
}

impl Guard {
    /// A guard for a controller whose watchdog trips after `watchdog_cycles` silent cycles.
    pub fn new(watchdog_cycles: u32) -> Self {
        Guard {
            last_seq: 0,
            last_q: None,
            lost: 0,
            repeated: 0,
            rejected: 0,
            max_gap: u64::from(watchdog_cycles.max(1)),
        }
    }

    /// Judges `msg`; `reference` is the controller's current reference (where a new session
    /// starts from).
    pub fn admit(
        &mut self,
        msg: &SetpointMsg,
        reference: &[f64; NA],
        model: &RobotModel,
        limits: &MotionLimits,
        dt: f64,
    ) -> Admission {
        if msg.flags & flags::FIRST != 0 {
            *self = Guard::new(self.max_gap as u32);
        } else if msg.seq <= self.last_seq {
            self.repeated = self.repeated.saturating_add(1);
            return Admission::Repeated;
        }
        let gap = msg.seq.saturating_sub(self.last_seq).max(1);
        self.lost = self
            .lost
            .saturating_add(u32::try_from(gap - 1).unwrap_or(u32::MAX));
        self.last_seq = msg.seq;
        match check(
            msg,
            self.last_q.as_ref().unwrap_or(reference),
            gap.min(self.max_gap),
            model,
            limits,
            dt,
        ) {
            Ok(()) => {
                self.last_q = Some(msg.q);
                Admission::Follow
            }
            Err(r) => {
                self.rejected = self.rejected.saturating_add(1);
                Admission::Refuse(r)
            }
        }
    }
}

fn check(
    msg: &SetpointMsg,
    previous: &[f64; NA],
    gap: u64,
    model: &RobotModel,
    limits: &MotionLimits,
    dt: f64,
) -> Result<(), Refusal> {
    let finite = msg
        .q
        .iter()
        .chain(&msg.qd)
        .chain(&msg.base_goal)
        .all(|v| v.is_finite());
    if !finite {
        return Err(Refusal::NonFinite);
    }
    if let Some((joint, value)) = model.limit_violation(&msg.q) {
        return Err(Refusal::JointLimit { joint, value });
    }
    let [x, y, yaw] = msg.base_goal;
    if x.abs() > FLOOR_HALF_EXTENT || y.abs() > FLOOR_HALF_EXTENT || yaw.abs() > MAX_GOAL_YAW {
        return Err(Refusal::BaseGoal {
            goal: msg.base_goal,
        });
    }
    for j in 0..NA {
        let v_max = limits.arm_speed[j] * (1.0 + SPEED_SLACK);
        let step = (msg.q[j] - previous[j]).abs();
        if step > v_max * dt * gap as f64 + 1e-9 {
            return Err(Refusal::Jump { joint: j, step });
        }
        if msg.qd[j].abs() > v_max {
            return Err(Refusal::Speed {
                joint: j,
                speed: msg.qd[j],
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn msg(seq: u64, q: [f64; NA]) -> SetpointMsg {
        SetpointMsg {
            seq,
            q,
            flags: if seq == 1 { flags::FIRST } else { 0 },
            ..Default::default()
        }
    }

    #[test]
    fn counts_lost_repeated_and_refuses_jumps_and_limits() {
        let model = RobotModel::kmr_iiwa14();
        let limits = MotionLimits::kmr_iiwa(&model);
        let home = model.home;
        let mut g = Guard::default();
        assert_eq!(
            g.admit(&msg(1, home), &home, &model, &limits, 1e-3),
            Admission::Follow
        );
        assert_eq!(
            g.admit(&msg(2, home), &home, &model, &limits, 1e-3),
            Admission::Follow
        );
        assert_eq!(
            g.admit(&msg(2, home), &home, &model, &limits, 1e-3),
            Admission::Repeated
        );
        assert_eq!(
            g.admit(&msg(5, home), &home, &model, &limits, 1e-3),
            Admission::Follow
        );
        assert_eq!((g.lost, g.repeated), (2, 1));
        // A1 at 85°/s for 1 ms moves 1.48 mrad: 1.4 passes, 1.6 is a jump.
        let mut q = home;
        q[0] += 1.4e-3;
        assert_eq!(
            g.admit(&msg(6, q), &home, &model, &limits, 1e-3),
            Admission::Follow
        );
        q[0] += 1.6e-3;
        assert!(matches!(
            g.admit(&msg(7, q), &home, &model, &limits, 1e-3),
            Admission::Refuse(Refusal::Jump { joint: 0, .. })
        ));
        let mut far = home;
        far[3] = 2.2; // A4 limit is 120° = 2.094 rad
        let mut g = Guard::default();
        assert!(matches!(
            g.admit(&msg(1, far), &far, &model, &limits, 1e-3),
            Admission::Refuse(Refusal::JointLimit { joint: 3, .. })
        ));
        let mut nan = home;
        nan[2] = f64::NAN;
        assert_eq!(
            g.admit(&msg(2, nan), &home, &model, &limits, 1e-3),
            Admission::Refuse(Refusal::NonFinite)
        );
    }

    /// A hostile sequence number far ahead: the lost count saturates instead of wrapping (or
    /// overflowing), and the step allowed is that of the watchdog's silence, not of the gap.
    #[test]
    fn a_huge_sequence_gap_saturates_and_earns_no_larger_step() {
        let model = RobotModel::kmr_iiwa14();
        let limits = MotionLimits::kmr_iiwa(&model);
        let home = model.home;
        let mut g = Guard::new(100);
        assert_eq!(
            g.admit(&msg(1, home), &home, &model, &limits, 1e-3),
            Admission::Follow
        );
        // 100 cycles at A1's 85°/s allow 0.148 rad; 0.2 rad is a jump, whatever the gap.
        let mut q = home;
        q[0] += 0.2;
        assert!(matches!(
            g.admit(&msg(u64::MAX, q), &home, &model, &limits, 1e-3),
            Admission::Refuse(Refusal::Jump { joint: 0, .. })
        ));
        assert_eq!(g.lost, u32::MAX);
        q[0] = home[0] + 0.1;
        let mut g = Guard::new(100);
        g.admit(&msg(1, home), &home, &model, &limits, 1e-3);
        assert_eq!(
            g.admit(&msg(1 << 40, q), &home, &model, &limits, 1e-3),
            Admission::Follow
        );
        // A platform goal the drive cannot plan to (Ruckig fails far off the floor).
        let mut far = msg((1 << 40) + 1, q);
        far.base_goal = [1e6, 0.0, 0.0];
        assert!(matches!(
            g.admit(&far, &home, &model, &limits, 1e-3),
            Admission::Refuse(Refusal::BaseGoal { .. })
        ));
    }
}
