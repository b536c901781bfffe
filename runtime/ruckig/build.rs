//! Builds the project's Ruckig binding (`shim/prf_ruckig.cpp`) with the vendored Ruckig core:
//! with the host's C++ compiler, or for the Cortex-M7 (`thumbv7em-none-eabihf`) with Debian's
//! `arm-none-eabi-g++` and newlib's maths library (double-precision FPU, hard float).
//! No exceptions, no RTTI; on the controller no `<iostream>` and no heap (`shim/bare_metal.cpp`).
use std::path::Path;
use std::process::Command;

include!("src/storage.rs");

const RUCKIG: &[&str] = &[
    "brake",
    "position_first_step1",
    "position_first_step2",
    "position_second_step1",
    "position_second_step2",
    "position_third_step1",
    "position_third_step2",
    "velocity_second_step1",
    "velocity_second_step2",
    "velocity_third_step1",
    "velocity_third_step2",
];

/// The Cortex-M7 with its double-precision FPU (mps2-an500), as the firmware's Rust code.
const M7: &[&str] = &[
    "-mthumb",
    "-mcpu=cortex-m7",
    "-mfpu=fpv5-d16",
    "-mfloat-abi=hard",
];

fn main() {
    let target = std::env::var("TARGET").unwrap_or_default();
    let bare = target.starts_with("thumbv7em");
    let mut build = cc::Build::new();
    build
        .cpp(true)
        // GNU dialect: newlib's <math.h> defines M_PI only outside strict ISO mode.
        .std("gnu++17")
        .warnings(false)
        .flag("-fno-exceptions")
        .flag("-fno-rtti")
        .define(
            "PRF_RUCKIG_STORAGE_BYTES",
            STORAGE_BYTES.to_string().as_str(),
        )
        .include("vendor/ruckig/include")
        .file("shim/prf_ruckig.cpp");
    for f in RUCKIG {
        build.file(format!("vendor/ruckig/src/ruckig/{f}.cpp"));
    }
    if bare {
        build
            .compiler("arm-none-eabi-g++")
            .archiver("arm-none-eabi-ar")
            .cpp_link_stdlib(None)
            // Searched before the system headers: the empty <iostream>.
            .include("shim/bare")
            .file("shim/bare_metal.cpp")
            .flag("-ffunction-sections")
            .flag("-fdata-sections");
        for f in M7 {
            build.flag(f);
        }
    }
    build.compile("prf_ruckig_shim");
    if bare {
        // sqrt, cbrt, sin, cos, acos, atan, fmod from newlib's libm; ldiv from its libc.
        let libm = Command::new("arm-none-eabi-gcc")
            .args(M7)
            .arg("-print-file-name=libm.a")
            .output()
            .expect("arm-none-eabi-gcc (Debian gcc-arm-none-eabi) builds the controller's Ruckig");
        let libm = String::from_utf8_lossy(&libm.stdout).trim().to_string();
        let dir = Path::new(&libm).parent().expect("libm.a has a directory");
        println!("cargo:rustc-link-search=native={}", dir.display());
        println!("cargo:rustc-link-lib=static=m");
        println!("cargo:rustc-link-lib=static=c");
    }
    println!("cargo:rerun-if-changed=shim");
    println!("cargo:rerun-if-changed=vendor/ruckig");
    println!("cargo:rerun-if-changed=src/storage.rs");
}
