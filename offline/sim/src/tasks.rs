//! Tasks on a floor plan: the runtime's [`Task`] for "part p from ℓ1 to ℓ2" with the poses
//! of the world file (location instances, the part's nominal pose at a location type, the
//! platform's home). Only the floor plan is read; the obstacles stay ground truth.

use crate::world::World;
use prf_runtime::task::{Placed, Task};
use prf_shared::se3::Pose;

/// Why a task cannot be made on a floor plan.
#[derive(Debug, thiserror::Error)]
pub enum FloorTaskError {
    #[error("unknown part id {id:?} (the floor plan has {known})")]
    UnknownPart { id: String, known: String },
    #[error("unknown location id {id:?} (the floor plan has {known})")]
    UnknownLocation { id: String, known: String },
    #[error("task {task}: {error}")]
    TaskBlock {
        task: String,
        error: prf_runtime::task_block::TaskBlockError,
    },
}

/// A task with owned names, resolved on a floor plan.
#[derive(Clone, Debug)]
pub struct FloorTask {
    pub part: (String, String),
    pub from: (String, String),
    pub to: (String, String),
    pub part_pose: Pose,
    pub from_pose: Pose,
    pub to_pose: Pose,
    pub goal: Pose,
    pub home: Pose,
}

impl FloorTask {
    /// Part `part` from location `from` to location `to`, by instance id.
    pub fn new(world: &World, part: &str, from: &str, to: &str) -> Result<Self, FloorTaskError> {
        let ids = |v: Vec<&str>| v.join(", ");
        let Some(p) = world.part_index(part) else {
            return Err(FloorTaskError::UnknownPart {
                id: part.to_string(),
                known: ids(world.parts.iter().map(|p| p.id.as_str()).collect()),
            });
        };
        let loc = |id: &str| {
            world
                .location_index(id)
                .ok_or_else(|| FloorTaskError::UnknownLocation {
                    id: id.to_string(),
                    known: ids(world.locations.iter().map(|l| l.id.as_str()).collect()),
                })
        };
        let (f, t) = (loc(from)?, loc(to)?);
        Ok(Self::from_indices(world, p, f, t))
    }

    /// The same by indices into the world's lists.
    pub fn from_indices(world: &World, p: usize, f: usize, t: usize) -> Self {
        let named = |id: &str, kind: &str| (id.to_string(), kind.to_string());
        FloorTask {
            part: named(&world.parts[p].id, &world.parts[p].kind),
            from: named(&world.locations[f].id, &world.locations[f].kind),
            to: named(&world.locations[t].id, &world.locations[t].kind),
            part_pose: world.part_pose_at(f),
            from_pose: world.location_pose(f),
            to_pose: world.location_pose(t),
            goal: world.part_pose_at(t),
            home: world.home.pose(),
        }
    }

    /// The runtime's view of it.
    pub fn task(&self) -> Task<'_> {
        fn placed(named: &(String, String), pose: Pose) -> Placed<'_> {
            Placed {
                id: &named.0,
                kind: &named.1,
                pose,
            }
        }
        Task {
            part: placed(&self.part, self.part_pose),
            from: placed(&self.from, self.from_pose),
            to: placed(&self.to, self.to_pose),
            goal: self.goal,
            home: self.home,
        }
    }

    /// The task as a task block ([`prf_runtime::task_block`]), as the firmware reads it from
    /// its TASK region.
    pub fn task_block(&self) -> Result<Vec<u8>, FloorTaskError> {
        let mut buf = [0u8; 1024];
        let n = prf_runtime::task_block::encode(&self.task(), &mut buf).map_err(|error| {
            FloorTaskError::TaskBlock {
                task: self.label(),
                error,
            }
        })?;
        Ok(buf[..n].to_vec())
    }

    /// "Part1 CNC1 → Table1".
    pub fn label(&self) -> String {
        format!("{} {} → {}", self.part.0, self.from.0, self.to.0)
    }
}

/// The world's tasks (18 in the example cell) on its floor plan.
pub fn world_tasks(world: &World) -> Vec<FloorTask> {
    world
        .tasks()
        .iter()
        .map(|t| FloorTask::from_indices(world, t.part, t.from, t.to))
        .collect()
}
