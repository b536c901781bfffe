//! Cutting a program into instances of motion classes (the `segment` of Sec. 5.1): the
//! shared helpers behind each class's `segment`.

use super::Sample;
use core::ops::Range;

/// Motion below this (rad per joint, m or rad per platform axis) between samples is standing
/// still; robot logs repeat a held setpoint exactly, so a tight threshold is right.
pub const STILL: f64 = 1e-7;

/// Which of the task's locations an instance happens at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TaskLocation {
    /// ℓ1, where the part starts.
    From,
    /// ℓ2, where the part goes.
    To,
}

/// The arm motion of a Pick or Place: `forward` runs from q_a,H to the gripper action, the
/// reversal follows it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ArmSegment {
    /// Samples of the forward motion (first: the arm still at its start; last: at rest
    /// before the gripper acts).
    pub forward: Range<usize>,
}

/// One instance of a motion class in a program.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Instance {
    /// All samples of the instance (for a Pick: forward, grip, reversal).
    pub range: Range<usize>,
    /// The sample at which the affordance frames are read (gripper action, Move's arrival).
    pub at: usize,
    /// The learnable arm motion, if the class has one.
    pub arm: Option<ArmSegment>,
    /// The location the instance happens at, if any (a Move home has none).
    pub location: Option<TaskLocation>,
}

fn arm_moves(p: &[Sample], i: usize) -> bool {
    p[i].arm
        .iter()
        .zip(&p[i + 1].arm)
        .any(|(a, b)| f64::abs(b - a) > STILL)
}

fn base_moves(p: &[Sample], i: usize) -> bool {
    p[i].base
        .iter()
        .zip(&p[i + 1].base)
        .any(|(a, b)| f64::abs(b - a) > STILL)
}

/// Indices k where the gripper crosses 0.5 between samples k−1 and k, closing (`close`) or
/// opening.
pub fn gripper_events(p: &[Sample], close: bool, mut out: impl FnMut(usize)) {
    for k in 1..p.len() {
        let (a, b) = (p[k - 1].gripper >= 0.5, p[k].gripper >= 0.5);
        if a != b && b == close {
            out(k);
        }
    }
}

/// The Pick/Place instance around the gripper event at sample `k`: within the period of
/// standing platform that contains `k`, the arm motion before the event and its reversal
/// after it. `None` if the arm does not move on both sides.
pub fn arm_instance(p: &[Sample], k: usize, location: TaskLocation) -> Option<Instance> {
    let mut lo = k;
    while lo > 0 && !base_moves(p, lo - 1) {
        lo -= 1;
    }
    let mut hi = k;
    while hi + 1 < p.len() && !base_moves(p, hi) {
        hi += 1;
    }
    // Forward motion: from the last still sample before the arm moves to the first still
    // sample after it stops, before the event.
    let start = (lo..k).find(|&i| arm_moves(p, i))?;
    let end = (start..k).rev().find(|&i| arm_moves(p, i))? + 1;
    // Reversal: the arm motion after the event.
    let back_start = (k..hi).find(|&i| arm_moves(p, i))?;
    let back_end = (back_start..hi).rev().find(|&i| arm_moves(p, i))? + 1;
    Some(Instance {
        range: start..back_end + 1,
        at: k,
        arm: Some(ArmSegment {
            forward: start..end + 1,
        }),
        location: Some(location),
    })
}

/// Every maximal period of platform motion, as (first sample, last sample) inclusive: the
/// platform is still at the first and at the last.
pub fn base_periods(p: &[Sample], mut out: impl FnMut(usize, usize)) {
    let mut i = 0;
    while i + 1 < p.len() {
        if base_moves(p, i) {
            let start = i;
            while i + 1 < p.len() && base_moves(p, i) {
                i += 1;
            }
            out(start, i);
        } else {
            i += 1;
        }
    }
}

/// The location of the next gripper action after sample `k`: a close happens at ℓ1, an
/// open at ℓ2; `None` if the gripper does not act again.
pub fn next_action_location(p: &[Sample], k: usize) -> Option<TaskLocation> {
    let g = p.get(k)?.gripper >= 0.5;
    p[k..].iter().find(|s| (s.gripper >= 0.5) != g).map(|s| {
        if s.gripper >= 0.5 {
            TaskLocation::From
        } else {
            TaskLocation::To
        }
    })
}
