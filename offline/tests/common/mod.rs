//! Helpers shared by the offline integration tests.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::Command;

/// Runs `prf` with `args`; returns its standard output (panics with both outputs when it
/// fails).
pub fn prf_stdout<S: AsRef<std::ffi::OsStr> + std::fmt::Debug>(args: &[S]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_prf"))
        .args(args)
        .output()
        .expect("start prf");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "prf {args:?}: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// Runs `prf` with `args` and `-o dir`; returns its standard output.
pub fn run_prf(args: &[&str], dir: &std::path::Path) -> String {
    let mut all: Vec<std::ffi::OsString> = args.iter().map(|a| a.into()).collect();
    all.push("-o".into());
    all.push(dir.into());
    prf_stdout(&all)
}

/// Asserts that every `dir/NAME.svg` and `dir/NAME.png` holds more than a kilobyte.
pub fn assert_charts(dir: &std::path::Path, names: &[String]) {
    for name in names {
        for ext in ["svg", "png"] {
            let p = dir.join(format!("{name}.{ext}"));
            let len = std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
            assert!(len > 1000, "{} has {len} bytes", p.display());
        }
    }
}

/// A fresh, empty directory under the system temp dir, removed on drop.
pub struct TempDir(pub PathBuf);

impl TempDir {
    pub fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("prf-test-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create temp dir");
        TempDir(dir)
    }

    pub fn path(&self) -> &std::path::Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
