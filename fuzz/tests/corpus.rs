//! Every committed seed (`fuzz/seeds/<target>`) and every input that once crashed a target
//! (`fuzz/regressions/<target>`) runs through its harness without breaking a property.

use std::path::{Path, PathBuf};

fn inputs(kind: &str, target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(kind)
        .join(target);
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = entries.map(|e| e.unwrap().path()).collect();
    files.sort();
    files
}

fn replay(kind: &str) -> usize {
    let mut n = 0;
    for (target, run) in prf_fuzz::TARGETS {
        for path in inputs(kind, target) {
            let data = std::fs::read(&path).unwrap();
            eprintln!("{target}: {}", path.display());
            run(&data);
            n += 1;
        }
    }
    n
}

#[test]
fn every_seed_passes() {
    let n = replay("seeds");
    for (target, _) in prf_fuzz::TARGETS {
        assert!(!inputs("seeds", target).is_empty(), "no seeds for {target}");
    }
    eprintln!("{n} seeds");
}

#[test]
fn every_regression_passes() {
    eprintln!("{} regressions", replay("regressions"));
}
