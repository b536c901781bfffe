//! Target `world`: the world-file reader (floor plan, obstacles, parts, afforded tasks) and
//! the tasks it yields.
//!
//! Input: the file's text. An accepted world must yield its tasks and afforded tasks with
//! finite poses.

use prf_sim::tasks::world_tasks;
use prf_sim::world::World;
use std::path::Path;

pub fn run(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match World::parse(text, Path::new("world.json")) {
        Ok(w) => {
            for t in world_tasks(&w) {
                let task = t.task();
                for p in [
                    task.part.pose,
                    task.from.pose,
                    task.to.pose,
                    task.goal,
                    task.home,
                ] {
                    assert!(
                        p.translation.vector.iter().all(|v| v.is_finite()),
                        "{}: a non-finite pose {p:?}",
                        t.label()
                    );
                }
            }
            for a in w.afforded_tasks() {
                assert!(!w.label(&a).is_empty());
            }
        }
        Err(e) => {
            let message = e.to_string();
            assert!(
                message.contains("world.json"),
                "{message:?} does not name the file"
            );
        }
    }
}
