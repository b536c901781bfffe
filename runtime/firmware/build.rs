//! Puts the top-level `memory.x` (FLASH / BLOB / RAM of the cell controller) on the linker's
//! search path, where cortex-m-rt's `link.x` includes it.
use std::path::PathBuf;

fn main() {
    let top = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap()).join("../..");
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    std::fs::copy(top.join("memory.x"), out.join("memory.x")).unwrap();
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=../../memory.x");
}
