//! Arm-motion evaluations kept across the tasks planned on one runtime.
//!
//! An evaluation ([`crate::skill_plan::evaluate_arm_motion`]) is a pure function of the
//! side's workspace (its location type), the skill, the stance's arm base (location frame),
//! the goal (arm base frame) and the bound; the RDMP always starts at q_a,H. Tasks that
//! share a side share these: the 18 tasks of the example cell integrate 9 candidates instead
//! of 36 (Part1's nine tasks share three pick sides and six place sides, since a place goal is
//! made from the grasp held, whichever location the part came from; Part2's grasps and poses
//! are Part1's, so its tasks recall all of theirs). [`Recall`] keeps each evaluation with the
//! bound it was made under and answers a later candidate with the same inputs exactly as
//! integrating it again would:
//! - a rated risk r (made under a bound above r): under a bound above r, the same rating
//!   (the running risk never reached either bound, so the same lookups ran); under a bound at
//!   or below r, pruned with the same steps (pruning does not change the timing);
//! - pruned under bound b (the risk reached b): pruned again under any bound ≤ b; above b
//!   nothing is known, so it is integrated;
//! - failed, missed or too fast: the same, whatever the bound (none depends on the risk).
//!
//! Under a step budget a recalled evaluation is charged the steps it took when integrated
//! ([`crate::skill_plan::PlanStats::charged`]), and one that would overrun what is left is
//! integrated again (and capped as it would be): the budget runs out where it would without
//! the recall.
//!
//! The memory is the caller's ([`Recall::new`] takes the slots): none on the firmware, which
//! plans one task; [`HOST_SLOTS`] in the host tools. A candidate is found by a linear scan,
//! a few µs against the milliseconds of one integration.

use crate::skill_plan::Evaluation;
use prf_shared::se3::{Pose, pose_bits};

/// The slots the host tools give a [`Recall`]: more than the 18 tasks of the example cell
/// integrate with their parts moved 2 cm and 8° (5,160 integrations); 1.7 MB at 208 B each.
pub const HOST_SLOTS: usize = 8192;

/// One kept evaluation: the candidate, the bound it was made under, what it came to.
pub type Kept = (Candidate, f64, Evaluation);

/// The inputs that decide an evaluation besides its bound, bit for bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Candidate {
    /// The side's location type (its workspace).
    pub location_type: usize,
    /// The skill (blob index).
    pub skill: u16,
    /// The stance's arm base, location frame.
    pub arm_base: [u64; 7],
    /// The goal, arm base frame.
    pub goal: [u64; 7],
}

impl Candidate {
    /// The candidate of `skill` at a side of `location_type`, from `arm_base` to `goal`.
    pub fn new(location_type: usize, skill: u16, arm_base: &Pose, goal: &Pose) -> Self {
        Candidate {
            location_type,
            skill,
            arm_base: pose_bits(arm_base),
            goal: pose_bits(goal),
        }
    }
}

/// Evaluations kept in the caller's slots, each with the bound it was made under (see the
/// module). Once the slots are full, later candidates are integrated every time.
#[derive(Debug)]
pub struct Recall<'s> {
    slots: &'s mut [Option<Kept>],
    len: usize,
}

impl<'s> Recall<'s> {
    /// An empty recall in `slots` (whatever they held is forgotten).
    pub fn new(slots: &'s mut [Option<Kept>]) -> Self {
        slots.fill(None);
        Recall { slots, len: 0 }
    }

    /// The evaluations kept.
    fn kept(&self) -> impl Iterator<Item = &Kept> {
        self.slots[..self.len].iter().flatten()
    }

    /// What evaluating `candidate` under `bound` would give, when the kept evaluation decides
    /// it; `None` when it must be integrated.
    pub fn get(&self, candidate: &Candidate, bound: f64) -> Option<Evaluation> {
        let (_, made_under, e) = self.kept().find(|(c, ..)| c == candidate)?;
        match *e {
            // Not integrated at all (as evaluating does below a bound of 0).
            _ if !(bound > 0.0) => Some(Evaluation::Pruned { steps: 0 }),
            Evaluation::Risk { risk, steps, .. } if !(risk < bound) => {
                Some(Evaluation::Pruned { steps })
            }
            Evaluation::Pruned { .. } if bound > *made_under => None,
            Evaluation::Capped { .. } => None,
            e => Some(e),
        }
    }

