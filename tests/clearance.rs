//! Issue 23 from the command line, with the real `prf` binary: r_d is a fact of the dataset.
//! `prf gen` states it, `prf check-dataset --world` refuses a stated r_d larger than what the
//! programs kept, `prf learn` refuses a dataset without one, and `prf plan --clearance`
//! refuses a clearance stricter than the blob's r.

mod common;

use common::dir;
use std::path::Path;
use std::process::{Command, Output};

fn prf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_prf"))
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("prf runs")
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Rewrites the manifest's `clearance_demo_m` (None: removes it).
fn state_r_d(ds: &Path, r_d: Option<f64>) {
    let path = ds.join("manifest.json");
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("manifest")).expect("json");
    let o = m.as_object_mut().expect("object");
    match r_d {
        Some(v) => o.insert("clearance_demo_m".into(), v.into()),
        None => o.remove("clearance_demo_m"),
    };
    std::fs::write(&path, serde_json::to_string_pretty(&m).expect("json")).expect("write");
}

#[test]
fn r_d_is_stated_checked_and_never_guessed() {
    let ds = dir().join("ds");
    let ds_s = ds.to_str().expect("utf-8");
    let out = prf(&["gen", "--only", "0,20", "-o", ds_s, "--quiet"]);
    assert!(out.status.success(), "{}", text(&out));
    let manifest = std::fs::read_to_string(ds.join("manifest.json")).expect("manifest");
    assert!(
        manifest.contains("\"clearance_demo_m\": 0.05"),
        "{manifest}"
    );

    // The generated programs keep r_d = 50 mm; a stated 200 mm is refused, with the demo.
    let ok = prf(&["check-dataset", ds_s, "--world", "example"]);
    assert!(ok.status.success(), "{}", text(&ok));
    state_r_d(&ds, Some(0.2));
    let refused = prf(&["check-dataset", ds_s, "--world", "example"]);
    let msg = text(&refused);
    assert!(!refused.status.success(), "{msg}");
    assert!(
        msg.contains("states r_d = 200.0 mm") && msg.contains("keeps only"),
        "{msg}"
    );

    // Without r_d, learning is refused and says what to add; with it, a larger one is refused.
    state_r_d(&ds, None);
    let blob = dir().join("cell.blob");
    let blob_s = blob.to_str().expect("utf-8");
    let out = prf(&["learn", ds_s, "-o", blob_s, "--quiet"]);
    assert!(!out.status.success());
    assert!(text(&out).contains("clearance_demo_m"), "{}", text(&out));
    state_r_d(&ds, Some(0.04));
    let out = prf(&[
        "learn",
        ds_s,
        "-o",
        blob_s,
        "--quiet",
        "--clearance-demo",
        "0.05",
    ]);
    assert!(!out.status.success());
    assert!(
        text(&out).contains("larger than the dataset's stated r_d"),
        "{}",
        text(&out)
    );

    // With its own r_d: ε = 40 − 30 = 10 mm, shown by inspect; plan states what risk 0 keeps.
    let out = prf(&["learn", ds_s, "-o", blob_s, "--quiet"]);
    assert!(out.status.success(), "{}", text(&out));
    let out = prf(&["inspect", blob_s]);
    assert!(
        text(&out).contains(
            "(≥ 2 mm beyond the link surfaces); clearances r_d = 40 mm, r = 30 mm (ε = 10 mm)"
        ),
        "{}",
        text(&out)
    );
    let out = prf(&["plan", blob_s, "--all", "--clearance", "0.03"]);
    assert!(out.status.success(), "{}", text(&out));
    assert!(text(&out).contains("keeps ≥ r = 30 mm"), "{}", text(&out));
    let out = prf(&["plan", blob_s, "--all", "--clearance", "0.035"]);
    assert!(!out.status.success());
    assert!(
        text(&out).contains("stricter than the 30 mm"),
        "{}",
        text(&out)
    );
}
