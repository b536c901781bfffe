//! `prf-sim`: the ground-truth cell, which only generation and validation know (the runtime and
//! the blob never see obstacles).
//!
//! - [`world`]: the world file (floor plan, obstacles, parts, afforded tasks) and its geometry;
//! - [`demogen`]: the demonstration generator (IK, RRT-Connect, LSPB timing), programming each
//!   afforded task as the paper's programmer did (Sec. 4.3.1);
//! - [`validate`]: re-checking programs against the ground truth (clearance, limits);
//! - [`tasks`]: the tasks of a floor plan as the runtime takes them.

pub mod demogen;
pub mod navigation;
pub mod tasks;
pub mod validate;
pub mod world;

use prf_files::OnProgress;

/// Why a blob could not be made from generated demonstrations.
#[derive(Debug, thiserror::Error)]
pub enum DemonstrationBlobError {
    #[error(transparent)]
    Generate(#[from] demogen::GenerateError),
    #[error(transparent)]
    Learn(#[from] prf_learn::LearnError),
    #[error(transparent)]
    Compile(#[from] prf_learn::CompileError),
}

/// The blob of a world from the demonstrations of `chosen`: generate them with the
/// ground-truth planner (seed 1, 100 Hz), learn with the default settings, compile.
pub fn blob_of_demonstrations(
    world: &world::World,
    chosen: &[world::AffordedTask],
    progress: OnProgress<'_>,
) -> Result<Vec<u8>, DemonstrationBlobError> {
    let model = prf_shared::robot::RobotModel::kmr_iiwa14();
    let ds = demogen::generate_dataset(world, chosen, 1, 100.0, progress)?;
    let k = prf_learn::learn(&ds, &model, &prf_learn::LearnConfig::default(), progress)?;
    Ok(prf_learn::compile(&k)?)
}
