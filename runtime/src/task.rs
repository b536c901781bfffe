//! A part-transportation task T = (T_p,0, T_p,g, T_ℓ1, T_ℓ2) and its symbolic feasibility
//! (Sec. 6.1): the affordances, skills and workspaces it needs must exist in the blob.

use crate::load::{LoadError, Runtime};
use prf_shared::se3::Pose;

/// An object of a task: instance id, type name, pose in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placed<'t> {
    /// Instance id, e.g. CNC1.
    pub id: &'t str,
    /// Its type, e.g. CNC.
    pub kind: &'t str,
    /// Its pose in the world.
    pub pose: Pose,
}

/// Move part `part` (at `part.pose` = T_p,0, on `from`) to `to`, so that it ends at `goal`
/// (T_p,g). The platform starts at `home` with the arm at q_a,H and the gripper open, and
/// returns there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Task<'t> {
    /// The part, at its start pose.
    pub part: Placed<'t>,
    /// The location it is at, ℓ1.
    pub from: Placed<'t>,
    /// The location it goes to, ℓ2.
    pub to: Placed<'t>,
    /// The part's goal pose T_p,g (world).
    pub goal: Pose,
    /// The platform's home pose (world), ℓ0.
    pub home: Pose,
}

/// Something the blob lacks for a task (Sec. 6.1's symbolic feasibility conditions).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Missing<'t> {
    /// No demonstration used a location of this type.
    LocationType(&'t str),
    /// No demonstration moved a part of this type.
    PartType(&'t str),
    /// A^b_ℓ is empty for this location type.
    Stances(&'t str),
    /// A^p_e is empty for this part type.
    Grasps(&'t str),
    /// Ω+_ℓ is empty for this location type.
    Workspace(&'t str),
    /// The blob has no motion class of this name.
    Class(&'static str),
    /// K_m is empty for this class.
    Skills(&'static str),
}

impl core::fmt::Display for Missing<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Missing::LocationType(t) => write!(f, "location type {t} (never demonstrated)"),
            Missing::PartType(t) => write!(f, "part type {t} (never demonstrated)"),
            Missing::Stances(t) => write!(f, "stances at {t}"),
            Missing::Grasps(t) => write!(f, "grasps of {t}"),
            Missing::Workspace(t) => write!(f, "workspace of {t}"),
            Missing::Class(c) => write!(f, "motion class {c}"),
            Missing::Skills(c) => write!(f, "{c} skills"),
        }
    }
}

impl core::error::Error for Missing<'_> {}

/// Everything a task lacks, in the order the checks run.
pub type MissingList<'t> = heapless::Vec<Missing<'t>, 8>;

/// A task resolved against the blob: type indices and the classes its plan uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolved {
    /// Blob part type of the part.
    pub part_type: usize,
    /// Blob location type of ℓ1.
    pub from_type: usize,
    /// Blob location type of ℓ2.
    pub to_type: usize,
}

/// Why a task is malformed (before any planning).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TaskError {
    /// A pose has a non-finite component: `what` names it.
    NonFinite {
        /// Which pose.
        what: &'static str,
    },
    /// ℓ1 and ℓ2 are the same location instance.
    SameLocation,
}

impl core::fmt::Display for TaskError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            TaskError::NonFinite { what } => write!(f, "the {what} pose is not finite"),
            TaskError::SameLocation => write!(f, "the task starts and ends at the same location"),
        }
    }
}

impl core::error::Error for TaskError {}

fn finite(p: &Pose) -> bool {
    p.translation.vector.iter().all(|v| v.is_finite())
        && p.rotation.coords.iter().all(|v| v.is_finite())
}

impl<'t> Task<'t> {
    /// Checks the task's own data.
    pub fn validate(&self) -> Result<(), TaskError> {
        for (p, what) in [
            (&self.part.pose, "part"),
            (&self.from.pose, "from-location"),
            (&self.to.pose, "to-location"),
            (&self.goal, "part goal"),
            (&self.home, "platform home"),
        ] {
            if !finite(p) {
                return Err(TaskError::NonFinite { what });
            }
        }
        if self.from.id == self.to.id {
            return Err(TaskError::SameLocation);
        }
        Ok(())
    }

    /// Symbolic feasibility (Sec. 6.1): A^b_ℓ1, A^b_ℓ2, A^p_e, K_Pick, K_Place, K_Move,
    /// Ω+_ℓ1 and Ω+_ℓ2 are all nonempty. Otherwise every missing item is listed.
    pub fn resolve(
        &self,
        rt: &Runtime<'_>,
    ) -> Result<Result<Resolved, MissingList<'t>>, LoadError> {
        let mut missing = MissingList::new();
        let mut need = |m: Missing<'t>| {
            if !missing.contains(&m) {
                // Capacity 8 exceeds the number of distinct checks below.
                let _ = missing.push(m);
            }
        };
        let blob = &rt.blob;
        let part_type = blob.part_type_index(self.part.kind);
        match part_type {
            None => need(Missing::PartType(self.part.kind)),
            Some(t) if blob.part_type(t)?.grasps.is_empty() => {
                need(Missing::Grasps(self.part.kind))
            }
            _ => {}
        }
        let mut location = |kind: &'t str| -> Result<Option<usize>, LoadError> {
            let Some(t) = blob.location_type_index(kind) else {
                need(Missing::LocationType(kind));
                return Ok(None);
            };
            let l = blob.location_type(t)?;
            if l.stances.is_empty() {
                need(Missing::Stances(kind));
            }
            if l.workspace.is_none() {
                need(Missing::Workspace(kind));
            }
            Ok(Some(t))
        };
        let from_type = location(self.from.kind)?;
        let to_type = location(self.to.kind)?;
        for name in crate::skill_plan::PTT_CLASSES {
            match rt.class_index(name) {
                None => need(Missing::Class(name)),
                Some(c) if rt.skills_of(c).next().is_none() => need(Missing::Skills(name)),
                _ => {}
            }
        }
        Ok(match (part_type, from_type, to_type) {
            (Some(part_type), Some(from_type), Some(to_type)) if missing.is_empty() => {
                Ok(Resolved {
                    part_type,
                    from_type,
                    to_type,
                })
            }
            _ => Err(missing),
        })
    }
}
