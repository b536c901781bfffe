//! Puts the top-level `memory.x` (FLASH / BLOB / TASK / RAM of the cell controller) on the
//! linker's search path, where cortex-m-rt's `link.x` includes it. With the feature `embed`,
//! checks the files to link into the BLOB and TASK regions: PRF_EMBED_BLOB (default: the
//! example cell's `target/prf-demo/cell.blob`, written by `prf demo`) and PRF_EMBED_TASK
//! (default `target/prf-demo/task.bin`, the cell's first task, also written by `prf demo`;
//! any task block from `prf plan … --task-block`).
use std::path::PathBuf;

fn main() {
    let top = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap()).join("../..");
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    std::fs::copy(top.join("memory.x"), out.join("memory.x")).unwrap();
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=../../memory.x");
    if std::env::var_os("CARGO_FEATURE_EMBED").is_some() {
        for (var, default) in [
            ("PRF_EMBED_BLOB", "target/prf-demo/cell.blob"),
            ("PRF_EMBED_TASK", "target/prf-demo/task.bin"),
        ] {
            println!("cargo:rerun-if-env-changed={var}");
            let path = std::env::var(var)
                .map(PathBuf::from)
                .unwrap_or_else(|_| top.join(default));
            let Ok(path) = path.canonicalize() else {
                panic!(
                    "feature embed: {var} = {} does not exist (write the blob with `prf demo` or `prf learn`, the task block with `prf plan … --task-block`)",
                    path.display()
                );
            };
            println!("cargo:rerun-if-changed={}", path.display());
            println!("cargo:rustc-env={var}={}", path.display());
        }
    }
}
