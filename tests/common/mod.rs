//! What the end-to-end tests share.

use indicatif::ProgressBar;
use prf_offline::compile::blob_of_demonstrations;
use prf_offline::world::World;
use std::path::Path;

/// Writes to `path` the blob learned from the paper's two diverse demonstrations of the
/// example cell (Part1 CNC → Printer, Part2 Printer → Table): all 18 tasks are feasible on it.
pub fn write_two_demonstration_blob(path: &Path) {
    let world = World::example();
    let chosen: Vec<_> = world
        .afforded_tasks()
        .into_iter()
        .filter(|a| {
            let t = &a.task;
            let key = (
                world.parts[t.part].id.as_str(),
                world.locations[t.from].kind.as_str(),
                world.locations[t.to].kind.as_str(),
            );
            (a.approach_from, a.approach_to, a.grasp) == (0, 0, 0)
                && (key == ("Part1", "CNC", "Printer") || key == ("Part2", "Printer", "Table"))
        })
        .collect();
    let bytes = blob_of_demonstrations(&world, &chosen, &ProgressBar::hidden()).expect("blob");
    std::fs::write(path, bytes).expect("write blob");
}
