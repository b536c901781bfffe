//! What the end-to-end tests share: a scratch directory per test process and the example
//! cell's two-demonstration blob in it.

use prf_sim::blob_of_demonstrations;
use prf_sim::world::World;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// This test process's directory, `<temp>/prf-<test binary>-<pid>`.
pub fn dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let exe = std::env::current_exe().expect("test executable");
        let name = exe.file_stem().and_then(|s| s.to_str()).unwrap_or("test");
        let d = std::env::temp_dir().join(format!("prf-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("temp dir");
        d
    })
}

/// The blob learned from the paper's two diverse demonstrations of the example cell (Part1
/// CNC → Printer, Part2 Printer → Table), written once into [`dir`]: all 18 tasks are
/// feasible on it.
#[allow(dead_code)] // not every test binary that shares this module needs a blob
pub fn blob() -> &'static Path {
    static BLOB: OnceLock<PathBuf> = OnceLock::new();
    BLOB.get_or_init(|| {
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
        let bytes =
            blob_of_demonstrations(&world, &chosen, &prf_files::progress::quiet).expect("blob");
        let path = dir().join("cell.blob");
        std::fs::write(&path, bytes).expect("write blob");
        path
    })
}
