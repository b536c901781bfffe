//! Nothing lost on disk (issue 18): a `prf` run cut short while it writes — here by a file-size
//! limit, whose SIGXFSZ kills the process mid-write as a full disk or a kill would stop it —
//! leaves the previous dataset, blob and bag exactly as they were. A run cut short by its
//! reader (a closed stdout) ends quietly.

mod common;

use common::{TempDir, run_prf};
use std::path::Path;
use std::process::Command;

/// Runs `prf args` with files limited to 8 KiB; its exit status must be a failure.
fn prf_limited(args: &[&str]) {
    let status = Command::new("bash")
        .arg("-c")
        .arg("ulimit -f 8; exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_prf"))
        .args(args)
        .status()
        .expect("start prf");
    assert!(
        !status.success(),
        "prf {args:?} wrote more than 8 KiB and still succeeded"
    );
}

/// Every file of `dir` with its bytes, sorted by name.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

#[test]
fn a_write_cut_short_leaves_the_previous_dataset_blob_and_bag_intact() {
    let dir = TempDir::new("atomic");
    let (ds, blob, bag) = (
        dir.path().join("dataset"),
        dir.path().join("cell.blob"),
        dir.path().join("dataset.mcap"),
    );
    run_prf(&["gen", "--only", "0", "--quiet"], &ds);
    run_prf(&["learn", ds.to_str().unwrap(), "--quiet"], &blob);
    run_prf(&["export-mcap", "--dataset", ds.to_str().unwrap()], &bag);
    let (before_ds, before_blob, before_bag) = (
        snapshot(&ds),
        std::fs::read(&blob).unwrap(),
        std::fs::read(&bag).unwrap(),
    );
    assert!(before_blob.len() > 8192 && before_bag.len() > 8192);

    prf_limited(&["gen", "--only", "1", "--quiet", "-o", ds.to_str().unwrap()]);
    assert_eq!(snapshot(&ds), before_ds, "the dataset changed");
    prf_limited(&[
        "learn",
        ds.to_str().unwrap(),
        "--quiet",
        "-o",
        blob.to_str().unwrap(),
    ]);
    assert_eq!(
        std::fs::read(&blob).unwrap(),
        before_blob,
        "the blob changed"
    );
    prf_limited(&[
        "export-mcap",
        "--dataset",
        ds.to_str().unwrap(),
        "-o",
        bag.to_str().unwrap(),
    ]);
    assert_eq!(std::fs::read(&bag).unwrap(), before_bag, "the bag changed");
    // What a killed run leaves is a temporary entry beside the targets, never in their place.
    for e in std::fs::read_dir(dir.path()).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(
            ["dataset", "cell.blob", "dataset.mcap"].contains(&name.as_str())
                || name.starts_with(prf_files::atomic::TMP_PREFIX),
            "{name}"
        );
    }
}

/// A reader that closes the pipe early (`prf plan … | head`) ends `prf` the way it ends Unix
/// tools, by SIGPIPE, not with a panic over the failed print.
#[test]
fn a_closed_stdout_ends_prf_quietly() {
    use std::os::unix::process::ExitStatusExt;
    let mut child = Command::new(env!("CARGO_BIN_EXE_prf"))
        .args(["bench", "--seconds", "0.01"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("start prf");
    // Close the read end before prf prints (or while it does).
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait for prf");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "prf panicked: {stderr}");
    assert_eq!(
        out.status.signal(),
        Some(13),
        "prf should end by SIGPIPE: {:?}, {stderr}",
        out.status
    );
}