    /// Keeps `e`, the evaluation of `candidate` under `bound`: a pruning only when its bound is
    /// higher than the one kept (it then decides more), a capped one never.
    pub fn keep(&mut self, candidate: Candidate, bound: f64, e: &Evaluation) {
        if matches!(e, Evaluation::Capped { .. }) {
            return;
        }
        let mut kept = self.slots[..self.len].iter_mut().flatten();
        match kept.find(|(c, ..)| *c == candidate) {
            Some(kept) => {
                if matches!(kept.2, Evaluation::Pruned { .. }) && !(bound <= kept.1) {
                    *kept = (candidate, bound, *e);
                }
            }
            None => {
                // Full: the candidate is integrated again when it comes back.
                if let Some(slot) = self.slots.get_mut(self.len) {
                    *slot = Some((candidate, bound, *e));
                    self.len += 1;
                }
            }
        }
    }

    /// Evaluations kept.
    pub fn len(&self) -> usize {
        self.len
    }

    /// No evaluation kept.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use prf_shared::limits::LimitRatios;
    use prf_shared::se3::pose_from_xyz_rpy;
    use prf_shared::timing::ArmTiming;

    fn candidate(skill: u16) -> Candidate {
        let base = pose_from_xyz_rpy([0.5, -0.2, 0.3], [0.0, 0.0, 1.0]);
        Candidate::new(
            2,
            skill,
            &base,
            &pose_from_xyz_rpy([0.6, 0.1, 0.4], [3.1, 0.0, 0.2]),
        )
    }

    fn rated(risk: f64) -> Evaluation {
        let timing = ArmTiming {
            scale: 1.0,
            steps: 3000,
            ratios: LimitRatios::default(),
        };
        Evaluation::Risk {
            risk,
            timing,
            steps: 3000,
        }
    }

    /// Each rule of the module: what a kept evaluation answers under another bound.
    #[test]
    fn kept_evaluations_answer_as_integrating_again_would() {
        let mut slots = [None; 8];
        let mut recall = Recall::new(&mut slots);
        let (a, b, c) = (candidate(1), candidate(2), candidate(3));
        recall.keep(a, f64::INFINITY, &rated(0.01));
        recall.keep(b, 0.02, &Evaluation::Pruned { steps: 700 });
        recall.keep(c, 0.02, &Evaluation::Capped { steps: 5 });
        assert_eq!(recall.get(&a, 0.011), Some(rated(0.01)));
        assert_eq!(
            recall.get(&a, 0.01),
            Some(Evaluation::Pruned { steps: 3000 })
        );
        assert_eq!(recall.get(&a, 0.0), Some(Evaluation::Pruned { steps: 0 }));
        assert_eq!(
            recall.get(&b, 0.02),
            Some(Evaluation::Pruned { steps: 700 })
        );
        assert_eq!(recall.get(&b, 0.03), None);
        assert_eq!(
            recall.get(&c, 0.02),
            None,
            "a capped evaluation is not kept"
        );
        // Another skill, or the goal one bit away, is another candidate.
        let mut moved = a;
        moved.goal[0] ^= 1;
        assert_eq!(recall.get(&moved, 1.0), None);
        // A pruning under a higher bound replaces the lower one; the rating replaces both.
        recall.keep(b, 0.03, &Evaluation::Pruned { steps: 900 });
        assert_eq!(
            recall.get(&b, 0.03),
            Some(Evaluation::Pruned { steps: 900 })
        );
        recall.keep(b, 0.05, &rated(0.04));
        assert_eq!(recall.get(&b, 0.06), Some(rated(0.04)));
        recall.keep(b, 0.01, &Evaluation::Pruned { steps: 1 });
        assert_eq!(recall.get(&b, 0.06), Some(rated(0.04)), "a rating is kept");
        assert_eq!(recall.len(), 2);
        let missed = Evaluation::Missed {
            position: 0.1,
            angle: 0.0,
            steps: 10,
        };
        recall.keep(c, 0.02, &missed);
        assert_eq!(recall.get(&c, 5.0), Some(missed));
        // Full: nothing more is kept, and what is kept still answers.
        for k in 10..20 {
            recall.keep(candidate(k), 1.0, &rated(0.0));
        }
        assert_eq!(recall.len(), 8);
        assert_eq!(recall.get(&candidate(14), 1.0), Some(rated(0.0)));
        assert_eq!(recall.get(&candidate(15), 1.0), None);
        assert_eq!(recall.get(&a, 0.011), Some(rated(0.01)));
    }
}
