//! `prf firmware-sim` as a child process of this one (`prf demo`, `prf run --spawn-firmware`,
//! `prf bench-cell`), killed when its guard is dropped.

use anyhow::Context;
use std::path::Path;
use std::process::{Child, Command, Stdio};

/// Starts `prf firmware-sim` for cell `cell` with the platform at `base`, logging to `log`;
/// the platform navigates on the floor map of `world` (a world file, or None for the built-in
/// example cell).
pub fn spawn_firmware(
    cell: &str,
    base: [f64; 3],
    log: &Path,
    world: Option<&Path>,
) -> anyhow::Result<Child> {
    let exe = std::env::current_exe().context("locating the prf executable")?;
    Command::new(exe)
        .args([
            "firmware-sim",
            "--cell",
            cell,
            "--exit-with-parent",
            "--log",
        ])
        .arg(log)
        .arg(format!("--base={},{},{}", base[0], base[1], base[2]))
        .arg("--world")
        .arg(world.unwrap_or(Path::new("example")))
        .stdout(Stdio::null())
        .spawn()
        .context("starting prf firmware-sim")
}

/// Kills the child when dropped (an error path must not leave a controller running).
pub struct ChildGuard(pub Child);

impl Drop for ChildGuard {
    fn drop(&mut self) {
        // A child that already exited after SHUTDOWN is reaped; otherwise it is killed.
        let exited = matches!(self.0.try_wait(), Ok(Some(_)));
        if !exited {
            std::thread::sleep(std::time::Duration::from_millis(50));
            if !matches!(self.0.try_wait(), Ok(Some(_))) {
                let _ = self.0.kill();
            }
        }
        let _ = self.0.wait();
    }
}
